// Bindings for spotkin::Arm: batched FK, Jacobian, singularity measures and
// closed-form IK with all 8 solutions.
#include "spotkin/kernels/arm.hpp"

#include <pybind11/stl.h>

#include <tuple>

#include "bindings.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace arm_glue {

constexpr std::ptrdiff_t kMinPerThread = min_chunk(20.0);  // FK ~20 ns; IK (~200 ns) uses kMinPerThreadIk
constexpr std::ptrdiff_t kMinPerThreadIk = min_chunk(200.0);

py::object fk(const Arm& arm, py::handle q_obj) {
  return map_batch(q_obj, "q", 6, {4, 4}, kMinPerThread,
                   [&](const auto* q, auto* T, std::ptrdiff_t n) { kernels::arm_fk(arm, q, T, n); }, all_angles(6));
}

py::object jacobian(const Arm& arm, py::handle q_obj) {
  return map_batch(q_obj, "q", 6, {6, 6}, kMinPerThread,
                   [&](const auto* q, auto* J, std::ptrdiff_t n) { kernels::arm_jacobian(arm, q, J, n); }, all_angles(6));
}

py::object singularity(const Arm& arm, py::handle q_obj) {
  py::array arr = as_real_array(q_obj, "q");
  const Shape leading = leading_shape(arr, "q", {6});
  auto q = contiguous<double>(arr);
  auto out = new_array<double>(leading, {4});
  const double* qd = q.data();
  double* od = out.mutable_data();
  {
    ReleaseGilFor release(count(leading));
    parallel_for(count(leading), kMinPerThread / 8, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
      with_reduced_angles(qd + 6 * b, 6, all_angles(6), od + 4 * b, 4, e - b, [&](const double* qb, double* ob, std::ptrdiff_t m) {
        for (std::ptrdiff_t i = 0; i < m; ++i) arm.singularity(qb + 6 * i, ob + 4 * i);
      });
    });
  }
  return std::move(out);
}

template <typename T>
py::array_t<T, py::array::c_style> seed_array(py::handle seed_obj, const Shape& leading, bool& has_seed) {
  has_seed = !seed_obj.is_none();
  if (!has_seed) return {};
  py::array seed_arr = as_real_array(seed_obj, "seed");
  const Shape seed_leading = leading_shape(seed_arr, "seed", {6});
  if (seed_leading != leading)
    throw py::value_error("seed must have the leading shape of T, " + format_shape(leading) + ", got " +
                          format_shape(seed_leading) + "; broadcast them first");
  return seed_angles<T>(seed_arr, 6, all_angles(6));
}

py::object ik_all(const Arm& arm, py::handle T_obj, py::handle seed_obj) {
  return dispatch_real(T_obj, "T", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto [format, leading] = pose_shape(arr, "T");
    auto poses = contiguous<T>(arr);
    bool has_seed = false;
    auto seed = seed_array<T>(seed_obj, leading, has_seed);
    auto q = new_array<T>(leading, {Arm::kSlots, 6});
    auto valid = new_array<bool>(leading, {Arm::kSlots});
    auto exists = new_array<bool>(leading, {Arm::kSlots});
    auto status = new_array<std::int8_t>(leading, {});
    const std::ptrdiff_t stride = format == PoseFormat::Matrix ? 16 : 7;
    const T* pd = poses.data();
    const T* sd = has_seed ? seed.data() : nullptr;
    T* qd = q.mutable_data();
    auto* vd = reinterpret_cast<std::uint8_t*>(valid.mutable_data());
    auto* ed = reinterpret_cast<std::uint8_t*>(exists.mutable_data());
    std::int8_t* std_ = status.mutable_data();
    const PoseFormat fmt = format;
    {
      ReleaseGilFor release(count(leading));
      parallel_for(count(leading), kMinPerThreadIk, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        kernels::arm_ik_all<T>(arm, pd + stride * b, fmt, sd ? sd + 6 * b : nullptr, qd + 48 * b, vd + 8 * b,
                               ed + 8 * b, std_ + b, e - b);
      });
    }
    if (leading.empty()) return py::make_tuple(q, valid, exists, status_object(status.data()[0]));
    return py::make_tuple(q, valid, exists, status);
  });
}

