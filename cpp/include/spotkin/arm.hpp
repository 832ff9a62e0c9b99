// 6R arm with a spherical wrist (the Spot Arm): FK, geometric Jacobian,
// singularity measures and closed-form IK with all 8 solutions (the course's Spot problem §4,
// re-derived; python/spotkin/reference/arm.py has the same steps written plainly).
//
//   T = Trans(mount) Rz(sh0) Ry(sh1) Trans(a,0,0) Ry(el0) Trans(b,0,h) Rx(el1) Ry(wr0) Rx(wr1) X
//
// with X = Trans(hand,0,0) . tool. The el1, wr0, wr1 axes meet at the wrist
// centre, so the IK decouples (Pieper):
//   (1) wrist pose T_w = T X^-1; wrist centre c = p(T_w) - mount.
//   (2) sh0 = atan2(c_y, c_x) (front) or + pi (back): cos, sin = +-(c_x, c_y) / r.
//   (3) elbow, Paul type 2: |c|^2 = a^2 + Lf^2 + 2 a Lf cos(el0 - phi), Lf = hypot(b, h),
//       phi = atan2(h, b):  el0 = phi + mu acos(K / Lf),  K = (|c|^2 - a^2 - Lf^2) / (2a),
//       mu = +1 (elbow branch 0) or -1; the forearm offset h is exact.
//   (4) sh1: Ry multiplies z + i x by e^{i angle}; with u the in-plane reach and
//       s = (a + b cos el0 + h sin el0, -b sin el0 + h cos el0) the wrist centre in
//       the sh1 frame, sh1 = arg((w + i u)(s_z - i s_x)).
//   (5) R_36 = (Rz(sh0) Ry(sh1 + el0))^T R_w = Rx(el1) Ry(wr0) Rx(wr1):
//       el1 = atan2(R10, -R20), wr0 = atan2(hypot(R10, R20), R00),
//       wr1 = atan2(-M12, M11), M = Rx(el1)^T R_36; the flip is (el1 + pi, -wr0, wr1 + pi).
// Slot = 4 * shoulder_branch + 2 * elbow_branch + wrist_branch.
//
// Singular cases, with defined answers:
//   shoulder (r = |c_xy| < kShoulderTolerance): sh0 = the seed's sh0 (0 without one);
//   wrist (|sin wr0| < kWristTolerance): el1 = the seed's el1 (0 without one), wr0 = 0
//   or pi exactly, wr1 solved so the orientation is exact;
//   elbow stretched or folded: |K / Lf| <= 1 + kRatioTolerance is clamped (both
//   elbow slots coincide).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "spotkin/common.hpp"
#include "spotkin/dense.hpp"
#include "spotkin/lane_rows.hpp"
#include "spotkin/leg.hpp"  // JointLimits, circle_distance
#include "spotkin/vector_math.hpp"

namespace spotkin {

struct ArmGeometry {
  double mount[3] = {0.292, 0.0, 0.188};  // sh0 origin in the body frame
  double upper_arm = 0.3385;              // a: sh1 -> el0 along x
  double forearm = 0.4033;                // b: el0 -> el1 along x
  double forearm_offset = 0.075;          // h: el0 -> el1 along z
  double hand = 0.19557;                  // wr1 -> hand frame along x
  Rigid<double> tool;                     // hand frame -> tool frame
};

// Which pose format a batch uses: row-major 4x4 matrices or [x y z qx qy qz qw].
enum class PoseFormat : std::int8_t { Matrix = 0, PositionQuaternion = 1 };

class Arm {
 public:
  static constexpr int kSlots = 8;
  static constexpr double kShoulderTolerance = 1e-12;  // m
  static constexpr double kWristTolerance = 1e-9;      // |sin wr0|
  static constexpr double kRatioTolerance = 1e-12;  // float32 targets: Leg::kRatioToleranceFloat
  static constexpr double kRotationTolerance = 1e-6;  // max |R^T R - I| accepted

  Arm() { update(); }
  Arm(const ArmGeometry& g, const JointLimits<6>& limits) : g_(g), limits_(limits) { update(); }

  const ArmGeometry& geometry() const noexcept { return g_; }
  const JointLimits<6>& limits() const noexcept { return limits_; }

