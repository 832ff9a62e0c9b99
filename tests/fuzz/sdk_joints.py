"""Registry entries of ``spotkin.sdk``'s joint states: ``joint_states``, ``joint_positions`` and
``kinematic_state``."""

from __future__ import annotations

import math

import numpy as np
from bosdyn.api import geometry_pb2, robot_state_pb2

import spotkin as sk
from spotkin import sdk

from .entry import register
from .outputs import describe
from .sdk_frames import NAN_KEPT, tree_probe
from .sdk_messages import rigid, same, se3, snapshot, type_errors
from .slots import ACCEPT, REJECT, Arg, Array, Choice, Custom


def streamed(count=19, kind="response"):
    values = np.random.default_rng(count).uniform(-1, 1, count).tolist()
    combined = robot_state_pb2.CombinedJointStates(position=values, velocity=values, load=values)
    if kind == "combined":
        return combined
    return robot_state_pb2.RobotStateStreamResponse(joint_states=combined)


def read_states(state, field):
    """(names, values) read field by field, the oracle's way."""
    if isinstance(state, robot_state_pb2.RobotState):
        state = state.kinematic_state
    if isinstance(state, robot_state_pb2.KinematicState):
        names = tuple(j.name for j in state.joint_states)
        values = [getattr(j, field).value if j.HasField(field) else math.nan for j in state.joint_states]
        return names, np.array(values, dtype=np.float64)
    if isinstance(state, robot_state_pb2.RobotStateStreamResponse):
        state = state.joint_states
    values = np.array(getattr(state, field), dtype=np.float64)
    return sdk.JOINT_NAMES[: len(values)], values


