"""Cartesian paths: straight segments with slerp, joined by parabolic blends
(:class:`~spotkin.trajectory.CartesianPath`), and the pose forms they read. Part of
:mod:`spotkin.trajectory` (documented there)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_real, rotation_tolerance
from ..model.body import unchecked_transform
from .joint_paths import _choice, _flag

_FORMS = {"matrix": 0, "quaternion": 1}
_HALF_TURN_TOL = 1e-12
_REPEAT_TOL = 1e-12  # rad: a waypoint at the previous position and within this rotation of it is a repeat
# ---- Cartesian paths ---------------------------------------------------------------------------


def _pose_matrices(poses: np.ndarray, name, dtypes=(np.float64,)) -> np.ndarray:
    """Checked rigid transforms (N, 4, 4) of N poses (N, 4, 4), (N, 7) or (N, 6) (float64, shape
    already checked); ``name(i)`` names pose i in the errors. ``dtypes``, one or one per pose, is the
    dtype each was given in: a float32 rotation is checked to float32 precision
    (:func:`rotation_tolerance`) and then replaced by the nearest rotation."""
    flat = poses.reshape(len(poses), -1)
    bad = np.flatnonzero(~np.isfinite(flat).all(axis=1))
    if bad.size:
        raise ValueError(f"{name(bad[0])} must be finite (no NaN or inf)")
    if poses.shape[1:] == (7,):
        scale = np.abs(poses[:, 3:]).max(axis=1)
        bad = np.flatnonzero(~(scale > 0))
        if bad.size:
            raise ValueError(f"{name(bad[0])} has a zero quaternion")
        # |q| in [1, 2] after scaling: s = 2 / |q|^2 neither overflows nor underflows
        poses = np.concatenate([poses[:, :3], poses[:, 3:] / scale[:, None]], axis=1)
    T = unchecked_transform(poses)  # checked here: quaternions are normalised above
    if poses.shape[1:] == (4, 4):
        R = T[:, :3, :3]
        tolerance = np.broadcast_to([rotation_tolerance(dtype) for dtype in dtypes], len(R))
        with np.errstate(over="ignore", invalid="ignore"):  # huge entries: not orthonormal
            gram_error = np.abs(np.einsum("nki,nkj->nij", R, R) - np.eye(3))
            # np.allclose(atol=tolerance): 1e-9 in float64
            orthonormal = (gram_error <= tolerance[:, None, None] + 1e-5 * np.eye(3)).all(axis=(1, 2))
            det = np.einsum("ni,ni->n", R[:, 0], np.cross(R[:, 1], R[:, 2]))
        rigid = orthonormal & (det > 0) & (poses[:, 3] == [0.0, 0.0, 0.0, 1.0]).all(axis=1)
        bad = np.flatnonzero(~rigid)
        if bad.size:
            raise ValueError(
                f"{name(bad[0])} must be a rigid transform (orthonormal rotation, last row [0, 0, 0, 1])"
            )
        rounded = tolerance > 1e-9
        if rounded.any():  # float32 rotations: the nearest rotation, without the float32 rounding
            U, _, Vt = np.linalg.svd(R[rounded])
            T[rounded, :3, :3] = U @ Vt
    return T


def _norm(u: np.ndarray) -> np.ndarray:
    """|u| of 3-vectors along the last axis, without overflow (hypot) for huge components."""
    return np.hypot(np.hypot(u[..., 0], u[..., 1]), u[..., 2])


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products of quaternions [x, y, z, w] along the last axis."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def _relative_rotations(quats: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World rotation vectors phi_k with R_{k+1} = exp(phi_k) R_k, each the shortest way, and the
    quaternions re-signed along the chain so that q_{k+1} = exp(phi_k) * q_k.

    The relative quaternion r_k = q_{k+1} q_k^-1 is taken with w >= 0; a half turn (|w| <= 1e-12)
    is ambiguous and is taken about the axis whose largest-magnitude component is positive. Flipping
    r_k flips q_{k+1}, and so every later quaternion: the signs are a cumulative product.
    """
    r = _quat_mul(quats[1:], quats[:-1] * [-1.0, -1.0, -1.0, 1.0])
    v, w = r[:, :3], r[:, 3]
    lead = v[np.arange(len(v)), np.argmax(np.abs(v), axis=1)]
    flip = np.where(np.abs(w) <= _HALF_TURN_TOL, lead < 0, w < 0)
    sign = np.where(flip, -1.0, 1.0)
    v, w = v * sign[:, None], w * sign
    s = np.linalg.norm(v, axis=1)
    scale = np.divide(2 * np.arctan2(s, w), s, out=np.zeros_like(s), where=s > 0)
    signs = np.concatenate([[1.0], np.cumprod(sign)])
    return v * scale[:, None], quats * signs[:, None]


