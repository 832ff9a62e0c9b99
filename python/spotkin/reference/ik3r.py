"""Reference position IK of any 3-joint chain (3R, and the prismatic variants), one sample at a time.

Slow and obvious on purpose: every candidate comes from a closed form (a polynomial of degree <= 4 in one
joint), then is polished with Newton steps on the original position equations.

Splitting the chain (eq. F)
---------------------------
With the elementary transforms of ``chain.py``, a joint's transform factors as T_j(q) = T_j(0) Z_j(q)
(DHm: RotZ/TransZ are the last factors) or T_j(q) = Z_j(q) T_j(0) (DH: they are the first), where
Z_j = RotZ(q) for a revolute joint and TransZ(q) for a prismatic one. So the tool point is

    (F)   p = M0 Z1(q1) M1 Z2(q2) M2 Z3(q3) w,
          DHm: M0 = base T1(0), M1 = T2(0), M2 = T3(0), w = tool origin,
          DH:  M0 = base,       M1 = T1(0), M2 = T2(0), w = T3(0) tool origin,

and with p' = M0^-1 p (the target in the frame whose z axis is joint 1's axis; Mj = [Rj | tj]):

    (F')  p' = Z1(q1) f(q2, q3),   f = R1 Z2(q2) g + t1,   g(q3) = R2 Z3(q3) w + t2.

g is the tool point in the frame of joint 2's axis; it is linear in (cos q3, sin q3) or affine in q3.

Eliminating q1 (Pieper): two invariants of Z1
---------------------------------------------
    revolute q1 (RotZ keeps |.| and z):      (I1) |f|^2 = |p'|^2          (I2) f_z = p'_z
    prismatic q1 (TransZ keeps x and y):     (I1) f_x  = p'_x             (I2) f_y = p'_y

Eliminating q2, revolute q2: with Rz(q2) g = [[g_x, -g_y], [g_y, g_x]] (cos q2, sin q2) + g_z e3, both
invariants read r_i . Rz(q2) g = kappa_i(q3), i.e. (rows r_a, r_b; u = R1^T t1, v = R1^T e3)

    RR: r_a = u, kappa_a = (|p'|^2 - |g|^2 - |t1|^2) / 2;     r_b = v, kappa_b = p'_z - t1_z
    PR: r_a = R1^T e1, kappa_a = p'_x - t1_x;                 r_b = R1^T e2, kappa_b = p'_y - t1_y

    (L)   Rr y = d,   Rr = [r_a,xy; r_b,xy] (2x2, constant),   d_i = kappa_i - r_i,z g_z,
          y = (g_x + i g_y) e^{i q2}, so |y|^2 = rho^2 := g_x^2 + g_y^2.

    (Q)   P(q3) = |adj(Rr) d|^2 - det(Rr)^2 rho^2 = 0                     (general: det Rr != 0)
    (B)   y = Rr^-1 d,   q2 = atan2(y_2, y_1) - atan2(g_y, g_x)           (one q2 per q3)

det Rr = t . (e3 x z2) for RR (zero iff axes 1 and 2 intersect or are parallel) and z1 . z2 for PR (zero
iff they are perpendicular). When it vanishes, Rr has rank 1 with left null vector n (a row of adj Rr):

    (Q')  P(q3) = n . d = 0                                                (reduced, degree 2)
    (B')  a cos q2 + b sin q2 = d_i,  [a, b] = r_i,xy [[g_x, -g_y], [g_y, g_x]]   (two q2 per q3)

Eliminating q2, prismatic q2: f = R1 (g + q2 e3) + t1.
    RP, v_z != 0:  q2 = (p'_z - t1_z - v.g) / v_z  from (I2),  P(q3) = |g + q2 e3 + u|^2 - |p'|^2  (I1)
    RP, v_z == 0:  P(q3) = v.g + t1_z - p'_z  (I2);  then q2^2 + 2 (g_z + u_z) q2 + |g + u|^2 - |p'|^2 = 0
    PP (e = R1 e3): q1 e3 + q2 e + (R1 g + t1 - p') = 0;  P(q3) = (e x k)_z, k = R1 g + t1 - p';
                    q2 = -(e_xy . k_xy) / |e_xy|^2

Degrees and roots: g, |g|^2, kappa_i, d_i are trigonometric polynomials of degree 1 in q3 (revolute) or
polynomials of degree <= 2 (prismatic), so P is a trigonometric polynomial of degree <= 2 (a quartic in
z = e^{i q3} = (1 + i tan(q3/2)) / (1 - i tan(q3/2)), which unlike tan(q3/2) has no root at infinity when
q3 = pi) or a polynomial of degree <= 4. Its coefficients are recovered exactly (up to rounding) from 5
samples: a 5-point DFT, or a Vandermonde solve at Chebyshev nodes in [-s, s]. Roots come from
numpy.roots (companion eigenvalues). Then q2 from (B)/(B'), and q1 from (I): revolute
q1 = atan2(p'_y, p'_x) - atan2(f_y, f_x), prismatic q1 = p'_z - f_z.

Reversal: (F') is equivalent to w = Z3(-q3) M2^-1 Z2(-q2) M1^-1 Z1(-q1) p', the same form with
(p', M1, M2, w) -> (w, M2^-1, M1^-1, p'). Solving it "backward" eliminates q2 between the axes 2 and 3
and leaves a polynomial in q1; it is used when axes 2-3 (not 1-2) allow the reduced form.

Kinds (``classify``): all revolute -> "3R-parallel" (axes 2-3, else 1-2, parallel; e.g. the planar
elbow of a leg), "3R-intersecting" (axes 1-2, else 2-3, intersect), "3R-general-quartic" (both pairs
skew). Otherwise the joint pattern, "PRR", "RPR", "RRP", "PPR", "PRP", "RPP" or "PPP". ValueError when
the tool point cannot be placed in 3D (position Jacobian of rank < 3 at every probe configuration:
planar chains, coincident axes, concurrent axes, tool point on axis 3, ...), for a row count other than
3, a sigma other than 0/1, or an unknown convention.

Tolerances (s = length scale: sum of |lengths| in the table + |tool origin|, at least |p'|; 1 if zero)
  ANGLE_TOL    1e-9  |sin| (parallel) or |cos| (perpendicular) between two axes
  LENGTH_TOL   1e-9  * s, distance between two axes counted as zero (intersect / coincide)
  RANK_TOL     1e-9  smallest singular value of the position Jacobian (revolute columns / s)
  TRIM_TOL     1e-11 relative to the largest coefficient: a leading coefficient counts as zero
  ROOT_TOL     1e-2  ||z| - 1| (revolute) or |Im x| / max(1, |x|) (prismatic, x = q / s): the root is
               projected to the real set (angle of z, real part) and tried. Loose on purpose: a double
               root splits off the real set by ~sqrt(eps), and a near-degenerate quartic (axes that
               almost intersect) clusters its roots much worse; the residual test below decides
  RATIO_TOL    1e-6  acos ratios within 1 + tol and discriminants within -tol s^2 are clamped
  RESIDUAL_TOL 1e-9  * s, |fk(q) - p| after polishing: the candidate is a solution
  MERGE_TOL    1e-6  max joint distance (rad, or length / s): two solutions are one (merged to
               their mean, so a double root comes back once and centred)
Each candidate gets up to NEWTON_STEPS Gauss-Newton steps (least squares on the 3x3 position Jacobian
of ``chain.jacobian``), a step kept only when it lowers the residual. A double root (target on the
workspace boundary) is only defined by the target to ~sqrt(eps / curvature of the fold) in q (1e-8 for
the Spot leg, up to ~1e-5 on flat folds); its residual stays ~eps.

Targets for which a joint is free (the tool point on axis 2, the target on axis 1 of a revolute joint)
give one representative with that joint at 0 (or whatever the back-substitution yields).

Output slots: solutions sorted lexicographically by (q1, q2, q3) after wrapping revolute angles to
(-pi, pi] (prismatic values divided by s), where values within ORDER_TIE count as equal (an angle
within ORDER_TIE of -pi counts as +pi), NaN-padded to 4 rows; more than 4 (never seen) keeps the 4
smallest residuals. Without the tie, two solutions sharing q1 (as every pair from one q1 does in the
degree-2 kinds) would be ordered by the rounding of q1. The C++ compares "diamond" pseudo-angles
(order_key below: monotone in the angle, slope 1/2 to 1) rather than angles; the order is the same
up to where a tie falls.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from spotkin.reference import chain as ref_chain
from spotkin.reference.leg import wrap_angle

ANGLE_TOL = 1e-9
LENGTH_TOL = 1e-9
RANK_TOL = 1e-9
TRIM_TOL = 1e-11
ROOT_TOL = 1e-2
RATIO_TOL = 1e-6
RESIDUAL_TOL = 1e-9
MERGE_TOL = 1e-6
NEWTON_STEPS = 6

# Generic probe configurations for the rank test (prismatic entries are multiplied by s).
_PROBES = ((0.7, -1.9, 2.4), (-2.2, 0.5, -0.8), (1.3, 2.9, -2.6))
_E3 = np.array([0.0, 0.0, 1.0])


def _check(rows, convention):
    if convention not in ("mdh", "dh"):
        raise ValueError(f"convention must be 'mdh' or 'dh', got {convention!r}")
    rows = np.asarray(rows, dtype=float)
    if rows.shape != (3, 5):
        raise ValueError(f"a 3-joint table (3, 5) is required, got shape {rows.shape}")
    if not np.all(np.isfinite(rows)):
        raise ValueError("the DH table has non-finite entries")
    if not np.all(np.isin(rows[:, 0], (0.0, 1.0))):
        raise ValueError("sigma must be 0 (revolute) or 1 (prismatic)")
    return rows


def _split(rows, convention, base, tool):
    """M0, M1, M2 (4x4) and w (3,) of eq. (F)."""
    B = np.eye(4) if base is None else np.asarray(base, dtype=float)
    Tt = np.eye(4) if tool is None else np.asarray(tool, dtype=float)
    T0 = [ref_chain.joint_transform(row, convention, 0.0) for row in rows]
    if convention == "mdh":
        return B @ T0[0], T0[1], T0[2], Tt[:3, 3].copy()
    return B, T0[0], T0[1], (T0[2] @ Tt)[:3, 3]


def _scale(rows, tool):
    s = float(np.sum(np.abs(rows[:, 1])) + np.sum(np.abs(rows[:, 3])))
    if tool is not None:
        s += float(np.linalg.norm(np.asarray(tool, dtype=float)[:3, 3]))
    return s if s > 0.0 else 1.0


def _check_rank(rows, convention, tool, s):
    """ValueError unless the position Jacobian has rank 3 at some probe configuration."""
    sig = rows[:, 0]
    best = 0.0
    for probe in _PROBES:
        q = [v * s if sj else v for v, sj in zip(probe, sig)]
        J = ref_chain.jacobian(rows, convention, q, None, tool)[:3]
        J = J / np.where(sig == 0, s, 1.0)  # revolute columns carry a length
        best = max(best, float(np.linalg.svd(J, compute_uv=False)[-1]))
    if best <= RANK_TOL:
        raise ValueError(
            "no closed form: the tool point of this chain cannot be placed in 3D (position Jacobian rank "
            "< 3 everywhere; e.g. planar or coincident/concurrent axes, or the tool point on axis 3)"
        )


def _relation(M, s):
    """Axis z of the current frame vs axis z of frame M: parallel/coincident/intersecting/skew."""
    t, z = M[:3, 3], M[:3, 2]
    cross = np.array([-z[1], z[0], 0.0])  # e3 x z
    sin = float(np.linalg.norm(cross))
    if sin <= ANGLE_TOL:
        return "coincident" if math.hypot(t[0], t[1]) <= LENGTH_TOL * s else "parallel"
    return "intersecting" if abs(float(t @ cross)) / sin <= LENGTH_TOL * s else "skew"


def _reduces(sa, sb, M, s):
    """Whether the pair (joint a, joint b = next) gives the reduced equation (Q')."""
    if sa == 1 and sb == 1:
        return True  # PP: always degree <= 2
    if sa != sb:
        return abs(float(M[2, 2])) <= ANGLE_TOL  # PR / RP: perpendicular axes
    return _relation(M, s) in ("parallel", "intersecting")


def _plan(rows, convention, tool):
    """(kind, direction, reduced, s)."""
    rows = _check(rows, convention)
    s = _scale(rows, tool)
    _check_rank(rows, convention, tool, s)
    _, M1, M2, _ = _split(rows, convention, None, tool)
    sig = tuple(int(v) for v in rows[:, 0])
    if sig == (0, 0, 0):
        r12, r23 = _relation(M1, s), _relation(M2, s)
        if r23 == "parallel":
            return "3R-parallel", "backward", True, s
        if r12 == "parallel":
            return "3R-parallel", "forward", True, s
        if r12 == "intersecting":
            return "3R-intersecting", "forward", True, s
        if r23 == "intersecting":
            return "3R-intersecting", "backward", True, s
        return "3R-general-quartic", "forward", False, s
    kind = "".join("RP"[v] for v in sig)
    if _reduces(sig[0], sig[1], M1, s):
        return kind, "forward", True, s
    if _reduces(sig[2], sig[1], np.linalg.inv(M2), s):
        return kind, "backward", True, s
    return kind, "forward", False, s


def classify(rows, convention, tool=None):
    """Name of the closed form used for this chain (see the module docstring); ValueError if none."""
    return _plan(rows, convention, tool)[0]


def _z_apply(sigma, q, x):
    """Z(q) x: RotZ(q) x (revolute) or x + q e3 (prismatic)."""
    if sigma == 0:
        c, sn = math.cos(q), math.sin(q)
        return np.array([c * x[0] - sn * x[1], sn * x[0] + c * x[1], x[2]])
    return np.array([x[0], x[1], x[2] + q])


def _cos_sin_roots(a, b, rhs):
    """x with a cos x + b sin x = rhs: atan2(b, a) +- acos(rhs / hypot(a, b))."""
    R = math.hypot(a, b)
    if R == 0.0:
        return [0.0]  # x is free (or there is no solution: the residual check decides)
    ratio = rhs / R
    if abs(ratio) > 1.0 + RATIO_TOL:
        return []
    phi, alpha = math.atan2(b, a), math.acos(min(1.0, max(-1.0, ratio)))
    return [phi + alpha, phi - alpha]


def _poly_roots(P, sigma, s):
    """Real roots of P, a trig polynomial of degree <= 2 (revolute) or polynomial of degree <= 4."""
    if sigma == 0:
        theta = 2.0 * math.pi * np.arange(5) / 5.0
        vals = np.array([P(t) for t in theta])
        # c[m + 2] = coefficient of e^{i m q3}, m = -2..2 (5-point DFT, exact for degree <= 2)
        c = np.array([np.sum(vals * np.exp(-1j * m * theta)) / 5.0 for m in range(-2, 3)])
        top = float(np.max(np.abs(c)))
        deg = 2
        while deg > 0 and abs(c[deg + 2]) <= TRIM_TOL * top:
            deg -= 1
        if deg == 0:
            return [0.0]  # P constant: q3 free or no solution; the residual check decides
        # z^deg P = sum_{m=-deg}^{deg} c_m z^{m + deg}; numpy.roots wants the highest power first
        z = np.roots(c[2 - deg : 3 + deg][::-1])
        return [float(np.angle(zi)) for zi in z if abs(abs(zi) - 1.0) <= ROOT_TOL]
    x = np.cos(math.pi * np.arange(5) / 4.0)  # Chebyshev extrema, q3 = s x
    vals = np.array([P(s * xi) for xi in x])
    c = np.linalg.solve(np.vander(x, 5, increasing=True), vals)
    top = float(np.max(np.abs(c)))
    deg = 4
    while deg > 0 and abs(c[deg]) <= TRIM_TOL * top:
        deg -= 1
    if deg == 0:
        return [0.0]
    r = np.roots(c[deg::-1])
    return [s * float(ri.real) for ri in r if abs(ri.imag) <= ROOT_TOL * max(1.0, abs(ri))]


def _solve_forward(sig, target, M1, M2, w, reduced, s):
    """Candidates (q1, q2, q3) of target = Z1(q1) M1 Z2(q2) M2 Z3(q3) w, eqs. (I), (L)-(B')."""
    R1, t1, R2, t2 = M1[:3, :3], M1[:3, 3], M2[:3, :3], M2[:3, 3]
    u, v = R1.T @ t1, R1[2]
    pp = float(target @ target)

    def g_of(q3):
        return R2 @ _z_apply(sig[2], q3, w) + t2

    if sig[1] == 0:  # revolute q2: eq. (L)
        if sig[0] == 0:
            r_a, r_b = u, v

            def kappa(g):
                return np.array([(pp - g @ g - t1 @ t1) / 2.0, target[2] - t1[2]])

        else:
            r_a, r_b = R1[0], R1[1]

            def kappa(g):
                return np.array([target[0] - t1[0], target[1] - t1[1]])

        Rr = np.array([[r_a[0], r_a[1]], [r_b[0], r_b[1]]])
        adj = np.array([[Rr[1, 1], -Rr[0, 1]], [-Rr[1, 0], Rr[0, 0]]])
        det = float(np.linalg.det(Rr))

        def d_of(g):
            return kappa(g) - np.array([r_a[2], r_b[2]]) * g[2]

        if not reduced:

            def P(q3):  # eq. (Q)
                g = g_of(q3)
                ad = adj @ d_of(g)
                return ad @ ad - det * det * (g[0] ** 2 + g[1] ** 2)

            def back(q3):  # eq. (B)
                g = g_of(q3)
                y = adj @ d_of(g) / det
                return [math.atan2(y[1], y[0]) - math.atan2(g[1], g[0])]

        else:
            n = adj[int(np.argmax(np.linalg.norm(adj, axis=1)))]
            i = int(np.argmax(np.linalg.norm(Rr, axis=1)))

            def P(q3):  # eq. (Q')
                return n @ d_of(g_of(q3))

            def back(q3):  # eq. (B')
                g = g_of(q3)
                a = Rr[i, 0] * g[0] + Rr[i, 1] * g[1]
                b = Rr[i, 1] * g[0] - Rr[i, 0] * g[1]
                return _cos_sin_roots(a, b, d_of(g)[i])

    elif sig[0] == 0:  # RP
        if not reduced:

            def q2_of(g):
                return (target[2] - t1[2] - v @ g) / v[2]

            def P(q3):
                g = g_of(q3)
                h = g + q2_of(g) * _E3 + u
                return h @ h - pp

            def back(q3):
                return [q2_of(g_of(q3))]

        else:

            def P(q3):
                return v @ g_of(q3) + t1[2] - target[2]

            def back(q3):
                g = g_of(q3)
                b, c = g[2] + u[2], (g + u) @ (g + u) - pp
                disc = b * b - c
                if disc < -RATIO_TOL * s * s:
                    return []
                root = math.sqrt(max(disc, 0.0))
                return [-b + root, -b - root]

    else:  # PP
        e = R1[:, 2]
        e2 = e[0] ** 2 + e[1] ** 2

        def P(q3):
            k = R1 @ g_of(q3) + t1 - target
            return e[0] * k[1] - e[1] * k[0]

        def back(q3):
            k = R1 @ g_of(q3) + t1 - target
            return [-(e[0] * k[0] + e[1] * k[1]) / e2]

    out = []
    for q3 in _poly_roots(P, sig[2], s):
        g = g_of(q3)
        for q2 in back(q3):
            f = R1 @ _z_apply(sig[1], q2, g) + t1
            if sig[0] == 0:
                q1 = math.atan2(target[1], target[0]) - math.atan2(f[1], f[0])
            else:
                q1 = target[2] - f[2]
            out.append(np.array([q1, q2, q3]))
    return out


def _polish(rows, convention, q, p, base, tool):
    """Up to NEWTON_STEPS Gauss-Newton steps on fk(q) = p; returns (q, |fk(q) - p|)."""
    r = ref_chain.fk(rows, convention, q, base, tool)[:3, 3] - p
    res = float(np.linalg.norm(r))
    for _ in range(NEWTON_STEPS):
        J = ref_chain.jacobian(rows, convention, q, base, tool)[:3]
        q_new = q - np.linalg.lstsq(J, r, rcond=None)[0]
        r_new = ref_chain.fk(rows, convention, q_new, base, tool)[:3, 3] - p
        res_new = float(np.linalg.norm(r_new))
        if not res_new < res:
            break
        q, r, res = q_new, r_new, res_new
    return q, res


def _distance(qa, qb, sig, s):
    return max(abs(wrap_angle(a - b)) if sj == 0 else abs(a - b) / s for a, b, sj in zip(qa, qb, sig))


def _mean(group, sig):
    out = []
    for j, sj in enumerate(sig):
        vals = [q[j] for q in group]
        if sj == 0:
            out.append(wrap_angle(math.atan2(sum(map(math.sin, vals)), sum(map(math.cos, vals)))))
        else:
            out.append(sum(vals) / len(vals))
    return np.array(out)


ORDER_TIE = 1e-7  # slot order: values this close count as equal


def order_key(value, sigma_j, s):
    """Sort key of one joint value: the diamond pseudo-angle of a revolute angle, in (-2, 2]
    (increasing with the angle over (-pi, pi]; within ORDER_TIE of -pi counts as +pi), or v / s."""
    if sigma_j == 1:
        return value / s
    c, sn = math.cos(value), math.sin(value)
    t = sn / (abs(c) + abs(sn))
    key = t if c >= 0.0 else (2.0 - t if sn >= 0.0 else -2.0 - t)
    return 2.0 if key <= -2.0 + ORDER_TIE else key


def _order(qa, qb, sig, s):
    """-1, 0 or 1: qa before qb lexicographically on order_key, ties within ORDER_TIE."""
    for a, b, sj in zip(qa, qb, sig):
        ka, kb = order_key(a, sj, s), order_key(b, sj, s)
        if abs(ka - kb) > ORDER_TIE:
            return -1 if ka < kb else 1
    return 0


def solve_position(rows, convention, p, base=None, tool=None):
    """Every real q with fk(q)[:3, 3] = p for a 3-joint chain.

    Returns (q_all (4, 3) NaN-padded, valid (4,) bool, kind). Slots are sorted by (q1, q2, q3),
    revolute angles wrapped to (-pi, pi]. ValueError for structures without a closed form here.
    """
    kind, direction, reduced, s_chain = _plan(rows, convention, tool)
    rows = np.asarray(rows, dtype=float)
    sig = tuple(int(v) for v in rows[:, 0])
    q_all, valid = np.full((4, 3), np.nan), np.zeros(4, dtype=bool)
    p = np.asarray(p, dtype=float).reshape(3)
    if not np.all(np.isfinite(p)):
        return q_all, valid, kind

    M0, M1, M2, w = _split(rows, convention, base, tool)
    target = (np.linalg.inv(M0) @ np.append(p, 1.0))[:3]
    s = max(s_chain, float(np.linalg.norm(target)))
    if direction == "forward":
        cands = _solve_forward(sig, target, M1, M2, w, reduced, s)
    else:  # reversed chain (see "Reversal"): returns (-q3, -q2, -q1)
        back = _solve_forward(sig[::-1], w, np.linalg.inv(M2), np.linalg.inv(M1), target, reduced, s)
        cands = [-c[::-1] for c in back]

    sols = []  # (residual, q)
    for q in cands:
        q, res = _polish(rows, convention, q, p, base, tool)
        if res <= RESIDUAL_TOL * s:
            q = np.array([wrap_angle(v) if sj == 0 else v for v, sj in zip(q, sig)])
            sols.append((res, q))
    sols.sort(key=lambda t: t[0])

    groups = []  # merge within MERGE_TOL, best residual first
    for res, q in sols:
        for grp in groups:
            if _distance(q, grp[0][1], sig, s) <= MERGE_TOL:
                grp.append((res, q))
                break
        else:
            groups.append([(res, q)])
    merged = []
    for grp in groups:
        q = _mean([q for _, q in grp], sig)
        res = float(np.linalg.norm(ref_chain.fk(rows, convention, q, base, tool)[:3, 3] - p))
        merged.append((res, q) if res <= RESIDUAL_TOL * s else grp[0])
    merged = sorted(merged, key=lambda t: t[0])[:4]

    qs = sorted((q for _, q in merged), key=functools.cmp_to_key(lambda a, b: _order(a, b, sig, s)))
    for k, q in enumerate(qs):
        q_all[k], valid[k] = q, True
    return q_all, valid, kind
