// Standing statics of a floating legged robot: the minimum-norm contact forces at the
// stance feet that balance its weight, and the joint torques that hold the legs there.
//
// Point contacts at the stance feet p_i carry world forces f_i (ground on foot). Static
// balance of the whole robot (total mass m, centre of mass c, gravity g):
//   sum f_i = -m g,   sum (p_i - c) x f_i = 0   (6 equations, 3k unknowns),
// f the minimum-norm solution; where the moment cannot be balanced (fewer than three feet, or
// collinear ones), the weight is still carried and the moment balanced in least squares
// (stance_forces), and the residual wrench says what is left. A leg's joints
// then hold tau_l = G_l - J_l^T f_l (the static model tau = J^T F of the course, with the
// gravity torques G of the leg's own links; J_l = d p_l / d q_l in world axes; a swing leg
// holds G_l alone). docs/dynamics.md gives the status rule and the support margin.
#pragma once

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "spotkin/dynamics/stance.hpp"

namespace spotkin::dynamics {

namespace detail_statics {

// Signed distance of c to the convex hull of pts (2-D): the smallest signed distance to
// the hull's edge lines, positive inside, with three or more non-collinear points;
// otherwise minus the distance to their segment or point.
inline double support_margin(const double (*pts)[2], int k, const double c[2]) {
  if (k == 0) return -std::numeric_limits<double>::infinity();
  int order[kMaxFeet];
  for (int i = 0; i < k; ++i) order[i] = i;
  std::sort(order, order + k, [&](int a, int b) {
    return pts[a][0] < pts[b][0] || (pts[a][0] == pts[b][0] && pts[a][1] < pts[b][1]);
  });
  auto cross = [&](int o, int a, int b) {
    return (pts[a][0] - pts[o][0]) * (pts[b][1] - pts[o][1]) - (pts[a][1] - pts[o][1]) * (pts[b][0] - pts[o][0]);
  };
  // Andrew's monotone chain, counter-clockwise; duplicates drop out (cross <= 0)
  int hull[2 * kMaxFeet], h = 0;
  for (int s = 0; s < k; ++s) {
    const int p = order[s];
    while (h >= 2 && cross(hull[h - 2], hull[h - 1], p) <= 0) --h;
    hull[h++] = p;
  }
  for (int s = k - 2, lower = h + 1; s >= 0; --s) {
    const int p = order[s];
    while (h >= lower && cross(hull[h - 2], hull[h - 1], p) <= 0) --h;
    hull[h++] = p;
  }
  if (k > 1) --h;  // the last point repeats the first
  double scale = 1.0, area = 0.0;
  for (int i = 0; i < k; ++i) scale = std::max({scale, std::fabs(pts[i][0]), std::fabs(pts[i][1])});
  for (int i = 0; i < h; ++i) {
    const double* a = pts[hull[i]];
    const double* b = pts[hull[(i + 1) % h]];
    area += a[0] * b[1] - b[0] * a[1];
  }
  if (h >= 3 && area > 1e-12 * scale * scale) {
    double margin = std::numeric_limits<double>::infinity();
    for (int i = 0; i < h; ++i) {
      const double* a = pts[hull[i]];
      const double* b = pts[hull[(i + 1) % h]];
      const double ex = b[0] - a[0], ey = b[1] - a[1], len = std::hypot(ex, ey);
      margin = std::min(margin, ((c[0] - a[0]) * -ey + (c[1] - a[1]) * ex) / len);  // left of a CCW edge
    }
    return margin;
  }
  // collinear (or one point): the extreme points of the sorted order
  const double* a = pts[order[0]];
  const double* b = pts[order[k - 1]];
  const double dx = b[0] - a[0], dy = b[1] - a[1], d2 = dx * dx + dy * dy;
  const double t = d2 > 0.0 ? std::clamp(((c[0] - a[0]) * dx + (c[1] - a[1]) * dy) / d2, 0.0, 1.0) : 0.0;
  return -std::hypot(c[0] - (a[0] + t * dx), c[1] - (a[1] + t * dy));
}

}  // namespace detail_statics

// (W) The stance forces: the weight carried exactly, the moment about the centre of mass in the
// least-squares sense, at the minimum norm. With F = -m g, r_i = p_i - c and f_0 = F / k on each of
// the k stance feet, every f with sum f_i = F is f = f_0 + N z, N an orthonormal basis of
// {sum z_i = 0} (Helmert's: column j < k has 1 / sqrt(j (j + 1)) on feet i < j and -j / sqrt(j (j +
// 1)) on foot j, per axis). The moment is M f = sum r_i x f_i, so z = pinv(M N) (-M f_0), dropping
// the singular values below 1e-9 of the largest: among the forces of least moment error, the
// smallest
// (|f|^2 = |f_0|^2 + |z|^2). M N = [[s_1]x ... [s_{k-1}]x] with s_j = sum_i N_ij r_i. When the
// moment can be balanced (three feet or more off one line) this is the minimum-norm exact balance.
// residual (6): [F - sum f_i; -sum r_i x f_i], the wrench the feet leave unbalanced.
inline void stance_forces(int k, const Eigen::Vector3d* r, const Eigen::Vector3d& F,
                          Eigen::Vector3d* f, double residual[6]) noexcept {
  Eigen::Vector3d mean_r = Eigen::Vector3d::Zero();
  for (int i = 0; i < k; ++i) f[i] = F / double(k), mean_r += r[i] / double(k);
  if (k > 1) {
    // Dynamic columns (at most 3): Eigen gives thin unitaries only for those
    using Tall = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3 * (kMaxFeet - 1), 3>;
    Tall At(3 * (k - 1), 3);  // (M N)^T
    for (int j = 1; j < k; ++j) {
      const double h = 1.0 / std::sqrt(double(j) * double(j + 1));
      Eigen::Vector3d sj = -double(j) * h * r[j];
      for (int i = 0; i < j; ++i) sj += h * r[i];
      // [s]x^T = -[s]x: rows 3 (j - 1) .. of (M N)^T
      At.block<3, 3>(3 * (j - 1), 0) << 0.0, sj[2], -sj[1], -sj[2], 0.0, sj[0], sj[1], -sj[0], 0.0;
    }
    const Eigen::Vector3d moment0 = mean_r.cross(F);  // M f_0
    const Eigen::JacobiSVD<Tall> svd(At, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto& sigma = svd.singularValues();  // (M N)^T = U S V^T, so pinv(M N) = U S^+ V^T
    Eigen::Vector3d w = svd.matrixV().transpose() * -moment0;
    for (int a = 0; a < 3; ++a) w[a] = sigma[a] > 1e-9 * sigma[0] ? w[a] / sigma[a] : 0.0;
    const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * (kMaxFeet - 1), 1> z = svd.matrixU() * w;
    for (int j = 1; j < k; ++j) {  // f += N z
      const double h = 1.0 / std::sqrt(double(j) * double(j + 1));
      const Eigen::Vector3d zj = z.segment<3>(3 * (j - 1));
      for (int i = 0; i < j; ++i) f[i] += h * zj;
      f[j] -= double(j) * h * zj;
    }
  }
  Eigen::Vector3d force = F, moment = Eigen::Vector3d::Zero();
  for (int i = 0; i < k; ++i) force -= f[i], moment -= r[i].cross(f[i]);
  for (int a = 0; a < 3; ++a) residual[a] = force[a], residual[3 + a] = moment[a];
}

// One sample. legs <= kMaxFeet; feet (legs, 3) foot points; foot_jacobians (legs, 3, 3) row-major
// d p_l / d q_l (the same axes); leg_gravity (3 legs) the legs' joint gravity torques; stance
// (legs) 0/1; gravity (3). Writes tau (3 legs), forces (legs, 3) (zero on swing feet), the status,
// the support margin (m; NaN without gravity) and the residual wrench (6, stance_forces). Balanced
// (the residual under 1e-9 of the weight): OK, PULLING or OUTSIDE; else UNBALANCED, with the
// least-squares forces and their torques (finite) and the wrench they leave.
inline void standing_sample(int legs, const double* com, double mass, const double* feet,
                            const double* foot_jacobians, const double* leg_gravity,
                            const std::uint8_t* stance, const double* gravity, double* tau,
                            double* forces, std::int8_t* status, double* margin,
                            double* residual) noexcept {
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

}  // namespace spotkin::dynamics
