"""Chain FK, frames and Jacobians: C++ against the pure-Python reference."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import spotkin as sk
from conftest import BATCH_SHAPES, TOLERANCE, random_rigid, random_table
from spotkin.reference import chain as ref

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")


def reference_batch(func, chain: sk.Chain, q: np.ndarray, **kwargs) -> np.ndarray:
    flat = q.reshape(-1, chain.dof).astype(np.float64)

    def one(qi):
        return np.asarray(func(chain.rows, chain.convention, qi, chain.base, chain.tool, **kwargs))

    trailing = one(np.zeros(chain.dof)).shape
    out = np.array([one(qi) for qi in flat], dtype=np.float64).reshape(len(flat), *trailing)
    return out.reshape(*q.shape[:-1], *trailing)


@pytest.mark.parametrize("convention", ["mdh", "dh"])
@pytest.mark.parametrize("dof", [1, 3, 6, 12])
def test_random_chains_match_reference(rng, convention, dof):
    for _ in range(10):
        rows = random_table(rng, dof)
        chain = sk.Chain(rows, convention=convention, base=random_rigid(rng), tool=random_rigid(rng))
        q = rng.uniform(-np.pi, np.pi, (20, dof))
        np.testing.assert_allclose(chain.fk(q), reference_batch(ref.fk, chain, q), rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            chain.frames(q),
            reference_batch(lambda *a: np.array(ref.frames(*a)), chain, q),
            rtol=0,
            atol=1e-12,
        )
        J = reference_batch(ref.jacobian, chain, q)
        np.testing.assert_allclose(chain.jacobian(q), J, rtol=0, atol=1e-12)
        np.testing.assert_allclose(chain.position_jacobian(q), J[..., :3, :], rtol=0, atol=1e-12)
        J_tool = reference_batch(ref.jacobian, chain, q, frame="tool")
        np.testing.assert_allclose(chain.jacobian(q, frame="tool"), J_tool, rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            chain.position_jacobian(q, frame="tool"), J_tool[..., :3, :], rtol=0, atol=1e-12
        )


@given(
    dof=st.integers(1, 7),
    convention=st.sampled_from(["mdh", "dh"]),
    batch=st.sampled_from(BATCH_SHAPES) | hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=4),
    dtype=st.sampled_from([np.float64, np.float32]),
    seed=st.integers(0, 2**32 - 1),
)
def test_batch_shapes_and_dtypes(dof, convention, batch, dtype, seed):
    rng = np.random.default_rng(seed)
    chain = sk.Chain(
        random_table(rng, dof), convention=convention, base=random_rigid(rng), tool=random_rigid(rng)
    )
    q = rng.uniform(-np.pi, np.pi, (*batch, dof)).astype(dtype)
    expected = {
        "fk": (reference_batch(ref.fk, chain, q), (4, 4)),
        "frames": (reference_batch(lambda *a: np.array(ref.frames(*a)), chain, q), (dof + 2, 4, 4)),
        "jacobian": (reference_batch(ref.jacobian, chain, q), (6, dof)),
    }
    for name, (want, trailing) in expected.items():
        got = getattr(chain, name)(q)
        assert got.shape == (*batch, *trailing)
        assert got.dtype == dtype
        np.testing.assert_allclose(got, want, rtol=0, atol=TOLERANCE[dtype])


def test_non_contiguous_input_matches_contiguous(rng):
    chain = sk.Chain.from_mdh(random_table(rng, 6), tool=random_rigid(rng))
    big = rng.uniform(-3, 3, (40, 13))
    q = big[::3, 1:13:2]  # strided in both axes
    assert not q.flags.c_contiguous
    np.testing.assert_array_equal(chain.fk(q), chain.fk(np.ascontiguousarray(q)))
    np.testing.assert_array_equal(chain.jacobian(q.T.T), chain.jacobian(q.copy()))
    fortran = np.asfortranarray(rng.uniform(-3, 3, (9, 6)))
    np.testing.assert_array_equal(chain.frames(fortran), chain.frames(np.ascontiguousarray(fortran)))


def test_integer_and_list_inputs_compute_in_float64(rng):
    chain = sk.Chain.from_dh(random_table(rng, 3))
    assert chain.fk([0, 1, 2]).dtype == np.float64
    np.testing.assert_array_equal(chain.fk(np.array([0, 1, 2])), chain.fk([0.0, 1.0, 2.0]))


def test_empty_batches(rng):
    chain = sk.Chain.from_mdh(random_table(rng, 4))
    assert chain.fk(np.zeros((0, 4))).shape == (0, 4, 4)
    assert chain.frames(np.zeros((2, 0, 4), np.float32)).shape == (2, 0, 6, 4, 4)
    assert chain.jacobian(np.zeros((0, 4))).shape == (0, 6, 4)


def test_nan_propagates_per_sample(rng):
    chain = sk.Chain.from_mdh(random_table(rng, 3, prismatic=False), tool=random_rigid(rng))
    q = rng.uniform(-1, 1, (3, 3))
    q[1, 2] = np.nan
    T = chain.fk(q)
    assert np.isnan(T[1, :3]).any() and np.isfinite(T[[0, 2]]).all()
    assert np.isnan(chain.jacobian(q)[1]).any() and np.isfinite(chain.jacobian(q)[[0, 2]]).all()


def test_thread_count_gives_bit_identical_results(rng):
    chain = sk.Chain.from_mdh(random_table(rng, 6), tool=random_rigid(rng))
    q = rng.uniform(-3, 3, (100_003, 6))
    before = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = chain.fk(q), chain.jacobian(q), chain.frames(q[:30_001])
        sk.set_num_threads(2)
        two = chain.fk(q), chain.jacobian(q), chain.frames(q[:30_001])
    finally:
        sk.set_num_threads(before)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_concurrent_python_threads_get_correct_results(rng):
    from concurrent.futures import ThreadPoolExecutor

    chain = sk.Chain.from_mdh(random_table(rng, 6), tool=random_rigid(rng))
    batches = [rng.uniform(-3, 3, (50_000, 6)) for _ in range(6)]
    expected = [chain.jacobian(q) for q in batches]
    with ThreadPoolExecutor(4) as pool:
        got = list(pool.map(chain.jacobian, batches))
    for a, b in zip(got, expected):
        np.testing.assert_array_equal(a, b)
