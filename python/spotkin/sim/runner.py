"""A controller driving a legged robot in MuJoCo, and what the run shows. Part of :mod:`spotkin.sim`
(documented there)."""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_finite
from ..motion import RobotState
from .model import FALL_GROUP, FOOT_GROUP, hip_height, layout

__all__ = ["Metrics", "SimResult", "run"]

ARM_HZ = 5.0
"""The arm's hold: a PD at this natural frequency (critically damped) on its own joint inertia, plus
the simulator's gravity and Coriolis torques, to its initial pose."""
FALL_HEIGHT = 0.6
"""A body lower than this fraction of its initial height above the ground has fallen."""
FALL_TILT = 0.3
"""A body rolled or pitched more than this (rad) beyond the terrain's slope has fallen."""


@dataclass(frozen=True)
class Metrics:
    """What a run shows (:func:`run`): ``str(metrics)`` is one readable line.

    - ``distance`` (m): the body's horizontal displacement, start to end.
    - ``velocity`` (vx, vy, yaw rate): the mean over the window (from t = min(2 s, duration / 2), so
      the last 8 s of 10) of the body's velocity in its heading frame (the body frame turned level:
      x forward, y left; m/s) and its yaw rate about the vertical (rad/s).
    - ``lateral_drift``: the displacement across the commanded direction (the mean commanded (vx, vy)
      from the initial heading), as a fraction of ``distance``; NaN without a linear command or
      when the body moved less than 1 % of its height.
    - ``heading_change`` (rad): the yaw at the end minus at the start, unwrapped.
    - ``lowest_height`` (m): the lowest body origin above the ground under it; ``initial_height`` the
      starting one.
    - ``max_roll``, ``max_pitch`` (rad): the largest |roll| and |pitch| of the body (Z-Y-X angles).
    - ``fell``: the body, a hip, a thigh or the arm touched the ground, or the body dropped below 0.6
      of its initial height, or |roll| or |pitch| exceeded 0.3 rad plus the terrain's slope;
      ``fall_time`` (s, or None) and ``fall_cause`` say when and why first.
    - ``torque_within``: the fraction of control ticks whose PD torques stayed within the effort
      limits before clipping, at every physics step of the tick.
    - ``controller_time`` (s): the mean wall time of ``controller.step`` per tick.
    """

    distance: float
    velocity: tuple[float, float, float]
    lateral_drift: float
    heading_change: float
    lowest_height: float
    initial_height: float
    max_roll: float
    max_pitch: float
    fell: bool
    fall_time: float | None
    fall_cause: str
    torque_within: float
    controller_time: float

    def __str__(self) -> str:
        vx, vy, wz = self.velocity
        drift = "n/a" if math.isnan(self.lateral_drift) else f"{self.lateral_drift:.1%}"
        fall = f"FELL at {self.fall_time:.2f} s ({self.fall_cause})" if self.fell else "no fall"
        return (
            f"distance {self.distance:.2f} m, velocity ({vx:+.3f} m/s, {vy:+.3f} m/s, {wz:+.3f} rad/s), "
            f"drift {drift}, heading {self.heading_change:+.3f} rad, lowest {self.lowest_height:.3f} m "
            f"({self.lowest_height / self.initial_height:.0%} of {self.initial_height:.3f}), "
            f"max roll {self.max_roll:.3f} rad, max pitch {self.max_pitch:.3f} rad, {fall}, "
            f"torques within limits on {self.torque_within:.1%} of ticks, "
            f"controller {1e6 * self.controller_time:.0f} µs/tick"
        )


@dataclass(frozen=True, repr=False)
class SimResult:
    """A run, one row per control tick (None with ``record=False``), and its :class:`Metrics`.

    ``t`` (n,) s; ``position`` (n, 3), ``quaternion`` (n, 4) (x, y, z, w), ``linear_velocity`` and
    ``angular_velocity`` (n, 3) of the body, world axes; ``q``, ``qd`` (n, 3 n_legs) in
    ``robot.leg_joint_names`` order; ``tau`` (n, 3 n_legs) the PD torques at the tick's first physics
    step, clipped to the efforts; ``within`` (n,) bool, the torques stayed within the efforts before
    clipping at every step of the tick; ``contact`` (n, n_legs) bool, ``robot.leg_names`` order;
    ``command`` (n, 3) the (vx, vy, yaw rate) given to the controller, ramp included.
    """

    t: np.ndarray | None
    position: np.ndarray | None
    quaternion: np.ndarray | None
    linear_velocity: np.ndarray | None
    angular_velocity: np.ndarray | None
    q: np.ndarray | None
    qd: np.ndarray | None
    tau: np.ndarray | None
    within: np.ndarray | None
    contact: np.ndarray | None
    command: np.ndarray | None
    metrics: Metrics

    def __repr__(self) -> str:
        ticks = "no record" if self.t is None else f"{len(self.t)} ticks"
        return f"SimResult({ticks}; {self.metrics})"


