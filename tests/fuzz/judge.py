"""Judging one case (in a worker): building the arguments, calling, and checking the outcome against
the documentation."""

from __future__ import annotations

import os
import re
import traceback
import warnings

import numpy as np

import spotkin as sk

from .entry import Entry
from .oracles import default_nan_rule, finite_check
from .outputs import close, describe, flatten
from .registry import BY_NAME
from .slots import (
    ACCEPT,
    ALLOWED,
    EITHER,
    INVALID,
    JOINT_LIMIT,
    MEMORY,
    OK,
    OMIT,
    REJECT,
    UNREACHABLE,
    finite,
)


def huge_argument(kw) -> bool:
    for value in kw.values():
        try:
            with np.errstate(all="ignore"):
                if np.abs(np.asarray(value, dtype=np.float64)).max(initial=0) >= 1e300:
                    return True
        except (TypeError, ValueError):
            continue
    return False


class Failure(Exception):
    def __init__(self, kind: str, detail: str):
        super().__init__(f"{kind}: {detail}")
        self.kind, self.detail = kind, detail


def _combo(entry: Entry, name: str) -> tuple[dict, str | None]:
    for combo in entry.combos:
        if isinstance(combo, tuple) and combo[0] == name:
            return dict(combo[1]), combo[2]
    batch = [s for s in entry.slots if s.batch]
    if name == "float32_all":
        return {s.name: "float32" for s in batch}, None
    if name == "batch_all":
        return {s.name: "batch" for s in batch}, None
    if name == "nan_all":
        plan = {s.name: "batch" for s in batch}
        plan[batch[0].name] = "nan"
        return plan, None
    raise KeyError(name)


def build_args(entry: Entry, case: dict, ctx) -> tuple[dict, str | None]:
    rng = np.random.default_rng(case["seed"])
    base = entry.baseline(ctx, rng, 3) if entry.baseline else {}
    plan, override = {}, None
    for slot_name, variant in case["variants"]:
        if slot_name == "*":
            combo, override = _combo(entry, variant)
            plan.update(combo)
        else:
            plan[slot_name] = variant
    if override is None and entry.pair_rule is not None:
        override = entry.pair_rule({s.name: plan.get(s.name, s.default) for s in entry.slots})
    args = {}
    for slot in entry.slots:
        args[slot.name] = slot.build(plan.get(slot.name, slot.default), ctx, rng, base)
    for slot in entry.slots:  # out=: from the other arguments' shapes and dtypes
        if getattr(slot, "after", False):
            args[slot.name] = slot.build_out(plan.get(slot.name, slot.default), args, entry)
    return args, override


def expectation(entry: Entry, args: dict, override) -> tuple[str, str, tuple]:
    """(expect, why, names): what the call must do, the error kind for a rejection, and the argument
    names the error message may use."""
    if override is not None:
        return override, "", ()
    if entry.expect == REJECT:
        return REJECT, entry.why, ()
    rejecting = [name for name, a in args.items() if a.expect == REJECT]
    batch = {n: a for n, a in args.items() if a.present}
    try:
        np.broadcast_shapes(*(a.lead for a in batch.values()))
        mismatch = False
    except ValueError:
        mismatch = True
    others = [a.expect for n, a in args.items() if n not in rejecting]
    if rejecting:
        if len(rejecting) == 1 and not mismatch and all(e == ACCEPT for e in others):
            name = rejecting[0]
            return REJECT, args[name].why, entry.slot(name).aliases
        return REJECT, "", ()  # another argument's error may come first
    if mismatch:
        if any(e != ACCEPT for e in others):
            return (
                REJECT,
                "",
                (),
            )  # that argument's own error (or the huge batch's MemoryError) may come first
        return REJECT, "shape", tuple(batch)
    if any(a.expect == MEMORY for a in args.values()):
        return MEMORY, "memory" if all(e in (ACCEPT, MEMORY) for e in others) else "", ()
    if any(a.expect == EITHER for a in args.values()):
        return EITHER, "", ()
    return ACCEPT, "", ()


def _names_in(message: str, names) -> bool:
    return any(re.search(rf"(?<![A-Za-z0-9_]){re.escape(n)}(?![A-Za-z0-9_])", message) for n in names)


