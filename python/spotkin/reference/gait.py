"""Reference gait formulas, one leg and one tick at a time: plain NumPy and ``math``.

Slow and obvious on purpose: the planner (:mod:`spotkin.reference.gait_plan`) is built from these
functions, and a compiled planner is checked against them sample by sample. The reference layer
imports nothing of the package: a robot or a leg is passed in and only its public methods are called
(``leg.ik``), and statuses are compared with their codes (0 is ``spotkin.Status.OK``).

Phases and contacts (the steady schedule)
-----------------------------------------
(P)  phase_i(t) = frac(t / T + o_i) in [0, 1): a leg is in stance while phase < d (the duty factor),
     in swing while phase >= d; it lifts off at phase = d and touches down when the phase wraps to 0.
     The planner replaces t / T by a clock theta(t) = integral of dt / T(t), so that the period can change.

Swing (the curve of a foot between lift-off p0 and touch-down p1, s in [0, 1])
-----------------------------------------------------------------------------
(Q)  b(x) = 10 x^3 - 15 x^4 + 6 x^5 (the quintic "smoothstep": b(0) = 0, b(1) = 1, b' and b'' zero
     at both ends; max b' = 15/8, max |b''| = 10 / sqrt(3)). It is the degree-5 Bezier curve with
     control values (0, 0, 0, 1, 1, 1): the first and last control points repeated three times.
(S)  horizontal: p_xy(s) = p0_xy + (p1_xy - p0_xy) b(s);
     vertical: apex z_a = max(z0, z1) + H, z(s) = z0 + (z_a - z0) b(2 s) for s <= 1/2,
     z(s) = z_a + (z1 - z_a) b(2 s - 1) for s >= 1/2.
     So dp/ds = 0 at s = 0 and 1 (the foot leaves and lands at rest relative to the ground), z = z_a
     at s = 1/2, and the curve is C2 (continuous velocity and acceleration) with
     |d2p/ds2| <= 10 / sqrt(3) |p1_xy - p0_xy| horizontally and 4 (10 / sqrt(3)) (z_a - z_end) vertically.

Footholds (Raibert, with the capture point)
-------------------------------------------
(F)  p = p_nom + v_cmd T_st / 2 + (omega z x r) T_st / 2 + k (v_meas - v_cmd) sqrt(h / g), horizontally,
     with p_nom the nominal foot under the hip at the predicted touch-down body pose, r the horizontal
     vector from the body origin to that foot (world axes), T_st = d T the stance time, h the
     nominal hip height, k the capture gain (1: the linear inverted pendulum's capture point). The
     height is p_nom's (flat ground).
(B)  bounded: the foothold must be reachable within the joint limits (``leg.ik`` status OK) at each
     of the given body poses (the planner gives five, predicted from touch-down to lift-off); when it
     is not, it moves along the line to p_nom, p(lambda) = p_nom + lambda (p - p_nom), to the largest
     lambda in [0, 1] found reachable by 30 bisection steps, and is reported shortened.

Support margin, stance forces
-----------------------------
(M)  margin: the signed distance of the centre of mass's horizontal projection to the convex hull of
     the stance feet's projections, positive inside; with fewer than three non-collinear feet, minus the
     distance to their segment or point; -inf with no foot down.
(W)  forces f_j on the stance feet (ground on foot, world) carrying the weight quasi-statically:
     sum f_j = F = -m g exactly, and the moment sum (p_j - c) x f_j = 0 in the least-squares sense, at
     the minimum norm. With f_0 = F / n on every foot and N an orthonormal basis of {z : sum z_j = 0}
     (Helmert's), f = f_0 + N z with z = pinv(M N) (-M f_0), M the moment map (singular values below
     1e-9 times the largest are dropped). f_0 is orthogonal to N's columns, so |f|^2 = |f_0|^2 + |z|^2:
     among the forces of least moment error, the smallest. The residual wrench (the part the feet do not
     carry: force F - sum f, moment -sum (p_j - c) x f_j) is reported: with two feet down, the weight's
     moment about the line through them. The joint torques are then tau_l = G_l - J_l^T f_l (G the
     generalised gravity, J_l = R J_leg the foot's Jacobian in world axes), as ``Robot.standing_torques``.
     A closed loop adds a wrench w = [F_w; M_w] (a controller's virtual force and moment on the body,
     world axes, the moment about c): then sum f_j = -m g + F_w exactly and sum (p_j - c) x f_j = M_w
     in the least-squares sense, z = pinv(M N) (M_w - M f_0), the same minimum norm; w = 0 is the
     quasi-static case above.

(T)  torque-weighted forces (a closed loop's): the forces on the loaded feet that minimise
         alpha |S (A f - b)|^2 + sum_l |(G_l - J_l^T f_l) / tau_max,l|^2 + eps |f / (m g)|^2,
     A f = [sum f_j; sum (p_j - c) x f_j] the wrench of the forces, b = [-m g + F_w; M_w] the one
     wanted (W), S = diag(sqrt(beta) / (m g), sqrt(beta) / (m g), 1 / (m g), 1 / (m g h) I_3) its
     scale, alpha = 1e4 (the wrench first), beta = 1e-2 (the horizontal force softer: a tenth of the
     weight missed costs as much as a joint at its limit), eps = 1e-6; G_l and J_l as in (W),
     tau_max,l the joints' effort limits. Among the forces that give the wrench (the vertical force
     and the moments exactly when the feet can: three feet or more), the ones that keep the joint
     torques smallest against their limits: a foot displaced from under its hip pushes partly along
     its leg rather than straight up (the hip's torque falls; the body's speed then swings a little
     within a step, as an inverted pendulum's does). One linear solve (normal equations); a foot
     whose force would pull (f_z < 0) is unloaded and the rest solved again. The limits are then
     held: a joint whose torque passes c = 0.8 of its limit (the rest is its PD's headroom) gets the
     term P (tau_j / tau_max,j - s_j c)^2 (s_j its sign, P = 1e3) and the rest is solved again, for
     up to three such rounds; the wrench gives way where the motors cannot carry it (the residual
     says how much). Without it, a fast trot of a robot whose centre of mass is well ahead of its
     hips' centre (Spot with its arm) asks its hind hip-pitch motors past their limits.

The crawl's body sway
---------------------
(C)  delta = w (s0 + sum_i (X_i cos(4 pi (phase_i - m)), Y_i cos(2 pi (phase_i - m)))), body frame,
     m = (1 + d) / 2 the middle of a swing, w the shift weight (1 for the crawl, 0 for the others).
     s0 = C - c puts the centre of mass c over the crossing C of the nominal stance's diagonals; the
     lateral terms (Y_i = -kappa_y W side_i / |sum_j side_j exp(2 pi i o_j)|, side +1 left, -1 right)
     sway it away from the side that swings, a sine of the cycle crossing the middle in the
     four-foot gaps; the fore-aft terms (X_i = kappa_x L hind_i / |sum_j hind_j exp(4 pi i o_j)|,
     hind +1, front -1) move it forward while a hind leg swings and back while a front one does, at
     twice the frequency. W and L are half the stance's width and length; the sums' moduli make the
     amplitudes kappa_y W and kappa_x L exactly (an axis whose sum vanishes, as in the trot, does not
     sway). Smooth (C-infinity) in the phases: no state, continuous through gait changes.
"""

