"""A chain's dynamics on its inertials (:mod:`spotkin.dynamics`): :class:`spotkin.Chain` takes these
methods from the base class here."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real, broadcast_lead
from .._support.forward import core_method
from ..dynamics import inertia
from ..dynamics import rigid_body as dynamics


class _ChainDynamicsMethods:
    """The dynamics methods of :class:`spotkin.Chain` (its base class; see there)."""

    __slots__ = ()

    @core_method("_dynamics", "rnea")
    def inverse_dynamics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        *,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Joint torques tau = A(q) qdd + C(q, qd) qd + G(q), (..., dof): recursive Newton–Euler.

        q, qd, qdd (..., dof) broadcast; ``gravity`` (3,) or (..., 3) in the frame before
        :attr:`base` (m/s²). Needs :attr:`inertials`; conventions in :mod:`spotkin.dynamics`.
        ``out``: an array of the result's shape and dtype to write into and return (every
        dynamics method takes it)."""
        return self._dynamics_core().rnea(q, qd, qdd, gravity, out)

    @core_method("_dynamics", "crba")
    def mass_matrix(self, q: ArrayLike, layout: str = "full", *, out: np.ndarray | None = None) -> np.ndarray:
        """The joint-space inertia matrix A(q), (..., dof, dof): composite-rigid-body algorithm.
        ``layout="lower"`` zeroes the strict upper triangle; ``"packed"`` gives the lower triangle
        row by row, (..., dof (dof + 1) / 2) (:func:`spotkin.dynamics.unpack_symmetric`)."""
        return self._dynamics_core().crba(q, layout, out)

    @core_method("_dynamics", "gravity")
    def gravity(
        self, q: ArrayLike, gravity: ArrayLike = (0.0, 0.0, -9.81), *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """The gravity torques G(q) = dU/dq, (..., dof)."""
        return self._dynamics_core().gravity(q, gravity, out)

    @core_method("_dynamics", "nonlinear_effects")
    def nonlinear_effects(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        *,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """h = C(q, qd) qd + G(q), (..., dof)."""
        return self._dynamics_core().nonlinear_effects(q, qd, gravity, out)

    @core_method("_dynamics", "coriolis_matrix")
    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """C(q, qd), (..., dof, dof), the form for which dA/dt - 2 C is skew-symmetric."""
        return self._dynamics_core().coriolis_matrix(q, qd, out)

    @core_method("_dynamics", "aba")
    def forward_dynamics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        tau: ArrayLike,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        *,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Joint accelerations qdd = A(q)^-1 (tau - C qd - G), (..., dof): articulated-body algorithm."""
        return self._dynamics_core().aba(q, qd, tau, gravity, out)

    def _tree(self, joints=None):
        """The fixed-base tree of this chain for :func:`spotkin.inertia.tree_of` (a robot's is its own)."""
        if joints is not None:
            raise ValueError("joints is for robots: a chain's tree has the chain's joints")
        return inertia.chain_tree(self)

    def _dynamics_core(self):
        """The C++ dynamics of this chain and its inertials (spotkin.dynamics), built on first use."""
        core = self._dynamics
        if core is None:
            core = self._dynamics = dynamics._core_of(self, None)
        return core

    def center_of_mass(self, q: ArrayLike) -> np.ndarray:
        """The links' centre of mass (..., 3) in the frame before :attr:`base` (needs :attr:`inertials`)."""
        return dynamics.center_of_mass(self, q)

    def center_of_mass_jacobian(self, q: ArrayLike) -> np.ndarray:
        """J_com (..., 3, dof): d com / dt = J_com qd, in the frame before :attr:`base`."""
        return dynamics.center_of_mass_jacobian(self, q)

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """The links' kinetic energy qd^T A(q) qd / 2, (...), in J."""
        return dynamics.kinetic_energy(self, q, qd)

    def potential_energy(self, q: ArrayLike, gravity: ArrayLike = (0.0, 0.0, -9.81)) -> np.ndarray:
        """The links' potential energy -m g . c, (...), in J (zero with the centre of mass at the origin of
        the frame before :attr:`base`); :meth:`gravity` is its gradient. ``gravity`` (3,) or (..., 3)."""
        return dynamics.potential_energy(self, q, gravity)

    def joint_torques_from_forces(self, q: ArrayLike, forces: ArrayLike) -> np.ndarray:
        """tau = J(q)^T F, (..., dof): the joint torques that balance, statically, a wrench F the tool
        exerts on its surroundings (gravity aside; add :meth:`gravity`).

        ``forces`` (..., 6) is [force; moment about the tool point], base axes, N and N m (J is
        :meth:`jacobian` with ``frame="base"``); (..., 3), a pure force at the tool point. Leading
        dimensions broadcast with q's."""
        F = as_real(forces, "forces")
        if F.ndim == 0 or F.shape[-1] not in (3, 6):
            raise ValueError(f"forces must have shape (..., 6) or (..., 3), got {F.shape}")
        J = self._core.jacobian(q, F.shape[-1], False)
        if J.dtype == np.float32 and F.dtype != np.float32:
            J = J.astype(np.float64)
        lead = broadcast_lead(q=(J.shape[:-2], J.shape), forces=(F.shape[:-1], F.shape))
        J = np.broadcast_to(J, (*lead, *J.shape[-2:]))
        F = np.broadcast_to(F.astype(J.dtype, copy=False), (*lead, F.shape[-1]))
        with np.errstate(invalid="ignore", over="ignore"):
            tau = np.einsum("...ij,...i->...j", J, F)
        # a sample with NaN or Inf anywhere gets NaN, not a partly infinite row
        return np.where(np.isfinite(F).all(axis=-1, keepdims=True), tau, np.nan).astype(J.dtype, copy=False)
