"""Registry entries of ``Spot``: its whole-body methods and its own."""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np

import spotkin as sk

from .body import SPOT_BODY, body_entries
from .entry import register
from .outputs import close, describe
from .slots import ACCEPT, REJECT, Arg, Choice, Custom, Real, finite


def spot_entries():
    body_entries(SPOT_BODY)

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
