"""Pictures of robots and their kinematics, drawn with matplotlib (an optional dependency:
``pip install "spotkin[plot]"``).

- :func:`robot`: a 3D stick figure of any loaded robot (or its side, front or top view): every
  link from joint frame to joint frame, the joints, the feet, the support polygon, the body axes
  and the arm; joints beyond their limits and legs at a singular configuration are marked.
- :func:`branches`: every IK branch of one target side by side (a leg's 4, an arm's 8, a
  3- or 6-joint chain's), the valid ones drawn solid, each with its joint values, the status in
  the title.
- :func:`workspace`: a planar slice of a leg's (or a 3-joint chain's) reach, coloured by the
  number of valid IK branches, from one batched IK call over the grid; the unreachable and
  limit-blocked regions, the singular sets and contours of ``|det J|``.
- :func:`trajectory`: a point-to-point motion's q, qd and qdd against time with the speed and
  acceleration limits, or a Cartesian path's position and velocities.
- :func:`animate`: a matplotlib animation of the robot along a body path (``.save("path.gif")``).

Every function returns the matplotlib Figure it drew in, or draws into an ``ax`` (or ``fig``)
that it is given, so that pictures compose and save as usual (``fig.savefig("stance.png")``).
Figures are made with ``matplotlib.pyplot``, so ``plt.show()`` shows them and ``plt.close(fig)``
frees them; nothing here picks a backend. Colours are chosen to stay distinct in greyscale,
helped by line styles, markers and hatching.
"""

from __future__ import annotations

import io
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

try:
    import matplotlib.pyplot as plt
    from matplotlib.animation import AbstractMovieWriter, FuncAnimation
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d import art3d
    from PIL import Image  # a dependency of matplotlib
except ImportError as _error:  # pragma: no cover - tested in a subprocess with matplotlib blocked
    raise ImportError(
        'spotkin.plot needs matplotlib, an optional dependency: pip install "spotkin[plot]" '
        "(or pip install matplotlib)"
    ) from _error

from .._boundary import as_index, as_real, as_scalar
from .._status import Status
from ..arm import SpotArm
from ..body import body_transform, parse_sequence
from ..chain import Chain
from ..leg import SLOT_NAMES, Leg
from ..robot import Robot
from ..trajectory import CartesianPath, PointToPoint

__all__ = ["animate", "branches", "robot", "trajectory", "workspace"]

# -- style: distinct in greyscale (luminance, line style, marker) -------------------------------------
_BODY_EDGE, _BODY_FACE = "#252525", "#bdbdbd"
_LEG = "#08519c"  # dark blue
_ARM = "#d94801"  # orange, mid grey in greyscale; square joint markers
_OTHER = "#737373"  # other links of the tree
_SUPPORT_FACE, _SUPPORT_EDGE = "#fdd0a2", "#7f2704"
_LIMIT = "#cb181d"
_AXES = (("x", "#a50f15", "-"), ("y", "#006d2c", "--"), ("z", "#08306b", ":"))
_VALID, _BLOCKED = "#08519c", "#969696"
# workspace categories: unreachable, blocked by the limits, 1, 2, 3 or 4 valid branches
_MAP_CODES = (-2, -1, 1, 2, 3)
_MAP_COLOURS = ("#ffffff", "#d9d9d9", "#6baed6", "#2171b5", "#08306b")
_MAP_LABELS = (
    "unreachable (no branch)",
    "branches exist, none within the limits",
    "1 valid branch",
    "2 valid branches",
    "3 or 4 valid branches",
)
_CYCLE_COLOURS = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d", "#666666")
_CYCLE_STYLES = ("-", "--", "-.", ":")
_LEG_JOINTS = ("hip roll", "hip pitch", "knee")
_SPOT_ARM_JOINTS = ("sh0", "sh1", "el0", "el1", "wr0", "wr1")
_LIMIT_TOL = 1e-9  # rad (or m): a joint this far beyond a bound is still within it
_PLANES = {"xz": (0, 2, 1), "yz": (1, 2, 0), "xy": (0, 1, 2)}  # (horizontal, vertical, fixed) axes
# views of a robot: None (3D), else (horizontal, vertical, depth axis, sign of the depth toward the viewer):
# the side view looks from the robot's right (x to the right, z up), the front view from ahead (y to the
# right), the top view from above (x to the right, y up)
_VIEWS = {"3d": None, "side": (0, 2, 1, -1.0), "front": (1, 2, 0, 1.0), "top": (0, 1, 2, 1.0)}
_VIEW_NAMES = {"side": "side view (x–z)", "front": "front view (y–z)", "top": "top view (x–y)"}
_MAX_RESOLUTION = 1000
_FAR = 1e6  # m (or s): coordinates beyond this are refused; a plot that far out loses its precision


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
    parse_sequence(seq)  # ValueError naming seq
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


# ---- geometry ---------------------------------------------------------------------------------------------


