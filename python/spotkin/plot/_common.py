"""What every picture family shares: the style (colours that stay distinct in greyscale), the argument
checks (each error names its argument) and the helpers that frame and label an Axes."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from numpy.typing import ArrayLike

from .. import Robot, body_transform

# spotkin's private helpers, imported here only (the picture modules take them from this one)
from .._support.boundary import as_index, as_real, as_scalar  # noqa: F401
from ..model.leg import SLOT_NAMES  # noqa: F401
from ..motion.reach import _numbers as _reach_numbers  # noqa: F401
from ..motion.reach import stance_frames  # noqa: F401

# -- style: distinct in greyscale (luminance, line style, marker) -------------------------------------
_BODY_EDGE, _BODY_FACE = "#252525", "#bdbdbd"
_LEG = "#08519c"  # dark blue
_ARM = "#d94801"  # orange, mid grey in greyscale; square joint markers
_OTHER = "#737373"  # other links of the tree
_SUPPORT_FACE, _SUPPORT_EDGE = "#fdd0a2", "#7f2704"
_LIMIT = "#cb181d"
_AXES = (("x", "#a50f15", "-"), ("y", "#006d2c", "--"), ("z", "#08306b", ":"))
_VALID, _BLOCKED = "#08519c", "#969696"
_LIMIT_TOL = 1e-9  # rad (or m): a joint this far beyond a bound is still within it
_FAR = 1e6  # m (or s): coordinates beyond this are refused; a plot that far out loses its precision
_LEVEL = np.zeros(6)  # a body pose, to check an Euler sequence with


# ---- argument checks ------------------------------------------------------------------------------------


def _check_robot(value) -> Robot:
    if not isinstance(value, Robot):
        raise TypeError(
            f"robot must be an sk.Robot (sk.Spot(), sk.Robot.from_urdf(...)), got {type(value).__name__}"
        )
    return value


def _vector(value: ArrayLike, name: str, n: int) -> np.ndarray:
    """A finite (n,) float64 array, or ValueError/TypeError naming the argument."""
    array = as_real(value, name, np.float64)
    if array.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite to be drawn, got {array.tolist()}")
    return array


def _batch(value: ArrayLike, name: str, n: int, frames: int | None) -> np.ndarray:
    """(frames, n) finite float64 rows from (n,) (shared by every frame) or (frames, n)."""
    array = as_real(value, name, np.float64)
    if array.shape == (n,) and frames is not None:
        array = np.broadcast_to(array, (frames, n))
    if array.ndim != 2 or array.shape[1] != n or (frames is not None and array.shape[0] != frames):
        expected = f"({n},) or ({frames}, {n})" if frames is not None else f"(K, {n})"
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite to be drawn")
    return array


def _single_pose(body_pose: ArrayLike, seq: str) -> np.ndarray:
    """The world <- body transform (4, 4) of one body pose, or ValueError."""
    pose = as_real(body_pose, "body_pose", np.float64)
    if pose.shape not in ((6,), (7,), (4, 4)):
        raise ValueError(
            "body_pose must be one pose: (6,) [x, y, z, a, b, c], (7,) [x, y, z, qx, qy, qz, qw] "
            f"or (4, 4), got shape {pose.shape}"
        )
    T = body_transform(pose, seq)
    if not np.isfinite(T).all():
        raise ValueError("body_pose must be a finite rigid transform (a unit quaternion, a rotation matrix)")
    return T


def _poses(body_poses: ArrayLike, seq: str) -> np.ndarray:
    """(K, 4, 4) world <- body transforms of K >= 1 body poses, or ValueError."""
    pose = as_real(body_poses, "body_poses", np.float64)
    if not (pose.ndim == 2 and pose.shape[1] in (6, 7)) and not (pose.ndim == 3 and pose.shape[1:] == (4, 4)):
        raise ValueError(
            "body_poses must have shape (K, 6) [x, y, z, a, b, c], (K, 7) [x, y, z, qx, qy, qz, qw] "
            f"or (K, 4, 4), got {pose.shape}"
        )
    if pose.shape[0] < 1:
        raise ValueError("body_poses must hold at least one pose")
    T = body_transform(pose, seq)
    if not np.isfinite(T).all():
        raise ValueError("body_poses must be finite rigid transforms (unit quaternions, rotation matrices)")
    return T


def _near(values: np.ndarray, name: str, what: str) -> None:
    """ValueError naming the argument when drawn coordinates lie beyond :data:`_FAR`."""
    if not (np.abs(values) <= _FAR).all():
        raise ValueError(f"{name} puts {what} beyond {_FAR:g} from the origin: too far to be drawn")


def _check_seq(seq) -> str:
    body_transform(_LEVEL, seq)  # the sequence is read first: ValueError naming seq
    return seq


def _check_ax(ax, three_d: bool):
    if ax is None:
        return None
    if not isinstance(ax, Axes):
        raise TypeError(f"ax must be a matplotlib Axes, got {type(ax).__name__}")
    if three_d != (getattr(ax, "name", "") == "3d"):
        wanted = "a 3D Axes (fig.add_subplot(projection='3d'))" if three_d else "a 2D Axes"
        raise ValueError(f"ax must be {wanted}, got a {getattr(ax, 'name', '?')!r} Axes")
    return ax


def _check_fig(fig):
    if fig is None:
        return None
    if not isinstance(fig, Figure):
        raise TypeError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    fig.clear()
    return fig


def _check_title(title):
    if title is not None and not isinstance(title, str):
        raise TypeError(f"title must be a str or None, got {type(title).__name__}")
    return title


def _positive(value, name: str) -> float:
    number = as_scalar(value, name)
    if not (math.isfinite(number) and number > 0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return number


# ---- axes ----------------------------------------------------------------------------------------------


def _equal_3d(ax, points: np.ndarray, pad: float = 0.05) -> None:
    """Axis limits around points with one scale on every axis."""
    points = points[np.isfinite(points).all(axis=1)]
    if len(points) == 0:
        return
    low, high = points.min(axis=0), points.max(axis=0)
    span = max(float((high - low).max()), 1e-3)
    margin = pad * span + 1e-3
    low, high = low - margin, high + margin
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_zlim(low[2], high[2])
    ax.set_box_aspect(tuple(high - low))


def _label_3d(ax, fontsize: float | None = None) -> None:
    ax.set_xlabel("x (m)", fontsize=fontsize)
    ax.set_ylabel("y (m)", fontsize=fontsize)
    ax.set_zlabel("z (m)", fontsize=fontsize)


def _sparse_ticks(ax, most: int = 4) -> None:
    """At most ``most`` ticks on the longest axis of a 3D panel and proportionally fewer (at least 2) on
    the shorter ones, so that the tick labels of a short axis do not run into each other."""
    spans = np.array([abs(high - low) for low, high in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())])
    longest = max(float(spans.max()), 1e-12)
    for axis, span in zip((ax.xaxis, ax.yaxis, ax.zaxis), spans):
        axis.set_major_locator(MaxNLocator(nbins=max(1, round(most * span / longest)), min_n_ticks=2))


def _frame_axes(ax, T: np.ndarray, length: float, style: str, gid: str) -> None:
    if not np.isfinite(T).all():
        return
    for k, (_, colour, _) in enumerate(_AXES):
        segment = np.array([T[:3, 3], T[:3, 3] + length * T[:3, k]])
        ax.plot(*segment.T, color=colour, linestyle=style, linewidth=1.5, gid=gid)


def _limits_2d(points: np.ndarray, pad: float = 0.08) -> tuple[np.ndarray, np.ndarray]:
    points = points[np.isfinite(points).all(axis=1)]
    if len(points) == 0:
        return np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    low, high = points.min(axis=0), points.max(axis=0)
    span = max(float((high - low).max()), 1e-3)
    centre = (low + high) / 2
    half = (high - low) / 2 + pad * span
    return centre - half, centre + half
