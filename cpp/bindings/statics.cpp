// Bindings of the standing statics (spotkin/dynamics/statics.hpp) and of a legged robot's whole-body
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
#include "numpy_boundary.hpp"
#include "spotkin/body.hpp"
#include "spotkin/dynamics/statics.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

struct Standing {
  double mass;
  int legs;
};

// Per sample: com (3), feet (legs, 3), foot Jacobians (legs, 3, 3), the legs' gravity torques
// (3 legs), the stance mask (legs: 0 or 1) and gravity (3), broadcast; float64.
py::tuple standing_torques(py::handle com, double mass, py::handle feet, py::handle jacobians, py::handle leg_gravity,
                           py::handle stance, py::handle gravity) {
  py::array feet_arr = as_real_array(feet, "feet");
  if (feet_arr.ndim() < 2 || feet_arr.shape(feet_arr.ndim() - 1) != 3)
    throw py::value_error("feet must have shape (..., legs, 3), got " +
                          format_shape(Shape(feet_arr.shape(), feet_arr.shape() + feet_arr.ndim())));
  const py::ssize_t legs = feet_arr.shape(feet_arr.ndim() - 2);
  if (legs < 1 || legs > dynamics::kMaxFeet)
    throw py::value_error("standing torques take 1 to " + std::to_string(dynamics::kMaxFeet) + " legs, got " +
                          std::to_string(legs));
  if (!(mass >= 0.0) || !std::isfinite(mass)) throw py::value_error("mass must be finite and non-negative");
  const Op op = Op({Arg("com", {3}), Arg("feet", {legs, 3}), Arg("foot_jacobians", {legs, 3, 3}),
                    Arg("leg_gravity", {3 * legs}), Arg("stance", {legs}), Arg("gravity", {3})},
                   {Out("tau", {3 * legs}), Out("forces", {legs, 3}), Out("status", {}, Kind::Status),
                    Out("margin", {})},
                   2000.0, [](const void* c, const auto& b) {
                     if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>) {
                       const Standing& s = binder::context<Standing>(c);
                       const int L = s.legs;
                       for (std::ptrdiff_t i = 0; i < b.m; ++i) {
                         double* t = b.real(0) + 3 * L * i;
                         double* f = b.real(1) + 3 * L * i;
                         std::int8_t* st = b.status(2) + i;
                         double* mg = b.real(3) + i;
                         std::uint8_t on[dynamics::kMaxFeet];
                         bool stance_ok = true;
                         for (int l = 0; l < L; ++l) {
                           const double v = b.in[4][L * i + l];
                           on[l] = v != 0.0;
                           stance_ok = stance_ok && (v == 0.0 || v == 1.0);
                         }
                         if (!stance_ok) {  // a NaN in the mask: invalid, as any non-finite input
                           std::fill(t, t + 3 * L, std::numeric_limits<double>::quiet_NaN());
                           std::fill(f, f + 3 * L, std::numeric_limits<double>::quiet_NaN());
                           *st = static_cast<std::int8_t>(dynamics::Stance::InvalidInput);
                           *mg = std::numeric_limits<double>::quiet_NaN();
                           continue;
                         }
                         dynamics::standing_sample(L, b.in[0] + 3 * i, s.mass, b.in[1] + 3 * L * i,
                                                   b.in[2] + 9 * L * i, b.in[3] + 3 * L * i, on, b.in[5] + 3 * i, t,
                                                   f, st, mg);
                       }
                     }
                   })
                   .float64_only();
  const Standing context{mass, int(legs)};
  return binder::call(op, &context, {com, feet, jacobians, leg_gravity, stance, gravity}, py::none());
}

// ---------------------------------------------------------------- a robot's statics

// The robot: its legs (Body: leg l's joints are q's columns[l]), its floating model (the body, then
// the legs' chains, then the arm's, in q's order) and its total mass. Held by reference: the
// Python object keeps both alive.
struct RobotStatics {
  const Body& body;
  const FloatingDynamics& floating;
  double mass;
  int n_arm;
  int nq() const { return floating.f64.nq(); }
  int nv() const { return floating.f64.nv(); }
};

constexpr int kSubBlock = 16;  // samples per call of the floating kernels (scratch on the stack)
constexpr int kMaxQ = 128;     // the floating model's q, at most

struct StaticsCall {
  const RobotStatics& robot;
  EulerSequence seq;
  double gravity[3];
};

