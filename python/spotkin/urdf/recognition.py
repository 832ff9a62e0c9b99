"""Legs and arms recognised in a description (:func:`find_legs`, :func:`find_arms`) and its summary
(:func:`describe`). Part of :mod:`spotkin.urdf` (documented there)."""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from .tree import _FOOT_WORDS, _TIP_WORDS, Joint, Model, _common_name, _fmt, _plural, _readonly

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
