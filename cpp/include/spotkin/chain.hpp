// Serial chains: one model for URDF, DH and DHm descriptions. Every joint is
//   T(j-1, j) = pre . Motion(axis, theta + q | r + q) . post
// with pre and post fixed placements (rigid transforms) and the motion a
// rotation about a unit axis of the frame reached after pre (revolute, q added
// to theta) or a translation along it (prismatic, q added to r); the revolute
// motion also carries the fixed shift r along its axis (the two commute).
//   URDF:                      pre = the joint's <origin> (fixed joints merged), post = I, any axis
//   DHm (Khalil-Kleinfinger):  pre = TransX(d) RotX(alpha), post = I, axis z
//   DH  (classic):             pre = I, post = TransX(a) RotX(alpha), axis z
// (RotX and TransX commute, as do RotZ and TransZ.) Placements and axes keep
// their kind (identity, x screw, translation, general; x, y, z or general axis)
// so that DH chains and URDF chains with axis-aligned joints pay only for
// what they use. Forward kinematics, frames and the geometric Jacobian
// (the course's summary sheet, "Jacobienne géométrique") are written once for every kind.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin {

enum class JointType : std::int8_t { Revolute = 0, Prismatic = 1 };
enum class Convention : std::int8_t { ModifiedDH = 0, ClassicDH = 1 };

enum class PlacementKind : std::int8_t { Identity = 0, XScrew = 1, Translation = 2, General = 3 };

// A fixed rigid transform, applied on the right: T <- T . placement.
template <typename Scalar>
struct Placement {
  PlacementKind kind = PlacementKind::Identity;
  Scalar a = 0, cos_alpha = 1, sin_alpha = 0;  // XScrew: TransX(a) RotX(alpha)
  Rigid<Scalar> X;                             // Translation (X.R = I) and General

  static Placement x_screw(double a, double alpha) {
    Placement s;
    if (a == 0.0 && alpha == 0.0) return s;
    s.kind = PlacementKind::XScrew;
    s.a = Scalar(a);
    s.cos_alpha = Scalar(std::cos(alpha));
    s.sin_alpha = Scalar(std::sin(alpha));
    s.X = Rigid<double>{Mat3<double>(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX())),
                        Eigen::Vector3d(a, 0.0, 0.0)}.template cast<Scalar>();
    return s;
  }

  // The kind is read off exactly: a rotation equal to I keeps the cheap forms.
  static Placement rigid(const Rigid<double>& T) {
    Placement s;
    const bool no_rotation = T.R == Mat3<double>::Identity();
    if (no_rotation && T.p.isZero(0.0)) return s;
    s.kind = no_rotation ? PlacementKind::Translation : PlacementKind::General;
    s.X = T.template cast<Scalar>();
    return s;
  }

  // Written out per coefficient: Eigen's expression templates are not always
  // inlined into the batch loops, and a call per joint costs more than the math.
  SPOTKIN_INLINE void apply(Rigid<Scalar>& T) const noexcept {
    switch (kind) {
      case PlacementKind::Identity:
        return;
      case PlacementKind::XScrew:
        for (int r = 0; r < 3; ++r) {
          T.p[r] += a * T.R(r, 0);
          const Scalar y = T.R(r, 1), z = T.R(r, 2);
          T.R(r, 1) = cos_alpha * y + sin_alpha * z;
          T.R(r, 2) = cos_alpha * z - sin_alpha * y;
        }
        return;
      case PlacementKind::Translation:
        for (int r = 0; r < 3; ++r) T.p[r] += T.R(r, 0) * X.p[0] + T.R(r, 1) * X.p[1] + T.R(r, 2) * X.p[2];
        return;
      case PlacementKind::General:
        for (int r = 0; r < 3; ++r) {
          const Scalar r0 = T.R(r, 0), r1 = T.R(r, 1), r2 = T.R(r, 2);
          T.p[r] += r0 * X.p[0] + r1 * X.p[1] + r2 * X.p[2];
          for (int k = 0; k < 3; ++k) T.R(r, k) = r0 * X.R(0, k) + r1 * X.R(1, k) + r2 * X.R(2, k);
        }
        return;
    }
  }

  Rigid<double> matrix() const {
    return kind == PlacementKind::Identity ? Rigid<double>{} : X.template cast<double>();
  }

  template <typename Other>
  Placement<Other> cast() const {
    Placement<Other> o;
    o.kind = kind;
    o.a = Other(a), o.cos_alpha = Other(cos_alpha), o.sin_alpha = Other(sin_alpha);
    o.X = X.template cast<Other>();
    return o;
  }
};

