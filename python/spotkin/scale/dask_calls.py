"""The calls of :mod:`spotkin.dask` (documented there), each with the plan ``spotkin batch`` runs too."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Callable

import numpy as np

from .._support.boundary import as_real
from ..model.chain import Chain
from ..model.robot import Robot
from .dask_graph import (
    _BODY_POSE,
    _as_dask,
    _dof,
    _fk_gives_poses,
    _lazy,
    _model,
    _Plan,
    _plan,
    _robot,
    _takes,
    _target_core,
)

__all__ = [
    "body_fk",
    "body_ik",
    "body_jacobian",
    "body_rates",
    "center_of_mass",
    "coriolis_matrix",
    "fk",
    "floating_q",
    "forward_dynamics",
    "gravity",
    "ik",
    "ik_all",
    "inverse_dynamics",
    "jacobian",
    "joint_torques_from_forces",
    "mass_matrix",
    "nonlinear_effects",
    "standing_torques",
]

# ---- whole body --------------------------------------------------------------------------------------


def _plan_body_ik(robot, body_pose, feet, seed=None, seq="XYZ", fallback="nearest") -> _Plan:
    robot = _robot(robot)
    legs = robot.n_legs
    inputs = [("body_pose", body_pose, _BODY_POSE), ("feet", feet, (legs, 3)), ("seed", seed, (3 * legs,))]
    return _plan(robot, "body_ik", inputs, {"seq": seq, "fallback": fallback}, (), None)


def body_ik(robot: Robot, body_pose, feet, seed=None, seq: str = "XYZ", fallback: str = "nearest"):
    """:meth:`Robot.body_ik` over dask arrays: a :class:`~spotkin.BodyIK` of lazy ``q`` (..., 3 n)
    and ``status`` (..., n), chunked along the batch axes as the inputs are.

    ``body_pose`` (..., 6), (..., 4, 4) or (..., 7), ``feet`` (..., n, 3) and ``seed`` (..., 3 n)
    broadcast over their leading dimensions (a shared stance of feet (n, 3) is typical); ``seq`` and
    ``fallback`` as in memory. ``robot`` is any :class:`~spotkin.Robot` (``sk.Spot()`` included).
    """
    return _lazy(_plan_body_ik(robot, body_pose, feet, seed, seq, fallback))


def _plan_body_fk(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, (3 * robot.n_legs,))]
    return _plan(robot, "body_fk", inputs, {"seq": seq}, (), "feet")


def body_fk(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """:meth:`Robot.body_fk` over dask arrays: lazy world feet (..., n, 3) from ``body_pose`` and the
    leg joints ``q`` (..., 3 n)."""
    return _lazy(_plan_body_fk(robot, body_pose, q, seq))


def _plan_body_jacobian(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, (3 * robot.n_legs,))]
    return _plan(robot, "body_jacobian", inputs, {"seq": seq}, (), "J")


def body_jacobian(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """:meth:`Robot.body_jacobian` over dask arrays: lazy (..., 3 n, 6 + 3 n) Jacobians."""
    return _lazy(_plan_body_jacobian(robot, body_pose, q, seq))


def _plan_body_rates(robot, body_pose, q, twist, seq="XYZ", tolerance=1e-6) -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, (3 * robot.n_legs,)), ("twist", twist, (6,))]
    return _plan(robot, "body_rates", inputs, {"seq": seq, "tolerance": tolerance}, (), None)


def body_rates(robot: Robot, body_pose, q, twist, seq: str = "XYZ", tolerance: float = 1e-6):
    """:meth:`Robot.body_rates` over dask arrays: a :class:`~spotkin.BodyRates` of lazy ``qd``
    (..., 3 n) and ``singular`` (..., n)."""
    return _lazy(_plan_body_rates(robot, body_pose, q, twist, seq, tolerance))


# ---- legs, arms, chains ------------------------------------------------------------------------------


def _plan_fk(model, q) -> _Plan:
    model = _model(model)
    return _plan(model, "fk", [("q", q, (_dof(model),))], {}, (), "T" if _fk_gives_poses(model) else "p")


def fk(model, q):
    """Lazy forward kinematics of an :class:`~spotkin.Leg` (foot points (..., 3)), an
    :class:`~spotkin.SpotArm` or a :class:`~spotkin.Chain` (tool poses (..., 4, 4)) for joint
    values ``q`` (..., dof)."""
    return _lazy(_plan_fk(model, q))


def _plan_jacobian(model, q, frame=None, point=None) -> _Plan:
    model = _model(model)
    options = {}
    for name, value in (("frame", frame), ("point", point)):
        if value is None:
            continue
        if not _takes(model.jacobian, name):
            raise ValueError(
                f"{name} is for a Chain's Jacobian; a {type(model).__name__}'s has none, got {value!r}"
            )
        options[name] = value
    return _plan(model, "jacobian", [("q", q, (_dof(model),))], options, (), "J")


def jacobian(model, q, frame: str | int | None = None, point: str | int | None = None):
    """Lazy Jacobians of an :class:`~spotkin.Leg` ((..., 3, 3), d foot / d q), an
    :class:`~spotkin.SpotArm` ((..., 6, 6)) or a :class:`~spotkin.Chain` ((..., 6, dof)); ``frame``
    (default ``"base"``) and ``point`` (default ``"tool"``) only for a chain, as
    :meth:`Chain.jacobian` (the preferential Jacobian J_point(frame))."""
    return _lazy(_plan_jacobian(model, q, frame, point))


def _plan_ik(model, target, seed=None, fallback=None) -> _Plan:
    model = _model(model)
    options = {}
    if _takes(model.ik, "fallback"):  # a leg's: the nearest reachable foot by default
        if fallback is not None:
            options["fallback"] = fallback
    else:
        if fallback is not None and fallback != "nan":
            raise ValueError(
                f"fallback must be None or 'nan' for a {type(model).__name__}: arm and chain IK give NaN "
                f"for a target without a solution, got {fallback!r}"
            )
    inputs = [("target", target, _target_core(model)), ("seed", seed, (_dof(model),))]
    return _plan(model, "ik", inputs, options, ("q", "status"), None)


def ik(model, target, seed=None, fallback: str | None = None):
    """Lazy closed-form IK, one solution per target: ``(q, status)`` as dask arrays.

    - :class:`~spotkin.Leg`: :meth:`Leg.ik` of foot points ``target`` (..., 3); ``fallback``
      ``"nearest"`` (the default) or ``"nan"``.
    - :class:`~spotkin.SpotArm`: :meth:`SpotArm.ik` of tool poses (..., 4, 4) or (..., 7).
    - :class:`~spotkin.Chain`: :meth:`Chain.ik` (points (..., 3) for 3 joints, tool poses for 6).

    ``seed`` (..., dof) picks the nearest valid branch and broadcasts against ``target``. Arms and
    chains give NaN without a solution: their ``fallback`` may only be None or ``"nan"``.
    """
    return _lazy(_plan_ik(model, target, seed, fallback))


def _plan_ik_all(model, target, seed=None) -> _Plan:
    model = _model(model)
    if _takes(model.ik_all, "seed"):  # a SpotArm's: the seed fixes the free angle of singular poses
        inputs = [("target", target, _target_core(model)), ("seed", seed, (_dof(model),))]
        return _plan(model, "ik_all", inputs, {}, (), None)
    if seed is not None:
        raise TypeError(f"ik_all of a {type(model).__name__} takes no seed (only a SpotArm's does)")
    return _plan(model, "ik_all", [("target", target, _target_core(model))], {}, (), None)


def ik_all(model, target, seed=None):
    """Lazy closed-form IK with every branch: the in-memory record (``q``, ``valid``, ``exists``,
    ``status``) of dask arrays.

    :meth:`Leg.ik_all` (foot points (..., 3)), :meth:`SpotArm.ik_all` (tool poses; ``seed`` (..., 6)
    fixes the free angle in singular cases), or a :class:`~spotkin.Chain`'s :meth:`Chain.ik_all`
    (3 joints: points; 6 joints: tool poses). Only the arm takes a ``seed``.
    """
    return _lazy(_plan_ik_all(model, target, seed))


# ---- dynamics ----------------------------------------------------------------------------------------

_GRAVITY = (0.0, 0.0, -9.81)


def _dynamics(model) -> tuple[str, int, int]:
    """(method prefix, nq, nv): a :class:`~spotkin.Chain`'s own methods (fixed base: q and its rates
    (..., dof)), or a :class:`~spotkin.Robot`'s :attr:`~spotkin.Robot.floating_base` (q (..., 7 + n),
    v (..., 6 + n))."""
    if hasattr(model, "mass_matrix") and hasattr(model, "dof"):  # a chain, fixed base
        return "", model.dof, model.dof
    if isinstance(model, Robot):
        floating = model.floating_base  # ValueError for a robot without a URDF description
        return "floating_base.", floating.nq, floating.nv
    raise TypeError(
        f"model must be an sk.Chain or an sk.Robot (its floating base), got {type(model).__name__}"
    )


def _plan_dynamics(model, method: str, inputs: Sequence, single: str) -> _Plan:
    prefix, _, _ = _dynamics(model)
    return _plan(model, prefix + method, inputs, {}, (), single)


_NO_GRAVITY = object()  # a call without a gravity argument (A(q), C(q, qd))


def _rates(model, names: Sequence[str], values: Sequence, gravity=_NO_GRAVITY) -> list:
    """The (name, value, core) inputs of a dynamics call: q (nq,), then each rate (nv,), then
    ``gravity`` (3,) for the calls that take it."""
    _, nq, nv = _dynamics(model)
    inputs = [(name, value, (nq if name == "q" else nv,)) for name, value in zip(names, values)]
    if gravity is not _NO_GRAVITY:
        inputs.append(("gravity", gravity, (3,)))
    return inputs


def _plan_inverse_dynamics(model, q, qd, qdd, gravity=_GRAVITY) -> _Plan:
    return _plan_dynamics(
        model, "inverse_dynamics", _rates(model, ("q", "qd", "qdd"), (q, qd, qdd), gravity), "tau"
    )


def inverse_dynamics(model, q, qd, qdd, gravity=_GRAVITY):
    """Lazy joint torques tau = A(q) qdd + C(q, qd) qd + G(q) (recursive Newton–Euler).

    ``model``: a :class:`~spotkin.Chain` with inertials (:meth:`Chain.inverse_dynamics`: ``q``,
    ``qd``, ``qdd`` (..., dof)), or a :class:`~spotkin.Robot` for its floating base
    (:meth:`spotkin.dynamics.FloatingBase.inverse_dynamics`: ``q`` (..., 7 + n) as
    :meth:`Robot.floating_q` gives it, ``qd``, ``qdd`` (..., 6 + n)). ``gravity`` (3,) or (..., 3).
    All broadcast over their leading dimensions."""
    return _lazy(_plan_inverse_dynamics(model, q, qd, qdd, gravity))


def _plan_mass_matrix(model, q) -> _Plan:
    return _plan_dynamics(model, "mass_matrix", _rates(model, ("q",), (q,)), "A")


def mass_matrix(model, q):
    """Lazy joint-space inertia matrices A(q), (..., nv, nv) (composite-rigid-body algorithm) of a
    :class:`~spotkin.Chain` or a :class:`~spotkin.Robot`'s floating base (see :func:`inverse_dynamics`)."""
    return _lazy(_plan_mass_matrix(model, q))