from __future__ import annotations

import math

import numpy as np

G = 9.81
"""Standard gravity (m/s^2) of the Froude scaling and the capture point."""
OK = 0
"""The code of ``spotkin.Status.OK``."""
TORQUE_ALPHA = 1e4
"""alpha of (T): the weight of the wrench against the torques."""
TORQUE_HORIZONTAL = 1e-2
"""beta of (T): the horizontal force's rows weigh beta alpha (the vertical force and the moments alpha)."""
TORQUE_EPS = 1e-6
"""eps of (T): the forces' own (regularising) weight."""
TORQUE_CAP = 0.8
"""(T) holds a joint whose torque would pass this fraction of its effort limit at the fraction (the
rest is the joint PD's headroom)."""
TORQUE_CAP_WEIGHT = 1e3
"""The weight of a held joint's (tau / tau_max - s TORQUE_CAP)^2, against 1 for a free joint's
(tau / tau_max)^2."""
TORQUE_CAP_ROUNDS = 3
"""(T) holds more joints in at most this many rounds."""
BISECTIONS = 30
"""Bisection steps of (B) (the foothold's lambda, 1e-9 of the step)."""

__all__ = [
    "G",
    "bounded_foothold",
    "contact",
    "crawl_shift",
    "foothold",
    "pendulum_sway",
    "phase",
    "quintic",
    "stance_forces",
    "step_reach",
    "support_margin",
    "sway_coefficients",
    "swing",
    "torque_weighted_forces",
]


