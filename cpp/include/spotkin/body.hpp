// Whole-body kinematics (the course's Spot problem §3, for any number of legs): the body pose
// in the world, the feet fixed on the ground, three joints per leg.
//
//   foot_world_i = t + R (hip_i + fk_leg_i(q_i))                      (B1)
//   IK: p_leg_i = R^T (foot_world_i - t) - hip_i, then the leg IK     (B2)
//   d foot_world_i = v + w x (foot_world_i - t) + R J_leg_i dq_i      (B3)
// with (v, w) the body twist: the linear velocity of the body origin and the
// angular velocity, both in the world frame.
//
// Body orientation from Euler angles: intrinsic sequences (scipy's upper case,
// e.g. "XYZ": R = R_X(a) R_Y(b) R_Z(c), the course's Spot problem) or extrinsic ones (lower
// case, e.g. "xyz": R = R_z(c) R_y(b) R_x(a), ROS roll-pitch-yaw).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "spotkin/arm.hpp"
#include "spotkin/common.hpp"
#include "spotkin/dynamics/pack.hpp"
#include "spotkin/lane_rows.hpp"
#include "spotkin/leg.hpp"
#include "spotkin/leg_lanes.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin {

enum class BodyPoseFormat : std::int8_t { Euler = 0, Matrix = 1, PositionQuaternion = 2 };

// An Euler sequence as three axes (0 = x, 1 = y, 2 = z) applied intrinsically:
// R = R_axis[0](angle[order[0]]) R_axis[1](angle[order[1]]) R_axis[2](angle[order[2]]).
struct EulerSequence {
  int axis[3] = {0, 1, 2};
  int order[3] = {0, 1, 2};
  // The sequence packed in one int (the façade's form): axis[0] + 3 axis[1] + 9 axis[2], plus 27
  // when the angles apply in reverse order (extrinsic sequences). std::invalid_argument otherwise.
  static EulerSequence from_code(int code) {
    if (code < 0 || code >= 54) throw std::invalid_argument("invalid Euler sequence code " + std::to_string(code));
    EulerSequence seq;
    seq.axis[0] = code % 3, seq.axis[1] = code / 3 % 3, seq.axis[2] = code / 9 % 3;
    for (int k = 0; k < 3; ++k) seq.order[k] = code >= 27 ? 2 - k : k;
    return seq;
  }
};

struct Body {
  std::vector<Leg> legs;
  std::vector<std::array<double, 3>> hips;   // hip-roll joint origins in the body frame
  std::vector<std::array<int, 3>> columns;   // each leg joint's column in q

  static constexpr int kMaxLegs = 21;  // q's angle mask holds 64 columns
  // body_batch::ik_pairs's lanes: lane k holds leg k % n, its constants and hip.
  static constexpr std::ptrdiff_t kPairLanes = 16;
  leg_batch::LegLanes<kPairLanes> pair_legs;
  double pair_hips[3][kPairLanes];
  bool shared_knees = true;  // every leg has a_z = 0 (Leg::shared_knee)
  int preferred_slot = -1;   // every leg's preferred slot when they share one, else -1

  Body() = default;
  // columns: a permutation of 0 .. 3 n - 1 (throws std::invalid_argument otherwise).
  Body(std::vector<Leg> legs_, std::vector<std::array<double, 3>> hips_, std::vector<std::array<int, 3>> columns_)
      : legs(std::move(legs_)), hips(std::move(hips_)), columns(std::move(columns_)) {
    const std::size_t n = legs.size();
    if (n == 0 || n > std::size_t(kMaxLegs)) throw std::invalid_argument("a body needs 1 to 21 legs");
    if (hips.size() != n || columns.size() != n)
      throw std::invalid_argument("one hip position and one column triple per leg");
    std::vector<bool> seen(3 * n, false);
    for (const auto& c : columns)
      for (int k : c) {
        if (k < 0 || k >= int(3 * n) || seen[std::size_t(k)])
          throw std::invalid_argument("leg joint columns must be a permutation of 0 .. 3 n - 1");
        seen[std::size_t(k)] = true;
      }
    for (std::ptrdiff_t k = 0; k < kPairLanes; ++k) {
      const std::size_t l = std::size_t(k) % n;
      pair_legs.set(k, legs[l]);
      for (int r = 0; r < 3; ++r) pair_hips[r][k] = hips[l][std::size_t(r)];
    }
    for (const Leg& leg : legs) shared_knees = shared_knees && leg.shared_knee();
    preferred_slot = legs[0].preferred_slot();
    for (const Leg& leg : legs)
      if (leg.preferred_slot() != preferred_slot) preferred_slot = -1;
  }

  int n_legs() const noexcept { return static_cast<int>(legs.size()); }
  int width() const noexcept { return 3 * n_legs(); }  // q holds every leg joint
  bool leg_contiguous() const noexcept {
    for (std::size_t l = 0; l < columns.size(); ++l)
      for (int k = 0; k < 3; ++k)
        if (columns[l][std::size_t(k)] != int(3 * l) + k) return false;
    return true;
  }

  // R = product of elementary rotations for one sample. vector_math::sincos is
  // exact for any magnitude (glibc's reduction beyond its polynomial range).
  static SPOTKIN_INLINE void euler_rotation(const EulerSequence& seq, const double angles[3], double R[3][3]) noexcept {
    double sines[3], cosines[3];
    vector_math::sincos(angles, sines, cosines, 3);
    double M[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int k = 0; k < 3; ++k) {
      const double s = sines[seq.order[k]], c = cosines[seq.order[k]];
      const int a = seq.axis[k], i = (a + 1) % 3, j = (a + 2) % 3;
      // M <- M R_a: columns i and j mix (R_a e_i = c e_i + s e_j, R_a e_j = -s e_i + c e_j)
      for (int r = 0; r < 3; ++r) {
        const double mi = M[r][i], mj = M[r][j];
        M[r][i] = c * mi + s * mj;
        M[r][j] = c * mj - s * mi;
      }
    }
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) R[r][k] = M[r][k];
  }
};

