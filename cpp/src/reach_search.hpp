// The reach search's state and its steps (C), (E), (A) and the branch-following of (R), shared by
// cpp/src/reach.cpp (the search of one target) and cpp/src/reach_steps.cpp (the Gauss-Newton steps
// and the repair): python/spotkin/reference/reach.py's functions of the same names.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "spotkin/chain_ik/kernels.hpp"
#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/kernels/arm.hpp"
#include "spotkin/kernels/body.hpp"
#include "spotkin/kernels/chain.hpp"
#include "spotkin/kernels/leg.hpp"
#include "spotkin/motion/gait_plan.hpp"
#include "spotkin/motion/reach.hpp"
#include "spotkin/motion/reach_geometry.hpp"

namespace spotkin::motion::search {

using namespace geometry;  // NOLINT: the search is written over these

inline constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// A target's search: its inputs, the shared numbers, and scratch for the kernels.
template <typename Model>
struct Search {
  const dynamics::RobotStaticsModel<Model>& robot;
  const ReachArm& arm;
  const ReachCapsules& caps;
  const ReachShared& sh;
  const ReachInput& in;
  int legs, m;
};

// The poses of one evaluation: body transforms, legs, arm branches.
struct Evaluation {
  int n = 0;
  std::vector<double> p, T, legs, arm_q;
  std::vector<double> targets, seeds;  // scratch: the arm's targets, the legs' seeds (reused)
  std::vector<std::int8_t> leg_status, arm_status;
  std::vector<std::uint8_t> valid, exists, exact;
  std::vector<bool> legs_ok;
  void resize(int count, int n_legs) {
    n = count;
    p.resize(std::size_t(6 * count)), T.resize(std::size_t(16 * count));
    legs.resize(std::size_t(3 * n_legs * count)), leg_status.resize(std::size_t(n_legs * count));
    arm_q.resize(std::size_t(48 * count)), arm_status.resize(std::size_t(count));
    valid.resize(std::size_t(8 * count)), exists.resize(std::size_t(8 * count)),
        exact.resize(std::size_t(8 * count));
    legs_ok.assign(std::size_t(count), false);
    targets.resize(std::size_t(16 * count)), seeds.resize(std::size_t(3 * n_legs * count));
  }
};

struct Option {
  const Evaluation* ev;
  int pose, slot, order;
  double cost, margin = kNan;
  bool collides = false, checked = false;
};

struct Miss {
  double violation;
  int order, slot;
  double p[6], q_arm[6];
};

template <typename Model>
void body_T(const Search<Model>& s, const double* p, double* T) {
  double local[16];
  body_batch::pose_transform(p, BodyPoseFormat::Euler, xyz_sequence(), local);
  mul4(s.in.stance, local, T);
}

// (world <- body <- arm base)^-1 target: the arm's target in its base frame.
template <typename Model>
void arm_target(const Search<Model>& s, const double* T_body, double* out) {
  double base[16];
  mul4(T_body, s.arm.mount, base);
  const double* t = s.in.target;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      out[4 * r + c] = base[r] * t[c] + base[4 + r] * t[4 + c] + base[8 + r] * t[8 + c];
    const double d[3] = {t[3] - base[3], t[7] - base[7], t[11] - base[11]};
    out[4 * r + 3] = base[r] * d[0] + base[4 + r] * d[1] + base[8 + r] * d[2];
  }
  out[12] = out[13] = out[14] = 0.0, out[15] = 1.0;
}

inline void arm_ik_all(const ReachArm& arm, const double* poses, double* q, std::uint8_t* valid,
                       std::uint8_t* exists, std::uint8_t* exact, std::int8_t* status, int n) {
  if (arm.spot)
    kernels::arm_ik_all(*arm.spot, poses, PoseFormat::Matrix, static_cast<const double*>(nullptr),
                        q, valid, exists, status, n);
  else
    chain_ik::arm6_kernel(*arm.six, *arm.six_limits, poses, PoseFormat::Matrix, q, valid, exists,
                          exact, status, n);
}

