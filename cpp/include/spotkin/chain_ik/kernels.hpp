// The batched chain IK entry points, each dispatched to the instruction-set clone of
// the active level (SPOTKIN_CLONES). They are compiled in their own translation units,
// cpp/src/chain_ik_position.cpp and cpp/src/chain_ik_arm6.cpp, for float and double:
// the two families' clones are the heaviest code to compile, and apart they build in
// parallel with half the memory each.
#pragma once

#include <cstdint>

#include "spotkin/chain_ik/arm6.hpp"

namespace spotkin::chain_ik {

// Every solution of 3-joint position IK: q (n, 4, 3), valid and exists (n, 4), status (n).
template <typename T>
void position_kernel(const Position3& solver, const Limits& limits, const T* p, T* q, std::uint8_t* valid,
                     std::uint8_t* exists, std::int8_t* status, std::ptrdiff_t n);

// One solution per target, the nearest to seed (may be null): q (n, 3), status (n).
template <typename T>
void position_nearest_kernel(const Position3& solver, const Limits& limits, const T* p, const T* seed, T* q,
                             std::int8_t* status, std::ptrdiff_t n);

// Every solution of 6R IK: q (n, 8, 6), valid, exists and exact (n, 8), status (n).
template <typename T>
void arm6_kernel(const Arm6& solver, const Limits& limits, const T* poses, PoseFormat format, T* q,
                 std::uint8_t* valid, std::uint8_t* exists, std::uint8_t* exact, std::int8_t* status,
                 std::ptrdiff_t n);

// One 6R solution per pose, the nearest to seed (may be null): q (n, 6), status (n).
template <typename T>
void arm6_nearest_kernel(const Arm6& solver, const Limits& limits, const T* poses, PoseFormat format, const T* seed,
                         T* q, std::int8_t* status, std::ptrdiff_t n);

}  // namespace spotkin::chain_ik
