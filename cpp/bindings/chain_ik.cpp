// Bindings for the closed-form IK of chains (DH or URDF): 3-joint position
// IK and 6R IK by family (spherical wrist, parallel 2-3-4, spherical shoulder).
#include "spotkin/chain_ik.hpp"
#include "spotkin/chain_ik/arm6.hpp"
#include "spotkin/chain_ik/free_joint.hpp"
#include "spotkin/chain_ik/kernels.hpp"

#include <memory>
#include <optional>

#include "bindings.hpp"
#include "dispatch.hpp"
#include "chain_model.hpp"
#include "numpy_boundary.hpp"

namespace spotkin::bindings {

namespace chain_ik_glue {

using chain_ik::Limits;
using chain_ik::Position3;
using chain_ik::Arm6;

struct ChainIK {
  std::optional<Position3> position;  // 3-joint chains
  std::optional<Arm6> arm;            // 6-joint chains
  Limits limits;
  std::uint64_t revolute_columns = 0;  // huge seed angles are reduced exactly

  std::string kind() const { return position ? position->name() : arm->kind(); }
  std::string position_kind() const { return position ? position->name() : arm->position_kind(); }
  bool idealised() const { return arm && arm->idealised(); }
  py::dict geometry() const {
    py::dict out;
    if (arm) {
      const auto& g = arm->geometry();
      out["wrist_meeting"] = g.wrist, out["shoulder_meeting"] = g.shoulder;
      out["parallel_234"] = g.parallel234, out["parallel_123"] = g.parallel123;
      out["axes_5_6_gap"] = g.gap56, out["axes_4_5_gap"] = g.gap45;
    }
    return out;
  }
};

ChainIK make_chain_ik(const ChainPair& pair, py::handle lower_obj, py::handle upper_obj, double angle_tolerance,
                      double distance_tolerance) {
  const Chain<double>& chain = pair.f64;
  const std::ptrdiff_t dof = chain.dof();
  // Length scale: every fixed length of the chain plus the tool offset (1 if all are zero).
  const double scale = chain.length_scale();

  ChainIK ik;
  for (std::ptrdiff_t j = 0; j < dof && j < 64; ++j)
    if (chain.joints()[std::size_t(j)].type == JointType::Revolute) ik.revolute_columns |= std::uint64_t{1} << j;
  auto lower = contiguous<double>(as_real_array(lower_obj, "lower"));
  auto upper = contiguous<double>(as_real_array(upper_obj, "upper"));
  if (lower.size() != dof || upper.size() != dof) throw py::value_error("lower and upper must have shape (dof,)");
  if (dof <= Limits::kMaxJoints) {
    ik.limits.dof = static_cast<int>(dof);
    for (std::ptrdiff_t j = 0; j < dof; ++j) {
      ik.limits.lower[j] = lower.data()[j], ik.limits.upper[j] = upper.data()[j];
      ik.limits.sigma[j] = chain.joints()[static_cast<std::size_t>(j)].type == JointType::Revolute ? 0 : 1;
    }
  }

  if (dof == 3) {
    const chain_ik::V3 w = (chain.z_tail(2) * chain.tool()).p;
    ik.position.emplace(chain_ik::split_first_three(chain), w, scale);
  } else if (dof == 6) {
    if (!(angle_tolerance >= 0.0 && angle_tolerance < 0.1) || !(distance_tolerance < 0.1 * scale))
      throw std::invalid_argument("the ik tolerances must be finite, angle in [0, 0.1) and distance below 0.1 times "
                                  "the chain's length scale");
    ik.arm.emplace(Arm6::make(chain, scale, {angle_tolerance, distance_tolerance}));
  } else {
    throw std::invalid_argument("no closed form here for a " + std::to_string(dof) +
                                "-joint chain: closed-form IK covers 3-joint chains (tool position) and 6-joint "
                                "chains with a spherical wrist, three parallel axes 2-3-4 or a spherical shoulder; "
                                "use Chain.ik_differential");
  }
  return ik;
}

// About 200-300 ns per target on one core.
constexpr std::ptrdiff_t kMinPerThread = min_chunk(250.0);

using chain_ik::arm6_kernel;
using chain_ik::arm6_nearest_kernel;
using chain_ik::position_kernel;
using chain_ik::position_nearest_kernel;

// The shared tail: (q, valid, exists, exact, status) arrays, filled on thread chunks
// (exact is exists where the kernel has no exact output).
template <typename T, typename Kernel>
py::object solutions(const Shape& leading, py::ssize_t slots, py::ssize_t dof, std::ptrdiff_t in_width,
                     const T* in, bool has_exact, Kernel&& kernel) {
  auto q = new_array<T>(leading, {slots, dof});
  auto valid = new_array<bool>(leading, {slots});
  auto exists = new_array<bool>(leading, {slots});
  auto exact = new_array<bool>(leading, {slots});
  auto status = new_array<std::int8_t>(leading, {});
  T* qd = q.mutable_data();
  auto* vd = reinterpret_cast<std::uint8_t*>(valid.mutable_data());
  auto* ed = reinterpret_cast<std::uint8_t*>(exists.mutable_data());
  auto* xd = reinterpret_cast<std::uint8_t*>(exact.mutable_data());
  std::int8_t* sd = status.mutable_data();
  const std::ptrdiff_t n = count(leading);
  {
    ReleaseGilFor release(n);
    parallel_for(n, kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
      kernel(in + in_width * b, qd + slots * dof * b, vd + slots * b, ed + slots * b, xd + slots * b, sd + b, e - b);
    });
    if (!has_exact) std::copy(ed, ed + slots * n, xd);
  }
  if (leading.empty()) return py::make_tuple(q, valid, exists, exact, status_object(status.data()[0]));
  return py::make_tuple(q, valid, exists, exact, status);
}

// One solution per target: (q (..., dof), status (...)), filled on thread chunks.
// seed None or (..., dof) with the targets' leading shape.
template <typename T, typename Kernel>
py::object nearest(const Shape& leading, py::ssize_t dof, std::ptrdiff_t in_width, const T* in,
                   py::handle seed_obj, const char* target_name, std::uint64_t revolute_columns, Kernel&& kernel) {
  py::array_t<T, py::array::c_style> seed;  // default-constructed: an empty array, not null
  const bool has_seed = !seed_obj.is_none();
  if (has_seed) {
    py::array seed_arr = as_real_array(seed_obj, "seed");
    const Shape seed_leading = leading_shape(seed_arr, "seed", {dof});
    if (seed_leading != leading)
      throw py::value_error("seed must have shape " + format_shape(leading) + " + (" + std::to_string(dof) +
                            ",), the leading shape of " + target_name + ", got " + format_shape(seed_leading) +
                            " + (" + std::to_string(dof) + ",)");
    seed = seed_angles<T>(seed_arr, dof, revolute_columns);
  }
  auto q = new_array<T>(leading, {dof});
  auto status = new_array<std::int8_t>(leading, {});
  const T* sd = has_seed ? seed.data() : nullptr;
  T* qd = q.mutable_data();
  std::int8_t* st = status.mutable_data();
  {
    ReleaseGilFor release(count(leading));
    parallel_for(count(leading), kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
      kernel(in + in_width * b, sd ? sd + dof * b : nullptr, qd + dof * b, st + b, e - b);
    });
  }
  if (leading.empty()) return py::make_tuple(q, status_object(status.data()[0]));
  return py::make_tuple(q, status);
}

