// Bindings of the gait planner (spotkin/motion/gait_plan.hpp): _core.plan_gait plans every command
// of a batch, one command per task on the threads, with the GIL released. The façade
// (spotkin.motion.plan) checks the user's arguments, resolves the gait into its numbers and
// broadcasts the commands; here the arrays' shapes are checked again, as any caller's.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "numpy_boundary.hpp"
#include "robot_statics.hpp"
#include "spotkin/motion/controller.hpp"
#include "spotkin/motion/gait_plan.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

py::tuple plan_gait(const RobotStatics& r, py::handle gait_obj, py::handle velocity_obj,
                    py::handle attitude_obj, py::ssize_t ticks, double rate, py::handle times_obj,
                    py::handle gaits_obj, py::handle velocities_obj) {
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
  // outputs from the buffer cache (large ones reuse freed buffers: no page faults on a rerun)
  const Shape lead{B, ticks};
  auto pose = new_array<double>(lead, {6}), feet = new_array<double>(lead, {kLegs, 3}),
       q = new_array<double>(lead, {W}), qd = new_array<double>(lead, {W}),
       tau = new_array<double>(lead, {W}), margin = new_array<double>(lead, {}),
       residual = new_array<double>(lead, {6});
  auto contact = new_array<bool>(lead, {kLegs}), shortened = new_array<bool>(lead, {});
  auto status = new_array<std::int8_t>(lead, {});
  const motion::PlanRows rows{pose.mutable_data(),      feet.mutable_data(),
                              contact.mutable_data(),   q.mutable_data(),
                              qd.mutable_data(),        tau.mutable_data(),
                              status.mutable_data(),    margin.mutable_data(),
                              shortened.mutable_data(), residual.mutable_data()};
  const double* v = velocity.data();
  const double att[2] = {attitude.data()[0], attitude.data()[1]};
  // the changes (time, gait numbers or a NaN row, velocity or a NaN row), in time order (stable)
  std::vector<motion::GaitNumbers> change_gaits;
  std::vector<std::array<double, 3>> change_velocities;
  std::vector<motion::PlanChange> changes;
  if (!times_obj.is_none()) {
    const auto times = exact(times_obj, "change_times", {-1});
    const py::ssize_t k = times.shape(0);
    const auto gaits = exact(gaits_obj, "change_gaits", {k, motion::kGaitNumbers});
    const auto velocities = exact(velocities_obj, "change_velocities", {k, 3});
    change_gaits.resize(std::size_t(k));
    change_velocities.resize(std::size_t(k));
    for (py::ssize_t i = 0; i < k; ++i) {
      const double* g = gaits.data() + motion::kGaitNumbers * i;
      const double* w = velocities.data() + 3 * i;
      if (!std::isfinite(times.data()[i])) throw py::value_error("change_times must be finite");
      std::copy(g, g + motion::kGaitNumbers, change_gaits[std::size_t(i)].v);
      std::copy(w, w + 3, change_velocities[std::size_t(i)].begin());
      const bool has_gait = std::isfinite(g[0]), has_velocity = std::isfinite(w[0] + w[1] + w[2]);
      if (has_gait &&
          (!(g[motion::kPeriod] > 0.0) || !(g[motion::kDuty] > 0.0 && g[motion::kDuty] <= 1.0)))
        throw py::value_error("a changed gait's period must be > 0 and its duty in (0, 1]");
      changes.push_back({times.data()[i], has_gait ? &change_gaits[std::size_t(i)] : nullptr,
                         has_velocity ? change_velocities[std::size_t(i)].data() : nullptr});
    }
    std::stable_sort(
        changes.begin(), changes.end(),
        [](const motion::PlanChange& a, const motion::PlanChange& b) { return a.time < b.time; });
  }
  {
    py::gil_scoped_release release;
    on_robot(r, ticks, [&](const auto& robot) {
      // one command's whole plan an item: chunks may start at any command (alignment 1)
      parallel_for(
          B, 1,
          [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
            for (std::ptrdiff_t b = begin; b < end; ++b) {
              const std::ptrdiff_t n = b * ticks;
              const motion::PlanRows at{rows.pose + 6 * n,        rows.feet + W * n,
                                        rows.contact + kLegs * n, rows.q + W * n,
                                        rows.qd + W * n,          rows.tau + W * n,
                                        rows.status + n,          rows.margin + n,
                                        rows.shortened + n,       rows.residual + 6 * n};
              motion::plan_command(robot, gait, v + 3 * b, att, ticks, rate, at, changes.data(),
                                   int(changes.size()));
            }
          },
          1);
    });
  }
  return py::make_tuple(pose, feet, contact, q, qd, tau, status, margin, shortened, residual);
}