def quintic(x: float) -> tuple[float, float, float]:
    """(b, db/dx, d2b/dx2) of (Q) at x clamped to [0, 1]."""
    x = min(max(x, 0.0), 1.0)
    b = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
    db = 30.0 * x * x * (1.0 - x) * (1.0 - x)
    d2b = 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x)
    return b, db, d2b


def frac(x: float) -> float:
    """x - floor(x), in [0, 1)."""
    return x - math.floor(x)


def phase(t: float, offsets, period: float) -> list[float]:
    """(P): each leg's phase at time t of a steady gait."""
    return [frac(t / period + o) for o in offsets]


def contact(phases, duty: float) -> list[bool]:
    """(P): stance while the phase is below the duty factor."""
    return [p < duty for p in phases]


def swing(p_liftoff, p_touchdown, s: float, step_height: float):
    """(S): the swing foot's position, dp/ds and d2p/ds2 at s in [0, 1], each (3,). The foot's
    velocity is dp/ds times ds/dt (the planner's ds/dt = phase rate / (1 - lift-off phase))."""
    p0 = np.asarray(p_liftoff, dtype=np.float64)
    p1 = np.asarray(p_touchdown, dtype=np.float64)
    b, db, d2b = quintic(s)
    p = np.empty(3)
    dp = np.empty(3)
    d2p = np.empty(3)
    for k in (0, 1):
        p[k] = p0[k] + (p1[k] - p0[k]) * b
        dp[k] = (p1[k] - p0[k]) * db
        d2p[k] = (p1[k] - p0[k]) * d2b
    apex = max(p0[2], p1[2]) + step_height
    if s <= 0.5:
        b, db, d2b = quintic(2.0 * s)
        rise = apex - p0[2]
        p[2], dp[2], d2p[2] = p0[2] + rise * b, 2.0 * rise * db, 4.0 * rise * d2b
    else:
        b, db, d2b = quintic(2.0 * s - 1.0)
        fall = p1[2] - apex
        p[2], dp[2], d2p[2] = apex + fall * b, 2.0 * fall * db, 4.0 * fall * d2b
    return p, dp, d2p


def foothold(p_nominal, r_hip, v_cmd, v_meas, yaw_rate, t_stance, h, k=1.0, g=G) -> np.ndarray:
    """(F): the Raibert foothold (3,) in the world. ``p_nominal`` (3,) the nominal foot under the hip at
    touch-down; ``r_hip`` the horizontal vector from the body origin to it; ``v_cmd``, ``v_meas`` the
    commanded and measured body velocities (world, the first two components used); ``yaw_rate`` rad/s;
    ``t_stance`` s; ``h`` the nominal hip height (m); ``k`` the capture gain."""
    p = np.array(p_nominal, dtype=np.float64)
    capture = k * math.sqrt(h / g)
    # the hip's velocity from the yaw rate: omega z x r = omega (-r_y, r_x)
    hip_velocity = (-yaw_rate * r_hip[1], yaw_rate * r_hip[0])
    for j in (0, 1):
        p[j] += (v_cmd[j] + hip_velocity[j]) * t_stance / 2.0 + capture * (v_meas[j] - v_cmd[j])
    return p


def _leg_point(T: np.ndarray, hip, p) -> np.ndarray:
    """A world point in the leg's frame: R^T (p - t) - hip."""
    R, t = T[:3, :3], T[:3, 3]
    return R.T @ (np.asarray(p, dtype=np.float64) - t) - np.asarray(hip, dtype=np.float64)


def _reachable(leg, hip, p, poses, seed) -> bool:
    for T in poses:
        _, status = leg.ik(_leg_point(T, hip, p), seed)
        if int(status) != OK:
            return False
    return True


