// Binding of the standing statics (spotkin/dynamics/statics.hpp). The façade
// (Robot.standing_torques) broadcasts and flattens the batch; here every array has
// the same leading count N and is checked by shape.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "numpy_boundary.hpp"
#include "spotkin/dynamics/statics.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

py::array_t<double, py::array::c_style> checked(py::handle obj, const char* name, const Shape& shape) {
  py::array arr = as_real_array(obj, name);
  const Shape got(arr.shape(), arr.shape() + arr.ndim());
  if (got != shape) throw py::value_error(std::string(name) + " must have shape " + format_shape(shape) + ", got " + format_shape(got));
  return contiguous<double>(arr);
}

py::tuple standing_torques(py::handle com_obj, double mass, py::handle feet_obj, py::handle jacobians_obj,
                           py::handle leg_gravity_obj, py::handle stance_obj, py::handle gravity_obj) {
  py::array com_arr = as_real_array(com_obj, "com");
  if (com_arr.ndim() != 2 || com_arr.shape(1) != 3)
    throw py::value_error("com must have shape (N, 3), got " +
                          format_shape(Shape(com_arr.shape(), com_arr.shape() + com_arr.ndim())));
  const py::ssize_t n = com_arr.shape(0);
  py::array feet_arr = as_real_array(feet_obj, "feet");
  if (feet_arr.ndim() != 3 || feet_arr.shape(0) != n || feet_arr.shape(2) != 3)
    throw py::value_error("feet must have shape (N, legs, 3)");
  const py::ssize_t legs = feet_arr.shape(1);
  if (legs < 1 || legs > dynamics::kMaxFeet)
    throw py::value_error("standing torques take 1 to " + std::to_string(dynamics::kMaxFeet) + " legs, got " +
                          std::to_string(legs));
  if (!(mass >= 0.0) || !std::isfinite(mass)) throw py::value_error("mass must be finite and non-negative");
  auto com = contiguous<double>(com_arr);
  auto feet = contiguous<double>(feet_arr);
  auto jacobians = checked(jacobians_obj, "foot_jacobians", {n, legs, 3, 3});
  auto leg_gravity = checked(leg_gravity_obj, "leg_gravity", {n, 3 * legs});
  auto stance = checked(stance_obj, "stance", {n, legs});
  auto gravity = checked(gravity_obj, "gravity", {n, 3});  // per sample (the body frame's)
  auto tau = new_array<double>({n}, {3 * legs});
  auto forces = new_array<double>({n}, {legs, 3});
  auto status = new_array<std::int8_t>({n}, {});
  auto margin = new_array<double>({n}, {});
  const double *c = com.data(), *p = feet.data(), *J = jacobians.data(), *G = leg_gravity.data(), *s = stance.data(),
               *g = gravity.data();
  double *t = tau.mutable_data(), *f = forces.mutable_data(), *mg = margin.mutable_data();
  std::int8_t* st = status.mutable_data();
  const int L = static_cast<int>(legs);
  {
    ReleaseGilFor release(n);
    parallel_for(n, min_chunk(2000.0), [&](std::ptrdiff_t b, std::ptrdiff_t e) {
      for (std::ptrdiff_t i = b; i < e; ++i) {
        std::uint8_t on[dynamics::kMaxFeet];
        bool stance_ok = true;
        for (int l = 0; l < L; ++l) {
          const double v = s[L * i + l];
          on[l] = v != 0.0;
          stance_ok = stance_ok && (v == 0.0 || v == 1.0);
        }
        if (!stance_ok) {  // a NaN in the mask: invalid, as any non-finite input
          for (int j = 0; j < 3 * L; ++j) t[3 * L * i + j] = std::numeric_limits<double>::quiet_NaN();
          for (int j = 0; j < 3 * L; ++j) f[3 * L * i + j] = std::numeric_limits<double>::quiet_NaN();
          st[i] = static_cast<std::int8_t>(dynamics::Stance::InvalidInput);
          mg[i] = std::numeric_limits<double>::quiet_NaN();
          continue;
        }
        dynamics::standing_sample(L, c + 3 * i, mass, p + 3 * L * i, J + 9 * L * i, G + 3 * L * i, on, g + 3 * i,
                                  t + 3 * L * i, f + 3 * L * i, st + i, mg + i);
      }
    });
  }
  return py::make_tuple(tau, forces, status, margin);
}

}  // namespace

void bind_statics(py::module_& m) {
  m.def("standing_torques", &standing_torques, py::arg("com"), py::arg("mass"), py::arg("feet"),
        py::arg("foot_jacobians"), py::arg("leg_gravity"), py::arg("stance"), py::arg("gravity"),
        "Minimum-norm stance forces and leg torques, per sample of flat (N, ...) arrays (see "
        "spotkin/dynamics/statics.hpp).");
}

}  // namespace spotkin::bindings
