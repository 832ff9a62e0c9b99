// Bindings for spotkin::differential: batched dls, pinv, null-space projector,
// singular values, rank and manipulability. Leading dimensions of J and the
// vectors broadcast (NumPy rules) without copying the broadcast operands.
#include "spotkin/differential.hpp"

#include "spotkin/compatibility.hpp"

#include <cmath>
#include <string>

#include "bindings.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

namespace diff = spotkin::differential;

// Maps a flat sample index of the broadcast batch to a sample of one operand.
class SampleIndex {
 public:
  SampleIndex(const Shape& leading, const Shape& batch) : batch_(batch), identity_(leading == batch) {
    strides_.assign(batch.size(), 0);
    py::ssize_t stride = 1;
    const std::size_t pad = batch.size() - leading.size();
    for (std::size_t k = leading.size(); k-- > 0;) {
      if (leading[k] != 1) strides_[k + pad] = stride;
      stride *= leading[k];
    }
  }
  py::ssize_t operator()(py::ssize_t i) const noexcept {
    if (identity_) return i;
    py::ssize_t offset = 0;
    for (std::size_t k = batch_.size(); k-- > 0;) {
      offset += (i % batch_[k]) * strides_[k];
      i /= batch_[k];
    }
    return offset;
  }

 private:
  Shape batch_;
  std::vector<py::ssize_t> strides_;
  bool identity_;
};

Shape broadcast(const Shape& a, const char* a_name, const Shape& b, const char* b_name) {
  Shape out(std::max(a.size(), b.size()), 1);
  for (std::size_t k = 0; k < out.size(); ++k) {
    const py::ssize_t da = k < out.size() - a.size() ? 1 : a[k - (out.size() - a.size())];
    const py::ssize_t db = k < out.size() - b.size() ? 1 : b[k - (out.size() - b.size())];
    if (da != db && da != 1 && db != 1)
      throw py::value_error(std::string("the leading dimensions of ") + a_name + " " + format_shape(a) + " and " +
                            b_name + " " + format_shape(b) + " do not broadcast");
    out[k] = da == 1 ? db : da;
  }
  return out;
}

struct JacobianArg {
  py::array arr;
  Shape leading;
  int m, n;
};

JacobianArg jacobian_arg(py::handle obj) {
  py::array arr = as_real_array(obj, "J");
  const Shape shape(arr.shape(), arr.shape() + arr.ndim());
  if (arr.ndim() < 2 || shape[shape.size() - 2] < 1 || shape.back() < 1 || shape[shape.size() - 2] > diff::kMaxDim ||
      shape.back() > diff::kMaxDim)
    throw py::value_error("J must have shape (..., m, n) with 1 <= m, n <= " + std::to_string(diff::kMaxDim) +
                          ", got " + format_shape(shape));
  const int m = static_cast<int>(shape[shape.size() - 2]), n = static_cast<int>(shape.back());
  return {arr, Shape(shape.begin(), shape.end() - 2), m, n};
}

// Rough single-thread cost per sample, ns, for the chunking thresholds.
std::ptrdiff_t min_per_thread(int m, int n, bool svd) {
  const double cubic = double(m) * n * std::min(m, n);
  // at least 4: parallel_for's chunk (min_per_thread / 4, rounded up to a block) must not be 0
  return std::max<std::ptrdiff_t>(4, min_chunk((svd ? 25.0 : 1.0) * cubic + 20.0));
}

