// Elementary functions over arrays of samples, written so the compiler
// vectorises the loops (plain arithmetic, selects and bit operations; no calls,
// no branches).
//
// sincos: Cody-Waite reduction by pi/2 in three 33-bit parts (fdlibm's
// pio2_1..3), r + tail with r's rounding error kept, then fdlibm's
// __kernel_sin / __kernel_cos of (r, tail) on [-pi/4, pi/4]; the quadrant
// k mod 4 chooses and signs them by floating selects (64-bit integer masks
// would stop GCC vectorising the kernels at SSE2).
// Measured: 0.9 ulp at most for |x| < kReducibleLimit; near a zero of sin or
// cos the error is absolute, below 1.1 (ulp + |x| eps^2). Arguments beyond
// kReducibleLimit, where the three-part reduction loses bits, are recomputed
// with std::sin / std::cos. NaN and Inf give NaN, as std::sin does.
//
// atan2: the ratio of min(|x|, |y|) to max(|x|, |y|) is in [0, 1]; above 1/2
// it is reduced by pi/4, t = (lo - hi) / (lo + hi), else t = lo / hi: one
// division, t in [-1/3, 1/2]. atan(t) = t + t z P(z), z = t^2, P of degree 11
// (Remez, relative error 2^-57.6) by Estrin's scheme; the octant's multiple of
// pi/4 (high part exact, low part separate) is added with its rounding error
// carried. Measured: 1.6 ulp at most (the division's rounding of t dominates).
// Zeros and infinities as std::atan2, except atan2(+-Inf, +-Inf): NaN, not an
// odd multiple of pi/4. Where lo + hi overflows (ratio above 1/2, max(|x|, |y|)
// above DBL_MAX / 2) the result is a multiple of pi/4, wrong; NaN propagates.
// acos(x) = atan2(sqrt((1 - x)(1 + x)), x).
//
// float overloads, for the float32 kernels (twice the lanes per vector): sincos
// by Cody-Waite in three float parts of pi/2, Cephes' sinf / cosf polynomials
// and the quadrant from the low mantissa bits of x * 2/pi + 1.5 * 2^23 by 32-bit
// integer masks (1.6 ulp at most; beyond kReducibleLimitFloat,
// std::sin / std::cos in double); atan2 as above with P of degree 4 (Remez,
// 2^-27.5), 1.6 ulp at most.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#if defined(__GNUC__)
#define SPOTKIN_VM_INLINE inline __attribute__((always_inline))
#else
#define SPOTKIN_VM_INLINE inline
#endif
#if defined(__has_builtin)
#if __has_builtin(__builtin_bit_cast)
#define SPOTKIN_VM_BUILTIN_BIT_CAST 1
#endif
#endif

