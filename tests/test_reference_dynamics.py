"""The pure-Python reference dynamics (spotkin.reference.dynamics) against Pinocchio (an independent
oracle) on Spot, Go2 and a test robot with a prismatic joint, against hand-derived Lagrange closed
forms on the course's arms, and against the identities of Lagrangian mechanics (Hypothesis)."""

from __future__ import annotations

import math
import re
from functools import cache

import numpy as np
import pinocchio as pin  # the independent oracle (requirements-test.txt: pin); never skipped
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm
from scipy.spatial.transform import Rotation
from test_robot import HEXAPOD, ZOO
from urdf_helpers import joint

import spotkin as sk
from spotkin import inertia
from spotkin.reference import course_robots as course
from spotkin.reference import dynamics as rd

TOL = 1e-10  # against Pinocchio, absolute (torques up to a few hundred N m)
G0 = 9.81

# --------------------------------------------------------------------------- a test robot


def _inertial(rng) -> str:
    xyz = " ".join(f"{v:.6f}" for v in rng.uniform(-0.05, 0.05, 3))
    rpy = " ".join(f"{v:.6f}" for v in rng.uniform(-1.5, 1.5, 3))
    a, b = rng.uniform(0.001, 0.01, 2)
    c = rng.uniform(abs(a - b) + 1e-4, a + b)  # principal moments obey the triangle inequality
    return (
        f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{rng.uniform(0.1, 2):.6f}"/>'
        f'<inertia ixx="{a:.6f}" ixy="0" ixz="0" iyy="{b:.6f}" iyz="0" izz="{c:.6f}"/></inertial>'
    )


def critter_text() -> str:
    """A quadruped with inertials everywhere (rotated by their rpy): rotors fixed off each thigh, a
    massive foot link, a continuous fan on the body, and an arm whose third joint is prismatic and whose
    wrist carries a fixed hand and a continuous finger. Joints written legs interleaved."""
    rng = np.random.default_rng(17)
    links, joints = ["base", "fan"], []
    joints.append(joint("fan_joint", "continuous", "base", "fan", "-0.2 0 0.1", axis="0 0 1"))
    legs = {"LF": (0.3, 0.12), "RF": (0.3, -0.12), "LH": (-0.3, 0.12), "RH": (-0.3, -0.12)}
    for step in range(4):
        for leg, (x, y) in legs.items():
            side = 1 if y > 0 else -1
            if step == 0:
                links += [f"{leg}_hip", f"{leg}_thigh", f"{leg}_calf", f"{leg}_foot", f"{leg}_rotor"]
                joints.append(
                    joint(
                        f"{leg}_hip_joint",
                        "revolute",
                        "base",
                        f"{leg}_hip",
                        f"{x} {y} 0",
                        axis="1 0 0",
                        limits=(-0.8, 0.8),
                    )
                )
            elif step == 1:
                joints.append(
                    joint(
                        f"{leg}_thigh_joint",
                        "revolute",
                        f"{leg}_hip",
                        f"{leg}_thigh",
                        f"0 {0.08 * side} 0",
                        axis="0 1 0",
                        limits=(-2, 2),
                    )
                )
                joints.append(
                    joint(
                        f"{leg}_rotor_joint",
                        "fixed",
                        f"{leg}_hip",
                        f"{leg}_rotor",
                        f"0 {0.05 * side} 0",
                        "0.3 0 0",
                    )
                )
            elif step == 2:
                joints.append(
                    joint(
                        f"{leg}_calf_joint",
                        "revolute",
                        f"{leg}_thigh",
                        f"{leg}_calf",
                        "0.02 0 -0.22",
                        axis="0 1 0",
                        limits=(-2.6, -0.2),
                    )
                )
            else:
                joints.append(joint(f"{leg}_foot_joint", "fixed", f"{leg}_calf", f"{leg}_foot", "0 0 -0.23"))
    arm = [
        ("sh0", "base", "0.25 0 0.1", "0 0 1", "revolute"),
        ("sh1", "arm_sh0", "0 0 0.05", "0 1 0", "revolute"),
        ("el0", "arm_sh1", "0.3 0 0", "1 0 0", "prismatic"),
        ("el1", "arm_el0", "0.05 0 0.05", "1 0 0", "revolute"),
        ("wr0", "arm_el1", "0.25 0 0", "0 1 0", "revolute"),
        ("wr1", "arm_wr0", "0.05 0 0", "1 0 0", "revolute"),
    ]
    for name, parent, xyz, axis, kind in arm:
        links.append(f"arm_{name}")
        joints.append(
            joint(f"arm_{name}_joint", kind, parent, f"arm_{name}", xyz, "0.1 -0.2 0.3", axis, (-1, 1))
        )
    links += ["arm_hand", "arm_finger"]
    joints.append(joint("arm_hand_joint", "fixed", "arm_wr1", "arm_hand", "0.1 0 0", "0 0.4 0"))
    joints.append(
        joint("arm_finger_joint", "continuous", "arm_wr1", "arm_finger", "0.08 0.02 0", axis="0 1 0")
    )
    body = "".join(f'<link name="{name}">{_inertial(rng)}</link>' for name in links)
    return f'<robot name="critter">{body}{"".join(joints)}</robot>'


