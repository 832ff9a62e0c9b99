"""URDF test helpers shared by test_urdf.py, test_robot.py and the fuzz registry (tests/fuzz/):
element builders for small URDFs and Pinocchio configurations.

Imported as a top-level module, as test_fuzz.py imports the fuzz package: pytest puts tests/ on sys.path (no
__init__.py, the default import mode), and the fuzz workers' subprocesses run with tests/ as their
working directory and on PYTHONPATH. The workers never need Pinocchio, so pin_q imports it itself.
"""

from __future__ import annotations

import math

import numpy as np

LIMIT = 'effort="10" velocity="5"'


def links(*names: str) -> str:
    """One empty <link> element per name, concatenated."""
    return "".join(f'<link name="{name}"/>' for name in names)


def joint_xml(name, jtype, parent, child, body: str) -> str:
    """A <joint> element: name, type, parent and child links, then body (origin, axis, limit, ...)."""
    return (
        f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/><child link="{child}"/>{body}</joint>'
    )


def joint(name, jtype, parent, child, xyz="0 0 0", rpy="0 0 0", axis=None, limits=None) -> str:
    """A <joint> element with an <origin>, an optional <axis> and optional (lower, upper) limits."""
    body = f'<origin xyz="{xyz}" rpy="{rpy}"/>'
    if axis is not None:
        body += f'<axis xyz="{axis}"/>'
    if limits is not None:
        body += f'<limit lower="{limits[0]}" upper="{limits[1]}" {LIMIT}/>'
    return joint_xml(name, jtype, parent, child, body)


def pin_q(pm, values: dict[str, float]) -> np.ndarray:
    """Pinocchio's configuration with the named joints at values (the others neutral)."""
    import pinocchio

    q = pinocchio.neutral(pm)
    for name, value in values.items():
        jm = pm.joints[pm.getJointId(name)]
        if jm.nq == 2:  # continuous joints: (cos, sin)
            q[jm.idx_q], q[jm.idx_q + 1] = math.cos(value), math.sin(value)
        else:
            q[jm.idx_q] = value
    return q


def _box(mass: float, x: float, y: float, z: float) -> str:
    ixx, iyy, izz = (mass * (b * b + c * c) / 12.0 for b, c in ((y, z), (x, z), (x, y)))
    return f'<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/>'


