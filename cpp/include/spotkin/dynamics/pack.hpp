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
