"""Whole-body reach: bring the hand of a legged robot's arm to a target by moving the body and the
arm together, the feet fixed. The method is in :mod:`spotkin.reference.reach` (letters (S) ... (F));
this module resolves the problem's numbers and runs the search over a batch of targets."""

from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np

from .. import _core
from .._support.boundary import as_real, broadcast_lead, check_trailing
from ..model import robot as robot_module
from ..model.arm import SpotArm
from ..model.body import body_transform
from ..reference import reach as ref
from ..reference.reach_geometry import stance_frame
from .capsules import capsule_model
from .gait import _nominal_height

__all__ = ["ReachBox", "ReachResult", "ReachStatus", "default_box", "reach"]


class ReachStatus(IntEnum):
    """One reach's outcome."""

    OK = ref.OK
    """The hand is at the target exactly, and every constraint holds."""
    UNREACHABLE = ref.UNREACHABLE
    """No body pose in the box brings the hand there with every joint in its limits and no collision:
    the answer is the nearest pose reached (``distance``, ``angle`` say how far)."""
    UNSTABLE = ref.UNSTABLE
    """The hand reaches the target only with the centre of mass closer to the support polygon's edge
    than ``margin`` (or outside it): the answer is the reaching pose with the largest margin."""
    INVALID_INPUT = ref.INVALID_INPUT
    """NaN or Inf, or a target that is not a rigid transform: NaN answers."""


class ReachBox(NamedTuple):
    """The body pose's bounds, as offsets from the nominal pose in the stance frame: ``lower`` and
    ``upper`` (6,) = [x, y, z (m), roll, pitch, yaw (rad)] (Euler "XYZ")."""

    lower: np.ndarray
    upper: np.ndarray


BOX_FRACTIONS = ((-0.25, 0.25), (-0.15, 0.15), (-0.3, 0.1))
"""The default box's x, y and z offsets as fractions of the hip height."""
BOX_ANGLES = ((-0.3, 0.3), (-0.4, 0.4), (-0.4, 0.4))
"""The default box's roll, pitch and yaw offsets (rad)."""
MARGIN_FRACTION = 0.05
"""The default support margin as a fraction of the hip height (Spot: 2.6 cm)."""


def default_box(robot) -> ReachBox:
    """The default :class:`ReachBox` of ``robot``: ``BOX_FRACTIONS`` of its hip height in x, y, z and
    ``BOX_ANGLES`` in roll, pitch, yaw."""
    L = _scales(robot)[1]
    lower = np.array([f[0] * L for f in BOX_FRACTIONS] + [a[0] for a in BOX_ANGLES])
    upper = np.array([f[1] * L for f in BOX_FRACTIONS] + [a[1] for a in BOX_ANGLES])
    return ReachBox(lower, upper)


class _Numbers:
    """A robot's reach numbers, made on first use and kept on the robot: its scales, its arm's chain from
    the body and capsules, and a compiled model per box."""

    def __init__(self, robot) -> None:
        self.h0 = _nominal_height(robot)
        self.feet = robot.stance_feet(self.h0)
        self.L = self.h0 + float(robot.hip_positions[:, 2].mean()) - float(self.feet[:, 2].mean())
        specs = robot._specs[1] if robot.model is not None else ()
        self.chain = robot.chain(specs[0].tip) if specs else None
        self.capsules = None if self.chain is None else capsule_model(robot, self.chain)
        self.models: dict = {}
        self.single = None  # reach's arrays for one target with the defaults (set on first use)
        self.stance = stance_frames(self.feet[None], self.feet)[0]  # the nominal feet's stance frame


def _numbers(robot) -> _Numbers:
    numbers = getattr(robot, "_reach_core", None)
    if numbers is None:
        numbers = _Numbers(robot)
        robot._reach_core = numbers
    return numbers


def _scales(robot) -> tuple[float, float, np.ndarray]:
    """(h0 the nominal body height, L the hip height above the feet, the nominal feet (n, 3))."""
    numbers = _numbers(robot)
    return numbers.h0, numbers.L, numbers.feet.copy()


