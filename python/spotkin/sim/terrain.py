"""The ground a simulated robot stands on: flat, a slope, a step, random bumps. Part of
:mod:`spotkin.sim` (documented there).

Every terrain gives its height under world points (``height_at(x, y)``, the same surface MuJoCo collides
with), its slope angle (the tilt a standing body may take without falling) and its MJCF. Heights and
lengths are in metres: scale them by the robot's size (:func:`spotkin.sim.hip_height`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Union

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_finite

__all__ = ["Bumps", "Flat", "Slope", "Step", "Terrain"]

_WIDE = 100.0  # half-width (m) of a step's box across the direction of travel


def _plane(name: str, friction: float, z: float = 0.0, quat: str = "1 0 0 0") -> str:
    return (
        f'<geom name="{name}" type="plane" size="0 0 1" pos="0 0 {z!r}" quat="{quat}" '
        f'friction="{friction!r} 0.005 0.0001" {_TERRAIN_GEOM}/>'
    )


# terrain geoms: collide with the robot's geoms (contype 1, conaffinity 0), never with each other; their
# friction decides every contact (priority)
_TERRAIN_GEOM = 'contype="0" conaffinity="1" condim="3" priority="1" group="3" rgba="0.55 0.6 0.55 1"'


@dataclass(frozen=True)
class Flat:
    """Level ground at z = 0 (``terrain=None`` or ``"flat"`` means this)."""

    slope = 0.0
    """The ground's tilt (rad): 0."""

    def height_at(self, x: ArrayLike, y: ArrayLike) -> np.ndarray:
        """The ground's height (m) under the world points (x, y) (arrays broadcast)."""
        return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)

    def _gap(self, centres: np.ndarray, radius: float) -> np.ndarray:
        """The clearance of spheres (n, 3) of ``radius`` above the ground (negative: inside it)."""
        return centres[:, 2] - radius - self.height_at(centres[:, 0], centres[:, 1])

    def _mjcf(self, friction: float) -> tuple[str, str]:
        """(assets, world geoms) of this terrain."""
        return "", _plane("floor", friction)


@dataclass(frozen=True)
class Slope(Flat):
    """An inclined plane through the origin, rising along +x at ``degrees`` (negative: falling):
    z = x tan(angle). ``|degrees| < 45``."""

    degrees: float

    def __post_init__(self) -> None:
        value = as_finite(self.degrees, "Slope degrees")
        if abs(value) >= 45.0:
            raise ValueError(f"Slope degrees must be within (-45, 45), got {self.degrees!r}")
        object.__setattr__(self, "degrees", value)

    @property
    def slope(self) -> float:  # type: ignore[override]
        """The tilt (rad), ``|degrees|`` in radians."""
        return math.radians(abs(self.degrees))

    def height_at(self, x: ArrayLike, y: ArrayLike) -> np.ndarray:
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        return x * math.tan(math.radians(self.degrees))

    def _gap(self, centres: np.ndarray, radius: float) -> np.ndarray:
        angle = math.radians(self.degrees)  # the distance along the plane's normal
        return (centres[:, 2] - centres[:, 0] * math.tan(angle)) * math.cos(angle) - radius

    def _mjcf(self, friction: float) -> tuple[str, str]:
        half = -0.5 * math.radians(self.degrees)  # about y by -angle: the normal leans back, +x rises
        return "", _plane("floor", friction, quat=f"{math.cos(half)!r} 0 {math.sin(half)!r} 0")


@dataclass(frozen=True)
class Step(Flat):
    """Level ground with a raised plateau: a step up of ``height`` at x = ``distance``, and back down
    at x = ``distance + length`` (default ``length``: ``distance``, the plateau as long as the
    approach). ``height`` and ``length`` > 0, ``distance`` >= 0."""

    height: float
    distance: float
    length: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "height", as_finite(self.height, "Step height", 0.0, strict=True))
        object.__setattr__(self, "distance", as_finite(self.distance, "Step distance", 0.0))
        plateau = self.distance if self.length is None else as_finite(self.length, "Step length", 0.0)
        if plateau <= 0.0:
            raise ValueError("Step length must be > 0 (its default, distance, is 0 here: give length)")
        object.__setattr__(self, "length", plateau)

    def height_at(self, x: ArrayLike, y: ArrayLike) -> np.ndarray:
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        on = (x >= self.distance) & (x <= self.distance + self.length) & (np.abs(y) <= _WIDE)
        return np.where(on, self.height, 0.0)

    def _mjcf(self, friction: float) -> tuple[str, str]:
        half = 0.5 * self.length
        box = (
            f'<geom name="step" type="box" size="{half!r} {_WIDE!r} {0.5 * self.height!r}" '
            f'pos="{self.distance + half!r} 0 {0.5 * self.height!r}" '
            f'friction="{friction!r} 0.005 0.0001" {_TERRAIN_GEOM}/>'
        )
        return "", _plane("floor", friction) + box


