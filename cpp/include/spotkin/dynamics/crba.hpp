// Composite-rigid-body algorithm for the joint-space inertia matrix, RBDA
// Table 6.2, on one block of lanes.
#pragma once

#include "spotkin/dynamics/model.hpp"

namespace spotkin::dynamics {

// H (n x n, row-major lanes) of the chain. Ic: n composite inertias of workspace.
// With root_inertia / root_force given (floating base), also the chain's
// composite inertia and its columns' forces F_j = X^T Ic_j S_j, both carried to
// the parent's coordinates.
template <typename M, int L>
SPOTKIN_INLINE void crba_chain(const ChainModel<M, L>& model, const Pose<Pack<M, L>>* X, Pack<M, L>* H,
                               RigidInertia<Pack<M, L>>* Ic, RigidInertia<Pack<M, L>>* root_inertia = nullptr,
                               Force<Pack<M, L>>* root_force = nullptr) noexcept {
  using P = Pack<M, L>;
  const int n = model.dof();
  for (int j = 0; j < n; ++j) Ic[j] = model.inertia(j);
  for (int j = n - 1; j >= 0; --j) {
    Force<P> F = apply(Ic[j], model.subspace(j));  // F = Ic_i S_i, H_ii = S_i^T F
    H[j * n + j] = dot(model.subspace(j), F);
    for (int k = j; k > 0; --k) {  // F = X^T F up the chain, H_ij = H_ji = S_j^T F
      F = to_parent(X[k], F);
      H[(k - 1) * n + j] = H[j * n + k - 1] = dot(model.subspace(k - 1), F);
    }
    if (root_force) root_force[j] = to_parent(X[0], F);
    if (j > 0) add_to(Ic[j - 1], to_parent(X[j], Ic[j]));  // Ic_parent += X^T Ic_i X
  }
  if (root_inertia) *root_inertia = to_parent(X[0], Ic[0]);
}

}  // namespace spotkin::dynamics