py::object dls(py::handle J_obj, py::handle dx_obj, double damping, py::handle z_obj) {
  if (!(damping >= 0.0) || !std::isfinite(damping))
    throw py::value_error("damping must be finite and >= 0, got " + std::to_string(damping));
  const JacobianArg J = jacobian_arg(J_obj);
  py::array dx = as_real_array(dx_obj, "dx");
  const Shape dx_lead = leading_shape(dx, "dx", {J.m});
  const bool has_z = !z_obj.is_none();
  py::array z = has_z ? as_real_array(z_obj, "nullspace") : py::array();
  const Shape z_lead = has_z ? leading_shape(z, "nullspace", {J.n}) : Shape{};
  Shape batch = broadcast(J.leading, "J", dx_lead, "dx");
  if (has_z) batch = broadcast(batch, "J and dx", z_lead, "nullspace");
  const bool f32 = is_float32(J.arr) && is_float32(dx) && (!has_z || is_float32(z));
  auto run = [&](auto tag) -> py::object {
    using T = decltype(tag);
    auto Jc = contiguous<T>(J.arr);
    auto dxc = contiguous<T>(dx);
    py::array_t<T, py::array::c_style> zc;
    if (has_z) zc = contiguous<T>(z);
    auto out = new_array<T>(batch, {J.n});
    const SampleIndex j_index(J.leading, batch), dx_index(dx_lead, batch), z_index(z_lead, batch);
    const T* jd = Jc.data();
    const T* dd = dxc.data();
    const T* zd = has_z ? zc.data() : nullptr;
    T* od = out.mutable_data();
    const int m = J.m, n = J.n;
    const T lambda2 = T(damping * damping);
    {
      ReleaseGilFor release(count(batch));
      // Other shapes, a null-space task or no damping: one sample at a time.
      auto solve = [&] {
        parallel_for(count(batch), min_per_thread(m, n, has_z || damping == 0.0), [&](std::ptrdiff_t b, std::ptrdiff_t e) {
          for (std::ptrdiff_t i = b; i < e; ++i)
            diff::dls<T>(jd + j_index(i) * m * n, dd + dx_index(i) * m, zd ? zd + z_index(i) * n : nullptr, lambda2,
                         m, n, od + i * n);
        });
      };
      // The fixed shapes without a null-space task: blocks of samples, vectorised.
      auto solve_blocks = [&](auto M, auto N) {
        constexpr int Mv = decltype(M)::value, Nv = decltype(N)::value, B = diff::kDlsBlock;
        parallel_for(count(batch), min_per_thread(m, n, false), [&](std::ptrdiff_t b, std::ptrdiff_t e) {
          T Js[Mv * Nv][B], dxs[Mv][B], dqs[Nv][B];
          bool finite[B];
          for (std::ptrdiff_t b0 = b; b0 < e; b0 += B) {
            const int k = static_cast<int>(std::min<std::ptrdiff_t>(B, e - b0));
            for (int i = 0; i < B; ++i) {
              const T* Ji = i < k ? jd + j_index(b0 + i) * Mv * Nv : nullptr;
              const T* di = i < k ? dd + dx_index(b0 + i) * Mv : nullptr;
              finite[i] = i < k && diff::all_finite(Ji, Mv * Nv) && diff::all_finite(di, Mv);
              for (int r = 0; r < Mv * Nv; ++r) Js[r][i] = finite[i] ? Ji[r] : T(0);
              for (int r = 0; r < Mv; ++r) dxs[r][i] = finite[i] ? di[r] : T(0);
            }
            diff::dls_block<T, Mv, Nv>(Js, dxs, lambda2, dqs);
            for (int i = 0; i < k; ++i) {
              T* dq = od + (b0 + i) * Nv;
              bool ok = finite[i];
              for (int c = 0; c < Nv; ++c) ok = ok && std::isfinite(dqs[c][i]), dq[c] = finite[i] ? dqs[c][i] : quiet_nan<T>();
              // a damping below the rounding of J J^T, or no positive pivot: the limit, J^+ dx
              const T* Ji = jd + j_index(b0 + i) * Mv * Nv;
              if (finite[i] && (!ok || diff::damping_below_rounding(Ji, Mv, Nv, lambda2)))
                diff::pinv_solve<T>(Ji, dd + dx_index(b0 + i) * Mv, nullptr, Mv, Nv, dq);
            }
          }
        });
      };
      if (has_z || damping == 0.0)  // decomposition-bound: no fixed-size path
        solve();
      else if (m == 6 && n == 6)
        solve_blocks(std::integral_constant<int, 6>{}, std::integral_constant<int, 6>{});
      else if (m == 3 && n == 3)
        solve_blocks(std::integral_constant<int, 3>{}, std::integral_constant<int, 3>{});
      else if (m == 12 && n == 18)
        solve_blocks(std::integral_constant<int, 12>{}, std::integral_constant<int, 18>{});
      else
        solve();
    }
    return std::move(out);
  };
  return f32 ? run(float{}) : run(double{});
}

