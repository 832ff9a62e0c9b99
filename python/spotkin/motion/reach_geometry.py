"""The batched reach search's numbers and geometry: a batch's resolved problem, and the residuals,
margins and capsule distances of :mod:`spotkin.reference.reach`, row by row over arrays."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.body import body_transform

_TWO_PI = 2.0 * math.pi


@dataclass
class Batch:
    """A batch's resolved numbers: N targets."""

    robot: object
    arm: object
    chain: object  # the arm's chain from the body, or None (no collision model)
    capsules: object
    mount: np.ndarray  # (4, 4)
    target: np.ndarray  # (N, 4, 4)
    feet: np.ndarray  # (N, n, 3)
    stance: np.ndarray  # (N, 4, 4) world <- S
    nominal: np.ndarray  # (6,)
    lower: np.ndarray  # (6,)
    upper: np.ndarray  # (6,)
    margin: np.ndarray  # (N,)
    scale: float
    q_lower: np.ndarray  # (m,)
    q_upper: np.ndarray
    p_ref: np.ndarray  # (N, 6)
    q_ref: np.ndarray  # (N, m)
    seed_pose: np.ndarray | None  # (N, 6) in S, or None
    hull: np.ndarray  # (N, n, n) bool: (i, j) is a counter-clockwise hull edge of target's feet

    @property
    def widths(self) -> tuple[np.ndarray, np.ndarray]:
        w_p = 0.5 * (self.upper - self.lower)
        finite = np.isfinite(self.q_lower) & np.isfinite(self.q_upper)
        w_q = np.where(finite, 0.5 * (self.q_upper - self.q_lower), math.pi)
        return np.where(w_p > 0.0, w_p, 1.0), np.where(w_q > 0.0, w_q, 1.0)


def hull_edges(feet_xy: np.ndarray) -> np.ndarray:
    """(N, n, n) bool: (i, j) is an edge of the feet's convex hull, counter-clockwise (every other
    foot strictly left of it, by more than (M)'s 1e-12)."""
    n = feet_xy.shape[-2]
    d = feet_xy[:, None, :, :] - feet_xy[:, :, None, :]  # (N, i, j, 2): p_j - p_i
    w = feet_xy[:, None, None, :, :] - feet_xy[:, :, None, None, :]  # (N, i, 1, k, 2): p_k - p_i
    cross = d[:, :, :, None, 0] * w[..., 1] - d[:, :, :, None, 1] * w[..., 0]  # (N, i, j, k)
    others = ~(
        np.eye(n, dtype=bool)[:, :, None] | np.eye(n, dtype=bool)[:, None, :] | np.eye(n, dtype=bool)[None]
    )
    left = (cross > 1e-12) | ~others[None]
    distinct = np.abs(d).sum(axis=-1) > 0.0
    return left.all(axis=-1) & distinct


