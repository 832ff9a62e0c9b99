// Composite-rigid-body algorithm for the joint-space inertia matrix, RBDA
// Table 6.2, on one block of lanes.
#pragma once

#include "spotkin/dynamics/model.hpp"

namespace spotkin::dynamics {

// One chain's CRBA: put(i, j, A_ij) for j <= i (the chain's joint indices). q, sines, cosines: the
// joints' values and joint_trig's; Ic: n composite inertias of workspace. Every transform goes
// through the joint's pieces in their sparse forms (ChainModel::to_parent): for a URDF joint (a
// translation, a rotation about +-e_k) about a third of a dense transform's operations.
// On a floating body (root non-null), body_column(j, F) also receives joint j's column force
// F_j = X^T Ic_j S_j in the root frame, and the chain's composite inertia there is added to *root.
template <typename M, int L, typename Put, typename BodyColumn>
SPOTKIN_INLINE void crba_chain(const ChainModel<M, L>& model, const Pack<M, L>* q, const Pack<M, L>* sines,
                               const Pack<M, L>* cosines, SymInertia<Pack<M, L>>* Ic, Put&& put,
                               BodyColumn&& body_column, SymInertia<Pack<M, L>>* root) noexcept {
  const int n = model.dof();
  for (int j = 0; j < n; ++j) Ic[j] = symmetric(model.inertia(j));
  for (int j = n - 1; j >= 0; --j) {
    auto F = model.inertia_subspace(j, Ic[j]);  // F = Ic_j S_j, A_jj = S_j^T F
    put(j, j, model.project(j, F));
    for (int i = j; i > 0; --i) {  // F = X^T F up the chain, A_ij = S_i^T F
      model.to_parent(i, q[i], sines[i], cosines[i], F);
      put(j, i - 1, model.project(i - 1, F));
    }
    if (root) {
      model.to_parent(0, q[0], sines[0], cosines[0], F);
      body_column(j, F);
    }
    if (j > 0 || root) {  // Ic_parent += X^T Ic_j X
      model.to_parent(j, q[j], sines[j], cosines[j], Ic[j]);
      add_to(j > 0 ? Ic[j - 1] : *root, Ic[j]);
    }
  }
}

}  // namespace spotkin::dynamics
