"""Registry entries of ``spotkin.trajectory``: point-to-point profiles and Cartesian paths."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import register
from .objects import P2P_Q0, P2P_QF, PATH_T0, PATH_T1, PROFILES, VIA_POSES, euler_matrix, pose_matrix
from .oracles import rigid_error, tol_for
from .outputs import Out, close, describe, outs
from .slots import ACCEPT, ALLOWED, EITHER, REJECT, Arg, Array, Choice, Custom, Flag, Int, Real, finite


def same_axes(plan):
    """q0 and qf both of the wrong length agree with each other (and with scalar limits)."""
    if plan["q0"] == plan["qf"] == "wrong_shape":
        return ACCEPT
    return EITHER if plan["q0"] == plan["qf"] == "empty" else None  # zero axes


def trajectory_entries():
    traj = sk.trajectory

    def p2p_probe(p2p, kw, c):
        if not isinstance(p2p, traj.PointToPoint):
            return f"not a PointToPoint: {describe(p2p)}"
        T = p2p.duration
        if not (isinstance(T, float) and math.isfinite(T) and T >= 0):
            return f"duration {T!r}"
        q, qd, qdd = p2p.sample(np.array([0.0, T / 3, T / 2, T]))
        if not (finite(q) and finite(qd) and finite(qdd)):
            return f"non-finite samples: q {describe(q)}"
        q0, qf = (np.asarray(kw[k], dtype=np.float64) for k in ("q0", "qf"))
        if not (close(q[0], q0, False) and close(q[-1], qf, False)):
            return f"the motion goes from {q[0]} to {q[-1]}, not from {q0} to {qf}"
        if (np.abs(qd) > p2p.vmax * (1 + 1e-6) + 1e-12).any():
            return f"speed {describe(qd)} above vmax {p2p.vmax}"
        return None

    q0 = Array("q0", lambda c: P2P_Q0, extra={"neg_huge": (lambda c, v: np.full(3, -1e308), EITHER, "")})
    qf = Array("qf", lambda c: P2P_QF, extra={"pos_huge": (lambda c, v: np.full(3, 1e308), EITHER, "")})
    limits = [Real("vmax", 1.0, vector=3), Real("amax", 2.0, vector=3)]
    overflow = ("span_overflow", {"q0": "neg_huge", "qf": "pos_huge"}, None)
    register(
        name="trajectory.point_to_point",
        covers="spotkin.trajectory.point_to_point",
        call=lambda c, **k: traj.point_to_point(**k),
        slots=[q0, qf, *limits, Choice("profile", "quintic", PROFILES, default="omit")],
        probe=p2p_probe,
        pair_rule=same_axes,
        combos=(overflow,),
    )
    register(
        name="trajectory.PointToPoint",
        covers="spotkin.trajectory.PointToPoint",
        call=lambda c, **k: traj.PointToPoint(**k),
        slots=[q0, qf, *limits, Choice("profile", "trapezoid", PROFILES)],
        probe=p2p_probe,
        pair_rule=same_axes,
        combos=(overflow,),
    )

    def time_equiv(duration):
        def equiv(sample, ctx):
            t = float(sample)
            T = duration(ctx)
            if t > T + 1:
                return np.asarray(T + 1.0, dtype=np.asarray(sample).dtype)
            if t < -1:
                return np.asarray(-1.0, dtype=np.asarray(sample).dtype)
            return None

        return equiv

    def time_slot(duration):
        return Batch(
            "t", (), valid=lambda s: not math.isnan(float(s)), equiv=time_equiv(duration), equiv_nan_ok=False
        )

    for profile in PROFILES:

        def get(c, profile=profile):
            return c.p2p(profile)

        def t_base(c, rng, n, get=get):
            T = get(c).duration
            return {"t": rng.uniform(-0.2 * T, 1.2 * T, n)}

        def sample_check(x, out, kw, c, get=get):
            p2p = get(c)
            q, qd, qdd = (np.asarray(v, dtype=np.float64) for v in out)
            t, T = float(x["t"]), p2p.duration
            tol = tol_for(x["t"], base=1e-9, f32=1e-4)
            if not (finite(q) and finite(qd) and finite(qdd)):
                return f"non-finite sample at t = {t}"
            lo, hi = np.minimum(p2p.q0, p2p.qf), np.maximum(p2p.q0, p2p.qf)
            if (q < lo - tol).any() or (q > hi + tol).any():
                return f"q {q} outside [q0, qf] at t = {t}"
            if (np.abs(qd) > p2p.vmax * (1 + 1e-6) + tol).any() or (
                np.abs(qdd) > p2p.amax * (1 + 1e-6) + tol
            ).any():
                return f"limits exceeded at t = {t}: qd {qd}, qdd {qdd}"
            if t < 0 or t > T:
                end = p2p.q0 if t < 0 else p2p.qf
                if np.abs(q - end).max() > tol or np.abs(qd).max() > 0 or np.abs(qdd).max() > 0:
                    return f"not at rest at the end state at t = {t}: {q}, {qd}, {qdd}"
            return None

        register(
            name=f"PointToPoint.sample[{profile}]",
            covers="spotkin.trajectory.PointToPoint.sample",
            call=lambda c, get=get, **k: get(c).sample(**k),
            slots=[time_slot(lambda c, get=get: get(c).duration)],
            baseline=t_base,
            outputs=outs(("float", (3,)), ("float", (3,)), ("float", (3,))),
            check=sample_check,
        )

    for kind in ("linear", "via"):

        def get(c, kind=kind):
            return c.path(kind)

        def t_base(c, rng, n, get=get):
            T = get(c).duration
            return {"t": rng.uniform(-0.2 * T, 1.2 * T, n)}

        def path_outputs(args, kw):
            pose = (7,) if kw.get("form") == "quaternion" else (4, 4)
            leaves = [Out("float", pose)]
            return (
                leaves + [Out("float", (6,))]
                if kw.get("twist") is True or kw.get("twist") is np.True_
                else leaves
            )

        def path_check(x, out, kw, c, get=get):
            path = get(c)
            pose = np.asarray(out[0], dtype=np.float64)
            t, T = float(x["t"]), path.duration
            tol = tol_for(x["t"], base=1e-9, f32=1e-4)
            if not finite(pose):
                return f"non-finite pose at t = {t}"
            M = pose_matrix(pose) if pose.shape == (7,) else pose
            if pose.shape == (7,) and abs(np.linalg.norm(pose[3:]) - 1) > tol:
                return f"non-unit quaternion at t = {t}: {pose}"
            if rigid_error(M) > 10 * tol:
                return f"not a rigid transform at t = {t}"
            if t <= 0 or t >= T:
                end = path.waypoints[0] if t <= 0 else path.waypoints[-1]
                if np.abs(M - end).max() > 10 * tol:
                    return f"not at the end pose at t = {t}"
                if len(out) > 1 and np.abs(out[1]).max() > 0:
                    return f"non-zero twist {out[1]} outside the path"
            if len(out) > 1 and not finite(out[1]):
                return f"non-finite twist at t = {t}"
            return None

        register(
            name=f"CartesianPath.sample[{kind}]",
            covers="spotkin.trajectory.CartesianPath.sample",
            call=lambda c, get=get, **k: get(c).sample(**k),
            slots=[
                time_slot(lambda c, get=get: get(c).duration),
                Choice("form", "matrix", ("matrix", "quaternion"), default="omit"),
                Flag("twist", default="omit"),
            ],
            baseline=t_base,
            outputs=path_outputs,
            check=path_check,
        )

    def path_probe(first, last):
        def probe(path, kw, c):
            if not isinstance(path, traj.CartesianPath):
                return f"not a CartesianPath: {describe(path)}"
            T = path.duration
            if not (isinstance(T, float) and math.isfinite(T) and T >= 0):
                return f"duration {T!r}"
            P = path.sample(np.linspace(0.0, T, 7))
            if not finite(P) or rigid_error(P) > 1e-9:
                return "samples are not finite rigid transforms"
            a, b = first(kw), last(kw)
            # float32 rotations are replaced by the nearest rotation: within their own rounding
            tol = 1e-6 if any(getattr(v, "dtype", None) == np.float32 for v in kw.values()) else 1e-9
            if np.abs(P[0] - a).max() > tol or np.abs(P[-1] - b).max() > tol:
                return "the path does not start at the first pose and end at the last"
            _, twist = path.sample(np.array([0.0, T / 2, T]), twist=True)
            if not finite(twist):
                return f"non-finite twist {describe(twist)}"
            return None

        return probe

    pose_extra = {
        "quat": (lambda c, v: np.concatenate([v[:3, 3], _quat_of(v)]), ACCEPT, ""),
        "euler": (lambda c, v: np.concatenate([v[:3, 3], _euler_of(v)]), ACCEPT, ""),
        "scaled": (lambda c, v: np.diag([2.0, 2.0, 2.0, 1.0]) @ v, REJECT, "value"),
        "reflect": (lambda c, v: np.diag([-1.0, 1.0, 1.0, 1.0]) @ v, REJECT, "value"),
        "last_row": (lambda c, v: v + np.diag([0.0, 0.0, 0.0, 1.0]), REJECT, "value"),
        "quat_zero": (lambda c, v: np.concatenate([v[:3, 3], np.zeros(4)]), REJECT, "value"),
        "quat_nonunit": (lambda c, v: np.concatenate([v[:3, 3], 2 * _quat_of(v)]), EITHER, ""),
        "batch": (lambda c, v: np.stack([v, v]), REJECT, "shape"),
    }
    angular = [Real("wmax", 1.0), Real("alphamax", 2.0)]
    no_angular = ("no_angular", {"wmax": "none", "alphamax": "none"}, ACCEPT)
    register(
        name="trajectory.linear",
        covers="spotkin.trajectory.linear",
        call=lambda c, **k: traj.linear(**k),
        slots=[
            Array("T0", lambda c: PATH_T0, extra=pose_extra),
            Array("T1", lambda c: PATH_T1, extra=pose_extra),
            Real("vmax", 0.5),
            Real("amax", 1.0),
            *angular,
        ],
        probe=path_probe(lambda kw: pose_matrix(kw["T0"]), lambda kw: pose_matrix(kw["T1"])),
        combos=(no_angular,),
        pair_rule=lambda plan: ACCEPT if plan["wmax"] == plan["alphamax"] == "none" else None,
    )

    poses_extra = {
        "quat": (lambda c, v: np.array([np.concatenate([T[:3, 3], _quat_of(T)]) for T in v]), ACCEPT, ""),
        "euler": (lambda c, v: np.array([np.concatenate([T[:3, 3], _euler_of(T)]) for T in v]), ACCEPT, ""),
        "one": (lambda c, v: v[:1], REJECT, "shape"),
        "two": (lambda c, v: v[:2], ACCEPT, ""),
        "repeat": (lambda c, v: np.concatenate([v[:2], v[1:2], v[2:]]), ACCEPT, ""),
        "all_same": (lambda c, v: np.stack([v[0]] * 3), EITHER, ""),
        "scaled": (lambda c, v: np.concatenate([v[:1], 2 * v[1:2], v[2:]]), REJECT, "value"),
        "many": (lambda c, v: _many_poses(60), ACCEPT, ""),
        "thousand": (lambda c, v: _many_poses(1001), ACCEPT, ""),
    }

    def first_last(kw, k):
        arr = np.asarray(kw["poses"], dtype=np.float64)
        return pose_matrix(arr[k])

    register(
        name="trajectory.via_points",
        covers="spotkin.trajectory.via_points",
        call=lambda c, **k: traj.via_points(**k),
        slots=[
            Array("poses", lambda c: VIA_POSES, extra=poses_extra),
            Real("vmax", 0.5),
            Real("amax", 1.0),
            *angular,
            Real("blend", 0.2, "nonneg", default="omit"),
        ],
        probe=path_probe(lambda kw: first_last(kw, 0), lambda kw: first_last(kw, -1)),
        combos=(no_angular,),
        pair_rule=lambda plan: ACCEPT if plan["wmax"] == plan["alphamax"] == "none" else None,
    )

    def path_part(attr):
        def table():
            def part(c):
                path = c.path("via")
                if attr == "quaternions":
                    return np.array([_quat_of(T) for T in path.waypoints])
                return np.array(getattr(path, attr), dtype=np.float64)

            def valid(c, r, b):
                return Arg(part(c))

            def bad(change):
                return lambda c, r, b: Arg(change(part(c)), EITHER)

            def nan(v):
                v.reshape(-1)[0] = np.nan
                return v

            return {
                "valid": valid,
                "nan": bad(nan),
                "short": bad(lambda v: v[:-1]),
                "empty": bad(lambda v: v[:0]),
                "flat": bad(lambda v: v.reshape(-1)),
                "big": bad(lambda v: v * 1e308),
                "str": bad(lambda v: v.astype(str)),
                "none": lambda c, r, b: Arg(None, EITHER),
            }

        return Custom(attr, table())

    def raw_probe(path, kw, c):
        if not isinstance(path, traj.CartesianPath):
            return f"not a CartesianPath: {describe(path)}"
        try:
            path.sample(np.linspace(-1.0, 10.0, 5), twist=True)
        except ALLOWED:
            pass
        return None

    register(
        name="trajectory.CartesianPath",
        covers="spotkin.trajectory.CartesianPath",
        call=lambda c, **k: traj.CartesianPath(**k),
        slots=[
            path_part(a)
            for a in ("waypoints", "times", "blends", "quaternions", "linear_velocity", "angular_velocity")
        ],
        probe=raw_probe,
    )

    def hb_base(c, rng, n):
        q = np.linspace([0.0, 0.8, -1.6], [0.2, 1.2, -2.0], 6) + rng.uniform(-0.01, 0.01, (6, 3))
        sol = c.leg.ik_all(c.leg.fk(q))
        return {"q_slots": sol.q, "valid": sol.valid}

    def hb(key, change, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(change(b[key].copy()), expect, why)

    def poke_nan(q):
        q[2, 0, 0] = np.nan
        return q

    def readonly(a):
        a.flags.writeable = False
        return a

    q_slots = Custom(
        "q_slots",
        {
            "valid": hb("q_slots", lambda q: q),
            "list": hb("q_slots", lambda q: q.tolist()),
            "float32": hb("q_slots", lambda q: q.astype(np.float32)),
            "readonly": hb("q_slots", readonly),
            "neg_stride": hb("q_slots", lambda q: q[::-1].copy()[::-1]),
            "nan_valid_slot": hb("q_slots", poke_nan, EITHER),
            "2d": hb("q_slots", lambda q: q[:, 0], REJECT, "shape"),
            "4d": hb("q_slots", lambda q: q[None], REJECT, "shape"),
            "empty": hb("q_slots", lambda q: q[:0], REJECT, "shape"),
            "complex": hb("q_slots", lambda q: q + 0j, REJECT, "type"),
            "str_array": hb("q_slots", lambda q: q.astype(str), REJECT, "type"),
            "masked": hb("q_slots", lambda q: np.ma.masked_invalid(q), REJECT),
            "str": lambda c, r, b: Arg("abc", REJECT, "type"),
            "none": lambda c, r, b: Arg(None, REJECT, "type"),
        },
    )
    valid = Custom(
        "valid",
        {
            "valid": hb("valid", lambda v: v),
            "list": hb("valid", lambda v: v.tolist()),
            "int": hb("valid", lambda v: v.astype(int), EITHER),
            "float": hb("valid", lambda v: v.astype(float), EITHER),
            "nan_float": hb("valid", lambda v: np.where(v, 1.0, np.nan), EITHER),
            "all_false": hb("valid", lambda v: np.zeros_like(v)),
            "shape": hb("valid", lambda v: v[:, :3], REJECT, "shape"),
            "extra_dim": hb("valid", lambda v: v[..., None], REJECT, "shape"),
            "str_array": hb("valid", lambda v: v.astype(str), REJECT),
            "complex": hb("valid", lambda v: v + 0j, REJECT),
            "masked": hb("valid", lambda v: np.ma.masked_array(v, mask=~v), REJECT),
            "none": lambda c, r, b: Arg(None, REJECT),
        },
    )

    def hb_probe(res, kw, c):
        if not isinstance(res, traj.BranchPath):
            return f"not a BranchPath: {describe(res)}"
        try:
            q = np.asarray(kw["q_slots"], dtype=np.float64)
            ok_slot = np.asarray(kw["valid"]).astype(bool)
        except (TypeError, ValueError):
            return None
        b = int(kw["branch"])
        K = q.shape[0]
        expected = np.where(ok_slot[:, b, None], q[:, b], np.nan)
        if not close(res.q, expected, False):
            return f"q {describe(res.q)} is not the held slot {describe(expected)}"
        if res.ok.shape != (K,) or res.ok.dtype != bool or (res.ok & ~ok_slot[:, b]).any():
            return f"ok {describe(res.ok)} for valid {describe(ok_slot[:, b])}"
        jumps = np.asarray(res.jumps)
        if jumps.ndim != 1 or jumps.dtype.kind not in "iu" or ((jumps < 0) | (jumps >= K)).any():
            return f"jumps {describe(jumps)}"
        if np.asarray(res.max_step).shape != (K,):
            return f"max_step {describe(res.max_step)}"
        return None

    register(
        name="trajectory.hold_branch",
        covers="spotkin.trajectory.hold_branch",
        call=lambda c, **k: traj.hold_branch(**k),
        slots=[q_slots, valid, Int("branch", 0, 0, 4), Real("max_step", 0.2, default="omit")],
        baseline=hb_base,
        probe=hb_probe,
    )


def _quat_of(T):
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.asarray(T)[:3, :3]).as_quat()


def _euler_of(T):
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.asarray(T)[:3, :3]).as_euler("XYZ")


def _many_poses(n):
    k = np.arange(n)
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, 0, 3] = 0.01 * k
    poses[:, 1, 3] = 0.02 * np.sin(k)
    poses[:, :3, :3] = [euler_matrix([0.0, 0.0, 0.05 * np.sin(0.3 * i)]) for i in k]
    return poses
