"""Planar slices of a leg's (or a 3-joint chain's) reach (:func:`workspace`), coloured by the number of
valid IK branches from one batched ``ik_all`` call over the grid, with the singular sets and contours of
``|det J|``."""

from __future__ import annotations

import math
from typing import NamedTuple

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from numpy.typing import ArrayLike

from ._common import _LIMIT, _check_ax, _near, as_index, as_real, as_scalar
from ._solvers import _default_q, _has_frames, _is_leg, _is_solver, _joint_origins, _revolute

_PLANES = {"xz": (0, 2, 1), "yz": (1, 2, 0), "xy": (0, 1, 2)}  # (horizontal, vertical, fixed) axes
_MAX_RESOLUTION = 1000
# workspace categories: unreachable, blocked by the limits, 1, 2, 3 or 4 valid branches
_MAP_COLOURS = ("#ffffff", "#d9d9d9", "#6baed6", "#2171b5", "#08306b")
_MAP_LABELS = (
    "unreachable (no branch)",
    "branches exist, none within the limits",
    "1 valid branch",
    "2 valid branches",
    "3 or 4 valid branches",
)


class _Grid(NamedTuple):
    u: np.ndarray  # (nu,) horizontal coordinates
    v: np.ndarray  # (nv,) vertical coordinates
    points: np.ndarray  # (nv, nu, 3)
    code: np.ndarray  # (nv, nu): -2 unreachable, -1 blocked by the limits, else the number of valid branches
    det: np.ndarray  # (nv, nu) |det J| of the first valid (else existing) branch, NaN where none exists


def _reach(solver) -> float:
    """How far from its hip-roll joint (its base) the solver reaches, at most: a leg's |a| and its
    pitch-plane reach; a chain's links at zero angles and its prismatic joints' largest travel."""
    if _is_leg(solver):
        return float(np.linalg.norm(solver.a) + solver.reach[1])
    origins = _joint_origins(solver, np.zeros(solver.dof))[0]
    reach = float(np.linalg.norm(np.diff(origins, axis=0), axis=1).sum())
    for (lower, upper), revolute in zip(solver.limits, _revolute(solver)):
        if not revolute:
            reach += max(abs(lower), abs(upper))
    if not math.isfinite(reach):
        raise ValueError("a prismatic joint without finite limits: give the map's extent")
    return reach


def _workspace_grid(solver, plane: str, offset: float, resolution: int, extent) -> _Grid:
    i, j, k = _PLANES[plane]
    u = np.linspace(extent[0], extent[1], resolution)
    v = np.linspace(extent[2], extent[3], resolution)
    points = np.empty((resolution, resolution, 3))
    points[..., i] = u[None, :]
    points[..., j] = v[:, None]
    points[..., k] = offset
    sol = solver.ik_all(points)  # one batched call
    count = sol.valid.sum(axis=-1)
    code = np.where(count > 0, np.minimum(count, 3), np.where(sol.exists.any(axis=-1), -1, -2))
    # |det J| of the first valid branch, else the first existing one
    pick = np.where(sol.valid.any(axis=-1), sol.valid.argmax(axis=-1), sol.exists.argmax(axis=-1))
    q = np.take_along_axis(sol.q, pick[..., None, None], axis=-2)[..., 0, :]
    with np.errstate(all="ignore"):  # d p / d q: a leg's Jacobian, the top rows of a chain's
        det = np.abs(np.linalg.det(solver.jacobian(np.nan_to_num(q))[..., :3, :]))
    det = np.where(sol.exists.any(axis=-1), det, np.nan)
    return _Grid(u, v, points, code.astype(np.int8), det)


def _crosses(field: np.ndarray, level: float = 0.0) -> bool:
    finite = field[np.isfinite(field)]
    return finite.size > 0 and finite.min() < level < finite.max()


def _cylinder_curves(h: float, plane: str, offset: float, extent: np.ndarray) -> list[np.ndarray]:
    """The hip-roll cylinder y² + z² = h² on the plane, as (m, 2) curves of (u, v) points (exact)."""
    if plane == "yz":
        angle = np.linspace(0.0, 2 * math.pi, 361)
        return [abs(h) * np.stack([np.cos(angle), np.sin(angle)], axis=1)]
    if abs(offset) > abs(h):  # the plane misses the cylinder
        return []
    level = math.sqrt(h * h - offset * offset)  # z (plane xz, y = offset) or y (plane xy, z = offset)
    u = np.array([extent[0], extent[1]])
    return [
        np.stack([u, np.full(2, sign * level)], axis=1) for sign in ((1.0, -1.0) if level > 0 else (1.0,))
    ]


