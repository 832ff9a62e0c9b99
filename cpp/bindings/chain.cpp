// Bindings for spotkin::Chain: construction from DH tables or URDF joints, batched FK,
// frames and Jacobians.
#include "spotkin/chain.hpp"
#include "spotkin/kernels/chain.hpp"

#include <type_traits>

#include "spotkin/compatibility.hpp"
#include "spotkin/differential.hpp"

#include "bindings.hpp"
#include "chain_model.hpp"
#include "binder.hpp"
#include "numpy_boundary.hpp"
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

py::object fk(const ChainPair& chain, py::handle q, py::handle out) {
  const Op op({joints_arg(chain)}, {Out("T", {4, 4})}, 40.0,
              [](const void* c, const auto& b) { kernels::chain_fk(chain_of(c, b), b.in[0], b.real(0), b.m); });
  return binder::call(op, &chain, {q}, out);
}

py::object frames(const ChainPair& chain, py::handle q, py::handle out) {
  const py::ssize_t n_frames = chain.f64.dof() + 2;
  const Op op({joints_arg(chain)}, {Out("frames", {n_frames, 4, 4})}, 160.0,
              [](const void* c, const auto& b) { kernels::chain_frames(chain_of(c, b), b.in[0], b.real(0), b.m); });
  return binder::call(op, &chain, {q}, out);
}

struct Jacobian {
  const ChainPair& chain;
  int rows;
  bool in_tool_frame;
  int point = 0;
  int frame = 0;
};

py::object jacobian(const ChainPair& chain, py::handle q, int rows, bool in_tool_frame, py::handle out) {
  const Op op({joints_arg(chain)}, {Out("J", {rows, chain.f64.dof()})}, 40.0, [](const void* c, const auto& b) {
    const Jacobian& j = binder::context<Jacobian>(c);
    kernels::chain_jacobian(j.chain.get(typename std::decay_t<decltype(b)>::Scalar{}), b.in[0], b.real(0), b.m,
                            j.rows, j.in_tool_frame);
  });
  const Jacobian context{chain, rows, in_tool_frame};
  return binder::call(op, &context, {q}, out);
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
  const Op op({joints_arg(chain)}, {Out("J", {rows, n})}, 40.0, [](const void* c, const auto& b) {
    const Jacobian& j = binder::context<Jacobian>(c);
    kernels::chain_point_jacobian(j.chain.get(typename std::decay_t<decltype(b)>::Scalar{}), b.in[0], b.real(0),
                                  b.m, j.rows, j.point, j.frame);
  });
  const Jacobian context{chain, rows, false, point, frame};
  return binder::call(op, &context, {q}, out);
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

// Closed-loop differential IK (spotkin::differential::ik_differential), always
// in float64: targets (..., K, 4, 4) and q0 (..., dof) with equal leading shapes.
py::tuple ik_differential(const ChainPair& chain, py::handle targets_obj, py::handle q0_obj, py::handle lower_obj,
                          py::handle upper_obj, double damping, double position_tolerance,
                          double orientation_tolerance, double max_step, int max_iterations, int rows) {
  const int n = chain.f64.dof();
  py::array targets_arr = as_real_array(targets_obj, "T_targets");
  const Shape t_lead = leading_shape(targets_arr, "T_targets", {4, 4});
  if (t_lead.empty()) throw py::value_error("T_targets must have shape (..., K, 4, 4)");
  const Shape lead(t_lead.begin(), t_lead.end() - 1);
  const py::ssize_t K = t_lead.back();
  py::array q0_arr = as_real_array(q0_obj, "q0");
  if (leading_shape(q0_arr, "q0", {n}) != lead)
    throw py::value_error("q0 must have shape " + format_shape(lead) + " + (" + std::to_string(n) + ",)");
  auto lower = contiguous<double>(as_real_array(lower_obj, "lower"));
  auto upper = contiguous<double>(as_real_array(upper_obj, "upper"));
  if (lower.size() != n || upper.size() != n) throw py::value_error("lower and upper must have shape (dof,)");
  if (!(damping > 0.0) || !std::isfinite(damping)) throw py::value_error("damping must be finite and > 0");
  if (!(position_tolerance >= 0.0) || !(orientation_tolerance >= 0.0))
    throw py::value_error("tolerances must be >= 0");
  if (!(max_step > 0.0)) throw py::value_error("max_step must be > 0");
  if (max_iterations < 0) throw py::value_error("max_iter must be >= 0");
  if (rows != 3 && rows != 6) throw py::value_error("rows must be 3 or 6");
  auto targets = contiguous<double>(targets_arr);
  auto q0 = reduce_seed_angles(contiguous<double>(q0_arr), n, revolute_columns(chain));
  const py::ssize_t N = count(lead);
  auto q_path = new_array<double>(t_lead, {n});
  py::array_t<bool> converged(t_lead);
  py::array_t<std::int32_t> iterations(t_lead);
  py::array_t<double> position_error(t_lead), orientation_error(t_lead), residual(t_lead);
  std::vector<differential::IkResult> results(static_cast<std::size_t>(N * K));
  differential::IkOptions options;
  options.damping = damping;
  options.position_tolerance = position_tolerance;
  options.orientation_tolerance = orientation_tolerance;
  options.max_step = max_step;
  options.max_iterations = max_iterations;
  options.rows = rows;
  const double* td = targets.data();
  const double* qd = q0.data();
  const double* lo = lower.data();
  const double* up = upper.data();
  double* out = q_path.mutable_data();
  differential::IkResult* res = results.data();
  double* rd = residual.mutable_data();
  {
    ReleaseGilFor release(N * 64);
    parallel_for(N, 4, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
      for (std::ptrdiff_t i = b; i < e; ++i)
      {
        differential::ik_differential(chain.f64, lo, up, td + 16 * K * i, K, qd + n * i, options,
                                      out + K * n * i, res + K * i);
        for (std::ptrdiff_t k = 0; k < K; ++k)
          rd[K * i + k] = final_residual(chain.f64, td + 16 * (K * i + k), out + n * (K * i + k), rows);
      }
    });
  }
  bool* cd = converged.mutable_data();
  std::int32_t* id = iterations.mutable_data();
  double* pd = position_error.mutable_data();
  double* od = orientation_error.mutable_data();
  for (std::size_t i = 0; i < results.size(); ++i) {
    cd[i] = results[i].converged;
    id[i] = results[i].iterations;
    pd[i] = results[i].position_error;
    od[i] = results[i].orientation_error;
  }
  return py::make_tuple(std::move(q_path), std::move(converged), std::move(iterations), std::move(position_error),
                        std::move(orientation_error), std::move(residual));
}

}  // namespace chain_glue

