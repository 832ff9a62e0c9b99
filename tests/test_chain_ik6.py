"""Closed-form IK of 6R families (Chain.ik): three parallel axes 2-3-4 (UR, Z1), the spherical
shoulder, the spherical wrist, and calibrated (nearly special) chains, against the pure-Python
reference (spotkin.reference.ik6r), FK round trips and EAIK."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_reference_ik6r import (
    UR3,
    UR5,
    UR10,
    angle_gap,
    eaik_pose,
    eaik_robot,
    perturbed,
    shoulder_arm,
    spot_arm_chain,
    ur5_singular,
    z1_like,
)

import spotkin as sk
from spotkin.reference import ik6r

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

PI = math.pi
X, Y, Z = np.eye(3)


def sk_chain(poe: ik6r.Chain6, limits=None) -> sk.Chain:
    """An sk.Chain with the FK of a POE description: joint j at p_j, axes in base directions."""
    n = len(poe.axes)
    placements = np.tile(np.eye(4), (n, 1, 1))
    placements[:, :3, 3] = np.diff(np.vstack([np.zeros(3), poe.points]), axis=0)
    tool = poe.tool.copy()
    tool[:3, 3] -= poe.points[-1]
    return sk.Chain.from_joints(placements, poe.axes, tool=tool, limits=limits)


def parallel_123_arm(skew: bool = False) -> ik6r.Chain6:
    """Axes 1, 2, 3 parallel (a SCARA-like planar shoulder) and an offset wrist whose axes 4 and 5
    meet (the rank-1 pair of equations), or pass 0.07 m apart (skew: the quartic)."""
    tool = np.eye(4)
    tool[:3, :3] = sk.rotation_y(0.4)[:3, :3]
    tool[:3, 3] = [1.0, 0.08, 0.1]
    p5 = [0.9, 0.0, 0.22 if skew else 0.15]
    return ik6r.make_chain(
        [Z, Z, Z, X, Y, Z],
        [[0, 0, 0], [0.35, 0, 0.05], [0.65, 0.02, 0.1], [0.8, 0, 0.15], p5, [0.95, 0.08, 0.15]],
        tool,
    )


CHAINS = {
    "parallel-123": parallel_123_arm,
    "parallel-123-skew": lambda: parallel_123_arm(skew=True),
    "UR5": lambda: ik6r.from_dh(UR5),
    "UR10": lambda: ik6r.from_dh(UR10),
    "UR3": lambda: ik6r.from_dh(UR3),
    "Z1-like": z1_like,
    "shoulder": shoulder_arm,
    "spot_arm": spot_arm_chain,
}
KINDS = {
    "parallel-123": "6R-three-parallel-123",
    "parallel-123-skew": "6R-three-parallel-123",
    "UR5": "6R-three-parallel-234",
    "UR10": "6R-three-parallel-234",
    "UR3": "6R-three-parallel-234",
    "Z1-like": "6R-three-parallel-234",
    "shoulder": "6R-spherical-shoulder",
    "spot_arm": "6R-spherical-wrist",
}


def contains(q_set: np.ndarray, q: np.ndarray, tol: float) -> bool:
    return bool(len(q_set)) and float(angle_gap(q_set, q).max(axis=1).min()) < tol


def fk_error(chain: sk.Chain, q: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Max |fk(q) - T| per row of q (..., 6) against T (..., 4, 4)."""
    return np.abs(chain.fk(q) - T).max(axis=(-2, -1))


