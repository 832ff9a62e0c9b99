// Bindings for whole-body kinematics: batched body IK, FK and Jacobian.
#include "spotkin/kernels/body.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <initializer_list>
#include <string>
#include <utility>

#include "bindings.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace body_glue {

constexpr std::ptrdiff_t kMinPerThread = min_chunk(55.0);  // body IK: ~55 ns per pose

std::ptrdiff_t pose_width(BodyPoseFormat format) {
  return format == BodyPoseFormat::Euler ? 6 : (format == BodyPoseFormat::Matrix ? 16 : 7);
}

// body_pose (N, width) contiguous in T, already broadcast by the façade.
struct Poses {
  BodyPoseFormat format;
  Shape leading;
};

Poses pose_shape(const py::array& arr, BodyPoseFormat format) {
  const Shape trailing = format == BodyPoseFormat::Matrix ? Shape{4, 4} : Shape{pose_width(format)};
  return {format, leading_shape(arr, "body_pose", trailing)};
}

// The Euler sequence packed in one int by the façade: axis[0] + 3 axis[1] + 9 axis[2],
// plus 27 when the angles are applied in reverse order (extrinsic sequences).
EulerSequence make_sequence(int code) {
  if (code < 0 || code >= 54) throw py::value_error("invalid Euler sequence code " + std::to_string(code));
  EulerSequence seq;
  seq.axis[0] = code % 3, seq.axis[1] = code / 3 % 3, seq.axis[2] = code / 9 % 3;
  const bool reversed = code >= 27;
  for (int k = 0; k < 3; ++k) seq.order[k] = reversed ? 2 - k : k;
  return seq;
}

// The format from the shape: (..., 6) Euler, (..., 4, 4) matrix, (..., 7) quaternion.
BodyPoseFormat detect_format(const py::array& arr) {
  const auto nd = arr.ndim();
  if (nd >= 1 && arr.shape(nd - 1) == 6) return BodyPoseFormat::Euler;
  if (nd >= 2 && arr.shape(nd - 1) == 4 && arr.shape(nd - 2) == 4) return BodyPoseFormat::Matrix;
  if (nd >= 1 && arr.shape(nd - 1) == 7) return BodyPoseFormat::PositionQuaternion;
  throw py::value_error(
      "body_pose must have shape (..., 6) [x, y, z, a, b, c], (..., 4, 4) or (..., 7) [x, y, z, qx, qy, qz, qw], got " +
      format_shape(Shape(arr.shape(), arr.shape() + nd)));
}

// The Euler angles' columns of a body pose: reduced exactly when huge.
std::uint64_t euler_columns(BodyPoseFormat format) {
  return format == BodyPoseFormat::Euler ? std::uint64_t{0b111000} : 0;
}

// Robot.body_ik's result type (a NamedTuple, registered at import by the
// façade; a plain tuple until then), built here without a Python-level call.
PyObject*& body_ik_type() {
  static PyObject* type = nullptr;  // a strong reference, never released (see status_members)
  return type;
}

py::object body_ik_result(py::object q, py::object status) {
  auto* type = reinterpret_cast<PyTypeObject*>(body_ik_type());
  if (!type) return py::make_tuple(q, status);
  PyObject* result = type->tp_alloc(type, 2);  // a tuple subclass, as tuple.__new__ makes it
  if (!result) throw py::error_already_set();
  PyTuple_SET_ITEM(result, 0, q.release().ptr());
  PyTuple_SET_ITEM(result, 1, status.release().ptr());
  return py::reinterpret_steal<py::object>(result);
}

