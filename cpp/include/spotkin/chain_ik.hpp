// Closed-form IK from a DH table: every position solution of a 3-joint chain
// (3R and its prismatic variants) and every solution of a 6R chain whose last
// three axes meet at one point (spherical wrist).
//
// The derivation, the equation labels (F), (I), (L), (Q), (B), (Q'), (B') and
// the tolerances are those of python/spotkin/reference/ik3r.py, which the tests
// compare this against. Two changes of representation, for speed:
//  - revolute values are carried as (cos q, sin q) until the end, so the back
//    substitution and the Newton polish need no trigonometric call;
//  - the quartic (Q) in e^{i q3} is solved in closed form (Ferrari) in
//    t = tan((q3 - phi) / 2), with phi chosen so that the leading coefficient
//    is the largest of the five samples of P (no root at t = infinity).
// For speed, batches of all-revolute chains run each step across 16 targets
// at once (Position3::solve_block, SphericalWrist6::solve_block), with a fixed
// set of 4 candidates per target and branch-free selects, so that the compiler
// vectorises across targets; only the quartic's roots, the rare Newton steps
// and the rare merges of near-equal solutions go target by target. solve()
// stays the one-target form (and the path of chains with prismatic joints).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <limits>
#include <string>
#include <type_traits>

#include <Eigen/SVD>

#include "spotkin/arm.hpp"
#include "spotkin/chain.hpp"
#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::chain_ik {

#if defined(__GNUC__)
#define SPOTKIN_INLINE_LAMBDA __attribute__((always_inline))
#else
#define SPOTKIN_INLINE_LAMBDA
#endif

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;

// Tolerances (s = the chain's length scale, see Position3::scale).
struct Tolerance {
  static constexpr double angle = 1e-9;     // |sin| or |cos| between two axes
  static constexpr double length = 1e-9;    // * s: distance between two axes counted as zero
  static constexpr double rank = 1e-9;      // smallest singular value of the scaled position Jacobian
  static constexpr double trim = 1e-11;     // leading coefficient / largest coefficient counted as zero
  static constexpr double root = 1e-2;      // ||z| - 1| (revolute) or |Im x| / max(1, |x|): root tried
  static constexpr double ratio = 1e-6;     // acos ratios within 1 + tol, discriminants within -tol s^2
  static constexpr double residual = 1e-9;  // * s: |fk(q) - p| after polishing, a solution
  static constexpr double merge = 1e-6;     // max joint distance (rad, or length / s): one solution
  static constexpr double wrist = 1e-9;     // * s: the last three axes meet within this distance
  static constexpr int newton_steps = 6;
};

enum class Kind : std::int8_t {
  Parallel3R,       // "3R-parallel": axes 2-3 (else 1-2) parallel, degree 2 in e^{iq}
  Intersecting3R,   // "3R-intersecting": axes 1-2 (else 2-3) intersect, degree 2
  GeneralQuartic3R, // "3R-general-quartic": both pairs skew, degree 4
  Prismatic,        // a pattern with prismatic joints, named by Position3::pattern
};

// A joint value: (cos q, sin q) for a revolute joint, v = q for a prismatic one.
// No default member initialisers: the solvers' scratch arrays stay
// uninitialised (zeroing them cost a memset per sample); use joint_zero().
struct JointValue {
  double c, s, v;
};

constexpr JointValue joint_zero() noexcept { return JointValue{1.0, 0.0, 0.0}; }

namespace detail {

SPOTKIN_INLINE V3 z_apply(int sigma, const JointValue& q, const V3& x) noexcept {
  if (sigma == 0) return V3(q.c * x[0] - q.s * x[1], q.s * x[0] + q.c * x[1], x[2]);
  return V3(x[0], x[1], x[2] + q.v);
}

// The rotation part of Z(q) applied to a direction.
SPOTKIN_INLINE V3 z_rotate(int sigma, const JointValue& q, const V3& x) noexcept {
  return sigma == 0 ? V3(q.c * x[0] - q.s * x[1], q.s * x[0] + q.c * x[1], x[2]) : x;
}

// d/dq (Z(q) x) = e3 x Z(q) x (revolute) or e3 (prismatic), given zx = Z(q) x.
SPOTKIN_INLINE V3 z_tangent(int sigma, const V3& zx) noexcept {
  return sigma == 0 ? V3(-zx[1], zx[0], 0.0) : V3(0.0, 0.0, 1.0);
}

// The unit vector of (x, y); (1, 0) at the origin (the angle is free there).
SPOTKIN_INLINE void unit(double x, double y, double& c, double& s) noexcept {
  const double r2 = x * x + y * y;
  if (r2 > 0.0) {
    const double inv = 1.0 / std::sqrt(r2);
    c = x * inv, s = y * inv;
  } else {
    c = 1.0, s = 0.0;
  }
}

// (cos, sin) of angle(x1, y1) - angle(x2, y2), with angle(0, 0) = 0: one
// square root and one division (these latencies dominate the back substitution).
SPOTKIN_INLINE JointValue angle_difference(double x1, double y1, double x2, double y2) noexcept {
  double r1 = x1 * x1 + y1 * y1, r2 = x2 * x2 + y2 * y2;
  if (!(r1 > 0.0)) x1 = 1.0, y1 = 0.0, r1 = 1.0;
  if (!(r2 > 0.0)) x2 = 1.0, y2 = 0.0, r2 = 1.0;
  const double inv = 1.0 / std::sqrt(r1 * r2);
  return JointValue{(x1 * x2 + y1 * y2) * inv, (y1 * x2 - x1 * y2) * inv, 0.0};
}

// y = M x and y = M^T x, written out (no inner loop: the lane loops around them vectorise).
SPOTKIN_INLINE void multiply(const M3& M, const double* x, double* y) noexcept {
  y[0] = M(0, 0) * x[0] + M(0, 1) * x[1] + M(0, 2) * x[2];
  y[1] = M(1, 0) * x[0] + M(1, 1) * x[1] + M(1, 2) * x[2];
  y[2] = M(2, 0) * x[0] + M(2, 1) * x[1] + M(2, 2) * x[2];
}
SPOTKIN_INLINE void multiply_transposed(const M3& M, const double* x, double* y) noexcept {
  y[0] = M(0, 0) * x[0] + M(1, 0) * x[1] + M(2, 0) * x[2];
  y[1] = M(0, 1) * x[0] + M(1, 1) * x[1] + M(2, 1) * x[2];
  y[2] = M(0, 2) * x[0] + M(1, 2) * x[1] + M(2, 2) * x[2];
}

// angle_difference without branches (for loops across samples).
SPOTKIN_INLINE JointValue angle_difference_lane(double x1, double y1, double x2, double y2) noexcept {
  const double r1 = x1 * x1 + y1 * y1, r2 = x2 * x2 + y2 * y2;
  const bool z1 = !(r1 > 0.0), z2 = !(r2 > 0.0);
  x1 = z1 ? 1.0 : x1, y1 = z1 ? 0.0 : y1, x2 = z2 ? 1.0 : x2, y2 = z2 ? 0.0 : y2;
  const double inv = 1.0 / std::sqrt((z1 ? 1.0 : r1) * (z2 ? 1.0 : r2));
  return JointValue{(x1 * x2 + y1 * y2) * inv, (y1 * x2 - x1 * y2) * inv, 0.0};
}

// One solution of a cos x + b sin x = rhs (the course's Spot problem, appendix, type 2): the angle
// of (a, b) plus (sign = +1) or minus (sign = -1) acos(rhs / hypot(a, b)),
// without trigonometric calls and without branches (it runs inside loops
// across samples). Writes (cos x, sin x); returns 1 if it exists, else 0.
// a = b = 0: the single answer x = 0 (sign +1; x is free or there is no
// solution, and the caller's residual test decides).
// With sin_alpha >= 0 given, it is used for the half-angle's sine times
// hypot(a, b) (when the caller has an accurate form of it).
SPOTKIN_INLINE double cos_sin_root(double a, double b, double rhs, double sign, double& c, double& s,
                                   double sin_alpha = -1.0) noexcept {
  const double r2 = a * a + b * b;
  const bool positive = r2 > 0.0;
  const double inv = 1.0 / std::sqrt(positive ? r2 : 1.0);
  const double ratio = rhs * inv, clamped = std::min(1.0, std::max(-1.0, ratio));
  const double k = sign * (sin_alpha >= 0.0 ? std::min(1.0, sin_alpha * inv)
                                            : std::sqrt(std::max(0.0, (1.0 - clamped) * (1.0 + clamped))));
  const double ca = a * inv, sa = b * inv;
  c = positive ? ca * clamped - sa * k : 1.0;
  s = positive ? sa * clamped + ca * k : 0.0;
  const double zero_answer = sign > 0.0 ? 1.0 : 0.0;
  return positive ? (std::fabs(ratio) <= 1.0 + Tolerance::ratio ? 1.0 : 0.0) : (r2 == 0.0 ? zero_answer : 0.0);
}

// Both solutions of a cos x + b sin x = rhs (cos_sin_root with sign +1, -1):
// returns their number, 0, 1 (a = b = 0) or 2.
SPOTKIN_INLINE int cos_sin_roots(double a, double b, double rhs, JointValue out[2], double sin_alpha = -1.0) noexcept {
  out[0].v = out[1].v = 0.0;
  if (cos_sin_root(a, b, rhs, 1.0, out[0].c, out[0].s, sin_alpha) == 0.0) return 0;
  if (!(a * a + b * b > 0.0)) return 1;
  cos_sin_root(a, b, rhs, -1.0, out[1].c, out[1].s, sin_alpha);
  return 2;
}

// A sorting network for 4 entries: exchange(x, y) puts entries x < y in order;
// these 5 exchanges sort any input with no data-dependent branch.
template <typename Exchange>
SPOTKIN_INLINE void sort4(Exchange&& exchange) noexcept {
  exchange(0, 1), exchange(2, 3), exchange(0, 2), exchange(1, 3), exchange(1, 2);
}

// The order of the solutions: lexicographic on (q1, q2, q3) in (-pi, pi]
// (revolute) or q / s (prismatic), where values within kOrderTie count as
// equal. Without the tie, two solutions that share q1 (every pair from one q1
// in the degree-2 kinds) would be ordered by the rounding of q1, which differs
// between the one-target and the lane paths.
constexpr double kOrderTie = 1e-7;  // below Tolerance::merge: distinct solutions never tie on all three

// Sort key of a revolute value (cos q, sin q): a "diamond" pseudo-angle,
// s / (|c| + |s|) unfolded to (-2, 2], increasing with q over (-pi, pi] with
// slope 1/2 to 1 (so a tie on keys is one on angles), without trigonometric
// calls. Angles within kOrderTie of -pi are keyed as +pi (the same angle).
SPOTKIN_INLINE double angle_key(double c, double s) noexcept {
  const double t = s / (std::fabs(c) + std::fabs(s));
  const double key = c >= 0.0 ? t : s >= 0.0 ? 2.0 - t : -2.0 - t;
  return key <= -2.0 + kOrderTie ? 2.0 : key;
}

// (b0, b1, b2) before (a0, a1, a2) in that order, without branches (+inf keys,
// for missing entries, go last).
SPOTKIN_INLINE bool order_less(double b0, double b1, double b2, double a0, double a1, double a2) noexcept {
  const bool tie0 = std::fabs(b0 - a0) <= kOrderTie, tie1 = std::fabs(b1 - a1) <= kOrderTie;
  return (!tie0 & (b0 < a0)) | (tie0 & ((!tie1 & (b1 < a1)) | (tie1 & (b2 < a2))));
}

using Complex = std::complex<double>;

// Roots of the monic z^2 + b z + c (real coefficients), the stable way.
SPOTKIN_INLINE void quadratic_roots(double b, double c, Complex out[2]) noexcept {
  const double disc = b * b - 4.0 * c;
  if (disc >= 0.0) {
    const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    out[0] = q;
    out[1] = q != 0.0 ? c / q : 0.0;
  } else {
    const double im = 0.5 * std::sqrt(-disc);
    out[0] = Complex(-0.5 * b, im);
    out[1] = Complex(-0.5 * b, -im);
  }
}

// Roots of the monic z^3 + b z^2 + c z + d (Cardano, trigonometric form when
// all three are real); the first is real and the largest real root. Each real
// root gets two Newton steps.
SPOTKIN_INLINE void cubic_roots(double b, double c, double d, Complex out[3]) noexcept {
  const double shift = b / 3.0;
  const double P = c - b * shift, Q = (2.0 * shift * shift - c) * shift + d;  // u^3 + P u + Q
  const double disc = 0.25 * Q * Q + P * P * P / 27.0;
  auto polish = [&](double z) {
    for (int k = 0; k < 2; ++k) {
      const double f = ((z + b) * z + c) * z + d, df = (3.0 * z + 2.0 * b) * z + c;
      if (df == 0.0) break;
      z -= f / df;
    }
    return z;
  };
  if (disc > 0.0) {
    const double A = -std::copysign(std::cbrt(0.5 * std::fabs(Q) + std::sqrt(disc)), Q);
    const double B = A != 0.0 ? -P / (3.0 * A) : 0.0;
    out[0] = polish(A + B - shift);
    const double re = -0.5 * (A + B) - shift, im = 0.5 * std::sqrt(3.0) * (A - B);
    out[1] = Complex(re, im);
    out[2] = Complex(re, -im);
  } else {
    const double m = std::sqrt(std::max(0.0, -P / 3.0));
    const double arg = m > 0.0 ? std::clamp(-0.5 * Q / (m * m * m), -1.0, 1.0) : 0.0;
    const double theta = std::acos(arg) / 3.0;
    constexpr double third = 2.0943951023931954923;  // 2 pi / 3
    for (int k = 0; k < 3; ++k) out[k] = polish(2.0 * m * std::cos(theta - third * k) - shift);
  }
}

// Roots of a4 z^4 + a3 z^3 + a2 z^2 + a1 z + a0, a4 != 0 (Ferrari: the
// depressed quartic y^4 + p y^2 + q y + r splits as two quadratics
// y^2 -+ S y + m +- q / (2 S), S^2 = 2 m - p, with m the largest root of the
// resolvent 8 m^3 - 4 p m^2 - 8 r m + 4 p r - q^2, for which 2 m - p > 0).
SPOTKIN_INLINE void quartic_roots(const double a[5], Complex out[4]) noexcept {
  const double A = a[3] / a[4], B = a[2] / a[4], C = a[1] / a[4], D = a[0] / a[4];
  const double shift = 0.25 * A, A2 = A * A;
  const double p = B - 0.375 * A2;
  const double q = C - 0.5 * A * B + 0.125 * A2 * A;
  const double r = D - 0.25 * A * C + A2 * B / 16.0 - 3.0 * A2 * A2 / 256.0;
  Complex resolvent[3];
  cubic_roots(-0.5 * p, -r, 0.5 * p * r - 0.125 * q * q, resolvent);
  const double m = resolvent[0].real(), S2 = 2.0 * m - p;
  const double scale = std::max({std::fabs(p), std::sqrt(std::fabs(r)), 1e-300});
  if (S2 <= 1e-14 * scale) {  // q ~ 0: biquadratic y^4 + p y^2 + r = 0
    Complex z[2];
    quadratic_roots(p, r, z);
    for (int k = 0; k < 2; ++k) {
      const Complex y = std::sqrt(z[k]);
      out[2 * k] = y - shift;
      out[2 * k + 1] = -y - shift;
    }
  } else {
    const double S = std::sqrt(S2), h = q / (2.0 * S);
    quadratic_roots(-S, m + h, out);
    quadratic_roots(S, m - h, out + 2);
    for (int k = 0; k < 4; ++k) out[k] -= shift;
  }
}

// Roots of the polynomial sum_k a[k] z^k of degree deg in 1..4.
inline int polynomial_roots(const double a[5], int deg, Complex out[4]) noexcept {
  switch (deg) {
    case 1:
      out[0] = -a[0] / a[1];
      return 1;
    case 2:
      quadratic_roots(a[1] / a[2], a[0] / a[2], out);
      return 2;
    case 3:
      cubic_roots(a[2] / a[3], a[1] / a[3], a[0] / a[3], out);
      return 3;
    default:
      quartic_roots(a, out);
      return 4;
  }
}

inline M3 rotation_z(double c, double s) {
  M3 R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

inline Rigid<double> inverse(const Rigid<double>& T) { return {T.R.transpose(), -(T.R.transpose() * T.p)}; }

}  // namespace detail

// The split (F) of a chain's first three joints:
//   p = M0 Z1(q1) M1 Z2(q2) M2 Z3(q3) w,
// with M0 = base . L_0, M1 = L_1, M2 = L_2 the fixed links of the chain's
// z-axis form (Chain::z_link): the same for URDF, DH and DHm chains.
struct Split {
  int sigma[3];
  Rigid<double> M0, M1, M2;
};

inline Rigid<double> link(const Chain<double>& chain, int j) { return chain.z_link(j); }

inline Split split_first_three(const Chain<double>& chain) {
  Split s;
  for (int j = 0; j < 3; ++j) s.sigma[j] = chain.joints()[static_cast<std::size_t>(j)].type == JointType::Revolute ? 0 : 1;
  s.M0 = chain.base() * link(chain, 0);
  s.M1 = link(chain, 1);
  s.M2 = link(chain, 2);
  return s;
}

// Position IK of the point w (in the frame after joint 3's variable Z) for
// the first three joints of a chain: the plan is made once per chain.
class Position3 {
 public:
  static constexpr int kSlots = 4;
  static constexpr int kMaxCandidates = 8;

