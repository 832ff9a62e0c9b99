"""Robots from their URDF: whole-body IK on the Unitree Go2 against the strong (32768-row chunked)
one-thread NumPy baseline, URDF loading time, and chain FK / Jacobians of a URDF-built chain
against the same chain as a DH table."""

from __future__ import annotations

import time

import numpy as np
import pytest

import spotkin as sk
from baselines import robot_body_ik_chunked

GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))
GO2_FEET = GO2.stance_feet(0.28)
GO2_LEGS = [(leg.a, leg.b, leg.c, leg.signs) for leg in GO2.legs]
SPOT = sk.Spot()
SPOT_FEET = SPOT.stance_feet(0.5)
SPOT_LEGS = [(leg.a, leg.b, leg.c, leg.signs) for leg in SPOT.legs]


def poses(n: int, height: float) -> np.ndarray:
    rng = np.random.default_rng(0)
    p = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]) + rng.normal(0, 1, (n, 6)) * [
        0.02,
        0.02,
        0.02,
        0.05,
        0.05,
        0.05,
    ]
    return p[0] if n == 1 else p


def test_baseline_agrees_with_spotkin():
    for robot, feet, legs, height in ((GO2, GO2_FEET, GO2_LEGS, 0.28), (SPOT, SPOT_FEET, SPOT_LEGS, 0.5)):
        p = poses(5000, height)
        res = robot.body_ik(p, feet)
        assert (res.status == 0).all()
        np.testing.assert_allclose(
            robot_body_ik_chunked(p, feet, robot.hip_positions, legs), res.q, atol=1e-9
        )


@pytest.mark.parametrize("n", [1, 1_000, 1_000_000])
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy-chunked"])
def test_go2_body_ik(measure, impl, n):
    p = poses(n, 0.28)
    if impl.startswith("numpy"):
        measure(
            "go2.body_ik",
            n,
            impl,
            robot_body_ik_chunked,
            np.atleast_2d(p),
            GO2_FEET,
            GO2.hip_positions,
            GO2_LEGS,
        )
    else:
        measure("go2.body_ik", n, impl, GO2.body_ik, p, GO2_FEET)


@pytest.mark.parametrize("n", [1_000_000])
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy-chunked"])
def test_spot_body_ik_chunked_baseline(measure, impl, n):
    p = poses(n, 0.5)
    if impl.startswith("numpy"):
        measure("spot.body_ik", n, impl, robot_body_ik_chunked, p, SPOT_FEET, SPOT.hip_positions, SPOT_LEGS)
    else:
        measure("spot.body_ik", n, impl, SPOT.body_ik, p, SPOT_FEET)


# The Spot Arm as a URDF chain and as a modified-DH table (sigma, d, alpha, r, theta) with the
# constant tool correction that makes its tool frame the hand frame: the same kinematics.
_A = sk.models.SPOT["arm"]
ARM_MDH = [
    (0, 0.0, 0.0, 0.0, 0.0),
    (0, 0.0, -np.pi / 2, 0.0, 0.0),
    (0, _A["upper_arm"], 0.0, 0.0, -np.pi / 2),
    (0, _A["forearm_offset"], -np.pi / 2, _A["forearm"], 0.0),
    (0, 0.0, np.pi / 2, 0.0, 0.0),
    (0, 0.0, -np.pi / 2, 0.0, 0.0),
]
ARM_URDF = sk.Robot.from_urdf(sk.robots.path("spot_with_arm")).chain("arm_hand")
_BARE = sk.Chain.from_mdh(ARM_MDH, base=sk.translation(_A["mount"]))
ARM_DH = sk.Chain.from_mdh(
    ARM_MDH,
    base=sk.translation(_A["mount"]),
    tool=np.linalg.inv(_BARE.fk(np.zeros(6))) @ ARM_URDF.fk(np.zeros(6)),
)


def test_arm_chains_agree():
    """Both chains give the same hand pose, so the timings compare the same work."""
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, (500, 6))
    np.testing.assert_allclose(ARM_URDF.fk(q), ARM_DH.fk(q), atol=1e-12)


@pytest.mark.parametrize("op", ["fk", "jacobian"])
@pytest.mark.parametrize("impl", ["urdf-1thread", "dh-1thread"])
def test_chain_urdf_vs_dh(measure, op, impl):
    n = 100_000
    q = np.random.default_rng(2).uniform(-1, 1, (n, 6))
    chain = ARM_URDF if impl.startswith("urdf") else ARM_DH
    measure(f"arm-chain.{op}", n, impl, getattr(chain, op), q)


def test_urdf_load_time(capsys):
    """Loading a URDF, recognition included: the best of 20 loads, per robot."""
    timings = {}
    for name in ("spot_with_arm", "go2"):
        path = sk.robots.path(name)
        best = np.inf
        for _ in range(20):
            start = time.perf_counter()
            sk.Robot.from_urdf(path)
            best = min(best, time.perf_counter() - start)
        timings[name] = best
    with capsys.disabled():
        print()
        for name, seconds in timings.items():
            joints = len(sk.Robot.from_urdf(sk.robots.path(name)).joint_names)
            print(
                f"Robot.from_urdf({name}.urdf, {joints} actuated joints): {seconds * 1e3:.2f} ms (best of 20)"
            )
    assert all(seconds < 0.05 for seconds in timings.values())
