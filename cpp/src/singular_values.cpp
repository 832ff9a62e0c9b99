// The singular-value quantities of spotkin/differential.hpp (singular values,
// rank, manipulability) and spotkin/compatibility.hpp, by two-sided Jacobi SVD,
// compiled once, for float and double.
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "differential_types.hpp"
#include "spotkin/compatibility.hpp"

namespace spotkin::differential {

template <typename S>
bool singular_values(const S* Jp, int m, int n, S* sigma) noexcept {
  const int k = std::min(m, n);
  if (!all_finite(Jp, std::ptrdiff_t(m) * n)) {
    fill_nan(sigma, k);
    return false;
  }
  Eigen::JacobiSVD<Types<double>::ColMajor, Eigen::ColPivHouseholderQRPreconditioner> svd(m, n);
  svd.compute(jacobian_in_double(Jp, m, n));
  for (int i = 0; i < k; ++i) sigma[i] = S(svd.singularValues()[i]);
  return true;
}

template <typename S>
std::int64_t rank(const S* Jp, int m, int n, S tol) noexcept {
  S sigma[kMaxDim];
  if (!singular_values<S>(Jp, m, n, sigma)) return -1;
  const int k = std::min(m, n);
  const S cutoff = tol >= S(0) ? tol : default_tolerance<S>(m, n, k > 0 ? sigma[0] : S(0));
  std::int64_t r = 0;
  for (int i = 0; i < k; ++i) r += sigma[i] > cutoff;
  return r;
}

template <typename S>
S manipulability(const S* Jp, int m, int n) noexcept {
  S sigma[kMaxDim];
  if (!singular_values<S>(Jp, m, n, sigma)) return quiet_nan<S>();
  if (m > n) return S(0);
  S w = S(1);
  for (int i = 0; i < m; ++i) w *= sigma[i];
  return w;
}

// tol >= 0 is absolute; tol < 0 asks for the default above.
template <typename S>
Compatibility<S> compatibility(const S* Jp, const S* dxp, int m, int n, S tol) noexcept {
  using T = Types<double>;
  if (!all_finite(Jp, std::ptrdiff_t(m) * n) || !all_finite(dxp, m)) return {quiet_nan<S>(), false};
  Eigen::JacobiSVD<T::ColMajor, Eigen::ColPivHouseholderQRPreconditioner> svd(m, n, Eigen::ComputeFullU);
  svd.compute(jacobian_in_double(Jp, m, n));
  const auto& sigma = svd.singularValues();
  const int k = std::min(m, n);
  const double sigma_max = k > 0 ? sigma[0] : 0.0;
  const double cutoff = std::max(m, n) * double(std::numeric_limits<S>::epsilon()) * sigma_max;  // as rank()
  // dx / scale, so the squares neither underflow nor overflow
  double scale = 0;
  for (int i = 0; i < m; ++i) scale = std::max(scale, std::fabs(double(dxp[i])));
  if (scale == 0.0) return {S(0), true};
  const T::VecM dx = vector_in_double(dxp, m) / scale;
  double outside = 0, pinv_norm2 = 0;
  for (int i = 0; i < m; ++i) {
    const double c = svd.matrixU().col(i).dot(dx);
    if (i < k && sigma[i] > cutoff)
      pinv_norm2 += (c / sigma[i]) * (c / sigma[i]);
    else
      outside += c * c;
  }
  // the rounding bound of the input's precision (S's epsilon)
  const S residual = S(scale * std::sqrt(outside));
  const S bound = tol >= S(0) ? tol
                              : S(std::max(m, n) * double(std::numeric_limits<S>::epsilon()) * scale *
                                  (dx.norm() + sigma_max * std::sqrt(pinv_norm2)));
  return {residual, residual <= bound};
}

#define SPOTKIN_INSTANTIATE(S)                                                 \
  template bool singular_values<S>(const S*, int, int, S*) noexcept;          \
  template std::int64_t rank<S>(const S*, int, int, S) noexcept;              \
  template S manipulability<S>(const S*, int, int) noexcept;                  \
  template Compatibility<S> compatibility<S>(const S*, const S*, int, int, S) noexcept;
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::differential
