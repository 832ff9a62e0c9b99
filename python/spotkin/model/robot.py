"""Legged robots from their descriptions: a body with any number of roll–pitch–pitch legs,
and the arms it carries. Whole-body IK, FK, Jacobians and joint rates for every robot,
built by :meth:`Robot.from_urdf`; :class:`spotkin.Spot` is one instance of it.

Frames: the body frame is the URDF's root link frame. Each leg's frame has its origin at
the leg's hip-roll joint and the body's axes (see :class:`spotkin.Leg`).
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Mapping
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core, urdf
from .._support.boundary import (
    as_finite,
    as_real,
    as_scalar,
    broadcast_lead,
    check_trailing,
    fallback_is_nearest,
    into_out,
    quiet_float_errors,
    real_dtype,
)
from .._support.status import Status
from .._support.transforms import quaternion_xyzw
from ..dynamics import inertia
from ..dynamics.rigid_body import FloatingBase
from .body import body_transform, sequence_code
from .chain import Chain
from .leg import Leg
from .urdf_chain import chain_from_model

__all__ = ["BodyFrames", "BodyIK", "BodyRates", "Robot"]

_DEFAULT_SEQ, _DEFAULT_FALLBACK = "XYZ", "nearest"  # body_ik's defaults: their fast test is by identity
_XYZ = sequence_code(_DEFAULT_SEQ)


class BodyIK(NamedTuple):
    """Whole-body IK results, from :meth:`Robot.body_ik`."""

    q: np.ndarray
    """(..., 3 n) leg joint angles, in the order of :attr:`Robot.leg_joint_names`."""
    status: np.ndarray
    """(..., n) int8 :class:`Status` per leg, with the leg API's meaning and fallback."""


_core._register_result_type("BodyIK", BodyIK)  # the core returns it itself


class BodyRates(NamedTuple):
    """Joint velocities that keep the feet fixed, from :meth:`Robot.body_rates`."""

    qd: np.ndarray
    """(..., 3 n) joint velocities; NaN for a singular leg."""
    singular: np.ndarray
    """(..., n) bool: the leg's Jacobian is singular (smallest singular value below ``tolerance``)."""


class BodyFrames(NamedTuple):
    """Frames of interest in the world frame, from :meth:`Robot.fk_all`."""

    body: np.ndarray
    """(..., 4, 4) world <- body."""
    hips: np.ndarray
    """(..., n, 3) hip-roll joint origins."""
    knees: np.ndarray
    """(..., n, 3) knee joint origins."""
    feet: np.ndarray
    """(..., n, 3) foot points."""
    hand: np.ndarray | None
    """(..., 4, 4) the arm's tool frame, or None without ``q_arm``."""


def _broadcast_to_lead(array: np.ndarray, trailing: int, lead: tuple[int, ...]) -> np.ndarray:
    if array.shape[: array.ndim - trailing] == lead:
        return array
    return np.broadcast_to(array, (*lead, *array.shape[array.ndim - trailing :]))


