"""Legs: C++ against the pure-Python reference, round trips, branches, limits,
singular sets, statuses, the course's DHm leg, and batch semantics."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from conftest import BATCH_SHAPES
from spotkin.reference import leg as ref

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

SPOT = sk.Spot()
LIMITS = SPOT.leg("fl").limits
U, L, K, H1 = 0.3205, 0.3365, 0.025, 0.110945


def params(leg: sk.Leg) -> tuple[float, float, float, float]:
    return leg.hip_offset, leg.upper_length, leg.lower_length, leg.knee_offset


def legs_under_test() -> list[sk.Leg]:
    return [
        SPOT.leg("fl"),
        SPOT.leg("hr"),
        sk.Leg(0.11, 0.32, 0.34, knee_offset=0.0, side="left", limits=LIMITS),
        sk.Leg(0.08, 0.25, 0.31, knee_offset=-0.02, side="right"),  # unlimited, backward knee offset
    ]


def in_limit_q(rng: np.random.Generator, n: int, limits: np.ndarray = LIMITS) -> np.ndarray:
    return rng.uniform(limits[:, 0], limits[:, 1], (n, 3))


def angle_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs((a - b + np.pi) % (2 * np.pi) - np.pi)


# -- reference agreement ------------------------------------------------------------------------------


@pytest.mark.parametrize("leg", legs_under_test(), ids=repr)
def test_fk_jacobian_singularity_match_reference(rng, leg):
    q = rng.uniform(-np.pi, np.pi, (300, 3))
    np.testing.assert_allclose(leg.fk(q), [ref.fk(qi, *params(leg)) for qi in q], rtol=0, atol=1e-15)
    np.testing.assert_allclose(
        leg.jacobian(q), [ref.jacobian(qi, *params(leg)) for qi in q], rtol=0, atol=1e-15
    )
    det, sigma = leg.singularity(q)
    expected = np.array([ref.singularity(qi, *params(leg)) for qi in q])
    np.testing.assert_allclose(det, expected[:, 0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(sigma, expected[:, 1], rtol=0, atol=1e-12)


def random_targets(rng: np.random.Generator, leg: sk.Leg, n: int) -> np.ndarray:
    """Reachable feet, unreachable feet, and feet inside the hip-roll cylinder."""
    reachable = leg.fk(rng.uniform(-np.pi, np.pi, (n, 3)))
    far = rng.normal(size=(n // 4, 3))
    far *= rng.uniform(0.7, 1.5, (n // 4, 1)) / np.linalg.norm(far, axis=1, keepdims=True)
    inner = rng.uniform(-0.05, 0.05, (n // 4, 3))
    return np.concatenate([reachable, far, inner])


@pytest.mark.parametrize("leg", legs_under_test(), ids=repr)
def test_ik_all_matches_reference(rng, leg):
    p = random_targets(rng, leg, 400)
    sol = leg.ik_all(p)
    lower, upper = leg.limits[:, 0], leg.limits[:, 1]
    for i, pi in enumerate(p):
        q_ref, exists_ref = ref.ik_all(pi, *params(leg))
        np.testing.assert_array_equal(sol.exists[i], exists_ref)
        for s in range(4):
            if not exists_ref[s]:
                assert np.isnan(sol.q[i, s]).all()
                assert not sol.valid[i, s]
                continue
            wrapped, ok = ref.wrap_into_limits(q_ref[s], lower, upper)
            assert sol.valid[i, s] == ok
            np.testing.assert_allclose(sol.q[i, s], wrapped if ok else q_ref[s], rtol=0, atol=1e-11)


@pytest.mark.parametrize("leg", legs_under_test(), ids=repr)
def test_ik_matches_reference_with_and_without_seed(rng, leg):
    p = random_targets(rng, leg, 400)
    seeds = rng.uniform(-np.pi, np.pi, p.shape)
    lower, upper = leg.limits[:, 0], leg.limits[:, 1]
    for seed in (None, seeds):
        q, status = leg.ik(p, seed=seed)
        for i, pi in enumerate(p):
            q_ref, status_ref = ref.ik(pi, *params(leg), lower, upper, None if seed is None else seed[i])
            assert status[i] == status_ref
            if status_ref == sk.Status.UNREACHABLE:
                # the nearest in-limit foot: its distance is what is defined (the minimiser can be
                # flat, e.g. with the knee folded at a singular value): ours is at least as near
                assert ((q[i] >= lower - 1e-12) & (q[i] <= upper + 1e-12)).all()
                ours = np.linalg.norm(leg.fk(q[i]) - pi)
                theirs = np.linalg.norm(ref.fk(q_ref, *params(leg)) - pi)
                assert ours <= theirs + 1e-12, (pi, q[i], q_ref)
            else:
                np.testing.assert_allclose(q[i], q_ref, rtol=0, atol=1e-11)


def test_float32_matches_reference(rng):
    leg = SPOT.leg("fr")
    q = in_limit_q(rng, 500).astype(np.float32)
    p = leg.fk(q)
    assert p.dtype == np.float32 and leg.jacobian(q).dtype == np.float32
    np.testing.assert_allclose(p, [ref.fk(qi, *params(leg)) for qi in q.astype(np.float64)], atol=1e-6)
    q_back, status = leg.ik(p)
    assert q_back.dtype == np.float32 and status.dtype == np.int8
    assert (status == sk.Status.OK).all()
    np.testing.assert_allclose(leg.fk(q_back), p, atol=1e-5)


# -- round trips --------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", ["fl", "fr", "hl", "hr"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_round_trip_contains_generating_configuration(rng, name, dtype):
    leg = SPOT.leg(name)
    n = 100_000
    q = in_limit_q(rng, n, leg.limits).astype(dtype)
    p = leg.fk(q)
    sol = leg.ik_all(p)
    assert sol.exists.all()
    # every existing branch reproduces the target...
    tolerance = {np.float64: 1e-12, np.float32: 1e-5}[dtype]
    feet = leg.fk(sol.q)
    assert np.abs(feet - p[:, None, :]).max() < tolerance
    # ...and one of them is the configuration that generated it
    error = angle_error(sol.q.astype(np.float64), q[:, None, :].astype(np.float64)).max(axis=-1)
    assert (error.min(axis=1) < {np.float64: 1e-9, np.float32: 2e-3}[dtype]).all()
    assert (sol.valid[np.arange(n), error.argmin(axis=1)]).all()


def test_ik_returns_generating_configuration_for_standing_feet(rng):
    leg = SPOT.leg("fl")
    q = in_limit_q(rng, 50_000)
    p = leg.fk(q)
    below = p[:, 2] < -0.08
    q_back, status = leg.ik(p[below])
    assert (status == sk.Status.OK).all()
    assert angle_error(q_back, q[below]).max() < 1e-9


def test_limits_leave_a_single_branch_below_hip_height(rng):
    # The course's Spot problem claims one branch survives the limits; it holds with the
    # official limits whenever the foot is more than 8 cm below the hx joint.
    for leg in SPOT.legs:
        p = leg.fk(in_limit_q(rng, 100_000, leg.limits))
        p = p[p[:, 2] < -0.08]
        sol = leg.ik_all(p)
        assert (sol.valid.sum(axis=1) == 1).all()
        assert sol.valid[:, 0].all()  # and it is slot 0, the walking branch


def test_two_branches_valid_near_hip_height_and_seed_chooses():
    leg = SPOT.leg("fl")
    p = np.array([0.3, 0.13, 0.0])
    sol = leg.ik_all(p)
    np.testing.assert_array_equal(sol.valid, [True, False, True, False])
    q0, status = leg.ik(p)
    assert status == sk.Status.OK
    np.testing.assert_allclose(q0, sol.q[0])
    q2, _ = leg.ik(p, seed=sol.q[2] + 0.01)
    np.testing.assert_allclose(q2, sol.q[2])
    # the measure is the largest single-joint move on the circle
    seed = sol.q[0] + np.array([2 * np.pi, 0, 0])
    np.testing.assert_allclose(leg.ik(p, seed=seed)[0], sol.q[0])


def test_branch_slots_have_the_documented_meaning(rng):
    leg = SPOT.leg("hl")
    p = leg.fk(in_limit_q(rng, 2000))
    sol = leg.ik_all(p)
    beta = np.arctan2(K, U)
    assert (sol.q[:, [0, 2], 2] + beta <= 1e-12).all()  # knee back: kn + beta <= 0
    assert (sol.q[:, [1, 3], 2] + beta >= -1e-12).all()
    # flipped hip: the hip-pitch plane is turned over, z' = -sin(hx) y + cos(hx) z > 0
    for slot, sign in ((0, -1), (2, 1)):
        hx = sol.q[:, slot, 0]
        z_prime = -np.sin(hx) * p[:, 1] + np.cos(hx) * p[:, 2]
        assert (sign * z_prime >= -1e-12).all()


def test_limit_wrapping_by_two_pi():
    limits = LIMITS.copy()
    limits[0] += 2 * np.pi  # hx limits shifted by a full turn
    leg = sk.Leg(H1, U, L, K, limits=limits)
    q = np.array([0.1, 1.0, -1.5])
    q_back, status = leg.ik(SPOT.leg("fl").fk(q))
    assert status == sk.Status.OK
    np.testing.assert_allclose(q_back, q + [2 * np.pi, 0, 0], atol=1e-12)


# -- singular sets --------------------------------------------------------------------------------------


def test_ik_exact_on_both_singular_sets():
    leg = sk.Leg(H1, U, L, K)  # no limits: the singular configurations are outside Spot's
    beta = np.arctan2(K, U)
    targets = []
    for hx in (-0.5, 0.0, 0.3):
        for hy in (-1.0, 0.2, 1.3):
            targets.append(leg.fk([hx, hy, -beta]))  # stretched: kn + beta = 0
            targets.append(leg.fk([hx, hy, np.pi - beta]))  # folded
    # foot on the hip-roll cylinder y^2 + z^2 = h1^2: level with the hip, in front or behind
    for x in (-0.5, 0.3, 0.6):
        targets.append(np.array([x, H1, 0.0]))
        targets.append(np.array([x, H1 * np.cos(0.4), H1 * np.sin(0.4)]))
    targets = np.array(targets)
    sol = leg.ik_all(targets)
    assert sol.exists.all() and np.isfinite(sol.q).all()
    np.testing.assert_allclose(leg.fk(sol.q), np.broadcast_to(targets[:, None], sol.q.shape), atol=1e-12)
    # targets are on the sets up to the rounding of their coordinates (~1e-17 m)
    det, sigma = leg.singularity(sol.q)
    assert det.max() < 1e-8 and sigma.max() < 1e-7


def test_ik_near_singular_sets_stays_exact(rng):
    leg = sk.Leg(H1, U, L, K)
    beta = np.arctan2(K, U)
    eps = 10.0 ** rng.uniform(-12, -4, 500)
    q = np.stack(
        [rng.uniform(-1, 1, 500), rng.uniform(-1, 1, 500), -beta + eps * rng.choice([-1, 1], 500)], -1
    )
    p = leg.fk(q)
    sol = leg.ik_all(p)
    assert sol.exists.all()
    np.testing.assert_allclose(leg.fk(sol.q), np.broadcast_to(p[:, None], sol.q.shape), atol=1e-12)


def test_singularity_measure_vanishes_on_both_sets():
    leg = sk.Leg(H1, U, L, 0.0)
    # course's det(J) = -h2 h3 sin(th3) (h2 cos th2 + h3 cos(th2 + th3)); th3 = kn, th2 = hy
    hy = 0.4
    kn_over_axis = np.arccos(-U * np.cos(hy) / L) - hy
    for q in ([0.2, 0.5, 0.0], [0.2, hy, kn_over_axis]):
        det, sigma = leg.singularity(q)
        assert det < 1e-15 and sigma < 1e-14
    det, _ = leg.singularity([0.2, 0.5, -1.0])
    expected = U * L * np.sin(-1.0) * (U * np.cos(0.5) + L * np.cos(0.5 - 1.0))
    np.testing.assert_allclose(det, abs(expected), rtol=1e-12)


# -- statuses -------------------------------------------------------------------------------------------


def test_unreachable_returns_nearest_configuration_within_limits(rng):
    leg = sk.Leg(H1, U, L, K, limits=LIMITS)
    lower, upper = LIMITS[:, 0], LIMITS[:, 1]
    directions = rng.normal(size=(200, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    far = directions * rng.uniform(0.72, 2.0, (200, 1))
    q, status = leg.ik(far)
    assert (status == sk.Status.UNREACHABLE).all() and np.isfinite(q).all()
    assert ((q >= lower - 1e-12) & (q <= upper + 1e-12)).all()  # always inside the limits
    feet = leg.fk(q)
    nearest = np.array([leg.nearest_reachable(p, within_limits=True) for p in far])
    np.testing.assert_allclose(feet, nearest, atol=1e-12)  # the fallback's foot is nearest_reachable's
    # no configuration inside the limits comes closer (dense sampling)
    samples = leg.fk(in_limit_q(rng, 400_000))
    for p, foot in zip(far[:60], feet[:60]):
        best = np.linalg.norm(samples - p, axis=1).min()
        assert np.linalg.norm(foot - p) <= best + 1e-12
    # a leg without limits: the geometric nearest point, and no configuration at all comes closer
    free = sk.Leg(H1, U, L, K)
    q, status = free.ik(far)
    feet = free.fk(q)
    np.testing.assert_allclose(feet, [free.nearest_reachable(p) for p in far], atol=1e-12)
    np.testing.assert_allclose(feet, [free.nearest_reachable(p, within_limits=True) for p in far], atol=1e-12)
    samples = free.fk(rng.uniform(-np.pi, np.pi, (400_000, 3)))
    for p, foot in zip(far[:40], feet[:40]):
        assert np.linalg.norm(foot - p) <= np.linalg.norm(samples - p, axis=1).min() + 1e-12


def test_unreachable_fallback_beats_the_stretched_leg():
    # the earlier fallback stretched the leg toward the target as far as the knee allowed, 13 cm
    # farther from p = (0.9, 0.1, 0.1) than the best in-limit foot: now the exact nearest one
    leg = SPOT.leg("fl")
    p = np.array([0.9, 0.1, 0.1])
    q, status = leg.ik(p)
    assert status == sk.Status.UNREACHABLE
    grid = np.stack(np.meshgrid(*(np.linspace(lo, hi, 90) for lo, hi in leg.limits), indexing="ij"), -1)
    best = np.linalg.norm(leg.fk(grid.reshape(-1, 3)) - p, axis=1).min()
    assert np.linalg.norm(leg.fk(q) - p) <= best + 1e-12


def test_nearest_reachable_bad_shape():
    with pytest.raises(ValueError, match=r"p must have shape \(3,\)"):
        SPOT.leg("fl").nearest_reachable([1.0, 2.0])


def test_knee_limited_reach_matches_sampling():
    """nearest_reachable(within_limits=True) uses the distances the knee reaches in its limits, eq. (I3);
    the reference finds them at the interval's ends and multiples of pi: check both by sampling kn."""
    for knee_limits in ((-2.7929, -0.2471), (-0.5, 0.4), (2.0, 4.0), (-4.0, -3.0), (-1.0, 7.0)):
        d_min, d_max = ref.knee_reach(U, L, K, knee_limits)
        kn = np.linspace(*knee_limits, 200_001)
        feet = np.array([ref.fk([0.0, 0.0, v], H1, U, L, K) for v in kn[::50]])
        d = np.sqrt(np.sum(feet**2, axis=1) - H1**2)
        assert d.min() >= d_min - 1e-9 and d.max() <= d_max + 1e-9
        assert d.min() <= d_min + 1e-5 and d.max() >= d_max - 1e-5
        limits = np.array([(-np.pi, np.pi), (-np.pi, np.pi), knee_limits])
        leg = sk.Leg(H1, U, L, K, limits=limits)
        far = np.array([0.3, 0.4, -2.0])
        np.testing.assert_allclose(
            np.linalg.norm(leg.nearest_reachable(far, within_limits=True)), np.hypot(H1, d_max), atol=1e-12
        )


