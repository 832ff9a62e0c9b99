// Elementary functions over arrays of samples, written so the compiler
// vectorises the loops (plain arithmetic and selects, no calls, no branches).
//
// sincos: Cody-Waite reduction by pi/2 in three parts (fdlibm's pio2_1..3),
// then fdlibm's __kernel_sin / __kernel_cos polynomials on [-pi/4, pi/4];
// about 1 ulp. Arguments beyond kReducibleLimit, where the three-part
// reduction loses bits, are recomputed with std::sin/std::cos. NaN and Inf give
// NaN, as std::sin does.
//
// atan2: Cephes' atan rational approximation on [0, 0.66] and on the range
// reduced by pi/4 for [0.66, 1] (the ratio min/max is in [0, 1]), then the
// octant by selects; about 1 ulp. acos(x) = atan2(sqrt((1 - x)(1 + x)), x).
//
// float overloads, for the float32 kernels (twice the lanes per vector):
// sincos by Cody-Waite in three float parts of pi/2 and Cephes' sinf / cosf
// polynomials (about 1 ulp; beyond kReducibleLimitFloat, std::sin / std::cos in
// double); atan2 by Cephes' atanf polynomial on [0, tan(pi/8)] and on the range
// reduced by pi/4 above it, one division (about 2 ulp).
#pragma once

#include <cmath>
#include <cstddef>

#if defined(__GNUC__)
#define SPOTKIN_VM_INLINE inline __attribute__((always_inline))
#else
#define SPOTKIN_VM_INLINE inline
#endif

