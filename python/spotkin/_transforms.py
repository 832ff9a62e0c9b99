"""Homogeneous-transform helpers, batched over leading dimensions (float64)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["rotation_x", "rotation_y", "rotation_z", "transform", "translation"]


def _real(value: ArrayLike, name: str) -> np.ndarray:
    array = np.asarray(value)
    if array.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be a real numeric array, got dtype {array.dtype}")
    return array.astype(np.float64, copy=False)


def translation(p: ArrayLike) -> np.ndarray:
    """Pure translation: p (..., 3) -> (..., 4, 4)."""
    p = _real(p, "p")
    if p.shape[-1:] != (3,):
        raise ValueError(f"p must have shape (..., 3), got {p.shape}")
    out = np.zeros((*p.shape[:-1], 4, 4))
    out[..., :3, :3] = np.eye(3)
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out


def _rotation(angle: ArrayLike, axis: int) -> np.ndarray:
    angle = _real(angle, "angle")
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
    R = _real(R, "R")
    p = _real(p, "p")
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"R must have shape (..., 3, 3), got {R.shape}")
    if p.shape[-1:] != (3,):
        raise ValueError(f"p must have shape (..., 3), got {p.shape}")
    lead = np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    out = np.zeros((*lead, 4, 4))
    out[..., :3, :3] = R
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out
