"""A legged robot's MuJoCo model, written from its spotkin description alone. Part of
:mod:`spotkin.sim` (documented there)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from .. import Robot
from .._support.boundary import as_finite
from ..motion.capsules import LINK_FRACTION, body_box
from ..motion.gait import hip_height as _motion_hip_height
from .terrain import Bumps, Flat, as_terrain

__all__ = ["foot_radius", "hip_height", "mjcf", "mujoco_model"]

FOOT_FRACTION = 0.05
"""The default foot radius as a fraction of the leg's reach (Spot: 0.036 / 0.658; Go2: 0.022 / 0.426)."""
ARMATURE = 1e-3
"""Each joint's armature (kg m²) is ARMATURE · m L² (m the robot's mass, L the leg's reach): the order
of a geared rotor's reflected inertia (Go2: 0.003, Spot: 0.024); it also keeps light links stable."""
DAMPING = 10.0
"""Each joint's viscous damping (N m s/rad) is DAMPING (1/s) times its armature: a small loss."""
MASSLESS = 1e-6
"""A moving body without mass gets this fraction of the robot's mass (MuJoCo needs positive masses)."""

# geom groups: what a contact with the ground means
FOOT_GROUP, FALL_GROUP, SHIN_GROUP = 0, 1, 2


def _reach(robot: Robot) -> float:
    return min(leg.reach[1] for leg in robot.legs)


def check_robot(robot) -> None:
    """ValueError unless ``robot`` is a quadruped :class:`spotkin.Robot` with a URDF description."""
    if not isinstance(robot, Robot):
        raise ValueError(
            "spotkin.sim simulates legged robots: robot must be a spotkin.Robot with four legs (a "
            f"quadruped, from Robot.from_urdf or Spot()), got {type(robot).__name__}"
        )
    if robot.n_legs != 4:
        raise ValueError(f"spotkin.sim simulates quadrupeds: this robot has {robot.n_legs} legs, not 4")
    if robot.model is None:
        raise ValueError(
            "spotkin.sim builds the model from the robot's URDF description: this robot has none"
        )
    if not any(link.inertial is not None and link.inertial.mass > 0 for link in robot.model.links.values()):
        raise ValueError("spotkin.sim needs masses: the robot's description has no <inertial> with mass")


def hip_height(robot: Robot) -> float:
    """The nominal standing hip height h (m): the hip-pitch joints' height above the foot points
    (the foot spheres' centres) in the simulator's initial stance (Spot: 0.526 m, Go2: 0.341 m): the
    speed scale of a walk ("0.5 h per second"). It is :func:`spotkin.motion.hip_height`, the gaits'
    h (:attr:`spotkin.motion.ResolvedGait.hip_height`): the simulated robot starts in the gaits' nominal
    stance, its most stretched leg at 0.8 of its reach."""
    check_robot(robot)
    return _motion_hip_height(robot)


def _urdf_names(robot: Robot, joints) -> list[str]:
    """The URDF names of ``joints`` (a q's names: leg_joint_names, arm_joint_names), in that order."""
    actuated = [joint.name for joint in robot.model.actuated_joints]
    if not joints:
        return []
    index = robot.q_from_names(actuated, np.arange(len(actuated), dtype=float), joints=joints)
    return [actuated[int(k)] for k in index]


def _foot_points(robot: Robot, knees: list[str]) -> list[np.ndarray]:
    """Each leg's foot point in its lower-leg link's frame (the knee joint's child link)."""
    model = robot.model
    feet = robot.body_fk(np.zeros(6), np.zeros(3 * robot.n_legs))
    points = []
    for k, knee in enumerate(knees):
        frame = model.placement(model.joint(knee).child)
        points.append(frame[:3, :3].T @ (feet[k] - frame[:3, 3]))
    return points


def foot_radius(robot: Robot) -> float:
    """The radius (m) of the simulator's foot spheres: the URDF's collision sphere around the foot
    point when it has one (the largest, over the legs); else the robot's own (Spot's 0.036 m, where
    its :meth:`~spotkin.Robot.stance_feet` puts the foot centres); else 0.05 of the leg's reach."""
    check_robot(robot)
    return _foot_radius(robot, _Tree(robot))


