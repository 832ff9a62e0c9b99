"""The reference closed-loop gait controller: one robot, one control tick at a time, in plain NumPy and
``math`` (slow and obvious on purpose; the compiled controller behind :class:`spotkin.GaitController`
mirrors it tick by tick, and the tests compare them). It imports nothing of the package: the robot is
passed in and only its public methods are called.

It runs the reference planner's state machine (:mod:`spotkin.reference.gait_plan`: the gait clock,
the latched contacts, the footholds) one tick at a time and closes the loop on the measured state
(:class:`spotkin.motion.RobotState`); each tick gives a :class:`spotkin.motion.JointCommand`
(``tau_joint = kp (q - q_meas) + kd (qd - qd_meas) + tau``). What it does, tick by tick:

1. **Measure.** The body's pose and twist; the feet by forward kinematics (``robot.body_fk``); the
   ground: a plane through the feet's last contact points (less the nominal foot height), low-passed
   over ``GROUND_TIME`` of a period.
2. **Plan.** The planner advances by the tick: gait clock, ramped velocity (the command, with the
   gait's acceleration limits), lift-offs and touch-downs, with its closed-loop inputs set
   (``PlannerState.v_measured``, ``p_measured``, ``ground``, ``ground_offsets``): the footholds (F)
   get the measured velocity in the capture-point term k (v_meas - v_cmd) sqrt(h / g); the body pose
   predicted for a touch-down moves by the measured position and velocity errors (the planner's own
   sway taken out); footholds lie on the ground plane's slope through each leg's own last contact;
   every one is bounded by the leg's workspace (B). With measured contacts, a swing foot that
   touches the ground in the second half of its swing lands there; a foot that finds no ground at
   its planned touch-down keeps reaching down (at the swing's mean descent speed, at most
   ``REACH_DOWN`` h), carries no load until it touches, and holds the gait clock meanwhile (no other
   leg lifts off). A stance foot carries load from its first touch to its lift-off. The first
   period is a settling: the clock held, every foot down, while the centre-of-mass shift blends in.
3. **Re-anchor.** The planner's planar pose is the body's reference; it is kept within
   ``ANCHOR`` h plus the most the crawl's sway moves the body (position; the sway's lead is the
   reference's to keep) and ``YAW_ANCHOR`` (yaw) of the measured body, so that drift, pushes and
   slopes never accumulate an error the legs would try to undo (after a push, the stance legs' PD
   pulls back by no more than that: their torques stay within the motors' limits). Stance feet are
   held where they are measured.
4. **Body reference.** Position: the anchored planar pose plus the centre-of-mass shift s0 (in every
   gait) and the sway (C): the crawl's static one, and in the other gaits the linear inverted
   pendulum's periodic orbit (:func:`spotkin.reference.gait.pendulum_sway`; it is not zero only when
   the sides' feet alternate, as in the pace, whose body must then swing over the side that is
   down, else it rolls off the line of its two feet); height: the gait's above the ground plane;
   attitude: the commanded roll and pitch, the pitch plus ``TERRAIN_FOLLOW`` of the ground's slope
   along the heading; yaw: the planner's.
5. **Joints.** ``robot.body_ik`` at the reference pose for the loaded legs (so that their PD pushes
   the body towards it) and at the measured pose for the others (so that a swing foot reaches its
   world foothold whatever the body's error), seeded with the previous tick. Joint velocities from
   the feet's and the body's velocities: qd_l = (R J_l)^-1 (pdot_l - v - w x (p_l - t)), with the
   reference twist for loaded legs and the measured one for the others.
6. **Feedforward torques.** tau = G - (R J_l)^T f_l per leg (G the generalised gravity at the
   measured configuration); a swing leg adds A_l qdd (its block of the mass matrix at the nominal
   stance, qdd from the swing curve's acceleration). The stance forces carry the weight plus a
   virtual body wrench, by the torque-weighted least squares (T)
   (:func:`spotkin.reference.gait.torque_weighted_forces`) over the loaded feet, then kept in a
   friction pyramid of ``FRICTION`` with f_z >= 0. The wrench is a critically damped PD on the body
   pose about the reference: F = m (wb^2 e_p + 2 wb e_v + a_ref), M = I (wb^2 e_R + 2 wb e_w), e_R
   the rotation vector of R_ref R^T, a_ref the reference's acceleration (low-passed), I the body's
   composite rotational inertia plus ``TIP_INERTIA`` m h^2 about the horizontal axes, wb =
   ``BODY_BANDWIDTH`` sqrt(g / h); F's horizontal part is at most ``HORIZONTAL_WRENCH`` m g (after a
   hard kick the velocity term alone asks several times the weight sideways, which feet under the
   body cannot give without tipping it: the footholds' capture-point term recovers it by stepping).
   The feedforward is clipped to the joints' effort limits
   (:attr:`GaitController.last` says which were).

Gains, from the robot's own inertias (no per-robot table): I_j, the diagonal of the floating base's
mass matrix ``A(q)`` at the nominal stance for joint j (the inertia of the leg below the joint about
its axis), sets

    kp_j = I_j w^2,   kd_j = 2 zeta I_j w,   w = kappa sqrt(g / h),   zeta = ``DAMPING_RATIO`` (1),

with kappa = ``SWING_BANDWIDTH`` (16) for a swinging leg and ``STANCE_BANDWIDTH`` (6) for a loaded
one: each joint's natural frequency on its own leg's inertia is a fixed multiple of sqrt(g / h),
which the gaits' period T = c sqrt(h / g) also scales with (Froude similarity: robots of any size get
the same gains relative to their gait).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from . import gait_plan
from .gait import G, frac, pendulum_sway, support_margin, sway_coefficients, swing, torque_weighted_forces

__all__ = ["Memory", "ReferenceController", "effort_limit", "gains"]

SWING_BANDWIDTH = 16.0
"""kappa of a swinging leg's joints: w = kappa sqrt(g / h)."""
STANCE_BANDWIDTH = 6.0
"""kappa of a stance leg's joints."""
DAMPING_RATIO = 1.0
"""zeta of the joints' PD (kd = 2 zeta I w)."""
BODY_BANDWIDTH = 1.5
"""The virtual body wrench's natural frequency, in sqrt(g / h)."""
TIP_INERTIA = 0.3
"""The virtual moment's roll and pitch inertia adds TIP_INERTIA m h^2 to the body's own."""
ANCHOR = 0.03
"""The body reference stays within this fraction of h (plus the crawl's sway) of the measured body,
horizontally."""
YAW_ANCHOR = 0.1
"""... and within this many radians of its yaw."""
TERRAIN_FOLLOW = 1.0
"""The body's pitch follows this fraction of the ground plane's slope along the heading."""
TERRAIN_ROLL = 0.0
"""... and its roll this fraction of the slope across it (none: a plane through four feet, two on a
step and two below, tilts sideways too)."""
REACH_DOWN = 0.3
"""A foot that finds no ground at its touch-down reaches at most this fraction of h further down."""
FRICTION = 0.6
"""The feedforward's contact forces keep |f_xy| <= FRICTION f_z (a friction pyramid, on the safe side)."""
ACCEL_TIME = 0.02
"""The body reference's acceleration (fed forward, m a) low-passes over this fraction of the period."""
MAX_GAP = 0.1
"""A longer time between two ticks (s) moves the gait by this much only."""
HORIZONTAL_WRENCH = 0.3
"""The virtual body force's horizontal part is at most this fraction of the weight."""
GROUND_TIME = 0.25
"""The ground plane low-passes over this fraction of the gait's period."""


