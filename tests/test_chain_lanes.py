"""The batched chain FK and Jacobian across lanes (cpp/include/spotkin/chain_lanes.hpp): every
placement and axis kind (URDF joints with general axes and rotated placements, pure
translations, prismatic joints, DH screws) against the pure-Python reference and Chain's
per-sample code (batches under 8 samples), for batch sizes around the block of 16, in float64
and float32, at every instruction-set level."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk
from conftest import random_rigid, random_table
from spotkin.reference import chain as ref

pytestmark = pytest.mark.usefixtures("every_isa")


def urdf_like(rng, n: int) -> sk.Chain:
    """Joints with rotated and translated placements (the General and Translation kinds, some
    identity), general and axis-aligned (signed) axes, and prismatic joints."""
    placements = np.array([random_rigid(rng) for _ in range(n)])
    placements[1::3, :3, :3] = np.eye(3)  # translations only
    if n > 2:
        placements[2] = np.eye(4)  # identity
    axes = rng.normal(size=(n, 3))
    axes[::2] = np.eye(3)[rng.integers(0, 3, len(axes[::2]))] * rng.choice([-1.0, 1.0], (len(axes[::2]), 1))
    types = [1 if k % 4 == 3 else 0 for k in range(n)]  # sigma: 1 prismatic
    return sk.Chain.from_joints(placements, axes, types=types, base=random_rigid(rng), tool=random_rigid(rng))


def central_jacobian(chain: sk.Chain, q: np.ndarray) -> np.ndarray:
    """The linear block of the Jacobian by central differences of FK."""
    step = 1e-6
    J = np.empty((*q.shape[:-1], 3, chain.dof))
    for j in range(chain.dof):
        dq = np.zeros(chain.dof)
        dq[j] = step
        J[..., j] = (chain.fk(q + dq)[..., :3, 3] - chain.fk(q - dq)[..., :3, 3]) / (2 * step)
    return J


@pytest.mark.parametrize("count", [1, 7, 8, 9, 16, 17, 33, 100])
def test_urdf_like_chains_batch_equals_single_and_differences(count, rng):
    for n in (2, 6, 7):
        chain = urdf_like(rng, n)
        q = rng.uniform(-2.5, 2.5, (count, n))
        T, J = chain.fk(q), chain.jacobian(q)
        singles = np.array([chain.fk(qi) for qi in q])
        np.testing.assert_allclose(T, singles, rtol=0, atol=1e-14)
        np.testing.assert_allclose(J, np.array([chain.jacobian(qi) for qi in q]), rtol=0, atol=1e-14)
        np.testing.assert_allclose(J[..., :3, :], central_jacobian(chain, q), rtol=0, atol=1e-7)
        # rotation rows: each column's angular part is the joint axis (revolute) or zero (prismatic)
        assert np.allclose(np.linalg.norm(J[..., 3:, :], axis=-2)[..., [k % 4 != 3 for k in range(n)]], 1.0)
        assert np.all(J[..., 3:, [k % 4 == 3 for k in range(n)]] == 0.0)
        # in the tool frame: both blocks rotated by R_tool^T
        R = T[..., :3, :3]
        J_tool = chain.jacobian(q, frame="tool")
        np.testing.assert_allclose(J_tool[..., :3, :], np.swapaxes(R, -1, -2) @ J[..., :3, :], atol=1e-13)
        np.testing.assert_allclose(J_tool[..., 3:, :], np.swapaxes(R, -1, -2) @ J[..., 3:, :], atol=1e-13)


@pytest.mark.parametrize("count", [5, 16, 45])
def test_dh_chains_match_the_reference(count, rng):
    for convention in ("mdh", "dh"):
        rows = random_table(rng, 6)
        chain = sk.Chain(rows, convention=convention, base=random_rigid(rng), tool=random_rigid(rng))
        q = rng.uniform(-np.pi, np.pi, (count, 6))
        want = np.array([ref.fk(chain.rows, chain.convention, qi, chain.base, chain.tool) for qi in q])
        np.testing.assert_allclose(chain.fk(q), want, rtol=0, atol=1e-12)
        want_J = np.array(
            [ref.jacobian(chain.rows, chain.convention, qi, chain.base, chain.tool) for qi in q]
        )
        np.testing.assert_allclose(chain.jacobian(q), want_J, rtol=0, atol=1e-12)


def test_float32_computes_in_float_lanes_near_float64(rng):
    chain = urdf_like(rng, 6)
    q = rng.uniform(-2.5, 2.5, (1000, 6))
    q32 = q.astype(np.float32)
    T32, J32 = chain.fk(q32), chain.jacobian(q32)
    assert T32.dtype == J32.dtype == np.float32
    T64, J64 = chain.fk(q32.astype(np.float64)), chain.jacobian(q32.astype(np.float64))
    scale = max(1.0, float(np.abs(T64).max()))
    assert np.abs(T32 - T64).max() <= 2e-6 * scale  # a few float32 roundings per joint
    assert np.abs(J32 - J64).max() <= 2e-6 * max(1.0, float(np.abs(J64).max()))
    np.testing.assert_array_equal(T32[:, 3], np.tile(np.float32([0, 0, 0, 1]), (1000, 1)))
    # NaN in one sample: NaN in that sample's pose only
    q32[17, 2] = np.nan
    T = chain.fk(q32)
    assert np.isnan(T[17, :3]).all() and np.isfinite(np.delete(T, 17, axis=0)).all()


def test_a_sample_has_the_same_bits_in_any_block(rng):
    """Blocks of 16 lanes (batches of 16 or more) and of 4 (smaller calls) run the same equations
    lane by lane: a single call, a short batch and a row of a long batch agree bit for bit, as do
    frames' last frame and FK (and Dask's chunks of any size with the whole batch)."""
    for n in (1, 3, 6, 7):
        for chain in (urdf_like(rng, n), sk.Chain(random_table(rng, n), base=random_rigid(rng))):
            for dtype in (np.float64, np.float32):
                q = rng.uniform(-3, 3, (37, n)).astype(dtype)
                T, J, F = chain.fk(q), chain.jacobian(q), chain.frames(q)
                np.testing.assert_array_equal(F[:, -1], T)
                for i in (0, 5, 36):
                    np.testing.assert_array_equal(chain.fk(q[i]), T[i])
                    np.testing.assert_array_equal(chain.jacobian(q[i]), J[i])
                    np.testing.assert_array_equal(chain.frames(q[i]), F[i])
                np.testing.assert_array_equal(chain.fk(q[3:8]), T[3:8])
                np.testing.assert_array_equal(
                    chain.jacobian(q[3:18], frame="tool"), chain.jacobian(q, frame="tool")[3:18]
                )
