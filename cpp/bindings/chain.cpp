// Bindings for spotkin::Chain: construction from DH tables or URDF joints, batched FK,
// frames and Jacobians.
#include "spotkin/chain.hpp"

#include <type_traits>

#include "binder.hpp"
#include "bindings.hpp"
#include "chain_model.hpp"
#include "fast_call.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/compatibility.hpp"
#include "spotkin/differential.hpp"
#include "spotkin/kernels/chain.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace chain_glue {

// The revolute joints' columns of q: huge angles are reduced exactly before the kernels.
std::uint64_t revolute_columns(const ChainPair& chain) {
  std::uint64_t mask = 0;
  const auto& joints = chain.f64.joints();
  for (std::size_t j = 0; j < joints.size() && j < 64; ++j)
    if (joints[j].type == JointType::Revolute) mask |= std::uint64_t{1} << j;
  return mask;
}

using binder::Arg;
using binder::Op;
using binder::Out;

// q (..., dof): the revolute joints' huge angles reduced exactly; a sample with NaN or Inf gets NaN.
Arg joints_arg(const ChainPair& chain) { return Arg("q", {chain.f64.dof()}, revolute_columns(chain)).nan_rows(); }

template <typename B>
const auto& chain_of(const void* c, const B&) {
  return binder::context<ChainPair>(c).get(typename B::Scalar{});
}

// The key of a chain's cached ops (binder::OpCache): its dof, its angle columns and `extra`.
binder::OpCache::Key key_of(const ChainPair& chain, std::uint64_t extra = 0) {
  return {std::uint64_t(chain.f64.dof()), revolute_columns(chain), extra};
}

py::object fk(const ChainPair& chain, py::handle q, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({joints_arg(chain)}, {Out("T", {4, 4})}, 40.0, [](const void* c, const auto& b) {
      kernels::chain_fk(chain_of(c, b), b.in[0], b.real(0), b.m);
    });
  };
  return ops.with(key_of(chain), make,
                  [&](const Op& op) { return binder::call(op, &chain, {q}, out); });
}

py::object frames(const ChainPair& chain, py::handle q, py::handle out) {
  const py::ssize_t n_frames = chain.f64.dof() + 2;
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({joints_arg(chain)}, {Out("frames", {n_frames, 4, 4})}, 160.0,
              [](const void* c, const auto& b) {
                kernels::chain_frames(chain_of(c, b), b.in[0], b.real(0), b.m);
              });
  };
  return ops.with(key_of(chain), make,
                  [&](const Op& op) { return binder::call(op, &chain, {q}, out); });
}

struct Jacobian {
  const ChainPair& chain;
  int rows;
  bool in_tool_frame;
  int point = 0;
  int frame = 0;
};

py::object jacobian(const ChainPair& chain, py::handle q, int rows, bool in_tool_frame, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({joints_arg(chain)}, {Out("J", {rows, chain.f64.dof()})}, 40.0,
              [](const void* c, const auto& b) {
                const Jacobian& j = binder::context<Jacobian>(c);
                kernels::chain_jacobian(j.chain.get(typename std::decay_t<decltype(b)>::Scalar{}),
                                        b.in[0], b.real(0), b.m, j.rows, j.in_tool_frame);
              });
  };
  const Jacobian context{chain, rows, in_tool_frame};
  return ops.with(key_of(chain, std::uint64_t(rows)), make,
                  [&](const Op& op) { return binder::call(op, &context, {q}, out); });
}

// J_point(frame): point in [0, dof + 1], frame in [-1, dof + 1] (-1: the reference frame's axes).
py::object point_jacobian(const ChainPair& chain, py::handle q, int rows, int point, int frame, py::handle out) {
  const int n = chain.f64.dof();
  if (rows != 3 && rows != 6) throw py::value_error("rows must be 3 or 6");
  if (point < 0 || point > n + 1)
    throw py::value_error("point must be a frame index in [0, " + std::to_string(n + 1) + "], got " +
                          std::to_string(point));
  if (frame < -1 || frame > n + 1)
    throw py::value_error("frame must be a frame index in [0, " + std::to_string(n + 1) + "], got " +
                          std::to_string(frame));
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({joints_arg(chain)}, {Out("J", {rows, n})}, 40.0, [](const void* c, const auto& b) {
      const Jacobian& j = binder::context<Jacobian>(c);
      kernels::chain_point_jacobian(j.chain.get(typename std::decay_t<decltype(b)>::Scalar{}),
                                    b.in[0], b.real(0), b.m, j.rows, j.point, j.frame);
    });
  };
  const Jacobian context{chain, rows, false, point, frame};
  return ops.with(key_of(chain, std::uint64_t(rows)), make,
                  [&](const Op& op) { return binder::call(op, &context, {q}, out); });
}

// The compatibility residual ||(I - J J^+) e|| of the final error e against the Jacobian at the
// returned joints (rows of the task), NaN where the target was invalid.
double final_residual(const Chain<double>& chain, const double* T_target, const double* q, int rows) {
  if (!differential::all_finite(q, chain.dof())) return quiet_nan<double>();
  Rigid<double> target;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) target.R(i, j) = T_target[4 * i + j];
    target.p[i] = T_target[4 * i + 3];
  }
  double e[6], J[6 * Chain<double>::kMaxJoints];
  differential::pose_error(target, chain.forward(q), e);
  chain.jacobian(q, J, rows, false);
  return differential::compatibility<double>(J, e, rows, chain.dof(), -1.0).residual;
}

