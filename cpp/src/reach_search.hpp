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
#include "spotkin/vector_math.hpp"

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
  int same_feet = -1;  // the block's first target with the same stance and feet (its own index)
};

// The poses of one evaluation: body transforms, legs, arm branches. Pose k belongs to the target
// owner[k] of the block (cpp/src/reach.cpp: the kernels run the poses of every target at once).
struct Evaluation {
  int n = 0;
  std::vector<int> owner;
  std::vector<const double*> local;          // S <- body of pose k when known (null: from p)
  std::vector<double> p, T, L, legs, arm_q;  // L: S <- body (T = stance L)
  std::vector<double> targets, seeds, feet;  // scratch: arm targets, legs' seeds, feet (reused)
  // scratch of the legs' distinct poses: pose k's legs are those of distinct pose at[k]
  std::vector<int> at, first;
  std::vector<double> distinct_T, distinct_feet, distinct_legs;
  std::vector<std::int8_t> distinct_status;
  std::vector<std::int8_t> leg_status, arm_status;
  std::vector<std::uint8_t> valid, exists, exact;
  std::vector<bool> legs_ok;
  void resize(int count, int n_legs) {
    n = count;
    p.resize(std::size_t(6 * count)), T.resize(std::size_t(16 * count)),
        L.resize(std::size_t(16 * count));
    legs.resize(std::size_t(3 * n_legs * count)), leg_status.resize(std::size_t(n_legs * count));
    arm_q.resize(std::size_t(48 * count)), arm_status.resize(std::size_t(count));
    valid.resize(std::size_t(8 * count)), exists.resize(std::size_t(8 * count)),
        exact.resize(std::size_t(8 * count));
    legs_ok.assign(std::size_t(count), false);
    targets.resize(std::size_t(16 * count)), seeds.resize(std::size_t(3 * n_legs * count));
    feet.resize(std::size_t(3 * n_legs * count)), owner.assign(std::size_t(count), 0);
    local.assign(std::size_t(count), nullptr);
  }
};

// An answer's arm branches from pose k of ev.
inline void branches_from(const Evaluation& ev, int k, double* branches, std::uint8_t* valid) {
  std::copy_n(&ev.arm_q[std::size_t(48 * k)], 48, branches);
  std::copy_n(&ev.valid[std::size_t(8 * k)], 8, valid);
}

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

