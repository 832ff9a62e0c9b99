"""Loading arms and other robots from their URDF (issue 32): ``Chain.from_urdf`` on a UR5-like and a
Panda-like description (tests/data, with package:// meshes that are never read), mimic joints, root
joints (floating / fixed to ``world``), xacro, planar joints, the messages that point elsewhere, and the
``spotkin inspect`` / ``spotkin plot`` commands on arms.

Oracles: Pinocchio on the same files (frame placements, ``computeFrameJacobian``, RNEA, CRBA, gravity,
non-linear effects, centre of mass; its mimic joints with ``mimic=True``), the UR5's published DH table,
the Panda's published modified-DH table, the mimic relation applied by hand, central differences, and the
properties every Coriolis matrix has (``C qd = h - G``, ``dA/dt - 2 C`` skew-symmetric)."""

from __future__ import annotations

import io
import math
import os
import pickle
import subprocess
import sys
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pinocchio
import pytest

import spotkin as sk
from conftest import PANDA_ROWS
from spotkin import urdf
from spotkin.__main__ import main

DATA = Path(__file__).parent / "data"
UR5, PANDA, GO2 = DATA / "ur5.urdf", DATA / "panda.urdf", DATA / "go2.urdf"
PI = math.pi

# The UR5's published DH table (Universal Robots): d1, a2, a3, d4, d5, d6 and the twists.
UR5_DH = [
    (0, 0.0, PI / 2, 0.089159, 0.0),
    (0, -0.425, 0.0, 0.0, 0.0),
    (0, -0.39225, 0.0, 0.0, 0.0),
    (0, 0.0, PI / 2, 0.10915, 0.0),
    (0, 0.0, -PI / 2, 0.09465, 0.0),
    (0, 0.0, 0.0, 0.0823, 0.0),
]


def _inertial(mass, com):
    return (
        f'<inertial><origin xyz="{com}" rpy="0.1 0.2 0.3"/><mass value="{mass}"/>'
        '<inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.03" iyz="0.002" izz="0.04"/></inertial>'
    )


def _limit(lower, upper):
    return f'<limit lower="{lower}" upper="{upper}" effort="10" velocity="2"/>'


# A spatial chain whose third joint mimics its second (both on the path): 4 joints, 3 variables.
COUPLED = f"""<robot name="coupled">
<link name="base"/>
<link name="l1">{_inertial(2.0, "0.05 0 0.1")}</link>
<link name="l2">{_inertial(1.5, "0.2 0.01 0")}</link>
<link name="l3">{_inertial(1.0, "0.15 0 0.02")}</link>
<link name="l4">{_inertial(0.5, "0.02 0.03 0.05")}</link>
<link name="tip"/>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
  <axis xyz="0 0 1"/>{_limit(-3, 3)}</joint>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.05 0 0.1" rpy="0.3 0 0"/>
  <axis xyz="0 1 0"/>{_limit(-2, 2)}</joint>
<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.4 0 0"/>
  <axis xyz="0 1 0"/>{_limit(-2, 2)}<mimic joint="j2" multiplier="-0.5" offset="0.2"/></joint>
<joint name="j4" type="prismatic"><parent link="l3"/><child link="l4"/><origin xyz="0.3 0 0" rpy="0 0.2 0"/>
  <axis xyz="1 0 0"/>{_limit(0, 0.2)}</joint>
<joint name="t" type="fixed"><parent link="l4"/><child link="tip"/><origin xyz="0.1 0.02 0"/></joint>
</robot>"""


def angle_gap(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def pin_model(text: str, mimic: bool = False):
    if not mimic:
        return pinocchio.buildModelFromXML(text)
    try:
        return pinocchio.buildModelFromXML(text, True)
    except TypeError:  # a Pinocchio without mimic joints (before 3.4)
        pytest.skip("this Pinocchio has no mimic joints")


def pin_columns(pm, names):
    """The Pinocchio q (and v) index of each named one-dof joint."""
    index = {pm.names[i]: pm.joints[i].idx_q for i in range(1, pm.njoints) if pm.joints[i].nq == 1}
    return [index[name] for name in names]


def random_pin_q(pm, rng):
    lower, upper = pm.lowerPositionLimit, pm.upperPositionLimit
    lower = np.where(np.isfinite(lower), lower, -PI)
    upper = np.where(np.isfinite(upper), upper, PI)
    return lower + (upper - lower) * rng.uniform(0.02, 0.98, pm.nq)


def check_frames_and_jacobians(chain, text, tip, rng, mimic=False, samples=10):
    pm = pin_model(text, mimic)
    frame = pm.getFrameId(tip)
    cols = pin_columns(pm, chain.joint_names)
    for _ in range(samples):
        qp = random_pin_q(pm, rng)
        q = qp[cols]
        data = pm.createData()
        pinocchio.forwardKinematics(pm, data, qp)
        pinocchio.updateFramePlacements(pm, data)
        np.testing.assert_allclose(chain.fk(q), data.oMf[frame].homogeneous, atol=1e-12)
        J = pinocchio.computeFrameJacobian(pm, pm.createData(), qp, frame, pinocchio.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(chain.jacobian(q), J[:, cols], atol=1e-12)


def central_jacobian(chain, q, h=1e-6):
    """[v; w] of the tool from central differences of fk."""
    J = np.zeros((6, chain.dof))
    R0 = chain.fk(q)[:3, :3]
    for k in range(chain.dof):
        dq = np.zeros(chain.dof)
        dq[k] = h
        Tp, Tm = chain.fk(q + dq), chain.fk(q - dq)
        J[:3, k] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        W = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ R0.T
        J[3:, k] = 0.5 * np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])
    return J


