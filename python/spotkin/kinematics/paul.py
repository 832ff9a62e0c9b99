"""Paul's method: the implementation of :mod:`spotkin.paul` (documented there)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_real, broadcast_lead

__all__ = ["type2", "type3", "type6"]


def _flat(**coefficients: ArrayLike) -> tuple[tuple[int, ...], list[np.ndarray]]:
    try:
        arrays = {name: as_real(value, name, np.float64) for name, value in coefficients.items()}
    except TypeError as error:
        raise TypeError(f"coefficients must be real numbers: {error}") from None
    shape = broadcast_lead(**{name: (a.shape, a.shape) for name, a in arrays.items()})
    return shape, [np.ascontiguousarray(np.broadcast_to(a, shape)).ravel() for a in arrays.values()]


def _half_open(t: np.ndarray) -> np.ndarray:
    """Angles in (-pi, pi]: the kernels' atan2 gives -pi for a -0 sine (and a sine below the
    smallest step at pi), the same angle as pi."""
    return np.where(t == -np.pi, np.pi, t)


def _finite_roots(valid: np.ndarray, *roots: np.ndarray) -> np.ndarray:
    """valid, and False wherever a root is NaN (so valid roots are never NaN)."""
    for t in roots:
        valid &= ~np.isnan(t)
    return valid


def type2(X: ArrayLike, Y: ArrayLike, Z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Roots of X sin t + Y cos t = Z: (t (..., 2), valid (..., 2))."""
    shape, flat = _flat(X=X, Y=Y, Z=Z)
    t, valid = _core.paul_type2(*flat)
    t = _half_open(t)
    return t.reshape(*shape, 2), _finite_roots(valid, t).reshape(*shape, 2)


def type3(X1: ArrayLike, Y1: ArrayLike, Z1: ArrayLike, X2: ArrayLike, Y2: ArrayLike, Z2: ArrayLike):
    """Root of X1 sin t + Y1 cos t = Z1 and X2 sin t + Y2 cos t = Z2: (t (...), valid (...))."""
    shape, flat = _flat(X1=X1, Y1=Y1, Z1=Z1, X2=X2, Y2=Y2, Z2=Z2)
    t, valid = _core.paul_type3(*flat)
    t = _half_open(t)
    return t.reshape(shape), _finite_roots(valid, t).reshape(shape)


def type6(W: ArrayLike, X: ArrayLike, Y: ArrayLike, Z1: ArrayLike, Z2: ArrayLike):
    """Pairs (ti, tj) solving the coupled type-6 equations: (ti (..., 2), tj (..., 2), valid (..., 2))."""
    shape, flat = _flat(W=W, X=X, Y=Y, Z1=Z1, Z2=Z2)
    ti, tj, valid = _core.paul_type6(*flat)
    ti, tj = _half_open(ti), _half_open(tj)
    return ti.reshape(*shape, 2), tj.reshape(*shape, 2), _finite_roots(valid, ti, tj).reshape(*shape, 2)
