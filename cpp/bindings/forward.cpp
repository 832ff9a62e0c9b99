// The façade's pass-through methods as C callables: spotkin._core._CoreMethod.
//
// A façade method such as Chain.gravity(self, q, gravity=(0, 0, -9.81), *, out=None) only calls
// self._dynamics.gravity(q, gravity, out). Run as Python, that call costs a frame, a bound method
// and a keyword parse (about 0.2 us, as much as the kernel of one sample). A _CoreMethod does the
// same call from C: it is a method descriptor (no bound method on `obj.method(...)`), takes the
// Python function's parameters by position or keyword with its defaults, and calls the core's
// method with them, in vectorcall.
//
// Anything else goes through the Python function it was made from, which stays the definition and
// the documentation: an unknown keyword or a missing argument (Python's own TypeError), a core not
// built yet (the function builds it), an argument whose value selects another path (a non-default
// `frame`), and any ValueError or TypeError the core raises (the function handles the other forms
// it accepts, such as a whole-body q, or raises its documented error). So the fast path never
// answers differently from the function: it is the function's common case, without the
// interpreter.
#include <pybind11/pybind11.h>
#include <structmember.h>

#include <cstddef>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "fast_call.hpp"

namespace spotkin::bindings {

namespace py = pybind11;

namespace fast {

namespace {
std::unordered_map<PyObject*, Entry>& registry() {
  static auto* entries = new std::unordered_map<PyObject*, Entry>();  // never freed: read at exit
  return *entries;
}
std::vector<std::pair<std::string, std::string>>& names() {  // (type, method), for the tests
  static auto* entries = new std::vector<std::pair<std::string, std::string>>();
  return *entries;
}
}  // namespace

void add(py::handle cls, const char* name, Entry entry) {
  py::str key(name);
  PyObject* descriptor = _PyType_Lookup(reinterpret_cast<PyTypeObject*>(cls.ptr()), key.ptr());
  if (!descriptor || !PyInstanceMethod_Check(descriptor))
    throw std::logic_error(std::string("def_fast: no method ") + name);
  registry()[PyInstanceMethod_GET_FUNCTION(descriptor)] = entry;
  names().emplace_back(py::str(cls.attr("__name__")), name);
}

Entry find(PyObject* function) noexcept {
  const auto it = registry().find(function);
  return it == registry().end() ? nullptr : it->second;
}

}  // namespace fast

namespace {

constexpr Py_ssize_t kMaxParams = 12;

struct CoreMethod {
  PyObject_HEAD vectorcallfunc vectorcall;
  PyObject* dict;        // __doc__, __wrapped__, __name__, __qualname__, __module__
  PyObject* function;    // the Python function: the definition, the documentation, the other paths
  PyObject* target;      // the attribute of self holding the core object (str)
  PyObject* method;      // the core object's method (str)
  PyObject* names;       // the parameters after self (tuple of interned str)
  PyObject* defaults;    // their defaults, converted (tuple; `required` where there is none)
  PyObject* converters;  // per parameter: None, a callable applied to a given value, or `required`
                         // (the fast path only at the default: another value takes the function)
  PyObject*
      order;  // the core's arguments: tuple of int, k >= 0 parameter k, k < 0 constants[-1 - k]
  Py_ssize_t slots[kMaxParams];  // order, read once
  Py_ssize_t n_core;
  PyObject* constants;  // tuple
  PyObject* required;   // the marker (inspect.Parameter.empty)
  Py_ssize_t n_params, n_positional;
  PyTypeObject* cached_type;  // the core object's type, and its method's function (pybind11's
  PyObject* cached_function;  // instancemethod wraps it), looked up once
  fast::Entry cached_fast;    // the function's direct call (fast_call.hpp), or null
};

PyObject* through_function(CoreMethod* self, PyObject* const* args, std::size_t nargsf,
                           PyObject* kwnames) {
  return PyObject_Vectorcall(self->function, args, nargsf, kwnames);
}

// The core object's method as a function taking the object first (cached per type), or null (then
// the caller takes the bound method).
PyObject* unbound_method(CoreMethod* self, PyObject* core) {
  PyTypeObject* type = Py_TYPE(core);
  if (type == self->cached_type) return self->cached_function;
  PyObject* descriptor = _PyType_Lookup(type, self->method);  // borrowed
  if (!descriptor || !PyInstanceMethod_Check(descriptor)) return nullptr;
  PyObject* function = PyInstanceMethod_GET_FUNCTION(descriptor);
  Py_XDECREF(reinterpret_cast<PyObject*>(self->cached_type));
  Py_XDECREF(self->cached_function);
  Py_INCREF(type);
  Py_INCREF(function);
  self->cached_type = type;
  self->cached_function = function;
  self->cached_fast = fast::find(function);
  return function;
}

PyObject* call(PyObject* callable, PyObject* const* args, std::size_t nargsf, PyObject* kwnames) {
  auto* self = reinterpret_cast<CoreMethod*>(callable);
  const Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
  if (nargs < 1 || nargs - 1 > self->n_positional)
    return through_function(self, args, nargsf, kwnames);
  PyObject* given[kMaxParams] = {};
  for (Py_ssize_t k = 1; k < nargs; ++k) given[k - 1] = args[k];
  if (kwnames) {
    const Py_ssize_t n_kw = PyTuple_GET_SIZE(kwnames);
    for (Py_ssize_t j = 0; j < n_kw; ++j) {
      PyObject* key = PyTuple_GET_ITEM(kwnames, j);
      Py_ssize_t i = 0;
      while (i < self->n_params && PyTuple_GET_ITEM(self->names, i) != key) ++i;
      if (i == self->n_params) {  // not interned: compare the text
        i = 0;
        while (i < self->n_params && PyUnicode_Compare(PyTuple_GET_ITEM(self->names, i), key) != 0)
          ++i;
        if (PyErr_Occurred()) return nullptr;
      }
      if (i == self->n_params || given[i]) return through_function(self, args, nargsf, kwnames);
      given[i] = args[nargs + j];
    }
  }
  PyObject* converted[kMaxParams] = {};  // new references
  PyObject* value[kMaxParams];
  const auto release = [&] {
    for (Py_ssize_t i = 0; i < self->n_params; ++i) Py_XDECREF(converted[i]);
  };
  for (Py_ssize_t i = 0; i < self->n_params; ++i) {
    PyObject* converter = PyTuple_GET_ITEM(self->converters, i);
    if (!given[i]) {
      value[i] = PyTuple_GET_ITEM(self->defaults, i);
      if (value[i] == self->required)
        return release(), through_function(self, args, nargsf, kwnames);
    } else if (converter == Py_None) {
      value[i] = given[i];
    } else if (converter == self->required) {  // only the default takes the fast path
      if (given[i] != PyTuple_GET_ITEM(self->defaults, i))
        return release(), through_function(self, args, nargsf, kwnames);
      value[i] = given[i];
    } else {
      converted[i] = PyObject_CallFunctionObjArgs(converter, given[i], nullptr);
      if (!converted[i])
        return release(), nullptr;  // the converter's own error, as the function raises it
      value[i] = converted[i];
    }
  }
  PyObject* core = PyObject_GetAttr(args[0], self->target);
  if (!core || core == Py_None) {  // not built yet: the function builds it
    if (!core) PyErr_Clear();
    Py_XDECREF(core);
    return release(), through_function(self, args, nargsf, kwnames);
  }
  const Py_ssize_t n_core = self->n_core;
  PyObject* stack[kMaxParams + 2];
  stack[0] = nullptr;  // PY_VECTORCALL_ARGUMENTS_OFFSET: room for the callee to prepend
  stack[1] = core;
  for (Py_ssize_t k = 0; k < n_core; ++k) {
    const Py_ssize_t slot = self->slots[k];
    stack[k + 2] = slot >= 0 ? value[slot] : PyTuple_GET_ITEM(self->constants, -1 - slot);
  }
  PyObject* result;
  if (PyObject* function = unbound_method(self, core)) {
    Py_INCREF(function);  // held through the call, should a re-entrant call replace the cache
    const fast::Entry direct = self->cached_fast;
    result = direct ? direct(core, stack + 2, n_core) : nullptr;
    if (!result && !PyErr_Occurred())  // no direct call, or it declined: pybind11's call
      result = PyObject_Vectorcall(
          function, stack + 1, std::size_t(n_core + 1) | PY_VECTORCALL_ARGUMENTS_OFFSET, nullptr);
    Py_DECREF(function);
  } else {
    PyObject* bound = PyObject_GetAttr(core, self->method);
    result = bound ? PyObject_Vectorcall(bound, stack + 2, std::size_t(n_core), nullptr) : nullptr;
    Py_XDECREF(bound);
  }
  Py_DECREF(core);
  release();
  if (!result &&
      (PyErr_ExceptionMatches(PyExc_ValueError) || PyErr_ExceptionMatches(PyExc_TypeError))) {
    PyErr_Clear();  // what the core refuses, the function handles or explains
    return through_function(self, args, nargsf, kwnames);
  }
  return result;
}

PyObject* descriptor_get(PyObject* self, PyObject* obj, PyObject*) {
  if (!obj || obj == Py_None) {
    Py_INCREF(self);
    return self;
  }
  return PyMethod_New(self, obj);
}

int traverse(PyObject* object, visitproc visit, void* arg) {
  auto* self = reinterpret_cast<CoreMethod*>(object);
  Py_VISIT(self->dict);
  Py_VISIT(self->function);
  Py_VISIT(self->defaults);
  Py_VISIT(self->converters);
  Py_VISIT(self->constants);
  Py_VISIT(self->required);
  Py_VISIT(reinterpret_cast<PyObject*>(self->cached_type));
  Py_VISIT(self->cached_function);
  return 0;
}

int clear(PyObject* object) {
  auto* self = reinterpret_cast<CoreMethod*>(object);
  Py_CLEAR(self->dict);
  Py_CLEAR(self->function);
  Py_CLEAR(self->target);
  Py_CLEAR(self->method);
  Py_CLEAR(self->names);
  Py_CLEAR(self->defaults);
  Py_CLEAR(self->converters);
  Py_CLEAR(self->order);
  Py_CLEAR(self->constants);
  Py_CLEAR(self->required);
  Py_CLEAR(self->cached_type);
  Py_CLEAR(self->cached_function);
  return 0;
}

void dealloc(PyObject* object) {
  PyTypeObject* type = Py_TYPE(object);
  PyObject_GC_UnTrack(object);
  clear(object);
  type->tp_free(object);
  Py_DECREF(type);  // a heap type: each instance holds a reference
}

PyTypeObject* core_method_type() {
  static PyMemberDef members[] = {
      {"__dictoffset__", T_PYSSIZET, offsetof(CoreMethod, dict), READONLY, nullptr},
      {"__vectorcalloffset__", T_PYSSIZET, offsetof(CoreMethod, vectorcall), READONLY, nullptr},
      {nullptr, 0, 0, 0, nullptr}};
  static PyGetSetDef getset[] = {
      {"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict, nullptr, nullptr},
      {nullptr, nullptr, nullptr, nullptr, nullptr}};
  static PyType_Slot slots[] = {
      {Py_tp_doc, const_cast<char*>("A façade method run from C: see cpp/bindings/forward.cpp.")},
      {Py_tp_call, reinterpret_cast<void*>(PyVectorcall_Call)},
      {Py_tp_descr_get, reinterpret_cast<void*>(descriptor_get)},
      {Py_tp_traverse, reinterpret_cast<void*>(traverse)},
      {Py_tp_clear, reinterpret_cast<void*>(clear)},
      {Py_tp_dealloc, reinterpret_cast<void*>(dealloc)},
      {Py_tp_members, members},
      {Py_tp_getset, getset},
      {0, nullptr}};
  static PyType_Spec spec = {"spotkin._core._CoreMethod", sizeof(CoreMethod), 0,
                             Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL |
                                 Py_TPFLAGS_METHOD_DESCRIPTOR,
                             slots};
  static PyTypeObject* type = reinterpret_cast<PyTypeObject*>(PyType_FromSpec(&spec));
  if (!type) throw py::error_already_set();
  return type;
}

py::object make_core_method(py::object function, py::str target, py::str method, py::tuple names,
                            py::tuple defaults, py::tuple converters, Py_ssize_t n_positional,
                            py::tuple order, py::tuple constants, py::object required) {
  const Py_ssize_t n = Py_ssize_t(names.size());
  if (n > kMaxParams || Py_ssize_t(order.size()) > kMaxParams)
    throw py::value_error("a core method takes at most " + std::to_string(kMaxParams) +
                          " parameters");
  if (Py_ssize_t(defaults.size()) != n || Py_ssize_t(converters.size()) != n || n_positional < 0 ||
      n_positional > n)
    throw py::value_error("names, defaults and converters must have one entry per parameter");
  for (py::handle k : order) {
    const Py_ssize_t slot = k.cast<Py_ssize_t>();
    if (slot >= n || -1 - slot >= Py_ssize_t(constants.size()))
      throw py::value_error("order names a parameter or constant that does not exist");
  }
  py::list interned;
  for (py::handle name : names) {
    PyObject* s = py::str(name).release().ptr();
    PyUnicode_InternInPlace(&s);
    interned.append(py::reinterpret_steal<py::object>(s));
  }
  PyObject* target_ptr = target.release().ptr();
  PyUnicode_InternInPlace(&target_ptr);
  PyObject* method_ptr = method.release().ptr();
  PyUnicode_InternInPlace(&method_ptr);
  PyTypeObject* type = core_method_type();
  auto* self = PyObject_GC_New(CoreMethod, type);
  if (!self) throw py::error_already_set();
  self->vectorcall = call;
  self->dict = PyDict_New();
  self->function = function.release().ptr();
  self->target = target_ptr;
  self->method = method_ptr;
  self->names = py::tuple(interned).release().ptr();
  self->defaults = defaults.release().ptr();
  self->converters = converters.release().ptr();
  self->n_core = Py_ssize_t(order.size());
  for (Py_ssize_t k = 0; k < self->n_core; ++k)
    self->slots[k] = order[std::size_t(k)].cast<Py_ssize_t>();
  self->order = order.release().ptr();
  self->constants = constants.release().ptr();
  self->required = required.release().ptr();
  self->n_params = n;
  self->n_positional = n_positional;
  self->cached_type = nullptr;
  self->cached_function = nullptr;
  self->cached_fast = nullptr;
  PyObject_GC_Track(self);
  return py::reinterpret_steal<py::object>(reinterpret_cast<PyObject*>(self));
}

}  // namespace

void bind_core_method(py::module_& m) {
  m.def(
      "_core_method", &make_core_method, py::arg("function"), py::arg("target"), py::arg("method"),
      py::arg("names"), py::arg("defaults"), py::arg("converters"), py::arg("n_positional"),
      py::arg("order"), py::arg("constants"), py::arg("required"),
      "A façade method that calls self.<target>.<method>(...) from C (spotkin._support.forward).");
  m.def(
      "_direct_calls",
      [] {
        py::list calls;
        for (const auto& [type, method] : fast::names()) calls.append(py::make_tuple(type, method));
        return calls;
      },
      "(core type, method) of every core method a façade method calls past pybind11's dispatcher "
      "(cpp/bindings/fast_call.hpp).");
}

}  // namespace spotkin::bindings
