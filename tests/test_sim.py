"""spotkin.sim: the MuJoCo model built from a robot's description (masses, limits, efforts, feet, FK),
the runner (a standing PD holds every robot on flat ground and on a slope, a push moves it), the
terrains, and clear answers to bad input."""

from __future__ import annotations

import math
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest

import spotkin as sk

mujoco = pytest.importorskip("mujoco")
sim = pytest.importorskip("spotkin.sim")
from urdf_helpers import quadruped_urdf  # noqa: E402

from spotkin.motion import JointCommand  # noqa: E402

ROBOTS = {
    "spot": sk.Spot,
    "go2": lambda: sk.Robot.from_urdf(sk.robots.path("go2")),
    "small": lambda: sk.Robot.from_urdf_string(quadruped_urdf(0.1, 2.0, 3.0)),  # 2 kg
    "large": lambda: sk.Robot.from_urdf_string(quadruped_urdf(0.4, 90.0, 200.0)),  # 90 kg
}


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request):
    return ROBOTS[request.param]()


def _id(model, kind, name: str) -> int:
    found = mujoco.mj_name2id(model, kind, name)
    assert found >= 0, name
    return found


def _urdf_joint(robot, name: str):
    """The URDF joint answering to a name of ``robot.leg_joint_names`` or ``arm_joint_names`` (Spot's
    "fl.hx" is the URDF's "front_left_hip_x"; other robots use the URDF's names)."""
    actuated = robot.model.actuated_joints
    slots = np.arange(len(actuated), dtype=float)
    return actuated[int(robot.q_from_names([j.name for j in actuated], slots, joints=[name])[0])]


def test_spots_joints_are_its_urdf_joints():
    assert _urdf_joint(sk.Spot(), "fl.hx").name == "front_left_hip_x"
    assert _urdf_joint(sk.Spot(), "arm0.el0").name == "arm_el0"


# ------------------------------------------------------------------ the model


def test_the_model_has_the_urdf_masses_limits_and_efforts(robot):
    model = sim.mujoco_model(robot)
    assert model.body_subtreemass[1] == pytest.approx(robot.mass, rel=1e-5)
    names = [*robot.leg_joint_names, *robot.arm_joint_names]
    assert model.nu == len(names)
    for k, name in enumerate(names):
        joint = _urdf_joint(robot, name)
        j = _id(model, mujoco.mjtObj.mjOBJ_JOINT, joint.name)
        assert model.actuator_trnid[k, 0] == j  # the motors in leg_joint_names then arm_joint_names order
        assert model.jnt_limited[j]
        np.testing.assert_allclose(model.jnt_range[j], [joint.lower, joint.upper], rtol=1e-12)
        assert model.actuator_ctrllimited[k]
        np.testing.assert_allclose(model.actuator_ctrlrange[k], [-joint.effort, joint.effort], rtol=1e-12)
    assert model.nq == 7 + len(names)  # a free joint, then the legs' and the arm's joints only
    robot_geoms = model.geom_bodyid > 0
    assert (model.geom_contype[robot_geoms] == 1).all() and (model.geom_conaffinity[robot_geoms] == 0).all()
    assert (model.geom_contype[~robot_geoms] == 0).all() and (model.geom_conaffinity[~robot_geoms] == 1).all()


def test_the_foot_spheres_follow_spotkins_fk(robot):
    model = sim.mujoco_model(robot)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    limits = np.array([leg.limits for leg in robot.legs]).reshape(-1, 2)
    feet = [_id(model, mujoco.mjtObj.mjOBJ_GEOM, f"foot_{name}") for name in robot.leg_names]
    for _ in range(5):
        pose = np.r_[rng.uniform(-0.3, 0.3, 3), rng.uniform(-0.5, 0.5, 3)]
        q = rng.uniform(np.maximum(limits[:, 0], -3.0), np.minimum(limits[:, 1], 3.0))
        T = sk.body_transform(pose)
        data.qpos[:3] = T[:3, 3]
        mujoco.mju_mat2Quat(data.qpos[3:7], T[:3, :3].ravel().copy())
        for name, value in zip(robot.leg_joint_names, q):
            data.qpos[
                model.jnt_qposadr[_id(model, mujoco.mjtObj.mjOBJ_JOINT, _urdf_joint(robot, name).name)]
            ] = value
        mujoco.mj_kinematics(model, data)
        np.testing.assert_allclose(data.geom_xpos[feet], robot.body_fk(pose, q), atol=1e-12)