def test_inner_dead_zone_and_hip_cylinder_fallbacks():
    leg = sk.Leg(H1, U, L, K)
    for p in ([0.0, 0.0, -0.01], [0.0, 0.0, 0.0], [0.02, 0.05, -0.03], [0.5, 0.0, 0.0]):
        q, status = leg.ik(p)
        assert status == sk.Status.UNREACHABLE and np.isfinite(q).all()
        np.testing.assert_allclose(leg.fk(q), leg.nearest_reachable(p), atol=1e-12)
        # the fallback point is reachable: it has an exact solution
        assert leg.ik_all(leg.nearest_reachable(p)).exists.all()


def test_joint_limit_status_gives_nan():
    leg = SPOT.leg("fl")
    p = np.array([0.0, H1, 0.5])  # foot above the hip: needs the hip flipped over
    sol = leg.ik_all(p)
    assert sol.exists.all() and not sol.valid.any()
    q, status = leg.ik(p)
    assert status == sk.Status.JOINT_LIMIT and np.isnan(q).all()
    assert sol.status == sk.Status.JOINT_LIMIT


def test_invalid_input_statuses_do_not_poison_neighbours():
    leg = SPOT.leg("fl")
    good = leg.fk([0.1, 1.0, -1.6])
    p = np.array([good, [np.nan, 0, 0], [0, np.inf, 0], good])
    q, status = leg.ik(p)
    np.testing.assert_array_equal(status, [0, 3, 3, 0])
    assert np.isnan(q[1:3]).all() and np.isfinite(q[[0, 3]]).all()
    seed = np.zeros((4, 3))
    seed[3, 0] = np.nan
    _, status = leg.ik(p, seed=seed)
    np.testing.assert_array_equal(status, [0, 3, 3, 3])
    sol = leg.ik_all(p)
    np.testing.assert_array_equal(sol.status, [0, 3, 3, 0])
    assert not sol.exists[1:3].any() and not sol.valid[1:3].any()