py::object ik_nearest(const ChainIK& ik, py::handle target_obj, py::handle seed_obj) {
  if (ik.position)
    return dispatch_real(target_obj, "p", [&](auto tag, py::array arr) -> py::object {
      using T = decltype(tag);
      const Shape leading = leading_shape(arr, "p", {3});
      auto p = contiguous<T>(arr);
      return nearest<T>(leading, 3, 3, p.data(), seed_obj, "p", ik.revolute_columns, [&](const T* in, const T* sd, T* q, std::int8_t* st,
                                                                    std::ptrdiff_t n) {
        position_nearest_kernel<T>(*ik.position, ik.limits, in, sd, q, st, n);
      });
    });
  return dispatch_real(target_obj, "T", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto [format, leading] = pose_shape(arr, "T");
    auto poses = contiguous<T>(arr);
    const PoseFormat fmt = format;
    return nearest<T>(leading, 6, fmt == PoseFormat::Matrix ? 16 : 7, poses.data(), seed_obj, "T",
                      ik.revolute_columns, [&](const T* in, const T* sd, T* q, std::int8_t* st, std::ptrdiff_t n) {
                        arm6_nearest_kernel<T>(*ik.arm, ik.limits, in, fmt, sd, q, st, n);
                      });
  });
}

py::object ik_position(const ChainIK& ik, py::handle p_obj) {
  if (!ik.position)
    throw py::value_error("ik_position needs a 3-joint chain; this " + ik.kind() +
                          " chain has 6 joints: use ik(T) for the full pose");
  return dispatch_real(p_obj, "p", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const Shape leading = leading_shape(arr, "p", {3});
    auto p = contiguous<T>(arr);
    return solutions<T>(leading, Position3::kSlots, 3, 3, p.data(), false,
                        [&](const T* in, T* q, std::uint8_t* valid, std::uint8_t* exists, std::uint8_t*,
                            std::int8_t* status, std::ptrdiff_t n) {
                          position_kernel<T>(*ik.position, ik.limits, in, q, valid, exists, status, n);
                        });
  });
}

py::object ik_pose(const ChainIK& ik, py::handle T_obj) {
  if (!ik.arm)
    throw py::value_error("ik(T) needs a 6-joint chain; this chain has 3 joints (" +
                          ik.kind() + "): use ik_position(p)");
  return dispatch_real(T_obj, "T", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto [format, leading] = pose_shape(arr, "T");
    auto poses = contiguous<T>(arr);
    const PoseFormat fmt = format;
    return solutions<T>(leading, Arm6::kSlots, 6, fmt == PoseFormat::Matrix ? 16 : 7, poses.data(), true,
                        [&](const T* in, auto... out) { arm6_kernel<T>(*ik.arm, ik.limits, in, fmt, out...); });
  });
}

