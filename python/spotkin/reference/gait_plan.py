"""The reference gait planner: one robot, one tick at a time, from the formulas of
:mod:`spotkin.reference.gait` (its letters (P), (Q), (S), (F), (B), (M), (W), (C) are cited here).

Slow and obvious on purpose; a compiled planner mirrors it sample by sample. Everything it remembers
between ticks is in :class:`PlannerState`; :func:`advance` moves the state by one tick and
:func:`sample` computes that tick's outputs from it. The gait is given resolved (an object with the
attributes of ``spotkin.ResolvedGait``: ``period``, ``duty``, ``offsets``, ``step_height``, ``height``,
``hip_height``, ``stance``, ``com_shift``, ``shift``, ``sway``, ``capture_gain``, ``accel``,
``yaw_accel``, ``step_reach``, ``moving``).

One tick, from t to t + dt (:func:`advance`)
--------------------------------------------
1. The gait's numbers at t + dt: during a change they blend from the old gait's (their values when
   the change came) to the new one's, p(t) = p_old + (p_new - p_old) b(x), x = (t - t0) / D, b the
   quintic (Q); offsets along the shorter way round (their difference wrapped into [-1/2, 1/2)),
   all shifted by the one c that makes the largest move smallest (c = -(max + min) / 2 of the
   wrapped differences: the same pattern, its clock relabelled; from the pace to the trot each pair
   moves a quarter cycle rather than the hind pair a half); from a gait without swing (duty 1, every
   foot down), the offsets are the new ones at once. The blend lasts
   D = max(T_new, 2 max_i |delta o_i| max(T_old, T_new), |T_old - T_new|), so that every phase keeps
   increasing (d phase / dt >= 1 / T - (15/8) |delta o| / D > 0): no foot goes back along its swing;
   and the clock speeds up or slows down over at least the periods' difference (from the crawl to
   the trot, 1.3 s on Spot rather than the trot's 0.6 s period: a swing under way does not finish
   three times faster than it started).
   At the start the gait blends, over its period, from itself with ``moving`` = 0 (:func:`start`).
2. The clock: theta += dt (1 / T(t) + 1 / T(t + dt)) / 2; phase_i = frac(theta + o_i) (P).
3. The body's planar velocity (body frame: vx, vy, yaw rate) moves towards the target by at most
   accel dt (vx, vy each) and yaw_accel dt: the target is the command times ``moving`` (0 while
   standing) times the step-fit scale s = 1 / max(1, max_i lambda_i), lambda_i =
   sqrt((Dx / room_x)^2 + (Dy / room_y)^2) with D = (d T / 2) (v + omega z x r_i) the half stride of leg i
   (r_i its nominal foot), room = max(eta rho - sway, rho / 10) per axis, rho its step reach
   (``step_reach``), eta = STEP_FIT and sway = w (|s0| + sum_j |(X_j, Y_j)|) the most the crawl's
   sway (C) moves the body: a command the legs cannot follow is slowed to what they reach (reported
   as ``shortened``). The planar pose integrates by the trapezoid rule (yaw first, then the
   position at the mid-yaw).
4. Contacts are latched: a swinging leg lands when its phase wraps (floor(theta + o_i) grows); a
   stance leg lifts off when phase >= d and the swing left, 1 - phase, is at least
   LIFTOFF_FRACTION (1 - d) of a nominal one (else it waits for the next cycle). At lift-off it
   latches its phase phi_lo, the step height and its foothold: (F) at the body pose predicted at
   touch-down, (1 - phase) T ahead, with v_cmd and the yaw rate those predicted in the middle of the
   coming stance (d T long, d and T the gait's predicted at touch-down), bounded by (B) at the
   CHECKS + 1 poses predicted from touch-down to lift-off (evenly in time), each with the sway (C)
   of its phases. The prediction is the plan's own motion under the current command
   (:func:`predict`: steps 1-3 in PREDICTION_STEPS steps between two of these times). The
   foothold's velocity terms use the planned body velocity for both v_cmd and v_meas (the plan is
   open loop: no capture correction).

Closed-loop inputs (a controller sets them on the state before :func:`advance`; None in a plan)
-----------------------------------------------------------------------------------------------
- ``v_measured`` (2,): the measured body velocity (world, horizontal): v_meas of (F), so that the
  capture-point term k (v_meas - v_cmd) sqrt(h / g) works.
- ``ground`` (3,) (c, a, b): the ground under the robot, z = c + a x + b y (world; e.g. a plane
  through the feet's last contacts): the footholds (and the nominal points they are pulled back to)
  lie on it, at the nominal foot height above it, and the predicted body poses of (B) are ``height``
  above it. None: the flat ground z = 0 of a plan.
- ``p_measured`` (2,): the measured body position (world, horizontal, less the crawl's shift): the
  body poses predicted for a foothold (touch-down and the checks of (B)) move by
  (p_measured - (x, y)) + (v_measured - v) (t_touchdown - t), where the body will be if it keeps its
  measured position error and velocity error (v the plan's velocity, in the world); so that after a
  push the feet land under the hips where they will be, and the capture term of (F) adds to that.
- ``ground_offsets`` (n,): leg i's footholds lie ``ground_offsets[i]`` above that plane (a plane of
  the same slope through the leg's own last contact, say: at a step's edge the hind feet keep to
  the lower ground while the front ones are up). None: 0.

One tick's outputs (:func:`sample`)
-----------------------------------
- feet: stance legs at their latched point; swing legs on (S) with s = (phase - phi_lo) /
  (1 - phi_lo), velocity dp/ds * (d phase / dt) / (1 - phi_lo);
- the body: position (x, y) + Rz(psi) delta, delta the crawl's sway (C) with its exact rate;
  height from the gait; R = Rz(psi) Ry(pitch) Rx(roll), given as Euler "XYZ" angles (yaw unwrapped
  to stay continuous); its twist (v, omega) in the world;
- q = robot.body_ik(pose, feet, seed = the previous tick's q); qd_i = J_leg_i^-1 R^T (pdot_i - v -
  omega x (p_i - t)) per leg (the foot's velocity relative to the hip, body axes);
- the margin (M) of ``robot.center_of_mass``; stance forces (W) and tau = G - J^T f.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .body import body_transform
from .gait import (
    G,
    bounded_foothold,
    crawl_shift,
    foothold,
    frac,
    quintic,
    stance_forces,
    support_margin,
    swing,
)

__all__ = ["PlannerState", "advance", "change", "floor_height", "plan", "sample", "start"]

LIFTOFF_FRACTION = 0.75
"""A stance leg lifts off only if at least this fraction of a nominal swing is left (step 4)."""
PREDICTION_STEPS = 16
"""Steps of the body's predicted motion between two checked poses (step 4)."""
CHECKS = 4
"""The stance is checked at CHECKS + 1 poses, touch-down to lift-off (step 4)."""
STEP_FIT = 0.8
"""eta of step 3: the half stride may use this fraction of the step reach."""
KEYS = (
    "period",
    "duty",
    "offsets",
    "step_height",
    "height",
    "hip_height",
    "stance",
    "com_shift",
    "shift",
    "sway",
    "capture_gain",
    "accel",
    "yaw_accel",
    "step_reach",
    "moving",
)
"""The gait's numbers that blend (step 1)."""


