"""URDF parsing, kinematic-tree utilities and recognition of legs and arms.

Standard library plus NumPy only: the XML is read with :mod:`xml.etree.ElementTree`.
Only kinematics and inertia are kept; meshes (``package://`` paths or any other),
visuals, collisions, transmissions and ``<gazebo>`` tags are read past and never loaded.
A ``.xacro`` description is expanded first with the ``xacro`` package when it is
installed (``pip install "spotkin[xacro]"``; see :func:`read_description`).

Joints
------
* ``<mimic joint="leader" multiplier="m" offset="o"/>``: the joint follows its leader,
  ``q = m q_leader + o``. It is no independent variable: :attr:`Model.actuated_joints`
  leaves it out (:attr:`Model.mimic_joints` lists it), and every chain it lies on moves it
  with its leader (:meth:`spotkin.Chain.from_urdf`).
* A ``floating`` joint from the root link (a massless ``world`` link), or a ``fixed`` joint
  from a link called ``world``, is the robot's root joint (:class:`RootJoint`): the world
  link and that joint are dropped and the robot's base link becomes the root. A
  ``floating`` joint anywhere else, and every ``planar`` joint, is refused.

Conventions (standard URDF semantics)
-------------------------------------
* ``origin rpy`` is fixed-axis roll-pitch-yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``.
* A joint moves its child as ``T_parent_child(q) = origin · Rot(axis, q)`` (revolute,
  continuous) or ``origin · Trans(axis · q)`` (prismatic); ``axis`` is in the joint frame.
* Every problem found in a file raises :class:`ValueError` naming the joint or link.
  Unknown link or joint names passed to the methods raise :class:`ValueError` too.

Recognition
-----------
:func:`find_legs` finds roll-pitch-pitch legs (hip roll about ±x, hip pitch and knee about
±y of the root frame at zero angles) and returns their geometry as used by the leg solver:
``p_leg(q) = Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c))`` in a frame at the hip-roll joint
origin with axes parallel to the root frame. :func:`find_arms` finds 6-joint arms and tells
whether their wrist is spherical. :func:`describe` prints a summary.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ._support.boundary import as_real

__all__ = [
    "ArmSpec",
    "ChainData",
    "Inertial",
    "Joint",
    "LegSpec",
    "Link",
    "Model",
    "RootJoint",
    "describe",
    "expand_xacro",
    "find_arms",
    "find_legs",
    "is_xacro",
    "load_urdf",
    "parse_urdf",
    "read_file",
    "read_text",
]

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_FOOT_WORDS = ("foot", "toe", "contact", "tip")
_TIP_WORDS = re.compile(r"hand|tool|gripper|flange|tip|(?:^|[^a-z])ee(?:[^a-z]|$)", re.IGNORECASE)


# --------------------------------------------------------------------------- helpers


def _readonly(value, shape: tuple[int, ...], what: str) -> np.ndarray:
    arr = np.array(as_real(value, what, np.float64), dtype=float)  # masked, complex, text: TypeError
    if arr.shape != shape:
        raise ValueError(f"{what}: expected shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what}: values must be finite")
    arr.setflags(write=False)
    return arr


def _rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) as a (3, 3) array."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _motion(joint: Joint, q: float) -> np.ndarray:
    """The (4, 4) motion of ``joint`` at value ``q`` (applied after its origin)."""
    T = np.eye(4)
    if joint.type == "fixed" or q == 0.0:
        return T
    x, y, z = joint.axis
    if joint.type == "prismatic":
        T[:3, 3] = (x * q, y * q, z * q)
        return T
    c, s = math.cos(q), math.sin(q)
    v = 1.0 - c
    T[:3, :3] = (
        (c + x * x * v, x * y * v - z * s, x * z * v + y * s),
        (y * x * v + z * s, c + y * y * v, y * z * v - x * s),
        (z * x * v - y * s, z * y * v + x * s, c + z * z * v),
    )
    return T


def _fmt(v) -> str:
    return "(" + ", ".join(f"{round(float(x), 12) + 0.0:.6g}" for x in np.ravel(v)) + ")"


def _plural(k: int, word: str) -> str:
    return f"{k} {word}" if k == 1 else f"{k} {word}s"


def _common_name(names: Iterable[str]) -> str:
    names = list(names)
    n = min(len(x) for x in names)
    k = 0
    while k < n and all(x[k] == names[0][k] for x in names):
        k += 1
    return names[0][:k].rstrip("_-. ")


# --------------------------------------------------------------------------- data model


@dataclass(frozen=True, eq=False)
class Inertial:
    """Mass properties of a link, in the link frame.

    ``com`` is the centre of mass; ``inertia`` the (3, 3) inertia tensor about the centre
    of mass, already rotated into the link frame (``R I R^T``); ``rotation`` is that ``R``
    (the rotation of the URDF ``<inertial><origin rpy>``).
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    rotation: np.ndarray

    def __post_init__(self) -> None:
        mass = float(self.mass)
        if not math.isfinite(mass) or mass < 0:
            raise ValueError(f"inertial: mass must be finite and non-negative, got {self.mass!r}")
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "com", _readonly(self.com, (3,), "inertial com"))
        inertia = _readonly(self.inertia, (3, 3), "inertial inertia")
        scale = max(float(np.max(np.abs(inertia))), 1e-300)
        if np.max(np.abs(inertia - inertia.T)) > 1e-12 * scale:
            raise ValueError("inertial: the inertia matrix is not symmetric")
        trace = float(np.trace(inertia))
        if float(np.min(np.linalg.eigvalsh(inertia))) < -1e-9 * max(abs(trace), 1e-300):
            raise ValueError("inertial: the inertia matrix is not positive semidefinite")
        object.__setattr__(self, "inertia", inertia)
        object.__setattr__(self, "rotation", _readonly(self.rotation, (3, 3), "inertial rotation"))


