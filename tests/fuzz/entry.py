""":class:`Entry`, one public callable bound to an object, and :data:`REGISTRY`, the list that
:func:`register` appends to (``fuzz.registry`` fills it, in order); the slot shorthands
:func:`angle_slot` and :func:`seq_slot`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import spotkin as sk

from .batch import Batch
from .slots import ACCEPT, Choice


@dataclass
class Entry:
    """One public callable on one object.

    ``call(ctx, **kwargs)`` makes the call. ``baseline(ctx, rng, n)`` gives n valid samples per batch
    slot. ``outputs(args, kw)`` lists the result's leaves (None: no batch semantics, ``probe`` judges).
    ``check(x, leaves, kw, ctx)`` judges one valid sample (x: the plain samples of the batch slots,
    leaves: that sample of each leaf); ``nan_rule`` one invalid sample (default: every float NaN,
    every flag False, every status INVALID_INPUT); ``nan_rule="check"``: ``check`` judges every
    sample. ``probe(result, kw, ctx)`` judges a result without batch semantics. ``mixed``: the
    output dtype when float32 and float64 inputs mix ("either" or "f64"). ``expect``: the baseline
    outcome (REJECT for a method this object does not support; ``why`` then names the error as for an
    argument). ``also_raises``: exceptions beyond ValueError/TypeError/MemoryError that a rejection
    may raise (OSError for a file that cannot be read). ``after(ctx)`` restores state.
    """

    name: str
    covers: str
    call: Callable
    slots: list = field(default_factory=list)
    baseline: Callable | None = None
    outputs: Callable | None = None
    check: Callable | None = None
    nan_rule: Any = None
    probe: Callable | None = None
    mixed: str = "either"
    expect: str = ACCEPT
    why: str = ""  # with expect=REJECT: the error every call must raise ("type", "value", "" either)
    after: Callable | None = None
    combos: tuple = ("float32_all", "batch_all", "nan_all")
    pair_rule: Callable | None = None  # plan {slot: variant} -> an expectation for dependent slots, or None
    overflow_ok: bool = False  # the probe may see Inf when an argument is near the largest float
    also_raises: tuple = ()
    light: bool = False  # CI: fewer variants (see cases_for)
    pairs: int | None = None  # CI: random pairs of variants (default CI_PAIRS, LIGHT_PAIRS if light)

    def slot(self, name):
        return next(s for s in self.slots if s.name == name)


# ---- the registry ------------------------------------------------------------------------------------

REGISTRY: list[Entry] = []


def register(**kw) -> Entry:
    entry = Entry(**kw)
    REGISTRY.append(entry)
    return entry


def angle_slot(name, dof, **kw):
    return Batch(name, (dof,), angles=True, **kw)


SEQS = sk.EULER_SEQUENCES


def seq_slot():
    return Choice("seq", "XYZ", SEQS, default="omit")
