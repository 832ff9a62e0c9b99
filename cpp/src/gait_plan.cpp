// The gait planner (spotkin/motion/gait_plan.hpp): the reference planner's state machine
// (python/spotkin/reference/gait_plan.py) line for line, in double, then each command's IK along
// its path, joint velocities and standing statics over all its ticks at once.
#include "spotkin/motion/gait_plan.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/kernels/body.hpp"
#include "spotkin/leg.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::motion {

namespace {

constexpr double kPiValue = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPiValue;

const GaitNumbers kZeroNumbers{};  // the rates of a settled gait

// Whether the blend of step 1 is over at t (the gait's numbers are the new ones).
inline bool settled_at(const PlannerState& s, double t) noexcept {
  return s.duration <= 0.0 || t >= s.t0 + s.duration;
}

}  // namespace

// (Q): b(x) = 10 x^3 - 15 x^4 + 6 x^5 at x clamped to [0, 1], with b' and b''.
Quintic quintic(double x) noexcept {
  x = std::min(std::max(x, 0.0), 1.0);
  return {x * x * x * (10.0 - 15.0 * x + 6.0 * x * x), 30.0 * x * x * (1.0 - x) * (1.0 - x),
          60.0 * x * (1.0 - x) * (1.0 - 2.0 * x)};
}

double floor_height(const PlannerState& s, double x, double y) noexcept {
  return s.has_ground ? s.ground[0] + s.ground[1] * x + s.ground[2] * y : 0.0;
}

// Step 1: the gait's numbers at t and (when rates) their time derivatives.
void blended(const PlannerState& s, double t, GaitNumbers& P, GaitNumbers* rates) noexcept {
  if (settled_at(s, t)) {
    P = s.new_numbers;
    if (rates) *rates = GaitNumbers{};
    return;
  }
  const Quintic q = quintic((t - s.t0) / s.duration);
  for (int k = 0; k < kGaitNumbers; ++k) {
    const double delta = s.new_numbers[k] - s.old_numbers[k];
    P[k] = s.old_numbers[k] + delta * q.b;
    if (rates) (*rates)[k] = delta * q.db / s.duration;
  }
}

