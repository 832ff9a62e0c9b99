// The configuration of a roll-pitch-pitch leg within its joint limits whose
// foot is nearest to a target, exactly: the slow path for unreachable targets.
// Same algorithm, step labels and tie rule as nearest_in_limits in
// python/spotkin/reference/rpp_leg.py, whose docstrings hold the derivation:
//
//   (R1) p = Rx(t1) (a + Ry(t2) (b + Ry(t3) c)),  t_k = sign[k] q_k,
//   (R2) zeta(u) = u_z + i u_x (Ry(t): times e^{it}), eta(u) = u_y + i u_z (Rx(t): times e^{it}).
//
// The minimiser of |fk(q) - p|^2 over the box is a KKT point: each joint at a
// "fixed value" (a bound, or for the knee a singular value psi = 0, pi) or free
// and stationary. (N1) exact IK within limits; (N3) vertices; (N4) one joint
// free: nearest point of a circle; (N5) roll fixed: planar 2R IK of the
// projection; (N6) roll and one pitch joint free: the roll torus, degree-8
// polynomial (T3) in t = tan(beta/2) over |t| <= 1 (+1/64), two charts; (N7) all
// free, hip-roll singular; (N8) the nearest, ties within 1e-12 m to the lower
// slot. Real roots of (T3) and of its derivative on the chart come from the
// roots of all its derivatives in turn (each derivative's roots bracket the
// monotone pieces of the one above, solved by safeguarded Newton).
// No heap allocation; a few tens of microseconds per call.
#pragma once

#include <cmath>
#include <complex>
#include <limits>

#include "spotkin/rpp_geometry.hpp"

