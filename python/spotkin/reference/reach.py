"""The reference whole-body reach: a hand target for a legged robot's arm, the feet fixed, one
target at a time. Slow and obvious on purpose; the batched search (:mod:`spotkin.motion.reach`)
mirrors it step by step, and the tests compare them.

It composes the robot's own closed forms (``robot.body_ik``, the arm's ``ik_all``, its ``fk``,
``robot.center_of_mass``), each checked against its own reference elsewhere; the search is written
here in plain Python.

The problem
-----------
Unknowns: the body pose and the arm's joints; the legs follow from the body pose by the leg IK (the
feet fixed). A body pose is given by its offset p = [x, y, z, a, b, c] (Euler "XYZ") in the stance
frame S:

(S) the stance frame: world <- S = Trans(t_x, t_y, dz) Rz(psi), the planar rigid motion (2-D
    Procrustes) that best carries the nominal stance's feet F0 (``robot.stance_feet`` at the nominal
    height h0, the body at [0, 0, h0, 0, 0, 0]) onto the given feet f, in x and y:
    psi = atan2(sum (u_i x v_i), sum (u_i . v_i)) with u_i = F0_i - mean F0, v_i = f_i - mean f
    (horizontal parts), t = mean f - Rz(psi) mean F0, dz = mean f_z - mean F0_z. The nominal body
    pose is p0 = [0, 0, h0, 0, 0, 0]; world <- body = (world <- S) T(p).
(B) the box: lower <= p - p0 <= upper (documented defaults in :mod:`spotkin.motion.reach`).

A body pose p with arm solution q_a (a branch of the arm's closed form) is **feasible** when every leg's
IK is OK (reachable, within its limits), q_a is within the arm's limits, no arm capsule collides with
the body box or a leg capsule (:mod:`spotkin.motion.capsules`: segment distance < 2 r to a leg
capsule, < r to the box) or the ground (an end of the capsule's segment lower than r above the
horizontal plane through the lowest foot point), and the support margin (M) of the centre of mass
(arm included) is at least ``margin``: the signed distance of its horizontal projection to the
convex hull of the feet.
It **reaches** when all of that but the margin holds.

(G) The objective, least squares: cost = |r|^2 / 2 with r = [(p - p_ref) / w_p, wrap(q - q_ref) / w_q],
    w_p the box's half-widths, w_q the joints' half-ranges (pi where unlimited), q the whole-body
    joints (legs, then arm). Without a seed, p_ref = p0 and q_ref the middle of each joint's range
    (0 where unlimited): comfort, away from the limits and near the nominal pose. With a seed, its
    body pose and joints: the feasible answer nearest to it.

The search
----------
(C) Candidates, in three stages: the seed's pose (clipped into the box) when there is one and p0;
    then the first 8 points of the Halton sequence (bases 2, 3, 5, 7, 11, 13, indices 1..) mapped
    into the box; then the rest, up to ``CANDIDATES``. A stage is evaluated only when the options of
    the stages before have no feasible one.
(E) At each candidate: the legs' IK (without a seed: each leg's preferred branch), the arm's target
    in the arm's base frame, (world <- body <- arm base)^-1 T_target, and every branch of the arm's
    IK; each valid branch is an option, with its margin, collision and cost.
(A) The answer: the feasible option of least cost among the stages evaluated (ties to the earlier
    candidate, then the lower branch); if none after the last stage, the reaching option of largest
    margin (status UNSTABLE); if none, the repair (F).
(R) Refinement: ``REFINE_STEPS`` Gauss-Newton steps on p for r(p), the arm following its branch (the
    valid solution nearest the current one) and the legs seeded with the current ones. J = dr/dp from
    the joints' sensitivities dq/dp, the feet and the hand held (:func:`sensitivities`: the legs' and the
    arm's Jacobians); delta = -(J^T J + mu I)^-1 J^T r, mu = ``GN_DAMPING``; the step is
    tried at 1, 1/2, 1/4 of its length (p clipped into the box) and taken when the option there is
    feasible and cheaper; else refinement stops.
(F) Repair, when no candidate reaches: damped least squares on z = (p, q_a) for the hand's pose error
    e = [p_target - p_hand; L log(R_target R_hand^T)] (world axes, L the hip height scale), from each
    of ``REPAIR_STARTS`` starts (:func:`repair_starts`: the nominal pose with the arm at zero, then the
    candidates' branches that exist outside the arm's limits, least violation first, then Halton arm
    postures). A step: J = d hand / dz by forward differences; the primary task's damped inverse
    J+ = J^T (J J^T + lambda^2 I)^-1, and the body drawn towards p0 in its null space,
    delta = J+ e + (I - J+ J) g, g = ``NULL_GAIN`` (p0 - p, 0); a variable on its bound that delta
    pushes out is held there (its column zeroed, up to ``ACTIVE_SET_PASSES`` passes); z + delta is
    clipped into the box and the arm's limits (``REPAIR_INSET`` inside them), and taken when every leg's
    IK there is OK and |e| decreases (lambda / 3), else refused (lambda x 3). At most
    ``REPAIR_ITERATIONS`` steps, until |e| < 1e-12 or lambda > ``REPAIR_STALL``; every
    ``REPAIR_CHECK`` steps, (E) at the body pose reached, and the start stops there when an option
    is feasible. The starts run in order, each ending with (E) at its body pose, until (A) over the
    ends' options finds a feasible one: the answer (refined by (R)); else a reaching one is UNSTABLE.
    Otherwise UNREACHABLE, the answer the end nearest the target (ties to the earlier start) with the
    legs' IK there, ``distance`` its position error (m) and ``angle`` its rotation error (rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .body import body_transform
from .gait import support_margin
from .reach_geometry import (
    euler_rates,
    halton,
    leg_segments,
    pose_of,
    rigid,
    rotation_log,
    segment_box_distance,
    segment_distance,
    wrap,
)

CANDIDATES = 64
"""Halton points in the box, after the seed's pose and the nominal one."""
STAGES = (0, 8)
"""(C)'s stages: the seed's and the nominal pose; then the first 8 Halton points; then the rest."""
REFINE_STEPS = 2
FD_STEP = 1e-6
GN_DAMPING = 1e-6
REPAIR_ITERATIONS = 60
REPAIR_DAMPING = 1e-2
REPAIR_STALL = 1e4
REPAIR_CHECK = 5
"""(F) tries the closed form at its body pose every this many iterations, and stops when it answers."""
"""(F) stops when its damping has grown past this (no step has helped for several tries)."""
REPAIR_STARTS = 6
ACTIVE_SET_PASSES = 3
REPAIR_INSET = 1e-6
"""(F) keeps the arm this far (rad) inside its limits, so that the closed form's answer is within them."""
NULL_GAIN = 0.2
"""(F)'s secondary task: the body's step towards the nominal pose, in the arm's null space."""

