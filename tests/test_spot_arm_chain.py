"""The Spot Arm is a Chain: the same object whichever way the robot was loaded (``sk.Spot()`` or
``sk.Robot.from_urdf``), every chain method on it (frames, point Jacobians, differential IK, the
dynamics from the URDF's inertials) answering as the plain chain of the same joints does, and its own
closed form (FK, Jacobian, all 8 IK solutions) where it overrides them."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import spotkin as sk
from spotkin import robots

URDF_NAMES = ("arm_sh0", "arm_sh1", "arm_el0", "arm_el1", "arm_wr0", "arm_wr1")
SDK_NAMES = ("arm0.sh0", "arm0.sh1", "arm0.el0", "arm0.el1", "arm0.wr0", "arm0.wr1")


@pytest.fixture(scope="module")
def loaded():
    """(Spot's arm, the arm of Spot loaded from its URDF, the plain chain of the same joints)."""
    robot = sk.Robot.from_urdf(robots.path("spot_with_arm"))
    return sk.Spot().arm, robot.arm, robot.chain("arm_hand")


def configurations(arm, n, seed=0):
    limits = arm.limits
    return np.random.default_rng(seed).uniform(limits[:, 0] + 0.05, limits[:, 1] - 0.05, (n, 6))


def test_both_loads_give_a_spot_arm_with_its_names(loaded):
    spot_arm, urdf_arm, chain = loaded
    assert type(spot_arm) is sk.SpotArm and type(urdf_arm) is sk.SpotArm and type(chain) is sk.Chain
    assert isinstance(spot_arm, sk.Chain)
    assert spot_arm.joint_names == SDK_NAMES and urdf_arm.joint_names == URDF_NAMES
    np.testing.assert_array_equal(spot_arm.limits, urdf_arm.limits)
    np.testing.assert_array_equal(spot_arm.limits, chain.limits)
    q = configurations(spot_arm, 200)
    T = spot_arm.fk(q)
    np.testing.assert_array_equal(urdf_arm.fk(q), T)
    a, b = spot_arm.ik_all(T), urdf_arm.ik_all(T)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.status, b.status)
    # both carry the URDF's mass properties: the arm has dynamics whichever way it was loaded
    assert spot_arm.inertials is not None and urdf_arm.inertials is not None
    np.testing.assert_array_equal(spot_arm.gravity(q), urdf_arm.gravity(q))


def test_the_closed_form_agrees_with_the_chain_it_overrides(loaded):
    """fk and jacobian by the arm's closed form against the chain's kernels; the 8 IK solutions against
    the chain's own 6R solver (an independent closed form), as sets."""
    arm, _, chain = loaded
    q = configurations(arm, 300, seed=1)
    np.testing.assert_allclose(arm.fk(q), chain.fk(q), atol=1e-14)
    np.testing.assert_allclose(arm.jacobian(q), chain.jacobian(q), atol=1e-14)
    T = chain.fk(q)
    ours, theirs = arm.ik_all(T), chain.ik_all(T)
    np.testing.assert_array_equal(ours.exact, ours.exists)  # the closed form is exact where it exists
    assert (ours.status == sk.Status.OK).all()
    assert (ours.valid.sum(-1) == theirs.valid.sum(-1)).all()
    for a, b, va, vb in zip(ours.q, theirs.q, ours.valid, theirs.valid):
        wrap = lambda x: np.round(np.mod(x + np.pi, 2 * np.pi) - np.pi, 7)  # noqa: E731
        np.testing.assert_allclose(
            np.array(sorted(map(tuple, wrap(a[va])))), np.array(sorted(map(tuple, wrap(b[vb])))), atol=2e-7
        )
    # the generating configuration is among the solutions
    assert np.any(np.abs(ours.q - q[:, None, :]).max(-1) < 1e-9, axis=-1).all()


