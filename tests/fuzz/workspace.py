"""Registry entries of the workspace functions and ``Dexterity``."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .entry import register
from .outputs import describe
from .slots import ACCEPT, REJECT, Arg, Custom, Int, Real, finite


def workspace_entries():
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
