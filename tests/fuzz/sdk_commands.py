"""Registry entries of ``spotkin.sdk``'s joint commands: ``joint_positions_message``,
``joint_command_positions``, ``arm_joint_position_message`` and ``arm_joint_positions``."""

from __future__ import annotations

import math

import numpy as np
from bosdyn.api import arm_command_pb2, basic_command_pb2, robot_command_pb2
from bosdyn.client.robot_command import RobotCommandBuilder

from spotkin import sdk

from .batch import Batch
from .entry import register
from .outputs import describe
from .sdk_conversions import array_probe, nested_messages, plain
from .sdk_messages import Q_STAND, same, type_errors
from .slots import REJECT, Arg, Choice, Custom

# values of a batch slot that a joint command must refuse (NaN, Inf, beyond float32)
COMMAND_REFUSED = {
    "nan",
    "inf",
    "-inf",
    "nan_all",
    "nan_single",
    "big",
    "-big",
    "mag_1e300",
    "float32_nan",
    "float32_inf",
}


def register_entries() -> None:
    """Registers these entries (:mod:`fuzz.sdk` calls it when the SDK is installed)."""
    # ---- joint commands ----

    def command_probe(result, kw, c):
        parts = [np.asarray(kw["q12"], dtype=np.float64)]
        if kw.get("q_arm") is not None:
            parts.append(np.asarray(kw["q_arm"], dtype=np.float64))
            parts.append(np.asarray(kw["gripper"], dtype=np.float64)[..., None])
        width = sum(p.shape[-1] for p in parts)
        extras = {
            f: np.asarray(kw[f], dtype=np.float64) for f in ("velocity", "load") if kw.get(f) is not None
        }
        lead = np.broadcast_shapes(*(p.shape[:-1] for p in [*parts, *extras.values()]))
        position = np.concatenate([np.broadcast_to(p, (*lead, p.shape[-1])) for p in parts], -1).reshape(
            -1, width
        )
        messages = nested_messages(result, lead, basic_command_pb2.JointCommand.UpdateRequest)
        if isinstance(messages, str):
            return messages
        for k, message in enumerate(messages):
            if list(message.position) != position[k].astype(np.float32).tolist():
                return f"message {k}: position {list(message.position)}, expected {position[k].tolist()}"
            for field in ("velocity", "load"):
                want = (
                    np.broadcast_to(extras[field], (*lead, width)).reshape(-1, width)[k]
                    if field in extras
                    else np.zeros(0)
                )
                if list(getattr(message, field)) != want.astype(np.float32).tolist():
                    return f"message {k}: {field} {list(getattr(message, field))}, expected {want.tolist()}"
        return None

    def command_rule(with_arm):
        def rule(plan):
            if any(v in COMMAND_REFUSED for v in plan.values()):
                return REJECT
            arm = plan["q_arm"] not in ("omit", "none")
            grip = plan["gripper"] not in ("omit", "none")
            extra = any(plan[f] not in ("omit", "none") for f in ("velocity", "load"))
            if arm != grip:
                return REJECT
            if extra and arm != with_arm:
                return REJECT  # 12 velocities with 19 joints, or 19 with 12
            return None

        return rule

    for with_arm in (False, True):
        width = 19 if with_arm else 12
        default = "valid" if with_arm else "omit"
        register(
            name=f"sdk.joint_positions_message[{'arm' if with_arm else 'legs'}]",
            covers="spotkin.sdk.joint_positions_message",
            call=lambda c, **k: sdk.joint_positions_message(**k),
            slots=[
                Batch("q12", (12,)),
                Batch("q_arm", (6,), optional=True, default=default),
                Batch("gripper", (), optional=True, default=default),
                Batch("velocity", (width,), optional=True, default="omit"),
                Batch("load", (width,), optional=True, default="omit"),
            ],
            baseline=lambda c, rng, n, width=width: {
                "q12": Q_STAND + rng.uniform(-0.2, 0.2, (n, 12)),
                "q_arm": rng.uniform(-1, 1, (n, 6)),
                "gripper": rng.uniform(-1, 0, n),
                "velocity": rng.uniform(-1, 1, (n, width)),
                "load": rng.uniform(-5, 5, (n, width)),
            },
            probe=command_probe,
            pair_rule=command_rule(with_arm),
        )

    def update(count=19, velocity=True):
        values = np.random.default_rng(count).uniform(-1, 1, count).tolist()
        message = basic_command_pb2.JointCommand.UpdateRequest(position=values)
        if velocity:
            message.velocity.extend(values)
            message.load.extend(values)
        return message

    commands = {
        "valid": lambda c, r, b: Arg(update()),
        "legs": lambda c, r, b: Arg(update(12)),
        "positions_only": lambda c, r, b: Arg(update(19, velocity=False)),
        "stream_request": lambda c, r, b: Arg(
            robot_command_pb2.JointControlStreamRequest(joint_command=update())
        ),
        "list": lambda c, r, b: Arg([update(), update(12)]),
        "empty_list": lambda c, r, b: Arg([]),
        "count_7": lambda c, r, b: Arg(update(7), REJECT, "value"),
        "empty_message": lambda c, r, b: Arg(basic_command_pb2.JointCommand.UpdateRequest(), REJECT, "value"),
        "nested_list": lambda c, r, b: Arg([[update()]], REJECT, "type"),
        "wrong_message": lambda c, r, b: Arg(arm_command_pb2.ArmJointPosition(), REJECT, "type"),
        **type_errors(update),
    }

    def read_command(message, field):
        if isinstance(message, robot_command_pb2.JointControlStreamRequest):
            message = message.joint_command
        values = np.full(19, np.nan)
        got = list(getattr(message, field))
        values[: len(got)] = got
        return values

    def command_read_probe(result, kw, c):
        field = kw.get("field", "position")
        message = kw["message"]
        want = (
            np.array([read_command(m, field) for m in message]).reshape(-1, 19)
            if isinstance(message, list)
            else read_command(message, field)
        )
        if not (isinstance(result, tuple) and len(result) == 3):
            return f"not (q12, q_arm, gripper): {describe(result)}"
        return (
            same(result[0], want[..., :12], "q12")
            or same(result[1], want[..., 12:18], "q_arm")
            or same(result[2], want[..., 18], "gripper")
        )

    register(
        name="sdk.joint_command_positions",
        covers="spotkin.sdk.joint_command_positions",
        call=lambda c, **k: sdk.joint_command_positions(**k),
        slots=[
            Custom("message", commands),
            Choice("field", "position", ("position", "velocity", "load"), default="omit"),
        ],
        probe=command_read_probe,
        pair_rule=lambda plan: (
            REJECT
            if plan["message"] in ("positions_only",) and plan["field"] in ("choice:velocity", "choice:load")
            else None
        ),
    )

    def arm_message_probe(result, kw, c):
        q, lead, _ = plain(kw["q_arm"], (6,))
        messages = nested_messages(result, lead, arm_command_pb2.ArmJointPosition)
        if isinstance(messages, str):
            return messages
        for k, (message, row) in enumerate(zip(messages, q.reshape(-1, 6))):
            if message != RobotCommandBuilder.create_arm_joint_trajectory_point(*row.tolist()).position:
                return f"message {k} differs from RobotCommandBuilder's for {row.tolist()}"
        return None

    register(
        name="sdk.arm_joint_position_message",
        covers="spotkin.sdk.arm_joint_position_message",
        call=lambda c, **k: sdk.arm_joint_position_message(**k),
        slots=[Batch("q_arm", (6,))],
        baseline=lambda c, rng, n: {"q_arm": rng.uniform(-2, 2, (n, 6))},
        probe=arm_message_probe,
        pair_rule=lambda plan: REJECT if plan["q_arm"] in COMMAND_REFUSED else None,
    )

    def arm_point(seed=1, clear=()):
        q = np.random.default_rng(seed).uniform(-1, 1, 6).tolist()
        point = RobotCommandBuilder.create_arm_joint_trajectory_point(*q)
        for joint in clear:
            point.position.ClearField(joint)
        return point

    def arm_read(value):
        if isinstance(value, arm_command_pb2.ArmJointTrajectoryPoint):
            value = value.position
        return [
            getattr(value, j).value if value.HasField(j) else math.nan
            for j in ("sh0", "sh1", "el0", "el1", "wr0", "wr1")
        ]

    def nan_joint(seed=1):
        point = arm_point(seed)
        point.position.el0.value = math.nan
        return point.position

    arm_messages = {
        "valid": lambda c, r, b: Arg(arm_point().position),
        "point": lambda c, r, b: Arg(arm_point()),
        "repeated": lambda c, r, b: Arg(
            RobotCommandBuilder.arm_joint_command(
                0.1, -1.0, 1.2, 0.0, 0.3, -0.2
            ).synchronized_command.arm_command.arm_joint_move_command.trajectory.points
        ),
        "list": lambda c, r, b: Arg([arm_point(1), arm_point(2).position]),
        "nested": lambda c, r, b: Arg([[arm_point(1)], [arm_point(2)]]),
        "empty": lambda c, r, b: Arg([]),
        "partial": lambda c, r, b: Arg(arm_point(clear=("sh1", "wr1")).position),
        "nothing_set": lambda c, r, b: Arg(arm_command_pb2.ArmJointPosition()),
        "nan": lambda c, r, b: Arg(nan_joint()),
        "ragged": lambda c, r, b: Arg([[arm_point()], []], REJECT, "value"),
        "wrong_message": lambda c, r, b: Arg(update(), REJECT, "type"),
        **type_errors(arm_point),
    }

    register(
        name="sdk.arm_joint_positions",
        covers="spotkin.sdk.arm_joint_positions",
        call=lambda c, **k: sdk.arm_joint_positions(**k),
        slots=[Custom("message", arm_messages)],
        probe=array_probe((6,), arm_read, "message"),
    )
