"""Roll–pitch–pitch legs (Spot's hx, hy, kn; Go2's hip, thigh, calf): FK, Jacobian,
singularities and closed-form IK with every branch.

Model (metres, radians), in the leg frame: origin at the hip-roll joint, axes parallel
to the body frame at zero angles (x forward, y left, z up). With o2, o3 the hip-pitch and
knee joint origins and f the foot, all at zero angles, a = o2, b = o3 − o2, c = f − o3,
and the joint axes s1·x, s2·y, s3·y (signs ±1)::

    p = Rx(s1 q1) ( a + Ry(s2 q2) ( b + Ry(s3 q3) c ) )

(the product of exponentials: rotated joint frames drop out). Spot's legs are
a = (0, ±0.110945, 0), b = (0.025, 0, −0.3205), c = (0, 0, −0.3365), s = (1, 1, 1).
The IK is closed form (Paul's method, derived in docs/derivations.md): hip roll from a
type-2 equation (two roots), knee from a second type-2 equation (two roots), hip pitch
from an angle difference; every offset is handled exactly. Branch slots are fixed and
geometric (the same meaning for every robot):

====  ==========  ==============  =============================================
slot  hip roll    knee            meaning
====  ==========  ==============  =============================================
0     normal      back            the foot on the lower side of the hip-roll axis,
                                  the knee pointing back (Spot's and Go2's
                                  walking branch)
1     normal      forward         knee bent the other way (ANYmal's and HyQ's
                                  hind legs walk on this one)
2     flipped     back            the leg swung over the hip-roll axis
3     flipped     forward
====  ==========  ==============  =============================================

"Knee back" means the lower link turned forward of the upper one about +y (body
axes): sin(theta3 + phi) <= 0 with phi the angle between the links at zero. The two
knee slots of a hip branch exist together; the two hip branches differ only when the
hip-pitch axis is offset vertically from the hip-roll axis (a_z != 0).

:meth:`Leg.ik` without a seed takes the leg's **preferred slot** when it is valid (then
the others in slot order): by default the knee branch that the middle of the knee's
limits lies on, with the hip normal; or given, or found from a nominal stance.
With Spot's limits, exactly one slot (0) is valid whenever the foot is more than about
8 cm below the hx joint; near hip height slots 0 and 2 can both be valid.
"""

from __future__ import annotations

import warnings
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import (
    as_flag,
    as_index,
    as_real,
    as_scalar,
    fallback_is_nearest,
    limit_table,
    quiet_float_errors,
)
from .._support.forward import core_method
from .._support.status import Status

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


_core._register_result_type("LegSolutions", LegSolutions)  # the core returns it itself


def _vector3(value: ArrayLike, name: str) -> tuple[float, float, float]:
    array = as_real(value, name, np.float64)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise ValueError(f"{name} must be 3 finite numbers (shape (3,)), got {np.asarray(array).tolist()}")
    return tuple(float(v) for v in array)


def _limit_table(limits: ArrayLike | None) -> np.ndarray:
    return limit_table(limits, 3)


