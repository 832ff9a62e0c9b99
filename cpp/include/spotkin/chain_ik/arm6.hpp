// Closed-form IK of 6R chains by family: the spherical wrist (SphericalWrist6 on
// the chain itself, the fast path), three parallel axes 2-3-4 (Parallel234) or 1-2-3
// (Parallel123), and the
// spherical shoulder (SphericalWrist6 on the reversed chain). A chain that fits a
// family only to within the caller's tolerances (a calibrated robot) is solved on
// its idealised chain, then every solution is polished by Newton steps on the true
// chain; only a residual below 1e-10 counts as exact.
#pragma once

#include <optional>
#include <sstream>

#include "spotkin/chain_ik/batch.hpp"
#include "spotkin/chain_ik/parallel.hpp"

namespace spotkin::chain_ik {

// Geometric tolerances of the family detection: axes count as parallel when the sine
// of their angle is <= angle, and as meeting when each passes within distance (m) of
// their common point. The strict tolerances (1e-9, 1e-9 s) are what counts as exact.
struct FamilyTolerance {
  double angle = Tolerance::angle;
  double distance = -1.0;  // negative: Tolerance::wrist * the chain's length scale
};

class Arm6 {
 public:
  static constexpr int kSlots = 8;
  static constexpr double kExact = 1e-10;   // residual (m and rad) of an exact solution
  static constexpr double kAccept = 1e-6;   // residual beyond which a polished branch is dropped
  static constexpr double kMirror = 0.05;   // Sp6's mirror for idealised chains
  static constexpr double kSame = 1e-8;     // polished slots this close (rad) are one solution
  // a block of at most this many poses is solved pose by pose (cheaper than a padded lane block)
  static constexpr int kShortBlock = 3;

  static Arm6 make(const Chain<double>& chain, double scale, FamilyTolerance tolerance) {
    if (chain.dof() != 6)
      throw std::invalid_argument("a 6R closed form needs 6 joints, got " + std::to_string(chain.dof()));
    for (int j = 0; j < 6; ++j)
      if (chain.joints()[std::size_t(j)].type != JointType::Revolute)
        throw std::invalid_argument("no closed form: joint " + std::to_string(j + 1) +
                                    " is prismatic; the 6R families need revolute joints");
    const double strict_distance = Tolerance::wrist * scale;
    if (!(tolerance.distance >= 0.0)) tolerance.distance = strict_distance;
    tolerance.angle = std::max(tolerance.angle, Tolerance::angle);
    tolerance.distance = std::max(tolerance.distance, strict_distance);
    const Poe poe = poe_of(chain);
    const Geometry6 geometry(poe);
    Arm6 arm(chain);
    arm.geometry_ = geometry;
    // the order of the checks: spherical wrist, parallel 2-3-4, parallel 1-2-3, spherical shoulder
    struct Check {
      Family6 family;
      double deviation, strict, tolerance;
    };
    const Check checks[] = {
        {Family6::SphericalWrist, geometry.wrist, strict_distance, tolerance.distance},
        {Family6::Parallel234, geometry.parallel234, Tolerance::angle, tolerance.angle},
        {Family6::Parallel123, geometry.parallel123, Tolerance::angle, tolerance.angle},
        {Family6::SphericalShoulder, geometry.shoulder, strict_distance, tolerance.distance},
    };
    const Check* chosen = nullptr;
    for (const auto& check : checks)
      if (check.deviation <= check.strict) {
        chosen = &check;
        break;
      }
    if (!chosen)
      for (const auto& check : checks)
        if (check.deviation <= check.tolerance) {
          chosen = &check;
          break;
        }
    if (!chosen) {
      std::ostringstream message;
      message.precision(3);
      message << "no closed-form 6R family fits this chain: checked axes 4-5-6 meeting (off by " << geometry.wrist
              << " m), axes 2-3-4 parallel (sin angle " << geometry.parallel234 << "), axes 1-2-3 parallel (sin angle "
              << geometry.parallel123 << "), axes 1-2-3 meeting (" << geometry.shoulder << " m), against tolerances of "
              << tolerance.angle << " (angle) and " << tolerance.distance
              << " m. Use Chain.ik_differential, or a looser ik tolerance (Chain.with_ik_tolerance) for a "
                 "calibrated robot";
      throw std::invalid_argument(message.str());
    }
    arm.family_ = chosen->family;
    arm.idealised_ = chosen->deviation > chosen->strict;
    // the parallel families: a rank-1 subproblem 6 when a pair of axes meets (below)
    const double gap = arm.family_ == Family6::Parallel234 ? geometry.gap56
                       : arm.family_ == Family6::Parallel123 ? geometry.gap45
                                                            : 0.0;
    if (gap > strict_distance && gap <= tolerance.distance) arm.idealised_ = true;
    // rank 1 exactly when that pair meets (idealised or within the strict distance): forced, so
    // that the choice is geometric, not a threshold on a matrix of mixed units
    const double rank_tolerance = gap <= tolerance.distance ? 1.0 : -1.0;
    const Poe ideal = arm.idealised_ ? idealise(poe, arm.family_, geometry, tolerance.distance) : poe;
    const double mirror = arm.idealised_ ? kMirror : 0.0;
    arm.M_ = poe.M;
    // three times the idealisation's error bound, relative to the chain's size
    arm.nudge_ = std::min(0.05, 3.0 * std::max(tolerance.distance, tolerance.angle * scale) / scale);
    arm.centre_ = poe.p[0];
    arm.M_inv_ = inverse_rigid(poe.M);
    switch (arm.family_) {
      case Family6::SphericalWrist:
        arm.wrist_.emplace(SphericalWrist6::make(arm.idealised_ ? chain_of(ideal) : chain, scale));
        break;
      case Family6::Parallel234:
        arm.parallel_.emplace(ideal, rank_tolerance, mirror);
        break;
      case Family6::Parallel123:
        arm.parallel123_.emplace(ideal, rank_tolerance, mirror);
        break;
      case Family6::SphericalShoulder: {
        const Chain<double> reversed_chain = chain_of(chain_ik::reversed(ideal));
        arm.wrist_.emplace(SphericalWrist6::make(reversed_chain, reversed_chain.length_scale()));
        arm.reversed_ = true;
        break;
      }
    }
    return arm;
  }

