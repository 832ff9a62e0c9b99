"""The proof of issue 35, item 8: sk.GaitController walks Spot, Go2 and the tests' own quadruped in
the MuJoCo simulator.

Every run: friction 1, 10 s, the command ramped over the first second, h the nominal hip height
(``sim.hip_height``, the gaits' h). Every run must keep the body above 60 % of its nominal height,
|roll| and |pitch| under 0.3 rad beyond the slope's, no fall, and the commanded torques within the
URDF's effort limits on at least 99 % of the ticks. The speed is the mean over the last 8 s in the
body's heading frame (``Metrics.velocity``).

Each run takes 3 to 5 s (marked ``sim``: ``pytest -m "not sim"`` leaves them out); the file takes
about 40 s on two cores.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk

mujoco = pytest.importorskip("mujoco")
sim = pytest.importorskip("spotkin.sim")
from urdf_helpers import quadruped_urdf  # noqa: E402  (after the optional imports)

DURATION = 10.0


def _go2():
    return sk.Robot.from_urdf(Path(sk.__file__).parent / "robots" / "go2.urdf")


def _own():
    """The tests' own quadruped: 0.4 m segments, 90 kg, 200 N m motors, no meshes, no collisions."""
    return sk.Robot.from_urdf_string(quadruped_urdf(0.4, 90.0, 200.0))


ROBOTS = {"spot": sk.Spot, "go2": _go2, "own": _own}
_made: dict = {}


def robot_named(name: str):
    if name not in _made:
        _made[name] = ROBOTS[name]()
    return _made[name]


class Recorder:
    """Runs a GaitController, switching gaits on schedule, and keeps each tick's planned margin."""

    def __init__(self, controller, changes=()) -> None:
        self.controller, self.changes, self.margin, self.contact = controller, list(changes), [], []

    def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
        gait = None
        for when, name in self.changes:
            if t >= when:
                gait = name
        command = self.controller.step(t, state, velocity, gait=gait)
        self.margin.append(self.controller.last["margin"])
        self.contact.append(command.contact)
        return command


def walk(robot, gait="trot", velocity=(0.0, 0.0, 0.0), changes=(), **options):
    recorder = Recorder(sk.GaitController(robot, gait), changes)
    result = sim.run(robot, recorder, duration=DURATION, velocity=velocity, friction=1.0, ramp=1.0, **options)
    return result, recorder


def holds(result, name: str) -> None:
    """What every run must hold."""
    m = result.metrics
    assert not m.fell, f"{name}: {m}"
    assert m.lowest_height > 0.6 * m.initial_height, f"{name}: {m}"
    # Metrics.fell already says |roll|, |pitch| < 0.3 rad + the slope; say it again, with the figure
    assert m.max_roll < 0.3 and m.max_pitch < 0.3 + math.radians(10.0), f"{name}: {m}"
    assert m.torque_within >= 0.99, f"{name}: {m}"


def within(measured: float, wanted: float, tolerance: float) -> bool:
    return abs(measured - wanted) <= tolerance * abs(wanted)


ALL = list(ROBOTS)
sim_mark = pytest.mark.sim

# The cases that do not pass yet, with what they measure and why (strict: a pass is reported).
BOUND = (
    "the bound is not stabilised: its body must pitch over the end whose feet are down, and the "
    "controller's pendulum sway (which holds the pace's roll) has no fore-aft term, nor a flight phase; "
    "the issue asks for the pace or the bound, and the pace passes on every robot"
)
FAILING = {
    ("transition", "spot", "bound"): f"{BOUND}; measured: Spot falls 1.0 s into the bound",
    ("transition", "go2", "bound"): f"{BOUND}; measured: Go2 falls 1.1 s into the bound",
    ("transition", "own", "bound"): f"{BOUND}; measured: the tests' quadruped falls 2.0 s into the bound",
}


def cases(kind: str, *extra):
    """pytest params (name, *extra) for every robot, the failing ones marked xfail(strict=True)."""
    params = []
    for name in ALL:
        for more in extra or [()]:
            more = more if isinstance(more, tuple) else (more,)
            reason = FAILING.get((kind, name, *more))
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            params.append(pytest.param(name, *more, marks=marks, id="-".join(str(v) for v in (name, *more))))
    return params


# ------------------------------------------------------------------ flat ground


