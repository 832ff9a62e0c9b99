// Bindings for spotkin::Leg: batched FK, Jacobian, singularity measures and
// closed-form IK (limit-aware choice, and every branch).
#include "spotkin/kernels/leg.hpp"

#include <pybind11/stl.h>

#include <array>
#include <tuple>

#include "bindings.hpp"
#include "numpy_boundary.hpp"
#include "spotkin/parallel.hpp"

namespace spotkin::bindings {

namespace leg_glue {

constexpr std::ptrdiff_t kMinPerThread = min_chunk(25.0);  // leg IK: ~25 ns; FK ~7 ns pays less

py::object fk(const Leg& leg, py::handle q_obj) {
  return map_batch(q_obj, "q", 3, {3}, kMinPerThread,
                   [&](const auto* q, auto* p, std::ptrdiff_t n) { kernels::leg_fk(leg, q, p, n); }, all_angles(3));
}

py::object jacobian(const Leg& leg, py::handle q_obj) {
  return map_batch(q_obj, "q", 3, {3, 3}, kMinPerThread,
                   [&](const auto* q, auto* J, std::ptrdiff_t n) { kernels::leg_jacobian(leg, q, J, n); }, all_angles(3));
}

py::object singularity(const Leg& leg, py::handle q_obj) {
  return dispatch_real(q_obj, "q", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const Shape leading = leading_shape(arr, "q", {3});
    auto q = contiguous<T>(arr);
    auto det = new_array<T>(leading, {});
    auto sigma = new_array<T>(leading, {});
    const T* qd = q.data();
    T* dd = det.mutable_data();
    T* sd = sigma.mutable_data();
    {
      ReleaseGilFor release(count(leading));
      parallel_for(count(leading), kMinPerThread / 8, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        with_reduced_angles(qd + 3 * b, 3, all_angles(3), dd + b, 1, e - b, [&](const T* qb, T* ob, std::ptrdiff_t m) {
          const std::ptrdiff_t first = ob - dd;  // the sub-block's first sample
          for (std::ptrdiff_t i = 0; i < m; ++i) leg.singularity(qb + 3 * i, dd + first + i, sd + first + i);
        });
      });
    }
    return py::make_tuple(det, sigma);
  });
}

// p (..., 3), seed None or (..., 3) of the same shape -> (q (..., 3), status (...)).
py::object ik(const Leg& leg, py::handle p_obj, py::handle seed_obj, bool nearest_fallback) {
  return dispatch_real(p_obj, "p", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const Shape leading = leading_shape(arr, "p", {3});
    auto p = contiguous<T>(arr);
    py::array_t<T, py::array::c_style> seed;  // default-constructed: an empty array, not null
    const bool has_seed = !seed_obj.is_none();
    if (has_seed) {
      py::array seed_arr = as_real_array(seed_obj, "seed");
      const Shape seed_leading = leading_shape(seed_arr, "seed", {3});
      if (seed_leading != leading)
        throw py::value_error("seed must have the shape of p, " + format_shape(leading) + " + (3,), got " +
                              format_shape(seed_leading) + " + (3,); broadcast them first");
      seed = seed_angles<T>(seed_arr, 3, all_angles(3));
    }
    const bool single = leading.empty();
    auto q = new_array<T>(leading, {3});
    std::int8_t single_status = 0;
    py::array_t<std::int8_t> status;
    if (!single) status = new_array<std::int8_t>(leading, {});
    const T* pd = p.data();
    const T* sd = has_seed ? seed.data() : nullptr;
    T* qd = q.mutable_data();
    std::int8_t* status_data = single ? &single_status : status.mutable_data();
    {
      ReleaseGilFor release(count(leading));
      parallel_for(count(leading), kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        kernels::leg_ik<T>(leg, pd + 3 * b, sd ? sd + 3 * b : nullptr, qd + 3 * b, status_data + b, e - b,
                           nearest_fallback);
      });
    }
    if (single) return py::make_tuple(q, status_object(single_status));
    return py::make_tuple(q, status);
  });
}