// (E) at ev.n poses ev.p (legs unseeded, or seeded by seed_legs (n, 3 legs) when given).
// The legs' fallback for an unreachable foot ("nearest", as the reference's body_ik) only matters
// for the answer of an UNREACHABLE target (nearest = true there); elsewhere a failed leg is a
// failed pose.
template <typename Model>
void run(const Search<Model>& s, Evaluation& ev, const double* seed_legs = nullptr,
         bool nearest = false) {
  const int n = ev.n;
  double* targets = ev.targets.data();
  for (int k = 0; k < n; ++k) body_T(s, &ev.p[std::size_t(6 * k)], &ev.T[std::size_t(16 * k)]);
  kernels::body_ik(s.robot.body, ev.T.data(), BodyPoseFormat::Matrix, xyz_sequence(), s.in.feet,
                   true, seed_legs, ev.legs.data(), ev.leg_status.data(), n, nearest);
  for (int k = 0; k < n; ++k) {
    bool ok = true;
    for (int l = 0; l < s.legs; ++l) ok = ok && ev.leg_status[std::size_t(s.legs * k + l)] == 0;
    ev.legs_ok[std::size_t(k)] = ok;
    arm_target(s, &ev.T[std::size_t(16 * k)], targets + 16 * k);
  }
  arm_ik_all(s.arm, targets, ev.arm_q.data(), ev.valid.data(), ev.exists.data(), ev.exact.data(),
             ev.arm_status.data(), n);
}

template <typename Model>
void whole_q(const Search<Model>& s, const Evaluation& ev, int pose, int slot, double* q) {
  const int n3 = 3 * s.legs;
  std::copy_n(&ev.legs[std::size_t(n3 * pose)], n3, q);
  std::copy_n(&ev.arm_q[std::size_t(48 * pose + 6 * slot)], 6, q + n3);
}

// (G): 0.5 |r|^2.
template <typename Model>
double cost_of(const Search<Model>& s, const double* p, const double* q) {
  double sum = 0.0;
  for (int k = 0; k < 6; ++k) {
    const double r = (p[k] - s.in.p_ref[k]) / s.sh.w_p[k];
    sum += r * r;
  }
  for (int k = 0; k < s.m; ++k) {
    const double r = wrap_angle(q[k] - s.in.q_ref[k]) / s.sh.w_q[k];
    sum += r * r;
  }
  return 0.5 * sum;
}

template <typename Model>
void residual(const Search<Model>& s, const double* p, const double* q, double* r) {
  for (int k = 0; k < 6; ++k) r[k] = (p[k] - s.in.p_ref[k]) / s.sh.w_p[k];
  for (int k = 0; k < s.m; ++k) r[6 + k] = wrap_angle(q[k] - s.in.q_ref[k]) / s.sh.w_q[k];
}

// (M) of the whole robot at T_body with q.
template <typename Model>
double margin_of(const Search<Model>& s, const double* T_body, const double* q) {
  dynamics::StaticsRows<double> rows{T_body, 16, BodyPoseFormat::Matrix, q, s.m, true};
  double com[3];
  dynamics::robot_com(s.robot, xyz_sequence(), rows, com, 1);
  double feet[Body::kMaxLegs][2];
  for (int l = 0; l < s.legs; ++l) feet[l][0] = s.in.feet[3 * l], feet[l][1] = s.in.feet[3 * l + 1];
  return support_margin(feet, s.legs, com);
}