namespace spotkin::vector_math {

constexpr double kReducibleLimit = 1.0e5;

namespace detail {
// The bits of a double or float, and back: memcpy, or __builtin_bit_cast where
// the compiler has it; either vectorises to no instruction at all.
template <typename To, typename From>
SPOTKIN_VM_INLINE To bit_cast(const From& from) noexcept {
  static_assert(sizeof(To) == sizeof(From), "bit_cast between types of one size");
#ifdef SPOTKIN_VM_BUILTIN_BIT_CAST
  return __builtin_bit_cast(To, from);
#else
  To to;
  std::memcpy(&to, &from, sizeof to);
  return to;
#endif
}

// a with its sign flipped where the sign bit of s is set (s = +-0 or any value): a multiply
// by +-1, exact. (Integer XOR on the bits would be one instruction, but with 64-bit integer
// operations in a loop GCC stops vectorising the kernels that inline this at SSE2.)
SPOTKIN_VM_INLINE double flip_sign(double a, double s) noexcept { return a * std::copysign(1.0, s); }
SPOTKIN_VM_INLINE float flip_sign(float a, float s) noexcept { return a * std::copysign(1.0f, s); }

constexpr double kTwoOverPi = 6.36619772367581382433e-01;
constexpr double kPio2_1 = 1.57079632673412561417e+00;
constexpr double kPio2_2 = 6.07710050630396597660e-11;
constexpr double kPio2_3 = 2.02226624871116645580e-21;
// Round to nearest integer without a libm call: valid for |x| < 2^51.
constexpr double kRoundMagic = 6755399441055744.0;  // 1.5 * 2^52

// fdlibm's __kernel_sin and __kernel_cos of x + y, to first order in the small correction y
SPOTKIN_VM_INLINE double kernel_sin(double x, double y) noexcept {
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  const double z = x * x;
  const double r = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
  const double v = z * x;
  return x - ((z * (0.5 * y - v * r) - y) - v * S1);  // x + v (S1 + z r) + y (1 - z/2)
}

SPOTKIN_VM_INLINE double kernel_cos(double x, double y) noexcept {
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double z = x * x;
  const double r = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
  const double hz = 0.5 * z;
  const double w = 1.0 - hz;
  return w + (((1.0 - w) - hz) + (z * r - x * y));  // compensated 1 - z/2 + z^2 r - x y
}
}  // namespace detail

// sin and cos of one bounded argument (|x| < kReducibleLimit), for use inside
// loops the compiler vectorises.
SPOTKIN_VM_INLINE void sincos_bounded(double x, double& s, double& c) noexcept {
  using namespace detail;
  const double k = (x * kTwoOverPi + kRoundMagic) - kRoundMagic;  // x * 2/pi rounded
  // x - k pi/2 = r + tail: k P1, k P2 and k P3 are exact (33-bit parts, |k| < 2^20), and so is
  // x - k P1 (Sterbenz)
  const double head = x - k * kPio2_1, w = k * kPio2_2;
  const double r = head - w;
  const double tail = ((head - r) - w) - k * kPio2_3;  // r's rounding error, then the third part
  const double sr = kernel_sin(r, tail), cr = kernel_cos(r, tail);
  // The quadrant q = k mod 4 by floating selects (integer masks on the bits of shifted would be
  // fewer instructions, but 64-bit integer operations stop GCC vectorising the kernels at SSE2).
  const double k4 = k * 0.25;
  double floor_k4 = (k4 + kRoundMagic) - kRoundMagic;
  floor_k4 -= floor_k4 > k4 ? 1.0 : 0.0;
  const double q = k - 4.0 * floor_k4;
  const bool odd = q == 1.0 || q == 3.0;
  const double sin_abs = odd ? cr : sr, cos_abs = odd ? sr : cr;
  s = q >= 2.0 ? -sin_abs : sin_abs;                 // negative in quadrants 2, 3
  c = q == 1.0 || q == 2.0 ? -cos_abs : cos_abs;     // negative in quadrants 1, 2
}

// Whether some |x[i]| > limit, or some x[i] is NaN: one vector compare and OR per register,
// no branch per element. Not unrolled: where n is a small constant (a block of 16 lanes) GCC
// unrolled the loop completely before the vectoriser ran, and the ORed compares stayed
// scalar (perf: 16 scalar compares per sincos of a block in the float chain FK at AVX-512).
template <typename S>
SPOTKIN_VM_INLINE bool any_beyond(const S* x, std::ptrdiff_t n, S limit) noexcept {
  int beyond = 0;
#pragma GCC unroll 1
  for (std::ptrdiff_t i = 0; i < n; ++i) beyond |= !(std::fabs(x[i]) <= limit);
  return beyond != 0;
}

// s[i], c[i] = sin(x[i]), cos(x[i]) for i < n.
SPOTKIN_VM_INLINE void sincos(const double* x, double* s, double* c, std::ptrdiff_t n) noexcept {
  using namespace detail;
  for (std::ptrdiff_t i = 0; i < n; ++i) sincos_bounded(x[i], s[i], c[i]);
  if (!any_beyond(x, n, kReducibleLimit)) return;  // a vector test first: the fix-up is rare
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    if (std::fabs(x[i]) > kReducibleLimit) {  // rare; also catches +-Inf (NaN either way)
      s[i] = std::sin(x[i]);
      c[i] = std::cos(x[i]);
    }
  }
}

