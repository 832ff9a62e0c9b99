"""Walks: a gait diagram (:func:`gait_diagram`, each leg's stance as bars against time) and the feet's
paths in side view over each leg's workspace (:func:`foot_paths`)."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from ._common import _BLOCKED, _LEG, _check_ax, _check_robot, _check_title, _near, as_real

_PLANNED, _MEASURED = "#08519c", "#fd8d3c"  # dark blue, light orange: distinct in greyscale
_WORKSPACE_GRID = 121  # grid points a side of the reachable region drawn under a foot path
_REACHABLE = "#deebf7"  # very light blue


def _contact(value: ArrayLike, name: str, ticks: int | None = None) -> np.ndarray:
    """(ticks, n) bool from bools (or 0 / 1), or TypeError / ValueError naming the argument."""
    array = np.asarray(value)
    if array.dtype != np.bool_:
        if array.dtype.kind not in "iu" or not np.isin(array, (0, 1)).all():
            raise TypeError(f"{name} must be a bool array (ticks, n_legs), got dtype {array.dtype}")
        array = array.astype(bool)
    if array.ndim != 2 or array.shape[0] < 1 or array.shape[1] < 1:
        raise ValueError(f"{name} must have shape (ticks, n_legs), got {array.shape}")
    if ticks is not None and array.shape[0] != ticks:
        raise ValueError(f"{name} must have {ticks} ticks, got {array.shape[0]}")
    return array


def _names(legs, n: int) -> list[str]:
    if legs is None:
        return [f"leg {k}" for k in range(n)]
    if isinstance(legs, str) or not all(isinstance(name, str) for name in legs):
        raise TypeError("legs must be a sequence of names (str), one per leg")
    names = list(legs)
    if len(names) != n:
        raise ValueError(f"legs must name {n} legs, got {len(names)}")
    return names


def _spans(t: np.ndarray, down: np.ndarray, dt: float) -> list[tuple[float, float]]:
    """(start, width) of each run of True in ``down``, each tick lasting until the next one."""
    edges = np.flatnonzero(np.diff(np.r_[0, down.astype(np.int8), 0]))
    ends = np.r_[t[1:], t[-1] + dt]
    return [(float(t[a]), float(ends[b - 1] - t[a])) for a, b in zip(edges[::2], edges[1::2])]


def gait_diagram(
    contact: ArrayLike,
    t: ArrayLike | None = None,
    *,
    legs=None,
    measured: ArrayLike | None = None,
    ax=None,
    title: str | None = None,
) -> Figure:
    """A gait diagram: a bar per leg, filled while its foot is down.

    ``contact`` (ticks, n_legs) bool: the planned stance (``GaitPlan.contact``, ``JointCommand.contact``
    tick by tick); ``t`` (ticks,) their times (s; default the tick numbers); ``legs`` the legs' names
    (``robot.leg_names``); ``measured`` (ticks, n_legs) bool, optional: the measured contacts
    (``SimResult.contact``), drawn as a thinner bar under each planned one. Into ``ax`` (a 2D Axes) when
    given, else a new figure; returns the Figure. Each leg's bars have the gid ``"stance:<k>"`` (and
    ``"measured:<k>"``).
    """
    down = _contact(contact, "contact")
    ticks, n = down.shape
    if t is None:
        times = np.arange(ticks, dtype=np.float64)
    else:
        times = as_real(t, "t", np.float64)
        if times.shape != (ticks,):
            raise ValueError(f"t must have shape ({ticks},) (one time per tick), got {times.shape}")
        if not np.isfinite(times).all() or (np.diff(times) <= 0).any():
            raise ValueError("t must be finite and increasing")
        _near(times, "t", "the times")
    touched = None if measured is None else _contact(measured, "measured", ticks)
    if touched is not None and touched.shape[1] != n:
        raise ValueError(f"measured must have {n} legs as contact has, got {touched.shape[1]}")
    names = _names(legs, n)
    ax = _check_ax(ax, three_d=False)
    title = _check_title(title)
    if ax is None:
        fig, ax = plt.subplots(figsize=(8.0, 0.6 + 0.45 * n), layout="constrained")
    else:
        fig = ax.figure
    dt = float(times[1] - times[0]) if ticks > 1 else 1.0
    for k in range(n):
        row = n - 1 - k  # the first leg on top
        planned_at = (row + 0.2, 0.6) if touched is None else (row + 0.35, 0.5)
        ax.broken_barh(_spans(times, down[:, k], dt), planned_at, facecolors=_PLANNED, gid=f"stance:{k}")
        if touched is not None:
            spans = _spans(times, touched[:, k], dt)
            ax.broken_barh(spans, (row + 0.1, 0.2), facecolors=_MEASURED, gid=f"measured:{k}")
    ax.set_yticks(np.arange(n) + 0.5, names[::-1])
    ax.set_ylim(0.0, n)
    ax.set_xlim(float(times[0]), float(times[-1]) + dt)
    ax.set_xlabel("t (s)" if t is not None else "tick")
    handles = [plt.Rectangle((0, 0), 1, 1, color=_PLANNED, label="planned stance")]
    if touched is not None:
        handles.append(plt.Rectangle((0, 0), 1, 1, color=_MEASURED, label="measured contact"))
    ax.legend(handles=handles, loc="upper right", fontsize="small", framealpha=0.9)
    ax.set_title(title if title is not None else "gait diagram")
    return fig


def _window(feet: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) (x, z) corners of a view around a foot path (K, 2), padded by a third of the reach."""
    low, high = feet.min(axis=0), feet.max(axis=0)
    middle, half = 0.5 * (low + high), 0.5 * (high - low) + reach / 3.0
    return middle - half, middle + half