// Closed-loop differential IK (spotkin::differential::ik_differential), in float64: paths of
// targets (..., K, 4, 4) and starts q0 (..., dof), broadcast -> (q (..., K, dof), converged,
// iterations (int64), position_error, orientation_error, residual, each (..., K)).
struct DifferentialIk {
  const ChainPair& chain;
  const double* lower;
  const double* upper;
  differential::IkOptions options;
  int targets;  // K
};

py::object ik_differential(const ChainPair& chain, py::handle targets, py::handle q0, py::handle lower_obj,
                           py::handle upper_obj, double damping, double position_tolerance,
                           double orientation_tolerance, double max_step, int max_iterations, int rows) {
  const int n = chain.f64.dof();
  py::array targets_arr = as_real_array(targets, "T_targets");
  if (targets_arr.ndim() < 3 || targets_arr.shape(targets_arr.ndim() - 1) != 4 ||
      targets_arr.shape(targets_arr.ndim() - 2) != 4)
    throw py::value_error("T_targets must have shape (..., K, 4, 4), got " +
                          format_shape(Shape(targets_arr.shape(), targets_arr.shape() + targets_arr.ndim())));
  const py::ssize_t K = targets_arr.shape(targets_arr.ndim() - 3);
  auto lower = contiguous<double>(as_real_array(lower_obj, "lower"));
  auto upper = contiguous<double>(as_real_array(upper_obj, "upper"));
  if (lower.size() != n || upper.size() != n) throw py::value_error("lower and upper must have shape (dof,)");
  if (!(damping > 0.0) || !std::isfinite(damping)) throw py::value_error("damping must be finite and > 0");
  if (!(position_tolerance >= 0.0) || !(orientation_tolerance >= 0.0))
    throw py::value_error("tolerances must be >= 0");
  if (!(max_step > 0.0)) throw py::value_error("max_step must be > 0");
  if (max_iterations < 0) throw py::value_error("max_iter must be >= 0");
  if (rows != 3 && rows != 6) throw py::value_error("rows must be 3 or 6");
  DifferentialIk context{chain, lower.data(), upper.data(), {}, int(K)};
  context.options.damping = damping;
  context.options.position_tolerance = position_tolerance;
  context.options.orientation_tolerance = orientation_tolerance;
  context.options.max_step = max_step;
  context.options.max_iterations = max_iterations;
  context.options.rows = rows;
  const Op op = Op({Arg("T_targets", {K, 4, 4}), Arg("q0", {n}, revolute_columns(chain))},
                   {Out("q", {K, n}), Out("converged", {K}, binder::Kind::Bool),
                    Out("iterations", {K}, binder::Kind::Index), Out("position_error", {K}),
                    Out("orientation_error", {K}), Out("residual", {K})},
                   50000.0, [](const void* c, const auto& b) {
                     if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>) {
                       const DifferentialIk& d = binder::context<DifferentialIk>(c);
                       const Chain<double>& ch = d.chain.f64;
                       const int dof = ch.dof(), K = d.targets;
                       std::vector<differential::IkResult> results(static_cast<std::size_t>(K));
                       for (std::ptrdiff_t i = 0; i < b.m; ++i) {
                         const double* path = b.in[0] + 16 * K * i;
                         double* q = b.real(0) + K * dof * i;
                         differential::ik_differential(ch, d.lower, d.upper, path, K, b.in[1] + dof * i, d.options, q,
                                                       results.data());
                         for (int k = 0; k < K; ++k) {
                           const std::ptrdiff_t at = K * i + k;
                           b.flags(1)[at] = results[std::size_t(k)].converged;
                           b.index(2)[at] = results[std::size_t(k)].iterations;
                           b.real(3)[at] = results[std::size_t(k)].position_error;
                           b.real(4)[at] = results[std::size_t(k)].orientation_error;
                           b.real(5)[at] = final_residual(ch, path + 16 * k, q + dof * k, d.options.rows);
                         }
                       }
                     }
                   })
                   .float64_only();
  return binder::call(op, &context, {targets, q0}, py::none());
}

}  // namespace chain_glue

void bind_chain(py::module_& m) {
  using namespace chain_glue;
  py::enum_<Convention>(m, "Convention")
      .value("MODIFIED_DH", Convention::ModifiedDH)
      .value("CLASSIC_DH", Convention::ClassicDH);

  py::class_<ChainPair> cls(m, "Chain");
  cls.def(py::init(&chain_from_table), py::arg("convention"), py::arg("rows"),
          py::arg("base") = py::none(), py::arg("tool") = py::none())
      .def_static("from_joints", &chain_from_joints, py::arg("placements"), py::arg("axes"),
                  py::arg("types"), py::arg("base") = py::none(), py::arg("tool") = py::none())
      .def_property_readonly("dof", [](const ChainPair& c) { return c.f64.dof(); })
      .def("frames", &frames, py::arg("q"), py::arg("out") = py::none())
      .def("point_jacobian", &point_jacobian, py::arg("q"), py::arg("rows"), py::arg("point"),
           py::arg("frame"), py::arg("out") = py::none())
      .def("ik_differential", &ik_differential, py::arg("T_targets"), py::arg("q0"),
           py::arg("lower"), py::arg("upper"), py::arg("damping"), py::arg("position_tolerance"),
           py::arg("orientation_tolerance"), py::arg("max_step"), py::arg("max_iterations"),
           py::arg("rows"));
  fast::def_fast<&fk>(cls, "fk", py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&jacobian>(cls, "jacobian", py::arg("q"), py::arg("rows"),
                            py::arg("in_tool_frame"), py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
