// Whole-body reach (spotkin/motion/reach.hpp): python/spotkin/reference/reach.py step for step, in
// double. A target's candidates go through the batched body and arm kernels in one call each; the
// options, the Gauss-Newton refinement and the repair are scalar code over them.
#include "spotkin/motion/reach.hpp"

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

namespace spotkin::motion {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// (x + pi) mod 2 pi - pi, in [-pi, pi): Python's modulo without fmod (exact enough for the
// residual).
double wrap_angle(double x) noexcept {
  const double y = x + kPi;
  return y - 2.0 * kPi * std::floor(y * (0.5 / kPi)) - kPi;
}

void mul4(const double* A, const double* B, double* C) noexcept {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      C[4 * r + c] = A[4 * r] * B[c] + A[4 * r + 1] * B[4 + c] + A[4 * r + 2] * B[8 + c] +
                     A[4 * r + 3] * B[12 + c];
}

// "XYZ" Euler angles of R = Rx(a) Ry(b) Rz(c) (ref.xyz_euler), and the pose [t, a, b, c] of T.
void pose_of(const double* T, double* pose) noexcept {
  pose[0] = T[3], pose[1] = T[7], pose[2] = T[11];
  pose[4] = std::asin(std::max(-1.0, std::min(1.0, T[2])));
  pose[3] = std::atan2(-T[6], T[10]);
  pose[5] = std::atan2(-T[1], T[0]);
}

// Solves the n x n symmetric positive definite A x = b in place of b (Cholesky); false if not SPD.
bool cholesky_solve(double* A, int n, double* b, int columns = 1) noexcept {
  for (int j = 0; j < n; ++j) {
    double d = A[n * j + j];
    for (int k = 0; k < j; ++k) d -= A[n * j + k] * A[n * j + k];
    if (!(d > 0.0)) return false;
    d = std::sqrt(d);
    A[n * j + j] = d;
    for (int i = j + 1; i < n; ++i) {
      double s = A[n * i + j];
      for (int k = 0; k < j; ++k) s -= A[n * i + k] * A[n * j + k];
      A[n * i + j] = s / d;
    }
  }
  for (int c = 0; c < columns; ++c) {
    for (int i = 0; i < n; ++i) {  // L y = b
      double s = b[columns * i + c];
      for (int k = 0; k < i; ++k) s -= A[n * i + k] * b[columns * k + c];
      b[columns * i + c] = s / A[n * i + i];
    }
    for (int i = n - 1; i >= 0; --i) {  // L^T x = y
      double s = b[columns * i + c];
      for (int k = i + 1; k < n; ++k) s -= A[n * k + i] * b[columns * k + c];
      b[columns * i + c] = s / A[n * i + i];
    }
  }
  return true;
}

// ref.segment_distance: the segments a-b and c-d (Ericson 5.1.9).
double segment_distance(const double* a, const double* b, const double* c,
                        const double* d) noexcept {
  double u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k) u[k] = b[k] - a[k], v[k] = d[k] - c[k], w[k] = a[k] - c[k];
  const double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2],
               vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const double uv = u[0] * v[0] + u[1] * v[1] + u[2] * v[2],
               uw = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
  const double vw = v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
  const auto clip = [](double x) { return std::min(std::max(x, 0.0), 1.0); };
  double s = 0.0, t = 0.0;
  if (uu <= 1e-30 && vv <= 1e-30) {
  } else if (uu <= 1e-30) {
    t = clip(vw / vv);
  } else if (vv <= 1e-30) {
    s = clip(-uw / uu);
  } else {
    const double den = uu * vv - uv * uv;
    s = den > 1e-30 ? clip((uv * vw - vv * uw) / den) : 0.0;
    t = (uv * s + vw) / vv;
    if (t < 0.0) {
      s = clip(-uw / uu), t = 0.0;
    } else if (t > 1.0) {
      s = clip((uv - uw) / uu), t = 1.0;
    }
  }
  double g2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double g = w[k] + s * u[k] - t * v[k];
    g2 += g * g;
  }
  return std::sqrt(g2);
}

