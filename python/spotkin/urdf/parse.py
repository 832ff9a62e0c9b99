"""URDF XML to a :class:`~spotkin.urdf.Model`: every element checked, problems named. Part of
:mod:`spotkin.urdf` (documented there)."""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET

import numpy as np

from .files import read_file
from .tree import _NUMBER, JOINT_TYPES, Inertial, Joint, Link, Model, RootJoint, _rpy

# --------------------------------------------------------------------------- parsing


def _floats(text: str | None, n: int, what: str, default: tuple[float, ...] | None = None):
    if text is None:
        if default is None:
            raise ValueError(f"{what}: missing")
        return default
    parts = text.split()
    if len(parts) != n:
        raise ValueError(f"{what}: expected {n} numbers, got {len(parts)} ({text!r})")
    out = []
    for p in parts:
        if not _NUMBER.fullmatch(p):
            raise ValueError(f"{what}: {p!r} is not a number")
        v = float(p)
        if not math.isfinite(v):
            raise ValueError(f"{what}: {p!r} is not finite")
        out.append(v)
    return tuple(out)


def _float(text: str | None, what: str, default: float | None = None) -> float | None:
    if text is None:
        return default
    return _floats(text, 1, what)[0]


def _origin(el: ET.Element | None, what: str) -> np.ndarray:
    T = np.eye(4)
    if el is None:
        return T
    xyz = _floats(el.get("xyz"), 3, f"{what}: origin xyz", (0.0, 0.0, 0.0))
    rpy = _floats(el.get("rpy"), 3, f"{what}: origin rpy", (0.0, 0.0, 0.0))
    if rpy != (0.0, 0.0, 0.0):
        T[:3, :3] = _rpy(*rpy)
    T[:3, 3] = xyz
    return T


def _parse_inertial(el: ET.Element, link: str) -> Inertial:
    what = f"link {link!r}: inertial"
    origin = _origin(el.find("origin"), what)
    mass_el = el.find("mass")
    if mass_el is None:
        raise ValueError(f"{what}: missing <mass>")
    mass = _float(mass_el.get("value"), f"{what}: mass")
    if mass is None:
        raise ValueError(f"{what}: <mass> has no value")
    if mass < 0:
        raise ValueError(f"{what}: negative mass {mass:g}")
    inertia_el = el.find("inertia")
    if inertia_el is None:
        raise ValueError(f"{what}: missing <inertia>")
    c = {}
    for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"):
        default = 0.0 if key in ("ixy", "ixz", "iyz") else None
        value = _float(inertia_el.get(key), f"{what}: inertia {key}", default)
        if value is None:
            raise ValueError(f"{what}: inertia has no {key}")
        c[key] = value
    local = np.array(
        [[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]], [c["ixz"], c["iyz"], c["izz"]]]
    )
    R = origin[:3, :3]
    inertia = R @ local @ R.T
    inertia = 0.5 * (inertia + inertia.T)
    try:
        return Inertial(mass=mass, com=origin[:3, 3].copy(), inertia=inertia, rotation=R.copy())
    except ValueError as exc:
        raise ValueError(f"link {link!r}: {exc}") from None


def _collision_spheres(el: ET.Element) -> tuple[tuple[tuple[float, float, float], float], ...]:
    """The link's ``<collision>`` spheres as ((x, y, z), radius) in the link frame. Collisions are
    optional extras to the kinematics: one that does not read as a sphere with a positive finite
    radius and a valid origin is read past, as every other collision geometry is."""
    spheres = []
    for collision in el.iterfind("collision"):
        sphere = collision.find("geometry/sphere")
        if sphere is None:
            continue
        try:
            radius = _float(sphere.get("radius"), "collision sphere radius")
            centre = _origin(collision.find("origin"), "collision")[:3, 3]
        except ValueError:
            continue
        if radius is not None and radius > 0:
            spheres.append((tuple(float(v) for v in centre), radius))
    return tuple(spheres)


