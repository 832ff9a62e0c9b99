"""Entries for whole-body reach: ``Robot.reach`` and ``Robot.reach_path`` (Go2 carrying a Z1-like arm,
from its URDF), ``Spot.reach`` and ``Spot.reach_path``. Each argument's variants, valid or not; the
probes check the results' shapes, their statuses, the hand's round trip through FK wherever a reach is
OK, and that an OK path holds at every sample."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .entry import register
from .outputs import describe
from .slots import ACCEPT, REJECT, Arg, Custom

# an arm configuration within each arm's limits, and the robot's nominal pose: a reachable target
ARM_Q = {"spot": [0.2, -0.8, 1.6, 0.1, 0.4, -0.2], "go2_z1": [0.2, 1.0, -1.2, 0.3, 0.2, 0.1]}


def _arg(value, expect=ACCEPT, why=""):
    return lambda c, r, b: Arg(value, expect, why)


def _nominal(c, key):
    """(body_pose (6,), feet (n, 3), a reachable target (4, 4)) of the robot ``key``."""

    def make():
        from spotkin.motion.reach import _scales

        robot = c.robot(key)
        h0, _, feet = _scales(robot)
        pose = np.array([0.0, 0.0, h0, 0.0, 0.0, 0.0])
        target = sk.body_transform(pose) @ robot.arm_mount @ np.asarray(robot.arm.fk(ARM_Q[key]))
        return pose, feet, target

    return c._get(("reach_nominal", key), make)


def _target_slot(key):
    def target(c, changed=None):
        T = _nominal(c, key)[2].copy()
        if changed is not None:
            changed(T)
        return T

    def far(T):
        T[:3, 3] += [3.0, 0.0, 0.0]

    def nan(T):
        T[0, 3] = math.nan

    def scaled(T):
        T[:3, :3] *= 1.1

    return Custom(
        "T_hand_world",
        {
            "valid": lambda c, r, b: Arg(target(c)),
            "batch": lambda c, r, b: Arg(np.stack([target(c), target(c, far)])),
            "batch2x1": lambda c, r, b: Arg(np.stack([target(c)] * 2)[:, None]),
            "empty": lambda c, r, b: Arg(np.zeros((0, 4, 4))),
            "float32": lambda c, r, b: Arg(target(c).astype(np.float32)),
            "list": lambda c, r, b: Arg(target(c).tolist()),
            "strided": lambda c, r, b: Arg(np.repeat(target(c)[None], 4, axis=0)[::2]),
            "far": lambda c, r, b: Arg(target(c, far)),
            "nan": lambda c, r, b: Arg(target(c, nan)),
            "not_rigid": lambda c, r, b: Arg(target(c, scaled)),
            "wrong_shape": lambda c, r, b: Arg(np.eye(3), REJECT, "value"),
            "complex": _arg(np.eye(4, dtype=complex), REJECT, "type"),
            "str": _arg("hand", REJECT, "type"),
            "none": _arg(None, REJECT, "type"),
        },
    )


def _feet_slot(key, nan=ACCEPT):
    """The feet; NaN feet: INVALID_INPUT for a reach (``nan`` ACCEPT), a ValueError for a path."""

    def feet(c, shift=(0.0, 0.0, 0.0)):
        return _nominal(c, key)[1] + shift

    return Custom(
        "feet",
        {
            "valid": lambda c, r, b: Arg(feet(c)),
            "shifted": lambda c, r, b: Arg(feet(c, (0.3, -0.2, 0.05))),
            "nan": lambda c, r, b: Arg(
                np.where(np.eye(4, 3, dtype=bool), math.nan, feet(c)), nan, "" if nan == ACCEPT else "value"
            ),
            "wrong_shape": lambda c, r, b: Arg(feet(c)[:3], REJECT, "value"),
            "str": _arg("stance", REJECT, "type"),
        },
        default="omit",
    )


def _seed_slot(key):
    def pair(c):
        pose, feet, _ = _nominal(c, key)
        robot = c.robot(key)
        q = np.concatenate([np.asarray(robot.body_ik(pose, feet).q), ARM_Q[key]])
        return pose, q

    return Custom(
        "seed",
        {
            "valid": lambda c, r, b: Arg(pair(c)),
            "nan": lambda c, r, b: Arg((pair(c)[0], np.full_like(pair(c)[1], math.nan))),
            "legs_only": lambda c, r, b: Arg((pair(c)[0], pair(c)[1][:12]), REJECT, "value"),
            "triple": lambda c, r, b: Arg((*pair(c), None), REJECT, "type"),
            "str": _arg("previous", REJECT, "type"),
        },
        default="omit",
    )


def _margin_slot(nan=ACCEPT):
    """The support margin; NaN: INVALID_INPUT for a reach (``nan`` ACCEPT), a ValueError for a path or a
    map."""
    return Custom(
        "margin",
        {
            "valid": _arg(0.02),
            "negative": _arg(-0.05),
            "huge": _arg(10.0),
            "nan": _arg(math.nan, nan, "" if nan == ACCEPT else "value"),
            "str": _arg("wide", REJECT, "type"),
        },
        default="omit",
    )


_MARGIN, _PATH_MARGIN = _margin_slot(), _margin_slot(nan=REJECT)

_BOX = Custom(
    "box",
    {
        "valid": _arg(sk.ReachBox(np.full(6, -0.05), np.full(6, 0.05))),
        "array": _arg(np.array([np.full(6, -0.1), np.full(6, 0.1)])),
        "point": _arg(np.zeros((2, 6))),
        "inverted": _arg(np.array([np.full(6, 0.1), np.full(6, -0.1)]), REJECT, "value"),
        "nan": _arg(np.full((2, 6), math.nan), REJECT, "value"),
        "wrong_shape": _arg(np.zeros((2, 5)), REJECT, "value"),
        "str": _arg("tight", REJECT, "type"),
    },
    default="omit",
)


def _probe_for(key):
    def probe(res, kw, c):
        if not isinstance(res, sk.ReachResult):
            return f"not a ReachResult: {describe(res)}"
        robot = c.robot(key)
        m = 3 * robot.n_legs + 6
        q = np.asarray(res.q)
        lead = q.shape[:-1]
        if q.shape[-1:] != (m,) or np.shape(res.body_pose) != (*lead, 6):
            return f"q {q.shape}, body_pose {np.shape(res.body_pose)}"
        status = np.asarray(res.status)
        if status.shape != lead or not np.isin(status, [0, 1, 2, 3]).all():
            return f"statuses {describe(res.status)}"
        ok = status == sk.ReachStatus.OK
        if ok.any():
            hand = robot.fk_all(np.asarray(res.body_pose, float)[ok], q.astype(float)[ok]).hand
            target = np.broadcast_to(np.asarray(kw["T_hand_world"], float), (*lead, 4, 4))[ok]
            tolerance = 1e-4 if q.dtype == np.float32 else 1e-9
            if np.abs(hand - target).max() > tolerance:
                return f"an OK answer misses its target by {np.abs(hand - target).max():.3g}"
        bad = status == sk.ReachStatus.INVALID_INPUT
        if bad.any() and not np.isnan(q[bad]).all():
            return "an INVALID_INPUT sample has joints"
        if not np.isfinite(q[~bad]).all():
            return "a valid sample has non-finite joints"
        return None

    return probe


def _register_both(method: str, slots_for, probe_for) -> None:
    """``method`` on Go2 carrying a Z1-like arm (``Robot.<method>``) and on ``Spot`` (``Spot.<method>``):
    the same slots and probe, each made for its robot."""
    for key, owner in (("go2_z1", "Robot"), ("spot", "Spot")):
        register(
            name=f"{owner}.{method}[{key}]",
            covers=f"spotkin.{owner}.{method}",
            call=lambda c, key=key, **k: getattr(c.robot(key), method)(**k),
            slots=slots_for(key),
            probe=probe_for(key),
        )


def reach_entries():
    _register_both(
        "reach",
        lambda key: [_target_slot(key), _feet_slot(key), _seed_slot(key), _MARGIN, _BOX],
        _probe_for,
    )


def _start_slot(key):
    def pair(c):
        pose, feet, _ = _nominal(c, key)
        q = np.concatenate([np.asarray(c.robot(key).body_ik(pose, feet).q), ARM_Q[key]])
        return pose, q

    return Custom(
        "start",
        {
            "valid": lambda c, r, b: Arg(pair(c)),
            "result": lambda c, r, b: Arg(c.robot(key).reach(_nominal(c, key)[2])),
            "nan": lambda c, r, b: Arg((pair(c)[0] * math.nan, pair(c)[1]), REJECT, "value"),
            "legs_only": lambda c, r, b: Arg((pair(c)[0], pair(c)[1][:12]), REJECT, "value"),
            "batch": lambda c, r, b: Arg(
                (np.stack([pair(c)[0]] * 2), np.stack([pair(c)[1]] * 2)), REJECT, "value"
            ),
            "str": _arg("here", REJECT, "type"),
        },
    )


def _path_target_slot(key):
    def moved(c, shift):
        T = _nominal(c, key)[2].copy()
        T[:3, 3] += shift
        return T

    return Custom(
        "target",
        {
            "valid": lambda c, r, b: Arg(moved(c, (0.05, -0.03, 0.04))),
            "far": lambda c, r, b: Arg(moved(c, (3.0, 0.0, 0.0))),
            "nan": lambda c, r, b: Arg(moved(c, (math.nan, 0.0, 0.0))),
            "batch": lambda c, r, b: Arg(np.stack([moved(c, (0.0, 0.0, 0.0))] * 2), REJECT, "value"),
            "str": _arg("there", REJECT, "type"),
        },
    )


_SAMPLES = Custom(
    "n",
    {
        "valid": _arg(6),
        "two": _arg(2),
        "one": _arg(1, REJECT, "value"),
        "float": _arg(6.0, REJECT, "type"),
        "str": _arg("six", REJECT, "type"),
    },
    default="omit",
)


def _path_probe_for(key):
    def probe(path, kw, c):
        if not isinstance(path, sk.ReachPath):
            return f"not a ReachPath: {describe(path)}"
        n = kw.get("n", 50)
        robot = c.robot(key)
        m = 3 * robot.n_legs + 6
        if path.q.shape != (n, m) or path.body_pose.shape != (n, 6) or path.ok.shape != (n,):
            return f"q {path.q.shape}, body_pose {path.body_pose.shape}, ok {path.ok.shape}"
        if not (np.isfinite(path.q[path.ok]).all() and np.isfinite(path.body_pose).all()):
            return "a path with non-finite poses, or non-finite joints at a sample that holds"
        if path.status == sk.ReachStatus.OK and not path.ok.all():
            return "an OK path with a sample that does not hold"
        return None

    return probe


def reach_path_entries():
    _register_both(
        "reach_path",
        lambda key: [
            _start_slot(key),
            _path_target_slot(key),
            _SAMPLES,
            _feet_slot(key, nan=REJECT),
            _PATH_MARGIN,
            _BOX,
        ],
        _path_probe_for,
    )


def _points_slot(key):
    def near(c):
        return _nominal(c, key)[2][:3, 3]

    return Custom(
        "points",
        {
            "valid": lambda c, r, b: Arg(near(c)[None]),
            "one": lambda c, r, b: Arg(near(c)),
            "batch2x1": lambda c, r, b: Arg(np.stack([near(c), near(c) + [3.0, 0.0, 0.0]])[:, None]),
            "far": lambda c, r, b: Arg(near(c)[None] + [[5.0, 0.0, 0.0]]),
            "nan": lambda c, r, b: Arg(np.array([[math.nan, 0.0, 0.5]])),
            "empty": _arg(np.zeros((0, 3))),
            "float32": lambda c, r, b: Arg(near(c)[None].astype(np.float32)),
            "wrong_shape": _arg(np.zeros((2, 2)), REJECT, "value"),
            "str": _arg("grid", REJECT, "type"),
        },
    )


_APPROACH = Custom(
    "approach",
    {
        "valid": _arg([1.0, 0.0, 0.0]),
        "unnormalised": _arg([0.0, 0.0, -3.0]),
        "zero": _arg([0.0, 0.0, 0.0], REJECT, "value"),
        "nan": _arg([math.nan, 0.0, 1.0], REJECT, "value"),
        "wrong_shape": _arg([1.0, 0.0], REJECT, "value"),
        "str": _arg("down", REJECT, "type"),
    },
    default="omit",
)

_SPACING = Custom(
    "spacing",
    {
        "valid": _arg(0.1),
        "zero": _arg(0.0, REJECT, "value"),
        "nan": _arg(math.nan, REJECT, "value"),
        "str": _arg("fine", REJECT, "type"),
    },
    default="omit",
)

_AXIS = Custom(
    "axis",
    {"valid": _arg("x"), "z": _arg("z"), "w": _arg("w", REJECT, "value"), "int": _arg(0, REJECT, "value")},
    default="omit",
)


def _count_slot(name):
    return Custom(
        name,
        {
            "valid": _arg(3),
            "one": _arg(1),
            "zero": _arg(0, REJECT, "value"),
            "float": _arg(2.5, REJECT, "type"),
        },
        default="omit",
    )


def _map_probe_for(key):
    def probe(result, kw, c):
        if not isinstance(result, sk.Reachability):
            return f"not a Reachability: {describe(result)}"
        lead = np.shape(result.reachable)
        if result.points.shape != (*lead, 3) or result.q.shape[: len(lead)] != lead:
            return f"points {result.points.shape}, reachable {lead}, q {result.q.shape}"
        ok = np.asarray(result.reachable)
        if ok.any():
            robot = c.robot(key)
            hand = robot.fk_all(result.body_pose[ok], result.q[ok]).hand
            if np.abs(hand[..., :3, 3] - result.points[ok]).max() > 1e-6:
                return "a reachable point's hand misses it"
        return None

    return probe


def reachability_entries():
    _register_both(
        "reachability",
        lambda key: [
            _points_slot(key),
            _APPROACH,
            _SPACING,
            _AXIS,
            _feet_slot(key, nan=REJECT),
            _PATH_MARGIN,
            _BOX,
            _count_slot("directions"),
            _count_slot("rolls"),
        ],
        _map_probe_for,
    )
