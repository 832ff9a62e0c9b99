// Bindings for run-time settings: the worker thread count, and Ctrl-C during long batches.
#include <Python.h>

#include "bindings.hpp"
#include "dispatch.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::bindings {

namespace {

// The signal's exception (KeyboardInterrupt, or what a Python handler raised),
// held from the poll until the binding that was interrupted raises it.
struct PendingError {
  PyObject* type = nullptr;
  PyObject* value = nullptr;
  PyObject* traceback = nullptr;
};
thread_local PendingError pending_error;

// parallel_for's poll: runs Python's signal handlers (main thread only, as Python does).
bool poll_python_signals() noexcept {
  const PyGILState_STATE state = PyGILState_Ensure();
  bool stop = false;
  if (PyErr_CheckSignals() != 0) {
    PyErr_Fetch(&pending_error.type, &pending_error.value, &pending_error.traceback);
    stop = true;
  }
  PyGILState_Release(state);
  return stop;
}

int thread_count_argument(py::handle n) {
  if (PyBool_Check(n.ptr()) || !PyIndex_Check(n.ptr()))
    throw py::type_error("n must be an integer thread count, got " +
                         std::string(py::str(py::type::handle_of(n).attr("__name__"))));
  const Py_ssize_t value = PyNumber_AsSsize_t(n.ptr(), nullptr);  // saturates instead of overflowing
  if (value == -1 && PyErr_Occurred()) throw py::error_already_set();
  if (value < 1 || value > kMaxThreads)
    throw py::value_error("n must be a thread count in [1, " + std::to_string(kMaxThreads) + "], got " +
                          std::string(py::str(n)));
  return static_cast<int>(value);
}

}  // namespace

SPOTKIN_CLONES((), bool, any_unusual, (const double* x, std::ptrdiff_t n) noexcept, (x, n),
  return vector_math::any_beyond(x, n, vector_math::kReducibleLimit);
)
SPOTKIN_CLONES((), bool, any_unusual, (const float* x, std::ptrdiff_t n) noexcept, (x, n),
  return vector_math::any_beyond(x, n, float(vector_math::kReducibleLimit));
)

void bind_runtime(pybind11::module_& m) {
  interrupt_poll().store(&poll_python_signals);
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const Interrupted&) {
      PendingError& e = pending_error;
      if (e.type != nullptr) {
        PyErr_Restore(e.type, e.value, e.traceback);
        e = PendingError{};
      } else {
        PyErr_SetNone(PyExc_KeyboardInterrupt);
      }
    }
  });
  m.attr("MAX_THREADS") = kMaxThreads;
  m.def("get_num_threads", &get_num_threads);
  m.def("_register_status", [](pybind11::object members) { status_members() = members; },
        pybind11::arg("members"));
  m.def("set_num_threads", [](py::handle n) { set_num_threads(thread_count_argument(n)); }, pybind11::arg("n"));
  // Sets this thread's limit (None lifts it) and returns the previous one (None: none).
  m.def(
      "_set_thread_limit",
      [](py::handle n) -> py::object {
        const int previous = thread_limit();
        thread_limit() = n.is_none() ? 0 : thread_count_argument(n);
        return previous > 0 ? py::object(py::int_(previous)) : py::object(py::none());
      },
      pybind11::arg("n"));
  m.def("_parse_thread_count", [](const std::string& text) { return parse_thread_count(text.c_str()); },
        pybind11::arg("text"));

  // Instruction-set levels (spotkin/isa.hpp). SPOTKIN_ISA is read once, here: a level the
  // CPU lacks, or an unknown name, fails the import with the reason.
  try {
    set_isa(isa_from_environment());
  } catch (const std::invalid_argument& e) {
    throw py::import_error(e.what());
  }
  m.def("get_isa", [] { return std::string(isa_name(active_isa())); });
  m.def("available_isas", [] {
    py::list levels;
    for (int level = 0; level <= static_cast<int>(best_isa()); ++level)
      levels.append(isa_name(static_cast<Isa>(level)));
    return py::tuple(levels);
  });
  m.def(
      "set_isa",
      [](const std::string& name) {
        try {
          set_isa(isa_from_name(name));
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
      },
      pybind11::arg("level"));
}

}  // namespace spotkin::bindings
