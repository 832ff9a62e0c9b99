"""Slots and probes for the robots built from URDF: ``from_urdf``'s keyword options, joint limits,
link tables, and the probes that check a robot, a chain or a leg against its description."""

from __future__ import annotations

import functools
import math
import pickle

import numpy as np

import spotkin as sk

from .body import knee_point
from .objects import ROBOT_FILES, in_limits, pose_matrix
from .outputs import close, describe
from .slots import ACCEPT, EITHER, REJECT, Arg, Choice, Custom, finite

GO2_FEET = ("FL_foot", "FR_foot", "RL_foot", "RR_foot")
GO2_NOMINAL = {
    "FL": (0.0, 0.85, -1.7),
    "FR": (0.05, 0.9, -1.6),
    "RL": (0.0, 0.8, -1.5),
    "RR": (-0.1, 1.0, -1.8),
}


def from_urdf_options():
    """Custom slots for from_urdf's keyword options, valid for Go2's names."""

    def arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    feet = Custom(
        "feet",
        {
            "none": arg(None),
            "all": arg(list(GO2_FEET)),
            "tuple": arg(GO2_FEET),
            "reversed": arg(GO2_FEET[::-1]),
            "one": arg("FL_foot"),
            "two": arg(["FL_foot", "RR_foot"]),
            "calf": arg(["FL_calf"], REJECT, "value"),  # the knee itself: no knee-to-foot vector
            "thigh": arg(["FL_thigh"], REJECT, "value"),  # two joints above it
            "base": arg(["base"], REJECT, "value"),
            "unknown": arg(["FL_foot", "nope"], REJECT, "value"),
            "twice": arg(["FL_foot", "FL_foot"], REJECT, "value"),
            "same_leg": arg(["FL_foot", "FL_calf_rotor"], REJECT, "value"),
            "empty": arg([], REJECT, "value"),
            "int": arg(1, REJECT),
            "none_item": arg([None], REJECT),
            "nested": arg([["FL_foot"]], REJECT),
            "bytes": arg(b"FL_foot", REJECT),
        },
        default="omit",
    )
    offset = np.array([0.0, 0.0, -0.02])
    contact_offset = Custom(
        "contact_offset",
        {
            "none": arg(None),
            "vector": arg(offset),
            "list": arg(offset.tolist()),
            "ints": arg(np.zeros(3, dtype=np.int64)),
            "float32": arg(offset.astype(np.float32)),
            "dict": arg({"FL_foot": offset, "RR_foot": (0.01, 0.0, -0.02)}),
            "dict_unknown": arg({"nope": offset}, REJECT, "value"),
            "dict_not_foot": arg({"FL_calf": offset}, REJECT, "value"),
            "dict_nan": arg({"FL_foot": (math.nan, 0.0, 0.0)}, REJECT, "value"),
            "dict_none": arg({"FL_foot": None}, REJECT),
            "nan": arg((math.nan, 0.0, 0.0), REJECT, "value"),
            "inf": arg((0.0, math.inf, 0.0), REJECT, "value"),
            "short": arg((0.0, 0.0), REJECT, "value"),
            "2d": arg(np.zeros((4, 3)), REJECT, "value"),
            "bool": arg(True, REJECT),
            "str": arg("abc", REJECT),  # documented: TypeError for non-numeric input
            "complex": arg(offset + 0j, REJECT, "type"),
            "masked": arg(
                np.ma.masked_array(offset, [True, False, False]), REJECT
            ),  # its mask would be ignored
        },
        default="omit",
    )
    nominal = Custom(
        "nominal",
        {
            "none": arg(None),
            "one": arg({"FL": GO2_NOMINAL["FL"]}),
            "all": arg(dict(GO2_NOMINAL)),
            "forward": arg({"RL": (0.0, -0.6, 1.4)}),  # knee forward: out of the limits, still a slot
            "array": arg({"FR": np.array(GO2_NOMINAL["FR"], dtype=np.float32)}),
            "unknown": arg({"XX": (0.0, 0.8, -1.5)}, REJECT, "value"),
            "nan": arg({"FL": (0.0, math.nan, -1.5)}, REJECT, "value"),
            "short": arg({"FL": (0.0, 0.8)}, REJECT, "value"),
            "str_value": arg({"FL": "abc"}, REJECT, "type"),
            "none_value": arg({"FL": None}, EITHER),
            "list": arg([(0.0, 0.8, -1.5)], REJECT),
            "str": arg("FL", REJECT),
        },
        default="omit",
    )
    return feet, contact_offset, nominal


QUAD_ROLES = ("front_left", "front_right", "hind_left", "hind_right")