  // Tool pose for one configuration (the block kernels' formulas, one sample).
  Rigid<double> forward(const double* q) const noexcept {
    double s[6][1], c[6][1], R[3][3], p[3];
    trig(q, s, c);
    forward_arrays<1>(s, c, 0, R, p);
    Rigid<double> T;
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) T.R(r, k) = R[r][k];
      T.p[r] = p[r];
    }
    return T;
  }

  // Geometric Jacobian [v; w] of the tool point, body frame, row-major 6x6.
  void jacobian(const double* q, double* J) const noexcept {
    double s[6][1], c[6][1];
    trig(q, s, c);
    jacobian_arrays<1>(s, c, 0, J);
  }

  // sin/cos of sh0, sh1, sh1 + el0, el1, wr0, wr1 for one sample (any magnitude).
  static void trig(const double* q, double (*s)[1], double (*c)[1]) noexcept {
    const double angles[6] = {q[0], q[1], q[1] + q[2], q[3], q[4], q[5]};
    double sv[6], cv[6];
    vector_math::sincos(angles, sv, cv, 6);
    for (int j = 0; j < 6; ++j) s[j][0] = sv[j], c[j][0] = cv[j];
  }

  // FK and Jacobian on plain arrays, so block kernels vectorise them across
  // samples; s[j][i], c[j][i] are the sines and cosines of sample i.
  template <std::ptrdiff_t B>
  SPOTKIN_INLINE void forward_arrays(const double (*s)[B], const double (*c)[B], std::ptrdiff_t i, double R[3][3],
                                     double p[3]) const noexcept {
    double wrist[3], Rw[3][3];
    wrist_frame(s, c, i, wrist, Rw, nullptr);
    // R = R03 R36 X_R, p = wrist + R03 R36 X_p
    double R6[3][3];
    const double s3 = s[3][i], c3 = c[3][i], s4 = s[4][i], c4 = c[4][i], s5 = s[5][i], c5 = c[5][i];
    const double R36[3][3] = {{c4, s4 * s5, s4 * c5},
                              {s3 * s4, c3 * c5 - s3 * c4 * s5, -c3 * s5 - s3 * c4 * c5},
                              {-c3 * s4, s3 * c5 + c3 * c4 * s5, -s3 * s5 + c3 * c4 * c5}};
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) R6[r][k] = Rw[r][0] * R36[0][k] + Rw[r][1] * R36[1][k] + Rw[r][2] * R36[2][k];
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) R[r][k] = R6[r][0] * X_R_[0][k] + R6[r][1] * X_R_[1][k] + R6[r][2] * X_R_[2][k];
      p[r] = wrist[r] + R6[r][0] * X_p_[0] + R6[r][1] * X_p_[1] + R6[r][2] * X_p_[2];
    }
  }

  template <std::ptrdiff_t B>
  SPOTKIN_INLINE void jacobian_arrays(const double (*s)[B], const double (*c)[B], std::ptrdiff_t i,
                                      double* J) const noexcept {
    double R[3][3], p[3], wrist[3], R03[3][3], elbow[3];
    forward_arrays(s, c, i, R, p);
    wrist_frame(s, c, i, wrist, R03, elbow);
    const double s0 = s[0][i], c0 = c[0][i], s3 = s[3][i], c3 = c[3][i], s4 = s[4][i], c4 = c[4][i];
    const double y4_local[3] = {0.0, c3, s3};                  // Rx(el1) e_y
    const double x5_local[3] = {c4, s3 * s4, -c3 * s4};        // Rx(el1) Ry(wr0) e_x
    double axes[6][3] = {{0, 0, 1}, {-s0, c0, 0}, {-s0, c0, 0}, {R03[0][0], R03[1][0], R03[2][0]}, {}, {}};
    for (int r = 0; r < 3; ++r) {
      axes[4][r] = R03[r][0] * y4_local[0] + R03[r][1] * y4_local[1] + R03[r][2] * y4_local[2];
      axes[5][r] = R03[r][0] * x5_local[0] + R03[r][1] * x5_local[1] + R03[r][2] * x5_local[2];
    }
    const double* points[6] = {g_.mount, g_.mount, elbow, wrist, wrist, wrist};
    for (int j = 0; j < 6; ++j) {
      const double d[3] = {p[0] - points[j][0], p[1] - points[j][1], p[2] - points[j][2]};
      const double* z = axes[j];
      J[0 * 6 + j] = z[1] * d[2] - z[2] * d[1];
      J[1 * 6 + j] = z[2] * d[0] - z[0] * d[2];
      J[2 * 6 + j] = z[0] * d[1] - z[1] * d[0];
      J[3 * 6 + j] = z[0];
      J[4 * 6 + j] = z[1];
      J[5 * 6 + j] = z[2];
    }
  }

  // Wrist centre and R03 = Rz(sh0) Ry(sh1 + el0) (and the elbow point if asked).
  template <std::ptrdiff_t B>
  SPOTKIN_INLINE void wrist_frame(const double (*s)[B], const double (*c)[B], std::ptrdiff_t i, double wrist[3],
                                  double R03[3][3], double* elbow) const noexcept {
    const double s0 = s[0][i], c0 = c[0][i], s1 = s[1][i], c1 = c[1][i], s2 = s[2][i], c2 = c[2][i];
    const double a = g_.upper_arm, b = g_.forearm, h = g_.forearm_offset;
    R03[0][0] = c0 * c2, R03[0][1] = -s0, R03[0][2] = c0 * s2;
    R03[1][0] = s0 * c2, R03[1][1] = c0, R03[1][2] = s0 * s2;
    R03[2][0] = -s2, R03[2][1] = 0.0, R03[2][2] = c2;
    const double e[3] = {g_.mount[0] + c0 * c1 * a, g_.mount[1] + s0 * c1 * a, g_.mount[2] - s1 * a};
    for (int r = 0; r < 3; ++r) wrist[r] = e[r] + R03[r][0] * b + R03[r][2] * h;
    if (elbow) elbow[0] = e[0], elbow[1] = e[1], elbow[2] = e[2];
  }

  // Wrist, elbow and shoulder distances to the singular sets, and sqrt(det(J J^T)).
  void singularity(const double* q, double* out) const noexcept {
    double J[36];
    jacobian(q, J);
    const double el0 = q[2];
    const double sx = g_.upper_arm + g_.forearm * std::cos(el0) + g_.forearm_offset * std::sin(el0);
    const double sz = -g_.forearm * std::sin(el0) + g_.forearm_offset * std::cos(el0);
    const double cx = std::cos(q[1]) * sx + std::sin(q[1]) * sz;  // in-plane reach of the wrist centre
    out[0] = std::fabs(std::sin(q[4]));
    out[1] = std::fabs(std::sin(el0 - phi_));
    out[2] = std::fabs(cx);
    out[3] = std::fabs(dense::determinant6(J));
  }

  // A pose as plain arrays: the vectorised kernels avoid Eigen, whose
  // out-of-line product loops would stop the compiler vectorising them.
  struct Pose {
    double R[3][3];
    double p[3];
  };

  // Target pose of one sample and its validity (1.0 / 0.0), branch-free.
  template <PoseFormat Format, typename T>
  static SPOTKIN_INLINE double read_pose(const T* in, Pose& pose) noexcept {
    double ok = 1.0;
    if constexpr (Format == PoseFormat::Matrix) {
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) pose.R[i][j] = double(in[4 * i + j]);
        pose.p[i] = double(in[4 * i + 3]);
      }
      const double row_error = std::max(std::max(std::fabs(double(in[12])), std::fabs(double(in[13]))),
                                        std::max(std::fabs(double(in[14])), std::fabs(double(in[15]) - 1.0)));
      ok = row_error <= 1e-9 ? ok : 0.0;
      double orth = 0.0;  // max |R^T R - I|
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const double dot = pose.R[0][a] * pose.R[0][b] + pose.R[1][a] * pose.R[1][b] + pose.R[2][a] * pose.R[2][b];
          orth = std::max(orth, std::fabs(dot - (a == b ? 1.0 : 0.0)));
        }
      const double det = pose.R[0][0] * (pose.R[1][1] * pose.R[2][2] - pose.R[1][2] * pose.R[2][1]) -
                         pose.R[0][1] * (pose.R[1][0] * pose.R[2][2] - pose.R[1][2] * pose.R[2][0]) +
                         pose.R[0][2] * (pose.R[1][0] * pose.R[2][1] - pose.R[1][1] * pose.R[2][0]);
      ok = ((orth <= kRotationTolerance) & (det > 0.0)) ? ok : 0.0;
    } else {
      const double x = double(in[3]), y = double(in[4]), z = double(in[5]), w = double(in[6]);
      const double n2 = x * x + y * y + z * z + w * w;
      ok = std::fabs(std::sqrt(n2) - 1.0) <= kRotationTolerance ? ok : 0.0;
      const double s = 2.0 / n2;  // an exact rotation even for |q| = 1 +- 1e-6
      pose.R[0][0] = 1 - s * (y * y + z * z), pose.R[0][1] = s * (x * y - z * w), pose.R[0][2] = s * (x * z + y * w);
      pose.R[1][0] = s * (x * y + z * w), pose.R[1][1] = 1 - s * (x * x + z * z), pose.R[1][2] = s * (y * z - x * w);
      pose.R[2][0] = s * (x * z - y * w), pose.R[2][1] = s * (y * z + x * w), pose.R[2][2] = 1 - s * (x * x + y * y);
      pose.p[0] = double(in[0]), pose.p[1] = double(in[1]), pose.p[2] = double(in[2]);
    }
    double sum = 0.0;  // NaN and Inf fail every comparison above or make this NaN
    for (int i = 0; i < 3; ++i) sum += pose.R[i][0] + pose.R[i][1] + pose.R[i][2] + pose.p[i];
    if constexpr (Format == PoseFormat::Matrix)  // std::max drops a NaN of the last row
      sum += double(in[12]) + double(in[13]) + double(in[14]) + double(in[15]);
    return (sum - sum) == 0.0 ? ok : 0.0;
  }

  // What the four (shoulder, elbow) branches of solve_all share: the wrist centre and frame, the
  // shoulder angle, the elbow's half angle and the seeds' sines and cosines (steps 1-3).
  struct Shared {
    double Rw[3][3], c[3], c0, s0, sh0, cos_delta, sin_delta, delta, seed_s3, seed_c3, seed_el1;
  };

  // Steps 1-3 for a target pose; returns 1.0 where the solutions exist (all eight or none).
  SPOTKIN_INLINE double solve_shared(const Pose& target, double seed_sh0, double seed_el1,
                                     Shared& h, double tol) const noexcept {
    // (1) wrist pose T_w = T X^-1
    double* c = h.c;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        h.Rw[i][j] = target.R[i][0] * inv_X_R_[0][j] + target.R[i][1] * inv_X_R_[1][j] +
                     target.R[i][2] * inv_X_R_[2][j];
      c[i] = target.R[i][0] * inv_X_p_[0] + target.R[i][1] * inv_X_p_[1] + target.R[i][2] * inv_X_p_[2] +
             target.p[i] - g_.mount[i];
    }
    const double r = std::sqrt(c[0] * c[0] + c[1] * c[1]);
    // (2) shoulder
    const bool shoulder_singular = r < kShoulderTolerance;
    double seed_s0, seed_c0;
    vector_math::sincos_bounded(seed_sh0, seed_s0, seed_c0);
    const double inv_r = shoulder_singular ? 0.0 : 1.0 / r;
    h.c0 = shoulder_singular ? seed_c0 : c[0] * inv_r;
    h.s0 = shoulder_singular ? seed_s0 : c[1] * inv_r;
    h.sh0 = shoulder_singular ? wrap_angle_vec(seed_sh0) : vector_math::atan2(c[1], c[0]);
    // (3) elbow
    const double a = g_.upper_arm;
    const double ratio = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2] - a * a - Lf_ * Lf_) * inv_2aLf_;
    const double exists = std::fabs(ratio) <= 1.0 + tol ? 1.0 : 0.0;
    h.cos_delta = std::clamp(ratio, -1.0, 1.0);
    h.sin_delta = std::sqrt((1.0 - h.cos_delta) * (1.0 + h.cos_delta));
    h.delta = vector_math::atan2(h.sin_delta, h.cos_delta);
    // seed el1 sin/cos for the wrist-singular case
    vector_math::sincos_bounded(seed_el1, h.seed_s3, h.seed_c3);
    h.seed_el1 = seed_el1;
    return exists;
  }

  // Steps 4-5 for one (shoulder, elbow) branch: sign0 = +1 / -1 the shoulder facing the wrist
  // centre or turned by pi, mu = +1 / -1 the elbow's sign; q0, q1 its two wrist solutions.
  // Branch-free. One pose alone runs the four branches through this (solve_block).
  SPOTKIN_INLINE void solve_branch(const Shared& h, double sign0, double mu, double q0[6],
                                   double q1[6]) const noexcept {
    const double a = g_.upper_arm;
    const double* c = h.c;
    const double cs0 = sign0 * h.c0, ss0 = sign0 * h.s0;
    const double sh0_b = sign0 > 0.0 ? h.sh0 : wrap_angle_vec(h.sh0 + kPi<double>);
    const double u = cs0 * c[0] + ss0 * c[1], w = c[2];  // (4) the arm plane
    const double el0 = wrap_angle_vec(phi_ + mu * h.delta);
    const double cos_el0 = cos_phi_ * h.cos_delta - mu * sin_phi_ * h.sin_delta;
    const double sin_el0 = sin_phi_ * h.cos_delta + mu * cos_phi_ * h.sin_delta;
    const double sx = a + g_.forearm * cos_el0 + g_.forearm_offset * sin_el0;
    const double sz = -g_.forearm * sin_el0 + g_.forearm_offset * cos_el0;
    const double sh1 = vector_math::atan2(u * sz - w * sx, w * sz + u * sx);
    double s12, c12;
    vector_math::sincos_bounded(sh1 + el0, s12, c12);
    // (5) R36 = R03^T R_w, R03 = Rz(sh0) Ry(sh1 + el0)
    const double r0[3] = {cs0 * c12, ss0 * c12, -s12};  // rows of R03^T
    const double r1[3] = {-ss0, cs0, 0.0};
    const double r2[3] = {cs0 * s12, ss0 * s12, c12};
    double R36[3][3];
    for (int j = 0; j < 3; ++j) {
      R36[0][j] = r0[0] * h.Rw[0][j] + r0[1] * h.Rw[1][j] + r0[2] * h.Rw[2][j];
      R36[1][j] = r1[0] * h.Rw[0][j] + r1[1] * h.Rw[1][j];
      R36[2][j] = r2[0] * h.Rw[0][j] + r2[1] * h.Rw[1][j] + r2[2] * h.Rw[2][j];
    }
    const double s4 = std::sqrt(R36[1][0] * R36[1][0] + R36[2][0] * R36[2][0]);
    const bool wrist_singular = s4 < kWristTolerance;
    const double inv_s4 = wrist_singular ? 0.0 : 1.0 / s4;
    const double c3 = wrist_singular ? h.seed_c3 : -R36[2][0] * inv_s4;
    const double s3 = wrist_singular ? h.seed_s3 : R36[1][0] * inv_s4;
    const double el1 =
        wrist_singular ? wrap_angle_vec(h.seed_el1) : vector_math::atan2(R36[1][0], -R36[2][0]);
    const double wr0 =
        wrist_singular ? (R36[0][0] > 0.0 ? 0.0 : kPi<double>) : vector_math::atan2(s4, R36[0][0]);
    const double M11 = c3 * R36[1][1] + s3 * R36[2][1];
    const double M12 = c3 * R36[1][2] + s3 * R36[2][2];
    const double wr1 = vector_math::atan2(-M12, M11);
    // atan2 gives -pi for a -0 sine: the angle pi, which (-pi, pi] keeps (wrap_angle_vec maps it)
    q0[0] = q1[0] = wrap_angle_vec(sh0_b);
    q0[1] = q1[1] = wrap_angle_vec(sh1);
    q0[2] = q1[2] = el0;
    q0[3] = wrap_angle_vec(el1), q0[4] = wr0, q0[5] = wrap_angle_vec(wr1);
    q1[3] = wrap_angle_vec(el1 + kPi<double>);
    q1[4] = wrap_angle_vec(-wr0);
    q1[5] = wrap_angle_vec(wr1 + kPi<double>);
  }

  // All 8 solutions for a target pose (steps 1-5). seed_sh0 / seed_el1 are the
  // free angles in the shoulder and wrist singular cases. Returns 1.0 where the
  // solutions exist (all eight or none), 0.0 elsewhere. Branch-free.
  SPOTKIN_INLINE double solve_all(const Pose& target, double seed_sh0, double seed_el1,
                                  double q[kSlots][6],
                                  double tol = kRatioTolerance) const noexcept {
    Shared h;
    const double exists = solve_shared(target, seed_sh0, seed_el1, h, tol);
#pragma GCC unroll 2
    for (int sb = 0; sb < 2; ++sb)
#pragma GCC unroll 2
      for (int eb = 0; eb < 2; ++eb)
        solve_branch(h, sb == 0 ? 1.0 : -1.0, eb == 0 ? 1.0 : -1.0, q[4 * sb + 2 * eb],
                     q[4 * sb + 2 * eb + 1]);
    return exists;
  }

 private:
  // Wrap into (-pi, pi] for |x| < 3 pi, branch-free.
  static SPOTKIN_INLINE double wrap_angle_vec(double x) noexcept {
    constexpr double pi = kPi<double>, two_pi = 2.0 * kPi<double>;
    const double y = x > pi ? x - two_pi : x;
    return y <= -pi ? y + two_pi : y;
  }

  void update() noexcept {
    Rigid<double> hand;
    hand.p = Vec3<double>(g_.hand, 0.0, 0.0);
    hand_tool_ = hand * g_.tool;
    inv_hand_tool_.R = hand_tool_.R.transpose();
    inv_hand_tool_.p = -(hand_tool_.R.transpose() * hand_tool_.p);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) inv_X_R_[i][j] = inv_hand_tool_.R(i, j), X_R_[i][j] = hand_tool_.R(i, j);
      inv_X_p_[i] = inv_hand_tool_.p[i], X_p_[i] = hand_tool_.p[i];
    }
    Lf_ = std::hypot(g_.forearm, g_.forearm_offset);
    phi_ = std::atan2(g_.forearm_offset, g_.forearm);
    cos_phi_ = g_.forearm / Lf_;
    sin_phi_ = g_.forearm_offset / Lf_;
    inv_2aLf_ = 1.0 / (2.0 * g_.upper_arm * Lf_);
  }

  ArmGeometry g_;
  JointLimits<6> limits_;
  Rigid<double> hand_tool_, inv_hand_tool_;
  double inv_X_R_[3][3], inv_X_p_[3], X_R_[3][3], X_p_[3];
  double Lf_ = 0, phi_ = 0, cos_phi_ = 1, sin_phi_ = 0, inv_2aLf_ = 0;
};

