"""An arm mounted on the body through fixed joints on an offset, rotated plate (tests/data's Go2 carrying a
Z1-like arm): ``robot.arm`` is expressed in the arm's base link, and every whole-body call composes
``robot.arm_mount``. Checked against Pinocchio's frame placements, centre of mass and dynamics on the
same file, with the body placed by hand (a fixed-base model) or as Pinocchio's free flyer."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

import spotkin as sk

pin = pytest.importorskip("pinocchio")
from urdf_helpers import pin_q  # noqa: E402

URDF = pathlib.Path(__file__).parent / "data" / "go2_z1_offset_mount.urdf"
ARM_BASE = "z1_link00"
HAND = "z1_gripper_link"


@pytest.fixture(scope="module")
def robot():
    return sk.Robot.from_urdf(URDF)


@pytest.fixture(scope="module")
def fixed():
    """Pinocchio's fixed-base model of the file: frames in the body (root link) frame."""
    model = pin.buildModelFromUrdf(str(URDF))
    return model, model.createData()


def _random_state(robot, rng, n):
    poses = np.c_[rng.uniform(-1, 1, (n, 3)), rng.uniform(-0.6, 0.6, (n, 3))]
    q_legs = np.concatenate([rng.uniform(*leg.limits.T, (n, 3)) for leg in robot.legs], axis=1)
    arm = robot.arm
    q_arm = rng.uniform(arm.lower, arm.upper, (n, 6))
    return poses, q_legs, q_arm


def _pin_frame(fixed, robot, q_legs, q_arm, frame):
    model, data = fixed
    names = (*robot.leg_joint_names, *robot.arm_joint_names)
    q = pin_q(model, dict(zip(names, np.r_[q_legs, q_arm])))
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[model.getFrameId(frame)].homogeneous


def test_the_mount_is_offset_and_rotated(robot, fixed):
    # the premise of this file: an arm whose base is not the body
    assert robot.arm is not None and robot.arm.joint_names[0] == "z1_joint1"
    mount = robot.arm_mount
    assert np.abs(mount[:3, 3]).max() > 0.05 and np.abs(mount[:3, :3] - np.eye(3)).max() > 0.1
    model, data = fixed
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    np.testing.assert_allclose(mount, data.oMf[model.getFrameId(ARM_BASE)].homogeneous, atol=1e-14)
    assert not mount.flags.writeable or robot.arm_mount is not mount  # callers cannot change it
    np.testing.assert_array_equal(sk.Spot().arm_mount, np.eye(4))  # Spot's arm hangs from the body
    assert len(robot.arm_mounts) == len(robot.arms) == 1
    np.testing.assert_array_equal(robot.arm_mounts[0], mount)


def test_fk_all_hand_matches_pinocchio(robot, fixed, rng):
    poses, q_legs, q_arm = _random_state(robot, rng, 12)
    frames = robot.fk_all(poses, q_legs, q_arm)
    T_wb = sk.body_transform(poses)
    worst = 0.0
    for k in range(len(poses)):
        hand = T_wb[k] @ _pin_frame(fixed, robot, q_legs[k], q_arm[k], HAND)
        worst = max(worst, np.abs(frames.hand[k] - hand).max())
        for i, spec in enumerate(robot._specs[0]):
            foot = T_wb[k] @ _pin_frame(fixed, robot, q_legs[k], q_arm[k], spec.foot)
            np.testing.assert_allclose(frames.feet[k, i], foot[:3, 3], atol=1e-12)
    assert worst < 1e-12
    # the chain alone is in the arm's base frame: composing the mount gives the body-frame hand
    body_hand = robot.arm_mount @ robot.arm.fk(q_arm[0])
    np.testing.assert_allclose(body_hand, _pin_frame(fixed, robot, q_legs[0], q_arm[0], HAND), atol=1e-12)


def test_arm_ik_world_reaches_valid_targets(robot, fixed, rng):
    """Every target made by a configuration inside the limits is reached: status OK and the hand, by
    Pinocchio's FK of the answer, on the target to 1e-9 (before the mount was composed, about a quarter
    came back OK, missing by up to 0.36 m)."""
    poses, q_legs, q_arm = _random_state(robot, rng, 40)
    T_wb = sk.body_transform(poses)
    targets = np.array(
        [T_wb[k] @ _pin_frame(fixed, robot, q_legs[k], q_arm[k], HAND) for k in range(len(poses))]
    )
    q, status = robot.arm_ik_world(poses, targets)
    assert (status == sk.Status.OK).all()
    for k in range(len(poses)):
        reached = T_wb[k] @ _pin_frame(fixed, robot, q_legs[k], q[k], HAND)
        np.testing.assert_allclose(reached, targets[k], atol=1e-9)
    # with the generating configuration as seed, it is the answer
    q_seeded, status = robot.arm_ik_world(poses, targets, seed=q_arm)
    assert (status == sk.Status.OK).all()
    np.testing.assert_allclose(q_seeded, q_arm, atol=1e-8)
    # float32 poses and targets: float32 answers, still on target to float32 precision
    q32, status32 = robot.arm_ik_world(poses.astype(np.float32), targets.astype(np.float32))
    assert q32.dtype == np.float32 and (status32 == sk.Status.OK).mean() > 0.9