CRITTER = critter_text()


def with_inertials(text: str, seed: int) -> str:
    """A test URDF of tests/test_robot.py (empty links) with a random inertial on every link."""
    rng = np.random.default_rng(seed)
    return re.sub(r'<link name="([^"]+)"/>', lambda m: f'<link name="{m[1]}">{_inertial(rng)}</link>', text)


# ZOO: rotated joint frames, negative and unnormalised axes, continuous leg joints, fixed and continuous
# rotors and a z-y-y limb that is not a leg (locked into the body); HEXAPOD: six legs, joints interleaved
TEXTS = {"critter": CRITTER, "zoo": with_inertials(ZOO, 3), "hexapod": with_inertials(HEXAPOD, 4)}
CRITTER_ARM = (
    "arm_sh0_joint",
    "arm_sh1_joint",
    "arm_el0_joint",
    "arm_el1_joint",
    "arm_wr0_joint",
    "arm_wr1_joint",
)


@cache
def robot(name: str) -> sk.Robot:
    if name in TEXTS:
        return sk.Robot.from_urdf_string(TEXTS[name])
    return sk.Robot.from_urdf(sk.robots.path({"spot": "spot_with_arm", "go2": "go2"}[name]))


@cache
def pin_full(name: str, floating: bool):
    root = (pin.JointModelFreeFlyer(),) if floating else ()
    if name in TEXTS:
        return pin.buildModelFromXML(TEXTS[name], *root)
    return pin.buildModelFromUrdf(str(sk.robots.path({"spot": "spot_with_arm", "go2": "go2"}[name])), *root)


# (robot, chain link or None for the floating base, joints of a floating tree or None for the default)
CASES = {
    "spot_leg": ("spot", "front_left_foot", None),
    "spot_arm": ("spot", "arm_hand", None),
    "spot_floating": ("spot", None, None),
    "go2_leg": ("go2", "RR_foot", None),
    "go2_floating": ("go2", None, None),
    "critter_leg": ("critter", "RF_foot", None),
    "critter_arm": ("critter", "arm_hand", None),  # a prismatic joint; the finger locked into the wrist
    "critter_floating": ("critter", None, "arm"),  # legs, then the arm given by name; the fan locked
    "zoo_leg": ("zoo", "TW_toe", None),  # the continuous hip rotor hangs off the body: not in the chain
    "zoo_continuous_leg": ("zoo", "CT_foot", None),  # continuous joints (cos, sin in Pinocchio's q)
    "zoo_floating": ("zoo", None, None),
    "hexapod_floating": ("hexapod", None, None),
}


@cache
def model(case: str):
    name, link, joints = CASES[case]
    r = robot(name)
    if link is not None:
        return inertia.tree_of(r.chain(link))
    if joints == "arm":
        return inertia.tree_of(r, joints=(*r.leg_joint_names, *CRITTER_ARM))
    return inertia.tree_of(r)


