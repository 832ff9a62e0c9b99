// Bindings for spotkin::trajectory: a planned point-to-point joint trajectory and a
// Cartesian waypoint path, each sampled in batches over time with the GIL released.
#include "spotkin/trajectory.hpp"

#include <array>
#include <cmath>
#include <type_traits>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "dispatch.hpp"
#include "binder.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace {

namespace tj = spotkin::trajectory;

constexpr double kNsPerJointSample = 10.0;  // a 6-axis sample
constexpr double kNsPerPathSample = 60.0;   // two quaternion exps per sample

// The path sampler compiled per CPU level (its sin/cos loop vectorises).
SPOTKIN_CLONES((template <typename T>), void, sample_path_kernel, (const tj::WaypointPath& path, tj::PoseForm form, const T* t, T* pose,
                                             T* twist, std::ptrdiff_t n), (path, form, t, pose, twist, n),
  tj::sample(path, form, t, pose, twist, n);
)

Shape shape_of(const py::array& arr) { return Shape(arr.shape(), arr.shape() + arr.ndim()); }

// A 1-D float64 vector of `n` entries (n < 0: any length); a scalar broadcasts when allowed.
std::vector<double> vector_arg(py::handle obj, const char* name, py::ssize_t n, bool scalar_ok) {
  py::array arr = contiguous<double>(as_real_array(obj, name));
  std::vector<double> out;
  if (arr.ndim() == 0 && scalar_ok && n >= 0) {
    out.assign(static_cast<std::size_t>(n), *static_cast<const double*>(arr.data()));
  } else if (arr.ndim() == 1 && (n < 0 || arr.shape(0) == n)) {
    const auto* d = static_cast<const double*>(arr.data());
    out.assign(d, d + arr.shape(0));
  } else {
    std::string expected = n < 0 ? "(n,)" : format_shape({n});
    if (scalar_ok) expected = "a scalar or " + expected;
    throw py::value_error(std::string(name) + " must be " + expected + ", got shape " +
                          format_shape(shape_of(arr)));
  }
  return out;
}

void require_finite(const std::vector<double>& v, const char* name) {
  for (double x : v)
    if (!std::isfinite(x)) throw py::value_error(std::string(name) + " must be finite (no NaN or inf)");
}

void require_positive(const std::vector<double>& v, const char* name) {
  for (double x : v)
    if (!(x > 0.0) || !std::isfinite(x))
      throw py::value_error(std::string(name) + " must be positive and finite, got " + std::to_string(x));
}

// The plan's inputs checked here (shapes, finite, positive rates); planned by the core.
class PointToPointCore {
 public:
  PointToPointCore(py::handle q0_obj, py::handle qf_obj, py::handle vmax_obj, py::handle amax_obj, int profile)
      : plan_(checked_plan(q0_obj, qf_obj, vmax_obj, amax_obj, profile)) {}

  // t (...) -> (q, qd, qdd), each (..., n), in t's precision.
  py::object sample(py::handle t, py::handle out) const {
    const auto n = static_cast<py::ssize_t>(plan_.q0.size());
    const binder::Op op({binder::Arg("t", {})}, {binder::Out("q", {n}), binder::Out("qd", {n}), binder::Out("qdd", {n})},
                        kNsPerJointSample, [](const void* c, const auto& b) {
                          // through a member function: inlined into the lambda, the loop measured 18 % slower
                          binder::context<PointToPointCore>(c).sample_block(b.in[0], b.real(0), b.real(1), b.real(2),
                                                                            b.m);
                        });
    return binder::call(op, this, {t}, out);
  }

  template <typename T>
  void sample_block(const T* t, T* q, T* qd, T* qdd, std::ptrdiff_t count) const {
    tj::sample(plan_.view(T{}), t, q, qd, qdd, count);
  }

  tj::PointToPointPlan plan_;

 private:
  static tj::PointToPointPlan checked_plan(py::handle q0_obj, py::handle qf_obj, py::handle vmax_obj,
                                           py::handle amax_obj, int profile) {
    if (profile < 0 || profile > 2) throw py::value_error("profile must be 0 (cubic), 1 (quintic) or 2 (trapezoid)");
    std::vector<double> q0 = vector_arg(q0_obj, "q0", -1, false);
    const auto n = static_cast<py::ssize_t>(q0.size());
    py::array qf_arr = as_real_array(qf_obj, "qf");
    if (qf_arr.ndim() != 1 || qf_arr.shape(0) != n)
      throw py::value_error("qf must have the shape of q0, " + format_shape({n}) + ", got " +
                            format_shape(shape_of(qf_arr)));
    std::vector<double> qf = vector_arg(qf_obj, "qf", n, false);
    const std::vector<double> vmax = vector_arg(vmax_obj, "vmax", n, true), amax = vector_arg(amax_obj, "amax", n, true);
    require_finite(q0, "q0");
    require_finite(qf, "qf");
    require_positive(vmax, "vmax");
    require_positive(amax, "amax");
    return tj::PointToPointPlan(static_cast<tj::Profile>(profile), std::move(q0), std::move(qf), vmax, amax);
  }
};