// format_code -1: detect the format from body_pose's shape.
py::object ik(const Body& body, py::handle pose_obj, int format_code, int sequence, py::handle feet_obj,
              py::handle seed_obj, bool nearest_fallback) {
  const EulerSequence seq = make_sequence(sequence);
  return dispatch_promoted(pose_obj, "body_pose", {{feet_obj, "feet"}}, [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const auto format = format_code < 0 ? detect_format(arr) : static_cast<BodyPoseFormat>(format_code);
    const Poses shape = pose_shape(arr, format);
    auto poses = contiguous<T>(arr);
    const py::ssize_t n_legs = body.n_legs(), w = body.width();
    auto feet = contiguous<T>(as_real_array(feet_obj, "feet"));
    const Shape feet_leading = leading_shape(feet, "feet", {n_legs, 3});
    const bool feet_shared = feet_leading.empty();
    if (!feet_shared && feet_leading != shape.leading)
      throw py::value_error("feet " + format_shape(feet_leading) + " + (" + std::to_string(n_legs) +
                            ", 3) must match body_pose's leading shape " + format_shape(shape.leading));
    const bool has_seed = !seed_obj.is_none();
    py::array_t<T, py::array::c_style> seed;
    if (has_seed) {
      seed = seed_angles<T>(as_real_array(seed_obj, "seed"), w, all_angles(int(w)));
      if (leading_shape(seed, "seed", {w}) != shape.leading)
        throw py::value_error("seed must have shape " + format_shape(shape.leading) + " + (" + std::to_string(w) +
                              ",)");
    }
    auto q = new_array<T>(shape.leading, {w});
    auto status = new_array<std::int8_t>(shape.leading, {n_legs});
    const std::ptrdiff_t width = pose_width(format);
    const T* pd = poses.data();
    const T* fd = feet.data();
    const T* sd = has_seed ? seed.data() : nullptr;
    T* qd = q.mutable_data();
    std::int8_t* std_ = status.mutable_data();
    {
      ReleaseGilFor release(count(shape.leading));
      parallel_for(count(shape.leading), kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        // huge Euler angles are reduced exactly; pose_block is the first pose of out_block's samples
        with_reduced_angles(pd + width * b, width, euler_columns(format), qd + w * b, w, e - b,
                            [&](const T* pose_block, T* out_block, std::ptrdiff_t m) {
                              const std::ptrdiff_t i = (out_block - qd) / w;
                              kernels::body_ik<T>(body, pose_block, format, seq, feet_shared ? fd : fd + 3 * n_legs * i,
                                                  feet_shared, sd ? sd + w * i : nullptr, out_block, std_ + n_legs * i,
                                                  m, nearest_fallback);
                            });
      });
    }
    return body_ik_result(std::move(q), std::move(status));
  });
}

// The data of obj when it is a plain, aligned, C-contiguous native float64
// ndarray of exactly `shape`; null otherwise (the general path then takes it).
const double* plain_float64(py::handle obj, std::initializer_list<py::ssize_t> shape) {
  auto& api = py::detail::npy_api::get();
  if (Py_TYPE(obj.ptr()) != api.PyArray_Type_) return nullptr;
  static PyObject* const float64 = api.PyArray_DescrFromType_(py::detail::npy_api::NPY_DOUBLE_);
  const auto* array = py::detail::array_proxy(obj.ptr());
  constexpr int kFlags = py::detail::npy_api::NPY_ARRAY_C_CONTIGUOUS_ | py::detail::npy_api::NPY_ARRAY_ALIGNED_;
  if (array->descr != float64 || (array->flags & kFlags) != kFlags || array->nd != int(shape.size())) return nullptr;
  int k = 0;
  for (const py::ssize_t d : shape)
    if (array->dimensions[k++] != d) return nullptr;
  return reinterpret_cast<const double*>(array->data);
}

// A new 1-d array of `size` elements of NumPy type `typenum`.
py::object new_vector(int typenum, py::ssize_t size) {
  auto& api = py::detail::npy_api::get();
  const Py_intptr_t dims[1] = {size};
  PyObject* array = api.PyArray_NewFromDescr_(api.PyArray_Type_, api.PyArray_DescrFromType_(typenum), 1, dims,
                                              nullptr, nullptr, 0, nullptr);
  if (!array) throw py::error_already_set();
  return py::reinterpret_steal<py::object>(array);
}

// The control-loop call, Robot.body_ik(pose, feet) with the defaults: one
// float64 (6,) pose [x, y, z, a, b, c] (intrinsic XYZ) and one shared (n, 3)
// float64 stance, both plain C-contiguous arrays. It skips the general path's
// shape bookkeeping, promotion and thread split and solves the pose in the
// same kernel (so the same answer bit for bit); any other input, or a pose with
// a non-finite or huge value, goes the general way.
py::object ik_one(const Body& body, py::handle pose_obj, py::handle feet_obj) {
  static const EulerSequence xyz = make_sequence(0 + 3 * 1 + 9 * 2);  // the packed code of "XYZ"
  const py::ssize_t n_legs = body.n_legs(), w = body.width();
  const double* pose = plain_float64(pose_obj, {6});
  const double* feet = plain_float64(feet_obj, {n_legs, 3});
  bool usual = pose && feet;
  for (int k = 0; usual && k < 6; ++k)
    usual = std::isfinite(pose[k]) && (k < 3 || std::fabs(pose[k]) <= vector_math::kReducibleLimit);
  if (!usual) return ik(body, pose_obj, -1, 0 + 3 * 1 + 9 * 2, feet_obj, py::none(), true);
  py::object q = new_vector(py::detail::npy_api::NPY_DOUBLE_, w);
  py::object status = new_vector(py::detail::npy_api::NPY_BYTE_, n_legs);
  kernels::body_ik<double>(body, pose, BodyPoseFormat::Euler, xyz, feet, true, nullptr,
                           reinterpret_cast<double*>(py::detail::array_proxy(q.ptr())->data),
                           reinterpret_cast<std::int8_t*>(py::detail::array_proxy(status.ptr())->data), 1, true);
  return body_ik_result(std::move(q), std::move(status));
}

