// The whole body's batch kernels (spotkin/kernels/body.hpp), one clone per
// instruction-set level, for float and double.
#include "spotkin/kernels/body.hpp"

#include "spotkin/isa.hpp"

namespace spotkin::kernels {

SPOTKIN_CLONES((template <typename T>), void, body_ik,
               (const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq,
                const T* feet, bool feet_shared, const T* seed, T* q, std::int8_t* status,
                std::ptrdiff_t n, bool nearest_fallback),
               (body, poses, format, seq, feet, feet_shared, seed, q, status, n, nearest_fallback),
               body_batch::ik<register_bytes(kIsa)>(body, poses, format, seq, feet, feet_shared,
                                                    seed, q, status, n, nearest_fallback);)
SPOTKIN_CLONES((template <typename T>), void, body_ik_path,
               (const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq,
                const T* feet, const T* seed, T* q, std::int8_t* status, std::ptrdiff_t n,
                bool nearest_fallback),
               (body, poses, format, seq, feet, seed, q, status, n, nearest_fallback),
               body_batch::ik_path(body, poses, format, seq, feet, seed, q, status, n,
                                   nearest_fallback);)
SPOTKIN_CLONES((template <typename T>), void, body_fk,
               (const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq, const T* q, T* feet,
                std::ptrdiff_t n),
               (body, poses, format, seq, q, feet, n),
  body_batch::fk(body, poses, format, seq, q, feet, n);
)
SPOTKIN_CLONES((template <typename T>), void, body_jacobian,
               (const Body& body, const T* poses, BodyPoseFormat format, const EulerSequence& seq, const T* q, T* J,
                std::ptrdiff_t n),
               (body, poses, format, seq, q, J, n),
  body_batch::jacobian(body, poses, format, seq, q, J, n);
)

#define SPOTKIN_INSTANTIATE(T)                                                                    \
  template void body_ik<T>(const Body&, const T*, BodyPoseFormat, const EulerSequence&, const T*, \
                           bool, const T*, T*, std::int8_t*, std::ptrdiff_t, bool);               \
  template void body_ik_path<T>(const Body&, const T*, BodyPoseFormat, const EulerSequence&,      \
                                const T*, const T*, T*, std::int8_t*, std::ptrdiff_t, bool);      \
  template void body_fk<T>(const Body&, const T*, BodyPoseFormat, const EulerSequence&, const T*, \
                           T*, std::ptrdiff_t);                                                   \
  template void body_jacobian<T>(const Body&, const T*, BodyPoseFormat, const EulerSequence&,     \
                                 const T*, T*, std::ptrdiff_t);
SPOTKIN_INSTANTIATE(float)
SPOTKIN_INSTANTIATE(double)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::kernels
