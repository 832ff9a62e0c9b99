"""A robot's whole-body kinematics: body IK, FK, Jacobians and rates, every frame, the arm's IK in the
world. :class:`spotkin.Robot` takes these methods from the base class here; their result types are
defined here."""

from __future__ import annotations

import contextlib
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import (
    as_finite,
    as_real,
    as_scalar,
    broadcast_lead,
    check_trailing,
    fallback_is_nearest,
    into_out,
    quiet_float_errors,
    real_dtype,
)
from .._support.forward import core_method
from .._support.status import Status
from .body import body_transform, sequence_code

__all__ = ["BodyFrames", "BodyIK", "BodyRates"]

_DEFAULT_SEQ, _DEFAULT_FALLBACK = "XYZ", "nearest"  # body_ik's defaults: their fast test is by identity
_XYZ = sequence_code(_DEFAULT_SEQ)


class BodyIK(NamedTuple):
    """Whole-body IK results, from :meth:`Robot.body_ik`."""

    q: np.ndarray
    """(..., 3 n) leg joint angles, in the order of :attr:`Robot.leg_joint_names`."""
    status: np.ndarray
    """(..., n) int8 :class:`Status` per leg, with the leg API's meaning and fallback."""


_core._register_result_type("BodyIK", BodyIK)  # the core returns it itself


class BodyRates(NamedTuple):
    """Joint velocities that keep the feet fixed, from :meth:`Robot.body_rates`."""

    qd: np.ndarray
    """(..., 3 n) joint velocities; NaN for a singular leg."""
    singular: np.ndarray
    """(..., n) bool: the leg's Jacobian is singular (smallest singular value below ``tolerance``)."""


class BodyFrames(NamedTuple):
    """Frames of interest in the world frame, from :meth:`Robot.fk_all`."""

    body: np.ndarray
    """(..., 4, 4) world <- body."""
    hips: np.ndarray
    """(..., n, 3) hip-roll joint origins."""
    knees: np.ndarray
    """(..., n, 3) knee joint origins."""
    feet: np.ndarray
    """(..., n, 3) foot points."""
    hand: np.ndarray | None
    """(..., 4, 4) the arm's tool frame, or None without ``q_arm``."""


def _broadcast_to_lead(array: np.ndarray, trailing: int, lead: tuple[int, ...]) -> np.ndarray:
    if array.shape[: array.ndim - trailing] == lead:
        return array
    return np.broadcast_to(array, (*lead, *array.shape[array.ndim - trailing :]))