def quadruped_urdf(
    segment: float, mass: float, effort: float, legs: int = 4, foot_sphere: float | None = None
) -> str:
    """A quadruped (or ``legs``: 2) of thigh and shank ``segment`` m and ``mass`` kg: boxes and rods, no
    meshes, no collisions (but a foot sphere when ``foot_sphere``), a massless hip link on the small
    robot (MuJoCo needs positive masses: the builder handles it)."""
    L, parts = segment, []
    body = 0.7 * mass
    parts.append(
        f'<link name="trunk"><inertial><origin xyz="0 0 0"/><mass value="{body}"/>'
        f"{_box(body, 2.2 * L, 0.8 * L, 0.4 * L)}</inertial></link>"
    )
    parts.append('<link name="imu"/><joint name="imu_joint" type="fixed"><parent link="trunk"/>')
    parts.append('<child link="imu"/><origin xyz="0.05 0 0.02"/></joint>')
    leg = 0.3 * mass / 4
    corners = [("fl", 1, 1), ("fr", 1, -1), ("hl", -1, 1), ("hr", -1, -1)][:legs]
    for name, sx, sy in corners:
        hip_mass = 0.0 if mass < 5 else 0.25 * leg
        hip_inertial = (
            ""
            if hip_mass == 0.0
            else f'<inertial><mass value="{hip_mass}"/>{_box(hip_mass, 0.3 * L, 0.3 * L, 0.3 * L)}</inertial>'
        )
        thigh, shank = 0.45 * leg, 0.3 * leg if hip_mass else 0.55 * leg
        sphere = (
            ""
            if foot_sphere is None
            else f'<collision><geometry><sphere radius="{foot_sphere}"/></geometry></collision>'
        )
        parts += [
            f'<link name="{name}_hip">{hip_inertial}</link>',
            f'<joint name="{name}_roll" type="revolute"><parent link="trunk"/><child link="{name}_hip"/>',
            f'<origin xyz="{sx * 0.9 * L} {sy * 0.25 * L} 0"/><axis xyz="1 0 0"/>',
            f'<limit lower="-0.6" upper="0.6" effort="{effort}" velocity="20"/></joint>',
            f'<link name="{name}_thigh"><inertial><origin xyz="0 0 {-L / 2}"/><mass value="{thigh}"/>',
            f"{_box(thigh, 0.15 * L, 0.15 * L, L)}</inertial></link>",
            f'<joint name="{name}_pitch" type="revolute"><parent link="{name}_hip"/>',
            f'<child link="{name}_thigh"/><origin xyz="0 {sy * 0.3 * L} 0"/><axis xyz="0 1 0"/>',
            f'<limit lower="-1.5" upper="2.5" effort="{effort}" velocity="20"/></joint>',
            f'<link name="{name}_shank"><inertial><origin xyz="0 0 {-L / 2}"/><mass value="{shank}"/>',
            f"{_box(shank, 0.1 * L, 0.1 * L, L)}</inertial></link>",
            f'<joint name="{name}_knee" type="revolute"><parent link="{name}_thigh"/>',
            f'<child link="{name}_shank"/><origin xyz="0 0 {-L}"/><axis xyz="0 1 0"/>',
            f'<limit lower="-2.6" upper="-0.3" effort="{effort}" velocity="20"/></joint>',
            f'<link name="{name}_foot">{sphere}</link>',
            f'<joint name="{name}_foot_joint" type="fixed"><parent link="{name}_shank"/>',
            f'<child link="{name}_foot"/><origin xyz="0 0 {-L}"/></joint>',
        ]
    return '<robot name="test_quadruped">' + "".join(parts) + "</robot>"


# A Unitree Z1-like arm (its URDF's joint origins and axes, rounded), mounted on Go2's body.
Z1_JOINTS = [
    ("z1_joint1", "base", "z1_link01", "0.1 0 0.08", "0 0 1"),
    ("z1_joint2", "z1_link01", "z1_link02", "0 0 0.045", "0 1 0"),
    ("z1_joint3", "z1_link02", "z1_link03", "-0.35 0 0", "0 1 0"),
    ("z1_joint4", "z1_link03", "z1_link04", "0.218 0 0.057", "0 1 0"),
    ("z1_joint5", "z1_link04", "z1_link05", "0.07 0 0", "0 0 1"),
    ("z1_joint6", "z1_link05", "z1_link06", "0.0492 0 0", "1 0 0"),
]
Z1_LIMITS = ((-2.618, 2.618), (0.0, 2.967), (-2.880, 0.0), (-1.518, 1.518), (-1.344, 1.344), (-2.793, 2.793))
"""The Unitree Z1's own joint ranges (rad), from its URDF (rounded)."""


def _with_arm(text: str, joints, inertia: float, effort: float, tool) -> str:
    """``text`` (a URDF) with an arm added before ``</robot>``: ``joints`` rows (name, parent, child,
    xyz, rpy, axis, mass, lower, upper) of revolute joints, each child link of that mass and a diagonal
    ``inertia``, then the fixed ``tool`` (name, parent, xyz, rpy)."""
    parts = []
    for name, parent, child, xyz, rpy, axis, mass, lower, upper in joints:
        parts.append(
            f'<link name="{child}"><inertial><mass value="{mass}"/><origin xyz="0 0 0"/>'
            f'<inertia ixx="{inertia}" ixy="0" ixz="0" iyy="{inertia}" iyz="0" izz="{inertia}"/>'
            "</inertial></link>"
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>'
            f'<limit lower="{lower}" upper="{upper}" effort="{effort}" velocity="3"/></joint>'
        )
    name, parent, xyz, rpy = tool
    parts.append(
        f'<link name="{name}"/><joint name="{name}_fixed" type="fixed"><parent link="{parent}"/>'
        f'<child link="{name}"/><origin xyz="{xyz}" rpy="{rpy}"/></joint>'
    )
    end = text.rindex("</robot>")
    return text[:end] + "\n".join(parts) + "\n" + text[end:]