def bounded_foothold(leg, hip, p, p_nominal, poses, seed=None) -> tuple[np.ndarray, bool]:
    """(B): ``p`` if the leg reaches it within its limits (``leg.ik`` OK) at every pose of ``poses``
    (4 x 4 world <- body transforms), else the point towards ``p_nominal`` found by bisection, and
    whether it was shortened. ``hip`` (3,) is the leg's hip in the body frame."""
    p = np.asarray(p, dtype=np.float64)
    p_nominal = np.asarray(p_nominal, dtype=np.float64)
    if _reachable(leg, hip, p, poses, seed):
        return p.copy(), False
    lo, hi = 0.0, 1.0
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        if _reachable(leg, hip, p_nominal + mid * (p - p_nominal), poses, seed):
            lo = mid
        else:
            hi = mid
    return p_nominal + lo * (p - p_nominal), True


def step_reach(leg, p_leg, direction, limit: float, iterations: int = 40) -> float:
    """The largest rho in [0, limit] with the foot at ``p_leg + rho direction`` (leg frame) reachable
    within the limits, by bisection (the reachable part of the ray taken as an interval from 0)."""
    p_leg = np.asarray(p_leg, dtype=np.float64)
    u = np.asarray(direction, dtype=np.float64)
    if int(leg.ik(p_leg + limit * u)[1]) == OK:
        return float(limit)
    lo, hi = 0.0, float(limit)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if int(leg.ik(p_leg + mid * u)[1]) == OK:
            lo = mid
        else:
            hi = mid
    return lo


