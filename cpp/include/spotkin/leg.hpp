// Roll-pitch-pitch leg (Spot's hx, hy, kn): FK, Jacobian and closed-form IK
// with every branch. Derivation (seed 000 Q2.1, re-derived; see
// python/spotkin/reference/leg.py for the same equations written plainly):
//
//   (M1) p = Rx(hx) ( [0, h1, 0] + Ry(hy) ( [k, 0, -U] + Ry(kn) [0, 0, -L] ) )
//   (I1) hip roll, Paul type 2:  y cos hx + z sin hx = h1.  With r^2 = y^2 + z^2,
//        S = sqrt(r^2 - h1^2) and eps = +1 (branch 0, foot under the hip) or -1:
//          cos hx = (y h1 - eps z S) / r^2,   sin hx = (z h1 + eps y S) / r^2
//        (the annex's type-2 formulas; no solution when r < |h1|).
//   (I2) the foot in the hip-pitch plane: x' = x, z' = -sin hx y + cos hx z = -eps S.
//   (I3) knee, type 2: U cos kn - k sin kn = Zk, Zk = (x^2 + S^2 - k^2 - U^2 - L^2) / (2L),
//        i.e. R cos(kn + beta) = Zk, R = hypot(U, k), beta = atan2(k, U):
//          kn = -beta - mu acos(Zk / R),  mu = +1 (branch 0, knee back) or -1.
//   (I4) hip pitch: Ry(hy) multiplies z + i x by e^{i hy}, so with
//        w = (k - L sin kn, -U - L cos kn):  hy = arg((z' + i x') (w_z - i w_x)).
//
// Slot order: slot = 2 * hip_branch + knee_branch:
//   0 (hip normal, knee back), 1 (normal, knee forward), 2 (flipped, back), 3 (flipped, forward).
// Either all four slots exist or none does: both conditions depend on p only.
#pragma once

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin {

// Joint limits and the branch choice shared by the leg and arm solvers.
template <int N>
struct JointLimits {
  double lower[N], upper[N];

  JointLimits() {
    for (int j = 0; j < N; ++j) {
      lower[j] = -std::numeric_limits<double>::infinity();
      upper[j] = std::numeric_limits<double>::infinity();
    }
  }

  static constexpr double kTolerance = 1e-12;  // rad

  // Wraps each joint by 0, -2pi or +2pi (the first that fits) into the limits,
  // in place, and returns 1.0 if every joint fits, 0.0 otherwise (joints that
  // fit no way are left as given). Branch-free, for vectorised loops.
  SPOTKIN_INLINE double wrap_mask(double* q) const noexcept {
    constexpr double two_pi = 2.0 * kPi<double>;
    double all = 1.0;
#pragma GCC unroll 8
    for (int j = 0; j < N; ++j) {
      const double lo = lower[j] - kTolerance, hi = upper[j] + kTolerance;
      const double v = q[j], minus = v - two_pi, plus = v + two_pi;
      const bool in0 = (v >= lo) & (v <= hi);
      const bool in_minus = (minus >= lo) & (minus <= hi);
      const bool in_plus = (plus >= lo) & (plus <= hi);
      q[j] = in0 ? v : (in_minus ? minus : (in_plus ? plus : v));
      all = (in0 | in_minus | in_plus) ? all : 0.0;
    }
    return all;
  }

  // Each joint wrapped into its limits as wrap_mask does, or, where no 2 pi
  // shift fits, set to the bound nearest on the circle: always in the limits.
  void clamp_into(double* q) const noexcept {
    wrap_mask(q);
    for (int j = 0; j < N; ++j) {
      if (q[j] >= lower[j] - kTolerance && q[j] <= upper[j] + kTolerance) continue;
      const double to_lower = std::fabs(wrap_angle(q[j] - lower[j])), to_upper = std::fabs(wrap_angle(q[j] - upper[j]));
      q[j] = to_lower <= to_upper ? lower[j] : upper[j];
    }
  }
};

// Largest single-joint move between a and b, measured on the circle.
template <int N>
SPOTKIN_INLINE double circle_distance(const double* a, const double* b) noexcept {
  double worst = 0.0;
  for (int j = 0; j < N; ++j) worst = std::max(worst, std::fabs(wrap_angle(a[j] - b[j])));
  return worst;
}

struct LegGeometry {
  double hip_offset = 0.110945;  // h1: signed, + for left legs
  double upper = 0.3205;         // U
  double lower = 0.3365;         // L
  double knee_offset = 0.025;    // k: forward offset of the knee from the hy joint
};

class Leg {
 public:
  static constexpr int kSlots = 4;
  // |ratio| <= 1 + tol counts as touching a singular set (so targets placed
  // exactly on it, after rounding, still have their merged solution). float32
  // targets carry ~6e-8 relative rounding, so they get a wider tolerance.
  static constexpr double kRatioTolerance = 1e-12;
  static constexpr double kRatioToleranceFloat = 1e-6;
  template <typename T>
  static constexpr double ratio_tolerance() noexcept {
    return sizeof(T) < sizeof(double) ? kRatioToleranceFloat : kRatioTolerance;
  }

  Leg() { update(); }
  Leg(const LegGeometry& g, const JointLimits<3>& limits) : g_(g), limits_(limits) { update(); }

  const LegGeometry& geometry() const noexcept { return g_; }
  const JointLimits<3>& limits() const noexcept { return limits_; }
  double max_reach() const noexcept { return d_max_; }  // |w| max = R + L
  double min_reach() const noexcept { return d_min_; }  // |w| min = |R - L|

  // (M1), expanded with X, Zs the forward and downward sagittal coordinates.
  template <typename T>
  SPOTKIN_INLINE void forward(const T* q, T* p) const noexcept {
    double s1, c1, s2, c2, s23, c23;
    const double hx = double(q[0]), hy = double(q[1]), hk = double(q[1]) + double(q[2]);
    vector_math::sincos(&hx, &s1, &c1, 1);
    vector_math::sincos(&hy, &s2, &c2, 1);
    vector_math::sincos(&hk, &s23, &c23, 1);
    const double X = g_.knee_offset * c2 - g_.upper * s2 - g_.lower * s23;
    const double Zs = -g_.knee_offset * s2 - g_.upper * c2 - g_.lower * c23;
    p[0] = T(X);
    p[1] = T(g_.hip_offset * c1 - Zs * s1);
    p[2] = T(g_.hip_offset * s1 + Zs * c1);
  }

  // d p / d q (row-major 3x3): columns (0, -p_z, p_y), (Zs, X s1, -X c1),
  // (-L c23, -L s23 s1, L s23 c1).
  template <typename T>
  SPOTKIN_INLINE void jacobian(const T* q, T* J) const noexcept {
    double s1, c1, s2, c2, s23, c23;
    const double hx = double(q[0]), hy = double(q[1]), hk = double(q[1]) + double(q[2]);
    vector_math::sincos(&hx, &s1, &c1, 1);
    vector_math::sincos(&hy, &s2, &c2, 1);
    vector_math::sincos(&hk, &s23, &c23, 1);
    const double X = g_.knee_offset * c2 - g_.upper * s2 - g_.lower * s23;
    const double Zs = -g_.knee_offset * s2 - g_.upper * c2 - g_.lower * c23;
    const double py = g_.hip_offset * c1 - Zs * s1, pz = g_.hip_offset * s1 + Zs * c1;
    const double L = g_.lower;
    J[0] = T(0.0), J[1] = T(Zs), J[2] = T(-L * c23);
    J[3] = T(-pz), J[4] = T(X * s1), J[5] = T(-L * s23 * s1);
    J[6] = T(py), J[7] = T(-X * c1), J[8] = T(L * s23 * c1);
  }

  // |det J| and the smallest singular value of J.
  template <typename T>
  void singularity(const T* q, T* abs_det, T* sigma_min) const noexcept {
    T Jt[9];
    jacobian(q, Jt);
    Eigen::Matrix3d J;
    for (int i = 0; i < 9; ++i) J(i / 3, i % 3) = double(Jt[i]);
    if (!J.allFinite()) {  // Eigen's SVD of NaN is unspecified (it read stale values)
      *abs_det = *sigma_min = T(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    *abs_det = T(std::fabs(J.determinant()));
    *sigma_min = T(Eigen::JacobiSVD<Eigen::Matrix3d>(J).singularValues()[2]);
  }

  // All four branches of (I1)-(I4) for one target, angles in (-pi, pi].
  // Returns whether they exist; when `force`, ratios are clamped into [-1, 1]
  // whatever their size (used for the nearest-reachable fallback).
  SPOTKIN_INLINE bool solve_all(double x, double y, double z, double q[kSlots][3], bool force = false,
                                double tol = kRatioTolerance) const noexcept {
    return solve_all_mask(x, y, z, q, tol) != 0.0 || force;
  }

  // As solve_all, returning 1.0 where the branches exist and 0.0 elsewhere: a
  // form the compiler vectorises over samples.
  SPOTKIN_INLINE double solve_all_mask(double x, double y, double z, double q[kSlots][3],
                                       double tol = kRatioTolerance) const noexcept {
    const Hip hip = solve_hip(y, z, tol);
    const Knee knee = solve_knee(x, hip.S, tol);
#pragma GCC unroll 2
    for (int hb = 0; hb < 2; ++hb) {
      const double eps = hb == 0 ? 1.0 : -1.0;
      const double hx_safe = hip_roll(y, z, hip, eps);
#pragma GCC unroll 2
      for (int kb = 0; kb < 2; ++kb) {
        double* slot = q[2 * hb + kb];
        slot[0] = hx_safe;
        slot[1] = hip_pitch(x, -eps * hip.S, knee, kb);
        slot[2] = knee_angle(knee, kb);
      }
    }
    return hip.exists * knee.exists;
  }

  // Slot 0 only (hip normal, knee back): the walking controller's branch.
  SPOTKIN_INLINE double solve_slot0(double x, double y, double z, double q[3],
                                    double tol = kRatioTolerance) const noexcept {
    const Hip hip = solve_hip(y, z, tol);
    const Knee knee = solve_knee(x, hip.S, tol);
    q[0] = hip_roll(y, z, hip, 1.0);
    q[1] = hip_pitch(x, -hip.S, knee, 0);
    q[2] = knee_angle(knee, 0);
    return hip.exists * knee.exists;
  }

  // The point of the reachable set (limits aside) nearest to an unreachable p:
  // the radial projection onto the shell h1^2 + Dmin^2 <= |p|^2 <= h1^2 + Dmax^2,
  // then, if that falls inside the hip-roll cylinder y^2 + z^2 < h1^2, onto the
  // cylinder (y, z scaled to |h1|, x clamped into the shell). within_limits:
  // the shell of the distances D the knee reaches inside its limits instead
  // (D^2 = R^2 + L^2 + 2 L R cos(kn + beta), eq. (I3)).
  SPOTKIN_INLINE void nearest_reachable(const double* p, double* out, bool within_limits = false) const noexcept {
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
      out[0] = out[1] = out[2] = quiet_nan<double>();
      return;
    }
    const double h1sq = h1_ * h1_;
    const double norm = std::hypot(p[0], std::hypot(p[1], p[2]));  // no overflow for |p| near 1e308
    const double d_min = within_limits ? d_knee_min_ : d_min_, d_max = within_limits ? d_knee_max_ : d_max_;
    const double rho_max = std::sqrt(h1sq + d_max * d_max), rho_min = std::sqrt(h1sq + d_min * d_min);
    double q[3] = {p[0], p[1], p[2]};
    if (norm == 0.0) {
      q[0] = 0.0, q[1] = h1_, q[2] = -d_min;
    } else {
      const double scale = std::clamp(norm, rho_min, rho_max) / norm;
      for (double& v : q) v *= scale;
    }
    const double r2 = q[1] * q[1] + q[2] * q[2];
    if (r2 < h1sq) {
      const double r = std::sqrt(r2);
      if (r > 0.0) {
        q[1] *= std::fabs(h1_) / r, q[2] *= std::fabs(h1_) / r;
      } else {
        q[1] = h1_, q[2] = 0.0;
      }
      const double ax = std::clamp(std::fabs(q[0]), d_min, d_max);
      q[0] = std::copysign(ax, q[0]);
    }
    out[0] = q[0], out[1] = q[1], out[2] = q[2];
  }

 private:
  // `exists` is 1.0 or 0.0 (a double, so that the solve loops vectorise).
  struct Hip {
    double r2, S, exists;
  };
  struct Knee {
    double cos_psi, sin_psi, acos_psi, exists;  // psi = kn + beta, knee branch 0: psi = -acos
  };

  SPOTKIN_INLINE Hip solve_hip(double y, double z, double tol) const noexcept {
    Hip h;
    h.r2 = y * y + z * z;
    const double disc = h.r2 - h1_ * h1_;
    h.exists = disc >= -tol * 2.0 * h1_ * h1_ ? 1.0 : 0.0;  // (h1/r)^2 <= 1 + 2 tol
    h.S = std::sqrt(std::max(disc, 0.0));
    return h;
  }

  SPOTKIN_INLINE Knee solve_knee(double x, double S, double tol) const noexcept {
    Knee k;
    const double ratio = (x * x + S * S - knee_sum_sq_) * inv_2LR_;
    k.exists = std::fabs(ratio) <= 1.0 + tol ? 1.0 : 0.0;
    k.cos_psi = std::clamp(ratio, -1.0, 1.0);
    k.sin_psi = std::sqrt((1.0 - k.cos_psi) * (1.0 + k.cos_psi));
    k.acos_psi = vector_math::atan2(k.sin_psi, k.cos_psi);
    return k;
  }

  // (I1): hx for hip branch eps; atan2 is scale-invariant, so the cos/sin are
  // used without their common 1 / r^2. hx = 0 when r = 0 (every hx works).
  SPOTKIN_INLINE double hip_roll(double y, double z, const Hip& hip, double eps) const noexcept {
    const double hx = vector_math::atan2(z * h1_ + eps * y * hip.S, y * h1_ - eps * z * hip.S);
    return hip.r2 > 0.0 ? hx : 0.0;
  }

  SPOTKIN_INLINE double knee_angle(const Knee& k, int kb) const noexcept {
    const double kn = kb == 0 ? -beta_ - k.acos_psi : -beta_ + k.acos_psi;
    const double wrapped = kn <= -kPi<double> ? kn + 2.0 * kPi<double> : kn;  // kn in (-2pi, 2pi)
    return wrapped > kPi<double> ? wrapped - 2.0 * kPi<double> : wrapped;
  }

  // (I4) with sin/cos of kn from psi = kn + beta: kn = psi - beta.
  SPOTKIN_INLINE double hip_pitch(double x, double z_prime, const Knee& k, int kb) const noexcept {
    const double sin_psi = kb == 0 ? -k.sin_psi : k.sin_psi;
    const double sin_kn = sin_psi * cos_beta_ - k.cos_psi * sin_beta_;
    const double cos_kn = k.cos_psi * cos_beta_ + sin_psi * sin_beta_;
    const double wx = g_.knee_offset - g_.lower * sin_kn, wz = -g_.upper - g_.lower * cos_kn;
    return vector_math::atan2(x * wz - z_prime * wx, z_prime * wz + x * wx);
  }

  void update() noexcept {
    h1_ = g_.hip_offset;
    const double R = std::hypot(g_.upper, g_.knee_offset);
    beta_ = std::atan2(g_.knee_offset, g_.upper);
    cos_beta_ = g_.upper / R;
    sin_beta_ = g_.knee_offset / R;
    knee_sum_sq_ = g_.knee_offset * g_.knee_offset + g_.upper * g_.upper + g_.lower * g_.lower;
    inv_2LR_ = 1.0 / (2.0 * g_.lower * R);
    d_max_ = R + g_.lower;
    d_min_ = std::fabs(R - g_.lower);
    // cos(psi) over the knee's limits, psi = kn + beta in [lo, hi]: 1 (or -1) if
    // the interval holds a multiple of 2 pi (or pi plus one), else its ends'
    const double lo = limits_.lower[2] + beta_, hi = limits_.upper[2] + beta_, two_pi = 2.0 * kPi<double>;
    double cos_max = 1.0, cos_min = -1.0;
    if (std::isfinite(lo) && std::isfinite(hi) && hi - lo < two_pi) {
      const bool has_zero = std::floor(hi / two_pi) * two_pi >= lo;
      const bool has_pi = std::floor((hi - kPi<double>) / two_pi) * two_pi + kPi<double> >= lo;
      cos_max = has_zero ? 1.0 : std::max(std::cos(lo), std::cos(hi));
      cos_min = has_pi ? -1.0 : std::min(std::cos(lo), std::cos(hi));
    }
    const double sum_sq = R * R + g_.lower * g_.lower, twice_LR = 2.0 * g_.lower * R;
    d_knee_max_ = std::sqrt(std::max(0.0, sum_sq + twice_LR * cos_max));
    d_knee_min_ = std::sqrt(std::max(0.0, sum_sq + twice_LR * cos_min));
  }

  LegGeometry g_;
  JointLimits<3> limits_;
  double h1_ = 0, beta_ = 0, cos_beta_ = 1, sin_beta_ = 0, knee_sum_sq_ = 0, inv_2LR_ = 0;
  double d_max_ = 0, d_min_ = 0, d_knee_max_ = 0, d_knee_min_ = 0;  // reach; with the knee in its limits
};

// Batched leg kernels over `count` targets (row-major (count, 3) inputs).
// Each block first solves every target with branch-free vector code, then
// picks branches, applies limits and statuses per target.
namespace leg_batch {

constexpr std::ptrdiff_t kBlock = 64;

template <typename T>
SPOTKIN_INLINE bool finite3(const T* v) noexcept {
  return std::isfinite(double(v[0])) && std::isfinite(double(v[1])) && std::isfinite(double(v[2]));
}

// Chooses among the four slots of one target. Writes q (limit-wrapped) and
// returns the status; sets valid[] when given.
template <typename T>
SPOTKIN_INLINE Status choose(const Leg& leg, double q_all[Leg::kSlots][3], bool exists,
                             const T* seed, T* q_out, std::uint8_t* valid_out) noexcept {
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  double seed_d[3] = {0, 0, 0};
  if (seed) seed_d[0] = double(seed[0]), seed_d[1] = double(seed[1]), seed_d[2] = double(seed[2]);
  for (int s = 0; s < Leg::kSlots; ++s) {
    const bool ok = exists && leg.limits().wrap_mask(q_all[s]) != 0.0;
    if (valid_out) valid_out[s] = ok;
    if (!ok) continue;
    if (!seed) {
      if (best < 0) best = s;
      continue;
    }
    const double d = circle_distance<3>(q_all[s], seed_d);
    if (d < best_distance) best = s, best_distance = d;
  }
  if (best >= 0) {
    for (int j = 0; j < 3; ++j) q_out[j] = T(q_all[best][j]);
    return Status::Ok;
  }
  for (int j = 0; j < 3; ++j) q_out[j] = T(quiet_nan<double>());
  return exists ? Status::JointLimit : Status::Unreachable;
}

// The documented UNREACHABLE answer, always inside the limits: the branches
// for the point nearest to p that the knee reaches inside its limits
// (nearest_reachable within_limits); the first slot inside all the limits,
// else slot 0 with each joint brought into its limits (clamp_into).
template <typename T>
SPOTKIN_INLINE void unreachable_fallback(const Leg& leg, double x, double y, double z, T* q_out) noexcept {
  const double p[3] = {x, y, z};
  double nearest[3], q_all[Leg::kSlots][3];
  leg.nearest_reachable(p, nearest, /*within_limits=*/true);
  leg.solve_all(nearest[0], nearest[1], nearest[2], q_all, /*force=*/true);
  int chosen = -1;
  for (int k = 0; k < Leg::kSlots && chosen < 0; ++k)
    if (leg.limits().wrap_mask(q_all[k]) != 0.0) chosen = k;
  if (chosen < 0) leg.limits().clamp_into(q_all[chosen = 0]);
  for (int j = 0; j < 3; ++j) q_out[j] = T(q_all[chosen][j]);
}

// 1.0 where x, y, z are all finite; vectorisable (x - x is NaN for NaN and Inf).
SPOTKIN_INLINE double finite_mask(double x, double y, double z) noexcept {
  return ((x - x) == 0.0) & ((y - y) == 0.0) & ((z - z) == 0.0) ? 1.0 : 0.0;
}

// Limit-aware IK: q (count, 3), status (count). seed may be null. An
// UNREACHABLE target gets unreachable_fallback's answer, or NaN when
// !nearest_fallback.
template <typename T>
SPOTKIN_INLINE void ik(const Leg& leg, const T* p, const T* seed, T* q, std::int8_t* status,
                       std::ptrdiff_t count, bool nearest_fallback = true) noexcept {
  double x[kBlock], y[kBlock], z[kBlock], hx[kBlock], hy[kBlock], kn[kBlock], exists[kBlock], ok[kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      x[i] = double(p[3 * (b0 + i)]), y[i] = double(p[3 * (b0 + i) + 1]), z[i] = double(p[3 * (b0 + i) + 2]);
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // vectorised: slot 0 and its limits for every target
      double q0[3];
      const double finite = finite_mask(x[i], y[i], z[i]);
      exists[i] = finite * leg.solve_slot0(x[i], y[i], z[i], q0, Leg::ratio_tolerance<T>());
      ok[i] = exists[i] * leg.limits().wrap_mask(q0);
      exists[i] = finite == 0.0 ? -1.0 : exists[i];  // -1: invalid input
      hx[i] = q0[0], hy[i] = q0[1], kn[i] = q0[2];
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const std::ptrdiff_t t = b0 + i;
      T* qt = q + 3 * t;
      const T* st = seed ? seed + 3 * t : nullptr;
      if (ok[i] != 0.0 && !st) {  // the common case: slot 0 valid, no seed
        qt[0] = T(hx[i]), qt[1] = T(hy[i]), qt[2] = T(kn[i]);
        status[t] = std::int8_t(Status::Ok);
        continue;
      }
      if (exists[i] < 0.0 || (st && !finite3(st))) {
        qt[0] = qt[1] = qt[2] = T(quiet_nan<double>());
        status[t] = std::int8_t(Status::InvalidInput);
        continue;
      }
      if (exists[i] == 0.0) {
        if (nearest_fallback)
          unreachable_fallback(leg, x[i], y[i], z[i], qt);
        else
          qt[0] = qt[1] = qt[2] = T(quiet_nan<double>());
        status[t] = std::int8_t(Status::Unreachable);
        continue;
      }
      double q_all[Leg::kSlots][3];
      leg.solve_all(x[i], y[i], z[i], q_all, true);
      status[t] = std::int8_t(choose(leg, q_all, true, st, qt, nullptr));
    }
  }
}

// Every branch: q (count, 4, 3), valid and exists (count, 4), status (count).
template <typename T>
SPOTKIN_INLINE void ik_all(const Leg& leg, const T* p, T* q, std::uint8_t* valid, std::uint8_t* exists,
                           std::int8_t* status, std::ptrdiff_t count) noexcept {
  constexpr double nan = quiet_nan<double>();
  double x[kBlock], y[kBlock], z[kBlock], qs[Leg::kSlots][3][kBlock], ok[Leg::kSlots][kBlock];
  double ex[kBlock], finite[kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      x[i] = double(p[3 * (b0 + i)]), y[i] = double(p[3 * (b0 + i) + 1]), z[i] = double(p[3 * (b0 + i) + 2]);
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // vectorised: all slots for every target
      double q_all[Leg::kSlots][3];
      finite[i] = finite_mask(x[i], y[i], z[i]);
      ex[i] = finite[i] * leg.solve_all_mask(x[i], y[i], z[i], q_all, Leg::ratio_tolerance<T>());
#pragma GCC unroll 4
      for (int s = 0; s < Leg::kSlots; ++s)
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) qs[s][j][i] = q_all[s][j];
    }
#pragma GCC unroll 4
    for (int s = 0; s < Leg::kSlots; ++s) {
      for (std::ptrdiff_t i = 0; i < m; ++i) {  // vectorised: limits per slot
        double qi[3] = {qs[s][0][i], qs[s][1][i], qs[s][2][i]};
        ok[s][i] = ex[i] * leg.limits().wrap_mask(qi);
        for (int j = 0; j < 3; ++j) qs[s][j][i] = ex[i] != 0.0 ? qi[j] : nan;
      }
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const std::ptrdiff_t t = b0 + i;
      T* qt = q + 12 * t;
      bool any_valid = false;
      for (int s = 0; s < Leg::kSlots; ++s) {
        for (int j = 0; j < 3; ++j) qt[3 * s + j] = T(qs[s][j][i]);
        valid[4 * t + s] = ok[s][i] != 0.0;
        exists[4 * t + s] = ex[i] != 0.0;
        any_valid |= ok[s][i] != 0.0;
      }
      const Status st = finite[i] == 0.0 ? Status::InvalidInput
                        : any_valid     ? Status::Ok
                        : ex[i] != 0.0  ? Status::JointLimit
                                        : Status::Unreachable;
      status[t] = std::int8_t(st);
    }
  }
}

