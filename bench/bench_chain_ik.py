"""Closed-form IK from DH tables: the general 3-joint position solve (target: <= 300 ns per target
per core with every solution) and the 6R spherical-wrist solve from a table (target: <= 2x the
time of the Spot-arm fast path, which runs as "ref:" in the same group, so speed-up >= 0.5x).

The 6R families beyond the wrist (issue targets: UR5, all 8 solutions, >= 15x EAIK's IK_batched
per core (EAIK with one worker thread), and <= 2x the spherical-wrist path, speed-up >= 0.5x
against "ref:SpotArm.ik_all"):
"6R 2-3-4 UR5 vs EAIK" (EAIK as ref: where it installs), "6R 2-3-4 UR5 vs the wrist path",
and the 1-2-3 parallel family beside the wrist path."""

from __future__ import annotations

import importlib.util

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
HAS_EAIK = importlib.util.find_spec("eaik") is not None
# UR5, Universal Robots' standard DH table as (sigma, a, alpha, d, theta): axes 2, 3, 4 parallel
UR5 = sk.Chain.from_dh(
    [
        (0, 0.0, np.pi / 2, 0.089159, 0.0),
        (0, -0.425, 0.0, 0.0, 0.0),
        (0, -0.39225, 0.0, 0.0, 0.0),
        (0, 0.0, np.pi / 2, 0.10915, 0.0),
        (0, 0.0, -np.pi / 2, 0.09465, 0.0),
        (0, 0.0, 0.0, 0.0823, 0.0),
    ]
)