// ---------------------------------------------------------------- the closed-loop controller

// The controller's compiled part: the robot, its constants, its gaits (resolved, by index) and each
// robot's state between ticks (created by the first step, dropped by reset).
struct ControllerCore {
  const RobotStatics& robot;
  motion::ControllerConfig config;
  std::vector<motion::GaitNumbers> gaits;
  std::vector<motion::ControllerMemory> memories;
  std::vector<motion::ControllerOutput> last;  // the last step's outputs, for details()
  std::vector<double> seconds;                 // and each robot's compiled time
  long long ticks = 0, clipped = 0;            // robot-ticks, and those with a clipped feedforward
};


std::unique_ptr<ControllerCore> make_controller(const RobotStatics& r, double h, double body_omega,
                                                py::handle body_inertia, py::handle kp,
                                                py::handle kd, py::handle stance_kp,
                                                py::handle stance_kd, py::handle effort,
                                                py::handle leg_inertia, py::handle attitude) {
  using motion::kLegs;
  if (r.body.n_legs() != kLegs)
    throw py::value_error("the gait controller takes a quadruped (4 legs)");
  auto core = std::unique_ptr<ControllerCore>(new ControllerCore{r, {}, {}, {}, {}, {}, 0, 0});
  motion::ControllerConfig& c = core->config;
  c.h = h, c.mass = r.mass, c.body_omega = body_omega;
  const py::ssize_t W = 3 * kLegs;
  copy_exact(body_inertia, "body_inertia", {3, 3}, c.body_inertia);
  copy_exact(kp, "kp", {W}, c.kp);
  copy_exact(kd, "kd", {W}, c.kd);
  copy_exact(stance_kp, "stance_kp", {W}, c.stance_kp);
  copy_exact(stance_kd, "stance_kd", {W}, c.stance_kd);
  copy_exact(effort, "effort", {W}, c.effort);
  copy_exact(leg_inertia, "leg_inertia", {kLegs, 3, 3}, &c.leg_inertia[0][0]);
  copy_exact(attitude, "attitude", {2}, c.attitude);
  if (!(h > 0.0) || !std::isfinite(h) || !std::isfinite(body_omega))
    throw py::value_error("h must be finite and > 0, and body_omega finite");
  return core;
}

int add_gait(ControllerCore& core, py::handle numbers) {
  motion::GaitNumbers gait;
  copy_exact(numbers, "gait", {motion::kGaitNumbers}, gait.v);
  if (!(gait[motion::kPeriod] > 0.0) || !(gait[motion::kDuty] > 0.0 && gait[motion::kDuty] <= 1.0))
    throw py::value_error("the gait's period must be > 0 and its duty in (0, 1]");
  core.gaits.push_back(gait);
  return int(core.gaits.size()) - 1;
}

// One field of every robot's output, as a (B, trailing...) array, or (trailing...) for one robot
// given as single rows.
template <typename Member>
auto gather(const std::vector<motion::ControllerOutput>& outs, const Shape& trailing, Member member,
            bool one_row = false) {
  using Field = std::remove_const_t<
      std::remove_all_extents_t<std::remove_reference_t<decltype(outs[0].*member)>>>;
  Shape shape;
  if (!one_row) shape.push_back(py::ssize_t(outs.size()));
  shape.insert(shape.end(), trailing.begin(), trailing.end());
  py::array_t<Field> arr(shape);
  Field* dst = arr.mutable_data();
  const std::size_t width = sizeof(outs[0].*member) / sizeof(Field);
  for (std::size_t b = 0; b < outs.size(); ++b) {
    const Field* src = reinterpret_cast<const Field*>(&(outs[b].*member));
    std::copy(src, src + width, dst + width * b);
  }
  return arr;
}

