"""Centres of mass and energies: Chain.center_of_mass, center_of_mass_jacobian, kinetic_energy and
potential_energy (fixed base) and FloatingBase.kinetic_energy / potential_energy, against Pinocchio
(centerOfMass, jacobianCenterOfMass, computeKineticEnergy, computePotentialEnergy) on Spot's and Go2's
chains and free-flyers, against the pure-Python reference, and against their own definitions:
G(q) = dU/dq and J_com by central differences, T = v^T A v / 2 > 0."""

from __future__ import annotations

import numpy as np
import pytest
from test_dynamics import CHAINS, FLOATING, Fixed, Floating, close

import spotkin as sk
from spotkin import dynamics as dyn
from spotkin import inertia
from spotkin.reference import dynamics as rd

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

pin = pytest.importorskip("pinocchio")


@pytest.fixture(scope="module", params=sorted(CHAINS))
def fixed(request):
    return Fixed(request.param)


@pytest.fixture(scope="module", params=sorted(FLOATING))
def floating(request):
    return Floating(request.param)


def test_chain_energies_match_pinocchio_and_the_reference(fixed):
    rng = np.random.default_rng(3)
    chain, m, d = fixed.chain.with_inertials(*fixed.inertials), fixed.model, fixed.data
    tree = inertia.tree_of(chain)
    q, qd, _ = fixed.random(rng, (12,))
    g = np.array([0.3, -0.2, -9.7])
    com, J = chain.center_of_mass(q), chain.center_of_mass_jacobian(q)
    T, U = chain.kinetic_energy(q, qd), chain.potential_energy(q, g)
    assert com.shape == (12, 3) and J.shape == (12, 3, chain.dof) and T.shape == U.shape == (12,)
    pin_gravity = m.gravity.linear.copy()
    m.gravity.linear = g
    try:
        for k in range(12):
            qp, vp = fixed.to_pin(q[k]), fixed.to_pin(qd[k])
            close(com[k], pin.centerOfMass(m, d, qp))
            close(J[k], pin.jacobianCenterOfMass(m, d, qp)[:, fixed.idx])
            close(T[k], pin.computeKineticEnergy(m, d, qp, vp))
            close(U[k], pin.computePotentialEnergy(m, d, qp))
            close(com[k], rd.center_of_mass(tree, q[k]))
            close(T[k], rd.kinetic_energy(tree, q[k], qd[k]))
            close(U[k], rd.potential_energy(tree, q[k], g))
    finally:
        m.gravity.linear = pin_gravity


def test_chain_energies_by_their_definitions(fixed):
    """G(q) = dU/dq, d com = J_com dq (central differences), T = qd^T A qd / 2 > 0 for qd != 0."""
    rng = np.random.default_rng(4)
    chain = fixed.chain.with_inertials(*fixed.inertials)
    q, qd, _ = fixed.random(rng, (5,))
    h = 1e-6
    steps = np.eye(chain.dof) * h
    dU = (chain.potential_energy(q[:, None] + steps) - chain.potential_energy(q[:, None] - steps)) / (2 * h)
    close(dU, chain.gravity(q), 1e-7)
    dcom = (chain.center_of_mass(q[:, None] + steps) - chain.center_of_mass(q[:, None] - steps)) / (2 * h)
    close(np.swapaxes(dcom, -1, -2), chain.center_of_mass_jacobian(q), 1e-7)
    T = chain.kinetic_energy(q, qd)
    assert (T > 0).all()
    close(T, 0.5 * np.einsum("ni,nij,nj->n", qd, chain.mass_matrix(q), qd))


def test_floating_energies_match_pinocchio(floating):
    rng = np.random.default_rng(5)
    fl, m, d = floating, floating.model, floating.data
    total = sum(inertia.mass for inertia in m.inertias[1:])
    assert abs(fl.fb.mass - total) <= 1e-12 * total
    for _ in range(8):
        q, v, _ = fl.random(rng)
        qp, vp = fl.to_pin(q, fl.iq), fl.to_pin(v, fl.iv)
        close(fl.fb.kinetic_energy(q, v), pin.computeKineticEnergy(m, d, qp, vp))
        close(fl.fb.potential_energy(q), pin.computePotentialEnergy(m, d, qp))


