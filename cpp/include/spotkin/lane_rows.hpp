// A block's answers held by column (structure of arrays, a sample per lane) into rows of the
// output (a sample per row): 4 x 4 tiles transposed in registers. Used by the body's and the
// arm's IK kernels.
#pragma once

#include <cstddef>
#include <type_traits>

#include "spotkin/common.hpp"
#include "spotkin/dynamics/pack.hpp"

namespace spotkin {

// Four values from or to memory that T aliases, through a vector type that says so
// (memcpy into the packs became 16-byte copies through the stack, whose whole-vector reloads
// missed store forwarding). Overloads, not a template: a typedef's attributes do not survive
// being a template argument.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"  // always inlined: no vector crosses a call by value
#endif
SPOTKIN_INLINE dynamics::Pack<double, 4>::Vector load_four(const double* from) noexcept {
  typedef double Four __attribute__((vector_size(32), aligned(8), may_alias));
  return *reinterpret_cast<const Four*>(from);
}
SPOTKIN_INLINE dynamics::Pack<float, 4>::Vector load_four(const float* from) noexcept {
  typedef float Four __attribute__((vector_size(16), aligned(4), may_alias));
  return *reinterpret_cast<const Four*>(from);
}
SPOTKIN_INLINE void store_four(double* to, dynamics::Pack<double, 4>::Vector v) noexcept {
  typedef double Four __attribute__((vector_size(32), aligned(8), may_alias));
  *reinterpret_cast<Four*>(to) = v;
}
SPOTKIN_INLINE void store_four(float* to, dynamics::Pack<float, 4>::Vector v) noexcept {
  typedef float Four __attribute__((vector_size(16), aligned(4), may_alias));
  *reinterpret_cast<Four*>(to) = v;
}
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

// out[w i + c] = Q[c][i] for i < m, c < w: a block's answers, held by column, into rows of q.
// Groups of 4 columns of 4 targets transposed in registers (dynamics::transpose_lanes), the
// columns and targets left over one by one: moves only, the same bits. RegisterBytes: the
// register of the level that runs it (register_bytes). float64 at 16 bytes (SSE2) goes value by
// value: its 4-double tiles are register pairs there (Spot body_ik, 1e5 poses, one thread: 197 ->
// 170 ns a pose; the arm's ik_all 510 -> 400 ns).
template <int RegisterBytes, std::ptrdiff_t Block, typename T>
SPOTKIN_INLINE void transpose_rows(const T (*__restrict Q)[Block], int w, std::ptrdiff_t m,
                                   T* __restrict out) noexcept {
  if constexpr (std::is_same_v<T, double> && RegisterBytes < 32) {
    for (std::ptrdiff_t i = 0; i < m; ++i)
      for (int c = 0; c < w; ++c) out[i * w + c] = Q[c][i];
    return;
  }
  constexpr int L = 4;
  using V = typename dynamics::Pack<T, L>::Vector;
  const int grouped = w / L * L;
  std::ptrdiff_t i0 = 0;
  for (; i0 + L <= m; i0 += L)
    for (int c0 = 0; c0 < grouped; c0 += L) {
      V r[L];
      for (int k = 0; k < L; ++k) r[k] = load_four(&Q[c0 + k][i0]);
      dynamics::transpose_lanes<T, L>(r);
      for (int k = 0; k < L; ++k) store_four(out + (i0 + k) * w + c0, r[k]);
    }
  for (std::ptrdiff_t i = 0; i < m; ++i)
    for (int c = i < i0 ? grouped : 0; c < w; ++c) out[i * w + c] = Q[c][i];
}

}  // namespace spotkin