def _foot_radius(robot: Robot, tree: _Tree) -> float:
    found = [radius for _, radius in tree.foot_spheres if radius is not None]
    if found:
        return float(max(found))
    own = _own_radius(robot)
    return own if own > 0.0 else FOOT_FRACTION * _reach(robot)


def _own_radius(robot: Robot) -> float:
    """The foot radius the robot's stance_feet applies (Spot's; 0 for a Robot from a URDF)."""
    hips, legs = robot.hip_positions, robot.legs
    height = hip_height(robot) - min(hips[k, 2] + leg.a[2] for k, leg in enumerate(legs))
    try:
        return float(robot.stance_feet(height)[:, 2].max())
    except ValueError:
        return 0.0


def _inertial(parts: list[tuple[float, np.ndarray, np.ndarray]]) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, com, inertia about com) of rigidly joined parts (mass, com, inertia about its com)."""
    mass = sum(m for m, _, _ in parts)
    if mass <= 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = sum(m * c for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, inner in parts:
        d = c - com
        inertia += inner + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, com, 0.5 * (inertia + inertia.T)


def _quat(R: np.ndarray) -> np.ndarray:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R, dtype=float).ravel())
    return quat


def _v(values) -> str:
    return " ".join(repr(round(float(v), 12) + 0.0) for v in np.ravel(values))


class _Tree:
    """The description as MuJoCo bodies: one per moving joint of the legs and the arm (and the root),
    each merging the links fixed to it (fixed joints, and the joints that are neither a leg's nor the
    arm's, locked at zero)."""

    def __init__(self, robot: Robot) -> None:
        model = robot.model
        self.leg_joints = _urdf_names(robot, robot.leg_joint_names)
        self.arm_joints = _urdf_names(robot, robot.arm_joint_names)
        active = set(self.leg_joints) | set(self.arm_joints)
        self.owner: dict[str, str] = {model.root: model.root}
        self.children: dict[str, list] = {model.root: []}
        stack = [model.root]
        while stack:
            link = stack.pop()
            for joint in model.children(link):
                if joint.name in active:
                    self.owner[joint.child] = joint.child
                    self.children[self.owner[link]].append(joint)
                    self.children[joint.child] = []
                else:
                    self.owner[joint.child] = self.owner[link]
                stack.append(joint.child)
        placement = {link: model.placement(link) for link in model.links}
        self.relative = {  # each link's frame in its body's frame (the joints between are at zero)
            link: np.linalg.solve(placement[body], placement[link]) for link, body in self.owner.items()
        }
        knees = [_urdf_names(robot, leg.joint_names)[2] for leg in robot.legs]  # in robot.legs order
        self.lower = [model.joint(knee).child for knee in knees]
        self.feet = _foot_points(robot, knees)
        self.foot_spheres = [self._sphere(model, body, foot) for body, foot in zip(self.lower, self.feet)]

    def _sphere(self, model, body: str, foot: np.ndarray) -> tuple[np.ndarray, float | None]:
        """The URDF's collision sphere holding the foot point (centre in the body frame, radius), the
        one nearest the point; else (the foot point, None)."""
        best, best_distance = (foot, None), math.inf
        for link, owner in self.owner.items():
            if owner != body:
                continue
            T = self.relative[link]
            for centre, radius in model.link(link).spheres:
                c = T[:3, :3] @ np.asarray(centre) + T[:3, 3]
                distance = float(np.linalg.norm(c - foot))
                if distance <= radius * (1 + 1e-9) and distance < best_distance:
                    best, best_distance = (c, float(radius)), distance
        return best

    def inertial(self, model, body: str) -> tuple[float, np.ndarray, np.ndarray]:
        parts = []
        for link, owner in self.owner.items():
            inertial = model.link(link).inertial
            if owner != body or inertial is None or inertial.mass <= 0.0:
                continue
            R, p = self.relative[link][:3, :3], self.relative[link][:3, 3]
            parts.append((inertial.mass, R @ inertial.com + p, R @ inertial.inertia @ R.T))
        return _inertial(parts)


@dataclass(frozen=True)
class Layout:
    """What the simulator needs to know about the model it wrote: the MJCF and the names in it."""

    xml: str
    leg_joints: tuple[str, ...]
    arm_joints: tuple[str, ...]
    foot_geoms: tuple[str, ...]
    foot_radius: float
    terrain: Flat
    body: str


def layout(robot, terrain=None, friction=1.0, timestep=0.001, foot_radius=None, seed: int = 0) -> Layout:
    """The robot's MJCF and its names (see :func:`mjcf`)."""
    check_robot(robot)
    terrain = as_terrain(terrain)
    if isinstance(terrain, Bumps):
        terrain = terrain.with_seed(seed)
    friction = as_finite(friction, "friction", 0.0, strict=True)
    timestep = as_finite(timestep, "timestep", 0.0, strict=True)
    model, tree = robot.model, _Tree(robot)
    if foot_radius is None:
        radius = _foot_radius(robot, tree)
    else:
        radius = as_finite(foot_radius, "foot_radius", 0.0, strict=True)
    reach = _reach(robot)
    link_radius = min(LINK_FRACTION * reach, 0.7 * radius)  # the capsule model's, capped by the feet
    total = sum(link.inertial.mass for link in model.links.values() if link.inertial is not None)
    armature = ARMATURE * total * reach**2
    lower = {body: k for k, body in enumerate(tree.lower)}

    def body_xml(link: str, joint, depth: int) -> list[str]:
        pad = "  " * depth
        lines = []
        if joint is None:
            lines.append(f'{pad}<body name="{link}" pos="0 0 0">')
            lines.append(f'{pad}  <freejoint name="root"/>')
        else:
            T = tree.relative[joint.parent] @ joint.origin
            lines.append(f'{pad}<body name="{link}" pos="{_v(T[:3, 3])}" quat="{_v(_quat(T[:3, :3]))}">')
            kind = "slide" if joint.type == "prismatic" else "hinge"
            limited = math.isfinite(joint.lower) and math.isfinite(joint.upper)
            bounds = (
                f'limited="true" range="{_v([joint.lower, joint.upper])}"' if limited else 'limited="false"'
            )
            lines.append(
                f'{pad}  <joint name="{joint.name}" type="{kind}" axis="{_v(joint.axis)}" {bounds} '
                f'armature="{_v(armature)}" damping="{_v(DAMPING * armature)}"/>'
            )
        mass, com, inertia = tree.inertial(model, link)
        if mass <= 0.0:
            mass = MASSLESS * total
            inertia = np.eye(3) * mass * (0.1 * reach) ** 2
        floor = 1e-9 * total * reach**2  # a point mass alone still gets a (tiny) inertia
        inertia = inertia + np.eye(3) * max(0.0, floor - float(np.linalg.eigvalsh(inertia)[0]))
        full = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]
        lines.append(f'{pad}  <inertial pos="{_v(com)}" mass="{_v(mass)}" fullinertia="{_v(full)}"/>')
        lines += geoms(link, joint, pad + "  ")
        for child in tree.children[link]:
            lines += body_xml(child.child, child, depth + 1)
        lines.append(f"{pad}</body>")
        return lines

    def capsule(name: str, end: np.ndarray, group: int, pad: str) -> list[str]:
        if np.linalg.norm(end) < 1e-6:
            return []
        return [
            f'{pad}<geom name="{name}" type="capsule" fromto="0 0 0 {_v(end)}" size="{_v(link_radius)}" '
            f'group="{group}" {_ROBOT_GEOM}/>'
        ]

    def geoms(link: str, joint, pad: str) -> list[str]:
        if joint is None:  # the body: a box over the hips
            centre, half = body_box(robot, link_radius)  # the capsule model's (spotkin.motion.capsules)
            return [
                f'{pad}<geom name="body" type="box" size="{_v(half)}" pos="{_v(centre)}" '
                f'group="{FALL_GROUP}" {_ROBOT_GEOM}/>'
            ]
        out = []
        if link in lower:  # the lower leg: a capsule to the foot, and the foot sphere
            k = lower[link]
            out += capsule(f"{link}_link", tree.feet[k], SHIN_GROUP, pad)
            centre = tree.foot_spheres[k][0]
            out.append(
                f'{pad}<geom name="foot_{robot.leg_names[k]}" type="sphere" size="{_v(radius)}" '
                f'pos="{_v(centre)}" group="{FOOT_GROUP}" {_ROBOT_GEOM}/>'
            )
            return out
        ends = [tree.relative[j.parent] @ j.origin for j in tree.children[link]]
        if not ends:  # the arm's last body: to its farthest fixed link
            ends = [T for other, T in tree.relative.items() if tree.owner[other] == link]
        for n, T in enumerate(ends):
            out += capsule(f"{link}_link{n}", T[:3, 3], FALL_GROUP, pad)
        return out

    bodies = body_xml(model.root, None, 2)
    motors = [
        f'    <motor name="{name}" joint="{name}" {_effort(model.joint(name).effort)}/>'
        for name in tree.leg_joints + tree.arm_joints
    ]
    assets, ground = terrain._mjcf(friction)
    xml = "\n".join(
        [
            f'<mujoco model="{_name(robot)}">',
            '  <compiler angle="radian" inertiafromgeom="false" balanceinertia="true"/>',
            f'  <option timestep="{timestep!r}" integrator="implicitfast" cone="elliptic" impratio="100"/>',
            '  <visual><global offwidth="1280" offheight="720"/></visual>',
            f"  <asset>{assets}</asset>",
            "  <worldbody>",
            '    <light name="sun" pos="0 0 10" dir="0 0 -1" directional="true"/>',
            f"    {ground}",
            *bodies,
            "  </worldbody>",
            "  <actuator>",
            *motors,
            "  </actuator>",
            "</mujoco>",
        ]
    )
    foot_geoms = tuple(f"foot_{name}" for name in robot.leg_names)
    return Layout(
        xml, tuple(tree.leg_joints), tuple(tree.arm_joints), foot_geoms, radius, terrain, model.root
    )