@cache
def twin(case: str):
    """(Pinocchio model of exactly the tree's joints, q indices, v indices): the other joints locked at
    0 by buildReducedModel, as the tree locks them."""
    tree = model(case)
    floating = tree.root is not None
    full = pin_full(CASES[case][0], floating)
    keep = set(tree.joint_names)
    first = 2 if floating else 1  # names[0] is the universe, names[1] the free flyer
    locked = [full.getJointId(name) for name in full.names[first:] if name not in keep]
    reduced = pin.buildReducedModel(full, locked, pin.neutral(full)) if locked else full
    jm = [reduced.joints[reduced.getJointId(name)] for name in tree.joint_names]
    iq = [(j.idx_q, j.nq) for j in jm]  # nq = 2: a continuous joint, (cos q, sin q)
    iv = ([0, 1, 2, 3, 4, 5] if floating else []) + [j.idx_v for j in jm]
    assert reduced.nv == len(iv)
    return reduced, iq, iv


def random_state(tree, rng):
    n = len(tree.parents)
    nv = n + (6 if tree.root is not None else 0)
    q = rng.uniform(-1.2, 1.2, n)
    pose = None
    if tree.root is not None:
        pose = np.eye(4)
        pose[:3, :3] = Rotation.random(random_state=int(rng.integers(1 << 30))).as_matrix()
        pose[:3, 3] = rng.uniform(-1, 1, 3)
    return q, pose, rng.normal(0, 1.5, nv), rng.normal(0, 2, nv)


def pin_vectors(case, q, pose, *vs):
    reduced, iq, iv = twin(case)
    qp = pin.neutral(reduced)
    for (index, nq), value in zip(iq, q):
        qp[index : index + nq] = value if nq == 1 else (math.cos(value), math.sin(value))
    if pose is not None:
        qp[:3] = pose[:3, 3]
        qp[3:7] = Rotation.from_matrix(pose[:3, :3]).as_quat()  # (x, y, z, w), Pinocchio's order
    out = []
    for v in vs:
        vp = np.zeros(reduced.nv)
        vp[iv] = v
        out.append(vp)
    return qp, *out


def close(ours, theirs, tol=TOL):
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    assert ours.shape == theirs.shape
    assert np.abs(ours - theirs).max(initial=0) <= tol, np.abs(ours - theirs).max()


@pytest.mark.parametrize("case", list(CASES))
def test_reference_matches_pinocchio(case, rng):
    tree = model(case)
    reduced, _, iv = twin(case)
    data = reduced.createData()
    block = np.ix_(iv, iv)
    for _ in range(4):
        q, pose, qd, qdd = random_state(tree, rng)
        qp, vp, ap = pin_vectors(case, q, pose, qd, qdd)
        tau = rd.rnea(tree, q, qd, qdd, body_pose=pose)
        close(tau, pin.rnea(reduced, data, qp, vp, ap)[iv])
        A = pin.crba(reduced, data, qp)
        A = np.triu(A) + np.triu(A, 1).T  # Pinocchio fills the upper triangle
        close(rd.crba(tree, q, body_pose=pose), A[block])
        close(
            rd.gravity_torques(tree, q, body_pose=pose), pin.computeGeneralizedGravity(reduced, data, qp)[iv]
        )
        close(
            rd.nonlinear_effects(tree, q, qd, body_pose=pose), pin.nonLinearEffects(reduced, data, qp, vp)[iv]
        )
        C = pin.computeCoriolisMatrix(reduced, data, qp, vp)
        close(rd.coriolis_matrix(tree, q, qd, body_pose=pose), C[block])
        close(
            rd.aba(tree, q, qd, tau, body_pose=pose),
            pin.aba(reduced, data, qp, vp, pin.rnea(reduced, data, qp, vp, ap))[iv],
        )
        close(rd.aba(tree, q, qd, tau, body_pose=pose), qdd, 1e-9)
        close(rd.center_of_mass(tree, q, body_pose=pose), pin.centerOfMass(reduced, data, qp))
        Jc = pin.jacobianCenterOfMass(reduced, data, qp)
        close(rd.center_of_mass_jacobian(tree, q, body_pose=pose), Jc[:, iv])
        close(rd.kinetic_energy(tree, q, qd, body_pose=pose), pin.computeKineticEnergy(reduced, data, qp, vp))
        close(rd.potential_energy(tree, q, body_pose=pose), pin.computePotentialEnergy(reduced, data, qp))