def params_of(gait) -> dict[str, np.ndarray]:
    """The blended numbers of a resolved gait, as float64 arrays."""
    return {key: np.array(getattr(gait, key), dtype=np.float64) for key in KEYS}


@dataclass
class PlannerState:
    """Everything the planner remembers between ticks (n legs, in the robot's leg order)."""

    t: float
    theta: float  # the gait clock, cycles
    clock_rate: float  # 1 / T at t
    x: float  # the planar pose (world), without the crawl shift
    y: float
    psi: float
    v: np.ndarray  # (2,) planar velocity, body frame (heading axes)
    w: float  # yaw rate
    command: np.ndarray  # (3,) vx, vy, yaw rate
    attitude: tuple[float, float]  # roll, pitch
    old: dict  # the blend: from old to new, started at t0, lasting duration (0: no blend)
    new: dict
    t0: float
    duration: float
    contact: np.ndarray  # (n,) bool, latched
    cycles: np.ndarray  # (n,) floor(theta + o_i) at t
    lift_phase: np.ndarray  # (n,) phi_lo of the current swing
    lift_height: np.ndarray  # (n,) its step height
    p_stance: np.ndarray  # (n, 3) the stance foot, or the lift-off point while swinging
    p_touchdown: np.ndarray  # (n, 3) the latched foothold of the current swing
    step_shortened: np.ndarray  # (n,) bool: the current swing's foothold was shortened (B)
    speed_scale: float  # s of step 3 at t
    q: np.ndarray | None  # the last tick's q, the next IK's seed
    v_measured: np.ndarray | None = None  # (2,) closed loop: the measured velocity (world) of (F)
    ground: np.ndarray | None = None  # (3,) closed loop: the ground plane z = c + a x + b y
    ground_offsets: np.ndarray | None = None  # (n,) closed loop: each leg's footholds above that plane
    p_measured: np.ndarray | None = None  # (2,) closed loop: the measured position (world, less the shift)


