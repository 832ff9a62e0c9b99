// Bindings for spotkin::Chain: construction from DH tables, batched FK,
// frames and Jacobians.
#include "spotkin/chain.hpp"

#include "bindings.hpp"
#include "dispatch.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

// The chain in both working precisions.
struct ChainPair {
  Chain<double> f64;
  Chain<float> f32;
  Convention convention;

  const Chain<double>& get(double) const { return f64; }
  const Chain<float>& get(float) const { return f32; }
};

ChainPair make_chain(Convention convention, py::handle rows_obj, py::handle base_obj,
                     py::handle tool_obj) {
  py::array rows_arr = as_real_array(rows_obj, "rows");
  if (rows_arr.ndim() != 2 || rows_arr.shape(1) != 5)
    throw py::value_error("rows must have shape (n, 5), got " +
                          format_shape(Shape(rows_arr.shape(), rows_arr.shape() + rows_arr.ndim())));
  auto rows = contiguous<double>(rows_arr);
  const Rigid<double> base = base_obj.is_none() ? Rigid<double>{} : rigid_from<Rigid<double>>(base_obj, "base");
  const Rigid<double> tool = tool_obj.is_none() ? Rigid<double>{} : rigid_from<Rigid<double>>(tool_obj, "tool");
  auto chain = Chain<double>::from_table(convention, rows.data(), rows.shape(0), base, tool);
  auto single = chain.template cast<float>();
  return ChainPair{std::move(chain), std::move(single), convention};
}

constexpr std::ptrdiff_t kMinPerThread = min_chunk(40.0);  // 6-joint FK/Jacobian: ~40 ns

// Batch kernels, one per operation and precision, cloned per CPU level.
SPOTKIN_MULTIVERSION void fk_kernel(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n) {
  c.forward_batch(q, out, n);
}
SPOTKIN_MULTIVERSION void fk_kernel(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n) {
  c.forward_batch(q, out, n);
}
SPOTKIN_MULTIVERSION void frames_kernel(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n) {
  c.frames_batch(q, out, n);
}
SPOTKIN_MULTIVERSION void frames_kernel(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n) {
  c.frames_batch(q, out, n);
}
SPOTKIN_MULTIVERSION void jacobian_kernel(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n,
                                          int rows, bool in_tool_frame) {
  c.jacobian_batch(q, out, n, rows, in_tool_frame);
}
SPOTKIN_MULTIVERSION void jacobian_kernel(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n,
                                          int rows, bool in_tool_frame) {
  c.jacobian_batch(q, out, n, rows, in_tool_frame);
}

py::object fk(const ChainPair& chain, py::handle q_obj) {
  return dispatch_real(q_obj, "q", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto& c = chain.get(tag);
    const py::ssize_t n = c.dof();
    const Shape leading = leading_shape(arr, "q", {n});
    auto q = contiguous<T>(arr);
    auto out = new_array<T>(leading, {4, 4});
    const py::ssize_t N = count(leading);
    const T* qd = q.data();
    T* od = out.mutable_data();
    {
      ReleaseGilFor release(N);
      parallel_for(N, kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        fk_kernel(c, qd + b * n, od + 16 * b, e - b);
      });
    }
    return std::move(out);
  });
}

py::object frames(const ChainPair& chain, py::handle q_obj) {
  return dispatch_real(q_obj, "q", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto& c = chain.get(tag);
    const py::ssize_t n = c.dof();
    const Shape leading = leading_shape(arr, "q", {n});
    auto q = contiguous<T>(arr);
    auto out = new_array<T>(leading, {n + 2, 4, 4});
    const py::ssize_t N = count(leading);
    const T* qd = q.data();
    T* od = out.mutable_data();
    {
      ReleaseGilFor release(N);
      parallel_for(N, kMinPerThread / 4, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        frames_kernel(c, qd + b * n, od + 16 * (n + 2) * b, e - b);
      });
    }
    return std::move(out);
  });
}

py::object jacobian(const ChainPair& chain, py::handle q_obj, int rows, bool in_tool_frame) {
  return dispatch_real(q_obj, "q", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto& c = chain.get(tag);
    const py::ssize_t n = c.dof();
    const Shape leading = leading_shape(arr, "q", {n});
    auto q = contiguous<T>(arr);
    auto out = new_array<T>(leading, {rows, n});
    const py::ssize_t N = count(leading);
    const T* qd = q.data();
    T* od = out.mutable_data();
    {
      ReleaseGilFor release(N);
      parallel_for(N, kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        jacobian_kernel(c, qd + b * n, od + rows * n * b, e - b, rows, in_tool_frame);
      });
    }
    return std::move(out);
  });
}

}  // namespace

void bind_chain(py::module_& m) {
  py::enum_<Convention>(m, "Convention")
      .value("MODIFIED_DH", Convention::ModifiedDH)
      .value("CLASSIC_DH", Convention::ClassicDH);

  py::class_<ChainPair>(m, "Chain")
      .def(py::init(&make_chain), py::arg("convention"), py::arg("rows"), py::arg("base") = py::none(),
           py::arg("tool") = py::none())
      .def_property_readonly("dof", [](const ChainPair& c) { return c.f64.dof(); })
      .def_property_readonly("convention", [](const ChainPair& c) { return c.convention; })
      .def("fk", &fk, py::arg("q"))
      .def("frames", &frames, py::arg("q"))
      .def("jacobian", &jacobian, py::arg("q"), py::arg("rows"), py::arg("in_tool_frame"));
}

}  // namespace spotkin::bindings
