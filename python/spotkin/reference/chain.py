"""Reference serial-chain kinematics from DH tables, one sample at a time.

Elementary transforms (the course's summary sheet §1.3):
  DHm  T(j-1,j) = RotX(alpha) · TransX(d) · RotZ(theta) · TransZ(r)
  DH   T(j-1,j) = RotZ(theta) · TransZ(d) · TransX(a) · RotX(alpha)
Joint variable q_j adds to theta (sigma = 0) or to the z offset (sigma = 1).
"""

from __future__ import annotations

import math

import numpy as np


def rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], dtype=float)


def rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)


def trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def mdh_transform(d: float, alpha: float, r: float, theta: float) -> np.ndarray:
    """Khalil–Kleinfinger DHm: RotX(alpha) TransX(d) RotZ(theta) TransZ(r)."""
    return rot_x(alpha) @ trans(d, 0, 0) @ rot_z(theta) @ trans(0, 0, r)


def dh_transform(a: float, alpha: float, d: float, theta: float) -> np.ndarray:
    """Classic DH: RotZ(theta) TransZ(d) TransX(a) RotX(alpha)."""
    return rot_z(theta) @ trans(0, 0, d) @ trans(a, 0, 0) @ rot_x(alpha)


def joint_transform(row, convention: str, q: float) -> np.ndarray:
    sigma, length, alpha, offset, theta = (float(v) for v in row)
    if sigma == 0:
        theta += q
    else:
        offset += q
    if convention == "mdh":
        return mdh_transform(length, alpha, offset, theta)
    return dh_transform(length, alpha, offset, theta)


def frames(rows, convention: str, q, base=None, tool=None) -> list[np.ndarray]:
    """[T_base, T_01, ..., T_0n, T_tool], all in the base frame."""
    T = np.eye(4) if base is None else np.asarray(base, dtype=float)
    out = [T]
    for row, qj in zip(rows, q):
        T = T @ joint_transform(row, convention, float(qj))
        out.append(T)
    out.append(T @ (np.eye(4) if tool is None else np.asarray(tool, dtype=float)))
    return out


def fk(rows, convention: str, q, base=None, tool=None) -> np.ndarray:
    return frames(rows, convention, q, base, tool)[-1]


def jacobian(rows, convention: str, q, base=None, tool=None, frame: str = "base") -> np.ndarray:
    """Geometric Jacobian [v; w] of the tool point (the course's summary sheet).

    Column j: revolute [z_j x (p_tool - o_j); z_j], prismatic [z_j; 0]. In DHm
    joint j moves about z of frame j; in classic DH about z of frame j-1.
    """
    F = frames(rows, convention, q, base, tool)
    p_tool = F[-1][:3, 3]
    n = len(rows)
    J = np.zeros((6, n))
    for j in range(n):
        axis_frame = F[j + 1] if convention == "mdh" else F[j]
        z, o = axis_frame[:3, 2], axis_frame[:3, 3]
        if float(rows[j][0]) == 0:
            J[:3, j] = np.cross(z, p_tool - o)
            J[3:, j] = z
        else:
            J[:3, j] = z
    if frame == "tool":
        R = F[-1][:3, :3]
        J[:3] = R.T @ J[:3]
        J[3:] = R.T @ J[3:]
    return J


def point_jacobian(rows, convention: str, q, point: int, frame="base", base=None, tool=None) -> np.ndarray:
    """Preferential Jacobian J_k(j) [v; w] (6, n): the velocity of the origin O_k of frame k and the
    angular velocity of frame k, relative to the base, in frame j's axes.

    Frames as :func:`frames`: 0 the base transform, i = 1..n after joint i, n + 1 the tool;
    ``frame="base"``: the reference axes. Column i, for a joint before frame k (i + 1 <= k):
    revolute [z_i x (O_k - o_i); z_i], prismatic [z_i; 0]; zero for the joints after frame k.
    Then both blocks are rotated by R_j^T (the course's change of frame of a Jacobian).
    """
    F = frames(rows, convention, q, base, tool)
    O_k = F[point][:3, 3]
    n = len(rows)
    J = np.zeros((6, n))
    for i in range(n):
        if i + 1 > point:
            continue  # joint i moves frames i + 1 onwards, not O_k
        axis_frame = F[i + 1] if convention == "mdh" else F[i]
        z, o = axis_frame[:3, 2], axis_frame[:3, 3]
        if float(rows[i][0]) == 0:
            J[:3, i] = np.cross(z, O_k - o)
            J[3:, i] = z
        else:
            J[:3, i] = z
    if frame != "base":
        R = F[frame][:3, :3]
        J[:3] = R.T @ J[:3]
        J[3:] = R.T @ J[3:]
    return J