def _knee_singular_fields(leg, points: np.ndarray) -> list[np.ndarray]:
    """Fields |W|² - (|B| ± |C|)², zero where the knee is stretched (+) or folded (-), for each hip
    branch, NaN inside the hip-roll cylinder (docs/derivations.md, "Roll–pitch–pitch legs from a URDF":
    W = (v_z - a_z) + i (x - a_x) with v_z = -ε sqrt(y² + z² - h²))."""
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    h = leg.hip_offset
    a, b, c = leg.a, leg.b, leg.c
    B, C = math.hypot(b[0], b[2]), math.hypot(c[0], c[2])
    square = y * y + z * z - h * h
    with np.errstate(invalid="ignore"):
        S = np.sqrt(np.where(square >= 0, square, np.nan))
    fields = []
    for epsilon in (1.0, -1.0) if a[2] != 0 else (1.0,):
        W2 = (-epsilon * S - a[2]) ** 2 + (x - a[0]) ** 2
        fields += [W2 - (B + C) ** 2, W2 - (B - C) ** 2]
    return fields


def workspace(
    solver,
    plane: str = "xz",
    offset: float | None = None,
    resolution: int = 400,
    extent: ArrayLike | None = None,
    ax=None,
) -> Figure:
    """A slice of a leg's reach, coloured by the number of valid IK branches.

    The grid of ``resolution`` x ``resolution`` targets on the plane is solved by one batched
    ``ik_all`` call of the solver (:meth:`Leg.ik_all`, :meth:`Chain.ik_all`). Each target is coloured by
    its count of valid branches (1, 2, 3 or 4), or as unreachable (no branch exists) or blocked by the
    joint limits (branches exist, none within the limits: hatched). Over the map: the singular sets of
    a leg, the knee stretched or folded (|W| = |B| ± |C| in the pitch plane) and the hip-roll
    cylinder y² + z² = h²; contours of ``|det J|`` (m³) of the first valid branch (else the first
    existing one), which for a chain also show its singular sets; the hip-roll joint (the chain's base);
    and, for a leg on a vertical plane, the lowest target with two or more valid branches: below it at
    most one is valid (for Spot's legs, about 8 cm below the hip, as the tests prove on random stances;
    a chain's map has no such line, as "below" means nothing for a chain's base).

    Parameters
    ----------
    solver:
        An :class:`spotkin.Leg` (coordinates in its leg frame) or a 3-joint :class:`spotkin.Chain`
        (its base frame).
    plane:
        ``"xz"`` (a vertical plane along the body, y = offset), ``"yz"`` (across it, x = offset) or
        ``"xy"`` (horizontal, z = offset).
    offset:
        The fixed coordinate (m). Default: for a leg, y = its lateral offset h (the plane of a nominal
        stance's foot) for ``"xz"``, x = the hip-pitch joint's for ``"yz"``, z = -0.75 of the reach for
        ``"xy"``; for a chain, 0.
    resolution:
        Targets per side, 2 to 1000 (default 400: 160,000 targets).
    extent:
        (u_min, u_max, v_min, v_max) of the plane's horizontal and vertical coordinates; default: a
        square around the hip (the base) that holds the whole reach.
    ax:
        A 2D Axes to draw in; default: a new figure.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn in. The map is ``ax.images[0]``: its array holds, per target, the number of
        valid branches, -1 (blocked by the limits) or -2 (unreachable); pixel (r, c) is the target at
        u = linspace(u_min, u_max, resolution)[c], v = linspace(v_min, v_max, resolution)[r].

    Raises ``TypeError`` for another solver or non-numeric arguments, and ``ValueError`` for an
    unknown plane, a non-finite offset, a resolution out of range, an extent that is not 4 increasing
    finite bounds, an offset or extent beyond 1e6 m, a chain without 3 joints, or a 3D ``ax``.
    """
    # a solver whose joints the map can place: by a leg's geometry or a chain's frames
    if not (_is_solver(solver) and (_is_leg(solver) or _has_frames(solver))):
        raise TypeError(f"solver must be an sk.Leg or a 3-joint sk.Chain, got {type(solver).__name__}")
    if solver.dof != 3:
        raise ValueError(f"workspace maps legs and 3-joint chains, this chain has {solver.dof} joints")
    if not isinstance(plane, str):
        raise TypeError(f"plane must be a str, one of {tuple(_PLANES)}, got {type(plane).__name__}")
    if plane not in _PLANES:
        raise ValueError(f"plane must be one of {tuple(_PLANES)}, got {plane!r}")
    resolution = as_index(resolution, "resolution")
    if not 2 <= resolution <= _MAX_RESOLUTION:
        raise ValueError(f"resolution must be an integer in [2, {_MAX_RESOLUTION}], got {resolution}")
    ax = _check_ax(ax, three_d=False)
    leg = solver if _is_leg(solver) else None  # the singular sets and the default planes of a leg
    i, j, k = _PLANES[plane]
    centre = _joint_origins(solver, _default_q(solver))[0][0]  # the hip-roll joint, a chain's base
    if offset is None:
        if leg is None:
            offset = 0.0
        else:
            offset = {"xz": leg.hip_offset, "yz": float(leg.a[0]), "xy": -0.75 * leg.reach[1]}[plane]
    else:
        offset = as_scalar(offset, "offset")
        if not math.isfinite(offset):
            raise ValueError(f"offset must be a finite number, got {offset!r}")
        _near(np.array([offset]), "offset", "the plane")
    if extent is None:
        half = 1.05 * _reach(solver)
        extent = np.array([centre[i] - half, centre[i] + half, centre[j] - half, centre[j] + half])
    else:
        extent = as_real(extent, "extent", np.float64)
        if extent.shape != (4,):
            raise ValueError(
                f"extent must have shape (4,) as (u_min, u_max, v_min, v_max), got {extent.shape}"
            )
        if not (np.isfinite(extent).all() and extent[0] < extent[1] and extent[2] < extent[3]):
            raise ValueError(
                f"extent must be finite with u_min < u_max and v_min < v_max, got {extent.tolist()}"
            )
        _near(extent, "extent", "the map")
    with np.errstate(all="ignore"):  # targets far from the leg: unreachable, never a warning
        grid = _workspace_grid(solver, plane, offset, resolution, extent)
    if ax is None:
        fig = plt.figure(figsize=(9.5, 6.5))
        ax = fig.add_axes((0.08, 0.1, 0.55, 0.8))
    du = (extent[1] - extent[0]) / max(resolution - 1, 1)
    dv = (extent[3] - extent[2]) / max(resolution - 1, 1)
    ax.imshow(
        grid.code,
        origin="lower",
        interpolation="nearest",
        aspect="equal",
        extent=(extent[0] - du / 2, extent[1] + du / 2, extent[2] - dv / 2, extent[3] + dv / 2),
        cmap=ListedColormap(_MAP_COLOURS),
        norm=BoundaryNorm((-2.5, -1.5, 0.0, 1.5, 2.5, 4.5), 5),
        gid="branch-count",
    )
    U, V = np.meshgrid(grid.u, grid.v)
    blocked = (grid.code == -1).astype(float)
    handles = [
        Patch(facecolor=c, edgecolor="black", linewidth=0.5, label=t)
        for c, t in zip(_MAP_COLOURS, _MAP_LABELS)
    ]
    handles[1].set_hatch("////")
    if _crosses(blocked, 0.5):
        ax.contourf(U, V, blocked, levels=(0.5, 1.5), colors="none", hatches=("////",))
    finite_det = grid.det[np.isfinite(grid.det)]
    if finite_det.size and finite_det.max() > 0:
        levels = finite_det.max() * np.array([0.02, 0.1, 0.3, 0.6])
        det = np.ma.masked_invalid(grid.det)
        contours = ax.contour(U, V, det, levels=levels, colors="#525252", linewidths=0.7, linestyles="-")
        ax.clabel(contours, fmt="%.2g", fontsize=6)
        handles.append(Line2D([], [], color="#525252", linewidth=0.7, label="|det J| contours (m³)"))
    if leg is not None:
        knees = _knee_singular_fields(leg, grid.points)
        for curve in _cylinder_curves(leg.hip_offset, plane, offset, extent):
            ax.plot(*curve.T, color="black", linewidth=1.6, linestyle="--", gid="singular:hip-roll")
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                linewidth=1.6,
                linestyle="--",
                label="singular: hip-roll cylinder y² + z² = h²",
            )
        )
        for field in knees:
            if _crosses(field):
                contour = ax.contour(
                    U,
                    V,
                    np.ma.masked_invalid(field),
                    levels=(0.0,),
                    colors="black",
                    linewidths=1.6,
                    linestyles=":",
                )
                for artist in getattr(contour, "collections", None) or [contour]:  # one per level before 3.8
                    artist.set_gid("singular:knee")
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                linewidth=1.6,
                linestyle=":",
                label="singular: knee stretched or folded",
            )
        )
    base = centre[[i, j]]
    ax.plot(*base, linestyle="none", marker="P", markersize=9, color="white", markeredgecolor="black")
    handles.append(
        Line2D(
            [],
            [],
            linestyle="none",
            marker="P",
            markersize=9,
            color="white",
            markeredgecolor="black",
            label="hip-roll joint" if leg is not None else "base",
        )
    )
    if leg is not None and plane != "xy" and (grid.code >= 2).any():  # a leg's uniqueness height
        lowest = float(V[grid.code >= 2].min())
        ax.axhline(lowest, color=_LIMIT, linewidth=1.2, linestyle="-.", gid="lowest-two-branches")
        handles.append(
            Line2D(
                [],
                [],
                color=_LIMIT,
                linewidth=1.2,
                linestyle="-.",
                label=f"lowest target with 2+ valid branches,\nz = {lowest:+.3f} m: at most one below",
            )
        )
    names = "xyz"
    frame = "leg frame" if leg is not None else "base frame"
    ax.set_xlabel(f"{names[i]} (m, {frame})")
    ax.set_ylabel(f"{names[j]} (m, {frame})")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    label = (leg.name or "leg") if leg is not None else "chain"
    ax.set_title(
        f"{label}: valid IK branches on the plane {names[k]} = {offset:.3f} m\n"
        f"({resolution} x {resolution} targets, one batched IK call)",
        fontsize=10,
    )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    return ax.figure
