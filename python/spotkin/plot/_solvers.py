"""The solvers as the pictures read them: through the interface that legs, the Spot arm and chains share
(``dof``, ``limits``, ``joint_names``, ``fk``, ``jacobian``, ``ik_all``, ``ik``), and, where a picture
draws a solver's links, through what the solver has to place them (a leg's geometry, a chain's frames,
the Spot arm's link lengths), asked for by capability rather than by class."""

from __future__ import annotations

import math

import numpy as np

from ._common import _LIMIT_TOL

# the solver interface (docs/guide/solvers.md)
_INTERFACE = ("dof", "limits", "joint_names", "fk", "jacobian", "ik_all", "ik")
# a roll–pitch–pitch leg's geometry, which its pictures draw (side and front views, singular sets)
_LEG_GEOMETRY = ("a", "b", "c", "signs", "knee", "hip_offset", "reach")


def _is_solver(value) -> bool:
    """``value`` answers the solver interface."""
    return all(hasattr(value, name) for name in _INTERFACE)


def _is_leg(solver) -> bool:
    """``solver`` has a roll–pitch–pitch leg's geometry (a leg frame at the hip-roll joint)."""
    return all(hasattr(solver, name) for name in _LEG_GEOMETRY)


def _has_frames(solver) -> bool:
    """``solver`` gives every joint frame (``frames(q)``: base, one per joint, tool), as a chain does."""
    return callable(getattr(solver, "frames", None))


def _drawable(solver) -> bool:
    """The pictures can place ``solver``'s joints (:func:`_joint_origins`)."""
    return _is_leg(solver) or _has_frames(solver)


def _rx(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _joint_origins(solver, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(points (k, 3), rows (dof,)): the joint origins of one configuration in the solver's own frame
    (a leg's leg frame, an arm's or a chain's base frame), from the first joint's to the foot or tool
    point, and for each joint the row of ``points`` that is its origin (where a joint beyond its limits
    is marked).

    - a leg: hip roll, hip pitch, knee, foot (rows 0, 1, 2);
    - a chain (the Spot arm too): its frames' origins, base first and tool last (joint k at row k + 1).
    """
    if _is_leg(solver):
        hip_pitch = _rx(solver.signs[0] * q[0]) @ solver.a
        points = np.array([np.zeros(3), hip_pitch, solver.knee(q), solver.fk(q)])
        return points, np.arange(3)
    if _has_frames(solver):
        return solver.frames(q)[:, :3, 3], np.arange(1, solver.dof + 1)
    raise TypeError(f"the joints of a {type(solver).__name__} cannot be drawn: it gives no joint frames")


def _revolute(solver) -> np.ndarray:
    """(dof,) bool: the revolute joints (a chain's ``sigma`` tells its prismatic ones; legs and the
    Spot arm have revolute joints only)."""
    sigma = getattr(solver, "sigma", None)
    if sigma is not None:
        return np.asarray(sigma) == 0
    return np.ones(solver.dof, dtype=bool)


def _beyond_limits(q: np.ndarray, limits: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """(..., n) bool: the joint lies outside its limits (a revolute joint also after ±2π)."""
    lower, upper = limits[:, 0], limits[:, 1]

    def inside(value):
        return (value >= lower - _LIMIT_TOL) & (value <= upper + _LIMIT_TOL)

    within = inside(q)
    turn = np.where(revolute, 2 * np.pi, 0.0)
    within |= inside(q + turn) | inside(q - turn)
    return ~within


def _joint_labels(solver) -> tuple[str, ...]:
    """The joints' names as a panel prints them: the solver's ``joint_names`` without a dotted prefix
    that every one of them shares (the Spot SDK's "arm0.": "sh0", "el1", ...), or q1, q2, ... when the
    solver has none."""
    names = solver.joint_names
    if names is None:
        return tuple(f"q{k + 1}" for k in range(solver.dof))
    prefix = names[0].rpartition(".")[0] + "." if "." in names[0] else ""
    if prefix and all(name.startswith(prefix) and len(name) > len(prefix) for name in names):
        return tuple(name[len(prefix) :] for name in names)
    return tuple(names)


def _default_q(solver) -> np.ndarray:
    """(dof,) the zero angles clipped into the solver's limits."""
    limits = solver.limits
    return np.clip(np.zeros(len(limits)), limits[:, 0], limits[:, 1])