class Leg:
    """A roll–pitch–pitch leg. See the module docstring for the model and branch slots.

    ``Leg(hip_offset, upper, lower, knee_offset, side)`` builds a Spot-style leg:
    a = (0, ±hip_offset, 0) (+ for ``side="left"``), b = (knee_offset, 0, −upper),
    c = (0, 0, −lower), all axes positive. :meth:`from_geometry` builds any leg of the
    family (what :meth:`spotkin.Robot.from_urdf` recognises).

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

    Lengths must be real numbers, ``limits`` a real array and ``name`` a str or None
    (``TypeError`` otherwise); non-finite lengths, ``upper`` or ``lower`` not positive, a
    negative ``hip_offset``, and limits with NaN or lower > upper raise ``ValueError``.
    """

    __slots__ = ("_core", "_geometry", "_joint_names", "_limits", "_name")

    slot_names = SLOT_NAMES
    """What each of :meth:`ik_all`'s 4 slots means (hip normal or flipped, knee back or forward)."""

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
        for value, label in ((upper, "upper"), (lower, "lower")):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{label} must be a positive finite length, got {value}")
        if not (np.isfinite(hip_offset) and np.isfinite(knee_offset)):
            raise ValueError("leg lengths must be finite")
        h1 = float(hip_offset) if side == "left" else -float(hip_offset)
        self._init(
            (0.0, h1, 0.0),
            (float(knee_offset), 0.0, -float(upper)),
            (0.0, 0.0, -float(lower)),
            (1.0, 1.0, 1.0),
            _limit_table(limits),
            name,
            None,
        )

    @classmethod
    def from_geometry(
        cls,
        a: ArrayLike,
        b: ArrayLike,
        c: ArrayLike,
        signs: ArrayLike = (1.0, 1.0, 1.0),
        limits: ArrayLike | None = None,
        name: str | None = None,
        preferred_slot: int | None = None,
        nominal: ArrayLike | None = None,
    ) -> Leg:
        """Any roll–pitch–pitch leg: a, b, c (3,) in metres and the axis signs, as in the module docstring.

        ``preferred_slot`` (0-3) is the slot :meth:`ik` takes without a seed when valid; by
        default it comes from ``nominal`` (3,) joint angles of a typical stance when given (the
        slot that holds them), else from the knee's limits. ``ValueError`` for non-finite
        vectors, signs other than ±1, b or c along the pitch axis (no closed form), or
        limits with NaN or lower > upper.
        """
        leg = cls.__new__(cls)
        sign_values = _vector3(signs, "signs")
        if any(v not in (1.0, -1.0) for v in sign_values):
            raise ValueError(f"signs must be +1 or -1 each, got {sign_values}")
        if preferred_slot is not None:
            preferred_slot = as_index(preferred_slot, "preferred_slot")
            if not 0 <= preferred_slot < 4:
                raise ValueError(f"preferred_slot must be 0, 1, 2 or 3, got {preferred_slot}")
        leg._init(
            _vector3(a, "a"),
            _vector3(b, "b"),
            _vector3(c, "c"),
            sign_values,
            _limit_table(limits),
            name,
            preferred_slot,
        )
        if nominal is not None and preferred_slot is None:
            leg._init(*leg._geometry, leg._limits, name, leg._slot_of(_vector3(nominal, "nominal")))
        return leg

    def _init(self, a, b, c, signs, limits, name, preferred_slot) -> None:
        if name is not None and not isinstance(name, str):
            raise TypeError(f"name must be a str or None, got {type(name).__name__}")
        try:
            self._core = _core.Leg(
                a, b, c, signs, limits[:, 0], limits[:, 1], -1 if preferred_slot is None else preferred_slot
            )
        except ValueError as error:
            raise ValueError(f"leg {name!r}: {error}" if name else str(error)) from None
        self._geometry = (a, b, c, signs)
        self._limits = limits
        self._name = name
        self._joint_names = getattr(self, "_joint_names", None)  # set by the robot that names them

    def _slot_of(self, q: tuple[float, float, float]) -> int:
        """The slot whose solution for fk(q) is q (up to 2 pi), or ValueError."""
        solutions = self._core.ik_all(self._core.fk(np.array(q)))
        distance = np.abs(np.angle(np.exp(1j * (solutions[0] - np.array(q))))).max(axis=1)
        distance = np.where(solutions[2], distance, np.inf)
        slot = int(np.argmin(distance))
        if not distance[slot] < 1e-6:
            raise ValueError(f"nominal {q} is not a solution of this leg")
        return slot

    # -- description -------------------------------------------------------------------------------------
    @property
    def name(self) -> str | None:
        return self._name

    @property
    def dof(self) -> int:
        """3: hip roll, hip pitch, knee (the solver interface shared with arms and chains)."""
        return 3

    @property
    def joint_names(self) -> tuple[str, str, str] | None:
        """The three joints' names in the robot the leg belongs to (its URDF's, or Spot's SDK names),
        None for a leg built alone."""
        return self._joint_names

    @property
    def a(self) -> np.ndarray:
        """(3,) hip roll → hip pitch joint, leg frame at zero angles."""
        return np.array(self._geometry[0])

    @property
    def b(self) -> np.ndarray:
        """(3,) hip pitch → knee joint."""
        return np.array(self._geometry[1])

    @property
    def c(self) -> np.ndarray:
        """(3,) knee joint → foot point."""
        return np.array(self._geometry[2])

    @property
    def signs(self) -> np.ndarray:
        """(3,) axis signs: the joint axes at zero angles are s1 x, s2 y, s3 y."""
        return np.array(self._geometry[3])

    @property
    def preferred_slot(self) -> int:
        """The slot :meth:`ik` takes without a seed when it is valid."""
        return self._core.preferred_slot

    @property
    def side(self) -> str:
        """``"left"`` when the foot's lateral offset h = a_y + b_y + c_y is >= 0, else ``"right"``."""
        return "left" if self.hip_offset >= 0 else "right"

    @property
    def hip_offset(self) -> float:
        """Signed lateral offset h = a_y + b_y + c_y (+ left, - right): the foot's distance
        from the hip-pitch plane through the roll axis, along y."""
        return float(self._geometry[0][1] + self._geometry[1][1] + self._geometry[2][1])

    @property
    def upper_length(self) -> float:
        """-b_z: the hip-pitch → knee length along -z (Spot's 0.3205): the upper leg."""
        return -self._geometry[1][2]

    @property
    def lower_length(self) -> float:
        """-c_z: the knee → foot length along -z (Spot's 0.3365): the lower leg."""
        return -self._geometry[2][2]

    @property
    def upper(self) -> float:
        """Deprecated: :attr:`upper_length` (a :class:`Chain`'s ``upper`` is its upper joint limits)."""
        warnings.warn(
            "Leg.upper is the upper leg's length: use Leg.upper_length (Chain.upper is a joint limit; "
            "a leg's joint limits are Leg.limits)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.upper_length

    @property
    def lower(self) -> float:
        """Deprecated: :attr:`lower_length` (a :class:`Chain`'s ``lower`` is its lower joint limits)."""
        warnings.warn(
            "Leg.lower is the lower leg's length: use Leg.lower_length (Chain.lower is a joint limit; "
            "a leg's joint limits are Leg.limits)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.lower_length

    @property
    def knee_offset(self) -> float:
        """b_x: the knee's forward offset from the hip-pitch joint (Spot's 0.025)."""
        return self._geometry[1][0]

    @property
    def limits(self) -> np.ndarray:
        """(3, 2) joint limits (lower, upper) for hx, hy, kn; ±inf where unlimited."""
        return self._limits.copy()

    @property
    def reach(self) -> tuple[float, float]:
        """(min, max) pitch-plane distance from the hip-pitch joint to the foot: ||B| - |C||, |B| + |C|,
        with |B|, |C| the pitch-plane lengths of b and c."""
        return self._core.min_reach, self._core.max_reach

    @quiet_float_errors
    def knee(self, q: ArrayLike) -> np.ndarray:
        """Knee joint origin in the leg frame: q (..., 3) -> (..., 3), Rx(s1 q1) (a + Ry(s2 q2) b).

        float32 in gives float32 out (computed in float64); NaN or Inf joints give NaN."""
        given = as_real(q, "q")
        if given.ndim < 1 or given.shape[-1] != 3:
            raise ValueError(f"q must have shape (..., 3), got {given.shape}")
        knee = self._knee(given.astype(np.float64, copy=False))
        return knee.astype(np.float32) if given.dtype == np.float32 else knee

    def _knee(self, q: np.ndarray) -> np.ndarray:
        (a, b, _, signs) = self._geometry
        t1, t2 = signs[0] * q[..., 0], signs[1] * q[..., 1]
        vx = a[0] + np.cos(t2) * b[0] + np.sin(t2) * b[2]
        vy = np.full_like(t1, a[1] + b[1])
        vz = a[2] - np.sin(t2) * b[0] + np.cos(t2) * b[2]
        return np.stack([vx, np.cos(t1) * vy - np.sin(t1) * vz, np.sin(t1) * vy + np.cos(t1) * vz], -1)

    # -- kinematics --------------------------------------------------------------------------------------
    @core_method("_core", "fk")
    def fk(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """Foot-sphere centre in the leg frame: q (..., 3) as [hx, hy, kn] -> (..., 3).

        ``out``: an array of the result's shape and dtype (C-contiguous) to write into
        and return, so that a control loop allocates nothing.
        """
        return self._core.fk(q, out)

    @core_method("_core", "jacobian")
    def jacobian(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """d foot / d q in the leg frame: q (..., 3) -> (..., 3, 3); ``out`` as in :meth:`fk`."""
        return self._core.jacobian(q, out)

    def singularity(
        self, q: ArrayLike, *, out: tuple[np.ndarray | None, np.ndarray | None] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(|det J|, smallest singular value of J), each (...,).

        Both vanish on the two singular sets: sin(kn + beta) = 0 (leg stretched
        or folded; beta = atan2(knee_offset, upper)), and the foot on the
        hip-roll boundary y^2 + z^2 = h1^2, where the two hip-roll branches merge.
        ``out``: two arrays to write them into, as in :meth:`fk`.
        """
        return self._core.singularity(q, out)

    @core_method("_core", "ik", convert={"fallback": fallback_is_nearest})
    def ik(
        self,
        p: ArrayLike,
        seed: ArrayLike | None = None,
        fallback: str = "nearest",
        *,
        out: tuple[np.ndarray | None, np.ndarray | None] | None = None,
    ) -> tuple[np.ndarray, np.ndarray | Status]:
        """Joint angles placing the foot at p: p (..., 3) -> (q (..., 3), status (...,)).

        Status per target (a :class:`Status` for a single target, an int8 array otherwise):

        - ``OK``: q is the valid branch (exists, within limits, wrapped by ±2π into
          them where needed). If several are valid: the one nearest to ``seed``
          (largest single-joint move, on the circle; ties to the preferred, then
          the lower slot), or the preferred slot (then the lower ones) without a seed.
        - ``UNREACHABLE``: the target is beyond reach, inside the inner dead zone
          or inside the hip-roll cylinder. q is the configuration within the
          joint limits whose foot is nearest to the target, computed exactly
          (:meth:`nearest_reachable` with ``within_limits=True``). With
          ``fallback="nan"``, q is NaN instead (as :meth:`SpotArm.ik` and
          :meth:`Chain.ik` answer).
        - ``JOINT_LIMIT``: branches exist, but none within the limits; q is NaN.
        - ``INVALID_INPUT``: NaN or Inf in p or seed; q is NaN.

        ``seed`` (..., 3) broadcasts with p over the leading dimensions.
        ``out``: ``(q, status)`` arrays (float of p's dtype, int8) of the result's shapes to
        write into, either may be None; they are returned.
        """
        return self._core.ik(p, seed, fallback_is_nearest(fallback), out)

    @core_method("_core", "ik_all")
    def ik_all(self, p: ArrayLike, *, out: tuple | None = None) -> LegSolutions:
        """Every branch for p (..., 3): see :class:`LegSolutions` and the slot table.
        ``out``: ``(q, valid, exists, status)`` arrays to write into (any may be None)."""
        return self._core.ik_all(p, out)  # a LegSolutions (the core builds it)

    def nearest_reachable(self, p: ArrayLike, within_limits: bool = False) -> np.ndarray:
        """The foot position nearest to p (3,) that the leg reaches: (3,) float64.

        ``within_limits=False``: over every configuration (limits aside); ``True``: over the
        configurations within the joint limits (the foot of :meth:`ik`'s UNREACHABLE answer).
        Exact: the box-constrained minimum of |fk(q) - p| is found among the stationary
        points of every boundary subproblem (joints at bounds, singular sets), each solved in
        closed form or as the real roots of a polynomial (see docs/derivations.md). A target
        farther than 1e8 m is solved at 1e8 m along its direction (the answer then tends to the
        leg's farthest point that way; it moves by less than ~1e-8 m).

        Returns all NaN when p has NaN or Inf. ``p`` must be a real array of shape (3,)
        (``TypeError`` for non-numeric or masked input, ``ValueError`` for another shape) and
        ``within_limits`` a bool (``TypeError`` otherwise, so ``"False"`` is not true).
        """
        point = as_real(p, "p", np.float64)
        if point.shape != (3,):
            raise ValueError(f"p must have shape (3,), got {point.shape}")
        within_limits = as_flag(within_limits, "within_limits")
        if not np.isfinite(point).all():
            return np.full(3, np.nan)
        return np.array(self._core.nearest_reachable(point, within_limits)[0])

    def __reduce__(self):
        return (
            _rebuild_leg,
            (*self._geometry, self._limits, self._name, self.preferred_slot, self._joint_names),
        )

    def __repr__(self) -> str:
        label = f"{self.name!r}, " if self.name else ""
        a, b, c, signs = self._geometry
        return f"Leg({label}a={a}, b={b}, c={c}, signs={signs})"


def _rebuild_leg(a, b, c, signs, limits, name, preferred_slot, joint_names=None) -> Leg:
    leg = Leg.from_geometry(a, b, c, signs, limits, name, preferred_slot)
    leg._joint_names = joint_names
    return leg
