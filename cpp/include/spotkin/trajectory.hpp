// Trajectory generation: synchronised point-to-point joint profiles (cubic,
// quintic, trapezoid) and Cartesian waypoint paths (straight segments joined by
// constant-acceleration blends; a straight line with a trapezoidal s(t) and
// slerp orientation is the two-waypoint case).
//
// Formulas (derived and checked numerically; the course summary's cubic
// velocity bound and trapezoid phases are wrong as printed):
//   cubic    s(tau) = 3 tau^2 - 2 tau^3, tau = t / t_f. Peak s' = 3/2 at tau = 1/2,
//            peak |s''| = 6 at tau = 0 and 1:  t_f >= 3 D / (2 Kv),  t_f >= sqrt(6 D / Ka).
//   quintic  s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5. Peak s' = 15/8 at tau = 1/2,
//            peak |s''| = 10 / sqrt(3) at tau = 1/2 -+ sqrt(3)/6:
//            t_f >= 15 D / (8 Kv),  t_f >= sqrt(10 D / (sqrt(3) Ka)).
//   trapezoid (bang-coast-bang) with cruise speed v and acceleration a, ramp t_a = v / a:
//            D = v (t_f - t_a). Minimum time: t_f = D / Kv + Kv / Ka when D >= Kv^2 / Ka,
//            else the triangular profile t_f = 2 sqrt(D / Ka) (peak speed sqrt(D Ka) < Kv).
//            Stretched to a longer t_f with a = Ka: v^2 - a t_f v + a D = 0, smaller root
//            v = 2 a D / (a t_f + sqrt(a^2 t_f^2 - 4 a D)) (the cancellation-free form).
// Synchronisation: t_f = max over axes of the per-axis minimum time.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::trajectory {

enum class Profile : int { Cubic = 0, Quintic = 1, Trapezoid = 2 };

// Minimum duration for one axis to move `distance` >= 0 with |qd| <= vmax and
// |qdd| <= amax (both > 0), from rest to rest. Formulas in the file header.
template <typename Scalar>
Scalar min_duration(Profile profile, Scalar distance, Scalar vmax, Scalar amax) noexcept {
  using std::sqrt;
  if (!(distance > Scalar(0))) return Scalar(0);
  switch (profile) {
    case Profile::Cubic:
      return std::max(Scalar(1.5) * distance / vmax, sqrt(Scalar(6) * distance / amax));
    case Profile::Quintic:
      return std::max(Scalar(15) / Scalar(8) * distance / vmax,
                      sqrt(Scalar(10) / sqrt(Scalar(3)) * distance / amax));
    case Profile::Trapezoid:
      if (distance * amax >= vmax * vmax) return distance / vmax + vmax / amax;  // reaches the cruise speed
      return Scalar(2) * sqrt(distance / amax);                                  // triangular
  }
  return std::numeric_limits<Scalar>::quiet_NaN();
}

// Cruise speed of a trapezoid covering `distance` >= 0 in `duration` (at least its
// minimum time) with acceleration `amax`: the smaller root of v^2 - a t_f v + a D = 0.
template <typename Scalar>
Scalar stretched_cruise_speed(Scalar distance, Scalar amax, Scalar duration) noexcept {
  if (!(distance > Scalar(0))) return Scalar(0);
  const Scalar at = amax * duration;
  const Scalar disc = std::max(Scalar(0), at * at - Scalar(4) * amax * distance);  // >= 0 up to rounding
  return Scalar(2) * amax * distance / (at + std::sqrt(disc));
}

// s, s', s'' of the normalised polynomial profiles at tau in [0, 1].
template <typename Scalar>
inline void polynomial(Profile profile, Scalar tau, Scalar& s, Scalar& ds, Scalar& dds) noexcept {
  const Scalar u = Scalar(1) - tau;
  if (profile == Profile::Cubic) {
    s = tau * tau * (Scalar(3) - Scalar(2) * tau);
    ds = Scalar(6) * tau * u;
    dds = Scalar(6) * (u - tau);
  } else {  // quintic
    s = tau * tau * tau * (Scalar(10) + tau * (Scalar(-15) + Scalar(6) * tau));
    ds = Scalar(30) * tau * tau * u * u;
    dds = Scalar(60) * tau * u * (u - tau);
  }
}

// One synchronised point-to-point trajectory over `axes` axes. For the
// trapezoid, per axis: signed acceleration `accel`, signed cruise speed `cruise`
// and ramp time `ramp`; unused by the polynomial profiles.
template <typename Scalar>
struct PointToPoint {
  Profile profile;
  int axes;
  Scalar duration;
  const Scalar* q0;
  const Scalar* qf;
  const Scalar* accel;
  const Scalar* cruise;
  const Scalar* ramp;
};

