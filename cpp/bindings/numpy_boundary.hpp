// The array checks and conversions under the binder (binder.hpp) and the bindings' model
// parameters: any array-like to a real array (TypeError otherwise), float32 detection, a
// C-contiguous view in the working dtype (copied only when needed), huge angles reduced in
// seeds, new outputs, the GIL release, spotkin.Status objects, rigid transforms.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "binder.hpp"
#include "buffer_cache.hpp"
#include "spotkin/arm.hpp"
#include "spotkin/parallel.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::bindings {

namespace py = pybind11;
using Shape = std::vector<py::ssize_t>;

// obj's NumPy type number when it is an ndarray (exactly) that a one-sample fast path may read in
// place: C-contiguous, aligned, in native byte order; -1 for any other object.
inline int in_place_type(PyObject* obj) {
  using api = py::detail::npy_api;
  if (Py_TYPE(obj) != reinterpret_cast<PyTypeObject*>(api::get().PyArray_Type_)) return -1;
  const auto* a = py::detail::array_proxy(obj);
  const auto* d = py::detail::array_descriptor_proxy(a->descr);
  constexpr int kNeeded = api::NPY_ARRAY_C_CONTIGUOUS_ | api::NPY_ARRAY_ALIGNED_;
#if PY_LITTLE_ENDIAN
  constexpr char kSwapped = '>';
#else
  constexpr char kSwapped = '<';
#endif
  if ((a->flags & kNeeded) != kNeeded || d->byteorder == kSwapped) return -1;
  return d->type_num;
}

// A Python float or int (exactly those types) as a double; false, with no error set, for anything
// else or an int too large for a double.
inline bool python_number(PyObject* item, double& v) {
  if (PyFloat_CheckExact(item)) return v = PyFloat_AS_DOUBLE(item), true;
  if (!PyLong_CheckExact(item)) return false;
  v = PyLong_AsDouble(item);
  return !(v == -1.0 && PyErr_Occurred()) || (PyErr_Clear(), false);
}

inline std::string format_shape(const Shape& shape, bool ellipsis = false) {
  std::string s = "(";
  if (ellipsis) s += shape.empty() ? "..." : "..., ";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (i) s += ", ";
    s += std::to_string(shape[i]);
  }
  if (!ellipsis && shape.size() == 1) s += ",";
  return s + ")";
}

// numpy.ma.MaskedArray, imported on first use (never released: see status_members).
inline bool is_masked_array(py::handle obj) {
  if (Py_TYPE(obj.ptr()) == reinterpret_cast<PyTypeObject*>(py::detail::npy_api::get().PyArray_Type_))
    return false;  // a plain ndarray: the common case, no call
  static PyObject* masked_type = [] {
    return py::object(py::module_::import("numpy.ma").attr("MaskedArray")).release().ptr();
  }();
  return PyObject_IsInstance(obj.ptr(), masked_type) == 1;
}

// An object array of plain Python numbers (NumPy's answer for a list holding ints beyond int64) as
// float64, as NumPy's float64 conversion reads them (spotkin._support.boundary._python_numbers);
// ValueError for an int beyond float64's range; a null object when it holds anything else.
inline py::object python_numbers(const py::array& arr, const char* name) {
  const py::list items = arr.attr("ravel")().attr("tolist")();
  py::array_t<double> out(arr.size());
  double* to = out.mutable_data();
  for (py::ssize_t i = 0; i < py::ssize_t(items.size()); ++i) {
    PyObject* item = PyList_GET_ITEM(items.ptr(), i);
    if (!PyLong_CheckExact(item) && !PyFloat_CheckExact(item) && !PyBool_Check(item)) return {};
    to[i] = PyFloat_AsDouble(item);
    if (to[i] == -1.0 && PyErr_Occurred()) {
      PyErr_Clear();
      throw py::value_error(std::string(name) +
                            " holds an integer too large for float64 (beyond about 1.8e308)");
    }
  }
  return out.attr("reshape")(arr.attr("shape"));
}

// Any array-like to an ndarray of a real dtype; TypeError otherwise (also for a
// masked array, whose mask the kernels would ignore).
inline py::array as_real_array(py::handle obj, const char* name) {
  py::array arr;
  if (py::isinstance<py::array>(obj)) {  // no conversion needed
    if (is_masked_array(obj))
      throw py::type_error(std::string(name) + " must be a plain array, got a masked array (its mask would be "
                           "ignored); pass " + name + ".filled(np.nan) to mark masked entries as missing");
    arr = py::reinterpret_borrow<py::array>(obj);
  } else {
    try {
      arr = py::array(py::reinterpret_borrow<py::object>(obj));  // throws numpy's error, unlike ensure()
    } catch (py::error_already_set& error) {
      if (error.matches(PyExc_ValueError))  // a ragged nested sequence
        throw py::value_error(std::string(name) + " must be a rectangular numeric array: " + error.what());
      arr = py::array();
    }
  }
  if (!arr) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + " must be a real numeric array, got " +
                         std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
  }
  const char kind = arr.dtype().kind();
  if (kind == 'O' && (PyList_Check(obj.ptr()) || PyTuple_Check(obj.ptr())))
    if (py::object numbers = python_numbers(arr, name)) return numbers;  // ints beyond int64
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b')
    throw py::type_error(std::string(name) + " must be a real numeric array, got dtype " +
                         std::string(py::str(arr.dtype())));
  return arr;
}

