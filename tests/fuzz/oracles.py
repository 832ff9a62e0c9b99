"""Oracle helpers shared by the registry's entries: NaN and limit checks, tolerances, the default rule
for an invalid sample, and the checks of inverse-kinematics solutions (fk(q) on the target)."""

from __future__ import annotations

import numpy as np

from .outputs import describe
from .slots import ACCEPT, INVALID, JOINT_LIMIT, OK, REJECT, UNREACHABLE, Arg, Custom, finite


def all_nan(a) -> bool:
    return bool(np.isnan(np.asarray(a, dtype=np.float64)).all())


def within(q, limits, tol=1e-9) -> bool:
    limits = np.asarray(limits)
    q = np.asarray(q, dtype=np.float64)
    return bool(np.all(q >= limits[:, 0] - tol) & np.all(q <= limits[:, 1] + tol))


def tol_for(*arrays, base=1e-7, f32=1e-3):
    return f32 if any(np.asarray(a).dtype == np.float32 for a in arrays) else base


def rigid_error(T) -> float:
    T = np.asarray(T, dtype=np.float64)
    R = T[..., :3, :3]
    err = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max()
    return float(max(err, np.abs(T[..., 3, :] - [0, 0, 0, 1]).max()))


def default_nan_rule(x, out, kw, ctx, spec):
    for leaf, o in zip(out, spec):
        if o.kind in ("float", "f64", "hand") and leaf is not None and not all_nan(leaf):
            how = "partly NaN" if np.isnan(np.asarray(leaf, dtype=np.float64)).any() else "no NaN"
            return f"{how}: a leaf ({o.kind} {o.trailing}) is not all NaN: {describe(leaf)}"
        if o.kind == "flag" and np.asarray(leaf).any():
            return f"a validity flag is True: {describe(leaf)}"
        if o.kind in ("status", "stance") and not np.all(np.asarray(leaf) == INVALID):
            return f"status is not INVALID_INPUT: {describe(leaf)}"
    return None


def frame_slot(dof: int, name: str) -> Custom:
    """``point`` / ``frame`` of Chain.jacobian: a frame index in [0, dof + 1] or a word."""
    words = ("tool",) if name == "point" else ("base", "tool")

    def arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    table = {
        "valid": arg("tool" if name == "point" else "base"),
        **{f"word:{w}": arg(w) for w in words},
        "first": arg(0),
        "middle": arg(dof // 2 + 1),
        "last": arg(dof + 1),
        "np_int": arg(np.int64(1)),
        "above": arg(dof + 2, REJECT, "value"),
        "negative": arg(-1, REJECT, "value"),
        "huge": arg(2**70, REJECT, "value"),
        "wrong_word": arg("world", REJECT, "value"),
        "float": arg(1.0, REJECT, "type"),
        "bool": arg(True, REJECT, "type"),
        "none": arg(None, REJECT, "type"),
        "list": arg([1], REJECT, "type"),
    }
    return Custom(name, table, default="omit")


def finite_check(x, out, kw, ctx):
    for leaf in out:
        if leaf is not None and np.asarray(leaf).dtype.kind == "f" and not finite(leaf):
            return f"non-finite output for finite input: {describe(leaf)}"
    return None


def nan_rule_rank(x, out, kw, ctx, spec):
    return None if np.all(np.asarray(out[0]) == -1) else f"rank is not -1: {out[0]}"


def solution_check(fk, target_of, limits, fallback_ok=False):
    """ik_all-style (q (S, n), valid, exists[, exact], status): q finite exactly where it exists,
    fk(q) on target, valid = exists and within limits, exact only where it exists, status consistent."""

    def check(x, out, kw, ctx):
        q, valid, exists, status = out[0], out[1], out[2], out[-1]
        if len(out) == 5 and np.any(np.asarray(out[3]) & ~np.asarray(exists)):
            return f"exact {out[3]} where no solution exists {exists}"
        status = int(status)
        target = target_of(x)
        tol = tol_for(*x.values())
        if status == INVALID:
            return "INVALID_INPUT for a valid target"
        for k in range(len(q)):
            if exists[k]:
                if not finite(q[k]):
                    return f"slot {k} exists but q is {q[k]}"
                if np.abs(fk(q[k].astype(np.float64)) - target).max() > tol * max(1.0, np.abs(target).max()):
                    return f"slot {k}: fk(q) is not the target (q = {q[k]})"
                if valid[k] and not within(q[k], limits, 1e-6):
                    return f"slot {k} valid but outside the limits: {q[k]}"
            else:
                if not all_nan(q[k]):
                    return f"slot {k} does not exist but q is {q[k]}"
                if valid[k]:
                    return f"slot {k} valid but does not exist"
        expected = OK if valid.any() else JOINT_LIMIT if exists.any() else UNREACHABLE
        if status != expected:
            return f"status {status} for valid {valid}, exists {exists}"
        return None

    return check


def nearest_check(fk, target_of, limits, fallback_finite=False):
    """(q, status) with q finite iff OK (or, with fallback_finite, UNREACHABLE in the limits)."""

    def check(x, out, kw, ctx):
        q, status = out
        status = int(status)
        target = target_of(x)
        tol = tol_for(*x.values())
        if status == INVALID:
            return "INVALID_INPUT for a valid input"
        if status == OK:
            if not finite(q):
                return f"OK with q {q}"
            if np.abs(fk(q.astype(np.float64)) - target).max() > tol * max(1.0, np.abs(target).max()):
                return f"OK but fk(q) is not the target (q = {q})"
            if not within(q, limits, 1e-6):
                return f"OK but q outside the limits: {q}"
        elif status == UNREACHABLE and fallback_finite and kw.get("fallback", "nearest") == "nearest":
            if not finite(q) or not within(q, limits, 1e-6):
                return f"UNREACHABLE fallback not finite in the limits: {q}"
        elif not all_nan(q):
            return f"status {status} with q {q}"
        return None

    return check
