"""Registry entries of spotkin's functions: transforms, poses, the linear-algebra helpers and the
thread settings."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import register, seq_slot
from .objects import body_poses, pose_matrix, quat_matrix, rigid, rotations, unit_quats
from .oracles import all_nan, nan_rule_rank, tol_for
from .outputs import Out, OutSlot, close, describe, outs
from .slots import ACCEPT, EITHER, REJECT, Arg, Flag, Int, Real, finite, pose_validity


def dls_pairs(plan):
    """J with another column count n: a nullspace (n,) of the baseline's length no longer fits."""
    if plan["J"] in ("shape:n1", "shape:n64", "shape:square") and plan["nullspace"] not in ("omit", "none"):
        return EITHER if plan["nullspace"] in ("trailing_minus", "trailing_plus") else REJECT
    return None


def function_entries():
    def transform_base(c, rng, n):
        return {
            "p": rng.normal(size=(n, 3)),
            "R": rotations(rng, n),
            "angle": rng.uniform(-3, 3, n),
            "position": rng.normal(size=(n, 3)),
            "quat_xyzw": unit_quats(rng, n),
            "body_pose": body_poses(rng, n),
        }

    def reference(make):
        def check(x, out, kw, c):
            if not all(finite(v) for v in x.values()) and all_nan(out[0]):
                return None  # NaN in, NaN out for the whole sample
            ref = make(x, kw)
            if ref is None:
                return None
            if not close(out[0], ref, tol_for(*x.values()) > 1e-6):
                return f"{describe(out[0])} differs from the reference {describe(ref)}"
            return None

        return check

    def translation_ref(x, kw):
        T = np.eye(4)
        T[:3, 3] = x["p"]
        return T

    register(
        name="translation",
        covers="spotkin.translation",
        call=lambda c, **k: sk.translation(**k),
        slots=[Batch("p", (3,))],
        baseline=transform_base,
        outputs=outs(("f64", (4, 4))),
        nan_rule="check",
        check=reference(translation_ref),
    )
    for axis, fn in enumerate((sk.rotation_x, sk.rotation_y, sk.rotation_z)):

        def rot_ref(x, kw, axis=axis):
            a = float(x["angle"])
            cs, sn = (math.cos(a), math.sin(a)) if math.isfinite(a) else (math.nan, math.nan)
            i, j = [(1, 2), (2, 0), (0, 1)][axis]
            T = np.eye(4)
            T[i, i] = T[j, j] = cs
            T[j, i], T[i, j] = sn, -sn
            return T

        register(
            name=fn.__name__,
            covers=f"spotkin.{fn.__name__}",
            call=lambda c, fn=fn, **k: fn(**k),
            slots=[Batch("angle", (), angles=True)],
            baseline=transform_base,
            outputs=outs(("f64", (4, 4))),
            nan_rule="check",
            check=reference(rot_ref),
        )

    register(
        name="transform",
        covers="spotkin.transform",
        call=lambda c, **k: sk.transform(**k),
        slots=[Batch("R", (3, 3)), Batch("p", (3,))],
        baseline=transform_base,
        outputs=outs(("f64", (4, 4))),
        nan_rule="check",
        check=reference(lambda x, kw: rigid(x["R"], x["p"])),
    )

    def body_transform_ref(x, kw):
        pose = np.asarray(x["body_pose"], dtype=np.float64)
        ok = pose_validity(pose)
        if ok is None:
            return None
        if not ok:
            return np.full((4, 4), np.nan)
        return pose_matrix(pose, kw.get("seq", "XYZ"))

    register(
        name="body_transform",
        covers="spotkin.body_transform",
        call=lambda c, **k: sk.body_transform(**k),
        slots=[
            Batch(
                "body_pose",
                (6,),
                pose="body",
                angles=np.array([False] * 3 + [True] * 3),
                valid=lambda s: True,
            ),
            seq_slot(),
            OutSlot(("f64", (4, 4))),
        ],
        baseline=transform_base,
        outputs=outs(("f64", (4, 4))),
        nan_rule="check",
        check=reference(body_transform_ref),
    )

    def pose_from_ref(x, kw):
        q = np.asarray(x["quat_xyzw"], dtype=np.float64)
        p = np.asarray(x["position"], dtype=np.float64)
        if not finite(q) or not finite(p):
            return np.full((4, 4), np.nan)
        err = abs(math.sqrt(float(q @ q)) - 1)
        if 1e-7 < err < 1e-5:
            return None
        return rigid(quat_matrix(q), p) if err <= 1e-7 else np.full((4, 4), np.nan)

    register(
        name="pose_from",
        covers="spotkin.pose_from",
        call=lambda c, **k: sk.pose_from(**k),
        slots=[Batch("position", (3,)), Batch("quat_xyzw", (4,))],
        baseline=transform_base,
        outputs=outs(("f64", (4, 4))),
        nan_rule="check",
        check=reference(pose_from_ref),
    )

    def unpack_ref(x, kw):  # element by element: A[i, j] = A[j, i] = packed[i (i + 1) / 2 + j], j <= i
        packed, A = np.asarray(x["packed"], dtype=np.float64), np.empty((6, 6))
        for i in range(6):
            for j in range(i + 1):
                A[i, j] = A[j, i] = packed[i * (i + 1) // 2 + j]
        return A

    def unpack_check(x, out, kw, c):
        want = unpack_ref(x, kw)
        got = np.asarray(out[0], dtype=np.float64)
        if not np.array_equal(got, want, equal_nan=True):  # a copy: exact, NaN where its element is
            return f"{describe(out[0])} differs from the reference {describe(want)}"
        return None

    register(
        name="unpack_symmetric",
        covers="spotkin.unpack_symmetric",
        call=lambda c, **k: sk.unpack_symmetric(**k),
        # (..., 21, 1) is a valid batch of 1 x 1 matrices (any triangular width is): not a bad shape here
        slots=[Batch("packed", (21,), skip=("extra_dim",))],
        baseline=lambda c, rng, n: {"packed": rng.normal(size=(n, 21))},
        outputs=outs(("float", (6, 6))),
        nan_rule="check",
        check=unpack_check,
    )

    # differential
    def diff_base(c, rng, n):
        return {
            "J": rng.normal(size=(n, 3, 4)),
            "dx": rng.normal(size=(n, 3)),
            "nullspace": rng.normal(size=(n, 4)),
        }

    def j_variant(make, expect=ACCEPT):
        def build(slot, c, rng, base):
            J = make(base["J"].copy(), rng)
            if expect != ACCEPT:
                return Arg(J, expect, "shape")
            return slot._arg(J, (len(J),))

        return build

    def zero_row(J, rng):
        J[1, 2] = 0.0
        return J

    def zero_matrix(J, rng):
        J[1] = 0.0
        return J

    j_extra = {
        "shape:n1": j_variant(lambda J, r: J[..., :1].copy()),
        "shape:n64": j_variant(lambda J, r: r.normal(size=(3, 3, 64))),
        "shape:square": j_variant(lambda J, r: J[..., :3].copy()),
        "shape:n65": j_variant(lambda J, r: r.normal(size=(3, 3, 65)), REJECT),
        "shape:m0": j_variant(lambda J, r: np.zeros((3, 0, 4)), REJECT),
        "shape:n0": j_variant(lambda J, r: np.zeros((3, 3, 0)), REJECT),
        "rank_deficient": j_variant(zero_row),
        "zeros": j_variant(zero_matrix),
    }

    def J_slot(**kw):  # n is free: the shape variants are the extras
        return Batch("J", (3, 4), extra=j_extra, skip=("trailing_plus", "trailing_minus", "extra_dim"), **kw)

    def jshape(args):
        a = args["J"]
        return a.plain.shape[-2:] if a.present else (3, 4)

    def diff_check(ref_fn, f32_tol=2e-3):
        def check(x, out, kw, c):
            J = np.asarray(x["J"], dtype=np.float64)
            got = np.asarray(out[0], dtype=np.float64)
            try:
                with np.errstate(all="ignore"):
                    ref = ref_fn(x, kw, J)
            except np.linalg.LinAlgError:
                ref = None
            f32 = tol_for(*x.values()) > 1e-6
            if ref is not None and (
                not finite(ref) or (f32 and np.abs(ref).max() > np.finfo(np.float32).max)
            ):
                return None  # the formula itself overflows (in the working dtype): any answer
            dtype = np.float32 if f32 else np.float64
            largest = max(float(np.abs(np.asarray(v, dtype=np.float64)).max(initial=0)) for v in x.values())
            if not finite(got) and largest > math.sqrt(np.finfo(dtype).max):
                return None  # products of such entries overflow in the working dtype
            if not finite(got):
                return f"non-finite result for a finite J: {describe(got)}"
            if ref is None:
                return None
            scale = max(1.0, float(np.abs(ref).max()), largest)  # rounding grows with the inputs
            tol = (f32_tol if f32 else 1e-8) * scale
            if np.abs(got - ref).max() > tol * max(1.0, np.linalg.cond(J) if J.size else 1.0):
                return f"{describe(got)} differs from NumPy's {describe(ref)}"
            return None

        return check

    def pinv(J):
        return np.linalg.pinv(J)

    def dls_ref(x, kw, J):
        lam = float(kw.get("damping", 1e-3))
        dx = np.asarray(x["dx"], dtype=np.float64)
        m, n = J.shape
        if lam * lam == 0:
            dq = pinv(J) @ dx
        elif m > n:  # the same vector, from the well-conditioned n x n system
            dq = np.linalg.solve(J.T @ J + lam * lam * np.eye(n), J.T @ dx)
        else:
            dq = J.T @ np.linalg.solve(J @ J.T + lam * lam * np.eye(m), dx)
        if "nullspace" in x:
            dq = dq + (np.eye(n) - pinv(J) @ J) @ np.asarray(x["nullspace"], dtype=np.float64)
        return dq

    register(
        name="dls",
        pair_rule=dls_pairs,
        covers="spotkin.dls",
        call=lambda c, **k: sk.dls(**k),
        slots=[
            J_slot(),
            Batch("dx", (3,)),
            Real("damping", 1e-3, "nonneg", default="omit"),
            Batch("nullspace", (4,), optional=True, default="omit"),
            Flag("return_residual", default="omit"),
        ],
        baseline=diff_base,
        outputs=lambda args, kw: (
            [Out("float", (jshape(args)[1],))]
            + ([Out("float", ())] if kw.get("return_residual") in (True, np.True_) else [])
        ),
        mixed="f64",
        check=diff_check(dls_ref),
    )

    def compatible_check(x, out, kw, c):
        ok, residual = bool(out[0]), float(out[1])
        J = np.asarray(x["J"], dtype=np.float64)
        dx = np.asarray(x["dx"], dtype=np.float64)
        f32 = tol_for(*x.values()) > 1e-6
        eps = np.finfo(np.float32 if f32 else np.float64).eps
        with np.errstate(all="ignore"):
            U, sigma, _ = np.linalg.svd(J)
            cutoff = max(J.shape) * eps * sigma.max(initial=0)
            if ((sigma > 1e-3 * cutoff) & (sigma < 1e6 * cutoff)).any():
                return None  # a singular value near the rank cutoff: either rank is right
            rank = int((sigma > cutoff).sum())
            expected = float(np.linalg.norm(U[:, rank:].T @ dx))
        if not math.isfinite(expected) or not math.isfinite(residual):
            return None if not math.isfinite(expected) else f"non-finite residual {residual} for finite input"
        scale = max(1.0, float(np.abs(dx).max()))
        if abs(residual - expected) > (2e-3 if f32 else 1e-8) * scale:
            return f"residual {residual}, expected {expected}"
        if "tol" in kw and kw["tol"] is not None and ok != (residual <= float(kw["tol"])):
            return f"compatible {ok} but residual {residual} against tol {kw['tol']}"
        return None

    register(
        name="compatible",
        covers="spotkin.compatible",
        call=lambda c, **k: sk.compatible(**k),
        slots=[J_slot(), Batch("dx", (3,)), Real("tol", 1e-3, "nonneg", optional=True, default="omit")],
        baseline=diff_base,
        outputs=outs(("flag", ()), ("float", ())),
        mixed="f64",
        check=compatible_check,
    )
    register(
        name="pinv",
        covers="spotkin.pinv",
        call=lambda c, **k: sk.pinv(**k),
        slots=[J_slot()],
        baseline=diff_base,
        outputs=lambda a, kw: [Out("float", jshape(a)[::-1])],
        check=diff_check(lambda x, kw, J: pinv(J)),
    )
    register(
        name="nullspace_projector",
        covers="spotkin.nullspace_projector",
        call=lambda c, **k: sk.nullspace_projector(**k),
        slots=[J_slot()],
        baseline=diff_base,
        outputs=lambda a, kw: [Out("float", (jshape(a)[1],) * 2)],
        check=diff_check(lambda x, kw, J: np.eye(J.shape[1]) - pinv(J) @ J),
    )
    register(
        name="singular_values",
        covers="spotkin.singular_values",
        call=lambda c, **k: sk.singular_values(**k),
        slots=[J_slot()],
        baseline=diff_base,
        outputs=lambda a, kw: [Out("float", (min(jshape(a)),))],
        check=diff_check(lambda x, kw, J: np.linalg.svd(J, compute_uv=False)),
    )

    def rank_check(x, out, kw, c):
        J = np.asarray(x["J"], dtype=np.float64)
        s = np.linalg.svd(J, compute_uv=False)
        tol = kw.get("tol")
        f32 = tol_for(*x.values()) > 1e-6
        if tol is None:
            tol = max(J.shape) * np.finfo(np.float32 if f32 else np.float64).eps * s.max(initial=0)
        near = np.abs(s - float(tol)) <= 1e-6 * max(float(tol), s.max(initial=0)) + (1e-5 if f32 else 0)
        if near.any():
            return None
        expected = int((s > float(tol)).sum())
        return (
            None if int(out[0]) == expected else f"rank {out[0]}, expected {expected} (sigma {s}, tol {tol})"
        )

    register(
        name="rank",
        covers="spotkin.rank",
        call=lambda c, **k: sk.rank(**k),
        slots=[J_slot(), Real("tol", 1e-3, "nonneg", optional=True, default="omit")],
        baseline=diff_base,
        outputs=outs(("int", ())),
        check=rank_check,
        nan_rule=nan_rule_rank,
    )

    def manip_ref(x, kw, J):
        m, n = J.shape
        return np.prod(np.linalg.svd(J, compute_uv=False)) if m <= n else 0.0

    register(
        name="manipulability",
        covers="spotkin.manipulability",
        call=lambda c, **k: sk.manipulability(**k),
        slots=[J_slot()],
        baseline=diff_base,
        outputs=outs(("float", ())),
        check=diff_check(manip_ref),
    )

    # threads
    max_threads = sk.MAX_THREADS

    def threads_probe(result, kw, c):
        if result is not None:
            return f"set_num_threads returned {describe(result)}"
        n = sk.get_num_threads()
        if not isinstance(n, int) or not 1 <= n <= max_threads:
            return f"get_num_threads() = {n!r} after set_num_threads({kw['n']!r})"
        J = np.random.default_rng(0).normal(size=(3000, 16, 16))
        many = sk.singular_values(J)
        sk.set_num_threads(1)
        one = sk.singular_values(J)
        if not np.array_equal(many, one):
            return "singular values differ between thread counts"
        return None

    def restore(c):
        sk.set_num_threads(1)

    register(
        name="set_num_threads",
        covers="spotkin.set_num_threads",
        call=lambda c, **k: sk.set_num_threads(**k),
        slots=[Int("n", 2, 1, max_threads + 1)],
        probe=threads_probe,
        after=restore,
    )
    register(
        name="get_num_threads",
        covers="spotkin.get_num_threads",
        call=lambda c: sk.get_num_threads(),
        probe=lambda n, kw, c: None if isinstance(n, int) and n >= 1 else f"get_num_threads() = {n!r}",
    )

    def limited(n):
        """(threads inside the block, after it, singular values computed inside)."""
        J = np.random.default_rng(0).normal(size=(3000, 16, 16))
        with sk.thread_limit(n):
            inside = sk.get_num_threads()
            values = sk.singular_values(J)
        return inside, sk.get_num_threads(), values

    def limit_probe(result, kw, c):
        inside, after, values = result
        setting = sk._core.get_num_threads()
        if inside != min(int(kw["n"]), setting) or after != setting:
            return f"thread_limit({kw['n']!r}): {inside} threads inside, {after} after (setting {setting})"
        if not np.array_equal(
            values, sk.singular_values(np.random.default_rng(0).normal(size=(3000, 16, 16)))
        ):
            return "singular values differ inside the limit"
        return None

    register(
        name="thread_limit",
        covers="spotkin.thread_limit",
        call=lambda c, **k: limited(**k),
        slots=[Int("n", 2, 1, max_threads + 1)],
        probe=limit_probe,
    )
