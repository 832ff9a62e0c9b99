"""Closed-form IK from DH tables: the general 3-joint position solve (target: <= 300 ns per target
per core with every solution) and the 6R spherical-wrist solve from a table (target: <= 2x the
time of the Spot-arm fast path, which runs as "ref:" in the same group, so speed-up >= 0.5x)."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk

ARM = sk.Spot().arm
# A chain with both consecutive pairs of axes skew: Pieper's quartic, up to 4 solutions.
GENERAL_ROWS = [(0, 0.3, 0.4, 0.1, 0.2), (0, 0.5, 1.1, 0.2, -0.3), (0, 0.4, -0.7, 0.3, 0.5)]
GENERAL = sk.Chain.from_mdh(GENERAL_ROWS, tool=sk.translation([0.2, 0.1, 0.3]))
# The Spot leg as a DHm table (knee offset left out): the parallel (degree-2) closed form.
LEG = sk.Chain.from_mdh(
    [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.110945, 0.0), (0, 0.3205, 0.0, 0.0, 0.0)],
    tool=sk.translation([0.3365, 0.0, 0.0]),
)


def arm_chain() -> sk.Chain:
    """The Spot arm as a DHm table (the table tests/test_arm.py derives)."""
    a, h, b = (sk.models.SPOT["arm"][k] for k in ("upper_arm", "forearm_offset", "forearm"))
    rows = [
        (0, 0.0, 0.0, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, a, 0.0, 0.0, -np.pi / 2),
        (0, h, -np.pi / 2, b, 0.0),
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
    ]
    base = sk.translation(sk.models.SPOT["arm"]["mount"])
    bare = sk.Chain.from_mdh(rows, base=base)
    tool = np.linalg.inv(bare.fk(np.zeros(6))) @ ARM.fk(np.zeros(6))
    return sk.Chain.from_mdh(rows, base=base, tool=tool, limits=ARM.limits)


ARM_CHAIN = arm_chain()


def targets(chain: sk.Chain, n: int) -> np.ndarray:
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (n, chain.dof))
    return chain.fk(q)[:, :3, 3]


def test_kinds():
    assert GENERAL.ik_kind == "3R-general-quartic"
    assert LEG.ik_kind == "3R-parallel"
    assert ARM_CHAIN.ik_kind == "6R-spherical-wrist"


@pytest.mark.parametrize("n", [1, 100_000])
@pytest.mark.parametrize("impl", ["spotkin", "spotkin-1thread"])
@pytest.mark.parametrize("name", ["general-quartic", "parallel"])
def test_position_ik(measure, name, impl, n):
    chain = GENERAL if name == "general-quartic" else LEG
    p = targets(chain, n)
    measure(f"Chain.ik_position {name}", n, impl, chain.ik_position, p[0] if n == 1 else p)


@pytest.mark.parametrize("n", [1, 100_000])
@pytest.mark.parametrize("impl", ["Chain.ik-1thread", "ref:SpotArm.ik_all-1thread", "Chain.ik"])
def test_6r_from_table(measure, impl, n):
    T = ARM.fk(np.random.default_rng(1).uniform(-np.pi, np.pi, (n, 6)))
    T = T[0] if n == 1 else T
    func = ARM.ik_all if impl.startswith("ref:") else ARM_CHAIN.ik
    measure("6R spherical wrist, all 8", n, impl, func, T)


@pytest.mark.parametrize("n", [1, 100_000])
@pytest.mark.parametrize("impl", ["Chain.ik_nearest-1thread", "ref:SpotArm.ik-1thread"])
def test_6r_nearest_from_table(measure, impl, n):
    rng = np.random.default_rng(2)
    T = ARM.fk(rng.uniform(-np.pi, np.pi, (n, 6)))
    seed = rng.uniform(-np.pi, np.pi, (n, 6))
    T, seed = (T[0], seed[0]) if n == 1 else (T, seed)
    func = ARM.ik if impl.startswith("ref:") else ARM_CHAIN.ik_nearest
    measure("6R nearest to a seed", n, impl, func, T, seed)
