"""Registry entries of joint positions by name (``q_from_names``, ``names_from_q``)."""

from __future__ import annotations

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import register
from .objects import ROBOT_LEGS
from .outputs import Out, close, describe
from .slots import ACCEPT, EITHER, REJECT, Arg, Choice, Custom

NAME_ROBOTS = ("spot", "go2", "hexapod", "spot_urdf")


def _joint_aliases_of(robot) -> dict:
    """Every name a robot's joint answers to -> that joint (Spot: its SDK name), from the descriptions."""
    table = {joint.name: joint.name for joint in robot.model.joints}
    if isinstance(robot, sk.Spot):  # the URDF's actuated joints are the SDK's legs, arm, gripper, in order
        sdk_names = (*robot.joint_names, *robot.arm_joint_names, "arm0.f1x")
        table.update(zip(robot.urdf_joint_names, sdk_names))
        table.update({name: name for name in (*sdk_names, "arm0.hr0")})
        table["arm_hr0"] = "arm0.hr0"
    return table


def _by_name(names, positions, joints, aliases) -> np.ndarray:
    """The oracle of q_from_names: each joint's position looked up by name (NaN when not given)."""
    table = {aliases.get(str(name), str(name)): value for name, value in zip(names, positions)}
    return np.array([table.get(aliases.get(j, j), np.nan) for j in joints], dtype=np.float64)


