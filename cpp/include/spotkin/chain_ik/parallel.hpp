// Closed-form IK of 6R chains with three consecutive parallel axes: 2, 3 and 4
// (UR3/5/10, Unitree Z1; Parallel234) or 1, 2 and 3 (Parallel123), in the POE form
// of poe.hpp; ported from python/spotkin/reference/ik6r.py (_solve_234, _solve_123),
// equation labels as there. Both reduce to SP6 (class Sp6).
//
// Parallel234:
//
// R_2 R_3 R_4 = Rot(h2, theta234) keeps h2^T x, so with G = T M^-1 = (R, t):
//   (P1)  h2^T R_1^T R h6 = h2^T R_5 h6
//   (P2)  h2^T R_1^T (t - R p6T - p01) - h2^T (p12 + p23 + p34 + p45) = h2^T R_5 p56
// two equations in q1 and q5 alone: A1 x1 + A2 x5 = e with x = (cos, sin) (SP6).
// A2 depends on the chain only. When it has rank 1 (p56 along h6, as on UR arms)
// its left null vector n gives n^T A1 x1 = n^T e (two q1), then its range m gives
// m^T A2 x5 = m^T (e - A1 x1) (two q5 per q1); with rank 2, |A2^-1 (e - A1 x1)| = 1
// is a quartic in tan(q1 / 2). Then per (q1, q5): q6 by SP1 from
// Rot(h6, q6) R^T R_1 h2 = R_5^T h2, theta234 from Rot(h2, theta234) = R_1^T R R_6^T R_5^T,
//   w = R_1^T (t - R p6T - p01) - p12 - Rot(h2, theta234) (p45 + R_5 p56) = R_2 (p23 + R_3 p34),
// q3 by SP3 (|p23 + R_3 p34| = |w|, the elbow), q2 by SP1 and q4 = s4 (theta234 - q2 - s3 q3),
// s_j = sign(h_j . h2).
// Slots 2 k + b: k numbers the (q1, q5) pairs (rank 1: k = 2 i1 + i5 with i1 the
// root of q1, "+" then "-", and i5 that of q5; rank 2: increasing q1), b the elbow root.
#pragma once

#include <Eigen/LU>

#include "spotkin/chain_ik/poe.hpp"

namespace spotkin::chain_ik {

namespace detail6 {

inline constexpr double kTangent = 1e-9;  // |C / hypot(A, B)| up to 1 + kTangent: a (double) root

  // h^T Rot(k, q) p = c + a cos q + b sin q
inline void trig(const V3& h, const V3& k, const V3& p, double& c, double& a, double& b) {
  const double along = k.dot(p);
  c = h.dot(k) * along, a = h.dot(p - k * along), b = h.dot(k.cross(p));
}

  // One root of a cos x + b sin x = rhs: angle(a, b) + sign acos(rhs / hypot(a, b)) (SP4);
// false if |rhs| / hypot > 1 + kTangent.
// clamp: take the nearest extreme when there is no root (returns true).
// mirror: |ratio| in (1 + kTangent, 1 + mirror] starts from 2 sign(ratio) - ratio (near_double).
SPOTKIN_INLINE bool root(double a, double b, double rhs, double sign, JointValue& x,
                                bool clamp = false, bool* near_double = nullptr, double mirror = 0.0) noexcept {
  const double r2 = a * a + b * b;
  if (!(r2 > 0.0)) return false;
  const double inv = 1.0 / std::sqrt(r2);
  double ratio = rhs * inv;
  if (near_double) *near_double = std::fabs(ratio) > 1.0 - 1e-8;
  if (std::fabs(ratio) > 1.0 + kTangent && std::fabs(ratio) <= 1.0 + mirror)
    ratio = std::copysign(2.0, ratio) - ratio;
  if (!(std::fabs(ratio) <= 1.0 + kTangent) && !(clamp && std::isfinite(ratio))) return false;
  const double c = std::min(1.0, std::max(-1.0, ratio)), k = sign * std::sqrt((1.0 - c) * (1.0 + c));
  const double ca = a * inv, sa = b * inv;
  x = JointValue{ca * c - sa * k, sa * c + ca * k, 0.0};
  return true;
}


// (cos, sin) of the angle turning p to q about unit k (SP1); (1, 0) when free (p or q along k).
// ill: p or q is within 1e-4 (relative) of k, where the angle loses digits (r2 = |p_perp|^2 |q_perp|^2).
SPOTKIN_INLINE JointValue sp1(const V3& p, const V3& q, const V3& k, bool* free = nullptr,
                              bool* ill = nullptr) noexcept {
  const double c = p.dot(q) - k.dot(p) * k.dot(q), s = k.dot(p.cross(q));
  const double r2 = c * c + s * s;
  if (free) *free = !(r2 > 1e-30);
  if (ill) *ill = !(r2 > 1e-16 * p.squaredNorm() * q.squaredNorm());
  if (!(r2 > 1e-30)) return joint_zero();
  const double inv = 1.0 / std::sqrt(r2);
  return JointValue{c * inv, s * inv, 0.0};
}


}  // namespace detail6

// SP6 for two angles: A1 x1 + A2 x2 = e, x = (cos, sin), A2 fixed by the chain and A1, e
// by the target. When A2 has rank 1 (s2 / s1 <= rank_tolerance) its left null vector n gives
// n^T A1 x1 = n^T e (two x1), then its range m gives m^T A2 x2 = m^T (e - A1 x1) (two x2 per
// x1): pair k = 2 i1 + i2, "+" root first. With rank 2, |A2^-1 (e - A1 x1)| = 1 is a quartic
// in tan(x1 / 2): pairs in increasing x1. near[k]: a root within 1e-8 of a double root.
// mirror: for an idealised chain, a root missing by up to this much (|ratio| up to 1 + mirror,
// or a complex quartic root within sqrt(mirror)) starts from the mirrored ratio
// 2 sign(ratio) - ratio (the real part), flagged near: Newton steps on the true chain decide.
class Sp6 {
 public:
  Sp6() = default;
  Sp6(const Eigen::Matrix2d& A2, double rank_tolerance, double mirror) : A2_(A2), mirror_(mirror) {
    Eigen::Vector2d sv;
    Eigen::Matrix2d U;
    dense::svd_u2(A2_, sv, U);
    if (!(sv[0] > 0.0)) throw std::invalid_argument("degenerate geometry: an angle does not enter the equations");
    rank_ratio_ = sv[1] / sv[0];
    rank1_ = rank_ratio_ <= rank_tolerance;
    // signs fixed (the largest component positive) so that the root order does not depend on the SVD
    auto oriented = [](Eigen::Vector2d x) {
      return Eigen::Vector2d((std::fabs(x[0]) >= std::fabs(x[1]) ? x[0] : x[1]) < 0.0 ? -x : x);
    };
    n_ = oriented(U.col(1)), m_ = oriented(U.col(0));
    ma_ = m_.transpose() * A2_;
    if (!rank1_) A2_inv_ = A2_.inverse();
  }