void bind_chain(py::module_& m) {
  using namespace chain_glue;
  py::enum_<Convention>(m, "Convention")
      .value("MODIFIED_DH", Convention::ModifiedDH)
      .value("CLASSIC_DH", Convention::ClassicDH);

  py::class_<ChainPair>(m, "Chain")
      .def(py::init(&chain_from_table), py::arg("convention"), py::arg("rows"), py::arg("base") = py::none(),
           py::arg("tool") = py::none())
      .def_static("from_joints", &chain_from_joints, py::arg("placements"), py::arg("axes"), py::arg("types"),
                  py::arg("base") = py::none(), py::arg("tool") = py::none())
      .def_property_readonly("dof", [](const ChainPair& c) { return c.f64.dof(); })
      .def("fk", &fk, py::arg("q"), py::kw_only(), py::arg("out") = py::none())
      .def("frames", &frames, py::arg("q"), py::kw_only(), py::arg("out") = py::none())
      .def("jacobian", &jacobian, py::arg("q"), py::arg("rows"), py::arg("in_tool_frame"), py::kw_only(),
           py::arg("out") = py::none())
      .def("point_jacobian", &point_jacobian, py::arg("q"), py::arg("rows"), py::arg("point"), py::arg("frame"),
           py::kw_only(), py::arg("out") = py::none())
      .def("ik_differential", &ik_differential, py::arg("T_targets"), py::arg("q0"), py::arg("lower"),
           py::arg("upper"), py::arg("damping"), py::arg("position_tolerance"), py::arg("orientation_tolerance"),
           py::arg("max_step"), py::arg("max_iterations"), py::arg("rows"));
}

}  // namespace spotkin::bindings
