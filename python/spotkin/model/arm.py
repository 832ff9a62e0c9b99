"""6-DOF arms with a spherical wrist (the Spot Arm): FK, Jacobian, singularities,
closed-form IK with all 8 solutions.

Model (body frame, metres, radians), joints q = [sh0, sh1, el0, el1, wr0, wr1]::

    T = Trans(mount) Rz(sh0) Ry(sh1) Trans(upper_arm, 0, 0) Ry(el0)
        Trans(forearm, 0, forearm_offset) Rx(el1) Ry(wr0) Rx(wr1) Trans(hand, 0, 0) tool

The el1, wr0 and wr1 axes meet at the wrist centre, so the IK splits into a
position part (sh0 from the wrist centre's azimuth, el0 from a Paul type-2
equation with the 0.075 m forearm offset exact, sh1 from an angle difference)
and an orientation part, R_36 = R_03^T R_wrist decomposed as X-Y-X Euler angles.

Solution slots (fixed): ``slot = 4 * shoulder + 2 * elbow + wrist``

- shoulder 0: sh0 = atan2(c_y, c_x), facing the wrist centre ("front"); 1: sh0 + pi ("back",
  the arm reaching over its own shoulder);
- elbow 0: el0 = phi + acos(K / L) ("elbow up" for the front shoulder; Spot's usual
  elbow, el0 in [0, pi]), 1: phi - acos(K / L) ("elbow down");
- wrist 0: wr0 >= 0; 1: the flip (el1 + pi, -wr0, wr1 + pi).

Either all eight solutions exist or none does (reachability depends on the
wrist centre's distance from the shoulder only).

Singular cases get defined answers, flagged by :meth:`SpotArm.singularity`:

- wrist (|sin wr0| < 1e-9, el1 and wr1 aligned): el1 is kept at the seed's el1 (0
  without a seed), wr0 is exactly 0 or pi, and wr1 is solved so the pose is exact;
- shoulder (wrist centre within 1e-12 m of the sh0 axis): sh0 is the seed's (0 without one);
- elbow stretched or folded: the two elbow slots coincide.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import (
    as_real,
    as_scalar,
    broadcast_lead,
    check_trailing,
    limit_table,
    quiet_float_errors,
    rigid_transforms,
)
from .._support.forward import core_method
from .._support.status import Status
from .presets import SPOT

__all__ = ["ArmSingularity", "ArmSolutions", "SpotArm", "pose_from"]


class ArmSolutions(NamedTuple):
    """Every IK solution for a batch of hand poses, from :meth:`SpotArm.ik_all`."""

    q: np.ndarray
    """(..., 8, 6) joint angles per slot, NaN where none exist. In (-pi, pi], or shifted
    by 2 pi where that brings them into the limits."""
    valid: np.ndarray
    """(..., 8) bool: exists and within the joint limits."""
    exists: np.ndarray
    """(..., 8) bool: exists, limits aside."""
    status: np.ndarray
    """(...,) int8 :class:`Status`: OK if any slot is valid, else JOINT_LIMIT,
    UNREACHABLE or INVALID_INPUT."""


_core._register_result_type("ArmSolutions", ArmSolutions)  # the core returns it itself


class ArmSingularity(NamedTuple):
    """Distances to the arm's singular sets, each (...,)."""

    wrist: np.ndarray
    """|sin wr0|: 0 when el1 and wr1 align."""
    elbow: np.ndarray
    """|sin(el0 - phi)|, phi = atan2(forearm_offset, forearm): 0 with the elbow stretched or folded."""
    shoulder: np.ndarray
    """Distance (m) of the wrist centre from the sh0 axis."""
    manipulability: np.ndarray
    """|det J| of the 6x6 geometric Jacobian (= sqrt(det(J J^T)))."""


