// Differential inverse kinematics (the course's summary sheet, "modèle différentiel inverse",
// "redondance"; the course's classic-DH leg, inverse model by the inverted Jacobian): damped least
// squares, the Moore-Penrose pseudo-inverse, null-space projection, singular
// values, rank and manipulability, per sample; and closed-loop IK along a path
// of targets for any Chain.
//
// Decompositions, chosen by measurement (2-core development machine, float64,
// ns per sample; Eigen 3.4 scalar code):
//                                   3x3    6x6    12x18
//   LLT of J J^T + lambda^2 I        65    190    1350
//   CompleteOrthogonalDecomposition  240    545    3300
//   JacobiSVD (U and V)              750   5400   33000
// so damped least squares with lambda > 0 solves the damped normal equations
// by Cholesky (the matrix is symmetric positive definite, eigenvalues >=
// lambda^2); the pseudo-inverse (lambda = 0, pinv, the null-space projector)
// uses the complete orthogonal decomposition; only the quantities that are
// singular values (singular_values, rank, manipulability) pay for an SVD.
// The Cholesky path has fixed-size code for 3x3, 6x6 and 12x18 and
// stack-allocated dynamic-size matrices (up to kMaxDim) for other shapes. The
// SVD and COD run on the dynamic-size matrices for every shape: fixed-size
// instantiations of them for the three shapes took this one file over ten
// minutes to compile (GCC -O3), for a speed that matters less off the hot path.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "spotkin/chain.hpp"
#include "spotkin/common.hpp"