def support_margins(batch: Batch, rows: np.ndarray, com_xy: np.ndarray) -> np.ndarray:
    """(M): the signed distance of com_xy (M, 2) to the hull of the feet of target ``rows`` (M,)."""
    feet = batch.feet[rows, :, :2]  # (M, n, 2)
    edges = batch.hull[rows]  # (M, n, n)
    a, b = feet[:, :, None, :], feet[:, None, :, :]  # (M, i, 1, 2), (M, 1, j, 2)
    ab = b - a
    length = np.hypot(ab[..., 0], ab[..., 1])
    c = com_xy[:, None, None, :]
    cross = ab[..., 0] * (c[..., 1] - a[..., 1]) - ab[..., 1] * (c[..., 0] - a[..., 0])
    with np.errstate(invalid="ignore", divide="ignore"):
        inside = np.where(edges, cross / np.where(length > 0.0, length, 1.0), np.inf).min(axis=(1, 2))
        length2 = np.where(length > 0.0, length * length, 1.0)
        t = np.clip(((c - a) * ab).sum(axis=-1) / length2, 0.0, 1.0)
        gap = np.hypot(c[..., 0] - a[..., 0] - t * ab[..., 0], c[..., 1] - a[..., 1] - t * ab[..., 1])
    has_hull = edges.any(axis=(1, 2))
    outside = -np.where(edges, gap, np.inf).min(axis=(1, 2))
    # collinear feet (no hull): minus the distance to the segment between the extreme feet
    order = np.lexsort((feet[..., 1], feet[..., 0]))  # per row, by x then y
    first = np.take_along_axis(feet, order[:, :1, None], axis=1)[:, 0]
    last = np.take_along_axis(feet, order[:, -1:, None], axis=1)[:, 0]
    seg = last - first
    seg2 = (seg * seg).sum(axis=-1)
    t = np.where(seg2 > 0.0, ((com_xy - first) * seg).sum(axis=-1) / np.where(seg2 > 0.0, seg2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    line = -np.hypot(*(com_xy - first - t[:, None] * seg).T)
    return np.where(has_hull, np.where(inside >= 0.0, inside, outside), line)


def wrap(x):
    return (x + math.pi) % _TWO_PI - math.pi


def residuals(batch: Batch, rows, p, q) -> np.ndarray:
    """(G) for rows: (M, 6 + m)."""
    w_p, w_q = batch.widths
    return np.concatenate([(p - batch.p_ref[rows]) / w_p, wrap(q - batch.q_ref[rows]) / w_q], axis=-1)


def body_T(batch: Batch, rows, p) -> np.ndarray:
    return batch.stance[rows] @ body_transform(p)


def arm_targets(batch: Batch, rows, T_body) -> np.ndarray:
    base = T_body @ batch.mount
    R, t = base[:, :3, :3], base[:, :3, 3]
    target = batch.target[rows]
    out = np.zeros((len(rows), 4, 4))
    out[:, :3, :3] = np.einsum("mji,mjk->mik", R, target[:, :3, :3])
    out[:, :3, 3] = np.einsum("mji,mj->mi", R, target[:, :3, 3] - t)
    out[:, 3, 3] = 1.0
    return out


def legs(batch: Batch, rows, T_body, seed=None) -> tuple[np.ndarray, np.ndarray]:
    sol = batch.robot.body_ik(T_body, batch.feet[rows], seed=seed)
    return np.asarray(sol.q, float), (np.asarray(sol.status) == 0).all(axis=-1)


def margins(batch: Batch, rows, T_body, q) -> np.ndarray:
    com = np.asarray(batch.robot.center_of_mass(T_body, q), float)
    return support_margins(batch, rows, com[:, :2])


def collisions(batch: Batch, q) -> np.ndarray:
    """(M,) bool: an arm capsule hits the body box or a leg capsule (see :func:`ref.collides`)."""
    model = batch.capsules
    M = len(q)
    hit = np.zeros(M, bool)
    if model is None or not model.arm_points or M == 0:
        return hit
    robot = batch.robot
    n3 = 3 * robot.n_legs
    frames = np.asarray(batch.chain.frames(q[:, n3:]), float)[:, :, :3, 3]
    segs = leg_segments(robot, q[:, :n3])  # (M, n, 3 points, 3)
    r = model.radius
    for k in range(len(model.arm_points) - 1):
        a, b = frames[:, model.arm_points[k]], frames[:, model.arm_points[k + 1]]
        if model.arm_vs_body[k]:
            hit |= segment_box_distances(a, b, model.box_centre, model.box_half) < r
        for i in range(robot.n_legs):
            for part in range(2):
                if model.arm_vs_legs[k, i, part]:
                    hit |= segment_distances(a, b, segs[:, i, part], segs[:, i, part + 1]) < 2.0 * r
    return hit


def leg_segments(robot, q_legs) -> np.ndarray:
    """(M, n, 3, 3): each leg's hip-pitch joint, knee and foot, body frame."""
    M = len(q_legs)
    out = np.empty((M, robot.n_legs, 3, 3))
    hips = robot.hip_positions
    for k, (leg, columns) in enumerate(zip(robot.legs, robot.leg_columns)):
        q = q_legs[:, columns]
        a, signs = leg.a, leg.signs
        t1 = signs[0] * q[:, 0]
        c, s = np.cos(t1), np.sin(t1)
        out[:, k, 0] = hips[k] + np.stack([np.full(M, a[0]), c * a[1] - s * a[2], s * a[1] + c * a[2]], -1)
        out[:, k, 1] = hips[k] + leg.knee(q)
        out[:, k, 2] = hips[k] + leg.fk(q)
    return out


def segment_distances(a, b, c, d) -> np.ndarray:
    """Row-wise :func:`ref.segment_distance`."""
    u, v, w = b - a, d - c, a - c
    uu, vv = (u * u).sum(-1), (v * v).sum(-1)
    uv, uw, vw = (u * v).sum(-1), (u * w).sum(-1), (v * w).sum(-1)
    tiny_u, tiny_v = uu <= 1e-30, vv <= 1e-30
    safe_uu, safe_vv = np.where(tiny_u, 1.0, uu), np.where(tiny_v, 1.0, vv)
    den = uu * vv - uv * uv
    s = np.where(den > 1e-30, np.clip((uv * vw - vv * uw) / np.where(den > 1e-30, den, 1.0), 0.0, 1.0), 0.0)
    t = (uv * s + vw) / safe_vv
    low, high = t < 0.0, t > 1.0
    s = np.where(
        low, np.clip(-uw / safe_uu, 0.0, 1.0), np.where(high, np.clip((uv - uw) / safe_uu, 0.0, 1.0), s)
    )
    t = np.where(low, 0.0, np.where(high, 1.0, t))
    # the degenerate cases, as the reference orders them
    s = np.where(tiny_u, 0.0, np.where(tiny_v, np.clip(-uw / safe_uu, 0.0, 1.0), s))
    t = np.where(tiny_u, np.where(tiny_v, 0.0, np.clip(vw / safe_vv, 0.0, 1.0)), np.where(tiny_v, 0.0, t))
    gap = w + s[:, None] * u - t[:, None] * v
    return np.sqrt((gap * gap).sum(-1))


def segment_box_distances(a, b, centre, half) -> np.ndarray:
    """Row-wise :func:`ref.segment_box_distance`: the ends, the face-plane crossings and each piece's
    own minimum."""
    a = a - centre
    u = b - centre - a
    M = len(a)

    def at(t):
        gap = np.maximum(np.abs(a + t[:, None] * u) - half, 0.0)
        return np.sqrt((gap * gap).sum(-1))

    with np.errstate(divide="ignore", invalid="ignore"):
        cross = np.concatenate([(half - a) / u, (-half - a) / u], -1)  # (M, 6)
    moving = np.concatenate([u != 0.0, u != 0.0], -1)
    cross = np.where(moving & (cross > 0.0) & (cross < 1.0), cross, np.nan)
    cuts = np.sort(np.concatenate([np.zeros((M, 1)), np.ones((M, 1)), cross], -1), axis=-1)  # NaN last
    best = np.full(M, np.inf)
    for k in range(8):
        t = cuts[:, k]
        best = np.where(np.isnan(t), best, np.minimum(best, at(np.nan_to_num(t))))
    for k in range(7):
        lo, hi = cuts[:, k], cuts[:, k + 1]
        piece = ~np.isnan(hi)
        mid = a + (0.5 * (np.nan_to_num(lo) + np.nan_to_num(hi)))[:, None] * u
        side = np.sign(mid) * (np.abs(mid) > half)
        den = (side * side * u * u).sum(-1)
        num = -(side * u * (side * a - half * side * side)).sum(-1)
        use = piece & (den > 0.0)
        t = np.clip(num / np.where(use, den, 1.0), np.nan_to_num(lo), np.nan_to_num(hi))
        best = np.where(use, np.minimum(best, at(t)), best)
    return best