// (E) at ev.n poses ev.p, pose k for target S[ev.owner[k]] (legs unseeded, or seeded by
// seed_legs (n, 3 legs) when given), each kernel called once for every pose. The kernels answer
// each pose as if alone (up to the arm's scalar and lane paths: an ulp), so a target's answer does
// not depend on the thread count. The legs' fallback for an unreachable foot ("nearest", as the
// reference's body_ik) only matters for the answer of an UNREACHABLE target (nearest = true
// there); elsewhere a failed leg is a failed pose.
template <typename Model>
void run(const Search<Model>* S, Evaluation& ev, const double* seed_legs = nullptr,
         bool nearest = false) {
  const int n = ev.n, legs = S[0].legs, n3 = 3 * legs;
  double* targets = ev.targets.data();
  for (int k = 0; k < n; ++k) {
    const Search<Model>& s = S[ev.owner[std::size_t(k)]];
    double* L = &ev.L[std::size_t(16 * k)];
    if (const double* local = ev.local[std::size_t(k)])
      std::copy_n(local, 16, L);
    else
      body_batch::pose_transform(&ev.p[std::size_t(6 * k)], BodyPoseFormat::Euler, xyz_sequence(),
                                 L);
    mul4(s.in.stance, L, &ev.T[std::size_t(16 * k)]);
    std::copy_n(s.in.feet, n3, &ev.feet[std::size_t(n3 * k)]);
  }
  // The legs: a candidate of (C) (ev.local) at targets of the same stance and feet is one pose for
  // them (the same T and feet, bit for bit), solved once; the others one by one. Unseeded only.
  constexpr int kLocals = kReachCandidates + 1;
  int owners = 0;
  for (int k = 0; k < n; ++k) owners = std::max(owners, ev.owner[std::size_t(k)] + 1);
  ev.at.resize(std::size_t(n));
  if (!seed_legs) ev.first.assign(std::size_t(owners * kLocals), -1);  // seeded: no sharing
  int distinct = 0;
  for (int k = 0; k < n; ++k) {
    const double* local = ev.local[std::size_t(k)];
    int* first = nullptr;
    if (local && !seed_legs) {
      const Search<Model>& s = S[ev.owner[std::size_t(k)]];
      const int candidate = int((local - &s.sh.local[0][0]) / 16);
      first = &ev.first[std::size_t(s.same_feet * kLocals + candidate)];
      if (*first >= 0) {
        ev.at[std::size_t(k)] = *first;
        continue;
      }
    }
    if (first) *first = distinct;
    ev.at[std::size_t(k)] = distinct++;
  }
  if (distinct == n) {
    kernels::body_ik(S[0].robot.body, ev.T.data(), BodyPoseFormat::Matrix, xyz_sequence(),
                     ev.feet.data(), false, seed_legs, ev.legs.data(), ev.leg_status.data(), n,
                     nearest);
  } else {
    ev.distinct_T.resize(std::size_t(16 * distinct)),
        ev.distinct_feet.resize(std::size_t(n3 * distinct));
    ev.distinct_legs.resize(std::size_t(n3 * distinct));
    ev.distinct_status.resize(std::size_t(legs * distinct));
    for (int k = 0, next = 0; k < n; ++k) {
      if (ev.at[std::size_t(k)] != next) continue;  // a pose met before
      std::copy_n(&ev.T[std::size_t(16 * k)], 16, &ev.distinct_T[std::size_t(16 * next)]);
      std::copy_n(&ev.feet[std::size_t(n3 * k)], n3, &ev.distinct_feet[std::size_t(n3 * next)]);
      ++next;
    }
    kernels::body_ik(S[0].robot.body, ev.distinct_T.data(), BodyPoseFormat::Matrix, xyz_sequence(),
                     ev.distinct_feet.data(), false, seed_legs, ev.distinct_legs.data(),
                     ev.distinct_status.data(), distinct, nearest);
    for (int k = 0; k < n; ++k) {
      const std::size_t j = std::size_t(ev.at[std::size_t(k)]);
      std::copy_n(&ev.distinct_legs[n3 * j], n3, &ev.legs[std::size_t(n3 * k)]);
      std::copy_n(&ev.distinct_status[std::size_t(legs) * j], legs,
                  &ev.leg_status[std::size_t(legs * k)]);
    }
  }
  for (int k = 0; k < n; ++k) {
    bool ok = true;
    for (int l = 0; l < legs; ++l) ok = ok && ev.leg_status[std::size_t(legs * k + l)] == 0;
    ev.legs_ok[std::size_t(k)] = ok;
    arm_target(S[ev.owner[std::size_t(k)]], &ev.T[std::size_t(16 * k)], targets + 16 * k);
  }
  arm_ik_all(S[0].arm, targets, ev.arm_q.data(), ev.valid.data(), ev.exists.data(), ev.exact.data(),
             ev.arm_status.data(), n);
}

template <typename Model>
void whole_q(const Search<Model>& s, const Evaluation& ev, int pose, int slot, double* q) {
  const int n3 = 3 * s.legs;
  std::copy_n(&ev.legs[std::size_t(n3 * pose)], n3, q);
  std::copy_n(&ev.arm_q[std::size_t(48 * pose + 6 * slot)], 6, q + n3);
}

// |r|^2 over the body pose and q's first `count` joints (the legs' when count = 3 legs).
template <typename Model>
double squares_of(const Search<Model>& s, const double* p, const double* q, int count) {
  double sum = 0.0;
  for (int k = 0; k < 6; ++k) {
    const double r = (p[k] - s.in.p_ref[k]) / s.sh.w_p[k];
    sum += r * r;
  }
  for (int k = 0; k < count; ++k) {
    const double r = wrap_angle(q[k] - s.in.q_ref[k]) / s.sh.w_q[k];
    sum += r * r;
  }
  return sum;
}

// sum plus |r|^2 over q's joints from..m - 1 (in order: the same sums as one loop).
template <typename Model>
double add_squares(const Search<Model>& s, double sum, const double* q, int from) {
  for (int k = from; k < s.m; ++k) {
    const double r = wrap_angle(q[k - from] - s.in.q_ref[k]) / s.sh.w_q[k];
    sum += r * r;
  }
  return sum;
}

// (G): 0.5 |r|^2.
template <typename Model>
double cost_of(const Search<Model>& s, const double* p, const double* q) {
  return 0.5 * squares_of(s, p, q, s.m);
}

template <typename Model>
void residual(const Search<Model>& s, const double* p, const double* q, double* r) {
  for (int k = 0; k < 6; ++k) r[k] = (p[k] - s.in.p_ref[k]) / s.sh.w_p[k];
  for (int k = 0; k < s.m; ++k) r[6 + k] = wrap_angle(q[k] - s.in.q_ref[k]) / s.sh.w_q[k];
}

