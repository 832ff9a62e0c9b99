"""Entries for whole-body reach: ``Robot.reach`` (Go2 carrying a Z1-like arm, from its URDF) and
``Spot.reach``. Each argument's variants, valid or not; the probe checks the result's shapes, its
statuses, and the hand's round trip through FK wherever the status is OK."""

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


def _feet_slot(key):
    def feet(c, shift=(0.0, 0.0, 0.0)):
        return _nominal(c, key)[1] + shift

    return Custom(
        "feet",
        {
            "valid": lambda c, r, b: Arg(feet(c)),
            "shifted": lambda c, r, b: Arg(feet(c, (0.3, -0.2, 0.05))),
            "nan": lambda c, r, b: Arg(np.where(np.eye(4, 3, dtype=bool), math.nan, feet(c))),
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


_MARGIN = Custom(
    "margin",
    {
        "valid": _arg(0.02),
        "negative": _arg(-0.05),
        "huge": _arg(10.0),
        "nan": _arg(math.nan),
        "str": _arg("wide", REJECT, "type"),
    },
    default="omit",
)

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


def reach_entries():
    for key, covers in (("go2_z1", "spotkin.Robot.reach"), ("spot", "spotkin.Spot.reach")):
        register(
            name=f"{covers.split('.', 1)[1]}[{key}]",
            covers=covers,
            call=lambda c, key=key, **k: c.robot(key).reach(**k),
            slots=[_target_slot(key), _feet_slot(key), _seed_slot(key), _MARGIN, _BOX],
            probe=_probe_for(key),
        )
