// Bindings for Paul's equation solvers: every coefficient a batched scalar (broadcast like NumPy by
// the binder), computed in float64; every root in (-pi, pi] with its validity (a valid root is
// never NaN).
#include "spotkin/paul.hpp"

#include <cmath>
#include <type_traits>

#include "binder.hpp"
#include "bindings.hpp"

namespace spotkin::bindings {

namespace {

namespace py = pybind11;

// Angles in (-pi, pi]: the kernels' atan2 gives -pi for a -0 sine (and a sine below the smallest
// step at pi), the same angle as pi.
double half_open(double t) { return t == -kPi<double> ? kPi<double> : t; }

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

py::object type2(py::handle X, py::handle Y, py::handle Z) {
  static const Op op = Op({Arg("X", {}), Arg("Y", {}), Arg("Z", {})}, {Out("t", {2}), Out("valid", {2}, Kind::Bool)},
                          20.0, [](const void*, const auto& b) {
                            if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>)
                              for (std::ptrdiff_t i = 0; i < b.m; ++i) {  // X sin t + Y cos t = Z
                                const auto r = paul::type2(b.in[0][i], b.in[1][i], b.in[2][i]);
                                for (int k = 0; k < 2; ++k)  // a valid root is never NaN
                                  b.real(0)[2 * i + k] = half_open(r.t[k]),
                                                    b.flags(1)[2 * i + k] = r.valid[k] != 0.0 && !std::isnan(r.t[k]);
                              }
                          })
                           .float64_only();
  return binder::call(op, nullptr, {X, Y, Z}, py::none());
}

py::object type3(py::handle X1, py::handle Y1, py::handle Z1, py::handle X2, py::handle Y2, py::handle Z2) {
  static const Op op = Op({Arg("X1", {}), Arg("Y1", {}), Arg("Z1", {}), Arg("X2", {}), Arg("Y2", {}), Arg("Z2", {})},
                          {Out("t", {}), Out("valid", {}, Kind::Bool)}, 20.0, [](const void*, const auto& b) {
                            if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>)
                              for (std::ptrdiff_t i = 0; i < b.m; ++i) {  // two equations in (sin t, cos t)
                                const auto r = paul::type3(b.in[0][i], b.in[1][i], b.in[2][i], b.in[3][i],
                                                           b.in[4][i], b.in[5][i]);
                                b.real(0)[i] = half_open(r.t), b.flags(1)[i] = r.valid != 0.0 && !std::isnan(r.t);
                              }
                          })
                           .float64_only();
  return binder::call(op, nullptr, {X1, Y1, Z1, X2, Y2, Z2}, py::none());
}

py::object type6(py::handle W, py::handle X, py::handle Y, py::handle Z1, py::handle Z2) {
  static const Op op =
      Op({Arg("W", {}), Arg("X", {}), Arg("Y", {}), Arg("Z1", {}), Arg("Z2", {})},
         {Out("ti", {2}), Out("tj", {2}), Out("valid", {2}, Kind::Bool)}, 40.0, [](const void*, const auto& b) {
           if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>)
             for (std::ptrdiff_t i = 0; i < b.m; ++i) {  // the coupled (ti, tj) pair
               const auto r = paul::type6(b.in[0][i], b.in[1][i], b.in[2][i], b.in[3][i], b.in[4][i]);
               for (int k = 0; k < 2; ++k)
                 b.real(0)[2 * i + k] = half_open(r.ti[k]), b.real(1)[2 * i + k] = half_open(r.tj[k]),
                                  b.flags(2)[2 * i + k] =
                                      r.valid[k] != 0.0 && !std::isnan(r.ti[k]) && !std::isnan(r.tj[k]);
             }
         })
          .float64_only();
  return binder::call(op, nullptr, {W, X, Y, Z1, Z2}, py::none());
}

}  // namespace

void bind_paul(py::module_& m) {
  m.def("paul_type2", &type2, py::arg("X"), py::arg("Y"), py::arg("Z"));
  m.def("paul_type3", &type3, py::arg("X1"), py::arg("Y1"), py::arg("Z1"), py::arg("X2"), py::arg("Y2"), py::arg("Z2"));
  m.def("paul_type6", &type6, py::arg("W"), py::arg("X"), py::arg("Y"), py::arg("Z1"), py::arg("Z2"));
}

}  // namespace spotkin::bindings
