"""Reference kinematics of a generalised roll-pitch-pitch (RPP) leg, one sample at a time.

Slow and obvious on purpose: the C++ kernels are tested against these functions.

Model (metres, radians)
-----------------------
Leg frame: origin at the hip-roll joint, axes parallel to the body frame. With o1 = 0, o2, o3 the
joint origins and f the foot, all at zero angles:

    a = o2 - o1,   b = o3 - o2,   c = f - o3,

joint axes s1 x, s2 y, s3 y (signs s_k = +-1), model angles theta_k = s_k q_k, and

    (R1)  p = Rx(theta1) ( a + Ry(theta2) ( b + Ry(theta3) c ) ),

    Rx(t) = [[1, 0, 0], [0, cos t, -sin t], [0, sin t, cos t]],
    Ry(t) = [[cos t, 0, sin t], [0, 1, 0], [-sin t, 0, cos t]].

Two complex coordinates make the rotations products:

    (R2)  zeta(u) = u_z + i u_x   (Ry(t) multiplies zeta by e^{it}, leaves u_y alone),
          eta(u)  = u_y + i u_z   (Rx(t) multiplies eta  by e^{it}, leaves u_x alone).

A geometry is a mapping (or any object with these attributes) with keys ``a``, ``b``, ``c`` (3-vectors)
and ``signs`` (three +-1; optional, default (1, 1, 1)); ``RppGeometry`` below is one. Spot's front
left leg: a = (0, 0.110945, 0), b = (0.025, 0, -0.3205), c = (0, 0, -0.3365), signs (1, 1, 1).

Jacobian
--------
    (J1)  dp/dq1 = s1 x^ x p,
          dp/dq2 = s2 Rx(theta1) (y^ x u2),   u2 = Ry(theta2) (b + Ry(theta3) c),
          dp/dq3 = s3 Rx(theta1) (y^ x u3),   u3 = Ry(theta2 + theta3) c.

The two pitch columns lie in the plane normal to Rx(theta1) y^; they are parallel exactly when the
knee is straight or folded (psi = 0 or pi below), and otherwise det J = 0 exactly when
(x^ x p) . Rx(theta1) y^ = -v_z = 0 (the hip-roll singular set, v below).

Inverse kinematics (closed form)
--------------------------------
(I1) Hip roll. v = Rx(theta1)^T p has v_y = h := a_y + b_y + c_y (Ry leaves y alone), so
         y cos theta1 + z sin theta1 = h   (Paul type 2).
     With r^2 = y^2 + z^2, S = sqrt(r^2 - h^2) (no solution if r < |h|) and eps = +1 (hip branch 0,
     "normal") or -1 (hip branch 1, "flipped"):
         cos theta1 = (y h - eps z S) / r^2,   sin theta1 = (z h + eps y S) / r^2,
     i.e. e^{i theta1} = eta(p) (h + i eps S) / r^2, which gives v_z = -eps S. If r = 0 (only
     possible with h = 0), theta1 = 0.
(I2) Pitch plane. W := zeta(v - a) = (v_z - a_z) + i (x - a_x) and, from (R1) and (R2),
         W = e^{i theta2} (B + e^{i theta3} C),   B = zeta(b),  C = zeta(c).
(I3) Knee. |W|^2 = |B|^2 + |C|^2 + 2 |B| |C| cos psi with psi = theta3 + phi,
     phi = arg C - arg B. Knee branch 0 ("knee back"): psi = -acos(ratio) (sin psi <= 0);
     knee branch 1 ("knee forward"): psi = +acos(ratio); ratio = (|W|^2 - |B|^2 - |C|^2) /
     (2 |B| |C|), no solution if |ratio| > 1. When a_z != 0, |W|^2 depends on the hip branch
     (through v_z = -eps S), so existence is decided per hip branch: the two knee slots of one hip
     branch exist together.
(I4) Hip pitch. theta2 = arg(W conj(D)), D = B + e^{i theta3} C.
(I5) q_k = s_k theta_k, each wrapped to (-pi, pi]. Slot order: slot = 2 * hip_branch + knee_branch.
Ratios within 1e-12 of the singular sets (r = |h|, |ratio| = 1) are clamped onto them. Geometries
with B = 0 or C = 0 (b or c along y) are not RPP legs in the sense used here and have no solutions.

Nearest foot within joint limits
--------------------------------
nearest_in_limits minimises f(q) = |fk(q) - p|^2 over the box of joint limits, exactly: the
minimiser is a KKT point, so each joint is either at a "fixed value" (a bound) or free with
df/dq_k = 0, and each combination reduces to a small closed-form or polynomial problem:

(K1) One joint free, the others fixed: the foot runs on a circle about that joint's axis, and
     |fk - p|^2 = const - 2 A cos(t - t0) has a single local minimum on the circle, the aligned
     angle t0 (nearest point of the circle, in closed form by (R2)).
(K2) Both pitch joints free, roll fixed: a planar 2R arm in a fixed plane. df = 0 for both joints
     means that the in-plane residual is parallel both to the foot seen from the hip-pitch joint
     and to the lower link, so either the in-plane projection of p is reached exactly ((I3)-(I4)
     on it) or the two links are parallel, i.e. the knee is singular (psi = 0 or pi), with
     theta2 aligned: (K1) with the knee at its singular value.
(K3) Roll and one pitch joint free, the other pitch joint fixed (or the knee at a singular value,
     see (K5)): the foot lies on the "roll torus" {Rx(theta1) (m + Ry(alpha) n)}: theta2 free:
     m = a, n = b + Ry(theta3) c, alpha = theta2; theta3 free: m = a + Ry(theta2) b, n = c,
     alpha = theta2 + theta3. With zeta(n) = r e^{i gamma} and beta = alpha + gamma,
         m + Ry(alpha) n = (m_x + r sin beta,  h',  w),  h' = m_y + n_y,  w = m_z + r cos beta.
     For a fixed beta the best theta1 aligns eta = h' + i w with eta(p) (K1), leaving
         (T1)  F(beta) = (X - r sin beta)^2 + (rho - s)^2,
               X = x - m_x, rho = hypot(y, z), s = sqrt(h'^2 + w^2),
     and a local minimum of the face is one of F (envelope argument: theta1 is the aligned one).
     F'(beta) = 0 reads, after multiplying by s / r,
         (T2)  s (X cos beta + m_z sin beta) = rho (m_z + r cos beta) sin beta.
     Squaring and t = tan(beta / 2) (times (1 + t^2)^4) give the degree-8 polynomial
         (T3)  (h'^2 (1 + t^2)^2 + W2^2) L2^2 - 4 rho^2 t^2 W2^2 = 0,
               W2 = (m_z + r) + (m_z - r) t^2,   L2 = X + 2 m_z t - X t^2.
     Its real roots contain every stationary point (and spurious ones of the other sign of s,
     which are harmless: every candidate is evaluated with the true FK). The roots with
     |t| <= 1 cover |beta| <= pi/2; the same polynomial with r -> -r, in beta' = beta - pi, covers
     the other half, so beta = pi needs no special case and no root is ever at infinity (each
     chart is searched to |t| <= 1 + 1/64, so roots at t = +-1 are not lost to rounding). (T3)
     is homogeneous of degree 8 in the lengths X, h', m_z, r, rho, which are scaled to a largest
     of 1 first. Stationary points can be double roots of (T3) (s = 0, i.e. h' = w = 0; rho = 0;
     rho = h' with m_z = 0 at beta = +-pi/2, a target on the hip-roll cylinder), so the roots of
     its derivative are candidates too: at a root of any multiplicity, (T3) or its derivative
     changes sign.
(K4) All joints free. grad f = 2 J^T (fk - p) = 0: either fk = p (the IK, (I1)-(I5)), or J is
     singular (J1): knee singular (K5), or hip-roll singular, v_z = 0. In the latter case, the
     pitch columns spanning the rotated xz plane, the residual must be parallel to Rx(theta1) y^:
     the foot is (x, h, 0) in the rotated frame (same x as p) and Rx(theta1)^T p has zero z, so
     theta1 = arg eta(p) or arg eta(p) + pi, and the pitch plane reaches W = -a_z + i (x - a_x)
     exactly ((I3)-(I4)). A foot on the line v_z = 0 with x != p_x is stationary only with a
     singular knee, which (K5) covers.
(K5) The knee's singular values psi = 0, pi (theta3 = -phi, pi - phi), where they lie within the
     knee's limits, count as fixed values of the knee: at psi = 0 or pi the knee column is
     parallel to the hip-pitch column, so df/dq2 = 0 implies df/dq3 = 0, and every stationary
     point with a singular knee is one with the knee "fixed" there.
The enumeration itself is written out step by step in nearest_in_limits.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as npoly

_RATIO_TOL = 1e-12  # |ratio| <= 1 + tol counts as touching a singular set
_LIMIT_TOL = 1e-12  # rad, tolerance on joint limits
_TIE_TOL = 1e-12  # m, distances closer than this are ties
_SLOT_TOL = 1e-9  # v_z (m) and sin psi up to this count as branch 0 (the singular sets are ties)
_ROOT_IMAG_TOL = 1e-6  # |Im t| up to this counts as a real root (a candidate, checked by its FK)
_CHART_REACH = 1.0 + 1.0 / 64.0  # each chart of (T3) is searched a little past |t| = 1
TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class RppGeometry:
    """a = o2 - o1, b = o3 - o2, c = f - o3 at zero angles (leg frame), signs of the axes s1 x, s2 y,
    s3 y. Spot's front left leg by default."""

    a: tuple = (0.0, 0.110945, 0.0)
    b: tuple = (0.025, 0.0, -0.3205)
    c: tuple = (0.0, 0.0, -0.3365)
    signs: tuple = (1.0, 1.0, 1.0)


