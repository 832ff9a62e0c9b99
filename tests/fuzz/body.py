"""Registry entries of the whole-body methods (``body_ik``, ``body_fk``, ``body_jacobian``,
``body_rates``, ``fk_all``, ``arm_ik_world``), for Spot and for robots from URDF (:class:`BodySpec`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import REGISTRY, angle_slot, register, seq_slot
from .objects import ROBOT_ARMS, ROBOT_LEGS, STANCE_HEIGHT, body_poses, in_limits, nominal_q12, pose_matrix
from .oracles import all_nan, nearest_check, tol_for, within
from .outputs import Out, OutSlot, close, describe, outs
from .slots import ACCEPT, INVALID, OK, REJECT, UNREACHABLE, Arg, Choice, Custom, Real, finite, pose_validity


@dataclass(frozen=True)
class BodySpec:
    """A robot whose whole-body methods are fuzzed: ``key`` (:meth:`Context.robot`), the class whose
    methods the entries cover, the name of the whole-body joint argument, and a name tag."""

    key: str
    cls: str = "Robot"
    qname: str = "q"

    def name(self, method: str) -> str:
        return f"{self.cls}.{method}" if self.cls == "Spot" else f"{self.cls}.{method}[{self.key}]"

    def covers(self, method: str) -> str:
        return f"spotkin.{self.cls}.{method}"


BODY_METHODS = ("body_ik", "body_fk", "body_jacobian", "body_rates", "fk_all", "arm_ik_world")
SPOT_BODY = BodySpec("spot", "Spot", "q")


def arm_limits(arm) -> np.ndarray:
    """(6, 2) limits of a SpotArm or a Chain."""
    return np.asarray(arm.limits) if isinstance(arm, sk.SpotArm) else np.stack([arm.lower, arm.upper], 1)


def knee_point(leg, q) -> np.ndarray:
    """The documented knee origin Rx(s1 q1) (a + Ry(s2 q2) b), NaN where a used angle is not finite."""
    q = np.asarray(q, dtype=np.float64)
    (s1, s2, _), a, b = leg.signs, leg.a, leg.b
    with np.errstate(all="ignore"):
        t1, t2 = s1 * q[..., 0], s2 * q[..., 1]
        v = np.stack(
            [
                a[0] + np.cos(t2) * b[0] + np.sin(t2) * b[2],
                np.full_like(t2, a[1] + b[1]),
                a[2] - np.sin(t2) * b[0] + np.cos(t2) * b[2],
            ],
            -1,
        )
        return np.stack(
            [
                v[..., 0],
                np.cos(t1) * v[..., 1] - np.sin(t1) * v[..., 2],
                np.sin(t1) * v[..., 1] + np.cos(t1) * v[..., 2],
            ],
            -1,
        )


def _body_base(spec: BodySpec):
    """Valid samples for the whole-body calls of one robot."""

    def base(c, rng, n):
        robot, height = c.robot(spec.key), STANCE_HEIGHT[spec.key]
        legs = robot.n_legs
        if spec.key == "spot":  # the Spot entries' historical draws
            q_arm = in_limits(c.arm.limits, rng, n, margin=0.1)
            pose = body_poses(rng, n)
            q, seed = nominal_q12(rng, n), nominal_q12(rng, n)
        else:
            pose = body_poses(rng, n, height)
            q = c.nominal(spec.key) + rng.uniform(-0.1, 0.1, (n, 3 * legs))
            seed = c.nominal(spec.key) + rng.uniform(-0.1, 0.1, (n, 3 * legs))
            q_arm = None if robot.arm is None else in_limits(arm_limits(robot.arm), rng, n, margin=0.1)
        feet = np.broadcast_to(robot.stance_feet(height), (n, legs, 3)) + rng.uniform(
            -0.02, 0.02, (n, legs, 3)
        )
        world = np.array([pose_matrix(p) for p in pose])
        out = {
            "body_pose": pose,
            "feet": feet,
            spec.qname: q,
            "seed": seed,
            "twist": rng.normal(0, 0.1, (n, 6)),
        }
        if q_arm is None:  # no arm: any target (the call raises)
            out["q_arm"] = np.zeros((n, 6))
            out["T_world"] = world @ sk.translation([0.5, 0.0, 0.2])
        else:
            out["q_arm"] = q_arm
            out["T_world"] = world @ robot.arm.fk(q_arm)
        return out

    return base


def body_entries(spec: BodySpec, methods=BODY_METHODS, light=()):
    """The whole-body ``methods`` of one robot, against the documented formulas per leg (n legs,
    each with its columns of the whole-body q); those in ``light`` are light entries (the code is
    Spot's: the robot changes the numbers and shapes, not the paths)."""
    first = len(REGISTRY)
    _body_methods(spec, methods)
    for entry in REGISTRY[first:]:
        entry.light = any(entry.name == spec.name(method) for method in light)


def _body_methods(spec, methods):
    qn = spec.qname
    base = _body_base(spec)

    def robot_of(c):
        return c.robot(spec.key)

    euler = np.array([False] * 3 + [True] * 3)

    def body_pose_slot():
        return Batch("body_pose", (6,), pose="body", angles=euler)

    def world(x, kw):
        return pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))

    def body_ik_check(x, out, kw, c):
        q, status = out
        ok = pose_validity(x["body_pose"])
        if ok is None:
            return None
        T = world(x, kw) if ok else None
        tol = tol_for(*x.values(), base=1e-7, f32=1e-3)
        hips = c.hips(spec.key)
        for k, (leg, cols) in enumerate(zip(robot_of(c).legs, c.columns(spec.key))):
            qk, sk_ = q[cols], int(status[k])
            bad = not ok or not finite(x["feet"][k]) or ("seed" in x and not finite(x["seed"][cols]))
            if bad:
                if sk_ != INVALID or not all_nan(qk):
                    return f"leg {k}: invalid input but status {sk_}, q {qk}"
                continue
            if sk_ == INVALID:
                return f"leg {k}: INVALID_INPUT for a valid input"
            if sk_ == OK:
                foot = T[:3, 3] + T[:3, :3] @ (hips[k] + leg.fk(qk.astype(np.float64)))
                if not finite(qk) or np.abs(foot - x["feet"][k]).max() > tol:
                    return f"leg {k}: OK but its foot is at {foot}, not {x['feet'][k]}"
                if not within(qk, leg.limits, 1e-6):
                    return f"leg {k}: OK outside the limits: {qk}"
            elif sk_ == UNREACHABLE and kw.get("fallback", "nearest") == "nearest":
                if not finite(qk) or not within(qk, leg.limits, 1e-6):
                    return f"leg {k}: UNREACHABLE fallback not finite in the limits: {qk}"
            elif not all_nan(qk):
                return f"leg {k}: status {sk_} with q {qk}"
        return None

    def legs(c):
        return robot_of(c).n_legs

    if "body_ik" in methods:
        register(
            name=spec.name("body_ik"),
            covers=spec.covers("body_ik"),
            call=lambda c, **k: robot_of(c).body_ik(**k),
            slots=[
                body_pose_slot(),
                Batch("feet", (ROBOT_LEGS[spec.key], 3)),
                angle_slot("seed", 3 * ROBOT_LEGS[spec.key], optional=True, default="omit"),
                seq_slot(),
                Choice("fallback", "nearest", ("nearest", "nan"), default="omit"),
                OutSlot(
                    ("float", (3 * ROBOT_LEGS[spec.key],)),
                    ("status", (ROBOT_LEGS[spec.key],)),
                    drivers=["body_pose", "feet"],
                ),
            ],
            baseline=base,
            outputs=outs(("float", (3 * ROBOT_LEGS[spec.key],)), ("status", (ROBOT_LEGS[spec.key],))),
            nan_rule="check",
            check=body_ik_check,
        )

    def legs_bad(x, c):
        return [not finite(x[qn][cols]) for cols in c.columns(spec.key)]

    def body_fk_check(x, out, kw, c):
        (feet,) = out
        ok = pose_validity(x["body_pose"])
        bad = legs_bad(x, c)
        if ok is None or (any(bad) and all_nan(feet)):  # NaN for the whole sample, or per leg
            return None
        if not ok:
            return None if all_nan(feet) else f"invalid body pose but feet {describe(feet)}"
        T = world(x, kw)
        tol = tol_for(*x.values(), base=1e-9, f32=1e-4)
        hips = c.hips(spec.key)
        for k, (leg, cols) in enumerate(zip(robot_of(c).legs, c.columns(spec.key))):
            if bad[k]:
                if not all_nan(feet[k]):
                    return f"leg {k} has a NaN/Inf joint but its foot is {feet[k]}"
                continue
            ref = T[:3, 3] + T[:3, :3] @ (hips[k] + leg.fk(x[qn][cols].astype(np.float64)))
            if not finite(feet[k]) or np.abs(feet[k] - ref).max() > tol * max(1, np.abs(ref).max()):
                return f"foot {k} is {feet[k]}, expected {ref}"
        return None

    n = ROBOT_LEGS[spec.key]
    if "body_fk" in methods:
        register(
            name=spec.name("body_fk"),
            covers=spec.covers("body_fk"),
            call=lambda c, **k: robot_of(c).body_fk(**k),
            slots=[
                body_pose_slot(),
                angle_slot(qn, 3 * n),
                seq_slot(),
                OutSlot(("float", (n, 3)), drivers=["body_pose", qn]),
            ],
            baseline=base,
            outputs=outs(("float", (n, 3))),
            nan_rule="check",
            check=body_fk_check,
        )

    def body_jacobian_check(x, out, kw, c):
        (J,) = out
        ok = pose_validity(x["body_pose"])
        bad = legs_bad(x, c)
        if ok is None or (any(bad) and all_nan(J)):  # NaN for the whole sample, or per leg
            return None
        if not ok:
            return None if all_nan(J) else f"partly NaN: invalid body pose but the Jacobian is {describe(J)}"
        T = world(x, kw)
        R = T[:3, :3]
        tol = tol_for(*x.values(), base=1e-9, f32=1e-4)
        hips = c.hips(spec.key)
        for k, (leg, cols) in enumerate(zip(robot_of(c).legs, c.columns(spec.key))):
            rows = J[3 * k : 3 * k + 3]
            if bad[k]:
                if not np.isnan(rows[:, 6 + cols]).all():
                    return f"leg {k} has a NaN/Inf joint but its Jacobian block is finite"
                continue
            qk = x[qn][cols].astype(np.float64)
            r = R @ (hips[k] + leg.fk(qk))
            ref = np.zeros((3, 6 + 3 * n))
            ref[:, :3] = np.eye(3)
            ref[:, 3:6] = -np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
            ref[:, 6 + cols] = R @ leg.jacobian(qk)
            if not finite(rows) or np.abs(rows - ref).max() > tol:
                return f"rows of leg {k} differ from v + w x (foot - t) + R J_leg dq"
        return None

    if "body_jacobian" in methods:
        register(
            name=spec.name("body_jacobian"),
            covers=spec.covers("body_jacobian"),
            call=lambda c, **k: robot_of(c).body_jacobian(**k),
            slots=[
                body_pose_slot(),
                angle_slot(qn, 3 * n),
                seq_slot(),
                OutSlot(("float", (3 * n, 6 + 3 * n)), drivers=["body_pose", qn]),
            ],
            baseline=base,
            outputs=outs(("float", (3 * n, 6 + 3 * n))),
            nan_rule="check",
            check=body_jacobian_check,
        )

    def body_rates_check(x, out, kw, c):
        qd, singular = out
        ok = pose_validity(x["body_pose"])
        if ok is None:
            return None
        tolerance = kw.get("tolerance", 1e-6)
        bad = legs_bad(x, c)
        hips = c.hips(spec.key)
        for k, (leg, cols) in enumerate(zip(robot_of(c).legs, c.columns(spec.key))):
            qdk = qd[cols]
            if bool(singular[k]) != all_nan(qdk) or (not singular[k] and not finite(qdk)):
                return f"leg {k}: singular {singular[k]} with qd {qdk}"
            if not ok or bad[k] or not finite(x["twist"]):
                if not singular[k]:
                    return f"leg {k}: invalid input but singular False, qd {qdk}"
                continue
            qk = x[qn][cols].astype(np.float64)
            J = leg.jacobian(qk)
            sigma = np.linalg.svd(J, compute_uv=False)[-1]
            R = world(x, kw)[:3, :3]
            v, w = x["twist"][:3].astype(np.float64), x["twist"][3:].astype(np.float64)
            with np.errstate(all="ignore"):
                rhs = -R.T @ (v + np.cross(w, R @ (hips[k] + leg.fk(qk))))
                try:
                    overflow = not finite(rhs) or (sigma > 0 and not finite(np.linalg.solve(J, rhs)))
                except np.linalg.LinAlgError:  # exactly singular (a stretched leg at integer angles)
                    overflow = False
            if overflow:
                continue  # the velocities themselves overflow: NaN and singular, or Inf
            if singular[k]:
                if sigma > tolerance * (1 + 1e-6) + 1e-12:
                    return f"leg {k}: singular with sigma_min {sigma} > tolerance {tolerance}"
                continue
            scale = max(1.0, float(np.abs(rhs).max()), float(np.abs(J).max() * np.abs(qdk).max()))
            if np.abs(J @ qdk - rhs).max() > 1e-8 * scale:
                return f"leg {k}: J qd != -R^T (v + w x (foot - t))"
        return None

    if "body_rates" in methods:
        register(
            name=spec.name("body_rates"),
            covers=spec.covers("body_rates"),
            call=lambda c, **k: robot_of(c).body_rates(**k),
            slots=[
                body_pose_slot(),
                angle_slot(qn, 3 * n),
                Batch("twist", (6,)),
                seq_slot(),
                Real("tolerance", 1e-6, "nonneg", default="omit"),
            ],
            baseline=base,
            outputs=outs(("f64", (3 * n,)), ("bool", (n,))),
            nan_rule="check",
            check=body_rates_check,
        )

    def fk_all_outputs(args, kw):
        hand = Out("hand", (4, 4)) if args["q_arm"].present else Out("none")
        return [Out("f64", (4, 4)), Out("f64", (n, 3)), Out("f64", (n, 3)), Out("f64", (n, 3)), hand]

    def fk_all_check(x, out, kw, c):
        body, hip_w, knees, feet, hand = out
        ok = pose_validity(x["body_pose"])
        bad = legs_bad(x, c)
        if ok is None or (any(bad) and all(all_nan(v) for v in (body, hip_w, knees, feet))):
            return None  # NaN for the whole sample, or per leg
        if not ok:
            leaves = [body, hip_w, knees, feet] + ([hand] if hand is not None else [])
            return None if all(all_nan(v) for v in leaves) else "invalid body pose but frames are not NaN"
        T = world(x, kw)
        R, t = T[:3, :3], T[:3, 3]
        hips = c.hips(spec.key)
        if not close(body, T, False) or not close(hip_w, (R @ hips.T).T + t, False):
            return "body or hips differ from the body transform"
        q = x[qn].astype(np.float64)
        robot = robot_of(c)
        for k, (leg, cols) in enumerate(zip(robot.legs, c.columns(spec.key))):
            knee = knee_point(leg, q[cols])
            knee = t + R @ (hips[k] + knee) if finite(knee) else np.full(3, np.nan)
            foot = t + R @ (hips[k] + leg.fk(q[cols])) if not bad[k] else np.full(3, np.nan)
            if finite(knee) != finite(knees[k]) or (finite(knee) and not close(knees[k], knee, False)):
                return f"knee {k} is {knees[k]}, expected {knee}"
            if finite(foot) != finite(feet[k]) or (finite(foot) and not close(feet[k], foot, False)):
                return f"foot {k} is {feet[k]}, expected {foot}"
        if hand is not None:
            if not finite(x["q_arm"]):
                return None if all_nan(hand) else f"NaN/Inf arm joint but hand {describe(hand)}"
            if not close(hand, T @ robot.arm.fk(x["q_arm"].astype(np.float64)), False):
                return "hand differs from T_world_body arm.fk(q_arm)"
        return None

    if ROBOT_ARMS[spec.key]:
        q_arm = angle_slot("q_arm", 6, optional=True, default="omit")
    else:  # q_arm needs an arm: any q_arm but None is refused
        q_arm = Custom(
            "q_arm",
            {
                "none": lambda c, r, b: Arg(None),
                "valid": lambda c, r, b: Arg(b["q_arm"][0], REJECT, "value"),
                "batch": lambda c, r, b: Arg(b["q_arm"], REJECT, "value"),
                "nan": lambda c, r, b: Arg(np.full(6, np.nan), REJECT, "value"),
                "float32": lambda c, r, b: Arg(b["q_arm"].astype(np.float32), REJECT, "value"),
                "str": lambda c, r, b: Arg("abc", REJECT),
                "wrong_shape": lambda c, r, b: Arg(np.zeros(5), REJECT),
            },
            default="omit",
        )
    if "fk_all" in methods:
        register(
            name=spec.name("fk_all"),
            covers=spec.covers("fk_all"),
            call=lambda c, **k: robot_of(c).fk_all(**k),
            slots=[body_pose_slot(), angle_slot(qn, 3 * n), q_arm, seq_slot()],
            baseline=base,
            outputs=fk_all_outputs,
            nan_rule="check",
            check=fk_all_check,
        )

    def arm_world_check(x, out, kw, c):
        q, status = out
        ok = pose_validity(x["body_pose"])
        target_ok = pose_validity(x["T_world"])
        if ok is None or target_ok is None:
            return None
        if not ok or not target_ok or ("seed" in x and not finite(x["seed"])):
            return None if int(status) == INVALID and all_nan(q) else f"invalid input but ({q}, {status})"
        T = world(x, kw)
        if (
            np.abs(T[:3, 3]).max() > 1e300
            and np.abs(np.asarray(x["T_world"], dtype=np.float64)).max() > 1e300
        ):
            return None  # the body-frame target may overflow
        arm = robot_of(c).arm
        return nearest_check(lambda q: T @ arm.fk(q), lambda x: x["T_world"], arm_limits(arm))(x, out, kw, c)

    def arm_base(c, rng, n):
        samples = base(c, rng, n)
        arm = robot_of(c).arm
        if arm is not None:
            samples["seed"] = in_limits(arm_limits(arm), rng, n, 0.1)
        else:
            samples["seed"] = np.zeros((n, 6))
        return samples

    if "arm_ik_world" in methods:
        register(
            name=spec.name("arm_ik_world"),
            covers=spec.covers("arm_ik_world"),
            call=lambda c, **k: robot_of(c).arm_ik_world(**k),
            slots=[
                body_pose_slot(),
                Batch("T_world", (4, 4), pose="T", quat_ok=False),
                angle_slot("seed", 6, optional=True, default="omit", dtype_driver=False),
                seq_slot(),
            ],
            baseline=arm_base,
            outputs=outs(("float", (6,)), ("status", ())),
            mixed="f64",
            nan_rule="check",
            check=arm_world_check,
            # "this robot has no arm": ValueError whatever the arguments
            expect=ACCEPT if ROBOT_ARMS[spec.key] else REJECT,
            why="" if ROBOT_ARMS[spec.key] else "value",
        )
