"""Registry entries of ``Robot`` (the Go2 and Spot URDFs, the hexapod), its constructors and
``describe``, ``Spot.from_urdf``, ``Leg.from_geometry``, ``Leg.knee`` and ``Chain.from_joints``."""

from __future__ import annotations

import os
import pathlib

import numpy as np

import spotkin as sk

from .arm import RIGID_EXTRA
from .body import BODY_METHODS, BodySpec, body_entries, knee_point
from .entry import angle_slot, register
from .objects import STANCE_HEIGHT, euler_matrix, in_limits, rigid
from .outputs import close, describe, outs
from .robot_options import (
    chain_of_link_probe,
    chain_pairs,
    from_joints_probe,
    from_urdf_options,
    geometry_probe,
    ignored_nominal,
    limit_options,
    link_table,
    option_pairs,
    robot_probe,
)
from .slots import ACCEPT, EITHER, INVALID, REJECT, Arg, Array, Choice, Custom, Int, Real
from .urdf_texts import HEXAPOD_LEGS, bad_urdfs, go2_kinematics, go2_text, odd_urdfs, vec_text


def robot_entries():
    # Go2: Spot's code with other numbers; the hexapod: six legs, their joints interleaved in q
    body_entries(BodySpec("go2"), BODY_METHODS, light=BODY_METHODS)
    body_entries(BodySpec("hexapod"), BODY_METHODS[:-1], light=("body_jacobian", "body_rates", "fk_all"))
    # Spot from its URDF: the arm is a Chain (closed form by ik)
    body_entries(BodySpec("spot_urdf"), ("fk_all", "arm_ik_world"), light=("fk_all", "arm_ik_world"))

    # stance_feet, leg
    def stance_probe(key):
        def probe(feet, kw, c):
            robot = c.robot(key)
            height, radius = float(kw.get("height", 0.5)), float(kw.get("foot_radius", 0.0))
            n = robot.n_legs
            if not (isinstance(feet, np.ndarray) and feet.shape == (n, 3) and feet.dtype == np.float64):
                return f"not (n, 3) float64 feet: {describe(feet)}"
            hips = robot.hip_positions
            for k, leg in enumerate(robot.legs):
                want = [hips[k, 0] + leg.a[0], hips[k, 1] + leg.hip_offset, radius]
                if not close(feet[k], want, False):
                    return f"foot {k} is {feet[k]}, not below its hip-pitch joint at {want}"
                drop, (lo, hi) = height + hips[k, 2] + leg.a[2] - radius, leg.reach
                if not (0 < drop <= hi * (1 + 1e-12) and drop >= lo * (1 - 1e-12)):
                    return f"height {height} accepted but leg {k} out of reach ({drop} not in [{lo}, {hi}])"
            status = robot.body_ik([0.0, 0.0, height, 0.0, 0.0, 0.0], feet).status
            if (status == INVALID).any():
                return f"body_ik of the stance gives {status}"
            return None

        return probe

    for key in ("go2", "hexapod"):
        height = STANCE_HEIGHT[key]
        register(
            name=f"Robot.stance_feet[{key}]",
            covers="spotkin.Robot.stance_feet",
            call=lambda c, key=key, **k: c.robot(key).stance_feet(**k),
            slots=[
                Real("height", height, skip=("int", "np_int")),
                Real("foot_radius", 0.02, "nonneg", default="omit", skip=("int", "np_int")),
            ],
            probe=stance_probe(key),
        )
    for key, names in (("go2", ("FL", "FR", "RL", "RR")), ("hexapod", HEXAPOD_LEGS)):
        register(
            name=f"Robot.leg[{key}]",
            covers="spotkin.Robot.leg",
            call=lambda c, key=key, **k: c.robot(key).leg(**k),
            slots=[Choice("name", names[1], names)],
            probe=lambda leg, kw, c, key=key: (
                None
                if isinstance(leg, sk.Leg)
                and leg is c.robot(key).legs[c.robot(key).leg_names.index(kw["name"])]
                else f"not the leg {kw['name']!r}: {describe(leg)}"
            ),
        )

    # chains of links
    chain_sets = {
        "Robot.chain": (
            "go2",
            {"valid": "FL_foot", "calf": "RR_calf", "hip": "FR_hip", "rotor": "RL_thigh_rotor"},
            {"valid": "base", "hip": "FL_hip", "other_leg": "FR_hip", "same": "FL_foot", "unknown": "nope"},
        ),
        "Spot.chain": (
            "spot",
            {
                "valid": "arm_hand",
                "finger": "arm_link_fngr",
                "foot": "rear_right_foot",
                "hr0": "arm_link_hr0",
            },
            {
                "valid": "body",
                "shoulder": "arm_link_sh0",
                "leg": "front_left_hip",
                "same": "arm_hand",
                "unknown": "nope",
            },
        ),
    }
    for name, (key, links, bases) in chain_sets.items():
        bad_links = {"root": bases["valid"], "unknown": "nope"}
        if key == "go2":
            bad_links["fixed_only"] = "radar"  # hangs from the base by a fixed joint
        link = Custom("link", link_table(links, bad_links))
        base_table = {
            "none": lambda c, r, b: Arg(None),
            **{
                k: (lambda c, r, b, v=v: Arg(v))
                for k, v in bases.items()
                if k in ("valid", "hip", "shoulder")
            },
            **{
                k: (lambda c, r, b, v=v: Arg(v, REJECT, "value"))
                for k, v in bases.items()
                if k in ("other_leg", "leg", "same", "unknown")
            },
            "int": lambda c, r, b: Arg(1, REJECT),
            "list": lambda c, r, b, v=bases["valid"]: Arg([v], REJECT),
        }
        register(
            name=name,
            covers=f"spotkin.{name}",
            call=lambda c, key=key, **k: c.robot(key).chain(**k),
            slots=[link, Custom("base", base_table, default="omit")],
            probe=chain_of_link_probe(key),
            pair_rule=chain_pairs(
                key, {**links, **bad_links}, {**bases, "omit": bases["valid"], "none": bases["valid"]}
            ),
        )

    def describe_probe(key):
        def probe(text, kw, c):
            robot = c.robot(key)
            if not isinstance(text, str):
                return f"not a str: {describe(text)}"
            if robot.model.name not in text or f"legs ({robot.n_legs}):" not in text:
                return f"the summary does not name the robot or its {robot.n_legs} legs: {text[:200]!r}"
            legs = text[text.index(f"legs ({robot.n_legs}):") :]
            for name, leg in zip(robot.leg_names, robot.legs):
                # Spot's summary is its URDF's, under the URDF's leg names (front_left for fl)
                named = isinstance(robot, sk.Spot) or f"  {name}: joints" in legs
                if not named or f"c = {vec_text(leg.c)}" not in legs:
                    return f"the summary does not describe leg {name} (c = {vec_text(leg.c)}): {legs[:300]!r}"
            return None

        return probe

    for name, key in (
        ("Robot.describe", "hexapod"),
        ("Robot.describe[go2_feet]", "go2_feet"),
        ("Spot.describe", "spot"),
    ):
        register(
            name=name,
            covers=f"spotkin.{name.split('[')[0]}",
            call=lambda c, key=key: c.robot(key).describe(),
            probe=describe_probe(key),
        )

    # construction
    feet, contact_offset, nominal = from_urdf_options()
    limit_slot, order_slot = limit_options()

    def path_table():
        def files(c):
            return c.files()

        def file(name, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(files(c)[name], expect, why)

        return {
            "valid": lambda c, r, b: Arg(sk.robots.path("go2")),
            "pathlib": lambda c, r, b: Arg(pathlib.Path(sk.robots.path("go2"))),
            "bytes": lambda c, r, b: Arg(os.fsencode(sk.robots.path("go2")), EITHER),
            "latin1": file("latin1"),  # declared ISO-8859-1
            "utf16": file("utf16"),  # declared UTF-16, with a byte-order mark
            "missing": file("missing", REJECT, "os"),
            "directory": file("directory", REJECT, "os"),
            "empty_path": lambda c, r, b: Arg("", REJECT, "os"),
            "empty_file": file("empty", REJECT, "value"),
            "not_xml": file("not_xml", REJECT, "value"),
            "loop": file("loop", REJECT, "value"),
            "nul": lambda c, r, b: Arg(sk.robots.path("go2") + "\0", REJECT),
            # TypeError from os.fspath, which does not name the argument (not a numeric input)
            "none": lambda c, r, b: Arg(None, REJECT),
            "int": lambda c, r, b: Arg(3, REJECT),
            "list": lambda c, r, b: Arg([sk.robots.path("go2")], REJECT),
        }

    def some(slot, names):  # from_urdf_string fuzzes the options in full
        return Custom(slot.name, {name: slot.table[name] for name in names}, default=slot.default)

    register(
        name="Robot.from_urdf",
        covers="spotkin.Robot.from_urdf",
        pairs=20,
        call=lambda c, **k: sk.Robot.from_urdf(**k),
        slots=[
            Custom("path", path_table()),
            some(feet, ("none", "two", "calf", "int")),
            some(contact_offset, ("vector", "dict", "nan")),
            some(nominal, ("one", "unknown")),
            limit_slot,
            order_slot,
        ],
        probe=robot_probe,
        pair_rule=option_pairs,
        also_raises=(OSError,),
    )

    def text_table():
        def text(value, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(value() if callable(value) else value, expect, why)

        table = {
            "valid": text(go2_kinematics),  # the options' cases: Go2 without its inertials (faster)
            "inertials": text(go2_text),
            "np_str": text(lambda: np.str_(go2_text())),
            "bytes": text(lambda: go2_text().encode(), REJECT, "type"),
            "none": text(None, REJECT, "type"),
            "int": text(1, REJECT, "type"),
            "path": text(lambda: sk.robots.path("go2"), REJECT, "value"),
        }
        table.update({name: text(value) for name, value in odd_urdfs().items()})
        table.update({name: text(*spec) for name, spec in bad_urdfs().items()})
        return table

    go2_texts = ("valid", "inertials", "np_str", "comments", "no_declaration", "extra_tags")
    neutral = {
        "feet": ("omit", "none"),
        "contact_offset": ("omit", "none", "vector", "list", "ints", "float32"),
        "nominal": ("omit", "none"),
        "limits": ("omit", "none", "empty"),
        "leg_order": ("omit", "valid", "choice:urdf", "choice:roles"),
    }

    def text_pairs(plan):
        """Go2's texts take Go2's names; the other valid texts have none of them (options naming
        Go2's feet or legs are refused, for that reason first)."""
        if plan["text"] in go2_texts:
            return option_pairs(plan)
        if plan["text"] in odd_urdfs() and any(plan[k] not in v for k, v in neutral.items()):
            return REJECT
        return None

    register(
        name="Robot.from_urdf_string",
        covers="spotkin.Robot.from_urdf_string",
        pairs=20,
        call=lambda c, **k: sk.Robot.from_urdf_string(**k),
        slots=[Custom("text", text_table()), feet, contact_offset, nominal, limit_slot, order_slot],
        probe=robot_probe,
        pair_rule=text_pairs,
    )
    register(
        name="Robot",
        covers="spotkin.Robot",
        call=lambda c: sk.Robot(),
        expect=REJECT,
        why="type",  # built by from_urdf or from_urdf_string only
    )
    register(
        name="Spot.from_urdf",
        covers="spotkin.Spot.from_urdf",
        call=lambda c: sk.Spot.from_urdf(sk.robots.path("spot_with_arm")),
        expect=REJECT,
        why="type",  # by design
    )
    register(
        name="Spot.from_urdf_string",
        covers="spotkin.Spot.from_urdf_string",
        call=lambda c: sk.Spot.from_urdf_string(sk.robots.text("spot_with_arm")),
        expect=REJECT,
        why="type",
    )

    # legs of any geometry
    def vector(name, value, **kw):
        return Array(name, lambda c: value, **kw)

    along_pitch = {
        "pitch_axis": (lambda c, v: np.array([0.0, 0.1, 0.0]), REJECT, "value"),
        "zeros": (lambda c, v: np.zeros(3), REJECT, "value"),
    }
    register(
        name="Leg.from_geometry",
        covers="spotkin.Leg.from_geometry",
        call=lambda _ctx, **k: sk.Leg.from_geometry(**k),  # (c is an argument)
        slots=[
            vector("a", (0.01, 0.08, 0.01), extra={"zeros": (lambda c, v: np.zeros(3), ACCEPT, "")}),
            vector("b", (0.02, 0.005, -0.2), extra=along_pitch),
            vector("c", (0.01, 0.01, -0.21), extra=along_pitch),
            vector(
                "signs",
                (1.0, -1.0, 1.0),
                default="omit",
                extra={
                    "negative": (lambda c, v: -np.ones(3), ACCEPT, ""),
                    "two": (lambda c, v: np.array([2.0, 1.0, 1.0]), REJECT, "value"),
                    "zero": (lambda c, v: np.array([1.0, 0.0, 1.0]), REJECT, "value"),
                    "half": (lambda c, v: np.array([1.0, 1.0, 0.5]), REJECT, "value"),
                },
            ),
            Array(
                "limits",
                lambda c: [(-0.7, 0.7), (-2.2, 2.2), (-2.6, -0.2)],
                inf_ok=True,
                optional=True,
                default="omit",
                extra={
                    "unbounded": (lambda c, v: [[-np.inf, np.inf]] * 3, ACCEPT, ""),
                    "inverted": (lambda c, v: v[:, ::-1], REJECT, "value"),
                    "transposed": (lambda c, v: v.T, REJECT, "shape"),
                    "point": (lambda c, v: np.stack([v[:, 0], v[:, 0]], 1), ACCEPT, ""),
                },
            ),
            Custom(
                "name",
                {
                    "valid": lambda c, r, b: Arg("R1"),
                    "none": lambda c, r, b: Arg(None),
                    "empty": lambda c, r, b: Arg(""),
                    "int": lambda c, r, b: Arg(1, EITHER),
                },
                default="omit",
            ),
            Int("preferred_slot", 1, 0, 4, optional=True, default="omit"),
            vector("nominal", (0.1, 0.8, -1.4), optional=True, default="omit"),
        ],
        probe=geometry_probe,
        overflow_ok=True,
        pair_rule=ignored_nominal,
    )

    # knee origins
    for key, get in (
        ("fl", lambda c: c.spot.leg("fl")),
        ("hexapod_R1", lambda c: c.robot("hexapod").leg("R1")),
    ):

        def knee_check(x, out, kw, c, get=get):
            (knee,) = out
            ref = knee_point(get(c), x["q"])
            if not close(knee, ref, x["q"].dtype == np.float32):
                return f"{describe(knee)} is not Rx(s1 q1) (a + Ry(s2 q2) b) = {describe(ref)}"
            return None

        def knee_q(c, rng, n, get=get):
            return {"q": in_limits(get(c).limits, rng, n)}

        register(
            name=f"Leg.knee[{key}]",
            covers="spotkin.Leg.knee",
            call=lambda c, get=get, **k: get(c).knee(**k),
            slots=[angle_slot("q", 3)],
            baseline=knee_q,
            outputs=outs(("float", (3,))),
            nan_rule="check",
            check=knee_check,
        )

    # chains from joints
    def fl(c):
        return c.robot("go2").model.chain_data("FL_foot")

    placements_extra = {
        "one": (lambda c, v: v[:1], REJECT, ""),  # axes (3, 3) no longer fit
        "six": (lambda c, v: np.concatenate([v, v]), REJECT, ""),
        "zero": (lambda c, v: v[:0], REJECT, ""),
        "2d": (lambda c, v: v[0], REJECT, "shape"),
        "scaled": (lambda c, v: v * np.array([2.0, 2.0, 2.0, 1.0])[:, None], REJECT, "value"),
        "reflect": (lambda c, v: v * np.array([-1.0, 1.0, 1.0, 1.0])[:, None], REJECT, "value"),
        "last_row": (lambda c, v: v + np.diag([0.0, 0.0, 0.0, 1.0]), REJECT, "value"),
        "skewed": (lambda c, v: v + np.pad(1e-6 * np.ones((3, 3)), ((0, 1), (0, 1))), REJECT, "value"),
        "rotated": (
            lambda c, v: np.array(
                [rigid(euler_matrix([0.1 * k, 0.5, -0.3]), P[:3, 3]) for k, P in enumerate(v)]
            ),
            ACCEPT,
            "",
        ),
    }
    axes_extra = {
        "one": (lambda c, v: v[:1], REJECT, ""),
        "six": (lambda c, v: np.concatenate([v, v]), REJECT, ""),
        "zero": (lambda c, v: v[:0], REJECT, ""),
        "zero_axis": (lambda c, v: np.vstack([v[:1], np.zeros((1, 3)), v[2:]]), REJECT, "value"),
        "scaled": (lambda c, v: 3.0 * v, ACCEPT, ""),
        "negated": (lambda c, v: -v, ACCEPT, ""),
        "oblique": (lambda c, v: v + [0.3, -0.2, 0.1], ACCEPT, ""),
    }

    def joint_count(plan):
        counts = {"one": 1, "six": 6, "zero": 0}
        n_p, n_a = counts.get(plan["placements"], 3), counts.get(plan["axes"], 3)
        if n_p == n_a != 3:
            fixed = ("types", "limits", "joint_names")
            if all(plan[k] in ("omit", "none") for k in fixed):
                return EITHER if n_p == 0 else ACCEPT
            return REJECT
        return None

    register(
        name="Chain.from_joints",
        covers="spotkin.Chain.from_joints",
        call=lambda c, **k: sk.Chain.from_joints(**k),
        slots=[
            Array("placements", lambda c: fl(c).placements, extra=placements_extra),
            Array("axes", lambda c: fl(c).axes, extra=axes_extra),
            Array(
                "types",
                lambda c: np.zeros(3),
                optional=True,
                default="omit",
                extra={
                    "prismatic": (lambda c, v: np.array([0.0, 0.0, 1.0]), ACCEPT, ""),
                    "two": (lambda c, v: np.array([0.0, 2.0, 0.0]), REJECT, "value"),
                    "half": (lambda c, v: np.array([0.0, 0.5, 0.0]), REJECT, "value"),
                    "negative": (lambda c, v: np.array([-1.0, 0.0, 0.0]), REJECT, "value"),
                },
            ),
            Array("base", lambda c: np.eye(4), optional=True, default="omit", extra=RIGID_EXTRA),
            Array("tool", lambda c: fl(c).tool, optional=True, default="omit", extra=RIGID_EXTRA),
            Array(
                "limits",
                lambda c: fl(c).limits,
                inf_ok=True,
                optional=True,
                default="omit",
                extra={
                    "inverted": (lambda c, v: v[:, ::-1], REJECT, "value"),
                    "unbounded": (lambda c, v: [[-np.inf, np.inf]] * 3, ACCEPT, ""),
                },
            ),
            Custom(
                "joint_names",
                {
                    "none": lambda c, r, b: Arg(None),
                    "valid": lambda c, r, b: Arg(fl(c).joint_names),
                    "list": lambda c, r, b: Arg(list(fl(c).joint_names)),
                    "short": lambda c, r, b: Arg(fl(c).joint_names[:2], REJECT, "value"),
                    "long": lambda c, r, b: Arg((*fl(c).joint_names, "extra"), REJECT, "value"),
                    "empty": lambda c, r, b: Arg((), REJECT, "value"),
                    "ints": lambda c, r, b: Arg((1, 2, 3), EITHER),
                    "int": lambda c, r, b: Arg(5, REJECT),
                },
                default="omit",
            ),
        ],
        probe=from_joints_probe,
        overflow_ok=True,
        pair_rule=joint_count,
        combos=(
            ("six_joints", {"placements": "six", "axes": "six"}, ACCEPT),
            ("no_joints", {"placements": "zero", "axes": "zero"}, EITHER),
        ),
    )
