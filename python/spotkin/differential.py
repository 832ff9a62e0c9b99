"""Differential inverse kinematics: damped least squares, pseudo-inverse, null space, rank.

Every function takes a batch of Jacobians ``J`` of shape ``(..., m, n)`` (m task
rows, n joints; 1 <= m, n <= 64) and works per matrix, in C++. Leading
dimensions of ``J`` and the vectors broadcast (NumPy rules); a single ``(m, n)``
input gives a single output. The result is float32 when every input is
float32, float64 otherwise. A matrix or vector with a NaN or infinity gives an
all-NaN result for that sample (``rank`` gives -1), never an exception.

Formulas (J^+ is the Moore–Penrose pseudo-inverse):

- damped least squares: ``dq = J^T (J J^T + λ² I)^-1 dx`` (λ = ``damping``), which
  minimises ``|J dq - dx|² + λ² |dq|²``; λ → 0 gives ``J^+ dx``;
- with a secondary task ``z`` (``nullspace``): ``dq = J^T (J J^T + λ² I)^-1 dx + (I - J^+ J) z``.
  ``J (I - J^+ J) = 0``, so the primary task motion ``J dq`` does not depend on ``z``;
- compatibility (``compatible``): ``J dq = dx`` has an exact solution iff dx lies in the range of
  J, iff the residual ``|(I - J J^+) dx|`` is zero; otherwise ``J^+ dx`` is only the least-squares
  step (a singular configuration, or more task rows than joints);
- rank: the number of singular values above ``tol``, by default
  ``max(m, n) · eps · σ_max`` (as ``numpy.linalg.matrix_rank``; eps of the working dtype);
- manipulability (Yoshikawa): ``sqrt(det(J J^T)) = σ_1 ··· σ_m`` for m <= n. For m > n
  (more task rows than joints) ``J J^T`` is singular and the result is 0; use
  ``np.prod(singular_values(J), -1)`` (= ``sqrt(det(J^T J))``) for that case.

Decompositions (measured, see ``cpp/include/spotkin/differential.hpp``): damping > 0
solves the damped normal equations by Cholesky (symmetric positive definite by
construction); the pseudo-inverse (``pinv``, ``damping=0``, the null-space projector)
uses a complete orthogonal decomposition (column-pivoted QR, pivots below
``max(m, n) · eps · |r_11|`` count as zero, which agrees with the singular-value
rank except within rounding of the threshold); ``singular_values``, ``rank`` and
``manipulability`` use a two-sided Jacobi SVD.
"""

from __future__ import annotations

from ._support.public import publish
from .kinematics.differential import *  # noqa: F403 (its __all__, below)
from .kinematics.differential import __all__

publish(__name__, globals(), __all__)
