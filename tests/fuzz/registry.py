"""The fuzz harness's machinery: argument slots and their hostile inputs, oracles, the registry of
spotkin's public API, and the pool of worker processes that runs the cases.

Used by ``tests/test_fuzz.py`` (which documents the modes). Overview:

- A **slot** describes one argument: :class:`Batch` (a ``(..., *trailing)`` array with batch
  semantics), :class:`Array` (a fixed-shape array parameter), :class:`Real`, :class:`Int`,
  :class:`Choice` (an enum string), :class:`Flag` or :class:`Custom` (an explicit table of
  values). Each slot names its **variants**: hostile inputs (wrong shapes, 0-d and empty
  arrays, every dtype, byte orders, read-only, zero- and negative-stride views, masked arrays,
  lists, None, NaN, Inf, 1e308, subnormals, huge angles, bad enum strings, bad numbers), each
  with what the documentation promises for it: the call must accept it, reject it
  (``ValueError``/``TypeError``/``MemoryError``), or either.
- An :class:`Entry` of :data:`REGISTRY` is one public callable bound to an object (for example
  ``Leg.fk`` on Spot's front-left leg): its slots, a generator of valid baseline samples, the
  outputs it documents (shape and dtype per leaf), and oracles.
- A **case** fuzzes one slot (CI) or two (exhaustive) while the other slots keep a valid
  baseline (a *light* entry, the same code as another entry's on another robot, runs fewer batch
  variants in CI). The worker builds the arguments, calls, and judges the outcome:

  (a) leaves have the documented shape (leading dimensions kept) and dtype (float32 in, float32
      out; every other real dtype float64);
  (b) a sample with NaN/Inf (or an invalid pose) gives NaN floats and INVALID_INPUT in that
      sample only (entry-specific where a sample has parts, such as one leg of four);
  (c) a finite valid sample gives finite results or a documented status/NaN, checked against
      the documentation (fk(ik(p)) = p, references from NumPy and SciPy, Paul residuals...);
  (d) an angle beyond 64 rad gives either NaN/INVALID_INPUT (a documented bound) or the
      result at the angle reduced exactly (``atan2(sin q, cos q)`` with Python's math); a
      time beyond the ends gives the end state;
  (e) every sample of a batch equals a single call on that sample alone.

  Anything else (other exceptions, pybind's "incompatible function arguments", LinAlgError, a
  warning, a crash, a hang) is a failure.
"""

from __future__ import annotations

import copy
import functools
import inspect
import itertools
import json
import math
import os
import pathlib
import pickle
import re
import selectors
import subprocess
import sys
import tempfile
import time
import traceback
import warnings
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from urdf_helpers import joint as _urdf_joint
from urdf_helpers import links as _urdf_links

import spotkin as sk

from . import dask as fuzz_dask
from . import isa as fuzz_isa
from . import limits as fuzz_limits
from . import plot as fuzz_plot
from . import sdk as fuzz_sdk
from . import urdf as fuzz_urdf

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # tests/

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


# -- batch arrays ------------------------------------------------------------------------------------

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


class Batch(Slot):
    """An array ``(..., *trailing)`` with batch semantics.

    ``angles``: True (every element) or a boolean mask over ``trailing`` (e.g. the Euler angles of a
    body pose); huge values there are compared with their exact reduction. ``pose``: ``"T"``
    ((..., 4, 4) or (..., 7)) or ``"body"`` ((..., 6), (..., 4, 4) or (..., 7)) adds the malformed-pose
    variants. ``valid``: sample -> True/False/None (borderline), default: finite. ``equiv``: sample ->
    an equivalent sample whose result must be the same (or None). ``single_only``: no leading
    dimensions allowed. ``extra``: name -> builder(slot, ctx, rng, base) -> Arg.
    """

    batch = True

    def __init__(
        self,
        name,
        trailing,
        *,
        angles=None,
        pose=None,
        valid=None,
        equiv=None,
        equiv_nan_ok=True,
        single_only=False,
        extra=None,
        skip=(),
        dtype_driver=True,
        quat_ok=True,
        **kw,
    ):
        super().__init__(name, **kw)
        self.trailing = tuple(trailing)
        self.size = math.prod(self.trailing)
        if angles is True:
            angles = np.ones(self.trailing, dtype=bool)
        self.angles = None if angles is None else np.asarray(angles, dtype=bool)
        self.pose = pose
        self._valid = valid
        self._equiv = equiv
        self.equiv_nan_ok = equiv_nan_ok
        self.single_only = single_only
        self.extra = dict(extra or {})
        self.skip = set(skip)
        self.dtype_driver = dtype_driver
        self.quat_ok = quat_ok
        if pose == "body":  # (..., 7) is a quaternion pose
            self.skip.add("trailing_plus")

    def variants(self, exhaustive):
        names = LAYOUT + DTYPES + BAD_DTYPES + VALUES + SHAPES + OBJECTS
        names += ["float32_nan", "float32_inf", "float32_big"]
        if self.pose == "T":
            names += ["pose:quat", *POSE_BAD]
        elif self.pose == "body":
            names += ["pose:matrix", "pose:quat", *POSE_BAD]
        names += list(self.extra)
        if not self.trailing:
            names = [
                n
                for n in names
                if n
                not in ("trailing_plus", "trailing_minus", "neg_stride_inner", "inner_strided", "fortran")
            ]
        return [n for n in names if n not in self.skip]

    # -- validity and equivalents of one sample (shape trailing, or a form's trailing) --
    def valid(self, sample) -> bool | None:
        if self._valid is not None:
            return self._valid(sample)
        if self.pose is not None:
            return pose_validity(sample)
        return finite(sample)

    def equiv(self, sample, ctx):
        if self._equiv is not None:
            return self._equiv(sample, ctx)
        sample = np.asarray(sample)
        if self.angles is None or sample.shape != self.trailing:
            return None
        flat = sample.astype(np.float64).reshape(-1)
        mask = self.angles.reshape(-1) & np.isfinite(flat) & (np.abs(flat) > HUGE_ANGLE)
        if not mask.any():
            return None
        out = flat.copy()
        out[mask] = [reduce_angle(v) for v in flat[mask]]
        return out.reshape(sample.shape).astype(sample.dtype)

    # -- building --
    def _arg(self, value, lead, plain=None, f32=False, expect=ACCEPT, why=""):
        if expect in (ACCEPT, EITHER) and self.single_only and lead != ():
            expect, why = REJECT, "shape" if expect == ACCEPT else ""
        if expect not in (ACCEPT, EITHER):
            return Arg(value, expect, why)
        if plain is None:
            plain = np.array(value, dtype=np.float32 if f32 else np.float64)
        return Arg(value, expect, why, tuple(lead), np.array(plain, order="C"), f32)

    def _position(self, rng, angle_only: bool) -> int:
        if angle_only and self.angles is not None and self.angles.any():
            return int(rng.choice(np.flatnonzero(self.angles.reshape(-1))))
        return int(rng.integers(self.size)) if self.size else 0

    def _poked(self, b, rng, value, angle_only=False, dtype=np.float64):
        x = b.astype(dtype)
        if self.size:
            x.reshape(len(b), -1)[1, self._position(rng, angle_only)] = value
        return x

    def build(self, variant, ctx, rng, base):
        if variant == "omit":
            return Arg(OMIT)
        tr, b = self.trailing, base[self.name]
        one, n = b[0], len(b)
        lead = (n,)
        if variant in self.extra:
            return self.extra[variant](self, ctx, rng, base)
        if variant.startswith("pose:"):
            return self._pose_variant(variant[5:], b, rng)
        if variant == "valid":
            return self._arg(one.copy(), ())
        if variant == "single":
            return self._arg(one.copy(), ())
        if variant == "batch":
            return self._arg(b.copy(), lead)
        if variant == "batch2x1":
            return self._arg(b[:2].reshape(2, 1, *tr), (2, 1))
        if variant == "empty":
            return self._arg(b[:0].copy(), (0,))
        if variant == "empty2":
            return self._arg(np.zeros((2, 0, *tr)), (2, 0))
        if variant == "list":
            return self._arg(one.tolist(), (), one)
        if variant == "nested_list":
            return self._arg(b.tolist(), lead, b)
        if variant == "tuple":
            return self._arg(tuple(b.tolist()), lead, b)
        if variant == "readonly":
            x = b.copy()
            x.flags.writeable = False
            return self._arg(x, lead, b)
        if variant == "zero_stride":
            return self._arg(np.broadcast_to(one, (4, *tr)), (4,))
        if variant == "neg_stride":
            return self._arg(b[::-1], lead, b[::-1].copy())
        if variant == "neg_stride_inner":
            return self._arg(b[..., ::-1].copy()[..., ::-1], lead, b)
        if variant == "fortran":
            return self._arg(np.asfortranarray(b), lead, b)
        if variant == "inner_strided":
            big = np.zeros((n, *tr[:-1], 2 * tr[-1]))
            big[..., ::2] = b
            return self._arg(big[..., ::2], lead, b)
        # dtypes
        if variant == "float32":
            return self._arg(b.astype(np.float32), lead, f32=True)
        if variant == "float32_be":
            x = b.astype(">f4")
            return self._arg(x, lead, x.astype(np.float32), f32=True)
        if variant in ("float32_nan", "float32_inf", "float32_big"):
            value = {"float32_nan": np.nan, "float32_inf": np.inf, "float32_big": 3e38}[variant]
            return self._arg(self._poked(b, rng, value, dtype=np.float32), lead, f32=True)
        if variant == "float64_be":
            return self._arg(b.astype(">f8"), lead, b)
        if variant in ("float16", "longdouble"):
            x = b.astype(np.float16 if variant == "float16" else np.longdouble)
            return self._arg(x, lead, x.astype(np.float64))
        if variant in ("int64", "int32", "int8"):
            x = np.round(b).astype(variant)
            return self._arg(x, lead, x.astype(np.float64))
        if variant in ("uint8", "uint64"):
            x = np.abs(np.round(b)).astype(variant)
            return self._arg(x, lead, x.astype(np.float64))
        if variant == "bool":
            x = b > 0
            return self._arg(x, lead, x.astype(np.float64))
        if variant in BAD_DTYPES:
            return self._bad_dtype(variant, b)
        # values
        if variant in ("nan", "inf", "-inf", "big", "-big", "subnormal", "neg_zero", "tiny"):
            value = {
                "nan": np.nan,
                "inf": np.inf,
                "-inf": -np.inf,
                "big": 1e308,
                "-big": -1e308,
                "subnormal": 5e-324,
                "neg_zero": -0.0,
                "tiny": 1e-300,
            }[variant]
            return self._arg(self._poked(b, rng, value), lead)
        if variant.startswith("mag_"):
            magnitude = float(variant[4:])
            return self._arg(self._poked(b, rng, magnitude * rng.choice([-1, 1]), angle_only=True), lead)
        if variant == "nan_all":
            return self._arg(np.full_like(b, np.nan), lead)
        if variant == "nan_single":
            x = self._poked(b, rng, np.nan)[1]
            return self._arg(x, ())
        # shapes
        if variant in ("scalar", "zero_d"):
            value = 0.5 if variant == "scalar" else np.array(0.5)
            if not tr:
                return self._arg(value, (), np.array(0.5))
            return Arg(value, REJECT, "shape")
        if variant in ("trailing_plus", "trailing_minus"):
            k = tr[-1] + 1 if variant == "trailing_plus" else tr[-1] - 1
            return Arg(np.zeros((n, *tr[:-1], k)), REJECT, "shape")
        if variant == "extra_dim":
            if not tr:
                return self._arg(b[:, None], (n, 1))
            return Arg(b[..., None], REJECT, "shape")
        if variant == "flat":
            if not tr:
                return self._arg(b.copy(), lead)
            return Arg(b.reshape(-1), REJECT, "shape")
        if variant == "ragged":
            rows = [np.atleast_1d(x).tolist() for x in b]
            rows[1] = rows[1][:-1]
            return Arg(rows, REJECT, "")
        if variant == "empty_flat":
            if not tr:
                return self._arg(np.zeros(0), (0,))
            return Arg(np.zeros(0), REJECT, "shape")
        # objects
        if variant == "none":
            if self.optional:
                return Arg(None)
            return Arg(None, REJECT, "type")
        if variant in ("str", "bytes", "dict", "object"):
            value = {"str": "abc", "bytes": b"abc", "dict": {}, "object": object()}[variant]
            return Arg(value, REJECT, "type")
        if variant == "masked":
            mask = np.zeros(b.shape, dtype=bool)
            if self.size:
                mask.reshape(n, -1)[1, self._position(rng, False)] = True
            x = np.ma.masked_array(b, mask=mask)
            return self._arg(x, lead, x.filled(np.nan), expect=EITHER)
        if variant == "masked_nomask":
            return self._arg(np.ma.masked_array(b), lead, b, expect=EITHER)
        if variant == "huge_batch":
            if self.single_only:
                return Arg(np.broadcast_to(one, (10**10, *tr)), REJECT, "shape")
            return Arg(np.broadcast_to(one, (10**10, *tr)), MEMORY, "memory", (10**10,))
        raise KeyError(f"{self.name}: unknown variant {variant}")

    def _bad_dtype(self, variant, b):
        if variant == "complex128":
            return Arg(b.astype(np.complex128), REJECT, "type")
        if variant == "complex64":
            return Arg(b.astype(np.complex64), REJECT, "type")
        if variant == "complex_imag":
            return Arg(b + 1j, REJECT, "type")
        if variant == "str_array":
            return Arg(b.astype(str), REJECT, "type")
        if variant == "bytes_array":
            return Arg(b.astype("S32"), REJECT, "type")
        if variant == "object_array":  # numbers in an object array: refused or read correctly
            return self._arg(b.astype(object), (len(b),), b, expect=EITHER)
        if variant == "datetime64":
            return Arg(np.zeros(b.shape, dtype="datetime64[s]"), REJECT, "type")
        if variant == "timedelta64":
            return Arg(np.zeros(b.shape, dtype="timedelta64[s]"), REJECT, "type")
        if variant == "structured":
            return Arg(np.zeros(b.shape, dtype=[("a", "f8")]), REJECT, "type")
        raise KeyError(variant)

    def _pose_variant(self, what, b, rng):
        from scipy.spatial.transform import Rotation

        n = len(b)
        if self.pose == "body":
            M = np.zeros((n, 4, 4))
            M[:, :3, :3] = Rotation.from_euler("XYZ", b[:, 3:]).as_matrix()
            M[:, :3, 3] = b[:, :3]
            M[:, 3, 3] = 1.0
        else:
            M = b.copy()
        Q = np.concatenate([M[:, :3, 3], Rotation.from_matrix(M[:, :3, :3]).as_quat()], axis=-1)
        if what == "matrix":
            return self._arg(M, (n,))
        if what == "quat" or what.startswith("quat_"):
            if what != "quat":
                Q[1, 3:] *= {"quat_nonunit": 2.0, "quat_zero": 0.0, "quat_near": 1 + 1e-9}[what]
            if not self.quat_ok:
                return Arg(Q, REJECT, "shape")
            return self._arg(Q, (n,))
        if what == "rot_zero":
            M[1, :3, :3] = 0.0
        elif what == "rot_scaled":
            M[1, :3, :3] *= 2.0
        elif what == "reflect":
            M[1, :3, 0] *= -1.0
        elif what == "last_row":
            M[1, 3, 3] = 2.0
        elif what == "last_row_x":
            M[1, 3, 0] = 1e-3
        elif what == "almost_rigid":
            M[1, :3, :3] += 1e-9 * rng.normal(size=(3, 3))
        return self._arg(M, (n,))


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


class OutSlot(Slot):
    """``out=``: arrays the call writes its results into and returns (a control loop allocates
    nothing). ``leaves``: the output spec, (kind, trailing) per result leaf, or a function of the
    built arguments' values giving it. ``drivers``: the batch arguments whose dtypes decide the
    working dtype (float32 only when every one is). Built after the other slots, from their
    leading shapes and dtypes: ``valid`` passes the float and bool leaves (a status is left to the
    call), ``valid_all`` every leaf of a batch; the other variants are each one documented
    rejection."""

    after = True

    def __init__(self, *leaves, drivers=None, **kw):
        super().__init__("out", optional=True, default="omit", **kw)
        self.leaves = leaves[0] if len(leaves) == 1 and callable(leaves[0]) else leaves
        self.drivers = drivers

    def variants(self, exhaustive):
        return [
            "valid",
            "valid_all",
            "wrong_dtype",
            "wrong_shape",
            "readonly",
            "strided",
            "not_array",
            "wrong_count",
        ]

    def build(self, variant, ctx, rng, base):
        return Arg(OMIT)  # build_out makes it, once the other arguments are built

    def _spec(self, args):
        leaves = self.leaves(args) if callable(self.leaves) else self.leaves
        return [Out(kind, tuple(trailing)) for kind, trailing in leaves]

    def build_out(self, variant, args, entry) -> Arg:
        if variant == "omit":
            return Arg(OMIT)
        batch = {n: a for n, a in args.items() if a.present}
        try:
            lead = tuple(np.broadcast_shapes(*(a.lead for a in batch.values()))) if batch else ()
        except ValueError:
            lead = ()
        if math.prod(lead) > 1 << 20:  # a huge batch (its MemoryError is the case): no out= beside it
            return Arg(OMIT)
        names = [n for n in (self.drivers or [n for n in batch if entry.slot(n).dtype_driver]) if n in batch]
        f32 = bool(names) and all(batch[n].f32 for n in names)
        dtypes = {
            "float": np.float32 if f32 else np.float64,
            "f64": np.float64,
            "flag": np.bool_,
            "bool": np.bool_,
        }
        spec = self._spec(args)
        arrays = [
            np.zeros(lead + leaf.trailing, dtype=dtypes.get(leaf.kind, np.int8))
            if (variant == "valid_all" and lead) or leaf.kind not in ("status", "stance")
            else None
            for leaf in spec
        ]

        def packed(values):
            return values[0] if len(values) == 1 else tuple(values)

        first = next(i for i, a in enumerate(arrays) if a is not None)
        bad = list(arrays)
        if variant in ("valid", "valid_all"):
            return Arg(packed(arrays))
        if variant == "wrong_dtype":
            a = arrays[first]
            bad[first] = a.astype(np.float64 if a.dtype == np.float32 else np.float32)
            return Arg(packed(bad), REJECT, "type")
        if variant == "wrong_shape":
            bad[first] = np.zeros((2, *arrays[first].shape), arrays[first].dtype)
            return Arg(packed(bad), REJECT, "shape")
        if variant == "readonly":
            bad[first].flags.writeable = False
            return Arg(packed(bad), REJECT, "value")
        if variant == "strided":
            a = arrays[first]
            bad[first] = np.zeros((*a.shape, 2), a.dtype)[..., 0]
            return Arg(packed(bad), REJECT if not bad[first].flags.c_contiguous else ACCEPT, "value")
        if variant == "not_array":
            bad[first] = arrays[first].tolist()
            return Arg(packed(bad), REJECT, "type")
        if variant == "wrong_count":
            return Arg((*arrays, None), REJECT, "value")
        raise KeyError(variant)