  Family6 family() const noexcept { return family_; }
  bool idealised() const noexcept { return idealised_; }
  bool reversed() const noexcept { return reversed_; }
  // The spherical wrist of the chain itself, solved by the lane kernel (wrist_block).
  bool direct_wrist() const noexcept { return family_ == Family6::SphericalWrist && !idealised_; }
  // Three parallel axes 2-3-4 of rank-1 form on the chain itself: solved across lanes
  // (Parallel234::solve_lanes), with solve() for the lanes it hands back.
  bool lane_parallel() const noexcept { return parallel_ && !idealised_ && parallel_->rank1(); }
  // The spherical shoulder on the chain itself: the wrist lane kernel on the reversed chain.
  bool lane_shoulder() const noexcept { return reversed_ && !idealised_; }
  const Rigid<double>& M() const noexcept { return M_; }
  // idealised chains: the relative radial move of a target for extra starts, and its centre (axis 1)
  double nudge() const noexcept { return nudge_; }
  const V3& centre() const noexcept { return centre_; }
  const Parallel234& parallel() const noexcept { return *parallel_; }
  const SphericalWrist6& wrist() const noexcept { return *wrist_; }
  const Geometry6& geometry() const noexcept { return geometry_; }
  std::string kind() const { return family_name(family_); }
  std::string position_kind() const {
    return wrist_ ? wrist_->position().name() : parallel_ ? "parallel-234" : "parallel-123";
  }

