// Roll-pitch-pitch legs (Spot's hx, hy, kn; Go2's hip, thigh, calf; any leg
// whose axes at zero angles are +-x, +-y, +-y in the body frame): FK,
// Jacobian and closed-form IK with every branch. Geometry and model (R1) in
// rpp_geometry.hpp; derivation (re-derived from the course's Spot problem and generalised;
// python/spotkin/reference/rpp_leg.py writes the same equations plainly):
//
//   (I1) hip roll, Paul type 2: v = Rx(theta1)^T p has v_y = h = a_y + b_y + c_y,
//        i.e. y cos theta1 + z sin theta1 = h.  With r^2 = y^2 + z^2,
//        S = sqrt(r^2 - h^2) and eps = +1 (hip branch 0, "normal") or -1:
//          cos theta1 = (y h - eps z S) / r^2,   sin theta1 = (z h + eps y S) / r^2,
//        and then v_z = -eps S (no solution when r < |h|).
//   (I2) the pitch plane, with zeta(u) = u_z + i u_x (Ry(t) multiplies zeta by e^{it}):
//          W = (v_z - a_z) + i (x - a_x) = e^{i theta2} (B + e^{i theta3} C),  B = zeta(b), C = zeta(c).
//   (I3) knee, type 2: |W|^2 = |B|^2 + |C|^2 + 2 |B| |C| cos psi,  psi = theta3 + phi,
//        phi = arg C - arg B:  psi = -mu acos(ratio), mu = +1 (knee branch 0,
//        "knee back": sin psi <= 0) or -1 ("knee forward").
//   (I4) hip pitch: theta2 = arg(W conj(D)),  D = B + e^{i theta3} C.
//   q_k = s_k theta_k, wrapped into (-pi, pi].
//
// Slot order: slot = 2 * hip_branch + knee_branch:
//   0 (hip normal, knee back), 1 (normal, forward), 2 (flipped, back), 3 (flipped, forward).
// The two knee slots of a hip branch exist together; the two hip branches
// differ only when a_z != 0 (|W| then depends on eps).
#pragma once

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "spotkin/common.hpp"
#include "spotkin/rpp_geometry.hpp"
#include "spotkin/rpp_nearest.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin {

// Joint limits and the branch choice shared by the leg and arm solvers.
template <int N>
struct JointLimits {
  double lower[N], upper[N];

  JointLimits() {
    for (int j = 0; j < N; ++j) {
      lower[j] = -std::numeric_limits<double>::infinity();
      upper[j] = std::numeric_limits<double>::infinity();
    }
  }

  static constexpr double kTolerance = 1e-12;  // rad
  // Solutions for float32 targets carry the targets' rounding (~1e-7 rad): a
  // solution that far outside a limit, from an in-limit configuration, still fits.
  static constexpr double kToleranceFloat = 2e-6;  // rad
  template <typename T>
  static constexpr double tolerance() noexcept {
    return sizeof(T) < sizeof(double) ? kToleranceFloat : kTolerance;
  }

  // Wraps each joint by 0, -2pi or +2pi (the first that fits, within tol) into
  // the limits, in place, then onto them (a joint within tol outside a bound is
  // set to the bound), and returns 1.0 if every joint fits, 0.0 otherwise
  // (joints that fit no way are left as given). Branch-free, for vectorised
  // loops; C is the kernel's compute type (float for the float32 kernels).
  // Turn false: the angles turned by 2 pi are not tried (may_turn).
  template <bool Turn = true, typename C = double>
  SPOTKIN_INLINE C wrap_mask(C* q, C tol = C(kTolerance)) const noexcept {
    return wrap_mask_within<Turn>(lower, upper, q, tol);
  }
  // Whether wrap_mask may turn an angle of [-pi, pi] by 2 pi to fit the limits: only where a
  // limit lies beyond +-3 (a margin over pi and the tolerances, in float and double). Where not,
  // wrap_mask<false> gives the same results and bits without computing the turned angles.
  bool may_turn() const noexcept {
    for (int j = 0; j < N; ++j)
      if (!(lower[j] > -3.0 && upper[j] < 3.0)) return true;
    return false;
  }
  // wrap_mask within the bounds lower, upper (a lane kernel's: each lane its own limits).
  template <bool Turn = true, typename C>
  static SPOTKIN_INLINE C wrap_mask_within(const double* lower, const double* upper, C* q,
                                           C tol) noexcept {
    constexpr C two_pi = C(2) * kPi<C>;
    C all = 1;
#pragma GCC unroll 8
    for (int j = 0; j < N; ++j) {
      const C lower_j = C(lower[j]), upper_j = C(upper[j]);
      const C lo = lower_j - tol, hi = upper_j + tol;
      const C v = q[j];
      const bool in0 = (v >= lo) & (v <= hi);
      C chosen = v;
      bool fits = in0;
      if constexpr (Turn) {
        const C minus = v - two_pi, plus = v + two_pi;
        const bool in_minus = (minus >= lo) & (minus <= hi);
        const bool in_plus = (plus >= lo) & (plus <= hi);
        chosen = in0 ? v : (in_minus ? minus : plus);
        fits = in0 | in_minus | in_plus;
      }
      q[j] = fits ? std::min(std::max(chosen, lower_j), upper_j) : v;
      all = fits ? all : C(0);
    }
    return all;
  }
};

// Largest single-joint move between a and b, measured on the circle.
template <int N>
SPOTKIN_INLINE double circle_distance(const double* a, const double* b) noexcept {
  double worst = 0.0;
  for (int j = 0; j < N; ++j) worst = std::max(worst, std::fabs(wrap_angle(a[j] - b[j])));
  return worst;
}

// The foot position a Spot-style description gives: lateral hx -> hy offset h1
// (signed: + left), hy -> knee (k forward, U down), knee -> foot (L down).
inline RppGeometry spot_style_geometry(double h1, double upper, double lower, double knee_offset) {
  RppGeometry g;
  g.a[0] = 0.0, g.a[1] = h1, g.a[2] = 0.0;
  g.b[0] = knee_offset, g.b[1] = 0.0, g.b[2] = -upper;
  g.c[0] = 0.0, g.c[1] = 0.0, g.c[2] = -lower;
  g.sign[0] = g.sign[1] = g.sign[2] = 1.0;
  return g;
}

