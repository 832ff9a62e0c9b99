"""The cases of an entry: which variants of which slots, for CI and for exhaustive runs."""

from __future__ import annotations

import itertools
import json
import zlib

import numpy as np

from .entry import Entry
from .slots import REPEATED, SHAPES, Slot


def case_seed(seed: int, *parts) -> int:
    return zlib.crc32(json.dumps([seed, *parts]).encode())


CI_PAIRS = 40  # random pairs of variants of two slots per entry in CI mode


# CI variants of a batch slot of a "light" entry (the same code as another entry's, on another robot):
# the layouts, dtypes and objects that take other paths, every shape, NaN and huge values
LIGHT = {
    "single",
    "batch",
    "batch2x1",
    "empty",
    "list",
    "zero_stride",
    "neg_stride",
    "fortran",
    "float32",
    "float32_nan",
    "int64",
    "bool",
    "complex128",
    "str_array",
    "object_array",
    "nan",
    "inf",
    "nan_all",
    "nan_single",
    "big",
    "subnormal",
    "mag_1e15",
    "mag_1e300",
    *SHAPES,
    "none",
    "str",
    "masked",
    "huge_batch",
    "pose:matrix",
    "pose:quat",
    "pose:rot_scaled",
    "pose:quat_nonunit",
    "pose:last_row",
}
LIGHT_PAIRS = 12


def ci_variants(entry: Entry, slot: Slot) -> list[str]:
    names = slot.variants(False)
    if entry.light and slot.batch:
        names = [n for n in names if n in LIGHT or n in slot.extra]
    return names


def cases_for(entry: Entry, exhaustive: bool, seed: int) -> list[dict]:
    """The cases of one entry: its baseline; each variant of each slot (others at baseline; the
    randomly placed values three times); the combos; :data:`CI_PAIRS` random pairs of variants of two
    slots. Exhaustive mode: every variant three times, and every pair of variants of every two slots.
    A ``light`` entry runs in CI the :data:`LIGHT` variants of its batch slots, once each, and
    :data:`LIGHT_PAIRS` pairs (exhaustive mode: everything)."""
    plans = [[]]
    for slot in entry.slots:
        plans += [[[slot.name, v]] for v in (slot.variants(True) if exhaustive else ci_variants(entry, slot))]
    batch = [s for s in entry.slots if s.batch]
    for combo in entry.combos:
        if isinstance(combo, str):
            if batch:
                plans.append([["*", combo]])
        else:
            plans.append([["*", combo[0]]])
    if exhaustive:
        for a, b in itertools.combinations(entry.slots, 2):
            for va in a.variants(True):
                plans += [[[a.name, va], [b.name, vb]] for vb in b.variants(True)]
    elif len(entry.slots) >= 2:
        rng = np.random.default_rng(case_seed(seed, entry.name, "pairs"))
        for _ in range(entry.pairs if entry.pairs is not None else LIGHT_PAIRS if entry.light else CI_PAIRS):
            a, b = (entry.slots[k] for k in rng.choice(len(entry.slots), 2, replace=False))
            plans.append(
                [
                    [a.name, str(rng.choice(ci_variants(entry, a)))],
                    [b.name, str(rng.choice(ci_variants(entry, b)))],
                ]
            )
    cases = []
    for plan in plans:
        reps = 1 if len(plan) != 1 else 3 if exhaustive or (plan[0][1] in REPEATED and not entry.light) else 1
        for rep in range(reps):
            cases.append(
                {"entry": entry.name, "variants": plan, "seed": case_seed(seed, entry.name, plan, rep)}
            )
    return cases


def label(case: dict) -> str:
    plan = ", ".join(f"{s}={v}" for s, v in case["variants"]) or "baseline"
    return f"{case['entry']}({plan})"