// One sub-block's poses and floating coordinates: T (16 per sample, NaN when invalid), qf (nq per
// sample: the body at the origin, then the joints; an invalid sample's joints at zero) and whether
// each sample is valid (a rigid pose, finite joints).
template <typename T>
void load_sub_block(const StaticsCall& s, const binder::Block<T>& b, std::ptrdiff_t first, int m, double* Tm,
                    double* qf, bool* valid) {
  const int nq = s.robot.nq(), width = 3 * s.robot.body.n_legs() + (b.shape[1] == 1 ? s.robot.n_arm : 0);
  const auto format = static_cast<BodyPoseFormat>(b.shape[0]);
  for (int i = 0; i < m; ++i) {
    const std::ptrdiff_t k = first + i;
    valid[i] = body_batch::pose_transform(b.in[0] + b.stride[0] * k, format, s.seq, Tm + 16 * i);
    const T* q = b.in[1] + b.stride[1] * k;
    double* row = qf + nq * i;
    std::fill(row, row + nq, 0.0);
    row[6] = 1.0;  // the identity quaternion [0, 0, 0, 1]
    bool finite = true;
    for (int j = 0; j < width; ++j) finite &= std::isfinite(double(q[j]));
    valid[i] = valid[i] && finite;
    if (finite)
      for (int j = 0; j < width; ++j) row[7 + j] = double(q[j]);
  }
}

// The centre of mass in the body frame (3 per sample) of a sub-block's floating coordinates.
void body_frame_com(const RobotStatics& r, const double* qf, int m, double* com) {
  with_model<double>(r.floating, [&](const auto& model) {
    dynamics::floating_com_k(model, Rows<double>{qf, r.nq()}, com, false, 0, m, false);
  });
}

// com = t + R c: the robot's centre of mass in the world (..., 3).
template <typename T>
void com_kernel(const void* c, const binder::Block<T>& b) {
  const StaticsCall& s = binder::context<StaticsCall>(c);
  double Tm[16 * kSubBlock], qf[kMaxQ * kSubBlock], com[3 * kSubBlock];
  bool valid[kSubBlock];
  for (std::ptrdiff_t first = 0; first < b.m; first += kSubBlock) {
    const int m = int(std::min<std::ptrdiff_t>(kSubBlock, b.m - first));
    load_sub_block(s, b, first, m, Tm, qf, valid);
    body_frame_com(s.robot, qf, m, com);
    for (int i = 0; i < m; ++i) {
      T* out = b.real(0) + 3 * (first + i);
      const double* M = Tm + 16 * i;
      for (int r = 0; r < 3; ++r) {
        const double v = M[4 * r + 3] + M[4 * r] * com[3 * i] + M[4 * r + 1] * com[3 * i + 1] + M[4 * r + 2] * com[3 * i + 2];
        out[r] = valid[i] ? T(v) : T(quiet_nan<double>());
      }
    }
  }
}

