"""Featherstone's spatial algebra for the reference dynamics (:mod:`spotkin.reference.dynamics`): motion
and force cross products, Plücker transforms, spatial inertias, joint motions; plain NumPy."""

from __future__ import annotations

import math

import numpy as np

# --------------------------------------------------------------------------- spatial algebra


def skew(p) -> np.ndarray:
    """[p]x, so that skew(p) @ x = p x x."""
    x, y, z = (float(v) for v in p)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def motion_transform(T) -> np.ndarray:
    """The 6x6 map of motion vectors from frame B's coordinates to frame A's, for T = pose of B in A:
    [v_A; w_A] = [[R, [p]x R], [0, R]] [v_B; w_B] (RBDA eq. 2.24, linear-first order)."""
    R, p = T[:3, :3], T[:3, 3]
    X = np.zeros((6, 6))
    X[:3, :3] = R
    X[:3, 3:] = skew(p) @ R
    X[3:, 3:] = R
    return X


def inverse_transform(T) -> np.ndarray:
    R, p = T[:3, :3], T[:3, 3]
    inverse = np.eye(4)
    inverse[:3, :3] = R.T
    inverse[:3, 3] = -R.T @ p
    return inverse


def crm(v) -> np.ndarray:
    """Motion cross product v x (RBDA eq. 2.31): [[w x, v x], [0, w x]]."""
    X = np.zeros((6, 6))
    X[:3, :3] = skew(v[3:])
    X[:3, 3:] = skew(v[:3])
    X[3:, 3:] = skew(v[3:])
    return X


def crf(v) -> np.ndarray:
    """Force cross product v x* = -crm(v)^T (RBDA eq. 2.32)."""
    return -crm(v).T


def spatial_inertia(mass: float, com, inertia) -> np.ndarray:
    """The 6x6 spatial inertia about the frame origin (RBDA eq. 2.63, linear first):
    [[m E, -m [c]x], [m [c]x, I_c - m [c]x [c]x]]."""
    C = skew(com)
    M = np.zeros((6, 6))
    M[:3, :3] = mass * np.eye(3)
    M[:3, 3:] = -mass * C
    M[3:, :3] = mass * C
    M[3:, 3:] = np.asarray(inertia) - mass * C @ C
    return M


def joint_motion(axis, joint_type: int, q: float) -> np.ndarray:
    """M_j(q): rotation about (type 0) or translation along (type 1) the unit axis."""
    T = np.eye(4)
    x, y, z = (float(v) for v in axis)
    if joint_type == 1:
        T[:3, 3] = (x * q, y * q, z * q)
        return T
    c, s = math.cos(q), math.sin(q)
    v = 1.0 - c
    T[:3, :3] = (
        (c + x * x * v, x * y * v - z * s, x * z * v + y * s),
        (y * x * v + z * s, c + y * y * v, y * z * v - x * s),
        (z * x * v - y * s, z * y * v + x * s, c + z * z * v),
    )
    return T


def motion_subspace(axis, joint_type: int) -> np.ndarray:
    """S_j in body j's coordinates: [0; a] for a revolute joint, [a; 0] for a prismatic one."""
    S = np.zeros(6)
    if joint_type == 1:
        S[:3] = axis
    else:
        S[3:] = axis
    return S