  // Every solution of one target pose as (cos, sin) per joint, in this chain's joint
  // order (not for direct_wrist chains, which go by lanes); refine[slot]: the slot is near
  // a double root and needs Newton steps (see Parallel234::solve).
  // Not inlined into the target-cloned lane kernels: compiled for the baseline target, where
  // Eigen's small products inline (inside a clone they cannot, and become calls).
  SPOTKIN_SCALAR_PATH void solve(const Arm::Pose& target, JointValue q[kSlots][6], bool exists[kSlots],
                                 bool refine[kSlots]) const noexcept {
    for (int k = 0; k < kSlots; ++k) refine[k] = false;
    const Rigid<double> T = rigid_of(target);
    if (parallel_ || parallel123_) {
      const Rigid<double> G = T * M_inv_;  // G = T M^-1 (M is the idealised chain's too)
      if (parallel_)
        parallel_->solve(G.R, G.p, q, exists, refine);
      else
        parallel123_->solve(G.R, G.p, q, exists, refine);
      return;
    }
    if (!reversed_) {
      wrist_->solve(target, q, exists);
      return;
    }
    // G^-1 = M T^-1: the reversed chain's target; its joint i is joint 5 - i, negated
    const Rigid<double> inner = M_ * inverse_rigid(T);
    Arm::Pose pose;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) pose.R[r][c] = inner.R(r, c);
      pose.p[r] = inner.p[r];
    }
    JointValue x[kSlots][6];
    wrist_->solve(pose, x, exists);
    for (int k = 0; k < kSlots; ++k)
      for (int j = 0; j < 6; ++j) q[k][j] = JointValue{x[k][5 - j].c, -x[k][5 - j].s, 0.0};
  }

  // Newton steps on the true chain from q (6 angles) towards target; the residual.
  double polish(const Arm::Pose& target, double* q) const noexcept {
    return newton_polish(chain_, q, rigid_of(target));
  }

  static Rigid<double> rigid_of(const Arm::Pose& pose) noexcept {
    Rigid<double> T;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) T.R(r, c) = pose.R[r][c];
      T.p[r] = pose.p[r];
    }
    return T;
  }

 private:
  explicit Arm6(const Chain<double>& chain) : chain_(chain) {}

  Chain<double> chain_;  // the true chain
  Geometry6 geometry_;
  Family6 family_ = Family6::SphericalWrist;
  bool idealised_ = false, reversed_ = false;
  Rigid<double> M_, M_inv_;
  double nudge_ = 0.0;
  V3 centre_ = V3::Zero();
  std::optional<SphericalWrist6> wrist_;
  std::optional<Parallel234> parallel_;
  std::optional<Parallel123> parallel123_;
};

static_assert(Parallel234::kLanes == SphericalWrist6::kLanes, "one block width for every 6R family");

// A finished block of 6R solutions plus exact[k][i] (1: residual below 1e-10).
struct Arm6Block : WristBlock {
  double exact[Arm6::kSlots][SphericalWrist6::kLanes];
};

// The rotation of a matrix pose (orthonormal to 1e-6, as read_pose checks) made a rotation to
// rounding by two Newton-Schulz steps R <- R (3 I - R^T R) / 2 (the error squares each step), so
// that a float32 pose has an exact solution and the residual of an exact one can be 1e-10.
inline void project_rotation(Arm::Pose& pose) noexcept {
  for (int step = 0; step < 2; ++step) {
    double gram[3][3], next[3][3];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        gram[a][b] = pose.R[0][a] * pose.R[0][b] + pose.R[1][a] * pose.R[1][b] + pose.R[2][a] * pose.R[2][b];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        double sum = 0.0;
        for (int a = 0; a < 3; ++a) sum += pose.R[r][a] * ((a == c ? 3.0 : 0.0) - gram[a][c]);
        next[r][c] = 0.5 * sum;
      }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) pose.R[r][c] = next[r][c];
  }
}

