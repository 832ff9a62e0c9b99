// Bindings for spotkin::differential: batched dls, pinv, null-space projector,
// singular values, rank and manipulability, through the binder: the leading dimensions of J and
// the vectors broadcast (NumPy rules).
#include "spotkin/differential.hpp"

#include "spotkin/compatibility.hpp"

#include <cmath>
#include <algorithm>
#include <string>
#include <type_traits>

#include "bindings.hpp"
#include "binder.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

namespace diff = spotkin::differential;

// Maps a flat sample index of the broadcast batch to a sample of one operand.
// J (..., m, n): m and n read from its shape, checked against the fixed bounds.
struct JacobianShape {
  int m, n;
};

JacobianShape jacobian_shape(py::handle obj) {
  py::array arr = as_real_array(obj, "J");
  const Shape shape(arr.shape(), arr.shape() + arr.ndim());
  if (arr.ndim() < 2 || shape[shape.size() - 2] < 1 || shape.back() < 1 || shape[shape.size() - 2] > diff::kMaxDim ||
      shape.back() > diff::kMaxDim)
    throw py::value_error("J must have shape (..., m, n) with 1 <= m, n <= " + std::to_string(diff::kMaxDim) +
                          ", got " + format_shape(shape));
  return {static_cast<int>(shape[shape.size() - 2]), static_cast<int>(shape.back())};
}

// Rough cost of one m x n problem, for the thread split.
double ns_per_matrix(int m, int n, bool svd) { return (svd ? 25.0 : 1.0) * double(m) * n * std::min(m, n) + 20.0; }

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

struct Damped {
  int m, n;
  double lambda2;
};

py::object dls(py::handle J, py::handle dx, double damping, py::handle nullspace, py::handle out) {
  if (!(damping >= 0.0) || !std::isfinite(damping))
    throw py::value_error("damping must be finite and >= 0, got " + std::to_string(damping));
  const auto [m, n] = jacobian_shape(J);
  const bool decomposition = !nullspace.is_none() || damping == 0.0;  // no fixed-size path then
  const Op op({Arg("J", {m, n}), Arg("dx", {m}), Arg("nullspace", {n}).maybe_none()}, {Out("dq", {n})},
              ns_per_matrix(m, n, decomposition), [](const void* c, const auto& b) {
                using T = typename std::decay_t<decltype(b)>::Scalar;
                const Damped& d = binder::context<Damped>(c);
                const T lambda2 = T(d.lambda2);
                if (!b.in[2] && d.lambda2 > 0.0) {
                  if (d.m == 6 && d.n == 6) return diff::dls_rows<T, 6, 6>(b.in[0], b.in[1], lambda2, b.real(0), b.m);
                  if (d.m == 3 && d.n == 3) return diff::dls_rows<T, 3, 3>(b.in[0], b.in[1], lambda2, b.real(0), b.m);
                  if (d.m == 12 && d.n == 18) return diff::dls_rows<T, 12, 18>(b.in[0], b.in[1], lambda2, b.real(0), b.m);
                }
                for (std::ptrdiff_t i = 0; i < b.m; ++i)
                  diff::dls<T>(b.in[0] + i * d.m * d.n, b.in[1] + i * d.m, b.in[2] ? b.in[2] + i * d.n : nullptr,
                               lambda2, d.m, d.n, b.real(0) + i * d.n);
              });
  const Damped context{m, n, damping * damping};
  return binder::call(op, &context, {J, dx, nullspace}, out);
}

// Compatibility of dx with J, per broadcast sample: (compatible (...) bool, residual (...)).
struct Tolerance {
  int m, n;
  double tol;
};

py::object compatible(py::handle J, py::handle dx, double tol) {
  if (std::isnan(tol) || std::isinf(tol)) throw py::value_error("tol must be finite");
  const auto [m, n] = jacobian_shape(J);
  const Op op({Arg("J", {m, n}), Arg("dx", {m})}, {Out("compatible", {}, Kind::Bool), Out("residual", {})},
              ns_per_matrix(m, n, true), [](const void* c, const auto& b) {
                using T = typename std::decay_t<decltype(b)>::Scalar;
                const Tolerance& t = binder::context<Tolerance>(c);
                for (std::ptrdiff_t i = 0; i < b.m; ++i) {
                  const auto r = diff::compatibility<T>(b.in[0] + i * t.m * t.n, b.in[1] + i * t.m, t.m, t.n, T(t.tol));
                  b.real(1)[i] = r.residual;
                  b.flags(0)[i] = r.compatible;
                }
              });
  const Tolerance context{m, n, tol};
  return binder::call(op, &context, {J, dx}, py::none());
}

