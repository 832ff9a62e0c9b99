"""Entries for the closed-loop gait controller: the ``GaitController`` constructor, ``step`` (on Go2
standing at its nominal stance, a first tick and a second one) and ``reset``."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk
from spotkin.motion import JointCommand, RobotState

from .entry import register
from .gait import _arg, attitude_slot
from .outputs import describe
from .slots import REJECT, Arg, Custom, Real


def standing_state(robot, **changes) -> RobotState:
    """The robot at rest on its trot's nominal stance."""
    gait = sk.Gait("trot").resolve(robot)
    pose = np.array([0.0, 0.0, gait.height, 0.0, 0.0, 0.0])
    q = robot.body_ik(pose, gait.stance).q
    n = robot.n_legs
    values = {
        "position": pose[:3],
        "quaternion": np.array([0.0, 0.0, 0.0, 1.0]),
        "linear_velocity": np.zeros(3),
        "angular_velocity": np.zeros(3),
        "q": q,
        "qd": np.zeros(3 * n),
        "contact": np.ones(n, dtype=bool),
    }
    values.update(changes)
    return RobotState(**values)


def _command_probe(command, kw, c):
    if not isinstance(command, JointCommand):
        return f"not a JointCommand: {describe(command)}"
    for name in ("q", "qd", "tau", "kp", "kd"):
        value = getattr(command, name)
        if value.shape[-1] != 12 or not np.isfinite(value).all():
            return f"{name}: {describe(value)}"
    if (command.kp < 0).any() or (command.kd < 0).any():
        return "negative gains"
    if command.contact.shape[-1] != 4 or command.contact.dtype != np.bool_:
        return f"contact {describe(command.contact)}"
    return None


def _states():
    def state(**changes):
        return lambda c, r, b: Arg(standing_state(c.robot("go2"), **changes))

    def bad(value, why):
        return lambda c, r, b: Arg(value(c), REJECT, why)

    def go2(c):
        return c.robot("go2")

    return Custom(
        "state",
        {
            "valid": state(),
            "no_contact": state(contact=None),
            "moving": state(
                linear_velocity=np.array([0.2, 0.0, 0.0]), angular_velocity=np.array([0, 0, 0.1])
            ),
            "float32": lambda c, r, b: Arg(
                standing_state(go2(c), q=standing_state(go2(c)).q.astype(np.float32))
            ),
            "nan_q": bad(lambda c: standing_state(go2(c), q=np.full(12, math.nan)), "value"),
            "inf_position": bad(
                lambda c: standing_state(go2(c), position=np.array([0, 0, math.inf])), "value"
            ),
            "wrong_width": bad(lambda c: standing_state(go2(c), q=np.zeros(9), qd=np.zeros(9)), "value"),
            "wrong_contact": bad(lambda c: standing_state(go2(c), contact=np.ones(3, dtype=bool)), "value"),
            "not_a_state": _arg(np.zeros(12), REJECT, "type"),
            "none": _arg(None, REJECT, "type"),
        },
    )


def controller_entries():
    robots = {
        "valid": lambda c, r, b: Arg(c.robot("go2")),
        "spot": lambda c, r, b: Arg(c.spot),
        "hexapod": lambda c, r, b: Arg(c.robot("hexapod"), REJECT, "value"),
        "leg": lambda c, r, b: Arg(c.leg, REJECT, "type"),
        "none": _arg(None, REJECT, "type"),
    }
    gaits = Custom(
        "gait",
        {
            "valid": _arg("trot"),
            "walk": _arg(sk.Gait("walk")),
            "custom": _arg(sk.Gait("trot", period=0.4)),
            "unknown": _arg("canter", REJECT, "value"),
            "int": _arg(3, REJECT, "type"),
        },
        default="omit",
    )
    attitude = attitude_slot()
    register(
        name="GaitController",
        covers="spotkin.GaitController",
        call=lambda c, **k: sk.GaitController(**k),
        slots=[Custom("robot", robots), gaits, Real("rate", 500.0, default="omit"), attitude],
        probe=lambda ctrl, kw, c: None if isinstance(ctrl, sk.GaitController) else f"made {describe(ctrl)}",
    )
    velocity = Custom(
        "velocity",
        {
            "valid": _arg(np.array([0.2, 0.0, 0.1])),
            "list": _arg([0.1, 0.05, 0.0]),
            "int": _arg(np.zeros(3, dtype=np.int64)),
            "fast": _arg(np.array([30.0, 0.0, 0.0])),
            "nan": _arg(np.array([0.1, math.nan, 0.0]), REJECT, "value"),
            "inf": _arg(np.array([math.inf, 0.0, 0.0]), REJECT, "value"),
            "short": _arg(np.zeros(2), REJECT, "value"),
            "complex": _arg(np.zeros(3, dtype=complex), REJECT, "type"),
            "str": _arg("fast", REJECT, "type"),
            "none": _arg(None, REJECT, "type"),
        },
        default="omit",
    )
    switch = Custom(
        "gait",
        {
            "valid": _arg(None),
            "pace": _arg("pace"),
            "walk": _arg(sk.Gait("walk")),
            "unknown": _arg("canter", REJECT, "value"),
            "int": _arg(3, REJECT, "type"),
        },
        default="omit",
    )

    def step(c, **k):
        controller = sk.GaitController(c.robot("go2"))
        controller.step(0.0, standing_state(c.robot("go2")))  # a first tick, then the fuzzed one
        return controller.step(**k)

    register(
        name="GaitController.step",
        covers="spotkin.GaitController.step",
        call=step,
        slots=[Real("t", 0.002, "finite"), _states(), velocity, switch],
        probe=_command_probe,
        pair_rule=_backwards,
    )

    def reset(c):
        controller = sk.GaitController(c.robot("go2"))
        controller.step(0.0, standing_state(c.robot("go2")))
        controller.reset()
        return controller.last

    register(
        name="GaitController.reset",
        covers="spotkin.GaitController.reset",
        call=reset,
        probe=lambda last, kw, c: None if last is None else f"still remembers {describe(last)}",
    )


def _backwards(plan):
    """A time before the first tick's (t < 0) goes backwards: ValueError."""
    return REJECT if plan.get("t") == "negative" else None