// A point-to-point plan (double): each axis' minimum duration under its vmax and amax, the common
// duration t_f (the slowest axis'), and for the trapezoid each axis stretched to t_f (its signed
// acceleration, cruise speed and ramp time; zero for an axis that does not move). The float copies
// feed the float32 sampler. Inputs are checked by the caller (finite, vmax and amax > 0).
struct PointToPointPlan {
  Profile profile;
  double duration = 0.0;
  std::vector<double> q0, qf, axis_durations, accel, cruise, ramp;
  std::vector<float> q0_f, qf_f, accel_f, cruise_f, ramp_f;

  PointToPointPlan(Profile p, std::vector<double> start, std::vector<double> end, const std::vector<double>& vmax,
                   const std::vector<double>& amax)
      : profile(p), q0(std::move(start)), qf(std::move(end)) {
    const std::size_t n = q0.size();
    axis_durations.resize(n), accel.assign(n, 0.0), cruise.assign(n, 0.0), ramp.assign(n, 0.0);
    for (std::size_t j = 0; j < n; ++j) {
      axis_durations[j] = min_duration(profile, std::fabs(qf[j] - q0[j]), vmax[j], amax[j]);
      duration = std::max(duration, axis_durations[j]);
    }
    if (profile == Profile::Trapezoid)
      for (std::size_t j = 0; j < n; ++j) {
        const double D = qf[j] - q0[j];
        const double v = stretched_cruise_speed(std::fabs(D), amax[j], duration);
        if (v > 0.0) {
          accel[j] = std::copysign(amax[j], D);
          cruise[j] = std::copysign(v, D);
          ramp[j] = std::min(v / amax[j], 0.5 * duration);
        }
      }
    const std::vector<double>* from[5] = {&q0, &qf, &accel, &cruise, &ramp};
    std::vector<float>* to[5] = {&q0_f, &qf_f, &accel_f, &cruise_f, &ramp_f};
    for (int k = 0; k < 5; ++k) to[k]->assign(from[k]->begin(), from[k]->end());
  }
  PointToPoint<double> view(double) const {
    return {profile, int(q0.size()), duration, q0.data(), qf.data(), accel.data(), cruise.data(), ramp.data()};
  }
  PointToPoint<float> view(float) const {
    return {profile, int(q0.size()), float(duration), q0_f.data(), qf_f.data(), accel_f.data(), cruise_f.data(),
            ramp_f.data()};
  }
};

// q, qd, qdd (rows of `axes`) at each of the n times t. Times outside [0, t_f]
// give the end states at rest (zero derivatives); at t = 0 and t_f themselves the
// profile's own acceleration (nonzero for the cubic and the trapezoid). A NaN time
// gives a NaN row.
template <typename Scalar>
void sample(const PointToPoint<Scalar>& traj, const Scalar* t, Scalar* q, Scalar* qd, Scalar* qdd,
            std::ptrdiff_t n) noexcept {
  const int m = traj.axes;
  const Scalar T = traj.duration;
  const Scalar inv_T = T > Scalar(0) ? Scalar(1) / T : Scalar(0);
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  for (std::ptrdiff_t i = 0; i < n; ++i, q += m, qd += m, qdd += m) {
    const Scalar ti = t[i];
    if (std::isnan(ti)) {
      for (int j = 0; j < m; ++j) q[j] = qd[j] = qdd[j] = nan;
      continue;
    }
    if (ti < Scalar(0) || ti > T) {  // outside [0, t_f]: at rest at an end
      const Scalar* end = ti > T ? traj.qf : traj.q0;
      for (int j = 0; j < m; ++j) {
        q[j] = end[j];
        qd[j] = qdd[j] = Scalar(0);
      }
      continue;
    }
    if (traj.profile != Profile::Trapezoid) {
      // q = q0 + D s(tau), qd = D s'(tau) / t_f, qdd = D s''(tau) / t_f^2
      Scalar s, ds, dds;
      polynomial(traj.profile, ti * inv_T, s, ds, dds);
      ds *= inv_T;
      dds *= inv_T * inv_T;
      for (int j = 0; j < m; ++j) {
        const Scalar D = traj.qf[j] - traj.q0[j];
        q[j] = ti == T ? traj.qf[j] : traj.q0[j] + D * s;  // exact at t_f
        qd[j] = D * ds;
        qdd[j] = D * dds;
      }
      continue;
    }
    for (int j = 0; j < m; ++j) {
      const Scalar a = traj.accel[j], v = traj.cruise[j], ta = traj.ramp[j];
      if (ti < ta) {  // accelerate: q0 + a t^2 / 2
        q[j] = traj.q0[j] + Scalar(0.5) * a * ti * ti;
        qd[j] = a * ti;
        qdd[j] = a;
      } else if (ti <= T - ta) {  // cruise: q0 + v (t - t_a / 2)
        q[j] = traj.q0[j] + v * (ti - Scalar(0.5) * ta);
        qd[j] = v;
        qdd[j] = Scalar(0);
      } else {  // decelerate: qf - a (t_f - t)^2 / 2
        const Scalar r = T - ti;
        q[j] = traj.qf[j] - Scalar(0.5) * a * r * r;
        qd[j] = a * r;
        qdd[j] = -a;
      }
    }
  }
}