@dataclass(frozen=True, eq=False)
class Link:
    """A link: its name and optional mass properties."""

    name: str
    inertial: Inertial | None = None


@dataclass(frozen=True, eq=False)
class Joint:
    """A joint between two links.

    ``origin`` (4, 4) places the joint frame in the parent link frame; the child link frame
    is the joint frame moved by the joint. ``axis`` is a unit vector in the joint frame
    (``None`` for fixed joints). ``lower``/``upper`` are ±inf for continuous joints.
    ``index`` is the position among the actuated joints (:attr:`Model.actuated_joints`: neither
    fixed nor mimic) in file order, -1 for fixed and mimic joints.

    ``mimic`` names the joint this one follows (URDF ``<mimic joint=... multiplier=... offset=...>``),
    None for an independent joint: ``q = multiplier * q_mimic + offset``. A mimic joint is not an
    independent variable: it moves with its leader in every chain it lies on.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray | None
    lower: float
    upper: float
    effort: float | None = None
    velocity: float | None = None
    index: int = -1
    mimic: str | None = None
    multiplier: float = 1.0
    offset: float = 0.0

    def __post_init__(self) -> None:
        if self.type not in JOINT_TYPES:
            raise ValueError(f"joint {self.name!r}: unknown type {self.type!r}")
        if self.mimic is not None:
            if not isinstance(self.mimic, str) or not self.mimic:
                raise ValueError(f"joint {self.name!r}: mimic must name a joint, got {self.mimic!r}")
            if self.type == "fixed":
                raise ValueError(f"joint {self.name!r}: a fixed joint cannot mimic another joint")
            if self.mimic == self.name:
                raise ValueError(f"joint {self.name!r}: a joint cannot mimic itself")
        for key in ("multiplier", "offset"):
            value = float(getattr(self, key))
            if not math.isfinite(value):
                raise ValueError(f"joint {self.name!r}: mimic {key} must be finite")
            object.__setattr__(self, key, value)
        object.__setattr__(self, "origin", _readonly(self.origin, (4, 4), f"joint {self.name!r} origin"))
        if self.type == "fixed":
            object.__setattr__(self, "axis", None)
        else:
            axis = np.array(self.axis if self.axis is not None else (1.0, 0.0, 0.0), dtype=float)
            norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else math.nan
            if not math.isfinite(norm):
                raise ValueError(f"joint {self.name!r}: axis must be 3 finite numbers")
            if norm == 0.0:
                raise ValueError(f"joint {self.name!r}: the axis of a {self.type} joint must not be zero")
            object.__setattr__(self, "axis", _readonly(axis / norm, (3,), f"joint {self.name!r} axis"))
        if self.type == "continuous":
            object.__setattr__(self, "lower", -math.inf)
            object.__setattr__(self, "upper", math.inf)
        lower, upper = float(self.lower), float(self.upper)
        if math.isnan(lower) or math.isnan(upper):
            raise ValueError(f"joint {self.name!r}: limits must not be NaN")
        if lower > upper:
            raise ValueError(f"joint {self.name!r}: lower limit {lower:g} is above upper limit {upper:g}")
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)

    @property
    def actuated(self) -> bool:
        """True for revolute, continuous and prismatic joints (a mimic joint moves too, with its
        leader; :attr:`Model.actuated_joints` leaves it out as it is no independent variable)."""
        return self.type != "fixed"

    def follows(self, value: float) -> float:
        """This mimic joint's value when its leader is at ``value``: ``multiplier * value + offset``."""
        return self.multiplier * value + self.offset


@dataclass(frozen=True, eq=False)
class RootJoint:
    """The joint a URDF hangs its robot from: a ``floating`` joint (the robot's base moves freely: a
    legged robot's body) or a ``fixed`` one from a link called ``world`` (a mounted arm), from the
    world link ``parent`` to the robot's root link ``child``, placed by ``origin`` (4, 4). It is read,
    not modelled: frames are in the root link's frame (see :attr:`Model.root_joint`)."""

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray

    def __post_init__(self) -> None:
        if self.type not in ("floating", "fixed"):
            raise ValueError(
                f"root joint {self.name!r}: type must be 'floating' or 'fixed', got {self.type!r}"
            )
        object.__setattr__(self, "origin", _readonly(self.origin, (4, 4), f"root joint {self.name!r} origin"))


@dataclass(frozen=True, eq=False)
class ChainData:
    """A serial chain from ``base`` to ``tip`` with the fixed joints merged.

    With ``F_0 = I``, the frame of the child link of actuated joint ``j`` in the base frame
    is ``F_{j+1} = F_j · placements[j] · M_j(q_j)``, with ``M_j`` the rotation about (types 0)
    or translation along (type 1) ``axes[j]``; the tip frame is ``F_n · tool``.

    Every moving joint on the path is a row, mimic joints included: ``mimic[j]`` is None for an
    independent joint and ``(leader, multiplier, offset)`` for a mimic one
    (``q_j = multiplier * q_leader + offset``; the leader may be off the path).
    """

    joint_names: tuple[str, ...]
    placements: np.ndarray
    axes: np.ndarray
    types: np.ndarray
    limits: np.ndarray
    tool: np.ndarray
    base: str
    tip: str
    continuous: np.ndarray
    mimic: tuple[tuple[str, float, float] | None, ...] | None = None

    def __post_init__(self) -> None:
        n = len(self.joint_names)
        object.__setattr__(self, "joint_names", tuple(self.joint_names))
        mimic = (None,) * n if self.mimic is None else tuple(self.mimic)
        if len(mimic) != n:
            raise ValueError(f"mimic: expected {n} entries, got {len(mimic)}")
        object.__setattr__(self, "mimic", mimic)
        object.__setattr__(self, "placements", _readonly(self.placements, (n, 4, 4), "placements"))
        object.__setattr__(self, "axes", _readonly(self.axes, (n, 3), "axes"))
        types = np.array(self.types, dtype=np.int8).reshape(n)
        types.setflags(write=False)
        object.__setattr__(self, "types", types)
        limits = np.array(self.limits, dtype=float).reshape(n, 2)
        limits.setflags(write=False)
        object.__setattr__(self, "limits", limits)
        object.__setattr__(self, "tool", _readonly(self.tool, (4, 4), "tool"))
        continuous = np.array(self.continuous, dtype=bool).reshape(n)
        continuous.setflags(write=False)
        object.__setattr__(self, "continuous", continuous)

    @property
    def n(self) -> int:
        """Number of actuated joints."""
        return len(self.joint_names)


