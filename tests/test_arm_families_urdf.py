"""A quadruped carrying a UR/Z1-type arm (axes 2, 3, 4 parallel) from its URDF: ``robot.arm`` is a
closed-form 6R chain of the parallel family, solved with every branch and checked by FK round
trips and against the chain's own DH-free POE reference."""

from __future__ import annotations

import numpy as np
from urdf_helpers import go2_with_z1

import spotkin as sk
from spotkin.reference import ik6r


def test_quadruped_with_z1_has_a_closed_form_arm():
    robot = sk.Robot.from_urdf_string(go2_with_z1())
    arm = robot.arm
    assert arm is not None and arm.dof == 6
    assert arm.ik_kind == "6R-three-parallel-234"
    assert not arm.ik_idealised
    assert arm.ik_geometry["axes_5_6_gap"] < 1e-12  # the rank-1 form, as on the real Z1
    rng = np.random.default_rng(7)
    q = rng.uniform(-2.8, 2.8, (500, 6))
    T = arm.fk(q)
    sol = arm.ik_all(T)
    assert (sol.status == sk.Status.OK).all()
    assert (sol.exact == sol.exists).all()
    gap = np.abs(np.angle(np.exp(1j * (sol.q - q[:, None, :])))).max(axis=2)
    assert (np.where(sol.exists, gap, np.inf).min(axis=1) < 1e-7).all()
    # every solution reaches the pose, and the POE reference finds the same set
    found = sol.q[sol.exists]
    assert np.abs(arm.fk(found) - np.repeat(T, sol.exists.sum(axis=1), axis=0)).max() < 1e-9
    poe = ik6r.from_sk_chain(arm)
    for i in range(0, 500, 25):
        ref = ik6r.solve(poe, T[i])
        assert ref.exists.sum() == sol.exists[i].sum()
        for row in ref.q[ref.exists]:
            assert np.abs(np.angle(np.exp(1j * (sol.q[i][sol.exists[i]] - row)))).max(axis=1).min() < 1e-7
    # the nearest solution to a seed near the generating configuration is that configuration
    q_near, status = arm.ik(T, seed=q + 0.01)
    assert (status == sk.Status.OK).all()
    np.testing.assert_allclose(q_near, q, atol=1e-7)
