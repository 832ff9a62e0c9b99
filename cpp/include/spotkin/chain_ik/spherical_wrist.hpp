// Closed-form IK of 6R chains with a spherical wrist.
#pragma once

#include "spotkin/chain_ik/position3.hpp"

namespace spotkin::chain_ik {

// 6R chains whose last three axes meet at one point c (a spherical wrist):
// c fixes q1..q3 through Position3, then
//   W = A4^T R_A3^T R_target Tail^T = Rz(q4) B5 Rz(q5) B6 Rz(q6)
// gives the wrist angles (Paul's method on the third column):
//   (A)  e3 . B5 Rz(q5) b = w_z:  c5 (a_x b_x + a_y b_y) + s5 (a_y b_x - a_x b_y) = w_z - a_z b_z,
//        a = B5^T e3, b = B6 e3, w = W e3 (type 2: two q5);
//   (B)  Rz(q4) v = w, v = B5 Rz(q5) b:  e^{i q4} = (w_x + i w_y) / (v_x + i v_y);
//   (C)  Rz(q6) = (Rz(q4) B5 Rz(q5) B6)^T W.
// At most 4 x 2 = 8 solutions (the position part has at most 4, the wrist 2).
// In a wrist singularity (axes 4 and 6 aligned, v_xy = 0) q4 is free: 0 is
// returned and q6 takes the whole rotation.
class SphericalWrist6 {
 public:
  static constexpr int kSlots = 8;

  // Throws std::invalid_argument, naming the structure, when the chain is not
  // a 6-joint chain with revolute joints 4-6 whose axes meet at one point.
  static SphericalWrist6 make(const Chain<double>& chain, double scale) {
    if (chain.dof() != 6)
      throw std::invalid_argument("a spherical-wrist IK needs 6 joints, got " + std::to_string(chain.dof()));
    for (int j = 3; j < 6; ++j)
      if (chain.joints()[static_cast<std::size_t>(j)].type != JointType::Revolute)
        throw std::invalid_argument("no closed form: joint " + std::to_string(j + 1) +
                                    " is prismatic; a spherical wrist needs revolute joints 4, 5 and 6");
    // Axes 4, 5, 6 at q = 0, in the frame A3 just after joint 3's variable.
    const Rigid<double> L4 = link(chain, 3), L5 = link(chain, 4), L6 = link(chain, 5);
    const Rigid<double> F5 = L4 * L5, F6 = F5 * L6;
    const V3 o4 = L4.p, z4 = L4.R.col(2), o5 = F5.p, z5 = F5.R.col(2), o6 = F6.p, z6 = F6.R.col(2);
    const double tol = Tolerance::wrist * scale;
    const V3 n45 = z4.cross(z5), n56 = z5.cross(z6);
    if (n45.norm() <= Tolerance::angle || n56.norm() <= Tolerance::angle)
      throw std::invalid_argument(
          "no closed form: axes " + std::string(n45.norm() <= Tolerance::angle ? "4 and 5" : "5 and 6") +
          " are parallel, so the last three axes do not form a spherical wrist");
    // c: the point of axis 4 closest to axis 5
    const double h = (o5 - o4).cross(z5).dot(n45) / n45.squaredNorm();
    const V3 c = o4 + h * z4;
    const double d45 = std::fabs((o5 - o4).dot(n45)) / n45.norm();
    const double d6 = (c - o6).cross(z6).norm();
    if (d45 > tol || d6 > tol)
      throw std::invalid_argument(
          "no closed form: the last three axes do not meet at one point (axes 4-5 " + std::to_string(d45) +
          ", axis 6 " + std::to_string(d6) + " from their meeting point; tolerance " + std::to_string(tol) +
          "); a 6R closed form here needs a spherical wrist");
    SphericalWrist6 wrist{Position3(split_first_three(chain), c, scale)};
    wrist.A4_ = L4.R;
    wrist.B5_ = L5.R;
    wrist.B6_ = L6.R;
    const Rigid<double> tail = chain.z_tail(5) * chain.tool();
    wrist.tail_R_T_ = tail.R.transpose();
    // c in the tool frame: F6^-1 c in frame 6, then Tail^-1
    const Rigid<double> tail_inv = detail::inverse(tail), F6_inv = detail::inverse(F6);
    wrist.c_tool_ = tail_inv.R * (F6_inv.R * c + F6_inv.p) + tail_inv.p;
    return wrist;
  }

  const Position3& position() const noexcept { return position_; }

