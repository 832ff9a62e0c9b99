"""Whole body: conventions against scipy, round trips, per-leg statuses, Jacobian,
the reverse differential map, the arm on the body, batch semantics, threads."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from urdf_helpers import robot_named

import spotkin as sk
from conftest import BATCH_SHAPES
from spotkin.reference import body as ref_body
from spotkin.reference import leg as ref_leg

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

SPOT = sk.Spot()
FEET = SPOT.stance_feet(0.5)
NOMINAL = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])


def random_poses(rng: np.random.Generator, n: int, spread: float = 0.05) -> np.ndarray:
    noise = rng.normal(0, 1, (n, 6)) * [spread, spread, spread, 2 * spread, 2 * spread, 2 * spread]
    return NOMINAL + noise


def matrix_poses(poses: np.ndarray, seq: str = "XYZ") -> np.ndarray:
    T = np.zeros((*poses.shape[:-1], 4, 4))
    T[..., :3, :3] = (
        Rotation.from_euler(seq, poses[..., 3:].reshape(-1, 3)).as_matrix().reshape(*poses.shape[:-1], 3, 3)
    )
    T[..., :3, 3] = poses[..., :3]
    T[..., 3, 3] = 1
    return T


# -- conventions -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("seq", sk.EULER_SEQUENCES)
def test_every_sequence_matches_scipy(rng, seq):
    poses = random_poses(rng, 200, spread=0.5)
    T_ref = matrix_poses(poses, seq)
    np.testing.assert_allclose(sk.body_transform(poses, seq), T_ref, atol=1e-14)
    q12 = SPOT.body_ik(NOMINAL, FEET).q
    np.testing.assert_allclose(SPOT.body_fk(poses, q12, seq=seq), SPOT.body_fk(T_ref, q12), atol=1e-14)


def test_default_is_intrinsic_xyz_and_ros_rpy_is_extrinsic():
    a, b, c = 0.3, -0.2, 0.7
    Rx, Ry, Rz = (sk.rotation_x(a)[:3, :3], sk.rotation_y(b)[:3, :3], sk.rotation_z(c)[:3, :3])
    pose = [0, 0, 0.5, a, b, c]
    np.testing.assert_allclose(sk.body_transform(pose)[:3, :3], Rx @ Ry @ Rz, atol=1e-15)
    np.testing.assert_allclose(sk.body_transform(pose, "xyz")[:3, :3], Rz @ Ry @ Rx, atol=1e-15)
    with pytest.raises(ValueError, match="seq must be one of scipy's Euler sequences"):
        SPOT.body_ik(pose, FEET, seq="XYX Z")
    with pytest.raises(ValueError, match="seq must be one of"):
        SPOT.body_fk(pose, np.zeros(12), seq="xYz")


@pytest.mark.parametrize("seq", ["XYZ", "ZYX", "xyz"])
def test_large_euler_angles_are_reduced_exactly(rng, seq):
    # the vectorised ("XYZ", "xyz") and generic paths must agree with NumPy far from 0
    poses = random_poses(rng, 50)
    poses[:, 3:] += rng.choice([1e6, -3e7, 1e12], (50, 3))
    q12 = SPOT.body_ik(NOMINAL, FEET).q
    T = sk.body_transform(poses, seq)
    np.testing.assert_allclose(SPOT.body_fk(poses, q12, seq=seq), SPOT.body_fk(T, q12), atol=1e-12)


def test_pose_formats_agree(rng):
    poses = random_poses(rng, 500)
    T = matrix_poses(poses)
    quat = Rotation.from_euler("XYZ", poses[:, 3:]).as_quat()
    p7 = np.concatenate([poses[:, :3], quat], -1)
    a, b, c = SPOT.body_ik(poses, FEET), SPOT.body_ik(T, FEET), SPOT.body_ik(p7, FEET)
    np.testing.assert_allclose(a.q, b.q, atol=1e-12)
    np.testing.assert_allclose(a.q, c.q, atol=1e-12)
    np.testing.assert_array_equal(a.status, b.status)


# -- IK ----------------------------------------------------------------------------------------------------


def test_body_ik_matches_the_leg_reference(rng):
    poses = random_poses(rng, 100, spread=0.1)
    feet = FEET + rng.normal(0, 0.1, (100, 4, 3))
    res = SPOT.body_ik(poses, feet)
    T = sk.body_transform(poses)
    for n in range(100):
        R, t = T[n, :3, :3], T[n, :3, 3]
        for i, leg in enumerate(SPOT.legs):
            p = R.T @ (feet[n, i] - t) - SPOT.hip_positions[i]
            q_ref, status_ref = ref_leg.ik(
                p,
                leg.hip_offset,
                leg.upper_length,
                leg.lower_length,
                leg.knee_offset,
                leg.limits[:, 0],
                leg.limits[:, 1],
            )
            assert res.status[n, i] == status_ref
            q = res.q[n, 3 * i : 3 * i + 3]
            if status_ref == sk.Status.UNREACHABLE:  # on a singular set: compare the feet
                np.testing.assert_allclose(leg.fk(q), leg.fk(q_ref), atol=1e-12)
            else:
                np.testing.assert_allclose(q, q_ref, atol=1e-9)


@pytest.mark.slow
def test_round_trip_on_random_stances(rng):
    n = 100_000
    poses = random_poses(rng, n)
    feet = FEET + rng.normal(0, 0.03, (n, 4, 3))
    res = SPOT.body_ik(poses, feet)
    ok = res.status == sk.Status.OK
    assert ok.mean() > 0.99
    back = SPOT.body_fk(poses, res.q)
    assert np.abs(back - feet)[ok].max() < 1e-12


@pytest.mark.slow
def test_round_trip_recovers_the_generating_joints(rng):
    # joints with every foot more than 8 cm below its hip, where the limits leave one branch
    n = 100_000
    # the tightest limits of the four legs (the knee stops differ per leg)
    limits = np.stack([leg.limits for leg in SPOT.legs])
    limits = np.stack([limits[:, :, 0].max(axis=0), limits[:, :, 1].min(axis=0)], axis=1)
    q = rng.uniform(limits[:, 0], limits[:, 1], (4 * n, 3))
    q = q[SPOT.leg("fl").fk(q)[:, 2] < -0.1][: 4 * (len(q) // 8) // 4 * 4]
    q12 = q[: (len(q) // 4) * 4].reshape(-1, 12)
    poses = random_poses(rng, len(q12), spread=0.1)
    feet = SPOT.body_fk(poses, q12)
    res = SPOT.body_ik(poses, feet)
    assert (res.status == 0).all()
    np.testing.assert_allclose(res.q, q12, atol=1e-9)


def test_failures_stay_in_their_leg():
    feet = np.broadcast_to(FEET, (4, 4, 3)).copy()
    feet[1, 2] = np.nan  # one foot NaN
    feet[2, 0, 2] = -1.0  # one foot far below: unreachable
    poses = np.tile(NOMINAL, (4, 1))
    poses[3, 4] = np.nan  # NaN in one body pose
    res = SPOT.body_ik(poses, feet)
    np.testing.assert_array_equal(res.status, [[0, 0, 0, 0], [0, 0, 3, 0], [1, 0, 0, 0], [3, 3, 3, 3]])
    good = SPOT.body_ik(NOMINAL, FEET).q
    np.testing.assert_array_equal(
        res.q[1, [0, 1, 2, 3, 4, 5, 9, 10, 11]], good[[0, 1, 2, 3, 4, 5, 9, 10, 11]]
    )
    assert np.isnan(res.q[1, 6:9]).all() and np.isnan(res.q[3]).all()
    # the unreachable leg gets the leg API's fallback
    p = feet[2, 0] - [0, 0, 0.5] - SPOT.hip_positions[0]
    q_leg, status = SPOT.leg("fl").ik(p)
    assert status == sk.Status.UNREACHABLE
    np.testing.assert_allclose(res.q[2, :3], q_leg, atol=1e-12)


@pytest.mark.parametrize("n", [1, 3, 100])  # one pose (its legs in lanes), a few, a block
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("fallback", ["nearest", "nan"])
def test_a_foot_too_far_to_subtract_is_unreachable_not_invalid(n, dtype, fallback):
    # Finite inputs whose hip-frame point overflows (foot - t beyond the largest float): the leg's
    # target is beyond reach, so UNREACHABLE with the leg API's answer for a target that far in that
    # direction (straight down here), as the other legs (far below, without overflow). A NaN foot
    # stays INVALID_INPUT.
    big = float(np.finfo(dtype).max) * 0.9
    pose = np.array([0.0, 0.0, big, 0.0, 0.0, 0.0], dtype)
    feet = FEET.astype(dtype)
    feet[1, 2] = -big
    res = SPOT.body_ik(np.tile(pose, (n, 1)), np.tile(feet, (n, 1, 1)), fallback=fallback)
    np.testing.assert_array_equal(res.status, np.ones((n, 4)))
    assert res.q.dtype == dtype
    q_leg, status = SPOT.leg("fr").ik(np.array([0.0, 0.0, -1e300]), fallback=fallback)
    assert status == sk.Status.UNREACHABLE
    if fallback == "nan":
        assert np.isnan(res.q[:, 3:6]).all()
    else:
        tolerance = 1e-6 if dtype == np.float32 else 1e-9
        np.testing.assert_allclose(res.q[:, 3:6], np.tile(q_leg, (n, 1)), atol=tolerance)
    feet[1, 2] = np.nan
    np.testing.assert_array_equal(SPOT.body_ik(pose, feet).status, [1, 3, 1, 1])


def test_invalid_rotation_marks_all_legs():
    T = matrix_poses(NOMINAL[None])[0]
    T[:3, :3] *= 1.01
    np.testing.assert_array_equal(SPOT.body_ik(T, FEET).status, [3, 3, 3, 3])


def test_seed_picks_among_valid_branches():
    # lift the body so the front-left foot ends near hip height: two hip branches are valid
    foot = SPOT.hip_positions[0] + [0.3, 0.13, 0.0] + [0, 0, 0.5]
    feet = FEET.copy()
    feet[0] = foot
    sol = SPOT.leg("fl").ik_all(foot - [0, 0, 0.5] - SPOT.hip_positions[0])
    assert sol.valid[[0, 2]].all()
    seed = np.zeros(12)
    seed[:3] = sol.q[2]
    np.testing.assert_allclose(SPOT.body_ik(NOMINAL, feet).q[:3], sol.q[0], atol=1e-12)
    np.testing.assert_allclose(SPOT.body_ik(NOMINAL, feet, seed=seed).q[:3], sol.q[2], atol=1e-12)


# -- Jacobian and rates ----------------------------------------------------------------------------------


def twist_step(T: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """exp of a world-frame twist applied to a body pose: t + v, exp([w]) R."""
    out = T.copy()
    out[:3, :3] = Rotation.from_rotvec(twist[3:]).as_matrix() @ T[:3, :3]
    out[:3, 3] = T[:3, 3] + twist[:3]
    return out


def test_body_jacobian_matches_central_differences(rng):
    step = 1e-6
    for _ in range(20):
        T = matrix_poses(random_poses(rng, 1))[0]
        q12 = SPOT.body_ik(T, FEET + rng.normal(0, 0.02, (4, 3))).q
        J = SPOT.body_jacobian(T, q12)
        fd = np.zeros((12, 18))
        for k in range(6):
            e = np.zeros(6)
            e[k] = step
            fd[:, k] = (
                SPOT.body_fk(twist_step(T, e), q12) - SPOT.body_fk(twist_step(T, -e), q12)
            ).ravel() / (2 * step)
        for k in range(12):
            e = np.zeros(12)
            e[k] = step
            fd[:, 6 + k] = (SPOT.body_fk(T, q12 + e) - SPOT.body_fk(T, q12 - e)).ravel() / (2 * step)
        np.testing.assert_allclose(J, fd, atol=1e-8)


def test_body_rates_keep_the_feet_still(rng):
    poses = random_poses(rng, 50)
    q12 = SPOT.body_ik(poses, FEET).q
    twist = rng.normal(0, 0.2, (50, 6))
    rates = SPOT.body_rates(poses, q12, twist)
    assert not rates.singular.any()
    J = SPOT.body_jacobian(poses, q12)
    feet_velocity = J[..., :6] @ twist[..., None] + J[..., 6:] @ rates.qd[..., None]
    assert np.abs(feet_velocity).max() < 1e-12


def test_body_rates_flag_singular_legs():
    q12 = SPOT.body_ik(NOMINAL, FEET).q
    beta = np.arctan2(SPOT.leg("fl").knee_offset, SPOT.leg("fl").upper_length)
    q12[2] = -beta  # front-left knee stretched
    rates = SPOT.body_rates(NOMINAL, q12, [0.1, 0, 0, 0, 0, 0.2])
    np.testing.assert_array_equal(rates.singular, [True, False, False, False])
    assert np.isnan(rates.qd[:3]).all() and np.isfinite(rates.qd[3:]).all()


# -- arm on the body, frames ---------------------------------------------------------------------------


def test_arm_ik_world_and_fk_all(rng):
    arm = SPOT.arm
    limits = arm.limits
    q_arm = rng.uniform(limits[:, 0], limits[:, 1], (200, 6))
    poses = random_poses(rng, 200)
    T_world = sk.body_transform(poses) @ arm.fk(q_arm)
    q, status = SPOT.arm_ik_world(poses, T_world, seed=q_arm)
    assert (status == 0).all()
    np.testing.assert_allclose(q, q_arm, atol=1e-9)
    q12 = SPOT.body_ik(poses, FEET).q
    frames = SPOT.fk_all(poses, q12, q_arm)
    np.testing.assert_allclose(frames.feet, SPOT.body_fk(poses, q12), atol=1e-14)
    np.testing.assert_allclose(frames.hand, T_world, atol=1e-14)
    np.testing.assert_allclose(
        frames.hips,
        sk.body_transform(poses)[:, None, :3, 3]
        + np.einsum("nij,kj->nki", sk.body_transform(poses)[:, :3, :3], SPOT.hip_positions),
        atol=1e-14,
    )
    # knees sit at the upper-leg length from the hy joints and the lower-leg length from the feet
    assert np.allclose(np.linalg.norm(frames.feet - frames.knees, axis=-1), SPOT.leg("fl").lower_length)
    # a hand target held fixed in the world while the body moves
    target = sk.body_transform(NOMINAL) @ arm.fk([0.2, -1.0, 1.7, 0.1, 0.4, 0.0])
    moving = random_poses(rng, 50, spread=0.02)
    q, status = SPOT.arm_ik_world(moving, target)
    assert (status == 0).all()
    np.testing.assert_allclose(
        sk.body_transform(moving) @ arm.fk(q), np.broadcast_to(target, (50, 4, 4)), atol=1e-12
    )


def test_stance_feet():
    feet = SPOT.stance_feet(0.46)
    q = SPOT.body_ik([0, 0, 0.46, 0, 0, 0], feet).q.reshape(4, 3)
    np.testing.assert_allclose(q[:, 0], 0.0, atol=1e-12)  # hx = 0: feet straight below the hips
    np.testing.assert_allclose(feet[:, 2], 0.036)
    with pytest.raises(ValueError, match="out of reach"):
        SPOT.stance_feet(1.5)


# -- batches, bad input, threads --------------------------------------------------------------------------


@given(
    pose_batch=st.sampled_from(BATCH_SHAPES),
    feet_shared=st.booleans(),
    dtype=st.sampled_from([np.float64, np.float32]),
    seed=st.integers(0, 2**32 - 1),
)
def test_batch_shapes_and_broadcasting(pose_batch, feet_shared, dtype, seed):
    rng = np.random.default_rng(seed)
    poses = random_poses(rng, int(np.prod(pose_batch, dtype=int)), 0.02).reshape(*pose_batch, 6).astype(dtype)
    feet = (
        FEET
        if feet_shared
        else np.broadcast_to(FEET, (*pose_batch, 4, 3)) + rng.normal(0, 0.01, (*pose_batch, 4, 3))
    )
    feet = feet.astype(dtype)
    res = SPOT.body_ik(poses, feet)
    assert res.q.shape == (*pose_batch, 12) and res.status.shape == (*pose_batch, 4) and res.q.dtype == dtype
    assert (res.status == 0).mean() > 0.5  # rare random stances may be out of reach or limits
    tolerance = 1e-12 if dtype == np.float64 else 2e-5
    ok = res.status == 0
    assert np.abs(SPOT.body_fk(poses, res.q) - feet)[ok].max(initial=0) < tolerance
    assert SPOT.body_jacobian(poses, res.q).shape == (*pose_batch, 12, 18)


def test_broadcasting_feet_against_poses(rng):
    poses = random_poses(rng, 6).reshape(2, 3, 6)
    feet = np.broadcast_to(FEET, (3, 4, 3)).copy()
    res = SPOT.body_ik(poses, feet)
    assert res.q.shape == (2, 3, 12)
    np.testing.assert_allclose(res.q[1, 2], SPOT.body_ik(poses[1, 2], FEET).q)
    empty = SPOT.body_ik(np.zeros((0, 6)), FEET)
    assert empty.q.shape == (0, 12) and empty.status.shape == (0, 4)


def test_bad_shapes_name_both_arguments():
    with pytest.raises(ValueError, match=r"body_pose \(5, 6\) and feet \(3, 4, 3\) do not broadcast"):
        SPOT.body_ik(np.zeros((5, 6)), np.zeros((3, 4, 3)))
    with pytest.raises(ValueError, match=r"feet must have shape \(\.\.\., 4, 3\)"):
        SPOT.body_ik(NOMINAL, np.zeros((4, 2)))
    with pytest.raises(ValueError, match=r"body_pose must have shape \(\.\.\., 6\)"):
        SPOT.body_ik(np.zeros(5), FEET)
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 12\)"):
        SPOT.body_fk(NOMINAL, np.zeros(11))
    with pytest.raises(TypeError, match="must be a real numeric array"):
        SPOT.body_ik(["a"] * 6, FEET)


def test_threads_bit_identical_and_concurrent_callers(rng):
    from concurrent.futures import ThreadPoolExecutor

    poses = random_poses(rng, 200_001)
    before = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = SPOT.body_ik(poses, FEET)
        sk.set_num_threads(2)
        two = SPOT.body_ik(poses, FEET)
    finally:
        sk.set_num_threads(before)
    np.testing.assert_array_equal(one.q, two.q)
    np.testing.assert_array_equal(one.status, two.status)
    chunks = np.array_split(poses, 8)
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda c: SPOT.body_ik(c, FEET).q, chunks))
    np.testing.assert_array_equal(np.concatenate(results), one.q)


def _hard_stances(rng, robot, height, n, dtype):
    """n poses and per-pose feet around a stance: in reach, far out (UNREACHABLE, JOINT_LIMIT), NaN, Inf,
    a scaled rotation matrix row, and random seeds (one with a NaN joint)."""
    feet0 = robot.stance_feet(height)
    poses = np.zeros((n, 6))
    poses[:, 2] = height
    poses += rng.normal(size=(n, 6)) * [0.08, 0.08, 0.08, 0.3, 0.3, 0.5]
    poses[::9] *= 5  # out of reach, or past a limit
    poses[3, 4] = np.nan
    feet = feet0 + rng.normal(size=(n, *feet0.shape)) * 0.03
    feet[5, 1, 2] = np.inf
    seeds = rng.uniform(-3, 3, size=(n, 3 * len(feet0)))
    seeds[6, 4] = np.nan
    return poses.astype(dtype), feet.astype(dtype), seeds.astype(dtype), feet0.astype(dtype)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_few_poses_equal_their_rows_of_a_batch_to_the_bit(rng, dtype):
    """One to four poses are solved with each (pose, leg) pair in its own lane (every slot at once), a
    batch leg by leg: the answers, statuses and fallbacks are the same bits either way, with and without
    a seed, a shared stance or one per pose, and in Euler, matrix and quaternion form. The lanes are
    padded to the running level's registers: the hexapod's 6 and 12 pairs leave padding lanes there."""
    from fuzz.urdf_texts import HEXAPOD_URDF  # six legs, their joints interleaved in q

    hexapod = sk.Robot.from_urdf_string(HEXAPOD_URDF)
    for robot, height in [
        (SPOT, 0.5),
        (robot_named("go2"), 0.3),
        (robot_named("heavy"), 0.6),
        (hexapod, 0.3),
    ]:
        poses, feet, seeds, feet0 = _hard_stances(rng, robot, height, 160, dtype)
        matrices = matrix_poses(poses.astype(np.float64)).astype(dtype)
        quats = np.hstack([poses[:, :3], Rotation.from_euler("XYZ", np.nan_to_num(poses[:, 3:])).as_quat()])
        quats = quats.astype(dtype)
        statuses = set()
        for form in (poses, matrices, quats):
            for seed in (None, seeds):
                for fallback in ("nearest", "nan"):
                    for stance in (feet, feet0):
                        batch = robot.body_ik(form, stance, seed, fallback=fallback)
                        statuses |= set(np.unique(batch.status).tolist())
                        for count in (1, 2, 3, 4):
                            for k in range(0, 160 - count, 23 + count):
                                rows = slice(k, k + count) if count > 1 else k
                                few = robot.body_ik(
                                    form[rows],
                                    stance[rows] if stance is feet else stance,
                                    None if seed is None else seed[rows],
                                    fallback=fallback,
                                )
                                assert few.q.dtype == dtype
                                np.testing.assert_array_equal(few.q, batch.q[rows])
                                np.testing.assert_array_equal(few.status, batch.status[rows])
        # the cases that matter were met: OK, UNREACHABLE, JOINT_LIMIT and INVALID_INPUT
        assert {int(sk.Status.OK), int(sk.Status.UNREACHABLE), int(sk.Status.INVALID_INPUT)} <= statuses


@pytest.mark.usefixtures("every_isa")
@pytest.mark.parametrize(("dtype", "n"), [(np.float64, 30_000), (np.float32, 50_000)])
def test_a_large_batch_streamed_out_equals_its_rows_solved_in_small_calls(rng, dtype, n):
    """A batch whose q passes 2 MB stages each block's answers and streams them out (non-temporal
    stores); small calls write in place. The bits are the same, with NaN, Inf, unreachable and
    past-limit targets, seeds and per-pose feet, in float64 and float32."""
    poses, feet, seeds, _ = _hard_stances(rng, SPOT, 0.5, n, dtype)
    threads = sk.get_num_threads()
    for seed in (None, seeds):
        sk.set_num_threads(1)  # one call of the kernel for the whole batch: its q passes 2 MB, streamed
        try:
            large = SPOT.body_ik(poses, feet, seed)
        finally:
            sk.set_num_threads(threads)
        assert large.q.nbytes >= 2 << 20
        for k in range(0, n, 997):
            rows = slice(k, k + 100)
            small = SPOT.body_ik(poses[rows], feet[rows], None if seed is None else seed[rows])
            np.testing.assert_array_equal(small.q, large.q[rows])
            np.testing.assert_array_equal(small.status, large.status[rows])
    assert {int(sk.Status.OK), int(sk.Status.INVALID_INPUT)} <= set(np.unique(large.status).tolist())


# ------------------------------------------------------------------ body_transform against the reference


def _pose_samples(rng):
    """Euler poses (a huge angle), rigid matrices, unit quaternions, and invalid ones of each form."""
    euler = np.hstack([rng.normal(size=(20, 3)), rng.uniform(-4, 4, (20, 3))])
    euler[3, 4] = 1e7  # a huge angle: reduced exactly
    euler[4, 0] = np.nan
    quat = rng.normal(size=(12, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    quats = np.hstack([rng.normal(size=(12, 3)), quat])
    quats[1, 3:] *= 1 + 5e-7  # within 1e-6 of unit norm: accepted, not renormalised
    quats[2, 3:] *= 1 + 5e-6  # beyond: invalid
    quats[3, 6] = np.inf
    mats = np.tile(np.eye(4), (10, 1, 1))
    mats[:, :3, :3] = Rotation.random(10, random_state=1).as_matrix()
    mats[:, :3, 3] = rng.normal(size=(10, 3))
    mats[1, :3, :3] *= -1  # det -1
    mats[2, 3, 0] = 1e-8  # last row off by more than 1e-9
    mats[3, 0, 0] += 2e-6  # not orthonormal to 1e-6
    mats[4, 3, 0] = 5e-10  # within 1e-9: returned as given
    return euler, quats, mats


@pytest.mark.parametrize("seq", ["XYZ", "xyz", "ZYX", "zxz", "YXY"])
def test_body_transform_matches_the_reference_in_every_form(seq, rng):
    for poses in _pose_samples(rng):
        T = sk.body_transform(poses, seq)
        assert T.shape == (*poses.shape[: -2 if poses.ndim == 3 else -1], 4, 4) and T.dtype == np.float64
        for pose, got in zip(poses, T):
            want = ref_body.body_transform(pose, seq)
            assert np.isnan(got).all() == np.isnan(want).all(), (pose, got, want)
            np.testing.assert_allclose(got, want, atol=1e-14, rtol=0)
            assert np.array_equal(sk.body_transform(pose, seq), got, equal_nan=True)  # one sample: same bits


def test_body_transform_broadcasts_writes_out_and_keeps_float64_for_float32(rng):
    euler, _, _ = _pose_samples(rng)
    poses = euler[5:11].reshape(3, 1, 2, 6)
    out = np.empty((3, 1, 2, 4, 4))
    assert sk.body_transform(poses, out=out) is out
    np.testing.assert_array_equal(out, sk.body_transform(euler[5:11]).reshape(3, 1, 2, 4, 4))
    assert sk.body_transform(poses.astype(np.float32)).dtype == np.float64
    assert sk.body_transform(np.empty((0, 6))).shape == (0, 4, 4)
    strided = np.asfortranarray(euler[5:11])
    np.testing.assert_array_equal(sk.body_transform(strided), sk.body_transform(euler[5:11]))
    with pytest.raises(ValueError, match="body_pose"):
        sk.body_transform(np.zeros(5))
    with pytest.raises(TypeError, match="out"):
        sk.body_transform(euler[5], out=np.empty((4, 4), np.float32))


def _wrapped(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def _wide_limits(name: str):
    """Go2 or the tests' heavy quadruped with every joint's range widened to (-pi, pi]: most feet
    then have all four branches valid, and a seed has a real choice."""
    import re

    from urdf_helpers import quadruped_urdf

    text = sk.robots.text("go2") if name == "go2" else quadruped_urdf(0.4, 90.0, 200.0)
    text = re.sub(r'lower="[^"]*"', 'lower="-3.14159"', text)
    text = re.sub(r'upper="[^"]*"', 'upper="3.14159"', text)
    return sk.Robot.from_urdf_string(text)


WIDE = {}


@pytest.mark.parametrize("name", ["go2", "heavy"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_seed_gets_the_valid_branch_nearest_it(rng, name, dtype):
    """With a seed, each leg's answer is its valid branch nearest the seed (the largest joint's circle
    distance), found here by brute force over the leg's ik_all, on robots whose joints turn all the
    way round (most feet have four valid branches). The seeds sit near the midpoints between two
    valid branches, where a shortcut that skipped the other branches would go wrong, and near one
    branch; some poses stretch the knees, where branches meet. In a batch, for a few poses (the
    batch's bits), and for each leg alone (Leg.ik with the leg's seed)."""
    if name not in WIDE:
        WIDE[name] = _wide_limits(name)
    robot = WIDE[name]
    height = {"go2": 0.3, "heavy": 0.6}[name]
    n = 400
    stance = robot.stance_feet(height)
    poses = np.zeros((n, 6))
    poses[:, 2] = height
    poses += rng.normal(size=(n, 6)) * [0.05, 0.05, 0.05, 0.2, 0.2, 0.3]
    poses[::7, 2] += rng.uniform(0.0, 0.3 * height, len(poses[::7]))  # stretched knees, or out of reach
    feet = stance + rng.normal(size=(n, *stance.shape)) * 0.04
    T = np.stack([sk.body_transform(p) for p in poses])
    seeds = np.empty((n, 12))
    branches, valid, locals_ = [], [], []
    for leg_index, leg in enumerate(robot.legs):
        hip = robot.hip_positions[leg_index]
        local = np.einsum("nji,nj->ni", T[:, :3, :3], feet[:, leg_index] - T[:, :3, 3]) - hip
        sol = leg.ik_all(local)
        locals_.append(local)
        branches.append(sol.q)
        valid.append(sol.valid)
        for k in range(n):
            slots = np.flatnonzero(sol.valid[k])
            if len(slots) == 0:
                seeds[k, 3 * leg_index : 3 * leg_index + 3] = rng.uniform(-3, 3, 3)
                continue
            a, b = rng.choice(slots, 2, replace=len(slots) == 1)
            u = rng.uniform(0.3, 0.7) if k % 3 else rng.uniform(0.0, 0.3)
            step = _wrapped(sol.q[k, b] - sol.q[k, a])
            seeds[k, 3 * leg_index : 3 * leg_index + 3] = sol.q[k, a] + u * step + rng.normal(0, 1e-3, 3)
    got = robot.body_ik(poses.astype(dtype), feet.astype(dtype), seed=seeds.astype(dtype))
    leg_answers = [  # the legs alone, each with its own seed: the same choice
        leg.ik(locals_[j].astype(dtype), seed=seeds[:, 3 * j : 3 * j + 3].astype(dtype))
        for j, leg in enumerate(robot.legs)
    ]
    rows = range(0, n, 37)
    few = [
        robot.body_ik(poses[k].astype(dtype), feet[k].astype(dtype), seed=seeds[k].astype(dtype))
        for k in rows
    ]
    tol = 1e-9 if dtype == np.float64 else 2e-3
    checked = 0
    for leg_index in range(len(robot.legs)):
        q = branches[leg_index]
        seed = seeds[:, 3 * leg_index : 3 * leg_index + 3]
        distance = np.abs(_wrapped(q - seed[:, None, :])).max(axis=2)
        distance[~valid[leg_index]] = np.inf
        for k in range(n):
            finite = np.sort(distance[k][np.isfinite(distance[k])])
            if len(finite) < 2 or finite[1] - finite[0] < 10 * tol:
                continue  # one valid branch (no choice), or a near tie (either is right to rounding)
            expected = q[k, np.argmin(distance[k])]
            answer = got.q[k, 3 * leg_index : 3 * leg_index + 3].astype(np.float64)
            np.testing.assert_allclose(
                _wrapped(answer - expected), 0.0, atol=tol, err_msg=f"pose {k} leg {leg_index}"
            )
            alone = leg_answers[leg_index][0][k].astype(np.float64)  # (q, status)
            np.testing.assert_allclose(
                _wrapped(alone - expected), 0.0, atol=tol, err_msg=f"leg {leg_index} target {k}"
            )
            checked += 1
    assert checked > n  # a real choice at most pose-legs
    for j, k in enumerate(rows):  # a few poses: the batch's bits
        np.testing.assert_array_equal(few[j].q, got.q[k])