namespace arm_batch {

constexpr std::ptrdiff_t kBlock = 32;

// sin/cos of sh0, sh1, sh1 + el0, el1, wr0, wr1 for a block (vectorised).
struct BlockTrig {
  double angle[6][kBlock], s[6][kBlock], c[6][kBlock];
};

template <typename T>
SPOTKIN_INLINE void block_trig(const T* q, std::ptrdiff_t m, BlockTrig& b) noexcept {
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    const T* qi = q + 6 * i;
    b.angle[0][i] = double(qi[0]), b.angle[1][i] = double(qi[1]), b.angle[2][i] = double(qi[1]) + double(qi[2]);
    b.angle[3][i] = double(qi[3]), b.angle[4][i] = double(qi[4]), b.angle[5][i] = double(qi[5]);
  }
  for (int j = 0; j < 6; ++j) vector_math::sincos(b.angle[j], b.s[j], b.c[j], m);
}

// Tool poses (16 per sample, row-major 4x4) from a block's sines and cosines.
SPOTKIN_CLONES((__attribute__((noinline)) inline), void, fk_block, (const Arm& arm, const double (*__restrict s)[kBlock],
                                           const double (*__restrict c)[kBlock], double (*__restrict out)[kBlock],
                                           std::ptrdiff_t m) noexcept, (arm, s, c, out, m),
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    double R[3][3], p[3];
    arm.forward_arrays(s, c, i, R, p);
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) out[4 * r + k][i] = R[r][k];
      out[4 * r + 3][i] = p[r];
    }
  }
)

