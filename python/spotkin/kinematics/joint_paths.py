"""Joint-space trajectories: synchronised point-to-point motions (:class:`~spotkin.trajectory.PointToPoint`)
and one IK branch held along a path (:func:`~spotkin.trajectory.hold_branch`). Part of
:mod:`spotkin.trajectory` (documented there)."""

from __future__ import annotations

import math
import numbers
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_index, as_real, quiet_float_errors

PROFILES = ("cubic", "quintic", "trapezoid")


def _choice(value, name: str, choices) -> str:
    """A string option: TypeError for a non-string, ValueError for an unknown one."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, one of {tuple(choices)}, got {type(value).__name__}")
    if value not in choices:
        raise ValueError(f"{name} must be one of {tuple(choices)}, got {value!r}")
    return value


def _flag(value, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a bool, got {type(value).__name__}")
    return bool(value)


def _no_bool(value: ArrayLike, name: str) -> None:
    """TypeError for a bool limit, which the C++ boundary takes as a number (a speed is not a truth value)."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a real number or array, got a bool")
    if isinstance(value, (int, float)):
        return
    try:
        kind = np.asarray(value).dtype.kind
    except (TypeError, ValueError):  # not an array at all: the C++ boundary names it
        return
    if kind == "b":
        raise TypeError(f"{name} must be a real number or array, got a bool array")


# where |qd| and |qdd| peak, in tau = t / t_f: the ends, 1/2 -+ sqrt(3)/6 (quintic), 1/2
_PEAK_TAU = np.array([0.0, 0.5 - math.sqrt(3) / 6, 0.5, 0.5 + math.sqrt(3) / 6, 1.0])


