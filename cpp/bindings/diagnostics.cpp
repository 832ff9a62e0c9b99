// Private diagnostics for the benchmark report (bench/conftest.py): the TSC
// rate, the measured cost of the elementary vectorised operations, and each
// kernel's operation counts (spotkin/diagnostics.hpp).
#include "spotkin/diagnostics.hpp"

#include <pybind11/stl.h>

#include <map>
#include <string>

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
}

}  // namespace spotkin::bindings
