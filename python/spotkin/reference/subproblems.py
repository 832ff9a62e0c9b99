"""Rotations and the Paden–Kahan subproblems the 6R reference (:mod:`spotkin.reference.ik6r`) is built
from: plain ``math`` and NumPy, one sample at a time."""

from __future__ import annotations

import cmath
import math

import numpy as np

TANGENT = 1e-9  # |C / hypot(A, B)| up to 1 + TANGENT is a (double) root, clamped
SCAN_STEPS = 1440
# ---- rotations ---------------------------------------------------------------------------------------


def rot(k, angle: float) -> np.ndarray:
    """Rodrigues: Rot(k, θ) = I + sin θ K + (1 − cos θ) K², K = [k]×, k unit."""
    x, y, z = (float(v) for v in k)
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


# ---- subproblems ----------------------------------------------------------------------------------


def sp1(p, q, k) -> float:
    """θ with Rot(k, θ) p = q (least squares when the components along k differ)."""
    return math.atan2(float(k @ np.cross(p, q)), float(p @ q - (k @ p) * (k @ q)))


def trig_coefficients(h, k, p) -> tuple[float, float, float]:
    """hᵀ Rot(k, θ) p = const + a cos θ + b sin θ: (const, a, b)."""
    along = float(k @ p)
    return float(h @ k) * along, float(h @ (p - k * along)), float(h @ np.cross(k, p))


def solve_trig(a: float, b: float, c: float) -> list[float]:
    """Roots of a cos θ + b sin θ = c: [φ + acos(c / r), φ − acos(c / r)], φ = atan2(b, a)."""
    r = math.hypot(a, b)
    if r == 0.0:
        return []
    ratio = c / r
    if abs(ratio) > 1.0 + TANGENT:
        return []
    phi, delta = math.atan2(b, a), math.acos(max(-1.0, min(1.0, ratio)))
    return [phi + delta, phi - delta]


def sp4(h, p, k, d: float) -> list[float]:
    const, a, b = trig_coefficients(h, k, p)
    return solve_trig(a, b, d - const)


def sp3(p1, p2, k, d: float) -> list[float]:
    return sp4(p2, p1, k, (p1 @ p1 + p2 @ p2 - d * d) / 2.0)


def sp2(p1, p2, k1, k2) -> list[tuple[float, float]]:
    """(θ1, θ2) pairs with Rot(k1, θ1) p1 = Rot(k2, θ2) p2."""
    return [(t1, sp1(p2, rot(k1, t1) @ p1, k2)) for t1 in sp4(k2, p1, k1, float(k2 @ p2))]


def sp6(A1: np.ndarray, A2: np.ndarray, e: np.ndarray) -> list[tuple[int, float, float]]:
    """(k, θ1, θ2) with A1 (cos θ1, sin θ1) + A2 (cos θ2, sin θ2) = e; k as in the module docstring."""
    U, s, _ = np.linalg.svd(A2)
    if s[0] == 0.0:
        raise ValueError("degenerate geometry: the second angle does not enter the equations")
    if s[1] > 1e-2 * s[0]:  # rank 2; below, rank 1 (exactly or nearly: the idealised structure)
        return [(k, t1, t2) for k, (t1, t2) in enumerate(_sp6_quartic(A1, A2, e))]
    # left null vector of A2 and its range direction, signed with their largest component positive
    # (so that the root order does not depend on the SVD's signs)
    n, m = (v if v[np.argmax(np.abs(v))] > 0 else -v for v in (U[:, 1], U[:, 0]))
    out = []
    na = n @ A1
    for i1, t1 in enumerate(solve_trig(na[0], na[1], float(n @ e))):
        rhs = e - A1 @ np.array([math.cos(t1), math.sin(t1)])
        ma = m @ A2
        for i2, t2 in enumerate(solve_trig(ma[0], ma[1], float(m @ rhs))):
            out.append((2 * i1 + i2, t1, t2))
    return out