def limit_options():
    """The ``limits`` and ``leg_order`` slots of from_urdf and from_urdf_string, valid for Go2's names."""

    def arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    limits = Custom(
        "limits",
        {
            "none": arg(None),
            "empty": arg({}),
            "knee": arg({"FL_calf_joint": (-2.0, -1.0)}),
            "unlimited": arg({"RR_hip_joint": (-np.inf, np.inf)}),
            "array": arg({"FR_thigh_joint": np.array([-1.0, 2.0], dtype=np.float32)}),
            "point": arg({"FR_thigh_joint": (0.5, 0.5)}),
            "reversed": arg({"FL_calf_joint": (-1.0, -2.0)}, REJECT, "value"),
            "nan": arg({"FL_calf_joint": (np.nan, 1.0)}, REJECT, "value"),
            "unknown": arg({"no_such_joint": (0.0, 1.0)}, REJECT, "value"),
            "fixed": arg({"FL_foot_joint": (0.0, 1.0)}, REJECT, "value"),
            "three": arg({"FL_calf_joint": (0.0, 1.0, 2.0)}, REJECT, "value"),
            "text": arg({"FL_calf_joint": "wide"}, REJECT),
            "int_key": arg({3: (0.0, 1.0)}, REJECT, "type"),
            "list": arg([(0.0, 1.0)], REJECT, "type"),
            "int": arg(1, REJECT, "type"),
        },
        default="omit",
    )
    leg_order = Choice("leg_order", "urdf", ("urdf", "roles"), default="omit")
    return limits, leg_order


def option_pairs(plan):
    """The options name Go2's feet and legs: a subset of feet leaves some nominal stances nameless."""
    if plan.get("nominal") == "all" and plan.get("feet") in ("one", "two"):
        return REJECT
    if plan.get("nominal") in ("forward", "array") and plan.get("feet") in ("one", "two"):
        return REJECT  # RL, FR not among FL, RR
    if plan.get("contact_offset") == "dict" and plan.get("feet") == "one":
        return REJECT  # RR_foot is not a foot then
    if plan.get("feet") == "calf" and plan.get("contact_offset") in (
        "vector",
        "list",
        "float32",
        "dict_not_foot",
    ):
        # the offset is the knee-to-foot vector: a leg (and the calf is then a foot)
        return ACCEPT
    return None


def robot_probe(robot, kw, c):
    """A robot as its description says: every foot (body_fk) where the URDF tree puts the foot link
    (plus its contact offset), the nominal stances in the preferred slots, and a faithful pickle."""
    if not isinstance(robot, sk.Robot):
        return f"not a Robot: {describe(robot)}"
    n = robot.n_legs
    if len(robot.leg_joint_names) != 3 * n or robot.hip_positions.shape != (n, 3) or len(robot.legs) != n:
        return f"{n} legs but {len(robot.leg_joint_names)} leg joints"
    model = robot.model
    specs, _ = sk.urdf.find_legs(model, feet=kw.get("feet"), contact_offset=kw.get("contact_offset"))
    if kw.get("leg_order") == "roles":  # the legs front to hind, left before right
        by_name = {spec.name: spec for spec in specs}
        if sorted(by_name) != sorted(robot.leg_names):
            return f"legs {robot.leg_names}, the description's {sorted(by_name)}"
        specs = [by_name[name] for name in robot.leg_names]
        hips = robot.hip_positions
        if n == 4 and (hips[:, 1] > 0).sum() == 2 and robot.leg_roles != QUAD_ROLES:
            return f"leg_order='roles' gave the roles {robot.leg_roles}"
        if any(hips[k, 0] < hips[k + 1, 0] - 1e-9 for k in range(0, n - 1, 2) if k + 1 < n and n == 4):
            return f"leg_order='roles': the legs are not front to hind: {robot.leg_roles}"
    if tuple(spec.name for spec in specs) != robot.leg_names:
        return f"legs {robot.leg_names}, the description's {[spec.name for spec in specs]}"
    limits = kw.get("limits")
    if isinstance(limits, dict):  # the overrides reach the legs
        for name, pair in limits.items():
            if name in robot.leg_joint_names:
                k = robot.leg_joint_names.index(name)
                legs_of = [i for i, spec in enumerate(specs) if name in spec.joint_names]
                row = robot.legs[legs_of[0]].limits[specs[legs_of[0]].joint_names.index(name)]
                if not np.array_equal(row, np.asarray(pair, dtype=np.float64)):
                    return f"limits={limits}: joint {name} (q column {k}) has the limits {row}"
    q = np.random.default_rng(0).uniform(-0.6, 0.6, 3 * n)
    pose = [0.1, -0.05, 0.3, 0.1, -0.2, 0.3]
    T = pose_matrix(pose)
    feet = robot.body_fk(pose, q)
    values = dict(zip(robot.leg_joint_names, q.tolist()))
    for k, spec in enumerate(specs):
        F = model.placement(spec.foot, values)
        ref = T[:3, 3] + T[:3, :3] @ (F[:3, 3] + F[:3, :3] @ spec.contact_offset)
        if not close(feet[k], ref, False):
            return f"leg {spec.name}: body_fk puts the foot at {feet[k]}, the URDF tree at {ref}"
    nominal = kw.get("nominal")
    if isinstance(nominal, dict):
        for name, stance in nominal.items():
            if stance is None:
                continue
            leg = robot.leg(name)
            stance = np.asarray(stance, dtype=np.float64)
            slot = leg.preferred_slot
            held = leg.ik_all(leg.fk(stance)).q[slot]
            if not np.allclose(np.angle(np.exp(1j * (held - stance))), 0.0, atol=1e-7):
                return f"leg {name}: the preferred slot {slot} holds {held}, not the nominal stance {stance}"
    try:
        clone = pickle.loads(pickle.dumps(robot))
    except Exception as error:
        return f"a pickled copy cannot be rebuilt: {type(error).__name__}: {error}"[:400]
    if not close(clone.body_fk(pose, q), feet, False):
        return "a pickled copy differs"
    if list(clone.model.links) != list(model.links) or clone.joint_names != robot.joint_names:
        return f"a pickled copy has other names: links {sorted(set(clone.model.links) ^ set(model.links))}"
    if [leg.preferred_slot for leg in clone.legs] != [leg.preferred_slot for leg in robot.legs]:
        return "a pickled copy has other preferred slots"
    return None