class ReachResult(NamedTuple):
    """What :meth:`spotkin.Robot.reach` gives, per target."""

    body_pose: np.ndarray
    """(..., 6) [x, y, z, a, b, c] in the world, Euler "XYZ"."""
    q: np.ndarray
    """(..., 3 n_legs + n_arm): the legs' joints (:attr:`spotkin.Robot.leg_joint_names`), then the arm's."""
    status: np.ndarray
    """(...,) int8 :class:`ReachStatus` (a :class:`ReachStatus` for one target)."""
    margin: np.ndarray
    """(...,) m: the support margin of the centre of mass (positive inside the feet's polygon)."""
    distance: np.ndarray
    """(...,) m: the hand's distance from the target (0 unless UNREACHABLE)."""
    angle: np.ndarray
    """(...,) rad: the hand's rotation from the target (0 unless UNREACHABLE)."""
    arm_branches: np.ndarray
    """(..., 8, n_arm): every solution of the arm's closed form at the chosen body pose, NaN where none."""
    arm_valid: np.ndarray
    """(..., 8) bool: which of ``arm_branches`` exist within the arm's limits."""
    arm_branch: np.ndarray
    """(...,) int: the branch chosen (-1 for none: UNREACHABLE, INVALID_INPUT)."""


def reference_problem(robot, target, feet=None, seed=None, margin=None, box=None) -> ref.Problem:
    """The :class:`spotkin.reference.reach.Problem` of one target, with the defaults of
    :meth:`spotkin.Robot.reach`; ``seed`` a (body_pose (6,), q) pair."""
    h0, L, nominal_feet = _scales(robot)
    feet = nominal_feet if feet is None else np.asarray(feet, float)
    box = default_box(robot) if box is None else box
    margin = MARGIN_FRACTION * L if margin is None else float(margin)
    stance = stance_frame(feet, nominal_feet)
    nominal = np.array([0.0, 0.0, h0, 0.0, 0.0, 0.0])
    limits = robot.limits
    seed_pose = seed_q = None
    if seed is not None:
        pose, seed_q = seed
        T = np.linalg.solve(stance, ref.body_transform(np.asarray(pose, float)))
        seed_pose, seed_q = ref.pose_of(T), np.asarray(seed_q, float)
    chain = _arm_chain(robot)
    return ref.Problem(
        robot=robot,
        arm=robot.arm,
        chain=chain,
        capsules=_capsules(robot),
        mount=robot.arm_mount,
        target=np.asarray(target, float),
        feet=feet,
        stance=stance,
        nominal=nominal,
        lower=nominal + box[0],
        upper=nominal + box[1],
        margin=margin,
        scale=L,
        q_lower=limits[:, 0],
        q_upper=limits[:, 1],
        seed_pose=seed_pose,
        seed_q=seed_q,
    )


def _arm_chain(robot):
    return _numbers(robot).chain


def _capsules(robot):
    return _numbers(robot).capsules


def _compiled(robot, box: ReachBox):
    """The robot's compiled reach model for ``box`` (made once per box)."""
    numbers = _numbers(robot)
    key = (tuple(box[0]), tuple(box[1]))
    model = numbers.models.get(key)
    if model is None:
        if numbers.chain is None:
            raise ValueError("reach needs the robot's description (a URDF) for its arm's chain and capsules")
        arm = robot.arm
        arm_core = arm._arm if isinstance(arm, SpotArm) else arm._ik_core()  # the solver its ik runs
        caps = numbers.capsules
        capsules = (
            None
            if caps is None or not caps.arm_points
            else (
                caps.radius,
                caps.box_centre,
                caps.box_half,
                np.array(caps.arm_points, float),
                caps.arm_vs_body.astype(float),
                caps.arm_vs_legs.astype(float),
            )
        )
        nominal = np.array([0.0, 0.0, numbers.h0, 0.0, 0.0, 0.0])
        limits = robot.limits
        model = _core.ReachModel(
            robot._statics,
            arm_core,
            numbers.chain._core,
            robot.arm_mount,
            capsules,
            nominal,
            nominal + box[0],
            nominal + box[1],
            numbers.L,
            limits[:, 0],
            limits[:, 1],
            ref.candidate_units(),
            ref.REFINE_STEPS,
        )
        numbers.models[key] = model
    return model


