"""Reference body poses: the world <- body transform of one pose, in plain ``math``.

A pose is ``[x, y, z, a, b, c]`` (Euler angles in a scipy sequence: upper case intrinsic,
R = R_s0(a) R_s1(b) R_s2(c); lower case extrinsic, R = R_s2(c) R_s1(b) R_s0(a)), a 4 x 4
matrix, or ``[x, y, z, qx, qy, qz, qw]``. Checks as the core's: a matrix must have last row
[0, 0, 0, 1] (1e-9) and a rotation (max |R^T R - I| <= 1e-6, det R > 0); a quaternion a norm
of 1 within 1e-6, converted with s = 2 / |q|^2 (never renormalised); anything invalid or
non-finite gives NaN throughout.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["body_transform"]


def _elementary(axis: int, angle: float) -> list[list[float]]:
    """R_x, R_y or R_z (axis 0, 1, 2) of angle."""
    c, s = math.cos(angle), math.sin(angle)
    if axis == 0:
        return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
    if axis == 1:
        return [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def _matmul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def body_transform(pose, seq: str = "XYZ") -> np.ndarray:
    """The 4 x 4 world <- body transform of one pose (6,), (4, 4) or (7,); NaN when invalid."""
    x = np.asarray(pose, dtype=np.float64)
    nan = np.full((4, 4), np.nan)
    if not np.isfinite(x).all():
        return nan
    if x.shape == (4, 4):
        R = x[:3, :3]
        orth = np.abs(R.T @ R - np.eye(3)).max()
        row = np.abs(x[3] - [0.0, 0.0, 0.0, 1.0]).max()
        return x.copy() if orth <= 1e-6 and row <= 1e-9 and np.linalg.det(R) > 0 else nan
    T = np.eye(4)
    T[:3, 3] = x[:3]
    if x.shape == (6,):
        axes = ["xyz".index(ch.lower()) for ch in seq]
        angles = list(x[3:])
        if seq.isupper():
            factors = [_elementary(axes[k], angles[k]) for k in range(3)]
        else:
            factors = [_elementary(axes[k], angles[k]) for k in (2, 1, 0)]
        T[:3, :3] = _matmul(_matmul(factors[0], factors[1]), factors[2])
        return T
    qx, qy, qz, qw = (float(v) for v in x[3:])
    n2 = qx * qx + qy * qy + qz * qz + qw * qw
    if not abs(math.sqrt(n2) - 1.0) <= 1e-6:
        return nan
    s = 2.0 / n2
    T[:3, :3] = [
        [1 - s * (qy * qy + qz * qz), s * (qx * qy - qz * qw), s * (qx * qz + qy * qw)],
        [s * (qx * qy + qz * qw), 1 - s * (qx * qx + qz * qz), s * (qy * qz - qx * qw)],
        [s * (qx * qz - qy * qw), s * (qy * qz + qx * qw), 1 - s * (qx * qx + qy * qy)],
    ]
    return T