// Arm::read_pose and project_rotation across the lanes of a block (lanes i >= m repeat pose m - 1):
// R[r][c][i], p[r][i] and ok[i] (1.0 / 0.0), the same arithmetic in lane-inner loops.
template <PoseFormat Format>
SPOTKIN_INLINE void read_pose_lanes(const double (*pose_in)[SphericalWrist6::kLanes], int m,
                                    double (&R)[3][3][SphericalWrist6::kLanes], double (&p)[3][SphericalWrist6::kLanes],
                                    double (&ok)[SphericalWrist6::kLanes]) noexcept {
  constexpr int L = SphericalWrist6::kLanes, width = Format == PoseFormat::Matrix ? 16 : 7;
  double in[width][L];
  for (int e = 0; e < width; ++e)
    for (int i = 0; i < L; ++i) in[e][i] = pose_in[e][i < m ? i : m - 1];
  for (int i = 0; i < L; ++i) {
    double okl = 1.0;
    if constexpr (Format == PoseFormat::Matrix) {
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R[r][c][i] = in[4 * r + c][i];
        p[r][i] = in[4 * r + 3][i];
      }
      const double row_error = std::max(std::max(std::fabs(in[12][i]), std::fabs(in[13][i])),
                                        std::max(std::fabs(in[14][i]), std::fabs(in[15][i] - 1.0)));
      okl = row_error <= 1e-9 ? okl : 0.0;
      double orth = 0.0;  // max |R^T R - I|
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const double dot = R[0][a][i] * R[0][b][i] + R[1][a][i] * R[1][b][i] + R[2][a][i] * R[2][b][i];
          orth = std::max(orth, std::fabs(dot - (a == b ? 1.0 : 0.0)));
        }
      const double det = R[0][0][i] * (R[1][1][i] * R[2][2][i] - R[1][2][i] * R[2][1][i]) -
                         R[0][1][i] * (R[1][0][i] * R[2][2][i] - R[1][2][i] * R[2][0][i]) +
                         R[0][2][i] * (R[1][0][i] * R[2][1][i] - R[1][1][i] * R[2][0][i]);
      okl = ((orth <= Arm::kRotationTolerance) & (det > 0.0)) ? okl : 0.0;
    } else {
      const double x = in[3][i], y = in[4][i], z = in[5][i], w = in[6][i];
      const double n2 = x * x + y * y + z * z + w * w;
      okl = std::fabs(std::sqrt(n2) - 1.0) <= Arm::kRotationTolerance ? okl : 0.0;
      const double s = 2.0 / n2;
      R[0][0][i] = 1 - s * (y * y + z * z), R[0][1][i] = s * (x * y - z * w), R[0][2][i] = s * (x * z + y * w);
      R[1][0][i] = s * (x * y + z * w), R[1][1][i] = 1 - s * (x * x + z * z), R[1][2][i] = s * (y * z - x * w);
      R[2][0][i] = s * (x * z - y * w), R[2][1][i] = s * (y * z + x * w), R[2][2][i] = 1 - s * (x * x + y * y);
      p[0][i] = in[0][i], p[1][i] = in[1][i], p[2][i] = in[2][i];
    }
    double sum = 0.0;  // NaN and Inf fail every comparison above or make this NaN
    for (int r = 0; r < 3; ++r) sum += R[r][0][i] + R[r][1][i] + R[r][2][i] + p[r][i];
    if constexpr (Format == PoseFormat::Matrix) sum += in[12][i] + in[13][i] + in[14][i] + in[15][i];
    ok[i] = (sum - sum) == 0.0 ? okl : 0.0;
  }
  if constexpr (Format == PoseFormat::Matrix)  // project_rotation, lane by lane
    for (int step = 0; step < 2; ++step)
      for (int i = 0; i < L; ++i) {
        double gram[3][3], next[3][3];
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            gram[a][b] = R[0][a][i] * R[0][b][i] + R[1][a][i] * R[1][b][i] + R[2][a][i] * R[2][b][i];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            double sum = 0.0;
            for (int a = 0; a < 3; ++a) sum += R[r][a][i] * ((a == c ? 3.0 : 0.0) - gram[a][c]);
            next[r][c] = 0.5 * sum;
          }
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) R[r][c][i] = ok[i] != 0.0 ? next[r][c] : R[r][c][i];
      }
}