// float32 of either byte order (a big-endian one is converted, and stays float32).
inline bool is_float32(const py::array& arr) {
  const py::dtype dtype = arr.dtype();
  return dtype.kind() == 'f' && dtype.itemsize() == 4;
}

// A C-contiguous view (or copy) of arr in dtype T. A copy too large to allocate
// raises MemoryError (numpy's), not a null array.
template <typename T>
py::array_t<T, py::array::c_style> contiguous(const py::array& arr) {
  using Exact = py::array_t<T, py::array::c_style>;
  if (Exact::check_(arr)) return py::reinterpret_borrow<Exact>(arr);  // already right: no copy, no call
  if constexpr (std::is_same_v<T, float>) {
    if (!is_float32(arr)) {  // float64 (a seed beside float32 targets): cast here, where 1e308 -> Inf
      const auto wide = contiguous<double>(arr);  // quietly, as the kernels then report (numpy would warn)
      Exact narrow(Shape(wide.shape(), wide.shape() + wide.ndim()));
      const double* from = wide.data();
      float* to = narrow.mutable_data();
      constexpr double kMax = std::numeric_limits<float>::max();
      for (py::ssize_t i = 0; i < wide.size(); ++i)  // beyond the float range: Inf (a cast there is undefined)
        to[i] = std::fabs(from[i]) > kMax ? std::copysign(std::numeric_limits<float>::infinity(), float(from[i] > 0 ? 1 : -1))
                                          : static_cast<float>(from[i]);
      return narrow;
    }
  }
  if (arr.dtype().kind() == 'f' && arr.dtype().itemsize() > 8) {  // longdouble: beyond the float64 range
    // it becomes Inf (then NaN or INVALID_INPUT), quietly: numpy's cast would warn (an error under -W error)
    py::object quiet = py::module_::import("numpy").attr("errstate")(py::arg("over") = "ignore");
    quiet.attr("__enter__")();
    py::object cast;
    try {
      cast = py::array_t<T, py::array::c_style | py::array::forcecast>(py::reinterpret_borrow<py::object>(arr));
    } catch (...) {
      quiet.attr("__exit__")(py::none(), py::none(), py::none());
      throw;
    }
    quiet.attr("__exit__")(py::none(), py::none(), py::none());
    return py::reinterpret_steal<Exact>(cast.release());
  }
  return py::array_t<T, py::array::c_style | py::array::forcecast>(py::reinterpret_borrow<py::object>(arr));
}

inline py::ssize_t count(const Shape& leading) {
  py::ssize_t n = 1;
  for (auto d : leading) n *= d;
  return n;
}

// A new C-contiguous output of shape leading + trailing (large ones from the buffer cache).
template <typename T>
py::array_t<T> new_array(const Shape& leading, const Shape& trailing) {
  Shape shape = leading;
  shape.insert(shape.end(), trailing.begin(), trailing.end());
  return cached_array<T>(shape);
}

// A float64 C-contiguous copy (or view) of obj with exactly `shape` (-1: any length); ValueError
// naming it otherwise.
inline py::array_t<double, py::array::c_style> exact(py::handle obj, const char* name,
                                                     const Shape& shape) {
  auto arr = contiguous<double>(as_real_array(obj, name));
  const Shape got(arr.shape(), arr.shape() + arr.ndim());
  bool same = got.size() == shape.size();
  for (std::size_t k = 0; same && k < shape.size(); ++k) same = shape[k] < 0 || got[k] == shape[k];
  if (!same)
    throw py::value_error(std::string(name) + " must have shape " + format_shape(shape) + ", got " +
                          format_shape(got));
  return arr;
}

// obj's numbers, of exactly `shape`, copied into out (ValueError naming it otherwise).
inline void copy_exact(py::handle obj, const char* name, const Shape& shape, double* out) {
  const auto arr = exact(obj, name, shape);
  std::copy_n(arr.data(), arr.size(), out);
}

// Releases the GIL for batches big enough to gain from it; for a handful of
// samples the release and re-acquire cost more than the computation.
class ReleaseGilFor {
 public:
  static constexpr py::ssize_t kMinSamples = 256;
  explicit ReleaseGilFor(py::ssize_t samples) {
    if (samples >= kMinSamples) release_.emplace();
  }

 private:
  std::optional<py::gil_scoped_release> release_;
};

