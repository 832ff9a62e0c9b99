"""Registry entries of ``SpotArm``."""

from __future__ import annotations

import pickle

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import angle_slot, register
from .objects import euler_matrix, in_limits, pose_matrix, rigid
from .oracles import finite_check, frame_slot, nearest_check, rigid_error, solution_check
from .outputs import OutSlot, close, describe, outs
from .slots import ACCEPT, OK, REJECT, Arg, Array, Custom, Real, finite

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
        slots=[
            angle_slot("q", 6),
            frame_slot(6, "frame"),
            frame_slot(6, "point"),
            OutSlot(("float", (6, 6))),
        ],
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
            Custom(
                "joint_names",
                {
                    "sdk": lambda c, r, b: Arg(("a", "b", "c", "d", "e", "f")),
                    "none": lambda c, r, b: Arg(None),
                    "list": lambda c, r, b: Arg(["a", "b", "c", "d", "e", "f"]),
                    "five": lambda c, r, b: Arg(("a", "b", "c", "d", "e"), REJECT, "value"),
                    "int": lambda c, r, b: Arg(3, REJECT, "type"),
                    "str": lambda c, r, b: Arg("abcdef", REJECT, "type"),
                    "numbers": lambda c, r, b: Arg((1, 2, 3, 4, 5, 6), REJECT, "type"),
                },
                default="omit",
            ),
        ],
        probe=arm_probe,
        pair_rule=lambda plan: REJECT if plan["forearm"] == plan["forearm_offset"] == "zero" else None,
        overflow_ok=True,
    )

    def limits_arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    def with_limits_probe(result, kw, c):
        if not isinstance(result, sk.SpotArm) or result is c.arm:
            return f"with_limits returned {describe(result)}, not a new SpotArm"
        q = in_limits(result.limits, np.random.default_rng(1), 16, margin=0.01)
        sol = result.ik_all(result.fk(q))
        inside = (sol.q >= result.limits[:, 0] - 1e-9) & (sol.q <= result.limits[:, 1] + 1e-9)
        if (sol.valid & ~inside.all(-1)).any():
            return "a valid slot lies outside the new limits: the closed form kept the old ones"
        return None

    register(
        name="SpotArm.with_limits",
        covers="spotkin.SpotArm.with_limits",
        call=lambda c, **k: c.arm.with_limits(**k),
        slots=[
            Custom(
                "limits",
                {
                    "valid": limits_arg({"arm0.sh0": (-1.0, 1.0)}),
                    "index": limits_arg({4: (-0.5, 0.5)}),
                    "table": limits_arg(np.tile([-2.0, 2.0], (6, 1))),
                    "unlimited": limits_arg(np.tile([-np.inf, np.inf], (6, 1))),
                    "empty": limits_arg({}),
                    "unknown": limits_arg({"arm0.xx": (0.0, 1.0)}, REJECT, "value"),
                    "inverted": limits_arg({"arm0.sh0": (1.0, -1.0)}, REJECT, "value"),
                    "nan": limits_arg({0: (np.nan, 1.0)}, REJECT, "value"),
                    "shape": limits_arg(np.zeros((5, 2)), REJECT, "value"),
                    "none": limits_arg(None, REJECT, "type"),
                    "str": limits_arg("arm0.sh0", REJECT, "type"),
                },
            )
        ],
        probe=with_limits_probe,
    )

    def from_chain_probe(result, kw, c):
        chain = kw["chain"]
        urdf_names = ("arm_sh0", "arm_sh1", "arm_el0", "arm_el1", "arm_wr0", "arm_wr1")
        spot_arm = isinstance(chain, sk.SpotArm) or chain.joint_names == urdf_names
        if result is None:
            return "the Spot arm's chain was not recognised" if spot_arm else None
        if not spot_arm:
            return f"from_chain made a SpotArm of a chain of another structure: {describe(chain)}"
        if not isinstance(result, sk.SpotArm) or result.joint_names != chain.joint_names:
            return f"from_chain returned {describe(result)}, not a SpotArm with the chain's names"
        q = in_limits(result.limits, np.random.default_rng(2), 8, margin=0.01)
        if np.abs(result.fk(q) - chain.fk(q)).max() > 1e-12:
            return "the SpotArm's fk differs from the chain's"
        return None

    register(
        name="SpotArm.from_chain",
        covers="spotkin.SpotArm.from_chain",
        call=lambda c, **k: sk.SpotArm.from_chain(**k),
        slots=[
            Custom(
                "chain",
                {
                    "valid": lambda c, r, b: Arg(c.robot("spot_urdf").chain("arm_hand")),
                    "spot_arm_itself": lambda c, r, b: Arg(c.arm),
                    "dh6": lambda c, r, b: Arg(c.chain("dh6")),
                    "leg_chain": lambda c, r, b: Arg(c.chain("go2_fl")),
                    "leg": lambda c, r, b: Arg(c.spot.leg("fl"), REJECT, "type"),
                    "none": lambda c, r, b: Arg(None, REJECT, "type"),
                },
            )
        ],
        probe=from_chain_probe,
    )
    return tool_extra
