"""The ``spotkin`` command line: ``spotkin demo`` runs the showcase on built-in data (``--plots DIR``
also writes its pictures); ``spotkin inspect ROBOT.urdf`` shows what a description holds and what
spotkin recognises; ``spotkin plot ROBOT.urdf`` draws a robot in its nominal or zero stance;
``spotkin batch OPERATION`` runs a batch kernel over datasets on disk (``spotkin[dask]``);
``spotkin workspace --robot spot`` estimates a leg's workspace volume and an arm's dexterous region."""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

from . import robots
from ._support.runtime import get_num_threads
from ._support.status import Status
from ._support.transforms import translation
from ._support.version import __version__
from .kinematics.joint_paths import hold_branch, point_to_point
from .kinematics.path_planning import via_points
from .model.arm import SpotArm
from .model.body import body_transform
from .model.chain import Chain
from .model.leg import SLOT_NAMES
from .model.robot import Robot
from .model.spot import Spot
from .scale import batch_operations, batch_run

# A Spot leg as a modified DH table (sigma, d, alpha, r, theta), knee offset left out: the leg model
# of the course this library follows (docs/derivations.md, "The leg as a DH table").
_H1, _H2, _H3 = 0.110945, 0.3205, 0.3365
LEG_MDH_ROWS = [
    (0, 0.0, -np.pi / 2, 0.0, 0.0),
    (0, 0.0, np.pi / 2, _H1, 0.0),
    (0, _H2, 0.0, 0.0, 0.0),
]


def _throughput(func, arg, repeats: int = 3) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        func(arg)
        best = min(best, time.perf_counter() - start)
    return best