namespace {

// blended() without a copy once the gait has settled: the new gait's numbers themselves (rates,
// when asked: zero).
const GaitNumbers& numbers_at(const PlannerState& s, double t, GaitNumbers& scratch,
                              const GaitNumbers** rates = nullptr,
                              GaitNumbers* rate_scratch = nullptr) noexcept {
  if (settled_at(s, t)) {
    if (rates) *rates = &kZeroNumbers;
    return s.new_numbers;
  }
  blended(s, t, scratch, rate_scratch);
  if (rates) *rates = rate_scratch;
  return scratch;
}

// D of step 1: max(T_new, 2 max_i |delta o_i| max(T_old, T_new)).
double blend_duration(const GaitNumbers& old, const GaitNumbers& nw) noexcept {
  double worst_delta = 0.0;
  for (int i = 0; i < kLegs; ++i)
    worst_delta = std::max(
        worst_delta, std::fabs(py_mod(nw[kOffsets + i] - old[kOffsets + i] + 0.5, 1.0) - 0.5));
  const double worst = std::max(old[kPeriod], nw[kPeriod]);
  return std::max({nw[kPeriod], 2.0 * worst_delta * worst, std::fabs(old[kPeriod] - nw[kPeriod])});
}

struct Planar {
  double x, y, psi, v[2], w;
};

// Step 3's motion over dt: velocity ramped towards the target, the pose by the trapezoid rule.
void ramp(Planar& p, const double target[3], double accel, double yaw_accel, double dt) noexcept {
  const double step = accel * dt, yaw_step = yaw_accel * dt;
  double v1[2];
  for (int k = 0; k < 2; ++k) v1[k] = p.v[k] + std::min(std::max(target[k] - p.v[k], -step), step);
  const double w1 = p.w + std::min(std::max(target[2] - p.w, -yaw_step), yaw_step);
  const double psi1 = p.psi + dt * (p.w + w1) / 2.0;
  const double mid = (p.psi + psi1) / 2.0;
  const double mean[2] = {(p.v[0] + v1[0]) / 2.0, (p.v[1] + v1[1]) / 2.0};
  const double c = std::cos(mid), s = std::sin(mid);
  p.x += dt * (c * mean[0] - s * mean[1]);
  p.y += dt * (s * mean[0] + c * mean[1]);
  p.psi = psi1, p.v[0] = v1[0], p.v[1] = v1[1], p.w = w1;
}

// s of step 3 for a target (vx, vy, yaw rate): the half strides against each leg's room.
double speed_scale(const GaitNumbers& P, const double target[3]) noexcept {
  const double half_stance = P[kDuty] * P[kPeriod] / 2.0;
  double sway[2];
  for (int k = 0; k < 2; ++k) {
    double total = 0.0;
    for (int j = 0; j < kLegs; ++j) total += std::fabs(P[kSway + 2 * j + k]);
    sway[k] = P[kComShift] * (std::fabs(P[kShift + k]) + total);
  }
  double worst = 1.0;
  for (int i = 0; i < kLegs; ++i) {
    const double r0 = P[kStance + 3 * i], r1 = P[kStance + 3 * i + 1];
    double room[2];
    for (int k = 0; k < 2; ++k) {
      const double reach = P[kStepReach + 2 * i + k];
      room[k] = std::max(kStepFit * reach - sway[k], 0.1 * reach);
    }
    const double dx = half_stance * (target[0] - target[2] * r1);
    const double dy = half_stance * (target[1] + target[2] * r0);
    const double a = dx / room[0], b = dy / room[1];
    worst = std::max(worst, a * a + b * b);
  }
  return 1.0 / std::sqrt(worst);  // the square root of the largest: the largest square root
}

// Step 3's target: the command times `moving` times the step-fit scale (returned). Once the gait
// has settled (P is the new gait's numbers), the scale is the state's cached one: the same numbers.
double target_of(const PlannerState& s, const GaitNumbers& P, double target[3],
                 bool settled) noexcept {
  for (int k = 0; k < 3; ++k) target[k] = s.command[k] * P[kMoving];
  double scale;
  const bool same = s.settled_command[0] == s.command[0] && s.settled_command[1] == s.command[1] &&
                    s.settled_command[2] == s.command[2];
  if (settled && same && s.settled_scale >= 0.0) {
    scale = s.settled_scale;
  } else {
    scale = speed_scale(P, target);
    if (settled) {
      s.settled_scale = scale;
      for (int k = 0; k < 3; ++k) s.settled_command[k] = s.command[k];
    }
  }
  for (int k = 0; k < 3; ++k) target[k] *= scale;
  return scale;
}

// The plan's own motion ahead (reference predict): steps 1-3 without the legs, kPredictionSteps
// equal steps between successive horizons.
struct Predictor {
  const PlannerState& s;
  Planar planar;
  double theta, rate, t;
  explicit Predictor(const PlannerState& state)
      : s(state),
        planar{state.x, state.y, state.psi, {state.v[0], state.v[1]}, state.w},
        theta(state.theta),
        rate(state.clock_rate),
        t(state.t) {}
  // Moves to s.t + horizon; P: the gait's numbers there.
  void to(double horizon, GaitNumbers& P) noexcept {
    const double dt = (s.t + horizon - t) / kPredictionSteps;
    double target[3];
    GaitNumbers scratch(uninitialized);
    for (int k = 0; k < kPredictionSteps; ++k) {
      t += dt;
      const GaitNumbers& Pt = numbers_at(s, t, scratch);  // no copy once the gait has settled
      const double rate1 = 1.0 / Pt[kPeriod];
      theta += dt * (rate + rate1) / 2.0;
      rate = rate1;
      target_of(s, Pt, target, settled_at(s, t));
      ramp(planar, target, Pt[kAccel], Pt[kYawAccel], dt);
    }
    blended(s, t, P, nullptr);
  }
};

}  // namespace

