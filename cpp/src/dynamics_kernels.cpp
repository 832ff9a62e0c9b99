// The fixed-base chain's dynamics kernels (spotkin/dynamics/kernels.hpp): one clone per
// lane width, each at the instruction-set level whose registers the width fills, in float
// and double. The floating base's are in dynamics_floating_kernels.cpp.
#include "spotkin/dynamics/kernels.hpp"

#include "spotkin/dynamics/batch.hpp"
#include "lane_clones.hpp"

namespace spotkin::dynamics {

SPOTKIN_LANE_CLONES(rnea_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, const NonDeduced<Rows<T>>* qd, const NonDeduced<Rows<T>>* qdd, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, qd, qdd, g, out, b, e, stream),
               rnea_batch(m, q, qd, qdd, g, out, b, e, stream);)
SPOTKIN_LANE_CLONES(crba_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream, SymmetricLayout layout), (m, q, out, b, e, stream, layout),
               crba_batch(m, q, out, b, e, stream, layout);)
SPOTKIN_LANE_CLONES(coriolis_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> qd, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, qd, out, b, e, stream),
               coriolis_batch(m, q, qd, out, b, e, stream);)
SPOTKIN_LANE_CLONES(aba_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> qd, NonDeduced<Rows<T>> tau, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, qd, tau, g, out, b, e, stream),
               aba_batch(m, q, qd, tau, g, out, b, e, stream);)

#define SPOTKIN_INSTANTIATE(T, L)                                                                                  \
  template void rnea_k<T, L>(const ChainModel<T, L>&, Rows<T>, const Rows<T>*, const Rows<T>*, Rows<T>, T*,       \
                             std::ptrdiff_t, std::ptrdiff_t, bool);                                                      \
  template void crba_k<T, L>(const ChainModel<T, L>&, Rows<T>, T*, std::ptrdiff_t, std::ptrdiff_t, bool,                 \
                             SymmetricLayout);                                                                     \
  template void coriolis_k<T, L>(const ChainModel<T, L>&, Rows<T>, Rows<T>, T*, std::ptrdiff_t, std::ptrdiff_t, bool);   \
  template void aba_k<T, L>(const ChainModel<T, L>&, Rows<T>, Rows<T>, Rows<T>, Rows<T>, T*, std::ptrdiff_t,       \
                            std::ptrdiff_t, bool);
SPOTKIN_FOR_EACH_LANE_MODEL(SPOTKIN_INSTANTIATE)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::dynamics
