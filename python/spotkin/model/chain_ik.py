"""A chain's inverse kinematics: the closed forms (3-joint position IK, the 6R families, a 7-joint chain
with one joint held) and differential IK. :class:`spotkin.Chain` takes its IK methods from the base
class here; its result types are defined here."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import (
    as_finite,
    as_index,
    as_real,
    broadcast_lead,
    broadcast_seed,
    into_out,
    quiet_float_errors,
)
from .._support.status import Status

if TYPE_CHECKING:
    from .chain import Chain

MAX_FREE_VALUES = 100_000
"""The most values of a held joint :meth:`Chain.ik_self_motion` and :meth:`Chain.ik_nearest_free` sample
(each builds a 6R solver, and every pose gets 8 solutions per value)."""


def _reduced(angles: np.ndarray) -> np.ndarray:
    """Revolute angles (float64) with those beyond pi reduced into [-pi, pi] first, as atan2(sin, cos):
    NumPy's sin and cos reduce any argument exactly (a difference taken before reducing loses a 1e17
    angle's fraction, and all of a 1e300 one's). NaN and Inf give NaN, quietly."""
    with np.errstate(invalid="ignore"):
        wide = ~(np.abs(angles) <= np.pi)
        if not wide.any():
            return angles
        return np.where(wide, np.arctan2(np.sin(angles), np.cos(angles)), angles)


class ChainSolutions(NamedTuple):
    """Every closed-form IK solution for a batch of targets, from :meth:`Chain.ik_position` or
    :meth:`Chain.ik`."""

    q: np.ndarray
    """(..., slots, dof) joint values per slot (4 slots for ik_position, 8 for ik), NaN where none.
    Solutions fill the first slots. Revolute angles are in [-pi, pi], or shifted by 2 pi where that
    brings them into the limits."""
    valid: np.ndarray
    """(..., slots) bool: the solution exists and is within the joint limits."""
    exists: np.ndarray
    """(..., slots) bool: the solution exists, limits aside."""
    exact: np.ndarray
    """(..., slots) bool: the solution is exact, its residual on the true chain (max of the position
    error in m and the rotation error in rad) below 1e-10. It equals ``exists`` except on a chain
    solved as an idealised family (:meth:`Chain.with_ik_tolerance`), whose solutions are Newton-polished
    on the true chain: those that only converge to within 1e-6 exist but are not exact."""
    status: np.ndarray
    """(...,) int8 :class:`Status`: OK if any slot is valid, else JOINT_LIMIT (solutions exist, none
    within the limits), UNREACHABLE (no solution: every slot NaN) or INVALID_INPUT (NaN/Inf, or a
    pose whose rotation is not one)."""


_core._register_result_type("ChainSolutions", ChainSolutions)  # the core returns it itself


class IKDifferentialInfo(NamedTuple):
    """Per-target outcome of :meth:`Chain.ik_differential`, each of shape (..., K) (or (...,))."""

    converged: np.ndarray
    """bool: both errors within tolerance (position only for ``task="position"``)."""
    iterations: np.ndarray
    """int32: DLS steps taken for this target (0 if the start already met it)."""
    position_error: np.ndarray
    """float64: final |p_target - p| (m); NaN for non-finite input."""
    orientation_error: np.ndarray
    """float64: final |log(R_target R^T)| (rad), reported for both tasks."""
    residual: np.ndarray
    """float64: the compatibility residual ``|(I - J J^+) e|`` of the final error e (the task's rows)
    against the base-frame Jacobian J at the returned joints, as :func:`spotkin.compatible`
    computes it. Near 0: the error lies in the range of J and a further step reduces it to first
    order; larger: part of it is out of J's range (a singular configuration, or fewer joints than
    task rows), and the steps were least-squares ones. NaN for invalid input."""


class _ChainIKMethods:
    """The IK methods of :class:`spotkin.Chain` (its base class; see there)."""

    __slots__ = ()

    def _ik_core(self):
        if self._ik is None or isinstance(self._ik, dict):  # a dict: a 7-joint chain's free-joint solvers
            angle, distance = self._ik_tolerance or (1e-9, -1.0)
            try:
                core = _core.ChainIK(self._core, *self._limits, angle, distance)
            except ValueError as error:
                if self.dof == 7:
                    raise ValueError(_SEVEN_JOINTS) from None
                if "ik_differential" in str(error):
                    raise
                raise ValueError(f"{error}; Chain.ik_differential solves it numerically") from None
            if self._ik is None:
                self._ik = core
            return core
        return self._ik

    def with_ik_tolerance(self, angle: float = 1e-3, distance: float = 1e-3) -> Chain:
        """This chain, with a looser geometric tolerance for recognising a 6R closed-form family
        (a calibrated robot whose axes are parallel or meet only nearly).

        ``angle``: axes count as parallel when the sine of their angle is at most this;
        ``distance`` (m): axes count as meeting when each passes within this of their common point.
        A chain within the strict tolerances (1e-9, and 1e-9 times the chain's length scale) is
        solved as before. A chain that fits a family only within these looser ones is solved on its
        *idealised* chain (the parallel axes set to their mean direction, the meeting axes moved to
        their common point), and each solution is then polished by Gauss–Newton steps on the true
        chain: :attr:`ChainSolutions.exact` says which reached a residual below 1e-10 (m and rad);
        a branch whose residual stays above 1e-6 is dropped. :attr:`ik_idealised` says whether this
        happens. Returns a new Chain (the same model); the original keeps its tolerances.
        """
        angle = as_finite(angle, "angle", 0.0)
        distance = as_finite(distance, "distance", 0.0)
        if not angle < 0.1:
            raise ValueError(f"angle must be below 0.1 (the sine of an angle), got {angle!r}")
        chain = self._copy()
        chain._ik = None
        chain._ik_tolerance = (float(angle), float(distance))
        return chain

    @property
    def ik_idealised(self) -> bool:
        """Whether :meth:`ik` solves an idealised family and polishes on the true chain (see
        :meth:`with_ik_tolerance`)."""
        return bool(self._ik_core().idealised)

    @property
    def ik_geometry(self) -> dict:
        """What the 6R family detection measured: ``wrist_meeting`` and ``shoulder_meeting`` (m, the
        largest distance of axes 4-5-6, or 1-2-3, from their nearest common point; inf when they are
        parallel), ``parallel_234`` and ``parallel_123`` (the largest sine of the angle between the
        first axis of the three and the others), ``axes_5_6_gap`` and ``axes_4_5_gap`` (m, the
        distance between those two axes, 0 when parallel: where it is 0 the parallel families' pair
        of equations has rank 1, as on UR arms and the Z1). Empty for 3-joint chains."""
        return dict(self._ik_core().geometry)

    @property
    def ik_kind(self) -> str:
        """The closed form :meth:`ik_position` or :meth:`ik` uses for this chain.

        3 joints: ``"3R-parallel"`` (two consecutive axes parallel: a degree-2 equation),
        ``"3R-intersecting"`` (two consecutive axes intersect: degree 2), ``"3R-general-quartic"``
        (both pairs skew: Pieper's quartic), or the joint pattern (``"PRR"``, ``"RPR"``, ``"RRP"``,
        ...) for prismatic joints. 6 revolute joints, checked in this order, the first that holds
        deciding (like EAIK's ``kinematicFamily``): ``"6R-spherical-wrist"`` (axes 4, 5, 6 meet; see
        :attr:`ik_position_kind` for its first three joints), ``"6R-three-parallel-234"`` (axes 2,
        3, 4 parallel: UR3/5/10, Unitree Z1), ``"6R-three-parallel-123"`` (axes 1, 2, 3 parallel),
        ``"6R-spherical-shoulder"`` (axes 1, 2, 3 meet). "Parallel" is a sine of the angle below
        1e-9, "meet" every axis within 1e-9 s of their common point (s: the chain's length scale);
        :meth:`with_ik_tolerance` loosens both for calibrated robots, whose chains are then solved
        on the idealised family (:attr:`ik_idealised`) and polished. Raises ``ValueError``, saying
        what was checked and by how much each check failed, for chains without a closed form here
        (other joint counts, a tool point that three joints cannot place in 3D, a 6R chain of no
        family); :meth:`ik_differential` solves those numerically. For a 7-joint chain the message
        names ``free_joint``: :meth:`ik` with one joint held is in closed form (:meth:`ik_free_kind`).
        """
        return self._ik_core().kind

    @property
    def ik_position_kind(self) -> str:
        """The closed form of the position part: :attr:`ik_kind` of the first three joints."""
        return self._ik_core().position_kind

    def ik_all(
        self,
        target: ArrayLike,
        free_joint: int | None = None,
        free_value: ArrayLike | None = None,
        *,
        out: tuple | None = None,
    ) -> ChainSolutions:
        """Every branch for ``target``, as :meth:`spotkin.Leg.ik_all` and :meth:`spotkin.SpotArm.ik_all`
        answer (:meth:`ik` chooses one of them).

        ``out``: ``(q, valid, exists, exact, status)`` arrays to write into (any may be None), each of
        the exact dtype and shape of that result, C-contiguous and writeable: the call then allocates
        nothing for them.

        **3 joints:** :meth:`ik_position`'s: p (..., 3) -> q (..., 4, 3). **6 joints**: every joint
        solution for a tool pose of a 6R chain of a closed-form family (:attr:`ik_kind`). **7 joints**:
        a 7R chain with one joint held (``free_joint``, ``free_value``). Errors name ``target``.

        **7 joints** (redundant arms: Franka-Panda- and Kinova-Gen3-like): ``free_joint`` (0-based)
        is held at ``free_value``, which broadcasts against T's leading dimensions (so one pose with
        (n,) values samples its self-motion in one call, see :meth:`ik_self_motion`). The other six
        are solved in closed form by their family, found when the free joint is first used (on probe
        values; a ``ValueError`` names the checks when none fits, or when the family changes with the
        value). q is (..., 8, 7) with ``free_value`` in column ``free_joint``; valid also needs
        ``free_value`` within that joint's limits. A non-finite ``free_value`` gives INVALID_INPUT.
        The first or the last joint held only moves the six's base or tool, so one 6R solver serves
        every value and a value per pose costs what one value does. A middle joint held changes the
        six's geometry: each distinct value builds its own 6R solver (about 10-20 microseconds), kept
        for later calls (the 1,024 most recently used values) and shared by every pose with that value.

        **6 joints:**
        ``target`` T (..., 4, 4) or (..., 7) [x, y, z, qx, qy, qz, qw] in the base frame ->
        :class:`ChainSolutions` with q (..., 8, 6): at most 8 solutions, slot ``2 k + b``.

        - ``"6R-spherical-wrist"``: the wrist centre (where axes 4, 5 and 6 meet) fixes q1..q3
          through :meth:`ik_position`'s engine (``k``, at most 4); then q5 solves
          e3 . B5 Rz(q5) b = w_z (Paul's type 2: ``b`` its root), q4 and q6 follow from the
          remaining rotation. In a wrist singularity (axes 4 and 6 aligned) q4 is free and set to
          0, q6 takes the whole rotation.
        - ``"6R-three-parallel-234"``: R2 R3 R4 is a rotation about the common axis, which leaves
          two equations in q1 and q5 alone. ``k`` numbers the (q1, q5) pairs: when p56 lies along
          axis 6 (UR arms, Z1) ``k = 2 i1 + i5`` with ``i1`` the shoulder root of q1 and ``i5`` the
          wrist root of q5 (``+`` then ``-`` of ``angle(a, b) ± acos``), otherwise the real roots of
          a quartic in increasing q1. q6 and q2 + q3 + q4 follow, then ``b`` is the elbow root of q3.
          Where q6 is free (axes 2 and 6 aligned) it is set to 0.
        - ``"6R-three-parallel-123"``: R1 R2 R3 is a rotation about the common axis; the same
          kind of pair of equations in q6 and q4 (``k``: the (q6, -q4) pairs, ordered as above),
          then q5, q1 + q2 + q3, and ``b`` the root of q2. Where q5 is free it is set to 0.
        - ``"6R-spherical-shoulder"``: the reversed chain has a spherical wrist; ``k`` numbers the
          position solutions of joints 6, 5, 4 and ``b`` the root of q2.

        Angles are in [-pi, pi], or shifted by 2 pi where that brings them into the limits. A rotation
        part that is not a rotation (|R^T R - I| > 1e-6 or det < 0) gives INVALID_INPUT. The
        derivations are in ``docs/derivations.md`` and ``spotkin.reference.ik6r``.
        """
        if self.dof == 3 and free_joint is None and free_value is None:
            return _as_target(self.ik_position, target, out=out)
        return _as_target(self._ik_pose_all, target, free_joint, free_value, out)

    def ik(
        self,
        target: ArrayLike,
        seed: ArrayLike | None = None,
        free_joint: int | None = None,
        free_value: ArrayLike | None = None,
        *,
        out: tuple | None = None,
    ) -> tuple[np.ndarray, np.ndarray | Status]:
        """One solution per target: (q (..., dof), status (...,)), of the branches :meth:`ik_all` gives.

        ``target`` is what :meth:`ik_all` takes (p (..., 3) for 3 joints, T (..., 4, 4) or (..., 7) for
        6); of its solutions, the one within the limits nearest to ``seed`` (..., dof) (the largest
        single-joint move: on the circle for a revolute joint, plain for a prismatic one; ties to the
        lower slot), or the lowest valid slot without a seed. Status as in :class:`ChainSolutions`; q is
        NaN unless it is OK; a seed with NaN or Inf gives INVALID_INPUT. The seed broadcasts against the
        target's leading dimensions. Runs in C++ per block of targets, with no temporary array of every
        solution (for control loops and large batches alike).

        **7 joints**: ``free_joint`` held at ``free_value`` (broadcast against the targets) chooses
        among that value's solutions; with ``free_joint`` alone, among the solutions over the sampled
        values of the joint and the seed's own (:meth:`ik_nearest_free`, which needs the seed).

        ``out``: ``(q, status)`` arrays to write into (either may be None; ``status`` int8), of the
        exact dtype and shape of that result, C-contiguous and writeable. Without a free joint the core
        writes them directly and the call allocates nothing (a control loop's path); with one, the
        choice is made in NumPy and copied in.
        """
        if free_joint is None and free_value is None:
            if self.dof == 7:
                raise ValueError(_SEVEN_JOINTS)
            return _as_target(self._ik_core().ik_nearest, target, seed, out)
        if free_value is None:
            if seed is None:
                raise ValueError(
                    "ik with free_joint alone searches the joint's values for the one nearest seed: pass seed"
                )
            _check_outs(out, 2)
            return _into_outs(_as_target(self.ik_nearest_free, target, seed, free_joint), out)
        _check_outs(out, 2)
        sol = self.ik_all(target, free_joint, free_value)
        return _into_outs(_nearest_solution(sol, seed, self.sigma == 1), out)

    @property
    def ik_nearest(self):
        """Deprecated: :meth:`ik` (the previous interface's name, kept a short while). A property, not a
        ``__getattr__`` hook: a class with one pays for it on every attribute read."""
        warnings.warn(
            "Chain.ik_nearest is deprecated: use Chain.ik(target, seed)", DeprecationWarning, stacklevel=2
        )
        return self.ik

    def ik_position(self, p: ArrayLike, *, out: tuple | None = None) -> ChainSolutions:
        """Every joint solution placing the tool point at p, for a 3-joint chain (``out``: as
        :meth:`ik_all`'s).

        p (..., 3) in the base frame -> :class:`ChainSolutions` with q (..., 4, 3). The
        tool orientation is free. The closed form is Pieper's: q1 is eliminated through two
        invariants of its joint (|f|^2 and f_z for a revolute, f_x and f_y for a prismatic),
        q2 through a 2x2 linear system, leaving a polynomial in q3 of degree <= 4 (degree 2
        when consecutive axes intersect or are parallel); every real root is back-substituted
        and polished by Gauss–Newton steps on fk(q) = p. Accepted solutions satisfy
        |fk(q) - p| <= 1e-9 s (s: the sum of the table's lengths and the tool offset, at least
        |p|); solutions closer than 1e-6 (rad, or length / s) are merged, so a double root comes
        back once. Slots are sorted by (q1, q2, q3), values within 1e-7 counting as equal. A
        target for which a joint is free (on a joint axis) gives one representative with that
        joint at 0. Unreachable targets get status UNREACHABLE and NaN in every slot; :meth:`fk`
        of the nearest configuration is not attempted (use a numerical solver for a
        least-squares answer). The full derivation is in ``spotkin.reference.ik3r``.
        """
        return self._ik_core().ik_position(p, out)  # a ChainSolutions (the core builds it)

    def _ik_pose_all(self, T, free_joint, free_value, out=None) -> ChainSolutions:
        """Every solution for tool poses (:meth:`ik_all` of a 6- or 7-joint chain)."""
        fast = self._ik is not None and not isinstance(self._ik, dict)
        if free_joint is None and free_value is None and fast:  # the single-call fast path
            return self._ik.ik(T, out)  # a ChainSolutions (the core builds it)
        if free_joint is None:
            if free_value is not None:
                raise ValueError("free_value needs free_joint (the index of the joint it holds)")
            if self.dof == 7:
                raise ValueError(
                    "a 7-joint chain is redundant: pass free_joint (0..6) and free_value to hold one "
                    "joint, or use ik_self_motion to sample it, or ik_differential to solve it numerically"
                )
            return self._ik_core().ik(T, out)
        core = self._free_core(free_joint)
        if free_value is None:
            raise ValueError("free_joint needs free_value (the value the joint is held at)")
        return core.ik(T, free_value, out)

    def _free_core(self, free_joint) -> _core.FreeJointIK:
        k = as_index(free_joint, "free_joint")
        if self.dof != 7:
            raise ValueError(f"free_joint is for 7-joint chains; this chain has {self.dof} joints")
        if not 0 <= k < 7:
            raise ValueError(f"free_joint must be in [0, 6], got {k}")
        if self._ik is None:
            self._ik = {}
        if k not in self._ik:
            angle, distance = self._ik_tolerance or (1e-9, -1.0)
            self._ik[k] = _core.FreeJointIK(self._core, *self._limits, k, angle, distance)
        return self._ik[k]

    def ik_free_kind(self, free_joint: int) -> str:
        """The 6R family (:attr:`ik_kind`) of the six joints left when ``free_joint`` is held
        (7-joint chains); ``ValueError`` when they have none."""
        return self._free_core(free_joint).kind

    def ik_self_motion(self, T: ArrayLike, free_joint: int, values: ArrayLike | int = 36):
        """Samples the self-motion of a 7-joint chain: every solution with ``free_joint`` held at each
        of ``values`` ((n,) values, or a count n spread evenly over the joint's limits, or over
        [-pi, pi) when unlimited; n at most :data:`MAX_FREE_VALUES`, 100,000, else ``ValueError``).
        Returns (values (n,), :class:`ChainSolutions` with q (..., n, 8, 7)), computed in one batched
        call (redundancy resolution by a free joint)."""
        k = as_index(free_joint, "free_joint")
        self._free_core(k)
        grid = self._free_grid(k, values)
        T = as_real(T, "T")
        trailing = 2 if T.shape[-2:] == (4, 4) else 1
        poses = np.expand_dims(T, axis=T.ndim - trailing)  # (..., 1, 4, 4): against (n,) values
        return grid, self.ik_all(poses, free_joint=k, free_value=grid.astype(T.dtype, copy=False))

    def _free_grid(self, k: int, values) -> np.ndarray:
        if isinstance(values, (int, np.integer)) and not isinstance(values, (bool, np.bool_)):
            count = int(values)
            if count < 1:
                raise ValueError(f"values must be a positive count or an array of values, got {count}")
            if count > MAX_FREE_VALUES:  # checked before anything is allocated
                raise ValueError(f"values must be a count of at most {MAX_FREE_VALUES:,}, got {count:,}")
            lower, upper = self._limits[0][k], self._limits[1][k]
            if np.isfinite(lower) and np.isfinite(upper):
                return np.linspace(lower, upper, count)
            return -np.pi + 2 * np.pi * np.arange(count) / count
        grid = as_real(values, "values")
        if grid.ndim != 1:
            raise ValueError(f"values must have shape (n,), got {grid.shape}")
        if grid.size > MAX_FREE_VALUES:
            raise ValueError(f"values must hold at most {MAX_FREE_VALUES:,} values, got {grid.size:,}")
        return grid

    @quiet_float_errors
    def ik_nearest_free(
        self, T: ArrayLike, seed: ArrayLike, free_joint: int, values: ArrayLike | int = 36
    ) -> tuple[np.ndarray, np.ndarray | Status]:
        """One solution per pose for a 7-joint chain: of every solution over the sampled values of
        ``free_joint`` (:meth:`ik_self_motion`) plus the seed's own value, the valid one nearest the
        seed (the largest single-joint move on the circle; a seed angle beyond pi is reduced exactly
        first). Returns (q (..., 7), status (...,)): OK, or JOINT_LIMIT / UNREACHABLE / INVALID_INPUT
        as in :class:`ChainSolutions` when none is valid (q NaN; a NaN or Inf seed: INVALID_INPUT).
        ``seed`` (..., 7) broadcasts against T's leading dimensions."""
        k = as_index(free_joint, "free_joint")
        self._free_core(k)
        T, seed = broadcast_seed(T, seed)
        if seed.shape[-1] != 7:
            raise ValueError(f"seed must have shape (..., 7), got {seed.shape}")
        grid = self._free_grid(k, values)
        trailing = 2 if T.shape[-2:] == (4, 4) else 1
        lead = T.shape[:-trailing]
        own = seed[..., k]
        candidates = np.concatenate([np.broadcast_to(grid, (*lead, grid.size)), own[..., None]], axis=-1)
        shape = (*lead, grid.size + 1, *T.shape[-trailing:])
        poses = np.broadcast_to(np.expand_dims(T, axis=T.ndim - trailing), shape)
        sol = self.ik_all(poses, free_joint=k, free_value=candidates.astype(T.dtype, copy=False))
        # reduced before the difference: q - 1e17 would lose q (and q - 1e300 everything)
        gap = sol.q - _reduced(seed.astype(np.float64))[..., None, None, :]
        move = np.abs(np.angle(np.exp(1j * gap))).max(axis=-1)
        width = (grid.size + 1) * 8  # every (value, slot) candidate of a pose; explicit for empty batches
        move = np.where(sol.valid, move, np.inf).reshape(*lead, width)
        best = np.argmin(move, axis=-1)
        q_all = sol.q.reshape(*lead, width, 7)
        q = np.take_along_axis(q_all, best[..., None, None], axis=-2)[..., 0, :]
        seed_ok = np.isfinite(seed).all(axis=-1)
        found = np.isfinite(np.take_along_axis(move, best[..., None], axis=-1)[..., 0]) & seed_ok
        exists = sol.exists.reshape(*lead, width).any(axis=-1)
        fallback = np.where(exists, np.int8(Status.JOINT_LIMIT), np.int8(Status.UNREACHABLE))
        invalid = (sol.status == Status.INVALID_INPUT).any(axis=-1) | ~seed_ok
        status = np.where(invalid, np.int8(Status.INVALID_INPUT), fallback)
        status = np.where(found, np.int8(Status.OK), status)
        status = status.astype(np.int8)
        q = np.where(found[..., None], q, np.nan).astype(T.dtype, copy=False)
        if not lead:
            return q, Status(int(status))
        return q, status

    def ik_differential(
        self,
        T_targets: ArrayLike,
        q0: ArrayLike,
        *,
        task: Literal["pose", "position"] = "pose",
        damping: float = 1e-2,
        position_tolerance: float = 1e-6,
        orientation_tolerance: float = 1e-6,
        max_iter: int = 100,
        max_step: float = 0.5,
    ) -> tuple[np.ndarray, IKDifferentialInfo]:
        """Closed-loop differential IK along a path of targets.

        ``T_targets`` is (..., K, 4, 4), a path of K base-frame tool poses, or a single
        target (..., 4, 4); ``q0`` (..., dof) is the start. ``T_targets`` is read as a
        single target per sample when it has no more leading dimensions than ``q0`` has
        (``(4, 4)`` or ``(N, 4, 4)`` with ``q0`` (N, dof)), as a path otherwise (``(K, 4, 4)``
        with ``q0`` (dof,); ``(N, K, 4, 4)`` with ``q0`` (N, dof)). Leading dimensions
        broadcast. Returns ``q_path`` (..., K, dof) (or (..., dof) for a single target)
        and an :class:`IKDifferentialInfo` of per-target arrays.

        For each target in turn, starting from the previous target's result (``q0``
        clamped into the limits for the first), iterate until converged or ``max_iter``
        steps:

        - error ``e = [p_target - p; log(R_target R^T)]`` in the base frame, the frame of
          the base-frame geometric Jacobian J (``d p/dt = v``, ``d R/dt = [w]x R``);
          ``task="position"`` keeps the top three rows only (for chains with fewer than
          6 joints, or when the orientation is free);
        - converged when ``|p_target - p| <= position_tolerance`` (m) and, for the pose
          task, ``|log(R_target R^T)| <= orientation_tolerance`` (rad);
        - step ``dq = J^T (J J^T + damping² I)^-1 e`` (``damping`` finite and > 0: the
          damping keeps the steps bounded at singular configurations), scaled down so that
          ``max |dq_j| <= max_step`` (finite and > 0);
        - joint limits by clamping: ``q <- clip(q + dq, lower, upper)``. A joint sitting
          at a limit whose step points outwards is locked (its Jacobian column removed)
          and the step re-solved, so the other joints make up for it.

        Unreachable targets (out of the workspace or the limits) end with
        ``converged=False`` and the final errors, after ``max_iter`` steps. Non-finite
        input, or a target that is not a rigid transform (last row ``[0, 0, 0, 1]``,
        ``max |R^T R - I| <= 1e-6``, ``det R > 0``, as :meth:`ik` requires), gives NaN
        joints and errors with ``converged=False`` for that target.
        Computed in float64; the result is float32 when ``T_targets`` and ``q0`` both are.
        """
        if task not in ("pose", "position"):
            raise ValueError(f"task must be 'pose' or 'position', got {task!r}")
        targets = as_real(T_targets, "T_targets")
        q0_arr = as_real(q0, "q0")
        if targets.ndim < 2 or targets.shape[-2:] != (4, 4):
            raise ValueError(f"T_targets must have shape (..., K, 4, 4) or (..., 4, 4), got {targets.shape}")
        if q0_arr.ndim < 1 or q0_arr.shape[-1] != self.dof:
            raise ValueError(f"q0 must have shape (..., {self.dof}), got {q0_arr.shape}")
        # a single target per sample when T_targets has no more leading dimensions than q0
        single = targets.ndim - 2 <= q0_arr.ndim - 1
        path = targets[..., None, :, :] if single else targets
        damping = as_finite(damping, "damping", 0.0, strict=True)
        max_step = as_finite(max_step, "max_step", 0.0, strict=True)
        position_tolerance = as_finite(position_tolerance, "position_tolerance")
        orientation_tolerance = as_finite(orientation_tolerance, "orientation_tolerance")
        max_iter = as_index(max_iter, "max_iter")
        if not 0 <= max_iter <= 2**31 - 1:
            raise ValueError(f"max_iter must be an int in [0, 2**31 - 1], got {max_iter!r}")
        q_path, converged, iterations, position_error, orientation_error, residual = (
            self._core.ik_differential(
                path,
                q0_arr,
                self._limits[0],
                self._limits[1],
                float(damping),
                float(position_tolerance),
                float(orientation_tolerance),
                float(max_step),
                int(max_iter),
                6 if task == "pose" else 3,
            )
        )
        if targets.dtype == np.float32 and q0_arr.dtype == np.float32:
            q_path = q_path.astype(np.float32)
        iterations = iterations.astype(np.int32)  # (..., K) step counts, at most max_iter < 2**31
        info = IKDifferentialInfo(converged, iterations, position_error, orientation_error, residual)
        if single:
            q_path = q_path[..., 0, :]
            info = IKDifferentialInfo(*(_scalar(field[..., 0]) for field in info))
        return q_path, info


def _scalar(array: np.ndarray):
    return array[()] if array.ndim == 0 else array


_SEVEN_JOINTS = (
    "a 7-joint chain is redundant: no closed form solves all 7 joints at once; "
    "ik_all(T, free_joint=k, free_value=v) solves the other six in closed form with joint k held "
    "(ik_free_kind(k) names their family; ik_self_motion samples the redundancy), and "
    "ik_differential solves the whole chain numerically"
)


def _nearest_solution(
    sol: ChainSolutions, seed, prismatic: np.ndarray
) -> tuple[np.ndarray, np.ndarray | Status]:
    """(q, status) from every solution: the valid one nearest to ``seed`` (the largest single-joint move,
    on the circle for a revolute joint; ties to the lower slot), or the lowest valid slot without a
    seed. q is NaN unless OK; a NaN or Inf seed gives INVALID_INPUT."""
    q_all, valid = sol.q, sol.valid
    n = q_all.shape[-1]
    slots = np.arange(q_all.shape[-2], dtype=np.float64)
    if seed is None:
        seed_ok = np.ones(q_all.shape[:-2], dtype=bool)
        move = np.where(valid, slots, np.inf)
    else:
        seed = as_real(seed, "seed", np.float64)
        if seed.ndim == 0 or seed.shape[-1] != n:
            raise ValueError(f"seed must have shape (..., {n}), got {seed.shape}")
        lead = broadcast_lead(target=(q_all.shape[:-2], q_all.shape), seed=(seed.shape[:-1], seed.shape))
        q_all = np.broadcast_to(q_all, (*lead, *q_all.shape[-2:]))
        valid = np.broadcast_to(valid, (*lead, valid.shape[-1]))
        seed = np.broadcast_to(seed, (*lead, n))
        seed_ok = np.isfinite(seed).all(axis=-1)
        with np.errstate(invalid="ignore"):
            gap = q_all - _reduced(np.where(np.isfinite(seed), seed, 0.0))[..., None, :]
            move = np.where(prismatic, np.abs(gap), np.abs(np.angle(np.exp(1j * gap)))).max(axis=-1)
        move = np.where(valid, move, np.inf)
    best = np.argmin(move, axis=-1)
    found = np.isfinite(np.take_along_axis(move, best[..., None], axis=-1)[..., 0]) & seed_ok
    q = np.take_along_axis(q_all, best[..., None, None], axis=-2)[..., 0, :]
    status = np.broadcast_to(np.asarray(sol.status, dtype=np.int8), found.shape)
    status = np.where(seed_ok, status, np.int8(Status.INVALID_INPUT))
    status = np.where(found, np.int8(Status.OK), status).astype(np.int8)
    q = np.where(found[..., None], q, np.nan).astype(sol.q.dtype, copy=False)
    if not found.shape:
        return q, Status(int(status))
    return q, status


def _check_outs(out, count: int) -> None:
    """The core's checks of an ``out`` tuple's kind and length, made before a solve in NumPy."""
    if out is not None and not isinstance(out, (tuple, list)):
        raise TypeError(f"out must be a tuple of {count} arrays (or None)")
    if out is not None and len(out) != count:
        raise ValueError(f"out must hold {count} arrays (or None), got {len(out)}")


def _into_outs(result: tuple, out) -> tuple:
    """A result computed in NumPy, written into the caller's ``out`` arrays (a tuple with an array or
    None per result, checked as the core checks them) and returned as the core returns it: the arrays
    given, in the result's own type (a :class:`ChainSolutions` stays one)."""
    if out is None:
        return result
    _check_outs(out, len(result))
    names = getattr(result, "_fields", ("q", "status"))
    written = []
    for k, (value, into) in enumerate(zip(result, out)):
        if into is None:
            written.append(value)
            continue
        try:
            written.append(into_out(np.asarray(value, np.int8 if isinstance(value, Status) else None), into))
        except (TypeError, ValueError) as error:
            message = str(error).replace("out must", f"out[{k}] ({names[k]}) must", 1)
            raise type(error)(message) from None
    return type(result)(*written) if hasattr(result, "_fields") else tuple(written)


def _as_target(call, target, *args, **kwargs):
    """call(target, *args), its errors naming ``target`` (the kernels call it p or T)."""
    try:
        return call(target, *args, **kwargs)
    except (TypeError, ValueError) as error:
        message = str(error)
        for name in ("p", "T"):
            if message.startswith(f"{name} "):
                message = "target" + message[len(name) :].replace(f" {name}.filled", " target.filled")
                raise type(error)(message) from None
        raise