# ---- outputs ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Out:
    """One leaf of a result: ``kind`` is "float" (float32 iff the inputs are), "f64", "flag" (a
    validity bool: False for invalid input), "bool", "status", "stance" (an sk.StanceStatus), "int" or
    "hand" (None or f64)."""

    kind: str
    trailing: tuple = ()


def flatten(result) -> list:
    if isinstance(result, tuple):
        return [leaf for item in result for leaf in flatten(item)]
    return [result]


def close(a, b, f32: bool) -> bool:
    """Equal shapes, NaN where the other is NaN, equal infinities, floats within tolerance."""
    if a is None or b is None:
        return a is None and b is None
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return False
    if a.dtype.kind in "biu" and b.dtype.kind in "biu":
        return bool(np.array_equal(a, b))
    a, b = a.astype(np.float64), b.astype(np.float64)
    if (np.isnan(a) != np.isnan(b)).any():
        return False
    fin = np.isfinite(a) & np.isfinite(b)
    inf = ~fin & ~np.isnan(a)
    if (a[inf] != b[inf]).any() or (np.isfinite(a) != np.isfinite(b)).any():
        return False
    scale = max(1.0, float(np.max(np.abs(b[fin]), initial=0.0)))
    return bool(np.all(np.abs(a[fin] - b[fin]) <= (2e-4 if f32 else 1e-9) * scale))


def describe(value, limit: int = 160) -> str:
    try:
        if isinstance(value, np.ma.MaskedArray):
            text = f"masked {value!r}"
        elif isinstance(value, np.ndarray):
            body = np.array2string(value, threshold=20, precision=6, max_line_width=10**6)
            text = f"array(shape={value.shape}, dtype={value.dtype}) {body}"
        else:
            text = repr(value)
    except Exception as error:  # pragma: no cover - a repr failing is itself reported elsewhere
        text = f"<unprintable: {error!r}>"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


# ---- the entry ----------------------------------------------------------------------------------


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


def dof_changes(plan):
    """A chain table of another joint count with the 3-joint limits: rejected."""
    if plan["rows"] in ("one_row", "zero_rows", "many_rows") and plan["limits"] not in ("omit", "none"):
        return REJECT
    return None


def dls_pairs(plan):
    """J with another column count n: a nullspace (n,) of the baseline's length no longer fits."""
    if plan["J"] in ("shape:n1", "shape:n64", "shape:square") and plan["nullspace"] not in ("omit", "none"):
        return EITHER if plan["nullspace"] in ("trailing_minus", "trailing_plus") else REJECT
    return None


def ikd_pairs(plan):
    """(2, 0, 4, 4) targets with a (0, dof) start read as paths: ambiguous with batches."""
    return EITHER if plan["T_targets"] == "empty2" else None


def same_axes(plan):
    """q0 and qf both of the wrong length agree with each other (and with scalar limits)."""
    if plan["q0"] == plan["qf"] == "wrong_shape":
        return ACCEPT
    return EITHER if plan["q0"] == plan["qf"] == "empty" else None  # zero axes


def huge_argument(kw) -> bool:
    for value in kw.values():
        try:
            with np.errstate(all="ignore"):
                if np.abs(np.asarray(value, dtype=np.float64)).max(initial=0) >= 1e300:
                    return True
        except (TypeError, ValueError):
            continue
    return False


def outs(*leaves):
    """A fixed output spec: Out(kind, trailing) leaves."""
    spec = [Out(kind, tuple(trailing)) for kind, trailing in leaves]
    return lambda args, kw: spec


class Failure(Exception):
    def __init__(self, kind: str, detail: str):
        super().__init__(f"{kind}: {detail}")
        self.kind, self.detail = kind, detail


# ---- the objects under test ------------------------------------------------------------------------

PROFILES = ("cubic", "quintic", "trapezoid")
P2P_Q0, P2P_QF = (0.0, 0.5, -1.0), (1.0, -0.5, 0.5)
CHAIN_ROWS = {
    # the README's DHm leg (sigma, d, alpha, r, theta)
    "mdh3": [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.11, 0.0), (0, 0.32, 0.0, 0.0, 0.0)],
    # an elbow arm in classic DH (sigma, a, alpha, d, theta)
    "dh3": [(0, 0.0, np.pi / 2, 0.3, 0.0), (0, 0.4, 0.0, 0.0, 0.0), (0, 0.3, 0.0, 0.0, 0.0)],
    # the Spot arm as DHm (tests/test_chain_ik.py)
    "mdh6": [
        (0, 0.0, 0.0, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, 0.3385, 0.0, 0.0, -np.pi / 2),
        (0, 0.075, -np.pi / 2, 0.4033, 0.0),
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
    ],
    # PUMA 560 in classic DH: a spherical wrist
    "dh6": [
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.4318, 0.0, 0.0, 0.0),
        (0, 0.0203, -np.pi / 2, 0.15005, 0.0),
        (0, 0.0, np.pi / 2, 0.4318, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, 0.0, 0.0, 0.0, 0.0),
    ],
}
LEG_LIMITS = [(-0.8, 0.8), (-0.9, 2.3), (-2.8, -0.25)]
# chains from URDFs: key -> (Context.robot key, tip link, dof)
URDF_CHAINS = {"go2_fl": ("go2", "FL_foot", 3), "spot_arm": ("spot_urdf", "arm_hand", 6)}
ROBOT_FILES = {"go2": "go2", "spot_urdf": "spot_with_arm"}
STANCE_HEIGHT = {"spot": 0.5, "go2": 0.28, "hexapod": 0.3, "spot_urdf": 0.5}


