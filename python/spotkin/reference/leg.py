"""Reference kinematics of one Spot leg (roll-pitch-pitch), one sample at a time.

Slow and obvious on purpose: the C++ results are tested against these functions.

Model (metres, radians)
-----------------------
Joints q = [hx, hy, kn]. Leg frame: origin at the hx joint, axes parallel to the
body frame (x forward, y left, z up). Parameters: hip_offset h1 (+ left, - right),
upper U, lower L, knee_offset k. Spot: h1 = +-0.110945, U = 0.3205, k = 0.025,
L = 0.3365.

    (M1)  p = Rx(hx) ( [0, h1, 0] + Ry(hy) ( [k, 0, -U] + Ry(kn) [0, 0, -L] ) )

Expanded, with s23 = sin(hy + kn), c23 = cos(hy + kn):

    (M2)  X  =  k cos hy - U sin hy - L s23        (sagittal forward)
          Zs = -k sin hy - U cos hy - L c23        (sagittal down, negative)
          p  = ( X,  h1 cos hx - Zs sin hx,  h1 sin hx + Zs cos hx )

Inverse kinematics (closed form)
--------------------------------
(I1) Hip roll. The y-component of Rx(-hx) p must be h1:
         y cos hx + z sin hx = h1,  i.e.  r cos(hx - phi) = h1,
     r = hypot(y, z), phi = atan2(z, y). So  hx = phi +- acos(h1 / r);
     no solution when r < |h1|.
       hip branch 0 ("normal"):  hx = phi + acos(h1 / r)   (hx = 0 for a foot
                                 straight below the hy joint, either sign of h1)
       hip branch 1 ("flipped"): hx = phi - acos(h1 / r)
(I2) Sagittal target: x' = x, z' = -sin(hx) y + cos(hx) z, and
     (x', z') = Ry(hy) w,  w = (k - L sin kn, -U - L cos kn).
(I3) Knee. |w|^2 = k^2 + U^2 + L^2 + 2L(U cos kn - k sin kn) = D^2 = x'^2 + z'^2
     (= |p|^2 - h1^2, the same for both hip branches), so
         R cos(kn + beta) = Zk := (D^2 - k^2 - U^2 - L^2) / (2L),
     R = hypot(U, k), beta = atan2(k, U); no solution when |Zk| > R.
       knee branch 0 ("knee back", Spot's):  kn = -beta - acos(Zk / R)
       knee branch 1 ("knee forward"):       kn = -beta + acos(Zk / R)
(I4) Hip pitch. Ry(hy) multiplies z + i x by exp(i hy), so
         hy = atan2(x', z') - atan2(w_x, w_z).
All angles are wrapped to (-pi, pi]. Slot order: slot = 2 * hip_branch +
knee_branch, i.e. 0 (normal, back), 1 (normal, forward), 2 (flipped, back),
3 (flipped, forward). Either all four slots exist or none does. On the singular
sets r = |h1| and |Zk| = R the two branches coincide; ratios within 1e-12 of +-1
are clamped so such targets still get finite answers.

Course (DHm) leg
----------------
The course's DHm leg (T = RotX(alpha) TransX(d) RotZ(theta) TransZ(r); rows
(d, alpha, r, theta) = (0, -90deg, 0, th1), (0, 90deg, h1, th2), (h2, 0, 0, th3);
foot (h3, 0, 0) in frame 3) is this model with k = 0, U = h2, L = h3, the SAME h1
(no sign flip), and

    (C1)  th1 = -hx,  th2 = hy,  th3 = kn,
    (C2)  p_course = R_course_from_leg p_leg,  R_course_from_leg = [[0, 0, -1],
                                                              [-1, 0, 0],
                                                              [0, 1, 0]]

(a proper rotation: course x = leg -z, course y = leg -x, course z = leg y). The hip
roll axis is course y0 and the zero pose of the course points the leg along course +x.
The th1 offset is fixed only by the choice of frame: th1 = c - hx works for any
constant c with R_course_from_leg replaced by RotY_course(c) R_course_from_leg. The
other exact proper correspondences are th1 = c + hx, th2 = hy + pi, th3 = kn
(same h1), and, with h1 -> -h1, th1 = c + hx, th2 = -hy, th3 = -kn or
th1 = c - hx, th2 = pi - hy, th3 = -kn. No correspondence has a +-pi/2 offset
on th2, so the course's own "th_u" is not Spot's hy. See course_to_leg.
"""

import math

import numpy as np

from . import rpp_leg

OK = 0
UNREACHABLE = 1
JOINT_LIMIT = 2
INVALID_INPUT = 3

_RATIO_TOL = 1e-12  # |ratio| <= 1 + tol counts as touching the singular set
_LIMIT_TOL = 1e-12  # rad, tolerance on joint limits


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def wrap_angle(a):
    """Wrap an angle to (-pi, pi]."""
    a = math.remainder(a, 2.0 * math.pi)  # in [-pi, pi]
    if a <= -math.pi:
        a += 2.0 * math.pi
    return a