// Why B robots at time t do not fit the controller's memory (other robots, or time going back);
// empty when they fit.
std::string batch_misfit(const ControllerCore& core, double t, py::ssize_t B) {
  if (!core.memories.empty() && py::ssize_t(core.memories.size()) != B)
    return "the batch changed from " + std::to_string(core.memories.size()) + " to " +
           std::to_string(B) + " robots: call reset() first";
  for (const auto& memory : core.memories)
    if (memory.started && t - memory.t < -1e-9)
      return "t went backwards: " + std::to_string(t) + " after " + std::to_string(memory.t) +
             ": call reset() first";
  return {};
}

// One tick of B robots (rows of the state's fields, checked), into core.last.
void run_ticks(ControllerCore& core, double t, int start_gait, int new_gait, const double* pos,
               const double* quat, const double* lin, const double* ang, const double* q,
               const double* qd, const bool* contact, const double* cmd, py::ssize_t B) {
  using motion::kLegs;
  constexpr py::ssize_t W = 3 * kLegs;
  if (core.memories.empty()) core.memories.resize(std::size_t(B));
  std::vector<motion::ControllerOutput>& outs = core.last;
  outs.resize(static_cast<std::size_t>(B));
  core.seconds.resize(static_cast<std::size_t>(B));
  double* wall = core.seconds.data();
  {
    ReleaseGilFor release(B);
    on_robot(core.robot, 1, [&](const auto& robot) {
      parallel_for(B, 64, [&](std::ptrdiff_t begin, std::ptrdiff_t end) {
        for (std::ptrdiff_t b = begin; b < end; ++b) {
          const auto start = std::chrono::steady_clock::now();
          const motion::ControllerInput in{
              t,           pos + 3 * b, quat + 4 * b, lin + 3 * b,
              ang + 3 * b, q + W * b,   qd + W * b,   contact ? contact + kLegs * b : nullptr,
              cmd + 3 * b};
          motion::controller_tick(robot, core.config, core.gaits.data(), start_gait, new_gait,
                                  core.memories[std::size_t(b)], in, outs[std::size_t(b)]);
          wall[b] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
      });
    });
  }
  for (const auto& out : outs) {
    bool any = false;
    for (bool c : out.clipped) any = any || c;
    core.clipped += any;
  }
  core.ticks += B;
}

// One tick of every robot: the state's arrays (B, width) each, contact (B, 4) bool or None, the
// command (B, 3). Returns the command (q, qd, tau, kp, kd, contact), (B, ...) arrays each, or
// (...) ones when the state came as single rows; details() gives the rest of the tick.
py::tuple controller_step(ControllerCore& core, double t, int start_gait, int new_gait,
                          py::handle position, py::handle quaternion, py::handle linear_velocity,
                          py::handle angular_velocity, py::handle q_obj, py::handle qd_obj,
                          py::handle contact_obj, py::handle command) {
  using motion::kLegs;
  constexpr py::ssize_t W = 3 * kLegs;
  if (!std::isfinite(t)) throw py::value_error("t must be finite, got " + std::to_string(t));
  const int n_gaits = int(core.gaits.size());
  if (start_gait < 0 || start_gait >= n_gaits || new_gait < -1 || new_gait >= n_gaits)
    throw py::value_error("gait index out of range");
  // rows (B, width), or one row (width,) for B = 1; finite
  py::ssize_t B = -1;
  bool one_row = false;  // the state given as single rows (width,): the command's arrays are too
  auto rows = [&](py::handle obj, const char* name, py::ssize_t width, const char* what,
                  const char* hint = "") {
    auto arr = contiguous<double>(as_real_array(obj, name));
    const bool one = arr.ndim() == 1 && arr.shape(0) == width;
    const bool many = arr.ndim() == 2 && arr.shape(1) == width && (B < 0 || arr.shape(0) == B);
    if (!one && !many)
      throw py::value_error(std::string(name) + " must have shape (" +
                            (B < 0 ? std::string("B") : std::to_string(B)) + ", " +
                            std::to_string(width) + ") or (" + std::to_string(width) + ",), got " +
                            format_shape(Shape(arr.shape(), arr.shape() + arr.ndim())) + hint);
    const py::ssize_t count = one ? 1 : arr.shape(0);
    if (B < 0) B = count;
    if (count != B)
      throw py::value_error(std::string(name) + " has " + std::to_string(count) + " rows, not " +
                            std::to_string(B));
    for (py::ssize_t k = 0; k < arr.size(); ++k)
      if (!std::isfinite(arr.data()[k]))
        throw py::value_error(std::string(name) + " must be finite" + what + ", got NaN or Inf");
    return arr;
  };
  const auto pos = rows(position, "state.position", 3, "");
  one_row = pos.ndim() == 1;
  const auto quat = rows(quaternion, "state.quaternion", 4, "");
  for (py::ssize_t b = 0; b < B; ++b) {  // a rotation: any non-zero length (scaled), not zero
    const double* x = quat.data() + 4 * b;
    if (!(x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] > 1e-12))
      throw py::value_error(
          "state.quaternion must be a rotation (x, y, z, w) of non-zero length, got a zero one");
  }
  const auto lin = rows(linear_velocity, "state.linear_velocity", 3, "");
  const auto ang = rows(angular_velocity, "state.angular_velocity", 3, "");
  const auto q = rows(q_obj, "state.q", W, "", ": 12 joints, in robot.leg_joint_names order");
  const auto qd = rows(qd_obj, "state.qd", W, "", ": 12 joints, in robot.leg_joint_names order");
  const auto cmd = rows(command, "velocity", 3, " (vx, vy, yaw rate)");
  py::array_t<bool, py::array::c_style | py::array::forcecast> contact;
  if (!contact_obj.is_none()) {
    contact = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(contact_obj);
    const bool fits =
        contact && ((contact.ndim() == 1 && B == 1 && contact.shape(0) == kLegs) ||
                    (contact.ndim() == 2 && contact.shape(0) == B && contact.shape(1) == kLegs));
    if (!fits)
      throw py::value_error("state.contact must have shape (" + std::to_string(B) + ", 4)");
  }
  if (std::string misfit = batch_misfit(core, t, B); !misfit.empty()) throw py::value_error(misfit);
  run_ticks(core, t, start_gait, new_gait, pos.data(), quat.data(), lin.data(), ang.data(),
            q.data(), qd.data(), contact_obj.is_none() ? nullptr : contact.data(), cmd.data(), B);
  using Out = motion::ControllerOutput;
  const std::vector<motion::ControllerOutput>& outs = core.last;
  return py::make_tuple(gather(outs, {W}, &Out::q, one_row), gather(outs, {W}, &Out::qd, one_row),
                        gather(outs, {W}, &Out::tau, one_row), gather(outs, {W}, &Out::kp, one_row),
                        gather(outs, {W}, &Out::kd, one_row),
                        gather(outs, {kLegs}, &Out::contact, one_row));
}