# --------------------------------------------------------------------------- UR5


def test_ur5_loads_as_a_6r_three_parallel_arm():
    chain = sk.Chain.from_urdf(UR5)
    assert chain.joint_names == (
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    )
    assert chain.ik_kind == "6R-three-parallel-234"
    # ee_link and tool0 are both fixed to wrist_3_link: the default tip is where they branch
    np.testing.assert_allclose(
        chain.fk(np.zeros(6)), sk.Chain.from_urdf(UR5, tip="wrist_3_link").fk(np.zeros(6))
    )
    np.testing.assert_allclose(chain.upper, [2 * PI, 2 * PI, PI, 2 * PI, 2 * PI, 2 * PI])
    assert chain.inertials is not None
    np.testing.assert_allclose(chain.inertials.mass, [3.7, 8.393, 2.275, 1.219, 1.219, 0.1879])


def test_ur5_matches_its_published_dh_table(rng):
    """tool0 in the 'base' frame (base_link turned by pi about z) is the controller's DH flange."""
    chain = sk.Chain.from_urdf(UR5, tip="tool0")
    base = urdf.load_urdf(UR5).placement("base")
    dh = sk.Chain.from_dh(UR5_DH)
    q = rng.uniform(-PI, PI, (50, 6))
    # the file writes pi/2 as 1.570796325: agreement to its 1e-9 rounding
    np.testing.assert_allclose(np.linalg.inv(base) @ chain.fk(q), dh.fk(q), atol=2e-8)


@pytest.mark.parametrize("tip", ["tool0", "ee_link", "wrist_2_link"])
def test_ur5_frames_and_jacobians_match_pinocchio(tip, rng):
    chain = sk.Chain.from_urdf(UR5, tip=tip)
    check_frames_and_jacobians(chain, UR5.read_text(), tip, rng)


def test_ur5_dynamics_match_pinocchio(rng):
    chain = sk.Chain.from_urdf(UR5, tip="tool0")
    pm = pin_model(UR5.read_text())
    for _ in range(5):
        q, qd, qdd = rng.uniform(-PI, PI, 6), rng.normal(size=6), rng.normal(size=6)
        np.testing.assert_allclose(
            chain.inverse_dynamics(q, qd, qdd), pinocchio.rnea(pm, pm.createData(), q, qd, qdd), atol=1e-10
        )
        np.testing.assert_allclose(chain.mass_matrix(q), pinocchio.crba(pm, pm.createData(), q), atol=1e-12)


def test_ur5_ik_every_branch_round_trips(rng):
    chain = sk.Chain.from_urdf(UR5, tip="tool0")
    q = rng.uniform(-PI, PI, (300, 6))
    q = q[np.abs(np.sin(q[:, 4])) > 0.05]  # away from the wrist singularity (q5 = 0, pi)
    T = chain.fk(q)
    sol = chain.ik_all(T)
    assert sol.exists.any(axis=-1).all()
    found = np.where(sol.exists[..., None, None], chain.fk(np.nan_to_num(sol.q)), T[:, None])
    np.testing.assert_allclose(found, np.broadcast_to(T[:, None], found.shape), atol=1e-10)
    assert (sol.exists.sum(axis=-1) >= 2).all()
    gaps = np.where(sol.exists, angle_gap(sol.q, q[:, None, :]).max(axis=-1), np.inf)
    assert (gaps.min(axis=-1) < 1e-7).all(), "the generating configuration is not among the solutions"


def test_ur5_shipped_and_with_meshes_are_the_same_arm(rng):
    """The packaged UR5 has no meshes; tests/data's has package:// meshes in visual and collision, which
    never matter."""
    text = UR5.read_text()
    assert text.count("package://ur_description/meshes/") >= 14
    assert "package://" not in sk.robots.text("ur5")
    q = rng.uniform(-PI, PI, (20, 6))
    for tip in ("tool0", "ee_link"):
        a, b = sk.Chain.from_urdf(UR5, tip=tip), sk.Chain.from_urdf(sk.robots.path("ur5"), tip=tip)
        np.testing.assert_array_equal(a.fk(q), b.fk(q))
        np.testing.assert_array_equal(a.inertials.inertia, b.inertials.inertia)
    panda = PANDA.read_text()
    assert "package://franka_description/" in panda
    np.testing.assert_array_equal(
        sk.Chain.from_urdf(PANDA).fk(np.full(7, 0.2)),
        sk.Chain.from_urdf(sk.robots.path("panda")).fk(np.full(7, 0.2)),
    )