def test_joints_listed_joint_kind_by_joint_kind_are_placed_right():
    """A URDF listing every hip roll, then every hip pitch, then every knee: the whole-body q is not
    leg by leg, the model still is."""
    text = quadruped_urdf(0.4, 90.0, 200.0)
    joints = re.findall(r"<joint name=.*?</joint>", text)
    moving = sorted((j for j in joints if "revolute" in j), key=lambda j: ("_roll" not in j, "_knee" in j))
    for j in joints:
        text = text.replace(j, "")
    text = text.replace("</robot>", "".join(moving + [j for j in joints if j not in moving]) + "</robot>")
    robot = sk.Robot.from_urdf_string(text)
    assert robot.leg_joint_names[:4] == ("fl_roll", "fr_roll", "hl_roll", "hr_roll")
    test_the_foot_spheres_follow_spotkins_fk(robot)
    test_the_model_has_the_urdf_masses_limits_and_efforts(robot)


def test_the_sizes_scale_with_the_robot():
    spot, go2 = sk.Spot(), sk.Robot.from_urdf(sk.robots.path("go2"))
    # one h for the simulator and the gaits: the most stretched leg at 0.8 of its reach
    assert sim.hip_height(spot) == pytest.approx(0.5264, abs=1e-3)
    assert sim.hip_height(go2) == pytest.approx(0.8 * 0.426)
    for robot in (spot, go2):
        assert sim.hip_height(robot) == sk.Gait("trot").resolve(robot).hip_height
    assert sim.foot_radius(spot) == 0.036  # Spot's own
    assert sim.foot_radius(go2) == pytest.approx(0.05 * 0.426)  # the default: 5 % of the reach
    text = quadruped_urdf(0.1, 2.0, 3.0, foot_sphere=0.012)
    assert sk.urdf.parse_urdf(text).link("fl_foot").spheres == (((0.0, 0.0, 0.0), 0.012),)
    with_sphere = sk.Robot.from_urdf_string(text)
    assert sim.foot_radius(with_sphere) == 0.012  # the URDF's collision sphere
    model = sim.mujoco_model(with_sphere, foot_radius=0.02)
    assert model.geom_size[_id(model, mujoco.mjtObj.mjOBJ_GEOM, "foot_fl"), 0] == 0.02


# ------------------------------------------------------------------ the runner


class Stand:
    """Hold the initial joints: PD gains from the robot's weight and leg length, the legs' standing
    torques (gravity and the weight on the feet) as feedforward."""

    def __init__(self, robot, feedforward: bool = True) -> None:
        self.robot, self.feedforward, self.command = robot, feedforward, None

    def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
        if self.command is None:
            robot, n = self.robot, len(state.q)
            reach = min(leg.reach[1] for leg in robot.legs)
            kp = np.full(n, 0.5 * robot.mass * 9.81 * reach)
            kd = 0.1 * kp * math.sqrt(reach / 9.81)
            pose = np.r_[state.position, state.quaternion]
            tau = robot.standing_torques(pose, state.q).tau if self.feedforward else np.zeros(n)
            self.command = JointCommand(state.q.copy(), np.zeros(n), tau, kp, kd, np.ones(robot.n_legs, bool))
        return self.command


@pytest.mark.parametrize("terrain", [None, sim.Slope(10.0)], ids=["flat", "slope"])
def test_a_standing_pd_holds_the_robot(robot, terrain):
    result = sim.run(robot, Stand(robot), duration=3.0, terrain=terrain)
    metrics = result.metrics
    assert not metrics.fell, str(metrics)
    assert metrics.lowest_height > 0.9 * metrics.initial_height, str(metrics)
    assert metrics.torque_within >= 0.99, str(metrics)
    assert metrics.distance < 0.05 * metrics.initial_height
    assert result.contact[-1].all()  # every foot on the ground
    assert result.q.shape == (1500, 3 * robot.n_legs) and result.t[-1] == pytest.approx(3.0 - 1 / 500)
    assert np.abs(result.tau).max() > 0
    np.testing.assert_allclose(np.linalg.norm(result.quaternion, axis=1), 1.0)
    assert "no fall" in str(metrics) and "of ticks" in str(metrics)


def test_a_push_moves_the_body():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    calm = sim.run(go2, Stand(go2), duration=1.0)
    pushed = sim.run(go2, Stand(go2), duration=1.0, pushes=[(0.5, (0.0, 0.4, 0.0))])
    after = pushed.t > 0.5
    assert pushed.linear_velocity[after, 1].max() > 0.2  # the kick, in world axes
    assert np.abs(calm.linear_velocity[:, 1]).max() < 0.01
    assert np.abs(pushed.position[:, 1] - pushed.position[0, 1]).max() > 0.005
    np.testing.assert_array_equal(calm.position[~after], pushed.position[~after])  # deterministic


