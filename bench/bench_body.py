"""Whole-body IK, FK and Jacobian against a NumPy-vectorised whole-body baseline
(body rotation, feet into the hip frames, closed-form leg IK with one branch),
with 1 and 2 threads, and the memory-bandwidth bound."""

from __future__ import annotations

import time

import numpy as np
import pytest

import spotkin as sk
from baselines import body_fk, body_ik, body_jacobian, numpy_impl
from conftest import SIZES

SPOT = sk.Spot()
FEET = SPOT.stance_feet(0.5)
HIPS = SPOT.hip_positions
LEGS = [(leg.hip_offset, leg.upper_length, leg.lower_length, leg.knee_offset) for leg in SPOT.legs]


def poses(n: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    p = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0]) + rng.normal(0, 1, (n, 6)) * [
        0.03,
        0.03,
        0.03,
        0.06,
        0.06,
        0.06,
    ]
    return p[0] if n == 1 else p


def test_baselines_agree_with_spotkin():
    p = poses(2000)
    res = SPOT.body_ik(p, FEET)
    assert (res.status == 0).all()
    np.testing.assert_allclose(body_ik(p, FEET, HIPS, LEGS), res.q, atol=1e-9)
    np.testing.assert_allclose(body_fk(p, res.q, HIPS, LEGS), SPOT.body_fk(p, res.q), atol=1e-13)
    np.testing.assert_allclose(body_jacobian(p, res.q, HIPS, LEGS), SPOT.body_jacobian(p, res.q), atol=1e-13)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize(
    "impl", ["spotkin", "spotkin-1thread", "spotkin-float32-1thread", "numpy", "numpy-unchunked"]
)
def test_body_ik(measure, impl, n):
    p = poses(n)
    if impl.startswith("numpy"):
        measure("body.ik", n, *numpy_impl(impl, body_ik, " slot 0"), np.atleast_2d(p), FEET, HIPS, LEGS)
    elif "float32" in impl:
        measure("body.ik", n, impl, SPOT.body_ik, p.astype(np.float32), FEET.astype(np.float32))
    else:
        measure("body.ik", n, impl, SPOT.body_ik, p, FEET)


@pytest.mark.parametrize("n", [1, 1_000, 1_000_000])
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy", "numpy-unchunked"])
@pytest.mark.parametrize("op", ["fk", "jacobian"])
def test_body_fk_jacobian(measure, op, impl, n):
    p = poses(n)
    q12 = SPOT.body_ik(p, FEET).q
    if impl.startswith("numpy"):
        base = {"fk": body_fk, "jacobian": body_jacobian}[op]
        measure(
            f"body.{op}",
            n,
            *numpy_impl(impl, base, n_arrays=2),
            np.atleast_2d(p),
            np.atleast_2d(q12),
            HIPS,
            LEGS,
        )
    else:
        measure(f"body.{op}", n, impl, getattr(SPOT, f"body_{op}"), p, q12)


def test_bandwidth_bound(capsys):
    """Bytes in + out per pose over the measured copy bandwidth: the floor for body_ik."""
    n = 1_000_000
    src = np.ones(8 * n)
    dst = np.empty_like(src)
    best = min(_timed(lambda: np.copyto(dst, src)) for _ in range(5))
    bandwidth = 2 * src.nbytes / best  # read + write
    bytes_per_pose = 6 * 8 + 12 * 8 + 4  # pose in; q and status out (the stance is shared)
    p = poses(n)
    ik_time = min(_timed(lambda: SPOT.body_ik(p, FEET)) for _ in range(5))
    ceiling = bandwidth / bytes_per_pose / 1e6
    with capsys.disabled():
        print(
            f"\nbody.ik bandwidth bound: {bytes_per_pose} B/pose in + out at {bandwidth / 1e9:.1f} GB/s "
            f"copy bandwidth -> {ceiling:.0f} M poses/s ceiling; measured {n / ik_time / 1e6:.1f} M poses/s "
            f"({sk.get_num_threads()} threads)"
        )


def _timed(func) -> float:
    start = time.perf_counter()
    func()
    return time.perf_counter() - start