def _free_flyer(robot):
    """Pinocchio's free-flyer model of the file and the index maps from robot.floating_q's coordinates."""
    model = pin.buildModelFromUrdf(str(URDF), pin.JointModelFreeFlyer())
    names = (*robot.leg_joint_names, *robot.arm_joint_names)
    jid = [model.getJointId(n) for n in names]
    iv = np.r_[np.arange(6), [model.idx_vs[i] for i in jid]]
    iq = np.r_[np.arange(7), [model.idx_qs[i] for i in jid]]
    return model, model.createData(), iq, iv


def test_center_of_mass_matches_pinocchio(robot, rng):
    # a free flyer: Pinocchio's fixed-base centre of mass leaves out the root link's mass
    model, data, iq, _ = _free_flyer(robot)
    poses, q_legs, q_arm = _random_state(robot, rng, 8)
    com = robot.center_of_mass(poses, np.c_[q_legs, q_arm])
    qf = robot.floating_q(poses, np.c_[q_legs, q_arm])
    for k in range(len(poses)):
        qp = np.zeros(model.nq)
        qp[iq] = qf[k]
        np.testing.assert_allclose(com[k], pin.centerOfMass(model, data, qp), atol=1e-12)
    np.testing.assert_allclose(robot.mass, sum(inertia.mass for inertia in model.inertias), rtol=1e-12)


def test_floating_base_dynamics_match_pinocchio(robot, rng):
    model, data, iq, iv = _free_flyer(robot)
    fb = robot.floating_base
    poses, q_legs, q_arm = _random_state(robot, rng, 5)
    qf = robot.floating_q(poses, np.c_[q_legs, q_arm])
    for k in range(len(poses)):
        qp = np.zeros(model.nq)
        qp[iq] = qf[k]
        v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
        vp, ap = np.zeros(model.nv), np.zeros(model.nv)
        vp[iv], ap[iv] = v, a
        np.testing.assert_allclose(
            fb.inverse_dynamics(qf[k], v, a), pin.rnea(model, data, qp, vp, ap)[iv], atol=1e-9
        )
        A = pin.crba(model, data, qp)
        A = np.triu(A) + np.triu(A, 1).T
        np.testing.assert_allclose(fb.mass_matrix(qf[k]), A[np.ix_(iv, iv)], atol=1e-10)


def test_standing_torques_hold_with_the_arm_out(robot, rng):
    """The statics see the arm where it is: the forces balance the weight about the centre of mass that
    Pinocchio computes (checked above), and the legs' torques change with the arm's pose."""
    feet = robot.stance_feet(0.3)
    pose = np.array([0.0, 0.0, 0.3, 0.0, 0.0, 0.0])
    q_legs = robot.body_ik(pose, feet).q
    a, b = np.zeros(6), np.array([0.5, 1.2, -1.0, 0.3, 0.2, 0.0])
    stand_a = robot.standing_torques(pose, np.r_[q_legs, a])
    stand_b = robot.standing_torques(pose, np.r_[q_legs, b])
    g = np.array([0.0, 0.0, -9.81])
    for stand, q_arm in ((stand_a, a), (stand_b, b)):
        com = robot.center_of_mass(pose, np.r_[q_legs, q_arm])
        np.testing.assert_allclose(stand.forces.sum(axis=0), -robot.mass * g, atol=1e-9)
        moment = np.cross(feet - com, stand.forces).sum(axis=0)
        np.testing.assert_allclose(moment, 0.0, atol=1e-9)
    assert np.abs(stand_a.tau - stand_b.tau).max() > 1e-3


def test_carried_arm_chain_from_the_body_equals_the_mount(robot, rng):
    """The same class of mistake elsewhere: a chain whose first joint's parent is not the root is
    expressed in its own base; robot.chain from the body composes the fixed joints in between."""
    q = rng.uniform(robot.arm.lower, robot.arm.upper, (6, 6))
    from_body = robot.chain(HAND)
    np.testing.assert_allclose(from_body.fk(q), robot.arm_mount @ robot.arm.fk(q), atol=1e-13)
    np.testing.assert_allclose(
        from_body.jacobian(q)[:, :3],
        np.einsum("ij,njk->nik", robot.arm_mount[:3, :3], robot.arm.jacobian(q)[:, :3]),
        atol=1e-12,
    )