py::array_t<double> to_array(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// The timing and geometry are planned by the Python façade (spotkin.trajectory); checked here.
class WaypointPathCore {
 public:
  WaypointPathCore(py::handle times, py::handle blends, py::handle positions, py::handle quaternions,
                   py::handle linear, py::handle angular)
      : data_(checked_data(times, blends, positions, quaternions, linear, angular)) {}

  py::object sample(py::handle t, int form, bool with_twist) const {
    if (form != 0 && form != 1) throw py::value_error("form must be 0 (matrix) or 1 (quaternion)");
    const tj::WaypointPath path = data_.view();
    struct Sampling {
      const tj::WaypointPath& path;
      tj::PoseForm form;
    };
    const Sampling context{path, static_cast<tj::PoseForm>(form)};
    const binder::Out pose = form == 0 ? binder::Out("pose", {4, 4}) : binder::Out("pose", {7});
    auto kernel = [](const void* c, const auto& b) {
      const Sampling& s = binder::context<Sampling>(c);
      sample_path_kernel(s.path, s.form, b.in[0], b.real(0), b.out[1] ? b.real(1) : nullptr, b.m);
    };
    if (!with_twist) return binder::call(binder::Op({binder::Arg("t", {})}, {pose}, kNsPerPathSample, kernel), &context, {t}, py::none());
    return binder::call(binder::Op({binder::Arg("t", {})}, {pose, binder::Out("twist", {6})}, kNsPerPathSample, kernel),
                        &context, {t}, py::none());
  }

  tj::WaypointPathData data_;

 private:
  static tj::WaypointPathData checked_data(py::handle times_obj, py::handle blends_obj, py::handle positions,
                                           py::handle quaternions, py::handle linear, py::handle angular) {
    std::vector<double> times = vector_arg(times_obj, "times", -1, false);
    const auto W = static_cast<py::ssize_t>(times.size());
    if (W < 1) throw py::value_error("times must hold at least one waypoint");
    std::vector<double> blends = vector_arg(blends_obj, "blends", W, false), p = rows(positions, "positions", W, 3),
                        q = rows(quaternions, "quaternions", W, 4), v = rows(linear, "linear", W - 1, 3),
                        w = rows(angular, "angular", W - 1, 3);
    for (const auto* x : {&times, &blends, &p, &q, &v, &w}) require_finite(*x, "waypoint path data");
    return tj::WaypointPathData(std::move(times), std::move(blends), std::move(p), std::move(q), std::move(v),
                                std::move(w));
  }
  static std::vector<double> rows(py::handle obj, const char* name, py::ssize_t n, py::ssize_t width) {
    py::array arr = contiguous<double>(as_real_array(obj, name));
    if (arr.ndim() != 2 || arr.shape(0) != n || arr.shape(1) != width)
      throw py::value_error(std::string(name) + " must have shape " + format_shape({n, width}) + ", got " +
                            format_shape(shape_of(arr)));
    const auto* d = static_cast<const double*>(arr.data());
    return std::vector<double>(d, d + n * width);
  }
};

}  // namespace

void bind_trajectory(py::module_& m) {
  py::class_<PointToPointCore>(m, "PointToPoint")
      .def(py::init<py::handle, py::handle, py::handle, py::handle, int>(), py::arg("q0"), py::arg("qf"),
           py::arg("vmax"), py::arg("amax"), py::arg("profile"))
      .def_property_readonly("duration", [](const PointToPointCore& p) { return p.plan_.duration; })
      .def_property_readonly("axis_durations", [](const PointToPointCore& p) { return to_array(p.plan_.axis_durations); })
      .def_property_readonly("acceleration", [](const PointToPointCore& p) { return to_array(p.plan_.accel); })
      .def_property_readonly("cruise_velocity", [](const PointToPointCore& p) { return to_array(p.plan_.cruise); })
      .def_property_readonly("ramp_time", [](const PointToPointCore& p) { return to_array(p.plan_.ramp); })
      .def("sample", &PointToPointCore::sample, py::arg("t"), py::arg("out") = py::none());

  py::class_<WaypointPathCore>(m, "WaypointPath")
      .def(py::init<py::handle, py::handle, py::handle, py::handle, py::handle, py::handle>(), py::arg("times"),
           py::arg("blends"), py::arg("positions"), py::arg("quaternions"), py::arg("linear"),
           py::arg("angular"))
      .def_property_readonly("duration", [](const WaypointPathCore& w) { return w.data_.duration; })
      .def("sample", &WaypointPathCore::sample, py::arg("t"), py::arg("form"), py::arg("twist"));

  m.def("trajectory_min_duration",
        [](int profile, double distance, double vmax, double amax) {
          if (profile < 0 || profile > 2) throw py::value_error("profile must be 0, 1 or 2");
          return tj::min_duration(static_cast<tj::Profile>(profile), distance, vmax, amax);
        },
        py::arg("profile"), py::arg("distance"), py::arg("vmax"), py::arg("amax"));
}

}  // namespace spotkin::bindings