namespace body_batch {

constexpr std::ptrdiff_t kBlock = 64;

// Rotation, translation and validity (1 / 0) of body poses for a block, SoA,
// in the compute type C.
template <typename C = double>
struct BlockPoses {
  C R[9][kBlock], t[3][kBlock], ok[kBlock];
};

// R of each pose, vectorised: Rx(a) Ry(b) Rz(c) ("XYZ", Intrinsic) or Rz(c) Ry(b) Rx(a)
// ("xyz"), from the sines and cosines of (a, b, c); ok = 1 where R and t are finite.
template <bool Intrinsic, typename C>
SPOTKIN_INLINE void euler_xyz_rotations(const C (*s)[kBlock], const C (*c)[kBlock], std::ptrdiff_t padded,
                                        BlockPoses<C>& out) noexcept {
  for (std::ptrdiff_t i = 0; i < padded; ++i) {
    const C sa = s[0][i], ca = c[0][i], sb = s[1][i], cb = c[1][i], sc = s[2][i], cc = c[2][i];
    const C R[9] = {
        cb * cc,
        Intrinsic ? -cb * sc : sa * sb * cc - ca * sc,
        Intrinsic ? sb : ca * sb * cc + sa * sc,
        Intrinsic ? ca * sc + sa * sb * cc : cb * sc,
        Intrinsic ? ca * cc - sa * sb * sc : sa * sb * sc + ca * cc,
        Intrinsic ? -sa * cb : ca * sb * sc - sa * cc,
        Intrinsic ? sa * sc - ca * sb * cc : -sb,
        Intrinsic ? sa * cc + ca * sb * sc : sa * cb,
        ca * cb,
    };
    C sum = out.t[0][i] + out.t[1][i] + out.t[2][i];
    for (int k = 0; k < 9; ++k) out.R[k][i] = R[k], sum += R[k];
    out.ok[i] = (sum - sum) == C(0) ? C(1) : C(0);
  }
}

// One pose's rotation R and translation t, as read_poses reads them one at a time: Euler angles by
// Body::euler_rotation, a matrix as given, a quaternion by Arm::read_pose (the same checks).
// Returns whether the pose is valid (finite, and a rigid transform).
template <typename T>
inline bool read_pose(const T* in, BodyPoseFormat format, const EulerSequence& seq, double R[3][3],
                      double t[3]) noexcept {
  double ok = 1.0;
  if (format == BodyPoseFormat::Euler) {
    const double angles[3] = {double(in[3]), double(in[4]), double(in[5])};
    Body::euler_rotation(seq, angles, R);
    t[0] = double(in[0]), t[1] = double(in[1]), t[2] = double(in[2]);
  } else {
    Arm::Pose pose;
    double buffer[16];
    const int width = format == BodyPoseFormat::Matrix ? 16 : 7;
    for (int k = 0; k < width; ++k) buffer[k] = double(in[k]);
    ok = format == BodyPoseFormat::Matrix ? Arm::read_pose<PoseFormat::Matrix>(buffer, pose)
                                          : Arm::read_pose<PoseFormat::PositionQuaternion>(buffer, pose);
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) R[r][k] = pose.R[r][k];
      t[r] = pose.p[r];
    }
  }
  double sum = t[0] + t[1] + t[2];  // NaN or Inf anywhere makes it NaN
  for (int r = 0; r < 3; ++r) sum += R[r][0] + R[r][1] + R[r][2];
  return ok != 0.0 && (sum - sum) == 0.0;
}

// The world <- body transform of one pose (out: 4 x 4, row-major); an invalid pose gives NaN
// throughout and returns false.
template <typename T>
inline bool pose_transform(const T* in, BodyPoseFormat format, const EulerSequence& seq, double* out) noexcept {
  double R[3][3], t[3];
  const bool valid = read_pose(in, format, seq, R, t);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) out[4 * r + k] = R[r][k];
    out[4 * r + 3] = t[r];
  }
  out[12] = out[13] = out[14] = 0.0, out[15] = 1.0;
  if (format == BodyPoseFormat::Matrix)  // a valid matrix as given (its last row within 1e-9)
    for (int k = 12; k < 16; ++k) out[k] = double(in[k]);
  if (!valid) std::fill(out, out + 16, quiet_nan<double>());
  return valid;
}

template <typename T, typename C>
SPOTKIN_INLINE void read_poses(const T* poses, BodyPoseFormat format, const EulerSequence& seq, std::ptrdiff_t stride,
                               std::ptrdiff_t m, BlockPoses<C>& out) noexcept {
  const bool intrinsic_xyz = seq.axis[0] == 0 && seq.axis[1] == 1 && seq.axis[2] == 2 && seq.order[0] == 0 &&
                             seq.order[1] == 1 && seq.order[2] == 2;
  const bool extrinsic_xyz = seq.axis[0] == 2 && seq.axis[1] == 1 && seq.axis[2] == 0 && seq.order[0] == 2 &&
                             seq.order[1] == 1 && seq.order[2] == 0;
  if (format == BodyPoseFormat::Euler && (intrinsic_xyz || extrinsic_xyz)) {
    // Fast paths, vectorised: Rx(a) Ry(b) Rz(c) ("XYZ") and Rz(c) Ry(b) Rx(a) ("xyz").
    // Whole vectors: the padding repeats the last pose, so that a pose's rotation
    // never comes from a loop's scalar remainder (an answer must not depend on
    // the batch around it; leg_batch::pad_block).
    C angle[3][kBlock], s[3][kBlock], c[3][kBlock];
    const std::ptrdiff_t padded = leg_batch::padded_count<C>(m);
    for (std::ptrdiff_t i = 0; i < padded; ++i) {
      const T* in = poses + 6 * std::min(i, m - 1);
      for (int k = 0; k < 3; ++k) out.t[k][i] = C(in[k]), angle[k][i] = C(in[3 + k]);
    }
    for (int k = 0; k < 3; ++k) vector_math::sincos(angle[k], s[k], c[k], padded);
    // One loop per sequence: a choice inside the loop kept GCC from vectorising it (perf: a
    // scalar loop, a fifth of body_ik's float32 kernel outside the legs on AVX-512).
    if (intrinsic_xyz)
      euler_xyz_rotations<true>(s, c, padded, out);
    else
      euler_xyz_rotations<false>(s, c, padded, out);
    return;
  }
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    double R[3][3], t[3];
    out.ok[i] = read_pose(poses + stride * i, format, seq, R, t) ? C(1) : C(0);
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) out.R[3 * r + k][i] = C(R[r][k]);
      out.t[r][i] = C(t[r]);
    }
  }
}

