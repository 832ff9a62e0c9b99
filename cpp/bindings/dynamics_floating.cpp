// Bindings for the floating-base dynamics (spotkin/dynamics/floating.hpp): a
// free-flyer body carrying ChainDynamics chains; RNEA, CRBA, G, h, ABA, the
// centre of mass and its Jacobian, batched.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "binder.hpp"
#include "dynamics_boundary.hpp"
#include "fast_call.hpp"

namespace spotkin::bindings {

namespace floating_glue {

FloatingDynamics make_floating(py::handle mass, py::handle com, py::handle inertia, const py::sequence& chain_list) {
  std::vector<ChainDynamics> chains;
  for (py::handle c : chain_list) {
    if (!py::isinstance<ChainDynamics>(c)) throw py::type_error("chains must hold ChainDynamics objects");
    chains.push_back(c.cast<const ChainDynamics&>());
  }
  auto mass_arr = as_real_array(mass, "body_mass");
  if (mass_arr.ndim() != 0) throw py::value_error("body_mass must be a scalar");
  auto com_arr = as_real_array(com, "body_com"), inertia_arr = as_real_array(inertia, "body_inertia");
  if (Shape(com_arr.shape(), com_arr.shape() + com_arr.ndim()) != Shape{3})
    throw py::value_error("body_com must have shape (3,)");
  if (Shape(inertia_arr.shape(), inertia_arr.shape() + inertia_arr.ndim()) != Shape{3, 3})
    throw py::value_error("body_inertia must have shape (3, 3)");
  const auto links = inertials_from(mass_arr.reshape(Shape{1}), com_arr.reshape(Shape{1, 3}),
                                    inertia_arr.reshape(Shape{1, 3, 3}), 1, "body_");
  std::vector<ChainModel<double, kLanes64>> c64;
  std::vector<ChainModel<float, kLanes32>> c32;
  std::vector<ChainModel<double, kMidLanes64>> m64;
  std::vector<ChainModel<float, kMidLanes32>> m32;
  std::vector<ChainModel<double, kSmallLanes64>> s64;
  std::vector<ChainModel<float, kSmallLanes32>> s32;
  for (const auto& c : chains) {
    c64.push_back(c.f64), c32.push_back(c.f32), m64.push_back(c.f64_mid), m32.push_back(c.f32_mid);
    s64.push_back(c.f64_small), s32.push_back(c.f32_small);
  }
  std::uint64_t angles = 0;
  int column = 7;  // after [x, y, z, qx, qy, qz, qw]
  for (const auto& c : chains)
    for (int j = 0; j < c.dof(); ++j, ++column)
      if (column < 64 && ((c.f64.angle_columns() >> j) & 1U)) angles |= std::uint64_t{1} << column;
  try {
    return FloatingDynamics{{FloatingModel<double, kLanes64>(links[0], std::move(c64)),
                             FloatingModel<float, kLanes32>(links[0], std::move(c32)),
                             FloatingModel<double, kMidLanes64>(links[0], std::move(m64)),
                             FloatingModel<float, kMidLanes32>(links[0], std::move(m32)),
                             FloatingModel<double, kSmallLanes64>(links[0], std::move(s64)),
                             FloatingModel<float, kSmallLanes32>(links[0], std::move(s32))},
                            angles};
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}



constexpr double kNsFloating = 400.0;

using binder::Arg;
using binder::Op;
using binder::Out;

// q (..., nq) = [x, y, z, qx, qy, qz, qw, joints]: the revolute joints' huge angles reduced exactly.
Arg positions(const FloatingDynamics& d) { return Arg("q", {d.f64.nq()}, d.angles).rows_strided(); }
Arg rates(const FloatingDynamics& d, const char* name) { return Arg(name, {d.f64.nv()}).rows_strided(); }


py::object floating_rnea(const FloatingDynamics& d, py::handle q, py::handle v, py::handle a, py::handle g,
                         py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), rates(d, "v"), rates(d, "a"), gravity_arg()},
              {Out("tau", {d.f64.nv()})}, kNsFloating, [](const void* c, const auto& b) {
                on_model<FloatingDynamics>(c, b, [&](const auto& model) {
                  const auto v = rows(b, 1), acc = rows(b, 2);
                  dynamics::floating_rnea_k(model, rows(b, 0), &v, &acc, rows(b, 3), b.real(0), 0,
                                            b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, v, a, g}, out); });
}

py::object floating_gravity(const FloatingDynamics& d, py::handle q, py::handle g, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), gravity_arg()}, {Out("tau", {d.f64.nv()})}, kNsFloating,
              [](const void* c, const auto& b) {
                on_model<FloatingDynamics>(c, b, [&](const auto& model) {
                  dynamics::floating_rnea_k(model, rows(b, 0), nullptr, nullptr, rows(b, 1),
                                            b.real(0), 0, b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, g}, out); });
}

