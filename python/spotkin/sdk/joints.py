"""Joint states: names and values from robot states, and kinematic states built from arrays. Part of
:mod:`spotkin.sdk` (documented there)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real, check_trailing
from .common import (
    _FIELDS,
    _Q_COLUMN,
    JOINT_NAMES,
    LEG_JOINT_NAMES,
    _is_sequence,
    _type_name,
    geometry_pb2,
    robot_state_pb2,
)
from .frames import frame_tree_snapshot

# ---- joint states ------------------------------------------------------------------------------------------


def _field(field: str, allowed=_FIELDS) -> str:
    if not isinstance(field, str) or field not in allowed:
        raise ValueError(f"field must be one of {allowed}, got {field!r}")
    return field


def _joint_source(state):
    """("named", repeated JointState) or ("indexed", CombinedJointStates), or None."""
    if isinstance(state, robot_state_pb2.RobotState):
        return "named", state.kinematic_state.joint_states
    if isinstance(state, robot_state_pb2.KinematicState):
        return "named", state.joint_states
    if isinstance(state, robot_state_pb2.RobotStateStreamResponse):
        return "indexed", state.joint_states
    if isinstance(state, robot_state_pb2.CombinedJointStates):
        return "indexed", state
    return None


_STATE_KINDS = "a bosdyn.api.RobotState, KinematicState, RobotStateStreamResponse or CombinedJointStates"


def _one_joint_states(state, field: str, where: str, present: bool = False):
    """(names, values), and with ``present`` a mask of the values the state sets."""
    source = _joint_source(state)
    if source is None:
        raise TypeError(f"{where} must be {_STATE_KINDS}, got {_type_name(state)}")
    kind, joints = source
    if kind == "named":
        names = tuple(joint.name for joint in joints)
        if len(set(names)) != len(names):
            twice = sorted({name for name in names if names.count(name) > 1})
            raise ValueError(f"{where} lists the joints {twice} twice")
        has = [joint.HasField(field) for joint in joints]
        values = np.array(
            [getattr(joint, field).value if set_ else math.nan for joint, set_ in zip(joints, has)],
            dtype=np.float64,
        )
        return (names, values, np.array(has, dtype=bool)) if present else (names, values)
    if field == "acceleration":
        raise ValueError("field 'acceleration': the streamed joint states have position, velocity and load")
    values = np.array(getattr(joints, field), dtype=np.float64)
    if values.size not in (0, len(LEG_JOINT_NAMES), len(JOINT_NAMES)):
        raise ValueError(
            f"{where}: the streamed joint {field}s must number 12 (legs) or 19 (legs, arm, gripper), "
            f"got {values.size}"
        )
    names = JOINT_NAMES[: values.size]
    return (names, values, np.ones(values.size, dtype=bool)) if present else (names, values)


def joint_states(state, field: str = "position") -> tuple[tuple[str, ...], np.ndarray]:
    """``(names, values)``: a robot state's joints by name, as the SDK reports them (the pairs
    :meth:`spotkin.Robot.q_from_names` reads).

    ``state`` is a ``bosdyn.api.RobotState`` or ``KinematicState`` (``joint_states``, names as
    given, ``arm0.hr0`` and ``arm0.f1x`` included), or a streamed ``RobotStateStreamResponse`` or
    ``CombinedJointStates`` (arrays in the SDK's joint index order, named by :data:`JOINT_NAMES`).
    ``field`` is ``"position"`` (rad), ``"velocity"`` (rad/s), ``"acceleration"`` (rad/s^2) or
    ``"load"`` (N m); a value the state does not set is NaN. ``values`` is float64 (k,). A joint
    listed twice, or a streamed array of another length than 12 or 19, raises ``ValueError``.
    """
    return _one_joint_states(state, _field(field), "state")


def joint_positions(state, *, field: str = "position", missing: str = "nan") -> tuple[np.ndarray, np.ndarray]:
    """``(q12, q_arm)`` from a robot state: the leg joints (12,) in :data:`LEG_JOINT_NAMES` order and
    the arm's (6,) in :data:`ARM_JOINT_NAMES` order, float64.

    ``state`` as in :func:`joint_states`, or a sequence of them (giving (n, 12) and (n, 6)).
    Joints the state does not report (the arm's on a Spot without one) or reports without a
    value are NaN (``missing="nan"``), or raise ``ValueError`` naming them (``missing="raise"``);
    a reported NaN stays NaN in its joint. Other joints (the gripper ``arm0.f1x``, the fixed
    ``arm0.hr0``) are skipped. ``field`` picks positions, velocities, accelerations or loads (see
    :func:`joint_states`).
    """
    field = _field(field)
    if not isinstance(missing, str) or missing not in ("nan", "raise"):
        raise ValueError(f"missing must be 'nan' or 'raise', got {missing!r}")

    def one(item, where):
        names, values, present = _one_joint_states(item, field, where, present=True)
        q = np.full(len(_Q_COLUMN), math.nan)
        found = np.zeros(len(_Q_COLUMN), dtype=bool)
        for name, value, set_ in zip(names, values, present):
            k = _Q_COLUMN.get(name)
            if k is not None:
                q[k], found[k] = value, set_
        if missing == "raise" and not found.all():
            absent = [name for name, k in _Q_COLUMN.items() if not found[k]]
            raise ValueError(f"{where} has no {field} for the joints {absent}")
        return q

    if _joint_source(state) is not None:
        q = one(state, "state")
    elif _is_sequence(state):
        q = np.array([one(item, f"state[{k}]") for k, item in enumerate(state)]).reshape(-1, len(_Q_COLUMN))
    else:
        raise TypeError(f"state must be {_STATE_KINDS}, or a sequence of them; got {_type_name(state)}")
    return q[..., :12].copy(), q[..., 12:].copy()


def _joint_names(names, name: str) -> tuple[str, ...]:
    if isinstance(names, (str, bytes, Mapping)) or not isinstance(names, (Sequence, np.ndarray)):
        raise TypeError(f"{name} must be a sequence of joint names, got {_type_name(names)}")
    listed = tuple(names)
    for item in listed:
        if not isinstance(item, str):
            raise TypeError(f"{name} must hold joint names (str), got {_type_name(item)}")
    if len(set(listed)) != len(listed):
        raise ValueError(f"{name} names a joint twice")
    return tuple(map(str, listed))


def kinematic_state(
    names,
    position: ArrayLike,
    *,
    velocity: ArrayLike | None = None,
    acceleration: ArrayLike | None = None,
    load: ArrayLike | None = None,
    frames=None,
) -> robot_state_pb2.KinematicState:
    """A ``bosdyn.api.KinematicState`` from joint values by name and a frame tree: the inverse of
    :func:`joint_states` and :func:`frame_tree_edges` (for tests, simulators and logs).

    ``names`` is a sequence of k joint names (for Spot ``sk.Spot.joint_names +
    sk.Spot.arm_joint_names``, and ``"arm0.f1x"`` for the gripper); ``position`` and the optional
    ``velocity``, ``acceleration`` and ``load`` are (k,) arrays. A NaN value is left unset (the state
    does not report it; :func:`joint_states` reads it back as NaN). ``frames`` is a
    ``FrameTreeSnapshot`` or ``{child: (parent, parent_tform_child)}`` (see
    :func:`frame_tree_snapshot`).
    """
    names = _joint_names(names, "names")
    columns = {}
    given = {"position": position, "velocity": velocity, "acceleration": acceleration, "load": load}
    if position is None:
        raise TypeError("position must be a real numeric array (k,), got None")
    for field, values in given.items():
        if values is None:
            continue
        array = as_real(values, field, np.float64)
        check_trailing(array, field, (len(names),))
        if array.ndim != 1:
            raise ValueError(f"{field} must have shape ({len(names)},), got {array.shape}")
        columns[field] = array.tolist()
    state = robot_state_pb2.KinematicState()
    for k, name in enumerate(names):
        joint = state.joint_states.add(name=name)
        for field, values in columns.items():
            if not math.isnan(values[k]):
                getattr(joint, field).value = values[k]
    if isinstance(frames, geometry_pb2.FrameTreeSnapshot):
        state.transforms_snapshot.CopyFrom(frames)
    elif isinstance(frames, Mapping):
        state.transforms_snapshot.CopyFrom(frame_tree_snapshot(frames))
    elif frames is not None:
        raise TypeError(
            "frames must be a bosdyn.api.FrameTreeSnapshot or a dict {child: (parent, parent_tform_child)}, "
            f"got {_type_name(frames)}"
        )
    return state
