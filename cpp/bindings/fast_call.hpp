// Direct calls of a binding's glue function from C, past pybind11's dispatcher.
//
// A façade method made by spotkin._support.forward (a _CoreMethod, forward.cpp) calls a core
// object's method once per control tick. Through pybind11, that call builds a function_call,
// walks the overload chain and finds the C++ type of `self` by its type_info (a hash lookup and
// a string compare): about 0.1 us per call, a quarter of a single-sample leg IK. def_fast defines
// the method as usual and also registers Caller<F>::call, which converts the arguments itself
// (py::handle as given, bool from True or False, int from an exact int) and calls F.
//
// The direct call declines (returns null with no Python error set) when an argument is of
// another kind or `self` is not exactly the bound C++ type: the caller then calls the method
// through pybind11, which converts or refuses it as it always does. An exception F throws is
// translated as pybind11's dispatcher translates it (the same translators: a ValueError, a
// TypeError, Ctrl-C during a long batch), never retried: the call ran once. So a direct call
// never answers differently from pybind11's: it is the same function, called with the same
// values.
#pragma once

#include <pybind11/pybind11.h>

#ifdef __GLIBCXX__
#include <cxxabi.h>
#endif
#include <climits>
#include <cstddef>
#include <tuple>
#include <type_traits>
#include <utility>

namespace spotkin::bindings::fast {

namespace py = pybind11;

// self, the method's arguments after self (positional), their count.
using Entry = PyObject* (*)(PyObject* self, PyObject* const* args, Py_ssize_t nargs);

// The registry, keyed by the function object pybind11 made for the method (the one a
// _CoreMethod finds on the core object's type). Filled at import, read under the GIL.
void add(py::handle cls, const char* name, Entry entry);
Entry find(PyObject* function) noexcept;

template <typename T>
struct ArgFrom;  // only these kinds are converted here; F with another one does not compile

template <>
struct ArgFrom<py::handle> {
  static bool get(PyObject* o, py::handle& v) noexcept { return v = o, true; }
};
template <>
struct ArgFrom<bool> {
  static bool get(PyObject* o, bool& v) noexcept {
    if (o != Py_True && o != Py_False) return false;
    return v = o == Py_True, true;
  }
};
template <>
struct ArgFrom<int> {
  static bool get(PyObject* o, int& v) noexcept {
    if (!PyLong_CheckExact(o)) return false;
    int overflow = 0;
    const long x = PyLong_AsLongAndOverflow(o, &overflow);
    if (overflow || x < INT_MIN || x > INT_MAX) return false;
    return v = int(x), true;
  }
};

// The C++ object a pybind11 instance holds, when its Python type is exactly Self's bound type.
template <typename Self>
const Self* instance_of(PyObject* self) noexcept {
  static const py::detail::type_info* info = py::detail::get_type_info(typeid(Self));
  if (!info || Py_TYPE(self) != info->type) return nullptr;
  auto* inst = reinterpret_cast<py::detail::instance*>(self);
  const py::detail::value_and_holder vh = inst->get_value_and_holder(info, false);
  if (!vh || !vh.holder_constructed()) return nullptr;
  return static_cast<const Self*>(vh.value_ptr());
}

template <auto F>
struct Caller;

template <typename Self, typename... A, py::object (*F)(const Self&, A...)>
struct Caller<F> {
  static PyObject* call(PyObject* self, PyObject* const* args, Py_ssize_t nargs) noexcept {
    if (nargs != Py_ssize_t(sizeof...(A))) return nullptr;
    const Self* object = instance_of<Self>(self);
    if (!object) return nullptr;
    return invoke(*object, args, std::index_sequence_for<A...>{});
  }

 private:
  template <std::size_t... I>
  static PyObject* invoke(const Self& object, PyObject* const* args,
                          std::index_sequence<I...>) noexcept {
    std::tuple<A...> values;
    if (!(ArgFrom<A>::get(args[I], std::get<I>(values)) && ...)) return nullptr;
    try {
      return F(object, std::get<I>(values)...).release().ptr();
    } catch (py::error_already_set& error) {  // as pybind11's dispatcher: the Python error, raised
      error.restore();
      return nullptr;
#ifdef __GLIBCXX__
    } catch (abi::__forced_unwind&) {  // a cancelled thread unwinds on
      throw;
#endif
    } catch (...) {  // ValueError, TypeError, Ctrl-C (Interrupted): the module's translators
      py::detail::try_translate_exceptions();
      return nullptr;
    }
  }
};

// cls.def(name, F, extra...), and F's direct call registered for a _CoreMethod.
template <auto F, typename Class, typename... Extra>
Class& def_fast(Class& cls, const char* name, const Extra&... extra) {
  cls.def(name, F, extra...);
  add(cls, name, &Caller<F>::call);
  return cls;
}

}  // namespace spotkin::bindings::fast