def _sp6_quartic(A1, A2, e) -> list[tuple[float, float]]:
    V, u = np.linalg.solve(A2, A1), np.linalg.solve(A2, e)
    W, g = V.T @ V, V.T @ u
    # f(t) = |u − V x|² − 1 = k0 + k1 cos t + k2 sin t + k3 cos 2t + k4 sin 2t
    k0 = u @ u - 1.0 + (W[0, 0] + W[1, 1]) / 2.0
    k1, k2 = -2.0 * g[0], -2.0 * g[1]
    k3, k4 = (W[0, 0] - W[1, 1]) / 2.0, W[0, 1]

    def f(t):
        return k0 + k1 * math.cos(t) + k2 * math.sin(t) + k3 * math.cos(2 * t) + k4 * math.sin(2 * t)

    def df(t):
        return -k1 * math.sin(t) + k2 * math.cos(t) - 2 * k3 * math.sin(2 * t) + 2 * k4 * math.cos(2 * t)

    # z² f with z = exp(i t): cos t = (z + 1/z)/2, sin t = (z − 1/z)/(2i), and the same for 2t
    coefficients = [
        complex(k3, -k4) / 2,
        complex(k1, -k2) / 2,
        complex(k0, 0.0),
        complex(k1, k2) / 2,
        complex(k3, k4) / 2,
    ]
    while coefficients and abs(coefficients[0]) < 1e-14 * max(abs(c) for c in coefficients):
        coefficients.pop(0)
    roots = np.roots(coefficients) if len(coefficients) > 1 else []
    scale = max(abs(k0), abs(k1), abs(k2), abs(k3), abs(k4), 1.0)
    found = []
    for z in roots:
        if abs(abs(z) - 1.0) > 1e-4:
            continue
        t = cmath.phase(z)
        for _ in range(8):  # Newton on f(t) (the root of np.roots is only near the circle)
            slope = df(t)
            if slope == 0.0:
                break
            t -= f(t) / slope
        if abs(f(t)) > 1e-10 * scale:
            continue
        x2 = u - V @ np.array([math.cos(t), math.sin(t)])
        found.append((math.remainder(t, 2 * math.pi), math.atan2(x2[1], x2[0])))
    return sorted(found)[:4]


def angle_about(axis, R: np.ndarray) -> float:
    """θ with R = Rot(axis, θ) (least squares on a vector normal to the axis)."""
    v = np.cross(axis, [1.0, 0.0, 0.0])
    if np.linalg.norm(v) < 0.5:
        v = np.cross(axis, [0.0, 1.0, 0.0])
    v = v / np.linalg.norm(v)
    return sp1(v, R @ v, axis)


def scan_roots(residuals, steps: int = SCAN_STEPS) -> list[tuple[float, int]]:
    """(x, branch) where ``residuals(x)[branch]`` changes sign, over x in [−π, π), by bisection."""
    grid = np.linspace(-math.pi, math.pi, steps + 1)
    values = [residuals(float(x)) for x in grid]
    roots = []
    for i in range(steps):
        for branch in range(2):
            a, b = values[i][branch], values[i + 1][branch]
            if not (math.isfinite(a) and math.isfinite(b)) or a * b > 0:
                continue
            lo, hi, f_lo = float(grid[i]), float(grid[i + 1]), a
            if a == 0.0:
                hi = lo
            for _ in range(80):
                if hi - lo < 1e-15:
                    break
                mid = (lo + hi) / 2
                f_mid = residuals(mid)[branch]
                if not math.isfinite(f_mid):
                    break
                if (f_mid < 0) == (f_lo < 0) and f_mid != 0:
                    lo, f_lo = mid, f_mid
                else:
                    hi = mid
            root = (lo + hi) / 2
            if not any(abs(root - r) < 1e-9 and br == branch for r, br in roots):
                roots.append((root, branch))
    return sorted(roots)