def test_gravity_is_configurable_and_pinocchio_agrees(rng):
    tree = model("spot_arm")
    reduced, _, iv = twin("spot_arm")
    data = reduced.createData()
    gravity = np.array([1.0, -2.0, -3.0])
    reduced.gravity.linear = gravity
    q, _, qd, qdd = random_state(tree, rng)
    qp, vp, ap = pin_vectors("spot_arm", q, None, qd, qdd)
    try:
        close(rd.rnea(tree, q, qd, qdd, gravity), pin.rnea(reduced, data, qp, vp, ap)[iv])
    finally:
        reduced.gravity.linear = np.array([0.0, 0.0, -G0])
    close(rd.gravity_torques(tree, q, (0, 0, 0)), np.zeros(len(q)))


# --------------------------------------------------------------------------- the course's arms, by hand


def test_planar_2r_matches_lagrange():
    """Two uniform rods, m = (2, 1.5) kg, l = (0.8, 0.6) m, in the (x, y) plane, gravity along -y.
    Rod j lies along -x of frame j + 1 (DH: frame j + 1 sits at the rod's far end)."""
    rows = [(0, 0.8, 0.0, 0.0, 0.0), (0, 0.6, 0.0, 0.0, 0.0)]
    chain = sk.Chain.from_dh(rows).with_inertials(
        [2.0, 1.5],
        [[-0.4, 0, 0], [-0.3, 0, 0]],
        [
            np.diag([0, 2.0 * 0.8**2 / 12, 2.0 * 0.8**2 / 12]),
            np.diag([0, 1.5 * 0.6**2 / 12, 1.5 * 0.6**2 / 12]),
        ],
    )
    tree = inertia.tree_of(chain)
    for q in ([0.0, 0.0], [0.3, -1.1], [2.0, 2.5], [-1.0, np.pi / 2]):
        close(rd.crba(tree, q), rd.planar_2r_mass_matrix(q, (2.0, 1.5), (0.8, 0.6)), 1e-13)
        close(
            rd.gravity_torques(tree, q, (0, -G0, 0)), rd.planar_2r_gravity(q, (2.0, 1.5), (0.8, 0.6)), 1e-12
        )
    # stretched along x: A11 = m1 l1²/3 + m2 (l1² + l2²/3 + l1 l2),
    # G = g0 ((m1/2 + m2) l1 + m2 l2 / 2, m2 l2 / 2)
    A = rd.planar_2r_mass_matrix([0.0, 0.0], (2.0, 1.5), (0.8, 0.6))
    assert A[0, 0] == pytest.approx(2.0 * 0.64 / 3 + 1.5 * (0.64 + 0.36 / 3 + 0.48))
    G = rd.planar_2r_gravity([0.0, 0.0], (2.0, 1.5), (0.8, 0.6))
    np.testing.assert_allclose(G, [G0 * (2.5 * 0.8 + 0.45), G0 * 0.45])


def rrr_chain(masses=(3.0, 2.0, 1.2)):
    """The course's RRR arm (worked lengths 1, 1.05, 0.89 m) as uniform thin rods: rod 1 from the base
    up to frame 1 (along y1), rod 2 from joint 2 to frame 2 (along -x2), rod 3 from frame 3 along z3
    to the tool."""
    rows, base, tool = course.rrr_001_dh()
    m1, m2, m3 = masses
    return sk.Chain.from_dh(rows, base=base, tool=tool).with_inertials(
        masses,
        [[0, -0.5, 0], [-0.525, 0, 0], [0, 0, 0.445]],
        [
            np.diag([m1 * 1.0**2 / 12, 0, m1 * 1.0**2 / 12]),
            np.diag([0, m2 * 1.05**2 / 12, m2 * 1.05**2 / 12]),
            np.diag([m3 * 0.89**2 / 12, m3 * 0.89**2 / 12, 0]),
        ],
    )


@given(st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3))
def test_course_rrr_arm_matches_lagrange(q):
    tree = inertia.tree_of(rrr_chain())
    masses, lengths = (3.0, 2.0, 1.2), (1.0, 1.05, 0.89)
    close(rd.crba(tree, q), rd.rrr_mass_matrix(q, masses, lengths), 1e-12)
    close(rd.gravity_torques(tree, q), rd.rrr_gravity(q, masses, lengths), 1e-12)


