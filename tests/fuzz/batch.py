""":class:`Batch`: an argument ``(..., *trailing)`` with batch semantics, and its hostile variants
(layouts, dtypes, values, shapes, objects, malformed poses)."""

from __future__ import annotations

import math

import numpy as np

from .slots import (
    ACCEPT,
    BAD_DTYPES,
    DTYPES,
    EITHER,
    HUGE_ANGLE,
    LAYOUT,
    MEMORY,
    OBJECTS,
    OMIT,
    POSE_BAD,
    REJECT,
    SHAPES,
    VALUES,
    Arg,
    Slot,
    finite,
    pose_validity,
    reduce_angle,
)


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
