"""Argument slots of the fuzz registry: the outcome constants, :class:`Arg` (one built argument and what
the documentation promises for it), :class:`Slot`, the names of the hostile variants, and the parameter
slots :class:`Real`, :class:`Int`, :class:`Choice`, :class:`Flag`, :class:`Array` and :class:`Custom`.
Batch arrays are :class:`fuzz.batch.Batch`; ``out=`` is :class:`fuzz.outputs.OutSlot`."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

OMIT = "<omitted>"  # a slot left out of the call (its default)
ACCEPT, REJECT, EITHER, MEMORY = "accept", "reject", "either", "memory"
OK, UNREACHABLE, JOINT_LIMIT, INVALID = 0, 1, 2, 3
HUGE_ANGLE = 64.0  # rad: angles beyond this are compared with their exact reduction
ALLOWED = (ValueError, TypeError, MemoryError)


# ---- arguments --------------------------------------------------------------------------------------


@dataclass
class Arg:
    """One built argument and what the documentation promises for it."""

    value: Any
    expect: str = ACCEPT
    why: str = ""  # for REJECT: "type" (TypeError), "shape" or "value" (ValueError), "" (either)
    lead: tuple | None = None  # batch slots: the leading shape of value
    plain: np.ndarray | None = None  # batch slots: the same numbers as a native array, lead + trailing
    f32: bool | None = None  # batch slots: float32 (either byte order)

    @property
    def present(self) -> bool:
        return self.lead is not None


def _f32(dtype) -> bool:
    return dtype.kind == "f" and dtype.itemsize == 4


class Slot:
    """An argument slot. ``default`` is the baseline variant (``"omit"``: left out)."""

    batch = False

    def __init__(self, name: str, *, optional: bool = False, aliases: tuple = (), default: str = "valid"):
        self.name = name
        self.optional = optional
        self.aliases = (name, *aliases)
        self.default = default

    def variants(self, exhaustive: bool) -> list[str]:
        raise NotImplementedError

    def build(self, variant: str, ctx, rng, base) -> Arg:
        raise NotImplementedError


# -- the variants of batch arrays (Batch) ------------------------------------------------------------

LAYOUT = [
    "single",
    "batch",
    "batch2x1",
    "empty",
    "empty2",
    "list",
    "nested_list",
    "tuple",
    "readonly",
    "zero_stride",
    "neg_stride",
    "neg_stride_inner",
    "fortran",
    "inner_strided",
]
DTYPES = [
    "float32",
    "float32_be",
    "float64_be",
    "float16",
    "longdouble",
    "int64",
    "int32",
    "int8",
    "uint8",
    "uint64",
    "bool",
]
BAD_DTYPES = [
    "complex128",
    "complex64",
    "complex_imag",
    "str_array",
    "bytes_array",
    "object_array",
    "datetime64",
    "timedelta64",
    "structured",
]
VALUES = [
    "nan",
    "inf",
    "-inf",
    "nan_all",
    "nan_single",
    "big",
    "-big",
    "subnormal",
    "neg_zero",
    "tiny",
    "mag_1e6",
    "mag_1e15",
    "mag_1e300",
]
SHAPES = ["scalar", "zero_d", "trailing_plus", "trailing_minus", "extra_dim", "flat", "ragged", "empty_flat"]
OBJECTS = ["none", "str", "bytes", "dict", "object", "masked", "masked_nomask", "huge_batch"]
EXHAUSTIVE_ONLY = {
    "tuple",
    "int32",
    "int8",
    "uint64",
    "longdouble",
    "neg_zero",
    "tiny",
    "mag_1e6",
    "empty2",
    "inner_strided",
    "bytes_array",
    "timedelta64",
    "bytes",
    "thousand",
}
REPEATED = {*VALUES, "float32_nan", "float32_inf", "float32_big", "masked"}  # random positions: 3 draws in CI
POSE_BAD = [
    "pose:rot_zero",
    "pose:rot_scaled",
    "pose:reflect",
    "pose:last_row",
    "pose:last_row_x",
    "pose:quat_nonunit",
    "pose:quat_zero",
    "pose:quat_near",
    "pose:almost_rigid",
]


def finite(sample) -> bool:
    return bool(np.isfinite(np.asarray(sample, dtype=np.float64)).all())


def pose_validity(x: np.ndarray, tol: float = 1e-6) -> bool | None:
    """A pose (4, 4) / (7,) / (6,) as the solvers read it: True rigid, False not, None borderline."""
    x = np.asarray(x, dtype=np.float64)
    if not np.isfinite(x).all():
        return False
    if x.shape == (6,):
        return True
    if x.shape == (7,):
        err = abs(math.sqrt(float(np.dot(x[3:], x[3:]))) - 1.0)
    else:
        R = x[:3, :3]
        if np.linalg.det(R) < 0:
            return False
        err = max(float(np.abs(R.T @ R - np.eye(3)).max()), float(np.abs(x[3] - [0.0, 0.0, 0.0, 1.0]).max()))
    if err <= tol / 10:
        return True
    return False if err > tol * 10 else None


def reduce_angle(x: float) -> float:
    """x reduced exactly into (-pi, pi] (libm's sin and cos reduce with the exact pi)."""
    return math.atan2(math.sin(x), math.cos(x))


# -- parameters --------------------------------------------------------------------------------------


class Real(Slot):
    """A real scalar parameter. ``rule``: "positive", "nonneg" or "finite" (all finite).
    ``vector``: the parameter may also be an (n,) array (n = vector)."""

    def __init__(self, name, valid, rule="positive", *, vector: int | None = None, skip=(), **kw):
        super().__init__(name, **kw)
        self.valid, self.rule, self.vector, self.skip = valid, rule, vector, set(skip)

    def variants(self, exhaustive):
        names = [
            "valid",
            "zero",
            "negative",
            "nan",
            "inf",
            "-inf",
            "big",
            "subnormal",
            "bool",
            "str",
            "none",
            "complex",
            "np_float32",
            "np_int",
            "int",
            "zero_d",
            "one_elem",
        ]
        if self.vector:
            names += ["vector", "vector_wrong", "vector_nan", "vector_2d"]
        if exhaustive:
            names += ["list", "np_bool", "big_int"]
        return [n for n in names if n not in self.skip]

    def build(self, variant, ctx, rng, base):
        v = self.valid
        if variant == "omit":
            return Arg(OMIT)
        table = {
            "valid": (v, ACCEPT, ""),
            "zero": (0.0, REJECT if self.rule == "positive" else ACCEPT, "value"),
            "negative": (-1.0, ACCEPT if self.rule == "finite" else REJECT, "value"),
            "nan": (math.nan, REJECT, "value"),
            "inf": (math.inf, REJECT, "value"),
            "-inf": (-math.inf, REJECT, "value"),
            "big": (1e308, EITHER, ""),
            "subnormal": (5e-324, EITHER, ""),
            "bool": (True, REJECT, ""),
            "np_bool": (np.True_, REJECT, ""),
            "str": (str(v), REJECT, ""),
            "none": (None, ACCEPT if self.optional else REJECT, ""),
            "complex": (complex(v, 0), REJECT, ""),
            "np_float32": (np.float32(v), ACCEPT, ""),
            "np_int": (np.int64(1), ACCEPT, ""),
            "int": (1, ACCEPT, ""),
            "big_int": (10**400, EITHER, ""),
            "zero_d": (np.array(v), ACCEPT if self.vector else EITHER, ""),
            "one_elem": (np.array([v]), EITHER, ""),
            "list": ([v], EITHER, ""),
        }
        if self.vector:
            table["vector"] = (np.full(self.vector, v), ACCEPT, "")
            table["vector_wrong"] = (np.full(self.vector + 1, v), REJECT, "shape")
            table["vector_nan"] = (np.array([v] * (self.vector - 1) + [math.nan]), REJECT, "value")
            table["vector_2d"] = (np.full((2, self.vector), v), REJECT, "shape")
        value, expect, why = table[variant]
        return Arg(value, expect, why)


class Int(Slot):
    """An integer parameter in [minimum, maximum) (maximum None: unbounded)."""

    def __init__(self, name, valid, minimum=0, maximum=None, *, skip=(), **kw):
        super().__init__(name, **kw)
        self.valid, self.minimum, self.maximum, self.skip = valid, minimum, maximum, set(skip)

    def variants(self, exhaustive):
        names = [
            "valid",
            "min",
            "below",
            "float",
            "float_integral",
            "bool",
            "str",
            "none",
            "big",
            "huge",
            "np_int",
            "np_float",
            "nan",
            "zero_d",
        ]
        if self.maximum is not None:
            names += ["max", "above"]
        return [n for n in names if n not in self.skip]

    def build(self, variant, ctx, rng, base):
        if variant == "omit":
            return Arg(OMIT)
        table = {
            "valid": (self.valid, ACCEPT, ""),
            "min": (self.minimum, ACCEPT, ""),
            "below": (self.minimum - 1, REJECT, "value"),
            "max": (None if self.maximum is None else self.maximum - 1, ACCEPT, ""),
            "above": (self.maximum, REJECT, "value"),
            "float": (1.5, REJECT, "type"),
            "float_integral": (float(self.valid), EITHER, ""),
            "bool": (True, REJECT, "type"),
            "str": (str(self.valid), REJECT, "type"),
            "none": (None, ACCEPT if self.optional else REJECT, "type"),
            "big": (2**63, EITHER, ""),
            "huge": (10**9, EITHER, ""),
            "np_int": (np.int64(self.valid), ACCEPT, ""),
            "np_float": (np.float64(1.5), REJECT, "type"),
            "nan": (math.nan, REJECT, ""),
            "zero_d": (np.array(self.valid), EITHER, ""),
        }
        value, expect, why = table[variant]
        if self.maximum is not None and variant in ("big", "huge"):
            expect, why = REJECT, "value"
        return Arg(value, expect, why)


class Choice(Slot):
    """An enum string among ``choices``."""

    def __init__(self, name, valid, choices, *, ci_choices: int = 6, **kw):
        super().__init__(name, **kw)
        self.valid, self.choices, self.ci_choices = valid, tuple(choices), ci_choices

    def variants(self, exhaustive):
        choices = list(self.choices)
        if not exhaustive and len(choices) > self.ci_choices:
            step = len(choices) / self.ci_choices
            choices = [choices[int(i * step)] for i in range(self.ci_choices)]
        names = [
            "valid",
            *[f"choice:{c}" for c in choices],
            "empty",
            "space",
            "swapcase",
            "wrong",
            "none",
            "int",
            "bytes",
            "list",
            "np_str",
            "nul",
        ]
        if self.valid.swapcase() in self.choices or self.valid.swapcase() == self.valid:
            names.remove("swapcase")
        return names

    def build(self, variant, ctx, rng, base):
        v = self.valid
        if variant == "omit":
            return Arg(OMIT)
        if variant.startswith("choice:"):
            return Arg(variant[7:])
        table = {
            "valid": (v, ACCEPT),
            "empty": ("", REJECT),
            "space": (v + " ", REJECT),
            "swapcase": (v.swapcase(), REJECT),
            "wrong": ("nope", REJECT),
            "none": (None, ACCEPT if self.optional else REJECT),
            "int": (1, REJECT),
            "bytes": (v.encode(), REJECT),
            "list": ([v], REJECT),
            "np_str": (np.str_(v), ACCEPT),
            "nul": (v + "\0", REJECT),
        }
        value, expect = table[variant]
        return Arg(value, expect)


class Flag(Slot):
    """A boolean parameter."""

    def __init__(self, name, valid=False, **kw):
        super().__init__(name, **kw)
        self.valid = valid

    def variants(self, exhaustive):
        return ["true", "false", "np_true", "one", "str_false", "none", "array"]

    def build(self, variant, ctx, rng, base):
        if variant == "omit":
            return Arg(OMIT)
        table = {
            "valid": (self.valid, ACCEPT),
            "true": (True, ACCEPT),
            "false": (False, ACCEPT),
            "np_true": (np.True_, ACCEPT),
            "one": (1, EITHER),
            "str_false": ("False", EITHER),
            "none": (None, EITHER),
            "array": (np.array([True, False]), EITHER),
        }
        value, expect = table[variant]
        return Arg(value, expect)


class Array(Slot):
    """A fixed-shape array parameter (a table, a transform, a limit pair). ``make(ctx)`` gives the
    valid value. ``inf_ok``: an infinity is meaningful (an unbounded limit). ``extra``: name ->
    (value(ctx, valid) , expect, why)."""

    def __init__(self, name, make, *, inf_ok=False, extra=None, **kw):
        super().__init__(name, **kw)
        self.make, self.inf_ok, self.extra = make, inf_ok, dict(extra or {})

    def variants(self, exhaustive):
        names = [
            "valid",
            "list",
            "float32",
            "int",
            "readonly",
            "neg_stride",
            "nan",
            "inf",
            "big",
            "wrong_shape",
            "extra_dim",
            "zero_d",
            "empty",
            "complex",
            "str_array",
            "object_array",
            "masked",
            "none",
            "str",
            *self.extra,
        ]
        if exhaustive:
            names += ["float32_be", "bool", "zero_stride"]
        return names if exhaustive else [n for n in names if n not in EXHAUSTIVE_ONLY]

    def build(self, variant, ctx, rng, base):
        if variant == "omit":
            return Arg(OMIT)
        v = np.array(self.make(ctx), dtype=np.float64)
        if variant in self.extra:
            make, expect, why = self.extra[variant]
            return Arg(make(ctx, v.copy()), expect, why)

        def poked(value):
            x = v.copy()
            x.reshape(-1)[int(rng.integers(x.size))] = value
            return x

        def reversed_twice():
            return v[::-1].copy()[::-1] if v.ndim else v

        table = {
            "valid": (v, ACCEPT, ""),
            "list": (v.tolist(), ACCEPT, ""),
            "float32": (v.astype(np.float32), EITHER, ""),  # rounding may change what it means
            "float32_be": (v.astype(">f4"), EITHER, ""),
            "int": (np.round(v).astype(np.int64), EITHER, ""),
            "bool": (v > 0, EITHER, ""),
            "readonly": (v.copy(), ACCEPT, ""),
            "neg_stride": (reversed_twice(), ACCEPT, ""),
            "zero_stride": (np.broadcast_to(v.reshape(-1)[:1], v.shape) if v.ndim else v, EITHER, ""),
            "nan": (poked(math.nan), REJECT, "value"),
            "inf": (poked(math.inf), EITHER if self.inf_ok else REJECT, "value"),
            "big": (poked(1e308), EITHER, ""),
            "wrong_shape": (np.zeros(v.size + 1), REJECT, "shape"),
            "extra_dim": (v[None, None], REJECT, "shape"),
            "zero_d": (np.array(0.5), REJECT, "shape"),
            "empty": (np.zeros(0), REJECT, "shape"),
            "complex": (v + 0j, REJECT, "type"),
            "str_array": (v.astype(str), REJECT, "type"),
            "object_array": (v.astype(object), EITHER, ""),
            "masked": (
                np.ma.masked_array(
                    v, mask=np.ones(v.shape, bool) & (np.arange(v.size) == 0).reshape(v.shape)
                ),
                REJECT,
                "",
            ),
            "none": (None, ACCEPT if self.optional else REJECT, "type"),
            "str": ("abc", REJECT, "type"),
        }
        value, expect, why = table[variant]
        if variant == "readonly":
            value.flags.writeable = False
        return Arg(value, expect, why)


class Custom(Slot):
    """An explicit table: name -> builder(ctx, rng, base) -> Arg. ``valid`` must be among them."""

    def __init__(self, name, table: dict, **kw):
        super().__init__(name, **kw)
        self.table = table

    def variants(self, exhaustive):
        return list(self.table)

    def build(self, variant, ctx, rng, base):
        if variant == "omit":
            return Arg(OMIT)
        return self.table[variant](ctx, rng, base)
