// Bindings of the standing statics (spotkin/dynamics/robot_statics.hpp) and of a legged robot's whole-body
// centre of mass, through the binder: every per-sample array broadcasts over the leading dimensions.
// RobotStatics computes a robot's centre of mass and standing torques from its body pose and joints
// in one kernel (the floating model's centre of mass and gravity torques, the legs' FK and Jacobians,
// the minimum-norm stance forces), for one sample as for millions.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <limits>
#include <string>
#include <type_traits>

#include "binder.hpp"
#include "dynamics_boundary.hpp"
#include "fast_call.hpp"
#include "numpy_boundary.hpp"
#include "robot_statics.hpp"
#include "spotkin/body.hpp"
#include "spotkin/dynamics/robot_statics.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

// ---------------------------------------------------------------- a robot's statics

struct StaticsCall {
  const RobotStatics& robot;
  EulerSequence seq;
  double gravity[3];
};

// The kernel's rows of a binder block: the pose, q (the legs', or the legs' then the arm's) and the stance.
template <typename T>
dynamics::StaticsRows<T> statics_rows(const binder::Block<T>& b) {
  dynamics::StaticsRows<T> rows{b.in[0], b.stride[0], static_cast<BodyPoseFormat>(b.shape[0]),
                                b.in[1], b.stride[1], b.shape[1] == 1};
  rows.stance = b.in[2], rows.stance_stride = b.stride[2];
  return rows;
}

// body_pose (any form) and q (..., 3 n_legs [+ n_arm]).
Arg statics_pose() {
  return Arg("body_pose", {6}, std::uint64_t{0b111000}).or_shape({4, 4}).or_shape({7});
}
Arg statics_q(const RobotStatics& r) {
  const py::ssize_t legs = 3 * r.body.n_legs();
  const std::uint64_t revolute = r.floating.angles >> 7;  // the joints' columns of q that are angles
  Arg q("q", {legs}, revolute & all_angles(int(legs)));     // the legs' joints, or the legs' then the arm's
  return r.n_arm ? q.or_shape({legs + r.n_arm}, revolute & all_angles(int(legs + r.n_arm))) : q;
}

void check_weight(double mass, const double* g);

// gravity (3,): finite, with a finite weight m |g|; ValueError otherwise.
void read_gravity(py::handle obj, double mass, double* g) {
  bool parsed = (PyTuple_CheckExact(obj.ptr()) || PyList_CheckExact(obj.ptr())) && PySequence_Fast_GET_SIZE(obj.ptr()) == 3;
  for (int k = 0; parsed && k < 3; ++k) {  // the default, a tuple of floats: no array
    PyObject* item = PySequence_Fast_GET_ITEM(obj.ptr(), k);
    parsed = PyFloat_CheckExact(item);
    if (parsed) g[k] = PyFloat_AS_DOUBLE(item);
  }
  if (parsed) return check_weight(mass, g);
  auto arr = contiguous<double>(as_real_array(obj, "gravity"));
  if (arr.ndim() != 1 || arr.shape(0) != 3)
    throw py::value_error("gravity must have shape (3,), got " + format_shape(Shape(arr.shape(), arr.shape() + arr.ndim())));
  for (int k = 0; k < 3; ++k) g[k] = arr.data()[k];
  check_weight(mass, g);
}

void check_weight(double mass, const double* g) {
  const double weight = mass * std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  if (!std::isfinite(g[0] + g[1] + g[2]) || !std::isfinite(weight))
    throw py::value_error("gravity must be finite and the weight m |g| too, got [" + std::to_string(g[0]) + ", " +
                          std::to_string(g[1]) + ", " + std::to_string(g[2]) + "]");
}

binder::OpCache::Key statics_key(const RobotStatics& r) {
  return {std::uint64_t(r.body.n_legs()), std::uint64_t(r.n_arm), r.floating.angles};
}

py::object robot_com(const RobotStatics& r, py::handle pose, int sequence, py::handle q, py::handle out) {
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({statics_pose(), statics_q(r)}, {Out("com", {3})}, 600.0, [](const void* c, const auto& b) {
      const StaticsCall& s = binder::context<StaticsCall>(c);
      on_robot(s.robot, b.m, [&](const auto& robot) {
        dynamics::robot_com(robot, s.seq, statics_rows(b), b.real(0), b.m);
      });
    });
  };
  const StaticsCall call{r, EulerSequence::from_code(sequence), {0.0, 0.0, 0.0}};
  return ops.with(statics_key(r), make, [&](const Op& op) { return binder::call(op, &call, {pose, q}, out); });
}

py::object robot_standing(const RobotStatics& r, py::handle pose, int sequence, py::handle q, py::handle stance,
                          py::handle gravity, py::handle out) {
  static binder::OpCache ops;
  const py::ssize_t L = r.body.n_legs();
  const auto make = [&] {
    return Op({statics_pose(), statics_q(r), Arg("stance", {L}).maybe_none().parameter()},
              {Out("tau", {3 * L}), Out("forces", {L, 3}),
               Out("status", {}, Kind::Code).members("StanceStatus"),
               Out("margin", {}).scalar_when_single(), Out("residual", {6})},
              2000.0,
              [](const void* c, const auto& b) {
                const StaticsCall& s = binder::context<StaticsCall>(c);
                on_robot(s.robot, b.m, [&](const auto& robot) {
                  dynamics::robot_standing(robot, s.seq, s.gravity, statics_rows(b), b.real(0),
                                           b.real(1), b.status(2), b.real(3), b.real(4), b.m);
                });
              })
        .returns("Standing");
  };
  StaticsCall call{r, EulerSequence::from_code(sequence), {}};
  read_gravity(gravity, r.mass, call.gravity);
  return ops.with(statics_key(r), make,
                  [&](const Op& op) { return binder::call(op, &call, {pose, q, stance}, out); });
}

RobotStatics make_robot_statics(const Body& body, const FloatingDynamics& floating, double mass) {
  const int legs = 3 * body.n_legs();
  const int n_arm = floating.f64.nq() - 7 - legs;
  if (n_arm < 0) throw py::value_error("the floating model has fewer joints than the legs");
  if (floating.f64.nq() > dynamics::kStaticsMaxQ)
    throw py::value_error("a robot's statics take at most " + std::to_string(dynamics::kStaticsMaxQ - 7) + " joints");
  if (body.n_legs() > dynamics::kMaxFeet)
    throw py::value_error("a robot's statics take at most " + std::to_string(dynamics::kMaxFeet) + " legs");
  if (!(mass > 0.0) || !std::isfinite(mass)) throw py::value_error("mass must be finite and positive");
  return RobotStatics{body, floating, mass, n_arm};
}

}  // namespace

void bind_statics(py::module_& m) {
  py::class_<RobotStatics> cls(m, "RobotStatics");
  cls.def(py::init(&make_robot_statics), py::arg("body"), py::arg("floating"), py::arg("mass"),
          py::keep_alive<1, 2>(), py::keep_alive<1, 3>());
  fast::def_fast<&robot_com>(cls, "com", py::arg("body_pose"), py::arg("sequence"), py::arg("q"),
                             py::arg("out") = py::none());
  fast::def_fast<&robot_standing>(cls, "standing", py::arg("body_pose"), py::arg("sequence"),
                                  py::arg("q"), py::arg("stance"), py::arg("gravity"),
                                  py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
