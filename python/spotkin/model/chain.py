"""Serial chains: one model for URDF, DH and DHm descriptions. FK, frames, geometric
Jacobians, closed-form IK where the structure has one, and differential IK.

Every joint is a fixed placement followed by a motion about (revolute) or along
(prismatic) a unit axis: what a URDF ``<joint>`` describes. :meth:`Chain.from_mdh` and
:meth:`Chain.from_dh` build the same model from DH tables; :meth:`Chain.from_joints` and
:meth:`spotkin.Robot.chain` from placements and axes."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_index, as_real, limit_table, rigid_transforms
from .._support.forward import AT_DEFAULT, core_method
from ..dynamics.inertia import link_inertials
from .chain_dynamics import _ChainDynamicsMethods
from .chain_ik import ChainSolutions, IKDifferentialInfo, _ChainIKMethods

__all__ = ["Chain", "ChainSolutions", "IKDifferentialInfo"]

_CONVENTIONS = {
    "mdh": _core.Convention.MODIFIED_DH,
    "dh": _core.Convention.CLASSIC_DH,
}


def _table(rows: ArrayLike) -> np.ndarray:
    try:
        table = as_real(rows, "rows", np.float64)
    except (TypeError, ValueError) as error:
        raise type(error)(f"rows must be a numeric table of shape (n, 5): {error}") from None
    if table.ndim != 2 or table.shape[1] != 5:
        raise ValueError(f"rows must have shape (n, 5), got {table.shape}")
    return table.copy()


def _limits(limits: ArrayLike | None, dof: int) -> tuple[np.ndarray, np.ndarray]:
    table = limit_table(limits, dof)
    return table[:, 0].copy(), table[:, 1].copy()


def _limit_override(limits, current, names, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) from ``current`` with ``limits`` applied: a (dof, 2) table, or a dict joint name
    or index -> (lower, upper) for the joints it names."""
    lower, upper = current[0].copy(), current[1].copy()
    dof = len(lower)
    if not isinstance(limits, Mapping):
        return _limits(limits, dof)
    for key, pair in limits.items():
        if isinstance(key, str):
            if names is None or key not in names:
                known = "this chain has no joint names" if names is None else f"the joints are {names}"
                raise ValueError(f"{what}: {key!r} is not a joint of this chain ({known})")
            k = names.index(key)
        elif isinstance(key, (int, np.integer)) and not isinstance(key, bool):
            if not -dof <= int(key) < dof:
                raise ValueError(f"{what}: joint index {key} is out of range for {dof} joints")
            k = int(key) % dof
        else:
            raise TypeError(f"{what}: keys must be joint names or indices, got {type(key).__name__}")
        row = as_real(pair, f"{what}[{key!r}]", np.float64)
        if row.shape != (2,):
            raise ValueError(f"{what}[{key!r}] must be a (lower, upper) pair, got shape {row.shape}")
        if np.isnan(row).any() or row[0] > row[1]:
            raise ValueError(f"{what}[{key!r}] must satisfy lower <= upper, with no NaN, got {row.tolist()}")
        lower[k], upper[k] = row
    return lower, upper


def _names(joint_names) -> tuple[str, ...]:
    """joint_names as a tuple of str (``TypeError`` naming it otherwise)."""
    names = None
    if not isinstance(joint_names, (str, bytes)):
        try:
            names = tuple(joint_names)
        except TypeError:
            names = None
    if names is None or not all(isinstance(name, str) for name in names):
        raise TypeError(f"joint_names must be a sequence of str, got {type(joint_names).__name__}")
    return names


def _urdf_loader_missing(*args):
    raise ImportError("spotkin.model.urdf_chain registers Chain.from_urdf's loader: import spotkin")


# Chain.from_urdf's loader: spotkin.model.urdf_chain.chain_from_urdf, which builds chains of whichever class a
# URDF needs (spotkin.model.mimic.MimicChain for mimic joints) and so sits above this module. It registers
# itself here when imported (the package imports it), so that this module never imports it.
_from_urdf = _urdf_loader_missing


