"""Reachability with the feet fixed (:meth:`spotkin.Robot.reachability`): which hand positions the
whole body can reach, optionally along an approach direction, and the volume they fill.

A point is reachable when some hand orientation there has an OK reach (:meth:`spotkin.Robot.reach`'s
constraints: every joint in its limits, no collision, the support margin, the body in its box). The
orientations tried, in rounds, each point until one reaches:

- with an approach direction a: the hand's approach axis (``axis``: its x by default, the gripper's
  direction on Spot and the Z1) along a, turned about it by ``rolls`` angles 2 pi k / rolls;
- without: ``directions`` approach directions spread over the sphere (a Fibonacci lattice), each with
  ``rolls`` turns, nearest first to the direction from the arm's base to the point.

The reach used here stops at the candidates of its search (no Gauss-Newton steps, no repair): a point
found is reached exactly, with every constraint held; a point not found may still be reachable by an
orientation between those tried, so the map is an inner estimate that grows with ``directions`` and
``rolls``. Points farther from the arm's base (at the nominal pose) than the arm's length plus the
box's reach cannot be reached and are not searched.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._support.boundary import as_index, as_real, as_scalar, broadcast_lead, check_trailing
from ..model import robot as robot_module
from ..model.body import body_transform
from .reach import MARGIN_FRACTION, _as_box, _compiled, _numbers, stance_frames

__all__ = ["Reachability"]

ROUND = 8
"""Orientations tried per point in one round (a point leaves the rounds when one reaches)."""
MAX_GRID_POINTS = 5_000_000
"""The most points a grid made here may have."""
GRID_SPACING = 0.15
"""The default grid's spacing as a fraction of the hip height (Spot: 7.9 cm)."""


class Reachability(NamedTuple):
    """What :meth:`spotkin.Robot.reachability` gives."""

    points: np.ndarray
    """(..., 3) the hand positions asked (world), or the grid made."""
    reachable: np.ndarray
    """(...,) bool: a reach was found there."""
    hand: np.ndarray
    """(..., 4, 4) the hand pose found (NaN where none)."""
    body_pose: np.ndarray
    """(..., 6) the body pose of that reach, Euler "XYZ" (NaN where none)."""
    q: np.ndarray
    """(..., 3 n_legs + n_arm) its joints (NaN where none)."""
    volume: float
    """m^3: the reachable points times the cell volume (``spacing`` cubed; NaN without a spacing)."""
    spacing: float
    """m: the grid's spacing (NaN for points given without one)."""


def _axis_index(axis) -> int:
    names = {"x": 0, "y": 1, "z": 2}
    if isinstance(axis, str) and axis in names:
        return names[axis]
    raise ValueError(f'axis must be "x", "y" or "z" (the hand axis that approaches), got {axis!r}')


def _frames_along(a: np.ndarray, axis: int, rolls: int) -> np.ndarray:
    """(..., rolls, 3, 3): rotations whose column ``axis`` is the unit a (..., 3), turned about a."""
    least = np.argmin(np.abs(a), axis=-1)
    e = np.eye(3)[least]
    v = np.cross(a, e)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    w = np.cross(a, v)
    angles = 2.0 * np.pi * np.arange(rolls) / rolls
    c, s = np.cos(angles), np.sin(angles)
    v_k = c[:, None] * v[..., None, :] + s[:, None] * w[..., None, :]  # (..., rolls, 3)
    w_k = np.cross(a[..., None, :], v_k)
    columns = [None, None, None]
    columns[axis], columns[(axis + 1) % 3], columns[(axis + 2) % 3] = (
        np.broadcast_to(a[..., None, :], v_k.shape),
        v_k,
        w_k,
    )
    return np.stack(columns, axis=-1)


def fibonacci_directions(count: int) -> np.ndarray:
    """(count, 3) unit vectors spread over the sphere (the Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def _arm_length(chain) -> float:
    """An upper bound of the distance from the arm's first joint to its hand: the lengths between
    consecutive frames, the tool's included."""
    origins = np.asarray(chain.frames(np.zeros(chain.dof)))[1:, :3, 3]
    return float(np.linalg.norm(np.diff(origins, axis=0), axis=-1).sum())


