// Preferential Jacobians (the course's "jacobienne préférentielle" J_k(j)): the geometric
// Jacobian of the origin O_k of frame k, expressed in the axes of frame j.
//
// Frames are numbered as Chain::frames: 0 the base transform's frame, i = 1..n the frame after
// joint i, n + 1 the tool; frame -1 is the reference frame the poses are given in (the Chain's
// "base" axes). With z_i, o_i joint i's axis and a point on it in the reference frame, column i of
// the reference-frame Jacobian of O_k is
//   revolute [z_i x (O_k - o_i); z_i],   prismatic [z_i; 0]      for the joints before frame k,
//   0                                                           for the others (they do not move O_k),
// and J_k(j) = diag(R_j^T, R_j^T) J_k(-1), R_j frame j's rotation in the reference frame. Both blocks
// are rotated: J_k(j) maps q' to O_k's velocity and the angular velocity of frame k, both relative
// to the reference frame, written in frame j's axes. Derivation: docs/derivations.md.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "spotkin/chain.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin {

// rows x n Jacobian per sample (row-major, rows = 6 or 3: the position block), q row-major
// count x n. point in [0, n + 1], frame in [-1, n + 1] (checked by the caller).
template <typename Scalar>
SPOTKIN_INLINE void point_jacobian_batch(const Chain<Scalar>& chain, const Scalar* q, Scalar* out,
                                         std::ptrdiff_t count, int rows, int point, int frame) noexcept {
  constexpr std::ptrdiff_t kBlock = 32;
  const auto& joints = chain.joints();
  const int n = chain.dof();
  const int tool_index = n + 1;
  const int walked = std::min(n, std::max(point, frame));  // joints the sample needs
  double angle[kBlock], s[Chain<Scalar>::kMaxJoints][kBlock], c[Chain<Scalar>::kMaxJoints][kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    for (int j = 0; j < walked; ++j) {
      const Joint<Scalar>& joint = joints[static_cast<std::size_t>(j)];
      const double revolute = joint.type == JointType::Revolute ? 1.0 : 0.0;
      for (std::ptrdiff_t i = 0; i < m; ++i) angle[i] = double(joint.theta) + revolute * double(q[(b0 + i) * n + j]);
      vector_math::sincos(angle, s[j], c[j], m);
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const Scalar* qi = q + (b0 + i) * n;
      Vec3<Scalar> axis[Chain<Scalar>::kMaxJoints], origin[Chain<Scalar>::kMaxJoints];
      Rigid<Scalar> T = chain.base();
      int next = 0;  // the next joint to apply
      auto walk_to = [&](int stop) {
        for (; next < stop; ++next) {
          const Joint<Scalar>& joint = joints[static_cast<std::size_t>(next)];
          joint.pre.apply(T);
          axis[next] = joint.axis_in(T);
          origin[next] = T.p;
          const Scalar shift = joint.type == JointType::Prismatic ? joint.r + qi[next] : joint.r;
          joint.apply_motion(T, Scalar(c[next][i]), Scalar(s[next][i]), shift);
          joint.post.apply(T);
        }
      };
      // walk to the nearer of the two frames, record it, then on to the other (no test per joint)
      Vec3<Scalar> p;
      Mat3<Scalar> R = Mat3<Scalar>::Identity();
      const int first = std::min(point, std::max(frame, 0)), second = std::max(point, frame);
      for (const int stop : {first, second}) {
        walk_to(std::min(stop, n));
        const Rigid<Scalar> F = stop == tool_index ? T * chain.tool() : T;
        if (stop == point) p = F.p;
        if (stop == frame) R = F.R;
      }
      Scalar* J = out + std::ptrdiff_t(rows) * n * (b0 + i);
      for (int j = 0; j < n; ++j) {
        Vec3<Scalar> v = Vec3<Scalar>::Zero(), w = Vec3<Scalar>::Zero();
        if (j < point) {  // joint j moves frames j + 1 onwards
          if (joints[static_cast<std::size_t>(j)].type == JointType::Revolute) {
            v = axis[j].cross(p - origin[j]);
            w = axis[j];
          } else {
            v = axis[j];
          }
          if (frame >= 0) {
            v = R.transpose() * v;
            w = R.transpose() * w;
          }
        }
        for (int r = 0; r < 3; ++r) J[r * n + j] = v[r];
        if (rows == 6)
          for (int r = 0; r < 3; ++r) J[(r + 3) * n + j] = w[r];
      }
    }
  }
}

}  // namespace spotkin
