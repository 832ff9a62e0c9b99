"""The closed-loop gait controller: :class:`GaitController`, one control tick at a time, for one robot or
a batch of them in one compiled call (cpp/src/gait_controller.cpp, the robots on the threads). The
compiled tick mirrors the pure-Python reference (:mod:`spotkin.reference.controller`), which the tests
compare it with tick by tick.

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
   ``ANCHOR`` h (position) and ``YAW_ANCHOR`` (yaw) of the measured body, so that drift, pushes and
   slopes never accumulate an error the legs would try to undo. Stance feet are held where they
   are measured.
4. **Body reference.** Position: the anchored planar pose plus the centre-of-mass shift s0 (in every
   gait) and the crawl's sway (C); height: the gait's above the ground plane; attitude: the commanded
   roll and pitch, the pitch plus ``TERRAIN_FOLLOW`` of the ground's slope along the heading; yaw:
   the planner's.
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
   ``BODY_BANDWIDTH`` sqrt(g / h). The feedforward is clipped to the joints' effort limits
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

import math

import numpy as np

from .. import _core
from .._support.boundary import as_real, as_scalar
from ..model.robot import Robot
from ..reference.controller import (
    ACCEL_TIME,
    ANCHOR,
    BODY_BANDWIDTH,
    DAMPING_RATIO,
    FRICTION,
    GROUND_TIME,
    MAX_GAP,
    REACH_DOWN,
    STANCE_BANDWIDTH,
    SWING_BANDWIDTH,
    TERRAIN_FOLLOW,
    TERRAIN_ROLL,
    TIP_INERTIA,
    YAW_ANCHOR,
    ReferenceController,
)
from .gait import Gait, ResolvedGait
from .plan import gait_numbers
from .state import JointCommand, RobotState

__all__ = ["GaitController"]

CONSTANTS = (
    ACCEL_TIME,
    ANCHOR,
    BODY_BANDWIDTH,
    DAMPING_RATIO,
    FRICTION,
    GROUND_TIME,
    MAX_GAP,
    REACH_DOWN,
    STANCE_BANDWIDTH,
    SWING_BANDWIDTH,
    TERRAIN_FOLLOW,
    TERRAIN_ROLL,
    TIP_INERTIA,
    YAW_ANCHOR,
)
"""The controller's documented constants (defined with the reference tick, compiled into the core)."""
DETAILS = (
    "body_pose",
    "feet",
    "contact",
    "loaded",
    "margin",
    "measured_margin",
    "forces",
    "residual",
    "wrench",
    "clipped",
    "status",
    "shortened",
    "ground",
    "reaching",
    "time",
)