def test_batches_dtypes_nan_and_errors():
    chain = sk.Robot.from_urdf(sk.robots.path("go2")).chain("FL_foot")
    rng = np.random.default_rng(6)
    q, qd = rng.uniform(-1, 1, (2, 4, 1, 3))
    T = chain.kinetic_energy(q, qd[0, 0])  # qd (3,) broadcasts
    assert T.shape == (4, 1)
    assert chain.kinetic_energy(q[0, 0], qd[0, 0]).shape == ()
    U = chain.potential_energy(q, np.tile([0.0, 0.0, -9.81], (4, 1, 1)))
    assert U.shape == (4, 1)
    f32 = chain.kinetic_energy(q.astype(np.float32), qd.astype(np.float32))
    assert f32.dtype == np.float32 and chain.center_of_mass(q.astype(np.float32)).dtype == np.float32
    close(f32, chain.kinetic_energy(q, qd), 1e-5)
    bad = q.reshape(4, 3).copy()
    bad[1, 0] = np.nan
    speeds = qd.reshape(4, 3).copy()
    speeds[2, 1] = np.inf
    T, U, com = chain.kinetic_energy(bad, speeds), chain.potential_energy(bad), chain.center_of_mass(bad)
    assert np.isnan(T[[1, 2]]).all() and np.isfinite(T[[0, 3]]).all()
    assert np.isnan(U[1]) and np.isfinite(U[[0, 2, 3]]).all() and np.isnan(com[1]).all()
    assert chain.kinetic_energy(np.zeros((0, 3)), np.zeros(3)).shape == (0,)
    with pytest.raises(ValueError, match=r"qd must have shape \(\.\.\., 3\)"):
        chain.kinetic_energy(q, np.zeros(4))
    with pytest.raises(ValueError, match="gravity"):
        chain.potential_energy(q, np.zeros(2))
    with pytest.raises(ValueError, match="broadcast"):
        chain.kinetic_energy(np.zeros((5, 3)), np.zeros((4, 3)))
    with pytest.raises(TypeError):
        chain.center_of_mass("q")
    with pytest.raises(ValueError, match="inertial"):
        dyn.center_of_mass(sk.Chain.from_dh([(0, 0.0, 0.0, 0.3, 0.0)]), np.zeros(1))


def test_huge_joint_angles_give_the_result_of_their_exact_remainder():
    """A revolute joint angle beyond 1e5 rad is reduced exactly (libm) before the dynamics kernels, as
    in the kinematics; a prismatic displacement never is."""
    import math

    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    chain = go2.chain("FL_foot")
    rng = np.random.default_rng(8)
    q, qd, qdd = rng.uniform(-1, 1, (3, 4, 3))
    huge = q.copy()
    huge[:, 1] = [1e6, 3e15, -7e300, 2.5e38]
    exact = np.vectorize(lambda x: math.atan2(math.sin(x), math.cos(x)))(huge)
    for method, args in (
        ("inverse_dynamics", (qd, qdd)),
        ("mass_matrix", ()),
        ("forward_dynamics", (qd, qdd)),
        ("coriolis_matrix", (qd,)),
        ("center_of_mass", ()),
    ):
        got, want = getattr(chain, method)(huge, *args), getattr(chain, method)(exact, *args)
        close(got, want, 1e-12)
    floating = go2.floating_base
    qf = go2.floating_q(np.array([0.1, 0.0, 0.3, 0.0, 0.0, 0.0]), np.tile(q[0], 4))
    qf_huge, qf_exact = qf.copy(), qf.copy()
    qf_huge[8], qf_exact[8] = 4e20, math.atan2(math.sin(4e20), math.cos(4e20))
    close(floating.mass_matrix(qf_huge), floating.mass_matrix(qf_exact), 1e-12)
    qf_far = qf.copy()
    qf_far[0] = 4e20  # the body's position is a length: never reduced
    assert floating.center_of_mass(qf_far)[0] > 1e20
    prismatic = sk.Chain.from_dh([(1, 0.0, 0.0, 0.0, 0.0), (0, 0.0, 0.0, 0.3, 0.0)]).with_inertials(
        [1.0, 2.0], np.zeros((2, 3)), np.tile(np.eye(3) * 0.01, (2, 1, 1))
    )
    far = prismatic.center_of_mass(np.array([1e7, 0.3]))  # 1e7 m along the slide (z), not an angle
    close(far - [0.0, 0.0, 1e7], prismatic.center_of_mass(np.array([0.0, 0.3])), 1e-9)
