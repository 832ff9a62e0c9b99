// Bindings of whole-body reach (spotkin/motion/reach.hpp): _core.ReachModel holds a robot's numbers
// for reach (its statics, its arm's closed form and chain, the capsules, the box and the limits);
// its solve() answers a batch of targets, one target per task on the threads, with the GIL
// released. The façade (spotkin.motion.reach) checks the user's arguments and resolves the stance
// frames and the residual's references; the arrays' shapes are checked again here.
#include "spotkin/motion/reach.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "chain_ik_glue.hpp"
#include "chain_model.hpp"
#include "numpy_boundary.hpp"
#include "robot_statics.hpp"
#include "spotkin/arm.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

// f(the robot with the floating model of one sample at the active level: motion::reach_block's
// vector model at AVX2 and AVX-512, its baseline model at the baseline; dynamics' with_model picks
// the same for one sample).
template <typename F>
void on_reach_robot(const RobotStatics& r, F&& f) {
  if (active_isa() == Isa::Baseline)
    f(dynamics::RobotStaticsModel<motion::ReachBaselineModel>{r.body, r.floating.small(0.0), r.mass,
                                                              r.n_arm});
  else
    f(dynamics::RobotStaticsModel<motion::ReachVectorModel>{r.body, r.floating.mid(0.0), r.mass,
                                                            r.n_arm});
}

constexpr double kPiValue = 3.14159265358979323846;

struct ReachModel {
  const RobotStatics& robot;
  motion::ReachArm arm;
  motion::ReachCapsules capsules;
  motion::ReachShared shared;
};

// capsules: None, or (radius, box_centre (3,), box_half (3,), points (k,), vs_body (k - 1,),
// vs_legs (k - 1, legs, 2)).
motion::ReachCapsules read_capsules(py::handle obj, int legs) {
  motion::ReachCapsules c;
  if (obj.is_none()) return c;
  const auto parts = py::reinterpret_borrow<py::tuple>(obj);
  if (parts.size() != 6) throw py::value_error("capsules must be a 6-tuple");
  c.radius = parts[0].cast<double>();
  copy_exact(parts[1], "box_centre", {3}, c.box_centre);
  copy_exact(parts[2], "box_half", {3}, c.box_half);
  const auto points = exact(parts[3], "points", {-1});
  const py::ssize_t k = points.shape(0);
  if (k < 1 || k > motion::kReachMaxSegments + 1)
    throw py::value_error("the arm has too many capsules");
  const auto vs_body = exact(parts[4], "vs_body", {k - 1});
  const auto vs_legs = exact(parts[5], "vs_legs", {k - 1, legs, 2});
  c.n_points = int(k);
  for (py::ssize_t j = 0; j < k; ++j) c.points[j] = int(points.data()[j]);
  for (py::ssize_t j = 0; j + 1 < k; ++j) {
    c.vs_body[j] = vs_body.data()[j] != 0.0;
    for (int l = 0; l < legs; ++l)
      for (int part = 0; part < 2; ++part)
        c.vs_legs[j][l][part] = vs_legs.data()[(j * legs + l) * 2 + part] != 0.0;
  }
  c.enabled = true;
  return c;
}

