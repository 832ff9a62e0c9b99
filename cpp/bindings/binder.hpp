// The one boundary between NumPy and the batch kernels.
//
// A binding declares an operation, Op: its batched arguments (name, the shape of
// one sample, which columns are angles, whether it may be None), its outputs (name,
// shape of one sample, real / bool / status), and one kernel for float and double.
// binder::call does everything else, once for every binding:
// - any array-like to an array of a real dtype, TypeError otherwise; float32 stays
//   float32 when every primary argument is float32 (NumPy's promotion), other
//   dtypes compute in float64;
// - each argument's shape checked, ValueError naming it and its expected shape;
// - NumPy broadcasting of the leading (batch) dimensions of every argument: one
//   row shared by every sample is read with stride 0, or copied block by block into
//   a small buffer for kernels that read contiguous rows; a partly broadcast
//   argument is gathered block by block (never materialised whole), and so is one
//   that is itself a broadcast view (leading strides 0: its repeated rows read once);
// - huge angles (beyond vector_math::kReducibleLimit) replaced by their exact
//   remainder, in a copy of the block that holds them;
// - NaN rows: a sample with a NaN or an Inf in an argument marked nan_rows gets NaN
//   in its whole real output row (or in the matching part of it, by groups);
// - outputs allocated, or written into the `out=` arrays the caller passes (exact
//   dtype and shape, C-contiguous, writeable; an input that overlaps one is read
//   from a copy);
// - the GIL released over parallel_for for batches, threads split on fixed block
//   boundaries (the same bits for any thread count); a single sample runs inline;
// - a single sample (no leading dimensions) returns its status as a spotkin.Status.
//
// The engine (binder.cpp) is compiled once, for float and double; a binding adds
// only its kernel's two instantiations.
#pragma once

#include <pybind11/pybind11.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <initializer_list>
#include <stdexcept>
#include <vector>

namespace spotkin::bindings::binder {

namespace py = pybind11;

constexpr int kMaxArgs = 6;
constexpr int kMaxOuts = 6;
constexpr int kMaxDims = 3;    // trailing dimensions of one sample
constexpr int kMaxShapes = 3;  // accepted sample shapes of one argument (pose formats)

// The shape of one sample: () to (a, b, c).
struct Trailing {
  int ndim = 0;
  py::ssize_t dim[kMaxDims] = {};
  Trailing() = default;
  Trailing(std::initializer_list<py::ssize_t> dims) {
    for (py::ssize_t d : dims) dim[ndim++] = d;
  }
  py::ssize_t size() const {
    py::ssize_t n = 1;
    for (int k = 0; k < ndim; ++k) n *= dim[k];
    return n;
  }
};

// A batched argument (..., *shape).
struct Arg {
  const char* name = "";
  Trailing shapes[kMaxShapes];            // accepted sample shapes, tried in order (Block::shape says which)
  std::uint64_t angles[kMaxShapes] = {};  // per shape: bit j set when column j is an angle
  int n_shapes = 0;
  bool optional = false;   // None is accepted: the kernel gets a null pointer
  bool primary = true;     // takes part in the dtype choice (a parameter such as gravity does not)
  bool strided = false;    // the kernel reads rows with Block::stride (0: one row for every sample)
  int nan_groups = 0;      // 0: the kernel handles NaN itself; g: NaN rows by g equal parts (below)