// (B2) + the leg's preferred slot (its branch signs, Leg::SlotSigns) for one leg over a block:
// vectorised.
// Bound: also each target's slot_separation (bound), for a seed's certificate (seed_certifies).
// Turn: the limits may take an angle turned by 2 pi (JointLimits::may_turn); where not, the
// in-limit test skips the turned angles (same bits, 6 % of body_ik at AVX2).
template <bool Bound, bool Turn, typename C>
SPOTKIN_INLINE void leg_block_slot(const Leg& leg, Leg::SlotSigns<C> signs, const C* __restrict hip,
                                   const C (*__restrict R)[kBlock], const C (*__restrict t)[kBlock],
                                   const C* __restrict fx, const C* __restrict fy,
                                   const C* __restrict fz, C* __restrict x, C* __restrict y,
                                   C* __restrict z, C (*__restrict q0)[kBlock],
                                   C* __restrict exists, C* __restrict ok, C* __restrict bound,
                                   std::ptrdiff_t m, C tol, C limit_tol) noexcept {
  Leg::SlotStages<C, kBlock> st;  // two loops: Leg::SlotStages
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    const C dx = fx[i] - t[0][i], dy = fy[i] - t[1][i], dz = fz[i] - t[2][i];
    const C px = R[0][i] * dx + R[3][i] * dy + R[6][i] * dz - hip[0];  // R^T d - hip
    const C py = R[1][i] * dx + R[4][i] * dy + R[7][i] * dz - hip[1];
    const C pz = R[2][i] * dx + R[5][i] * dy + R[8][i] * dz - hip[2];
    x[i] = px, y[i] = py, z[i] = pz;
    leg.slot_hip(i, py, pz, tol, signs, st);
  }
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    leg.slot_knee(i, x[i], tol, signs, st);
    C q[3];
    const C finite = leg_batch::finite_mask(x[i], y[i], z[i]);
    const C e = finite * leg.slot_angles(i, x[i], y[i], z[i], st, q);
    ok[i] = e * leg.limits().template wrap_mask<Turn>(q, limit_tol);
    exists[i] = finite == C(0) ? C(-1) : e;
    q0[0][i] = q[0], q0[1][i] = q[1], q0[2][i] = q[2];
    if constexpr (Bound) bound[i] = leg.slot_separation(i, st);
  }
}

template <bool Bound, typename C>
SPOTKIN_INLINE void leg_block_impl(const Leg& leg_in, const C* __restrict hip,
                                   const C (*__restrict R)[kBlock], const C (*__restrict t)[kBlock],
                                   const C* __restrict fx, const C* __restrict fy,
                                   const C* __restrict fz, C* __restrict x, C* __restrict y,
                                   C* __restrict z, C (*__restrict q0)[kBlock],
                                   C* __restrict exists, C* __restrict ok, C* __restrict bound,
                                   std::ptrdiff_t m, C tol, C limit_tol) noexcept {
  const Leg leg = leg_in;  // a local copy: the outputs cannot alias its constants
  const Leg::SlotSigns<C> signs = Leg::slot_signs<C>(leg.preferred_slot());
  with_turn(leg.limits().may_turn(), [&](auto turn) SPOTKIN_LAMBDA_INLINE {
    leg_block_slot<Bound, decltype(turn)::value>(leg, signs, hip, R, t, fx, fy, fz, x, y, z, q0,
                                                 exists, ok, bound, m, tol, limit_tol);
  });
}

// One run-time dispatched kernel per compute type (target_clones takes no templates). bound: null,
// or each target's slot_separation too (the seeded paths' certificates).
#define SPOTKIN_LEG_BLOCK(C)                                                                      \
  SPOTKIN_CLONES((__attribute__((noinline)) inline), void, leg_block,                             \
                 (const Leg& leg, const C* __restrict hip, const C(*__restrict R)[kBlock],        \
                  const C(*__restrict t)[kBlock], const C* __restrict fx, const C* __restrict fy, \
                  const C* __restrict fz, C* __restrict x, C* __restrict y, C* __restrict z,      \
                  C(*__restrict q0)[kBlock], C* __restrict exists, C* __restrict ok,              \
                  C* __restrict bound, std::ptrdiff_t m, C tol, C limit_tol) noexcept,            \
                 (leg, hip, R, t, fx, fy, fz, x, y, z, q0, exists, ok, bound, m, tol, limit_tol), \
                 if (bound) leg_block_impl<true>(leg, hip, R, t, fx, fy, fz, x, y, z, q0, exists, \
                                                 ok, bound, m, tol, limit_tol);                   \
                 else leg_block_impl<false>(leg, hip, R, t, fx, fy, fz, x, y, z, q0, exists, ok,  \
                                            bound, m, tol, limit_tol);)
SPOTKIN_LEG_BLOCK(double)
SPOTKIN_LEG_BLOCK(float)
#undef SPOTKIN_LEG_BLOCK

