// Bindings for whole-body kinematics: batched body IK, FK and Jacobian.
#include "spotkin/kernels/body.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <utility>

#include "binder.hpp"
#include "bindings.hpp"
#include "fast_call.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace body_glue {

EulerSequence make_sequence(int code) { return EulerSequence::from_code(code); }

// The Euler angles' columns of a body pose: reduced exactly when huge.
std::uint64_t euler_columns(BodyPoseFormat format) {
  return format == BodyPoseFormat::Euler ? std::uint64_t{0b111000} : 0;
}

using binder::Arg;
using binder::Kind;
using binder::Op;
using binder::Out;

// body_pose: (..., 6) [x, y, z, a, b, c] (the Euler angles reduced exactly when huge), (..., 4, 4) or
// (..., 7) [x, y, z, qx, qy, qz, qw]; Block::shape gives the BodyPoseFormat (the same order).
Arg pose_arg(bool nan_rows) {
  Arg pose = Arg("body_pose", {6}, euler_columns(BodyPoseFormat::Euler)).or_shape({4, 4}).or_shape({7});
  return nan_rows ? pose.nan_rows() : pose;
}

template <typename B>
BodyPoseFormat format_of(const B& b) {
  return static_cast<BodyPoseFormat>(b.shape[0]);
}

struct Solve {
  const Body& body;
  EulerSequence seq;
  bool nearest_fallback;
};

// body_pose, feet (..., n, 3) and seed None or (..., 3 n) broadcast -> (q (..., 3 n), status (..., n)).
py::object ik(const Body& body, py::handle pose, int sequence, py::handle feet, py::handle seed,
              bool nearest_fallback, py::handle out) {
  const py::ssize_t n_legs = body.n_legs(), w = body.width();
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({pose_arg(false), Arg("feet", {n_legs, 3}).rows_strided(),
               Arg("seed", {w}, all_angles(int(w))).maybe_none().parameter()},
              {Out("q", {w}), Out("status", {n_legs}, Kind::Status)}, 55.0,
              [](const void* c, const auto& b) {
                const Solve& s = binder::context<Solve>(c);
                // a shared stance is read with stride 0; the kernel reads either form
                kernels::body_ik(s.body, b.in[0], format_of(b), s.seq, b.in[1], b.stride[1] == 0,
                                 b.in[2], b.real(0), b.status(1), b.m, s.nearest_fallback);
              })
        .returns("BodyIK");
  };
  const Solve context{body, make_sequence(sequence), nearest_fallback};
  return ops.with({std::uint64_t(n_legs), std::uint64_t(w), 0}, make,
               [&](const Op& op) { return binder::call(op, &context, {pose, feet, seed}, out); });
}

struct Posed {
  const Body& body;
  EulerSequence seq;
};

// body_pose and q (..., 3 n) broadcast -> feet (..., n, 3), or the Jacobian (..., 3 n, 6 + 3 n). A leg's
// non-finite joints make its foot (its Jacobian rows) NaN, and only them, when each leg's joints are its
// own three columns of q; otherwise the whole sample.
template <bool Jacobian>
py::object fk_or_jacobian(const Body& body, py::handle pose, int sequence, py::handle q, py::handle out) {
  const py::ssize_t n_legs = body.n_legs(), w = body.width();
  const int groups = body.leg_contiguous() ? int(n_legs) : 1;
  const Out result = Jacobian ? Out("J", {w, 6 + w}) : Out("feet", {n_legs, 3});
  static binder::OpCache ops;
  const auto make = [&] {
    return Op({pose_arg(true), Arg("q", {w}, all_angles(int(w))).nan_rows(groups)}, {result},
              55.0, [](const void* c, const auto& b) {
                const Posed& s = binder::context<Posed>(c);
                if constexpr (Jacobian) {
                  kernels::body_jacobian(s.body, b.in[0], format_of(b), s.seq, b.in[1], b.real(0),
                                         b.m);
                } else {
                  kernels::body_fk(s.body, b.in[0], format_of(b), s.seq, b.in[1], b.real(0), b.m);
                }
              });
  };
  const Posed context{body, make_sequence(sequence)};
  return ops.with({std::uint64_t(n_legs), std::uint64_t(w), std::uint64_t(groups)}, make, [&](const Op& op) { return binder::call(op, &context, {pose, q}, out); });
}