@sim_mark
@pytest.mark.parametrize(("name", "speed"), cases("trot", 0.8, 1.5))
def test_trot_forward(name, speed):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    result, _ = walk(robot, "trot", (speed * h, 0.0, 0.0))
    m = result.metrics
    holds(result, name)
    assert within(m.velocity[0], speed * h, 0.10), f"{name}: {m.velocity[0]:.3f} m/s for {speed * h:.3f}"
    assert m.lateral_drift < 0.10, str(m)
    assert abs(m.heading_change) < 0.15, str(m)


@sim_mark
@pytest.mark.parametrize("name", ALL)
def test_turn_in_place(name):
    robot = robot_named(name)
    result, _ = walk(robot, "trot", (0.0, 0.0, 0.5))
    m = result.metrics
    holds(result, name)
    assert within(m.velocity[2], 0.5, 0.20), str(m)


@sim_mark
@pytest.mark.parametrize("name", ALL)
def test_step_sideways(name):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    result, _ = walk(robot, "trot", (0.0, 0.3 * h, 0.0))
    m = result.metrics
    holds(result, name)
    assert within(m.velocity[1], 0.3 * h, 0.20), str(m)


@sim_mark
@pytest.mark.parametrize("name", ALL)
def test_crawl_keeps_its_margin(name):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    result, recorder = walk(robot, "walk", (0.3 * h, 0.0, 0.0))
    holds(result, name)
    margin = np.array(recorder.margin)
    assert (margin > 0.0).all(), f"{name}: the plan's margin {margin.min():.4f} m"
    assert result.metrics.velocity[0] > 0.15 * h, str(result.metrics)


@sim_mark
@pytest.mark.parametrize(("name", "fast"), cases("transition", "pace", "bound"))
def test_gait_transitions_while_moving(name, fast):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    changes = [(3.0, "trot"), (5.5, fast), (8.0, "trot")]
    result, recorder = walk(robot, "walk", (0.5 * h, 0.0, 0.0), changes)
    holds(result, name)
    contact = np.array(recorder.contact)
    t = result.t
    # the gaits did change: the crawl has three feet or more down, the others two at times
    assert contact[(t > 1.0) & (t < 3.0)].sum(axis=1).min() >= 3
    assert contact[(t > 4.5) & (t < 5.5)].sum(axis=1).min() <= 2
    assert result.metrics.velocity[0] > 0.25 * h, str(result.metrics)


@sim_mark
@pytest.mark.parametrize("name", cases("push"))
def test_lateral_pushes_during_the_trot(name):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    pushes = [(4.0, (0.0, 0.5, 0.0)), (7.0, (0.0, -0.5, 0.0))]
    result, _ = walk(robot, "trot", (0.5 * h, 0.0, 0.0), pushes=pushes)
    holds(result, name)
    assert within(result.metrics.velocity[0], 0.5 * h, 0.25), str(result.metrics)


# ------------------------------------------------------------------ uneven ground


@sim_mark
@pytest.mark.parametrize("degrees", [10.0, -10.0], ids=["up", "down"])
@pytest.mark.parametrize("name", ALL)
def test_trot_on_a_slope(name, degrees):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    result, _ = walk(robot, "trot", (0.5 * h, 0.0, 0.0), terrain=sim.Slope(degrees))
    holds(result, name)
    assert within(result.metrics.velocity[0], 0.5 * h, 0.25), str(result.metrics)


@sim_mark
@pytest.mark.parametrize("name", ALL)
def test_a_step_up_and_back_down(name):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    step = sim.Step(0.1 * h, 1.0 * h, length=1.5 * h)
    result, _ = walk(robot, "trot", (0.5 * h, 0.0, 0.0), terrain=step)
    holds(result, name)
    assert result.position[-1, 0] > step.distance + step.length + 0.5 * h, "it went up and came down"


@sim_mark
@pytest.mark.parametrize("name", ALL)
def test_trot_over_random_bumps(name):
    robot = robot_named(name)
    h = sim.hip_height(robot)
    bumps = sim.Bumps(0.05 * h, seed=1, spacing=0.5 * h, size=12.0 * h)
    result, _ = walk(robot, "trot", (0.5 * h, 0.0, 0.0), terrain=bumps)
    holds(result, name)
    assert within(result.metrics.velocity[0], 0.5 * h, 0.25), str(result.metrics)