// ---------------------------------------------------------------- one robot, as a control loop
// calls

// The JointCommand class (spotkin.motion.JointCommand), registered by the façade at import: the
// one-robot step builds its instances without calling its __init__ (a frozen dataclass's setattrs).
PyObject*& joint_command_type() {
  static PyObject* type = nullptr;  // never released: it lives as long as the module
  return type;
}

// obj's data when it is a (width,) array of NumPy type `type` to read in place (in_place_type);
// else null.
const void* row_of(PyObject* obj, int type, Py_intptr_t width) {
  if (in_place_type(obj) != type) return nullptr;
  const auto* a = py::detail::array_proxy(obj);
  return a->nd == 1 && a->dimensions[0] == width ? a->data : nullptr;
}

// A new (n,) array of NumPy type `type`, uninitialised.
PyObject* new_row(int type, Py_intptr_t n) {
  auto& numpy = py::detail::npy_api::get();
  return numpy.PyArray_NewFromDescr_(numpy.PyArray_Type_, numpy.PyArray_DescrFromType_(type), 1, &n,
                                     nullptr, nullptr, 0, nullptr);
}

// GaitController.step for one robot whose state holds single rows: the state's fields read in
// place (float64 rows of their widths, C-contiguous), velocity three Python numbers or a float64
// row, contact None or four bools; every value finite, the quaternion non-zero, the gait indices
// valid, the controller holding one robot or none, and t not going back. Then one tick and a
// JointCommand of (12,) and (4,) arrays. Anything else returns None, and the general step converts,
// checks and says what is wrong: the same tick either way.
py::object controller_step_one(ControllerCore& core, py::handle t_obj, int start_gait, int new_gait,
                               py::handle state, py::handle velocity) {
  using motion::kLegs;
  using api = py::detail::npy_api;
  constexpr Py_intptr_t W = 3 * kLegs;
  PyObject* type = joint_command_type();
  if (!type || !PyFloat_Check(t_obj.ptr())) return py::none();
  const double t = PyFloat_AS_DOUBLE(t_obj.ptr());
  const int n_gaits = int(core.gaits.size());
  if (!std::isfinite(t) || start_gait < 0 || start_gait >= n_gaits || new_gait < -1 ||
      new_gait >= n_gaits || !batch_misfit(core, t, 1).empty())
    return py::none();
  static PyObject* names[7] = {PyUnicode_InternFromString("position"),
                               PyUnicode_InternFromString("quaternion"),
                               PyUnicode_InternFromString("linear_velocity"),
                               PyUnicode_InternFromString("angular_velocity"),
                               PyUnicode_InternFromString("q"),
                               PyUnicode_InternFromString("qd"),
                               PyUnicode_InternFromString("contact")};
  static constexpr Py_intptr_t widths[6] = {3, 4, 3, 3, W, W};
  py::object fields[7];  // the state's attributes, held while the tick reads them
  const double* rows[6];
  for (int k = 0; k < 7; ++k) {
    fields[k] = py::reinterpret_steal<py::object>(PyObject_GetAttr(state.ptr(), names[k]));
    if (!fields[k]) return PyErr_Clear(), py::none();
  }
  for (int k = 0; k < 6; ++k)
    if (!(rows[k] =
              static_cast<const double*>(row_of(fields[k].ptr(), api::NPY_DOUBLE_, widths[k]))))
      return py::none();
  const bool* contact = nullptr;
  if (!fields[6].is_none() &&
      !(contact = static_cast<const bool*>(row_of(fields[6].ptr(), api::NPY_BOOL_, kLegs))))
    return py::none();
  double command[3];
  PyObject* v = velocity.ptr();
  if (PyTuple_CheckExact(v) || PyList_CheckExact(v)) {
    if (PySequence_Fast_GET_SIZE(v) != 3) return py::none();
    for (int k = 0; k < 3; ++k)
      if (!python_number(PySequence_Fast_ITEMS(v)[k], command[k])) return py::none();
  } else if (const void* row = row_of(v, api::NPY_DOUBLE_, 3)) {
    std::copy_n(static_cast<const double*>(row), 3, command);
  } else {
    return py::none();
  }
  double sum = command[0] + command[1] + command[2];  // NaN or Inf anywhere makes it NaN
  for (int k = 0; k < 6; ++k)
    for (Py_intptr_t j = 0; j < widths[k]; ++j) sum += rows[k][j];
  const double* x = rows[1];
  if (!std::isfinite(sum) || !(x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] > 1e-12))
    return py::none();
  run_ticks(core, t, start_gait, new_gait, rows[0], rows[1], rows[2], rows[3], rows[4], rows[5],
            contact, command, 1);
  const motion::ControllerOutput& out = core.last[0];
  const double* values[5] = {out.q, out.qd, out.tau, out.kp, out.kd};
  static PyObject* command_names[6] = {
      PyUnicode_InternFromString("q"),   PyUnicode_InternFromString("qd"),
      PyUnicode_InternFromString("tau"), PyUnicode_InternFromString("kp"),
      PyUnicode_InternFromString("kd"),  PyUnicode_InternFromString("contact")};
  auto* cls = reinterpret_cast<PyTypeObject*>(type);
  auto made = py::reinterpret_steal<py::object>(cls->tp_alloc(cls, 0));
  if (!made) throw py::error_already_set();
  for (int k = 0; k < 6; ++k) {
    auto row = py::reinterpret_steal<py::object>(
        new_row(k < 5 ? api::NPY_DOUBLE_ : api::NPY_BOOL_, k < 5 ? W : kLegs));
    if (!row) throw py::error_already_set();
    void* data = py::detail::array_proxy(row.ptr())->data;
    if (k < 5)
      std::copy(values[k], values[k] + W, static_cast<double*>(data));
    else
      std::copy(out.contact, out.contact + kLegs, static_cast<bool*>(data));
    // object.__setattr__, as the frozen dataclass's own __init__ sets its fields
    if (PyObject_GenericSetAttr(made.ptr(), command_names[k], row.ptr()) != 0)
      throw py::error_already_set();
  }
  return made;
}