def test_sources_path_text_bytes_pathlike_are_the_same_chain(rng):
    q = rng.uniform(-1, 1, 6)
    text = UR5.read_text()
    chains = [
        sk.Chain.from_urdf(str(UR5)),
        sk.Chain.from_urdf(UR5),
        sk.Chain.from_urdf(text),
        sk.Chain.from_urdf("\n  " + text),
        sk.Chain.from_urdf(text.encode()),
    ]
    for chain in chains[1:]:
        assert chain.joint_names == chains[0].joint_names
        np.testing.assert_array_equal(chain.fk(q), chains[0].fk(q))


def test_chain_is_robot_chain_and_pickles(rng):
    """Chain.from_urdf and Robot.chain share one route: the same chain, bodies included."""
    robot = sk.Robot.from_urdf(GO2)
    a, b = robot.chain("FL_foot"), sk.Chain.from_urdf(GO2, tip="FL_foot")
    q = rng.uniform(-1, 1, (5, 3))
    assert a.joint_names == b.joint_names
    np.testing.assert_array_equal(a.fk(q), b.fk(q))
    np.testing.assert_array_equal(a.inertials.mass, b.inertials.mass)
    for chain in (b, sk.Chain.from_urdf(UR5), sk.Chain.from_urdf(PANDA, tip="panda_rightfinger")):
        again = pickle.loads(pickle.dumps(chain))
        assert type(again) is type(chain) and again.joint_names == chain.joint_names
        qq = rng.uniform(0, 0.04, chain.dof)
        np.testing.assert_array_equal(again.fk(qq), chain.fk(qq))
        np.testing.assert_array_equal(again.inertials.mass, chain.inertials.mass)
        np.testing.assert_array_equal(again.lower, chain.lower)


# --------------------------------------------------------------------------- Panda, mimic joints


def test_panda_default_tip_is_the_hand_and_its_ik_needs_a_free_joint(rng):
    chain = sk.Chain.from_urdf(PANDA)
    assert chain.dof == 7 and chain.joint_names == tuple(f"panda_joint{k}" for k in range(1, 8))
    hand = urdf.load_urdf(PANDA).placement("panda_hand")
    np.testing.assert_allclose(chain.fk(np.zeros(7)), hand, atol=1e-15)
    with pytest.raises(ValueError, match="free_joint") as error:
        _ = chain.ik_kind
    assert "ik_differential" in str(error.value)
    T = chain.fk(np.zeros(7) + 0.1)
    with pytest.raises(ValueError, match=r"free_joint.*ik_differential"):
        chain.ik_all(T)
    assert chain.ik_free_kind(6) == "6R-spherical-shoulder"
    chain.ik_all(T, free_joint=6, free_value=0.1)
    with pytest.raises(ValueError, match="free_joint"):  # still named after a free-joint call
        _ = chain.ik_kind


def test_panda_matches_its_published_mdh_table(rng):
    chain = sk.Chain.from_urdf(PANDA, tip="panda_link8")
    mdh = sk.Chain.from_mdh(PANDA_ROWS, tool=sk.translation([0.0, 0.0, 0.107]))
    q = rng.uniform(-2.5, 2.5, (50, 7))
    np.testing.assert_allclose(chain.fk(q), mdh.fk(q), atol=1e-14)
    np.testing.assert_allclose(chain.jacobian(q), mdh.jacobian(q), atol=1e-14)


def test_panda_ik_with_a_free_joint_round_trips(rng):
    chain = sk.Chain.from_urdf(PANDA)
    lower, upper = chain.lower, chain.upper
    q = lower + 0.05 + (upper - lower - 0.1) * rng.uniform(0, 1, (300, 7))
    T = chain.fk(q)
    sol = chain.ik_all(T, free_joint=6, free_value=q[:, 6])
    assert sol.exists.any(axis=-1).all()
    found = np.where(sol.exists[..., None, None], chain.fk(np.nan_to_num(sol.q)), T[:, None])
    np.testing.assert_allclose(found, np.broadcast_to(T[:, None], found.shape), atol=1e-10)
    np.testing.assert_array_equal(
        np.where(sol.exists, sol.q[..., 6], q[:, None, 6]), q[:, None, 6].repeat(8, 1)
    )
    gaps = np.where(sol.valid, angle_gap(sol.q, q[:, None, :]).max(axis=-1), np.inf)
    assert (gaps.min(axis=-1) < 1e-7).mean() > 0.99, "the generating configuration is not among the solutions"


@pytest.mark.parametrize("tip", ["panda_hand", "panda_leftfinger", "panda_rightfinger"])
def test_panda_frames_and_jacobians_match_pinocchio_mimic(tip, rng):
    chain = sk.Chain.from_urdf(PANDA, tip=tip)
    check_frames_and_jacobians(chain, PANDA.read_text(), tip, rng, mimic=True)


