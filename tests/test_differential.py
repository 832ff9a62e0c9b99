"""Differential IK: dls, pinv, null space, rank, manipulability, Chain.ik_differential."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from conftest import BATCH_SHAPES, TOLERANCE, random_table
from spotkin.reference import differential as ref

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

SHAPES = [(3, 3), (6, 6), (12, 18), (6, 12), (7, 4), (1, 5), (5, 1), (2, 2)]
DTYPES = [np.float64, np.float32]


def conditioned(rng, lead, m, n, low=0.5, high=2.0, rank=None):
    """Matrices U diag(sigma) V^T with singular values in [low, high] (the last min(m,n) - rank zero)."""
    k = min(m, n)
    out = np.empty((*lead, m, n))
    for idx in np.ndindex(*lead):
        U, _ = np.linalg.qr(rng.normal(size=(m, m)))
        V, _ = np.linalg.qr(rng.normal(size=(n, n)))
        sigma = np.sort(rng.uniform(low, high, k))[::-1]
        if rank is not None:
            sigma[rank:] = 0.0
        S = np.zeros((m, n))
        S[:k, :k] = np.diag(sigma)
        out[idx] = U @ S @ V.T
    return out


def tolerance(dtype):
    return {np.float64: 1e-10, np.float32: 1e-4}[dtype]


def per_sample(func, *arrays):
    lead = np.broadcast_shapes(*(a.shape[: a.ndim - t] for a, t in arrays))
    results = [
        func(*(np.broadcast_to(a, (*lead, *a.shape[a.ndim - t :]))[idx] for a, t in arrays))
        for idx in np.ndindex(*lead)
    ]
    first = np.asarray(results[0]) if results else np.empty(0)
    return np.array(results).reshape(*lead, *first.shape)


# -- agreement with the reference ------------------------------------------------------------------


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("damping", [1e-3, 0.1, 0.0])
@pytest.mark.parametrize("dtype", DTYPES)
def test_dls_matches_reference(rng, shape, damping, dtype):
    m, n = shape
    J = conditioned(rng, (4,), m, n).astype(dtype)
    dx = rng.normal(size=(4, m)).astype(dtype)
    dq = sk.dls(J, dx, damping=damping)
    assert dq.dtype == dtype and dq.shape == (4, n)
    expected = per_sample(lambda a, b: ref.dls(a, b, damping), (J, 2), (dx, 1))
    np.testing.assert_allclose(dq, expected, rtol=tolerance(dtype), atol=tolerance(dtype))


@pytest.mark.parametrize("shape", SHAPES)
def test_dls_with_nullspace_matches_reference(rng, shape):
    m, n = shape
    J = conditioned(rng, (3,), m, n)
    dx, z = rng.normal(size=(3, m)), rng.normal(size=(3, n))
    for damping in (0.0, 1e-3):
        dq = sk.dls(J, dx, damping=damping, nullspace=z)
        expected = per_sample(lambda a, b, c, d=damping: ref.dls(a, b, d, c), (J, 2), (dx, 1), (z, 1))
        np.testing.assert_allclose(dq, expected, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("shape", SHAPES)
def test_decompositions_match_reference(rng, shape):
    m, n = shape
    J = conditioned(rng, (5,), m, n)
    np.testing.assert_allclose(sk.pinv(J), per_sample(ref.pinv, (J, 2)), atol=1e-12 * 10)
    np.testing.assert_allclose(sk.singular_values(J), per_sample(ref.singular_values, (J, 2)), atol=1e-12)
    np.testing.assert_allclose(
        sk.nullspace_projector(J), per_sample(ref.nullspace_projector, (J, 2)), atol=1e-12 * 10
    )
    np.testing.assert_allclose(sk.manipulability(J), per_sample(ref.manipulability, (J, 2)), rtol=1e-12)
    np.testing.assert_array_equal(sk.rank(J), per_sample(ref.rank, (J, 2)))


def test_manipulability_definitions(rng):
    J = conditioned(rng, (4,), 6, 6)
    np.testing.assert_allclose(sk.manipulability(J), np.abs(np.linalg.det(J)), rtol=1e-12)
    J = conditioned(rng, (4,), 3, 7)
    np.testing.assert_allclose(sk.manipulability(J), np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2))))
    np.testing.assert_allclose(sk.manipulability(J), np.prod(sk.singular_values(J), -1), rtol=1e-12)
    tall = conditioned(rng, (4,), 7, 3)
    assert (sk.manipulability(tall) == 0).all()


# -- limits and algebraic identities ---------------------------------------------------------------


@pytest.mark.parametrize("shape", [(3, 3), (6, 6), (12, 18), (5, 8), (8, 5)])
def test_dls_tends_to_pseudo_inverse(rng, shape):
    m, n = shape
    J = conditioned(rng, (6,), m, n)
    dx = rng.normal(size=(6, m))
    expected = np.einsum("...ij,...j->...i", np.linalg.pinv(J), dx)
    np.testing.assert_allclose(sk.dls(J, dx, damping=1e-7), expected, atol=1e-9)
    np.testing.assert_allclose(sk.dls(J, dx, damping=0.0), expected, atol=1e-12)
    # and away from 0 it is really damped: |dq| strictly smaller
    assert (np.linalg.norm(sk.dls(J, dx, damping=0.5), axis=-1) < np.linalg.norm(expected, axis=-1)).all()


@pytest.mark.parametrize("shape", [(3, 3), (6, 6), (12, 18), (5, 8), (8, 5)])
@pytest.mark.parametrize("damping", [1e-100, 1e-160, 1e-200, 5e-324])
def test_dls_with_a_damping_below_rounding_is_the_pseudo_inverse_limit(rng, shape, damping):
    """A damping whose square is below the rounding of J J^T (or underflows) is numerically zero:
    the step is J^+ dx, for a singular J too (a Cholesky of J J^T + damping² I would factor rounding
    noise there), on the fixed-size block path and the general one alike."""
    m, n = shape
    J = conditioned(rng, (40,), m, n, rank=min(m, n) - 1)
    dx = rng.normal(size=(40, m))
    expected = np.einsum("...ij,...j->...i", np.linalg.pinv(J), dx)
    np.testing.assert_allclose(sk.dls(J, dx, damping=damping), expected, atol=1e-9)
    np.testing.assert_allclose(sk.dls(J[0], dx[0], damping=damping), expected[0], atol=1e-9)
    np.testing.assert_allclose(ref.dls(J[0], dx[0], damping), expected[0], atol=1e-9)


def test_ik_differential_with_a_tiny_damping_at_a_limit_stays_finite():
    """Joints held at their limits zero Jacobian columns; with a damping below rounding the step
    is the pseudo-inverse one, not NaN (a fuzzing find)."""
    arm = sk.Spot().chain("arm_hand")
    T = np.array(
        [
            [0.14901586854489351, 0.9880591381670932, -0.03915878453568479, 0.7026143444750562],
            [-0.43528902631021, 0.02998832997002488, -0.8997911777960031, -0.12107199146460712],
            [-0.8878725891115912, 0.1511285530603337, 0.4345600372263532, -0.07876287231556375],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )
    q0 = np.array(
        [-0.07322401353124758, -0.9172158095301937, 1e-300, 1.7411595370267487, -0.4148944238, -0.3461887637]
    )
    for damping in (5e-324, 1e-200, 1e-100):
        q, info = arm.ik_differential(T, q0=q0, damping=damping)
        assert np.isfinite(q).all() and np.isfinite(info.position_error), damping


@pytest.mark.parametrize("shape", [(3, 3), (6, 6), (12, 18), (5, 8), (8, 5)])
@pytest.mark.parametrize("rank", [None, 1, 2])
def test_moore_penrose_conditions(rng, shape, rank):
    m, n = shape
    A = conditioned(rng, (4,), m, n, rank=rank)
    P = sk.pinv(A)
    assert P.shape == (4, n, m)
    T = np.swapaxes
    np.testing.assert_allclose(A @ P @ A, A, atol=1e-12 * 10)
    np.testing.assert_allclose(P @ A @ P, P, atol=1e-12 * 10)
    np.testing.assert_allclose(T(A @ P, -1, -2), A @ P, atol=1e-12 * 10)
    np.testing.assert_allclose(T(P @ A, -1, -2), P @ A, atol=1e-12 * 10)


def test_rank_constructed(rng):
    for r in range(0, 6):
        J = conditioned(rng, (3,), 6, 6, rank=r) if r else np.zeros((3, 6, 6))
        assert (sk.rank(J) == r).all()
        np.testing.assert_array_equal(sk.rank(J), [np.linalg.matrix_rank(j) for j in J])
    # near-singular: a singular value of 1e-9 counts, one of 1e-17 does not (default tol ~ 1.3e-15 sigma_max)
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    for small, expected in ((1e-9, 6), (1e-17, 5)):
        J = U @ np.diag([2, 1.5, 1, 0.8, 0.5, small]) @ V.T
        assert sk.rank(J) == expected
        assert sk.rank(J, tol=1e-6) == 5
    assert sk.rank(np.diag([1.0, 1e-5, 1e-3]), tol=1e-4) == 2
    assert isinstance(sk.rank(np.eye(3)), np.integer)
    # float32 uses its own eps: 1e-9 relative is below 3 * 1.2e-7
    assert sk.rank(np.diag([1.0, 1.0, 1e-9]).astype(np.float32)) == 2


def test_rank_spot_leg_and_arm_singularities():
    spot = sk.Spot()
    leg = spot.legs[0]
    assert sk.rank(leg.jacobian([0.1, 0.4, 0.7])) == 3
    # stretched knee: with the 0.025 m knee offset at kn = -atan2(knee_offset, upper), not at 0
    stretched = -np.arctan2(leg.knee_offset, leg.upper_length)
    assert sk.rank(leg.jacobian([0.1, 0.4, stretched])) == 2
    assert sk.rank(leg.jacobian([0.1, 0.4, 0.0])) == 3
    arm = spot.arm
    q = np.array([0.3, -0.7, 1.6, 0.4, 0.0, -0.2])  # wr0 = 0: el1 and wr1 aligned
    assert arm.singularity(q).wrist < 1e-12
    assert sk.rank(arm.jacobian(q)) == 5
    assert sk.manipulability(arm.jacobian(q)) < 1e-12
    q[4] = 0.5
    assert sk.rank(arm.jacobian(q)) == 6
    np.testing.assert_allclose(
        sk.manipulability(arm.jacobian(q)), arm.singularity(q).manipulability, rtol=1e-9
    )
    # near the wrist singularity dls stays bounded where the pseudo-inverse blows up
    q[4] = 1e-9
    J = arm.jacobian(q)
    dx = np.array([0, 0, 0, 1.0, 0, 0])
    assert np.abs(sk.dls(J, dx, damping=1e-2)).max() < 1e3
    assert np.abs(np.linalg.solve(J, dx)).max() > 1e6


# -- null space ------------------------------------------------------------------------------------


@pytest.mark.parametrize("shape", [(6, 12), (3, 7), (6, 6), (12, 18)])
def test_nullspace_leaves_primary_task_unchanged(rng, shape):
    m, n = shape
    J = conditioned(rng, (5,), m, n)
    dx, z = rng.normal(size=(5, m)), rng.normal(size=(5, n))
    for damping in (0.0, 1e-3, 0.3):
        primary = sk.dls(J, dx, damping=damping)
        dq = sk.dls(J, dx, damping=damping, nullspace=z)
        np.testing.assert_allclose(
            np.einsum("...ij,...j->...i", J, dq), np.einsum("...ij,...j->...i", J, primary), atol=1e-12 * 10
        )
        if n > m:
            assert np.linalg.norm(dq - primary, axis=-1).min() > 1e-3  # z really moved something
    P = sk.nullspace_projector(J)
    np.testing.assert_allclose(P @ P, P, atol=1e-12 * 10)
    np.testing.assert_allclose(P, np.swapaxes(P, -1, -2), atol=0)
    np.testing.assert_allclose(J @ P, 0, atol=1e-12 * 10)
    np.testing.assert_allclose(np.trace(P, axis1=-2, axis2=-1), n - min(m, n), atol=1e-10)


def _skew(r):
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def _rodrigues(w):
    theta = np.linalg.norm(w)
    if theta == 0:
        return np.eye(3)
    K = _skew(w / theta)
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K


def _hand_jacobian(spot, T_wb, q_arm):
    """d(hand pose)/d[body twist (world v, w); arm joints]: 6x12, world frame."""
    R, p = T_wb[:3, :3], T_wb[:3, 3]
    hand = T_wb @ spot.arm.fk(q_arm)
    J_arm = spot.arm.jacobian(q_arm)
    Jc = np.zeros((6, 12))
    Jc[:3, :3] = np.eye(3)
    Jc[:3, 3:6] = -_skew(hand[:3, 3] - p)  # w x r = -[r]x w
    Jc[3:, 3:6] = np.eye(3)
    Jc[:3, 6:] = R @ J_arm[:3]
    Jc[3:, 6:] = R @ J_arm[3:]
    return Jc, hand


def test_combined_jacobian_by_finite_differences():
    spot = sk.Spot()
    T_wb = sk.body_transform([0.1, -0.2, 0.5, 0.05, -0.1, 0.2])
    q = np.array([0.2, -1.0, 1.8, 0.3, 0.6, -0.4])
    Jc, hand = _hand_jacobian(spot, T_wb, q)
    np.testing.assert_allclose(
        spot.fk_all([0.1, -0.2, 0.5, 0.05, -0.1, 0.2], np.zeros(12), q).hand, hand, atol=1e-12
    )
    h = 1e-6
    for k in range(12):
        step = np.zeros(12)
        step[k] = h
        T2 = T_wb.copy()
        T2[:3, 3] += step[:3]
        T2[:3, :3] = _rodrigues(step[3:6]) @ T_wb[:3, :3]
        hand2 = T2 @ spot.arm.fk(q + step[6:])
        v = (hand2[:3, 3] - hand[:3, 3]) / h
        w = ref.log_rotation(hand2[:3, :3] @ hand[:3, :3].T) / h
        np.testing.assert_allclose(np.concatenate([v, w]), Jc[:, k], atol=1e-5)


def test_body_moves_while_hand_holds_its_pose():
    """Redundancy (the course): hand pose as the primary task, body motion in the null space."""
    spot = sk.Spot()
    T_wb = sk.body_transform([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    q = np.array([0.0, -1.2, 1.9, 0.0, 0.6, 0.0])
    _, hand0 = _hand_jacobian(spot, T_wb, q)
    request = np.concatenate([[0.0, 0.0, -0.1, 0.0, 0.0, 0.0], np.zeros(6)])  # lower the body
    steps, dt = 400, 1.0 / 400
    body_start = T_wb.copy()
    for _ in range(steps):
        Jc, _ = _hand_jacobian(spot, T_wb, q)
        rate = sk.dls(Jc, np.zeros(6), damping=1e-3, nullspace=request)
        np.testing.assert_allclose(Jc @ rate, 0, atol=1e-12)  # first order: the hand does not move
        d = rate * dt
        T_wb[:3, 3] += d[:3]
        T_wb[:3, :3] = _rodrigues(d[3:6]) @ T_wb[:3, :3]
        q = q + d[6:]
    hand = T_wb @ spot.arm.fk(q)
    # the body really moved down (P z . z = |P z|^2 >= 0: never against the request)
    assert body_start[2, 3] - T_wb[2, 3] > 0.01
    # the hand stayed put, to second order in the step
    assert np.linalg.norm(hand[:3, 3] - hand0[:3, 3]) < 1e-4
    assert np.linalg.norm(ref.log_rotation(hand[:3, :3] @ hand0[:3, :3].T)) < 1e-4


# -- batch semantics -------------------------------------------------------------------------------


@given(
    lead=st.sampled_from(BATCH_SHAPES),
    shape=st.sampled_from([(3, 3), (6, 6), (12, 18), (2, 4)]),
    dtype=st.sampled_from(DTYPES),
    damping=st.sampled_from([0.0, 1e-3, 0.1]),
    seed=st.integers(0, 2**32 - 1),
    with_z=st.booleans(),
)
def test_property_batches_and_dtypes(lead, shape, dtype, damping, seed, with_z):
    rng = np.random.default_rng(seed)
    m, n = shape
    J = conditioned(rng, lead, m, n).astype(dtype)
    dx = rng.normal(size=(*lead, m)).astype(dtype)
    z = rng.normal(size=(*lead, n)).astype(dtype) if with_z else None
    dq = sk.dls(J, dx, damping=damping, nullspace=z)
    assert dq.shape == (*lead, n) and dq.dtype == dtype
    args = [(J, 2), (dx, 1)] + ([(z, 1)] if with_z else [])
    expected = per_sample(lambda a, b, c=None: ref.dls(a, b, damping, c), *args)
    np.testing.assert_allclose(dq, expected, rtol=tolerance(dtype), atol=tolerance(dtype))
    for func, trailing in (
        (sk.pinv, (n, m)),
        (sk.nullspace_projector, (n, n)),
        (sk.singular_values, (min(m, n),)),
    ):
        out = func(J)
        assert out.shape == (*lead, *trailing) and out.dtype == dtype
    assert np.shape(sk.rank(J)) == lead and np.shape(sk.manipulability(J)) == lead
    np.testing.assert_allclose(
        sk.singular_values(J),
        per_sample(ref.singular_values, (J, 2)),
        rtol=TOLERANCE[dtype] * 100,
        atol=TOLERANCE[dtype] * 100,
    )


def test_broadcasting(rng):
    J = conditioned(rng, (2, 1), 6, 6)
    dx = rng.normal(size=(3, 6))
    dq = sk.dls(J, dx)
    assert dq.shape == (2, 3, 6)
    for i in range(2):
        for j in range(3):
            np.testing.assert_allclose(dq[i, j], ref.dls(J[i, 0], dx[j], 1e-3), atol=1e-12)
    single = sk.dls(J[0, 0], dx)  # one Jacobian, many tasks
    np.testing.assert_allclose(single, dq[0], atol=0)
    z = rng.normal(size=6)
    assert sk.dls(J, dx, nullspace=z).shape == (2, 3, 6)
    assert sk.dls(J[0, 0], dx[0]).shape == (6,)


def test_non_contiguous_integer_and_empty(rng):
    J = conditioned(rng, (4,), 6, 6)
    Jt = np.swapaxes(np.swapaxes(J, -1, -2).copy(), -1, -2)  # Fortran-ordered per matrix
    dx = rng.normal(size=(4, 12))[:, ::2]
    assert not Jt.flags.c_contiguous and not dx.flags.c_contiguous
    np.testing.assert_allclose(sk.dls(Jt, dx), sk.dls(J.copy(), dx.copy()), atol=0)
    np.testing.assert_allclose(sk.pinv(J[::2]), sk.pinv(J[::2].copy()), atol=0)
    assert sk.dls(np.eye(3, dtype=int), [1, 2, 3], damping=0).dtype == np.float64
    np.testing.assert_allclose(sk.dls(np.eye(3, dtype=int), [1, 2, 3], damping=0), [1, 2, 3])
    assert sk.dls(np.zeros((0, 6, 6)), np.zeros((0, 6))).shape == (0, 6)
    assert sk.pinv(np.zeros((0, 3, 4))).shape == (0, 4, 3)
    assert sk.rank(np.zeros((2, 0, 3, 3))).shape == (2, 0)
    assert sk.manipulability(np.zeros((0, 6, 6))).shape == (0,)


def test_nan_propagates_per_sample(rng):
    J = conditioned(rng, (3,), 6, 6)
    dx = rng.normal(size=(3, 6))
    J[1, 2, 3] = np.nan
    dx[2, 0] = np.inf
    dq = sk.dls(J, dx)
    assert np.isnan(dq[1]).all() and np.isnan(dq[2]).all() and np.isfinite(dq[0]).all()
    z = np.full(6, np.nan)
    assert np.isnan(sk.dls(J[0], dx[0], nullspace=z)).all()
    assert np.isnan(sk.pinv(J)[1]).all() and np.isfinite(sk.pinv(J)[0]).all()
    assert np.isnan(sk.nullspace_projector(J)[1]).all()
    assert np.isnan(sk.singular_values(J)[1]).all()
    assert np.isnan(sk.manipulability(J)[1])
    np.testing.assert_array_equal(sk.rank(J), [6, -1, 6])


@pytest.mark.parametrize(
    ("call", "error", "words"),
    [
        (lambda: sk.dls(np.eye(6), np.zeros(5)), ValueError, ["dx", "(..., 6)"]),
        (lambda: sk.dls(np.zeros(6), np.zeros(6)), ValueError, ["J", "(..., m, n)"]),
        (lambda: sk.dls(np.zeros((6, 0)), np.zeros(6)), ValueError, ["J"]),
        (lambda: sk.dls(np.zeros((65, 6)), np.zeros(65)), ValueError, ["J", "64"]),
        (
            lambda: sk.dls(np.eye(6), np.zeros(6), nullspace=np.zeros(5)),
            ValueError,
            ["nullspace", "(..., 6)"],
        ),
        (lambda: sk.dls(np.zeros((2, 6, 6)), np.zeros((3, 6))), ValueError, ["J", "dx", "broadcast"]),
        (lambda: sk.dls(np.eye(6) * 1j, np.zeros(6)), TypeError, ["J"]),
        (lambda: sk.dls(np.eye(6), ["a"] * 6), TypeError, ["dx"]),
        (lambda: sk.dls(np.eye(6), np.zeros(6), damping=-1e-3), ValueError, ["damping"]),
        (lambda: sk.dls(np.eye(6), np.zeros(6), damping=np.nan), ValueError, ["damping"]),
        (lambda: sk.rank(np.eye(3), tol=-1.0), ValueError, ["tol"]),
        (lambda: sk.pinv(np.zeros(3)), ValueError, ["J"]),
        (lambda: sk.singular_values("x"), TypeError, ["J"]),
    ],
)
def test_bad_input_raises(call, error, words):
    with pytest.raises(error) as info:
        call()
    for word in words:
        assert word in str(info.value)


# -- Chain.ik_differential -------------------------------------------------------------------------


def _pose_errors(chain, q, targets):
    T = chain.fk(q)
    dp = np.linalg.norm(T[..., :3, 3] - targets[..., :3, 3], axis=-1)
    R = targets[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    dw = np.array([np.linalg.norm(ref.log_rotation(r)) for r in R.reshape(-1, 3, 3)]).reshape(dp.shape)
    return dp, dw


def _well_posed(chain, q, rows=6):
    """Samples whose Jacobian is well conditioned (IK from a nearby start must converge there)."""
    J = chain.jacobian(q)[..., :rows, :]
    sigma = sk.singular_values(J)
    return sigma[..., -1] > 0.05


@pytest.mark.parametrize("dof", [6, 7])
def test_ik_differential_converges_on_reachable_targets(rng, dof):
    rows = random_table(rng, dof)
    rows[:, 1] = np.where(rows[:, 1] == 0, 0.3, rows[:, 1])  # no degenerate zero lengths
    chain = sk.Chain.from_mdh(rows)
    q_true = rng.uniform(-1.5, 1.5, (60, dof))
    q_true = q_true[_well_posed(chain, q_true)]
    assert len(q_true) >= 10
    targets = chain.fk(q_true)
    q0 = q_true + rng.uniform(-0.2, 0.2, q_true.shape)
    q, info = chain.ik_differential(targets, q0)
    assert q.shape == q_true.shape and info.converged.shape == (len(q_true),)
    assert info.converged.all()
    dp, dw = _pose_errors(chain, q, targets)
    assert (dp <= 1e-6).all() and (dw <= 1e-6).all()
    np.testing.assert_allclose(info.position_error, dp, atol=1e-12)
    np.testing.assert_allclose(info.orientation_error, dw, atol=1e-9)
    assert (info.iterations >= 1).all() and (info.iterations < 100).all()


def test_ik_differential_path_and_broadcast(rng):
    rows = np.array(
        [
            [0, 0, 0, 0.3, 0],
            [0, 0, -np.pi / 2, 0, 0],
            [0, 0.5, 0, 0, 0],
            [0, 0, -np.pi / 2, 0.4, 0],
            [0, 0, np.pi / 2, 0, 0],
            [0, 0, -np.pi / 2, 0, 0],
        ],
        dtype=float,
    )
    chain = sk.Chain.from_mdh(rows, tool=sk.translation([0, 0, 0.1]))
    t = np.linspace(0, 1, 25)[:, None]
    q_a, q_b = np.array([0.1, 0.4, 0.6, 0.2, 0.9, -0.3]), np.array([0.8, -0.1, 1.0, -0.5, 1.2, 0.4])
    q_line = q_a + t * (q_b - q_a)
    targets = chain.fk(q_line)  # (25, 4, 4): a path for one start
    q_path, info = chain.ik_differential(targets, q_a)
    assert q_path.shape == (25, 6) and info.converged.shape == (25,)
    assert info.converged.all()
    dp, dw = _pose_errors(chain, q_path, targets)
    assert dp.max() <= 1e-6 and dw.max() <= 1e-6
    # many starts on the same path, and float32 in -> float32 out
    starts = q_a + rng.uniform(-0.05, 0.05, (3, 6))
    q_many, info_many = chain.ik_differential(targets[None], starts)
    assert q_many.shape == (3, 25, 6) and info_many.converged.all()
    q32, _ = chain.ik_differential(targets.astype(np.float32), q_a.astype(np.float32))
    assert q32.dtype == np.float32
    # single target per sample
    q_one, info_one = chain.ik_differential(targets[-1], q_a)
    assert q_one.shape == (6,) and bool(info_one.converged)


def test_ik_differential_underactuated_position_task(rng):
    rows = random_table(rng, 3)
    rows[:, 1] = np.where(rows[:, 1] == 0, 0.4, rows[:, 1])
    chain = sk.Chain.from_mdh(rows)
    q_true = rng.uniform(-1.5, 1.5, (40, 3))
    q_true = q_true[_well_posed(chain, q_true, rows=3)]
    targets = chain.fk(q_true)
    targets[..., :3, :3] = np.eye(3)  # orientation unreachable, ignored by the position task
    q, info = chain.ik_differential(targets, q_true + 0.1, task="position")
    assert info.converged.all()
    np.testing.assert_allclose(chain.fk(q)[..., :3, 3], targets[..., :3, 3], atol=1e-6)
    _, info_pose = chain.ik_differential(targets, q_true + 0.1, task="pose", max_iter=30)
    assert not info_pose.converged.any()  # the full pose is out of reach for 3 joints


def test_ik_differential_prismatic_and_limits(rng):
    # cylindrical: slide along z, turn about z, slide radially (one solution per reachable point)
    rows = np.array([[1, 0, 0, 0, 0], [0, 0, 0, 0, 0], [1, 0, np.pi / 2, 0, 0]], dtype=float)
    limits = np.array([[0.0, 0.5], [-1.0, 1.0], [0.1, 0.6]])
    chain = sk.Chain.from_mdh(rows, limits=limits)
    q_true = rng.uniform(limits[:, 0] + 0.05, limits[:, 1] - 0.05, (20, 3))
    targets = chain.fk(q_true)
    q, info = chain.ik_differential(targets, np.full(3, 0.2) + 0 * q_true, task="position")
    assert info.converged.all()
    assert ((q >= limits[:, 0]) & (q <= limits[:, 1])).all()
    np.testing.assert_allclose(chain.fk(q)[..., :3, 3], targets[..., :3, 3], atol=1e-6)
    # a target needing joint 0 at 0.8 > 0.5: reported as not converged, limits respected
    q_out = q_true[0].copy()
    q_out[0] = 0.8
    q_bad, info_bad = chain.ik_differential(chain.fk(q_out), q_true[0], task="position")
    assert not info_bad.converged and info_bad.position_error > 0.2
    assert info_bad.iterations == 100
    assert limits[0, 0] <= q_bad[0] <= limits[0, 1]


def test_ik_differential_unreachable_and_nan(rng):
    chain = sk.Chain.from_mdh(
        np.array([[0, 0, 0, 0, 0], [0, 0.5, np.pi / 2, 0, 0], [0, 0.4, 0, 0, 0]], float)
    )
    far = sk.translation([5.0, 0, 0])
    q, info = chain.ik_differential(far, np.array([0.1, 0.2, 0.3]), task="position", max_iter=50)
    assert not info.converged and info.iterations == 50
    assert info.position_error > 4.0 and np.isfinite(q).all()
    targets = np.stack([chain.fk([0.1, 0.2, 0.3]), np.full((4, 4), np.nan)])
    q, info = chain.ik_differential(targets, np.zeros(3), task="position")
    assert info.converged.tolist() == [True, False]
    assert np.isfinite(q[0]).all() and np.isnan(q[1]).all() and np.isnan(info.position_error[1])
    q, info = chain.ik_differential(targets[0], np.array([np.nan, 0, 0]), task="position")
    assert np.isnan(q).all() and not info.converged


def test_ik_differential_bad_input():
    chain = sk.Chain.from_mdh(np.array([[0, 0, 0, 0, 0], [0, 0.5, 0, 0, 0]], float))
    T = np.eye(4)
    with pytest.raises(ValueError, match="q0"):
        chain.ik_differential(T, np.zeros(3))
    with pytest.raises(ValueError, match="T_targets"):
        chain.ik_differential(np.eye(3), np.zeros(2))
    with pytest.raises(TypeError, match="T_targets"):
        chain.ik_differential(np.eye(4) * 1j, np.zeros(2))
    with pytest.raises(ValueError, match="task"):
        chain.ik_differential(T, np.zeros(2), task="orientation")
    with pytest.raises(ValueError, match="damping"):
        chain.ik_differential(T, np.zeros(2), damping=0.0)
    with pytest.raises(ValueError, match="max_iter"):
        chain.ik_differential(T, np.zeros(2), max_iter=-1)
    with pytest.raises(ValueError, match="broadcast"):
        chain.ik_differential(np.tile(T, (3, 1, 1)), np.zeros((2, 2)))


def test_log_rotation_reference_against_rodrigues(rng):
    for _ in range(20):
        w = rng.normal(size=3)
        w *= rng.uniform(0, np.pi) / np.linalg.norm(w)
        np.testing.assert_allclose(ref.log_rotation(_rodrigues(w)), w, atol=1e-9)
    w = np.array([0, 0, np.pi])
    np.testing.assert_allclose(np.abs(ref.log_rotation(_rodrigues(w))), np.abs(w), atol=1e-9)
