// Bindings for the floating-base dynamics (spotkin/dynamics/floating.hpp): a
// free-flyer body carrying ChainDynamics chains; RNEA, CRBA, G, h, ABA, the
// centre of mass and its Jacobian, batched.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "dynamics_boundary.hpp"

namespace spotkin::bindings {

namespace floating_glue {

using dynamics::FloatingModel;

// ---------------------------------------------------------------- floating base

struct FloatingDynamics {
  FloatingModel<double, kLanes64> f64;
  FloatingModel<float, kLanes32> f32;
  FloatingModel<double, kMidLanes64> f64_mid;
  FloatingModel<float, kMidLanes32> f32_mid;
  FloatingModel<double, kSmallLanes64> f64_small;
  FloatingModel<float, kSmallLanes32> f32_small;
  const FloatingModel<double, kLanes64>& get(double) const { return f64; }
  const FloatingModel<float, kLanes32>& get(float) const { return f32; }
  const FloatingModel<double, kMidLanes64>& mid(double) const { return f64_mid; }
  const FloatingModel<float, kMidLanes32>& mid(float) const { return f32_mid; }
  const FloatingModel<double, kSmallLanes64>& small(double) const { return f64_small; }
  const FloatingModel<float, kSmallLanes32>& small(float) const { return f32_small; }
  std::uint64_t angles = 0;  // the q columns that are joint angles (7 + each revolute joint's index)
};

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
    return FloatingDynamics{FloatingModel<double, kLanes64>(links[0], std::move(c64)),
                            FloatingModel<float, kLanes32>(links[0], std::move(c32)),
                            FloatingModel<double, kMidLanes64>(links[0], std::move(m64)),
                            FloatingModel<float, kMidLanes32>(links[0], std::move(m32)),
                            FloatingModel<double, kSmallLanes64>(links[0], std::move(s64)),
                            FloatingModel<float, kSmallLanes32>(links[0], std::move(s32)), angles};
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}



constexpr double kNsFloating = 400.0;

py::object floating_rnea(const FloatingDynamics& d, py::handle q, py::handle v, py::handle a, py::handle g) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  return run_batch({{q, "q", nq, true, d.angles}, {v, "v", nv}, {a, "a", nv}, {g, "gravity", 3, false}}, {nv}, kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::floating_rnea_k(model, rows[0], &rows[1], &rows[2], rows[3], out, b, e, stream);
                     });
                   });
}
py::object floating_gravity(const FloatingDynamics& d, py::handle q, py::handle g) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  return run_batch({{q, "q", nq, true, d.angles}, {g, "gravity", 3, false}}, {nv}, kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::floating_rnea_k(model, rows[0], nullptr, nullptr, rows[1], out, b, e, stream);
                     });
                   });
}
py::object floating_nonlinear(const FloatingDynamics& d, py::handle q, py::handle v, py::handle g) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  return run_batch({{q, "q", nq, true, d.angles}, {v, "v", nv}, {g, "gravity", 3, false}}, {nv}, kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::floating_rnea_k(model, rows[0], &rows[1], nullptr, rows[2], out, b, e, stream);
                     });
                   });
}
py::object floating_crba(const FloatingDynamics& d, py::handle q, py::handle layout_name) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  const dynamics::SymmetricLayout layout = symmetric_layout(layout_name);
  return run_batch({{q, "q", nq, true, d.angles}}, symmetric_shape(nv, layout), kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::floating_crba_k(model, rows[0], out, b, e, stream, layout);
                     });
                   });
}
py::object floating_aba(const FloatingDynamics& d, py::handle q, py::handle v, py::handle tau, py::handle g) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  return run_batch({{q, "q", nq, true, d.angles}, {v, "v", nv}, {tau, "tau", nv}, {g, "gravity", 3, false}}, {nv}, 2 * kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::floating_aba_k(model, rows[0], rows[1], rows[2], rows[3], out, b, e, stream);
                     });
                   });
}
py::object floating_coriolis(const FloatingDynamics& d, py::handle q, py::handle v) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  return run_batch({{q, "q", nq, true, d.angles}, {v, "v", nv}}, {nv, nv}, 3 * kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) { dynamics::floating_coriolis_k(model, rows[0], rows[1], out, b, e, stream); });
                   });
}
py::object floating_com(const FloatingDynamics& d, py::handle q, bool jacobian) {
  const py::ssize_t nq = d.f64.nq(), nv = d.f64.nv();
  return run_batch({{q, "q", nq, true, d.angles}}, jacobian ? Shape{3, nv} : Shape{3}, kNsFloating,
                   [&](const auto& rows, auto* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream) {
                     using T = std::remove_pointer_t<decltype(out)>;
                     with_model<T>(d, [&](const auto& model) {
                       dynamics::floating_com_k(model, rows[0], out, jacobian, b, e, stream);
                     });
                   });
}

}  // namespace floating_glue

void bind_floating_dynamics(py::module_& m) {
  using namespace floating_glue;
  py::class_<FloatingDynamics>(m, "FloatingDynamics")
      .def(py::init(&make_floating), py::arg("body_mass"), py::arg("body_com"), py::arg("body_inertia"),
           py::arg("chains"))
      .def_property_readonly("nq", [](const FloatingDynamics& d) { return d.f64.nq(); })
      .def_property_readonly("nv", [](const FloatingDynamics& d) { return d.f64.nv(); })
      .def("rnea", &floating_rnea, py::arg("q"), py::arg("v"), py::arg("a"), py::arg("gravity"))
      .def("gravity", &floating_gravity, py::arg("q"), py::arg("gravity"))
      .def("nonlinear_effects", &floating_nonlinear, py::arg("q"), py::arg("v"), py::arg("gravity"))
      .def("crba", &floating_crba, py::arg("q"), py::arg("layout") = "full")
      .def("coriolis_matrix", &floating_coriolis, py::arg("q"), py::arg("v"))
      .def("aba", &floating_aba, py::arg("q"), py::arg("v"), py::arg("tau"), py::arg("gravity"))
      .def("com", [](const FloatingDynamics& d, py::handle q) { return floating_com(d, q, false); }, py::arg("q"))
      .def("com_jacobian", [](const FloatingDynamics& d, py::handle q) { return floating_com(d, q, true); },
           py::arg("q"));
}

}  // namespace spotkin::bindings