def _unpack(geometry):
    """(a, b, c, signs) as float arrays from a mapping or an object with those attributes."""
    if isinstance(geometry, Mapping):
        get = geometry.get
    else:

        def get(key, default=None):
            return getattr(geometry, key, default)

    a, b, c = (np.asarray(get(key), dtype=float).reshape(3) for key in ("a", "b", "c"))
    signs = np.asarray(get("signs", (1.0, 1.0, 1.0)), dtype=float).reshape(3)
    return a, b, c, signs


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _zeta(u):
    """zeta(u) = u_z + i u_x, eq. (R2)."""
    return complex(float(u[2]), float(u[0]))


def _eta(u):
    """eta(u) = u_y + i u_z, eq. (R2)."""
    return complex(float(u[1]), float(u[2]))


def _arg(w):
    return math.atan2(w.imag, w.real)


def wrap_angle(t):
    """Wrap an angle to (-pi, pi]."""
    t = math.remainder(t, TWO_PI)  # in [-pi, pi]
    if t <= -math.pi:
        t += TWO_PI
    return t


def _leg_point(a, b, c, theta):
    """u = a + Ry(theta2) (b + Ry(theta3) c): the foot in the hip-roll-rotated frame."""
    return a + _ry(theta[1]) @ (b + _ry(theta[2]) @ c)


