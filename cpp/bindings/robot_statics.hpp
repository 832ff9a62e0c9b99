// A legged robot as the statics and the motion bindings see it (statics.cpp binds it as
// _core.RobotStatics; motion.cpp plans gaits over it).
#pragma once

#include <cstddef>
#include <type_traits>

#include "dynamics_boundary.hpp"
#include "spotkin/body.hpp"
#include "spotkin/dynamics/robot_statics.hpp"

namespace spotkin::bindings {

// The robot: its legs (Body: leg l's joints are q's columns[l]), its floating model (the body, then
// the legs' chains, then the arm's, in q's order) and its total mass. Held by reference: the
// Python object keeps both alive.
struct RobotStatics {
  const Body& body;
  const FloatingDynamics& floating;
  double mass;
  int n_arm;
};

// f(the robot with the active level's floating model)
template <typename F>
void on_robot(const RobotStatics& r, std::ptrdiff_t samples, F&& f) {
  with_model<double>(
      r.floating,
      [&](const auto& model) {
        f(dynamics::RobotStaticsModel<std::decay_t<decltype(model)>>{r.body, model, r.mass,
                                                                     r.n_arm});
      },
      samples);
}

}  // namespace spotkin::bindings