def _sagittal_workspace(leg, lateral: float, low: np.ndarray, high: np.ndarray):
    """(x, z, reachable) on a grid over the window: where the leg reaches within its limits (``leg.ik``
    status OK, one batched call) in the plane ``lateral`` from the hip-pitch joint (x, z from it)."""
    xs = np.linspace(low[0], high[0], _WORKSPACE_GRID)
    zs = np.linspace(low[1], high[1], _WORKSPACE_GRID)
    X, Z = np.meshgrid(xs, zs)
    a = np.asarray(leg.a, dtype=np.float64)
    points = np.stack([X.ravel() + a[0], np.full(X.size, lateral + a[1]), Z.ravel() + a[2]], axis=1)
    status = np.asarray(leg.ik(points)[1])
    return X, Z, (status == 0).reshape(X.shape)


def foot_paths(robot, q: ArrayLike, *, ax=None, title: str | None = None) -> Figure:
    """The feet's paths in side view, each relative to its leg's hip-pitch joint in the body frame
    (forward x, up z), over the leg's workspace: the region it reaches within its joint limits (shaded,
    ``leg.ik`` status OK on a grid) in the plane of the path's mean lateral offset, around the path.

    ``robot`` a :class:`spotkin.Robot`; ``q`` (ticks, 3 n_legs) (or with the arm's joints after the
    legs', ignored): the leg joints along a walk (``GaitPlan.q``, ``SimResult.q``). A panel per leg
    (titled with its name and role), or every leg into ``ax`` (a 2D Axes) when given; returns the
    Figure. Each path has the gid ``"path:<k>"``, its (x, z) in metres.
    """
    robot = _check_robot(robot)
    n = robot.n_legs
    joints = as_real(q, "q", np.float64)
    if joints.ndim != 2 or joints.shape[0] < 1 or joints.shape[1] < 3 * n:
        raise ValueError(f"q must have shape (ticks, {3 * n}) (the legs' joints), got {joints.shape}")
    joints = joints[:, : 3 * n]
    if not np.isfinite(joints).all():
        raise ValueError("q must be finite to be drawn")
    ax = _check_ax(ax, three_d=False)
    title = _check_title(title)
    names = list(robot.leg_joint_names)
    if ax is None:
        cols = 2 if n > 1 else 1
        rows = math.ceil(n / cols)
        fig, axes = plt.subplots(
            rows, cols, figsize=(4.0 * cols, 3.4 * rows), layout="constrained", squeeze=False
        )
        panels = list(axes.ravel())
        for extra in panels[n:]:
            extra.set_visible(False)
    else:
        fig, panels = ax.figure, [ax] * n
    roles = list(robot.leg_roles) if n == 4 else [""] * n
    for k, leg in enumerate(robot.legs):
        columns = [names.index(j) for j in leg.joint_names]
        feet = np.asarray(leg.fk(joints[:, columns]), dtype=np.float64) - np.asarray(leg.a, dtype=np.float64)
        panel = panels[k]
        _near(feet, "q", "the feet")
        if ax is None or k == 0:
            low, high = _window(feet[:, [0, 2]], float(leg.reach[1]))
            X, Z, inside = _sagittal_workspace(leg, float(feet[:, 1].mean()), low, high)
            panel.contourf(X, Z, inside.astype(float), levels=[0.5, 1.5], colors=[_REACHABLE])
            panel.contour(X, Z, inside.astype(float), levels=[0.5], colors=[_BLOCKED], linewidths=0.8)
            panel.set_xlim(low[0], high[0])
            panel.set_ylim(low[1], high[1])
        panel.plot(
            feet[:, 0],
            feet[:, 2],
            color=_LEG if ax is None else None,
            linewidth=1.4,
            gid=f"path:{k}",
            label=f"{robot.leg_names[k]} foot",
        )
        panel.plot(feet[:1, 0], feet[:1, 2], marker="s", color="black", markersize=4, linestyle="none")
        panel.set_aspect("equal", adjustable="box")
        panel.set_xlabel("x (m), forward of the hip-pitch joint")
        panel.set_ylabel("z (m), above it")
        if ax is None:
            role = roles[k].replace("_", " ")
            panel.set_title(f"{robot.leg_names[k]} ({role})" if role else robot.leg_names[k])
    if ax is not None:
        ax.legend(fontsize="small")
        ax.set_title(title if title is not None else "foot paths, side view")
    elif title is not None:
        fig.suptitle(title)
    return fig