// Jacobians (36 per sample, row-major 6x6) from a block's sines and cosines.
SPOTKIN_CLONES((__attribute__((noinline)) inline), void, jacobian_block, (const Arm& arm, const double (*__restrict s)[kBlock],
                                                 const double (*__restrict c)[kBlock],
                                                 double (*__restrict out)[kBlock], std::ptrdiff_t m) noexcept, (arm, s, c, out, m),
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    double J[36];
    arm.jacobian_arrays(s, c, i, J);
    for (int k = 0; k < 36; ++k) out[k][i] = J[k];
  }
)

template <typename T>
SPOTKIN_INLINE void fk(const Arm& arm, const T* q, T* out, std::ptrdiff_t count) noexcept {
  BlockTrig b;
  double soa[16][kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    block_trig(q + 6 * b0, m, b);
    fk_block(arm, b.s, b.c, soa, m);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      T* o = out + 16 * (b0 + i);
      for (int k = 0; k < 12; ++k) o[k] = T(soa[k][i]);
      o[12] = o[13] = o[14] = T(0), o[15] = T(1);
    }
  }
}

template <typename T>
SPOTKIN_INLINE void jacobian(const Arm& arm, const T* q, T* out, std::ptrdiff_t count) noexcept {
  BlockTrig b;
  double soa[36][kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    block_trig(q + 6 * b0, m, b);
    jacobian_block(arm, b.s, b.c, soa, m);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      T* o = out + 36 * (b0 + i);
      for (int k = 0; k < 36; ++k) o[k] = T(soa[k][i]);
    }
  }
}

