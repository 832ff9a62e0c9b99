// The Coriolis matrix C(q, qd) for which dA/dt - 2C is skew-symmetric (the
// Christoffel-consistent factorisation of Echeandia & Wensing, "A Numerical
// Method for Computing the Coriolis Matrix", 2021; Pinocchio's
// computeCoriolisMatrix), on one block of lanes:
//   C = sum_k J_k^T (I_k dJ_k + B_k J_k),
//   B_k = 1/2 [(v_k x*) I_k - I_k (v_k x) + (I_k v_k) xbar*],   (f xbar*) u = u x* f
// with J_k, dJ_k, v_k, I_k body k's Jacobian, its derivative, velocity and
// inertia in root coordinates. For a rigid I = (m, h, J) and v = (w, v) this B
// is [[B11, 0], [-[f0]x, 0]], B11 = 1/2 ([w]J - J[w] - [v][h] - [h][v] - [n0]),
// (n0, f0) = I v. On a chain, bodies i and j share the subtree of max(i, j):
//   C_ij = S_i^T (Ic_j dS_j + Bc_j S_j)            (i <= j)
//   C_ij = (Ic_i S_i)^T dS_j + (Bc_i^T S_i)^T S_j  (i > j)
// with S_j joint j's column in root coordinates, dS_j = v_j x S_j, and Ic, Bc
// the sums over a subtree.
#pragma once

#include "spotkin/dynamics/model.hpp"

namespace spotkin::dynamics {

template <typename P>
struct CoriolisWork {
  Motion<P> S, dS;     // column and its rate, root coordinates
  RigidInertia<P> Ic;  // subtree inertia, root coordinates
  M3<P> B11;           // subtree sum of B11
  V3<P> f0;            // subtree sum of f0
};

// y_j = Ic_j dS_j + Bc_j S_j: C_ij = S_i^T y_j for every i whose subtree holds j's.
template <typename P>
SPOTKIN_INLINE Force<P> coriolis_column(const CoriolisWork<P>& a) noexcept {
  const Force<P> IdS = apply(a.Ic, a.dS);
  return {IdS.n + mul(a.B11, a.S.w), IdS.f - cross(a.f0, a.S.w)};
}
// Row i beyond the subtree of i: C_ij = (Ic_i S_i)^T dS_j + (Bc_i^T S_i)^T S_j for a column j
// (S, dS) above body i.
template <typename P>
struct CoriolisRow {
  Force<P> IS;
  V3<P> BtS;
  SPOTKIN_INLINE P operator()(const Motion<P>& S, const Motion<P>& dS) const noexcept {
    return dot(dS, IS) + dot(S.w, BtS);
  }
};
template <typename P>
SPOTKIN_INLINE CoriolisRow<P> coriolis_row(const CoriolisWork<P>& a) noexcept {
  return {apply(a.Ic, a.S), mul_t(a.B11, a.S.w) + cross(a.f0, a.S.v)};
}

// Body k's B11 and f0 (B_k = [[B11, 0], [-[f0]x, 0]]) from its inertia I and velocity v, root coordinates.
template <typename P>
SPOTKIN_INLINE void coriolis_terms(const RigidInertia<P>& I, const Motion<P>& v, M3<P>& B, V3<P>& f0) noexcept {
  using M = typename LanesOf<P>::Scalar;
  const Force<P> iv = apply(I, v);
  B = skew_mul(v.w, I.J);
  const M3<P> Jw = mul_skew(I.J, v.w);
  const P vh = dot(v.v, I.h);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) B(r, c) = B(r, c) - Jw(r, c) - v.v[r] * I.h[c] - I.h[r] * v.v[c];
  for (int r = 0; r < 3; ++r) B(r, r) += P(M(2)) * vh;
  B(0, 1) += iv.n[2], B(0, 2) -= iv.n[1], B(1, 2) += iv.n[0];  // - [n0]x
  B(1, 0) -= iv.n[2], B(2, 0) += iv.n[1], B(2, 1) -= iv.n[0];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) B(r, c) *= P(M(0.5));
  f0 = iv.f;
}

// The chain's block of C (n x n, row stride `stride`), its columns S, dS and subtree sums in w,
// for a chain whose parent has pose T0 and velocity v0 in root coordinates (none: the root itself).
template <typename M, int L>
SPOTKIN_INLINE void coriolis_chain(const ChainModel<M, L>& model, const Pose<Pack<M, L>>* X, const Pack<M, L>* qd,
                                   Pack<M, L>* C, CoriolisWork<Pack<M, L>>* w, int stride = -1,
                                   const Pose<Pack<M, L>>* T0 = nullptr,
                                   const Motion<Pack<M, L>>* v0 = nullptr) noexcept {
  using P = Pack<M, L>;
  const int n = model.dof();
  if (stride < 0) stride = n;
  Pose<P> T = T0 ? compose(*T0, X[0]) : X[0];
  Motion<P> v = v0 ? *v0 : zero_motion<P>();
  for (int j = 0; j < n; ++j) {
    if (j > 0) T = compose(T, X[j]);
    w[j].S = to_parent(T, model.subspace(j));
    v.w += scale(w[j].S.w, qd[j]), v.v += scale(w[j].S.v, qd[j]);
    w[j].dS = crm(v, w[j].S);
    w[j].Ic = to_parent(T, model.inertia(j));
    coriolis_terms(w[j].Ic, v, w[j].B11, w[j].f0);
  }
  for (int j = n - 1; j > 0; --j) {  // subtree sums
    add_to(w[j - 1].Ic, w[j].Ic);
    add_to(w[j - 1].B11, w[j].B11);
    w[j - 1].f0 += w[j].f0;
  }
  for (int j = 0; j < n; ++j) {
    const CoriolisWork<P>& a = w[j];
    const Force<P> y = coriolis_column(a);
    for (int i = 0; i <= j; ++i) C[i * stride + j] = dot(w[i].S, y);
    const CoriolisRow<P> row = coriolis_row(a);
    for (int k = 0; k < j; ++k) C[j * stride + k] = row(w[k].S, w[k].dS);
  }
}

}  // namespace spotkin::dynamics