constexpr float kReducibleLimitFloat = 8192.0f;

// sin and cos of one float argument, |x| < kReducibleLimitFloat.
SPOTKIN_VM_INLINE void sincos_bounded(float x, float& s, float& c) noexcept {
  using detail::bit_cast;
  // pi/2 = P1 + P2 + P3, P1 and P2 with few enough bits that k * P1, k * P2 are exact
  constexpr float kTwoOverPi = 0.636619772367581f, P1 = 1.5703125f, P2 = 4.837512969970703125e-4f,
                  P3 = 7.54978995489188216e-8f, kRoundMagic = 12582912.0f;  // 1.5 * 2^23
  const float shifted = x * kTwoOverPi + kRoundMagic;  // 1.5 * 2^23 + k
  const float k = shifted - kRoundMagic;
  const float r = ((x - k * P1) - k * P2) - k * P3;
  const float z = r * r;
  const float sr = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
  const float cr = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z -
                   0.5f * z + 1.0f;
  const std::uint32_t q = bit_cast<std::uint32_t>(shifted);  // k mod 4 in the low two bits
  const std::uint32_t sb = bit_cast<std::uint32_t>(sr), cb = bit_cast<std::uint32_t>(cr);
  const std::uint32_t swap = (sb ^ cb) & (0 - (q & 1));
  s = bit_cast<float>((sb ^ swap) ^ ((q & 2) << 30));
  c = bit_cast<float>((cb ^ swap) ^ (((q + 1) & 2) << 30));
}

SPOTKIN_VM_INLINE void sincos(const float* x, float* s, float* c, std::ptrdiff_t n) noexcept {
  for (std::ptrdiff_t i = 0; i < n; ++i) sincos_bounded(x[i], s[i], c[i]);
  if (!any_beyond(x, n, kReducibleLimitFloat)) return;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    if (std::fabs(x[i]) > kReducibleLimitFloat) {  // rare; also catches +-Inf (NaN either way)
      s[i] = float(std::sin(double(x[i])));
      c[i] = float(std::cos(double(x[i])));
    }
  }
}

// An angle beyond kReducibleLimit brought into [-pi, pi] with libm's exact
// (Payne-Hanek) reduction inside sin and cos; smaller ones are returned as they
// are. Kernels sum angles (hy + kn) before their sincos, and a sum of huge
// angles has lost its fraction: the bindings reduce such inputs first.
inline double reduce_huge_angle(double x) noexcept {
  return std::fabs(x) > kReducibleLimit && std::isfinite(x) ? std::atan2(std::sin(x), std::cos(x)) : x;
}

namespace detail {
// atan(t) = t + t z P(z) for z = t^2 <= 1/4: P of degree 11, fitted by Remez
// (relative error 2^-57.6 with the coefficients rounded); Estrin's scheme.
SPOTKIN_VM_INLINE double atan_p(double z) noexcept {
  constexpr double A0 = -0x1.5555555555516p-2, A1 = 0x1.999999999113bp-3, A2 = -0x1.249249215da9dp-3,
                   A3 = 0x1.c71c7090d1600p-4, A4 = -0x1.745cf4c8ab165p-4, A5 = 0x1.3b113d967de29p-4,
                   A6 = -0x1.10f31d534ffeep-4, A7 = 0x1.dfe95eb58a419p-5, A8 = -0x1.a397f2b2b7078p-5,
                   A9 = 0x1.56f479f785db9p-5, A10 = -0x1.c17b91292cab5p-6, A11 = 0x1.4b7dfdb9212c5p-7;
  const double z2 = z * z, z4 = z2 * z2, z8 = z4 * z4;
  const double a = (A0 + A1 * z) + (A2 + A3 * z) * z2, b = (A4 + A5 * z) + (A6 + A7 * z) * z2,
               c = (A8 + A9 * z) + (A10 + A11 * z) * z2;
  return a + b * z4 + c * z8;
}
}  // namespace detail