@dataclass(frozen=True, eq=False)
class Model:
    """A kinematic tree: links (file order), joints (file order) and the root link name.

    Construction validates the tree (declared links, one parent per link, no loop, a
    single root) and the mimic joints (their leader exists, moves the same way and is no mimic).

    ``root_joint`` is the joint the file hangs the root link from, when it has one: a
    ``floating`` joint from the root link, or a ``fixed`` one from a link called ``world``. That
    link and joint are not part of the tree: the root (the body, for a legged robot) is the joint's
    child, and every frame is in its frame.
    """

    name: str
    links: dict[str, Link]
    joints: tuple[Joint, ...]
    root: str
    root_joint: RootJoint | None = None
    _joint_by_name: dict[str, Joint] = field(init=False, repr=False)
    _parent: dict[str, Joint] = field(init=False, repr=False)
    _children: dict[str, tuple[Joint, ...]] = field(init=False, repr=False)
    _zero: dict[str, np.ndarray] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        links = dict(self.links)
        joints = tuple(self.joints)
        object.__setattr__(self, "links", links)
        object.__setattr__(self, "joints", joints)
        if not links:
            raise ValueError(f"robot {self.name!r} has no links")
        by_name: dict[str, Joint] = {}
        parent: dict[str, Joint] = {}
        children: dict[str, list[Joint]] = {name: [] for name in links}
        for j in joints:
            if j.name in by_name:
                raise ValueError(f"duplicate joint name {j.name!r}")
            by_name[j.name] = j
            for role, link in (("parent", j.parent), ("child", j.child)):
                if link not in links:
                    raise ValueError(f"joint {j.name!r}: {role} link {link!r} is not declared")
            if j.parent == j.child:
                raise ValueError(f"joint {j.name!r}: a loop, link {j.child!r} is its own parent")
            if j.child in parent:
                raise ValueError(
                    f"link {j.child!r} has two parent joints: {parent[j.child].name!r} and {j.name!r}"
                )
            parent[j.child] = j
            children[j.parent].append(j)
        for j in joints:
            if j.mimic is None:
                continue
            leader = by_name.get(j.mimic)
            if leader is None:
                raise ValueError(f"joint {j.name!r}: it mimics joint {j.mimic!r}, which does not exist")
            if leader.type == "fixed":
                raise ValueError(f"joint {j.name!r}: it mimics joint {leader.name!r}, which is fixed")
            if leader.mimic is not None:
                raise ValueError(
                    f"joint {j.name!r}: it mimics joint {leader.name!r}, itself a mimic of {leader.mimic!r}; "
                    f"make {j.name!r} mimic {leader.mimic!r} directly"
                )
            if (leader.type == "prismatic") != (j.type == "prismatic"):
                raise ValueError(
                    f"joint {j.name!r} ({j.type}) mimics joint {leader.name!r} ({leader.type}): a mimic "
                    "joint must move the way its leader does (both prismatic, or both revolute/continuous)"
                )
        # Each link has at most one parent: follow parents to find loops.
        state: dict[str, int] = {}
        for start in links:
            trail = []
            link = start
            while link in parent and state.get(link) is None:
                state[link] = 1
                trail.append(link)
                link = parent[link].parent
            if state.get(link) == 1:
                cycle = trail[trail.index(link) :] if link in trail else [link]
                raise ValueError("the joints form a loop through links " + ", ".join(repr(x) for x in cycle))
            for x in trail:
                state[x] = 2
        roots = [name for name in links if name not in parent]
        if len(roots) > 1:
            raise ValueError(
                f"robot {self.name!r} has {len(roots)} root links (links without a parent joint): "
                + ", ".join(repr(r) for r in roots)
                + "; a URDF must form a single tree"
            )
        if self.root != roots[0]:
            raise ValueError(f"robot {self.name!r}: the root link is {roots[0]!r}, not {self.root!r}")
        if self.root_joint is not None and self.root_joint.child != self.root:
            raise ValueError(
                f"robot {self.name!r}: the root joint's child is not the root link {self.root!r}"
            )
        object.__setattr__(self, "_joint_by_name", by_name)
        object.__setattr__(self, "_parent", parent)
        object.__setattr__(self, "_children", {k: tuple(v) for k, v in children.items()})
        # Placements at zero angles, in the root frame (parents before children); a mimic joint sits
        # at its offset (its leader at zero).
        zero = {self.root: np.eye(4)}
        stack = [self.root]
        while stack:
            link = stack.pop()
            for j in reversed(self._children[link]):
                zero[j.child] = zero[link] @ j.origin
                if j.mimic is not None and j.offset != 0.0:
                    zero[j.child] = zero[j.child] @ _motion(j, j.offset)
                stack.append(j.child)
        for T in zero.values():
            T.setflags(write=False)
        object.__setattr__(self, "_zero", zero)

    def __repr__(self) -> str:
        links, joints = _plural(len(self.links), "link"), _plural(len(self.joints), "joint")
        n = len(self.actuated_joints)
        mimic = f", {len(self.mimic_joints)} mimic" if self.mimic_joints else ""
        return f"Model(name={self.name!r}, {links}, {joints} ({n} actuated{mimic}), root={self.root!r})"

    # ---- look-ups

    def _check_link(self, name: str) -> None:
        if name not in self.links:
            raise ValueError(f"unknown link {name!r}")

    @property
    def actuated_joints(self) -> tuple[Joint, ...]:
        """The independent moving joints (neither fixed nor mimic), in file order: the variables of
        the description."""
        return tuple(j for j in self.joints if j.type != "fixed" and j.mimic is None)

    @property
    def mimic_joints(self) -> tuple[Joint, ...]:
        """The mimic joints (each follows an actuated joint, :attr:`Joint.mimic`), in file order."""
        return tuple(j for j in self.joints if j.mimic is not None)

    def joint(self, name: str) -> Joint:
        """The joint called ``name``."""
        try:
            return self._joint_by_name[name]
        except KeyError:
            raise ValueError(f"unknown joint {name!r}") from None

    def link(self, name: str) -> Link:
        """The link called ``name``."""
        self._check_link(name)
        return self.links[name]

    def parent_joint(self, link: str) -> Joint | None:
        """The joint whose child is ``link`` (None for the root)."""
        self._check_link(link)
        return self._parent.get(link)

    def children(self, link: str) -> tuple[Joint, ...]:
        """The joints whose parent is ``link``, in file order."""
        self._check_link(link)
        return self._children[link]

    @property
    def leaves(self) -> tuple[str, ...]:
        """The links without child joints, in file order."""
        return tuple(name for name in self.links if not self._children[name])

    def path(self, link: str, base: str | None = None) -> tuple[Joint, ...]:
        """The joints from ``base`` (default: the root) down to ``link``."""
        self._check_link(link)
        base = self.root if base is None else base
        self._check_link(base)
        out = []
        cur = link
        while cur != base:
            j = self._parent.get(cur)
            if j is None:
                raise ValueError(f"link {link!r} is not below link {base!r}")
            out.append(j)
            cur = j.parent
        return tuple(reversed(out))

    def placement(self, link: str, q: Mapping[str, float] | None = None) -> np.ndarray:
        """The (4, 4) frame of ``link`` in the root frame, at zero angles or at ``q``.

        ``q`` maps actuated joint names to values; joints not named are at zero. A mimic joint
        follows its leader (``multiplier * q[leader] + offset``), also when ``q`` is empty.
        """
        self._check_link(link)
        q = {} if q is None else q
        if not q:
            return self._zero[link].copy()
        path = self.path(link)
        for name in q:
            joint = self.joint(name)
            if joint.type == "fixed":
                raise ValueError(f"joint {name!r} is fixed and takes no value")
            if joint.mimic is not None:
                raise ValueError(
                    f"joint {name!r} mimics joint {joint.mimic!r} and takes no value: give {joint.mimic!r}'s"
                )
        T = np.eye(4)
        for j in path:
            T = T @ j.origin
            if j.type != "fixed":
                if j.mimic is None:
                    value = float(q.get(j.name, 0.0))
                else:
                    value = j.follows(float(q.get(j.mimic, 0.0)))
                if not math.isfinite(value):
                    raise ValueError(f"joint {j.name!r}: value must be finite")
                T = T @ _motion(j, value)
        return T

    def with_limits(self, limits: Mapping[str, tuple[float, float]]) -> Model:
        """A new Model whose named moving joints have other (lower, upper) limits; a continuous joint
        given finite limits becomes revolute. ``ValueError`` for an unknown or fixed joint."""
        table = dict(limits)
        for name in table:
            if self.joint(name).type == "fixed":
                raise ValueError(f"limits: joint {name!r} is fixed and has no limits")
        joints = []
        for j in self.joints:
            if j.name in table:
                lower, upper = (float(v) for v in table[j.name])
                kind = "revolute" if j.type == "continuous" and math.isfinite(upper - lower) else j.type
                j = dataclasses.replace(j, type=kind, lower=lower, upper=upper)
            joints.append(j)
        return Model(
            name=self.name, links=self.links, joints=tuple(joints), root=self.root, root_joint=self.root_joint
        )

    def chain_data(self, link: str, base: str | None = None) -> ChainData:
        """The serial chain from ``base`` (default: the root) to ``link``, fixed joints merged."""
        base = self.root if base is None else base
        path = self.path(link, base)
        names, placements, axes, types, limits, continuous, mimic = [], [], [], [], [], [], []
        acc = np.eye(4)
        for j in path:
            acc = acc @ j.origin
            if j.type == "fixed":
                continue
            names.append(j.name)
            placements.append(acc)
            axes.append(j.axis)
            types.append(1 if j.type == "prismatic" else 0)
            limits.append((j.lower, j.upper))
            continuous.append(j.type == "continuous")
            mimic.append(None if j.mimic is None else (j.mimic, j.multiplier, j.offset))
            acc = np.eye(4)
        n = len(names)
        return ChainData(
            joint_names=tuple(names),
            placements=np.array(placements).reshape(n, 4, 4),
            axes=np.array(axes, dtype=float).reshape(n, 3),
            types=np.array(types, dtype=np.int8),
            limits=np.array(limits, dtype=float).reshape(n, 2),
            tool=acc,
            base=base,
            tip=link,
            continuous=np.array(continuous, dtype=bool),
            mimic=tuple(mimic),
        )


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
        links[link] = Link(link, inertial)
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


