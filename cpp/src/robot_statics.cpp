// A legged robot's centre of mass and standing statics (spotkin/dynamics/robot_statics.hpp), compiled
// once: the floating kernels it calls are dispatched per level, and the rest is a few small products
// per sample and the stance forces' decomposition (statics.hpp, Eigen's dense solvers).
#include "spotkin/dynamics/robot_statics.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "spotkin/dense.hpp"
#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/dynamics/statics.hpp"

namespace spotkin::dynamics {

// statics.hpp (W)
void stance_forces(int k, const Eigen::Vector3d* r, const Eigen::Vector3d& F, Eigen::Vector3d* f,
                   double residual[6]) noexcept {
  Eigen::Vector3d mean_r = Eigen::Vector3d::Zero();
  for (int i = 0; i < k; ++i) f[i] = F / double(k), mean_r += r[i] / double(k);
  if (k > 1) {
    const int rows = 3 * (k - 1);
    double At[3 * dense::kMaxThinRows];  // (M N)^T, row-major
    static_assert(3 * (kMaxFeet - 1) <= dense::kMaxThinRows, "dense::thin_svd3 takes the rows");
    for (int j = 1; j < k; ++j) {
      const double h = 1.0 / std::sqrt(double(j) * double(j + 1));
      Eigen::Vector3d sj = -double(j) * h * r[j];
      for (int i = 0; i < j; ++i) sj += h * r[i];
      // [s]x^T = -[s]x: rows 3 (j - 1) .. of (M N)^T
      const double block[9] = {0.0, sj[2], -sj[1], -sj[2], 0.0, sj[0], sj[1], -sj[0], 0.0};
      std::copy(block, block + 9, At + 9 * (j - 1));
    }
    const Eigen::Vector3d moment0 = mean_r.cross(F);  // M f_0
    double U[3 * dense::kMaxThinRows], sigma[3], V[9];
    dense::thin_svd3(At, rows, U, sigma, V);  // (M N)^T = U S V^T, so pinv(M N) = U S^+ V^T
    double w[3];
    for (int a = 0; a < 3; ++a) {
      const double v_m = -(V[a] * moment0[0] + V[3 + a] * moment0[1] + V[6 + a] * moment0[2]);
      w[a] = sigma[a] > 1e-9 * sigma[0] ? v_m / sigma[a] : 0.0;
    }
    double z[3 * dense::kMaxThinRows];
    for (int i = 0; i < rows; ++i)
      z[i] = U[3 * i] * w[0] + U[3 * i + 1] * w[1] + U[3 * i + 2] * w[2];
    for (int j = 1; j < k; ++j) {  // f += N z
      const double h = 1.0 / std::sqrt(double(j) * double(j + 1));
      const Eigen::Vector3d zj(z[3 * (j - 1)], z[3 * (j - 1) + 1], z[3 * (j - 1) + 2]);
      for (int i = 0; i < j; ++i) f[i] += h * zj;
      f[j] -= double(j) * h * zj;
    }
  }
  Eigen::Vector3d force = F, moment = Eigen::Vector3d::Zero();
  for (int i = 0; i < k; ++i) force -= f[i], moment -= r[i].cross(f[i]);
  for (int a = 0; a < 3; ++a) residual[a] = force[a], residual[3 + a] = moment[a];
}

// statics.hpp: one sample
void standing_sample(int legs, const double* com, double mass, const double* feet,
                     const double* foot_jacobians, const double* leg_gravity,
                     const std::uint8_t* stance, const double* gravity, double* tau, double* forces,
                     std::int8_t* status, double* margin, double* residual) noexcept {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  double sum = mass + gravity[0] + gravity[1] + gravity[2];  // NaN or Inf anywhere makes it NaN
  for (int r = 0; r < 3; ++r) sum += com[r];
  for (int j = 0; j < 3 * legs; ++j) sum += feet[j] + leg_gravity[j];
  for (int j = 0; j < 9 * legs; ++j) sum += foot_jacobians[j];
  if (!(sum - sum == 0.0)) {
    for (int j = 0; j < 3 * legs; ++j) tau[j] = nan, forces[j] = nan;
    for (int a = 0; a < 6; ++a) residual[a] = nan;
    *status = static_cast<std::int8_t>(Stance::InvalidInput);
    *margin = nan;
    return;
  }

  const Eigen::Vector3d g(gravity[0], gravity[1], gravity[2]), c(com[0], com[1], com[2]);
  const double weight = mass * g.norm();
  int k = 0, foot_of[kMaxFeet];
  for (int l = 0; l < legs; ++l)
    if (stance[l]) foot_of[k++] = l;
  Eigen::Vector3d r[kMaxFeet], f[kMaxFeet];
  for (int i = 0; i < k; ++i) {
    const double* p = feet + 3 * foot_of[i];
    r[i] = Eigen::Vector3d(p[0] - c[0], p[1] - c[1], p[2] - c[2]);
  }
  // The common case first: three feet or more off one line balance the moment exactly, and the
  // minimum-norm forces are f = A^T (A A^T)^-1 b (A: [I ...; [r_i]x ...], b = [-m g; 0]); else, or
  // when that solve is inaccurate, stance_forces' least squares (the same f when it is exact).
  bool solved = false;
  if (k >= 3) {
    Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 3 * kMaxFeet> A(6, 3 * k);
    for (int i = 0; i < k; ++i) {
      A.block<3, 3>(0, 3 * i).setIdentity();
      A.block<3, 3>(3, 3 * i) << 0.0, -r[i][2], r[i][1], r[i][2], 0.0, -r[i][0], -r[i][1], r[i][0],
          0.0;
    }
    Eigen::Matrix<double, 6, 1> b;
    b << -mass * g, Eigen::Vector3d::Zero();
    // a coefficient-wise product (A has at most 3 kMaxFeet columns): Eigen's general product of a
    // dynamic-width A packs blocks for a cache-blocked kernel, a third of a sample's time here
    const Eigen::Matrix<double, 6, 6> AAt = A.lazyProduct(A.transpose());
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(AAt);
    const auto& D = ldlt.vectorD();
    if (ldlt.info() == Eigen::Success && D.minCoeff() > 1e-10 * D.maxCoeff()) {
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * kMaxFeet, 1> x =
          A.transpose() * ldlt.solve(b);
      const Eigen::Matrix<double, 6, 1> left = b - A * x;
      solved = left.norm() <= 1e-12 * weight;
      if (solved) {
        for (int i = 0; i < k; ++i) f[i] = x.segment<3>(3 * i);
        for (int a = 0; a < 6; ++a) residual[a] = left[a];
      }
    }
  }
  if (!solved) stance_forces(k, r, -mass * g, f, residual);

  // the support margin in the plane normal to gravity
  double m = nan;
  if (g.norm() > 0.0) {
    const Eigen::Vector3d up = -g.normalized();
    Eigen::Vector3d u = up.cross(Eigen::Vector3d::UnitX());
    if (u.norm() < 0.5) u = up.cross(Eigen::Vector3d::UnitY());
    u.normalize();
    const Eigen::Vector3d w = up.cross(u);
    double flat[kMaxFeet][2];
    for (int i = 0; i < k; ++i) {
      const Eigen::Map<const Eigen::Vector3d> p(feet + 3 * foot_of[i]);
      flat[i][0] = p.dot(u), flat[i][1] = p.dot(w);
    }
    const double cc[2] = {c.dot(u), c.dot(w)};
    m = detail_statics::support_margin(flat, k, cc);
  }

  Stance s = Stance::Ok;
  if (Eigen::Map<const Eigen::Matrix<double, 6, 1>>(residual).norm() > 1e-9 * weight) {
    s = Stance::Unbalanced;
  } else if (g.norm() > 0.0) {
    const Eigen::Vector3d up = -g.normalized();
    for (int i = 0; i < k; ++i)
      if (f[i].dot(up) < -1e-9 * weight) s = m > 0.0 ? Stance::Pulling : Stance::Outside;
  }
  for (int j = 0; j < 3 * legs; ++j) tau[j] = leg_gravity[j], forces[j] = 0.0;
  for (int i = 0; i < k; ++i) {
    const int l = foot_of[i];
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(foot_jacobians + 9 * l);
    const Eigen::Vector3d held = J.transpose() * f[i];
    for (int a = 0; a < 3; ++a) tau[3 * l + a] -= held[a], forces[3 * l + a] = f[i][a];
  }
  *status = static_cast<std::int8_t>(s);
  *margin = m;
}

namespace {

// One sub-block's poses and floating coordinates: T (16 per sample, NaN when invalid), qf (nq per
// sample: the body at the origin, then the joints; an invalid sample's joints at zero) and whether
// each sample is valid (a rigid pose, finite joints). Flattened: the pose reading inlined, as it
// was in the binding (measured: 7 % of a batch's centre of mass when it was a call).
template <typename Model, typename T>
__attribute__((flatten)) void load_sub_block(const RobotStaticsModel<Model>& robot,
                                             const EulerSequence& seq, const StaticsRows<T>& rows,
                                             std::ptrdiff_t first, int m, double* Tm, double* qf,
                                             bool* valid) {
  const int nq = robot.floating.nq(), width = 3 * robot.body.n_legs() + (rows.with_arm ? robot.n_arm : 0);
  for (int i = 0; i < m; ++i) {
    const std::ptrdiff_t k = first + i;
    valid[i] = body_batch::pose_transform(rows.pose + rows.pose_stride * k, rows.format, seq, Tm + 16 * i);
    const T* q = rows.q + rows.q_stride * k;
    double* row = qf + nq * i;
    std::fill(row, row + nq, 0.0);
    row[6] = 1.0;  // the identity quaternion [0, 0, 0, 1]
    bool finite = true;
    for (int j = 0; j < width; ++j) finite &= std::isfinite(double(q[j]));
    valid[i] = valid[i] && finite;
    if (finite)
      for (int j = 0; j < width; ++j) row[7 + j] = double(q[j]);
  }
}

}  // namespace

template <typename Model, typename T>
void robot_com(const RobotStaticsModel<Model>& robot, const EulerSequence& seq, const StaticsRows<T>& rows, T* com_out,
               std::ptrdiff_t count) {
  double Tm[16 * kStaticsSubBlock], qf[kStaticsMaxQ * kStaticsSubBlock], com[3 * kStaticsSubBlock];
  bool valid[kStaticsSubBlock];
  for (std::ptrdiff_t first = 0; first < count; first += kStaticsSubBlock) {
    const int m = int(std::min<std::ptrdiff_t>(kStaticsSubBlock, count - first));
    load_sub_block(robot, seq, rows, first, m, Tm, qf, valid);
    floating_com_k(robot.floating, Rows<double>{qf, robot.floating.nq()}, com, false, 0, m, false);
    for (int i = 0; i < m; ++i) {
      T* out = com_out + 3 * (first + i);
      const double* M = Tm + 16 * i;
      for (int r = 0; r < 3; ++r) {
        const double v = M[4 * r + 3] + M[4 * r] * com[3 * i] + M[4 * r + 1] * com[3 * i + 1] + M[4 * r + 2] * com[3 * i + 2];
        out[r] = valid[i] ? T(v) : T(quiet_nan<double>());
      }
    }
  }
}

template <typename Model, typename T>
void robot_standing(const RobotStaticsModel<Model>& robot, const EulerSequence& seq,
                    const double gravity[3], const StaticsRows<T>& rows, T* tau_rows, T* force_rows,
                    std::int8_t* status_rows, T* margin_rows, T* residual_rows,
                    std::ptrdiff_t count) {
  const Body& body = robot.body;
  const int L = body.n_legs(), nq = robot.floating.nq(), nv = robot.floating.nv();
  constexpr double nan = quiet_nan<double>();
  double Tm[16 * kStaticsSubBlock], qf[kStaticsMaxQ * kStaticsSubBlock], com[3 * kStaticsSubBlock];
  double g_body[3 * kStaticsSubBlock], gravity_torques[kStaticsMaxQ * kStaticsSubBlock];
  bool valid[kStaticsSubBlock];
  for (std::ptrdiff_t first = 0; first < count; first += kStaticsSubBlock) {
    const int m = int(std::min<std::ptrdiff_t>(kStaticsSubBlock, count - first));
    load_sub_block(robot, seq, rows, first, m, Tm, qf, valid);
    for (int i = 0; i < m; ++i) {  // g_body = R^T g
      const double* M = Tm + 16 * i;
      for (int r = 0; r < 3; ++r)
        g_body[3 * i + r] = valid[i] ? M[r] * gravity[0] + M[4 + r] * gravity[1] + M[8 + r] * gravity[2] : 0.0;
    }
    floating_rnea_k(robot.floating, Rows<double>{qf, nq}, nullptr, nullptr, Rows<double>{g_body, 3}, gravity_torques, 0,
                    m, false);
    for (int i = 0; i < m; ++i) {
      // The centre of mass across gravity from G(q)'s body wrench [f; n] (body frame, at rest):
      // f = -m g, n = c x f, so c_perp = f x n / |f|^2 = c - f (f . c) / |f|^2. The balance and the
      // margin need no more: c's part along g moves the moment of sum f_i = -m g by nothing.
      const double* w = gravity_torques + nv * i;
      const double ff = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
      const double inv = ff > 0.0 ? 1.0 / ff : 0.0;  // no weight: no force, any centre
      com[3 * i] = (w[1] * w[5] - w[2] * w[4]) * inv;
      com[3 * i + 1] = (w[2] * w[3] - w[0] * w[5]) * inv;
      com[3 * i + 2] = (w[0] * w[4] - w[1] * w[3]) * inv;
    }
    for (int i = 0; i < m; ++i) {
      const std::ptrdiff_t k = first + i;
      T* tau_out = tau_rows + 3 * L * k;
      T* force_out = force_rows + 3 * L * k;
      std::int8_t* status = status_rows + k;
      std::uint8_t on[kMaxFeet];
      bool ok = valid[i];
      for (int l = 0; l < L; ++l) {
        const double v = rows.stance ? double(rows.stance[rows.stance_stride * k + l]) : 1.0;
        on[l] = v != 0.0;
        ok = ok && (v == 0.0 || v == 1.0);  // a NaN in the mask: invalid, as any non-finite input
      }
      if (!ok) {
        std::fill(tau_out, tau_out + 3 * L, T(nan));
        std::fill(force_out, force_out + 3 * L, T(nan));
        std::fill(residual_rows + 6 * k, residual_rows + 6 * k + 6, T(nan));
        *status = static_cast<std::int8_t>(Stance::InvalidInput);
        margin_rows[k] = T(nan);
        continue;
      }
      double feet[3 * kMaxFeet], jacobians[9 * kMaxFeet], leg_gravity[3 * kMaxFeet];
      const double* joints = qf + nq * i + 7;
      for (int l = 0; l < L; ++l) {  // the feet in the body frame: hip + leg FK, and d foot / d q_l
        const auto& col = body.columns[std::size_t(l)];
        const double q_leg[3] = {joints[col[0]], joints[col[1]], joints[col[2]]};
        body.legs[std::size_t(l)].forward(q_leg, feet + 3 * l);
        body.legs[std::size_t(l)].jacobian(q_leg, jacobians + 9 * l);
        for (int r = 0; r < 3; ++r) {
          feet[3 * l + r] += body.hips[std::size_t(l)][std::size_t(r)];
          leg_gravity[3 * l + r] = gravity_torques[nv * i + 6 + col[std::size_t(r)]];
        }
      }
      double tau[3 * kMaxFeet], forces[3 * kMaxFeet], margin, residual[6];
      standing_sample(L, com + 3 * i, robot.mass, feet, jacobians, leg_gravity, on, g_body + 3 * i,
                      tau, forces, status, &margin, residual);
      const double* M = Tm + 16 * i;
      for (int h = 0; h < 2; ++h)  // the residual force and moment, turned to the world: R v
        for (int r = 0; r < 3; ++r) {
          const double* v = residual + 3 * h;
          residual_rows[6 * k + 3 * h + r] =
              T(M[4 * r] * v[0] + M[4 * r + 1] * v[1] + M[4 * r + 2] * v[2]);
        }
      for (int l = 0; l < L; ++l) {
        const auto& col = body.columns[std::size_t(l)];
        const double* f = forces + 3 * l;
        for (int r = 0; r < 3; ++r) {
          tau_out[col[std::size_t(r)]] = T(tau[3 * l + r]);
          force_out[3 * l + r] = T(M[4 * r] * f[0] + M[4 * r + 1] * f[1] + M[4 * r + 2] * f[2]);  // R f
        }
      }
      margin_rows[k] = T(margin);
    }
  }
}

#define SPOTKIN_INSTANTIATE(T, L)                                                              \
  template void robot_com<FloatingModel<double, L>, T>(                                        \
      const RobotStaticsModel<FloatingModel<double, L>>&, const EulerSequence&,                \
      const StaticsRows<T>&, T*, std::ptrdiff_t);                                              \
  template void robot_standing<FloatingModel<double, L>, T>(                                   \
      const RobotStaticsModel<FloatingModel<double, L>>&, const EulerSequence&, const double*, \
      const StaticsRows<T>&, T*, T*, std::int8_t*, T*, T*, std::ptrdiff_t);
#define SPOTKIN_INSTANTIATE_WIDTH(L) SPOTKIN_INSTANTIATE(float, L) SPOTKIN_INSTANTIATE(double, L)
SPOTKIN_INSTANTIATE_WIDTH(kLanes64)
SPOTKIN_INSTANTIATE_WIDTH(kMidLanes64)
SPOTKIN_INSTANTIATE_WIDTH(kSmallLanes64)
#undef SPOTKIN_INSTANTIATE_WIDTH
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::dynamics
