"""Workspaces by sampling: the reachable set of a leg, an arm or a chain within its joint limits,
the volume of a leg's workspace, and the dexterity of a 6-joint arm.

- :func:`workspace` samples joint space uniformly within the limits, maps the samples through the
  C++ forward kinematics, and counts for each reached point (or pose, for 6-joint arms) how many
  closed-form IK branches within the limits reach it.
- :func:`workspace_volume` estimates the volume of the set of positions a 3-joint leg or chain
  reaches within its limits: Monte Carlo over a box that holds the sampled workspace, each point
  tested exactly by the closed-form IK (``valid`` in some slot). Unbiased, with its standard error.
- :func:`dexterity`: for a 6-joint arm or chain, on a grid of tool positions, the fraction of
  uniformly sampled orientations for which the closed-form IK finds a solution within the limits.
  The dexterous workspace (every orientation reachable) is where the fraction is 1; with M sampled
  orientations, a position where all M are reached misses at most about 3/M of the orientations
  (95 % confidence).

Batches run through the batched C++ kernels (FK, IK), a bounded number of samples at a time.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._support.boundary import as_finite, as_index
from .._support.status import Status

__all__ = ["Dexterity", "WorkspaceSamples", "dexterity", "workspace", "workspace_volume"]

_BATCH = 65_536
MAX_SAMPLES = 20_000_000
"""The most samples :func:`workspace` (and :func:`dexterity`'s ``samples``) draws: they are kept in memory
(about 80 bytes each for a 6-joint arm)."""
MAX_VOLUME_SAMPLES = 10**10
"""The most Monte Carlo points :func:`workspace_volume` tests (streamed: a bound on the time, several
minutes at the bound)."""
MAX_GRID = 10_000_000
"""The most grid positions :func:`dexterity` evaluates (about 100 bytes each while it runs)."""
MAX_ORIENTATIONS = 1_000_000
"""The most orientations :func:`dexterity` samples per position."""
MAX_SOLVES = 10**10
"""The most IK solves :func:`dexterity` runs (grid positions times orientations: hours at the bound)."""


class WorkspaceSamples(NamedTuple):
    """Samples of a workspace, from :func:`workspace`."""

    q: np.ndarray
    """(n, dof) joint values, uniform within the limits (revolute joints without limits: [-pi, pi))."""
    points: np.ndarray
    """(n, 3) the tool point (a leg's foot) for each sample, in the base (leg) frame."""
    branches: np.ndarray
    """(n,) int8: the number of closed-form IK solutions within the limits that reach the sample's
    point (3-joint legs and chains, position IK) or pose (6-joint arms and chains, pose IK); at least
    1 up to rounding at the boundary. -1 for a chain without a closed form."""


class Dexterity(NamedTuple):
    """The dexterity of a 6-joint arm on a grid of positions, from :func:`dexterity`."""

    positions: np.ndarray
    """(G, 3) grid positions of the tool point, in the base frame."""
    fraction: np.ndarray
    """(G,) the fraction of the sampled orientations reached within the limits."""
    spacing: float
    """The grid spacing (m): each position stands for a cube of ``spacing**3``."""
    orientations: int
    """The number of orientations sampled per position."""

    def volume(self, at_least: float = 1.0) -> float:
        """The volume (m³) of the grid cells whose fraction is at least ``at_least`` (1: the
        dexterous workspace, every sampled orientation reached); ``at_least`` a finite number."""
        at_least = as_finite(at_least, "at_least")
        return float(np.count_nonzero(self.fraction >= at_least)) * self.spacing**3


_INTERFACE = ("dof", "limits", "fk", "ik_all", "ik")


def _check_solver(obj) -> None:
    """``obj`` answers the solver interface every leg, arm and chain shares (``TypeError`` otherwise)."""
    if not all(hasattr(obj, name) for name in _INTERFACE):
        raise TypeError(
            f"obj must be a solver (a spotkin Leg, arm or Chain: {', '.join(_INTERFACE)}), "
            f"got {type(obj).__name__}"
        )


def _limits(obj) -> tuple[np.ndarray, np.ndarray]:
    lower, upper = obj.limits[:, 0], obj.limits[:, 1]  # the solvers' shared (n, 2) limits
    sigma = getattr(obj, "sigma", None)  # a chain's joint types; a leg's joints are all revolute
    prismatic = np.zeros(lower.shape, dtype=bool) if sigma is None else np.asarray(sigma) == 1
    if (prismatic & ~(np.isfinite(lower) & np.isfinite(upper))).any():
        raise ValueError("sampling a workspace needs finite limits on every prismatic joint")
    lower = np.where(np.isfinite(lower), lower, -np.pi)
    upper = np.where(np.isfinite(upper), upper, np.pi)
    return lower, upper


def _tool_points(obj, q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(points (n, 3), poses (n, 4, 4), or None where fk gives points: a leg's feet)."""
    out = obj.fk(q)
    if out.shape[-2:] == (4, 4):
        return out[..., :3, 3], out
    return out, None


def _ik_targets(obj, points: np.ndarray, poses: np.ndarray | None):
    """What the solver's closed-form ``ik_all`` takes: points for 3 joints, poses for 6; None otherwise."""
    return points if obj.dof == 3 else poses if obj.dof == 6 else None


def _branch_counts(obj, points: np.ndarray, poses: np.ndarray | None) -> np.ndarray:
    targets = _ik_targets(obj, points, poses)
    if targets is not None:
        try:
            return obj.ik_all(targets).valid.sum(-1).astype(np.int8)
        except ValueError:  # no closed form for this chain
            pass
    return np.full(len(points), -1, dtype=np.int8)


def _rng(seed) -> np.random.Generator:
    return np.random.default_rng(None if seed is None else as_index(seed, "seed"))


def _count(n, name: str, maximum: int) -> int:
    """A count in [0, maximum], checked before anything is allocated."""
    n = as_index(n, name)
    if n < 0:
        raise ValueError(f"{name} must be >= 0, got {n}")
    if n > maximum:
        raise ValueError(f"{name} must be at most {maximum:,}, got {n:,}")
    return n


def workspace(obj, n: int = 100_000, seed: int | None = 0) -> WorkspaceSamples:
    """``n`` samples of the workspace of ``obj`` (a :class:`Leg`, :class:`SpotArm` or
    :class:`Chain`), drawn uniformly in joint space within its limits (``seed`` for
    :func:`numpy.random.default_rng`; None for fresh entropy), with their FK points and branch
    counts (see :class:`WorkspaceSamples`). ``n`` is at most :data:`MAX_SAMPLES` (20,000,000). A
    prismatic joint without finite limits raises ``ValueError``; another object ``TypeError``."""
    _check_solver(obj)
    n = _count(n, "n", MAX_SAMPLES)
    lower, upper = _limits(obj)
    rng = _rng(seed)
    q = rng.random((n, lower.size))  # then lower + (upper - lower) * q, in place (the same numbers)
    q *= upper - lower
    q += lower
    points = np.empty((n, 3))
    branches = np.empty(n, dtype=np.int8)
    for start in range(0, n, _BATCH):
        block = slice(start, min(n, start + _BATCH))
        points[block], poses = _tool_points(obj, q[block])
        branches[block] = _branch_counts(obj, points[block], poses)
    return WorkspaceSamples(q, points, branches)


def _position_reachable(obj, points: np.ndarray) -> np.ndarray:
    return obj.ik_all(points).valid.any(-1)  # a 3-joint solver's closed-form position IK


def workspace_volume(obj, n: int = 1_000_000, seed: int | None = 0, pad: float = 0.05):
    """Volume (m³) of the positions a :class:`Leg` or 3-joint :class:`Chain` reaches within its
    limits, with its standard error: (volume, standard_error).

    The box is the bounding box of 100,000 workspace samples (:func:`workspace`), widened by
    ``pad`` (in [0, 1]) times its size on each side so it holds the whole workspace; ``n`` points uniform in
    the box are tested by the closed-form IK (some slot valid), ``n`` at most :data:`MAX_VOLUME_SAMPLES`
    (1e10). volume = box volume x hit fraction p, standard error = box volume x sqrt(p (1 - p) / n)."""
    _check_solver(obj)
    n = _count(n, "n", MAX_VOLUME_SAMPLES)
    if n < 1:
        raise ValueError("n must be >= 1")
    pad = as_finite(pad, "pad", 0.0)
    if pad > 1.0:
        raise ValueError(f"pad must be in [0, 1] (a fraction of the box size), got {pad}")
    if obj.dof != 3:
        raise ValueError("workspace_volume needs a Leg or a 3-joint Chain (position IK in closed form)")
    rng = _rng(seed)
    points = workspace(obj, 100_000, int(rng.integers(2**63))).points
    low, high = points.min(0), points.max(0)
    size = high - low
    low, high = low - pad * size, high + pad * size
    box = float(np.prod(high - low))
    hits = 0
    for start in range(0, n, _BATCH):
        m = min(n, start + _BATCH) - start
        hits += int(np.count_nonzero(_position_reachable(obj, low + (high - low) * rng.random((m, 3)))))
    p = hits / n
    return box * p, box * float(np.sqrt(p * (1 - p) / n))


def _random_rotations(rng: np.random.Generator, m: int) -> np.ndarray:
    """(m, 3, 3) rotations uniform on SO(3) (normalised Gaussian quaternions)."""
    quat = rng.standard_normal((m, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    x, y, z, w = quat.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def _check_grid(low: np.ndarray, high: np.ndarray, spacing: float, orientations: int) -> None:
    """``ValueError`` when the grid of ``spacing`` over the box [low, high] would exceed :data:`MAX_GRID`
    positions or :data:`MAX_SOLVES` solves (counted as floats: a 1e-9 spacing gives ~1e27)."""
    size = high - low
    with np.errstate(over="ignore"):  # a tiny spacing: Inf positions, refused below
        count = float(np.prod(np.maximum(1.0, np.ceil(size / spacing))))
    box = " x ".join(f"{float(side):.3g}" for side in size)
    if count > MAX_GRID:
        least = float(np.cbrt(np.prod(np.maximum(size, 1e-300)) / MAX_GRID))
        raise ValueError(
            f"spacing {spacing:g} m makes a grid of about {count:.3g} positions over the workspace's "
            f"{box} m box; at most {MAX_GRID:,}: use a spacing of at least about {least:.2g} m"
        )
    if count * orientations > MAX_SOLVES:
        raise ValueError(
            f"spacing {spacing:g} m and orientations {orientations:,} make about {count * orientations:.3g} "
            f"IK solves ({count:.3g} positions); at most {MAX_SOLVES:.0e}: use a larger spacing or fewer "
            "orientations"
        )


def dexterity(
    obj, spacing: float = 0.05, orientations: int = 64, seed: int | None = 0, samples: int = 100_000
) -> Dexterity:
    """The dexterity of a 6-joint arm (:class:`SpotArm`, or a 6-joint :class:`Chain` with a
    closed-form :meth:`Chain.ik`): on a grid of tool positions with ``spacing`` (m) covering the
    bounding box of ``samples`` workspace samples, the fraction of ``orientations`` rotations
    (uniform on SO(3), the same set at every position) for which the IK finds a solution within the
    limits. See :class:`Dexterity`; positions that no sampled orientation reaches are kept with
    fraction 0. The grid holds at most :data:`MAX_GRID` (10,000,000) positions, ``orientations`` is
    at most :data:`MAX_ORIENTATIONS` (1,000,000), their product at most :data:`MAX_SOLVES` (1e10) and
    ``samples`` at most :data:`MAX_SAMPLES`: ``ValueError`` (naming the argument and the bound) before
    anything is allocated."""
    _check_solver(obj)
    if obj.dof != 6:
        raise ValueError("dexterity needs a 6-joint arm or chain")
    spacing = as_finite(spacing, "spacing", 0.0, strict=True)
    orientations = _count(orientations, "orientations", MAX_ORIENTATIONS)
    if orientations < 1:
        raise ValueError("orientations must be >= 1")
    samples = _count(samples, "samples", MAX_SAMPLES)
    if samples < 1:
        raise ValueError("samples must be >= 1")
    rng = _rng(seed)
    points = workspace(obj, samples, int(rng.integers(2**63))).points
    low, high = points.min(0), points.max(0)
    _check_grid(low, high, spacing, orientations)
    axes = [np.arange(lo + spacing / 2, hi + spacing / 2, spacing) for lo, hi in zip(low, high)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    rotations = _random_rotations(rng, orientations)
    solve = obj.ik
    reached = np.zeros(len(grid), dtype=np.int64)
    per_block = max(1, _BATCH // orientations)
    for start in range(0, len(grid), per_block):
        block = grid[start : start + per_block]
        T = np.zeros((len(block), orientations, 4, 4))
        T[..., :3, :3] = rotations
        T[..., :3, 3] = block[:, None, :]
        T[..., 3, 3] = 1.0
        status = solve(T.reshape(-1, 4, 4))[1].reshape(len(block), orientations)
        reached[start : start + len(block)] = np.count_nonzero(status == Status.OK, axis=1)
    return Dexterity(grid, reached / orientations, spacing, orientations)
