// Spatial (6D) algebra for the dynamics kernels, in Featherstone's notation
// (RBDA, ch. 2), written on a lane type S (a scalar or a Pack).
//   motion  (w, v): angular velocity, linear velocity of the frame's origin
//   force   (n, f): moment about the frame's origin, force
// Both in the coordinates of one body frame. A body's pose in its parent is
// X = (R, p): x_parent = R x_child + p.
#pragma once

#include "spotkin/common.hpp"

namespace spotkin::dynamics {

template <typename S>
struct V3 {
  S x[3];
  SPOTKIN_INLINE S& operator[](int i) noexcept { return x[i]; }
  SPOTKIN_INLINE const S& operator[](int i) const noexcept { return x[i]; }
};

template <typename S>
SPOTKIN_INLINE V3<S> zero3() noexcept {
  return {{S(0), S(0), S(0)}};
}
template <typename S>
SPOTKIN_INLINE V3<S> operator+(const V3<S>& a, const V3<S>& b) noexcept {
  return {{a[0] + b[0], a[1] + b[1], a[2] + b[2]}};
}
template <typename S>
SPOTKIN_INLINE V3<S> operator-(const V3<S>& a, const V3<S>& b) noexcept {
  return {{a[0] - b[0], a[1] - b[1], a[2] - b[2]}};
}
template <typename S, typename K>
SPOTKIN_INLINE V3<S> scale(const V3<S>& a, const K& k) noexcept {
  return {{a[0] * k, a[1] * k, a[2] * k}};
}
template <typename S>
SPOTKIN_INLINE V3<S>& operator+=(V3<S>& a, const V3<S>& b) noexcept {
  for (int i = 0; i < 3; ++i) a[i] += b[i];
  return a;
}
template <typename S>
SPOTKIN_INLINE V3<S> cross(const V3<S>& a, const V3<S>& b) noexcept {
  return {{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}};
}
template <typename S>
SPOTKIN_INLINE S dot(const V3<S>& a, const V3<S>& b) noexcept {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
// A model constant (plain scalar) broadcast to the lane type.
template <typename S, typename M>
SPOTKIN_INLINE V3<S> broadcast(const M* c) noexcept {
  return {{S(c[0]), S(c[1]), S(c[2])}};
}

// 3x3 matrix, row-major.
template <typename S>
struct M3 {
  S a[3][3];
  SPOTKIN_INLINE S& operator()(int r, int c) noexcept { return a[r][c]; }
  SPOTKIN_INLINE const S& operator()(int r, int c) const noexcept { return a[r][c]; }
};
template <typename S>
SPOTKIN_INLINE M3<S> zero33() noexcept {
  M3<S> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = S(0);
  return m;
}
template <typename S>
SPOTKIN_INLINE V3<S> mul(const M3<S>& m, const V3<S>& x) noexcept {
  V3<S> y;
  for (int r = 0; r < 3; ++r) y[r] = m(r, 0) * x[0] + m(r, 1) * x[1] + m(r, 2) * x[2];
  return y;
}
template <typename S>
SPOTKIN_INLINE V3<S> mul_t(const M3<S>& m, const V3<S>& x) noexcept {  // m^T x
  V3<S> y;
  for (int c = 0; c < 3; ++c) y[c] = m(0, c) * x[0] + m(1, c) * x[1] + m(2, c) * x[2];
  return y;
}
template <typename S>
SPOTKIN_INLINE M3<S> mul(const M3<S>& a, const M3<S>& b) noexcept {
  M3<S> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a(r, 0) * b(0, c) + a(r, 1) * b(1, c) + a(r, 2) * b(2, c);
  return m;
}
template <typename S>
SPOTKIN_INLINE M3<S> mul_bt(const M3<S>& a, const M3<S>& b) noexcept {  // a b^T
  M3<S> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a(r, 0) * b(c, 0) + a(r, 1) * b(c, 1) + a(r, 2) * b(c, 2);
  return m;
}
template <typename S>
SPOTKIN_INLINE M3<S> transpose(const M3<S>& a) noexcept {
  M3<S> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = a(c, r);
  return m;
}
template <typename S>
SPOTKIN_INLINE void add_to(M3<S>& a, const M3<S>& b) noexcept {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a(r, c) += b(r, c);
}
// [p]x m (columns crossed) and m [p]x (rows crossed: row r of m [p]x is m.row(r) x p).
template <typename S>
SPOTKIN_INLINE M3<S> skew_mul(const V3<S>& p, const M3<S>& m) noexcept {
  M3<S> o;
  for (int c = 0; c < 3; ++c) {
    const V3<S> col{{m(0, c), m(1, c), m(2, c)}};
    const V3<S> x = cross(p, col);
    for (int r = 0; r < 3; ++r) o(r, c) = x[r];
  }
  return o;
}
template <typename S>
SPOTKIN_INLINE M3<S> mul_skew(const M3<S>& m, const V3<S>& p) noexcept {
  M3<S> o;
  for (int r = 0; r < 3; ++r) {
    const V3<S> row{{m(r, 0), m(r, 1), m(r, 2)}};
    const V3<S> x = cross(row, p);
    for (int c = 0; c < 3; ++c) o(r, c) = x[c];
  }
  return o;
}

template <typename S>
struct Motion {
  V3<S> w, v;
};
template <typename S>
struct Force {
  V3<S> n, f;
};
template <typename S>
SPOTKIN_INLINE Motion<S> zero_motion() noexcept {
  return {zero3<S>(), zero3<S>()};
}
template <typename S>
SPOTKIN_INLINE Force<S> zero_force() noexcept {
  return {zero3<S>(), zero3<S>()};
}
// <motion, force>: power.
template <typename S>
SPOTKIN_INLINE S dot(const Motion<S>& m, const Force<S>& f) noexcept {
  return dot(m.w, f.n) + dot(m.v, f.f);
}

// A body pose in its parent: x_parent = R x_child + p.
template <typename S>
struct Pose {
  M3<S> R;
  V3<S> p;
};

// Parent motion in child coordinates, X m (RBDA eq. 2.24): w' = R^T w, v' = R^T (v + w x p).
template <typename S>
SPOTKIN_INLINE Motion<S> to_child(const Pose<S>& X, const Motion<S>& m) noexcept {
  return {mul_t(X.R, m.w), mul_t(X.R, m.v + cross(m.w, X.p))};
}
// Child motion in parent coordinates, X^-1 m.
template <typename S>
SPOTKIN_INLINE Motion<S> to_parent(const Pose<S>& X, const Motion<S>& m) noexcept {
  const V3<S> w = mul(X.R, m.w);
  return {w, mul(X.R, m.v) + cross(X.p, w)};
}
// Child force in parent coordinates, X^T f (RBDA eq. 2.25): f' = R f, n' = R n + p x f'.
template <typename S>
SPOTKIN_INLINE Force<S> to_parent(const Pose<S>& X, const Force<S>& f) noexcept {
  const V3<S> ff = mul(X.R, f.f);
  return {mul(X.R, f.n) + cross(X.p, ff), ff};
}
// Pose composition: a (child in parent) then b (grandchild in child).
template <typename S>
SPOTKIN_INLINE Pose<S> compose(const Pose<S>& a, const Pose<S>& b) noexcept {
  return {mul(a.R, b.R), mul(a.R, b.p) + a.p};
}

// Motion cross product m x u (RBDA eq. 2.31).
template <typename S>
SPOTKIN_INLINE Motion<S> crm(const Motion<S>& m, const Motion<S>& u) noexcept {
  return {cross(m.w, u.w), cross(m.w, u.v) + cross(m.v, u.w)};
}
// Force cross product m x* f (RBDA eq. 2.32).
template <typename S>
SPOTKIN_INLINE Force<S> crf(const Motion<S>& m, const Force<S>& f) noexcept {
  return {cross(m.w, f.n) + cross(m.v, f.f), cross(m.w, f.f)};
}

// A rigid-body inertia about the frame's origin: mass m, first moment h = m c,
// rotational inertia J = I_c - m [c]x^2 (RBDA eq. 2.63). Also the form of a
// composite of rigid bodies (CRBA).
template <typename S>
struct RigidInertia {
  S m;
  V3<S> h;
  M3<S> J;
};
// I u: n = J w + h x v, f = m v - h x w.
template <typename S>
SPOTKIN_INLINE Force<S> apply(const RigidInertia<S>& I, const Motion<S>& u) noexcept {
  return {mul(I.J, u.w) + cross(I.h, u.v), scale(u.v, I.m) - cross(I.h, u.w)};
}
template <typename S>
SPOTKIN_INLINE void add_to(RigidInertia<S>& a, const RigidInertia<S>& b) noexcept {
  a.m += b.m;
  a.h += b.h;
  add_to(a.J, b.J);
}
// A child's inertia in parent coordinates, X^T I X (RBDA eq. 2.66 with
// [a]x[b]x = b a^T - (a.b) 1): h' = R h + m p,
//   J' = R J R^T - (p (Rh)^T + (Rh) p^T) + 2 (p.Rh) 1 - m (p p^T - |p|^2 1).
template <typename S>
SPOTKIN_INLINE RigidInertia<S> to_parent(const Pose<S>& X, const RigidInertia<S>& I) noexcept {
  RigidInertia<S> o;
  o.m = I.m;
  const V3<S> hr = mul(X.R, I.h);
  o.h = hr + scale(X.p, I.m);
  o.J = mul_bt(mul(X.R, I.J), X.R);
  const S ph = dot(X.p, hr), pp = dot(X.p, X.p);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) o.J(r, c) -= X.p[r] * hr[c] + hr[r] * X.p[c] + I.m * X.p[r] * X.p[c];
    o.J(r, r) += S(2) * ph + I.m * pp;
  }
  return o;
}