# ---- families and detection --------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(CHAINS))
def test_kind_matches_the_reference_classification(name):
    poe = CHAINS[name]()
    chain = sk_chain(poe)
    assert chain.ik_kind == KINDS[name]
    reference = {
        "spherical_wrist": "6R-spherical-wrist",
        "three_parallel_234": "6R-three-parallel-234",
        "three_parallel_123": "6R-three-parallel-123",
        "spherical_shoulder": "6R-spherical-shoulder",
    }
    assert chain.ik_kind == reference[ik6r.classify(poe)]
    assert not chain.ik_idealised
    geometry = chain.ik_geometry
    assert set(geometry) == {
        "wrist_meeting",
        "shoulder_meeting",
        "parallel_234",
        "parallel_123",
        "axes_5_6_gap",
        "axes_4_5_gap",
    }
    # the gaps between axes 5 and 6, 4 and 5: |(p_j - p_i) . n| along their common normal
    for key, (i, j) in {"axes_5_6_gap": (4, 5), "axes_4_5_gap": (3, 4)}.items():
        normal = np.cross(poe.axes[i], poe.axes[j])
        sine = np.linalg.norm(normal)
        expected = 0.0 if sine < 1e-12 else abs((poe.points[j] - poe.points[i]) @ normal) / sine
        assert geometry[key] == pytest.approx(expected, abs=1e-12)


def test_dh_tables_are_recognised():
    for rows in (UR3, UR5, UR10):
        assert sk.Chain.from_dh(rows).ik_kind == "6R-three-parallel-234"


def test_chain_of_no_family_raises_naming_what_was_checked():
    X, Y, Z = np.eye(3)
    general = ik6r.make_chain(
        [Z, Y, X, Y, Z, X], [[0, 0, 0], [0.1, 0, 0], [0.2, 0.1, 0], [0.3, 0, 0.1], [0.4, 0.1, 0], [0.5, 0, 0]]
    )
    chain = sk_chain(general)
    with pytest.raises(ValueError, match=r"axes 4-5-6 meeting.*axes 2-3-4 parallel.*ik_differential"):
        chain.ik_all(np.eye(4))
    with pytest.raises(ValueError, match="ik_differential"):
        _ = chain.ik_kind


# ---- against the reference, slot by slot --------------------------------------------------------------


def assert_same_slots(ours, ref, tol):
    assert (ours.exists == ref.exists).all(), (ours.exists, ref.exists)
    gap = angle_gap(ours.q[ours.exists], ref.q[ref.exists])
    assert gap.size == 0 or gap.max() < tol, gap.max()


@pytest.mark.parametrize("name", ["UR5", "UR10", "UR3", "Z1-like", "parallel-123", "parallel-123-skew"])
def test_parallel_234_matches_the_reference_slot_by_slot(name, rng):
    poe = CHAINS[name]()
    chain = sk_chain(poe)
    q = rng.uniform(-PI, PI, (200, 6))
    T = chain.fk(q)
    T[-40:, :3, 3] += rng.normal(size=(40, 3)) * 0.2  # other targets, some unreachable
    sol = chain.ik_all(T)
    for i in range(len(q)):
        ref = ik6r.solve(poe, T[i])
        assert_same_slots(
            sk.ChainSolutions(sol.q[i], sol.valid[i], sol.exists[i], sol.exact[i], sol.status[i]), ref, 1e-8
        )


@pytest.mark.parametrize("name", ["shoulder", "spot_arm"])
def test_searched_families_contain_the_reference(name, rng):
    """The reference finds these by a 1-D scan, which can miss a pair of roots that nearly touch:
    every reference solution is one of ours, and ours are exact (test_round_trips)."""
    poe = CHAINS[name]()
    chain = sk_chain(poe)
    q = rng.uniform(-PI, PI, (10, 6))
    sol = chain.ik_all(chain.fk(q))
    for i in range(len(q)):
        ref = ik6r.solve(poe, chain.fk(q[i]))
        ours, theirs = sol.q[i][sol.exists[i]], ref.q[ref.exists]
        assert len(ours) >= len(theirs)
        for row in theirs:
            assert contains(ours, row, 1e-7)


