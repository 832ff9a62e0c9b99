// Revolute chains in product-of-exponentials form, the 6R families that have a
// closed form, the idealised chain of a calibrated (nearly special) one, and
// the Newton polish on the true chain. Derivations: docs/derivations.md#6r-families
// and python/spotkin/reference/ik6r.py, which the tests compare against.
//
//   (K1)  T(q) = E_1(q_1) ... E_n(q_n) M,   E_i(q): x -> p_i + Rot(h_i, q) (x - p_i),
// with unit axes h_i and points p_i on them in the base frame at q = 0, and M = T(0).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "spotkin/chain_ik/common.hpp"
#include "spotkin/differential.hpp"

namespace spotkin::chain_ik {

struct Poe {
  static constexpr int kMaxJoints = 7;
  int n = 0;
  std::array<V3, kMaxJoints> h = zeros(), p = zeros();
  static std::array<V3, kMaxJoints> zeros() {
    std::array<V3, kMaxJoints> out;
    out.fill(V3::Zero());
    return out;
  }
  Rigid<double> M;
};

// Rot(h, q) x for (cos q, sin q) = (c, s), h unit (Rodrigues).
SPOTKIN_INLINE V3 rotate(const V3& h, double c, double s, const V3& x) noexcept {
  const double along = h.dot(x);
  return along * h + c * (x - along * h) + s * h.cross(x);
}

inline Rigid<double> inverse_rigid(const Rigid<double>& T) { return {T.R.transpose(), -(T.R.transpose() * T.p)}; }

// The POE form of a revolute chain, from its geometric Jacobian at q = 0: column j is
// [h x (p_tool - o); h], so h x o = h x p_tool - v and (h x o) x h is the point of
// axis j nearest the origin.
inline Poe poe_of(const Chain<double>& chain) {
  const int n = chain.dof();
  if (n > Poe::kMaxJoints) throw std::invalid_argument("at most 7 joints in a POE chain");
  std::vector<double> q(static_cast<std::size_t>(n), 0.0), J(static_cast<std::size_t>(6 * n));
  chain.jacobian(q.data(), J.data(), 6, false);
  Poe poe;
  poe.n = n;
  poe.M = chain.forward(q.data());
  for (int j = 0; j < n; ++j) {
    const V3 v(J[j], J[n + j], J[2 * n + j]);
    V3 h(J[3 * n + j], J[4 * n + j], J[5 * n + j]);
    h.normalize();
    poe.h[j] = h;
    poe.p[j] = (h.cross(poe.M.p) - v).cross(h);
  }
  return poe;
}

// A Chain with the same FK as poe: joint j placed at p_j (axes in base-frame
// directions), T(q) = Trans(p_1) Rot(h_1, q_1) Trans(p_2 - p_1) ... Rot(h_n, q_n) Trans(-p_n) M.
inline Chain<double> chain_of(const Poe& poe) {
  std::vector<Rigid<double>> placements(static_cast<std::size_t>(poe.n));
  std::vector<Vec3<double>> axes(static_cast<std::size_t>(poe.n));
  std::vector<JointType> types(static_cast<std::size_t>(poe.n), JointType::Revolute);
  for (int j = 0; j < poe.n; ++j) {
    placements[std::size_t(j)].p = poe.p[j] - (j > 0 ? poe.p[j - 1] : V3::Zero());
    axes[std::size_t(j)] = poe.h[j];
  }
  Rigid<double> tool = poe.M;
  tool.p -= poe.p[poe.n - 1];
  return Chain<double>::from_joints(placements, axes, types, Rigid<double>{}, tool);
}

// The chain of G^-1 = E_n(-q_n) ... E_1(-q_1) with G = T M^-1: axes and points in
// reverse, M = I. Its joint i is joint n - 1 - i of poe, with the value negated.
inline Poe reversed(const Poe& poe) {
  Poe out;
  out.n = poe.n;
  for (int j = 0; j < poe.n; ++j) out.h[j] = poe.h[poe.n - 1 - j], out.p[j] = poe.p[poe.n - 1 - j];
  return out;
}

// The (n - 1)-joint chain with joint k held at v: E_k(v) moved to the right through
// the later joints turns their axes and points by E_k(v) and ends in the tool.
inline Poe fix_joint(const Poe& poe, int k, double value) {
  const double c = std::cos(value), s = std::sin(value);
  Poe out;
  out.n = poe.n - 1;
  for (int j = 0, o = 0; j < poe.n; ++j) {
    if (j == k) continue;
    out.h[o] = j < k ? poe.h[j] : rotate(poe.h[k], c, s, poe.h[j]);
    out.p[o] = j < k ? poe.p[j] : V3(poe.p[k] + rotate(poe.h[k], c, s, poe.p[j] - poe.p[k]));
    ++o;
  }
  Rigid<double> E;
  for (int col = 0; col < 3; ++col) E.R.col(col) = rotate(poe.h[k], c, s, V3::Unit(col));
  E.p = poe.p[k] - E.R * poe.p[k];
  out.M = E * poe.M;
  return out;
}

// ---- the families -------------------------------------------------------------------------------

enum class Family6 : std::int8_t { SphericalWrist, Parallel234, Parallel123, SphericalShoulder };

inline const char* family_name(Family6 f) {
  switch (f) {
    case Family6::SphericalWrist: return "6R-spherical-wrist";
    case Family6::Parallel234: return "6R-three-parallel-234";
    case Family6::Parallel123: return "6R-three-parallel-123";
    case Family6::SphericalShoulder: return "6R-spherical-shoulder";
  }
  return "?";
}

// Largest sine of the angle between axis first and axes first + 1, first + 2.
inline double parallel_error(const Poe& poe, int first) {
  double worst = 0.0;
  for (int j = first + 1; j < first + 3; ++j) worst = std::max(worst, poe.h[first].cross(poe.h[j]).norm());
  return worst;
}

// The point nearest (least squares) to axes first..first + 2 and the largest distance
// from it to one of them; infinite distance when the axes are parallel (no point).
inline double meeting_error(const Poe& poe, int first, V3& point) {
  M3 A = M3::Zero();
  V3 b = V3::Zero();
  for (int j = first; j < first + 3; ++j) {
    const M3 P = M3::Identity() - poe.h[j] * poe.h[j].transpose();
    A += P, b += P * poe.p[j];
  }
  V3 sigma;
  const V3 solution = dense::svd_solve3(A, b, &sigma);
  if (sigma[2] <= 1e-12 * sigma[0]) {
    point = V3::Constant(std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::infinity();
  }
  point = solution;
  double worst = 0.0;
  for (int j = first; j < first + 3; ++j)
    worst = std::max(worst, ((M3::Identity() - poe.h[j] * poe.h[j].transpose()) * (point - poe.p[j])).norm());
  return worst;
}

// The distance between axes i and j, and the translation of axis j (normal to both) that makes
// it meet axis i; 0 for parallel axes (they meet at infinity).
inline double axis_gap(const Poe& poe, int i, int j, V3& shift) {
  const V3 normal = poe.h[i].cross(poe.h[j]);
  const double sine = normal.norm();
  if (sine <= 1e-12) {
    shift = V3::Zero();
    return 0.0;
  }
  const V3 n = normal / sine;
  const double distance = (poe.p[j] - poe.p[i]).dot(n);
  shift = -distance * n;
  return std::fabs(distance);
}

// What the classification measured: the deviations from each family, and for the parallel
// families whether the pair of axes that makes their subproblem 6 rank 1 meets (axes 5 and 6
// for 2-3-4, 4 and 5 for 1-2-3; UR arms and the Z1 have both).
struct Geometry6 {
  double wrist = 0.0, shoulder = 0.0, parallel234 = 0.0, parallel123 = 0.0;  // m, m, sin, sin
  double gap56 = 0.0, gap45 = 0.0;                                          // m
  V3 wrist_point = V3::Zero(), shoulder_point = V3::Zero(), shift6 = V3::Zero(), shift5 = V3::Zero();

  Geometry6() = default;
  // (in the body: the points are written by the calls, after every member exists)
  explicit Geometry6(const Poe& poe) {
    wrist = meeting_error(poe, 3, wrist_point);
    shoulder = meeting_error(poe, 0, shoulder_point);
    parallel234 = parallel_error(poe, 1);
    parallel123 = parallel_error(poe, 0);
    gap56 = axis_gap(poe, 4, 5, shift6);
    gap45 = axis_gap(poe, 3, 4, shift5);
  }

  double deviation(Family6 f) const {
    switch (f) {
      case Family6::SphericalWrist: return wrist;
      case Family6::Parallel234: return parallel234;
      case Family6::Parallel123: return parallel123;
      case Family6::SphericalShoulder: return shoulder;
    }
    return shoulder;
  }
};

// The chain made exactly of its family: parallel axes set to their mean direction
// (signs kept), meeting axes moved to pass through their nearest common point. For the
// parallel families, axes 5 and 6 (2-3-4) or 4 and 5 (1-2-3) that pass within meet_distance
// (but not within 1e-12) are made to meet, by moving axis 6 (or 5) normal to both.
inline Poe idealise(const Poe& poe, Family6 family, const Geometry6& geometry, double meet_distance) {
  Poe out = poe;
  if (family == Family6::Parallel234 && geometry.gap56 > 1e-12 && geometry.gap56 <= meet_distance)
    out.p[5] += geometry.shift6;
  if (family == Family6::Parallel123 && geometry.gap45 > 1e-12 && geometry.gap45 <= meet_distance)
    out.p[4] += geometry.shift5;
  if (family == Family6::Parallel234 || family == Family6::Parallel123) {
    const int first = family == Family6::Parallel234 ? 1 : 0;
    V3 mean = V3::Zero();
    for (int j = first; j < first + 3; ++j) mean += (poe.h[j].dot(poe.h[first]) >= 0.0 ? 1.0 : -1.0) * poe.h[j];
    mean.normalize();
    for (int j = first; j < first + 3; ++j) out.h[j] = (poe.h[j].dot(poe.h[first]) >= 0.0 ? 1.0 : -1.0) * mean;
  } else {
    const int first = family == Family6::SphericalWrist ? 3 : 0;
    const V3 c = family == Family6::SphericalWrist ? geometry.wrist_point : geometry.shoulder_point;
    for (int j = first; j < first + 3; ++j) out.p[j] = c;
  }
  return out;
}

// ---- the polish on the true chain ---------------------------------------------------------------

// max(|p_target - p| (m), |log(R_target R^T)| (rad)) at q.
inline double pose_residual(const Chain<double>& chain, const double* q, const Rigid<double>& target) {
  double e[6];
  differential::pose_error(target, chain.forward(q), e);
  return std::max(std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]), std::sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]));
}

