// The closed-loop gait controller (spotkin/motion/controller.hpp): the reference controller's tick
// (python/spotkin/reference/controller.py) in double, for one robot; the binding runs robots on
// threads.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "spotkin/dense.hpp"
#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/dynamics/statics.hpp"
#include "spotkin/kernels/body.hpp"
#include "spotkin/motion/controller.hpp"

namespace spotkin::motion {

namespace {

constexpr double kPiValue = 3.14159265358979323846;
constexpr int W = 3 * kLegs;

// R of a quaternion (x, y, z, w), s = 2 / |q|^2 (a non-unit quaternion scaled).
void rotation_of(const double* quaternion, double R[3][3]) noexcept {
  const double x = quaternion[0], y = quaternion[1], z = quaternion[2], w = quaternion[3];
  const double norm = x * x + y * y + z * z + w * w;
  const double s = norm > 0 ? 2.0 / norm : 0.0;
  R[0][0] = 1 - s * (y * y + z * z), R[0][1] = s * (x * y - w * z), R[0][2] = s * (x * z + w * y);
  R[1][0] = s * (x * y + w * z), R[1][1] = 1 - s * (x * x + z * z), R[1][2] = s * (y * z - w * x);
  R[2][0] = s * (x * z - w * y), R[2][1] = s * (y * z + w * x), R[2][2] = 1 - s * (x * x + y * y);
}

// The rotation vector (axis times angle) of R.
void rotation_vector(const double R[3][3], double out[3]) noexcept {
  const double c = std::min(std::max((R[0][0] + R[1][1] + R[2][2] - 1.0) / 2.0, -1.0), 1.0);
  const double angle = std::acos(c);
  const double axis[3] = {R[2][1] - R[1][2], R[0][2] - R[2][0], R[1][0] - R[0][1]};
  const double s = std::sin(angle);
  for (int k = 0; k < 3; ++k) out[k] = s < 1e-9 ? 0.5 * axis[k] : axis[k] * (angle / (2.0 * s));
}

// (c, a, b) of the least-squares plane z = c + a x + b y through the ground under the feet (each
// foot_z above it), the minimum-norm one when the feet do not fix it (as lstsq).
void ground_plane(const double (*points)[3], const double* foot_z, double out[3]) noexcept {
  Eigen::Matrix<double, kLegs, 3> X;
  Eigen::Matrix<double, kLegs, 1> z;
  for (int i = 0; i < kLegs; ++i)
    X(i, 0) = 1.0, X(i, 1) = points[i][0], X(i, 2) = points[i][1], z(i) = points[i][2] - foot_z[i];
  const Eigen::Vector3d plane = dense::lstsq43(X, z);
  for (int k = 0; k < 3; ++k) out[k] = plane(k);
}

// x = H^-1 rhs for a symmetric positive definite H (n x n, n <= W, row-major) by Cholesky; false
// when H is not positive definite.
bool cholesky_solve(double* H, int n, double* x) noexcept {
  for (int j = 0; j < n; ++j) {
    double d = H[j * W + j];
    for (int k = 0; k < j; ++k) d -= H[j * W + k] * H[j * W + k];
    if (!(d > 0.0)) return false;
    const double l = std::sqrt(d);
    H[j * W + j] = l;
    for (int i = j + 1; i < n; ++i) {
      double v = H[i * W + j];
      for (int k = 0; k < j; ++k) v -= H[i * W + k] * H[j * W + k];
      H[i * W + j] = v / l;
    }
  }
  for (int i = 0; i < n; ++i) {  // L y = rhs, then L^T x = y
    double v = x[i];
    for (int k = 0; k < i; ++k) v -= H[i * W + k] * x[k];
    x[i] = v / H[i * W + i];
  }
  for (int i = n - 1; i >= 0; --i) {
    double v = x[i];
    for (int k = i + 1; k < n; ++k) v -= H[k * W + i] * x[k];
    x[i] = v / H[i * W + i];
  }
  return true;
}

// (T): the loaded feet's forces minimising alpha |S (A f - b)|^2 + sum_l |(G_l - J_l^T f_l) /
// tau_max|^2
// + eps |f / (m g)|^2, a foot that would pull unloaded and the rest solved again; the residual b -
// A f. The normal equations by blocks: A's block of foot j is [I; [r_j]x], so (A^T S A)_jk = S_f +
// s_m ((r_j . r_k) I - r_k r_j^T) (S = diag(S_f, s_m I)) and (A^T y)_j = y_f + y_m x r_j; D_j =
// diag(1 / tau_max) J_j^T.
void torque_weighted_forces(const double (*feet)[3], const bool* loaded, const double* com,
                            double mass, const double (*jacobians)[9],
                            const double (*leg_gravity)[3], const double (*limits)[3], double h,
                            const double* wrench, double (*forces)[3],
                            double residual[6]) noexcept {
  const double weight = mass * kGravity;
  double b[6] = {0.0, 0.0, weight, 0.0, 0.0, 0.0};
  for (int a = 0; a < 6; ++a) b[a] += wrench[a];
  const double s_f[3] = {kTorqueHorizontal / (weight * weight),
                         kTorqueHorizontal / (weight * weight), 1.0 / (weight * weight)};
  const double s_m = 1.0 / ((weight * h) * (weight * h));
  const double y[6] = {kTorqueAlpha * s_f[0] * b[0], kTorqueAlpha * s_f[1] * b[1],
                       kTorqueAlpha * s_f[2] * b[2], kTorqueAlpha * s_m * b[3],
                       kTorqueAlpha * s_m * b[4],    kTorqueAlpha * s_m * b[5]};
  bool down[kLegs];
  double r[kLegs][3], D[kLegs][9], Dg[kLegs][3];
  for (int j = 0; j < kLegs; ++j) {
    down[j] = loaded[j], forces[j][0] = forces[j][1] = forces[j][2] = 0.0;
    for (int a = 0; a < 3; ++a) r[j][a] = feet[j][a] - com[a];
    for (int row = 0; row < 3; ++row) {  // D_j[row][col] = J_j[col][row] / tau_max[row]
      const double scale = 1.0 / limits[j][row];
      for (int col = 0; col < 3; ++col) D[j][3 * row + col] = scale * jacobians[j][3 * col + row];
    }
    for (int col = 0; col < 3; ++col) {
      double v = 0.0;
      for (int row = 0; row < 3; ++row)
        v += D[j][3 * row + col] * (leg_gravity[j][row] / limits[j][row]);
      Dg[j][col] = v;
    }
  }
  int slots[kLegs], k = 0;
  double f[W];
  // joints held at kTorqueCap of their limit (sign in cap, 0 free): the penalty
  // kTorqueCapWeight (d_j . f - (g_j - s c))^2 for each, added one round at a time
  double cap[kLegs][3] = {};
  int cap_rounds = 0;
  while (true) {
    k = 0;
    for (int j = 0; j < kLegs; ++j)
      if (down[j]) slots[k++] = j;
    if (k == 0) {
      for (int a = 0; a < 6; ++a) residual[a] = b[a];
      return;
    }
    double H[W * W];
    for (int sj = 0; sj < k; ++sj)
      for (int sk = 0; sk <= sj; ++sk) {
        const double* rj = r[slots[sj]];
        const double* rk = r[slots[sk]];
        const double dot = rj[0] * rk[0] + rj[1] * rk[1] + rj[2] * rk[2];
        for (int p = 0; p < 3; ++p)
          for (int q = 0; q < 3; ++q) {
            double v = kTorqueAlpha * s_m * ((p == q ? dot : 0.0) - rk[p] * rj[q]);
            if (p == q) v += kTorqueAlpha * s_f[p];
            if (sj == sk) {
              const double* Dj = D[slots[sj]];
              v += Dj[p] * Dj[q] + Dj[3 + p] * Dj[3 + q] + Dj[6 + p] * Dj[6 + q];
              for (int row = 0; row < 3; ++row)
                if (cap[slots[sj]][row] != 0.0)
                  v += kTorqueCapWeight * Dj[3 * row + p] * Dj[3 * row + q];
              if (p == q) v += kTorqueEps / (weight * weight);
            }
            H[(3 * sj + p) * W + 3 * sk + q] = v;
            H[(3 * sk + q) * W + 3 * sj + p] = v;
          }
      }
    for (int sj = 0; sj < k; ++sj) {  // alpha A^T (S b) + D^T g
      const double* rj = r[slots[sj]];
      const double ym_x_r[3] = {y[4] * rj[2] - y[5] * rj[1], y[5] * rj[0] - y[3] * rj[2],
                                y[3] * rj[1] - y[4] * rj[0]};
      for (int p = 0; p < 3; ++p) f[3 * sj + p] = y[p] + ym_x_r[p] + Dg[slots[sj]][p];
      const int j = slots[sj];
      for (int row = 0; row < 3; ++row)
        if (cap[j][row] != 0.0) {
          const double goal = leg_gravity[j][row] / limits[j][row] - cap[j][row] * kTorqueCap;
          for (int p = 0; p < 3; ++p) f[3 * sj + p] += kTorqueCapWeight * D[j][3 * row + p] * goal;
        }
    }
    if (!cholesky_solve(H, 3 * k, f)) {  // not reached: eps I keeps H positive definite
      for (int a = 0; a < 3 * k; ++a) f[a] = 0.0;
    }
    bool pulling = false;
    for (int slot = 0; slot < k; ++slot)
      if (f[3 * slot + 2] < 0.0) down[slots[slot]] = false, pulling = true;
    if (pulling) continue;
    bool capped = false;  // a joint past kTorqueCap of its limit: held there, solved again
    if (cap_rounds < kTorqueCapRounds) {
      for (int slot = 0; slot < k; ++slot) {
        const int j = slots[slot];
        for (int row = 0; row < 3; ++row) {
          const double* d = D[j] + 3 * row;
          const double u = leg_gravity[j][row] / limits[j][row] -
                           (d[0] * f[3 * slot] + d[1] * f[3 * slot + 1] + d[2] * f[3 * slot + 2]);
          if (cap[j][row] == 0.0 && std::fabs(u) > kTorqueCap)
            cap[j][row] = u > 0.0 ? 1.0 : -1.0, capped = true;
        }
      }
      cap_rounds += capped;
    }
    if (!capped) break;
  }
  double total[3] = {0.0, 0.0, 0.0}, moment[3] = {0.0, 0.0, 0.0};
  for (int slot = 0; slot < k; ++slot) {
    const int j = slots[slot];
    const double* fj = f + 3 * slot;
    for (int a = 0; a < 3; ++a) forces[j][a] = fj[a], total[a] += fj[a];
    moment[0] += r[j][1] * fj[2] - r[j][2] * fj[1];
    moment[1] += r[j][2] * fj[0] - r[j][0] * fj[2];
    moment[2] += r[j][0] * fj[1] - r[j][1] * fj[0];
  }
  for (int a = 0; a < 3; ++a) residual[a] = b[a] - total[a], residual[3 + a] = b[3 + a] - moment[a];
}

// Each force with f_z >= 0 and its horizontal part within kFriction f_z.
void friction(double (*forces)[3]) noexcept {
  for (int j = 0; j < kLegs; ++j) {
    double* f = forces[j];
    f[2] = std::max(f[2], 0.0);
    const double horizontal = std::hypot(f[0], f[1]), limit = kFriction * f[2];
    const double scale = horizontal > limit ? limit / std::max(horizontal, 1e-300) : 1.0;
    f[0] *= scale, f[1] *= scale;
  }
}

void transform_matrix(const double R[3][3], const double* t, double* M) noexcept {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) M[4 * r + c] = R[r][c];
    M[4 * r + 3] = t[r];
  }
  M[12] = M[13] = M[14] = 0.0, M[15] = 1.0;
}

}  // namespace