def fk(geometry, q):
    """Foot in the leg frame, eq. (R1)."""
    a, b, c, s = _unpack(geometry)
    theta = s * np.asarray(q, dtype=float).reshape(3)
    return _rx(theta[0]) @ _leg_point(a, b, c, theta)


def jacobian(geometry, q):
    """d foot / d q (3x3) from the geometric Jacobian, eq. (J1)."""
    a, b, c, s = _unpack(geometry)
    theta = s * np.asarray(q, dtype=float).reshape(3)
    R1 = _rx(theta[0])
    p = R1 @ _leg_point(a, b, c, theta)
    y_hat = np.array([0.0, 1.0, 0.0])
    u2 = _ry(theta[1]) @ (b + _ry(theta[2]) @ c)
    u3 = _ry(theta[1] + theta[2]) @ c
    return np.column_stack(
        [
            s[0] * np.cross([1.0, 0.0, 0.0], p),
            s[1] * (R1 @ np.cross(y_hat, u2)),
            s[2] * (R1 @ np.cross(y_hat, u3)),
        ]
    )


def _hip_roll(y, z, h, eps):
    """(theta1, v_z) of eq. (I1) for branch eps = +1 / -1, or None when r < |h|."""
    r = math.hypot(y, z)
    if r == 0.0:
        return (0.0, 0.0) if h == 0.0 else None
    ratio = h / r
    if abs(ratio) > 1.0 + _RATIO_TOL:
        return None
    sr = math.sqrt(max(0.0, 1.0 - ratio * ratio))  # S / r, written so that r^2 cannot overflow
    cos1 = (y / r) * ratio - eps * (z / r) * sr
    sin1 = (z / r) * ratio + eps * (y / r) * sr
    return math.atan2(sin1, cos1), -eps * r * sr


