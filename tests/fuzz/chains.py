"""Registry entries of ``Chain``: 3-joint and 6-joint (spherical-wrist) chains from ``from_mdh`` and
``from_dh``, and chains from URDFs (a Go2 leg, the Spot arm); ``from_mdh`` and ``from_dh``."""

from __future__ import annotations

import pickle

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import angle_slot, register
from .objects import CHAIN_ROWS, LEG_LIMITS, URDF_CHAINS, in_limits, pose_matrix
from .oracles import all_nan, finite_check, frame_slot, nearest_check, rigid_error, solution_check
from .outputs import OutSlot, close, describe, outs
from .slots import ACCEPT, EITHER, REJECT, Arg, Array, Choice, Custom, Int, Real, finite, pose_validity


def dof_changes(plan):
    """A chain table of another joint count with the 3-joint limits: rejected."""
    if plan["rows"] in ("one_row", "zero_rows", "many_rows") and plan["limits"] not in ("omit", "none"):
        return REJECT
    return None


def ikd_pairs(plan):
    """(2, 0, 4, 4) targets with a (0, dof) start read as paths: ambiguous with batches."""
    return EITHER if plan["T_targets"] == "empty2" else None


def chain_entries(tool_extra):
    for key in (*CHAIN_ROWS, *URDF_CHAINS):
        dof = len(CHAIN_ROWS[key]) if key in CHAIN_ROWS else URDF_CHAINS[key][2]

        def get(c, key=key):
            return c.chain(key)

        def chain_q(c, rng, n, get=get):
            chain = get(c)
            limits = np.stack([chain.lower, chain.upper], axis=1)
            q = in_limits(limits, rng, n, margin=0.1)
            T = chain.fk(q)
            return {
                "q": q,
                "seed": q + rng.normal(0, 0.05, q.shape),
                "p": T[:, :3, 3],
                "T": T,
                "T_targets": T,
                "q0": q + rng.normal(0, 0.05, q.shape),
                "target": T[:, :3, 3] if len(chain.lower) == 3 else T,
            }

        def limits_of(c, get=get):
            return np.stack([get(c).lower, get(c).upper], axis=1)

        def fk_check(x, out, kw, c):
            (T,) = out
            return (
                None
                if finite(T) and rigid_error(T) < 1e-5
                else f"not a finite rigid transform: {describe(T)}"
            )

        def frames_check(x, out, kw, c, get=get):
            (F,) = out
            if not finite(F) or rigid_error(F) > 1e-5:
                return f"frames are not finite rigid transforms: {describe(F)}"
            if not close(F[-1], get(c).fk(x["q"]), True):
                return "the last frame is not fk(q)"
            return None

        frame = frame_slot(dof, "frame")
        point = frame_slot(dof, "point")
        q_slot = angle_slot("q", dof)
        tag = f"[{key}]"
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.fk{tag}",
            covers="spotkin.Chain.fk",
            call=lambda c, get=get, **k: get(c).fk(**k),
            slots=[q_slot, OutSlot(("float", (4, 4)))],
            baseline=chain_q,
            outputs=outs(("float", (4, 4))),
            check=fk_check,
        )
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.frames{tag}",
            covers="spotkin.Chain.frames",
            call=lambda c, get=get, **k: get(c).frames(**k),
            slots=[q_slot],
            baseline=chain_q,
            outputs=outs(("float", (dof + 2, 4, 4))),
            check=frames_check,
        )
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.jacobian{tag}",
            covers="spotkin.Chain.jacobian",
            call=lambda c, get=get, **k: get(c).jacobian(**k),
            slots=[q_slot, frame, point, OutSlot(("float", (6, dof)))],
            baseline=chain_q,
            outputs=outs(("float", (6, dof))),
            check=finite_check,
        )
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.position_jacobian{tag}",
            covers="spotkin.Chain.position_jacobian",
            call=lambda c, get=get, **k: get(c).position_jacobian(**k),
            slots=[q_slot, frame, point],
            baseline=chain_q,
            outputs=outs(("float", (3, dof))),
            check=finite_check,
        )

        def fk_point(get=get):
            return lambda c: lambda q: get(c).fk(q)[:3, 3]

        def fk_pose(get=get):
            return lambda c: lambda q: get(c).fk(q)

        point_fk, pose_fk = fk_point(), fk_pose()
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.ik_position{tag}",
            covers="spotkin.Chain.ik_position",
            call=lambda c, get=get, **k: get(c).ik_position(**k),
            slots=[
                Batch("p", (3,)),
                OutSlot(
                    ("float", (4, 3)),
                    ("flag", (4,)),
                    ("flag", (4,)),
                    ("flag", (4,)),
                    ("status", ()),
                    drivers=["p"],
                ),
            ],
            baseline=chain_q,
            outputs=outs(("float", (4, 3)), ("flag", (4,)), ("flag", (4,)), ("flag", (4,)), ("status", ())),
            expect=ACCEPT if dof == 3 else REJECT,
            check=lambda x, out, kw, c, fkp=point_fk, lim=limits_of: solution_check(
                fkp(c), lambda x: x["p"], lim(c)
            )(x, out, kw, c),
        )
        held = [  # a held joint is for 7-joint chains: refused here, and free_value alone too
            Custom("free_joint", {"two": lambda c, r, b: Arg(2, REJECT, "value")}, default="omit"),
            Custom("free_value", {"value": lambda c, r, b: Arg(0.3, REJECT, "value")}, default="omit"),
        ]
        if dof == 3:  # every branch under the solver interface's name: ik_position's for 3 joints
            leaves = (("float", (4, 3)), ("flag", (4,)), ("flag", (4,)), ("flag", (4,)), ("status", ()))
            all_slots = [Batch("target", (3,)), *held, OutSlot(*leaves, drivers=["target"])]
            all_outs = outs(*leaves)
            all_check = lambda x, out, kw, c, fkp=point_fk, lim=limits_of: solution_check(  # noqa: E731
                fkp(c), lambda x: x["target"], lim(c)
            )(x, out, kw, c)
        else:  # ik's for the others (a 6-joint chain; any other width is refused)
            leaves = (("float", (8, 6)), ("flag", (8,)), ("flag", (8,)), ("flag", (8,)), ("status", ()))
            all_slots = [Batch("target", (4, 4), pose="T"), *held, OutSlot(*leaves, drivers=["target"])]
            all_outs = outs(*leaves)
            all_check = lambda x, out, kw, c, fkp=pose_fk, lim=limits_of: solution_check(  # noqa: E731
                fkp(c), lambda x: pose_matrix(x["target"]), lim(c)
            )(x, out, kw, c)
        register(
            light=key in URDF_CHAINS,
            name=f"Chain.ik_all{tag}",
            covers="spotkin.Chain.ik_all",
            call=lambda c, get=get, **k: get(c).ik_all(**k),
            slots=all_slots,
            baseline=chain_q,
            outputs=all_outs,
            expect=ACCEPT if dof in (3, 6) else REJECT,
            check=all_check,
        )

        def tolerance_probe(result, kw, c, get=get):
            if not isinstance(result, sk.Chain) or result.dof != get(c).dof:
                return f"with_ik_tolerance returned {result!r}, not a Chain of the same joints"
            if result is get(c):
                return "with_ik_tolerance returned the chain itself, not a new one"
            return None

        register(
            light=True,
            name=f"Chain.with_ik_tolerance{tag}",
            covers="spotkin.Chain.with_ik_tolerance",
            call=lambda c, get=get, **k: get(c).with_ik_tolerance(**k),
            slots=[
                Real("angle", 1e-3, "nonneg", skip=("int", "np_int"), default="omit"),
                Real("distance", 1e-3, "nonneg", default="omit"),
            ],
            probe=tolerance_probe,
            overflow_ok=True,
        )

        def inertials_probe(result, kw, c, get=get, dof=dof):
            if not isinstance(result, sk.Chain) or result.dof != dof or result is get(c):
                return f"with_inertials returned {result!r}, not a new Chain of the same joints"
            given = [np.asarray(kw[name], dtype=np.float64) for name in ("mass", "com", "inertia")]
            got = result.inertials
            if got is None or not all(
                a.shape == b.shape and np.allclose(a, b, rtol=1e-6, atol=1e-9) for a, b in zip(got, given)
            ):
                return f"with_inertials kept {got!r}, not the given arrays"
            return None

        def rods(c, dof=dof):  # uniform rods of 0.3 m along x, 1 kg each
            return np.tile(np.diag([0.0, 0.0075, 0.0075]), (dof, 1, 1))

        register(
            light=True,
            name=f"Chain.with_inertials{tag}",
            covers="spotkin.Chain.with_inertials",
            call=lambda c, get=get, **k: get(c).with_inertials(**k),
            slots=[
                Array("mass", lambda c, dof=dof: np.ones(dof)),
                Array("com", lambda c, dof=dof: np.tile([-0.15, 0.0, 0.0], (dof, 1))),
                Array("inertia", rods),
            ],
            probe=inertials_probe,
            overflow_ok=True,
        )

        # the free-joint methods need a 7-joint chain (tests/test_chain_ik7.py covers them on
        # Panda- and Kinova-like arms): on these chains every call is refused
        def needs_seven(result, kw, c):
            return f"a 7-joint chain was needed, got {result!r}"

        register(
            name=f"Chain.ik_free_kind{tag}",
            covers="spotkin.Chain.ik_free_kind",
            call=lambda c, get=get, **k: get(c).ik_free_kind(**k),
            slots=[Int("free_joint", 1, 0, 7)],
            expect=REJECT,
            why="",
            probe=needs_seven,
        )
        register(
            name=f"Chain.ik_self_motion{tag}",
            covers="spotkin.Chain.ik_self_motion",
            call=lambda c, get=get, **k: get(c).ik_self_motion(**k),
            slots=[
                Batch("T", (4, 4), pose="T"),
                Int("free_joint", 1, 0, 7),
                Custom(
                    "values",
                    {"count": lambda c, r, b: Arg(4), "array": lambda c, r, b: Arg(np.zeros(3))},
                    default="omit",
                ),
            ],
            baseline=chain_q,
            expect=REJECT,
            why="",
            probe=needs_seven,
        )
        register(
            name=f"Chain.ik_nearest_free{tag}",
            covers="spotkin.Chain.ik_nearest_free",
            call=lambda c, get=get, **k: get(c).ik_nearest_free(**k),
            slots=[
                Batch("T", (4, 4), pose="T"),
                angle_slot("seed", dof),
                Int("free_joint", 1, 0, 7),
                Custom("values", {"count": lambda c, r, b: Arg(4)}, default="omit"),
            ],
            baseline=chain_q,
            expect=REJECT,
            why="",
            probe=needs_seven,
        )
        target = (
            Batch("target", (3,), aliases=("p",))
            if dof == 3
            else Batch("target", (4, 4), pose="T", aliases=("T",))
        )
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.ik{tag}",
            covers="spotkin.Chain.ik",
            call=lambda c, get=get, **k: get(c).ik(**k),
            slots=[
                target,
                angle_slot("seed", dof, optional=True, default="omit"),
                # a held joint is for 7-joint chains: refused here, and free_value alone too
                Custom("free_joint", {"two": lambda c, r, b: Arg(2, REJECT, "value")}, default="omit"),
                Custom("free_value", {"value": lambda c, r, b: Arg(0.3, REJECT, "value")}, default="omit"),
                OutSlot(("float", (dof,)), ("status", ()), drivers=["target"]),
            ],
            baseline=chain_q,
            outputs=outs(("float", (dof,)), ("status", ())),
            check=lambda x, out, kw, c, fkp=(point_fk if dof == 3 else pose_fk), lim=limits_of, d=dof: (
                nearest_check(fkp(c), lambda x: x["target"] if d == 3 else pose_matrix(x["target"]), lim(c))(
                    x, out, kw, c
                )
            ),
        )

        def ikd_check(x, out, kw, c, get=get):
            q, converged, _, pos_err, ori_err, residual = out
            T = pose_matrix(x["T_targets"])
            with np.errstate(all="ignore"):
                actual = np.linalg.norm(get(c).fk(q.astype(np.float64))[:3, 3] - T[:3, 3])
            if not (finite(q) and finite(ori_err) and (finite(pos_err) or not finite([actual]))):
                return f"non-finite result for a valid target: q {q}, errors {pos_err}, {ori_err}"
            if q.dtype == np.float64 and abs(actual - pos_err) > 1e-9:
                return f"position_error {pos_err} but |p_target - fk(q)| = {actual}"
            if finite([actual]) and not residual >= 0:
                return f"residual {residual} for a valid target"
            if finite([actual]) and residual > np.hypot(pos_err, ori_err) * (1 + 1e-9) + 1e-12:
                return f"residual {residual} above the error it is part of ({pos_err}, {ori_err})"
            if converged and pos_err > kw.get("position_tolerance", 1e-6) * (1 + 1e-9):
                return f"converged with position_error {pos_err}"
            if (
                converged
                and kw.get("task", "pose") == "pose"
                and ori_err > kw.get("orientation_tolerance", 1e-6) * (1 + 1e-9)
            ):
                return f"converged with orientation_error {ori_err}"
            return None

        ikd_skip = ("batch2x1", "single", "list", "nan_single", "scalar", "zero_d", "empty2", "valid")
        register(
            light=key in URDF_CHAINS,  # the DH chains' kernels
            name=f"Chain.ik_differential{tag}",
            covers="spotkin.Chain.ik_differential",
            call=lambda c, get=get, **k: get(c).ik_differential(**k),
            slots=[
                Batch("T_targets", (4, 4), pose="T", default="batch", skip=("batch2x1",), quat_ok=False),
                angle_slot("q0", dof, default="batch", skip=ikd_skip, equiv=lambda s, c: None),
                Choice(
                    "task",
                    "pose" if dof == 6 else "position",
                    ("pose", "position"),
                    default="omit" if dof == 6 else "valid",
                ),
                Real("damping", 1e-2, default="omit"),
                Real("position_tolerance", 1e-6, "nonneg", default="omit"),
                Real("orientation_tolerance", 1e-6, "nonneg", default="omit"),
                Int("max_iter", 100, 0, default="omit", skip=("huge",)),
                Real("max_step", 0.5, default="omit"),
            ],
            baseline=chain_q,
            mixed="f64",
            pair_rule=ikd_pairs,
            outputs=outs(("float", (dof,)), ("flag", ()), ("int", ()), ("f64", ()), ("f64", ()), ("f64", ())),
            check=ikd_check,
        )

        if key not in ("mdh3", "mdh6"):
            continue

        def path_base(c, rng, n, get=get, dof=dof):
            chain = get(c)
            limits = np.stack([chain.lower, chain.upper], axis=1)
            q = in_limits(limits, rng, n * 3, margin=0.3).reshape(n, 3, dof)
            q[:, 1:] = q[:, :1] + 0.1 * (q[:, 1:] - q[:, :1])  # a short path
            return {"T_targets": chain.fk(q), "q0": q[:, 0] + rng.normal(0, 0.05, (n, dof))}

        def path_check(x, out, kw, c, ikd_check=ikd_check):
            q, converged, iterations, pos_err, ori_err, residual = out
            for k, target in enumerate(x["T_targets"]):
                ok = pose_validity(target)
                if ok is None:
                    return None
                if not ok:
                    if not all_nan(q[k]) or converged[k]:
                        return f"target {k} is invalid but q {q[k]}, converged {converged[k]}"
                    return None  # the path after an invalid target is not specified
                if not finite(x["q0"]):
                    return None if all_nan(q) else f"a NaN/Inf q0 but q {describe(q)}"
                message = ikd_check(
                    {"T_targets": target},
                    [q[k], converged[k], iterations[k], pos_err[k], ori_err[k], residual[k]],
                    kw,
                    c,
                )
                if message:
                    return f"target {k}: {message}"
            return None

        register(
            name=f"Chain.ik_differential{tag[:-1]}:path]",
            covers="spotkin.Chain.ik_differential",
            call=lambda c, get=get, **k: get(c).ik_differential(**k),
            slots=[
                Batch(
                    "T_targets",
                    (3, 4, 4),
                    valid=lambda s: True,
                    default="batch",
                    skip=("trailing_minus", "valid", "single", "list", "nan_single"),
                ),
                angle_slot("q0", dof, default="batch", equiv=lambda s, c: None, skip=("batch2x1", "empty2")),
                Choice(
                    "task",
                    "pose" if dof == 6 else "position",
                    ("pose", "position"),
                    default="omit" if dof == 6 else "valid",
                ),
                Real("damping", 1e-2, default="omit"),
                Real("position_tolerance", 1e-6, "nonneg", default="omit"),
                Real("orientation_tolerance", 1e-6, "nonneg", default="omit"),
                Int("max_iter", 100, 0, default="omit", skip=("huge",)),
                Real("max_step", 0.5, default="omit"),
            ],
            baseline=path_base,
            mixed="f64",
            nan_rule="check",
            check=path_check,
            outputs=outs(("float", (3, dof)), ("flag", (3,)), ("int", (3,)), *[("f64", (3,))] * 3),
        )

    # constructors
    def chain_probe(chain, kw, ctx):
        if not isinstance(chain, sk.Chain):
            return f"not a Chain: {describe(chain)}"
        q = np.zeros(chain.dof)
        T = chain.fk(q)
        if not finite(T) or rigid_error(T) > 1e-9:
            return f"fk(0) is not a finite rigid transform: {describe(T)}"
        if not close(pickle.loads(pickle.dumps(chain)).fk(q), T, False):
            return "a pickled copy differs"
        return None

    rigid_extra = {k: v for k, v in tool_extra.items()}
    rows_extra = {
        "sigma2": (lambda c, v: np.vstack([[2, 0, 0, 0, 0], v[1:]]), REJECT, "value"),
        "sigma_half": (lambda c, v: np.vstack([[0.5, 0, 0, 0, 0], v[1:]]), REJECT, "value"),
        "sigma_neg": (lambda c, v: np.vstack([[-1, 0, 0, 0, 0], v[1:]]), REJECT, "value"),
        "four_cols": (lambda c, v: v[:, :4], REJECT, "shape"),
        "one_row": (lambda c, v: v[:1], ACCEPT, ""),
        "zero_rows": (lambda c, v: np.zeros((0, 5)), EITHER, ""),
        "many_rows": (lambda c, v: np.tile(v, (24, 1)), EITHER, ""),
        "prismatic": (lambda c, v: np.vstack([[1, 0.1, 0, 0.2, 0], v[1:]]), ACCEPT, ""),
        "ragged": (lambda c, v: [list(v[0]), list(v[1][:4])], REJECT, ""),
    }
    rows = Array("rows", lambda c: CHAIN_ROWS["mdh3"], extra=rows_extra)
    base = Array("base", lambda c: np.eye(4), optional=True, default="omit", extra=rigid_extra)
    tool = Array("tool", lambda c: np.eye(4), optional=True, default="omit", extra=rigid_extra)
    limits = Array(
        "limits",
        lambda c: LEG_LIMITS,
        inf_ok=True,
        optional=True,
        default="omit",
        extra={
            "inverted": (lambda c, v: v[:, ::-1], REJECT, "value"),
            "unbounded": (lambda c, v: [[-np.inf, np.inf]] * 3, ACCEPT, ""),
        },
    )
    register(
        name="Chain",
        covers="spotkin.Chain",
        call=lambda c, **k: sk.Chain(**k),
        slots=[rows, Choice("convention", "mdh", ("mdh", "dh"), default="omit"), base, tool, limits],
        probe=chain_probe,
        overflow_ok=True,
        pair_rule=dof_changes,
    )
    for method in ("from_mdh", "from_dh"):
        register(
            name=f"Chain.{method}",
            covers=f"spotkin.Chain.{method}",
            call=lambda c, method=method, **k: getattr(sk.Chain, method)(**k),
            slots=[rows, base, tool, limits],
            probe=chain_probe,
            overflow_ok=True,
            pair_rule=dof_changes,
        )