def test_panda_right_finger_follows_the_left_finger_joint(rng):
    right = sk.Chain.from_urdf(PANDA, tip="panda_rightfinger")
    left = sk.Chain.from_urdf(PANDA, tip="panda_leftfinger")
    hand = sk.Chain.from_urdf(PANDA)
    # the right finger's variable is the left finger's joint, its leader, off the right finger's path
    assert right.joint_names == left.joint_names == (*hand.joint_names, "panda_finger_joint1")
    assert right.full_joint_names[-1] == "panda_finger_joint2" and right.dof == 8
    q = np.c_[rng.uniform(-1.5, 1.5, (20, 7)), rng.uniform(0, 0.04, 20)]
    # the relation by hand: the fingers open symmetrically, d each side, 0.0584 m out of the hand
    for chain, side in ((left, 1.0), (right, -1.0)):
        finger = np.linalg.inv(hand.fk(q[:, :7])) @ chain.fk(q)
        expected = np.broadcast_to(np.eye(4), finger.shape).copy()
        expected[:, :3, 3] = np.c_[np.zeros(20), side * q[:, 7], np.full(20, 0.0584)]
        np.testing.assert_allclose(finger, expected, atol=1e-14)
    # the finger column of the Jacobian: d p / d d = -y_hand for the right finger
    J = right.jacobian(q)
    np.testing.assert_allclose(J[:, :3, 7], -hand.fk(q[:, :7])[:, :3, 1], atol=1e-14)
    np.testing.assert_allclose(J[:, 3:, 7], 0.0, atol=1e-15)
    for k in range(3):
        np.testing.assert_allclose(J[k], central_jacobian(right, q[k]), atol=1e-8)


def test_panda_finger_dynamics_match_pinocchio_mimic(rng):
    """With the left finger massless, Pinocchio's tree is the right finger's chain: its dynamics, the
    mimic joint moving with its leader, are the chain's."""
    text = PANDA.read_text()
    start = text.index('<link name="panda_leftfinger">')
    end = text.index("</link>", start) + len("</link>")
    text = text[:start] + '<link name="panda_leftfinger"/>' + text[end:]
    chain = sk.Chain.from_urdf(text, tip="panda_rightfinger")
    pm = pin_model(text, mimic=True)
    cols = pin_columns(pm, chain.joint_names)
    assert pm.nv == 8 and sorted(cols) == list(range(8))
    for _ in range(4):
        qp = random_pin_q(pm, rng)
        vp, ap, taup = rng.normal(size=8), rng.normal(size=8), rng.normal(size=8)
        q, qd, qdd, tau = qp[cols], vp[cols], ap[cols], taup[cols]
        new = pm.createData  # Pinocchio's mimic algorithms want fresh data
        np.testing.assert_allclose(
            chain.inverse_dynamics(q, qd, qdd), pinocchio.rnea(pm, new(), qp, vp, ap)[cols], atol=1e-10
        )
        A = pinocchio.crba(pm, new(), qp)
        np.testing.assert_allclose(chain.mass_matrix(q), A[np.ix_(cols, cols)], atol=1e-12)
        np.testing.assert_allclose(
            chain.gravity(q), pinocchio.computeGeneralizedGravity(pm, new(), qp)[cols], atol=1e-10
        )
        h = pinocchio.nonLinearEffects(pm, new(), qp, vp)
        np.testing.assert_allclose(chain.nonlinear_effects(q, qd), h[cols], atol=1e-10)
        np.testing.assert_allclose(
            chain.forward_dynamics(q, qd, tau), np.linalg.solve(A, taup - h)[cols], rtol=1e-8, atol=1e-8
        )
        np.testing.assert_allclose(chain.center_of_mass(q), pinocchio.centerOfMass(pm, new(), qp), atol=1e-12)


