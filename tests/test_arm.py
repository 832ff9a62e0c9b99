"""Spot Arm: C++ against the reference, round trips, all 8 solutions, singular
cases, statuses, pose formats, an independent DHm Chain, batch semantics."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from conftest import BATCH_SHAPES, vee_so3
from spotkin.reference import arm as ref

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

ARM = sk.Spot().arm
LIMITS = ARM.limits
A, B, H, HAND = 0.3385, 0.4033, 0.075, 0.19557
FINGERTIP = sk.translation([0.11745 + 0.05, 0, 0.01482]) @ sk.rotation_y(0.3)


def in_limit_q(rng: np.random.Generator, n: int) -> np.ndarray:
    return rng.uniform(LIMITS[:, 0], LIMITS[:, 1], (n, 6))


def angle_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs((a - b + np.pi) % (2 * np.pi) - np.pi)


def dhm_chain(tool: np.ndarray | None = None) -> sk.Chain:
    """The same arm as a DHm chain (derived by hand; frames differ, joint angles agree)."""
    rows = [
        (0, 0.0, 0.0, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, A, 0.0, 0.0, -np.pi / 2),
        (0, H, -np.pi / 2, B, 0.0),
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
    ]
    base = sk.translation(sk.models.SPOT["arm"]["mount"])
    bare = sk.Chain.from_mdh(rows, base=base)
    arm = ARM if tool is None else sk.SpotArm(tool=tool)
    constant = np.linalg.inv(bare.fk(np.zeros(6))) @ arm.fk(np.zeros(6))
    return sk.Chain.from_mdh(rows, base=base, tool=constant)


# -- reference agreement --------------------------------------------------------------------------------


@pytest.mark.parametrize("tool", [None, FINGERTIP], ids=["hand", "fingertip"])
def test_fk_jacobian_singularity_match_reference(rng, tool):
    arm = ARM if tool is None else sk.SpotArm(tool=tool)
    q = rng.uniform(-np.pi, np.pi, (300, 6))
    np.testing.assert_allclose(arm.fk(q), [ref.fk(qi, tool=tool) for qi in q], rtol=0, atol=1e-14)
    np.testing.assert_allclose(arm.jacobian(q), [ref.jacobian(qi, tool=tool) for qi in q], rtol=0, atol=1e-14)
    s = arm.singularity(q)
    expected = [ref.singularity(qi, tool=tool) for qi in q]
    for name in ("wrist", "elbow", "shoulder"):
        np.testing.assert_allclose(getattr(s, name), [e[name] for e in expected], rtol=0, atol=1e-14)
    np.testing.assert_allclose(
        s.manipulability, [e["manipulability"] for e in expected], rtol=1e-9, atol=1e-12
    )


def random_poses(rng: np.random.Generator, n: int) -> np.ndarray:
    reachable = ARM.fk(rng.uniform(-np.pi, np.pi, (n, 6)))
    far = ARM.fk(rng.uniform(-np.pi, np.pi, (n // 4, 6)))
    far[:, :3, 3] *= 3.0  # beyond reach
    return np.concatenate([reachable, far])


@pytest.mark.parametrize("with_seed", [False, True])
def test_ik_all_and_ik_match_reference(rng, with_seed):
    T = random_poses(rng, 300)
    seeds = rng.uniform(-np.pi, np.pi, (len(T), 6)) if with_seed else None
    sol = ARM.ik_all(T, seed=seeds)
    q, status = ARM.ik(T, seed=seeds)
    for i, Ti in enumerate(T):
        seed = None if seeds is None else seeds[i]
        q_ref, exists_ref = ref.ik_all(Ti, seed=seed)
        np.testing.assert_array_equal(sol.exists[i], exists_ref)
        for s in range(8):
            if not exists_ref[s]:
                assert np.isnan(sol.q[i, s]).all() and not sol.valid[i, s]
                continue
            wrapped, ok = ref.wrap_into_limits(q_ref[s])
            assert sol.valid[i, s] == ok
            np.testing.assert_allclose(sol.q[i, s], wrapped if ok else q_ref[s], rtol=0, atol=1e-10)
        q_one, status_ref = ref.ik(Ti, seed=seed)
        assert status[i] == status_ref
        np.testing.assert_allclose(q[i], q_one, rtol=0, atol=1e-10)


# -- round trips ----------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize(
    ("dtype", "pose_tol", "q_tol"), [(np.float64, 1e-10, 1e-7), (np.float32, 1e-4, 5e-2)]
)
def test_round_trip_contains_generating_configuration(rng, dtype, pose_tol, q_tol):
    n = 100_000
    q = in_limit_q(rng, n)
    T = ARM.fk(q.astype(dtype))
    sol = ARM.ik_all(T)
    assert sol.q.dtype == dtype and sol.exists.all()
    # every valid solution reproduces the target pose
    back = ARM.fk(np.where(sol.valid[..., None], sol.q, 0).astype(np.float64))
    error = np.abs(back - T[:, None].astype(np.float64)).max(axis=(-1, -2))
    assert error[sol.valid].max() < pose_tol
    # the generating configuration is among the valid ones (for float32, skip the
    # samples within 1e-2 of a singular set, where float32 rounding of the pose
    # moves the angles by more than the tolerance)
    distance = angle_error(sol.q.astype(np.float64), q[:, None]).max(-1)
    distance = np.where(sol.valid, distance, np.inf).min(-1)
    s = ARM.singularity(q)
    margin = 1e-2 if dtype == np.float32 else 0.0
    regular = (s.wrist > margin) & (s.elbow > margin) & (s.shoulder > margin)
    assert regular.mean() > 0.9
    assert distance[regular].max() < q_tol


def test_eight_solutions_generically_without_limits(rng):
    free = sk.SpotArm(limits=None)
    q = rng.uniform(-np.pi, np.pi, (20_000, 6))
    sol = free.ik_all(free.fk(q))
    assert sol.valid.all()  # all 8 exist and, without limits, all are valid
    # the 8 are distinct solutions away from singular configurations
    s = free.singularity(q)
    regular = (s.wrist > 1e-3) & (s.elbow > 1e-3) & (s.shoulder > 1e-3)
    flat = sol.q[regular]
    gaps = angle_error(flat[:, :, None, :], flat[:, None, :, :]).max(-1)
    gaps[:, np.arange(8), np.arange(8)] = np.inf
    assert gaps.min() > 1e-6


# -- singular cases -------------------------------------------------------------------------------------


def pose_error(arm: sk.SpotArm, q: np.ndarray, T: np.ndarray) -> float:
    return float(np.abs(arm.fk(q) - T).max())


def test_wrist_singularity_keeps_seed_el1_and_is_exact(rng):
    for _ in range(50):
        q = in_limit_q(rng, 1)[0]
        q[4] = 0.0  # wr0 = 0: el1 and wr1 align
        T = ARM.fk(q)
        sol = ARM.ik_all(T)
        assert sol.exists.all()
        # the (shoulder, elbow) pair of the generating configuration is wrist-singular:
        # its wrist-0 slot keeps el1 at 0 without a seed, at the seed's el1 with one
        pair = 2 * int(angle_error(sol.q[:, :3], q[:3]).max(-1).argmin() // 2)
        assert np.abs(np.sin(sol.q[pair, 4])) < 1e-9
        assert sol.q[pair, 3] == 0.0
        seed = q + rng.normal(0, 0.05, 6)
        seeded = ARM.ik_all(T, seed=seed)
        np.testing.assert_allclose(seeded.q[pair, 3], seed[3], atol=1e-15)
        for solutions in (sol, seeded):
            for s in range(8):
                assert pose_error(ARM.__class__(limits=None), solutions.q[s], T) < 1e-12
        q_seeded, status = ARM.ik(T, seed=seed)
        assert status == sk.Status.OK and pose_error(ARM, q_seeded, T) < 1e-12
        assert ARM.singularity(q_seeded).wrist < 1e-9


def test_shoulder_singularity_uses_seed_sh0():
    # wrist centre on the sh0 axis: choose sh1 so that its in-plane reach
    # cos(sh1) sx + sin(sh1) sz vanishes
    free = sk.SpotArm(limits=None)
    for el0 in (0.0, 0.4, -0.7):
        sx = A + B * np.cos(el0) + H * np.sin(el0)
        sz = -B * np.sin(el0) + H * np.cos(el0)
        q = np.array([0.7, np.arctan2(-sx, sz), el0, 0.3, 0.8, -0.4])
        assert free.singularity(q).shoulder < 1e-15
        T = free.fk(q)
        sol = free.ik_all(T, seed=q)
        assert sol.exists.all()
        np.testing.assert_allclose(sol.q[0, 0], 0.7, atol=1e-15)
        for s in range(8):
            assert pose_error(free, sol.q[s], T) < 1e-12
        assert angle_error(sol.q, q).max(-1).min() < 1e-9
        unseeded = free.ik_all(T)
        assert unseeded.q[0, 0] == 0.0


def test_elbow_stretched_is_exact():
    free = sk.SpotArm(limits=None)
    phi = np.arctan2(H, B)
    for q in ([0.3, -0.4, phi, 0.2, 0.9, 0.1], [0.3, -0.4, phi + np.pi, 0.2, 0.9, 0.1]):
        q = np.array(q)
        assert free.singularity(q).elbow < 1e-15
        T = free.fk(q)
        sol = free.ik_all(T)
        assert sol.exists.all()
        for s in range(8):
            assert pose_error(free, sol.q[s], T) < 1e-12
        np.testing.assert_allclose(
            sol.q[:, 2][::2], sol.q[:, 2][1::2], atol=1e-7
        )  # the two elbow slots merge


# -- statuses, formats, bad input -----------------------------------------------------------------------


def test_statuses():
    T_ok = ARM.fk(np.array([0.1, -1.0, 1.5, 0.2, 0.5, 0.0]))
    far = T_ok.copy()
    far[:3, 3] = [2.0, 0.0, 0.5]
    scaled = T_ok.copy()
    scaled[:3, :3] *= 1.0 + 2e-6
    reflected = T_ok.copy()
    reflected[:3, 0] *= -1
    bad_row = T_ok.copy()
    bad_row[3, 0] = 0.1
    nan = T_ok.copy()
    nan[0, 3] = np.nan
    tight = sk.SpotArm(limits=np.tile([0.0, 0.01], (6, 1)))
    q, status = ARM.ik(np.stack([T_ok, far, scaled, reflected, bad_row, nan]))
    np.testing.assert_array_equal(status, [0, 1, 3, 3, 3, 3])
    assert np.isfinite(q[0]).all() and np.isnan(q[1:]).all()
    sol = ARM.ik_all(far)
    assert sol.status == sk.Status.UNREACHABLE and not sol.exists.any() and np.isnan(sol.q).all()
    q, status = tight.ik(T_ok)
    assert status == sk.Status.JOINT_LIMIT and np.isnan(q).all()
    # a rotation within 1e-6 of orthonormal is accepted, not silently fixed
    nearly = T_ok.copy()
    nearly[:3, :3] *= 1.0 + 4e-7
    assert ARM.ik(nearly)[1] == sk.Status.OK
    seed = np.full(6, np.nan)
    assert ARM.ik(T_ok, seed=seed)[1] == sk.Status.INVALID_INPUT


def test_position_quaternion_format_and_pose_from(rng):
    from scipy.spatial.transform import Rotation

    q = in_limit_q(rng, 200)
    T = ARM.fk(q)
    quat = Rotation.from_matrix(T[:, :3, :3]).as_quat()  # xyzw
    p7 = np.concatenate([T[:, :3, 3], quat], axis=-1)
    np.testing.assert_allclose(sk.pose_from(T[:, :3, 3], quat), T, atol=1e-15)
    a, b = ARM.ik_all(T), ARM.ik_all(p7)
    np.testing.assert_allclose(a.q, b.q, atol=1e-12)
    np.testing.assert_array_equal(a.valid, b.valid)
    bad = p7[:3].copy()
    bad[0, 3:] *= 1.01  # non-unit quaternion
    assert list(ARM.ik(bad)[1]) == [3, 0, 0]
    assert np.isnan(sk.pose_from([0, 0, 0], [0, 0, 0, 1.1])).all()
    np.testing.assert_allclose(sk.pose_from([1, 2, 3], [0, 0, 0, 1]), sk.translation([1, 2, 3]))


def test_seed_picks_the_nearest_valid_solution(rng):
    free = sk.SpotArm(limits=None)
    q = rng.uniform(-np.pi, np.pi, (500, 6))
    T = free.fk(q)
    sol = free.ik_all(T)
    for target in range(8):
        seed = sol.q[:, target] + rng.normal(0, 1e-3, (500, 6))
        chosen, status = free.ik(T, seed=seed)
        assert (status == 0).all()
        distance = angle_error(sol.q, seed[:, None]).max(-1)
        best = distance.argmin(-1)
        np.testing.assert_allclose(chosen, sol.q[np.arange(500), best], atol=1e-12)


def test_bad_input_raises():
    with pytest.raises(ValueError, match=r"T must have shape \(\.\.\., 4, 4\) or \(\.\.\., 7\)"):
        ARM.ik(np.zeros((5, 3)))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 6\), got \(2, 5\)"):
        ARM.fk(np.zeros((2, 5)))
    with pytest.raises(TypeError, match="T must be a real numeric array"):
        ARM.ik_all("pose")
    with pytest.raises(ValueError, match="do not broadcast"):
        ARM.ik(np.tile(np.eye(4), (3, 1, 1)), seed=np.zeros((2, 6)))
    with pytest.raises(ValueError, match="tool must be a finite rigid transform"):
        sk.SpotArm(tool=np.diag([2.0, 1, 1, 1]))
    with pytest.raises(ValueError, match=r"limits must have shape \(6, 2\)"):
        sk.SpotArm(limits=np.zeros((3, 2)))


# -- independent oracle, Jacobian, batches ------------------------------------------------------------


@pytest.mark.parametrize("tool", [None, FINGERTIP], ids=["hand", "fingertip"])
def test_dhm_chain_of_the_same_arm_agrees(rng, tool):
    arm = ARM if tool is None else sk.SpotArm(tool=tool)
    chain = dhm_chain(tool)
    q = rng.uniform(-np.pi, np.pi, (2000, 6))
    np.testing.assert_allclose(chain.fk(q), arm.fk(q), atol=1e-14)
    np.testing.assert_allclose(chain.jacobian(q), arm.jacobian(q), atol=1e-14)


def test_jacobian_matches_central_differences(rng):
    arm = sk.SpotArm(tool=FINGERTIP)
    step = 1e-6
    for q in rng.uniform(-np.pi, np.pi, (100, 6)):
        J = np.zeros((6, 6))
        R = arm.fk(q)[:3, :3]
        for j in range(6):
            dq = np.zeros(6)
            dq[j] = step
            plus, minus = arm.fk(q + dq), arm.fk(q - dq)
            J[:3, j] = (plus[:3, 3] - minus[:3, 3]) / (2 * step)
            J[3:, j] = vee_so3((plus[:3, :3] - minus[:3, :3]) / (2 * step) @ R.T)
        np.testing.assert_allclose(arm.jacobian(q), J, atol=1e-8)


@given(
    batch=st.sampled_from(BATCH_SHAPES),
    dtype=st.sampled_from([np.float64, np.float32]),
    seed=st.integers(0, 2**32 - 1),
    fmt=st.sampled_from(["matrix", "quaternion"]),
)
def test_batch_shapes(batch, dtype, seed, fmt):
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    q = in_limit_q(rng, int(np.prod(batch, dtype=int))).reshape(*batch, 6)
    T = ARM.fk(q)
    if fmt == "quaternion":
        quat = Rotation.from_matrix(T[..., :3, :3].reshape(-1, 3, 3)).as_quat().reshape(*batch, 4)
        T = np.concatenate([T[..., :3, 3], quat], -1)
    T = T.astype(dtype)
    assert ARM.fk(q.astype(dtype)).shape == (*batch, 4, 4) and ARM.fk(q.astype(dtype)).dtype == dtype
    assert ARM.jacobian(q).shape == (*batch, 6, 6)
    assert ARM.singularity(q).wrist.shape == batch
    sol = ARM.ik_all(T)
    assert sol.q.shape == (*batch, 8, 6) and sol.q.dtype == dtype and sol.valid.shape == (*batch, 8)
    q_back, status = ARM.ik(T, seed=q)
    assert q_back.shape == (*batch, 6) and q_back.dtype == dtype
    if batch:
        assert status.shape == batch
    else:
        assert isinstance(status, sk.Status)
    assert (np.asarray(status) == 0).all()


def test_empty_noncontiguous_and_pickle(rng):
    assert ARM.ik_all(np.zeros((0, 4, 4))).q.shape == (0, 8, 6)
    assert ARM.ik(np.zeros((2, 0, 7)))[0].shape == (2, 0, 6)
    T = ARM.fk(in_limit_q(rng, 20))
    strided = np.asfortranarray(T)[::2]
    np.testing.assert_array_equal(ARM.ik_all(strided).q, ARM.ik_all(np.ascontiguousarray(strided)).q)
    clone = pickle.loads(pickle.dumps(sk.SpotArm(tool=FINGERTIP)))
    np.testing.assert_array_equal(clone.fk(np.ones(6)), sk.SpotArm(tool=FINGERTIP).fk(np.ones(6)))


def test_threads_bit_identical(rng):
    T = ARM.fk(in_limit_q(rng, 100_003))
    before = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = ARM.ik_all(T).q
        sk.set_num_threads(2)
        two = ARM.ik_all(T).q
    finally:
        sk.set_num_threads(before)
    np.testing.assert_array_equal(one, two)