  bool rank1() const noexcept { return rank1_; }
  double rank_ratio() const noexcept { return rank_ratio_; }
  double mirror() const noexcept { return mirror_; }
  const Eigen::Vector2d& null_vector() const noexcept { return n_; }
  const Eigen::Vector2d& range_vector() const noexcept { return m_; }
  const Eigen::RowVector2d& range_row() const noexcept { return ma_; }

  SPOTKIN_INLINE void pairs(const Eigen::Matrix2d& A1, const Eigen::Vector2d& e, JointValue pair[4][2],
                            bool found[4], bool near[4]) const noexcept {
    using detail6::root;
    for (int k = 0; k < 4; ++k) found[k] = false, near[k] = false;
    if (!rank1_) {
      quartic_pairs(A1, e, pair, found, near);
      return;
    }
    const Eigen::RowVector2d na = n_.transpose() * A1;
    for (int i1 = 0; i1 < 2; ++i1) {
      JointValue x1;
      bool near1 = false;
      if (!root(na[0], na[1], n_.dot(e), i1 == 0 ? 1.0 : -1.0, x1, false, &near1, mirror_)) continue;
      const double rhs = m_.dot(e - A1 * Eigen::Vector2d(x1.c, x1.s));
      for (int i2 = 0; i2 < 2; ++i2) {
        JointValue x2;
        bool near2 = false;
        if (!root(ma_[0], ma_[1], rhs, i2 == 0 ? 1.0 : -1.0, x2, false, &near2, mirror_)) continue;
        pair[2 * i1 + i2][0] = x1, pair[2 * i1 + i2][1] = x2, found[2 * i1 + i2] = true;
        near[2 * i1 + i2] = near1 || near2;
      }
    }
  }

