"""sk.GaitController without the simulator: its gains come from the robot's own inertias, a tick's
command holds the robot (the stance forces carry the weight), a batch of robots is each robot alone,
and bad input gets a clear answer. The walks themselves are in tests/test_walk.py."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

import spotkin as sk
from spotkin.motion import JointCommand, RobotState
from spotkin.motion import controller as ctl
from spotkin.reference import gait as ref

GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))


def standing(robot, **changes) -> RobotState:
    gait = sk.Gait("trot").resolve(robot)
    pose = np.array([0.0, 0.0, gait.height, 0.0, 0.0, 0.0])
    values = {
        "position": pose[:3],
        "quaternion": np.array([0.0, 0.0, 0.0, 1.0]),
        "linear_velocity": np.zeros(3),
        "angular_velocity": np.zeros(3),
        "q": robot.body_ik(pose, gait.stance).q,
        "qd": np.zeros(3 * robot.n_legs),
        "contact": np.ones(robot.n_legs, dtype=bool),
    }
    values.update(changes)
    return RobotState(**values)


@pytest.mark.parametrize("robot", [GO2, sk.Spot()], ids=["go2", "spot"])
def test_the_gains_come_from_the_legs_inertias(robot):
    controller = sk.GaitController(robot)
    gait = sk.Gait("trot").resolve(robot)
    pose = np.array([0.0, 0.0, gait.height, 0.0, 0.0, 0.0])
    A = robot.floating_base.mass_matrix(robot.floating_q(pose, robot.body_ik(pose, gait.stance).q))
    inertia = np.diag(A)[6 : 6 + 3 * robot.n_legs]
    for kappa, kp, kd in (
        (ctl.SWING_BANDWIDTH, controller.kp, controller.kd),
        (ctl.STANCE_BANDWIDTH, controller.stance_kp, controller.stance_kd),
    ):
        omega = kappa * math.sqrt(ref.G / gait.hip_height)
        np.testing.assert_allclose(kp, inertia * omega**2, rtol=1e-12)
        np.testing.assert_allclose(kd, 2.0 * ctl.DAMPING_RATIO * inertia * omega, rtol=1e-12)
    assert (controller.stance_kp < controller.kp).all()
    np.testing.assert_array_equal(
        controller.effort, [robot.model.joint(j.name).effort for j in _joints(robot)]
    )


def _joints(robot):
    actuated = robot.model.actuated_joints
    index = robot.q_from_names([j.name for j in actuated], np.arange(len(actuated), dtype=float))
    return [actuated[int(k)] for k in index]


def test_a_standing_tick_holds_the_robot():
    controller = sk.GaitController(GO2)
    state = standing(GO2)
    command = controller.step(0.0, state, velocity=(0.2, 0.0, 0.0))
    assert isinstance(command, JointCommand)
    assert command.q.shape == command.qd.shape == command.tau.shape == (12,)
    assert command.contact.tolist() == [True] * 4  # the start: every foot down while the body settles
    np.testing.assert_allclose(command.q, state.q, atol=1e-6)  # the reference is where the robot is
    last = controller.last
    weight = GO2.mass * ref.G
    total = last["forces"].sum(axis=0)  # the weight exactly; the horizontal rows of (T) are the softer
    np.testing.assert_allclose(total[2], weight, atol=1e-3 * weight)
    np.testing.assert_allclose(total[:2], 0.0, atol=1e-2 * weight)
    assert last["margin"] > 0 and last["status"] == 0 and not last["clipped"].any()
    # the feedforward: each leg's gravity torques less J^T f of its stance force
    pose = np.r_[state.position, state.quaternion]
    gravity = GO2.floating_base.gravity(GO2.floating_q(pose, state.q))[6:18]
    J = GO2.body_jacobian(pose, state.q)[:, 6:]
    np.testing.assert_allclose(command.tau, gravity - J.T @ last["forces"].ravel(), atol=1e-9)


def test_a_batch_of_robots_is_each_robot_alone():
    states = [standing(GO2, position=np.array([0.1 * k, 0.0, 0.3408])) for k in range(3)]
    batch = RobotState(
        *(
            np.stack([getattr(s, f) for s in states])
            for f in ("position", "quaternion", "linear_velocity", "angular_velocity", "q", "qd", "contact")
        )
    )
    velocity = np.array([[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.3]])
    together = sk.GaitController(GO2)
    alone = [sk.GaitController(GO2) for _ in range(3)]
    for tick in range(40):
        t = tick / 500
        command = together.step(t, batch, velocity)
        for k in range(3):
            single = alone[k].step(t, states[k], velocity[k])
            np.testing.assert_array_equal(command.q[k], single.q)
            np.testing.assert_array_equal(command.tau[k], single.tau)
    assert command.q.shape == (3, 12) and command.contact.shape == (3, 4)
    assert len(together.last) == 3
    with pytest.raises(ValueError, match="reset"):
        together.step(1.0, states[0])
    together.reset()
    assert together.last is None
    together.step(1.0, states[0])


def test_bad_input_gets_a_clear_answer():
    controller = sk.GaitController(GO2)
    state = standing(GO2)
    with pytest.raises(ValueError, match="q must be finite"):
        controller.step(0.0, standing(GO2, q=np.full(12, np.nan)))
    with pytest.raises(ValueError, match="velocity must be finite"):
        controller.step(0.0, state, velocity=(np.nan, 0.0, 0.0))
    with pytest.raises(ValueError, match="velocity"):
        controller.step(0.0, state, velocity=(0.1, 0.0))
    with pytest.raises(ValueError, match="12 joints"):
        controller.step(0.0, standing(GO2, q=np.zeros(9), qd=np.zeros(9)))
    with pytest.raises(
        ValueError, match=r"q and qd must have the same width .* got q \(11,\) and qd \(12,\)"
    ):
        standing(GO2, q=np.zeros(11))  # the state names the field that differs, not qd alone
    with pytest.raises(TypeError, match="RobotState"):
        controller.step(0.0, np.zeros(12))
    with pytest.raises(ValueError, match="quaternion"):
        controller.step(0.0, standing(GO2, quaternion=np.zeros(4)))
    controller.step(1.0, state)
    with pytest.raises(ValueError, match="backwards"):
        controller.step(0.5, state)
    with pytest.raises(ValueError, match="unknown gait"):
        controller.step(1.1, state, gait="canter")
    with pytest.raises(ValueError, match="quadrupeds"):
        sk.GaitController(sk.Robot.from_urdf_string(_biped()))
    with pytest.raises(TypeError, match=r"spotkin\.Robot"):
        sk.GaitController(GO2.legs[0])
    with pytest.raises(ValueError, match="rate"):
        sk.GaitController(GO2, rate=-1.0)
    with pytest.raises(ValueError, match="attitude"):
        sk.GaitController(GO2, attitude=(np.nan, 0.0))


def _biped() -> str:
    from urdf_helpers import quadruped_urdf

    return quadruped_urdf(0.1, 2.0, 3.0, legs=2)


def test_a_tick_costs_under_two_milliseconds():
    """The controller's cost per tick, one robot from Python (the figure the docs quote, with room for a
    slow machine): a second of walking at 500 Hz, the robot following the plan exactly."""
    controller = sk.GaitController(GO2)
    state = standing(GO2)
    command = controller.step(0.0, state, velocity=(0.2, 0.0, 0.0))
    start = time.perf_counter()
    for tick in range(1, 501):  # the robot at its last targets
        command = controller.step(tick / 500, state.replace(q=command.q), velocity=(0.2, 0.0, 0.0))
    cost = (time.perf_counter() - start) / 500
    assert np.isfinite(command.tau).all()
    assert cost < 2e-3, f"{1e3 * cost:.2f} ms per tick"


def _legs_at(robot, pose, feet):
    q = robot.body_ik(pose, feet).q
    names = list(robot.leg_joint_names)
    cols = [[names.index(j) for j in leg.joint_names] for leg in robot.legs]
    J = robot.body_jacobian(pose, q)[:, 6:]
    jac = [J[3 * i : 3 * i + 3][:, c] for i, c in enumerate(cols)]
    gravity = robot.floating_base.gravity(robot.floating_q(pose, q))[6 : 6 + 3 * robot.n_legs]
    return q, cols, jac, [gravity[c] for c in cols]


def _spot_in_a_stride(first: float, second: float):
    """Spot standing at its trot's height, the left-front and left-hind feet ``first`` m forward of
    their nominal place, the others ``second``: (robot, gait, feet, each leg's Jacobian, gravity
    torques, the centre of mass)."""
    spot = sk.Spot()
    gait = sk.Gait("trot").resolve(spot)
    pose = np.array([0.0, 0.0, gait.height, 0.0, 0.0, 0.0])
    feet = gait.stance + np.array([[first, 0, 0], [second, 0, 0], [first, 0, 0], [second, 0, 0]])
    q, _, jac, gravity = _legs_at(spot, pose, feet)
    return spot, gait, feet, jac, gravity, spot.center_of_mass(pose, q)


def test_the_stance_forces_carry_a_wrench_and_the_torque_weighted_ones_spare_the_motors():
    """(W) with a wrench: the feet carry the weight plus the wrench's force exactly, its moment in the
    least-squares sense. (T): with three feet or more the same wrench (vertical force and moments
    exactly), the joints further from their limits than (W)'s, with the feet displaced as in a stride."""
    spot, gait, feet, jac, gravity, com = _spot_in_a_stride(0.12, -0.12)
    wrench = np.array([10.0, -5.0, 20.0, 1.0, 2.0, -0.5])
    down = np.ones(4, dtype=bool)
    forces, residual = ref.stance_forces(feet, down, com, spot.mass, (0, 0, -ref.G), wrench)
    np.testing.assert_allclose(forces.sum(axis=0), [10.0, -5.0, 20.0 + spot.mass * ref.G], atol=1e-9)
    np.testing.assert_allclose(residual, 0.0, atol=1e-8)  # four feet: every moment balances
    limits = [[45.0, 45.0, 115.0]] * 4
    weighted, rest = ref.torque_weighted_forces(
        feet, down, com, spot.mass, jac, gravity, limits, gait.hip_height, wrench
    )
    assert abs(rest[2]) < 1e-3 * spot.mass * ref.G and np.abs(rest[3:]).max() < 1e-2 * spot.mass * ref.G
    assert np.abs(rest[:2]).max() < 0.1 * spot.mass * ref.G  # the softer horizontal rows

    def worst(f):
        return max(np.abs((gravity[i] - jac[i].T @ f[i]) / limits[i]).max() for i in range(4))

    assert worst(weighted) < worst(forces)
    # a foot that would have to pull is unloaded
    two = np.array([True, False, False, True])
    weighted, _ = ref.torque_weighted_forces(feet, two, com, spot.mass, jac, gravity, limits, gait.hip_height)
    assert (weighted[~two] == 0).all() and (weighted[two, 2] > 0).all()