def parallel_123_chain() -> sk.Chain:
    """Axes 1, 2, 3 parallel (z), an offset wrist x, y, z whose axes 4 and 5 meet."""
    points = np.array(
        [[0, 0, 0], [0.35, 0, 0.05], [0.65, 0.02, 0.1], [0.8, 0, 0.15], [0.9, 0, 0.15], [0.95, 0.08, 0.15]]
    )
    axes = np.array([[0, 0, 1], [0, 0, 1], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    placements = np.tile(np.eye(4), (6, 1, 1))
    placements[:, :3, 3] = np.diff(np.vstack([np.zeros(3), points]), axis=0)
    tool = sk.translation(np.array([1.0, 0.08, 0.1]) - points[-1])
    return sk.Chain.from_joints(placements, axes, tool=tool)


PARALLEL_123 = parallel_123_chain()


def ur5_eaik():
    """EAIK's H, P description of UR5 (from the chain's Jacobian at q = 0), and the tool rotation
    EAIK leaves out (its tool frame at q = 0 is the base's)."""
    from eaik.IK_HP import HPRobot

    M, J = UR5.fk(np.zeros(6)), UR5.jacobian(np.zeros(6))
    axes = J[3:].T
    points = np.array([np.cross(np.cross(h, M[:3, 3]) - v, h) for h, v in zip(axes, J[:3].T)])
    P = np.vstack([points[0], np.diff(points, axis=0), M[:3, 3] - points[-1]])
    return HPRobot(axes.copy(), P), M[:3, :3]


def targets(chain: sk.Chain, n: int) -> np.ndarray:
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (n, chain.dof))
    return chain.fk(q)[:, :3, 3]


def test_kinds():
    assert UR5.ik_kind == "6R-three-parallel-234"
    assert PARALLEL_123.ik_kind == "6R-three-parallel-123"
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


@pytest.mark.parametrize("n", [1, 100_000])
@pytest.mark.parametrize(
    "impl", ["Chain.ik-1thread", "Chain.ik", "ref:EAIK IK_batched-1worker", "EAIK IK_batched-2workers"]
)
def test_6r_parallel_234_vs_eaik(measure, impl, n):
    """Per core: EAIK's IK_batched with one worker thread (its default is 4) against spotkin on one
    thread; both on two threads beside them for the scaling."""
    T = UR5.fk(np.random.default_rng(3).uniform(-np.pi, np.pi, (n, 6)))
    if "EAIK" in impl:
        if not HAS_EAIK:
            pytest.skip("EAIK not installed")
        robot, tool_rotation = ur5_eaik()
        poses = T.copy()
        poses[:, :3, :3] = T[:, :3, :3] @ tool_rotation.T
        workers = 1 if impl.endswith("1worker") else 2
        measure("6R 2-3-4 UR5 vs EAIK, all 8", n, impl, robot.IK_batched, poses, workers)
    else:
        measure("6R 2-3-4 UR5 vs EAIK, all 8", n, impl, UR5.ik, T[0] if n == 1 else T)


@pytest.mark.parametrize("n", [1, 100_000])
@pytest.mark.parametrize(
    "impl", ["UR5 Chain.ik-1thread", "1-2-3 Chain.ik-1thread", "ref:SpotArm.ik_all-1thread"]
)
def test_6r_parallel_vs_wrist_path(measure, impl, n):
    rng = np.random.default_rng(4)
    chain = {"UR5": UR5, "1-2-3": PARALLEL_123}.get(impl.split()[0], None)
    T = (chain or ARM).fk(rng.uniform(-np.pi, np.pi, (n, 6)))
    T = T[0] if n == 1 else T
    func = ARM.ik_all if chain is None else chain.ik
    measure("6R parallel families vs the wrist path, all 8", n, impl, func, T)


def poe_chain(axes, points, tool_position, limits=None) -> sk.Chain:
    """A revolute chain from its axes and a point on each (base frame, q = 0)."""
    points = np.asarray(points, dtype=float)
    placements = np.tile(np.eye(4), (len(points), 1, 1))
    placements[:, :3, 3] = np.diff(np.vstack([np.zeros(3), points]), axis=0)
    tool = sk.translation(np.asarray(tool_position, dtype=float) - points[-1])
    return sk.Chain.from_joints(placements, np.asarray(axes, dtype=float), tool=tool, limits=limits)


X_, Y_, Z_ = np.eye(3)
# A spherical shoulder (z, y, x meet) and an offset forearm and wrist: the reversed wrist path
SHOULDER = poe_chain(
    [Z_, Y_, X_, Y_, X_, Z_],
    [[0, 0, 0.1], [0, 0, 0.1], [0, 0, 0.1], [0.3, 0, 0.12], [0.55, 0.05, 0.1], [0.65, 0, 0.12]],
    [0.75, 0.02, 0.12],
)
# Franka Emika Panda's published modified-DH table; holding joint 7 leaves a spherical shoulder
PANDA = sk.Chain.from_mdh(
    [
        (0, 0.0, 0.0, 0.333, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, 0.0, np.pi / 2, 0.316, 0.0),
        (0, 0.0825, np.pi / 2, 0.0, 0.0),
        (0, -0.0825, -np.pi / 2, 0.384, 0.0),
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.088, np.pi / 2, 0.0, 0.0),
    ],
    tool=sk.translation([0.0, 0.0, 0.107]),
)


@pytest.mark.parametrize("n", [100_000])
@pytest.mark.parametrize(
    "impl",
    [
        "shoulder Chain.ik-1thread",
        "Panda free joint, one value-1thread",
        "Panda free joint, a value per pose-1thread",
        "ref:SpotArm.ik_all-1thread",
    ],
)
def test_6r_shoulder_and_7r_free_joint_vs_wrist_path(measure, impl, n):
    rng = np.random.default_rng(5)
    if impl.startswith("shoulder"):
        T = SHOULDER.fk(rng.uniform(-np.pi, np.pi, (n, 6)))
        measure("6R shoulder, 7R free joint vs the wrist path, all 8", n, impl, SHOULDER.ik, T)
    elif impl.startswith("Panda"):
        q = rng.uniform(-1.0, 1.0, (n, 7))
        q[:, 3] = -1.5
        T = PANDA.fk(q)
        # one value for every pose, or each pose's own (1e5 distinct values; target: <= 3x the wrist path)
        value = 0.3 if "one value" in impl else q[:, 6]
        func = lambda T: PANDA.ik(T, free_joint=6, free_value=value)  # noqa: E731
        measure("6R shoulder, 7R free joint vs the wrist path, all 8", n, impl, func, T)
    else:
        T = ARM.fk(rng.uniform(-np.pi, np.pi, (n, 6)))
        measure("6R shoulder, 7R free joint vs the wrist path, all 8", n, impl, ARM.ik_all, T)