// The constants of (I1)-(I4) for one leg, derived from its RppGeometry (Leg::update): the
// branch solves read only these, so that a kernel can give each lane a different leg's.
struct RppConstants {
  double a0 = 0, a2 = 0, h = 0;  // a_x, a_z; h = a_y + b_y + c_y (I1)
  double h2 =
      0;  // h^2, rounded once: a kernel with h in lanes must not fuse r^2 - h^2 into one FMA
  double Bz = 0, Bx = 0, Cz = 0, Cx = 0;     // B = zeta(b), C = zeta(c) (I2)
  double phi = 0, cos_phi = 1, sin_phi = 0;  // phi = arg C - arg B (I3)
  double knee_sum_sq = 0, inv_2BC = 0;       // |B|^2 + |C|^2, 1 / (2 |B| |C|) (I3)
  double sign1 = 1, sign2 = 1, sign3 = 1;    // q_k = s_k theta_k
};

class Leg {
 public:
  static constexpr int kSlots = 4;
  // |ratio| <= 1 + tol counts as touching a singular set (so targets placed
  // exactly on it, after rounding, still have their merged solution). float32
  // targets carry ~6e-8 relative rounding, so they get a wider tolerance.
  static constexpr double kRatioTolerance = 1e-12;
  static constexpr double kRatioToleranceFloat = 1e-6;
  template <typename T>
  static constexpr double ratio_tolerance() noexcept {
    return sizeof(T) < sizeof(double) ? kRatioToleranceFloat : kRatioTolerance;
  }

