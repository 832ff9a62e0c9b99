"""One configuration of a robot in the world frame, as the robot's pictures draw it (the legs, the arm,
the other links of its description, the support polygon, the joints beyond their limits and the singular
legs), and the configurations drawn by default (a nominal stance, the zero angles)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import Robot, Status
from ._solvers import _beyond_limits, _joint_origins, _revolute

_NAME_SUFFIXES = ("description", "robot", "urdf")


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
        points, rows = _joint_origins(leg, q_leg)
        legs.append(_world(T, hips[k] + points))
        feet.append(legs[-1][3])
        outside = _beyond_limits(q_leg, leg.limits, _revolute(leg))
        beyond.extend(legs[-1][rows[outside]])  # a joint's origin: hip roll, hip pitch, knee
        sigma = leg.singularity(q_leg)[1]
        if sigma < 1e-3 * max(leg.reach[1], 1e-9):
            singular.append(legs[-1][2])
    arm_points = None
    if q_arm is not None:
        arm = robot.arm
        mount = getattr(robot, "arm_mount", None)  # body <- arm base (the identity when None)
        points, rows = _joint_origins(arm, q_arm)
        arm_points = _world(T if mount is None else T @ mount, points)
        outside = _beyond_limits(q_arm, arm.limits, _revolute(arm))
        beyond.extend(arm_points[rows[outside]])
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


def _frame_points(frame: _Frame) -> np.ndarray:
    parts = [frame.outline, frame.feet, frame.support, frame.T[:3, 3][None], frame.tree.reshape(-1, 3)]
    parts += list(frame.legs)
    if frame.arm is not None:
        parts.append(frame.arm)
    return np.concatenate(parts)


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
