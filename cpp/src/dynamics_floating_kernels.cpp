// The floating base's dynamics kernels (spotkin/dynamics/kernels.hpp): one clone per lane
// width, each at the instruction-set level whose registers the width fills, in float and
// double.
#include "spotkin/dynamics/kernels.hpp"

#include "lane_clones.hpp"

namespace spotkin::dynamics {

SPOTKIN_LANE_CLONES(floating_rnea_k, (const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, const NonDeduced<Rows<T>>* v, const NonDeduced<Rows<T>>* a, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, v, a, g, out, b, e, stream),
               floating_rnea_batch(m, q, v, a, g, out, b, e, stream);)
SPOTKIN_LANE_CLONES(floating_crba_k, (const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream, SymmetricLayout layout), (m, q, out, b, e, stream, layout),
               floating_crba_batch(m, q, out, b, e, stream, layout);)
SPOTKIN_LANE_CLONES(floating_aba_k, (const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> v, NonDeduced<Rows<T>> tau, NonDeduced<Rows<T>> g, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, v, tau, g, out, b, e, stream),
               floating_aba_batch(m, q, v, tau, g, out, b, e, stream);)
SPOTKIN_LANE_CLONES(floating_coriolis_k, (const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, NonDeduced<Rows<T>> v, T* out, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, v, out, b, e, stream),
               floating_coriolis_batch(m, q, v, out, b, e, stream);)
SPOTKIN_LANE_CLONES(floating_com_k, (const FloatingModel<T, L>& m, NonDeduced<Rows<T>> q, T* out, bool jacobian, std::ptrdiff_t b, std::ptrdiff_t e, bool stream), (m, q, out, jacobian, b, e, stream),
               floating_com_batch(m, q, out, jacobian, b, e, stream);)

#define SPOTKIN_INSTANTIATE(T, L)                                                                                \
  template void floating_rnea_k<T, L>(const FloatingModel<T, L>&, Rows<T>, const Rows<T>*, const Rows<T>*,       \
                                      Rows<T>, T*, std::ptrdiff_t, std::ptrdiff_t, bool);                              \
  template void floating_crba_k<T, L>(const FloatingModel<T, L>&, Rows<T>, T*, std::ptrdiff_t, std::ptrdiff_t, bool,   \
                                      SymmetricLayout);                                                          \
  template void floating_aba_k<T, L>(const FloatingModel<T, L>&, Rows<T>, Rows<T>, Rows<T>, Rows<T>, T*,         \
                                     std::ptrdiff_t, std::ptrdiff_t, bool);                                            \
  template void floating_coriolis_k<T, L>(const FloatingModel<T, L>&, Rows<T>, Rows<T>, T*, std::ptrdiff_t,      \
                                          std::ptrdiff_t, bool);                                                       \
  template void floating_com_k<T, L>(const FloatingModel<T, L>&, Rows<T>, T*, bool, std::ptrdiff_t,              \
                                     std::ptrdiff_t, bool);
SPOTKIN_FOR_EACH_LANE_MODEL(SPOTKIN_INSTANTIATE)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::dynamics
