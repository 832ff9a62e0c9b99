"""Standing statics (Robot.standing_torques, C++ spotkin/dynamics/statics.hpp) against the pure-Python
reference (spotkin.reference.dynamics.standing_torques, itself checked against Pinocchio's foot Jacobians
in test_reference_dynamics.py), the balance it promises, batches and bad input; the floating-base
coordinates (Robot.floating_q); the chains' dynamics methods and tau = J^T F by virtual work."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import spotkin as sk
from spotkin import inertia
from spotkin.reference import dynamics as rd

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

G = np.array([0.0, 0.0, -9.81])


@cache
def robot(name: str) -> sk.Robot:
    return sk.Spot() if name == "spot" else sk.Robot.from_urdf(sk.robots.path("go2"))


def nominal(name: str):
    height = 0.5 if name == "spot" else 0.3
    r = robot(name)
    return r, r.stance_feet(height=height), height


def reference(r: sk.Robot, pose, q, stance, gravity=G):
    """The reference on the whole tree (arm at zero), its stance as foot indices."""
    tree = inertia.tree_of(r)
    q_full = np.concatenate([q, np.zeros(len(r.arm_joint_names))])
    return rd.standing_torques(tree, sk.body_transform(pose), q_full, np.flatnonzero(stance), gravity)


STANCES = [
    [True, True, True, True],
    [True, True, True, False],
    [False, True, True, True],
    [True, False, False, True],  # diagonal pair: unbalanced unless the centre of mass is on the line
    [True, False, False, False],
]


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_matches_the_reference(name, rng):
    r, feet, height = nominal(name)
    for _ in range(12):
        pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]) + rng.uniform(-1, 1, 6) * [
            0.06,
            0.06,
            0.04,
            0.1,
            0.1,
            0.2,
        ]
        q = r.body_ik(pose, feet).q
        if np.isnan(q).any():
            continue
        for stance in STANCES:
            got = r.standing_torques(pose, q, stance)
            want = reference(r, pose, q, stance)
            names = {rd.STANCE_OK: "OK", rd.STANCE_PULLING: "PULLING", rd.STANCE_OUTSIDE: "OUTSIDE"}
            assert got.status.name == names.get(want.status, "UNBALANCED"), (stance, got.status, want.status)
            np.testing.assert_allclose(got.margin, want.margin, atol=1e-12)
            np.testing.assert_allclose(got.tau, want.tau[: 3 * r.n_legs], atol=1e-9)
            forces = np.zeros((r.n_legs, 3))
            forces[np.flatnonzero(stance)] = want.forces
            np.testing.assert_allclose(got.forces, forces, atol=1e-9)
            np.testing.assert_allclose(got.residual, want.residual, atol=1e-9)


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_forces_balance_the_weight(name, rng):
    """sum f = -m g and sum (p - c) x f = 0, from spotkin's own feet and centre of mass."""
    r, feet, height = nominal(name)
    pose = np.array([0.03, -0.02, height, 0.05, -0.04, 0.1])
    q = r.body_ik(pose, feet).q
    g = np.array([0.5, -0.3, -9.7])  # tilted gravity too
    for stance in STANCES[:3]:
        got = r.standing_torques(pose, q, stance, gravity=g)
        assert got.status not in (sk.StanceStatus.UNBALANCED, sk.StanceStatus.INVALID_INPUT)
        com = r.center_of_mass(pose, q)
        p = r.body_fk(pose, q)
        np.testing.assert_allclose(got.forces.sum(axis=0), -r.mass * g, atol=1e-9)
        moment = np.cross(p - com, got.forces).sum(axis=0)
        np.testing.assert_allclose(moment, 0.0, atol=1e-9)
        # the minimum-norm solution: orthogonal to the null space of the balance equations
        A = np.vstack([np.hstack([np.eye(3)] * 4), np.hstack([rd.skew(pi - com) for pi in p])])
        A = A[:, np.repeat(stance, 3)]
        f = got.forces[np.asarray(stance)].ravel()
        null = np.linalg.svd(A)[2][np.linalg.matrix_rank(A) :]
        np.testing.assert_allclose(null @ f, 0.0, atol=1e-9)


