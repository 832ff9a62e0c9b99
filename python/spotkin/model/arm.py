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

from collections.abc import Mapping
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
from .._support.forward import AT_DEFAULT, core_method
from .._support.status import Status
from .chain import Chain
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

    @property
    def exact(self) -> np.ndarray:
        """(..., 8) bool: the slot solves the pose exactly, as :attr:`spotkin.ChainSolutions.exact`; the
        arm's closed form is exact wherever a solution exists, so this is :attr:`exists`."""
        return self.exists


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


ARM_JOINT_NAMES = ("arm0.sh0", "arm0.sh1", "arm0.el0", "arm0.el1", "arm0.wr0", "arm0.wr1")


ARM_SLOT_NAMES = tuple(
    f"{shoulder} shoulder, elbow {elbow}, {wrist}"
    for shoulder in ("front", "back")
    for elbow in ("up", "down")
    for wrist in ("wr0 ≥ 0", "wr0 < 0")
)
"""What each of :meth:`SpotArm.ik_all`'s 8 slots means (``slot = 4 * shoulder + 2 * elbow + wrist``)."""


def _translation(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


# The Spot Arm's joint axes at zero angles, in order: z, y, y, x, y, x (module docstring)
_AXES = np.array([(0, 0, 1), (0, 1, 0), (0, 1, 0), (1, 0, 0), (0, 1, 0), (1, 0, 0)], dtype=np.float64)


class SpotArm(Chain):
    """The Spot Arm, or any arm of the same structure: a 6-joint :class:`~spotkin.Chain` whose FK,
    Jacobian and IK (all 8 solutions) run the arm's own closed form. See the module docstring.

    Parameters default to the official Spot numbers (Boston Dynamics' ``spot_with_arm.urdf``).
    ``tool`` (4, 4) maps the hand frame to the frame the IK targets (for example the
    gripper fingertip); ``limits`` is (6, 2) [(lower, upper)], or None for none; ``joint_names``
    the six joints' names (the Spot SDK's by default). Lengths must be real numbers and arrays
    real arrays (``TypeError`` otherwise); the core rejects non-finite values and inconsistent
    limits with ``ValueError``.

    Being a :class:`~spotkin.Chain`, it has every chain method as well: :meth:`~spotkin.Chain.frames`,
    the point Jacobians, differential IK and, with mass properties (:meth:`~spotkin.Chain.with_inertials`,
    or an arm loaded from a URDF), the dynamics. :attr:`tool` is the chain's: the last joint's
    frame to the tool, ``Trans(hand, 0, 0) @ tool``. A robot loaded from a URDF whose arm has this
    structure gets a SpotArm as its :attr:`spotkin.Robot.arm` (:meth:`from_chain`), as
    :class:`spotkin.Spot` does.
    """

    __slots__ = ("_arm", "_params")

    slot_names = ARM_SLOT_NAMES
    """What each of :meth:`ik_all`'s 8 slots means: the shoulder (front or back), the elbow (up or
    down) and the wrist (wr0 >= 0 or its flip). A plain chain's slots have no fixed meaning."""

    def __init__(
        self,
        mount: ArrayLike = SPOT["arm"]["mount"],
        upper_arm: float = SPOT["arm"]["upper_arm"],
        forearm: float = SPOT["arm"]["forearm"],
        forearm_offset: float = SPOT["arm"]["forearm_offset"],
        hand: float = SPOT["arm"]["hand"],
        tool: ArrayLike | None = None,
        limits: ArrayLike | None = SPOT["arm"]["limits"],
        *,
        joint_names: tuple[str, ...] | None = ARM_JOINT_NAMES,
    ) -> None:
        table = limit_table(limits, 6)
        mount = as_real(mount, "mount", np.float64).copy()
        if mount.shape != (3,):
            raise ValueError(f"mount must have shape (3,), got {mount.shape}")
        tool = None if tool is None else rigid_transforms(tool, "tool")
        upper_arm, forearm = as_scalar(upper_arm, "upper_arm"), as_scalar(forearm, "forearm")
        forearm_offset, hand = as_scalar(forearm_offset, "forearm_offset"), as_scalar(hand, "hand")
        self._params = (mount, float(upper_arm), float(forearm), float(forearm_offset), float(hand), tool)
        self._arm = self._arm_core(table)
        placements = np.stack(
            [
                _translation(*mount),
                np.eye(4),
                _translation(float(upper_arm), 0.0, 0.0),
                _translation(float(forearm), 0.0, float(forearm_offset)),
                np.eye(4),
                np.eye(4),
            ]
        )
        chain_tool = _translation(float(hand), 0.0, 0.0)
        if tool is not None:
            chain_tool = chain_tool @ tool
        self._set_joints(placements, _AXES, None, None, chain_tool, table, joint_names)

    def _arm_core(self, table: np.ndarray):
        mount, upper_arm, forearm, forearm_offset, hand, tool = self._params
        return _core.Arm(mount, upper_arm, forearm, forearm_offset, hand, tool, table[:, 0], table[:, 1])

    @classmethod
    def from_chain(cls, chain: Chain) -> SpotArm | None:
        """``chain`` as a SpotArm when it has the Spot Arm's structure (six revolute joints whose axes
        at zero are z, y, y, x, y, x, no rotation in any placement, offsets only where the module
        docstring's model has them, to 1e-12), keeping its joint names, limits, mass properties and
        IK tolerances; None otherwise. The tool may be any rigid transform."""
        if not isinstance(chain, Chain):
            raise TypeError(f"chain must be an sk.Chain, got {type(chain).__name__}")
        if isinstance(chain, SpotArm):
            return chain
        joints = getattr(chain, "_joints", None)
        if type(chain) is not Chain or joints is None or chain.dof != 6 or chain._base is not None:
            return None
        placements, axes, types = joints
        norms = np.linalg.norm(axes, axis=1, keepdims=True)
        offsets = placements[:, :3, 3]
        if (
            types.any()
            or np.abs(axes / norms - _AXES).max() > 1e-12
            or np.abs(placements[:, :3, :3] - np.eye(3)).max() > 1e-12
            or np.abs(offsets[[1, 4, 5]]).max() > 1e-12
            or np.abs(offsets[2, 1:]).max() > 1e-12
            or abs(offsets[3, 1]) > 1e-12
        ):
            return None
        tool = chain.tool
        plain = np.abs(tool[:3, :3] - np.eye(3)).max() == 0.0 and not tool[1:3, 3].any()
        hand, rest = (float(tool[0, 3]), None) if plain else (0.0, tool)
        try:
            arm = cls(
                offsets[0],
                offsets[2, 0],
                offsets[3, 0],
                offsets[3, 2],
                hand,
                rest,
                chain.limits,
                joint_names=chain.joint_names,
            )
        except ValueError:  # a geometry the closed form refuses (a zero upper arm, say): the chain's own IK
            return None
        arm._inertials = chain._inertials
        arm._ik_tolerance = chain._ik_tolerance
        return arm

    def singularity(self, q: ArrayLike) -> ArmSingularity:
        """Wrist, elbow and shoulder distances to the singular sets, and manipulability (float64)."""
        out = self._arm.singularity(q)
        return ArmSingularity(out[..., 0], out[..., 1], out[..., 2], out[..., 3])

    @core_method("_arm", "fk")
    def fk(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """Tool pose in the arm's base frame: q (..., 6) -> (..., 4, 4), by the arm's closed form.
        ``out``: an array of the result's shape and dtype to write into and return."""
        return self._arm.fk(q, out)

    @core_method("_arm", "jacobian", call=("q", "out"), convert={"frame": AT_DEFAULT, "point": AT_DEFAULT})
    def jacobian(
        self,
        q: ArrayLike,
        frame: str | int = "base",
        *,
        point: str | int = "tool",
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Geometric Jacobian [v; w] of the tool point in the base frame: (..., 6) -> (..., 6, 6), by the
        arm's closed form; another ``frame`` or ``point`` as :meth:`spotkin.Chain.jacobian`. ``out`` as
        in :meth:`fk`."""
        if frame is _BASE and point is _TOOL:
            return self._arm.jacobian(q, out)
        return super().jacobian(q, frame, point=point, out=out)

    @core_method("_arm", "ik_all")
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
        return self._arm.ik_all(T, seed, out)  # an ArmSolutions (the core builds it)

    @core_method("_arm", "ik")
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
        return self._arm.ik(T, seed, out)

    def with_limits(self, limits) -> SpotArm:
        """As :meth:`spotkin.Chain.with_limits`: a new SpotArm whose closed form uses the new limits."""
        arm = super().with_limits(limits)
        arm._arm = arm._arm_core(arm.limits)
        return arm

    def __reduce__(self):
        limits = None if np.isinf(self._limits).all() else self.limits
        args = (*self._params, limits, self._names, self._inertials, self._ik_tolerance)
        return (_rebuild_spot_arm, args)

    def __repr__(self) -> str:
        mount, upper_arm, forearm, forearm_offset, hand, _ = self._params
        return (
            f"SpotArm(mount={tuple(float(v) for v in mount)}, upper_arm={upper_arm}, forearm={forearm}, "
            f"forearm_offset={forearm_offset}, hand={hand})"
        )


_BASE, _TOOL = "base", "tool"  # SpotArm.jacobian's defaults


def arm_solver(chain: Chain, renames: Mapping[str, str] | None = None) -> Chain:
    """A robot's arm from its chain: a :class:`SpotArm` where it has that structure (its own closed form,
    the same whichever way the robot was loaded), else the chain; joints renamed by ``renames`` (the
    description's name -> the robot's)."""
    arm = SpotArm.from_chain(chain) or chain
    if renames and arm.joint_names is not None:
        arm = arm._renamed(tuple(renames.get(name, name) for name in arm.joint_names))
    return arm


def _rebuild_spot_arm(
    mount, upper_arm, forearm, forearm_offset, hand, tool, limits, names, inertials, tolerance
):
    arm = SpotArm(mount, upper_arm, forearm, forearm_offset, hand, tool, limits, joint_names=names)
    if inertials is not None:
        arm = arm.with_inertials(*inertials)
    if tolerance is not None:
        arm = arm.with_ik_tolerance(*tolerance)
    return arm