// A rigid inertia with J's six distinct entries (xx, yy, zz, xy, xz, yz): the composite
// inertias of the floating-base CRBA, summed in one frame.
template <typename S>
struct SymInertia {
  S m;
  V3<S> h;
  S J[6];
};
template <typename S>
SPOTKIN_INLINE void add_to(SymInertia<S>& a, const SymInertia<S>& b) noexcept {
  a.m += b.m;
  a.h += b.h;
  for (int k = 0; k < 6; ++k) a.J[k] += b.J[k];
}
template <typename S>
SPOTKIN_INLINE SymInertia<S> symmetric(const RigidInertia<S>& I) noexcept {
  return {I.m, I.h, {I.J(0, 0), I.J(1, 1), I.J(2, 2), I.J(0, 1), I.J(0, 2), I.J(1, 2)}};
}
// I u: n = J w + h x v, f = m v - h x w.
template <typename S>
SPOTKIN_INLINE Force<S> apply(const SymInertia<S>& I, const Motion<S>& u) noexcept {
  const S* J = I.J;
  const V3<S> Jw{{J[0] * u.w[0] + J[3] * u.w[1] + J[4] * u.w[2], J[3] * u.w[0] + J[1] * u.w[1] + J[5] * u.w[2],
                  J[4] * u.w[0] + J[5] * u.w[1] + J[2] * u.w[2]}};
  return {Jw + cross(I.h, u.v), scale(u.v, I.m) - cross(I.h, u.w)};
}
// One piece of a joint's transform at a time, child to parent (x_parent = R x_child + p), on a
// SymInertia (X^T I X, RBDA eq. 2.66) or a Force (X^T f, eq. 2.25). Rotations about a coordinate
// axis K and translations along it touch only the entries they change: the composite inertias and
// forces of the floating CRBA go through a URDF joint (translation, rotation about +-e_k) for a
// third of the dense transform's operations.
constexpr int kSymIndex[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};  // J(r, c) in SymInertia::J