template <typename Model>
void controller_tick(const dynamics::RobotStaticsModel<Model>& robot,
                     const ControllerConfig& config, const GaitNumbers* gaits, int start_gait,
                     int new_gait, ControllerMemory& memory, const ControllerInput& in,
                     ControllerOutput& out) {
  const Body& body = robot.body;
  const double h = config.h, t = in.t;
  const double* position = in.position;
  const double* v = in.linear_velocity;
  const double* w = in.angular_velocity;
  const double* q = in.q;
  double R[3][3];
  rotation_of(in.quaternion, R);
  const double yaw = std::atan2(R[1][0], R[0][0]);
  // 1. the measured feet: t + R (hip + FK)
  double feet_meas[kLegs][3];
  for (int l = 0; l < kLegs; ++l) {
    const auto& col = body.columns[std::size_t(l)];
    const double q_leg[3] = {q[col[0]], q[col[1]], q[col[2]]};
    double p[3];
    body.legs[std::size_t(l)].forward(q_leg, p);
    for (int r = 0; r < 3; ++r) p[r] += body.hips[std::size_t(l)][std::size_t(r)];
    for (int r = 0; r < 3; ++r)
      feet_meas[l][r] = position[r] + R[r][0] * p[0] + R[r][1] * p[1] + R[r][2] * p[2];
  }
  PlannerState& plan = memory.plan;
  if (!memory.started) {  // start: the robot where it stands, the shift blending in
    memory.started = true;
    memory.gait = new_gait >= 0 ? new_gait : start_gait;
    const GaitNumbers& gait = gaits[memory.gait];
    const double zero[3] = {0.0, 0.0, 0.0}, level[2] = {0.0, 0.0};
    start(gait, zero, level, plan);
    plan.t = plan.t0 = t;
    plan.x = position[0], plan.y = position[1], plan.psi = yaw;
    for (int l = 0; l < kLegs; ++l)
      for (int r = 0; r < 3; ++r) plan.p_stance[l][r] = plan.p_touchdown[l][r] = feet_meas[l][r];
    plan.old_numbers[kComShift] = 0.0;
    memory.t = t;
    memory.settle = t + plan.duration;
    double foot_z[kLegs];
    for (int l = 0; l < kLegs; ++l) foot_z[l] = gait[kStance + 3 * l + 2];
    for (int l = 0; l < kLegs; ++l)
      for (int r = 0; r < 3; ++r) memory.ground_points[l][r] = feet_meas[l][r];
    ground_plane(memory.ground_points, foot_z, memory.ground);
  }
  if (new_gait >= 0 && new_gait != memory.gait) {
    memory.gait = new_gait;
    change(plan, &gaits[new_gait], nullptr);
  }
  double dt = t - memory.t;
  memory.t = t;
  dt = std::min(std::max(dt, 0.0), kMaxGap);
  for (int k = 0; k < 3; ++k) plan.command[k] = in.command[k];
  plan.has_v_measured = plan.has_p_measured = plan.has_ground = true;
  for (int k = 0; k < 2; ++k)
    plan.v_measured[k] = v[k] - memory.shift_rate[k],
    plan.p_measured[k] = position[k] - memory.shift[k];
  for (int k = 0; k < 3; ++k) plan.ground[k] = memory.ground[k];
  bool before[kLegs];
  for (int l = 0; l < kLegs; ++l) before[l] = plan.contact[l];
  double settling =
      std::min(dt, std::max(0.0, memory.settle - plan.t));  // the start: the clock held
  for (int l = 0; l < kLegs; ++l)
    if (memory.reaching[l] && memory.depth[l] < kReachDown * h)
      settling = dt;  // a foot still reaching
  plan.t += settling;
  if (dt - settling > 0.0) advance(body, plan, dt - settling);
  GaitNumbers P(uninitialized), Pd(uninitialized);  // blended writes both whole
  blended(plan, plan.t, P, &Pd);
  const double period = P[kPeriod], duty = P[kDuty];
  double nominal_z[kLegs], phases[kLegs], phase_rates[kLegs];
  for (int l = 0; l < kLegs; ++l) {
    nominal_z[l] = P[kStance + 3 * l + 2];
    phases[l] = frac(plan.theta + P[kOffsets + l]);
    phase_rates[l] = plan.clock_rate + Pd[kOffsets + l];
  }
  const double swing_time = std::max((1.0 - duty) * period, 1e-3);
  const double descent = 2.0 * (P[kStepHeight] + 1e-3 * h) / swing_time;
  // 2. contacts: touch-downs (planned, early, late) and the stance feet
  bool touched[kLegs];
  for (int l = 0; l < kLegs; ++l) touched[l] = in.contact ? in.contact[l] : true;
  for (int i = 0; i < kLegs; ++i) {
    if (plan.contact[i] && !before[i]) {  // the planned touch-down
      memory.reaching[i] = !touched[i], memory.depth[i] = 0.0;
      if (touched[i])
        for (int r = 0; r < 3; ++r) plan.p_stance[i][r] = feet_meas[i][r];
    } else if (!plan.contact[i]) {
      const double lift = plan.lift_phase[i];
      const double progress = (phases[i] - lift) / (1.0 - lift);
      if (in.contact && touched[i] && 0.5 < progress && progress < 1.0) {  // early: lands here
        plan.contact[i] = true, memory.reaching[i] = false;
        for (int r = 0; r < 3; ++r) plan.p_stance[i][r] = feet_meas[i][r];
      }
    } else if (memory.reaching[i]) {
      if (touched[i]) {
        memory.reaching[i] = false;
        for (int r = 0; r < 3; ++r) plan.p_stance[i][r] = feet_meas[i][r];
      } else if (memory.depth[i] < kReachDown * h) {
        const double step = std::min(descent * std::max(dt, 0.0), kReachDown * h - memory.depth[i]);
        memory.depth[i] += step;
        plan.p_stance[i][2] -= step;
      }
    } else if (touched[i]) {
      for (int r = 0; r < 3; ++r)
        plan.p_stance[i][r] = feet_meas[i][r];  // held where it is measured
    }
    if (plan.contact[i] && touched[i] && !memory.reaching[i]) {
      for (int r = 0; r < 3; ++r) memory.ground_points[i][r] = feet_meas[i][r];
      memory.landed[i] = true;
    }
    memory.landed[i] = memory.landed[i] && plan.contact[i];
  }
  bool loaded[kLegs];
  for (int l = 0; l < kLegs; ++l) loaded[l] = memory.landed[l] && !memory.reaching[l];
  // the ground plane, low-passed; each leg's footholds on its slope through its own last contact
  double target[3];
  ground_plane(memory.ground_points, nominal_z, target);
  const double ground_blend = std::min(1.0, std::max(dt, 0.0) / (kGroundTime * period));
  for (int k = 0; k < 3; ++k) memory.ground[k] += (target[k] - memory.ground[k]) * ground_blend;
  const double* g = memory.ground;
  plan.has_ground_offsets = true;
  for (int l = 0; l < kLegs; ++l) {
    const double own = memory.ground_points[l][2] - nominal_z[l];
    const double plane = g[0] + g[1] * memory.ground_points[l][0];
    plan.ground_offsets[l] = own - plane - g[2] * memory.ground_points[l][1];
  }
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double slope_x = g[1] * cy + g[2] * sy, slope_y = -g[1] * sy + g[2] * cy;
  set_attitude(plan, config.attitude[0] + kTerrainRoll * std::atan(slope_y),
               config.attitude[1] - kTerrainFollow * std::atan(slope_x));
  for (int k = 0; k < 3; ++k) plan.ground[k] = g[k];
  // 3. re-anchor the planar reference (with its shift) to the measured body
  const double epsi = py_mod(plan.psi - yaw + kPiValue, 2.0 * kPiValue) - kPiValue;
  if (std::fabs(epsi) > kYawAnchor) plan.psi -= epsi - std::copysign(kYawAnchor, epsi);
  double delta[2], delta_rate[2];
  crawl_shift(P, Pd, phases, phase_rates, delta, delta_rate);
  const double cp = std::cos(plan.psi), sp = std::sin(plan.psi);
  const double shift[2] = {cp * delta[0] - sp * delta[1], sp * delta[0] + cp * delta[1]};
  memory.shift[0] = shift[0], memory.shift[1] = shift[1];
  const double ex = plan.x + shift[0] - position[0], ey = plan.y + shift[1] - position[1];
  // the bound: kAnchor h, plus the most the crawl's sway (C) moves the body (its planned lead)
  double sway[2] = {0.0, 0.0};
  for (int l = 0; l < kLegs; ++l)
    sway[0] += std::fabs(P[kSway + 2 * l]), sway[1] += std::fabs(P[kSway + 2 * l + 1]);
  const double bound = kAnchor * h + P[kComShift] * std::hypot(sway[0], sway[1]),
               norm = std::hypot(ex, ey);
  if (norm > bound) {
    plan.x -= ex * (1.0 - bound / norm);
    plan.y -= ey * (1.0 - bound / norm);
  }
  // 4. the body reference
  const double x_ref = plan.x + shift[0], y_ref = plan.y + shift[1];
  const double floor = floor_height(plan, x_ref, y_ref);
  double R_ref[3][3];
  body_pose(x_ref, y_ref, floor + P[kHeight], plan.psi, cp, sp, plan, out.body_pose);
  Body::euler_rotation(xyz_sequence(), out.body_pose + 3, R_ref);  // body_transform of the pose
  const double* t_ref = out.body_pose;
  const double planar[2] = {plan.v[0] + delta_rate[0], plan.v[1] + delta_rate[1]};
  double v_ref[3] = {cp * planar[0] - sp * planar[1] - plan.w * shift[1],
                     sp * planar[0] + cp * planar[1] + plan.w * shift[0], 0.0};
  v_ref[2] = g[1] * v_ref[0] + g[2] * v_ref[1] + Pd[kHeight];
  const double w_ref[3] = {0.0, 0.0, plan.w};
  memory.shift_rate[0] = v_ref[0] - (cp * plan.v[0] - sp * plan.v[1]);
  memory.shift_rate[1] = v_ref[1] - (sp * plan.v[0] + cp * plan.v[1]);
  // the feet
  double feet_rate[kLegs][3] = {}, feet_accel[kLegs][3] = {};
  for (int i = 0; i < kLegs; ++i) {
    for (int r = 0; r < 3; ++r) out.feet[i][r] = plan.p_stance[i][r];
    if (plan.contact[i]) {
      if (memory.reaching[i] && memory.depth[i] < kReachDown * h) feet_rate[i][2] = -descent;
      continue;
    }
    const double lift = plan.lift_phase[i];
    const double progress = (phases[i] - lift) / (1.0 - lift);
    double dp[3], d2p[3];
    swing(plan.p_stance[i], plan.p_touchdown[i], progress, plan.lift_height[i], out.feet[i], dp,
          d2p);
    const double rate = phase_rates[i] / (1.0 - lift);
    for (int r = 0; r < 3; ++r)
      feet_rate[i][r] = dp[r] * phase_rates[i] / (1.0 - lift),
      feet_accel[i][r] = d2p[r] * (rate * rate);
  }
  // 5. joints: loaded legs at the reference pose, the others (swinging, reaching) at the measured
  // one
  double poses[32], seed[2 * W], solved[2 * W];
  std::int8_t status[2 * kLegs];
  transform_matrix(R_ref, t_ref, poses);
  transform_matrix(R, position, poses + 16);
  const double* seed_row = memory.has_q ? memory.q : q;
  std::copy(seed_row, seed_row + W, seed), std::copy(seed_row, seed_row + W, seed + W);
  kernels::body_ik<double>(body, poses, BodyPoseFormat::Matrix, xyz_sequence(), &out.feet[0][0],
                           true, seed, solved, status, 2, true);
  bool stance_column[W];
  for (int l = 0; l < kLegs; ++l)
    for (int j = 0; j < 3; ++j)
      stance_column[body.columns[std::size_t(l)][std::size_t(j)]] = loaded[l];
  for (int j = 0; j < W; ++j) {
    const double chosen = stance_column[j] ? solved[j] : solved[W + j];
    out.q[j] = std::isfinite(chosen) ? chosen : q[j];  // a leg without an answer holds where it is
  }
  std::copy(out.q, out.q + W, memory.q);
  memory.has_q = true;
  // joint velocities: qd_l = (R J_l)^-1 (pdot_l - v - w x (p_l - t)), the reference twist for
  // loaded legs
  double jacobians[kLegs][9];
  for (int l = 0; l < kLegs; ++l) {
    const auto& col = body.columns[std::size_t(l)];
    const double q_leg[3] = {q[col[0]], q[col[1]], q[col[2]]};
    double J[9];
    body.legs[std::size_t(l)].jacobian(q_leg, J);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        jacobians[l][3 * r + c] = R[r][0] * J[c] + R[r][1] * J[3 + c] + R[r][2] * J[6 + c];
    const double* vl = loaded[l] ? v_ref : v;
    const double* wl = loaded[l] ? w_ref : w;
    const double* origin = loaded[l] ? t_ref : position;
    const double d[3] = {out.feet[l][0] - origin[0], out.feet[l][1] - origin[1],
                         out.feet[l][2] - origin[2]};
    const double rel[3] = {feet_rate[l][0] - vl[0] - (wl[1] * d[2] - wl[2] * d[1]),
                           feet_rate[l][1] - vl[1] - (wl[2] * d[0] - wl[0] * d[2]),
                           feet_rate[l][2] - vl[2] - (wl[0] * d[1] - wl[1] * d[0])};
    double qd[3];
    if (!solve3(jacobians[l], rel, qd)) qd[0] = qd[1] = qd[2] = 0.0;
    for (int j = 0; j < 3; ++j) out.qd[col[std::size_t(j)]] = std::isfinite(qd[j]) ? qd[j] : 0.0;
  }
  // 6. feedforward: gravity, the weight and the virtual body wrench on the loaded feet
  const int nq = robot.floating.nq();
  double qf[2 * dynamics::kStaticsMaxQ], wrench_rows[dynamics::kStaticsMaxQ], com2[6], g_body[3];
  for (int k = 0; k < 3; ++k) g_body[k] = -kGravity * R[2][k];  // R^T (0, 0, -g)
  {
    double* row = qf;
    std::fill(row, row + nq, 0.0);
    row[6] = 1.0;
    for (int j = 0; j < W; ++j) row[7 + j] = q[j];
    dynamics::floating_rnea_k(robot.floating, dynamics::Rows<double>{qf, nq}, nullptr, nullptr,
                              dynamics::Rows<double>{g_body, 3}, wrench_rows, 0, 1, false);
    double q2[2 * W];  // the centre of mass at the measured and at the reference pose
    std::copy(q, q + W, q2), std::copy(out.q, out.q + W, q2 + W);
    double poses2[32];
    std::copy(poses + 16, poses + 32, poses2), std::copy(poses, poses + 16, poses2 + 16);
    const dynamics::StaticsRows<double> rows{poses2, 16, BodyPoseFormat::Matrix, q2, W, false};
    dynamics::robot_com(robot, xyz_sequence(), rows, com2, 2);
  }
  const double* com = com2;
  const double* com_ref = com2 + 3;
  const double mass = robot.mass, wb = config.body_omega;
  if (memory.has_v_ref && dt > 0.0) {  // the reference's acceleration, low-passed
    const double blend = std::min(1.0, dt / (kAccelTime * period));
    for (int k = 0; k < 3; ++k)
      memory.a_ref[k] += ((v_ref[k] - memory.v_ref[k]) / dt - memory.a_ref[k]) * blend;
  }
  std::copy(v_ref, v_ref + 3, memory.v_ref);
  memory.has_v_ref = true;
  double* wrench = out.wrench;
  for (int k = 0; k < 3; ++k)
    wrench[k] = mass * (wb * wb * (t_ref[k] - position[k]) + 2.0 * wb * (v_ref[k] - v[k]) +
                        memory.a_ref[k]);
  const double horizontal = std::hypot(wrench[0], wrench[1]);
  if (horizontal > kHorizontalWrench * mass * kGravity) {
    const double scale = kHorizontalWrench * mass * kGravity / horizontal;
    wrench[0] *= scale, wrench[1] *= scale;
  }
  double inertia[3][3], RI[3][3];  // R I R^T
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      RI[r][c] = R[r][0] * config.body_inertia[c] + R[r][1] * config.body_inertia[3 + c] +
                 R[r][2] * config.body_inertia[6 + c];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      inertia[r][c] = RI[r][0] * R[c][0] + RI[r][1] * R[c][1] + RI[r][2] * R[c][2];
  double error_R[3][3], e_R[3];  // R_ref R^T
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      error_R[r][c] = R_ref[r][0] * R[c][0] + R_ref[r][1] * R[c][1] + R_ref[r][2] * R[c][2];
  rotation_vector(error_R, e_R);
  double angular[3];
  for (int k = 0; k < 3; ++k) angular[k] = wb * wb * e_R[k] + 2.0 * wb * (w_ref[k] - w[k]);
  for (int r = 0; r < 3; ++r)
    wrench[3 + r] =
        inertia[r][0] * angular[0] + inertia[r][1] * angular[1] + inertia[r][2] * angular[2];
  double leg_gravity[kLegs][3], limits[kLegs][3];
  for (int l = 0; l < kLegs; ++l)
    for (int j = 0; j < 3; ++j) {
      const int column = body.columns[std::size_t(l)][std::size_t(j)];
      leg_gravity[l][j] = wrench_rows[6 + column];
      limits[l][j] = std::min(config.effort[column], 1e12);
    }
  torque_weighted_forces(feet_meas, loaded, com, mass, jacobians, leg_gravity, limits, h, wrench,
                         out.forces, out.residual);
  friction(out.forces);
  for (int j = 0; j < W; ++j) out.tau[j] = wrench_rows[6 + j];
  for (int l = 0; l < kLegs; ++l) {
    const auto& col = body.columns[std::size_t(l)];
    const double* J = jacobians[l];
    if (loaded[l]) {
      for (int j = 0; j < 3; ++j)
        out.tau[col[std::size_t(j)]] -=
            J[j] * out.forces[l][0] + J[3 + j] * out.forces[l][1] + J[6 + j] * out.forces[l][2];
    } else if (!plan.contact[l]) {  // a swing leg: M_leg qdd, qdd from the swing's acceleration
      double qdd[3];
      if (!solve3(J, feet_accel[l], qdd) || !std::isfinite(qdd[0] + qdd[1] + qdd[2])) continue;
      for (int j = 0; j < 3; ++j)
        out.tau[col[std::size_t(j)]] += config.leg_inertia[l][3 * j] * qdd[0] +
                                        config.leg_inertia[l][3 * j + 1] * qdd[1] +
                                        config.leg_inertia[l][3 * j + 2] * qdd[2];
    }
  }
  for (int j = 0; j < W; ++j) {
    out.clipped[j] = std::fabs(out.tau[j]) > config.effort[j];
    out.tau[j] = std::min(std::max(out.tau[j], -config.effort[j]), config.effort[j]);
    out.kp[j] = stance_column[j] ? config.stance_kp[j] : config.kp[j];
    out.kd[j] = stance_column[j] ? config.stance_kd[j] : config.kd[j];
  }
  // the details
  double flat[kLegs][2];
  int k = 0;
  for (int l = 0; l < kLegs; ++l)
    if (plan.contact[l]) flat[k][0] = out.feet[l][0], flat[k][1] = out.feet[l][1], ++k;
  out.margin = support_margin(flat, k, com_ref);
  out.measured_margin = support_margin(flat, k, com);
  std::int8_t worst = status[0];
  for (int l = 1; l < kLegs; ++l) worst = std::max(worst, status[l]);
  out.status = worst;
  bool shortened = plan.speed_scale < 1.0;
  for (int l = 0; l < kLegs; ++l) {
    shortened = shortened || (plan.step_shortened[l] && !plan.contact[l]);
    out.contact[l] = plan.contact[l], out.loaded[l] = loaded[l],
    out.reaching[l] = memory.reaching[l];
  }
  out.shortened = shortened;
  std::copy(g, g + 3, out.ground);
}

#define SPOTKIN_INSTANTIATE(L)                                                  \
  template void controller_tick<dynamics::FloatingModel<double, L>>(            \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&,   \
      const ControllerConfig&, const GaitNumbers*, int, int, ControllerMemory&, \
      const ControllerInput&, ControllerOutput&);
SPOTKIN_INSTANTIATE(dynamics::kLanes64)
SPOTKIN_INSTANTIATE(dynamics::kMidLanes64)
SPOTKIN_INSTANTIATE(dynamics::kSmallLanes64)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::motion
