// The Cholesky and complete-orthogonal-decomposition paths of
// spotkin/differential.hpp (dls, pinv, the null-space projector) and the
// closed-loop IK, compiled once, for float and double.
#include "spotkin/differential.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>

#include "differential_types.hpp"
#include "spotkin/dense.hpp"

namespace spotkin::differential {

namespace {

// Damped least squares, lambda2 = damping^2 > 0:
//   dq = J^T (J J^T + lambda^2 I_m)^-1 dx          (m <= n)
//      = (J^T J + lambda^2 I_n)^-1 J^T dx          (m > n; the same matrix, since
//        J^T (J J^T + l^2 I) = (J^T J + l^2 I) J^T)
// solved by Cholesky on the smaller Gram matrix (see damping_below_rounding for
// a damping too small to matter; a factorisation that still meets a
// non-positive pivot also gives J^+ dx, never NaN).
// Returns false when the factorisation met a non-positive pivot.
template <typename S>
bool dls_damped_cholesky(const S* Jp, const S* dxp, S lambda2, int m, int n, S* dqp) noexcept {
  using T = Types<double>;
  const T::Jac J = jacobian_in_double(Jp, m, n);
  const T::VecM dx = vector_in_double(dxp, m);
  T::VecN dq;
  bool ok;
  if (m <= n) {
    T::SquareM A = J * J.transpose();
    A.diagonal().array() += double(lambda2);
    const Eigen::LLT<T::SquareM> llt(A);
    dq.noalias() = J.transpose() * llt.solve(dx);
    ok = llt.info() == Eigen::Success;
  } else {
    T::SquareN A = J.transpose() * J;
    A.diagonal().array() += double(lambda2);
    const T::VecN rhs = J.transpose() * dx;
    const Eigen::LLT<T::SquareN> llt(A);
    dq = llt.solve(rhs);
    ok = llt.info() == Eigen::Success;
  }
  Eigen::Map<VecOf<S>>(dqp, n) = dq.template cast<S>();
  return ok;
}

template <typename S>
void dls_damped(const S* Jp, const S* dxp, S lambda2, int m, int n, S* dqp) noexcept {
  if (damping_below_rounding(Jp, m, n, lambda2)) return pinv_solve<S>(Jp, dxp, nullptr, m, n, dqp);
  bool ok = dls_damped_cholesky<S>(Jp, dxp, lambda2, m, n, dqp);
  for (int j = 0; j < n; ++j) ok = ok && std::isfinite(dqp[j]);
  if (!ok) pinv_solve<S>(Jp, dxp, nullptr, m, n, dqp);
}

// J (rows x n, row-major) with the columns of locked joints zeroed, one DLS step
// on e (rows <= 6).
void ik_step(const double* J, const double* e, const bool* locked, int rows, int n, double lambda2,
             double* dq) noexcept {
  using Mat = Eigen::Matrix<double, Dyn, Dyn, Eigen::RowMajor, 6, Chain<double>::kMaxJoints>;
  Eigen::Map<const Mat> Jfull(J, rows, n);
  Mat Jm = Jfull;
  for (int j = 0; j < n; ++j)
    if (locked[j]) Jm.col(j).setZero();
  dls_damped<double>(Jm.data(), e, lambda2, rows, n, dq);
}

using Cod = Eigen::CompleteOrthogonalDecomposition<Types<double>::ColMajor>;

// J's complete orthogonal decomposition, in double, with the rank cutoff of the input's type.
template <typename S>
Cod complete_orthogonal(const Types<double>::Jac& J, int m, int n) noexcept {
  Cod cod(m, n);
  cod.setThreshold(cod_threshold<S>(m, n));
  cod.compute(J);
  return cod;
}

}  // namespace

template <typename S>
void pinv_solve(const S* Jp, const S* dxp, const S* zp, int m, int n, S* dqp) noexcept {
  using T = Types<double>;
  const T::Jac J = jacobian_in_double(Jp, m, n);
  const Cod cod = complete_orthogonal<S>(J, m, n);
  T::VecN dq = T::VecN::Zero(n);
  if (dxp != nullptr) dq = cod.solve(vector_in_double(dxp, m));
  if (zp != nullptr) {
    const T::VecN z = vector_in_double(zp, n);
    const T::VecM Jz = J * z;
    const T::VecN back = cod.solve(Jz);
    dq += z - back;
  }
  Eigen::Map<VecOf<S>>(dqp, n) = dq.template cast<S>();
}

template <typename S>
void dls(const S* J, const S* dx, const S* z, S lambda2, int m, int n, S* dq) noexcept {
  if (!all_finite(J, std::ptrdiff_t(m) * n) || !all_finite(dx, m) || (z != nullptr && !all_finite(z, n))) {
    fill_nan(dq, n);
    return;
  }
  if (lambda2 > S(0)) {
    dls_damped<S>(J, dx, lambda2, m, n, dq);
    if (z == nullptr) return;
    S null_part[kMaxDim];
    pinv_solve<S>(J, nullptr, z, m, n, null_part);
    for (int j = 0; j < n; ++j) dq[j] += null_part[j];
  } else {
    pinv_solve<S>(J, dx, z, m, n, dq);
  }
}

template <typename S>
void pinv(const S* Jp, int m, int n, S* outp) noexcept {
  if (!all_finite(Jp, std::ptrdiff_t(m) * n)) {
    fill_nan(outp, std::ptrdiff_t(m) * n);
    return;
  }
  const Cod cod = complete_orthogonal<S>(jacobian_in_double(Jp, m, n), m, n);
  Eigen::Map<RowMajorOf<S>>(outp, n, m) = cod.pseudoInverse().template cast<S>();
}

template <typename S>
void nullspace_projector(const S* Jp, int m, int n, S* outp) noexcept {
  using T = Types<double>;
  if (!all_finite(Jp, std::ptrdiff_t(m) * n)) {
    fill_nan(outp, std::ptrdiff_t(n) * n);
    return;
  }
  const T::Jac J = jacobian_in_double(Jp, m, n);
  const Cod cod = complete_orthogonal<S>(J, m, n);
  T::SquareN P = -(cod.pseudoInverse() * J);
  P.diagonal().array() += 1.0;
  Eigen::Map<RowMajorOf<S>>(outp, n, n) = (0.5 * (P + P.transpose())).template cast<S>();  // exactly symmetric
}

void ik_differential(const Chain<double>& chain, const double* lower, const double* upper,
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

#define SPOTKIN_INSTANTIATE(S)                                                                          \
  template void pinv_solve<S>(const S*, const S*, const S*, int, int, S*) noexcept;                    \
  template void dls<S>(const S*, const S*, const S*, S, int, int, S*) noexcept;                        \
  template void pinv<S>(const S*, int, int, S*) noexcept;                                              \
  template void nullspace_projector<S>(const S*, int, int, S*) noexcept;
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::differential

namespace spotkin::dense {

// spotkin/dense.hpp: here, so that the build instantiates Eigen's complete orthogonal
// decomposition once (pinv_solve's; a 6 x dynamic one of its own took 9 s of compiling).
void cod_solve6(const double* J_row_major, int n, const double* e, double threshold, double* dq) {
  using T = differential::Types<double>;
  differential::Cod cod(6, n);
  cod.setThreshold(threshold);
  cod.compute(differential::map_jacobian<double>(J_row_major, 6, n));
  const T::VecN x = cod.solve(differential::vector_in_double<double>(e, 6));
  for (int j = 0; j < n; ++j) dq[j] = x[j];
}

}  // namespace spotkin::dense
