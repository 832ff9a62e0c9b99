// The gait planner: a quadruped's walk, one command at a time, tick by tick. It mirrors the
// pure-Python reference (python/spotkin/reference/gait_plan.py, whose numbered steps and lettered
// formulas (P), (Q), (S), (F), (B), (C) are cited here; docs/guide/walking.md explains them):
//   advance()  steps 1-4: the gait's blend, the clock, the ramped planar motion, the latched
//              contacts and, at a lift-off, the foothold (Raibert, bounded by the leg's reach);
//   sample()   a tick's body pose, feet, contacts and twist.
// plan_command() runs them over every tick of one command, then solves the whole-body IK along the
// path (each tick seeded with the previous one), the joint velocities and the standing statics.
// Everything is double; a command's ticks are sequential, commands are independent (threads).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "spotkin/body.hpp"
#include "spotkin/dynamics/robot_statics.hpp"
#include "spotkin/scratch.hpp"

namespace spotkin::motion {

constexpr int kLegs = 4;  // quadrupeds

// The resolved gait's numbers that blend (reference KEYS), flattened in this order.
enum GaitSlot : int {
  kPeriod = 0,
  kDuty = 1,
  kOffsets = 2,                      // (4,)
  kStepHeight = kOffsets + kLegs,    // 6
  kHeight,                           // 7: the body's height above the ground
  kHipHeight,                        // 8: h, the speed and length scale
  kStance,                           // 9: (4, 3) the nominal feet, body frame (z: above the ground)
  kComShift = kStance + 3 * kLegs,   // 21: w, the crawl's shift weight
  kShift,                            // 22: (2,) s0
  kSway = kShift + 2,                // 24: (4, 2) (X_i, Y_i) of (C)
  kCaptureGain = kSway + 2 * kLegs,  // 32
  kAccel,                            // 33
  kYawAccel,                         // 34
  kStepReach,                        // 35: (4, 2) rho per axis
  kMoving = kStepReach + 2 * kLegs,  // 43
  kGaitNumbers                       // 44
};

struct GaitNumbers {
  double v[kGaitNumbers];
  GaitNumbers() noexcept : v{} {}
  // Scratch that is written whole before it is read: no zeroing (the planner's per-tick copies).
  explicit GaitNumbers(Uninitialized) noexcept {}
  double operator[](int k) const noexcept { return v[k]; }
  double& operator[](int k) noexcept { return v[k]; }
};

constexpr double kLiftoffFraction = 0.75;  // LIFTOFF_FRACTION
constexpr int kPredictionSteps = 16;       // PREDICTION_STEPS
constexpr int kChecks = 4;                 // CHECKS
constexpr double kStepFit = 0.8;           // STEP_FIT
constexpr int kBisections = 30;            // BISECTIONS of (B)
constexpr double kGravity = 9.81;          // G

// Everything the planner remembers between ticks (reference PlannerState).
struct PlannerState {
  double t = 0, theta = 0, clock_rate = 0;
  double x = 0, y = 0, psi = 0, v[2] = {0, 0}, w = 0;
  double command[3] = {0, 0, 0};
  double roll = 0, pitch = 0;
  GaitNumbers old_numbers, new_numbers;
  double t0 = 0, duration = 0;
  bool contact[kLegs] = {};
  double cycles[kLegs] = {};  // floor(theta + o_i), integral values
  double lift_phase[kLegs] = {}, lift_height[kLegs] = {};
  double p_stance[kLegs][3] = {}, p_touchdown[kLegs][3] = {};
  bool step_shortened[kLegs] = {};
  double speed_scale = 1;
  // derived, for speed: the settled gait's step-fit scale under the command (< 0: not yet known;
  // change() forgets it), and the attitude's cosines and sines
  mutable double settled_scale = -1, settled_command[3] = {0, 0, 0};
  double cos_roll = 1, sin_roll = 0, cos_pitch = 1, sin_pitch = 0;
  // closed-loop inputs (a controller's; absent in a plan)
  bool has_v_measured = false, has_ground = false, has_ground_offsets = false,
       has_p_measured = false;
  double v_measured[2] = {0, 0}, ground[3] = {0, 0, 0}, ground_offsets[kLegs] = {},
         p_measured[2] = {0, 0};
};

// One tick's kinematic outputs (reference sample, before the IK).
struct TickKinematics {
  double pose[6];  // [x, y, z, a, b, c], Euler "XYZ"
  double R[3][3];  // its rotation
  double feet[kLegs][3], feet_rate[kLegs][3];
  bool contact[kLegs];
  double linear[3], angular[3];  // the body's twist, world axes
  bool shortened;
};

void start(const GaitNumbers& gait, const double command[3], const double attitude[2],
           PlannerState& s) noexcept;
// A new gait (blended from now) and / or a new command; either may be null.
void change(PlannerState& s, const GaitNumbers* gait, const double* command) noexcept;
void advance(const Body& body, PlannerState& s, double dt) noexcept;
// The commanded roll and pitch of the body (a controller's, tick by tick).
void set_attitude(PlannerState& s, double roll, double pitch) noexcept;
// Reference formulas the controller shares: (Q), (S), (C), step 1 and the body pose.
struct Quintic {
  double b, db, d2b;
};
Quintic quintic(double x) noexcept;
void swing(const double p0[3], const double p1[3], double s, double height, double p[3],
           double dp[3], double d2p[3]) noexcept;
void blended(const PlannerState& s, double t, GaitNumbers& P, GaitNumbers* rates) noexcept;
void crawl_shift(const GaitNumbers& P, const GaitNumbers& Pd, const double* phases,
                 const double* phase_rates, double value[2], double rate[2]) noexcept;
double floor_height(const PlannerState& s, double x, double y) noexcept;
// [x, y, z, a, b, c] (Euler "XYZ") of the body at (x, y, z), heading psi (cos, sin given), the
// state's attitude; R (optional): its rotation.
void body_pose(double x, double y, double z, double psi, double cos_psi, double sin_psi,
               const PlannerState& s, double pose[6], double (*R)[3] = nullptr) noexcept;
inline double frac(double x) noexcept { return x - std::floor(x); }
// x mod m as Python's float % (m > 0: the result in [0, m)).
double py_mod(double x, double m) noexcept;
// x = A^-1 b (3x3 row-major) by the adjugate (Cramer's rule), branch-free (the plan's statics run
// it in lanes); returns det, and x is meaningless where det is 0 or not finite.
SPOTKIN_INLINE double adjugate_solve(const double* A, const double* b, double* x) noexcept {
  const double c0[3] = {A[4] * A[8] - A[5] * A[7], A[5] * A[6] - A[3] * A[8],
                        A[3] * A[7] - A[4] * A[6]};
  const double det = A[0] * c0[0] + A[1] * c0[1] + A[2] * c0[2];
  const double inv = 1.0 / det;  // the rows of adj(A), the cofactors' transpose
  x[0] = (c0[0] * b[0] + (A[2] * A[7] - A[1] * A[8]) * b[1] + (A[1] * A[5] - A[2] * A[4]) * b[2]) *
         inv;
  x[1] = (c0[1] * b[0] + (A[0] * A[8] - A[2] * A[6]) * b[1] + (A[2] * A[3] - A[0] * A[5]) * b[2]) *
         inv;
  x[2] = (c0[2] * b[0] + (A[1] * A[6] - A[0] * A[7]) * b[1] + (A[0] * A[4] - A[1] * A[3]) * b[2]) *
         inv;
  return det;
}
// adjugate_solve; false (x not written) when singular (det 0) or not finite, or x not finite. The
// references' np.linalg.solve agrees to rounding away from singular matrices.
bool solve3(const double* A, const double* b, double* x) noexcept;
// The Euler sequence "XYZ" of the plans' body poses.
const EulerSequence& xyz_sequence() noexcept;
// (M): the signed distance of c to the convex hull of the points (k <= Body::kMaxLegs), positive
// inside; outside, minus the distance to the hull; fewer than three points off one line: minus the
// distance to their segment or point; -inf with none.
double support_margin(const double (*points)[2], int k, const double c[2]) noexcept;
void sample(const PlannerState& s, TickKinematics& out) noexcept;

// One command's plan over `ticks` ticks t_k = k / rate, written at row k of each output:
// pose (6), feet (4, 3), contact (4), q (12), qd (12), tau (12), status, margin, shortened,
// residual (6). q is in the body's column order (the robot's leg joint order).
struct PlanRows {
  double* pose;
  double* feet;
  bool* contact;
  double* q;
  double* qd;
  double* tau;
  std::int8_t* status;
  double* margin;
  bool* shortened;
  double* residual;
};

// A change during a plan (reference plan's `changes`): at the first tick at or after `time` (after
// its advance, before its sample), the gait (null: unchanged) and / or the command (null:
// unchanged).
struct PlanChange {
  double time;
  const GaitNumbers* gait;
  const double* command;
};

template <typename Model>
void plan_command(const dynamics::RobotStaticsModel<Model>& robot, const GaitNumbers& gait,
                  const double command[3], const double attitude[2], std::ptrdiff_t ticks,
                  double rate, const PlanRows& out, const PlanChange* changes = nullptr,
                  int n_changes = 0);

// The statics along a plan's path (plan_command's last stage, gait_statics.cpp): from the rows'
// pose, feet, contact and q, with each tick's rotation (9, row-major), feet velocities (4, 3) and
// body twist [v; w] (6, world), and the legs' IK statuses (4): the rows' status, qd, tau, residual
// and margin.
template <typename Model>
void plan_statics(const dynamics::RobotStaticsModel<Model>& robot, const PlanRows& out,
                  const double* rotation, const double* feet_rate, const double* twist,
                  const std::int8_t* leg_status, std::ptrdiff_t ticks);

}  // namespace spotkin::motion