def _velocity(velocity) -> Callable[[float], np.ndarray]:
    """The command as a function of t, checked: (3,) finite."""

    def checked(value, where: str) -> np.ndarray:
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{where} must be (vx, vy, yaw rate), got {value!r}") from None
        if array.shape != (3,) or not np.isfinite(array).all():
            raise ValueError(f"{where} must be 3 finite numbers (vx, vy, yaw rate), got {array.tolist()}")
        return array

    if callable(velocity):
        return lambda t: checked(velocity(t), f"velocity({t:.3f})")
    constant = checked(velocity, "velocity")
    return lambda t: constant


def _pushes(pushes) -> list[tuple[float, np.ndarray]]:
    out = []
    for k, push in enumerate(pushes):
        try:
            when, kick = push
            kick = np.asarray(kick, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"pushes[{k}] must be (time, (dvx, dvy, dvz)), got {push!r}") from None
        when = as_finite(when, f"pushes[{k}] time", 0.0)
        if kick.shape != (3,) or not np.isfinite(kick).all():
            raise ValueError(f"pushes[{k}] must be (time, (dvx, dvy, dvz)), got {push!r}")
        out.append((when, kick))
    return sorted(out, key=lambda p: p[0])


_FIELDS = ("q", "qd", "tau", "kp", "kd")


def _command(cmd, n: int, t: float) -> list[np.ndarray]:
    """The command's q, qd, tau, kp, kd as (n,) float arrays, checked (ValueError naming the field)."""
    out = []
    for name in _FIELDS:
        if not hasattr(cmd, name):
            raise ValueError(
                f"controller.step must return a spotkin.motion.JointCommand, got {type(cmd).__name__} "
                f"(no {name}) at t = {t:.3f} s"
            )
        try:
            value = np.asarray(getattr(cmd, name), dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"the controller's command {name} is not numeric at t = {t:.3f} s") from None
        if value.shape != (n,):
            if name in ("kp", "kd") and value.shape in ((), (1,)):
                value = np.full(n, float(value.reshape(-1)[0]))
            else:
                raise ValueError(
                    f"the controller's command {name} must have shape ({n},) (robot.leg_joint_names), got "
                    f"{value.shape} at t = {t:.3f} s"
                )
        if not np.isfinite(value).all():
            raise ValueError(f"the controller's command {name} is not finite at t = {t:.3f} s: {value}")
        if name in ("kp", "kd") and (value < 0).any():
            raise ValueError(f"the controller's command {name} must be >= 0 at t = {t:.3f} s: {value}")
        out.append(value)
    return out