enum class AxisKind : std::int8_t { X = 0, Y = 1, Z = 2, General = 3 };

template <typename Scalar>
struct Joint {
  JointType type = JointType::Revolute;
  Placement<Scalar> pre, post;
  AxisKind axis_kind = AxisKind::Z;
  Scalar axis_sign = 1;                     // X, Y, Z: the axis is axis_sign e_k
  Vec3<Scalar> axis = Vec3<Scalar>::UnitZ();  // the unit axis, in the frame after pre
  Scalar theta = 0;  // angle about the axis at q = 0
  Scalar r = 0;      // offset along the axis at q = 0

  // Sets the axis from a unit vector; exact +-e_k keep the cheap kinds.
  void set_axis(const Vec3<double>& u) {
    axis = u.template cast<Scalar>();
    axis_kind = AxisKind::General;
    axis_sign = 1;
    for (int k = 0; k < 3; ++k)
      if (std::fabs(u[k]) == 1.0 && u[(k + 1) % 3] == 0.0 && u[(k + 2) % 3] == 0.0) {
        axis_kind = static_cast<AxisKind>(k);
        axis_sign = Scalar(u[k]);
      }
  }

  // T <- T . Rot(axis, angle) . Trans(axis, shift), given c = cos(angle), s = sin(angle).
  SPOTKIN_INLINE void apply_motion(Rigid<Scalar>& T, Scalar c, Scalar s, Scalar shift) const noexcept {
    switch (axis_kind) {
      case AxisKind::X:
        rotate_columns<1, 2>(T, c, axis_sign * s, axis_sign * shift);
        return;
      case AxisKind::Y:
        rotate_columns<2, 0>(T, c, axis_sign * s, axis_sign * shift);
        return;
      case AxisKind::Z:
        rotate_columns<0, 1>(T, c, axis_sign * s, axis_sign * shift);
        return;
      case AxisKind::General: {
        const Scalar one_c = Scalar(1) - c, u0 = axis[0], u1 = axis[1], u2 = axis[2];
        // R Rot(u, angle) = c R + s R [u]x + (1 - c) (R u) u^T (Rodrigues)
        for (int r = 0; r < 3; ++r) {
          const Scalar c0 = T.R(r, 0), c1 = T.R(r, 1), c2 = T.R(r, 2);
          const Scalar w = c0 * u0 + c1 * u1 + c2 * u2;
          T.R(r, 0) = c * c0 + s * (u2 * c1 - u1 * c2) + one_c * u0 * w;
          T.R(r, 1) = c * c1 + s * (u0 * c2 - u2 * c0) + one_c * u1 * w;
          T.R(r, 2) = c * c2 + s * (u1 * c0 - u0 * c1) + one_c * u2 * w;
          T.p[r] += shift * w;
        }
        return;
      }
    }
  }

  // Rotation about +-e_k, k the third axis after I, J (cyclic): columns I and J mix.
  template <int I, int J>
  static SPOTKIN_INLINE void rotate_columns(Rigid<Scalar>& T, Scalar c, Scalar s, Scalar shift) noexcept {
    constexpr int K = 3 - I - J;
    for (int r = 0; r < 3; ++r) {
      const Scalar ci = T.R(r, I), cj = T.R(r, J);
      T.R(r, I) = c * ci + s * cj;
      T.R(r, J) = c * cj - s * ci;
      T.p[r] += shift * T.R(r, K);
    }
  }

  // The joint axis in the frame T reached after pre.
  SPOTKIN_INLINE Vec3<Scalar> axis_in(const Rigid<Scalar>& T) const noexcept {
    Vec3<Scalar> out;
    if (axis_kind == AxisKind::General) {
      for (int r = 0; r < 3; ++r) out[r] = T.R(r, 0) * axis[0] + T.R(r, 1) * axis[1] + T.R(r, 2) * axis[2];
      return out;
    }
    const int k = static_cast<int>(axis_kind);
    for (int r = 0; r < 3; ++r) out[r] = axis_sign * T.R(r, k);
    return out;
  }