# -- mapping to the course, mirroring ---------------------------------------------------------------------


def test_course_dhm_leg_maps_onto_the_leg_model(rng):
    # The course's DHm rows (d, alpha, r, theta): (0, -90, 0, th1), (0, 90, h1, th2), (h2, 0, 0, th3),
    # foot (h3, 0, 0) in frame 3. With no knee offset it is this leg with th1 = -hx, th2 = hy,
    # th3 = kn, seen from a base frame rotated by R (course x = -leg z, y = -leg x, z = leg y).
    course = sk.Chain.from_mdh(
        [(0, 0, -np.pi / 2, 0, 0), (0, 0, np.pi / 2, H1, 0), (0, U, 0, 0, 0)], tool=sk.translation([L, 0, 0])
    )
    leg = sk.Leg(H1, U, L, knee_offset=0.0)
    R_course_from_leg = np.array([[0, 0, -1], [-1, 0, 0], [0, 1, 0]])
    q = rng.uniform(-np.pi, np.pi, (1000, 3))
    th = np.stack([-q[:, 0], q[:, 1], q[:, 2]], -1)
    np.testing.assert_allclose(course.fk(th)[:, :3, 3], leg.fk(q) @ R_course_from_leg.T, atol=1e-15)
    R_leg_from_course, ref_q = ref.course_to_leg(th[0], H1)
    np.testing.assert_allclose(R_leg_from_course, R_course_from_leg.T)
    np.testing.assert_allclose(ref_q, q[0], atol=1e-15)