template <typename T>
SPOTKIN_INLINE bool finite6(const T* v) noexcept {
  for (int j = 0; j < 6; ++j)
    if (!std::isfinite(double(v[j]))) return false;
  return true;
}

// The vectorised core of ik_all: every solution of every pose in a block.
// soa[k][i] is pose element k of sample i; qs[6 * slot + joint][i] receives the angles.
SPOTKIN_CLONES_T(
    (template <PoseFormat Format> __attribute__((noinline))), void, solve_block, (<Format>),
    (const Arm& arm, const double (*__restrict soa)[kBlock], const double* __restrict seed_sh0,
     const double* __restrict seed_el1, const double* __restrict seed_ok,
     double* __restrict ok_pose, double* __restrict ex, double (*__restrict qs)[kBlock],
     std::ptrdiff_t m, double tol) noexcept,
    (arm, soa, seed_sh0, seed_el1, seed_ok, ok_pose, ex, qs, m, tol),
    constexpr int kWidth = Format == PoseFormat::Matrix ? 16 : 7;
    // One pose (a single call): its four branches through a loop of their own, rather than the
    // batch's per-pose code as the vector loop's remainder (AVX2: 0.81 us a call from Python, and
    // the loop over the branches in lanes with `omp simd` 0.71 us, against 0.50 us this way; GCC
    // keeps it scalar). No fused multiply-adds in this unit (CMakeLists.txt): the same bits.
    if (m == 1) {
      double in[kWidth];
      for (int k = 0; k < kWidth; ++k) in[k] = soa[k][0];
      Arm::Pose pose;
      const double pose_ok = arm.read_pose<Format>(in, pose) * seed_ok[0];
      Arm::Shared h;
      const double found = arm.solve_shared(pose, seed_sh0[0], seed_el1[0], h, tol);
      ok_pose[0] = pose_ok;
      ex[0] = pose_ok * found;
      double lanes[12][4];
      for (int k = 0; k < 4; ++k) {  // k = 2 sb + eb
        double q0[6], q1[6];
        arm.solve_branch(h, k < 2 ? 1.0 : -1.0, (k & 1) ? -1.0 : 1.0, q0, q1);
        for (int j = 0; j < 6; ++j) lanes[j][k] = q0[j], lanes[6 + j][k] = q1[j];
      }
      for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 12; ++j) qs[12 * k + j][0] = lanes[j][k];
      return;
    } for (std::ptrdiff_t i = 0; i < m; ++i) {
      double in[kWidth];
      for (int k = 0; k < kWidth; ++k) in[k] = soa[k][i];
      Arm::Pose pose;
      const double pose_ok = arm.read_pose<Format>(in, pose) * seed_ok[i];
      double q_all[Arm::kSlots][6];
      const double found = arm.solve_all(pose, seed_sh0[i], seed_el1[i], q_all, tol);
      ok_pose[i] = pose_ok;
      ex[i] = pose_ok * found;
      for (int s = 0; s < Arm::kSlots; ++s)
        for (int j = 0; j < 6; ++j) qs[6 * s + j][i] = q_all[s][j];
    })