def _angles(quaternion: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(roll, pitch, yaw) Z-Y-X angles of (..., 4) (x, y, z, w) quaternions."""
    x, y, z, w = np.moveaxis(quaternion, -1, 0)
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


class _Sim:
    """The compiled model, its data and the addresses of the robot's joints, feet and fall geoms."""

    def __init__(self, robot, lay) -> None:
        self.model = model = mujoco.MjModel.from_xml_string(lay.xml)
        self.data = mujoco.MjData(model)
        self.lay = lay

        def joints(names):
            ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name) for name in names]
            return model.jnt_qposadr[ids].astype(int), model.jnt_dofadr[ids].astype(int)

        self.leg_q, self.leg_v = joints(lay.leg_joints)
        self.arm_q, self.arm_v = joints(lay.arm_joints)
        self.body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, lay.body)
        self.feet = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in lay.foot_geoms])
        self.falls = np.flatnonzero(model.geom_group == FALL_GROUP)
        assert (model.geom_group[self.feet] == FOOT_GROUP).all()
        # the motors become PD actuators, force = ctrl - kp q - kd qd, clamped to the efforts (ctrl
        # carries kp q* + kd qd* + tau): MuJoCo evaluates the law at every step, kd implicitly
        limited = model.actuator_ctrllimited.astype(bool)
        self.effort = np.where(limited, model.actuator_ctrlrange[:, 1], np.inf)
        model.actuator_forcerange[:] = np.where(limited[:, None], model.actuator_ctrlrange, 0.0)
        model.actuator_forcelimited[:] = limited
        model.actuator_ctrllimited[:] = 0
        model.actuator_gaintype[:] = mujoco.mjtGain.mjGAIN_FIXED
        model.actuator_gainprm[:, 0] = 1.0
        model.actuator_biastype[:] = mujoco.mjtBias.mjBIAS_AFFINE
        model.actuator_biasprm[:, :3] = 0.0

    def contacts(self) -> tuple[np.ndarray, bool]:
        """(each foot touches the ground, a fall geom does)."""
        n = self.data.ncon
        if n == 0:
            return np.zeros(len(self.feet), dtype=bool), False
        geoms = self.data.contact.geom[:n]
        return np.isin(self.feet, geoms), bool(np.isin(geoms, self.falls).any())

    def place(self, robot, arm_q) -> float:
        """Stand the robot: the body level with its hips h above the feet, the feet on the ground, the
        arm at ``arm_q``; zero velocity. Returns the body's height above the ground."""
        terrain, radius, h = self.lay.terrain, self.lay.foot_radius, hip_height(robot)
        hips = robot.hip_positions
        feet = np.array(
            [[hips[k, 0] + leg.a[0], hips[k, 1] + leg.hip_offset, 0.0] for k, leg in enumerate(robot.legs)]
        )
        feet[:, 2] = terrain.height_at(feet[:, 0], feet[:, 1]) + radius
        lift = [hips[k, 2] + leg.a[2] for k, leg in enumerate(robot.legs)]
        pose = np.array([0.0, 0.0, float(np.mean(feet[:, 2] - lift)) + h, 0.0, 0.0, 0.0])
        solved = robot.body_ik(pose, feet)
        if (np.asarray(solved.status) != 0).any():
            raise ValueError(
                f"the initial stance (the hips {h:.3f} m above the feet, on this terrain) is out of reach"
            )
        model, data = self.model, self.data
        data.qpos[:] = 0.0
        data.qpos[:3] = pose[:3]
        data.qpos[3:7] = (1.0, 0.0, 0.0, 0.0)
        data.qpos[self.leg_q] = solved.q
        data.qpos[self.arm_q] = arm_q
        data.qvel[:] = 0.0
        mujoco.mj_kinematics(model, data)
        data.qpos[2] -= float(terrain._gap(data.geom_xpos[self.feet], radius).min())
        mujoco.mj_forward(model, data)
        return float(data.qpos[2] - terrain.height_at(0.0, 0.0))

    def arm_gains(self) -> tuple[np.ndarray, np.ndarray]:
        if not len(self.arm_v):
            return np.zeros(0), np.zeros(0)
        inertia = np.zeros(len(self.arm_v))
        unit, column = np.zeros(self.model.nv), np.zeros(self.model.nv)
        for k, dof in enumerate(self.arm_v):  # the mass matrix's diagonal (M e_i)_i, in any MuJoCo 3 or 4
            unit[:] = 0.0
            unit[dof] = 1.0
            mujoco.mj_mulM(self.model, self.data, column, unit)
            inertia[k] = column[dof]
        omega = 2.0 * math.pi * ARM_HZ
        return inertia * omega**2, 2.0 * inertia * omega


def _arm_pose(robot, arm_q) -> np.ndarray:
    n = len(robot.arm_joint_names)
    if arm_q is None:
        limits = np.asarray(robot.arm.limits, dtype=float) if n else np.zeros((0, 2))
        return np.clip(0.0, limits[:, 0], limits[:, 1])
    value = np.asarray(arm_q, dtype=float)
    if value.shape != (n,) or not np.isfinite(value).all():
        raise ValueError(f"arm_q must be {n} finite joint angles (robot.arm_joint_names), got {value.shape}")
    return value