def _planar_ik(W, B, C):
    """[(theta2, theta3) for knee branch 0, 1] reaching W = e^{i theta2} (B + e^{i theta3} C),
    eqs. (I3)-(I4); [] when |ratio| > 1 (or B = 0 or C = 0)."""
    nB, nC = abs(B), abs(C)
    if nB == 0.0 or nC == 0.0:
        return []
    ratio = (abs(W) * abs(W) - nB * nB - nC * nC) / (2.0 * nB * nC)
    if abs(ratio) > 1.0 + _RATIO_TOL:
        return []
    acos = math.acos(min(1.0, max(-1.0, ratio)))
    phi = _arg(C) - _arg(B)
    out = []
    for psi in (-acos, acos):
        theta3 = psi - phi
        D = B + cmath.exp(1j * theta3) * C
        out.append((_arg(W * D.conjugate()), theta3))
    return out


def ik_all(geometry, p):
    """All closed-form IK branches, eqs. (I1)-(I5).

    Returns (q_all (4, 3), exists (4,) bool); rows are slots 2 * hip_branch + knee_branch, NaN where
    the branch does not exist.
    """
    a, b, c, s = _unpack(geometry)
    q_all = np.full((4, 3), np.nan)
    exists = np.zeros(4, dtype=bool)
    x, y, z = (float(v) for v in np.asarray(p, dtype=float).reshape(3))
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return q_all, exists
    h = a[1] + b[1] + c[1]
    B, C = _zeta(b), _zeta(c)
    for hip_branch, eps in enumerate((1.0, -1.0)):
        hip = _hip_roll(y, z, h, eps)
        if hip is None:
            continue
        theta1, v_z = hip
        W = complex(v_z - a[2], x - a[0])
        for knee_branch, (theta2, theta3) in enumerate(_planar_ik(W, B, C)):
            slot = 2 * hip_branch + knee_branch
            q_all[slot] = [wrap_angle(s[k] * t) for k, t in enumerate((theta1, theta2, theta3))]
            exists[slot] = True
    return q_all, exists


def _limited(lo, hi):
    """Whether a joint with limits [lo, hi] is limited on the circle (finite, range < 2 pi)."""
    return math.isfinite(lo) and math.isfinite(hi) and hi - lo < TWO_PI


def into_range(q, lo, hi):
    """The angle congruent to q (mod 2 pi) inside [lo, hi], or None (also for a non-finite q).

    A joint whose range is 2 pi or more (or infinite) is unconstrained on the circle: the result is
    wrap_angle(q) when that lies in [lo, hi], else the representative in [lo, lo + 2 pi) (or in
    (hi - 2 pi, hi] when lo = -inf). A limited joint accepts q within 1e-12 of its limits, clamped.
    """
    if not math.isfinite(q):
        return None
    if not _limited(lo, hi):
        w = wrap_angle(q)
        if lo <= w <= hi:
            return w
        if math.isfinite(lo):
            return lo + (w - lo) % TWO_PI
        return hi - (hi - w) % TWO_PI
    k = lo - _LIMIT_TOL + (q - lo + _LIMIT_TOL) % TWO_PI  # in [lo - tol, lo - tol + 2 pi)
    if k <= hi + _LIMIT_TOL:
        return min(max(k, lo), hi)
    return None


def _newton(poly, t, steps=4):
    """t after a few Newton steps on poly (low-to-high coefficients); eigenvalues give near-double
    roots only to ~1e-8, so both the root and its polished value are candidates."""
    dpoly = npoly.polyder(poly)
    for _ in range(steps):
        slope = float(npoly.polyval(t, dpoly))
        if slope == 0.0 or not abs(t) <= 2.0:
            break
        t -= float(npoly.polyval(t, poly)) / slope
    return t


def _torus_stationary(m, n, p):
    """(theta1, alpha) candidates on the roll torus {Rx(theta1) (m + Ry(alpha) n)}, eqs. (T1)-(T3)."""
    x, y, z = (float(v) for v in p)
    X, h_, mz = x - m[0], m[1] + n[1], m[2]
    r, gamma = abs(_zeta(n)), _arg(_zeta(n))
    rho = math.hypot(y, z)
    # (T3) is homogeneous (degree 8) in the lengths: scaled to 1, its roots are unchanged and
    # its coefficients cannot overflow.
    scale = max(abs(X), abs(h_), abs(mz), r, rho)
    if scale == 0.0:
        return []
    Xs, hs, mzs, rs, rhos = X / scale, h_ / scale, mz / scale, r / scale, rho / scale
    betas = []
    for offset, rr in ((0.0, rs), (math.pi, -rs)):  # chart |beta| <= pi/2, then beta = pi + beta'
        Q = [1.0, 0.0, 1.0]
        W2 = [mzs + rr, 0.0, mzs - rr]
        L2 = [Xs, 2.0 * mzs, -Xs]
        lhs = npoly.polymul(
            npoly.polyadd(hs * hs * npoly.polymul(Q, Q), npoly.polymul(W2, W2)), npoly.polymul(L2, L2)
        )
        rhs = npoly.polymul([0.0, 0.0, 4.0 * rhos * rhos], npoly.polymul(W2, W2))
        P8 = npoly.polysub(lhs, rhs)
        for poly in (P8, npoly.polyder(P8)):
            if not np.any(poly):
                continue
            for t in np.roots(poly[::-1]):
                if abs(t.imag) <= _ROOT_IMAG_TOL and abs(t.real) <= _CHART_REACH:
                    for t_cand in (float(t.real), _newton(poly, float(t.real))):
                        if abs(t_cand) <= _CHART_REACH:
                            betas.append(offset + 2.0 * math.atan(t_cand))
    out = []
    for beta in betas:
        w = mz + r * math.cos(beta)
        out.append((math.atan2(z, y) - math.atan2(w, h_), beta - gamma))
    return out