SPOTKIN_CLONES_T((template <PoseFormat Format> __attribute__((noinline))), void, arm6_block, (<Format>), (const Arm6& solver, const Limits& limits,
                                      const double (*pose_in)[SphericalWrist6::kLanes], int m,
                                      Arm6Block& out) noexcept, (solver, limits, pose_in, m, out),
  constexpr int L = SphericalWrist6::kLanes, S = Arm6::kSlots;
  if (solver.direct_wrist()) {
    wrist_block<Format>(solver.wrist(), limits, pose_in, m, out);
    for (int k = 0; k < S; ++k)
      for (int i = 0; i < L; ++i) out.exact[k][i] = out.exists[k][i];
    return;
  }
  constexpr int width = Format == PoseFormat::Matrix ? 16 : 7;
  if (solver.lane_shoulder()) {
    // G^-1 = M T^-1 for the reversed chain (its joint i is joint 5 - i, negated), whose limits are
    // the negated, reversed ones; then the angles mapped back
    Limits reversed_limits;
    reversed_limits.dof = 6;
    for (int j = 0; j < 6; ++j) {
      reversed_limits.lower[j] = -limits.upper[5 - j], reversed_limits.upper[j] = -limits.lower[5 - j];
      reversed_limits.sigma[j] = 0;
    }
    const Rigid<double>& Mr = solver.M();
    double inner[16][L];
    for (int i = 0; i < L; ++i) {
      double in[width];
      for (int e = 0; e < width; ++e) in[e] = pose_in[e][std::min(i, m - 1)];
      Arm::Pose T;
      const bool ok = Arm::read_pose<Format>(in, T) != 0.0;
      const double nan = std::numeric_limits<double>::quiet_NaN();
      double Rin[3][3], pin[3];
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col)  // M.R R^T
          Rin[r][col] = Mr.R(r, 0) * T.R[col][0] + Mr.R(r, 1) * T.R[col][1] + Mr.R(r, 2) * T.R[col][2];
      }
      for (int r = 0; r < 3; ++r) pin[r] = Mr.p[r] - (Rin[r][0] * T.p[0] + Rin[r][1] * T.p[1] + Rin[r][2] * T.p[2]);
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col) inner[4 * r + col][i] = ok ? Rin[r][col] : nan;
        inner[4 * r + 3][i] = ok ? pin[r] : nan;
      }
      inner[12][i] = 0.0, inner[13][i] = 0.0, inner[14][i] = 0.0, inner[15][i] = 1.0;
    }
    wrist_block<PoseFormat::Matrix>(solver.wrist(), reversed_limits, inner, m, out);
    for (int k = 0; k < S; ++k)
      for (int i = 0; i < L; ++i) {
        double a[6];
        for (int j = 0; j < 6; ++j) a[j] = out.angle[k][j][i];
        for (int j = 0; j < 6; ++j) out.angle[k][j][i] = -a[5 - j];
        out.exact[k][i] = out.exists[k][i];
      }
    return;
  }
  double c[S][6][L], s[S][6][L];
  bool refine_slot[S][L] = {};
  Arm::Pose targets[L];
  bool shared = false;  // the lane solve's slots share q1 (by root 1) and q5, q6 (by roots 1 and 5)
  if (solver.lane_parallel() && m > Arm6::kShortBlock) {
    // every lane, a short block's padded with its last pose, so that a pose's answer does not
    // depend on its neighbours or on how a batch is split
    double R[3][3][L], t[3][L], fallback[L], exists[S][L], TR[3][3][L], Tp[3][L];
    read_pose_lanes<Format>(pose_in, m, TR, Tp, out.input_ok);
    const Rigid<double>& M_inv = solver.parallel().M_inv();
    double Mi[3][3], mp[3];
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) Mi[r][col] = M_inv.R(r, col);
      mp[r] = M_inv.p[r];
    }
    for (int i = 0; i < L; ++i)
      for (int r = 0; r < 3; ++r) {  // G = T M^-1
        for (int col = 0; col < 3; ++col)
          R[r][col][i] = TR[r][0][i] * Mi[0][col] + TR[r][1][i] * Mi[1][col] + TR[r][2][i] * Mi[2][col];
        t[r][i] = TR[r][0][i] * mp[0] + TR[r][1][i] * mp[1] + TR[r][2][i] * mp[2] + Tp[r][i];
      }
    solver.parallel().solve_lanes(R, t, out.input_ok, c, s, exists, fallback);
    for (int i = 0; i < L; ++i)
      for (int k = 0; k < S; ++k) out.exists[k][i] = exists[k][i];
    shared = true;
    for (int i = 0; i < m; ++i) {
      if (fallback[i] == 0.0 || out.input_ok[i] == 0.0) continue;
      shared = false;  // the lane's slots come from solve(): each angle on its own
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col) targets[i].R[r][col] = TR[r][col][i];
        targets[i].p[r] = Tp[r][i];
      }
      JointValue q[S][6];
      bool ok[S] = {}, refine[S] = {};
      solver.solve(targets[i], q, ok, refine);
      for (int k = 0; k < S; ++k) {
        refine_slot[k][i] = refine[k];
        out.exists[k][i] = ok[k] ? 1.0 : 0.0;
        for (int j = 0; j < 6; ++j) c[k][j][i] = ok[k] ? q[k][j].c : 1.0, s[k][j][i] = ok[k] ? q[k][j].s : 0.0;
      }
    }
  } else {
    for (int i = 0; i < m; ++i) {  // lanes from m on are never read
      double in[width];
      for (int e = 0; e < width; ++e) in[e] = pose_in[e][i];
      out.input_ok[i] = Arm::read_pose<Format>(in, targets[i]);
      if (Format == PoseFormat::Matrix && out.input_ok[i] != 0.0) project_rotation(targets[i]);
      JointValue q[S][6];
      bool ok[S] = {}, refine[S] = {};
      if (out.input_ok[i] != 0.0) solver.solve(targets[i], q, ok, refine);
      for (int k = 0; k < S; ++k) {
        refine_slot[k][i] = refine[k];
        out.exists[k][i] = ok[k] ? 1.0 : 0.0;
        for (int j = 0; j < 6; ++j) c[k][j][i] = ok[k] ? q[k][j].c : 1.0, s[k][j][i] = ok[k] ? q[k][j].s : 0.0;
      }
    }
  }
  // the angles of the m lanes in use (a short block pays for its poses only), 0 where no slot.
  // Slot k = 4 i1 + 2 i5 + i3 of the lane solve (Parallel234::solve_lanes): q1 is slot (k & 4)'s,
  // q5 and q6 slot (k & 6)'s, so 34 of the 48 atan2 are distinct; a copy has the same bits
  for (int k = 0; k < S; ++k)
    for (int j = 0; j < 6; ++j) {
      const int from = !shared ? k : j == 0 ? (k & 4) : j >= 4 ? (k & 6) : k;
      if (from == k)
        for (int i = 0; i < m; ++i) out.angle[k][j][i] = vector_math::atan2(s[k][j][i], c[k][j][i]);
      else
        for (int i = 0; i < m; ++i) out.angle[k][j][i] = out.angle[from][j][i];
    }
  for (int k = 0; k < S; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < m; ++i) out.angle[k][j][i] = out.exists[k][i] != 0.0 ? out.angle[k][j][i] : 0.0;
  for (int k = 0; k < S; ++k)
    for (int i = 0; i < m; ++i) out.exact[k][i] = 1.0;
  // Newton on the true chain for an idealised chain (a branch that does not converge there is
  // dropped) and for slots near a double root
  const bool idealised = solver.idealised();
  for (int i = 0; i < m; ++i)
      for (int k = 0; k < S; ++k) {
        if (out.exists[k][i] == 0.0 || !(idealised || refine_slot[k][i])) continue;
        double q[6];
        for (int j = 0; j < 6; ++j) q[j] = out.angle[k][j][i];
        const double residual = solver.polish(targets[i], q);
        out.exists[k][i] = residual <= Arm6::kAccept ? 1.0 : 0.0;
        out.exact[k][i] = residual < Arm6::kExact ? 1.0 : 0.0;
        for (int j = 0; j < 6; ++j) out.angle[k][j][i] = remainder_two_pi(q[j]);
      }
  // idealised chains: two starts polished to one solution keep the first slot
  for (int i = 0; i < m && idealised; ++i)
    for (int k = 1; k < S; ++k) {
      if (out.exists[k][i] == 0.0) continue;
      for (int o = 0; o < k && out.exists[k][i] != 0.0; ++o) {
        if (out.exists[o][i] == 0.0) continue;
        double gap = 0.0;
        for (int j = 0; j < 6; ++j)
          gap = std::max(gap, std::fabs(remainder_two_pi(out.angle[k][j][i] - out.angle[o][j][i])));
        if (gap < Arm6::kSame) out.exists[k][i] = 0.0;
      }
    }
  // idealised chains: a target within the geometry error of the idealised workspace's boundary
  // has fewer idealised solutions than the true chain; missing branches start from the target moved
  // radially (from axis 1) by -+ the nudge, each polished on the true target, and kept in its own
  // slot when that slot is free and it is a new solution
  for (int i = 0; i < m && idealised; ++i) {
    int count = 0;
    for (int k = 0; k < S; ++k) count += out.exists[k][i] != 0.0;
    if (out.input_ok[i] == 0.0 || count == S) continue;
    for (const double scale : {1.0 - solver.nudge(), 1.0 + solver.nudge()}) {
      Arm::Pose moved = targets[i];
      for (int r = 0; r < 3; ++r) moved.p[r] = solver.centre()[r] + scale * (targets[i].p[r] - solver.centre()[r]);
      JointValue q[S][6];
      bool ok[S] = {}, refine[S] = {};
      solver.solve(moved, q, ok, refine);
      for (int k = 0; k < S; ++k) {
        if (!ok[k] || out.exists[k][i] != 0.0) continue;
        double x[6];
        for (int j = 0; j < 6; ++j) x[j] = std::atan2(q[k][j].s, q[k][j].c);
        const double residual = solver.polish(targets[i], x);
        if (!(residual <= Arm6::kAccept)) continue;
        bool known = false;
        for (int o = 0; o < S && !known; ++o) {
          if (out.exists[o][i] == 0.0) continue;
          double gap = 0.0;
          for (int j = 0; j < 6; ++j)
            gap = std::max(gap, std::fabs(remainder_two_pi(x[j] - out.angle[o][j][i])));
          known = gap < Arm6::kSame;
        }
        if (known) continue;
        for (int j = 0; j < 6; ++j) out.angle[k][j][i] = remainder_two_pi(x[j]);
        out.exists[k][i] = 1.0;
        out.exact[k][i] = residual < Arm6::kExact ? 1.0 : 0.0;
      }
    }
  }
  finish_lanes<false>(limits, m, out.input_ok, out.angle, out.exists, out.valid);
  for (int k = 0; k < S; ++k)
    for (int i = 0; i < m; ++i) out.exact[k][i] *= out.exists[k][i];
  lane_status(m, out.input_ok, out.exists, out.valid, out.status);
)