  // A rotation Q with Q e_z = axis: Rot(axis, t) = Q Rz(t) Q^T (for the z-axis
  // forms of the closed-form solvers).
  Mat3<double> z_alignment() const {
    const Vec3<double> u = axis.template cast<double>();
    Vec3<double> x = std::fabs(u[0]) < 0.9 ? Vec3<double>::UnitX() : Vec3<double>::UnitY();
    x = (x - x.dot(u) * u).normalized();
    Mat3<double> Q;
    Q.col(0) = x, Q.col(1) = u.cross(x), Q.col(2) = u;
    if (axis_kind == AxisKind::Z && axis_sign > 0) Q.setIdentity();
    return Q;
  }

  template <typename Other>
  Joint<Other> cast() const {
    Joint<Other> o;
    o.type = type;
    o.pre = pre.template cast<Other>();
    o.post = post.template cast<Other>();
    o.axis_kind = axis_kind;
    o.axis_sign = Other(axis_sign);
    o.axis = axis.template cast<Other>();
    o.theta = Other(theta);
    o.r = Other(r);
    return o;
  }
};

// T <- T . RotZ(theta) TransZ(r), given c = cos(theta), s = sin(theta)
template <typename Scalar>
SPOTKIN_INLINE void apply_z_screw(Rigid<Scalar>& T, Scalar c, Scalar s, Scalar r) noexcept {
  const Vec3<Scalar> x = T.R.col(0), y = T.R.col(1);
  T.R.col(0) = c * x + s * y;
  T.R.col(1) = c * y - s * x;
  T.p.noalias() += r * T.R.col(2);
}

template <typename Scalar>
SPOTKIN_INLINE void apply_z_screw(Rigid<Scalar>& T, Scalar theta, Scalar r) noexcept {
  apply_z_screw(T, Scalar(std::cos(theta)), Scalar(std::sin(theta)), r);
}

template <typename Scalar>
class Chain {
 public:
  static constexpr int kMaxJoints = 64;

  Chain() = default;
  Chain(std::vector<Joint<Scalar>> joints, Rigid<Scalar> base, Rigid<Scalar> tool)
      : joints_(std::move(joints)), base_(base), tool_(tool) {}

  // rows: n x 5, (sigma, d, alpha, r, theta) for DHm or (sigma, a, alpha, d, theta)
  // for classic DH. Throws std::invalid_argument on malformed rows.
  static Chain from_table(Convention convention, const double* rows, std::ptrdiff_t n,
                          const Rigid<double>& base, const Rigid<double>& tool) {
    check_count(n);
    std::vector<Joint<Scalar>> joints(static_cast<std::size_t>(n));
    for (std::ptrdiff_t j = 0; j < n; ++j) {
      const double* row = rows + 5 * j;
      for (int k = 0; k < 5; ++k)
        if (!std::isfinite(row[k]))
          throw std::invalid_argument("row " + std::to_string(j) + " has a non-finite entry");
      if (row[0] != 0.0 && row[0] != 1.0)
        throw std::invalid_argument("row " + std::to_string(j) +
                                    ": sigma must be 0 (revolute) or 1 (prismatic), got " +
                                    std::to_string(row[0]));
      Joint<Scalar>& joint = joints[static_cast<std::size_t>(j)];
      joint.type = row[0] == 0.0 ? JointType::Revolute : JointType::Prismatic;
      joint.theta = Scalar(row[4]);
      joint.r = Scalar(row[3]);
      const auto screw = Placement<Scalar>::x_screw(row[1], row[2]);
      (convention == Convention::ModifiedDH ? joint.pre : joint.post) = screw;
    }
    check_finite(base, tool);
    return Chain(std::move(joints), base.template cast<Scalar>(), tool.template cast<Scalar>());
  }

