"""A legged robot's collision model: capsules along its links and a box for its body, in the body frame.

The simulator (:mod:`spotkin.sim`) gives its links the same capsules and its body the same box, and
whole-body reach (:meth:`spotkin.Robot.reach`) checks the arm against them. The model, for a robot
whose shortest leg reaches l (its longest hip-pitch to foot distance):

- every link is a capsule of radius r = ``LINK_FRACTION`` l (the simulator caps it at 70 % of its
  foot sphere's radius) around the segment from its joint to the next joint;
- the body is the box over the hips: half-lengths (x: half the hips' spread + r, y: the largest
  |hip y| + r, z: the same as y), centred between the front and hind hips at the hips' mean height;
- a leg is two capsules: hip-pitch joint to knee, knee to foot;
- the arm is a capsule per segment between consecutive joint origins (and from the last joint to
  the hand frame); zero-length segments are dropped.

An arm capsule is checked against the body box, and against each leg capsule, unless it already
touches that part with the arm and the legs at zero: such a capsule is mounted on it (the arm's
base link on the body's top, typically), and its contact is by design. Every arm capsule is also kept
above the ground, the horizontal plane through the lowest foot point (both ends of its segment at least
r above it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..reference.reach_geometry import leg_segments, segment_box_distance, segment_distance

__all__ = ["LINK_FRACTION", "CapsuleModel", "body_box", "capsule_model"]

LINK_FRACTION = 0.04
"""The links' capsule radius as a fraction of the leg's reach."""


def link_radius(robot) -> float:
    """r (m): ``LINK_FRACTION`` times the shortest leg's reach."""
    return LINK_FRACTION * min(leg.reach[1] for leg in robot.legs)


def body_box(robot, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(centre (3,), half-lengths (3,)) of the body's box in the body frame (see the module docstring)."""
    hips = robot.hip_positions
    low, high = hips.min(axis=0), hips.max(axis=0)
    half = np.array([0.5 * (high[0] - low[0]), np.abs(hips[:, 1]).max(), 0.0]) + radius
    half[2] = half[1]
    centre = np.array([0.5 * (high[0] + low[0]), 0.0, hips[:, 2].mean()])
    return centre, half


@dataclass(frozen=True)
class CapsuleModel:
    """What :func:`capsule_model` gives: see the module docstring."""

    radius: float
    """r (m), every capsule's radius."""
    box_centre: np.ndarray
    """(3,) the body box's centre, body frame."""
    box_half: np.ndarray
    """(3,) its half-lengths."""
    arm_points: tuple[int, ...]
    """Indices into the arm chain's frames (:meth:`spotkin.Chain.frames`) of the segments' end points:
    segment k runs from frame ``arm_points[k]`` to frame ``arm_points[k + 1]``."""
    arm_vs_body: np.ndarray
    """(segments,) bool: this arm segment is checked against the body box."""
    arm_vs_legs: np.ndarray
    """(segments, n_legs, 2) bool: checked against that leg's upper (0) and lower (1) capsule."""


def capsule_model(robot, arm_chain=None) -> CapsuleModel:
    """The robot's capsules and body box (see the module docstring); ``arm_chain`` the arm's chain from
    the body (default ``robot.chain`` of the arm's tip), None for a robot without an arm."""
    radius = link_radius(robot)
    centre, half = body_box(robot, radius)
    if arm_chain is None:
        return CapsuleModel(radius, centre, half, (), np.zeros(0, bool), np.zeros((0, robot.n_legs, 2), bool))
    frames = arm_chain.frames(np.zeros(arm_chain.dof))[:, :3, 3]
    points = [1]
    for k in range(2, len(frames)):
        if np.linalg.norm(frames[k] - frames[points[-1]]) > 1e-9:
            points.append(k)
    legs = leg_segments(robot, np.zeros(3 * robot.n_legs))
    count = len(points) - 1
    vs_body = np.zeros(count, bool)
    vs_legs = np.zeros((count, robot.n_legs, 2), bool)
    for k in range(count):
        a, b = frames[points[k]], frames[points[k + 1]]
        vs_body[k] = segment_box_distance(a, b, centre, half) > radius
        for i, (hip_pitch, knee, foot) in enumerate(legs):
            vs_legs[k, i, 0] = segment_distance(a, b, hip_pitch, knee) > 2.0 * radius
            vs_legs[k, i, 1] = segment_distance(a, b, knee, foot) > 2.0 * radius
    return CapsuleModel(radius, centre, half, tuple(points), vs_body, vs_legs)
