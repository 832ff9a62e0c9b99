// Bindings for the closed-form IK of chains (DH or URDF): 3-joint position
// IK and 6R IK by family (spherical wrist, parallel 2-3-4, spherical shoulder).
#include "spotkin/chain_ik.hpp"

#include <algorithm>
#include <memory>
#include <optional>

#include "binder.hpp"
#include "bindings.hpp"
#include "chain_ik_glue.hpp"
#include "chain_model.hpp"
#include "dispatch.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/chain_ik/arm6.hpp"
#include "spotkin/chain_ik/free_joint.hpp"
#include "spotkin/chain_ik/kernels.hpp"

namespace spotkin::bindings {

namespace chain_ik_glue {

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
constexpr double kNsPerTarget = 250.0;

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;
using chain_ik::arm6_kernel;
using chain_ik::arm6_nearest_kernel;
using chain_ik::position_kernel;
using chain_ik::position_nearest_kernel;



py::object ik_nearest(const ChainIK& ik, py::handle target, py::handle seed, py::handle out) {
  if (ik.position) {
    static const Op op({Arg("p", {3}), Arg("seed", {3}).maybe_none().parameter()},
                       {Out("q", {3}), Out("status", {}, Kind::Status)}, kNsPerTarget, [](const void* c, const auto& b) {
                         const ChainIK& k = binder::context<ChainIK>(c);
                         position_nearest_kernel(*k.position, k.limits, b.in[0], b.in[1], b.real(0), b.status(1), b.m);
                       });
    Op with_angles = op;  // the seed's revolute columns are angles, reduced exactly when huge
    with_angles.args[1].angles[0] = ik.revolute_columns;
    return binder::call(with_angles, &ik, {target, seed}, out);
  }
  static const Op op({pose_target_arg(), Arg("seed", {6}).maybe_none().parameter()},
                     {Out("q", {6}), Out("status", {}, Kind::Status)}, kNsPerTarget, [](const void* c, const auto& b) {
                       const ChainIK& k = binder::context<ChainIK>(c);
                       arm6_nearest_kernel(*k.arm, k.limits, b.in[0], pose_format(b), b.in[1], b.real(0), b.status(1),
                                           b.m);
                     });
  Op with_angles = op;
  with_angles.args[1].angles[0] = ik.revolute_columns;
  return binder::call(with_angles, &ik, {target, seed}, out);
}

py::object ik_position(const ChainIK& ik, py::handle p, py::handle out) {
  if (!ik.position)
    throw py::value_error("ik_position needs a 3-joint chain; this " + ik.kind() +
                          " chain has 6 joints: use ik(T) for the full pose");
  constexpr py::ssize_t kSlots = Position3::kSlots;
  static const Op op = Op({Arg("p", {3})},
                     {Out("q", {kSlots, 3}), Out("valid", {kSlots}, Kind::Bool), Out("exists", {kSlots}, Kind::Bool),
                      Out("exact", {kSlots}, Kind::Bool), Out("status", {}, Kind::Status)},
                     kNsPerTarget, [](const void* c, const auto& b) {
                       const ChainIK& k = binder::context<ChainIK>(c);
                       position_kernel(*k.position, k.limits, b.in[0], b.real(0), b.flags(1), b.flags(2), b.status(4),
                                       b.m);
                       std::copy(b.flags(2), b.flags(2) + kSlots * b.m, b.flags(3));  // closed form: exact where it exists
                     }).returns("ChainSolutions");
  return binder::call(op, &ik, {p}, out);
}

py::object ik_pose(const ChainIK& ik, py::handle T, py::handle out) {
  if (!ik.arm)
    throw py::value_error("ik(T) needs a 6-joint chain; this chain has 3 joints (" +
                          ik.kind() + "): use ik_position(p)");
  constexpr py::ssize_t kSlots = Arm6::kSlots;
  static const Op op = Op({pose_target_arg()},
                     {Out("q", {kSlots, 6}), Out("valid", {kSlots}, Kind::Bool), Out("exists", {kSlots}, Kind::Bool),
                      Out("exact", {kSlots}, Kind::Bool), Out("status", {}, Kind::Status)},
                     kNsPerTarget, [](const void* c, const auto& b) {
                       const ChainIK& k = binder::context<ChainIK>(c);
                       arm6_kernel(*k.arm, k.limits, b.in[0], pose_format(b), b.real(0), b.flags(1), b.flags(2),
                                   b.flags(3), b.status(4), b.m);
                     }).returns("ChainSolutions");
  return binder::call(op, &ik, {T}, out);
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
// costs its own 6R solver (cached across calls), then the 6R solve per pose. T and free_value broadcast.
py::object ik_free(const FreeJointIK& ik, py::handle T, py::handle value, py::handle out) {
  constexpr py::ssize_t kSlots = chain_ik::FreeJoint7::kSlots;
  static const Op op = Op({pose_target_arg(), Arg("free_value", {})},
                     {Out("q", {kSlots, 7}), Out("valid", {kSlots}, Kind::Bool), Out("exists", {kSlots}, Kind::Bool),
                      Out("exact", {kSlots}, Kind::Bool), Out("status", {}, Kind::Status)},
                     kNsPerTarget, [](const void* c, const auto& b) {
                       const FreeJointIK& k = binder::context<FreeJointIK>(c);
                       if (pose_format(b) == PoseFormat::Matrix)
                         chain_ik::ik_free_joint<PoseFormat::Matrix>(k.solver, k.lower, k.upper, b.in[0], b.in[1],
                                                                     b.real(0), b.flags(1), b.flags(2), b.flags(3),
                                                                     b.status(4), b.m);
                       else
                         chain_ik::ik_free_joint<PoseFormat::PositionQuaternion>(
                             k.solver, k.lower, k.upper, b.in[0], b.in[1], b.real(0), b.flags(1), b.flags(2),
                             b.flags(3), b.status(4), b.m);
                     }).returns("ChainSolutions");
  return binder::call(op, &ik, {T, value}, out);
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
      .def("ik", &ik_free, py::arg("T"), py::arg("free_value"), py::arg("out") = py::none());
  py::class_<ChainIK>(m, "ChainIK")
      .def(py::init(&make_chain_ik), py::arg("chain"), py::arg("lower"), py::arg("upper"),
           py::arg("angle_tolerance") = chain_ik::Tolerance::angle, py::arg("distance_tolerance") = -1.0)
      .def_property_readonly("kind", &ChainIK::kind)
      .def_property_readonly("idealised", &ChainIK::idealised)
      .def_property_readonly("geometry", &ChainIK::geometry)
      .def_property_readonly("position_kind", &ChainIK::position_kind)
      .def("ik_position", &ik_position, py::arg("p"), py::arg("out") = py::none())
      .def("ik", &ik_pose, py::arg("T"), py::arg("out") = py::none())
      .def("ik_nearest", &ik_nearest, py::arg("target"), py::arg("seed") = py::none(), py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
