"""The compiled gait controller (``sk.GaitController``, cpp/src/gait_controller.cpp) against the
pure-Python reference controller (``spotkin.reference.controller``), tick by tick, on the same
measured states: those of a walk in the simulator (a trot with a push, then the walk, then the pace,
with the feet's measured contacts and without); Spot, Go2 and the tests' own 90 kg quadruped; every
instruction-set level. The commands and every detail of a tick agree to 1e-8."""

from __future__ import annotations

import numpy as np
import pytest
from urdf_helpers import robot_named

import spotkin as sk
from spotkin.motion import RobotState
from spotkin.motion.controller import DETAILS
from spotkin.reference import controller as reference


def assert_close(got, want, name: str, scale: float = 1.0) -> None:
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    assert got.shape == want.shape, name
    np.testing.assert_allclose(got, want, rtol=1e-8, atol=1e-8 * scale, err_msg=name)


class Replay:
    """Runs the compiled controller in the simulator and records what each tick was given."""

    def __init__(self, controller, changes) -> None:
        self.controller, self.changes, self.ticks = controller, dict(changes), []

    def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
        tick = len(self.ticks)
        gait = self.changes.get(tick)
        command = self.controller.step(t, state, velocity, gait=gait)
        self.ticks.append((t, state, np.array(velocity, dtype=float), gait, command, self.controller.last))
        return command


GAITS = ("trot", "walk", "pace")


@pytest.mark.usefixtures("every_isa")
@pytest.mark.parametrize("name", ["spot", "go2", "heavy"])
@pytest.mark.parametrize("contacts", [True, False])
def test_the_compiled_tick_is_the_reference_tick(name, contacts):
    """The simulator gives physically consistent states (the legs in their workspace, the contacts the
    feet's): a trot with a push, then the walk, then the pace; replayed through the reference."""
    sim = pytest.importorskip("spotkin.sim")
    robot = robot_named(name)
    compiled = sk.GaitController(robot, "trot", attitude=(0.02, -0.03))
    h = compiled.h
    replay = Replay(compiled, {400: "walk", 700: "pace"})
    sim.run(
        robot,
        replay,
        duration=1.8,
        velocity=(0.5 * h, 0.1 * h, 0.3),
        ramp=0.2,
        pushes=[(0.5, (0.0, 0.3, 0.0))],
    )
    table = [compiled._resolve(sk.Gait(gait)) for gait in GAITS]
    ref = reference.ReferenceController(robot, table[0], attitude=(0.02, -0.03))
    memory = reference.Memory(robot.n_legs)
    weight = robot.mass * 9.81
    compiled_without = sk.GaitController(robot, "trot", attitude=(0.02, -0.03))
    for tick, (t, state, velocity, gait, command, last) in enumerate(replay.ticks):
        index = -1 if gait is None else GAITS.index(gait)
        contact = state.contact if contacts else None
        if not contacts:  # the run had them: a second controller without, on the same states
            command = compiled_without.step(t, state.replace(contact=None), velocity, gait=gait)
            last = compiled_without.last
        want = ref.tick(
            memory,
            table,
            0,
            index,
            t,
            state.position,
            state.quaternion,
            state.linear_velocity,
            state.angular_velocity,
            state.q,
            state.qd,
            contact,
            velocity,
        )
        for got, expected, field in zip(
            (command.q, command.qd, command.tau, command.contact, command.kp, command.kd),
            want,
            ("q", "qd", "tau", "contact", "kp", "kd"),
        ):
            scale = weight * h if field == "tau" else 1.0
            assert_close(got, expected, f"tick {tick}: {field}", scale)
        for field in DETAILS:
            if field == "time":
                continue
            scale = weight * max(h, 1.0) if field in ("forces", "residual", "wrench") else 1.0
            assert_close(last[field], memory.last[field], f"tick {tick}: {field}", scale)


FIELDS = ("position", "quaternion", "linear_velocity", "angular_velocity", "q", "qd")


def _standing(robot, lead=(), dtype=np.float64) -> RobotState:
    gait = sk.Gait("trot").resolve(robot)
    pose = np.array([0.0, 0.0, gait.height, 0.0, 0.0, 0.0])
    q = robot.body_ik(pose, gait.stance).q
    return RobotState(
        np.broadcast_to(pose[:3], (*lead, 3)).astype(dtype),
        np.broadcast_to([0.0, 0.0, 0.0, 1.0], (*lead, 4)).astype(dtype),
        np.zeros((*lead, 3), dtype),
        np.zeros((*lead, 3), dtype),
        np.broadcast_to(q, (*lead, 12)).astype(dtype),
        np.zeros((*lead, 12), dtype),
    )


@pytest.mark.parametrize("lead", [(), (1,), (3, 1, 2), (0,)])
def test_a_batch_of_any_shape_is_each_robot_alone(lead):
    robot = robot_named("go2")
    rng = np.random.default_rng(len(lead))
    velocity = rng.uniform(-0.2, 0.2, (*lead, 3))
    state = _standing(robot, lead)
    state = state.replace(position=state.position + rng.normal(0, 0.01, state.position.shape))
    together = sk.GaitController(robot)
    alone = [sk.GaitController(robot) for _ in np.ndindex(*lead)]
    for tick in range(30):
        command = together.step(tick / 500, state, velocity)
        assert command.q.shape == command.tau.shape == command.kp.shape == (*lead, 12)
        assert command.contact.shape == (*lead, 4) and command.contact.dtype == bool
        for controller, index in zip(alone, np.ndindex(*lead)):
            one = RobotState(
                *(
                    getattr(state, f)[index]
                    for f in ("position", "quaternion", "linear_velocity", "angular_velocity", "q", "qd")
                )
            )
            single = controller.step(tick / 500, one, velocity[index])
            for field in ("q", "qd", "tau", "kp", "kd", "contact"):
                assert np.array_equal(getattr(command, field)[index], getattr(single, field)), field


def test_float32_stays_float32_and_strided_states_work():
    robot = robot_named("go2")
    single = sk.GaitController(robot).step(0.0, _standing(robot, (), np.float32), np.float32([0.1, 0.0, 0.0]))
    assert single.q.dtype == single.tau.dtype == single.kp.dtype == np.float32
    wide = _standing(robot, (4,))
    strided = RobotState(
        *(
            np.asfortranarray(getattr(wide, f)[::2])
            for f in ("position", "quaternion", "linear_velocity", "angular_velocity", "q", "qd")
        )
    )
    dense = RobotState(
        *(
            np.ascontiguousarray(getattr(strided, f))
            for f in ("position", "quaternion", "linear_velocity", "angular_velocity", "q", "qd")
        )
    )
    a = sk.GaitController(robot).step(0.0, strided, (0.1, 0.0, 0.0))
    b = sk.GaitController(robot).step(0.0, dense, (0.1, 0.0, 0.0))
    assert np.array_equal(a.tau, b.tau) and a.q.shape == (2, 12)


def test_the_threads_do_not_change_a_batch_s_bits():
    robot = robot_named("spot")
    state = _standing(robot, (300,))
    velocity = np.random.default_rng(1).uniform(-0.3, 0.3, (300, 3))
    before = sk.get_num_threads()
    commands = []
    try:
        for threads in (1, 2):
            sk.set_num_threads(threads)
            controller = sk.GaitController(robot)
            for tick in range(20):
                command = controller.step(tick / 500, state, velocity)
            commands.append(command)
    finally:
        sk.set_num_threads(before)
    for field in ("q", "qd", "tau", "kp", "kd", "contact"):
        assert np.array_equal(getattr(commands[0], field), getattr(commands[1], field)), field