  // Throws std::invalid_argument when no closed form applies, saying why.
  Position3(const Split& split, const V3& w, double scale) : split_(split), w_(w), scale_(scale) {
    for (int j = 0; j < 3; ++j) sigma_[j] = split.sigma[j];
    check_rank();
    plan();
    M0_inv_ = detail::inverse(split.M0);
    M1_inv_ = detail::inverse(split.M1);
    M2_inv_ = detail::inverse(split.M2);
    revolute_ = sigma_[0] == 0 && sigma_[1] == 0 && sigma_[2] == 0;
    if (revolute_) {  // the constants of (L) for solve_block
      P1_ = backward_ ? M2_inv_ : split.M1;
      P2_ = backward_ ? M1_inv_ : split.M2;
      ra_ = P1_.R.transpose() * P1_.p;
      rb_ = P1_.R.row(2).transpose();
    }
  }

  Kind kind() const noexcept { return kind_; }
  std::string name() const {
    switch (kind_) {
      case Kind::Parallel3R: return "3R-parallel";
      case Kind::Intersecting3R: return "3R-intersecting";
      case Kind::GeneralQuartic3R: return "3R-general-quartic";
      default: {
        std::string s;
        for (int j = 0; j < 3; ++j) s += sigma_[j] == 0 ? 'R' : 'P';
        return s;
      }
    }
  }
  bool backward() const noexcept { return backward_; }
  bool reduced() const noexcept { return reduced_; }
  int sigma(int j) const noexcept { return sigma_[j]; }
  double scale() const noexcept { return scale_; }
  const Split& split() const noexcept { return split_; }

  // Tool point for joint values (cos/sin or value), in the base frame.
  V3 point(const JointValue q[3]) const noexcept {
    const Split& S = split_;
    V3 x = detail::z_apply(sigma_[2], q[2], w_);
    x = S.M2.R * x + S.M2.p;
    x = detail::z_apply(sigma_[1], q[1], x);
    x = S.M1.R * x + S.M1.p;
    x = detail::z_apply(sigma_[0], q[0], x);
    return S.M0.R * x + S.M0.p;
  }

  // Every solution of point(q) = p: returns their number n <= 4 and writes
  // q[k] for k < n, sorted by (q1, q2, q3) with revolute angles in [-pi, pi]
  // (compared through their cosines and sines). 0 for a non-finite or an
  // unreachable p.
  SPOTKIN_INLINE int solve(const V3& p, JointValue q[kSlots][3]) const noexcept {
    if (!p.allFinite()) return 0;
    const V3 target = M0_inv_.R * p + M0_inv_.p;  // p' of (F')
    const double s = std::max(scale_, target.norm());
    Candidate cands[kMaxCandidates];
    int n;
    if (!backward_) {
      Problem pb{{sigma_[0], sigma_[1], sigma_[2]}, target, split_.M1, split_.M2, w_, reduced_, s};
      n = pb.candidates(cands);
    } else {  // (F') reversed: w = Z3(-q3) M2^-1 Z2(-q2) M1^-1 Z1(-q1) p'
      Problem pb{{sigma_[2], sigma_[1], sigma_[0]}, w_, M2_inv_, M1_inv_, target, reduced_, s};
      n = pb.candidates(cands);
      for (int k = 0; k < n; ++k) {
        std::swap(cands[k].q[0], cands[k].q[2]);
        for (auto& v : cands[k].q) v.s = -v.s, v.v = -v.v;
      }
    }
    return finish(target, s, cands, n, q);
  }


  static constexpr int kLanes = 16;

  // Solutions of a block of targets, across the lanes: solution k of target i
  // is (c, s, v)[k][j][i] for joint j, k < n[i].
  struct BlockSolutions {
    double c[kSlots][3][kLanes], s[kSlots][3][kLanes], v[kSlots][3][kLanes];
    int n[kLanes];
  };