  // URDF-style joints: placements[j] (the fixed transform before joint j's
  // motion), a unit axis in that frame and the type. Axes are normalised here;
  // a zero or non-finite axis, or a non-finite placement, throws.
  static Chain from_joints(const std::vector<Rigid<double>>& placements, const std::vector<Vec3<double>>& axes,
                           const std::vector<JointType>& types, const Rigid<double>& base,
                           const Rigid<double>& tool) {
    const auto n = static_cast<std::ptrdiff_t>(placements.size());
    check_count(n);
    if (axes.size() != placements.size() || types.size() != placements.size())
      throw std::invalid_argument("placements, axes and types must have one entry per joint");
    std::vector<Joint<Scalar>> joints(placements.size());
    for (std::size_t j = 0; j < placements.size(); ++j) {
      const double norm = axes[j].norm();
      if (!(norm > 0.0) || !std::isfinite(norm))
        throw std::invalid_argument("joint " + std::to_string(j) + ": the axis must be finite and non-zero");
      if (!placements[j].R.allFinite() || !placements[j].p.allFinite())
        throw std::invalid_argument("joint " + std::to_string(j) + ": the placement must be finite");
      Vec3<double> u = axes[j] / norm;
      for (int k = 0; k < 3; ++k)  // keep exact unit axes exact
        if (std::fabs(std::fabs(u[k]) - 1.0) <= 4e-16) u = Vec3<double>::Zero(), u[k] = axes[j][k] > 0 ? 1.0 : -1.0;
      joints[j].type = types[j];
      joints[j].pre = Placement<Scalar>::rigid(placements[j]);
      joints[j].set_axis(u);
    }
    check_finite(base, tool);
    return Chain(std::move(joints), base.template cast<Scalar>(), tool.template cast<Scalar>());
  }

  template <typename Other>
  Chain<Other> cast() const {
    std::vector<Joint<Other>> joints;
    joints.reserve(joints_.size());
    for (const auto& j : joints_) joints.push_back(j.template cast<Other>());
    return Chain<Other>(std::move(joints), base_.template cast<Other>(), tool_.template cast<Other>());
  }

  int dof() const noexcept { return static_cast<int>(joints_.size()); }
  const std::vector<Joint<Scalar>>& joints() const noexcept { return joints_; }
  const Rigid<Scalar>& base() const noexcept { return base_; }
  const Rigid<Scalar>& tool() const noexcept { return tool_; }

  // A length scale for tolerances: the L1 norms of every fixed translation
  // (1 if all are zero). For DH tables, the sum of |a| (or |d|) and |r|.
  double length_scale() const noexcept {
    double scale = double(tool_.p.template cast<double>().norm());
    for (const auto& j : joints_) {
      for (const auto* P : {&j.pre, &j.post})
        scale += P->kind == PlacementKind::XScrew ? std::fabs(double(P->a))
                                                  : P->matrix().p.template lpNorm<1>();
      scale += std::fabs(double(j.r));
    }
    return scale > 0.0 ? scale : 1.0;
  }

  // The z-axis form of the chain for the closed-form solvers:
  //   T = base . L_0 Z(q_0) L_1 Z(q_1) ... L_{n-1} Z(q_{n-1}) . tail(n-1) . tool
  // with Z(q) = RotZ(q) (revolute) or TransZ(q) (prismatic), Q_j the joint's
  // z_alignment, and the fixed links
  //   L_j = Q_{j-1}^T post_{j-1} pre_j Q_j RotZ(theta_j) TransZ(r_j),   tail(j) = Q_j^T post_j
  // (Rot(u, t) = Q RotZ(t) Q^T; the constant z screw commutes with Z(q)).
  Rigid<double> z_link(int j) const {
    const auto& J = joints_[static_cast<std::size_t>(j)];
    Rigid<double> T = j > 0 ? z_tail(j - 1) : Rigid<double>{};
    Rigid<double> screw;
    apply_z_screw(screw, double(J.theta), double(J.r));
    return T * J.pre.matrix() * Rigid<double>{J.z_alignment(), Vec3<double>::Zero()} * screw;
  }
  Rigid<double> z_tail(int j) const {
    const auto& J = joints_[static_cast<std::size_t>(j)];
    return Rigid<double>{J.z_alignment().transpose(), Vec3<double>::Zero()} * J.post.matrix();
  }