namespace spotkin::differential {

constexpr int kMaxDim = 64;
constexpr int Dyn = Eigen::Dynamic;

// Matrix types for compile-time sizes (M, N), or Dyn with a kMaxDim cap.
template <typename S, int M, int N>
struct Types {
  static constexpr int kMaxM = M == Dyn ? kMaxDim : M;
  static constexpr int kMaxN = N == Dyn ? kMaxDim : N;
  static constexpr int kMin = (M == Dyn || N == Dyn) ? Dyn : (M < N ? M : N);
  static constexpr int kMaxMin = kMaxM < kMaxN ? kMaxM : kMaxN;
  using Jac = Eigen::Matrix<S, M, N, Eigen::RowMajor, kMaxM, kMaxN>;  // row-major like numpy
  using JacT = Eigen::Matrix<S, N, M, Eigen::RowMajor, kMaxN, kMaxM>;
  using SquareM = Eigen::Matrix<S, M, M, Eigen::ColMajor, kMaxM, kMaxM>;
  using SquareN = Eigen::Matrix<S, N, N, Eigen::RowMajor, kMaxN, kMaxN>;
  using VecM = Eigen::Matrix<S, M, 1, Eigen::ColMajor, kMaxM, 1>;
  using VecN = Eigen::Matrix<S, N, 1, Eigen::ColMajor, kMaxN, 1>;
  using Svd = Eigen::JacobiSVD<Eigen::Matrix<S, M, N, Eigen::ColMajor, kMaxM, kMaxN>, Eigen::ColPivHouseholderQRPreconditioner>;
  using Cod = Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<S, M, N, Eigen::ColMajor, kMaxM, kMaxN>>;
};

template <typename S>
SPOTKIN_INLINE bool all_finite(const S* x, std::ptrdiff_t count) noexcept {
  bool ok = true;
  for (std::ptrdiff_t i = 0; i < count; ++i) ok &= std::isfinite(x[i]);
  return ok;
}

template <typename S>
SPOTKIN_INLINE void fill_nan(S* x, std::ptrdiff_t count) noexcept {
  std::fill(x, x + count, quiet_nan<S>());
}

// Default rank tolerance, as numpy.linalg.matrix_rank: max(m, n) * eps * sigma_max.
template <typename S>
SPOTKIN_INLINE S default_tolerance(int m, int n, S sigma_max) noexcept {
  return S(std::max(m, n)) * std::numeric_limits<S>::epsilon() * sigma_max;
}

// The pseudo-inverse's relative cutoff for the complete orthogonal
// decomposition: pivots |r_kk| <= max(m, n) * eps * |r_11| count as zero.
template <typename S>
SPOTKIN_INLINE S cod_threshold(int m, int n) noexcept {
  return S(std::max(m, n)) * std::numeric_limits<S>::epsilon();
}

template <typename S, int M, int N>
SPOTKIN_INLINE Eigen::Map<const typename Types<S, M, N>::Jac> map_jacobian(const S* J, int m, int n) noexcept {
  return Eigen::Map<const typename Types<S, M, N>::Jac>(J, m, n);
}

template <typename S>
inline void pinv_solve(const S* Jp, const S* dxp, const S* zp, int m, int n, S* dqp) noexcept;

// Damped least squares, lambda2 = damping^2 > 0:
//   dq = J^T (J J^T + lambda^2 I_m)^-1 dx          (m <= n)
//      = (J^T J + lambda^2 I_n)^-1 J^T dx          (m > n; the same matrix, since
//        J^T (J J^T + l^2 I) = (J^T J + l^2 I) J^T)
// solved by Cholesky on the smaller Gram matrix (see damping_below_rounding for
// a damping too small to matter; a factorisation that still meets a
// non-positive pivot also gives J^+ dx, never NaN).
// Returns false when the factorisation met a non-positive pivot.
template <typename S, int M, int N>
SPOTKIN_INLINE bool dls_damped_cholesky(const S* Jp, const S* dxp, S lambda2, int m, int n, S* dqp) noexcept {
  using T = Types<S, M, N>;
  const auto J = map_jacobian<S, M, N>(Jp, m, n);
  const Eigen::Map<const typename T::VecM> dx(dxp, m);
  Eigen::Map<typename T::VecN> dq(dqp, n);
  if (m <= n) {
    typename T::SquareM A = J * J.transpose();
    A.diagonal().array() += lambda2;
    const Eigen::LLT<typename T::SquareM> llt(A);
    dq.noalias() = J.transpose() * llt.solve(dx);
    return llt.info() == Eigen::Success;
  }
  typename T::SquareN A = J.transpose() * J;
  A.diagonal().array() += lambda2;
  const typename T::VecN rhs = J.transpose() * dx;
  const Eigen::LLT<typename T::SquareN> llt(A);
  dq = llt.solve(rhs);
  return llt.info() == Eigen::Success;
}

// lambda^2 at or below the rounding of J J^T: (J J^T + lambda^2 I) is J J^T in
// floating point, and a singular J's factorisation is rounding noise. Such a
// damping is numerically zero: the step is its lambda -> 0 limit, J^+ dx. The
// bound uses double's epsilon for both dtypes, so a float32 step with a usual
// damping (1e-3) stays damped.
template <typename S>
SPOTKIN_INLINE bool damping_below_rounding(const S* J, int m, int n, S lambda2) noexcept {
  double frobenius2 = 0.0;
  for (int k = 0; k < m * n; ++k) frobenius2 += double(J[k]) * double(J[k]);
  return double(lambda2) <= std::numeric_limits<double>::epsilon() * frobenius2;
}

template <typename S, int M, int N>
SPOTKIN_INLINE void dls_damped(const S* Jp, const S* dxp, S lambda2, int m, int n, S* dqp) noexcept {
  if (damping_below_rounding(Jp, m, n, lambda2)) return pinv_solve<S>(Jp, dxp, nullptr, m, n, dqp);
  bool ok = dls_damped_cholesky<S, M, N>(Jp, dxp, lambda2, m, n, dqp);
  for (int j = 0; j < n; ++j) ok = ok && std::isfinite(dqp[j]);
  if (!ok) pinv_solve<S>(Jp, dxp, nullptr, m, n, dqp);
}

// dls_damped for a block of kDlsBlock samples at fixed M <= N, vectorised
// across samples (structure of arrays: J[r * N + c][i] is J_rc of sample i):
// A = J J^T + lambda^2 I, A = L L^T (Cholesky-Banachiewicz), L y = dx,
// L^T x = y, dq = J^T x. Padding samples (J = 0) give A = lambda^2 I.
constexpr int kDlsBlock = 32;

SPOTKIN_CLONES_T((template <typename S, int M, int N> __attribute__((noinline))), void, dls_block, (<S, M, N>), (const S (*__restrict J)[kDlsBlock], const S (*__restrict dx)[kDlsBlock], S lambda2,
                                     S (*__restrict dq)[kDlsBlock]) noexcept, (J, dx, lambda2, dq),
  constexpr int B = kDlsBlock;
  auto at = [](int r, int c) { return r * (r + 1) / 2 + c; };  // packed lower triangle, c <= r
  S L[M * (M + 1) / 2][B], inv[M][B], y[M][B];
  for (int r = 0; r < M; ++r)
    for (int c = 0; c <= r; ++c) {
      S* out = L[at(r, c)];
      for (int i = 0; i < B; ++i) out[i] = r == c ? lambda2 : S(0);
      for (int k = 0; k < N; ++k)
        for (int i = 0; i < B; ++i) out[i] += J[r * N + k][i] * J[c * N + k][i];
    }
  for (int j = 0; j < M; ++j) {
    for (int k = 0; k < j; ++k)
      for (int i = 0; i < B; ++i) L[at(j, j)][i] -= L[at(j, k)][i] * L[at(j, k)][i];
    for (int i = 0; i < B; ++i) inv[j][i] = S(1) / std::sqrt(L[at(j, j)][i]);
    for (int r = j + 1; r < M; ++r) {
      for (int k = 0; k < j; ++k)
        for (int i = 0; i < B; ++i) L[at(r, j)][i] -= L[at(r, k)][i] * L[at(j, k)][i];
      for (int i = 0; i < B; ++i) L[at(r, j)][i] *= inv[j][i];
    }
  }
  for (int r = 0; r < M; ++r) {
    for (int i = 0; i < B; ++i) y[r][i] = dx[r][i];
    for (int k = 0; k < r; ++k)
      for (int i = 0; i < B; ++i) y[r][i] -= L[at(r, k)][i] * y[k][i];
    for (int i = 0; i < B; ++i) y[r][i] *= inv[r][i];
  }
  for (int r = M - 1; r >= 0; --r) {
    for (int k = r + 1; k < M; ++k)
      for (int i = 0; i < B; ++i) y[r][i] -= L[at(k, r)][i] * y[k][i];
    for (int i = 0; i < B; ++i) y[r][i] *= inv[r][i];
  }
  for (int c = 0; c < N; ++c) {
    for (int i = 0; i < B; ++i) dq[c][i] = S(0);
    for (int r = 0; r < M; ++r)
      for (int i = 0; i < B; ++i) dq[c][i] += J[r * N + c][i] * y[r][i];
  }
)

// The minimum-norm least-squares solution dq = J^+ dx (the limit lambda -> 0 of
// dls) and, when z is given, the null-space term (I - J^+ J) z, which J maps to
// zero, so J dq = J J^+ dx whatever z is.
template <typename S>
inline void pinv_solve(const S* Jp, const S* dxp, const S* zp, int m, int n, S* dqp) noexcept {
  using T = Types<S, Dyn, Dyn>;
  const auto J = map_jacobian<S, Dyn, Dyn>(Jp, m, n);
  typename T::Cod cod(m, n);
  cod.setThreshold(cod_threshold<S>(m, n));
  cod.compute(J);
  Eigen::Map<typename T::VecN> dq(dqp, n);
  if (dxp != nullptr) {
    dq = cod.solve(Eigen::Map<const typename T::VecM>(dxp, m));
  } else {
    dq.setZero();
  }
  if (zp != nullptr) {
    const Eigen::Map<const typename T::VecN> z(zp, n);
    const typename T::VecM Jz = J * z;
    const typename T::VecN back = cod.solve(Jz);
    dq += z - back;
  }
}

// dls with an optional secondary task z projected into the null space:
//   dq = J^T (J J^T + lambda^2 I)^-1 dx + (I - J^+ J) z
// The projector uses the exact pseudo-inverse, so J (I - J^+ J) z = 0 and the
// primary task is the same as without z. lambda = 0 gives J^+ dx. Non-finite
// input gives an all-NaN dq.
template <typename S, int M, int N>
SPOTKIN_INLINE void dls(const S* J, const S* dx, const S* z, S lambda2, int m, int n, S* dq) noexcept {
  if (!all_finite(J, std::ptrdiff_t(m) * n) || !all_finite(dx, m) || (z != nullptr && !all_finite(z, n))) {
    fill_nan(dq, n);
    return;
  }
  if (lambda2 > S(0)) {
    dls_damped<S, M, N>(J, dx, lambda2, m, n, dq);
    if (z == nullptr) return;
    S null_part[kMaxDim];
    pinv_solve<S>(J, nullptr, z, m, n, null_part);
    for (int j = 0; j < n; ++j) dq[j] += null_part[j];
  } else {
    pinv_solve<S>(J, dx, z, m, n, dq);
  }
}

// J^+ (n x m, row-major) from the complete orthogonal decomposition
// J P = Q [T 0; 0 0] Z: J^+ = P Z^T [T^-1 0; 0 0] Q^T.
template <typename S>
inline void pinv(const S* Jp, int m, int n, S* outp) noexcept {
  using T = Types<S, Dyn, Dyn>;
  if (!all_finite(Jp, std::ptrdiff_t(m) * n)) {
    fill_nan(outp, std::ptrdiff_t(m) * n);
    return;
  }
  typename T::Cod cod(m, n);
  cod.setThreshold(cod_threshold<S>(m, n));
  cod.compute(map_jacobian<S, Dyn, Dyn>(Jp, m, n));
  Eigen::Map<typename T::JacT>(outp, n, m) = cod.pseudoInverse();
}

// Null-space projector P = I_n - J^+ J (n x n, row-major): symmetric,
// idempotent, J P = 0.
template <typename S>
inline void nullspace_projector(const S* Jp, int m, int n, S* outp) noexcept {
  using T = Types<S, Dyn, Dyn>;
  if (!all_finite(Jp, std::ptrdiff_t(m) * n)) {
    fill_nan(outp, std::ptrdiff_t(n) * n);
    return;
  }
  const auto J = map_jacobian<S, Dyn, Dyn>(Jp, m, n);
  typename T::Cod cod(m, n);
  cod.setThreshold(cod_threshold<S>(m, n));
  cod.compute(J);
  typename T::SquareN P = -(cod.pseudoInverse() * J);
  P.diagonal().array() += S(1);
  Eigen::Map<typename T::SquareN>(outp, n, n) = S(0.5) * (P + P.transpose());  // exactly symmetric
}

// Singular values, descending, min(m, n) of them (two-sided Jacobi SVD: small
// singular values to full relative accuracy of the input, unlike the
// eigenvalues of J J^T). Returns false (and NaN) for non-finite input.
template <typename S>
inline bool singular_values(const S* Jp, int m, int n, S* sigma) noexcept {
  using T = Types<S, Dyn, Dyn>;
  const int k = std::min(m, n);
  if (!all_finite(Jp, std::ptrdiff_t(m) * n)) {
    fill_nan(sigma, k);
    return false;
  }
  typename T::Svd svd(m, n);
  svd.compute(map_jacobian<S, Dyn, Dyn>(Jp, m, n));
  for (int i = 0; i < k; ++i) sigma[i] = svd.singularValues()[i];
  return true;
}

// rank = #{sigma_i > tol}, tol = max(m, n) * eps * sigma_max unless tol >= 0 is
// given. Non-finite J gives -1.
template <typename S>
inline std::int64_t rank(const S* Jp, int m, int n, S tol) noexcept {
  S sigma[kMaxDim];
  if (!singular_values<S>(Jp, m, n, sigma)) return -1;
  const int k = std::min(m, n);
  const S cutoff = tol >= S(0) ? tol : default_tolerance<S>(m, n, k > 0 ? sigma[0] : S(0));
  std::int64_t r = 0;
  for (int i = 0; i < k; ++i) r += sigma[i] > cutoff;
  return r;
}

// Yoshikawa's manipulability sqrt(det(J J^T)) = prod sigma_i for m <= n; for
// m > n, J J^T (m x m) has rank <= n < m, so it is 0.
template <typename S>
inline S manipulability(const S* Jp, int m, int n) noexcept {
  S sigma[kMaxDim];
  if (!singular_values<S>(Jp, m, n, sigma)) return quiet_nan<S>();
  if (m > n) return S(0);
  S w = S(1);
  for (int i = 0; i < m; ++i) w *= sigma[i];
  return w;
}

// Calls f(std::integral_constant M, N) for the fixed-size shapes of the
// Cholesky path, or with Dyn.
template <typename F>
decltype(auto) with_shape(int m, int n, F&& f) {
  if (m == 6 && n == 6) return f(std::integral_constant<int, 6>{}, std::integral_constant<int, 6>{});
  if (m == 3 && n == 3) return f(std::integral_constant<int, 3>{}, std::integral_constant<int, 3>{});
  if (m == 12 && n == 18) return f(std::integral_constant<int, 12>{}, std::integral_constant<int, 18>{});
  return f(std::integral_constant<int, Dyn>{}, std::integral_constant<int, Dyn>{});
}

// ---------------------------------------------------------------------------
// Closed-loop IK along a path of targets.

// log of a rotation matrix as an axis-angle vector theta * a, theta in [0, pi]:
//   w = vee(R - R^T) / 2 = sin(theta) a,  cos(theta) = (tr R - 1) / 2,
//   theta / sin(theta) * w away from pi; near pi the axis comes from the
//   symmetric part (R + R^T) / 2 - cos(theta) I = (1 - cos(theta)) a a^T,
//   signed like w.
template <typename S>
inline Vec3<S> log_rotation(const Mat3<S>& R) noexcept {
  const Vec3<S> w(S(0.5) * (R(2, 1) - R(1, 2)), S(0.5) * (R(0, 2) - R(2, 0)), S(0.5) * (R(1, 0) - R(0, 1)));
  const S c = std::clamp(S(0.5) * (R.trace() - S(1)), S(-1), S(1));
  const S s = w.norm();
  const S theta = std::atan2(s, c);
  if (c > S(-0.9)) {
    const S scale = s < S(1e-4) ? S(1) + theta * theta / S(6) : theta / s;  // theta / sin(theta)
    return scale * w;
  }
  const Mat3<S> B = S(0.5) * (R + R.transpose()) - c * Mat3<S>::Identity();
  int k = 0;
  B.diagonal().maxCoeff(&k);
  Vec3<S> axis = B.col(k) / std::sqrt(std::max(B(k, k), S(0)) * (S(1) - c));
  if (axis.dot(w) < S(0)) axis = -axis;
  return theta * axis.normalized();
}

struct IkOptions {
  double damping = 1e-2;           // lambda
  double position_tolerance = 1e-6;     // m, ||p_target - p||
  double orientation_tolerance = 1e-6;  // rad, ||log(R_target R^T)||
  double max_step = 0.5;           // largest |dq_j| per iteration (rad or m)
  int max_iterations = 100;
  int rows = 6;                    // 6: pose, 3: position only
};

struct IkResult {
  bool converged;
  std::int32_t iterations;
  double position_error, orientation_error;
};

// Pose error [p_t - p; log(R_t R^T)] in the base frame, the frame of the
// chain's geometric Jacobian (d p / dt = v, d R / dt = [w]x R).
inline void pose_error(const Rigid<double>& target, const Rigid<double>& T, double* e) noexcept {
  const Vec3<double> dp = target.p - T.p;
  const Vec3<double> dw = log_rotation<double>(target.R * T.R.transpose());
  for (int i = 0; i < 3; ++i) {
    e[i] = dp[i];
    e[i + 3] = dw[i];
  }
}

// One DLS step dq = J^T (J J^T + lambda^2 I)^-1 e with the columns of locked
// joints zeroed (rows <= 6).
inline void ik_step(const double* J, const double* e, const bool* locked, int rows, int n, double lambda2,
                    double* dq) noexcept {
  using Mat = Eigen::Matrix<double, Dyn, Dyn, Eigen::RowMajor, 6, Chain<double>::kMaxJoints>;
  Eigen::Map<const Mat> Jfull(J, rows, n);
  Mat Jm = Jfull;
  for (int j = 0; j < n; ++j)
    if (locked[j]) Jm.col(j).setZero();
  dls_damped<double, Dyn, Dyn>(Jm.data(), e, lambda2, rows, n, dq);
}


// A finite (4, 4) rigid transform, row-major: last row [0, 0, 0, 1] (1e-9),
// max |R^T R - I| <= 1e-6 and det R > 0, as the closed-form IK accepts (Arm::read_pose).
inline bool is_rigid_transform(const double* T) noexcept {
  if (!all_finite(T, 16)) return false;
  const double row_error = std::max(std::max(std::fabs(T[12]), std::fabs(T[13])),
                                    std::max(std::fabs(T[14]), std::fabs(T[15] - 1.0)));
  if (!(row_error <= 1e-9)) return false;
  double orth = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double dot = T[a] * T[b] + T[4 + a] * T[4 + b] + T[8 + a] * T[8 + b];
      orth = std::max(orth, std::fabs(dot - (a == b ? 1.0 : 0.0)));
    }
  const double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                     T[2] * (T[4] * T[9] - T[5] * T[8]);
  return orth <= 1e-6 && det > 0.0;
}

