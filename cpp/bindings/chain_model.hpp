// The chain model shared by the chain bindings (FK, frames, Jacobians) and the
// closed-form chain IK: one spotkin::Chain in both working precisions.
#pragma once

#include <string>
#include <vector>

#include "spotkin/chain.hpp"

#include "numpy_boundary.hpp"

namespace spotkin::bindings {

struct ChainPair {
  Chain<double> f64;
  Chain<float> f32;

  const Chain<double>& get(double) const { return f64; }
  const Chain<float>& get(float) const { return f32; }
};

inline ChainPair pair_of(Chain<double> chain) {
  auto single = chain.template cast<float>();
  return ChainPair{std::move(chain), std::move(single)};
}

inline Rigid<double> optional_rigid(py::handle obj, const char* name) {
  return obj.is_none() ? Rigid<double>{} : rigid_from<Rigid<double>>(obj, name);
}

// From a DH table (n, 5).
inline ChainPair chain_from_table(Convention convention, py::handle rows_obj, py::handle base_obj,
                                  py::handle tool_obj) {
  py::array rows_arr = as_real_array(rows_obj, "rows");
  if (rows_arr.ndim() != 2 || rows_arr.shape(1) != 5)
    throw py::value_error("rows must have shape (n, 5), got " +
                          format_shape(Shape(rows_arr.shape(), rows_arr.shape() + rows_arr.ndim())));
  auto rows = contiguous<double>(rows_arr);
  return pair_of(Chain<double>::from_table(convention, rows.data(), rows.shape(0),
                                           optional_rigid(base_obj, "base"), optional_rigid(tool_obj, "tool")));
}

// From URDF-style joints: placements (n, 4, 4), axes (n, 3), types (n,) of 0
// (revolute) or 1 (prismatic).
inline ChainPair chain_from_joints(py::handle placements_obj, py::handle axes_obj, py::handle types_obj,
                                   py::handle base_obj, py::handle tool_obj) {
  py::array placements_arr = as_real_array(placements_obj, "placements");
  if (placements_arr.ndim() != 3 || placements_arr.shape(1) != 4 || placements_arr.shape(2) != 4)
    throw py::value_error("placements must have shape (n, 4, 4), got " +
                          format_shape(Shape(placements_arr.shape(), placements_arr.shape() + placements_arr.ndim())));
  const py::ssize_t n = placements_arr.shape(0);
  py::array axes_arr = as_real_array(axes_obj, "axes");
  if (axes_arr.ndim() != 2 || axes_arr.shape(0) != n || axes_arr.shape(1) != 3)
    throw py::value_error("axes must have shape (" + std::to_string(n) + ", 3), got " +
                          format_shape(Shape(axes_arr.shape(), axes_arr.shape() + axes_arr.ndim())));
  py::array types_arr = as_real_array(types_obj, "types");
  if (types_arr.ndim() != 1 || types_arr.shape(0) != n)
    throw py::value_error("types must have shape (" + std::to_string(n) + ",), got " +
                          format_shape(Shape(types_arr.shape(), types_arr.shape() + types_arr.ndim())));
  auto axes = contiguous<double>(axes_arr);
  auto types = contiguous<double>(types_arr);
  std::vector<Rigid<double>> placements;
  std::vector<Vec3<double>> axis_list;
  std::vector<JointType> type_list;
  for (py::ssize_t j = 0; j < n; ++j) {
    const std::string name = "placements[" + std::to_string(j) + "]";
    placements.push_back(rigid_from<Rigid<double>>(placements_arr[py::int_(j)], name.c_str()));
    axis_list.emplace_back(axes.data()[3 * j], axes.data()[3 * j + 1], axes.data()[3 * j + 2]);
    const double t = types.data()[j];
    if (t != 0.0 && t != 1.0)
      throw py::value_error("types[" + std::to_string(j) + "] must be 0 (revolute) or 1 (prismatic)");
    type_list.push_back(t == 0.0 ? JointType::Revolute : JointType::Prismatic);
  }
  return pair_of(Chain<double>::from_joints(placements, axis_list, type_list, optional_rigid(base_obj, "base"),
                                            optional_rigid(tool_obj, "tool")));
}

}  // namespace spotkin::bindings
