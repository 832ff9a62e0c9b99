// The 6R IK batches (spotkin/chain_ik/kernels.hpp), one clone per instruction-set
// level, for float and double; the 7-joint solver's per-value 6R solves call these too.
#include "spotkin/chain_ik/kernels.hpp"

namespace spotkin::chain_ik {

SPOTKIN_CLONES((template <typename T>), void, arm6_kernel,
               (const Arm6& solver, const Limits& limits, const T* poses, PoseFormat format, T* q,
                std::uint8_t* valid, std::uint8_t* exists, std::uint8_t* exact, std::int8_t* status,
                std::ptrdiff_t n),
               (solver, limits, poses, format, q, valid, exists, exact, status, n),
  if (format == PoseFormat::Matrix)
    ik_arm6<PoseFormat::Matrix>(solver, limits, poses, q, valid, exists, exact, status, n);
  else
    ik_arm6<PoseFormat::PositionQuaternion>(solver, limits, poses, q, valid, exists, exact, status, n);
)

SPOTKIN_CLONES((template <typename T>), void, arm6_nearest_kernel,
               (const Arm6& solver, const Limits& limits, const T* poses, PoseFormat format, const T* seed, T* q,
                std::int8_t* status, std::ptrdiff_t n),
               (solver, limits, poses, format, seed, q, status, n),
  if (format == PoseFormat::Matrix)
    ik_arm6_nearest<PoseFormat::Matrix>(solver, limits, poses, seed, q, status, n);
  else
    ik_arm6_nearest<PoseFormat::PositionQuaternion>(solver, limits, poses, seed, q, status, n);
)

#define SPOTKIN_INSTANTIATE(T)                                                                                     \
  template void arm6_kernel<T>(const Arm6&, const Limits&, const T*, PoseFormat, T*, std::uint8_t*, std::uint8_t*, \
                               std::uint8_t*, std::int8_t*, std::ptrdiff_t);                                       \
  template void arm6_nearest_kernel<T>(const Arm6&, const Limits&, const T*, PoseFormat, const T*, T*,            \
                                       std::int8_t*, std::ptrdiff_t);
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::chain_ik
