"""The artists of one robot (body, legs, feet, support polygon, arm, other links, body axes, marks), in a
3D Axes or projected on a side, front or top view, updated in place from frame to frame."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d import art3d

from .. import Robot
from ._common import (
    _ARM,
    _AXES,
    _BODY_EDGE,
    _BODY_FACE,
    _LEG,
    _LIMIT,
    _OTHER,
    _SUPPORT_EDGE,
    _SUPPORT_FACE,
)
from ._stance import _Frame

# views of a robot: None (3D), else (horizontal, vertical, depth axis, sign of the depth toward the viewer):
# the side view looks from the robot's right (x to the right, z up), the front view from ahead (y to the
# right), the top view from above (x to the right, y up)
_VIEWS = {"3d": None, "side": (0, 2, 1, -1.0), "front": (1, 2, 0, 1.0), "top": (0, 1, 2, 1.0)}


class _RobotArtists:
    """The artists of one robot in a 3D Axes, or projected on a 2D Axes for a side, front or top view
    (``view``: a key of :data:`_VIEWS`), updated in place (for animations)."""

    def __init__(self, ax, robot: Robot, frame: _Frame, axes_length: float, view: str = "3d"):
        self.ax, self.robot, self.axes_length = ax, robot, axes_length
        self.projection = _VIEWS[view]
        if self.projection is None:
            # a stick figure reads best with the sticks over the translucent faces (the default orders
            # artists by their mean depth, which hides a leg behind the support polygon)
            ax.computed_zorder = False
            polygons = art3d.Poly3DCollection
        else:
            polygons = PolyCollection
        self.body = polygons(
            [self._flat(frame.outline)], facecolor=_BODY_FACE, edgecolor=_BODY_EDGE, linewidths=1.5, alpha=0.6
        )
        self.body.set_gid("body")
        self.body.set_zorder(2)
        self.support = polygons(
            [self._flat(frame.support)],
            facecolor=_SUPPORT_FACE,
            edgecolor=_SUPPORT_EDGE,
            linewidths=1.0,
            linestyles="--",
            alpha=0.5,
        )
        self.support.set_gid("support")
        self.support.set_zorder(1)
        for collection in (self.body, self.support):
            if self.projection is None:
                ax.add_collection3d(collection)
            else:
                ax.add_collection(collection)
        self.tree = [
            self._line(segment, color=_OTHER, linewidth=1.0, linestyle=":", gid="tree", zorder=3)
            for segment in frame.tree
        ]
        self.legs = []
        far = self._far_legs(frame)
        for k, (name, points) in enumerate(zip(robot.leg_names, frame.legs)):
            line = self._line(
                points,
                color=_LEG,
                linewidth=2.5,
                marker="o",
                markersize=4.5,
                markerfacecolor="white",
                markeredgecolor=_LEG,
                gid=f"leg:{name}",
                zorder=3.5 if far[k] else 4,
                alpha=0.45 if far[k] else 1.0,
            )
            self.legs.append(line)
        self.feet = self._line(
            frame.feet, linestyle="none", marker="o", markersize=7, color="black", gid="feet", zorder=5
        )
        self.arm = None
        if frame.arm is not None:
            self.arm = self._line(
                frame.arm,
                color=_ARM,
                linewidth=3.0,
                marker="s",
                markersize=4.5,
                markerfacecolor="white",
                markeredgecolor=_ARM,
                gid="arm",
                zorder=4,
            )
            self.hand = self._line(
                frame.arm[-1:], linestyle="none", marker="D", markersize=6, color=_ARM, gid="hand", zorder=5
            )
        self.beyond = self._line(
            frame.beyond,
            linestyle="none",
            marker="X",
            markersize=10,
            color=_LIMIT,
            gid="beyond-limits",
            zorder=6,
        )
        self.singular = self._line(
            frame.singular,
            linestyle="none",
            marker="*",
            markersize=12,
            markerfacecolor="none",
            markeredgecolor="black",
            gid="singular",
            zorder=6,
        )
        self.axes = []
        for k, (label, colour, style) in enumerate(_AXES):
            segment = self._axis(frame.T, k)
            line = self._line(
                segment, color=colour, linestyle=style, linewidth=1.8, gid=f"body-axis:{label}", zorder=4
            )
            if self.projection is None:
                text = ax.text(*segment[1], label, color=colour, fontsize=9, fontweight="bold")
            else:
                text = ax.text(
                    *self._flat(segment[1:])[0], label, color=colour, fontsize=9, fontweight="bold"
                )
            self.axes.append((line, text))
        self._hide_end_on_axes(frame)

    def _flat(self, points: np.ndarray) -> np.ndarray:
        """Points (m, 3) as drawn: themselves in 3D, their (m, 2) projection on a 2D view."""
        if self.projection is None:
            return points
        return points[:, list(self.projection[:2])]

    def _line(self, points: np.ndarray, **style):
        if self.projection is None:
            return self.ax.plot(*points.T, **style)[0]
        return self.ax.plot(*self._flat(points).T, **style)[0]

    def _set(self, line, points: np.ndarray) -> None:
        if self.projection is None:
            line.set_data_3d(*points.T)
        else:
            line.set_data(*self._flat(points).T)

    def _count(self, line) -> int:
        return len(line.get_data_3d()[0] if self.projection is None else line.get_xdata())

    def _far_legs(self, frame: _Frame) -> np.ndarray:
        """(n,) bool: on a 2D view, the legs whose hips lie behind the body's middle (drawn lighter)."""
        if self.projection is None or not frame.legs:
            return np.zeros(len(frame.legs), dtype=bool)
        _, _, depth, sign = self.projection
        hips = np.array([points[0, depth] for points in frame.legs]) * sign
        return hips < hips.mean() - 1e-9

    def _hide_end_on_axes(self, frame: _Frame) -> None:
        """On a 2D view, the label of a body axis that points at the viewer (or away) is hidden."""
        if self.projection is None:
            return
        for k, (_, text) in enumerate(self.axes):
            drawn = np.ptp(self._flat(self._axis(frame.T, k)), axis=0)
            text.set_visible(bool(np.hypot(*drawn) > 0.25 * self.axes_length))

    def _axis(self, T: np.ndarray, k: int) -> np.ndarray:
        origin = T[:3, 3]
        return np.array([origin, origin + self.axes_length * T[:3, k]])

    def update(self, frame: _Frame) -> None:
        self.body.set_verts([self._flat(frame.outline)])
        self.support.set_verts([self._flat(frame.support)])
        for line, segment in zip(self.tree, frame.tree):
            self._set(line, segment)
        for line, points in zip(self.legs, frame.legs):
            self._set(line, points)
        self._set(self.feet, frame.feet)
        if self.arm is not None and frame.arm is not None:
            self._set(self.arm, frame.arm)
            self._set(self.hand, frame.arm[-1:])
        self._set(self.beyond, frame.beyond)
        self._set(self.singular, frame.singular)
        for k, (line, text) in enumerate(self.axes):
            segment = self._axis(frame.T, k)
            self._set(line, segment)
            if self.projection is None:
                text.set_position_3d(segment[1])
            else:
                text.set_position(self._flat(segment[1:])[0])
        self._hide_end_on_axes(frame)

    def handles(self, extra=()) -> list:
        """The legend's entries."""
        handles = [
            Patch(facecolor=_BODY_FACE, edgecolor=_BODY_EDGE, label="body (through the hips)"),
            Line2D(
                [],
                [],
                color=_LEG,
                linewidth=2.5,
                marker="o",
                markerfacecolor="white",
                label="legs, joint to joint",
            ),
        ]
        if self.projection is not None and any(line.get_alpha() < 1 for line in self.legs):
            handles.append(
                Line2D(
                    [],
                    [],
                    color=_LEG,
                    linewidth=2.5,
                    marker="o",
                    markerfacecolor="white",
                    alpha=0.45,
                    label="legs on the far side",
                )
            )
        handles += [
            Line2D([], [], color="black", linestyle="none", marker="o", label="feet"),
            Patch(facecolor=_SUPPORT_FACE, edgecolor=_SUPPORT_EDGE, linestyle="--", label="support polygon"),
        ]
        if self.arm is not None:
            handles.append(
                Line2D(
                    [],
                    [],
                    color=_ARM,
                    linewidth=3,
                    marker="s",
                    markerfacecolor="white",
                    label="arm, joint to joint",
                )
            )
        if self.tree:
            handles.append(Line2D([], [], color=_OTHER, linestyle=":", label="other links (URDF)"))
        handles.append(Line2D([], [], color="black", linestyle="-", label="body axes x, y (--), z (:)"))
        if self._count(self.beyond):
            handles.append(
                Line2D(
                    [],
                    [],
                    color=_LIMIT,
                    linestyle="none",
                    marker="X",
                    markersize=9,
                    label="joint beyond its limits",
                )
            )
        if self._count(self.singular):
            handles.append(
                Line2D(
                    [],
                    [],
                    color="black",
                    linestyle="none",
                    marker="*",
                    markerfacecolor="none",
                    markersize=11,
                    label="leg at a singular configuration",
                )
            )
        handles.extend(extra)
        return handles

    def legend(self, extra=(), fontsize: float = 7, outside: bool = False, replace=None) -> None:
        """The legend: beside the axes, right of their box (``outside``: the figure leaves room for it), or
        in the axes' upper left corner (a 2D view: where it hides the least of the drawing). ``replace``:
        label -> the entries that stand for that one (a picture where the feet mean more)."""
        handles = self.handles(extra)
        if replace:
            handles = [entry for handle in handles for entry in replace.get(handle.get_label(), [handle])]
        if outside:  # in figure coordinates, by the box as drawn (a 3D Axes' labels spill out of it)
            self.ax.apply_aspect()
            box = self.ax.get_position()
            right = self.ax.get_position(original=True).x1 if self.projection is None else box.x1
            self.ax.legend(
                handles=handles,
                loc="upper left",
                bbox_to_anchor=(right + 0.01, box.y1),
                bbox_transform=self.ax.figure.transFigure,
                fontsize=fontsize,
                frameon=False,
            )
        else:
            where = "upper left" if self.projection is None else "best"
            self.ax.legend(handles=handles, loc=where, fontsize=fontsize, framealpha=0.85)