// The status and answer of a leg whose hip-frame point is not finite, at lane i of a block's poses
// P (valid). A finite foot whose point overflowed (|foot - t| near the largest double, or float's
// for float inputs) is a target beyond reach, not an invalid input: its direction, computed in
// double at a scale where nothing overflows, gives Leg::ik's answer for a target that far
// (UNREACHABLE, with the in-limit configuration nearest to it, NaN without the fallback; the hip's
// offset is nothing at that distance). A foot that is not finite: INVALID_INPUT and NaN.
template <typename T, typename C>
Status unfinite_foot(const Leg& leg, const BlockPoses<C>& P, std::ptrdiff_t i, const T* foot,
                     bool nearest_fallback, T* q_out) noexcept {
  q_out[0] = q_out[1] = q_out[2] = T(quiet_nan<double>());
  if (!leg_batch::finite3(foot)) return Status::InvalidInput;
  const double scale = std::is_same_v<T, float> ? 1.0 : 0x1p-600;  // (1e308 2^-600: 4e127, far)
  double d[3], p[3];
  for (int j = 0; j < 3; ++j) d[j] = double(foot[j]) * scale - double(P.t[j][i]) * scale;
  for (int r = 0; r < 3; ++r)  // R^T d, R(j, r) = P.R[3 j + r]
    p[r] = double(P.R[r][i]) * d[0] + double(P.R[3 + r][i]) * d[1] + double(P.R[6 + r][i]) * d[2];
  if (nearest_fallback) leg_batch::unreachable_fallback(leg, p[0], p[1], p[2], q_out);
  return Status::Unreachable;
}

// read_poses, then whole vectors (as leg_batch::pad_block): the padding repeats the last pose, so
// that a pose's answer never comes from a loop's scalar remainder. Returns the padded count.
template <typename T, typename C>
SPOTKIN_INLINE std::ptrdiff_t read_padded_poses(const T* poses, BodyPoseFormat format,
                                                const EulerSequence& seq, std::ptrdiff_t stride,
                                                std::ptrdiff_t m, BlockPoses<C>& P) noexcept {
  read_poses(poses, format, seq, stride, m, P);
  const std::ptrdiff_t padded = leg_batch::padded_count<C>(m);
  for (std::ptrdiff_t k = m; k < padded; ++k) {
    for (int r = 0; r < 9; ++r) P.R[r][k] = P.R[r][m - 1];
    for (int r = 0; r < 3; ++r) P.t[r][k] = P.t[r][m - 1];
  }
  return padded;
}

// Whether ik_pairs gives the batch's bits with this compiler and target: checked on x86-64 (GCC and
// Clang, every instruction-set level: tests/test_body.py and the C++ harness). GCC for aarch64
// contracts their multiply-adds differently from the batch loops' (the harness found 18 of 400
// calls equal), so there a few poses take the batch path, as every thread count must give one bits.
#if defined(__x86_64__)
constexpr bool kPairLanesExact = true;
#else
constexpr bool kPairLanesExact = false;
#endif

// ik_pairs' unseeded first pass: the pairs of open.x, y, z (padded) in the legs' shared preferred
// slot. Writes q and status and returns true when it settles every pair; false, and nothing
// written, else.
template <typename T, typename C>
SPOTKIN_INLINE bool ik_pairs_preferred(const Body& body, const BlockPoses<C>& P,
                                       const leg_batch::OpenTargets<C>& open, std::ptrdiff_t count,
                                       std::ptrdiff_t padded, C tol, C limit_tol, T* q,
                                       std::int8_t* status) noexcept {
  C q0[3][kBlock], exists[kBlock], ok[kBlock];
  leg_batch::preferred_pass_lanes<false>(body.pair_legs, body.preferred_slot, open.x, open.y,
                                         open.z, padded, tol, limit_tol, q0, exists, ok,
                                         static_cast<C*>(nullptr));
  const int n = body.n_legs(), w = body.width();
  int unsettled = 0;
  for (std::ptrdiff_t k = 0, i = 0, l = 0; k < count * n;
       ++k, l = l + 1 == n ? 0 : l + 1, i += l == 0)
    unsettled |= !(ok[k] != C(0) && P.ok[i] != C(0));
  if (unsettled) return false;
  for (std::ptrdiff_t k = 0, i = 0, l = 0; k < count * n;
       ++k, l = l + 1 == n ? 0 : l + 1, i += l == 0) {
    const std::array<int, 3>& col = body.columns[std::size_t(l)];
    T* qt = q + w * i;
    qt[col[0]] = T(q0[0][k]), qt[col[1]] = T(q0[1][k]), qt[col[2]] = T(q0[2][k]);
    status[n * i + l] = std::int8_t(Status::Ok);
  }
  return true;
}

