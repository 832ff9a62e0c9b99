"""Animations of a robot along a body path (:func:`animate`), saved as GIFs on one palette."""

from __future__ import annotations

import io

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import AbstractMovieWriter, FuncAnimation
from matplotlib.lines import Line2D
from numpy.typing import ArrayLike
from PIL import Image  # a dependency of matplotlib

from .. import Robot
from ._artists import _RobotArtists
from ._common import (
    _ARM,
    _BODY_EDGE,
    _batch,
    _check_fig,
    _check_robot,
    _check_seq,
    _equal_3d,
    _label_3d,
    _near,
    _poses,
    _positive,
    _sparse_ticks,
)
from ._solvers import _default_q
from ._stance import _frame, _frame_points, _robot_name


class _GifWriter(AbstractMovieWriter):
    """Writes a GIF with Pillow, every frame on one palette of ``colors`` colours (128) without dithering:
    the static parts (axes, legend) stay identical between frames, so the file holds little more than what
    moves (a few times smaller than a per-frame dithered palette; line art needs no more colours)."""

    def __init__(self, fps: float = 10.0, colors: int = 128):
        super().__init__(fps=fps)
        self._frames: list = []
        self.colors = colors

    def setup(self, fig, outfile, dpi=None):
        super().setup(fig, outfile, dpi=dpi)
        self._frames = []

    def grab_frame(self, **savefig_kwargs):
        buffer = io.BytesIO()
        self.fig.savefig(buffer, **{**savefig_kwargs, "format": "rgba", "dpi": self.dpi})
        self._frames.append(Image.frombuffer("RGBA", self.frame_size, buffer.getbuffer()).convert("RGB"))

    def finish(self):
        frames = self._frames
        picks = sorted({0, len(frames) // 2, len(frames) - 1})
        sample = Image.new("RGB", (frames[0].width, frames[0].height * len(picks)))
        for row, k in enumerate(picks):
            sample.paste(frames[k], (0, row * frames[0].height))
        palette = sample.quantize(colors=self.colors, method=0, dither=0)  # median cut, no dithering
        images = [frame.quantize(palette=palette, dither=0) for frame in frames]
        images[0].save(
            self.outfile, save_all=True, append_images=images[1:], duration=round(1000 / self.fps), loop=0
        )


class _Animation(FuncAnimation):
    """A FuncAnimation whose ``save`` writes a ``.gif`` with :class:`_GifWriter` (on ``gif_colors``
    colours) unless given a writer, and draws each frame once while saving (the writer's grab draws it;
    the idle redraw is skipped)."""

    _saving = False
    gif_colors = 128

    def __init__(self, fig, func, *, frames: int, interval: float):
        self.figure = fig
        self.frame_interval = interval  # ms
        super().__init__(fig, func, frames=frames, interval=interval, blit=False, repeat=True)

    def save(self, filename, writer=None, *args, **kwargs):
        if writer is None and str(filename).lower().endswith(".gif"):
            fps = kwargs.pop("fps", None) or 1000.0 / self.frame_interval
            writer = _GifWriter(fps=fps, colors=self.gif_colors)
        self._saving = True
        try:
            return super().save(filename, writer, *args, **kwargs)
        finally:
            self._saving = False

    def _post_draw(self, framedata, blit):
        if not self._saving:
            super()._post_draw(framedata, blit)


def animate(
    robot: Robot,
    body_poses: ArrayLike,
    q: ArrayLike,
    q_arm: ArrayLike | None = None,
    seq: str = "XYZ",
    interval: float = 100.0,
    fig=None,
):
    """An animation of ``robot`` along a body path: one frame per body pose.

    ``body_poses`` (K, 6) [x, y, z, a, b, c] (Euler angles in ``seq``), (K, 7) or (K, 4, 4); ``q``
    (K, 3 n) leg joints (or (3 n,) for every frame), ``q_arm`` (K, 6) or (6,) for a robot with an arm
    (default: zero angles clipped into the limits). Each frame is drawn as :func:`robot` draws one
    configuration; the body origin's path (and the tool's, with an arm) is traced dotted and the body's
    outline at frame 1 stays drawn dashed (id ``"body-start"``), to show the motion. ``interval``
    is the time between frames in milliseconds (> 0); ``fig``: a Figure to draw in (its contents are
    replaced), default a new one of 8 x 5 in (800 x 500 pixels at 100 dpi). The drawing fills the
    figure's left three quarters, framed on every frame's robot at one scale on every axis, the legend
    beside it on the right; the title names the robot as :func:`robot` does and counts the frames.

    Returns a :class:`matplotlib.animation.FuncAnimation` (shown at frame 0 until it runs; its Figure
    is ``anim.figure``):
    ``anim.save("path.gif")`` writes a GIF with Pillow (matplotlib's dependency), ``anim.to_jshtml()``
    an HTML player. Keep a reference to it while it plays.

    Raises as :func:`robot`; every frame must be finite, and ``q`` and ``q_arm`` must have one row
    per pose (or one row for all).
    """
    robot = _check_robot(robot)
    seq = _check_seq(seq)
    interval = _positive(interval, "interval")
    T = _poses(body_poses, seq)
    count = len(T)
    q = _batch(q, "q", 3 * robot.n_legs, count)
    arm = robot.arm
    if q_arm is not None and arm is None:
        raise ValueError("q_arm was given but this robot has no arm")
    if arm is not None:
        q_arm = _batch(_default_q(arm) if q_arm is None else q_arm, "q_arm", arm.dof, count)
    fig = _check_fig(fig)
    frames = [_frame(robot, T[k], q[k], None if q_arm is None else q_arm[k]) for k in range(count)]
    points = np.concatenate([_frame_points(frame) for frame in frames])
    _near(points, "body_poses", "the robot")
    if fig is None:
        fig = plt.figure(figsize=(8, 5))
    ax = fig.add_axes((0.0, 0.0, 0.72, 0.92), projection="3d")
    span = float(np.ptp(points, axis=0).max())
    artists = _RobotArtists(ax, robot, frames[0], 0.15 * span)
    start = np.vstack([frames[0].outline, frames[0].outline[:1]])
    ax.plot(*start.T, color=_BODY_EDGE, linewidth=0.8, linestyle="--", alpha=0.6, gid="body-start", zorder=1)
    ax.plot(*T[:, :3, 3].T, color="black", linewidth=1.2, linestyle=":", gid="body-path", zorder=4)
    extra = [
        Line2D([], [], color=_BODY_EDGE, linewidth=0.8, linestyle="--", alpha=0.6, label="body at frame 1"),
        Line2D([], [], color="black", linewidth=1.2, linestyle=":", label="body origin's path"),
    ]
    if q_arm is not None:
        tool = np.array([frame.arm[-1] for frame in frames])
        ax.plot(*tool.T, color=_ARM, linewidth=1.0, linestyle=":", gid="tool-path")
        extra.append(Line2D([], [], color=_ARM, linestyle=":", label="tool's path"))
    axis_ends = [artists._axis(frame.T, k) for frame in frames for k in range(3)]
    _equal_3d(ax, np.concatenate([points, *axis_ends]))
    _label_3d(ax)
    _sparse_ticks(ax, 7)
    artists.legend(extra, fontsize=7, outside=True)
    name = _robot_name(robot)
    title = ax.set_title(f"{name}: frame 1 of {count}", fontsize=9)

    def draw(k):
        artists.update(frames[k])
        title.set_text(f"{name}: frame {k + 1} of {count}")
        return ()

    return _Animation(fig, draw, frames=count, interval=interval)