// The last step's details, (B, ...) arrays by name (the façade's `last`).
py::dict controller_details(const ControllerCore& core) {
  using motion::kLegs;
  constexpr py::ssize_t W = 3 * kLegs;
  const auto& outs = core.last;
  const py::ssize_t B = py::ssize_t(outs.size());
  py::dict result;
  auto put = [&](const char* name, const Shape& trailing, auto member) {
    result[name] = gather(outs, trailing, member);
  };
  using Out = motion::ControllerOutput;
  put("q", {W}, &Out::q);
  put("qd", {W}, &Out::qd);
  put("tau", {W}, &Out::tau);
  put("kp", {W}, &Out::kp);
  put("kd", {W}, &Out::kd);
  put("contact", {kLegs}, &Out::contact);
  put("body_pose", {6}, &Out::body_pose);
  put("feet", {kLegs, 3}, &Out::feet);
  put("loaded", {kLegs}, &Out::loaded);
  put("clipped", {W}, &Out::clipped);
  put("shortened", {}, &Out::shortened);
  put("reaching", {kLegs}, &Out::reaching);
  put("margin", {}, &Out::margin);
  put("measured_margin", {}, &Out::measured_margin);
  put("forces", {kLegs, 3}, &Out::forces);
  put("residual", {6}, &Out::residual);
  put("wrench", {6}, &Out::wrench);
  put("ground", {3}, &Out::ground);
  put("status", {}, &Out::status);
  result["time"] = py::array_t<double>(B, core.seconds.data());
  return result;
}

}  // namespace