  // Base -> tool transform for joint values q[0..n).
  Rigid<Scalar> forward(const Scalar* q) const noexcept {
    Rigid<Scalar> T = base_;
    for (std::size_t j = 0; j < joints_.size(); ++j) advance(T, j, q[j]);
    return T * tool_;
  }

  // frames[0] = base, frames[i] = T_0i for joint i = 1..n, frames[n+1] = tool.
  void frames(const Scalar* q, Rigid<Scalar>* out) const noexcept {
    Rigid<Scalar> T = base_;
    out[0] = T;
    for (std::size_t j = 0; j < joints_.size(); ++j) {
      advance(T, j, q[j]);
      out[j + 1] = T;
    }
    out[joints_.size() + 1] = T * tool_;
  }

  // Geometric Jacobian [v; w] of the tool point, column j:
  //   revolute  [z_j x (p_tool - o_j); z_j],   prismatic [z_j; 0],
  // with z_j, o_j the joint axis and a point on it (the course's summary sheet). Written
  // row-major into J (rows x n), rows = 6, or 3 for the position block.
  // In the tool frame, both blocks are rotated by R_tool^T.
  void jacobian(const Scalar* q, Scalar* J, int rows, bool in_tool_frame) const noexcept {
    const std::size_t n = joints_.size();
    Vec3<Scalar> axis[kMaxJoints], origin[kMaxJoints];
    Rigid<Scalar> T = base_;
    for (std::size_t j = 0; j < n; ++j) {
      const Joint<Scalar>& joint = joints_[j];
      joint.pre.apply(T);
      axis[j] = joint.axis_in(T);
      origin[j] = T.p;
      const Scalar angle = joint_theta(joint, q[j]);
      joint.apply_motion(T, Scalar(std::cos(angle)), Scalar(std::sin(angle)), joint_r(joint, q[j]));
      joint.post.apply(T);
    }
    write_jacobian(T * tool_, axis, origin, J, rows, in_tool_frame);
  }

 private:
  static void check_count(std::ptrdiff_t n) {
    if (n < 1 || n > kMaxJoints)
      throw std::invalid_argument("a chain needs 1 to " + std::to_string(kMaxJoints) + " joints, got " +
                                  std::to_string(n));
  }
  static void check_finite(const Rigid<double>& base, const Rigid<double>& tool) {
    for (const auto* T : {&base, &tool})
      if (!T->R.allFinite() || !T->p.allFinite())
        throw std::invalid_argument("base and tool transforms must be finite");
  }

  SPOTKIN_INLINE void write_jacobian(const Rigid<Scalar>& T, const Vec3<Scalar>* axis,
                                     const Vec3<Scalar>* origin, Scalar* J, int rows,
                                     bool in_tool_frame) const noexcept {
    const std::size_t n = joints_.size();
    for (std::size_t j = 0; j < n; ++j) {
      Vec3<Scalar> v, w;
      if (joints_[j].type == JointType::Revolute) {
        v = axis[j].cross(T.p - origin[j]);
        w = axis[j];
      } else {
        v = axis[j];
        w.setZero();
      }
      if (in_tool_frame) {
        v = T.R.transpose() * v;
        w = T.R.transpose() * w;
      }
      for (int r = 0; r < 3; ++r) J[r * n + j] = v[r];
      if (rows == 6)
        for (int r = 0; r < 3; ++r) J[(r + 3) * n + j] = w[r];
    }
  }

  static Scalar joint_theta(const Joint<Scalar>& j, Scalar q) noexcept {
    return j.type == JointType::Revolute ? j.theta + q : j.theta;
  }
  static Scalar joint_r(const Joint<Scalar>& j, Scalar q) noexcept {
    return j.type == JointType::Prismatic ? j.r + q : j.r;
  }
  void advance(Rigid<Scalar>& T, std::size_t j, Scalar q) const noexcept {
    const Joint<Scalar>& joint = joints_[j];
    joint.pre.apply(T);
    const Scalar angle = joint_theta(joint, q);
    joint.apply_motion(T, Scalar(std::cos(angle)), Scalar(std::sin(angle)), joint_r(joint, q));
    joint.post.apply(T);
  }

  std::vector<Joint<Scalar>> joints_;
  Rigid<Scalar> base_, tool_;
};

}  // namespace spotkin