// ik() for a few poses (count * n <= Body::kPairLanes): each (pose, leg) pair in its own lane,
// every slot at once (leg_batch::solve_slots_lanes), then each pair chosen as ik() chooses it. ik()
// pads each leg's targets to whole vectors, so one pose costs n vector passes (2 n with a seed);
// here the n legs of a pose share them. The lanes run ik()'s operations on the same values: the
// same bits.
template <int RegisterBytes, typename T>
SPOTKIN_INLINE void ik_pairs(const Body& body, const T* poses, BodyPoseFormat format,
                             const EulerSequence& seq, const T* feet, bool feet_shared,
                             const T* seed, T* q, std::int8_t* status, std::ptrdiff_t count,
                             bool nearest_fallback) noexcept {
  const std::ptrdiff_t stride =
      format == BodyPoseFormat::Euler ? 6 : (format == BodyPoseFormat::Matrix ? 16 : 7);
  using C = leg_batch::Compute<T>;
  const int n = body.n_legs(), w = body.width();
  const C tol = C(Leg::ratio_tolerance<T>()), limit_tol = C(JointLimits<3>::tolerance<T>());
  BlockPoses<C> P;
  read_padded_poses(poses, format, seq, stride, count, P);
  leg_batch::OpenTargets<C> open;
  // the pairs padded to whole registers of the level that runs (not to the 64 bytes of the batch's
  // vectors: at AVX2 one Go2 pose is one register, not two); the loops run these whole
  const std::ptrdiff_t m = count * n,
                       padded = leg_batch::register_padded_count<C, RegisterBytes>(m);
  // (B2), as leg_block_slot, pair by pair: pair k is pose k / n (the last one for the padding), leg
  // k % n (counters: no division). Computed where the pairs are gathered: staging the pairs' poses
  // and feet in lane arrays cost 15 scalar stores a pair, then vector loads that waited for them
  // (store forwarding fails): a fifth of a single pose's kernel.
  for (std::ptrdiff_t k = 0, i = 0, l = 0; k < padded; ++k) {
    const std::ptrdiff_t pose = std::min(i, count - 1);
    const T* foot = feet + (feet_shared ? 3 * l : 3 * n * pose + 3 * l);
    const C dx = C(foot[0]) - P.t[0][pose], dy = C(foot[1]) - P.t[1][pose], dz = C(foot[2]) - P.t[2][pose];
    open.x[k] = P.R[0][pose] * dx + P.R[3][pose] * dy + P.R[6][pose] * dz - C(body.pair_hips[0][k]);
    open.y[k] = P.R[1][pose] * dx + P.R[4][pose] * dy + P.R[7][pose] * dz - C(body.pair_hips[1][k]);
    open.z[k] = P.R[2][pose] * dx + P.R[5][pose] * dy + P.R[8][pose] * dz - C(body.pair_hips[2][k]);
    if (++l == n) l = 0, ++i;
  }
  // Without a seed, first the legs' shared preferred slot, as ik()'s leg_block: when it settles
  // every pair (and every pose is valid), those are ik()'s answers
  if (!seed && body.preferred_slot >= 0 &&
      ik_pairs_preferred(body, P, open, count, padded, tol, limit_tol, q, status))
    return;
  // With a seed, as ik(): the preferred slot's answer where the seed certifies it
  // (seed_certifies); every slot is solved only when some pair's seed does not
  const bool certify = seed && body.preferred_slot >= 0;
  C q0[3][kBlock], exists0[kBlock], ok0[kBlock], bound[kBlock];
  bool certified[kBlock] = {};
  bool every_slot = !certify;
  if (certify) {
    leg_batch::preferred_pass_lanes<true>(body.pair_legs, body.preferred_slot, open.x, open.y,
                                          open.z, padded, tol, limit_tol, q0, exists0, ok0, bound);
    for (std::ptrdiff_t k = 0, i = 0, l = 0; k < m; ++k, l = l + 1 == n ? 0 : l + 1, i += l == 0) {
      const std::array<int, 3>& col = body.columns[std::size_t(l)];
      const T* s = seed + w * i;
      const T sd[3] = {s[col[0]], s[col[1]], s[col[2]]};
      if (P.ok[i] == C(0) || !leg_batch::finite3(sd) ||
          leg_batch::finite_mask(open.x[k], open.y[k], open.z[k]) == C(0))
        continue;  // invalid, or a NaN foot: below, as without a certificate
      certified[k] = leg_batch::seed_certifies(ok0[k], bound[k], q0[0][k], q0[1][k], q0[2][k], sd);
      every_slot = every_slot || !certified[k];
    }
  }
  if (every_slot && body.shared_knees)
    leg_batch::solve_slots_lanes<true>(body.pair_legs, open.x, open.y, open.z, padded, tol,
                                       limit_tol, open.q, open.ok, open.exists_hip);
  else if (every_slot)
    leg_batch::solve_slots_lanes<false>(body.pair_legs, open.x, open.y, open.z, padded, tol,
                                        limit_tol, open.q, open.ok, open.exists_hip);
  // pair k = n i + l: pose i, leg l (counters, in the increment: the loop body may `continue`)
  for (std::ptrdiff_t k = 0, i = 0, l = 0; k < m; ++k, l = l + 1 == n ? 0 : l + 1, i += l == 0) {
    const Leg& leg = body.legs[std::size_t(l)];
    const std::array<int, 3>& col = body.columns[std::size_t(l)];
    T* qt = q + w * i;
    std::int8_t& st = status[n * i + l];
    const T* s = seed ? seed + w * i : nullptr;
    T sd[3], leg_q[3];
    if (P.ok[i] == C(0) ||
        (s && !(std::isfinite(double(s[col[0]])) && std::isfinite(double(s[col[1]])) &&
                std::isfinite(double(s[col[2]]))))) {
      qt[col[0]] = qt[col[1]] = qt[col[2]] = T(quiet_nan<double>());
      st = std::int8_t(Status::InvalidInput);
      continue;
    }
    if (leg_batch::finite_mask(open.x[k], open.y[k], open.z[k]) == C(0)) {  // NaN foot, or overflow
      st = std::int8_t(unfinite_foot(leg, P, i, feet + (feet_shared ? 3 * l : 3 * n * i + 3 * l),
                                     nearest_fallback, leg_q));
    } else if (certified[k]) {
      leg_q[0] = T(q0[0][k]), leg_q[1] = T(q0[1][k]), leg_q[2] = T(q0[2][k]);
      st = std::int8_t(Status::Ok);
    } else {
      if (s) sd[0] = s[col[0]], sd[1] = s[col[1]], sd[2] = s[col[2]];
      st = std::int8_t(open.choose(leg, k, s ? sd : nullptr, leg_q, nearest_fallback));
    }
    qt[col[0]] = leg_q[0], qt[col[1]] = leg_q[1], qt[col[2]] = leg_q[2];
  }
}

// Fetches the cache lines of share `share` of `shares` of [from, from + bytes), for writing
// (Write) or reading.
template <int Write>
SPOTKIN_INLINE void prefetch_share(const char* from, std::size_t bytes, int share,
                                   int shares) noexcept {
  const std::size_t end = bytes * std::size_t(share + 1) / std::size_t(shares);
  for (std::size_t k = bytes * std::size_t(share) / std::size_t(shares) / 64 * 64; k < end; k += 64)
    __builtin_prefetch(from + k, Write, 3);
}

