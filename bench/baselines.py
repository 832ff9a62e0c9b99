"""NumPy-vectorised baselines: the same work as spotkin, vectorised over samples."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

CHUNK = 32768


def chunked(func: Callable, n_arrays: int = 1) -> Callable:
    """func over 32768-row chunks of its first n_arrays arguments (the others passed as they are),
    results written into preallocated outputs: the strong NumPy form, whose temporaries stay in
    cache. A 1-D first argument (one sample) is passed through whole."""

    def run(*args):
        arrays, rest = args[:n_arrays], args[n_arrays:]
        n = arrays[0].shape[0] if arrays[0].ndim > 1 else 0
        if n <= CHUNK:
            return func(*args)
        first = func(*(a[:CHUNK] for a in arrays), *rest)
        single = not isinstance(first, tuple)
        parts = (first,) if single else first
        outs = tuple(np.empty((n, *x.shape[1:]), x.dtype) for x in parts)
        for out, x in zip(outs, parts):
            out[:CHUNK] = x
        for start in range(CHUNK, n, CHUNK):
            got = func(*(a[start : start + CHUNK] for a in arrays), *rest)
            for out, x in zip(outs, (got,) if single else got):
                out[start : start + CHUNK] = x
        return outs[0] if single else outs

    return run


def numpy_impl(impl: str, func: Callable, what: str = "", n_arrays: int = 1) -> tuple[str, Callable]:
    """(label, callable) of a NumPy baseline: "numpy" is the chunked form, the one the targets
    use; "numpy-unchunked" the same function over the whole array at once."""
    if impl == "numpy-unchunked":
        return f"numpy-unchunked ({what.strip() or 'whole array'})", func
    return f"numpy (chunked{',' + what if what else ''})", chunked(func, n_arrays)


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


# -- Spot leg (roll-pitch-pitch), eqs. (M2) and (I1)-(I4) of spotkin.reference.leg ----------------------


def leg_fk(q: np.ndarray, h1: float, U: float, L: float, k: float) -> np.ndarray:
    hx, hy, kn = q[..., 0], q[..., 1], q[..., 2]
    s1, c1 = np.sin(hx), np.cos(hx)
    X = k * np.cos(hy) - U * np.sin(hy) - L * np.sin(hy + kn)
    Zs = -k * np.sin(hy) - U * np.cos(hy) - L * np.cos(hy + kn)
    return np.stack([X, h1 * c1 - Zs * s1, h1 * s1 + Zs * c1], axis=-1)


def leg_jacobian(q: np.ndarray, h1: float, U: float, L: float, k: float) -> np.ndarray:
    hx, hy, kn = q[..., 0], q[..., 1], q[..., 2]
    s1, c1, s2, c2 = np.sin(hx), np.cos(hx), np.sin(hy), np.cos(hy)
    s23, c23 = np.sin(hy + kn), np.cos(hy + kn)
    X = k * c2 - U * s2 - L * s23
    Zs = -k * s2 - U * c2 - L * c23
    J = np.empty((*q.shape[:-1], 3, 3))
    J[..., 0, 0] = 0.0
    J[..., 1, 0] = -(h1 * s1 + Zs * c1)
    J[..., 2, 0] = h1 * c1 - Zs * s1
    J[..., 0, 1] = Zs
    J[..., 1, 1] = X * s1
    J[..., 2, 1] = -X * c1
    J[..., 0, 2] = -L * c23
    J[..., 1, 2] = -L * s23 * s1
    J[..., 2, 2] = L * s23 * c1
    return J


def leg_ik_one_branch(p: np.ndarray, h1: float, U: float, L: float, k: float) -> np.ndarray:
    """Slot 0 (hip normal, knee back), no limits or statuses: the usual hand-written IK."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    hx = np.arctan2(z, y) + np.arccos(np.clip(h1 / np.hypot(y, z), -1, 1))
    zp = -np.sin(hx) * y + np.cos(hx) * z
    R = np.hypot(U, k)
    beta = np.arctan2(k, U)
    ratio = (x * x + zp * zp - k * k - U * U - L * L) / (2 * L * R)
    kn = -beta - np.arccos(np.clip(ratio, -1, 1))
    hy = np.arctan2(x, zp) - np.arctan2(k - L * np.sin(kn), -U - L * np.cos(kn))
    hy = (hy + np.pi) % (2 * np.pi) - np.pi
    return np.stack([hx, hy, kn], axis=-1)


# -- Spot Arm ------------------------------------------------------------------------------------------


