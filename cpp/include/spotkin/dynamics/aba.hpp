// Articulated-body algorithm for forward dynamics, RBDA Table 7.1, on one
// block of lanes, in three passes so that a floating base can sit between the
// second and the third (the floating-base form, RBDA section 9.3: the chains'
// articulated inertias are gathered at the body, its acceleration solved, then
// passed down).
#pragma once

#include "spotkin/dynamics/model.hpp"

namespace spotkin::dynamics {

template <typename P>
struct AbaWork {
  Motion<P> c;     // velocity-product acceleration v_i x S qd
  Inertia6<P> IA;  // articulated inertia
  Force<P> pA;     // articulated bias force
  Force<P> U;      // IA S
  P Dinv, u;       // (S^T U)^-1, tau - S^T pA
};

// Passes 1 and 2 for a chain hanging from a parent moving with v0: fills w and
// returns in (IA_root, pA_root) the chain's articulated inertia and bias force
// as seen by the parent (its coordinates); skipped when root is false.
template <typename M, int L>
SPOTKIN_INLINE void aba_down_up(const ChainModel<M, L>& model, const Pose<Pack<M, L>>* X, const Pack<M, L>* qd,
                                const Pack<M, L>* tau, const Motion<Pack<M, L>>& v0, AbaWork<Pack<M, L>>* w,
                                bool root, Inertia6<Pack<M, L>>* IA_root, Force<Pack<M, L>>* pA_root) noexcept {
  using P = Pack<M, L>;
  const int n = model.dof();
  Motion<P> v = v0;
  for (int j = 0; j < n; ++j) {  // pass 1: v_i, c_i, IA_i = I_i, pA_i = v_i x* I_i v_i
    const Motion<P> vJ = model.subspace_times(j, qd[j]);
    Motion<P> vj = to_child(X[j], v);
    vj.w += vJ.w, vj.v += vJ.v;
    w[j].c = crm(vj, vJ);
    const RigidInertia<P> I = model.inertia(j);
    w[j].IA = general(I);
    w[j].pA = crf(vj, apply(I, vj));
    v = vj;
  }
  for (int j = n - 1; j >= 0; --j) {  // pass 2
    AbaWork<P>& a = w[j];
    const Motion<P> S = model.subspace(j);
    a.U = apply(a.IA, S);                      // U_i = IA_i S_i
    a.Dinv = P(M(1)) / dot(S, a.U);            // D_i = S_i^T U_i
    a.u = tau[j] - dot(S, a.pA);               // u_i = tau_i - S_i^T pA_i
    if (j == 0 && !root) break;
    Inertia6<P> Ia = a.IA;                     // Ia = IA_i - U_i D_i^-1 U_i^T
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        Ia.A(r, c) -= a.U.n[r] * a.U.n[c] * a.Dinv;
        Ia.B(r, c) -= a.U.n[r] * a.U.f[c] * a.Dinv;
        Ia.C(r, c) -= a.U.f[r] * a.U.f[c] * a.Dinv;
      }
    const Force<P> Iac = apply(Ia, a.c);       // pa = pA_i + Ia c_i + U_i D_i^-1 u_i
    const P k = a.Dinv * a.u;
    const Force<P> pa{a.pA.n + Iac.n + scale(a.U.n, k), a.pA.f + Iac.f + scale(a.U.f, k)};
    const Inertia6<P> Ip = to_parent(X[j], Ia);  // IA_parent += X^T Ia X, pA_parent += X^T pa
    const Force<P> pp = to_parent(X[j], pa);
    if (j > 0) {
      add_to(w[j - 1].IA, Ip);
      w[j - 1].pA.n += pp.n, w[j - 1].pA.f += pp.f;
    } else {
      *IA_root = Ip;
      *pA_root = pp;
    }
  }
}

// Pass 3: qdd_i = D_i^-1 (u_i - U_i^T a'), a' = X a_parent + c_i, a_i = a' + S_i qdd_i.
template <typename M, int L>
SPOTKIN_INLINE void aba_down(const ChainModel<M, L>& model, const Pose<Pack<M, L>>* X,
                             const AbaWork<Pack<M, L>>* w, const Motion<Pack<M, L>>& a0, Pack<M, L>* qdd) noexcept {
  using P = Pack<M, L>;
  Motion<P> a = a0;
  for (int j = 0; j < model.dof(); ++j) {
    Motion<P> ap = to_child(X[j], a);
    ap.w += w[j].c.w, ap.v += w[j].c.v;
    qdd[j] = w[j].Dinv * (w[j].u - dot(ap, w[j].U));
    const Motion<P> sa = model.subspace_times(j, qdd[j]);
    a = {ap.w + sa.w, ap.v + sa.v};
  }
}

}  // namespace spotkin::dynamics