py::object floating_nonlinear(const FloatingDynamics& d, py::handle q, py::handle v, py::handle g, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), rates(d, "v"), gravity_arg()}, {Out("h", {d.f64.nv()})}, kNsFloating,
              [](const void* c, const auto& b) {
                on_model<FloatingDynamics>(c, b, [&](const auto& model) {
                  const auto v = rows(b, 1);
                  dynamics::floating_rnea_k(model, rows(b, 0), &v, nullptr, rows(b, 2), b.real(0),
                                            0, b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, v, g}, out); });
}


py::object floating_crba(const FloatingDynamics& d, py::handle q, py::handle layout_name, py::handle out) {
  const MassMatrix<FloatingDynamics> context{d, symmetric_layout(layout_name)};
  static binder::OpCache ops;
  const auto make = [&] {
    return Op(
        {positions(d)}, {Out("A", symmetric_shape(d.f64.nv(), context.layout))}, kNsFloating,
        [](const void* c, const auto& b) {
          const auto& mm = binder::context<MassMatrix<FloatingDynamics>>(c);
          with_model<typename std::decay_t<decltype(b)>::Scalar>(
              mm.d,
              [&](const auto& model) {
                dynamics::floating_crba_k(model, rows(b, 0), b.real(0), 0, b.m, b.stream,
                                          mm.layout);
              },
              b.m);
        });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, std::uint64_t(context.layout)}, make,
                  [&](const Op& op) { return binder::call(op, &context, {q}, out); });
}

py::object floating_aba(const FloatingDynamics& d, py::handle q, py::handle v, py::handle tau, py::handle g,
                        py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), rates(d, "v"), rates(d, "tau"), gravity_arg()},
              {Out("a", {d.f64.nv()})}, 2 * kNsFloating, [](const void* c, const auto& b) {
                on_model<FloatingDynamics>(c, b, [&](const auto& model) {
                  dynamics::floating_aba_k(model, rows(b, 0), rows(b, 1), rows(b, 2), rows(b, 3),
                                           b.real(0), 0, b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, v, tau, g}, out); });
}

py::object floating_coriolis(const FloatingDynamics& d, py::handle q, py::handle v, py::handle out) {
  const py::ssize_t nv = d.f64.nv();
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), rates(d, "v")}, {Out("C", {nv, nv})}, 3 * kNsFloating,
              [](const void* c, const auto& b) {
                on_model<FloatingDynamics>(c, b, [&](const auto& model) {
                  dynamics::floating_coriolis_k(model, rows(b, 0), rows(b, 1), b.real(0), 0, b.m,
                                                b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, v}, out); });
}

template <bool Jacobian>
py::object floating_com(const FloatingDynamics& d, py::handle q, py::handle out) {
  const Out result = Jacobian ? Out("J_com", {3, d.f64.nv()}) : Out("com", {3});
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d)}, {result}, kNsFloating, [](const void* c, const auto& b) {
      on_model<FloatingDynamics>(c, b, [&](const auto& model) {
        dynamics::floating_com_k(model, rows(b, 0), b.real(0), Jacobian, 0, b.m, b.stream);
      });
    });
  };
  return ops.with({std::uint64_t(d.f64.nq()), d.angles, 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q}, out); });
}

}  // namespace floating_glue

void bind_floating_dynamics(py::module_& m) {
  using namespace floating_glue;
  py::class_<FloatingDynamics> cls(m, "FloatingDynamics");
  cls.def(py::init(&make_floating), py::arg("body_mass"), py::arg("body_com"),
          py::arg("body_inertia"), py::arg("chains"))
      .def_property_readonly("nq", [](const FloatingDynamics& d) { return d.f64.nq(); })
      .def_property_readonly("nv", [](const FloatingDynamics& d) { return d.f64.nv(); });
  fast::def_fast<&floating_rnea>(cls, "rnea", py::arg("q"), py::arg("v"), py::arg("a"),
                                 py::arg("gravity"), py::arg("out") = py::none());
  fast::def_fast<&floating_gravity>(cls, "gravity", py::arg("q"), py::arg("gravity"),
                                    py::arg("out") = py::none());
  fast::def_fast<&floating_nonlinear>(cls, "nonlinear_effects", py::arg("q"), py::arg("v"),
                                      py::arg("gravity"), py::arg("out") = py::none());
  fast::def_fast<&floating_crba>(cls, "crba", py::arg("q"), py::arg("layout") = "full",
                                 py::arg("out") = py::none());
  fast::def_fast<&floating_coriolis>(cls, "coriolis_matrix", py::arg("q"), py::arg("v"),
                                     py::arg("out") = py::none());
  fast::def_fast<&floating_aba>(cls, "aba", py::arg("q"), py::arg("v"), py::arg("tau"),
                                py::arg("gravity"), py::arg("out") = py::none());
  fast::def_fast<&floating_com<false>>(cls, "com", py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&floating_com<true>>(cls, "com_jacobian", py::arg("q"),
                                      py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