OK, UNREACHABLE, UNSTABLE, INVALID_INPUT = 0, 1, 2, 3
_LEG_OK = 0
_PRIMES = (2, 3, 5, 7, 11, 13)


# -- geometry ------------------------------------------------------------------------------------
def candidate_units(count: int = CANDIDATES) -> np.ndarray:
    """(count, 6) Halton points in [0, 1)^6, indices 1..count."""
    return np.array([[halton(k, b) for b in _PRIMES] for k in range(1, count + 1)]).reshape(count, 6)


def collides(problem, q, T_body) -> bool:
    """Whether an arm capsule hits the body box or a leg capsule (in the body frame), or the ground: the
    horizontal plane through the lowest foot point (world <- body ``T_body``)."""
    model = problem.capsules
    if model is None or not model.arm_points:
        return False
    n3 = 3 * problem.robot.n_legs
    frames = problem.chain.frames(q[n3:])[:, :3, 3]
    legs = leg_segments(problem.robot, q[:n3])
    r = model.radius
    T_body = np.asarray(T_body, float)
    heights = frames @ T_body[2, :3] + T_body[2, 3]  # each frame origin's height in the world
    ground = float(np.min(problem.feet[:, 2]))
    for k in range(len(model.arm_points) - 1):
        a, b = frames[model.arm_points[k]], frames[model.arm_points[k + 1]]
        if min(heights[model.arm_points[k]], heights[model.arm_points[k + 1]]) < ground + r:
            return True
        if model.arm_vs_body[k] and segment_box_distance(a, b, model.box_centre, model.box_half) < r:
            return True
        for i, (hip_pitch, knee, foot) in enumerate(legs):
            if model.arm_vs_legs[k, i, 0] and segment_distance(a, b, hip_pitch, knee) < 2.0 * r:
                return True
            if model.arm_vs_legs[k, i, 1] and segment_distance(a, b, knee, foot) < 2.0 * r:
                return True
    return False


