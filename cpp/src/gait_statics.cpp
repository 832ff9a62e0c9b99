// The gait plan's statics along its path (spotkin/motion/gait_plan.hpp, plan_statics): per block of
// ticks, the floating model's gravity torques G(q) in lanes, then each leg's Jacobian, the
// stance forces (W), the residual, the joint velocities and tau = G - J^T f with a tick per lane
// (statics_lanes, one clone per instruction-set level), and the support margin (M) tick by tick.
#include <algorithm>
#include <cmath>
#include <vector>

#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/isa.hpp"
#include "spotkin/leg.hpp"
#include "spotkin/motion/gait_plan.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::motion {

namespace {

constexpr int kSub = dynamics::kStaticsSubBlock;
constexpr int kW = 3 * kLegs;

// A block of ticks, a tick per lane: one array per component.
struct StaticsLanes {
  // inputs: the body's rotation (row-major) and position, the feet and their velocities (world),
  // the body's twist (world), G's body wrench [f; n], each leg's joint angles and torques G (the
  // leg's joint order), 1 / 0 per leg down, 1 / 0 valid
  double R[9][kSub], t[3][kSub], feet[kLegs][3][kSub], rate[kLegs][3][kSub], v[3][kSub], w[3][kSub];
  double wrench[6][kSub], q[kLegs][3][kSub], G[kLegs][3][kSub], down[kLegs][kSub], valid[kSub];
  // each leg's cos and sin of theta1, theta2, theta2 + theta3 (Leg::jacobian_from)
  double cos_theta[kLegs][3][kSub], sin_theta[kLegs][3][kSub];
  // outputs: the centre of mass (world), the residual wrench [force; moment], qd and tau per leg
  double com[3][kSub], residual[6][kSub], qd[kLegs][3][kSub], tau[kLegs][3][kSub];
};

// 1 where a condition holds, else 0: the lanes' masks are doubles, so that the loop over lanes
// has one element type and no control flow (GCC then vectorises it).
SPOTKIN_INLINE double mask(bool condition) noexcept { return condition ? 1.0 : 0.0; }
SPOTKIN_INLINE double finite_mask(double x) noexcept { return mask(x - x == 0.0); }

// One tick (lane i) of the statics, branch-free. weight: m g.
SPOTKIN_INLINE void statics_tick(StaticsLanes& b, const Leg* legs, int i, double weight) noexcept {
  constexpr double nan = quiet_nan<double>();
  const double F[3] = {0.0, 0.0, weight};  // the weight the feet carry, -m g
  // the centre of mass across gravity from G's body wrench [f; n] (f = -m g, n = c x f):
  // c = f x n / |f|^2 (its part along g moves no moment), then in the world
  const double g0 = b.wrench[0][i], g1 = b.wrench[1][i], g2 = b.wrench[2][i], g3 = b.wrench[3][i],
               g4 = b.wrench[4][i], g5 = b.wrench[5][i];
  const double ff = g0 * g0 + g1 * g1 + g2 * g2, inv = ff > 0.0 ? 1.0 / ff : 0.0;
  const double cb[3] = {(g1 * g5 - g2 * g4) * inv, (g2 * g3 - g0 * g5) * inv,
                        (g0 * g4 - g1 * g3) * inv};
  double c[3];
#pragma GCC unroll 3
  for (int r = 0; r < 3; ++r)
    c[r] =
        b.t[r][i] + b.R[3 * r][i] * cb[0] + b.R[3 * r + 1][i] * cb[1] + b.R[3 * r + 2][i] * cb[2];
  // (W) in closed form, the feet down in the legs' order (a foot up adds exact zeros). The
  // minimum-norm forces with sum f_i = F and, in least squares, sum (p_i - c) x f_i = 0 are
  // f_i = F / k + y x s_i, s_i = p_i - p_mean, where K y = -m, m = (p_mean - c) x F and
  // K = sum (|s_i|^2 I - s_i s_i^T) (= (M N)(M N)^T of the reference's Helmert form, so
  // y = pinv(K) (-m) is its z = pinv(M N) (-M f_0) mapped back). Feet off one line: K is invertible
  // and the moment balances; on one line (two feet, say) along d, K = S (I - d d^T) with
  // S = sum |s_i|^2, and the moment about the line is left (the residual). k = 0: no force.
  double k = 0.0, mean[3] = {0.0, 0.0, 0.0}, down[kLegs];
#pragma GCC unroll 4
  for (int l = 0; l < kLegs; ++l) {
    down[l] = b.down[l][i];  // 1 or 0
    k += down[l];
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) mean[a] += down[l] != 0.0 ? b.feet[l][a][i] : 0.0;
  }
  const double k_safe = k > 0.0 ? k : 1.0;
#pragma GCC unroll 3
  for (int a = 0; a < 3; ++a) mean[a] /= k_safe;
  double s[kLegs][3], K[9] = {}, S = 0.0, longest = -1.0, d[3] = {0.0, 0.0, 0.0};
#pragma GCC unroll 4
  for (int l = 0; l < kLegs; ++l) {
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) s[l][a] = down[l] != 0.0 ? b.feet[l][a][i] - mean[a] : 0.0;
    const double n2 = s[l][0] * s[l][0] + s[l][1] * s[l][1] + s[l][2] * s[l][2];
    S += n2;
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a)
#pragma GCC unroll 3
      for (int e = 0; e < 3; ++e) K[3 * a + e] += (a == e ? n2 : 0.0) - s[l][a] * s[l][e];
    const double longer = down[l] * mask(n2 > longest);
    longest = longer != 0.0 ? n2 : longest;
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) d[a] = longer != 0.0 ? s[l][a] : d[a];
  }
  const double r[3] = {mean[0] - c[0], mean[1] - c[1], mean[2] - c[2]};
  const double m[3] = {r[1] * F[2] - r[2] * F[1], r[2] * F[0] - r[0] * F[2],
                       r[0] * F[1] - r[1] * F[0]};
  const double minus_m[3] = {-m[0], -m[1], -m[2]};
  // full rank: the smallest eigenvalue above ~1e-9 of the largest (det = l1 l2 l3 against (tr /
  // 2)^3)
  double y_full[3];
  const double det = adjugate_solve(K, minus_m, y_full);
  const double rank3 = mask(k >= 3.0) * mask(det > 1e-9 * S * S * S);
  const double full = rank3 * mask(det != 0.0) * finite_mask(det);
  // else the feet on a line along d: y = -(m - d (d . m)) / S
  const double line = (1.0 - rank3) * mask(S > 0.0);
  const double n = std::sqrt(line != 0.0 ? longest : 1.0), S_safe = line != 0.0 ? S : 1.0;
  double along = 0.0, y[3];
