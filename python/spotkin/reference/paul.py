"""Paul's method: the standard trigonometric equation types 2, 3 and 6, one sample at a time.

The course's Spot problem, appendix "Équations". Every root is returned together with a validity flag;
invalid roots are NaN. Angles are wrapped to (-pi, pi].
Each equation (each row, for type 3) is first divided by its largest |coefficient|: same
roots, and squares such as X^2 + Y^2 can neither underflow nor overflow.

(T2)  X sin t + Y cos t = Z.
      With r2 = X^2 + Y^2 > 0 and D = r2 - Z^2 (derived by squaring, then checked by
      substitution: X s + Y c = Z and s^2 + c^2 = 1):
          cos t = (Y Z - eps X sqrt(D)) / r2,   sin t = (X Z + eps Y sqrt(D)) / r2,   eps = +-1.
      Root 0 takes eps = +1, root 1 eps = -1 (the same convention in every case below).
      No real root when D < 0, i.e. X^2 + Y^2 < Z^2. The appendix calls the last case
      "configuration singulière si X != 0 et Y != 0", which is wrong (see docs/course-errata.md).
      D >= -1e-12 r2 counts as touching: D is clamped to 0 and the double root is returned twice.
      Special cases of the appendix table, all the eps formula above specialised:
        X = 0, Y != 0:  cos t = Z / Y,  sin t = eps sign(Y) sqrt(1 - cos^2 t)
        Y = 0, X != 0:  sin t = Z / X,  cos t = -eps sign(X) sqrt(1 - sin^2 t)
        Z = 0:          t = atan2(eps Y, -eps X): root 0 = atan2(-Y, X) + pi, root 1 = atan2(-Y, X)
        X = Y = 0:      Z != 0 -> no root; Z == 0 -> identity, EVERY angle solves it:
                        t = 0 is returned twice, both valid. Callers that need the whole
                        circle must test for X == Y == Z == 0 themselves.

(T3)  X1 sin t + Y1 cos t = Z1,  X2 sin t + Y2 cos t = Z2.
      det = X1 Y2 - X2 Y1 != 0: Cramer's rule (the appendix's formulas, verified correct):
          sin t = (Z1 Y2 - Z2 Y1) / det,   cos t = (X1 Z2 - X2 Z1) / det,   t = atan2(sin t, cos t),
      valid only if |sin^2 t + cos^2 t - 1| <= 1e-9 (otherwise the system has no solution).
      |det| <= 1e-12 |(X1, Y1)| |(X2, Y2)| is degenerate (parallel rows): the equation with the
      larger |(X, Y)| is solved as type 2 and the first of its roots (root 0, then root 1)
      that also satisfies the other equation, |X s + Y c - Z| <= 1e-9 max(|(X, Y)|, |Z|), is
      returned. In that case the system may have a second root; get it from type2 directly.

(T6)  W sin tj = X cos ti + Y sin ti + Z1,   W cos tj = X sin ti - Y cos ti + Z2.
      Squaring and adding removes tj (derived here, cross terms 2XY cs cancel):
          W^2 = X^2 + Y^2 + Z1^2 + Z2^2 + 2 (Y Z1 + X Z2) sin ti + 2 (X Z1 - Y Z2) cos ti,
      a type-2 equation B1 sin ti + B2 cos ti = B3 with
          B1 = 2 (Y Z1 + X Z2),   B2 = 2 (X Z1 - Y Z2),   B3 = W^2 - X^2 - Y^2 - Z1^2 - Z2^2.
      Then tj from the type-3 system W sin tj = A, W cos tj = B (det = W^2).
      W = 0: both right-hand sides vanish, a type-3 system in ti alone
          Y sin ti + X cos ti = -Z1,   X sin ti - Y cos ti = -Z2   (det = -(X^2 + Y^2)),
      and tj is free (every angle): slot 0 holds (ti, tj = 0), slot 1 is invalid.
"""

from __future__ import annotations

import math
import sys

import numpy as np

__all__ = ["type2", "type3", "type6", "wrap"]

TOUCH_TOL = 1e-12  # type 2: X^2 + Y^2 - Z^2 >= -TOUCH_TOL (X^2 + Y^2) counts as a double root
DET_TOL = 1e-12  # type 3: |det| <= DET_TOL |row1| |row2| counts as degenerate
CONSISTENCY_TOL = 1e-9  # type 3: |s^2 + c^2 - 1| and the residual of the other equation
TYPE6_SLACK = 16 * sys.float_info.epsilon  # type 6: rounding of B3, relative to W^2 + X^2 + Y^2 + Z1^2 + Z2^2


def wrap(angle: float) -> float:
    """Angle in (-pi, pi]."""
    a = math.remainder(angle, 2 * math.pi)  # in [-pi, pi]
    return math.pi if a <= -math.pi else a


def _clamp(x: float) -> float:
    return max(-1.0, min(1.0, x))


def _scaled(*coefs: float) -> tuple[float, ...]:
    """Divide a homogeneous equation by its largest |coefficient| (same roots; no under/overflow)."""
    values = tuple(float(v) for v in coefs)
    m = max(abs(v) for v in values)
    return values if m == 0.0 or not math.isfinite(m) else tuple(v / m for v in values)


def _no_root() -> tuple[np.ndarray, np.ndarray]:
    return np.full(2, math.nan), np.zeros(2, dtype=bool)