// (C): the crawl's sway delta and d delta / dt (body frame), with its weight and base offset.
void crawl_shift(const GaitNumbers& P, const GaitNumbers& Pd, const double* phases,
                 const double* phase_rates, double value[2], double rate[2]) noexcept {
  const double weight = P[kComShift], weight_rate = Pd[kComShift];
  value[0] = value[1] = rate[0] = rate[1] = 0.0;
  if (weight == 0.0 && weight_rate == 0.0) return;
  const double centre = (1.0 + P[kDuty]) / 2.0, centre_rate = Pd[kDuty] / 2.0;
  // the first harmonic's angles a_i, their sines and cosines in one vectorised call; the second
  // harmonic's angle is 2 a_i exactly (a product by 2), its cos and sin by the double angle
  double first[kLegs], sin1[kLegs], cos1[kLegs];
  for (int i = 0; i < kLegs; ++i) first[i] = kTwoPi * (phases[i] - centre);
  vector_math::sincos(first, sin1, cos1, kLegs);
  double sum[2] = {0.0, 0.0}, sum_rate[2] = {0.0, 0.0};
  for (int i = 0; i < kLegs; ++i)
    for (int axis = 0; axis < 2; ++axis) {
      const double harmonic = axis == 0 ? 2.0 : 1.0;
      const double angle_rate = kTwoPi * harmonic * (phase_rates[i] - centre_rate);
      const double X = P[kSway + 2 * i + axis], X_rate = Pd[kSway + 2 * i + axis];
      const double c = axis == 0 ? (cos1[i] - sin1[i]) * (cos1[i] + sin1[i]) : cos1[i],
                   s = axis == 0 ? 2.0 * sin1[i] * cos1[i] : sin1[i];
      sum[axis] += X * c;
      sum_rate[axis] += X_rate * c - X * s * angle_rate;
    }
  for (int axis = 0; axis < 2; ++axis) {
    const double v = sum[axis] + P[kShift + axis], r = sum_rate[axis] + Pd[kShift + axis];
    value[axis] = weight * v;
    rate[axis] = weight_rate * v + weight * r;
  }
}

// [x, y, z, a, b, c] with R = Rx(a) Ry(b) Rz(c) = Rz(psi) Ry(pitch) Rx(roll), c unwrapped near psi;
// R_out (optional) that rotation.
void body_pose(double x, double y, double z, double psi, double cz, double sz,
               const PlannerState& s, double pose[6], double (*R_out)[3]) noexcept {
  const double cy = s.cos_pitch, sy = s.sin_pitch, cx = s.cos_roll, sx = s.sin_roll;
  const double R00 = cz * cy, R01 = -sz * cx + cz * sy * sx, R02 = sz * sx + cz * sy * cx;
  const double R12 = -cz * sx + sz * sy * cx, R22 = cy * cx;
  pose[0] = x, pose[1] = y, pose[2] = z;
  if (sx == 0.0 && sy == 0.0) {  // level (roll and pitch 0, cosines 1): R = Rz(psi), a = b = 0, c = psi
    pose[3] = 0.0, pose[4] = 0.0, pose[5] = psi;
  } else {
    const double b = std::asin(std::min(std::max(R02, -1.0), 1.0));
    const double a = vector_math::atan2(-R12, R22);
    double c = vector_math::atan2(-R01, R00);
    c += kTwoPi * std::nearbyint((psi - c) / kTwoPi);
    pose[3] = a, pose[4] = b, pose[5] = c;
  }
  if (R_out) {
    const double R[3][3] = {
        {R00, R01, R02}, {sz * cy, sz * sy * sx + cz * cx, R12}, {-sy, cy * sx, R22}};
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) R_out[r][k] = R[r][k];
  }
}