  // solve() for m <= kLanes targets at once (coordinates in lanes, kLanes entries each), into out (same solutions, same
  // order). The all-revolute kinds run each step across the targets (lanes),
  // so that it vectorises; the roots of the quartic, the rare Newton steps and
  // the rare merges stay per target. Same equations and tolerances as solve().
  SPOTKIN_INLINE void solve_block(const double* px, const double* py, const double* pz, int m,
                                  BlockSolutions& out) const noexcept {
    auto store = [&](int i, const JointValue (*q)[3], int n) {
      out.n[i] = n;
      for (int k = 0; k < kSlots; ++k)
        for (int j = 0; j < 3; ++j) {
          const JointValue v = k < n ? q[k][j] : joint_zero();
          out.c[k][j][i] = v.c, out.s[k][j][i] = v.s, out.v[k][j][i] = v.v;
        }
    };
    if (!revolute_ || m < kLanes) {  // one by one (a short block costs no more than its targets)
      for (int i = 0; i < m; ++i) {
        JointValue q[kSlots][3];
        store(i, q, solve(V3(px[i], py[i], pz[i]), q));
      }
      return;
    }
    constexpr int L = kLanes, C = kSlots;  // C candidates: 4 roots q3 (Q), or 2 q3 x 2 q2 (Q')
    // target p' of (F'), the problem's target and point (PT, PW): (p', w) or (w, p') reversed
    double tx[L], ty[L], tz[L], sc[L], PTx[L], PTy[L], PTz[L], PWx[L], PWy[L], PWz[L];
    const M3& R0 = M0_inv_.R;
    const V3 t0 = M0_inv_.p;
    for (int i = 0; i < L; ++i) {
      tx[i] = R0(0, 0) * px[i] + R0(0, 1) * py[i] + R0(0, 2) * pz[i] + t0[0];
      ty[i] = R0(1, 0) * px[i] + R0(1, 1) * py[i] + R0(1, 2) * pz[i] + t0[1];
      tz[i] = R0(2, 0) * px[i] + R0(2, 1) * py[i] + R0(2, 2) * pz[i] + t0[2];
      sc[i] = std::max(scale_, std::sqrt(tx[i] * tx[i] + ty[i] * ty[i] + tz[i] * tz[i]));
      PTx[i] = backward_ ? w_[0] : tx[i], PTy[i] = backward_ ? w_[1] : ty[i], PTz[i] = backward_ ? w_[2] : tz[i];
      PWx[i] = backward_ ? tx[i] : w_[0], PWy[i] = backward_ ? ty[i] : w_[1], PWz[i] = backward_ ? tz[i] : w_[2];
    }
    const M3& R1 = P1_.R;
    const M3& R2 = P2_.R;
    const V3 t1 = P1_.p, t2 = P2_.p;
    const double a00 = ra_[0], a01 = ra_[1], a10 = rb_[0], a11 = rb_[1], ra2 = ra_[2], rb2 = rb_[2];
    const double det = a00 * a11 - a01 * a10, t1_2 = t1.squaredNorm();
    // (B') uses the row of Rr of largest norm; (Q') its left null vector
    const bool first_row = a00 * a00 + a01 * a01 >= a10 * a10 + a11 * a11;
    const Eigen::Vector2d null = Problem::null_row(a00, a01, a10, a11);
    // g = R2 Z3(q3) PW + t2 and d = kappa(g) - (ra2, rb2) g_z of (L)
    auto gd = [&](int i, double c3, double s3, double* g, double* d) SPOTKIN_INLINE_LAMBDA {
      const double hx = c3 * PWx[i] - s3 * PWy[i], hy = s3 * PWx[i] + c3 * PWy[i], hz = PWz[i];
      for (int r = 0; r < 3; ++r) g[r] = R2(r, 0) * hx + R2(r, 1) * hy + R2(r, 2) * hz + t2[r];
      const double pt2 = PTx[i] * PTx[i] + PTy[i] * PTy[i] + PTz[i] * PTz[i];
      d[0] = 0.5 * (pt2 - (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) - t1_2) - ra2 * g[2];
      d[1] = PTz[i] - t1[2] - rb2 * g[2];
    };
    // roots q3 (per target)
    double c3[C][L], s3[C][L];
    double roots3[L];  // their number (a double: one element width in the lane loops, so that they vectorise)
    if (reduced_) {
      double vals[3][L];
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < L; ++i) {
          double g[3], d[2];
          gd(i, kCos3[k], kSin3[k], g, d);
          vals[k][i] = null[0] * d[0] + null[1] * d[1];
        }
      for (int i = 0; i < L; ++i)
        roots3[i] = trig_roots3(vals[0][i], vals[1][i], vals[2][i], c3[0][i], s3[0][i], c3[1][i], s3[1][i]);
    } else {
      double vals[5][L];
      for (int k = 0; k < 5; ++k)
        for (int i = 0; i < L; ++i) {
          double g[3], d[2];
          gd(i, kCos5[k], kSin5[k], g, d);
          const double x = a11 * d[0] - a01 * d[1], y = -a10 * d[0] + a00 * d[1];
          vals[k][i] = x * x + y * y - det * det * (g[0] * g[0] + g[1] * g[1]);
        }
      for (int i = 0; i < m; ++i) {
        const double v[5] = {vals[0][i], vals[1][i], vals[2][i], vals[3][i], vals[4][i]};
        JointValue r[4];
        const int count = trig_roots5(v, r);
        roots3[i] = count;
        for (int k = 0; k < 4; ++k) c3[k][i] = k < count ? r[k].c : 1.0, s3[k][i] = k < count ? r[k].s : 0.0;
      }
    }
    double roots_found[L];
    for (int i = 0; i < L; ++i) roots_found[i] = i < m ? roots3[i] : 0.0;
    // candidates: q2 by (B) or (B'), q1 by (I), and the residual |point - PT|
    double q1c[C][L], q1s[C][L], q2c[C][L], q2s[C][L], q3c[C][L], q3s[C][L], res2[C][L];  // res2: squared residual
    double ok[C][L];  // 1 or 0
    // For candidate k of target i: q2 by (B) or (B'), q1 by (I), the residual
    // |point - PT|, and whether it exists. Reduced is a compile-time copy of
    // reduced_ (no branch in the lane loop, so that it vectorises).
    auto candidates = [&](auto reduced_tag) SPOTKIN_INLINE_LAMBDA {
      constexpr bool Reduced = decltype(reduced_tag)::value;
      for (int k = 0; k < C; ++k) {
        const int root = Reduced ? k / 2 : k;
        const double sign = k % 2 == 0 ? 1.0 : -1.0;
        double c3_row[L], s3_row[L];
        std::copy(c3[root], c3[root] + L, c3_row);
        std::copy(s3[root], s3[root] + L, s3_row);
        for (int i = 0; i < L; ++i) {
          const double c = c3_row[i], s = s3_row[i];
          double g[3], d[2], cq2, sq2, exists;
          gd(i, c, s, g, d);
          if constexpr (!Reduced) {  // (B): e^{i q2} = (adj(Rr) d / det) / (g_x + i g_y)
            const JointValue v = detail::angle_difference_lane((a11 * d[0] - a01 * d[1]) / det,
                                                               (-a10 * d[0] + a00 * d[1]) / det, g[0], g[1]);
            cq2 = v.c, sq2 = v.s;
            exists = root < roots_found[i] ? 1.0 : 0.0;
          } else {  // (B'): a cos q2 + b sin q2 = d_i, branch k % 2
            const double r0 = first_row ? a00 : a10, r1 = first_row ? a01 : a11;
            const double a = r0 * g[0] + r1 * g[1], b = r1 * g[0] - r0 * g[1], rhs = first_row ? d[0] : d[1];
            exists = (root < roots_found[i] ? 1.0 : 0.0) * detail::cos_sin_root(a, b, rhs, sign, cq2, sq2);
          }
          // f = R1 Z2(q2) g + t1; (I) q1 = angle(PT_xy) - angle(f_xy)
          const double mx = cq2 * g[0] - sq2 * g[1], my = sq2 * g[0] + cq2 * g[1], mz = g[2];
          double f[3];
          for (int r = 0; r < 3; ++r) f[r] = R1(r, 0) * mx + R1(r, 1) * my + R1(r, 2) * mz + t1[r];
          const JointValue v1 = detail::angle_difference_lane(PTx[i], PTy[i], f[0], f[1]);
          const double ex = v1.c * f[0] - v1.s * f[1] - PTx[i], ey = v1.s * f[0] + v1.c * f[1] - PTy[i],
                       ez = f[2] - PTz[i];
          q1c[k][i] = v1.c, q1s[k][i] = v1.s, q2c[k][i] = cq2, q2s[k][i] = sq2, q3c[k][i] = c, q3s[k][i] = s;
          res2[k][i] = ex * ex + ey * ey + ez * ez;
          ok[k][i] = exists;
        }
      }
    };
    if (reduced_)
      candidates(std::true_type{});
    else
      candidates(std::false_type{});
    // Newton steps where a residual is above 1e-13 s (rare), in the problem's frame
    for (int k = 0; k < C; ++k)
      for (int i = 0; i < m; ++i) {
        if (!(ok[k][i] != 0.0 && res2[k][i] > 1e-26 * sc[i] * sc[i])) continue;
        const Problem pb{{0, 0, 0}, V3(PTx[i], PTy[i], PTz[i]), P1_, P2_, V3(PWx[i], PWy[i], PWz[i]), reduced_, sc[i]};
        Candidate cand{{JointValue{q1c[k][i], q1s[k][i], 0.0}, JointValue{q2c[k][i], q2s[k][i], 0.0},
                        JointValue{q3c[k][i], q3s[k][i], 0.0}},
                       std::sqrt(res2[k][i])};
        pb.polish(cand);
        q1c[k][i] = cand.q[0].c, q1s[k][i] = cand.q[0].s, q2c[k][i] = cand.q[1].c, q2s[k][i] = cand.q[1].s;
        q3c[k][i] = cand.q[2].c, q3s[k][i] = cand.q[2].s, res2[k][i] = cand.residual * cand.residual;
      }
    // the chain's joints: (q3, q2, q1) with negated angles when the problem is reversed
    double joint_c[C][3][L], joint_s[C][3][L];
    const double sign = backward_ ? -1.0 : 1.0;
    for (int k = 0; k < C; ++k)
      for (int i = 0; i < L; ++i) {
        joint_c[k][0][i] = backward_ ? q3c[k][i] : q1c[k][i], joint_s[k][0][i] = sign * (backward_ ? q3s[k][i] : q1s[k][i]);
        joint_c[k][1][i] = q2c[k][i], joint_s[k][1][i] = sign * q2s[k][i];
        joint_c[k][2][i] = backward_ ? q1c[k][i] : q3c[k][i], joint_s[k][2][i] = sign * (backward_ ? q1s[k][i] : q3s[k][i]);
      }
    // finish() across the lanes where no two accepted candidates are within
    // Tolerance::merge (nothing to merge): accepted candidates sorted by their
    // (q1, q2, q3) pseudo-angles by a sorting network. Lanes with a pair to
    // merge go through finish() itself.
    const double merge2 = Tolerance::merge * Tolerance::merge;
    double accepted[C][L], key[C][3][L], merge_lane[L];
    for (int i = 0; i < L; ++i) {
      const bool finite = std::isfinite(px[i]) && std::isfinite(py[i]) && std::isfinite(pz[i]);
      for (int k = 0; k < C; ++k) {
        const bool acc = finite && ok[k][i] != 0.0 && res2[k][i] <= Tolerance::residual * Tolerance::residual * sc[i] * sc[i];
        accepted[k][i] = acc ? 1.0 : 0.0;
      }
      double near = 0.0;
      for (int a = 0; a < C; ++a)
        for (int b = a + 1; b < C; ++b) {
          double worst = 0.0;
          for (int j = 0; j < 3; ++j) {
            const double dc = joint_c[a][j][i] - joint_c[b][j][i], ds = joint_s[a][j][i] - joint_s[b][j][i];
            worst = std::max(worst, dc * dc + ds * ds);
          }
          near = std::max(near, accepted[a][i] * accepted[b][i] * (worst <= merge2 ? 1.0 : 0.0));
        }
      merge_lane[i] = near;
    }
    for (int k = 0; k < C; ++k)  // a loop of its own, so that it vectorises
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < L; ++i)
          key[k][j][i] = accepted[k][i] != 0.0 ? detail::angle_key(joint_c[k][j][i], joint_s[k][j][i])
                                               : std::numeric_limits<double>::infinity();
    // the network moves keys and values together (selects, no gathers); the
    // unsorted values stay in joint_c, joint_s for the lanes that merge
    double sorted_c[C][3][L], sorted_s[C][3][L];
    std::copy(&joint_c[0][0][0], &joint_c[0][0][0] + C * 3 * L, &sorted_c[0][0][0]);
    std::copy(&joint_s[0][0][0], &joint_s[0][0][0] + C * 3 * L, &sorted_s[0][0][0]);
    detail::sort4([&](int x, int y) SPOTKIN_INLINE_LAMBDA {
      for (int i = 0; i < L; ++i) {
        const bool swap = detail::order_less(key[y][0][i], key[y][1][i], key[y][2][i], key[x][0][i],
                                             key[x][1][i], key[x][2][i]);
        for (int j = 0; j < 3; ++j) {
          const double kx = key[x][j][i], ky = key[y][j][i], cx = sorted_c[x][j][i], cy = sorted_c[y][j][i];
          const double sx = sorted_s[x][j][i], sy = sorted_s[y][j][i];
          key[x][j][i] = swap ? ky : kx, key[y][j][i] = swap ? kx : ky;
          sorted_c[x][j][i] = swap ? cy : cx, sorted_c[y][j][i] = swap ? cx : cy;
          sorted_s[x][j][i] = swap ? sy : sx, sorted_s[y][j][i] = swap ? sx : sy;
        }
      }
    });
    for (int k = 0; k < C; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < L; ++i) out.c[k][j][i] = sorted_c[k][j][i], out.s[k][j][i] = sorted_s[k][j][i], out.v[k][j][i] = 0.0;
    for (int i = 0; i < m; ++i) {
      if (merge_lane[i] == 0.0) {
        out.n[i] = static_cast<int>(accepted[0][i] + accepted[1][i] + accepted[2][i] + accepted[3][i]);
        continue;
      }
      Candidate cands[C];
      for (int k = 0; k < C; ++k) {
        for (int j = 0; j < 3; ++j) cands[k].q[j] = JointValue{joint_c[k][j][i], joint_s[k][j][i], 0.0};
        cands[k].residual = ok[k][i] != 0.0 ? std::sqrt(res2[k][i]) : std::numeric_limits<double>::quiet_NaN();
      }
      JointValue q[kSlots][3];
      store(i, q, finish(V3(tx[i], ty[i], tz[i]), sc[i], cands, C, q));
    }
  }
 private:
  struct Candidate {
    JointValue q[3];
    double residual;
  };

  // Sample angles 2 pi k / 3 and 2 pi k / 5 for P's coefficients.
  static constexpr double kCos3[3] = {1.0, -0.5, -0.5}, kSin3[3] = {0.0, 0.8660254037844386, -0.8660254037844386};
  static constexpr double kCos5[5] = {1.0, 0.30901699437494745, -0.8090169943749473, -0.8090169943749476,
                                      0.30901699437494723};
  static constexpr double kSin5[5] = {0.0, 0.9510565162951535, 0.5877852522924732, -0.587785252292473,
                                      -0.9510565162951536};

  // Real roots q3 of (Q'), of degree 1 in (cos q3, sin q3), from its samples
  // at 2 pi k / 3: P = a0 + a1 cos + b1 sin exactly. Branch-free: writes both
  // candidate roots and returns how many exist (0, 1 or 2; one, q3 = 0, when
  // P is constant: q3 free or no solution, and the residual test decides).
  static SPOTKIN_INLINE double trig_roots3(double v0, double v1, double v2, double& c0, double& s0, double& c1,
                                           double& s1) noexcept {
    const double a0 = (v0 + v1 + v2) / 3.0;
    const double a1 = (2.0 / 3.0) * (v0 * kCos3[0] + v1 * kCos3[1] + v2 * kCos3[2]);
    const double b1 = (2.0 / 3.0) * (v1 * kSin3[1] + v2 * kSin3[2]);
    const double m1 = 0.5 * std::sqrt(a1 * a1 + b1 * b1), top = std::max(std::fabs(a0), m1);
    const bool varying = m1 > Tolerance::trim * top;
    const double found = detail::cos_sin_root(a1, b1, -a0, 1.0, c0, s0);
    detail::cos_sin_root(a1, b1, -a0, -1.0, c1, s1);
    c0 = varying ? c0 : 1.0, s0 = varying ? s0 : 0.0;
    return !(top == top) ? 0.0 : !varying ? 1.0 : 2.0 * found;
  }

  static SPOTKIN_INLINE int trig_roots3(const double vals[3], JointValue out[2]) noexcept {
    out[0].v = out[1].v = 0.0;
    return static_cast<int>(trig_roots3(vals[0], vals[1], vals[2], out[0].c, out[0].s, out[1].c, out[1].s));
  }

  // Real roots q3 of (Q) from its samples at 2 pi k / 5; the DFT gives
  // P = a0 + a1 cos + b1 sin + a2 cos 2q + b2 sin 2q exactly.
  static SPOTKIN_INLINE int trig_roots5(const double vals[5], JointValue out[4]) noexcept {
    double a0 = 0, a1 = 0, b1 = 0, a2 = 0, b2 = 0;
    for (int k = 0; k < 5; ++k) {
      const int k2 = (2 * k) % 5;
      a0 += vals[k];
      a1 += vals[k] * kCos5[k], b1 += vals[k] * kSin5[k];
      a2 += vals[k] * kCos5[k2], b2 += vals[k] * kSin5[k2];
    }
    a0 /= 5.0, a1 *= 0.4, b1 *= 0.4, a2 *= 0.4, b2 *= 0.4;
    // |c_m| of the complex form, m = 0, 1, 2
    const double m1 = 0.5 * std::sqrt(a1 * a1 + b1 * b1), m2 = 0.5 * std::sqrt(a2 * a2 + b2 * b2);
    const double top = std::max({std::fabs(a0), m1, m2});
    if (!(top == top)) return 0;
    if (m2 > Tolerance::trim * top) {
      // phi = theta_k* - pi, k* the sample of largest |P|: the quartic in
      // t = tan(theta / 2), q3 = phi + theta, has leading coefficient P(theta_k*).
      int kmax = 0;
      for (int k = 1; k < 5; ++k)
        if (std::fabs(vals[k]) > std::fabs(vals[kmax])) kmax = k;
      const double cp = -kCos5[kmax], sp = -kSin5[kmax];
      const double c2p = cp * cp - sp * sp, s2p = 2.0 * cp * sp;
      const double A1 = a1 * cp + b1 * sp, B1 = b1 * cp - a1 * sp;
      const double A2 = a2 * c2p + b2 * s2p, B2 = b2 * c2p - a2 * s2p;
      // (1 + t^2)^2 P(phi + theta), cos = (1 - t^2) / (1 + t^2), sin = 2 t / (1 + t^2)
      const double coef[5] = {a0 + A1 + A2, 2.0 * B1 + 4.0 * B2, 2.0 * a0 - 6.0 * A2, 2.0 * B1 - 4.0 * B2,
                              a0 - A1 + A2};
      detail::Complex z[4];
      detail::quartic_roots(coef, z);
      int n = 0;
      for (const auto& t : z) {
        const double re = t.real(), im = t.imag();
        // ||e^{i theta}| - 1| ~ 2 |Im t| / (1 + |t|^2)
        if (!(2.0 * std::fabs(im) <= Tolerance::root * (1.0 + re * re))) continue;
        const double d = 1.0 + re * re, ct = (1.0 - re * re) / d, st = 2.0 * re / d;
        out[n++] = JointValue{cp * ct - sp * st, sp * ct + cp * st, 0.0};
      }
      return n;
    }
    if (m1 > Tolerance::trim * top) return detail::cos_sin_roots(a1, b1, -a0, out);
    out[0] = joint_zero();  // P constant: q3 free or no solution; the residual test decides
    return 1;
  }

  // The forward problem target = Z1(q1) M1 Z2(q2) M2 Z3(q3) w of (F').
  struct Problem {
    int sig[3];
    V3 target;
    Rigid<double> M1, M2;
    V3 w;
    bool reduced;
    double s;

    // g(q3) = R2 Z3(q3) w + t2
    SPOTKIN_INLINE V3 g_of(const JointValue& q3) const noexcept { return M2.R * detail::z_apply(sig[2], q3, w) + M2.p; }

    // q2 revolute, eq. (L): rows r_a, r_b and kappa(g).
    SPOTKIN_INLINE void rows(V3& ra, V3& rb) const noexcept {
      if (sig[0] == 0) {
        ra = M1.R.transpose() * M1.p;      // u
        rb = M1.R.row(2).transpose();      // v = R1^T e3
      } else {
        ra = M1.R.row(0).transpose();
        rb = M1.R.row(1).transpose();
      }
    }
    SPOTKIN_INLINE Eigen::Vector2d kappa(const V3& g) const noexcept {
      if (sig[0] == 0)
        return {(target.squaredNorm() - g.squaredNorm() - M1.p.squaredNorm()) / 2.0, target[2] - M1.p[2]};
      return {target[0] - M1.p[0], target[1] - M1.p[1]};
    }

    // P(q3) of (Q), (Q') or the prismatic variants, and the back substitution.
    SPOTKIN_INLINE double P(const JointValue& q3, const V3& ra, const V3& rb) const noexcept {
      const V3 g = g_of(q3);
      if (sig[1] == 0) {
        const Eigen::Vector2d d = kappa(g) - Eigen::Vector2d(ra[2], rb[2]) * g[2];
        const double a00 = ra[0], a01 = ra[1], a10 = rb[0], a11 = rb[1];
        if (!reduced) {  // (Q) |adj(Rr) d|^2 - det(Rr)^2 (g_x^2 + g_y^2)
          const double det = a00 * a11 - a01 * a10;
          const double x = a11 * d[0] - a01 * d[1], y = -a10 * d[0] + a00 * d[1];
          return x * x + y * y - det * det * (g[0] * g[0] + g[1] * g[1]);
        }
        const Eigen::Vector2d n = null_row(a00, a01, a10, a11);  // (Q') n . d
        return n.dot(d);
      }
      const V3 u = M1.R.transpose() * M1.p, v = M1.R.row(2).transpose();
      if (sig[0] == 0) {
        if (!reduced) {  // RP: q2 from (I2), then (I1)
          const double q2 = (target[2] - M1.p[2] - v.dot(g)) / v[2];
          return (g + V3(0, 0, q2) + u).squaredNorm() - target.squaredNorm();
        }
        return v.dot(g) + M1.p[2] - target[2];
      }
      const V3 e = M1.R.col(2), k = M1.R * g + M1.p - target;  // PP
      return e[0] * k[1] - e[1] * k[0];
    }

    // A row of adj(Rr) of largest norm: the left null vector when det Rr = 0.
    static SPOTKIN_INLINE Eigen::Vector2d null_row(double a00, double a01, double a10, double a11) noexcept {
      const Eigen::Vector2d n0(a11, -a01), n1(-a10, a00);
      return n0.squaredNorm() >= n1.squaredNorm() ? n0 : n1;
    }

    // q2 values for a root q3 (eqs. (B), (B') and the prismatic forms).
    SPOTKIN_INLINE int back(const JointValue& q3, const V3& ra, const V3& rb, JointValue out[2]) const noexcept {
      const V3 g = g_of(q3);
      if (sig[1] == 0) {
        const Eigen::Vector2d d = kappa(g) - Eigen::Vector2d(ra[2], rb[2]) * g[2];
        const double a00 = ra[0], a01 = ra[1], a10 = rb[0], a11 = rb[1];
        if (!reduced) {  // (B): y = adj(Rr) d / det, e^{i q2} = y / (g_x + i g_y)
          const double det = a00 * a11 - a01 * a10;
          const double y0 = (a11 * d[0] - a01 * d[1]) / det, y1 = (-a10 * d[0] + a00 * d[1]) / det;
          out[0] = detail::angle_difference(y0, y1, g[0], g[1]);
          return 1;
        }
        // (B'): a cos q2 + b sin q2 = d_i on the row i of Rr of largest norm
        const bool first = a00 * a00 + a01 * a01 >= a10 * a10 + a11 * a11;
        const double r0 = first ? a00 : a10, r1 = first ? a01 : a11;
        const double a = r0 * g[0] + r1 * g[1], b = r1 * g[0] - r0 * g[1];
        return detail::cos_sin_roots(a, b, first ? d[0] : d[1], out);
      }
      const V3 u = M1.R.transpose() * M1.p, v = M1.R.row(2).transpose();
      if (sig[0] == 0) {
        if (!reduced) {
          out[0] = JointValue{1.0, 0.0, (target[2] - M1.p[2] - v.dot(g)) / v[2]};
          return 1;
        }
        // q2^2 + 2 (g_z + u_z) q2 + |g + u|^2 - |p'|^2 = 0
        const double b = g[2] + u[2], c = (g + u).squaredNorm() - target.squaredNorm();
        const double disc = b * b - c;
        if (disc < -Tolerance::ratio * s * s) return 0;
        const double root = std::sqrt(std::max(disc, 0.0));
        out[0] = JointValue{1.0, 0.0, -b + root};
        out[1] = JointValue{1.0, 0.0, -b - root};
        return 2;
      }
      const V3 e = M1.R.col(2), k = M1.R * g + M1.p - target;  // PP
      out[0] = JointValue{1.0, 0.0, -(e[0] * k[0] + e[1] * k[1]) / (e[0] * e[0] + e[1] * e[1])};
      return 1;
    }

    // Real roots q3 of P: a trigonometric polynomial of degree <= 2 (revolute
    // q3) or a polynomial of degree <= 4 (prismatic), recovered from 5 samples.
    SPOTKIN_INLINE int roots(const V3& ra, const V3& rb, JointValue out[4]) const noexcept {
      if (sig[2] == 0 && reduced) {
        double vals[3];
        for (int k = 0; k < 3; ++k) vals[k] = P(JointValue{kCos3[k], kSin3[k], 0.0}, ra, rb);
        return trig_roots3(vals, out);
      }
      if (sig[2] == 0) {
        double vals[5];
        for (int k = 0; k < 5; ++k) vals[k] = P(JointValue{kCos5[k], kSin5[k], 0.0}, ra, rb);
        return trig_roots5(vals, out);
      }
      // Prismatic q3 = s x: samples at the Chebyshev extrema x_k = cos(pi k / 4).
      static const Eigen::Matrix<double, 5, 5> inverse_vandermonde = [] {
        Eigen::Matrix<double, 5, 5> V;
        for (int k = 0; k < 5; ++k) {
          const double x = std::cos(kPi<double> * k / 4.0);
          for (int j = 0; j < 5; ++j) V(k, j) = std::pow(x, j);
        }
        return Eigen::Matrix<double, 5, 5>(V.inverse());
      }();
      Eigen::Matrix<double, 5, 1> vals;
      for (int k = 0; k < 5; ++k) vals[k] = P(JointValue{1, 0, s * std::cos(kPi<double> * k / 4.0)}, ra, rb);
      const Eigen::Matrix<double, 5, 1> c = inverse_vandermonde * vals;
      const double top = c.cwiseAbs().maxCoeff();
      if (!(top == top)) return 0;
      int deg = 4;
      while (deg > 0 && std::fabs(c[deg]) <= Tolerance::trim * top) --deg;
      if (deg == 0) {
        out[0] = joint_zero();
        return 1;
      }
      detail::Complex z[4];
      const int m = detail::polynomial_roots(c.data(), deg, z);
      int n = 0;
      for (int k = 0; k < m; ++k)
        if (std::fabs(z[k].imag()) <= Tolerance::root * std::max(1.0, std::sqrt(std::norm(z[k]))))
          out[n++] = JointValue{1, 0, s * z[k].real()};
      return n;
    }

    // Tool point and its 3x3 Jacobian in the problem's frame.
    SPOTKIN_INLINE V3 point(const JointValue q[3], M3* J) const noexcept {
      const V3 h = detail::z_apply(sig[2], q[2], w);
      const V3 g = M2.R * h + M2.p;
      const V3 m = detail::z_apply(sig[1], q[1], g);
      const V3 f = M1.R * m + M1.p;
      const V3 p = detail::z_apply(sig[0], q[0], f);
      if (J) {
        J->col(0) = detail::z_tangent(sig[0], p);
        J->col(1) = detail::z_rotate(sig[0], q[0], M1.R * detail::z_tangent(sig[1], m));
        J->col(2) = detail::z_rotate(sig[0], q[0], M1.R * detail::z_rotate(sig[1], q[1], M2.R * detail::z_tangent(sig[2], h)));
      }
      return p;
    }

    // Candidates, each polished by Gauss-Newton on the position equations.
    SPOTKIN_INLINE int candidates(Candidate out[kMaxCandidates]) const noexcept {
      V3 ra = V3::Zero(), rb = V3::Zero();
      if (sig[1] == 0) rows(ra, rb);
      JointValue q3s[4];
      const int n3 = roots(ra, rb, q3s);
      int n = 0;
      for (int i = 0; i < n3; ++i) {
        JointValue q2s[2];
        const int n2 = back(q3s[i], ra, rb, q2s);
        const V3 g = g_of(q3s[i]);
        for (int j = 0; j < n2; ++j) {
          Candidate& c = out[n++];
          c.q[2] = q3s[i];
          c.q[1] = q2s[j];
          const V3 f = M1.R * detail::z_apply(sig[1], q2s[j], g) + M1.p;
          if (sig[0] == 0) {  // (I) q1 = angle(p'_xy) - angle(f_xy)
            c.q[0] = detail::angle_difference(target[0], target[1], f[0], f[1]);
          } else {
            c.q[0] = JointValue{1.0, 0.0, target[2] - f[2]};
          }
          polish(c);
        }
      }
      return n;
    }

    SPOTKIN_INLINE void polish(Candidate& c) const noexcept {
      // Steps stop once |fk(q) - p| <= 1e-13 s (4 orders below Tolerance::residual,
      // 3 below the 1e-10 accuracy promised; a closed-form root usually starts there).
      const double done = 1e-13 * s;
      V3 r = point(c.q, nullptr) - target;
      double res = r.norm();
      M3 J;
      if (res > done) point(c.q, &J);
      for (int step = 0; step < Tolerance::newton_steps && res > done; ++step) {
        // Gauss-Newton step J delta = -r (least squares when J is singular)
        V3 delta;
        const M3 adj = (M3() << J.col(1).cross(J.col(2)).transpose(), J.col(2).cross(J.col(0)).transpose(),
                        J.col(0).cross(J.col(1)).transpose())
                           .finished();
        const double det = J.col(0).dot(J.col(1).cross(J.col(2)));
        const double norms = J.col(0).norm() * J.col(1).norm() * J.col(2).norm();
        if (std::fabs(det) > 1e-8 * norms) {
          delta = -(adj * r) / det;
        } else {
          Eigen::JacobiSVD<M3> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
          delta = -svd.solve(r);
        }
        Candidate next = c;
        for (int j = 0; j < 3; ++j) advance(sig[j], delta[j], next.q[j]);
        M3 J_next;
        const V3 r_next = point(next.q, &J_next) - target;
        const double res_next = r_next.norm();
        if (!(res_next < res)) break;
        c = next, r = r_next, res = res_next, J = J_next;
      }
      c.residual = res;
    }

    static SPOTKIN_INLINE void advance(int sigma, double delta, JointValue& q) noexcept {
      if (sigma == 1) {
        q.v += delta;
        return;
      }
      double sd, cd;
      if (std::fabs(delta) < 0.05) {  // Taylor to the 9th order: exact to 1e-16 here
        const double d2 = delta * delta;
        sd = delta * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))));
        cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)));
      } else {
        sd = std::sin(delta), cd = std::cos(delta);
      }
      const double c = q.c * cd - q.s * sd, s = q.s * cd + q.c * sd;
      const double norm = std::sqrt(c * c + s * s);
      q.c = c / norm, q.s = s / norm;
    }
  };

  // Residual test, merging of near-equal solutions, angles, sorting.
  SPOTKIN_INLINE int finish(const V3& target, double s, Candidate* cands, int n, JointValue q[kSlots][3]) const noexcept {
    const double merge2 = Tolerance::merge * Tolerance::merge, length2 = s * s;
    // joint distance within Tolerance::merge: chord (revolute) or |dv| / s (prismatic)
    auto close = [&](const Candidate& a, const Candidate& b) SPOTKIN_INLINE_LAMBDA {
      for (int j = 0; j < 3; ++j) {
        const double dc = a.q[j].c - b.q[j].c, ds = a.q[j].s - b.q[j].s, dv = a.q[j].v - b.q[j].v;
        if (sigma_[j] == 0 ? dc * dc + ds * ds > merge2 : dv * dv > merge2 * length2) return false;
      }
      return true;
    };
    // accepted candidates, best residual first: a branch-free sorting network
    // for up to 4 (the residuals are random), else an insertion sort (at most 8)
    int order[kMaxCandidates], m = 0;
    if (n <= 4) {
      double key[4];
      for (int k = 0; k < 4; ++k) {
        const bool accepted = k < n && cands[k].residual <= Tolerance::residual * s;
        key[k] = accepted ? cands[k].residual : std::numeric_limits<double>::infinity();
        order[k] = k;
        m += accepted;
      }
      detail::sort4([&](int x, int y) SPOTKIN_INLINE_LAMBDA {
        const bool swap = key[order[y]] < key[order[x]];
        const int ox = order[x], oy = order[y];
        order[x] = swap ? oy : ox, order[y] = swap ? ox : oy;
      });
    } else {
      for (int k = 0; k < n; ++k) {
        if (!(cands[k].residual <= Tolerance::residual * s)) continue;
        int at = m++;
        for (; at > 0 && cands[order[at - 1]].residual > cands[k].residual; --at) order[at] = order[at - 1];
        order[at] = k;
      }
    }
    // merge solutions within Tolerance::merge into their mean (kept if it is a solution)
    const Candidate* groups[kMaxCandidates];
    Candidate means[kMaxCandidates];
    int count_groups = 0;
    bool used[kMaxCandidates] = {};
    for (int a = 0; a < m; ++a) {
      if (used[a]) continue;
      const Candidate& lead = cands[order[a]];
      Candidate& mean = means[count_groups];
      int count = 1;
      for (int b = a + 1; b < m; ++b) {
        const Candidate& other = cands[order[b]];
        if (used[b] || !close(lead, other)) continue;
        used[b] = true;
        if (count++ == 1) mean = lead;
        for (int j = 0; j < 3; ++j) mean.q[j].c += other.q[j].c, mean.q[j].s += other.q[j].s, mean.q[j].v += other.q[j].v;
      }
      const Candidate* kept = &lead;
      if (count > 1) {
        for (int j = 0; j < 3; ++j) {
          detail::unit(mean.q[j].c, mean.q[j].s, mean.q[j].c, mean.q[j].s);
          mean.q[j].v /= count;
        }
        const Problem forward{{sigma_[0], sigma_[1], sigma_[2]}, target, split_.M1, split_.M2, w_, reduced_, s};
        mean.residual = (forward.point(mean.q, nullptr) - target).norm();
        if (mean.residual <= Tolerance::residual * s) kept = &mean;
      }
      groups[count_groups++] = kept;
    }
    // the kSlots best residuals (groups keep the residual order; more than 4 never seen)
    count_groups = std::min(count_groups, kSlots);
    // (q1, q2, q3) order (detail::order_less, on detail::angle_key or v / s).
    // Branch-free (the signs and the order are random): keys, then a sorting
    // network over kSlots = 4 entries, missing ones keyed +inf.
    static_assert(kSlots == 4, "the sorting network below is for 4 slots");
    if (count_groups == 0) return 0;
    double keys[kSlots][3];
    int rank[kSlots] = {0, 1, 2, 3};
    for (int k = 0; k < kSlots; ++k)
      for (int j = 0; j < 3; ++j) {
        const JointValue& v = groups[std::min(k, count_groups - 1)]->q[j];
        const double key = sigma_[j] == 1 ? v.v / s : detail::angle_key(v.c, v.s);
        keys[k][j] = k < count_groups ? key : std::numeric_limits<double>::infinity();
      }
    detail::sort4([&](int x, int y) SPOTKIN_INLINE_LAMBDA {
      const double* a = keys[rank[x]];
      const double* b = keys[rank[y]];
      const bool swap = detail::order_less(b[0], b[1], b[2], a[0], a[1], a[2]);
      const int rx = rank[x], ry = rank[y];
      rank[x] = swap ? ry : rx, rank[y] = swap ? rx : ry;
    });
    for (int k = 0; k < count_groups; ++k)
      for (int j = 0; j < 3; ++j) q[k][j] = groups[rank[k]]->q[j];
    return count_groups;
  }

  // ValueError unless the position Jacobian has rank 3 somewhere (3 probes).
  void check_rank() const {
    static constexpr double probes[3][3] = {{0.7, -1.9, 2.4}, {-2.2, 0.5, -0.8}, {1.3, 2.9, -2.6}};
    double best = 0.0;
    for (const auto& probe : probes) {
      JointValue q[3];
      for (int j = 0; j < 3; ++j) q[j] = sigma_[j] == 0 ? JointValue{std::cos(probe[j]), std::sin(probe[j]), 0.0}
                                                        : JointValue{1, 0, probe[j] * scale_};
      const Problem pb{{sigma_[0], sigma_[1], sigma_[2]}, V3::Zero(), split_.M1, split_.M2, w_, false, scale_};
      M3 J;
      pb.point(q, &J);
      for (int j = 0; j < 3; ++j)
        if (sigma_[j] == 0) J.col(j) /= scale_;  // revolute columns carry a length
      best = std::max(best, Eigen::JacobiSVD<M3>(J).singularValues()[2]);
    }
    if (!(best > Tolerance::rank))
      throw std::invalid_argument(
          "no closed form: the tool point of this " + pattern() +
          " chain cannot be placed in 3D (position Jacobian of rank < 3 at every probe configuration: "
          "e.g. a planar chain, coincident or concurrent axes, or the tool point on the last axis)");
  }

  std::string pattern() const {
    std::string s;
    for (int j = 0; j < 3; ++j) s += sigma_[j] == 0 ? 'R' : 'P';
    return s;
  }

  enum class Relation { Coincident, Parallel, Intersecting, Skew };

  // Axis z of the current frame vs axis z of frame M.
  Relation relation(const Rigid<double>& M) const noexcept {
    const V3 t = M.p, z = M.R.col(2);
    const V3 cross(-z[1], z[0], 0.0);  // e3 x z
    const double sin = cross.norm();
    if (sin <= Tolerance::angle)
      return std::hypot(t[0], t[1]) <= Tolerance::length * scale_ ? Relation::Coincident : Relation::Parallel;
    return std::fabs(t.dot(cross)) / sin <= Tolerance::length * scale_ ? Relation::Intersecting : Relation::Skew;
  }

  // Whether the pair (joint a, next joint b) gives the reduced equation (Q').
  bool reduces(int sa, int sb, const Rigid<double>& M) const noexcept {
    if (sa == 1 && sb == 1) return true;                           // PP: degree <= 2
    if (sa != sb) return std::fabs(M.R(2, 2)) <= Tolerance::angle;  // PR / RP: perpendicular axes
    const Relation r = relation(M);
    return r == Relation::Parallel || r == Relation::Intersecting;
  }

  void plan() {
    const Rigid<double> M2_inv = detail::inverse(split_.M2);
    if (sigma_[0] == 0 && sigma_[1] == 0 && sigma_[2] == 0) {
      const Relation r12 = relation(split_.M1), r23 = relation(split_.M2);
      if (r23 == Relation::Parallel) {
        kind_ = Kind::Parallel3R, backward_ = true, reduced_ = true;
      } else if (r12 == Relation::Parallel) {
        kind_ = Kind::Parallel3R, backward_ = false, reduced_ = true;
      } else if (r12 == Relation::Intersecting) {
        kind_ = Kind::Intersecting3R, backward_ = false, reduced_ = true;
      } else if (r23 == Relation::Intersecting) {
        kind_ = Kind::Intersecting3R, backward_ = true, reduced_ = true;
      } else {
        kind_ = Kind::GeneralQuartic3R, backward_ = false, reduced_ = false;
      }
      return;
    }
    kind_ = Kind::Prismatic;
    if (reduces(sigma_[0], sigma_[1], split_.M1)) {
      backward_ = false, reduced_ = true;
    } else if (reduces(sigma_[2], sigma_[1], M2_inv)) {
      backward_ = true, reduced_ = true;
    } else {
      backward_ = false, reduced_ = false;
    }
  }

  Split split_;
  V3 w_;
  double scale_;
  int sigma_[3];
  Kind kind_ = Kind::GeneralQuartic3R;
  bool backward_ = false, reduced_ = false;
  Rigid<double> M0_inv_, M1_inv_, M2_inv_;
  bool revolute_ = false;
  Rigid<double> P1_, P2_;  // M1 and M2 of the problem solved (reversed when backward_)
  V3 ra_ = V3::Zero(), rb_ = V3::Zero();
};