def _cross2(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _segment_distance(c, a, b) -> float:
    ab = (b[0] - a[0], b[1] - a[1])
    length2 = ab[0] * ab[0] + ab[1] * ab[1]
    t = 0.0 if length2 == 0.0 else ((c[0] - a[0]) * ab[0] + (c[1] - a[1]) * ab[1]) / length2
    t = min(max(t, 0.0), 1.0)
    return math.hypot(c[0] - a[0] - t * ab[0], c[1] - a[1] - t * ab[1])


def support_margin(points, c) -> float:
    """(M): signed distance of c (2,) to the convex hull of ``points`` (k, 2), positive inside."""
    pts = sorted({(float(p[0]), float(p[1])) for p in points})
    c = (float(c[0]), float(c[1]))
    if not pts:
        return -math.inf
    chains = []  # Andrew's monotone chain: the lower then the upper hull, counter-clockwise
    for sweep in (pts, pts[::-1]):
        chain: list[tuple[float, float]] = []
        for p in sweep:
            while len(chain) >= 2 and _cross2(chain[-2], chain[-1], p) <= 1e-12:
                chain.pop()
            chain.append(p)
        chains.append(chain[:-1])
    hull = chains[0] + chains[1]
    if len(hull) < 3:  # a point or collinear feet: minus the distance to their segment
        ends = (pts[0], pts[-1])
        return -_segment_distance(c, ends[0], ends[1])
    edges = [(hull[k], hull[(k + 1) % len(hull)]) for k in range(len(hull))]
    inside = min(_cross2(a, b, c) / math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in edges)
    if inside >= 0.0:
        return inside
    return -min(_segment_distance(c, a, b) for a, b in edges)


def _skew(r) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def stance_forces(feet, stance, com, mass: float, gravity=(0.0, 0.0, -9.81), wrench=None):
    """(W): (forces (n, 3), residual (6,)): the least-squares quasi-static forces on the stance feet
    (zero on the others) and the wrench [force; moment about the centre of mass] they leave unbalanced.
    ``wrench`` (6,) [F_w; M_w], world axes, optional: a wrench the feet carry besides the weight (a
    closed loop's virtual force and moment on the body, the moment about ``com``)."""
    feet = np.asarray(feet, dtype=np.float64)
    com = np.asarray(com, dtype=np.float64)
    F = -mass * np.asarray(gravity, dtype=np.float64)
    target = np.zeros(3)  # the moment the feet should give about the com
    if wrench is not None:
        wrench = np.asarray(wrench, dtype=np.float64)
        F, target = F + wrench[:3], wrench[3:6].copy()
    down = [j for j in range(len(feet)) if stance[j]]
    forces = np.zeros((len(feet), 3))
    n = len(down)
    if n == 0:
        return forces, np.concatenate([F, target])
    if not (np.isfinite(feet[down]).all() and np.isfinite(com).all()):
        return np.full((len(feet), 3), np.nan), np.full(6, np.nan)
    M = np.hstack([_skew(feet[j] - com) for j in down])  # (3, 3 n): the moments about the com
    f0 = np.tile(F / n, n)
    N = np.zeros((3 * n, 3 * (n - 1)))  # Helmert's basis of {sum z_j = 0}, per component
    for k in range(1, n):
        column = np.zeros(n)
        column[:k] = 1.0
        column[k] = -float(k)
        column /= math.sqrt(k * (k + 1))
        for axis in range(3):
            N[axis::3, 3 * (k - 1) + axis] = column
    f = f0
    if n > 1:
        A = M @ N
        U, sigma, Vt = np.linalg.svd(A, full_matrices=False)
        keep = sigma > 1e-9 * sigma[0] if sigma[0] > 0 else np.zeros_like(sigma, dtype=bool)
        rhs = U.T @ (target - M @ f0)
        z = Vt[keep].T @ (rhs[keep] / sigma[keep])
        f = f0 + N @ z
    for slot, j in enumerate(down):
        forces[j] = f[3 * slot : 3 * slot + 3]
    residual = np.concatenate([F - forces.sum(axis=0), target - M @ f])
    return forces, residual


def torque_weighted_forces(feet, loaded, com, mass, jacobians, gravity_torques, limits, h, wrench=None):
    """(T): (forces (n, 3), residual (6,)): the loaded feet's forces (world) and the wrench left
    unbalanced. ``jacobians`` (n, 3, 3) each foot's d foot / d q_leg in world axes; ``gravity_torques``
    and ``limits`` (n, 3) each leg's G and effort limits; ``h`` the length scale of the moments;
    ``wrench`` (6,) [F_w; M_w] as in :func:`stance_forces` (gravity -9.81 z)."""
    feet = np.asarray(feet, dtype=np.float64)
    com = np.asarray(com, dtype=np.float64)
    n = len(feet)
    weight = mass * G
    b = np.array([0.0, 0.0, weight, 0.0, 0.0, 0.0])
    if wrench is not None:
        b = b + np.asarray(wrench, dtype=np.float64)
    down = [j for j in range(n) if loaded[j]]
    forces = np.zeros((n, 3))
    cap = np.zeros((n, 3))  # the held joints: the sign of their torque, 0 when free
    rounds = 0
    while True:
        k = len(down)
        if k == 0:
            return forces, b.copy()
        A = np.zeros((6, 3 * k))
        D = np.zeros((3 * k, 3 * k))
        g = np.zeros(3 * k)
        held = np.zeros(3 * k)
        for slot, j in enumerate(down):
            A[:3, 3 * slot : 3 * slot + 3] = np.eye(3)
            A[3:, 3 * slot : 3 * slot + 3] = _skew(feet[j] - com)
            scale = 1.0 / np.asarray(limits[j], dtype=np.float64)
            D[3 * slot : 3 * slot + 3, 3 * slot : 3 * slot + 3] = scale[:, None] * np.asarray(jacobians[j]).T
            g[3 * slot : 3 * slot + 3] = scale * np.asarray(gravity_torques[j], dtype=np.float64)
            held[3 * slot : 3 * slot + 3] = cap[j]
        S2 = np.r_[np.full(3, 1.0 / weight**2), np.full(3, 1.0 / (weight * h) ** 2)]
        S2[:2] *= TORQUE_HORIZONTAL
        # a held joint's row of D f = g - tau / tau_max is pulled to g - s TORQUE_CAP
        P = TORQUE_CAP_WEIGHT * (held != 0.0)
        H = (
            TORQUE_ALPHA * A.T @ (S2[:, None] * A)
            + D.T @ D
            + D.T @ (P[:, None] * D)
            + np.eye(3 * k) * (TORQUE_EPS / weight**2)
        )
        f = np.linalg.solve(H, TORQUE_ALPHA * A.T @ (S2 * b) + D.T @ g + D.T @ (P * (g - held * TORQUE_CAP)))
        pulling = [j for slot, j in enumerate(down) if f[3 * slot + 2] < 0.0]
        if pulling:
            down = [j for j in down if j not in pulling]
            continue
        if rounds == TORQUE_CAP_ROUNDS:
            break
        u = g - D @ f  # tau / tau_max
        new = (held == 0.0) & (np.abs(u) > TORQUE_CAP)
        if not new.any():
            break
        rounds += 1
        for slot, j in enumerate(down):
            part = slice(3 * slot, 3 * slot + 3)
            cap[j] = np.where(new[part], np.sign(u[part]), cap[j])
    for slot, j in enumerate(down):
        forces[j] = f[3 * slot : 3 * slot + 3]
    return forces, b - A @ f


def pendulum_sway(duty, period, h):
    """kappa_y of the lateral sway that the linear inverted pendulum (LIP) needs when the two sides'
    feet alternate (the pace): the fundamental of the periodic orbit of y'' = w^2 (y - p(t)), p the
    centre of pressure (+-W while one side's pair alone is down, for min(d, 1 - d) of the period; the
    stance's centre, 0, otherwise), w^2 = g / h, W half the stance's width. The bounded periodic
    solution is p filtered, y_k = w^2 / (w^2 + k^2 W_c^2) p_k (W_c = 2 pi / T), and p's fundamental
    is (4 W / pi) sin(pi min(d, 1 - d)); the third harmonic is under 5 % of it for the presets'
    periods (T = c sqrt(h / g), c >= 2). A fraction of W, in phase with p: the body over the side
    that is down, as the crawl's static sway (C) but smaller (0.17 W for the pace's defaults)."""
    omega2 = G / h
    cycle2 = (2.0 * math.pi / period) ** 2
    return 4.0 / math.pi * math.sin(math.pi * min(duty, 1.0 - duty)) * omega2 / (omega2 + cycle2)


def sway_coefficients(stance_xy, roles, offsets, com_xy, amplitude=(0.0, 0.45)):
    """(C): (X_i, Y_i) per leg (n, 2) and the base offset s0 (2,) of the crawl's sway, body frame.
    ``stance_xy`` (4, 2) the nominal feet, ``roles`` their roles, ``offsets`` (4,) the gait's,
    ``com_xy`` the nominal centre of mass's projection, ``amplitude`` (kappa_x, kappa_y)."""
    at = {role: np.asarray(stance_xy[k], dtype=np.float64) for k, role in enumerate(roles)}
    fl, fr, hl, hr = at["front_left"], at["front_right"], at["hind_left"], at["hind_right"]
    # the diagonals' crossing: fl + a (hr - fl) = fr + b (hl - fr)
    a = np.linalg.solve(np.column_stack([hr - fl, -(hl - fr)]), fr - fl)[0]
    base = fl + a * (hr - fl) - np.asarray(com_xy, dtype=np.float64)
    half_length = ((fl[0] + fr[0]) - (hl[0] + hr[0])) / 4.0
    half_width = ((fl[1] + hl[1]) - (fr[1] + hr[1])) / 4.0
    hind = [1.0 if role.startswith("hind") else -1.0 for role in roles]
    left = [1.0 if role.endswith("left") else -1.0 for role in roles]
    # |sum_j sign_j exp(i k 2 pi o_j)|: the amplitude of the steady sum of (C)
    norm_x = abs(
        sum(
            hind[j] * complex(math.cos(4 * math.pi * o), math.sin(4 * math.pi * o))
            for j, o in enumerate(offsets)
        )
    )
    norm_y = abs(
        sum(
            left[j] * complex(math.cos(2 * math.pi * o), math.sin(2 * math.pi * o))
            for j, o in enumerate(offsets)
        )
    )
    X = [amplitude[0] * half_length * hind[j] / norm_x if norm_x > 1e-9 else 0.0 for j in range(len(roles))]
    Y = [-amplitude[1] * half_width * left[j] / norm_y if norm_y > 1e-9 else 0.0 for j in range(len(roles))]
    return np.column_stack([X, Y]), base


def crawl_shift(phases, phase_rates, duty, duty_rate, coefficients, coefficient_rates):
    """(C): the sum of the sway terms (2,) and its time derivative (2,), body frame (without the weight
    and the base offset). ``coefficients`` (n, 2) (X_i, Y_i) and their rates."""
    centre, centre_rate = (1.0 + duty) / 2.0, duty_rate / 2.0
    value, rate = np.zeros(2), np.zeros(2)
    for i, phase_ in enumerate(phases):
        for axis, harmonic in ((0, 2.0), (1, 1.0)):
            angle = 2.0 * math.pi * harmonic * (phase_ - centre)
            angle_rate = 2.0 * math.pi * harmonic * (phase_rates[i] - centre_rate)
            value[axis] += coefficients[i][axis] * math.cos(angle)
            rate[axis] += (
                coefficient_rates[i][axis] * math.cos(angle)
                - coefficients[i][axis] * math.sin(angle) * angle_rate
            )
    return value, rate