def go2_with_z1(limits=None) -> str:
    """Go2's packaged URDF with a Z1-like arm on its body: 0.5 kg links, ``limits`` (6 (lower, upper)
    pairs; default -2.9..2.9 on every joint)."""
    import spotkin as sk

    with open(sk.robots.path("go2"), encoding="utf-8") as file:
        text = file.read()
    rows = [
        (name, parent, child, xyz, "0 0 0", axis, 0.5, *((-2.9, 2.9) if limits is None else limits[k]))
        for k, (name, parent, child, xyz, axis) in enumerate(Z1_JOINTS)
    ]
    return _with_arm(text, rows, 1e-3, 30, ("z1_gripper", "z1_link06", "0.051 0 0", "0 0 0"))


UR5_JOINTS = [  # name, parent, child, xyz, rpy, axis, mass: the UR5's own URDF (ur_description)
    ("ur_shoulder_pan", "trunk", "ur_shoulder", "0.3 0 0.17", "0 0 0", "0 0 1", 3.7),
    (
        "ur_shoulder_lift",
        "ur_shoulder",
        "ur_upper_arm",
        "0 0.13585 0",
        "0 1.5707963267948966 0",
        "0 1 0",
        8.393,
    ),
    ("ur_elbow", "ur_upper_arm", "ur_forearm", "0 -0.1197 0.425", "0 0 0", "0 1 0", 2.275),
    ("ur_wrist_1", "ur_forearm", "ur_wrist_1_link", "0 0 0.39225", "0 1.5707963267948966 0", "0 1 0", 1.219),
    ("ur_wrist_2", "ur_wrist_1_link", "ur_wrist_2_link", "0 0.093 0", "0 0 0", "0 0 1", 1.219),
    ("ur_wrist_3", "ur_wrist_2_link", "ur_wrist_3_link", "0 0 0.09465", "0 0 0", "0 1 0", 0.1879),
]


def heavy_with_ur5() -> str:
    """The tests' 90 kg quadruped ("heavy") carrying a UR5 on its trunk: the UR5's joint frames
    (rotated origins included), link masses and tool frame, joints limited to +-pi, the base 0.3 m
    ahead of the trunk's centre and 0.17 m above it."""
    rows = [(*row, -3.14159, 3.14159) for row in UR5_JOINTS]
    tool = ("ur_tool0", "ur_wrist_3_link", "0 0.0823 0", "0 0 1.5707963267948966")
    return _with_arm(quadruped_urdf(0.4, 90.0, 200.0), rows, 1e-2, 150, tool)


_named: dict = {}


def robot_named(name: str):
    """A robot by name, made once: "spot" (built in), "go2" (packaged), "heavy" (the tests' own 90 kg
    quadruped: 0.4 m segments, 200 N m motors, no meshes), "small" (2 kg, 0.1 m segments), "go2_z1"
    (Go2 carrying a Z1-like arm with the Z1's joint ranges) and "heavy_ur5" (heavy carrying a UR5)."""
    import spotkin as sk

    if name not in _named:
        _named[name] = {
            "spot": sk.Spot,
            "go2": lambda: sk.Robot.from_urdf(sk.robots.path("go2")),
            "heavy": lambda: sk.Robot.from_urdf_string(quadruped_urdf(0.4, 90.0, 200.0)),
            "small": lambda: sk.Robot.from_urdf_string(quadruped_urdf(0.1, 2.0, 5.0)),
            "go2_z1": lambda: sk.Robot.from_urdf_string(go2_with_z1(Z1_LIMITS)),
            "heavy_ur5": lambda: sk.Robot.from_urdf_string(heavy_with_ur5()),
        }[name]()
    return _named[name]