  Leg() { update(-1); }
  // preferred_slot: the slot ik() takes without a seed when it is valid (then
  // the others in slot order); -1 picks it from the knee's limits (the knee
  // branch that the middle of the knee's range lies on, hip normal).
  // Throws std::invalid_argument for a geometry without a closed form.
  Leg(const RppGeometry& g, const JointLimits<3>& limits, int preferred_slot = -1) : g_(g), limits_(limits) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(g.a[k]) || !std::isfinite(g.b[k]) || !std::isfinite(g.c[k]))
        throw std::invalid_argument("leg geometry must be finite");
      if (g.sign[k] != 1.0 && g.sign[k] != -1.0) throw std::invalid_argument("axis signs must be +1 or -1");
    }
    if (!(std::hypot(g.b[0], g.b[2]) > 0.0) || !(std::hypot(g.c[0], g.c[2]) > 0.0))
      throw std::invalid_argument(
          "no closed form: the hip-pitch -> knee and knee -> foot offsets must not lie along the pitch axis");
    if (preferred_slot < -1 || preferred_slot >= kSlots)
      throw std::invalid_argument("preferred_slot must be -1 or a slot 0..3");
    update(preferred_slot);
  }

  const RppGeometry& geometry() const noexcept { return g_; }
  const JointLimits<3>& limits() const noexcept { return limits_; }
  double max_reach() const noexcept { return d_max_; }  // |W| max = |B| + |C|
  double min_reach() const noexcept { return d_min_; }  // |W| min = ||B| - |C||
  int preferred_slot() const noexcept { return order_[0]; }
  // Slots in the order ik() tries them without a seed.
  const int* slot_order() const noexcept { return order_; }
  // a_z = 0: the knee's solution does not depend on the hip branch.
  bool shared_knee() const noexcept { return g_.a[2] == 0.0; }
  const RppConstants& constants() const noexcept { return k_; }

  // (R1), with zeta = A + e^{i theta2} (B + e^{i theta3} C) the pitch-plane part.
  template <typename T>
  SPOTKIN_INLINE void forward(const T* q, T* p) const noexcept {
    double s[3], c[3];
    const double angles[3] = {k_.sign1 * double(q[0]), k_.sign2 * double(q[1]),
                              k_.sign2 * double(q[1]) + k_.sign3 * double(q[2])};
    vector_math::sincos(angles, s, c, 3);
    double vx, vz;
    plane(c[1], s[1], c[2], s[2], vx, vz);
    p[0] = T(vx);
    p[1] = T(k_.h * c[0] - vz * s[0]);
    p[2] = T(k_.h * s[0] + vz * c[0]);
  }

  // d p / d q (row-major 3x3): columns s1 (0, -p_z, p_y), s2 Rx(theta1)(y x u2),
  // s3 Rx(theta1)(y x u3), u2 = zeta^-1(e^{i theta2}(B + e^{i theta3} C)), u3 = zeta^-1(e^{i(theta2+theta3)} C).
  template <typename T>
  SPOTKIN_INLINE void jacobian(const T* q, T* J) const noexcept {
    double s[3], c[3];
    const double angles[3] = {k_.sign1 * double(q[0]), k_.sign2 * double(q[1]),
                              k_.sign2 * double(q[1]) + k_.sign3 * double(q[2])};
    vector_math::sincos(angles, s, c, 3);
    double out[9];
    jacobian_from(c, s, out);
    for (int k = 0; k < 9; ++k) J[k] = T(out[k]);
  }

  // |det J| and the smallest singular value of J.
  template <typename T>
  void singularity(const T* q, T* abs_det, T* sigma_min) const noexcept {
    T Jt[9];
    jacobian(q, Jt);
    Eigen::Matrix3d J;
    for (int i = 0; i < 9; ++i) J(i / 3, i % 3) = double(Jt[i]);
    if (!J.allFinite()) {  // Eigen's SVD of NaN is unspecified (it read stale values)
      *abs_det = *sigma_min = T(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    *abs_det = T(std::fabs(J.determinant()));
    *sigma_min = T(Eigen::JacobiSVD<Eigen::Matrix3d>(J).singularValues()[2]);
  }

  // A slot's branch signs as values (slot = 2 hip branch + knee branch), for the batch passes of
  // one slot: hip is eps of (I1), +1 for the normal hip branch and -1 for the flipped one; knee is
  // -1 for knee branch 0 (psi = -acos, (I3)) and +1 for branch 1. Multiplying by +-1 is exact, so
  // the passes give the bits that constant signs gave, in one compiled copy instead of four.
  template <typename C>
  struct SlotSigns {
    C hip, knee;
  };
  template <typename C>
  static constexpr SlotSigns<C> slot_signs(int slot) noexcept {
    return {slot < 2 ? C(1) : C(-1), slot % 2 == 0 ? C(-1) : C(1)};
  }

  // One slot of (I1)-(I4) in stages for block loops, over arrays the caller holds (SlotStages): the
  // hip's square root in one loop (slot_hip), the knee and the angles in the next (slot_knee,
  // slot_angles). The hip's square root then no longer sits on the long loop's critical path: the
  // out-of-order core overlaps those of successive iterations (AVX2: body_ik 113 -> 102 ns; a third
  // loop for the knee measured no better). Same operations as solve_all_with's. The stages hold the
  // slot's signs: S is eps S, and sin_psi and acos_psi carry the knee branch's sign (the stages'
  // one multiply each, where the angles' loop, the longest, would take two).
  template <typename C, std::ptrdiff_t N>
  struct SlotStages {
    C S[N], hip_exists[N], cos_psi[N], sin_psi[N], acos_psi[N], knee_exists[N];
  };
  template <typename C, std::ptrdiff_t N>
  SPOTKIN_INLINE void slot_hip(std::ptrdiff_t i, C y, C z, C tol, SlotSigns<C> signs,
                               SlotStages<C, N>& st) const noexcept {
    slot_hip_with(k_, i, y, z, tol, signs, st);
  }
  template <typename C, std::ptrdiff_t N>
  SPOTKIN_INLINE void slot_knee(std::ptrdiff_t i, C x, C tol, SlotSigns<C> signs,
                                SlotStages<C, N>& st) const noexcept {
    slot_knee_with(k_, i, x, tol, signs, st);
  }
  template <typename C, std::ptrdiff_t N>
  SPOTKIN_INLINE C slot_angles(std::ptrdiff_t i, C x, C y, C z, const SlotStages<C, N>& st,
                               C q[3]) const noexcept {
    return slot_angles_with(k_, i, x, y, z, st, q);
  }
  // A lower bound on the circle distance (circle_distance, the largest joint's) from the slot's
  // answer to any other slot's, from its stages: the other knee branch's q3 is 2 acos_psi away
  // (mod 2 pi), at least 2 sin_psi; the other hip branch's q1 is 2 atan2(S, h) away (mod 2 pi), at
  // least 2 S / (|h| + S) (atan t >= t / (1 + t) for t >= 0). 0 where the branches meet.
  template <typename C, std::ptrdiff_t N>
  SPOTKIN_INLINE C slot_separation(std::ptrdiff_t i, const SlotStages<C, N>& st) const noexcept {
    return slot_separation_with(k_, i, st);
  }
  template <typename C, std::ptrdiff_t N>
  static SPOTKIN_INLINE C slot_separation_with(const RppConstants& k, std::ptrdiff_t i,
                                               const SlotStages<C, N>& st) noexcept {
    const C S = std::fabs(st.S[i]), sum = C(std::fabs(k.h)) + S;
    const C hip = sum > C(0) ? C(2) * S / sum : C(0), knee = C(2) * std::fabs(st.sin_psi[i]);
    return hip < knee ? hip : knee;
  }
  // The stages with a leg's constants k (a lane kernel's: each lane its own leg's).
  template <typename C, std::ptrdiff_t N>
  static SPOTKIN_INLINE void slot_hip_with(const RppConstants& k, std::ptrdiff_t i, C y, C z, C tol,
                                           SlotSigns<C> signs, SlotStages<C, N>& st) noexcept {
    const Hip<C> hip = solve_hip(k, y, z, tol);
    st.S[i] = signs.hip * hip.S, st.hip_exists[i] = hip.exists;
  }
  template <typename C, std::ptrdiff_t N>
  static SPOTKIN_INLINE void slot_knee_with(const RppConstants& k, std::ptrdiff_t i, C x, C tol,
                                            SlotSigns<C> signs, SlotStages<C, N>& st) noexcept {
    const Knee<C> knee = solve_knee(k, x - C(k.a0), -st.S[i] - C(k.a2), tol, signs.knee);
    st.cos_psi[i] = knee.cos_psi, st.sin_psi[i] = knee.sin_psi, st.acos_psi[i] = knee.acos_psi;
    st.knee_exists[i] = knee.exists;
  }
  template <typename C, std::ptrdiff_t N>
  static SPOTKIN_INLINE C slot_angles_with(const RppConstants& k, std::ptrdiff_t i, C x, C y, C z,
                                           const SlotStages<C, N>& st, C q[3]) noexcept {
    const C signed_S = st.S[i];  // eps S: (eps y) S = y (eps S) exactly
    const Knee<C> knee{st.cos_psi[i], st.sin_psi[i], st.acos_psi[i], st.knee_exists[i]};
    const C wx = x - C(k.a0), wz = -signed_S - C(k.a2);
    q[0] = hip_roll_signed(k, y, z, y * y + z * z, signed_S);
    q[1] = hip_pitch(k, wx, wz, knee, C(1));  // the knee's sign is in knee's sin_psi, acos_psi
    q[2] = knee_angle(k, knee, C(1));
    return st.hip_exists[i] * knee.exists;
  }

  // All four branches of (I1)-(I4) for one target, angles in (-pi, pi], and
  // 1.0 / 0.0 per hip branch for whether it exists (both knee slots of a hip
  // branch exist together; ratios are clamped into [-1, 1] either way): a form
  // the compiler vectorises over samples.
  // SharedKnee: the caller knows a_z = 0 (shared_knee()), so |W| and the knee
  // are the same on both hip branches and are solved once.
  // C: the compute type (double, or float for the float32 kernels).
  template <bool SharedKnee = false, typename C = double>
  SPOTKIN_INLINE void solve_all_mask(C x, C y, C z, C q[kSlots][3], C exists_hip[2],
                                     C tol = C(kRatioTolerance)) const noexcept {
    solve_all_with<SharedKnee>(k_, x, y, z, q, exists_hip, tol);
  }
  // solve_all_mask with a leg's constants k (a lane kernel's: each lane its own leg's).
  template <bool SharedKnee, typename C>
  static SPOTKIN_INLINE void solve_all_with(const RppConstants& k, C x, C y, C z, C q[kSlots][3],
                                            C exists_hip[2], C tol) noexcept {
    const Hip<C> hip = solve_hip(k, y, z, tol);
    const C wx = x - C(k.a0);
    Knee<C> shared;
    if (SharedKnee) shared = solve_knee(k, wx, hip.S, tol);
#pragma GCC unroll 2
    for (int hb = 0; hb < 2; ++hb) {
      const C eps = hb == 0 ? C(1) : C(-1);
      const C hx = hip_roll(k, y, z, hip, eps);
      const C wz = SharedKnee ? -eps * hip.S : -eps * hip.S - C(k.a2);
      const Knee<C> knee = SharedKnee ? shared : solve_knee(k, wx, wz, tol);
      exists_hip[hb] = hip.exists * knee.exists;
#pragma GCC unroll 2
      for (int kb = 0; kb < 2; ++kb) {
        C* slot = q[2 * hb + kb];
        slot[0] = hx;
        const C knee_sign = kb == 0 ? C(-1) : C(1);
        slot[1] = hip_pitch(k, wx, wz, knee, knee_sign);
        slot[2] = knee_angle(k, knee, knee_sign);
      }
    }
  }

  // The configuration within `limits` whose foot is nearest to p (exact; see
  // rpp_nearest.hpp), or with no limits at all when !within_limits. Writes the
  // foot position to out and, when q_out is given, the joint angles. NaN for a
  // non-finite p.
  void nearest_reachable(const double* p, double* out, bool within_limits = false,
                         double* q_out = nullptr) const noexcept {
    constexpr double inf = std::numeric_limits<double>::infinity();
    const double no_lower[3] = {-inf, -inf, -inf}, no_upper[3] = {inf, inf, inf};
    // A target farther than kFar is solved at kFar along its direction: the candidates' distances
    // stay resolvable (~1e-8 m), and the nearest point moves by less than that (it tends to the
    // support point in that direction).
    constexpr double kFar = 1e8;
    double target[3] = {p[0], p[1], p[2]}, q[3];
    const double norm = std::hypot(p[0], std::hypot(p[1], p[2]));
    if (norm > kFar && std::isfinite(norm))
      for (double& v : target) v = v / norm * kFar;
    rpp_nearest_in_limits(g_, within_limits ? limits_.lower : no_lower, within_limits ? limits_.upper : no_upper,
                          target, q);
    if (q_out) q_out[0] = q[0], q_out[1] = q[1], q_out[2] = q[2];
    forward(q, out);
  }

  // Knee joint origin for q (the leg frame): Rx(theta1)(a + Ry(theta2) b).
  void knee_position(const double* q, double* out) const noexcept {
    const double t1 = k_.sign1 * q[0], t2 = k_.sign2 * q[1];
    const double c2 = std::cos(t2), s2 = std::sin(t2), c1 = std::cos(t1), s1 = std::sin(t1);
    const double vx = g_.a[0] + c2 * g_.b[0] + s2 * g_.b[2], vy = g_.a[1] + g_.b[1];
    const double vz = g_.a[2] - s2 * g_.b[0] + c2 * g_.b[2];
    out[0] = vx, out[1] = c1 * vy - s1 * vz, out[2] = s1 * vy + c1 * vz;
  }

  // Batch helpers (leg_batch): the pitch-plane part of (R1) from the
  // cosines and sines of theta2 and theta2 + theta3.
  SPOTKIN_INLINE void plane(double c2, double s2, double c23, double s23, double& vx, double& vz) const noexcept {
    // zeta = A + e^{i t2} B + e^{i t23} C;  v_z = Re, v_x = Im
    vz = g_.a[2] + c2 * k_.Bz - s2 * k_.Bx + c23 * k_.Cz - s23 * k_.Cx;
    vx = g_.a[0] + c2 * k_.Bx + s2 * k_.Bz + c23 * k_.Cx + s23 * k_.Cz;
  }
  SPOTKIN_INLINE double lateral() const noexcept { return k_.h; }
  SPOTKIN_INLINE double sign(int k) const noexcept {
    return k == 0 ? k_.sign1 : (k == 1 ? k_.sign2 : k_.sign3);
  }

  // Jacobian from c[k], s[k] = cos, sin of theta1, theta2, theta2 + theta3.
  SPOTKIN_INLINE void jacobian_from(const double* c, const double* s, double* J) const noexcept {
    // u3 = e^{i t23} C, u2 = e^{i t2} B + u3 (zeta components z + i x)
    const double u3z = c[2] * k_.Cz - s[2] * k_.Cx, u3x = c[2] * k_.Cx + s[2] * k_.Cz;
    const double u2z = c[1] * k_.Bz - s[1] * k_.Bx + u3z, u2x = c[1] * k_.Bx + s[1] * k_.Bz + u3x;
    const double vz = g_.a[2] + u2z, vx = g_.a[0] + u2x;
    const double py = k_.h * c[0] - vz * s[0], pz = k_.h * s[0] + vz * c[0];
    (void)vx;
    // y x u = (u_z, 0, -u_x), then Rx(theta1): (u_z, s1 u_x, -c1 u_x)
    J[0] = 0.0, J[1] = k_.sign2 * u2z, J[2] = k_.sign3 * u3z;
    J[3] = -k_.sign1 * pz, J[4] = k_.sign2 * s[0] * u2x, J[5] = k_.sign3 * s[0] * u3x;
    J[6] = k_.sign1 * py, J[7] = -k_.sign2 * c[0] * u2x, J[8] = -k_.sign3 * c[0] * u3x;
  }

 private:
  // `exists` is 1 or 0 (of the compute type C, so that the solve loops vectorise).
  template <typename C>
  struct Hip {
    C r2, S, exists;
  };
  template <typename C>
  struct Knee {
    C cos_psi, sin_psi, acos_psi, exists;  // knee branch 0: psi = -acos
  };

  template <typename C>
  static SPOTKIN_INLINE Hip<C> solve_hip(const RppConstants& k, C y, C z, C tol) noexcept {
    const C h = C(k.h);
    Hip<C> hp;
    hp.r2 = y * y + z * z;
    // r^2 - h^2 cancels where the foot nears the hip-roll circle (S -> 0, where
    // the hip pitch then depends on S): float kernels form it in double.
    C disc;
    if constexpr (std::is_same_v<C, float>)
      disc = C(double(y) * double(y) + double(z) * double(z) - k.h2);
    else
      disc = hp.r2 - C(k.h2);
    hp.exists = disc >= -tol * C(2) * h * h ? C(1) : C(0);  // (h/r)^2 <= 1 + 2 tol
    hp.S = std::sqrt(std::max(disc, C(0)));
    return hp;
  }

  template <typename C>
  // knee_sign: sin_psi and acos_psi of that knee branch's sign (SlotSigns::knee; exact, as atan2
  // is odd in its first argument), or of +1.
  static SPOTKIN_INLINE Knee<C> solve_knee(const RppConstants& kc, C wx, C wz, C tol,
                                           C knee_sign = C(1)) noexcept {
    Knee<C> k;
    if constexpr (std::is_same_v<C, float>) {
      // Near the stretched and folded knee (ratio -> +-1) psi is sqrt-sensitive to the
      // ratio's rounding, and |B|^2 + |C|^2 rounded to float alone would cost ~1e-4 rad:
      // the ratio and 1 - ratio^2 are formed in double.
      const double ratio =
          (double(wx) * double(wx) + double(wz) * double(wz) - kc.knee_sum_sq) * kc.inv_2BC;
      k.exists = std::fabs(ratio) <= 1.0 + double(tol) ? C(1) : C(0);
      const double cos_psi = std::clamp(ratio, -1.0, 1.0);
      k.cos_psi = C(cos_psi);
      k.sin_psi = knee_sign * std::sqrt(C((1.0 - cos_psi) * (1.0 + cos_psi)));
    } else {
      const C ratio = (wx * wx + wz * wz - C(kc.knee_sum_sq)) * C(kc.inv_2BC);
      k.exists = std::fabs(ratio) <= C(1) + tol ? C(1) : C(0);
      k.cos_psi = std::clamp(ratio, C(-1), C(1));
      k.sin_psi = knee_sign * std::sqrt((C(1) - k.cos_psi) * (C(1) + k.cos_psi));
    }
    k.acos_psi = vector_math::atan2(k.sin_psi, k.cos_psi);
    return k;
  }

  // (I1): theta1 for hip branch eps; atan2 is scale-invariant, so the cos/sin
  // are used without their common 1 / r^2. 0 when r = 0 (every angle works).
  template <typename C>
  static SPOTKIN_INLINE C hip_roll(const RppConstants& k, C y, C z, const Hip<C>& hip,
                                   C eps) noexcept {
    return hip_roll_signed(k, y, z, hip.r2, eps * hip.S);
  }
  // hip_roll with eps S given ((eps y) S = y (eps S): a product's sign is exact).
  template <typename C>
  static SPOTKIN_INLINE C hip_roll_signed(const RppConstants& k, C y, C z, C r2,
                                          C signed_S) noexcept {
    const C h = C(k.h);
    const C t1 = vector_math::atan2(z * h + y * signed_S, y * h - z * signed_S);
    return r2 > C(0) ? half_open(C(k.sign1) * t1) : C(0);
  }

  // An angle in [-pi, pi] (an atan2, maybe negated) into (-pi, pi]: -pi (atan2 of a -0 sine, or pi
  // negated) is pi.
  template <typename C>
  static SPOTKIN_INLINE C half_open(C t) noexcept {
    return t <= -kPi<C> ? kPi<C> : t;
  }

  // theta3 = psi - phi, then q3 = s3 theta3 in (-pi, pi];
  // knee_sign: -1 for knee branch 0 (psi = -acos), +1 for branch 1 (SlotSigns::knee).
  template <typename C>
  static SPOTKIN_INLINE C knee_angle(const RppConstants& kc, const Knee<C>& k,
                                     C knee_sign) noexcept {
    const C t3 = knee_sign * k.acos_psi - C(kc.phi);
    const C q3 = C(kc.sign3) * t3;  // in (-2pi, 2pi)
    const C wrapped = q3 <= -kPi<C> ? q3 + C(2) * kPi<C> : q3;
    return wrapped > kPi<C> ? wrapped - C(2) * kPi<C> : wrapped;
  }

  // (I4) with e^{i theta3} from psi: theta3 = psi - phi.
  template <typename C>
  static SPOTKIN_INLINE C hip_pitch(const RppConstants& kc, C wx, C wz, const Knee<C>& k,
                                    C knee_sign) noexcept {
    const C Bz = C(kc.Bz), Bx = C(kc.Bx), Cz = C(kc.Cz), Cx = C(kc.Cx), cos_phi = C(kc.cos_phi),
            sin_phi = C(kc.sin_phi);
    const C sin_psi = knee_sign * k.sin_psi;
    const C c3 = k.cos_psi * cos_phi + sin_psi * sin_phi;
    const C s3 = sin_psi * cos_phi - k.cos_psi * sin_phi;
    const C dz = Bz + c3 * Cz - s3 * Cx, dx = Bx + c3 * Cx + s3 * Cz;
    const C t2 = vector_math::atan2(wx * dz - wz * dx, wz * dz + wx * dx);
    return half_open(C(kc.sign2) * t2);
  }

  void update(int preferred_slot) noexcept {
    k_.sign1 = g_.sign[0], k_.sign2 = g_.sign[1], k_.sign3 = g_.sign[2];
    k_.a0 = g_.a[0], k_.a2 = g_.a[2];
    k_.h = g_.a[1] + g_.b[1] + g_.c[1];
    k_.h2 = k_.h * k_.h;
    k_.Bz = g_.b[2], k_.Bx = g_.b[0], k_.Cz = g_.c[2], k_.Cx = g_.c[0];
    const double nB = std::hypot(k_.Bz, k_.Bx), nC = std::hypot(k_.Cz, k_.Cx);
    k_.phi = std::atan2(k_.Cx, k_.Cz) - std::atan2(k_.Bx, k_.Bz);
    k_.cos_phi = std::cos(k_.phi), k_.sin_phi = std::sin(k_.phi);
    k_.knee_sum_sq = nB * nB + nC * nC;
    k_.inv_2BC = 1.0 / (2.0 * nB * nC);
    d_max_ = nB + nC;
    d_min_ = std::fabs(nB - nC);
    if (preferred_slot < 0) {
      // knee branch of the middle of the knee's range: sin(psi) <= 0 is branch 0
      const double lo = limits_.lower[2], hi = limits_.upper[2];
      int knee = 0;
      if (std::isfinite(lo) && std::isfinite(hi))
        knee = std::sin(k_.sign3 * 0.5 * (lo + hi) + k_.phi) > 0.0 ? 1 : 0;
      preferred_slot = knee;
    }
    order_[0] = preferred_slot;
    for (int s = 0, k = 1; s < kSlots; ++s)
      if (s != preferred_slot) order_[k++] = s;
  }

  RppGeometry g_;
  JointLimits<3> limits_;
  RppConstants k_;
  double d_max_ = 0, d_min_ = 0;
  int order_[kSlots] = {0, 1, 2, 3};
};

// f(std::bool_constant<Turn>) for a run-time turn flag (JointLimits::may_turn): the batch
// kernels' in-limit test skips the turned angles where the limits cannot take them. f: a generic
// lambda marked SPOTKIN_LAMBDA_INLINE, so that it compiles into the caller's clone.
template <typename F>
SPOTKIN_INLINE void with_turn(bool turn, F&& f) noexcept {
  if (turn) return f(std::true_type{});
  f(std::false_type{});
}

// Batched leg kernels over `count` targets (row-major (count, 3) inputs).
// Each block first solves every target with branch-free vector code, then
// picks branches, applies limits and statuses per target.
namespace leg_batch {

constexpr std::ptrdiff_t kBlock = 64;

// The compute type of the kernels for T: float32 data is solved in float,
// twice as many lanes per vector as double (accuracy: docs/derivations.md).
template <typename T>
using Compute = std::conditional_t<std::is_same_v<T, float>, float, double>;

// Lanes of the widest vector (64 bytes) of C: a block holds whole vectors.
template <typename C>
constexpr std::ptrdiff_t kLanes = 64 / std::ptrdiff_t(sizeof(C));
static_assert(kBlock % kLanes<float> == 0, "blocks hold whole vectors");

// m targets padded to whole registers of RegisterBytes (the level that runs: isa.hpp's
// register_bytes; a few targets fill fewer of them than of 64 bytes: at AVX2 one target is one
// register), at most a block.
template <typename C, int RegisterBytes>
constexpr std::ptrdiff_t register_padded_count(std::ptrdiff_t m) noexcept {
  constexpr std::ptrdiff_t lanes = RegisterBytes / std::ptrdiff_t(sizeof(C));
  return std::min(kBlock, (m + lanes - 1) / lanes * lanes);
}
// The same in 64-byte vectors (kLanes), whatever the level.
template <typename C>
constexpr std::ptrdiff_t padded_count(std::ptrdiff_t m) noexcept {
  return register_padded_count<C, 64>(m);
}

// Pads x, y, z after their first m entries with copies of entry m - 1, up to
// whole vectors (padded_count), and returns that count. Vector passes over the
// padded count run every target in the loop's full lanes (its scalar remainder
// may round differently), so that an answer never depends on the target's
// place in a block, that is on how the batch was split between threads or calls.
// RegisterBytes (default: the 64 of padded_count): pads to whole registers of that many bytes.
template <int RegisterBytes = 64, typename C>
SPOTKIN_INLINE std::ptrdiff_t pad_block(C* x, C* y, C* z, std::ptrdiff_t m) noexcept {
  const std::ptrdiff_t padded = register_padded_count<C, RegisterBytes>(m);
  if (m == 1) {  // one target (a single call): whole-vector stores, which the vector loads that
    // follow can take from the store buffer (after scalar stores they wait for them to commit)
    const C x0 = x[0], y0 = y[0], z0 = z[0];
    for (std::ptrdiff_t k = 0; k < padded; ++k) x[k] = x0, y[k] = y0, z[k] = z0;
    return padded;
  }
  for (std::ptrdiff_t k = m; k < padded; ++k) x[k] = x[m - 1], y[k] = y[m - 1], z[k] = z[m - 1];
  return padded;
}

template <typename T>
SPOTKIN_INLINE bool finite3(const T* v) noexcept {
  return std::isfinite(double(v[0])) && std::isfinite(double(v[1])) && std::isfinite(double(v[2]));
}

// solve_slots' first pass: every slot of m targets, before the limits.
template <bool SharedKnee, typename C>
SPOTKIN_INLINE void solve_slots_raw(const Leg& leg, const C* x, const C* y, const C* z, std::ptrdiff_t m, C tol,
                                    C (*q)[3][kBlock], C (*exists_hip)[kBlock]) noexcept {
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    C q_all[Leg::kSlots][3], e[2];
    leg.solve_all_mask<SharedKnee>(x[i], y[i], z[i], q_all, e, tol);
    exists_hip[0][i] = e[0], exists_hip[1][i] = e[1];
#pragma GCC unroll 4
    for (int s = 0; s < Leg::kSlots; ++s)
#pragma GCC unroll 3
      for (int j = 0; j < 3; ++j) q[s][j][i] = q_all[s][j];
  }
}

// Every slot of m targets (vectorised): q[s][j][i] wrapped into the limits
// where it fits, ok[s][i] = 1.0 where slot s exists and fits, exists_hip[hb][i]
// = 1.0 where hip branch hb exists (both of its knee slots then do).
template <typename C>
SPOTKIN_INLINE void solve_slots(const Leg& leg_in, const C* x, const C* y, const C* z, std::ptrdiff_t m, C tol,
                                C limit_tol, C (*q)[3][kBlock], C (*ok)[kBlock], C (*exists_hip)[kBlock]) noexcept {
  const Leg leg = leg_in;  // a local copy: the outputs cannot alias its constants
  if (leg.shared_knee())
    solve_slots_raw<true>(leg, x, y, z, m, tol, q, exists_hip);
  else
    solve_slots_raw<false>(leg, x, y, z, m, tol, q, exists_hip);
#pragma GCC unroll 4
  for (int s = 0; s < Leg::kSlots; ++s) {
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      C qi[3] = {q[s][0][i], q[s][1][i], q[s][2][i]};
      ok[s][i] = exists_hip[s / 2][i] * leg.limits().wrap_mask(qi, limit_tol);
      q[s][0][i] = qi[0], q[s][1][i] = qi[1], q[s][2][i] = qi[2];
    }
  }
}

