"""Chains from URDF models: the one route :meth:`spotkin.Robot.chain` and :meth:`spotkin.Chain.from_urdf`
share (placements, axes, limits and joint names from :meth:`spotkin.urdf.Model.chain_data`, bodies from
:func:`spotkin.inertia.model_tree`, mimic joints through :class:`spotkin.model.mimic.MimicChain`), the default
tip of :meth:`spotkin.Chain.from_urdf`, and the chains ``spotkin inspect`` lists."""

from __future__ import annotations

import os

import numpy as np

from .. import urdf
from ..dynamics import inertia
from . import chain as chain_module
from .chain import Chain
from .mimic import MimicChain, mapped_limits

__all__ = [
    "chain_from_model",
    "chain_from_urdf",
    "chains_summary",
    "default_tip",
    "link_name",
    "tip_candidates",
]


def link_name(value, name: str, model: urdf.Model) -> str:
    """``value`` as a link name of ``model``: ``TypeError`` for a non-str, ``ValueError`` for an unknown
    link."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a link name (str), got {type(value).__name__}")
    if value not in model.links:
        known = ", ".join(repr(x) for x in list(model.links)[:12])
        more = ", ..." if len(model.links) > 12 else ""
        raise ValueError(f"{name}: {value!r} is not a link of {model.name!r} (links: {known}{more})")
    return value


def chain_from_model(model: urdf.Model, link: str, base: str | None = None) -> Chain:
    """The chain from link ``base`` (default: the root) to link ``link`` of ``model``: fixed joints merged
    into the placements, the URDF's joint names and limits, and its bodies when the file gives any
    ``<inertial>``. A path holding mimic joints gives a :class:`spotkin.model.mimic.MimicChain`, whose
    variables are its independent joints and the mimic joints' leaders."""
    data = model.chain_data(link, base)
    if data.n == 0:
        raise ValueError(f"no actuated joint between {data.base!r} and {link!r}")
    has_inertials = any(item.inertial is not None for item in model.links.values())
    if all(m is None for m in data.mimic):
        chain = Chain.from_joints(
            data.placements,
            data.axes,
            data.types,
            tool=data.tool,
            limits=data.limits,
            joint_names=data.joint_names,
        )
        if not has_inertials:
            return chain
        tree = inertia.model_tree(model, data.base, data.joint_names, floating=False)
        return chain.with_inertials(*tree.inertials)
    return _mimic_chain(model, data, has_inertials)


def _mimic_chain(model: urdf.Model, data: urdf.ChainData, has_inertials: bool) -> Chain:
    variables: list[str] = []
    columns: list[tuple[int, float]] = []  # per joint of the path: (variable, multiplier); -1 for none
    offsets = np.zeros(data.n)
    for i, (name, mimic) in enumerate(zip(data.joint_names, data.mimic)):
        leader, multiplier = (name, 1.0) if mimic is None else (mimic[0], mimic[1])
        if mimic is not None:
            offsets[i] = mimic[2]
        if multiplier == 0.0:  # held at its offset: it drives nothing
            columns.append((-1, 0.0))
            continue
        if leader not in variables:
            variables.append(leader)
        columns.append((variables.index(leader), multiplier))
    n = len(variables)
    if n == 0:
        raise ValueError(f"no independent joint moves the chain from {data.base!r} to {data.tip!r}")
    M = np.zeros((data.n, n))
    for i, (k, multiplier) in enumerate(columns):
        if k >= 0:
            M[i, k] = multiplier
    leaders = [model.joint(name) for name in variables]
    limits = np.array([(j.lower, j.upper) for j in leaders], dtype=float).reshape(n, 2)
    sigma = np.array([1 if j.type == "prismatic" else 0 for j in leaders], dtype=np.int8)
    # The full chain's limits: a mimic joint's are its leader's, mapped: the full chain's closed form
    # then keeps the leader within its limits.
    full_limits = mapped_limits(M, offsets, limits)
    full = Chain.from_joints(
        data.placements,
        data.axes,
        data.types,
        tool=data.tool,
        limits=full_limits,
        joint_names=data.joint_names,
    )
    if has_inertials:
        tree = inertia.model_tree(model, data.base, data.joint_names, floating=False)
        full = full.with_inertials(*tree.inertials)
    return MimicChain._make(full, M, offsets, variables, limits, sigma)


