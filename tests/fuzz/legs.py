"""Registry entries of ``Leg``: Spot's legs, and a leg of another geometry."""

from __future__ import annotations

import pickle

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import angle_slot, register
from .objects import LEG_LIMITS, in_limits
from .oracles import finite_check, nearest_check, solution_check, tol_for
from .outputs import OutSlot, close, describe, outs
from .slots import ACCEPT, EITHER, INVALID, OK, REJECT, Arg, Array, Choice, Custom, Flag, Real, finite


def leg_entries():
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