def stance_frames(feet: np.ndarray, nominal_feet: np.ndarray) -> np.ndarray:
    """Row-wise :func:`spotkin.reference.reach_geometry.stance_frame`: (N, n, 3) feet -> (N, 4, 4)."""
    cf, c0 = feet.mean(axis=1), nominal_feet.mean(axis=0)
    u, v = nominal_feet - c0, feet - cf[:, None, :]
    cross = (u[:, 0] * v[..., 1] - u[:, 1] * v[..., 0]).sum(-1)
    dot = (u[:, 0] * v[..., 0] + u[:, 1] * v[..., 1]).sum(-1)
    psi = np.arctan2(cross, dot)
    c, s = np.cos(psi), np.sin(psi)
    T = np.zeros((len(feet), 4, 4))
    T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = c, -s, s, c
    T[:, 2, 2] = T[:, 3, 3] = 1.0
    T[:, 0, 3] = cf[:, 0] - (c * c0[0] - s * c0[1])
    T[:, 1, 3] = cf[:, 1] - (s * c0[0] + c * c0[1])
    T[:, 2, 3] = cf[:, 2] - c0[2]
    return T


def _as_box(box, robot) -> ReachBox:
    if box is None:
        return default_box(robot)
    rows = as_real(box, "box", np.float64)
    if rows.shape != (2, 6):
        raise ValueError(
            "box must be a ReachBox or a (2, 6) array [lower; upper] of [x, y, z, roll, pitch, yaw] "
            f"offsets, got shape {rows.shape}"
        )
    if not np.isfinite(rows).all() or (rows[0] > rows[1]).any():
        raise ValueError(f"box must be finite with lower <= upper, got {rows.tolist()}")
    return ReachBox(rows[0].copy(), rows[1].copy())


def _seed_parts(seed):
    """(body_pose, q) of a seed: a ReachResult or a (body_pose, q) pair."""
    if seed is None:
        return None, None
    if isinstance(seed, ReachResult):
        return seed.body_pose, seed.q
    if isinstance(seed, (tuple, list)) and len(seed) == 2:
        return seed
    raise TypeError(f"seed must be a ReachResult or a (body_pose, q) pair, got {type(seed).__name__}")


