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


def test_one_robot_s_fast_step_is_the_general_step_to_the_bit():
    """``step`` reads a single robot's float64 rows in place and builds the JointCommand in the core;
    ``_step`` converts, broadcasts and checks in general. Over a walk with changing commands, measured
    contacts and without, both give the same bits, and the command is a full JointCommand."""
    robot = robot_named("go2")
    rng = np.random.default_rng(7)
    fast, general = sk.GaitController(robot), sk.GaitController(robot)
    base = _standing(robot)
    for tick in range(300):
        state = base.replace(
            position=base.position + rng.normal(0, 0.005, 3),
            linear_velocity=rng.normal(0, 0.05, 3),
            q=base.q + rng.normal(0, 0.01, 12),
            qd=rng.normal(0, 0.1, 12),
            contact=None if tick % 3 else rng.random(4) < 0.7,
        )
        velocity = (0.2, 0.05 * np.sin(tick / 50), 0.1) if tick % 2 else [0, 0, 0]  # a list of ints too
        a = fast.step(tick / 500, state, velocity)
        b = general._step(tick / 500, state, velocity, None)
        for field in ("q", "qd", "tau", "kp", "kd", "contact"):
            got, want = getattr(a, field), getattr(b, field)
            assert got.shape == want.shape and got.dtype == want.dtype, field
            assert np.array_equal(got, want), f"tick {tick}: {field}"
        for field in DETAILS:
            if field != "time":
                assert np.array_equal(fast.last[field], general.last[field]), f"tick {tick}: {field}"
    assert type(a) is sk.motion.JointCommand and fast.ticks == general.ticks == 300
    with pytest.raises(AttributeError):  # frozen, as one made by its __init__
        a.q = a.qd
    np.testing.assert_array_equal(a.torques(a.q, a.qd), a.tau)
    # the states above did take the in-place path: it answers them (and declines what it does not take)
    probe = sk.GaitController(robot)
    assert type(probe._core.step_one(0.0, probe._start_index, -1, base, [0, 0, 0])) is sk.motion.JointCommand
    assert probe._core.step_one(0.002, probe._start_index, -1, base, (0.1, 0.0)) is None


def test_one_robot_s_step_declines_to_the_general_path_with_its_errors():
    """What the in-place step does not take goes the general way: the same command for a strided row,
    an integer time or a NumPy scalar one, and the general path's errors for NaN, a zero quaternion,
    a wrong width or time going back."""
    robot = robot_named("go2")
    state = _standing(robot)
    want = sk.GaitController(robot).step(0.25, state, (0.1, 0.0, 0.0))
    wide = np.zeros((12, 2))
    wide[:, 0] = state.q
    strided = state.replace(q=wide[:, 0])  # a non-contiguous (12,) row
    assert not strided.q.flags.c_contiguous
    probe = sk.GaitController(robot)
    assert probe._core.step_one(0.25, probe._start_index, -1, strided, (0.1, 0.0, 0.0)) is None
    assert probe._core.step_one(1, probe._start_index, -1, state, (0.1, 0.0, 0.0)) is None  # an int t
    for t, s, v in [(0.25, strided, (0.1, 0.0, 0.0)), (np.float64(0.25), state, np.array([0.1, 0.0, 0.0]))]:
        got = sk.GaitController(robot).step(t, s, v)
        assert np.array_equal(got.tau, want.tau) and np.array_equal(got.q, want.q)
    assert sk.GaitController(robot).step(1, state, (0, 0, 0)).q.shape == (12,)
    controller = sk.GaitController(robot)
    with pytest.raises(ValueError, match=r"state\.position must be finite"):
        controller.step(0.0, state.replace(position=np.array([0.0, np.nan, 0.3])), (0.1, 0.0, 0.0))
    with pytest.raises(ValueError, match="velocity must be finite"):
        controller.step(0.0, state, (0.1, np.inf, 0.0))
    with pytest.raises(ValueError, match="non-zero length"):
        controller.step(0.0, state.replace(quaternion=np.zeros(4)), (0.1, 0.0, 0.0))
    with pytest.raises(ValueError, match="velocity"):
        controller.step(0.0, state, (0.1, 0.0))
    controller.step(1.0, state, (0.1, 0.0, 0.0))
    with pytest.raises(ValueError, match="t went backwards"):
        controller.step(0.5, state, (0.1, 0.0, 0.0))
    with pytest.raises(TypeError, match="RobotState"):
        controller.step(1.5, (state.position, state.quaternion), (0.1, 0.0, 0.0))


@pytest.mark.parametrize("name", ["go2", "spot"])
def test_a_hard_kick_asks_no_more_horizontal_force_than_the_feet_can_give(name):
    """A body moving sideways at 2 m/s while the reference stands still: the virtual force's velocity
    term alone would be 2 wb m (2 m/s), several times the weight; its horizontal part is limited to
    HORIZONTAL_WRENCH m g (beyond it the feet under the body would tip it or slip), in the compiled
    tick and in the reference alike."""
    robot = robot_named(name)
    controller = sk.GaitController(robot, "trot")
    still = _standing(robot)
    controller.step(0.0, still)
    kicked = still.replace(linear_velocity=np.array([0.0, 2.0, 0.0]))
    controller.step(0.002, kicked)
    wrench = controller.last["wrench"]
    weight = robot.mass * 9.81
    unclamped = 2.0 * controller.body_omega * robot.mass * 2.0
    assert unclamped > 2.0 * weight  # the case does reach the limit
    assert np.hypot(*wrench[:2]) == pytest.approx(reference.HORIZONTAL_WRENCH * weight, rel=1e-12)
    assert wrench[1] < 0.0  # it still opposes the kick
    table = [controller._resolve(sk.Gait("trot"))]
    ref = reference.ReferenceController(robot, table[0])
    memory = reference.Memory(robot.n_legs)
    for t, state in ((0.0, still), (0.002, kicked)):
        ref.tick(memory, table, 0, -1, t, *(getattr(state, f) for f in FIELDS), state.contact, np.zeros(3))
    assert_close(wrench, memory.last["wrench"], "wrench", weight)
