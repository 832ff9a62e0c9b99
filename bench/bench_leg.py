"""Spot leg FK, Jacobian and IK against NumPy-vectorised closed-form baselines."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk
from baselines import leg_fk, leg_ik_one_branch, leg_jacobian, numpy_impl
from conftest import SIZES

LEG = sk.Spot().leg("fl")
PARAMS = (LEG.hip_offset, LEG.upper_length, LEG.lower_length, LEG.knee_offset)


def configurations(n: int) -> np.ndarray:
    limits = LEG.limits
    q = np.random.default_rng(0).uniform(limits[:, 0], limits[:, 1], (n, 3))
    return q[0] if n == 1 else q


def test_baselines_agree_with_spotkin():
    q = configurations(1000)
    np.testing.assert_allclose(leg_fk(q, *PARAMS), LEG.fk(q), atol=1e-14)
    np.testing.assert_allclose(leg_jacobian(q, *PARAMS), LEG.jacobian(q), atol=1e-14)
    p = LEG.fk(q)
    below = p[:, 2] < -0.08  # where slot 0 is the limit-respecting branch
    np.testing.assert_allclose(leg_ik_one_branch(p[below], *PARAMS), LEG.ik(p[below])[0], atol=1e-9)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy", "numpy-unchunked"])
@pytest.mark.parametrize("op", ["fk", "jacobian"])
def test_leg_fk_jacobian(measure, op, impl, n):
    q = configurations(n)
    if impl.startswith("numpy"):
        base = {"fk": leg_fk, "jacobian": leg_jacobian}[op]
        measure(f"leg.{op}", n, *numpy_impl(impl, lambda a: base(a, *PARAMS)), q)
    else:
        measure(f"leg.{op}", n, impl, getattr(LEG, op), q)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize(
    "impl",
    ["spotkin", "spotkin-1thread", "spotkin-float32-1thread", "spotkin.ik_all", "numpy", "numpy-unchunked"],
)
def test_leg_ik(measure, impl, n):
    p = LEG.fk(configurations(n))
    if "float32" in impl:
        p = p.astype(np.float32)
    if impl.startswith("numpy"):
        measure("leg.ik", n, *numpy_impl(impl, lambda a: leg_ik_one_branch(a, *PARAMS), " slot 0"), p)
    elif impl == "spotkin.ik_all":
        measure("leg.ik", n, impl, LEG.ik_all, p)
    else:
        measure("leg.ik", n, impl, LEG.ik, p)