def joint_name_entries():
    def reversed_names(c, key):
        return list(reversed(c.robot(key).leg_joint_names))

    def others(c, key):
        """Two joints of the robot that are not in its whole-body q (skipped by q_from_names)."""
        robot = c.robot(key)
        if isinstance(robot, sk.Spot):
            return ["arm0.f1x", "arm0.hr0"]
        leg_joints = set(robot.leg_joint_names)
        return [j.name for j in robot.model.joints if j.name not in leg_joints][:2]

    def names_table(key, lenient=False):
        def arg(make, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(make(c), expect, why)

        def swap_first(value):
            return lambda c: [value(c), *reversed_names(c, key)[1:]]

        table = {
            "valid": arg(lambda c: reversed_names(c, key)),
            "tuple": arg(lambda c: tuple(reversed_names(c, key))),
            "array": arg(lambda c: np.array(reversed_names(c, key))),
            "np_str": arg(lambda c: [np.str_(n) for n in reversed_names(c, key)]),
            "str": arg(lambda c: reversed_names(c, key)[0], REJECT, "type"),
            "bytes": arg(lambda c: [n.encode() for n in reversed_names(c, key)], REJECT, "type"),
            "ints": arg(lambda c: list(range(len(reversed_names(c, key)))), REJECT, "type"),
            "none": arg(lambda c: None, REJECT, "type"),
            "nested": arg(lambda c: [reversed_names(c, key)], REJECT, "type"),
            "dict": arg(lambda c: dict.fromkeys(reversed_names(c, key), 0.0), REJECT, "type"),
            "set": arg(lambda c: set(reversed_names(c, key)), REJECT, "type"),
            "fewer": arg(lambda c: reversed_names(c, key)[1:], REJECT),
            "more": arg(lambda c: [*reversed_names(c, key), "nope"], REJECT),
            "empty": arg(lambda c: [], REJECT),
        }
        if key == "spot":  # the packaged URDF's names for the same joints
            table["aliases"] = arg(lambda c: list(reversed(c.robot(key).urdf_joint_names[:12])))
        strict = REJECT if not lenient else ACCEPT
        table["duplicate"] = arg(swap_first(lambda c: reversed_names(c, key)[1]), REJECT, "value")
        table["stranger"] = arg(swap_first(lambda c: "nope"), strict, "value")
        table["outside_q"] = arg(swap_first(lambda c: others(c, key)[0]), strict, "value")
        if lenient:
            table["two_strangers"] = arg(lambda c: ["nope", "lidar", *reversed_names(c, key)[2:]])
        return table

    def joints_table(key, widths_kept=False):
        def arg(make, expect=ACCEPT, why=""):
            return lambda c, r, b: Arg(make(c), expect, why)

        table = {
            "none": arg(lambda c: None),
            "reversed": arg(lambda c: reversed_names(c, key)),
            "unknown": arg(lambda c: ["nope"], REJECT, "value"),
            "duplicate": arg(lambda c: [c.robot(key).leg_joint_names[0]] * 2, REJECT, "value"),
            "str": arg(lambda c: c.robot(key).leg_joint_names[0], REJECT, "type"),
            "ints": arg(lambda c: [0, 1], REJECT, "type"),
        }
        if key == "spot":
            table["aliases"] = arg(lambda c: list(c.robot(key).urdf_joint_names[:12]))
        if not widths_kept:
            table["subset"] = arg(lambda c: list(c.robot(key).leg_joint_names[:3]))
        return table

    def q_pairs(lenient):
        def rule(plan):
            """The dependent slots: names whose count matches a positions of another width, and a
            missing joint that missing="nan" or a narrower ``joints`` forgives."""
            names, positions, joints = plan["names"], plan["positions"], plan["joints"]
            nan_ok = lenient or plan.get("missing") == "choice:nan"
            ignore_ok = lenient or plan.get("unknown") == "choice:ignore"
            narrow = joints == "subset"  # without the last leg joint, the one names drops
            widths = {"fewer": "trailing_minus", "more": "trailing_plus", "empty": "empty_flat"}
            if widths.get(names) == positions:
                return (
                    ACCEPT
                    if (
                        (names == "fewer" and (nan_ok or narrow))
                        or (names == "more" and ignore_ok and nan_ok)
                        or (names == "empty" and nan_ok)
                    )
                    else REJECT
                )
            if names == "outside_q" and not lenient and positions == "valid" and (nan_ok or narrow):
                return ACCEPT
            return None

        return rule

    def joints_of(c, key, kw):
        joints = kw.get("joints")
        return list(c.robot(key).leg_joint_names) if joints is None else [str(j) for j in joints]

    for key in NAME_ROBOTS:
        covers = "spotkin.Spot" if key == "spot" else "spotkin.Robot"
        light = key == "spot_urdf"
        n = 3 * ROBOT_LEGS[key]

        def baseline(c, rng, n, key=key):
            return {"positions": rng.uniform(-3.0, 3.0, (n, len(c.robot(key).leg_joint_names)))}

        def check(x, out, kw, c, key=key):
            robot = c.robot(key)
            want = _by_name(kw["names"], x["positions"], joints_of(c, key, kw), _joint_aliases_of(robot))
            if not close(out[0], want, x["positions"].dtype == np.float32):
                return f"q {describe(out[0])}, looked up by name {describe(want)}"
            return None

        def outputs(args, kw, n=n):
            joints = kw.get("joints")
            return [Out("float", (n if joints is None else len(joints),))]

        for lenient in (False, True):
            fixed = {"missing": "nan", "unknown": "ignore"} if lenient else {}
            slots = [
                Custom("names", names_table(key, lenient)),
                Batch("positions", (n,)),
                Custom("joints", joints_table(key), default="omit"),
            ]
            if not lenient:
                slots += [
                    Choice("missing", "raise", ("raise", "nan"), default="omit"),
                    Choice("unknown", "raise", ("raise", "ignore"), default="omit"),
                ]
            register(
                name=f"{covers[8:]}.q_from_names[{key}{', lenient' if lenient else ''}]",
                covers="" if lenient else f"{covers}.q_from_names",
                call=lambda c, key=key, fixed=fixed, **k: c.robot(key).q_from_names(**k, **fixed),
                slots=slots,
                baseline=baseline,
                outputs=outputs,
                check=check,
                nan_rule="check",
                light=light,
                pair_rule=q_pairs(lenient),
            )

        def names_probe(result, kw, c, key=key):
            robot = c.robot(key)
            joints = joints_of(c, key, kw)
            aliases = _joint_aliases_of(robot)
            q = kw["q"]
            raw = np.asarray(q)
            f32 = raw.dtype.kind == "f" and raw.dtype.itemsize == 4
            q64 = np.asarray(q, dtype=np.float64)
            names = [str(n) for n in (joints if kw.get("names") is None else kw["names"])]
            if not (isinstance(result, tuple) and len(result) == 2 and isinstance(result[1], np.ndarray)):
                return f"not (names, positions): {describe(result)}"
            got_names, positions = result
            if got_names != tuple(names) or not all(type(n) is str for n in got_names):
                return f"names {got_names}, expected {tuple(names)}"
            canonical = [aliases.get(j, j) for j in joints]
            want = q64[..., [canonical.index(aliases[n]) for n in names]]
            if positions.dtype != (np.float32 if f32 else np.float64):
                return f"positions dtype {positions.dtype} for q of dtype {raw.dtype}"
            if positions.shape != want.shape or not close(positions, want, f32):
                return f"positions {describe(positions)}, expected {describe(want)}"
            if isinstance(q, np.ndarray) and positions.size and np.shares_memory(positions, q):
                return "positions share memory with q"
            return None

        names_only = {
            "none": lambda c, r, b: Arg(None),
            "valid": lambda c, r, b, key=key: Arg(reversed_names(c, key)),
            "subset": lambda c, r, b, key=key: Arg(reversed_names(c, key)[::4]),
            "empty": lambda c, r, b: Arg([]),
            "stranger": lambda c, r, b: Arg(["nope"], REJECT, "value"),
            "outside_q": lambda c, r, b, key=key: Arg(others(c, key)[:1], REJECT, "value"),
            "duplicate": lambda c, r, b, key=key: Arg(reversed_names(c, key)[:1] * 2, REJECT, "value"),
            "str": lambda c, r, b, key=key: Arg(reversed_names(c, key)[0], REJECT, "type"),
            "ints": lambda c, r, b: Arg([0], REJECT, "type"),
        }
        if key == "spot":
            names_only["aliases"] = lambda c, r, b, key=key: Arg(list(c.robot(key).urdf_joint_names[:12]))
        register(
            name=f"{covers[8:]}.names_from_q[{key}]",
            covers=f"{covers}.names_from_q",
            call=lambda c, key=key, **k: c.robot(key).names_from_q(**k),
            slots=[
                Batch("q", (n,)),
                Custom("names", names_only, default="omit"),
                Custom("joints", joints_table(key, widths_kept=True), default="omit"),
            ],
            baseline=lambda c, rng, m, n=n: {"q": rng.uniform(-3.0, 3.0, (m, n))},
            probe=names_probe,
            light=light,
            pair_rule=lambda plan: EITHER if (plan["q"], plan["names"]) == ("huge_batch", "empty") else None,
        )