// Joint limits of a chain: a revolute value is shifted by 0, -2 pi or +2 pi
// (the first that fits, as the leg and arm solvers do); a prismatic one is not.
struct Limits {
  static constexpr double kTolerance = 1e-12;
  static constexpr int kMaxJoints = 6;
  int dof = 0;
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double lower[kMaxJoints] = {-kInf, -kInf, -kInf, -kInf, -kInf, -kInf};  // infinite: no limit
  double upper[kMaxJoints] = {kInf, kInf, kInf, kInf, kInf, kInf};
  int sigma[kMaxJoints] = {};

  // Joint j's value v wrapped into its limits (v, then v - 2 pi, then v + 2 pi
  // for a revolute joint: the first that fits, as the leg and arm solvers do);
  // fit becomes 0 if none fits. Branch-free, for loops across samples.
  SPOTKIN_INLINE double wrap_value(int j, double v, double& fit) const noexcept {
    const double lo = lower[j] - kTolerance, hi = upper[j] + kTolerance, two_pi = 2.0 * kPi<double>;
    const bool revolute = sigma[j] == 0;
    const double below = v - two_pi, above = v + two_pi;
    const bool in = (v >= lo) & (v <= hi), in_below = revolute & (below >= lo) & (below <= hi),
               in_above = revolute & (above >= lo) & (above <= hi);
    fit = in | in_below | in_above ? fit : 0.0;
    return in ? v : in_below ? below : in_above ? above : v;
  }
};

