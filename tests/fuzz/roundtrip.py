"""Registry entries for the pickling and copying of every object."""

from __future__ import annotations

import copy
import pickle

import numpy as np

from .entry import register
from .objects import CHAIN_ROWS, PROFILES, URDF_CHAINS
from .outputs import close


def roundtrip_entries():
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