// The sphere around the segment a-b: its centre and radius.
inline void sphere(const double* a, const double* b, double* centre, double& radius) {
  double sum = 0.0;
  for (int i = 0; i < 3; ++i) {
    centre[i] = 0.5 * (a[i] + b[i]);
    sum += (b[i] - a[i]) * (b[i] - a[i]);
  }
  radius = 0.5 * std::sqrt(sum);
}

// Scratch of the batched constraint checks (reused).
struct Checks {
  std::vector<double> T, q, com, arm_q, frames, margin;
  std::vector<std::uint8_t> hits;
  std::vector<int> owner;
  std::vector<const double*> local;  // S <- body of pose k when known (null: from p)
  void resize(int n, int m, int dof) {
    T.resize(std::size_t(16 * n)), q.resize(std::size_t(m * n)), com.resize(std::size_t(3 * n));
    arm_q.resize(std::size_t(dof * n)), frames.resize(std::size_t((dof + 2) * 16 * n));
    margin.resize(std::size_t(n)), hits.resize(std::size_t(n)), owner.resize(std::size_t(n));
  }
};

// (M) of the whole robot at n samples, sample i for target S[owner[i]] at body c.T (n, 16) and
// c.q (n, m), in one call of the centre-of-mass kernel: c.margin (n).
template <typename Model>
void margins_of(const Search<Model>* S, Checks& c, int n) {
  const Search<Model>& s0 = S[0];
  dynamics::StaticsRows<double> rows{c.T.data(), 16,   BodyPoseFormat::Matrix,
                                     c.q.data(), s0.m, true};
  dynamics::robot_com(s0.robot, xyz_sequence(), rows, c.com.data(), n);
  for (int i = 0; i < n; ++i) {
    const Search<Model>& s = S[c.owner[std::size_t(i)]];
    double feet[Body::kMaxLegs][2];
    for (int l = 0; l < s.legs; ++l)
      feet[l][0] = s.in.feet[3 * l], feet[l][1] = s.in.feet[3 * l + 1];
    c.margin[std::size_t(i)] = support_margin(feet, s.legs, &c.com[std::size_t(3 * i)]);
  }
}

// Whether an arm capsule hits the body box or a leg capsule, or the ground (ref.collides), with the
// arm's frames (dof + 2, 4, 4) in the body. A pair whose bounding spheres are apart by the
// capsules' radii is skipped: the segments' distance is at least the spheres'.
template <typename Model>
bool collides_framed(const Search<Model>& s, const double* q, const double* T_body,
                     const double* frames) {
  const ReachCapsules& c = s.caps;
  double seg[Body::kMaxLegs][3][3];  // hip pitch, knee, foot (body frame)
  double centre[Body::kMaxLegs][2][3], half[Body::kMaxLegs][2];
  double angle[3 * Body::kMaxLegs], sines[3 * Body::kMaxLegs], cosines[3 * Body::kMaxLegs];
  for (int l = 0; l < s.legs; ++l) {
    const auto& g = s.robot.body.legs[std::size_t(l)].geometry();
    const auto& col = s.robot.body.columns[std::size_t(l)];
    for (int j = 0; j < 3; ++j) angle[3 * l + j] = g.sign[j] * q[col[j]];
  }
  vector_math::sincos(angle, sines, cosines, 3 * s.legs);  // every leg joint's at once
  for (int l = 0; l < s.legs; ++l) {
    const auto& g = s.robot.body.legs[std::size_t(l)].geometry();
    const double c1 = cosines[3 * l], s1 = sines[3 * l], c2 = cosines[3 * l + 1],
                 s2 = sines[3 * l + 1], c3 = cosines[3 * l + 2], s3 = sines[3 * l + 2];
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
    for (int part = 0; part < 2; ++part)
      sphere(seg[l][part], seg[l][part + 1], centre[l][part], half[l][part]);
  }
  double ground = s.in.feet[2];  // the horizontal plane through the lowest foot point
  for (int l = 1; l < s.legs; ++l) ground = std::min(ground, s.in.feet[3 * l + 2]);
  const auto height = [&](const double* F) {  // a frame origin's height in the world
    return T_body[8] * F[3] + T_body[9] * F[7] + T_body[10] * F[11] + T_body[11];
  };
  const double reach = 2.0 * c.radius * (1.0 + 1e-9) + 1e-12;  // the pairs' test, with slack
  for (int k = 0; k + 1 < c.n_points; ++k) {
    const double* F0 = frames + 16 * c.points[k];
    const double* F1 = frames + 16 * c.points[k + 1];
    const double a[3] = {F0[3], F0[7], F0[11]}, b[3] = {F1[3], F1[7], F1[11]};
    if (std::min(height(F0), height(F1)) < ground + c.radius) return true;
    double mid[3], r;
    sphere(a, b, mid, r);
    if (c.vs_body[k]) {
      double g2 = 0.0;  // the sphere's centre from the box (axis-aligned in the body)
      for (int i = 0; i < 3; ++i) {
        const double g = std::max(std::abs(mid[i] - c.box_centre[i]) - c.box_half[i], 0.0);
        g2 += g * g;
      }
      if (std::sqrt(g2) - r < 0.5 * reach &&
          segment_box_distance(a, b, c.box_centre, c.box_half) < c.radius)
        return true;
    }
    for (int l = 0; l < s.legs; ++l)
      for (int part = 0; part < 2; ++part) {
        if (!c.vs_legs[k][l][part]) continue;
        const double* o = centre[l][part];
        const double apart = reach + r + half[l][part];  // |mid - o| >= apart: no need of the
        const double d2 = (mid[0] - o[0]) * (mid[0] - o[0]) + (mid[1] - o[1]) * (mid[1] - o[1]) +
                          (mid[2] - o[2]) * (mid[2] - o[2]);  // exact distance
        if (d2 >= apart * apart) continue;
        if (segment_distance(a, b, seg[l][part], seg[l][part + 1]) < 2.0 * c.radius) return true;
      }
  }
  return false;
}