// The standing statics of each sample, in the body frame where only gravity's direction depends on
// the pose: tau_l = G_l - J_l^T f_l (spotkin/dynamics/statics.hpp), the forces then turned to the world.
template <typename T>
void standing_kernel(const void* c, const binder::Block<T>& b) {
  const StaticsCall& s = binder::context<StaticsCall>(c);
  const Body& body = s.robot.body;
  const int L = body.n_legs(), nv = s.robot.nv();
  constexpr double nan = quiet_nan<double>();
  double Tm[16 * kSubBlock], qf[kMaxQ * kSubBlock], com[3 * kSubBlock], g_body[3 * kSubBlock];
  double gravity_torques[kMaxQ * kSubBlock];
  bool valid[kSubBlock];
  for (std::ptrdiff_t first = 0; first < b.m; first += kSubBlock) {
    const int m = int(std::min<std::ptrdiff_t>(kSubBlock, b.m - first));
    load_sub_block(s, b, first, m, Tm, qf, valid);
    for (int i = 0; i < m; ++i) {  // g_body = R^T g
      const double* M = Tm + 16 * i;
      for (int r = 0; r < 3; ++r)
        g_body[3 * i + r] = valid[i] ? M[r] * s.gravity[0] + M[4 + r] * s.gravity[1] + M[8 + r] * s.gravity[2] : 0.0;
    }
    body_frame_com(s.robot, qf, m, com);
    with_model<double>(s.robot.floating, [&](const auto& model) {
      dynamics::floating_rnea_k(model, Rows<double>{qf, s.robot.nq()}, nullptr, nullptr, Rows<double>{g_body, 3},
                                gravity_torques, 0, m, false);
    });
    for (int i = 0; i < m; ++i) {
      const std::ptrdiff_t k = first + i;
      T* tau_out = b.real(0) + 3 * L * k;
      T* force_out = b.real(1) + 3 * L * k;
      std::int8_t* status = b.status(2) + k;
      T* margin = b.real(3) + k;
      std::uint8_t on[dynamics::kMaxFeet];
      bool ok = valid[i];
      for (int l = 0; l < L; ++l) {
        const double v = b.in[2] ? double(b.in[2][b.stride[2] * k + l]) : 1.0;
        on[l] = v != 0.0;
        ok = ok && (v == 0.0 || v == 1.0);  // a NaN in the mask: invalid, as any non-finite input
      }
      if (!ok) {
        std::fill(tau_out, tau_out + 3 * L, T(nan));
        std::fill(force_out, force_out + 3 * L, T(nan));
        *status = static_cast<std::int8_t>(dynamics::Stance::InvalidInput);
        *margin = T(nan);
        continue;
      }
      double feet[3 * dynamics::kMaxFeet], jacobians[9 * dynamics::kMaxFeet], leg_gravity[3 * dynamics::kMaxFeet];
      const double* joints = qf + s.robot.nq() * i + 7;
      for (int l = 0; l < L; ++l) {  // the feet in the body frame: hip + leg FK, and d foot / d q_l
        const auto& col = body.columns[std::size_t(l)];
        const double q_leg[3] = {joints[col[0]], joints[col[1]], joints[col[2]]};
        body.legs[std::size_t(l)].forward(q_leg, feet + 3 * l);
        body.legs[std::size_t(l)].jacobian(q_leg, jacobians + 9 * l);
        for (int r = 0; r < 3; ++r) {
          feet[3 * l + r] += body.hips[std::size_t(l)][std::size_t(r)];
          leg_gravity[3 * l + r] = gravity_torques[nv * i + 6 + col[std::size_t(r)]];
        }
      }
      double tau[3 * dynamics::kMaxFeet], forces[3 * dynamics::kMaxFeet], margin_value;
      dynamics::standing_sample(L, com + 3 * i, s.robot.mass, feet, jacobians, leg_gravity, on, g_body + 3 * i, tau,
                                forces, status, &margin_value);
      const double* M = Tm + 16 * i;
      for (int l = 0; l < L; ++l) {
        const auto& col = body.columns[std::size_t(l)];
        const double* f = forces + 3 * l;
        for (int r = 0; r < 3; ++r) {
          tau_out[col[std::size_t(r)]] = T(tau[3 * l + r]);
          force_out[3 * l + r] = T(M[4 * r] * f[0] + M[4 * r + 1] * f[1] + M[4 * r + 2] * f[2]);  // R f
        }
      }
      *margin = T(margin_value);
    }
  }
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
    return Op({statics_pose(), statics_q(r)}, {Out("com", {3})}, 600.0,
              [](const void* c, const auto& b) { com_kernel(c, b); });
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
              {Out("tau", {3 * L}), Out("forces", {L, 3}), Out("status", {}, Kind::Code), Out("margin", {})},
              2000.0, [](const void* c, const auto& b) { standing_kernel(c, b); });
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
  if (floating.f64.nq() > kMaxQ)
    throw py::value_error("a robot's statics take at most " + std::to_string(kMaxQ - 7) + " joints");
  if (body.n_legs() > dynamics::kMaxFeet)
    throw py::value_error("a robot's statics take at most " + std::to_string(dynamics::kMaxFeet) + " legs");
  if (!(mass > 0.0) || !std::isfinite(mass)) throw py::value_error("mass must be finite and positive");
  return RobotStatics{body, floating, mass, n_arm};
}

}  // namespace

void bind_statics(py::module_& m) {
  py::class_<RobotStatics>(m, "RobotStatics")
      .def(py::init(&make_robot_statics), py::arg("body"), py::arg("floating"), py::arg("mass"), py::keep_alive<1, 2>(),
           py::keep_alive<1, 3>())
      .def("com", &robot_com, py::arg("body_pose"), py::arg("sequence"), py::arg("q"), py::arg("out") = py::none())
      .def("standing", &robot_standing, py::arg("body_pose"), py::arg("sequence"), py::arg("q"),
           py::arg("stance"), py::arg("gravity"), py::arg("out") = py::none());
  m.def("standing_torques", &standing_torques, py::arg("com"), py::arg("mass"), py::arg("feet"),
        py::arg("foot_jacobians"), py::arg("leg_gravity"), py::arg("stance"), py::arg("gravity"),
        "Minimum-norm stance forces and leg torques, per sample of flat (N, ...) arrays (see "
        "spotkin/dynamics/statics.hpp).");
}

}  // namespace spotkin::bindings
