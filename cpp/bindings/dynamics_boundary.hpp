// What the dynamics bindings (dynamics.cpp, dynamics_floating.cpp) share: the model of the
// active instruction-set level, inertials, the mass matrix's layouts, and the fixed-base chain
// model. Their batches go through the binder (binder.hpp).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "binder.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/dynamics/floating.hpp"
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
SPOTKIN_INLINE void with_model(const D& d, F&& f, std::ptrdiff_t samples = PTRDIFF_MAX) {
  switch (active_isa()) {
    case Isa::Avx512:
      // A few samples (one sample of a control loop) run the AVX2 model, whose one vector holds
      // them: its clone fuses the same multiply-adds, so the bits are the AVX-512 model's, and a
      // lone sample moves a quarter of the scratch (5-15 % faster from Python).
      if (samples <= (std::is_same_v<T, float> ? dynamics::kMidLanes32 : dynamics::kMidLanes64))
        return f(d.mid(T{}));
      return f(d.get(T{}));
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

// The mass matrix's layout argument ("full", "lower" or "packed") and its output's trailing shape.
inline dynamics::SymmetricLayout symmetric_layout(py::handle layout) {
  // the default, as the façade passes it: the interned "full" (a pointer compare, no string made)
  static PyObject* const full = PyUnicode_InternFromString("full");
  if (layout.ptr() == full) return dynamics::SymmetricLayout::Full;
  if (!py::isinstance<py::str>(layout))
    throw py::type_error("layout must be a str, 'full', 'lower' or 'packed', got " +
                         std::string(py::str(py::type::of(layout).attr("__name__"))));
  const std::string name = layout.cast<std::string>();
  if (name == "full") return dynamics::SymmetricLayout::Full;
  if (name == "lower") return dynamics::SymmetricLayout::Lower;
  if (name == "packed") return dynamics::SymmetricLayout::Packed;
  throw py::value_error("layout must be 'full', 'lower' or 'packed', got '" + name + "'");
}
inline binder::Trailing symmetric_shape(py::ssize_t n, dynamics::SymmetricLayout layout) {
  if (layout == dynamics::SymmetricLayout::Packed) return {n * (n + 1) / 2};
  return {n, n};
}

// ---------------------------------------------------------------- the binder's side

// Gravity (3,): a parameter (it does not decide the dtype), read with a row stride (0: shared).
inline binder::Arg gravity_arg() { return binder::Arg("gravity", {3}).parameter().rows_strided(); }

// Argument k of a block as the dynamics kernels read it.
template <typename T>
Rows<T> rows(const binder::Block<T>& b, int k) {
  return {b.in[k], b.stride[k]};
}

// Calls f(model) with the model (of Dynamics, the kernel's context) of the active level, in the
// block's precision.
template <typename Dynamics, typename B, typename F>
void on_model(const void* context, const B& b, F&& f) {
  with_model<typename B::Scalar>(binder::context<Dynamics>(context), f, b.m);
}

// The mass matrix's context: the model and the output layout.
template <typename Dynamics>
struct MassMatrix {
  const Dynamics& d;
  dynamics::SymmetricLayout layout;
};

// ---------------------------------------------------------------- models at every lane width

using dynamics::FloatingModel;

// A model in each precision at each level's lane width (with_model picks the active level's).
template <template <typename, int> class Model>
struct LaneModels {
  Model<double, kLanes64> f64;
  Model<float, kLanes32> f32;
  Model<double, kMidLanes64> f64_mid;
  Model<float, kMidLanes32> f32_mid;
  Model<double, kSmallLanes64> f64_small;
  Model<float, kSmallLanes32> f32_small;
  const Model<double, kLanes64>& get(double) const { return f64; }
  const Model<float, kLanes32>& get(float) const { return f32; }
  const Model<double, kMidLanes64>& mid(double) const { return f64_mid; }
  const Model<float, kMidLanes32>& mid(float) const { return f32_mid; }
  const Model<double, kSmallLanes64>& small(double) const { return f64_small; }
  const Model<float, kSmallLanes32>& small(float) const { return f32_small; }
};

// A fixed-base chain.
struct ChainDynamics : LaneModels<ChainModel> {
  int dof() const { return f64.dof(); }
};

// A floating base carrying chains.
struct FloatingDynamics : LaneModels<FloatingModel> {
  std::uint64_t angles = 0;  // the q columns that are joint angles (7 + each revolute joint's index)
};

void bind_floating_dynamics(py::module_& m);  // dynamics_floating.cpp

}  // namespace spotkin::bindings

#pragma GCC visibility pop
