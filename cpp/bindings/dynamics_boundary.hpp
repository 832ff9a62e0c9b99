// The numpy boundary of the dynamics bindings (dynamics.cpp, dynamics_floating.cpp):
// inertials, NumPy broadcasting of several batch arguments, the call with the GIL
// released over parallel_for, and the fixed-base chain model shared by both.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "numpy_boundary.hpp"
#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/dynamics/model.hpp"
#include "spotkin/parallel.hpp"
#include "spotkin/stream.hpp"

// Hidden like pybind11's own types, which these helpers hold.
#pragma GCC visibility push(hidden)

namespace spotkin::bindings {

using dynamics::ChainModel;
using dynamics::LinkInertial;
using dynamics::Rows;

using dynamics::kLanes32;
using dynamics::kLanes64;
using dynamics::kMidLanes32;
using dynamics::kMidLanes64;
using dynamics::kSmallLanes32;
using dynamics::kSmallLanes64;

// Calls f(model) with the model of `d` in precision T whose packs fill one register of the
// active instruction-set level: 64 bytes at AVX-512, 32 at AVX2, 16 at the baseline (SSE2,
// NEON). The choice depends on the level only, never on the batch: a batch shorter than
// the lanes runs one partial block, and a sample's bits are the same alone, in any batch,
// and in any thread's chunk.
template <typename T, typename D, typename F>
SPOTKIN_INLINE void with_model(const D& d, F&& f) {
  switch (active_isa()) {
    case Isa::Avx512: return f(d.get(T{}));
    case Isa::Avx2: return f(d.mid(T{}));
    default: return f(d.small(T{}));
  }
}


// ---------------------------------------------------------------- inertials

inline std::vector<LinkInertial> inertials_from(py::handle mass_obj, py::handle com_obj, py::handle inertia_obj, int n,
                                         const char* prefix = "") {
  const std::string p(prefix);
  auto mass_arr = as_real_array(mass_obj, (p + "mass").c_str());
  auto com_arr = as_real_array(com_obj, (p + "com").c_str());
  auto inertia_arr = as_real_array(inertia_obj, (p + "inertia").c_str());
  auto shape_of = [](const py::array& a) { return Shape(a.shape(), a.shape() + a.ndim()); };
  if (shape_of(mass_arr) != Shape{n})
    throw py::value_error(p + "mass must have shape (" + std::to_string(n) + ",), got " + format_shape(shape_of(mass_arr)));
  if (shape_of(com_arr) != Shape{n, 3})
    throw py::value_error(p + "com must have shape (" + std::to_string(n) + ", 3), got " + format_shape(shape_of(com_arr)));
  if (shape_of(inertia_arr) != Shape{n, 3, 3})
    throw py::value_error(p + "inertia must have shape (" + std::to_string(n) + ", 3, 3), got " +
                          format_shape(shape_of(inertia_arr)));
  auto mass = contiguous<double>(mass_arr);
  auto com = contiguous<double>(com_arr);
  auto inertia = contiguous<double>(inertia_arr);
  std::vector<LinkInertial> links(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    LinkInertial& l = links[static_cast<std::size_t>(j)];
    l.mass = mass.data()[j];
    for (int r = 0; r < 3; ++r) {
      l.com[r] = com.data()[3 * j + r];
      for (int c = 0; c < 3; ++c) l.inertia(r, c) = inertia.data()[9 * j + 3 * r + c];
    }
  }
  return links;
}

// ---------------------------------------------------------------- broadcasting

struct BatchArg {
  py::handle obj;
  const char* name;
  py::ssize_t width;
  bool primary = true;        // a parameter (gravity) does not decide the working dtype
  std::uint64_t angles = 0;   // columns that are angles: reduced exactly when huge (reduce_seed_angles)
};

// NumPy's broadcast of the leading shapes; ValueError naming the arguments.
inline Shape broadcast_leading(const std::vector<Shape>& shapes, const std::vector<BatchArg>& args) {
  std::size_t nd = 0;
  for (const auto& s : shapes) nd = std::max(nd, s.size());
  Shape out(nd, 1);
  for (std::size_t a = 0; a < shapes.size(); ++a) {
    const Shape& s = shapes[a];
    for (std::size_t k = 0; k < s.size(); ++k) {
      py::ssize_t& o = out[nd - s.size() + k];
      if (s[k] == o || s[k] == 1) continue;
      if (o == 1) {
        o = s[k];
        continue;
      }
      std::string msg = "the leading (batch) dimensions of ";
      for (std::size_t b = 0; b < args.size(); ++b) msg += (b ? ", " : "") + std::string(args[b].name);
      msg += " do not broadcast together: ";
      for (std::size_t b = 0; b < shapes.size(); ++b)
        msg += (b ? ", " : "") + std::string(args[b].name) + " " + format_shape(shapes[b]);
      throw py::value_error(msg);
    }
  }
  return out;
}

// The working arrays of a call: every argument C-contiguous in T, with a row
// stride (0 for one row shared by every sample).
template <typename T>
struct Prepared {
  Shape leading;
  py::ssize_t count = 0;
  std::vector<py::array_t<T, py::array::c_style>> arrays;
  std::vector<Rows<T>> rows;
};

template <typename T>
Prepared<T> prepare(const std::vector<py::array>& arrs, const std::vector<BatchArg>& args) {
  std::vector<Shape> shapes;
  for (std::size_t a = 0; a < args.size(); ++a) shapes.push_back(leading_shape(arrs[a], args[a].name, {args[a].width}));
  Prepared<T> p;
  p.leading = broadcast_leading(shapes, args);
  p.count = count(p.leading);
  for (std::size_t a = 0; a < args.size(); ++a) {
    py::array arr = arrs[a];
    py::ssize_t stride = args[a].width;
    if (count(shapes[a]) == 1 && p.count != 1) {
      stride = 0;
    } else if (shapes[a] != p.leading) {
      Shape full = p.leading;
      full.push_back(args[a].width);
      py::tuple shape(full.size());
      for (std::size_t k = 0; k < full.size(); ++k) shape[k] = py::int_(full[k]);
      arr = py::module_::import("numpy").attr("broadcast_to")(arr, shape);
    }
    auto working = contiguous<T>(arr);
    // a joint angle beyond kReducibleLimit gives the result of its exact remainder, as in the kinematics
    if (args[a].angles) working = reduce_seed_angles(std::move(working), args[a].width, args[a].angles);
    p.arrays.push_back(std::move(working));
    p.rows.push_back(Rows<T>{p.arrays.back().data(), stride});
  }
  return p;
}

// Converts every argument; float32 when all the primary ones are.
template <typename F>
py::object dispatch_args(const std::vector<BatchArg>& args, F&& f) {
  std::vector<py::array> arrs;
  bool single = true;
  for (const auto& a : args) {
    arrs.push_back(as_real_array(a.obj, a.name));
    if (a.primary) single = single && is_float32(arrs.back());
  }
  if (single) return f(float{}, arrs);
  return f(double{}, arrs);
}

// Runs kernel(rows, out, begin, end, stream) over the broadcast batch with the GIL released;
// stream: the whole output is large enough for streamed stores (spotkin/stream.hpp).
template <typename Kernel>
py::object run_batch(const std::vector<BatchArg>& args, const Shape& trailing, double ns_per_sample,
                     Kernel&& kernel) {
  return dispatch_args(args, [&](auto tag, const std::vector<py::array>& arrs) -> py::object {
    using T = decltype(tag);
    Prepared<T> p = prepare<T>(arrs, args);
    auto out = new_array<T>(p.leading, trailing);
    T* od = out.mutable_data();
    const std::vector<Rows<T>>& rows = p.rows;
    const bool stream = std::size_t(out.size()) * sizeof(T) >= kStreamBytes;
    {
      ReleaseGilFor release(p.count);
      parallel_for(p.count, min_chunk(ns_per_sample), [&](std::ptrdiff_t b, std::ptrdiff_t e) { kernel(rows, od, b, e, stream); });
    }
    return std::move(out);
  });
}

// The mass matrix's layout argument ("full", "lower" or "packed") and its output's trailing shape.
inline dynamics::SymmetricLayout symmetric_layout(py::handle layout) {
  if (!py::isinstance<py::str>(layout))
    throw py::type_error("layout must be a str, 'full', 'lower' or 'packed', got " +
                         std::string(py::str(py::type::of(layout).attr("__name__"))));
  const std::string name = layout.cast<std::string>();
  if (name == "full") return dynamics::SymmetricLayout::Full;
  if (name == "lower") return dynamics::SymmetricLayout::Lower;
  if (name == "packed") return dynamics::SymmetricLayout::Packed;
  throw py::value_error("layout must be 'full', 'lower' or 'packed', got '" + name + "'");
}
inline Shape symmetric_shape(py::ssize_t n, dynamics::SymmetricLayout layout) {
  if (layout == dynamics::SymmetricLayout::Packed) return {n * (n + 1) / 2};
  return {n, n};
}

// ---------------------------------------------------------------- fixed base

struct ChainDynamics {
  ChainModel<double, kLanes64> f64;
  ChainModel<float, kLanes32> f32;
  ChainModel<double, kMidLanes64> f64_mid;
  ChainModel<float, kMidLanes32> f32_mid;
  ChainModel<double, kSmallLanes64> f64_small;
  ChainModel<float, kSmallLanes32> f32_small;
  const ChainModel<double, kLanes64>& get(double) const { return f64; }
  const ChainModel<float, kLanes32>& get(float) const { return f32; }
  const ChainModel<double, kMidLanes64>& mid(double) const { return f64_mid; }
  const ChainModel<float, kMidLanes32>& mid(float) const { return f32_mid; }
  const ChainModel<double, kSmallLanes64>& small(double) const { return f64_small; }
  const ChainModel<float, kSmallLanes32>& small(float) const { return f32_small; }
  int dof() const { return f64.dof(); }
};

void bind_floating_dynamics(py::module_& m);  // dynamics_floating.cpp

}  // namespace spotkin::bindings

#pragma GCC visibility pop
