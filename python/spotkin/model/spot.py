"""The built-in Spot: a :class:`spotkin.Robot` built from the packaged Spot URDF
(``spotkin/robots/spot_with_arm.urdf``), with the SDK's leg and joint names and the Spot
Arm's dedicated closed form."""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping

import numpy as np

from .. import robots, urdf
from .._support.boundary import as_finite, as_real
from .arm import ARM_JOINT_NAMES, SpotArm
from .leg import Leg
from .presets import LEG_NAMES, SPOT
from .robot import Robot, RobotNaming, _limit_table
from .robot_body import BodyFrames, BodyIK, BodyRates

__all__ = ["BodyFrames", "BodyIK", "BodyRates", "Spot"]

# the packaged description's names, in SDK leg order
_URDF_LEGS = {"fl": "front_left", "fr": "front_right", "hl": "rear_left", "hr": "rear_right"}
_URDF_ARM = ("arm_sh0", "arm_sh1", "arm_el0", "arm_el1", "arm_wr0", "arm_wr1")


@functools.lru_cache(maxsize=1)
def builtin_urdf_text() -> str:
    """The packaged Spot URDF's text (spot_with_arm.urdf: kinematics and inertials)."""
    return robots.text("spot_with_arm")


@functools.lru_cache(maxsize=1)
def _builtin_model() -> urdf.Model:
    return urdf.parse_urdf(builtin_urdf_text())


def _section(table: Mapping, key: str, where: str):
    """table[key], with a ValueError naming the missing key (``where`` names the table)."""
    if not isinstance(table, Mapping):
        raise TypeError(f"{where} must be a dict, got {type(table).__name__}")
    try:
        return table[key]
    except KeyError:
        raise ValueError(f"{where} is missing the key {key!r}") from None


def _number(table: Mapping, key: str, where: str, minimum: float = -math.inf, strict: bool = False) -> float:
    return as_finite(_section(table, key, where), f"{where}[{key!r}]", minimum, strict)


def _point(table: Mapping, key: str, where: str) -> tuple[float, ...]:
    name = f"{where}[{key!r}]"
    point = as_real(_section(table, key, where), name, np.float64)
    if point.shape != (3,) or not np.isfinite(point).all():
        raise ValueError(f"{name} must be 3 finite numbers (shape (3,)), got {point.tolist()}")
    return tuple(point.tolist())


def _limit_rows(table: Mapping, key: str, where: str, joints: int) -> tuple[tuple[float, float], ...]:
    name = f"{where}[{key!r}]"
    rows = as_real(_section(table, key, where), name, np.float64)
    if rows.shape != (joints, 2):
        raise ValueError(f"{name} must have shape ({joints}, 2) as (lower, upper) rows, got {rows.shape}")
    if np.isnan(rows).any() or (rows[:, 0] > rows[:, 1]).any():
        raise ValueError(f"{name} must satisfy lower <= upper, with no NaN, got {rows.tolist()}")
    return tuple(map(tuple, rows.tolist()))


def _checked_model(model: Mapping) -> dict:
    """A validated copy of a model dict shaped like :data:`spotkin.models.SPOT`."""
    if not isinstance(model, Mapping):
        raise TypeError(f"model must be a dict shaped like spotkin.models.SPOT, got {type(model).__name__}")
    hips = _section(model, "hip_positions", "model")
    leg = _section(model, "leg", "model")
    arm = _section(model, "arm", "model")
    where_hips, where_leg, where_arm = "model['hip_positions']", "model['leg']", "model['arm']"
    checked = {
        "hip_positions": {name: _point(hips, name, where_hips) for name in LEG_NAMES},
        "leg": {
            "hip_offset": _number(leg, "hip_offset", where_leg, 0.0),
            "upper": _number(leg, "upper", where_leg, 0.0, strict=True),
            "knee_offset": _number(leg, "knee_offset", where_leg),
            "lower": _number(leg, "lower", where_leg, 0.0, strict=True),
            "foot_radius": _number(leg, "foot_radius", where_leg, 0.0),
            "limits": _limit_rows(leg, "limits", where_leg, 3),
        },
        "arm": {
            "mount": _point(arm, "mount", where_arm),
            "upper_arm": _number(arm, "upper_arm", where_arm, 0.0, strict=True),
            "forearm": _number(arm, "forearm", where_arm),
            "forearm_offset": _number(arm, "forearm_offset", where_arm),
            "hand": _number(arm, "hand", where_arm),
            "limits": _limit_rows(arm, "limits", where_arm, 6),
        },
    }
    if checked["arm"]["forearm"] == 0.0 and checked["arm"]["forearm_offset"] == 0.0:
        raise ValueError("model['arm']['forearm'] and model['arm']['forearm_offset'] are both 0")
    if "nominal_stance" in model:
        checked["nominal_stance"] = _point(model, "nominal_stance", "model")
    if "leg_limits" in model:
        per_leg = _section(model, "leg_limits", "model")
        checked["leg_limits"] = {
            name: _limit_rows(per_leg, name, "model['leg_limits']", 3)
            for name in LEG_NAMES
            if name in per_leg
        }
    return checked