// ref.segment_box_distance: the ends, the face-plane crossings and each piece's own minimum.
double segment_box_distance(const double* a_in, const double* b_in, const double* centre,
                            const double* half) noexcept {
  double a[3], u[3];
  for (int k = 0; k < 3; ++k) a[k] = a_in[k] - centre[k], u[k] = b_in[k] - centre[k] - a[k];
  const auto at = [&](double t) {
    double g2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double g = std::max(std::abs(a[k] + t * u[k]) - half[k], 0.0);
      g2 += g * g;
    }
    return std::sqrt(g2);
  };
  double cuts[8] = {0.0, 1.0};
  int n = 2;
  for (int k = 0; k < 3; ++k) {
    if (u[k] == 0.0) continue;
    for (const double t : {(half[k] - a[k]) / u[k], (-half[k] - a[k]) / u[k]})
      if (0.0 < t && t < 1.0) cuts[n++] = t;
  }
  for (int i = 1; i < n; ++i)  // insertion sort (at most 8)
    for (int j = i; j > 0 && cuts[j] < cuts[j - 1]; --j) std::swap(cuts[j], cuts[j - 1]);
  double best = kInf;
  for (int k = 0; k < n; ++k) best = std::min(best, at(cuts[k]));
  for (int k = 0; k + 1 < n; ++k) {
    const double lo = cuts[k], hi = cuts[k + 1];
    double num = 0.0, den = 0.0;
    for (int j = 0; j < 3; ++j) {
      const double mid = a[j] + 0.5 * (lo + hi) * u[j];
      const double side = std::abs(mid) > half[j] ? (mid > 0.0 ? 1.0 : -1.0) : 0.0;
      den += side * side * u[j] * u[j];
      num += side * u[j] * (side * a[j] - half[j] * side * side);
    }
    if (den > 0.0) best = std::min(best, at(std::min(std::max(-num / den, lo), hi)));
  }
  return best;
}

// ref.rotation_log: the rotation vector of R (3 x 3, row-major).
void rotation_log(const double* R, double* out) noexcept {
  const double w[3] = {R[7] - R[5], R[2] - R[6], R[3] - R[1]};
  const double s = 0.5 * std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  const double c = 0.5 * (R[0] + R[4] + R[8] - 1.0);
  const double angle = std::atan2(s, c);
  if (s < 1e-9) {
    if (c > 0.0) {
      for (int k = 0; k < 3; ++k) out[k] = 0.5 * w[k];
      return;
    }
    int k = 0;
    for (int j = 1; j < 3; ++j)
      if (R[4 * j] > R[4 * k]) k = j;
    double n[3];
    const double scale = std::sqrt(std::max(2.0 * (1.0 + R[4 * k]), 1e-300));
    for (int j = 0; j < 3; ++j) n[j] = (R[3 * j + k] + (j == k ? 1.0 : 0.0)) / scale;
    const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int j = 0; j < 3; ++j) out[j] = angle * n[j] / norm;
    return;
  }
  for (int k = 0; k < 3; ++k) out[k] = angle * w[k] / (2.0 * s);
}

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