// The documented UNREACHABLE answer, always inside the limits: the
// configuration whose foot is nearest to p among all those within the joint
// limits (exact, Leg::nearest_reachable within_limits).
template <typename T>
SPOTKIN_INLINE void unreachable_fallback(const Leg& leg, double x, double y, double z, T* q_out) noexcept {
  const double p[3] = {x, y, z};
  double foot[3], q[3];
  leg.nearest_reachable(p, foot, /*within_limits=*/true, q);
  for (int j = 0; j < 3; ++j) q_out[j] = T(q[j]);
}

// Whether ok[i] and also[i] are nonzero for every i < m (the preferred slot valid for
// every target of a block, and every pose valid): one vector test, no branch per target.
template <typename C>
SPOTKIN_INLINE bool all_settled(const C* ok, const C* also, std::ptrdiff_t m) noexcept {
  int unsettled = 0;
  for (std::ptrdiff_t i = 0; i < m; ++i) unsettled |= !(ok[i] != C(0) && also[i] != C(0));
  return unsettled == 0;
}

// 1 where x, y, z are all finite; vectorisable (x - x is NaN for NaN and Inf).
template <typename C>
SPOTKIN_INLINE C finite_mask(C x, C y, C z) noexcept {
  return (((x - x) == C(0)) & ((y - y) == C(0)) & ((z - z) == C(0))) ? C(1) : C(0);
}