// A pose's status: from its validity, whether any slot is valid, and whether solutions exist.
SPOTKIN_INLINE std::int8_t pose_status(double pose_ok, double any_valid, double exists) noexcept {
  return pose_ok == 0.0     ? std::int8_t(Status::InvalidInput)
         : any_valid != 0.0 ? std::int8_t(Status::Ok)
         : exists != 0.0    ? std::int8_t(Status::JointLimit)
                            : std::int8_t(Status::Unreachable);
}

// Every solution: q (count, 8, 6) NaN where none exist, valid and exists
// (count, 8), status (count). seed (count, 6) or null: used for the free angles
// of the shoulder and wrist singular cases.
template <int RegisterBytes = 64, typename T>
SPOTKIN_INLINE void ik_all(const Arm& arm, const T* poses, PoseFormat format, const T* seed, T* q,
                           std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                           std::ptrdiff_t count) noexcept {
  constexpr double nan = quiet_nan<double>();
  const std::ptrdiff_t stride = format == PoseFormat::Matrix ? 16 : 7;
  double qs[Arm::kSlots * 6][kBlock], ex[kBlock], ok_pose[kBlock], ok[Arm::kSlots][kBlock];
  double seed_sh0[kBlock], seed_el1[kBlock], seed_ok[kBlock], soa[16][kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // stage the poses as structure of arrays
      const T* in = poses + stride * (b0 + i);
      for (std::ptrdiff_t k = 0; k < stride; ++k) soa[k][i] = double(in[k]);
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const T* si = seed ? seed + 6 * (b0 + i) : nullptr;
      seed_ok[i] = !si || finite6(si) ? 1.0 : 0.0;
      seed_sh0[i] = si && seed_ok[i] != 0.0 ? remainder_two_pi(double(si[0])) : 0.0;
      seed_el1[i] = si && seed_ok[i] != 0.0 ? remainder_two_pi(double(si[3])) : 0.0;
    }
    if (format == PoseFormat::Matrix) {
      solve_block<PoseFormat::Matrix>(arm, soa, seed_sh0, seed_el1, seed_ok, ok_pose, ex, qs, m, Leg::ratio_tolerance<T>());
    } else {
      solve_block<PoseFormat::PositionQuaternion>(arm, soa, seed_sh0, seed_el1, seed_ok, ok_pose, ex, qs, m, Leg::ratio_tolerance<T>());
    }
    if (m == 1) {  // one pose (a single call): its eight slots in a loop of their own
      const double e = ex[0];
      T* qt = q + 48 * b0;
      double any = 0.0;
      for (int s = 0; s < Arm::kSlots; ++s) {  // the limits, each slot written as it is tested
        double qi[6];
        for (int j = 0; j < 6; ++j) qi[j] = qs[6 * s + j][0];
        const double valid_slot = e * arm.limits().wrap_mask(qi);
        any = std::max(any, valid_slot);
        for (int j = 0; j < 6; ++j) qt[6 * s + j] = T(e != 0.0 ? qi[j] : nan);
        valid[8 * b0 + s] = valid_slot != 0.0;
        exists[8 * b0 + s] = e != 0.0;
      }
      status[b0] = pose_status(ok_pose[0], any, e);
      continue;
    }
    double any_valid[kBlock];
    for (std::ptrdiff_t i = 0; i < m; ++i) any_valid[i] = 0.0;
#pragma GCC unroll 8
    for (int s = 0; s < Arm::kSlots; ++s) {
      for (std::ptrdiff_t i = 0; i < m; ++i) {  // vectorised: limits per slot
        double qi[6];
        for (int j = 0; j < 6; ++j) qi[j] = qs[6 * s + j][i];
        ok[s][i] = ex[i] * arm.limits().wrap_mask(qi);
        any_valid[i] = std::max(any_valid[i], ok[s][i]);
        for (int j = 0; j < 6; ++j) qs[6 * s + j][i] = ex[i] != 0.0 ? qi[j] : nan;
      }
    }
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // vectorised: statuses
      status[b0 + i] = pose_status(ok_pose[i], any_valid[i], ex[i]);
    }
    // back to (sample, slot, joint) order: float64 by transpose_rows (one value at a time, the
    // loads 256 bytes apart took a quarter of a batch's time; 1e5 poses, one thread: AVX2 204-208
    // -> 187-188 ns a pose, AVX-512 161-163 -> 151 ns); float32 answers are rounded one by one
    constexpr bool same_type = std::is_same_v<T, double>;
    if constexpr (same_type) transpose_rows<RegisterBytes>(qs, 48, m, q + 48 * b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      T* qt = q + 48 * (b0 + i);
      if constexpr (!same_type)
        for (int k = 0; k < 48; ++k) qt[k] = T(qs[k][i]);
      for (int s = 0; s < Arm::kSlots; ++s) {
        valid[8 * (b0 + i) + s] = ok[s][i] != 0.0;
        exists[8 * (b0 + i) + s] = ex[i] != 0.0;
      }
    }
  }
}

