// Batches of closed-form chain IK: blocks of targets across vector lanes, finished
// into every-solution or nearest-solution outputs.
#pragma once

#include "spotkin/chain_ik/spherical_wrist.hpp"

namespace spotkin::chain_ik {


// The finished lanes of one block: angle[k][j][i] (NaN where slot k has no
// solution), valid and exists (1 or 0), status (a Status).
template <int Slots, int Dof, int L>
struct FinishedBlock {
  static constexpr int S = Slots;
  double angle[Slots][Dof][L], exists[Slots][L], valid[Slots][L], status[L], input_ok[L];
};

// Writes lane i of a finished block as one sample: q (Slots, Dof), valid and
// exists (Slots), status.
template <int Slots, int Dof, int L, typename T>
SPOTKIN_INLINE void store_lane(const FinishedBlock<Slots, Dof, L>& block, int i, T* q, std::uint8_t* valid,
                               std::uint8_t* exists, std::int8_t* status) noexcept {
  const double* angles = &block.angle[0][0][0];
  for (int k = 0; k < Slots * Dof; ++k) q[k] = T(angles[k * L + i]);
  for (int k = 0; k < Slots; ++k) valid[k] = block.valid[k][i] != 0.0, exists[k] = block.exists[k][i] != 0.0;
  *status = static_cast<std::int8_t>(block.status[i]);
}

// The solves of one block (up to 16 samples), finished in the lanes, compiled
// once per CPU level with the solvers inlined (double only: the I/O type is
// handled outside).
using PositionBlock = FinishedBlock<Position3::kSlots, 3, Position3::kLanes>;

SPOTKIN_CLONES((__attribute__((flatten)) __attribute__((noinline)) inline), void, position_block, (const Position3& solver,
                                                                          const Limits& limits, const double* px,
                                                                          const double* py, const double* pz, int m,
                                                                          PositionBlock& out) noexcept, (solver, limits, px, py, pz, m, out),
  constexpr int S = PositionBlock::S, L = Position3::kLanes;
  Position3::BlockSolutions sol;
  solver.solve_block(px, py, pz, m, sol);
  for (int i = 0; i < L; ++i)
    out.input_ok[i] = std::isfinite(px[i]) && std::isfinite(py[i]) && std::isfinite(pz[i]) ? 1.0 : 0.0;
  auto finish = [&](auto full) SPOTKIN_INLINE_LAMBDA {
    const int lanes = decltype(full)::value ? L : m;
    for (int k = 0; k < S; ++k) {
      for (int i = 0; i < lanes; ++i) out.exists[k][i] = k < sol.n[i] ? 1.0 : 0.0;
      for (int j = 0; j < 3; ++j) {
        const bool prismatic = solver.sigma(j) == 1;
        for (int i = 0; i < lanes; ++i)
          out.angle[k][j][i] = prismatic ? sol.v[k][j][i] : vector_math::atan2(sol.s[k][j][i], sol.c[k][j][i]);
      }
    }
    finish_lanes<decltype(full)::value>(limits, m, out.input_ok, out.angle, out.exists, out.valid);
  };
  if (m == L)
    finish(std::true_type{});
  else
    finish(std::false_type{});
  lane_status(m, out.input_ok, out.exists, out.valid, out.status);
)

using WristBlock = FinishedBlock<SphericalWrist6::kSlots, 6, SphericalWrist6::kLanes>;

SPOTKIN_CLONES_T((template <PoseFormat Format> __attribute__((flatten)) __attribute__((noinline))), void, wrist_block, (<Format>), (const SphericalWrist6& solver, const Limits& limits,
                                                                const double (*pose_in)[SphericalWrist6::kLanes],
                                                                int m, WristBlock& out) noexcept, (solver, limits, pose_in, m, out),
  solver.solve_block<Format>(pose_in, m, limits, out.angle, out.exists, out.valid, out.input_ok);
  lane_status(m, out.input_ok, out.exists, out.valid, out.status);
)

// Lane i of a finished block as one answer: the valid slot nearest to the
// seed (the largest single-joint move: on the circle for a revolute joint,
// plain for a prismatic one; ties to the lower slot), or the lowest valid slot
// without a seed (seed null). q (Dof) is NaN unless the status is OK; a seed
// with NaN or Inf gives INVALID_INPUT.
template <int Slots, int Dof, int L, typename T>
SPOTKIN_INLINE void store_nearest(const FinishedBlock<Slots, Dof, L>& block, int i, const Limits& limits,
                                  const T* seed, T* q, std::int8_t* status) noexcept {
  constexpr double two_pi = 2.0 * kPi<double>, inv_two_pi = 1.0 / two_pi;
  bool seed_ok = true;
  double seed_value[Dof] = {};
  for (int j = 0; seed && j < Dof; ++j) {
    seed_value[j] = double(seed[j]), seed_ok &= std::isfinite(seed_value[j]);
    if (limits.sigma[j] == 0) seed_value[j] = wrap_angle(seed_value[j]);  // any magnitude, exactly
  }
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < Slots; ++k) {
    if (block.valid[k][i] == 0.0) continue;
    if (!seed) {
      best = k;
      break;
    }
    double distance = 0.0;
    for (int j = 0; j < Dof; ++j) {
      // |move| <= 4 pi here (angles within 2 pi of (-pi, pi], the seed in it): one rounding wraps it
      const double move = block.angle[k][j][i] - seed_value[j];
      distance = std::max(distance, std::fabs(limits.sigma[j] == 0 ? move - two_pi * std::round(move * inv_two_pi) : move));
    }
    if (distance < best_distance) best = k, best_distance = distance;  // strict: ties keep the lower slot
  }
  const auto st = seed_ok ? static_cast<std::int8_t>(block.status[i]) : static_cast<std::int8_t>(Status::InvalidInput);
  const bool ok = st == static_cast<std::int8_t>(Status::Ok) && best >= 0;
  for (int j = 0; j < Dof; ++j) q[j] = ok ? T(block.angle[best][j][i]) : quiet_nan<T>();
  *status = st;
}