def fk(q, h1, U, L, k):
    """Foot centre in the leg frame, eq. (M1)."""
    hx, hy, kn = float(q[0]), float(q[1]), float(q[2])
    foot_in_knee = np.array([0.0, 0.0, -L])
    knee_in_hy = np.array([k, 0.0, -U])
    hy_in_hx = np.array([0.0, h1, 0.0])
    return _rx(hx) @ (hy_in_hx + _ry(hy) @ (knee_in_hy + _ry(kn) @ foot_in_knee))


def jacobian(q, h1, U, L, k):
    """d foot / d q (3x3), differentiated by hand from eq. (M2).

    With X, Zs from (M2): dX/dhy = Zs, dZs/dhy = -X,
    dX/dkn = -L c23, dZs/dkn = L s23, and d p / d hx = (0, -p_z, p_y).
    """
    hx, hy, kn = float(q[0]), float(q[1]), float(q[2])
    c1, s1 = math.cos(hx), math.sin(hx)
    c2, s2 = math.cos(hy), math.sin(hy)
    c23, s23 = math.cos(hy + kn), math.sin(hy + kn)
    X = k * c2 - U * s2 - L * s23
    Zs = -k * s2 - U * c2 - L * c23
    py = h1 * c1 - Zs * s1
    pz = h1 * s1 + Zs * c1
    return np.array(
        [
            [0.0, Zs, -L * c23],
            [-pz, s1 * X, -s1 * L * s23],
            [py, -c1 * X, c1 * L * s23],
        ]
    )


def _acos_branch(ratio):
    """acos(ratio) and whether it exists; |ratio| <= 1 + 1e-12 is clamped."""
    if abs(ratio) > 1.0 + _RATIO_TOL:
        return math.nan, False
    return math.acos(min(1.0, max(-1.0, ratio))), True


def _hip_angles(y, z, h1):
    """(phi, acos(h1/r), exists) for eq. (I1)."""
    r = math.hypot(y, z)
    phi = math.atan2(z, y)
    if r == 0.0:
        if h1 == 0.0:
            return 0.0, 0.0, True  # every hx works; pick 0
        return phi, math.nan, False
    a, ok = _acos_branch(h1 / r)
    return phi, a, ok


def _knee_ratio(D2, U, L, k):
    """Zk / R from eq. (I3), and beta."""
    R = math.hypot(U, k)
    Zk = (D2 - k * k - U * U - L * L) / (2.0 * L)
    return Zk / R, math.atan2(k, U)


def _hip_pitch(x, y, z, hx, kn, U, L, k):
    """hy from eqs. (I2) and (I4)."""
    zp = -math.sin(hx) * y + math.cos(hx) * z
    wx = k - L * math.sin(kn)
    wz = -U - L * math.cos(kn)
    return math.atan2(x, zp) - math.atan2(wx, wz)


def ik_all(p, h1, U, L, k):
    """All closed-form IK branches, eqs. (I1)-(I4).

    Returns (q_all (4,3), exists (4,) bool); rows are slots 2*hip + knee
    (see module docstring), NaN where the branch does not exist.
    """
    q_all = np.full((4, 3), np.nan)
    exists = np.zeros(4, dtype=bool)
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return q_all, exists

    phi, a_hip, hip_ok = _hip_angles(y, z, h1)
    ratio, beta = _knee_ratio(x * x + y * y + z * z - h1 * h1, U, L, k)
    a_knee, knee_ok = _acos_branch(ratio)
    if not (hip_ok and knee_ok):
        return q_all, exists

    for hip_branch, hx in enumerate((phi + a_hip, phi - a_hip)):
        for knee_branch, kn in enumerate((-beta - a_knee, -beta + a_knee)):
            hy = _hip_pitch(x, y, z, hx, kn, U, L, k)
            slot = 2 * hip_branch + knee_branch
            q_all[slot] = [wrap_angle(hx), wrap_angle(hy), wrap_angle(kn)]
            exists[slot] = True
    return q_all, exists


def wrap_into_limits(q, lower, upper):
    """Per joint, the first of q, q - 2pi, q + 2pi inside [lower, upper] (+-1e-12).

    Returns (q_wrapped (3,), ok); a joint with no fit keeps its value, ok False.
    """
    out = np.array(q, dtype=float)
    ok = True
    for i in range(3):
        for cand in (out[i], out[i] - 2.0 * math.pi, out[i] + 2.0 * math.pi):
            if lower[i] - _LIMIT_TOL <= cand <= upper[i] + _LIMIT_TOL:
                out[i] = cand
                break
        else:
            ok = False
    return out, ok


def _circle_distance(qa, qb):
    """max over joints of |qa - qb| wrapped to (-pi, pi]."""
    return max(abs(wrap_angle(float(a) - float(b))) for a, b in zip(qa, qb))