def test_the_torque_weighted_forces_hold_a_joint_at_its_cap_and_give_the_wrench_way(monkeypatch):
    """(T) with two diagonal feet displaced as in a fast stride, hip-pitch motors too weak for the
    wrench asked (12 N m) and a forward push: unheld, both hip-pitch joints pass their limits; held,
    they stop at TORQUE_CAP of it, the weight and the moments are still carried, and the horizontal
    force gives way (the residual says by how much)."""
    spot, gait, feet, jac, gravity, com = _spot_in_a_stride(0.15, -0.10)
    two = np.array([True, False, False, True])
    limits = np.array([[45.0, 12.0, 115.0]] * 4)
    wrench = np.array([100.0, 0.0, 0.0, 0.0, 0.0, 0.0])

    def load(f):  # |tau / tau_max| of the loaded legs
        return np.array([np.abs((gravity[i] - jac[i].T @ f[i]) / limits[i]) for i in np.flatnonzero(two)])

    args = (feet, two, com, spot.mass, jac, gravity, limits, gait.hip_height, wrench)
    held, rest = ref.torque_weighted_forces(*args)
    monkeypatch.setattr(ref, "TORQUE_CAP_ROUNDS", 0)
    free, free_rest = ref.torque_weighted_forces(*args)
    assert (load(free)[:, 1] > 1.0).all()  # past the limits
    np.testing.assert_allclose(load(held)[:, 1], ref.TORQUE_CAP, atol=5e-3)
    assert load(held).max() <= ref.TORQUE_CAP + 5e-3
    weight = spot.mass * ref.G
    # the vertical force and the moments as well carried as without the cap (two feet leave a little)
    np.testing.assert_allclose(rest[2:], free_rest[2:], atol=1e-3 * weight)
    assert abs(rest[0]) > abs(free_rest[0]) + 0.01 * weight  # the push gives way
    assert (held[two, 2] > 0).all() and (held[~two] == 0).all()


def test_a_velocity_beyond_float64_says_so():
    controller = sk.GaitController(GO2, "trot")
    with pytest.raises(ValueError, match="velocity holds an integer too large for float64"):
        controller.step(0.0, standing(GO2), (10**400, 0, 0))
