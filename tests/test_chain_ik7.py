"""7-joint arms with one joint held (redundancy resolution by a free joint): Franka-Panda-like and
Kinova-Gen3-like tables. Every solution against FK round trips and the pure-Python reference
(``ik6r.solve_free``), broadcasting of the free value, self-motion sampling, the nearest solution
to a seed, and the errors and statuses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import spotkin as sk
from conftest import PANDA_ROWS, panda
from spotkin.reference import ik6r

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

PI = math.pi


def kinova_like() -> sk.Chain:
    """A Kinova-Gen3-like S-R-S arm: shoulder axes z, y, z meeting at 0.28 m, an elbow y with a
    small lateral offset, wrist axes z, y, z meeting (continuous joints 1, 3, 5, 7)."""
    _, Y, Z = np.eye(3)
    axes = np.array([Z, Y, Z, Y, Z, Y, Z])
    points = np.array(
        [[0, 0, 0.28], [0, 0, 0.28], [0, 0, 0.28], [0, 0.01, 0.69], [0, 0, 1.0], [0, 0, 1.0], [0, 0, 1.0]]
    )
    placements = np.tile(np.eye(4), (7, 1, 1))
    placements[:, :3, 3] = np.diff(np.vstack([np.zeros(3), points]), axis=0)
    tool = sk.translation([0.0, 0.0, 0.16])
    free = (-np.inf, np.inf)
    limits = [free, (-2.41, 2.41), free, (-2.66, 2.66), free, (-2.23, 2.23), free]
    return sk.Chain.from_joints(placements, axes, tool=tool, limits=limits)


# (chain, held joint, family of the other six): the first and last joints go through one 6R solver
# for every value (the pose moved by the held joint's motion), a middle joint through one per value
ARMS = {
    "panda-7": (panda, 6, "6R-spherical-shoulder"),
    "panda-5": (panda, 4, "6R-spherical-shoulder"),
    "kinova-1": (kinova_like, 0, "6R-spherical-wrist"),
    "kinova-3": (kinova_like, 2, "6R-spherical-wrist"),
    "kinova-7": (kinova_like, 6, "6R-spherical-shoulder"),
}


def angle_gap(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def configurations(chain: sk.Chain, rng, n: int) -> np.ndarray:
    lower, upper = chain.lower, chain.upper
    lo, hi = np.where(np.isfinite(lower), lower, -PI), np.where(np.isfinite(upper), upper, PI)
    return rng.uniform(lo + 0.05, hi - 0.05, (n, 7))


@pytest.mark.parametrize("name", sorted(ARMS))
def test_every_solution_and_the_generating_configuration(name, rng):
    make, k, kind = ARMS[name]
    chain = make()
    assert chain.ik_free_kind(k) == kind
    q = configurations(chain, rng, 2000)
    T = chain.fk(q)
    sol = chain.ik_all(T, free_joint=k, free_value=q[:, k])
    assert sol.q.shape == (2000, 8, 7)
    assert (sol.status == sk.Status.OK).all()
    assert (sol.exact == sol.exists).all()
    # the held joint is the value given, every solution reaches the pose
    np.testing.assert_array_equal(sol.q[..., k][sol.exists], np.repeat(q[:, k], sol.exists.sum(axis=1)))
    found = sol.q[sol.exists]
    assert np.abs(chain.fk(found) - np.repeat(T, sol.exists.sum(axis=1), axis=0)).max() < 1e-9
    gap = angle_gap(sol.q, q[:, None, :]).max(axis=2)
    assert (np.where(sol.exists, gap, np.inf).min(axis=1) < 1e-7).all()
    # valid = exists and every joint within its limits
    lower, upper = chain.lower, chain.upper
    inside = ((sol.q >= lower - 1e-9) & (sol.q <= upper + 1e-9)).all(axis=2)
    np.testing.assert_array_equal(sol.valid, sol.exists & inside)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_matches_the_reference(name, rng):
    make, k, _ = ARMS[name]
    chain = make()
    poe = ik6r.from_sk_chain(chain)
    q = configurations(chain, rng, 10)
    T = chain.fk(q)
    sol = chain.ik_all(T, free_joint=k, free_value=q[:, k])
    for i in range(len(q)):
        ref = ik6r.solve_free(poe, T[i], free_joint=k, free_value=float(q[i, k]))
        ours = sol.q[i][sol.exists[i]]
        theirs = ref.q[ref.exists]
        # the reference's searched (scan) families may miss a branch: ours, FK-checked above,
        # contain every one of its solutions
        assert len(ours) >= len(theirs) > 0
        for row in theirs:
            assert angle_gap(ours, row).max(axis=1).min() < 1e-7


@pytest.mark.parametrize("name", ["panda-5", "kinova-3"])
def test_middle_joint_solvers_are_cached_and_grouped_by_value(name, rng):
    make, k, _ = ARMS[name]
    chain = make()
    core = chain._free_core(k)
    poses = chain.fk(configurations(chain, rng, 40))
    grid = np.linspace(-1.0, 1.0, 7)
    # 40 poses against 7 values, interleaved: one 6R solver per value, kept across calls
    first = chain.ik_all(poses[:, None], free_joint=k, free_value=grid)
    assert core.cached_values == 7
    again = chain.ik_all(poses[:, None], free_joint=k, free_value=grid)
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a, b)
    # a pose's answer does not depend on its neighbours: shuffled, each sample alone, other threads
    flat_T = np.broadcast_to(poses[:, None], (40, 7, 4, 4)).reshape(-1, 4, 4)
    flat_v = np.broadcast_to(grid, (40, 7)).reshape(-1)
    order = rng.permutation(len(flat_v))
    shuffled = chain.ik_all(flat_T[order], free_joint=k, free_value=flat_v[order])
    np.testing.assert_array_equal(shuffled.q, first.q.reshape(-1, 8, 7)[order])
    np.testing.assert_array_equal(shuffled.status, first.status.reshape(-1)[order])
    for i in (0, 13, 279):
        one = chain.ik_all(flat_T[i], free_joint=k, free_value=flat_v[i])
        np.testing.assert_array_equal(one.q, first.q.reshape(-1, 8, 7)[i])
    threads = sk.get_num_threads()
    try:
        sk.set_num_threads(2)
        two = chain.ik_all(flat_T, free_joint=k, free_value=flat_v)
    finally:
        sk.set_num_threads(threads)
    np.testing.assert_array_equal(two.q, first.q.reshape(-1, 8, 7))
    # bounded: the most recently used values only; -0.0 is 0.0
    chain.ik_all(np.broadcast_to(poses[0], (1500, 4, 4)), free_joint=k, free_value=np.linspace(-2, 2, 1500))
    assert core.cached_values == 1024
    zero, negative_zero = chain.ik_all(poses[0], free_joint=k, free_value=np.array([0.0, -0.0]))[0]
    np.testing.assert_array_equal(zero, negative_zero)


@pytest.mark.parametrize("name", ["panda-7", "kinova-1", "kinova-7"])
def test_end_joints_take_a_value_per_pose(name, rng):
    """The first or last joint held: a distinct value per pose, in one batch, round trips exactly;
    a bad pose or value is INVALID_INPUT for that sample only."""
    make, k, _ = ARMS[name]
    chain = make()
    q = configurations(chain, rng, 3000)
    T = chain.fk(q)
    sol = chain.ik_all(T, free_joint=k, free_value=q[:, k])
    assert (sol.status == sk.Status.OK).all()
    found = sol.q[sol.exists]
    assert np.abs(chain.fk(found) - np.repeat(T, sol.exists.sum(axis=1), axis=0)).max() < 1e-9
    # position + quaternion poses give the same solutions
    pq = np.concatenate([T[:, :3, 3], Rotation.from_matrix(T[:, :3, :3]).as_quat()], axis=1)
    by_pq = chain.ik_all(pq, free_joint=k, free_value=q[:, k])
    assert (by_pq.status == sk.Status.OK).all()
    found = by_pq.q[by_pq.exists]
    assert np.abs(chain.fk(found) - np.repeat(T, by_pq.exists.sum(axis=1), axis=0)).max() < 1e-9
    bad = T[:4].copy()
    bad[1, 0, 0] += 1e-3  # not a rotation
    values = q[:4, k].copy()
    values[2] = np.inf
    out = chain.ik_all(bad, free_joint=k, free_value=values)
    assert out.status[1] == sk.Status.INVALID_INPUT and np.isnan(out.q[1]).all()
    assert out.status[2] == sk.Status.INVALID_INPUT and np.isnan(out.q[2]).all()
    assert out.status[0] == out.status[3] == sk.Status.OK
    np.testing.assert_array_equal(out.q[[0, 3]], sol.q[[0, 3]])


def test_free_values_broadcast_and_sample_the_self_motion(rng):
    chain = panda()
    q = configurations(chain, rng, 1)[0]
    T = chain.fk(q)
    values = np.linspace(-2.5, 2.5, 11)
    sol = chain.ik_all(T, free_joint=6, free_value=values)
    assert sol.q.shape == (11, 8, 7) and sol.status.shape == (11,)
    grid, motion = chain.ik_self_motion(T, 6, 24)
    np.testing.assert_allclose(grid, np.linspace(-2.8973, 2.8973, 24))
    assert motion.q.shape == (24, 8, 7)
    for sample in (sol, motion):
        found = sample.q[sample.exists]
        assert len(found) > 0
        assert np.abs(chain.fk(found) - T).max() < 1e-9
    # a batch of poses against a grid of values: (..., n, 8, 7)
    Ts = chain.fk(configurations(chain, rng, 3))
    grid, many = chain.ik_self_motion(Ts, 6, np.array([0.1, 0.5]))
    assert many.q.shape == (3, 2, 8, 7)
    # float32 stays float32
    assert chain.ik_all(T.astype(np.float32), free_joint=6, free_value=np.float32(0.3)).q.dtype == np.float32


def test_nearest_to_a_seed(rng):
    chain = kinova_like()
    q = configurations(chain, rng, 200)
    T = chain.fk(q)
    seed = q + rng.normal(0, 0.01, q.shape)
    best, status = chain.ik_nearest_free(T, seed, 2, values=16)
    assert best.shape == (200, 7) and (status == sk.Status.OK).all()
    assert np.abs(chain.fk(best) - T).max() < 1e-9
    # never farther from the seed than the best valid solution at the seed's own value (a candidate)
    best_move = angle_gap(best, seed).max(axis=1)
    own = chain.ik_all(T, free_joint=2, free_value=seed[:, 2])
    own_move = np.where(own.valid, angle_gap(own.q, seed[:, None, :]).max(axis=2), np.inf).min(axis=1)
    assert (best_move <= own_move + 1e-12).all()
    assert np.median(best_move) < 0.05
    one, one_status = chain.ik_nearest_free(T[0], seed[0], 2)
    assert one.shape == (7,) and isinstance(one_status, sk.Status)
    bad_seed = seed[0].copy()
    bad_seed[3] = np.nan
    q_bad, st_bad = chain.ik_nearest_free(T[0], bad_seed, 2)
    assert st_bad == sk.Status.INVALID_INPUT and np.isnan(q_bad).all()


def test_ik_chooses_among_a_held_values_solutions_or_searches_the_joint(rng):
    """chain.ik (the solver interface's one answer) on a 7-joint chain: with free_joint and free_value,
    the valid solution at that value nearest the seed (the lowest valid slot without one); with
    free_joint alone, ik_nearest_free's search near the seed."""
    chain = kinova_like()
    q = configurations(chain, rng, 64)
    T = chain.fk(q)
    seed = q + rng.normal(0, 1e-3, q.shape)
    chosen, status = chain.ik(T, seed, free_joint=2, free_value=q[:, 2])
    assert chosen.shape == (64, 7) and (status == sk.Status.OK).all()
    assert angle_gap(chosen, q).max() < 1e-8  # the generating configuration is the nearest
    every = chain.ik_all(T, free_joint=2, free_value=q[:, 2])
    first = np.argmax(every.valid, axis=1)
    lowest, _ = chain.ik(T, free_joint=2, free_value=q[:, 2])
    np.testing.assert_array_equal(lowest, every.q[np.arange(64), first])
    searched, searched_status = chain.ik(T[:8], seed[:8], free_joint=2)
    expected, expected_status = chain.ik_nearest_free(T[:8], seed[:8], 2)
    np.testing.assert_array_equal(searched, expected)
    np.testing.assert_array_equal(searched_status, expected_status)
    one, one_status = chain.ik(T[0], seed[0], free_joint=2, free_value=q[0, 2])
    assert one.shape == (7,) and one_status == sk.Status.OK
    bad = seed[0].copy()
    bad[1] = np.nan
    q_bad, st_bad = chain.ik(T[0], bad, free_joint=2, free_value=q[0, 2])
    assert st_bad == sk.Status.INVALID_INPUT and np.isnan(q_bad).all()
    with pytest.raises(ValueError, match="redundant"):
        chain.ik(T[0])
    with pytest.raises(ValueError, match="seed"):
        chain.ik(T[0], free_joint=2)
    with pytest.warns(DeprecationWarning, match="ik_nearest"):
        six = sk.Chain.from_urdf(sk.robots.path("ur5"), tip="tool0")
        q6 = np.array([0.3, -1.2, 1.4, -0.8, 1.1, 0.4])
        np.testing.assert_array_equal(six.ik_nearest(six.fk(q6), q6)[0], six.ik(six.fk(q6), q6)[0])


def test_errors_and_statuses(rng):
    chain = panda()
    T = chain.fk(configurations(chain, rng, 4))
    with pytest.raises(ValueError, match="redundant"):
        chain.ik_all(T)
    with pytest.raises(ValueError, match=r"free_joint must be in \[0, 6\]"):
        chain.ik_all(T, free_joint=7, free_value=0.0)
    with pytest.raises(TypeError, match="free_joint"):
        chain.ik_all(T, free_joint=True, free_value=0.0)
    with pytest.raises(ValueError, match="needs free_value"):
        chain.ik_all(T, free_joint=6)
    with pytest.raises(ValueError, match="free_value needs free_joint"):
        chain.ik_all(T, free_value=0.3)
    with pytest.raises(ValueError, match="do not broadcast"):
        chain.ik_all(T, free_joint=6, free_value=np.zeros(3))
    six = sk.Chain.from_mdh(PANDA_ROWS[:6])
    with pytest.raises(ValueError, match="7-joint chains"):
        six.ik_all(np.eye(4), free_joint=2, free_value=0.0)
    # holding joint 1 leaves no closed-form family: the checks are named
    with pytest.raises(ValueError, match="no closed-form 6R family"):
        chain.ik_all(T, free_joint=0, free_value=-1.0)
    # NaN value: INVALID_INPUT for that sample only; a value outside its limits: no valid slot
    values = np.array([np.nan, 0.2, 5.0, 0.2])
    sol = chain.ik_all(T, free_joint=6, free_value=values)
    assert sol.status[0] == sk.Status.INVALID_INPUT and np.isnan(sol.q[0]).all()
    assert not sol.valid[2].any()
    assert sol.status[2] in (sk.Status.JOINT_LIMIT, sk.Status.UNREACHABLE)


def test_empty_and_unreachable_batches(rng):
    chain = panda()
    q, status = chain.ik_nearest_free(np.zeros((0, 4, 4)), np.zeros((0, 7)), 6, values=4)
    assert q.shape == (0, 7) and status.shape == (0,)
    far = chain.fk(configurations(chain, rng, 3))
    far[:, :3, 3] *= 10  # 10 m away: no solution for any value
    sol = chain.ik_all(far, free_joint=6, free_value=0.2)
    assert (sol.status == sk.Status.UNREACHABLE).all() and np.isnan(sol.q).all()
    q, status = chain.ik_nearest_free(far, np.zeros((3, 7)), 6, values=4)
    assert (status == sk.Status.UNREACHABLE).all() and np.isnan(q).all()
