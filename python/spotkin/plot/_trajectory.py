"""Trajectories against time (:func:`trajectory`): a point-to-point motion's q, qd and qdd with its
speed, acceleration and joint limits, or a Cartesian path's position and velocities."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from .. import trajectory as _trajectories
from ._common import _check_fig, _near, as_real

_CYCLE_COLOURS = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d", "#666666")
_CYCLE_STYLES = ("-", "--", "-.", ":")


def _times(t, duration: float) -> np.ndarray:
    if t is None:
        return np.linspace(0.0, duration, 400) if duration > 0 else np.zeros(1)
    times = as_real(t, "t", np.float64)
    if times.ndim != 1 or times.size == 0:
        raise ValueError(f"t must be a non-empty 1-D array of times, got shape {times.shape}")
    if not np.isfinite(times).all():
        raise ValueError("t must be finite")
    _near(times, "t", "the times")
    return times


def _style(k: int) -> dict:
    return {
        "color": _CYCLE_COLOURS[k % len(_CYCLE_COLOURS)],
        "linestyle": _CYCLE_STYLES[k % len(_CYCLE_STYLES)],
    }


def _bound_lines(ax, values: np.ndarray, name: str, unit: str) -> None:
    """± per-axis limits: one pair of black lines when every axis shares the limit, else per axis."""
    if np.allclose(values, values[0]):
        for sign in (1, -1):
            ax.axhline(
                sign * values[0],
                color="black",
                linewidth=1.0,
                linestyle=(0, (6, 3)),
                label=f"±{name} = {values[0]:.3g} {unit}" if sign == 1 else None,
                gid=f"limit:{name}",
            )
        return
    for k, value in enumerate(values):
        style = _style(k)
        for sign in (1, -1):
            ax.axhline(
                sign * value,
                color=style["color"],
                linewidth=0.8,
                linestyle=(0, (6, 3)),
                label=f"±{name} axis {k + 1}" if sign == 1 else None,
                gid=f"limit:{name}",
            )


def _joint_limit_lines(ax, q: np.ndarray, table: np.ndarray, names: tuple) -> None:
    """The q panel's view and joint limits. The view spans the motion (every axis) with a margin of 10 %
    of its range (at least 0.05 rad), widened to hold the bounds near their own joint's motion (within a
    quarter of the panel's range, at least 0.1 rad, of it). Each finite bound within the view is drawn as
    a dotted line; the others are listed beside the panel (id ``"limits-beyond:q"``), an arrow giving
    the side of the view where they lie."""
    low, high = float(q.min()), float(q.max())
    span = high - low
    margin, near = max(0.1 * span, 0.05), max(0.25 * span, 0.1)
    view = [low - margin, high + margin]
    bounds = [(k, side, float(b)) for k in range(len(names)) for side, b in zip(("≥", "≤"), table[k])]
    bounds = [(k, side, b) for k, side, b in bounds if math.isfinite(b)]
    for k, _, bound in bounds:
        if q[:, k].min() - near <= bound <= q[:, k].max() + near:
            view = [min(view[0], bound - 0.5 * margin), max(view[1], bound + 0.5 * margin)]
    beyond, drawn = [], 0
    for k, side, bound in bounds:
        if view[0] <= bound <= view[1]:
            ax.axhline(bound, color=_style(k)["color"], linewidth=0.8, linestyle=(0, (1, 2)), gid="limit:q")
            drawn += 1
        else:
            beyond.append(f"{'↑' if bound > view[1] else '↓'} {names[k]} {side} {bound:.3g}")
    ax.set_ylim(*view)
    if drawn:
        ax.plot([], [], color="black", linewidth=0.8, linestyle=(0, (1, 2)), label="joint limits")
    if beyond:
        ax.text(
            1.01,
            0.0,
            "limits beyond the view (rad):\n" + "\n".join(beyond),
            transform=ax.transAxes,
            ha="left",
            va="bottom",
            fontsize=6.5,
            gid="limits-beyond:q",
        )


def trajectory(
    traj, t: ArrayLike | None = None, limits: ArrayLike | None = None, names=None, fig=None
) -> Figure:
    """A trajectory against time, with its limits.

    - A :class:`spotkin.trajectory.PointToPoint`: q, qd and qdd of every axis (three panels), with the
      speed and acceleration limits ±vmax and ±amax drawn (one pair of lines when every axis shares
      them), and the joint position ``limits`` (n, 2) when given. The q panel spans the motion (with a
      margin of 10 % of its range, at least 0.05 rad), widened for the limits near their joint's motion
      (within a quarter of the range, at least 0.1 rad); the limits in that view are drawn as dotted
      lines, the farther ones (a joint that turns ±3π, say) are listed beside the panel with an arrow for
      the side of the view they lie on; infinite bounds are not drawn.
    - A :class:`spotkin.trajectory.CartesianPath`: the position (x, y, z), the linear velocity and the
      angular velocity (world frame) with their norms; ``limits`` and ``names`` must be None.

    ``t`` (K,): the times to sample (default: 400 over [0, duration]); ``names``: the n axis names
    (default q1, q2, ...); ``fig``: a Figure to draw in (its contents are replaced), default a new one.
    Returns the figure; each sampled curve's data is the trajectory's own ``sample(t)``.

    Raises ``TypeError`` for another object, non-numeric arrays or names that are not strings, and
    ``ValueError`` for times that are not a finite 1-D array, limits not of shape (n, 2) or with NaN,
    times or finite limits beyond 1e6, names of another count, or limits or names for a Cartesian path.
    """
    if not isinstance(traj, (_trajectories.PointToPoint, _trajectories.CartesianPath)):
        raise TypeError(
            f"traj must be a PointToPoint or a CartesianPath (spotkin.trajectory), got {type(traj).__name__}"
        )
    times = _times(t, traj.duration)
    fig = _check_fig(fig)
    if isinstance(traj, _trajectories.CartesianPath):
        if limits is not None or names is not None:
            raise ValueError("limits and names apply to joint trajectories (PointToPoint) only")
        if fig is None:
            fig = plt.figure(figsize=(8, 7))
        _trajectory_cartesian(fig, traj, times)
        return fig
    n = traj.q0.shape[0]
    if names is None:
        names = tuple(f"q{k + 1}" for k in range(n))
    else:
        if isinstance(names, str) or not all(isinstance(name, str) for name in names):
            raise TypeError("names must be a sequence of str, one per axis")
        names = tuple(names)
        if len(names) != n:
            raise ValueError(f"names must name the {n} axes, got {len(names)} names")
    table = None
    if limits is not None:
        table = as_real(limits, "limits", np.float64)
        if table.shape != (n, 2):
            raise ValueError(f"limits must have shape ({n}, 2) as (lower, upper) rows, got {table.shape}")
        if np.isnan(table).any():
            raise ValueError("limits must not hold NaN")
        _near(table[np.isfinite(table)], "limits", "a bound (use ±inf for none)")
    if fig is None:
        fig = plt.figure(figsize=(8, 7))
    q, qd, qdd = traj.sample(times)
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        (q, "q (rad)", None),
        (qd, "qd (rad/s)", ("vmax", traj.vmax, "rad/s")),
        (qdd, "qdd (rad/s²)", ("amax", traj.amax, "rad/s²")),
    )
    for ax, (values, ylabel, bound) in zip(axes, panels):
        for k in range(n):
            ax.plot(
                times,
                values[:, k],
                linewidth=1.6,
                label=names[k],
                gid=f"{ylabel.split()[0]}:{k}",
                **_style(k),
            )
        if bound is not None:
            _bound_lines(ax, bound[1], bound[0], bound[2])
        ax.set_ylabel(ylabel)
        ax.grid(True, linewidth=0.3)
    if table is not None:
        _joint_limit_lines(axes[0], q, table, names)
    for ax in axes:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(f"{traj.profile} point-to-point motion, duration {traj.duration:.3f} s", fontsize=10)
    fig.subplots_adjust(right=0.8)
    return fig


def _trajectory_cartesian(fig, path: _trajectories.CartesianPath, times: np.ndarray) -> None:
    poses, twist = path.sample(times, twist=True)
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        (poses[:, :3, 3], ("x", "y", "z"), "position (m)", None),
        (twist[:, :3], ("vx", "vy", "vz"), "linear velocity (m/s)", "|v|"),
        (twist[:, 3:], ("wx", "wy", "wz"), "angular velocity (rad/s)", "|w|"),
    )
    for ax, (values, labels, ylabel, norm) in zip(axes, panels):
        for k in range(3):
            ax.plot(times, values[:, k], linewidth=1.6, label=labels[k], gid=f"{labels[k]}", **_style(k))
        if norm is not None:
            ax.plot(times, np.linalg.norm(values, axis=1), color="black", linewidth=1.2, label=norm, gid=norm)
        ax.set_ylabel(ylabel)
        ax.grid(True, linewidth=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    for t_k in path.times:
        for ax in axes:
            ax.axvline(t_k, color="#969696", linewidth=0.6, linestyle=":")
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(
        f"Cartesian path through {len(path.times)} waypoints (dotted: their times), "
        f"duration {path.duration:.3f} s",
        fontsize=10,
    )
    fig.subplots_adjust(right=0.8)
