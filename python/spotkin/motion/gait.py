"""Gaits: which feet are down when, for any quadruped, with numbers that scale with the robot.

A gait is a contact schedule: leg i's phase is frac(t / T + o_i) and the leg is in stance while the
phase is below the duty factor d (it lifts off at phase d and lands when the phase wraps to 0). The
offsets o_i are given per geometric role (``"front_left"``, ``"front_right"``, ``"hind_left"``,
``"hind_right"``: :attr:`spotkin.Robot.leg_roles`, from the hips' positions), never per joint name,
so a gait runs unchanged on any robot that :meth:`spotkin.Robot.from_urdf` recognises.
:meth:`Gait.resolve` turns a gait into numbers for one robot (:class:`ResolvedGait`); the plan
(:meth:`spotkin.Robot.plan_gait`) follows them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._support.boundary import as_scalar
from ..model.robot import Robot
from ..reference.gait import G, step_reach, sway_coefficients

__all__ = ["ROLES", "Gait", "ResolvedGait", "hip_height"]

ROLES = ("front_left", "front_right", "hind_left", "hind_right")
"""A quadruped's leg roles, the keys of a gait's offsets."""

REACH_FRACTION = 0.8
"""The nominal stance stretches each leg to this fraction of its reach (hip pitch to foot)."""
STEP_FRACTION = 0.15
"""The default step height, as a fraction of the nominal hip height h."""
ACCEL_FRACTION = 0.1
"""The body's acceleration limit, as a fraction of g (yaw: the same at the farthest nominal foot)."""
SWAY = (0.05, 0.45)
"""(kappa_x, kappa_y): the crawl's sway amplitudes, fractions of half the stance's length and width.
The fore-aft sway runs at twice the cycle's frequency: at 0.15 its acceleration (0.2 g on Spot) took
a walking Spot's hip-pitch motors to their 45 N m; at 0.05 they stay under 65 % of it in the
simulator, and the centre of mass still keeps 7 % of h inside the support triangle."""


def _walk_offsets(duty: float) -> dict[str, float]:
    """The lateral-sequence crawl: hind left, front left, (all four down), hind right, front right,
    (all four down). Swings of beta = 1 - d, gaps of g = (4 d - 3) / 2, the cycle starting in the
    middle of a gap (so that the plan starts with every foot down)."""
    beta = 1.0 - duty
    gap = max(0.0, (4.0 * duty - 3.0) / 2.0)
    starts = {
        "hind_left": 0.0,
        "front_left": beta,
        "hind_right": 2 * beta + gap,
        "front_right": 3 * beta + gap,
    }
    return {role: round((duty - (start + gap / 2.0)) % 1.0, 12) for role, start in starts.items()}


# name: (period factor c, T = c sqrt(h / g); duty; offsets by role; shift the body (crawl)); the step
# height is STEP_FRACTION h for all but "stand" (0)
PRESETS: dict[str, tuple] = {
    "stand": (2.5, 1.0, dict.fromkeys(ROLES, 0.0), False),
    "walk": (8.0, 0.85, _walk_offsets, True),
    "trot": (2.5, 0.6, {"front_left": 0.0, "front_right": 0.5, "hind_left": 0.5, "hind_right": 0.0}, False),
    "pace": (2.5, 0.6, {"front_left": 0.0, "front_right": 0.5, "hind_left": 0.0, "hind_right": 0.5}, False),
    "bound": (2.2, 0.4, {"front_left": 0.0, "front_right": 0.0, "hind_left": 0.5, "hind_right": 0.5}, False),
    "pronk": (2.2, 0.4, dict.fromkeys(ROLES, 0.0), False),
    "gallop": (2.0, 0.4, {"front_left": 0.5, "front_right": 0.6, "hind_left": 0.0, "hind_right": 0.1}, False),
}
"""The preset gaits (see :class:`Gait`)."""


def _optional(value, name: str, *, positive: bool = False, unit: bool = False, minimum=None):
    if value is None:
        return None
    if isinstance(value, bool):
        raise TypeError(f"{name} must be a real number, got a bool")
    number = as_scalar(value, name)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {number}")
    if positive and not number > 0.0:
        raise ValueError(f"{name} must be > 0, got {number}")
    if unit and not 0.0 < number < 1.0:
        raise ValueError(f"{name} must be in (0, 1) (the fraction of the cycle in stance), got {number}")
    if minimum is not None and number < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {number}")
    return number