def floor_height(state: PlannerState, x: float, y: float) -> float:
    """The ground's height under the world point (x, y): ``state.ground``'s plane, or 0 (a plan)."""
    g = state.ground
    return 0.0 if g is None else float(g[0] + g[1] * x + g[2] * y)


def blend_duration(old: dict, new: dict) -> float:
    """D of step 1."""
    delta = np.abs((new["offsets"] - old["offsets"] + 0.5) % 1.0 - 0.5)
    worst = max(float(old["period"]), float(new["period"]))
    return max(
        float(new["period"]),
        2.0 * float(delta.max()) * worst,
        abs(float(old["period"]) - float(new["period"])),
    )


def blended(state: PlannerState, t: float) -> tuple[dict, dict]:
    """The gait's numbers at t and their time derivatives (step 1)."""
    if state.duration <= 0.0 or t >= state.t0 + state.duration:
        return state.new, {key: np.zeros_like(value) for key, value in state.new.items()}
    b, db, _ = quintic((t - state.t0) / state.duration)
    values, rates = {}, {}
    for key in KEYS:
        old, new = state.old[key], state.new[key]
        delta = new - old  # the offsets' already the shorter way round (change)
        values[key] = old + delta * b
        rates[key] = delta * db / state.duration
    return values, rates


def change(state: PlannerState, gait=None, command=None) -> None:
    """A new gait (blended from now, step 1) and / or a new command (ramped, step 3), at ``state.t``."""
    if command is not None:
        state.command = np.array(command, dtype=np.float64)
    if gait is None:
        return
    now, _ = blended(state, state.t)
    new = params_of(gait)
    old = {key: np.array(value) for key, value in now.items()}
    # the offsets move the shorter way round, and end there (not at the new gait's values mod 1, so
    # that floor(theta + o_i), whose growth is a touch-down, never jumps); all of them by the same
    # c more (the same gait, its clock relabelled), the c that makes the largest move smallest: from
    # the pace to the trot the front pair moves a quarter cycle and the hind a quarter back, rather
    # than the hind pair half a cycle (its legs' clocks all but stopped half-way through the blend)
    delta = (new["offsets"] - old["offsets"] + 0.5) % 1.0 - 0.5
    new["offsets"] = old["offsets"] + (delta - (delta.max() + delta.min()) / 2.0)
    if float(old["duty"]) >= 1.0 and state.contact.all():  # no swing: the new offsets at once
        old["offsets"] = new["offsets"].copy()
    state.old, state.new, state.t0 = old, new, state.t
    state.duration = blend_duration(old, new)