def demo(samples: int = 1_000_000, plots: str | None = None, dpi: int = 100) -> int:
    """Print the showcase: the whole body, a timed body path, one leg, the arm and a DH chain; with
    ``plots``, also write its pictures into that folder (:func:`write_plots`)."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
        raise ValueError(f"samples must be a positive integer, got {samples!r}")
    if plots is not None:
        _plotting()  # before the showcase: a missing matplotlib is reported at once
    print(f"spotkin {__version__} demo: the built-in Spot model")
    print()
    _demo_body(samples)
    print()
    _demo_standing()
    print()
    _demo_urdf_robot(samples)
    print()
    _demo_path()
    print()
    _demo_leg(samples)
    print()
    _demo_arm(samples)
    print()
    _demo_chain(samples)
    if plots is not None:
        print()
        print(f"Pictures (spotkin.plot, {dpi} dpi):")
        for path in write_plots(plots, dpi):
            print(f"  wrote {path}")
    return 0


def body_trajectory(samples: int, height: float = 0.5) -> np.ndarray:
    """A body trajectory (samples, 6) [x, y, z, roll, pitch, yaw] over 20 s: sway, pitch, crouch."""
    t = np.linspace(0.0, 20.0, samples)
    pose = np.zeros((samples, 6))
    pose[:, 1] = 0.06 * np.sin(2 * np.pi * 0.5 * t)  # lateral sway
    pose[:, 0] = 0.04 * np.sin(2 * np.pi * 0.25 * t)  # fore-aft
    pose[:, 2] = height - 0.08 * (0.5 - 0.5 * np.cos(2 * np.pi * 0.1 * t))  # crouch
    pose[:, 3] = 0.12 * np.sin(2 * np.pi * 0.3 * t)  # roll
    pose[:, 4] = 0.15 * np.sin(2 * np.pi * 0.2 * t)  # pitch
    pose[:, 5] = 0.10 * np.sin(2 * np.pi * 0.15 * t)  # yaw
    return pose


def _demo_body(samples: int) -> None:
    spot = Spot()
    feet = spot.stance_feet(height=0.5)
    poses = body_trajectory(samples)
    print(
        f"Whole body: {samples:,} body poses (sway, pitch, crouch) over a fixed stance, "
        f"{get_num_threads()} threads"
    )
    seconds = _throughput(lambda p: spot.body_ik(p, feet), poses)
    result = spot.body_ik(poses, feet)
    print(
        f"  body_ik: {seconds * 1e3:.1f} ms, {samples / seconds / 1e6:.1f} M poses/s "
        f"({seconds / samples * 1e9:.1f} ns per pose, 12 joints)"
    )
    counts = {s.name: int((result.status == s).sum()) for s in Status}
    ok = result.status == Status.OK
    error = np.abs(spot.body_fk(poses, result.q) - feet)[ok].max(initial=0.0)
    print(f"  check by body_fk: worst foot error {error:.1e} m; leg statuses {counts}")
    # the arm holds a hand target fixed in the world while the body moves
    arm_q = np.array([0.0, -1.2, 1.9, 0.0, 0.4, 0.0])
    target = body_transform(poses[0]) @ spot.arm.fk(arm_q)
    every = max(1, samples // 100_000)
    q_arm, arm_status = spot.arm_ik_world(poses[::every], target, seed=arm_q)
    reached = arm_status == Status.OK
    hand = body_transform(poses[::every][reached]) @ spot.arm.fk(q_arm[reached])
    hand_error = np.abs(hand - target).max(initial=0.0)
    print(
        f"  arm holding a world-fixed hand target at {np.round(target[:3, 3], 3)} m on "
        f"{len(reached):,} of those poses: {int(reached.sum()):,} solved within limits, "
        f"worst hand pose error {hand_error:.1e}"
    )


def _demo_standing() -> None:
    """Spot's standing torques (the URDF's inertials): nominal stance and a crouch, four feet down."""
    spot = Spot()
    feet = spot.stance_feet(height=0.5)
    print(
        f"Standing statics: Spot ({spot.mass:.1f} kg with its arm, from the URDF's inertials) on four feet, "
        "minimum-norm contact forces"
    )
    for label, height in (("nominal stance", 0.5), ("crouch", 0.38)):
        pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0])
        q = spot.body_ik(pose, feet).q
        standing = spot.standing_torques(pose, q)
        knees = ", ".join(f"{name} {tau:+.1f}" for name, tau in zip(spot.leg_names, standing.tau[2::3]))
        print(
            f"  {label:<14} (body at {height:.2f} m): knee torques {knees} N m; "
            f"foot loads {np.round(standing.forces[:, 2], 1)} N; {standing.status.name}, "
            f"support margin {standing.margin:.3f} m"
        )


def _demo_urdf_robot(samples: int) -> None:
    """Whole-body IK on a robot loaded from its URDF (the packaged Unitree Go2)."""
    start = time.perf_counter()
    go2 = Robot.from_urdf(robots.path("go2"))
    load_ms = (time.perf_counter() - start) * 1e3
    print(
        f"Unitree Go2 from its URDF ({load_ms:.1f} ms to load): legs {', '.join(go2.leg_names)}, "
        f"{len(go2.joint_names)} actuated joints"
    )
    leg = go2.legs[0]
    print(
        f"  {leg.name}: a = {np.round(leg.a, 4)}, b = {np.round(leg.b, 4)}, c = {np.round(leg.c, 4)} m, "
        f"preferred slot {leg.preferred_slot} ({SLOT_NAMES[leg.preferred_slot]})"
    )
    feet = go2.stance_feet(height=0.3)
    poses = body_trajectory(samples, height=0.3) * [0.5, 0.5, 1.0, 0.5, 0.5, 0.5]
    seconds = _throughput(lambda p: go2.body_ik(p, feet), poses)
    result = go2.body_ik(poses, feet)
    ok = result.status == Status.OK
    error = np.abs(go2.body_fk(poses, result.q) - feet)[ok].max(initial=0.0)
    counts = {s.name: int((result.status == s).sum()) for s in Status}
    print(
        f"  body_ik: {samples:,} poses in {seconds * 1e3:.1f} ms "
        f"({seconds / samples * 1e9:.1f} ns per pose); worst foot error by body_fk {error:.1e} m; "
        f"leg statuses {counts}"
    )


def inspect(path: str) -> int:
    """Print a URDF's tree, the legs and arms spotkin recognises with their geometry, and why the
    other branches were not recognised. A description without legs (an arm, a gripper, a head) is
    described with the chains from its root to each tip: joints, dof, closed-form IK or what applies
    instead, mimic joints (:meth:`spotkin.Chain.from_urdf` builds them)."""
    from . import urdf
    from .model.urdf_chain import chains_summary

    model = urdf.load_urdf(path)
    if urdf.find_legs(model)[0]:
        print(Robot.from_urdf(path).describe())
        return 0
    text = urdf.describe(model)
    print(text[: text.index("\nlegs (")])  # the header and the tree
    print("no legs: not a Robot; its chains load with spotkin.Chain.from_urdf(path, tip=...)")
    print(chains_summary(model))
    return 0


def _demo_path(rate: float = 1000.0) -> None:
    """The body on a timed via-point path (trapezoidal speed, blends) while the hand holds its pose."""
    spot = Spot()
    feet = spot.stance_feet(height=0.5)
    waypoints = DEMO_WAYPOINTS
    path = via_points(waypoints, **DEMO_PATH_LIMITS)
    t = np.arange(0.0, path.duration, 1.0 / rate)
    print(
        f"Timed body path: {len(waypoints)} via points, blends, |v| <= 0.1 m/s, |a| <= 0.5 m/s^2: "
        f"{path.duration:.2f} s sampled at {rate:.0f} Hz ({len(t):,} poses)"
    )
    start = time.perf_counter()
    poses = path.sample(t, form="quaternion")  # (K, 7) [x, y, z, qx, qy, qz, qw]
    legs = spot.body_ik(poses, feet)
    T_body = path.sample(t)  # (K, 4, 4) world <- body
    arm_q0 = np.array([0.0, -1.2, 1.9, 0.0, 0.4, 0.0])
    hand = T_body[0] @ spot.arm.fk(arm_q0)  # held fixed in the world
    T_arm = np.linalg.solve(T_body, np.broadcast_to(hand, T_body.shape))  # the hand in the moving body frame
    arm = spot.arm.ik_all(T_arm)
    seconds = time.perf_counter() - start
    branch = int(np.argmin(np.abs(np.angle(np.exp(1j * (arm.q[0] - arm_q0)))).max(axis=-1)))
    held = hold_branch(arm.q, arm.valid, branch)
    reached = np.isfinite(held.q).all(axis=-1)
    hand_error = np.abs(T_body[reached] @ spot.arm.fk(held.q[reached]) - hand).max(initial=0.0)
    foot_error = np.abs(spot.body_fk(poses, legs.q) - feet)[legs.status == Status.OK].max(initial=0.0)
    counts = {s.name: int((legs.status == s).sum()) for s in Status}
    print(
        f"  path sampling + body_ik + arm ik_all for every sample: {seconds * 1e3:.1f} ms; "
        f"leg statuses {counts}; worst foot error {foot_error:.1e} m"
    )
    print(
        f"  hand held in the world on arm branch {branch}: {int(held.ok.sum()):,} of {len(t):,} samples "
        f"continuous, worst hand pose error {hand_error:.1e}, branch jumps at samples "
        f"{held.jumps.tolist() or 'none'}"
    )


DEMO_WAYPOINTS = np.array(
    [  # the demo's body path, [x, y, z, roll, pitch, yaw] (Spot standing 0.5 m high)
        [0.00, 0.00, 0.50, 0.00, 0.00, 0.00],
        [0.05, 0.06, 0.46, 0.10, -0.08, 0.12],
        [-0.04, 0.05, 0.44, -0.05, 0.12, -0.10],
        [0.00, -0.06, 0.48, 0.08, 0.05, 0.05],
        [0.00, 0.00, 0.50, 0.00, 0.00, 0.00],
    ]
)
DEMO_PATH_LIMITS = {"vmax": 0.1, "amax": 0.5, "wmax": 0.4, "alphamax": 2.0, "blend": 0.3}
DEMO_ARM_Q = np.array([0.0, -1.2, 1.9, 0.0, 0.4, 0.0])  # the arm's joints at the start of the body path


def _demo_leg(samples: int) -> None:
    spot = Spot()
    leg = spot.leg("fl")
    print(f"Front-left leg: {leg!r}")
    q_stand = np.array([0.05, 1.04, -1.8])
    target = leg.fk(q_stand)
    print(f"  target foot (leg frame) = fk({q_stand}) = {np.round(target, 6)} m")
    sol = leg.ik_all(target)
    for slot, name in enumerate(SLOT_NAMES):
        mark = "valid" if sol.valid[slot] else ("outside limits" if sol.exists[slot] else "no solution")
        error = np.linalg.norm(leg.fk(sol.q[slot]) - target)
        print(
            f"  slot {slot} ({name:<25}) q = {np.round(sol.q[slot], 4)}  |fk - target| = {error:.1e}  {mark}"
        )
    q, status = leg.ik(target)
    print(f"  leg.ik -> {np.round(q, 6)} {status!r}")
    for label, p in (("beyond reach", [0.0, 0.11, -0.9]), ("NaN", [np.nan, 0.0, -0.5])):
        q, status = leg.ik(p)
        print(f"  {label:>12}: {p} -> {status!r}, q = {np.round(q, 4)}")
    rng = np.random.default_rng(0)
    limits = leg.limits
    q_batch = rng.uniform(limits[:, 0], limits[:, 1], (samples, 3))
    feet = leg.fk(q_batch)
    for name, func, arg in (("fk", leg.fk, q_batch), ("ik", leg.ik, feet), ("ik_all", leg.ik_all, feet)):
        seconds = _throughput(func, arg)
        print(
            f"  {name:>8} on {samples:,} targets: {seconds * 1e3:7.1f} ms "
            f"({samples / seconds / 1e6:.1f} M/s, {seconds / samples * 1e9:.1f} ns each)"
        )
    q_back, status = leg.ik(feet)
    counts = {s.name: int((status == s).sum()) for s in Status}
    foot_error = np.linalg.norm(leg.fk(q_back) - feet, axis=-1).max()
    unique = feet[:, 2] < -0.08  # below this, the limits leave a single branch (slot 0)
    joint_error = np.abs(q_back[unique] - q_batch[unique]).max(initial=0.0)
    print(
        f"  round trip fk -> ik: worst |fk(ik(p)) - p| = {foot_error:.1e} m; worst joint error "
        f"{joint_error:.1e} rad where the branch is unique (foot > 8 cm below hx); statuses {counts}"
    )


def _demo_arm(samples: int) -> None:
    arm = Spot().arm
    print(f"Spot Arm: {arm!r}")
    q_true = np.array([0.4, -1.2, 1.9, 0.3, -0.6, 0.8])
    T = arm.fk(q_true)
    print(f"  hand target = fk({q_true}): position {np.round(T[:3, 3], 4)} m")
    sol = arm.ik_all(T)
    names = [
        f"{('front', 'back ')[s // 4]} {('up  ', 'down')[s // 2 % 2]} {('wr0+', 'wr0-')[s % 2]}"
        for s in range(8)
    ]
    for slot in range(8):
        error = np.abs(arm.fk(sol.q[slot]) - T).max()
        mark = "valid" if sol.valid[slot] else ("outside limits" if sol.exists[slot] else "no solution")
        print(f"  slot {slot} ({names[slot]}) q = {np.round(sol.q[slot], 3)}  |fk - T| = {error:.0e}  {mark}")
    q, status = arm.ik(T, seed=q_true + 0.05)
    print(f"  arm.ik(T, seed=q_true + 0.05) -> {np.round(q, 6)} {status!r}")
    rng = np.random.default_rng(1)
    limits = arm.limits
    n = max(1, samples // 10)
    poses = arm.fk(rng.uniform(limits[:, 0], limits[:, 1], (n, 6)))
    seconds = _throughput(arm.ik_all, poses)
    print(
        f"    ik_all on {n:,} poses (8 solutions each): {seconds * 1e3:7.1f} ms "
        f"({n / seconds / 1e6:.2f} M poses/s, {seconds / n * 1e9:.0f} ns each)"
    )


def _demo_chain(samples: int) -> None:
    leg = Chain.from_mdh(LEG_MDH_ROWS, tool=translation([_H3, 0.0, 0.0]))
    print(
        "A Spot leg as a modified DH table, knee offset left out "
        f"(angles th1 = -hx, th2 = hy, th3 = kn): {leg!r}"
    )
    q = np.array([0.1, -0.6, 1.2])
    T = leg.fk(q)
    print(f"  q = {q} rad -> foot at {np.round(T[:3, 3], 6)} m")
    J = leg.position_jacobian(q)
    t2, t3 = q[1], q[2]
    det_closed = -_H2 * _H3 * np.sin(t3) * (_H2 * np.cos(t2) + _H3 * np.cos(t2 + t3))
    print(f"  det(J) = {np.linalg.det(J):+.9f}, closed form -h2 h3 s3 (h2 c2 + h3 c23) = {det_closed:+.9f}")
    batch = np.random.default_rng(0).uniform(-np.pi, np.pi, (samples, 3))
    for name, func in (("fk", leg.fk), ("jacobian", leg.jacobian)):
        seconds = _throughput(func, batch)
        print(
            f"  {name:>8} on {samples:,} configurations: {seconds * 1e3:7.1f} ms "
            f"({samples / seconds / 1e6:.1f} M/s, {seconds / samples * 1e9:.0f} ns each)"
        )
    checked = batch[:1000]
    worst = _fd_error(leg, checked)
    print(f"  worst |J - central finite differences| over {len(checked):,} samples: {worst:.1e}")
    targets = leg.fk(batch)[:, :3, 3]
    seconds = _throughput(leg.ik_position, targets)
    sol = leg.ik_position(targets)
    found = sol.q[sol.exists]
    error = np.abs(leg.fk(found)[:, :3, 3] - np.repeat(targets, sol.exists.sum(-1), axis=0)).max()
    print(
        f"  closed-form IK from the table ({leg.ik_kind}): {samples:,} targets in {seconds * 1e3:.1f} ms "
        f"({seconds / samples * 1e9:.0f} ns each), {sol.exists.sum(-1).mean():.2f} solutions per target, "
        f"worst |fk(q) - p| {error:.1e} m"
    )


def _fd_error(chain: Chain, q: np.ndarray, step: float = 1e-6) -> float:
    J = chain.position_jacobian(q)
    worst = 0.0
    for j in range(chain.dof):
        dq = np.zeros(chain.dof)
        dq[j] = step
        column = (chain.fk(q + dq)[:, :3, 3] - chain.fk(q - dq)[:, :3, 3]) / (2 * step)
        worst = max(worst, float(np.abs(column - J[:, :, j]).max()))
    return worst


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
    from . import plot

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
        from . import urdf

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


def workspace_report(
    source: str = "spot",
    samples: int = 2_000_000,
    spacing: float = 0.05,
    orientations: int = 128,
    seed: int = 0,
) -> int:
    """Print the workspace volume of the robot's first leg (:func:`spotkin.workspace_volume`, ``samples``
    Monte Carlo points) and, with an arm, its dexterity (:func:`spotkin.dexterity` on a grid of
    ``spacing`` with ``orientations`` orientations per position). Deterministic for a given ``seed``."""
    from .kinematics.workspace import dexterity, workspace_volume

    robot = _load_robot(source)
    name = robot.name or source
    print(f"spotkin {__version__} workspace: {name} (seed {seed})")
    if robot.legs:
        leg = robot.legs[0]
        start = time.perf_counter()
        volume, error = workspace_volume(leg, n=samples, seed=seed)
        elapsed = time.perf_counter() - start
        print(
            f"leg {robot.leg_names[0]}: workspace volume within the joint limits {1e3 * volume:.1f} L "
            f"(± {1e3 * error:.1f} L, one standard error; {samples:,} points tested by the closed-form IK, "
            f"{elapsed:.1f} s)"
        )
    arm = robot.arm
    if arm is not None:
        start = time.perf_counter()
        dex = dexterity(arm, spacing=spacing, orientations=orientations, seed=seed)
        elapsed = time.perf_counter() - start
        print(
            f"arm: {len(dex.positions):,} grid positions ({1e3 * spacing:.0f} mm spacing) x {orientations} "
            f"orientations uniform on SO(3), IK within the limits ({elapsed:.1f} s)"
        )
        print(f"  reached with some sampled orientation: {1e3 * dex.volume(1e-12):.0f} L")
        for level in (0.5, 0.9, 1.0):
            print(
                f"  reached with >= {100 * level:.0f} % of the orientations: {1e3 * dex.volume(level):.1f} L"
            )
        print(
            f"  best position: {100 * dex.fraction.max():.1f} % of the orientations, at "
            f"{np.array2string(dex.positions[np.argmax(dex.fraction)], precision=3)} m (body frame)"
        )
        best = dex.fraction >= 0.5
        if best.any():
            low, high = dex.positions[best].min(0), dex.positions[best].max(0)
            print(
                f"  the >= 50 % region spans x {low[0]:.2f}..{high[0]:.2f}, y {low[1]:.2f}..{high[1]:.2f}, "
                f"z {low[2]:.2f}..{high[2]:.2f} m"
            )
        if isinstance(arm, SpotArm):  # the same arm with its joint limits removed, for comparison
            free = dexterity(
                SpotArm(*arm._params[:6], limits=None), spacing=spacing, orientations=orientations, seed=seed
            )
            print(
                f"  without joint limits: every sampled orientation at {1e3 * free.volume(1.0):.1f} L of "
                f"positions, >= 50 % at {1e3 * free.volume(0.5):.1f} L"
            )
    return 0


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT in pixels (e.g. 800x600), got {text!r}"
        ) from None
    if width < 16 or height < 16 or width > 10_000 or height > 10_000:
        raise argparse.ArgumentTypeError(f"each side must be 16 to 10000 pixels, got {text!r}")
    return width, height


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


DEMO_MAX_SAMPLES = 10_000_000  # the demo holds a few arrays of this many samples (GBs at the bound)
DPI_RANGE = (10, 600)  # below 10 dpi the fonts get no pixel (FreeType refuses); above, GIF frames of GBs


def _out_of_range(args) -> str | None:
    """What is wrong with a parsed option's value (a count, a resolution) that argparse's types accept,
    or None: checked before anything is loaded, computed or allocated."""
    from .kinematics import workspace as _workspace

    checks = []
    if args.command == "demo":
        checks.append(("--samples", args.samples, 1, DEMO_MAX_SAMPLES))
    if args.command in ("demo", "plot"):
        checks.append(("--dpi", args.dpi, *DPI_RANGE))
    if args.command == "workspace":
        checks.append(("--samples", args.samples, 1, _workspace.MAX_VOLUME_SAMPLES))
        checks.append(("--orientations", args.orientations, 1, _workspace.MAX_ORIENTATIONS))
        checks.append(("--seed", args.seed, 0, 2**64 - 1))
        if not (np.isfinite(args.spacing) and args.spacing > 0):
            return f"--spacing must be a positive number of metres, got {args.spacing}"
    for option, value, low, high in checks:
        if not low <= value <= high:
            return f"{option} must be in [{low:,}, {high:,}], got {value:,}"
    return None


def main(argv: list[str] | None = None) -> int:
    # the module docstring without its reST markup: ``spotkin demo`` reads "spotkin demo" in a terminal
    parser = argparse.ArgumentParser(prog="spotkin", description=__doc__.replace("``", '"'))
    parser.add_argument("--version", action="version", version=f"spotkin {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    demo_parser = commands.add_parser("demo", help="run the showcase on the built-in Spot model")
    demo_parser.add_argument(
        "--samples",
        type=_positive_int,
        default=1_000_000,
        help="batch size for the throughput figures (1 to 10,000,000; default 1,000,000)",
    )
    inspect_parser = commands.add_parser(
        "inspect", help="show a URDF's tree and the legs and arms spotkin recognises in it"
    )
    inspect_parser.add_argument("urdf", help="path of the URDF file")
    demo_parser.add_argument(
        "--plots",
        metavar="DIR",
        help=f"also write the demo's pictures (PNGs and GIFs) into DIR (needs matplotlib: {PLOT_EXTRA})",
    )
    dpi_help = "resolution of the pictures (10 to 600; default 100)"
    demo_parser.add_argument("--dpi", type=_positive_int, default=100, help=dpi_help)
    plot_parser = commands.add_parser(
        "plot", help=f"draw a robot from its URDF in its nominal or zero stance (needs {PLOT_EXTRA})"
    )
    plot_parser.add_argument("urdf", help="path of the URDF file, or spot, spot_with_arm, go2 (packaged)")
    plot_parser.add_argument("--out", help="the PNG to write (default: NAME_stance.png here)")
    plot_parser.add_argument("--stance", choices=("nominal", "zero"), default="nominal")
    plot_parser.add_argument(
        "--view", choices=("3d", "side", "front", "top"), default="3d", help="3D (default) or a 2D view"
    )
    plot_parser.add_argument(
        "--size", type=_size, default=(800, 600), help="WIDTHxHEIGHT in pixels (800x600)"
    )
    plot_parser.add_argument("--dpi", type=_positive_int, default=100, help=dpi_help)
    workspace_parser = commands.add_parser(
        "workspace", help="estimate a leg's workspace volume and an arm's dexterous region by sampling"
    )
    workspace_parser.add_argument(
        "--robot", default="spot", help="spot (built-in), a packaged name or a URDF path"
    )
    workspace_parser.add_argument(
        "--samples",
        type=_positive_int,
        default=2_000_000,
        help="Monte Carlo points for the leg volume (at most 1e10; default 2,000,000)",
    )
    workspace_parser.add_argument(
        "--spacing", type=float, default=0.05, help="arm grid spacing, m (default 0.05)"
    )
    workspace_parser.add_argument(
        "--orientations",
        type=_positive_int,
        default=128,
        help="orientations sampled per arm grid position (at most 1,000,000; default 128)",
    )
    workspace_parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    batch_operations.add_parser(commands)  # spotkin batch OPERATION ... (spotkin/scale/batch_*.py)
    args = parser.parse_args(argv)
    if args.command == "batch":
        return batch_run.main(args)
    refused = _out_of_range(args)
    if refused:  # before any work, as argparse refuses malformed values: one line, exit 2
        print(f"spotkin {args.command}: error: {refused}", file=sys.stderr)
        return 2
    if args.command == "demo":
        try:
            return demo(args.samples, args.plots, args.dpi)
        except (ImportError, OSError) as error:
            print(f"spotkin demo: {error}", file=sys.stderr)
            return 1
    if args.command == "plot":
        try:
            return plot_stance(args.urdf, args.out, args.stance, args.size, args.dpi, args.view)
        except (ImportError, OSError, ValueError) as error:
            print(f"spotkin plot: {error}", file=sys.stderr)
            return 1
    if args.command == "workspace":
        try:
            return workspace_report(args.robot, args.samples, args.spacing, args.orientations, args.seed)
        except (OSError, ValueError) as error:
            print(f"spotkin workspace: {error}", file=sys.stderr)
            return 1
    if args.command == "inspect":
        try:
            return inspect(args.urdf)
        except (OSError, ValueError) as error:
            print(f"spotkin inspect: {error}", file=sys.stderr)
            return 1
    return 2  # pragma: no cover


if __name__ == "__main__":
    sys.exit(main())