def test_statuses_outside_and_unbalanced():
    r, feet, height = nominal("spot")
    # three feet, body (and centre of mass) pushed over the lifted hind-right corner: no pushing forces
    pose = np.array([-0.15, -0.1, height, 0.0, 0.0, 0.0])
    q = r.body_ik(pose, feet).q
    got = r.standing_torques(pose, q, [True, True, True, False])
    assert got.status == sk.StanceStatus.OUTSIDE and got.margin < 0
    assert got.forces[:, 2].min() < 0  # a foot pulls
    # one foot: it carries the weight, nothing balances the moment, which the residual gives
    one = r.standing_torques(pose, q, [True, False, False, False])
    assert one.status == sk.StanceStatus.UNBALANCED and np.isfinite(one.tau).all()
    weight = r.mass * np.array([0.0, 0.0, 9.81])
    np.testing.assert_allclose(one.forces[0], weight, atol=1e-9)
    com, foot = r.center_of_mass(pose, q), r.body_fk(pose, q)[0]
    np.testing.assert_allclose(one.residual, np.r_[0.0, 0.0, 0.0, -np.cross(foot - com, weight)], atol=1e-9)
    # no foot: the whole weight is left
    none = r.standing_torques(pose, q, [False] * 4)
    assert none.status == sk.StanceStatus.UNBALANCED and none.margin == -np.inf
    np.testing.assert_array_equal(none.forces, 0.0)
    np.testing.assert_allclose(none.residual, np.r_[weight, 0.0, 0.0, 0.0], atol=1e-9)
    # no gravity: nothing to hold, every force zero, the margin undefined
    free = r.standing_torques(pose, q, gravity=[0.0, 0.0, 0.0])
    assert free.status == sk.StanceStatus.OK and np.isnan(free.margin)
    np.testing.assert_array_equal(free.forces, 0.0)


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_two_feet_carry_the_weight_and_the_moment_in_least_squares(name, rng):
    """A trot's or a pace's two feet: sum f = -m g exactly; the moment left is the least one (normal
    to every moment the feet can make without changing sum f) and the forces the smallest giving it;
    the residual is that moment, about the centre of mass."""
    r, feet, height = nominal(name)
    for stance in ([True, False, False, True], [True, False, True, False], [False, True, True, False]):
        pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]) + rng.uniform(-1, 1, 6) * 0.03
        q = r.body_ik(pose, feet).q
        got = r.standing_torques(pose, q, stance)
        assert got.status == sk.StanceStatus.UNBALANCED
        weight = r.mass * np.array([0.0, 0.0, 9.81])
        np.testing.assert_allclose(got.forces.sum(axis=0), weight, atol=1e-9)
        np.testing.assert_allclose(got.residual[:3], 0.0, atol=1e-9)
        com, p = r.center_of_mass(pose, q), r.body_fk(pose, q)
        down = np.flatnonzero(stance)
        moment = np.cross(p[down] - com, got.forces[down]).sum(axis=0)
        np.testing.assert_allclose(got.residual[3:], -moment, atol=1e-9)
        # moving force between the feet (keeping the sum) changes the moment by (p_a - p_b) x d:
        # the moment left is normal to all of them, and the forces move none along the null space
        a, b = p[down[0]] - com, p[down[1]] - com
        span = np.array([np.cross(a - b, e) for e in np.eye(3)])
        np.testing.assert_allclose(span @ got.residual[3:], 0.0, atol=1e-7 * r.mass)
        # the smallest forces with this sum and this moment: orthogonal to the null space of both maps
        A = np.vstack([np.hstack([np.eye(3)] * 2), np.hstack([rd.skew(a), rd.skew(b)])])
        null = np.linalg.svd(A)[2][np.linalg.matrix_rank(A) :]
        np.testing.assert_allclose(null @ got.forces[down].ravel(), 0.0, atol=1e-9)
        tau = r.standing_torques(pose, q, [True] * 4).tau
        assert np.isfinite(got.tau).all() and not np.allclose(got.tau, tau)