def run(
    robot,
    controller,
    *,
    duration: float = 10.0,
    rate: float = 500,
    velocity: ArrayLike | Callable[[float], ArrayLike] = (0.0, 0.0, 0.0),
    ramp: float = 1.0,
    terrain=None,
    friction: float = 1.0,
    pushes: Sequence = (),
    timestep: float = 0.001,
    seed: int = 0,
    record: bool = True,
    foot_radius: float | None = None,
    arm_q: ArrayLike | None = None,
) -> SimResult:
    """Run ``controller`` on ``robot`` in MuJoCo (:func:`mujoco_model`) for ``duration`` seconds.

    The robot starts standing, its body level with the hips :func:`hip_height` above the feet, the
    feet on the ground (the legs from ``robot.body_ik``), the arm at ``arm_q`` (default: zero,
    clipped into its limits), at rest. At each control tick (``rate`` Hz, which must divide the physics
    rate ``1 / timestep``) the controller is called as ``controller.step(t, state, velocity=v)`` with a
    :class:`spotkin.motion.RobotState` read from the simulator (the body's position, its quaternion
    (x, y, z, w), its linear and angular velocity in world axes, ``q`` and ``qd`` in
    ``robot.leg_joint_names`` order, ``contact`` per foot from the foot spheres' contacts) and the
    command v = (vx, vy, yaw rate): ``velocity``, a (3,) constant or a function of t, ramped linearly
    from 0 over the first ``ramp`` seconds. It returns a :class:`spotkin.motion.JointCommand`, held
    until the next tick; at every physics step the joints get ``kp (q - q_meas) + kd (qd - qd_meas) +
    tau``, clipped to the URDF's efforts. The arm holds its initial pose (a PD inside the runner).

    ``pushes``: (time, (dvx, dvy, dvz)) world velocity kicks to the body. ``terrain``, ``friction``,
    ``timestep``, ``foot_radius``: as :func:`mjcf`. ``seed``: the terrain's when a :class:`Bumps`
    has none (the run is otherwise deterministic). ``record=False`` keeps the metrics only.

    ValueError for a robot that is not a quadruped, a bad argument, or a command of the wrong shape,
    not finite, or with negative gains (naming the field and the time); TypeError for a controller
    without ``step``.
    """
    step = getattr(controller, "step", None)
    if not callable(step):
        raise TypeError(f"controller must have a step(t, state, velocity=...) method, got {controller!r}")
    duration = as_finite(duration, "duration", 0.0, strict=True)
    rate = as_finite(rate, "rate", 0.0, strict=True)
    ramp = as_finite(ramp, "ramp", 0.0)
    timestep = as_finite(timestep, "timestep", 0.0, strict=True)
    if not isinstance(seed, numbers.Integral) or isinstance(seed, bool):
        raise TypeError(f"seed must be an int, got {type(seed).__name__}")
    per_tick = 1.0 / (rate * timestep)
    steps = round(per_tick)
    if steps < 1 or abs(per_tick - steps) > 1e-6 * per_tick:
        raise ValueError(
            f"rate ({rate:g} Hz) must divide the physics rate 1 / timestep ({1 / timestep:g} Hz)"
        )
    command_of = _velocity(velocity)
    kicks = _pushes(pushes)
    lay = layout(robot, terrain, friction, timestep, foot_radius, int(seed))
    sim = _Sim(robot, lay)
    model, data = sim.model, sim.data
    arm_home = _arm_pose(robot, arm_q)
    initial_height = sim.place(robot, arm_home)
    arm_kp, arm_kd = sim.arm_gains()
    n, n_legs = len(sim.leg_q), robot.n_legs
    legs = np.arange(n)
    arms = np.arange(n, n + len(sim.arm_q))
    model.actuator_biasprm[arms, 1] = -arm_kp
    model.actuator_biasprm[arms, 2] = -arm_kd
    effort = sim.effort[legs]

    ticks = max(1, round(duration * rate))
    rec = {
        "t": np.zeros(ticks),
        "position": np.zeros((ticks, 3)),
        "quaternion": np.zeros((ticks, 4)),
        "linear_velocity": np.zeros((ticks, 3)),
        "angular_velocity": np.zeros((ticks, 3)),
        "q": np.zeros((ticks, n)),
        "qd": np.zeros((ticks, n)),
        "tau": np.zeros((ticks, n)),
        "within": np.ones(ticks, dtype=bool),
        "contact": np.zeros((ticks, n_legs), dtype=bool),
        "command": np.zeros((ticks, 3)),
    }
    falls = np.zeros(ticks, dtype=bool)
    wall = 0.0
    next_kick = 0
    for i in range(ticks):
        t = data.time
        R = data.xmat[sim.body].reshape(3, 3)
        contact, fall = sim.contacts()
        w, x, y, z = data.qpos[3:7]
        state = RobotState(
            data.qpos[:3].copy(),
            np.array([x, y, z, w]),
            data.qvel[:3].copy(),
            R @ data.qvel[3:6],
            data.qpos[sim.leg_q],
            data.qvel[sim.leg_v],
            contact,
        )
        scale = 1.0 if ramp == 0.0 else min(t / ramp, 1.0)
        v = scale * command_of(t)
        start = time.perf_counter()
        cmd = step(t, state, velocity=v)
        wall += time.perf_counter() - start
        q_ref, qd_ref, tau_ff, kp, kd = _command(cmd, n, t)
        ctrl = kp * q_ref + kd * qd_ref + tau_ff
        model.actuator_biasprm[legs, 1] = -kp
        model.actuator_biasprm[legs, 2] = -kd
        data.ctrl[legs] = ctrl
        if len(arms):
            data.ctrl[arms] = arm_kp * arm_home + data.qfrc_bias[sim.arm_v]
        rec["t"][i], rec["position"][i], rec["quaternion"][i] = t, state.position, state.quaternion
        rec["linear_velocity"][i], rec["angular_velocity"][i] = state.linear_velocity, state.angular_velocity
        rec["q"][i], rec["qd"][i], rec["contact"][i] = state.q, state.qd, contact
        rec["command"][i] = v
        falls[i] = fall
        within = True
        for s in range(steps):
            while next_kick < len(kicks) and kicks[next_kick][0] <= data.time + 0.5 * timestep:
                data.qvel[:3] += kicks[next_kick][1]
                next_kick += 1
            raw = ctrl - kp * data.qpos[sim.leg_q] - kd * data.qvel[sim.leg_v]
            if s == 0:
                rec["tau"][i] = np.clip(raw, -effort, effort)
            within = within and bool((np.abs(raw) <= effort).all())
            mujoco.mj_step(model, data)
        rec["within"][i] = within
    metrics = _metrics(rec, falls, lay.terrain, initial_height, wall / ticks, duration)
    if not record:
        rec = dict.fromkeys(rec)
    return SimResult(**rec, metrics=metrics)