namespace {

struct Transform {
  double R[3][3], t[3];
};

Transform transform_of(const double pose[6]) noexcept {
  Transform T;
  Body::euler_rotation(xyz_sequence(), pose + 3, T.R);
  for (int k = 0; k < 3; ++k) T.t[k] = pose[k];
  return T;
}

// (B)'s test: leg i reaches the world point p within its limits at every pose.
bool reachable(const Body& body, int i, const double p[3], const Transform* poses,
               int count) noexcept {
  double points[3 * (kChecks + 1)], q[3 * (kChecks + 1)];
  std::int8_t status[kChecks + 1];
  const auto& hip = body.hips[std::size_t(i)];
  for (int k = 0; k < count; ++k) {  // R^T (p - t) - hip
    const Transform& T = poses[k];
    const double d[3] = {p[0] - T.t[0], p[1] - T.t[1], p[2] - T.t[2]};
    for (int r = 0; r < 3; ++r)
      points[3 * k + r] =
          T.R[0][r] * d[0] + T.R[1][r] * d[1] + T.R[2][r] * d[2] - hip[std::size_t(r)];
  }
  leg_batch::ik(body.legs[std::size_t(i)], points, static_cast<const double*>(nullptr), q, status,
                count, false);
  for (int k = 0; k < count; ++k)
    if (status[k] != std::int8_t(Status::Ok)) return false;
  return true;
}

// (B): p if reachable at every pose, else the point towards p_nominal found by bisection.
bool bounded_foothold(const Body& body, int i, double p[3], const double p_nominal[3],
                      const Transform* poses, int count) noexcept {
  if (reachable(body, i, p, poses, count)) return false;
  double lo = 0.0, hi = 1.0, trial[3];
  for (int n = 0; n < kBisections; ++n) {
    const double mid = 0.5 * (lo + hi);
    for (int r = 0; r < 3; ++r) trial[r] = p_nominal[r] + mid * (p[r] - p_nominal[r]);
    (reachable(body, i, trial, poses, count) ? lo : hi) = mid;
  }
  for (int r = 0; r < 3; ++r) p[r] = p_nominal[r] + lo * (p[r] - p_nominal[r]);
  return true;
}

// Step 4's foothold of leg i lifting off now at `phase` (P: the gait's numbers now).
void plan_foothold(const Body& body, PlannerState& s, const GaitNumbers& P, int i,
                   double phase) noexcept {
  const double to_touchdown = (1.0 - phase) * P[kPeriod];
  Predictor ahead(s);
  Planar planar[kChecks + 1];
  double theta[kChecks + 1];
  GaitNumbers Pf[kChecks + 1];  // once a lift-off
  ahead.to(to_touchdown, Pf[0]);
  planar[0] = ahead.planar, theta[0] = ahead.theta;
  const double t_stance = Pf[0][kDuty] * Pf[0][kPeriod];  // the gait's at touch-down
  for (int k = 1; k <= kChecks; ++k) {
    ahead.to(to_touchdown + t_stance * k / kChecks, Pf[k]);
    planar[k] = ahead.planar, theta[k] = ahead.theta;
  }
  double offset[2] = {0.0, 0.0};  // closed loop: where the body will be
  if (s.has_p_measured) {
    offset[0] = s.p_measured[0] - s.x, offset[1] = s.p_measured[1] - s.y;
    if (s.has_v_measured) {
      const double c0 = std::cos(s.psi), s0 = std::sin(s.psi);
      const double now[2] = {c0 * s.v[0] - s0 * s.v[1], s0 * s.v[0] + c0 * s.v[1]};
      for (int k = 0; k < 2; ++k) offset[k] = offset[k] + (s.v_measured[k] - now[k]) * to_touchdown;
    }
  }
  const double x = planar[0].x + offset[0], y = planar[0].y + offset[1], psi = planar[0].psi;
  const Planar& middle = planar[kChecks / 2];
  const double c = std::cos(psi), sn = std::sin(psi);
  const double* nominal = &P.v[kStance + 3 * i];
  const double r[2] = {c * nominal[0] - sn * nominal[1], sn * nominal[0] + c * nominal[1]};
  double p_nominal[3] = {x + r[0], y + r[1], nominal[2] + floor_height(s, x + r[0], y + r[1])};
  const double velocity[2] = {c * middle.v[0] - sn * middle.v[1],
                              sn * middle.v[0] + c * middle.v[1]};
  const double* measured = s.has_v_measured ? s.v_measured : velocity;
  // (F): p = p_nom + (v_cmd + omega z x r) T_st / 2 + k (v_meas - v_cmd) sqrt(h / g)
  const double capture = P[kCaptureGain] * std::sqrt(P[kHipHeight] / kGravity);
  const double hip_velocity[2] = {-middle.w * r[1], middle.w * r[0]};
  double p[3] = {p_nominal[0], p_nominal[1], p_nominal[2]};
  for (int j = 0; j < 2; ++j)
    p[j] +=
        (velocity[j] + hip_velocity[j]) * t_stance / 2.0 + capture * (measured[j] - velocity[j]);
  p[2] = nominal[2] + floor_height(s, p[0], p[1]);
  if (s.has_ground_offsets) p[2] += s.ground_offsets[i], p_nominal[2] += s.ground_offsets[i];
  Transform poses[kChecks + 1];
  for (int k = 0; k <= kChecks; ++k) {
    const GaitNumbers& F = Pf[k];
    double phases[kLegs], rates[kLegs], delta[2], delta_rate[2];
    for (int j = 0; j < kLegs; ++j)
      phases[j] = frac(theta[k] + F[kOffsets + j]), rates[j] = 1.0 / F[kPeriod];
    crawl_shift(F, kZeroNumbers, phases, rates, delta, delta_rate);
    const double cp = std::cos(planar[k].psi), sp = std::sin(planar[k].psi);
    const double px = planar[k].x + cp * delta[0] - sp * delta[1] + offset[0];
    const double py = planar[k].y + sp * delta[0] + cp * delta[1] + offset[1];
    double pose[6];
    body_pose(px, py, F[kHeight] + floor_height(s, px, py), planar[k].psi, cp, sp, s, pose);
    poses[k] = transform_of(pose);
  }
  s.step_shortened[i] = bounded_foothold(body, i, p, p_nominal, poses, kChecks + 1);
  for (int k = 0; k < 3; ++k) s.p_touchdown[i][k] = p[k];
}

}  // namespace