def test_a_limp_robot_falls():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))

    class Limp(Stand):
        def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
            c = super().step(t, state, velocity)
            return JointCommand(c.q, c.qd, 0 * c.tau, 0 * c.kp, 0.05 * c.kd, c.contact)

    metrics = sim.run(go2, Limp(go2), duration=1.0).metrics
    assert metrics.fell and 0.0 < metrics.fall_time < 0.5
    assert metrics.fall_cause == "the body below 60% of its initial height"
    assert "FELL at" in str(metrics)


def test_the_command_is_ramped_and_recorded():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    seen = []

    class Recorder(Stand):
        def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
            seen.append((t, np.array(velocity), state))
            return super().step(t, state, velocity)

    result = sim.run(go2, Recorder(go2), duration=0.2, rate=100, ramp=0.1, velocity=lambda t: (0.2, 0.0, t))
    assert len(seen) == 20
    t, v, state = seen[5]
    np.testing.assert_allclose(v, 0.5 * np.array([0.2, 0.0, t]))
    np.testing.assert_allclose(result.command[15], [0.2, 0.0, result.t[15]])
    assert state.contact.shape == (4,) and state.q.shape == (12,)
    assert state.quaternion[3] == pytest.approx(1.0, abs=1e-3)  # (x, y, z, w): level, w last
    bare = sim.run(go2, Stand(go2), duration=0.1, record=False)
    assert bare.t is None and bare.metrics.torque_within == 1.0
    assert "no record" in repr(bare)


def test_the_metrics_read_a_walk():
    from spotkin.sim.runner import _metrics

    t = np.arange(0.0, 10.0, 0.002)
    yaw = 0.01 * t  # turning slowly left
    rec = {
        "t": t,
        "position": np.stack([0.5 * t, 0.005 * t, np.full_like(t, 0.3)], axis=1),
        "quaternion": np.stack([0 * t, 0 * t, np.sin(yaw / 2), np.cos(yaw / 2)], axis=1),
        "linear_velocity": np.tile([0.5, 0.005, 0.0], (len(t), 1)),
        "angular_velocity": np.tile([0.0, 0.0, 0.01], (len(t), 1)),
        "within": np.r_[np.ones(len(t) - 10, bool), np.zeros(10, bool)],
        "command": np.tile([0.5, 0.0, 0.0], (len(t), 1)),
    }
    m = _metrics(rec, np.zeros(len(t), bool), sim.Flat(), 0.3, 1e-5, 10.0)
    assert m.distance == pytest.approx(np.hypot(5.0, 0.05), rel=1e-3)
    assert m.lateral_drift == pytest.approx(0.01, rel=1e-2)
    assert m.heading_change == pytest.approx(0.1, rel=1e-2)
    heading = 0.01 * t[t >= 2.0]  # the body-frame velocity, over the last 8 s
    assert m.velocity[0] == pytest.approx(np.mean(0.5 * np.cos(heading) + 0.005 * np.sin(heading)))
    assert m.velocity[2] == pytest.approx(0.01)
    assert m.torque_within == pytest.approx(1 - 10 / len(t))
    assert not m.fell and m.lowest_height == pytest.approx(0.3)
    assert "drift 1.0%" in str(m) and "10 µs/tick" in str(m)


# ------------------------------------------------------------------ terrains


def _ground(model, x: float, y: float) -> float:
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    hit = np.zeros(1, np.int32)
    terrain = np.array([0, 0, 0, 1, 0, 0], np.uint8)  # the terrain's geoms are in group 3
    return 5.0 - mujoco.mj_ray(
        model, data, np.array([x, y, 5.0]), np.array([0.0, 0.0, -1.0]), terrain, 1, -1, hit
    )


def test_the_terrains_have_the_right_heights():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    slope = sim.Slope(10.0)
    assert slope.height_at(1.0, 0.3) == pytest.approx(math.tan(math.radians(10.0)))
    assert slope.slope == pytest.approx(math.radians(10.0))
    assert _ground(sim.mujoco_model(go2, terrain=slope), 1.0, 0.3) == pytest.approx(
        math.tan(math.radians(10))
    )
    step = sim.Step(0.05, 0.5, length=0.4)
    np.testing.assert_array_equal(step.height_at([0.4, 0.6, 0.85, 1.0], 0.0), [0.0, 0.05, 0.05, 0.0])
    model = sim.mujoco_model(go2, terrain=step)
    assert [_ground(model, x, 0.1) for x in (0.4, 0.6, 1.0)] == pytest.approx([0.0, 0.05, 0.0])
    bumps = sim.Bumps(0.02, seed=4, spacing=0.2, size=3.0)
    grid = bumps.grid()
    assert np.abs(grid).max() <= 0.02 and grid.max() - grid.min() > 0.02
    np.testing.assert_array_equal(grid, sim.Bumps(0.02, seed=4, spacing=0.2, size=3.0).grid())
    assert not np.array_equal(grid, sim.Bumps(0.02, seed=5, spacing=0.2, size=3.0).grid())
    model = sim.mujoco_model(go2, terrain=bumps)
    points = np.random.default_rng(1).uniform(-1.4, 1.4, size=(20, 2))
    expected = bumps.height_at(points[:, 0], points[:, 1])
    assert [_ground(model, x, y) for x, y in points] == pytest.approx(expected, abs=1e-6)
    assert "flat" and sim.mjcf(go2, terrain="flat") == sim.mjcf(go2)


