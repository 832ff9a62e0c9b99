"""Differential kinematics helpers: the implementation of :mod:`spotkin.differential` (documented there)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_flag, as_scalar

__all__ = ["compatible", "dls", "manipulability", "nullspace_projector", "pinv", "rank", "singular_values"]


def _scalar(out: np.ndarray):
    return out[()] if out.ndim == 0 else out


def dls(
    J: ArrayLike,
    dx: ArrayLike,
    damping: float = 1e-3,
    nullspace: ArrayLike | None = None,
    *,
    return_residual: bool = False,
):
    """Damped least-squares step: J (..., m, n), dx (..., m) -> dq (..., n).

    ``dq = J^T (J J^T + damping² I)^-1 dx``, plus ``(I - J^+ J) nullspace`` when a
    secondary joint-space motion ``nullspace`` (..., n) is given. ``damping = 0`` gives
    the minimum-norm least-squares solution ``J^+ dx``; so does a damping that is numerically
    zero, ``damping² <= eps · ‖J‖_F²`` (eps = 2.2e-16, for float32 input too): ``J J^T +
    damping² I`` is then ``J J^T`` in floating point, and the step is the damped one's limit.
    ``damping`` must be finite and >= 0 (ValueError otherwise).

    ``return_residual=True`` returns ``(dq, residual)``, with ``residual`` (...,) the compatibility
    residual ``|(I - J J^+) dx|`` of :func:`compatible` (whatever the damping): near 0, dx is in the
    range of J and the undamped step solves ``J dq = dx`` exactly; otherwise the step is a
    least-squares one, and ``residual`` is the part of dx no joint motion produces.
    """
    damping = _nonnegative(damping, "damping")
    dq = _core.dls(J, dx, damping, nullspace)
    if not as_flag(return_residual, "return_residual"):
        return dq
    residual = np.broadcast_to(_core.compatible(J, dx, -1.0)[1], dq.shape[:-1]).astype(dq.dtype)
    residual[np.isnan(dq).any(axis=-1)] = np.nan  # a non-finite nullspace sample too
    return dq, _scalar(residual)


def compatible(J: ArrayLike, dx: ArrayLike, tol: float | None = None):
    """The compatibility condition: does ``J dq = dx`` have an exact solution?
    J (..., m, n), dx (..., m) -> (compatible (...,) bool, residual (...,)).

    ``residual = |(I - J J^+) dx|``, the distance from dx to the range of J, where the range is
    spanned by the left singular vectors whose singular values count for :func:`rank` (above
    ``max(m, n) · eps · σ_max``); it is summed from dx's components along the other left singular
    vectors, so it has no cancellation. ``compatible`` is ``residual <= tol``, per sample.

    ``tol=None`` uses ``max(m, n) · eps · (|dx| + σ_max |J^+ dx|)`` with eps of the working dtype
    (2.2e-16 for float64, 1.2e-7 for float32): the rounding of forming ``dx - J J^+ dx`` plus that
    of a dx computed as ``J dq``, so a dx built from a joint motion is compatible and one with a
    component out of the range above rounding is not. A given ``tol`` (finite, >= 0) is absolute,
    in dx's units. Leading dimensions broadcast; the residual is float32 when J and dx both are.
    A NaN or infinity in a sample gives ``(False, NaN)`` for that sample.
    """
    tol = -1.0 if tol is None else _nonnegative(tol, "tol")
    ok, residual = _core.compatible(J, dx, tol)
    return _scalar(ok), _scalar(residual)


def pinv(J: ArrayLike) -> np.ndarray:
    """Moore–Penrose pseudo-inverse: J (..., m, n) -> J^+ (..., n, m).

    Directions with singular values below about ``max(m, n) · eps · σ_max`` are
    treated as exactly singular (see the module docstring).
    """
    return _core.pinv(J)


def nullspace_projector(J: ArrayLike) -> np.ndarray:
    """Orthogonal projector onto the null space of J: (..., m, n) -> ``I - J^+ J`` (..., n, n).

    Symmetric and idempotent, with ``J P = 0``; the zero matrix when J has full column rank.
    """
    return _core.nullspace_projector(J)


def singular_values(J: ArrayLike) -> np.ndarray:
    """Singular values, descending: J (..., m, n) -> (..., min(m, n))."""
    return _core.singular_values(J)


def rank(J: ArrayLike, tol: float | None = None):
    """Numerical rank: the number of singular values ``> tol``, (...,) int64.

    ``tol=None`` uses ``max(m, n) · eps · σ_max`` with eps of the working dtype (2.2e-16
    for float64, 1.2e-7 for float32), as ``numpy.linalg.matrix_rank``; a given ``tol``
    (finite, >= 0) is absolute. A non-finite J gives -1.
    """
    tol = -1.0 if tol is None else _nonnegative(tol, "tol")
    return _scalar(_core.rank(J, tol))


def manipulability(J: ArrayLike):
    """Yoshikawa manipulability ``sqrt(det(J J^T))``: J (..., m, n) -> (...,).

    The product of the singular values for m <= n; 0 for m > n (``J J^T`` is then
    singular; see the module docstring).
    """
    return _scalar(_core.manipulability(J))


def _nonnegative(value: float, name: str) -> float:
    """A real number (bool, str, None and complex raise TypeError), finite and >= 0."""
    value = as_scalar(value, name)
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be finite and >= 0, got {value}")
    return value