// A 7R chain with one joint held (FreeJoint7) and the 7 joints' limits.
struct FreeJointIK {
  chain_ik::FreeJoint7 solver;
  double lower[7], upper[7];
};

FreeJointIK make_free_joint_ik(const ChainPair& pair, py::handle lower_obj, py::handle upper_obj, int free_joint,
                               double angle_tolerance, double distance_tolerance) {
  const Chain<double>& chain = pair.f64;
  if (!(angle_tolerance >= 0.0 && angle_tolerance < 0.1) || !(distance_tolerance < 0.1 * chain.length_scale()))
    throw std::invalid_argument("the ik tolerances must be finite, angle in [0, 0.1) and distance below 0.1 times "
                                "the chain's length scale");
  auto lower = contiguous<double>(as_real_array(lower_obj, "lower"));
  auto upper = contiguous<double>(as_real_array(upper_obj, "upper"));
  if (lower.size() != 7 || upper.size() != 7) throw py::value_error("lower and upper must have shape (7,)");
  FreeJointIK out{chain_ik::FreeJoint7::make(chain, free_joint, {angle_tolerance, distance_tolerance}), {}, {}};
  for (int j = 0; j < 7; ++j) out.lower[j] = lower.data()[j], out.upper[j] = upper.data()[j];
  return out;
}

// The first or last joint held: one 6R solver for every value. A middle joint: each distinct value
// costs its own 6R solver (cached across calls), then the 6R solve per pose.
py::object ik_free(const FreeJointIK& ik, py::handle T_obj, py::handle value_obj) {
  return dispatch_real(T_obj, "T", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto [format, leading] = pose_shape(arr, "T");
    auto poses = contiguous<T>(arr);
    py::array value_arr = as_real_array(value_obj, "free_value");
    const Shape value_leading = leading_shape(value_arr, "free_value", {});
    if (value_leading != leading)
      throw py::value_error("free_value must have shape " + format_shape(leading) + ", the leading shape of T, got " +
                            format_shape(value_leading));
    auto values = contiguous<T>(value_arr);
    const PoseFormat fmt = format;
    const std::ptrdiff_t width = fmt == PoseFormat::Matrix ? 16 : 7;
    const T* base = poses.data();
    const T* value_data = values.data();
    return solutions<T>(leading, chain_ik::FreeJoint7::kSlots, 7, width, base, true,
                        [&](const T* in, T* q, std::uint8_t* valid, std::uint8_t* exists, std::uint8_t* exact,
                            std::int8_t* status, std::ptrdiff_t n) {
                          const T* v = value_data + (in - base) / width;
                          if (fmt == PoseFormat::Matrix)
                            chain_ik::ik_free_joint<PoseFormat::Matrix>(ik.solver, ik.lower, ik.upper, in, v, q, valid,
                                                                        exists, exact, status, n);
                          else
                            chain_ik::ik_free_joint<PoseFormat::PositionQuaternion>(
                                ik.solver, ik.lower, ik.upper, in, v, q, valid, exists, exact, status, n);
                        });
  });
}

}  // namespace chain_ik_glue

void bind_chain_ik(py::module_& m) {
  using namespace chain_ik_glue;
  py::class_<FreeJointIK>(m, "FreeJointIK")
      .def(py::init(&make_free_joint_ik), py::arg("chain"), py::arg("lower"), py::arg("upper"),
           py::arg("free_joint"), py::arg("angle_tolerance") = chain_ik::Tolerance::angle,
           py::arg("distance_tolerance") = -1.0)
      .def_property_readonly("kind", [](const FreeJointIK& ik) { return ik.solver.kind(); })
      .def_property_readonly("cached_values", [](const FreeJointIK& ik) { return ik.solver.cached_values(); })
      .def("ik", &ik_free, py::arg("T"), py::arg("free_value"));
  py::class_<ChainIK>(m, "ChainIK")
      .def(py::init(&make_chain_ik), py::arg("chain"), py::arg("lower"), py::arg("upper"),
           py::arg("angle_tolerance") = chain_ik::Tolerance::angle, py::arg("distance_tolerance") = -1.0)
      .def_property_readonly("kind", &ChainIK::kind)
      .def_property_readonly("idealised", &ChainIK::idealised)
      .def_property_readonly("geometry", &ChainIK::geometry)
      .def_property_readonly("position_kind", &ChainIK::position_kind)
      .def("ik_position", &ik_position, py::arg("p"))
      .def("ik", &ik_pose, py::arg("T"))
      .def("ik_nearest", &ik_nearest, py::arg("target"), py::arg("seed") = py::none());
}

}  // namespace spotkin::bindings