// The in-limit solution nearest to the seed (largest single-joint move on the
// circle; ties to the lower slot), or the lowest valid slot without a seed. Every solution
// of a block comes from all(poses, format, seed, q_all, valid, exists, status, m), ik_all's
// signature: the bindings pass their dispatched ik_all kernel, so that the solver is not
// compiled a second time inside this one.
template <typename T, typename All>
SPOTKIN_INLINE void ik(const Arm& /*arm: all() holds it*/, const T* poses, PoseFormat format, const T* seed, T* q,
                       std::int8_t* status, std::ptrdiff_t count, All&& all) noexcept {
  T q_all[kBlock * Arm::kSlots * 6];
  std::uint8_t valid[kBlock * Arm::kSlots], exists[kBlock * Arm::kSlots];
  std::int8_t st[kBlock];
  const std::ptrdiff_t stride = format == PoseFormat::Matrix ? 16 : 7;
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    all(poses + stride * b0, format, seed ? seed + 6 * b0 : nullptr, q_all, valid, exists, st, m);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const std::ptrdiff_t t = b0 + i;
      T* qt = q + 6 * t;
      status[t] = st[i];
      int best = -1;
      double best_distance = std::numeric_limits<double>::infinity();
      for (int s = 0; s < Arm::kSlots && st[i] == std::int8_t(Status::Ok); ++s) {
        if (!valid[Arm::kSlots * i + s]) continue;
        if (!seed) {
          best = s;
          break;
        }
        double qa[6], qb[6];
        for (int j = 0; j < 6; ++j) qa[j] = double(q_all[48 * i + 6 * s + j]), qb[j] = double(seed[6 * t + j]);
        const double d = circle_distance<6>(qa, qb);
        if (d < best_distance) best = s, best_distance = d;
      }
      for (int j = 0; j < 6; ++j) qt[j] = best >= 0 ? q_all[48 * i + 6 * best + j] : T(quiet_nan<double>());
    }
  }
}

}  // namespace arm_batch

}  // namespace spotkin
