// Bindings of the gait planner (spotkin/motion/gait_plan.hpp): _core.plan_gait plans every command
// of a batch, one command per task on the threads, with the GIL released. The façade
// (spotkin.motion.plan) checks the user's arguments, resolves the gait into its numbers and
// broadcasts the commands; here the arrays' shapes are checked again, as any caller's.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <string>

#include "numpy_boundary.hpp"
#include "robot_statics.hpp"
#include "spotkin/motion/gait_plan.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

// A float64 C-contiguous copy (or view) of obj with exactly `shape`; ValueError naming it
// otherwise.
py::array_t<double, py::array::c_style> exact(py::handle obj, const char* name,
                                              const Shape& shape) {
  auto arr = contiguous<double>(as_real_array(obj, name));
  const Shape got(arr.shape(), arr.shape() + arr.ndim());
  bool same = got.size() == shape.size();
  for (std::size_t k = 0; same && k < shape.size(); ++k) same = shape[k] < 0 || got[k] == shape[k];
  if (!same)
    throw py::value_error(std::string(name) + " must have shape " + format_shape(shape) + ", got " +
                          format_shape(got));
  return arr;
}

py::tuple plan_gait(const RobotStatics& r, py::handle gait_obj, py::handle velocity_obj,
                    py::handle attitude_obj, py::ssize_t ticks, double rate) {
  using motion::kLegs;
  if (r.body.n_legs() != kLegs)
    throw py::value_error("the gait planner takes a quadruped (4 legs)");
  const auto gait_arr = exact(gait_obj, "gait", {motion::kGaitNumbers});
  const auto velocity = exact(velocity_obj, "velocity", {-1, 3});
  const auto attitude = exact(attitude_obj, "attitude", {2});
  if (ticks < 1) throw py::value_error("ticks must be at least 1, got " + std::to_string(ticks));
  if (!(std::isfinite(rate) && rate > 0.0)) throw py::value_error("rate must be finite and > 0");
  motion::GaitNumbers gait;
  for (int k = 0; k < motion::kGaitNumbers; ++k) gait[k] = gait_arr.data()[k];
  if (!(gait[motion::kPeriod] > 0.0) || !(gait[motion::kDuty] > 0.0 && gait[motion::kDuty] <= 1.0))
    throw py::value_error("the gait's period must be > 0 and its duty in (0, 1]");
  const py::ssize_t B = velocity.shape(0);
  constexpr py::ssize_t W = 3 * kLegs;
  py::array_t<double> pose({B, ticks, py::ssize_t(6)}),
      feet({B, ticks, py::ssize_t(kLegs), py::ssize_t(3)}), q({B, ticks, W}), qd({B, ticks, W}),
      tau({B, ticks, W}), margin({B, ticks}), residual({B, ticks, py::ssize_t(6)});
  py::array_t<bool> contact({B, ticks, py::ssize_t(kLegs)}), shortened({B, ticks});
  py::array_t<std::int8_t> status({B, ticks});
  const motion::PlanRows rows{pose.mutable_data(),      feet.mutable_data(),
                              contact.mutable_data(),   q.mutable_data(),
                              qd.mutable_data(),        tau.mutable_data(),
                              status.mutable_data(),    margin.mutable_data(),
                              shortened.mutable_data(), residual.mutable_data()};
  const double* v = velocity.data();
  const double att[2] = {attitude.data()[0], attitude.data()[1]};
  {
    py::gil_scoped_release release;
    on_robot(r, ticks, [&](const auto& robot) {
      parallel_for(B, 1, [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
        for (std::ptrdiff_t b = begin; b < end; ++b) {
          const std::ptrdiff_t n = b * ticks;
          const motion::PlanRows at{
              rows.pose + 6 * n,  rows.feet + W * n,    rows.contact + kLegs * n, rows.q + W * n,
              rows.qd + W * n,    rows.tau + W * n,     rows.status + n,          rows.margin + n,
              rows.shortened + n, rows.residual + 6 * n};
          motion::plan_command(robot, gait, v + 3 * b, att, ticks, rate, at);
        }
      });
    });
  }
  return py::make_tuple(pose, feet, contact, q, qd, tau, status, margin, shortened, residual);
}

}  // namespace

void bind_motion(py::module_& m) {
  m.def("plan_gait", &plan_gait, py::arg("robot"), py::arg("gait"), py::arg("velocity"),
        py::arg("attitude"), py::arg("ticks"), py::arg("rate"),
        "Plans of a quadruped's walk for commands (B, 3): (pose, feet, contact, q, qd, tau, "
        "status, margin, "
        "shortened, residual), each (B, ticks, ...). gait: the resolved gait's numbers (44,).");
}

}  // namespace spotkin::bindings