# ---- FK round trips ------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("name", sorted(CHAINS))
def test_round_trips_1e5(name, dtype, rng):
    chain = sk_chain(CHAINS[name]())
    n = 100_000
    q = rng.uniform(-PI, PI, (n, 6))
    T = chain.fk(q)
    sol = chain.ik_all(T.astype(dtype))
    assert sol.q.dtype == dtype
    ok = sol.status == sk.Status.OK
    if dtype == np.float64:
        assert ok.all()
    else:
        # a float32 pose is a rounded pose: within ~1e-7 of a stretched elbow or a singular wrist
        # it can lie (just) outside the reach, and is then honestly UNREACHABLE
        assert ok.mean() > 0.9995
        assert set(np.unique(sol.status[~ok])) <= {sk.Status.UNREACHABLE}
    gap = angle_gap(sol.q.astype(np.float64), q[:, None, :]).max(axis=2)
    gap = np.where(sol.exists, gap, np.inf).min(axis=1)[ok]
    # float64: the generating configuration is found to 1e-7 except near singular ones
    tol = 1e-6 if dtype == np.float64 else 5e-3
    # float32: within ~1e-3 rad of a wrist singularity the rounded pose fixes q4 - q6 only roughly
    assert np.quantile(gap, 0.9999 if dtype == np.float64 else 0.999) < tol
    found = sol.q[sol.exists].astype(np.float64)
    error = fk_error(chain, found, np.repeat(T, sol.exists.sum(axis=1), axis=0))
    assert error.max() < (1e-9 if dtype == np.float64 else 2e-5)


@pytest.mark.parametrize("name", sorted(CHAINS))
def test_round_trips(name, rng):
    chain = sk_chain(CHAINS[name]())
    q = rng.uniform(-PI, PI, (2000, 6))
    T = chain.fk(q)
    sol = chain.ik_all(T)
    assert (sol.status == sk.Status.OK).all()
    assert (sol.exact == sol.exists).all()
    for i in range(len(q)):
        assert contains(sol.q[i][sol.exists[i]], q[i], 1e-6), (name, q[i])
    found = sol.q[sol.exists]
    assert fk_error(chain, found, np.repeat(T, sol.exists.sum(axis=1), axis=0)).max() < 1e-9
    # no duplicates: distinct slots are distinct configurations
    for i in range(0, len(q), 50):
        rows = sol.q[i][sol.exists[i]]
        gaps = angle_gap(rows[:, None, :], rows[None, :, :]).max(axis=2) + np.eye(len(rows))
        assert gaps.min() > 1e-6


@pytest.mark.parametrize("kind", ["shoulder", "elbow", "wrist"])
def test_near_singular_ur5(kind, rng):
    chain = sk.Chain.from_dh(UR5)
    for jitter in (0.0, 1e-9, -1e-7, 1e-5):
        q = np.array([ur5_singular(kind, rng, jitter) for _ in range(20)])
        T = chain.fk(q)
        sol = chain.ik_all(T)
        assert (sol.status == sk.Status.OK).all(), (kind, jitter)
        # exact solutions are exact; within 1e-7 of a wrist singularity the split of q4 and q6 is
        # fixed by the 1e-7 only, so a solution may end as approximate (exact False), never wrong
        exact = sol.q[sol.exact]
        assert fk_error(chain, exact, np.repeat(T, sol.exact.sum(axis=1), axis=0)).max() < 1e-9
        approx = sol.exists & ~sol.exact
        if approx.any():
            assert kind == "wrist" and 0 < abs(jitter) < 1e-6, (kind, jitter)
            assert fk_error(chain, sol.q[approx], np.repeat(T, approx.sum(axis=1), axis=0)).max() < 1e-6
        if kind == "wrist" and abs(jitter) < 1e-6:
            continue  # q4 and q6 trade off: any split is a solution
        for i in range(len(q)):
            assert contains(sol.q[i][sol.exists[i]], q[i], 1e-5 if jitter == 0.0 else 1e-6), (kind, jitter)


