"""The plain geometry of the reference reach (:mod:`spotkin.reference.reach`): the Halton sequence,
Euler angles and poses, the stance frame (S), the capsules' segment distances, the legs' segments,
rotation vectors and Euler rates. Slow and obvious on purpose."""

from __future__ import annotations

import math

import numpy as np


def halton(index: int, base: int) -> float:
    """The radical inverse of ``index`` in ``base``."""
    f, out = 1.0, 0.0
    while index > 0:
        f /= base
        out += f * (index % base)
        index //= base
    return out


def xyz_euler(R) -> np.ndarray:
    """(a, b, c) with R = Rx(a) Ry(b) Rz(c)."""
    b = math.asin(max(-1.0, min(1.0, float(R[0, 2]))))
    a = math.atan2(-float(R[1, 2]), float(R[2, 2]))
    c = math.atan2(-float(R[0, 1]), float(R[0, 0]))
    return np.array([a, b, c])


def pose_of(T) -> np.ndarray:
    """[x, y, z, a, b, c] (Euler "XYZ") of a rigid transform."""
    return np.concatenate([np.asarray(T, float)[:3, 3], xyz_euler(np.asarray(T, float)[:3, :3])])


def stance_frame(feet, nominal_feet) -> np.ndarray:
    """(S): world <- S (4, 4) from the feet (n, 3) and the nominal stance's feet (n, 3)."""
    f, F0 = np.asarray(feet, float), np.asarray(nominal_feet, float)
    cf, c0 = f.mean(axis=0), F0.mean(axis=0)
    cross = dot = 0.0
    for u, v in zip(F0 - c0, f - cf):
        cross += u[0] * v[1] - u[1] * v[0]
        dot += u[0] * v[0] + u[1] * v[1]
    psi = math.atan2(cross, dot)
    c, s = math.cos(psi), math.sin(psi)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[0, 3] = cf[0] - (c * c0[0] - s * c0[1])
    T[1, 3] = cf[1] - (s * c0[0] + c * c0[1])
    T[2, 3] = cf[2] - c0[2]
    return T


def segment_distance(a, b, c, d) -> float:
    """Distance between the segments a-b and c-d (Ericson, Real-Time Collision Detection, 5.1.9)."""
    a, b, c, d = (np.asarray(v, float) for v in (a, b, c, d))
    u, v, w = b - a, d - c, a - c
    uu, vv, uv, uw, vw = u @ u, v @ v, u @ v, u @ w, v @ w
    if uu <= 1e-30 and vv <= 1e-30:
        return float(np.linalg.norm(w))
    if uu <= 1e-30:
        s, t = 0.0, min(max(vw / vv, 0.0), 1.0)
    elif vv <= 1e-30:
        s, t = min(max(-uw / uu, 0.0), 1.0), 0.0
    else:
        den = uu * vv - uv * uv
        s = min(max((uv * vw - vv * uw) / den, 0.0), 1.0) if den > 1e-30 else 0.0
        t = (uv * s + vw) / vv
        if t < 0.0:
            s, t = min(max(-uw / uu, 0.0), 1.0), 0.0
        elif t > 1.0:
            s, t = min(max((uv - uw) / uu, 0.0), 1.0), 1.0
    return float(np.linalg.norm(w + s * u - t * v))


def segment_box_distance(a, b, centre, half) -> float:
    """Distance from the segment a-b to the box (centre, half-lengths), in the box's axes, exactly:
    d(t)^2 = sum_k max(|a_k + t u_k - centre_k| - half_k, 0)^2 is a quadratic in t between the points
    where a coordinate crosses a face's plane, so its minimum is at an end, at one of those points, or
    at a piece's own minimum, t = -sum_k s_k u_k (s_k (a_k - centre_k) - half_k) / sum_k u_k^2 over the
    coordinates outside the slab (s_k their side)."""
    a = np.asarray(a, float) - np.asarray(centre, float)
    u, half = np.asarray(b, float) - np.asarray(centre, float) - a, np.asarray(half, float)

    def at(t: float) -> float:
        gap = np.maximum(np.abs(a + t * u) - half, 0.0)
        return float(np.sqrt(gap @ gap))

    cuts = [0.0, 1.0]
    for k in range(3):
        if u[k] != 0.0:
            cuts += [t for t in ((half[k] - a[k]) / u[k], (-half[k] - a[k]) / u[k]) if 0.0 < t < 1.0]
    cuts.sort()
    best = min(at(t) for t in cuts)
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        mid = a + 0.5 * (lo + hi) * u
        side = np.sign(mid) * (np.abs(mid) > half)
        den = float(np.sum(side * side * u * u))
        if den > 0.0:
            t = -float(np.sum(side * u * (side * a - half * side * side))) / den
            best = min(best, at(min(max(t, lo), hi)))
    return best


def leg_segments(robot, q_legs) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Each leg's (hip-pitch joint, knee, foot) in the body frame for the legs' joints (3 n,)."""
    q_legs = np.asarray(q_legs, float)
    out = []
    for k, leg in enumerate(robot.legs):
        q = q_legs[robot.leg_columns[k]]
        a, signs = leg.a, leg.signs
        t1 = signs[0] * q[0]
        c, s = math.cos(t1), math.sin(t1)
        hip_pitch = robot.hip_positions[k] + np.array([a[0], c * a[1] - s * a[2], s * a[1] + c * a[2]])
        out.append((hip_pitch, robot.hip_positions[k] + leg.knee(q), robot.hip_positions[k] + leg.fk(q)))
    return out


def wrap(x):
    return (np.asarray(x, float) + math.pi) % (2.0 * math.pi) - math.pi


def euler_rates(angles) -> np.ndarray:
    """E (3, 3): the angular velocity w = E (a', b', c') of R = Rx(a) Ry(b) Rz(c), in the frame R is
    given in: w = a' x + Rx(a) (b' y) + Rx(a) Ry(b) (c' z)."""
    a, b = float(angles[0]), float(angles[1])
    ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
    return np.array([[1.0, 0.0, sb], [0.0, ca, -sa * cb], [0.0, sa, ca * cb]])


def rotation_log(R) -> np.ndarray:
    """The rotation vector of R (axis times angle, angle in [0, pi])."""
    R = np.asarray(R, float)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s, c = 0.5 * float(np.linalg.norm(w)), 0.5 * (float(np.trace(R)) - 1.0)
    angle = math.atan2(s, c)
    if s < 1e-9:
        if c > 0.0:  # near the identity: w / 2 is the vector to first order
            return 0.5 * w
        # near pi: the axis from the diagonal of (R + I) / 2 = n n^T
        k = int(np.argmax(np.diag(R)))
        n = (R[:, k] + np.eye(3)[k]) / math.sqrt(max(2.0 * (1.0 + R[k, k]), 1e-300))
        return angle * n / np.linalg.norm(n)
    return angle * w / (2.0 * s)


def rigid(T) -> bool:
    T = np.asarray(T, float)
    if not np.isfinite(T).all() or np.abs(T[3] - [0.0, 0.0, 0.0, 1.0]).max() > 1e-6:
        return False
    R = T[:3, :3]
    return np.abs(R.T @ R - np.eye(3)).max() <= 1e-6 and np.linalg.det(R) > 0.0