// Finishes a block across the lanes, in place: the angles wrapped into the
// limits (infinite limits keep every finite value) and NaN where a slot has no
// solution; exists[k][i] becomes 0 for a lane whose input is bad, and
// valid[k][i] says whether slot k exists and fits the limits. Lanes [0, L) for
// a full block (a compile-time count: the loops vectorise), [0, m) for a short
// one (a single target pays for one lane).
template <bool Full, int Slots, int Dof, int L>
SPOTKIN_INLINE void finish_lanes(const Limits& limits, int m, const double (&input_ok)[L],
                                 double (&angle)[Slots][Dof][L], double (&exists)[Slots][L],
                                 double (&valid)[Slots][L]) noexcept {
  const Limits local = limits;  // a copy: the stores below cannot alias it
  const int lanes = Full ? L : m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < Slots; ++k) {
    for (int i = 0; i < lanes; ++i) exists[k][i] *= input_ok[i], valid[k][i] = exists[k][i];
    for (int j = 0; j < Dof; ++j)
      for (int i = 0; i < lanes; ++i) {
        const double wrapped = local.wrap_value(j, angle[k][j][i], valid[k][i]);
        angle[k][j][i] = exists[k][i] != 0.0 ? wrapped : nan;
      }
  }
}

// The Status of each lane of a finished block (as a double).
template <int Slots, int L>
SPOTKIN_INLINE void lane_status(int m, const double (&input_ok)[L], const double (&exists)[Slots][L],
                                const double (&valid)[Slots][L], double (&status)[L]) noexcept {
  for (int i = 0; i < m; ++i) {
    double any_exists = 0.0, any_valid = 0.0;
    for (int k = 0; k < Slots; ++k) any_exists = std::max(any_exists, exists[k][i]), any_valid = std::max(any_valid, valid[k][i]);
    status[i] = static_cast<double>(input_ok[i] == 0.0 ? Status::InvalidInput
                                    : any_valid != 0.0 ? Status::Ok
                                    : any_exists != 0.0 ? Status::JointLimit
                                                        : Status::Unreachable);
  }
}