namespace spotkin {
namespace rpp_nearest_detail {

constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr double kTwoPi = 2.0 * kPi;
constexpr double kRatioTol = 1e-12;  // |ratio| <= 1 + tol touches a singular set
constexpr double kLimitTol = 1e-12;  // rad, tolerance on joint limits
constexpr double kTieTol = 1e-12;    // m, distances closer than this are ties
constexpr double kSlotTol = 1e-9;    // v_z (m), sin psi up to this: branch 0 (singular sets)
// Each chart of (T3) is searched over |t| <= 1 + 1/64, a little past its half of
// the circle, so that roots at t = +-1 (beta = +-pi/2, often double) are not lost
// to rounding at an end of the interval.
constexpr double kChartReach = 1.0 + 1.0 / 64.0;

using Cx = std::complex<double>;

struct V3 {
  double x, y, z;
};
inline V3 operator+(V3 u, V3 v) noexcept { return {u.x + v.x, u.y + v.y, u.z + v.z}; }
inline V3 operator-(V3 u, V3 v) noexcept { return {u.x - v.x, u.y - v.y, u.z - v.z}; }
inline V3 rx(double t, V3 u) noexcept {
  const double c = std::cos(t), s = std::sin(t);
  return {u.x, c * u.y - s * u.z, s * u.y + c * u.z};
}
inline V3 ry(double t, V3 u) noexcept {
  const double c = std::cos(t), s = std::sin(t);
  return {c * u.x + s * u.z, u.y, -s * u.x + c * u.z};
}
inline Cx zeta(V3 u) noexcept { return {u.z, u.x}; }
inline Cx eta(V3 u) noexcept { return {u.y, u.z}; }
inline double arg(Cx w) noexcept { return std::atan2(w.imag(), w.real()); }
inline double wrap(double t) noexcept {
  t = std::remainder(t, kTwoPi);
  return t <= -kPi ? t + kTwoPi : t;
}
inline double pmod(double x) noexcept {  // x mod 2 pi in [0, 2 pi], as Python's %
  const double r = std::fmod(x, kTwoPi);
  return r < 0.0 ? r + kTwoPi : r;
}

struct Leg {
  V3 a, b, c;
  double s[3];
  Cx B, C;
  double phi;  // arg C - arg B
  double h;    // a_y + b_y + c_y
};

inline V3 leg_point(const Leg& L, double t2, double t3) noexcept {
  return L.a + ry(t2, L.b + ry(t3, L.c));
}

inline bool limited(double lo, double hi) noexcept {
  return std::isfinite(lo) && std::isfinite(hi) && hi - lo < kTwoPi;
}

// The angle congruent to q (mod 2 pi) inside [lo, hi]; false if none. A joint
// with a range of 2 pi or more is unconstrained on the circle.
inline bool into_range(double q, double lo, double hi, double* out) noexcept {
  if (!std::isfinite(q)) return false;
  if (!limited(lo, hi)) {
    const double w = wrap(q);
    if (lo <= w && w <= hi) *out = w;
    else if (std::isfinite(lo)) *out = lo + pmod(w - lo);
    else *out = hi - pmod(hi - w);
    return true;
  }
  const double k = lo - kLimitTol + pmod(q - lo + kLimitTol);
  if (k > hi + kLimitTol) return false;
  *out = std::fmin(std::fmax(k, lo), hi);
  return true;
}

// (I1) hip roll for branch eps: theta1 and v_z = -eps S; false when r < |h|.
inline bool hip_roll(double y, double z, double h, double eps, double* t1, double* vz) noexcept {
  const double r = std::hypot(y, z);
  if (r == 0.0) {
    *t1 = *vz = 0.0;
    return h == 0.0;
  }
  const double ratio = h / r;
  if (!(std::fabs(ratio) <= 1.0 + kRatioTol)) return false;
  const double sr = std::sqrt(std::fmax(0.0, 1.0 - ratio * ratio));  // S / r: no overflow of r^2
  *t1 = std::atan2((z / r) * ratio + eps * (y / r) * sr, (y / r) * ratio - eps * (z / r) * sr);
  *vz = -eps * r * sr;
  return true;
}

// (I3)-(I4) planar 2R: W = e^{i t2} (B + e^{i t3} C), knee branches 0, 1 in out[k] = {t2, t3}.
inline bool planar_ik(Cx W, const Leg& L, double out[2][2]) noexcept {
  const double nB = std::abs(L.B), nC = std::abs(L.C);
  if (nB == 0.0 || nC == 0.0) return false;
  const double ratio = (std::norm(W) - nB * nB - nC * nC) / (2.0 * nB * nC);
  if (!(std::fabs(ratio) <= 1.0 + kRatioTol)) return false;
  const double ac = std::acos(std::fmin(1.0, std::fmax(-1.0, ratio)));
  for (int k = 0; k < 2; ++k) {
    const double t3 = (k == 0 ? -ac : ac) - L.phi;
    const Cx D = L.B + Cx(std::cos(t3), std::sin(t3)) * L.C;
    out[k][0] = arg(W * std::conj(D));
    out[k][1] = t3;
  }
  return true;
}

// ---- real roots on [-R, R] of a polynomial of degree <= 8 (coefficients low to high)

inline double horner(const double* c, int n, double t) noexcept {  // n coefficients
  double v = 0.0;
  for (int i = n - 1; i >= 0; --i) v = v * t + c[i];
  return v;
}

// The root of p (n coefficients) in [u, v], where p is monotone
// and changes sign (fu = p(u), fv = p(v)): Newton steps from the secant point,
// bisection whenever a step leaves the bracket. Stops once a step is below
// 1e-12: Newton's error is then ~1e-24, and a candidate's distance is second
// order in it anyway (it is a stationary point).
inline double bracketed_root(const double* p, int n, double u, double v, double fu,
                             double fv) noexcept {
  double x = u - fu * (v - u) / (fv - fu);
  if (!(x > u && x < v)) x = 0.5 * (u + v);
  for (int it = 0; it < 200; ++it) {
    double f = p[n - 1], df = 0.0;  // p(x) and p'(x) by one Horner pass
    for (int i = n - 2; i >= 0; --i) df = df * x + f, f = f * x + p[i];
    if (f == 0.0) return x;
    if ((f < 0.0) == (fu < 0.0)) u = x;
    else v = x;
    double xn = df != 0.0 ? x - f / df : 0.5 * (u + v);
    if (!(xn > std::fmin(u, v) && xn < std::fmax(u, v))) xn = 0.5 * (u + v);
    if (std::fabs(xn - x) <= 1e-12 || std::fabs(v - u) <= 1e-15) return xn;
    x = xn;
  }
  return x;
}

// Roots in [-R, R] (R = kChartReach) of p (9 coefficients) and of p': the roots
// of the k-th derivative split [-R, R] into pieces where the (k-1)-th is monotone.
inline void unit_roots(const double p[9], double r0[8], int* n0, double r1[8], int* n1) noexcept {
  double d[9][9];  // d[k]: k-th derivative, 9 - k coefficients
  for (int i = 0; i < 9; ++i) d[0][i] = p[i];
  for (int k = 1; k < 9; ++k)
    for (int i = 0; i < 9 - k; ++i) d[k][i] = d[k - 1][i + 1] * double(i + 1);
  double roots[9][8];
  int count[9] = {0};
  for (int k = 7; k >= 0; --k) {
    const int n = 9 - k;
    bool zero = true;
    for (int i = 0; i < n; ++i) zero = zero && d[k][i] == 0.0;
    if (zero) continue;  // identically zero: no isolated roots
    double breaks[10];
    int nb = 0;
    breaks[nb++] = -kChartReach;
    for (int i = 0; i < count[k + 1]; ++i) breaks[nb++] = roots[k + 1][i];
    breaks[nb++] = kChartReach;
    for (int i = 0; i + 1 < nb; ++i) {
      const double u = breaks[i], v = breaks[i + 1];
      const double fu = horner(d[k], n, u), fv = horner(d[k], n, v);
      if (fu == 0.0) {
        if (count[k] == 0 || roots[k][count[k] - 1] != u) roots[k][count[k]++] = u;
      } else if (v > u && (fu < 0.0) != (fv < 0.0) && fv != 0.0) {
        roots[k][count[k]++] = bracketed_root(d[k], n, u, v, fu, fv);
      }
      if (count[k] >= 8) break;
    }
    const bool end_is_new = count[k] == 0 || roots[k][count[k] - 1] != kChartReach;
    if (count[k] < 8 && end_is_new && horner(d[k], n, kChartReach) == 0.0)
      roots[k][count[k]++] = kChartReach;
  }
  *n0 = count[0];
  *n1 = count[1];
  for (int i = 0; i < count[0]; ++i) r0[i] = roots[0][i];
  for (int i = 0; i < count[1]; ++i) r1[i] = roots[1][i];
}

inline void polymul(const double* a, int na, const double* b, int nb, double* out) noexcept {
  for (int i = 0; i < na + nb - 1; ++i) out[i] = 0.0;
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < nb; ++j) out[i + j] += a[i] * b[j];
}

// (N6) (theta1, alpha) candidates on the roll torus {Rx(theta1) (m + Ry(alpha) n)}:
// stationary points of (T1) from the roots of (T3) and its derivative, both charts.
inline int torus_stationary(V3 m, V3 n, V3 p, double out[32][2]) noexcept {
  const double X = p.x - m.x, hp = m.y + n.y, mz = m.z;
  const double r = std::abs(zeta(n)), gamma = arg(zeta(n));
  const double rho = std::hypot(p.y, p.z);
  // (T3) is homogeneous of degree 8 in the lengths: scaled to 1, same roots, no overflow
  const double scale = std::fmax(std::fmax(std::fabs(X), std::fabs(hp)),
                                 std::fmax(std::fabs(mz), std::fmax(r, rho)));
  if (!(scale > 0.0)) return 0;
  const double Xs = X / scale, hs = hp / scale, mzs = mz / scale;
  const double rs = r / scale, rhos = rho / scale;
  int count = 0;
  for (int chart = 0; chart < 2; ++chart) {
    const double offset = chart == 0 ? 0.0 : kPi, rr = chart == 0 ? rs : -rs;
    const double Q2[5] = {1.0, 0.0, 2.0, 0.0, 1.0};  // (1 + t^2)^2
    const double W2[3] = {mzs + rr, 0.0, mzs - rr}, L2[3] = {Xs, 2.0 * mzs, -Xs};
    double WW[5], LL[5], S[5], lhs[9], rhs[9], P8[9];
    polymul(W2, 3, W2, 3, WW);
    polymul(L2, 3, L2, 3, LL);
    for (int i = 0; i < 5; ++i) S[i] = hs * hs * Q2[i] + WW[i];
    polymul(S, 5, LL, 5, lhs);
    for (int i = 0; i < 9; ++i) rhs[i] = 0.0;
    for (int i = 0; i < 5; ++i) rhs[i + 2] = 4.0 * rhos * rhos * WW[i];
    for (int i = 0; i < 9; ++i) P8[i] = lhs[i] - rhs[i];
    double r0[8], r1[8];
    int n0, n1;
    unit_roots(P8, r0, &n0, r1, &n1);
    for (int i = 0; i < n0 + n1; ++i) {
      const double beta = offset + 2.0 * std::atan(i < n0 ? r0[i] : r1[i - n0]);
      const double w = mz + r * std::cos(beta);
      out[count][0] = std::atan2(p.z, p.y) - std::atan2(w, hp);
      out[count][1] = beta - gamma;
      ++count;
    }
  }
  return count;
}

// (N8) the nearest in-limit candidate so far; ties go to the lower slot
// (hip 1 when v_z > 1e-9, knee 1 when sin psi > 1e-9), then to the first offered.
struct Best {
  const Leg& L;
  const double *lower, *upper;
  V3 p;
  double q[3] = {0.0, 0.0, 0.0};
  double d = std::numeric_limits<double>::infinity();
  int slot = 4;
  bool found = false;

