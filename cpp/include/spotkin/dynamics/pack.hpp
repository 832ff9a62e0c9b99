// Pack<T, L>: L samples of one quantity, the lane type of the dynamics kernels.
// The kernels are written once on a scalar type S; instantiated with S = Pack
// they run L samples side by side (structure of arrays), every operator a
// short loop over lanes that the compiler turns into vector instructions of
// the target clone it is inlined into. Model constants (inertias, axes) stay
// plain T and broadcast implicitly.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstring>
#include <utility>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::dynamics {

// GCC's vector extension: each operator is one vector instruction of the
// target clone the kernel is compiled for (split into narrower ones below it).
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"  // packs never cross a non-inlined call boundary by value
#endif
// The vector type of L values of T (GCC ignores vector_size on a dependent
// typedef, hence one specialisation per width).
template <typename T, int L>
struct VectorOf;
#define SPOTKIN_VECTOR_OF(T, L)                          \
  template <>                                            \
  struct VectorOf<T, L> {                                \
    typedef T type __attribute__((vector_size(sizeof(T) * L))); \
  };
SPOTKIN_VECTOR_OF(double, 2)
SPOTKIN_VECTOR_OF(double, 4)
SPOTKIN_VECTOR_OF(double, 8)
SPOTKIN_VECTOR_OF(double, 16)
SPOTKIN_VECTOR_OF(float, 4)
SPOTKIN_VECTOR_OF(float, 8)
SPOTKIN_VECTOR_OF(float, 16)
SPOTKIN_VECTOR_OF(float, 32)
#undef SPOTKIN_VECTOR_OF

// Aligned to its size explicitly: GCC gives a vector type wider than the
// target's registers a smaller alignment, and the std::vector code compiled for
// the baseline target would then allocate packs the AVX-512 clone loads with
// aligned moves.
template <typename T, int L>
struct alignas(sizeof(T) * L) Pack {
  static constexpr int kLanes = L;
  using Scalar = T;
  using Vector = typename VectorOf<T, L>::type;
  Vector v;

  Pack() = default;
  // Copies as one vector move: the implicit (trivial) copy lets GCC copy structs of packs by
  // pieces of the translation unit's baseline width (16 bytes) inside wider target clones, and a
  // pack stored in two halves then loaded whole stalls store forwarding.
  SPOTKIN_INLINE Pack(const Pack& o) noexcept : v(o.v) {}
  SPOTKIN_INLINE Pack& operator=(const Pack& o) noexcept {
    v = o.v;
    return *this;
  }
  SPOTKIN_INLINE Pack(T x) noexcept : v(Vector{} + x) {}  // NOLINT: implicit broadcast of constants
  SPOTKIN_INLINE explicit Pack(const Vector& x) noexcept : v(x) {}

#define SPOTKIN_PACK_OP(OP)                                                                                  \
  friend SPOTKIN_INLINE Pack operator OP(const Pack& a, const Pack& b) noexcept { return Pack(a.v OP b.v); }  \
  SPOTKIN_INLINE Pack& operator OP##=(const Pack& b) noexcept {                                               \
    v = v OP b.v;                                                                                             \
    return *this;                                                                                             \
  }
  SPOTKIN_PACK_OP(+)
  SPOTKIN_PACK_OP(-)
  SPOTKIN_PACK_OP(*)
  SPOTKIN_PACK_OP(/)
#undef SPOTKIN_PACK_OP

  friend SPOTKIN_INLINE Pack operator-(const Pack& a) noexcept { return Pack(-a.v); }
};

// Lane count of a scalar or a pack (1 for plain T).
template <typename S>
struct LanesOf {
  static constexpr int value = 1;
  using Scalar = S;
};
template <typename T, int L>
struct LanesOf<Pack<T, L>> {
  static constexpr int value = L;
  using Scalar = T;
};