// Gauss-Newton steps q <- q + J^+ e on the true chain (at most 20; stops below 1e-14 or
// when neither the step nor its halves, down to 1/16, lower the residual); returns the final
// residual. J^+ drops singular directions below 1e-9 of the largest (near a singularity a
// full pseudo-inverse step would be huge along a direction that barely moves the pose).
inline double newton_polish(const Chain<double>& chain, double* q, const Rigid<double>& target) {
  const int n = chain.dof();
  using Mat = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor, 6, Poe::kMaxJoints>;
  Mat J(6, n);
  double residual = pose_residual(chain, q, target);
  for (int it = 0; it < 20 && residual > 1e-14; ++it) {
    double e[6], trial[Poe::kMaxJoints];
    differential::pose_error(target, chain.forward(q), e);
    chain.jacobian(q, J.data(), 6, false);
    static_assert(Poe::kMaxJoints <= 7, "dense::cod_solve6 takes at most 7 columns");
    double dq[Poe::kMaxJoints];
    dense::cod_solve6(J.data(), n, e, 1e-9, dq);
    bool improved = false;
    for (double step = 1.0; step >= 1.0 / 16.0 && !improved; step *= 0.5) {
      for (int j = 0; j < n; ++j) trial[j] = q[j] + step * dq[j];
      const double next = pose_residual(chain, trial, target);
      if (next < residual) {
        residual = next, improved = true;
        for (int j = 0; j < n; ++j) q[j] = trial[j];
      }
    }
    if (!improved) break;
  }
  return residual;
}

}  // namespace spotkin::chain_ik
