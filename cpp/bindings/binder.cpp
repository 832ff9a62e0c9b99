// The engine of the one boundary (binder.hpp), compiled once for float and double.
#include "binder.hpp"

#include <pybind11/numpy.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <new>
#include <string>
#include <type_traits>
#include <vector>

#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"
#include "spotkin/stream.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::bindings::binder {

namespace {

std::string describe(const Trailing& t) {
  return format_shape(Shape(t.dim, t.dim + t.ndim), true);
}

// How argument k's rows are read: as they are (its leading shape is the batch's), one
// row for every sample, or gathered through its broadcast strides.
enum class Rows : std::uint8_t { Absent, Direct, Shared, Gathered };

template <typename T>
struct Argument {
  Rows rows = Rows::Absent;
  py::object array;  // C-contiguous in T (a py::object: a default py::array would be a new empty array)
  const T* data = nullptr;
  std::ptrdiff_t width = 0;
  std::uint64_t angles = 0;
  int shape = 0;
  Shape leading;
  std::vector<std::ptrdiff_t> row_step;  // Gathered: rows to step per batch dimension (0 where broadcast)
};

struct Output {
  py::object array;  // null for a single sample's status
  void* data = nullptr;
  std::ptrdiff_t width = 0;
  std::int8_t single_status = 0;  // a single sample's status, without an array
  bool scalar = false;            // returned as a spotkin.Status
  bool single = false;            // one sample (no leading dimension)
  bool given = false;             // the caller's out= array
  PyObject** codes = nullptr;     // Out::codes
  bool to_scalar = false;         // Out::scalar
  py::object result() const {
    if (scalar) return status_object(single_status);
    if (single && codes && *codes) {  // the enum's member, by value
      const std::int8_t code = *static_cast<const std::int8_t*>(data);
      if (code >= 0 && code < PyTuple_GET_SIZE(*codes))
        return py::reinterpret_borrow<py::object>(PyTuple_GET_ITEM(*codes, code));
    }
    if (single && to_scalar && !given) {  // array[()]: a NumPy scalar
      PyObject* value = PyObject_GetItem(array.ptr(), py::tuple().ptr());
      if (!value) throw py::error_already_set();
      return py::reinterpret_steal<py::object>(value);
    }
    return array;
  }
  void describe(const Out& spec, bool one, bool caller_s) {
    single = one, given = caller_s, to_scalar = spec.scalar;
    codes = spec.kind == Kind::Code ? spec.codes : nullptr;
  }
};

// The outputs of one call, only the op's constructed (an array of kMaxOuts was zeroed whole, a
// `rep stos` on every single-sample call).
class Outputs {
 public:
  explicit Outputs(int n) {
    for (; n_ < n; ++n_) new (storage_ + n_ * sizeof(Output)) Output();
  }
  ~Outputs() {
    while (n_ > 0) (*this)[--n_].~Output();
  }
  Outputs(const Outputs&) = delete;
  Outputs& operator=(const Outputs&) = delete;
  Output* data() { return std::launder(reinterpret_cast<Output*>(storage_)); }
  Output& operator[](int k) { return data()[k]; }