def _solve_rows(J: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with J x = rhs for each J (n, 3, 3), rhs (n, 3); NaN rows where LAPACK finds J
    exactly singular (the rest of the batch is unaffected)."""
    try:
        return np.linalg.solve(J, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:  # one exactly singular J: solve one by one
        x = np.full(rhs.shape, np.nan)
        for k in range(len(J)):
            with contextlib.suppress(np.linalg.LinAlgError):
                x[k] = np.linalg.solve(J[k], rhs[k])
        return x


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


def _side_groups(hips: np.ndarray, tolerance: float) -> dict[str, list[int]]:
    """The legs on each side (left: y > tolerance, right: y < -tolerance, else center), front to hind."""
    groups: dict[str, list[int]] = {"left": [], "right": [], "center": []}
    for k, y in enumerate(hips[:, 1]):
        groups["left" if y > tolerance else "right" if y < -tolerance else "center"].append(k)
    for members in groups.values():
        members.sort(key=lambda k: (-hips[k, 0], k))  # front first; a tie keeps the URDF's order
    return groups


def leg_roles(hips: ArrayLike, tolerance: float = 1e-6) -> tuple[str, ...]:
    """The role of each leg from its hip position (n, 3) in the body frame (x forward, y left): see
    :attr:`Robot.leg_roles`."""
    hips = np.asarray(hips, dtype=np.float64).reshape(-1, 3)
    roles = [""] * len(hips)
    for side, members in _side_groups(hips, tolerance).items():
        m = len(members)
        for p, k in enumerate(members):
            if m == 1:
                place = None
            elif p == 0:
                place = "front"
            elif p == m - 1:
                place = "hind"
            else:
                place = "middle" if m == 3 else f"middle_{p}"
            roles[k] = side if place is None else f"{place}_{side}"
    return tuple(roles)


def _role_order(hips: np.ndarray, tolerance: float = 1e-6) -> list[int]:
    """Leg indices front to hind, left before right (then center): the ``leg_order="roles"`` order."""
    ranks = {}
    for side_rank, members in enumerate(_side_groups(hips, tolerance).values()):
        for p, k in enumerate(members):
            ranks[k] = (p / max(len(members) - 1, 1), side_rank)
    return sorted(range(len(hips)), key=ranks.__getitem__)


def _limit_table(limits, model) -> dict[str, tuple[float, float]]:
    """``limits`` as a dict URDF joint name -> (lower, upper), checked: every name an actuated joint of
    ``model``, every pair real with lower <= upper and no NaN (ValueError / TypeError naming it)."""
    if limits is None:
        return {}
    if not isinstance(limits, Mapping):
        raise TypeError(f"limits must be a dict joint name -> (lower, upper), got {type(limits).__name__}")
    actuated = {joint.name for joint in model.actuated_joints}
    table = {}
    for name, pair in limits.items():
        if not isinstance(name, str):
            raise TypeError(f"limits: keys must be joint names (str), got {_described(name)}")
        if name not in actuated:
            raise ValueError(f"limits: {name!r} is not a moving joint of this robot")
        row = as_real(pair, f"limits[{name!r}]", np.float64)
        if row.shape != (2,):
            raise ValueError(f"limits[{name!r}] must be a (lower, upper) pair, got shape {row.shape}")
        if np.isnan(row).any() or row[0] > row[1]:
            raise ValueError(f"limits[{name!r}] must satisfy lower <= upper, with no NaN, got {row.tolist()}")
        table[name] = (float(row[0]), float(row[1]))
    return table


class Robot:
    """A legged robot: a body, its roll–pitch–pitch legs and the arms it carries.

    Build one with :meth:`from_urdf` (or :meth:`from_urdf_string`). The legs are found in
    the kinematic tree (:func:`spotkin.urdf.find_legs`): a path of three revolute joints from
    the body to a leaf link whose axes at zero angles are ±x, ±y, ±y in the body frame. Arms
    are 6-joint paths from the body that share no joint with a leg. :attr:`report` says what
    was recognised and why other branches were not; every link is still reachable as a chain
    (:meth:`chain`) with FK, Jacobians and differential IK.

    Whole-body calls take ``q`` (..., 3 n) holding the legs' joints in the order of
    :attr:`leg_joint_names` (the URDF's joint order), and give one status per leg.
    """

    __slots__ = (
        "_aliases",
        "_arm",
        "_arm_mount",
        "_arms",
        "_body_core",
        "_columns",
        "_floating",
        "_hips",
        "_leg_joint_names",
        "_leg_names",
        "_legs",
        "_model",
        "_report",
        "_roles",
        "_source",
        "_specs",
        "_statics_core",
    )

    def __init__(self) -> None:
        raise TypeError("build a Robot with Robot.from_urdf(path) or Robot.from_urdf_string(text)")

    # -- construction --------------------------------------------------------------------------------
    @classmethod
    def from_urdf(
        cls,
        path: str | os.PathLike,
        *,
        feet=None,
        contact_offset=None,
        nominal=None,
        limits=None,
        leg_order: str = "urdf",
    ) -> Robot:
        """Load a robot from a URDF file.

        ``feet``: link names to use as the feet (default: found, see :func:`spotkin.urdf.find_legs`);
        ``contact_offset``: a (3,) contact point offset in the foot link's frame, for every foot or
        as a dict foot link -> (3,), when the leaf link's origin is not the contact point;
        ``nominal``: a dict leg name -> (3,) joint angles of a typical stance, which sets each
        leg's preferred branch (default: from the knee's limits); ``limits``: a dict joint name -> (lower,
        upper) replacing the URDF's limits of those joints (see :meth:`with_limits`); ``leg_order``:
        ``"urdf"`` (the legs, and the whole-body ``q``, in the URDF's order) or ``"roles"`` (front to
        hind, left before right: :attr:`leg_roles` order, the same on every robot). ``ValueError`` names
        the joint or link for malformed descriptions (see :func:`spotkin.urdf.parse_urdf`); an unreadable
        path raises ``OSError`` (``FileNotFoundError``, ...); a path that is not a ``str`` or
        ``os.PathLike`` raises ``TypeError``.
        """
        if not isinstance(path, (str, os.PathLike)):
            raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
        data = urdf.read_file(path)  # bytes (the XML's own encoding declaration decides); xacro expanded
        model = urdf.parse_urdf(data)
        return cls._from_model(model, feet, contact_offset, nominal, data, limits, leg_order)

    @classmethod
    def from_urdf_string(
        cls, text: str, *, feet=None, contact_offset=None, nominal=None, limits=None, leg_order: str = "urdf"
    ) -> Robot:
        """As :meth:`from_urdf`, from the URDF's XML text."""
        if not isinstance(text, str):
            raise TypeError(f"text must be a str holding URDF XML, got {type(text).__name__}")
        text = urdf.read_text(text)  # xacro expanded
        model = urdf.parse_urdf(text)
        return cls._from_model(model, feet, contact_offset, nominal, text, limits, leg_order)

    @classmethod
    def _from_model(cls, model, feet, contact_offset, nominal, text, limits=None, leg_order="urdf") -> Robot:
        leg_order = _choice(leg_order, "leg_order", ("urdf", "roles"))
        limits = _limit_table(limits, model)
        if limits:
            model = model.with_limits(limits)
        specs, leg_report = urdf.find_legs(model, feet=feet, contact_offset=contact_offset)
        if leg_order == "roles" and specs:
            order = _role_order(np.array([spec.hip_origin for spec in specs]))
            specs = tuple(specs[k] for k in order)
        arms, arm_report = urdf.find_arms(model, specs)
        if nominal is not None and not isinstance(nominal, dict):
            raise TypeError(
                f"nominal must be a dict leg name -> (3,) joint angles, got {type(nominal).__name__}"
            )
        nominal = {} if nominal is None else dict(nominal)
        unknown = set(nominal) - {spec.name for spec in specs}
        if unknown:
            raise ValueError(f"nominal names legs that were not recognised: {sorted(unknown)}")
        for name, value in nominal.items():
            if value is None:
                raise ValueError(f"nominal[{name!r}] must be (3,) joint angles, got None")
        legs = [
            Leg.from_geometry(
                spec.a, spec.b, spec.c, spec.signs, spec.limits, spec.name, nominal=nominal.get(spec.name)
            )
            for spec in specs
        ]
        robot = cls.__new__(cls)
        robot._model = model
        robot._source = (text, feet, contact_offset, nominal, limits, leg_order)
        robot._report = tuple(leg_report) + tuple(arm_report)
        robot._specs = (tuple(specs), tuple(arms))
        arm_chains = tuple(robot.chain(arm.tip, base=arm.base) for arm in arms)
        robot._arms = arm_chains
        # body <- arm base: the arm's chain starts at the link its first joint hangs from, which the
        # recognition reaches from the body through fixed joints only (find_arms takes the first six
        # actuated joints below the root), so the mount is that link's placement at zero angles
        robot._arm_mount = model.placement(arms[0].base) if arms else np.eye(4)
        robot._arm_mount.flags.writeable = False
        robot._set_legs(
            legs,
            [spec.hip_origin for spec in specs],
            [spec.name for spec in specs],
            [tuple(spec.joint_names) for spec in specs],
            arm_chains[0] if arm_chains else None,
        )
        return robot

    def _set_legs(self, legs, hips, names, joint_names, arm) -> None:
        if not legs:
            raise ValueError(
                "no roll-pitch-pitch legs were recognised (see spotkin.urdf.find_legs's report): a Robot is "
                "a legged robot; for an arm, a gripper or a head, load its chain with "
                "spotkin.Chain.from_urdf(path, tip=..., base=...)"
            )
        self._legs = tuple(legs)
        for leg, triple in zip(legs, joint_names):
            leg._joint_names = tuple(triple)
        self._leg_names = tuple(names)
        self._hips = np.array(hips, dtype=np.float64).reshape(len(legs), 3)
        self._hips.flags.writeable = False
        self._roles = leg_roles(self._hips)
        flat = [name for triple in joint_names for name in triple]
        source = getattr(self, "_source", None)
        by_roles = source is not None and len(source) > 5 and source[5] == "roles"
        order = {name: k for k, name in enumerate(flat)} if by_roles else self._urdf_order(flat)
        self._leg_joint_names = tuple(sorted(flat, key=order.__getitem__))
        position = {name: k for k, name in enumerate(self._leg_joint_names)}
        self._columns = np.array(
            [[position[name] for name in triple] for triple in joint_names], dtype=np.int64
        )
        contiguous = bool((self._columns == np.arange(3 * len(legs)).reshape(-1, 3)).all())
        self._body_core = _core.Body(
            [leg._core for leg in self._legs], self._hips, None if contiguous else self._columns.astype(float)
        )
        self._arm = arm

    def _urdf_order(self, names):
        model = getattr(self, "_model", None)
        if model is None:
            return {name: k for k, name in enumerate(names)}
        index = {joint.name: joint.index for joint in model.actuated_joints}
        return {name: index.get(name, k) for k, name in enumerate(names)}

    # -- description ---------------------------------------------------------------------------------
    @property
    def name(self) -> str | None:
        """The URDF's robot name."""
        return None if self._model is None else self._model.name

    @property
    def model(self) -> urdf.Model | None:
        """The parsed description (:class:`spotkin.urdf.Model`)."""
        return self._model

    @property
    def legs(self) -> tuple[Leg, ...]:
        """The recognised legs, in the URDF's order of their first joints."""
        return self._legs

    @property
    def leg_names(self) -> tuple[str, ...]:
        """The legs' names, in :attr:`legs` order."""
        return self._leg_names

    def leg(self, name: str) -> Leg:
        """One leg by name (:attr:`leg_names`) or by role (:attr:`leg_roles`, such as ``"front_left"``,
        the same on every quadruped)."""
        if not isinstance(name, str):
            raise TypeError(f"name must be a leg name or role (str), got {type(name).__name__}")
        if name in self._leg_names:
            return self._legs[self._leg_names.index(name)]
        if name in self._roles:
            return self._legs[self._roles.index(name)]
        raise ValueError(
            f"leg name must be one of {self._leg_names} or a leg role {self._roles}, got {name!r}"
        )

    @property
    def leg_roles(self) -> tuple[str, ...]:
        """Each leg's place on the body, in :attr:`legs` order, from the hips' positions in the body frame
        (x forward, y left, as URDFs are written): ``"front_left"``, ``"front_right"``, ``"hind_left"``,
        ``"hind_right"`` on a quadruped. A side with three legs or more has ``"middle"`` legs between its
        front and hind ones (``"middle_1"``, ``"middle_2"``, ... front to hind when there are several);
        a side with one leg calls it ``"left"`` or ``"right"``; hips within 1 µm of the sagittal plane are
        on side ``"center"``. :meth:`leg` takes these names, and ``Robot.from_urdf(..., leg_order="roles")``
        orders the legs and ``q`` by them."""
        return self._roles

    @property
    def n_legs(self) -> int:
        return len(self._legs)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Every actuated joint of the description, in the URDF's order."""
        return tuple(joint.name for joint in self._model.actuated_joints)

    @property
    def leg_joint_names(self) -> tuple[str, ...]:
        """The legs' joints in the order of the whole-body ``q``: :attr:`joint_names` restricted to
        the legs."""
        return self._leg_joint_names

    @property
    def hip_positions(self) -> np.ndarray:
        """(n, 3) hip-roll joint origins in the body frame."""
        return self._hips.copy()

    @property
    def arm(self):
        """The first arm found on the body (a 6-joint :class:`Chain`), or None. Its :meth:`Chain.ik` is in
        closed form when the arm is of a 6R family (:attr:`Chain.ik_kind`: a spherical wrist, three
        parallel axes as on UR arms and the Unitree Z1, or a spherical shoulder).

        **Its frame is the arm's base link**, the link its first joint hangs from (``arm.fk`` gives
        base <- tool), which is the body only when the arm is mounted straight on it. The whole-body
        calls (:meth:`fk_all`, :meth:`arm_ik_world`, :meth:`center_of_mass`, the dynamics) compose
        :attr:`arm_mount`; to use the chain alone in the body frame, compose it too:
        ``robot.arm_mount @ robot.arm.fk(q_arm)`` is body <- tool."""
        return self._arm

    @property
    def arm_mount(self) -> np.ndarray:
        """(4, 4) body <- arm base: where :attr:`arm`'s frame sits on the body (the fixed joints between
        the URDF's root link and the arm's base link composed; the identity when the arm hangs from the
        body itself, as on Spot). A read-only copy; the identity when the robot has no arm."""
        mount = getattr(self, "_arm_mount", None)
        return np.eye(4) if mount is None else mount.copy()

    @property
    def arms(self) -> tuple:
        """Every arm found (see :attr:`arm`), each in its own base link's frame (:attr:`arm_mounts`)."""
        return self._arms

    @property
    def arm_mounts(self) -> tuple[np.ndarray, ...]:
        """(4, 4) body <- arm base of each of :attr:`arms`, in that order (see :attr:`arm_mount`)."""
        model, (_, specs) = self._model, self._specs
        if not specs:  # Spot built from a model dict, or no arm
            return tuple(self.arm_mount for _ in self._arms)
        return tuple(model.placement(spec.base) for spec in specs)

    @property
    def report(self) -> tuple[str, ...]:
        """What was recognised, what was not, and why."""
        return self._report

    def describe(self) -> str:
        """A readable summary: the tree, the legs and arms with their geometry, the report."""
        legs, arms = self._specs
        return urdf.describe(self._model, legs, arms, self._report)

    def chain(self, link: str, base: str | None = None) -> Chain:
        """The serial chain from ``base`` (default: the body, the URDF's root) to ``link``, as a
        :class:`Chain` with the URDF's joint names and limits: FK, frames, Jacobians, differential
        IK, and the closed-form IK where the structure has one. Fixed joints are merged into the
        placements; ``link`` may be any link, fixed ones (feet, hands, sensors) included.

        When the URDF gives any ``<inertial>``, the chain carries its bodies' mass properties
        (:attr:`Chain.inertials`, a link without one has none): body j is everything that moves with
        joint j. Links rigidly attached to it (fixed joints, on the path or off it, the tool link's
        subtree included) merge into it, and the joints off the path are locked at 0, so the subtree
        they carry merges too (a gripper finger joins the wrist). ``base`` and everything attached
        to it without passing through one of the chain's joints (the body and the other legs, for a
        leg chain) is not part of the chain's dynamics. See :mod:`spotkin.inertia`.

        Mimic joints on the path follow their leaders: the chain's q holds the independent joints and
        the leaders (see :meth:`Chain.from_urdf`, which builds its chains the same way)."""
        if self._model is None:
            raise ValueError("this robot has no URDF description")
        for value, name in ((link, "link"), (base, "base")):
            if not isinstance(value, str) and not (name == "base" and value is None):
                raise TypeError(f"{name} must be a link name (str), got {type(value).__name__}")
        return chain_from_model(self._model, link, base)  # the route of Chain.from_urdf

    @property
    def body_inertial(self) -> inertia.LinkInertials:
        """The floating body's mass properties in the body frame (the URDF's root link frame): mass (),
        com (3,) and inertia (3, 3) about the centre of mass. The root link, the links fixed to it, and
        the subtrees of the joints that are neither a leg's nor the arm's (locked at 0) merge into it;
        the legs and the arm are the tree's moving bodies (:func:`spotkin.inertia.tree_of`)."""
        return self._tree(None).root

    # -- floating-base dynamics and standing statics -------------------------------------------------
    @property
    def floating_base(self):
        """The whole robot as a floating body carrying its legs and arm
        (:class:`spotkin.dynamics.FloatingBase`, built from the URDF's inertials on first use): A(q)
        (6 + n) x (6 + n), RNEA, ABA, G, the centre of mass and its Jacobian. Its coordinates are
        Pinocchio's free-flyer ones: ``[x, y, z, qx, qy, qz, qw]`` then the joints of
        :attr:`leg_joint_names` and :attr:`arm_joint_names` (see :meth:`floating_q`); velocities
        ``[v_body; w_body]`` in the body frame, then the joint rates."""
        floating = getattr(self, "_floating", None)
        if floating is None:
            legs, arms = self._specs
            if self._model is None or not legs:
                raise ValueError("dynamics need a URDF description; a robot from a model dict has none")
            chains = [self.chain(spec.foot) for spec in legs]
            if self.arm_joint_names:
                arm = self.chain(arms[0].tip)
                if arm.dof != len(self.arm_joint_names):
                    raise ValueError(
                        f"the arm's chain from the body has {arm.dof} joints, not the arm's "
                        f"{len(self.arm_joint_names)}: joints between the body and the arm's base are "
                        "not supported"
                    )
                chains.append(arm)
            body = self.body_inertial
            floating = FloatingBase((body.mass, body.com, body.inertia), chains)
            self._floating = floating
        return floating

    @property
    def mass(self) -> float:
        """The robot's total mass (kg): the body's, the legs' and the arm's links."""
        return self.floating_base.mass

    def floating_q(self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ") -> np.ndarray:
        """The generalised coordinates (..., 7 + n) of :attr:`floating_base`: the body's position and unit
        quaternion ``[x, y, z, qx, qy, qz, qw]`` (from ``body_pose``, any form :func:`spotkin.body_transform`
        takes), then ``q``: the legs' joints (..., 3 n_legs), followed by the arm's when given (..., 3 n_legs
        + n_arm; else the arm at zero). Leading dimensions broadcast; an invalid pose gives NaN there."""
        T = body_transform(body_pose, seq)
        q = self._legs_and_arm(q)
        lead = broadcast_lead(body_pose=(T.shape[:-2], T.shape), q=(q.shape[:-1], q.shape))
        T = np.broadcast_to(T, (*lead, 4, 4))
        q = np.broadcast_to(q, (*lead, q.shape[-1]))
        out = np.concatenate([T[..., :3, 3], quaternion_xyzw(T[..., :3, :3]), q], axis=-1)
        # a sample with an invalid pose or a NaN or Inf joint: NaN throughout
        return np.where(np.isfinite(out).all(axis=-1, keepdims=True), out, np.nan)

    def _legs_and_arm(self, q: ArrayLike) -> np.ndarray:
        """q (..., 3 n_legs) or (..., 3 n_legs + n_arm) in float64, the arm at zero if not given."""
        q = as_real(q, "q", np.float64)
        legs, arm = 3 * len(self._legs), len(self.arm_joint_names)
        self._leg_q(q, "q")  # the width check
        if q.shape[-1] == legs and arm:
            q = np.concatenate([q, np.zeros((*q.shape[:-1], arm))], axis=-1)
        return q

    def center_of_mass(
        self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """The whole robot's centre of mass in the world (..., 3); ``q`` as in :meth:`floating_q`. Leading
        dimensions broadcast; float32 when ``body_pose`` and ``q`` both are. An invalid pose, or a NaN or
        Inf joint, gives NaN in that sample. ``out``: an array of the result's shape and dtype to fill."""
        return self._statics.com(body_pose, sequence_code(seq), q, out)

    @property
    def _statics(self):
        """The C++ statics of the robot (its centre of mass and standing torques), built on first use."""
        statics = getattr(self, "_statics_core", None)
        if statics is None:
            floating = self.floating_base
            statics = _core.RobotStatics(self._body_core, floating._core, floating.mass)
            self._statics_core = statics
        return statics

    def standing_torques(
        self,
        body_pose: ArrayLike,
        q: ArrayLike,
        stance: ArrayLike | None = None,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        seq: str = "XYZ",
        *,
        out: tuple | None = None,
    ) -> Standing:
        """The leg torques that hold the robot still on its stance feet, and the contact forces.

        Point contacts at the stance feet (the foot points of :meth:`body_fk`) carry world forces f_i,
        the minimum-norm ones that balance the weight: sum f_i = -m g and sum (p_i - c) x f_i = 0 (c the
        centre of mass). Each leg then holds tau_l = G_l - J_l^T f_l, with G_l its joint gravity torques
        and J_l = d foot_l / d q_l (world axes); a swing leg holds G_l alone.

        ``body_pose`` as :meth:`body_fk` takes it; ``q`` (..., 3 n_legs), or with the arm's joints after
        the legs' (else the arm is at zero; it moves the centre of mass); ``stance`` (..., n_legs) bool,
        default every foot; ``gravity`` (3,) world, m/s². Leading dimensions broadcast.

        Returns :class:`Standing`: ``tau`` (..., 3 n_legs) N m in :attr:`leg_joint_names` order, ``forces``
        (..., n_legs, 3) N (zero on swing feet), ``status`` (:class:`StanceStatus`; an int8 array for a
        batch) and ``margin`` (m): the signed distance of the centre of mass's projection, along gravity,
        to the support polygon (positive inside). The status, checked in this order: UNBALANCED (no forces
        at these feet balance the weight, e.g. fewer than three feet with the centre of mass off their line
        or point; tau and forces NaN), OK (every foot pushes), PULLING (the minimum-norm forces pull on a
        foot though the centre of mass projects inside the polygon: a pushing distribution exists, this is
        not it), OUTSIDE (a foot pulls and the centre of mass projects on or outside the polygon: no
        pushing distribution exists on level ground). NaN or Inf input, or an invalid pose: INVALID_INPUT
        and NaN in that sample. ``out``: ``(tau, forces, status, margin)`` arrays of the result's shapes
        (float of the working dtype; status int8), any of them None, to write into.
        """
        code = sequence_code(seq)
        tau, forces, status, margin = self._statics.standing(body_pose, code, q, stance, gravity, out)
        if status.ndim == 0:
            return Standing(tau, forces, _STANCE_STATUS[status], margin if out is not None else margin[()])
        return Standing(tau, forces, status, margin)

    def _tree(self, joints) -> inertia.Tree:
        if self._model is None or not self._specs[0]:
            raise ValueError("dynamics need a URDF description; a robot from a model dict has none")
        to_urdf = {}
        aliases = self._joint_aliases()
        for joint in self._model.actuated_joints:
            to_urdf.setdefault(aliases.get(joint.name, joint.name), joint.name)
        if joints is None:
            joints = [to_urdf[name] for name in (*self.leg_joint_names, *self.arm_joint_names)]
        else:
            joints = [to_urdf.get(aliases.get(name, name), name) for name in _names(joints, "joints")]
        feet = [(spec.name, spec.foot, spec.contact_offset) for spec in self._specs[0]]
        names = dict(zip((spec.name for spec in self._specs[0]), self._leg_names))
        feet = [(names[name], link, offset) for name, link, offset in feet]
        return inertia.model_tree(self._model, self._model.root, joints, floating=True, feet=feet)

    # -- joint names ---------------------------------------------------------------------------------
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

    # -- whole body ----------------------------------------------------------------------------------
    def stance_feet(self, height: float = 0.5, foot_radius: float = 0.0) -> np.ndarray:
        """(n, 3) world foot points of a nominal stance, for the body at [0, 0, height, 0, 0, 0].

        Each foot is straight below its hip-pitch joint at the leg's lateral offset (hip roll 0),
        with the foot point ``foot_radius`` above the ground z = 0.
        """
        height = as_scalar(height, "height")
        foot_radius = as_finite(foot_radius, "foot_radius", 0.0)
        feet = self.hip_positions
        for k, leg in enumerate(self._legs):
            feet[k, 0] += leg.a[0]
            feet[k, 1] += leg.hip_offset
        feet[:, 2] = foot_radius
        for k, leg in enumerate(self._legs):
            drop = height + self._hips[k, 2] + leg.a[2] - foot_radius
            if not (0.0 < drop <= leg.reach[1] and drop >= leg.reach[0]):
                raise ValueError(f"height {height} m puts the feet out of reach")
        return feet

    def body_ik(
        self,
        body_pose: ArrayLike,
        feet: ArrayLike,
        seed: ArrayLike | None = None,
        seq: str = "XYZ",
        fallback: str = "nearest",
        *,
        out: tuple[np.ndarray | None, np.ndarray | None] | None = None,
    ) -> BodyIK:
        """The leg joints placing the body at ``body_pose`` with the feet at ``feet``.

        ``body_pose`` is (..., 6) [x, y, z, a, b, c] with Euler angles in ``seq``
        (default intrinsic X-Y'-Z''), (..., 4, 4), or (..., 7) [x, y, z, qx, qy, qz, qw]:
        see :func:`spotkin.body_transform`. ``feet`` (..., n, 3) are world foot points; leading
        dimensions broadcast (a single (n, 3) stance is shared without copying). Each
        foot is brought into its hip frame, p = R^T (foot - t) - hip, and solved by the
        limit-aware leg IK: each leg's status and fallback are exactly those of
        :meth:`Leg.ik`, and a leg's failure never touches the other legs. ``seed``
        (..., 3 n), or a whole-body q with the arm's joints after (unused), picks the
        branch where several are valid. A pose with NaN, or a 4x4 / quaternion that is not
        a rotation, gives INVALID_INPUT on every leg of that sample only. ``fallback`` is the
        UNREACHABLE legs' answer, as in :meth:`Leg.ik`: ``"nearest"`` (the in-limit
        configuration whose foot is nearest to the target) or ``"nan"``. Computed in float32
        when ``body_pose`` and ``feet`` both are float32, else float64; ``seed`` takes that
        dtype. ``out``: ``(q, status)`` arrays of the result's shapes and dtypes (either may be
        None) to write into, so that a control loop allocates nothing.
        """
        if seq is _DEFAULT_SEQ and fallback is _DEFAULT_FALLBACK:  # the defaults (interned strings)
            code, nearest = _XYZ, True
        else:
            code, nearest = sequence_code(seq), fallback_is_nearest(fallback)
        if seed is not None and not (type(seed) is np.ndarray and seed.shape[-1:] == (3 * len(self._legs),)):
            seed = self._leg_q(as_real(seed, "seed"), "seed")[0]  # a whole-body q: the arm's part unused
        return self._body_core.ik(body_pose, code, feet, seed, nearest, out)

    def body_fk(
        self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """(..., n, 3) world foot points: foot = t + R (hip + leg.fk(q_leg)). Leading dimensions broadcast.
        ``q`` holds the legs' joints (..., 3 n), or the legs' then the arm's, as every whole-body call
        takes it (the arm does not move the feet).

        float32 when ``body_pose`` and ``q`` both are float32, else float64. A leg with a
        NaN or Inf joint gets a NaN foot; an invalid body pose NaN feet for its sample.
        ``out``: an array of the result's shape and dtype to write into and return."""
        q = self._leg_q(as_real(q, "q"), "q")[0]
        return self._body_core.fk(body_pose, sequence_code(seq), q, out)

    def body_jacobian(
        self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """(..., 3 n, 6 + 3 n) d(feet world) / d(body twist [v; w], q).

        The twist is the linear velocity of the body origin and the angular velocity,
        both in the world frame: d foot_i = v + w x (foot_i - t) + R J_leg_i dq_i. ``q`` (..., 3 n), or
        (..., 3 n + n_arm) with the arm's joints after the legs': then the arm's columns follow, zero
        (the arm does not move the feet), so that J has a column per entry of the twist and of ``q``.
        ``out``: an array of the result's shape and dtype to write into and return.
        """
        if type(q) is np.ndarray and q.shape == (3 * len(self._legs),):  # the control loop's call
            return self._body_core.jacobian(body_pose, sequence_code(seq), q, out)
        q = as_real(q, "q")
        width = q.shape[-1] if q.ndim else 0
        q = self._leg_q(q, "q")[0]
        if width == q.shape[-1]:
            return self._body_core.jacobian(body_pose, sequence_code(seq), q, out)
        J = self._body_core.jacobian(body_pose, sequence_code(seq), q, None)
        full = np.zeros((*J.shape[:-1], 6 + width), dtype=J.dtype)
        full[..., : J.shape[-1]] = J
        return into_out(full, out)

    @quiet_float_errors
    def body_rates(
        self,
        body_pose: ArrayLike,
        q: ArrayLike,
        twist: ArrayLike,
        seq: str = "XYZ",
        tolerance: float = 1e-6,
    ) -> BodyRates:
        """Joint velocities that keep every foot fixed while the body moves with ``twist``.

        ``q`` (..., 3 n), or with the arm's joints after the legs': ``qd`` then has the same width, the
        arm's rates zero (the arm held still on the body; NaN in a sample with NaN or Inf input).
        ``twist`` (..., 6) is [v; w] (world frame, as in :meth:`body_jacobian`). Per leg,
        J_leg dq = -R^T (v + w x (foot - t)). Leading dimensions of ``body_pose``, ``q``
        and ``twist`` broadcast; the result is float64.

        A leg gets NaN velocities and ``singular = True`` when it has no usable answer:
        its Jacobian's smallest singular value is not above ``tolerance`` (stretched,
        folded, or on the hip-roll cylinder: it cannot follow every twist), or its
        sample has a NaN or Inf joint angle, twist or body pose, or a body pose that is
        not a rigid transform (as :meth:`body_fk` reads it). So ``qd`` is NaN exactly
        where ``singular`` is True, and such a leg never affects another leg or sample.

        ``tolerance`` must be a finite real number >= 0 (``TypeError`` for a non-number,
        ``ValueError`` for NaN, Inf or a negative value). Non-numeric arrays raise
        ``TypeError``, wrong or non-broadcasting shapes ``ValueError``, naming the argument.
        """
        tolerance = as_finite(tolerance, "tolerance", 0.0)
        n_legs = len(self._legs)
        T, pose = self._world_from_body(body_pose, seq)
        q = as_real(q, "q", np.float64)
        given = q.shape[-1] if q.ndim else 0
        q, q_arm = self._leg_q(q, "q")
        width = 3 * n_legs
        twist = as_real(twist, "twist", np.float64)
        lead = broadcast_lead(
            body_pose=(T.shape[:-2], pose.shape),
            q=(q.shape[:-1], q.shape),
            twist=(check_trailing(twist, "twist", (6,)), twist.shape),
        )
        n = math.prod(lead)
        R = np.broadcast_to(T[..., :3, :3], (*lead, 3, 3)).reshape(n, 3, 3)
        q = np.broadcast_to(q, (*lead, width)).reshape(n, width)
        twist = np.broadcast_to(twist, (*lead, 6)).reshape(n, 6)
        v, w = twist[:, :3], twist[:, 3:]
        qd = np.full((n, width), np.nan)
        singular = np.ones((n, n_legs), dtype=bool)
        for i, leg in enumerate(self._legs):
            columns = self._columns[i]
            q_leg = q[:, columns]
            r = np.einsum("nij,nj->ni", R, self._hips[i] + leg.fk(q_leg))
            rhs = -np.einsum("nji,nj->ni", R, v + np.cross(w, r))
            J = leg.jacobian(q_leg)
            sigma = leg.singularity(q_leg)[1]
            # the finiteness checks do not rely on sigma, which NaN input need not make NaN
            finite_input = np.isfinite(J).all((1, 2)) & np.isfinite(rhs).all(1)
            usable = np.flatnonzero((sigma > tolerance) & finite_input)
            solved = _solve_rows(J[usable], rhs[usable])
            finite = np.isfinite(solved).all(1)
            rows = usable[finite]
            qd[rows[:, None], columns[None, :]] = solved[finite]
            singular[rows, i] = False
        if q_arm is not None:  # the arm held still on the body: zero rates, NaN for a non-finite sample
            q_arm = np.broadcast_to(q_arm, (*lead, given - width)).reshape(n, given - width)
            finite = (
                np.isfinite(q_arm).all(1)
                & np.isfinite(q).all(1)
                & np.isfinite(twist).all(1)
                & np.broadcast_to(np.isfinite(T).all((-2, -1)), lead).reshape(n)
            )
            arm_rates = np.where(finite[:, None], 0.0, np.nan) * np.ones((n, given - width))
            qd = np.concatenate([qd, arm_rates], axis=1)
        return BodyRates(qd.reshape(*lead, given), singular.reshape(*lead, n_legs))

    @quiet_float_errors
    def fk_all(
        self, body_pose: ArrayLike, q: ArrayLike, q_arm: ArrayLike | None = None, seq: str = "XYZ"
    ) -> BodyFrames:
        """Every frame of interest in the world frame: body, hips, knees, feet, and the hand.

        Checked as :meth:`body_fk`: ``body_pose`` in any accepted form, ``q`` (..., 3 n) (or with the
        arm's joints after the legs', in place of ``q_arm``) and ``q_arm`` (..., 6) real arrays whose
        leading dimensions broadcast (``TypeError``
        for non-numeric input such as None, ``ValueError`` naming the argument for another
        shape). A body pose with NaN or Inf, or that is not a rigid transform (a 4x4 whose
        rotation part is not a rotation or whose last row is not [0, 0, 0, 1], a non-unit
        quaternion), gives NaN frames for that sample only, as :meth:`body_fk` gives NaN
        feet. Every frame is float64. ``q_arm`` needs an :attr:`arm`.
        """
        n_legs = len(self._legs)
        T, pose = self._world_from_body(body_pose, seq)
        q, q_arm_in_q = self._leg_q(as_real(q, "q", np.float64), "q")
        if q_arm_in_q is not None:
            if q_arm is not None:
                raise ValueError("q holds the arm's joints, so q_arm must be None")
            q_arm = q_arm_in_q
        leads = {
            "body_pose": (T.shape[:-2], pose.shape),
            "q": (q.shape[:-1], q.shape),
        }
        if q_arm is not None:
            if self._arm is None:
                raise ValueError("q_arm was given but this robot has no arm")
            q_arm = as_real(q_arm, "q_arm", np.float64)
            leads["q_arm"] = (check_trailing(q_arm, "q_arm", (6,)), q_arm.shape)
        lead = broadcast_lead(**leads)
        T = np.broadcast_to(T, (*lead, 4, 4))
        q = np.broadcast_to(q, (*lead, 3 * n_legs))
        R, t = T[..., :3, :3], T[..., :3, 3]

        def world(p):
            return t[..., None, :] + np.einsum("...ij,...kj->...ki", R, p)

        hips = np.broadcast_to(self._hips, (*lead, n_legs, 3))
        knees, feet = np.empty((*lead, n_legs, 3)), np.empty((*lead, n_legs, 3))
        for i, leg in enumerate(self._legs):
            q_leg = q[..., self._columns[i]]
            knees[..., i, :] = self._hips[i] + leg.knee(q_leg)
            feet[..., i, :] = self._hips[i] + leg.fk(q_leg)
        hand = None if q_arm is None else T @ self.arm_mount @ self._arm.fk(q_arm)
        return BodyFrames(T.copy(), world(hips), world(knees), world(feet), hand)

    @quiet_float_errors
    def arm_ik_world(
        self, body_pose: ArrayLike, T_world: ArrayLike, seed: ArrayLike | None = None, seq: str = "XYZ"
    ) -> tuple[np.ndarray, np.ndarray | Status]:
        """Arm IK for hand targets given in the world frame: (q (..., 6), status).

        T_base = (T_world_body . arm_mount)^-1 T_world, the target in the frame of :attr:`arm`, then the
        arm's closed-form IK (one solution, nearest to ``seed`` or the first valid). ``T_world`` is
        (..., 4, 4) and ``seed`` (..., 6); leading dimensions of body poses, targets and seeds
        broadcast together (``ValueError`` naming them otherwise). A body pose with NaN/Inf or
        that is not a rigid transform (as :meth:`body_fk` reads it) gives INVALID_INPUT for that
        sample, like a bad target. q is float32 when ``body_pose`` and ``T_world`` both are,
        float64 otherwise.
        """
        if self._arm is None:
            raise ValueError("this robot has no arm")
        T_wb, pose = self._world_from_body(body_pose, seq)
        target = as_real(T_world, "T_world")
        leads = {
            "body_pose": (T_wb.shape[:-2], pose.shape),
            "T_world": (check_trailing(target, "T_world", (4, 4)), target.shape),
        }
        if seed is not None:
            seed = as_real(seed, "seed")
            leads["seed"] = (check_trailing(seed, "seed", (6,)), seed.shape)
        lead = broadcast_lead(**leads)
        T_world64 = target.astype(np.float64, copy=False)
        # world <- arm base = world <- body . body <- arm base (arm_mount)
        mount = self.arm_mount
        R = T_wb[..., :3, :3] @ mount[:3, :3]
        t = T_wb[..., :3, 3] + np.einsum("...ij,j->...i", T_wb[..., :3, :3], mount[:3, 3])
        # the blocks apart, R^T R_w and R^T (p_w - t), so that the target's last row (checked by
        # the arm as it is given) never mixes into them: a far body times a last row within
        # tolerance of [0, 0, 0, 1] would otherwise tilt the rotation
        lead_shape = np.broadcast_shapes(T_wb.shape[:-2], T_world64.shape[:-2])
        T_body = np.empty((*lead_shape, 4, 4))
        T_body[..., :3, :3] = np.einsum("...ji,...jk->...ik", R, T_world64[..., :3, :3])
        T_body[..., :3, 3] = np.einsum("...ji,...j->...i", R, T_world64[..., :3, 3] - t)
        T_body[..., 3, :] = T_world64[..., 3, :]  # the caller's last row, so a bad one is still reported
        T_body = np.broadcast_to(T_body, (*lead, 4, 4)).astype(real_dtype(pose, target))
        if seed is not None:
            seed = _broadcast_to_lead(seed, 1, lead)
        return self._arm_ik(T_body, seed)

    def _arm_ik(self, T_body, seed):
        return self._arm.ik(T_body, seed)

    def _q_widths(self) -> tuple[int, ...]:
        """The widths a whole-body q may have: the legs' joints, or the legs' then the arm's."""
        legs, arm = 3 * len(self._legs), len(self.arm_joint_names)
        return (legs, legs + arm) if arm else (legs,)

    def _leg_q(self, q: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray | None]:
        """(q_legs, q_arm or None) of a whole-body q (..., 3 n) or (..., 3 n + n_arm): the one width rule
        of every whole-body call. ValueError naming ``name`` for another width."""
        if q.ndim and q.shape[-1] == 3 * len(self._legs):  # the common case, first
            return q, None
        widths = self._q_widths()
        if q.ndim == 0 or q.shape[-1] not in widths:
            expected = " or ".join(f"(..., {w})" for w in widths)
            what = "the legs' joints" + (", or the legs' then the arm's" if len(widths) > 1 else "")
            raise ValueError(f"{name} must have shape {expected} ({what}), got {q.shape}")
        if q.shape[-1] == widths[0]:
            return q, None
        return q[..., : widths[0]], q[..., widths[0] :]

    def _world_from_body(self, body_pose, seq) -> tuple[np.ndarray, np.ndarray]:
        """(T, pose): world <- body transforms (..., 4, 4) in float64, NaN for every pose the
        core rejects (body_transform checks them as the core does), and ``body_pose`` as an array."""
        pose = as_real(body_pose, "body_pose")
        return body_transform(pose, seq), pose

    def with_limits(self, limits) -> Robot:
        """This robot with other joint limits: a new Robot (the original is unchanged), built as
        ``from_urdf(..., limits=...)`` builds it, so that the legs' and the arm's closed-form IK, their
        fallbacks (the nearest configuration inside the limits), :meth:`body_ik` and the workspace code
        all use the new limits.

        ``limits`` is a dict joint name -> (lower, upper) in radians (metres for a prismatic joint);
        ±inf means unlimited; the joints it does not name keep their limits (earlier ``with_limits``
        calls included). A continuous joint given finite limits becomes a revolute one. ``ValueError``
        for a name that is not a moving joint, NaN or lower > upper; ``TypeError`` for a non-dict or
        non-numeric values. Some URDFs give wide ranges (ANYmal C's hip and knee flexion are ±9.42 rad,
        which lets the leg IK pick a knee above the hip); :meth:`describe` flags ranges beyond 2π."""
        if not isinstance(limits, Mapping):
            raise TypeError(
                f"limits must be a dict joint name -> (lower, upper), got {type(limits).__name__}"
            )
        text, feet, contact_offset, nominal, old, leg_order = self._source
        aliases = self._joint_aliases()
        to_urdf = {}  # any name a joint answers to -> its URDF name
        for joint in self._model.actuated_joints:
            to_urdf.setdefault(aliases.get(joint.name, joint.name), joint.name)
        limits = {
            to_urdf.get(aliases.get(k, k), k) if isinstance(k, str) else k: v for k, v in limits.items()
        }
        merged = {**(old or {}), **_limit_table(limits, self._model)}
        return _rebuild_robot(text, feet, contact_offset, nominal, merged, leg_order)

    def __reduce__(self):
        return (_rebuild_robot, self._source)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, legs={self._leg_names}, arm={'yes' if self._arm is not None else 'no'})"


def _rebuild_robot(source, feet, contact_offset, nominal, limits=None, leg_order="urdf") -> Robot:
    """From the URDF's text (str) or the file's bytes, as the robot was loaded."""
    return Robot._from_model(
        urdf.parse_urdf(source), feet, contact_offset, nominal, source, limits, leg_order
    )


class StanceStatus(IntEnum):
    """Outcome of :meth:`Robot.standing_torques` for one sample."""

    OK = 0
    """The minimum-norm contact forces balance the robot, and every one pushes on the ground."""
    PULLING = 1
    """They balance, but a foot pulls, though the centre of mass projects inside the support polygon: a
    pushing distribution exists, the minimum-norm one is not it."""
    OUTSIDE = 2
    """They balance only by pulling on a foot, and the centre of mass projects on or outside the support
    polygon: no pushing distribution exists on level ground."""
    INVALID_INPUT = 3
    """NaN or Inf in the input, an invalid body pose or a stance value other than 0/1: everything NaN
    (the code of :attr:`Status.INVALID_INPUT`)."""
    UNBALANCED = 4
    """No forces at these feet balance the weight (fewer than three feet, or collinear ones, with the
    centre of mass off their line or point): tau and forces are NaN."""


_STANCE_STATUS = tuple(StanceStatus)  # by value: one sample's status


class Standing(NamedTuple):
    """The result of :meth:`Robot.standing_torques`."""

    tau: np.ndarray
    """(..., 3 n_legs) N m: the leg joint torques that hold the pose, in leg_joint_names order."""
    forces: np.ndarray
    """(..., n_legs, 3) N: the world contact forces on the feet (ground on foot), zero on swing feet."""
    status: np.ndarray | StanceStatus
    """(...) :class:`StanceStatus` values (int8), or one member for a single sample."""
    margin: np.ndarray
    """(...) m: signed distance of the centre of mass's projection to the support polygon, in the plane
    normal to gravity, positive inside (with fewer than three non-collinear feet: minus the distance to
    their segment or point; NaN without gravity)."""