def gains(inertia: np.ndarray, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """kp = I w^2, kd = 2 zeta I w."""
    return inertia * omega**2, 2.0 * DAMPING_RATIO * inertia * omega


def _rotation(quaternion) -> np.ndarray:
    x, y, z, w = (float(v) for v in quaternion)
    norm = x * x + y * y + z * z + w * w
    s = 2.0 / norm if norm > 0 else 0.0
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)],
            [s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)],
            [s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)],
        ]
    )


def _rotation_vector(R: np.ndarray) -> np.ndarray:
    """The rotation vector (axis times angle) of R."""
    c = min(max((np.trace(R) - 1.0) / 2.0, -1.0), 1.0)
    angle = math.acos(c)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = math.sin(angle)
    return 0.5 * axis if s < 1e-9 else axis * (angle / (2.0 * s))


class Memory:
    """One robot's controller state between ticks."""

    def __init__(self, n: int) -> None:
        self.plan: gait_plan.PlannerState | None = None
        self.reaching = np.zeros(n, dtype=bool)  # planned stance, no ground found yet
        self.landed = np.ones(n, dtype=bool)  # touched since its touch-down
        self.shift = np.zeros(2)  # the planner's shift (C) at the last tick, world
        self.shift_rate = np.zeros(2)  # and its rate
        self.depth = np.zeros(n)  # how far each reaching foot went below its foothold
        self.ground_points = np.zeros((n, 3))  # the feet's last contacts
        self.ground = np.zeros(3)  # (c, a, b), low-passed
        self.q = None  # the last targets (the next IK's seed)
        self.v_ref = None  # the last reference velocity (world)
        self.a_ref = np.zeros(3)  # its rate, low-passed
        self.gait = -1  # the index of its gait in the controller's table
        self.last = None
        self.t = -math.inf  # the last tick's time
        self.settle = -math.inf  # the gait clock starts then


