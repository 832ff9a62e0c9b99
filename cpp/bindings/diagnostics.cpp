// Private diagnostics for the benchmark report (bench/conftest.py): the TSC
// rate, the measured cost of the elementary vectorised operations, and each
// kernel's operation counts (spotkin/diagnostics.hpp); and the elementary
// loops themselves on 1-D arrays, for the accuracy tests (tests/test_vector_math.py).
#include "spotkin/diagnostics.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <map>
#include <string>
#include <utility>

#include "bindings.hpp"
#include "dispatch.hpp"

namespace spotkin::bindings {

namespace {

namespace py = pybind11;
namespace d = spotkin::diagnostics;

SPOTKIN_CLONES((), void, atan2_of, (const double* y, const double* x, double* out, std::ptrdiff_t n), (y, x, out, n),
  d::atan2_loop(y, x, out, n);
)
SPOTKIN_CLONES((), void, atan2_of, (const float* y, const float* x, float* out, std::ptrdiff_t n), (y, x, out, n),
  d::atan2_loop(y, x, out, n);
)
SPOTKIN_CLONES((), void, sincos_of, (const double* x, double* s, double* c, std::ptrdiff_t n), (x, s, c, n),
  d::sincos_loop(x, s, c, n);
)
SPOTKIN_CLONES((), void, sincos_of, (const float* x, float* s, float* c, std::ptrdiff_t n), (x, s, c, n),
  d::sincos_loop(x, s, c, n);
)
SPOTKIN_CLONES((), void, sqrt_of, (const double* x, double* out, std::ptrdiff_t n), (x, out, n), d::sqrt_loop(x, out, n); )
SPOTKIN_CLONES((), void, sqrt_of, (const float* x, float* out, std::ptrdiff_t n), (x, out, n), d::sqrt_loop(x, out, n); )
SPOTKIN_CLONES((), void, fma32_of, (const double* x, double* out, std::ptrdiff_t n), (x, out, n), d::fma32_loop(x, out, n); )
SPOTKIN_CLONES((), void, fma32_of, (const float* x, float* out, std::ptrdiff_t n), (x, out, n), d::fma32_loop(x, out, n); )

struct Loops {
  template <typename T>
  static void atan2(const T* y, const T* x, T* out, std::ptrdiff_t n) { atan2_of(y, x, out, n); }
  template <typename T>
  static void sincos(const T* x, T* s, T* c, std::ptrdiff_t n) { sincos_of(x, s, c, n); }
  template <typename T>
  static void sqrt(const T* x, T* out, std::ptrdiff_t n) { sqrt_of(x, out, n); }
  template <typename T>
  static void fma32(const T* x, T* out, std::ptrdiff_t n) { fma32_of(x, out, n); }
};

std::map<std::string, double> as_dict(const d::Costs& c) {
  return {{"atan2", c.atan2}, {"sincos", c.sincos}, {"sqrt", c.sqrt}, {"fma", c.fma}};
}

// A 1-D C-contiguous float64 or float32 array, taken as it is (the tests' inputs
// must reach the loop unconverted): TypeError for another type or dtype,
// ValueError for another shape or layout.
py::array vector_argument(py::handle obj, const char* name) {
  if (!py::isinstance<py::array>(obj))
    throw py::type_error(std::string(name) + " must be a numpy array, got " +
                         std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
  auto arr = py::reinterpret_borrow<py::array>(obj);
  if (!py::array_t<double>::check_(arr) && !py::array_t<float>::check_(arr))
    throw py::type_error(std::string(name) + " must have dtype float64 or float32, got " +
                         std::string(py::str(arr.dtype())));
  if (arr.ndim() != 1)
    throw py::value_error(std::string(name) + " must be 1-D, got " + std::to_string(arr.ndim()) +
                          " dimensions");
  if (!(arr.flags() & py::array::c_style)) throw py::value_error(std::string(name) + " must be contiguous");
  return arr;
}

bool is_single(const py::array& arr) { return py::array_t<float>::check_(arr); }

// `other` (a vector_argument) beside `first`: the same dtype and length.
void check_alike(const py::array& first, const char* first_name, const py::array& other, const char* name) {
  if (is_single(other) != is_single(first))
    throw py::type_error(std::string(name) + " must have the dtype of " + first_name + ", " +
                         std::string(py::str(first.dtype())) + ", got " +
                         std::string(py::str(other.dtype())));
  if (other.shape(0) != first.shape(0))
    throw py::value_error(std::string(name) + " must have the length of " + first_name + ", " +
                          std::to_string(first.shape(0)) + ", got " + std::to_string(other.shape(0)));
}

template <typename T>
py::object vector_atan2(const py::array& y, const py::array& x) {
  const py::ssize_t n = y.shape(0);
  py::array_t<T> out(n);
  const T *yd = static_cast<const T*>(y.data()), *xd = static_cast<const T*>(x.data());
  T* od = out.mutable_data();
  {
    py::gil_scoped_release release;
    atan2_of(yd, xd, od, n);
  }
  return std::move(out);
}

template <typename T>
py::object vector_sincos(const py::array& x) {
  const py::ssize_t n = x.shape(0);
  py::array_t<T> s(n), c(n);
  const T* xd = static_cast<const T*>(x.data());
  T *sd = s.mutable_data(), *cd = c.mutable_data();
  {
    py::gil_scoped_release release;
    sincos_of(xd, sd, cd, n);
  }
  return py::make_tuple(std::move(s), std::move(c));
}

}  // namespace

void bind_diagnostics(py::module_& m) {
  m.def(
      "_tsc_ghz",
      [] {
        py::gil_scoped_release release;
        return d::tsc_ghz();
      },
      "The TSC rate in GHz, measured against steady_clock over 0.2 s (0 off x86-64).");
  m.def(
      "_elementary_costs",
      [](const std::string& dtype, int repeats) {
        if (dtype != "float64" && dtype != "float32")
          throw py::value_error("dtype must be 'float64' or 'float32', got '" + dtype + "'");
        if (repeats < 1) throw py::value_error("repeats must be >= 1");
        d::Costs costs;
        {
          py::gil_scoped_release release;
          costs = dtype == "float64" ? d::measure_costs<double, Loops>(repeats) : d::measure_costs<float, Loops>(repeats);
        }
        return as_dict(costs);
      },
      py::arg("dtype") = "float64", py::arg("repeats") = 100,
      "ns per element of the vectorised atan2, sincos, sqrt and multiply-add, on one thread.");
  m.def(
      "_kernel_work",
      [] {
        std::map<std::string, std::map<std::string, double>> out;
        for (const d::KernelWork& k : d::kKernels)
          out[k.name] = {{"atan2", k.work.atan2}, {"sincos", k.work.sincos}, {"sqrt", k.work.sqrt}, {"fma", k.work.fma}};
        return out;
      },
      "Per kernel, the elementary operations per sample that its floor estimate counts.");
  m.def(
      "_vector_atan2",
      [](py::handle y_obj, py::handle x_obj) -> py::object {
        const py::array y = vector_argument(y_obj, "y"), x = vector_argument(x_obj, "x");
        check_alike(y, "y", x, "x");
        return is_single(y) ? vector_atan2<float>(y, x) : vector_atan2<double>(y, x);
      },
      py::arg("y"), py::arg("x"),
      "The kernels' vectorised atan2 loop (vector_math.hpp, at the active ISA level) on 1-D contiguous "
      "float64 or float32 arrays y and x of one dtype and length.");
  m.def(
      "_vector_sincos",
      [](py::handle x_obj) -> py::object {
        const py::array x = vector_argument(x_obj, "x");
        return is_single(x) ? vector_sincos<float>(x) : vector_sincos<double>(x);
      },
      py::arg("x"),
      "The kernels' vectorised sincos loop (vector_math.hpp sincos_bounded, at the active ISA level; "
      "no fallback beyond its reducible limit) on a 1-D contiguous float64 or float32 array: the tuple "
      "(sin, cos).");
}

}  // namespace spotkin::bindings