class _Tour:
    """A depth-first walk of the tree below ``base``: each link's depth, entry and exit times and parent
    link, for ancestor tests and deepest common links in linear time."""

    def __init__(self, model: urdf.Model, base: str) -> None:
        self.depth, self.tin, self.tout, self.parent = {base: 0}, {}, {}, {base: None}
        clock = 0
        stack = [(base, False)]
        while stack:
            link, done = stack.pop()
            if done:
                self.tout[link] = clock
                continue
            self.tin[link] = clock
            clock += 1
            stack.append((link, True))
            for j in reversed(model.children(link)):
                self.depth[j.child] = self.depth[link] + 1
                self.parent[j.child] = link
                stack.append((j.child, False))

    def above(self, a: str, b: str) -> bool:
        """Whether link ``a`` is ``b`` or above it."""
        return self.tin[a] <= self.tin[b] < self.tout[a]

    def common(self, links) -> str:
        """The deepest link above (or equal to) every one of ``links``."""
        links = list(links)
        a = min(links, key=self.tin.__getitem__)
        b = max(links, key=self.tin.__getitem__)
        while not self.above(a, b):
            a = self.parent[a]
        return a


def _gripper_joints(model: urdf.Model, tour: _Tour) -> set[str]:
    """The joints of a gripper's mechanism: each mimic joint whose leader is on another branch (not above
    it: the fingers of a gripper), and that leader. A mimic joint below its leader is part of the chain."""
    out = set()
    for j in model.mimic_joints:
        leader = model.joint(j.mimic)
        if j.child not in tour.tin or leader.child not in tour.tin or not tour.above(leader.child, j.child):
            out.update((j.name, j.mimic))
    return out


def _ends(model: urdf.Model, base: str, tour: _Tour, cut: bool) -> dict[str, list[str]]:
    """The leaves below ``base`` grouped by the last actuated joint above them (leaves with none left out):
    last joint name -> the leaves, or with ``cut`` the link a gripper hangs from for a leaf below one."""
    gripper = _gripper_joints(model, tour) if cut else set()
    found: dict[str, list[str]] = {}
    stack: list[tuple[str, str | None, str | None]] = [(base, None, None)]
    while stack:
        link, last, hand = stack.pop()
        children = model.children(link)
        if not children and last is not None:
            found.setdefault(last, []).append(hand or link)
        for j in reversed(children):
            if hand is not None:
                stack.append((j.child, last, hand))
            elif j.name in gripper:
                stack.append((j.child, last, j.parent))
            else:
                stack.append((j.child, j.name if j.type != "fixed" else last, None))
    return found


def tip_candidates(model: urdf.Model, base: str | None = None) -> tuple[str, ...]:
    """The links a chain from ``base`` can end at by default, one per distinct chain: each leaf below
    ``base`` with a moving joint between them, cut before the first joint of a gripper on its path (a
    mimic joint whose leader is on another branch, or that leader: the fingers; the tip is then the link
    they hang from, the hand). Candidates moved by the same joints (a flange and a tool frame on one
    wrist) merge into their deepest common link. Linear in the size of the tree."""
    base = model.root if base is None else base
    tour = _Tour(model, base)
    return tuple(tour.common(set(tips)) for tips in _ends(model, base, tour, cut=True).values())


def default_tip(model: urdf.Model, base: str | None = None) -> str:
    """The only tip candidate (:func:`tip_candidates`) below ``base``, or ``ValueError`` listing them."""
    tips = tip_candidates(model, base)
    where = f"below link {base!r}" if base is not None else f"in {model.name!r}"
    if len(tips) == 1:
        return tips[0]
    if not tips:
        raise ValueError(f"no link {where} is moved by an actuated joint: there is no chain to build")
    top = model.root if base is None else base
    hint = _Tour(model, top).common(tips)
    common = f"; their branches meet at {hint!r}" if hint != top else ""
    listed = ", ".join(repr(t) for t in tips[:12]) + (f" and {len(tips) - 12} more" if len(tips) > 12 else "")
    raise ValueError(
        f"tip: {len(tips)} chains end {where}, at {listed}{common}; pass tip= (one of them, or any link) to "
        "choose"
    )