def test_the_robot_stands_on_every_terrain():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    h = sim.hip_height(go2)
    for terrain in (sim.Step(0.1 * h, 0.5), sim.Bumps(0.05 * h, spacing=0.15, size=3.0)):
        metrics = sim.run(go2, Stand(go2), duration=1.0, terrain=terrain).metrics
        assert not metrics.fell and metrics.lowest_height > 0.9 * metrics.initial_height, str(metrics)


# ------------------------------------------------------------------ bad input


def test_a_robot_that_is_not_a_quadruped_is_refused():
    arm = sk.Chain.from_urdf(sk.robots.path("ur5"))
    with pytest.raises(ValueError, match=r"legged robots.*got Chain"):
        sim.mjcf(arm)
    with pytest.raises(ValueError, match="no roll-pitch-pitch legs"):  # an arm's URDF is no Robot
        sk.Robot.from_urdf(sk.robots.path("ur5"))
    biped = sk.Robot.from_urdf_string(quadruped_urdf(0.1, 2.0, 3.0, legs=2))
    with pytest.raises(ValueError, match="quadrupeds: this robot has 2 legs"):
        sim.mujoco_model(biped)
    with pytest.raises(ValueError, match="quadrupeds"):
        sim.run(biped, Stand(biped), duration=0.1)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda c: JointCommand(c.q[:-1], c.qd, c.tau, c.kp, c.kd, c.contact),
            r"command q must have shape \(12,\)",
        ),
        (
            lambda c: JointCommand(c.q, c.qd, c.tau[None], c.kp, c.kd, c.contact),
            r"command tau must have shape",
        ),
        (
            lambda c: JointCommand(c.q, c.qd * np.nan, c.tau, c.kp, c.kd, c.contact),
            "command qd is not finite",
        ),
        (lambda c: JointCommand(c.q, c.qd, c.tau, -c.kp, c.kd, c.contact), "command kp must be >= 0"),
        (lambda c: (c.q, c.qd), "must return a spotkin.motion.JointCommand"),
    ],
    ids=["short q", "tau (1, 12)", "NaN qd", "negative kp", "a tuple"],
)
def test_a_bad_command_is_named(change, message):
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))

    class Bad(Stand):
        def step(self, t, state, velocity=(0.0, 0.0, 0.0)):
            return change(super().step(t, state, velocity))

    with pytest.raises(ValueError, match=message):
        sim.run(go2, Bad(go2), duration=0.05)


def test_bad_arguments_are_named():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    stand = Stand(go2)
    with pytest.raises(ValueError, match="velocity must be 3 finite numbers"):
        sim.run(go2, stand, duration=0.05, velocity=(0.1, 0.0))
    with pytest.raises(ValueError, match=r"rate .* must divide the physics rate"):
        sim.run(go2, stand, duration=0.05, rate=300)
    with pytest.raises(ValueError, match=r"pushes\[0\]"):
        sim.run(go2, stand, duration=0.05, pushes=[(0.1, (1.0, 0.0))])
    with pytest.raises(ValueError, match="terrain must be"):
        sim.mjcf(go2, terrain="hilly")
    with pytest.raises(ValueError, match="friction must be"):
        sim.mjcf(go2, friction=0.0)
    with pytest.raises(ValueError, match="Slope degrees"):
        sim.Slope(60.0)
    with pytest.raises(ValueError, match="Step height"):
        sim.Step(-0.1, 0.5)
    with pytest.raises(ValueError, match="Bumps amplitude"):
        sim.Bumps(0.0)
    with pytest.raises(TypeError, match="step"):
        sim.run(go2, object(), duration=0.05)


def test_without_mujoco_the_import_says_what_to_install():
    code = (
        "import sys\n"
        "import spotkin\n"
        "assert 'mujoco' not in sys.modules, 'import spotkin imported mujoco'\n"
        "sys.modules['mujoco'] = None\n"
        "try:\n"
        "    import spotkin.sim\n"
        "except ImportError as error:\n"
        "    print(error)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert 'pip install "spotkin[sim]"' in run.stdout


def test_a_run_of_one_tick_has_its_metrics_without_a_warning():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = sim.run(go2, sk.GaitController(go2), duration=0.002)
    assert len(result.t) == 1 and np.isfinite(result.metrics.velocity).all()