// A per-matrix operation J (..., m, n) -> (..., *trailing), of kind `kind` (Real: J's dtype).
template <typename Operation>
py::object map_matrices(py::handle J, bool svd, Operation operation) {
  const auto [m, n] = jacobian_shape(J);
  const Shape trailing = operation.trailing(m, n);
  binder::Trailing shape;
  for (py::ssize_t d : trailing) shape.dim[shape.ndim++] = d;
  struct Context {
    int m, n;
    Operation operation;
  };
  const Op op({Arg("J", {m, n})}, {Out("result", shape, Operation::kKind)}, ns_per_matrix(m, n, svd),
              [](const void* c, const auto& b) {
                using T = typename std::decay_t<decltype(b)>::Scalar;
                const Context& k = binder::context<Context>(c);
                const std::ptrdiff_t width = k.operation.width(k.m, k.n);
                for (std::ptrdiff_t i = 0; i < b.m; ++i)
                  k.operation.template run<T>(b.in[0] + i * k.m * k.n, k.m, k.n, b, i * width);
              });
  const Context context{m, n, operation};
  return binder::call(op, &context, {J}, py::none());
}

// Each operation: its output's sample shape and kind, and the computation of one matrix into the
// output at element offset `at`.
struct PinvOp {
  static constexpr Kind kKind = Kind::Real;
  Shape trailing(int m, int n) const { return {n, m}; }
  std::ptrdiff_t width(int m, int n) const { return std::ptrdiff_t(m) * n; }
  template <typename T, typename B>
  void run(const T* J, int m, int n, const B& b, std::ptrdiff_t at) const noexcept {
    diff::pinv<T>(J, m, n, b.real(0) + at);
  }
};
struct ProjectorOp {
  static constexpr Kind kKind = Kind::Real;
  Shape trailing(int, int n) const { return {n, n}; }
  std::ptrdiff_t width(int, int n) const { return std::ptrdiff_t(n) * n; }
  template <typename T, typename B>
  void run(const T* J, int m, int n, const B& b, std::ptrdiff_t at) const noexcept {
    diff::nullspace_projector<T>(J, m, n, b.real(0) + at);
  }
};
struct SingularValuesOp {
  static constexpr Kind kKind = Kind::Real;
  Shape trailing(int m, int n) const { return {std::min(m, n)}; }
  std::ptrdiff_t width(int m, int n) const { return std::min(m, n); }
  template <typename T, typename B>
  void run(const T* J, int m, int n, const B& b, std::ptrdiff_t at) const noexcept {
    diff::singular_values<T>(J, m, n, b.real(0) + at);
  }
};
struct ManipulabilityOp {
  static constexpr Kind kKind = Kind::Real;
  Shape trailing(int, int) const { return {}; }
  std::ptrdiff_t width(int, int) const { return 1; }
  template <typename T, typename B>
  void run(const T* J, int m, int n, const B& b, std::ptrdiff_t at) const noexcept {
    b.real(0)[at] = diff::manipulability<T>(J, m, n);
  }
};
struct RankOp {
  static constexpr Kind kKind = Kind::Index;
  double tol;
  Shape trailing(int, int) const { return {}; }
  std::ptrdiff_t width(int, int) const { return 1; }
  template <typename T, typename B>
  void run(const T* J, int m, int n, const B& b, std::ptrdiff_t at) const noexcept {
    b.index(0)[at] = diff::rank<T>(J, m, n, T(tol));
  }
};

}  // namespace

void bind_differential(py::module_& m) {
  m.def("dls", &dls, py::arg("J"), py::arg("dx"), py::arg("damping"), py::arg("nullspace") = py::none(),
        py::arg("out") = py::none());
  m.def("compatible", &compatible, py::arg("J"), py::arg("dx"), py::arg("tol") = -1.0);
  m.def("pinv", [](py::handle J) { return map_matrices(J, false, PinvOp{}); }, py::arg("J"));
  m.def("nullspace_projector", [](py::handle J) { return map_matrices(J, false, ProjectorOp{}); },
        py::arg("J"));
  m.def("singular_values", [](py::handle J) { return map_matrices(J, true, SingularValuesOp{}); },
        py::arg("J"));
  m.def("manipulability", [](py::handle J) { return map_matrices(J, true, ManipulabilityOp{}); },
        py::arg("J"));
  m.def(
      "rank",
      [](py::handle J, double tol) {
        if (std::isnan(tol) || std::isinf(tol)) throw py::value_error("tol must be finite");
        return map_matrices(J, true, RankOp{tol});
      },
      py::arg("J"), py::arg("tol") = -1.0);
}

}  // namespace spotkin::bindings