def chains_summary(model: urdf.Model, most: int = 24) -> str:
    """Text lines for ``spotkin inspect``: the chain from the root to each tip candidate and to each other
    leaf moved by other joints (at most ``most`` chains), with its joints, dof, closed-form IK family (or
    what applies instead) and mimic joints."""
    tour = _Tour(model, model.root)
    tips = {last: tour.common(set(t)) for last, t in _ends(model, model.root, tour, cut=True).items()}
    ends = [(tip, " (the default tip)" if len(tips) == 1 else " (a tip)") for tip in tips.values()]
    fixed_to: dict[str, list[str]] = {}
    for last, leaves in _ends(model, model.root, tour, cut=False).items():
        if last in tips:  # moved by the same joints as a tip: fixed to it
            fixed_to[tips[last]] = [x for x in leaves if x != tips[last]]
        else:
            ends.extend((leaf, "") for leaf in leaves)
    lines = [f"chains from {model.root!r} ({len(ends)}):"]
    for end, note in ends[:most]:
        try:
            chain = chain_from_model(model, end)
        except ValueError as error:
            lines.append(f"  to {end}{note}: {error}")
            continue
        lines.append(f"  to {end}{note}: {chain.dof} dof, joints {', '.join(chain.joint_names or ())}")
        if fixed_to.get(end):
            lines.append(f"    also ends at {', '.join(fixed_to[end])} (fixed to it: tip=...)")
        full = getattr(chain, "full_chain", None)
        if full is not None:
            lines.append(
                f"    mimic: {chain._coupling()} ({full.dof} joints move with {chain.dof} variables)"
            )
        lines.append(f"    ik: {ik_summary(chain)}")
    if len(ends) > most:
        lines.append(f"  ... and {len(ends) - most} more (Chain.from_urdf(path, tip=...) builds any of them)")
    return "\n".join(lines) + "\n"


def ik_summary(chain: Chain) -> str:
    """What :meth:`spotkin.Chain.ik` does for ``chain``, in a line."""
    try:
        return f"closed form, ik_kind {chain.ik_kind!r}"
    except ValueError as error:
        if chain.dof == 7:
            kinds = []
            for k in range(7):
                try:
                    kinds.append(f"free_joint={k}: {chain.ik_free_kind(k)}")
                except ValueError:
                    continue
            if kinds:
                return (
                    "7 joints: ik(T, free_joint=k, free_value=v) in closed form with joint k held ("
                    + ", ".join(kinds)
                    + "); ik_differential for the whole chain"
                )
        reason = str(error).split(";")[0]
        if "ik_differential" in reason:
            return reason
        return f"no closed form ({reason}); ik_differential solves it numerically"


def chain_from_urdf(source, tip: str | None = None, base: str | None = None) -> Chain:
    """:meth:`spotkin.Chain.from_urdf` (documented there): the chain from link ``base`` to link ``tip``
    of a URDF file or text."""
    if isinstance(source, (bytes, bytearray, memoryview)) or (
        isinstance(source, str) and source.lstrip().startswith("<")
    ):
        data = urdf.read_text(source.lstrip() if isinstance(source, str) else source)
    elif isinstance(source, (str, os.PathLike)):
        data = urdf.read_file(source)
    else:
        raise TypeError(
            "source must be a URDF path (str or os.PathLike) or its XML (str or bytes), "
            f"got {type(source).__name__}"
        )
    model = urdf.parse_urdf(data)
    if base is not None:
        base = link_name(base, "base", model)
    if tip is None:
        tip = default_tip(model, base)
    else:
        tip = link_name(tip, "tip", model)
    return chain_from_model(model, tip, base)


chain_module._from_urdf = (
    chain_from_urdf  # Chain.from_urdf's loader (spotkin.model.chain cannot import this module)
)
