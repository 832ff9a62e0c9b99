// The closed-form IK of a chain as the bindings hold it (_core.ChainIK): chain_ik.cpp binds it, and
// the reach binding (motion.cpp) solves an arm's branches with it.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>
#include <optional>
#include <string>

#include "spotkin/chain_ik.hpp"
#include "spotkin/chain_ik/arm6.hpp"

namespace spotkin::bindings {

namespace py = pybind11;

namespace chain_ik_glue {

using chain_ik::Arm6;
using chain_ik::Limits;
using chain_ik::Position3;

struct ChainIK {
  std::optional<Position3> position;  // 3-joint chains
  std::optional<Arm6> arm;            // 6-joint chains
  Limits limits;
  std::uint64_t revolute_columns = 0;  // huge seed angles are reduced exactly

  std::string kind() const { return position ? position->name() : arm->kind(); }
  std::string position_kind() const { return position ? position->name() : arm->position_kind(); }
  bool idealised() const { return arm && arm->idealised(); }
  py::dict geometry() const {
    py::dict out;
    if (arm) {
      const auto& g = arm->geometry();
      out["wrist_meeting"] = g.wrist, out["shoulder_meeting"] = g.shoulder;
      out["parallel_234"] = g.parallel234, out["parallel_123"] = g.parallel123;
      out["axes_5_6_gap"] = g.gap56, out["axes_4_5_gap"] = g.gap45;
    }
    return out;
  }
};

}  // namespace chain_ik_glue

}  // namespace spotkin::bindings