  Arg() = default;
  Arg(const char* arg_name, Trailing shape, std::uint64_t angle_columns = 0) : name(arg_name) {
    or_shape(shape, angle_columns);
  }
  Arg& or_shape(Trailing shape, std::uint64_t angle_columns = 0) {
    if (n_shapes == kMaxShapes) throw std::length_error("binder::Arg: raise kMaxShapes");
    shapes[n_shapes] = shape;
    angles[n_shapes++] = angle_columns;
    return *this;
  }
  Arg& maybe_none() { return optional = true, *this; }
  Arg& parameter() { return primary = false, *this; }
  Arg& rows_strided() { return strided = true, *this; }
  // A NaN or Inf in part g of a sample's row (the row split in `groups` equal parts)
  // makes part g of every real output row NaN (the legs of a body: one leg's joints).
  Arg& nan_rows(int groups = 1) { return nan_groups = groups, *this; }
};

// Real: the working dtype (float32 or float64); Bool; Status: int8 spotkin.Status codes (a single
// sample's as a spotkin.Status); Code: int8 codes of another enum (an int8 array; a single sample's
// as the member of the enum registered under `codes`, when named); Index: int64.
enum class Kind : std::uint8_t { Real, Bool, Status, Code, Index };

PyObject** result_type(const char* name);  // a registered result type or enum's members, by name

struct Out {
  const char* name = "";
  Trailing shape;
  Kind kind = Kind::Real;
  PyObject** codes = nullptr;  // Code: the enum's members (a tuple, by value), registered by name
  bool scalar =
      false;  // Real of no sample shape: a single sample's as a NumPy scalar (a new array)
  Out() = default;
  Out(const char* out_name, Trailing out_shape, Kind out_kind = Kind::Real)
      : name(out_name), shape(out_shape), kind(out_kind) {}
  // A single sample's code as a member of the enum whose members (by value) are registered under
  // `name` (spotkin._core._register_result_type), an int8 array for a batch.
  Out& members(const char* enum_name) { return codes = result_type(enum_name), *this; }
  // A single sample's value as a NumPy scalar, as `array[()]` gives it (the caller's out= array
  // stays).
  Out& scalar_when_single() { return scalar = true, *this; }
};

// What a kernel sees: m samples, the first at index `first` of the batch. Argument k's
// row i starts at in[k] + i * stride[k] (stride 0: one row for all; in[k] null: an
// omitted optional argument); unless the argument is rows_strided, stride[k] is its
// row width. Output k's row i starts at real(k), flags(k), status(k) or index(k), plus i * width.
template <typename T>
struct Block {
  using Scalar = T;
  std::ptrdiff_t first = 0;
  std::ptrdiff_t m = 0;
  const T* in[kMaxArgs];
  std::ptrdiff_t stride[kMaxArgs];
  int shape[kMaxArgs];  // which of the argument's accepted shapes it has
  void* out[kMaxOuts];
  bool stream = false;  // the call's outputs are large (spotkin/stream.hpp): store them streamed where the kernel can
  // Every pointer null (a kernel may test an output past the op's, as the path sampler's optional
  // twist), the strides and shapes of n_args arguments zero: a single sample's call zeroes no more
  // (the whole arrays took a `rep stos`, about 10 ns a call).
  explicit Block(int n_args = kMaxArgs) {
    for (int k = 0; k < kMaxArgs; ++k) in[k] = nullptr;
    for (int k = 0; k < kMaxOuts; ++k) out[k] = nullptr;
    for (int k = 0; k < n_args; ++k) stride[k] = 0, shape[k] = 0;
  }
  T* real(int k) const { return static_cast<T*>(out[k]); }
  std::uint8_t* flags(int k) const { return static_cast<std::uint8_t*>(out[k]); }
  std::int8_t* status(int k) const { return static_cast<std::int8_t*>(out[k]); }  // Status or Code
  std::int64_t* index(int k) const { return static_cast<std::int64_t*>(out[k]); }
};

template <typename T>
using Kernel = void (*)(const void* context, const Block<T>& block);

struct Op {
  Arg args[kMaxArgs];
  Out outs[kMaxOuts];
  int n_args = 0;
  int n_outs = 0;
  double ns_per_sample = 50.0;  // rough single-thread cost, for the thread split
  Kernel<float> f32 = nullptr;
  Kernel<double> f64 = nullptr;
  bool float32 = true;  // false: computed in float64 whatever the dtype (float64_only)
  PyObject** named = nullptr;  // the registered result type (returns), or null: a plain tuple

  // kernel: a captureless generic lambda [](const void* context, const auto& block) {...}
  template <typename F>
  Op(std::initializer_list<Arg> arg_list, std::initializer_list<Out> out_list, double ns, F kernel)
      : ns_per_sample(ns), f32(kernel), f64(kernel) {
    if (arg_list.size() > std::size_t(kMaxArgs) || out_list.size() > std::size_t(kMaxOuts))
      throw std::length_error("binder::Op: raise kMaxArgs or kMaxOuts");  // a binding's mistake, never an input's
    for (const Arg& a : arg_list) args[n_args++] = a;
    for (const Out& o : out_list) outs[n_outs++] = o;
  }
  // An operation whose kernel has no float32 form: float32 input is computed, and answered, in float64.
  Op& float64_only() { return float32 = false, *this; }
  // Several outputs come back as the tuple subclass the façade registers under `name`
  // (spotkin._core._register_result_type: LegSolutions, ArmSolutions, ...).
  Op& returns(const char* name);
};

// The slot of the result type registered under `name` (null until registered; the address is stable).
PyObject** result_type(const char* name);
inline Op& Op::returns(const char* name) { return named = result_type(name), *this; }

// spotkin._core._register_result_type(name, type).
void bind_result_types(py::module_& m);

// The ops of a binding whose shapes depend on its model (a chain's dof, a body's legs), built
// once per distinct key instead of at every call (a single sample's call measured ~0.1 us of
// building). Used under the GIL; references stay valid (a deque). Past kMaxEntries distinct
// keys an op is built per call.
class OpCache {
 public:
  using Key = std::array<std::uint64_t, 3>;
  static constexpr std::size_t kMaxEntries = 256;
  template <typename Make, typename Use>
  decltype(auto) with(const Key& key, Make&& make, Use&& use) {
    for (std::size_t i = 0; i < keys_.size(); ++i)
      if (keys_[i] == key) return use(ops_[i]);
    if (keys_.size() == kMaxEntries) {
      const Op op = make();
      return use(op);
    }
    ops_.push_back(make());
    keys_.push_back(key);
    return use(ops_.back());
  }

 private:
  std::vector<Key> keys_;
  std::deque<Op> ops_;
};

// Runs op on the arguments (n_args handles) with `context` passed to the kernel.
// out: None, an array (one output) or a tuple / list with an array or None per output.
// Returns the output, or a tuple of the outputs.
py::object call(const Op& op, const void* context, std::initializer_list<py::handle> args, py::handle out);

// The context object of a kernel.
template <typename C>
const C& context(const void* c) {
  return *static_cast<const C*>(c);
}

}  // namespace spotkin::bindings::binder