def test_coupled_mimic_chain_matches_pinocchio(rng):
    chain = sk.Chain.from_urdf(COUPLED)
    assert chain.joint_names == ("j1", "j2", "j4") and chain.full_joint_names == ("j1", "j2", "j3", "j4")
    np.testing.assert_array_equal(chain.mimic_matrix, [[1, 0, 0], [0, 1, 0], [0, -0.5, 0], [0, 0, 1]])
    np.testing.assert_array_equal(chain.mimic_offset, [0, 0, 0.2, 0])
    np.testing.assert_array_equal(chain.lower, [-3, -2, 0])  # the leaders' limits
    np.testing.assert_array_equal(chain.sigma, [0, 0, 1])
    check_frames_and_jacobians(chain, COUPLED, "tip", rng, mimic=True)
    pm = pin_model(COUPLED, mimic=True)
    new = pm.createData
    for _ in range(5):
        q = np.array([rng.uniform(-3, 3), rng.uniform(-2, 2), rng.uniform(0, 0.2)])
        qd, qdd, tau = rng.normal(size=(3, 3))
        np.testing.assert_allclose(
            chain.inverse_dynamics(q, qd, qdd), pinocchio.rnea(pm, new(), q, qd, qdd), atol=1e-12
        )
        A = pinocchio.crba(pm, new(), q)
        np.testing.assert_allclose(chain.mass_matrix(q), A, atol=1e-13)
        G = pinocchio.computeGeneralizedGravity(pm, new(), q)
        np.testing.assert_allclose(chain.gravity(q), G, atol=1e-12)
        h = pinocchio.nonLinearEffects(pm, new(), q, qd)
        np.testing.assert_allclose(chain.nonlinear_effects(q, qd), h, atol=1e-12)
        np.testing.assert_allclose(
            chain.forward_dynamics(q, qd, tau), np.linalg.solve(A, tau - h), atol=1e-10
        )
        np.testing.assert_allclose(chain.center_of_mass(q), pinocchio.centerOfMass(pm, new(), q), atol=1e-13)
        np.testing.assert_allclose(
            chain.center_of_mass_jacobian(q), pinocchio.jacobianCenterOfMass(pm, new(), q), atol=1e-13
        )
        np.testing.assert_allclose(chain.kinetic_energy(q, qd), 0.5 * qd @ A @ qd, atol=1e-13)
        # Coriolis (Pinocchio's computeCoriolisMatrix does not handle mimic joints): its two properties
        C = chain.coriolis_matrix(q, qd)
        np.testing.assert_allclose(C @ qd, h - G, atol=1e-12)
        step = 1e-6
        A_dot = (chain.mass_matrix(q + step * qd) - chain.mass_matrix(q - step * qd)) / (2 * step)
        N = A_dot - 2 * C
        np.testing.assert_allclose(N + N.T, 0.0, atol=1e-8)
        np.testing.assert_allclose(chain.jacobian(q), central_jacobian(chain, q), atol=1e-8)
        np.testing.assert_allclose(
            chain.joint_torques_from_forces(q, [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]),
            chain.jacobian(q).T @ [1.0, 2.0, 3.0, 0.1, 0.2, 0.3],
            atol=1e-14,
        )
    # batches broadcast like the plain chain's
    q = np.c_[rng.uniform(-1, 1, (4, 2)), rng.uniform(0, 0.2, 4)]
    assert chain.mass_matrix(q).shape == (4, 3, 3) and chain.fk(q.astype(np.float32)).dtype == np.float32
    np.testing.assert_allclose(chain.gravity(q)[2], chain.gravity(q[2]), atol=1e-15)


def test_coupled_mimic_chain_ik_says_what_applies(rng):
    chain = sk.Chain.from_urdf(COUPLED)
    for call in (lambda: chain.ik_kind, lambda: chain.ik_position([0.5, 0.1, 0.4])):
        with pytest.raises(ValueError, match=r"j3 = -0.5 × j2 \+ 0.2.*ik_differential"):
            call()
    q = np.array([0.3, -0.7, 0.1])
    T = chain.fk(q)
    q_found, info = chain.ik_differential(T, np.zeros(3), task="position")
    assert info.converged and info.position_error <= 1e-6
    np.testing.assert_allclose(chain.fk(q_found)[:3, 3], T[:3, 3], atol=1e-6)
    # a path of targets from a batch of starts, limits held
    path = chain.fk(np.c_[np.linspace(0.1, 0.4, 5), np.linspace(-0.5, -0.8, 5), np.full(5, 0.05)])
    q_path, info = chain.ik_differential(path[None], np.zeros((2, 3)), task="position")
    assert q_path.shape == (2, 5, 3) and info.converged.all()
    assert (q_path[..., 2] >= 0).all() and (q_path[..., 2] <= 0.2).all()
    q_nan, info = chain.ik_differential(np.full((4, 4), np.nan), np.zeros(3))
    assert np.isnan(q_nan).all() and not info.converged


def test_closed_form_ik_maps_back_through_a_mimic_joint(rng):
    """A UR5 whose last joint mimics a knob beside the arm (2 q_knob + 0.1): the knob is the chain's
    sixth variable, the full chain's closed form solves the pose and maps back."""
    text = UR5.read_text().replace(
        '<joint name="wrist_3_joint" type="revolute">',
        '<joint name="wrist_3_joint" type="revolute"><mimic joint="knob" multiplier="2" offset="0.1"/>',
    )
    text = text.replace(
        "</robot>",
        '<link name="knob_link"/><joint name="knob" type="revolute"><parent link="base_link"/>'
        f'<child link="knob_link"/><axis xyz="0 0 1"/>{_limit(-3, 3)}</joint></robot>',
    )
    chain = sk.Chain.from_urdf(text, tip="tool0")
    assert chain.joint_names[-1] == "knob" and chain.dof == 6
    assert chain.ik_kind == "6R-three-parallel-234"
    np.testing.assert_array_equal([chain.lower[5], chain.upper[5]], [-3, 3])
    plain = sk.Chain.from_urdf(UR5, tip="tool0")
    q = rng.uniform(-1.5, 1.4, (100, 6))
    q = q[np.abs(np.sin(q[:, 4])) > 0.05]
    q_full = q.copy()
    q_full[:, 5] = 2 * q[:, 5] + 0.1
    np.testing.assert_allclose(chain.fk(q), plain.fk(q_full), atol=1e-15)
    T = chain.fk(q)
    sol = chain.ik_all(T)
    found = np.where(sol.exists[..., None, None], chain.fk(np.nan_to_num(sol.q)), T[:, None])
    np.testing.assert_allclose(found, np.broadcast_to(T[:, None], found.shape), atol=1e-10)
    gaps = np.where(sol.valid, np.abs(sol.q - q[:, None, :]).max(axis=-1), np.inf)
    assert (gaps.min(axis=-1) < 1e-7).all()
    q_near, _ = chain.ik(T, q + 0.01)
    np.testing.assert_allclose(q_near, q, atol=1e-7)
    # out=: the mapped-back results written into the caller's arrays, the same bits
    q_out, status_out = np.empty_like(q), np.empty(len(q), np.int8)
    got = chain.ik(T, q + 0.01, out=(q_out, status_out))
    assert got[0] is q_out and got[1] is status_out
    np.testing.assert_array_equal(q_out, q_near)
    outs = tuple(np.empty_like(np.asarray(a)) for a in sol)
    got_all = chain.ik_all(T, out=outs)
    assert isinstance(got_all, sk.ChainSolutions) and all(g is o for g, o in zip(got_all, outs))
    for a, b in zip(outs, sol):
        np.testing.assert_array_equal(a, b)