  void offer(double t1, double t2, double t3) noexcept {
    const double t[3] = {t1, t2, t3};
    double qc[3], th[3];
    for (int k = 0; k < 3; ++k) {
      if (!into_range(L.s[k] * t[k], lower[k], upper[k], &qc[k])) return;
      th[k] = L.s[k] * qc[k];
    }
    const V3 u = leg_point(L, th[1], th[2]);
    const V3 e = rx(th[0], u) - p;
    const double dist = std::hypot(e.x, e.y, e.z);
    const int sl = 2 * (u.z > kSlotTol ? 1 : 0) + (std::sin(th[2] + L.phi) > kSlotTol ? 1 : 0);
    if (dist < d - kTieTol || (dist <= d + kTieTol && sl < slot)) {
      for (int k = 0; k < 3; ++k) q[k] = qc[k];
      d = dist;
      slot = sl;
      found = true;
    }
  }
};

inline void nearest(const RppGeometry& g, const double lower[3], const double upper[3],
                    const double p[3], double q[3]) noexcept {
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
    q[0] = q[1] = q[2] = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  Leg L;
  L.a = {g.a[0], g.a[1], g.a[2]};
  L.b = {g.b[0], g.b[1], g.b[2]};
  L.c = {g.c[0], g.c[1], g.c[2]};
  for (int k = 0; k < 3; ++k) L.s[k] = g.sign[k];
  L.B = zeta(L.b);
  L.C = zeta(L.c);
  L.phi = arg(L.C) - arg(L.B);
  L.h = L.a.y + L.b.y + L.c.y;
  const V3 P = {p[0], p[1], p[2]};
  double sol[2][2];

  // (N1) exact IK (I1)-(I5), the first slot within the limits
  for (int hb = 0; hb < 2; ++hb) {
    double t1, vz;
    if (!hip_roll(P.y, P.z, L.h, hb == 0 ? 1.0 : -1.0, &t1, &vz)) continue;
    if (!planar_ik(Cx(vz - L.a.z, P.x - L.a.x), L, sol)) continue;
    for (int kb = 0; kb < 2; ++kb) {
      const double t[3] = {t1, sol[kb][0], sol[kb][1]};
      double qc[3];
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k)
        ok = into_range(wrap(L.s[k] * t[k]), lower[k], upper[k], &qc[k]);
      if (ok) {
        for (int k = 0; k < 3; ++k) q[k] = qc[k];
        return;
      }
    }
  }