def test_course_rrr_closed_form_values():
    """At q = (0, 0, 0) the arm is an L: rod 2 horizontal, rod 3 hanging down from its end.
    A11 = m2 l2²/3 + m3 l2² = 2 * 1.1025 / 3 + 1.2 * 1.1025; G2 = g0 (m2 l2 / 2 + m3 l2)."""
    A = rd.rrr_mass_matrix([0, 0, 0], (3.0, 2.0, 1.2), (1.0, 1.05, 0.89))
    assert A[0, 0] == pytest.approx(2 * 1.1025 / 3 + 1.2 * 1.1025)
    assert A[2, 2] == pytest.approx(1.2 * 0.89**2 / 3)
    G = rd.rrr_gravity([0, 0, 0], (3.0, 2.0, 1.2), (1.0, 1.05, 0.89))
    np.testing.assert_allclose(G, [0, G0 * (1.05 + 1.2 * 1.05), 0], atol=1e-14)


def arm_002_chain():
    """The course's three-joint arm (illustrative lengths a = 0.10, 0.12, 0.09 m) as uniform thin rods
    of 0.5, 0.4 and 0.3 kg: rod 1 up the vertical axis to frame 1 (along y1), rods 2 and 3 along -x of
    frames 2 and 3 (each DH row ends with TransX(a))."""
    rows, base, tool = course.arm_002_dh()
    return sk.Chain.from_dh(rows, base=base, tool=tool).with_inertials(
        [0.5, 0.4, 0.3],
        [[0, -0.05, 0], [-0.06, 0, 0], [-0.045, 0, 0]],
        [
            np.diag([0.5 * 0.10**2 / 12, 0, 0.5 * 0.10**2 / 12]),
            np.diag([0, 0.4 * 0.12**2 / 12, 0.4 * 0.12**2 / 12]),
            np.diag([0, 0.3 * 0.09**2 / 12, 0.3 * 0.09**2 / 12]),
        ],
    )


@given(st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3))
def test_course_three_joint_arm_planar_block_is_the_2r_arm(q):
    """Joints 2 and 3 turn in the arm's vertical plane: their block of A is the planar 2R arm's, with
    link 3 at q3 - 90° from link 2 (T12 = RotZ(q2) TransY(a2), T23 = RotZ(q3) TransX(a3)); the
    turntable q1 does not enter it. Gravity (along -z0, in that plane) gives G1 = 0."""
    tree = inertia.tree_of(arm_002_chain())
    A = rd.crba(tree, q)
    planar = rd.planar_2r_mass_matrix([0.0, q[2] - np.pi / 2], (0.4, 0.3), (0.12, 0.09))
    close(A[1:, 1:], planar, 1e-15)
    close(A[0, 1:], np.zeros(2), 1e-15)
    assert abs(rd.gravity_torques(tree, q)[0]) < 1e-15


# --------------------------------------------------------------------------- identities

IDENTITY_CASES = ["rrr", "arm_002", "spot_arm", "go2_leg", "critter_arm", "go2_floating", "critter_floating"]
COURSE_CHAINS = {"rrr": rrr_chain, "arm_002": arm_002_chain}


def identity_model(case):
    return inertia.tree_of(COURSE_CHAINS[case]()) if case in COURSE_CHAINS else model(case)


def twist_step(pose, twist, h):
    """pose · exp(h [twist]) for a body-frame twist [v; w]."""
    hat = np.zeros((4, 4))
    hat[:3, :3] = rd.skew(twist[3:])
    hat[:3, 3] = twist[:3]
    return pose @ expm(h * hat)


def moved(tree, q, pose, direction, h):
    """(q, pose) moved by h along a velocity direction (6 + n for a floating base)."""
    if tree.root is None:
        return q + h * direction, None
    return q + h * direction[6:], twist_step(pose, direction[:6], h)


seeds = st.integers(0, 2**32 - 1)


@pytest.mark.parametrize("case", IDENTITY_CASES)
@settings(max_examples=12)
@given(seed=seeds)
def test_mass_matrix_is_symmetric_positive_definite_and_gives_the_kinetic_energy(case, seed):
    tree = identity_model(case)
    q, pose, qd, _ = random_state(tree, np.random.default_rng(seed))
    A = rd.crba(tree, q, body_pose=pose)
    np.testing.assert_array_equal(A, A.T)
    assert np.linalg.eigvalsh(A).min() > 0
    close(0.5 * qd @ A @ qd, rd.kinetic_energy(tree, q, qd, body_pose=pose), 1e-11)