  // Every solution for a target pose: returns 1 if the position part has any
  // solution; q[slot] = (cos, sin) of the 6 angles, exists[slot] per slot.
  // Slot 2 k + b: position solution k (as Position3 orders them), wrist branch b.
  // solve, out of line, for the pose-by-pose path of solve_block (compiled once,
  // not in every instruction-set clone of the block kernels).
  SPOTKIN_SCALAR_PATH void solve_one(const Arm::Pose& target, JointValue q[kSlots][6], bool exists[kSlots]) const noexcept {
    solve(target, q, exists);
  }

  SPOTKIN_INLINE void solve(const Arm::Pose& target, JointValue q[kSlots][6], bool exists[kSlots]) const noexcept {
    M3 R;
    V3 p;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) R(i, j) = target.R[i][j];
      p[i] = target.p[i];
    }
    for (int k = 0; k < kSlots; ++k) exists[k] = false;
    JointValue arm[Position3::kSlots][3];
    const int n = position_.solve(R * c_tool_ + p, arm);
    // Columns 1 and 3 of R_F6 = R Tail^T: all of W that (A)-(C) need.
    const V3 x_F6 = R * tail_R_T_.col(0), z_F6 = R * tail_R_T_.col(2);
    const Split& S = position_.split();
    const V3 a = B5_.row(2).transpose(), b = B6_.col(2);
    for (int k = 0; k < n; ++k) {
      // W e = A4^T Rz3^T R2^T Rz2^T R1^T Rz1^T R0^T (R_F6 e), vector by vector
      auto to_wrist = [&](V3 x) {
        x = S.M0.R.transpose() * x;
        x = detail::z_rotate(position_.sigma(0), conjugate(arm[k][0]), x);
        x = S.M1.R.transpose() * x;
        x = detail::z_rotate(position_.sigma(1), conjugate(arm[k][1]), x);
        x = S.M2.R.transpose() * x;
        x = detail::z_rotate(position_.sigma(2), conjugate(arm[k][2]), x);
        return V3(A4_.transpose() * x);
      };
      const V3 w = to_wrist(z_F6), wx = to_wrist(x_F6);
      // (A) with sin(alpha) from the Gram determinant written as
      // |w_xy|^2 (1 - b_z^2) - (a_z - b_z w_z)^2, which keeps its accuracy where
      // axes 4 and 6 align (1 - ratio^2 would lose half the digits there).
      JointValue q5[2];
      const double gram = (w[0] * w[0] + w[1] * w[1]) * (1.0 - b[2] * b[2]) - (a[2] - b[2] * w[2]) * (a[2] - b[2] * w[2]);
      const int m = detail::cos_sin_roots(a[0] * b[0] + a[1] * b[1], a[1] * b[0] - a[0] * b[1], w[2] - a[2] * b[2], q5,
                                          std::sqrt(std::max(gram, 0.0)));
      for (int branch = 0; branch < m; ++branch) {
        const int slot = 2 * k + branch;
        const V3 v = B5_ * detail::z_rotate(0, q5[branch], b);
        // (B); q4 free (set to 0) where axes 4 and 6 align
        const JointValue q4 =
            v[0] * v[0] + v[1] * v[1] <= 1e-24 ? joint_zero() : detail::angle_difference(w[0], w[1], v[0], v[1]);
        // (C) first column of Rz(q6) = B6^T Rz5^T B5^T Rz4^T (W e1); unit up to
        // rounding, and only its angle is used
        V3 x = detail::z_rotate(0, conjugate(q4), wx);
        x = B5_.transpose() * x;
        x = detail::z_rotate(0, conjugate(q5[branch]), x);
        x = B6_.transpose() * x;
        const JointValue q6{x[0], x[1], 0.0};
        for (int j = 0; j < 3; ++j) q[slot][j] = arm[k][j];
        q[slot][3] = q4, q[slot][4] = q5[branch], q[slot][5] = q6;
        exists[slot] = true;
      }
    }
  }

  static constexpr int kLanes = Position3::kLanes;

  // solve() for m <= kLanes poses at once (the same equations run across the
  // poses, so that they vectorise; a short block goes pose by pose), finished
  // as finish_lanes does. pose_in[e][i] is element e of pose i, in the layout
  // of Arm::read_pose. Solutions across the lanes: slot k of pose i is
  // angle[k][j][i] for joint j (the value of a prismatic joint; wrapped into
  // the limits, NaN if the slot has no solution), exists[k][i] and
  // valid[k][i] (in the limits too) are 1 or 0, and input_ok[i] is 0 for a
  // pose that is not a rigid transform.
  template <PoseFormat Format>
  SPOTKIN_INLINE void solve_block(const double (*pose_in)[kLanes], int m, const Limits& limits,
                                  double (&angle)[kSlots][6][kLanes], double (&exists)[kSlots][kLanes],
                                  double (&valid)[kSlots][kLanes], double (&input_ok)[kLanes]) const noexcept {
    constexpr int width = Format == PoseFormat::Matrix ? 16 : 7;
    if (!position_.lane_form()) {  // pose by pose; otherwise a short block is padded (it costs less, measured)
      for (int i = 0; i < m; ++i) {
        double in[width];
        for (int e = 0; e < width; ++e) in[e] = pose_in[e][i];
        Arm::Pose target;
        input_ok[i] = Arm::read_pose<Format>(in, target);
        JointValue q[kSlots][6];
        bool ok[kSlots] = {};
        if (input_ok[i] != 0.0) solve_one(target, q, ok);
        for (int k = 0; k < kSlots; ++k) {
          exists[k][i] = ok[k] ? 1.0 : 0.0;
          for (int j = 0; j < 6; ++j)
            angle[k][j][i] = !ok[k] ? 0.0
                                 : j < 3 && position_.sigma(j) == 1 ? q[k][j].v
                                                                    : vector_math::atan2(q[k][j].s, q[k][j].c);
        }
      }
      finish_lanes<false>(limits, m, input_ok, angle, exists, valid);
      return;
    }
    constexpr int L = kLanes, K = Position3::kSlots;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // wrist centres c = R c_tool + p, and x0, z0 = R0^T R (columns 1 and 3 of Tail^T),
    // the columns 1 and 3 of R_F6 = R Tail^T seen from frame M0
    const Split& S = position_.split();
    double R[3][3][L], p[3][L];
    for (int i = 0; i < L; ++i) {
      double in[width];
      for (int e = 0; e < width; ++e) in[e] = pose_in[e][i < m ? i : m - 1];  // a short block: padded
      Arm::Pose target;
      const double use = Arm::read_pose<Format>(in, target);
      input_ok[i] = use;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R[r][c][i] = use != 0.0 ? target.R[r][c] : nan;
        p[r][i] = use != 0.0 ? target.p[r] : nan;
      }
    }
    const V3 t0 = tail_R_T_.col(0), t2 = tail_R_T_.col(2);
    const M3 M0T = S.M0.R.transpose();
    double cx[L], cy[L], cz[L], x0[3][L], z0[3][L];
    for (int i = 0; i < L; ++i) {
      double Rc[3], Rx[3], Rz[3];
      for (int r = 0; r < 3; ++r) {
        Rc[r] = R[r][0][i] * c_tool_[0] + R[r][1][i] * c_tool_[1] + R[r][2][i] * c_tool_[2] + p[r][i];
        Rx[r] = R[r][0][i] * t0[0] + R[r][1][i] * t0[1] + R[r][2][i] * t0[2];
        Rz[r] = R[r][0][i] * t2[0] + R[r][1][i] * t2[1] + R[r][2][i] * t2[2];
      }
      cx[i] = Rc[0], cy[i] = Rc[1], cz[i] = Rc[2];
      double x[3], z[3];
      detail::multiply(M0T, Rx, x);
      detail::multiply(M0T, Rz, z);
      for (int r = 0; r < 3; ++r) x0[r][i] = x[r], z0[r][i] = z[r];
    }
    Position3::BlockSolutions arm;
    position_.solve_block(cx, cy, cz, L, arm);
    // local copies: the stores to out cannot alias them (so the lane loops vectorise)
    const M3 B5 = B5_, B6 = B6_, A4 = A4_, M1R = S.M1.R, M2R = S.M2.R;
    const V3 a = B5.row(2).transpose(), b = B6.col(2);
    // (A): A c5 + B s5 = w_z - a_z b_z, solved as detail::cos_sin_root does but
    // with hypot(A, B) hoisted out of the lane loop (calling cos_sin_root here
    // stops GCC 12 from vectorising the loop)
    const double A = a[0] * b[0] + a[1] * b[1], B = a[1] * b[0] - a[0] * b[1];
    const double r2 = A * A + B * B, inv = r2 > 0.0 ? 1.0 / std::sqrt(r2) : 1.0, ca = A * inv, sa = B * inv;
    const Limits limit = limits;  // a local copy: the stores below cannot alias it
    for (int k = 0; k < K; ++k) {
      // position solution k (lane_form: every joint revolute) -> slots 2k, 2k + 1
      const int slot0 = 2 * k, slot1 = 2 * k + 1;
      for (int i = 0; i < L; ++i) {
        const double found = k < arm.n[i] ? input_ok[i] : 0.0;
        // q1..q3 wrapped into their limits, once for both slots
        double position_fit = 1.0, position_angle[3];
#pragma GCC unroll 3
        for (int j = 0; j < 3; ++j) {
          position_angle[j] = limit.wrap_value(j, vector_math::atan2(arm.s[k][j][i], arm.c[k][j][i]), position_fit);
        }
        // W e = A4^T Rz3^T R2^T Rz2^T R1^T Rz1^T (R0^T R_F6 e) for e = z, x
        double w[3] = {z0[0][i], z0[1][i], z0[2][i]}, wx[3] = {x0[0][i], x0[1][i], x0[2][i]};
        auto back = [&](int j, const M3& M) SPOTKIN_INLINE_LAMBDA {
          const double cj = arm.c[k][j][i], sj = arm.s[k][j][i];
          const double u[3] = {cj * w[0] + sj * w[1], -sj * w[0] + cj * w[1], w[2]};
          const double ux[3] = {cj * wx[0] + sj * wx[1], -sj * wx[0] + cj * wx[1], wx[2]};
          detail::multiply_transposed(M, u, w);
          detail::multiply_transposed(M, ux, wx);
        };
        back(0, M1R);
        back(1, M2R);
        back(2, A4);
        // (A), as solve() does, with sin(alpha) from the Gram determinant
        const double gram = (w[0] * w[0] + w[1] * w[1]) * (1.0 - b[2] * b[2]) - (a[2] - b[2] * w[2]) * (a[2] - b[2] * w[2]);
        const double ratio = (w[2] - a[2] * b[2]) * inv, clamped = std::min(1.0, std::max(-1.0, ratio));
        const double h = std::min(1.0, std::sqrt(std::max(gram, 0.0)) * inv);
        // r2 = 0 (axes 4 and 5, or 5 and 6, parallel) is refused when the chain is built
        const double solvable = r2 > 0.0 && std::fabs(ratio) <= 1.0 + Tolerance::ratio ? found : 0.0;
        auto branch = [&](int slot, double sign) SPOTKIN_INLINE_LAMBDA {
          const double hb = sign * h;
          const double c5 = r2 > 0.0 ? ca * clamped - sa * hb : 1.0, s5 = r2 > 0.0 ? sa * clamped + ca * hb : 0.0;
          // (B) v = B5 Rz(q5) b; q4 free (0) where axes 4 and 6 align
          const double rb[3] = {c5 * b[0] - s5 * b[1], s5 * b[0] + c5 * b[1], b[2]};
          double v[3];
          detail::multiply(B5, rb, v);
          const bool aligned = v[0] * v[0] + v[1] * v[1] <= 1e-24;
          const JointValue q4 = detail::angle_difference_lane(w[0], w[1], v[0], v[1]);
          const double c4 = aligned ? 1.0 : q4.c, s4 = aligned ? 0.0 : q4.s;
          // (C) first column of Rz(q6) = B6^T Rz5^T B5^T Rz4^T (W e1)
          const double y[3] = {c4 * wx[0] + s4 * wx[1], -s4 * wx[0] + c4 * wx[1], wx[2]};
          double z[3], x6[3];
          detail::multiply_transposed(B5, y, z);
          const double t[3] = {c5 * z[0] + s5 * z[1], -s5 * z[0] + c5 * z[1], z[2]};
          detail::multiply_transposed(B6, t, x6);
          const double wrist[3] = {vector_math::atan2(s4, c4), vector_math::atan2(s5, c5),
                                   vector_math::atan2(x6[1], x6[0])};
          double fit = solvable * position_fit;
#pragma GCC unroll 3
          for (int j = 0; j < 3; ++j) {
            const double wrapped = limit.wrap_value(3 + j, wrist[j], fit);
            angle[slot][j][i] = solvable != 0.0 ? position_angle[j] : nan;
            angle[slot][3 + j][i] = solvable != 0.0 ? wrapped : nan;
          }
          exists[slot][i] = solvable, valid[slot][i] = fit;
        };
        branch(slot0, 1.0);
        branch(slot1, -1.0);
      }
    }
  }

 private:
  static JointValue conjugate(const JointValue& q) noexcept { return JointValue{q.c, -q.s, -q.v}; }

  explicit SphericalWrist6(Position3 position) : position_(std::move(position)) {}

  Position3 position_;
  M3 A4_, B5_, B6_, tail_R_T_;
  V3 c_tool_;
};

}  // namespace spotkin::chain_ik