# -- the problem ---------------------------------------------------------------------------------
@dataclass
class Problem:
    """Everything one reach needs, resolved (the batched search builds the same numbers)."""

    robot: object
    arm: object  # the arm's solver: ik_all, fk, limits (in the arm's base frame)
    chain: object  # the arm's chain from the body (for the capsules), or None
    capsules: object  # a spotkin.motion.capsules.CapsuleModel, or None
    mount: np.ndarray  # (4, 4) body <- arm base
    target: np.ndarray  # (4, 4) world <- hand target
    feet: np.ndarray  # (n, 3) world
    stance: np.ndarray  # (4, 4) world <- S
    nominal: np.ndarray  # (6,) p0
    lower: np.ndarray  # (6,) box, absolute in S
    upper: np.ndarray
    margin: float
    scale: float  # L (m): the hip height, the rotation error's weight in (F)
    q_lower: np.ndarray  # (3 n + 6,) whole-body limits
    q_upper: np.ndarray
    seed_pose: np.ndarray | None = None  # (6,) in S
    seed_q: np.ndarray | None = None  # (3 n + 6,)

    @property
    def widths(self) -> tuple[np.ndarray, np.ndarray]:
        w_p = 0.5 * (self.upper - self.lower)
        finite = np.isfinite(self.q_lower) & np.isfinite(self.q_upper)
        w_q = np.where(finite, 0.5 * (self.q_upper - self.q_lower), math.pi)
        return np.where(w_p > 0.0, w_p, 1.0), np.where(w_q > 0.0, w_q, 1.0)

    @property
    def reference(self) -> tuple[np.ndarray, np.ndarray]:
        if self.seed_q is not None:
            return self.seed_pose, self.seed_q
        finite = np.isfinite(self.q_lower) & np.isfinite(self.q_upper)
        return self.nominal, np.where(finite, 0.5 * (self.q_lower + self.q_upper), 0.0)


@dataclass
class Option:
    p: np.ndarray  # (6,) body pose in S
    q: np.ndarray  # (3 n + 6,)
    slot: int
    margin: float
    collides: bool
    cost: float
    order: int  # candidate index (ties)

    def feasible(self, problem: Problem) -> bool:
        return not self.collides and self.margin >= problem.margin


def residual(problem: Problem, p, q) -> np.ndarray:
    """(G): r = [(p - p_ref) / w_p, wrap(q - q_ref) / w_q]."""
    w_p, w_q = problem.widths
    p_ref, q_ref = problem.reference
    return np.concatenate([(np.asarray(p) - p_ref) / w_p, wrap(np.asarray(q) - q_ref) / w_q])


def body_T(problem: Problem, p) -> np.ndarray:
    return problem.stance @ body_transform(np.asarray(p, float))