// Closed-loop IK for one sample: targets K x (4, 4) row-major, q0 (n), limits
// (n). For each target in turn, from the previous result (q0 clamped into the
// limits for the first): stop if converged, else a DLS step on the pose error,
// capped at max_step per joint, then clamped into [lower, upper]. A joint at a
// limit whose step points out of range is locked (its column removed) and the
// step re-solved, so the others make up for it.
inline void ik_differential(const Chain<double>& chain, const double* lower, const double* upper,
                            const double* targets, std::ptrdiff_t K, const double* q0, const IkOptions& opt,
                            double* q_path, IkResult* results) noexcept {
  const int n = chain.dof();
  const int rows = opt.rows;
  const double lambda2 = opt.damping * opt.damping;
  double q[Chain<double>::kMaxJoints], dq[Chain<double>::kMaxJoints], J[6 * Chain<double>::kMaxJoints];
  bool locked[Chain<double>::kMaxJoints];
  for (int j = 0; j < n; ++j) q[j] = std::clamp(q0[j], lower[j], upper[j]);
  bool finite_seed = all_finite(q0, n);
  for (std::ptrdiff_t k = 0; k < K; ++k) {
    const double* Tk = targets + 16 * k;
    Rigid<double> target;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) target.R(i, j) = Tk[4 * i + j];
      target.p[i] = Tk[4 * i + 3];
    }
    IkResult& res = results[k];
    double* qk = q_path + k * n;
    if (!finite_seed || !is_rigid_transform(Tk)) {  // invalid in, NaN out; the path continues from q
      fill_nan(qk, n);
      res = {false, 0, quiet_nan<double>(), quiet_nan<double>()};
      continue;
    }
    double e[6];
    int it = 0;
    bool converged = false;
    for (;; ++it) {
      pose_error(target, chain.forward(q), e);
      const double ep = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      const double eo = std::sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]);
      res.position_error = ep;
      res.orientation_error = eo;
      converged = ep <= opt.position_tolerance && (rows == 3 || eo <= opt.orientation_tolerance);
      if (converged || it >= opt.max_iterations || !std::isfinite(ep + eo)) break;
      chain.jacobian(q, J, rows, false);
      std::fill(locked, locked + n, false);
      ik_step(J, e, locked, rows, n, lambda2, dq);
      bool relock = false;
      for (int j = 0; j < n; ++j) {
        if ((q[j] <= lower[j] && dq[j] < 0) || (q[j] >= upper[j] && dq[j] > 0)) locked[j] = relock = true;
      }
      if (relock) ik_step(J, e, locked, rows, n, lambda2, dq);
      double largest = 0;
      for (int j = 0; j < n; ++j) largest = std::max(largest, std::abs(dq[j]));
      const double scale = largest > opt.max_step ? opt.max_step / largest : 1.0;
      for (int j = 0; j < n; ++j) q[j] = locked[j] ? q[j] : std::clamp(q[j] + scale * dq[j], lower[j], upper[j]);
    }
    res.converged = converged;
    res.iterations = it;
    std::copy(q, q + n, qk);
  }
}

}  // namespace spotkin::differential