def _rotation(psi: float, roll: float, pitch: float) -> np.ndarray:
    """Rz(psi) Ry(pitch) Rx(roll)."""
    cz, sz, cy, sy, cx, sx = (
        math.cos(psi),
        math.sin(psi),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(roll),
        math.sin(roll),
    )
    Rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    Ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return Rz @ Ry @ Rx


def body_pose(x: float, y: float, z: float, psi: float, attitude) -> np.ndarray:
    """[x, y, z, a, b, c] with R = Rx(a) Ry(b) Rz(c) = Rz(psi) Ry(pitch) Rx(roll), c unwrapped near psi."""
    R = _rotation(psi, attitude[0], attitude[1])
    b = math.asin(min(max(R[0, 2], -1.0), 1.0))
    a = math.atan2(-R[1, 2], R[2, 2])
    c = math.atan2(-R[0, 1], R[0, 0])
    c += 2.0 * math.pi * round((psi - c) / (2.0 * math.pi))
    return np.array([x, y, z, a, b, c])


def ramp(planar, target, accel: float, yaw_accel: float, dt: float):
    """Step 3's motion over dt: planar = (x, y, psi, (vx, vy), yaw rate) -> the same at t + dt."""
    x, y, psi, v0, w0 = planar
    step, yaw_step = accel * dt, yaw_accel * dt
    v1 = np.array([v0[k] + min(max(target[k] - v0[k], -step), step) for k in (0, 1)])
    w1 = w0 + min(max(target[2] - w0, -yaw_step), yaw_step)
    psi1 = psi + dt * (w0 + w1) / 2.0
    mid = (psi + psi1) / 2.0
    mean = (v0 + v1) / 2.0
    x += dt * (math.cos(mid) * mean[0] - math.sin(mid) * mean[1])
    y += dt * (math.sin(mid) * mean[0] + math.cos(mid) * mean[1])
    return x, y, psi1, v1, w1


def predict(state: PlannerState, horizons) -> list:
    """The plan's own motion ahead, for each of the increasing ``horizons`` (s): (planar, theta, P), the
    planar motion and the clock there and the gait's numbers. Steps 1-3 (without the legs), in
    PREDICTION_STEPS equal steps between successive horizons: for an unchanged command the plan's."""
    planar = (state.x, state.y, state.psi, state.v, state.w)
    theta, rate, t, out = state.theta, state.clock_rate, state.t, []
    for horizon in horizons:
        dt = (state.t + horizon - t) / PREDICTION_STEPS
        for _ in range(PREDICTION_STEPS):
            t += dt
            P, _ = blended(state, t)
            rate1 = 1.0 / float(P["period"])
            theta += dt * (rate + rate1) / 2.0
            rate = rate1
            planar = ramp(planar, _target(state, P), float(P["accel"]), float(P["yaw_accel"]), dt)
        out.append((planar, theta, blended(state, t)[0]))
    return out


def _target(state: PlannerState, P: dict) -> np.ndarray:
    """Step 3's target: the command times ``moving`` times the step-fit scale."""
    target = state.command * float(P["moving"])
    return target * speed_scale(P, target)


def start(robot, gait, command=(0.0, 0.0, 0.0), attitude=(0.0, 0.0)) -> PlannerState:
    """The planner at t = 0: standing on the gait's nominal feet, at rest, every leg down, clock 0; the
    gait's ``moving`` blends in from 0 over its first period (step 1), so that the body gathers speed
    while every leg takes its first step (a foot left at its start would fall a stride behind)."""
    params = params_of(gait)
    n = robot.n_legs
    stance = params["stance"].copy()
    resting = dict(params, moving=np.zeros_like(params["moving"]))  # the start: the speed blends in
    return PlannerState(
        t=0.0,
        theta=0.0,
        clock_rate=1.0 / float(params["period"]),
        x=0.0,
        y=0.0,
        psi=0.0,
        v=np.zeros(2),
        w=0.0,
        command=np.array(command, dtype=np.float64),
        attitude=(float(attitude[0]), float(attitude[1])),
        old=resting,
        new=params,
        t0=0.0,
        duration=float(params["period"]),
        contact=np.ones(n, dtype=bool),
        cycles=np.array([math.floor(o) for o in params["offsets"]], dtype=np.int64),
        lift_phase=np.zeros(n),
        lift_height=np.zeros(n),
        p_stance=stance,
        p_touchdown=stance.copy(),
        step_shortened=np.zeros(n, dtype=bool),
        speed_scale=1.0,
        q=None,
    )