def arm_target(problem: Problem, T_body) -> np.ndarray:
    """The hand target in the arm's base frame: (world <- body <- arm base)^-1 T_target."""
    base = T_body @ problem.mount
    R, t = base[:3, :3], base[:3, 3]
    out = np.eye(4)
    out[:3, :3] = R.T @ problem.target[:3, :3]
    out[:3, 3] = R.T @ (problem.target[:3, 3] - t)
    return out


def _legs(problem: Problem, T_body, seed=None):
    sol = problem.robot.body_ik(T_body, problem.feet, seed=seed)
    return np.asarray(sol.q, float), bool((np.asarray(sol.status) == _LEG_OK).all())


def _option(problem: Problem, p, T_body, q_legs, q_arm, slot: int, order: int) -> Option:
    q = np.concatenate([q_legs, q_arm])
    com = np.asarray(problem.robot.center_of_mass(T_body, q), float)
    margin = support_margin(problem.feet[:, :2], com[:2])
    r = residual(problem, p, q)
    hit = collides(problem, q, T_body)
    return Option(np.array(p, float), q, slot, margin, hit, 0.5 * float(r @ r), order)


def evaluate(problem: Problem, p, order: int = 0, misses: list | None = None) -> list[Option]:
    """(E): every valid branch at the body pose p (in S) as an option; [] when a leg fails. Into
    ``misses``, each branch that exists outside the arm's limits: (violation, order, slot, p, q_a)."""
    T_body = body_T(problem, p)
    q_legs, legs_ok = _legs(problem, T_body)
    if not legs_ok:
        return []
    sols = problem.arm.ik_all(arm_target(problem, T_body))
    q_all, valid = np.asarray(sols.q, float), np.asarray(sols.valid)
    if misses is not None:
        exists = np.asarray(sols.exists)
        for k in range(len(valid)):
            if exists[k] and not valid[k]:
                misses.append((violation(problem, q_all[k]), order, k, np.array(p, float), q_all[k]))
    return [_option(problem, p, T_body, q_legs, q_all[k], k, order) for k in range(len(valid)) if valid[k]]


def violation(problem: Problem, q_arm) -> float:
    """How far (rad) the arm's joints are outside their limits, summed."""
    lo, hi = problem.q_lower[-6:], problem.q_upper[-6:]
    return float(np.sum(np.maximum(lo - q_arm, 0.0) + np.maximum(q_arm - hi, 0.0)))


def _nearest_valid(q_all, valid, q_now) -> int:
    """The valid slot nearest to q_now: the smallest largest-single-joint move (on the circle), ties
    to the lower slot; -1 when none is valid."""
    best, best_slot = math.inf, -1
    for k in range(len(valid)):
        if valid[k]:
            move = float(np.max(np.abs(wrap(q_all[k] - q_now))))
            if move < best:
                best, best_slot = move, k
    return best_slot


def follow(problem: Problem, p, option: Option) -> Option | None:
    """The option at p on the branch of ``option`` (legs seeded by its legs), or None where a leg or
    the arm fails."""
    n3 = 3 * problem.robot.n_legs
    T_body = body_T(problem, p)
    q_legs, legs_ok = _legs(problem, T_body, seed=option.q[:n3])
    if not legs_ok:
        return None
    sols = problem.arm.ik_all(arm_target(problem, T_body))
    q_all, valid = np.asarray(sols.q, float), np.asarray(sols.valid)
    slot = _nearest_valid(q_all, valid, option.q[n3:])
    if slot < 0:
        return None
    return _option(problem, p, T_body, q_legs, q_all[slot], slot, option.order)