// 6R chains whose last three axes meet at one point c (a spherical wrist):
// c fixes q1..q3 through Position3, then
//   W = A4^T R_A3^T R_target Tail^T = Rz(q4) B5 Rz(q5) B6 Rz(q6)
// gives the wrist angles (Paul's method on the third column):
//   (A)  e3 . B5 Rz(q5) b = w_z:  c5 (a_x b_x + a_y b_y) + s5 (a_y b_x - a_x b_y) = w_z - a_z b_z,
//        a = B5^T e3, b = B6 e3, w = W e3 (type 2: two q5);
//   (B)  Rz(q4) v = w, v = B5 Rz(q5) b:  e^{i q4} = (w_x + i w_y) / (v_x + i v_y);
//   (C)  Rz(q6) = (Rz(q4) B5 Rz(q5) B6)^T W.
// At most 4 x 2 = 8 solutions (the position part has at most 4, the wrist 2).
// In a wrist singularity (axes 4 and 6 aligned, v_xy = 0) q4 is free: 0 is
// returned and q6 takes the whole rotation.
class SphericalWrist6 {
 public:
  static constexpr int kSlots = 8;

  // Throws std::invalid_argument, naming the structure, when the chain is not
  // a 6-joint chain with revolute joints 4-6 whose axes meet at one point.
  static SphericalWrist6 make(const Chain<double>& chain, double scale) {
    if (chain.dof() != 6)
      throw std::invalid_argument("a spherical-wrist IK needs 6 joints, got " + std::to_string(chain.dof()));
    for (int j = 3; j < 6; ++j)
      if (chain.joints()[static_cast<std::size_t>(j)].type != JointType::Revolute)
        throw std::invalid_argument("no closed form: joint " + std::to_string(j + 1) +
                                    " is prismatic; a spherical wrist needs revolute joints 4, 5 and 6");
    // Axes 4, 5, 6 at q = 0, in the frame A3 just after joint 3's variable.
    const Rigid<double> L4 = link(chain, 3), L5 = link(chain, 4), L6 = link(chain, 5);
    const Rigid<double> F5 = L4 * L5, F6 = F5 * L6;
    const V3 o4 = L4.p, z4 = L4.R.col(2), o5 = F5.p, z5 = F5.R.col(2), o6 = F6.p, z6 = F6.R.col(2);
    const double tol = Tolerance::wrist * scale;
    const V3 n45 = z4.cross(z5), n56 = z5.cross(z6);
    if (n45.norm() <= Tolerance::angle || n56.norm() <= Tolerance::angle)
      throw std::invalid_argument(
          "no closed form: axes " + std::string(n45.norm() <= Tolerance::angle ? "4 and 5" : "5 and 6") +
          " are parallel, so the last three axes do not form a spherical wrist");
    // c: the point of axis 4 closest to axis 5
    const double h = (o5 - o4).cross(z5).dot(n45) / n45.squaredNorm();
    const V3 c = o4 + h * z4;
    const double d45 = std::fabs((o5 - o4).dot(n45)) / n45.norm();
    const double d6 = (c - o6).cross(z6).norm();
    if (d45 > tol || d6 > tol)
      throw std::invalid_argument(
          "no closed form: the last three axes do not meet at one point (axes 4-5 " + std::to_string(d45) +
          ", axis 6 " + std::to_string(d6) + " from their meeting point; tolerance " + std::to_string(tol) +
          "); a 6R closed form here needs a spherical wrist");
    SphericalWrist6 wrist{Position3(split_first_three(chain), c, scale)};
    wrist.A4_ = L4.R;
    wrist.B5_ = L5.R;
    wrist.B6_ = L6.R;
    const Rigid<double> tail = chain.z_tail(5) * chain.tool();
    wrist.tail_R_T_ = tail.R.transpose();
    // c in the tool frame: F6^-1 c in frame 6, then Tail^-1
    const Rigid<double> tail_inv = detail::inverse(tail), F6_inv = detail::inverse(F6);
    wrist.c_tool_ = tail_inv.R * (F6_inv.R * c + F6_inv.p) + tail_inv.p;
    return wrist;
  }