// (S): the swing foot's position, dp/ds and d2p/ds2 at s.
void swing(const double p0[3], const double p1[3], double s, double height, double p[3],
           double dp[3], double d2p[3]) noexcept {
  const Quintic h = quintic(s);
  for (int k = 0; k < 2; ++k)
    p[k] = p0[k] + (p1[k] - p0[k]) * h.b, dp[k] = (p1[k] - p0[k]) * h.db,
    d2p[k] = (p1[k] - p0[k]) * h.d2b;
  const double apex = std::max(p0[2], p1[2]) + height;
  if (s <= 0.5) {
    const Quintic v = quintic(2.0 * s);
    const double rise = apex - p0[2];
    p[2] = p0[2] + rise * v.b, dp[2] = 2.0 * rise * v.db, d2p[2] = 4.0 * rise * v.d2b;
  } else {
    const Quintic v = quintic(2.0 * s - 1.0);
    const double fall = p1[2] - apex;
    p[2] = apex + fall * v.b, dp[2] = 2.0 * fall * v.db, d2p[2] = 4.0 * fall * v.d2b;
  }
}


void start(const GaitNumbers& gait, const double command[3], const double attitude[2],
           PlannerState& s) noexcept {
  s = PlannerState{};
  s.clock_rate = 1.0 / gait[kPeriod];
  for (int k = 0; k < 3; ++k) s.command[k] = command[k];
  s.roll = s.pitch = 0.0;  // cos 1, sin 0
  set_attitude(s, attitude[0], attitude[1]);
  s.old_numbers = gait;
  s.old_numbers[kMoving] = 0.0;  // the start: the speed blends in over the first period
  s.new_numbers = gait;
  s.t0 = 0.0, s.duration = gait[kPeriod];
  for (int i = 0; i < kLegs; ++i) {
    s.contact[i] = true;
    s.cycles[i] = std::floor(gait[kOffsets + i]);
    for (int k = 0; k < 3; ++k) s.p_stance[i][k] = s.p_touchdown[i][k] = gait[kStance + 3 * i + k];
  }
}

