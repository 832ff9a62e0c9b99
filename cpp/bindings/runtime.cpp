// Bindings for run-time settings: the worker thread count.
#include "bindings.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

void bind_runtime(pybind11::module_& m) {
  m.def("get_num_threads", &get_num_threads);
  m.def("_register_status", [](pybind11::object members) { status_members() = members; },
        pybind11::arg("members"));
  m.def("set_num_threads", [](int n) {
    if (n < 1) throw pybind11::value_error("n must be a positive thread count, got " + std::to_string(n));
    set_num_threads(n);
  }, pybind11::arg("n"));
}

}  // namespace spotkin::bindings