template <bool Jacobian>
py::object fk_or_jacobian(const Body& body, py::handle pose_obj, int format_code, int sequence, py::handle q_obj) {
  const auto format = static_cast<BodyPoseFormat>(format_code);
  const EulerSequence seq = make_sequence(sequence);
  return dispatch_promoted(pose_obj, "body_pose", {{q_obj, "q"}}, [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const Poses shape = pose_shape(arr, format);
    auto poses = contiguous<T>(arr);
    const py::ssize_t n_legs = body.n_legs(), w = body.width();
    auto q = contiguous<T>(as_real_array(q_obj, "q"));
    if (leading_shape(q, "q", {w}) != shape.leading)
      throw py::value_error("q must have shape " + format_shape(shape.leading) + " + (" + std::to_string(w) + ",)");
    auto out = Jacobian ? new_array<T>(shape.leading, {w, 6 + w}) : new_array<T>(shape.leading, {n_legs, 3});
    const std::ptrdiff_t width = pose_width(format);
    const T* pd = poses.data();
    const T* qd = q.data();
    T* od = out.mutable_data();
    // a leg's non-finite joints make its foot (its Jacobian rows) NaN, and only them, when each
    // leg's joints are its own three columns of q; otherwise the whole sample
    const std::ptrdiff_t groups = body.leg_contiguous() ? n_legs : 1;
    {
      ReleaseGilFor release(count(shape.leading));
      const std::ptrdiff_t out_width = Jacobian ? w * (6 + w) : 3 * n_legs;
      parallel_for(count(shape.leading), kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        // huge joint and Euler angles are reduced exactly (with_reduced_angles, once per input)
        with_reduced_angles(qd + w * b, w, all_angles(int(w)), od + out_width * b, out_width, e - b,
                            [&](const T* q_block, T* out_block, std::ptrdiff_t m) {
          const std::ptrdiff_t i = (out_block - od) / out_width;
          with_reduced_angles(pd + width * i, width, euler_columns(format), out_block, out_width, m,
                              [&](const T* pose_block, T* out_inner, std::ptrdiff_t k) {
            if constexpr (Jacobian) {
              kernels::body_jacobian<T>(body, pose_block, format, seq, q_block, out_inner, k);
            } else {
              kernels::body_fk<T>(body, pose_block, format, seq, q_block, out_inner, k);
            }
          });
        }, groups);
      });
    }
    return std::move(out);
  });
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
  m.def(
      "_register_body_ik",
      [](py::object type) {
        if (!PyType_Check(type.ptr()) || !PyType_IsSubtype(reinterpret_cast<PyTypeObject*>(type.ptr()), &PyTuple_Type))
          throw py::type_error("_register_body_ik takes a tuple subclass");
        PyObject*& slot = body_ik_type();
        Py_XDECREF(slot);
        slot = type.release().ptr();
      },
      py::arg("type"));
  py::class_<Body>(m, "Body")
      .def(py::init(&make_body), py::arg("legs"), py::arg("hip_positions"), py::arg("columns") = py::none())
      .def_property_readonly("n_legs", &Body::n_legs)
      .def("ik", &ik, py::arg("body_pose"), py::arg("format"), py::arg("sequence"), py::arg("feet"),
           py::arg("seed"), py::arg("nearest_fallback") = true)
      .def("ik_one", &ik_one, py::arg("body_pose"), py::arg("feet"))
      .def("fk", &fk_or_jacobian<false>, py::arg("body_pose"), py::arg("format"), py::arg("sequence"),
           py::arg("q"))
      .def("jacobian", &fk_or_jacobian<true>, py::arg("body_pose"), py::arg("format"), py::arg("sequence"),
           py::arg("q"));
}

}  // namespace spotkin::bindings