namespace {

double cross2(const double* o, const double* a, const double* b) noexcept {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// |(x, y)|: the square root of the sum of squares, which is several times faster than std::hypot;
// hypot where the squares would overflow or underflow (a point 1e160 m away).
inline double norm2d(double x, double y) noexcept {
  const double n2 = x * x + y * y;
  return n2 < 1e300 && n2 > 1e-300 ? std::sqrt(n2) : std::hypot(x, y);
}

double segment_distance(const double* c, const double* a, const double* b) noexcept {
  const double ab[2] = {b[0] - a[0], b[1] - a[1]};
  const double length2 = ab[0] * ab[0] + ab[1] * ab[1];
  double t = length2 == 0.0 ? 0.0 : ((c[0] - a[0]) * ab[0] + (c[1] - a[1]) * ab[1]) / length2;
  t = std::min(std::max(t, 0.0), 1.0);
  return norm2d(c[0] - a[0] - t * ab[0], c[1] - a[1] - t * ab[1]);
}

}  // namespace

double support_margin(const double (*points)[2], int k, const double c[2]) noexcept {
  if (k <= 2) {  // no area (a trot's or a pace's two feet): minus the distance to the segment
    if (k == 0) return -std::numeric_limits<double>::infinity();
    const double *lo = points[0], *hi = points[k - 1];  // lexicographic order, as sorted below
    if (hi[0] < lo[0] || (hi[0] == lo[0] && hi[1] < lo[1])) std::swap(lo, hi);
    return -segment_distance(c, lo, hi);
  }
  // the distinct points in lexicographic order, then Andrew's monotone chain (counter-clockwise)
  std::array<double, 2> pts[Body::kMaxLegs];
  int n = 0;
  for (int i = 0; i < k; ++i) {  // insertion sort: a handful of feet
    std::array<double, 2> p{points[i][0], points[i][1]};
    int j = n++;
    for (; j > 0 && p < pts[j - 1]; --j) pts[j] = pts[j - 1];
    pts[j] = p;
  }
  n = int(std::unique(pts, pts + n) - pts);
  if (n == 0) return -std::numeric_limits<double>::infinity();
  const double* hull[2 * Body::kMaxLegs];
  int h = 0;
  for (int pass = 0; pass < 2; ++pass) {
    const double* chain[Body::kMaxLegs];
    int m = 0;
    for (int j = 0; j < n; ++j) {
      const double* p = pts[pass == 0 ? j : n - 1 - j].data();
      while (m >= 2 && cross2(chain[m - 2], chain[m - 1], p) <= 1e-12) --m;
      chain[m++] = p;
    }
    for (int j = 0; j + 1 < m; ++j) hull[h++] = chain[j];
  }
  if (h < 3) return -segment_distance(c, pts[0].data(), pts[n - 1].data());
  double inside = std::numeric_limits<double>::infinity();
  for (int j = 0; j < h; ++j) {
    const double *a = hull[j], *b = hull[(j + 1) % h];
    inside = std::min(inside, cross2(a, b, c) / norm2d(b[0] - a[0], b[1] - a[1]));
  }
  if (inside >= 0.0) return inside;
  double nearest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < h; ++j)
    nearest = std::min(nearest, segment_distance(c, hull[j], hull[(j + 1) % h]));
  return -nearest;
}

double py_mod(double x, double m) noexcept {
  const double r = std::fmod(x, m);
  if (r == 0.0) return 0.0;  // +0, as Python
  return r < 0.0 ? r + m : r;
}

bool solve3(const double* A, const double* b, double* x) noexcept {
  double y[3];
  const double det = adjugate_solve(A, b, y);
  if (!(det != 0.0) || !std::isfinite(det)) return false;
  x[0] = y[0], x[1] = y[1], x[2] = y[2];
  return std::isfinite(x[0] + x[1] + x[2]);
}

const EulerSequence& xyz_sequence() noexcept {
  static const EulerSequence seq = EulerSequence::from_code(0 + 3 * 1 + 9 * 2);  // "XYZ"
  return seq;
}

void set_attitude(PlannerState& s, double roll, double pitch) noexcept {
  if (roll != s.roll) s.roll = roll, s.cos_roll = std::cos(roll), s.sin_roll = std::sin(roll);
  if (pitch != s.pitch)
    s.pitch = pitch, s.cos_pitch = std::cos(pitch), s.sin_pitch = std::sin(pitch);
}