class Gait:
    """A gait: a preset, or custom offsets and duty, with optional numbers; :meth:`resolve` fills in
    the rest for a robot.

    ``name``: one of :data:`PRESETS` or ``"custom"`` (then ``offsets`` and ``duty`` are required).
    Each preset: period factor c (T = c sqrt(h / g)), duty d, offsets (front_left, front_right,
    hind_left, hind_right), and whether the body sways (the crawl):

    - ``"stand"``: c 2.5, d 1, every foot down, the body still whatever the command (with a duty
      below 1 it steps in place);
    - ``"walk"``: c 8, d 0.85, offsets 0.6, 0.1, 0.75, 0.25 (hind left, front left, a four-foot gap,
      hind right, front right, a gap: the lateral-sequence static crawl), sways;
    - ``"trot"``: c 2.5, d 0.6, offsets 0, 0.5, 0.5, 0 (diagonals together);
    - ``"pace"``: c 2.5, d 0.6, offsets 0, 0.5, 0, 0.5 (sides together);
    - ``"bound"``: c 2.2, d 0.4, offsets 0, 0, 0.5, 0.5 (the front pair, then the hind pair);
    - ``"pronk"``: c 2.2, d 0.4, offsets 0, 0, 0, 0 (all together);
    - ``"gallop"``: c 2, d 0.4, offsets 0.5, 0.6, 0, 0.1 (transverse: hind right, hind left, front
      right, front left).

    The walk's offsets follow its duty d: swings of 1 - d, hind left then front left, a four-foot gap
    of (4 d - 3) / 2, hind right then front right, a gap; its duty must be above 0.75.

    Keyword numbers (None: from the robot, see :meth:`resolve`): ``period`` T (s); ``duty`` d in
    (0, 1); ``step_height`` (m, above the higher end of each swing); ``offsets`` a dict role -> phase
    offset (cycles), all four roles; ``height`` the body's height above the ground (m);
    ``capture_gain`` k of the capture-point term of the footholds (default 1); ``com_shift`` whether
    the body sways to keep the centre of mass over the support triangle (default: the walk's).

    ``ValueError`` for an unknown name (listing the presets), a period that is not finite and > 0, a
    duty outside (0, 1), offsets naming unknown roles or not all four, a negative step height;
    ``TypeError`` for a non-number.
    """

    __slots__ = ("_com_shift", "_duty", "_gain", "_height", "_name", "_offsets", "_period", "_step")

    def __init__(
        self,
        name: str = "trot",
        *,
        period: float | None = None,
        duty: float | None = None,
        step_height: float | None = None,
        offsets: Mapping[str, float] | None = None,
        height: float | None = None,
        capture_gain: float = 1.0,
        com_shift: bool | None = None,
    ) -> None:
        if not isinstance(name, str):
            raise TypeError(f"name must be a gait name (str), got {type(name).__name__}")
        if name not in PRESETS and name != "custom":
            raise ValueError(f"unknown gait {name!r}: the presets are {', '.join(PRESETS)} (or 'custom')")
        self._name = name
        self._period = _optional(period, "period", positive=True)
        self._duty = _optional(duty, "duty", unit=True)
        self._step = _optional(step_height, "step_height", minimum=0.0)
        self._height = _optional(height, "height", positive=True)
        if capture_gain is None:
            raise TypeError("capture_gain must be a real number >= 0, got None")
        self._gain = _optional(capture_gain, "capture_gain", minimum=0.0)
        if com_shift is not None and not isinstance(com_shift, (bool, np.bool_)):
            raise TypeError(f"com_shift must be a bool or None, got {type(com_shift).__name__}")
        self._com_shift = None if com_shift is None else bool(com_shift)
        self._offsets = None if offsets is None else _role_offsets(offsets)
        if name == "custom" and (self._offsets is None or self._duty is None):
            raise ValueError("a custom gait needs offsets (a dict role -> phase) and a duty")
        if name == "walk" and self._offsets is None and self._duty is not None and self._duty <= 0.75:
            raise ValueError(f"the walk (a static crawl) needs a duty above 0.75, got {self._duty}")

    @property
    def name(self) -> str:
        return self._name

    @property
    def period(self) -> float | None:
        """T (s), or None (from the robot)."""
        return self._period

    @property
    def duty(self) -> float:
        """d: the fraction of each cycle a foot is down (1 for ``"stand"``)."""
        return self._duty if self._duty is not None else float(PRESETS.get(self._name, PRESETS["trot"])[1])

    @property
    def offsets(self) -> dict[str, float]:
        """Phase offset per role (cycles, in [0, 1))."""
        if self._offsets is not None:
            return dict(self._offsets)
        offsets = PRESETS[self._name][2]
        return dict(offsets(self.duty) if callable(offsets) else offsets)

    @property
    def step_height(self) -> float | None:
        return self._step

    @property
    def height(self) -> float | None:
        return self._height

    @property
    def capture_gain(self) -> float:
        return self._gain

    @property
    def com_shift(self) -> bool:
        if self._com_shift is not None:
            return self._com_shift
        return bool(PRESETS.get(self._name, PRESETS["trot"])[3])

    def replace(self, **changes) -> Gait:
        """A copy with some of the keyword numbers changed."""
        values = {
            "period": self._period,
            "duty": self._duty,
            "step_height": self._step,
            "offsets": self._offsets,
            "height": self._height,
            "capture_gain": self._gain,
            "com_shift": self._com_shift,
        }
        values.update(changes)
        return Gait(self._name, **values)

    def resolve(self, robot) -> ResolvedGait:
        """The gait's numbers for ``robot`` (a quadruped: four legs with the four roles, else
        ``ValueError``). Defaults, with h the nominal hip height above the feet:

        - height: the body height at which the most stretched leg's hip pitch to foot distance is
          ``REACH_FRACTION`` (0.8) of its reach, feet straight below the hip pitch joints
          (:meth:`spotkin.Robot.stance_feet`); the stance is those feet;
        - period: T = c sqrt(h / g) (equal Froude numbers: robots of any size step alike), c per preset;
        - step height: ``STEP_FRACTION`` (0.15) h; body acceleration ``ACCEL_FRACTION`` (0.1) g, yaw
          acceleration the same at the farthest nominal foot;
        - the crawl's sway (:func:`spotkin.reference.gait.sway_coefficients`, amplitudes ``SWAY``) and
          the step reach (how far each foot can move from its nominal place along x and along y within
          the joint limits, by bisection on the IK status), from the nominal stance.
        """
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a spotkin.Robot, got {type(robot).__name__}")
        _check_quadruped(robot)
        roles = tuple(robot.leg_roles)
        legs, hips = robot.legs, robot.hip_positions
        height = self._height if self._height is not None else _nominal_height(robot)
        stance = robot.stance_feet(height)
        pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0])
        nominal = robot.body_ik(pose, stance)
        if (np.asarray(nominal.status) != 0).any():
            raise ValueError(
                f"the nominal stance at height {height:.4g} m is outside the legs' limits "
                f"(statuses {np.asarray(nominal.status).tolist()}): give Gait(..., height=...)"
            )
        ground = float(stance[:, 2].mean())
        hip_height = height + float(hips[:, 2].mean()) - ground  # hip_height(robot) at the default height
        factor = PRESETS.get(self._name, PRESETS["trot"])[0]
        period = self._period if self._period is not None else factor * math.sqrt(hip_height / G)
        duty = self.duty
        step = (
            self._step
            if self._step is not None
            else (0.0 if self._name == "stand" else STEP_FRACTION * hip_height)
        )
        offsets = self.offsets
        com = robot.center_of_mass(pose, nominal.q)
        reach = np.empty((4, 2))
        for i, leg in enumerate(legs):
            p_leg = stance[i] - pose[:3] - hips[i]
            limit = float(leg.reach[1])
            for axis in (0, 1):
                ways = [step_reach(leg, p_leg, sign * np.eye(3)[axis], limit) for sign in (1.0, -1.0)]
                reach[i, axis] = min(ways)
        radius = float(np.hypot(stance[:, 0], stance[:, 1]).max())
        offsets_array = np.array([offsets[role] for role in roles])
        sway, base = sway_coefficients(stance[:, :2], roles, offsets_array, com[:2], SWAY)
        return ResolvedGait(
            name=self._name,
            roles=roles,
            period=float(period),
            duty=float(duty),
            offsets=offsets_array,
            step_height=float(step),
            height=float(height),
            hip_height=float(hip_height),
            stance=stance,
            com_shift=1.0 if self.com_shift else 0.0,
            shift=base,
            sway=sway,
            capture_gain=float(self._gain),
            accel=ACCEL_FRACTION * G,
            yaw_accel=ACCEL_FRACTION * G / radius,
            step_reach=reach,
            moving=0.0 if self._name == "stand" else 1.0,
        )

    def __eq__(self, other) -> bool:
        return isinstance(other, Gait) and repr(self) == repr(other)

    def __hash__(self) -> int:
        return hash(repr(self))

    def __repr__(self) -> str:
        given = {
            "period": self._period,
            "duty": self._duty,
            "step_height": self._step,
            "offsets": self._offsets,
            "height": self._height,
            "com_shift": self._com_shift,
        }
        parts = [repr(self._name)] + [f"{k}={v!r}" for k, v in given.items() if v is not None]
        if self._gain != 1.0:
            parts.append(f"capture_gain={self._gain!r}")
        return f"Gait({', '.join(parts)})"


