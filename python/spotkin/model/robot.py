"""Legged robots from their descriptions: a body with any number of roll–pitch–pitch legs,
and the arms it carries. Whole-body IK, FK, Jacobians and joint rates for every robot,
built by :meth:`Robot.from_urdf`; :class:`spotkin.Spot` is one instance of it.

Frames: the body frame is the URDF's root link frame. Each leg's frame has its origin at
the leg's hip-roll joint and the body's axes (see :class:`spotkin.Leg`).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core, urdf
from .._support.boundary import as_real
from ..dynamics import inertia
from .arm import arm_solver
from .chain import Chain
from .leg import Leg
from .robot_body import _WholeBodyMethods
from .robot_joints import _choice, _described, _JointNameMethods
from .robot_statics import _FloatingBaseMethods
from .urdf_chain import chain_from_model

__all__ = ["Robot"]

_MOTION: dict[str, Callable] = {}
"""What the motion layer (above this one: the model may not import it) lends to :class:`Robot`:
``spotkin.motion.plan`` registers ``"plan_gait"`` when the package is imported."""


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


class RobotNaming(NamedTuple):
    """A description's legs and joints under other names (the Spot SDK's, say): what
    :class:`spotkin.Spot` adds to the packaged description. Data only: the robot is built as any other."""

    legs: Mapping[str, str]
    """Recognised leg name -> the robot's leg name, in the robot's leg order."""
    joints: Callable[[str], tuple[str, str, str]]
    """A leg's (new) name -> its three joints' names."""
    arm_joints: Mapping[str, str] | None = None
    """The description's arm joint name -> the robot's (None: the description's names)."""


class Robot(_WholeBodyMethods, _FloatingBaseMethods, _JointNameMethods):
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
        "_reach_core",
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
        robot = cls.__new__(cls)
        robot._assemble(model, feet, contact_offset, nominal, text, limits, leg_order)
        return robot

    def _assemble(
        self, model, feet, contact_offset, nominal, text, limits=None, leg_order="urdf", naming=None
    ) -> None:
        """Build this robot from a parsed description: every robot, :class:`spotkin.Spot` included, goes
        through here. ``naming`` (a :class:`RobotNaming`, or None for the description's own names) renames
        and orders the recognised legs and joints, and may give the arm a dedicated solver."""
        leg_order = _choice(leg_order, "leg_order", ("urdf", "roles"))
        limits = _limit_table(limits, model)
        if limits:
            model = model.with_limits(limits)
        specs, leg_report = urdf.find_legs(model, feet=feet, contact_offset=contact_offset)
        if naming is not None:
            by_name = {spec.name: spec for spec in specs}
            missing = [name for name in naming.legs if name not in by_name]
            if missing:
                raise ValueError(f"the description lacks the legs {missing} that its names expect")
            specs = tuple(by_name[name] for name in naming.legs)
        elif leg_order == "roles" and specs:
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
        names = [naming.legs[spec.name] if naming else spec.name for spec in specs]
        legs = [
            Leg.from_geometry(
                spec.a, spec.b, spec.c, spec.signs, spec.limits, name, nominal=nominal.get(spec.name)
            )
            for spec, name in zip(specs, names)
        ]
        self._model = model
        self._source = None if naming else (text, feet, contact_offset, nominal, limits, leg_order)
        self._report = tuple(leg_report) + tuple(arm_report)
        self._specs = (tuple(specs), tuple(arms))
        renames = naming.arm_joints if naming is not None else None
        arm_solvers = tuple(arm_solver(self.chain(arm.tip, base=arm.base), renames) for arm in arms)
        self._arms = arm_solvers
        # body <- arm base: the arm's chain starts at the link its first joint hangs from, which the
        # recognition reaches from the body through fixed joints only (find_arms takes the first six
        # actuated joints below the root), so the mount is that link's placement at zero angles
        self._arm_mount = model.placement(arms[0].base) if arms else np.eye(4)
        self._arm_mount.flags.writeable = False
        joints = [
            naming.joints(name) if naming else tuple(spec.joint_names) for spec, name in zip(specs, names)
        ]
        keep_order = naming is not None or leg_order == "roles"
        self._set_legs(
            legs,
            [spec.hip_origin for spec in specs],
            names,
            joints,
            arm_solvers[0] if arm_solvers else None,
            keep_order,
        )

    def _set_legs(self, legs, hips, names, joint_names, arm, keep_order=False) -> None:
        """The legs (their joints in ``joint_names``' order when ``keep_order``, else the description's)."""
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
        order = {name: k for k, name in enumerate(flat)} if keep_order else self._urdf_order(flat)
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
        model = self._model
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
        """The recognised legs, in :attr:`leg_names` order (the URDF's order of their first joints, unless
        ``leg_order="roles"`` or the robot names its legs itself, as :class:`spotkin.Spot` does)."""
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
    def limits(self) -> np.ndarray:
        """(3 n_legs + n_arm, 2) joint limits (lower, upper) in the order of a whole-body q: the legs'
        joints (:attr:`leg_joint_names`), then the arm's (:attr:`arm_joint_names`); ±inf where
        unlimited. A copy."""
        n_legs = 3 * len(self._legs)
        out = np.empty((n_legs + (0 if self._arm is None else self._arm.dof), 2))
        for columns, leg in zip(self._columns, self._legs):
            out[columns] = leg.limits
        if self._arm is not None:
            out[n_legs:] = self._arm.limits
        return out

    @property
    def leg_columns(self) -> np.ndarray:
        """(n_legs, 3) int: where each leg's joints (hip roll, hip pitch, knee) sit in a whole-body q."""
        return self._columns.copy()

    @property
    def hip_positions(self) -> np.ndarray:
        """(n, 3) hip-roll joint origins in the body frame."""
        return self._hips.copy()

    @property
    def arm(self):
        """The first arm found on the body (a 6-joint :class:`Chain`), or None. Its :meth:`Chain.ik` is in
        closed form when the arm is of a 6R family (:attr:`Chain.ik_kind`: a spherical wrist, three
        parallel axes as on UR arms and the Unitree Z1, or a spherical shoulder). An arm with the Spot
        Arm's structure is a :class:`SpotArm` (a Chain solved by the arm's own closed form), as
        :attr:`spotkin.Spot.arm` is: the same object whichever way the robot was loaded.

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

    # -- motion --------------------------------------------------------------------------------------
    def plan_gait(
        self,
        gait,
        velocity=(0.0, 0.0, 0.0),
        duration: float = 5.0,
        rate: float = 500.0,
        *,
        attitude=(0.0, 0.0),
        changes=(),
    ):
        """A walk planned open loop: ``gait`` (a :class:`spotkin.Gait` or a preset name) following
        ``velocity`` (..., 3) = (vx, vy, yaw rate) in the body frame (m/s, rad/s; a batch of commands
        broadcasts, one plan each) for ``duration`` s at ``rate`` ticks per second, starting at rest on
        the gait's nominal feet with the body at the origin; ``attitude`` (roll, pitch) of the body
        (rad); ``changes``: a schedule of ``(time, gait, velocity)`` (either may be None: unchanged),
        each applied at the first tick at or after its time, the gait blended in as the guide describes,
        the velocity (3,) replacing every command's. Returns a :class:`spotkin.GaitPlan`: per tick the
        body pose, the feet, the contacts, q
        (IK seeded with the previous tick's), qd, feedforward torques, the worst IK status, the support
        margin and whether a step was shortened. A quadruped only (``ValueError`` otherwise), and at most
        1e8 ticks; a NaN or Inf command is a ``ValueError``. The gait model is in the guide's *Walking*
        page. Computed by the compiled planner, each command of a batch on the threads.
        """
        return _MOTION["plan_gait"](self, gait, velocity, duration, rate, attitude, changes)

    def reach(self, T_hand_world, feet=None, seed=None, margin=None, box=None):
        """Whole-body reach: the body pose, the legs' joints and the arm's that put the hand exactly at
        ``T_hand_world`` (..., 4, 4) in the world with the feet fixed at ``feet`` (..., n, 3) (default:
        the nominal stance, :meth:`stance_feet` at the nominal height), every joint within its limits,
        no collision between the arm and the body, the legs or the ground (the horizontal plane through
        the lowest foot point) (:mod:`spotkin.motion.capsules`), the
        centre of mass at least ``margin`` m (default 5 % of the hip height) inside the feet's support
        polygon, and the body pose within ``box`` (a :class:`spotkin.ReachBox` of offsets from the
        nominal pose in the stance frame; default :func:`spotkin.motion.reach.default_box`).

        Among the answers, the one nearest to the joints' mid-ranges and the nominal body pose (in the
        least-squares sense, each as a fraction of its range); with ``seed`` (a previous
        :class:`spotkin.ReachResult`, or a (body_pose, q) pair), the one nearest to the seed, so that a
        moving target gets a continuous answer. Leading dimensions of every argument broadcast.

        Returns a :class:`spotkin.ReachResult`: ``body_pose`` (..., 6) [x, y, z, Euler "XYZ"], ``q``
        (..., 3 n_legs + n_arm), ``status`` (:class:`spotkin.ReachStatus`), ``margin``, ``distance``
        and ``angle`` (how far the hand is from the target: 0 unless UNREACHABLE, where the answer is the
        nearest pose the search reached), and the arm's branches at the chosen body pose. The method is
        in the guide's *Reach* page. A robot without an arm, an arm without 6 joints or without a
        closed form, a target of another shape or a ``box`` that is not (2, 6) with lower <= upper is a
        ``ValueError``; NaN or Inf in a sample, or a target that is not a rigid transform, gives
        INVALID_INPUT and NaN in that sample only.
        """
        return _MOTION["reach"](self, T_hand_world, feet, seed, margin, box)

    def reach_path(self, start, target, n: int = 50, feet=None, margin=None, box=None):
        """A motion from ``start`` (a :class:`spotkin.ReachResult` of one target, or a (body_pose (6,), q)
        pair) to the reach answer for ``target`` (4, 4) (:meth:`reach`, seeded with the start), in ``n``
        samples, the feet fixed at ``feet`` (default the nominal stance), every constraint of
        :meth:`reach` held at every sample: the body pose and the arm's joints along straight lines
        timed by a quintic, the legs from the leg IK; five orders are tried (together, the body first, the
        arm first, the arm through two via postures), the first whose every sample holds is taken.
        Returns a :class:`spotkin.ReachPath` (``t``, ``body_pose``, ``q``, ``margin``, ``ok`` per sample,
        ``status``, ``order``, ``answer``). The method is in the guide's *Reach* page.
        """
        return _MOTION["reach_path"](self, start, target, n, feet, margin, box)

    def reachability(
        self,
        points=None,
        approach=None,
        *,
        spacing=None,
        axis="x",
        feet=None,
        margin=None,
        box=None,
        directions=14,
        rolls=4,
    ):
        """Which hand positions ``points`` (..., 3) (world; default a grid around the arm at ``spacing``,
        15 % of the hip height unless given) the whole body reaches with the feet fixed at ``feet``, with
        the hand's ``axis`` ("x", "y" or "z") along ``approach`` (..., 3) when given, else along any of
        ``directions`` directions, each turned about it by ``rolls`` angles. Every answer found holds
        every constraint of :meth:`reach`; a point not found may be reached by an orientation between
        those tried (an inner estimate). Returns a :class:`spotkin.Reachability`: ``reachable``, the
        hand pose, body pose and joints found, and the ``volume`` (m^3) when the points are a grid of
        known ``spacing``. Drawn by :func:`spotkin.plot.reachability`. The method is in the guide's
        *Reach* page.
        """
        return _MOTION["reachability"](
            self,
            points,
            approach,
            spacing=spacing,
            axis=axis,
            feet=feet,
            margin=margin,
            box=box,
            directions=directions,
            rolls=rolls,
        )

    def __reduce__(self):
        return (_rebuild_robot, self._source)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, legs={self._leg_names}, arm={'yes' if self._arm is not None else 'no'})"


def _rebuild_robot(source, feet, contact_offset, nominal, limits=None, leg_order="urdf") -> Robot:
    """From the URDF's text (str) or the file's bytes, as the robot was loaded."""
    return Robot._from_model(
        urdf.parse_urdf(source), feet, contact_offset, nominal, source, limits, leg_order
    )