// Whether a seed certifies the preferred slot's answer q (ok: it is valid; bound: slot_separation)
// as the valid slot nearest to it, the one OpenTargets::choose would pick: within 0.45 bound of the
// seed (circle_distance), every other slot is at least bound from q, so at least 0.55 bound from
// the seed (the triangle inequality; the margins cover rounding). Then no other slot need be
// solved.
template <typename C, typename T>
SPOTKIN_INLINE bool seed_certifies(C ok, C bound, C q0, C q1, C q2, const T* seed) noexcept {
  if (ok == C(0) || !(double(bound) > 1e-6)) return false;
  const double q[3] = {double(q0), double(q1), double(q2)},
               s[3] = {double(seed[0]), double(seed[1]), double(seed[2])};
  return circle_distance<3>(q, s) <= 0.45 * double(bound);
}

// The targets of a block that the preferred-slot pass did not settle (a seed,
// a limit, the other hip branch, or no solution): gathered, solved in every
// slot at once by solve_slots, then chosen one by one.
template <typename C>
struct OpenTargets {
  std::ptrdiff_t count = 0;
  std::ptrdiff_t index[kBlock];  // the target's place in the block (leg_batch::ik: in the batch)
  C x[kBlock], y[kBlock], z[kBlock];
  C q[Leg::kSlots][3][kBlock], ok[Leg::kSlots][kBlock], exists_hip[2][kBlock];