// ---- Cartesian waypoint paths ---------------------------------------------------------------
// Quaternions are [x, y, z, w] (scalar last, as spotkin's (..., 7) poses).

template <typename Scalar>
struct Quat {
  Scalar x, y, z, w;
};

template <typename Scalar>
inline Quat<Scalar> operator*(const Quat<Scalar>& a, const Quat<Scalar>& b) noexcept {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

// v rotated by the unit quaternion q: v + 2 w (u x v) + 2 u x (u x v).
template <typename Scalar>
inline void rotate(const Quat<Scalar>& q, const Scalar* v, Scalar* out) noexcept {
  const Scalar cx = q.y * v[2] - q.z * v[1], cy = q.z * v[0] - q.x * v[2], cz = q.x * v[1] - q.y * v[0];
  out[0] = v[0] + Scalar(2) * (q.w * cx + q.y * cz - q.z * cy);
  out[1] = v[1] + Scalar(2) * (q.w * cy + q.z * cx - q.x * cz);
  out[2] = v[2] + Scalar(2) * (q.w * cz + q.x * cy - q.y * cx);
}

// A path through W >= 2 waypoints (position P_k, orientation Q_k) reached at times
// t_k. Segment k (k < W-1) moves at constant linear velocity v_k and constant
// world angular velocity w_k: p = P_k + v_k (t - t_k), R = exp(w_k (t - t_k)) R_k.
// Around each waypoint a blend of duration b_k, centred on t_k, changes the
// velocity linearly from the incoming (v_{k-1}, w_{k-1}) to the outgoing (v_k, w_k)
// (zero before the first and after the last waypoint). With tau = t - t_k,
// u = tau + b_k/2 in [0, b_k], f2 = u^2 / (2 b_k), f1 = tau - f2:
//   p = P_k + v_{k-1} f1 + v_k f2,   R = exp(w_{k-1} f1) exp(w_k f2) R_k,
//   p' = v_{k-1} (1 - u/b) + v_k u/b,   w = w_{k-1} (1 - u/b) + exp(w_{k-1} f1) w_k u/b.
// The end blends start and stop exactly at P_0 and P_{W-1}; an interior blend
// passes P_k + (v_k - v_{k-1}) b_k / 8 at t_k (near, not through, the waypoint).
// The path runs over [0, t_{W-1} + b_{W-1}/2] with t_0 = b_0 / 2.
struct WaypointPath {
  std::ptrdiff_t count;         // W
  const double* times;          // t_k (W)
  const double* blends;         // b_k (W)
  const double* blend_starts;   // t_k - b_k / 2 (W), increasing
  const double* positions;      // P_k (W, 3)
  const double* quaternions;    // Q_k (W, 4), consecutive ones in the same hemisphere
  const double* linear;         // v_k (W-1, 3)
  const double* angular;        // w_k (W-1, 3)
  const double* axes;           // w_k / |w_k| (W-1, 3), zero for w_k = 0
  const double* rates;          // |w_k| (W-1)
  double duration;
};

// A waypoint path's data and what the sampler derives from it: each segment's angular rate |w_k|
// and axis, each blend's start, the duration. Blends must be >= 0 and must not overlap
// (std::invalid_argument otherwise); the data must be finite (checked by the caller).
struct WaypointPathData {
  std::vector<double> times, blends, positions, quaternions, linear, angular, blend_starts, axes, rates;
  double duration = 0.0;

  WaypointPathData(std::vector<double> t, std::vector<double> b, std::vector<double> p, std::vector<double> q,
                   std::vector<double> v, std::vector<double> w)
      : times(std::move(t)), blends(std::move(b)), positions(std::move(p)), quaternions(std::move(q)),
        linear(std::move(v)), angular(std::move(w)) {
    for (std::size_t k = 0; k + 1 < times.size(); ++k) {
      const double* wk = angular.data() + 3 * k;
      const double rate = std::sqrt(wk[0] * wk[0] + wk[1] * wk[1] + wk[2] * wk[2]);
      rates.push_back(rate);
      for (int c = 0; c < 3; ++c) axes.push_back(rate > 0.0 ? wk[c] / rate : 0.0);
    }
    blend_starts.resize(times.size());
    for (std::size_t k = 0; k < times.size(); ++k) {
      if (blends[k] < 0.0) throw std::invalid_argument("blends must be >= 0");
      blend_starts[k] = times[k] - 0.5 * blends[k];
      if (k > 0 && blend_starts[k] < blend_starts[k - 1]) throw std::invalid_argument("blends must not overlap");
    }
    duration = times.back() + 0.5 * blends.back();
  }
  WaypointPath view() const {
    return {std::ptrdiff_t(times.size()), times.data(),   blends.data(), blend_starts.data(), positions.data(),
            quaternions.data(),           linear.data(),  angular.data(), axes.data(),        rates.data(),
            duration};
  }
};

enum class PoseForm : int { Matrix = 0, Quaternion = 1 };

// Pose (row-major 4x4, or [x, y, z, qx, qy, qz, qw]) and, if twist != nullptr,
// the world twist [v; w] at each of the n times t. Times outside [0, duration]
// clamp to the end poses with a zero twist; a NaN time gives NaN outputs.
// Blocks of samples: (1) per sample, the segment or blend and the two rotation
// angles of exp(w_{k-1} f1) and exp(w_k f2) (or exp(w_k tau)); (2) their sines
// and cosines in one vectorised loop; (3) per sample, the pose and twist.
// (SPOTKIN_INLINE: compiled into each CPU-level clone of its caller.)
template <typename Scalar>
SPOTKIN_INLINE void sample(const WaypointPath& path, PoseForm form, const Scalar* t, Scalar* pose, Scalar* twist,
                           std::ptrdiff_t n) noexcept {
  enum Kind : int { kNaN, kAtRest, kBlend, kSegment };
  constexpr std::ptrdiff_t B = 64;
  const std::ptrdiff_t W = path.count;
  const std::ptrdiff_t width = form == PoseForm::Matrix ? 16 : 7;
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  static constexpr double zero[3] = {0, 0, 0};
  int kind[B];
  std::ptrdiff_t segment[B];
  double tau[B], f1[B], f2[B], g2[B], half1[B], half2[B], s1[B], c1[B], s2[B], c2[B];
  for (std::ptrdiff_t b0 = 0; b0 < n; b0 += B) {
    const std::ptrdiff_t m = std::min(B, n - b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // (1)
      const double ti = static_cast<double>(t[b0 + i]);
      half1[i] = half2[i] = 0.0;
      if (std::isnan(ti)) {
        kind[i] = kNaN;
        continue;
      }
      if (!(ti > 0.0) || ti >= path.duration) {  // clamped to an end, at rest
        kind[i] = kAtRest, segment[i] = ti > 0.0 ? W - 1 : 0;
        continue;
      }
      // the last waypoint whose blend has started
      std::ptrdiff_t k = std::upper_bound(path.blend_starts, path.blend_starts + W, ti) - path.blend_starts - 1;
      k = std::max<std::ptrdiff_t>(k, 0);
      const double tk = ti - path.times[k], bk = path.blends[k];
      segment[i] = k, tau[i] = tk;
      if ((tk <= 0.5 * bk && bk > 0.0) || k == W - 1) {  // blend around waypoint k
        const double u = std::min(std::max(tk + 0.5 * bk, 0.0), bk);
        f2[i] = bk > 0.0 ? 0.5 * u * u / bk : 0.0, f1[i] = tk - f2[i];
        g2[i] = bk > 0.0 ? u / bk : 0.0;
        kind[i] = kBlend;
        // exp(w f) = rotation by |w| f about w / |w|; the end blends have one zero factor
        half1[i] = k > 0 ? 0.5 * path.rates[k - 1] * f1[i] : 0.0;
        half2[i] = k < W - 1 ? 0.5 * path.rates[k] * f2[i] : 0.0;
      } else {  // straight segment k
        kind[i] = kSegment;
        half2[i] = 0.5 * path.rates[k] * tk;
      }
    }
    bool bounded = true;  // |angle| within the inline sin/cos's range (always, short of absurd rates)
    for (std::ptrdiff_t i = 0; i < m; ++i)
      bounded &= std::fabs(half1[i]) < vector_math::kReducibleLimit && std::fabs(half2[i]) < vector_math::kReducibleLimit;
    if (bounded) {  // (2)
      for (std::ptrdiff_t i = 0; i < m; ++i) vector_math::sincos_bounded(half1[i], s1[i], c1[i]);
      for (std::ptrdiff_t i = 0; i < m; ++i) vector_math::sincos_bounded(half2[i], s2[i], c2[i]);
    } else {
      for (std::ptrdiff_t i = 0; i < m; ++i)
        s1[i] = std::sin(half1[i]), c1[i] = std::cos(half1[i]), s2[i] = std::sin(half2[i]), c2[i] = std::cos(half2[i]);
    }
    for (std::ptrdiff_t i = 0; i < m; ++i, pose += width) {  // (3)
      Scalar* tw = twist ? twist + 6 * (b0 + i) : nullptr;
      if (kind[i] == kNaN) {
        for (std::ptrdiff_t c = 0; c < width; ++c) pose[c] = nan;
        if (tw)
          for (int c = 0; c < 6; ++c) tw[c] = nan;
        continue;
      }
      const std::ptrdiff_t k = segment[i];
      double p[3], vel[3] = {0, 0, 0}, omega[3] = {0, 0, 0};
      const double* P = path.positions + 3 * k;
      const double* Q = path.quaternions + 4 * k;
      const Quat<double> Qk{Q[0], Q[1], Q[2], Q[3]};
      Quat<double> q = Qk;
      if (kind[i] == kAtRest) {
        for (int c = 0; c < 3; ++c) p[c] = P[c];
      } else {
        if (kind[i] == kBlend) {
          const double* v0 = k > 0 ? path.linear + 3 * (k - 1) : zero;
          const double* w0 = k > 0 ? path.angular + 3 * (k - 1) : zero;
          const double* v1 = k < W - 1 ? path.linear + 3 * k : zero;
          const double* w1 = k < W - 1 ? path.angular + 3 * k : zero;
          const double* axis0 = k > 0 ? path.axes + 3 * (k - 1) : zero;
          const double* axis1 = k < W - 1 ? path.axes + 3 * k : zero;
          const Quat<double> A{s1[i] * axis0[0], s1[i] * axis0[1], s1[i] * axis0[2], c1[i]};
          const Quat<double> Bq{s2[i] * axis1[0], s2[i] * axis1[1], s2[i] * axis1[2], c2[i]};
          q = A * Bq * Qk;
          double w1_rot[3];
          rotate(A, w1, w1_rot);
          const double g = g2[i];
          for (int c = 0; c < 3; ++c) {
            p[c] = P[c] + v0[c] * f1[i] + v1[c] * f2[i];
            vel[c] = v0[c] * (1.0 - g) + v1[c] * g;
            omega[c] = w0[c] * (1.0 - g) + w1_rot[c] * g;
          }
        } else {  // straight segment k
          const double* v = path.linear + 3 * k;
          const double* w = path.angular + 3 * k;
          const double* axis = path.axes + 3 * k;
          q = Quat<double>{s2[i] * axis[0], s2[i] * axis[1], s2[i] * axis[2], c2[i]} * Qk;
          for (int c = 0; c < 3; ++c) {
            p[c] = P[c] + v[c] * tau[i];
            vel[c] = v[c];
            omega[c] = w[c];
          }
        }
        const double inv_norm = 1.0 / std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
        q = {q.x * inv_norm, q.y * inv_norm, q.z * inv_norm, q.w * inv_norm};
      }
      if (form == PoseForm::Quaternion) {
        const double out[7] = {p[0], p[1], p[2], q.x, q.y, q.z, q.w};
        for (int c = 0; c < 7; ++c) pose[c] = static_cast<Scalar>(out[c]);
      } else {
        const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
        const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
        const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
        const double mtx[16] = {1 - 2 * (yy + zz), 2 * (xy - wz),     2 * (xz + wy),     p[0],
                                2 * (xy + wz),     1 - 2 * (xx + zz), 2 * (yz - wx),     p[1],
                                2 * (xz - wy),     2 * (yz + wx),     1 - 2 * (xx + yy), p[2],
                                0,                 0,                 0,                 1};
        for (int c = 0; c < 16; ++c) pose[c] = static_cast<Scalar>(mtx[c]);
      }
      if (tw)
        for (int c = 0; c < 3; ++c) {
          tw[c] = static_cast<Scalar>(vel[c]);
          tw[3 + c] = static_cast<Scalar>(omega[c]);
        }
    }
  }
}

}  // namespace spotkin::trajectory
