// Pack<T, L>: L samples of one quantity, the lane type of the dynamics kernels.
// The kernels are written once on a scalar type S; instantiated with S = Pack
// they run L samples side by side (structure of arrays), every operator a
// short loop over lanes that the compiler turns into vector instructions of
// the target clone it is inlined into. Model constants (inertias, axes) stay
// plain T and broadcast implicitly.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::dynamics {

template <typename T, int L>
struct Pack {
  static constexpr int kLanes = L;
  using Scalar = T;
  T v[L];

  Pack() = default;
  SPOTKIN_INLINE Pack(T x) noexcept {  // NOLINT: implicit broadcast of constants
    for (int i = 0; i < L; ++i) v[i] = x;
  }

#define SPOTKIN_PACK_OP(OP)                                                            \
  friend SPOTKIN_INLINE Pack operator OP(Pack a, const Pack& b) noexcept {              \
    for (int i = 0; i < L; ++i) a.v[i] = a.v[i] OP b.v[i];                              \
    return a;                                                                           \
  }                                                                                     \
  SPOTKIN_INLINE Pack& operator OP##=(const Pack& b) noexcept {                         \
    for (int i = 0; i < L; ++i) v[i] = v[i] OP b.v[i];                                  \
    return *this;                                                                       \
  }
  SPOTKIN_PACK_OP(+)
  SPOTKIN_PACK_OP(-)
  SPOTKIN_PACK_OP(*)
  SPOTKIN_PACK_OP(/)
#undef SPOTKIN_PACK_OP

  friend SPOTKIN_INLINE Pack operator-(Pack a) noexcept {
    for (int i = 0; i < L; ++i) a.v[i] = -a.v[i];
    return a;
  }
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

template <typename T>
SPOTKIN_INLINE T& lane(T& x, int) noexcept { return x; }
template <typename T, int L>
SPOTKIN_INLINE T& lane(Pack<T, L>& x, int i) noexcept { return x.v[i]; }
template <typename T>
SPOTKIN_INLINE T lane(const T& x, int) noexcept { return x; }
template <typename T, int L>
SPOTKIN_INLINE T lane(const Pack<T, L>& x, int i) noexcept { return x.v[i]; }

template <typename T, int L>
SPOTKIN_INLINE Pack<T, L> sqrt(Pack<T, L> x) noexcept {
  for (int i = 0; i < L; ++i) x.v[i] = std::sqrt(x.v[i]);
  return x;
}

// sin and cos of every lane (vector_math: about 1 ulp, huge arguments exact, NaN/Inf -> NaN).
template <typename T, int L>
SPOTKIN_INLINE void sincos(const Pack<T, L>& x, Pack<T, L>& s, Pack<T, L>& c) noexcept {
  vector_math::sincos(x.v, s.v, c.v, L);
}
SPOTKIN_INLINE void sincos(double x, double& s, double& c) noexcept { vector_math::sincos(&x, &s, &c, 1); }
SPOTKIN_INLINE void sincos(float x, float& s, float& c) noexcept { vector_math::sincos(&x, &s, &c, 1); }

}  // namespace spotkin::dynamics

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
