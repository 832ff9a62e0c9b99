// The leg's batch kernels (spotkin/kernels/leg.hpp), one clone per instruction-set
// level, for float and double.
#include "spotkin/kernels/leg.hpp"

#include "spotkin/isa.hpp"

namespace spotkin::kernels {

SPOTKIN_CLONES((template <typename T>), void, leg_fk, (const Leg& leg, const T* q, T* p, std::ptrdiff_t n),
               (leg, q, p, n),
  leg_batch::fk(leg, q, p, n);
)
SPOTKIN_CLONES((template <typename T>), void, leg_jacobian, (const Leg& leg, const T* q, T* J, std::ptrdiff_t n),
               (leg, q, J, n),
  leg_batch::jacobian(leg, q, J, n);
)
SPOTKIN_CLONES((template <typename T>), void, leg_ik,
               (const Leg& leg, const T* p, const T* seed, T* q, std::int8_t* status,
                std::ptrdiff_t n, bool nearest_fallback),
               (leg, p, seed, q, status, n, nearest_fallback),
               leg_batch::ik<register_bytes(kIsa)>(leg, p, seed, q, status, n, nearest_fallback);)
SPOTKIN_CLONES((template <typename T>), void, leg_ik_all,
               (const Leg& leg, const T* p, T* q, std::uint8_t* valid, std::uint8_t* exists, std::int8_t* status,
                std::ptrdiff_t n),
               (leg, p, q, valid, exists, status, n),
  leg_batch::ik_all(leg, p, q, valid, exists, status, n);
)

#define SPOTKIN_INSTANTIATE(T)                                                                                    \
  template void leg_fk<T>(const Leg&, const T*, T*, std::ptrdiff_t);                                              \
  template void leg_jacobian<T>(const Leg&, const T*, T*, std::ptrdiff_t);                                        \
  template void leg_ik<T>(const Leg&, const T*, const T*, T*, std::int8_t*, std::ptrdiff_t, bool);                \
  template void leg_ik_all<T>(const Leg&, const T*, T*, std::uint8_t*, std::uint8_t*, std::int8_t*, std::ptrdiff_t);
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::kernels
