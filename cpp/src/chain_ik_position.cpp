// The 3-joint position IK batches (spotkin/chain_ik/kernels.hpp), one clone per
// instruction-set level, for float and double.
#include "spotkin/chain_ik/kernels.hpp"

namespace spotkin::chain_ik {

SPOTKIN_CLONES((template <typename T>), void, position_kernel,
               (const Position3& solver, const Limits& limits, const T* p, T* q, std::uint8_t* valid,
                std::uint8_t* exists, std::int8_t* status, std::ptrdiff_t n),
               (solver, limits, p, q, valid, exists, status, n),
  ik_position(solver, limits, p, q, valid, exists, status, n);
)

SPOTKIN_CLONES((template <typename T>), void, position_nearest_kernel,
               (const Position3& solver, const Limits& limits, const T* p, const T* seed, T* q, std::int8_t* status,
                std::ptrdiff_t n),
               (solver, limits, p, seed, q, status, n),
  ik_position_nearest(solver, limits, p, seed, q, status, n);
)

#define SPOTKIN_INSTANTIATE(T)                                                                                  \
  template void position_kernel<T>(const Position3&, const Limits&, const T*, T*, std::uint8_t*, std::uint8_t*, \
                                   std::int8_t*, std::ptrdiff_t);                                               \
  template void position_nearest_kernel<T>(const Position3&, const Limits&, const T*, const T*, T*,            \
                                           std::int8_t*, std::ptrdiff_t);
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::chain_ik