 private:
  // Rank 2: x2 = u - V x1 (V = A2^-1 A1, u = A2^-1 e) and |x5|^2 = 1, i.e.
  //   f(t) = k0 + k1 cos t + k2 sin t + k3 cos 2t + k4 sin 2t = 0,
  // times (1 + x^2)^2 with x = tan((t - phi) / 2) a real quartic whose leading
  // coefficient is f(phi + pi) (phi the best of five samples). Real roots get Newton
  // steps on f; pairs in increasing x1.
  // With mirror > 0, a complex pair whose imaginary part is within sqrt(mirror) starts
  // from its real part (flagged near: the polish decides).
  SPOTKIN_INLINE void quartic_pairs(const Eigen::Matrix2d& A1, const Eigen::Vector2d& e, JointValue pair[4][2], bool found[4],
                     bool near[4]) const noexcept {
    const Eigen::Matrix2d V = A2_inv_ * A1;
    const Eigen::Vector2d u = A2_inv_ * e;
    const Eigen::Matrix2d W = V.transpose() * V;
    const Eigen::Vector2d g = V.transpose() * u;
    const double k0 = u.squaredNorm() - 1.0 + 0.5 * (W(0, 0) + W(1, 1)), k1 = -2.0 * g[0], k2 = -2.0 * g[1],
                 k3 = 0.5 * (W(0, 0) - W(1, 1)), k4 = W(0, 1);
    auto f = [&](double t) {
      return k0 + k1 * std::cos(t) + k2 * std::sin(t) + k3 * std::cos(2 * t) + k4 * std::sin(2 * t);
    };
    auto df = [&](double t) {
      return -k1 * std::sin(t) + k2 * std::cos(t) - 2 * k3 * std::sin(2 * t) + 2 * k4 * std::cos(2 * t);
    };
    double phi = 0.0, best = -1.0;
    for (int j = 0; j < 5; ++j) {
      const double candidate = 2.0 * kPi<double> * j / 5.0, value = std::fabs(f(candidate + kPi<double>));
      if (value > best) best = value, phi = candidate;
    }
    const double cp = std::cos(phi), sp = std::sin(phi), c2p = std::cos(2 * phi), s2p = std::sin(2 * phi);
    const double k1p = k1 * cp + k2 * sp, k2p = k2 * cp - k1 * sp, k3p = k3 * c2p + k4 * s2p, k4p = k4 * c2p - k3 * s2p;
    const double a[5] = {k0 + k1p + k3p, 2 * k2p + 4 * k4p, 2 * k0 - 6 * k3p, 2 * k2p - 4 * k4p, k0 - k1p + k3p};
    const double scale = std::max({std::fabs(k0), std::fabs(k1), std::fabs(k2), std::fabs(k3), std::fabs(k4), 1.0});
    detail::Complex roots[4];
    const int count = detail::polynomial_roots(a, 4, roots);
    std::pair<double, bool> t_found[4];  // (q1, near)
    int n = 0;
    for (int r = 0; r < count; ++r) {
      const double x = roots[r].real(), bound = std::max(1.0, std::fabs(x));
      const bool real = std::fabs(roots[r].imag()) <= Tolerance::root * bound;
      if (!real && !(std::fabs(roots[r].imag()) <= std::sqrt(mirror_) * bound)) continue;
      double t = phi + 2.0 * std::atan(x);
      if (real) {
        for (int it = 0; it < 8; ++it) {
          const double slope = df(t);
          if (slope == 0.0) break;
          t -= f(t) / slope;
        }
        if (!(std::fabs(f(t)) <= 1e-10 * scale)) continue;
      }
      t = remainder_two_pi(t);
      bool duplicate = false;
      for (int o = 0; o < n; ++o)
        duplicate |= std::fabs(remainder_two_pi(t - t_found[o].first)) < 1e-9;
      if (!duplicate) t_found[n++] = {t, !real};
    }
    std::sort(t_found, t_found + n);
    for (int k = 0; k < n; ++k) {
      near[k] = t_found[k].second;
      const double c1 = std::cos(t_found[k].first), s1 = std::sin(t_found[k].first);
      const Eigen::Vector2d x2 = u - V * Eigen::Vector2d(c1, s1);
      const double norm = x2.norm();
      pair[k][0] = JointValue{c1, s1, 0.0};
      pair[k][1] = norm > 0.0 ? JointValue{x2[0] / norm, x2[1] / norm, 0.0} : joint_zero();
      found[k] = true;
    }
  }

  Eigen::Matrix2d A2_ = Eigen::Matrix2d::Identity(), A2_inv_ = Eigen::Matrix2d::Zero();
  double mirror_ = 0.0, rank_ratio_ = 0.0;
  bool rank1_ = true;
  Eigen::Vector2d n_ = Eigen::Vector2d::Zero(), m_ = Eigen::Vector2d::Zero();
  Eigen::RowVector2d ma_ = Eigen::RowVector2d::Zero();
};

// The offsets of (K2) shared by the parallel families: axes h_i, p01 = p_1,
// p_{i,i+1} = d_[i] = p_{i+1} - p_i, p6T = -p_6, and M^-1 (G = T M^-1).
class PoeOffsets {
 public:
  explicit PoeOffsets(const Poe& poe) : M_inv_(inverse_rigid(poe.M)) {
    for (int j = 0; j < 6; ++j) h_[j] = poe.h[j];
    p01_ = poe.p[0];
    for (int j = 0; j < 5; ++j) d_[j] = poe.p[j + 1] - poe.p[j];
    p6T_ = -poe.p[5];
  }
  const Rigid<double>& M_inv() const noexcept { return M_inv_; }

 protected:
  V3 h_[6], d_[5], p01_, p6T_;
  Rigid<double> M_inv_;
};

class Parallel234 : public PoeOffsets {
 public:
  static constexpr int kSlots = 8;

