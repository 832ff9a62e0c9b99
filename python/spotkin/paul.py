"""Paul's standard trigonometric equations (seed 000 annex, corrected), batched.

Every function broadcasts its inputs like NumPy and returns every root with a
validity mask; invalid roots are NaN. Angles are in (-pi, pi].

- :func:`type2` ``X sin t + Y cos t = Z``: two roots (eps = +1, -1 in
  cos t = (Y Z - eps X S) / r^2, sin t = (X Z + eps Y S) / r^2, S = sqrt(r^2 - Z^2),
  r^2 = X^2 + Y^2). No root when r^2 < Z^2 (the annex calls this case "singular";
  it has no real solution). X = Y = 0: no root unless Z = 0, where every t solves
  it and t = 0 is reported.
- :func:`type3` the 2x2 linear system in (sin t, cos t): one root.
- :func:`type6` the coupled pair ``W sin tj = X cos ti + Y sin ti + Z1``,
  ``W cos tj = X sin ti - Y cos ti + Z2``: up to two (ti, tj) pairs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import _core

__all__ = ["type2", "type3", "type6"]


def _flat(*args: ArrayLike) -> tuple[tuple[int, ...], list[np.ndarray]]:
    arrays = []
    for value in args:
        array = np.asarray(value)
        if array.dtype.kind not in "biuf":
            raise TypeError(f"coefficients must be real numbers, got dtype {array.dtype}")
        arrays.append(array)
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    return shape, [np.ascontiguousarray(np.broadcast_to(a, shape), dtype=np.float64).ravel() for a in arrays]


def type2(X: ArrayLike, Y: ArrayLike, Z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Roots of X sin t + Y cos t = Z: (t (..., 2), valid (..., 2))."""
    shape, flat = _flat(X, Y, Z)
    t, valid = _core.paul_type2(*flat)
    return t.reshape(*shape, 2), valid.reshape(*shape, 2)


def type3(X1: ArrayLike, Y1: ArrayLike, Z1: ArrayLike, X2: ArrayLike, Y2: ArrayLike, Z2: ArrayLike):
    """Root of X1 sin t + Y1 cos t = Z1 and X2 sin t + Y2 cos t = Z2: (t (...), valid (...))."""
    shape, flat = _flat(X1, Y1, Z1, X2, Y2, Z2)
    t, valid = _core.paul_type3(*flat)
    return t.reshape(shape), valid.reshape(shape)


def type6(W: ArrayLike, X: ArrayLike, Y: ArrayLike, Z1: ArrayLike, Z2: ArrayLike):
    """Pairs (ti, tj) solving the coupled type-6 equations: (ti (..., 2), tj (..., 2), valid (..., 2))."""
    shape, flat = _flat(W, X, Y, Z1, Z2)
    ti, tj, valid = _core.paul_type6(*flat)
    return ti.reshape(*shape, 2), tj.reshape(*shape, 2), valid.reshape(*shape, 2)
