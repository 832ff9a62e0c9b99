"""The C++ dynamics of the course's small arms (classic-DH chains, uniform rods) against the closed forms
derived by hand with Lagrange's equations (spotkin.reference.dynamics; docs/dynamics.md), in float64 and
float32, batched."""

from __future__ import annotations

import numpy as np
import pytest
from test_reference_dynamics import rrr_chain

import spotkin as sk
from spotkin.reference import dynamics as rd

G0 = 9.81


def planar_2r() -> sk.Chain:
    """Two uniform rods, m = (2, 1.5) kg, l = (0.8, 0.6) m, in the (x, y) plane: rod j lies along -x of
    frame j + 1 (classic DH puts frame j + 1 at the rod's far end)."""
    return sk.Chain.from_dh([(0, 0.8, 0.0, 0.0, 0.0), (0, 0.6, 0.0, 0.0, 0.0)]).with_inertials(
        [2.0, 1.5],
        [[-0.4, 0, 0], [-0.3, 0, 0]],
        [
            np.diag([0, 2.0 * 0.8**2 / 12, 2.0 * 0.8**2 / 12]),
            np.diag([0, 1.5 * 0.6**2 / 12, 1.5 * 0.6**2 / 12]),
        ],
    )


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_planar_2r(dtype, rng):
    chain = planar_2r()
    q = rng.uniform(-np.pi, np.pi, (3, 1, 2, 2))
    A = chain.mass_matrix(q.astype(dtype))
    G = chain.gravity(q.astype(dtype), np.array([0.0, -G0, 0.0], dtype))
    assert A.dtype == dtype and A.shape == (3, 1, 2, 2, 2) and G.shape == (3, 1, 2, 2)
    tol = 1e-12 if dtype == np.float64 else 1e-4
    for idx in np.ndindex(3, 1, 2):
        np.testing.assert_allclose(A[idx], rd.planar_2r_mass_matrix(q[idx], (2.0, 1.5), (0.8, 0.6)), atol=tol)
        np.testing.assert_allclose(
            G[idx], rd.planar_2r_gravity(q[idx], (2.0, 1.5), (0.8, 0.6)), atol=tol * 10
        )


def test_course_rrr_arm(rng):
    chain = rrr_chain()
    masses, lengths = (3.0, 2.0, 1.2), (1.0, 1.05, 0.89)
    q = rng.uniform(-np.pi, np.pi, (40, 3))
    A, G = chain.mass_matrix(q), chain.gravity(q)
    for k in range(len(q)):
        np.testing.assert_allclose(A[k], rd.rrr_mass_matrix(q[k], masses, lengths), atol=1e-12)
        np.testing.assert_allclose(G[k], rd.rrr_gravity(q[k], masses, lengths), atol=1e-11)
    # stretched upright (q = 0): the outer rods' weights act on no lever, G = (0, G2, 0) with
    # G2 = g0 (m2 l2 / 2 + m3 l2) (rods 2 and 3 along x2 at q2 = 0; rod 3 vertical above joint 3)
    G_zero = chain.gravity(np.zeros(3))
    np.testing.assert_allclose(G_zero, [0.0, G0 * (2.0 * 1.05 / 2 + 1.2 * 1.05), 0.0], atol=1e-12)