void bind_motion(py::module_& m) {
  m.def("plan_gait", &plan_gait, py::arg("robot"), py::arg("gait"), py::arg("velocity"),
        py::arg("attitude"), py::arg("ticks"), py::arg("rate"),
        py::arg("change_times") = py::none(), py::arg("change_gaits") = py::none(),
        py::arg("change_velocities") = py::none(),
        "Plans of a quadruped's walk for commands (B, 3): (pose, feet, contact, q, qd, tau, "
        "status, margin, "
        "shortened, residual), each (B, ticks, ...). gait: the resolved gait's numbers (44,); "
        "changes: "
        "times (k,), gaits (k, 44) and velocities (k, 3), a NaN row where unchanged.");
  m.def(
      "_register_joint_command",
      [](py::handle type) {
        if (!PyType_Check(type.ptr()))
          throw py::type_error("_register_joint_command takes a class");
        PyObject*& slot = joint_command_type();
        Py_XDECREF(slot);
        slot = py::reinterpret_borrow<py::object>(type).release().ptr();
      },
      py::arg("type"), "Registers spotkin.motion.JointCommand, which the one-robot step returns.");
  py::class_<ControllerCore>(m, "GaitControllerCore")
      .def(py::init(&make_controller), py::arg("robot"), py::arg("h"), py::arg("body_omega"),
           py::arg("body_inertia"), py::arg("kp"), py::arg("kd"), py::arg("stance_kp"),
           py::arg("stance_kd"), py::arg("effort"), py::arg("leg_inertia"), py::arg("attitude"),
           py::keep_alive<1, 2>())
      .def("add_gait", &add_gait, py::arg("gait"))
      .def("reset",
           [](ControllerCore& c) {
             c.memories.clear(), c.last.clear(), c.seconds.clear();
             c.ticks = c.clipped = 0;
           })
      .def_property_readonly("ticks", [](const ControllerCore& c) { return c.ticks; })
      .def_property_readonly("clipped", [](const ControllerCore& c) { return c.clipped; })
      .def("details", &controller_details)
      .def_property_readonly("robots", [](const ControllerCore& c) { return c.memories.size(); })
      .def("step_one", &controller_step_one, py::arg("t"), py::arg("start_gait"),
           py::arg("new_gait"), py::arg("state"), py::arg("velocity"),
           "One robot's tick (its state in single rows), as a JointCommand; None when the state or "
           "the command needs the general step's conversions or checks.")
      .def("step", &controller_step, py::arg("t"), py::arg("start_gait"), py::arg("new_gait"),
           py::arg("position"), py::arg("quaternion"), py::arg("linear_velocity"),
           py::arg("angular_velocity"), py::arg("q"), py::arg("qd"), py::arg("contact"),
           py::arg("velocity"));
}

}  // namespace spotkin::bindings