ReachModel make_reach_model(const RobotStatics& robot, py::handle arm_obj, const ChainPair& chain,
                            py::handle mount, py::handle capsules, py::handle nominal,
                            py::handle lower, py::handle upper, double scale, py::handle q_lower,
                            py::handle q_upper, py::handle halton, int refine_steps) {
  const int legs = robot.body.n_legs();
  const int m = 3 * legs + 6;
  if (robot.n_arm != 6)
    throw py::value_error("reach needs the statics of a robot with a 6-joint arm");
  if (chain.f64.dof() != 6) throw py::value_error("the arm's chain must have 6 joints");
  ReachModel model{robot, {}, read_capsules(capsules, legs), {}};
  if (py::isinstance<Arm>(arm_obj)) {
    model.arm.spot = &arm_obj.cast<const Arm&>();
  } else if (py::isinstance<chain_ik_glue::ChainIK>(arm_obj)) {
    const auto& ik = arm_obj.cast<const chain_ik_glue::ChainIK&>();
    if (!ik.arm) throw py::value_error("the arm's closed form must be a 6-joint chain's");
    model.arm.six = &*ik.arm, model.arm.six_limits = &ik.limits;
  } else {
    throw py::type_error("arm must be an Arm or a ChainIK core");
  }
  model.arm.chain = &chain.f64;
  copy_exact(mount, "mount", {4, 4}, model.arm.mount);
  motion::ReachShared& sh = model.shared;
  copy_exact(nominal, "nominal", {6}, sh.nominal);
  copy_exact(lower, "lower", {6}, sh.lower);
  copy_exact(upper, "upper", {6}, sh.upper);
  copy_exact(q_lower, "q_lower", {m}, sh.q_lower);
  copy_exact(q_upper, "q_upper", {m}, sh.q_upper);
  copy_exact(halton, "halton", {motion::kReachCandidates, 6}, &sh.halton[0][0]);
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw py::value_error("scale must be finite and positive");
  if (refine_steps < 0 || refine_steps > 100)
    throw py::value_error("refine_steps must be in 0 .. 100");
  sh.scale = scale, sh.m = m, sh.refine_steps = refine_steps;
  for (int k = 0; k < 6; ++k) {  // ref.Problem.widths
    const double w = 0.5 * (sh.upper[k] - sh.lower[k]);
    if (!std::isfinite(w) || !(sh.lower[k] <= sh.upper[k]))
      throw py::value_error("the box must be finite, lower <= upper");
    sh.w_p[k] = w > 0.0 ? w : 1.0;
  }
  for (int k = 0; k < m; ++k) {
    const bool finite = std::isfinite(sh.q_lower[k]) && std::isfinite(sh.q_upper[k]);
    const double w = finite ? 0.5 * (sh.q_upper[k] - sh.q_lower[k]) : kPiValue;
    sh.w_q[k] = w > 0.0 ? w : 1.0;
  }
  motion::prepare_shared(sh);
  return model;
}

py::tuple solve(const ReachModel& model, py::handle target_obj, py::handle feet_obj,
                py::handle stance_obj, py::handle p_ref_obj, py::handle q_ref_obj,
                py::handle seed_obj, py::handle margin_obj, bool refine, bool repair) {
  const int legs = model.robot.body.n_legs();
  const int m = model.shared.m;
  const auto target = exact(target_obj, "targets", {-1, 4, 4});
  const py::ssize_t N = target.shape(0);
  const auto feet = exact(feet_obj, "feet", {N, legs, 3});
  const auto stance = exact(stance_obj, "stance", {N, 4, 4});
  const auto p_ref = exact(p_ref_obj, "p_ref", {N, 6});
  const auto q_ref = exact(q_ref_obj, "q_ref", {N, m});
  const auto margin = exact(margin_obj, "margin", {N});
  py::array_t<double, py::array::c_style> seed;
  if (!seed_obj.is_none()) seed = exact(seed_obj, "seed_pose", {N, 6});
  const Shape lead{N};
  auto pose = new_array<double>(lead, {6}), q = new_array<double>(lead, {m}),
       margins = new_array<double>(lead, {}), distance = new_array<double>(lead, {}),
       angle = new_array<double>(lead, {}), branches = new_array<double>(lead, {8, 6});
  auto status = new_array<std::int8_t>(lead, {});
  auto valid = new_array<bool>(lead, {8});
  auto slot = new_array<std::int64_t>(lead, {});
  const double* seed_data = seed_obj.is_none() ? nullptr : seed.data();
  const motion::ReachOutput rows{
      pose.mutable_data(),     q.mutable_data(),
      status.mutable_data(),   margins.mutable_data(),
      distance.mutable_data(), angle.mutable_data(),
      branches.mutable_data(), reinterpret_cast<std::uint8_t*>(valid.mutable_data()),
      slot.mutable_data()};
  {
    py::gil_scoped_release release;
    // one sample's statics model: the answers do not depend on the batch
    on_reach_robot(model.robot, [&](const auto& robot) {
      // blocks of kReachBlock targets, fixed by the targets' indices: the same answers for any
      // thread count (the threads' chunks start at multiples of kChunkAlignment, so they hold
      // whole blocks; a thread for every two blocks at least)
      static_assert(kChunkAlignment % motion::kReachBlock == 0, "chunks hold whole blocks");
      parallel_for(N, 2 * motion::kReachBlock, [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
        for (std::ptrdiff_t i0 = begin; i0 < end; i0 += motion::kReachBlock) {
          motion::ReachInput in[motion::kReachBlock];
          motion::ReachOutput out[motion::kReachBlock];
          const int count = int(std::min<std::ptrdiff_t>(motion::kReachBlock, end - i0));
          for (int k = 0; k < count; ++k) {
            const std::ptrdiff_t i = i0 + k;
            in[k] = {target.data() + 16 * i,
                     feet.data() + 3 * legs * i,
                     stance.data() + 16 * i,
                     p_ref.data() + 6 * i,
                     q_ref.data() + m * i,
                     seed_data ? seed_data + 6 * i : nullptr,
                     margin.data()[i],
                     refine,
                     repair};
            out[k] = {rows.body_pose + 6 * i, rows.q + m * i,     rows.status + i,
                      rows.margin + i,        rows.distance + i,  rows.angle + i,
                      rows.branches + 48 * i, rows.valid + 8 * i, rows.slot + i};
          }
          motion::reach_block(robot, model.arm, model.capsules, model.shared, in, out, count);
        }
      });
    });
  }
  return py::make_tuple(pose, q, status, margins, distance, angle, branches, valid, slot);
}