 private:
  alignas(Output) unsigned char storage_[kMaxOuts * sizeof(Output)];
  int n_ = 0;
};

// The call's answer: its one output, or a tuple of them: the op's registered result type (a
// NamedTuple, built here as tuple.__new__ builds it) or a plain tuple until one is registered.
py::object results(const Op& op, const Output* outs) {
  if (op.n_outs == 1) return outs[0].result();
  auto* type = op.named && *op.named ? reinterpret_cast<PyTypeObject*>(*op.named) : &PyTuple_Type;
  PyObject* result = type == &PyTuple_Type ? PyTuple_New(op.n_outs) : type->tp_alloc(type, op.n_outs);
  if (!result) throw py::error_already_set();
  for (int o = 0; o < op.n_outs; ++o) PyTuple_SET_ITEM(result, o, outs[o].result().release().ptr());
  return py::reinterpret_steal<py::object>(result);
}

// NumPy's broadcast of the arguments' leading shapes; ValueError naming them.
template <typename T>
Shape broadcast(const Op& op, const Argument<T>* args) {
  std::size_t nd = 0;
  for (int k = 0; k < op.n_args; ++k)
    if (args[k].rows != Rows::Absent) nd = std::max(nd, args[k].leading.size());
  Shape out(nd, 1);
  for (int k = 0; k < op.n_args; ++k) {
    if (args[k].rows == Rows::Absent) continue;
    const Shape& s = args[k].leading;
    for (std::size_t d = 0; d < s.size(); ++d) {
      py::ssize_t& o = out[nd - s.size() + d];
      if (s[d] == o || s[d] == 1) continue;
      if (o == 1) {
        o = s[d];
        continue;
      }
      // "a (5, 6) and b (3, 4, 3) do not broadcast over their leading dimensions", as the façade's
      std::vector<std::string> named;
      for (int j = 0; j < op.n_args; ++j) {
        if (args[j].rows == Rows::Absent) continue;
        Shape full = args[j].leading;
        const Trailing& t = op.args[j].shapes[args[j].shape];
        full.insert(full.end(), t.dim, t.dim + t.ndim);
        named.push_back(std::string(op.args[j].name) + " " + format_shape(full));
      }
      std::string msg;
      for (std::size_t j = 0; j < named.size(); ++j)
        msg += (j == 0 ? "" : j + 1 == named.size() ? " and " : ", ") + named[j];
      throw py::value_error(msg + " do not broadcast over their leading dimensions");
    }
  }
  return out;
}

// Finds which accepted shape arr has; ValueError listing them otherwise.
int match_shape(const Arg& spec, const py::array& arr, Shape& leading) {
  const auto nd = static_cast<std::size_t>(arr.ndim());
  const py::ssize_t* shape = arr.shape();  // read in place: no vector for a call's usual shapes
  for (int s = 0; s < spec.n_shapes; ++s) {
    const Trailing& t = spec.shapes[s];
    bool ok = nd >= std::size_t(t.ndim);
    for (int d = 0; ok && d < t.ndim; ++d) ok = shape[nd - std::size_t(t.ndim) + std::size_t(d)] == t.dim[d];
    if (ok) {
      leading.assign(shape, shape + nd - std::size_t(t.ndim));
      return s;
    }
  }
  std::string expected = describe(spec.shapes[0]);
  for (int s = 1; s < spec.n_shapes; ++s) expected += (s + 1 == spec.n_shapes ? " or " : ", ") + describe(spec.shapes[s]);
  throw py::value_error(std::string(spec.name) + " must have shape " + expected + ", got " +
                        format_shape(Shape(shape, shape + nd)));
}

template <typename T>
std::size_t element_size(Kind kind) {
  return kind == Kind::Real ? sizeof(T) : kind == Kind::Index ? sizeof(std::int64_t) : 1;
}

const char* dtype_name(Kind kind, bool single) {
  if (kind == Kind::Bool) return "bool";
  if (kind == Kind::Status || kind == Kind::Code) return "int8";
  if (kind == Kind::Index) return "int64";
  return single ? "float32" : "float64";
}

// Checks a caller's out= array for output k; TypeError (dtype) or ValueError (shape, layout).
template <typename T>
py::array checked_out(py::handle obj, const Out& spec, int k, const py::ssize_t* shape, int ndim) {
  const auto label = [&] {
    return "out[" + std::to_string(k) + "] (" + spec.name + ")";
  };  // for errors only
  if (!py::isinstance<py::array>(obj) || is_masked_array(obj))
    throw py::type_error(label() + " must be a NumPy array, got " +
                         std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
  auto arr = py::reinterpret_borrow<py::array>(obj);
  bool dtype_ok = false;
  switch (spec.kind) {
    case Kind::Real: dtype_ok = py::array_t<T>::check_(arr); break;
    case Kind::Bool: dtype_ok = py::array_t<bool>::check_(arr); break;
    case Kind::Status:
    case Kind::Code: dtype_ok = py::array_t<std::int8_t>::check_(arr); break;
    case Kind::Index: dtype_ok = py::array_t<std::int64_t>::check_(arr); break;
  }
  if (!dtype_ok)
    throw py::type_error(label() + " must have dtype " +
                         dtype_name(spec.kind, std::is_same_v<T, float>) + ", got " +
                         std::string(py::str(arr.dtype())));
  // compared in place (a Shape made per call was two allocations per out= array, a control tick's
  // cost)
  if (arr.ndim() != ndim || !std::equal(shape, shape + ndim, arr.shape()))
    throw py::value_error(label() + " must have shape " + format_shape(Shape(shape, shape + ndim)) +
                          ", got " + format_shape(Shape(arr.shape(), arr.shape() + arr.ndim())));
  constexpr int kNeeded = py::detail::npy_api::NPY_ARRAY_C_CONTIGUOUS_ | py::detail::npy_api::NPY_ARRAY_ALIGNED_ |
                          py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  if ((py::detail::array_proxy(arr.ptr())->flags & kNeeded) != kNeeded)
    throw py::value_error(label() + " must be a C-contiguous, aligned and writeable array");
  return arr;
}

// NumPy's type number of an output of this kind, T the working dtype.
template <typename T>
int npy_type(Kind kind) {
  using api = py::detail::npy_api;
  return kind == Kind::Real    ? (std::is_same_v<T, float> ? api::NPY_FLOAT_ : api::NPY_DOUBLE_)
         : kind == Kind::Bool  ? api::NPY_BOOL_
         : kind == Kind::Index ? api::NPY_INT64_
                               : api::NPY_INT8_;
}

// A new C-contiguous array of NumPy type `type` and shape dims[0, nd), made directly (no shape
// vectors): a new reference.
PyObject* small_array(int type, int nd, Py_intptr_t* dims) {
  auto& numpy = py::detail::npy_api::get();
  PyObject* made =
      numpy.PyArray_NewFromDescr_(numpy.PyArray_Type_, numpy.PyArray_DescrFromType_(type), nd, dims,
                                  nullptr, nullptr, 0, nullptr);
  if (!made) throw py::error_already_set();
  return made;
}

// A new C-contiguous output (leading + the sample's shape) of the output's dtype. A small one is made
// directly (no shape vectors: a single sample's call makes several); a large one comes from the
// buffer cache (cached_array).
template <typename T>
py::array new_output(const Out& spec, const Shape& leading) {
  const std::size_t nd = leading.size() + std::size_t(spec.shape.ndim);
  const std::size_t item = element_size<T>(spec.kind);
  std::size_t bytes = item;
  for (py::ssize_t d : leading) bytes *= std::size_t(d);
  for (int d = 0; d < spec.shape.ndim; ++d) bytes *= std::size_t(spec.shape.dim[d]);
  if (bytes >= BufferCache::kMinBytes || nd > 32) {
    Shape trailing(spec.shape.dim, spec.shape.dim + spec.shape.ndim);
    switch (spec.kind) {
      case Kind::Real: return new_array<T>(leading, trailing);
      case Kind::Bool: return new_array<bool>(leading, trailing);
      case Kind::Index: return new_array<std::int64_t>(leading, trailing);
      case Kind::Status:
      case Kind::Code: break;
    }
    return new_array<std::int8_t>(leading, trailing);
  }
  Py_intptr_t dims[32];
  std::size_t k = 0;
  for (py::ssize_t d : leading) dims[k++] = d;
  for (int d = 0; d < spec.shape.ndim; ++d) dims[k++] = spec.shape.dim[d];
  return py::reinterpret_steal<py::array>(small_array(npy_type<T>(spec.kind), int(nd), dims));
}

// A single sample's outputs, reused (issue 34: a control loop's call allocates nothing). Making
// and freeing a small NumPy array costs ~50-60 ns (NumPy's allocator looks up its handler in a
// context variable on both), two or three per call. The pool keeps a reference to the arrays it
// made; one whose only reference is the pool's is unreachable from Python, so it is handed out
// again, as CPython's zip reuses its result tuple. Only if it is exactly as made: no weak
// reference, no base, its shape, strides, dtype and flags unchanged (a user may set a.shape or
// a.flags.writeable before dropping it). Used under the GIL only: off on free-threaded Python.
// Every output is written whole by its kernel, as a new array's would be.
class SparePool {
 public:
  // A free array of this type and sample shape (a new reference), or null.
  PyObject* take(int type, int nd, const Py_intptr_t* dims) {
#ifdef Py_GIL_DISABLED
    return nullptr;
#else
    for (Entry& e : entries_) {
      if (!e.array || e.type != type || e.nd != nd || !same(dims, e.dims, nd)) continue;
      if (Py_REFCNT(e.array) != 1) continue;  // the caller holds it
      if (!e.unchanged()) {                   // changed before it was dropped: let it go
        Py_CLEAR(e.array);
        continue;
      }
      Py_INCREF(e.array);
      return e.array;
    }
    return nullptr;
#endif
  }
  // A free result tuple of this type and length, its items replaced by None (they go back to
  // the pool free), or null. Filled whole by single_results before Python sees it.
  PyObject* take_tuple(PyTypeObject* type, int n) {
#ifdef Py_GIL_DISABLED
    return nullptr;
#else
    for (PyObject* t : tuples_) {
      if (!t || Py_TYPE(t) != type || PyTuple_GET_SIZE(t) != n || Py_REFCNT(t) != 1) continue;
      for (int k = 0; k < n; ++k) {  // None, never null: gc.get_objects() may show it
        PyObject* item = PyTuple_GET_ITEM(t, k);
        Py_INCREF(Py_None);
        PyTuple_SET_ITEM(t, k, Py_None);
        Py_XDECREF(item);
      }
      Py_INCREF(t);
      return t;
    }
    return nullptr;
#endif
  }
  // Keep a reference to `made`, a new result tuple of a type without a __dict__ or weak
  // references (a NamedTuple), as keep does an array.
  void keep_tuple(PyObject* made) {
#ifndef Py_GIL_DISABLED
    const PyTypeObject* type = Py_TYPE(made);
    if (type->tp_dictoffset || type->tp_weaklistoffset) return;
    PyObject*& slot = *choose(tuples_, next_tuple_, [](PyObject*& t) -> PyObject*& { return t; });
    Py_XDECREF(slot);
    slot = made;
    Py_INCREF(made);
#else
    (void)made;
#endif
  }
  // Keep a reference to `made`, a new array of this type and shape: in a free slot, else in
  // place of an unused array, else in place of the oldest kept (the caller may still hold it).
  void keep(PyObject* made, int type, int nd, const Py_intptr_t* dims) {
#ifndef Py_GIL_DISABLED
    Entry* slot = choose(entries_, next_, [](Entry& e) -> PyObject*& { return e.array; });
    Py_XDECREF(slot->array);
    const auto* a = reinterpret_cast<const Fields*>(made);
    slot->array = made, slot->type = type, slot->nd = nd;
    slot->descr = a->descr, slot->flags = a->flags;
    std::copy(dims, dims + nd, slot->dims);
    std::copy(a->strides, a->strides + nd, slot->strides);
    Py_INCREF(made);
#else
    (void)made, (void)type, (void)nd, (void)dims;
#endif
  }

 private:
  // NumPy's PyArrayObject_fields up to weakreflist (the same in NumPy 1.x and 2.x).
  struct Fields {
    PyObject ob_base;  // PyObject_HEAD
    char* data;
    int nd;
    Py_intptr_t* dimensions;
    Py_intptr_t* strides;
    PyObject* base;
    PyObject* descr;
    int flags;
    PyObject* weakreflist;
  };
  struct Entry {
    PyObject* array = nullptr;
    int type = 0, nd = 0, flags = 0;
    PyObject* descr = nullptr;
    Py_intptr_t dims[kMaxDims] = {}, strides[kMaxDims] = {};
    bool unchanged() const {
      const auto* a = reinterpret_cast<const Fields*>(array);
      return Py_TYPE(array) ==
                 reinterpret_cast<PyTypeObject*>(py::detail::npy_api::get().PyArray_Type_) &&
             !a->weakreflist && !a->base && a->descr == descr && a->flags == flags && a->nd == nd &&
             same(dims, a->dimensions, nd) && same(strides, a->strides, nd);
    }
  };
  // The slot for a new object among `slots` (object(slot): its reference): an empty one, else one
  // whose object only the pool refers to, else the next in turn (the caller may still hold its
  // object; the pool lets it go).
  template <typename Slot, std::size_t N, typename Object>
  static Slot* choose(Slot (&slots)[N], unsigned& next, Object object) {
    for (Slot& slot : slots)
      if (!object(slot)) return &slot;
    for (Slot& slot : slots)
      if (Py_REFCNT(object(slot)) == 1) return &slot;
    return &slots[next++ % N];
  }
  // a loop, not std::equal: GCC makes that a call of memcmp (~10 ns a call on these few bytes)
  static bool same(const Py_intptr_t* a, const Py_intptr_t* b, int n) {
    for (int k = 0; k < n; ++k)
      if (a[k] != b[k]) return false;
    return true;
  }
  static constexpr int kSlots = 16, kTupleSlots = 8;
  Entry entries_[kSlots];
  PyObject* tuples_[kTupleSlots] = {};
  unsigned next_ = 0, next_tuple_ = 0;
};

SparePool& spare_pool() {
  static SparePool* pool =
      new SparePool();  // never freed: its arrays outlive the interpreter's teardown order
  return *pool;
}

// A single sample's output array (no leading dimension): a free spare, or a new one kept.
template <typename T>
py::array single_output(const Out& spec) {
  const int type = npy_type<T>(spec.kind);
  Py_intptr_t dims[kMaxDims];
  std::copy(spec.shape.dim, spec.shape.dim + spec.shape.ndim, dims);
  SparePool& pool = spare_pool();
  if (PyObject* spare = pool.take(type, spec.shape.ndim, dims))
    return py::reinterpret_steal<py::array>(spare);
  PyObject* made = small_array(type, spec.shape.ndim, dims);
  pool.keep(made, type, spec.shape.ndim, dims);
  return py::reinterpret_steal<py::array>(made);
}

// A single sample's result tuple of the op's registered type (several outputs): a free spare
// taken before the outputs were made (`spare`, its items None so that its arrays are free for
// them), else a new one kept. Any other case: results().
py::object single_results(const Op& op, const Output* outs, py::object spare) {
  if (!spare) {
    py::object made = results(op, outs);
    if (op.n_outs > 1 && op.named && *op.named) spare_pool().keep_tuple(made.ptr());
    return made;
  }
  for (int o = 0; o < op.n_outs; ++o) {
    PyObject* none = PyTuple_GET_ITEM(spare.ptr(), o);
    PyTuple_SET_ITEM(spare.ptr(), o, outs[o].result().release().ptr());
    Py_DECREF(none);
  }
  return spare;
}

// Output r made here: a single sample's status in r itself (returned as a spotkin.Status), else a
// new array of the leading shape and the output's sample shape (reusable: a free spare of the
// pool).
template <typename T>
void make_output(Output& r, const Out& spec, const Shape& leading, bool reusable = false) {
  r.describe(spec, leading.empty(), false);
  if (spec.kind == Kind::Status && leading.empty() && spec.shape.ndim == 0) {
    r.data = &r.single_status;
    r.scalar = true;
    return;
  }
  py::array made =
      reusable && leading.empty() ? single_output<T>(spec) : new_output<T>(spec, leading);
  r.data = made.mutable_data();
  r.array = std::move(made);
}

// The bytes an array spans (a C-contiguous `out=` array's), read once for the inputs it is tested
// on.
struct Span {
  const char *lo, *hi;
  explicit Span(const py::array& a) : lo(static_cast<const char*>(a.data())), hi(lo + a.nbytes()) {}
  bool overlaps(const void* data, std::size_t bytes) const noexcept {
    const auto* b = static_cast<const char*>(data);
    return hi > lo && bytes > 0 && lo < b + bytes && b < hi;
  }
};

// One span of a thread's samples. The common case: every argument read in place (its own rows, or
// one row for all read with stride 0) and nothing huge, NaN or Inf in the span: one kernel call.
template <typename T>
void run_span(const Op& op, const void* context, Kernel<T> kernel, const Argument<T>* args, const Output* outs,
              const Shape& leading, bool stream, bool in_place, std::ptrdiff_t begin, std::ptrdiff_t end) {
  Block<T> block;
  block.stream = stream;
  for (int k = 0; k < op.n_args; ++k) block.shape[k] = args[k].shape;
  for (int k = 0; in_place && k < op.n_args; ++k) {
    const Argument<T>& a = args[k];
    if (a.rows == Rows::Absent || (!a.angles && !op.args[k].nan_groups)) continue;
    const std::ptrdiff_t rows = a.rows == Rows::Shared ? 1 : end - begin;
    const T* first = a.rows == Rows::Shared ? a.data : a.data + a.width * begin;
    if (any_unusual(first, rows * a.width)) in_place = false;
  }
  if (in_place) {
    block.first = begin;
    block.m = end - begin;
    for (int k = 0; k < op.n_args; ++k) {
      const Argument<T>& a = args[k];
      const bool shared = a.rows == Rows::Shared;
      block.in[k] = a.rows == Rows::Absent ? nullptr : shared ? a.data : a.data + a.width * begin;
      block.stride[k] = shared || a.rows == Rows::Absent ? 0 : a.width;
    }
    for (int o = 0; o < op.n_outs; ++o) {
      const std::size_t size = element_size<T>(op.outs[o].kind);
      block.out[o] = static_cast<char*>(outs[o].data) + size * std::size_t(outs[o].width * begin);
    }
    kernel(context, block);
    return;
  }
  // Otherwise block by block: gathered rows, and copies of the blocks with huge angles reduced.
  std::vector<T> scratch[kMaxArgs];  // per argument, allocated when first needed
  bool scratch_filled[kMaxArgs] = {};
  for (std::ptrdiff_t first = begin; first < end; first += kAngleBlock) {
    const std::ptrdiff_t m = std::min(kAngleBlock, end - first);
    block.first = first;
    block.m = m;
    bool unusual[kMaxArgs] = {};
    for (int k = 0; k < op.n_args; ++k) {
      const Argument<T>& a = args[k];
      const Arg& spec = op.args[k];
      const std::ptrdiff_t w = a.width;
      std::vector<T>& buffer = scratch[k];
      switch (a.rows) {
        case Rows::Absent:
          block.in[k] = nullptr;
          block.stride[k] = 0;
          continue;
        case Rows::Direct:
          block.in[k] = a.data + w * first;
          block.stride[k] = w;
          break;
        case Rows::Shared:
          if (spec.strided) {
            block.in[k] = a.data;
            block.stride[k] = 0;
          } else {  // the one row, repeated (filled once per thread; the scan below keeps it reduced)
            if (!scratch_filled[k]) {
              buffer.resize(std::size_t(w * kAngleBlock));
              for (std::ptrdiff_t i = 0; i < kAngleBlock; ++i) std::copy(a.data, a.data + w, buffer.data() + w * i);
              scratch_filled[k] = true;
            }
            block.in[k] = buffer.data();
            block.stride[k] = w;
          }
          break;
        case Rows::Gathered: {
          buffer.resize(std::size_t(w * kAngleBlock));
          const std::size_t nd = leading.size();
          std::ptrdiff_t index[16] = {};  // the multi-index of sample `first` (more than 16 leading
          std::ptrdiff_t rest = first;    // dimensions: call_in materialises the broadcast instead)
          for (std::size_t d = nd; d-- > 0;) {
            index[d] = rest % leading[d];
            rest /= leading[d];
          }
          std::ptrdiff_t row = 0;
          for (std::size_t d = 0; d < nd; ++d) row += index[d] * a.row_step[d];
          for (std::ptrdiff_t i = 0; i < m; ++i) {
            std::copy(a.data + w * row, a.data + w * row + w, buffer.data() + w * i);
            for (std::size_t d = nd; d-- > 0;) {  // the next multi-index, and its row
              row += a.row_step[d];
              if (++index[d] < leading[d]) break;
              row -= a.row_step[d] * index[d];
              index[d] = 0;
            }
          }
          block.in[k] = buffer.data();
          block.stride[k] = w;
          break;
        }
      }
      if (!a.angles && !spec.nan_groups) continue;
      const std::ptrdiff_t rows = block.stride[k] == 0 ? 1 : m;
      if (!any_unusual(block.in[k], rows * w)) continue;
      unusual[k] = true;
      if (!a.angles) continue;
      if (block.in[k] != buffer.data()) {  // reduce in a copy, never in the caller's array
        buffer.resize(std::size_t(w * std::max<std::ptrdiff_t>(rows, kAngleBlock)));
        std::copy(block.in[k], block.in[k] + rows * w, buffer.data());
        block.in[k] = buffer.data();
      }
      T* x = buffer.data();
      for (std::ptrdiff_t i = 0; i < rows; ++i)
        for (std::ptrdiff_t j = 0; j < w; ++j)
          if ((a.angles >> j) & 1U) x[i * w + j] = T(vector_math::reduce_huge_angle(double(x[i * w + j])));
    }
    for (int o = 0; o < op.n_outs; ++o) {
      const std::size_t size = element_size<T>(op.outs[o].kind);
      block.out[o] = static_cast<char*>(outs[o].data) + size * std::size_t(outs[o].width * first);
    }
    kernel(context, block);
    // NaN rows: a non-finite value in part g of an argument's row makes part g of each real output row NaN
    for (int k = 0; k < op.n_args; ++k) {
      const int groups = op.args[k].nan_groups;
      if (!unusual[k] || !groups) continue;
      const std::ptrdiff_t w = args[k].width, part = w / groups;
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const T* row = block.in[k] + block.stride[k] * i;
        for (int g = 0; g < groups; ++g) {
          bool finite = true;
          for (std::ptrdiff_t j = 0; j < part; ++j) finite &= std::isfinite(double(row[g * part + j]));
          if (finite) continue;
          for (int o = 0; o < op.n_outs; ++o) {
            if (op.outs[o].kind != Kind::Real) continue;
            const std::ptrdiff_t ow = outs[o].width, opart = ow / groups;
            T* out_row = block.real(o) + ow * i + opart * g;
            std::fill(out_row, out_row + opart, T(quiet_nan<double>()));
          }
        }
      }
    }
  }
}

// A thread's samples [begin, end), in spans. Where arguments are scanned for huge, NaN or Inf
// values, spans of kScanSpan samples: the kernel then reads each span while the scan left it in
// cache (the body's FK and Jacobian measured 5-15 % slower after one scan of a whole chunk, and
// leg FK over 1e6 samples 5-10 % slower in 2048-sample spans than in 512); in one span otherwise.
// Whether large outputs are streamed is the call's decision (Block::stream), not the span's.
constexpr std::ptrdiff_t kScanSpan = kAngleBlock;

template <typename T>
void run_range(const Op& op, const void* context, Kernel<T> kernel, const Argument<T>* args, const Output* outs,
               const Shape& leading, bool stream, std::ptrdiff_t begin, std::ptrdiff_t end) {
  bool in_place = true, scanned = false;
  for (int k = 0; k < op.n_args; ++k) {
    const Argument<T>& a = args[k];
    if (a.rows == Rows::Gathered || (a.rows == Rows::Shared && !op.args[k].strided)) in_place = false;
    if (a.rows != Rows::Absent && (a.angles || op.args[k].nan_groups)) scanned = true;
  }
  const std::ptrdiff_t span = in_place && !scanned ? std::max<std::ptrdiff_t>(1, end - begin) : kScanSpan;
  for (std::ptrdiff_t first = begin; first < end; first += span)
    run_span<T>(op, context, kernel, args, outs, leading, stream, in_place, first, std::min(end, first + span));
}

// arr with its repeated rows read once: each leading dimension that steps by 0 bytes (a broadcast
// view, such as np.broadcast_to's) gets length 1, so that the rows are broadcast here (Shared or
// Gathered) instead of copied whole by contiguous(). arr itself when it repeats none.
py::array collapse_repeated_rows(const py::array& arr, std::size_t n_leading) {
  const py::ssize_t* shape = arr.shape();
  const py::ssize_t* strides = arr.strides();
  bool repeats = false;
  for (std::size_t d = 0; d < n_leading; ++d) repeats |= strides[d] == 0 && shape[d] > 1;
  if (!repeats) return arr;
  std::vector<py::ssize_t> collapsed(shape, shape + arr.ndim()),
      steps(strides, strides + arr.ndim());
  for (std::size_t d = 0; d < n_leading; ++d)
    if (steps[d] == 0) collapsed[d] = 1;
  return py::array(arr.dtype(), collapsed, steps, arr.data(), arr);  // a view: arr stays its base
}

template <typename T>
py::object call_in(const Op& op, const void* context, const py::object* objects, const bool* present, py::handle out) {
  Argument<T> args[kMaxArgs];
  // each argument's leading shape as read, where its repeated rows are collapsed
  Shape read_leading[kMaxArgs];
  bool collapsed[kMaxArgs] = {};
  for (int k = 0; k < op.n_args; ++k) {
    if (!present[k]) continue;  // an omitted optional argument
    const Arg& spec = op.args[k];
    Argument<T>& a = args[k];
    const auto as_given = py::reinterpret_borrow<py::array>(objects[k]);
    a.shape = match_shape(spec, as_given, a.leading);
    const py::array given = collapse_repeated_rows(as_given, a.leading.size());
    if (given.ptr() != as_given.ptr()) {
      collapsed[k] = true;
      read_leading[k].assign(given.shape(), given.shape() + a.leading.size());
    }
    a.width = spec.shapes[a.shape].size();
    a.angles = spec.angles[a.shape];
    // a float64 angle beside float32 arguments is reduced before it is narrowed (1e308 rad is an angle)
    auto working = std::is_same_v<T, float> && a.angles && !is_float32(given) ? seed_angles<T>(given, a.width, a.angles)
                                                                             : contiguous<T>(given);
    a.data = working.data();
    a.array = std::move(working);
    a.rows = Rows::Direct;
  }
  const Shape leading = broadcast(op, args);  // of the leading shapes as given
  const py::ssize_t n = count(leading);
  for (int k = 0; k < op.n_args; ++k)  // then each argument's rows as read
    if (collapsed[k]) args[k].leading = read_leading[k];
  for (int k = 0; k < op.n_args; ++k) {
    Argument<T>& a = args[k];
    if (a.rows == Rows::Absent || a.leading == leading) continue;
    if (count(a.leading) == 1) {
      a.rows = Rows::Shared;
      continue;
    }
    if (leading.size() > 16) {  // beyond the gather's index: materialise the broadcast
      Shape full = leading;
      full.push_back(a.width);
      py::tuple shape(full.size());
      for (std::size_t d = 0; d < full.size(); ++d) shape[d] = py::int_(full[d]);
      auto working = contiguous<T>(py::module_::import("numpy").attr("broadcast_to")(a.array, shape));
      a.data = working.data();
      a.array = std::move(working);
      continue;
    }
    a.rows = Rows::Gathered;
    a.row_step.assign(leading.size(), 0);
    std::ptrdiff_t step = 1;
    const std::size_t offset = leading.size() - a.leading.size();
    for (std::size_t d = a.leading.size(); d-- > 0;) {
      a.row_step[offset + d] = a.leading[d] == 1 ? 0 : step;
      step *= a.leading[d];
    }
  }

  // the outputs: the caller's (checked) or new ones
  Output outs[kMaxOuts];
  py::handle given[kMaxOuts];
  if (!out.is_none()) {
    if (py::isinstance<py::tuple>(out) || (op.n_outs > 1 && py::isinstance<py::list>(out))) {
      auto seq = py::reinterpret_borrow<py::sequence>(out);
      if (py::ssize_t(seq.size()) != op.n_outs)
        throw py::value_error("out must hold " + std::to_string(op.n_outs) + " arrays (or None), got " +
                              std::to_string(seq.size()));
      for (int o = 0; o < op.n_outs; ++o) given[o] = seq[std::size_t(o)];
    } else if (op.n_outs == 1) {
      given[0] = out;
    } else {
      throw py::type_error("out must be a tuple of " + std::to_string(op.n_outs) + " arrays (or None)");
    }
  }
  for (int o = 0; o < op.n_outs; ++o) {
    const Out& spec = op.outs[o];
    Output& r = outs[o];
    r.width = spec.shape.size();
    if (given[o] && !given[o].is_none()) {
      Shape shape = leading;
      shape.insert(shape.end(), spec.shape.dim, spec.shape.dim + spec.shape.ndim);
      py::array checked = checked_out<T>(given[o], spec, o, shape.data(), int(shape.size()));
      r.describe(spec, leading.empty(), true);
      r.data = checked.mutable_data();
      r.array = checked;
      const Span span(checked);
      for (int k = 0; k < op.n_args; ++k)  // an input that shares memory with an output is read from a copy
        if (args[k].rows != Rows::Absent &&
            span.overlaps(args[k].data,
                          sizeof(T) * std::size_t(count(args[k].leading) * args[k].width))) {
          const auto source = py::reinterpret_borrow<py::array>(args[k].array);
          py::array_t<T, py::array::c_style> copy(Shape(source.shape(), source.shape() + source.ndim()));
          if (source.nbytes()) std::memcpy(copy.mutable_data(), source.data(), std::size_t(source.nbytes()));
          args[k].data = copy.data();
          args[k].array = std::move(copy);
        }
      continue;
    }
    make_output<T>(r, spec, leading);
  }

  Kernel<T> kernel;
  if constexpr (std::is_same_v<T, float>) {
    kernel = op.f32;
  } else {
    kernel = op.f64;
  }
  std::size_t out_bytes = 0;  // the whole call's
  for (int o = 0; o < op.n_outs; ++o)
    out_bytes += std::size_t(n * outs[o].width) * element_size<T>(op.outs[o].kind);
  const bool stream = out_bytes >= kStreamBytes;
  const std::ptrdiff_t min_per_thread = min_chunk(op.ns_per_sample);
  if (n < 2 * min_per_thread) {  // one thread would run it all: inline, no thread start
    ReleaseGilFor release(n);
    run_range<T>(op, context, kernel, args, outs, leading, stream, 0, n);
  } else {
    ReleaseGilFor release(n);
    parallel_for(n, min_per_thread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
      run_range<T>(op, context, kernel, args, outs, leading, stream, b, e);
    });
  }

