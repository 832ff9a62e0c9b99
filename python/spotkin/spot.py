"""The built-in Spot model: four legs in SDK order and the arm, from the official URDF
numbers; whole-body IK, FK and Jacobians."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from .arm import SpotArm
from .body import body_transform, pose_format, sequence_code
from .leg import Leg
from .models import LEG_NAMES, SPOT

__all__ = ["BodyFrames", "BodyIK", "BodyRates", "Spot"]


class BodyIK(NamedTuple):
    """Whole-body IK results, from :meth:`Spot.body_ik`."""

    q: np.ndarray
    """(..., 12) joint angles in SDK order fl.hx fl.hy fl.kn fr.* hl.* hr.*."""
    status: np.ndarray
    """(..., 4) int8 :class:`Status` per leg, with the leg API's meaning and fallback."""


class BodyRates(NamedTuple):
    """Joint velocities that keep the feet fixed, from :meth:`Spot.body_rates`."""

    qd: np.ndarray
    """(..., 12) joint velocities; NaN for a singular leg."""
    singular: np.ndarray
    """(..., 4) bool: the leg's Jacobian is singular (smallest singular value below ``tolerance``)."""


class BodyFrames(NamedTuple):
    """Frames of interest in the world frame, from :meth:`Spot.fk_all`."""

    body: np.ndarray
    """(..., 4, 4) world <- body."""
    hips: np.ndarray
    """(..., 4, 3) hx joint origins."""
    knees: np.ndarray
    """(..., 4, 3) knee joint origins."""
    feet: np.ndarray
    """(..., 4, 3) foot-sphere centres."""
    hand: np.ndarray | None
    """(..., 4, 4) the arm's tool frame, or None without ``q_arm``."""


_XYZ = sequence_code("XYZ")


def _broadcast_to_lead(array: np.ndarray, trailing: int, lead: tuple[int, ...]) -> np.ndarray:
    if array.shape[: array.ndim - trailing] == lead:
        return array
    return np.broadcast_to(array, (*lead, *array.shape[array.ndim - trailing :]))