@pytest.mark.parametrize(
    ("method", "args"),
    [
        ("frames", ()),
        ("position_jacobian", ()),
        ("jacobian", ("tool",)),
        ("jacobian", (2,)),
        ("gravity", ()),
        ("mass_matrix", ()),
        ("inverse_dynamics", ("qd", "qd")),
        ("nonlinear_effects", ("qd",)),
        ("coriolis_matrix", ("qd",)),
        ("forward_dynamics", ("qd", "qd")),
        ("center_of_mass", ()),
        ("center_of_mass_jacobian", ()),
        ("kinetic_energy", ("qd",)),
        ("potential_energy", ()),
        ("joint_torques_from_forces", ("force",)),
    ],
)
def test_every_chain_method_answers_as_the_plain_chain(loaded, method, args):
    arm, _, chain = loaded
    q = configurations(arm, 7, seed=2)
    rng = np.random.default_rng(3)
    values = {"qd": rng.normal(size=(7, 6)), "force": rng.normal(size=(7, 6))}
    call = [q, *(values.get(a, a) for a in args)]
    np.testing.assert_allclose(
        getattr(arm, method)(*call), getattr(chain, method)(*call), rtol=1e-12, atol=1e-12
    )


def test_differential_ik_and_the_chain_queries(loaded):
    arm, _, chain = loaded
    q = configurations(arm, 4, seed=4)
    T = chain.fk(q)
    start = q + 0.05
    a, b = arm.ik_differential(T, start), chain.ik_differential(T, start)
    np.testing.assert_allclose(a[0], b[0], atol=1e-9)
    assert a[1].converged.all()
    np.testing.assert_allclose(arm.fk(a[0]), T, atol=2e-6)  # within the default tolerances, 1e-6
    assert arm.ik_kind == chain.ik_kind == "6R-spherical-wrist"
    np.testing.assert_array_equal(arm.lower, chain.lower)
    np.testing.assert_array_equal(arm.sigma, np.zeros(6, dtype=np.int8))


def test_with_limits_rebuilds_the_closed_form(loaded):
    arm, _, _ = loaded
    q = configurations(arm, 50, seed=5)
    T = arm.fk(q)
    narrow = arm.with_limits({"arm0.el1": (-0.2, 0.2)})
    assert type(narrow) is sk.SpotArm and narrow.inertials is arm.inertials
    assert narrow.joint_names == arm.joint_names
    sol = narrow.ik_all(T)
    assert (np.abs(sol.q[..., 3][sol.valid]) <= 0.2 + 1e-12).all()
    assert arm.ik_all(T).valid.sum() > sol.valid.sum()
    # the limits apply to the inherited chain methods too (differential IK clamps to them)
    np.testing.assert_array_equal(narrow.limits[3], [-0.2, 0.2])
    unlimited = arm.with_limits(np.tile([-np.inf, np.inf], (6, 1)))
    assert np.isinf(unlimited.limits).all() and unlimited.ik_all(T).valid.all()


def test_pickles_keep_names_inertials_and_limits(loaded):
    arm = loaded[0].with_limits({"arm0.sh0": (-1.0, 1.0)})
    copy = pickle.loads(pickle.dumps(arm))
    assert type(copy) is sk.SpotArm and copy.joint_names == arm.joint_names
    np.testing.assert_array_equal(copy.limits, arm.limits)
    q = configurations(arm, 5, seed=6)
    np.testing.assert_array_equal(copy.gravity(q), arm.gravity(q))
    np.testing.assert_array_equal(copy.ik_all(arm.fk(q)).q, arm.ik_all(arm.fk(q)).q)
    plain = sk.SpotArm()
    assert plain.inertials is None and pickle.loads(pickle.dumps(plain)).inertials is None
    with pytest.raises(ValueError, match=r"chain.with_inertials\(mass, com, inertia\)"):  # how to give some
        plain.gravity(q)