  const Position3& position() const noexcept { return position_; }

  // Every solution for a target pose: returns 1 if the position part has any
  // solution; q[slot] = (cos, sin) of the 6 angles, exists[slot] per slot.
  // Slot 2 k + b: position solution k (as Position3 orders them), wrist branch b.
  SPOTKIN_INLINE void solve(const Arm::Pose& target, JointValue q[kSlots][6], bool exists[kSlots]) const noexcept {
    M3 R;
    V3 p;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) R(i, j) = target.R[i][j];
      p[i] = target.p[i];
    }
    for (int k = 0; k < kSlots; ++k) exists[k] = false;
    JointValue arm[Position3::kSlots][3];
    const int n = position_.solve(R * c_tool_ + p, arm);
    // Columns 1 and 3 of R_F6 = R Tail^T: all of W that (A)-(C) need.
    const V3 x_F6 = R * tail_R_T_.col(0), z_F6 = R * tail_R_T_.col(2);
    const Split& S = position_.split();
    const V3 a = B5_.row(2).transpose(), b = B6_.col(2);
    for (int k = 0; k < n; ++k) {
      // W e = A4^T Rz3^T R2^T Rz2^T R1^T Rz1^T R0^T (R_F6 e), vector by vector
      auto to_wrist = [&](V3 x) {
        x = S.M0.R.transpose() * x;
        x = detail::z_rotate(position_.sigma(0), conjugate(arm[k][0]), x);
        x = S.M1.R.transpose() * x;
        x = detail::z_rotate(position_.sigma(1), conjugate(arm[k][1]), x);
        x = S.M2.R.transpose() * x;
        x = detail::z_rotate(position_.sigma(2), conjugate(arm[k][2]), x);
        return V3(A4_.transpose() * x);
      };
      const V3 w = to_wrist(z_F6), wx = to_wrist(x_F6);
      // (A) with sin(alpha) from the Gram determinant written as
      // |w_xy|^2 (1 - b_z^2) - (a_z - b_z w_z)^2, which keeps its accuracy where
      // axes 4 and 6 align (1 - ratio^2 would lose half the digits there).
      JointValue q5[2];
      const double gram = (w[0] * w[0] + w[1] * w[1]) * (1.0 - b[2] * b[2]) - (a[2] - b[2] * w[2]) * (a[2] - b[2] * w[2]);
      const int m = detail::cos_sin_roots(a[0] * b[0] + a[1] * b[1], a[1] * b[0] - a[0] * b[1], w[2] - a[2] * b[2], q5,
                                          std::sqrt(std::max(gram, 0.0)));
      for (int branch = 0; branch < m; ++branch) {
        const int slot = 2 * k + branch;
        const V3 v = B5_ * detail::z_rotate(0, q5[branch], b);
        // (B); q4 free (set to 0) where axes 4 and 6 align
        const JointValue q4 =
            v[0] * v[0] + v[1] * v[1] <= 1e-24 ? joint_zero() : detail::angle_difference(w[0], w[1], v[0], v[1]);
        // (C) first column of Rz(q6) = B6^T Rz5^T B5^T Rz4^T (W e1); unit up to
        // rounding, and only its angle is used
        V3 x = detail::z_rotate(0, conjugate(q4), wx);
        x = B5_.transpose() * x;
        x = detail::z_rotate(0, conjugate(q5[branch]), x);
        x = B6_.transpose() * x;
        const JointValue q6{x[0], x[1], 0.0};
        for (int j = 0; j < 3; ++j) q[slot][j] = arm[k][j];
        q[slot][3] = q4, q[slot][4] = q5[branch], q[slot][5] = q6;
        exists[slot] = true;
      }
    }
  }

  static constexpr int kLanes = Position3::kLanes;

  // solve() for m <= kLanes poses at once (the same equations run across the
  // poses, so that they vectorise; a short block goes pose by pose), finished
  // as finish_lanes does. pose_in[e][i] is element e of pose i, in the layout
  // of Arm::read_pose. Solutions across the lanes: slot k of pose i is
  // angle[k][j][i] for joint j (the value of a prismatic joint; wrapped into
  // the limits, NaN if the slot has no solution), exists[k][i] and
  // valid[k][i] (in the limits too) are 1 or 0, and input_ok[i] is 0 for a
  // pose that is not a rigid transform.
  template <PoseFormat Format>
  SPOTKIN_INLINE void solve_block(const double (*pose_in)[kLanes], int m, const Limits& limits,
                                  double (&angle)[kSlots][6][kLanes], double (&exists)[kSlots][kLanes],
                                  double (&valid)[kSlots][kLanes], double (&input_ok)[kLanes]) const noexcept {
    constexpr int width = Format == PoseFormat::Matrix ? 16 : 7;
    if (m < kLanes) {  // one by one (a short block costs no more than its poses)
      for (int i = 0; i < m; ++i) {
        double in[width];
        for (int e = 0; e < width; ++e) in[e] = pose_in[e][i];
        Arm::Pose target;
        input_ok[i] = Arm::read_pose<Format>(in, target);
        JointValue q[kSlots][6];
        bool ok[kSlots] = {};
        if (input_ok[i] != 0.0) solve(target, q, ok);
        for (int k = 0; k < kSlots; ++k) {
          exists[k][i] = ok[k] ? 1.0 : 0.0;
          for (int j = 0; j < 6; ++j)
            angle[k][j][i] = !ok[k] ? 0.0
                                 : j < 3 && position_.sigma(j) == 1 ? q[k][j].v
                                                                    : vector_math::atan2(q[k][j].s, q[k][j].c);
        }
      }
      finish_lanes<false>(limits, m, input_ok, angle, exists, valid);
      return;
    }
    constexpr int L = kLanes, K = Position3::kSlots;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // wrist centres c = R c_tool + p, and x0, z0 = R0^T R (columns 1 and 3 of Tail^T),
    // the columns 1 and 3 of R_F6 = R Tail^T seen from frame M0
    const Split& S = position_.split();
    double R[3][3][L], p[3][L];
    for (int i = 0; i < L; ++i) {
      double in[width];
      for (int e = 0; e < width; ++e) in[e] = pose_in[e][i];
      Arm::Pose target;
      const double use = Arm::read_pose<Format>(in, target);
      input_ok[i] = use;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R[r][c][i] = use != 0.0 ? target.R[r][c] : nan;
        p[r][i] = use != 0.0 ? target.p[r] : nan;
      }
    }
    const V3 t0 = tail_R_T_.col(0), t2 = tail_R_T_.col(2);
    const M3 M0T = S.M0.R.transpose();
    double cx[L], cy[L], cz[L], x0[3][L], z0[3][L];
    for (int i = 0; i < L; ++i) {
      double Rc[3], Rx[3], Rz[3];
      for (int r = 0; r < 3; ++r) {
        Rc[r] = R[r][0][i] * c_tool_[0] + R[r][1][i] * c_tool_[1] + R[r][2][i] * c_tool_[2] + p[r][i];
        Rx[r] = R[r][0][i] * t0[0] + R[r][1][i] * t0[1] + R[r][2][i] * t0[2];
        Rz[r] = R[r][0][i] * t2[0] + R[r][1][i] * t2[1] + R[r][2][i] * t2[2];
      }
      cx[i] = Rc[0], cy[i] = Rc[1], cz[i] = Rc[2];
      double x[3], z[3];
      detail::multiply(M0T, Rx, x);
      detail::multiply(M0T, Rz, z);
      for (int r = 0; r < 3; ++r) x0[r][i] = x[r], z0[r][i] = z[r];
    }
    Position3::BlockSolutions arm;
    position_.solve_block(cx, cy, cz, m, arm);
    // local copies: the stores to out cannot alias them (so the lane loops vectorise)
    const M3 B5 = B5_, B6 = B6_, A4 = A4_, M1R = S.M1.R, M2R = S.M2.R;
    const V3 a = B5.row(2).transpose(), b = B6.col(2);
    // (A): A c5 + B s5 = w_z - a_z b_z, solved as detail::cos_sin_root does but
    // with hypot(A, B) hoisted out of the lane loop (calling cos_sin_root here
    // stops GCC 12 from vectorising the loop)
    const double A = a[0] * b[0] + a[1] * b[1], B = a[1] * b[0] - a[0] * b[1];
    const double r2 = A * A + B * B, inv = r2 > 0.0 ? 1.0 / std::sqrt(r2) : 1.0, ca = A * inv, sa = B * inv;
    const Limits limit = limits;  // a local copy: the stores below cannot alias it
    const bool prismatic[3] = {position_.sigma(0) == 1, position_.sigma(1) == 1, position_.sigma(2) == 1};
    for (int k = 0; k < K; ++k) {
      // position solution k (cos, sin) = (1, 0) for a prismatic joint) -> slots 2k, 2k + 1
      const int slot0 = 2 * k, slot1 = 2 * k + 1;
      for (int i = 0; i < L; ++i) {
        const double found = k < arm.n[i] ? input_ok[i] : 0.0;
        // q1..q3 wrapped into their limits, once for both slots
        double position_fit = 1.0, position_angle[3];
        for (int j = 0; j < 3; ++j) {
          const double value = prismatic[j] ? arm.v[k][j][i] : vector_math::atan2(arm.s[k][j][i], arm.c[k][j][i]);
          position_angle[j] = limit.wrap_value(j, value, position_fit);
        }
        // W e = A4^T Rz3^T R2^T Rz2^T R1^T Rz1^T (R0^T R_F6 e) for e = z, x
        double w[3] = {z0[0][i], z0[1][i], z0[2][i]}, wx[3] = {x0[0][i], x0[1][i], x0[2][i]};
        auto back = [&](int j, const M3& M) SPOTKIN_INLINE_LAMBDA {
          const double cj = arm.c[k][j][i], sj = arm.s[k][j][i];
          const double u[3] = {cj * w[0] + sj * w[1], -sj * w[0] + cj * w[1], w[2]};
          const double ux[3] = {cj * wx[0] + sj * wx[1], -sj * wx[0] + cj * wx[1], wx[2]};
          detail::multiply_transposed(M, u, w);
          detail::multiply_transposed(M, ux, wx);
        };
        back(0, M1R);
        back(1, M2R);
        back(2, A4);
        // (A), as solve() does, with sin(alpha) from the Gram determinant
        const double gram = (w[0] * w[0] + w[1] * w[1]) * (1.0 - b[2] * b[2]) - (a[2] - b[2] * w[2]) * (a[2] - b[2] * w[2]);
        const double ratio = (w[2] - a[2] * b[2]) * inv, clamped = std::min(1.0, std::max(-1.0, ratio));
        const double h = std::min(1.0, std::sqrt(std::max(gram, 0.0)) * inv);
        // r2 = 0 (axes 4 and 5, or 5 and 6, parallel) is refused when the chain is built
        const double solvable = r2 > 0.0 && std::fabs(ratio) <= 1.0 + Tolerance::ratio ? found : 0.0;
        auto branch = [&](int slot, double sign) SPOTKIN_INLINE_LAMBDA {
          const double hb = sign * h;
          const double c5 = r2 > 0.0 ? ca * clamped - sa * hb : 1.0, s5 = r2 > 0.0 ? sa * clamped + ca * hb : 0.0;
          // (B) v = B5 Rz(q5) b; q4 free (0) where axes 4 and 6 align
          const double rb[3] = {c5 * b[0] - s5 * b[1], s5 * b[0] + c5 * b[1], b[2]};
          double v[3];
          detail::multiply(B5, rb, v);
          const bool aligned = v[0] * v[0] + v[1] * v[1] <= 1e-24;
          const JointValue q4 = detail::angle_difference_lane(w[0], w[1], v[0], v[1]);
          const double c4 = aligned ? 1.0 : q4.c, s4 = aligned ? 0.0 : q4.s;
          // (C) first column of Rz(q6) = B6^T Rz5^T B5^T Rz4^T (W e1)
          const double y[3] = {c4 * wx[0] + s4 * wx[1], -s4 * wx[0] + c4 * wx[1], wx[2]};
          double z[3], x6[3];
          detail::multiply_transposed(B5, y, z);
          const double t[3] = {c5 * z[0] + s5 * z[1], -s5 * z[0] + c5 * z[1], z[2]};
          detail::multiply_transposed(B6, t, x6);
          const double wrist[3] = {vector_math::atan2(s4, c4), vector_math::atan2(s5, c5),
                                   vector_math::atan2(x6[1], x6[0])};
          double fit = solvable * position_fit;
          for (int j = 0; j < 3; ++j) {
            const double wrapped = limit.wrap_value(3 + j, wrist[j], fit);
            angle[slot][j][i] = solvable != 0.0 ? position_angle[j] : nan;
            angle[slot][3 + j][i] = solvable != 0.0 ? wrapped : nan;
          }
          exists[slot][i] = solvable, valid[slot][i] = fit;
        };
        branch(slot0, 1.0);
        branch(slot1, -1.0);
      }
    }
  }

 private:
  static JointValue conjugate(const JointValue& q) noexcept { return JointValue{q.c, -q.s, -q.v}; }

  explicit SphericalWrist6(Position3 position) : position_(std::move(position)) {}

  Position3 position_;
  M3 A4_, B5_, B6_, tail_R_T_;
  V3 c_tool_;
};

