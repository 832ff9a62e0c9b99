"""Homogeneous-transform helpers, batched over leading dimensions (float64).

Inputs go through the library's numpy boundary: non-numeric or masked input raises
``TypeError``, a wrong shape ``ValueError`` naming the argument.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .boundary import as_real, broadcast_lead, check_trailing, quiet_float_errors

__all__ = ["quaternion_xyzw", "rotation_x", "rotation_y", "rotation_z", "transform", "translation"]


def translation(p: ArrayLike) -> np.ndarray:
    """Pure translation: p (..., 3) -> (..., 4, 4)."""
    p = as_real(p, "p", np.float64)
    out = np.zeros((*check_trailing(p, "p", (3,)), 4, 4))
    out[..., :3, :3] = np.eye(3)
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out


@quiet_float_errors
def _rotation(angle: ArrayLike, axis: int) -> np.ndarray:
    angle = as_real(angle, "angle", np.float64)
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]  # R e_i = c e_i + s e_j, R e_j = -s e_i + c e_j
    out = np.zeros((*angle.shape, 4, 4))
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., j, i] = s
    out[..., i, j] = -s
    out[..., 3, 3] = 1.0
    return out


def rotation_x(angle: ArrayLike) -> np.ndarray:
    """Rotation about x by angle (rad): (...,) -> (..., 4, 4)."""
    return _rotation(angle, 0)


def rotation_y(angle: ArrayLike) -> np.ndarray:
    """Rotation about y by angle (rad): (...,) -> (..., 4, 4)."""
    return _rotation(angle, 1)


def rotation_z(angle: ArrayLike) -> np.ndarray:
    """Rotation about z by angle (rad): (...,) -> (..., 4, 4)."""
    return _rotation(angle, 2)


def transform(R: ArrayLike, p: ArrayLike) -> np.ndarray:
    """Homogeneous transform from a rotation R (..., 3, 3) and a translation p (..., 3).

    Leading dimensions broadcast. R is used as given: it is not checked or
    orthonormalised.
    """
    R = as_real(R, "R", np.float64)
    p = as_real(p, "p", np.float64)
    R_lead, p_lead = check_trailing(R, "R", (3, 3)), check_trailing(p, "p", (3,))
    lead = broadcast_lead(R=(R_lead, R.shape), p=(p_lead, p.shape))
    out = np.zeros((*lead, 4, 4))
    out[..., :3, :3] = R
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out


@quiet_float_errors
def quaternion_xyzw(R: np.ndarray) -> np.ndarray:
    """Unit quaternions [x, y, z, w] (w >= 0) of rotation matrices (..., 3, 3), float64, branch-free over
    the batch (Shepperd: row k of K = 4 q_k q, taken for the largest of x, y, z, w, is well conditioned);
    NaN where R is NaN. The one conversion the package uses (the floating base's q, the trajectories,
    the Spot SDK's (w, x, y, z): reorder the columns)."""
    t = np.stack(
        [
            1.0 + R[..., 0, 0] - R[..., 1, 1] - R[..., 2, 2],
            1.0 - R[..., 0, 0] + R[..., 1, 1] - R[..., 2, 2],
            1.0 - R[..., 0, 0] - R[..., 1, 1] + R[..., 2, 2],
            1.0 + R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2],
        ],
        axis=-1,
    )  # 4 x^2, 4 y^2, 4 z^2, 4 w^2
    pick = np.argmax(np.where(np.isnan(t), -np.inf, t), axis=-1)
    d = {
        "xy": R[..., 0, 1] + R[..., 1, 0],
        "xz": R[..., 0, 2] + R[..., 2, 0],
        "yz": R[..., 1, 2] + R[..., 2, 1],
        "wx": R[..., 2, 1] - R[..., 1, 2],
        "wy": R[..., 0, 2] - R[..., 2, 0],
        "wz": R[..., 1, 0] - R[..., 0, 1],
    }
    rows = np.stack(
        [
            np.stack([t[..., 0], d["xy"], d["xz"], d["wx"]], axis=-1),
            np.stack([d["xy"], t[..., 1], d["yz"], d["wy"]], axis=-1),
            np.stack([d["xz"], d["yz"], t[..., 2], d["wz"]], axis=-1),
            np.stack([d["wx"], d["wy"], d["wz"], t[..., 3]], axis=-1),
        ],
        axis=-2,
    )  # row k: 4 q_k q
    quat = np.take_along_axis(rows, pick[..., None, None], axis=-2)[..., 0, :]
    quat = quat / np.linalg.norm(quat, axis=-1, keepdims=True)  # quietly: NaN or Inf input gives NaN
    return np.where(quat[..., 3:4] < 0.0, -quat, quat)