def register_entries() -> None:
    """Registers these entries (:mod:`fuzz.sdk` calls it when the SDK is installed)."""
    # ---- joint states ----

    SDK_LISTING = [
        *sk.Spot.joint_names,
        "arm0.sh0",
        "arm0.sh1",
        "arm0.hr0",
        *sk.Spot.arm_joint_names[2:],
        "arm0.f1x",
    ]

    def named_state(seed=1, skip=(), change=None, kind="kinematic"):
        rng = np.random.default_rng(seed)
        state = robot_state_pb2.KinematicState()
        for name in rng.permutation(SDK_LISTING):
            if name in skip:
                continue
            joint = state.joint_states.add(name=str(name))
            value = 0.0 if name == "arm0.hr0" else float(rng.uniform(-1, 1))
            joint.position.value, joint.velocity.value, joint.load.value = value, 2 * value, -value
        if change is not None:
            change(state)
        if kind == "robot":
            return robot_state_pb2.RobotState(kinematic_state=state)
        return state

    def nan_value(state):
        state.joint_states[3].position.value = math.nan
        state.joint_states[5].velocity.value = math.inf

    def twice(state):
        state.joint_states.add(name=state.joint_states[0].name).position.value = 0.0

    def unset(state):
        state.joint_states[0].ClearField("position")

    state_table = {
        "valid": lambda c, r, b: Arg(named_state()),
        "robot_state": lambda c, r, b: Arg(named_state(kind="robot")),
        "stream": lambda c, r, b: Arg(streamed()),
        "stream_legs": lambda c, r, b: Arg(streamed(12)),
        "combined": lambda c, r, b: Arg(streamed(19, "combined")),
        "no_arm": lambda c, r, b: Arg(named_state(skip=sk.Spot.arm_joint_names + ("arm0.hr0", "arm0.f1x"))),
        "missing_leg_joint": lambda c, r, b: Arg(named_state(skip=("hl.kn",))),
        "unset_value": lambda c, r, b: Arg(named_state(change=unset)),
        "nan_values": lambda c, r, b: Arg(named_state(change=nan_value)),
        "empty_state": lambda c, r, b: Arg(robot_state_pb2.KinematicState()),
        "empty_stream": lambda c, r, b: Arg(robot_state_pb2.CombinedJointStates()),
        "named_twice": lambda c, r, b: Arg(named_state(change=twice), REJECT, "value"),
        "stream_7": lambda c, r, b: Arg(streamed(7), REJECT, "value"),
        "wrong_message": lambda c, r, b: Arg(se3(rigid(1)), REJECT, "type"),
        **{k: v for k, v in type_errors(named_state).items() if k != "list_mixed"},
    }

    STREAMS = ("stream", "stream_legs", "combined", "empty_stream")

    def states_probe(result, kw, c):
        names, values = read_states(kw["state"], kw.get("field", "position"))
        if not (isinstance(result, tuple) and len(result) == 2 and result[0] == names):
            return f"names {describe(result)}, expected {names}"
        return same(result[1], values, "values")

    register(
        name="sdk.joint_states",
        covers="spotkin.sdk.joint_states",
        call=lambda c, **k: sdk.joint_states(**k),
        slots=[
            Custom("state", {**state_table, "list": lambda c, r, b: Arg([named_state()], REJECT, "type")}),
            Choice("field", "position", ("position", "velocity", "acceleration", "load"), default="omit"),
        ],
        probe=states_probe,
        pair_rule=lambda plan: (
            REJECT if plan["state"] in STREAMS and plan["field"] == "choice:acceleration" else None
        ),
    )

    Q_NAMES = (*sk.Spot.joint_names, *sk.Spot.arm_joint_names)

    def q_of(state, field):
        names, values = read_states(state, field)
        table = dict(zip(names, values))
        return np.array([table.get(name, math.nan) for name in Q_NAMES])

    def positions_probe(result, kw, c):
        field = kw.get("field", "position")
        state = kw["state"]
        want = (
            np.array([q_of(s, field) for s in state]).reshape(-1, 18)
            if isinstance(state, list)
            else q_of(state, field)
        )
        if not (isinstance(result, tuple) and len(result) == 2):
            return f"not (q12, q_arm): {describe(result)}"
        return same(result[0], want[..., :12], "q12") or same(result[1], want[..., 12:], "q_arm")

    def positions_pairs(plan):
        if plan["state"] in STREAMS + ("list_streams",) and plan["field"] == "choice:acceleration":
            return REJECT
        incomplete = (
            "no_arm",
            "missing_leg_joint",
            "unset_value",
            "empty_state",
            "empty_stream",
            "stream_legs",
        )
        if plan["state"] in incomplete and plan["missing"] == "choice:raise":
            return REJECT
        if plan["missing"] == "choice:raise" and plan["field"] == "choice:acceleration":
            return REJECT  # the states here report no accelerations
        return None

    register(
        name="sdk.joint_positions",
        covers="spotkin.sdk.joint_positions",
        call=lambda c, **k: sdk.joint_positions(**k),
        slots=[
            Custom(
                "state",
                {
                    **state_table,
                    "list": lambda c, r, b: Arg(
                        [named_state(1), named_state(2, kind="robot"), named_state(3)]
                    ),
                    "list_streams": lambda c, r, b: Arg([streamed(), streamed(19, "combined")]),
                    "empty_list": lambda c, r, b: Arg([]),
                    "nested_list": lambda c, r, b: Arg([[named_state()]], REJECT, "type"),
                    "list_mixed": lambda c, r, b: Arg([named_state(), "x"], REJECT, "type"),
                },
            ),
            Choice("field", "position", ("position", "velocity", "acceleration", "load"), default="omit"),
            Choice("missing", "nan", ("nan", "raise"), default="omit"),
        ],
        probe=positions_probe,
        pair_rule=positions_pairs,
    )

    def names_arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    EVERY = [*Q_NAMES, "arm0.f1x"]

    def frames_arg(kind):
        def make(c, r, b):
            if kind == "dict":
                return Arg({"odom": ("body", rigid(7)), "gpe": ("odom", rigid(8))})
            if kind == "snapshot":
                return Arg(snapshot())
            if kind == "loop":
                return Arg({"a": ("b", np.eye(4)), "b": ("a", np.eye(4))}, REJECT, "value")
            return Arg("odom", REJECT, "type")

        return make

    def kinematic_probe(result, kw, c):
        if not isinstance(result, robot_state_pb2.KinematicState):
            return f"not a KinematicState: {describe(result)}"
        names = tuple(str(n) for n in kw["names"])
        for field in ("position", "velocity", "acceleration", "load"):
            given = kw.get(field)
            got_names, got = read_states(result, field)
            if got_names != names:
                return f"names {got_names}, expected {names}"
            want = (
                np.full(len(names), np.nan)
                if given is None
                else np.asarray(given, dtype=np.float64).reshape(-1)
            )
            if not np.array_equal(got, want, equal_nan=True):
                return f"{field}s {describe(got)}, given {describe(want)} (NaN: unset)"
        frames = kw.get("frames")
        if frames is None:
            return None if not result.HasField("transforms_snapshot") else "a frame tree from no frames"
        if isinstance(frames, geometry_pb2.FrameTreeSnapshot):
            return None if result.transforms_snapshot == frames else "the snapshot is not the one given"
        return tree_probe(result.transforms_snapshot, {"edges": frames}, c)

    def values_array(name, optional=True):
        extra = {"optional": True, "default": "omit"} if optional else {}
        return Array(name, lambda c: np.linspace(-1.0, 1.0, 19), inf_ok=True, extra=NAN_KEPT, **extra)

    register(
        name="sdk.kinematic_state",
        covers="spotkin.sdk.kinematic_state",
        call=lambda c, **k: sdk.kinematic_state(**k),
        slots=[
            Custom(
                "names",
                {
                    "valid": names_arg(EVERY),
                    "tuple": names_arg(tuple(EVERY)),
                    "array": names_arg(np.array(EVERY)),
                    "twice": names_arg([EVERY[0], *EVERY[:-1]], REJECT, "value"),
                    "str": names_arg("fl.hx", REJECT, "type"),
                    "ints": names_arg(list(range(19)), REJECT, "type"),
                    "none": names_arg(None, REJECT, "type"),
                    "dict": names_arg(dict.fromkeys(EVERY, 0.0), REJECT, "type"),
                    "fewer": names_arg(EVERY[:-1], REJECT),  # 18 names for 19 positions
                },
            ),
            values_array("position", optional=False),
            values_array("velocity"),
            values_array("acceleration"),
            values_array("load"),
            Custom(
                "frames",
                {
                    "none": lambda c, r, b: Arg(None),
                    "dict": frames_arg("dict"),
                    "snapshot": frames_arg("snapshot"),
                    "loop": frames_arg("loop"),
                    "str": frames_arg("str"),
                },
                default="omit",
            ),
        ],
        probe=kinematic_probe,
    )
