"""Whole-body reach (issue 36 item 8), per target, one thread, in one run, against mink (a QP over
MuJoCo: the hand's pose task and each foot's position task, its configuration limits, daqp) on the
same targets, from the same nominal stance:

- mink's time to converge: until the hand is within 1e-6 m and 1e-6 rad of the target and every foot
  within 1e-6 m of its own (at most ``MINK_ITERATIONS`` steps; a target that does not converge counts
  the time it took to give up); its mean and its median over the targets;
- spotkin's batched reach (every target in one call), and a single reach call from Python.

Targets: batched at least 100x faster per target than mink's time to converge, a single call at least
30x. The targets are made from random feasible configurations (``spotkin.reference.reach.
feasible_samples``): a body pose in the box, the arm's joints in their limits, no collision, the centre
of mass inside the feet. mink solves a simpler problem (no margin, no collision, no box, the nearest
local answer), and gives no branches.

Needs ``mink`` (``pip install mink daqp``); skipped without it."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk
from conftest import _RESULTS, median_time
from spotkin.motion import reach as reach_module
from spotkin.reference import reach as ref

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from urdf_helpers import robot_named  # the tests' robots: Go2 carrying a Z1-like arm

TARGETS, SINGLES, MINK_TARGETS, MINK_ITERATIONS = 500, 100, 60, 100
TOLERANCE = 1e-6


class MinkReach:
    """mink on the robot's own MuJoCo model (:func:`spotkin.sim.mujoco_model`'s MJCF, with a site at
    the hand frame): the hand's frame task, a position task per foot geom, configuration limits."""

    def __init__(self, robot) -> None:
        mink = pytest.importorskip("mink")
        pytest.importorskip("daqp")
        import mujoco

        from spotkin.sim.model import _quat, _Tree, _v, layout

        self.mink, lay, tree = mink, layout(robot), _Tree(robot)
        tip = robot._specs[1][0].tip
        owner, placement = tree.owner[tip], tree.relative[tip]
        lines = lay.xml.split("\n")
        at = next(i for i, line in enumerate(lines) if line.strip().startswith(f'<body name="{owner}"'))
        site = f'<site name="hand" pos="{_v(placement[:3, 3])}" quat="{_v(_quat(placement[:3, :3]))}"/>'
        lines.insert(at + 1, site)
        self.model = mujoco.MjModel.from_xml_string("\n".join(lines))
        self.configuration = mink.Configuration(self.model)
        self.hand = mink.FrameTask("hand", "site", position_cost=1.0, orientation_cost=1.0)
        self.feet = [
            mink.FrameTask(g, "geom", position_cost=10.0, orientation_cost=0.0) for g in lay.foot_geoms
        ]
        self.limits = [mink.ConfigurationLimit(self.model)]
        h0, _, feet = reach_module._scales(robot)
        q_legs = np.asarray(robot.body_ik([0.0, 0.0, h0, 0.0, 0.0, 0.0], feet).q)
        arm = robot.limits[3 * robot.n_legs :]
        q_arm = np.clip(np.zeros(len(arm)), arm[:, 0], arm[:, 1])
        self.start = self.model.qpos0.copy()
        self.start[:7] = [0.0, 0.0, h0, 1.0, 0.0, 0.0, 0.0]
        for name, value in zip(lay.leg_joints + lay.arm_joints, np.concatenate([q_legs, q_arm])):
            self.start[self.model.joint(name).qposadr[0]] = value
        self.configuration.update(self.start)
        for task in self.feet:
            task.set_target_from_configuration(self.configuration)

    def solve(self, T) -> tuple[bool, int]:
        mink, conf = self.mink, self.configuration
        conf.update(self.start)
        self.hand.set_target(mink.SE3.from_matrix(T))
        tasks = [self.hand, *self.feet]
        for step in range(1, MINK_ITERATIONS + 1):
            velocity = mink.solve_ik(conf, tasks, 0.01, solver="daqp", damping=1e-6, limits=self.limits)
            conf.integrate_inplace(velocity, 0.01)
            e = self.hand.compute_error(conf)
            feet = max(np.linalg.norm(task.compute_error(conf)[:3]) for task in self.feet)
            if np.linalg.norm(e[:3]) < TOLERANCE and np.linalg.norm(e[3:]) < TOLERANCE and feet < TOLERANCE:
                return True, step
        return False, MINK_ITERATIONS


@pytest.mark.parametrize("name", ["spot", "go2_z1", "heavy_ur5"])
def test_reach_against_mink(name, capsys):
    robot = robot_named(name)
    problem = reach_module.reference_problem(robot, np.eye(4))
    T, _, _ = ref.feasible_samples(problem, TARGETS, seed=1)
    mink = MinkReach(robot)
    times, converged = [], 0
    for k in range(MINK_TARGETS):
        start = time.perf_counter()
        ok, _ = mink.solve(T[k])
        times.append(time.perf_counter() - start)
        converged += ok
    mink_mean, mink_median = float(np.mean(times)), float(np.median(times))
    threads = sk.get_num_threads()
    sk.set_num_threads(1)
    try:
        result = robot.reach(T)
        batched = median_time(lambda: robot.reach(T), 15) / TARGETS
        singles = []
        for k in range(SINGLES):
            target = T[k]
            singles.append(median_time(lambda target=target: robot.reach(target), 3))
        single = float(np.median(singles))
    finally:
        sk.set_num_threads(threads)
    solved = float(np.mean(result.status == sk.ReachStatus.OK))
    op = f"{name}.reach"
    _RESULTS[(op, TARGETS)].update(
        {"spotkin-batched-1thread": batched * TARGETS, "ref:mink-mean": mink_mean * TARGETS}
    )
    _RESULTS[(f"{name}.reach.single", 1)].update({"spotkin-single": single, "ref:mink-mean": mink_mean})
    with capsys.disabled():
        print(
            f"\n{op}: spotkin solves {solved:.1%} of {TARGETS} feasible targets; mink converges on "
            f"{converged}/{MINK_TARGETS} (mean {mink_mean * 1e3:.2f} ms, median {mink_median * 1e3:.2f} ms); "
            f"batched {batched * 1e6:.1f} us/target: {mink_mean / batched:.0f}x mink's mean, "
            f"{mink_median / batched:.0f}x its median [>= 100x]; single call {single * 1e6:.1f} us: "
            f"{mink_mean / single:.0f}x mean, {mink_median / single:.0f}x median [>= 30x]"
        )
