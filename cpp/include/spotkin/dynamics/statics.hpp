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
//
// stance_forces and standing_sample are compiled once, in cpp/src/robot_statics.cpp: their Eigen
// decompositions (JacobiSVD, LDLT) took about 10 s of compiler CPU in each unit that included
// this header, whether it called them or not.
#pragma once

#include <Eigen/Core>
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
void stance_forces(int k, const Eigen::Vector3d* r, const Eigen::Vector3d& F, Eigen::Vector3d* f,
                   double residual[6]) noexcept;

// One sample. legs <= kMaxFeet; feet (legs, 3) foot points; foot_jacobians (legs, 3, 3) row-major
// d p_l / d q_l (the same axes); leg_gravity (3 legs) the legs' joint gravity torques; stance
// (legs) 0/1; gravity (3). Writes tau (3 legs), forces (legs, 3) (zero on swing feet), the status,
// the support margin (m; NaN without gravity) and the residual wrench (6, stance_forces). Balanced
// (the residual under 1e-9 of the weight): OK, PULLING or OUTSIDE; else UNBALANCED, with the
// least-squares forces and their torques (finite) and the wrench they leave.
void standing_sample(int legs, const double* com, double mass, const double* feet,
                     const double* foot_jacobians, const double* leg_gravity,
                     const std::uint8_t* stance, const double* gravity, double* tau, double* forces,
                     std::int8_t* status, double* margin, double* residual) noexcept;

}  // namespace spotkin::dynamics