  // poe: 6 joints with h2, h3, h4 exactly parallel (the idealised chain).
  // rank_tolerance: s2 / s1 of A2 at or below which the rank-1 form is used.
  // mirror: for an idealised chain, a root missing by up to this much (|ratio| up to
  // 1 + mirror) starts from the mirrored ratio 2 sign(ratio) - ratio and is flagged for
  // Newton steps on the true chain, where the pair of roots may exist (0: exact chains).
  explicit Parallel234(const Poe& poe, double rank_tolerance, double mirror = 0.0) : PoeOffsets(poe) {
    const V3 &h1 = h_[0], &h2 = h_[1];
    s3_ = h_[2].dot(h2) >= 0.0 ? 1.0 : -1.0;
    s4_ = h_[3].dot(h2) >= 0.0 ? 1.0 : -1.0;
    h2_perp_ = h2 - h1 * h1.dot(h2);
    h1_x_h2_ = h1.cross(h2);
    h12_ = h1.dot(h2);
    // q5 side of (P1), (P2): h2^T R_5 x = const + a cos q5 + b sin q5, x = h6, p56
    double c5a, a5a, b5a, c5b, a5b, b5b;
    detail6::trig(h2, h_[4], h_[5], c5a, a5a, b5a);
    detail6::trig(h2, h_[4], d_[4], c5b, a5b, b5b);
    Eigen::Matrix2d A2;
    A2 << -a5a, -b5a, -a5b, -b5b;
    e_const_ << c5a, c5b + h2.dot(d_[0] + d_[1] + d_[2] + d_[3]);
    sp6_ = Sp6(A2, rank_tolerance, mirror);
    // SP3 for q3: |Rot(h3, q3) p34 + p23| = |w| <=> (-p23)^T Rot(h3, q3) p34 = (|p34|^2 + |p23|^2 - |w|^2) / 2,
    // written as the reference does (the sign fixes which root is b = 0)
    detail6::trig(-d_[1], h_[2], d_[2], c3_, a3_, b3_);
    base3_ = d_[2].squaredNorm() + d_[1].squaredNorm();
    // a unit vector normal to h2, for theta234
    V3 v = h2.cross(V3::UnitX());
    if (v.norm() < 0.5) v = h2.cross(V3::UnitY());
    v2_ = v.normalized();
  }

  bool rank1() const noexcept { return sp6_.rank1(); }
  double rank_ratio() const noexcept { return sp6_.rank_ratio(); }

  // ---- the same solve across L lanes (rank-1 form, exact chains): plain arrays and selects ----
  static constexpr int kLanes = 16;