// Sines and cosines of hx, hy and hy + kn for a block, vectorised.
struct BlockAngles {
  double angle[3][kBlock], s[3][kBlock], c[3][kBlock];
};

template <typename T>
SPOTKIN_INLINE void block_angles(const T* q, std::ptrdiff_t m, BlockAngles& a) noexcept {
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    a.angle[0][i] = double(q[3 * i]);
    a.angle[1][i] = double(q[3 * i + 1]);
    a.angle[2][i] = double(q[3 * i + 1]) + double(q[3 * i + 2]);
  }
  for (int j = 0; j < 3; ++j) vector_math::sincos(a.angle[j], a.s[j], a.c[j], m);
}

template <typename T>
SPOTKIN_INLINE void fk(const Leg& leg, const T* q, T* p, std::ptrdiff_t count) noexcept {
  BlockAngles a;
  const LegGeometry& g = leg.geometry();
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    block_angles(q + 3 * b0, m, a);
    T* out = p + 3 * b0;
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // (M2)
      const double X = g.knee_offset * a.c[1][i] - g.upper * a.s[1][i] - g.lower * a.s[2][i];
      const double Zs = -g.knee_offset * a.s[1][i] - g.upper * a.c[1][i] - g.lower * a.c[2][i];
      out[3 * i] = T(X);
      out[3 * i + 1] = T(g.hip_offset * a.c[0][i] - Zs * a.s[0][i]);
      out[3 * i + 2] = T(g.hip_offset * a.s[0][i] + Zs * a.c[0][i]);
    }
  }
}