def _role_offsets(offsets) -> dict[str, float]:
    if not isinstance(offsets, Mapping):
        raise TypeError(f"offsets must be a dict role -> phase offset, got {type(offsets).__name__}")
    unknown = [key for key in offsets if key not in ROLES]
    if unknown:
        raise ValueError(f"offsets: unknown roles {unknown}; the roles are {ROLES} (never joint names)")
    missing = [role for role in ROLES if role not in offsets]
    if missing:
        raise ValueError(f"offsets must give all four roles, missing {missing}")
    return {role: _optional(offsets[role], f"offsets[{role!r}]") % 1.0 for role in ROLES}


def hip_height(robot) -> float:
    """h (m), the robot's nominal hip height: the hips' mean height above the foot points when the body
    stands at its default height (:meth:`Gait.resolve`: the most stretched leg's hip pitch to foot
    distance at ``REACH_FRACTION`` (0.8) of its reach, the feet straight below the hip-pitch joints).
    Spot 0.526 m, Go2 0.341 m.

    The one size and speed scale of walking ("0.5 h per second"): :attr:`ResolvedGait.hip_height` of
    a gait without its own height, the gait's period and step height, :func:`spotkin.sim.hip_height`
    and the simulator's starting stance all use it. ``ValueError`` unless ``robot`` is a quadruped."""
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a spotkin.Robot, got {type(robot).__name__}")
    _check_quadruped(robot)
    height = _nominal_height(robot)
    stance = robot.stance_feet(height)
    return height + float(robot.hip_positions[:, 2].mean()) - float(stance[:, 2].mean())


