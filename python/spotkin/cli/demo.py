"""``spotkin demo``: the showcase on built-in data (the whole body, a timed body path, one leg, the arm
and a DH chain)."""

from __future__ import annotations

import math
import time

import numpy as np

from .. import robots
from .._support.runtime import get_num_threads
from .._support.status import Status
from .._support.transforms import translation
from .._support.version import __version__
from ..kinematics.joint_paths import hold_branch
from ..kinematics.path_planning import via_points
from ..model.body import body_transform
from ..model.chain import Chain
from ..model.leg import SLOT_NAMES
from ..model.robot import Robot
from ..model.spot import Spot
from .demo_data import DEMO_PATH_LIMITS, DEMO_WAYPOINTS
from .pictures import _plotting, write_plots

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
    _demo_reach()
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


def _demo_reach(targets: int = 500) -> None:
    """Spot.reach on hand targets made from random feasible whole-body configurations, then one target
    moving with seeds."""
    from ..motion import reach as reach_module
    from ..reference.reach import feasible_samples

    spot = Spot()
    problem = reach_module.reference_problem(spot, np.eye(4))
    T, _, _ = feasible_samples(problem, targets, seed=0)
    spot.reach(T[:2])  # the compiled model, made once
    seconds = math.inf
    for _ in range(3):  # the best of three calls: the threads' first call also sets up their memory
        start = time.perf_counter()
        result = spot.reach(T)
        seconds = min(seconds, time.perf_counter() - start)
    ok = result.status == 0
    frames = spot.fk_all(result.body_pose[ok], result.q[ok])
    hand = float(np.abs(frames.hand - T[ok]).max(initial=0.0))
    feet = float(np.abs(frames.feet - problem.feet).max(initial=0.0))
    print(
        f"Whole-body reach (Spot.reach): {targets} hand targets from random feasible configurations (the "
        "body in its box, the arm's joints in their limits, no collision, the centre of mass inside the feet)"
    )
    print(
        f"  {ok.sum()} of {targets} reached exactly: worst hand pose error {hand:.1e}, worst foot error "
        f"{feet:.1e} m, smallest support margin {np.min(result.margin[ok]):.3f} m; "
        f"{seconds / targets * 1e6:.1f} us per target on {get_num_threads()} threads"
    )
    previous, jumps = spot.reach(T[0]), []
    for step in range(1, 21):  # the hand target moving 4 cm, each answer seeded with the last
        target = T[0].copy()
        target[:3, 3] += step * np.array([0.002, 0.0, 0.001])
        following = spot.reach(target, seed=previous)
        jumps.append(float(np.abs(following.q - previous.q).max()))
        previous = following
    print(
        f"  a target moving 4.5 cm in 20 steps, each reach seeded with the last: {previous.status.name}, "
        f"largest joint step {max(jumps):.4f} rad"
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
