// The 6-DOF arm's batch kernels, each dispatched to the clone of the active
// instruction-set level (SPOTKIN_CLONES, spotkin/isa.hpp), compiled in
// cpp/src/arm_kernels.cpp for float and double, apart from the bindings.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spotkin/arm.hpp"

namespace spotkin::kernels {

// q (n, 6) -> the tool's poses (n, 4, 4).
template <typename T>
void arm_fk(const Arm& arm, const T* q, T* out, std::ptrdiff_t n);

// q (n, 6) -> the tool's Jacobians (n, 6, 6).
template <typename T>
void arm_jacobian(const Arm& arm, const T* q, T* out, std::ptrdiff_t n);

// Poses (n, format's width), seed null or (n, 6) -> all 8 solutions q (n, 8, 6), valid and
// exists (n, 8), status (n).
template <typename T>
void arm_ik_all(const Arm& arm, const T* poses, PoseFormat format, const T* seed, T* q, std::uint8_t* valid,
                std::uint8_t* exists, std::int8_t* status, std::ptrdiff_t n);

// The chosen solution, the nearest to seed (null: arm_batch::ik's choice): q (n, 6), status (n).
// It chooses among arm_ik_all's solutions: one copy of the solver per level.
template <typename T>
void arm_ik(const Arm& arm, const T* poses, PoseFormat format, const T* seed, T* q, std::int8_t* status,
            std::ptrdiff_t n);

}  // namespace spotkin::kernels
