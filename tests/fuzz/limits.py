"""The fuzz registry's entries for the joint-limit overrides: ``Robot.with_limits``, ``Spot.with_limits``
and ``Chain.with_limits``. ``tests/fuzz/registry.py`` calls :func:`register_entries`.

The probes read the limits back from the new object (the named joints have the given limits, the others
keep theirs) and check that the original is unchanged."""

from __future__ import annotations

import numpy as np

import spotkin as sk

from .entry import register
from .slots import ACCEPT, REJECT, Arg, Custom


def register_entries() -> None:

    def arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    def rejections(name):
        return {
            "reversed": arg({name: (-1.0, -2.0)}, REJECT, "value"),
            "nan": arg({name: (np.nan, 1.0)}, REJECT, "value"),
            "unknown": arg({"no_such_joint": (0.0, 1.0)}, REJECT, "value"),
            "three": arg({name: (0.0, 1.0, 2.0)}, REJECT, "value"),
            "scalar": arg({name: 1.0}, REJECT, "value"),
            "text": arg({name: "wide"}, REJECT),
            "none_value": arg({name: None}, REJECT),
            "list": arg([(0.0, 1.0)], REJECT, "type"),
            "none": arg(None, REJECT, "type"),
            "int": arg(1, REJECT, "type"),
            "str": arg(name, REJECT, "type"),
        }

    def leg_limits_probe(get, joint_slot):
        """joint_slot(robot, name) -> (leg index, joint index) of a leg joint, or None."""

        def probe(result, kw, c):
            robot = get(c)
            if not isinstance(result, type(robot)) or result is robot:
                return f"with_limits returned {result!r}, not a new {type(robot).__name__}"
            for name, pair in kw["limits"].items():
                where = joint_slot(result, name)
                if where is None:
                    continue
                row = result.legs[where[0]].limits[where[1]]
                if not np.array_equal(row, np.asarray(pair, dtype=np.float64)):
                    return f"joint {name}: limits {row}, given {pair}"
            for k, (old, new) in enumerate(zip(robot.legs, result.legs)):
                changed = [
                    j
                    for j in range(3)
                    if not np.array_equal(old.limits[j], new.limits[j])
                    and all(joint_slot(result, name) != (k, j) for name in kw["limits"])
                ]
                if changed:
                    return f"leg {k}: joints {changed} changed limits though not named"
            return None

        return probe

    def go2_slot(robot, name):
        if name not in robot.leg_joint_names:
            return None
        k = robot.leg_joint_names.index(name)
        return k // 3, k % 3

    go2_table = {
        "valid": arg({"FL_calf_joint": (-2.0, -1.0)}),
        "two": arg({"FL_calf_joint": (-2.0, -1.0), "RR_hip_joint": (-0.1, 0.1)}),
        "empty": arg({}),
        "unlimited": arg({"RR_hip_joint": (-np.inf, np.inf)}),
        "float32": arg({"FR_thigh_joint": np.array([-1.0, 2.0], dtype=np.float32)}),
        "point": arg({"FR_thigh_joint": (0.5, 0.5)}),
        "fixed": arg({"FL_foot_joint": (0.0, 1.0)}, REJECT, "value"),
        "int_key": arg({3: (0.0, 1.0)}, REJECT, "type"),
        **rejections("FL_calf_joint"),
    }
    register(
        name="Robot.with_limits[go2]",
        covers="spotkin.Robot.with_limits",
        call=lambda c, **k: c.robot("go2").with_limits(**k),
        slots=[Custom("limits", go2_table)],
        probe=leg_limits_probe(lambda c: c.robot("go2"), go2_slot),
    )

    def spot_slot(robot, name):
        names = sk.Spot.joint_names
        urdf = {f"front_left_{j}": f"fl.{k}" for j, k in (("hip_x", "hx"), ("hip_y", "hy"), ("knee", "kn"))}
        name = urdf.get(name, name)
        if name not in names:
            return None
        k = names.index(name)
        return k // 3, k % 3

    spot_table = {
        "valid": arg({"fl.kn": (-2.0, -1.0)}),
        "urdf_name": arg({"front_left_knee": (-2.0, -1.0)}),
        "arm": arg({"arm0.sh0": (-1.0, 1.0)}),
        "gripper": arg({"arm0.f1x": (-1.0, 0.0)}),
        "empty": arg({}),
        "fixed": arg({"arm0.hr0": (0.0, 1.0)}, REJECT, "value"),
        **rejections("fl.kn"),
    }
    register(
        name="Spot.with_limits",
        covers="spotkin.Spot.with_limits",
        call=lambda c, **k: c.spot.with_limits(**k),
        slots=[Custom("limits", spot_table)],
        probe=leg_limits_probe(lambda c: c.spot, spot_slot),
    )

    def chain(c):
        return c.robot("go2").chain("FL_foot")

    def chain_probe(result, kw, c):
        original = chain(c)
        if not isinstance(result, sk.Chain) or result is original or result.dof != original.dof:
            return f"with_limits returned {result!r}, not a new Chain of the same joints"
        expected = np.c_[original.lower, original.upper]
        limits = kw["limits"]
        if isinstance(limits, dict):
            for key, pair in limits.items():
                k = original.joint_names.index(key) if isinstance(key, str) else int(key)
                expected[k] = np.asarray(pair, dtype=np.float64)
        else:
            expected = np.asarray(limits, dtype=np.float64)
        if not np.array_equal(np.c_[result.lower, result.upper], expected):
            return f"limits {np.c_[result.lower, result.upper].tolist()}, expected {expected.tolist()}"
        return None

    chain_table = {
        "valid": arg({"FL_calf_joint": (-2.0, -1.0)}),
        "index": arg({2: (-2.0, -1.0)}),
        "np_index": arg({np.int64(0): (-0.5, 0.5)}),
        "negative_index": arg({-1: (-2.0, -1.0)}),
        "table": arg(np.array([[-1.0, 1.0], [-1.5, 3.4], [-2.7, -0.8]])),
        "table_f32": arg(np.array([[-1.0, 1.0], [-1.5, 3.4], [-2.7, -0.8]], dtype=np.float32)),
        "table_list": arg([[-1.0, 1.0], [-1.5, 3.4], [-2.7, -0.8]]),
        "empty": arg({}),
        "table_shape": arg(np.zeros((2, 2)), REJECT, "value"),
        "table_nan": arg(np.full((3, 2), np.nan), REJECT, "value"),
        "out_of_range": arg({3: (0.0, 1.0)}, REJECT, "value"),
        "bool_key": arg({True: (0.0, 1.0)}, REJECT, "type"),
        "float_key": arg({1.0: (0.0, 1.0)}, REJECT, "type"),
        **{k: v for k, v in rejections("FL_calf_joint").items() if k not in ("list", "str")},
        "str": arg("FL_calf_joint", REJECT),
    }
    register(
        name="Chain.with_limits[go2_leg]",
        covers="spotkin.Chain.with_limits",
        call=lambda c, **k: chain(c).with_limits(**k),
        slots=[Custom("limits", chain_table)],
        probe=chain_probe,
    )