def test_swing_legs_hold_their_own_weight():
    """A swing leg's torques are its gravity torques: those of the leg as a fixed-base chain with
    gravity seen from the body."""
    r, feet, height = nominal("spot")
    pose = np.array([0.02, 0.01, height, 0.1, -0.05, 0.3])
    q = r.body_ik(pose, feet).q
    got = r.standing_torques(pose, q, [True, True, True, False])
    R = sk.body_transform(pose)[:3, :3]
    hind_right = r.chain("rear_right_foot")
    np.testing.assert_allclose(got.tau[9:], hind_right.gravity(q[9:], R.T @ G), atol=1e-10)
    stance_leg = r.chain("front_left_foot")
    J = hind_right.position_jacobian(q[9:])  # a check of the test's own chain: 3 x 3
    assert J.shape == (3, 3)
    # a stance leg: G_l - J_l^T f_l with the foot Jacobian in world axes
    J_world = R @ stance_leg.position_jacobian(q[:3])
    np.testing.assert_allclose(
        got.tau[:3], stance_leg.gravity(q[:3], R.T @ G) - J_world.T @ got.forces[0], atol=1e-9
    )


def test_batches_broadcast_and_match_single_calls(rng):
    r, feet, height = nominal("go2")
    poses = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]) + rng.uniform(-1, 1, (3, 1, 2, 6)) * 0.04
    q = r.body_ik(poses, feet).q
    stance = np.array([[True, True, True, True], [True, True, False, True]])  # (2, 4) broadcasts
    got = r.standing_torques(poses, q, stance)
    assert got.tau.shape == (3, 1, 2, 12) and got.forces.shape == (3, 1, 2, 4, 3)
    assert got.status.shape == (3, 1, 2) and got.status.dtype == np.int8 and got.margin.shape == (3, 1, 2)
    for idx in np.ndindex(3, 1, 2):
        one = r.standing_torques(poses[idx], q[idx], stance[idx[-1]])
        assert isinstance(one.status, sk.StanceStatus) and isinstance(one.margin, np.float64)
        np.testing.assert_array_equal(one.tau, got.tau[idx])
        assert one.status == got.status[idx]
    empty = r.standing_torques(np.zeros((0, 6)), np.zeros((0, 12)))
    assert empty.tau.shape == (0, 12) and empty.status.shape == (0,)
    single = r.standing_torques(poses[0, 0, 0].astype(np.float32), q[0, 0, 0].astype(np.float32))
    assert single.tau.dtype == np.float32


def test_bad_input_gives_a_status_or_a_clear_error():
    r, feet, height = nominal("go2")
    poses = np.tile([0.0, 0.0, height, 0.0, 0.0, 0.0], (3, 1))
    q = r.body_ik(poses, feet).q
    poses[1, 3] = np.nan
    q[2, 4] = np.inf
    got = r.standing_torques(poses, q)
    assert got.status[0] == sk.StanceStatus.OK
    assert (got.status[1:] == sk.StanceStatus.INVALID_INPUT).all()
    assert np.isnan(got.tau[1:]).all() and np.isfinite(got.tau[0]).all()
    with pytest.raises(ValueError, match="q must have shape"):
        r.standing_torques(poses[0], np.zeros(5))
    with pytest.raises(ValueError, match="stance must have shape"):
        r.standing_torques(poses[0], q[0], [True, True])
    with pytest.raises(TypeError, match="stance"):
        r.standing_torques(poses[0], q[0], ["a", "b", "c", "d"])
    with pytest.raises(ValueError, match="gravity"):
        r.standing_torques(poses[0], q[0], gravity=[0.0, -9.81])
    with pytest.raises(ValueError, match="body_pose"):
        r.standing_torques(np.zeros(5), q[0])
    with pytest.raises(ValueError, match="do not broadcast"):
        r.standing_torques(poses, q[:2])


