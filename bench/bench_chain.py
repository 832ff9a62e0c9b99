"""Chain FK and Jacobian for a 6-joint DHm arm, against the NumPy baseline."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk
from baselines import mdh_fk, mdh_jacobian, numpy_impl
from conftest import SIZES

ROWS = np.array(
    [
        (0, 0.0, 0.0, 0.3, 0.0),
        (0, 0.05, -np.pi / 2, 0.0, -np.pi / 2),
        (0, 0.4, 0.0, 0.0, 0.0),
        (0, 0.03, -np.pi / 2, 0.42, 0.0),
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
    ]
)
TOOL = sk.translation([0.0, 0.0, 0.1])
CHAIN = sk.Chain.from_mdh(ROWS, tool=TOOL)


def joint_samples(n: int) -> np.ndarray:
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (n, 6))
    return q[0] if n == 1 else q


def test_baselines_agree_with_spotkin():
    q = joint_samples(1000)
    np.testing.assert_allclose(mdh_fk(ROWS, q, TOOL), CHAIN.fk(q), atol=1e-12)
    np.testing.assert_allclose(mdh_jacobian(ROWS, q, TOOL), CHAIN.jacobian(q), atol=1e-12)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize(
    "impl", ["spotkin", "spotkin-1thread", "spotkin-float32-1thread", "numpy", "numpy-unchunked"]
)
@pytest.mark.parametrize("op", ["fk", "jacobian"])
def test_chain6(measure, op, impl, n):
    q = joint_samples(n)
    if "float32" in impl:  # float lanes: twice the samples per register (target: 1.8x the float64 throughput)
        q = q.astype(np.float32)
    if impl.startswith("numpy"):
        func = {"fk": mdh_fk, "jacobian": mdh_jacobian}[op]
        measure(f"chain6.{op}", n, *numpy_impl(impl, lambda a: func(ROWS, a, TOOL)), np.atleast_2d(q))
        return
    measure(f"chain6.{op}", n, impl, getattr(CHAIN, op), q)
