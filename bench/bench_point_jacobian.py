"""Preferential Jacobians J_k(j) (Chain.jacobian with point= and frame=) against the tool-point,
base-frame Jacobian of the same chain in the same run: the "ref:" row is the base Jacobian, so the
summary's speed-up column is its time over the preferential one's (below 1: the preferential one
costs more)."""

from __future__ import annotations

import numpy as np
import pytest
from bench_chain import CHAIN, joint_samples

CASES = {
    "J_3(2)": {"point": 3, "frame": 2},
    "J_tool(3)": {"point": "tool", "frame": 3},
    "J_7(base)": {"point": 7, "frame": "base"},
    "J_tool(tool)": {"point": "tool", "frame": "tool"},
}


def test_the_preferential_cases_are_rotations_of_the_base_one():
    q = joint_samples(100)
    frames = CHAIN.frames(q)
    J = CHAIN.jacobian(q, point=3)
    Rt = np.swapaxes(frames[:, 2, :3, :3], -1, -2)
    np.testing.assert_allclose(CHAIN.jacobian(q, **CASES["J_3(2)"])[:, :3], Rt @ J[:, :3], atol=1e-12)


@pytest.mark.parametrize("n", [1_000, 100_000, 1_000_000])
@pytest.mark.parametrize("impl", ["ref:jacobian(base)", *CASES])
def test_point_jacobian(measure, impl, n):
    q = joint_samples(n)
    if impl.startswith("ref:"):
        measure("chain6.point_jacobian", n, impl, CHAIN.jacobian, q)
        return
    kwargs = CASES[impl]
    measure("chain6.point_jacobian", n, f"spotkin {impl}", lambda a: CHAIN.jacobian(a, **kwargs), q)