# ---- calibrated chains ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["UR5", "Z1-like", "spot_arm", "shoulder"])
def test_perturbed_geometry_is_solved_and_polished(name, rng):
    ideal = CHAINS[name]()
    tilted = perturbed(ideal, rng, 1e-3)  # every axis tilted by 1e-3 rad, and moved by 1e-3 m
    shift = rng.normal(size=tilted.points.shape)
    shift -= np.sum(shift * tilted.axes, axis=1, keepdims=True) * tilted.axes
    shift *= 1e-3 / np.linalg.norm(shift, axis=1, keepdims=True)
    chain = sk_chain(ik6r.Chain6(tilted.axes, tilted.points + shift, tilted.tool))
    with pytest.raises(ValueError, match="ik_differential"):
        _ = chain.ik_kind  # not special within the strict tolerance
    calibrated = chain.with_ik_tolerance(angle=5e-3, distance=5e-3)
    assert calibrated.ik_kind == KINDS[name]
    assert calibrated.ik_idealised
    q = rng.uniform(-PI, PI, (300, 6))
    T = chain.fk(q)
    sol = calibrated.ik_all(T)
    found = sol.q[sol.exact]
    # exact solutions are exact on the true chain, the others only within 1e-6
    assert fk_error(chain, found, np.repeat(T, sol.exact.sum(axis=1), axis=0)).max() < 1e-9
    approx = sol.exists & ~sol.exact
    if approx.any():
        assert fk_error(chain, sol.q[approx], np.repeat(T, approx.sum(axis=1), axis=0)).max() < 1e-5
    hits = [contains(sol.q[i][sol.exact[i]], q[i], 1e-6) for i in range(len(q))]
    # the generating configuration is found >99% of the time by the parallel families and the
    # wrist, ~98% by the shoulder (3000 targets each, measured; 96-97% for the last two before the
    # radially moved starts). The misses sit near wrist singularities, where 1e-3 of geometry moves
    # the solutions far and the true (general) 6R chain can have more than the family's 8 solutions,
    # or where a polished start lands on another solution.
    floor = 0.99 if KINDS[name].startswith("6R-three-parallel") else 0.97
    assert np.mean(hits) > floor, np.mean(hits)


def test_calibrated_tolerance_arguments():
    chain = sk.Chain.from_dh(UR5)
    assert chain.with_ik_tolerance().ik_kind == chain.ik_kind
    for bad in (-1.0, math.nan, 0.5):
        with pytest.raises(ValueError, match="angle"):
            chain.with_ik_tolerance(angle=bad)
    with pytest.raises(ValueError, match="distance"):
        chain.with_ik_tolerance(distance=math.inf)


# ---- limits, statuses, bad input, batches --------------------------------------------------------------


def test_limits_wrap_and_statuses(rng):
    q = np.array([0.3, -1.0, 1.2, 0.4, -0.6, 0.8])
    chain = sk_chain(CHAINS["UR5"](), limits=np.array([[0.0, 2 * PI]] * 6))
    sol = chain.ik_all(chain.fk(q))
    assert sol.status == sk.Status.OK
    assert (sol.valid == sol.exists).all()
    assert contains(sol.q[sol.valid], np.where(q < 0, q + 2 * PI, q), 1e-8)
    assert (sol.q[sol.valid] >= -1e-12).all()
    narrow = np.array([[0.2, 0.4], [-1.1, -0.9], [1.1, 1.3], [0.3, 0.5], [-0.7, -0.5], [0.7, 0.9]])
    tight = sk_chain(CHAINS["UR5"](), limits=narrow)
    sol = tight.ik_all(tight.fk(q))
    assert sol.valid.sum() == 1 and np.allclose(sol.q[sol.valid][0], q)
    far = tight.fk(q)
    far[:3, 3] = [5.0, 0.0, 0.0]
    out = tight.ik_all(np.stack([far, np.full((4, 4), np.nan), 2 * tight.fk(q)]))
    assert list(out.status) == [sk.Status.UNREACHABLE, sk.Status.INVALID_INPUT, sk.Status.INVALID_INPUT]
    assert np.isnan(out.q).all() and not out.exists.any() and not out.exact.any()
    blocked = sk_chain(CHAINS["UR5"](), limits=np.array([[2.0, 2.1]] * 6))
    assert blocked.ik_all(blocked.fk(q)).status == sk.Status.JOINT_LIMIT


