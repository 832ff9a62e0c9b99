"""Animations of a simulated walk (:func:`walk_animation`): the robot as the simulator recorded it, tick by
tick, the feet in contact marked, the camera following the body."""

from __future__ import annotations

import math
import sys

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d import art3d
from numpy.typing import ArrayLike

from .. import Robot
from ._animation import _Animation
from ._artists import _VIEWS, _RobotArtists
from ._common import (
    _BODY_EDGE,
    _OTHER,
    _SUPPORT_EDGE,
    _SUPPORT_FACE,
    _check_fig,
    _check_robot,
    _check_title,
    _label_3d,
    _near,
    _poses,
    _positive,
    _sparse_ticks,
    _vector,
    as_index,
)
from ._robot import _check_view
from ._solvers import _default_q
from ._stance import _convex_hull, _frame, _frame_points, _robot_name

_GROUND = "#969696"  # the ground grid and line
_MARGIN = 0.08  # of the robot's size: the room around it
_FOOTHOLD = {"linestyle": "none", "marker": "s", "markersize": 3.5, "color": _OTHER, "alpha": 0.8}
_PATH = {"color": _BODY_EDGE, "linewidth": 1.0, "linestyle": ":"}
_LEGEND_WIDTH = 1.85  # in: the legend's width at 7 pt
_GIF_COLORS = 32  # a walk's GIF: its line art on 32 colours, a sixth smaller than on 128


def _check_result(result, n_legs: int) -> dict:
    """The recording of a :class:`spotkin.sim.SimResult` as finite arrays, or TypeError / ValueError naming
    ``result``. The class is looked up among the loaded modules: without spotkin.sim loaded (it needs
    MuJoCo) there can be no SimResult, and the pictures never import the simulator."""
    sim = sys.modules.get("spotkin.sim")
    if sim is None or not isinstance(result, sim.SimResult):
        raise TypeError(
            f"result must be a spotkin.sim.SimResult (spotkin.sim.run's), got {type(result).__name__}"
        )
    if result.t is None:
        raise ValueError("result holds no record (spotkin.sim.run(..., record=False)): nothing to draw")
    t = np.asarray(result.t, dtype=np.float64)
    ticks = len(t)
    wanted = {"position": 3, "quaternion": 4, "q": 3 * n_legs, "contact": n_legs}
    record = {"t": t}
    for name, width in wanted.items():
        value = np.asarray(getattr(result, name))
        if value.shape != (ticks, width):
            raise ValueError(
                f"result.{name} must have shape ({ticks}, {width}) for this robot's {n_legs} legs, got "
                f"{value.shape} (the walk of another robot?)"
            )
        record[name] = value.astype(bool if name == "contact" else np.float64)
    for name in ("t", "position", "quaternion", "q"):
        if not np.isfinite(record[name]).all():
            raise ValueError(f"result.{name} must be finite to be drawn")
    if ticks < 1 or (np.diff(t) <= 0).any():
        raise ValueError("result.t must hold at least one tick, its times increasing")
    return record


def _frame_ticks(t: np.ndarray, fps: float, max_frames: int) -> tuple[np.ndarray, float]:
    """(the ticks drawn, the interval between frames in ms): a frame every 1 / fps s of the walk, or
    ``max_frames`` (at most one per tick) spread evenly over it when that would be more; played in real
    time either way."""
    span = float(t[-1] - t[0])
    wanted = span * fps  # frames after the first
    if wanted + 1.0 <= min(max_frames, len(t)):
        count = math.floor(wanted + 1e-9) + 1
        times = t[0] + np.arange(count) / fps
        interval = 1e3 / fps
    else:
        count = min(max_frames, len(t))
        times = np.linspace(t[0], t[-1], count)
        interval = 1e3 * span / (count - 1) if count > 1 else 1e3 / fps
    if not (math.isfinite(interval) and interval > 0):
        raise ValueError(f"fps must give a finite time between frames, got fps = {fps!r}")
    after = np.clip(np.searchsorted(t, times), 1, len(t) - 1) if len(t) > 1 else np.zeros(count, int)
    before = np.maximum(after - 1, 0)
    nearest = np.where(np.abs(t[before] - times) <= np.abs(t[after] - times), before, after)
    return nearest.astype(np.int64), interval


def _spacing(span: float) -> float:
    """A round grid spacing (1, 2 or 5 times a power of ten) giving about six lines over ``span``."""
    raw = max(span, 1e-6) / 6.0
    power = 10.0 ** math.floor(math.log10(raw))
    return next(step * power for step in (1.0, 2.0, 5.0, 10.0) if step * power >= raw)