  return results(op, outs);
}

// The single-sample fast path (issue: a control loop's call). Every argument one sample with
// no leading dimension: an ndarray already in the working dtype, C-contiguous and aligned,
// or a short tuple / list of Python floats and ints (float64, as NumPy reads it); nothing
// NaN, Inf or huge where the op scans; out= None or exactly right with no overlap. Then the
// kernel runs inline on the caller's memory: no conversion, no shape vectors, no threads,
// no scans of spans. Anything else returns a null object and takes the general path, which
// gives the same bits (a single sample is one block there too).
constexpr int kSeqMax = 16;  // a tuple / list argument's longest width on the fast path

enum class Given : std::uint8_t { None, F64, F32, Seq, Other };

Given classify(py::handle obj) {
  using api = py::detail::npy_api;
  PyObject* o = obj.ptr();
  if (o == Py_None) return Given::None;
  const int type = in_place_type(o);
  if (type == api::NPY_DOUBLE_) return Given::F64;
  if (type == api::NPY_FLOAT_) return Given::F32;
  if (PyTuple_CheckExact(o) || PyList_CheckExact(o)) return Given::Seq;
  return Given::Other;
}

template <typename T>
py::object call_single(const Op& op, const void* context, const py::handle* objs,
                       const Given* kinds, py::handle out) {
  Block<T> block(op.n_args);
  T seq_rows[kMaxArgs][kSeqMax];
  std::ptrdiff_t widths[kMaxArgs];  // set with block.in
  for (int k = 0; k < op.n_args; ++k) {
    const Arg& spec = op.args[k];
    PyObject* o = objs[k].ptr();
    if (kinds[k] == Given::None) {
      if (!spec.optional) return {};
      continue;
    }
    int s = 0;
    if (kinds[k] == Given::Seq) {  // a flat sequence of Python numbers: shape (len,)
      const Py_ssize_t len = PySequence_Fast_GET_SIZE(o);
      while (s < spec.n_shapes && !(spec.shapes[s].ndim == 1 && spec.shapes[s].dim[0] == len)) ++s;
      if (s == spec.n_shapes || len > kSeqMax) return {};
      PyObject** items = PySequence_Fast_ITEMS(o);
      for (Py_ssize_t j = 0; j < len; ++j) {
        double v;
        if (!python_number(items[j], v)) return {};
        if (std::is_same_v<T, float> &&
            !(std::fabs(v) <= double(std::numeric_limits<float>::max())))
          return {};
        seq_rows[k][j] = T(v);
      }
      block.in[k] = seq_rows[k];
    } else {
      const auto* a = py::detail::array_proxy(o);
      for (; s < spec.n_shapes; ++s) {
        const Trailing& t = spec.shapes[s];
        bool ok = a->nd == t.ndim;
        for (int d = 0; ok && d < t.ndim; ++d) ok = a->dimensions[d] == t.dim[d];
        if (ok) break;
      }
      if (s == spec.n_shapes) return {};  // a batch, or a wrong shape: the general path says which
      block.in[k] = reinterpret_cast<const T*>(a->data);
    }
    block.shape[k] = s;
    widths[k] = spec.shapes[s].size();
    block.stride[k] = widths[k];
    if (spec.angles[s] ||
        spec.nan_groups) {  // the scan of run_span: NaN, Inf or huge goes the general way
      const double limit = std::is_same_v<T, float> ? double(float(vector_math::kReducibleLimit))
                                                    : vector_math::kReducibleLimit;
      for (std::ptrdiff_t j = 0; j < widths[k]; ++j)
        if (!(std::fabs(double(block.in[k][j])) <= limit)) return {};
    }
  }

  // a spare result tuple first: the arrays it held are then free for the outputs
  py::object spare_tuple;
  if (op.n_outs > 1 && op.named && *op.named && out.is_none())
    spare_tuple = py::reinterpret_steal<py::object>(
        spare_pool().take_tuple(reinterpret_cast<PyTypeObject*>(*op.named), op.n_outs));
  Outputs outs(op.n_outs);
  py::handle given[kMaxOuts];
  if (!out.is_none()) {
    if (PyTuple_CheckExact(out.ptr()) && PyTuple_GET_SIZE(out.ptr()) == op.n_outs) {
      for (int o = 0; o < op.n_outs; ++o) given[o] = PyTuple_GET_ITEM(out.ptr(), o);
    } else if (op.n_outs == 1 && classify(out) != Given::Seq) {  // an array (checked below), not a sequence
      given[0] = out;
    } else {
      return {};
    }
  }
  static const Shape kNoLeading;
  for (int o = 0; o < op.n_outs; ++o) {
    const Out& spec = op.outs[o];
    Output& r = outs[o];
    r.width = spec.shape.size();
    if (given[o] && !given[o].is_none()) {
      py::array checked = checked_out<T>(given[o], spec, o, spec.shape.dim, spec.shape.ndim);
      const Span span(checked);
      for (int k = 0; k < op.n_args; ++k)
        if (block.in[k] && span.overlaps(block.in[k], sizeof(T) * std::size_t(widths[k])))
          return {};
      r.describe(spec, true, true);
      r.data = checked.mutable_data();
      r.array = std::move(checked);
      continue;
    }
    make_output<T>(r, spec, kNoLeading, true);
  }
  block.first = 0;
  block.m = 1;
  for (int o = 0; o < op.n_outs; ++o) block.out[o] = outs[o].data;
  if constexpr (std::is_same_v<T, float>) {
    op.f32(context, block);
  } else {
    op.f64(context, block);
  }
  return single_results(op, outs.data(), std::move(spare_tuple));
}

}  // namespace