def sensitivities(problem: Problem, option: Option) -> np.ndarray | None:
    """dq/dp (m, 6) at an option, the feet and the hand held (R). In the stance frame S, with the body
    at (t, R) moving at v = t' and w = E (a', b', c') (:func:`euler_rates`):

    - leg l, its foot f_l fixed: J_l q_l' = -R^T (v + w x (f_l - t)) (J_l its Jacobian, body axes);
    - the arm, its hand on the fixed target (p_t, R_t): J_a q_a' = [-R^T (v + w x (p_t - t)); -R^T w],
      J_a the geometric Jacobian of its chain from the body (the hand point, body axes).

    None where a Jacobian is singular."""
    robot, n3 = problem.robot, 3 * problem.robot.n_legs
    inverse = np.linalg.inv(problem.stance)
    feet = problem.feet @ inverse[:3, :3].T + inverse[:3, 3]
    target = inverse @ problem.target
    T = body_transform(option.p)
    R, t = T[:3, :3], T[:3, 3]
    E = euler_rates(option.p[3:])
    v, w = np.hstack([np.eye(3), np.zeros((3, 3))]), np.hstack([np.zeros((3, 3)), E])  # (3, 6) each
    out = np.empty((len(option.q), 6))
    try:
        for columns, leg, foot in zip(robot.leg_columns, robot.legs, feet):
            J = np.asarray(leg.jacobian(option.q[columns]), float)
            out[columns] = np.linalg.solve(J, -R.T @ (v + np.cross(w.T, foot - t).T))
        J = np.asarray(problem.chain.jacobian(option.q[n3:]), float)
        rhs = np.vstack([-R.T @ (v + np.cross(w.T, target[:3, 3] - t).T), -R.T @ w])
        out[n3:] = np.linalg.solve(J, rhs)
    except np.linalg.LinAlgError:
        return None
    return out


def refine(problem: Problem, option: Option) -> Option:
    """(R): Gauss-Newton steps on p."""
    w_p, w_q = problem.widths
    for _ in range(REFINE_STEPS):
        r0 = residual(problem, option.p, option.q)
        dq = sensitivities(problem, option)
        if dq is None:
            return option
        J = np.vstack([np.diag(1.0 / w_p), dq / w_q[:, None]])
        delta = np.linalg.solve(J.T @ J + GN_DAMPING * np.eye(6), -(J.T @ r0))
        for alpha in (1.0, 0.5, 0.25):
            p_new = np.clip(option.p + alpha * delta, problem.lower, problem.upper)
            moved = follow(problem, p_new, option)
            if moved is not None and moved.feasible(problem) and moved.cost < option.cost:
                option = moved
                break
        else:
            return option
    return option


def candidates(problem: Problem) -> list[list[np.ndarray]]:
    """(C), in stages: the seed's pose (clipped into the box) when there is one and the nominal pose;
    then the first ``STAGES[1]`` Halton points; then the rest, up to ``CANDIDATES``."""
    first = [] if problem.seed_pose is None else [np.clip(problem.seed_pose, problem.lower, problem.upper)]
    first.append(problem.nominal.copy())
    points = [problem.lower + u * (problem.upper - problem.lower) for u in candidate_units()]
    return [first, points[: STAGES[1]], points[STAGES[1] :]]


def _choose(problem: Problem, options: list[Option]) -> tuple[Option | None, int]:
    """(A): (option, status) of a list of options; (None, UNREACHABLE) when it is empty."""
    feasible = [o for o in options if o.feasible(problem)]
    if feasible:
        return min(feasible, key=lambda o: (o.cost, o.order, o.slot)), OK
    reaching = [o for o in options if not o.collides]
    if reaching:
        return min(reaching, key=lambda o: (-o.margin, o.cost, o.order, o.slot)), UNSTABLE
    return None, UNREACHABLE


def hand_error(problem: Problem, p, q_arm) -> np.ndarray:
    """(F)'s e: [p_target - p_hand; L log(R_target R_hand^T)], world axes."""
    T_hand = body_T(problem, p) @ problem.mount @ np.asarray(problem.arm.fk(np.asarray(q_arm, float)), float)
    R = problem.target[:3, :3] @ T_hand[:3, :3].T
    return np.concatenate([problem.target[:3, 3] - T_hand[:3, 3], problem.scale * rotation_log(R)])


