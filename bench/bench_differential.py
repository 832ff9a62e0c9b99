"""Batched damped least squares against NumPy: np.linalg.pinv and the solve-based formula.

Each shape is timed twice in the same run, once beside each baseline, so the summary
shows both speed-ups: ``dls MxN vs solve`` (J^T solve(J J^T + λ² I, dx), batched) and
``dls MxN vs pinv`` (np.linalg.pinv(J) @ dx, batched SVD).
"""

from __future__ import annotations

import numpy as np
import pytest
from bench_chain import CHAIN

import spotkin as sk
from conftest import rounds_for

DAMPING = 1e-3
CASES = [((3, 3), 100_000), ((6, 6), 100_000), ((12, 18), 10_000)]


def numpy_dls_solve(J: np.ndarray, dx: np.ndarray, damping: float) -> np.ndarray:
    """J^T (J J^T + λ² I)^-1 dx with NumPy's batched solve."""
    JT = np.swapaxes(J, -1, -2)
    A = J @ JT + damping**2 * np.eye(J.shape[-2])
    return (JT @ np.linalg.solve(A, dx[..., None]))[..., 0]


def numpy_pinv(J: np.ndarray, dx: np.ndarray) -> np.ndarray:
    return (np.linalg.pinv(J) @ dx[..., None])[..., 0]


def problem(shape, n):
    rng = np.random.default_rng(0)
    return rng.normal(size=(n, *shape)), rng.normal(size=(n, shape[0]))


def test_baselines_agree_with_spotkin():
    for shape, _ in CASES:
        J, dx = problem(shape, 100)
        np.testing.assert_allclose(
            numpy_dls_solve(J, dx, DAMPING), sk.dls(J, dx, DAMPING), rtol=1e-6, atol=1e-8
        )
        np.testing.assert_allclose(numpy_pinv(J, dx), sk.dls(J, dx, 0.0), rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize(("shape", "n"), CASES)
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy"])
@pytest.mark.parametrize("baseline", ["solve", "pinv"])
def test_dls(measure, shape, n, impl, baseline):
    J, dx = problem(shape, n)
    op = f"dls {shape[0]}x{shape[1]} vs {baseline}"
    if impl == "numpy":
        if baseline == "solve":
            measure(op, n, "numpy-solve", numpy_dls_solve, J, dx, DAMPING)
        else:
            measure(op, n, "numpy-pinv", numpy_pinv, J, dx)
        return
    measure(op, n, impl, sk.dls, J, dx, DAMPING)


@pytest.mark.parametrize(("shape", "n"), [((6, 6), 10_000), ((12, 18), 2_000)])
@pytest.mark.parametrize("impl", ["spotkin", "numpy"])
def test_pinv(measure, shape, n, impl):
    J, _ = problem(shape, n)
    op = f"pinv {shape[0]}x{shape[1]}"
    measure(
        op, n, "numpy-pinv" if impl == "numpy" else impl, np.linalg.pinv if impl == "numpy" else sk.pinv, J
    )


@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread"])
def test_ik_differential(measure, impl):
    """Throughput: one target per sample, 0.2 rad from the answer, 6-joint chain."""
    n = 10_000
    rng = np.random.default_rng(1)
    q_true = rng.uniform(-1.5, 1.5, (n, 6))
    targets = CHAIN.fk(q_true)
    q0 = q_true + rng.uniform(-0.2, 0.2, q_true.shape)
    _, info = measure("ik_differential chain6", n, impl, CHAIN.ik_differential, targets, q0)
    assert info.converged.mean() > 0.9
    assert rounds_for(n)