#pragma GCC unroll 3
  for (int a = 0; a < 3; ++a) d[a] /= n, along += d[a] * m[a];
#pragma GCC unroll 3
  for (int a = 0; a < 3; ++a)
    y[a] = full != 0.0 ? y_full[a] : line != 0.0 ? -(m[a] - d[a] * along) / S_safe : 0.0;
  double total[3] = {0.0, 0.0, 0.0}, moment[3] = {0.0, 0.0, 0.0}, f[kLegs][3];
#pragma GCC unroll 4
  for (int l = 0; l < kLegs; ++l) {
    const double* sl = s[l];
    const double ys[3] = {y[1] * sl[2] - y[2] * sl[1], y[2] * sl[0] - y[0] * sl[2],
                          y[0] * sl[1] - y[1] * sl[0]};
    double arm[3];
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) {
      f[l][a] = down[l] != 0.0 ? F[a] / k_safe + ys[a] : 0.0;
      total[a] += f[l][a], arm[a] = b.feet[l][a][i] - c[a];
    }
    const double mi[3] = {arm[1] * f[l][2] - arm[2] * f[l][1], arm[2] * f[l][0] - arm[0] * f[l][2],
                          arm[0] * f[l][1] - arm[1] * f[l][0]};
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) moment[a] += down[l] != 0.0 ? mi[a] : 0.0;
  }
  const double valid = b.valid[i];
#pragma GCC unroll 3
  for (int a = 0; a < 3; ++a) {
    b.com[a][i] = c[a];
    b.residual[a][i] = valid != 0.0 ? F[a] - total[a] : nan;
    b.residual[3 + a][i] = valid != 0.0 ? (k == 0.0 ? 0.0 : -moment[a]) : nan;
  }
  const double t[3] = {b.t[0][i], b.t[1][i], b.t[2][i]}, v[3] = {b.v[0][i], b.v[1][i], b.v[2][i]},
               w[3] = {b.w[0][i], b.w[1][i], b.w[2][i]};
