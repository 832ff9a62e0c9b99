// Shared types: statuses, rigid transforms as (R, p) pairs, angle helpers.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>

#include "spotkin/isa.hpp"

// Forces inlining of the per-sample kernels into the batch loops, so that every
// run-time dispatched clone of a loop gets its own vector code.
#if defined(__GNUC__)
#define SPOTKIN_INLINE inline __attribute__((always_inline))
// For a lambda in a kernel: `[&](int i) SPOTKIN_LAMBDA_INLINE { ... }`. A lambda does not take
// its enclosing function's target attribute: one too large for the inliner's heuristics would be
// compiled (and called) at the baseline instruction set, with its packs passed through memory.
#define SPOTKIN_LAMBDA_INLINE __attribute__((always_inline))
#else
#define SPOTKIN_INLINE inline
#define SPOTKIN_LAMBDA_INLINE
#endif

// Run-time dispatched kernels: SPOTKIN_CLONES in isa.hpp. A vectorised kernel that must not
// be inlined (inlining drops its __restrict guarantees and with them the vectorisation) is
// declared there with __attribute__((noinline)).

// A scalar routine called once per sample from a vector kernel: kept out of the kernel's
// target clones so that its own callees (Eigen's fixed-size products) inline into it.
#if defined(__GNUC__)
#define SPOTKIN_SCALAR_PATH __attribute__((noinline))
#else
#define SPOTKIN_SCALAR_PATH
#endif

namespace spotkin {

// One status per target; mirrored by the Python IntEnum `spotkin.Status`.
enum class Status : std::int8_t {
  Ok = 0,
  Unreachable = 1,
  JointLimit = 2,
  InvalidInput = 3,
};

template <typename Scalar>
using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
template <typename Scalar>
using Mat3 = Eigen::Matrix<Scalar, 3, 3>;

// A rigid transform kept as rotation + translation; cheaper than a 4x4 product.
template <typename Scalar>
struct Rigid {
  Mat3<Scalar> R = Mat3<Scalar>::Identity();
  Vec3<Scalar> p = Vec3<Scalar>::Zero();

  // lazyProduct: coefficient-wise products that inline into vectorised loops
  SPOTKIN_INLINE Rigid operator*(const Rigid& other) const noexcept {
    return {R.lazyProduct(other.R), R.lazyProduct(other.p) + p};
  }

  template <typename Other>
  Rigid<Other> cast() const noexcept {
    return {R.template cast<Other>(), p.template cast<Other>()};
  }
};

// Writes X as a row-major 4x4 homogeneous matrix.
template <typename Scalar>
SPOTKIN_INLINE void write_homogeneous(const Rigid<Scalar>& X, Scalar* out) noexcept {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out[4 * i + j] = X.R(i, j);
    out[4 * i + 3] = X.p[i];
  }
  out[12] = out[13] = out[14] = Scalar(0);
  out[15] = Scalar(1);
}

template <typename Scalar>
constexpr Scalar kPi = Scalar(3.14159265358979323846264338327950288);

template <typename Scalar>
constexpr Scalar quiet_nan() noexcept {
  return std::numeric_limits<Scalar>::quiet_NaN();
}

// std::remainder(a, 2 pi), bit for bit, in [-pi, pi]. For |a| < 3 pi, one
// subtraction of 2 pi at most, which is exact there (Sterbenz: pi <= |a| <= 4 pi),
// so the library call (tens of ns) is left for large angles, NaN and Inf.
template <typename Scalar>
SPOTKIN_INLINE Scalar remainder_two_pi(Scalar a) noexcept {
  constexpr Scalar pi = kPi<Scalar>, two_pi = Scalar(2) * kPi<Scalar>;
  if (!(std::fabs(a) < Scalar(3) * pi)) return std::remainder(a, two_pi);
  return a > pi ? a - two_pi : (a < -pi ? -(-a - two_pi) : a);  // -(-a - 2 pi): -0 at -2 pi, as std::remainder
}

// Wrap an angle into (-pi, pi].
template <typename Scalar>
SPOTKIN_INLINE Scalar wrap_angle(Scalar a) noexcept {
  const Scalar w = remainder_two_pi(a);  // in [-pi, pi]
  return w <= -kPi<Scalar> ? w + Scalar(2) * kPi<Scalar> : w;
}

}  // namespace spotkin