def test_mimic_validation_names_the_joint():
    base = COUPLED
    cases = {
        "no_such": (
            '<mimic joint="j2"',
            '<mimic joint="no_such"',
            "j3.*mimics joint 'no_such', which does not exist",
        ),
        "itself": ('<mimic joint="j2"', '<mimic joint="j3"', "j3.*cannot mimic itself"),
        "prismatic": (
            '<mimic joint="j2"',
            '<mimic joint="j4"',
            "j3.*\\(revolute\\) mimics joint 'j4' \\(prismatic\\)",
        ),
        "fixed": ('<mimic joint="j2"', '<mimic joint="t"', "j3.*mimics joint 't', which is fixed"),
    }
    for old, new, message in cases.values():
        with pytest.raises(ValueError, match=message):
            urdf.parse_urdf(base.replace(old, new))
    chained = base.replace("</robot>", "") + (
        f'<link name="l5"/><joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>'
        f'<axis xyz="0 0 1"/>{_limit(-1, 1)}<mimic joint="j3"/></joint></robot>'
    )
    with pytest.raises(ValueError, match=r"j5.*mimics joint 'j3', itself a mimic of 'j2'"):
        urdf.parse_urdf(chained)
    model = urdf.parse_urdf(base)
    assert [j.name for j in model.actuated_joints] == ["j1", "j2", "j4"]
    assert [j.index for j in model.actuated_joints] == [0, 1, 2] and model.joint("j3").index == -1
    assert "mimic: j3 follows j2 × -0.5 + 0.2" in urdf.describe(model)
    with pytest.raises(ValueError, match=r"j3.*takes no value"):
        model.placement("tip", {"j3": 0.1})


def test_mimic_chains_refuse_the_plain_dynamics_functions():
    chain = sk.Chain.from_urdf(COUPLED)
    with pytest.raises(ValueError, match="mimic"):
        sk.dynamics.mass_matrix(chain, np.zeros(3))
    with pytest.raises(ValueError, match="full_chain"):
        sk.inertia.tree_of(chain)
    assert sk.inertia.tree_of(chain.full_chain).joint_names == ("j1", "j2", "j3", "j4")


def test_robot_joint_names_leave_mimic_joints_out():
    text = GO2.read_text().replace(
        "</robot>",
        '<link name="finger_a"/><link name="finger_b"/>'
        '<joint name="fa" type="prismatic"><parent link="base"/><child link="finger_a"/>'
        f"{_limit(0, 0.1)}</joint>"
        f'<joint name="fb" type="prismatic"><parent link="base"/><child link="finger_b"/>{_limit(0, 0.1)}'
        '<mimic joint="fa" multiplier="-1"/></joint></robot>',
    )
    robot = sk.Robot.from_urdf_string(text)
    assert "fa" in robot.joint_names and "fb" not in robot.joint_names
    assert robot.leg_names == sk.Robot.from_urdf(GO2).leg_names
    chain = robot.chain("finger_b")
    assert chain.joint_names == ("fa",)
    np.testing.assert_allclose(chain.fk([0.05])[:3, 3] - chain.fk([0.0])[:3, 3], [-0.05, 0, 0], atol=1e-15)


# --------------------------------------------------------------------------- root joints, planar


def _wrapped_go2(kind: str, parent_mass: str = "") -> str:
    text = GO2.read_text()
    head = '<robot name="go2_description">'
    world = f'<link name="world">{parent_mass}</link>' if parent_mass else '<link name="world"/>'
    joint = (
        f'<joint name="root_joint" type="{kind}"><parent link="world"/><child link="base"/>'
        '<origin xyz="0 0 0.45"/></joint>'
    )
    return text.replace(head, head + world + joint)


