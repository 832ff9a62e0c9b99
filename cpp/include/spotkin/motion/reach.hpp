// Whole-body reach: the body pose, legs and arm that put a legged robot's hand on a target with the
// feet fixed. The search of python/spotkin/reference/reach.py, step for step (its letters (S) ...
// (F) are cited in reach.cpp): candidates in the body-pose box, the legs' and the arm's closed
// forms at each (the batched kernels over a target's candidates), the feasible option of least
// cost, a few Gauss-Newton steps on the body pose, and a damped least-squares repair when no
// candidate reaches. Targets go in blocks of kReachBlock, searched together; the binding runs the
// blocks on the threads.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spotkin/arm.hpp"
#include "spotkin/body.hpp"
#include "spotkin/chain.hpp"
#include "spotkin/chain_ik/arm6.hpp"
#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/dynamics/robot_statics.hpp"

namespace spotkin::motion {

constexpr int kReachCandidates =
    64;  // CANDIDATES: Halton points after the seed's pose and the nominal
constexpr int kReachStageTwo = 8;             // STAGES[1]: the Halton points of (C)'s second stage
constexpr double kReachFdStep = 1e-6;         // FD_STEP
constexpr double kReachGnDamping = 1e-6;      // GN_DAMPING
constexpr int kReachRepairIterations = 60;    // REPAIR_ITERATIONS
constexpr double kReachRepairDamping = 1e-2;  // REPAIR_DAMPING
constexpr double kReachRepairStall = 1e4;
constexpr int kReachRepairCheck = 5;        // REPAIR_CHECK     // REPAIR_STALL
constexpr int kReachRepairStarts = 6;       // REPAIR_STARTS
constexpr int kReachActiveSetPasses = 3;    // ACTIVE_SET_PASSES
constexpr double kReachRepairInset = 1e-6;  // REPAIR_INSET
constexpr double kReachNullGain = 0.2;      // NULL_GAIN
constexpr int kReachMaxQ = 3 * Body::kMaxLegs + 6;
constexpr int kReachMaxSegments = 8;
constexpr int kReachBlock = 64;  // targets searched together: one call of each kernel per step

// The statuses (ReachStatus).
enum ReachCode : std::int8_t {
  kReachOk = 0,
  kReachUnreachable = 1,
  kReachUnstable = 2,
  kReachInvalid = 3
};

// The arm: its closed form (exactly one of spot and six), and its chain from the body (body <-
// hand: the FK of the repair and the capsules' frames).
struct ReachArm {
  const Arm* spot = nullptr;
  const chain_ik::Arm6* six = nullptr;
  const chain_ik::Limits* six_limits = nullptr;
  const Chain<double>* chain = nullptr;
  double mount[16];  // body <- arm base, row-major
};

// The capsule model (spotkin/motion/capsules.py): segment k of the arm runs from frame points[k] to
// frame points[k + 1] of the chain's frames; checked against the body box where vs_body[k], against
// leg l's upper (0) and lower (1) capsule where vs_legs[k][l][part].
struct ReachCapsules {
  bool enabled = false;
  double radius = 0.0;
  double box_centre[3] = {}, box_half[3] = {};
  int n_points = 0;
  int points[kReachMaxSegments + 1] = {};
  bool vs_body[kReachMaxSegments] = {};
  bool vs_legs[kReachMaxSegments][Body::kMaxLegs][2] = {};
};

// The numbers shared by every target of a call: the box (absolute, in the stance frame), the
// nominal pose, the scale L, the whole-body limits (m = 3 legs + 6), the residual's widths.
struct ReachShared {
  double nominal[6], lower[6], upper[6], w_p[6];
  double scale;
  int m;
  int refine_steps;  // REFINE_STEPS of (R)
  double q_lower[kReachMaxQ], q_upper[kReachMaxQ], w_q[kReachMaxQ];
  double halton[kReachCandidates][6];  // the unit points of (C)
  // S <- body at the nominal pose (0) and at (C)'s points (1 + k), set by prepare_shared
  double local[kReachCandidates + 1][16];
};

// Sets shared.local from the nominal pose, the box and the Halton points.
void prepare_shared(ReachShared& shared);

// One target's inputs (row-major): world <- hand target (16), feet (legs, 3), world <- S (16), the
// residual's references p_ref (6) and q_ref (m), the seed's pose in S (6, or null) and the margin.
struct ReachInput {
  const double* target;
  const double* feet;
  const double* stance;
  const double* p_ref;
  const double* q_ref;
  const double* seed_pose;
  double margin;
  bool refine = true;  // (R); false: the chosen option as it is
  bool repair = true;  // (F); false: UNREACHABLE with NaN answers when no candidate reaches
};

// One target's outputs: body pose (6, world, Euler "XYZ"), q (m), status, margin, distance, angle,
// the arm's branches at the chosen pose (8 x 6) and their validity (8), the chosen branch (-1:
// none).
struct ReachOutput {
  double* body_pose;
  double* q;
  std::int8_t* status;
  double* margin;
  double* distance;
  double* angle;
  double* branches;
  std::uint8_t* valid;
  std::int64_t* slot;
};

// The floating models reach runs on (one sample's, as dynamics' with_model picks for one sample):
// the 4-lane model at the AVX2 and AVX-512 levels, the 2-lane model at the baseline.
using ReachVectorModel = dynamics::FloatingModel<double, dynamics::kMidLanes64>;
using ReachBaselineModel = dynamics::FloatingModel<double, dynamics::kSmallLanes64>;

// The answers for count (at most kReachBlock) targets in[k] -> out[k], searched together: each
// step of the search runs the kernels once over the candidates of every target still searching
// (NaN and INVALID_INPUT for a target that is not a finite rigid transform, or non-finite feet,
// margin or references). A target's answer is the one it gets alone, whatever its block (up to the
// arm's scalar and lane paths, an ulp). The vector model's runs at the AVX2 and AVX-512 levels
// only (it is compiled for AVX2), the baseline model's at any.
void reach_block(const dynamics::RobotStaticsModel<ReachVectorModel>& robot, const ReachArm& arm,
                 const ReachCapsules& capsules, const ReachShared& shared, const ReachInput* in,
                 const ReachOutput* out, int count);
void reach_block(const dynamics::RobotStaticsModel<ReachBaselineModel>& robot, const ReachArm& arm,
                 const ReachCapsules& capsules, const ReachShared& shared, const ReachInput* in,
                 const ReachOutput* out, int count);

// The constraints of (A) at one whole-body sample: world <- body T_body (16), q (m) and the feet
// (legs, 3): its support margin (M), and whether an arm capsule collides (with the body, a leg or
// the ground).
template <typename Model>
void reach_constraints(const dynamics::RobotStaticsModel<Model>& robot, const ReachArm& arm,
                       const ReachCapsules& capsules, const ReachShared& shared,
                       const double* T_body, const double* q, const double* feet, double* margin,
                       bool* collides);

}  // namespace spotkin::motion