def _plan_gravity(model, q, gravity=_GRAVITY) -> _Plan:
    return _plan_dynamics(model, "gravity", _rates(model, ("q",), (q,), gravity), "G")


def gravity(model, q, gravity=_GRAVITY):
    """Lazy gravity torques G(q), (..., nv) (see :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_gravity(model, q, gravity))


def _plan_nonlinear_effects(model, q, qd, gravity=_GRAVITY) -> _Plan:
    return _plan_dynamics(model, "nonlinear_effects", _rates(model, ("q", "qd"), (q, qd), gravity), "h")


def nonlinear_effects(model, q, qd, gravity=_GRAVITY):
    """Lazy h = C(q, qd) qd + G(q), (..., nv) (see :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_nonlinear_effects(model, q, qd, gravity))


def _plan_coriolis_matrix(model, q, qd) -> _Plan:
    return _plan_dynamics(model, "coriolis_matrix", _rates(model, ("q", "qd"), (q, qd)), "C")


def coriolis_matrix(model, q, qd):
    """Lazy Coriolis matrices C(q, qd), (..., nv, nv), with dA/dt - 2 C skew-symmetric (see
    :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_coriolis_matrix(model, q, qd))


def _plan_forward_dynamics(model, q, qd, tau, gravity=_GRAVITY) -> _Plan:
    inputs = _rates(model, ("q", "qd", "tau"), (q, qd, tau), gravity)
    return _plan_dynamics(model, "forward_dynamics", inputs, "qdd")


def forward_dynamics(model, q, qd, tau, gravity=_GRAVITY):
    """Lazy accelerations qdd = A(q)^-1 (tau - C qd - G), (..., nv) (articulated-body algorithm; see
    :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_forward_dynamics(model, q, qd, tau, gravity))


