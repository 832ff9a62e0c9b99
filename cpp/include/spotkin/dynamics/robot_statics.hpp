// A legged robot's centre of mass and standing statics from its body pose and joints, in
// batches: the floating model's centre of mass and gravity torques (spotkin/dynamics/kernels.hpp),
// the legs' FK and Jacobians (spotkin/leg.hpp), and the minimum-norm stance forces
// (spotkin/dynamics/statics.hpp). Compiled once in cpp/src/robot_statics.cpp, for float and double
// rows and the floating model at each lane width; the bindings pick the active level's model.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spotkin/body.hpp"
#include "spotkin/dynamics/floating.hpp"
#include "spotkin/dynamics/stance.hpp"

namespace spotkin::dynamics {

constexpr int kStaticsSubBlock = 16;  // samples per call of the floating kernels (scratch on the stack)
constexpr int kStaticsMaxQ = 128;     // the floating model's q, at most (7 + the joints)

// A robot's statics: its legs (leg l's joints are q's body.columns[l]), its floating model (the
// body, then the legs' chains, then the arm's, in q's order), its total mass and its arm's joints.
template <typename Model>
struct RobotStaticsModel {
  const Body& body;
  const Model& floating;
  double mass;
  int n_arm;
};

// m samples' rows, row i of each at ptr + i * stride: body poses in `format`, the joints (the legs',
// or the legs' then the arm's when with_arm) and the stance mask (null: every leg in stance).
template <typename T>
struct StaticsRows {
  const T* pose;
  std::ptrdiff_t pose_stride;
  BodyPoseFormat format;
  const T* q;
  std::ptrdiff_t q_stride;
  bool with_arm;
  const T* stance = nullptr;
  std::ptrdiff_t stance_stride = 0;
};

// com (m, 3): c = t + R c_body, the whole robot's centre of mass in the world; NaN for an invalid
// sample (a pose that is not rigid, a joint that is not finite).
template <typename Model, typename T>
void robot_com(const RobotStaticsModel<Model>& robot, const EulerSequence& seq, const StaticsRows<T>& rows, T* com,
               std::ptrdiff_t m);

// The standing statics of each sample, in the body frame where only gravity's direction depends on
// the pose: tau_l = G_l - J_l^T f_l (statics.hpp), the forces and the residual wrench then turned
// to the world. tau (m, 3 legs) in q's leg columns, forces (m, legs, 3), status (m) Stance codes,
// margin (m), residual (m, 6) [force; moment about the centre of mass].
template <typename Model, typename T>
void robot_standing(const RobotStaticsModel<Model>& robot, const EulerSequence& seq,
                    const double gravity[3], const StaticsRows<T>& rows, T* tau, T* forces,
                    std::int8_t* status, T* margin, T* residual, std::ptrdiff_t m);

}  // namespace spotkin::dynamics
