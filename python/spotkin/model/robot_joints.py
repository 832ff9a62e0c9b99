"""A robot's joints by name: :class:`spotkin.Robot` takes these methods from the base class here."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real, check_trailing


def _names(value, name: str) -> tuple[str, ...]:
    """A sequence of joint names (list, tuple, 1-D string array...) as a tuple of str."""
    try:  # lists and tuples are checked item by item below
        flat = isinstance(value, (list, tuple)) or (
            not isinstance(value, (str, bytes, Mapping)) and np.ndim(value) == 1
        )
    except ValueError:  # a ragged nesting
        flat = False
    if not flat:
        raise TypeError(f"{name} must be a sequence of joint names, got {_described(value)}")
    items = tuple(value)
    strange = [item for item in items if not isinstance(item, str)]
    if strange:
        raise TypeError(f"{name} must hold joint names (str), got {_described(strange[0])}")
    return tuple(str(item) for item in items)


def _described(value) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 60 else text[:57] + '...'}"


def _listing(names) -> str:
    shown = ", ".join(repr(name) for name in names[:8])
    return shown + (f" and {len(names) - 8} more" if len(names) > 8 else "")


def _is_are(names) -> str:
    return "is" if len(names) == 1 else "are"


def _no_repeats(joints, given, name: str) -> None:
    """ValueError when one joint appears twice in ``joints`` (``given``: the names as written)."""
    first: dict[str, str] = {}
    for joint, written in zip(joints, given):
        if joint in first:
            also = "" if first[joint] == written else f" (as {first[joint]!r} and {written!r})"
            raise ValueError(f"{name} gives the joint {joint!r} twice{also}")
        first[joint] = written


def _choice(value, name: str, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")
    return value


class _JointNameMethods:
    """The joint-name methods of :class:`spotkin.Robot` (its base class; see there)."""

    __slots__ = ()

    @property
    def arm_joint_names(self) -> tuple[str, ...]:
        """The joints of :attr:`arm` from the body out, the order of ``q_arm`` (``()`` without an arm)."""
        names = None if self._arm is None else getattr(self._arm, "joint_names", None)
        return tuple(names) if names else ()

    def _joint_aliases(self) -> dict[str, str]:
        """Every name a joint of this robot answers to -> the joint's name in q: every joint of the URDF."""
        table = getattr(self, "_aliases", None)
        if table is None:
            table = {joint.name: joint.name for joint in self._model.joints}
            table.update((name, name) for name in (*self.leg_joint_names, *self.arm_joint_names))
            self._aliases = table
        return table

    def _joint_slots(self, joints) -> tuple[str, ...]:
        """The joints of a q, in order: ``joints`` (any of their names) or the whole-body q."""
        if joints is None:
            return self.leg_joint_names
        aliases = self._joint_aliases()
        listed = _names(joints, "joints")
        unknown = [name for name in listed if name not in aliases]
        if unknown:
            raise ValueError(f"joints: {_listing(unknown)} {_is_are(unknown)} not a joint of this robot")
        slots = tuple(aliases[name] for name in listed)
        _no_repeats(slots, listed, "joints")
        return slots

    def q_from_names(
        self,
        names,
        positions: ArrayLike,
        *,
        joints=None,
        missing: str = "raise",
        unknown: str = "raise",
    ) -> np.ndarray:
        """q (..., n) from joint positions given by name in any order: a ROS ``sensor_msgs/JointState``
        (``msg.name``, ``msg.position``) or any middleware's (names, positions) pairs.

        ``names`` is a sequence of k joint names and ``positions`` (..., k) their values, leading
        dimensions kept. q follows ``joints``: by default :attr:`leg_joint_names` (the whole-body q);
        :attr:`arm_joint_names` gives ``q_arm``; any sequence of this robot's joint names gives that
        order. A name may be any joint of the URDF (:class:`spotkin.Spot` also answers to the Boston
        Dynamics SDK's names, such as ``"fl.hx"`` and ``"arm0.f1x"``); a joint of this robot that
        ``joints`` does not hold (a gripper, another limb, a fixed joint) is skipped.

        ``missing``: a joint of ``joints`` absent from ``names`` raises ``ValueError`` naming it
        (``"raise"``), or is NaN in q (``"nan"``). ``unknown``: a name that is no joint of this robot
        raises ``ValueError`` naming it (``"raise"``) or is skipped (``"ignore"``). A joint named
        twice raises ``ValueError``. NaN positions stay NaN in their own joint and sample. q is
        float32 for float32 positions, float64 otherwise; ``TypeError`` for non-string names or
        non-numeric positions, ``ValueError`` when positions is not (..., k).
        """
        nan_for_missing = _choice(missing, "missing", ("raise", "nan")) == "nan"
        skip_unknown = _choice(unknown, "unknown", ("raise", "ignore")) == "ignore"
        slots = self._joint_slots(joints)
        given = _names(names, "names")
        positions = as_real(positions, "positions")
        lead = check_trailing(positions, "positions", (len(given),))
        aliases = self._joint_aliases()
        column = {name: k for k, name in enumerate(slots)}
        canonical = [aliases.get(name) for name in given]
        strangers = [name for name, joint in zip(given, canonical) if joint is None]
        if strangers and not skip_unknown:
            raise ValueError(
                f"names: {_listing(strangers)} {_is_are(strangers)} not a joint of this robot "
                f"(unknown='ignore' skips such names)"
            )
        known = [(i, joint) for i, joint in enumerate(canonical) if joint is not None]
        _no_repeats([joint for _, joint in known], [given[i] for i, _ in known], "names")
        pairs = [(i, column[joint]) for i, joint in known if joint in column]
        if len(pairs) < len(slots) and not nan_for_missing:
            present = {joint for _, joint in known}
            absent = [name for name in slots if name not in present]
            raise ValueError(f"names lacks the joints {_listing(absent)} (missing='nan' gives NaN for them)")
        q = np.full((*lead, len(slots)), np.nan, dtype=positions.dtype)
        if pairs:
            source, target = (list(side) for side in zip(*pairs))
            q[..., target] = positions[..., source]
        return q

    def names_from_q(self, q: ArrayLike, names=None, *, joints=None) -> tuple[tuple[str, ...], np.ndarray]:
        """``(names, positions)``: q (..., n) as joint positions by name, for a ROS
        ``sensor_msgs/JointState`` or any middleware; the inverse of :meth:`q_from_names`.

        ``q`` follows ``joints`` (default :attr:`leg_joint_names`, see :meth:`q_from_names`).
        ``names`` picks and orders the joints (any of their names, kept as given; a subset is
        fine); by default every joint of q under its name in ``joints``. ``positions`` (..., k) is a
        new array, float32 for float32 q, float64 otherwise. A name that is no joint of q, or a joint
        named twice, raises ``ValueError``.
        """
        slots = self._joint_slots(joints)
        q = as_real(q, "q")
        check_trailing(q, "q", (len(slots),))
        if names is None:  # the joints as ``joints`` writes them
            return (slots if joints is None else _names(joints, "joints")), q.copy()
        wanted = _names(names, "names")
        aliases = self._joint_aliases()
        column = {name: k for k, name in enumerate(slots)}
        strangers = [name for name in wanted if aliases.get(name) not in column]
        if strangers:
            raise ValueError(f"names: {_listing(strangers)} {_is_are(strangers)} not a joint of q ({slots})")
        _no_repeats([aliases[name] for name in wanted], wanted, "names")
        return wanted, q[..., [column[aliases[name]] for name in wanted]]