def chain_of_link_probe(key):
    """Robot.chain: the URDF's joints, limits and FK (the tree's placements) from base to link."""

    def probe(chain, kw, c):
        if not isinstance(chain, sk.Chain):
            return f"not a Chain: {describe(chain)}"
        model = c.robot(key).model
        link, base = kw["link"], kw.get("base") or model.root
        joints = [j for j in model.path(link, base) if j.actuated]
        if chain.joint_names != tuple(j.name for j in joints) or chain.dof != len(joints):
            return f"joints {chain.joint_names}, the description's {[j.name for j in joints]}"
        if not (
            close(chain.lower, [j.lower for j in joints], False)
            and close(chain.upper, [j.upper for j in joints], False)
        ):
            return "limits differ from the description's"
        q = np.random.default_rng(1).uniform(-1.0, 1.0, chain.dof)
        values = {j.name: v for j, v in zip(joints, q.tolist())}
        ref = np.linalg.inv(model.placement(base)) @ model.placement(link, values)
        if not close(chain.fk(q), ref, False):
            return f"fk {describe(chain.fk(q))}, the URDF tree's {describe(ref)}"
        if not close(pickle.loads(pickle.dumps(chain)).fk(q), ref, False):
            return "a pickled copy differs"
        return None

    return probe


def link_table(valid, others):
    """A Custom slot table of link names: valid ones, bad ones, non-strings."""
    table = {name: (lambda c, r, b, v=value: Arg(v)) for name, value in valid.items()}
    table.update({name: (lambda c, r, b, v=value: Arg(v, REJECT, "value")) for name, value in others.items()})
    table.update(
        {
            "none": lambda c, r, b: Arg(None, REJECT),
            "int": lambda c, r, b: Arg(1, REJECT),
            "bytes": lambda c, r, b: Arg(valid["valid"].encode(), REJECT),
            "list": lambda c, r, b: Arg([valid["valid"]], REJECT),
            "np_str": lambda c, r, b: Arg(np.str_(valid["valid"])),
            "empty": lambda c, r, b: Arg("", REJECT, "value"),
            "space": lambda c, r, b: Arg(valid["valid"] + " ", REJECT, "value"),
            "nul": lambda c, r, b: Arg(valid["valid"] + "\0", REJECT, "value"),
        }
    )
    return table


@functools.cache
def _model_of(key):
    return sk.urdf.parse_urdf(sk.robots.text(ROBOT_FILES.get(key, "spot_with_arm")))


def chain_pairs(key, links, bases):
    """link and base both names: accepted iff the link is below the base with a moving joint between."""

    def rule(plan):
        link, base = links.get(plan["link"]), bases.get(plan["base"])
        if link is None or base is None:
            return None  # not a name: the slots' own expectations
        model = _model_of(key)
        try:
            moving = [j for j in model.path(link, base) if j.actuated]
        except ValueError:
            return REJECT
        return ACCEPT if moving else REJECT

    return rule


def ignored_nominal(plan):
    """With a preferred_slot, nominal is not used: whether a bad one is still refused is not documented."""
    given = ("valid", "min", "max", "np_int", "zero_d")
    if plan["preferred_slot"] in given and plan["nominal"] not in ("omit", "none"):
        return EITHER
    return None