void change(PlannerState& s, const GaitNumbers* gait, const double* command) noexcept {
  if (command || gait) s.settled_scale = -1.0;
  if (command)
    for (int k = 0; k < 3; ++k) s.command[k] = command[k];
  if (!gait) return;
  GaitNumbers old;
  blended(s, s.t, old, nullptr);
  GaitNumbers nw = *gait;
  // the offsets move the shorter way round, and end there (floor(theta + o_i) never jumps), all
  // by the same c more, the c that makes the largest move smallest (reference: change)
  double delta[kLegs];
  for (int i = 0; i < kLegs; ++i)
    delta[i] = py_mod(nw[kOffsets + i] - old[kOffsets + i] + 0.5, 1.0) - 0.5;
  const double centre =
      (*std::max_element(delta, delta + kLegs) + *std::min_element(delta, delta + kLegs)) / 2.0;
  for (int i = 0; i < kLegs; ++i) nw[kOffsets + i] = old[kOffsets + i] + (delta[i] - centre);
  bool all_down = true;
  for (int i = 0; i < kLegs; ++i) all_down = all_down && s.contact[i];
  if (old[kDuty] >= 1.0 && all_down)  // no swing: the new offsets at once
    for (int i = 0; i < kLegs; ++i) old[kOffsets + i] = nw[kOffsets + i];
  s.old_numbers = old, s.new_numbers = nw, s.t0 = s.t;
  s.duration = blend_duration(old, nw);
}

void advance(const Body& body, PlannerState& s, double dt) noexcept {
  const double t1 = s.t + dt;
  GaitNumbers scratch(uninitialized);
  const GaitNumbers& P = numbers_at(s, t1, scratch);
  const double rate1 = 1.0 / P[kPeriod];
  s.theta += dt * (s.clock_rate + rate1) / 2.0;
  s.clock_rate = rate1;
  double target[3];
  s.speed_scale = target_of(s, P, target, settled_at(s, t1));  // the scale of command * moving
  Planar planar{s.x, s.y, s.psi, {s.v[0], s.v[1]}, s.w};
  ramp(planar, target, P[kAccel], P[kYawAccel], dt);
  s.x = planar.x, s.y = planar.y, s.psi = planar.psi, s.v[0] = planar.v[0], s.v[1] = planar.v[1],
  s.w = planar.w;
  s.t = t1;
  const double duty = P[kDuty];
  for (int i = 0; i < kLegs; ++i) {
    const double cycles = std::floor(s.theta + P[kOffsets + i]);
    const double phase = s.theta + P[kOffsets + i] - cycles;
    if (!s.contact[i]) {
      if (cycles > s.cycles[i]) {  // the phase wrapped: touch-down
        s.contact[i] = true;
        for (int k = 0; k < 3; ++k) s.p_stance[i][k] = s.p_touchdown[i][k];
        s.step_shortened[i] = false;
      }
    } else if (phase >= duty && 1.0 - phase >= kLiftoffFraction * (1.0 - duty)) {
      s.contact[i] = false;
      s.lift_phase[i] = phase;
      s.lift_height[i] = P[kStepHeight];
      plan_foothold(body, s, P, i, phase);
    }
    s.cycles[i] = cycles;
  }
}

void sample(const PlannerState& s, TickKinematics& out) noexcept {
  GaitNumbers scratch(uninitialized), rate_scratch(uninitialized);
  const GaitNumbers* rates_of = nullptr;
  const GaitNumbers& P = numbers_at(s, s.t, scratch, &rates_of, &rate_scratch);
  const GaitNumbers& Pd = *rates_of;
  double phases[kLegs], rates[kLegs];
  bool shortened = s.speed_scale < 1.0;
  for (int i = 0; i < kLegs; ++i) {
    phases[i] = frac(s.theta + P[kOffsets + i]);
    rates[i] = s.clock_rate + Pd[kOffsets + i];
    out.contact[i] = s.contact[i];
    if (s.contact[i]) {
      for (int k = 0; k < 3; ++k) out.feet[i][k] = s.p_stance[i][k], out.feet_rate[i][k] = 0.0;
      continue;
    }
    shortened = shortened || s.step_shortened[i];
    const double lift = s.lift_phase[i];
    double dp[3], d2p[3];
    swing(s.p_stance[i], s.p_touchdown[i], (phases[i] - lift) / (1.0 - lift), s.lift_height[i],
          out.feet[i], dp, d2p);
    for (int k = 0; k < 3; ++k) out.feet_rate[i][k] = dp[k] * rates[i] / (1.0 - lift);
  }
  double delta[2], delta_rate[2];
  crawl_shift(P, Pd, phases, rates, delta, delta_rate);
  const double c = std::cos(s.psi), sn = std::sin(s.psi);
  const double shift[2] = {c * delta[0] - sn * delta[1], sn * delta[0] + c * delta[1]};
  const double x = s.x + shift[0], y = s.y + shift[1];
  body_pose(x, y, P[kHeight] + floor_height(s, x, y), s.psi, c, sn, s, out.pose, out.R);
  const double planar[2] = {s.v[0] + delta_rate[0], s.v[1] + delta_rate[1]};
  out.linear[0] = c * planar[0] - sn * planar[1] - s.w * shift[1];
  out.linear[1] = sn * planar[0] + c * planar[1] + s.w * shift[0];
  out.linear[2] = Pd[kHeight];
  out.angular[0] = out.angular[1] = 0.0, out.angular[2] = s.w;
  out.shortened = shortened;
}