// The Python IntEnum spotkin.Status, registered at import; single targets get
// its members, batches an int8 array of its values.
inline py::object& status_members() {
  // Never destroyed: a static py::object would be released after the
  // interpreter has finalised.
  static auto* members = new py::object(py::none());
  return *members;
}
inline py::object status_object(std::int8_t code) {
  py::object& members = status_members();
  if (members.is_none()) return py::int_(code);
  PyObject* m = members.ptr();
  if (PyTuple_CheckExact(m) && code >= 0 && code < PyTuple_GET_SIZE(m))  // by value, no int made
    return py::reinterpret_borrow<py::object>(PyTuple_GET_ITEM(m, code));
  return members[py::int_(code)];
}

// The binder's block: huge angles are reduced, and NaN rows written, block by block (binder.cpp).
constexpr std::ptrdiff_t kAngleBlock = 512;  // a multiple of kChunkAlignment: same results for any split

// Whether some of x[0, n) is NaN, Inf or beyond vector_math::kReducibleLimit
// (vector_math::any_beyond): a vectorised scan compiled per CPU level (runtime.cpp).
bool any_unusual(const double* x, std::ptrdiff_t n) noexcept;
bool any_unusual(const float* x, std::ptrdiff_t n) noexcept;

// A seed (or start) array with its huge angles (columns in angle_columns) reduced
// exactly, as with_reduced_angles does for kernel inputs; the same array when it
// has none (one scan; seeds only choose among solutions, so this runs up front).
template <typename T>
py::array_t<T, py::array::c_style> reduce_seed_angles(py::array_t<T, py::array::c_style> seed, std::ptrdiff_t width,
                                                      std::uint64_t angle_columns) {
  const T* data = seed.data();
  const py::ssize_t size = seed.size();
  // the dispatched scan (vectorised at the CPU's level, float compared in float: a
  // baseline-level scan in double was 5 % of the float32 arm RNEA on AVX-512); NaN and Inf
  // also make the copy, which reduce_huge_angle leaves unchanged
  if (!any_unusual(data, size)) return seed;
  py::array_t<T, py::array::c_style> copy(Shape(seed.shape(), seed.shape() + seed.ndim()));
  T* out = copy.mutable_data();
  for (py::ssize_t k = 0; k < size; ++k)
    out[k] = (angle_columns >> (k % width)) & 1U ? T(vector_math::reduce_huge_angle(double(data[k]))) : data[k];
  return copy;
}

// A seed in the working dtype T with its huge angles reduced exactly; a float64
// seed beside float32 targets is reduced before it is narrowed (1e308 rad is an
// angle, not an overflow).
template <typename T>
py::array_t<T, py::array::c_style> seed_angles(const py::array& seed, std::ptrdiff_t width,
                                               std::uint64_t angle_columns) {
  if constexpr (std::is_same_v<T, float>) {
    if (!is_float32(seed)) return contiguous<float>(seed_angles<double>(seed, width, angle_columns));
  }
  return reduce_seed_angles(contiguous<T>(seed), width, angle_columns);
}

// A pose target T: (..., 4, 4) or (..., 7) [x, y, z, qx, qy, qz, qw] (the arm's and the 6R / 7R
// solvers'), and the format of a block's argument k (Block::shape: which of the two it has).
inline binder::Arg pose_target_arg() { return binder::Arg("T", {4, 4}).or_shape({7}); }
template <typename B>
PoseFormat pose_format(const B& b, int k = 0) {
  return b.shape[k] == 0 ? PoseFormat::Matrix : PoseFormat::PositionQuaternion;
}

// Every column of a width-n joint vector is an angle.
constexpr std::uint64_t all_angles(int n) { return n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1; }

// Reads a (4, 4) rigid transform given as any array-like (a model parameter:
// a base, a tool). It must be finite, with last row [0, 0, 0, 1] and a rotation
// orthonormal to 1e-9 with det +1; ValueError otherwise (never orthonormalised).
template <typename Rigid>
Rigid rigid_from(py::handle obj, const char* name) {
  py::array arr = as_real_array(obj, name);
  if (arr.ndim() != 2 || arr.shape(0) != 4 || arr.shape(1) != 4)
    throw py::value_error(std::string(name) + " must have shape (4, 4), got " +
                          format_shape(Shape(arr.shape(), arr.shape() + arr.ndim())));
  auto a = contiguous<double>(arr);
  auto m = a.template unchecked<2>();
  Rigid T;
  double row_error = std::fabs(m(3, 3) - 1.0);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) T.R(i, j) = m(i, j);
    T.p[i] = m(i, 3);
    row_error = std::max(row_error, std::fabs(m(3, i)));
  }
  bool finite = true;  // all 16 (std::max above drops a NaN)
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) finite &= std::isfinite(m(i, j));
  const double orth = finite ? (T.R.transpose() * T.R - decltype(T.R)::Identity()).cwiseAbs().maxCoeff() : 0.0;
  if (!finite || !(row_error <= 1e-9) || !(orth <= 1e-9) || !(T.R.determinant() > 0.0))
    throw py::value_error(std::string(name) +
                          " must be a finite rigid transform: last row [0, 0, 0, 1], rotation part "
                          "orthonormal to 1e-9 with determinant +1");
  return T;
}

}  // namespace spotkin::bindings