// R = Rot_K(c, s): R e_I = c e_I + s e_J (I, J = K + 1, K + 2 cyclic).
template <int K, typename S>
SPOTKIN_INLINE void rotate_about(V3<S>& v, const S& c, const S& s) noexcept {
  constexpr int I = (K + 1) % 3, J = (K + 2) % 3;
  const S vi = v[I], vj = v[J];
  v[I] = c * vi - s * vj, v[J] = s * vi + c * vj;
}
template <int K, typename S>
SPOTKIN_INLINE void rotate_about(Force<S>& f, const S& c, const S& s) noexcept {
  rotate_about<K>(f.n, c, s), rotate_about<K>(f.f, c, s);
}
// J' = R J R^T: J'_II = c^2 a - 2 cs d + s^2 b, J'_JJ = s^2 a + 2 cs d + c^2 b,
// J'_IJ = cs (a - b) + (c^2 - s^2) d, J'_IK = c e - s f, J'_JK = s e + c f (a, b, d, e, f = J_II,
// J_JJ, J_IJ, J_IK, J_JK); h' = R h.
template <int K, typename S>
SPOTKIN_INLINE void rotate_about(SymInertia<S>& X, const S& c, const S& s) noexcept {
  constexpr int I = (K + 1) % 3, J = (K + 2) % 3;
  S* j = X.J;
  const S a = j[kSymIndex[I][I]], b = j[kSymIndex[J][J]], d = j[kSymIndex[I][J]];
  const S e = j[kSymIndex[I][K]], f = j[kSymIndex[J][K]];
  const S cc = c * c, ss = s * s, cs = c * s, cs_d2 = S(2) * cs * d;
  j[kSymIndex[I][I]] = cc * a - cs_d2 + ss * b;
  j[kSymIndex[J][J]] = ss * a + cs_d2 + cc * b;
  j[kSymIndex[I][J]] = cs * (a - b) + (cc - ss) * d;
  j[kSymIndex[I][K]] = c * e - s * f;
  j[kSymIndex[J][K]] = s * e + c * f;
  rotate_about<K>(X.h, c, s);
}
// Translation by p (R = 1): n' = n + p x f.
template <typename S, typename V>
SPOTKIN_INLINE void translate(Force<S>& f, const V& p) noexcept {
  const V3<S> pp{{S(p[0]), S(p[1]), S(p[2])}};
  f.n += cross(pp, f.f);
}
// h' = h + m p, J' = J - (p h^T + h p^T) - m p p^T + (2 p.h + m |p|^2) 1.
template <typename S, typename V>
SPOTKIN_INLINE void translate(SymInertia<S>& X, const V& p_in) noexcept {
  const V3<S> p{{S(p_in[0]), S(p_in[1]), S(p_in[2])}};
  const V3<S> h = X.h;
  const S diagonal = S(2) * dot(p, h) + X.m * dot(p, p);
  constexpr int row[6] = {0, 1, 2, 0, 0, 1}, col[6] = {0, 1, 2, 1, 2, 2};
  for (int k = 0; k < 6; ++k) {
    const int r = row[k], c = col[k];
    const S x = X.J[k] - (p[r] * h[c] + h[r] * p[c] + (X.m * p[r]) * p[c]);
    X.J[k] = k < 3 ? x + diagonal : x;
  }
  for (int r = 0; r < 3; ++r) X.h[r] = h[r] + X.m * p[r];
}
// Translation by d e_K: n' = n + d e_K x f, (e_K x f) = f_I e_J - f_J e_I.
template <int K, typename S>
SPOTKIN_INLINE void translate_along(Force<S>& f, const S& d) noexcept {
  constexpr int I = (K + 1) % 3, J = (K + 2) % 3;
  f.n[I] -= d * f.f[J], f.n[J] += d * f.f[I];
}
// translate() with p = d e_K: J'_II += 2 d h_K + m d^2 (and J'_JJ), J'_IK -= d h_I, J'_JK -= d h_J.
template <int K, typename S>
SPOTKIN_INLINE void translate_along(SymInertia<S>& X, const S& d) noexcept {
  constexpr int I = (K + 1) % 3, J = (K + 2) % 3;
  const S grow = S(2) * d * X.h[K] + X.m * d * d;
  X.J[kSymIndex[I][I]] += grow, X.J[kSymIndex[J][J]] += grow;
  X.J[kSymIndex[I][K]] -= d * X.h[I], X.J[kSymIndex[J][K]] -= d * X.h[J];
  X.h[K] += X.m * d;
}
// A dense rotation R (row-major, any scalar type convertible to S).
template <typename S, typename R3>
SPOTKIN_INLINE void rotate(Force<S>& f, const R3& R) noexcept {
  const Force<S> o = f;
  for (int r = 0; r < 3; ++r) {
    f.n[r] = S(R(r, 0)) * o.n[0] + S(R(r, 1)) * o.n[1] + S(R(r, 2)) * o.n[2];
    f.f[r] = S(R(r, 0)) * o.f[0] + S(R(r, 1)) * o.f[1] + S(R(r, 2)) * o.f[2];
  }
}
template <typename S, typename R3>
SPOTKIN_INLINE void rotate(SymInertia<S>& X, const R3& R) noexcept {
  S RJ[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      RJ[r][c] = S(R(r, 0)) * X.J[kSymIndex[0][c]] + S(R(r, 1)) * X.J[kSymIndex[1][c]] +
                 S(R(r, 2)) * X.J[kSymIndex[2][c]];
  constexpr int row[6] = {0, 1, 2, 0, 0, 1}, col[6] = {0, 1, 2, 1, 2, 2};
  for (int k = 0; k < 6; ++k)
    X.J[k] = RJ[row[k]][0] * S(R(col[k], 0)) + RJ[row[k]][1] * S(R(col[k], 1)) + RJ[row[k]][2] * S(R(col[k], 2));
  const V3<S> h = X.h;
  for (int r = 0; r < 3; ++r) X.h[r] = S(R(r, 0)) * h[0] + S(R(r, 1)) * h[1] + S(R(r, 2)) * h[2];
}

// A general symmetric spatial inertia (articulated-body inertia, RBDA ch. 7):
// (n, f) = [[A, B], [B^T, C]] (w, v), A and C symmetric.
template <typename S>
struct Inertia6 {
  M3<S> A, B, C;
};
template <typename S>
SPOTKIN_INLINE Inertia6<S> general(const RigidInertia<S>& I) noexcept {
  Inertia6<S> o;
  o.A = I.J;
  o.C = zero33<S>();
  const V3<S>& h = I.h;
  o.B(0, 0) = S(0), o.B(0, 1) = -h[2], o.B(0, 2) = h[1];
  o.B(1, 0) = h[2], o.B(1, 1) = S(0), o.B(1, 2) = -h[0];
  o.B(2, 0) = -h[1], o.B(2, 1) = h[0], o.B(2, 2) = S(0);
  for (int r = 0; r < 3; ++r) o.C(r, r) = I.m;
  return o;
}
template <typename S>
SPOTKIN_INLINE Force<S> apply(const Inertia6<S>& I, const Motion<S>& u) noexcept {
  return {mul(I.A, u.w) + mul(I.B, u.v), mul_t(I.B, u.w) + mul(I.C, u.v)};
}
template <typename S>
SPOTKIN_INLINE void add_to(Inertia6<S>& a, const Inertia6<S>& b) noexcept {
  add_to(a.A, b.A);
  add_to(a.B, b.B);
  add_to(a.C, b.C);
}
// X^T I X: rotate each block (R . R^T), then move the origin by p:
//   A'' = A' - K - K^T - [p] C' [p],  K = B'[p];  B'' = B' + [p] C';  C'' = C'.
template <typename S>
SPOTKIN_INLINE Inertia6<S> to_parent(const Pose<S>& X, const Inertia6<S>& I) noexcept {
  Inertia6<S> o;
  const M3<S> A = mul_bt(mul(X.R, I.A), X.R), B = mul_bt(mul(X.R, I.B), X.R), C = mul_bt(mul(X.R, I.C), X.R);
  const M3<S> K = mul_skew(B, X.p);
  const M3<S> PCP = skew_mul(X.p, mul_skew(C, X.p));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) o.A(r, c) = A(r, c) - K(r, c) - K(c, r) - PCP(r, c);
  o.B = skew_mul(X.p, C);
  add_to(o.B, B);
  o.C = C;
  return o;
}

}  // namespace spotkin::dynamics