def test_right_legs_mirror_left_legs(rng):
    left, right = SPOT.leg("fl"), SPOT.leg("fr")
    q = rng.uniform(-np.pi, np.pi, (1000, 3))
    mirrored = q * [-1, 1, 1]
    np.testing.assert_allclose(right.fk(mirrored), left.fk(q) * [1, -1, 1], atol=1e-15)
    p = left.fk(in_limit_q(rng, 1000))
    q_left, _ = left.ik(p)
    q_right, status = right.ik(p * [1, -1, 1])
    assert (status == 0).all()
    np.testing.assert_allclose(q_right, q_left * [-1, 1, 1], atol=1e-12)


# -- batch semantics and bad input ------------------------------------------------------------------------


@given(
    batch=st.sampled_from(BATCH_SHAPES),
    dtype=st.sampled_from([np.float64, np.float32]),
    seed=st.integers(0, 2**32 - 1),
    with_seed=st.booleans(),
)
def test_batch_shapes(batch, dtype, seed, with_seed):
    rng = np.random.default_rng(seed)
    leg = SPOT.leg("hr")
    q = in_limit_q(rng, int(np.prod(batch, dtype=int))).reshape(*batch, 3).astype(dtype)
    p = leg.fk(q)
    assert p.shape == (*batch, 3) and p.dtype == dtype
    assert leg.jacobian(q).shape == (*batch, 3, 3)
    det, sigma = leg.singularity(q)
    assert det.shape == batch == sigma.shape
    q_back, status = leg.ik(p, seed=q[..., :1, :] if with_seed and batch else (q if with_seed else None))
    assert q_back.shape == (*batch, 3) and q_back.dtype == dtype
    if batch:
        assert status.shape == batch and status.dtype == np.int8
    else:
        assert isinstance(status, sk.Status)
    sol = leg.ik_all(p)
    assert sol.q.shape == (*batch, 4, 3) and sol.valid.shape == (*batch, 4) == sol.exists.shape
    assert sol.valid.dtype == bool and sol.q.dtype == dtype