def default_grid(robot, spacing: float, feet: np.ndarray, box) -> np.ndarray:
    """A grid (nx, ny, nz, 3) around the arm's base at the nominal pose: the cube of half-side the arm's
    length plus the box's largest offset, above the lowest foot."""
    numbers = _numbers(robot)
    base = _arm_base(robot, feet)
    half = _arm_length(numbers.chain) + float(np.abs(np.concatenate([box[0][:3], box[1][:3]])).max())
    count = (math.floor(2.0 * half / spacing) + 1) ** 3
    if count > MAX_GRID_POINTS:
        raise ValueError(
            f"spacing {spacing:g} m makes a grid of about {count:,} points, more than {MAX_GRID_POINTS:,}: "
            "choose a coarser spacing, or pass the points"
        )
    axes = [np.arange(base[k] - half, base[k] + half + 0.5 * spacing, spacing) for k in range(3)]
    axes[2] = axes[2][axes[2] >= feet[:, 2].min()]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)


def _arm_base(robot, feet: np.ndarray) -> np.ndarray:
    """The arm's first joint in the world, the body at its nominal pose over ``feet``."""
    numbers = _numbers(robot)
    stance = stance_frames(feet[None], numbers.feet)[0]
    T = stance @ body_transform(np.array([0.0, 0.0, numbers.h0, 0.0, 0.0, 0.0]))
    first = np.asarray(numbers.chain.frames(np.zeros(numbers.chain.dof)))[1]
    return (T @ first)[:3, 3]