def reach(robot, T_hand_world, feet=None, seed=None, margin=None, box=None) -> ReachResult:
    """:meth:`spotkin.Robot.reach` (documented there)."""
    if (
        type(T_hand_world) is np.ndarray
        and T_hand_world.shape == (4, 4)
        and T_hand_world.dtype == np.float64
        and feet is None
        and seed is None
        and margin is None
        and box is None
    ):
        fast = _numbers(robot).single  # one target with the defaults: the other arrays are made once
        if fast is not None:
            model, feet1, stance1, p_ref1, q_ref1, margin1 = fast
            pose, q, status, margins, distance, angle, branches, valid, slot = model.solve(
                T_hand_world.reshape(1, 4, 4), feet1, stance1, p_ref1, q_ref1, None, margin1
            )
            return ReachResult(
                pose[0],
                q[0],
                ReachStatus(int(status[0])),
                float(margins[0]),
                float(distance[0]),
                float(angle[0]),
                branches[0],
                valid[0],
                int(slot[0]),
            )
    arm = robot.arm
    if arm is None:
        raise ValueError("reach needs an arm: this robot has none (robot.arm is None)")
    if arm.dof != 6:
        raise ValueError(f"reach solves 6-joint arms in closed form; this arm has {arm.dof} joints")
    target = as_real(T_hand_world, "T_hand_world")
    leads = {"T_hand_world": (check_trailing(target, "T_hand_world", (4, 4)), target.shape)}
    n = robot.n_legs
    L, nominal_feet = _scales(robot)[1:]
    if feet is not None:
        feet = as_real(feet, "feet", np.float64)
        leads["feet"] = (check_trailing(feet, "feet", (n, 3)), feet.shape)
    seed_pose, seed_q = _seed_parts(seed)
    m = 3 * n + arm.dof
    if seed_pose is not None:
        seed_pose = as_real(seed_pose, "seed body_pose", np.float64)
        seed_q = as_real(seed_q, "seed q", np.float64)
        leads["seed body_pose"] = (check_trailing(seed_pose, "seed body_pose", (6,)), seed_pose.shape)
        leads["seed q"] = (check_trailing(seed_q, "seed q", (m,)), seed_q.shape)
    if margin is not None:
        margin = as_real(margin, "margin", np.float64)
        leads["margin"] = (margin.shape, margin.shape)
    box = _as_box(box, robot)
    lead = broadcast_lead(**leads)
    N = math.prod(lead)
    model = _compiled(robot, box)
    flat_target = np.ascontiguousarray(np.broadcast_to(target, (*lead, 4, 4)).reshape(N, 4, 4), np.float64)
    flat_feet = np.ascontiguousarray(
        np.broadcast_to(nominal_feet if feet is None else feet, (*lead, n, 3)).reshape(N, n, 3)
    )
    flat_margin = np.ascontiguousarray(
        np.broadcast_to(MARGIN_FRACTION * L if margin is None else margin, lead).reshape(N), np.float64
    )
    if feet is None:  # every target's stance frame is the nominal stance's
        stance = np.ascontiguousarray(np.broadcast_to(_numbers(robot).stance, (N, 4, 4)))
    else:
        with np.errstate(invalid="ignore"):  # NaN feet: NaN stance frames (the core answers INVALID_INPUT)
            stance = stance_frames(flat_feet, nominal_feet)
    h0 = _numbers(robot).h0
    if seed_pose is None:
        limits = robot.limits
        finite = np.isfinite(limits).all(axis=1)
        p_ref = np.broadcast_to(np.array([0.0, 0.0, h0, 0.0, 0.0, 0.0]), (N, 6))
        q_ref = np.broadcast_to(np.where(finite, 0.5 * (limits[:, 0] + limits[:, 1]), 0.0), (N, m))
        seed_in_stance = None
    else:
        seed_pose = np.broadcast_to(seed_pose, (*lead, 6)).reshape(N, 6)
        q_ref = np.broadcast_to(seed_q, (*lead, m)).reshape(N, m)
        with np.errstate(invalid="ignore"):
            local = np.linalg.solve(
                np.where(np.isfinite(stance), stance, np.eye(4)), body_transform(seed_pose)
            )
        p_ref = seed_in_stance = np.where(
            np.isfinite(stance).all(axis=(1, 2))[:, None], poses_of(local), np.nan
        )
    p_ref, q_ref = np.ascontiguousarray(p_ref), np.ascontiguousarray(q_ref)
    pose, q, status, margins, distance, angle, branches, valid, slot = model.solve(
        flat_target, flat_feet, stance, p_ref, q_ref, seed_in_stance, flat_margin
    )
    numbers = _numbers(robot)
    defaults = N == 1 and feet is None and seed_in_stance is None and margin is None
    if numbers.single is None and defaults and np.array_equal(np.array(box), np.array(default_box(robot))):
        numbers.single = (model, flat_feet, stance, p_ref, q_ref, flat_margin)
    dtype = np.float32 if target.dtype == np.float32 else np.float64
    body_pose = pose.reshape(*lead, 6).astype(dtype, copy=False)
    q = q.reshape(*lead, m).astype(dtype, copy=False)
    branches = branches.reshape(*lead, 8, arm.dof).astype(dtype, copy=False)
    arm_valid = valid.reshape(*lead, 8)
    if lead == ():
        return ReachResult(
            body_pose,
            q,
            ReachStatus(int(status[0])),
            float(margins[0]),
            float(distance[0]),
            float(angle[0]),
            branches,
            arm_valid,
            int(slot[0]),
        )
    return ReachResult(
        body_pose,
        q,
        status.reshape(lead),
        margins.reshape(lead).astype(dtype, copy=False),
        distance.reshape(lead).astype(dtype, copy=False),
        angle.reshape(lead).astype(dtype, copy=False),
        branches,
        arm_valid,
        slot.reshape(lead),
    )


def poses_of(T) -> np.ndarray:
    """Row-wise :func:`spotkin.reference.reach.pose_of`: [x, y, z, a, b, c] (Euler "XYZ") of (N, 4, 4)."""
    R = T[:, :3, :3]
    b = np.arcsin(np.clip(R[:, 0, 2], -1.0, 1.0))
    a = np.arctan2(-R[:, 1, 2], R[:, 2, 2])
    c = np.arctan2(-R[:, 0, 1], R[:, 0, 0])
    return np.concatenate([T[:, :3, 3], np.stack([a, b, c], -1)], -1)


robot_module._MOTION["reach"] = reach