def ik(p, h1, U, L, k, lower, upper, seed=None):
    """Joint angles for foot target p, returns (q (3,), status).

    Valid slots: existing (ik_all) and inside the limits (wrap_into_limits).
    Among valid slots: the one nearest to seed in max-joint circle distance,
    ties to the lowest slot; with no seed the lowest valid slot. -> OK.
    Solutions exist but none valid -> (NaN, JOINT_LIMIT).
    Non-finite p -> (NaN, INVALID_INPUT).
    No solution -> UNREACHABLE with the configuration inside the limits whose
    foot is nearest to p (rpp_leg.nearest_in_limits, exact).
    """
    nan3 = np.full(3, np.nan)
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return nan3, INVALID_INPUT

    q_all, exists = ik_all(p, h1, U, L, k)
    if exists.any():
        best, best_d = None, math.inf
        for slot in range(4):
            if not exists[slot]:
                continue
            q_slot, ok = wrap_into_limits(q_all[slot], lower, upper)
            if not ok:
                continue
            if seed is None:
                return q_slot, OK
            d = _circle_distance(q_slot, seed)
            if d < best_d:  # strict: ties keep the lowest slot
                best, best_d = q_slot, d
        if best is None:
            return nan3, JOINT_LIMIT
        return best, OK

    # Unreachable: the in-limit configuration whose foot is nearest to p (the general leg's exact answer).
    geometry = {"a": (0.0, h1, 0.0), "b": (k, 0.0, -U), "c": (0.0, 0.0, -L)}
    q_near, _ = rpp_leg.nearest_in_limits(geometry, lower, upper, np.asarray(p, dtype=float))
    return np.asarray(q_near, dtype=float), UNREACHABLE


def knee_reach(U, L, k, knee_limits=None):
    """(Dmin, Dmax): the distances hy -> foot the knee reaches, eq. (I3):
    D^2 = R^2 + L^2 + 2 L R cos(kn + beta), over every kn or over knee_limits (lo, hi).
    The extremes of cos(psi) over the interval lie at its ends or at a multiple of pi inside it."""
    R, beta = math.hypot(U, k), math.atan2(k, U)
    lo, hi = (-math.inf, math.inf) if knee_limits is None else knee_limits
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi - lo >= 2 * math.pi:
        cosines = [1.0, -1.0]
    else:
        lo, hi = lo + beta, hi + beta
        multiples_of_pi = range(math.ceil(lo / math.pi), math.floor(hi / math.pi) + 1)
        cosines = [math.cos(lo), math.cos(hi)] + [math.cos(m * math.pi) for m in multiples_of_pi]
    d2 = [R * R + L * L + 2.0 * L * R * c for c in cosines]
    return math.sqrt(max(0.0, min(d2))), math.sqrt(max(0.0, max(d2)))


def nearest_reachable(p, h1, U, L, k, knee_limits=None):
    """The point of the reachable set (limits aside) nearest to p; with knee_limits (lo, hi),
    of the set reachable with the knee inside them (Dmin, Dmax from knee_reach).

    The reachable set is the shell h1^2 + Dmin^2 <= |p|^2 <= h1^2 + Dmax^2
    (Dmax = R + L, Dmin = |R - L|, R = hypot(U, k); eq. (I3)) outside the
    hip-roll cylinder y^2 + z^2 >= h1^2 (eq. (I1)). First the radial projection
    onto the shell (exactly the nearest point when it lands outside the
    cylinder); if it lands inside, (y, z) is pushed out to radius |h1| and
    |x| clamped into [Dmin, Dmax]. p = 0 maps to (0, h1, -Dmin).
    """
    d_min, d_max = knee_reach(U, L, k, knee_limits)
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    norm = math.sqrt(x * x + y * y + z * z)
    if norm == 0.0:
        x, y, z = 0.0, h1, -d_min
    else:
        target = min(max(norm, math.sqrt(h1 * h1 + d_min * d_min)), math.sqrt(h1 * h1 + d_max * d_max))
        x, y, z = x * target / norm, y * target / norm, z * target / norm
    r = math.hypot(y, z)
    if r * r < h1 * h1:
        if r > 0.0:
            y, z = y * abs(h1) / r, z * abs(h1) / r
        else:
            y, z = h1, 0.0
        x = math.copysign(min(max(abs(x), d_min), d_max), x)
    return x, y, z


def singularity(q, h1, U, L, k):
    """(|det J|, smallest singular value of J) for the jacobian at q."""
    J = jacobian(q, h1, U, L, k)
    return abs(float(np.linalg.det(J))), float(np.linalg.svd(J, compute_uv=False)[-1])


def course_to_leg(th, h1):
    """Map the course's DHm leg angles th = (th1, th2, th3) onto this model.

    Eq. (C1)/(C2) of the module docstring, with k = 0, U = h2, L = h3 and the
    same h1: q_leg = (-th1, th2, th3) and p_course = R_course_from_leg @ fk(q_leg).
    Returns (R_leg_from_course (3,3), q_leg (3,)), so that
    fk(q_leg, h1, h2, h3, 0) = R_leg_from_course @ p_course(th). h1 is unchanged
    (argument kept for call symmetry; no sign flip is needed).
    """
    del h1  # the correspondence does not depend on h1
    R_course_from_leg = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    q_leg = np.array([-float(th[0]), float(th[1]), float(th[2])])
    return R_course_from_leg.T, q_leg