@pytest.mark.parametrize("kind", ["floating", "fixed"])
def test_a_root_joint_from_world_is_the_robot_root(kind, rng):
    plain = sk.Robot.from_urdf(GO2)
    robot = sk.Robot.from_urdf_string(_wrapped_go2(kind))
    assert robot.model.root == "base" and "world" not in robot.model.links
    assert robot.model.root_joint.type == kind and robot.model.root_joint.name == "root_joint"
    np.testing.assert_array_equal(robot.model.root_joint.origin[:3, 3], [0, 0, 0.45])
    assert robot.leg_names == plain.leg_names and robot.joint_names == plain.joint_names
    np.testing.assert_array_equal(robot.hip_positions, plain.hip_positions)
    q = rng.uniform(-0.5, 0.5, 12)
    pose = [0, 0, 0.3, 0.1, -0.1, 0.2]
    np.testing.assert_array_equal(robot.body_fk(pose, q), plain.body_fk(pose, q))
    np.testing.assert_allclose(robot.mass, plain.mass)
    assert f"root joint: {kind} root_joint from 'world' to 'base'" in robot.describe()
    robot2 = pickle.loads(pickle.dumps(robot))
    np.testing.assert_array_equal(robot2.body_fk(pose, q), plain.body_fk(pose, q))


def test_floating_joints_elsewhere_and_planar_joints_are_refused():
    text = GO2.read_text().replace(
        'name="FL_hip_joint" type="revolute"', 'name="FL_hip_joint" type="floating"'
    )
    with pytest.raises(ValueError, match=r"FL_hip_joint.*'floating' is only supported as the root joint"):
        sk.Robot.from_urdf_string(text)
    with pytest.raises(ValueError, match="'world', above the floating root joint 'root_joint', has a mass"):
        urdf.parse_urdf(
            _wrapped_go2(
                "floating", '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial>'
            )
        )
    planar = GO2.read_text().replace(
        'name="FL_hip_joint" type="revolute"', 'name="FL_hip_joint" type="planar"'
    )
    with pytest.raises(
        ValueError, match=r"FL_hip_joint.*'planar' is not supported.*two prismatic joints and a revolute"
    ):
        sk.Robot.from_urdf_string(planar)
    with pytest.raises(ValueError, match="planar"):
        sk.Chain.from_urdf(planar.encode(), tip="FL_foot")


# --------------------------------------------------------------------------- messages, types, xacro


def test_robot_from_an_arm_points_to_chain_from_urdf():
    for load in (lambda: sk.Robot.from_urdf(UR5), lambda: sk.Robot.from_urdf_string(PANDA.read_text())):
        with pytest.raises(ValueError, match=r"no roll-pitch-pitch legs.*spotkin.Chain.from_urdf"):
            load()


def test_default_tip_is_refused_when_several_chains_end():
    with pytest.raises(ValueError, match=r"tip: .*'FL_foot'.*'RR_foot'.*pass tip="):
        sk.Chain.from_urdf(GO2)
    with pytest.raises(ValueError, match="no link below link 'tool0' is moved"):
        sk.Chain.from_urdf(UR5, base="tool0")
    # two independent fingers (no mimic): two chains, and where they branch is named
    text = PANDA.read_text().replace('<mimic joint="panda_finger_joint1" multiplier="1" offset="0"/>', "")
    with pytest.raises(ValueError, match=r"panda_leftfinger.*panda_rightfinger.*meet at 'panda_hand'"):
        sk.Chain.from_urdf(text)
    assert sk.Chain.from_urdf(text, tip="panda_hand").dof == 7


def test_bad_sources_tips_and_bases(tmp_path):
    for value in (None, 3, 1.5, [str(UR5)]):
        with pytest.raises(TypeError, match="source"):
            sk.Chain.from_urdf(value)
    with pytest.raises(ValueError, match="malformed URDF"):
        sk.Chain.from_urdf(b"\x00\xff garbage")
    with pytest.raises(IsADirectoryError):
        sk.Chain.from_urdf(tmp_path)
    with pytest.raises(FileNotFoundError):
        sk.Chain.from_urdf(tmp_path / "missing.urdf")
    if os.path.exists("/dev/zero"):
        with pytest.raises(ValueError, match="larger than 64 MiB"):
            sk.Chain.from_urdf("/dev/zero")
    for name, value in (("tip", 3), ("tip", b"tool0"), ("base", 0), ("base", Path("base_link"))):
        with pytest.raises(TypeError, match=name):
            sk.Chain.from_urdf(UR5, **{name: value})
    for name, value in (("tip", "no_such_link"), ("base", "nowhere")):
        with pytest.raises(ValueError, match=f"{name}: '{value}' is not a link of 'ur5'"):
            sk.Chain.from_urdf(UR5, **{name: value})
    with pytest.raises(ValueError, match="no actuated joint between 'base_link' and 'base_link'"):
        sk.Chain.from_urdf(UR5, tip="base_link")
    assert sk.Chain.from_urdf(UR5, tip="tool0", base="shoulder_link").dof == 5


def test_seven_and_five_joint_messages_name_what_applies():
    five = sk.Chain.from_urdf(UR5, tip="wrist_2_link")
    for call in (lambda: five.ik_kind, lambda: five.ik_all(np.eye(4))):
        with pytest.raises(ValueError, match="ik_differential") as error:
            call()
        assert "free_joint" not in str(error.value)
    with pytest.raises(ValueError, match="free_joint is for 7-joint chains"):
        five.ik_all(np.eye(4), free_joint=0, free_value=0.0)