def test_from_chain_recognises_the_structure_only(loaded):
    _, _, chain = loaded
    arm = sk.SpotArm.from_chain(chain)
    assert type(arm) is sk.SpotArm and arm.joint_names == URDF_NAMES
    assert sk.SpotArm.from_chain(arm) is arm
    # a rotated tool is kept whole (the hand length then 0)
    R = sk.body_transform([0.0, 0.0, 0.0, 0.3, -0.2, 0.1])
    tooled = sk.Chain.from_joints(*chain._joints, tool=chain.tool @ R, limits=chain.limits)
    other = sk.SpotArm.from_chain(tooled)
    q = configurations(chain, 20, seed=7)
    np.testing.assert_allclose(other.fk(q), tooled.fk(q), atol=1e-14)
    back, status = other.ik(other.fk(q), seed=q)
    assert (status == sk.Status.OK).all() and np.abs(back - q).max() < 1e-9
    # another structure: None (a UR5-like arm, a leg, a tilted axis, a moved wrist)
    ur5 = sk.Chain.from_dh(
        [
            (0, 0, np.pi / 2, 0.0892, 0),
            (0, -0.425, 0, 0, 0),
            (0, -0.392, 0, 0, 0),
            (0, 0, np.pi / 2, 0.1093, 0),
            (0, 0, -np.pi / 2, 0.0946, 0),
            (0, 0, 0, 0.0823, 0),
        ]
    )
    assert sk.SpotArm.from_chain(ur5) is None
    assert sk.SpotArm.from_chain(sk.Robot.from_urdf(robots.path("go2")).chain("FL_foot")) is None
    placements, axes, types = chain._joints
    tilted = axes.copy()
    tilted[3] = (1.0, 1e-6, 0.0)
    assert sk.SpotArm.from_chain(sk.Chain.from_joints(placements, tilted, types)) is None
    moved = placements.copy()
    moved[4, 1, 3] = 0.01  # an offset between the wrist axes: no longer a spherical wrist
    assert sk.SpotArm.from_chain(sk.Chain.from_joints(moved, axes, types)) is None
    with pytest.raises(TypeError, match="chain"):
        sk.SpotArm.from_chain(sk.Spot().leg("fl"))


def test_solvers_share_one_interface():
    """Legs, the Spot Arm and chains answer the same protocol: dof, limits, joint_names, fk, jacobian,
    ik_all (every branch with its validity and status) and ik (one, with a status)."""
    spot = sk.Spot()
    solvers = [spot.leg("fl"), spot.arm, sk.Robot.from_urdf(robots.path("go2")).chain("FL_foot")]
    for solver in solvers:
        assert solver.limits.shape == (solver.dof, 2) and len(solver.joint_names) == solver.dof
        limits = solver.limits
        q = np.random.default_rng(8).uniform(limits[:, 0] + 0.1, limits[:, 1] - 0.1, (10, solver.dof))
        out = solver.fk(q)
        target = out[..., :3, 3] if solver.dof == 3 and out.shape[-2:] == (4, 4) else out
        assert solver.jacobian(q).shape[-1] == solver.dof
        sol = solver.ik_all(target)
        assert sol.q.shape[:-2] == (10,) and sol.valid.shape == sol.exists.shape and sol.status.shape == (10,)
        back, status = solver.ik(target, q)
        assert (status == sk.Status.OK).all()
        np.testing.assert_allclose(back, q, atol=1e-8)


def test_a_legs_lengths_are_not_its_limits():
    """``upper``/``lower`` mean joint limits on a chain; a leg's link lengths are ``upper_length`` and
    ``lower_length``, and the old names warn (and still answer the lengths)."""
    leg = sk.Leg(hip_offset=0.11, upper=0.32, lower=0.34, knee_offset=0.02, side="left")
    assert (leg.upper_length, leg.lower_length) == (0.32, 0.34)
    with pytest.warns(DeprecationWarning, match="upper_length"):
        assert leg.upper == 0.32
    with pytest.warns(DeprecationWarning, match="lower_length"):
        assert leg.lower == 0.34
    # the knee at full stretch is the two lengths plus the offset, as fk says
    p = leg.fk([0.0, 0.0, -np.arctan2(0.02, 0.32)])
    assert np.hypot(0.02, 0.32) + 0.34 == pytest.approx(np.hypot(p[0], p[2]), abs=1e-12)