@pytest.mark.parametrize("case", ["rrr", "arm_002", "spot_arm", "critter_arm"])
@settings(max_examples=12)
@given(seed=seeds)
def test_kinetic_energy_equals_the_links_from_the_compiled_frames(case, seed):
    """Each body's velocity by central differences of Chain.frames (the compiled FK), then
    m |v_com|² / 2 + w^T R I R^T w / 2, summed: the mass matrix's quadratic form."""
    chain = COURSE_CHAINS[case]() if case in COURSE_CHAINS else robot(CASES[case][0]).chain(CASES[case][1])
    rng = np.random.default_rng(seed)
    q, qd = rng.uniform(-1.2, 1.2, chain.dof), rng.normal(0, 1.5, chain.dof)
    h = 1e-6
    F, Fp, Fm = chain.frames(q), chain.frames(q + h * qd), chain.frames(q - h * qd)
    m, c, inertias = chain.inertials
    energy = 0.0
    for j in range(chain.dof):
        R, dR = F[j + 1][:3, :3], (Fp[j + 1][:3, :3] - Fm[j + 1][:3, :3]) / (2 * h)
        W = dR @ R.T
        w = np.array([W[2, 1], W[0, 2], W[1, 0]])
        centre = lambda T, j=j: T[j + 1][:3, :3] @ c[j] + T[j + 1][:3, 3]  # noqa: E731
        v = (centre(Fp) - centre(Fm)) / (2 * h)
        energy += 0.5 * m[j] * v @ v + 0.5 * w @ R @ inertias[j] @ R.T @ w
    expected = 0.5 * qd @ rd.crba(inertia.tree_of(chain), q) @ qd
    assert energy == pytest.approx(expected, rel=1e-7, abs=1e-9)


@pytest.mark.parametrize("case", IDENTITY_CASES)
@settings(max_examples=10)
@given(seed=seeds)
def test_gravity_is_the_gradient_of_the_potential_energy(case, seed):
    tree = identity_model(case)
    rng = np.random.default_rng(seed)
    q, pose, _, _ = random_state(tree, rng)
    G = rd.gravity_torques(tree, q, body_pose=pose)
    h = 1e-5
    numeric = np.zeros_like(G)
    for k in range(len(G)):
        e = np.zeros(len(G))
        e[k] = 1.0
        up = rd.potential_energy(tree, *_config(moved(tree, q, pose, e, h)))
        down = rd.potential_energy(tree, *_config(moved(tree, q, pose, e, -h)))
        numeric[k] = (up - down) / (2 * h)
    close(G, numeric, 1e-6 * max(1.0, np.abs(G).max()))


def _config(state):
    q, pose = state
    return q, rd.GRAVITY, pose


@pytest.mark.parametrize("case", IDENTITY_CASES)
@settings(max_examples=10)
@given(seed=seeds)
def test_equation_of_motion_aba_and_skew_symmetry(case, seed):
    tree = identity_model(case)
    q, pose, qd, qdd = random_state(tree, np.random.default_rng(seed))
    A = rd.crba(tree, q, body_pose=pose)
    C = rd.coriolis_matrix(tree, q, qd, body_pose=pose)
    G = rd.gravity_torques(tree, q, body_pose=pose)
    tau = rd.rnea(tree, q, qd, qdd, body_pose=pose)
    scale = max(1.0, np.abs(tau).max())
    close(tau, A @ qdd + C @ qd + G, 1e-11 * scale)
    close(rd.nonlinear_effects(tree, q, qd, body_pose=pose), C @ qd + G, 1e-11 * scale)
    close(rd.aba(tree, q, qd, tau, body_pose=pose), qdd, 1e-9 * max(1.0, np.abs(qdd).max()))
    h = 1e-6
    qa, pa = moved(tree, q, pose, qd, h)
    qb, pb = moved(tree, q, pose, qd, -h)
    A_dot = (rd.crba(tree, qa, body_pose=pa) - rd.crba(tree, qb, body_pose=pb)) / (2 * h)
    N = A_dot - 2 * C
    close(N, -N.T, 1e-6 * max(1.0, np.abs(A_dot).max()))


