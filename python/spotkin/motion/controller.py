"""The closed-loop gait controller: :class:`GaitController`, one control tick at a time, for one robot or
a batch of them in one compiled call (cpp/src/gait_controller.cpp, the robots on the threads).

Each tick measures the body, the feet and the ground, advances the gait planner's state machine with
those measurements (footholds with the capture point, touch-downs from the measured contacts),
re-anchors the reference to the measured body, solves the joints and their velocities, and gives the
feedforward torques (gravity, the weight and a virtual body wrench on the loaded feet, the swing legs'
inertia), with PD gains chosen from the robot's own inertias. The guide's *Walking* page explains it;
the pure-Python reference tick (:mod:`spotkin.reference.controller`, whose docstring lists every step,
constant and gain) is its definition: the compiled tick mirrors it, and the tests compare them tick by
tick.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _core
from .._support.boundary import as_real, as_scalar
from ..model.robot import Robot

# the gains' constants are defined with the reference tick and compiled into the core; named here too
from ..reference.controller import (  # noqa: F401
    DAMPING_RATIO,
    STANCE_BANDWIDTH,
    SWING_BANDWIDTH,
    ReferenceController,
)
from .gait import Gait, ResolvedGait
from .plan import gait_numbers
from .state import JointCommand, RobotState

__all__ = ["GaitController"]

_core._register_joint_command(JointCommand)  # the one-robot step makes its instances

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
    (:mod:`spotkin.reference.controller` documents each tick and the gains).

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
        if gait is None and self._batch in (None, ()):
            # one robot in single float64 rows: read in place and checked by the compiled step, which
            # returns None for anything that needs the general path's conversions or its errors
            command = self._core.step_one(t, self._start_index, -1, state, velocity)
            if command is not None:
                self._batch = ()
                return command
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
