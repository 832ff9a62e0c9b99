"""Spot Arm FK, Jacobian and IK (all 8 solutions) against NumPy baselines and,
where it installs (`pip install EAIK`), EAIK's batched analytic solver."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import spotkin as sk
from baselines import arm_fk, arm_jacobian, numpy_impl
from conftest import SIZES

ARM = sk.Spot().arm
HAS_EAIK = importlib.util.find_spec("eaik") is not None


def configurations(n: int) -> np.ndarray:
    limits = ARM.limits
    q = np.random.default_rng(0).uniform(limits[:, 0], limits[:, 1], (n, 6))
    return q[0] if n == 1 else q


def eaik_robot():
    from eaik.IK_HP import HPRobot

    ex, ey, ez = np.eye(3)
    H = np.array([ez, ey, ey, ex, ey, ex])
    P = np.array(
        [
            [0.292, 0, 0.188],
            [0, 0, 0],
            [0.3385, 0, 0],
            [0.4033, 0, 0.075],
            [0, 0, 0],
            [0, 0, 0],
            [0.19557, 0, 0],
        ]
    )
    return HPRobot(H, P)


def test_baselines_agree_with_spotkin():
    q = configurations(500)
    np.testing.assert_allclose(arm_fk(q), ARM.fk(q), atol=1e-14)
    np.testing.assert_allclose(arm_jacobian(q), ARM.jacobian(q), atol=1e-14)


@pytest.mark.skipif(not HAS_EAIK, reason="EAIK not installed")
def test_eaik_solves_the_same_arm():
    q = configurations(200)
    T = ARM.fk(q)
    robot = eaik_robot()
    free = sk.SpotArm(limits=None).ik_all(T)
    for solution, ours in zip(robot.IK_batched(T), free.q):
        assert solution.num_solutions() == 8
        theirs = np.sort(np.round(np.mod(solution.Q, 2 * np.pi), 6), axis=0)
        np.testing.assert_allclose(theirs, np.sort(np.round(np.mod(ours, 2 * np.pi), 6), axis=0), atol=2e-6)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy", "numpy-unchunked"])
@pytest.mark.parametrize("op", ["fk", "jacobian"])
def test_arm_fk_jacobian(measure, op, impl, n):
    q = configurations(n)
    if impl.startswith("numpy"):
        base = {"fk": arm_fk, "jacobian": arm_jacobian}[op]
        measure(f"arm.{op}", n, *numpy_impl(impl, base), np.atleast_2d(q))
    else:
        measure(f"arm.{op}", n, impl, getattr(ARM, op), q)


@pytest.mark.parametrize("n", [1, 1_000, 100_000])
@pytest.mark.parametrize("impl", ["spotkin.ik_all", "spotkin.ik_all-1thread", "spotkin.ik", "eaik"])
def test_arm_ik(measure, impl, n):
    T = ARM.fk(configurations(n))
    if impl == "eaik":
        if not HAS_EAIK:
            pytest.skip("EAIK not installed")
        robot = eaik_robot()
        measure("arm.ik (all 8)", n, "eaik IK_batched", robot.IK_batched, np.atleast_3d(T).reshape(-1, 4, 4))
    else:
        measure("arm.ik (all 8)", n, impl, ARM.ik if impl == "spotkin.ik" else ARM.ik_all, T)