def judge_error(error: BaseException, expect: str, why: str, names, also=()) -> None:
    kind, text = type(error).__name__, f"{type(error).__name__}: {error}"
    if isinstance(error, np.linalg.LinAlgError):
        raise Failure("LinAlgError", text)
    if isinstance(error, TypeError) and "incompatible function arguments" in str(error):
        raise Failure("pybind-signature-error", text.splitlines()[0])
    if why == "os" and expect == REJECT and not isinstance(error, OSError):
        raise Failure(f"unreadable file: {kind}, not OSError", text)
    if also and isinstance(error, also) and not isinstance(error, ALLOWED) and expect != ACCEPT:
        if why in ("type", "shape", "value", "memory"):
            raise Failure(f"raised {kind}, not {'TypeError' if why == 'type' else 'ValueError'}", text)
        return  # e.g. OSError for a file that cannot be read
    if not isinstance(error, ALLOWED):
        raise Failure(f"raised {kind}", text + "\n" + "".join(traceback.format_tb(error.__traceback__)[-3:]))
    if expect == ACCEPT:
        raise Failure(f"rejected valid input ({kind})", text)
    if expect == MEMORY and why == "memory" and not isinstance(error, MemoryError):
        raise Failure(f"huge batch: {kind}, not MemoryError", text)
    if expect == REJECT:
        if why == "type" and not isinstance(error, TypeError):
            raise Failure(f"non-numeric input: {kind}, not TypeError", text)
        if why in ("shape", "value") and not isinstance(error, ValueError):
            raise Failure(f"bad {why}: {kind}, not ValueError", text)
        if why in ("shape", "type") and names and not _names_in(str(error), names):
            raise Failure(f"{kind} does not name the argument", f"{text} (expected one of {list(names)})")


