"""The built-in Spot model: four legs in SDK order and the arm, from the official URDF
numbers; whole-body IK, FK and Jacobians."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._boundary import (
    as_finite,
    as_real,
    as_scalar,
    broadcast_lead,
    check_trailing,
    fallback_is_nearest,
    quiet_float_errors,
    real_dtype,
)
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


def _section(table: Mapping, key: str, where: str):
    """table[key], with a ValueError naming the missing key (``where`` names the table)."""
    if not isinstance(table, Mapping):
        raise TypeError(f"{where} must be a dict, got {type(table).__name__}")
    try:
        return table[key]
    except KeyError:
        raise ValueError(f"{where} is missing the key {key!r}") from None


def _number(table: Mapping, key: str, where: str, minimum: float = -math.inf, strict: bool = False) -> float:
    return as_finite(_section(table, key, where), f"{where}[{key!r}]", minimum, strict)


def _point(table: Mapping, key: str, where: str) -> tuple[float, ...]:
    name = f"{where}[{key!r}]"
    point = as_real(_section(table, key, where), name, np.float64)
    if point.shape != (3,) or not np.isfinite(point).all():
        raise ValueError(f"{name} must be 3 finite numbers (shape (3,)), got {point.tolist()}")
    return tuple(point.tolist())


def _limit_rows(table: Mapping, key: str, where: str, joints: int) -> tuple[tuple[float, float], ...]:
    name = f"{where}[{key!r}]"
    rows = as_real(_section(table, key, where), name, np.float64)
    if rows.shape != (joints, 2):
        raise ValueError(f"{name} must have shape ({joints}, 2) as (lower, upper) rows, got {rows.shape}")
    if np.isnan(rows).any() or (rows[:, 0] > rows[:, 1]).any():
        raise ValueError(f"{name} must satisfy lower <= upper, with no NaN, got {rows.tolist()}")
    return tuple(map(tuple, rows.tolist()))


def _checked_model(model: Mapping) -> dict:
    """A validated copy of a model dict shaped like :data:`spotkin.models.SPOT`."""
    if not isinstance(model, Mapping):
        raise TypeError(f"model must be a dict shaped like spotkin.models.SPOT, got {type(model).__name__}")
    hips = _section(model, "hip_positions", "model")
    leg = _section(model, "leg", "model")
    arm = _section(model, "arm", "model")
    where_hips, where_leg, where_arm = "model['hip_positions']", "model['leg']", "model['arm']"
    checked = {
        "hip_positions": {name: _point(hips, name, where_hips) for name in LEG_NAMES},
        "leg": {
            "hip_offset": _number(leg, "hip_offset", where_leg, 0.0),
            "upper": _number(leg, "upper", where_leg, 0.0, strict=True),
            "knee_offset": _number(leg, "knee_offset", where_leg),
            "lower": _number(leg, "lower", where_leg, 0.0, strict=True),
            "foot_radius": _number(leg, "foot_radius", where_leg, 0.0),
            "limits": _limit_rows(leg, "limits", where_leg, 3),
        },
        "arm": {
            "mount": _point(arm, "mount", where_arm),
            "upper_arm": _number(arm, "upper_arm", where_arm, 0.0, strict=True),
            "forearm": _number(arm, "forearm", where_arm),
            "forearm_offset": _number(arm, "forearm_offset", where_arm),
            "hand": _number(arm, "hand", where_arm),
            "limits": _limit_rows(arm, "limits", where_arm, 6),
        },
    }
    if checked["arm"]["forearm"] == 0.0 and checked["arm"]["forearm_offset"] == 0.0:
        raise ValueError("model['arm']['forearm'] and model['arm']['forearm_offset'] are both 0")
    if "nominal_stance" in model:
        checked["nominal_stance"] = _point(model, "nominal_stance", "model")
    return checked


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


class Spot:
    """Boston Dynamics Spot. Body frame: x forward, y left, z up, origin at the
    centre of the four hx joints. Legs in SDK order: fl, fr, hl, hr.

    ``model`` is a dict shaped like :data:`spotkin.models.SPOT` (the default): keys
    ``"hip_positions"`` (a (3,) point per leg name), ``"leg"`` (``hip_offset``,
    ``upper``, ``knee_offset``, ``lower``, ``foot_radius``, ``limits`` (3, 2)) and
    ``"arm"`` (``mount`` (3,), ``upper_arm``, ``forearm``, ``forearm_offset``, ``hand``,
    ``limits`` (6, 2)); other keys are ignored. It is checked and copied: a missing key,
    a non-finite number, ``upper``, ``lower`` or ``upper_arm`` not positive, a negative
    ``hip_offset`` or ``foot_radius``, a point not of shape (3,), or limits with NaN or
    lower > upper raise ``ValueError`` naming the key; a non-dict or non-numeric value
    raises ``TypeError``.
    """

    __slots__ = ("_arm", "_body_core", "_hips", "_legs", "_model")

    leg_names = LEG_NAMES
    """The legs in SDK order: ("fl", "fr", "hl", "hr") (h: hind)."""
    joint_names = tuple(f"{leg}.{joint}" for leg in LEG_NAMES for joint in ("hx", "hy", "kn"))
    """The 12 leg joints in SDK order, the order of ``q12``: "fl.hx", "fl.hy", "fl.kn", "fr.hx", ...,
    "hr.kn"."""
    arm_joint_names = ("arm0.sh0", "arm0.sh1", "arm0.el0", "arm0.el1", "arm0.wr0", "arm0.wr1")
    """The 6 arm joints in SDK order, the order of ``q_arm``."""

    def __init__(self, model: Mapping | None = None) -> None:
        self._model = SPOT if model is None else _checked_model(model)
        self._hips = np.array([self._model["hip_positions"][name] for name in LEG_NAMES], dtype=np.float64)
        self._hips.flags.writeable = False
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
        self._body_core = _core.Body([leg._core for leg in self._legs], self._hips)
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
        return self._hips.copy()

    # -- whole body -----------------------------------------------------------------------------------

    def stance_feet(self, height: float = 0.5) -> np.ndarray:
        """(4, 3) world foot centres of a nominal stance, for the body at [0, 0, height, 0, 0, 0].

        Each foot is straight below its hy joint (hx = 0) with the foot sphere resting on
        the ground z = 0, so its centre is at z = foot_radius.
        """
        height = as_scalar(height, "height")
        feet = self.hip_positions
        feet[:, 1] += [leg.hip_offset for leg in self._legs]
        feet[:, 2] = self._model["leg"]["foot_radius"]
        if not 0.0 < height - feet[0, 2] <= self._legs[0].reach[1]:
            raise ValueError(f"height {height} m puts the feet out of reach")
        return feet

    def body_ik(
        self,
        body_pose: ArrayLike,
        feet: ArrayLike,
        seed: ArrayLike | None = None,
        seq: str = "XYZ",
        fallback: str = "nearest",
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
        sample only. ``fallback`` is the UNREACHABLE legs' answer, as in :meth:`Leg.ik`:
        ``"nearest"`` (in the limits, stretched or folded toward the foot) or ``"nan"``.
        Computed in float32 when ``body_pose`` and ``feet`` both are float32, else float64;
        ``seed`` takes that dtype.
        """
        if (
            seed is None
            and seq == "XYZ"
            and fallback == "nearest"
            and type(feet) is np.ndarray
            and feet.shape == (4, 3)
        ):
            # the control-loop call, one shared stance: the core checks body_pose itself
            return BodyIK._make(self._body_core.ik(body_pose, -1, _XYZ, feet, None))
        nearest = fallback_is_nearest(fallback)
        pose = as_real(body_pose, "body_pose")
        fmt, pose_lead = pose_format(pose)
        code = sequence_code(seq)
        feet = as_real(feet, "feet")
        feet_lead = check_trailing(feet, "feet", (4, 3))
        if seed is not None:
            seed = as_real(seed, "seed")
            seed_lead = check_trailing(seed, "seed", (12,))
        # nothing to broadcast for a shared stance or one stance per pose, and one seed per pose
        if (feet_lead and feet_lead != pose_lead) or (seed is not None and seed_lead != pose_lead):
            leads = {"body_pose": (pose_lead, pose.shape), "feet": (feet_lead, feet.shape)}
            if seed is not None:
                leads["seed"] = (seed_lead, seed.shape)
            lead = broadcast_lead(**leads)
            if feet_lead and feet_lead != lead:  # a single stance is shared without copying
                feet = feet.reshape(4, 3) if feet.size == 12 else np.broadcast_to(feet, (*lead, 4, 3))
            pose = _broadcast_to_lead(pose, pose.ndim - len(pose_lead), lead)
            if seed is not None:
                seed = _broadcast_to_lead(seed, 1, lead)
        return BodyIK(*self._body_core.ik(pose, fmt, code, feet, seed, nearest))

    def body_fk(self, body_pose: ArrayLike, q12: ArrayLike, seq: str = "XYZ") -> np.ndarray:
        """(..., 4, 3) world foot centres: foot = t + R (hip + leg.fk(q)). Leading dimensions broadcast.

        float32 when ``body_pose`` and ``q12`` both are float32, else float64. A leg with a
        NaN or Inf joint gets a NaN foot; an invalid body pose NaN feet for its sample."""
        pose, q12, fmt, code = self._pose_and_q(body_pose, q12, seq)
        return self._body_core.fk(pose, fmt, code, q12)

    def body_jacobian(self, body_pose: ArrayLike, q12: ArrayLike, seq: str = "XYZ") -> np.ndarray:
        """(..., 12, 18) d(feet world) / d(body twist [v; w], q12).

        The twist is the linear velocity of the body origin and the angular velocity,
        both in the world frame: d foot_i = v + w x (foot_i - t) + R J_leg_i dq_i.
        """
        pose, q12, fmt, code = self._pose_and_q(body_pose, q12, seq)
        return self._body_core.jacobian(pose, fmt, code, q12)

    @quiet_float_errors
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
        J_leg dq = -R^T (v + w x (foot - t)). Leading dimensions of ``body_pose``, ``q12``
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
        T, pose = self._world_from_body(body_pose, seq)
        q12 = as_real(q12, "q12", np.float64)
        twist = as_real(twist, "twist", np.float64)
        lead = broadcast_lead(
            body_pose=(T.shape[:-2], pose.shape),
            q12=(check_trailing(q12, "q12", (12,)), q12.shape),
            twist=(check_trailing(twist, "twist", (6,)), twist.shape),
        )
        n = math.prod(lead)
        R = np.broadcast_to(T[..., :3, :3], (*lead, 3, 3)).reshape(n, 3, 3)
        q = np.broadcast_to(q12, (*lead, 12)).reshape(n, 4, 3)
        twist = np.broadcast_to(twist, (*lead, 6)).reshape(n, 6)
        v, w = twist[:, :3], twist[:, 3:]
        qd = np.full((n, 4, 3), np.nan)
        singular = np.ones((n, 4), dtype=bool)
        for i, leg in enumerate(self._legs):
            q_leg = q[:, i]
            r = np.einsum("nij,nj->ni", R, self._hips[i] + leg.fk(q_leg))
            rhs = -np.einsum("nji,nj->ni", R, v + np.cross(w, r))
            J = leg.jacobian(q_leg)
            sigma = leg.singularity(q_leg)[1]
            # the finiteness checks do not rely on sigma, which NaN input need not make NaN
            finite_input = np.isfinite(J).all((1, 2)) & np.isfinite(rhs).all(1)
            usable = np.flatnonzero((sigma > tolerance) & finite_input)
            solved = _solve_rows(J[usable], rhs[usable])
            finite = np.isfinite(solved).all(1)
            qd[usable[finite], i] = solved[finite]
            singular[usable[finite], i] = False
        return BodyRates(qd.reshape(*lead, 12), singular.reshape(*lead, 4))

    @quiet_float_errors
    def arm_ik_world(
        self, body_pose: ArrayLike, T_world: ArrayLike, seed: ArrayLike | None = None, seq: str = "XYZ"
    ):
        """Arm IK for hand targets given in the world frame: (q (..., 6), status).

        T_body = T_world_body^-1 T_world, then :meth:`SpotArm.ik`. ``T_world`` is (..., 4, 4)
        and ``seed`` (..., 6); leading dimensions of body poses, targets and seeds broadcast
        together (``ValueError`` naming them otherwise). A body pose with NaN/Inf or that
        is not a rigid transform (as :meth:`body_fk` reads it) gives INVALID_INPUT for
        that sample, like a bad target. q is float32 when ``body_pose`` and ``T_world``
        both are, float64 otherwise.
        """
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
        R, t = T_wb[..., :3, :3], T_wb[..., :3, 3]
        T_bw = np.zeros_like(T_wb)
        T_bw[..., :3, :3] = np.swapaxes(R, -1, -2)
        T_bw[..., :3, 3] = -np.einsum("...ji,...j->...i", R, t)
        T_bw[..., 3, 3] = 1.0
        T_body = T_bw @ T_world64
        T_body[..., 3, :] = T_world64[..., 3, :]  # keep the caller's last row, so a bad one is still reported
        T_body = np.broadcast_to(T_body, (*lead, 4, 4)).astype(real_dtype(pose, target))
        if seed is not None:
            seed = _broadcast_to_lead(seed, 1, lead)
        return self._arm.ik(T_body, seed=seed)

    @quiet_float_errors
    def fk_all(
        self, body_pose: ArrayLike, q12: ArrayLike, q_arm: ArrayLike | None = None, seq: str = "XYZ"
    ) -> BodyFrames:
        """Every frame of interest in the world frame: body, hips, knees, feet, and the hand.

        Checked as :meth:`body_fk`: ``body_pose`` in any accepted form, ``q12`` (..., 12)
        and ``q_arm`` (..., 6) real arrays whose leading dimensions broadcast (``TypeError``
        for non-numeric input such as None, ``ValueError`` naming the argument for another
        shape). A body pose with NaN or Inf, or that is not a rigid transform (a 4x4 whose
        rotation part is not a rotation or whose last row is not [0, 0, 0, 1], a non-unit
        quaternion), gives NaN frames for that sample only, as :meth:`body_fk` gives NaN
        feet. Every frame is float64.
        """
        T, pose = self._world_from_body(body_pose, seq)
        q12 = as_real(q12, "q12", np.float64)
        leads = {
            "body_pose": (T.shape[:-2], pose.shape),
            "q12": (check_trailing(q12, "q12", (12,)), q12.shape),
        }
        if q_arm is not None:
            q_arm = as_real(q_arm, "q_arm", np.float64)
            leads["q_arm"] = (check_trailing(q_arm, "q_arm", (6,)), q_arm.shape)
        lead = broadcast_lead(**leads)
        T = np.broadcast_to(T, (*lead, 4, 4))
        q = np.broadcast_to(q12, (*lead, 12)).reshape(*lead, 4, 3)
        R, t = T[..., :3, :3], T[..., :3, 3]

        def world(p):
            return t[..., None, :] + np.einsum("...ij,...kj->...ki", R, p)

        hips = np.broadcast_to(self._hips, (*lead, 4, 3))
        knees, feet = np.empty((*lead, 4, 3)), np.empty((*lead, 4, 3))
        for i, leg in enumerate(self._legs):
            hx, hy = q[..., i, 0], q[..., i, 1]
            # knee = Rx(hx) ([0, h1, 0] + Ry(hy) [k, 0, -upper]) in the leg frame
            kx = leg.knee_offset * np.cos(hy) - leg.upper * np.sin(hy)
            kz = -leg.knee_offset * np.sin(hy) - leg.upper * np.cos(hy)
            knees[..., i, :] = self._hips[i] + np.stack(
                [
                    kx,
                    leg.hip_offset * np.cos(hx) - kz * np.sin(hx),
                    leg.hip_offset * np.sin(hx) + kz * np.cos(hx),
                ],
                -1,
            )
            feet[..., i, :] = self._hips[i] + leg.fk(q[..., i, :])
        hand = None if q_arm is None else T @ self._arm.fk(q_arm)
        return BodyFrames(T.copy(), world(hips), world(knees), world(feet), hand)

    def _pose_and_q(self, body_pose, q12, seq):
        pose = as_real(body_pose, "body_pose")
        fmt, pose_lead = pose_format(pose)
        code = sequence_code(seq)
        q12 = as_real(q12, "q12")
        q_lead = check_trailing(q12, "q12", (12,))
        if q_lead != pose_lead:
            lead = broadcast_lead(body_pose=(pose_lead, pose.shape), q12=(q_lead, q12.shape))
            pose = _broadcast_to_lead(pose, pose.ndim - len(pose_lead), lead)
            q12 = _broadcast_to_lead(q12, 1, lead)
        return pose, q12, fmt, code

    def _world_from_body(self, body_pose, seq) -> tuple[np.ndarray, np.ndarray]:
        """(T, pose): world <- body transforms (..., 4, 4) in float64, NaN for every pose the
        core rejects (body_transform checks them as the core does), and ``body_pose`` as an array."""
        pose = as_real(body_pose, "body_pose")
        return body_transform(pose, seq), pose

    def __reduce__(self):
        return (Spot, (None if self._model is SPOT else self._model,))

    def __repr__(self) -> str:
        return "Spot()"