py::object ik(const Arm& arm, py::handle T_obj, py::handle seed_obj) {
  return dispatch_real(T_obj, "T", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto [format, leading] = pose_shape(arr, "T");
    auto poses = contiguous<T>(arr);
    bool has_seed = false;
    auto seed = seed_array<T>(seed_obj, leading, has_seed);
    const bool single = leading.empty();
    auto q = new_array<T>(leading, {6});
    std::int8_t single_status = 0;
    py::array_t<std::int8_t> status;
    if (!single) status = new_array<std::int8_t>(leading, {});
    const std::ptrdiff_t stride = format == PoseFormat::Matrix ? 16 : 7;
    const T* pd = poses.data();
    const T* sd = has_seed ? seed.data() : nullptr;
    T* qd = q.mutable_data();
    std::int8_t* std_ = single ? &single_status : status.mutable_data();
    const PoseFormat fmt = format;
    {
      ReleaseGilFor release(count(leading));
      parallel_for(count(leading), kMinPerThreadIk, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        kernels::arm_ik<T>(arm, pd + stride * b, fmt, sd ? sd + 6 * b : nullptr, qd + 6 * b, std_ + b, e - b);
      });
    }
    if (single) return py::make_tuple(q, status_object(single_status));
    return py::make_tuple(q, status);
  });
}

Arm make_arm(std::array<double, 3> mount, double upper_arm, double forearm, double forearm_offset, double hand,
             py::handle tool_obj, py::handle lower_limits, py::handle upper_limits) {
  for (double v : {mount[0], mount[1], mount[2], upper_arm, forearm, forearm_offset, hand})
    if (!std::isfinite(v)) throw std::invalid_argument("arm lengths and mount must be finite");
  if (!(upper_arm > 0.0) || !(std::hypot(forearm, forearm_offset) > 0.0))
    throw std::invalid_argument("upper_arm must be positive and the forearm non-degenerate");
  ArmGeometry g;
  for (int i = 0; i < 3; ++i) g.mount[i] = mount[i];
  g.upper_arm = upper_arm, g.forearm = forearm, g.forearm_offset = forearm_offset, g.hand = hand;
  if (!tool_obj.is_none()) {
    g.tool = rigid_from<Rigid<double>>(tool_obj, "tool");  // checked to be rigid there
  }
  JointLimits<6> limits;
  for (auto [obj, target, name] : {std::tuple{lower_limits, limits.lower, "lower limits"},
                                   std::tuple{upper_limits, limits.upper, "upper limits"}}) {
    auto arr = contiguous<double>(as_real_array(obj, name));
    if (arr.ndim() != 1 || arr.shape(0) != 6) throw py::value_error(std::string(name) + " must have shape (6,)");
    for (int j = 0; j < 6; ++j) target[j] = arr.data()[j];
  }
  for (int j = 0; j < 6; ++j)
    if (std::isnan(limits.lower[j]) || std::isnan(limits.upper[j]) || limits.lower[j] > limits.upper[j])
      throw std::invalid_argument("limits must satisfy lower <= upper, with no NaN");
  return Arm(g, limits);
}

}  // namespace arm_glue

void bind_arm(py::module_& m) {
  using namespace arm_glue;
  py::class_<Arm>(m, "Arm")
      .def(py::init(&make_arm), py::arg("mount"), py::arg("upper_arm"), py::arg("forearm"),
           py::arg("forearm_offset"), py::arg("hand"), py::arg("tool"), py::arg("lower_limits"),
           py::arg("upper_limits"))
      .def("fk", &fk, py::arg("q"))
      .def("jacobian", &jacobian, py::arg("q"))
      .def("singularity", &singularity, py::arg("q"))
      .def("ik", &ik, py::arg("T"), py::arg("seed") = py::none())
      .def("ik_all", &ik_all, py::arg("T"), py::arg("seed") = py::none());
}

}  // namespace spotkin::bindings