def repair_starts(problem: Problem, misses=()) -> list[np.ndarray]:
    """(F)'s starting points z = (p, q_a): the nominal pose with the arm at zero (clipped into its
    limits); then the candidates' branches that exist outside the arm's limits, least violation first
    (ties to the earlier candidate, then the lower branch), clipped into the limits; then, while fewer
    than ``REPAIR_STARTS``, the nominal pose with Halton points of the arm's range ([-pi, pi] where
    unlimited)."""
    lo, hi = problem.q_lower[-6:], problem.q_upper[-6:]
    lo, hi = np.where(np.isfinite(lo), lo, -math.pi), np.where(np.isfinite(hi), hi, math.pi)
    starts = [np.concatenate([problem.nominal, np.clip(np.zeros(6), lo, hi)])]
    for miss in sorted(misses, key=lambda m: m[:3])[: REPAIR_STARTS - 1]:
        starts.append(np.concatenate([miss[3], np.clip(miss[4], lo, hi)]))
    units = candidate_units(REPAIR_STARTS)
    for u in units[: REPAIR_STARTS - len(starts)]:
        starts.append(np.concatenate([problem.nominal, lo + u * (hi - lo)]))
    return starts


def descend(problem: Problem, z, order: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[Option]]:
    """(F)'s damped least squares from z = (p, q_a): (p, q_a, e, the options at p (order ``order``)),
    stopping early where the closed form at p has a feasible option (tried every ``REPAIR_CHECK``
    iterations)."""
    arm_lower, arm_upper = problem.q_lower[-6:] + REPAIR_INSET, problem.q_upper[-6:] - REPAIR_INSET
    lower, upper = np.concatenate([problem.lower, arm_lower]), np.concatenate([problem.upper, arm_upper])
    z = np.clip(np.array(z, float), lower, upper)
    e = hand_error(problem, z[:6], z[6:])
    lam = REPAIR_DAMPING
    for iteration in range(REPAIR_ITERATIONS):
        if float(e @ e) < 1e-24 or lam > REPAIR_STALL:
            break
        J = np.empty((6, 12))  # d hand / dz = -d e / dz, forward differences
        for j in range(12):
            step = np.zeros(12)
            step[j] = FD_STEP
            J[:, j] = -(hand_error(problem, (z + step)[:6], (z + step)[6:]) - e) / FD_STEP
        toward = np.concatenate([NULL_GAIN * (problem.nominal - z[:6]), np.zeros(6)])
        free = np.ones(12, bool)  # a variable on its bound that the step pushes out is held there
        for _ in range(ACTIVE_SET_PASSES):
            Jf = J * free
            pinv = Jf.T @ np.linalg.inv(Jf @ Jf.T + lam * lam * np.eye(6))
            delta = pinv @ e + (np.eye(12) - pinv @ Jf) @ (toward * free)
            held = free & (((z <= lower) & (delta < 0.0)) | ((z >= upper) & (delta > 0.0)))
            if not held.any():
                break
            free &= ~held
        z_new = np.clip(z + delta, lower, upper)
        e_new = hand_error(problem, z_new[:6], z_new[6:])
        legs_ok = _legs(problem, body_T(problem, z_new[:6]))[1]
        if legs_ok and float(e_new @ e_new) < max(float(e @ e), 1e-24):
            z, e, lam = z_new, e_new, lam / 3.0
        else:
            lam *= 3.0
        if (iteration + 1) % REPAIR_CHECK == 0:
            options = evaluate(problem, z[:6], order)
            if any(o.feasible(problem) for o in options):
                return z[:6], z[6:], e, options
    return z[:6], z[6:], e, evaluate(problem, z[:6], order)


def nan_result(robot) -> dict:
    n = 3 * robot.n_legs + robot.arm.dof
    return {
        "body_pose": np.full(6, np.nan),
        "q": np.full(n, np.nan),
        "status": INVALID_INPUT,
        "margin": math.nan,
        "distance": math.nan,
        "angle": math.nan,
        "slot": -1,
        "branches": np.full((8, robot.arm.dof), np.nan),
        "valid": np.zeros(8, bool),
    }