// Whole-body IK over `count` poses, with n = body.n_legs() and w = 3 n. feet:
// (count, n, 3) or, when feet_shared, one (n, 3) stance for every pose. seed:
// null or (count, w). q (count, w) in the body's column order, status
// (count, n): each leg's status and fallback are exactly the leg API's (NaN
// for UNREACHABLE when !nearest_fallback). RegisterBytes: the vector register of the level that
// runs it (register_bytes), whose width a few poses' lanes are padded to (ik_pairs).
template <int RegisterBytes = 64, typename T>
SPOTKIN_INLINE void ik(const Body& body, const T* poses, BodyPoseFormat format,
                       const EulerSequence& seq, const T* feet, bool feet_shared, const T* seed,
                       T* q, std::int8_t* status, std::ptrdiff_t count,
                       bool nearest_fallback = true) noexcept {
  const std::ptrdiff_t stride = format == BodyPoseFormat::Euler ? 6 : (format == BodyPoseFormat::Matrix ? 16 : 7);
  using C = leg_batch::Compute<T>;
  const int n = body.n_legs(), w = body.width();
  // A few double poses in the pair lanes. float32 ones take the batch path at any count: GCC
  // fused another of hip_pitch's multiply-adds in the float batch kernel than in its lanes (one ulp
  // apart at AVX2 on a tenth of Spot's targets, once leg_block_slot skipped the turned angles), and
  // a pose's bits must not depend on the batch around it (one pose: 0.68 -> 0.8 us).
  if constexpr (std::is_same_v<C, double>)
    if (kPairLanesExact && count * n <= Body::kPairLanes)
      return ik_pairs<RegisterBytes>(body, poses, format, seq, feet, feet_shared, seed, q, status,
                                     count, nearest_fallback);
  const C tol = C(Leg::ratio_tolerance<T>()), limit_tol = C(JointLimits<3>::tolerance<T>());
  BlockPoses<C> P;
  C fx[kBlock], fy[kBlock], fz[kBlock], x[kBlock], y[kBlock], z[kBlock], own_q0[3][kBlock],
      exists[kBlock], ok[kBlock], bound[kBlock];
  // The block's answers by column, Q[c][i], written out row by row at the block's end
  // (transpose_rows): stored leg by leg into rows of w values, 3 scattered stores a target whose
  // loads waited on them were a tenth of the kernel (AVX2). Legs in column order solve straight
  // into their rows.
  static_assert(std::is_same_v<C, T>, "the kernels compute in their input's type");
  alignas(64) C Q[3 * Body::kMaxLegs][kBlock];
  const bool contiguous = body.leg_contiguous();
  leg_batch::OpenTargets<C> open;
  // with a seed, the preferred slot's answer where the seed certifies it (seed_certifies), every
  // slot where it does not; on the terms ik_pairs has (legs sharing their preferred slot)
  const bool certify = seed && body.preferred_slot >= 0;
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    // While the legs are solved, each leg fetches its share of the lines of the block's rows of q
    // (for writing) and of the next block's poses (prefetch_share): written at the end in one
    // burst, the rows waited on their cache lines (2-3 % of body_ik; non-temporal stores of the
    // rows measured no faster, with one thread or two); fetched all at the block's start, the
    // prefetches waited in turn (3 % at AVX2); without the poses', body_ik was 2-4 % slower at AVX2
    // (the boundary's scan of a span leaves them in cache, but not in the nearest one).
    const char* const rows = reinterpret_cast<const char*>(q + w * b0);
    const std::size_t bytes = std::size_t(m * w) * sizeof(T);
    const char* const next = reinterpret_cast<const char*>(poses + stride * (b0 + m));
    const std::size_t next_bytes =
        std::size_t(std::min(kBlock, count - b0 - m) * stride) * sizeof(T);
    const std::ptrdiff_t padded = read_padded_poses(poses + stride * b0, format, seq, stride, m, P);
    for (int l = 0; l < n; ++l) {
      prefetch_share<1>(rows, bytes, l, n);
      prefetch_share<0>(next, next_bytes, l, n);
      const Leg& leg = body.legs[std::size_t(l)];
      const std::array<int, 3>& col = body.columns[std::size_t(l)];
      C* const q_col[3] = {Q[col[0]], Q[col[1]], Q[col[2]]};
      C(*const q0)[kBlock] = contiguous ? Q + 3 * l : own_q0;
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const T* f = feet + (feet_shared ? 3 * l : 3 * n * (b0 + i) + 3 * l);
        fx[i] = C(f[0]), fy[i] = C(f[1]), fz[i] = C(f[2]);
      }
      leg_batch::pad_block(fx, fy, fz, m);
      const std::array<double, 3>& hip = body.hips[std::size_t(l)];
      const C hip_c[3] = {C(hip[0]), C(hip[1]), C(hip[2])};
      leg_block(leg, hip_c, P.R, P.t, fx, fy, fz, x, y, z, q0, exists, ok,
                certify ? bound : nullptr, padded, tol, limit_tol);
      open.count = 0;
      if (!seed && leg_batch::all_settled(ok, P.ok, m)) {  // the common case, without a branch per target
        if (!contiguous)
          for (int j = 0; j < 3; ++j) std::copy(q0[j], q0[j] + m, q_col[j]);
        std::int8_t* st = status + n * b0 + l;
        for (std::ptrdiff_t i = 0; i < m; ++i, st += n) *st = std::int8_t(Status::Ok);
        continue;
      }
      // (each target's answer below lands in its own lane i of Q, after q0's lane i is read: q0
      // may be those rows)
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const std::ptrdiff_t t = b0 + i;
        std::int8_t& st = status[n * t + l];
        if (!seed && ok[i] != C(0) && P.ok[i] != C(0)) {  // the common case (seeded: ok unset)
          q_col[0][i] = q0[0][i], q_col[1][i] = q0[1][i], q_col[2][i] = q0[2][i];
          st = std::int8_t(Status::Ok);
          continue;
        }
        const T* s = seed ? seed + w * t : nullptr;
        if (P.ok[i] == C(0) ||
            (s && !(std::isfinite(double(s[col[0]])) && std::isfinite(double(s[col[1]])) &&
                    std::isfinite(double(s[col[2]]))))) {
          q_col[0][i] = q_col[1][i] = q_col[2][i] = T(quiet_nan<double>());
          st = std::int8_t(Status::InvalidInput);
          continue;
        }
        if (exists[i] < C(0)) {  // a NaN foot, or overflow
          T leg_q[3];
          st =
              std::int8_t(unfinite_foot(leg, P, i, feet + (feet_shared ? 3 * l : 3 * n * t + 3 * l),
                                        nearest_fallback, leg_q));
          q_col[0][i] = leg_q[0], q_col[1][i] = leg_q[1], q_col[2][i] = leg_q[2];
          continue;
        }
        if (certify) {
          const T sd[3] = {s[col[0]], s[col[1]], s[col[2]]};
          if (leg_batch::seed_certifies(ok[i], bound[i], q0[0][i], q0[1][i], q0[2][i], sd)) {
            q_col[0][i] = q0[0][i], q_col[1][i] = q0[1][i], q_col[2][i] = q0[2][i];
            st = std::int8_t(Status::Ok);
            continue;
          }
        }
        open.add(i, x[i], y[i], z[i]);
      }
      open.solve(leg, tol, limit_tol);
      for (std::ptrdiff_t k = 0; k < open.count; ++k) {
        const std::ptrdiff_t i = open.index[k], t = b0 + i;
        T sd[3], leg_q[3];
        if (seed) {
          const T* s = seed + w * t;
          sd[0] = s[col[0]], sd[1] = s[col[1]], sd[2] = s[col[2]];
        }
        status[n * t + l] = std::int8_t(open.choose(leg, k, seed ? sd : nullptr, leg_q, nearest_fallback));
        q_col[0][i] = leg_q[0], q_col[1][i] = leg_q[1], q_col[2][i] = leg_q[2];
      }
    }
    transpose_rows<RegisterBytes>(Q, w, m, q + w * b0);
  }
}

