// The fixed-base chain's dynamics kernels (spotkin/dynamics/kernels.hpp): one clone per
// lane width, each at the instruction-set level whose registers the width fills, in float
// and double. The floating base's are in dynamics_floating_kernels.cpp.
#include "spotkin/dynamics/kernels.hpp"

#include "spotkin/dynamics/batch.hpp"
#include "lane_clones.hpp"

namespace spotkin::dynamics {

SPOTKIN_LANE_CLONES(rnea_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, const NonDeduced<Rows<T>>* qd, const NonDeduced<Rows<T>>* qdd, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e), (m, q, qd, qdd, g, out, b, e),
               rnea_batch(m, q, qd, qdd, g, out, b, e);)
SPOTKIN_LANE_CLONES(crba_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, std::ptrdiff_t b, std::ptrdiff_t e, SymmetricLayout layout), (m, q, out, b, e, layout),
               crba_batch(m, q, out, b, e, layout);)
SPOTKIN_LANE_CLONES(coriolis_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> qd, T* out, std::ptrdiff_t b, std::ptrdiff_t e), (m, q, qd, out, b, e),
               coriolis_batch(m, q, qd, out, b, e);)
SPOTKIN_LANE_CLONES(aba_k, (const ChainModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> qd, NonDeduced<Rows<T>> tau, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e), (m, q, qd, tau, g, out, b, e),
               aba_batch(m, q, qd, tau, g, out, b, e);)

#define SPOTKIN_INSTANTIATE(T, L)                                                                                  \
  template void rnea_k<T, L>(const ChainModel<T, L>&, Rows<T>, const Rows<T>*, const Rows<T>*, Rows<T>, T*,       \
                             std::ptrdiff_t, std::ptrdiff_t);                                                      \
  template void crba_k<T, L>(const ChainModel<T, L>&, Rows<T>, T*, std::ptrdiff_t, std::ptrdiff_t,                 \
                             SymmetricLayout);                                                                     \
  template void coriolis_k<T, L>(const ChainModel<T, L>&, Rows<T>, Rows<T>, T*, std::ptrdiff_t, std::ptrdiff_t);   \
  template void aba_k<T, L>(const ChainModel<T, L>&, Rows<T>, Rows<T>, Rows<T>, Rows<T>, T*, std::ptrdiff_t,       \
                            std::ptrdiff_t);
SPOTKIN_FOR_EACH_LANE_MODEL(SPOTKIN_INSTANTIATE)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::dynamics
