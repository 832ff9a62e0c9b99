"""Serial chains from Denavit–Hartenberg tables: FK, frames and geometric Jacobians."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from . import _core

__all__ = ["Chain"]

_CONVENTIONS = {
    "mdh": _core.Convention.MODIFIED_DH,
    "dh": _core.Convention.CLASSIC_DH,
}


def _table(rows: ArrayLike) -> np.ndarray:
    try:
        table = np.asarray(rows)
    except ValueError as error:  # ragged rows
        raise ValueError(f"rows must be a numeric table of shape (n, 5): {error}") from None
    if table.dtype.kind not in "biuf":
        raise TypeError(f"rows must be a numeric table of shape (n, 5), got dtype {table.dtype}")
    if table.ndim != 2 or table.shape[1] != 5:
        raise ValueError(f"rows must have shape (n, 5), got {table.shape}")
    return table.astype(np.float64)


def _limits(limits: ArrayLike | None, dof: int) -> tuple[np.ndarray, np.ndarray]:
    if limits is None:
        return np.full(dof, -np.inf), np.full(dof, np.inf)
    table = np.array(limits, dtype=np.float64)
    if table.shape != (dof, 2):
        raise ValueError(f"limits must have shape ({dof}, 2) as (lower, upper) rows, got {table.shape}")
    lower, upper = table[:, 0].copy(), table[:, 1].copy()
    if np.isnan(table).any() or (lower > upper).any():
        raise ValueError("limits must satisfy lower <= upper, with no NaN")
    return lower, upper


class Chain:
    """A serial chain of revolute and prismatic joints described by a DH table.

    Build one with :meth:`from_mdh` (modified DH, Khalil–Kleinfinger) or
    :meth:`from_dh` (classic DH). ``base`` maps the world (base) frame to frame 0,
    ``tool`` maps the last joint frame to the tool frame; both are (4, 4).

    Batch semantics follow NumPy: ``q`` has shape ``(..., dof)`` and leading
    dimensions are kept; float32 input gives float32 output, anything else is
    computed in float64. NaN in ``q`` propagates to NaN in the result.
    """

    __slots__ = ("_base", "_convention", "_core", "_limits", "_rows", "_tool")

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
        self._base = None if base is None else np.array(base, dtype=np.float64)
        self._tool = None if tool is None else np.array(tool, dtype=np.float64)
        self._core = _core.Chain(_CONVENTIONS[convention], table, self._base, self._tool)
        self._limits = _limits(limits, table.shape[0])

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
        return cls(rows, convention="mdh", base=base, tool=tool, limits=limits)

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
        return cls(rows, convention="dh", base=base, tool=tool, limits=limits)

    @property
    def dof(self) -> int:
        """Number of joints."""
        return self._rows.shape[0]

    @property
    def rows(self) -> np.ndarray:
        """A copy of the DH table, (dof, 5)."""
        return self._rows.copy()

    @property
    def convention(self) -> str:
        """``"mdh"`` or ``"dh"``."""
        return self._convention

    @property
    def sigma(self) -> np.ndarray:
        """Joint types, (dof,): 0 revolute, 1 prismatic."""
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

    def fk(self, q: ArrayLike) -> np.ndarray:
        """Base-to-tool transform: q (..., dof) -> (..., 4, 4)."""
        return self._core.fk(q)

    def frames(self, q: ArrayLike) -> np.ndarray:
        """Every frame in the base frame: q (..., dof) -> (..., dof + 2, 4, 4).

        Index 0 is the base transform, index i = 1..dof is T_0i after joint i, and
        the last index is the tool frame.
        """
        return self._core.frames(q)

    def jacobian(self, q: ArrayLike, frame: Literal["base", "tool"] = "base") -> np.ndarray:
        """Geometric Jacobian [v; w] of the tool point: q (..., dof) -> (..., 6, dof).

        Column j is [z_j x (p_tool - o_j); z_j] for a revolute joint and [z_j; 0]
        for a prismatic one, where z_j is joint j's axis and o_j a point on it.
        ``frame="base"`` expresses both blocks in the base frame; ``frame="tool"``
        rotates them into the tool frame (same point, v and w in tool axes).
        """
        return self._core.jacobian(q, 6, _tool_frame(frame))

    def position_jacobian(self, q: ArrayLike, frame: Literal["base", "tool"] = "base") -> np.ndarray:
        """Top three rows of :meth:`jacobian`, d p_tool / d q: (..., 3, dof)."""
        return self._core.jacobian(q, 3, _tool_frame(frame))

    def __reduce__(self):
        limits = None if np.isinf(self._limits).all() else np.stack(self._limits, axis=1)
        return (_rebuild, (self._rows, self._convention, self._base, self._tool, limits))

    def __repr__(self) -> str:
        kinds = "".join("RP"[int(s)] for s in self._rows[:, 0])
        return f"Chain({kinds}, convention={self._convention!r}, dof={self.dof})"


def _rebuild(rows, convention, base, tool, limits) -> Chain:
    return Chain(rows, convention=convention, base=base, tool=tool, limits=limits)


def _tool_frame(frame: str) -> bool:
    if frame not in ("base", "tool"):
        raise ValueError(f"frame must be 'base' or 'tool', got {frame!r}")
    return frame == "tool"