// Whether an arm capsule hits the body box or a leg capsule, or the ground (ref.collides).
template <typename Model>
bool collides(const Search<Model>& s, const double* q, const double* T_body) {
  const ReachCapsules& c = s.caps;
  if (!c.enabled || c.n_points < 2) return false;
  const int dof = int(s.arm.chain->dof());
  double frames[(6 + 2) * 16];
  kernels::chain_frames(*s.arm.chain, q + 3 * s.legs, frames, 1);
  (void)dof;
  double seg[Body::kMaxLegs][3][3];  // hip pitch, knee, foot (body frame)
  for (int l = 0; l < s.legs; ++l) {
    const Leg& leg = s.robot.body.legs[std::size_t(l)];
    const auto& g = leg.geometry();
    const auto& col = s.robot.body.columns[std::size_t(l)];
    const double t1 = g.sign[0] * q[col[0]], t2 = g.sign[1] * q[col[1]], t3 = g.sign[2] * q[col[2]];
    const double c1 = std::cos(t1), s1 = std::sin(t1), c2 = std::cos(t2), s2 = std::sin(t2);
    const double c3 = std::cos(t3), s3 = std::sin(t3);
    // Ry(t3) c, then b + that, Ry(t2) of it, a + that, Rx(t1) of each point
    const double kc[3] = {c3 * g.c[0] + s3 * g.c[2], g.c[1], -s3 * g.c[0] + c3 * g.c[2]};
    const double bf[3] = {g.b[0] + kc[0], g.b[1] + kc[1], g.b[2] + kc[2]};
    const double knee_l[3] = {g.a[0] + c2 * g.b[0] + s2 * g.b[2], g.a[1] + g.b[1],
                              g.a[2] - s2 * g.b[0] + c2 * g.b[2]};
    const double foot_l[3] = {g.a[0] + c2 * bf[0] + s2 * bf[2], g.a[1] + bf[1],
                              g.a[2] - s2 * bf[0] + c2 * bf[2]};
    const double* hip = s.robot.body.hips[std::size_t(l)].data();
    const double* pts[3] = {g.a, knee_l, foot_l};
    for (int k = 0; k < 3; ++k) {
      const double* v = pts[k];
      seg[l][k][0] = hip[0] + v[0];
      seg[l][k][1] = hip[1] + c1 * v[1] - s1 * v[2];
      seg[l][k][2] = hip[2] + s1 * v[1] + c1 * v[2];
    }
  }
  double ground = s.in.feet[2];  // the horizontal plane through the lowest foot point
  for (int l = 1; l < s.legs; ++l) ground = std::min(ground, s.in.feet[3 * l + 2]);
  const auto height = [&](const double* F) {  // a frame origin's height in the world
    return T_body[8] * F[3] + T_body[9] * F[7] + T_body[10] * F[11] + T_body[11];
  };
  for (int k = 0; k + 1 < c.n_points; ++k) {
    const double* F0 = frames + 16 * c.points[k];
    const double* F1 = frames + 16 * c.points[k + 1];
    const double a[3] = {F0[3], F0[7], F0[11]}, b[3] = {F1[3], F1[7], F1[11]};
    if (std::min(height(F0), height(F1)) < ground + c.radius) return true;
    if (c.vs_body[k] && segment_box_distance(a, b, c.box_centre, c.box_half) < c.radius)
      return true;
    for (int l = 0; l < s.legs; ++l) {
      if (c.vs_legs[k][l][0] && segment_distance(a, b, seg[l][0], seg[l][1]) < 2.0 * c.radius)
        return true;
      if (c.vs_legs[k][l][1] && segment_distance(a, b, seg[l][1], seg[l][2]) < 2.0 * c.radius)
        return true;
    }
  }
  return false;
}

template <typename Model>
void check(const Search<Model>& s, Option& o) {
  if (o.checked) return;
  double q[kReachMaxQ];
  whole_q(s, *o.ev, o.pose, o.slot, q);
  o.margin = margin_of(s, &o.ev->T[std::size_t(16 * o.pose)], q);
  o.collides = collides(s, q, &o.ev->T[std::size_t(16 * o.pose)]);
  o.checked = true;
}

