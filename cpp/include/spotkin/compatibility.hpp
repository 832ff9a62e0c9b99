// The compatibility condition of the inverse differential model (the course's summary sheet,
// "condition de compatibilité"): J dq = dx has an exact solution iff dx lies in the range of J,
// i.e. iff the residual ||(I - J J^+) dx|| is zero. At a singular configuration (rank J < m) or
// with more task rows than joints, only compatible task velocities are reachable exactly; for the
// others J^+ dx is the least-squares step.
//
// With the SVD J = U S V^T (U full, m x m) and r the numerical rank (singular values above
// max(m, n) eps sigma_max, as rank()), the range of J is spanned by u_1..u_r, so
//   residual^2 = sum_{i > r} (u_i . dx)^2,   ||J^+ dx||^2 = sum_{i <= r} ((u_i . dx) / sigma_i)^2,
// the residual summed from the discarded components, with no cancellation. Default tolerance:
//   tol = max(m, n) eps (||dx|| + sigma_max ||J^+ dx||),
// the rounding of forming dx - J J^+ dx (size ||dx||) plus that of a dx computed as J dq
// (size sigma_max ||dq|| >= sigma_max ||J^+ dx||).
#pragma once

#include "spotkin/differential.hpp"

namespace spotkin::differential {

template <typename S>
struct Compatibility {
  S residual;       // ||(I - J J^+) dx||, NaN for non-finite input
  bool compatible;  // residual <= tolerance
};

// tol >= 0 is absolute; tol < 0 asks for the default above (cpp/src/differential.cpp).
template <typename S>
Compatibility<S> compatibility(const S* Jp, const S* dxp, int m, int n, S tol) noexcept;

}  // namespace spotkin::differential