// Whole-body IK along a path (double): pose k seeded with the answer at pose k - 1, pose 0 with
// `seed` (null: unseeded). Each leg's running seed takes its last finite joints (a leg without an
// answer keeps the seed it had), so the branch never flips while an answer exists. Answers and
// statuses are those of ik() called pose by pose with these seeds: every slot of a block is solved
// in lanes (OpenTargets), then chosen in order.
template <typename T>
SPOTKIN_INLINE void ik_path(const Body& body, const T* poses, BodyPoseFormat format,
                            const EulerSequence& seq, const T* feet, const T* seed, T* q,
                            std::int8_t* status, std::ptrdiff_t count,
                            bool nearest_fallback = true) noexcept {
  const std::ptrdiff_t stride =
      format == BodyPoseFormat::Euler ? 6 : (format == BodyPoseFormat::Matrix ? 16 : 7);
  using C = leg_batch::Compute<T>;
  const int n = body.n_legs(), w = body.width();
  const C tol = C(Leg::ratio_tolerance<T>()), limit_tol = C(JointLimits<3>::tolerance<T>());
  BlockPoses<C> P;
  C fx[kBlock], fy[kBlock], fz[kBlock], x[kBlock], y[kBlock], z[kBlock], exists[kBlock],
      q0[3][kBlock], ok[kBlock], bound[kBlock];
  leg_batch::OpenTargets<C> open;
  const bool certify = body.preferred_slot >= 0;  // as ik() certifies a seed
  T running[3 * Body::kMaxLegs];  // each leg's seed, in its own three slots
  bool seeded = seed != nullptr;
  if (seeded)
    for (int l = 0; l < n; ++l)
      for (int j = 0; j < 3; ++j)
        running[3 * l + j] = seed[body.columns[std::size_t(l)][std::size_t(j)]];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    const std::ptrdiff_t padded = read_padded_poses(poses + stride * b0, format, seq, stride, m, P);
    const bool block_seeded = seeded;
    for (int l = 0; l < n; ++l) {
      const Leg& leg = body.legs[std::size_t(l)];
      const std::array<int, 3>& col = body.columns[std::size_t(l)];
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const T* f = feet + 3 * n * (b0 + i) + 3 * l;
        fx[i] = C(f[0]), fy[i] = C(f[1]), fz[i] = C(f[2]);
      }
      leg_batch::pad_block(fx, fy, fz, m);
      const std::array<double, 3>& hip = body.hips[std::size_t(l)];
      const C hip_c[3] = {C(hip[0]), C(hip[1]), C(hip[2])};
      // the preferred slot's answers and the seeds' certificates (as ik() has them); every slot is
      // solved only from the first target a seed does not certify (the seed of each is the answer
      // before it), once a block
      leg_block(leg, hip_c, P.R, P.t, fx, fy, fz, x, y, z, q0, exists, ok,
                certify ? bound : nullptr, padded, tol, limit_tol);
      open.count = 0;
      bool opened = false;
      T* sd = running + 3 * l;
      bool leg_seeded = block_seeded;
      for (std::ptrdiff_t i = 0, k = 0; i < m; ++i) {
        const std::ptrdiff_t t = b0 + i;
        T* qt = q + w * t;
        T leg_q[3];
        std::int8_t st;
        if (P.ok[i] == C(0) || (leg_seeded && !leg_batch::finite3(sd))) {  // as ik()
          leg_q[0] = leg_q[1] = leg_q[2] = T(quiet_nan<double>());
          st = std::int8_t(Status::InvalidInput);
        } else if (exists[i] < C(0)) {  // a NaN foot, or overflow
          st = std::int8_t(
              unfinite_foot(leg, P, i, feet + 3 * n * t + 3 * l, nearest_fallback, leg_q));
        } else if (certify && (leg_seeded ? leg_batch::seed_certifies(ok[i], bound[i], q0[0][i],
                                                                      q0[1][i], q0[2][i], sd)
                                          : ok[i] != C(0))) {  // unseeded: the preferred slot first
          leg_q[0] = T(q0[0][i]), leg_q[1] = T(q0[1][i]), leg_q[2] = T(q0[2][i]);
          st = std::int8_t(Status::Ok);
        } else {
          if (!opened) {
            for (std::ptrdiff_t j = i; j < m; ++j)
              if (P.ok[j] != C(0) && exists[j] >= C(0)) open.add(j, x[j], y[j], z[j]);
            open.solve(leg, tol, limit_tol);
            opened = true;
          }
          while (open.index[k] < i) ++k;
          st = std::int8_t(open.choose(leg, k, leg_seeded ? sd : nullptr, leg_q, nearest_fallback));
        }
        qt[col[0]] = leg_q[0], qt[col[1]] = leg_q[1], qt[col[2]] = leg_q[2];
        status[n * t + l] = st;
        for (int j = 0; j < 3;
             ++j)  // the next seed: the last finite joints (all of them at the first pose)
          if (!leg_seeded || std::isfinite(double(leg_q[j]))) sd[j] = leg_q[j];
        leg_seeded = true;
      }
    }
    seeded = true;
  }
}

