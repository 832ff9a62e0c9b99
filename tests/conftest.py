"""Shared fixtures and helpers for the spotkin test suite."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import spotkin as sk

# Random examples locally (they explore); fixed ones under CI (CI=1 in .ci/run), so that a landing
# never hangs on a new draw. Cases Hypothesis finds are kept as @example.
settings.register_profile(
    "spotkin",
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    derandomize=bool(os.environ.get("CI")),
)
settings.load_profile("spotkin")

# Absolute tolerances against the float64 reference, per working dtype.
TOLERANCE = {np.float64: 1e-12, np.float32: 1e-5}
BATCH_SHAPES = [(), (1,), (3, 1, 2)]


@pytest.fixture(scope="module", params=sk.available_isas())
def every_isa(request):
    """Runs a test once per instruction-set level the CPU has (``sk.available_isas()``), with
    the kernels of that level: modules of reference cross-checks use it through
    ``pytestmark = pytest.mark.usefixtures("every_isa")``."""
    with sk.isa(request.param):
        yield request.param


@pytest.fixture(scope="module")
def cluster():
    """A local dask.distributed cluster (2 worker processes) and its client, for a test module."""
    distributed = pytest.importorskip("distributed")
    with (
        # no dashboard, and the scheduler's HTTP server on a free port: the default, 8787, may be
        # taken (another cluster on this machine), and distributed's warning would fail the test
        distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            scheduler_kwargs={"dashboard_address": ":0"},
            silence_logs=50,
        ) as local,
        distributed.Client(local) as client,
    ):
        yield local, client


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


def joint_distance(qa, qb, sigma) -> float:
    """max over joints: wrapped angle difference (revolute) or plain difference (prismatic)."""
    d = np.asarray(qa, dtype=float) - np.asarray(qb, dtype=float)
    d = np.where(np.asarray(sigma) == 0, np.abs(np.mod(d + np.pi, 2 * np.pi) - np.pi), np.abs(d))
    return float(np.max(d))


def newton_oracle(chain: sk.Chain, p, rng, starts=400, iters=60) -> list[np.ndarray]:
    """Brute force: damped Gauss-Newton (Levenberg-Marquardt) from many random starts, deduplicated."""
    sigma = chain.sigma
    Q = rng.uniform(-np.pi, np.pi, (starts, 3))
    Q[:, sigma == 1] *= 2.0
    lam = np.full(starts, 1e-2)
    r = chain.fk(Q)[:, :3, 3] - p
    cost = np.einsum("ki,ki->k", r, r)
    for _ in range(iters):
        J = chain.position_jacobian(Q)
        A = np.einsum("kij,kil->kjl", J, J) + lam[:, None, None] * np.eye(3)
        step = np.linalg.solve(A, np.einsum("kij,ki->kj", J, r)[:, :, None])[:, :, 0]
        Qn = Q - step
        rn = chain.fk(Qn)[:, :3, 3] - p
        cn = np.einsum("ki,ki->k", rn, rn)
        ok = cn < cost
        Q[ok], r[ok], cost[ok] = Qn[ok], rn[ok], cn[ok]
        lam = np.where(ok, np.maximum(lam / 5, 1e-12), lam * 4)
    found: list[np.ndarray] = []
    for q in Q[np.sqrt(cost) < 1e-11]:
        if all(joint_distance(q, f, sigma) > 1e-6 for f in found):
            found.append(q)
    return found


# Franka Emika Panda, its published modified-DH table as (sigma, a_{i-1}, alpha_{i-1}, d_i, theta_i),
# the flange 0.107 m along the last axis; its joint limits (rad).
PANDA_ROWS = [
    (0, 0.0, 0.0, 0.333, 0.0),
    (0, 0.0, -np.pi / 2, 0.0, 0.0),
    (0, 0.0, np.pi / 2, 0.316, 0.0),
    (0, 0.0825, np.pi / 2, 0.0, 0.0),
    (0, -0.0825, -np.pi / 2, 0.384, 0.0),
    (0, 0.0, np.pi / 2, 0.0, 0.0),
    (0, 0.088, np.pi / 2, 0.0, 0.0),
]
PANDA_LIMITS = [
    (-2.8973, 2.8973),
    (-1.7628, 1.7628),
    (-2.8973, 2.8973),
    (-3.0718, -0.0698),
    (-2.8973, 2.8973),
    (-0.0175, 3.7525),
    (-2.8973, 2.8973),
]


def panda() -> sk.Chain:
    return sk.Chain.from_mdh(PANDA_ROWS, tool=sk.translation([0.0, 0.0, 0.107]), limits=PANDA_LIMITS)
