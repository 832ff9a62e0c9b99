// Paul's standard trigonometric equations (the course's Spot problem, appendix, corrected per the
// errata), every root plus validity. Each solver is branch-free per sample.
//
// Type 2:  X sin t + Y cos t = Z.  With r^2 = X^2 + Y^2 and S = sqrt(r^2 - Z^2):
//            cos t = (Y Z - eps X S) / r^2,   sin t = (X Z + eps Y S) / r^2,
//          root 0: eps = +1, root 1: eps = -1. No root when r^2 < Z^2 (the appendix
//          says "singular" there; see ERRATA.md). X = Y = 0: no root if Z != 0;
//          if Z = 0 every t solves it, reported as t = 0 (both roots valid).
// Type 3:  X1 sin t + Y1 cos t = Z1, X2 sin t + Y2 cos t = Z2.  With
//          D = X1 Y2 - X2 Y1 != 0: cos t = (Z2 X1 - Z1 X2) / D, sin t = (Z1 Y2 - Z2 Y1) / D,
//          valid when sin^2 + cos^2 = 1 (1e-9). D = 0: the type-2 roots of the first
//          non-trivial equation that also satisfy the other (the first such root).
// Type 6:  W sin tj = X cos ti + Y sin ti + Z1,  W cos tj = X sin ti - Y cos ti + Z2.
//          Squaring and adding: B1 sin ti + B2 cos ti = B3 (type 2) with
//          B1 = 2 (Z1 Y + Z2 X), B2 = 2 (Z1 X - Z2 Y), B3 = W^2 - X^2 - Y^2 - Z1^2 - Z2^2;
//          (|B3| within 16 eps (W^2 + X^2 + Y^2 + Z1^2 + Z2^2) beyond hypot(B1, B2), B3's own
//          rounding, counts as touching: a double root)
//          then tj from sin tj = (X cos ti + Y sin ti + Z1) / W, cos tj = (X sin ti - Y cos ti + Z2) / W
//          (type 3, valid when on the unit circle to 1e-9). W = 0: ti from the type-3 system
//          X cos ti + Y sin ti = -Z1, X sin ti - Y cos ti = -Z2, tj free (reported 0) in slot 0,
//          slot 1 invalid. X = Y = 0 leaves ti free: ti = 0 is reported, tj solving the pair.
//          Every equation is first divided by its largest coefficient.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "spotkin/common.hpp"
#include "spotkin/vector_math.hpp"