def _last_axis(value, name: str, check: Callable) -> tuple[int, ...]:
    """The per-sample shape (k,) of an input whose width the model allows several values of: the
    array's last axis, after ``check`` (the in-memory call's own shape check) accepted it."""
    shape = _as_dask(value, name).shape  # a TypeError for what is not a real numeric array
    check(np.zeros(shape[-1:] if shape else ()))
    return tuple(shape[-1:])


def _plan_joint_torques_from_forces(chain, q, forces) -> _Plan:
    if not isinstance(chain, Chain):
        raise TypeError(f"chain must be an sk.Chain, got {type(chain).__name__}")

    def check(forces):
        if forces.ndim == 0 or forces.shape[-1] not in (3, 6):
            raise ValueError(f"forces must have shape (..., 6) or (..., 3), got {forces.shape}")

    inputs = [("q", q, (chain.dof,)), ("forces", forces, _last_axis(forces, "forces", check))]
    return _plan(chain, "joint_torques_from_forces", inputs, {}, (), "tau")


def joint_torques_from_forces(chain, q, forces):
    """Lazy tau = J(q)^T F, (..., dof) (:meth:`Chain.joint_torques_from_forces`): ``forces`` (..., 6)
    or (..., 3) at the tool, base axes."""
    return _lazy(_plan_joint_torques_from_forces(chain, q, forces))