#pragma GCC unroll 4
  for (int l = 0; l < kLegs; ++l) {
    // qd_l = J_l^-1 R^T (pdot_l - v - w x (p_l - t)): the foot's velocity relative to the hip
    const double dp[3] = {b.feet[l][0][i] - t[0], b.feet[l][1][i] - t[1], b.feet[l][2][i] - t[2]};
    const double u[3] = {b.rate[l][0][i] - v[0] - (w[1] * dp[2] - w[2] * dp[1]),
                         b.rate[l][1][i] - v[1] - (w[2] * dp[0] - w[0] * dp[2]),
                         b.rate[l][2][i] - v[2] - (w[0] * dp[1] - w[1] * dp[0])};
    double relative[3], fb[3], J[9], qd[3];
#pragma GCC unroll 3
    for (int e = 0; e < 3; ++e) {
      relative[e] = b.R[e][i] * u[0] + b.R[3 + e][i] * u[1] + b.R[6 + e][i] * u[2];
      fb[e] = b.R[e][i] * f[l][0] + b.R[3 + e][i] * f[l][1] + b.R[6 + e][i] * f[l][2];  // R^T f
    }
    {  // d foot / d q_l (body frame, row-major), as Leg::jacobian
      const double c[3] = {b.cos_theta[l][0][i], b.cos_theta[l][1][i], b.cos_theta[l][2][i]},
                   sn[3] = {b.sin_theta[l][0][i], b.sin_theta[l][1][i], b.sin_theta[l][2][i]};
      legs[l].jacobian_from(c, sn, J);
    }
    const double det_J = adjugate_solve(J, relative, qd);
    const double solved =
        mask(det_J != 0.0) * finite_mask(det_J) * finite_mask(qd[0] + qd[1] + qd[2]);
#pragma GCC unroll 3
    for (int j = 0; j < 3; ++j) {
      b.qd[l][j][i] = solved != 0.0 ? qd[j] : nan;
      // tau = G - (R J)^T f = G - J^T (R^T f)
      b.tau[l][j][i] =
          valid != 0.0 ? b.G[l][j][i] - (J[j] * fb[0] + J[3 + j] * fb[1] + J[6 + j] * fb[2]) : nan;
    }
  }
}

SPOTKIN_CLONES((__attribute__((noinline)) inline), void, statics_lanes,
               (StaticsLanes & b, const Leg* legs, double weight), (b, legs, weight),
               for (int l = 0; l < kLegs;
                    ++l) {  // Leg::jacobian's angles, each leg's sines and cosines in lanes
                 double angle[3][kSub];
                 for (int i = 0; i < kSub; ++i) {
                   angle[0][i] = legs[l].sign(0) * b.q[l][0][i],
                   angle[1][i] = legs[l].sign(1) * b.q[l][1][i];
                   angle[2][i] = legs[l].sign(1) * b.q[l][1][i] + legs[l].sign(2) * b.q[l][2][i];
                 }
                 for (int k = 0; k < 3; ++k)
                   vector_math::sincos(angle[k], b.sin_theta[l][k], b.cos_theta[l][k], kSub);
               } for (int i = 0; i < kSub; ++i) statics_tick(b, legs, i, weight);)

}  // namespace