def test_non_contiguous_and_empty():
    leg = SPOT.leg("fl")
    p = leg.fk(in_limit_q(np.random.default_rng(1), 40))
    strided = np.asfortranarray(p)[::2]
    np.testing.assert_array_equal(leg.ik(strided)[0], leg.ik(np.ascontiguousarray(strided))[0])
    q, status = leg.ik(np.zeros((0, 3)))
    assert q.shape == (0, 3) and status.shape == (0,)
    assert leg.ik_all(np.zeros((2, 0, 3))).q.shape == (2, 0, 4, 3)


def test_bad_input_raises_clear_errors():
    leg = SPOT.leg("fl")
    with pytest.raises(ValueError, match=r"p must have shape \(\.\.\., 3\), got \(5, 2\)"):
        leg.ik(np.zeros((5, 2)))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 3\)"):
        leg.fk(np.zeros(4))
    with pytest.raises(TypeError, match="p must be a real numeric array"):
        leg.ik_all("foot")
    with pytest.raises(ValueError, match="do not broadcast"):
        leg.ik(np.zeros((4, 3)), seed=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="side must be"):
        sk.Leg(0.1, 0.3, 0.3, side="middle")
    with pytest.raises(ValueError, match="positive"):
        sk.Leg(0.1, -0.3, 0.3)
    with pytest.raises(ValueError, match=r"limits must have shape \(3, 2\)"):
        sk.Leg(0.1, 0.3, 0.3, limits=[(0, 1)])
    with pytest.raises(ValueError, match="lower <= upper"):
        sk.Leg(0.1, 0.3, 0.3, limits=[(1, 0), (0, 1), (0, 1)])
    with pytest.raises(ValueError, match="leg name must be one of"):
        SPOT.leg("front-left")


