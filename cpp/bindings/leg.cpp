// Bindings for spotkin::Leg: batched FK, Jacobian, singularity measures and
// closed-form IK (limit-aware choice, and every branch).
#include "spotkin/kernels/leg.hpp"

#include <pybind11/stl.h>

#include <array>
#include <tuple>

#include "binder.hpp"
#include "bindings.hpp"
#include "fast_call.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace leg_glue {

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

struct Solve {
  const Leg& leg;
  bool nearest_fallback;
};

py::object fk(const Leg& leg, py::handle q, py::handle out) {
  static const Op op({Arg("q", {3}, all_angles(3)).nan_rows()}, {Out("p", {3})}, 25.0,
                     [](const void* c, const auto& b) { kernels::leg_fk(binder::context<Leg>(c), b.in[0], b.real(0), b.m); });
  return binder::call(op, &leg, {q}, out);
}

py::object jacobian(const Leg& leg, py::handle q, py::handle out) {
  static const Op op({Arg("q", {3}, all_angles(3)).nan_rows()}, {Out("J", {3, 3})}, 25.0,
                     [](const void* c, const auto& b) {
                       kernels::leg_jacobian(binder::context<Leg>(c), b.in[0], b.real(0), b.m);
                     });
  return binder::call(op, &leg, {q}, out);
}

py::object singularity(const Leg& leg, py::handle q, py::handle out) {
  static const Op op({Arg("q", {3}, all_angles(3)).nan_rows()}, {Out("abs_det", {}), Out("sigma_min", {})}, 200.0,
                     [](const void* c, const auto& b) {
                       const Leg& l = binder::context<Leg>(c);
                       for (std::ptrdiff_t i = 0; i < b.m; ++i) l.singularity(b.in[0] + 3 * i, b.real(0) + i, b.real(1) + i);
                     });
  return binder::call(op, &leg, {q}, out);
}

// p (..., 3), seed None or (..., 3), broadcasting -> (q (..., 3), status (...)).
py::object ik(const Leg& leg, py::handle p, py::handle seed, bool nearest_fallback, py::handle out) {
  static const Op op({Arg("p", {3}), Arg("seed", {3}, all_angles(3)).maybe_none().parameter()},
                     {Out("q", {3}), Out("status", {}, Kind::Status)}, 25.0, [](const void* c, const auto& b) {
                       const Solve& s = binder::context<Solve>(c);
                       kernels::leg_ik(s.leg, b.in[0], b.in[1], b.real(0), b.status(1), b.m, s.nearest_fallback);
                     });
  const Solve context{leg, nearest_fallback};
  return binder::call(op, &context, {p, seed}, out);
}

py::object ik_all(const Leg& leg, py::handle p, py::handle out) {
  static const Op op = Op({Arg("p", {3})},
                     {Out("q", {Leg::kSlots, 3}), Out("valid", {Leg::kSlots}, Kind::Bool),
                      Out("exists", {Leg::kSlots}, Kind::Bool), Out("status", {}, Kind::Status)},
                     25.0, [](const void* c, const auto& b) {
                       kernels::leg_ik_all(binder::context<Leg>(c), b.in[0], b.real(0), b.flags(1), b.flags(2),
                                           b.status(3), b.m);
                     }).returns("LegSolutions");
  return binder::call(op, &leg, {p}, out);
}

std::array<double, 3> vector3(py::handle obj, const char* name) {
  auto arr = contiguous<double>(as_real_array(obj, name));
  if (arr.ndim() != 1 || arr.shape(0) != 3) throw py::value_error(std::string(name) + " must have shape (3,)");
  std::array<double, 3> v{arr.data()[0], arr.data()[1], arr.data()[2]};
  for (double x : v)
    if (!std::isfinite(x)) throw py::value_error(std::string(name) + " must be finite");
  return v;
}

// a, b, c, signs: (3,) each (rpp_geometry.hpp); limits (3,) each.
Leg make_leg(py::handle a, py::handle b, py::handle c, py::handle signs, py::handle lower_limits,
             py::handle upper_limits, int preferred_slot) {
  RppGeometry g;
  const auto va = vector3(a, "a"), vb = vector3(b, "b"), vc = vector3(c, "c"), vs = vector3(signs, "signs");
  for (int k = 0; k < 3; ++k) g.a[k] = va[k], g.b[k] = vb[k], g.c[k] = vc[k], g.sign[k] = vs[k];
  JointLimits<3> limits;
  for (auto [obj, target, name] : {std::tuple{lower_limits, limits.lower, "lower limits"},
                                   std::tuple{upper_limits, limits.upper, "upper limits"}}) {
    auto arr = contiguous<double>(as_real_array(obj, name));
    if (arr.ndim() != 1 || arr.shape(0) != 3)
      throw py::value_error(std::string(name) + " must have shape (3,)");
    for (int j = 0; j < 3; ++j) target[j] = arr.data()[j];
  }
  for (int j = 0; j < 3; ++j)
    if (std::isnan(limits.lower[j]) || std::isnan(limits.upper[j]) || limits.lower[j] > limits.upper[j])
      throw std::invalid_argument("limits must satisfy lower <= upper, with no NaN");
  return Leg(g, limits, preferred_slot);
}

}  // namespace leg_glue

void bind_leg(py::module_& m) {
  using namespace leg_glue;
  py::class_<Leg> cls(m, "Leg");
  cls.def(py::init(&make_leg), py::arg("a"), py::arg("b"), py::arg("c"), py::arg("signs"),
          py::arg("lower_limits"), py::arg("upper_limits"), py::arg("preferred_slot") = -1)
      .def_property_readonly("preferred_slot", &Leg::preferred_slot)
      .def_property_readonly("max_reach", &Leg::max_reach)
      .def_property_readonly("min_reach", &Leg::min_reach)
      .def("singularity", &singularity, py::arg("q"), py::arg("out") = py::none())
      .def(
          "nearest_reachable",
          [](const Leg& leg, std::array<double, 3> p, bool within_limits) {
            std::array<double, 3> out, q;
            leg.nearest_reachable(p.data(), out.data(), within_limits, q.data());
            return py::make_tuple(out, q);
          },
          py::arg("p"), py::arg("within_limits") = false);
  fast::def_fast<&fk>(cls, "fk", py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&jacobian>(cls, "jacobian", py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&ik>(cls, "ik", py::arg("p"), py::arg("seed") = py::none(),
                      py::arg("nearest_fallback") = true, py::arg("out") = py::none());
  fast::def_fast<&ik_all>(cls, "ik_all", py::arg("p"), py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
