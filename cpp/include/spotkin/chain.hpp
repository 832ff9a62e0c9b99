// Serial chains from Denavit-Hartenberg tables: forward kinematics, every
// frame, and the geometric Jacobian (seed 004, "Jacobienne géométrique").
//
// Both conventions are screws along x and z (RotX and TransX commute, as do
// RotZ and TransZ):
//   DHm (Khalil-Kleinfinger):  T(j-1,j) = RotX(alpha) TransX(d) . RotZ(theta) TransZ(r)
//   DH  (classic):             T(j-1,j) = RotZ(theta) TransZ(d) . TransX(a) RotX(alpha)
// so every joint is  X(pre) . Z(theta, r) . X(post),  with the joint variable
// added to theta (revolute) or r (prismatic). The joint axis is the z axis of
// the frame reached after X(pre).
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

// Screw along x: TransX(a) RotX(alpha), with alpha's cosine and sine cached.
template <typename Scalar>
struct XScrew {
  Scalar a = 0, alpha = 0, cos_alpha = 1, sin_alpha = 0;
  bool identity = true;

  static XScrew make(double a, double alpha) {
    XScrew s;
    s.a = Scalar(a);
    s.alpha = Scalar(alpha);
    s.cos_alpha = Scalar(std::cos(alpha));
    s.sin_alpha = Scalar(std::sin(alpha));
    s.identity = (a == 0.0 && alpha == 0.0);
    return s;
  }

  // T <- T . TransX(a) RotX(alpha)
  SPOTKIN_INLINE void apply(Rigid<Scalar>& T) const noexcept {
    if (identity) return;
    T.p.noalias() += a * T.R.col(0);
    const Vec3<Scalar> y = T.R.col(1), z = T.R.col(2);
    T.R.col(1) = cos_alpha * y + sin_alpha * z;
    T.R.col(2) = cos_alpha * z - sin_alpha * y;
  }
};

