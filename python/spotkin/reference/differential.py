"""Reference differential IK: one matrix at a time, straight from the formulas.

Slow and obvious on purpose; the tests compare spotkin's C++ results against these.
"""

from __future__ import annotations

import math

import numpy as np


def dls(J: np.ndarray, dx: np.ndarray, damping: float, z: np.ndarray | None = None) -> np.ndarray:
    """dq = J^T (J J^T + damping^2 I)^-1 dx  [+ (I - J^+ J) z]   (damping = 0: J^+ dx).

    For m > n the same vector as (J^T J + damping^2 I)^-1 J^T dx, since
    (J^T J + l^2 I) J^T = J^T (J J^T + l^2 I); the n x n system is the well-conditioned one.
    """
    J = np.asarray(J, dtype=np.float64)
    dx = np.asarray(dx, dtype=np.float64)
    m, n = J.shape
    if damping**2 <= np.finfo(np.float64).eps * float(np.sum(J * J)):
        damping = 0.0  # below the rounding of J J^T: numerically zero, the limit J^+ dx
    if damping > 0 and m <= n:
        dq = J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(m), dx)
    elif damping > 0:
        dq = np.linalg.solve(J.T @ J + damping**2 * np.eye(n), J.T @ dx)
    else:
        dq = pinv(J) @ dx
    if z is not None:
        dq = dq + nullspace_projector(J) @ np.asarray(z, dtype=np.float64)
    return dq


def singular_values(J: np.ndarray) -> np.ndarray:
    return np.linalg.svd(np.asarray(J, dtype=np.float64), compute_uv=False)


def default_tolerance(J: np.ndarray, eps: float = np.finfo(np.float64).eps) -> float:
    """max(m, n) * eps * sigma_max."""
    return max(J.shape) * eps * singular_values(J)[0]


def rank(J: np.ndarray, tol: float | None = None) -> int:
    sigma = singular_values(J)
    cutoff = default_tolerance(J) if tol is None else tol
    return int(sum(1 for s in sigma if s > cutoff))


def pinv(J: np.ndarray) -> np.ndarray:
    """J^+ = V diag(1/sigma_i for sigma_i > tol, else 0) U^T."""
    J = np.asarray(J, dtype=np.float64)
    U, sigma, Vt = np.linalg.svd(J)
    cutoff = default_tolerance(J)
    k = len(sigma)
    inverse = np.zeros((J.shape[1], J.shape[0]))
    for i in range(k):
        if sigma[i] > cutoff:
            inverse += np.outer(Vt[i], U[:, i]) / sigma[i]
    return inverse


def nullspace_projector(J: np.ndarray) -> np.ndarray:
    """I - J^+ J."""
    J = np.asarray(J, dtype=np.float64)
    return np.eye(J.shape[1]) - pinv(J) @ J


def manipulability(J: np.ndarray) -> float:
    """sqrt(det(J J^T)); 0 when m > n (J J^T is singular)."""
    J = np.asarray(J, dtype=np.float64)
    m, n = J.shape
    if m > n:
        return 0.0
    return math.sqrt(max(np.linalg.det(J @ J.T), 0.0))


def log_rotation(R: np.ndarray) -> np.ndarray:
    """Axis-angle vector theta * a of a rotation matrix (Rodrigues inverted), theta in [0, pi]."""
    c = min(max((np.trace(R) - 1) / 2, -1.0), 1.0)
    theta = math.acos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2
    if theta < 1e-8:
        return w
    if math.pi - theta > 1e-6:
        return theta / math.sin(theta) * w
    # theta = pi: R = 2 a a^T - I
    k = int(np.argmax(np.diag(R)))
    a = (R[:, k] + np.eye(3)[:, k]) / math.sqrt(2 * (1 + R[k, k]))
    return theta * a


def compatibility_residual(J: np.ndarray, dx: np.ndarray) -> float:
    """|(I - J J^+) dx|: the distance from dx to the range of J (J^+ with rank's cutoff)."""
    J = np.asarray(J, dtype=np.float64)
    dx = np.asarray(dx, dtype=np.float64)
    return float(np.linalg.norm(dx - J @ (pinv(J) @ dx)))


def compatible(
    J: np.ndarray, dx: np.ndarray, tol: float | None = None, eps: float = np.finfo(np.float64).eps
):
    """(residual <= tol, residual); tol by default max(m, n) eps (|dx| + sigma_max |J^+ dx|)."""
    J = np.asarray(J, dtype=np.float64)
    dx = np.asarray(dx, dtype=np.float64)
    residual = compatibility_residual(J, dx)
    if tol is None:
        sigma_max = singular_values(J)[0]
        tol = max(J.shape) * eps * (np.linalg.norm(dx) + sigma_max * np.linalg.norm(pinv(J) @ dx))
    return residual <= tol, residual
