"""What a legged-robot controller reads and writes, one tick at a time.

:class:`RobotState` is the measured state of the floating base and the leg joints;
:class:`JointCommand` is what a joint-level PD loop with feedforward applies:
``tau_joint = kp (q - q_meas) + kd (qd - qd_meas) + tau``. Every field broadcasts over leading
dimensions, so one object may hold many robots.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real, check_trailing

__all__ = ["JointCommand", "RobotState"]


def _field(value: ArrayLike, name: str, width: int | None) -> np.ndarray:
    array = as_real(value, name)
    if width is not None:
        check_trailing(array, name, (width,))
    return array


@dataclass(frozen=True)
class RobotState:
    """The measured state of a legged robot.

    - ``position`` (..., 3): the body origin in the world, m.
    - ``quaternion`` (..., 4): the body's orientation in the world, (x, y, z, w).
    - ``linear_velocity``, ``angular_velocity`` (..., 3): the body's, in world axes (m/s, rad/s).
    - ``q``, ``qd`` (..., 3 n_legs): the leg joints in ``robot.leg_joint_names`` order (rad, rad/s).
    - ``contact`` (..., n_legs) bool, optional: the measured foot contacts, in ``robot.leg_names``
      order (foot sensors or a contact estimator); None when not measured.

    Arrays are converted once (float32 stays float32, other reals become float64); a wrong trailing
    shape raises ``ValueError`` naming the field.
    """

    position: np.ndarray
    quaternion: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    contact: np.ndarray | None = None

    def __post_init__(self) -> None:
        widths = {"position": 3, "quaternion": 4, "linear_velocity": 3, "angular_velocity": 3}
        for name, width in widths.items():
            object.__setattr__(self, name, _field(getattr(self, name), name, width))
        q = _field(self.q, "q", None)
        if q.ndim == 0:
            raise ValueError("q must have shape (..., 3 n_legs), got a scalar")
        qd = _field(self.qd, "qd", None)
        if qd.ndim == 0 or qd.shape[-1] != q.shape[-1]:
            raise ValueError(
                f"q and qd must have the same width (3 n_legs, robot.leg_joint_names), got q {q.shape} "
                f"and qd {qd.shape}"
            )
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "qd", qd)
        if self.contact is not None:
            contact = np.asarray(self.contact)
            if contact.dtype != np.bool_:
                raise TypeError(f"contact must be a bool array, got dtype {contact.dtype}")
            if contact.ndim == 0:
                raise ValueError("contact must have shape (..., n_legs), got a scalar")
            object.__setattr__(self, "contact", contact)

    def replace(self, **changes) -> RobotState:
        """A copy with some fields replaced."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values.update(changes)
        return RobotState(**values)


@dataclass(frozen=True)
class JointCommand:
    """A joint-level command for one control tick: ``tau_joint = kp (q - q_meas) + kd (qd - qd_meas) + tau``.

    - ``q``, ``qd`` (..., n): the joint targets (rad, rad/s), ``robot.leg_joint_names`` order.
    - ``tau`` (..., n): the feedforward torques, N m.
    - ``kp``, ``kd`` (n,): the gains, N m/rad and N m s/rad.
    - ``contact`` (..., n_legs) bool: the planned stance, ``robot.leg_names`` order.
    """

    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    kp: np.ndarray
    kd: np.ndarray
    contact: np.ndarray

    def torques(self, q_measured: ArrayLike, qd_measured: ArrayLike) -> np.ndarray:
        """The joint torques this command applies at the measured joints (before any effort limit)."""
        q_measured = np.asarray(q_measured, dtype=self.q.dtype)
        qd_measured = np.asarray(qd_measured, dtype=self.q.dtype)
        return self.kp * (self.q - q_measured) + self.kd * (self.qd - qd_measured) + self.tau