def test_spot_model_and_pickling():
    np.testing.assert_allclose(
        SPOT.hip_positions[:, :2],
        [[0.29785, 0.055], [0.29785, -0.055], [-0.29785, 0.055], [-0.29785, -0.055]],
    )
    assert [leg.name for leg in SPOT.legs] == ["fl", "fr", "hl", "hr"]
    assert [leg.hip_offset > 0 for leg in SPOT.legs] == [True, False, True, False]
    for leg in SPOT.legs:
        clone = pickle.loads(pickle.dumps(leg))
        np.testing.assert_array_equal(clone.fk([0.1, 0.9, -1.5]), leg.fk([0.1, 0.9, -1.5]))
        np.testing.assert_array_equal(clone.limits, leg.limits)
    assert pickle.loads(pickle.dumps(SPOT)).leg("hr").hip_offset == SPOT.leg("hr").hip_offset


def test_leg_jacobian_matches_central_differences(rng):
    leg = SPOT.leg("hl")
    q = rng.uniform(-np.pi, np.pi, (200, 3))
    step = 1e-6
    J_fd = np.stack([(leg.fk(q + step * e) - leg.fk(q - step * e)) / (2 * step) for e in np.eye(3)], -1)
    np.testing.assert_allclose(leg.jacobian(q), J_fd, atol=1e-9)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("seeded", [False, True])
