"""The hand positions a legged robot reaches with its feet fixed (:func:`reachability`): a
:class:`spotkin.Reachability` as a 3D scatter coloured by height, optionally with the robot standing
at the reach's nominal pose."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import ArrayLike

from .. import Reachability, Robot, Status
from ._artists import _RobotArtists
from ._common import (
    _check_ax,
    _check_robot,
    _check_title,
    _equal_3d,
    _label_3d,
    _near,
    _reach_numbers,
    _sparse_ticks,
    as_real,
    as_scalar,
    stance_frames,
)
from ._solvers import _default_q
from ._stance import _frame, _frame_points, _robot_name

_CMAP = "viridis"  # its luminance grows with the value: the heights read in greyscale too


def _check_result(value) -> tuple[np.ndarray, np.ndarray]:
    """(points (N, 3), reachable (N,)) of a Reachability, flattened, or TypeError/ValueError naming it."""
    if not isinstance(value, Reachability):
        raise TypeError(
            f"result must be an sk.Reachability (from robot.reachability(...)), got {type(value).__name__}"
        )
    points = as_real(value.points, "result.points", np.float64)
    reachable = np.asarray(value.reachable)
    if reachable.dtype != np.bool_:
        raise TypeError(f"result.reachable must be a bool array, got dtype {reachable.dtype}")
    if points.ndim < 1 or points.shape[-1] != 3 or points.shape[:-1] != reachable.shape:
        raise ValueError(
            "result must hold points (..., 3) and reachable (...) of the same leading shape, got "
            f"{points.shape} and {reachable.shape}"
        )
    points, reachable = points.reshape(-1, 3), reachable.reshape(-1)
    if not np.isfinite(points[reachable]).all():
        raise ValueError("result marks points that are not finite as reachable")
    _near(points[reachable], "result", "reachable points")
    for name in ("volume", "spacing"):
        as_scalar(getattr(value, name), f"result.{name}")  # a number (NaN for points without a grid)
    return points, reachable


def _standing(robot: Robot, feet: ArrayLike | None, q_width: int):
    """The robot at the reach's nominal pose over ``feet`` (default: the nominal stance's): the frame to
    draw, its legs from ``body_ik`` and its arm at zero (clipped into the limits)."""
    arm = robot.arm
    if arm is None or 3 * robot.n_legs + arm.dof != q_width:
        have = "no arm" if arm is None else f"{3 * robot.n_legs + arm.dof} joints"
        raise ValueError(
            f"robot does not match result: its q has {q_width} columns, this robot has {have} "
            "(draw a result with the robot that computed it)"
        )
    numbers = _reach_numbers(robot)
    if feet is None:
        feet = numbers.feet
    else:
        feet = as_real(feet, "feet", np.float64)
        if feet.shape != (robot.n_legs, 3) or not np.isfinite(feet).all():
            raise ValueError(f"feet must be finite with shape ({robot.n_legs}, 3), got {feet.shape}")
        _near(feet, "feet", "the robot")
    T = stance_frames(feet[None], numbers.feet)[0]
    T[2, 3] += numbers.h0  # world <- stance, then the nominal pose [0, 0, h0, 0, 0, 0] in it
    legs = robot.body_ik(T, feet)
    if (np.asarray(legs.status) != Status.OK).any():
        raise ValueError(
            "feet are out of the legs' reach (or limits) from the nominal pose: the robot cannot stand there"
        )
    return _frame(robot, T, np.asarray(legs.q, np.float64), _default_q(arm))


def reachability(
    result: Reachability,
    robot: Robot | None = None,
    *,
    feet: ArrayLike | None = None,
    ax=None,
    title: str | None = None,
) -> Figure:
    """The hand positions a legged robot reaches with its feet fixed, in 3D.

    The reachable points of ``result`` (:meth:`spotkin.Robot.reachability`) are drawn as a scatter
    coloured by their height (a colour bar beside the drawing), one scale on every axis. With ``robot``,
    the robot that computed the result is drawn standing at the reach's nominal pose (the body at its
    nominal height over the nominal stance's feet, or over ``feet``), its arm at zero angles clipped into
    the limits, as :func:`robot` draws it. The title gives the reachable volume (m³) when the points are
    a grid of known spacing, and the count of reachable points.

    Parameters
    ----------
    result:
        An :class:`spotkin.Reachability`: a grid (``robot.reachability()``, ``spacing=...``) or points
        given with or without an approach direction.
    robot:
        The :class:`spotkin.Robot` that computed ``result``, to draw; default: the points alone.
    feet:
        (n_legs, 3) the feet the result was computed with (``reachability(..., feet=...)``), to stand the
        drawn robot on; default: the nominal stance's (the default of ``reachability``). Needs ``robot``.
    ax:
        A 3D Axes to draw in (``fig.add_subplot(projection="3d")``; the colour bar takes room beside
        it); default: a new figure of 9 x 6.5 in, the legend and the colour bar on the right.
    title:
        The title; default: the robot's name (when given), the volume and the count of reachable
        points.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn in. The scatter's id (``get_gid()``) is ``"reachable"``; the robot's artists
        carry the ids of :func:`robot`'s (``"feet"``, ``"arm"``, ``"leg:NAME"``, ...).

    Raises ``TypeError`` for a ``result`` that is not a Reachability (or whose ``reachable`` is not
    bool), a non-robot, a non-Axes ``ax`` or a non-str ``title``; ``ValueError`` for a result whose
    points and ``reachable`` disagree in shape or that marks a non-finite point (or one beyond 1e6 m) as
    reachable, a robot of another joint count than the result's, ``feet`` of a wrong shape, NaN or out
    of the legs' reach, ``feet`` without ``robot``, or a 2D ``ax``.
    """
    points, reachable = _check_result(result)
    if robot is not None:
        robot = _check_robot(robot)
    elif feet is not None:
        raise ValueError("feet stands the drawn robot on its feet: give the robot too")
    ax = _check_ax(ax, three_d=True)
    title = _check_title(title)
    frame = None
    if robot is not None:
        frame = _standing(robot, feet, int(np.shape(result.q)[-1]) if np.ndim(result.q) else -1)
    outside = ax is None
    if ax is None:
        fig = plt.figure(figsize=(9, 6.5))
        ax = fig.add_axes((0.0, 0.03, 0.66, 0.88), projection="3d")
    fig = ax.figure
    hits = points[reachable]
    count, total = len(hits), len(points)
    size = float(np.clip(2500.0 / max(count, 1) ** (2 / 3), 2.0, 40.0))  # points² per marker
    scatter = ax.scatter(
        *hits.T, c=hits[:, 2], cmap=_CMAP, s=size, alpha=0.5, linewidths=0, depthshade=False, gid="reachable"
    )
    scatter.set_zorder(1)
    shown = [hits]
    handles = []
    artists = None
    if frame is not None:
        drawn = _frame_points(frame)
        span = float(np.ptp(drawn, axis=0).max())
        artists = _RobotArtists(ax, robot, frame, 0.15 * span, "3d")
        shown.append(drawn)
    if count == 0 and frame is None:
        shown.append(points[np.isfinite(points).all(axis=1)])
    _equal_3d(ax, np.concatenate(shown))
    _label_3d(ax)
    _sparse_ticks(ax, 6)
    if count:
        if outside:
            bar_ax = fig.add_axes((0.72, 0.08, 0.018, 0.42))
            bar = fig.colorbar(scatter, cax=bar_ax)
        else:
            bar = fig.colorbar(scatter, ax=ax, shrink=0.6, pad=0.08)
        bar.set_label("hand height z (m)")
        bar.ax.set_gid("height")
    cmap = plt.get_cmap(_CMAP)
    handles.append(
        Line2D([], [], linestyle="none", marker="o", color=cmap(0.6), label="reachable hand positions")
    )
    if artists is not None:
        artists.legend(extra=handles, outside=outside)
    elif outside:
        ax.legend(
            handles=handles,
            loc="upper left",
            bbox_to_anchor=(0.67, 0.91),
            bbox_transform=fig.transFigure,
            fontsize=7,
            frameon=False,
        )
    else:
        ax.legend(handles=handles, loc="upper left", fontsize=7)
    if title is None:
        name = _robot_name(robot) if robot is not None else "Reachability"
        volume = float(result.volume)
        found = f"{count} of {total} points reachable"
        if math.isfinite(volume):
            found = (
                f"volume {volume:.3f} m³: {count} of {total} points of a {float(result.spacing):.3g} m grid"
            )
        title = f"{name}: hand positions reached, feet fixed\n{found}"
    ax.set_title(title, fontsize=10)
    return fig