  // (N2) fixed values in model angles: bounds, and the knee's singular values (K5) within limits
  double V1[2], V2[2], V3v[4];
  int n1 = 0, n2 = 0, n3 = 0;
  auto add_bounds = [&](int k, double* V, int* n) {
    if (!limited(lower[k], upper[k])) return;
    V[(*n)++] = L.s[k] * lower[k];
    if (upper[k] != lower[k]) V[(*n)++] = L.s[k] * upper[k];
  };
  add_bounds(0, V1, &n1);
  add_bounds(1, V2, &n2);
  add_bounds(2, V3v, &n3);
  for (double t : {-L.phi, kPi - L.phi}) {
    double unused;
    if (into_range(L.s[2] * t, lower[2], upper[2], &unused)) V3v[n3++] = t;
  }

  Best best{L, lower, upper, P};
  // (N3) vertices
  for (int i = 0; i < n1; ++i)
    for (int j = 0; j < n2; ++j)
      for (int k = 0; k < n3; ++k) best.offer(V1[i], V2[j], V3v[k]);
  // (N4) edges: one joint free, the nearest point of its circle (K1)
  const double arg_p = arg(eta(P));
  for (int j = 0; j < n2; ++j)
    for (int k = 0; k < n3; ++k)
      best.offer(arg_p - arg(eta(leg_point(L, V2[j], V3v[k]))), V2[j], V3v[k]);
  for (int i = 0; i < n1; ++i) {
    const V3 v = rx(-V1[i], P) - L.a;  // Rx(t1)^T p - a
    for (int k = 0; k < n3; ++k)
      best.offer(V1[i], arg(zeta(v)) - arg(zeta(L.b + ry(V3v[k], L.c))), V3v[k]);
    for (int j = 0; j < n2; ++j)
      best.offer(V1[i], V2[j], arg(zeta(ry(-V2[j], v) - L.b)) - arg(L.C));
  }
  // (N5) roll fixed: planar 2R IK of the projection (K2)
  for (int i = 0; i < n1; ++i)
    if (planar_ik(zeta(rx(-V1[i], P) - L.a), L, sol))
      for (int kb = 0; kb < 2; ++kb) best.offer(V1[i], sol[kb][0], sol[kb][1]);
  // (N6) roll free, one pitch joint fixed: the roll torus (K3). Skipped when it
  // cannot beat the best so far: in the meridian half-plane (x, hypot(y, z)) the
  // torus lies within |zeta(n)| of (m_x, hypot(m_y + n_y, m_z)) (a 1-Lipschitz
  // image of its generating circle), which bounds every candidate's distance.
  double cand[32][2];
  auto torus_can_win = [&](V3 m, V3 n) {
    const double radial = std::hypot(P.y, P.z) - std::hypot(m.y + n.y, m.z);
    const double lower_bound = std::hypot(P.x - m.x, radial) - std::abs(zeta(n));
    return !(lower_bound > best.d + 2.0 * kTieTol);
  };
  for (int k = 0; k < n3; ++k) {
    const V3 n = L.b + ry(V3v[k], L.c);
    if (!torus_can_win(L.a, n)) continue;
    const int nc = torus_stationary(L.a, n, P, cand);
    for (int i = 0; i < nc; ++i) best.offer(cand[i][0], cand[i][1], V3v[k]);
  }
  for (int j = 0; j < n2; ++j) {
    const V3 m = L.a + ry(V2[j], L.b);
    if (!torus_can_win(m, L.c)) continue;
    const int nc = torus_stationary(m, L.c, P, cand);
    for (int i = 0; i < nc; ++i) best.offer(cand[i][0], V2[j], cand[i][1] - V2[j]);
  }
  // (N7) all free, hip-roll singular (K4): theta1 aligned with eta(p), foot at v = (x, h, 0)
  if (planar_ik(Cx(-L.a.z, P.x - L.a.x), L, sol))
    for (double t1 : {arg_p, arg_p + kPi})
      for (int kb = 0; kb < 2; ++kb) best.offer(t1, sol[kb][0], sol[kb][1]);

  if (!best.found)  // degenerate geometry: every joint at its lower bound (0 if unconstrained)
    best.offer(L.s[0] * (limited(lower[0], upper[0]) ? lower[0] : 0.0),
               L.s[1] * (limited(lower[1], upper[1]) ? lower[1] : 0.0),
               L.s[2] * (limited(lower[2], upper[2]) ? lower[2] : 0.0));
  for (int k = 0; k < 3; ++k) q[k] = best.q[k];
}

}  // namespace rpp_nearest_detail

// q within [lower, upper] (a joint with a range >= 2 pi or an infinite one is
// unconstrained on the circle) whose foot is nearest to p; NaN if p is not finite.
inline void rpp_nearest_in_limits(const RppGeometry& g, const double lower[3],
                                  const double upper[3], const double p[3], double q[3]) noexcept {
  rpp_nearest_detail::nearest(g, lower, upper, p, q);
}

}  // namespace spotkin