// The options of an evaluation (every valid branch where the legs are OK), and its misses.
template <typename Model>
void options_of(const Search<Model>& s, const Evaluation& ev, const int* order,
                std::vector<Option>& out, std::vector<Miss>* misses) {
  double q[kReachMaxQ];
  const double* lo = s.sh.q_lower + 3 * s.legs;
  const double* hi = s.sh.q_upper + 3 * s.legs;
  for (int k = 0; k < ev.n; ++k) {
    if (!ev.legs_ok[std::size_t(k)]) continue;
    for (int slot = 0; slot < 8; ++slot) {
      const std::size_t at = std::size_t(8 * k + slot);
      if (ev.valid[at]) {
        whole_q(s, ev, k, slot, q);
        out.push_back({&ev, k, slot, order[k], cost_of(s, &ev.p[std::size_t(6 * k)], q)});
      } else if (misses && ev.exists[at]) {
        Miss miss{0.0, order[k], slot, {}, {}};
        for (int j = 0; j < 6; ++j) {
          const double v = ev.arm_q[48 * std::size_t(k) + std::size_t(6 * slot + j)];
          miss.violation += std::max(lo[j] - v, 0.0) + std::max(v - hi[j], 0.0);
          miss.q_arm[j] = v, miss.p[j] = ev.p[std::size_t(6 * k + j)];
        }
        misses->push_back(miss);
      }
    }
  }
}

// (A): the index of the chosen option (-1: none) and the status.
template <typename Model>
int choose(const Search<Model>& s, std::vector<Option>& options, std::int8_t& status) {
  std::vector<int> order(options.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = int(k);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Option &x = options[std::size_t(a)], &y = options[std::size_t(b)];
    if (x.cost != y.cost) return x.cost < y.cost;
    if (x.order != y.order) return x.order < y.order;
    return x.slot < y.slot;
  });
  for (const int k : order) {
    Option& o = options[std::size_t(k)];
    check(s, o);
    if (!o.collides && o.margin >= s.in.margin) return status = kReachOk, k;
  }
  int best = -1;
  for (const int k : order) {  // every option is checked: the reaching one of largest margin
    const Option& o = options[std::size_t(k)];
    if (!o.collides && (best < 0 || o.margin > options[std::size_t(best)].margin)) best = k;
  }
  status = best < 0 ? kReachUnreachable : kReachUnstable;
  return best;
}

// The state of the chosen answer.
struct Answer {
  double p[6], q[kReachMaxQ], T[16];
  int slot;
  double cost, margin;
};

// follow at n poses (n, 6) from the answer's branch: q (n, m) and ok (n).
template <typename Model>
void follow(const Search<Model>& s, const Answer& a, const double* poses, int n, Evaluation& ev,
            double* q, bool* ok) {
  ev.resize(n, s.legs);
  std::copy_n(poses, 6 * n, ev.p.data());
  const int n3 = 3 * s.legs;
  for (int k = 0; k < n; ++k) std::copy_n(a.q, n3, &ev.seeds[std::size_t(n3 * k)]);
  run(s, ev, ev.seeds.data());
  for (int k = 0; k < n; ++k) {
    double best = kInf;
    int slot = -1;
    for (int j = 0; j < 8; ++j) {
      if (!ev.valid[std::size_t(8 * k + j)]) continue;
      double move = 0.0;
      for (int i = 0; i < 6; ++i)
        move = std::max(move,
                        std::abs(wrap_angle(ev.arm_q[48 * std::size_t(k) + std::size_t(6 * j + i)] -
                                            a.q[n3 + i])));
      if (move < best) best = move, slot = j;
    }
    ok[k] = ev.legs_ok[std::size_t(k)] && slot >= 0;
    if (slot >= 0) whole_q(s, ev, k, slot, q + std::size_t(s.m) * std::size_t(k));
    ev.arm_status[std::size_t(k)] = std::int8_t(slot);  // the branch taken (reused field)
  }
}
// (R): Gauss-Newton steps on the answer's body pose (cpp/src/reach_steps.cpp).
template <typename Model>
void refine(const Search<Model>& s, Answer& a);

// (F)'s damped least squares from z (12): z and e (6) in place, and (E) at its final body pose in
// `end` (with options of order `order`); it stops early where an option there is feasible, tried
// every REPAIR_CHECK iterations (cpp/src/reach_steps.cpp).
template <typename Model>
void descend(const Search<Model>& s, double* z, double* e, int order, Evaluation& end);

}  // namespace spotkin::motion::search