def _robot_q(robot: Robot, q) -> tuple[int, ...]:
    return _last_axis(q, "q", robot._legs_and_arm)


def _plan_floating_q(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, _robot_q(robot, q))]
    return _plan(robot, "floating_q", inputs, {"seq": seq}, (), "q")


def floating_q(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """Lazy floating-base coordinates (..., 7 + n) (:meth:`Robot.floating_q`): the body's position and
    quaternion, then ``q``, the legs' joints (..., 3 n) or the legs' and the arm's, for
    :func:`inverse_dynamics` and the other functions of a robot's floating base."""
    return _lazy(_plan_floating_q(robot, body_pose, q, seq))


def _plan_center_of_mass(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, _robot_q(robot, q))]
    # the floating base's kernels run in float64 (Robot.center_of_mass converts the result)
    return _plan(robot, "center_of_mass", inputs, {"seq": seq}, (), "com")


def center_of_mass(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """Lazy centres of mass in the world (..., 3) (:meth:`Robot.center_of_mass`): ``body_pose`` as
    :func:`body_fk` takes it, ``q`` the legs' joints (..., 3 n), or the legs' and the arm's."""
    return _lazy(_plan_center_of_mass(robot, body_pose, q, seq))


def _plan_standing_torques(robot, body_pose, q, stance=None, gravity=_GRAVITY, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [
        ("body_pose", body_pose, _BODY_POSE),
        ("q", q, _robot_q(robot, q)),
        ("stance", stance, (robot.n_legs,)),
    ]
    g = as_real(gravity, "gravity", np.float64)
    options = {"gravity": tuple(float(v) for v in g) if g.shape == (3,) else g, "seq": seq}
    return _plan(robot, "standing_torques", inputs, options, (), None)


def standing_torques(robot: Robot, body_pose, q, stance=None, gravity=_GRAVITY, seq: str = "XYZ"):
    """Lazy :meth:`Robot.standing_torques`: a :class:`~spotkin.Standing` of dask arrays (``tau``
    (..., 3 n), ``forces`` (..., n, 3), ``status`` (...) int8, ``margin`` (...)). ``stance`` (..., n)
    bool (default every foot) broadcasts with ``body_pose`` and ``q``; ``gravity`` is one (3,) vector."""
    return _lazy(_plan_standing_torques(robot, body_pose, q, stance, gravity, seq))