class Spot:
    """Boston Dynamics Spot. Body frame: x forward, y left, z up, origin at the
    centre of the four hx joints. Legs in SDK order: fl, fr, hl, hr."""

    __slots__ = ("_arm", "_body_core", "_legs", "_model")

    def __init__(self, model: dict | None = None) -> None:
        self._model = SPOT if model is None else model
        leg = self._model["leg"]
        self._legs = tuple(
            Leg(
                leg["hip_offset"],
                leg["upper"],
                leg["lower"],
                leg["knee_offset"],
                side="left" if name.endswith("l") else "right",
                limits=leg["limits"],
                name=name,
            )
            for name in LEG_NAMES
        )
        self._body_core = _core.Body([leg._core for leg in self._legs], self.hip_positions)
        arm = self._model["arm"]
        self._arm = SpotArm(
            arm["mount"],
            arm["upper_arm"],
            arm["forearm"],
            arm["forearm_offset"],
            arm["hand"],
            limits=arm["limits"],
        )

    @property
    def arm(self) -> SpotArm:
        """The Spot Arm, mounted at its official position on the body."""
        return self._arm

    @property
    def legs(self) -> tuple[Leg, Leg, Leg, Leg]:
        """The four legs in SDK order (fl, fr, hl, hr)."""
        return self._legs

    def leg(self, name: str) -> Leg:
        """One leg by SDK name: "fl", "fr", "hl" or "hr"."""
        try:
            return self._legs[LEG_NAMES.index(name)]
        except ValueError:
            raise ValueError(f"leg name must be one of {LEG_NAMES}, got {name!r}") from None

    @property
    def hip_positions(self) -> np.ndarray:
        """(4, 3) hx joint origins in the body frame, SDK order."""
        return np.array([self._model["hip_positions"][name] for name in LEG_NAMES], dtype=np.float64)

    # -- whole body -----------------------------------------------------------------------------------

    def stance_feet(self, height: float = 0.5) -> np.ndarray:
        """(4, 3) world foot centres of a nominal stance, for the body at [0, 0, height, 0, 0, 0].

        Each foot is straight below its hy joint (hx = 0) with the foot sphere resting on
        the ground z = 0, so its centre is at z = foot_radius.
        """
        leg = self._model["leg"]
        feet = self.hip_positions.copy()
        feet[:, 1] += [leg.hip_offset for leg in self._legs]
        feet[:, 2] = self._model["leg"]["foot_radius"]
        if not 0.0 < height - feet[0, 2] <= self._legs[0].reach[1]:
            raise ValueError(f"height {height} m puts the feet out of reach")
        del leg
        return feet

    def body_ik(
        self, body_pose: ArrayLike, feet: ArrayLike, seed: ArrayLike | None = None, seq: str = "XYZ"
    ) -> BodyIK:
        """The 12 leg joints placing the body at ``body_pose`` with the feet at ``feet``.

        ``body_pose`` is (..., 6) [x, y, z, a, b, c] with Euler angles in ``seq``
        (default intrinsic X-Y'-Z''), (..., 4, 4), or (..., 7) [x, y, z, qx, qy, qz, qw]:
        see :mod:`spotkin.body`. ``feet`` (..., 4, 3) are world foot centres; leading
        dimensions broadcast (a single (4, 3) stance is shared without copying). Each
        foot is brought into its hip frame, p = R^T (foot - t) - hip, and solved by the
        limit-aware leg IK: each leg's status and fallback are exactly those of
        :meth:`Leg.ik`, and a leg's failure never touches the other legs. ``seed``
        (..., 12) picks the branch where several are valid. A pose with NaN, or a 4x4 /
        quaternion that is not a rotation, gives INVALID_INPUT on all four legs of that
        sample only.
        """
        if seed is None and seq == "XYZ" and type(feet) is np.ndarray and feet.shape == (4, 3):
            # the control-loop call, one shared stance: the core checks body_pose itself
            return BodyIK._make(self._body_core.ik(body_pose, -1, _XYZ, feet, None))
        pose = body_pose if type(body_pose) is np.ndarray else np.asarray(body_pose)
        fmt, pose_lead = pose_format(pose)
        code = sequence_code(seq)
        feet = feet if type(feet) is np.ndarray else np.asarray(feet)
        if feet.shape[-2:] != (4, 3):
            raise ValueError(f"feet must have shape (..., 4, 3), got {feet.shape}")
        feet_lead = feet.shape[:-2]
        if not feet_lead or feet_lead == pose_lead:  # a shared stance, or one stance per pose
            lead = pose_lead
        else:
            try:
                lead = np.broadcast_shapes(pose_lead, feet_lead)
            except ValueError:
                raise ValueError(f"body_pose {pose.shape} and feet {feet.shape} do not broadcast") from None
            if feet_lead != lead:
                feet = feet.reshape(4, 3) if feet.size == 12 else np.broadcast_to(feet, (*lead, 4, 3))
            pose = _broadcast_to_lead(pose, pose.ndim - len(pose_lead), lead)
        if seed is not None:
            seed = np.asarray(seed)
            if seed.shape[-1:] != (12,):
                raise ValueError(f"seed must have shape (..., 12), got {seed.shape}")
            if seed.shape[:-1] != lead:
                seed = np.broadcast_to(seed, (*lead, 12))
        return BodyIK(*self._body_core.ik(pose, fmt, code, feet, seed))

    def body_fk(self, body_pose: ArrayLike, q12: ArrayLike, seq: str = "XYZ") -> np.ndarray:
        """(..., 4, 3) world foot centres: foot = t + R (hip + leg.fk(q)). Leading dimensions broadcast."""
        pose, q12, fmt, code = self._pose_and_q(body_pose, q12, seq)
        return self._body_core.fk(pose, fmt, code, q12)

    def body_jacobian(self, body_pose: ArrayLike, q12: ArrayLike, seq: str = "XYZ") -> np.ndarray:
        """(..., 12, 18) d(feet world) / d(body twist [v; w], q12).

        The twist is the linear velocity of the body origin and the angular velocity,
        both in the world frame: d foot_i = v + w x (foot_i - t) + R J_leg_i dq_i.
        """
        pose, q12, fmt, code = self._pose_and_q(body_pose, q12, seq)
        return self._body_core.jacobian(pose, fmt, code, q12)

    def body_rates(
        self,
        body_pose: ArrayLike,
        q12: ArrayLike,
        twist: ArrayLike,
        seq: str = "XYZ",
        tolerance: float = 1e-6,
    ) -> BodyRates:
        """Joint velocities that keep every foot fixed while the body moves with ``twist``.

        ``twist`` (..., 6) is [v; w] (world frame, as in :meth:`body_jacobian`). Per leg,
        J_leg dq = -R^T (v + w x (foot - t)). A leg whose Jacobian's smallest singular
        value is below ``tolerance`` (stretched, folded, or on the hip-roll cylinder)
        gets NaN velocities and ``singular = True``: it cannot follow every twist.
        """
        T = body_transform(body_pose, seq)
        q12 = np.asarray(q12, dtype=np.float64)
        twist = np.asarray(twist, dtype=np.float64)
        if q12.shape[-1:] != (12,):
            raise ValueError(f"q12 must have shape (..., 12), got {q12.shape}")
        if twist.shape[-1:] != (6,):
            raise ValueError(f"twist must have shape (..., 6), got {twist.shape}")
        lead = np.broadcast_shapes(T.shape[:-2], q12.shape[:-1], twist.shape[:-1])
        R = np.broadcast_to(T[..., :3, :3], (*lead, 3, 3))
        q = np.broadcast_to(q12, (*lead, 12)).reshape(*lead, 4, 3)
        v, w = np.broadcast_to(twist[..., :3], (*lead, 3)), np.broadcast_to(twist[..., 3:], (*lead, 3))
        qd = np.empty((*lead, 4, 3))
        singular = np.empty((*lead, 4), dtype=bool)
        for i, leg in enumerate(self._legs):
            r = np.einsum("...ij,...j->...i", R, self.hip_positions[i] + leg.fk(q[..., i, :]))
            rhs = -np.einsum("...ji,...j->...i", R, v + np.cross(w, r))
            J = leg.jacobian(q[..., i, :])
            sigma = leg.singularity(q[..., i, :])[1]
            bad = ~(sigma >= tolerance)
            J_safe = np.where(bad[..., None, None], np.eye(3), J)
            qd[..., i, :] = np.where(bad[..., None], np.nan, np.linalg.solve(J_safe, rhs[..., None])[..., 0])
            singular[..., i] = bad
        return BodyRates(qd.reshape(*lead, 12), singular)

    def arm_ik_world(
        self, body_pose: ArrayLike, T_world: ArrayLike, seed: ArrayLike | None = None, seq: str = "XYZ"
    ):
        """Arm IK for hand targets given in the world frame: (q (..., 6), status).

        T_body = T_world_body^-1 T_world, then :meth:`SpotArm.ik`. ``T_world`` is (..., 4, 4);
        body poses, targets and seeds broadcast together.
        """
        T_wb = body_transform(body_pose, seq)
        T_world = np.asarray(T_world, dtype=np.float64)
        if T_world.shape[-2:] != (4, 4):
            raise ValueError(f"T_world must have shape (..., 4, 4), got {T_world.shape}")
        R, t = T_wb[..., :3, :3], T_wb[..., :3, 3]
        T_bw = np.zeros_like(T_wb)
        T_bw[..., :3, :3] = np.swapaxes(R, -1, -2)
        T_bw[..., :3, 3] = -np.einsum("...ji,...j->...i", R, t)
        T_bw[..., 3, 3] = 1.0
        T_body = T_bw @ T_world
        T_body[..., 3, :] = T_world[..., 3, :]  # keep the caller's last row, so a bad one is still reported
        return self._arm.ik(T_body, seed=seed)

    def fk_all(
        self, body_pose: ArrayLike, q12: ArrayLike, q_arm: ArrayLike | None = None, seq: str = "XYZ"
    ) -> BodyFrames:
        """Every frame of interest in the world frame: body, hips, knees, feet, and the hand."""
        T = body_transform(body_pose, seq)
        q12 = np.asarray(q12, dtype=np.float64)
        lead = np.broadcast_shapes(T.shape[:-2], q12.shape[:-1])
        T = np.broadcast_to(T, (*lead, 4, 4))
        q = np.broadcast_to(q12, (*lead, 12)).reshape(*lead, 4, 3)
        R, t = T[..., :3, :3], T[..., :3, 3]

        def world(p):
            return t[..., None, :] + np.einsum("...ij,...kj->...ki", R, p)

        hips = np.broadcast_to(self.hip_positions, (*lead, 4, 3))
        knees, feet = np.empty((*lead, 4, 3)), np.empty((*lead, 4, 3))
        for i, leg in enumerate(self._legs):
            hx, hy = q[..., i, 0], q[..., i, 1]
            # knee = Rx(hx) ([0, h1, 0] + Ry(hy) [k, 0, -upper]) in the leg frame
            kx = leg.knee_offset * np.cos(hy) - leg.upper * np.sin(hy)
            kz = -leg.knee_offset * np.sin(hy) - leg.upper * np.cos(hy)
            knees[..., i, :] = self.hip_positions[i] + np.stack(
                [
                    kx,
                    leg.hip_offset * np.cos(hx) - kz * np.sin(hx),
                    leg.hip_offset * np.sin(hx) + kz * np.cos(hx),
                ],
                -1,
            )
            feet[..., i, :] = self.hip_positions[i] + leg.fk(q[..., i, :])
        hand = None if q_arm is None else T @ self._arm.fk(q_arm)
        return BodyFrames(T.copy(), world(hips), world(knees), world(feet), hand)

    def _pose_and_q(self, body_pose, q12, seq):
        pose = body_pose if type(body_pose) is np.ndarray else np.asarray(body_pose)
        fmt, pose_lead = pose_format(pose)
        code = sequence_code(seq)
        q12 = q12 if type(q12) is np.ndarray else np.asarray(q12)
        if q12.shape[-1:] != (12,):
            raise ValueError(f"q12 must have shape (..., 12), got {q12.shape}")
        if q12.shape[:-1] != pose_lead:
            try:
                lead = np.broadcast_shapes(pose_lead, q12.shape[:-1])
            except ValueError:
                raise ValueError(f"body_pose {pose.shape} and q12 {q12.shape} do not broadcast") from None
            pose = _broadcast_to_lead(pose, pose.ndim - len(pose_lead), lead)
            q12 = _broadcast_to_lead(q12, 1, lead)
        return pose, q12, fmt, code

    def __reduce__(self):
        return (Spot, (None if self._model is SPOT else self._model,))

    def __repr__(self) -> str:
        return "Spot()"