void arm_ik_all(const ReachArm& arm, const double* poses, double* q, std::uint8_t* valid,
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
  std::vector<double> targets(std::size_t(16 * n));
  for (int k = 0; k < n; ++k) body_T(s, &ev.p[std::size_t(6 * k)], &ev.T[std::size_t(16 * k)]);
  kernels::body_ik(s.robot.body, ev.T.data(), BodyPoseFormat::Matrix, xyz_sequence(), s.in.feet,
                   true, seed_legs, ev.legs.data(), ev.leg_status.data(), n, nearest);
  for (int k = 0; k < n; ++k) {
    bool ok = true;
    for (int l = 0; l < s.legs; ++l) ok = ok && ev.leg_status[std::size_t(s.legs * k + l)] == 0;
    ev.legs_ok[std::size_t(k)] = ok;
    arm_target(s, &ev.T[std::size_t(16 * k)], &targets[std::size_t(16 * k)]);
  }
  arm_ik_all(s.arm, targets.data(), ev.arm_q.data(), ev.valid.data(), ev.exists.data(),
             ev.exact.data(), ev.arm_status.data(), n);
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

// Whether an arm capsule hits the body box or a leg capsule (ref.collides).
template <typename Model>
bool collides(const Search<Model>& s, const double* q) {
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
  for (int k = 0; k + 1 < c.n_points; ++k) {
    const double* F0 = frames + 16 * c.points[k];
    const double* F1 = frames + 16 * c.points[k + 1];
    const double a[3] = {F0[3], F0[7], F0[11]}, b[3] = {F1[3], F1[7], F1[11]};
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
  o.collides = collides(s, q);
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
  std::vector<double> seeds(std::size_t(n3 * n));
  for (int k = 0; k < n; ++k) std::copy_n(a.q, n3, &seeds[std::size_t(n3 * k)]);
  run(s, ev, seeds.data());
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

// Solves the n x n A x = b in place of b (Gaussian elimination, partial pivoting, `columns`
// right-hand sides); false when A is singular.
bool lu_solve(double* A, int n, double* b, int columns) noexcept {
  for (int k = 0; k < n; ++k) {
    int pivot = k;
    for (int i = k + 1; i < n; ++i)
      if (std::abs(A[n * i + k]) > std::abs(A[n * pivot + k])) pivot = i;
    if (!(std::abs(A[n * pivot + k]) > 0.0)) return false;
    if (pivot != k) {
      for (int j = 0; j < n; ++j) std::swap(A[n * k + j], A[n * pivot + j]);
      for (int j = 0; j < columns; ++j) std::swap(b[columns * k + j], b[columns * pivot + j]);
    }
    for (int i = k + 1; i < n; ++i) {
      const double f = A[n * i + k] / A[n * k + k];
      for (int j = k; j < n; ++j) A[n * i + j] -= f * A[n * k + j];
      for (int j = 0; j < columns; ++j) b[columns * i + j] -= f * b[columns * k + j];
    }
  }
  for (int i = n - 1; i >= 0; --i)
    for (int j = 0; j < columns; ++j) {
      double sum = b[columns * i + j];
      for (int k = i + 1; k < n; ++k) sum -= A[n * i + k] * b[columns * k + j];
      b[columns * i + j] = sum / A[n * i + i];
    }
  return true;
}

// ref.sensitivities: dq/dp (m, 6), row-major, at the answer; false where a Jacobian is singular.
template <typename Model>
bool sensitivities(const Search<Model>& s, const Answer& a, double* dq) {
  const int n3 = 3 * s.legs;
  const double* S = s.in.stance;  // world <- S: points into S by R_S^T (x - t_S)
  const auto to_stance = [&](const double* x, double* out) {
    const double d[3] = {x[0] - S[3], x[1] - S[7], x[2] - S[11]};
    for (int i = 0; i < 3; ++i) out[i] = S[i] * d[0] + S[4 + i] * d[1] + S[8 + i] * d[2];
  };
  double T[16];
  body_batch::pose_transform(a.p, BodyPoseFormat::Euler, xyz_sequence(), T);
  const double ca = std::cos(a.p[3]), sa = std::sin(a.p[3]), cb = std::cos(a.p[4]),
               sb = std::sin(a.p[4]);
  const double E[3][3] = {{1.0, 0.0, sb}, {0.0, ca, -sa * cb}, {0.0, sa, ca * cb}};
  // column j of (v, w): p_j' = 1
  const auto motion = [&](int j, double* v, double* w) {
    for (int i = 0; i < 3; ++i) v[i] = j == i ? 1.0 : 0.0, w[i] = j >= 3 ? E[i][j - 3] : 0.0;
  };
  // -R^T (v + w x (x - t)) for the 6 columns: rhs (3, 6)
  const auto held = [&](const double* x, double* rhs) {
    const double d[3] = {x[0] - T[3], x[1] - T[7], x[2] - T[11]};
    for (int j = 0; j < 6; ++j) {
      double v[3], w[3];
      motion(j, v, w);
      const double u[3] = {v[0] + w[1] * d[2] - w[2] * d[1], v[1] + w[2] * d[0] - w[0] * d[2],
                           v[2] + w[0] * d[1] - w[1] * d[0]};
      for (int i = 0; i < 3; ++i)
        rhs[6 * i + j] = -(T[i] * u[0] + T[4 + i] * u[1] + T[8 + i] * u[2]);
    }
  };
  for (int l = 0; l < s.legs; ++l) {
    const auto& col = s.robot.body.columns[std::size_t(l)];
    const double q_leg[3] = {a.q[col[0]], a.q[col[1]], a.q[col[2]]};
    double J[9], foot[3], rhs[18];
    kernels::leg_jacobian(s.robot.body.legs[std::size_t(l)], q_leg, J, 1);
    to_stance(s.in.feet + 3 * l, foot);
    held(foot, rhs);
    if (!lu_solve(J, 3, rhs, 6)) return false;
    for (int i = 0; i < 3; ++i) std::copy_n(rhs + 6 * i, 6, dq + 6 * col[i]);
  }
  double J[36], target[3], rhs[36];
  kernels::chain_jacobian(*s.arm.chain, a.q + n3, J, 1, 6, false);
  {  // the target's position in S (its column 3)
    const double p_t[3] = {s.in.target[3], s.in.target[7], s.in.target[11]};
    to_stance(p_t, target);
  }
  held(target, rhs);
  for (int j = 0; j < 6; ++j) {  // -R^T w
    double v[3], w[3];
    motion(j, v, w);
    for (int i = 0; i < 3; ++i)
      rhs[6 * (3 + i) + j] = -(T[i] * w[0] + T[4 + i] * w[1] + T[8 + i] * w[2]);
  }
  if (!lu_solve(J, 6, rhs, 6)) return false;
  std::copy_n(rhs, 36, dq + 6 * n3);
  return true;
}

// (R): Gauss-Newton steps on p.
template <typename Model>
void refine(const Search<Model>& s, Answer& a) {
  const int m = s.m, rows = 6 + m;
  Evaluation ev;
  std::vector<double> r0(static_cast<std::size_t>(rows)), dq(static_cast<std::size_t>(6 * m));
  for (int step = 0; step < kReachRefineSteps; ++step) {
    residual(s, a.p, a.q, r0.data());
    if (!sensitivities(s, a, dq.data())) return;
    // J = [diag(1 / w_p); dq / w_q]: J^T J + mu I and -J^T r0
    double A[36], g[6];
    for (int i = 0; i < 6; ++i) {
      g[i] = -r0[std::size_t(i)] / s.sh.w_p[i];
      for (int j = 0; j < 6; ++j)
        A[6 * i + j] = (i == j ? 1.0 / (s.sh.w_p[i] * s.sh.w_p[i]) + kReachGnDamping : 0.0);
    }
    for (int k = 0; k < m; ++k) {
      const double* row = &dq[std::size_t(6 * k)];
      const double inv = 1.0 / s.sh.w_q[k], r = r0[std::size_t(6 + k)];
      for (int i = 0; i < 6; ++i) {
        g[i] -= row[i] * inv * r;
        for (int j = 0; j < 6; ++j) A[6 * i + j] += row[i] * row[j] * inv * inv;
      }
    }
    if (!cholesky_solve(A, 6, g)) return;
    bool taken = false;
    for (const double alpha : {1.0, 0.5, 0.25}) {
      double p_new[6], q_new[kReachMaxQ];
      for (int k = 0; k < 6; ++k)
        p_new[k] = std::min(std::max(a.p[k] + alpha * g[k], s.sh.lower[k]), s.sh.upper[k]);
      bool ok_new;
      follow(s, a, p_new, 1, ev, q_new, &ok_new);
      if (!ok_new) continue;
      const double cost = cost_of(s, p_new, q_new);
      if (!(cost < a.cost)) continue;
      const double margin = margin_of(s, ev.T.data(), q_new);
      if (!(margin >= s.in.margin) || collides(s, q_new)) continue;
      std::copy_n(p_new, 6, a.p), std::copy_n(q_new, m, a.q), std::copy_n(ev.T.data(), 16, a.T);
      a.slot = ev.arm_status[0], a.cost = cost, a.margin = margin;
      taken = true;
      break;
    }
    if (!taken) return;
  }
}

// (F)'s hand error at each z (n, 12): e (n, 6).
template <typename Model>
void hand_errors(const Search<Model>& s, const double* z, int n, double* e) {
  std::vector<double> hands(std::size_t(16 * n)), arm_q(std::size_t(6 * n));
  for (int k = 0; k < n; ++k) std::copy_n(z + 12 * k + 6, 6, &arm_q[std::size_t(6 * k)]);
  kernels::chain_fk(*s.arm.chain, arm_q.data(), hands.data(), n);
  const double* t = s.in.target;
  for (int k = 0; k < n; ++k) {
    double T_body[16], T_hand[16];
    body_T(s, z + 12 * k, T_body);
    mul4(T_body, &hands[std::size_t(16 * k)], T_hand);
    double R[9];  // R_target R_hand^T
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        R[3 * i + j] = t[4 * i] * T_hand[4 * j] + t[4 * i + 1] * T_hand[4 * j + 1] +
                       t[4 * i + 2] * T_hand[4 * j + 2];
    double* out = e + 6 * k;
    for (int i = 0; i < 3; ++i) out[i] = t[4 * i + 3] - T_hand[4 * i + 3];
    rotation_log(R, out + 3);
    for (int i = 3; i < 6; ++i) out[i] *= s.sh.scale;
  }
}

template <typename Model>
bool legs_ok_at(const Search<Model>& s, const double* p) {
  double T[16], q[kReachMaxQ];
  std::int8_t status[Body::kMaxLegs];
  body_T(s, p, T);
  kernels::body_ik(s.robot.body, T, BodyPoseFormat::Matrix, xyz_sequence(), s.in.feet, true,
                   static_cast<const double*>(nullptr), q, status, 1, false);
  for (int l = 0; l < s.legs; ++l)
    if (status[l] != 0) return false;
  return true;
}

// (F)'s damped least squares from z (12): z and e (6) in place.
template <typename Model>
void descend(const Search<Model>& s, double* z, double* e) {
  const int n3 = 3 * s.legs;
  double lower[12], upper[12];
  for (int k = 0; k < 6; ++k) {
    lower[k] = s.sh.lower[k], upper[k] = s.sh.upper[k];
    lower[6 + k] = s.sh.q_lower[n3 + k] + kReachRepairInset,
              upper[6 + k] = s.sh.q_upper[n3 + k] - kReachRepairInset;
  }
  for (int k = 0; k < 12; ++k) z[k] = std::min(std::max(z[k], lower[k]), upper[k]);
  hand_errors(s, z, 1, e);
  double lam = kReachRepairDamping;
  double zs[12 * 12], es[12 * 6];
  const auto norm2 = [](const double* v) {
    double sum = 0.0;
    for (int k = 0; k < 6; ++k) sum += v[k] * v[k];
    return sum;
  };
  for (int it = 0; it < kReachRepairIterations; ++it) {
    if (norm2(e) < 1e-24 || lam > kReachRepairStall) break;
    for (int j = 0; j < 12; ++j) {
      std::copy_n(z, 12, zs + 12 * j);
      zs[12 * j + j] += kReachFdStep;
    }
    hand_errors(s, zs, 12, es);
    double J[6][12];  // d hand / dz = -d e / dz, forward differences
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 6; ++i) J[i][j] = -(es[6 * j + i] - e[i]) / kReachFdStep;
    double toward[12] = {};
    for (int k = 0; k < 6; ++k) toward[k] = kReachNullGain * (s.sh.nominal[k] - z[k]);
    bool free_[12];
    std::fill(free_, free_ + 12, true);
    double delta[12] = {};
    for (int pass = 0; pass < kReachActiveSetPasses; ++pass) {
      double Jf[6][12];
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 12; ++j) Jf[i][j] = free_[j] ? J[i][j] : 0.0;
      double A[36], X[36];  // X = (Jf Jf^T + lam^2 I)^-1
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) {
          double sum = 0.0;
          for (int k = 0; k < 12; ++k) sum += Jf[i][k] * Jf[j][k];
          A[6 * i + j] = sum + (i == j ? lam * lam : 0.0);
          X[6 * i + j] = i == j ? 1.0 : 0.0;
        }
      cholesky_solve(A, 6, X, 6);
      double P[12][6];  // pinv = Jf^T X
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 6; ++j) {
          double sum = 0.0;
          for (int k = 0; k < 6; ++k) sum += Jf[k][i] * X[6 * k + j];
          P[i][j] = sum;
        }
      double secondary[12];
      for (int k = 0; k < 12; ++k) secondary[k] = free_[k] ? toward[k] : 0.0;
      double Jy[6];  // Jf secondary
      for (int i = 0; i < 6; ++i) {
        Jy[i] = 0.0;
        for (int k = 0; k < 12; ++k) Jy[i] += Jf[i][k] * secondary[k];
      }
      bool held_any = false;
      bool held[12];
      for (int i = 0; i < 12; ++i) {
        double d = secondary[i];
        for (int k = 0; k < 6; ++k) d += P[i][k] * (e[k] - Jy[k]);
        delta[i] = d;
      }
      for (int i = 0; i < 12; ++i) {
        held[i] = free_[i] &&
                  ((z[i] <= lower[i] && delta[i] < 0.0) || (z[i] >= upper[i] && delta[i] > 0.0));
        held_any = held_any || held[i];
      }
      if (!held_any) break;
      for (int i = 0; i < 12; ++i) free_[i] = free_[i] && !held[i];
    }
    double z_new[12], e_new[6];
    for (int k = 0; k < 12; ++k) z_new[k] = std::min(std::max(z[k] + delta[k], lower[k]), upper[k]);
    hand_errors(s, z_new, 1, e_new);
    if (legs_ok_at(s, z_new) && norm2(e_new) < std::max(norm2(e), 1e-24)) {
      std::copy_n(z_new, 12, z), std::copy_n(e_new, 6, e);
      lam /= 3.0;
    } else {
      lam *= 3.0;
    }
  }
}

}  // namespace