  SPOTKIN_INLINE void add(std::ptrdiff_t i, C xi, C yi, C zi) noexcept {
    index[count] = i, x[count] = xi, y[count] = yi, z[count] = zi;
    ++count;
  }
  // Padded (pad_block): an open target's answer must not depend on which of
  // its neighbours are open too.
  SPOTKIN_INLINE void solve(const Leg& leg, C tol, C limit_tol) noexcept {
    if (count > 0) solve_slots(leg, x, y, z, pad_block(x, y, z, count), tol, limit_tol, q, ok, exists_hip);
  }

  // Open target k: writes q_out and returns its status. Without a seed, the
  // first valid slot in the leg's slot order (the preferred slot first); with
  // one, the valid slot nearest to it on the circle (ties: that order). No
  // valid slot: NaN and JOINT_LIMIT, or UNREACHABLE with unreachable_fallback's
  // answer (NaN when !nearest_fallback).
  template <typename T>
  Status choose(const Leg& leg, std::ptrdiff_t k, const T* seed, T* q_out, bool nearest_fallback) const noexcept {
    int best = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    const int* order = leg.slot_order();
    for (int n = 0; n < Leg::kSlots; ++n) {
      const int s = order[n];
      if (ok[s][k] == C(0)) continue;
      if (!seed) {
        best = s;
        break;
      }
      const double qs[3] = {double(q[s][0][k]), double(q[s][1][k]), double(q[s][2][k])};
      const double seed_d[3] = {double(seed[0]), double(seed[1]), double(seed[2])};
      const double d = circle_distance<3>(qs, seed_d);
      if (d < best_distance) best = s, best_distance = d;
    }
    if (best >= 0) {
      for (int j = 0; j < 3; ++j) q_out[j] = T(q[best][j][k]);
      return Status::Ok;
    }
    if (exists_hip[0][k] != C(0) || exists_hip[1][k] != C(0)) {
      for (int j = 0; j < 3; ++j) q_out[j] = T(quiet_nan<double>());
      return Status::JointLimit;
    }
    if (nearest_fallback)
      unreachable_fallback(leg, double(x[k]), double(y[k]), double(z[k]), q_out);
    else
      q_out[0] = q_out[1] = q_out[2] = T(quiet_nan<double>());
    return Status::Unreachable;
  }
};

