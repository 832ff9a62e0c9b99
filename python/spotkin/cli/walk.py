"""``spotkin walk ROBOT``: a closed-loop walk of a quadruped in the MuJoCo simulator
(:class:`spotkin.GaitController` in :func:`spotkin.sim.run`), its figures, and its pictures."""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np

from .pictures import PLOT_EXTRA, _load_robot, _plotting, save_png

SIM_EXTRA = 'pip install "spotkin[sim]"'
# --plots animates the walk's last 2 s (four or five steps of each leg) at 20 frames a second, the camera
# fixed on them, 600 x 375 pixels at 100 dpi: about 150 KB, as small as the repository keeps its pictures
ANIMATED_SECONDS = 2.0
ANIMATION_FPS = 20.0
ANIMATION_SIZE = (6.0, 3.75)  # in


def _simulator():
    """spotkin.sim, or ImportError naming the extra."""
    try:
        from .. import sim
    except ImportError:
        raise ImportError(
            f"spotkin walk runs the robot in MuJoCo, an optional dependency: {SIM_EXTRA}"
        ) from None
    return sim


class _Recorder:
    """The controller, with each tick's planned contacts kept."""

    def __init__(self, controller) -> None:
        self.controller, self.contact = controller, []

    def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
        command = self.controller.step(t, state, velocity)
        self.contact.append(command.contact)
        return command


def _ratio(measured: float, wanted: float) -> str:
    return f" ({measured / wanted:.0%} of {wanted:+.3f})" if abs(wanted) > 1e-12 else ""


def walk(
    source: str,
    gait: str = "trot",
    velocity=(0.3, 0.0, 0.0),
    duration: float = 10.0,
    plots: str | None = None,
    dpi: int = 100,
    rate: float = 500.0,
) -> int:
    """Walk ``source`` (``spot``, a packaged name or a URDF path) with ``gait`` at ``velocity`` (vx m/s,
    vy m/s, yaw rate rad/s; ramped over the first second) for ``duration`` s on flat ground; print the
    distance, speed tracking (the mean over the run after its first 2 s, in the body's heading frame),
    heading drift (the heading change less the commanded turn), the lowest body height, falls, the
    torques against their limits and the controller's cost per tick. ``plots``: also write the gait
    diagram and the foot paths (PNGs) and an animation of the walk (a GIF) into that folder. Returns 0,
    or 1 when the robot fell."""
    sim = _simulator()
    from ..motion.controller import GaitController

    robot = _load_robot(source)
    h = sim.hip_height(robot)
    controller = GaitController(robot, gait, rate=rate)
    recorder = _Recorder(controller)
    command = np.asarray(velocity, dtype=np.float64)
    result = sim.run(robot, recorder, duration=duration, rate=rate, velocity=command, ramp=1.0)
    m = result.metrics
    name = os.path.splitext(os.path.basename(source))[0]  # the pictures' prefix: spot, go2, robot.urdf's
    print(
        f"{robot.name or name}: {robot.mass:.1f} kg, h = {h:.3f} m; {gait} at ({command[0]:+.3f} m/s, "
        f"{command[1]:+.3f} m/s, {command[2]:+.3f} rad/s) for {duration:g} s at {rate:g} Hz, on flat ground"
    )
    vx, vy, wz = m.velocity
    turned = float(np.sum(result.command[:, 2]) / rate)
    print(f"  distance      {m.distance:.2f} m ({m.distance / h:.1f} h)")
    print(
        f"  speed         {vx:+.3f} m/s forward{_ratio(vx, command[0])}, {vy:+.3f} m/s sideways"
        f"{_ratio(vy, command[1])}, {wz:+.3f} rad/s{_ratio(wz, command[2])}"
    )
    if abs(command[2]) > 1e-12:
        drift = "n/a (the command turns)"
    elif math.isnan(m.lateral_drift):
        drift = "n/a"
    else:
        drift = f"{m.lateral_drift:.1%} of the distance"
    print(f"  drift         {drift} across the commanded direction")
    print(
        f"  heading       {m.heading_change - turned:+.3f} rad off the command "
        f"({m.heading_change:+.3f} rad turned)"
    )
    print(
        f"  lowest body   {m.lowest_height:.3f} m "
        f"({m.lowest_height / m.initial_height:.0%} of {m.initial_height:.3f} m)"
    )
    print(f"  roll, pitch   at most {m.max_roll:.3f} rad, {m.max_pitch:.3f} rad")
    fall = f"FELL at {m.fall_time:.2f} s ({m.fall_cause})" if m.fell else "none"
    print(f"  falls         {fall}")
    print(f"  torques       within the effort limits on {m.torque_within:.1%} of ticks")
    print(f"  controller    {1e3 * m.controller_time:.3f} ms per tick (GaitController.step, Python)")
    if plots:
        for path in write_walk_plots(plots, robot, name, result, np.array(recorder.contact), dpi):
            print(f"  wrote {path}")
    return 1 if m.fell else 0


def write_walk_plots(folder: str, robot, name: str, result, planned, dpi: int = 100) -> list[str]:
    """The walk's gait diagram (the last 3 s: planned stance and measured contacts), its foot paths in
    side view over the legs' workspaces, and an animation of its last 2 s (20 frames a second, the camera
    fixed on them; 600 x 375 pixels at 100 dpi), as ``NAME_gait.png``, ``NAME_foot_paths.png`` and
    ``NAME_walk.gif`` in ``folder`` (NAME: the robot argument's file name without its extension, or spot,
    go2); ImportError naming the plot extra without matplotlib."""
    try:
        plot = _plotting()
    except ImportError:
        raise ImportError(f"--plots needs matplotlib: {PLOT_EXTRA}") from None
    import matplotlib.pyplot as plt

    os.makedirs(folder, exist_ok=True)
    last = result.t >= result.t[-1] - 3.0
    written = []
    fig = plot.gait_diagram(
        planned[last],
        result.t[last],
        legs=robot.leg_names,
        measured=result.contact[last],
        title=f"{name}: gait diagram (the last 3 s)",
    )
    try:
        written.append(os.path.join(folder, f"{name}_gait.png"))
        save_png(fig, written[-1], dpi)
    finally:
        plt.close(fig)
    fig = plot.foot_paths(robot, result.q[last], title=f"{name}: foot paths, side view (the last 3 s)")
    try:
        written.append(os.path.join(folder, f"{name}_foot_paths.png"))
        save_png(fig, written[-1], dpi)
    finally:
        plt.close(fig)
    fig = plt.figure(figsize=ANIMATION_SIZE)
    try:
        shown = _last(result, ANIMATED_SECONDS)
        title = f"{name}, simulated walk"
        animation = plot.walk_animation(robot, shown, fps=ANIMATION_FPS, follow=False, fig=fig, title=title)
        written.append(os.path.join(folder, f"{name}_walk.gif"))
        animation.save(written[-1], dpi=dpi)
    finally:
        plt.close(fig)
    return written


def _last(result, seconds: float):
    """The result's record over its last ``seconds`` (the whole of a shorter run)."""
    keep = result.t >= result.t[-1] - seconds + 1e-9
    fields = {field.name: getattr(result, field.name) for field in dataclasses.fields(result)}
    return dataclasses.replace(
        result, **{key: value[keep] for key, value in fields.items() if isinstance(value, np.ndarray)}
    )