template <typename Model>
void reach_target(const dynamics::RobotStaticsModel<Model>& robot, const ReachArm& arm,
                  const ReachCapsules& capsules, const ReachShared& shared, const ReachInput& in,
                  const ReachOutput& out) {
  const int legs = robot.body.n_legs(), m = shared.m, n3 = 3 * legs;
  const auto invalid = [&] {
    std::fill(out.body_pose, out.body_pose + 6, kNan), std::fill(out.q, out.q + m, kNan);
    *out.status = kReachInvalid, *out.margin = *out.distance = *out.angle = kNan;
    std::fill(out.branches, out.branches + 48, kNan),
        std::fill(out.valid, out.valid + 8, std::uint8_t(0));
    *out.slot = -1;
  };
  {  // a finite rigid target (ref.rigid), finite feet, margin and references
    const double* T = in.target;
    bool ok = std::isfinite(in.margin);
    for (int k = 0; k < 16; ++k) ok = ok && std::isfinite(T[k]);
    for (int k = 0; k < 3 * legs; ++k) ok = ok && std::isfinite(in.feet[k]);
    for (int k = 0; k < 6; ++k)
      ok = ok && std::isfinite(in.p_ref[k]) && (!in.seed_pose || std::isfinite(in.seed_pose[k]));
    for (int k = 0; k < m; ++k) ok = ok && std::isfinite(in.q_ref[k]);
    if (ok) {
      double last = 0.0, ortho = 0.0;
      for (int k = 0; k < 4; ++k) last = std::max(last, std::abs(T[12 + k] - (k == 3 ? 1.0 : 0.0)));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double d =
              T[i] * T[j] + T[4 + i] * T[4 + j] + T[8 + i] * T[8 + j] - (i == j ? 1.0 : 0.0);
          ortho = std::max(ortho, std::abs(d));
        }
      const double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                         T[2] * (T[4] * T[9] - T[5] * T[8]);
      ok = last <= 1e-6 && ortho <= 1e-6 && det > 0.0;
    }
    if (!ok) return invalid();
  }
  const Search<Model> s{robot, arm, capsules, shared, in, legs, m};
  // (C), (E), (A): stage by stage, until an option is feasible
  const int first = (in.seed_pose ? 1 : 0) + 1;
  const int sizes[3] = {first, kReachStageTwo, kReachCandidates - kReachStageTwo};
  Evaluation stages[3];
  std::vector<int> order(std::size_t(first + kReachCandidates));
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = int(k);
  std::vector<Option> options;
  options.reserve(
      std::size_t(8 * (first + kReachCandidates)));  // no reallocation: options point at stages
  std::vector<Miss> misses;
  std::int8_t status = kReachUnreachable;
  int chosen = -1, halton = 0, next_order = 0;
  for (int stage = 0; stage < 3; ++stage) {
    Evaluation& ev = stages[stage];
    ev.resize(sizes[stage], legs);
    for (int j = 0; j < sizes[stage]; ++j) {
      double* p = &ev.p[std::size_t(6 * j)];
      if (stage == 0 && in.seed_pose && j == 0) {
        for (int k = 0; k < 6; ++k)
          p[k] = std::min(std::max(in.seed_pose[k], shared.lower[k]), shared.upper[k]);
      } else if (stage == 0) {
        std::copy_n(shared.nominal, 6, p);
      } else {
        for (int k = 0; k < 6; ++k)
          p[k] = shared.lower[k] + shared.halton[halton][k] * (shared.upper[k] - shared.lower[k]);
        ++halton;
      }
    }
    run(s, ev);
    options_of(s, ev, order.data() + next_order, options, &misses);
    next_order += sizes[stage];
    chosen = choose(s, options, status);
    if (status == kReachOk) break;
  }
  Answer a{};
  a.slot = -1;
  Evaluation ends;
  std::vector<int> start_order(kReachRepairStarts);
  for (int k = 0; k < kReachRepairStarts; ++k) start_order[std::size_t(k)] = k;
  std::vector<Option> repaired;
  const Option* picked = chosen >= 0 ? &options[std::size_t(chosen)] : nullptr;
  double nearest_e[6] = {};
  if (!picked && !in.repair) {
    std::fill(out.body_pose, out.body_pose + 6, kNan), std::fill(out.q, out.q + m, kNan);
    *out.status = kReachUnreachable, *out.margin = *out.distance = *out.angle = kNan;
    std::fill(out.branches, out.branches + 48, kNan),
        std::fill(out.valid, out.valid + 8, std::uint8_t(0));
    *out.slot = -1;
    return;
  }
  if (!picked) {  // (F)
    double lo[6], hi[6];
    for (int k = 0; k < 6; ++k) {
      lo[k] = std::isfinite(shared.q_lower[n3 + k]) ? shared.q_lower[n3 + k] : -kPi;
      hi[k] = std::isfinite(shared.q_upper[n3 + k]) ? shared.q_upper[n3 + k] : kPi;
    }
    std::stable_sort(misses.begin(), misses.end(), [](const Miss& x, const Miss& y) {
      if (x.violation != y.violation) return x.violation < y.violation;
      if (x.order != y.order) return x.order < y.order;
      return x.slot < y.slot;
    });
    double z[kReachRepairStarts][12], e[kReachRepairStarts][6];
    int count = 0;
    std::copy_n(shared.nominal, 6, z[count]);
    for (int k = 0; k < 6; ++k) z[count][6 + k] = std::min(std::max(0.0, lo[k]), hi[k]);
    ++count;
    for (std::size_t j = 0; j < misses.size() && count < kReachRepairStarts; ++j, ++count) {
      std::copy_n(misses[j].p, 6, z[count]);
      for (int k = 0; k < 6; ++k)
        z[count][6 + k] = std::min(std::max(misses[j].q_arm[k], lo[k]), hi[k]);
    }
    for (int u = 0; count < kReachRepairStarts; ++u, ++count) {
      std::copy_n(shared.nominal, 6, z[count]);
      for (int k = 0; k < 6; ++k) z[count][6 + k] = lo[k] + shared.halton[u][k] * (hi[k] - lo[k]);
    }
    ends.resize(kReachRepairStarts, legs);
    for (int j = 0; j < kReachRepairStarts; ++j) {
      descend(s, z[j], e[j]);
      std::copy_n(z[j], 6, &ends.p[std::size_t(6 * j)]);
    }
    run(s, ends, nullptr, true);
    options_of(s, ends, start_order.data(), repaired, nullptr);
    chosen = choose(s, repaired, status);
    picked = chosen >= 0 ? &repaired[std::size_t(chosen)] : nullptr;
    if (!picked) {  // the nearest the repair came (ties to the earlier start)
      int best = 0;
      double best_e = kInf;
      for (int j = 0; j < kReachRepairStarts; ++j) {
        double sum = 0.0;
        for (int k = 0; k < 6; ++k) sum += e[j][k] * e[j][k];
        if (sum < best_e) best_e = sum, best = j;
      }
      std::copy_n(z[best], 6, a.p);
      std::copy_n(&ends.legs[std::size_t(n3 * best)], n3, a.q);
      std::copy_n(z[best] + 6, 6, a.q + n3);
      std::copy_n(&ends.T[std::size_t(16 * best)], 16, a.T);
      a.margin = margin_of(s, a.T, a.q);
      std::copy_n(e[best], 6, nearest_e);
      status = kReachUnreachable;
    }
  }
  if (picked) {
    const Evaluation& ev = *picked->ev;
    std::copy_n(&ev.p[std::size_t(6 * picked->pose)], 6, a.p);
    whole_q(s, ev, picked->pose, picked->slot, a.q);
    std::copy_n(&ev.T[std::size_t(16 * picked->pose)], 16, a.T);
    a.slot = picked->slot, a.cost = picked->cost, a.margin = picked->margin;
    if (status == kReachOk && in.refine) refine(s, a);
  }
  // the answer
  pose_of(a.T, out.body_pose);
  std::copy_n(a.q, m, out.q);
  *out.status = status, *out.margin = a.margin,
  *out.slot = status == kReachUnreachable ? -1 : a.slot;
  if (status == kReachUnreachable) {
    *out.distance = std::sqrt(nearest_e[0] * nearest_e[0] + nearest_e[1] * nearest_e[1] +
                              nearest_e[2] * nearest_e[2]);
    *out.angle = std::sqrt(nearest_e[3] * nearest_e[3] + nearest_e[4] * nearest_e[4] +
                           nearest_e[5] * nearest_e[5]) /
                 shared.scale;
  } else {
    *out.distance = *out.angle = 0.0;
  }
  double target[16], exact[8];
  std::uint8_t exists[8], exact_flags[8];
  std::int8_t arm_status;
  (void)exact;
  arm_target(s, a.T, target);
  arm_ik_all(arm, target, out.branches, out.valid, exists, exact_flags, &arm_status, 1);
}