class _Best:
    """The nearest in-limit candidate so far; ties (within 1e-12 m) go to the lower slot of the
    candidate (2 * hip + knee, hip = 1 when v_z > 1e-9, knee = 1 when sin psi > 1e-9: on and near
    the singular sets, where the branches meet, both count as 0), then to the first offered."""

    def __init__(self, geometry, lower, upper, p):
        self.geometry, self.lower, self.upper, self.p = geometry, lower, upper, np.asarray(p, dtype=float)
        self.a, self.b, self.c, self.s = _unpack(geometry)
        self.phi = _arg(_zeta(self.c)) - _arg(_zeta(self.b))
        self.q, self.foot, self.d, self.slot = None, None, math.inf, 4

    def offer(self, theta1, theta2, theta3):
        q = []
        for k, t in enumerate((theta1, theta2, theta3)):
            qk = into_range(self.s[k] * t, self.lower[k], self.upper[k])
            if qk is None:
                return
            q.append(qk)
        q = np.array(q)
        foot = fk(self.geometry, q)
        d = math.hypot(*(foot - self.p))
        theta = self.s * q
        hip = 1 if _leg_point(self.a, self.b, self.c, theta)[2] > _SLOT_TOL else 0
        knee = 1 if math.sin(theta[2] + self.phi) > _SLOT_TOL else 0
        slot = 2 * hip + knee
        if d < self.d - _TIE_TOL or (d <= self.d + _TIE_TOL and slot < self.slot):
            self.q, self.foot, self.d, self.slot = q, foot, d, slot


def _bounds(lo, hi):
    """The bounds of a limited joint ([] for one unconstrained on the circle)."""
    if not _limited(lo, hi):
        return []
    return [lo] if lo == hi else [lo, hi]