@pytest.mark.parametrize("name", ["UR5", "shoulder"])
def test_ik_nearest_returns_the_seed_configuration(name, rng):
    chain = sk_chain(CHAINS[name]())
    q = rng.uniform(-PI, PI, (64, 6))
    q_back, status = chain.ik(chain.fk(q), q + 1e-4)
    assert (status == sk.Status.OK).all()
    assert angle_gap(q_back, q).max() < 1e-6
    xyzw = Rotation.from_matrix(chain.fk(q)[:, :3, :3]).as_quat()
    pose7 = np.concatenate([chain.fk(q)[:, :3, 3], xyzw], axis=1)
    q7, _ = chain.ik(pose7, q)
    assert angle_gap(q7, q).max() < 1e-6


@pytest.mark.parametrize("shape", [(), (1,), (3, 1, 2)])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_batch_shapes_and_single_calls(shape, dtype, rng):
    chain = sk_chain(CHAINS["UR5"]())
    q = rng.uniform(-PI, PI, (*shape, 6))
    T = chain.fk(q).astype(dtype)
    sol = chain.ik_all(T)
    assert sol.q.shape == (*shape, 8, 6) and sol.q.dtype == dtype
    assert sol.exact.shape == (*shape, 8) and np.shape(sol.status) == shape
    flat = chain.ik_all(T.reshape(-1, 4, 4))
    assert np.array_equal(flat.q.reshape(sol.q.shape), sol.q, equal_nan=True)
    if shape == ():
        assert isinstance(sol.status, sk.Status)
    strided = chain.ik_all(np.repeat(T.reshape(-1, 4, 4), 2, axis=0)[::2])
    assert np.array_equal(strided.q, flat.q, equal_nan=True)
    assert chain.ik_all(np.zeros((0, 4, 4))).q.shape == (0, 8, 6)
    with pytest.raises(ValueError, match="target"):
        chain.ik_all(np.zeros((3, 4, 3)))


def test_threads_give_identical_results(rng):
    chain = sk_chain(CHAINS["Z1-like"]())
    T = chain.fk(rng.uniform(-PI, PI, (5000, 6)))
    before = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = chain.ik_all(T)
        sk.set_num_threads(2)
        two = chain.ik_all(T)
    finally:
        sk.set_num_threads(before)
    assert np.array_equal(one.q, two.q, equal_nan=True) and np.array_equal(one.exact, two.exact)


# ---- EAIK --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["UR5", "UR10", "UR3", "Z1-like", "shoulder", "spot_arm"])
def test_against_eaik(name, rng):
    pytest.importorskip("eaik", reason="EAIK is not installed (pip install EAIK; see requirements-test.txt)")
    poe = CHAINS[name]()
    chain, robot = sk_chain(poe), eaik_robot(poe)
    q = rng.uniform(-PI, PI, (100, 6))
    T = chain.fk(q)
    sol = chain.ik_all(T)
    least_squares = 0
    for i in range(len(q)):
        theirs = robot.IK(eaik_pose(poe, T[i]))
        exact = [qe for qe, ls in zip(theirs.Q, theirs.is_LS) if not ls]
        if len(exact) < theirs.num_solutions():
            least_squares += 1
            continue
        ours = sol.q[i][sol.exists[i]]
        assert len(ours) == len(exact), (name, i)
        for row in exact:
            assert contains(ours, np.asarray(row), 1e-6), (name, i)
    print(f"EAIK {name}: {least_squares} of {len(q)} targets answered with least squares")
    if name != "shoulder":  # EAIK answers the spherical shoulder with least squares only
        assert least_squares < len(q)


def test_calibrated_chains_pickle_with_their_tolerance(rng):
    import pickle

    chain = sk_chain(perturbed(CHAINS["UR5"](), rng, 1e-4)).with_ik_tolerance(angle=1e-3, distance=1e-3)
    copy = pickle.loads(pickle.dumps(chain))
    assert copy.ik_idealised and copy.ik_kind == chain.ik_kind
    T = chain.fk(rng.uniform(-PI, PI, (50, 6)))
    a, b = chain.ik_all(T), copy.ik_all(T)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.exact, b.exact)
