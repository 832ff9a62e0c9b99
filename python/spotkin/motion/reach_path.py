"""A reach as a motion: from a starting configuration to the reach answer, the feet fixed, every
constraint of :meth:`spotkin.Robot.reach` held at every sample (:meth:`spotkin.Robot.reach_path`).

The path, in the stance frame S of :mod:`spotkin.reference.reach` (the box's frame):

- the body pose's offsets p and the arm's joints move along straight lines (both sets are convex: the
  box and the joint limits hold at every sample because they hold at both ends), timed by the quintic
  s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 (zero velocity and acceleration at both ends);
- the legs follow from the body pose by the leg IK at every sample (the feet never move), seeded
  with the start's legs, so that their branch never changes;
- five orders are tried, the first whose every sample holds is the answer: body and arm together;
  the body first, then the arm; the arm first, then the body; together, the arm through a via
  posture at mid-path (its joints at zero, then at the middle of their ranges, clipped into the
  limits: both within them, so the straight pieces are too). Each sample is checked: every leg's
  IK OK, the support margin at least ``margin``, no collision between the arm and the body or the
  legs (the capsules of :mod:`spotkin.motion.capsules`), the body pose within the box and every joint
  within its limits (a start outside them makes those samples fail).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._support.boundary import as_finite, as_index, as_real
from ..model import robot as robot_module
from ..model.body import body_transform
from .reach import (
    MARGIN_FRACTION,
    ReachResult,
    ReachStatus,
    _as_box,
    _compiled,
    _numbers,
    poses_of,
    stance_frames,
)

__all__ = ["ReachPath"]

MAX_SAMPLES = 1_000_000
"""The most samples a path may have."""
ORDERS = ("together", "body_first", "arm_first", "via_zero", "via_middle")


class ReachPath(NamedTuple):
    """What :meth:`spotkin.Robot.reach_path` gives: n samples from the start to the reach answer."""

    t: np.ndarray
    """(n,) the normalised time of each sample, 0 to 1."""
    body_pose: np.ndarray
    """(n, 6) [x, y, z, a, b, c] in the world, Euler "XYZ"."""
    q: np.ndarray
    """(n, 3 n_legs + n_arm): the legs' joints, then the arm's (NaN for a leg whose IK fails at a sample
    that does not hold)."""
    margin: np.ndarray
    """(n,) m: the support margin of the centre of mass."""
    ok: np.ndarray
    """(n,) bool: every constraint holds at that sample."""
    status: ReachStatus
    """OK when every sample holds; else the reach's own status when it is not OK (the path then stays at
    the start), or UNSTABLE (a sample's margin is short) or UNREACHABLE (a sample collides or a leg's IK
    fails) for the path of the first order tried."""
    order: str
    """The order taken: "together", "body_first", "arm_first", "via_zero", "via_middle" (the first
    whose samples all hold), or "start" when the reach is not OK."""
    answer: ReachResult
    """The reach answer the path ends at."""


def quintic(tau: np.ndarray) -> np.ndarray:
    tau = np.clip(tau, 0.0, 1.0)
    return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau * tau)


def _start_parts(start, m: int) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(start, ReachResult):
        pose, q = start.body_pose, start.q
    elif isinstance(start, (tuple, list)) and len(start) == 2:
        pose, q = start
    else:
        raise TypeError(f"start must be a ReachResult or a (body_pose, q) pair, got {type(start).__name__}")
    pose, q = as_real(pose, "start body_pose", np.float64), as_real(q, "start q", np.float64)
    if pose.shape != (6,):
        raise ValueError(f"start body_pose must have shape (6,) [x, y, z, a, b, c], got {pose.shape}")
    if q.shape != (m,):
        raise ValueError(f"start q must have shape ({m},) (the legs' joints, then the arm's), got {q.shape}")
    if not (np.isfinite(pose).all() and np.isfinite(q).all()):
        raise ValueError("start must be finite")
    return pose, q


def _arm_path(order: str, tau: np.ndarray, start: np.ndarray, end: np.ndarray, limits) -> np.ndarray:
    """The arm's joints (n, 6) along ``order``: straight to the end, or through a via posture (the
    joints at zero, or at the middle of their ranges, clipped into the limits) at mid-path."""
    lo = np.where(np.isfinite(limits[:, 0]), limits[:, 0], -np.pi)
    hi = np.where(np.isfinite(limits[:, 1]), limits[:, 1], np.pi)
    if order in ("together", "body_first", "arm_first"):
        s = _profiles(order, tau)[1]
        return start + s[:, None] * (end - start)
    via = np.clip(np.zeros(len(start)), lo, hi) if order == "via_zero" else 0.5 * (lo + hi)
    first, second = quintic(2.0 * tau)[:, None], quintic(2.0 * tau - 1.0)[:, None]
    return np.where(tau[:, None] <= 0.5, start + first * (via - start), via + second * (end - via))


def _profiles(order: str, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(s_body, s_arm): each part's progress at the samples tau."""
    if order in ("together", "via_zero", "via_middle"):
        return quintic(tau), quintic(tau)
    first, second = quintic(2.0 * tau), quintic(2.0 * tau - 1.0)
    return (first, second) if order == "body_first" else (second, first)


