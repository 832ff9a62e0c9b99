// Binding of the standing statics (spotkin/dynamics/statics.hpp), through the binder: every
// per-sample array broadcasts over the leading dimensions.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <limits>
#include <string>
#include <type_traits>

#include "binder.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/dynamics/statics.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

struct Standing {
  double mass;
  int legs;
};

// Per sample: com (3), feet (legs, 3), foot Jacobians (legs, 3, 3), the legs' gravity torques
// (3 legs), the stance mask (legs: 0 or 1) and gravity (3), broadcast; float64.
py::tuple standing_torques(py::handle com, double mass, py::handle feet, py::handle jacobians, py::handle leg_gravity,
                           py::handle stance, py::handle gravity) {
  py::array feet_arr = as_real_array(feet, "feet");
  if (feet_arr.ndim() < 2 || feet_arr.shape(feet_arr.ndim() - 1) != 3)
    throw py::value_error("feet must have shape (..., legs, 3), got " +
                          format_shape(Shape(feet_arr.shape(), feet_arr.shape() + feet_arr.ndim())));
  const py::ssize_t legs = feet_arr.shape(feet_arr.ndim() - 2);
  if (legs < 1 || legs > dynamics::kMaxFeet)
    throw py::value_error("standing torques take 1 to " + std::to_string(dynamics::kMaxFeet) + " legs, got " +
                          std::to_string(legs));
  if (!(mass >= 0.0) || !std::isfinite(mass)) throw py::value_error("mass must be finite and non-negative");
  const Op op = Op({Arg("com", {3}), Arg("feet", {legs, 3}), Arg("foot_jacobians", {legs, 3, 3}),
                    Arg("leg_gravity", {3 * legs}), Arg("stance", {legs}), Arg("gravity", {3})},
                   {Out("tau", {3 * legs}), Out("forces", {legs, 3}), Out("status", {}, Kind::Status),
                    Out("margin", {})},
                   2000.0, [](const void* c, const auto& b) {
                     if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>) {
                       const Standing& s = binder::context<Standing>(c);
                       const int L = s.legs;
                       for (std::ptrdiff_t i = 0; i < b.m; ++i) {
                         double* t = b.real(0) + 3 * L * i;
                         double* f = b.real(1) + 3 * L * i;
                         std::int8_t* st = b.status(2) + i;
                         double* mg = b.real(3) + i;
                         std::uint8_t on[dynamics::kMaxFeet];
                         bool stance_ok = true;
                         for (int l = 0; l < L; ++l) {
                           const double v = b.in[4][L * i + l];
                           on[l] = v != 0.0;
                           stance_ok = stance_ok && (v == 0.0 || v == 1.0);
                         }
                         if (!stance_ok) {  // a NaN in the mask: invalid, as any non-finite input
                           std::fill(t, t + 3 * L, std::numeric_limits<double>::quiet_NaN());
                           std::fill(f, f + 3 * L, std::numeric_limits<double>::quiet_NaN());
                           *st = static_cast<std::int8_t>(dynamics::Stance::InvalidInput);
                           *mg = std::numeric_limits<double>::quiet_NaN();
                           continue;
                         }
                         dynamics::standing_sample(L, b.in[0] + 3 * i, s.mass, b.in[1] + 3 * L * i,
                                                   b.in[2] + 9 * L * i, b.in[3] + 3 * L * i, on, b.in[5] + 3 * i, t,
                                                   f, st, mg);
                       }
                     }
                   })
                   .float64_only();
  const Standing context{mass, int(legs)};
  return binder::call(op, &context, {com, feet, jacobians, leg_gravity, stance, gravity}, py::none());
}

}  // namespace

void bind_statics(py::module_& m) {
  m.def("standing_torques", &standing_torques, py::arg("com"), py::arg("mass"), py::arg("feet"),
        py::arg("foot_jacobians"), py::arg("leg_gravity"), py::arg("stance"), py::arg("gravity"),
        "Minimum-norm stance forces and leg torques, per sample of flat (N, ...) arrays (see "
        "spotkin/dynamics/statics.hpp).");
}

}  // namespace spotkin::bindings