// (margin (N,), collides (N,)) of whole-body samples: body transforms (N, 4, 4), q (N, m), feet (N,
// legs, 3).
py::tuple constraints(const ReachModel& model, py::handle T_obj, py::handle q_obj,
                      py::handle feet_obj) {
  const int legs = model.robot.body.n_legs();
  const int m = model.shared.m;
  const auto T = exact(T_obj, "T_body", {-1, 4, 4});
  const py::ssize_t N = T.shape(0);
  const auto q = exact(q_obj, "q", {N, m});
  const auto feet = exact(feet_obj, "feet", {N, legs, 3});
  auto margin = new_array<double>({N}, {});
  auto collides = new_array<bool>({N}, {});
  double* out_margin = margin.mutable_data();
  bool* out_collides = collides.mutable_data();
  {
    py::gil_scoped_release release;
    on_reach_robot(model.robot, [&](const auto& robot) {
      parallel_for(N, 16, [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
        for (std::ptrdiff_t i = begin; i < end; ++i)
          motion::reach_constraints(robot, model.arm, model.capsules, model.shared,
                                    T.data() + 16 * i, q.data() + m * i, feet.data() + 3 * legs * i,
                                    out_margin + i, out_collides + i);
      });
    });
  }
  return py::make_tuple(margin, collides);
}

}  // namespace

void bind_reach(py::module_& m) {
  py::class_<ReachModel>(m, "ReachModel")
      .def(py::init(&make_reach_model), py::arg("statics"), py::arg("arm"), py::arg("chain"),
           py::arg("mount"), py::arg("capsules"), py::arg("nominal"), py::arg("lower"),
           py::arg("upper"), py::arg("scale"), py::arg("q_lower"), py::arg("q_upper"),
           py::arg("halton"), py::arg("refine_steps"), py::keep_alive<1, 2>(),
           py::keep_alive<1, 3>(), py::keep_alive<1, 4>())
      .def("solve", &solve, py::arg("targets"), py::arg("feet"), py::arg("stance"),
           py::arg("p_ref"), py::arg("q_ref"), py::arg("seed_pose"), py::arg("margin"),
           py::arg("refine") = true, py::arg("repair") = true,
           "Reach answers for targets (N, 4, 4) (refine: the Gauss-Newton steps; repair: the "
           "damped least squares "
           "when no candidate reaches, else NaN answers): (body_pose, q, status, margin, distance, "
           "angle, "
           "branches, valid, slot), each (N, ...).")
      .def("constraints", &constraints, py::arg("T_body"), py::arg("q"), py::arg("feet"),
           "(margin, collides) of whole-body samples: body transforms (N, 4, 4), q (N, m), feet "
           "(N, legs, 3).");
}

}  // namespace spotkin::bindings
