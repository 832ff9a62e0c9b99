"""Registry entries of ``SpotArm``."""

from __future__ import annotations

import pickle

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import angle_slot, register
from .objects import euler_matrix, in_limits, pose_matrix, rigid
from .oracles import finite_check, nearest_check, rigid_error, solution_check
from .outputs import OutSlot, close, describe, outs
from .slots import ACCEPT, OK, REJECT, Array, Real, finite

RIGID_EXTRA = {  # (4, 4) tools and bases
    "scaled": (lambda c, v: 2 * np.eye(4), REJECT, "value"),
    "last_row": (lambda c, v: np.diag([1.0, 1.0, 1.0, 2.0]), REJECT, "value"),
    "zeros": (lambda c, v: np.zeros((4, 4)), REJECT, "value"),
    "reflect": (lambda c, v: np.diag([-1.0, 1.0, 1.0, 1.0]), REJECT, "value"),
    "rigid": (lambda c, v: rigid(euler_matrix([0.3, 0.2, 0.1]), [0.05, 0, 0.02]), ACCEPT, ""),
}


def arm_entries():
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
