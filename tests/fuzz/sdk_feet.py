"""Registry entries of ``spotkin.sdk``'s feet: ``foot_positions`` and ``foot_states``."""

from __future__ import annotations

import numpy as np
from bosdyn.api import robot_state_pb2
from bosdyn.client import frame_helpers

import spotkin as sk
from spotkin import sdk

from .entry import register
from .outputs import describe
from .sdk_frames import NAN_KEPT
from .sdk_joints import read_states, streamed
from .sdk_messages import Q_STAND, rigid, snapshot, type_errors
from .slots import EITHER, REJECT, Arg, Array, Choice, Custom


def register_entries() -> None:
    """Registers these entries (:mod:`fuzz.sdk` calls it when the SDK is installed)."""
    # ---- feet ----

    def standing(seed=1, feet=4, skip=(), kinematic=False):
        rng = np.random.default_rng(seed)
        spot = sk.Spot()
        q12 = Q_STAND + rng.uniform(-0.1, 0.1, 12)
        feet_body = spot.body_fk(np.eye(4), q12)
        names = [n for n in sk.Spot.joint_names if n not in skip]
        values = [v for n, v in zip(sk.Spot.joint_names, q12) if n not in skip]
        frames = {
            "odom": ("body", rigid(seed + 10)),
            "vision": ("body", rigid(seed + 11)),
            **{name: ("body", sk.translation(p)) for name, p in zip(sdk.FOOT_FRAME_NAMES, feet_body)},
        }
        state = sdk.kinematic_state(names, values, frames=frames)
        if kinematic:
            return state
        return robot_state_pb2.RobotState(kinematic_state=state, foot_state=sdk.foot_states(feet_body)[:feet])

    feet_states = {
        "valid": lambda c, r, b: Arg(standing()),
        "kinematic_state": lambda c, r, b: Arg(standing(kinematic=True)),
        "three_feet": lambda c, r, b: Arg(standing(feet=3)),
        "no_feet": lambda c, r, b: Arg(standing(feet=0)),
        "missing_joint": lambda c, r, b: Arg(standing(skip=("fr.kn",))),
        "list": lambda c, r, b: Arg([standing(1), standing(2)]),
        "empty_list": lambda c, r, b: Arg([]),
        "nested_list": lambda c, r, b: Arg([[standing()]], REJECT, "type"),
        "stream": lambda c, r, b: Arg(streamed(), REJECT, "type"),
        "wrong_message": lambda c, r, b: Arg(snapshot(), REJECT, "type"),
        **type_errors(standing),
    }

    def feet_of(state, frame, source, spot):
        """The oracle: each source read plainly, moved into ``frame`` by the SDK's get_a_tform_b."""
        kinematic = state.kinematic_state if isinstance(state, robot_state_pb2.RobotState) else state
        feet_list = state.foot_state if isinstance(state, robot_state_pb2.RobotState) else []
        if source == "auto":
            source = "foot_state" if len(feet_list) == 4 else "kinematics"
        tree = kinematic.transforms_snapshot
        if source == "foot_state":
            body = np.array(
                [
                    [f.foot_position_rt_body.x, f.foot_position_rt_body.y, f.foot_position_rt_body.z]
                    for f in feet_list
                ]
            )
        elif source == "kinematics":
            table = dict(zip(*read_states(kinematic, "position")))
            q12 = np.array([table.get(n, np.nan) for n in sk.Spot.joint_names])
            body = np.array(
                [spot.hip_positions[k] + spot.legs[k].fk(q12[3 * k : 3 * k + 3]) for k in range(4)]
            )
        else:
            body = np.array(
                [frame_helpers.get_a_tform_b(tree, "body", f).get_translation() for f in sdk.FOOT_FRAME_NAMES]
            )
        if frame == "body":
            return body
        pose = frame_helpers.get_a_tform_b(tree, frame, "body")
        return np.array([pose.transform_point(*p) for p in body])

    def feet_probe(result, kw, c):
        state, frame, source = kw["state"], kw.get("frame", "body"), kw.get("source", "auto")
        spot = kw.get("spot") or c.spot
        if isinstance(state, list):
            want = np.array([feet_of(s, frame, source, spot) for s in state]).reshape(-1, 4, 3)
        else:
            want = feet_of(state, frame, source, spot)
        if isinstance(result, np.ndarray) and result.shape == want.shape and result.dtype == np.float64:
            if (
                np.array_equal(np.isnan(result), np.isnan(want))
                and np.nanmax(np.abs(result - want), initial=0) < 1e-11
            ):
                return None
        return f"feet {describe(result)}, expected {describe(want)}"

    register(
        name="sdk.foot_positions",
        covers="spotkin.sdk.foot_positions",
        call=lambda c, **k: sdk.foot_positions(**k),
        slots=[
            Custom("state", feet_states),
            Custom(
                "frame",
                {
                    "valid": lambda c, r, b: Arg("odom"),
                    "body": lambda c, r, b: Arg("body"),
                    "vision": lambda c, r, b: Arg("vision"),
                    "foot_frame": lambda c, r, b: Arg("hl_foot"),
                    "unknown": lambda c, r, b: Arg("map", REJECT, "value"),
                    "none": lambda c, r, b: Arg(None, REJECT, "type"),
                    "int": lambda c, r, b: Arg(1, REJECT, "type"),
                },
                default="omit",
            ),
            Choice("source", "auto", ("auto", "foot_state", "kinematics", "frames"), default="omit"),
            Custom(
                "spot",
                {
                    "none": lambda c, r, b: Arg(None),
                    "spot": lambda c, r, b: Arg(c.spot),
                    "robot": lambda c, r, b: Arg(c.robot("go2"), REJECT, "type"),
                    "str": lambda c, r, b: Arg("spot", REJECT, "type"),
                },
                default="omit",
            ),
        ],
        probe=feet_probe,
        pair_rule=lambda plan: (
            EITHER
            if plan["state"] == "empty_list"
            else REJECT
            if plan["source"] == "choice:foot_state"
            and plan["state"] in ("three_feet", "no_feet", "kinematic_state")
            else None
        ),
    )

    def foot_states_probe(result, kw, c):
        feet = np.asarray(kw["feet"], dtype=np.float64)
        if not (isinstance(result, list) and len(result) == len(feet)):
            return f"not a list of {len(feet)} FootState: {describe(result)}"
        for k, (state, p) in enumerate(zip(result, feet)):
            if not isinstance(state, robot_state_pb2.FootState):
                return f"item {k} is not a FootState"
            got = [
                state.foot_position_rt_body.x,
                state.foot_position_rt_body.y,
                state.foot_position_rt_body.z,
            ]
            if not np.array_equal(got, p, equal_nan=True):
                return f"foot {k} at {got}, given {p}"
            contact = kw.get("contact")
            want = 0 if contact is None else (1 if contact[k] else 2)
            if state.contact != want:
                return f"foot {k} contact {state.contact}, expected {want}"
        return None

    register(
        name="sdk.foot_states",
        covers="spotkin.sdk.foot_states",
        call=lambda c, **k: sdk.foot_states(**k),
        slots=[
            Array("feet", lambda c: c.spot.body_fk(np.eye(4), Q_STAND), inf_ok=True, extra=NAN_KEPT),
            Custom(
                "contact",
                {
                    "none": lambda c, r, b: Arg(None),
                    "valid": lambda c, r, b: Arg([True, False, True, True]),
                    "array": lambda c, r, b: Arg(np.array([False] * 4)),
                    "short": lambda c, r, b: Arg([True] * 3, REJECT, "value"),
                    "ints": lambda c, r, b: Arg([1, 0, 1, 1], REJECT, "type"),
                    "str": lambda c, r, b: Arg("yes", REJECT, "type"),
                },
                default="omit",
            ),
        ],
        probe=foot_states_probe,
    )
