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

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "spotkin/differential.hpp"

namespace spotkin::differential {

template <typename S>
struct Compatibility {
  S residual;       // ||(I - J J^+) dx||, NaN for non-finite input
  bool compatible;  // residual <= tolerance
};

// tol >= 0 is absolute; tol < 0 asks for the default above.
template <typename S>
inline Compatibility<S> compatibility(const S* Jp, const S* dxp, int m, int n, S tol) noexcept {
  using T = Types<S, Dyn, Dyn>;
  if (!all_finite(Jp, std::ptrdiff_t(m) * n) || !all_finite(dxp, m)) return {quiet_nan<S>(), false};
  typename T::Svd svd(m, n, Eigen::ComputeFullU);
  svd.compute(map_jacobian<S, Dyn, Dyn>(Jp, m, n));
  const auto& sigma = svd.singularValues();
  const int k = std::min(m, n);
  const S sigma_max = k > 0 ? sigma[0] : S(0);
  const S cutoff = default_tolerance<S>(m, n, sigma_max);
  // dx / scale, so the squares neither underflow nor overflow
  S scale = 0;
  for (int i = 0; i < m; ++i) scale = std::max(scale, std::fabs(dxp[i]));
  if (scale == S(0)) return {S(0), true};
  const typename T::VecM dx = Eigen::Map<const typename T::VecM>(dxp, m) / scale;
  S outside = 0, pinv_norm2 = 0;
  for (int i = 0; i < m; ++i) {
    const S c = svd.matrixU().col(i).dot(dx);
    if (i < k && sigma[i] > cutoff)
      pinv_norm2 += (c / sigma[i]) * (c / sigma[i]);
    else
      outside += c * c;
  }
  const S residual = scale * std::sqrt(outside);
  const S bound = tol >= S(0) ? tol
                              : S(std::max(m, n)) * std::numeric_limits<S>::epsilon() * scale *
                                    (dx.norm() + sigma_max * std::sqrt(pinv_norm2));
  return {residual, residual <= bound};
}

}  // namespace spotkin::differential