// -- batches ------------------------------------------------------------------

// The finished lanes of one block: angle[k][j][i] (NaN where slot k has no
// solution), valid and exists (1 or 0), status (a Status).
template <int Slots, int Dof, int L>
struct FinishedBlock {
  static constexpr int S = Slots;
  double angle[Slots][Dof][L], exists[Slots][L], valid[Slots][L], status[L], input_ok[L];
};

// Writes lane i of a finished block as one sample: q (Slots, Dof), valid and
// exists (Slots), status.
template <int Slots, int Dof, int L, typename T>
SPOTKIN_INLINE void store_lane(const FinishedBlock<Slots, Dof, L>& block, int i, T* q, std::uint8_t* valid,
                               std::uint8_t* exists, std::int8_t* status) noexcept {
  const double* angles = &block.angle[0][0][0];
  for (int k = 0; k < Slots * Dof; ++k) q[k] = T(angles[k * L + i]);
  for (int k = 0; k < Slots; ++k) valid[k] = block.valid[k][i] != 0.0, exists[k] = block.exists[k][i] != 0.0;
  *status = static_cast<std::int8_t>(block.status[i]);
}

// The solves of one block (up to 16 samples), finished in the lanes, compiled
// once per CPU level with the solvers inlined (double only: the I/O type is
// handled outside).
using PositionBlock = FinishedBlock<Position3::kSlots, 3, Position3::kLanes>;

__attribute__((flatten)) SPOTKIN_VECTOR_KERNEL inline void position_block(const Position3& solver,
                                                                          const Limits& limits, const double* px,
                                                                          const double* py, const double* pz, int m,
                                                                          PositionBlock& out) noexcept {
  constexpr int S = PositionBlock::S, L = Position3::kLanes;
  Position3::BlockSolutions sol;
  solver.solve_block(px, py, pz, m, sol);
  for (int i = 0; i < L; ++i)
    out.input_ok[i] = std::isfinite(px[i]) && std::isfinite(py[i]) && std::isfinite(pz[i]) ? 1.0 : 0.0;
  auto finish = [&](auto full) SPOTKIN_INLINE_LAMBDA {
    const int lanes = decltype(full)::value ? L : m;
    for (int k = 0; k < S; ++k) {
      for (int i = 0; i < lanes; ++i) out.exists[k][i] = k < sol.n[i] ? 1.0 : 0.0;
      for (int j = 0; j < 3; ++j) {
        const bool prismatic = solver.sigma(j) == 1;
        for (int i = 0; i < lanes; ++i)
          out.angle[k][j][i] = prismatic ? sol.v[k][j][i] : vector_math::atan2(sol.s[k][j][i], sol.c[k][j][i]);
      }
    }
    finish_lanes<decltype(full)::value>(limits, m, out.input_ok, out.angle, out.exists, out.valid);
  };
  if (m == L)
    finish(std::true_type{});
  else
    finish(std::false_type{});
  lane_status(m, out.input_ok, out.exists, out.valid, out.status);
}

using WristBlock = FinishedBlock<SphericalWrist6::kSlots, 6, SphericalWrist6::kLanes>;

template <PoseFormat Format>
__attribute__((flatten)) SPOTKIN_VECTOR_KERNEL void wrist_block(const SphericalWrist6& solver, const Limits& limits,
                                                                const double (*pose_in)[SphericalWrist6::kLanes],
                                                                int m, WristBlock& out) noexcept {
  solver.solve_block<Format>(pose_in, m, limits, out.angle, out.exists, out.valid, out.input_ok);
  lane_status(m, out.input_ok, out.exists, out.valid, out.status);
}

// Lane i of a finished block as one answer: the valid slot nearest to the
// seed (the largest single-joint move: on the circle for a revolute joint,
// plain for a prismatic one; ties to the lower slot), or the lowest valid slot
// without a seed (seed null). q (Dof) is NaN unless the status is OK; a seed
// with NaN or Inf gives INVALID_INPUT.
template <int Slots, int Dof, int L, typename T>
SPOTKIN_INLINE void store_nearest(const FinishedBlock<Slots, Dof, L>& block, int i, const Limits& limits,
                                  const T* seed, T* q, std::int8_t* status) noexcept {
  constexpr double two_pi = 2.0 * kPi<double>, inv_two_pi = 1.0 / two_pi;
  bool seed_ok = true;
  double seed_value[Dof] = {};
  for (int j = 0; seed && j < Dof; ++j) {
    seed_value[j] = double(seed[j]), seed_ok &= std::isfinite(seed_value[j]);
    if (limits.sigma[j] == 0) seed_value[j] = wrap_angle(seed_value[j]);  // any magnitude, exactly
  }
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < Slots; ++k) {
    if (block.valid[k][i] == 0.0) continue;
    if (!seed) {
      best = k;
      break;
    }
    double distance = 0.0;
    for (int j = 0; j < Dof; ++j) {
      // |move| <= 4 pi here (angles within 2 pi of (-pi, pi], the seed in it): one rounding wraps it
      const double move = block.angle[k][j][i] - seed_value[j];
      distance = std::max(distance, std::fabs(limits.sigma[j] == 0 ? move - two_pi * std::round(move * inv_two_pi) : move));
    }
    if (distance < best_distance) best = k, best_distance = distance;  // strict: ties keep the lower slot
  }
  const auto st = seed_ok ? static_cast<std::int8_t>(block.status[i]) : static_cast<std::int8_t>(Status::InvalidInput);
  const bool ok = st == static_cast<std::int8_t>(Status::Ok) && best >= 0;
  for (int j = 0; j < Dof; ++j) q[j] = ok ? T(block.angle[best][j][i]) : quiet_nan<T>();
  *status = st;
}

// Position IK for count targets p (count, 3), block by block: store(block,
// i, n) writes lane i of a finished PositionBlock as answer n.
template <typename T, typename Store>
SPOTKIN_INLINE void position_blocks(const Position3& solver, const Limits& limits, const T* points,
                                    std::ptrdiff_t count, Store&& store) noexcept {
  constexpr int L = Position3::kLanes;
  PositionBlock block;
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, count - b0));
    double px[L], py[L], pz[L];
    for (int i = 0; i < L; ++i) {
      const T* point = points + 3 * (b0 + std::min(i, m - 1));
      px[i] = double(point[0]), py[i] = double(point[1]), pz[i] = double(point[2]);
    }
    position_block(solver, limits, px, py, pz, m, block);
    for (int i = 0; i < m; ++i) store(block, i, b0 + i);
  }
}

// 6R IK for count poses ((count, 16) matrices or (count, 7) position +
// quaternion), block by block, as position_blocks.
template <PoseFormat Format, typename T, typename Store>
SPOTKIN_INLINE void wrist_blocks(const SphericalWrist6& solver, const Limits& limits, const T* poses,
                                 std::ptrdiff_t count, Store&& store) noexcept {
  constexpr int L = SphericalWrist6::kLanes, width = Format == PoseFormat::Matrix ? 16 : 7;
  WristBlock block;
  double pose_in[width][L];  // the poses as structure of arrays
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, count - b0));
    for (int i = 0; i < m; ++i)
      for (int e = 0; e < width; ++e) pose_in[e][i] = double(poses[width * (b0 + i) + e]);
    wrist_block<Format>(solver, limits, pose_in, m, block);
    for (int i = 0; i < m; ++i) store(block, i, b0 + i);
  }
}

// Every solution: q (count, 4, 3), valid and exists (count, 4), status (count).
template <typename T>
SPOTKIN_INLINE void ik_position(const Position3& solver, const Limits& limits, const T* points, T* q,
                                std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                                std::ptrdiff_t count) noexcept {
  constexpr int S = PositionBlock::S, W = S * 3;
  position_blocks(solver, limits, points, count, [&](const PositionBlock& block, int i, std::ptrdiff_t at) {
    store_lane(block, i, q + W * at, valid + S * at, exists + S * at, status + at);
  });
}

// Every solution: q (count, 8, 6), valid and exists (count, 8), status (count).
template <PoseFormat Format, typename T>
SPOTKIN_INLINE void ik_wrist(const SphericalWrist6& solver, const Limits& limits, const T* poses, T* q,
                             std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                             std::ptrdiff_t count) noexcept {
  constexpr int S = WristBlock::S, W = S * 6;
  wrist_blocks<Format>(solver, limits, poses, count, [&](const WristBlock& block, int i, std::ptrdiff_t at) {
    store_lane(block, i, q + W * at, valid + S * at, exists + S * at, status + at);
  });
}

// One solution per target (store_nearest): q (count, 3), status (count);
// seed (count, 3) or null.
template <typename T>
SPOTKIN_INLINE void ik_position_nearest(const Position3& solver, const Limits& limits, const T* points,
                                        const T* seed, T* q, std::int8_t* status, std::ptrdiff_t count) noexcept {
  position_blocks(solver, limits, points, count, [&](const PositionBlock& block, int i, std::ptrdiff_t at) {
    store_nearest(block, i, limits, seed ? seed + 3 * at : nullptr, q + 3 * at, status + at);
  });
}

// One solution per pose (store_nearest): q (count, 6), status (count); seed
// (count, 6) or null.
template <PoseFormat Format, typename T>
SPOTKIN_INLINE void ik_wrist_nearest(const SphericalWrist6& solver, const Limits& limits, const T* poses,
                                     const T* seed, T* q, std::int8_t* status, std::ptrdiff_t count) noexcept {
  wrist_blocks<Format>(solver, limits, poses, count, [&](const WristBlock& block, int i, std::ptrdiff_t at) {
    store_nearest(block, i, limits, seed ? seed + 6 * at : nullptr, q + 6 * at, status + at);
  });
}

}  // namespace spotkin::chain_ik