def _support(feet: np.ndarray, down: np.ndarray) -> np.ndarray:
    """The support polygon of the feet in contact (their convex hull on the lowest one's plane); the first
    foot when none is (the polygon is then hidden)."""
    touching = feet[down] if down.any() else feet[:1]
    hull = touching[_convex_hull(touching[:, :2])].copy()
    hull[:, 2] = touching[:, 2].min()
    return hull


def walk_animation(
    robot: Robot,
    result,
    *,
    q_arm: ArrayLike | None = None,
    fps: float = 20.0,
    max_frames: int = 300,
    view: str = "3d",
    follow: bool = True,
    fig=None,
    title: str | None = None,
):
    """An animation of a simulated walk: ``robot`` as :func:`spotkin.sim.run` recorded it in ``result`` (a
    :class:`spotkin.sim.SimResult`), the body at its recorded position and orientation and the legs at
    their recorded joint angles, each frame drawn as :func:`robot` draws one configuration (the legs from
    joint frame to joint frame by the robot's kinematics: the feet are ``robot.body_fk``'s).

    The feet the simulator found in contact are filled (id ``"contact"``), the others hollow (``"feet"``
    holds every foot); the support polygon is that of the feet in contact; the footholds so far (each
    foot where it touched down, ``"footholds"``) and the body origin's path so far (``"body-path"``) stay
    drawn. The ground is level, at the lowest foot in contact (on sloped or rough terrain, a reference).

    ``q_arm``: the arm's joints (dof,), for a robot with an arm (the simulator holds it still); default
    zero angles clipped into the limits, as :func:`spotkin.sim.run` holds it. ``fps``: frames per second
    of the walk (> 0), each frame the recorded tick nearest its time; at most ``max_frames`` frames (an
    integer >= 1), a longer walk sampled more sparsely. The animation plays in real time either way;
    ``anim.ticks`` holds each frame's tick (its row of ``result``). ``view``: ``"3d"`` (default),
    ``"side"``, ``"front"`` or ``"top"``, as :func:`robot` draws them. ``follow``: the camera follows the
    body (default), the robot kept at one size: in 3D without the box (its panes and ticks would move
    every frame), the ground a grid of lines a round distance apart, named in the legend (id
    ``"ground"``); False: the camera frames the whole walk, the 3D box's floor the ground. The side and
    front views draw the ground as a line. ``fig``: a Figure to draw in (its contents are replaced),
    default a new one of 8 x 5 in; the legend is beside the drawing on the right. The title is ``title``
    (default the robot's name as :func:`robot` gives it, "simulated walk") and the time.

    Returns a :class:`matplotlib.animation.FuncAnimation`, as :func:`animate` does (its Figure is
    ``anim.figure``): ``anim.save("walk.gif")`` writes a GIF with Pillow, on a palette of 32 colours. At
    20 fps a 10 s walk is 200 frames, about 2 MB at 800 x 500 pixels with the camera following the body,
    0.4 MB with it fixed.

    Raises ``TypeError`` for a robot that is not an :class:`spotkin.Robot`, a ``result`` that is not a
    SimResult, or an argument of the wrong type (``follow`` not a bool, ``max_frames`` not an integer);
    ``ValueError`` for a result without a record (``record=False``) or of another robot (its joints or
    legs do not match), a record that is not finite, ``fps`` not finite and > 0, ``max_frames`` < 1, an
    unknown ``view``, or ``q_arm`` for a robot without an arm.
    """
    robot = _check_robot(robot)
    record = _check_result(result, robot.n_legs)
    arm = robot.arm
    if q_arm is not None and arm is None:
        raise ValueError("q_arm was given but this robot has no arm")
    if arm is not None:
        q_arm = _default_q(arm) if q_arm is None else _vector(q_arm, "q_arm", arm.dof)
    fps = _positive(fps, "fps")
    max_frames = as_index(max_frames, "max_frames")
    if max_frames < 1:
        raise ValueError(f"max_frames must be at least 1, got {max_frames}")
    view = _check_view(view)
    if not isinstance(follow, (bool, np.bool_)):
        raise TypeError(f"follow must be True or False, got {type(follow).__name__}")
    title = _check_title(title)
    fig = _check_fig(fig)
    return _WalkAnimation(robot, record, q_arm, fps, max_frames, view, bool(follow), fig, title).animation