def speed_scale(P: dict, target) -> float:
    """s of step 3 for a target (vx, vy, yaw rate)."""
    half_stance = float(P["duty"]) * float(P["period"]) / 2.0
    # the body's sway (C) takes its share of the reach: |s0| + sum_i |(X_i, Y_i)| per axis
    sway = float(P["com_shift"]) * (np.abs(P["shift"]) + np.abs(P["sway"]).sum(axis=0))
    worst = 1.0
    for r, reach in zip(P["stance"][:, :2], P["step_reach"]):
        room = [max(STEP_FIT * reach[k] - sway[k], 0.1 * reach[k]) for k in (0, 1)]
        dx = half_stance * (target[0] - target[2] * r[1])
        dy = half_stance * (target[1] + target[2] * r[0])
        a, b = dx / room[0], dy / room[1]
        worst = max(worst, math.sqrt(a * a + b * b))
    return 1.0 / worst


def _leg_columns(robot) -> list[list[int]]:
    names = list(robot.leg_joint_names)
    return [[names.index(name) for name in leg.joint_names] for leg in robot.legs]


def _plan_foothold(robot, state: PlannerState, P: dict, i: int, phase_: float) -> tuple[np.ndarray, bool]:
    """Step 4's foothold of leg i lifting off now."""
    to_touchdown = (1.0 - phase_) * float(P["period"])
    touchdown = predict(state, [to_touchdown])[0]
    t_stance = float(touchdown[2]["duty"]) * float(touchdown[2]["period"])  # the gait's at touch-down
    ahead = [to_touchdown + t_stance * k / CHECKS for k in range(CHECKS + 1)]
    future = predict(state, ahead)
    offset = np.zeros(2)  # closed loop: where the body will be, from its measured position and velocity
    if state.p_measured is not None:
        offset = np.asarray(state.p_measured, dtype=np.float64) - (state.x, state.y)
        if state.v_measured is not None:
            c0, s0 = math.cos(state.psi), math.sin(state.psi)
            now = (c0 * state.v[0] - s0 * state.v[1], s0 * state.v[0] + c0 * state.v[1])
            offset = offset + (np.asarray(state.v_measured, dtype=np.float64) - now) * to_touchdown
    (x, y, psi, _, _), _, _ = future[0]
    x, y = x + offset[0], y + offset[1]
    _, v_mid, w_mid = future[CHECKS // 2][0][2:]
    c, s = math.cos(psi), math.sin(psi)
    nominal = P["stance"][i]
    r = (c * nominal[0] - s * nominal[1], s * nominal[0] + c * nominal[1])
    p_nominal = np.array([x + r[0], y + r[1], nominal[2] + floor_height(state, x + r[0], y + r[1])])
    velocity = (c * v_mid[0] - s * v_mid[1], s * v_mid[0] + c * v_mid[1])
    measured = velocity if state.v_measured is None else state.v_measured
    p = foothold(
        p_nominal, r, velocity, measured, w_mid, t_stance, float(P["hip_height"]), float(P["capture_gain"])
    )
    p[2] = nominal[2] + floor_height(state, p[0], p[1])
    if state.ground_offsets is not None:
        p[2] += float(state.ground_offsets[i])
        p_nominal[2] += float(state.ground_offsets[i])
    poses = []
    for (px, py, ppsi, _, _), theta, Pf in future:
        phases = [frac(theta + o) for o in Pf["offsets"]]
        rates = [1.0 / float(Pf["period"])] * len(phases)
        zero = {key: np.zeros_like(value) for key, value in Pf.items()}
        delta, _ = _crawl_shift(Pf, zero, phases, rates)
        cp, sp = math.cos(ppsi), math.sin(ppsi)
        px, py = (
            px + cp * delta[0] - sp * delta[1] + offset[0],
            py + sp * delta[0] + cp * delta[1] + offset[1],
        )
        z = float(Pf["height"]) + floor_height(state, px, py)
        poses.append(body_transform(body_pose(px, py, z, ppsi, state.attitude)))
    seed = None if state.q is None else state.q[_leg_columns(robot)[i]]
    return bounded_foothold(robot.legs[i], robot.hip_positions[i], p, p_nominal, poses, seed)


def advance(robot, state: PlannerState, dt: float) -> PlannerState:
    """Steps 1-4: the state at t + dt (in place; returned)."""
    t1 = state.t + dt
    P, _ = blended(state, t1)
    rate1 = 1.0 / float(P["period"])
    state.theta += dt * (state.clock_rate + rate1) / 2.0
    state.clock_rate = rate1
    target = _target(state, P)
    state.speed_scale = speed_scale(P, state.command * float(P["moving"]))
    planar = (state.x, state.y, state.psi, state.v, state.w)
    state.x, state.y, state.psi, state.v, state.w = ramp(
        planar, target, float(P["accel"]), float(P["yaw_accel"]), dt
    )
    state.t = t1
    duty = float(P["duty"])
    for i, offset in enumerate(P["offsets"]):
        cycles = math.floor(state.theta + offset)
        phase_ = state.theta + offset - cycles
        if not state.contact[i]:
            if cycles > state.cycles[i]:  # the phase wrapped: touch-down
                state.contact[i] = True
                state.p_stance[i] = state.p_touchdown[i]
                state.step_shortened[i] = False
        elif phase_ >= duty and 1.0 - phase_ >= LIFTOFF_FRACTION * (1.0 - duty):
            state.contact[i] = False
            state.lift_phase[i] = phase_
            state.lift_height[i] = float(P["step_height"])
            state.p_touchdown[i], state.step_shortened[i] = _plan_foothold(robot, state, P, i, phase_)
        state.cycles[i] = cycles
    return state


def _crawl_shift(P: dict, Pd: dict, phases, phase_rates):
    """delta and d delta / dt (2,), body frame: (C)."""
    weight, weight_rate = float(P["com_shift"]), float(Pd["com_shift"])
    if weight == 0.0 and weight_rate == 0.0:
        return np.zeros(2), np.zeros(2)
    value, rate = crawl_shift(phases, phase_rates, float(P["duty"]), float(Pd["duty"]), P["sway"], Pd["sway"])
    value, rate = value + P["shift"], rate + Pd["shift"]
    return weight * value, weight_rate * value + weight * rate


def sample(robot, state: PlannerState) -> dict:
    """The outputs at ``state.t``; writes the solved q into ``state.q`` (the next tick's seed)."""
    P, Pd = blended(state, state.t)
    n = robot.n_legs
    phases, phase_rates = np.empty(n), np.empty(n)
    feet, feet_rate = np.empty((n, 3)), np.zeros((n, 3))
    for i, offset in enumerate(P["offsets"]):
        phases[i] = frac(state.theta + offset)
        phase_rates[i] = state.clock_rate + float(Pd["offsets"][i])
        if state.contact[i]:
            feet[i] = state.p_stance[i]
            continue
        lift = state.lift_phase[i]
        s = (phases[i] - lift) / (1.0 - lift)
        feet[i], dp_ds, _ = swing(state.p_stance[i], state.p_touchdown[i], s, state.lift_height[i])
        feet_rate[i] = dp_ds * phase_rates[i] / (1.0 - lift)
    delta, delta_rate = _crawl_shift(P, Pd, phases, phase_rates)
    c, s = math.cos(state.psi), math.sin(state.psi)
    shift = np.array([c * delta[0] - s * delta[1], s * delta[0] + c * delta[1]])
    x, y = state.x + shift[0], state.y + shift[1]
    pose = body_pose(x, y, float(P["height"]) + floor_height(state, x, y), state.psi, state.attitude)
    T = body_transform(pose)
    R, origin = T[:3, :3], T[:3, 3]
    planar = state.v + delta_rate
    linear = np.array(
        [
            c * planar[0] - s * planar[1] - state.w * shift[1],
            s * planar[0] + c * planar[1] + state.w * shift[0],
            float(Pd["height"]),
        ]
    )
    angular = np.array([0.0, 0.0, state.w])
    q, status = robot.body_ik(pose, feet, seed=state.q)
    # the next seed: this q, the last finite one for a leg without an answer (NaN: JOINT_LIMIT, ...)
    state.q = q.copy() if state.q is None else np.where(np.isfinite(q), q, state.q)
    columns = _leg_columns(robot)
    qd = np.empty(3 * n)
    jacobians = []
    for i, leg in enumerate(robot.legs):
        J = leg.jacobian(q[columns[i]])
        jacobians.append(J)
        relative = R.T @ (feet_rate[i] - linear - np.cross(angular, feet[i] - origin))
        try:  # NaN for a leg without an answer (NaN q) or a singular one
            qd[columns[i]] = np.linalg.solve(J, relative) if np.isfinite(J).all() else np.nan
        except np.linalg.LinAlgError:
            qd[columns[i]] = np.nan
    com = robot.center_of_mass(pose, q)
    down = [i for i in range(n) if state.contact[i]]
    margin = support_margin([feet[i, :2] for i in down], com[:2]) if np.isfinite(com).all() else math.nan
    gravity = np.array([0.0, 0.0, -G])
    forces, residual = stance_forces(feet, state.contact, com, robot.mass, gravity)
    if not np.isfinite(com).all():  # a leg without an answer: the centre of mass, and so the wrench, unknown
        residual = np.full(6, np.nan)
    weight = robot.floating_base.gravity(robot.floating_q(pose, q), gravity)[6 : 6 + 3 * n]
    tau = np.empty(3 * n)
    for i in range(n):
        tau[columns[i]] = weight[columns[i]] - (R @ jacobians[i]).T @ forces[i]
    return {
        "t": state.t,
        "body_pose": pose,
        "feet": feet,
        "feet_rate": feet_rate,
        "contact": state.contact.copy(),
        "q": q,
        "qd": qd,
        "tau": tau,
        "status": int(np.max(status)),
        "margin": margin,
        "shortened": bool(state.speed_scale < 1.0 or (state.step_shortened & ~state.contact).any()),
        "residual": residual,
        "forces": forces,
        "com": com,
    }


OUTPUTS = ("t", "body_pose", "feet", "contact", "q", "qd", "tau", "status", "margin", "shortened", "residual")


def plan(robot, gait, velocity, duration: float, rate: float, changes=(), attitude=(0.0, 0.0)) -> dict:
    """One command's plan: the outputs of every tick t_k = k / rate, k = 0 .. round(duration rate), as
    arrays (``OUTPUTS``). ``changes``: (time, gait or None, velocity or None) applied at the first tick
    at or after that time (after its :func:`advance`, before its :func:`sample`)."""
    state = start(robot, gait, velocity, attitude)
    ticks = round(duration * rate) + 1
    pending = sorted(changes, key=lambda item: item[0])
    rows = []
    for k in range(ticks):
        if k:
            advance(robot, state, k / rate - state.t)  # the tick times without drift
        while pending and pending[0][0] <= state.t + 1e-12:
            _, new_gait, new_velocity = pending.pop(0)
            change(state, new_gait, new_velocity)
        rows.append(sample(robot, state))
    out = {key: np.array([row[key] for row in rows]) for key in OUTPUTS}
    out["status"] = out["status"].astype(np.int8)
    return out
