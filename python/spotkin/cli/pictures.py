"""The command line's pictures (:mod:`spotkin.plot`, an optional extra): ``spotkin demo --plots`` and
``spotkin plot``."""

from __future__ import annotations

import os

import numpy as np

from .. import robots
from ..kinematics.joint_paths import hold_branch, point_to_point
from ..kinematics.path_planning import via_points
from ..model.robot import Robot
from ..model.spot import Spot
from .demo_data import DEMO_ARM_Q, DEMO_PATH_LIMITS, DEMO_WAYPOINTS

# ---- pictures (spotkin.plot, an optional extra) -----------------------------------------------------

PLOT_EXTRA = 'pip install "spotkin[plot]"'
GIF_FRAMES = 20
GIF_SIZE = (7.2, 4.5)  # inches: 720 x 450 pixels at 100 dpi


def _plotting():
    """spotkin.plot, drawing into files (matplotlib's Agg backend); ImportError naming the extra."""
    try:
        import matplotlib
    except ImportError:
        raise ImportError(f"pictures need matplotlib: {PLOT_EXTRA}") from None
    matplotlib.use("Agg")
    from .. import plot

    return plot


def write_plots(folder: str, dpi: int = 100) -> list[str]:
    """Write the demo's pictures into ``folder`` (created if missing) for Spot and the Unitree Go2; returns
    the paths written, in order. PNGs: ``ROBOT_stance`` and ``ROBOT_stance_side`` (its side view; 8 x 6 in),
    ``ROBOT_leg_branches`` (12 x 6.5 in; Spot also ``spot_leg_branches_hip_height``, where two branches are
    valid), ``spot_arm_branches`` (13 x 7 in), ``ROBOT_workspace`` (9.5 x 6.5 in), ``ROBOT_trajectory``
    (8 x 7 in), at ``dpi``; and ``ROBOT_path.gif``, the demo's body path in 20 frames of 7.2 x 4.5 in, its
    motions scaled to the robot (1.5 times for Spot, 0.9 for the smaller Go2: several centimetres and
    degrees, visible at that size), with the hand held in the world for a robot with an arm. Every figure
    is closed, also on error."""
    plot = _plotting()
    import matplotlib.pyplot as plt

    os.makedirs(folder, exist_ok=True)
    before = set(plt.get_fignums())
    written: list[str] = []
    try:
        written += _robot_plots(plot, plt, folder, "spot", Spot(), 0.5, 1.5, dpi)
        go2 = Robot.from_urdf(robots.path("go2"))
        written += _robot_plots(plot, plt, folder, "go2", go2, 0.3, 0.9, dpi)
    finally:
        for number in set(plt.get_fignums()) - before:
            plt.close(number)
    return written


def save_png(fig, path: str, dpi: float) -> None:
    """Save a figure as a PNG on a palette of 256 colours, without dithering: line art looks the same and
    the file is a few times smaller (the repository keeps its pictures under 200 KB)."""
    import io

    from PIL import Image  # a dependency of matplotlib

    buffer = io.BytesIO()
    fig.savefig(buffer, format="rgba", dpi=dpi)
    width, height = fig.get_size_inches()
    size = (int(width * dpi), int(height * dpi))  # as the Agg renderer sizes it
    image = Image.frombuffer("RGBA", size, buffer.getbuffer()).convert("RGB")
    image.quantize(colors=256, method=0, dither=0).save(path, format="PNG", optimize=True)


def _scaled_waypoints(height: float, scale: float) -> np.ndarray:
    """The demo's body path for a robot standing ``height`` high, its motions scaled by ``scale``."""
    waypoints = DEMO_WAYPOINTS * scale
    waypoints[:, 2] = height + (DEMO_WAYPOINTS[:, 2] - 0.5) * scale
    return waypoints


def _held_arm(robot: Robot, T_body: np.ndarray, rate_samples: int = 2000) -> np.ndarray:
    """(K, 6) arm joints holding the hand fixed in the world along the body poses T_body (K, 4, 4): the
    branch of DEMO_ARM_Q held continuously (checked on a fine resampling of the path), gaps filled with
    the last reached joints."""
    arm = robot.arm
    T_base = T_body @ robot.arm_mount  # world <- arm base: the arm's chain is in its base link's frame
    hand = T_base[0] @ arm.fk(DEMO_ARM_Q)
    sol = arm.ik_all(np.linalg.solve(T_base, np.broadcast_to(hand, T_base.shape)))
    branch = int(np.argmin(np.abs(np.angle(np.exp(1j * (sol.q[0] - DEMO_ARM_Q)))).max(axis=-1)))
    q = hold_branch(sol.q, sol.valid, branch).q
    for k in range(len(q)):
        if not np.isfinite(q[k]).all():
            q[k] = q[k - 1] if k else DEMO_ARM_Q
    return q