// Vectorised: slot `slot` and its limits for every target of a block; exists
// -1 for invalid input.
// Bound: also each target's slot_separation (bound), for a seed's certificate (seed_certifies).
// Turn: the limits may take an angle turned by 2 pi (JointLimits::may_turn; else wrap_mask<false>).
template <bool Bound, bool Turn, typename C>
SPOTKIN_INLINE void slot_pass(const Leg& leg, int slot, const C* x, const C* y, const C* z, C* hx,
                              C* hy, C* kn, C* exists, C* ok, std::ptrdiff_t m, C tol, C limit_tol,
                              C* bound = nullptr) noexcept {
  const Leg::SlotSigns<C> signs = Leg::slot_signs<C>(slot);
  Leg::SlotStages<C, kBlock> st;  // m <= kBlock
  for (std::ptrdiff_t i = 0; i < m; ++i) leg.slot_hip(i, y[i], z[i], tol, signs, st);
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    leg.slot_knee(i, x[i], tol, signs, st);
    C q0[3];
    const C finite = finite_mask(x[i], y[i], z[i]);
    exists[i] = finite * leg.slot_angles(i, x[i], y[i], z[i], st, q0);
    ok[i] = exists[i] * leg.limits().template wrap_mask<Turn>(q0, limit_tol);
    exists[i] = finite == C(0) ? C(-1) : exists[i];
    hx[i] = q0[0], hy[i] = q0[1], kn[i] = q0[2];
    if constexpr (Bound) bound[i] = leg.slot_separation(i, st);
  }
}

template <bool Bound = false, typename C>
SPOTKIN_INLINE void preferred_pass(const Leg& leg_in, const C* x, const C* y, const C* z, C* hx,
                                   C* hy, C* kn, C* exists, C* ok, std::ptrdiff_t m, C tol,
                                   C limit_tol, C* bound = nullptr) noexcept {
  const Leg leg = leg_in;  // a local copy: the output arrays cannot alias its constants
  with_turn(leg.limits().may_turn(), [&](auto turn) SPOTKIN_LAMBDA_INLINE {
    slot_pass<Bound, decltype(turn)::value>(leg, leg.preferred_slot(), x, y, z, hx, hy, kn, exists,
                                            ok, m, tol, limit_tol, bound);
  });
}

// Solves and chooses the gathered targets (open.index: places in the batch),
// then empties the list. Not a lambda: a lambda would not be compiled for the
// caller's CPU level, and its loops would not be vectorised.
template <typename C, typename T>
SPOTKIN_INLINE void settle_open(OpenTargets<C>& open, const Leg& leg, const T* seed, T* q, std::int8_t* status,
                                C tol, C limit_tol, bool nearest_fallback) noexcept {
  open.solve(leg, tol, limit_tol);
  for (std::ptrdiff_t k = 0; k < open.count; ++k) {
    const std::ptrdiff_t t = open.index[k];
    status[t] = std::int8_t(open.choose(leg, k, seed ? seed + 3 * t : nullptr, q + 3 * t, nearest_fallback));
  }
  open.count = 0;
}