@dataclass(frozen=True)
class Bumps(Flat):
    """Ground with random, smooth bumps within ±``amplitude`` about z = 0, reproducible by ``seed``.

    Random heights uniform in [-amplitude, amplitude] at the nodes of a grid of ``spacing`` metres,
    blended between nodes with smoothstep weights (so every height stays within ±amplitude), sampled
    on a heightfield of cells ``spacing / 4`` wide (at most 400 per side) over a ``size`` x ``size``
    square centred at the origin; a plane at z = -amplitude lies beyond it. ``seed`` None takes the
    run's seed (:func:`spotkin.sim.run`; 0 for :func:`spotkin.sim.mjcf`). :meth:`height_at` interpolates the
    samples on the heightfield's triangles, as MuJoCo collides with them.
    """

    amplitude: float
    seed: int | None = None
    spacing: float = 0.25
    size: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude", as_finite(self.amplitude, "Bumps amplitude", 0.0, strict=True))
        object.__setattr__(self, "spacing", as_finite(self.spacing, "Bumps spacing", 0.0, strict=True))
        object.__setattr__(self, "size", as_finite(self.size, "Bumps size", 0.0, strict=True))
        if self.seed is not None and (isinstance(self.seed, bool) or not isinstance(self.seed, int)):
            raise TypeError(f"Bumps seed must be an int or None, got {type(self.seed).__name__}")
        if self.spacing > self.size:
            raise ValueError(f"Bumps spacing ({self.spacing:g} m) must not exceed its size ({self.size:g} m)")

    def with_seed(self, seed: int) -> Bumps:
        """This terrain with ``seed`` when it has none."""
        if self.seed is not None:
            return self
        return Bumps(self.amplitude, seed, self.spacing, self.size)

    @functools.cached_property
    def _samples(self) -> np.ndarray:
        return self.grid()

    @property
    def _cells(self) -> int:
        return min(400, math.ceil(4.0 * self.size / self.spacing))

    def grid(self) -> np.ndarray:
        """(n + 1, n + 1) the heightfield's samples (m), ``[i, j]`` at y = -size/2 + i size/n,
        x = -size/2 + j size/n."""
        rng = np.random.default_rng(0 if self.seed is None else self.seed)
        nodes = math.ceil(self.size / self.spacing) + 1
        coarse = rng.uniform(-self.amplitude, self.amplitude, size=(nodes, nodes))
        n = self._cells
        u = np.linspace(0.0, self.size, n + 1) / self.spacing  # node coordinates of the samples
        k = np.minimum(np.floor(u).astype(int), nodes - 2)
        s = u - k
        s = s * s * (3.0 - 2.0 * s)  # smoothstep: weights in [0, 1], flat at the nodes
        rows = coarse[k] * (1.0 - s)[:, None] + coarse[k + 1] * s[:, None]  # along y
        return rows[:, k] * (1.0 - s) + rows[:, k + 1] * s  # along x

    def height_at(self, x: ArrayLike, y: ArrayLike) -> np.ndarray:
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        grid, n, half = self._samples, self._cells, 0.5 * self.size
        u = (x + half) / self.size * n
        v = (y + half) / self.size * n
        inside = (u >= 0.0) & (u <= n) & (v >= 0.0) & (v <= n)
        j = np.clip(np.floor(u).astype(int), 0, n - 1)
        i = np.clip(np.floor(v).astype(int), 0, n - 1)
        su, sv = np.clip(u - j, 0.0, 1.0), np.clip(v - i, 0.0, 1.0)
        # MuJoCo's triangles: each cell split along its (-x, -y) to (+x, +y) diagonal
        g00, g01, g10, g11 = grid[i, j], grid[i, j + 1], grid[i + 1, j], grid[i + 1, j + 1]
        upper = (1 - sv) * g00 + (sv - su) * g10 + su * g11
        lower = (1 - su) * g00 + (su - sv) * g01 + sv * g11
        z = np.where(sv >= su, upper, lower)
        return np.where(inside, z, -self.amplitude)

    def _mjcf(self, friction: float) -> tuple[str, str]:
        grid, n, half = self._samples, self._cells, 0.5 * self.size
        low, high = float(grid.min()), float(grid.max())
        rise = max(high - low, 1e-9)
        # MJCF's elevation lists the rows from +y down to -y (an image's rows)
        values = " ".join(f"{v:.6g}" for v in (grid[::-1] - low).ravel())
        asset = (
            f'<hfield name="bumps" nrow="{n + 1}" ncol="{n + 1}" '
            f'size="{half!r} {half!r} {rise!r} {self.amplitude!r}" elevation="{values}"/>'
        )
        field = (
            f'<geom name="bumps" type="hfield" hfield="bumps" pos="0 0 {low!r}" '
            f'friction="{friction!r} 0.005 0.0001" {_TERRAIN_GEOM}/>'
        )
        return asset, field + _plane("floor", friction, z=-self.amplitude)


Terrain = Union[Flat, Slope, Step, Bumps]
"""A terrain: :class:`Flat`, :class:`Slope`, :class:`Step` or :class:`Bumps`."""


def as_terrain(terrain) -> Flat:
    """``terrain`` checked: None and ``"flat"`` give :class:`Flat`."""
    if terrain is None or (isinstance(terrain, str) and terrain == "flat"):
        return Flat()
    if isinstance(terrain, Flat):
        return terrain
    raise ValueError(
        f"terrain must be None, 'flat', spotkin.sim.Slope, Step or Bumps, got {type(terrain).__name__} "
        f"{terrain!r}"
    )
