// One binder per concept; module.cpp calls them all.
#pragma once

#include <pybind11/pybind11.h>

namespace spotkin::bindings {
void bind_chain(pybind11::module_& m);
void bind_runtime(pybind11::module_& m);
void bind_leg(pybind11::module_& m);
void bind_arm(pybind11::module_& m);
void bind_body(pybind11::module_& m);
void bind_paul(pybind11::module_& m);
void bind_chain_ik(pybind11::module_& m);
void bind_trajectory(pybind11::module_& m);
void bind_differential(pybind11::module_& m);
void bind_diagnostics(pybind11::module_& m);
}  // namespace spotkin::bindings
