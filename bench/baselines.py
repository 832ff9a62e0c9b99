"""NumPy-vectorised baselines: the same work as spotkin, vectorised over samples."""

from __future__ import annotations

import numpy as np


def _rot_x_trans_x(alpha: float, a: float) -> np.ndarray:
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[1, 0, 0, a], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rot_z_trans_z(theta: np.ndarray, r: np.ndarray) -> np.ndarray:
    n = theta.shape[0]
    T = np.zeros((n, 4, 4))
    c, s = np.cos(theta), np.sin(theta)
    T[:, 0, 0] = c
    T[:, 0, 1] = -s
    T[:, 1, 0] = s
    T[:, 1, 1] = c
    T[:, 2, 2] = 1
    T[:, 2, 3] = r
    T[:, 3, 3] = 1
    return T


def mdh_frames(rows: np.ndarray, q: np.ndarray, tool: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Joint axis frames (after RotX TransX) and the tool transform, DHm, (N, 4, 4) each."""
    n = q.shape[0]
    T = np.broadcast_to(np.eye(4), (n, 4, 4))
    axis_frames = []
    for j, (sigma, d, alpha, r, theta) in enumerate(rows):
        T = T @ _rot_x_trans_x(alpha, d)
        axis_frames.append(T)
        qj = q[:, j]
        T = T @ (
            _rot_z_trans_z(theta + qj, np.full(n, r))
            if sigma == 0
            else _rot_z_trans_z(np.full(n, theta), r + qj)
        )
    return axis_frames, T @ tool


def mdh_fk(rows: np.ndarray, q: np.ndarray, tool: np.ndarray) -> np.ndarray:
    return mdh_frames(rows, q, tool)[1]


def mdh_jacobian(rows: np.ndarray, q: np.ndarray, tool: np.ndarray) -> np.ndarray:
    axis_frames, T = mdh_frames(rows, q, tool)
    p = T[:, :3, 3]
    J = np.zeros((q.shape[0], 6, len(rows)))
    for j, F in enumerate(axis_frames):
        z = F[:, :3, 2]
        if rows[j][0] == 0:
            J[:, :3, j] = np.cross(z, p - F[:, :3, 3])
            J[:, 3:, j] = z
        else:
            J[:, :3, j] = z
    return J
