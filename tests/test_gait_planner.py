"""The compiled gait planner (``Robot.plan_gait``, cpp/src/gait_plan.cpp) against the pure-Python
reference planner (``spotkin.reference.gait_plan.plan``), tick by tick: every preset on Spot, Go2 and
two quadrupeds the tests describe (2 kg and 90 kg), commands the legs cannot follow, custom gaits,
attitudes and rates; at every instruction-set level. Then the batch semantics (leading shapes, each
command's plan the same alone and in a batch, for any thread count) and the compiled entry point's
own checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from urdf_helpers import robot_named

import spotkin as sk
from spotkin import _core
from spotkin.motion.plan import gait_numbers
from spotkin.reference import gait_plan

PRESETS = ("stand", "walk", "trot", "pace", "bound", "pronk", "gallop")
FLAGS = ("contact", "status", "shortened")


def assert_same_plan(robot, gait, velocity, duration, rate, attitude=(0.0, 0.0)) -> None:
    """The compiled plan equals the reference's: the flags exactly, the numbers to 1e-9 (relative to
    their size), NaN and infinities where the reference has them."""
    plan = robot.plan_gait(gait, velocity=velocity, duration=duration, rate=rate, attitude=attitude)
    resolved = (sk.Gait(gait) if isinstance(gait, str) else gait).resolve(robot)
    ref = gait_plan.plan(robot, resolved, velocity, duration, rate, attitude=attitude)
    assert plan.t.shape == ref["t"].shape
    np.testing.assert_allclose(plan.t, ref["t"], rtol=0, atol=1e-9)
    for name in gait_plan.OUTPUTS[1:]:
        got, want = getattr(plan, name), ref[name]
        assert got.shape == want.shape, name
        if name in FLAGS:
            mismatch = np.flatnonzero(got != want)
            assert mismatch.size == 0, f"{name} differs at ticks {mismatch[:5]}"
            continue
        assert np.array_equal(np.isnan(got), np.isnan(want)), name
        assert np.array_equal(np.isinf(got), np.isinf(want)) and np.array_equal(
            got[np.isinf(got)], want[np.isinf(want)]
        )
        finite = np.isfinite(want)
        scale = 1.0 if name not in ("tau", "residual") else robot.mass * 9.81
        np.testing.assert_allclose(got[finite], want[finite], rtol=1e-9, atol=1e-9 * scale, err_msg=name)


@pytest.mark.usefixtures("every_isa")
@pytest.mark.parametrize("name", ["spot", "go2", "heavy", "small"])
@pytest.mark.parametrize("gait", PRESETS)
def test_every_preset_on_every_robot_is_the_reference_plan(name, gait):
    robot = robot_named(name)
    h = sk.motion.hip_height(robot)
    period = sk.Gait(gait).resolve(robot).period
    # a forward, sideways and turning command, over the start's blend and two more periods
    assert_same_plan(robot, gait, [0.4 * h, 0.1 * h, 0.3], 3.0 * period, rate=100.0)


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_a_command_the_legs_cannot_follow_is_shortened_as_the_reference_does(name):
    robot = robot_named(name)
    h = sk.motion.hip_height(robot)
    plan = robot.plan_gait("trot", velocity=[6.0 * h, 2.0 * h, 1.5], duration=1.5, rate=100.0)
    assert plan.shortened.any()
    assert_same_plan(robot, "trot", [6.0 * h, 2.0 * h, 1.5], 1.5, rate=100.0)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    vx=st.floats(-1.5, 1.5),
    vy=st.floats(-0.6, 0.6),
    yaw=st.floats(-1.0, 1.0),
    period=st.floats(0.25, 0.8),
    duty=st.floats(0.3, 0.9),
    step=st.floats(0.0, 0.12),
    roll=st.floats(-0.1, 0.1),
    pitch=st.floats(-0.1, 0.1),
    rate=st.sampled_from([60.0, 173.0, 400.0]),
    preset=st.sampled_from(["walk", "trot", "pace", "bound", "gallop"]),
)
# a flight phase (no foot down) at ticks where a leg has no IK answer: the residual is NaN there, as
# the margin (the centre of mass is unknown), in both planners
@example(
    vx=1.5,
    vy=0.5,
    yaw=-1.0,
    period=0.75,
    duty=0.375,
    step=0.0,
    roll=0.0,
    pitch=0.0625,
    rate=60.0,
    preset="trot",
)
def test_custom_gaits_commands_attitudes_and_rates_are_the_reference_plan(
    vx, vy, yaw, period, duty, step, roll, pitch, rate, preset
):
    robot = robot_named("go2")
    h = sk.motion.hip_height(robot)
    if preset == "walk":  # a static crawl needs a duty above 3/4
        duty = 0.76 + 0.2 * duty
    gait = sk.Gait(preset, period=period, duty=duty, step_height=step)
    assert_same_plan(robot, gait, [vx * h, vy * h, yaw], 2.5 * period, rate, attitude=(roll, pitch))


@pytest.mark.parametrize("lead", [(), (1,), (3, 1, 2), (0,)])
def test_commands_broadcast_and_each_plan_is_its_own_alone(lead):
    robot = robot_named("go2")
    rng = np.random.default_rng(len(lead))
    velocity = rng.uniform(-0.3, 0.3, (*lead, 3))
    plan = robot.plan_gait("trot", velocity=velocity, duration=0.6, rate=100.0)
    ticks = 61
    assert plan.t.shape == (ticks,)
    assert plan.body_pose.shape == (*lead, ticks, 6)
    assert plan.feet.shape == (*lead, ticks, 4, 3)
    assert plan.contact.shape == (*lead, ticks, 4) and plan.contact.dtype == bool
    assert plan.q.shape == plan.qd.shape == plan.tau.shape == (*lead, ticks, 12)
    assert plan.status.shape == plan.margin.shape == plan.shortened.shape == (*lead, ticks)
    assert plan.status.dtype == np.int8 and plan.residual.shape == (*lead, ticks, 6)
    for index in np.ndindex(*lead):
        one = robot.plan_gait("trot", velocity=velocity[index], duration=0.6, rate=100.0)
        for name in sk.GaitPlan._fields[1:]:
            assert np.array_equal(getattr(plan, name)[index], getattr(one, name), equal_nan=True), name


def test_the_plans_bits_do_not_depend_on_the_thread_count():
    robot = robot_named("spot")
    velocity = np.random.default_rng(7).uniform(-0.4, 0.4, (9, 3))
    before = sk.get_num_threads()
    try:
        plans = []
        for threads in (1, 2, 3):
            sk.set_num_threads(threads)
            plans.append(robot.plan_gait("walk", velocity=velocity, duration=1.0, rate=200.0))
    finally:
        sk.set_num_threads(before)
    for other in plans[1:]:
        for name in sk.GaitPlan._fields:
            assert np.array_equal(getattr(plans[0], name), getattr(other, name), equal_nan=True), name


def test_the_compiled_entry_point_checks_its_arrays():
    robot = robot_named("go2")
    numbers = gait_numbers(sk.Gait("trot").resolve(robot))
    statics = robot._statics
    ok = dict(gait=numbers, velocity=np.zeros((1, 3)), attitude=np.zeros(2), ticks=3, rate=100.0)
    _core.plan_gait(statics, **ok)
    for name, bad in (
        ("gait", numbers[:-1]),
        ("velocity", np.zeros((1, 2))),
        ("attitude", np.zeros(3)),
    ):
        with pytest.raises(ValueError, match=name):
            _core.plan_gait(statics, **{**ok, name: bad})
    with pytest.raises(ValueError, match="ticks"):
        _core.plan_gait(statics, **{**ok, "ticks": 0})
    with pytest.raises(ValueError, match="rate"):
        _core.plan_gait(statics, **{**ok, "rate": math.nan})
    period = numbers.copy()
    period[0] = -1.0
    with pytest.raises(ValueError, match="period"):
        _core.plan_gait(statics, **{**ok, "gait": period})


def test_float32_commands_give_a_float32_plan():
    robot = robot_named("go2")
    velocity = np.float32([[0.1, 0.0, 0.1]])
    plan = robot.plan_gait("trot", velocity=velocity, duration=0.2, rate=100.0)
    wide = robot.plan_gait("trot", velocity=velocity.astype(np.float64), duration=0.2, rate=100.0)
    for name in ("body_pose", "feet", "q", "qd", "tau", "margin", "residual"):
        assert getattr(plan, name).dtype == np.float32, name
        np.testing.assert_array_equal(getattr(plan, name), getattr(wide, name).astype(np.float32))
    assert plan.contact.dtype == bool and plan.status.dtype == np.int8


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_a_schedule_of_gaits_and_commands_is_the_reference_plan(name):
    """walk, then trot, a new command, then the pace with another: each change at the first tick at or
    after its time, as the reference plans it."""
    robot = robot_named(name)
    h = sk.motion.hip_height(robot)
    gaits = {preset: sk.Gait(preset) for preset in ("walk", "trot", "pace")}
    changes = [
        (2.6, gaits["pace"], [0.2 * h, 0.0, 0.0]),  # out of order: sorted by time, as the reference does
        (1.2, gaits["trot"], None),
        (2.0, None, [0.3 * h, 0.1 * h, 0.2]),
    ]
    plan = robot.plan_gait("walk", velocity=[0.2 * h, 0.0, 0.0], duration=3.5, rate=200.0, changes=changes)
    resolved = [(t, None if g is None else g.resolve(robot), v) for t, g, v in changes]
    ref = gait_plan.plan(
        robot, gaits["walk"].resolve(robot), [0.2 * h, 0.0, 0.0], 3.5, 200.0, changes=resolved
    )
    for field in gait_plan.OUTPUTS[1:]:
        got, want = getattr(plan, field), ref[field]
        if field in FLAGS:
            assert np.array_equal(got, want), field
        else:
            finite = np.isfinite(want)
            assert np.array_equal(finite, np.isfinite(got)), field
            np.testing.assert_allclose(got[finite], want[finite], rtol=1e-9, atol=1e-9 * robot.mass * 9.81)
    # the pace's two-foot support after its blend, the crawl's three before the trot
    assert plan.contact[plan.t < 1.2].sum(axis=-1).min() >= 3
    assert plan.contact[plan.t > 3.2].sum(axis=-1).min() <= 2


def test_a_bad_schedule_gets_a_clear_answer():
    robot = robot_named("go2")
    for changes, error, match in (
        (3, TypeError, "changes"),
        ([(1.0, "trot")], ValueError, r"changes\[0\]"),
        ([(np.nan, "trot", None)], ValueError, r"changes\[0\] time"),
        ([(1.0, "canter", None)], ValueError, "canter"),
        ([(1.0, 4, None)], TypeError, r"changes\[0\] gait"),
        ([(1.0, None, [0.1, 0.0])], ValueError, r"changes\[0\] velocity"),
        ([(1.0, None, [np.inf, 0.0, 0.0])], ValueError, r"changes\[0\] velocity"),
    ):
        with pytest.raises(error, match=match):
            robot.plan_gait("trot", duration=0.5, rate=50.0, changes=changes)
