"""Gait plans: :meth:`spotkin.Robot.plan_gait` and its result, :class:`GaitPlan`.

The plan is computed by the compiled planner (``_core.plan_gait``, cpp/src/gait_plan.cpp): every
command of a batch on the threads, each one's ticks in order. It mirrors the pure-Python reference
(:mod:`spotkin.reference.gait_plan`), which the tests compare it with sample by sample.
``Robot.plan_gait`` is defined in :mod:`spotkin.model.robot` and calls through the registry that this
module fills on import (the model layer may not import motion, which sits above it).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .. import _core
from .._support.boundary import as_real, as_scalar, check_trailing
from ..model import robot as robot_module
from ..reference.gait_plan import KEYS
from .gait import Gait

__all__ = ["GaitPlan"]

GAIT_NUMBERS = 44
"""The length of :func:`gait_numbers`."""
MAX_TICKS = 1e8
"""The most ticks a plan may have (duration * rate)."""


class GaitPlan(NamedTuple):
    """A planned walk, from :meth:`spotkin.Robot.plan_gait`: one row per tick, for each command (the
    leading dimensions ``...`` of the velocity given)."""

    t: np.ndarray
    """(ticks,) s: k / rate."""
    body_pose: np.ndarray
    """(..., ticks, 6) [x, y, z, a, b, c], Euler "XYZ" as :meth:`spotkin.Robot.body_ik` takes it (the
    yaw c continuous, not wrapped)."""
    feet: np.ndarray
    """(..., ticks, n_legs, 3) world foot points."""
    contact: np.ndarray
    """(..., ticks, n_legs) bool: the planned stance."""
    q: np.ndarray
    """(..., ticks, 3 n_legs) rad, :attr:`spotkin.Robot.leg_joint_names` order, each tick's IK seeded with
    the previous tick's q."""
    qd: np.ndarray
    """(..., ticks, 3 n_legs) rad/s, from the leg Jacobians and the feet's and body's velocities."""
    tau: np.ndarray
    """(..., ticks, 3 n_legs) N m feedforward: each leg's gravity torques minus J^T f of its stance force."""
    status: np.ndarray
    """(..., ticks) int8 :class:`spotkin.Status`: the worst leg's IK status."""
    margin: np.ndarray
    """(..., ticks) m: the centre of mass's projection to the support polygon, positive inside; NaN at a
    tick where a leg has no IK answer (the centre of mass is then unknown)."""
    shortened: np.ndarray
    """(..., ticks) bool: the command was slowed to fit the legs' steps, or a swinging foot's foothold was
    pulled back towards its nominal point to be reachable."""
    residual: np.ndarray
    """(..., ticks, 6) the wrench the stance forces leave unbalanced, [force (N); moment about the centre
    of mass (N m)], world axes: the weight's moment about the line of two feet in a trot, say; NaN at a
    tick where a leg has no IK answer, as :attr:`margin`."""


def gait_numbers(resolved) -> np.ndarray:
    """A resolved gait's numbers (44,) as the compiled planner takes them: the blended numbers of the
    reference planner (``spotkin.reference.gait_plan.KEYS``), each flattened, in that order."""
    return np.concatenate([np.ravel(np.asarray(getattr(resolved, key), dtype=np.float64)) for key in KEYS])


def _as_gait(gait, name: str = "gait") -> Gait:
    if isinstance(gait, str):
        gait = Gait(gait)
    if not isinstance(gait, Gait):
        raise TypeError(f"{name} must be a spotkin.Gait or a preset name, got {type(gait).__name__}")
    return gait


def _changes(robot, changes) -> tuple:
    """The schedule as the compiled planner takes it: times (k,), gaits (k, 44) and velocities (k, 3),
    a NaN row where unchanged; (None, None, None) for none."""
    try:
        items = list(changes)
    except TypeError:
        kind = type(changes).__name__
        raise TypeError(f"changes must be a sequence of (time, gait, velocity), got {kind}") from None
    if not items:
        return None, None, None
    times = np.empty(len(items))
    gaits = np.full((len(items), GAIT_NUMBERS), np.nan)
    velocities = np.full((len(items), 3), np.nan)
    for k, item in enumerate(items):
        try:
            time, gait, velocity = item
        except (TypeError, ValueError):
            raise ValueError(f"changes[{k}] must be (time, gait, velocity), got {item!r}") from None
        times[k] = as_scalar(time, f"changes[{k}] time")
        if not math.isfinite(times[k]):
            raise ValueError(f"changes[{k}] time must be finite, got {times[k]}")
        if gait is not None:
            gaits[k] = gait_numbers(_as_gait(gait, f"changes[{k}] gait").resolve(robot))
        if velocity is not None:
            v = as_real(velocity, f"changes[{k}] velocity", np.float64)
            if v.shape != (3,) or not np.isfinite(v).all():
                raise ValueError(f"changes[{k}] velocity must be finite (vx, vy, yaw rate), got {v.tolist()}")
            velocities[k] = v
    return times, gaits, velocities


def _plan_gait(robot, gait, velocity, duration, rate, attitude, changes=()) -> GaitPlan:
    """:meth:`spotkin.Robot.plan_gait`: checks the arguments, resolves the gait, and runs the compiled
    planner over the commands (..., 3), one plan each."""
    gait = _as_gait(gait)
    velocity = as_real(velocity, "velocity")
    single = velocity.dtype == np.float32  # float32 in, float32 out (as NumPy); computed in float64
    velocity = velocity.astype(np.float64, copy=False)
    lead = check_trailing(velocity, "velocity", (3,))
    if not np.isfinite(velocity).all():
        raise ValueError("velocity must be finite (vx, vy, yaw rate), got NaN or Inf")
    duration, rate = as_scalar(duration, "duration"), as_scalar(rate, "rate")
    if not (math.isfinite(duration) and duration > 0.0):
        raise ValueError(f"duration must be finite and > 0, got {duration}")
    if not (math.isfinite(rate) and rate > 0.0):
        raise ValueError(f"rate must be finite and > 0, got {rate}")
    if duration * rate > MAX_TICKS:
        raise ValueError(f"duration * rate must be at most {MAX_TICKS:.0e} ticks, got {duration * rate:.3g}")
    attitude = as_real(attitude, "attitude", np.float64)
    if attitude.shape != (2,) or not np.isfinite(attitude).all():
        raise ValueError(f"attitude must be finite (roll, pitch), got {attitude.tolist()}")
    resolved = gait.resolve(robot)
    schedule = _changes(robot, changes)
    ticks = round(duration * rate) + 1
    commands = np.ascontiguousarray(velocity.reshape(-1, 3))
    arrays = _core.plan_gait(
        robot._statics, gait_numbers(resolved), commands, attitude, ticks, rate, *schedule
    )
    fields = {"t": np.arange(ticks) / rate}
    for name, array in zip(GaitPlan._fields[1:], arrays):
        fields[name] = array.reshape(*lead, *array.shape[1:])
    if single:
        fields = {k: v.astype(np.float32) if v.dtype == np.float64 else v for k, v in fields.items()}
    return GaitPlan(**fields)


robot_module._MOTION["plan_gait"] = _plan_gait
