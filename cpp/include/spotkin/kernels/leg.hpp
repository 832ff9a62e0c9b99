// The leg's batch kernels, each dispatched to the clone of the active instruction-set
// level (SPOTKIN_CLONES, spotkin/isa.hpp). They are compiled in cpp/src/leg_kernels.cpp,
// for float and double, apart from the bindings: a unit that includes pybind11 compiles
// its internals again, so the bindings' glue builds in few units (docs/build.md).
#pragma once

#include <cstddef>
#include <cstdint>

#include "spotkin/leg.hpp"

namespace spotkin::kernels {

// q (n, 3) -> foot positions p (n, 3).
template <typename T>
void leg_fk(const Leg& leg, const T* q, T* p, std::ptrdiff_t n);

// q (n, 3) -> the foot's Jacobians J (n, 3, 3).
template <typename T>
void leg_jacobian(const Leg& leg, const T* q, T* J, std::ptrdiff_t n);

// p (n, 3), seed null or (n, 3) -> q (n, 3), status (n): the limit-aware choice.
template <typename T>
void leg_ik(const Leg& leg, const T* p, const T* seed, T* q, std::int8_t* status, std::ptrdiff_t n,
            bool nearest_fallback);

// p (n, 3) -> every branch: q (n, 4, 3), valid and exists (n, 4), status (n).
template <typename T>
void leg_ik_all(const Leg& leg, const T* p, T* q, std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                std::ptrdiff_t n);

}  // namespace spotkin::kernels
