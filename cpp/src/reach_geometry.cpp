// The plain geometry of the reach search (spotkin/motion/reach_geometry.hpp): poses, small linear
// solves, the capsules' distances and rotation vectors, as
// python/spotkin/reference/reach_geometry.py computes them.
#include "spotkin/motion/reach_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace spotkin::motion::geometry {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

// "XYZ" Euler angles of R = Rx(a) Ry(b) Rz(c) (ref.xyz_euler), and the pose [t, a, b, c] of T.
void pose_of(const double* T, double* pose) noexcept {
  pose[0] = T[3], pose[1] = T[7], pose[2] = T[11];
  pose[4] = std::asin(std::max(-1.0, std::min(1.0, T[2])));
  pose[3] = std::atan2(-T[6], T[10]);
  pose[5] = std::atan2(-T[1], T[0]);
}

// ref.segment_distance: the segments a-b and c-d (Ericson 5.1.9).
double segment_distance(const double* a, const double* b, const double* c,
                        const double* d) noexcept {
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k) u[k] = b[k] - a[k], v[k] = d[k] - c[k], w[k] = a[k] - c[k];
  const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2],
               vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const double uv = u[0] * v[0] + u[1] * v[1] + u[2] * v[2],
               uw = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
  const double vw = v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
  const auto clip = [](double x) { return std::min(std::max(x, 0.0), 1.0); };
  double s = 0.0, t = 0.0;
  if (uu <= 1e-30 && vv <= 1e-30) {
  } else if (uu <= 1e-30) {
    t = clip(vw / vv);
  } else if (vv <= 1e-30) {
    s = clip(-uw / uu);
  } else {
    const double den = uu * vv - uv * uv;
    s = den > 1e-30 ? clip((uv * vw - vv * uw) / den) : 0.0;
    t = (uv * s + vw) / vv;
    if (t < 0.0) {
      s = clip(-uw / uu), t = 0.0;
    } else if (t > 1.0) {
      s = clip((uv - uw) / uu), t = 1.0;
    }
  }
  double g2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double g = w[k] + s * u[k] - t * v[k];
    g2 += g * g;
  }
  return std::sqrt(g2);
}

// ref.segment_box_distance: the ends, the face-plane crossings and each piece's own minimum.
double segment_box_distance(const double* a_in, const double* b_in, const double* centre,
                            const double* half) noexcept {
  double a[3], u[3];
  for (int k = 0; k < 3; ++k) a[k] = a_in[k] - centre[k], u[k] = b_in[k] - centre[k] - a[k];
  const auto at = [&](double t) {
    double g2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double g = std::max(std::abs(a[k] + t * u[k]) - half[k], 0.0);
      g2 += g * g;
    }
    return std::sqrt(g2);
  };
  double cuts[8] = {0.0, 1.0};
  int n = 2;
  for (int k = 0; k < 3; ++k) {
    if (u[k] == 0.0) continue;
    for (const double t : {(half[k] - a[k]) / u[k], (-half[k] - a[k]) / u[k]})
      if (0.0 < t && t < 1.0) cuts[n++] = t;
  }
  for (int i = 1; i < n; ++i)  // insertion sort (at most 8)
    for (int j = i; j > 0 && cuts[j] < cuts[j - 1]; --j) std::swap(cuts[j], cuts[j - 1]);
  double best = kInf;
  for (int k = 0; k < n; ++k) best = std::min(best, at(cuts[k]));
  for (int k = 0; k + 1 < n; ++k) {
    const double lo = cuts[k], hi = cuts[k + 1];
    double num = 0.0, den = 0.0;
    for (int j = 0; j < 3; ++j) {
      const double mid = a[j] + 0.5 * (lo + hi) * u[j];
      const double side = std::abs(mid) > half[j] ? (mid > 0.0 ? 1.0 : -1.0) : 0.0;
      den += side * side * u[j] * u[j];
      num += side * u[j] * (side * a[j] - half[j] * side * side);
    }
    if (den > 0.0) best = std::min(best, at(std::min(std::max(-num / den, lo), hi)));
  }
  return best;
}

// ref.rotation_log: the rotation vector of R (3 x 3, row-major).
void rotation_log(const double* R, double* out) noexcept {
  const double w[3] = {R[7] - R[5], R[2] - R[6], R[3] - R[1]};
  const double s = 0.5 * std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  const double c = 0.5 * (R[0] + R[4] + R[8] - 1.0);
  const double angle = std::atan2(s, c);
  if (s < 1e-9) {
    if (c > 0.0) {
      for (int k = 0; k < 3; ++k) out[k] = 0.5 * w[k];
      return;
    }
    int k = 0;
    for (int j = 1; j < 3; ++j)
      if (R[4 * j] > R[4 * k]) k = j;
    double n[3];
    const double scale = std::sqrt(std::max(2.0 * (1.0 + R[4 * k]), 1e-300));
    for (int j = 0; j < 3; ++j) n[j] = (R[3 * j + k] + (j == k ? 1.0 : 0.0)) / scale;
    const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int j = 0; j < 3; ++j) out[j] = angle * n[j] / norm;
    return;
  }
  for (int k = 0; k < 3; ++k) out[k] = angle * w[k] / (2.0 * s);
}

}  // namespace spotkin::motion::geometry
