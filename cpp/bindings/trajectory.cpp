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

class PointToPointCore {
 public:
  PointToPointCore(py::handle q0_obj, py::handle qf_obj, py::handle vmax_obj, py::handle amax_obj,
                   int profile)
      : profile_(static_cast<tj::Profile>(profile)) {
    if (profile < 0 || profile > 2) throw py::value_error("profile must be 0 (cubic), 1 (quintic) or 2 (trapezoid)");
    q0_ = vector_arg(q0_obj, "q0", -1, false);
    const auto n = static_cast<py::ssize_t>(q0_.size());
    {
      py::array qf_arr = as_real_array(qf_obj, "qf");
      if (qf_arr.ndim() != 1 || qf_arr.shape(0) != n)
        throw py::value_error("qf must have the shape of q0, " + format_shape({n}) + ", got " +
                              format_shape(shape_of(qf_arr)));
    }
    qf_ = vector_arg(qf_obj, "qf", n, false);
    vmax_ = vector_arg(vmax_obj, "vmax", n, true);
    amax_ = vector_arg(amax_obj, "amax", n, true);
    require_finite(q0_, "q0");
    require_finite(qf_, "qf");
    require_positive(vmax_, "vmax");
    require_positive(amax_, "amax");
    axis_durations_.resize(q0_.size());
    duration_ = 0.0;
    for (std::size_t j = 0; j < q0_.size(); ++j) {
      axis_durations_[j] = tj::min_duration(profile_, std::fabs(qf_[j] - q0_[j]), vmax_[j], amax_[j]);
      duration_ = std::max(duration_, axis_durations_[j]);
    }
    accel_.assign(q0_.size(), 0.0);
    cruise_.assign(q0_.size(), 0.0);
    ramp_.assign(q0_.size(), 0.0);
    if (profile_ == tj::Profile::Trapezoid) {
      for (std::size_t j = 0; j < q0_.size(); ++j) {
        const double D = qf_[j] - q0_[j];
        const double v = tj::stretched_cruise_speed(std::fabs(D), amax_[j], duration_);
        if (v > 0.0) {
          accel_[j] = std::copysign(amax_[j], D);
          cruise_[j] = std::copysign(v, D);
          ramp_[j] = std::min(v / amax_[j], 0.5 * duration_);
        }
      }
    }
    keep_params();
  }

  void keep_params() {
    int k = 0;
    for (const auto* src : {&q0_, &qf_, &accel_, &cruise_, &ramp_}) {
      params64_[k] = *src;
      params32_[k++].assign(src->begin(), src->end());
    }
  }

  // t (...) -> (q, qd, qdd), each (..., n), in t's precision.
  py::object sample(py::handle t, py::handle out) const {
    const auto n = static_cast<py::ssize_t>(q0_.size());
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
    const auto& p = params(T{});
    const tj::PointToPoint<T> traj{profile_,    static_cast<int>(q0_.size()), T(duration_), p[0].data(),
                                   p[1].data(), p[2].data(),                  p[3].data(),  p[4].data()};
    tj::sample(traj, t, q, qd, qdd, count);
  }

  // q0, qf, accel, cruise, ramp in each precision (built once).
  const std::array<std::vector<double>, 5>& params(double) const { return params64_; }
  const std::array<std::vector<float>, 5>& params(float) const { return params32_; }

  double duration_;
  tj::Profile profile_;
  std::vector<double> q0_, qf_, vmax_, amax_, axis_durations_, accel_, cruise_, ramp_;
  std::array<std::vector<double>, 5> params64_;
  std::array<std::vector<float>, 5> params32_;
};

py::array_t<double> to_array(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// The timing and geometry are planned by the Python façade (spotkin.trajectory).
class WaypointPathCore {
 public:
  WaypointPathCore(py::handle times, py::handle blends, py::handle positions, py::handle quaternions,
                   py::handle linear, py::handle angular) {
    times_ = vector_arg(times, "times", -1, false);
    const auto W = static_cast<py::ssize_t>(times_.size());
    if (W < 1) throw py::value_error("times must hold at least one waypoint");
    blends_ = vector_arg(blends, "blends", W, false);
    positions_ = rows(positions, "positions", W, 3);
    quaternions_ = rows(quaternions, "quaternions", W, 4);
    linear_ = rows(linear, "linear", W - 1, 3);
    angular_ = rows(angular, "angular", W - 1, 3);
    for (const auto* v : {&times_, &blends_, &positions_, &quaternions_, &linear_, &angular_})
      require_finite(*v, "waypoint path data");
    for (std::size_t k = 0; k + 1 < times_.size(); ++k) {
      const double* w = angular_.data() + 3 * k;
      const double rate = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
      rates_.push_back(rate);
      for (int c = 0; c < 3; ++c) axes_.push_back(rate > 0.0 ? w[c] / rate : 0.0);
    }
    blend_starts_.resize(times_.size());
    for (std::size_t k = 0; k < times_.size(); ++k) {
      if (blends_[k] < 0.0) throw py::value_error("blends must be >= 0");
      blend_starts_[k] = times_[k] - 0.5 * blends_[k];
      if (k > 0 && blend_starts_[k] < blend_starts_[k - 1])
        throw py::value_error("blends must not overlap");
    }
    duration_ = times_.back() + 0.5 * blends_.back();
  }

  py::object sample(py::handle t, int form, bool with_twist) const {
    if (form != 0 && form != 1) throw py::value_error("form must be 0 (matrix) or 1 (quaternion)");
    const tj::WaypointPath path{static_cast<std::ptrdiff_t>(times_.size()),
                                times_.data(),
                                blends_.data(),
                                blend_starts_.data(),
                                positions_.data(),
                                quaternions_.data(),
                                linear_.data(),
                                angular_.data(),
                                axes_.data(),
                                rates_.data(),
                                duration_};
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

  double duration_;
  std::vector<double> times_, blends_, blend_starts_, positions_, quaternions_, linear_, angular_, axes_, rates_;

 private:
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
      .def_readonly("duration", &PointToPointCore::duration_)
      .def_property_readonly("axis_durations", [](const PointToPointCore& p) { return to_array(p.axis_durations_); })
      .def_property_readonly("acceleration", [](const PointToPointCore& p) { return to_array(p.accel_); })
      .def_property_readonly("cruise_velocity", [](const PointToPointCore& p) { return to_array(p.cruise_); })
      .def_property_readonly("ramp_time", [](const PointToPointCore& p) { return to_array(p.ramp_); })
      .def("sample", &PointToPointCore::sample, py::arg("t"), py::arg("out") = py::none());

  py::class_<WaypointPathCore>(m, "WaypointPath")
      .def(py::init<py::handle, py::handle, py::handle, py::handle, py::handle, py::handle>(), py::arg("times"),
           py::arg("blends"), py::arg("positions"), py::arg("quaternions"), py::arg("linear"),
           py::arg("angular"))
      .def_readonly("duration", &WaypointPathCore::duration_)
      .def("sample", &WaypointPathCore::sample, py::arg("t"), py::arg("form"), py::arg("twist"));

  m.def("trajectory_min_duration",
        [](int profile, double distance, double vmax, double amax) {
          if (profile < 0 || profile > 2) throw py::value_error("profile must be 0, 1 or 2");
          return tj::min_duration(static_cast<tj::Profile>(profile), distance, vmax, amax);
        },
        py::arg("profile"), py::arg("distance"), py::arg("vmax"), py::arg("amax"));
}

}  // namespace spotkin::bindings