def _spot_arm(arm: Mapping) -> SpotArm:
    """The Spot Arm's dedicated closed form from its numbers (mount, link lengths, limits)."""
    return SpotArm(
        arm["mount"],
        arm["upper_arm"],
        arm["forearm"],
        arm["forearm_offset"],
        arm["hand"],
        limits=arm["limits"],
    )


def _sdk_joints(leg: str) -> tuple[str, str, str]:
    """A leg's joints as the SDK names them: fl.hx, fl.hy, fl.kn."""
    return (f"{leg}.hx", f"{leg}.hy", f"{leg}.kn")


# The packaged description under the SDK's names (legs in SDK order, the arm's joints arm0.sh0, ...)
_SDK_NAMING = RobotNaming(
    legs={_URDF_LEGS[name]: name for name in LEG_NAMES},
    joints=_sdk_joints,
    arm_joints=dict(zip(_URDF_ARM, ARM_JOINT_NAMES)),
)


class Spot(Robot):
    """Boston Dynamics Spot. Body frame: x forward, y left, z up, origin at the
    centre of the four hx joints. Legs in SDK order: fl, fr, hl, hr.

    By default the model is the packaged Spot URDF (``spotkin/robots/spot_with_arm.urdf``,
    built by the same machinery as :meth:`Robot.from_urdf`, with per-leg joint limits),
    named as the SDK names it: legs fl, fr, hl, hr; joints fl.hx, ... hr.kn; the arm is a
    :class:`SpotArm` (arm0.sh0, ... arm0.wr1). :meth:`q_from_names` and :meth:`names_from_q` also answer
    to the packaged URDF's joint names (``front_left_hip_x``, ``arm_sh0``, ...).

    ``model`` is instead a dict shaped like :data:`spotkin.models.SPOT`: keys
    ``"hip_positions"`` (a (3,) point per leg name), ``"leg"`` (``hip_offset``,
    ``upper``, ``knee_offset``, ``lower``, ``foot_radius``, ``limits`` (3, 2)),
    optionally ``"leg_limits"`` (a (3, 2) table per leg name, overriding ``limits``) and
    ``"arm"`` (``mount`` (3,), ``upper_arm``, ``forearm``, ``forearm_offset``, ``hand``,
    ``limits`` (6, 2)); other keys are ignored. It is checked and copied: a missing key,
    a non-finite number, ``upper``, ``lower`` or ``upper_arm`` not positive, a negative
    ``hip_offset`` or ``foot_radius``, a point not of shape (3,), or limits with NaN or
    lower > upper raise ``ValueError`` naming the key; a non-dict or non-numeric value
    raises ``TypeError``. :meth:`chain` and :meth:`describe` always show the packaged
    description (URDF link and leg names), also for a model dict.
    """

    __slots__ = ("_foot_radius", "_limit_override", "_spot_model")

    leg_names = LEG_NAMES
    """The legs in SDK order: ("fl", "fr", "hl", "hr") (h: hind)."""
    joint_names = tuple(name for leg in LEG_NAMES for name in _sdk_joints(leg))
    """The 12 leg joints in SDK order, the order of the legs' ``q``: "fl.hx", "fl.hy", "fl.kn", "fr.hx", ...,
    "hr.kn"."""
    leg_joint_names = joint_names
    arm_joint_names = ARM_JOINT_NAMES
    """The 6 arm joints in SDK order, the order of ``q_arm``."""

    def __init__(self, model: Mapping | None = None) -> None:
        self._build(model, {})

    def _build(self, model: Mapping | None, limits: dict[str, tuple[float, float]]) -> None:
        """``limits``: packaged-URDF joint name -> (lower, upper), checked (see :meth:`with_limits`)."""
        self._limit_override = dict(limits)
        self._spot_model = None if model is None else _checked_model(model)
        if model is None:  # the packaged description, through Robot's construction, with the SDK's names
            self._assemble(_builtin_model(), None, None, None, None, limits, naming=_SDK_NAMING)
            self._foot_radius = SPOT["leg"]["foot_radius"]
            return
        description = _builtin_model()
        if limits:
            description = description.with_limits(limits)
        self._model = description
        self._source = None
        checked = self._spot_model
        leg = checked["leg"]
        per_leg = checked.get("leg_limits", {})
        # the overrides apply to a model dict too, by joint (a URDF name -> its SDK slot)
        urdf_legs = [
            f"{_URDF_LEGS[name]}_{joint}" for name in LEG_NAMES for joint in ("hip_x", "hip_y", "knee")
        ]
        legs = []
        for k, name in enumerate(LEG_NAMES):
            rows = np.array(per_leg.get(name, leg["limits"]), dtype=float)
            for j in range(3):
                rows[j] = limits.get(urdf_legs[3 * k + j], rows[j])
            side = "left" if name.endswith("l") else "right"
            legs.append(
                Leg(
                    leg["hip_offset"],
                    leg["upper"],
                    leg["lower"],
                    leg["knee_offset"],
                    side=side,
                    limits=rows,
                    name=name,
                )
            )
        hips = [checked["hip_positions"][name] for name in LEG_NAMES]
        arm = dict(checked["arm"])
        arm["limits"] = tuple(limits.get(name, row) for name, row in zip(_URDF_ARM, arm["limits"]))
        self._foot_radius = leg["foot_radius"]
        self._report = ("built from a model dict: chain() and describe() show the packaged description",)
        self._specs = ((), ())
        spot_arm = _spot_arm(arm)
        self._arms = (spot_arm,)
        self._set_legs(
            legs, hips, LEG_NAMES, [_sdk_joints(name) for name in LEG_NAMES], spot_arm, keep_order=True
        )

    @classmethod
    def from_urdf(cls, *args, **kwargs):
        """Not for Spot: ``sk.Spot()`` is the packaged description; load other files with
        :meth:`Robot.from_urdf`. Raises ``TypeError``."""
        raise TypeError("Spot() is built from the packaged Spot description; use sk.Robot.from_urdf(path)")

    @classmethod
    def from_urdf_string(cls, *args, **kwargs):
        """Not for Spot (see :meth:`from_urdf`). Raises ``TypeError``."""
        raise TypeError(
            "Spot() is built from the packaged Spot description; use sk.Robot.from_urdf_string(text)"
        )

    @property
    def arm(self) -> SpotArm:
        """The Spot Arm, mounted at its official position on the body: a :class:`SpotArm` (a
        :class:`Chain` with the arm's closed form and the URDF's mass properties; joints named as the
        SDK names them), the one :meth:`Robot.from_urdf` gives for the same description."""
        return self._arm

    @property
    def urdf_joint_names(self) -> tuple[str, ...]:
        """The packaged description's actuated joints (legs, arm, gripper) in its order."""
        return tuple(joint.name for joint in self._model.actuated_joints)

    def _joint_aliases(self) -> dict[str, str]:
        """The SDK's joint names (legs, arm, ``arm0.hr0`` and the gripper ``arm0.f1x``) and the
        packaged URDF's (``front_left_hip_x``, ``arm_sh0``, ...; every joint), each -> its SDK name."""
        table = getattr(self, "_aliases", None)
        if table is None:
            table = {joint.name: joint.name for joint in self._model.joints}
            legs = [f"{_URDF_LEGS[leg]}_{joint}" for leg in LEG_NAMES for joint in ("hip_x", "hip_y", "knee")]
            arm = [*_URDF_ARM, "arm_hr0", "arm_f1x"]
            sdk = [*self.joint_names, *self.arm_joint_names, "arm0.hr0", "arm0.f1x"]
            table.update(zip(legs + arm, sdk))
            table.update((name, name) for name in sdk)
            self._aliases = table
        return table

    def stance_feet(self, height: float = 0.5) -> np.ndarray:
        """(4, 3) world foot centres of a nominal stance, for the body at [0, 0, height, 0, 0, 0].

        Each foot is straight below its hy joint (hx = 0) with the foot sphere resting on
        the ground z = 0, so its centre is at z = foot_radius (0.036 m).
        """
        return super().stance_feet(height, self._foot_radius)

    def _arm_ik(self, T_body, seed):
        return self._arm.ik(T_body, seed=seed)

    def with_limits(self, limits) -> Spot:
        """This Spot with other joint limits (a new Spot; see :meth:`Robot.with_limits`). The keys may be
        the SDK's joint names (``"fl.kn"``, ``"arm0.sh1"``) or the packaged URDF's (``"front_left_knee"``);
        the legs' and the arm's closed forms, fallbacks and workspaces use the new limits."""
        if not isinstance(limits, Mapping):
            raise TypeError(
                f"limits must be a dict joint name -> (lower, upper), got {type(limits).__name__}"
            )
        aliases = self._joint_aliases()
        to_urdf = {}
        for joint in self._model.actuated_joints:
            to_urdf.setdefault(aliases.get(joint.name, joint.name), joint.name)
        limits = {
            to_urdf.get(aliases.get(k, k), k) if isinstance(k, str) else k: v for k, v in limits.items()
        }
        table = {**self._limit_override, **_limit_table(limits, self._model)}
        return _rebuild_spot(self._spot_model, table)

    def __reduce__(self):
        if self._limit_override:
            return (_rebuild_spot, (self._spot_model, self._limit_override))
        return (Spot, (self._spot_model,))

    def __repr__(self) -> str:
        return "Spot()"


def _rebuild_spot(model, limits) -> Spot:
    spot = Spot.__new__(Spot)
    spot._build(model, limits)
    return spot
