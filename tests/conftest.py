"""Shared fixtures and helpers for the spotkin test suite."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "spotkin", max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile("spotkin")

# Absolute tolerances against the float64 reference, per working dtype.
TOLERANCE = {np.float64: 1e-12, np.float32: 1e-5}
BATCH_SHAPES = [(), (1,), (3, 1, 2)]


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


def random_rigid(rng: np.random.Generator) -> np.ndarray:
    """A random rigid transform (4, 4): QR-based rotation, translation in [-1, 1]^3."""
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    if np.linalg.det(Q) < 0:
        Q[:, 0] = -Q[:, 0]
    T = np.eye(4)
    T[:3, :3] = Q
    T[:3, 3] = rng.uniform(-1, 1, 3)
    return T


def random_table(rng: np.random.Generator, n: int, prismatic: bool = True) -> np.ndarray:
    """A random DH table (n, 5) with special angles and zero lengths mixed in."""
    rows = np.empty((n, 5))
    rows[:, 0] = (rng.random(n) < 0.3) if prismatic else 0
    special = np.array([0.0, np.pi / 2, -np.pi / 2, np.pi])
    for col in (2, 4):
        rows[:, col] = np.where(rng.random(n) < 0.5, rng.choice(special, n), rng.uniform(-np.pi, np.pi, n))
    for col in (1, 3):
        rows[:, col] = np.where(rng.random(n) < 0.3, 0.0, rng.uniform(-0.5, 0.5, n))
    return rows


def vee_so3(W: np.ndarray) -> np.ndarray:
    return np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]]) / 2