// sin and cos of every lane (vector_math: about 1 ulp, huge arguments exact, NaN/Inf -> NaN).
template <typename T, int L>
SPOTKIN_INLINE void sincos(const Pack<T, L>& x, Pack<T, L>& s, Pack<T, L>& c) noexcept {
  T xs[L], ss[L], cs[L];
  std::memcpy(xs, &x.v, sizeof xs);
  vector_math::sincos(xs, ss, cs, L);
  std::memcpy(&s.v, ss, sizeof ss);
  std::memcpy(&c.v, cs, sizeof cs);
}
SPOTKIN_INLINE void sincos(double x, double& s, double& c) noexcept { vector_math::sincos(&x, &s, &c, 1); }
SPOTKIN_INLINE void sincos(float x, float& s, float& c) noexcept { vector_math::sincos(&x, &s, &c, 1); }

// The integer vector of a pack's width, for shuffle masks (one specialisation per
// width: GCC ignores vector_size on a dependent typedef).
template <typename M, int L>
struct MaskOf;
#define SPOTKIN_MASK_OF(M, I, L)                                  \
  template <>                                                     \
  struct MaskOf<M, L> {                                           \
    typedef I type __attribute__((vector_size(sizeof(I) * L)));   \
  };
SPOTKIN_MASK_OF(double, long long, 2)
SPOTKIN_MASK_OF(double, long long, 4)
SPOTKIN_MASK_OF(double, long long, 8)
SPOTKIN_MASK_OF(float, int, 4)
SPOTKIN_MASK_OF(float, int, 8)
SPOTKIN_MASK_OF(float, int, 16)
#undef SPOTKIN_MASK_OF

// Element e of a transpose stage's 2-input shuffle over blocks of B lanes: the low
// (Hi = false) or high half of each pair of blocks, from the first input (indices
// 0 .. L-1) then the second (L .. 2L-1).
template <int L, int B, bool Hi>
constexpr int transpose_index(int e) noexcept {
  const int group = e / (2 * B) * 2 * B, offset = e % (2 * B), half = Hi ? B : 0;
  return offset < B ? group + half + offset : L + group + half + offset - B;
}

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"  // always inlined: no vector crosses a call by value
#endif
template <typename M, int L, int B, bool Hi, typename V, std::size_t... E>
SPOTKIN_INLINE V transpose_shuffle(const V& a, const V& b, std::index_sequence<E...>) noexcept {
#if defined(__clang__)
  return __builtin_shufflevector(a, b, transpose_index<L, B, Hi>(int(E))...);
#else
  using I = typename MaskOf<M, L>::type;
  return __builtin_shuffle(a, b, I{transpose_index<L, B, Hi>(int(E))...});
#endif
}

// Transposes L packs of L lanes in registers (log2 L stages of 2-input shuffles, each
// a native shuffle of the level's registers): r[j] holds column j of L samples, on
// return r[i] holds sample i's L columns.
template <typename M, int L, int B = 1>
SPOTKIN_INLINE void transpose_lanes(typename Pack<M, L>::Vector r[L]) noexcept {
  if constexpr (B < L) {
    for (int k = 0; k < L; ++k) {
      if (k & B) continue;
      const auto lo = transpose_shuffle<M, L, B, false>(r[k], r[k + B], std::make_index_sequence<L>{});
      const auto hi = transpose_shuffle<M, L, B, true>(r[k], r[k + B], std::make_index_sequence<L>{});
      r[k] = lo, r[k + B] = hi;
    }
    transpose_lanes<M, L, 2 * B>(r);
  }
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

}  // namespace spotkin::dynamics

#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

// Eigen matrices of packs: the chain's per-joint transform code (Rigid<Scalar>,
// Joint<Scalar>) runs on Pack unchanged, coefficient by coefficient.
namespace Eigen {
template <typename T, int L>
struct NumTraits<spotkin::dynamics::Pack<T, L>> : NumTraits<T> {
  using Real = spotkin::dynamics::Pack<T, L>;
  using NonInteger = Real;
  using Nested = Real;
  using Literal = T;
  enum { IsComplex = 0, IsInteger = 0, IsSigned = 1, RequireInitialization = 0, ReadCost = 1, AddCost = 1, MulCost = 1 };
};
}  // namespace Eigen