def geometry_fk(a, b, c, signs, q):
    """The documented leg FK p = Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c)), in NumPy."""

    def rx(t):
        return np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]])

    def ry(t):
        return np.array([[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]])

    s1, s2, s3 = signs
    return rx(s1 * q[0]) @ (a + ry(s2 * q[1]) @ (b + ry(s3 * q[2]) @ c))


def geometry_probe(leg, kw, c):
    if not isinstance(leg, sk.Leg):
        return f"not a Leg: {describe(leg)}"
    a, b, c3 = (np.asarray(kw[k], dtype=np.float64) for k in "abc")
    signs = np.asarray(kw.get("signs", (1.0, 1.0, 1.0)), dtype=np.float64)
    for name, got, want in (("a", leg.a, a), ("b", leg.b, b), ("c", leg.c, c3), ("signs", leg.signs, signs)):
        if not close(got, want, False):
            return f"leg.{name} is {got}, given {want}"
    if not close(leg.hip_offset, a[1] + b[1] + c3[1], False):
        return f"hip_offset {leg.hip_offset}, a_y + b_y + c_y = {a[1] + b[1] + c3[1]}"
    q = in_limits(leg.limits, np.random.default_rng(2), 6, margin=0.01)
    p = leg.fk(q)
    ref = np.array([geometry_fk(a, b, c3, signs, qk) for qk in q])
    if not close(p, ref, False):
        return f"fk {describe(p)} is not Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c)) = {describe(ref)}"
    if not close(leg.knee(q), knee_point(leg, q), False):
        return "knee(q) is not Rx(s1 q1) (a + Ry(s2 q2) b)"
    sol = leg.ik_all(p)
    for k in range(len(q)):
        wrapped = np.abs(np.angle(np.exp(1j * (sol.q[k] - q[k])))).max(axis=1)
        if not (sol.exists[k] & (wrapped < 1e-6)).any():
            return f"ik_all(fk(q)) does not hold q = {q[k]}: {describe(sol.q[k])}"
    slot = kw.get("preferred_slot")
    if slot is not None and leg.preferred_slot != int(slot):
        return f"preferred_slot {leg.preferred_slot}, given {slot}"
    nominal = kw.get("nominal")
    if slot is None and nominal is not None:
        stance = np.asarray(nominal, dtype=np.float64)
        held = leg.ik_all(leg.fk(stance)).q[leg.preferred_slot]
        if not np.allclose(np.angle(np.exp(1j * (held - stance))), 0.0, atol=1e-7):
            return f"the preferred slot {leg.preferred_slot} holds {held}, not the nominal stance {stance}"
    clone = pickle.loads(pickle.dumps(leg))
    if not close(clone.fk(q), p, False) or clone.preferred_slot != leg.preferred_slot:
        return "a pickled copy differs"
    return None


def joints_fk(placements, axes, types, base, tool, q):
    """The documented chain FK base · prod(placements[j] · M_j(q_j)) · tool, in NumPy and SciPy."""
    from scipy.spatial.transform import Rotation

    T = np.array(base, dtype=np.float64)
    for P, w, kind, value in zip(placements, axes, types, q):
        w = np.asarray(w, dtype=np.float64) / np.linalg.norm(w)
        M = np.eye(4)
        if kind == 0:
            M[:3, :3] = Rotation.from_rotvec(w * value).as_matrix()
        else:
            M[:3, 3] = w * value
        T = T @ P @ M
    return T @ tool


def from_joints_probe(chain, kw, c):
    if not isinstance(chain, sk.Chain):
        return f"not a Chain: {describe(chain)}"
    placements = np.asarray(kw["placements"], dtype=np.float64)
    n = len(placements)
    types = np.asarray(kw["types"] if kw.get("types") is not None else np.zeros(n), dtype=np.float64)
    base = np.asarray(kw["base"] if kw.get("base") is not None else np.eye(4), dtype=np.float64)
    tool = np.asarray(kw["tool"] if kw.get("tool") is not None else np.eye(4), dtype=np.float64)
    if chain.dof != n or not np.array_equal(chain.sigma, types.astype(np.int8)):
        return f"dof {chain.dof}, sigma {chain.sigma} for {n} joints of types {types}"
    names = kw.get("joint_names")
    if names is not None and chain.joint_names != tuple(str(name) for name in names):
        return f"joint_names {chain.joint_names}, given {names}"
    q = np.linspace(-0.9, 0.7, n)
    ref = joints_fk(placements, np.asarray(kw["axes"], dtype=np.float64), types, base, tool, q)
    T = chain.fk(q)
    if not finite(T) or not close(T, ref, False):
        return f"fk {describe(T)} is not base · prod(placement · motion) · tool = {describe(ref)}"
    frames = chain.frames(q)
    if not close(frames[-1], T, False) or not close(frames[0], base, False):
        return "frames do not run from the base to fk(q)"
    if not close(pickle.loads(pickle.dumps(chain)).fk(q), T, False):
        return "a pickled copy differs"
    return None