PyObject** result_type(const char* name) {
  static auto* types = new std::map<std::string, PyObject*>;  // never destroyed (see status_members)
  return &(*types)[name];
}

void bind_result_types(py::module_& m) {
  m.def(
      "_register_result_type",
      [](const std::string& name, py::object type) {
        const bool members =
            PyTuple_CheckExact(type.ptr());  // an enum's members, by value (Out::members)
        if (!members &&
            (!PyType_Check(type.ptr()) ||
             !PyType_IsSubtype(reinterpret_cast<PyTypeObject*>(type.ptr()), &PyTuple_Type)))
          throw py::type_error(
              "_register_result_type takes a tuple subclass, or a tuple of an enum's members");
        PyObject** slot = result_type(name.c_str());
        Py_XDECREF(*slot);
        *slot = type.release().ptr();
      },
      py::arg("name"), py::arg("type"),
      "Registers the NamedTuple the core returns for the ops that name it (LegSolutions, ...), or "
      "an enum's "
      "members by value (StanceStatus).");
}

py::object call(const Op& op, const void* context, std::initializer_list<py::handle> arg_list, py::handle out) {
  {  // one sample, as a control loop passes it
    Given kinds[kMaxArgs];
    bool any32 = false, all32 = true, fast = true, f32_array = false, f64_array = false;
    int k = 0;
    for (py::handle obj : arg_list) {
      kinds[k] = classify(obj);
      fast &= kinds[k] != Given::Other;
      f32_array |= kinds[k] == Given::F32;
      f64_array |= kinds[k] == Given::F64;
      if (op.args[k].primary && kinds[k] != Given::None) {
        any32 |= kinds[k] == Given::F32;
        all32 &= kinds[k] == Given::F32;
      }
      ++k;
    }
    // every array already in the working dtype (a parameter of the other one: the general path's casts)
    if (fast) {
      py::object result;
      if (any32 && all32 && op.float32 && !f64_array) {
        result = call_single<float>(op, context, arg_list.begin(), kinds, out);
      } else if (!f32_array) {
        result = call_single<double>(op, context, arg_list.begin(), kinds, out);
      }
      if (result) return result;
    }
  }
  py::object arrays[kMaxArgs];  // null until converted (a default py::array would be a new empty array)
  bool present[kMaxArgs] = {};
  bool single = false, any_primary = false;
  int k = 0;
  for (py::handle obj : arg_list) {
    const Arg& spec = op.args[k];
    if (obj.is_none() && spec.optional) {
      ++k;
      continue;
    }
    arrays[k] = as_real_array(obj, spec.name);
    present[k] = true;
    if (spec.primary) {
      const bool f32 = is_float32(py::reinterpret_borrow<py::array>(arrays[k]));
      single = any_primary ? single && f32 : f32;
      any_primary = true;
    }
    ++k;
  }
  if (single && op.float32) return call_in<float>(op, context, arrays, present, out);
  return call_in<double>(op, context, arrays, present, out);
}

}  // namespace spotkin::bindings::binder
