"""Reference trajectories, one time sample at a time, written straight from the formulas.

Slow and obvious on purpose: the C++ sampling is tested against these functions.

Point to point, one axis moving D = qf - q0 in t_f, tau = t / t_f
-----------------------------------------------------------------
(C)  cubic     s = 3 tau^2 - 2 tau^3;  s' = 6 tau (1 - tau);  s'' = 6 - 12 tau.
               max s' = 3/2 (tau = 1/2), max |s''| = 6 (tau = 0, 1)
               => t_f = max(3 |D| / (2 Kv), sqrt(6 |D| / Ka)).
(Q)  quintic   s = 10 tau^3 - 15 tau^4 + 6 tau^5;  s' = 30 tau^2 (1 - tau)^2;
               s'' = 60 tau (1 - tau) (1 - 2 tau). max s' = 15/8 (tau = 1/2); s''' = 0 at
               tau = 1/2 -+ sqrt(3)/6 where |s''| = 60 (1/6) (1/sqrt(3)) = 10 / sqrt(3)
               => t_f = max(15 |D| / (8 Kv), sqrt(10 |D| / (sqrt(3) Ka))).
(T)  trapezoid ramp t_a = v / a:  0 <= t < t_a:          q = q0 + a t^2 / 2
                                  t_a <= t <= t_f - t_a:  q = q0 + v t - v^2 / (2 a)
                                  t_f - t_a < t <= t_f:   q = qf - a (t_f - t)^2 / 2
               and |D| = v (t_f - t_a). Minimum time: v = Kv, a = Ka, t_f = |D|/Kv + Kv/Ka if
               |D| >= Kv^2/Ka; else triangular, v = sqrt(|D| Ka), t_f = 2 sqrt(|D|/Ka).
               Stretched to t_f with a = Ka: v^2 - Ka t_f v + Ka |D| = 0, the smaller root.
(S)  synchronisation: t_f = max over axes of the per-axis minimum time.

Cartesian
---------
(L)  linear: s(t) in [0, 1] trapezoidal with V = min(vmax/L, wmax/theta),
     A = min(amax/L, alphamax/theta) (by (T) with D = 1); p = p0 + s (p1 - p0);
     slerp q(s) = sin((1 - s) O) / sin O q0 + sin(s O) / sin O q1, cos O = q0 . q1 >= 0.
(B)  blended waypoint path (see spotkin.trajectory.CartesianPath), with rotation matrices.
(P)  its plan (see spotkin.kinematics.path_planning._plan): rates r_k = 1 / d_k, segment k's (dp_k, phi_k),
     N(u, w) = max(|u| / amax, |w| / alphamax), blend b_j = max(N(twist change), min_blend).
     Fit rule b_j <= min(d_{j-1}, d_j), bounded by the triangle inequality: with
     gamma = N(seg_j - seg_{j-1}), accelerating (r_j >= r_{j-1}):
     beta r_j^2 - (beta - gamma) r_{j-1} r_j <= 1, beta = max(N(seg_j), gamma);
     decelerating the same with j-1 and j swapped. Caps r_k <= 1 / d_min_k,
     r^2 <= 1 / gamma next to a corner, r^2 <= 1 / N(seg) on the end segments,
     r <= 1 / min_blend next to an interior waypoint. The fastest rates: a forward then a
     backward pass, one corner at a time, each solving its quadratic for the largest root.
"""

from __future__ import annotations

import math

import numpy as np

PROFILES = ("cubic", "quintic", "trapezoid")


def min_duration(profile: str, D: float, vmax: float, amax: float) -> float:
    D = abs(D)
    if D == 0:
        return 0.0
    if profile == "cubic":
        return max(3 * D / (2 * vmax), math.sqrt(6 * D / amax))
    if profile == "quintic":
        return max(15 * D / (8 * vmax), math.sqrt(10 * D / (math.sqrt(3) * amax)))
    if D >= vmax**2 / amax:
        return D / vmax + vmax / amax
    return 2 * math.sqrt(D / amax)


def trapezoid_1d(t: float, D: float, v: float, a: float, tf: float) -> tuple[float, float, float]:
    """s, s', s'' of a trapezoid from 0 to D >= 0 with cruise v and acceleration a, ending at tf."""
    if D == 0:
        return 0.0, 0.0, 0.0
    ta = v / a
    if t < ta:
        return a * t * t / 2, a * t, a
    if t <= tf - ta:
        return v * t - v * v / (2 * a), v, 0.0
    return D - a * (tf - t) ** 2 / 2, a * (tf - t), -a