@pytest.mark.parametrize("case", ["go2_floating", "critter_floating"])
@settings(max_examples=10)
@given(seed=seeds)
def test_floating_mass_matrix_ignores_the_body_pose(case, seed):
    tree = model(case)
    rng = np.random.default_rng(seed)
    q, pose, _, _ = random_state(tree, rng)
    _, other, _, _ = random_state(tree, rng)
    close(rd.crba(tree, q, body_pose=pose), rd.crba(tree, q, body_pose=other), 1e-12)


# --------------------------------------------------------------------------- statics


def spot_standing(stance, gravity=rd.GRAVITY, q=None):
    tree = model("spot_floating")
    pose = np.eye(4)
    pose[2, 3] = 0.5
    q = np.zeros(len(tree.joint_names)) if q is None else q
    return tree, pose, q, rd.standing_torques(tree, pose, q, stance, gravity)


def test_standing_on_four_feet_balances_and_holds():
    tree, pose, q, result = spot_standing([True] * 4)
    assert result.status == rd.STANCE_OK and result.margin > 0
    weight = 56.351 * G0  # every link of the file, the arm included
    np.testing.assert_allclose(result.forces.sum(axis=0), [0, 0, weight], atol=1e-9)
    assert (result.forces[:, 2] > 0).all()
    # the floating-base rows of G - sum J^T f vanish: the forces hold the body
    G = rd.gravity_torques(tree, q, body_pose=pose)
    jacobians = rd.body_jacobians(tree, q, body_pose=pose)
    residual = G.copy()
    for i, f in enumerate(result.forces):
        body = int(tree.feet[i])
        T = rd._state(tree, q, pose).world[body]
        point = T[:3, :3] @ tree.foot_points[i] + T[:3, 3]
        residual -= rd.joint_torques_from_forces(rd.point_jacobian(jacobians[body + 1], point), f)
    close(residual[:6], np.zeros(6), 1e-9)
    close(residual[6:], result.tau, 1e-12)


def test_standing_torques_match_pinocchio_jacobians():
    _, pose, q, result = spot_standing([True] * 4)
    reduced, _, iv = twin("spot_floating")
    data = reduced.createData()
    (qp,) = pin_vectors("spot_floating", q, pose)
    pin.computeJointJacobians(reduced, data, qp)
    pin.framesForwardKinematics(reduced, data, qp)
    tau = pin.computeGeneralizedGravity(reduced, data, qp)
    for leg, f in zip(("front_left", "front_right", "rear_left", "rear_right"), result.forces):
        frame = reduced.getFrameId(f"{leg}_foot")
        J = pin.getFrameJacobian(reduced, data, frame, pin.LOCAL_WORLD_ALIGNED)[:3]
        tau = tau - J.T @ f
    close(result.tau, tau[iv][6:], 1e-9)
    close(tau[iv][:6], np.zeros(6), 1e-9)


def test_three_feet_share_the_weight_by_barycentric_weights():
    """On level ground, three feet carry the weight in the proportions of the centre of mass's
    barycentric coordinates in their triangle (moments about the centre of mass)."""
    tree, pose, q, result = spot_standing([True, True, True, False])
    assert result.status == rd.STANCE_OK
    com = rd.center_of_mass(tree, q, body_pose=pose)
    feet = rd.standing_torques(tree, pose, q, [0, 1, 2])
    state = rd._state(tree, q, pose)
    points = [
        state.world[int(tree.feet[i])][:3, :3] @ tree.foot_points[i] + state.world[int(tree.feet[i])][:3, 3]
        for i in range(3)
    ]
    M = np.vstack([np.ones(3), np.array(points)[:, :2].T])
    weights = np.linalg.solve(M, [1.0, com[0], com[1]])
    np.testing.assert_allclose(result.forces[:, 2], 56.351 * G0 * weights, rtol=1e-9)
    np.testing.assert_array_equal(feet.forces, result.forces)