def call_entry(entry: Entry, ctx, kwargs: dict):
    """(result, error, warnings) of one call."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            return entry.call(ctx, **kwargs), None, list(caught)
        except BaseException as error:  # every exception is judged, KeyboardInterrupt and SystemExit too
            return None, error, list(caught)


def _leaf_sample(leaf, j):
    if leaf is None or isinstance(leaf, (sk.Status, sk.StanceStatus)):
        return leaf
    return np.asarray(leaf)[j]


def check_leaves(entry, leaves, spec, lead, want):
    if len(leaves) != len(spec):
        raise Failure("result structure", f"{len(leaves)} leaves, the documentation gives {len(spec)}")
    for i, (leaf, out) in enumerate(zip(leaves, spec)):
        where = f"leaf {i} ({out.kind})"
        if out.kind == "none":
            if leaf is not None:
                raise Failure("result structure", f"{where} should be None, got {describe(leaf)}")
            continue
        if out.kind in ("status", "stance") and lead + out.trailing == ():
            kind = sk.Status if out.kind == "status" else sk.StanceStatus
            if not isinstance(leaf, kind):
                raise Failure(
                    "status type",
                    f"{where}: a single target should get an sk.{kind.__name__}, got {describe(leaf)}",
                )
            continue
        if not isinstance(leaf, (np.ndarray, np.generic)):
            raise Failure("result type", f"{where}: {type(leaf).__name__}, not an ndarray")
        shape = lead + out.trailing
        if leaf.shape != shape:
            raise Failure("output shape", f"{where}: shape {leaf.shape}, expected {shape}")
        dt = leaf.dtype
        if out.kind == "float":
            expected = {"f32": (np.float32,), "f64": (np.float64,), "either": (np.float32, np.float64)}[want]
            if dt not in expected:
                raise Failure(
                    "output dtype",
                    f"{where}: {dt}, expected {' or '.join(map(str, map(np.dtype, expected)))}",
                )
        elif out.kind in ("f64", "hand") and dt != np.float64:
            raise Failure("output dtype", f"{where}: {dt}, documented float64")
        elif out.kind in ("flag", "bool") and dt != np.bool_:
            raise Failure("output dtype", f"{where}: {dt}, expected bool")
        elif out.kind in ("status", "stance"):
            if dt != np.int8:
                raise Failure("output dtype", f"{where}: status {dt}, expected int8")
            codes = (
                (OK, UNREACHABLE, JOINT_LIMIT, INVALID) if out.kind == "status" else tuple(sk.StanceStatus)
            )
            if not np.isin(leaf, codes).all():
                raise Failure("status value", f"{where}: {describe(leaf)}")
        elif out.kind == "int" and dt.kind not in "iu":
            raise Failure("output dtype", f"{where}: {dt}, expected an integer dtype")


def _without_out(kw: dict) -> dict:
    """The keywords of a call without its out= arrays (shaped for the whole batch)."""
    return {k: v for k, v in kw.items() if k != "out"}


def verify(entry: Entry, ctx, args: dict, kw: dict, result, expect: str) -> None:
    if entry.outputs is None:
        message = entry.probe(result, kw, ctx) if entry.probe else None
        if message and entry.overflow_ok and huge_argument(kw):
            message = None
        if message:
            raise Failure("accepted but wrong" if expect != ACCEPT else "wrong result", message)
        return
    batch = {n: a for n, a in args.items() if a.present}
    lead = tuple(np.broadcast_shapes(*(a.lead for a in batch.values()))) if batch else ()
    spec = entry.outputs(args, kw)
    leaves = flatten(result)
    drivers = [a.f32 for n, a in batch.items() if entry.slot(n).dtype_driver]
    want = "f32" if drivers and all(drivers) else "f64" if not any(drivers) else entry.mixed
    check_leaves(entry, leaves, spec, lead, want)
    f32 = any(a.f32 for a in batch.values())
    plains = {n: np.broadcast_to(a.plain, lead + a.plain.shape[len(a.lead) :]) for n, a in batch.items()}
    for count, j in enumerate(np.ndindex(*lead)):
        if count >= 8:
            break
        x = {n: np.array(p[j]) for n, p in plains.items()}
        out = [_leaf_sample(leaf, j) for leaf in leaves]
        where = f"sample {j}" if lead else "the single sample"
        judge_sample(entry, ctx, x, out, kw, spec, f32, where)
        if lead:
            single, error, _ = call_entry(entry, ctx, {**_without_out(kw), **x})
            if error is not None:
                raise Failure("single call fails", f"{where} alone raises {type(error).__name__}: {error}")
            for i, (a, b) in enumerate(zip(out, flatten(single))):
                if not close(a, b, f32):
                    raise Failure(
                        "batch differs from single calls",
                        f"{where}, leaf {i}: batch {describe(a)} but alone {describe(b)}; inputs "
                        f"{ {n: describe(v, 80) for n, v in x.items()} }",
                    )


def judge_sample(entry, ctx, x, out, kw, spec, f32, where):
    equivalent = {}
    out_f32 = any(isinstance(leaf, (np.ndarray, np.generic)) and leaf.dtype == np.float32 for leaf in out)
    for name, sample in x.items():
        # computed in float32: the angle is the float32 one, except a seed's, which is reduced
        # before it is narrowed (documented)
        if out_f32 and sample.dtype == np.float64 and name != "seed":
            sample = sample.astype(np.float32)
        replacement = entry.slot(name).equiv(sample, ctx)
        if replacement is not None:
            equivalent[name] = replacement
    if equivalent:
        ref, error, _ = call_entry(entry, ctx, {**_without_out(kw), **x, **equivalent})
        if error is None and all(close(a, b, f32) for a, b in zip(out, flatten(ref))):
            return
        if all(entry.slot(n).equiv_nan_ok for n in equivalent):
            # an angle bound: the huge angle counts as NaN (INVALID_INPUT where it lies, NaN results)
            beyond = {}
            for n, reduced in equivalent.items():
                value = np.array(x[n], dtype=np.asarray(reduced).dtype).astype(np.float64)
                value[np.asarray(reduced, dtype=np.float64) != value] = np.nan
                beyond[n] = value
            xb = {**x, **beyond}
            if entry.nan_rule == "check":
                if entry.check is None or entry.check(xb, out, kw, ctx) is None:
                    return
            else:
                rule = entry.nan_rule if callable(entry.nan_rule) else default_nan_rule
                if rule(xb, out, kw, ctx, spec) is None:
                    return
        others = {n: v for n, v in x.items() if n not in equivalent}
        if entry.overflow_ok and huge_argument(others) and not all(finite(a) for a in out):
            # 1e300 rates beside the huge angle: the results overflow (NaN, 1e282 torques), and the angle's
            # last bits (the check's reduced angle is narrowed to float32) move what is left of them
            return
        names = ", ".join(f"{n} = {describe(x[n], 60)}" for n in equivalent)
        reduced = ", ".join(f"{describe(v, 60)}" for v in equivalent.values())
        got = describe(out[0] if len(out) == 1 else out, 120)
        want = describe(flatten(ref)[0] if error is None else error, 120)
        raise Failure(
            "huge angle or time: result differs from the reduced input",
            f"{where}: {names} gives {got}; at {reduced}: {want}",
        )
    validity = True
    for name, sample in x.items():
        v = entry.slot(name).valid(sample)
        if v is False:
            validity = False
            break
        if v is None:
            validity = None
    if entry.nan_rule == "check":
        message = entry.check(x, out, kw, ctx) if entry.check else None
        tag = message.split(":")[0] if message and message.split(":")[0] in ("partly NaN", "no NaN") else ""
        kind = f"NaN/Inf/invalid input: {tag}" if tag else "documented result"
    elif validity is False:
        rule = entry.nan_rule if callable(entry.nan_rule) else default_nan_rule
        message = rule(x, out, kw, ctx, spec)
        tag = message.split(":")[0] if message and message.split(":")[0] in ("partly NaN", "no NaN") else ""
        kind = f"NaN/Inf/invalid input: {tag or 'not NaN/INVALID_INPUT'}"
    elif validity:
        message = (entry.check or finite_check)(x, out, kw, ctx)
        kind = "documented result"
    else:
        message = None
    if message:
        inputs = {n: describe(v, 90) for n, v in x.items()}
        raise Failure(kind, f"{where}: {message}; inputs {inputs}")


def run_case(case: dict, ctx) -> dict:
    entry = BY_NAME[case["entry"]]
    try:
        args, override = build_args(entry, case, ctx)
        expect, why, names = expectation(entry, args, override)
        kw = {n: a.value for n, a in args.items() if a.value is not OMIT}
        result, error, caught = call_entry(entry, ctx, kw)
        try:
            if caught:
                w = caught[0]
                raise Failure(
                    f"warning {w.category.__name__}",
                    f"{w.message} ({os.path.basename(w.filename)}:{w.lineno})",
                )
            if error is not None:
                judge_error(error, expect, why, names, entry.also_raises)
                return {"ok": True}
            if expect == REJECT:
                bad = [f"{n}={describe(a.value, 80)}" for n, a in args.items() if a.expect == REJECT]
                raise Failure(
                    "accepted invalid input",
                    f"{', '.join(bad) or 'the call'} accepted; got {describe(flatten(result)[0], 100)}",
                )
            if expect == MEMORY:
                raise Failure("huge batch accepted", "no MemoryError")
            if entry.outputs is not None and any(a.expect == REJECT for a in args.values()):
                return {"ok": True}  # a pair rule accepted a combination the samples cannot be cut from
            if kw.get("out") is not None:  # out= arrays are filled and returned, not copied
                given = kw["out"] if isinstance(kw["out"], tuple) else (kw["out"],)
                for i, (array, leaf) in enumerate(zip(given, flatten(result))):
                    if array is not None and leaf is not array:
                        raise Failure("out= not returned", f"leaf {i}: {describe(leaf)} is not the out array")
            verify(entry, ctx, args, kw, result, expect)
        finally:
            if entry.after:
                entry.after(ctx)
    except Failure as failure:
        return {"ok": False, "kind": failure.kind, "detail": failure.detail}
    except Exception as error:  # an oracle tripping over a result
        tb = "".join(traceback.format_exception(type(error), error, error.__traceback__)[-4:])
        return {"ok": False, "kind": f"oracle error ({type(error).__name__})", "detail": tb}
    return {"ok": True}