def point_to_point(q0, qf, vmax, amax, profile: str, t: float):
    """(q, qd, qdd) as lists at one time t, planned from scratch."""
    n = len(q0)
    vmax = np.broadcast_to(vmax, (n,))
    amax = np.broadcast_to(amax, (n,))
    tf = max([min_duration(profile, qf[j] - q0[j], vmax[j], amax[j]) for j in range(n)] + [0.0])
    if math.isnan(t):
        return [math.nan] * n, [math.nan] * n, [math.nan] * n
    if t < 0 or t > tf:  # at rest at an end
        return list(q0 if t < 0 else qf), [0.0] * n, [0.0] * n
    q, qd, qdd = [], [], []
    for j in range(n):
        D = qf[j] - q0[j]
        if tf == 0 or D == 0:
            s, ds, dds = 0.0, 0.0, 0.0
            sign = 0.0
        elif profile == "trapezoid":
            a = amax[j]
            v = (a * tf - math.sqrt(max(0.0, (a * tf) ** 2 - 4 * a * abs(D)))) / 2
            s, ds, dds = trapezoid_1d(t, abs(D), v, a, tf)
            sign = math.copysign(1.0, D)
        else:
            tau = t / tf
            if profile == "cubic":
                s, ds, dds = 3 * tau**2 - 2 * tau**3, 6 * tau - 6 * tau**2, 6 - 12 * tau
            else:
                s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
                ds = 30 * tau**2 - 60 * tau**3 + 30 * tau**4
                dds = 60 * tau - 180 * tau**2 + 120 * tau**3
            s, ds, dds = s * abs(D), ds * abs(D) / tf, dds * abs(D) / tf**2
            sign = math.copysign(1.0, D)
        q.append(q0[j] + sign * s)
        qd.append(sign * ds)
        qdd.append(sign * dds)
    return q, qd, qdd