  // Lane i of (R, t) (G = T M^-1, rows r, columns c: R[r][c][i]) -> c, s of every slot and
  // joint, exists[slot][i] (0/1) and fallback[i] (1: a near double root, an ill-conditioned or
  // free angle: the caller solves that lane again by solve() and refines it). Lanes whose
  // input_ok is 0 give no slot.
  SPOTKIN_INLINE void solve_lanes(const double (&R)[3][3][kLanes], const double (&t)[3][kLanes],
                                  const double (&input_ok)[kLanes], double (&c)[kSlots][6][kLanes],
                                  double (&s)[kSlots][6][kLanes], double (&exists)[kSlots][kLanes],
                                  double (&fallback)[kLanes]) const noexcept {
    constexpr int L = kLanes;
    // local copies of the constants: the stores below cannot alias them
    double h[6][3], d[5][3], p01[3], p6T[3], h2p[3], h1x2[3], v2[3];
    for (int r = 0; r < 3; ++r) {
      for (int j = 0; j < 6; ++j) h[j][r] = h_[j][r];
      for (int j = 0; j < 5; ++j) d[j][r] = d_[j][r];
      p01[r] = p01_[r], p6T[r] = p6T_[r], h2p[r] = h2_perp_[r], h1x2[r] = h1_x_h2_[r], v2[r] = v2_[r];
    }
    const double h12 = h12_, e0c = e_const_[0], e1c = e_const_[1], s3 = s3_, s4 = s4_;
    const double n0 = sp6_.null_vector()[0], n1 = sp6_.null_vector()[1];
    const double m0 = sp6_.range_vector()[0], m1 = sp6_.range_vector()[1];
    const double ma0 = sp6_.range_row()[0], ma1 = sp6_.range_row()[1];
    const double ma_r2 = ma0 * ma0 + ma1 * ma1, ma_inv = ma_r2 > 0.0 ? 1.0 / std::sqrt(ma_r2) : 0.0;
    const double a3 = a3_, b3 = b3_, c3 = c3_, base3 = base3_;
    const double r3 = a3 * a3 + b3 * b3, inv3 = r3 > 0.0 ? 1.0 / std::sqrt(r3) : 0.0;
    constexpr double tangent = detail6::kTangent;
    auto dot = [](const double* a, const double* b) SPOTKIN_INLINE_LAMBDA { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    // Rot(k, q) x for (cos q, sin q) = (cq, sq) (Rodrigues)
    auto rotate = [&](const double* k, double cq, double sq, const double* x, double* out) SPOTKIN_INLINE_LAMBDA {
      const double along = dot(k, x);
      const double cross[3] = {k[1] * x[2] - k[2] * x[1], k[2] * x[0] - k[0] * x[2], k[0] * x[1] - k[1] * x[0]};
      for (int r = 0; r < 3; ++r) out[r] = along * k[r] + cq * (x[r] - along * k[r]) + sq * cross[r];
    };
    // (cos, sin) turning p to q about unit k; ill: the angle loses digits (or is free)
    auto sp1 = [&](const double* p, const double* q, const double* k, double& cq, double& sq, double& ill) SPOTKIN_INLINE_LAMBDA {
      const double cross[3] = {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
      const double cc = dot(p, q) - dot(k, p) * dot(k, q), ss = dot(k, cross), r2 = cc * cc + ss * ss;
      const bool bad = !(r2 > 1e-16 * dot(p, p) * dot(q, q)) || !(r2 > 1e-30);
      const double inv = bad ? 0.0 : 1.0 / std::sqrt(r2);
      cq = bad ? 1.0 : cc * inv, sq = bad ? 0.0 : ss * inv;
      ill = bad ? 1.0 : ill;
    };
    // a cos x + b sin x = rhs with hypot(a, b) = 1 / inv: the root of sign "sign"; ok and near flags
    auto root = [&](double ca, double sa, double ratio, double sign, double& cq, double& sq, double& ok,
                    double& near) SPOTKIN_INLINE_LAMBDA {
      const bool root_exists = std::fabs(ratio) <= 1.0 + tangent;
      ok = root_exists ? ok : 0.0;
      near = root_exists && std::fabs(ratio) > 1.0 - 1e-8 ? 1.0 : near;  // a double root (acos loses digits)
      const double cl = std::min(1.0, std::max(-1.0, ratio)), k = sign * std::sqrt((1.0 - cl) * (1.0 + cl));
      cq = ca * cl - sa * k, sq = sa * cl + ca * k;
    };
    // lane-inner loops (one pass per root choice), so that each loop body vectorises
    double Rl[3][3][L], tt[3][L], A00[L], A01[L], A10[L], A11[L], e0[L], e1[L], na0[L], na1[L], inv1[L], ratio1[L];
    for (int i = 0; i < L; ++i) {
      fallback[i] = 0.0;
      double Rh6[3], t3[3];
      for (int r = 0; r < 3; ++r) {
        for (int cc = 0; cc < 3; ++cc) Rl[r][cc][i] = R[r][cc][i];
        Rh6[r] = R[r][0][i] * h[5][0] + R[r][1][i] * h[5][1] + R[r][2][i] * h[5][2];
        t3[r] = t[r][i] - (R[r][0][i] * p6T[0] + R[r][1][i] * p6T[1] + R[r][2][i] * p6T[2]) - p01[r];
        tt[r][i] = t3[r];
      }
      A00[i] = dot(Rh6, h2p), A01[i] = dot(Rh6, h1x2), A10[i] = dot(t3, h2p), A11[i] = dot(t3, h1x2);
      e0[i] = e0c - dot(Rh6, h[0]) * h12, e1[i] = e1c - dot(t3, h[0]) * h12;
      na0[i] = n0 * A00[i] + n1 * A10[i], na1[i] = n0 * A01[i] + n1 * A11[i];
      const double r1 = na0[i] * na0[i] + na1[i] * na1[i];
      inv1[i] = r1 > 0.0 ? 1.0 / std::sqrt(r1) : 0.0;
      ratio1[i] = r1 > 0.0 ? (n0 * e0[i] + n1 * e1[i]) * inv1[i] : 2.0;
      fallback[i] = r1 > 0.0 || input_ok[i] == 0.0 ? 0.0 : 1.0;
    }
    for (int i1 = 0; i1 < 2; ++i1) {
      double c1[L], s1[L], ok1[L], near1[L], ratio5[L], a[3][L], A[3][L];
      for (int i = 0; i < L; ++i) {
        double ok = input_ok[i], nr = 0.0, cq, sq;
        root(na0[i] * inv1[i], na1[i] * inv1[i], ratio1[i], i1 == 0 ? 1.0 : -1.0, cq, sq, ok, nr);
        c1[i] = cq, s1[i] = sq, ok1[i] = ok, near1[i] = nr;
        const double f0 = e0[i] - (A00[i] * cq + A01[i] * sq), f1 = e1[i] - (A10[i] * cq + A11[i] * sq);
        ratio5[i] = (m0 * f0 + m1 * f1) * ma_inv;
        double h2_1[3], tl[3], Al[3];  // R_1 h2, R^T R_1 h2, R_1^T tt - p12
        rotate(h[0], cq, sq, h[1], h2_1);
        for (int r = 0; r < 3; ++r) a[r][i] = Rl[0][r][i] * h2_1[0] + Rl[1][r][i] * h2_1[1] + Rl[2][r][i] * h2_1[2];
        for (int r = 0; r < 3; ++r) tl[r] = tt[r][i];
        rotate(h[0], cq, -sq, tl, Al);
        for (int r = 0; r < 3; ++r) A[r][i] = Al[r] - d[0][r];
      }
      for (int i5 = 0; i5 < 2; ++i5) {
        double c5[L], s5[L], ok5[L], near5[L], ill6[L], c6[L], s6[L], ct[L], st[L], w[3][L], ratio3[L];
        for (int i = 0; i < L; ++i) {
          double ok = ok1[i], nr = near1[i], cq, sq;
          root(ma0 * ma_inv, ma1 * ma_inv, ratio5[i], i5 == 0 ? 1.0 : -1.0, cq, sq, ok, nr);
          c5[i] = cq, s5[i] = sq, ok5[i] = ok, near5[i] = nr;
          double b[3], al[3], ill = 0.0, cq6, sq6;
          rotate(h[4], cq, -sq, h[1], b);
          for (int r = 0; r < 3; ++r) al[r] = a[r][i];
          sp1(al, b, h[5], cq6, sq6, ill);
          c6[i] = cq6, s6[i] = sq6, ill6[i] = ill;
          // theta: Rot(h2, theta) v2 = R_1^T R R_6^T R_5^T v2
          double u5[3], u6[3], Ru[3], y[3];
          rotate(h[4], cq, -sq, v2, u5);
          rotate(h[5], cq6, -sq6, u5, u6);
          for (int r = 0; r < 3; ++r) Ru[r] = Rl[r][0][i] * u6[0] + Rl[r][1][i] * u6[1] + Rl[r][2][i] * u6[2];
          rotate(h[0], c1[i], -s1[i], Ru, y);
          double ctl, stl, ill_theta = 0.0;
          sp1(v2, y, h[1], ctl, stl, ill_theta);
          ct[i] = ctl, st[i] = stl;
          double B[3], RB[3], wl[3];
          rotate(h[4], cq, sq, d[4], B);
          for (int r = 0; r < 3; ++r) B[r] += d[3][r];
          rotate(h[1], ctl, stl, B, RB);
          for (int r = 0; r < 3; ++r) wl[r] = A[r][i] - RB[r], w[r][i] = wl[r];
          ratio3[i] = (0.5 * (base3 - dot(wl, wl)) - c3) * inv3;
        }
        for (int b3i = 0; b3i < 2; ++b3i) {
          const int slot = 4 * i1 + 2 * i5 + b3i;
          for (int i = 0; i < L; ++i) {
            double ok3 = ok5[i], near3 = near5[i], cq3, sq3;
            root(a3 * inv3, b3 * inv3, ratio3[i], b3i == 0 ? 1.0 : -1.0, cq3, sq3, ok3, near3);
            double rd2[3], u[3], wl[3], c2, s2, ill2 = ill6[i];
            rotate(h[2], cq3, sq3, d[2], rd2);
            for (int r = 0; r < 3; ++r) u[r] = d[1][r] + rd2[r], wl[r] = w[r][i];
            sp1(u, wl, h[1], c2, s2, ill2);
            const double c23 = c2 * cq3 - s3 * s2 * sq3, s23 = s2 * cq3 + s3 * c2 * sq3;
            const double c4 = ct[i] * c23 + st[i] * s23, s4v = st[i] * c23 - ct[i] * s23;
            c[slot][0][i] = c1[i], s[slot][0][i] = s1[i];
            c[slot][1][i] = c2, s[slot][1][i] = s2;
            c[slot][2][i] = cq3, s[slot][2][i] = sq3;
            c[slot][3][i] = c4, s[slot][3][i] = s4 * s4v;
            c[slot][4][i] = c5[i], s[slot][4][i] = s5[i];
            c[slot][5][i] = c6[i], s[slot][5][i] = s6[i];
            exists[slot][i] = ok3;
            // redo the lane: a (q1, q5) pair whose q6 is free or ill-conditioned (the wrist
            // singularity, where solve() picks theta for the elbow), or a slot that exists but is
            // near a double root or ill-conditioned
            const bool edgy = (ok5[i] != 0.0 && ill6[i] != 0.0) || (ok3 != 0.0 && (near3 != 0.0 || ill2 != 0.0));
            fallback[i] = edgy && input_ok[i] != 0.0 ? 1.0 : fallback[i];
          }
        }
      }
    }
  }

  // Every solution for G = T M^-1 (R, t): q[slot] = (cos, sin) of the 6 angles.
  // refine[slot]: a root of q1, q5 or q3 is within 1e-8 of a double root (|ratio| near 1), where
  // acos loses half the digits, or an SP1 angle is ill-conditioned (sp1's ill): the caller
  // refines that slot by Newton steps.
  SPOTKIN_INLINE void solve(const M3& R, const V3& t, JointValue q[kSlots][6], bool exists[kSlots],
                            bool refine[kSlots]) const noexcept {
    for (int k = 0; k < kSlots; ++k) exists[k] = false, refine[k] = false;
    const V3 &h2 = h_[1];
    const V3 Rh6 = R * h_[5], tt = t - R * p6T_ - p01_;
    // (P1), (P2), q1 side: trig(x, h1, h2) = (x.h1) h12, x.h2perp, x.(h1 x h2)
    Eigen::Matrix2d A1;
    A1 << Rh6.dot(h2_perp_), Rh6.dot(h1_x_h2_), tt.dot(h2_perp_), tt.dot(h1_x_h2_);
    const Eigen::Vector2d e(e_const_[0] - Rh6.dot(h_[0]) * h12_, e_const_[1] - tt.dot(h_[0]) * h12_);
    JointValue pair[4][2];  // (q1, q5)
    bool found[4], near[4];
    sp6_.pairs(A1, e, pair, found, near);
    for (int k = 0; k < 4; ++k) {
      if (!found[k]) continue;
      const JointValue x1 = pair[k][0], x5 = pair[k][1];
      // q6: Rot(h6, q6) R^T R_1 h2 = R_5^T h2 (SP1; free, 0, when both lie along h6)
      const V3 a = R.transpose() * rotate(h_[0], x1.c, x1.s, h2), b = rotate(h_[4], x5.c, -x5.s, h2);
      bool free6 = false, ill6 = false;
      JointValue x6 = detail6::sp1(a, b, h_[5], &free6, &ill6);
      // theta234: Rot(h2, theta) v = R_1^T R R_6^T R_5^T v
      const V3 y = rotate(h_[0], x1.c, -x1.s, R * rotate(h_[5], x6.c, -x6.s, rotate(h_[4], x5.c, -x5.s, v2_)));
      JointValue theta = detail6::sp1(v2_, y, h2);
      const V3 A = rotate(h_[0], x1.c, -x1.s, tt) - d_[0], B = d_[3] + rotate(h_[4], x5.c, x5.s, d_[4]);
      if (free6) {
        // Wrist singularity (R_5 h6 = +-h2): only theta -+ q6 is fixed by the rotation, and
        // w = A - Rot(h2, theta) B. Take theta with |w|^2 at the middle of the elbow's range,
        // |p23|^2 + |p34|^2 + 2 c (c: the constant of p23^T Rot(h3, q3) p34), or the nearest.
        double c, ta, tb;
        detail6::trig(A, h2, B, c, ta, tb);
        const JointValue theta0 = theta;
        detail6::root(ta, tb, 0.5 * (A.squaredNorm() + B.squaredNorm() - (base3_ - 2.0 * c3_)) - c, 1.0, theta, true);
        // q6 = sigma (theta0 - theta), sigma = sign(h2 . R_5 h6)
        const double sigma = h2.dot(rotate(h_[4], x5.c, x5.s, h_[5])) >= 0.0 ? 1.0 : -1.0;
        x6 = JointValue{theta0.c * theta.c + theta0.s * theta.s, sigma * (theta0.s * theta.c - theta0.c * theta.s), 0.0};
      }
      const V3 w = A - rotate(h2, theta.c, theta.s, B);
      const double rhs3 = 0.5 * (base3_ - w.squaredNorm()) - c3_;
      for (int b3 = 0; b3 < 2; ++b3) {
        JointValue x3;
        bool near3 = false;
        if (!detail6::root(a3_, b3_, rhs3, b3 == 0 ? 1.0 : -1.0, x3, false, &near3, sp6_.mirror())) continue;
        const V3 u = d_[1] + rotate(h_[2], x3.c, x3.s, d_[2]);
        bool ill2 = false;
        const JointValue x2 = detail6::sp1(u, w, h2, nullptr, &ill2);
        // q4 = s4 (theta - q2 - s3 q3), as unit complex numbers
        const double c23 = x2.c * x3.c - s3_ * x2.s * x3.s, s23 = x2.s * x3.c + s3_ * x2.c * x3.s;
        const double c4 = theta.c * c23 + theta.s * s23, s4 = theta.s * c23 - theta.c * s23;
        const int slot = 2 * k + b3;
        q[slot][0] = x1, q[slot][1] = x2, q[slot][2] = x3;
        q[slot][3] = JointValue{c4, s4_ * s4, 0.0}, q[slot][4] = x5, q[slot][5] = x6;
        exists[slot] = true;
        refine[slot] = near[k] || near3 || ill6 || ill2;
      }
    }
  }

 private:
  V3 h2_perp_, h1_x_h2_, v2_;
  double h12_ = 0.0, s3_ = 1.0, s4_ = 1.0, a3_ = 0.0, b3_ = 0.0, c3_ = 0.0, base3_ = 0.0;
  Eigen::Vector2d e_const_;
  Sp6 sp6_;
};

// 6R chains whose axes 1, 2 and 3 are parallel. R_1 R_2 R_3 = Rot(h1, theta), theta =
// q1 + s2 q2 + s3 q3 (s_j = sign(h_j . h1)), keeps h1^T x, so with G = (R, t), a = R^T h1,
// u = Rot(h4, -q4) h1 and v = Rot(h6, q6) a:
//   orientation  R_5^T u = v, which needs (Q1) h5^T u = h5^T v
//   position     (Q2) p45^T u + p56^T v = h1^T (t - R p6T - p01 - p12 - p23 - p34)
// (h1^T R_4 R_5 R_6 p6T = a^T p6T moved right). Again A1 x6 + A2 x(-q4) = e (SP6), A2 fixed by
// the chain. Per (q6, q4): q5 by SP1 (Rot(h5, q5) v = u), theta from Rot(h1, theta) =
// R R_6^T R_5^T R_4^T, w = t - R p6T - p01 - Rot(h1, theta) (p34 + R_4 (p45 + R_5 p56)) =
// R_1 (p12 + R_2 p23): q2 by SP3, q1 by SP1, q3 = s3 (theta - q1 - s2 q2).
// Slots 2 k + b: k the (q6, -q4) pair of Sp6, b the root of q2. At the wrist singularity
// (u along h5, q5 free) q5 is set to 0 and the slot flagged for Newton steps.
class Parallel123 : public PoeOffsets {
 public:
  static constexpr int kSlots = 8;

  explicit Parallel123(const Poe& poe, double rank_tolerance, double mirror = 0.0) : PoeOffsets(poe) {
    const V3& h1 = h_[0];
    s2_ = h_[1].dot(h1) >= 0.0 ? 1.0 : -1.0;
    s3_ = h_[2].dot(h1) >= 0.0 ? 1.0 : -1.0;
    // the -q4 side of (Q1), (Q2): h5^T Rot(h4, phi) h1 and p45^T Rot(h4, phi) h1
    double a4a, b4a, a4b, b4b;
    detail6::trig(h_[4], h_[3], h1, c4a_, a4a, b4a);
    detail6::trig(d_[3], h_[3], h1, c4b_, a4b, b4b);
    Eigen::Matrix2d A2;
    A2 << -a4a, -b4a, a4b, b4b;
    sp6_ = Sp6(A2, rank_tolerance, mirror);
    offset_ = h1.dot(d_[0] + d_[1] + d_[2]);
    // SP3 for q2: |p12 + Rot(h2, q2) p23| = |w| <=> (-p12)^T Rot(h2, q2) p23 = (|p12|^2 + |p23|^2 - |w|^2) / 2
    detail6::trig(-d_[0], h_[1], d_[1], c2_, a2_, b2_);
    base2_ = d_[0].squaredNorm() + d_[1].squaredNorm();
    V3 v = h1.cross(V3::UnitX());
    if (v.norm() < 0.5) v = h1.cross(V3::UnitY());
    v1_ = v.normalized();
  }

  bool rank1() const noexcept { return sp6_.rank1(); }
  double rank_ratio() const noexcept { return sp6_.rank_ratio(); }

  SPOTKIN_INLINE void solve(const M3& R, const V3& t, JointValue q[kSlots][6], bool exists[kSlots],
                            bool refine[kSlots]) const noexcept {
    for (int k = 0; k < kSlots; ++k) exists[k] = false, refine[k] = false;
    const V3& h1 = h_[0];
    const V3 a = R.transpose() * h1, tt = t - R * p6T_ - p01_;
    double c6a, a6a, b6a, c6b, a6b, b6b;
    detail6::trig(h_[4], h_[5], a, c6a, a6a, b6a);
    detail6::trig(d_[4], h_[5], a, c6b, a6b, b6b);
    Eigen::Matrix2d A1;
    A1 << a6a, b6a, a6b, b6b;
    const Eigen::Vector2d e(c4a_ - c6a, h1.dot(tt) - offset_ - c6b - c4b_);
    JointValue pair[4][2];  // (q6, -q4)
    bool found[4], near[4];
    sp6_.pairs(A1, e, pair, found, near);
    for (int k = 0; k < 4; ++k) {
      if (!found[k]) continue;
      const JointValue x6 = pair[k][0], x4{pair[k][1].c, -pair[k][1].s, 0.0};
      const V3 u = rotate(h_[3], x4.c, -x4.s, h1), v = rotate(h_[5], x6.c, x6.s, a);
      bool ill5 = false;
      const JointValue x5 = detail6::sp1(v, u, h_[4], nullptr, &ill5);
      // theta: Rot(h1, theta) v1 = R R_6^T R_5^T R_4^T v1
      const V3 y = R * rotate(h_[5], x6.c, -x6.s, rotate(h_[4], x5.c, -x5.s, rotate(h_[3], x4.c, -x4.s, v1_)));
      const JointValue theta = detail6::sp1(v1_, y, h1);
      const V3 w = tt - rotate(h1, theta.c, theta.s,
                               d_[2] + rotate(h_[3], x4.c, x4.s, d_[3] + rotate(h_[4], x5.c, x5.s, d_[4])));
      const double rhs2 = 0.5 * (base2_ - w.squaredNorm()) - c2_;
      for (int b2 = 0; b2 < 2; ++b2) {
        JointValue x2;
        bool near2 = false;
        if (!detail6::root(a2_, b2_, rhs2, b2 == 0 ? 1.0 : -1.0, x2, false, &near2, sp6_.mirror())) continue;
        bool ill1 = false;
        const JointValue x1 = detail6::sp1(d_[0] + rotate(h_[1], x2.c, x2.s, d_[1]), w, h1, nullptr, &ill1);
        // q3 = s3 (theta - q1 - s2 q2), as unit complex numbers
        const double c12 = x1.c * x2.c - s2_ * x1.s * x2.s, s12 = x1.s * x2.c + s2_ * x1.c * x2.s;
        const double c3 = theta.c * c12 + theta.s * s12, s3 = theta.s * c12 - theta.c * s12;
        const int slot = 2 * k + b2;
        q[slot][0] = x1, q[slot][1] = x2, q[slot][2] = JointValue{c3, s3_ * s3, 0.0};
        q[slot][3] = x4, q[slot][4] = x5, q[slot][5] = x6;
        exists[slot] = true;
        refine[slot] = near[k] || near2 || ill5 || ill1;
      }
    }
  }

 private:
  V3 v1_;
  double s2_ = 1.0, s3_ = 1.0, c4a_ = 0.0, c4b_ = 0.0, offset_ = 0.0, a2_ = 0.0, b2_ = 0.0, c2_ = 0.0, base2_ = 0.0;
  Sp6 sp6_;
};

}  // namespace spotkin::chain_ik