def _metrics(rec, falls, terrain, initial_height, controller_time, duration) -> Metrics:
    t, position = rec["t"], rec["position"]
    roll, pitch, yaw = _angles(rec["quaternion"])
    window = t >= min(2.0, 0.5 * duration)
    if not window.any():  # a run of a tick or so: its last tick is the window
        window = t >= t[-1]
    c, s = np.cos(yaw), np.sin(yaw)
    vx, vy, _ = rec["linear_velocity"].T
    heading = np.stack([c * vx + s * vy, -s * vx + c * vy, rec["angular_velocity"][:, 2]], axis=-1)
    velocity = tuple(float(v) for v in heading[window].mean(axis=0))
    shift = position[-1, :2] - position[0, :2]
    distance = float(np.hypot(*shift))
    wanted = rec["command"][:, :2].mean(axis=0)
    drift = math.nan
    if np.hypot(*wanted) > 1e-9 and distance > 0.01 * initial_height:  # else too short to tell
        along = np.array(
            [c[0] * wanted[0] - s[0] * wanted[1], s[0] * wanted[0] + c[0] * wanted[1]]
        ) / np.hypot(*wanted)
        drift = abs(along[0] * shift[1] - along[1] * shift[0]) / distance
    heights = position[:, 2] - terrain.height_at(position[:, 0], position[:, 1])
    tilt = FALL_TILT + terrain.slope
    causes = (
        (falls, "the body, a hip, a thigh or the arm touched the ground"),
        (heights < FALL_HEIGHT * initial_height, f"the body below {FALL_HEIGHT:.0%} of its initial height"),
        (np.abs(roll) > tilt, f"|roll| over {tilt:.2f} rad"),
        (np.abs(pitch) > tilt, f"|pitch| over {tilt:.2f} rad"),
    )
    first, cause = None, ""
    for flags, why in causes:
        hit = np.flatnonzero(flags)
        if len(hit) and (first is None or hit[0] < first):
            first, cause = int(hit[0]), why
    return Metrics(
        distance=distance,
        velocity=velocity,
        lateral_drift=float(drift),
        heading_change=float(np.unwrap(yaw)[-1] - yaw[0]),
        lowest_height=float(heights.min()),
        initial_height=initial_height,
        max_roll=float(np.abs(roll).max()),
        max_pitch=float(np.abs(pitch).max()),
        fell=first is not None,
        fall_time=None if first is None else float(t[first]),
        fall_cause=cause,
        torque_within=float(rec["within"].mean()),
        controller_time=controller_time,
    )
