"""The parsed description (:class:`Model`: links, joints, inertials) and its kinematic tree: paths,
placements, chains. Part of :mod:`spotkin.urdf` (documented there)."""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from .._support.boundary import as_real

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
    """A link: its name, optional mass properties and its collision spheres.

    ``spheres`` holds the link's ``<collision>`` elements whose geometry is a ``<sphere>``, as
    ``((x, y, z), radius)`` pairs in the link frame (a foot's contact sphere, for the simulator);
    every other collision geometry is read past.
    """

    name: str
    inertial: Inertial | None = None
    spheres: tuple[tuple[tuple[float, float, float], float], ...] = ()


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
