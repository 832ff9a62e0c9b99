"""Pictures of a robot at one configuration (:func:`robot`: in 3D, or its side, front or top view), and of
a description without legs (an arm, a gripper: the tree that ``spotkin plot`` draws)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import ArrayLike

from .. import Robot
from ._artists import _VIEWS, _RobotArtists
from ._common import (
    _ARM,
    _OTHER,
    _check_ax,
    _check_robot,
    _check_seq,
    _check_title,
    _equal_3d,
    _frame_axes,
    _label_3d,
    _limits_2d,
    _near,
    _single_pose,
    _sparse_ticks,
    _vector,
)
from ._solvers import _default_q
from ._stance import _frame, _frame_points, _nominal_stance, _robot_name

_VIEW_NAMES = {"side": "side view (x–z)", "front": "front view (y–z)", "top": "top view (x–y)"}


def _check_view(view) -> str:
    if not isinstance(view, str):
        raise TypeError(f"view must be a str, one of {tuple(_VIEWS)}, got {type(view).__name__}")
    if view not in _VIEWS:
        raise ValueError(f"view must be one of {tuple(_VIEWS)}, got {view!r}")
    return view


def _frame_2d(ax, points: np.ndarray, ground: float | None, pad: float = 0.06) -> None:
    """Limits of a 2D view around the drawn points (m, 2), one scale on both axes, and the ground line."""
    low, high = _limits_2d(points, pad)
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_aspect("equal", adjustable="box")
    if ground is not None:
        ax.axhline(ground, color="#525252", linewidth=1.0, zorder=0, gid="ground")
    ax.grid(True, linewidth=0.3)


def _description(ax, model, values: dict, title: str | None = None) -> None:
    """Draw a URDF tree that has no legs (an arm, a gripper, a head) into the 3D ``ax`` at the joint
    values ``values`` (actuated joint name -> value; mimic joints follow their leaders, joints not named
    are at 0): every link from its parent's frame to its own (grey), the chain from the root to each tip
    (the URDF chain loader's ``tip_candidates``) with its joints (orange squares, mimic joints hollow), the
    root's axes and each tip's frame. Used by ``spotkin plot`` for descriptions without legs."""
    from ..model.urdf_chain import tip_candidates

    placements = {link: model.placement(link, values) for link in model.links}
    points = np.array([T[:3, 3] for T in placements.values()])
    span = float(np.ptp(points, axis=0).max()) if len(points) > 1 else 0.1
    span = max(span, 0.05)
    for joint in model.joints:
        start, end = placements[joint.parent][:3, 3], placements[joint.child][:3, 3]
        if np.linalg.norm(end - start) > 1e-9:
            ax.plot(*np.array([start, end]).T, color=_OTHER, linewidth=1.2, gid="tree")
    tips = tip_candidates(model)
    for tip in tips:
        path = model.path(tip)
        line = np.array([placements[model.root][:3, 3]] + [placements[j.child][:3, 3] for j in path])
        ax.plot(*line.T, color=_ARM, linewidth=2.5, gid=f"chain:{tip}")
        for j in path:
            if j.type == "fixed":
                continue
            p = placements[j.child][:3, 3]
            face = "white" if j.mimic is not None else _ARM
            ax.plot(*p[:, None], linestyle="none", marker="s", markersize=6, color=_ARM, markerfacecolor=face)
        _frame_axes(ax, placements[tip], 0.12 * span, "-", f"tip:{tip}")
    for j in model.mimic_joints:
        if not any(j in model.path(tip) for tip in tips):
            p = placements[j.child][:3, 3]
            ax.plot(
                *p[:, None], linestyle="none", marker="s", markersize=5, color=_ARM, markerfacecolor="white"
            )
    _frame_axes(ax, np.eye(4), 0.2 * span, ":", "root")
    _equal_3d(ax, points)
    _sparse_ticks(ax)
    _label_3d(ax)
    handles = [
        Line2D([], [], color=_ARM, linewidth=2.5, marker="s", label="chain to a tip, its joints"),
        Line2D(
            [], [], color=_ARM, linestyle="none", marker="s", markerfacecolor="white", label="mimic joint"
        ),
        Line2D([], [], color=_OTHER, linewidth=1.2, label="other links"),
        Line2D([], [], color="black", linestyle=":", label=f"root frame ({model.root})"),
    ]
    ax.legend(handles=handles, loc="upper left", fontsize=7)
    if title is not None:
        ax.set_title(title, fontsize=10)


def robot(
    robot: Robot,
    body_pose: ArrayLike | None = None,
    q: ArrayLike | None = None,
    q_arm: ArrayLike | None = None,
    seq: str = "XYZ",
    ax=None,
    title: str | None = None,
    view: str = "3d",
) -> Figure:
    """A stick figure of ``robot`` at one configuration, in the world frame: in 3D, or seen from the side,
    the front or above.

    Drawn: the body (a polygon through the hip-roll joints), each leg from joint frame to joint
    frame (hip roll, hip pitch, knee, foot), the feet, the support polygon (the feet's convex
    hull, on the plane of the lowest foot), the body axes (x solid, y dashed, z dotted), the arm
    when the robot has one, and every other link of the URDF tree (sensors, rotors, limbs that are
    not recognised as legs) from its frame to its child joints' frames. Joints beyond their limits
    are marked with a cross, legs at a singular configuration (smallest singular value of the
    Jacobian below 1e-3 of the leg's reach) with a star.

    Parameters
    ----------
    robot:
        An :class:`spotkin.Robot` (``sk.Spot()``, ``sk.Robot.from_urdf(...)``).
    body_pose:
        One body pose, (6,) [x, y, z, a, b, c] with Euler angles in ``seq``, (7,) [x, y, z, qx, qy,
        qz, qw] or (4, 4). Default: a nominal stance (the feet below the hips at about 70 % of the
        legs' reach, solved by ``body_ik``; the zero angles when no such stance solves).
    q:
        (3 n,) leg joints in the order of ``robot.leg_joint_names``. Default: the nominal stance's.
    q_arm:
        The arm's joints (6,), for a robot with an arm. Default: zero angles clipped into the limits.
        Other joints of the description (grippers, rotors) are drawn at zero, clipped into their limits.
    seq:
        The Euler sequence of a (6,) ``body_pose``.
    ax:
        An Axes to draw in: 3D (``fig.add_subplot(projection="3d")``) for ``view="3d"``, 2D for the
        other views; default: a new figure of 8 x 6 in, the legend beside the drawing on its right
        (in a given ``ax``, the legend goes in its upper left corner, or where it hides the least on a
        2D view).
    title:
        The title; default: the robot's name (its description's name made readable: "Go2" for
        "go2_description") and the body pose.
    view:
        ``"3d"`` (default); ``"side"``: projected on the world's x–z plane, seen from the robot's right
        (x to the right); ``"front"``: on the y–z plane, seen from ahead (y to the right); ``"top"``: on
        the x–y plane, seen from above. The 2D views use one scale on both axes, draw the ground (the
        plane of the lowest foot) as a line in the side and front views, and draw the legs on the far
        side lighter.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn in. Its artists carry ids (``get_gid()``): ``"feet"``, ``"leg:NAME"``,
        ``"arm"``, ``"hand"``, ``"body"``, ``"support"``, ``"tree"``, ``"beyond-limits"``, ``"singular"``
        (and ``"ground"`` on the side and front views); their data are world coordinates (x, y, z) in
        3D, the view's two coordinates on a 2D view.

    Raises ``TypeError`` for a non-robot, non-numeric arrays, a non-Axes ``ax`` or a non-str ``view``;
    ``ValueError`` for a wrong shape, NaN or Inf, a body pose that is not a rigid transform or puts the
    robot beyond 1e6 m from the origin (too far to draw precisely), an unknown ``seq`` or ``view``, an
    ``ax`` of the other kind (2D for ``"3d"``, 3D for a 2D view), or ``q_arm`` for a robot without an
    arm.
    """
    robot = _check_robot(robot)
    seq = _check_seq(seq)
    view = _check_view(view)
    flat = _VIEWS[view] is not None
    ax = _check_ax(ax, three_d=not flat)
    title = _check_title(title)
    nominal = None
    if body_pose is None or q is None:
        nominal = _nominal_stance(robot)
    T = _single_pose(nominal[0] if body_pose is None else body_pose, seq)
    q = nominal[1] if q is None else _vector(q, "q", 3 * robot.n_legs)
    arm = robot.arm
    if q_arm is not None and arm is None:
        raise ValueError("q_arm was given but this robot has no arm")
    if arm is not None:
        q_arm = _default_q(arm) if q_arm is None else _vector(q_arm, "q_arm", arm.dof)
    frame = _frame(robot, T, q, q_arm)
    _near(_frame_points(frame), "body_pose", "the robot")
    points = _frame_points(frame)
    outside = ax is None
    if ax is None:
        fig = plt.figure(figsize=(8, 6))
        ax = fig.add_axes(
            (0.01, 0.03, 0.72, 0.88) if not flat else (0.1, 0.1, 0.63, 0.8), projection=None if flat else "3d"
        )
    span = float(np.ptp(points, axis=0).max())
    artists = _RobotArtists(ax, robot, frame, 0.15 * span, view)
    ends = np.concatenate([points, artists._axis(T, 0), artists._axis(T, 1), artists._axis(T, 2)])
    if flat:
        ground = None if view == "top" else float(frame.feet[:, 2].min()) if len(frame.feet) else None
        _frame_2d(ax, artists._flat(ends), ground)
        names = "xyz"
        i, j = _VIEWS[view][:2]
        ax.set_xlabel(f"{names[i]} (m)")
        ax.set_ylabel(f"{names[j]} (m)")
    else:
        _equal_3d(ax, ends)
        _label_3d(ax)
        _sparse_ticks(ax, 7)
    artists.legend(outside=outside)
    if title is None:
        position = ", ".join(f"{v:.3f}" for v in T[:3, 3])
        seen = f", {_VIEW_NAMES[view]}" if flat else ""
        title = f"{_robot_name(robot)}: body at ({position}) m{seen}"
    ax.set_title(title)
    return ax.figure
