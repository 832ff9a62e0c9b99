// Bindings for the rigid-body dynamics of a fixed-base chain (spotkin/dynamics/):
// RNEA, CRBA, G, h, the Coriolis matrix and ABA, batched. Every batch input
// broadcasts over its leading dimensions like NumPy; float32 inputs (all of the
// state arguments) compute in float32, anything else in float64.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "dynamics_boundary.hpp"
#include "chain_model.hpp"

namespace spotkin::bindings {

namespace dynamics_glue {

ChainDynamics make_chain_dynamics(const ChainPair& chain, py::handle mass, py::handle com, py::handle inertia) {
  const auto links = inertials_from(mass, com, inertia, chain.f64.dof());
  try {
    return ChainDynamics{ChainModel<double, kLanes64>(chain.f64, links), ChainModel<float, kLanes32>(chain.f64, links),
                         ChainModel<double, kMidLanes64>(chain.f64, links),
                         ChainModel<float, kMidLanes32>(chain.f64, links),
                         ChainModel<double, kSmallLanes64>(chain.f64, links),
                         ChainModel<float, kSmallLanes32>(chain.f64, links)};
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}



// Rough single-thread cost per sample of a 6-joint chain (for the thread split).
constexpr double kNsPerSample = 150.0;

py::object chain_rnea(const ChainDynamics& d, py::handle q, py::handle qd, py::handle qdd, py::handle g) {
  const py::ssize_t n = d.dof();
  return run_batch({{q, "q", n, true, d.f64.angle_columns()}, {qd, "qd", n}, {qdd, "qdd", n}, {g, "gravity", 3, false}}, {n}, kNsPerSample,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::rnea_k(model, rows[0], &rows[1], &rows[2], rows[3], out, b, e);
                     });
                   });
}

py::object chain_gravity(const ChainDynamics& d, py::handle q, py::handle g) {
  const py::ssize_t n = d.dof();
  return run_batch({{q, "q", n, true, d.f64.angle_columns()}, {g, "gravity", 3, false}}, {n}, kNsPerSample,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::rnea_k(model, rows[0], nullptr, nullptr, rows[1], out, b, e);
                     });
                   });
}

py::object chain_nonlinear(const ChainDynamics& d, py::handle q, py::handle qd, py::handle g) {
  const py::ssize_t n = d.dof();
  return run_batch({{q, "q", n, true, d.f64.angle_columns()}, {qd, "qd", n}, {g, "gravity", 3, false}}, {n}, kNsPerSample,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::rnea_k(model, rows[0], &rows[1], nullptr, rows[2], out, b, e);
                     });
                   });
}

py::object chain_crba(const ChainDynamics& d, py::handle q, py::handle layout_name) {
  const py::ssize_t n = d.dof();
  const dynamics::SymmetricLayout layout = symmetric_layout(layout_name);
  return run_batch({{q, "q", n, true, d.f64.angle_columns()}}, symmetric_shape(n, layout), kNsPerSample,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::crba_k(model, rows[0], out, b, e, layout);
                     });
                   });
}

py::object chain_coriolis(const ChainDynamics& d, py::handle q, py::handle qd) {
  const py::ssize_t n = d.dof();
  return run_batch({{q, "q", n, true, d.f64.angle_columns()}, {qd, "qd", n}}, {n, n}, 2 * kNsPerSample,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::coriolis_k(model, rows[0], rows[1], out, b, e);
                     });
                   });
}

py::object chain_aba(const ChainDynamics& d, py::handle q, py::handle qd, py::handle tau, py::handle g) {
  const py::ssize_t n = d.dof();
  return run_batch({{q, "q", n, true, d.f64.angle_columns()}, {qd, "qd", n}, {tau, "tau", n}, {g, "gravity", 3, false}}, {n}, 2 * kNsPerSample,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::aba_k(model, rows[0], rows[1], rows[2], rows[3], out, b, e);
                     });
                   });
}

}  // namespace dynamics_glue

void bind_dynamics(py::module_& m) {
  using namespace dynamics_glue;
  py::class_<ChainDynamics>(m, "ChainDynamics")
      .def(py::init(&make_chain_dynamics), py::arg("chain"), py::arg("mass"), py::arg("com"), py::arg("inertia"))
      .def_property_readonly("dof", &ChainDynamics::dof)
      .def("rnea", &chain_rnea, py::arg("q"), py::arg("qd"), py::arg("qdd"), py::arg("gravity"))
      .def("gravity", &chain_gravity, py::arg("q"), py::arg("gravity"))
      .def("nonlinear_effects", &chain_nonlinear, py::arg("q"), py::arg("qd"), py::arg("gravity"))
      .def("crba", &chain_crba, py::arg("q"), py::arg("layout") = "full")
      .def("coriolis_matrix", &chain_coriolis, py::arg("q"), py::arg("qd"))
      .def("aba", &chain_aba, py::arg("q"), py::arg("qd"), py::arg("tau"), py::arg("gravity"));
  bind_floating_dynamics(m);
}

}  // namespace spotkin::bindings