class _WalkAnimation:
    """The drawing of a walk: the frames, the artists, the camera, and the function that moves them."""

    def __init__(self, robot, record, q_arm, fps, max_frames, view, follow, fig, title):
        self.projection, self.follow = _VIEWS[view], follow
        self.ticks, interval = _frame_ticks(record["t"], fps, max_frames)
        self.t, self.contact, self.origin = record["t"], record["contact"], record["position"]
        self._record(robot, record, q_arm)
        if fig is None:
            fig = plt.figure(figsize=(8, 5))
        flat = self.projection is not None
        room = _LEGEND_WIDTH / fig.get_size_inches()[0]  # the legend's, on the right
        box = (0.07, 0.1, max(0.4, 0.91 - room), 0.8) if flat else (0.0, 0.0, max(0.5, 0.98 - room), 0.92)
        self.ax = ax = fig.add_axes(box, projection=None if flat else "3d")
        self.artists = artists = _RobotArtists(ax, robot, self.frames[0], self.axes_length, view)
        artists.feet.set_markerfacecolor("white")  # in the air, unless drawn over by a foot in contact
        nothing = np.zeros((0, 3))
        self.touching = artists._line(
            nothing, linestyle="none", marker="o", markersize=7, color="black", gid="contact", zorder=6
        )
        self.placed = artists._line(nothing, gid="footholds", zorder=1.5, **_FOOTHOLD)
        self.path = artists._line(nothing, gid="body-path", zorder=4, **_PATH)
        extra = [
            Line2D([], [], label="body origin's path", **_PATH),
            Line2D([], [], label="footholds (touch-downs)", **_FOOTHOLD),
            *self._ground(view),
        ]
        artists.legend(extra, fontsize=7, outside=True, replace=self._replace())
        self.name = title if title is not None else f"{_robot_name(robot)}, simulated walk"
        self.title = ax.set_title("", fontsize=9)
        self.draw(0)
        self.animation = _Animation(fig, self.draw, frames=len(self.ticks), interval=interval)
        self.animation.ticks = self.ticks
        self.animation.gif_colors = _GIF_COLORS

    def _record(self, robot, record, q_arm) -> None:
        """The frames (the robot at each frame's tick), the footholds (each foot where it touched down:
        ``footholds`` (m, 3) at ``touch_ticks``), the ticks of the body's path drawn, the ground's height
        and the camera."""
        poses = np.concatenate(
            [record["position"], record["quaternion"]], axis=1
        )  # [x, y, z, qx, qy, qz, qw]
        T = _poses(poses[self.ticks], "XYZ")
        self.frames = [_frame(robot, T[k], record["q"][tick], q_arm) for k, tick in enumerate(self.ticks)]
        touched = self.contact & ~np.vstack([np.zeros_like(self.contact[:1]), self.contact[:-1]])
        at, leg = np.nonzero(touched)  # each touch-down: its tick and leg
        self.footholds, self.touch_ticks = np.zeros((0, 3)), at
        if len(at):
            feet = np.asarray(robot.body_fk(poses[at], record["q"][at]), dtype=np.float64)  # (m, n, 3)
            self.footholds = feet[np.arange(len(at)), leg]
        self.trail = np.arange(0, len(self.t), max(1, len(self.t) // 5000))  # the path's ticks drawn
        self.axes_length = 0.15 * float(np.ptp(_frame_points(self.frames[0]), axis=0).max())
        drawn = [  # each frame's points, with the body axes' ends
            np.concatenate([_frame_points(frame), frame.T[:3, 3] + self.axes_length * frame.T[:3, :3].T])
            for frame in self.frames
        ]
        _near(np.concatenate([*drawn, self.footholds, self.origin]), "result", "the robot")
        down = [frame.feet[self.contact[tick]] for frame, tick in zip(self.frames, self.ticks)]
        lowest = np.concatenate([self.footholds, *down])
        if not len(lowest):
            lowest = np.concatenate([frame.feet for frame in self.frames])
        self.ground = float(lowest[:, 2].min())  # the lowest foot down (in a frame or at a touch-down)
        self._limits(drawn)

    def _ground(self, view: str) -> list:
        """Label the axes and draw the ground (a line in the side and front views; with a camera that
        follows the body in 3D, a grid of lines instead of the box); its legend entries."""
        ax, self.grid = self.ax, None
        entries = []
        if self.projection is not None:
            names, (i, j) = "xyz", self.projection[:2]
            ax.set_xlabel(f"{names[i]} (m)")
            ax.set_ylabel(f"{names[j]} (m)")
            ax.set_aspect("equal", adjustable="box")
            ax.grid(True, linewidth=0.3)
            if view != "top":
                ax.axhline(self.ground, color=_GROUND, linewidth=1.0, zorder=0, gid="ground")
                entries.append(
                    Line2D([], [], color=_GROUND, linewidth=1.0, label="ground (the lowest foot down)")
                )
            self._camera(0)
            return entries
        if self.follow:  # the box's panes and ticks would change every frame: a grid on the ground instead
            ax.set_axis_off()
            self.step = _spacing(float((self.around[1] - self.around[0]).max()))
            self.grid = art3d.Line3DCollection(
                [np.zeros((2, 3))], colors=_GROUND, linewidths=0.6, gid="ground"
            )
            self.grid.set_zorder(0.5)
            ax.add_collection3d(self.grid)
            label = f"ground, lines {self.step:g} m apart"
            entries.append(Line2D([], [], color=_GROUND, linewidth=0.6, label=label))
        else:
            _label_3d(ax)
        self._camera(0)
        low, high = self._box(0)
        ax.set_box_aspect(tuple(high - low), zoom=1.2 if self.follow else 1.0)
        if not self.follow:
            _sparse_ticks(ax, 7)
        return entries

    def _limits(self, drawn: list) -> None:
        """The camera: ``fixed`` (low, high) (3,) around every frame's robot, from the ground up (the 3D
        box's floor is the ground; a 2D view shows it as a line); ``around`` (low, high) (2,), the room
        about the body origin (x, y) that every frame's robot fits in, for the camera that follows it."""
        offsets = np.concatenate(
            [points[:, :2] - frame.T[:2, 3] for points, frame in zip(drawn, self.frames)]
        )
        margin = _MARGIN * float(np.ptp(offsets, axis=0).max()) + 1e-3
        self.around = (offsets.min(axis=0) - margin, offsets.max(axis=0) + margin)
        points = np.concatenate(drawn)
        low, high = points.min(axis=0) - margin, points.max(axis=0) + margin
        bottom = min(self.ground, float(points[:, 2].min()))
        low[2] = bottom - margin if self.projection is not None else bottom
        self.fixed = (low, high)

    def _box(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) (3,) world limits of the camera at frame k."""
        low, high = (limit.copy() for limit in self.fixed)
        if self.follow:
            centre = self.frames[k].T[:2, 3]
            low[:2], high[:2] = centre + self.around[0], centre + self.around[1]
        return low, high

    def _camera(self, k: int) -> None:
        low, high = self._box(k)
        if self.projection is not None:
            i, j = self.projection[:2]
            self.ax.set_xlim(low[i], high[i])
            self.ax.set_ylim(low[j], high[j])
            return
        self.ax.set_xlim(low[0], high[0])
        self.ax.set_ylim(low[1], high[1])
        self.ax.set_zlim(low[2], high[2])
        if self.grid is not None:  # lines fixed in the world, clipped to the box: they pass as it moves
            lines = []
            for axis in (0, 1):
                first, last = math.ceil(low[axis] / self.step), math.floor(high[axis] / self.step)
                for value in np.arange(first, last + 1) * self.step:
                    ends = np.full((2, 3), self.ground)
                    ends[:, axis] = value
                    ends[:, 1 - axis] = low[1 - axis], high[1 - axis]
                    lines.append(ends)
            self.grid.set_segments(lines)

    def _inside(self, points: np.ndarray, k: int) -> np.ndarray:
        """The points (m, 3) inside frame k's camera (3D artists are not clipped to their axes)."""
        low, high = self._box(k)
        keep = ((points[:, :2] >= low[:2]) & (points[:, :2] <= high[:2])).all(axis=1)
        return points[keep]

    def draw(self, k: int):
        frame, tick = self.frames[k], int(self.ticks[k])
        down = self.contact[tick]
        frame = frame._replace(support=_support(frame.feet, down))
        artists = self.artists
        artists.update(frame)
        artists.support.set_visible(bool(down.any()))
        artists._set(self.touching, frame.feet[down])
        artists._set(self.placed, self._inside(self.footholds[self.touch_ticks <= tick], k))
        trail = self.origin[np.append(self.trail[self.trail < tick], tick)]
        artists._set(self.path, self._inside(trail, k))
        if self.follow:
            self._camera(k)
        self.title.set_text(f"{self.name}: t = {self.t[tick]:.2f} s")
        return ()

    def _replace(self) -> dict:
        """The robot's legend entries that mean more here: the feet, the support polygon."""
        down = Line2D([], [], color="black", linestyle="none", marker="o", label="foot in contact")
        up = Line2D(
            [],
            [],
            color="black",
            linestyle="none",
            marker="o",
            markerfacecolor="white",
            label="foot in the air",
        )
        support = Patch(
            facecolor=_SUPPORT_FACE,
            edgecolor=_SUPPORT_EDGE,
            linestyle="--",
            label="support polygon, feet down",
        )
        return {"feet": [down, up], "support polygon": [support]}