def _hexapod_urdf() -> str:
    """Six roll-pitch-pitch legs in three pairs at different x (and heights), with mixed axis signs
    (a knee about -y takes positive limits to bend back) and offsets; the joints are written hips
    first, then thighs, then knees, so the whole-body q interleaves the legs (as tests/test_robot.py's
    hexapod)."""
    legs = [  # name, hip origin, axes, knee limits, a, b, c
        (
            "L1",
            "0.3 0.12 0",
            ("1 0 0", "0 1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 0.08 0",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
        (
            "R1",
            "0.31 -0.1 0.01",
            ("-1 0 0", "0 -1 0", "0 -1 0"),
            (0.2, 2.6),
            "0 -0.07 0.01",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
        (
            "L2",
            "0.02 0.15 -0.01",
            ("1 0 0", "0 -1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 0.08 0",
            "-0.015 0.005 -0.22",
            "0 0 -0.21",
        ),
        (
            "R2",
            "-0.01 -0.16 0",
            ("1 0 0", "0 1 0", "0 -1 0"),
            (0.2, 2.6),
            "0.01 -0.09 0",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
        (
            "L3",
            "-0.33 0.11 0.005",
            ("-1 0 0", "0 1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 0.08 0",
            "0.02 0 -0.2",
            "0.01 0.01 -0.2",
        ),
        (
            "R3",
            "-0.3 -0.12 -0.02",
            ("-1 0 0", "0 -1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 -0.085 -0.01",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
    ]
    link_names = ["base"]
    joints = [[], [], [], []]
    for name, hip, axes, knee, a, b, c in legs:
        parts = [f"{name}_{part}" for part in ("hip", "thigh", "calf", "foot")]
        link_names += parts
        joints[0].append(
            _urdf_joint(
                f"{name}_hip_joint", "revolute", "base", parts[0], hip, axis=axes[0], limits=(-0.7, 0.7)
            )
        )
        joints[1].append(
            _urdf_joint(
                f"{name}_thigh_joint", "revolute", parts[0], parts[1], a, axis=axes[1], limits=(-2.2, 2.2)
            )
        )
        joints[2].append(
            _urdf_joint(f"{name}_calf_joint", "revolute", parts[1], parts[2], b, axis=axes[2], limits=knee)
        )
        joints[3].append(_urdf_joint(f"{name}_foot_joint", "fixed", parts[2], parts[3], c))
    body = _urdf_links(*link_names) + "".join(j for group in joints for j in group)
    return f'<?xml version="1.0"?><robot name="hexapod">{body}</robot>'


HEXAPOD_URDF = _hexapod_urdf()
HEXAPOD_LEGS = ("L1", "R1", "L2", "R2", "L3", "R3")


def rigid(R, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def euler_matrix(angles, seq="XYZ"):
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler(seq, angles).as_matrix()


def quat_matrix(q):
    """The documented conversion (scalar last, s = 2 / |q|^2), without normalising."""
    x, y, z, w = q
    s = 2.0 / (x * x + y * y + z * z + w * w)
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
        ]
    )


def pose_matrix(x, seq="XYZ"):
    """A (6,), (7,) or (4, 4) pose sample as a float64 4x4 (body_transform's reading)."""
    x = np.asarray(x, dtype=np.float64)
    if x.shape == (4, 4):
        return x.copy()
    R = euler_matrix(x[3:], seq) if x.shape == (6,) else quat_matrix(x[3:])
    return rigid(R, x[:3])


class Context:
    """The objects the registry's entries are called on, built once per worker (lazily)."""

    def __init__(self):
        self._cache = {}

    def _get(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    @property
    def spot(self):
        return self._get("spot", sk.Spot)

    @property
    def leg(self):
        return self.spot.leg("fl")

    @property
    def arm(self):
        return self.spot.arm

    def robot(self, key):
        """A whole-body robot: "spot" (sk.Spot()), "go2", "spot_urdf" (sk.Robot from the packaged
        URDFs) or "hexapod" (sk.Robot from :data:`HEXAPOD_URDF`)."""

        def make():
            if key == "hexapod":
                return sk.Robot.from_urdf_string(HEXAPOD_URDF)
            if key == "go2_feet":  # two of the legs, with a contact offset
                return sk.Robot.from_urdf(
                    sk.robots.path("go2"), feet=["FL_foot", "RR_foot"], contact_offset=(0.0, 0.0, -0.02)
                )
            return sk.Robot.from_urdf(sk.robots.path(ROBOT_FILES[key]))

        return self.spot if key == "spot" else self._get(("robot", key), make)

    def columns(self, key):
        """Per leg (robot.legs order), the indices of its three joints in the whole-body q."""

        def make():
            robot = self.robot(key)
            if isinstance(robot, sk.Spot):
                return [np.arange(3 * k, 3 * k + 3) for k in range(4)]
            specs = {spec.name: spec for spec in sk.urdf.find_legs(robot.model)[0]}
            order = list(robot.leg_joint_names)
            return [np.array([order.index(j) for j in specs[name].joint_names]) for name in robot.leg_names]

        return self._get(("columns", key), make)

    def hips(self, key):
        return self._get(("hips", key), lambda: self.robot(key).hip_positions)

    def nominal(self, key):
        """(3 n,) whole-body joints of the nominal stance (body_ik of stance_feet at its height)."""

        def make():
            robot, height = self.robot(key), STANCE_HEIGHT[key]
            q, status = robot.body_ik([0.0, 0.0, height, 0.0, 0.0, 0.0], robot.stance_feet(height))
            assert (status == OK).all(), (key, status)
            return q

        return self._get(("nominal", key), make)

    def files(self):
        """URDF files for Robot.from_urdf: name -> path (in a temporary folder of this worker)."""

        def make():
            folder = tempfile.TemporaryDirectory(prefix="spotkin-fuzz-")
            self._cache["folder"] = folder  # removed at exit
            go2 = _go2_text()
            body = go2.split("?>", 1)[1] if go2.startswith("<?xml") else go2
            contents = {
                "latin1": _latin1_urdf(),
                "utf16": ('<?xml version="1.0" encoding="UTF-16"?>' + body).encode("utf-16"),
                "empty": b"",
                "not_xml": b"hello",
                "loop": _bad_urdfs()["loop"][0].encode(),
            }
            paths = {"missing": os.path.join(folder.name, "missing.urdf"), "directory": folder.name}
            for name, data in contents.items():
                paths[name] = os.path.join(folder.name, f"{name}.urdf")
                with open(paths[name], "wb") as file:
                    file.write(data)
            return paths

        return self._get("files", make)

    def chain(self, key):
        def make():
            if key in URDF_CHAINS:
                robot, link, _ = URDF_CHAINS[key]
                return self.robot(robot).chain(link)
            rows = CHAIN_ROWS[key]
            if key == "mdh3":
                return sk.Chain.from_mdh(rows, tool=sk.translation([0.37, 0.0, 0.0]), limits=LEG_LIMITS)
            if key == "dh3":
                return sk.Chain.from_dh(rows, base=rigid(euler_matrix([0.1, 0.2, 0.3]), [0.1, 0, 0.2]))
            if key == "mdh6":
                base = sk.translation([0.292, 0.0, 0.188])
                return sk.Chain.from_mdh(
                    rows, base=base, tool=sk.translation([0.19557, 0.0, 0.0]), limits=self.arm.limits
                )
            return sk.Chain.from_dh(rows, tool=sk.translation([0.0, 0.0, 0.1]))

        return self._get(("chain", key), make)

    def p2p(self, profile):
        return self._get(
            ("p2p", profile), lambda: sk.trajectory.point_to_point(P2P_Q0, P2P_QF, 1.0, 2.0, profile)
        )

    def path(self, kind):
        def make():
            if kind == "linear":
                return sk.trajectory.linear(PATH_T0, PATH_T1, 0.5, 1.0, 1.0, 2.0)
            return sk.trajectory.via_points(VIA_POSES, 0.5, 1.0, 1.0, 2.0, blend=0.2)

        return self._get(("path", kind), make)


PATH_T0 = rigid(euler_matrix([0.1, -0.2, 0.3]), [0.1, 0.2, 0.3])
PATH_T1 = rigid(euler_matrix([-0.4, 0.5, 1.2]), [0.6, -0.1, 0.5])
VIA_POSES = np.array(
    [rigid(euler_matrix([0.1 * k, -0.2, 0.3 * k]), [0.1 * k, 0.2 - 0.05 * k * k, 0.3]) for k in range(4)]
)


# ---- baseline samples --------------------------------------------------------------------------------


def in_limits(limits, rng, n, margin=0.05):
    limits = np.asarray(limits, dtype=np.float64)
    lo = np.where(np.isfinite(limits[:, 0]), limits[:, 0], -np.pi)
    hi = np.where(np.isfinite(limits[:, 1]), limits[:, 1], np.pi)
    margin = np.minimum(margin, np.maximum(hi - lo, 0) / 4)  # narrow (or inverted) limits: their middle
    return rng.uniform(
        np.minimum(lo + margin, hi - margin), np.maximum(lo + margin, hi - margin), (n, len(limits))
    )


def rotations(rng, n):
    from scipy.spatial.transform import Rotation

    q = rng.normal(size=(n, 4))
    return Rotation.from_quat(q / np.linalg.norm(q, axis=1, keepdims=True)).as_matrix()


def unit_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def nominal_q12(rng, n):
    return np.tile([0.0, 1.04, -1.8], 4) + rng.uniform(-0.1, 0.1, (n, 12))


def body_poses(rng, n, height=0.48):
    pose = np.zeros((n, 6))
    pose[:, :3] = rng.uniform(-0.03, 0.03, (n, 3)) + [0.0, 0.0, height]
    pose[:, 3:] = rng.uniform(-0.15, 0.15, (n, 3))
    return pose


# ---- oracle helpers -----------------------------------------------------------------------------------


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


# -- legs --


def _leg_entries():
    def leg_singularity_check(leg):
        def check(x, out, kw, ctx):
            det, sigma = out
            if not (finite(det) and finite(sigma)) or det < 0 or sigma < 0:
                return f"(|det J|, sigma_min) = ({det}, {sigma}) for finite q"
            ref = np.linalg.svd(leg(ctx).jacobian(x["q"].astype(np.float64)), compute_uv=False)
            tol = tol_for(x["q"], base=1e-9, f32=1e-4)
            if abs(sigma - ref[-1]) > tol or abs(det - np.prod(ref)) > tol:
                return (
                    f"(|det J|, sigma_min) = ({det}, {sigma}), the Jacobian's are ({np.prod(ref)}, {ref[-1]})"
                )
            return None

        return check

    def nearest_reachable_check(leg):
        def check(x, out, kw, ctx):
            (point,) = out
            if not finite(point):
                return f"non-finite point {point} for a finite p"
            if int(leg(ctx).ik(point)[1]) == INVALID:
                return f"ik of the returned point gives INVALID_INPUT: {point}"
            p = x["p"].astype(np.float64)
            if int(leg(ctx).ik(p)[1]) == OK and np.abs(point - p).max() > 1e-9:
                return f"p is reachable but the nearest reachable point is {point}"
            return None

        return check

    for key in ("fl", "hr"):  # a left and a right leg

        def leg(c, key=key):
            return c.spot.leg(key)

        def leg_q(c, rng, n, leg=leg):
            return {"q": in_limits(leg(c).limits, rng, n)}

        def leg_p(c, rng, n, leg=leg):
            q = in_limits(leg(c).limits, rng, n, margin=0.1)
            return {"p": leg(c).fk(q), "seed": q + rng.normal(0, 0.05, q.shape)}

        tag = f"[{key}]"
        register(
            name=f"Leg.fk{tag}",
            covers="spotkin.Leg.fk",
            call=lambda c, leg=leg, **k: leg(c).fk(**k),
            slots=[angle_slot("q", 3), OutSlot(("float", (3,)))],
            baseline=leg_q,
            outputs=outs(("float", (3,))),
            check=finite_check,
        )
        register(
            name=f"Leg.jacobian{tag}",
            covers="spotkin.Leg.jacobian",
            call=lambda c, leg=leg, **k: leg(c).jacobian(**k),
            slots=[angle_slot("q", 3), OutSlot(("float", (3, 3)))],
            baseline=leg_q,
            outputs=outs(("float", (3, 3))),
            check=finite_check,
        )
        register(
            name=f"Leg.singularity{tag}",
            covers="spotkin.Leg.singularity",
            call=lambda c, leg=leg, **k: leg(c).singularity(**k),
            slots=[angle_slot("q", 3), OutSlot(("float", ()), ("float", ()))],
            baseline=leg_q,
            outputs=outs(("float", ()), ("float", ())),
            check=leg_singularity_check(leg),
        )
        register(
            name=f"Leg.ik{tag}",
            covers="spotkin.Leg.ik",
            call=lambda c, leg=leg, **k: leg(c).ik(**k),
            slots=[
                Batch("p", (3,)),
                angle_slot("seed", 3, optional=True, default="omit"),
                Choice("fallback", "nearest", ("nearest", "nan"), default="omit"),
                OutSlot(("float", (3,)), ("status", ()), drivers=["p"]),
            ],
            baseline=leg_p,
            outputs=outs(("float", (3,)), ("status", ())),
            check=lambda x, out, kw, c, leg=leg: nearest_check(
                leg(c).fk, lambda x: x["p"], leg(c).limits, True
            )(x, out, kw, c),
        )
        register(
            name=f"Leg.ik_all{tag}",
            covers="spotkin.Leg.ik_all",
            call=lambda c, leg=leg, **k: leg(c).ik_all(**k),
            slots=[
                Batch("p", (3,)),
                OutSlot(("float", (4, 3)), ("flag", (4,)), ("flag", (4,)), ("status", ())),
            ],
            baseline=leg_p,
            outputs=outs(("float", (4, 3)), ("flag", (4,)), ("flag", (4,)), ("status", ())),
            check=lambda x, out, kw, c, leg=leg: solution_check(leg(c).fk, lambda x: x["p"], leg(c).limits)(
                x, out, kw, c
            ),
        )
        register(
            name=f"Leg.nearest_reachable{tag}",
            covers="spotkin.Leg.nearest_reachable",
            call=lambda c, leg=leg, **k: leg(c).nearest_reachable(**k),
            slots=[Batch("p", (3,), single_only=True), Flag("within_limits", default="omit")],
            baseline=leg_p,
            outputs=outs(("f64", (3,))),
            check=nearest_reachable_check(leg),
        )

    def leg_probe(leg, kw, ctx):
        if not isinstance(leg, sk.Leg):
            return f"not a Leg: {describe(leg)}"
        q = in_limits(leg.limits, np.random.default_rng(0), 4, margin=0.01)
        p = leg.fk(q)
        if not finite(p):
            return f"fk of in-limit angles is not finite: {describe(p)}"
        back, status = leg.ik(p)
        ok = status == OK
        if np.abs(leg.fk(back[ok]) - p[ok]).max(initial=0) > 1e-7:
            return "ik(fk(q)) does not return to the foot"
        clone = pickle.loads(pickle.dumps(leg))
        if not close(clone.fk(q), p, False):
            return "a pickled copy differs"
        return None

    limits3 = Array(
        "limits",
        lambda c: LEG_LIMITS,
        inf_ok=True,
        optional=True,
        default="omit",
        extra={
            "unbounded": (lambda c, v: [[-np.inf, np.inf]] * 3, ACCEPT, ""),
            "inverted": (lambda c, v: v[:, ::-1], REJECT, "value"),
            "transposed": (lambda c, v: v.T, REJECT, "shape"),
        },
    )
    register(
        name="Leg",
        covers="spotkin.Leg",
        call=lambda c, **k: sk.Leg(**k),
        slots=[
            Real("hip_offset", 0.11, "nonneg"),
            Real("upper", 0.32),
            Real("lower", 0.34),
            Real("knee_offset", 0.025, "finite", default="omit"),
            Choice("side", "left", ("left", "right"), default="omit"),
            limits3,
            Custom(
                "name",
                {
                    "valid": lambda c, r, b: Arg("fl"),
                    "none": lambda c, r, b: Arg(None),
                    "empty": lambda c, r, b: Arg(""),
                    "int": lambda c, r, b: Arg(1, EITHER),
                },
                default="omit",
            ),
        ],
        probe=leg_probe,
        overflow_ok=True,
    )


# -- the arm --

RIGID_EXTRA = {  # (4, 4) tools and bases
    "scaled": (lambda c, v: 2 * np.eye(4), REJECT, "value"),
    "last_row": (lambda c, v: np.diag([1.0, 1.0, 1.0, 2.0]), REJECT, "value"),
    "zeros": (lambda c, v: np.zeros((4, 4)), REJECT, "value"),
    "reflect": (lambda c, v: np.diag([-1.0, 1.0, 1.0, 1.0]), REJECT, "value"),
    "rigid": (lambda c, v: rigid(euler_matrix([0.3, 0.2, 0.1]), [0.05, 0, 0.02]), ACCEPT, ""),
}


def _arm_entries():
    def arm_q(c, rng, n):
        q = in_limits(c.arm.limits, rng, n, margin=0.1)
        return {"q": q, "T": c.arm.fk(q), "seed": q + rng.normal(0, 0.05, q.shape)}

    def arm_singularity_check(x, out, kw, ctx):
        if not all(finite(v) and v >= 0 for v in out):
            return f"non-finite or negative measure: {out}"
        return None

    register(
        name="SpotArm.fk",
        covers="spotkin.SpotArm.fk",
        call=lambda c, **k: c.arm.fk(**k),
        slots=[angle_slot("q", 6), OutSlot(("float", (4, 4)))],
        baseline=arm_q,
        outputs=outs(("float", (4, 4))),
        check=lambda x, out, kw, c: (
            None
            if finite(out[0]) and rigid_error(out[0]) < 1e-5
            else f"fk is not a finite rigid transform: {describe(out[0])}"
        ),
    )
    register(
        name="SpotArm.jacobian",
        covers="spotkin.SpotArm.jacobian",
        call=lambda c, **k: c.arm.jacobian(**k),
        slots=[angle_slot("q", 6), OutSlot(("float", (6, 6)))],
        baseline=arm_q,
        outputs=outs(("float", (6, 6))),
        check=finite_check,
    )
    register(
        name="SpotArm.singularity",
        covers="spotkin.SpotArm.singularity",
        call=lambda c, **k: c.arm.singularity(**k),
        slots=[angle_slot("q", 6)],
        baseline=arm_q,
        outputs=outs(("f64", ()), ("f64", ()), ("f64", ()), ("f64", ())),
        check=arm_singularity_check,
    )

    def target_matrix(x):
        return pose_matrix(x["T"])

    register(
        name="SpotArm.ik_all",
        covers="spotkin.SpotArm.ik_all",
        call=lambda c, **k: c.arm.ik_all(**k),
        slots=[
            Batch("T", (4, 4), pose="T"),
            angle_slot("seed", 6, optional=True, default="omit"),
            OutSlot(("float", (8, 6)), ("flag", (8,)), ("flag", (8,)), ("status", ()), drivers=["T"]),
        ],
        baseline=arm_q,
        outputs=outs(("float", (8, 6)), ("flag", (8,)), ("flag", (8,)), ("status", ())),
        check=lambda x, out, kw, c: solution_check(c.arm.fk, target_matrix, c.arm.limits)(x, out, kw, c),
    )
    register(
        name="SpotArm.ik",
        covers="spotkin.SpotArm.ik",
        call=lambda c, **k: c.arm.ik(**k),
        slots=[
            Batch("T", (4, 4), pose="T"),
            angle_slot("seed", 6, optional=True, default="omit"),
            OutSlot(("float", (6,)), ("status", ()), drivers=["T"]),
        ],
        baseline=arm_q,
        outputs=outs(("float", (6,)), ("status", ())),
        check=lambda x, out, kw, c: nearest_check(c.arm.fk, target_matrix, c.arm.limits)(x, out, kw, c),
    )

    def arm_probe(arm, kw, ctx):
        if not isinstance(arm, sk.SpotArm):
            return f"not a SpotArm: {describe(arm)}"
        q = in_limits(arm.limits, np.random.default_rng(0), 4, margin=0.01)
        T = arm.fk(q)
        if not finite(T) or rigid_error(T) > 1e-9:
            return f"fk of in-limit angles is not a finite rigid transform: {describe(T)}"
        back, status = arm.ik(T)
        ok = status == OK
        if np.abs(arm.fk(back[ok]) - T[ok]).max(initial=0) > 1e-7:
            return "fk(ik(T)) is not T"
        if not close(pickle.loads(pickle.dumps(arm)).fk(q), T, False):
            return "a pickled copy differs"
        return None

    tool_extra = RIGID_EXTRA
    register(
        name="SpotArm",
        covers="spotkin.SpotArm",
        call=lambda c, **k: sk.SpotArm(**k),
        slots=[
            Array("mount", lambda c: (0.292, 0.0, 0.188), default="omit"),
            Real("upper_arm", 0.3385, default="omit"),
            Real("forearm", 0.4033, "finite", default="omit"),
            Real("forearm_offset", 0.075, "finite", default="omit"),
            Real("hand", 0.19557, "finite", default="omit"),
            Array("tool", lambda c: np.eye(4), optional=True, default="omit", extra=tool_extra),
            Array(
                "limits",
                lambda c: c.arm.limits,
                inf_ok=True,
                optional=True,
                default="omit",
                extra={"inverted": (lambda c, v: v[:, ::-1], REJECT, "value")},
            ),
        ],
        probe=arm_probe,
        pair_rule=lambda plan: REJECT if plan["forearm"] == plan["forearm_offset"] == "zero" else None,
        overflow_ok=True,
    )
    return tool_extra


# -- chains --


def _chain_entries(tool_extra):
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
            slots=[Batch("p", (3,))],
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
            all_slots = [Batch("target", (3,)), *held]
            all_outs = outs(("float", (4, 3)), ("flag", (4,)), ("flag", (4,)), ("flag", (4,)), ("status", ()))
            all_check = lambda x, out, kw, c, fkp=point_fk, lim=limits_of: solution_check(  # noqa: E731
                fkp(c), lambda x: x["target"], lim(c)
            )(x, out, kw, c)
        else:  # ik's for the others (a 6-joint chain; any other width is refused)
            all_slots = [Batch("target", (4, 4), pose="T"), *held]
            all_outs = outs(("float", (8, 6)), ("flag", (8,)), ("flag", (8,)), ("flag", (8,)), ("status", ()))
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


# -- the whole body --


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


def _body_entries(spec: BodySpec, methods=BODY_METHODS, light=()):
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


ROBOT_LEGS = {"spot": 4, "go2": 4, "hexapod": 6, "spot_urdf": 4}
ROBOT_ARMS = {"spot": True, "go2": False, "hexapod": False, "spot_urdf": True}


def _spot_entries():
    _body_entries(SPOT_BODY)

    def stance_probe(feet, kw, c):
        height = kw.get("height", 0.5)
        if not (isinstance(feet, np.ndarray) and feet.shape == (4, 3) and finite(feet)):
            return f"not finite (4, 3) feet: {describe(feet)}"
        if not 0 < float(height) - feet[0, 2] <= c.spot.legs[0].reach[1]:
            return f"height {height} accepted but out of reach"
        return None

    register(
        name="Spot.stance_feet",
        covers="spotkin.Spot.stance_feet",
        call=lambda c, **k: c.spot.stance_feet(**k),
        slots=[Real("height", 0.5, default="omit", skip=("int", "np_int"))],
        probe=stance_probe,
    )
    register(
        name="Spot.leg",
        covers="spotkin.Spot.leg",
        call=lambda c, **k: c.spot.leg(**k),
        slots=[Choice("name", "fl", ("fl", "fr", "hl", "hr"))],
        probe=lambda leg, kw, c: (
            None
            if isinstance(leg, sk.Leg) and leg.name == kw["name"]
            else f"not the leg {kw['name']!r}: {describe(leg)}"
        ),
    )

    def model(change):
        def make(c, rng, base):
            from spotkin.models import SPOT

            m = copy.deepcopy(SPOT)
            expect = change(m)
            return Arg(m, *(expect if isinstance(expect, tuple) else (expect or REJECT, "")))

        return make

    def spot_probe(spot, kw, c):
        if not isinstance(spot, sk.Spot):
            return f"not a Spot: {describe(spot)}"
        feet = spot.body_fk([0, 0, 0.5, 0, 0, 0], np.tile([0.0, 1.04, -1.8], 4))
        if not finite(feet):
            return f"body_fk of the nominal stance is not finite: {describe(feet)}"
        if not close(
            pickle.loads(pickle.dumps(spot)).body_fk([0, 0, 0.5, 0, 0, 0], np.zeros(12)),
            spot.body_fk([0, 0, 0.5, 0, 0, 0], np.zeros(12)),
            False,
        ):
            return "a pickled copy differs"
        return None

    def set_(path, value, expect=REJECT):
        def change(m):
            d = m
            for key in path[:-1]:
                d = d[key]
            if value is KeyError:
                del d[path[-1]]
            else:
                d[path[-1]] = value
            return expect

        return model(change)

    register(
        name="Spot",
        covers="spotkin.Spot",
        call=lambda c, **k: sk.Spot(**k),
        slots=[
            Custom(
                "model",
                {
                    "none": lambda c, r, b: Arg(None),
                    "copy": model(lambda m: ACCEPT),
                    "empty": lambda c, r, b: Arg({}, REJECT, "value"),
                    "str": lambda c, r, b: Arg("spot", REJECT, "type"),
                    "list": lambda c, r, b: Arg([], REJECT, "type"),
                    "no_arm": set_(("arm",), KeyError),
                    "no_leg_upper": set_(("leg", "upper"), KeyError),
                    "no_hip": set_(("hip_positions", "fl"), KeyError),
                    "nan_hip": set_(("hip_positions", "fl"), (math.nan, 0.0, 0.0)),
                    "inf_hip": set_(("hip_positions", "hr"), (0.0, math.inf, 0.0)),
                    "short_hip": set_(("hip_positions", "fl"), (0.3, 0.05)),
                    "str_hip": set_(("hip_positions", "fl"), "abc"),
                    "neg_upper": set_(("leg", "upper"), -0.32),
                    "nan_lower": set_(("leg", "lower"), math.nan),
                    "str_lower": set_(("leg", "lower"), "0.3"),
                    "bool_lower": set_(("leg", "lower"), True),
                    "none_offset": set_(("leg", "knee_offset"), None),
                    "nan_limits": set_(("leg", "limits"), ((math.nan, 1.0), (-1.0, 1.0), (-2.0, -0.2))),
                    "inverted_limits": set_(("arm", "limits"), ((1.0, -1.0),) * 6),
                    "short_limits": set_(("arm", "limits"), ((-1.0, 1.0),) * 5),
                    "inf_mount": set_(("arm", "mount"), (math.inf, 0.0, 0.0)),
                    "extra_key": set_(("comment",), "hello", ACCEPT),
                },
                default="omit",
            )
        ],
        probe=spot_probe,
    )


# -- robots from URDF, their legs and chains --


@functools.cache
def _go2_text() -> str:
    return sk.robots.text("go2")


@functools.cache
def _go2_kinematics() -> str:
    return re.sub(r"<inertial>.*?</inertial>", "", _go2_text(), flags=re.S)


def _fmt(v) -> str:
    """A vector as spotkin.urdf.describe prints it."""
    return "(" + ", ".join(f"{round(float(x), 12) + 0.0:.6g}" for x in np.ravel(v)) + ")"


def _urdf(body: str, name: str = "r") -> str:
    return f'<?xml version="1.0"?><robot name="{name}">{body}</robot>'


def _one_leg(prefix="L", parent="base", hip="0.2 0.1 0") -> str:
    """Links and joints of one roll-pitch-pitch leg hanging from ``parent``."""
    names = [f"{prefix}_{part}" for part in ("hip", "thigh", "calf", "foot")]
    return _urdf_links(*names) + "".join(
        [
            _urdf_joint(
                f"{prefix}_hip_joint", "revolute", parent, names[0], hip, axis="1 0 0", limits=(-0.7, 0.7)
            ),
            _urdf_joint(
                f"{prefix}_thigh_joint",
                "revolute",
                names[0],
                names[1],
                "0 0.08 0",
                axis="0 1 0",
                limits=(-2, 2),
            ),
            _urdf_joint(
                f"{prefix}_calf_joint",
                "revolute",
                names[1],
                names[2],
                "0 0 -0.2",
                axis="0 1 0",
                limits=(-2.6, -0.2),
            ),
            _urdf_joint(f"{prefix}_foot_joint", "fixed", names[2], names[3], "0 0 -0.2"),
        ]
    )


@functools.cache
def _bad_urdfs() -> dict:
    """Malformed or unusable descriptions: name -> (text, expect, why)."""
    leg = '<link name="base"/>' + _one_leg()
    go2 = _go2_text()
    laughs = "".join(f'<!ENTITY l{i + 1} "{f"&l{i};" * 10}">' for i in range(9))
    return {
        "empty": ("", REJECT, "value"),
        "whitespace": (" \n\t", REJECT, "value"),
        "not_xml": ("hello", REJECT, "value"),
        "truncated": (go2[: len(go2) // 2], REJECT, "value"),
        "not_robot": ('<sdf version="1.6"/>', REJECT, "value"),
        "no_links": ('<robot name="r"/>', REJECT, "value"),
        "loop": (
            _urdf(
                '<link name="base"/><link name="a"/><link name="b"/>'
                + _urdf_joint("j0", "fixed", "base", "a", "0 0 0")
                + _urdf_joint("j1", "revolute", "a", "b", "0 0 0", axis="1 0 0", limits=(-1, 1))
                + _urdf_joint("j2", "revolute", "b", "a", "0 0 0", axis="1 0 0", limits=(-1, 1))
            ),
            REJECT,
            "value",
        ),
        "self_parent": (
            _urdf(leg.replace('parent link="L_thigh"', 'parent link="L_calf"')),
            REJECT,
            "value",
        ),
        "two_roots": (_urdf(leg + '<link name="orphan"/>'), REJECT, "value"),
        "undeclared_link": (_urdf(leg.replace('<link name="L_calf"/>', "")), REJECT, "value"),
        "duplicate_link": (_urdf(leg + '<link name="L_calf"/>'), REJECT, "value"),
        "duplicate_joint": (_urdf(leg.replace("L_calf_joint", "L_thigh_joint")), REJECT, "value"),
        "no_limit": (
            _urdf(leg.replace('<limit lower="-2.6" upper="-0.2" effort="10" velocity="5"/>', "")),
            REJECT,
            "value",
        ),
        "inverted_limit": (
            _urdf(leg.replace('lower="-2.6" upper="-0.2"', 'lower="-0.2" upper="-2.6"')),
            REJECT,
            "value",
        ),
        "nan_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="nan 0 -0.2"', 1)), REJECT, "value"),
        "inf_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="1e999 0 -0.2"', 1)), REJECT, "value"),
        "short_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="0 -0.2"', 1)), REJECT, "value"),
        "word_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="0 zero -0.2"', 1)), REJECT, "value"),
        "zero_axis": (_urdf(leg.replace('xyz="0 1 0"', 'xyz="0 0 0"', 1)), REJECT, "value"),
        "floating": (_urdf(leg.replace('type="fixed"', 'type="floating"')), REJECT, "value"),
        "unknown_type": (_urdf(leg.replace('type="fixed"', 'type="ball"')), REJECT, "value"),
        "no_parent": (_urdf(leg.replace('<parent link="L_calf"/>', "")), REJECT, "value"),
        "negative_mass": (
            _urdf(
                leg.replace(
                    '<link name="L_hip"/>',
                    '<link name="L_hip"><inertial><mass value="-1"/>'
                    '<inertia ixx="1" iyy="1" izz="1"/></inertial></link>',
                )
            ),
            REJECT,
            "value",
        ),
        "asymmetric_inertia": (
            _urdf(
                leg.replace(
                    '<link name="L_hip"/>',
                    '<link name="L_hip"><inertial><mass value="1"/>'
                    '<inertia ixx="1" iyy="1" izz="-5"/></inertial></link>',
                )
            ),
            REJECT,
            "value",
        ),
        "no_legs": (  # a 2-joint arm only: nothing recognised
            _urdf(
                '<link name="base"/><link name="a"/><link name="b"/>'
                + _urdf_joint("j1", "revolute", "base", "a", "0 0 0.1", axis="0 0 1", limits=(-1, 1))
                + _urdf_joint("j2", "revolute", "a", "b", "0 0 0.3", axis="0 1 0", limits=(-1, 1))
            ),
            REJECT,
            "value",
        ),
        "yaw_leg": (_urdf(leg.replace('xyz="1 0 0"', 'xyz="0 0 1"', 1)), REJECT, "value"),  # z-y-y
        "laughs": (  # entity expansion (a billion laughs): refused by the parser, quickly
            f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY l0 "lol">{laughs}]><robot name="&l9;">'
            '<link name="a"/></robot>',
            REJECT,
            "value",
        ),
        "external_entity": (
            '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
            '<robot name="&x;"><link name="a"/></robot>',
            REJECT,
            "value",
        ),
        "nul": (go2.replace("<robot", "<robot\0", 1), REJECT, "value"),
        "surrogate": (go2.replace('name="base"', 'name="\ud800"', 1), REJECT, ""),
    }


@functools.cache
def _odd_urdfs() -> dict:
    """Unusual but valid descriptions: name -> text."""
    go2 = _go2_text()
    body = go2.split("?>", 1)[1] if go2.startswith("<?xml") else go2
    return {
        "comments": go2.replace("<link", "<!-- a comment --><link", 3),
        "no_declaration": body,
        "extra_tags": go2.replace(
            "</robot>",
            '<gazebo reference="base"><material>x</material></gazebo><transmission name="t"/>'
            '<material name="m"/></robot>',
        ),
        "mimic": _urdf(
            '<link name="base"/>'
            + _one_leg()
            + _one_leg("R", hip="0.2 -0.1 0").replace(
                '<limit lower="-2.6"', '<mimic joint="L_calf_joint"/><limit lower="-2.6"', 1
            )
        ),
        "one_leg": _urdf('<link name="base"/>' + _one_leg()),
        "deep_fixed": _urdf(  # the leg hangs below 300 fixed links
            '<link name="base"/>'
            + _urdf_links(*(f"f{i}" for i in range(300)))
            + "".join(
                _urdf_joint(f"fj{i}", "fixed", "base" if i == 0 else f"f{i - 1}", f"f{i}", "0 0 0.001")
                for i in range(300)
            )
            + _one_leg(parent="f299")
        ),
    }


def _latin1_urdf() -> bytes:
    """Go2 declared and encoded as ISO-8859-1, with a non-ASCII link name (not a leg's)."""
    go2 = _go2_text()
    body = go2.split("?>", 1)[1] if go2.startswith("<?xml") else go2
    return ('<?xml version="1.0" encoding="ISO-8859-1"?>' + body.replace('"radar"', '"r\xe4dar"')).encode(
        "latin-1"
    )


GO2_FEET = ("FL_foot", "FR_foot", "RL_foot", "RR_foot")
GO2_NOMINAL = {
    "FL": (0.0, 0.85, -1.7),
    "FR": (0.05, 0.9, -1.6),
    "RL": (0.0, 0.8, -1.5),
    "RR": (-0.1, 1.0, -1.8),
}


def _robot_options():
    """Custom slots for from_urdf's keyword options, valid for Go2's names."""

    def arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    feet = Custom(
        "feet",
        {
            "none": arg(None),
            "all": arg(list(GO2_FEET)),
            "tuple": arg(GO2_FEET),
            "reversed": arg(GO2_FEET[::-1]),
            "one": arg("FL_foot"),
            "two": arg(["FL_foot", "RR_foot"]),
            "calf": arg(["FL_calf"], REJECT, "value"),  # the knee itself: no knee-to-foot vector
            "thigh": arg(["FL_thigh"], REJECT, "value"),  # two joints above it
            "base": arg(["base"], REJECT, "value"),
            "unknown": arg(["FL_foot", "nope"], REJECT, "value"),
            "twice": arg(["FL_foot", "FL_foot"], REJECT, "value"),
            "same_leg": arg(["FL_foot", "FL_calf_rotor"], REJECT, "value"),
            "empty": arg([], REJECT, "value"),
            "int": arg(1, REJECT),
            "none_item": arg([None], REJECT),
            "nested": arg([["FL_foot"]], REJECT),
            "bytes": arg(b"FL_foot", REJECT),
        },
        default="omit",
    )
    offset = np.array([0.0, 0.0, -0.02])
    contact_offset = Custom(
        "contact_offset",
        {
            "none": arg(None),
            "vector": arg(offset),
            "list": arg(offset.tolist()),
            "ints": arg(np.zeros(3, dtype=np.int64)),
            "float32": arg(offset.astype(np.float32)),
            "dict": arg({"FL_foot": offset, "RR_foot": (0.01, 0.0, -0.02)}),
            "dict_unknown": arg({"nope": offset}, REJECT, "value"),
            "dict_not_foot": arg({"FL_calf": offset}, REJECT, "value"),
            "dict_nan": arg({"FL_foot": (math.nan, 0.0, 0.0)}, REJECT, "value"),
            "dict_none": arg({"FL_foot": None}, REJECT),
            "nan": arg((math.nan, 0.0, 0.0), REJECT, "value"),
            "inf": arg((0.0, math.inf, 0.0), REJECT, "value"),
            "short": arg((0.0, 0.0), REJECT, "value"),
            "2d": arg(np.zeros((4, 3)), REJECT, "value"),
            "bool": arg(True, REJECT),
            "str": arg("abc", REJECT),  # documented: TypeError for non-numeric input
            "complex": arg(offset + 0j, REJECT, "type"),
            "masked": arg(
                np.ma.masked_array(offset, [True, False, False]), REJECT
            ),  # its mask would be ignored
        },
        default="omit",
    )
    nominal = Custom(
        "nominal",
        {
            "none": arg(None),
            "one": arg({"FL": GO2_NOMINAL["FL"]}),
            "all": arg(dict(GO2_NOMINAL)),
            "forward": arg({"RL": (0.0, -0.6, 1.4)}),  # knee forward: out of the limits, still a slot
            "array": arg({"FR": np.array(GO2_NOMINAL["FR"], dtype=np.float32)}),
            "unknown": arg({"XX": (0.0, 0.8, -1.5)}, REJECT, "value"),
            "nan": arg({"FL": (0.0, math.nan, -1.5)}, REJECT, "value"),
            "short": arg({"FL": (0.0, 0.8)}, REJECT, "value"),
            "str_value": arg({"FL": "abc"}, REJECT, "type"),
            "none_value": arg({"FL": None}, EITHER),
            "list": arg([(0.0, 0.8, -1.5)], REJECT),
            "str": arg("FL", REJECT),
        },
        default="omit",
    )
    return feet, contact_offset, nominal


QUAD_ROLES = ("front_left", "front_right", "hind_left", "hind_right")


def _limit_options():
    """The ``limits`` and ``leg_order`` slots of from_urdf and from_urdf_string, valid for Go2's names."""

    def arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    limits = Custom(
        "limits",
        {
            "none": arg(None),
            "empty": arg({}),
            "knee": arg({"FL_calf_joint": (-2.0, -1.0)}),
            "unlimited": arg({"RR_hip_joint": (-np.inf, np.inf)}),
            "array": arg({"FR_thigh_joint": np.array([-1.0, 2.0], dtype=np.float32)}),
            "point": arg({"FR_thigh_joint": (0.5, 0.5)}),
            "reversed": arg({"FL_calf_joint": (-1.0, -2.0)}, REJECT, "value"),
            "nan": arg({"FL_calf_joint": (np.nan, 1.0)}, REJECT, "value"),
            "unknown": arg({"no_such_joint": (0.0, 1.0)}, REJECT, "value"),
            "fixed": arg({"FL_foot_joint": (0.0, 1.0)}, REJECT, "value"),
            "three": arg({"FL_calf_joint": (0.0, 1.0, 2.0)}, REJECT, "value"),
            "text": arg({"FL_calf_joint": "wide"}, REJECT),
            "int_key": arg({3: (0.0, 1.0)}, REJECT, "type"),
            "list": arg([(0.0, 1.0)], REJECT, "type"),
            "int": arg(1, REJECT, "type"),
        },
        default="omit",
    )
    leg_order = Choice("leg_order", "urdf", ("urdf", "roles"), default="omit")
    return limits, leg_order


def _option_pairs(plan):
    """The options name Go2's feet and legs: a subset of feet leaves some nominal stances nameless."""
    if plan.get("nominal") == "all" and plan.get("feet") in ("one", "two"):
        return REJECT
    if plan.get("nominal") in ("forward", "array") and plan.get("feet") in ("one", "two"):
        return REJECT  # RL, FR not among FL, RR
    if plan.get("contact_offset") == "dict" and plan.get("feet") == "one":
        return REJECT  # RR_foot is not a foot then
    if plan.get("feet") == "calf" and plan.get("contact_offset") in (
        "vector",
        "list",
        "float32",
        "dict_not_foot",
    ):
        # the offset is the knee-to-foot vector: a leg (and the calf is then a foot)
        return ACCEPT
    return None


def robot_probe(robot, kw, c):
    """A robot as its description says: every foot (body_fk) where the URDF tree puts the foot link
    (plus its contact offset), the nominal stances in the preferred slots, and a faithful pickle."""
    if not isinstance(robot, sk.Robot):
        return f"not a Robot: {describe(robot)}"
    n = robot.n_legs
    if len(robot.leg_joint_names) != 3 * n or robot.hip_positions.shape != (n, 3) or len(robot.legs) != n:
        return f"{n} legs but {len(robot.leg_joint_names)} leg joints"
    model = robot.model
    specs, _ = sk.urdf.find_legs(model, feet=kw.get("feet"), contact_offset=kw.get("contact_offset"))
    if kw.get("leg_order") == "roles":  # the legs front to hind, left before right
        by_name = {spec.name: spec for spec in specs}
        if sorted(by_name) != sorted(robot.leg_names):
            return f"legs {robot.leg_names}, the description's {sorted(by_name)}"
        specs = [by_name[name] for name in robot.leg_names]
        hips = robot.hip_positions
        if n == 4 and (hips[:, 1] > 0).sum() == 2 and robot.leg_roles != QUAD_ROLES:
            return f"leg_order='roles' gave the roles {robot.leg_roles}"
        if any(hips[k, 0] < hips[k + 1, 0] - 1e-9 for k in range(0, n - 1, 2) if k + 1 < n and n == 4):
            return f"leg_order='roles': the legs are not front to hind: {robot.leg_roles}"
    if tuple(spec.name for spec in specs) != robot.leg_names:
        return f"legs {robot.leg_names}, the description's {[spec.name for spec in specs]}"
    limits = kw.get("limits")
    if isinstance(limits, dict):  # the overrides reach the legs
        for name, pair in limits.items():
            if name in robot.leg_joint_names:
                k = robot.leg_joint_names.index(name)
                legs_of = [i for i, spec in enumerate(specs) if name in spec.joint_names]
                row = robot.legs[legs_of[0]].limits[specs[legs_of[0]].joint_names.index(name)]
                if not np.array_equal(row, np.asarray(pair, dtype=np.float64)):
                    return f"limits={limits}: joint {name} (q column {k}) has the limits {row}"
    q = np.random.default_rng(0).uniform(-0.6, 0.6, 3 * n)
    pose = [0.1, -0.05, 0.3, 0.1, -0.2, 0.3]
    T = pose_matrix(pose)
    feet = robot.body_fk(pose, q)
    values = dict(zip(robot.leg_joint_names, q.tolist()))
    for k, spec in enumerate(specs):
        F = model.placement(spec.foot, values)
        ref = T[:3, 3] + T[:3, :3] @ (F[:3, 3] + F[:3, :3] @ spec.contact_offset)
        if not close(feet[k], ref, False):
            return f"leg {spec.name}: body_fk puts the foot at {feet[k]}, the URDF tree at {ref}"
    nominal = kw.get("nominal")
    if isinstance(nominal, dict):
        for name, stance in nominal.items():
            if stance is None:
                continue
            leg = robot.leg(name)
            stance = np.asarray(stance, dtype=np.float64)
            slot = leg.preferred_slot
            held = leg.ik_all(leg.fk(stance)).q[slot]
            if not np.allclose(np.angle(np.exp(1j * (held - stance))), 0.0, atol=1e-7):
                return f"leg {name}: the preferred slot {slot} holds {held}, not the nominal stance {stance}"
    try:
        clone = pickle.loads(pickle.dumps(robot))
    except Exception as error:
        return f"a pickled copy cannot be rebuilt: {type(error).__name__}: {error}"[:400]
    if not close(clone.body_fk(pose, q), feet, False):
        return "a pickled copy differs"
    if list(clone.model.links) != list(model.links) or clone.joint_names != robot.joint_names:
        return f"a pickled copy has other names: links {sorted(set(clone.model.links) ^ set(model.links))}"
    if [leg.preferred_slot for leg in clone.legs] != [leg.preferred_slot for leg in robot.legs]:
        return "a pickled copy has other preferred slots"
    return None


def chain_of_link_probe(key):
    """Robot.chain: the URDF's joints, limits and FK (the tree's placements) from base to link."""

    def probe(chain, kw, c):
        if not isinstance(chain, sk.Chain):
            return f"not a Chain: {describe(chain)}"
        model = c.robot(key).model
        link, base = kw["link"], kw.get("base") or model.root
        joints = [j for j in model.path(link, base) if j.actuated]
        if chain.joint_names != tuple(j.name for j in joints) or chain.dof != len(joints):
            return f"joints {chain.joint_names}, the description's {[j.name for j in joints]}"
        if not (
            close(chain.lower, [j.lower for j in joints], False)
            and close(chain.upper, [j.upper for j in joints], False)
        ):
            return "limits differ from the description's"
        q = np.random.default_rng(1).uniform(-1.0, 1.0, chain.dof)
        values = {j.name: v for j, v in zip(joints, q.tolist())}
        ref = np.linalg.inv(model.placement(base)) @ model.placement(link, values)
        if not close(chain.fk(q), ref, False):
            return f"fk {describe(chain.fk(q))}, the URDF tree's {describe(ref)}"
        if not close(pickle.loads(pickle.dumps(chain)).fk(q), ref, False):
            return "a pickled copy differs"
        return None

    return probe


def link_table(valid, others):
    """A Custom slot table of link names: valid ones, bad ones, non-strings."""
    table = {name: (lambda c, r, b, v=value: Arg(v)) for name, value in valid.items()}
    table.update({name: (lambda c, r, b, v=value: Arg(v, REJECT, "value")) for name, value in others.items()})
    table.update(
        {
            "none": lambda c, r, b: Arg(None, REJECT),
            "int": lambda c, r, b: Arg(1, REJECT),
            "bytes": lambda c, r, b: Arg(valid["valid"].encode(), REJECT),
            "list": lambda c, r, b: Arg([valid["valid"]], REJECT),
            "np_str": lambda c, r, b: Arg(np.str_(valid["valid"])),
            "empty": lambda c, r, b: Arg("", REJECT, "value"),
            "space": lambda c, r, b: Arg(valid["valid"] + " ", REJECT, "value"),
            "nul": lambda c, r, b: Arg(valid["valid"] + "\0", REJECT, "value"),
        }
    )
    return table


@functools.cache
def _model_of(key):
    return sk.urdf.parse_urdf(sk.robots.text(ROBOT_FILES.get(key, "spot_with_arm")))


def chain_pairs(key, links, bases):
    """link and base both names: accepted iff the link is below the base with a moving joint between."""

    def rule(plan):
        link, base = links.get(plan["link"]), bases.get(plan["base"])
        if link is None or base is None:
            return None  # not a name: the slots' own expectations
        model = _model_of(key)
        try:
            moving = [j for j in model.path(link, base) if j.actuated]
        except ValueError:
            return REJECT
        return ACCEPT if moving else REJECT

    return rule


def _ignored_nominal(plan):
    """With a preferred_slot, nominal is not used: whether a bad one is still refused is not documented."""
    given = ("valid", "min", "max", "np_int", "zero_d")
    if plan["preferred_slot"] in given and plan["nominal"] not in ("omit", "none"):
        return EITHER
    return None


def geometry_fk(a, b, c, signs, q):
    """The documented leg FK p = Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c)), in NumPy."""

    def rx(t):
        return np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]])

    def ry(t):
        return np.array([[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]])

    s1, s2, s3 = signs
    return rx(s1 * q[0]) @ (a + ry(s2 * q[1]) @ (b + ry(s3 * q[2]) @ c))


def geometry_probe(leg, kw, c):
    if not isinstance(leg, sk.Leg):
        return f"not a Leg: {describe(leg)}"
    a, b, c3 = (np.asarray(kw[k], dtype=np.float64) for k in "abc")
    signs = np.asarray(kw.get("signs", (1.0, 1.0, 1.0)), dtype=np.float64)
    for name, got, want in (("a", leg.a, a), ("b", leg.b, b), ("c", leg.c, c3), ("signs", leg.signs, signs)):
        if not close(got, want, False):
            return f"leg.{name} is {got}, given {want}"
    if not close(leg.hip_offset, a[1] + b[1] + c3[1], False):
        return f"hip_offset {leg.hip_offset}, a_y + b_y + c_y = {a[1] + b[1] + c3[1]}"
    q = in_limits(leg.limits, np.random.default_rng(2), 6, margin=0.01)
    p = leg.fk(q)
    ref = np.array([geometry_fk(a, b, c3, signs, qk) for qk in q])
    if not close(p, ref, False):
        return f"fk {describe(p)} is not Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c)) = {describe(ref)}"
    if not close(leg.knee(q), knee_point(leg, q), False):
        return "knee(q) is not Rx(s1 q1) (a + Ry(s2 q2) b)"
    sol = leg.ik_all(p)
    for k in range(len(q)):
        wrapped = np.abs(np.angle(np.exp(1j * (sol.q[k] - q[k])))).max(axis=1)
        if not (sol.exists[k] & (wrapped < 1e-6)).any():
            return f"ik_all(fk(q)) does not hold q = {q[k]}: {describe(sol.q[k])}"
    slot = kw.get("preferred_slot")
    if slot is not None and leg.preferred_slot != int(slot):
        return f"preferred_slot {leg.preferred_slot}, given {slot}"
    nominal = kw.get("nominal")
    if slot is None and nominal is not None:
        stance = np.asarray(nominal, dtype=np.float64)
        held = leg.ik_all(leg.fk(stance)).q[leg.preferred_slot]
        if not np.allclose(np.angle(np.exp(1j * (held - stance))), 0.0, atol=1e-7):
            return f"the preferred slot {leg.preferred_slot} holds {held}, not the nominal stance {stance}"
    clone = pickle.loads(pickle.dumps(leg))
    if not close(clone.fk(q), p, False) or clone.preferred_slot != leg.preferred_slot:
        return "a pickled copy differs"
    return None


def joints_fk(placements, axes, types, base, tool, q):
    """The documented chain FK base · prod(placements[j] · M_j(q_j)) · tool, in NumPy and SciPy."""
    from scipy.spatial.transform import Rotation

    T = np.array(base, dtype=np.float64)
    for P, w, kind, value in zip(placements, axes, types, q):
        w = np.asarray(w, dtype=np.float64) / np.linalg.norm(w)
        M = np.eye(4)
        if kind == 0:
            M[:3, :3] = Rotation.from_rotvec(w * value).as_matrix()
        else:
            M[:3, 3] = w * value
        T = T @ P @ M
    return T @ tool


def from_joints_probe(chain, kw, c):
    if not isinstance(chain, sk.Chain):
        return f"not a Chain: {describe(chain)}"
    placements = np.asarray(kw["placements"], dtype=np.float64)
    n = len(placements)
    types = np.asarray(kw["types"] if kw.get("types") is not None else np.zeros(n), dtype=np.float64)
    base = np.asarray(kw["base"] if kw.get("base") is not None else np.eye(4), dtype=np.float64)
    tool = np.asarray(kw["tool"] if kw.get("tool") is not None else np.eye(4), dtype=np.float64)
    if chain.dof != n or not np.array_equal(chain.sigma, types.astype(np.int8)):
        return f"dof {chain.dof}, sigma {chain.sigma} for {n} joints of types {types}"
    names = kw.get("joint_names")
    if names is not None and chain.joint_names != tuple(str(name) for name in names):
        return f"joint_names {chain.joint_names}, given {names}"
    q = np.linspace(-0.9, 0.7, n)
    ref = joints_fk(placements, np.asarray(kw["axes"], dtype=np.float64), types, base, tool, q)
    T = chain.fk(q)
    if not finite(T) or not close(T, ref, False):
        return f"fk {describe(T)} is not base · prod(placement · motion) · tool = {describe(ref)}"
    frames = chain.frames(q)
    if not close(frames[-1], T, False) or not close(frames[0], base, False):
        return "frames do not run from the base to fk(q)"
    if not close(pickle.loads(pickle.dumps(chain)).fk(q), T, False):
        return "a pickled copy differs"
    return None


def _robot_entries():
    # Go2: Spot's code with other numbers; the hexapod: six legs, their joints interleaved in q
    _body_entries(BodySpec("go2"), BODY_METHODS, light=BODY_METHODS)
    _body_entries(BodySpec("hexapod"), BODY_METHODS[:-1], light=("body_jacobian", "body_rates", "fk_all"))
    # Spot from its URDF: the arm is a Chain (closed form by ik)
    _body_entries(BodySpec("spot_urdf"), ("fk_all", "arm_ik_world"), light=("fk_all", "arm_ik_world"))

    # stance_feet, leg
    def stance_probe(key):
        def probe(feet, kw, c):
            robot = c.robot(key)
            height, radius = float(kw.get("height", 0.5)), float(kw.get("foot_radius", 0.0))
            n = robot.n_legs
            if not (isinstance(feet, np.ndarray) and feet.shape == (n, 3) and feet.dtype == np.float64):
                return f"not (n, 3) float64 feet: {describe(feet)}"
            hips = robot.hip_positions
            for k, leg in enumerate(robot.legs):
                want = [hips[k, 0] + leg.a[0], hips[k, 1] + leg.hip_offset, radius]
                if not close(feet[k], want, False):
                    return f"foot {k} is {feet[k]}, not below its hip-pitch joint at {want}"
                drop, (lo, hi) = height + hips[k, 2] + leg.a[2] - radius, leg.reach
                if not (0 < drop <= hi * (1 + 1e-12) and drop >= lo * (1 - 1e-12)):
                    return f"height {height} accepted but leg {k} out of reach ({drop} not in [{lo}, {hi}])"
            status = robot.body_ik([0.0, 0.0, height, 0.0, 0.0, 0.0], feet).status
            if (status == INVALID).any():
                return f"body_ik of the stance gives {status}"
            return None

        return probe

    for key in ("go2", "hexapod"):
        height = STANCE_HEIGHT[key]
        register(
            name=f"Robot.stance_feet[{key}]",
            covers="spotkin.Robot.stance_feet",
            call=lambda c, key=key, **k: c.robot(key).stance_feet(**k),
            slots=[
                Real("height", height, skip=("int", "np_int")),
                Real("foot_radius", 0.02, "nonneg", default="omit", skip=("int", "np_int")),
            ],
            probe=stance_probe(key),
        )
    for key, names in (("go2", ("FL", "FR", "RL", "RR")), ("hexapod", HEXAPOD_LEGS)):
        register(
            name=f"Robot.leg[{key}]",
            covers="spotkin.Robot.leg",
            call=lambda c, key=key, **k: c.robot(key).leg(**k),
            slots=[Choice("name", names[1], names)],
            probe=lambda leg, kw, c, key=key: (
                None
                if isinstance(leg, sk.Leg)
                and leg is c.robot(key).legs[c.robot(key).leg_names.index(kw["name"])]
                else f"not the leg {kw['name']!r}: {describe(leg)}"
            ),
        )

    # chains of links
    chain_sets = {
        "Robot.chain": (
            "go2",
            {"valid": "FL_foot", "calf": "RR_calf", "hip": "FR_hip", "rotor": "RL_thigh_rotor"},
            {"valid": "base", "hip": "FL_hip", "other_leg": "FR_hip", "same": "FL_foot", "unknown": "nope"},
        ),
        "Spot.chain": (
            "spot",
            {
                "valid": "arm_hand",
                "finger": "arm_link_fngr",
                "foot": "rear_right_foot",
                "hr0": "arm_link_hr0",
            },
            {
                "valid": "body",
                "shoulder": "arm_link_sh0",
                "leg": "front_left_hip",
                "same": "arm_hand",
                "unknown": "nope",
            },
        ),
    }
    for name, (key, links, bases) in chain_sets.items():
        bad_links = {"root": bases["valid"], "unknown": "nope"}
        if key == "go2":
            bad_links["fixed_only"] = "radar"  # hangs from the base by a fixed joint
        link = Custom("link", link_table(links, bad_links))
        base_table = {
            "none": lambda c, r, b: Arg(None),
            **{
                k: (lambda c, r, b, v=v: Arg(v))
                for k, v in bases.items()
                if k in ("valid", "hip", "shoulder")
            },
            **{
                k: (lambda c, r, b, v=v: Arg(v, REJECT, "value"))
                for k, v in bases.items()
                if k in ("other_leg", "leg", "same", "unknown")
            },
            "int": lambda c, r, b: Arg(1, REJECT),
            "list": lambda c, r, b, v=bases["valid"]: Arg([v], REJECT),
        }
        register(
            name=name,
            covers=f"spotkin.{name}",
            call=lambda c, key=key, **k: c.robot(key).chain(**k),
            slots=[link, Custom("base", base_table, default="omit")],
            probe=chain_of_link_probe(key),
            pair_rule=chain_pairs(
                key, {**links, **bad_links}, {**bases, "omit": bases["valid"], "none": bases["valid"]}
            ),
        )

    def describe_probe(key):
        def probe(text, kw, c):
            robot = c.robot(key)
            if not isinstance(text, str):
                return f"not a str: {describe(text)}"
            if robot.model.name not in text or f"legs ({robot.n_legs}):" not in text:
                return f"the summary does not name the robot or its {robot.n_legs} legs: {text[:200]!r}"
            legs = text[text.index(f"legs ({robot.n_legs}):") :]
            for name, leg in zip(robot.leg_names, robot.legs):
                # Spot's summary is its URDF's, under the URDF's leg names (front_left for fl)
                named = isinstance(robot, sk.Spot) or f"  {name}: joints" in legs
                if not named or f"c = {_fmt(leg.c)}" not in legs:
                    return f"the summary does not describe leg {name} (c = {_fmt(leg.c)}): {legs[:300]!r}"
            return None

        return probe

    for name, key in (
        ("Robot.describe", "hexapod"),
        ("Robot.describe[go2_feet]", "go2_feet"),
        ("Spot.describe", "spot"),
    ):
        register(
            name=name,
            covers=f"spotkin.{name.split('[')[0]}",
            call=lambda c, key=key: c.robot(key).describe(),
            probe=describe_probe(key),
        )

    # construction
    feet, contact_offset, nominal = _robot_options()
    limit_slot, order_slot = _limit_options()

    def path_table():
        def files(c):
            return c.files()

        def file(name, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(files(c)[name], expect, why)

        return {
            "valid": lambda c, r, b: Arg(sk.robots.path("go2")),
            "pathlib": lambda c, r, b: Arg(pathlib.Path(sk.robots.path("go2"))),
            "bytes": lambda c, r, b: Arg(os.fsencode(sk.robots.path("go2")), EITHER),
            "latin1": file("latin1"),  # declared ISO-8859-1
            "utf16": file("utf16"),  # declared UTF-16, with a byte-order mark
            "missing": file("missing", REJECT, "os"),
            "directory": file("directory", REJECT, "os"),
            "empty_path": lambda c, r, b: Arg("", REJECT, "os"),
            "empty_file": file("empty", REJECT, "value"),
            "not_xml": file("not_xml", REJECT, "value"),
            "loop": file("loop", REJECT, "value"),
            "nul": lambda c, r, b: Arg(sk.robots.path("go2") + "\0", REJECT),
            # TypeError from os.fspath, which does not name the argument (not a numeric input)
            "none": lambda c, r, b: Arg(None, REJECT),
            "int": lambda c, r, b: Arg(3, REJECT),
            "list": lambda c, r, b: Arg([sk.robots.path("go2")], REJECT),
        }

    def some(slot, names):  # from_urdf_string fuzzes the options in full
        return Custom(slot.name, {name: slot.table[name] for name in names}, default=slot.default)

    register(
        name="Robot.from_urdf",
        covers="spotkin.Robot.from_urdf",
        pairs=20,
        call=lambda c, **k: sk.Robot.from_urdf(**k),
        slots=[
            Custom("path", path_table()),
            some(feet, ("none", "two", "calf", "int")),
            some(contact_offset, ("vector", "dict", "nan")),
            some(nominal, ("one", "unknown")),
            limit_slot,
            order_slot,
        ],
        probe=robot_probe,
        pair_rule=_option_pairs,
        also_raises=(OSError,),
    )

    def text_table():
        def text(value, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(value() if callable(value) else value, expect, why)

        table = {
            "valid": text(_go2_kinematics),  # the options' cases: Go2 without its inertials (faster)
            "inertials": text(_go2_text),
            "np_str": text(lambda: np.str_(_go2_text())),
            "bytes": text(lambda: _go2_text().encode(), REJECT, "type"),
            "none": text(None, REJECT, "type"),
            "int": text(1, REJECT, "type"),
            "path": text(lambda: sk.robots.path("go2"), REJECT, "value"),
        }
        table.update({name: text(value) for name, value in _odd_urdfs().items()})
        table.update({name: text(*spec) for name, spec in _bad_urdfs().items()})
        return table

    go2_texts = ("valid", "inertials", "np_str", "comments", "no_declaration", "extra_tags")
    neutral = {
        "feet": ("omit", "none"),
        "contact_offset": ("omit", "none", "vector", "list", "ints", "float32"),
        "nominal": ("omit", "none"),
        "limits": ("omit", "none", "empty"),
        "leg_order": ("omit", "valid", "choice:urdf", "choice:roles"),
    }

    def text_pairs(plan):
        """Go2's texts take Go2's names; the other valid texts have none of them (options naming
        Go2's feet or legs are refused, for that reason first)."""
        if plan["text"] in go2_texts:
            return _option_pairs(plan)
        if plan["text"] in _odd_urdfs() and any(plan[k] not in v for k, v in neutral.items()):
            return REJECT
        return None

    register(
        name="Robot.from_urdf_string",
        covers="spotkin.Robot.from_urdf_string",
        pairs=20,
        call=lambda c, **k: sk.Robot.from_urdf_string(**k),
        slots=[Custom("text", text_table()), feet, contact_offset, nominal, limit_slot, order_slot],
        probe=robot_probe,
        pair_rule=text_pairs,
    )
    register(
        name="Robot",
        covers="spotkin.Robot",
        call=lambda c: sk.Robot(),
        expect=REJECT,
        why="type",  # built by from_urdf or from_urdf_string only
    )
    register(
        name="Spot.from_urdf",
        covers="spotkin.Spot.from_urdf",
        call=lambda c: sk.Spot.from_urdf(sk.robots.path("spot_with_arm")),
        expect=REJECT,
        why="type",  # by design
    )
    register(
        name="Spot.from_urdf_string",
        covers="spotkin.Spot.from_urdf_string",
        call=lambda c: sk.Spot.from_urdf_string(sk.robots.text("spot_with_arm")),
        expect=REJECT,
        why="type",
    )

    # legs of any geometry
    def vector(name, value, **kw):
        return Array(name, lambda c: value, **kw)

    along_pitch = {
        "pitch_axis": (lambda c, v: np.array([0.0, 0.1, 0.0]), REJECT, "value"),
        "zeros": (lambda c, v: np.zeros(3), REJECT, "value"),
    }
    register(
        name="Leg.from_geometry",
        covers="spotkin.Leg.from_geometry",
        call=lambda _ctx, **k: sk.Leg.from_geometry(**k),  # (c is an argument)
        slots=[
            vector("a", (0.01, 0.08, 0.01), extra={"zeros": (lambda c, v: np.zeros(3), ACCEPT, "")}),
            vector("b", (0.02, 0.005, -0.2), extra=along_pitch),
            vector("c", (0.01, 0.01, -0.21), extra=along_pitch),
            vector(
                "signs",
                (1.0, -1.0, 1.0),
                default="omit",
                extra={
                    "negative": (lambda c, v: -np.ones(3), ACCEPT, ""),
                    "two": (lambda c, v: np.array([2.0, 1.0, 1.0]), REJECT, "value"),
                    "zero": (lambda c, v: np.array([1.0, 0.0, 1.0]), REJECT, "value"),
                    "half": (lambda c, v: np.array([1.0, 1.0, 0.5]), REJECT, "value"),
                },
            ),
            Array(
                "limits",
                lambda c: [(-0.7, 0.7), (-2.2, 2.2), (-2.6, -0.2)],
                inf_ok=True,
                optional=True,
                default="omit",
                extra={
                    "unbounded": (lambda c, v: [[-np.inf, np.inf]] * 3, ACCEPT, ""),
                    "inverted": (lambda c, v: v[:, ::-1], REJECT, "value"),
                    "transposed": (lambda c, v: v.T, REJECT, "shape"),
                    "point": (lambda c, v: np.stack([v[:, 0], v[:, 0]], 1), ACCEPT, ""),
                },
            ),
            Custom(
                "name",
                {
                    "valid": lambda c, r, b: Arg("R1"),
                    "none": lambda c, r, b: Arg(None),
                    "empty": lambda c, r, b: Arg(""),
                    "int": lambda c, r, b: Arg(1, EITHER),
                },
                default="omit",
            ),
            Int("preferred_slot", 1, 0, 4, optional=True, default="omit"),
            vector("nominal", (0.1, 0.8, -1.4), optional=True, default="omit"),
        ],
        probe=geometry_probe,
        overflow_ok=True,
        pair_rule=_ignored_nominal,
    )

    # knee origins
    for key, get in (
        ("fl", lambda c: c.spot.leg("fl")),
        ("hexapod_R1", lambda c: c.robot("hexapod").leg("R1")),
    ):

        def knee_check(x, out, kw, c, get=get):
            (knee,) = out
            ref = knee_point(get(c), x["q"])
            if not close(knee, ref, x["q"].dtype == np.float32):
                return f"{describe(knee)} is not Rx(s1 q1) (a + Ry(s2 q2) b) = {describe(ref)}"
            return None

        def knee_q(c, rng, n, get=get):
            return {"q": in_limits(get(c).limits, rng, n)}

        register(
            name=f"Leg.knee[{key}]",
            covers="spotkin.Leg.knee",
            call=lambda c, get=get, **k: get(c).knee(**k),
            slots=[angle_slot("q", 3)],
            baseline=knee_q,
            outputs=outs(("float", (3,))),
            nan_rule="check",
            check=knee_check,
        )

    # chains from joints
    def fl(c):
        return c.robot("go2").model.chain_data("FL_foot")

    placements_extra = {
        "one": (lambda c, v: v[:1], REJECT, ""),  # axes (3, 3) no longer fit
        "six": (lambda c, v: np.concatenate([v, v]), REJECT, ""),
        "zero": (lambda c, v: v[:0], REJECT, ""),
        "2d": (lambda c, v: v[0], REJECT, "shape"),
        "scaled": (lambda c, v: v * np.array([2.0, 2.0, 2.0, 1.0])[:, None], REJECT, "value"),
        "reflect": (lambda c, v: v * np.array([-1.0, 1.0, 1.0, 1.0])[:, None], REJECT, "value"),
        "last_row": (lambda c, v: v + np.diag([0.0, 0.0, 0.0, 1.0]), REJECT, "value"),
        "skewed": (lambda c, v: v + np.pad(1e-6 * np.ones((3, 3)), ((0, 1), (0, 1))), REJECT, "value"),
        "rotated": (
            lambda c, v: np.array(
                [rigid(euler_matrix([0.1 * k, 0.5, -0.3]), P[:3, 3]) for k, P in enumerate(v)]
            ),
            ACCEPT,
            "",
        ),
    }
    axes_extra = {
        "one": (lambda c, v: v[:1], REJECT, ""),
        "six": (lambda c, v: np.concatenate([v, v]), REJECT, ""),
        "zero": (lambda c, v: v[:0], REJECT, ""),
        "zero_axis": (lambda c, v: np.vstack([v[:1], np.zeros((1, 3)), v[2:]]), REJECT, "value"),
        "scaled": (lambda c, v: 3.0 * v, ACCEPT, ""),
        "negated": (lambda c, v: -v, ACCEPT, ""),
        "oblique": (lambda c, v: v + [0.3, -0.2, 0.1], ACCEPT, ""),
    }

    def joint_count(plan):
        counts = {"one": 1, "six": 6, "zero": 0}
        n_p, n_a = counts.get(plan["placements"], 3), counts.get(plan["axes"], 3)
        if n_p == n_a != 3:
            fixed = ("types", "limits", "joint_names")
            if all(plan[k] in ("omit", "none") for k in fixed):
                return EITHER if n_p == 0 else ACCEPT
            return REJECT
        return None

    register(
        name="Chain.from_joints",
        covers="spotkin.Chain.from_joints",
        call=lambda c, **k: sk.Chain.from_joints(**k),
        slots=[
            Array("placements", lambda c: fl(c).placements, extra=placements_extra),
            Array("axes", lambda c: fl(c).axes, extra=axes_extra),
            Array(
                "types",
                lambda c: np.zeros(3),
                optional=True,
                default="omit",
                extra={
                    "prismatic": (lambda c, v: np.array([0.0, 0.0, 1.0]), ACCEPT, ""),
                    "two": (lambda c, v: np.array([0.0, 2.0, 0.0]), REJECT, "value"),
                    "half": (lambda c, v: np.array([0.0, 0.5, 0.0]), REJECT, "value"),
                    "negative": (lambda c, v: np.array([-1.0, 0.0, 0.0]), REJECT, "value"),
                },
            ),
            Array("base", lambda c: np.eye(4), optional=True, default="omit", extra=RIGID_EXTRA),
            Array("tool", lambda c: fl(c).tool, optional=True, default="omit", extra=RIGID_EXTRA),
            Array(
                "limits",
                lambda c: fl(c).limits,
                inf_ok=True,
                optional=True,
                default="omit",
                extra={
                    "inverted": (lambda c, v: v[:, ::-1], REJECT, "value"),
                    "unbounded": (lambda c, v: [[-np.inf, np.inf]] * 3, ACCEPT, ""),
                },
            ),
            Custom(
                "joint_names",
                {
                    "none": lambda c, r, b: Arg(None),
                    "valid": lambda c, r, b: Arg(fl(c).joint_names),
                    "list": lambda c, r, b: Arg(list(fl(c).joint_names)),
                    "short": lambda c, r, b: Arg(fl(c).joint_names[:2], REJECT, "value"),
                    "long": lambda c, r, b: Arg((*fl(c).joint_names, "extra"), REJECT, "value"),
                    "empty": lambda c, r, b: Arg((), REJECT, "value"),
                    "ints": lambda c, r, b: Arg((1, 2, 3), EITHER),
                    "int": lambda c, r, b: Arg(5, REJECT),
                },
                default="omit",
            ),
        ],
        probe=from_joints_probe,
        overflow_ok=True,
        pair_rule=joint_count,
        combos=(
            ("six_joints", {"placements": "six", "axes": "six"}, ACCEPT),
            ("no_joints", {"placements": "zero", "axes": "zero"}, EITHER),
        ),
    )


# -- functions --


def _function_entries():
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
    max_threads = getattr(sk, "MAX_THREADS", None) or getattr(sk._runtime, "MAX_THREADS", 1024)

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


# -- Paul's equations --


def _workspace_entries():
    def obj_slot(kind: str) -> Custom:
        """The object a workspace function samples: legs, arms and chains it takes, others it refuses."""

        def arg(make, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(make(c), expect, why)

        table = {
            "valid": arg(lambda c: c.leg if kind != "dexterity" else c.arm),
            "str": arg(lambda c: "spot", REJECT, "type"),
            "none": arg(lambda c: None, REJECT, "type"),
            "spot": arg(lambda c: c.spot, REJECT, "type"),
        }
        if kind == "workspace":
            table["arm"] = arg(lambda c: c.arm)
            table["chain6"] = arg(lambda c: c.chain("spot_arm"))
            table["chain3"] = arg(lambda c: c.chain("mdh3"))
        elif kind == "volume":
            table["chain3"] = arg(lambda c: c.chain("mdh3"))
            table["arm"] = arg(lambda c: c.arm, REJECT, "value")
        else:
            table["chain6"] = arg(lambda c: c.chain("spot_arm"))
            table["leg"] = arg(lambda c: c.leg, REJECT, "value")
        return Custom("obj", table)

    def samples_probe(result, kw, c):
        n = int(kw.get("n", 100_000))
        if not isinstance(result, sk.WorkspaceSamples):
            return f"not WorkspaceSamples: {describe(result)}"
        q, points, branches = result
        if points.shape != (n, 3) or branches.shape != (n,) or q.shape[0] != n:
            return f"shapes {q.shape}, {points.shape}, {branches.shape} for n = {n}"
        if not finite(points) or not finite(q):
            return "non-finite samples"
        if n and not ((branches >= 1).mean() > 0.9 or (branches == -1).all()):
            return f"branch counts {np.bincount(branches + 1)} for reached samples"
        return None

    sample_skip = ("huge", "big")
    register(
        name="workspace",
        covers="spotkin.workspace",
        call=lambda c, **k: sk.workspace(**k),
        slots=[
            obj_slot("workspace"),
            Int("n", 200, 0, skip=sample_skip),
            Int("seed", 0, 0, optional=True, default="omit"),
        ],
        probe=samples_probe,
    )

    def volume_probe(result, kw, c):
        if not (isinstance(result, tuple) and len(result) == 2):
            return f"not (volume, error): {describe(result)}"
        volume, error = result
        if not (math.isfinite(volume) and math.isfinite(error)) and float(kw.get("pad", 0.05)) < 1e100:
            return f"non-finite volume {volume} or error {error}"
        if volume < 0 or error < 0:
            return f"negative volume {volume} or error {error}"
        return None

    register(
        name="workspace_volume",
        covers="spotkin.workspace_volume",
        call=lambda c, **k: sk.workspace_volume(**k),
        slots=[
            obj_slot("volume"),
            Int("n", 2000, 1, skip=sample_skip),
            Int("seed", 0, 0, optional=True, default="omit"),
            Real("pad", 0.05, "nonneg", default="omit"),
        ],
        probe=volume_probe,
    )

    def dexterity_probe(result, kw, c):
        if not isinstance(result, sk.Dexterity):
            return f"not a Dexterity: {describe(result)}"
        fraction = result.fraction
        if result.positions.shape != (len(fraction), 3) or not ((fraction >= 0) & (fraction <= 1)).all():
            return f"positions {result.positions.shape}, fractions out of [0, 1] or mismatched"
        return None

    register(
        name="dexterity",
        covers="spotkin.dexterity",
        call=lambda c, **k: sk.dexterity(**k),
        slots=[
            obj_slot("dexterity"),
            Real("spacing", 0.4, skip=("subnormal",)),
            Int("orientations", 4, 1, skip=sample_skip),
            Int("seed", 0, 0, optional=True, default="omit"),
            Int("samples", 500, 1, skip=sample_skip),
        ],
        probe=dexterity_probe,
    )

    def volume_of(c):
        return c._get("dexterity", lambda: sk.dexterity(c.arm, spacing=0.4, orientations=4, samples=500))

    register(
        name="Dexterity.volume",
        covers="spotkin.Dexterity.volume",
        call=lambda c, **k: volume_of(c).volume(**k),
        slots=[Real("at_least", 0.5, "finite", default="omit")],
        probe=lambda v, kw, c: None if isinstance(v, float) and v >= 0 else f"volume {describe(v)}",
    )


def _paul_entries():
    def residual_tol(*coefs):
        return 1e-9 * max(1.0, *(abs(float(v)) for v in coefs))

    def type2_base(c, rng, n):
        t = rng.uniform(-3, 3, n)
        X, Y = rng.normal(size=n), rng.normal(size=n)
        return {"X": X, "Y": Y, "Z": X * np.sin(t) + Y * np.cos(t) + rng.uniform(-0.1, 0.1, n)}

    def type2_check(x, out, kw, c):
        t, valid = out
        X, Y, Z = (float(x[k]) for k in "XYZ")
        for k in range(2):
            if valid[k]:
                if not (finite([t[k]]) and -math.pi - 1e-12 <= t[k] <= math.pi + 1e-12):
                    return f"valid root {t[k]}"
                if abs(X * math.sin(t[k]) + Y * math.cos(t[k]) - Z) > residual_tol(X, Y, Z):
                    return f"valid root {t[k]} does not solve {X} sin t + {Y} cos t = {Z}"
            elif not math.isnan(t[k]):
                return f"invalid root {t[k]} is not NaN"
        r = math.hypot(X, Y)
        if not valid.any() and r > abs(Z) * (1 + 1e-9) and r > 0:
            return f"no valid root, but |(X, Y)| = {r} > |Z| = {abs(Z)}"
        return None

    register(
        name="paul.type2",
        covers="spotkin.paul.type2",
        call=lambda c, **k: sk.paul.type2(**k),
        slots=[Batch(k, ()) for k in "XYZ"],
        baseline=type2_base,
        outputs=outs(("f64", (2,)), ("flag", (2,))),
        check=type2_check,
    )

    def type3_base(c, rng, n):
        t = rng.uniform(-3, 3, n)
        out = {}
        for row in "12":
            X, Y = rng.normal(size=n), rng.normal(size=n)
            out.update({f"X{row}": X, f"Y{row}": Y, f"Z{row}": X * np.sin(t) + Y * np.cos(t)})
        return out

    def type3_check(x, out, kw, c):
        t, valid = out
        v = {k: float(x[k]) for k in x}
        if valid:
            for row in "12":
                X, Y, Z = v[f"X{row}"], v[f"Y{row}"], v[f"Z{row}"]
                if not finite([t]) or abs(X * math.sin(t) + Y * math.cos(t) - Z) > 1e-6 * max(
                    1, abs(X), abs(Y), abs(Z)
                ):
                    return f"valid root {t} does not solve equation {row}"
        elif not math.isnan(t):
            return f"invalid root {t} is not NaN"
        return None

    register(
        name="paul.type3",
        covers="spotkin.paul.type3",
        call=lambda c, **k: sk.paul.type3(**k),
        slots=[Batch(k, ()) for k in ("X1", "Y1", "Z1", "X2", "Y2", "Z2")],
        baseline=type3_base,
        outputs=outs(("f64", ()), ("flag", ())),
        check=type3_check,
    )

    def type6_base(c, rng, n):
        ti, tj = rng.uniform(-3, 3, n), rng.uniform(-3, 3, n)
        W, X, Y = rng.uniform(0.5, 2, n), rng.normal(size=n), rng.normal(size=n)
        return {
            "W": W,
            "X": X,
            "Y": Y,
            "Z1": W * np.sin(tj) - X * np.cos(ti) - Y * np.sin(ti),
            "Z2": W * np.cos(tj) - X * np.sin(ti) + Y * np.cos(ti),
        }

    def type6_check(x, out, kw, c):
        ti, tj, valid = out
        W, X, Y, Z1, Z2 = (float(x[k]) for k in ("W", "X", "Y", "Z1", "Z2"))
        for k in range(2):
            if valid[k]:
                a, b = ti[k], tj[k]
                tol = 1e-7 * max(1, abs(W), abs(X), abs(Y), abs(Z1), abs(Z2))
                if (
                    not finite([a, b])
                    or abs(W * math.sin(b) - X * math.cos(a) - Y * math.sin(a) - Z1) > tol
                    or abs(W * math.cos(b) - X * math.sin(a) + Y * math.cos(a) - Z2) > tol
                ):
                    return f"valid pair ({a}, {b}) does not solve the equations"
            elif not (math.isnan(ti[k]) and math.isnan(tj[k])):
                return f"invalid pair ({ti[k]}, {tj[k]}) is not NaN"
        return None

    register(
        name="paul.type6",
        covers="spotkin.paul.type6",
        call=lambda c, **k: sk.paul.type6(**k),
        slots=[Batch(k, ()) for k in ("W", "X", "Y", "Z1", "Z2")],
        baseline=type6_base,
        outputs=outs(("f64", (2,)), ("f64", (2,)), ("flag", (2,))),
        check=type6_check,
    )


# -- trajectories --


def _trajectory_entries():
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


# -- joint positions by name (issue 19) --

NAME_ROBOTS = ("spot", "go2", "hexapod", "spot_urdf")


def _joint_aliases_of(robot) -> dict:
    """Every name a robot's joint answers to -> that joint (Spot: its SDK name), from the descriptions."""
    table = {joint.name: joint.name for joint in robot.model.joints}
    if isinstance(robot, sk.Spot):  # the URDF's actuated joints are the SDK's legs, arm, gripper, in order
        sdk_names = (*robot.joint_names, *robot.arm_joint_names, "arm0.f1x")
        table.update(zip(robot.urdf_joint_names, sdk_names))
        table.update({name: name for name in (*sdk_names, "arm0.hr0")})
        table["arm_hr0"] = "arm0.hr0"
    return table


def _by_name(names, positions, joints, aliases) -> np.ndarray:
    """The oracle of q_from_names: each joint's position looked up by name (NaN when not given)."""
    table = {aliases.get(str(name), str(name)): value for name, value in zip(names, positions)}
    return np.array([table.get(aliases.get(j, j), np.nan) for j in joints], dtype=np.float64)


def _joint_name_entries():
    def reversed_names(c, key):
        return list(reversed(c.robot(key).leg_joint_names))

    def others(c, key):
        """Two joints of the robot that are not in its whole-body q (skipped by q_from_names)."""
        robot = c.robot(key)
        if isinstance(robot, sk.Spot):
            return ["arm0.f1x", "arm0.hr0"]
        leg_joints = set(robot.leg_joint_names)
        return [j.name for j in robot.model.joints if j.name not in leg_joints][:2]

    def names_table(key, lenient=False):
        def arg(make, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(make(c), expect, why)

        def swap_first(value):
            return lambda c: [value(c), *reversed_names(c, key)[1:]]

        table = {
            "valid": arg(lambda c: reversed_names(c, key)),
            "tuple": arg(lambda c: tuple(reversed_names(c, key))),
            "array": arg(lambda c: np.array(reversed_names(c, key))),
            "np_str": arg(lambda c: [np.str_(n) for n in reversed_names(c, key)]),
            "str": arg(lambda c: reversed_names(c, key)[0], REJECT, "type"),
            "bytes": arg(lambda c: [n.encode() for n in reversed_names(c, key)], REJECT, "type"),
            "ints": arg(lambda c: list(range(len(reversed_names(c, key)))), REJECT, "type"),
            "none": arg(lambda c: None, REJECT, "type"),
            "nested": arg(lambda c: [reversed_names(c, key)], REJECT, "type"),
            "dict": arg(lambda c: dict.fromkeys(reversed_names(c, key), 0.0), REJECT, "type"),
            "set": arg(lambda c: set(reversed_names(c, key)), REJECT, "type"),
            "fewer": arg(lambda c: reversed_names(c, key)[1:], REJECT),
            "more": arg(lambda c: [*reversed_names(c, key), "nope"], REJECT),
            "empty": arg(lambda c: [], REJECT),
        }
        if key == "spot":  # the packaged URDF's names for the same joints
            table["aliases"] = arg(lambda c: list(reversed(c.robot(key).urdf_joint_names[:12])))
        strict = REJECT if not lenient else ACCEPT
        table["duplicate"] = arg(swap_first(lambda c: reversed_names(c, key)[1]), REJECT, "value")
        table["stranger"] = arg(swap_first(lambda c: "nope"), strict, "value")
        table["outside_q"] = arg(swap_first(lambda c: others(c, key)[0]), strict, "value")
        if lenient:
            table["two_strangers"] = arg(lambda c: ["nope", "lidar", *reversed_names(c, key)[2:]])
        return table

    def joints_table(key, widths_kept=False):
        def arg(make, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(make(c), expect, why)

        table = {
            "none": arg(lambda c: None),
            "reversed": arg(lambda c: reversed_names(c, key)),
            "unknown": arg(lambda c: ["nope"], REJECT, "value"),
            "duplicate": arg(lambda c: [c.robot(key).leg_joint_names[0]] * 2, REJECT, "value"),
            "str": arg(lambda c: c.robot(key).leg_joint_names[0], REJECT, "type"),
            "ints": arg(lambda c: [0, 1], REJECT, "type"),
        }
        if key == "spot":
            table["aliases"] = arg(lambda c: list(c.robot(key).urdf_joint_names[:12]))
        if not widths_kept:
            table["subset"] = arg(lambda c: list(c.robot(key).leg_joint_names[:3]))
        return table

    def q_pairs(lenient):
        def rule(plan):
            """The dependent slots: names whose count matches a positions of another width, and a
            missing joint that missing="nan" or a narrower ``joints`` forgives."""
            names, positions, joints = plan["names"], plan["positions"], plan["joints"]
            nan_ok = lenient or plan.get("missing") == "choice:nan"
            ignore_ok = lenient or plan.get("unknown") == "choice:ignore"
            narrow = joints == "subset"  # without the last leg joint, the one names drops
            widths = {"fewer": "trailing_minus", "more": "trailing_plus", "empty": "empty_flat"}
            if widths.get(names) == positions:
                return (
                    ACCEPT
                    if (
                        (names == "fewer" and (nan_ok or narrow))
                        or (names == "more" and ignore_ok and nan_ok)
                        or (names == "empty" and nan_ok)
                    )
                    else REJECT
                )
            if names == "outside_q" and not lenient and positions == "valid" and (nan_ok or narrow):
                return ACCEPT
            return None

        return rule

    def joints_of(c, key, kw):
        joints = kw.get("joints")
        return list(c.robot(key).leg_joint_names) if joints is None else [str(j) for j in joints]

    for key in NAME_ROBOTS:
        covers = "spotkin.Spot" if key == "spot" else "spotkin.Robot"
        light = key == "spot_urdf"
        n = 3 * ROBOT_LEGS[key]

        def baseline(c, rng, n, key=key):
            return {"positions": rng.uniform(-3.0, 3.0, (n, len(c.robot(key).leg_joint_names)))}

        def check(x, out, kw, c, key=key):
            robot = c.robot(key)
            want = _by_name(kw["names"], x["positions"], joints_of(c, key, kw), _joint_aliases_of(robot))
            if not close(out[0], want, x["positions"].dtype == np.float32):
                return f"q {describe(out[0])}, looked up by name {describe(want)}"
            return None

        def outputs(args, kw, n=n):
            joints = kw.get("joints")
            return [Out("float", (n if joints is None else len(joints),))]

        for lenient in (False, True):
            fixed = {"missing": "nan", "unknown": "ignore"} if lenient else {}
            slots = [
                Custom("names", names_table(key, lenient)),
                Batch("positions", (n,)),
                Custom("joints", joints_table(key), default="omit"),
            ]
            if not lenient:
                slots += [
                    Choice("missing", "raise", ("raise", "nan"), default="omit"),
                    Choice("unknown", "raise", ("raise", "ignore"), default="omit"),
                ]
            register(
                name=f"{covers[8:]}.q_from_names[{key}{', lenient' if lenient else ''}]",
                covers="" if lenient else f"{covers}.q_from_names",
                call=lambda c, key=key, fixed=fixed, **k: c.robot(key).q_from_names(**k, **fixed),
                slots=slots,
                baseline=baseline,
                outputs=outputs,
                check=check,
                nan_rule="check",
                light=light,
                pair_rule=q_pairs(lenient),
            )

        def names_probe(result, kw, c, key=key):
            robot = c.robot(key)
            joints = joints_of(c, key, kw)
            aliases = _joint_aliases_of(robot)
            q = kw["q"]
            raw = np.asarray(q)
            f32 = raw.dtype.kind == "f" and raw.dtype.itemsize == 4
            q64 = np.asarray(q, dtype=np.float64)
            names = [str(n) for n in (joints if kw.get("names") is None else kw["names"])]
            if not (isinstance(result, tuple) and len(result) == 2 and isinstance(result[1], np.ndarray)):
                return f"not (names, positions): {describe(result)}"
            got_names, positions = result
            if got_names != tuple(names) or not all(type(n) is str for n in got_names):
                return f"names {got_names}, expected {tuple(names)}"
            canonical = [aliases.get(j, j) for j in joints]
            want = q64[..., [canonical.index(aliases[n]) for n in names]]
            if positions.dtype != (np.float32 if f32 else np.float64):
                return f"positions dtype {positions.dtype} for q of dtype {raw.dtype}"
            if positions.shape != want.shape or not close(positions, want, f32):
                return f"positions {describe(positions)}, expected {describe(want)}"
            if isinstance(q, np.ndarray) and positions.size and np.shares_memory(positions, q):
                return "positions share memory with q"
            return None

        names_only = {
            "none": lambda c, r, b: Arg(None),
            "valid": lambda c, r, b, key=key: Arg(reversed_names(c, key)),
            "subset": lambda c, r, b, key=key: Arg(reversed_names(c, key)[::4]),
            "empty": lambda c, r, b: Arg([]),
            "stranger": lambda c, r, b: Arg(["nope"], REJECT, "value"),
            "outside_q": lambda c, r, b, key=key: Arg(others(c, key)[:1], REJECT, "value"),
            "duplicate": lambda c, r, b, key=key: Arg(reversed_names(c, key)[:1] * 2, REJECT, "value"),
            "str": lambda c, r, b, key=key: Arg(reversed_names(c, key)[0], REJECT, "type"),
            "ints": lambda c, r, b: Arg([0], REJECT, "type"),
        }
        if key == "spot":
            names_only["aliases"] = lambda c, r, b, key=key: Arg(list(c.robot(key).urdf_joint_names[:12]))
        register(
            name=f"{covers[8:]}.names_from_q[{key}]",
            covers=f"{covers}.names_from_q",
            call=lambda c, key=key, **k: c.robot(key).names_from_q(**k),
            slots=[
                Batch("q", (n,)),
                Custom("names", names_only, default="omit"),
                Custom("joints", joints_table(key, widths_kept=True), default="omit"),
            ],
            baseline=lambda c, rng, m, n=n: {"q": rng.uniform(-3.0, 3.0, (m, n))},
            probe=names_probe,
            light=light,
            pair_rule=lambda plan: EITHER if (plan["q"], plan["names"]) == ("huge_batch", "empty") else None,
        )


# -- pickling and copying of every object --


def _roundtrip_entries():
    q12 = np.tile([0.0, 1.04, -1.8], 4)
    objects = {
        "Spot": (lambda c: c.spot, lambda o: o.body_fk([0.0, 0.0, 0.5, 0.1, 0.0, 0.0], q12)),
        "Leg": (lambda c: c.leg, lambda o: o.fk([0.1, 1.0, -1.5])),
        "SpotArm": (lambda c: c.arm, lambda o: o.fk(np.full(6, 0.3))),
        **{
            f"Chain[{key}]": (lambda c, key=key: c.chain(key), lambda o: o.fk(np.full(o.dof, 0.3)))
            for key in (*CHAIN_ROWS, *URDF_CHAINS)
        },
        **{
            f"Robot[{key}]": (
                lambda c, key=key: c.robot(key),
                lambda o: o.body_fk([0.0, 0.0, 0.3, 0.1, -0.1, 0.2], np.linspace(-0.5, 0.5, 3 * o.n_legs)),
            )
            for key in ("go2", "hexapod", "spot_urdf")
        },
        "Leg[geometry]": (lambda c: c.robot("hexapod").leg("R1"), lambda o: o.fk([0.1, 1.0, 1.5])),
        **{
            f"PointToPoint[{p}]": (lambda c, p=p: c.p2p(p), lambda o: o.sample(np.linspace(-1, 5, 7))[0])
            for p in PROFILES
        },
        **{
            f"CartesianPath[{k}]": (lambda c, k=k: c.path(k), lambda o: o.sample(np.linspace(-1, 5, 7)))
            for k in ("linear", "via")
        },
    }
    for name, (get, signature) in objects.items():

        def call(c, get=get):
            obj = get(c)
            return obj, pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj), copy.copy(obj)

        def probe(result, kw, c, signature=signature):
            obj, *copies = result
            want = signature(obj)
            for how, other in zip(("pickle", "deepcopy", "copy"), copies):
                if type(other) is not type(obj) or not close(signature(other), want, False):
                    return f"a {how} copy differs from the original"
            return None

        register(name=f"pickle[{name}]", covers="", call=call, probe=probe)


# -- dynamics: the chains' methods and the whole robot's statics, against the pure-Python reference --


G0 = np.array([0.0, 0.0, -9.81])


def laid_out(A, layout):
    """One sample's full symmetric matrix in a mass-matrix layout (lower: upper triangle zero;
    packed: the lower triangle row by row)."""
    if layout == "lower":
        return np.tril(A)
    if layout == "packed":
        return A[np.tril_indices(A.shape[-1])]
    return A


def _dynamics_entries():
    from spotkin import inertia
    from spotkin.reference import dynamics as rd

    trees = {}

    def tree(c, key, chain):
        if key not in trees:
            trees[key] = inertia.tree_of(chain)
        return trees[key]

    def against(reference, tol_base=1e-8):
        """A check of one valid sample: the output within tol (relative to its size) of the reference's."""

        def check(x, out, kw, c, reference=reference):
            want = np.asarray(reference(c, {k: np.asarray(v, dtype=np.float64) for k, v in x.items()}, kw))
            if not np.isfinite(want).all():
                return None  # the reference overflows (1e300 rates): nothing to compare
            (got,) = out
            biggest = max(float(np.abs(np.asarray(v, np.float64)).max()) for v in x.values())
            dtype = np.asarray(got).dtype if np.asarray(got).dtype.kind == "f" else np.dtype(np.float64)
            if not finite(got) and biggest > 1e-4 * math.sqrt(float(np.finfo(dtype).max)):
                # squares of rates beyond the square root of the dtype's range overflow to Inf (1e150 in
                # float64, 2e15 in float32): never a plausible finite number
                return None
            tol = tol_for(*x.values(), base=tol_base, f32=2e-3) * max(1.0, float(np.abs(want).max()))
            if not finite(got) or np.abs(np.asarray(got, dtype=np.float64) - want).max() > tol:
                return f"got {describe(got)}, the reference gives {describe(want)}"
            return None

        return check

    for key in URDF_CHAINS:
        dof = URDF_CHAINS[key][2]

        def get(c, key=key):
            return c.chain(key)

        def base(c, rng, n, get=get, dof=dof):
            chain = get(c)
            return {
                "q": in_limits(np.stack([chain.lower, chain.upper], axis=1), rng, n, margin=0.1),
                "qd": rng.normal(0.0, 1.0, (n, dof)),
                "qdd": rng.normal(0.0, 1.0, (n, dof)),
                "tau": rng.normal(0.0, 5.0, (n, dof)),
                "gravity": np.tile([0.0, 0.0, -9.81], (n, 1)) + rng.normal(0.0, 0.5, (n, 3)),
                "forces": rng.normal(0.0, 10.0, (n, 6)),
            }

        def t(c, get=get, key=key):
            return tree(c, key, get(c))

        q_slot, qd, qdd = angle_slot("q", dof), Batch("qd", (dof,)), Batch("qdd", (dof,))
        tau_slot, gravity = Batch("tau", (dof,)), Batch("gravity", (3,), default="omit")

        def g(x):
            return x.get("gravity", G0)

        methods = {
            "inverse_dynamics": (
                [q_slot, qd, qdd, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.rnea(t(c), x["q"], x["qd"], x["qdd"], g(x)),
            ),
            "mass_matrix": (
                [q_slot, Choice("layout", "full", ("full", "lower", "packed"), default="omit")],
                None,  # (dof, dof), or (dof (dof + 1) / 2,) packed
                lambda c, x, kw, t=t: laid_out(rd.crba(t(c), x["q"]), kw.get("layout", "full")),
            ),
            "gravity": (
                [q_slot, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.gravity_torques(t(c), x["q"], g(x)),
            ),
            "nonlinear_effects": (
                [q_slot, qd, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.nonlinear_effects(t(c), x["q"], x["qd"], g(x)),
            ),
            "coriolis_matrix": (
                [q_slot, qd],
                (dof, dof),
                lambda c, x, kw, t=t: rd.coriolis_matrix(t(c), x["q"], x["qd"]),
            ),
            "forward_dynamics": (
                [q_slot, qd, tau_slot, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.aba(t(c), x["q"], x["qd"], x["tau"], g(x)),
            ),
            "center_of_mass": ([q_slot], (3,), lambda c, x, kw, t=t: rd.center_of_mass(t(c), x["q"])),
            "center_of_mass_jacobian": (
                [q_slot],
                (3, dof),
                lambda c, x, kw, t=t: rd.center_of_mass_jacobian(t(c), x["q"]),
            ),
            "kinetic_energy": (
                [q_slot, qd],
                (),
                lambda c, x, kw, t=t: rd.kinetic_energy(t(c), x["q"], x["qd"]),
            ),
            "potential_energy": (
                [q_slot, gravity],
                (),
                lambda c, x, kw, t=t: rd.potential_energy(t(c), x["q"], g(x)),
            ),
            "joint_torques_from_forces": (
                [q_slot, Batch("forces", (6,))],
                (dof,),
                lambda c, x, kw, get=get: get(c).jacobian(x["q"]).T @ x["forces"],
            ),
        }

        def symmetric_out(args, kw, dof=dof):
            packed = kw.get("layout") == "packed"
            return [Out("float", (dof * (dof + 1) // 2,) if packed else (dof, dof))]

        def out_of(trailing, dof=dof):
            if trailing is not None:
                return OutSlot(("float", trailing), drivers=["q", "qd", "qdd", "tau"])

            def leaves(args, dof=dof):  # the mass matrix: its layout decides the shape
                layout = args["layout"].value
                packed = layout == "packed"
                return [("float", (dof * (dof + 1) // 2,) if packed else (dof, dof))]

            return OutSlot(leaves, drivers=["q"])

        with_out = (
            "inverse_dynamics",
            "mass_matrix",
            "gravity",
            "nonlinear_effects",
            "coriolis_matrix",
            "forward_dynamics",
        )
        for method, (slots, trailing, reference) in methods.items():
            if method in with_out:
                slots = [*slots, out_of(trailing)]
            register(
                name=f"Chain.{method}[{key}]",
                covers=f"spotkin.Chain.{method}",
                call=lambda c, get=get, method=method, **k: getattr(get(c), method)(**k),
                slots=slots,
                baseline=base,
                outputs=outs(("float", trailing)) if trailing is not None else symmetric_out,
                check=against(reference),
                overflow_ok=True,
            )

    # the whole robot: Spot (sk.Spot) and Go2 (sk.Robot)
    for key, cls in (("spot", "Spot"), ("go2", "Robot")):
        legs = ROBOT_LEGS[key]

        def robot_of(c, key=key):
            return c.robot(key)

        def body_base(c, rng, n, key=key, legs=legs):
            height = STANCE_HEIGHT[key]
            pose = body_poses(rng, n, height)
            q = c.nominal(key) + rng.uniform(-0.1, 0.1, (n, 3 * legs))
            stance = rng.uniform(size=(n, legs)) < 0.8
            return {"body_pose": pose, "q": q, "stance": stance}

        def whole_tree(c, key=key):
            if ("robot", key) not in trees:
                trees[("robot", key)] = inertia.tree_of(c.robot(key))
            return trees[("robot", key)]

        def full_q(c, q, key=key):
            return np.concatenate([q, np.zeros(len(c.robot(key).arm_joint_names))])

        euler = np.array([False] * 3 + [True] * 3)
        pose_slot = Batch("body_pose", (6,), pose="body", angles=euler)
        q_slot = angle_slot("q", 3 * legs)
        names = {rd.STANCE_OK: 0, rd.STANCE_PULLING: 1, rd.STANCE_OUTSIDE: 2, rd.STANCE_UNBALANCED: 4}

        def standing_check(x, out, kw, c, whole_tree=whole_tree, full_q=full_q, names=names):
            tau, forces, status, margin = out
            ok = pose_validity(x["body_pose"])
            stance = np.asarray(x.get("stance", np.ones(len(tau) // 3)), dtype=np.float64)
            if ok is None:
                return None
            if not ok or not finite(x["q"]) or not np.isin(stance, (0.0, 1.0)).all():
                if int(status) != INVALID or not all_nan(tau) or not all_nan(forces) or not all_nan(margin):
                    return f"invalid input but status {status}, tau {describe(tau)}"
                return None
            T = pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))
            T[:3, 3] = 0.0  # the statics do not depend on where the body is
            q = np.asarray(x["q"], dtype=np.float64)
            gravity = np.asarray(kw.get("gravity", G0), dtype=np.float64)
            want = rd.standing_torques(whole_tree(c), T, full_q(c, q), np.flatnonzero(stance), gravity)
            if int(status) != names[want.status]:
                return f"status {status}, the reference's {want.status}"
            tol = tol_for(*x.values(), base=1e-7, f32=5e-2)
            if np.isfinite(want.margin) and abs(float(margin) - want.margin) > tol:
                return f"margin {margin}, the reference's {want.margin}"
            if want.status == rd.STANCE_UNBALANCED:
                return None if all_nan(tau) else f"unbalanced but tau {describe(tau)}"
            scale = max(1.0, float(np.abs(want.tau).max()))
            if (
                not finite(tau)
                or np.abs(np.asarray(tau, np.float64) - want.tau[: tau.shape[-1]]).max() > tol * scale
            ):
                return f"tau {describe(tau)}, the reference's {describe(want.tau)}"
            return None

        stance_slot = Batch(
            "stance",
            (legs,),
            valid=lambda s: bool(np.isin(np.asarray(s, np.float64), (0.0, 1.0)).all()),
            optional=True,
        )
        register(
            name=f"{cls}.standing_torques[{key}]",
            covers=f"spotkin.{cls}.standing_torques",
            call=lambda c, robot_of=robot_of, **k: robot_of(c).standing_torques(**k),
            slots=[
                pose_slot,
                q_slot,
                stance_slot,
                Array("gravity", lambda c: np.array([0.0, 0.0, -9.81]), default="omit"),
                seq_slot(),
                OutSlot(
                    ("float", (3 * legs,)),
                    ("float", (legs, 3)),
                    ("stance", ()),
                    ("float", ()),
                    drivers=["body_pose", "q"],
                ),
            ],
            baseline=body_base,
            outputs=outs(("float", (3 * legs,)), ("float", (legs, 3)), ("stance", ()), ("float", ())),
            nan_rule="check",
            check=standing_check,
            overflow_ok=True,
        )

        def com_check(x, out, kw, c, whole_tree=whole_tree, full_q=full_q):
            (com,) = out
            T = pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))
            want = rd.center_of_mass(whole_tree(c), full_q(c, np.asarray(x["q"], np.float64)), T)
            tol = tol_for(*x.values(), base=1e-9, f32=1e-3)
            if not np.isfinite(want).all():
                return None  # the reference overflows at a body 1e308 m away
            if not finite(com) or np.abs(np.asarray(com, np.float64) - want).max() > tol * max(
                1.0, np.abs(want).max()
            ):
                return f"centre of mass {describe(com)}, the reference's {describe(want)}"
            return None

        def floating_q_check(x, out, kw, c):
            (qf,) = out
            T = pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))
            x_, y_, z_, w_ = (float(v) for v in qf[3:7])
            R = np.array(
                [
                    [1 - 2 * (y_ * y_ + z_ * z_), 2 * (x_ * y_ - z_ * w_), 2 * (x_ * z_ + y_ * w_)],
                    [2 * (x_ * y_ + z_ * w_), 1 - 2 * (x_ * x_ + z_ * z_), 2 * (y_ * z_ - x_ * w_)],
                    [2 * (x_ * z_ - y_ * w_), 2 * (y_ * z_ + x_ * w_), 1 - 2 * (x_ * x_ + y_ * y_)],
                ]
            )
            # a rotation accepted within 1e-6 of orthonormal is read as its nearby rotation
            if (
                not finite(qf)
                or np.abs(R - T[:3, :3]).max() > 1e-5
                or np.abs(qf[:3] - T[:3, 3]).max() > 1e-12
            ):
                return f"the pose part {describe(qf[:7])} is not the body pose"
            return None

        n_arm = 6 if key == "spot" else 0
        register(
            name=f"{cls}.center_of_mass[{key}]",
            covers=f"spotkin.{cls}.center_of_mass",
            call=lambda c, robot_of=robot_of, **k: robot_of(c).center_of_mass(**k),
            slots=[pose_slot, q_slot, seq_slot(), OutSlot(("float", (3,)), drivers=["body_pose", "q"])],
            baseline=body_base,
            outputs=outs(("float", (3,))),
            check=com_check,
            light=key == "go2",
        )
        register(
            name=f"{cls}.floating_q[{key}]",
            covers=f"spotkin.{cls}.floating_q",
            call=lambda c, robot_of=robot_of, **k: robot_of(c).floating_q(**k),
            slots=[pose_slot, Batch("q", (3 * legs,)), seq_slot()],  # copied: no angle is read
            baseline=body_base,
            outputs=outs(("f64", (7 + 3 * legs + n_arm,))),
            check=floating_q_check,
            mixed="f64",
            light=key == "go2",
        )


_leg_entries()
_chain_entries(_arm_entries())
_spot_entries()
_robot_entries()
_dynamics_entries()
_function_entries()
_paul_entries()
_trajectory_entries()
_workspace_entries()
_roundtrip_entries()
_joint_name_entries()
fuzz_sdk.register_entries(sys.modules[__name__])  # spotkin.sdk, when its optional SDK is installed
fuzz_dask.register_entries(sys.modules[__name__])  # spotkin.dask, when Dask is installed
fuzz_plot.register_entries(sys.modules[__name__])  # spotkin.plot, when matplotlib is installed
fuzz_limits.register_entries(sys.modules[__name__])  # with_limits of robots and chains
fuzz_isa.register_entries(sys.modules[__name__])  # instruction-set levels
fuzz_urdf.register_entries(sys.modules[__name__])  # Chain.from_urdf (arms, mimic joints)
BY_NAME = {entry.name: entry for entry in REGISTRY}
assert len(BY_NAME) == len(REGISTRY), "registry names must be unique"


# ---- canaries: broken on purpose, to show that the harness catches each kind of failure ---------------


def _canary_fk(q):
    """Wrong on purpose: complex input accepted (imaginary part dropped), float32 computed in float64,
    and a NaN sample of a batch takes its neighbour's result."""
    q = np.asarray(q)
    if q.dtype.kind not in "biufc":
        raise TypeError(f"q must be a real numeric array, got dtype {q.dtype}")
    q = np.real(q).astype(np.float64)
    if q.shape[-1:] != (3,):
        raise ValueError(f"q must have shape (..., 3), got {q.shape}")
    out = np.cos(q)
    bad = np.isnan(out).any(-1)
    if out.ndim == 2 and bad.any() and not bad.all():
        out[bad] = out[np.argmin(bad)]
    return out


CANARIES = {
    "canary:abort": (Entry(name="canary:abort", covers="", call=lambda c: os.abort()), "crash"),
    "canary:hang": (Entry(name="canary:hang", covers="", call=lambda c: time.sleep(3600)), "hang (timeout)"),
    "canary:pybind": (
        Entry(
            name="canary:pybind",
            covers="",
            call=lambda c: _raise(TypeError("f(): incompatible function arguments")),
        ),
        "pybind-signature-error",
    ),
    "canary:key": (Entry(name="canary:key", covers="", call=lambda c: {}["x"]), "raised KeyError"),
    "canary:warning": (
        Entry(name="canary:warning", covers="", call=lambda c: np.float64(1.0) / np.float64(0.0)),
        "warning RuntimeWarning",
    ),
}
CANARY_FK = Entry(
    name="canary:fk",
    covers="",
    call=lambda c, **k: _canary_fk(**k),
    slots=[angle_slot("q", 3)],
    baseline=lambda c, rng, n: {"q": rng.uniform(-1, 1, (n, 3))},
    outputs=outs(("float", (3,))),
)


def _raise(error):
    raise error


BY_NAME.update({name: entry for name, (entry, _) in CANARIES.items()})
BY_NAME[CANARY_FK.name] = CANARY_FK


# ---- the public API and the registry's coverage -------------------------------------------------------

# Callables that take no input worth fuzzing, with the reason. Anything else public must be registered.
EXCLUDED = {
    "spotkin.Status": "IntEnum of result codes: int methods only, no spotkin code",
    "spotkin.StanceStatus": "IntEnum of result codes: int methods only, no spotkin code",
}

# Optional modules (each needs an extra's dependency, which requirements-test.txt installs): their
# public callables must be registered too, whenever the module imports.
OPTIONAL_MODULES = ("spotkin.sdk", "spotkin.dask", "spotkin.plot")


def _optional_modules() -> list:
    """(prefix, module) of each optional module that imports here."""
    import importlib

    found = []
    for name in OPTIONAL_MODULES:
        try:
            found.append((name, importlib.import_module(name)))
        except ImportError:  # the extra is not installed: nothing of it is public here
            continue
    return found


def _is_record(cls) -> bool:
    """A NamedTuple result record (built by spotkin, only tuple methods)."""
    return isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")


def public_callables() -> dict[str, Callable]:
    """Every public function, class (its constructor) and method reachable from ``spotkin.__all__``,
    ``spotkin.paul.__all__``, ``spotkin.trajectory.__all__`` and the ``__all__`` of each optional module
    that imports (:data:`OPTIONAL_MODULES`); NamedTuple records keep only methods that tuples do not
    have."""
    found = {}
    core = [("spotkin", sk), ("spotkin.paul", sk.paul), ("spotkin.trajectory", sk.trajectory)]
    for prefix, module in core + _optional_modules():
        for name in module.__all__:
            obj = getattr(module, name)
            qual = f"{prefix}.{name}"
            if inspect.ismodule(obj) or not callable(obj):
                continue
            if not inspect.isclass(obj):
                found[qual] = obj
                continue
            record = _is_record(obj)
            if not record:
                found[qual] = obj
            for attr in dir(obj):
                if attr.startswith("_"):
                    continue
                raw = inspect.getattr_static(obj, attr)
                if isinstance(raw, property) or not callable(getattr(obj, attr)):
                    continue
                if record and hasattr(tuple, attr):
                    continue
                found[f"{qual}.{attr}"] = getattr(obj, attr)
    return found


def coverage_problems() -> list[str]:
    """Public callables missing from the registry, stale registry entries, and registry slots that do
    not match the signature's parameters."""
    public = public_callables()
    covered = {e.covers for e in REGISTRY if e.covers}
    problems = []
    for qual in sorted(public):
        if any(qual == q or qual.startswith(q + ".") for q in EXCLUDED):
            continue
        if qual not in covered:
            problems.append(f"{qual} is public but not in the fuzz registry (tests/fuzz/)")
    for qual in sorted(covered - set(public)):
        problems.append(f"the registry covers {qual}, which is not public (any more)")
    for entry in REGISTRY:
        if entry.covers not in public:
            continue
        params = [
            p
            for p in inspect.signature(public[entry.covers]).parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and p.name not in ("self", "cls")
        ]
        names, slots = [p.name for p in params], [s.name for s in entry.slots]
        if sorted(names) != sorted(slots):
            problems.append(f"{entry.name}: slots {slots} do not match the parameters {names}")
    return problems


# ---- cases --------------------------------------------------------------------------------------------


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


# ---- judging one case (in the worker) -----------------------------------------------------------------


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


# ---- worker processes ---------------------------------------------------------------------------------

ADDRESS_SPACE = 6 << 30  # bytes: allocations beyond it fail (MemoryError), as do excess thread stacks


def worker_main() -> None:
    """Reads cases (JSON lines) on stdin, writes verdicts on the original stdout; everything the
    library prints goes to stderr."""
    import resource

    proto = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
    ctx = Context()
    proto.write(json.dumps({"ready": True}) + "\n")
    for line in sys.stdin:
        case = json.loads(line)
        sys.stderr.write(f"case {label(case)}\n")
        proto.write(json.dumps(run_case(case, ctx)) + "\n")


class _Worker:
    def __init__(self):
        env = dict(
            os.environ,
            SPOTKIN_NUM_THREADS="1",
            OPENBLAS_NUM_THREADS="1",
            OMP_NUM_THREADS="1",
            MKL_NUM_THREADS="1",
            PYTHONFAULTHANDLER="1",
        )
        env["PYTHONPATH"] = os.pathsep.join(p for p in (HERE, env.get("PYTHONPATH")) if p)
        self.stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(
            [sys.executable, "-c", "from fuzz import registry; registry.worker_main()"],
            cwd=HERE,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            text=True,
            bufsize=1,
        )
        self.case = None
        self.deadline = 0.0

    def tail(self, size=1500) -> str:
        self.stderr.seek(0, os.SEEK_END)
        end = self.stderr.tell()
        self.stderr.seek(max(0, end - size))
        text = self.stderr.read().decode(errors="replace")
        return "\n".join(line for line in text.splitlines() if not line.startswith("case "))[-size:]

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for stream in (self.proc.stdin, self.proc.stdout):
            try:
                stream.close()
            except OSError:  # a broken pipe to a dead worker
                pass
        self.stderr.close()


class Pool:
    """Long-lived worker subprocesses; one dying (crash, abort) or stuck (timeout) is a failure of its
    case and is replaced."""

    def __init__(self, size: int = 2, timeout: float = 60.0):
        self.size, self.timeout = size, timeout
        self.workers: list[_Worker] = []
        self.restarts = 0

    def _spawn(self) -> _Worker:
        worker = _Worker()
        selector = selectors.DefaultSelector()
        selector.register(worker.proc.stdout, selectors.EVENT_READ)
        ready = selector.select(timeout=300)
        selector.close()
        line = worker.proc.stdout.readline() if ready else ""
        if not line.startswith('{"ready"'):
            tail = worker.tail()
            worker.kill()
            raise RuntimeError(f"a fuzz worker failed to start: {line!r}\n{tail}")
        return worker

    def run(self, cases: list[dict]) -> list[dict]:
        results: list[dict | None] = [None] * len(cases)
        pending = list(range(len(cases)))[::-1]
        while len(self.workers) < self.size:
            self.workers.append(self._spawn())
        busy: dict[int, _Worker] = {}
        selector = selectors.DefaultSelector()
        try:
            while pending or busy:
                for worker in self.workers:
                    if worker.case is None and pending:
                        index = pending.pop()
                        worker.case, worker.deadline = index, time.monotonic() + self.timeout
                        worker.proc.stdin.write(json.dumps(cases[index]) + "\n")
                        worker.proc.stdin.flush()
                        selector.register(worker.proc.stdout, selectors.EVENT_READ, worker)
                        busy[index] = worker
                wait = max(0.0, min(w.deadline for w in busy.values()) - time.monotonic())
                events = selector.select(timeout=wait)
                done = [key.data for key, _ in events]
                for worker in list(busy.values()):
                    if worker not in done and time.monotonic() > worker.deadline:
                        done.append(worker)
                for worker in done:
                    index = worker.case
                    selector.unregister(worker.proc.stdout)
                    del busy[index]
                    worker.case = None
                    line = worker.proc.stdout.readline() if worker in [k.data for k, _ in events] else None
                    if line:
                        results[index] = json.loads(line)
                        continue
                    if line is None:
                        results[index] = {
                            "ok": False,
                            "kind": "hang (timeout)",
                            "detail": f"no answer within {self.timeout:.0f} s",
                        }
                    else:
                        worker.proc.wait()
                        code = worker.proc.returncode
                        how = f"signal {-code}" if code < 0 else f"exit code {code}"
                        results[index] = {"ok": False, "kind": "crash", "detail": f"{how}: {worker.tail()}"}
                    worker.kill()
                    self.workers[self.workers.index(worker)] = self._spawn()
                    self.restarts += 1
        finally:
            selector.close()
        return results  # type: ignore[return-value]

    def close(self):
        for worker in self.workers:
            try:
                worker.proc.stdin.close()  # the worker's loop ends
            except OSError:
                pass
            try:
                worker.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
            worker.kill()
        self.workers = []