def _robot_plots(plot, plt, folder, name, robot, height, scale, dpi) -> list[str]:
    written = []

    def save(fig, stem):
        path = os.path.join(folder, f"{name}_{stem}")
        save_png(fig, path, dpi)
        plt.close(fig)
        written.append(path)

    pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0])
    stance = robot.body_ik(pose, robot.stance_feet(height))
    arm_q = DEMO_ARM_Q if robot.arm is not None else None
    title = f"{plot._robot_name(robot)}: a nominal stance"
    save(plot.robot(robot, pose, stance.q, arm_q, title=title), "stance.png")
    side = plot.robot(robot, pose, stance.q, arm_q, title=f"{title}, side view", view="side")
    save(side, "stance_side.png")
    leg = robot.legs[0]
    q_leg = stance.q[robot._columns[0]]
    save(plot.branches(leg, leg.fk(q_leg)), "leg_branches.png")
    if name == "spot":
        save(plot.branches(leg, [0.3, 0.13, 0.0]), "leg_branches_hip_height.png")
        save(plot.branches(robot.arm, robot.arm.fk([0.4, -1.2, 1.9, 0.3, -0.6, 0.8])), "arm_branches.png")
    save(plot.workspace(leg, "xz", offset=round(0.99 * leg.hip_offset, 3)), "workspace.png")
    swing = point_to_point(q_leg, q_leg + [0.1, -0.4, 0.6], vmax=2.0, amax=8.0, profile="trapezoid")
    save(plot.trajectory(swing, limits=leg.limits, names=("hip roll", "hip pitch", "knee")), "trajectory.png")
    path = via_points(_scaled_waypoints(height, scale), **DEMO_PATH_LIMITS)
    T_body = path.sample(np.linspace(0.0, path.duration, GIF_FRAMES))
    legs = robot.body_ik(T_body, robot.stance_feet(height))
    q_arm = _held_arm(robot, T_body) if robot.arm is not None else None
    fig = plt.figure(figsize=GIF_SIZE)
    interval = 1e3 * path.duration / (GIF_FRAMES - 1)
    animation = plot.animate(robot, T_body, legs.q, q_arm, interval=interval, fig=fig)
    gif = os.path.join(folder, f"{name}_path.gif")
    animation.save(gif, dpi=dpi)
    plt.close(fig)
    written.append(gif)
    return written


def _load_robot(source: str) -> Robot:
    """``spot`` (the built-in Spot), a packaged description's name, or a URDF path."""
    if source == "spot":
        return Spot()
    if source in robots.NAMES:
        return Robot.from_urdf(robots.path(source))
    return Robot.from_urdf(source)


def plot_stance(
    source: str, out: str | None = None, stance: str = "nominal", size=(800, 600), dpi=100, view="3d"
) -> int:
    """Draw a robot (see :func:`_load_robot`) in its nominal stance (the feet below the hips at about 70 %
    of the legs' reach, solved by body_ik; the zero stance when none solves) or its zero stance, in 3D or
    a side, front or top ``view`` (:func:`spotkin.plot.robot`), into a PNG of ``size`` pixels; print the
    path written."""
    plot = _plotting()
    import matplotlib.pyplot as plt

    if source != "spot":
        from .. import urdf

        model = urdf.load_urdf(robots.path(source) if source in robots.NAMES else source)
        if not urdf.find_legs(model)[0]:  # an arm, a gripper, a head: its tree and chains
            return _plot_description(plot, plt, model, source, out, stance, size, dpi)
    robot = _load_robot(source)
    pose, q = plot._nominal_stance(robot) if stance == "nominal" else plot._zero_stance(robot)
    if out is None:
        out = f"{os.path.splitext(os.path.basename(source))[0]}_stance.png"
    name = plot._robot_name(robot) if robot.name else source
    title = f"{name}: {stance} stance, body at {pose[2]:.3f} m"
    fig = plot.robot(robot, pose, q, title=title if view == "3d" else f"{title}, {view} view", view=view)
    try:
        fig.set_size_inches(size[0] / dpi, size[1] / dpi)
        save_png(fig, out, dpi)
    finally:
        plt.close(fig)
    print(f"wrote {out}")
    return 0


def _plot_description(plot, plt, model, source: str, out, stance: str, size, dpi) -> int:
    """``spotkin plot`` for a description without legs: its tree at the zero configuration, or at
    mid-limits for ``stance="nominal"`` (0 for an unlimited joint), drawn by ``plot._description``."""
    values = {}
    for joint in model.actuated_joints:
        middle = 0.5 * (joint.lower + joint.upper)
        values[joint.name] = middle if stance == "nominal" and np.isfinite(middle) else 0.0
    if out is None:
        out = f"{os.path.splitext(os.path.basename(source))[0]}_stance.png"
    what = "mid-limit" if stance == "nominal" else "zero"
    fig = plt.figure(figsize=(size[0] / dpi, size[1] / dpi))
    try:
        ax = fig.add_subplot(projection="3d")
        plot._description(ax, model, values, title=f"{model.name or source}: {what} configuration")
        save_png(fig, out, dpi)
    finally:
        plt.close(fig)
    print(f"wrote {out}")
    return 0