def _rx(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _leg_points(leg: Leg, q: np.ndarray) -> np.ndarray:
    """(4, 3) joint origins of a leg in its leg frame: hip roll, hip pitch, knee, foot."""
    hip_pitch = _rx(leg.signs[0] * q[0]) @ leg.a
    return np.array([np.zeros(3), hip_pitch, leg.knee(q), leg.fk(q)])


def _arm_points(arm, q: np.ndarray) -> np.ndarray:
    """(k, 3) joint origins of an arm (or chain) in its base frame, ending at the tool point."""
    if isinstance(arm, Chain):
        return arm.frames(q)[:, :3, 3]
    mount, upper_arm, forearm, forearm_offset, _, _, _ = arm._params
    shoulder = _rz(q[0]) @ _ry(q[1])
    elbow = mount + shoulder @ np.array([upper_arm, 0.0, 0.0])
    wrist = elbow + shoulder @ _ry(q[2]) @ np.array([forearm, 0.0, forearm_offset])
    return np.array([mount, elbow, wrist, arm.fk(q)[:3, 3]])


def _limits_of(solver) -> np.ndarray:
    """(n, 2) joint limits of a leg, a SpotArm or a chain (the solvers' shared ``limits``)."""
    return solver.limits


def _revolute(solver) -> np.ndarray:
    if isinstance(solver, Chain):
        return solver.sigma == 0
    return np.ones(len(_limits_of(solver)), dtype=bool)


def _beyond_limits(q: np.ndarray, limits: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """(..., n) bool: the joint lies outside its limits (a revolute joint also after ±2π)."""
    lower, upper = limits[:, 0], limits[:, 1]

    def inside(value):
        return (value >= lower - _LIMIT_TOL) & (value <= upper + _LIMIT_TOL)

    within = inside(q)
    turn = np.where(revolute, 2 * np.pi, 0.0)
    within |= inside(q + turn) | inside(q - turn)
    return ~within


def _joint_names(solver) -> tuple[str, ...]:
    if isinstance(solver, Leg):
        return _LEG_JOINTS
    if isinstance(solver, SpotArm):
        return _SPOT_ARM_JOINTS
    if solver.joint_names is not None:
        return solver.joint_names
    return tuple(f"q{k + 1}" for k in range(solver.dof))


def _convex_hull(points: np.ndarray) -> np.ndarray:
    """Indices of the 2D convex hull of points (m, 2), counter-clockwise (Andrew's monotone chain)."""
    order = sorted(range(len(points)), key=lambda k: (points[k, 0], points[k, 1]))
    if len(order) <= 2:
        return np.array(order, dtype=int)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def half(indices):
        chain: list[int] = []
        for k in indices:
            while len(chain) >= 2 and cross(points[chain[-2]], points[chain[-1]], points[k]) <= 0:
                chain.pop()
            chain.append(k)
        return chain

    lower, upper = half(order), half(order[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=int)


class _Frame(NamedTuple):
    """One configuration of a robot in the world frame."""

    T: np.ndarray  # (4, 4) world <- body
    outline: np.ndarray  # (m, 3) body outline through the hips (closed polygon, not repeated)
    legs: tuple  # per leg (4, 3): hip roll, hip pitch, knee, foot
    feet: np.ndarray  # (n, 3)
    arm: np.ndarray | None  # (k, 3) arm joint origins ending at the tool point, or None
    tree: np.ndarray  # (s, 2, 3) other links of the URDF tree, joint frame to joint frame
    beyond: np.ndarray  # (b, 3) joints beyond their limits
    singular: np.ndarray  # (c, 3) knees of legs at a singular configuration
    support: np.ndarray  # (h, 3) support polygon: the feet's convex hull on the lowest foot's plane


def _world(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ T[:3, :3].T + T[:3, 3]


def _default_arm_q(arm) -> np.ndarray:
    limits = _limits_of(arm)
    return np.clip(np.zeros(len(limits)), limits[:, 0], limits[:, 1])


def _arm_dof(arm) -> int:
    return arm.dof if isinstance(arm, Chain) else 6


def _joint_values(robot: Robot, q: np.ndarray, q_arm: np.ndarray | None) -> dict:
    """Every actuated joint of the description -> its value: the legs' from q, the arm's from q_arm,
    the others at zero (clipped into their limits)."""
    model = robot.model
    values = {j.name: min(max(0.0, j.lower), j.upper) for j in model.actuated_joints}
    leg_specs, arm_specs = robot._specs
    for spec, columns in zip(leg_specs, robot._columns):
        for name, column in zip(spec.joint_names, columns):
            values[name] = float(q[column])
    if q_arm is not None and arm_specs:
        values.update(zip(arm_specs[0].joint_names, map(float, q_arm)))
    return values


def _tree_segments(robot: Robot, q: np.ndarray, q_arm: np.ndarray | None) -> np.ndarray:
    """(s, 2, 3) body-frame segments from each link's frame to its child joints' frames, for the
    links that are not drawn as a leg or the arm (sensors, rotors, unrecognised limbs)."""
    leg_specs, arm_specs = robot._specs
    model = robot.model
    if model is None or not leg_specs:  # a Spot built from a model dict: its own legs only
        return np.zeros((0, 2, 3))
    drawn = {j.child for spec in leg_specs for j in model.path(spec.foot)}
    if arm_specs and robot.arm is not None:
        drawn |= {j.child for j in model.path(arm_specs[0].tip)}
    values = _joint_values(robot, q, q_arm)
    placements: dict[str, np.ndarray] = {}

    def placement(link):
        if link not in placements:
            placements[link] = model.placement(link, values)
        return placements[link]

    segments = []
    for joint in model.joints:
        if joint.child in drawn:
            continue
        start, end = placement(joint.parent)[:3, 3], placement(joint.child)[:3, 3]
        if np.linalg.norm(end - start) > 1e-9:
            segments.append((start, end))
    return np.array(segments).reshape(-1, 2, 3)


def _frame(robot: Robot, T: np.ndarray, q: np.ndarray, q_arm: np.ndarray | None) -> _Frame:
    hips = robot.hip_positions
    legs, feet, beyond, singular = [], [], [], []
    for k, leg in enumerate(robot.legs):
        q_leg = q[robot._columns[k]]
        points = hips[k] + _leg_points(leg, q_leg)
        legs.append(_world(T, points))
        feet.append(legs[-1][3])
        outside = _beyond_limits(q_leg, leg.limits, np.ones(3, dtype=bool))
        beyond.extend(legs[-1][np.flatnonzero(outside)])  # a joint's origin: hip roll, hip pitch, knee
        sigma = leg.singularity(q_leg)[1]
        if sigma < 1e-3 * max(leg.reach[1], 1e-9):
            singular.append(legs[-1][2])
    arm_points = None
    if q_arm is not None:
        arm = robot.arm
        mount = getattr(robot, "arm_mount", None)  # body <- arm base (the identity when None)
        arm_points = _world(T if mount is None else T @ mount, _arm_points(arm, q_arm))
        outside = _beyond_limits(q_arm, _limits_of(arm), _revolute(arm))
        joints = arm_points[1 : 1 + len(q_arm)] if isinstance(arm, Chain) else arm_points[[0, 0, 1, 2, 2, 2]]
        beyond.extend(joints[np.flatnonzero(outside)])
    centre = hips[:, :2].mean(axis=0)
    angle = np.arctan2(hips[:, 1] - centre[1], hips[:, 0] - centre[0])
    outline = _world(T, hips[np.argsort(angle, kind="stable")])
    feet = np.array(feet).reshape(-1, 3)
    support = feet[_convex_hull(feet[:, :2])].copy()
    support[:, 2] = feet[:, 2].min()
    tree = _tree_segments(robot, q, q_arm)
    tree = _world(T, tree.reshape(-1, 3)).reshape(-1, 2, 3)
    return _Frame(
        T,
        outline,
        tuple(legs),
        feet,
        arm_points,
        tree,
        np.array(beyond).reshape(-1, 3),
        np.array(singular).reshape(-1, 3),
        support,
    )


def _nominal_stance(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """A standing configuration (body_pose (6,), q (3 n,)): the feet below the hips at about 70 % of
    the legs' reach, every leg solved by body_ik; or, when no such stance solves, the zero angles
    (clipped into the limits) with the lowest foot on the ground z = 0."""
    hips = robot.hip_positions
    radius = getattr(robot, "_foot_radius", 0.0)
    for fraction in (0.7, 0.75, 0.65, 0.8, 0.6, 0.85, 0.55, 0.9, 0.5):
        height = (
            min(fraction * leg.reach[1] - hips[k, 2] - leg.a[2] for k, leg in enumerate(robot.legs)) + radius
        )
        pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0])
        try:
            feet = robot.stance_feet(height)
        except ValueError:
            continue
        result = robot.body_ik(pose, feet)
        if (result.status == Status.OK).all():
            return pose, result.q
    return _zero_stance(robot)


def _zero_stance(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """(body_pose (6,), q (3 n,)): every leg joint at zero (clipped into its limits), the body level
    with the lowest foot on the ground z = 0 (the foot sphere's centre at its radius, for Spot)."""
    radius = getattr(robot, "_foot_radius", 0.0)
    q = np.zeros(3 * robot.n_legs)
    for k, leg in enumerate(robot.legs):
        limits = leg.limits
        q[robot._columns[k]] = np.clip(0.0, limits[:, 0], limits[:, 1])
    feet = robot.body_fk(np.zeros(6), q)
    return np.array([0.0, 0.0, radius - feet[:, 2].min(), 0.0, 0.0, 0.0]), q


# ---- drawing a robot ---------------------------------------------------------------------------------------


class _RobotArtists:
    """The artists of one robot in a 3D Axes, or projected on a 2D Axes for a side, front or top view
    (``view``: a key of :data:`_VIEWS`), updated in place (for animations)."""

    def __init__(self, ax, robot: Robot, frame: _Frame, axes_length: float, view: str = "3d"):
        self.ax, self.robot, self.axes_length = ax, robot, axes_length
        self.projection = _VIEWS[view]
        if self.projection is None:
            # a stick figure reads best with the sticks over the translucent faces (the default orders
            # artists by their mean depth, which hides a leg behind the support polygon)
            ax.computed_zorder = False
            polygons = art3d.Poly3DCollection
        else:
            polygons = PolyCollection
        self.body = polygons(
            [self._flat(frame.outline)], facecolor=_BODY_FACE, edgecolor=_BODY_EDGE, linewidths=1.5, alpha=0.6
        )
        self.body.set_gid("body")
        self.body.set_zorder(2)
        self.support = polygons(
            [self._flat(frame.support)],
            facecolor=_SUPPORT_FACE,
            edgecolor=_SUPPORT_EDGE,
            linewidths=1.0,
            linestyles="--",
            alpha=0.5,
        )
        self.support.set_gid("support")
        self.support.set_zorder(1)
        for collection in (self.body, self.support):
            if self.projection is None:
                ax.add_collection3d(collection)
            else:
                ax.add_collection(collection)
        self.tree = [
            self._line(segment, color=_OTHER, linewidth=1.0, linestyle=":", gid="tree", zorder=3)
            for segment in frame.tree
        ]
        self.legs = []
        far = self._far_legs(frame)
        for k, (name, points) in enumerate(zip(robot.leg_names, frame.legs)):
            line = self._line(
                points,
                color=_LEG,
                linewidth=2.5,
                marker="o",
                markersize=4.5,
                markerfacecolor="white",
                markeredgecolor=_LEG,
                gid=f"leg:{name}",
                zorder=3.5 if far[k] else 4,
                alpha=0.45 if far[k] else 1.0,
            )
            self.legs.append(line)
        self.feet = self._line(
            frame.feet, linestyle="none", marker="o", markersize=7, color="black", gid="feet", zorder=5
        )
        self.arm = None
        if frame.arm is not None:
            self.arm = self._line(
                frame.arm,
                color=_ARM,
                linewidth=3.0,
                marker="s",
                markersize=4.5,
                markerfacecolor="white",
                markeredgecolor=_ARM,
                gid="arm",
                zorder=4,
            )
            self.hand = self._line(
                frame.arm[-1:], linestyle="none", marker="D", markersize=6, color=_ARM, gid="hand", zorder=5
            )
        self.beyond = self._line(
            frame.beyond,
            linestyle="none",
            marker="X",
            markersize=10,
            color=_LIMIT,
            gid="beyond-limits",
            zorder=6,
        )
        self.singular = self._line(
            frame.singular,
            linestyle="none",
            marker="*",
            markersize=12,
            markerfacecolor="none",
            markeredgecolor="black",
            gid="singular",
            zorder=6,
        )
        self.axes = []
        for k, (label, colour, style) in enumerate(_AXES):
            segment = self._axis(frame.T, k)
            line = self._line(
                segment, color=colour, linestyle=style, linewidth=1.8, gid=f"body-axis:{label}", zorder=4
            )
            if self.projection is None:
                text = ax.text(*segment[1], label, color=colour, fontsize=9, fontweight="bold")
            else:
                text = ax.text(
                    *self._flat(segment[1:])[0], label, color=colour, fontsize=9, fontweight="bold"
                )
            self.axes.append((line, text))
        self._hide_end_on_axes(frame)

    def _flat(self, points: np.ndarray) -> np.ndarray:
        """Points (m, 3) as drawn: themselves in 3D, their (m, 2) projection on a 2D view."""
        if self.projection is None:
            return points
        return points[:, list(self.projection[:2])]

    def _line(self, points: np.ndarray, **style):
        if self.projection is None:
            return self.ax.plot(*points.T, **style)[0]
        return self.ax.plot(*self._flat(points).T, **style)[0]

    def _set(self, line, points: np.ndarray) -> None:
        if self.projection is None:
            line.set_data_3d(*points.T)
        else:
            line.set_data(*self._flat(points).T)

    def _count(self, line) -> int:
        return len(line.get_data_3d()[0] if self.projection is None else line.get_xdata())

    def _far_legs(self, frame: _Frame) -> np.ndarray:
        """(n,) bool: on a 2D view, the legs whose hips lie behind the body's middle (drawn lighter)."""
        if self.projection is None or not frame.legs:
            return np.zeros(len(frame.legs), dtype=bool)
        _, _, depth, sign = self.projection
        hips = np.array([points[0, depth] for points in frame.legs]) * sign
        return hips < hips.mean() - 1e-9

    def _hide_end_on_axes(self, frame: _Frame) -> None:
        """On a 2D view, the label of a body axis that points at the viewer (or away) is hidden."""
        if self.projection is None:
            return
        for k, (_, text) in enumerate(self.axes):
            drawn = np.ptp(self._flat(self._axis(frame.T, k)), axis=0)
            text.set_visible(bool(np.hypot(*drawn) > 0.25 * self.axes_length))

    def _axis(self, T: np.ndarray, k: int) -> np.ndarray:
        origin = T[:3, 3]
        return np.array([origin, origin + self.axes_length * T[:3, k]])

    def update(self, frame: _Frame) -> None:
        self.body.set_verts([self._flat(frame.outline)])
        self.support.set_verts([self._flat(frame.support)])
        for line, segment in zip(self.tree, frame.tree):
            self._set(line, segment)
        for line, points in zip(self.legs, frame.legs):
            self._set(line, points)
        self._set(self.feet, frame.feet)
        if self.arm is not None and frame.arm is not None:
            self._set(self.arm, frame.arm)
            self._set(self.hand, frame.arm[-1:])
        self._set(self.beyond, frame.beyond)
        self._set(self.singular, frame.singular)
        for k, (line, text) in enumerate(self.axes):
            segment = self._axis(frame.T, k)
            self._set(line, segment)
            if self.projection is None:
                text.set_position_3d(segment[1])
            else:
                text.set_position(self._flat(segment[1:])[0])
        self._hide_end_on_axes(frame)

    def handles(self, extra=()) -> list:
        """The legend's entries."""
        handles = [
            Patch(facecolor=_BODY_FACE, edgecolor=_BODY_EDGE, label="body (through the hips)"),
            Line2D(
                [],
                [],
                color=_LEG,
                linewidth=2.5,
                marker="o",
                markerfacecolor="white",
                label="legs, joint to joint",
            ),
        ]
        if self.projection is not None and any(line.get_alpha() < 1 for line in self.legs):
            handles.append(
                Line2D(
                    [],
                    [],
                    color=_LEG,
                    linewidth=2.5,
                    marker="o",
                    markerfacecolor="white",
                    alpha=0.45,
                    label="legs on the far side",
                )
            )
        handles += [
            Line2D([], [], color="black", linestyle="none", marker="o", label="feet"),
            Patch(facecolor=_SUPPORT_FACE, edgecolor=_SUPPORT_EDGE, linestyle="--", label="support polygon"),
        ]
        if self.arm is not None:
            handles.append(
                Line2D(
                    [],
                    [],
                    color=_ARM,
                    linewidth=3,
                    marker="s",
                    markerfacecolor="white",
                    label="arm, joint to joint",
                )
            )
        if self.tree:
            handles.append(Line2D([], [], color=_OTHER, linestyle=":", label="other links (URDF)"))
        handles.append(Line2D([], [], color="black", linestyle="-", label="body axes x, y (--), z (:)"))
        if self._count(self.beyond):
            handles.append(
                Line2D(
                    [],
                    [],
                    color=_LIMIT,
                    linestyle="none",
                    marker="X",
                    markersize=9,
                    label="joint beyond its limits",
                )
            )
        if self._count(self.singular):
            handles.append(
                Line2D(
                    [],
                    [],
                    color="black",
                    linestyle="none",
                    marker="*",
                    markerfacecolor="none",
                    markersize=11,
                    label="leg at a singular configuration",
                )
            )
        handles.extend(extra)
        return handles

    def legend(self, extra=(), fontsize: float = 7, outside: bool = False) -> None:
        """The legend: beside the axes, right of their box (``outside``: the figure leaves room for it), or
        in the axes' upper left corner (a 2D view: where it hides the least of the drawing)."""
        handles = self.handles(extra)
        if outside:  # in figure coordinates, by the box as drawn (a 3D Axes' labels spill out of it)
            self.ax.apply_aspect()
            box = self.ax.get_position()
            right = self.ax.get_position(original=True).x1 if self.projection is None else box.x1
            self.ax.legend(
                handles=handles,
                loc="upper left",
                bbox_to_anchor=(right + 0.01, box.y1),
                bbox_transform=self.ax.figure.transFigure,
                fontsize=fontsize,
                frameon=False,
            )
        else:
            where = "upper left" if self.projection is None else "best"
            self.ax.legend(handles=handles, loc=where, fontsize=fontsize, framealpha=0.85)


def _frame_points(frame: _Frame) -> np.ndarray:
    parts = [frame.outline, frame.feet, frame.support, frame.T[:3, 3][None], frame.tree.reshape(-1, 3)]
    parts += list(frame.legs)
    if frame.arm is not None:
        parts.append(frame.arm)
    return np.concatenate(parts)


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


_NAME_SUFFIXES = ("description", "robot", "urdf")


def _sparse_ticks(ax, most: int = 4) -> None:
    """At most ``most`` ticks on the longest axis of a 3D panel and proportionally fewer (at least 2) on
    the shorter ones, so that the tick labels of a short axis do not run into each other."""
    spans = np.array([abs(high - low) for low, high in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())])
    longest = max(float(spans.max()), 1e-12)
    for axis, span in zip((ax.xaxis, ax.yaxis, ax.zaxis), spans):
        axis.set_major_locator(MaxNLocator(nbins=max(1, round(most * span / longest)), min_n_ticks=2))


def _q_text(solver, q: np.ndarray) -> str:
    """A branch's joints as its panel prints them: revolute joints in degrees (0.1°), prismatic ones in
    metres (1 mm)."""
    values = [f"{math.degrees(v):.1f}°" if turn else f"{v:.3f} m" for v, turn in zip(q, _revolute(solver))]
    return "q = (" + ", ".join(values) + ")"


def _q_label(ax, solver, q: np.ndarray, slot: int, valid: bool) -> None:
    """The branch's joints (:func:`_q_text`) at the top of its panel (a 3D panel), or just above it
    (below its title, a 2D panel), id ``"q:SLOT"``."""
    three_d = getattr(ax, "name", "") == "3d"
    (ax.text2D if three_d else ax.text)(
        0.5,
        1.0 if three_d else 1.015,
        _q_text(solver, q),
        transform=ax.transAxes,
        ha="center",
        va="top" if three_d else "bottom",
        fontsize=6.5,
        color=_VALID if valid else "#525252",
        gid=f"q:{slot}",
    )


def _robot_name(robot: Robot) -> str:
    """The robot's name as titles show it: its description's ``<robot name=...>`` without a trailing
    ``_description``, ``_robot`` or ``_urdf`` (also after ``-`` or a space, any case, repeatedly),
    underscores and hyphens read as spaces, the first letter capitalised ("go2_description" -> "Go2",
    "spot" -> "Spot", "anymal_c_robot" -> "Anymal c"); the class name ("Robot") when nothing is left."""
    words = (robot.name or "").replace("_", " ").replace("-", " ").split()
    while words and words[-1].lower() in _NAME_SUFFIXES:
        words.pop()
    if not words:
        return type(robot).__name__
    name = " ".join(words)
    return name[0].upper() + name[1:]


def _check_view(view) -> str:
    if not isinstance(view, str):
        raise TypeError(f"view must be a str, one of {tuple(_VIEWS)}, got {type(view).__name__}")
    if view not in _VIEWS:
        raise ValueError(f"view must be one of {tuple(_VIEWS)}, got {view!r}")
    return view


def _frame_2d(ax, points: np.ndarray, ground: float | None, pad: float = 0.06) -> None:
    """Limits of a 2D view around the drawn points (m, 2), one scale on both axes, and the ground line."""
    low, high = _limits_2d(points, pad)
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_aspect("equal", adjustable="box")
    if ground is not None:
        ax.axhline(ground, color="#525252", linewidth=1.0, zorder=0, gid="ground")
    ax.grid(True, linewidth=0.3)


def _description(ax, model, values: dict, title: str | None = None) -> None:
    """Draw a URDF tree that has no legs (an arm, a gripper, a head) into the 3D ``ax`` at the joint
    values ``values`` (actuated joint name -> value; mimic joints follow their leaders, joints not named
    are at 0): every link from its parent's frame to its own (grey), the chain from the root to each tip
    (:func:`spotkin._urdf_chain.tip_candidates`) with its joints (orange squares, mimic joints hollow), the
    root's axes and each tip's frame. Used by ``spotkin plot`` for descriptions without legs."""
    from .._urdf_chain import tip_candidates

    placements = {link: model.placement(link, values) for link in model.links}
    points = np.array([T[:3, 3] for T in placements.values()])
    span = float(np.ptp(points, axis=0).max()) if len(points) > 1 else 0.1
    span = max(span, 0.05)
    for joint in model.joints:
        start, end = placements[joint.parent][:3, 3], placements[joint.child][:3, 3]
        if np.linalg.norm(end - start) > 1e-9:
            ax.plot(*np.array([start, end]).T, color=_OTHER, linewidth=1.2, gid="tree")
    tips = tip_candidates(model)
    for tip in tips:
        path = model.path(tip)
        line = np.array([placements[model.root][:3, 3]] + [placements[j.child][:3, 3] for j in path])
        ax.plot(*line.T, color=_ARM, linewidth=2.5, gid=f"chain:{tip}")
        for j in path:
            if j.type == "fixed":
                continue
            p = placements[j.child][:3, 3]
            face = "white" if j.mimic is not None else _ARM
            ax.plot(*p[:, None], linestyle="none", marker="s", markersize=6, color=_ARM, markerfacecolor=face)
        _frame_axes(ax, placements[tip], 0.12 * span, "-", f"tip:{tip}")
    for j in model.mimic_joints:
        if not any(j in model.path(tip) for tip in tips):
            p = placements[j.child][:3, 3]
            ax.plot(
                *p[:, None], linestyle="none", marker="s", markersize=5, color=_ARM, markerfacecolor="white"
            )
    _frame_axes(ax, np.eye(4), 0.2 * span, ":", "root")
    _equal_3d(ax, points)
    _sparse_ticks(ax)
    _label_3d(ax)
    handles = [
        Line2D([], [], color=_ARM, linewidth=2.5, marker="s", label="chain to a tip, its joints"),
        Line2D(
            [], [], color=_ARM, linestyle="none", marker="s", markerfacecolor="white", label="mimic joint"
        ),
        Line2D([], [], color=_OTHER, linewidth=1.2, label="other links"),
        Line2D([], [], color="black", linestyle=":", label=f"root frame ({model.root})"),
    ]
    ax.legend(handles=handles, loc="upper left", fontsize=7)
    if title is not None:
        ax.set_title(title, fontsize=10)


def robot(
    robot: Robot,
    body_pose: ArrayLike | None = None,
    q: ArrayLike | None = None,
    q_arm: ArrayLike | None = None,
    seq: str = "XYZ",
    ax=None,
    title: str | None = None,
    view: str = "3d",
) -> Figure:
    """A stick figure of ``robot`` at one configuration, in the world frame: in 3D, or seen from the side,
    the front or above.

    Drawn: the body (a polygon through the hip-roll joints), each leg from joint frame to joint
    frame (hip roll, hip pitch, knee, foot), the feet, the support polygon (the feet's convex
    hull, on the plane of the lowest foot), the body axes (x solid, y dashed, z dotted), the arm
    when the robot has one, and every other link of the URDF tree (sensors, rotors, limbs that are
    not recognised as legs) from its frame to its child joints' frames. Joints beyond their limits
    are marked with a cross, legs at a singular configuration (smallest singular value of the
    Jacobian below 1e-3 of the leg's reach) with a star.

    Parameters
    ----------
    robot:
        An :class:`spotkin.Robot` (``sk.Spot()``, ``sk.Robot.from_urdf(...)``).
    body_pose:
        One body pose, (6,) [x, y, z, a, b, c] with Euler angles in ``seq``, (7,) [x, y, z, qx, qy,
        qz, qw] or (4, 4). Default: a nominal stance (the feet below the hips at about 70 % of the
        legs' reach, solved by ``body_ik``; the zero angles when no such stance solves).
    q:
        (3 n,) leg joints in the order of ``robot.leg_joint_names``. Default: the nominal stance's.
    q_arm:
        The arm's joints (6,), for a robot with an arm. Default: zero angles clipped into the limits.
        Other joints of the description (grippers, rotors) are drawn at zero, clipped into their limits.
    seq:
        The Euler sequence of a (6,) ``body_pose``.
    ax:
        An Axes to draw in: 3D (``fig.add_subplot(projection="3d")``) for ``view="3d"``, 2D for the
        other views; default: a new figure of 8 x 6 in, the legend beside the drawing on its right
        (in a given ``ax``, the legend goes in its upper left corner, or where it hides the least on a
        2D view).
    title:
        The title; default: the robot's name (its description's name made readable: "Go2" for
        "go2_description") and the body pose.
    view:
        ``"3d"`` (default); ``"side"``: projected on the world's x–z plane, seen from the robot's right
        (x to the right); ``"front"``: on the y–z plane, seen from ahead (y to the right); ``"top"``: on
        the x–y plane, seen from above. The 2D views use one scale on both axes, draw the ground (the
        plane of the lowest foot) as a line in the side and front views, and draw the legs on the far
        side lighter.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn in. Its artists carry ids (``get_gid()``): ``"feet"``, ``"leg:NAME"``,
        ``"arm"``, ``"hand"``, ``"body"``, ``"support"``, ``"tree"``, ``"beyond-limits"``, ``"singular"``
        (and ``"ground"`` on the side and front views); their data are world coordinates (x, y, z) in
        3D, the view's two coordinates on a 2D view.

    Raises ``TypeError`` for a non-robot, non-numeric arrays, a non-Axes ``ax`` or a non-str ``view``;
    ``ValueError`` for a wrong shape, NaN or Inf, a body pose that is not a rigid transform or puts the
    robot beyond 1e6 m from the origin (too far to draw precisely), an unknown ``seq`` or ``view``, an
    ``ax`` of the other kind (2D for ``"3d"``, 3D for a 2D view), or ``q_arm`` for a robot without an
    arm.
    """
    robot = _check_robot(robot)
    seq = _check_seq(seq)
    view = _check_view(view)
    flat = _VIEWS[view] is not None
    ax = _check_ax(ax, three_d=not flat)
    title = _check_title(title)
    nominal = None
    if body_pose is None or q is None:
        nominal = _nominal_stance(robot)
    T = _single_pose(nominal[0] if body_pose is None else body_pose, seq)
    q = nominal[1] if q is None else _vector(q, "q", 3 * robot.n_legs)
    arm = robot.arm
    if q_arm is not None and arm is None:
        raise ValueError("q_arm was given but this robot has no arm")
    if arm is not None:
        q_arm = _default_arm_q(arm) if q_arm is None else _vector(q_arm, "q_arm", _arm_dof(arm))
    frame = _frame(robot, T, q, q_arm)
    _near(_frame_points(frame), "body_pose", "the robot")
    points = _frame_points(frame)
    outside = ax is None
    if ax is None:
        fig = plt.figure(figsize=(8, 6))
        ax = fig.add_axes(
            (0.01, 0.03, 0.72, 0.88) if not flat else (0.1, 0.1, 0.63, 0.8), projection=None if flat else "3d"
        )
    span = float(np.ptp(points, axis=0).max())
    artists = _RobotArtists(ax, robot, frame, 0.15 * span, view)
    ends = np.concatenate([points, artists._axis(T, 0), artists._axis(T, 1), artists._axis(T, 2)])
    if flat:
        ground = None if view == "top" else float(frame.feet[:, 2].min()) if len(frame.feet) else None
        _frame_2d(ax, artists._flat(ends), ground)
        names = "xyz"
        i, j = _VIEWS[view][:2]
        ax.set_xlabel(f"{names[i]} (m)")
        ax.set_ylabel(f"{names[j]} (m)")
    else:
        _equal_3d(ax, ends)
        _label_3d(ax)
        _sparse_ticks(ax, 7)
    artists.legend(outside=outside)
    if title is None:
        position = ", ".join(f"{v:.3f}" for v in T[:3, 3])
        seen = f", {_VIEW_NAMES[view]}" if flat else ""
        title = f"{_robot_name(robot)}: body at ({position}) m{seen}"
    ax.set_title(title)
    return ax.figure


# ---- IK branches ------------------------------------------------------------------------------------------


def _arm_slot_name(slot: int) -> str:
    shoulder = ("front", "back")[slot // 4]
    elbow = ("up", "down")[slot // 2 % 2]
    wrist = ("wr0 ≥ 0", "wr0 < 0")[slot % 2]
    return f"{shoulder} shoulder, elbow {elbow}, {wrist}"


def _solve_all(solver, target: ArrayLike):
    """(solutions, target as drawn (3,) point or (4, 4) pose, slot names)."""
    value = as_real(target, "target", np.float64)
    if isinstance(solver, Leg) or (isinstance(solver, Chain) and solver.dof == 3):
        if value.shape != (3,):
            raise ValueError(f"target must be one foot or tool point of shape (3,), got {value.shape}")
        if isinstance(solver, Leg):
            return solver.ik_all(value), value, SLOT_NAMES
        sol = solver.ik_position(value)
        return sol, value, tuple(f"solution {k}" for k in range(sol.q.shape[-2]))
    if isinstance(solver, SpotArm) or (isinstance(solver, Chain) and solver.dof == 6):
        if value.shape not in ((4, 4), (7,)):
            raise ValueError(f"target must be one pose of shape (4, 4) or (7,), got {value.shape}")
        if isinstance(solver, SpotArm):
            sol = solver.ik_all(value)
            names = tuple(_arm_slot_name(k) for k in range(8))
        else:
            sol = solver.ik_all(value)
            names = tuple(f"solution {k}" for k in range(sol.q.shape[-2]))
        with np.errstate(all="ignore"):
            pose = (
                body_transform(np.where(np.isfinite(value), value, np.nan)) if value.shape == (7,) else value
            )
        return sol, pose, names
    if isinstance(solver, Chain):
        raise ValueError(
            f"branches draws 3- and 6-joint chains (closed-form IK), this chain has {solver.dof} joints"
        )
    raise TypeError(f"solver must be an sk.Leg, an sk.SpotArm or an sk.Chain, got {type(solver).__name__}")


def _panel_state(sol, slot: int, solver, names) -> tuple[str, bool, bool]:
    """(text, exists, valid) of one slot."""
    if not sol.exists[slot]:
        return "no solution", False, False
    if sol.valid[slot]:
        return "valid", True, True
    outside = _beyond_limits(sol.q[slot], _limits_of(solver), _revolute(solver))
    joints = ", ".join(name for name, out in zip(names, outside) if out) or "a joint"
    return f"beyond limits: {joints}", True, False


def _limits_2d(points: np.ndarray, pad: float = 0.08) -> tuple[np.ndarray, np.ndarray]:
    points = points[np.isfinite(points).all(axis=1)]
    if len(points) == 0:
        return np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    low, high = points.min(axis=0), points.max(axis=0)
    span = max(float((high - low).max()), 1e-3)
    centre = (low + high) / 2
    half = (high - low) / 2 + pad * span
    return centre - half, centre + half


def _branches_leg(fig, solver: Leg, sol, target: np.ndarray, names) -> None:
    slots = sol.q.shape[0]
    axes = fig.subplots(2, slots, squeeze=False)
    points = [_leg_points(solver, sol.q[k]) for k in range(slots) if sol.exists[k]]
    everything = np.concatenate([np.zeros((1, 3)), target[None], *points]) if points else target[None]
    h = abs(solver.hip_offset)
    circle = h * np.array([[math.cos(t), math.sin(t)] for t in np.linspace(0, 2 * math.pi, 121)])
    views = (((0, 2), "side view (x–z)", "x (m)"), ((1, 2), "front view (y–z)", "y (m)"))
    for row, ((i, j), view, xlabel) in enumerate(views):
        low, high = _limits_2d(
            np.concatenate([everything[:, [i, j]], circle if i == 1 else np.zeros((0, 2))])
        )
        for slot in range(slots):
            ax = axes[row, slot]
            text, exists, valid = _panel_state(sol, slot, solver, _LEG_JOINTS)
            if i == 0:
                ax.axhline(0.0, color="black", linewidth=0.8, linestyle="-.", label="hip-roll axis")
            else:
                ax.plot(*circle.T, color="black", linewidth=0.8, linestyle=":", label="hip-roll cylinder")
            if exists:
                p = _leg_points(solver, sol.q[slot])[:, [i, j]]
                ax.plot(
                    *p.T,
                    color=_VALID if valid else _BLOCKED,
                    linestyle="-" if valid else "--",
                    linewidth=2.5 if valid else 1.8,
                    marker="o",
                    markerfacecolor="white",
                    label="valid branch" if valid else "beyond the limits",
                    gid=f"slot:{slot}",
                )
            else:
                ax.text(0.5, 0.5, "no solution", transform=ax.transAxes, ha="center", va="center", fontsize=9)
            ax.plot(
                *target[[i, j]],
                linestyle="none",
                marker="*",
                markersize=13,
                markerfacecolor="none",
                markeredgecolor="black",
                label="target",
            )
            ax.plot(0.0, 0.0, linestyle="none", marker="+", markersize=9, color="black")
            ax.set_xlim(low[0], high[0])
            ax.set_ylim(low[1], high[1])
            ax.set_aspect("equal", adjustable="box")
            ax.tick_params(labelsize=7)
            ax.set_xlabel(xlabel, fontsize=8)
            if slot == 0:
                ax.set_ylabel(f"{view}\nz (m)", fontsize=8)
            if row == 0:
                mark = "✓ " if valid else ""
                ax.set_title(
                    f"slot {slot}: {names[slot]}\n{mark}{text}",
                    fontsize=8,
                    fontweight="bold" if valid else "normal",
                    pad=14,
                )
                if exists:
                    _q_label(ax, solver, sol.q[slot], slot, valid)
    handles = [
        Line2D(
            [], [], color=_VALID, linewidth=2.5, marker="o", markerfacecolor="white", label="valid branch"
        ),
        Line2D(
            [],
            [],
            color=_BLOCKED,
            linestyle="--",
            linewidth=1.8,
            marker="o",
            markerfacecolor="white",
            label="branch beyond the joint limits",
        ),
        Line2D(
            [],
            [],
            linestyle="none",
            marker="*",
            markersize=12,
            markerfacecolor="none",
            markeredgecolor="black",
            label="target foot",
        ),
        Line2D([], [], color="black", linestyle="-.", linewidth=0.8, label="hip-roll axis"),
        Line2D([], [], color="black", linestyle=":", linewidth=0.8, label="hip-roll cylinder (singular)"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)


def _frame_axes(ax, T: np.ndarray, length: float, style: str, gid: str) -> None:
    if not np.isfinite(T).all():
        return
    for k, (_, colour, _) in enumerate(_AXES):
        segment = np.array([T[:3, 3], T[:3, 3] + length * T[:3, k]])
        ax.plot(*segment.T, color=colour, linestyle=style, linewidth=1.5, gid=gid)


def _branches_arm(fig, solver, sol, T: np.ndarray, names) -> None:
    slots = sol.q.shape[0]
    columns = min(4, slots)
    rows = -(-slots // columns)
    joint_names = _joint_names(solver)
    points = {k: _arm_points(solver, sol.q[k]) for k in range(slots) if sol.exists[k]}
    base = _arm_points(solver, _default_arm_q(solver))[0]
    cloud = [base[None], T[:3, 3][None], *points.values()]
    cloud = np.concatenate(cloud)
    cloud = cloud[np.isfinite(cloud).all(axis=1)]
    span = float(np.ptp(cloud, axis=0).max()) if len(cloud) else 1.0
    for slot in range(slots):
        ax = fig.add_subplot(rows, columns, slot + 1, projection="3d")
        text, exists, valid = _panel_state(sol, slot, solver, joint_names)
        if exists:
            p = points[slot]
            ax.plot(
                *p.T,
                color=_VALID if valid else _BLOCKED,
                linestyle="-" if valid else "--",
                linewidth=2.5 if valid else 1.8,
                marker="s",
                markersize=3.5,
                markerfacecolor="white",
                gid=f"slot:{slot}",
            )
            hand = solver.fk(sol.q[slot])
            _frame_axes(ax, hand, 0.12 * span, "-", "hand")
        else:
            ax.text2D(0.5, 0.5, "no solution", transform=ax.transAxes, ha="center", va="center", fontsize=9)
        _frame_axes(ax, T, 0.2 * span, ":", "target")
        ax.plot(*base[:, None], linestyle="none", marker="^", markersize=7, color="black")
        _equal_3d(ax, cloud)
        _label_3d(ax, 7)
        ax.tick_params(labelsize=6)
        _sparse_ticks(ax)
        if exists:
            _q_label(ax, solver, sol.q[slot], slot, valid)
        mark = "✓ " if valid else ""
        ax.set_title(
            f"slot {slot}: {names[slot]}\n{mark}{text}", fontsize=8, fontweight="bold" if valid else "normal"
        )
    handles = [
        Line2D(
            [], [], color=_VALID, linewidth=2.5, marker="s", markerfacecolor="white", label="valid solution"
        ),
        Line2D(
            [],
            [],
            color=_BLOCKED,
            linestyle="--",
            linewidth=1.8,
            marker="s",
            markerfacecolor="white",
            label="solution beyond the joint limits",
        ),
        Line2D([], [], color="black", linestyle=":", label="target frame (x, y, z)"),
        Line2D([], [], color="black", linestyle="-", label="the solution's tool frame"),
        Line2D([], [], color="black", linestyle="none", marker="^", label="base (mount)"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)


def branches(solver, target: ArrayLike, fig=None) -> Figure:
    """Every IK branch of one target, side by side, with its status.

    ``solver`` is an :class:`spotkin.Leg` (``target``: a foot point (3,) in the leg frame; the 4
    slots, each in a side view x–z and a front view y–z), an :class:`spotkin.SpotArm` (``target``: a
    tool pose (4, 4) or (7,) in the body frame; the 8 slots in 3D), or an :class:`spotkin.Chain` with a
    closed form: 3 joints (``target`` (3,), :meth:`Chain.ik_position`) or 6 with a spherical wrist
    (``target`` (4, 4) or (7,), :meth:`Chain.ik`). Valid branches are drawn solid and marked "✓";
    branches beyond the joint limits dashed, naming the joints; a slot without a solution says so. The
    figure's title gives the status (:class:`spotkin.Status`): an unreachable target, or NaN in it, is
    drawn with its status and no branch.

    ``fig``: a Figure to draw in (its contents are replaced); default: a new figure. Returns the figure.
    Each branch's line has the id ``"slot:K"``.

    Raises ``TypeError`` for another solver, non-numeric targets or a non-Figure ``fig``, and
    ``ValueError`` for a target of another shape (one target only) or beyond 1e6 from the origin, or a
    chain without a closed form.
    """
    sol, drawn_target, names = _solve_all(solver, target)
    point = drawn_target if drawn_target.shape == (3,) else drawn_target[:3, 3]
    _near(point[np.isfinite(point)], "target", "the target")
    fig = _check_fig(fig)
    arm = not (isinstance(solver, Leg) or (isinstance(solver, Chain) and solver.dof == 3))
    if fig is None:
        fig = plt.figure(figsize=(12, 6.5) if not arm else (13, 7))
    if arm:
        _branches_arm(fig, solver, sol, drawn_target, names)
        what = f"tool position ({', '.join(f'{v:.3f}' for v in drawn_target[:3, 3])}) m"
    else:
        if isinstance(solver, Leg):
            _branches_leg(fig, solver, sol, drawn_target, names)
        else:
            _branches_chain3(fig, solver, sol, drawn_target, names)
        what = f"target ({', '.join(f'{v:.3f}' for v in drawn_target)}) m"
    status = Status(int(sol.status))
    label = solver.name if isinstance(solver, Leg) and solver.name else type(solver).__name__
    count = f"{int(sol.valid.sum())} of {int(sol.exists.sum())} solutions within the limits"
    fig.suptitle(f"{label} IK, every branch: {what}; status {status.name}, {count}", fontsize=10)
    fig.subplots_adjust(bottom=0.12, top=0.86, wspace=0.35, hspace=0.45)
    return fig


def _branches_chain3(fig, solver: Chain, sol, target: np.ndarray, names) -> None:
    slots = sol.q.shape[0]
    joint_names = _joint_names(solver)
    points = {k: _arm_points(solver, sol.q[k]) for k in range(slots) if sol.exists[k]}
    base = solver.base[:3, 3]
    cloud = np.concatenate([base[None], target[None], *points.values()])
    cloud = cloud[np.isfinite(cloud).all(axis=1)]
    for slot in range(slots):
        ax = fig.add_subplot(1, slots, slot + 1, projection="3d")
        text, exists, valid = _panel_state(sol, slot, solver, joint_names)
        if exists:
            ax.plot(
                *points[slot].T,
                color=_VALID if valid else _BLOCKED,
                linestyle="-" if valid else "--",
                linewidth=2.5 if valid else 1.8,
                marker="o",
                markerfacecolor="white",
                gid=f"slot:{slot}",
            )
        else:
            ax.text2D(0.5, 0.5, "no solution", transform=ax.transAxes, ha="center", va="center", fontsize=9)
        ax.plot(
            *target[:, None],
            linestyle="none",
            marker="*",
            markersize=13,
            markerfacecolor="none",
            markeredgecolor="black",
        )
        ax.plot(*base[:, None], linestyle="none", marker="^", markersize=7, color="black")
        _equal_3d(ax, cloud)
        _label_3d(ax, 7)
        ax.tick_params(labelsize=6)
        _sparse_ticks(ax)
        if exists:
            _q_label(ax, solver, sol.q[slot], slot, valid)
        mark = "✓ " if valid else ""
        ax.set_title(f"{names[slot]}\n{mark}{text}", fontsize=8, fontweight="bold" if valid else "normal")
    handles = [
        Line2D(
            [], [], color=_VALID, linewidth=2.5, marker="o", markerfacecolor="white", label="valid solution"
        ),
        Line2D(
            [],
            [],
            color=_BLOCKED,
            linestyle="--",
            linewidth=1.8,
            marker="o",
            markerfacecolor="white",
            label="solution beyond the joint limits",
        ),
        Line2D(
            [],
            [],
            linestyle="none",
            marker="*",
            markersize=12,
            markerfacecolor="none",
            markeredgecolor="black",
            label="target",
        ),
        Line2D([], [], color="black", linestyle="none", marker="^", label="base"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8, frameon=False)


# ---- workspace maps ---------------------------------------------------------------------------------------


class _Grid(NamedTuple):
    u: np.ndarray  # (nu,) horizontal coordinates
    v: np.ndarray  # (nv,) vertical coordinates
    points: np.ndarray  # (nv, nu, 3)
    code: np.ndarray  # (nv, nu): -2 unreachable, -1 blocked by the limits, else the number of valid branches
    det: np.ndarray  # (nv, nu) |det J| of the first valid (else existing) branch, NaN where none exists


def _reach(solver) -> float:
    if isinstance(solver, Leg):
        return float(np.linalg.norm(solver.a) + solver.reach[1])
    origins = solver.frames(np.zeros(solver.dof))[:, :3, 3]
    reach = float(np.linalg.norm(np.diff(origins, axis=0), axis=1).sum())
    for lower, upper, prismatic in zip(solver.lower, solver.upper, solver.sigma == 1):
        if prismatic:
            reach += max(abs(lower), abs(upper))
    if not math.isfinite(reach):
        raise ValueError("a prismatic joint without finite limits: give the map's extent")
    return reach


def _workspace_grid(solver, plane: str, offset: float, resolution: int, extent) -> _Grid:
    i, j, k = _PLANES[plane]
    u = np.linspace(extent[0], extent[1], resolution)
    v = np.linspace(extent[2], extent[3], resolution)
    points = np.empty((resolution, resolution, 3))
    points[..., i] = u[None, :]
    points[..., j] = v[:, None]
    points[..., k] = offset
    sol = solver.ik_all(points) if isinstance(solver, Leg) else solver.ik_position(points)  # one batched call
    count = sol.valid.sum(axis=-1)
    code = np.where(count > 0, np.minimum(count, 3), np.where(sol.exists.any(axis=-1), -1, -2))
    # |det J| of the first valid branch, else the first existing one
    pick = np.where(sol.valid.any(axis=-1), sol.valid.argmax(axis=-1), sol.exists.argmax(axis=-1))
    q = np.take_along_axis(sol.q, pick[..., None, None], axis=-2)[..., 0, :]
    if isinstance(solver, Leg):
        det = solver.singularity(q)[0]
    else:
        with np.errstate(all="ignore"):
            det = np.abs(np.linalg.det(solver.position_jacobian(np.nan_to_num(q))))
    det = np.where(sol.exists.any(axis=-1), det, np.nan)
    return _Grid(u, v, points, code.astype(np.int8), det)


def _crosses(field: np.ndarray, level: float = 0.0) -> bool:
    finite = field[np.isfinite(field)]
    return finite.size > 0 and finite.min() < level < finite.max()


def _cylinder_curves(h: float, plane: str, offset: float, extent: np.ndarray) -> list[np.ndarray]:
    """The hip-roll cylinder y² + z² = h² on the plane, as (m, 2) curves of (u, v) points (exact)."""
    if plane == "yz":
        angle = np.linspace(0.0, 2 * math.pi, 361)
        return [abs(h) * np.stack([np.cos(angle), np.sin(angle)], axis=1)]
    if abs(offset) > abs(h):  # the plane misses the cylinder
        return []
    level = math.sqrt(h * h - offset * offset)  # z (plane xz, y = offset) or y (plane xy, z = offset)
    u = np.array([extent[0], extent[1]])
    return [
        np.stack([u, np.full(2, sign * level)], axis=1) for sign in ((1.0, -1.0) if level > 0 else (1.0,))
    ]


def _knee_singular_fields(leg: Leg, points: np.ndarray) -> list[np.ndarray]:
    """Fields |W|² - (|B| ± |C|)², zero where the knee is stretched (+) or folded (-), for each hip
    branch, NaN inside the hip-roll cylinder (docs/derivations.md, "Roll–pitch–pitch legs from a URDF":
    W = (v_z - a_z) + i (x - a_x) with v_z = -ε sqrt(y² + z² - h²))."""
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    h = leg.hip_offset
    a, b, c = leg.a, leg.b, leg.c
    B, C = math.hypot(b[0], b[2]), math.hypot(c[0], c[2])
    square = y * y + z * z - h * h
    with np.errstate(invalid="ignore"):
        S = np.sqrt(np.where(square >= 0, square, np.nan))
    fields = []
    for epsilon in (1.0, -1.0) if a[2] != 0 else (1.0,):
        W2 = (-epsilon * S - a[2]) ** 2 + (x - a[0]) ** 2
        fields += [W2 - (B + C) ** 2, W2 - (B - C) ** 2]
    return fields


def workspace(
    solver,
    plane: str = "xz",
    offset: float | None = None,
    resolution: int = 400,
    extent: ArrayLike | None = None,
    ax=None,
) -> Figure:
    """A slice of a leg's reach, coloured by the number of valid IK branches.

    The grid of ``resolution`` x ``resolution`` targets on the plane is solved by one batched
    :meth:`Leg.ik_all` call (:meth:`Chain.ik_position` for a 3-joint chain). Each target is coloured by
    its count of valid branches (1, 2, 3 or 4), or as unreachable (no branch exists) or blocked by the
    joint limits (branches exist, none within the limits: hatched). Over the map: the singular sets of
    a leg, the knee stretched or folded (|W| = |B| ± |C| in the pitch plane) and the hip-roll
    cylinder y² + z² = h²; contours of ``|det J|`` (m³) of the first valid branch (else the first
    existing one), which for a chain also show its singular sets; the hip-roll joint (the chain's base);
    and, for a leg on a vertical plane, the lowest target with two or more valid branches: below it at
    most one is valid (for Spot's legs, about 8 cm below the hip, as the tests prove on random stances;
    a chain's map has no such line, as "below" means nothing for a chain's base).

    Parameters
    ----------
    solver:
        An :class:`spotkin.Leg` (coordinates in its leg frame) or a 3-joint :class:`spotkin.Chain`
        (its base frame).
    plane:
        ``"xz"`` (a vertical plane along the body, y = offset), ``"yz"`` (across it, x = offset) or
        ``"xy"`` (horizontal, z = offset).
    offset:
        The fixed coordinate (m). Default: for a leg, y = its lateral offset h (the plane of a nominal
        stance's foot) for ``"xz"``, x = the hip-pitch joint's for ``"yz"``, z = -0.75 of the reach for
        ``"xy"``; for a chain, 0.
    resolution:
        Targets per side, 2 to 1000 (default 400: 160,000 targets).
    extent:
        (u_min, u_max, v_min, v_max) of the plane's horizontal and vertical coordinates; default: a
        square around the hip (the base) that holds the whole reach.
    ax:
        A 2D Axes to draw in; default: a new figure.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn in. The map is ``ax.images[0]``: its array holds, per target, the number of
        valid branches, -1 (blocked by the limits) or -2 (unreachable); pixel (r, c) is the target at
        u = linspace(u_min, u_max, resolution)[c], v = linspace(v_min, v_max, resolution)[r].

    Raises ``TypeError`` for another solver or non-numeric arguments, and ``ValueError`` for an
    unknown plane, a non-finite offset, a resolution out of range, an extent that is not 4 increasing
    finite bounds, an offset or extent beyond 1e6 m, a chain without 3 joints, or a 3D ``ax``.
    """
    if not isinstance(solver, (Leg, Chain)):
        raise TypeError(f"solver must be an sk.Leg or a 3-joint sk.Chain, got {type(solver).__name__}")
    if isinstance(solver, Chain) and solver.dof != 3:
        raise ValueError(f"workspace maps legs and 3-joint chains, this chain has {solver.dof} joints")
    if not isinstance(plane, str):
        raise TypeError(f"plane must be a str, one of {tuple(_PLANES)}, got {type(plane).__name__}")
    if plane not in _PLANES:
        raise ValueError(f"plane must be one of {tuple(_PLANES)}, got {plane!r}")
    resolution = as_index(resolution, "resolution")
    if not 2 <= resolution <= _MAX_RESOLUTION:
        raise ValueError(f"resolution must be an integer in [2, {_MAX_RESOLUTION}], got {resolution}")
    ax = _check_ax(ax, three_d=False)
    leg = solver if isinstance(solver, Leg) else None
    i, j, k = _PLANES[plane]
    centre = np.zeros(3) if leg is not None else solver.base[:3, 3]
    if offset is None:
        if leg is None:
            offset = 0.0
        else:
            offset = {"xz": leg.hip_offset, "yz": float(leg.a[0]), "xy": -0.75 * leg.reach[1]}[plane]
    else:
        offset = as_scalar(offset, "offset")
        if not math.isfinite(offset):
            raise ValueError(f"offset must be a finite number, got {offset!r}")
        _near(np.array([offset]), "offset", "the plane")
    if extent is None:
        half = 1.05 * _reach(solver)
        extent = np.array([centre[i] - half, centre[i] + half, centre[j] - half, centre[j] + half])
    else:
        extent = as_real(extent, "extent", np.float64)
        if extent.shape != (4,):
            raise ValueError(
                f"extent must have shape (4,) as (u_min, u_max, v_min, v_max), got {extent.shape}"
            )
        if not (np.isfinite(extent).all() and extent[0] < extent[1] and extent[2] < extent[3]):
            raise ValueError(
                f"extent must be finite with u_min < u_max and v_min < v_max, got {extent.tolist()}"
            )
        _near(extent, "extent", "the map")
    with np.errstate(all="ignore"):  # targets far from the leg: unreachable, never a warning
        grid = _workspace_grid(solver, plane, offset, resolution, extent)
    if ax is None:
        fig = plt.figure(figsize=(9.5, 6.5))
        ax = fig.add_axes((0.08, 0.1, 0.55, 0.8))
    du = (extent[1] - extent[0]) / max(resolution - 1, 1)
    dv = (extent[3] - extent[2]) / max(resolution - 1, 1)
    ax.imshow(
        grid.code,
        origin="lower",
        interpolation="nearest",
        aspect="equal",
        extent=(extent[0] - du / 2, extent[1] + du / 2, extent[2] - dv / 2, extent[3] + dv / 2),
        cmap=ListedColormap(_MAP_COLOURS),
        norm=BoundaryNorm((-2.5, -1.5, 0.0, 1.5, 2.5, 4.5), 5),
        gid="branch-count",
    )
    U, V = np.meshgrid(grid.u, grid.v)
    blocked = (grid.code == -1).astype(float)
    handles = [
        Patch(facecolor=c, edgecolor="black", linewidth=0.5, label=t)
        for c, t in zip(_MAP_COLOURS, _MAP_LABELS)
    ]
    handles[1].set_hatch("////")
    if _crosses(blocked, 0.5):
        ax.contourf(U, V, blocked, levels=(0.5, 1.5), colors="none", hatches=("////",))
    finite_det = grid.det[np.isfinite(grid.det)]
    if finite_det.size and finite_det.max() > 0:
        levels = finite_det.max() * np.array([0.02, 0.1, 0.3, 0.6])
        det = np.ma.masked_invalid(grid.det)
        contours = ax.contour(U, V, det, levels=levels, colors="#525252", linewidths=0.7, linestyles="-")
        ax.clabel(contours, fmt="%.2g", fontsize=6)
        handles.append(Line2D([], [], color="#525252", linewidth=0.7, label="|det J| contours (m³)"))
    if leg is not None:
        knees = _knee_singular_fields(leg, grid.points)
        for curve in _cylinder_curves(leg.hip_offset, plane, offset, extent):
            ax.plot(*curve.T, color="black", linewidth=1.6, linestyle="--", gid="singular:hip-roll")
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                linewidth=1.6,
                linestyle="--",
                label="singular: hip-roll cylinder y² + z² = h²",
            )
        )
        for field in knees:
            if _crosses(field):
                contour = ax.contour(
                    U,
                    V,
                    np.ma.masked_invalid(field),
                    levels=(0.0,),
                    colors="black",
                    linewidths=1.6,
                    linestyles=":",
                )
                for artist in getattr(contour, "collections", None) or [contour]:  # one per level before 3.8
                    artist.set_gid("singular:knee")
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                linewidth=1.6,
                linestyle=":",
                label="singular: knee stretched or folded",
            )
        )
    base = centre[[i, j]]
    ax.plot(*base, linestyle="none", marker="P", markersize=9, color="white", markeredgecolor="black")
    handles.append(
        Line2D(
            [],
            [],
            linestyle="none",
            marker="P",
            markersize=9,
            color="white",
            markeredgecolor="black",
            label="hip-roll joint" if leg is not None else "base",
        )
    )
    if leg is not None and plane != "xy" and (grid.code >= 2).any():  # a leg's uniqueness height
        lowest = float(V[grid.code >= 2].min())
        ax.axhline(lowest, color=_LIMIT, linewidth=1.2, linestyle="-.", gid="lowest-two-branches")
        handles.append(
            Line2D(
                [],
                [],
                color=_LIMIT,
                linewidth=1.2,
                linestyle="-.",
                label=f"lowest target with 2+ valid branches,\nz = {lowest:+.3f} m: at most one below",
            )
        )
    names = "xyz"
    frame = "leg frame" if leg is not None else "base frame"
    ax.set_xlabel(f"{names[i]} (m, {frame})")
    ax.set_ylabel(f"{names[j]} (m, {frame})")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    label = (leg.name or "leg") if leg is not None else "chain"
    ax.set_title(
        f"{label}: valid IK branches on the plane {names[k]} = {offset:.3f} m\n"
        f"({resolution} x {resolution} targets, one batched IK call)",
        fontsize=10,
    )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    return ax.figure


# ---- trajectories -----------------------------------------------------------------------------------------


def _times(t, duration: float) -> np.ndarray:
    if t is None:
        return np.linspace(0.0, duration, 400) if duration > 0 else np.zeros(1)
    times = as_real(t, "t", np.float64)
    if times.ndim != 1 or times.size == 0:
        raise ValueError(f"t must be a non-empty 1-D array of times, got shape {times.shape}")
    if not np.isfinite(times).all():
        raise ValueError("t must be finite")
    _near(times, "t", "the times")
    return times


def _style(k: int) -> dict:
    return {
        "color": _CYCLE_COLOURS[k % len(_CYCLE_COLOURS)],
        "linestyle": _CYCLE_STYLES[k % len(_CYCLE_STYLES)],
    }


def _bound_lines(ax, values: np.ndarray, name: str, unit: str) -> None:
    """± per-axis limits: one pair of black lines when every axis shares the limit, else per axis."""
    if np.allclose(values, values[0]):
        for sign in (1, -1):
            ax.axhline(
                sign * values[0],
                color="black",
                linewidth=1.0,
                linestyle=(0, (6, 3)),
                label=f"±{name} = {values[0]:.3g} {unit}" if sign == 1 else None,
                gid=f"limit:{name}",
            )
        return
    for k, value in enumerate(values):
        style = _style(k)
        for sign in (1, -1):
            ax.axhline(
                sign * value,
                color=style["color"],
                linewidth=0.8,
                linestyle=(0, (6, 3)),
                label=f"±{name} axis {k + 1}" if sign == 1 else None,
                gid=f"limit:{name}",
            )


def _joint_limit_lines(ax, q: np.ndarray, table: np.ndarray, names: tuple) -> None:
    """The q panel's view and joint limits. The view spans the motion (every axis) with a margin of 10 %
    of its range (at least 0.05 rad), widened to hold the bounds near their own joint's motion (within a
    quarter of the panel's range, at least 0.1 rad, of it). Each finite bound within the view is drawn as
    a dotted line; the others are listed beside the panel (id ``"limits-beyond:q"``), an arrow giving
    the side of the view where they lie."""
    low, high = float(q.min()), float(q.max())
    span = high - low
    margin, near = max(0.1 * span, 0.05), max(0.25 * span, 0.1)
    view = [low - margin, high + margin]
    bounds = [(k, side, float(b)) for k in range(len(names)) for side, b in zip(("≥", "≤"), table[k])]
    bounds = [(k, side, b) for k, side, b in bounds if math.isfinite(b)]
    for k, _, bound in bounds:
        if q[:, k].min() - near <= bound <= q[:, k].max() + near:
            view = [min(view[0], bound - 0.5 * margin), max(view[1], bound + 0.5 * margin)]
    beyond, drawn = [], 0
    for k, side, bound in bounds:
        if view[0] <= bound <= view[1]:
            ax.axhline(bound, color=_style(k)["color"], linewidth=0.8, linestyle=(0, (1, 2)), gid="limit:q")
            drawn += 1
        else:
            beyond.append(f"{'↑' if bound > view[1] else '↓'} {names[k]} {side} {bound:.3g}")
    ax.set_ylim(*view)
    if drawn:
        ax.plot([], [], color="black", linewidth=0.8, linestyle=(0, (1, 2)), label="joint limits")
    if beyond:
        ax.text(
            1.01,
            0.0,
            "limits beyond the view (rad):\n" + "\n".join(beyond),
            transform=ax.transAxes,
            ha="left",
            va="bottom",
            fontsize=6.5,
            gid="limits-beyond:q",
        )


def trajectory(
    traj, t: ArrayLike | None = None, limits: ArrayLike | None = None, names=None, fig=None
) -> Figure:
    """A trajectory against time, with its limits.

    - A :class:`spotkin.trajectory.PointToPoint`: q, qd and qdd of every axis (three panels), with the
      speed and acceleration limits ±vmax and ±amax drawn (one pair of lines when every axis shares
      them), and the joint position ``limits`` (n, 2) when given. The q panel spans the motion (with a
      margin of 10 % of its range, at least 0.05 rad), widened for the limits near their joint's motion
      (within a quarter of the range, at least 0.1 rad); the limits in that view are drawn as dotted
      lines, the farther ones (a joint that turns ±3π, say) are listed beside the panel with an arrow for
      the side of the view they lie on; infinite bounds are not drawn.
    - A :class:`spotkin.trajectory.CartesianPath`: the position (x, y, z), the linear velocity and the
      angular velocity (world frame) with their norms; ``limits`` and ``names`` must be None.

    ``t`` (K,): the times to sample (default: 400 over [0, duration]); ``names``: the n axis names
    (default q1, q2, ...); ``fig``: a Figure to draw in (its contents are replaced), default a new one.
    Returns the figure; each sampled curve's data is the trajectory's own ``sample(t)``.

    Raises ``TypeError`` for another object, non-numeric arrays or names that are not strings, and
    ``ValueError`` for times that are not a finite 1-D array, limits not of shape (n, 2) or with NaN,
    times or finite limits beyond 1e6, names of another count, or limits or names for a Cartesian path.
    """
    if not isinstance(traj, (PointToPoint, CartesianPath)):
        raise TypeError(
            f"traj must be a PointToPoint or a CartesianPath (spotkin.trajectory), got {type(traj).__name__}"
        )
    times = _times(t, traj.duration)
    fig = _check_fig(fig)
    if isinstance(traj, CartesianPath):
        if limits is not None or names is not None:
            raise ValueError("limits and names apply to joint trajectories (PointToPoint) only")
        if fig is None:
            fig = plt.figure(figsize=(8, 7))
        _trajectory_cartesian(fig, traj, times)
        return fig
    n = traj.q0.shape[0]
    if names is None:
        names = tuple(f"q{k + 1}" for k in range(n))
    else:
        if isinstance(names, str) or not all(isinstance(name, str) for name in names):
            raise TypeError("names must be a sequence of str, one per axis")
        names = tuple(names)
        if len(names) != n:
            raise ValueError(f"names must name the {n} axes, got {len(names)} names")
    table = None
    if limits is not None:
        table = as_real(limits, "limits", np.float64)
        if table.shape != (n, 2):
            raise ValueError(f"limits must have shape ({n}, 2) as (lower, upper) rows, got {table.shape}")
        if np.isnan(table).any():
            raise ValueError("limits must not hold NaN")
        _near(table[np.isfinite(table)], "limits", "a bound (use ±inf for none)")
    if fig is None:
        fig = plt.figure(figsize=(8, 7))
    q, qd, qdd = traj.sample(times)
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        (q, "q (rad)", None),
        (qd, "qd (rad/s)", ("vmax", traj.vmax, "rad/s")),
        (qdd, "qdd (rad/s²)", ("amax", traj.amax, "rad/s²")),
    )
    for ax, (values, ylabel, bound) in zip(axes, panels):
        for k in range(n):
            ax.plot(
                times,
                values[:, k],
                linewidth=1.6,
                label=names[k],
                gid=f"{ylabel.split()[0]}:{k}",
                **_style(k),
            )
        if bound is not None:
            _bound_lines(ax, bound[1], bound[0], bound[2])
        ax.set_ylabel(ylabel)
        ax.grid(True, linewidth=0.3)
    if table is not None:
        _joint_limit_lines(axes[0], q, table, names)
    for ax in axes:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(f"{traj.profile} point-to-point motion, duration {traj.duration:.3f} s", fontsize=10)
    fig.subplots_adjust(right=0.8)
    return fig


def _trajectory_cartesian(fig, path: CartesianPath, times: np.ndarray) -> None:
    poses, twist = path.sample(times, twist=True)
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        (poses[:, :3, 3], ("x", "y", "z"), "position (m)", None),
        (twist[:, :3], ("vx", "vy", "vz"), "linear velocity (m/s)", "|v|"),
        (twist[:, 3:], ("wx", "wy", "wz"), "angular velocity (rad/s)", "|w|"),
    )
    for ax, (values, labels, ylabel, norm) in zip(axes, panels):
        for k in range(3):
            ax.plot(times, values[:, k], linewidth=1.6, label=labels[k], gid=f"{labels[k]}", **_style(k))
        if norm is not None:
            ax.plot(times, np.linalg.norm(values, axis=1), color="black", linewidth=1.2, label=norm, gid=norm)
        ax.set_ylabel(ylabel)
        ax.grid(True, linewidth=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    for t_k in path.times:
        for ax in axes:
            ax.axvline(t_k, color="#969696", linewidth=0.6, linestyle=":")
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(
        f"Cartesian path through {len(path.times)} waypoints (dotted: their times), "
        f"duration {path.duration:.3f} s",
        fontsize=10,
    )
    fig.subplots_adjust(right=0.8)


# ---- animation ---------------------------------------------------------------------------------------------


class _GifWriter(AbstractMovieWriter):
    """Writes a GIF with Pillow, every frame on one palette of 128 colours without dithering: the static
    parts (axes, legend) stay identical between frames, so the file holds little more than what moves (a
    few times smaller than a per-frame dithered palette; line art needs no more colours)."""

    def __init__(self, fps: float = 10.0):
        super().__init__(fps=fps)
        self._frames: list = []

    def setup(self, fig, outfile, dpi=None):
        super().setup(fig, outfile, dpi=dpi)
        self._frames = []

    def grab_frame(self, **savefig_kwargs):
        buffer = io.BytesIO()
        self.fig.savefig(buffer, **{**savefig_kwargs, "format": "rgba", "dpi": self.dpi})
        self._frames.append(Image.frombuffer("RGBA", self.frame_size, buffer.getbuffer()).convert("RGB"))

    def finish(self):
        frames = self._frames
        picks = sorted({0, len(frames) // 2, len(frames) - 1})
        sample = Image.new("RGB", (frames[0].width, frames[0].height * len(picks)))
        for row, k in enumerate(picks):
            sample.paste(frames[k], (0, row * frames[0].height))
        palette = sample.quantize(colors=128, method=0, dither=0)  # median cut, no dithering
        images = [frame.quantize(palette=palette, dither=0) for frame in frames]
        images[0].save(
            self.outfile, save_all=True, append_images=images[1:], duration=round(1000 / self.fps), loop=0
        )


class _Animation(FuncAnimation):
    """A FuncAnimation whose ``save`` writes a ``.gif`` with :class:`_GifWriter` unless given a writer,
    and draws each frame once while saving (the writer's grab draws it; the idle redraw is skipped)."""

    _saving = False

    def __init__(self, fig, func, *, frames: int, interval: float):
        self.figure = fig
        self.frame_interval = interval  # ms
        super().__init__(fig, func, frames=frames, interval=interval, blit=False, repeat=True)

    def save(self, filename, writer=None, *args, **kwargs):
        if writer is None and str(filename).lower().endswith(".gif"):
            writer = _GifWriter(fps=kwargs.pop("fps", None) or 1000.0 / self.frame_interval)
        self._saving = True
        try:
            return super().save(filename, writer, *args, **kwargs)
        finally:
            self._saving = False

    def _post_draw(self, framedata, blit):
        if not self._saving:
            super()._post_draw(framedata, blit)


def animate(
    robot: Robot,
    body_poses: ArrayLike,
    q: ArrayLike,
    q_arm: ArrayLike | None = None,
    seq: str = "XYZ",
    interval: float = 100.0,
    fig=None,
):
    """An animation of ``robot`` along a body path: one frame per body pose.

    ``body_poses`` (K, 6) [x, y, z, a, b, c] (Euler angles in ``seq``), (K, 7) or (K, 4, 4); ``q``
    (K, 3 n) leg joints (or (3 n,) for every frame), ``q_arm`` (K, 6) or (6,) for a robot with an arm
    (default: zero angles clipped into the limits). Each frame is drawn as :func:`robot` draws one
    configuration; the body origin's path (and the tool's, with an arm) is traced dotted and the body's
    outline at frame 1 stays drawn dashed (id ``"body-start"``), to show the motion. ``interval``
    is the time between frames in milliseconds (> 0); ``fig``: a Figure to draw in (its contents are
    replaced), default a new one of 8 x 5 in (800 x 500 pixels at 100 dpi). The drawing fills the
    figure's left three quarters, framed on every frame's robot at one scale on every axis, the legend
    beside it on the right; the title names the robot as :func:`robot` does and counts the frames.

    Returns a :class:`matplotlib.animation.FuncAnimation` (shown at frame 0 until it runs; its Figure
    is ``anim.figure``):
    ``anim.save("path.gif")`` writes a GIF with Pillow (matplotlib's dependency), ``anim.to_jshtml()``
    an HTML player. Keep a reference to it while it plays.

    Raises as :func:`robot`; every frame must be finite, and ``q`` and ``q_arm`` must have one row
    per pose (or one row for all).
    """
    robot = _check_robot(robot)
    seq = _check_seq(seq)
    interval = _positive(interval, "interval")
    T = _poses(body_poses, seq)
    count = len(T)
    q = _batch(q, "q", 3 * robot.n_legs, count)
    arm = robot.arm
    if q_arm is not None and arm is None:
        raise ValueError("q_arm was given but this robot has no arm")
    if arm is not None:
        q_arm = _batch(_default_arm_q(arm) if q_arm is None else q_arm, "q_arm", _arm_dof(arm), count)
    fig = _check_fig(fig)
    frames = [_frame(robot, T[k], q[k], None if q_arm is None else q_arm[k]) for k in range(count)]
    points = np.concatenate([_frame_points(frame) for frame in frames])
    _near(points, "body_poses", "the robot")
    if fig is None:
        fig = plt.figure(figsize=(8, 5))
    ax = fig.add_axes((0.0, 0.0, 0.72, 0.92), projection="3d")
    span = float(np.ptp(points, axis=0).max())
    artists = _RobotArtists(ax, robot, frames[0], 0.15 * span)
    start = np.vstack([frames[0].outline, frames[0].outline[:1]])
    ax.plot(*start.T, color=_BODY_EDGE, linewidth=0.8, linestyle="--", alpha=0.6, gid="body-start", zorder=1)
    ax.plot(*T[:, :3, 3].T, color="black", linewidth=1.2, linestyle=":", gid="body-path", zorder=4)
    extra = [
        Line2D([], [], color=_BODY_EDGE, linewidth=0.8, linestyle="--", alpha=0.6, label="body at frame 1"),
        Line2D([], [], color="black", linewidth=1.2, linestyle=":", label="body origin's path"),
    ]
    if q_arm is not None:
        tool = np.array([frame.arm[-1] for frame in frames])
        ax.plot(*tool.T, color=_ARM, linewidth=1.0, linestyle=":", gid="tool-path")
        extra.append(Line2D([], [], color=_ARM, linestyle=":", label="tool's path"))
    axis_ends = [artists._axis(frame.T, k) for frame in frames for k in range(3)]
    _equal_3d(ax, np.concatenate([points, *axis_ends]))
    _label_3d(ax)
    _sparse_ticks(ax, 7)
    artists.legend(extra, fontsize=7, outside=True)
    name = _robot_name(robot)
    title = ax.set_title(f"{name}: frame 1 of {count}", fontsize=9)

    def draw(k):
        artists.update(frames[k])
        title.set_text(f"{name}: frame {k + 1} of {count}")
        return ()

    return _Animation(fig, draw, frames=count, interval=interval)
