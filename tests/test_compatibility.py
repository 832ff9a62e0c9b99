"""The compatibility condition: sk.compatible, the residual of sk.dls and of Chain.ik_differential,
against the plain reference and hand-worked cases."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from conftest import BATCH_SHAPES
from spotkin.reference import differential as ref


def low_rank(rng, m, n, r):
    """An m x n matrix of rank r (r = 0: zero), singular values spread in [0.5, 2]."""
    U, _ = np.linalg.qr(rng.normal(size=(m, m)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    S = np.zeros((m, n))
    S[range(r), range(r)] = rng.uniform(0.5, 2.0, r)
    return U @ S @ V.T, U


def test_hand_worked_cases():
    J = np.array([[1.0, 0.0], [0.0, 0.0]])
    assert sk.compatible(J, [3.0, 0.0]) == (True, 0.0)
    ok, residual = sk.compatible(J, [1.0, 2.0])
    assert not ok and residual == 2.0
    # a tall J (3 task rows, 2 joints): only its column plane is reachable
    J = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    assert sk.compatible(J, [0.3, -0.2, 0.0])[0]
    ok, residual = sk.compatible(J, [0.3, -0.2, 0.5])
    assert not ok and residual == pytest.approx(0.5, abs=1e-15)
    # the zero matrix: only dx = 0
    assert sk.compatible(np.zeros((2, 3)), np.zeros(2)) == (True, 0.0)
    assert sk.compatible(np.zeros((2, 3)), [0.0, 1e-300])[0] is np.False_


@pytest.mark.parametrize(("m", "n", "r"), [(3, 3, 3), (3, 3, 2), (6, 6, 5), (6, 7, 4), (6, 3, 3), (2, 5, 1)])
def test_against_the_reference(rng, m, n, r):
    for _ in range(20):
        J, U = low_rank(rng, m, n, r)
        inside = J @ rng.normal(size=n)
        outside = inside + (U[:, r:] @ rng.normal(size=m - r) if r < m else 0.0)
        for dx in (inside, outside):
            ok, residual = sk.compatible(J, dx)
            ref_ok, ref_residual = ref.compatible(J, dx)
            assert ok == ref_ok
            assert residual == pytest.approx(ref_residual, abs=1e-12)
        assert sk.compatible(J, inside)[0]
        assert sk.compatible(J, outside)[0] == (r == m)


@given(
    batch=st.sampled_from(BATCH_SHAPES + [(0,), (2, 0)]),
    dtype=st.sampled_from([np.float64, np.float32]),
    seed=st.integers(0, 2**32 - 1),
)
def test_batch_shapes_and_dtypes(batch, dtype, seed):
    rng = np.random.default_rng(seed)
    count = int(np.prod(batch, dtype=int))
    pairs = [low_rank(rng, 6, 6, 4) for _ in range(count)]
    J = np.array([p[0] for p in pairs]).reshape(*batch, 6, 6)
    out_of_range = np.array([p[1][:, 5] for p in pairs]).reshape(*batch, 6)
    dx = np.einsum("...ij,...j->...i", J, rng.normal(size=(*batch, 6))) + np.where(
        rng.random((*batch, 1)) < 0.5, 0.3 * out_of_range, 0.0
    )
    ok, residual = sk.compatible(J.astype(dtype), dx.astype(dtype))
    assert ok.shape == batch and residual.shape == batch and residual.dtype == dtype and ok.dtype == bool
    expected = np.array(
        [ref.compatibility_residual(a, b) for a, b in zip(J.reshape(-1, 6, 6), dx.reshape(-1, 6))]
    )
    np.testing.assert_allclose(
        residual.reshape(-1), expected, rtol=0, atol=1e-12 if dtype == np.float64 else 1e-5
    )
    np.testing.assert_array_equal(ok.reshape(-1), expected < 1e-3)


def test_broadcast_non_contiguous_and_one_nan_sample(rng):
    J, U = low_rank(rng, 3, 3, 2)
    dx = np.stack([J @ rng.normal(size=3), U[:, 2], J @ rng.normal(size=3)])
    ok, residual = sk.compatible(J, dx)  # one J against three dx
    assert ok.tolist() == [True, False, True]
    assert residual[1] == pytest.approx(1.0, abs=1e-12)
    wide = np.repeat(dx, 2, axis=1)[:, ::2]
    assert not wide.flags.c_contiguous
    np.testing.assert_array_equal(sk.compatible(J, wide)[0], ok)
    dx[2, 0] = np.nan
    ok, residual = sk.compatible(J, dx)
    assert ok.tolist() == [True, False, False] and np.isnan(residual[2]) and np.isfinite(residual[:2]).all()


def test_given_tolerance_is_absolute():
    J = np.diag([1.0, 0.0])
    assert sk.compatible(J, [1.0, 1e-3], tol=1e-2)[0]
    assert not sk.compatible(J, [1.0, 1e-3], tol=1e-4)[0]
    assert not sk.compatible(J, [1.0, 1e-3])[0]


def planar_2r(l1=0.5, l2=0.3):
    return sk.Chain.from_dh([(0, l1, 0, 0, 0), (0, l2, 0, 0, 0)])


def test_at_a_stretched_arm_only_motions_across_it_are_exact():
    """A planar 2R arm stretched along x at q = (0, 0): the tip moves only along y (and not in z)."""
    J = planar_2r().position_jacobian([0.0, 0.0])
    assert sk.rank(J) == 1
    assert sk.compatible(J, [0.0, 0.4, 0.0])[0]
    ok, residual = sk.compatible(J, [0.1, 0.4, 0.0])
    assert not ok and residual == pytest.approx(0.1, abs=1e-15)
    # float32: the same answers
    ok32, residual32 = sk.compatible(J.astype(np.float32), np.float32([0.1, 0.4, 0.0]))
    assert not ok32 and residual32.dtype == np.float32 and residual32 == pytest.approx(0.1, abs=1e-7)


def test_dls_reports_the_compatibility_residual(rng):
    J, U = low_rank(rng, 6, 6, 5)
    dx = np.stack([J @ rng.normal(size=6), J @ rng.normal(size=6) + 0.2 * U[:, 5]])
    for damping in (0.0, 1e-3, 0.1):
        dq, residual = sk.dls(J, dx, damping, return_residual=True)
        np.testing.assert_array_equal(dq, sk.dls(J, dx, damping))
        np.testing.assert_allclose(residual, [0.0, 0.2], rtol=0, atol=1e-12)
        np.testing.assert_array_equal(residual, sk.compatible(J, dx)[1])
    # the undamped step: exact for the compatible dx, off by the residual (the least-squares
    # distance) for the other
    dq = sk.dls(J, dx, 0.0)
    np.testing.assert_allclose(np.linalg.norm(dx - dq @ J.T, axis=-1), [0.0, 0.2], rtol=0, atol=1e-12)
    assert np.ndim(sk.dls(J, dx[0], return_residual=True)[1]) == 0
    with pytest.raises(TypeError, match="return_residual"):
        sk.dls(J, dx, return_residual="yes")


def test_ik_differential_reports_the_residual_of_its_final_error():
    chain = planar_2r()
    reachable = sk.translation([0.3, 0.5, 0.0])
    above = sk.translation([0.3, 0.5, 0.2])  # out of the arm's plane: no joint motion reaches z
    q, info = chain.ik_differential(np.stack([reachable, above]), [0.3, 0.6], task="position")
    assert info.converged.tolist() == [True, False]
    assert info.residual[0] < 1e-9
    assert info.residual[1] == pytest.approx(0.2, abs=1e-12)  # the z error, all of it out of range
    for k in range(2):
        e = np.array([0.3, 0.5, 0.2 * k]) - chain.fk(q[k])[:3, 3]
        assert info.residual[k] == pytest.approx(
            float(sk.compatible(chain.position_jacobian(q[k]), e)[1]), abs=1e-15
        )
    _, info_one = chain.ik_differential(above, [0.3, 0.6], task="position")
    assert np.ndim(info_one.residual) == 0 and info_one.residual == pytest.approx(0.2, abs=1e-12)
    _, info_bad = chain.ik_differential(np.full((4, 4), np.nan), [0.3, 0.6], task="position")
    assert np.isnan(info_bad.residual)


def test_ik_differential_pose_residual_matches_compatible(rng):
    rows = np.array([(0, 0.0, -np.pi / 2, 0.3, 0.0), (0, 0.4, 0.0, 0.0, 0.0), (0, 0.3, 0.0, 0.0, 0.0)])
    chain = sk.Chain.from_dh(rows)
    target = chain.fk([0.4, -0.3, 0.8]) @ sk.rotation_x(0.3)  # a position it reaches, a tilt it cannot
    q, info = chain.ik_differential(target, [0.0, 0.0, 0.5], max_iter=20)
    from spotkin.reference.differential import log_rotation

    T = chain.fk(q)
    e = np.concatenate([target[:3, 3] - T[:3, 3], log_rotation(target[:3, :3] @ T[:3, :3].T)])
    assert info.residual == pytest.approx(float(sk.compatible(chain.jacobian(q), e)[1]), abs=1e-12)
    assert info.residual > 1e-3


@pytest.mark.parametrize(
    ("args", "kwargs", "error", "match"),
    [
        ((np.eye(3), np.ones(2)), {}, ValueError, "dx"),
        ((np.eye(3)[None].repeat(2, 0), np.ones((3, 3))), {}, ValueError, "broadcast"),
        ((np.ones(3), np.ones(3)), {}, ValueError, "J must have shape"),
        ((np.eye(3), np.ones(3)), {"tol": -1.0}, ValueError, "tol"),
        ((np.eye(3), np.ones(3)), {"tol": np.inf}, ValueError, "tol"),
        ((np.eye(3), np.ones(3)), {"tol": "1e-3"}, TypeError, "tol"),
        (("J", np.ones(3)), {}, TypeError, "J"),
    ],
)
def test_bad_input(args, kwargs, error, match):
    with pytest.raises(error, match=match):
        sk.compatible(*args, **kwargs)
