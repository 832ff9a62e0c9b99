"""Paul's method: the implementation of :mod:`spotkin.paul` (documented there). The coefficients go
straight to the core, which broadcasts them, checks their types and computes every root."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _core

__all__ = ["type2", "type3", "type6"]


def type2(X: ArrayLike, Y: ArrayLike, Z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Roots of X sin t + Y cos t = Z: (t (..., 2), valid (..., 2))."""
    return _core.paul_type2(X, Y, Z)


def type3(X1: ArrayLike, Y1: ArrayLike, Z1: ArrayLike, X2: ArrayLike, Y2: ArrayLike, Z2: ArrayLike):
    """Root of X1 sin t + Y1 cos t = Z1 and X2 sin t + Y2 cos t = Z2: (t (...), valid (...))."""
    return _core.paul_type3(X1, Y1, Z1, X2, Y2, Z2)


def type6(W: ArrayLike, X: ArrayLike, Y: ArrayLike, Z1: ArrayLike, Z2: ArrayLike):
    """Pairs (ti, tj) solving the coupled type-6 equations: (ti (..., 2), tj (..., 2), valid (..., 2))."""
    return _core.paul_type6(W, X, Y, Z1, Z2)
