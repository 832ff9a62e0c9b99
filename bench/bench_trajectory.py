"""Trajectory sampling (spotkin.trajectory) against NumPy-vectorised baselines of the same formulas:
a 6-axis quintic and trapezoid point-to-point move (q, qd, qdd) and a Cartesian straight line
(4x4 poses, slerp). Target: 1e6 time points in under 20 ms. Also the planning of a
blended waypoint path (via_points) with 1e3 and 1e5 waypoints."""

from __future__ import annotations

import math

import numpy as np
import pytest

import spotkin as sk
from baselines import linear_path, p2p_quintic, p2p_trapezoid

SIZES = [1_000, 1_000_000]
Q0 = np.zeros(6)
QF = np.array([0.5, -1.0, 1.5, 0.2, -0.3, 2.0])
TRAJ = {p: sk.trajectory.point_to_point(Q0, QF, 1.5, 4.0, p) for p in ("quintic", "trapezoid")}

P0, P1 = np.array([0.0, 0.0, 0.5]), np.array([0.3, -0.1, 0.45])
QUAT0 = np.array([0.0, 0.0, 0.0, 1.0])
QUAT1 = np.array([math.sin(0.2), 0.0, 0.0, math.cos(0.2)])  # 0.4 rad about x
PATH = sk.trajectory.linear(np.concatenate([P0, QUAT0]), np.concatenate([P1, QUAT1]), vmax=0.5, amax=1.0)


def times(n: int, duration: float) -> np.ndarray:
    return np.linspace(0.0, duration, n)


def path_baseline_args():
    L = float(np.linalg.norm(P1 - P0))
    V, A = 0.5 / L, 1.0 / L
    return V, A, 1 / V + V / A


def test_baselines_agree_with_spotkin():
    for profile, traj in TRAJ.items():
        t = times(10_001, traj.duration)
        if profile == "quintic":
            want = p2p_quintic(t, Q0, QF, traj.duration)
        else:
            want = p2p_trapezoid(
                t, Q0, QF, traj.acceleration, traj.cruise_velocity, traj.ramp_time, traj.duration
            )
        for g, w in zip(traj.sample(t), want):
            np.testing.assert_allclose(g, w, atol=1e-12)
    V, A, tf = path_baseline_args()
    assert tf == pytest.approx(PATH.duration, rel=1e-14)
    t = times(10_001, PATH.duration)
    np.testing.assert_allclose(PATH.sample(t), linear_path(t, P0, P1, QUAT0, QUAT1, V, A, tf), atol=1e-12)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy"])
@pytest.mark.parametrize("profile", ["quintic", "trapezoid"])
def test_point_to_point_sample(measure, profile, impl, n):
    traj = TRAJ[profile]
    t = times(n, traj.duration)
    op = f"traj.p2p.{profile}"
    if impl != "numpy":
        measure(op, n, impl, traj.sample, t)
    elif profile == "quintic":
        measure(op, n, impl, p2p_quintic, t, Q0, QF, traj.duration)
    else:
        args = (traj.acceleration, traj.cruise_velocity, traj.ramp_time, traj.duration)
        measure(op, n, impl, p2p_trapezoid, t, Q0, QF, *args)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread", "numpy"])
def test_linear_path_sample(measure, impl, n):
    t = times(n, PATH.duration)
    if impl == "numpy":
        measure("traj.linear.matrix", n, impl, linear_path, t, P0, P1, QUAT0, QUAT1, *path_baseline_args())
    else:
        measure("traj.linear.matrix", n, impl, PATH.sample, t)


def waypoints(n: int) -> np.ndarray:
    """n poses (n, 6): a helix with 0.3 mm jitter (many corners to blend) and a turning body."""
    s = np.linspace(0.0, 40 * np.pi, n)
    jitter = np.random.default_rng(5).normal(0.0, 3e-4, (n, 3))
    positions = np.stack([np.cos(s), np.sin(s), s / 50], axis=1) + jitter
    euler = np.stack([0.1 * np.sin(s / 7), 0.1 * np.cos(s / 5), s / 20], axis=1)
    return np.concatenate([positions, euler], axis=1)


@pytest.mark.parametrize("n", [1_000, 100_000])
def test_via_points_plan(measure, n):
    """Planning the blends of an n-waypoint path (O(n log n)); time per waypoint."""
    measure("traj.via_points.plan", n, "spotkin", sk.trajectory.via_points, waypoints(n), 1.0, 2.0, 1.0, 2.0)