template <typename Model>
void plan_command(const dynamics::RobotStaticsModel<Model>& robot, const GaitNumbers& gait,
                  const double command[3], const double attitude[2], std::ptrdiff_t ticks,
                  double rate, const PlanRows& out, const PlanChange* changes, int n_changes) {
  const Body& body = robot.body;
  constexpr int W = 3 * kLegs;
  // each tick's feet velocities, body twist and rotation (27 doubles) and legs' IK statuses,
  // written before they are read (not zeroed)
  const std::unique_ptr<double[]> values(new double[std::size_t(ticks) * (W + 6 + 9)]);
  const std::unique_ptr<std::int8_t[]> statuses(new std::int8_t[std::size_t(ticks) * kLegs]);
  double* const feet_rate = values.get();
  double* const twist = feet_rate + std::size_t(ticks) * W;
  double* const rotation = twist + std::size_t(ticks) * 6;
  std::int8_t* const leg_status = statuses.get();
  PlannerState s;
  start(gait, command, attitude, s);
  TickKinematics k;
  int pending = 0;  // changes sorted by time (the binding sorts them)
  for (std::ptrdiff_t n = 0; n < ticks; ++n) {
    if (n) advance(body, s, double(n) / rate - s.t);  // the tick times without drift
    for (; pending < n_changes && changes[pending].time <= s.t + 1e-12; ++pending)
      change(s, changes[pending].gait, changes[pending].command);
    sample(s, k);
    std::copy(k.pose, k.pose + 6, out.pose + 6 * n);
    std::copy(&k.R[0][0], &k.R[0][0] + 9, rotation + 9 * n);
    std::copy(&k.feet[0][0], &k.feet[0][0] + W, out.feet + W * n);
    std::copy(&k.feet_rate[0][0], &k.feet_rate[0][0] + W, feet_rate + W * n);
    std::copy(k.linear, k.linear + 3, twist + 6 * n);
    std::copy(k.angular, k.angular + 3, twist + 6 * n + 3);
    for (int i = 0; i < kLegs; ++i) out.contact[kLegs * n + i] = k.contact[i];
    out.shortened[n] = k.shortened;
  }
  // the whole-body IK along the path, each tick seeded with the previous one
  kernels::body_ik_path<double>(body, out.pose, BodyPoseFormat::Euler, xyz_sequence(), out.feet,
                                nullptr, out.q, leg_status, ticks, true);
  // the statics along the path: G(q), the stance forces, qd, tau and the margin (gait_statics.cpp)
  plan_statics(robot, out, rotation, feet_rate, twist, leg_status, ticks);
}

#define SPOTKIN_INSTANTIATE(L)                                                                    \
  template void plan_command<dynamics::FloatingModel<double, L>>(                                 \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&, const GaitNumbers&, \
      const double*, const double*, std::ptrdiff_t, double, const PlanRows&, const PlanChange*,   \
      int);
SPOTKIN_INSTANTIATE(dynamics::kLanes64)
SPOTKIN_INSTANTIATE(dynamics::kMidLanes64)
SPOTKIN_INSTANTIATE(dynamics::kSmallLanes64)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::motion