// collides_framed at n samples (c.T, c.q, c.owner as margins_of), the arm's frames in one call:
// c.hits (n).
template <typename Model>
void collisions_of(const Search<Model>* S, Checks& c, int n) {
  const Search<Model>& s0 = S[0];
  if (!s0.caps.enabled || s0.caps.n_points < 2) {
    std::fill_n(c.hits.begin(), n, std::uint8_t(0));
    return;
  }
  const int dof = int(s0.arm.chain->dof()), n3 = 3 * s0.legs, stride = (dof + 2) * 16;
  for (int i = 0; i < n; ++i)
    std::copy_n(&c.q[std::size_t(s0.m * i + n3)], dof, &c.arm_q[std::size_t(dof * i)]);
  kernels::chain_frames(*s0.arm.chain, c.arm_q.data(), c.frames.data(), n);
  for (int i = 0; i < n; ++i)
    c.hits[std::size_t(i)] =
        collides_framed(S[c.owner[std::size_t(i)]], &c.q[std::size_t(s0.m * i)],
                        &c.T[std::size_t(16 * i)], &c.frames[std::size_t(stride * i)]);
}

template <typename Model>
int arm_dof(const Search<Model>& s) {
  return s.arm.chain ? int(s.arm.chain->dof()) : 6;
}

// The checks' memory holding one sample (T_body, q) of target s (a thread's, reused: a path's
// samples check one by one).
template <typename Model>
Checks& one_sample(const Search<Model>& s, const double* T_body, const double* q) {
  static thread_local Checks c;
  c.resize(1, s.m, arm_dof(s));
  std::copy_n(T_body, 16, c.T.data()), std::copy_n(q, s.m, c.q.data()), c.owner[0] = 0;
  return c;
}

// (M) of one sample.
template <typename Model>
double margin_of(const Search<Model>& s, const double* T_body, const double* q) {
  Checks& c = one_sample(s, T_body, q);
  margins_of(&s, c, 1);
  return c.margin[0];
}

// Whether one sample collides.
template <typename Model>
bool collides(const Search<Model>& s, const double* q, const double* T_body) {
  Checks& c = one_sample(s, T_body, q);
  collisions_of(&s, c, 1);
  return c.hits[0] != 0;
}

// check of n options, option i of target S[owner[i]], in one call of each kernel.
template <typename Model>
void check_all(const Search<Model>* S, Option* const* options, const int* owner, int n, Checks& c) {
  if (n == 0) return;
  const Search<Model>& s0 = S[0];
  c.resize(n, s0.m, arm_dof(s0));
  for (int i = 0; i < n; ++i) {
    const Option& o = *options[i];
    c.owner[std::size_t(i)] = owner[i];
    std::copy_n(&o.ev->T[std::size_t(16 * o.pose)], 16, &c.T[std::size_t(16 * i)]);
    whole_q(s0, *o.ev, o.pose, o.slot, &c.q[std::size_t(s0.m * i)]);
  }
  margins_of(S, c, n);
  collisions_of(S, c, n);
  for (int i = 0; i < n; ++i) {
    Option& o = *options[i];
    o.margin = c.margin[std::size_t(i)], o.collides = c.hits[std::size_t(i)] != 0, o.checked = true;
  }
}

