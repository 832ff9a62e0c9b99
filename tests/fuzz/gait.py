"""Entries for gaits and their plans: the ``Gait`` constructor, ``Gait.replace``, ``Gait.resolve`` and
``Robot.plan_gait`` (on Go2 from its URDF and on ``Spot``). Plans are short (a tenth of a second at
50 ticks per second): the planner is the pure-Python reference."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .entry import register
from .outputs import describe
from .slots import ACCEPT, REJECT, Arg, Choice, Custom, Flag, Real

PRESETS = ("stand", "walk", "trot", "pace", "bound", "pronk", "gallop")
ROLES = ("front_left", "front_right", "hind_left", "hind_right")
TROT = {"front_left": 0.0, "front_right": 0.5, "hind_left": 0.5, "hind_right": 0.0}
DURATION, RATE = 0.1, 50.0


def _arg(value, expect=ACCEPT, why=""):
    return lambda c, r, b: Arg(value, expect, why)


def attitude_slot():
    """The (roll, pitch) a plan or a controller holds, valid or not (shared with fuzz/controller.py)."""
    return Custom(
        "attitude",
        {
            "valid": _arg((0.05, -0.03)),
            "nan": _arg((math.nan, 0.0), REJECT, "value"),
            "wrong_shape": _arg((0.0, 0.0, 0.0), REJECT, "value"),
            "str": _arg("flat", REJECT, "type"),
        },
        default="omit",
    )


def _offsets_slot():
    return Custom(
        "offsets",
        {
            "valid": _arg(TROT),
            "none": _arg(None),
            "wrapped": _arg({role: value + 3.0 for role, value in TROT.items()}),
            "joint_name": _arg({**TROT, "FL_hip_joint": 0.0}, REJECT, "value"),
            "missing": _arg({"front_left": 0.0, "front_right": 0.5}, REJECT, "value"),
            "nan": _arg({**TROT, "hind_left": math.nan}, REJECT, "value"),
            "str_value": _arg({**TROT, "hind_left": "half"}, REJECT, "type"),
            "list": _arg(list(TROT.values()), REJECT, "type"),
            "str": _arg("trot", REJECT, "type"),
        },
        default="omit",
    )


def _gait_probe(gait, kw, c):
    if not isinstance(gait, sk.Gait):
        return f"not a Gait: {describe(gait)}"
    if gait.name != kw.get("name", "trot"):
        return f"name {gait.name!r}, not {kw.get('name', 'trot')!r}"
    for key in ("period", "duty", "step_height", "height"):
        if kw.get(key) is not None and getattr(gait, key) != float(kw[key]):
            return f"{key} {getattr(gait, key)!r}, not {kw[key]!r}"
    offsets = gait.offsets
    if sorted(offsets) != sorted(ROLES) or not all(0.0 <= v < 1.0 for v in offsets.values()):
        return f"offsets {offsets}"
    return None


def _resolved_probe(resolved, kw, c):
    numbers = (resolved.period, resolved.duty, resolved.step_height, resolved.height, resolved.hip_height)
    if not all(math.isfinite(x) and x >= 0 for x in numbers) or resolved.period <= 0:
        return f"numbers {numbers}"
    arrays = (resolved.offsets, resolved.stance, resolved.sway, resolved.shift, resolved.step_reach)
    if not all(np.isfinite(a).all() for a in arrays) or resolved.stance.shape != (4, 3):
        return "non-finite or misshapen arrays"
    return None


def _plan_probe(plan, kw, c):
    if not isinstance(plan, sk.GaitPlan):
        return f"not a GaitPlan: {describe(plan)}"
    velocity = np.asarray(kw.get("velocity", (0.0, 0.0, 0.0)), dtype=np.float64)
    lead = velocity.shape[:-1]
    ticks = round(float(kw.get("duration", 5.0)) * float(kw.get("rate", 500.0))) + 1
    if plan.t.shape != (ticks,):
        return f"t has shape {plan.t.shape}, not ({ticks},)"
    shapes = {"body_pose": (6,), "feet": (4, 3), "contact": (4,), "q": (12,), "qd": (12,), "tau": (12,)}
    for name, trailing in shapes.items():
        if getattr(plan, name).shape != (*lead, ticks, *trailing):
            return f"{name} has shape {getattr(plan, name).shape}"
    if plan.status.dtype != np.int8 or plan.status.shape != (*lead, ticks) or (plan.status != 0).any():
        return f"statuses {describe(plan.status)}"
    if not (np.isfinite(plan.q).all() and np.isfinite(plan.qd).all() and np.isfinite(plan.tau).all()):
        return "non-finite q, qd or tau"
    return None


def gait_entries():
    register(
        name="Gait",
        covers="spotkin.Gait",
        call=lambda c, **k: sk.Gait(**k),
        slots=[
            Choice("name", "trot", PRESETS),
            Real("period", 0.5, optional=True, default="omit"),
            Real("duty", 0.8, optional=True, default="omit", skip=("int", "np_int")),
            Real("step_height", 0.05, "nonneg", optional=True, default="omit"),
            _offsets_slot(),
            Real("height", 0.3, optional=True, default="omit"),
            Real("capture_gain", 1.0, "nonneg", default="omit"),
            Flag("com_shift", optional=True, default="omit"),
        ],
        probe=_gait_probe,
    )
    register(
        name="Gait.replace",
        covers="spotkin.Gait.replace",
        call=lambda c: sk.Gait("trot").replace(period=0.5, duty=0.7),
        probe=lambda gait, kw, c: (
            None if (gait.name, gait.period, gait.duty) == ("trot", 0.5, 0.7) else f"replaced into {gait!r}"
        ),
    )
    robots = {
        "valid": lambda c, r, b: Arg(c.robot("go2")),
        "spot": lambda c, r, b: Arg(c.spot),
        "hexapod": lambda c, r, b: Arg(c.robot("hexapod"), REJECT, "value"),
        "leg": lambda c, r, b: Arg(c.leg, REJECT, "type"),
        "none": _arg(None, REJECT, "type"),
        "str": _arg("go2", REJECT, "type"),
    }
    register(
        name="Gait.resolve",
        covers="spotkin.Gait.resolve",
        call=lambda c, **k: sk.Gait("walk").resolve(**k),
        slots=[Custom("robot", robots)],
        probe=_resolved_probe,
    )
    velocity = Custom(
        "velocity",
        {
            "valid": _arg(np.array([0.2, 0.0, 0.1])),
            "list": _arg([0.1, 0.05, 0.0]),
            "batch": _arg(np.array([[0.1, 0.0, 0.0], [0.0, 0.05, 0.3]])),
            "batch2x1": _arg(np.zeros((2, 1, 3))),
            "empty": _arg(np.zeros((0, 3))),
            "float32": _arg(np.array([0.2, 0.0, 0.1], dtype=np.float32)),
            "int": _arg(np.zeros(3, dtype=np.int64)),
            "fast": _arg(np.array([30.0, 0.0, 0.0])),
            "nan": _arg(np.array([0.1, math.nan, 0.0]), REJECT, "value"),
            "inf": _arg(np.array([math.inf, 0.0, 0.0]), REJECT, "value"),
            "short": _arg(np.zeros(2), REJECT, "value"),
            "scalar": _arg(0.3, REJECT, "value"),
            "complex": _arg(np.zeros(3, dtype=complex), REJECT, "type"),
            "str": _arg("fast", REJECT, "type"),
            "none": _arg(None, REJECT, "type"),
        },
    )
    gaits = Custom(
        "gait",
        {
            "valid": _arg(sk.Gait("trot")),
            "walk": _arg(sk.Gait("walk")),
            "stand": _arg(sk.Gait("stand")),
            "name": _arg("pace"),
            "custom": _arg(sk.Gait("custom", duty=0.7, offsets=TROT)),
            "unknown": _arg("canter", REJECT, "value"),
            "int": _arg(3, REJECT, "type"),
            "none": _arg(None, REJECT, "type"),
        },
    )
    attitude = attitude_slot()
    changes = Custom(
        "changes",
        {
            "valid": _arg(()),
            "schedule": _arg([(0.02, "walk", None), (0.05, None, [0.1, 0.0, 0.2])]),
            "gait_object": _arg([(0.0, sk.Gait("pace"), np.zeros(3))]),
            "unsorted": _arg([(0.05, "trot", None), (0.01, None, (0.0, 0.1, 0.0))]),
            "late": _arg([(100.0, "walk", None)]),
            "pair": _arg([(0.02, "walk")], REJECT, "value"),
            "nan_time": _arg([(math.nan, "walk", None)], REJECT, "value"),
            "unknown": _arg([(0.02, "canter", None)], REJECT, "value"),
            "bad_gait": _arg([(0.02, 5, None)], REJECT, "type"),
            "short_velocity": _arg([(0.02, None, [0.1, 0.0])], REJECT, "value"),
            "inf_velocity": _arg([(0.02, None, [math.inf, 0.0, 0.0])], REJECT, "value"),
            "int": _arg(3, REJECT, "type"),
        },
    )
    for key, covers in (("go2", "spotkin.Robot.plan_gait"), ("spot", "spotkin.Spot.plan_gait")):
        register(
            name=f"{covers.split('.', 1)[1]}[{key}]",
            covers=covers,
            call=lambda c, key=key, **k: c.robot(key).plan_gait(**k),
            slots=[
                gaits,
                velocity,
                Real("duration", DURATION),
                Real("rate", RATE),
                attitude,
                changes,
            ],
            probe=_plan_probe,
        )