namespace spotkin::vector_math {

constexpr double kReducibleLimit = 1.0e5;

namespace detail {
constexpr double kTwoOverPi = 6.36619772367581382433e-01;
constexpr double kPio2_1 = 1.57079632673412561417e+00;
constexpr double kPio2_2 = 6.07710050630396597660e-11;
constexpr double kPio2_3 = 2.02226624871116645580e-21;
// Round to nearest integer without a libm call: valid for |x| < 2^51.
constexpr double kRoundMagic = 6755399441055744.0;  // 1.5 * 2^52

SPOTKIN_VM_INLINE double kernel_sin(double x) noexcept {
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  const double z = x * x;
  const double r = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
  return x + x * z * (S1 + z * r);
}

SPOTKIN_VM_INLINE double kernel_cos(double x) noexcept {
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double z = x * x;
  const double r = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
  const double hz = 0.5 * z;
  const double w = 1.0 - hz;
  return w + (((1.0 - w) - hz) + z * r);  // fdlibm's compensated 1 - z/2 + z^2 r
}
}  // namespace detail

// sin and cos of one bounded argument (|x| < kReducibleLimit), for use inside
// loops the compiler vectorises.
SPOTKIN_VM_INLINE void sincos_bounded(double x, double& s, double& c) noexcept {
  using namespace detail;
  const double k = (x * kTwoOverPi + kRoundMagic) - kRoundMagic;
  const double r = ((x - k * kPio2_1) - k * kPio2_2) - k * kPio2_3;
  const double sr = kernel_sin(r), cr = kernel_cos(r);
  const double k4 = k * 0.25;
  double floor_k4 = (k4 + kRoundMagic) - kRoundMagic;
  floor_k4 -= floor_k4 > k4 ? 1.0 : 0.0;
  const double q = k - 4.0 * floor_k4;
  const double q_mod2 = q >= 2.0 ? q - 2.0 : q;
  const double q_plus1 = q == 3.0 ? 0.0 : q + 1.0;
  const bool odd = q_mod2 == 1.0;
  const double sin_abs = odd ? cr : sr, cos_abs = odd ? sr : cr;
  s = q >= 2.0 ? -sin_abs : sin_abs;
  c = q_plus1 >= 2.0 ? -cos_abs : cos_abs;
}

// s[i], c[i] = sin(x[i]), cos(x[i]) for i < n.
SPOTKIN_VM_INLINE void sincos(const double* x, double* s, double* c, std::ptrdiff_t n) noexcept {
  using namespace detail;
  for (std::ptrdiff_t i = 0; i < n; ++i) sincos_bounded(x[i], s[i], c[i]);
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
  // pi/2 = P1 + P2 + P3, P1 and P2 with few enough bits that k * P1, k * P2 are exact
  constexpr float kTwoOverPi = 0.636619772367581f, P1 = 1.5703125f, P2 = 4.837512969970703125e-4f,
                  P3 = 7.54978995489188216e-8f, kRoundMagic = 12582912.0f;  // 1.5 * 2^23
  const float k = (x * kTwoOverPi + kRoundMagic) - kRoundMagic;
  const float r = ((x - k * P1) - k * P2) - k * P3;
  const float z = r * r;
  const float sr = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
  const float cr = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z -
                   0.5f * z + 1.0f;
  const float k4 = k * 0.25f;
  float floor_k4 = (k4 + kRoundMagic) - kRoundMagic;
  floor_k4 -= floor_k4 > k4 ? 1.0f : 0.0f;
  const float q = k - 4.0f * floor_k4;  // k mod 4
  const float q_mod2 = q >= 2.0f ? q - 2.0f : q;
  const float q_plus1 = q == 3.0f ? 0.0f : q + 1.0f;
  const bool odd = q_mod2 == 1.0f;
  const float sin_abs = odd ? cr : sr, cos_abs = odd ? sr : cr;
  s = q >= 2.0f ? -sin_abs : sin_abs;
  c = q_plus1 >= 2.0f ? -cos_abs : cos_abs;
}

SPOTKIN_VM_INLINE void sincos(const float* x, float* s, float* c, std::ptrdiff_t n) noexcept {
  for (std::ptrdiff_t i = 0; i < n; ++i) sincos_bounded(x[i], s[i], c[i]);
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
// atan(lo / hi) for 0 <= lo <= hi (Cephes atan.c, P/Q of degree 4/5). Above
// 0.66 the argument is reduced by pi/4, x = (lo - hi) / (lo + hi), formed with
// a single division either way.
SPOTKIN_VM_INLINE double atan_ratio(double lo, double hi) noexcept {
  constexpr double P0 = -8.750608600031904122785e-01, P1 = -1.615753718733365076637e+01,
                   P2 = -7.500855792314704667340e+01, P3 = -1.228866684490136173410e+02,
                   P4 = -6.485021904942025371773e+01;
  constexpr double Q0 = 2.485846490142306297962e+01, Q1 = 1.650270098316988542046e+02,
                   Q2 = 4.328810604912902668951e+02, Q3 = 4.853903996359136964868e+02,
                   Q4 = 1.945506571482613964425e+02;
  constexpr double kPio4 = 7.85398163397448309616e-01, kMoreBits = 6.123233995736765886130e-17;
  const bool reduce = lo > 0.66 * hi;
  const double num = reduce ? lo - hi : lo, den = reduce ? lo + hi : hi;
  const double x = den > 0.0 ? num / den : num + den;  // 0/0 -> 0, a NaN stays
  const double z = x * x;
  const double p = (((P0 * z + P1) * z + P2) * z + P3) * z + P4;
  const double q = ((((z + Q0) * z + Q1) * z + Q2) * z + Q3) * z + Q4;
  const double r = x + x * (z * p / q);
  return reduce ? kPio4 + (r + 0.5 * kMoreBits) : r;
}
}  // namespace detail

// atan2(y, x) for one pair; finite inputs (NaN propagates).
SPOTKIN_VM_INLINE double atan2(double y, double x) noexcept {
  constexpr double kPio2 = 1.57079632679489661923, kPi = 3.14159265358979323846;
  constexpr double kPio2Lo = 6.123233995736765886130e-17, kPiLo = 1.2246467991473531772e-16;
  const double ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  const double hi = steep ? ay : ax, lo = steep ? ax : ay;
  double a = detail::atan_ratio(lo, hi);
  a = steep ? (kPio2 - a) + kPio2Lo : a;
  const bool x_negative = std::copysign(1.0, x) < 0.0;  // true for -0 too: atan2(0, -0) = pi
  a = x_negative ? (kPi - a) + kPiLo : a;
  return std::copysign(a, y);
}

// acos(x) for x in [-1, 1]; NaN outside.
SPOTKIN_VM_INLINE double acos(double x) noexcept {
  return vector_math::atan2(std::sqrt((1.0 - x) * (1.0 + x)), x);
}

// atan2(y, x) for one float pair (NaN propagates).
SPOTKIN_VM_INLINE float atan2(float y, float x) noexcept {
  constexpr float kPio4 = 0.785398163397448f, kPio2 = 1.57079632679489662f, kPi = 3.14159265358979324f;
  constexpr float kPio2Lo = -4.37113883e-8f, kPiLo = -8.74227766e-8f;  // pi/2 and pi minus their float values
  constexpr float kTanPio8 = 0.414213562373095f;
  const float ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  const float hi = steep ? ay : ax, lo = steep ? ax : ay;
  const bool reduce = lo > kTanPio8 * hi;
  const float num = reduce ? lo - hi : lo, den = reduce ? lo + hi : hi;
  const float t = den > 0.0f ? num / den : num + den;  // 0/0 -> 0, a NaN stays
  const float z = t * t;
  const float r = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) *
                      z * t + t;
  float a = reduce ? kPio4 + r : r;
  a = steep ? (kPio2 - a) + kPio2Lo : a;
  const bool x_negative = std::copysign(1.0f, x) < 0.0f;  // true for -0 too: atan2(0, -0) = pi
  a = x_negative ? (kPi - a) + kPiLo : a;
  return std::copysign(a, y);
}

SPOTKIN_VM_INLINE float acos(float x) noexcept {
  return vector_math::atan2(std::sqrt((1.0f - x) * (1.0f + x)), x);
}

}  // namespace spotkin::vector_math