// Compatibility of dx with J, per broadcast sample: (compatible (...) bool, residual (...)).
py::tuple compatible(py::handle J_obj, py::handle dx_obj, double tol) {
  if (std::isnan(tol) || std::isinf(tol)) throw py::value_error("tol must be finite");
  const JacobianArg J = jacobian_arg(J_obj);
  py::array dx = as_real_array(dx_obj, "dx");
  const Shape dx_lead = leading_shape(dx, "dx", {J.m});
  const Shape batch = broadcast(J.leading, "J", dx_lead, "dx");
  const bool f32 = is_float32(J.arr) && is_float32(dx);
  auto run = [&](auto tag) -> py::tuple {
    using T = decltype(tag);
    auto Jc = contiguous<T>(J.arr);
    auto dxc = contiguous<T>(dx);
    auto residual = new_array<T>(batch, {});
    py::array_t<bool> ok(batch);
    const SampleIndex j_index(J.leading, batch), dx_index(dx_lead, batch);
    const T* jd = Jc.data();
    const T* dd = dxc.data();
    T* rd = residual.mutable_data();
    bool* od = ok.mutable_data();
    const int m = J.m, n = J.n;
    {
      ReleaseGilFor release(count(batch));
      parallel_for(count(batch), min_per_thread(m, n, true), [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        for (std::ptrdiff_t i = b; i < e; ++i) {
          const auto c = diff::compatibility<T>(jd + j_index(i) * m * n, dd + dx_index(i) * m, m, n, T(tol));
          rd[i] = c.residual;
          od[i] = c.compatible;
        }
      });
    }
    return py::make_tuple(std::move(ok), std::move(residual));
  };
  return f32 ? run(float{}) : run(double{});
}

// A per-matrix operation J (..., m, n) -> (..., *trailing) of dtype Out (T when void).
template <typename Out, typename Kernel>
py::object map_matrices(py::handle J_obj, bool svd, Kernel&& kernel_for_shape) {
  const JacobianArg J = jacobian_arg(J_obj);
  return dispatch_real(J.arr, "J", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    using O = std::conditional_t<std::is_void_v<Out>, T, Out>;
    auto Jc = contiguous<T>(arr);
    const int m = J.m, n = J.n;
    const Shape trailing = kernel_for_shape.trailing(m, n);
    py::ssize_t width = 1;
    for (auto d : trailing) width *= d;
    auto out = new_array<O>(J.leading, trailing);
    const T* jd = Jc.data();
    O* od = out.mutable_data();
    {
      ReleaseGilFor release(count(J.leading));
      parallel_for(count(J.leading), min_per_thread(m, n, svd), [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        for (std::ptrdiff_t i = b; i < e; ++i) kernel_for_shape.template run<T>(jd + i * m * n, m, n, od + i * width);
      });
    }
    return std::move(out);
  });
}

struct PinvOp {
  Shape trailing(int m, int n) const { return {n, m}; }
  template <typename T>
  void run(const T* J, int m, int n, T* out) const noexcept { diff::pinv<T>(J, m, n, out); }
};
struct ProjectorOp {
  Shape trailing(int, int n) const { return {n, n}; }
  template <typename T>
  void run(const T* J, int m, int n, T* out) const noexcept { diff::nullspace_projector<T>(J, m, n, out); }
};
struct SingularValuesOp {
  Shape trailing(int m, int n) const { return {std::min(m, n)}; }
  template <typename T>
  void run(const T* J, int m, int n, T* out) const noexcept { diff::singular_values<T>(J, m, n, out); }
};
struct ManipulabilityOp {
  Shape trailing(int, int) const { return {}; }
  template <typename T>
  void run(const T* J, int m, int n, T* out) const noexcept { *out = diff::manipulability<T>(J, m, n); }
};
struct RankOp {
  double tol;
  Shape trailing(int, int) const { return {}; }
  template <typename T>
  void run(const T* J, int m, int n, std::int64_t* out) const noexcept {
    *out = diff::rank<T>(J, m, n, T(tol));
  }
};

}  // namespace

void bind_differential(py::module_& m) {
  m.def("dls", &dls, py::arg("J"), py::arg("dx"), py::arg("damping"), py::arg("nullspace") = py::none());
  m.def("compatible", &compatible, py::arg("J"), py::arg("dx"), py::arg("tol") = -1.0);
  m.def("pinv", [](py::handle J) { return map_matrices<void>(J, false, PinvOp{}); }, py::arg("J"));
  m.def("nullspace_projector", [](py::handle J) { return map_matrices<void>(J, false, ProjectorOp{}); },
        py::arg("J"));
  m.def("singular_values", [](py::handle J) { return map_matrices<void>(J, true, SingularValuesOp{}); },
        py::arg("J"));
  m.def("manipulability", [](py::handle J) { return map_matrices<void>(J, true, ManipulabilityOp{}); },
        py::arg("J"));
  m.def(
      "rank",
      [](py::handle J, double tol) {
        if (std::isnan(tol) || std::isinf(tol)) throw py::value_error("tol must be finite");
        return map_matrices<std::int64_t>(J, true, RankOp{tol});
      },
      py::arg("J"), py::arg("tol") = -1.0);
}

}  // namespace spotkin::bindings