// (B1): world foot positions (count, n, 3).
template <typename T>
SPOTKIN_INLINE void fk(const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq,
                       const T* q, T* feet, std::ptrdiff_t count) noexcept {
  const std::ptrdiff_t stride = format == BodyPoseFormat::Euler ? 6 : (format == BodyPoseFormat::Matrix ? 16 : 7);
  const int n = body.n_legs(), w = body.width();
  BlockPoses<double> P;
  double legq[kBlock * 3], p[kBlock * 3];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    read_poses(poses + stride * b0, format, seq, stride, m, P);
    for (int l = 0; l < n; ++l) {
      const std::array<int, 3>& col = body.columns[std::size_t(l)];
      const std::array<double, 3>& hip = body.hips[std::size_t(l)];
      for (std::ptrdiff_t i = 0; i < m; ++i)
        for (int j = 0; j < 3; ++j) legq[3 * i + j] = double(q[w * (b0 + i) + col[j]]);
      leg_batch::fk(body.legs[std::size_t(l)], legq, p, m);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const double h[3] = {hip[0] + p[3 * i], hip[1] + p[3 * i + 1], hip[2] + p[3 * i + 2]};
        T* f = feet + 3 * n * (b0 + i) + 3 * l;
        const double nan_if_bad = P.ok[i] != 0.0 ? 0.0 : quiet_nan<double>();
        for (int r = 0; r < 3; ++r)
          f[r] = T(P.t[r][i] + P.R[3 * r][i] * h[0] + P.R[3 * r + 1][i] * h[1] + P.R[3 * r + 2][i] * h[2] +
                   nan_if_bad);
      }
    }
  }
}

// (B3): d(feet world) / d(v, w, q), (count, 3 n, 6 + 3 n), row-major; the q
// columns in the body's column order.
template <typename T>
SPOTKIN_INLINE void jacobian(const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq,
                             const T* q, T* J, std::ptrdiff_t count) noexcept {
  const std::ptrdiff_t stride = format == BodyPoseFormat::Euler ? 6 : (format == BodyPoseFormat::Matrix ? 16 : 7);
  const int n = body.n_legs(), w = body.width(), cols = 6 + w;
  const std::ptrdiff_t size = std::ptrdiff_t(3 * n) * cols;
  BlockPoses<double> P;
  double legq[kBlock * 3], p[kBlock * 3], Jl[kBlock * 9];
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min(kBlock, count - b0);
    read_poses(poses + stride * b0, format, seq, stride, m, P);
    for (std::ptrdiff_t i = 0; i < m; ++i) std::fill(J + size * (b0 + i), J + size * (b0 + i + 1), T(0));
    for (int l = 0; l < n; ++l) {
      const std::array<int, 3>& col = body.columns[std::size_t(l)];
      const std::array<double, 3>& hip = body.hips[std::size_t(l)];
      for (std::ptrdiff_t i = 0; i < m; ++i)
        for (int j = 0; j < 3; ++j) legq[3 * i + j] = double(q[w * (b0 + i) + col[j]]);
      leg_batch::fk(body.legs[std::size_t(l)], legq, p, m);
      leg_batch::jacobian(body.legs[std::size_t(l)], legq, Jl, m);
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        const double nan_if_bad = P.ok[i] != 0.0 ? 0.0 : quiet_nan<double>();
        const double h[3] = {hip[0] + p[3 * i], hip[1] + p[3 * i + 1], hip[2] + p[3 * i + 2]};
        double r[3];  // foot_world - t = R h
        for (int a = 0; a < 3; ++a) r[a] = P.R[3 * a][i] * h[0] + P.R[3 * a + 1][i] * h[1] + P.R[3 * a + 2][i] * h[2];
        T* rows = J + size * (b0 + i) + std::ptrdiff_t(cols) * 3 * l;
        for (int a = 0; a < 3; ++a) rows[cols * a + a] = T(1.0 + nan_if_bad);  // d/dv = I
        // d/dw: w x r = -[r]x w
        rows[0 * cols + 3] = T(0.0 + nan_if_bad), rows[0 * cols + 4] = T(r[2] + nan_if_bad),
        rows[0 * cols + 5] = T(-r[1] + nan_if_bad);
        rows[1 * cols + 3] = T(-r[2] + nan_if_bad), rows[1 * cols + 4] = T(0.0 + nan_if_bad),
        rows[1 * cols + 5] = T(r[0] + nan_if_bad);
        rows[2 * cols + 3] = T(r[1] + nan_if_bad), rows[2 * cols + 4] = T(-r[0] + nan_if_bad),
        rows[2 * cols + 5] = T(0.0 + nan_if_bad);
        // d/dq_l = R J_leg
        const double* Jli = Jl + 9 * i;
        for (int a = 0; a < 3; ++a)
          for (int k = 0; k < 3; ++k)
            rows[cols * a + 6 + col[k]] = T(P.R[3 * a][i] * Jli[k] + P.R[3 * a + 1][i] * Jli[3 + k] +
                                             P.R[3 * a + 2][i] * Jli[6 + k] + nan_if_bad);
      }
    }
    for (std::ptrdiff_t i = 0; i < m; ++i)  // an invalid pose: NaN everywhere, the zero blocks too
      if (P.ok[i] == 0.0) std::fill(J + size * (b0 + i), J + size * (b0 + i + 1), T(quiet_nan<double>()));
  }
}

}  // namespace body_batch

}  // namespace spotkin