// Position IK for count targets p (count, 3), block by block: store(block,
// i, n) writes lane i of a finished PositionBlock as answer n.
template <typename T, typename Store>
SPOTKIN_INLINE void position_blocks(const Position3& solver, const Limits& limits, const T* points,
                                    std::ptrdiff_t count, Store&& store) noexcept {
  constexpr int L = Position3::kLanes;
  PositionBlock block;
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, count - b0));
    double px[L], py[L], pz[L];
    for (int i = 0; i < L; ++i) {
      const T* point = points + 3 * (b0 + std::min(i, m - 1));
      px[i] = double(point[0]), py[i] = double(point[1]), pz[i] = double(point[2]);
    }
    position_block(solver, limits, px, py, pz, m, block);
    for (int i = 0; i < m; ++i) store(block, i, b0 + i);
  }
}

// 6R IK for count poses ((count, 16) matrices or (count, 7) position +
// quaternion), block by block, as position_blocks.
template <PoseFormat Format, typename T, typename Store>
SPOTKIN_INLINE void wrist_blocks(const SphericalWrist6& solver, const Limits& limits, const T* poses,
                                 std::ptrdiff_t count, Store&& store) noexcept {
  constexpr int L = SphericalWrist6::kLanes, width = Format == PoseFormat::Matrix ? 16 : 7;
  WristBlock block;
  double pose_in[width][L];  // the poses as structure of arrays
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, count - b0));
    for (int i = 0; i < m; ++i)
      for (int e = 0; e < width; ++e) pose_in[e][i] = double(poses[width * (b0 + i) + e]);
    wrist_block<Format>(solver, limits, pose_in, m, block);
    for (int i = 0; i < m; ++i) store(block, i, b0 + i);
  }
}

// Every solution: q (count, 4, 3), valid and exists (count, 4), status (count).
template <typename T>
SPOTKIN_INLINE void ik_position(const Position3& solver, const Limits& limits, const T* points, T* q,
                                std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                                std::ptrdiff_t count) noexcept {
  constexpr int S = PositionBlock::S, W = S * 3;
  position_blocks(solver, limits, points, count, [&](const PositionBlock& block, int i, std::ptrdiff_t at) {
    store_lane(block, i, q + W * at, valid + S * at, exists + S * at, status + at);
  });
}

// Every solution: q (count, 8, 6), valid and exists (count, 8), status (count).
template <PoseFormat Format, typename T>
SPOTKIN_INLINE void ik_wrist(const SphericalWrist6& solver, const Limits& limits, const T* poses, T* q,
                             std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                             std::ptrdiff_t count) noexcept {
  constexpr int S = WristBlock::S, W = S * 6;
  wrist_blocks<Format>(solver, limits, poses, count, [&](const WristBlock& block, int i, std::ptrdiff_t at) {
    store_lane(block, i, q + W * at, valid + S * at, exists + S * at, status + at);
  });
}

// One solution per target (store_nearest): q (count, 3), status (count);
// seed (count, 3) or null.
template <typename T>
SPOTKIN_INLINE void ik_position_nearest(const Position3& solver, const Limits& limits, const T* points,
                                        const T* seed, T* q, std::int8_t* status, std::ptrdiff_t count) noexcept {
  position_blocks(solver, limits, points, count, [&](const PositionBlock& block, int i, std::ptrdiff_t at) {
    store_nearest(block, i, limits, seed ? seed + 3 * at : nullptr, q + 3 * at, status + at);
  });
}

// One solution per pose (store_nearest): q (count, 6), status (count); seed
// (count, 6) or null.
template <PoseFormat Format, typename T>
SPOTKIN_INLINE void ik_wrist_nearest(const SphericalWrist6& solver, const Limits& limits, const T* poses,
                                     const T* seed, T* q, std::int8_t* status, std::ptrdiff_t count) noexcept {
  wrist_blocks<Format>(solver, limits, poses, count, [&](const WristBlock& block, int i, std::ptrdiff_t at) {
    store_nearest(block, i, limits, seed ? seed + 6 * at : nullptr, q + 6 * at, status + at);
  });
}

}  // namespace spotkin::chain_ik