template <typename Model>
void plan_statics(const dynamics::RobotStaticsModel<Model>& robot, const PlanRows& out,
                  const double* rotation, const double* feet_rate, const double* twist,
                  const std::int8_t* leg_status, std::ptrdiff_t ticks) {
  const Body& body = robot.body;
  const int nq = robot.floating.nq(), nv = robot.floating.nv();
  std::vector<double> qf(std::size_t(nq) * kSub), wrench(std::size_t(nv) * kSub);
  double g_body[3 * kSub];
  StaticsLanes lanes;
  constexpr double nan = quiet_nan<double>();
  for (std::ptrdiff_t b0 = 0; b0 < ticks; b0 += kSub) {
    const int m = int(std::min<std::ptrdiff_t>(kSub, ticks - b0));
    for (int i = 0; i < m; ++i) {
      const double* R = rotation + 9 * (b0 + i);
      const double* q = out.q + kW * (b0 + i);
      double* row = qf.data() + std::ptrdiff_t(nq) * i;
      std::fill(row, row + nq, 0.0);
      row[6] = 1.0;  // the body at the origin, the identity quaternion
      bool finite_q = true;
      for (int j = 0; j < kW; ++j) finite_q = finite_q && std::isfinite(q[j]);
      lanes.valid[i] = finite_q ? 1.0 : 0.0;
      if (finite_q)
        for (int j = 0; j < kW; ++j) row[7 + j] = q[j];
      for (int r = 0; r < 3; ++r) g_body[3 * i + r] = -kGravity * R[6 + r];  // R^T (0, 0, -g)
    }
    dynamics::floating_rnea_k(robot.floating, dynamics::Rows<double>{qf.data(), nq}, nullptr,
                              nullptr, dynamics::Rows<double>{g_body, 3}, wrench.data(), 0, m,
                              false);
    // into the lanes; the lanes past the block repeat its last tick
    for (int i = 0; i < kSub; ++i) {
      const int src = std::min(i, m - 1);
      const std::ptrdiff_t n = b0 + src;
      const double* R = rotation + 9 * n;
      const double* pose = out.pose + 6 * n;
      const double* feet = out.feet + kW * n;
      const double* rate = feet_rate + kW * n;
      const double* tw = twist + 6 * n;
      const double* G = wrench.data() + std::ptrdiff_t(nv) * src;
      for (int e = 0; e < 9; ++e) lanes.R[e][i] = R[e];
      for (int e = 0; e < 3; ++e)
        lanes.t[e][i] = pose[e], lanes.v[e][i] = tw[e], lanes.w[e][i] = tw[3 + e];
      for (int e = 0; e < 6; ++e) lanes.wrench[e][i] = G[e];
      for (int l = 0; l < kLegs; ++l) {
        const auto& col = body.columns[std::size_t(l)];
        for (int e = 0; e < 3; ++e) {
          lanes.feet[l][e][i] = feet[3 * l + e], lanes.rate[l][e][i] = rate[3 * l + e];
          lanes.G[l][e][i] = G[6 + col[std::size_t(e)]];
          lanes.q[l][e][i] = out.q[kW * n + col[std::size_t(e)]];
        }
        lanes.down[l][i] = out.contact[kLegs * n + l] ? 1.0 : 0.0;
      }
      if (i >= m) lanes.valid[i] = lanes.valid[m - 1];
    }
    statics_lanes(lanes, body.legs.data(), robot.mass * kGravity);
    for (int i = 0; i < m; ++i) {
      const std::ptrdiff_t n = b0 + i;
      std::int8_t worst = leg_status[kLegs * n];
      for (int l = 1; l < kLegs; ++l) worst = std::max(worst, leg_status[kLegs * n + l]);
      out.status[n] = worst;
      double flat[kLegs][2];
      int feet_down = 0;
      for (int l = 0; l < kLegs; ++l)
        if (out.contact[kLegs * n + l])
          flat[feet_down][0] = out.feet[kW * n + 3 * l],
          flat[feet_down][1] = out.feet[kW * n + 3 * l + 1], ++feet_down;
      const double c[3] = {lanes.com[0][i], lanes.com[1][i], lanes.com[2][i]};
      out.margin[n] = lanes.valid[i] != 0.0 ? support_margin(flat, feet_down, c) : nan;
      for (int a = 0; a < 6; ++a) out.residual[6 * n + a] = lanes.residual[a][i];
      for (int l = 0; l < kLegs; ++l) {
        const auto& col = body.columns[std::size_t(l)];
        for (int j = 0; j < 3; ++j) {
          out.qd[kW * n + col[std::size_t(j)]] = lanes.qd[l][j][i];
          out.tau[kW * n + col[std::size_t(j)]] = lanes.tau[l][j][i];
        }
      }
    }
  }
}

#define SPOTKIN_INSTANTIATE(L)                                                                 \
  template void plan_statics<dynamics::FloatingModel<double, L>>(                              \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&, const PlanRows&, \
      const double*, const double*, const double*, const std::int8_t*, std::ptrdiff_t);
SPOTKIN_INSTANTIATE(dynamics::kLanes64)
SPOTKIN_INSTANTIATE(dynamics::kMidLanes64)
SPOTKIN_INSTANTIATE(dynamics::kSmallLanes64)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::motion