def test_stances_that_cannot_balance_are_flagged():
    for stance in ([True, False, False, False], [0, 3], []):
        _, _, _, result = spot_standing(stance)
        assert result.status == rd.STANCE_UNBALANCED
        # the weight carried (no foot: all of it left), the moment left in the residual, finite torques
        assert np.isfinite(result.tau).all() and np.isfinite(result.forces).all()
        np.testing.assert_allclose(
            result.forces.sum(axis=0) + result.residual[:3], 56.351 * G0 * np.eye(3)[2]
        )
        assert np.abs(result.residual).max() > 1e-3
    assert spot_standing([0, 3])[3].margin < 0
    # the arm puts Spot's centre of mass ahead of the body's centre, which the diagonal from the front
    # left to the rear right foot crosses: on the left and rear feet, it projects outside their triangle
    _, _, _, result = spot_standing([0, 2, 3])
    assert result.status == rd.STANCE_OUTSIDE and result.margin < 0
    assert (result.forces[:, 2] < 0).any()
    assert np.isfinite(result.tau).all()
    with pytest.raises(ValueError, match="stance_feet"):
        spot_standing([0, 4])
    with pytest.raises(ValueError, match="stance_feet"):
        spot_standing([True, False])


def test_status_follows_the_documented_rule(rng):
    tree = model("go2_floating")
    pose = np.eye(4)
    pose[2, 3] = 0.3
    seen = set()
    for _ in range(40):
        tilt = rng.uniform(0, 0.8)
        heading = rng.uniform(-np.pi, np.pi)
        g = G0 * np.array([np.sin(tilt) * np.cos(heading), np.sin(tilt) * np.sin(heading), -np.cos(tilt)])
        stance = rng.random(4) < 0.8
        result = rd.standing_torques(tree, pose, rng.uniform(-0.3, 0.3, 12), stance, g)
        seen.add(result.status)
        if result.status == rd.STANCE_UNBALANCED:
            assert np.isfinite(result.tau).all() and np.linalg.norm(result.residual) > 1e-9 * 16.085 * G0
            continue
        up = -g / G0
        normals = result.forces @ up
        if result.status == rd.STANCE_OK:
            assert (normals >= -1e-9 * 16.085 * G0).all()
        else:
            assert (normals < 0).any()
            assert (result.margin > 0) == (result.status == rd.STANCE_PULLING)
    assert {rd.STANCE_OK, rd.STANCE_UNBALANCED} <= seen


def test_joint_torques_from_forces_is_the_transpose():
    J = np.arange(12.0).reshape(3, 4)
    np.testing.assert_array_equal(rd.joint_torques_from_forces(J, [1, 0, -1]), J[0] - J[2])
    with pytest.raises(ValueError, match="F must have shape"):
        rd.joint_torques_from_forces(J, [1, 0])
    with pytest.raises(ValueError, match="J must have shape"):
        rd.joint_torques_from_forces(np.zeros(3), [1, 0, 0])


# --------------------------------------------------------------------------- bad input


def test_bad_shapes_name_the_argument():
    arm, legs = model("spot_arm"), model("go2_floating")
    with pytest.raises(ValueError, match="q must have shape"):
        rd.rnea(arm, np.zeros(5), np.zeros(6), np.zeros(6))
    with pytest.raises(ValueError, match="qd must have shape"):
        rd.rnea(arm, np.zeros(6), np.zeros(7), np.zeros(6))
    with pytest.raises(ValueError, match="qdd must have shape"):
        rd.rnea(arm, np.zeros(6), np.zeros(6), np.zeros(5))
    with pytest.raises(ValueError, match="tau must have shape"):
        rd.aba(arm, np.zeros(6), np.zeros(6), np.zeros(5))
    with pytest.raises(ValueError, match="gravity must have shape"):
        rd.gravity_torques(arm, np.zeros(6), (0, -9.81))
    with pytest.raises(ValueError, match="body_pose"):
        rd.crba(legs, np.zeros(12))
    with pytest.raises(ValueError, match="body_pose"):
        rd.crba(arm, np.zeros(6), body_pose=np.eye(4))
    with pytest.raises(ValueError, match="body_pose must have shape"):
        rd.crba(legs, np.zeros(12), body_pose=np.eye(3))
    with pytest.raises(ValueError, match="qd must have shape"):
        rd.coriolis_matrix(legs, np.zeros(12), np.zeros(12), body_pose=np.eye(4))
    with pytest.raises(ValueError, match="floating-base"):
        rd.standing_torques(arm, np.eye(4), np.zeros(6), [0])