def test_floating_q_quaternions(rng):
    r = robot("spot")
    rotations = Rotation.random(200, random_state=7)
    # near half turns (w ~ 0) and the identity too
    extra = Rotation.from_rotvec([[np.pi, 0, 0], [0, np.pi - 1e-9, 0], [0, 0, 0], [1e-12, 0, 0], [0, 2, 2.4]])
    rotations = Rotation.concatenate([rotations, extra])
    T = np.tile(np.eye(4), (len(rotations), 1, 1))
    T[:, :3, :3] = rotations.as_matrix()
    T[:, :3, 3] = rng.normal(size=(len(rotations), 3))
    q = rng.uniform(-1, 1, (len(rotations), 18))
    qf = r.floating_q(T, q)
    assert qf.shape == (len(rotations), 25)
    np.testing.assert_allclose(Rotation.from_quat(qf[:, 3:7]).as_matrix(), T[:, :3, :3], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(qf[:, 3:7], axis=1), 1.0, atol=1e-14)
    np.testing.assert_array_equal(qf[:, 7:], q)
    legs_only = r.floating_q(T[0], q[0, :12])
    np.testing.assert_array_equal(legs_only[19:], 0.0)  # the arm at zero
    bad = r.floating_q(np.full(6, np.nan), q[0])
    assert np.isnan(bad[:7]).all()


def test_chain_dynamics_methods_and_forces_by_virtual_work(rng):
    arm = robot("spot").chain("arm_hand")
    q, qd, qdd = rng.uniform(-1, 1, (3, 5, 6))
    from spotkin import dynamics

    np.testing.assert_array_equal(
        arm.inverse_dynamics(q, qd, qdd), dynamics.inverse_dynamics(arm, q, qd, qdd)
    )
    np.testing.assert_array_equal(arm.mass_matrix(q), dynamics.mass_matrix(arm, q))
    np.testing.assert_array_equal(arm.gravity(q), dynamics.gravity(arm, q))
    np.testing.assert_allclose(arm.forward_dynamics(q, qd, arm.inverse_dynamics(q, qd, qdd)), qdd, atol=1e-9)
    np.testing.assert_allclose(arm.nonlinear_effects(q, qd), arm.inverse_dynamics(q, qd, 0 * qd), atol=1e-12)
    np.testing.assert_allclose(
        arm.coriolis_matrix(q, qd) @ qd[..., None],
        (arm.nonlinear_effects(q, qd) - arm.gravity(q))[..., None],
        atol=1e-10,
    )
    # tau = J^T F: the power tau . qd equals the wrench's power F . (v, w), the tool twist from
    # finite differences of fk
    F = rng.normal(size=(5, 6))
    tau = arm.joint_torques_from_forces(q, F)
    eps = 1e-6
    T_plus, T_minus = arm.fk(q + eps * qd), arm.fk(q - eps * qd)
    v = (T_plus[:, :3, 3] - T_minus[:, :3, 3]) / (2 * eps)
    dR = (T_plus[:, :3, :3] - T_minus[:, :3, :3]) / (2 * eps)
    W = dR @ np.swapaxes(arm.fk(q)[:, :3, :3], 1, 2)
    w = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], axis=1)
    np.testing.assert_allclose(
        np.sum(tau * qd, axis=1), np.sum(F[:, :3] * v + F[:, 3:] * w, axis=1), atol=1e-7
    )
    np.testing.assert_allclose(
        arm.joint_torques_from_forces(q, F[:, :3]),
        np.einsum("nij,ni->nj", arm.position_jacobian(q), F[:, :3]),
        atol=1e-14,
    )
    assert arm.joint_torques_from_forces(q[0], F).shape == (5, 6)  # broadcast
    with pytest.raises(ValueError, match="forces"):
        arm.joint_torques_from_forces(q, np.zeros((5, 4)))
    with pytest.raises(ValueError, match="do not broadcast"):
        arm.joint_torques_from_forces(q, np.zeros((4, 6)))
