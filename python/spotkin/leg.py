"""Roll–pitch–pitch legs (Spot's hx, hy, kn): FK, Jacobian, singularities and closed-form IK.

Model (metres, radians), in the leg frame: origin at the hx joint, axes parallel
to the body frame (x forward, y left, z up)::

    p = Rx(hx) ( [0, h1, 0] + Ry(hy) ( [k, 0, -upper] + Ry(kn) [0, 0, -lower] ) )

with h1 = +hip_offset for a left leg and -hip_offset for a right leg, and k the
knee's forward offset. The IK is closed form (Paul's method, re-derived in
docs/derivations.md): hip roll from a type-2 equation (two roots), knee from a second
type-2 equation (two roots), hip pitch from an angle difference; the knee
offset is handled exactly. Branch slots are fixed:

====  ==========  ==============  =============================================
slot  hip roll    knee            meaning
====  ==========  ==============  =============================================
0     normal      back            the foot under the hip, knee pointing back:
                                  Spot's walking branch (the preferred one)
1     normal      forward         knee bent the other way
2     flipped     back            the leg swung over the hip-roll axis
3     flipped     forward
====  ==========  ==============  =============================================

Either all four slots exist for a target or none does. With Spot's limits,
exactly one slot (0) is valid whenever the foot is more than about 8 cm below
the hx joint; near hip height (|z| < ~6.5 cm, a band of y beside the hip),
slots 0 and 2 can both be valid, and :meth:`Leg.ik` then takes the one nearest
to ``seed`` (or slot 0 without one).
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._boundary import as_flag, as_real, as_scalar, broadcast_lead, fallback_is_nearest

__all__ = ["Leg", "LegSolutions"]

SLOT_NAMES = (
    "normal hip, knee back",
    "normal hip, knee forward",
    "flipped hip, knee back",
    "flipped hip, knee forward",
)


class LegSolutions(NamedTuple):
    """Every IK branch for a batch of foot targets, from :meth:`Leg.ik_all`."""

    q: np.ndarray
    """(..., 4, 3) joint angles per slot, NaN where the branch does not exist.
    Angles are in (-pi, pi], or shifted by 2 pi where that brings them into the limits."""
    valid: np.ndarray
    """(..., 4) bool: the branch exists and is within the joint limits."""
    exists: np.ndarray
    """(..., 4) bool: the branch exists, limits aside."""
    status: np.ndarray
    """(...,) int8 :class:`Status`: OK if any slot is valid, else JOINT_LIMIT,
    UNREACHABLE or INVALID_INPUT."""


def _broadcast_pair(a: ArrayLike, b: ArrayLike, name_a: str, name_b: str) -> tuple[np.ndarray, np.ndarray]:
    """Two batches (..., n) broadcast over their leading dimensions (the core checks n)."""
    a, b = as_real(a, name_a), as_real(b, name_b)
    if a.shape[:-1] == b.shape[:-1]:
        return a, b  # nothing to broadcast (the common case: a few microseconds saved per call)
    lead = broadcast_lead(**{name_a: (a.shape[:-1], a.shape), name_b: (b.shape[:-1], b.shape)})
    return (np.broadcast_to(a, (*lead, *a.shape[-1:])), np.broadcast_to(b, (*lead, *b.shape[-1:])))


class Leg:
    """A roll–pitch–pitch leg. See the module docstring for the model and branch slots.

    Parameters
    ----------
    hip_offset, upper, lower, knee_offset:
        Lengths in metres: the lateral hx → hy offset (its magnitude; ``side``
        sets its sign), the hy → knee length along -z, the knee → foot length,
        and the knee's forward offset along +x.
    side:
        ``"left"`` (h1 = +hip_offset) or ``"right"`` (h1 = -hip_offset).
    limits:
        Optional (3, 2) joint limits [(lower, upper)] for hx, hy, kn; None for none.

    Lengths must be real numbers and ``limits`` a real array (``TypeError`` otherwise);
    non-finite lengths, ``upper`` or ``lower`` not positive, a negative ``hip_offset``,
    and limits with NaN or lower > upper raise ``ValueError``.
    """

    __slots__ = ("_core", "_limits", "_params")

    def __init__(
        self,
        hip_offset: float,
        upper: float,
        lower: float,
        knee_offset: float = 0.0,
        side: Literal["left", "right"] = "left",
        limits: ArrayLike | None = None,
        name: str | None = None,
    ) -> None:
        if side not in ("left", "right"):
            raise ValueError(f"side must be 'left' or 'right', got {side!r}")
        hip_offset, knee_offset = as_scalar(hip_offset, "hip_offset"), as_scalar(knee_offset, "knee_offset")
        upper, lower = as_scalar(upper, "upper"), as_scalar(lower, "lower")
        if not hip_offset >= 0:
            raise ValueError(f"hip_offset is a length (its sign comes from side), got {hip_offset}")
        unlimited = np.tile([-np.inf, np.inf], (3, 1))
        table = unlimited if limits is None else as_real(limits, "limits", np.float64).copy()
        if table.shape != (3, 2):
            raise ValueError(f"limits must have shape (3, 2) as (lower, upper) rows, got {table.shape}")
        h1 = float(hip_offset) if side == "left" else -float(hip_offset)
        self._core = _core.Leg(h1, float(upper), float(lower), float(knee_offset), table[:, 0], table[:, 1])
        self._limits = table
        self._params = (float(hip_offset), float(upper), float(lower), float(knee_offset), side, name)

    # -- description -------------------------------------------------------------------------------------
    @property
    def name(self) -> str | None:
        return self._params[5]

    @property
    def side(self) -> str:
        return self._params[4]

    @property
    def hip_offset(self) -> float:
        """Signed lateral offset h1 (+ left, - right)."""
        return self._params[0] if self.side == "left" else -self._params[0]

    @property
    def upper(self) -> float:
        return self._params[1]

    @property
    def lower(self) -> float:
        return self._params[2]

    @property
    def knee_offset(self) -> float:
        return self._params[3]

    @property
    def limits(self) -> np.ndarray:
        """(3, 2) joint limits (lower, upper) for hx, hy, kn; ±inf where unlimited."""
        return self._limits.copy()

    @property
    def reach(self) -> tuple[float, float]:
        """(min, max) distance from the hy joint to the foot: |R - lower|, R + lower, R = hypot(upper, k)."""
        return self._core.min_reach, self._core.max_reach

    # -- kinematics --------------------------------------------------------------------------------------
    def fk(self, q: ArrayLike) -> np.ndarray:
        """Foot-sphere centre in the leg frame: q (..., 3) as [hx, hy, kn] -> (..., 3)."""
        return self._core.fk(q)

    def jacobian(self, q: ArrayLike) -> np.ndarray:
        """d foot / d q in the leg frame: q (..., 3) -> (..., 3, 3)."""
        return self._core.jacobian(q)

    def singularity(self, q: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(|det J|, smallest singular value of J), each (...,).

        Both vanish on the two singular sets: sin(kn + beta) = 0 (leg stretched
        or folded; beta = atan2(knee_offset, upper)), and the foot on the
        hip-roll boundary y^2 + z^2 = h1^2, where the two hip-roll branches merge.
        """
        return self._core.singularity(q)

    def ik(self, p: ArrayLike, seed: ArrayLike | None = None, fallback: str = "nearest"):
        """Joint angles placing the foot at p: p (..., 3) -> (q (..., 3), status (...,)).

        Status per target (a :class:`Status` for a single target, an int8 array otherwise):

        - ``OK``: q is the valid branch (exists, within limits, wrapped by ±2π into
          them where needed). If several are valid: the one nearest to ``seed``
          (largest single-joint move, on the circle; ties to the lower slot), or
          slot 0 without a seed.
        - ``UNREACHABLE``: the target is beyond reach, inside the inner dead zone
          or inside the hip-roll cylinder. q is always inside the limits: the leg
          stretched or folded toward the target as far as the knee's limits allow,
          i.e. a branch for ``nearest_reachable(p, within_limits=True)`` (the
          first slot inside all the limits; if none, slot 0 with each joint
          brought to its nearest bound, the foot then further away). With
          ``fallback="nan"``, q is NaN instead (as :meth:`SpotArm.ik` and
          :meth:`Chain.ik_nearest` answer).
        - ``JOINT_LIMIT``: branches exist, but none within the limits; q is NaN.
        - ``INVALID_INPUT``: NaN or Inf in p or seed; q is NaN.

        ``seed`` (..., 3) must have the shape of p when given.
        """
        nearest = fallback_is_nearest(fallback)
        if seed is None:
            return self._core.ik(p, None, nearest)
        return self._core.ik(*_broadcast_pair(p, seed, "p", "seed"), nearest)

    def ik_all(self, p: ArrayLike) -> LegSolutions:
        """Every branch for p (..., 3): see :class:`LegSolutions` and the slot table."""
        return LegSolutions(*self._core.ik_all(p))

    def nearest_reachable(self, p: ArrayLike, within_limits: bool = False) -> np.ndarray:
        """The reachable foot position nearest to p (3,), limits aside.

        Radial projection onto the shell of reachable distances; if that lands
        inside the hip-roll cylinder y^2 + z^2 < h1^2, the nearest point on it.
        ``within_limits``: the shell of the distances the knee reaches inside its
        limits instead (the hip limits aside): the foot position of ``ik``'s
        UNREACHABLE answer whenever that answer needs no hip joint brought to a bound.

        Returns float64 (3,), all NaN when p has NaN or Inf. ``p`` must be a real array
        of shape (3,) (``TypeError`` for non-numeric or masked input, ``ValueError`` for
        another shape) and ``within_limits`` a bool (``TypeError`` otherwise, so
        ``"False"`` is not true).
        """
        point = as_real(p, "p", np.float64)
        if point.shape != (3,):
            raise ValueError(f"p must have shape (3,), got {point.shape}")
        within_limits = as_flag(within_limits, "within_limits")
        if not np.isfinite(point).all():
            return np.full(3, np.nan)
        return np.array(self._core.nearest_reachable(point, within_limits))

    def __reduce__(self):
        hip_offset, upper, lower, knee_offset, side, name = self._params
        return (Leg, (hip_offset, upper, lower, knee_offset, side, self._limits, name))

    def __repr__(self) -> str:
        label = f"{self.name!r}, " if self.name else ""
        return (
            f"Leg({label}h1={self.hip_offset:+.6g}, upper={self.upper:.6g}, lower={self.lower:.6g}, "
            f"knee_offset={self.knee_offset:.6g})"
        )