def _limit(value, name: str, *, optional: bool = False, zero_ok: bool = False) -> float:
    """A scalar limit: TypeError unless a real number (bool, str, complex are not), ValueError
    unless finite and positive (or zero, where ``zero_ok``); None means "no limit" where ``optional``."""
    if value is None and optional:
        return math.inf
    if isinstance(value, (bool, np.bool_, str, bytes, complex)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    if not isinstance(value, numbers.Real):  # an array, a list, None...
        array = as_real(value, name)
        if array.shape != ():
            raise ValueError(f"{name} must be a scalar, got shape {array.shape}")
        if np.asarray(value).dtype.kind == "b":
            raise TypeError(f"{name} must be a real number, got a bool")
        value = array[()]
    try:
        v = float(value)
    except OverflowError:  # an int beyond the float range
        v = math.inf
    if not (math.isfinite(v) and (v > 0 or (zero_ok and v == 0))):
        bound = ">= 0" if zero_ok else "positive"
        raise ValueError(f"{name} must be {bound} and finite, got {v}")
    return v


class PointToPoint:
    """A synchronised rest-to-rest joint trajectory; build it with :func:`point_to_point`.

    Attributes: ``q0``, ``qf`` (n,), ``vmax``, ``amax`` (n,), ``profile``, ``duration`` t_f,
    ``axis_durations`` (n,) (each axis's own minimum time; t_f is their maximum), and for the
    trapezoid the signed ``acceleration``, ``cruise_velocity`` and ``ramp_time`` per axis.
    Pickles and copies (it is rebuilt from q0, qf, vmax, amax and the profile).
    """

    def __init__(self, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, profile: str):
        _choice(profile, "profile", PROFILES)
        _no_bool(vmax, "vmax")
        _no_bool(amax, "amax")
        self._core = _core.PointToPoint(q0, qf, vmax, amax, PROFILES.index(profile))
        self.profile = profile
        self.q0 = np.array(q0, dtype=np.float64)
        self.qf = np.array(qf, dtype=np.float64)
        n = self.q0.shape[0]
        self.vmax = np.broadcast_to(np.asarray(vmax, dtype=np.float64), (n,)).copy()
        self.amax = np.broadcast_to(np.asarray(amax, dtype=np.float64), (n,)).copy()
        self.duration: float = self._core.duration
        self.axis_durations: np.ndarray = self._core.axis_durations
        self.acceleration: np.ndarray = self._core.acceleration
        self.cruise_velocity: np.ndarray = self._core.cruise_velocity
        self.ramp_time: np.ndarray = self._core.ramp_time
        self._check_range()

    def _check_range(self) -> None:
        """The plan must be representable: a span qf - q0, a duration and peak rates that overflow (or a
        duration that underflows to 0 for a real move) would sample as NaN or jump."""
        with np.errstate(over="ignore", invalid="ignore"):
            span = self.qf - self.q0
        if not np.isfinite(span).all():
            raise ValueError("qf - q0 overflows: the span of the motion is not a finite float")
        moving = bool((span != 0).any())
        if not math.isfinite(self.duration) or (moving and not self.duration > 0):
            raise ValueError(
                f"the motion's duration is not representable ({self.duration}): span and limits too far apart"
            )
        if not moving:
            return
        # the rates peak at _PEAK_TAU and at the trapezoid's ramp ends: overflow shows there
        T = self.duration
        t = np.concatenate([T * _PEAK_TAU, self.ramp_time, T - self.ramp_time])
        q, qd, qdd = self._core.sample(t)
        plan = (self.acceleration, self.cruise_velocity, self.ramp_time, q.ravel(), qd.ravel(), qdd.ravel())
        # a trapezoid axis that moves but neither accelerates nor cruises lost its speed to an overflow
        stalled = self.profile == "trapezoid" and bool(
            ((span != 0) & ((self.acceleration == 0) | (self.cruise_velocity == 0))).any()
        )
        if stalled or not np.isfinite(np.concatenate(plan)).all():
            raise ValueError("the motion's velocity or acceleration overflows: span and limits too far apart")

    def sample(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (..., n), at times t (...). At rest outside [0, duration]; NaN t -> NaN rows."""
        return self._core.sample(t)

    def __reduce__(self):
        return (PointToPoint, (self.q0, self.qf, self.vmax, self.amax, self.profile))

    def __repr__(self) -> str:
        axes = self.q0.shape[0]
        return f"PointToPoint(profile={self.profile!r}, axes={axes}, duration={self.duration:.6g})"


def point_to_point(
    q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, profile: str = "quintic"
) -> PointToPoint:
    """A synchronised rest-to-rest motion from q0 to qf (n,): see the module docstring for the profiles.

    Raises ValueError for limits that are not positive and finite, NaN/inf positions, mismatched
    shapes, or a motion whose span, duration or peak rates overflow (e.g. q0 = -1e308, qf = 1e308);
    TypeError for non-numeric input and bool limits. qf == q0 gives a zero-length trajectory
    (duration 0).
    """
    return PointToPoint(q0, qf, vmax, amax, profile)


class BranchPath(NamedTuple):
    """One IK branch held along a sampled path, from :func:`hold_branch`."""

    q: np.ndarray
    """(K, n) the held slot's joint values; NaN where the branch does not exist or is invalid."""
    ok: np.ndarray
    """(K,) bool: the branch is valid at this sample and reached continuously from the previous one."""
    jumps: np.ndarray
    """(J,) indices k where the branch is discontinuous between samples k - 1 and k (a joint moves
    more than ``max_step``), appears or disappears: never taken silently."""
    max_step: np.ndarray
    """(K,) the largest joint move from the previous sample (0 at k = 0; revolute moves wrapped)."""


@quiet_float_errors
def hold_branch(q_slots: ArrayLike, valid: ArrayLike, branch: int, max_step: float = 0.2) -> BranchPath:
    """Hold IK slot ``branch`` along a path and report every jump.

    ``q_slots`` (K, S, n) and ``valid`` (K, S) are the ``q`` and ``valid`` (or ``exists``) of an
    ``ik_all``-style result over K consecutive path samples: :meth:`Leg.ik_all`, :meth:`SpotArm.ik_all`
    (slots with a fixed branch meaning). :meth:`Chain.ik` and :meth:`Chain.ik_position` sort their
    slots by joint value, so a slot there is not a branch: hold one only where the sort order is
    stable. A jump is a sample where the branch vanishes or reappears, or where a joint moves by more
    than ``max_step`` (rad or length units; revolute moves measured on the circle) from the previous
    sample: typically a singularity crossing (the wrist flipping, the elbow stretching), where the
    solver's slots swap meaning. Sample the path finely enough that real motion stays below
    ``max_step``. Vectorised over the path.

    Non-numeric or masked arrays and a non-integer ``branch`` (1.5, True) raise TypeError; wrong
    shapes, a branch out of range and a NaN, infinite or non-positive ``max_step`` ValueError.
    """
    q = as_real(q_slots, "q_slots", np.float64)
    if q.ndim != 3:
        raise ValueError(f"q_slots must have shape (K, S, n), got {q.shape}")
    flags = as_real(valid, "valid")
    if flags.shape != q.shape[:2]:
        raise ValueError(f"valid must have shape (K, S) = {q.shape[:2]} (that of q_slots), got {flags.shape}")
    if not np.isin(flags, (0, 1)).all():
        raise ValueError("valid must hold booleans (or 0 and 1)")
    ok_slot = flags.astype(bool)
    branch = as_index(branch, "branch")
    if not 0 <= branch < q.shape[1]:
        raise ValueError(f"branch must be a slot index in [0, {q.shape[1]}), got {branch}")
    max_step = _limit(max_step, "max_step")
    held = np.where(ok_slot[:, branch, None], q[:, branch], np.nan)
    step = np.zeros(len(held))
    if len(held) > 1:
        delta = np.diff(held, axis=0)
        wrapped = np.abs(np.mod(delta + np.pi, 2 * np.pi) - np.pi)  # revolute joints: on the circle
        step[1:] = np.max(np.minimum(wrapped, np.abs(delta)), axis=-1, initial=0.0)
    present = ok_slot[:, branch]
    jump = np.zeros(len(held), dtype=bool)
    jump[1:] = (present[1:] != present[:-1]) | (present[1:] & present[:-1] & ~(step[1:] <= max_step))
    ok = present & ~jump
    if len(ok) > 1:  # after a jump the branch is no longer the one chosen: not ok until the end
        ok &= np.cumsum(jump) == 0
    return BranchPath(held, ok, np.nonzero(jump)[0], step)