template <PoseFormat Format, typename T, typename Store>
SPOTKIN_INLINE void arm6_blocks(const Arm6& solver, const Limits& limits, const T* poses, std::ptrdiff_t count,
                                Store&& store) noexcept {
  constexpr int L = SphericalWrist6::kLanes, width = Format == PoseFormat::Matrix ? 16 : 7;
  Arm6Block block;
  double pose_in[width][L];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, count - b0));
    for (int i = 0; i < m; ++i)
      for (int e = 0; e < width; ++e) pose_in[e][i] = double(poses[width * (b0 + i) + e]);
    arm6_block<Format>(solver, limits, pose_in, m, block);
    for (int i = 0; i < m; ++i) store(block, i, b0 + i);
  }
}

// Every solution: q (count, 8, 6), valid, exists and exact (count, 8), status (count).
template <PoseFormat Format, typename T>
SPOTKIN_INLINE void ik_arm6(const Arm6& solver, const Limits& limits, const T* poses, T* q, std::uint8_t* valid,
                            std::uint8_t* exists, std::uint8_t* exact, std::int8_t* status,
                            std::ptrdiff_t count) noexcept {
  constexpr int S = Arm6::kSlots, W = S * 6;
  arm6_blocks<Format>(solver, limits, poses, count, [&](const Arm6Block& block, int i, std::ptrdiff_t at) {
    store_lane(block, i, q + W * at, valid + S * at, exists + S * at, status + at);
    for (int k = 0; k < S; ++k) exact[S * at + k] = block.exact[k][i] != 0.0;
  });
}

// One solution per pose (store_nearest): q (count, 6), status (count); seed (count, 6) or null.
template <PoseFormat Format, typename T>
SPOTKIN_INLINE void ik_arm6_nearest(const Arm6& solver, const Limits& limits, const T* poses, const T* seed, T* q,
                                    std::int8_t* status, std::ptrdiff_t count) noexcept {
  arm6_blocks<Format>(solver, limits, poses, count, [&](const Arm6Block& block, int i, std::ptrdiff_t at) {
    store_nearest(block, i, limits, seed ? seed + 6 * at : nullptr, q + 6 * at, status + at);
  });
}

}  // namespace spotkin::chain_ik