def _rz(t):
    c, s = np.cos(t), np.sin(t)
    R = np.zeros((*t.shape, 3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1
    return R


def _ry(t):
    c, s = np.cos(t), np.sin(t)
    R = np.zeros((*t.shape, 3, 3))
    R[..., 0, 0], R[..., 0, 2], R[..., 2, 0], R[..., 2, 2], R[..., 1, 1] = c, s, -s, c, 1
    return R


def _rx(t):
    c, s = np.cos(t), np.sin(t)
    R = np.zeros((*t.shape, 3, 3))
    R[..., 1, 1], R[..., 1, 2], R[..., 2, 1], R[..., 2, 2], R[..., 0, 0] = c, -s, s, c, 1
    return R


ARM = {"mount": np.array([0.292, 0.0, 0.188]), "a": 0.3385, "b": 0.4033, "h": 0.075, "hand": 0.19557}


def _arm_frames(q):
    R1 = _rz(q[:, 0])
    R2 = R1 @ _ry(q[:, 1])
    elbow = ARM["mount"] + R2[..., :, 0] * ARM["a"]
    R3 = R2 @ _ry(q[:, 2])
    wrist = elbow + R3 @ np.array([ARM["b"], 0.0, ARM["h"]])
    R4 = R3 @ _rx(q[:, 3])
    R5 = R4 @ _ry(q[:, 4])
    R6 = R5 @ _rx(q[:, 5])
    hand = wrist + R6[..., :, 0] * ARM["hand"]
    return (R1, R2, R3, R4, R5, R6), (elbow, wrist, hand)


def arm_fk(q: np.ndarray) -> np.ndarray:
    (*_, R6), (_, _, hand) = _arm_frames(q)
    T = np.zeros((q.shape[0], 4, 4))
    T[:, :3, :3] = R6
    T[:, :3, 3] = hand
    T[:, 3, 3] = 1
    return T


def arm_jacobian(q: np.ndarray) -> np.ndarray:
    (R1, R2, R3, R4, R5, _), (elbow, wrist, hand) = _arm_frames(q)
    mount = np.broadcast_to(ARM["mount"], hand.shape)
    axes = [
        np.broadcast_to([0.0, 0.0, 1.0], hand.shape),
        R1[..., :, 1],
        R2[..., :, 1],
        R3[..., :, 0],
        R4[..., :, 1],
        R5[..., :, 0],
    ]
    points = [mount, mount, elbow, wrist, wrist, wrist]
    J = np.empty((q.shape[0], 6, 6))
    for j, (z, o) in enumerate(zip(axes, points)):
        J[:, :3, j] = np.cross(z, hand - o)
        J[:, 3:, j] = z
    return J


# -- whole body ----------------------------------------------------------------------------------------


def body_rotation_xyz(angles: np.ndarray) -> np.ndarray:
    """R = Rx(a) Ry(b) Rz(c), vectorised."""
    return _rx(angles[:, 0]) @ _ry(angles[:, 1]) @ _rz(angles[:, 2])


def body_ik(poses: np.ndarray, feet: np.ndarray, hips: np.ndarray, legs: list[tuple]) -> np.ndarray:
    """Body rotation, feet into the hip frames, closed-form leg IK (slot 0): (N, 12)."""
    R = body_rotation_xyz(poses[:, 3:])
    q = np.empty((poses.shape[0], 12))
    for i, params in enumerate(legs):
        d = feet[i] - poses[:, :3]
        p = np.einsum("nji,nj->ni", R, d) - hips[i]
        q[:, 3 * i : 3 * i + 3] = leg_ik_one_branch(p, *params)
    return q


def body_fk(poses: np.ndarray, q12: np.ndarray, hips: np.ndarray, legs: list[tuple]) -> np.ndarray:
    R = body_rotation_xyz(poses[:, 3:])
    feet = np.empty((poses.shape[0], 4, 3))
    for i, params in enumerate(legs):
        local = hips[i] + leg_fk(q12[:, 3 * i : 3 * i + 3], *params)
        feet[:, i] = poses[:, :3] + np.einsum("nij,nj->ni", R, local)
    return feet


def body_jacobian(poses: np.ndarray, q12: np.ndarray, hips: np.ndarray, legs: list[tuple]) -> np.ndarray:
    R = body_rotation_xyz(poses[:, 3:])
    n = poses.shape[0]
    J = np.zeros((n, 12, 18))
    for i, params in enumerate(legs):
        qi = q12[:, 3 * i : 3 * i + 3]
        r = np.einsum("nij,nj->ni", R, hips[i] + leg_fk(qi, *params))
        rows = slice(3 * i, 3 * i + 3)
        J[:, rows, 0:3] = np.eye(3)
        skew = np.zeros((n, 3, 3))
        skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = r[:, 2], -r[:, 1], r[:, 0]
        skew[:, 1, 0], skew[:, 2, 0], skew[:, 2, 1] = -r[:, 2], r[:, 1], -r[:, 0]
        J[:, rows, 3:6] = skew
        J[:, rows, 6 + 3 * i : 9 + 3 * i] = R @ leg_jacobian(qi, *params)
    return J


# -- Trajectories (spotkin.trajectory), vectorised over the time samples ----------------------------------


def p2p_quintic(t: np.ndarray, q0: np.ndarray, qf: np.ndarray, tf: float):
    """q, qd, qdd (N, n): q = q0 + D s(tau), s = 10 tau^3 - 15 tau^4 + 6 tau^5, at rest outside [0, tf]."""
    tau = np.clip(t / tf, 0.0, 1.0)[:, None]
    D = qf - q0
    s = tau**3 * (10 + tau * (-15 + 6 * tau))
    ds = 30 * tau**2 * (1 - tau) ** 2 / tf
    dds = 60 * tau * (1 - tau) * (1 - 2 * tau) / tf**2
    return q0 + D * s, D * ds, D * dds


def p2p_trapezoid(
    t: np.ndarray, q0: np.ndarray, qf: np.ndarray, a: np.ndarray, v: np.ndarray, ta: np.ndarray, tf: float
):
    """q, qd, qdd (N, n) of bang-coast-bang axes with signed acceleration a, cruise v and ramp ta."""
    tc = np.clip(t, 0.0, tf)[:, None]
    r = tf - tc
    acc, dec = tc < ta, tc > tf - ta
    q = np.where(acc, q0 + 0.5 * a * tc**2, np.where(dec, qf - 0.5 * a * r**2, q0 + v * (tc - 0.5 * ta)))
    qd = np.where(acc, a * tc, np.where(dec, a * r, v))
    qdd = np.where(acc, a, np.where(dec, -a, 0.0))
    return q, qd, qdd


def linear_path(
    t: np.ndarray,
    p0: np.ndarray,
    p1: np.ndarray,
    q0: np.ndarray,
    q1: np.ndarray,
    V: float,
    A: float,
    tf: float,
) -> np.ndarray:
    """(N, 4, 4) poses of a straight line with a trapezoidal s(t) (cruise V, acceleration A) and slerp."""
    tc = np.clip(t, 0.0, tf)
    ta = V / A
    cruise = V * (tc - 0.5 * ta)
    s = np.where(tc < ta, 0.5 * A * tc**2, np.where(tc > tf - ta, 1 - 0.5 * A * (tf - tc) ** 2, cruise))
    omega = np.arccos(np.clip(q0 @ q1, -1.0, 1.0))
    q = (np.sin((1 - s) * omega)[:, None] * q0 + np.sin(s * omega)[:, None] * q1) / np.sin(omega)
    x, y, z, w = q.T
    T = np.empty((t.shape[0], 4, 4))
    T[:, 0, 0] = 1 - 2 * (y * y + z * z)
    T[:, 0, 1] = 2 * (x * y - w * z)
    T[:, 0, 2] = 2 * (x * z + w * y)
    T[:, 1, 0] = 2 * (x * y + w * z)
    T[:, 1, 1] = 1 - 2 * (x * x + z * z)
    T[:, 1, 2] = 2 * (y * z - w * x)
    T[:, 2, 0] = 2 * (x * z - w * y)
    T[:, 2, 1] = 2 * (y * z + w * x)
    T[:, 2, 2] = 1 - 2 * (x * x + y * y)
    T[:, :3, 3] = p0 + s[:, None] * (p1 - p0)
    T[:, 3] = [0, 0, 0, 1]
    return T


# -- Any roll-pitch-pitch leg (spotkin.Leg's model), slot 0, no limits: the hand-written NumPy form ---------


def rpp_leg_ik_one_branch(p: np.ndarray, a, b, c, signs) -> np.ndarray:
    """p = Rx(s1 q1)(a + Ry(s2 q2)(b + Ry(s3 q3) c)): hip normal, knee back, no limits or statuses."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    h = a[1] + b[1] + c[1]
    r2 = y * y + z * z
    S = np.sqrt(np.maximum(r2 - h * h, 0.0))
    t1 = np.arctan2(z * h + y * S, y * h - z * S)
    wx, wz = x - a[0], -S - a[2]
    nB, nC = np.hypot(b[0], b[2]), np.hypot(c[0], c[2])
    phi = np.arctan2(c[0], c[2]) - np.arctan2(b[0], b[2])
    ratio = (wx * wx + wz * wz - nB * nB - nC * nC) / (2 * nB * nC)
    psi = -np.arccos(np.clip(ratio, -1, 1))
    t3 = psi - phi
    c3, s3 = np.cos(t3), np.sin(t3)
    dz, dx = b[2] + c3 * c[2] - s3 * c[0], b[0] + c3 * c[0] + s3 * c[2]
    t2 = np.arctan2(wx * dz - wz * dx, wz * dz + wx * dx)
    t3 = (t3 + np.pi) % (2 * np.pi) - np.pi
    return np.stack([signs[0] * t1, signs[1] * t2, signs[2] * t3], axis=-1)


def robot_body_ik_chunked(
    poses: np.ndarray, feet: np.ndarray, hips: np.ndarray, legs: list[tuple]
) -> np.ndarray:
    """Whole-body IK for any number of RPP legs (a, b, c, signs), one branch, in 32768-row chunks
    (so that the temporaries stay in cache: the strong NumPy form)."""
    n_legs = len(legs)
    q = np.empty((poses.shape[0], 3 * n_legs))
    for start in range(0, poses.shape[0], CHUNK):
        chunk = poses[start : start + CHUNK]
        R = body_rotation_xyz(chunk[:, 3:])
        for i, geometry in enumerate(legs):
            d = feet[i] - chunk[:, :3]
            p = np.einsum("nji,nj->ni", R, d) - hips[i]
            q[start : start + CHUNK, 3 * i : 3 * i + 3] = rpp_leg_ik_one_branch(p, *geometry)
    return q