def type2(X: float, Y: float, Z: float) -> tuple[np.ndarray, np.ndarray]:
    """Both roots of X sin t + Y cos t = Z (type 2): (roots (2,), valid (2,)).

    Root 0 uses eps = +1 (+sqrt), root 1 eps = -1, in
    cos t = (Y Z - eps X sqrt(X^2 + Y^2 - Z^2)) / (X^2 + Y^2),
    sin t = (X Z + eps Y sqrt(X^2 + Y^2 - Z^2)) / (X^2 + Y^2).
    X = Y = Z = 0 is the identity (every angle): returns t = 0 twice, valid.
    """
    X, Y, Z = _scaled(X, Y, Z)
    if X == 0.0 and Y == 0.0:
        if Z == 0.0:
            return np.zeros(2), np.ones(2, dtype=bool)  # identity, every angle
        return _no_root()
    r2 = X * X + Y * Y
    D = r2 - Z * Z
    if D < -TOUCH_TOL * r2:
        return _no_root()  # X^2 + Y^2 < Z^2
    D = max(D, 0.0)
    roots = np.empty(2)
    for k, eps in enumerate((1.0, -1.0)):
        if X == 0.0:  # Y cos t = Z
            c = _clamp(Z / Y)
            s = eps * math.copysign(1.0, Y) * math.sqrt(1.0 - c * c)
        elif Y == 0.0:  # X sin t = Z
            s = _clamp(Z / X)
            c = -eps * math.copysign(1.0, X) * math.sqrt(1.0 - s * s)
        elif Z == 0.0:  # tan t = -Y / X
            s, c = eps * Y, -eps * X
        else:
            root = math.sqrt(D)
            c = (Y * Z - eps * X * root) / r2
            s = (X * Z + eps * Y * root) / r2
        roots[k] = wrap(math.atan2(s, c))
    return roots, np.ones(2, dtype=bool)


def type3(X1: float, Y1: float, Z1: float, X2: float, Y2: float, Z2: float) -> tuple[float, bool]:
    """The root of X1 sin t + Y1 cos t = Z1, X2 sin t + Y2 cos t = Z2 (type 3): (t, valid).

    det = X1 Y2 - X2 Y1 != 0: sin t = (Z1 Y2 - Z2 Y1) / det, cos t = (X1 Z2 - X2 Z1) / det,
    valid when sin^2 + cos^2 = 1 within 1e-9. Degenerate det: first type-2 root of the
    larger row that satisfies the other equation (module docstring).
    """
    X1, Y1, Z1 = _scaled(X1, Y1, Z1)
    X2, Y2, Z2 = _scaled(X2, Y2, Z2)
    n1, n2 = math.hypot(X1, Y1), math.hypot(X2, Y2)
    det = X1 * Y2 - X2 * Y1
    if abs(det) > DET_TOL * n1 * n2:
        s = (Z1 * Y2 - Z2 * Y1) / det
        c = (X1 * Z2 - X2 * Z1) / det
        if abs(s * s + c * c - 1.0) <= CONSISTENCY_TOL:
            return wrap(math.atan2(s, c)), True
        return math.nan, False
    # Degenerate: rows parallel (or null). Solve the larger one, test the other.
    if n1 >= n2:
        (Xa, Ya, Za), (Xb, Yb, Zb), nb = (X1, Y1, Z1), (X2, Y2, Z2), n2
    else:
        (Xa, Ya, Za), (Xb, Yb, Zb), nb = (X2, Y2, Z2), (X1, Y1, Z1), n1
    roots, valid = type2(Xa, Ya, Za)
    for t, ok in zip(roots, valid):
        if ok and abs(Xb * math.sin(t) + Yb * math.cos(t) - Zb) <= CONSISTENCY_TOL * max(nb, abs(Zb)):
            return float(t), True
    return math.nan, False


def type6(W: float, X: float, Y: float, Z1: float, Z2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both solutions of W sin tj = X cos ti + Y sin ti + Z1, W cos tj = X sin ti - Y cos ti + Z2.

    Type 6: ti from the type-2 equation B1 sin ti + B2 cos ti = B3,
    B1 = 2 (Y Z1 + X Z2), B2 = 2 (X Z1 - Y Z2), B3 = W^2 - X^2 - Y^2 - Z1^2 - Z2^2
    (slot k holds type2's root k), then tj by type 3. Returns (ti (2,), tj (2,), valid (2,)).
    W = 0: ti from a type-3 system, tj free (returned as 0) in slot 0; slot 1 invalid.
    """
    W, X, Y, Z1, Z2 = _scaled(W, X, Y, Z1, Z2)
    ti = np.full(2, math.nan)
    tj = np.full(2, math.nan)
    valid = np.zeros(2, dtype=bool)
    if W == 0.0:
        t, ok = type3(Y, X, -Z1, X, -Y, -Z2)
        if ok:
            ti[0], tj[0], valid[0] = t, 0.0, True  # tj: every angle
        return ti, tj, valid
    B1 = 2.0 * (Y * Z1 + X * Z2)
    B2 = 2.0 * (X * Z1 - Y * Z2)
    B3 = W * W - X * X - Y * Y - Z1 * Z1 - Z2 * Z2
    # B3 is a difference of squares summing to `scale`: within its rounding (16 eps scale) of
    # touching hypot(B1, B2), the equation touches (a double root), not misses
    scale = W * W + X * X + Y * Y + Z1 * Z1 + Z2 * Z2
    r = math.sqrt(B1 * B1 + B2 * B2)
    if abs(B3) > r and abs(B3) - r <= TYPE6_SLACK * scale:
        B3 = math.copysign(r, B3)
    roots, ok = type2(B1, B2, B3)
    for k in range(2):
        if not ok[k]:
            continue
        si, ci = math.sin(roots[k]), math.cos(roots[k])
        t, v = type3(W, 0.0, X * ci + Y * si + Z1, 0.0, W, X * si - Y * ci + Z2)
        if v:
            ti[k], tj[k], valid[k] = roots[k], t, True
    return ti, tj, valid