MAX_BYTES = 64 * 2**20
"""The largest description read (64 MiB): a URDF of kinematics and inertials is far smaller."""

XACRO_EXTRA = 'pip install "spotkin[xacro]"'


def read_file(path: str | os.PathLike) -> str | bytes:
    """The URDF XML in the file at ``path`` (``str`` or ``os.PathLike``): its bytes (so the XML encoding
    declaration decides), or, for a xacro file (:func:`is_xacro`), its expansion. ``OSError`` when it
    cannot be read (``IsADirectoryError``, ``FileNotFoundError``, ...), ``ValueError`` above
    :data:`MAX_BYTES`, ``TypeError`` for another type."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    name = os.fsdecode(os.fspath(path))
    with open(name, "rb") as fh:
        data = fh.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise ValueError(f"{name!r} is larger than {MAX_BYTES // 2**20} MiB: not a URDF description")
    return expand_xacro(data, name) if is_xacro(data, name) else data


def read_text(text: str | bytes) -> str | bytes:
    """URDF XML given as text (``str``, or ``bytes`` honouring the XML encoding declaration), expanded
    when it is xacro (:func:`is_xacro`). ``ValueError`` above :data:`MAX_BYTES`."""
    if isinstance(text, (bytearray, memoryview)):
        text = bytes(text)
    if not isinstance(text, (str, bytes)):
        raise TypeError(f"text must be a str or bytes holding URDF XML, got {type(text).__name__}")
    if len(text) > MAX_BYTES:
        raise ValueError(f"the text is larger than {MAX_BYTES // 2**20} MiB: not a URDF description")
    return expand_xacro(text) if is_xacro(text) else text


def is_xacro(data: str | bytes, name: str | None = None) -> bool:
    """Whether a description is xacro: its file name ends in ``.xacro``, or its text declares the
    ``xmlns:xacro`` namespace or uses ``<xacro:`` elements."""
    if name is not None and name.lower().endswith(".xacro"):
        return True
    markers = ("xmlns:xacro", "<xacro:")
    if isinstance(data, bytes):
        return any(m.encode() in data for m in markers)
    return any(m in data for m in markers)


def expand_xacro(data: str | bytes, name: str | None = None) -> str:
    """The URDF a xacro description expands to, with the ``xacro`` package (``pip install
    "spotkin[xacro]"``); ``name`` is its file (relative ``<xacro:include>`` are resolved from its
    folder). ``ImportError`` saying what to install when ``xacro`` is missing; ``ValueError`` when the
    expansion fails."""
    what = repr(name) if name else "the description"
    try:
        import xacro
    except ImportError:
        example = os.path.basename(name) if name else "robot.urdf.xacro"
        raise ImportError(
            f"{what} is xacro: expanding it needs the xacro package ({XACRO_EXTRA}), or expand it "
            f"first with `xacro {example} > robot.urdf` and load the URDF"
        ) from None
    text = data.decode("utf-8") if isinstance(data, bytes) else data
    try:
        if name is not None:
            doc = xacro.process_file(name)
        else:
            xacro.init_stacks(None)
            doc = xacro.parse(text)
            xacro.process_doc(doc)
        return doc.toxml()
    except Exception as error:  # xacro raises its own XacroException, XML errors, NameError...
        raise ValueError(f"xacro could not expand {what}: {error}") from None


# --------------------------------------------------------------------------- recognition


@dataclass(frozen=True, eq=False)
class LegSpec:
    """A roll-pitch-pitch leg, in the convention of the leg solver.

    Leg frame at the hip-roll joint origin (``hip_origin``, root frame, zero angles), axes
    parallel to the root frame; ``a``, ``b``, ``c`` are hip-roll→hip-pitch, hip-pitch→knee
    and knee→foot at zero angles; ``signs`` the axis signs (s1 x, s2 y, s3 y), so that
    ``p(q) = Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c))``. ``limits`` (3, 2) are the URDF
    limits of q. The foot point is the foot link origin plus ``R_foot · contact_offset``.
    """

    name: str
    joint_names: tuple[str, str, str]
    foot: str
    hip_origin: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    signs: np.ndarray
    limits: np.ndarray
    contact_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        names = tuple(self.joint_names)
        if len(names) != 3:
            raise ValueError(f"leg {self.name!r}: expected 3 joint names, got {len(names)}")
        object.__setattr__(self, "joint_names", names)
        for key in ("hip_origin", "a", "b", "c", "signs", "contact_offset"):
            object.__setattr__(self, key, _readonly(getattr(self, key), (3,), f"leg {self.name!r} {key}"))
        if not np.all(np.abs(self.signs) == 1.0):
            raise ValueError(f"leg {self.name!r}: signs must be +1 or -1")
        limits = np.array(self.limits, dtype=float)
        if limits.shape != (3, 2) or np.any(np.isnan(limits)):
            raise ValueError(f"leg {self.name!r}: limits must be a (3, 2) array of numbers")
        limits.setflags(write=False)
        object.__setattr__(self, "limits", limits)


@dataclass(frozen=True, eq=False)
class ArmSpec:
    """A 6-joint arm: its joints (root to tip), the tip link, the link it hangs from, and
    whether the last three axes meet at one point (``wrist_center``, root frame, zero
    angles; None when the wrist is not spherical)."""

    name: str
    joint_names: tuple[str, ...]
    tip: str
    base: str
    wrist_center: np.ndarray | None
    spherical_wrist: bool

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint_names", tuple(self.joint_names))
        if self.wrist_center is not None:
            object.__setattr__(
                self, "wrist_center", _readonly(self.wrist_center, (3,), f"arm {self.name!r} wrist_center")
            )


def _joint_frame(model: Model, j: Joint) -> np.ndarray:
    """The frame of joint ``j`` in the root frame at zero angles."""
    return model._zero[j.parent] @ j.origin


def _axis_root(model: Model, j: Joint) -> tuple[np.ndarray, np.ndarray]:
    F = _joint_frame(model, j)
    return F[:3, 3].copy(), F[:3, :3] @ j.axis


def _matches(axis: np.ndarray, k: int, tolerance: float) -> float:
    """+1 or -1 when ``axis`` is ±e_k within ``tolerance`` (component-wise), else 0."""
    s = 1.0 if axis[k] > 0 else -1.0
    e = np.zeros(3)
    e[k] = s
    return s if np.all(np.abs(axis - e) <= tolerance) else 0.0


def _relative(model: Model, start: str, end: str, offset=None) -> np.ndarray:
    """The vector from link ``start``'s origin to link ``end``'s (plus ``offset`` in ``end``'s frame),
    at zero angles, in root axes: R_start (product of the origins from start down to end).p."""
    T = np.eye(4)
    for joint in model.path(end, base=start):
        T = T @ joint.origin
    local = T[:3, 3] if offset is None else T[:3, 3] + T[:3, :3] @ offset
    return model._zero[start][:3, :3] @ local


def _offsets(model: Model, contact_offset) -> dict[str, np.ndarray] | np.ndarray:
    if contact_offset is None:
        return np.zeros(3)
    if isinstance(contact_offset, Mapping):
        out = {}
        for link, v in contact_offset.items():
            model.link(link)
            out[link] = _readonly(v, (3,), f"contact_offset for {link!r}")
        return out
    return _readonly(contact_offset, (3,), "contact_offset")


def _leg_geometry(model, joints, foot, offset, tolerance):
    """(LegSpec fields, None) for a roll-pitch-pitch path, or (None, reason)."""
    origins, axes = zip(*(_axis_root(model, j) for j in joints))
    signs = [
        _matches(axes[0], 0, tolerance),
        _matches(axes[1], 1, tolerance),
        _matches(axes[2], 1, tolerance),
    ]
    if 0.0 in signs:
        return None, "not roll-pitch-pitch: axes at zero angles are " + ", ".join(_fmt(z) for z in axes)
    # a, b, c from the relative placements along the path (rotated into the root frame), not as
    # differences of absolute positions: exact where the URDF's numbers are (Spot's a_y is 0.110945)
    a = _relative(model, joints[0].child, joints[1].child)
    b = _relative(model, joints[1].child, joints[2].child)
    c = _relative(model, joints[2].child, foot, offset)
    if math.hypot(b[0], b[2]) <= 1e-9:
        return None, f"not a leg: the hip-pitch to knee vector b = {_fmt(b)} has no x or z component"
    if math.hypot(c[0], c[2]) <= 1e-9:
        return None, f"not a leg: the knee to foot vector c = {_fmt(c)} has no x or z component"
    limits = [(j.lower, j.upper) for j in joints]
    return dict(hip_origin=origins[0], a=a, b=b, c=c, signs=signs, limits=limits), None


def _moving_above(
    model: Model, keep: int, marked: Collection[str] = ()
) -> dict[str, tuple[int, tuple[Joint, ...], bool]]:
    """For every link: the number of moving (non-fixed) joints on its path from the root, the first
    ``keep`` of them, and whether the path holds a joint named in ``marked``. One walk down the tree,
    linear in its size (a path per leaf would be quadratic on a long chain with a leaf per link)."""
    above = {model.root: (0, (), False)}
    stack = [model.root]
    while stack:
        link = stack.pop()
        count, first, on_marked = above[link]
        for j in model._children[link]:
            moving = j.type != "fixed"
            above[j.child] = (
                count + moving,
                first + (j,) if moving and count < keep else first,
                on_marked or j.name in marked,
            )
            stack.append(j.child)
    return above


def _link_names(value, name: str) -> tuple[str, ...] | None:
    """None, or link names given as one ``str`` or an iterable of them; ``TypeError`` naming ``name``."""
    if value is None:
        return None
    if isinstance(value, str):
        return (value,)
    try:
        names = tuple(value)
    except TypeError:
        raise TypeError(
            f"{name} must be a link name or a sequence of link names, got {type(value).__name__}"
        ) from None
    for item in names:
        if not isinstance(item, str):
            raise TypeError(f"{name} must hold link names (str), got {type(item).__name__}")
    return names


def find_legs(
    model: Model,
    feet: Iterable[str] | None = None,
    contact_offset=None,
    tolerance: float = 1e-9,
) -> tuple[tuple[LegSpec, ...], tuple[str, ...]]:
    """Find the roll-pitch-pitch legs of ``model``.

    Candidates are the leaves whose path from the root holds exactly three actuated joints,
    all revolute or continuous. Leaves sharing the same three joints give one leg; the foot
    is a leaf named with "foot", "toe", "contact" or "tip", else the one farthest from the
    knee. ``feet`` names the foot links instead (each must have exactly three revolute or
    continuous joints above it; it need not be a leaf) and only those legs are returned.
    ``contact_offset`` is None, a (3,) offset in the foot link frame for every foot, or a
    dict foot link -> (3,). Returns ``(legs, report)``: legs in URDF order of their first
    joint, and text lines on what was ignored or chosen, and why.
    """
    feet = _link_names(feet, "feet")
    offsets = _offsets(model, contact_offset)
    report: list[str] = []
    paths = {}
    above = _moving_above(model, 3)  # one walk down the tree: linear in its size

    def actuated_path(link):
        count, first, _ = above[link]
        return first if count <= 3 else tuple(j for j in model.path(link) if j.type != "fixed")

    if feet is not None:
        if len(set(feet)) != len(feet):
            raise ValueError("feet: a link is named twice")
        groups: dict[tuple[str, ...], list[str]] = {}
        for foot in feet:
            model.link(foot)
            joints = actuated_path(foot)
            if len(joints) != 3 or any(j.type == "prismatic" or j.mimic is not None for j in joints):
                kinds = ", ".join(f"{j.name} ({'mimic' if j.mimic else j.type})" for j in joints) or "none"
                raise ValueError(
                    f"foot link {foot!r} is not a leg candidate: it needs exactly 3 revolute or "
                    f"continuous joints above it, has {kinds}"
                )
            key = tuple(j.name for j in joints)
            if key in groups:
                raise ValueError(f"feet {groups[key][0]!r} and {foot!r} hang from the same three joints")
            groups[key] = [foot]
            paths[key] = joints
        chosen = {key: v[0] for key, v in groups.items()}
    else:
        groups = {}
        for leaf in model.leaves:
            count, joints, _ = above[leaf]
            if count != 3:
                report.append(f"ignored: {leaf} ({_plural(count, 'actuated joint')})")
                continue
            prismatic = [j.name for j in joints if j.type == "prismatic"]
            if prismatic:
                report.append(f"{leaf}: not a leg: joint {prismatic[0]!r} is prismatic")
                continue
            mimic = [j for j in joints if j.mimic is not None]
            if mimic:
                report.append(f"{leaf}: not a leg: joint {mimic[0].name!r} mimics {mimic[0].mimic!r}")
                continue
            key = tuple(j.name for j in joints)
            groups.setdefault(key, []).append(leaf)
            paths[key] = joints
        chosen = {}
        for key, leaves in groups.items():
            if len(leaves) == 1:
                chosen[key] = leaves[0]
                continue
            named = [x for x in leaves if any(w in x.lower() for w in _FOOT_WORDS)]
            pool = named or leaves
            knee = _joint_frame(model, paths[key][2])[:3, 3]
            foot = max(pool, key=lambda x: float(np.linalg.norm(model._zero[x][:3, 3] - knee)))
            why = "by name" if len(named) == 1 else "farthest from the knee"
            others = ", ".join(x for x in leaves if x != foot)
            report.append(f"{foot}: chosen as the foot of joints {', '.join(key)} ({why}); not {others}")
            chosen[key] = foot
    if isinstance(offsets, dict):
        unknown = [x for x in offsets if x not in chosen.values()]
        if unknown:
            raise ValueError(f"contact_offset names link {unknown[0]!r}, which is not a foot")
    found = []
    for key, foot in chosen.items():
        joints = paths[key]
        offset = offsets.get(foot, np.zeros(3)) if isinstance(offsets, dict) else offsets
        geometry, reason = _leg_geometry(model, joints, foot, offset, tolerance)
        if geometry is None:
            if feet is not None:
                raise ValueError(f"foot link {foot!r}: {reason}")
            report.append(f"{foot}: {reason}")
            continue
        found.append((joints[0].index, key, foot, offset, geometry))
    found.sort(key=lambda item: item[0])
    names = [_common_name(key) or foot for _, key, foot, _, _ in found]
    if len(set(names)) != len(names):
        report.append("leg names from the joint names are not unique; legs are named after their feet")
        names = [foot for _, _, foot, _, _ in found]
    legs = tuple(
        LegSpec(name=name, joint_names=key, foot=foot, contact_offset=offset, **geometry)
        for name, (_, key, foot, offset, geometry) in zip(names, found)
    )
    return legs, tuple(report)


def _wrist_center(lines, tolerance: float) -> tuple[np.ndarray | None, str]:
    """The common point of three lines (point, direction), or (None, reason)."""
    best, pair = -1.0, (0, 1)
    for i in range(3):
        for k in range(i + 1, 3):
            s = float(np.linalg.norm(np.cross(lines[i][1], lines[k][1])))
            if s > best:
                best, pair = s, (i, k)
    if best <= 1e-9:
        return None, "the last three axes are parallel"
    (p1, d1), (p2, d2) = lines[pair[0]], lines[pair[1]]
    # Closest points p1 + t1 d1 and p2 + t2 d2 of two skew lines.
    w = p1 - p2
    b = float(d1 @ d2)
    d, e = float(d1 @ w), float(d2 @ w)
    den = 1.0 - b * b
    t1 = (b * e - d) / den
    t2 = (e - b * d) / den
    center = 0.5 * (p1 + t1 * d1 + p2 + t2 * d2)
    for p, u in lines:
        r = center - p
        if float(np.linalg.norm(r - (r @ u) * u)) > tolerance:
            return None, "the last three axes do not meet at one point"
    return center, ""


def find_arms(
    model: Model, legs: Iterable[LegSpec], tolerance: float = 1e-9
) -> tuple[tuple[ArmSpec, ...], tuple[str, ...]]:
    """Find 6-joint arms on the branches that share no joint with ``legs``.

    For every leaf whose path from the root holds at least six actuated joints, the first
    six form an arm (arms sharing the same six joints are merged). The tip is a leaf reached
    from the sixth joint's child through fixed joints only and named with "hand", "ee",
    "tool", "gripper", "flange" or "tip", else that child link. The wrist is spherical when
    the last three axes (root frame, zero angles) meet at one point within ``tolerance``
    metres. Returns ``(arms, report)``.
    """
    leg_joints = {name for leg in legs for name in leg.joint_names}
    report: list[str] = []
    found: dict[tuple[str, ...], dict] = {}
    listed = 3  # the joints past the sixth named in the report (then how many more)
    above = _moving_above(model, 6 + listed, leg_joints)  # one walk down the tree: linear in its size
    for leaf in model.leaves:
        count, joints, on_leg = above[leaf]
        if on_leg or not count:
            continue
        mimic = [j for j in joints[:6] if j.mimic is not None]
        if mimic:
            report.append(f"{leaf}: not an arm: joint {mimic[0].name!r} mimics {mimic[0].mimic!r}")
            continue
        if count < 6:
            report.append(f"{leaf}: {_plural(count, 'actuated joint')}, not an arm")
            continue
        key = tuple(j.name for j in joints[:6])
        if count > 6:
            extra = ", ".join(j.name for j in joints[6:])
            if count > 6 + listed:
                extra += f" and {count - 6 - listed} more"
            report.append(
                f"{leaf}: {count} actuated joints, the first 6 ({', '.join(key)}) are taken "
                f"as an arm; {extra} not part of it"
            )
        if key not in found:
            found[key] = {"joints": joints[:6], "leaves": []}
        found[key]["leaves"].append(leaf)
    arms = []
    names = []
    for key, item in found.items():
        joints = item["joints"]
        child = joints[5].child
        # Links reached from the sixth joint's child through fixed joints only.
        reach, stack = [], [(child, 0)]
        while stack:
            link, depth = stack.pop()
            reach.append((link, depth))
            stack.extend((j.child, depth + 1) for j in model.children(link) if j.type == "fixed")
        named = [(d, x) for x, d in reach if not model.children(x) and _TIP_WORDS.search(x)]
        tip = max(named, key=lambda t: t[0])[1] if named else child
        spherical, center = False, None
        wrist = joints[3:]
        if any(j.type == "prismatic" for j in wrist):
            reason = "a wrist joint is prismatic"
        else:
            center, reason = _wrist_center([_axis_root(model, j) for j in wrist], tolerance)
            spherical = center is not None
        name = _common_name(key) or tip
        if not spherical:
            report.append(
                f"arm {name!r}: wrist not spherical ({reason}); its chain's ik_kind names the closed-form "
                "6R family it has, if any (three parallel axes, spherical shoulder)"
            )
        names.append(name)
        arms.append(
            dict(
                joint_names=key,
                tip=tip,
                base=joints[0].parent,
                wrist_center=center,
                spherical_wrist=spherical,
            )
        )
    if len(set(names)) != len(names):
        names = [a["tip"] for a in arms]
    return tuple(ArmSpec(name=n, **a) for n, a in zip(names, arms)), tuple(report)


def describe(
    model: Model,
    legs: Iterable[LegSpec] = (),
    arms: Iterable[ArmSpec] = (),
    report: Iterable[str] = (),
) -> str:
    """A human-readable summary: the tree, the legs and arms found, and the report lines."""
    legs, arms, report = tuple(legs), tuple(arms), tuple(report)
    n_act = len(model.actuated_joints)
    lines = [
        f"robot {model.name!r}: {_plural(len(model.links), 'link')}, {_plural(len(model.joints), 'joint')} "
        f"({n_act} actuated), root {model.root!r}",
    ]
    if model.root_joint is not None:
        rj = model.root_joint
        what = "a floating base" if rj.type == "floating" else "mounted (fixed)"
        lines.append(
            f"root joint: {rj.type} {rj.name} from {rj.parent!r} to {rj.child!r}, read as {what}: "
            f"frames are in the frame of {rj.child!r}"
        )
    for j in model.mimic_joints:
        lines.append(f"mimic: {j.name} follows {j.mimic} × {j.multiplier:.6g} + {j.offset:.6g}")
    lines.append("tree:")
    stack: list[tuple[str, Joint | None, int]] = [(model.root, None, 1)]
    while stack:
        link, joint, depth = stack.pop()
        if joint is None:
            lines.append("  " * depth + link)
        else:
            mimic = "" if joint.mimic is None else f" (mimic of {joint.mimic})"
            lines.append("  " * depth + f"{link}  <- {joint.type} {joint.name}{mimic}")
        stack.extend((j.child, j, depth + 1) for j in reversed(model.children(link)))
    lines.append(f"legs ({len(legs)}):")
    for leg in legs:
        limits = ", ".join(f"[{lo:.6g}, {hi:.6g}]" for lo, hi in leg.limits)
        lines += [
            f"  {leg.name}: joints {', '.join(leg.joint_names)}; foot {leg.foot}",
            f"    hip origin {_fmt(leg.hip_origin)}",
            f"    a = {_fmt(leg.a)}, b = {_fmt(leg.b)}, c = {_fmt(leg.c)}",
            "    signs (" + ", ".join(f"{s:+.0f}" for s in leg.signs) + f"), limits {limits}",
        ]
        if np.any(leg.contact_offset != 0):
            lines.append(f"    contact offset {_fmt(leg.contact_offset)}")
    lines.append(f"arms ({len(arms)}):")
    for arm in arms:
        wrist = f"yes, centre {_fmt(arm.wrist_center)}" if arm.spherical_wrist else "no"
        lines += [
            f"  {arm.name}: joints {', '.join(arm.joint_names)}",
            f"    base {arm.base}, tip {arm.tip}, spherical wrist: {wrist}",
        ]
    wide = [j for j in model.actuated_joints if j.type == "revolute" and j.upper - j.lower > 2 * math.pi]
    for j in wide:
        lines.append(
            f"warning: joint {j.name!r} has the range [{j.lower:.6g}, {j.upper:.6g}] rad, wider than 2π: "
            "the IK may choose configurations the robot cannot take (on a leg, a knee above its hip); "
            "narrow it "
            "with from_urdf(..., limits={name: (lower, upper)}) or with_limits"
        )
    if report:
        lines.append("not recognised / notes:")
        lines += [f"  {line}" for line in report]
    return "\n".join(lines) + "\n"