def _parse_joint(el: ET.Element, k: int, index: int) -> Joint:
    name = el.get("name")
    if not name:
        raise ValueError(f"joint #{k + 1} (in file order) has no name")
    what = f"joint {name!r}"
    jtype = el.get("type")
    if jtype is None:
        raise ValueError(f"{what}: missing type")
    if jtype == "planar":
        raise ValueError(
            f"{what}: type 'planar' is not supported: spotkin's chains and trees are made of 1-dof revolute "
            "and prismatic joints, and a planar joint moves in 3 (x, y and the rotation about the normal); "
            "describe it as two prismatic joints and a revolute one through massless links"
        )
    floating = jtype == "floating"  # the root joint, when it is one: parse_urdf decides
    if floating:
        jtype = "fixed"
    if jtype not in JOINT_TYPES:
        raise ValueError(f"{what}: unknown type {jtype!r}")
    links = []
    for role in ("parent", "child"):
        sub = el.find(role)
        link = sub.get("link") if sub is not None else None
        if not link:
            raise ValueError(f"{what}: missing {role} link")
        links.append(link)
    origin = _origin(el.find("origin"), what)
    axis = None
    lower, upper, effort, velocity = -math.inf, math.inf, None, None
    if jtype != "fixed":
        axis_el = el.find("axis")
        axis = (1.0, 0.0, 0.0)
        if axis_el is not None:
            axis = _floats(axis_el.get("xyz"), 3, f"{what}: axis xyz", axis)
        if axis == (0.0, 0.0, 0.0):
            raise ValueError(f"{what}: the axis of a {jtype} joint must not be zero")
        limit = el.find("limit")
        if limit is None and jtype != "continuous":
            raise ValueError(f"{what}: a {jtype} joint needs a <limit>")
        if limit is not None:
            effort = _float(limit.get("effort"), f"{what}: limit effort")
            velocity = _float(limit.get("velocity"), f"{what}: limit velocity")
            if jtype != "continuous":
                lower = _float(limit.get("lower"), f"{what}: limit lower", 0.0)
                upper = _float(limit.get("upper"), f"{what}: limit upper", 0.0)
                if lower > upper:
                    raise ValueError(f"{what}: lower limit {lower:g} is above upper limit {upper:g}")
    mimic, multiplier, offset = None, 1.0, 0.0
    mimic_el = el.find("mimic")
    if mimic_el is not None and jtype != "fixed":
        mimic = mimic_el.get("joint")
        if not mimic:
            raise ValueError(f"{what}: <mimic> names no joint")
        multiplier = _float(mimic_el.get("multiplier"), f"{what}: mimic multiplier", 1.0)
        offset = _float(mimic_el.get("offset"), f"{what}: mimic offset", 0.0)
    elif mimic_el is not None:
        raise ValueError(f"{what}: a {'floating' if floating else jtype} joint cannot mimic another joint")
    return Joint(
        name=name,
        type=jtype,
        parent=links[0],
        child=links[1],
        origin=origin,
        axis=None if axis is None else np.array(axis),
        lower=lower,
        upper=upper,
        effort=effort,
        velocity=velocity,
        index=index if jtype != "fixed" and mimic is None else -1,
        mimic=mimic,
        multiplier=multiplier,
        offset=offset,
    )


def parse_urdf(text: str | bytes) -> Model:
    """Parse URDF text (``str``, or ``bytes`` honouring the XML encoding declaration); ``TypeError``
    for another type."""
    if not isinstance(text, (str, bytes, bytearray)):
        raise TypeError(f"text must be a str or bytes holding URDF XML, got {type(text).__name__}")
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as exc:
        line, column = exc.position
        raise ValueError(f"malformed URDF (XML error at line {line}, column {column}): {exc}") from None
    if robot.tag != "robot":
        raise ValueError(f"the root element is <{robot.tag}>, not <robot>")
    name = robot.get("name", "")
    links: dict[str, Link] = {}
    for k, el in enumerate(robot.iterfind("link")):
        link = el.get("name")
        if not link:
            raise ValueError(f"link #{k + 1} (in file order) has no name")
        if link in links:
            raise ValueError(f"duplicate link name {link!r}")
        inertial_el = el.find("inertial")
        inertial = _parse_inertial(inertial_el, link) if inertial_el is not None else None
        links[link] = Link(link, inertial, _collision_spheres(el))
    if not links:
        raise ValueError(f"robot {name!r} has no links")
    joints = []
    index = 0
    seen: set[str] = set()
    floating: list[str] = []
    for k, el in enumerate(robot.iterfind("joint")):
        j = _parse_joint(el, k, index)
        if j.name in seen:
            raise ValueError(f"duplicate joint name {j.name!r}")
        seen.add(j.name)
        for role, link in (("parent", j.parent), ("child", j.child)):
            if link not in links:
                raise ValueError(f"joint {j.name!r}: {role} link {link!r} is not declared")
        if el.get("type") == "floating":
            floating.append(j.name)
        if j.type != "fixed" and j.mimic is None:
            index += 1
        joints.append(j)
    children = {j.child for j in joints}
    roots = [link for link in links if link not in children]
    root_joint = _root_joint(links, joints, roots, floating)
    if root_joint is not None:
        del links[root_joint.parent]
        joints = [j for j in joints if j.name != root_joint.name]
        roots = [root_joint.child]
    for j in floating:
        if root_joint is None or j != root_joint.name:
            raise ValueError(
                f"joint {j!r}: type 'floating' is only supported as the root joint, from the root link (a "
                "'world' link with no mass and no other joint) to the robot's base"
            )
    # Model validates the tree (loops, several roots) with a message naming the links.
    root = roots[0] if roots else next(iter(links))
    return Model(name=name, links=links, joints=tuple(joints), root=root, root_joint=root_joint)


def _root_joint(links: dict[str, Link], joints: list[Joint], roots: list[str], floating: list[str]):
    """The :class:`RootJoint` of a file whose single root link hangs the robot by a floating joint (or a
    fixed joint from a link called ``world``), or None."""
    if len(roots) != 1:
        return None
    top = roots[0]
    below = [j for j in joints if j.parent == top]
    if len(below) != 1:
        return None
    j = below[0]
    if j.name not in floating and not (j.type == "fixed" and top == "world"):
        return None
    inertial = links[top].inertial
    if inertial is not None and inertial.mass > 0:
        if j.name in floating:
            raise ValueError(
                f"link {top!r}, above the floating root joint {j.name!r}, has a mass: the root joint must "
                "start from a massless world link"
            )
        return None
    kind = "floating" if j.name in floating else "fixed"
    return RootJoint(name=j.name, type=kind, parent=top, child=j.child, origin=j.origin)


def load_urdf(path: str | os.PathLike) -> Model:
    """Read and parse a URDF file (bytes, so the XML encoding declaration is honoured); a ``.xacro``
    file is expanded first (:func:`read_file`)."""
    return parse_urdf(read_file(path))