template <typename T>
SPOTKIN_INLINE void jacobian(const Leg& leg, const T* q, T* J, std::ptrdiff_t count) noexcept {
  BlockAngles a;
  const LegGeometry& g = leg.geometry();
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    block_angles(q + 3 * b0, m, a);
    T* out = J + 9 * b0;
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // columns as in Leg::jacobian
      const double s1 = a.s[0][i], c1 = a.c[0][i], s23 = a.s[2][i], c23 = a.c[2][i];
      const double X = g.knee_offset * a.c[1][i] - g.upper * a.s[1][i] - g.lower * s23;
      const double Zs = -g.knee_offset * a.s[1][i] - g.upper * a.c[1][i] - g.lower * c23;
      const double py = g.hip_offset * c1 - Zs * s1, pz = g.hip_offset * s1 + Zs * c1;
      T* Ji = out + 9 * i;
      Ji[0] = T(0.0), Ji[1] = T(Zs), Ji[2] = T(-g.lower * c23);
      Ji[3] = T(-pz), Ji[4] = T(X * s1), Ji[5] = T(-g.lower * s23 * s1);
      Ji[6] = T(py), Ji[7] = T(-X * c1), Ji[8] = T(g.lower * s23 * c1);
    }
  }
}

}  // namespace leg_batch

}  // namespace spotkin
