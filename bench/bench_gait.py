"""Gait plans (issue 35 item 10), per robot-tick, one thread, in one run:

- the compiled planner (``Robot.plan_gait``: 64 commands x 1001 ticks at 500 Hz) against the pure-Python
  reference planner (``spotkin.reference.gait_plan.plan``, one command, fewer ticks: it is slow);
- against the batched ``body_ik`` alone on the plan's own poses and feet: unseeded, and seeded with
  the previous tick's q as the plan seeds it (the plan then adds its gait, joint velocities and
  statics to that IK).

Targets: compiled >= 50x the reference; the plan <= 2x the batched body_ik (speed-up >= 0.5x in the
summary, whose baseline here is the IK, "ref:")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import spotkin as sk
from conftest import _RESULTS, median_time
from spotkin.reference import gait_plan

COMMANDS, DURATION, RATE = 64, 2.0, 500.0
ROBOTS = {
    "spot": sk.Spot,
    "go2": lambda: sk.Robot.from_urdf(Path(sk.__file__).parent / "robots" / "go2.urdf"),
}


@pytest.mark.parametrize("gait", ["trot", "walk"])
@pytest.mark.parametrize("name", list(ROBOTS))
def test_plan_generation(name, gait, capsys):
    robot = ROBOTS[name]()
    h = sk.motion.hip_height(robot)
    velocity = np.random.default_rng(0).uniform(-0.5, 0.5, (COMMANDS, 3)) * [h, 0.5 * h, 1.0]
    ticks = round(DURATION * RATE) + 1
    n = COMMANDS * ticks
    threads = sk.get_num_threads()
    sk.set_num_threads(1)
    try:
        plan = robot.plan_gait(gait, velocity=velocity, duration=DURATION, rate=RATE)
        compiled = median_time(
            lambda: robot.plan_gait(gait, velocity=velocity, duration=DURATION, rate=RATE), 7
        )
        poses = plan.body_pose.reshape(-1, 6)
        feet = plan.feet.reshape(-1, 4, 3)
        seed = np.concatenate([plan.q[:, :1], plan.q[:, :-1]], axis=1).reshape(-1, 12)  # the previous tick's
        unseeded = median_time(lambda: robot.body_ik(poses, feet), 7)
        seeded = median_time(lambda: robot.body_ik(poses, feet, seed=seed), 7)
        resolved = sk.Gait(gait).resolve(robot)
        ref_ticks = 201
        reference = median_time(
            lambda: gait_plan.plan(robot, resolved, velocity[0], (ref_ticks - 1) / RATE, RATE), 3
        )
    finally:
        sk.set_num_threads(threads)
    per = {
        "spotkin-plan-1thread": compiled / n,
        "ref:body_ik-seeded-1thread": seeded / n,
        "ref:body_ik-1thread": unseeded / n,
        "reference-python": reference / ref_ticks,
    }
    op = f"{name}.plan_gait.{gait}"
    for impl, t in per.items():
        _RESULTS[(op, n)][impl] = t * n
    with capsys.disabled():
        print(
            f"\n{op}: plan {per['spotkin-plan-1thread'] * 1e9:.0f} ns/robot-tick; "
            f"reference / plan {per['reference-python'] / per['spotkin-plan-1thread']:.0f}x [>= 50x]; "
            f"plan / seeded body_ik {per['spotkin-plan-1thread'] / per['ref:body_ik-seeded-1thread']:.2f}x, "
            f"plan / unseeded body_ik {per['spotkin-plan-1thread'] / per['ref:body_ik-1thread']:.2f}x [<= 2x]"
        )
