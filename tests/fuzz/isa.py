"""Fuzz registry entries for the instruction-set levels: spotkin.set_isa, spotkin.isa,
spotkin.get_isa and spotkin.available_isas (registered by tests/fuzz/registry.py at import)."""

from __future__ import annotations

import numpy as np

import spotkin as sk

from .entry import register
from .slots import Choice


def register_entries() -> None:
    levels = sk.available_isas()
    best = levels[-1]

    def same_answers() -> np.ndarray:
        leg = sk.Spot().leg("fl")
        return leg.ik(leg.fk(np.full((40, 3), 0.3)))[0]

    expected = same_answers()

    def level_probe(result, kw, c):
        if result is not None:
            return f"set_isa returned {result!r}"
        wanted = best if kw["level"] == "best" else str(kw["level"])
        if sk.get_isa() != wanted:
            return f"get_isa() = {sk.get_isa()!r} after set_isa({kw['level']!r})"
        got = same_answers()
        if not np.allclose(got, expected, rtol=0, atol=1e-9):
            return f"leg IK at {wanted} differs from the best level's by {np.abs(got - expected).max():.3g}"
        return None

    def restore(c):
        sk.set_isa("best")

    register(
        name="set_isa",
        covers="spotkin.set_isa",
        call=lambda c, **k: sk.set_isa(**k),
        slots=[Choice("level", levels[0], (*levels, "best"))],
        probe=level_probe,
        after=restore,
    )

    def inside(level):
        with sk.isa(level):
            return sk.get_isa(), same_answers()

    def block_probe(result, kw, c):
        level, got = result
        wanted = best if kw["level"] == "best" else str(kw["level"])
        if level != wanted or sk.get_isa() != best:
            return f"isa({kw['level']!r}): {level!r} inside, {sk.get_isa()!r} after"
        if not np.allclose(got, expected, rtol=0, atol=1e-9):
            return f"leg IK inside isa({wanted!r}) differs from the best level's"
        return None

    register(
        name="isa",
        covers="spotkin.isa",
        call=lambda c, **k: inside(**k),
        slots=[Choice("level", levels[0], (*levels, "best"))],
        probe=block_probe,
        after=restore,
    )
    register(
        name="get_isa",
        covers="spotkin.get_isa",
        call=lambda c: sk.get_isa(),
        probe=lambda r, kw, c: None if r in levels else f"get_isa() = {r!r}, not among {levels}",
    )
    register(
        name="available_isas",
        covers="spotkin.available_isas",
        call=lambda c: sk.available_isas(),
        probe=lambda r, kw, c: None if isinstance(r, tuple) and r == levels else f"available_isas() = {r!r}",
    )