def test_answers_do_not_depend_on_the_neighbouring_targets(rng, seeded, dtype):
    """A target's answer is bit-identical whatever targets surround it in the batch (the kernels
    work in blocks, a short one padded to whole registers of the running level, and solve the open
    targets of a block together, in vector lanes)."""
    leg = SPOT.leg("fl")
    q = in_limit_q(rng, 4_001)
    p = leg.fk(q)
    p[::37] *= 3.0  # unreachable targets among them
    p = p.astype(dtype)
    seed = (q + 0.3).astype(dtype) if seeded else None
    whole_q, whole_status = leg.ik(p, seed=seed)
    every = leg.ik_all(p)
    for shift in (1, 3, 5, 7, 63):
        part_q, part_status = leg.ik(p[shift:], seed=None if seed is None else seed[shift:])
        np.testing.assert_array_equal(part_q, whole_q[shift:])
        np.testing.assert_array_equal(part_status, whole_status[shift:])
        np.testing.assert_array_equal(leg.ik_all(p[shift:]).q, every.q[shift:])
    feet = SPOT.stance_feet(0.5)
    poses = np.array([0, 0, 0.5, 0, 0, 0]) + rng.normal(0, 1, (2_001, 6)) * [0.05, 0.05, 0.1, 0.3, 0.3, 0.3]
    poses, feet = poses.astype(dtype), feet.astype(dtype)
    body = SPOT.body_ik(poses, feet)
    assert (body.status != 0).any() and (body.status == 0).any()
    for shift in (1, 5, 63):
        np.testing.assert_array_equal(SPOT.body_ik(poses[shift:], feet).q, body.q[shift:])
    # one pose per call (the control-loop path: its own fast path in the core) and one target per
    # call give the batch's rows bit for bit, and the same result type
    for i in range(0, 2_001, 97):
        single = SPOT.body_ik(poses[i], feet)
        assert type(single) is sk.BodyIK and single.q.shape == (12,) and single.status.shape == (4,)
        np.testing.assert_array_equal(single.q, body.q[i])
        np.testing.assert_array_equal(single.status, body.status[i])
    assert type(body) is sk.BodyIK
    for i in range(0, 4_001, 211):
        single_q, single_status = leg.ik(p[i], seed=None if seed is None else seed[i])
        np.testing.assert_array_equal(single_q, whole_q[i])
        assert single_status == whole_status[i]


def test_threads_are_bit_identical_and_concurrent_calls_correct(rng):
    from concurrent.futures import ThreadPoolExecutor

    leg = SPOT.leg("fl")
    p = leg.fk(in_limit_q(rng, 300_001))
    before = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = leg.ik(p), leg.ik_all(p)
        sk.set_num_threads(2)
        two = leg.ik(p), leg.ik_all(p)
    finally:
        sk.set_num_threads(before)
    np.testing.assert_array_equal(one[0][0], two[0][0])
    np.testing.assert_array_equal(one[1].q, two[1].q)
    chunks = np.array_split(p, 8)
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda c: leg.ik(c)[0], chunks))
    np.testing.assert_array_equal(np.concatenate(results), one[0][0])
