"""Registry entries of ``spotkin.paul`` (Paul's equations of types 2, 3 and 6)."""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import register
from .outputs import outs
from .slots import finite


def paul_entries():
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