class CartesianPath:
    """A Cartesian path through waypoints; build it with :func:`linear` or :func:`via_points`.

    The path passes waypoint k (position P_k, rotation R_k) at time ``times[k]``; between
    blends it moves at constant linear velocity ``linear_velocity[k]`` and constant world
    angular velocity ``angular_velocity[k]``: p = P_k + v_k (t - t_k), R = exp(w_k (t - t_k)) R_k.
    Around waypoint k a blend of duration ``blends[k]`` centred on t_k changes the velocity at
    a constant rate from (v_{k-1}, w_{k-1}) to (v_k, w_k) (zero outside the path):
    with u = t - t_k + b_k / 2, f2 = u^2 / (2 b_k), f1 = t - t_k - f2,
    p = P_k + v_{k-1} f1 + v_k f2 and R = exp(w_{k-1} f1) exp(w_k f2) R_k.
    The path starts exactly at the first pose and stops exactly at the last; interior
    waypoints are passed near, not through (see :func:`via_points`). Pickles and copies.
    """

    def __init__(
        self,
        waypoints: np.ndarray,
        times: np.ndarray,
        blends: np.ndarray,
        quaternions: np.ndarray,
        linear_velocity: np.ndarray,
        angular_velocity: np.ndarray,
    ):
        # the plan's arrays, as linear / via_points build them; checked, since the class is public
        waypoints = as_real(waypoints, "waypoints", np.float64)
        if waypoints.ndim != 3 or waypoints.shape[1:] != (4, 4) or len(waypoints) < 1:
            raise ValueError(f"waypoints must have shape (K, 4, 4) with K >= 1, got {waypoints.shape}")
        count = len(waypoints)
        arrays = {}
        for name, value, shape in (
            ("times", times, (count,)),
            ("blends", blends, (count,)),
            ("quaternions", quaternions, (count, 4)),
            ("linear_velocity", linear_velocity, (count - 1, 3)),
            ("angular_velocity", angular_velocity, (count - 1, 3)),
        ):
            array = as_real(value, name, np.float64)
            if array.shape != shape:
                raise ValueError(f"{name} must have shape {shape} for {count} waypoints, got {array.shape}")
            arrays[name] = array
        times, blends, quaternions = arrays["times"], arrays["blends"], arrays["quaternions"]
        linear_velocity, angular_velocity = arrays["linear_velocity"], arrays["angular_velocity"]
        self.waypoints = waypoints
        self.times = times
        self.blends = blends
        self.linear_velocity = linear_velocity
        self.angular_velocity = angular_velocity
        self._quaternions = quaternions
        self._core = _core.WaypointPath(
            times, blends, waypoints[:, :3, 3].copy(), quaternions, linear_velocity, angular_velocity
        )
        self.duration: float = self._core.duration

    def sample(self, t: ArrayLike, form: str = "matrix", twist: bool = False):
        """Poses at times t (...): ``form="matrix"`` (..., 4, 4) or ``"quaternion"`` (..., 7)
        [x, y, z, qx, qy, qz, qw], both accepted by :meth:`spotkin.Spot.body_ik`.

        With ``twist=True`` returns (poses, twist), twist (..., 6) = [v; w], the linear velocity
        and the angular velocity, both in the world frame. Times are clamped to
        [0, duration] (zero twist outside); a NaN time gives NaN. A non-string ``form`` or a
        non-bool ``twist`` raises TypeError, an unknown ``form`` ValueError.
        """
        code = _FORMS[_choice(form, "form", _FORMS)]
        return self._core.sample(t, code, _flag(twist, "twist"))

    def __reduce__(self):
        arrays = (self.times, self.blends, self._quaternions, self.linear_velocity, self.angular_velocity)
        return (CartesianPath, (self.waypoints, *arrays))

    def __repr__(self) -> str:
        return f"CartesianPath(waypoints={len(self.times)}, duration={self.duration:.6g})"