def quaternion_to_matrix(q) -> np.ndarray:
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def rodrigues(phi) -> np.ndarray:
    """exp of the rotation vector phi: I + sin(th) K + (1 - cos(th)) K^2, K the unit axis's cross matrix."""
    th = float(np.linalg.norm(phi))
    if th == 0:
        return np.eye(3)
    kx, ky, kz = np.asarray(phi) / th
    K = np.array([[0, -kz, ky], [kz, 0, -kx], [-ky, kx, 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def linear(p0, q0, p1, q1, vmax, amax, wmax, alphamax, t: float):
    """(p, quaternion [x, y, z, w], v, w) of the straight-line path at time t, by (L).

    q0, q1 as unit quaternions; q1 is negated when q0 . q1 < 0 (shortest path).
    """
    p0, p1, q0, q1 = (np.asarray(x, dtype=float) for x in (p0, p1, q0, q1))
    if np.dot(q0, q1) < 0:
        q1 = -q1
    L = float(np.linalg.norm(p1 - p0))
    omega = math.acos(min(1.0, float(np.dot(q0, q1))))  # half the rotation angle
    theta = 2 * omega
    V = min(vmax / L if L else math.inf, wmax / theta if theta else math.inf)
    A = min(amax / L if L else math.inf, alphamax / theta if theta else math.inf)
    if math.isinf(V):
        return p0, q0, np.zeros(3), np.zeros(3)
    tf = min_duration("trapezoid", 1.0, V, A)
    v = V if 1.0 >= V * V / A else math.sqrt(A)
    t = min(max(t, 0.0), tf)
    s, ds, _ = trapezoid_1d(t, 1.0, v, A, tf)
    p = p0 + s * (p1 - p0)
    if omega == 0:
        q = q0
        w = np.zeros(3)
    else:
        q = (math.sin((1 - s) * omega) * q0 + math.sin(s * omega) * q1) / math.sin(omega)
        # world angular velocity: ds * theta * (world axis of q1 q0^-1)
        r = quat_mul(q1, q0 * [-1, -1, -1, 1])
        w = ds * theta * r[:3] / np.linalg.norm(r[:3])
    return p, q, ds * (p1 - p0), w


def quat_mul(a, b) -> np.ndarray:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    va, vb = np.array([ax, ay, az]), np.array([bx, by, bz])
    return np.concatenate([aw * vb + bw * va + np.cross(va, vb), [aw * bw - va @ vb]])


def blended(times, blends, positions, rotations, linear_velocity, angular_velocity, t: float):
    """(T 4x4, twist [v; w]) of a blended waypoint path at time t, by (B) with rotation matrices."""
    W = len(times)
    duration = times[-1] + blends[-1] / 2
    t = min(max(t, 0.0), duration)
    zero = np.zeros(3)
    k = max(i for i in range(W) if times[i] - blends[i] / 2 <= t) if t > 0 else 0
    tau = t - times[k]
    b = blends[k]
    if (b > 0 and tau <= b / 2) or k == W - 1:
        v0 = linear_velocity[k - 1] if k > 0 else zero
        w0 = angular_velocity[k - 1] if k > 0 else zero
        v1 = linear_velocity[k] if k < W - 1 else zero
        w1 = angular_velocity[k] if k < W - 1 else zero
        u = tau + b / 2
        f2 = u * u / (2 * b) if b > 0 else 0.0
        f1 = tau - f2
        g2 = u / b if b > 0 else 0.0
        A = rodrigues(np.multiply(w0, f1))
        R = A @ rodrigues(np.multiply(w1, f2)) @ rotations[k]
        p = positions[k] + np.multiply(v0, f1) + np.multiply(v1, f2)
        v = np.multiply(v0, 1 - g2) + np.multiply(v1, g2)
        w = np.multiply(w0, 1 - g2) + A @ w1 * g2
    else:
        R = rodrigues(np.multiply(angular_velocity[k], tau)) @ rotations[k]
        p = positions[k] + np.multiply(linear_velocity[k], tau)
        v, w = np.asarray(linear_velocity[k]), np.asarray(angular_velocity[k])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T, np.concatenate([v, w])


def blend_plan(positions, rotation_vectors, vmax, amax, wmax, alphamax, min_blend):
    """(P) Segment durations d (S,) and blend durations b (S + 1,) of a blended path through
    ``positions`` (S + 1, 3) with world rotation vectors ``rotation_vectors`` (S, 3) between them,
    one segment at a time. wmax = alphamax = inf: no rotation limit."""
    P = [np.asarray(p, dtype=float) for p in positions]
    segments = [(P[k + 1] - P[k], np.asarray(rotation_vectors[k], dtype=float)) for k in range(len(P) - 1)]
    S = len(segments)

    def N(u, w) -> float:
        return max(float(np.linalg.norm(u)) / amax, float(np.linalg.norm(w)) / alphamax)

    r = []
    for u, w in segments:
        d_min = max(float(np.linalg.norm(u)) / vmax, float(np.linalg.norm(w)) / wmax)
        r.append(1 / d_min)
    r[0] = min(r[0], 1 / math.sqrt(N(*segments[0])))
    r[-1] = min(r[-1], 1 / math.sqrt(N(*segments[-1])))
    gamma = [math.nan]
    for j in range(1, S):
        (a, wa), (b, wb) = segments[j - 1], segments[j]
        gamma.append(N(b - a, wb - wa))
        if gamma[j] > 0:
            r[j - 1] = min(r[j - 1], 1 / math.sqrt(gamma[j]))
            r[j] = min(r[j], 1 / math.sqrt(gamma[j]))
        if min_blend > 0:
            r[j - 1] = min(r[j - 1], 1 / min_blend)
            r[j] = min(r[j], 1 / min_blend)

    def largest_root(beta, g, x):  # the largest y with beta y^2 - (beta - g) x y <= 1
        k = (beta - g) * x
        return (k + math.sqrt(k * k + 4 * beta)) / (2 * beta)

    for j in range(1, S):  # forward: segment j accelerating from j - 1
        beta = max(N(*segments[j]), gamma[j])
        r[j] = min(r[j], largest_root(beta, gamma[j], r[j - 1]))
    for j in range(S - 1, 0, -1):  # backward: segment j - 1 decelerating into j
        beta = max(N(*segments[j - 1]), gamma[j])
        r[j - 1] = min(r[j - 1], largest_root(beta, gamma[j], r[j]))
    d = [1 / rk for rk in r]
    twists = [(np.zeros(3), np.zeros(3))] + [(u / dk, w / dk) for (u, w), dk in zip(segments, d)]
    twists.append((np.zeros(3), np.zeros(3)))
    b = []
    for j in range(S + 1):
        (v0, w0), (v1, w1) = twists[j], twists[j + 1]
        b.append(max(N(v1 - v0, w1 - w0), min_blend if 0 < j < S else 0.0))
    return np.array(d), np.array(b)