class ReferenceController:
    """The constants of a controller for one robot (computed once from its inertias: see the module's
    docstring) and :meth:`tick`. ``robot``: a quadruped; ``gait``: its resolved gait (the gains'
    nominal stance and h); ``attitude``: the commanded (roll, pitch)."""

    def __init__(self, robot, gait, attitude=(0.0, 0.0)) -> None:
        self.robot = robot
        self.attitude = (float(attitude[0]), float(attitude[1]))
        n = robot.n_legs
        names = list(robot.leg_joint_names)
        self._columns = [[names.index(j) for j in leg.joint_names] for leg in robot.legs]
        self.h = gait.hip_height
        pose = np.array([0.0, 0.0, gait.height, 0.0, 0.0, 0.0])
        q0 = robot.body_ik(pose, gait.stance).q
        A = robot.floating_base.mass_matrix(robot.floating_q(pose, q0))
        inertia = np.diag(A)[6 : 6 + 3 * n].copy()
        # each leg's own block of A at the nominal stance: the swing's inertial feedforward
        self.leg_inertia = [A[6:, 6:][np.ix_(cols, cols)] for cols in self._columns]
        scale = math.sqrt(G / self.h)
        self.kp, self.kd = gains(inertia, SWING_BANDWIDTH * scale)
        self.stance_kp, self.stance_kd = gains(inertia, STANCE_BANDWIDTH * scale)
        # the body's rotational inertia for the virtual moment: its own (the composite, about the body
        # origin, body axes) plus m h^2 about the horizontal axes (the body tips about its feet)
        self.body_inertia = A[3:6, 3:6] + np.diag([1.0, 1.0, 0.0]) * robot.mass * self.h**2 * TIP_INERTIA
        self.body_omega = BODY_BANDWIDTH * scale
        self.effort = np.array(
            [effort_limit(robot, name) for name in robot.leg_joint_names], dtype=np.float64
        )
        self._leg_inertia = self.leg_inertia

    @staticmethod
    def resolved(gait):
        """A resolved gait with its centre-of-mass shift s0 applied in every gait (a weight of 1), and
        where the gait has no sway of its own (all but the crawl) the pendulum's: the lateral sway
        (C) of amplitude :func:`spotkin.reference.gait.pendulum_sway` (zero but in the pace)."""
        if gait.com_shift == 0.0:
            kappa = pendulum_sway(gait.duty, gait.period, gait.hip_height)
            sway, _ = sway_coefficients(
                gait.stance[:, :2], gait.roles, gait.offsets, np.zeros(2), (0.0, kappa)
            )
            return dataclasses.replace(gait, com_shift=1.0, sway=sway)
        return gait

    def start(self, memory: Memory, t, position, yaw, feet, gait) -> None:
        plan = gait_plan.start(self.robot, gait)
        plan.t, plan.t0 = t, t
        plan.x, plan.y, plan.psi = float(position[0]), float(position[1]), yaw
        plan.p_stance = feet.copy()
        plan.p_touchdown = feet.copy()
        plan.old = dict(plan.old, com_shift=np.zeros_like(plan.old["com_shift"]))  # the shift blends in
        memory.plan, memory.t = plan, t
        memory.settle = t + plan.duration  # every foot down while the body moves to its shifted place
        memory.ground_points = feet.copy()
        memory.ground = self.plane(feet, np.asarray(gait.stance)[:, 2])

    @staticmethod
    def plane(points: np.ndarray, foot_z: np.ndarray) -> np.ndarray:
        """(c, a, b) of the least-squares plane z = c + a x + b y through the ground under the foot
        ``points`` (each ``foot_z`` above it)."""
        ground = points[:, 2] - foot_z
        X = np.column_stack([np.ones(len(points)), points[:, 0], points[:, 1]])
        return np.linalg.lstsq(X, ground, rcond=None)[0]

    def tick(
        self, memory, gaits, start_gait, new_gait, t, position, quaternion, v, w, q, qd, contact, command
    ):
        """One tick of one robot: the joint command (q, qd, tau, contact, kp, kd), and ``memory.last`` the
        tick's details. ``gaits``: the resolved gaits (their centre-of-mass shift applied, see
        :meth:`resolved`); ``start_gait`` the index of a robot's first gait; ``new_gait`` a change
        (an index, or -1)."""
        start_time = time.perf_counter()
        robot, legs = self.robot, self.robot.n_legs
        R = _rotation(quaternion)
        yaw = math.atan2(R[1, 0], R[0, 0])
        T_meas = np.eye(4)
        T_meas[:3, :3], T_meas[:3, 3] = R, position
        feet_meas = robot.body_fk(T_meas, q)
        if memory.plan is None:
            memory.gait = new_gait if new_gait >= 0 else start_gait
            self.start(memory, t, position, yaw, feet_meas, gaits[memory.gait])
        plan = memory.plan
        if new_gait >= 0 and new_gait != memory.gait:
            memory.gait = new_gait
            gait_plan.change(plan, gaits[new_gait])
        dt = t - memory.t
        if dt < -1e-9:
            raise ValueError(f"t went backwards: {t} after {memory.t}: call reset() first")
        memory.t = t
        dt = min(max(dt, 0.0), MAX_GAP)  # a gap between ticks is walked as MAX_GAP at most
        plan.command = np.array(command, dtype=np.float64)
        # the measured body less the planner's own shift (C) and its rate: the errors the footholds correct
        plan.v_measured = v[:2] - memory.shift_rate
        plan.p_measured = position[:2] - memory.shift
        plan.ground = memory.ground
        before = plan.contact.copy()
        settling = min(dt, max(0.0, memory.settle - plan.t))  # the start: the clock held
        if (memory.reaching & (memory.depth < REACH_DOWN * self.h)).any():
            settling = dt  # a foot still reaching for the ground: no other leg lifts off meanwhile
        plan.t += settling
        if dt - settling > 0.0:
            gait_plan.advance(robot, plan, dt - settling)
        P, Pd = gait_plan.blended(plan, plan.t)
        period, duty = float(P["period"]), float(P["duty"])
        nominal_z = np.asarray(P["stance"])[:, 2]
        # --- contacts: touch-downs (planned, early, late) and the stance feet
        phases = np.array([frac(plan.theta + o) for o in P["offsets"]])
        phase_rates = plan.clock_rate + np.asarray(Pd["offsets"], dtype=np.float64)
        swing_time = max((1.0 - duty) * period, 1e-3)
        descent = 2.0 * (float(P["step_height"]) + 1e-3 * self.h) / swing_time
        touched = np.ones(legs, dtype=bool) if contact is None else np.asarray(contact, dtype=bool)
        for i in range(legs):
            if plan.contact[i] and not before[i]:  # the planned touch-down
                memory.reaching[i], memory.depth[i] = not touched[i], 0.0
                if touched[i]:
                    plan.p_stance[i] = feet_meas[i]
            elif not plan.contact[i]:
                lift = plan.lift_phase[i]
                progress = (phases[i] - lift) / (1.0 - lift)
                if contact is not None and touched[i] and 0.5 < progress < 1.0:  # early: lands here
                    plan.contact[i], memory.reaching[i] = True, False
                    plan.p_stance[i] = feet_meas[i]
            elif memory.reaching[i]:
                if touched[i]:
                    memory.reaching[i] = False
                    plan.p_stance[i] = feet_meas[i]
                elif memory.depth[i] < REACH_DOWN * self.h:
                    step = min(descent * max(dt, 0.0), REACH_DOWN * self.h - memory.depth[i])
                    memory.depth[i] += step
                    plan.p_stance[i, 2] -= step
            elif touched[i]:
                plan.p_stance[i] = feet_meas[i]  # held where it is measured
            if plan.contact[i] and touched[i] and not memory.reaching[i]:
                memory.ground_points[i] = feet_meas[i]
                memory.landed[i] = True
            memory.landed[i] &= bool(plan.contact[i])
        # a stance foot carries load from its first touch to its lift-off (a flickering contact, a foot
        # on an edge, stays loaded)
        loaded = memory.landed & ~memory.reaching
        # --- the ground plane, low-passed
        target = self.plane(memory.ground_points, nominal_z)
        memory.ground += (target - memory.ground) * min(1.0, max(dt, 0.0) / (GROUND_TIME * period))
        # each leg's footholds: the plane's slope through its own last contact
        own = memory.ground_points[:, 2] - nominal_z
        plane = memory.ground[0] + memory.ground[1] * memory.ground_points[:, 0]
        plan.ground_offsets = own - plane - memory.ground[2] * memory.ground_points[:, 1]
        c, s = math.cos(yaw), math.sin(yaw)
        slope_x = memory.ground[1] * c + memory.ground[2] * s
        slope_y = -memory.ground[1] * s + memory.ground[2] * c
        roll = self.attitude[0] + TERRAIN_ROLL * math.atan(slope_y)
        pitch = self.attitude[1] - TERRAIN_FOLLOW * math.atan(slope_x)
        plan.attitude = (roll, pitch)
        # --- re-anchor the planar reference (with its shift) to the measured body
        epsi = (plan.psi - yaw + math.pi) % (2.0 * math.pi) - math.pi
        if abs(epsi) > YAW_ANCHOR:
            plan.psi -= epsi - math.copysign(YAW_ANCHOR, epsi)
        delta, delta_rate = gait_plan._crawl_shift(P, Pd, phases, phase_rates)
        cp, sp = math.cos(plan.psi), math.sin(plan.psi)
        shift = np.array([cp * delta[0] - sp * delta[1], sp * delta[0] + cp * delta[1]])
        memory.shift = shift
        ex, ey = plan.x + shift[0] - position[0], plan.y + shift[1] - position[1]
        sway = np.abs(np.asarray(P["sway"], dtype=np.float64)).sum(axis=0)  # the most (C) moves the body
        bound = ANCHOR * self.h + float(P["com_shift"]) * math.hypot(sway[0], sway[1])
        norm = math.hypot(ex, ey)
        if norm > bound:
            plan.x -= ex * (1.0 - bound / norm)
            plan.y -= ey * (1.0 - bound / norm)
        # --- the body reference
        x_ref, y_ref = plan.x + shift[0], plan.y + shift[1]
        floor = gait_plan.floor_height(plan, x_ref, y_ref)
        pose_ref = gait_plan.body_pose(x_ref, y_ref, floor + float(P["height"]), plan.psi, plan.attitude)
        T_ref = gait_plan.body_transform(pose_ref)
        planar = plan.v + delta_rate
        v_ref = np.array(
            [
                cp * planar[0] - sp * planar[1] - plan.w * shift[1],
                sp * planar[0] + cp * planar[1] + plan.w * shift[0],
                0.0,
            ]
        )
        v_ref[2] = memory.ground[1] * v_ref[0] + memory.ground[2] * v_ref[1] + float(Pd["height"])
        w_ref = np.array([0.0, 0.0, plan.w])
        memory.shift_rate = v_ref[:2] - (cp * plan.v[0] - sp * plan.v[1], sp * plan.v[0] + cp * plan.v[1])
        # --- the feet
        feet = plan.p_stance.copy()
        feet_rate = np.zeros((legs, 3))
        feet_accel = np.zeros((legs, 3))
        for i in range(legs):
            if plan.contact[i]:
                if memory.reaching[i] and memory.depth[i] < REACH_DOWN * self.h:
                    feet_rate[i, 2] = -descent
                continue
            lift = plan.lift_phase[i]
            progress = (phases[i] - lift) / (1.0 - lift)
            feet[i], dp, d2p = swing(plan.p_stance[i], plan.p_touchdown[i], progress, plan.lift_height[i])
            feet_rate[i] = dp * phase_rates[i] / (1.0 - lift)
            feet_accel[i] = d2p * (phase_rates[i] / (1.0 - lift)) ** 2
        # --- joints: loaded legs at the reference pose, the others (swinging, reaching) at the measured one
        seed = q if memory.q is None else memory.q
        solved = robot.body_ik(np.stack([T_ref, T_meas]), feet, seed=np.stack([seed, seed]))
        q_ref, q_sw = solved.q
        stance_cols = np.zeros(3 * legs, dtype=bool)
        for i in range(legs):
            stance_cols[self._columns[i]] = loaded[i]
        q_des = np.where(stance_cols, q_ref, q_sw)
        q_des = np.where(np.isfinite(q_des), q_des, q)  # a leg without an answer holds where it is
        memory.q = q_des.copy()
        plan.q = q_des.copy()
        Jb = robot.body_jacobian(T_meas, q)  # (3 n, 6 + 3 n): world feet by [v; w; q]
        qd_des = np.zeros(3 * legs)
        jac = []
        for i in range(legs):
            cols = self._columns[i]
            Jw = Jb[3 * i : 3 * i + 3, 6:][:, cols]
            jac.append(Jw)
            if loaded[i]:
                rel = feet_rate[i] - v_ref - np.cross(w_ref, feet[i] - T_ref[:3, 3])
            else:
                rel = feet_rate[i] - v - np.cross(w, feet[i] - position)
            try:
                qd_des[cols] = np.linalg.solve(Jw, rel)
            except np.linalg.LinAlgError:
                qd_des[cols] = 0.0
        qd_des = np.where(np.isfinite(qd_des), qd_des, 0.0)
        # --- feedforward: gravity, the weight and the virtual body wrench on the loaded feet
        com = robot.center_of_mass(T_meas, q)
        mass = robot.mass
        e_p = T_ref[:3, 3] - position
        wb = self.body_omega
        if memory.v_ref is not None and dt > 0.0:  # the reference's acceleration, low-passed
            blend = min(1.0, dt / (ACCEL_TIME * period))
            memory.a_ref += ((v_ref - memory.v_ref) / dt - memory.a_ref) * blend
        memory.v_ref = v_ref
        force = mass * (wb * wb * e_p + 2.0 * wb * (v_ref - v) + memory.a_ref)
        horizontal = math.hypot(force[0], force[1])
        if horizontal > HORIZONTAL_WRENCH * mass * G:
            force[:2] *= HORIZONTAL_WRENCH * mass * G / horizontal
        inertia = R @ self.body_inertia @ R.T
        e_R = _rotation_vector(T_ref[:3, :3] @ R.T)
        moment = inertia @ (wb * wb * e_R + 2.0 * wb * (w_ref - w))
        gravity = robot.floating_base.gravity(robot.floating_q(T_meas, q))[6 : 6 + 3 * legs]
        leg_gravity = [gravity[cols] for cols in self._columns]
        limits = [np.minimum(self.effort[cols], 1e12) for cols in self._columns]
        forces, residual = torque_weighted_forces(
            feet_meas, loaded, com, mass, jac, leg_gravity, limits, self.h, np.r_[force, moment]
        )
        forces = _friction(forces)
        tau = gravity.copy()
        for i in range(legs):
            if loaded[i]:
                tau[self._columns[i]] -= jac[i].T @ forces[i]
            elif not plan.contact[i]:  # a swing leg: M_leg qdd, qdd from the swing's acceleration
                try:
                    qdd = np.linalg.solve(jac[i], feet_accel[i])
                except np.linalg.LinAlgError:
                    continue
                if np.isfinite(qdd).all():
                    tau[self._columns[i]] += self._leg_inertia[i] @ qdd
        clipped = np.abs(tau) > self.effort
        tau = np.clip(tau, -self.effort, self.effort)
        kp = np.where(stance_cols, self.stance_kp, self.kp)
        kd = np.where(stance_cols, self.stance_kd, self.kd)
        down = [feet[i, :2] for i in range(legs) if plan.contact[i]]
        com_ref = robot.center_of_mass(T_ref, q_des)
        memory.last = {
            "t": t,
            "body_pose": pose_ref,
            "feet": feet,
            "contact": plan.contact.copy(),
            "loaded": loaded,
            "margin": support_margin(down, com_ref[:2]),
            "measured_margin": support_margin(down, com[:2]),
            "forces": forces,
            "residual": residual,
            "wrench": np.r_[force, moment],
            "clipped": clipped,
            "status": int(np.max(solved.status[0])),
            "shortened": bool(plan.speed_scale < 1.0 or (plan.step_shortened & ~plan.contact).any()),
            "ground": memory.ground.copy(),
            "reaching": memory.reaching.copy(),
            "time": time.perf_counter() - start_time,
        }
        return q_des, qd_des, tau, plan.contact.copy(), kp, kd


def _friction(forces: np.ndarray) -> np.ndarray:
    """Each force with f_z >= 0 and its horizontal part within FRICTION f_z."""
    out = forces.copy()
    out[:, 2] = np.maximum(out[:, 2], 0.0)
    horizontal = np.hypot(out[:, 0], out[:, 1])
    limit = FRICTION * out[:, 2]
    scale = np.where(horizontal > limit, limit / np.maximum(horizontal, 1e-300), 1.0)
    out[:, :2] *= scale[:, None]
    return out


def effort_limit(robot, name: str) -> float:
    """The effort limit (N m) of the joint ``name`` of ``robot.leg_joint_names`` (inf when none)."""
    model = robot.model
    if model is None:
        return math.inf
    actuated = [joint.name for joint in model.actuated_joints]
    index = robot.q_from_names(actuated, np.arange(len(actuated), dtype=float), joints=[name])
    effort = model.joint(actuated[int(index[0])]).effort
    return math.inf if effort is None or not effort > 0 else float(effort)
