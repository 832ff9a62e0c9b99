// Recursive Newton-Euler inverse dynamics, RBDA Table 5.1, on one block of
// lanes. Gravity enters as a fictitious acceleration of the root, a_0 = -g
// (RBDA section 5.3).
#pragma once

#include "spotkin/dynamics/model.hpp"

namespace spotkin::dynamics {

// tau = S^T f over the chain hanging from a parent moving with (v0, a0) in the
// parent's coordinates; returns the chain's force on the parent, in the parent's
// coordinates. X: poses (ChainModel::poses); f: n forces of workspace.
template <typename M, int L>
SPOTKIN_INLINE Force<Pack<M, L>> rnea_chain(const ChainModel<M, L>& model, const Pose<Pack<M, L>>* X,
                                            const Pack<M, L>* qd, const Pack<M, L>* qdd,
                                            const Motion<Pack<M, L>>& v0, const Motion<Pack<M, L>>& a0,
                                            Pack<M, L>* tau, Force<Pack<M, L>>* f) noexcept {
  using P = Pack<M, L>;
  const int n = model.dof();
  Motion<P> v = v0, a = a0;
  for (int j = 0; j < n; ++j) {
    Motion<P> vj = to_child(X[j], v);  // v_i = X v_parent + S qd
    model.add_subspace(j, qd[j], vj);
    const Motion<P> c = model.cross_subspace(j, vj, qd[j]);
    Motion<P> aj = to_child(X[j], a);  // a_i = X a_parent + S qdd + v_i x S qd
    model.add_subspace(j, qdd[j], aj);
    aj.w += c.w, aj.v += c.v;
    const RigidInertia<P> I = model.inertia(j);
    const Force<P> fa = apply(I, aj), fv = crf(vj, apply(I, vj));  // f_i = I a_i + v_i x* I v_i
    f[j] = {fa.n + fv.n, fa.f + fv.f};
    v = vj, a = aj;
  }
  for (int j = n - 1; j >= 0; --j) {  // tau_i = S^T f_i, f_parent += X^T f_i
    tau[j] = model.project(j, f[j]);
    if (j > 0) {
      const Force<P> up = to_parent(X[j], f[j]);
      f[j - 1].n += up.n, f[j - 1].f += up.f;
    }
  }
  return to_parent(X[0], f[0]);
}

// rnea_chain at rest (qd = qdd = 0, v0 = 0): G(q) when the root's acceleration is the linear
// a0 = -g (its angular part zero). The velocity terms of RBDA Table 5.1 vanish, and with them
// every angular acceleration: a_i = X a_parent is (0, R^T a_parent), f_i = I a_i is
// (h x a_i, m a_i), tau_i = S^T f_i, f_parent += X^T f_i. The same values as rnea_chain with zero
// rates up to the sign of a zero (the dropped terms are exact zeros), in about a third of the
// forward pass's arithmetic.
template <typename M, int L>
SPOTKIN_INLINE Force<Pack<M, L>> gravity_chain(const ChainModel<M, L>& model,
                                               const Pose<Pack<M, L>>* X, const V3<Pack<M, L>>& a0,
                                               Pack<M, L>* tau, Force<Pack<M, L>>* f) noexcept {
  using P = Pack<M, L>;
  const int n = model.dof();
  V3<P> a = a0;
  for (int j = 0; j < n; ++j) {
    a = mul_t(X[j].R, a);
    const RigidInertia<P> I = model.inertia(j);
    f[j] = {cross(I.h, a), scale(a, I.m)};
  }
  for (int j = n - 1; j >= 0; --j) {
    tau[j] = model.project(j, f[j]);
    if (j > 0) {
      const Force<P> up = to_parent(X[j], f[j]);
      f[j - 1].n += up.n, f[j - 1].f += up.f;
    }
  }
  return to_parent(X[0], f[0]);
}

}  // namespace spotkin::dynamics