template <typename Model>
void reach_constraints(const dynamics::RobotStaticsModel<Model>& robot, const ReachArm& arm,
                       const ReachCapsules& capsules, const ReachShared& shared,
                       const double* T_body, const double* q, const double* feet, double* margin,
                       bool* hits) {
  const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const double zeros[kReachMaxQ] = {};
  const ReachInput in{identity, feet, identity, zeros, zeros, nullptr, 0.0};
  const Search<Model> s{robot, arm, capsules, shared, in, robot.body.n_legs(), shared.m};
  *margin = margin_of(s, T_body, q);
  *hits = collides(s, q);
}

#define SPOTKIN_INSTANTIATE(L)                                                                 \
  template void reach_target<dynamics::FloatingModel<double, L>>(                              \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&, const ReachArm&, \
      const ReachCapsules&, const ReachShared&, const ReachInput&, const ReachOutput&);        \
  template void reach_constraints<dynamics::FloatingModel<double, L>>(                         \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&, const ReachArm&, \
      const ReachCapsules&, const ReachShared&, const double*, const double*, const double*,   \
      double*, bool*);
SPOTKIN_INSTANTIATE(dynamics::kLanes64)
SPOTKIN_INSTANTIATE(dynamics::kMidLanes64)
SPOTKIN_INSTANTIATE(dynamics::kSmallLanes64)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::motion