def reachability(
    robot,
    points=None,
    approach=None,
    *,
    spacing=None,
    axis="x",
    feet=None,
    margin=None,
    box=None,
    directions=14,
    rolls=4,
) -> Reachability:
    """:meth:`spotkin.Robot.reachability` (documented there)."""
    arm = robot.arm
    if arm is None:
        raise ValueError("reachability needs an arm: this robot has none (robot.arm is None)")
    numbers = _numbers(robot)
    if numbers.chain is None:
        raise ValueError("reachability needs the robot's description (a URDF) for its arm's chain")
    k_axis = _axis_index(axis)
    directions, rolls = as_index(directions, "directions"), as_index(rolls, "rolls")
    if directions < 1 or rolls < 1:
        raise ValueError(f"directions and rolls must be at least 1, got {directions} and {rolls}")
    n_legs, m = robot.n_legs, 3 * robot.n_legs + arm.dof
    feet = numbers.feet if feet is None else as_real(feet, "feet", np.float64)
    if feet.shape != (n_legs, 3) or not np.isfinite(feet).all():
        raise ValueError(f"feet must be finite with shape ({n_legs}, 3), got {feet.shape}")
    margin = MARGIN_FRACTION * numbers.L if margin is None else as_scalar(margin, "margin")
    if not math.isfinite(margin):
        raise ValueError(f"margin must be finite, got {margin}")
    box = _as_box(box, robot)
    if spacing is not None:
        spacing = as_scalar(spacing, "spacing")
        if not (spacing > 0.0 and math.isfinite(spacing)):
            raise ValueError(f"spacing must be a finite length > 0, got {spacing}")
    if points is None:
        spacing = GRID_SPACING * numbers.L if spacing is None else spacing
        points = default_grid(robot, spacing, feet, box)
    points = as_real(points, "points", np.float64)
    leads = {"points": (check_trailing(points, "points", (3,)), points.shape)}
    if approach is not None:
        approach = as_real(approach, "approach", np.float64)
        leads["approach"] = (check_trailing(approach, "approach", (3,)), approach.shape)
        norms = np.linalg.norm(approach, axis=-1)
        if not (np.isfinite(approach).all() and (norms > 0.0).all()):
            raise ValueError("approach must be finite, non-zero directions")
        approach = approach / norms[..., None]
    lead = broadcast_lead(**leads)
    P = np.broadcast_to(points, (*lead, 3)).reshape(-1, 3)
    N = len(P)
    base = _arm_base(robot, feet)
    if approach is None:
        dirs = fibonacci_directions(directions)  # nearest first to the direction base -> point
        outward = P - base
        order = np.argsort(-(outward @ dirs.T), axis=1, kind="stable")  # (N, directions)
        frames = _frames_along(dirs, k_axis, rolls)  # (directions, rolls, 3, 3)
        R_all = frames[order].reshape(N, directions * rolls, 3, 3)
    else:
        A = np.broadcast_to(approach, (*lead, 3)).reshape(-1, 3)
        R_all = _frames_along(A, k_axis, rolls)  # (N, rolls, 3, 3)
    count = R_all.shape[1]
    # the farthest the arm's base moves from its nominal place: the box's translation, plus its rotation
    # (at most the sum of the Euler offsets' magnitudes) times the base's distance from the body origin
    lo, hi = np.abs(box[0]), np.abs(box[1])
    first = np.asarray(numbers.chain.frames(np.zeros(numbers.chain.dof)))[1, :3, 3]
    moves = float(np.linalg.norm(np.maximum(lo[:3], hi[:3]))) + float(
        np.maximum(lo[3:], hi[3:]).sum()
    ) * float(np.linalg.norm(first))
    reach_limit = _arm_length(numbers.chain) + moves
    finite = np.isfinite(P).all(axis=1)
    searching = finite & (np.linalg.norm(np.where(finite[:, None], P, 0.0) - base, axis=1) <= reach_limit)
    hand = np.full((N, 4, 4), np.nan)
    body_pose, q = np.full((N, 6), np.nan), np.full((N, m), np.nan)
    found = np.zeros(N, bool)
    model = _compiled(robot, box)
    stance = stance_frames(feet[None], numbers.feet)
    limits = robot.limits
    mid = np.where(np.isfinite(limits).all(axis=1), 0.5 * (limits[:, 0] + limits[:, 1]), 0.0)
    nominal = np.array([0.0, 0.0, numbers.h0, 0.0, 0.0, 0.0])
    for start in range(0, count, ROUND):
        rows = np.nonzero(searching & ~found)[0]
        if len(rows) == 0:
            break
        tried = min(ROUND, count - start)
        T = np.zeros((len(rows), tried, 4, 4))
        T[..., :3, :3] = R_all[rows, start : start + tried]
        T[..., :3, 3] = P[rows, None, :]
        T[..., 3, 3] = 1.0
        M = len(rows) * tried
        pose, qs, status = model.solve(
            T.reshape(M, 4, 4),
            np.ascontiguousarray(np.broadcast_to(feet, (M, n_legs, 3))),
            np.ascontiguousarray(np.broadcast_to(stance, (M, 4, 4))),
            np.ascontiguousarray(np.broadcast_to(nominal, (M, 6))),
            np.ascontiguousarray(np.broadcast_to(mid, (M, m))),
            None,
            np.full(M, margin),
            refine=False,
            repair=False,
        )[:3]
        ok = (status == 0).reshape(len(rows), tried)
        first = np.argmax(ok, axis=1)
        hit = ok.any(axis=1)
        take = rows[hit]
        flat = np.nonzero(hit)[0] * tried + first[hit]
        hand[take], body_pose[take], q[take] = T.reshape(M, 4, 4)[flat], pose[flat], qs[flat]
        found[take] = True
    volume = float(found.sum()) * spacing**3 if spacing is not None else math.nan
    return Reachability(
        np.broadcast_to(points, (*lead, 3)).copy(),
        found.reshape(lead),
        hand.reshape(*lead, 4, 4),
        body_pose.reshape(*lead, 6),
        q.reshape(*lead, m),
        volume,
        math.nan if spacing is None else float(spacing),
    )


robot_module._MOTION["reachability"] = reachability
