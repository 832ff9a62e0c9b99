// The 6-DOF arm's batch kernels (spotkin/kernels/arm.hpp), one clone per
// instruction-set level, for float and double.
#include "spotkin/kernels/arm.hpp"

#include "spotkin/isa.hpp"

namespace spotkin::kernels {

SPOTKIN_CLONES((template <typename T>), void, arm_fk, (const Arm& arm, const T* q, T* out, std::ptrdiff_t n),
               (arm, q, out, n),
  arm_batch::fk(arm, q, out, n);
)
SPOTKIN_CLONES((template <typename T>), void, arm_jacobian, (const Arm& arm, const T* q, T* out, std::ptrdiff_t n),
               (arm, q, out, n),
  arm_batch::jacobian(arm, q, out, n);
)
SPOTKIN_CLONES((template <typename T>), void, arm_ik_all,
               (const Arm& arm, const T* poses, PoseFormat format, const T* seed, T* q,
                std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status, std::ptrdiff_t n),
               (arm, poses, format, seed, q, valid, exists, status, n),
               arm_batch::ik_all<register_bytes(kIsa)>(arm, poses, format, seed, q, valid, exists,
                                                       status, n);)

// Only the choice is compiled here, at the baseline level; the solutions come from the
// dispatched kernel above.
template <typename T>
void arm_ik(const Arm& arm, const T* poses, PoseFormat format, const T* seed, T* q, std::int8_t* status,
            std::ptrdiff_t n) {
  arm_batch::ik(arm, poses, format, seed, q, status, n,
                [&](const T* p, PoseFormat f, const T* s, T* q_all, std::uint8_t* valid, std::uint8_t* exists,
                    std::int8_t* st, std::ptrdiff_t m) { arm_ik_all<T>(arm, p, f, s, q_all, valid, exists, st, m); });
}

#define SPOTKIN_INSTANTIATE(T)                                                                                 \
  template void arm_fk<T>(const Arm&, const T*, T*, std::ptrdiff_t);                                           \
  template void arm_jacobian<T>(const Arm&, const T*, T*, std::ptrdiff_t);                                     \
  template void arm_ik_all<T>(const Arm&, const T*, PoseFormat, const T*, T*, std::uint8_t*, std::uint8_t*,    \
                              std::int8_t*, std::ptrdiff_t);                                                   \
  template void arm_ik<T>(const Arm&, const T*, PoseFormat, const T*, T*, std::int8_t*, std::ptrdiff_t);
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::kernels
