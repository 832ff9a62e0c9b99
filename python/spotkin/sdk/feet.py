"""Feet: positions from robot states (reported, by kinematics or from the frame tree) and foot states
from arrays. Part of :mod:`spotkin.sdk` (documented there)."""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real
from .common import (
    _CONTACT_LOST,
    _CONTACT_MADE,
    FOOT_FRAME_NAMES,
    _is_sequence,
    _read_vec3,
    _type_name,
    geometry_pb2,
    robot_state_pb2,
)
from .frames import _frame_name, frame_transform
from .joints import joint_positions

# ---- feet -------------------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=1)
def _default_spot():
    from ..model.spot import Spot

    return Spot()


def _checked_spot(spot):
    from ..model.spot import Spot

    if spot is None:
        return _default_spot()
    if not isinstance(spot, Spot):
        raise TypeError(f"spot must be an sk.Spot or None, got {_type_name(spot)}")
    return spot


_SOURCES = ("auto", "foot_state", "kinematics", "frames")


def _one_feet(state, frame: str, source: str, spot, where: str) -> np.ndarray:
    if isinstance(state, robot_state_pb2.RobotState):
        foot_list = state.foot_state
    elif isinstance(state, robot_state_pb2.KinematicState):
        foot_list = ()
    else:
        raise TypeError(f"{where} must be a bosdyn.api.RobotState or KinematicState, got {_type_name(state)}")
    chosen = source
    if source == "auto":
        chosen = "foot_state" if len(foot_list) == 4 else "kinematics"
    if chosen == "foot_state":
        if len(foot_list) != 4:
            raise ValueError(
                f"{where} has {len(foot_list)} foot states; source='foot_state' needs 4 (fl, fr, hl, hr)"
            )
        feet = np.array([_read_vec3(foot.foot_position_rt_body) for foot in foot_list], dtype=np.float64)
    elif chosen == "kinematics":
        q12, _ = joint_positions(state)
        feet = spot.body_fk(np.eye(4), q12)
    else:
        feet = np.array([frame_transform(state, "body", name)[:3, 3] for name in FOOT_FRAME_NAMES])
    if frame != "body":
        T = frame_transform(state, frame, "body")
        with np.errstate(invalid="ignore"):
            feet = feet @ T[:3, :3].T + T[:3, 3]
    return feet


def foot_positions(state, frame: str = "body", *, source: str = "auto", spot=None) -> np.ndarray:
    """(4, 3) foot points in ``frame``, legs in order fl, fr, hl, hr, float64.

    ``state`` is a ``bosdyn.api.RobotState`` (or a ``KinematicState``, which has no foot states), or a
    sequence of them (giving (n, 4, 3)). ``source``: ``"foot_state"`` reads
    ``RobotState.foot_state`` (``foot_position_rt_body``, in the body frame); ``"kinematics"`` runs
    spotkin's FK on the state's leg joints (``spot``: the :class:`spotkin.Spot` model, default
    ``sk.Spot()``; a leg with a missing joint gets NaN); ``"frames"`` reads the tree's ``fl_foot``
    ... ``hr_foot`` frames; ``"auto"`` (default) takes the foot states when all four are there, else
    the kinematics. The points are then moved into ``frame`` through the state's frame tree
    (``frame_transform(state, frame, "body")``): ``"body"``, ``"odom"``, ``"vision"``, or any frame of
    the tree. Each is spotkin's foot point (the foot-sphere centre), as :meth:`spotkin.Spot.body_ik`
    takes feet.
    """
    frame = _frame_name(frame, "frame")
    if not isinstance(source, str) or source not in _SOURCES:
        raise ValueError(f"source must be one of {_SOURCES}, got {source!r}")
    spot = _checked_spot(spot)
    if isinstance(state, (robot_state_pb2.RobotState, robot_state_pb2.KinematicState)):
        return _one_feet(state, frame, source, spot, "state")
    if not _is_sequence(state):
        raise TypeError(
            f"state must be a bosdyn.api.RobotState or KinematicState, or a sequence; got {_type_name(state)}"
        )
    out = np.empty((len(state), 4, 3))
    for k, item in enumerate(state):
        out[k] = _one_feet(item, frame, source, spot, f"state[{k}]")
    return out


def foot_states(feet: ArrayLike, contact=None) -> list:
    """A list of ``bosdyn.api.FootState`` (for ``RobotState.foot_state``) from foot points ``feet``
    (n, 3) in the body frame, in leg order (fl, fr, hl, hr for Spot); the inverse of
    :func:`foot_positions` with ``source="foot_state"``. ``contact``: None (``CONTACT_UNKNOWN``) or n
    booleans (True: ``CONTACT_MADE``, False: ``CONTACT_LOST``). NaN coordinates stay NaN."""
    feet = as_real(feet, "feet", np.float64)
    if feet.ndim != 2 or feet.shape[1] != 3:
        raise ValueError(f"feet must have shape (n, 3), got {feet.shape}")
    if contact is not None:
        if isinstance(contact, (str, bytes)):
            raise TypeError(f"contact must be None or {len(feet)} booleans, got {_type_name(contact)}")
        flags = np.asarray(contact)
        if flags.dtype != np.bool_:
            raise TypeError(f"contact must be None or {len(feet)} booleans, got dtype {flags.dtype}")
        if flags.shape != (len(feet),):
            raise ValueError(f"contact must have shape ({len(feet)},), got {flags.shape}")
        contact = flags.tolist()
    states = []
    for k, (x, y, z) in enumerate(feet.tolist()):
        state = robot_state_pb2.FootState(foot_position_rt_body=geometry_pb2.Vec3(x=x, y=y, z=z))
        if contact is not None:
            state.contact = _CONTACT_MADE if contact[k] else _CONTACT_LOST
        states.append(state)
    return states