def reach_path(robot, start, target, n=50, feet=None, margin=None, box=None) -> ReachPath:
    """:meth:`spotkin.Robot.reach_path` (documented there)."""
    arm = robot.arm
    if arm is None:
        raise ValueError("reach_path needs an arm: this robot has none (robot.arm is None)")
    n = as_index(n, "n")
    if n < 2 or n > MAX_SAMPLES:
        raise ValueError(f"n must be in [2, {MAX_SAMPLES:,}] (the start, the end and between), got {n}")
    n_legs, m = robot.n_legs, 3 * robot.n_legs + arm.dof
    pose0, q0 = _start_parts(start, m)
    target = as_real(target, "target", np.float64)
    if target.shape != (4, 4):
        raise ValueError(f"target must have shape (4, 4) (one hand pose in the world), got {target.shape}")
    numbers = _numbers(robot)
    feet = numbers.feet if feet is None else as_real(feet, "feet", np.float64)
    if feet.shape != (n_legs, 3):
        raise ValueError(f"feet must have shape ({n_legs}, 3), got {feet.shape}")
    if not np.isfinite(feet).all():
        raise ValueError("feet must be finite")
    margin = MARGIN_FRACTION * numbers.L if margin is None else as_finite(margin, "margin")
    box = _as_box(box, robot)
    answer = robot.reach(target, feet=feet, seed=(pose0, q0), margin=margin, box=box)
    model = _compiled(robot, box)
    stance = stance_frames(feet[None], numbers.feet)[0]
    to_stance = np.linalg.inv(stance)
    p0 = poses_of((to_stance @ body_transform(pose0))[None])[0]
    t = np.linspace(0.0, 1.0, n)
    nominal = np.array([0.0, 0.0, numbers.h0, 0.0, 0.0, 0.0])
    bounds = (stance, nominal + box[0], nominal + box[1])
    if answer.status != ReachStatus.OK:
        poses, qs = np.broadcast_to(pose0, (n, 6)).copy(), np.broadcast_to(q0, (n, m)).copy()
        margins, ok = _check(robot, model, poses, qs, feet, margin, bounds)[:2]
        return ReachPath(t, poses, qs, margins, ok, answer.status, "start", answer)
    p1 = poses_of((to_stance @ body_transform(answer.body_pose))[None])[0]
    n3 = 3 * n_legs
    first = None
    arm_limits = robot.limits[n3:]
    for order in ORDERS:
        s_body = _profiles(order, t)[0]
        p = p0 + s_body[:, None] * (p1 - p0)
        T_body = stance @ body_transform(p)
        legs = robot.body_ik(T_body, feet, seed=q0[:n3])
        q_arm = _arm_path(order, t, q0[n3:], answer.q[n3:], arm_limits)
        q = np.concatenate([np.asarray(legs.q), q_arm], axis=1)
        poses = poses_of(T_body)
        poses[0], q[0] = pose0, q0  # the start and the end as given, to their last bits
        poses[-1], q[-1] = answer.body_pose, answer.q
        margins, ok, short = _check(robot, model, poses, q, feet, margin, bounds, legs.status)
        path = ReachPath(t, poses, q, margins, ok, ReachStatus.OK, order, answer)
        if ok.all():
            return path
        if first is None:
            status = ReachStatus.UNSTABLE if short else ReachStatus.UNREACHABLE
            first = path._replace(status=status)
    return first


def _check(robot, model, poses, q, feet, margin, bounds, leg_status=None):
    """(margin (n,), ok (n,), only the margin fails) of whole-body samples; ``bounds`` = (world <- S,
    the box's lower and upper offsets in S, absolute)."""
    n = len(poses)
    T_body = body_transform(poses)
    feet_n = np.ascontiguousarray(np.broadcast_to(feet, (n, *feet.shape)))
    margins, collides = model.constraints(np.ascontiguousarray(T_body), np.ascontiguousarray(q), feet_n)
    if leg_status is None:
        legs_ok = (np.asarray(robot.body_ik(T_body, feet).status) == 0).all(axis=-1)
    else:
        legs_ok = (np.asarray(leg_status) == 0).all(axis=-1)
    stance, lower, upper = bounds
    p = poses_of(np.linalg.inv(stance) @ T_body)
    in_box = ((p >= lower - 1e-9) & (p <= upper + 1e-9)).all(axis=1)
    limits = robot.limits
    with np.errstate(invalid="ignore"):
        in_limits = ((q >= limits[:, 0] - 1e-12) & (q <= limits[:, 1] + 1e-12)).all(axis=1)
    held = legs_ok & ~collides & in_box & in_limits
    ok = held & (margins >= margin)
    only_margin = bool(held.all() and not ok.all())
    return margins, ok, only_margin


robot_module._MOTION["reach_path"] = reach_path