def _check_quadruped(robot) -> None:
    roles = tuple(robot.leg_roles)
    if robot.n_legs != 4 or sorted(roles) != sorted(ROLES):
        raise ValueError(
            f"gaits are for quadrupeds with legs {ROLES}; this robot has {robot.n_legs} legs {roles}"
        )


def _nominal_height(robot) -> float:
    """The default body height (see :meth:`Gait.resolve`)."""
    hips = robot.hip_positions
    bodies = [REACH_FRACTION * leg.reach[1] - hips[k, 2] - leg.a[2] for k, leg in enumerate(robot.legs)]
    guess = min(bodies)
    foot = float(robot.stance_feet(guess)[:, 2].mean())  # the foot point above the ground (a sphere's radius)
    return guess + foot


@dataclass(frozen=True, eq=False)
class ResolvedGait:
    """A gait's numbers for one robot (from :meth:`Gait.resolve`); arrays in the robot's leg order."""

    name: str
    roles: tuple[str, ...]
    """Each leg's role."""
    period: float
    """T (s)."""
    duty: float
    """d."""
    offsets: np.ndarray
    """(4,) phase offsets, cycles."""
    step_height: float
    """m, above the higher end of a swing."""
    height: float
    """The body origin's height above the ground, m."""
    hip_height: float
    """h: the hips' mean height above the feet points, m (the speed scale)."""
    stance: np.ndarray
    """(4, 3) the nominal feet, world, for the body at [0, 0, height, 0, 0, 0]."""
    com_shift: float
    """1: the body sways to keep the centre of mass over the support triangle (the crawl); 0: not."""
    shift: np.ndarray
    """(2,) s0: the body-frame offset that puts the nominal centre of mass over the crossing of the
    stance's diagonals (applied with the sway)."""
    sway: np.ndarray
    """(4, 2) (X_i, Y_i): each leg's fore-aft and lateral sway terms (see
    :func:`spotkin.reference.gait.sway_coefficients`)."""
    capture_gain: float
    """k."""
    accel: float
    """The body's acceleration limit, m/s^2 (forward and sideways each)."""
    yaw_accel: float
    """rad/s^2."""
    step_reach: np.ndarray
    """(4, 2) how far each foot can move from its nominal point along x and along y (the lesser of the
    two ways), within the joint limits, m."""
    moving: float
    """0 for ``"stand"`` (the body holds still whatever the command), else 1."""