def nearest_in_limits(geometry, lower, upper, p):
    """The configuration within the joint limits whose foot is nearest to p, exactly.

    Returns (q (3,), foot (3,)), q inside [lower, upper] (lower <= upper; a joint with a range of
    2 pi or more, or an infinite one, is unconstrained on the circle: see into_range); NaN for a
    non-finite p.
    Minimises |fk(q) - p|^2 over the box by enumerating its KKT candidates ((K1)-(K5) of the
    module docstring), all in model angles theta = s q, each kept only if every joint fits its
    limits (mod 2 pi, into_range) and scored by the distance of its true FK:

    (N0) p not finite: NaN.
    (N1) p reachable within the limits: the first slot of ik_all (0, 1, 2, 3) that fits the
         limits; distance 0.
    (N2) Fixed values: V1, V2 = the bounds of the hip roll and hip pitch (none for an unconstrained
         joint); V3 = the knee's bounds and its singular values theta3 = -phi, pi - phi (K5).
    (N3) Vertices: every (t1, t2, t3) in V1 x V2 x V3.
    (N4) Edges, one joint free (K1), the foot on a circle, nearest point by alignment:
         theta1 free, (t2, t3) in V2 x V3:  theta1 = arg eta(p) - arg eta(u), u = a + Ry(t2)(b + Ry(t3) c);
         theta2 free, (t1, t3) in V1 x V3:  theta2 = arg zeta(Rx(t1)^T p - a) - arg zeta(b + Ry(t3) c);
         theta3 free, (t1, t2) in V1 x V2:  theta3 = arg zeta(Ry(t2)^T (Rx(t1)^T p - a) - b) - arg zeta(c).
    (N5) Roll fixed, pitch joints free (K2): for t1 in V1, both knee branches of the planar IK
         (I3)-(I4) of W = zeta(Rx(t1)^T p - a), if it exists.
    (N6) Roll free, one pitch joint fixed (K3): for t3 in V3 the torus m = a, n = b + Ry(t3) c
         (theta2 = alpha); for t2 in V2 the torus m = a + Ry(t2) b, n = c (theta3 = alpha - t2). The
         real roots, |t| <= 1 + 1/64, of (T3) and of its derivative, in both charts (numpy.roots,
         |Im t| <= 1e-6, each also after 4 Newton steps), each with
         theta1 = arg eta(p) - atan2(w, h') and alpha = beta - gamma.
    (N7) All free, hip-roll singular (K4): theta1 = arg eta(p) and arg eta(p) + pi, both knee branches
         of the planar IK of W = -a_z + i (x - a_x).
    (N8) The nearest candidate; ties within 1e-12 m go to the lower slot (2 * hip + knee with
         hip = 1 when v_z > 1e-9 m, knee = 1 when sin psi > 1e-9, so that the singular sets, where
         branches meet, count as branch 0), then to the first in the order above.
    If no candidate fits (a degenerate geometry), every joint at its lower bound (0 for an
    unconstrained joint, mapped into its limits).
    """
    a, b, c, s = _unpack(geometry)
    lower = [float(v) for v in lower]
    upper = [float(v) for v in upper]
    p = np.asarray(p, dtype=float).reshape(3)
    if not np.all(np.isfinite(p)):
        return np.full(3, np.nan), np.full(3, np.nan)
    x = float(p[0])

    # (N1) exact IK within the limits
    q_all, exists = ik_all(geometry, p)
    for slot in range(4):
        if exists[slot]:
            q = [into_range(q_all[slot, k], lower[k], upper[k]) for k in range(3)]
            if all(v is not None for v in q):
                q = np.array(q)
                return q, fk(geometry, q)

    best = _Best(geometry, lower, upper, p)
    B, C = _zeta(b), _zeta(c)
    phi = _arg(C) - _arg(B)
    # (N2) fixed values in model angles (knee singular values outside the limits are dropped)
    V1 = [s[0] * v for v in _bounds(lower[0], upper[0])]
    V2 = [s[1] * v for v in _bounds(lower[1], upper[1])]
    V3 = [s[2] * v for v in _bounds(lower[2], upper[2])]
    V3 += [t for t in (-phi, math.pi - phi) if into_range(s[2] * t, lower[2], upper[2]) is not None]

    # (N3) vertices
    for t1 in V1:
        for t2 in V2:
            for t3 in V3:
                best.offer(t1, t2, t3)
    # (N4) edges: one joint free, nearest point of a circle
    arg_p = _arg(_eta(p))
    for t2 in V2:
        for t3 in V3:
            best.offer(arg_p - _arg(_eta(_leg_point(a, b, c, (0.0, t2, t3)))), t2, t3)
    for t1 in V1:
        v = _rx(t1).T @ p - a
        for t3 in V3:
            best.offer(t1, _arg(_zeta(v)) - _arg(_zeta(b + _ry(t3) @ c)), t3)
        for t2 in V2:
            best.offer(t1, t2, _arg(_zeta(_ry(t2).T @ v - b)) - _arg(C))
    # (N5) roll fixed: planar 2R on the projection
    for t1 in V1:
        for t2, t3 in _planar_ik(_zeta(_rx(t1).T @ p - a), B, C):
            best.offer(t1, t2, t3)
    # (N6) roll free, one pitch joint fixed: the roll torus
    for t3 in V3:
        for t1, alpha in _torus_stationary(a, b + _ry(t3) @ c, p):
            best.offer(t1, alpha, t3)
    for t2 in V2:
        for t1, alpha in _torus_stationary(a + _ry(t2) @ b, c, p):
            best.offer(t1, t2, alpha - t2)
    # (N7) all free, hip-roll singular: foot at (x, Rx(theta1) (h, 0)), theta1 aligned with eta(p)
    for t1 in (arg_p, arg_p + math.pi):
        for t2, t3 in _planar_ik(complex(-a[2], x - a[0]), B, C):
            best.offer(t1, t2, t3)

    if best.q is None:
        best.offer(*(s[k] * (lower[k] if _limited(lower[k], upper[k]) else 0.0) for k in range(3)))
    return best.q, best.foot
