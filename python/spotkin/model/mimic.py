"""Chains with mimic joints: the full chain underneath, moved through q_full = M q + b.

A URDF ``<mimic>`` joint follows its leader, ``q_follower = multiplier * q_leader + offset``. A chain
whose path holds mimic joints has ``n_full`` joints but fewer independent variables: its variables are
the path's independent joints and the leaders of its mimic joints (a leader off the path, as a
gripper's other finger, included), in the order they first drive a joint of the path. With M the
(n_full, n) matrix of multipliers (1 for a joint that is its own variable) and b the offsets:

- kinematics: ``fk(q) = fk_full(M q + b)``, the same for :meth:`frames` (whose indices are the full
  chain's frames), ``J = J_full M``;
- dynamics (Lagrange's equations under the constraint): ``tau = M^T tau_full(M q + b, M qd, M qdd)``,
  ``A = M^T A_full M``, ``C = M^T C_full M``, ``G = M^T G_full``; the bodies are the full chain's;
- closed-form IK: when every variable drives exactly one joint of the path with a non-zero multiplier
  (M is diagonal: a mimic joint whose leader is off the path), the full chain's closed form solves the
  pose and each solution maps back, ``q = (q_full - b) / m``. When a mimic joint and its leader are
  both on the path, no closed form here accounts for the coupling: :attr:`ik_kind` and every closed-form
  call raise ``ValueError`` and point to :meth:`ik_differential`, which works on the coupled chain.

The C++ kernels are the full chain's; the mapping is done here.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_finite, as_index, as_real, broadcast_lead, into_out
from ..dynamics.rigid_body import _check_layout, _in_layout
from .chain import Chain, _limit_override
from .chain_ik import ChainSolutions, IKDifferentialInfo, _into_outs, _scalar

__all__ = ["MimicChain"]


def _log_rotation(R: np.ndarray) -> np.ndarray:
    """log of rotations (..., 3, 3) as axis-angle vectors (..., 3), as the C++ differential IK."""
    w = 0.5 * np.stack(
        [R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1
    )
    c = np.clip(0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    s = np.linalg.norm(w, axis=-1)
    theta = np.arctan2(s, c)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(s < 1e-4, 1.0 + theta * theta / 6.0, theta / s)
    out = scale[..., None] * w
    near_pi = c <= -0.9
    if np.any(near_pi):
        for i in zip(*np.nonzero(near_pi)):
            Ri, ci = R[i], c[i]
            B = 0.5 * (Ri + Ri.T) - ci * np.eye(3)
            k = int(np.argmax(np.diag(B)))
            axis = B[:, k] / math.sqrt(max(B[k, k], 0.0) * (1.0 - ci))
            if axis @ w[i] < 0:
                axis = -axis
            out[i] = theta[i] * axis / np.linalg.norm(axis)
    return out


def _dls(J: np.ndarray, e: np.ndarray, lambda2: float) -> np.ndarray:
    """dq = J^T (J J^T + lambda^2 I)^-1 e per sample (the pseudo-inverse when the damping is below the
    rounding of J J^T, or the factorisation fails)."""
    m, n = J.shape[-2:]
    out = np.empty(J.shape[:-2] + (n,))
    frobenius2 = np.einsum("...ij,...ij->...", J, J)
    tiny = lambda2 <= np.finfo(float).eps * frobenius2
    for i in range(J.shape[0]):
        Ji, ei = J[i], e[i]
        if not tiny[i]:
            try:
                if m <= n:
                    out[i] = Ji.T @ np.linalg.solve(Ji @ Ji.T + lambda2 * np.eye(m), ei)
                else:
                    out[i] = np.linalg.solve(Ji.T @ Ji + lambda2 * np.eye(n), Ji.T @ ei)
                if np.isfinite(out[i]).all():
                    continue
            except np.linalg.LinAlgError:
                pass
        out[i] = np.linalg.pinv(Ji) @ ei
    return out


def mapped_limits(M: np.ndarray, b: np.ndarray, limits: np.ndarray) -> np.ndarray:
    """(n_full, 2) limits of the full chain from the variables' (n, 2): each joint's is its variable's
    mapped by its multiplier and offset (a mimic joint's own ``<limit>`` is not used, as in Pinocchio);
    a joint that no variable drives (multiplier 0) is held at its offset."""
    out = np.empty((M.shape[0], 2))
    for i in range(M.shape[0]):
        (cols,) = np.nonzero(M[i])
        if len(cols) == 0:
            out[i] = (b[i], b[i])
            continue
        with np.errstate(invalid="ignore"):
            ends = M[i, cols[0]] * limits[cols[0]] + b[i]
        out[i] = (np.min(ends), np.max(ends))
    return out


def _rigid(T: np.ndarray) -> np.ndarray:
    """(...,) bool: finite rigid transforms as the closed-form IK accepts them."""
    finite = np.isfinite(T).all(axis=(-2, -1))
    safe = np.where(finite[..., None, None], T, 0.0)
    row = np.abs(safe[..., 3, :] - np.array([0.0, 0.0, 0.0, 1.0])).max(axis=-1) <= 1e-9
    R = safe[..., :3, :3]
    orth = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(axis=(-2, -1)) <= 1e-6
    return finite & row & orth & (np.linalg.det(R) > 0)


class MimicChain(Chain):
    """A :class:`spotkin.Chain` whose path holds mimic joints (see :mod:`spotkin.model.mimic`): its q holds
    the independent variables (:attr:`joint_names`), the full chain (:attr:`full_chain`) moves through
    ``q_full = M q + b`` (:attr:`mimic_matrix`, :attr:`mimic_offset`). Build one with
    :meth:`spotkin.Chain.from_urdf` or :meth:`spotkin.Robot.chain`."""

    __slots__ = ("_M", "_b", "_diagonal", "_full", "_sigma")

    @classmethod
    def _make(cls, full: Chain, M, b, names, limits, sigma) -> MimicChain:
        chain = cls.__new__(cls)
        M = np.array(M, dtype=float)
        b = np.array(b, dtype=float)
        n_full, n = M.shape
        if full.dof != n_full or b.shape != (n_full,) or len(names) != n:
            raise ValueError("mimic mapping: inconsistent shapes")
        M.setflags(write=False)
        b.setflags(write=False)
        chain._full = full
        chain._M, chain._b = M, b
        chain._names = tuple(names)
        chain._sigma = np.array(sigma, dtype=np.int8).reshape(n)
        table = np.array(limits, dtype=float).reshape(n, 2)
        chain._limits = (table[:, 0].copy(), table[:, 1].copy())
        chain._diagonal = (
            n == n_full and np.array_equal(M, np.diag(np.diag(M))) and bool(np.all(np.diag(M) != 0))
        )
        chain._core = None  # never the full chain's kernel with these q: everything goes through _full
        chain._rows = None
        chain._convention = "joints"
        chain._joints = None
        chain._base = full._base
        chain._tool = full._tool
        chain._ik = None
        chain._ik_tolerance = full._ik_tolerance
        chain._inertials = full.inertials
        return chain

    def _derived(self, full: Chain) -> MimicChain:
        return MimicChain._make(
            full, self._M, self._b, self._names, np.stack(self._limits, axis=1), self._sigma
        )

    # -- the mapping ---------------------------------------------------------------------------------

    @property
    def full_chain(self) -> Chain:
        """The chain of every moving joint on the path (mimic joints included), ``q_full = M q + b``. Its
        bodies (:attr:`inertials`) and frames (:meth:`frames`) are this chain's."""
        return self._full

    @property
    def full_joint_names(self) -> tuple[str, ...] | None:
        """The names of :attr:`full_chain`'s joints, mimic joints included."""
        return self._full.joint_names

    @property
    def mimic_matrix(self) -> np.ndarray:
        """M (n_full, n): column k holds the multipliers of the joints variable k drives."""
        return self._M.copy()

    @property
    def mimic_offset(self) -> np.ndarray:
        """b (n_full,): the mimic joints' offsets (0 for the others)."""
        return self._b.copy()

    def full_q(self, q: ArrayLike) -> np.ndarray:
        """q (..., dof) -> q_full = M q + b (..., n_full)."""
        return self._expand(q, "q", offset=True)

    def _expand(self, value, name: str, offset: bool) -> np.ndarray:
        arr = as_real(value, name)
        if arr.ndim < 1 or arr.shape[-1] != self.dof:
            raise ValueError(f"{name} must have shape (..., {self.dof}), got {arr.shape}")
        dtype = np.float32 if arr.dtype == np.float32 else np.float64
        with np.errstate(invalid="ignore", over="ignore"):
            out = np.einsum("ij,...j->...i", self._M.astype(dtype), arr.astype(dtype, copy=False))
            if offset:
                out = out + self._b.astype(dtype)
        return out.astype(dtype, copy=False)

    def _row(self, value: np.ndarray) -> np.ndarray:
        """(..., n_full) -> M^T value (..., n), keeping value's dtype."""
        with np.errstate(invalid="ignore", over="ignore"):
            return np.einsum("...i,ik->...k", value, self._M.astype(value.dtype)).astype(
                value.dtype, copy=False
            )

    def _square(self, value: np.ndarray) -> np.ndarray:
        """(..., n_full, n_full) -> M^T value M (..., n, n)."""
        M = self._M.astype(value.dtype)
        with np.errstate(invalid="ignore", over="ignore"):
            return np.einsum("ik,...ij,jl->...kl", M, value, M).astype(value.dtype, copy=False)

    def _columns(self, value: np.ndarray) -> np.ndarray:
        """(..., r, n_full) -> value M (..., r, n)."""
        with np.errstate(invalid="ignore", over="ignore"):
            return np.einsum("...ri,ik->...rk", value, self._M.astype(value.dtype)).astype(
                value.dtype, copy=False
            )

    # -- description ---------------------------------------------------------------------------------

    @property
    def dof(self) -> int:
        """Number of independent variables (the mimic joints follow them)."""
        return self._M.shape[1]

    @property
    def sigma(self) -> np.ndarray:
        """The variables' types, (dof,): 0 revolute, 1 prismatic."""
        return self._sigma.copy()

    def with_inertials(self, mass: ArrayLike, com: ArrayLike, inertia: ArrayLike) -> Chain:
        """As :meth:`spotkin.Chain.with_inertials`, with one body per joint of :attr:`full_chain`
        (n_full rows: a mimic joint moves a body too)."""
        return self._derived(self._full.with_inertials(mass, com, inertia))

    def with_limits(self, limits) -> Chain:
        """As :meth:`spotkin.Chain.with_limits`, for the variables (names: :attr:`joint_names`); the mimic
        joints' limits follow their leaders'."""
        lower, upper = _limit_override(limits, self._limits, self._names, "limits")
        table = np.stack([lower, upper], axis=1)
        full = self._full.with_limits(mapped_limits(self._M, self._b, table))
        return MimicChain._make(full, self._M, self._b, self._names, table, self._sigma)

    def with_ik_tolerance(self, angle: float = 1e-3, distance: float = 1e-3) -> Chain:
        """As :meth:`spotkin.Chain.with_ik_tolerance`, on :attr:`full_chain`."""
        return self._derived(self._full.with_ik_tolerance(angle, distance))

    # -- kinematics ----------------------------------------------------------------------------------

    def fk(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """Base-to-tool transform: q (..., dof) -> (..., 4, 4), the full chain's at ``M q + b``."""
        return self._full.fk(self.full_q(q), out=out)

    def frames(self, q: ArrayLike) -> np.ndarray:
        """Every frame of :attr:`full_chain` (one per joint, mimic joints included): q (..., dof) ->
        (..., n_full + 2, 4, 4)."""
        return self._full.frames(self.full_q(q))

    def jacobian(
        self,
        q: ArrayLike,
        frame: str | int = "base",
        *,
        point: str | int = "tool",
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """J_full(M q + b) M, (..., 6, dof): a variable's column sums the columns of the joints it drives,
        times their multipliers. ``frame`` and ``point`` index :attr:`full_chain`'s frames."""
        return into_out(self._columns(self._full.jacobian(self.full_q(q), frame, point=point)), out)

    def position_jacobian(
        self, q: ArrayLike, frame: str | int = "base", *, point: str | int = "tool"
    ) -> np.ndarray:
        """The top three rows of :meth:`jacobian`, (..., 3, dof)."""
        return self._columns(self._full.position_jacobian(self.full_q(q), frame, point=point))

    def joint_torques_from_forces(self, q: ArrayLike, forces: ArrayLike) -> np.ndarray:
        """tau = (J_full M)^T F, (..., dof) (see :meth:`spotkin.Chain.joint_torques_from_forces`)."""
        return self._row(self._full.joint_torques_from_forces(self.full_q(q), forces))

    # -- dynamics (Lagrange's equations with q_full = M q + b) ----------------------------------------

    def inverse_dynamics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        *,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """tau = M^T tau_full(M q + b, M qd, M qdd), (..., dof)."""
        full = self._full.inverse_dynamics(
            self.full_q(q), self._expand(qd, "qd", False), self._expand(qdd, "qdd", False), gravity
        )
        return into_out(self._row(full), out)

    def mass_matrix(self, q: ArrayLike, layout: str = "full", *, out: np.ndarray | None = None) -> np.ndarray:
        """A = M^T A_full(M q + b) M, (..., dof, dof); ``layout`` as :meth:`Chain.mass_matrix`."""
        layout = _check_layout(layout)  # before the work
        return into_out(_in_layout(self._square(self._full.mass_matrix(self.full_q(q))), layout), out)

    def gravity(
        self, q: ArrayLike, gravity: ArrayLike = (0.0, 0.0, -9.81), *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """G = M^T G_full(M q + b), (..., dof)."""
        return into_out(self._row(self._full.gravity(self.full_q(q), gravity)), out)

    def nonlinear_effects(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        *,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """h = M^T h_full(M q + b, M qd), (..., dof)."""
        full = self._full.nonlinear_effects(self.full_q(q), self._expand(qd, "qd", False), gravity)
        return into_out(self._row(full), out)

    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """C = M^T C_full(M q + b, M qd) M, (..., dof, dof): dA/dt - 2 C stays skew-symmetric."""
        full = self._full.coriolis_matrix(self.full_q(q), self._expand(qd, "qd", False))
        return into_out(self._square(full), out)

    def forward_dynamics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        tau: ArrayLike,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        *,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """qdd = A^-1 (tau - h), (..., dof), with :meth:`mass_matrix` and :meth:`nonlinear_effects`."""
        A = self.mass_matrix(q)
        h = self.nonlinear_effects(q, qd, gravity)
        tau = as_real(tau, "tau")
        if tau.ndim < 1 or tau.shape[-1] != self.dof:
            raise ValueError(f"tau must have shape (..., {self.dof}), got {tau.shape}")
        lead = broadcast_lead(
            q=(A.shape[:-2], A.shape), qd=(h.shape[:-1], h.shape), tau=(tau.shape[:-1], tau.shape)
        )
        dtype = np.float32 if A.dtype == np.float32 and tau.dtype == np.float32 else np.float64
        A = np.broadcast_to(A, (*lead, self.dof, self.dof)).astype(np.float64)
        rhs = np.broadcast_to(tau, (*lead, self.dof)).astype(np.float64) - np.broadcast_to(
            h, (*lead, self.dof)
        )
        qdd = np.full((*lead, self.dof), np.nan)
        finite = np.isfinite(A).all(axis=(-2, -1)) & np.isfinite(rhs).all(axis=-1)
        if finite.any():
            qdd[finite] = np.linalg.solve(A[finite], rhs[finite][..., None])[..., 0]
        return into_out(qdd.astype(dtype, copy=False), out)

    def center_of_mass(self, q: ArrayLike) -> np.ndarray:
        """The links' centre of mass (..., 3): the full chain's at ``M q + b``."""
        return self._full.center_of_mass(self.full_q(q))

    def center_of_mass_jacobian(self, q: ArrayLike) -> np.ndarray:
        """J_com_full M, (..., 3, dof)."""
        return self._columns(self._full.center_of_mass_jacobian(self.full_q(q)))

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """The full chain's kinetic energy at (M q + b, M qd), (...)."""
        return self._full.kinetic_energy(self.full_q(q), self._expand(qd, "qd", False))

    def potential_energy(self, q: ArrayLike, gravity: ArrayLike = (0.0, 0.0, -9.81)) -> np.ndarray:
        """The full chain's potential energy at M q + b, (...)."""
        return self._full.potential_energy(self.full_q(q), gravity)

    # -- closed-form IK (M diagonal only) ------------------------------------------------------------

    def _coupling(self) -> str:
        """The chain's mimic relations, as text."""
        names = self._full.joint_names or tuple(f"joint {i}" for i in range(self._M.shape[0]))
        out = []
        for i, name in enumerate(names):
            (cols,) = np.nonzero(self._M[i])
            if len(cols) == 1 and self._names[cols[0]] == name and self._M[i, cols[0]] == 1.0:
                continue  # its own variable
            terms = " + ".join(f"{self._M[i, k]:g} × {self._names[k]}" for k in cols) or "0"
            out.append(f"{name} = {terms} + {self._b[i]:g}")
        return "; ".join(out)

    @property
    def inertials(self):
        """The bodies' mass properties, one per joint of :attr:`full_chain` (n_full rows: a mimic joint
        moves a body too), or None."""
        return self._inertials

    def _ik_core(self):
        self._closed_form()
        return self._full._ik_core()

    def _closed_form(self) -> None:
        """``ValueError`` naming ik_differential when a mimic joint is coupled to another of the chain's."""
        if not self._diagonal:
            raise ValueError(
                f"no closed-form IK for this chain: its {self._M.shape[0]} joints move with {self.dof} "
                f"variables ({self._coupling()}), a mimic joint coupled to another joint of the chain; "
                "use ik_differential, which solves the coupled chain"
            )

    def _free_core(self, free_joint):
        self._closed_form()
        return self._full._free_core(free_joint)

    def _back(self, sol: ChainSolutions) -> ChainSolutions:
        m, b = np.diag(self._M), self._b
        q = ((sol.q.astype(np.float64) - b) / m).astype(sol.q.dtype, copy=False)
        return sol._replace(q=q)

    def ik_position(self, p: ArrayLike, *, out: tuple | None = None) -> ChainSolutions:
        """As :meth:`spotkin.Chain.ik_position`, solved on :attr:`full_chain` and mapped back (M diagonal);
        ``out`` is written with the result."""
        self._ik_core()
        return _into_outs(self._back(self._full.ik_position(p)), out)

    def _ik_pose_all(self, T, free_joint, free_value, out=None) -> ChainSolutions:
        """:meth:`spotkin.Chain.ik_all` for poses, solved on :attr:`full_chain` and mapped back, when every
        variable drives one joint of the chain (``ValueError`` naming :meth:`ik_differential` otherwise)."""
        self._closed_form()
        if free_joint is not None and free_value is not None:
            k = as_index(free_joint, "free_joint")
            if 0 <= k < self.dof:
                value = as_real(free_value, "free_value")
                with np.errstate(invalid="ignore", over="ignore"):
                    free_value = value * self._M[k, k] + self._b[k]
        return _into_outs(self._back(self._full.ik_all(T, free_joint, free_value)), out)

    def ik(
        self, target: ArrayLike, seed: ArrayLike | None = None, free_joint=None, free_value=None, *, out=None
    ):
        """As :meth:`spotkin.Chain.ik`, on :attr:`full_chain` (M diagonal); ``out`` is written with the
        result."""
        if free_joint is not None or free_value is not None:  # chosen among ik_all's, mapped back
            return super().ik(target, seed, free_joint, free_value, out=out)
        self._ik_core()
        if seed is not None:
            seed = self._expand(seed, "seed", offset=True)
        q, status = self._full.ik(target, seed)
        m, b = np.diag(self._M), self._b
        q = ((np.asarray(q, dtype=np.float64) - b) / m).astype(np.asarray(q).dtype, copy=False)
        return _into_outs((q, status), out)

    # -- differential IK on the coupled chain ----------------------------------------------------------

    def ik_differential(
        self,
        T_targets: ArrayLike,
        q0: ArrayLike,
        *,
        task: str = "pose",
        damping: float = 1e-2,
        position_tolerance: float = 1e-6,
        orientation_tolerance: float = 1e-6,
        max_iter: int = 100,
        max_step: float = 0.5,
    ) -> tuple[np.ndarray, IKDifferentialInfo]:
        """As :meth:`spotkin.Chain.ik_differential` (the same damped least-squares steps, limits and
        locking), on the variables: the Jacobian is ``J_full M``. Run in NumPy over the batch."""
        if task not in ("pose", "position"):
            raise ValueError(f"task must be 'pose' or 'position', got {task!r}")
        targets = as_real(T_targets, "T_targets")
        q0_arr = as_real(q0, "q0")
        n = self.dof
        if targets.ndim < 2 or targets.shape[-2:] != (4, 4):
            raise ValueError(f"T_targets must have shape (..., K, 4, 4) or (..., 4, 4), got {targets.shape}")
        if q0_arr.ndim < 1 or q0_arr.shape[-1] != n:
            raise ValueError(f"q0 must have shape (..., {n}), got {q0_arr.shape}")
        single = targets.ndim - 2 <= q0_arr.ndim - 1
        path = targets[..., None, :, :] if single else targets
        lead = broadcast_lead(
            T_targets=(path.shape[:-3], targets.shape), q0=(q0_arr.shape[:-1], q0_arr.shape)
        )
        K = path.shape[-3]
        damping = float(as_finite(damping, "damping", 0.0, strict=True))
        max_step = float(as_finite(max_step, "max_step", 0.0, strict=True))
        position_tolerance = float(as_finite(position_tolerance, "position_tolerance"))
        orientation_tolerance = float(as_finite(orientation_tolerance, "orientation_tolerance"))
        max_iter = as_index(max_iter, "max_iter")
        if not 0 <= max_iter <= 2**31 - 1:
            raise ValueError(f"max_iter must be an int in [0, 2**31 - 1], got {max_iter!r}")
        rows = 6 if task == "pose" else 3
        B = int(np.prod(lead, dtype=np.int64))
        path = np.broadcast_to(path, (*lead, K, 4, 4)).astype(np.float64).reshape(B, K, 4, 4)
        start = np.broadcast_to(q0_arr, (*lead, n)).astype(np.float64).reshape(B, n)
        lower, upper = self._limits
        lambda2 = damping * damping
        q = np.clip(start, lower, upper)
        seeded = np.isfinite(start).all(axis=-1)
        q_path = np.full((B, K, n), np.nan)
        converged = np.zeros((B, K), dtype=bool)
        iterations = np.zeros((B, K), dtype=np.int32)
        position_error = np.full((B, K), np.nan)
        orientation_error = np.full((B, K), np.nan)
        residual = np.full((B, K), np.nan)
        for k in range(K):
            target = path[:, k]
            ok = seeded & _rigid(target)
            active = ok.copy()
            it = np.zeros(B, dtype=np.int32)
            error = np.zeros((B, 6))
            while True:
                idx = np.nonzero(active)[0]
                if idx.size == 0:
                    break
                T = self.fk(q[idx])
                e = np.concatenate(
                    [
                        target[idx, :3, 3] - T[:, :3, 3],
                        _log_rotation(target[idx, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2)),
                    ],
                    axis=-1,
                )
                error[idx] = e
                ep = np.linalg.norm(e[:, :3], axis=-1)
                eo = np.linalg.norm(e[:, 3:], axis=-1)
                position_error[idx, k], orientation_error[idx, k] = ep, eo
                done = (ep <= position_tolerance) & ((rows == 3) | (eo <= orientation_tolerance))
                converged[idx, k] = done
                stop = done | (it[idx] >= max_iter) | ~np.isfinite(ep + eo)
                active[idx[stop]] = False
                go = idx[~stop]
                if go.size == 0:
                    break
                J = self.jacobian(q[go])[:, :rows]
                eg = e[~stop][:, :rows]
                dq = _dls(J, eg, lambda2)
                qg = q[go]
                locked = ((qg <= lower) & (dq < 0)) | ((qg >= upper) & (dq > 0))
                again = locked.any(axis=-1)
                if again.any():
                    dq[again] = _dls(J[again] * ~locked[again][:, None, :], eg[again], lambda2)
                largest = np.abs(dq).max(axis=-1)
                scale = np.where(largest > max_step, max_step / np.where(largest > 0, largest, 1.0), 1.0)
                stepped = np.clip(qg + scale[:, None] * dq, lower, upper)
                q[go] = np.where(locked, qg, stepped)
                it[go] += 1
            iterations[:, k] = np.where(ok, it, 0)
            idx = np.nonzero(ok)[0]
            q_path[idx, k] = q[idx]
            position_error[~ok, k] = np.nan
            orientation_error[~ok, k] = np.nan
            if idx.size:
                J = self.jacobian(q[idx])[:, :rows]
                residual[idx, k] = _core.compatible(J, error[idx, :rows], -1.0)[1]
        if targets.dtype == np.float32 and q0_arr.dtype == np.float32:
            q_path = q_path.astype(np.float32)
        shape = (*lead, K)
        q_path = q_path.reshape(*shape, n)
        info = IKDifferentialInfo(
            converged.reshape(shape),
            iterations.reshape(shape),
            position_error.reshape(shape),
            orientation_error.reshape(shape),
            residual.reshape(shape),
        )
        if single:
            q_path = q_path[..., 0, :]
            info = IKDifferentialInfo(*(_scalar(field[..., 0]) for field in info))
        return q_path, info

    def __reduce__(self):
        return (
            _rebuild_mimic,
            (self._full, self._M, self._b, self._names, np.stack(self._limits, axis=1), self._sigma),
        )

    def __repr__(self) -> str:
        kinds = "".join("RP"[int(s)] for s in self._sigma)
        return (
            f"Chain({kinds}, convention='joints', dof={self.dof}, "
            f"mimic: {self._M.shape[0]} joints from {self.dof} variables)"
        )


def _rebuild_mimic(full, M, b, names, limits, sigma) -> MimicChain:
    return MimicChain._make(full, M, b, names, limits, sigma)