@quiet_float_errors
def pose_from(position: ArrayLike, quat_xyzw: ArrayLike) -> np.ndarray:
    """(..., 4, 4) pose from positions (..., 3) and scalar-last quaternions (..., 4) (scipy order).

    Quaternions must be unit to 1e-6; others give an all-NaN matrix (they are never
    silently normalised), as does a non-finite position. Leading dimensions broadcast;
    the result is float64. Non-numeric input raises ``TypeError``, a wrong or
    non-broadcasting shape ``ValueError``, each naming the argument.
    """
    p = as_real(position, "position", np.float64)
    quat = as_real(quat_xyzw, "quat_xyzw", np.float64)
    lead = broadcast_lead(
        position=(check_trailing(p, "position", (3,)), p.shape),
        quat_xyzw=(check_trailing(quat, "quat_xyzw", (4,)), quat.shape),
    )
    x, y, z, w = np.moveaxis(quat, -1, 0)
    n2 = x * x + y * y + z * z + w * w
    s = 2.0 / n2
    R = np.stack(
        [
            np.stack([1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)], -1),
            np.stack([s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)], -1),
            np.stack([s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)], -1),
        ],
        -2,
    )
    T = np.zeros((*lead, 4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    bad = ~(np.abs(np.sqrt(n2) - 1.0) <= 1e-6) | ~np.isfinite(p).all(-1)
    T[np.broadcast_to(bad, lead)] = np.nan
    return T


def _broadcast_seed(T: ArrayLike, seed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Pose targets (..., 4, 4) or (..., 7) and seeds (..., n) broadcast over their leading
    dimensions (the core checks the trailing ones)."""
    T, seed = as_real(T, "T"), as_real(seed, "seed")
    trailing = 2 if T.shape[-2:] == (4, 4) else 1
    if T.shape[:-trailing] == seed.shape[:-1]:
        return T, seed  # nothing to broadcast (the common case: a few microseconds saved per call)
    lead = broadcast_lead(T=(T.shape[:-trailing], T.shape), seed=(seed.shape[:-1], seed.shape))
    return (
        np.broadcast_to(T, (*lead, *T.shape[-trailing:])),
        np.broadcast_to(seed, (*lead, *seed.shape[-1:])),
    )


ARM_JOINT_NAMES = ("arm0.sh0", "arm0.sh1", "arm0.el0", "arm0.el1", "arm0.wr0", "arm0.wr1")


class SpotArm:
    """The Spot Arm, or any arm of the same structure. See the module docstring.

    Parameters default to the official Spot numbers (Boston Dynamics' ``spot_with_arm.urdf``).
    ``tool`` (4, 4) maps the hand frame to the frame the IK targets (for example the
    gripper fingertip); ``limits`` is (6, 2) [(lower, upper)], or None for none. Lengths
    must be real numbers and arrays real arrays (``TypeError`` otherwise); the core
    rejects non-finite values and inconsistent limits with ``ValueError``.
    """

    __slots__ = ("_core", "_params")

    def __init__(
        self,
        mount: ArrayLike = SPOT["arm"]["mount"],
        upper_arm: float = SPOT["arm"]["upper_arm"],
        forearm: float = SPOT["arm"]["forearm"],
        forearm_offset: float = SPOT["arm"]["forearm_offset"],
        hand: float = SPOT["arm"]["hand"],
        tool: ArrayLike | None = None,
        limits: ArrayLike | None = SPOT["arm"]["limits"],
    ) -> None:
        table = limit_table(limits, 6)
        mount = as_real(mount, "mount", np.float64).copy()
        if mount.shape != (3,):
            raise ValueError(f"mount must have shape (3,), got {mount.shape}")
        tool = None if tool is None else rigid_transforms(tool, "tool")
        upper_arm, forearm = as_scalar(upper_arm, "upper_arm"), as_scalar(forearm, "forearm")
        forearm_offset, hand = as_scalar(forearm_offset, "forearm_offset"), as_scalar(hand, "hand")
        self._core = _core.Arm(
            mount,
            float(upper_arm),
            float(forearm),
            float(forearm_offset),
            float(hand),
            tool,
            table[:, 0],
            table[:, 1],
        )
        self._params = (
            mount,
            float(upper_arm),
            float(forearm),
            float(forearm_offset),
            float(hand),
            tool,
            table,
        )

    @property
    def limits(self) -> np.ndarray:
        """(6, 2) joint limits (lower, upper); ±inf where unlimited."""
        return self._params[6].copy()

    @property
    def tool(self) -> np.ndarray:
        """(4, 4) hand -> tool transform."""
        return np.eye(4) if self._params[5] is None else self._params[5].copy()

    @property
    def dof(self) -> int:
        """6 (the solver interface shared with legs and chains)."""
        return 6

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The joints by their role, as the Spot SDK names them: shoulder (sh0, sh1), elbow (el0,
        el1), wrist (wr0, wr1)."""
        return ARM_JOINT_NAMES

    @core_method("_core", "fk")
    def fk(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """Tool pose in the body frame: q (..., 6) -> (..., 4, 4). ``out``: an array of the result's
        shape and dtype to write into and return."""
        return self._core.fk(q, out)

    @core_method("_core", "jacobian")
    def jacobian(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """Geometric Jacobian [v; w] of the tool point in the body frame: (..., 6) -> (..., 6, 6);
        ``out`` as in :meth:`fk`."""
        return self._core.jacobian(q, out)

    def singularity(self, q: ArrayLike) -> ArmSingularity:
        """Wrist, elbow and shoulder distances to the singular sets, and manipulability (float64)."""
        out = self._core.singularity(q)
        return ArmSingularity(out[..., 0], out[..., 1], out[..., 2], out[..., 3])

    @core_method("_core", "ik_all")
    def ik_all(
        self, T: ArrayLike, seed: ArrayLike | None = None, *, out: tuple | None = None
    ) -> ArmSolutions:
        """Every solution for tool poses T (..., 4, 4) or (..., 7) [x, y, z, qx, qy, qz, qw].

        ``seed`` (..., 6) only fixes the free angle in the singular cases (sh0 with the
        wrist centre on the sh0 axis, el1 with wr0 = 0). A pose whose rotation part is
        not a rotation (max |R^T R - I| > 1e-6, or det < 0), whose last row is not
        [0, 0, 0, 1], or with a non-unit quaternion, gets INVALID_INPUT: it is never
        silently orthonormalised. The seed broadcasts with T over the leading dimensions.
        ``out``: ``(q, valid, exists, status)`` arrays to write into (any may be None).
        """
        return self._core.ik_all(T, seed, out)  # an ArmSolutions (the core builds it)

    @core_method("_core", "ik")
    def ik(
        self, T: ArrayLike, seed: ArrayLike | None = None, *, out: tuple | None = None
    ) -> tuple[np.ndarray, np.ndarray | Status]:
        """The in-limit solution nearest to ``seed``: (q (..., 6), status).

        Nearest means the smallest largest-single-joint move, measured on the circle
        (ties to the lower slot); without a seed, the lowest valid slot. Statuses:
        OK; UNREACHABLE (no solution: q is NaN); JOINT_LIMIT (solutions exist, none
        within the limits: q is NaN); INVALID_INPUT (NaN/Inf, a non-rotation, or a
        NaN seed: q is NaN). A single pose gets an :class:`Status`, a batch an int8 array. The seed
        broadcasts with T; ``out``: ``(q, status)`` arrays to write into (either may be None).
        """
        return self._core.ik(T, seed, out)

    def __reduce__(self):
        mount, upper_arm, forearm, forearm_offset, hand, tool, limits = self._params
        return (SpotArm, (mount, upper_arm, forearm, forearm_offset, hand, tool, limits))

    def __repr__(self) -> str:
        mount, upper_arm, forearm, forearm_offset, hand, _, _ = self._params
        return (
            f"SpotArm(mount={tuple(float(v) for v in mount)}, upper_arm={upper_arm}, forearm={forearm}, "
            f"forearm_offset={forearm_offset}, hand={hand})"
        )
