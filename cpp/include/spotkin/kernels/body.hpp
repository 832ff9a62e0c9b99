// The whole body's batch kernels, each dispatched to the clone of the active
// instruction-set level (SPOTKIN_CLONES, spotkin/isa.hpp), compiled in
// cpp/src/body_kernels.cpp for float and double, apart from the bindings.
#pragma once

#include <cstddef>
#include <cstdint>

#include "spotkin/body.hpp"

namespace spotkin::kernels {

// Body poses (n, format's width) and feet (n, legs, 3), or one set of feet for every pose when
// feet_shared; seed null or (n, 3 legs) -> q (n, 3 legs), status (n).
template <typename T>
void body_ik(const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq, const T* feet,
             bool feet_shared, const T* seed, T* q, std::int8_t* status, std::ptrdiff_t n, bool nearest_fallback);

// body_ik along a path (body_batch::ik_path): pose k seeded with pose k - 1's answer, pose 0 with
// seed (null: unseeded); feet (n, legs, 3).
template <typename T>
void body_ik_path(const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq,
                  const T* feet, const T* seed, T* q, std::int8_t* status, std::ptrdiff_t n,
                  bool nearest_fallback);

// Body poses (n, width) and q (n, 3 legs) -> the feet in the world frame (n, legs, 3).
template <typename T>
void body_fk(const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq, const T* q, T* feet,
             std::ptrdiff_t n);

// The feet's Jacobians with respect to the body pose and the joints (body_batch::jacobian).
template <typename T>
void body_jacobian(const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq, const T* q,
                   T* J, std::ptrdiff_t n);

}  // namespace spotkin::kernels