class GaitController:
    """A closed-loop gait controller for a quadruped: ``step(t, state, velocity) -> JointCommand``
    (module :mod:`spotkin.motion.controller` documents each tick and the gains).

    ``robot``: a quadruped :class:`spotkin.Robot`; ``gait``: a :class:`spotkin.Gait` or a preset
    name; ``rate``: the control rate (Hz), the tick of the first step; ``attitude``: the commanded
    (roll, pitch) of the body (rad). Gaits change on the fly (``step(..., gait=...)``, blended as in a
    plan). ``kp`` and ``kd`` are the swing gains, ``stance_kp`` and ``stance_kd`` the stance ones.
    """

    def __init__(self, robot, gait="trot", *, rate: float = 500.0, attitude=(0.0, 0.0)) -> None:
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a spotkin.Robot, got {type(robot).__name__}")
        self.robot = robot
        self._resolved: dict[Gait, ResolvedGait] = {}
        self.gait = self._gait(gait)
        base = self._resolve(self.gait)  # ValueError for a robot that is not a quadruped
        rate = as_scalar(rate, "rate")
        if not (math.isfinite(rate) and rate > 0.0):
            raise ValueError(f"rate must be finite and > 0, got {rate}")
        self.rate = rate
        attitude = as_real(attitude, "attitude", np.float64)
        if attitude.shape != (2,) or not np.isfinite(attitude).all():
            raise ValueError(f"attitude must be finite (roll, pitch), got {attitude.tolist()}")
        self.attitude = (float(attitude[0]), float(attitude[1]))
        constants = ReferenceController(robot, base, self.attitude)
        self.h = constants.h
        self.kp, self.kd = constants.kp, constants.kd
        self.stance_kp, self.stance_kd = constants.stance_kp, constants.stance_kd
        self.body_inertia, self.body_omega = constants.body_inertia, constants.body_omega
        self.effort = constants.effort
        self._core = _core.GaitControllerCore(
            robot._statics,
            self.h,
            self.body_omega,
            self.body_inertia,
            self.kp,
            self.kd,
            self.stance_kp,
            self.stance_kd,
            self.effort,
            np.array(constants.leg_inertia),
            np.array(self.attitude),
        )
        self._indices: dict[Gait, int] = {}
        self._by_key: dict = {}
        self._start_index = self._index(self.gait)
        self._batch: tuple | None = None

    def _gait(self, gait) -> Gait:
        if isinstance(gait, str):
            gait = Gait(gait)
        if not isinstance(gait, Gait):
            raise TypeError(f"gait must be a spotkin.Gait or a preset name, got {type(gait).__name__}")
        return gait

    def _resolve(self, gait: Gait) -> ResolvedGait:
        """The gait resolved for the robot, its centre-of-mass shift s0 applied in every gait (a
        weight of 1 with no sway where the gait has none)."""
        if gait not in self._resolved:
            self._resolved[gait] = ReferenceController.resolved(gait.resolve(self.robot))
        return self._resolved[gait]

    def _index(self, gait: Gait) -> int:
        """The gait's index in the compiled controller's table (added on first use)."""
        if gait not in self._indices:
            self._indices[gait] = self._core.add_gait(gait_numbers(self._resolve(gait)))
        return self._indices[gait]

    def _new_index(self, gait) -> int:
        """The table index of a gait given to :meth:`step` (a Gait or a preset name), cached by the
        object given: a controller called with the same gait every tick looks it up once."""
        try:
            return self._by_key[gait]
        except KeyError:
            index = self._index(self._gait(gait))  # TypeError / ValueError for a bad gait
            self._by_key[gait] = index
            return index
        except TypeError:  # not hashable: not a gait
            return self._index(self._gait(gait))

    def reset(self) -> None:
        """Forget the robots' states: the next :meth:`step` starts afresh from the measured state."""
        self._core.reset()
        self._batch = None

    @property
    def ticks(self) -> int:
        """Robot-ticks since the start or :meth:`reset`."""
        return self._core.ticks

    @property
    def clipped(self) -> int:
        """Robot-ticks whose feedforward was clipped to an effort limit, of :attr:`ticks`."""
        return self._core.clipped

    @property
    def last(self) -> dict | None:
        """The last tick's details (one robot; a list for a batch): the planned ``body_pose``, ``feet``,
        ``contact``, the plan's support ``margin`` (m, positive inside), ``measured_margin`` (the
        measured centre of mass's), the stance ``forces`` (world), the unbalanced ``residual`` wrench,
        ``clipped`` (the joints whose feedforward was clipped to its effort), ``status`` (the worst IK
        status), ``shortened`` (the command or a foothold was cut to fit the legs) and ``time`` (s, the
        tick's compiled time)."""
        if not self._core.robots or self._batch is None:
            return None
        out = self._core.details()
        lasts = []
        for k in range(len(out["body_pose"])):
            last = {}
            for name in DETAILS:
                value = out[name][k]
                last[name] = value.item() if value.ndim == 0 else value
            last["status"] = int(last["status"])
            last["shortened"] = bool(last["shortened"])
            lasts.append(last)
        return lasts[0] if self._batch == () else lasts

    def step(self, t, state: RobotState, velocity=(0.0, 0.0, 0.0), gait=None) -> JointCommand:
        """The joint command for the measured ``state`` at time ``t`` (s), for the commanded ``velocity``
        (vx, vy, yaw rate) in the body's heading frame; ``gait`` (a Gait or a preset name) switches the
        gait (blended). A state with leading dimensions holds a batch of robots (each keeps its own
        controller state; the batch must keep its shape until :meth:`reset`); ``velocity`` broadcasts.
        ``ValueError`` for a NaN or misshapen state or command, or a time that goes backwards."""
        if type(state) is not RobotState and not isinstance(state, RobotState):
            raise TypeError(f"state must be a spotkin.motion.RobotState, got {type(state).__name__}")
        q_in = state.q
        if (
            gait is None
            and self._batch in (None, ())
            and q_in.ndim == 1
            and q_in.dtype == np.float64
            and isinstance(t, float)
        ):
            # one robot, one sample per field: the compiled step checks shapes and values itself
            position, quaternion = state.position, state.quaternion
            v, w, qd, contact = state.linear_velocity, state.angular_velocity, state.qd, state.contact
            if position.ndim == quaternion.ndim == v.ndim == w.ndim == qd.ndim == 1 and (
                contact is None or contact.ndim == 1
            ):
                index = -1 if gait is None else self._new_index(gait)
                q, qd, tau, kp, kd, planned = self._core.step(
                    t, self._start_index, index, position, quaternion, v, w, state.q, qd, contact, velocity
                )
                self._batch = ()
                return JointCommand(q[0], qd[0], tau[0], kp[0], kd[0], planned[0])
        return self._step(t, state, velocity, gait)

    def _step(self, t, state: RobotState, velocity, gait) -> JointCommand:
        """:meth:`step` in general: checks and broadcasts the state, the command and the gait."""
        t = as_scalar(t, "t")
        if not math.isfinite(t):
            raise ValueError(f"t must be finite, got {t}")
        n, legs = 3 * self.robot.n_legs, self.robot.n_legs
        if state.q.shape[-1] != n:
            raise ValueError(f"state.q must have {n} joints (robot.leg_joint_names), got {state.q.shape[-1]}")
        lead = state.q.shape[:-1]
        arrays = [state.position, state.quaternion, state.linear_velocity, state.angular_velocity, state.qd]
        try:
            shape = np.broadcast_shapes(lead, *(a.shape[:-1] for a in arrays))
        except ValueError:
            raise ValueError("the state's fields do not broadcast to one batch of robots") from None
        if state.contact is not None and state.contact.shape[-1] != legs:
            raise ValueError(f"state.contact must have {legs} feet, got {state.contact.shape[-1]}")
        velocity = as_real(velocity, "velocity")
        if velocity.shape[-1:] != (3,):
            raise ValueError(f"velocity must be (vx, vy, yaw rate), got shape {velocity.shape}")
        shape = np.broadcast_shapes(shape, velocity.shape[:-1])
        new_index = -1 if gait is None else self._new_index(gait)
        if self._batch is not None and self._batch != shape:
            raise ValueError(f"the batch changed from {self._batch} to {shape}: call reset() first")

        def flat(a, width):
            return np.ascontiguousarray(np.broadcast_to(a, (*shape, width)).reshape(-1, width))

        contact = None if state.contact is None else flat(state.contact, legs)
        q, qd, tau, kp, kd, planned = self._core.step(
            t,
            self._start_index,
            new_index,
            flat(state.position, 3),
            flat(state.quaternion, 4),
            flat(state.linear_velocity, 3),
            flat(state.angular_velocity, 3),
            flat(state.q, n),
            flat(state.qd, n),
            contact,
            flat(velocity, 3),
        )
        self._batch = shape
        # float32 in (every field of the state and the command), float32 out, as NumPy
        inputs = (
            state.position,
            state.quaternion,
            state.linear_velocity,
            state.angular_velocity,
            state.q,
            state.qd,
        )
        if np.result_type(*inputs, velocity) == np.float32:
            q, qd, tau, kp, kd = (a.astype(np.float32) for a in (q, qd, tau, kp, kd))
        if shape == ():
            return JointCommand(q[0], qd[0], tau[0], kp[0], kd[0], planned[0])
        return JointCommand(*(a.reshape(*shape, a.shape[-1]) for a in (q, qd, tau, kp, kd, planned)))
