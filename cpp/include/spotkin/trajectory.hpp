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

// exp of the rotation by `angle` about the unit `axis`; the identity for a zero axis.
inline Quat<double> axis_angle(const double* axis, double angle) noexcept {
  const double half = 0.5 * angle, sh = std::sin(half), ch = std::cos(half);
  return {sh * axis[0], sh * axis[1], sh * axis[2], ch};
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

enum class PoseForm : int { Matrix = 0, Quaternion = 1 };

// Pose (row-major 4x4, or [x, y, z, qx, qy, qz, qw]) and, if twist != nullptr,
// the world twist [v; w] at each of the n times t. Times outside [0, duration]
// clamp to the end poses with a zero twist; a NaN time gives NaN outputs.
template <typename Scalar>
void sample(const WaypointPath& path, PoseForm form, const Scalar* t, Scalar* pose, Scalar* twist,
            std::ptrdiff_t n) noexcept {
  const std::ptrdiff_t W = path.count;
  const std::ptrdiff_t width = form == PoseForm::Matrix ? 16 : 7;
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  for (std::ptrdiff_t i = 0; i < n; ++i, pose += width) {
    Scalar* tw = twist ? twist + 6 * i : nullptr;
    const double ti = static_cast<double>(t[i]);
    if (std::isnan(ti)) {
      for (std::ptrdiff_t c = 0; c < width; ++c) pose[c] = nan;
      if (tw)
        for (int c = 0; c < 6; ++c) tw[c] = nan;
      continue;
    }
    double p[3], vel[3] = {0, 0, 0}, omega[3] = {0, 0, 0};
    Quat<double> q;
    std::ptrdiff_t k;
    if (!(ti > 0.0) || ti >= path.duration) {  // clamped to an end, at rest
      k = ti > 0.0 ? W - 1 : 0;
      for (int c = 0; c < 3; ++c) p[c] = path.positions[3 * k + c];
      const double* Q = path.quaternions + 4 * k;
      q = {Q[0], Q[1], Q[2], Q[3]};
    } else {
      // the last waypoint whose blend has started
      k = std::upper_bound(path.blend_starts, path.blend_starts + W, ti) - path.blend_starts - 1;
      k = std::max<std::ptrdiff_t>(k, 0);
      const double tau = ti - path.times[k], b = path.blends[k];
      const double* P = path.positions + 3 * k;
      const double* Q = path.quaternions + 4 * k;
      const Quat<double> Qk{Q[0], Q[1], Q[2], Q[3]};
      if ((tau <= 0.5 * b && b > 0.0) || k == W - 1) {  // blend around waypoint k
        static constexpr double zero[3] = {0, 0, 0};
        const double* v0 = k > 0 ? path.linear + 3 * (k - 1) : zero;
        const double* w0 = k > 0 ? path.angular + 3 * (k - 1) : zero;
        const double* v1 = k < W - 1 ? path.linear + 3 * k : zero;
        const double* w1 = k < W - 1 ? path.angular + 3 * k : zero;
        const double u = std::min(std::max(tau + 0.5 * b, 0.0), b);
        const double f2 = b > 0.0 ? 0.5 * u * u / b : 0.0, f1 = tau - f2;
        const double g2 = b > 0.0 ? u / b : 0.0, g1 = 1.0 - g2;
        // exp(w f) = rotation by |w| f about w / |w|; the end blends have one zero factor
        const Quat<double> A = k > 0 ? axis_angle(path.axes + 3 * (k - 1), path.rates[k - 1] * f1)
                                     : Quat<double>{0, 0, 0, 1};
        q = k < W - 1 ? A * axis_angle(path.axes + 3 * k, path.rates[k] * f2) * Qk : A * Qk;
        double w1_rot[3];
        rotate(A, w1, w1_rot);
        for (int c = 0; c < 3; ++c) {
          p[c] = P[c] + v0[c] * f1 + v1[c] * f2;
          vel[c] = v0[c] * g1 + v1[c] * g2;
          omega[c] = w0[c] * g1 + w1_rot[c] * g2;
        }
      } else {  // straight segment k
        const double* v = path.linear + 3 * k;
        const double* w = path.angular + 3 * k;
        q = axis_angle(path.axes + 3 * k, path.rates[k] * tau) * Qk;
        for (int c = 0; c < 3; ++c) {
          p[c] = P[c] + v[c] * tau;
          vel[c] = v[c];
          omega[c] = w[c];
        }
      }
      const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
      q = {q.x / norm, q.y / norm, q.z / norm, q.w / norm};
    }
    if (form == PoseForm::Quaternion) {
      const double out[7] = {p[0], p[1], p[2], q.x, q.y, q.z, q.w};
      for (int c = 0; c < 7; ++c) pose[c] = static_cast<Scalar>(out[c]);
    } else {
      const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
      const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
      const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
      const double m[16] = {1 - 2 * (yy + zz), 2 * (xy - wz),     2 * (xz + wy),     p[0],
                            2 * (xy + wz),     1 - 2 * (xx + zz), 2 * (yz - wx),     p[1],
                            2 * (xz - wy),     2 * (yz + wx),     1 - 2 * (xx + yy), p[2],
                            0,                 0,                 0,                 1};
      for (int c = 0; c < 16; ++c) pose[c] = static_cast<Scalar>(m[c]);
    }
    if (tw)
      for (int c = 0; c < 3; ++c) {
        tw[c] = static_cast<Scalar>(vel[c]);
        tw[3 + c] = static_cast<Scalar>(omega[c]);
      }
  }
}

}  // namespace spotkin::trajectory