XACRO = """<?xml version="1.0"?>
<robot name="xarm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="length" value="0.3"/>
  <xacro:macro name="segment" params="i parent axis">
    <link name="link${i}"/>
    <joint name="joint${i}" type="revolute">
      <parent link="${parent}"/><child link="link${i}"/>
      <origin xyz="0 0 ${length}"/><axis xyz="${axis}"/>
      <limit lower="-1" upper="1" effort="1" velocity="1"/>
    </joint>
  </xacro:macro>
  <link name="base"/>
  <xacro:segment i="1" parent="base" axis="0 0 1"/>
  <xacro:segment i="2" parent="link1" axis="0 1 0"/>
  <xacro:segment i="3" parent="link2" axis="0 1 0"/>
  <link name="tool"/>
  <joint name="tool_joint" type="fixed">
    <parent link="link3"/><child link="tool"/><origin xyz="0.2 0 0"/>
  </joint>
</robot>
"""


def test_xacro_is_expanded_when_xacro_is_installed(tmp_path):
    pytest.importorskip("xacro")
    path = tmp_path / "arm.urdf.xacro"
    path.write_text(XACRO)
    for source in (path, str(path), XACRO, XACRO.encode()):
        chain = sk.Chain.from_urdf(source)
        assert chain.joint_names == ("joint1", "joint2", "joint3")
        # 3 segments of 0.3 up, then the tool 0.2 along x
        np.testing.assert_allclose(chain.fk(np.zeros(3))[:3, 3], [0.2, 0.0, 0.9], atol=1e-15)
        # joint 2 (0.6 up) turned by pi/2 about y: the last 0.3 segment along +x, the tool 0.2 down
        np.testing.assert_allclose(chain.fk([0.0, PI / 2, 0.0])[:3, 3], [0.3, 0.0, 0.6 - 0.2], atol=1e-15)
    with pytest.raises(ValueError, match="xacro could not expand"):
        sk.Chain.from_urdf(XACRO.replace('parent="base"', 'parent="${nowhere}"'))


def test_xacro_without_xacro_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "xacro", None)  # import xacro raises ImportError
    path = tmp_path / "arm.urdf.xacro"
    path.write_text(XACRO)
    for load in (
        lambda: sk.Chain.from_urdf(path),
        lambda: sk.Chain.from_urdf(XACRO),
        lambda: sk.Robot.from_urdf(path),
        lambda: urdf.load_urdf(path),
    ):
        with pytest.raises(ImportError, match=r'pip install "spotkin\[xacro\]".*xacro .* > robot\.urdf'):
            load()
    assert not urdf.is_xacro(UR5.read_text(), str(UR5)) and urdf.is_xacro("<robot/>", "a.xacro")


# --------------------------------------------------------------------------- command line


def _run(*argv) -> tuple[int, str]:
    out = io.StringIO()
    with redirect_stdout(out):
        code = main(list(argv))
    return code, out.getvalue()


def test_inspect_an_arm_and_a_gripper():
    code, text = _run("inspect", str(PANDA))
    assert code == 0
    assert "mimic: panda_finger_joint2 follows panda_finger_joint1 × 1 + 0" in text
    assert "to panda_hand (the default tip): 7 dof" in text
    assert "free_joint=6: 6R-spherical-shoulder" in text
    assert (
        "to panda_rightfinger: 8 dof" in text and "panda_finger_joint2 = 1 × panda_finger_joint1 + 0" in text
    )
    assert "(mimic of panda_finger_joint1)" in text and "Chain.from_urdf" in text
    code, text = _run("inspect", str(UR5))
    assert code == 0 and "to wrist_3_link (the default tip): 6 dof" in text
    assert "ik_kind '6R-three-parallel-234'" in text and "also ends at ee_link, tool0" in text
    # a legged robot is described as before
    code, text = _run("inspect", str(GO2))
    assert code == 0 and "legs (4):" in text


def test_inspect_subprocess_on_the_packaged_arm():
    result = subprocess.run(
        [sys.executable, "-m", "spotkin", "inspect", sk.robots.path("ur5")], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    assert "6R-three-parallel-234" in result.stdout


@pytest.mark.parametrize("source", [str(UR5), str(PANDA), "panda"])
@pytest.mark.parametrize("stance", ["nominal", "zero"])
def test_plot_an_arm(source, stance, tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "arm.png"
    code, text = _run("plot", source, "--out", str(out), "--stance", stance, "--size", "400x300")
    assert code == 0 and text.strip() == f"wrote {out}"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_draws_the_chain_where_fk_puts_it():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from spotkin import plot

    model = urdf.load_urdf(PANDA)
    values = {j.name: 0.3 for j in model.actuated_joints}
    fig = plt.figure()
    try:
        ax = fig.add_subplot(projection="3d")
        plot._description(ax, model, values, title="panda")
        (line,) = [x for x in ax.lines if x.get_gid() == "chain:panda_hand"]
        end = np.array([line.get_data_3d()[k][-1] for k in range(3)])
        chain = sk.Chain.from_urdf(PANDA)
        np.testing.assert_allclose(end, chain.fk(np.full(7, 0.3))[:3, 3], atol=1e-12)
    finally:
        plt.close(fig)
