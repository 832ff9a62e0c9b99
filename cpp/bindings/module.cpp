// The private extension module spotkin._core.
#include <pybind11/pybind11.h>

#include "bindings.hpp"

namespace spotkin::bindings::binder {
void bind_result_types(pybind11::module_& m);  // binder.cpp
}
namespace spotkin::bindings {
void bind_dynamics(pybind11::module_& m);  // dynamics.cpp
void bind_statics(pybind11::module_& m);   // statics.cpp
void bind_core_method(pybind11::module_& m);  // forward.cpp
void bind_motion(pybind11::module_& m);       // motion.cpp
void bind_reach(pybind11::module_& m);        // reach.cpp
}

PYBIND11_MODULE(_core, m) {
  m.doc() = "spotkin's C++ core. Use the public façade in `spotkin` instead.";
  spotkin::bindings::binder::bind_result_types(m);
  spotkin::bindings::bind_runtime(m);
  spotkin::bindings::bind_chain(m);
  spotkin::bindings::bind_leg(m);
  spotkin::bindings::bind_arm(m);
  spotkin::bindings::bind_body(m);
  spotkin::bindings::bind_paul(m);
  spotkin::bindings::bind_chain_ik(m);
  spotkin::bindings::bind_trajectory(m);
  spotkin::bindings::bind_differential(m);
  spotkin::bindings::bind_diagnostics(m);
  spotkin::bindings::bind_dynamics(m);
  spotkin::bindings::bind_statics(m);
  spotkin::bindings::bind_core_method(m);
  spotkin::bindings::bind_motion(m);
  spotkin::bindings::bind_reach(m);
}