py::object ik_all(const Leg& leg, py::handle p_obj) {
  return dispatch_real(p_obj, "p", [&](auto tag, py::array arr) -> py::object {
    using T = decltype(tag);
    const Shape leading = leading_shape(arr, "p", {3});
    auto p = contiguous<T>(arr);
    auto q = new_array<T>(leading, {Leg::kSlots, 3});
    auto valid = new_array<bool>(leading, {Leg::kSlots});
    auto exists = new_array<bool>(leading, {Leg::kSlots});
    auto status = new_array<std::int8_t>(leading, {});
    const T* pd = p.data();
    T* qd = q.mutable_data();
    auto* vd = reinterpret_cast<std::uint8_t*>(valid.mutable_data());
    auto* ed = reinterpret_cast<std::uint8_t*>(exists.mutable_data());
    std::int8_t* sd = status.mutable_data();
    {
      ReleaseGilFor release(count(leading));
      parallel_for(count(leading), kMinPerThread, [&](std::ptrdiff_t b, std::ptrdiff_t e) {
        kernels::leg_ik_all<T>(leg, pd + 3 * b, qd + 12 * b, vd + 4 * b, ed + 4 * b, sd + b, e - b);
      });
    }
    if (leading.empty()) return py::make_tuple(q, valid, exists, status_object(status.data()[0]));
    return py::make_tuple(q, valid, exists, status);
  });
}

std::array<double, 3> vector3(py::handle obj, const char* name) {
  auto arr = contiguous<double>(as_real_array(obj, name));
  if (arr.ndim() != 1 || arr.shape(0) != 3) throw py::value_error(std::string(name) + " must have shape (3,)");
  std::array<double, 3> v{arr.data()[0], arr.data()[1], arr.data()[2]};
  for (double x : v)
    if (!std::isfinite(x)) throw py::value_error(std::string(name) + " must be finite");
  return v;
}

// a, b, c, signs: (3,) each (rpp_geometry.hpp); limits (3,) each.
Leg make_leg(py::handle a, py::handle b, py::handle c, py::handle signs, py::handle lower_limits,
             py::handle upper_limits, int preferred_slot) {
  RppGeometry g;
  const auto va = vector3(a, "a"), vb = vector3(b, "b"), vc = vector3(c, "c"), vs = vector3(signs, "signs");
  for (int k = 0; k < 3; ++k) g.a[k] = va[k], g.b[k] = vb[k], g.c[k] = vc[k], g.sign[k] = vs[k];
  JointLimits<3> limits;
  for (auto [obj, target, name] : {std::tuple{lower_limits, limits.lower, "lower limits"},
                                   std::tuple{upper_limits, limits.upper, "upper limits"}}) {
    auto arr = contiguous<double>(as_real_array(obj, name));
    if (arr.ndim() != 1 || arr.shape(0) != 3)
      throw py::value_error(std::string(name) + " must have shape (3,)");
    for (int j = 0; j < 3; ++j) target[j] = arr.data()[j];
  }
  for (int j = 0; j < 3; ++j)
    if (std::isnan(limits.lower[j]) || std::isnan(limits.upper[j]) || limits.lower[j] > limits.upper[j])
      throw std::invalid_argument("limits must satisfy lower <= upper, with no NaN");
  return Leg(g, limits, preferred_slot);
}

}  // namespace leg_glue

void bind_leg(py::module_& m) {
  using namespace leg_glue;
  py::class_<Leg>(m, "Leg")
      .def(py::init(&make_leg), py::arg("a"), py::arg("b"), py::arg("c"), py::arg("signs"),
           py::arg("lower_limits"), py::arg("upper_limits"), py::arg("preferred_slot") = -1)
      .def_property_readonly("preferred_slot", &Leg::preferred_slot)
      .def_property_readonly("max_reach", &Leg::max_reach)
      .def_property_readonly("min_reach", &Leg::min_reach)
      .def("fk", &fk, py::arg("q"))
      .def("jacobian", &jacobian, py::arg("q"))
      .def("singularity", &singularity, py::arg("q"))
      .def("ik", &ik, py::arg("p"), py::arg("seed") = py::none(), py::arg("nearest_fallback") = true)
      .def("ik_all", &ik_all, py::arg("p"))
      .def("nearest_reachable", [](const Leg& leg, std::array<double, 3> p, bool within_limits) {
        std::array<double, 3> out, q;
        leg.nearest_reachable(p.data(), out.data(), within_limits, q.data());
        return py::make_tuple(out, q);
      }, py::arg("p"), py::arg("within_limits") = false);
}

}  // namespace spotkin::bindings