namespace spotkin::paul {

constexpr double kTolerance = 1e-12;  // relative: r^2 - Z^2 >= -tol r^2 counts as a double root
constexpr double kType6Slack = 16.0 * std::numeric_limits<double>::epsilon();  // type 6: rounding of B3 / scale

// The largest |coefficient| (1 if all are zero or it is not finite): every
// equation is solved after dividing by it, which leaves the roots unchanged and
// keeps tiny or huge coefficients from under- or overflowing in the squares.
// (Dividing, not multiplying by its reciprocal, which overflows for subnormals.)
template <typename... Args>
SPOTKIN_INLINE double scale_of(Args... c) noexcept {
  double m = 0.0;
  ((m = std::max(m, std::fabs(c))), ...);
  return m > 0.0 && std::isfinite(m) ? m : 1.0;
}

struct Type2 {
  double t[2];
  double valid[2];  // 1.0 / 0.0
};

// zero_tolerance: |Z| at or below it counts as 0 when X = Y = 0 (type 6 passes
// one scaled to its coefficients, since its Z is a difference of squares).
SPOTKIN_INLINE Type2 type2(double X, double Y, double Z, double zero_tolerance = 0.0) noexcept {
  // Inf or NaN: no root (ints and &, not &&: no branch, and no Clang -Wbitwise-instead-of-logical)
  const bool finite = (int(std::isfinite(X)) & int(std::isfinite(Y)) & int(std::isfinite(Z))) != 0;
  const double m = scale_of(X, Y, Z);
  X /= m, Y /= m, Z /= m, zero_tolerance /= m;
  Type2 out;
  const double r2 = X * X + Y * Y;
  const double disc = r2 - Z * Z;
  const bool degenerate = !(r2 > zero_tolerance * zero_tolerance);
  const bool exists = finite && (degenerate ? std::fabs(Z) <= zero_tolerance : disc >= -kTolerance * r2);
  const double S = std::sqrt(std::max(disc, 0.0));
  for (int k = 0; k < 2; ++k) {
    const double eps = k == 0 ? 1.0 : -1.0;
    const double t = vector_math::atan2(X * Z + eps * Y * S, Y * Z - eps * X * S);  // atan2 is scale-free
    out.t[k] = degenerate ? 0.0 : t;
    out.valid[k] = exists ? 1.0 : 0.0;
    out.t[k] = exists ? out.t[k] : quiet_nan<double>();
  }
  return out;
}

struct Type3 {
  double t, valid;
};

SPOTKIN_INLINE Type3 type3(double X1, double Y1, double Z1, double X2, double Y2, double Z2) noexcept {
  if (!(std::isfinite(X1) && std::isfinite(Y1) && std::isfinite(Z1) && std::isfinite(X2) && std::isfinite(Y2) &&
        std::isfinite(Z2)))
    return Type3{quiet_nan<double>(), 0.0};
  const double m1 = scale_of(X1, Y1, Z1), m2 = scale_of(X2, Y2, Z2);
  X1 /= m1, Y1 /= m1, Z1 /= m1, X2 /= m2, Y2 /= m2, Z2 /= m2;
  const double D = X1 * Y2 - X2 * Y1;
  const double scale = std::max(std::max(std::fabs(X1), std::fabs(Y1)), std::max(std::fabs(X2), std::fabs(Y2)));
  Type3 out;
  if (std::fabs(D) > 1e-12 * scale * scale) {
    const double c = (Z2 * X1 - Z1 * X2) / D, s = (Z1 * Y2 - Z2 * Y1) / D;
    out.valid = std::fabs(s * s + c * c - 1.0) <= 1e-9 ? 1.0 : 0.0;
    out.t = out.valid != 0.0 ? vector_math::atan2(s, c) : quiet_nan<double>();
    return out;
  }
  // dependent equations: solve the first non-trivial one, keep a root satisfying both
  const bool first = X1 * X1 + Y1 * Y1 >= X2 * X2 + Y2 * Y2;
  const Type2 roots = first ? type2(X1, Y1, Z1) : type2(X2, Y2, Z2);
  out.t = quiet_nan<double>(), out.valid = 0.0;
  for (int k = 0; k < 2 && out.valid == 0.0; ++k) {
    if (roots.valid[k] == 0.0) continue;
    const double s = std::sin(roots.t[k]), c = std::cos(roots.t[k]);
    const double r1 = X1 * s + Y1 * c - Z1, r2 = X2 * s + Y2 * c - Z2;
    if (std::fabs(r1) <= 1e-9 * (1.0 + std::fabs(Z1)) && std::fabs(r2) <= 1e-9 * (1.0 + std::fabs(Z2)))
      out.t = roots.t[k], out.valid = 1.0;
  }
  return out;
}

struct Type6 {
  double ti[2], tj[2], valid[2];
};

SPOTKIN_INLINE Type6 type6(double W, double X, double Y, double Z1, double Z2) noexcept {
  const double m = scale_of(W, X, Y, Z1, Z2);
  W /= m, X /= m, Y /= m, Z1 /= m, Z2 /= m;
  Type6 out;
  out.ti[0] = out.ti[1] = out.tj[0] = out.tj[1] = quiet_nan<double>();
  out.valid[0] = out.valid[1] = 0.0;
  if (!(std::isfinite(W) && std::isfinite(X) && std::isfinite(Y) && std::isfinite(Z1) && std::isfinite(Z2)))
    return out;  // Inf or NaN: no root
  if (W == 0.0) {  // X cos ti + Y sin ti = -Z1, X sin ti - Y cos ti = -Z2 (type 3); tj free, reported 0
    const Type3 t = type3(Y, X, -Z1, X, -Y, -Z2);
    if (t.valid != 0.0) out.ti[0] = t.t, out.tj[0] = 0.0, out.valid[0] = 1.0;
    return out;
  }
  const double scale = W * W + X * X + Y * Y + Z1 * Z1 + Z2 * Z2;
  const double B1 = 2.0 * (Z1 * Y + Z2 * X), B2 = 2.0 * (Z1 * X - Z2 * Y);
  double B3 = W * W - X * X - Y * Y - Z1 * Z1 - Z2 * Z2;
  // B3 is a difference of squares adding up to `scale`: its rounding (a few eps
  // scale) can push a double root (|B3| = hypot(B1, B2)) out of reach when B1 and
  // B2 are small. Within kType6Slack scale of touching, it touches.
  const double r = std::sqrt(B1 * B1 + B2 * B2);
  B3 = std::fabs(B3) > r && std::fabs(B3) - r <= kType6Slack * scale ? std::copysign(r, B3) : B3;
  const Type2 roots = type2(B1, B2, B3, 1e-12 * scale);
  for (int r = 0; r < 2; ++r) {
    if (roots.valid[r] == 0.0) continue;
    double s, c;
    vector_math::sincos_bounded(roots.t[r], s, c);
    const double sj = (X * c + Y * s + Z1) / W, cj = (X * s - Y * c + Z2) / W;
    if (std::fabs(sj * sj + cj * cj - 1.0) > 1e-9) continue;  // type 3 consistency
    out.ti[r] = roots.t[r], out.tj[r] = vector_math::atan2(sj, cj), out.valid[r] = 1.0;
  }
  return out;
}

}  // namespace spotkin::paul
