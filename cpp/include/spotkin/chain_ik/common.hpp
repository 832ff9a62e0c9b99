// Closed-form chain IK, shared pieces: tolerances, joint values (cos, sin), the
// polynomial and trigonometric helpers, the split of a chain's first three joints,
// joint limits and the lane finishing of a block. See spotkin/chain_ik.hpp.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "spotkin/arm.hpp"
#include "spotkin/chain.hpp"
#include "spotkin/common.hpp"
#include "spotkin/dense.hpp"
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
    fit = (in | in_below | in_above) ? fit : 0.0;
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

}  // namespace spotkin::chain_ik
