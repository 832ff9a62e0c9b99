"""What a call returns: :class:`Out` (one documented leaf of a result) and :func:`outs`, the ``out=``
slot (:class:`OutSlot`), and the helpers that compare and print results (:func:`flatten`,
:func:`close`, :func:`describe`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .slots import ACCEPT, OMIT, REJECT, Arg, Slot


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


def outs(*leaves):
    """A fixed output spec: Out(kind, trailing) leaves."""
    spec = [Out(kind, tuple(trailing)) for kind, trailing in leaves]
    return lambda args, kw: spec


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
