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

template <typename M, int L>
SPOTKIN_INLINE void coriolis_chain(const ChainModel<M, L>& model, const Pose<Pack<M, L>>* X, const Pack<M, L>* qd,
                                   Pack<M, L>* C, CoriolisWork<Pack<M, L>>* w) noexcept {
  using P = Pack<M, L>;
  const int n = model.dof();
  Pose<P> T = X[0];
  Motion<P> v = zero_motion<P>();
  for (int j = 0; j < n; ++j) {
    if (j > 0) T = compose(T, X[j]);
    w[j].S = to_parent(T, model.subspace(j));
    v.w += scale(w[j].S.w, qd[j]), v.v += scale(w[j].S.v, qd[j]);
    w[j].dS = crm(v, w[j].S);
    const RigidInertia<P> I = to_parent(T, model.inertia(j));
    const Force<P> f0 = apply(I, v);
    M3<P> B = skew_mul(v.w, I.J);
    const M3<P> Jw = mul_skew(I.J, v.w);
    const P vh = dot(v.v, I.h);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) B(r, c) = B(r, c) - Jw(r, c) - v.v[r] * I.h[c] - I.h[r] * v.v[c];
    for (int r = 0; r < 3; ++r) B(r, r) += P(M(2)) * vh;
    B(0, 1) += f0.n[2], B(0, 2) -= f0.n[1], B(1, 2) += f0.n[0];  // - [n0]x
    B(1, 0) -= f0.n[2], B(2, 0) += f0.n[1], B(2, 1) -= f0.n[0];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) B(r, c) *= P(M(0.5));
    w[j].Ic = I, w[j].B11 = B, w[j].f0 = f0.f;
  }
  for (int j = n - 1; j > 0; --j) {  // subtree sums
    add_to(w[j - 1].Ic, w[j].Ic);
    add_to(w[j - 1].B11, w[j].B11);
    w[j - 1].f0 += w[j].f0;
  }
  for (int j = 0; j < n; ++j) {
    const CoriolisWork<P>& a = w[j];
    const Force<P> IdS = apply(a.Ic, a.dS);  // y_j = Ic_j dS_j + Bc_j S_j
    const V3<P> Bw = mul(a.B11, a.S.w);
    const Force<P> y{IdS.n + Bw, IdS.f - cross(a.f0, a.S.w)};
    for (int i = 0; i <= j; ++i) C[i * n + j] = dot(w[i].S, y);
    const Force<P> IS = apply(a.Ic, a.S);  // row j beyond the diagonal
    const V3<P> BtS = mul_t(a.B11, a.S.w) + cross(a.f0, a.S.v);
    for (int k = 0; k < j; ++k) C[j * n + k] = dot(w[k].dS, IS) + dot(w[k].S.w, BtS);
  }
}

}  // namespace spotkin::dynamics