// Whether option x comes before y in (A)'s order: cost, then candidate, then branch.
inline bool before(const Option& x, const Option& y) {
  if (x.cost != y.cost) return x.cost < y.cost;
  if (x.order != y.order) return x.order < y.order;
  return x.slot < y.slot;
}

// The first unchecked option in (A)'s order (null: none), the one choose() checks first.
inline Option* first_unchecked(std::vector<Option>& options) {
  Option* best = nullptr;
  for (Option& o : options)
    if (!o.checked && (!best || before(o, *best))) best = &o;
  return best;
}

template <typename Model>
void check(const Search<Model>& s, Option& o) {
  if (o.checked) return;
  Option* one = &o;
  const int owner = 0;
  static thread_local Checks c;  // a thread's, reused
  check_all(&s, &one, &owner, 1, c);
}

// The options of an evaluation's poses begin .. end - 1 (every valid branch where the legs are OK),
// numbered from first_order, and their misses.
template <typename Model>
void options_of(const Search<Model>& s, const Evaluation& ev, int begin, int end, int first_order,
                std::vector<Option>& out, std::vector<Miss>* misses) {
  const int n3 = 3 * s.legs;
  const double* lo = s.sh.q_lower + n3;
  const double* hi = s.sh.q_upper + n3;
  for (int k = begin; k < end; ++k) {
    const int order = first_order + (k - begin);
    if (!ev.legs_ok[std::size_t(k)]) continue;
    double legs_sum = kNan;  // the pose's and the legs' squares, shared by its branches
    for (int slot = 0; slot < 8; ++slot) {
      const std::size_t at = std::size_t(8 * k + slot);
      if (ev.valid[at]) {
        if (std::isnan(legs_sum))
          legs_sum = squares_of(s, &ev.p[std::size_t(6 * k)], &ev.legs[std::size_t(n3 * k)], n3);
        const double sum = add_squares(s, legs_sum, &ev.arm_q[std::size_t(48 * k + 6 * slot)], n3);
        out.push_back({&ev, k, slot, order, 0.5 * sum});
      } else if (misses && ev.exists[at]) {
        Miss miss{0.0, order, slot, {}, {}};
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
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return before(options[std::size_t(a)], options[std::size_t(b)]); });
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
  double p[6], q[kReachMaxQ], T[16], L[16];  // L: S <- body
  double branches[48];  // the arm's branches at T, and their validity, as its evaluation found
  std::uint8_t valid[8];
  int slot;
  double cost, margin;
};

// follow at ev's poses (ev.p and ev.owner set), pose k from the branch of its target's answer
// A[ev.owner[k]]: q (n, m) and ok (n).
template <typename Model>
void follow(const Search<Model>* S, const Answer* A, Evaluation& ev, double* q, bool* ok) {
  const int n = ev.n, n3 = 3 * S[0].legs, m = S[0].m;
  for (int k = 0; k < n; ++k)
    std::copy_n(A[ev.owner[std::size_t(k)]].q, n3, &ev.seeds[std::size_t(n3 * k)]);
  run(S, ev, ev.seeds.data());
  for (int k = 0; k < n; ++k) {
    const Answer& a = A[ev.owner[std::size_t(k)]];
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
    if (slot >= 0) whole_q(S[0], ev, k, slot, q + std::size_t(m) * std::size_t(k));
    ev.arm_status[std::size_t(k)] = std::int8_t(slot);  // the branch taken (reused field)
  }
}
// (R): Gauss-Newton steps on the body poses of answers A[t] for the targets t in active (count),
// the steps of every target in one call of each kernel (cpp/src/reach_steps.cpp).
template <typename Model>
void refine(const Search<Model>* S, Answer* A, const int* active, int count);

// (F)'s damped least squares from z (12): z and e (6) in place, and (E) at its final body pose in
// `end` (with options of order `order`); it stops early where an option there is feasible, tried
// every REPAIR_CHECK iterations (cpp/src/reach_steps.cpp).
template <typename Model>
void descend(const Search<Model>& s, double* z, double* e, int order, Evaluation& end);

}  // namespace spotkin::motion::search