def _solve_rows(J: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with J x = rhs for each J (n, 3, 3), rhs (n, 3); NaN rows where LAPACK finds J
    exactly singular (the rest of the batch is unaffected)."""
    try:
        return np.linalg.solve(J, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:  # one exactly singular J: solve one by one
        x = np.full(rhs.shape, np.nan)
        for k in range(len(J)):
            with contextlib.suppress(np.linalg.LinAlgError):
                x[k] = np.linalg.solve(J[k], rhs[k])
        return x


class _WholeBodyMethods:
    """The whole-body kinematics methods of :class:`spotkin.Robot` (its base class; see there)."""

    __slots__ = ()

    def stance_feet(self, height: float = 0.5, foot_radius: float = 0.0) -> np.ndarray:
        """(n, 3) world foot points of a nominal stance, for the body at [0, 0, height, 0, 0, 0].

        Each foot is straight below its hip-pitch joint at the leg's lateral offset (hip roll 0),
        with the foot point ``foot_radius`` above the ground z = 0.
        """
        height = as_scalar(height, "height")
        foot_radius = as_finite(foot_radius, "foot_radius", 0.0)
        feet = self.hip_positions
        for k, leg in enumerate(self._legs):
            feet[k, 0] += leg.a[0]
            feet[k, 1] += leg.hip_offset
        feet[:, 2] = foot_radius
        for k, leg in enumerate(self._legs):
            drop = height + self._hips[k, 2] + leg.a[2] - foot_radius
            if not (0.0 < drop <= leg.reach[1] and drop >= leg.reach[0]):
                raise ValueError(f"height {height} m puts the feet out of reach")
        return feet

    @core_method(
        "_body_core",
        "ik",
        call=("body_pose", "seq", "feet", "seed", "fallback", "out"),
        convert={"seq": sequence_code, "fallback": fallback_is_nearest},
    )
    def body_ik(
        self,
        body_pose: ArrayLike,
        feet: ArrayLike,
        seed: ArrayLike | None = None,
        seq: str = "XYZ",
        fallback: str = "nearest",
        *,
        out: tuple[np.ndarray | None, np.ndarray | None] | None = None,
    ) -> BodyIK:
        """The leg joints placing the body at ``body_pose`` with the feet at ``feet``.

        ``body_pose`` is (..., 6) [x, y, z, a, b, c] with Euler angles in ``seq``
        (default intrinsic X-Y'-Z''), (..., 4, 4), or (..., 7) [x, y, z, qx, qy, qz, qw]:
        see :func:`spotkin.body_transform`. ``feet`` (..., n, 3) are world foot points; leading
        dimensions broadcast (a single (n, 3) stance is shared without copying). Each
        foot is brought into its hip frame, p = R^T (foot - t) - hip, and solved by the
        limit-aware leg IK: each leg's status and fallback are exactly those of
        :meth:`Leg.ik`, and a leg's failure never touches the other legs. ``seed``
        (..., 3 n), or a whole-body q with the arm's joints after (unused), picks the
        branch where several are valid. A pose with NaN, or a 4x4 / quaternion that is not
        a rotation, gives INVALID_INPUT on every leg of that sample only. ``fallback`` is the
        UNREACHABLE legs' answer, as in :meth:`Leg.ik`: ``"nearest"`` (the in-limit
        configuration whose foot is nearest to the target) or ``"nan"``. Computed in float32
        when ``body_pose`` and ``feet`` both are float32, else float64; ``seed`` takes that
        dtype. ``out``: ``(q, status)`` arrays of the result's shapes and dtypes (either may be
        None) to write into, so that a control loop allocates nothing.
        """
        if seq is _DEFAULT_SEQ and fallback is _DEFAULT_FALLBACK:  # the defaults (interned strings)
            code, nearest = _XYZ, True
        else:
            code, nearest = sequence_code(seq), fallback_is_nearest(fallback)
        if seed is not None and not (type(seed) is np.ndarray and seed.shape[-1:] == (3 * len(self._legs),)):
            seed = self._leg_q(as_real(seed, "seed"), "seed")[0]  # a whole-body q: the arm's part unused
        return self._body_core.ik(body_pose, code, feet, seed, nearest, out)

    @core_method("_body_core", "fk", call=("body_pose", "seq", "q", "out"), convert={"seq": sequence_code})
    def body_fk(
        self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """(..., n, 3) world foot points: foot = t + R (hip + leg.fk(q_leg)). Leading dimensions broadcast.
        ``q`` holds the legs' joints (..., 3 n), or the legs' then the arm's, as every whole-body call
        takes it (the arm does not move the feet).

        float32 when ``body_pose`` and ``q`` both are float32, else float64. A leg with a
        NaN or Inf joint gets a NaN foot; an invalid body pose NaN feet for its sample.
        ``out``: an array of the result's shape and dtype to write into and return."""
        q = self._leg_q(as_real(q, "q"), "q")[0]
        return self._body_core.fk(body_pose, sequence_code(seq), q, out)

    @core_method(
        "_body_core", "jacobian", call=("body_pose", "seq", "q", "out"), convert={"seq": sequence_code}
    )
    def body_jacobian(
        self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """(..., 3 n, 6 + 3 n) d(feet world) / d(body twist [v; w], q).

        The twist is the linear velocity of the body origin and the angular velocity,
        both in the world frame: d foot_i = v + w x (foot_i - t) + R J_leg_i dq_i. ``q`` (..., 3 n), or
        (..., 3 n + n_arm) with the arm's joints after the legs': then the arm's columns follow, zero
        (the arm does not move the feet), so that J has a column per entry of the twist and of ``q``.
        ``out``: an array of the result's shape and dtype to write into and return.
        """
        if type(q) is np.ndarray and q.shape == (3 * len(self._legs),):  # the control loop's call
            return self._body_core.jacobian(body_pose, sequence_code(seq), q, out)
        q = as_real(q, "q")
        width = q.shape[-1] if q.ndim else 0
        q = self._leg_q(q, "q")[0]
        if width == q.shape[-1]:
            return self._body_core.jacobian(body_pose, sequence_code(seq), q, out)
        J = self._body_core.jacobian(body_pose, sequence_code(seq), q, None)
        full = np.zeros((*J.shape[:-1], 6 + width), dtype=J.dtype)
        full[..., : J.shape[-1]] = J
        return into_out(full, out)

    @quiet_float_errors
    def body_rates(
        self,
        body_pose: ArrayLike,
        q: ArrayLike,
        twist: ArrayLike,
        seq: str = "XYZ",
        tolerance: float = 1e-6,
    ) -> BodyRates:
        """Joint velocities that keep every foot fixed while the body moves with ``twist``.

        ``q`` (..., 3 n), or with the arm's joints after the legs': ``qd`` then has the same width, the
        arm's rates zero (the arm held still on the body; NaN in a sample with NaN or Inf input).
        ``twist`` (..., 6) is [v; w] (world frame, as in :meth:`body_jacobian`). Per leg,
        J_leg dq = -R^T (v + w x (foot - t)). Leading dimensions of ``body_pose``, ``q``
        and ``twist`` broadcast; the result is float64.

        A leg gets NaN velocities and ``singular = True`` when it has no usable answer:
        its Jacobian's smallest singular value is not above ``tolerance`` (stretched,
        folded, or on the hip-roll cylinder: it cannot follow every twist), or its
        sample has a NaN or Inf joint angle, twist or body pose, or a body pose that is
        not a rigid transform (as :meth:`body_fk` reads it). So ``qd`` is NaN exactly
        where ``singular`` is True, and such a leg never affects another leg or sample.

        ``tolerance`` must be a finite real number >= 0 (``TypeError`` for a non-number,
        ``ValueError`` for NaN, Inf or a negative value). Non-numeric arrays raise
        ``TypeError``, wrong or non-broadcasting shapes ``ValueError``, naming the argument.
        """
        tolerance = as_finite(tolerance, "tolerance", 0.0)
        n_legs = len(self._legs)
        T, pose = self._world_from_body(body_pose, seq)
        q = as_real(q, "q", np.float64)
        given = q.shape[-1] if q.ndim else 0
        q, q_arm = self._leg_q(q, "q")
        width = 3 * n_legs
        twist = as_real(twist, "twist", np.float64)
        lead = broadcast_lead(
            body_pose=(T.shape[:-2], pose.shape),
            q=(q.shape[:-1], q.shape),
            twist=(check_trailing(twist, "twist", (6,)), twist.shape),
        )
        n = math.prod(lead)
        R = np.broadcast_to(T[..., :3, :3], (*lead, 3, 3)).reshape(n, 3, 3)
        q = np.broadcast_to(q, (*lead, width)).reshape(n, width)
        twist = np.broadcast_to(twist, (*lead, 6)).reshape(n, 6)
        v, w = twist[:, :3], twist[:, 3:]
        qd = np.full((n, width), np.nan)
        singular = np.ones((n, n_legs), dtype=bool)
        for i, leg in enumerate(self._legs):
            columns = self._columns[i]
            q_leg = q[:, columns]
            r = np.einsum("nij,nj->ni", R, self._hips[i] + leg.fk(q_leg))
            rhs = -np.einsum("nji,nj->ni", R, v + np.cross(w, r))
            J = leg.jacobian(q_leg)
            sigma = leg.singularity(q_leg)[1]
            # the finiteness checks do not rely on sigma, which NaN input need not make NaN
            finite_input = np.isfinite(J).all((1, 2)) & np.isfinite(rhs).all(1)
            usable = np.flatnonzero((sigma > tolerance) & finite_input)
            solved = _solve_rows(J[usable], rhs[usable])
            finite = np.isfinite(solved).all(1)
            rows = usable[finite]
            qd[rows[:, None], columns[None, :]] = solved[finite]
            singular[rows, i] = False
        if q_arm is not None:  # the arm held still on the body: zero rates, NaN for a non-finite sample
            q_arm = np.broadcast_to(q_arm, (*lead, given - width)).reshape(n, given - width)
            finite = (
                np.isfinite(q_arm).all(1)
                & np.isfinite(q).all(1)
                & np.isfinite(twist).all(1)
                & np.broadcast_to(np.isfinite(T).all((-2, -1)), lead).reshape(n)
            )
            arm_rates = np.where(finite[:, None], 0.0, np.nan) * np.ones((n, given - width))
            qd = np.concatenate([qd, arm_rates], axis=1)
        return BodyRates(qd.reshape(*lead, given), singular.reshape(*lead, n_legs))

    @quiet_float_errors
    def fk_all(
        self, body_pose: ArrayLike, q: ArrayLike, q_arm: ArrayLike | None = None, seq: str = "XYZ"
    ) -> BodyFrames:
        """Every frame of interest in the world frame: body, hips, knees, feet, and the hand.

        Checked as :meth:`body_fk`: ``body_pose`` in any accepted form, ``q`` (..., 3 n) (or with the
        arm's joints after the legs', in place of ``q_arm``) and ``q_arm`` (..., 6) real arrays whose
        leading dimensions broadcast (``TypeError``
        for non-numeric input such as None, ``ValueError`` naming the argument for another
        shape). A body pose with NaN or Inf, or that is not a rigid transform (a 4x4 whose
        rotation part is not a rotation or whose last row is not [0, 0, 0, 1], a non-unit
        quaternion), gives NaN frames for that sample only, as :meth:`body_fk` gives NaN
        feet. Every frame is float64. ``q_arm`` needs an :attr:`arm`.
        """
        n_legs = len(self._legs)
        T, pose = self._world_from_body(body_pose, seq)
        q, q_arm_in_q = self._leg_q(as_real(q, "q", np.float64), "q")
        if q_arm_in_q is not None:
            if q_arm is not None:
                raise ValueError("q holds the arm's joints, so q_arm must be None")
            q_arm = q_arm_in_q
        leads = {
            "body_pose": (T.shape[:-2], pose.shape),
            "q": (q.shape[:-1], q.shape),
        }
        if q_arm is not None:
            if self._arm is None:
                raise ValueError("q_arm was given but this robot has no arm")
            q_arm = as_real(q_arm, "q_arm", np.float64)
            leads["q_arm"] = (check_trailing(q_arm, "q_arm", (6,)), q_arm.shape)
        lead = broadcast_lead(**leads)
        T = np.broadcast_to(T, (*lead, 4, 4))
        q = np.broadcast_to(q, (*lead, 3 * n_legs))
        R, t = T[..., :3, :3], T[..., :3, 3]

        def world(p):
            return t[..., None, :] + np.einsum("...ij,...kj->...ki", R, p)

        hips = np.broadcast_to(self._hips, (*lead, n_legs, 3))
        knees, feet = np.empty((*lead, n_legs, 3)), np.empty((*lead, n_legs, 3))
        for i, leg in enumerate(self._legs):
            q_leg = q[..., self._columns[i]]
            knees[..., i, :] = self._hips[i] + leg.knee(q_leg)
            feet[..., i, :] = self._hips[i] + leg.fk(q_leg)
        hand = None if q_arm is None else T @ self.arm_mount @ self._arm.fk(q_arm)
        return BodyFrames(T.copy(), world(hips), world(knees), world(feet), hand)

    @quiet_float_errors
    def arm_ik_world(
        self, body_pose: ArrayLike, T_world: ArrayLike, seed: ArrayLike | None = None, seq: str = "XYZ"
    ) -> tuple[np.ndarray, np.ndarray | Status]:
        """Arm IK for hand targets given in the world frame: (q (..., 6), status).

        T_base = (T_world_body . arm_mount)^-1 T_world, the target in the frame of :attr:`arm`, then the
        arm's closed-form IK (one solution, nearest to ``seed`` or the first valid). ``T_world`` is
        (..., 4, 4) and ``seed`` (..., 6); leading dimensions of body poses, targets and seeds
        broadcast together (``ValueError`` naming them otherwise). A body pose with NaN/Inf or
        that is not a rigid transform (as :meth:`body_fk` reads it) gives INVALID_INPUT for that
        sample, like a bad target. q is float32 when ``body_pose`` and ``T_world`` both are,
        float64 otherwise.
        """
        if self._arm is None:
            raise ValueError("this robot has no arm")
        T_wb, pose = self._world_from_body(body_pose, seq)
        target = as_real(T_world, "T_world")
        leads = {
            "body_pose": (T_wb.shape[:-2], pose.shape),
            "T_world": (check_trailing(target, "T_world", (4, 4)), target.shape),
        }
        if seed is not None:
            seed = as_real(seed, "seed")
            leads["seed"] = (check_trailing(seed, "seed", (6,)), seed.shape)
        lead = broadcast_lead(**leads)
        T_world64 = target.astype(np.float64, copy=False)
        # world <- arm base = world <- body . body <- arm base (arm_mount)
        mount = self.arm_mount
        R = T_wb[..., :3, :3] @ mount[:3, :3]
        t = T_wb[..., :3, 3] + np.einsum("...ij,j->...i", T_wb[..., :3, :3], mount[:3, 3])
        # the blocks apart, R^T R_w and R^T (p_w - t), so that the target's last row (checked by
        # the arm as it is given) never mixes into them: a far body times a last row within
        # tolerance of [0, 0, 0, 1] would otherwise tilt the rotation
        lead_shape = np.broadcast_shapes(T_wb.shape[:-2], T_world64.shape[:-2])
        T_body = np.empty((*lead_shape, 4, 4))
        T_body[..., :3, :3] = np.einsum("...ji,...jk->...ik", R, T_world64[..., :3, :3])
        T_body[..., :3, 3] = np.einsum("...ji,...j->...i", R, T_world64[..., :3, 3] - t)
        T_body[..., 3, :] = T_world64[..., 3, :]  # the caller's last row, so a bad one is still reported
        T_body = np.broadcast_to(T_body, (*lead, 4, 4)).astype(real_dtype(pose, target))
        if seed is not None:
            seed = _broadcast_to_lead(seed, 1, lead)
        return self._arm_ik(T_body, seed)

    def _arm_ik(self, T_body, seed):
        return self._arm.ik(T_body, seed)

    def _q_widths(self) -> tuple[int, ...]:
        """The widths a whole-body q may have: the legs' joints, or the legs' then the arm's."""
        legs, arm = 3 * len(self._legs), len(self.arm_joint_names)
        return (legs, legs + arm) if arm else (legs,)

    def _leg_q(self, q: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray | None]:
        """(q_legs, q_arm or None) of a whole-body q (..., 3 n) or (..., 3 n + n_arm): the one width rule
        of every whole-body call. ValueError naming ``name`` for another width."""
        if q.ndim and q.shape[-1] == 3 * len(self._legs):  # the common case, first
            return q, None
        widths = self._q_widths()
        if q.ndim == 0 or q.shape[-1] not in widths:
            expected = " or ".join(f"(..., {w})" for w in widths)
            what = "the legs' joints" + (", or the legs' then the arm's" if len(widths) > 1 else "")
            raise ValueError(f"{name} must have shape {expected} ({what}), got {q.shape}")
        if q.shape[-1] == widths[0]:
            return q, None
        return q[..., : widths[0]], q[..., widths[0] :]

    def _world_from_body(self, body_pose, seq) -> tuple[np.ndarray, np.ndarray]:
        """(T, pose): world <- body transforms (..., 4, 4) in float64, NaN for every pose the
        core rejects (body_transform checks them as the core does), and ``body_pose`` as an array."""
        pose = as_real(body_pose, "body_pose")
        return body_transform(pose, seq), pose
