// Bindings for Paul's equation solvers: broadcast 1-D float64 inputs, every root.
#include "spotkin/paul.hpp"

#include "bindings.hpp"
#include "numpy_boundary.hpp"

namespace spotkin::bindings {

namespace {

// All inputs arrive flattened and broadcast to the same length by the façade.
std::vector<const double*> inputs(const std::vector<py::array_t<double, py::array::c_style>>& arrays, py::ssize_t& n) {
  n = arrays.empty() ? 0 : arrays[0].size();
  std::vector<const double*> ptrs;
  for (const auto& a : arrays) {
    if (a.ndim() != 1 || a.size() != n) throw py::value_error("Paul solver inputs must be 1-D of equal length");
    ptrs.push_back(a.data());
  }
  return ptrs;
}

using Flat = py::array_t<double, py::array::c_style | py::array::forcecast>;

py::tuple type2(Flat X, Flat Y, Flat Z) {
  py::ssize_t n;
  auto in = inputs({X, Y, Z}, n);
  py::array_t<double> t({n, py::ssize_t(2)});
  py::array_t<bool> valid({n, py::ssize_t(2)});
  double* td = t.mutable_data();
  bool* vd = valid.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto r = paul::type2(in[0][i], in[1][i], in[2][i]);
    for (int k = 0; k < 2; ++k) td[2 * i + k] = r.t[k], vd[2 * i + k] = r.valid[k] != 0.0;
  }
  return py::make_tuple(t, valid);
}

py::tuple type3(Flat X1, Flat Y1, Flat Z1, Flat X2, Flat Y2, Flat Z2) {
  py::ssize_t n;
  auto in = inputs({X1, Y1, Z1, X2, Y2, Z2}, n);
  py::array_t<double> t(n);
  py::array_t<bool> valid(n);
  double* td = t.mutable_data();
  bool* vd = valid.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto r = paul::type3(in[0][i], in[1][i], in[2][i], in[3][i], in[4][i], in[5][i]);
    td[i] = r.t, vd[i] = r.valid != 0.0;
  }
  return py::make_tuple(t, valid);
}

py::tuple type6(Flat W, Flat X, Flat Y, Flat Z1, Flat Z2) {
  py::ssize_t n;
  auto in = inputs({W, X, Y, Z1, Z2}, n);
  py::array_t<double> ti({n, py::ssize_t(2)}), tj({n, py::ssize_t(2)});
  py::array_t<bool> valid({n, py::ssize_t(2)});
  double *tid = ti.mutable_data(), *tjd = tj.mutable_data();
  bool* vd = valid.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto r = paul::type6(in[0][i], in[1][i], in[2][i], in[3][i], in[4][i]);
    for (int k = 0; k < 2; ++k) tid[2 * i + k] = r.ti[k], tjd[2 * i + k] = r.tj[k], vd[2 * i + k] = r.valid[k] != 0.0;
  }
  return py::make_tuple(ti, tj, valid);
}

}  // namespace

void bind_paul(py::module_& m) {
  m.def("paul_type2", &type2, py::arg("X"), py::arg("Y"), py::arg("Z"));
  m.def("paul_type3", &type3, py::arg("X1"), py::arg("Y1"), py::arg("Z1"), py::arg("X2"), py::arg("Y2"), py::arg("Z2"));
  m.def("paul_type6", &type6, py::arg("W"), py::arg("X"), py::arg("Y"), py::arg("Z1"), py::arg("Z2"));
}

}  // namespace spotkin::bindings