// Limit-aware IK: q (count, 3), status (count). seed may be null. An
// UNREACHABLE target gets unreachable_fallback's answer, or NaN when
// !nearest_fallback. RegisterBytes: the register of the level that runs it (register_bytes), whose
// width the preferred-slot pass pads a short block to.
template <int RegisterBytes = 64, typename T>
SPOTKIN_INLINE void ik(const Leg& leg, const T* p, const T* seed, T* q, std::int8_t* status,
                       std::ptrdiff_t count, bool nearest_fallback = true) noexcept {
  using C = Compute<T>;
  C x[kBlock], y[kBlock], z[kBlock], hx[kBlock], hy[kBlock], kn[kBlock], exists[kBlock], ok[kBlock],
      bound[kBlock];
  OpenTargets<C> open;
  const C tol = C(Leg::ratio_tolerance<T>()), limit_tol = C(JointLimits<3>::tolerance<T>());
  // Open targets gather across blocks (index: their place in the batch) and are
  // solved when the list is full: a few per block would leave most lanes of the
  // all-slot pass idle (settling before each block that might overflow the list
  // solved every block's few: Spot's leg over its whole box, 8 % open, float32
  // AVX-512: 6.4 -> 4.9 ns per target).
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      x[i] = C(p[3 * (b0 + i)]), y[i] = C(p[3 * (b0 + i) + 1]), z[i] = C(p[3 * (b0 + i) + 2]);
    }
    // One target alone (a single call) is not padded to a register: the loops' remainder code runs
    // it, the same operations (tests/test_isa.py checks its bits against a batch's rows at every
    // level). A loop of one call in C++ ran 89 -> 56 ns at AVX-512 and
    // 78 -> 59 ns at AVX2; leg.ik from Python 251 -> 187 ns and 220 -> 207 ns.
    const std::ptrdiff_t lanes = count == 1 ? 1 : pad_block<RegisterBytes>(x, y, z, m);
    if (!seed) {  // two loops: GCC did not take the seed's test out of the loop on its own
      preferred_pass(leg, x, y, z, hx, hy, kn, exists, ok, lanes, tol, limit_tol);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const std::ptrdiff_t t = b0 + i;
        T* qt = q + 3 * t;
        if (ok[i] != C(0)) {  // the common case: the preferred slot valid
          qt[0] = T(hx[i]), qt[1] = T(hy[i]), qt[2] = T(kn[i]);
          status[t] = std::int8_t(Status::Ok);
        } else if (exists[i] < C(0)) {
          qt[0] = qt[1] = qt[2] = T(quiet_nan<double>());
          status[t] = std::int8_t(Status::InvalidInput);
        } else {
          open.add(t, x[i], y[i], z[i]);
          if (open.count == kBlock) settle_open(open, leg, seed, q, status, tol, limit_tol, nearest_fallback);
        }
      }
    } else {  // the preferred slot where the seed certifies it (seed_certifies), else every slot
      preferred_pass<true>(leg, x, y, z, hx, hy, kn, exists, ok, lanes, tol, limit_tol, bound);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const std::ptrdiff_t t = b0 + i;
        T* qt = q + 3 * t;
        if (exists[i] < C(0) || !finite3(seed + 3 * t)) {
          qt[0] = qt[1] = qt[2] = T(quiet_nan<double>());
          status[t] = std::int8_t(Status::InvalidInput);
        } else if (seed_certifies(ok[i], bound[i], hx[i], hy[i], kn[i], seed + 3 * t)) {
          qt[0] = T(hx[i]), qt[1] = T(hy[i]), qt[2] = T(kn[i]);
          status[t] = std::int8_t(Status::Ok);
        } else {
          open.add(t, x[i], y[i], z[i]);
          if (open.count == kBlock) settle_open(open, leg, seed, q, status, tol, limit_tol, nearest_fallback);
        }
      }
    }
  }
  settle_open(open, leg, seed, q, status, tol, limit_tol, nearest_fallback);
}

// Every branch: q (count, 4, 3), valid and exists (count, 4), status (count).
template <typename T>
SPOTKIN_INLINE void ik_all(const Leg& leg, const T* p, T* q, std::uint8_t* valid, std::uint8_t* exists,
                           std::int8_t* status, std::ptrdiff_t count) noexcept {
  using C = Compute<T>;
  constexpr C nan = quiet_nan<C>();
  C x[kBlock], y[kBlock], z[kBlock], qs[Leg::kSlots][3][kBlock], ok[Leg::kSlots][kBlock];
  C ex[2][kBlock], finite[kBlock];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      x[i] = C(p[3 * (b0 + i)]), y[i] = C(p[3 * (b0 + i) + 1]), z[i] = C(p[3 * (b0 + i) + 2]);
      finite[i] = finite_mask(x[i], y[i], z[i]);
    }
    solve_slots(leg, x, y, z, pad_block(x, y, z, m), C(Leg::ratio_tolerance<T>()), C(JointLimits<3>::tolerance<T>()),
                qs, ok, ex);
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const std::ptrdiff_t t = b0 + i;
      T* qt = q + 12 * t;
      const bool exists_hip[2] = {finite[i] != C(0) && ex[0][i] != C(0), finite[i] != C(0) && ex[1][i] != C(0)};
      bool any_valid = false;
      for (int s = 0; s < Leg::kSlots; ++s) {
        const bool e = exists_hip[s / 2], v = e && ok[s][i] != C(0);
        for (int j = 0; j < 3; ++j) qt[3 * s + j] = T(e ? qs[s][j][i] : nan);
        valid[4 * t + s] = v;
        exists[4 * t + s] = e;
        any_valid |= v;
      }
      const Status st = finite[i] == C(0)               ? Status::InvalidInput
                        : any_valid                     ? Status::Ok
                        : exists_hip[0] || exists_hip[1] ? Status::JointLimit
                                                        : Status::Unreachable;
      status[t] = std::int8_t(st);
    }
  }
}

// Sines and cosines of theta1, theta2 and theta2 + theta3 for a block, vectorised.
struct BlockAngles {
  double angle[3][kBlock], s[3][kBlock], c[3][kBlock];
};

template <typename T>
SPOTKIN_INLINE void block_angles(const Leg& leg, const T* q, std::ptrdiff_t m, BlockAngles& a) noexcept {
  const double s1 = leg.sign(0), s2 = leg.sign(1), s3 = leg.sign(2);
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    a.angle[0][i] = s1 * double(q[3 * i]);
    a.angle[1][i] = s2 * double(q[3 * i + 1]);
    a.angle[2][i] = s2 * double(q[3 * i + 1]) + s3 * double(q[3 * i + 2]);
  }
  for (int j = 0; j < 3; ++j) vector_math::sincos(a.angle[j], a.s[j], a.c[j], m);
}

template <typename T>
SPOTKIN_INLINE void fk(const Leg& leg_in, const T* q, T* p, std::ptrdiff_t count) noexcept {
  const Leg leg = leg_in;  // a local copy: the outputs cannot alias its constants
  BlockAngles a;
  const double h = leg.lateral();
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    block_angles(leg, q + 3 * b0, m, a);
    T* out = p + 3 * b0;
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // (R1)
      double vx, vz;
      leg.plane(a.c[1][i], a.s[1][i], a.c[2][i], a.s[2][i], vx, vz);
      out[3 * i] = T(vx);
      out[3 * i + 1] = T(h * a.c[0][i] - vz * a.s[0][i]);
      out[3 * i + 2] = T(h * a.s[0][i] + vz * a.c[0][i]);
    }
  }
}

template <typename T>
SPOTKIN_INLINE void jacobian(const Leg& leg_in, const T* q, T* J, std::ptrdiff_t count) noexcept {
  const Leg leg = leg_in;  // a local copy: the outputs cannot alias its constants
  BlockAngles a;
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    block_angles(leg, q + 3 * b0, m, a);
    T* out = J + 9 * b0;
    for (std::ptrdiff_t i = 0; i < m; ++i) {  // as Leg::jacobian
      const double c[3] = {a.c[0][i], a.c[1][i], a.c[2][i]}, s[3] = {a.s[0][i], a.s[1][i], a.s[2][i]};
      double Ji[9];
      leg.jacobian_from(c, s, Ji);
      for (int k = 0; k < 9; ++k) out[9 * i + k] = T(Ji[k]);
    }
  }
}

}  // namespace leg_batch

}  // namespace spotkin
