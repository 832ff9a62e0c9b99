// Bindings for spotkin::Chain: construction from DH tables, batched FK,
// frames and Jacobians.
#include "spotkin/chain.hpp"

#include <type_traits>

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

// The chain in the precision of the batch's working dtype.
template <typename T>
const Chain<std::remove_const_t<T>>& in_precision(const ChainPair& chain, T*) {
  return chain.get(std::remove_const_t<T>{});
}

py::object fk(const ChainPair& chain, py::handle q_obj) {
  return map_batch(q_obj, "q", chain.f64.dof(), {4, 4}, kMinPerThread, [&](const auto* q, auto* T, std::ptrdiff_t n) {
    fk_kernel(in_precision(chain, q), q, T, n);
  });
}

py::object frames(const ChainPair& chain, py::handle q_obj) {
  const py::ssize_t n_frames = chain.f64.dof() + 2;
  return map_batch(q_obj, "q", chain.f64.dof(), {n_frames, 4, 4}, kMinPerThread / 4,
                   [&](const auto* q, auto* F, std::ptrdiff_t n) { frames_kernel(in_precision(chain, q), q, F, n); });
}

py::object jacobian(const ChainPair& chain, py::handle q_obj, int rows, bool in_tool_frame) {
  return map_batch(q_obj, "q", chain.f64.dof(), {rows, chain.f64.dof()}, kMinPerThread,
                   [&](const auto* q, auto* J, std::ptrdiff_t n) {
                     jacobian_kernel(in_precision(chain, q), q, J, n, rows, in_tool_frame);
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