// body_pose (any form) -> the world <- body transforms (..., 4, 4), float64; NaN for an invalid pose.
py::object transform(py::handle pose, int sequence, py::handle out) {
  static const Op op =
      Op({pose_arg(false)}, {Out("T", {4, 4})}, 30.0, [](const void* c, const auto& b) {
        if constexpr (std::is_same_v<typename std::decay_t<decltype(b)>::Scalar, double>) {  // float64_only
          const EulerSequence& seq = binder::context<EulerSequence>(c);
          for (std::ptrdiff_t i = 0; i < b.m; ++i)
            body_batch::pose_transform(b.in[0] + b.stride[0] * i, format_of(b), seq, b.real(0) + 16 * i);
        }
      }).float64_only();
  const EulerSequence seq = make_sequence(sequence);
  return binder::call(op, &seq, {pose}, out);
}

// legs: sk.Leg cores; hips (n, 3); columns (n, 3) integers (None: leg l's
// joints are columns 3 l, 3 l + 1, 3 l + 2).
Body make_body(const std::vector<const Leg*>& legs, py::handle hips_obj, py::handle columns_obj) {
  const auto n = static_cast<py::ssize_t>(legs.size());
  if (n < 1 || n > Body::kMaxLegs)
    throw py::value_error("a body needs 1 to " + std::to_string(Body::kMaxLegs) + " legs, got " + std::to_string(n));
  auto hips = contiguous<double>(as_real_array(hips_obj, "hip_positions"));
  if (hips.ndim() != 2 || hips.shape(0) != n || hips.shape(1) != 3)
    throw py::value_error("hip_positions must have shape (" + std::to_string(n) + ", 3)");
  std::vector<Leg> leg_list;
  std::vector<std::array<double, 3>> hip_list;
  std::vector<std::array<int, 3>> column_list;
  py::array_t<double, py::array::c_style> columns;
  if (!columns_obj.is_none()) {
    columns = contiguous<double>(as_real_array(columns_obj, "columns"));
    if (columns.ndim() != 2 || columns.shape(0) != n || columns.shape(1) != 3)
      throw py::value_error("columns must have shape (" + std::to_string(n) + ", 3)");
  }
  for (py::ssize_t l = 0; l < n; ++l) {
    leg_list.push_back(*legs[std::size_t(l)]);
    std::array<double, 3> hip;
    std::array<int, 3> col;
    for (int k = 0; k < 3; ++k) {
      hip[std::size_t(k)] = hips.data()[3 * l + k];
      if (!std::isfinite(hip[std::size_t(k)])) throw py::value_error("hip_positions must be finite");
      const double c = columns_obj.is_none() ? double(3 * l + k) : columns.data()[3 * l + k];
      if (c != std::floor(c)) throw py::value_error("columns must be integers");
      col[std::size_t(k)] = int(c);
    }
    hip_list.push_back(hip);
    column_list.push_back(col);
  }
  return Body(std::move(leg_list), std::move(hip_list), std::move(column_list));
}

}  // namespace body_glue

void bind_body(py::module_& m) {
  using namespace body_glue;
  m.def("body_transform", &transform, py::arg("body_pose"), py::arg("sequence"), py::arg("out") = py::none());
  py::class_<Body> cls(m, "Body");
  cls.def(py::init(&make_body), py::arg("legs"), py::arg("hip_positions"),
          py::arg("columns") = py::none())
      .def_property_readonly("n_legs", &Body::n_legs);
  fast::def_fast<&ik>(cls, "ik", py::arg("body_pose"), py::arg("sequence"), py::arg("feet"),
                      py::arg("seed"), py::arg("nearest_fallback") = true,
                      py::arg("out") = py::none());
  fast::def_fast<&fk_or_jacobian<false>>(cls, "fk", py::arg("body_pose"), py::arg("sequence"),
                                         py::arg("q"), py::arg("out") = py::none());
  fast::def_fast<&fk_or_jacobian<true>>(cls, "jacobian", py::arg("body_pose"), py::arg("sequence"),
                                        py::arg("q"), py::arg("out") = py::none());
}

}  // namespace spotkin::bindings
