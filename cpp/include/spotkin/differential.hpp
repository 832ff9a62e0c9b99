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
// The Cholesky path has vectorised fixed-size blocks for 3x3, 6x6 and 12x18
// (dls_block, here, instantiated by the bindings) and stack-allocated
// dynamic-size Eigen matrices (up to kMaxDim) for other shapes. The Eigen code
// (LLT, COD, SVD) is compiled once, in cpp/src/differential.cpp, for float and
// double: each instantiation of it costs GCC's front end about 10 s, and every
// translation unit that included it paid again.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "spotkin/chain.hpp"
#include "spotkin/common.hpp"

namespace spotkin::differential {

constexpr int kMaxDim = 64;

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

// The minimum-norm least-squares solution dq = J^+ dx (the limit lambda -> 0 of
// dls) and, when z is given, the null-space term (I - J^+ J) z, which J maps to
// zero, so J dq = J J^+ dx whatever z is. zp and dxp may be null.
template <typename S>
void pinv_solve(const S* Jp, const S* dxp, const S* zp, int m, int n, S* dqp) noexcept;

// dls with an optional secondary task z projected into the null space:
//   dq = J^T (J J^T + lambda^2 I)^-1 dx + (I - J^+ J) z
// The projector uses the exact pseudo-inverse, so J (I - J^+ J) z = 0 and the
// primary task is the same as without z. lambda = 0 gives J^+ dx. Non-finite
// input gives an all-NaN dq.
template <typename S>
void dls(const S* J, const S* dx, const S* z, S lambda2, int m, int n, S* dq) noexcept;

// J^+ (n x m, row-major) from the complete orthogonal decomposition
// J P = Q [T 0; 0 0] Z: J^+ = P Z^T [T^-1 0; 0 0] Q^T.
template <typename S>
void pinv(const S* Jp, int m, int n, S* outp) noexcept;

// Null-space projector P = I_n - J^+ J (n x n, row-major): symmetric,
// idempotent, J P = 0.
template <typename S>
void nullspace_projector(const S* Jp, int m, int n, S* outp) noexcept;

// Singular values, descending, min(m, n) of them (two-sided Jacobi SVD: small
// singular values to full relative accuracy of the input, unlike the
// eigenvalues of J J^T). Returns false (and NaN) for non-finite input.
template <typename S>
bool singular_values(const S* Jp, int m, int n, S* sigma) noexcept;

// rank = #{sigma_i > tol}, tol = max(m, n) * eps * sigma_max unless tol >= 0 is
// given. Non-finite J gives -1.
template <typename S>
std::int64_t rank(const S* Jp, int m, int n, S tol) noexcept;

// Yoshikawa's manipulability sqrt(det(J J^T)) = prod sigma_i for m <= n; for
// m > n, J J^T (m x m) has rank <= n < m, so it is 0.
template <typename S>
S manipulability(const S* Jp, int m, int n) noexcept;

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

// Damped least squares over `count` contiguous rows of J (M x N) and dx (M), kDlsBlock samples at
// a time in lanes (dls_block); a sample whose damping is below rounding, or whose lane answer is
// not finite, is solved again alone (pinv_solve); a sample with a NaN or an Inf gets NaN.
template <typename T, int M, int N>
void dls_rows(const T* J, const T* dx, T lambda2, T* out, std::ptrdiff_t count) noexcept {
  constexpr int B = kDlsBlock;
  T Js[M * N][B], dxs[M][B], dqs[N][B];
  bool finite[B];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += B) {
    const int k = static_cast<int>(std::min<std::ptrdiff_t>(B, count - b0));
    for (int i = 0; i < B; ++i) {
      const T* Ji = i < k ? J + (b0 + i) * M * N : nullptr;
      const T* di = i < k ? dx + (b0 + i) * M : nullptr;
      finite[i] = i < k && all_finite(Ji, M * N) && all_finite(di, M);
      for (int r = 0; r < M * N; ++r) Js[r][i] = finite[i] ? Ji[r] : T(0);
      for (int r = 0; r < M; ++r) dxs[r][i] = finite[i] ? di[r] : T(0);
    }
    dls_block<T, M, N>(Js, dxs, lambda2, dqs);
    for (int i = 0; i < k; ++i) {
      T* dq = out + (b0 + i) * N;
      bool ok = finite[i];
      for (int c = 0; c < N; ++c) ok = ok && std::isfinite(dqs[c][i]), dq[c] = finite[i] ? dqs[c][i] : quiet_nan<T>();
      const T* Ji = J + (b0 + i) * M * N;
      if (finite[i] && (!ok || damping_below_rounding(Ji, M, N, lambda2)))
        pinv_solve<T>(Ji, dx + (b0 + i) * M, nullptr, M, N, dq);
    }
  }
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
void ik_differential(const Chain<double>& chain, const double* lower, const double* upper, const double* targets,
                     std::ptrdiff_t K, const double* q0, const IkOptions& opt, double* q_path,
                     IkResult* results) noexcept;

}  // namespace spotkin::differential
