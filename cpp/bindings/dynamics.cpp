// Bindings for the rigid-body dynamics of a fixed-base chain (spotkin/dynamics/):
// RNEA, CRBA, G, h, the Coriolis matrix and ABA, batched. Every batch input
// broadcasts over its leading dimensions like NumPy; float32 inputs (all of the
// state arguments) compute in float32, anything else in float64.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "binder.hpp"
#include "chain_model.hpp"
#include "dynamics_boundary.hpp"
#include "fast_call.hpp"

namespace spotkin::bindings {

namespace dynamics_glue {

ChainDynamics make_chain_dynamics(const ChainPair& chain, py::handle mass, py::handle com, py::handle inertia) {
  const auto links = inertials_from(mass, com, inertia, chain.f64.dof());
  try {
    return ChainDynamics{{ChainModel<double, kLanes64>(chain.f64, links), ChainModel<float, kLanes32>(chain.f64, links),
                          ChainModel<double, kMidLanes64>(chain.f64, links),
                          ChainModel<float, kMidLanes32>(chain.f64, links),
                          ChainModel<double, kSmallLanes64>(chain.f64, links),
                          ChainModel<float, kSmallLanes32>(chain.f64, links)}};
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}



// Rough single-thread cost per sample of a 6-joint chain (for the thread split).
constexpr double kNsPerSample = 150.0;

using binder::Arg;
using binder::Op;
using binder::Out;

// The batch arguments: q (its revolute columns are angles), the other joint vectors, gravity (a parameter).
Arg joints(const ChainDynamics& d, const char* name) { return Arg(name, {d.dof()}).rows_strided(); }
Arg positions(const ChainDynamics& d) { return Arg("q", {d.dof()}, d.f64.angle_columns()).rows_strided(); }


py::object chain_rnea(const ChainDynamics& d, py::handle q, py::handle qd, py::handle qdd, py::handle g,
                      py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), joints(d, "qd"), joints(d, "qdd"), gravity_arg()},
              {Out("tau", {d.dof()})}, kNsPerSample, [](const void* c, const auto& b) {
                on_model<ChainDynamics>(c, b, [&](const auto& model) {
                  const auto qd = rows(b, 1), qdd = rows(b, 2);
                  dynamics::rnea_k(model, rows(b, 0), &qd, &qdd, rows(b, 3), b.real(0), 0, b.m,
                                   b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.dof()), d.f64.angle_columns(), 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, qd, qdd, g}, out); });
}

py::object chain_gravity(const ChainDynamics& d, py::handle q, py::handle g, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), gravity_arg()}, {Out("tau", {d.dof()})}, kNsPerSample,
              [](const void* c, const auto& b) {
                on_model<ChainDynamics>(c, b, [&](const auto& model) {
                  dynamics::rnea_k(model, rows(b, 0), nullptr, nullptr, rows(b, 1), b.real(0), 0,
                                   b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.dof()), d.f64.angle_columns(), 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, g}, out); });
}

py::object chain_nonlinear(const ChainDynamics& d, py::handle q, py::handle qd, py::handle g, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), joints(d, "qd"), gravity_arg()}, {Out("h", {d.dof()})}, kNsPerSample,
              [](const void* c, const auto& b) {
                on_model<ChainDynamics>(c, b, [&](const auto& model) {
                  const auto qd = rows(b, 1);
                  dynamics::rnea_k(model, rows(b, 0), &qd, nullptr, rows(b, 2), b.real(0), 0, b.m,
                                   b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.dof()), d.f64.angle_columns(), 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, qd, g}, out); });
}


py::object chain_crba(const ChainDynamics& d, py::handle q, py::handle layout_name, py::handle out) {
  const MassMatrix<ChainDynamics> context{d, symmetric_layout(layout_name)};
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d)}, {Out("A", symmetric_shape(d.dof(), context.layout))}, kNsPerSample,
              [](const void* c, const auto& b) {
                const auto& mm = binder::context<MassMatrix<ChainDynamics>>(c);
                with_model<typename std::decay_t<decltype(b)>::Scalar>(
                    mm.d,
                    [&](const auto& model) {
                      dynamics::crba_k(model, rows(b, 0), b.real(0), 0, b.m, b.stream, mm.layout);
                    },
                    b.m);
              });
  };
  return ops.with({std::uint64_t(d.dof()), d.f64.angle_columns(), std::uint64_t(context.layout)},
                  make, [&](const Op& op) { return binder::call(op, &context, {q}, out); });
}

py::object chain_coriolis(const ChainDynamics& d, py::handle q, py::handle qd, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), joints(d, "qd")}, {Out("C", {d.dof(), d.dof()})}, 2 * kNsPerSample,
              [](const void* c, const auto& b) {
                on_model<ChainDynamics>(c, b, [&](const auto& model) {
                  dynamics::coriolis_k(model, rows(b, 0), rows(b, 1), b.real(0), 0, b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.dof()), d.f64.angle_columns(), 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, qd}, out); });
}

py::object chain_aba(const ChainDynamics& d, py::handle q, py::handle qd, py::handle tau, py::handle g,
                     py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({positions(d), joints(d, "qd"), joints(d, "tau"), gravity_arg()},
              {Out("qdd", {d.dof()})}, 2 * kNsPerSample, [](const void* c, const auto& b) {
                on_model<ChainDynamics>(c, b, [&](const auto& model) {
                  dynamics::aba_k(model, rows(b, 0), rows(b, 1), rows(b, 2), rows(b, 3), b.real(0),
                                  0, b.m, b.stream);
                });
              });
  };
  return ops.with({std::uint64_t(d.dof()), d.f64.angle_columns(), 0}, make,
                  [&](const Op& op) { return binder::call(op, &d, {q, qd, tau, g}, out); });
}

}  // namespace dynamics_glue

void bind_dynamics(py::module_& m) {
  using namespace dynamics_glue;
  py::class_<ChainDynamics> cls(m, "ChainDynamics");
  cls.def(py::init(&make_chain_dynamics), py::arg("chain"), py::arg("mass"), py::arg("com"),
          py::arg("inertia"))
      .def_property_readonly("dof", &ChainDynamics::dof);
  fast::def_fast<&chain_rnea>(cls, "rnea", py::arg("q"), py::arg("qd"), py::arg("qdd"),
                              py::arg("gravity"), py::arg("out") = py::none());
  fast::def_fast<&chain_gravity>(cls, "gravity", py::arg("q"), py::arg("gravity"),
                                 py::arg("out") = py::none());
  fast::def_fast<&chain_nonlinear>(cls, "nonlinear_effects", py::arg("q"), py::arg("qd"),
                                   py::arg("gravity"), py::arg("out") = py::none());
  fast::def_fast<&chain_crba>(cls, "crba", py::arg("q"), py::arg("layout") = "full",
                              py::arg("out") = py::none());
  fast::def_fast<&chain_coriolis>(cls, "coriolis_matrix", py::arg("q"), py::arg("qd"),
                                  py::arg("out") = py::none());
  fast::def_fast<&chain_aba>(cls, "aba", py::arg("q"), py::arg("qd"), py::arg("tau"),
                             py::arg("gravity"), py::arg("out") = py::none());
  bind_floating_dynamics(m);
}

}  // namespace spotkin::bindings