template <typename Scalar>
struct Joint {
  JointType type = JointType::Revolute;
  XScrew<Scalar> pre, post;
  Scalar theta = 0;  // angle about z at q = 0
  Scalar r = 0;      // offset along z at q = 0
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
    if (n < 1 || n > kMaxJoints)
      throw std::invalid_argument("a chain needs 1 to " + std::to_string(kMaxJoints) +
                                  " joints, got " + std::to_string(n));
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
      const auto screw = XScrew<Scalar>::make(row[1], row[2]);
      (convention == Convention::ModifiedDH ? joint.pre : joint.post) = screw;
    }
    for (const auto* T : {&base, &tool})
      if (!T->R.allFinite() || !T->p.allFinite())
        throw std::invalid_argument("base and tool transforms must be finite");
    return Chain(std::move(joints), base.template cast<Scalar>(), tool.template cast<Scalar>());
  }

  template <typename Other>
  Chain<Other> cast() const {
    std::vector<Joint<Other>> joints;
    joints.reserve(joints_.size());
    for (const auto& j : joints_) {
      Joint<Other> o;
      o.type = j.type;
      o.pre = XScrew<Other>::make(double(j.pre.a), double(j.pre.alpha));
      o.post = XScrew<Other>::make(double(j.post.a), double(j.post.alpha));
      o.theta = Other(j.theta);
      o.r = Other(j.r);
      joints.push_back(o);
    }
    return Chain<Other>(std::move(joints), base_.template cast<Other>(),
                        tool_.template cast<Other>());
  }

  int dof() const noexcept { return static_cast<int>(joints_.size()); }
  const std::vector<Joint<Scalar>>& joints() const noexcept { return joints_; }
  const Rigid<Scalar>& base() const noexcept { return base_; }
  const Rigid<Scalar>& tool() const noexcept { return tool_; }

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
  // with z_j, o_j the joint axis and a point on it (seed 004). Written
  // row-major into J (rows x n), rows = 6, or 3 for the position block.
  // In the tool frame, both blocks are rotated by R_tool^T.
  void jacobian(const Scalar* q, Scalar* J, int rows, bool in_tool_frame) const noexcept {
    const std::size_t n = joints_.size();
    Vec3<Scalar> axis[kMaxJoints], origin[kMaxJoints];
    Rigid<Scalar> T = base_;
    for (std::size_t j = 0; j < n; ++j) {
      const Joint<Scalar>& joint = joints_[j];
      joint.pre.apply(T);
      axis[j] = T.R.col(2);
      origin[j] = T.p;
      apply_z_screw(T, joint_theta(joint, q[j]), joint_r(joint, q[j]));
      joint.post.apply(T);
    }
    write_jacobian(T * tool_, axis, origin, J, rows, in_tool_frame);
  }

  // Batched versions over `count` samples (q row-major count x n). They work on
  // blocks of kBlock samples: first every joint's sine and cosine for the whole
  // block (vectorised), then the per-sample products.
  static constexpr std::ptrdiff_t kBlock = 32;

  SPOTKIN_INLINE void forward_batch(const Scalar* q, Scalar* out, std::ptrdiff_t count) const noexcept {
    BlockTrig trig;
    for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
      const std::ptrdiff_t m = std::min(kBlock, count - b0);
      block_trig(q + b0 * dof(), m, trig);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const Scalar* qi = q + (b0 + i) * dof();
        Rigid<Scalar> T = base_;
        for (std::size_t j = 0; j < joints_.size(); ++j) advance(T, j, qi[j], trig, i);
        write_homogeneous(T * tool_, out + 16 * (b0 + i));
      }
    }
  }

  // (n + 2) frames per sample, as frames().
  SPOTKIN_INLINE void frames_batch(const Scalar* q, Scalar* out, std::ptrdiff_t count) const noexcept {
    BlockTrig trig;
    const std::ptrdiff_t stride = 16 * (dof() + 2);
    for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
      const std::ptrdiff_t m = std::min(kBlock, count - b0);
      block_trig(q + b0 * dof(), m, trig);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const Scalar* qi = q + (b0 + i) * dof();
        Scalar* o = out + stride * (b0 + i);
        Rigid<Scalar> T = base_;
        write_homogeneous(T, o);
        for (std::size_t j = 0; j < joints_.size(); ++j) {
          advance(T, j, qi[j], trig, i);
          write_homogeneous(T, o + 16 * (j + 1));
        }
        write_homogeneous(T * tool_, o + 16 * (joints_.size() + 1));
      }
    }
  }

  // rows x n Jacobian per sample, as jacobian().
  SPOTKIN_INLINE void jacobian_batch(const Scalar* q, Scalar* out, std::ptrdiff_t count, int rows,
                                     bool in_tool_frame) const noexcept {
    BlockTrig trig;
    const std::ptrdiff_t n = dof();
    for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
      const std::ptrdiff_t m = std::min(kBlock, count - b0);
      block_trig(q + b0 * n, m, trig);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const Scalar* qi = q + (b0 + i) * n;
        Vec3<Scalar> axis[kMaxJoints], origin[kMaxJoints];
        Rigid<Scalar> T = base_;
        for (std::size_t j = 0; j < joints_.size(); ++j) {
          const Joint<Scalar>& joint = joints_[j];
          joint.pre.apply(T);
          axis[j] = T.R.col(2);
          origin[j] = T.p;
          apply_z_screw(T, Scalar(trig.c[j][i]), Scalar(trig.s[j][i]), joint_r(joint, qi[j]));
          joint.post.apply(T);
        }
        write_jacobian(T * tool_, axis, origin, out + rows * n * (b0 + i), rows, in_tool_frame);
      }
    }
  }

 private:
  struct BlockTrig {
    double angle[kBlock];
    double s[kMaxJoints][kBlock];
    double c[kMaxJoints][kBlock];
  };

  SPOTKIN_INLINE void block_trig(const Scalar* q, std::ptrdiff_t m, BlockTrig& trig) const noexcept {
    const std::ptrdiff_t n = dof();
    for (std::ptrdiff_t j = 0; j < n; ++j) {
      const Joint<Scalar>& joint = joints_[static_cast<std::size_t>(j)];
      const double revolute = joint.type == JointType::Revolute ? 1.0 : 0.0;
      for (std::ptrdiff_t i = 0; i < m; ++i)
        trig.angle[i] = double(joint.theta) + revolute * double(q[i * n + j]);
      vector_math::sincos(trig.angle, trig.s[j], trig.c[j], m);
    }
  }

  SPOTKIN_INLINE void advance(Rigid<Scalar>& T, std::size_t j, Scalar q, const BlockTrig& trig,
                              std::ptrdiff_t i) const noexcept {
    const Joint<Scalar>& joint = joints_[j];
    joint.pre.apply(T);
    apply_z_screw(T, Scalar(trig.c[j][i]), Scalar(trig.s[j][i]), joint_r(joint, q));
    joint.post.apply(T);
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
    apply_z_screw(T, joint_theta(joint, q), joint_r(joint, q));
    joint.post.apply(T);
  }

  std::vector<Joint<Scalar>> joints_;
  Rigid<Scalar> base_, tool_;
};

}  // namespace spotkin