# the robot's geoms collide with the terrain (conaffinity 1) and never with each other
_ROBOT_GEOM = 'contype="1" conaffinity="0" condim="3" rgba="0.85 0.6 0.2 1"'


def _effort(effort: float | None) -> str:
    if effort is None or not effort > 0.0 or not math.isfinite(effort):
        return 'ctrllimited="false"'
    return f'ctrllimited="true" ctrlrange="{-effort!r} {effort!r}"'


def _name(robot: Robot) -> str:
    return "".join(c for c in (robot.name or "robot") if c.isalnum() or c in "_-.") or "robot"


def mjcf(
    robot: Robot,
    *,
    terrain=None,
    friction: float = 1.0,
    timestep: float = 0.001,
    foot_radius: float | None = None,
) -> str:
    """The robot's MuJoCo model (MJCF XML), written from its description alone (no meshes, no
    collision elements needed).

    - A free joint on the body (the URDF's root link); a body per moving joint of the legs and the
      arm, carrying its link's inertial and those of the links fixed to it (fixed joints, and the
      joints that are neither a leg's nor the arm's, locked at zero: the total mass is the URDF's).
      Hinge (slide for prismatic) joints with the URDF's limits, armature ``ARMATURE m L²`` and
      damping ``DAMPING`` times that (m the mass, L the leg's reach).
    - A sphere per foot, named ``foot_<leg name>``, centred at the leg's foot point (or the URDF's
      collision sphere holding it), of radius ``foot_radius`` (default :func:`foot_radius`).
    - Capsules along the links (joint to joint, knee to foot), a box over the hips for the body: the
      ground touching the body, a hip or a thigh is a fall. The robot's geoms collide with the ground
      only (contype 1, conaffinity 0), and the ground's ``friction`` decides every contact.
    - A torque motor per joint of ``robot.leg_joint_names`` then ``robot.arm_joint_names``, named as
      the URDF's joints, with ctrlrange ± the URDF's effort (unlimited where it gives none).
    - The terrain: None or ``"flat"``, :class:`Slope`, :class:`Step`, :class:`Bumps`.

    ValueError for a robot that is not a quadruped :class:`spotkin.Robot` with masses, a friction or
    timestep <= 0, or an unknown terrain.
    """
    return layout(robot, terrain, friction, timestep, foot_radius).xml


def mujoco_model(
    robot: Robot,
    *,
    terrain=None,
    friction: float = 1.0,
    timestep: float = 0.001,
    foot_radius: float | None = None,
) -> mujoco.MjModel:
    """The compiled ``mujoco.MjModel`` of :func:`mjcf` (same arguments)."""
    xml = mjcf(robot, terrain=terrain, friction=friction, timestep=timestep, foot_radius=foot_radius)
    return mujoco.MjModel.from_xml_string(xml)