// atan2(y, x) for one pair; finite inputs (NaN propagates).
SPOTKIN_VM_INLINE double atan2(double y, double x) noexcept {
  using detail::flip_sign;
  // pi/4 = kPio4 + kPio4 * kLoOverHi; kPio4 ends in three zero bits: its multiples to pi are exact
  constexpr double kPio4 = 0x1.921fb54442d18p-1, kPio2 = 2 * kPio4;
  constexpr double kLoOverHi = 0x1.678afae35cdd1p-55;
  const double ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  const double hi = steep ? ay : ax, lo = steep ? ax : ay;
  // above 1/2, atan(lo/hi) = pi/4 + atan(t) with t = (lo - hi)/(lo + hi), where lo - hi is exact
  const bool reduce = lo + lo > hi;  // (lo + lo is exact, unlike 0.5 * hi for subnormals)
  const double num = reduce ? lo - hi : lo;
  double den = reduce ? lo + hi : hi;
  den = den == 0.0 ? 1.0 : den;  // 0/0 -> 0; a NaN stays
  const double t = num / den;    // in [-1/3, 1/2]
  // The angle in [0, pi] is corner +- (pi/4 if reduce) +- atan(t), subtracted when steep xor x < 0
  // (masks from floating compares and sign bits only: SSE2 has no 64-bit integer compare).
  const double x_sign = std::copysign(0.0, x);       // -0 for x < 0 and x = -0: atan2(0, -0) = pi
  const double flip = steep ? -x_sign : x_sign;       // -0: subtract
  const double corner = steep ? kPio2 : kPio2 - std::copysign(kPio2, x);  // 0, pi/2 or pi
  const double base = corner + flip_sign(reduce ? kPio4 : 0.0, flip);   // exact
  const double u = flip_sign(t, flip);
  const double z = t * t;
  const double sum = base + u;
  const double err = (base - sum) + u;  // sum's rounding error (|base| >= |u| or base = 0)
  const double a = sum + (err + (u * z * detail::atan_p(z) + base * kLoOverHi));
  return std::copysign(a, y);
}

// acos(x) for x in [-1, 1]; NaN outside.
SPOTKIN_VM_INLINE double acos(double x) noexcept {
  return vector_math::atan2(std::sqrt((1.0 - x) * (1.0 + x)), x);
}

// atan2(y, x) for one float pair (NaN propagates); as the double one, with P of
// degree 4 (5 coefficients, relative error 2^-27.5).
SPOTKIN_VM_INLINE float atan2(float y, float x) noexcept {
  using detail::flip_sign;
  // pi/4 = kPio4 + kPio4 * kLoOverHi; kPio4 ends in two zero bits: its multiples to pi are exact
  constexpr float kPio4 = 0x1.921fb8p-1f, kPio2 = 2 * kPio4, kLoOverHi = -0x1.bd77b6p-24f;
  const float ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  const float hi = steep ? ay : ax, lo = steep ? ax : ay;
  const bool reduce = lo + lo > hi;
  const float num = reduce ? lo - hi : lo;
  float den = reduce ? lo + hi : hi;
  den = den == 0.0f ? 1.0f : den;  // 0/0 -> 0; a NaN stays
  const float t = num / den;
  const float x_sign = std::copysign(0.0f, x);
  const float flip = steep ? -x_sign : x_sign;
  const float corner = steep ? kPio2 : kPio2 - std::copysign(kPio2, x);
  const float base = corner + flip_sign(reduce ? kPio4 : 0.0f, flip);
  const float u = flip_sign(t, flip);
  const float z = t * t;
  const float p = (((-0x1.a3da84p-5f * z + 0x1.9ffb94p-4f) * z - 0x1.2249b2p-3f) * z + 0x1.997b06p-3f) * z -
                  0x1.555512p-2f;
  const float sum = base + u;
  const float err = (base - sum) + u;
  const float a = sum + (err + (u * z * p + base * kLoOverHi));
  return std::copysign(a, y);
}

SPOTKIN_VM_INLINE float acos(float x) noexcept {
  return vector_math::atan2(std::sqrt((1.0f - x) * (1.0f + x)), x);
}

}  // namespace spotkin::vector_math