def _result(problem: Problem, option: Option, status: int) -> dict:
    T_body = body_T(problem, option.p)
    sols = problem.arm.ik_all(arm_target(problem, T_body))
    return {
        "body_pose": pose_of(T_body),
        "q": option.q,
        "status": status,
        "margin": option.margin,
        "distance": 0.0,
        "angle": 0.0,
        "slot": option.slot,
        "branches": np.asarray(sols.q, float),
        "valid": np.asarray(sols.valid),
    }


def reach(problem: Problem) -> dict:
    """The answer for one target: a dict with ``body_pose`` (6,) in the world, ``q`` (3 n + 6,),
    ``status``, ``margin``, ``distance``, ``angle``, ``slot`` (the arm's branch, -1 for none),
    ``branches`` (8, 6) and ``valid`` (8,): every arm solution at the chosen pose."""
    if not rigid(problem.target) or not np.isfinite(problem.feet).all():
        return nan_result(problem.robot)
    options, misses, order = [], [], 0
    for stage in candidates(problem):
        for p in stage:
            options += evaluate(problem, p, order, misses)
            order += 1
        option, status = _choose(problem, options)
        if status == OK:
            break
    if option is None:  # (F), start by start until one ends with a feasible option
        ends, repaired = [], []
        for k, z in enumerate(repair_starts(problem, misses)):
            p, q_arm, e, found = descend(problem, z, k)
            ends.append((p, q_arm, e))
            repaired += found
            option, status = _choose(problem, repaired)
            if status == OK:
                break
        if option is None:  # the nearest the repair came (ties to the earlier start)
            p, q_arm, e = min(ends, key=lambda end: float(end[2] @ end[2]))
            T_body = body_T(problem, p)
            q_legs, _ = _legs(problem, T_body)
            q = np.concatenate([q_legs, q_arm])
            com = np.asarray(problem.robot.center_of_mass(T_body, q), float)
            nearest = Option(p, q, -1, support_margin(problem.feet[:, :2], com[:2]), False, 0.0, 0)
            out = _result(problem, nearest, UNREACHABLE)
            out["distance"] = float(np.linalg.norm(e[:3]))
            out["angle"] = float(np.linalg.norm(e[3:])) / problem.scale
            return out
    if status == OK:
        option = refine(problem, option)
    return _result(problem, option, status)


def feasible_samples(problem: Problem, n: int, seed: int = 0):
    """n hand targets (n, 4, 4) from random feasible configurations of ``problem``'s robot (its target
    unused): a body pose uniform in the box, the legs on the problem's feet (each leg's IK OK), the
    arm's joints uniform within their limits, no collision, and the centre of mass at least the margin
    inside the feet. Also the generating body offsets from the nominal pose (n, 6) and joints (n, m).
    What the success rate of a reach is measured on."""
    robot = problem.robot
    rng = np.random.default_rng(seed)
    n3 = 3 * robot.n_legs
    lo, hi = problem.q_lower[n3:], problem.q_upper[n3:]
    targets, offsets, qs = [], [], []
    while len(targets) < n:
        p = problem.lower + rng.random(6) * (problem.upper - problem.lower)
        T = body_T(problem, p)
        q_legs, ok = _legs(problem, T)
        q = np.concatenate([q_legs, lo + rng.random(len(lo)) * (hi - lo)])
        if not ok or collides(problem, q, T):
            continue
        com = np.asarray(robot.center_of_mass(T, q), float)
        if support_margin(problem.feet[:, :2], com[:2]) < problem.margin:
            continue
        targets.append(T @ problem.mount @ np.asarray(problem.arm.fk(q[n3:]), float))
        offsets.append(p - problem.nominal)
        qs.append(q)
    return np.array(targets), np.array(offsets), np.array(qs)
