"""Canaries: entries broken on purpose, to show that the harness catches each kind of failure."""

from __future__ import annotations

import os
import time

import numpy as np

from .entry import Entry, angle_slot
from .outputs import outs


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
