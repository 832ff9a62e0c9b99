// Bindings for spotkin::Arm: batched FK, Jacobian, singularity measures and
// closed-form IK with all 8 solutions.
#include "spotkin/kernels/arm.hpp"

#include <pybind11/stl.h>

#include <tuple>
#include <type_traits>

#include "binder.hpp"
#include "bindings.hpp"
#include "fast_call.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace arm_glue {

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

Arg seed_arg() { return Arg("seed", {6}, all_angles(6)).maybe_none().parameter(); }


py::object fk(const Arm& arm, py::handle q, py::handle out) {
  static const Op op({Arg("q", {6}, all_angles(6)).nan_rows()}, {Out("T", {4, 4})}, 20.0,
                     [](const void* c, const auto& b) { kernels::arm_fk(binder::context<Arm>(c), b.in[0], b.real(0), b.m); });
  return binder::call(op, &arm, {q}, out);
}

py::object jacobian(const Arm& arm, py::handle q, py::handle out) {
  static const Op op({Arg("q", {6}, all_angles(6)).nan_rows()}, {Out("J", {6, 6})}, 20.0,
                     [](const void* c, const auto& b) {
                       kernels::arm_jacobian(binder::context<Arm>(c), b.in[0], b.real(0), b.m);
                     });
  return binder::call(op, &arm, {q}, out);
}

// (..., 4) float64: the singularity measures (Arm::singularity), computed in float64.
py::object singularity(const Arm& arm, py::handle q) {
  static const Op op = Op({Arg("q", {6}, all_angles(6)).nan_rows()}, {Out("measures", {4})}, 160.0,
                          [](const void* c, const auto& b) {
                            if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>) {
                              const Arm& a = binder::context<Arm>(c);
                              for (std::ptrdiff_t i = 0; i < b.m; ++i) a.singularity(b.in[0] + 6 * i, b.real(0) + 4 * i);
                            }
                          })
                           .float64_only();
  return binder::call(op, &arm, {q}, py::none());
}

py::object ik_all(const Arm& arm, py::handle T, py::handle seed, py::handle out) {
  static const Op op = Op({pose_target_arg(), seed_arg()},
                     {Out("q", {Arm::kSlots, 6}), Out("valid", {Arm::kSlots}, Kind::Bool),
                      Out("exists", {Arm::kSlots}, Kind::Bool), Out("status", {}, Kind::Status)},
                     200.0, [](const void* c, const auto& b) {
                       kernels::arm_ik_all(binder::context<Arm>(c), b.in[0], pose_format(b), b.in[1], b.real(0),
                                           b.flags(1), b.flags(2), b.status(3), b.m);
                     }).returns("ArmSolutions");
  return binder::call(op, &arm, {T, seed}, out);
}

py::object ik(const Arm& arm, py::handle T, py::handle seed, py::handle out) {
  static const Op op({pose_target_arg(), seed_arg()}, {Out("q", {6}), Out("status", {}, Kind::Status)}, 200.0,
                     [](const void* c, const auto& b) {
                       kernels::arm_ik(binder::context<Arm>(c), b.in[0], pose_format(b), b.in[1], b.real(0),
                                       b.status(1), b.m);
                     });
  return binder::call(op, &arm, {T, seed}, out);
}

Arm make_arm(std::array<double, 3> mount, double upper_arm, double forearm, double forearm_offset, double hand,
             py::handle tool_obj, py::handle lower_limits, py::handle upper_limits) {
  for (double v : {mount[0], mount[1], mount[2], upper_arm, forearm, forearm_offset, hand})
    if (!std::isfinite(v)) throw std::invalid_argument("arm lengths and mount must be finite");
  if (!(upper_arm > 0.0) || !(std::hypot(forearm, forearm_offset) > 0.0))
    throw std::invalid_argument("upper_arm must be positive and the forearm non-degenerate");
  ArmGeometry g;
  for (int i = 0; i < 3; ++i) g.mount[i] = mount[i];
  g.upper_arm = upper_arm, g.forearm = forearm, g.forearm_offset = forearm_offset, g.hand = hand;
  if (!tool_obj.is_none()) {
    g.tool = rigid_from<Rigid<double>>(tool_obj, "tool");  // checked to be rigid there
  }
  JointLimits<6> limits;
  for (auto [obj, target, name] : {std::tuple{lower_limits, limits.lower, "lower limits"},
                                   std::tuple{upper_limits, limits.upper, "upper limits"}}) {
    auto arr = contiguous<double>(as_real_array(obj, name));
    if (arr.ndim() != 1 || arr.shape(0) != 6) throw py::value_error(std::string(name) + " must have shape (6,)");
    for (int j = 0; j < 6; ++j) target[j] = arr.data()[j];
  }
  for (int j = 0; j < 6; ++j)
    if (std::isnan(limits.lower[j]) || std::isnan(limits.upper[j]) || limits.lower[j] > limits.upper[j])
      throw std::invalid_argument("limits must satisfy lower <= upper, with no NaN");
  return Arm(g, limits);
}

}  // namespace arm_glue

void bind_arm(py::module_& m) {
  using namespace arm_glue;
  py::class_<Arm> cls(m, "Arm");
  cls.def(py::init(&make_arm), py::arg("mount"), py::arg("upper_arm"), py::arg("forearm"),
          py::arg("forearm_offset"), py::arg("hand"), py::arg("tool"), py::arg("lower_limits"),
          py::arg("upper_limits"))
      .def("singularity", &singularity, py::arg("q"));
  fast::def_fast<&fk>(cls, "fk", py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&jacobian>(cls, "jacobian", py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&ik>(cls, "ik", py::arg("T"), py::arg("seed") = py::none(),
                      py::arg("out") = py::none());
  fast::def_fast<&ik_all>(cls, "ik_all", py::arg("T"), py::arg("seed") = py::none(),
                          py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
