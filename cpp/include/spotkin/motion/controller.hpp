// The closed-loop gait controller, one robot and one tick at a time: the pure-Python reference
// (python/spotkin/reference/controller.py, whose numbered steps are cited here) line for line. It
// runs the planner's state machine (gait_plan.hpp) with its closed-loop inputs, reads the measured
// contacts, re-anchors the reference to the measured body, solves the joints and their velocities,
// and gives the feedforward torques: gravity, the weight and a virtual body wrench on the loaded
// feet by the torque-weighted least squares (T), and the swing legs' inertia.
#pragma once

#include <cstdint>

#include "spotkin/dynamics/robot_statics.hpp"
#include "spotkin/motion/gait_plan.hpp"

namespace spotkin::motion {

constexpr double kSwingBandwidth = 16.0;  // reference SWING_BANDWIDTH ...
constexpr double kAnchor = 0.03;
constexpr double kYawAnchor = 0.1;
constexpr double kTerrainFollow = 1.0;
constexpr double kTerrainRoll = 0.0;
constexpr double kReachDown = 0.3;
constexpr double kFriction = 0.6;
constexpr double kAccelTime = 0.02;
constexpr double kMaxGap = 0.1;
constexpr double kGroundTime = 0.25;
constexpr double kHorizontalWrench = 0.3;   // HORIZONTAL_WRENCH
constexpr double kTorqueAlpha = 1e4;        // (T)'s alpha, beta and eps
constexpr double kTorqueHorizontal = 1e-2;  // beta of (T)
constexpr double kTorqueCap = 0.8;          // (T) holds a joint's torque here, of its limit
constexpr double kTorqueCapWeight = 1e3;
constexpr int kTorqueCapRounds = 3;
constexpr double kTorqueEps = 1e-6;

// What a controller knows of its robot, computed once (the reference's constructor): the speed
// scale h, the gains, the body's inertia for the virtual moment, each leg's block of A(q) at the
// nominal stance, the effort limits, the commanded attitude. Joint arrays in q's order.
struct ControllerConfig {
  double h, mass, body_omega;
  double body_inertia[9];
  double kp[3 * kLegs], kd[3 * kLegs], stance_kp[3 * kLegs], stance_kd[3 * kLegs],
      effort[3 * kLegs];
  double leg_inertia[kLegs][9];
  double attitude[2];
};

// One robot's controller state between ticks (the reference's _Memory).
struct ControllerMemory {
  bool started = false;
  PlannerState plan;
  int gait = -1;  // the index of its gait in the controller's table
  bool reaching[kLegs] = {}, landed[kLegs] = {true, true, true, true};
  double shift[2] = {0, 0}, shift_rate[2] = {0, 0}, depth[kLegs] = {};
  double ground_points[kLegs][3] = {}, ground[3] = {0, 0, 0};
  bool has_q = false, has_v_ref = false;
  double q[3 * kLegs] = {}, v_ref[3] = {0, 0, 0}, a_ref[3] = {0, 0, 0};
  double t = 0, settle = 0;
};

// One tick's measured state and command (q, qd in q's order; contact null when not measured).
struct ControllerInput {
  double t;
  const double *position, *quaternion, *linear_velocity, *angular_velocity, *q, *qd;
  const bool* contact;
  const double* command;
};

// The joint command and the tick's details (the reference's `last`).
struct ControllerOutput {
  double q[3 * kLegs], qd[3 * kLegs], tau[3 * kLegs], kp[3 * kLegs], kd[3 * kLegs];
  bool contact[kLegs];
  double body_pose[6], feet[kLegs][3];
  bool loaded[kLegs], clipped[3 * kLegs], shortened, reaching[kLegs];
  double margin, measured_margin, forces[kLegs][3], residual[6], wrench[6], ground[3];
  std::int8_t status;
};

// One tick of one robot. gaits: the controller's resolved gaits (its centre-of-mass shift applied
// in every gait); start_gait: the gait of a robot's first tick; new_gait: a gait change (-1: none).
template <typename Model>
void controller_tick(const dynamics::RobotStaticsModel<Model>& robot,
                     const ControllerConfig& config, const GaitNumbers* gaits, int start_gait,
                     int new_gait, ControllerMemory& memory, const ControllerInput& in,
                     ControllerOutput& out);

}  // namespace spotkin::motion