class Chain(_ChainDynamicsMethods, _ChainIKMethods):
    """A serial chain of revolute and prismatic joints described by a DH table.

    Build one with :meth:`from_mdh` (modified DH, Khalil–Kleinfinger) or
    :meth:`from_dh` (classic DH). ``base`` maps the world (base) frame to frame 0,
    ``tool`` maps the last joint frame to the tool frame; both are (4, 4).

    Batch semantics follow NumPy: ``q`` has shape ``(..., dof)`` and leading
    dimensions are kept; float32 input gives float32 output, anything else is
    computed in float64. NaN in ``q`` propagates to NaN in the result.
    """

    __slots__ = (
        "_base",
        "_convention",
        "_core",
        "_dynamics",
        "_ik",
        "_ik_tolerance",
        "_inertials",
        "_joints",
        "_limits",
        "_names",
        "_rows",
        "_tool",
    )

    _block_dependent = frozenset({"ik", "ik_all", "ik_position"})
    """Methods whose answer for a sample may differ in the last bits between a full block of the lane
    kernels and a short one (spotkin.dask cuts its batches at block multiples for them)."""

    def __init__(
        self,
        rows: ArrayLike,
        *,
        convention: Literal["mdh", "dh"] = "mdh",
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        limits: ArrayLike | None = None,
    ) -> None:
        if convention not in _CONVENTIONS:
            raise ValueError(f"convention must be 'mdh' or 'dh', got {convention!r}")
        table = _table(rows)
        self._rows = table
        self._convention = convention
        self._joints = None
        self._names = None
        self._base = None if base is None else rigid_transforms(base, "base")
        self._tool = None if tool is None else rigid_transforms(tool, "tool")
        self._core = _core.Chain(_CONVENTIONS[convention], table, self._base, self._tool)
        self._limits = _limits(limits, table.shape[0])
        self._ik = None
        self._ik_tolerance = None
        self._inertials = None
        self._dynamics = None

    @classmethod
    def from_joints(
        cls,
        placements: ArrayLike,
        axes: ArrayLike,
        types: ArrayLike | None = None,
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        limits: ArrayLike | None = None,
        joint_names: tuple[str, ...] | None = None,
    ) -> Chain:
        """Chain from URDF-style joints: T(j-1, j) = placements[j] · Rot(axes[j], q_j) (revolute) or
        placements[j] · Trans(axes[j] q_j) (prismatic).

        ``placements`` (n, 4, 4) rigid transforms (finite, rotation orthonormal to 1e-9), ``axes``
        (n, 3) non-zero (normalised here, any sign), ``types`` (n,) 0 revolute / 1 prismatic
        (default all revolute), ``limits`` (n, 2). ``base`` maps the world frame to the frame
        before joint 0 and ``tool`` the last joint's frame to the tool frame.
        """
        chain = Chain.__new__(Chain)  # a Chain whichever class asks (a subclass has its own constructor)
        chain._set_joints(placements, axes, types, base, tool, limits, joint_names)
        return chain

    def _set_joints(self, placements, axes, types, base, tool, limits, joint_names) -> None:
        """:meth:`from_joints`'s model, checked, set on this (new) object."""
        placements = rigid_transforms(placements, "placements")
        if placements.ndim != 3 or placements.shape[1:] != (4, 4):
            raise ValueError(f"placements must have shape (n, 4, 4), got {placements.shape}")
        n = placements.shape[0]
        axes = as_real(axes, "axes", np.float64).copy()
        if axes.shape != (n, 3):
            raise ValueError(f"axes must have shape ({n}, 3), got {axes.shape}")
        types = np.zeros(n, dtype=np.int8) if types is None else as_real(types, "types", np.float64)
        if types.shape != (n,) or not np.isin(types, (0, 1)).all():
            raise ValueError(f"types must have shape ({n},) with 0 (revolute) or 1 (prismatic) entries")
        types = types.astype(np.int8)
        self._base = None if base is None else rigid_transforms(base, "base")
        self._tool = None if tool is None else rigid_transforms(tool, "tool")
        self._core = _core.Chain.from_joints(
            placements, axes, types.astype(np.float64), self._base, self._tool
        )
        self._rows = None
        self._convention = "joints"
        self._joints = (placements, axes, types)
        self._names = None if joint_names is None else _names(joint_names)
        if self._names is not None and len(self._names) != n:
            raise ValueError(f"joint_names must have {n} names, got {len(self._names)}")
        self._limits = _limits(limits, n)
        self._ik = None
        self._ik_tolerance = None
        self._inertials = None
        self._dynamics = None

    @classmethod
    def from_urdf(
        cls, source: str | bytes | os.PathLike[str], tip: str | None = None, base: str | None = None
    ) -> Chain:
        """The chain from link ``base`` to link ``tip`` of a URDF: a robot arm, a gripper, a head, a leg.

        ``source`` is a file path (``str`` or ``os.PathLike``; a ``.xacro`` file is expanded with the
        ``xacro`` package, ``pip install "spotkin[xacro]"``) or the URDF's XML (a ``str`` starting with
        ``<``, or ``bytes``). ``base`` defaults to the root link (below a ``world`` link and its
        ``floating`` or ``fixed`` root joint, which are read past). ``tip`` defaults to the end of the
        only chain below ``base``: each leaf link moved by an actuated joint ends one, cut before the
        first joint of a gripper on its way (a mimic joint whose leader is on another branch, or that
        leader: fingers; the tip is then the hand they hang from; a mimic joint below its leader is
        part of the chain), and leaves moved by the same joints (a flange and a tool frame) end at the
        link where they branch; with several chains (two arms, four legs, fingers that are no mimic of
        each other) ``ValueError`` lists their tips. ``tip`` may be any link below ``base``.

        The chain is :meth:`spotkin.Robot.chain`'s: fixed joints merged, the URDF's joint names and
        limits, the bodies' mass properties when the file gives ``<inertial>`` (:attr:`inertials`), and
        the closed-form IK family recognised from the geometry (:attr:`ik_kind`). A path holding mimic
        joints gives a chain whose q holds the independent joints and the mimic joints' leaders (a
        leader off the path included); the mimic joints follow them in FK, Jacobians, IK and dynamics
        (``full_chain``, ``mimic_matrix``: ``q_full = M q + b``).

        ``TypeError`` for another ``source``, ``tip`` or ``base`` type; ``ValueError`` naming the
        joint or link for a malformed description, an unknown link, or a description above 64 MiB;
        ``OSError`` when the file cannot be read; ``ImportError`` (saying what to install) for xacro
        without the ``xacro`` package.
        """
        return _from_urdf(source, tip, base)

    @classmethod
    def from_mdh(
        cls,
        rows: ArrayLike,
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        limits: ArrayLike | None = None,
    ) -> Chain:
        """Chain from a modified-DH table, one row ``(sigma, d, alpha, r, theta)`` per joint.

        T(j-1, j) = RotX(alpha) · TransX(d) · RotZ(theta) · TransZ(r). ``sigma`` is 0
        for a revolute joint (q adds to theta) and 1 for a prismatic one (q adds to r).
        ``limits`` is an optional (dof, 2) array of (lower, upper) joint limits.
        """
        return Chain(rows, convention="mdh", base=base, tool=tool, limits=limits)

    @classmethod
    def from_dh(
        cls,
        rows: ArrayLike,
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        limits: ArrayLike | None = None,
    ) -> Chain:
        """Chain from a classic-DH table, one row ``(sigma, a, alpha, d, theta)`` per joint.

        T(j-1, j) = RotZ(theta) · TransZ(d) · TransX(a) · RotX(alpha). The joint
        variable adds to theta (sigma = 0) or to d (sigma = 1). Joint j turns about
        the z axis of frame j-1.
        """
        return Chain(rows, convention="dh", base=base, tool=tool, limits=limits)

    @property
    def dof(self) -> int:
        """Number of joints."""
        return self._core.dof

    @property
    def rows(self) -> np.ndarray | None:
        """A copy of the DH table, (dof, 5); None for a chain built from joints."""
        return None if self._rows is None else self._rows.copy()

    @property
    def convention(self) -> str:
        """``"mdh"``, ``"dh"``, or ``"joints"`` (built by :meth:`from_joints` or from a URDF)."""
        return self._convention

    @property
    def joint_names(self) -> tuple[str, ...] | None:
        """The joints' names (from a URDF), or None."""
        return self._names

    @property
    def sigma(self) -> np.ndarray:
        """Joint types, (dof,): 0 revolute, 1 prismatic."""
        if self._rows is None:
            return self._joints[2].copy()
        return self._rows[:, 0].astype(np.int8)

    @property
    def base(self) -> np.ndarray:
        """Base transform, (4, 4)."""
        return np.eye(4) if self._base is None else self._base.copy()

    @property
    def tool(self) -> np.ndarray:
        """Tool transform, (4, 4)."""
        return np.eye(4) if self._tool is None else self._tool.copy()

    @property
    def lower(self) -> np.ndarray:
        """Lower joint limits, (dof,); -inf where unlimited."""
        return self._limits[0].copy()

    @property
    def upper(self) -> np.ndarray:
        """Upper joint limits, (dof,); +inf where unlimited."""
        return self._limits[1].copy()

    @property
    def limits(self) -> np.ndarray:
        """(dof, 2) joint limits (lower, upper); ±inf where unlimited (as :attr:`spotkin.Leg.limits`)."""
        return np.stack(self._limits, axis=1)

    @property
    def inertials(self):
        """The bodies' mass properties (:class:`spotkin.inertia.LinkInertials`), or None. Row j is the
        body moved by joint j, in frame j + 1 of :meth:`frames`; a chain from :meth:`spotkin.Robot.chain`
        carries its URDF's (fixed children merged, see :mod:`spotkin.inertia`)."""
        return self._inertials

    def with_inertials(self, mass: ArrayLike, com: ArrayLike, inertia: ArrayLike) -> Chain:
        """This chain carrying mass properties: a new Chain (the same model; the original is unchanged).

        ``mass`` (dof,) kg >= 0; ``com`` (dof, 3) m, each body's centre of mass in frame j + 1 of
        :meth:`frames` (the frame after joint j's motion); ``inertia`` (dof, 3, 3) kg m², the rotational
        inertia about the centre of mass in that frame's axes, symmetric positive semidefinite.
        ``TypeError`` for non-numeric input, ``ValueError`` naming the argument otherwise (see
        :func:`spotkin.inertia.link_inertials`).
        """
        inertials = link_inertials(mass, com, inertia, self.dof)
        chain = self._copy()
        chain._inertials = inertials
        chain._dynamics = None  # built from the new inertials on first use
        return chain

    def _renamed(self, names: tuple[str, ...]) -> Chain:
        """This chain with other joint names (a new object), checked as :meth:`from_joints` checks them."""
        if len(names) != self.dof:
            raise ValueError(f"joint_names must have {self.dof} names, got {len(names)}")
        chain = self._copy()
        chain._names = _names(names)
        return chain

    def _copy(self) -> Chain:
        """A shallow copy of this object (every slot, a subclass's too): the ``with_*`` methods' start."""
        chain = self.__class__.__new__(self.__class__)
        for cls in type(self).__mro__:
            for name in getattr(cls, "__slots__", ()):
                setattr(chain, name, getattr(self, name))
        return chain

    @core_method("_core", "fk")
    def fk(self, q: ArrayLike, *, out: np.ndarray | None = None) -> np.ndarray:
        """Base-to-tool transform: q (..., dof) -> (..., 4, 4). ``out``: an array of the result's
        shape and dtype to write into and return (a control loop then allocates nothing)."""
        return self._core.fk(q, out)

    def frames(self, q: ArrayLike) -> np.ndarray:
        """Every frame in the base frame: q (..., dof) -> (..., dof + 2, 4, 4).

        Index 0 is the base transform, index i = 1..dof is T_0i after joint i, and
        the last index is the tool frame.
        """
        return self._core.frames(q)

    @core_method(
        "_core",
        "jacobian",
        call=("q", (6,), (False,), "out"),
        convert={"frame": AT_DEFAULT, "point": AT_DEFAULT},
    )
    def jacobian(
        self,
        q: ArrayLike,
        frame: str | int = "base",
        *,
        point: str | int = "tool",
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Geometric Jacobian [v; w]: q (..., dof) -> (..., 6, dof).

        By default of the tool point in the base frame: column j is [z_j x (p_tool - o_j); z_j] for a
        revolute joint and [z_j; 0] for a prismatic one, where z_j is joint j's axis and o_j a point
        on it. ``frame="tool"`` rotates both blocks into the tool frame (same point, tool axes).

        **Preferential Jacobian** J_k(j): ``point=k`` takes the origin of frame k instead of the tool
        point, ``frame=j`` expresses both blocks in frame j's axes. Frames are numbered as
        :meth:`frames`: 0 is the base transform's frame (frame 0 of a DH table), i = 1..dof the frame
        after joint i, dof + 1 the tool (also ``"tool"``); ``frame="base"`` is the reference frame
        the poses are given in (the same axes as frame 0 when ``base`` is the identity). Columns of
        the joints after frame k are zero (they do not move its origin), and

            J_k(j) = [[R_j^T, 0], [0, R_j^T]] J_k(base),

        R_j frame j's rotation: the velocity of O_k and the angular velocity of frame k, both
        relative to the base, written in frame j's axes. ``point`` and ``frame`` must be integers in
        [0, dof + 1] or the strings above (``ValueError`` out of range, ``TypeError`` for another type).
        ``out``: an array of the result's shape and dtype to write into and return.
        """
        if frame is _BASE and point is _TOOL:  # the defaults (interned strings): the control loop's call
            return self._core.jacobian(q, 6, False, out)
        return self._point_jacobian(q, 6, frame, point, out)

    def position_jacobian(
        self, q: ArrayLike, frame: str | int = "base", *, point: str | int = "tool"
    ) -> np.ndarray:
        """Top three rows of :meth:`jacobian`, d p / d q of the point (..., 3, dof), in ``frame``'s axes."""
        return self._point_jacobian(q, 3, frame, point)

    def _point_jacobian(self, q, rows: int, frame, point, out=None) -> np.ndarray:
        if isinstance(point, str) and point == "tool" and isinstance(frame, str):
            return self._core.jacobian(q, rows, _tool_frame(frame), out)  # the tool point: the fast kernel
        last = self.dof + 1
        return self._core.point_jacobian(
            q,
            rows,
            _frame_index(point, "point", last, ("tool",)),
            _frame_index(frame, "frame", last, ("base", "tool")),
            out,
        )

    def with_limits(self, limits) -> Chain:
        """This chain with other joint limits: a new Chain (the same model, inertials and IK tolerances;
        the original is unchanged). Every limit-aware call of the new chain uses them: the closed-form
        IK's validity and choice, the free-joint grids, :meth:`ik_differential`'s clamping, and the
        workspace and dexterity estimates.

        ``limits`` is a (dof, 2) table of (lower, upper) rows, or a dict whose keys are joint names
        (:attr:`joint_names`) or indices and whose values are (lower, upper) pairs; the joints a dict
        does not name keep their limits. ±inf means unlimited. ``ValueError`` naming the joint for an
        unknown name or index, NaN, or lower > upper; ``TypeError`` for non-numeric values.
        """
        if not isinstance(limits, Mapping) and (limits is None or np.ndim(limits) == 0):
            raise TypeError(
                "limits must be a (dof, 2) table or a dict joint -> (lower, upper), "
                f"got {type(limits).__name__}"
            )
        lower, upper = _limit_override(limits, self._limits, self._names, "limits")
        chain = self._copy()
        chain._limits = (lower, upper)
        chain._ik = None  # the closed-form solvers hold the limits
        return chain

    def __reduce__(self):
        limits = None if np.isinf(self._limits).all() else np.stack(self._limits, axis=1)
        if self._rows is None:
            plain = (_rebuild_joints, (*self._joints, self._base, self._tool, limits, self._names))
        else:
            plain = (_rebuild_chain, (self._rows, self._convention, self._base, self._tool, limits))
        if self._inertials is not None:
            plain = (_rebuild_with_inertials, (*plain, tuple(self._inertials)))
        if self._ik_tolerance is None:
            return plain
        return (_rebuild_with_ik_tolerance, (*plain, self._ik_tolerance))

    def __repr__(self) -> str:
        kinds = "".join("RP"[int(s)] for s in self.sigma)
        return f"Chain({kinds}, convention={self._convention!r}, dof={self.dof})"


def _rebuild_chain(rows, convention, base, tool, limits) -> Chain:
    return Chain(rows, convention=convention, base=base, tool=tool, limits=limits)


def _rebuild_joints(placements, axes, types, base, tool, limits, names) -> Chain:
    return Chain.from_joints(placements, axes, types, base, tool, limits, names)


def _rebuild_with_ik_tolerance(rebuild, args, tolerance) -> Chain:
    return rebuild(*args).with_ik_tolerance(*tolerance)


def _rebuild_with_inertials(rebuild, args, inertials) -> Chain:
    return rebuild(*args).with_inertials(*inertials)


def _frame_index(value, name: str, last: int, words: tuple[str, ...]) -> int:
    """A frame of :meth:`Chain.frames` as its index (``"tool"``: last, ``"base"``: -1, the reference
    frame's axes)."""
    if isinstance(value, str):
        if value not in words:
            raise ValueError(f"{name} must be an integer in [0, {last}] or one of {words}, got {value!r}")
        return last if value == "tool" else -1
    index = as_index(value, name)
    if not 0 <= index <= last:
        raise ValueError(f"{name} must be a frame index in [0, {last}] (as Chain.frames), got {index}")
    return index


_BASE, _TOOL = "base", "tool"  # Chain.jacobian's defaults


def _tool_frame(frame: str) -> bool:
    if frame not in ("base", "tool"):
        raise ValueError(f"frame must be 'base', 'tool' or a frame index, got {frame!r}")
    return frame == "tool"
