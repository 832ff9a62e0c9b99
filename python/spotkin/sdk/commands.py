"""Joint commands: leg and arm joint-position messages from arrays, and back. Part of :mod:`spotkin.sdk`
(documented there)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real, check_trailing
from .common import (
    _ARM_FIELDS,
    _FLOAT32_MAX,
    _gather,
    _is_sequence,
    _nested,
    _type_name,
    arm_command_pb2,
    basic_command_pb2,
    robot_command_pb2,
    wrappers_pb2,
)
from .joints import _field

# ---- joint commands ---------------------------------------------------------------------------------------


def _command_values(value, name: str, width: int) -> np.ndarray:
    """A (..., width) float64 array of finite numbers that a float32 field holds."""
    array = as_real(value, name, np.float64)
    check_trailing(array, name, (width,))
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(array) <= _FLOAT32_MAX)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{name}[{', '.join(map(str, where))}] is {array[where]}: a joint command must hold finite "
            "numbers within float32 range (the message's fields are float32)"
        )
    return array


def joint_positions_message(
    q12: ArrayLike,
    q_arm: ArrayLike | None = None,
    gripper: ArrayLike | None = None,
    *,
    velocity: ArrayLike | None = None,
    load: ArrayLike | None = None,
):
    """The SDK's joint-position message for a joint command: a ``bosdyn.api.JointCommand.UpdateRequest``
    (what ``JointControlStreamRequest.joint_command`` holds), its arrays in the SDK's joint index
    order (:data:`JOINT_NAMES`).

    ``q12`` (..., 12) are the leg targets (rad, :data:`LEG_JOINT_NAMES` order). With ``q_arm``
    (..., 6) the message holds all 19 joints, so ``gripper`` (..., ) (rad) must be given too.
    ``velocity`` and ``load`` (..., 12 or 19, matching) fill those arrays; fields left out stay
    empty. One message for single targets; nested lists of messages (a stream) for leading
    dimensions, which broadcast. The fields are float32 (about 1e-7 rad of rounding). A NaN or Inf
    target (such as a failed IK's NaN), or one beyond float32, raises ``ValueError``: a command
    never carries one. Gains, timing and the request header are yours to set.
    """
    parts = [_command_values(q12, "q12", 12)]
    if q_arm is not None:
        if gripper is None:
            raise ValueError("gripper must be given with q_arm: the 19-joint command includes arm0.f1x")
        parts.append(_command_values(q_arm, "q_arm", 6))
        gripper = as_real(gripper, "gripper", np.float64)
        parts.append(_command_values(gripper[..., None], "gripper", 1))
    elif gripper is not None:
        raise ValueError("gripper needs q_arm: a leg-only command has 12 joints")
    width = 12 if q_arm is None else 19
    extras = {}
    for field, value in (("velocity", velocity), ("load", load)):
        if value is not None:
            extras[field] = _command_values(value, field, width)
    leads = [p.shape[:-1] for p in parts] + [e.shape[:-1] for e in extras.values()]
    try:
        lead = np.broadcast_shapes(*leads)
    except ValueError:
        raise ValueError(f"q12, q_arm, gripper, velocity and load do not broadcast: {leads}") from None
    position = np.concatenate([np.broadcast_to(p, (*lead, p.shape[-1])) for p in parts], axis=-1)
    fields = {"position": position.reshape(-1, width)}
    fields.update({f: np.broadcast_to(v, (*lead, width)).reshape(-1, width) for f, v in extras.items()})
    messages = []
    for k in range(len(fields["position"])):
        message = basic_command_pb2.JointCommand.UpdateRequest()
        for field, rows in fields.items():
            getattr(message, field).extend(rows[k].tolist())
        messages.append(message)
    return _nested(messages, tuple(lead))


def joint_command_positions(message, field: str = "position") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q12, q_arm, gripper)`` read back from a joint command: a ``JointCommand.UpdateRequest`` or a
    ``JointControlStreamRequest`` (its ``joint_command``), or a sequence of them (giving (n, 12),
    (n, 6), (n,)); the inverse of :func:`joint_positions_message`. ``field`` is ``"position"``,
    ``"velocity"`` or ``"load"``. A 12-joint command gives NaN for the arm and gripper; an array of
    another length raises ``ValueError``."""
    field = _field(field, ("position", "velocity", "load"))

    def one(item, where):
        if isinstance(item, robot_command_pb2.JointControlStreamRequest):
            item = item.joint_command
        if not isinstance(item, basic_command_pb2.JointCommand.UpdateRequest):
            raise TypeError(
                f"{where} must be a bosdyn.api.JointCommand.UpdateRequest or JointControlStreamRequest, "
                f"got {_type_name(item)}"
            )
        values = np.array(getattr(item, field), dtype=np.float64)
        if values.size not in (12, 19):
            raise ValueError(f"{where}: a joint command's {field} has 12 or 19 values, got {values.size}")
        full = np.full(19, math.nan)
        full[: values.size] = values
        return full

    if _is_sequence(message):
        rows = np.array([one(item, f"message[{k}]") for k, item in enumerate(message)]).reshape(-1, 19)
    else:
        rows = one(message, "message")
    return rows[..., :12].copy(), rows[..., 12:18].copy(), rows[..., 18].copy()


def arm_joint_position_message(q_arm: ArrayLike):
    """A ``bosdyn.api.ArmJointPosition`` (``sh0`` ... ``wr1``, the positions of an
    ``ArmJointTrajectoryPoint`` in an ``ArmJointMoveCommand``) from ``q_arm`` (6,) in
    :data:`ARM_JOINT_NAMES` order; nested lists of them for (..., 6). A NaN or Inf target raises
    ``ValueError``. ``bosdyn.client.robot_command.RobotCommandBuilder.arm_joint_command(*q_arm)``
    builds a whole arm command from the same six numbers."""
    q_arm = _command_values(q_arm, "q_arm", 6)
    messages = [
        arm_command_pb2.ArmJointPosition(
            **{joint: wrappers_pb2.DoubleValue(value=value) for joint, value in zip(_ARM_FIELDS, row)}
        )
        for row in q_arm.reshape(-1, 6).tolist()
    ]
    return _nested(messages, q_arm.shape[:-1])


def _read_arm(value):
    if isinstance(value, arm_command_pb2.ArmJointTrajectoryPoint):
        value = value.position
    if isinstance(value, arm_command_pb2.ArmJointPosition):
        return tuple(getattr(value, j).value if value.HasField(j) else math.nan for j in _ARM_FIELDS)
    return None


def arm_joint_positions(message) -> np.ndarray:
    """``q_arm`` (6,) float64 from a ``bosdyn.api.ArmJointPosition`` or ``ArmJointTrajectoryPoint``;
    (..., 6) from a (nested) sequence of them (a trajectory's ``points``). A joint the message does
    not set (the robot then keeps its current angle) is NaN."""
    return _gather(
        message, "message", _read_arm, 6, "a bosdyn.api.ArmJointPosition or ArmJointTrajectoryPoint"
    )
