"""The Python-composed entry points check what the C++ boundary checks.

Non-numeric or masked input raises TypeError naming the argument; float32 (either
byte order) stays float32 where the output follows the input; shape and broadcast
errors are ValueErrors naming the arguments; NaN in one sample stays in that sample.
"""

from __future__ import annotations

import copy
import pickle
import re

import numpy as np
import pytest

import spotkin as sk
from spotkin._support import boundary as _boundary
from spotkin.model.robot_body import _solve_rows
from spotkin.models import LEG_NAMES
from spotkin.models import SPOT as SPOT_MODEL

SPOT = sk.Spot()
Q12 = np.tile([0.0, 1.04, -1.8], 4)
Q_ARM = np.array([0.2, -1.0, 1.7, 0.1, 0.4, 0.0])
POSE = np.array([0.02, -0.01, 0.5, 0.05, -0.1, 0.2])
TWIST = np.array([0.1, -0.05, 0.02, 0.1, 0.05, 0.2])
CHAIN = sk.Chain.from_mdh(np.array([[0, 0, 0, 0, 0], [0, 0.5, 0, 0, 0]], float))


def _euler_matrix(pose) -> np.ndarray:
    """World <- body for [x, y, z, a, b, c], intrinsic XYZ, from elementary rotations."""
    x, y, z, a, b, c = pose
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    T = np.eye(4)
    T[:3, :3] = Rx @ Ry @ Rz
    T[:3, 3] = x, y, z
    return T


T_BODY = _euler_matrix(POSE)
T_HAND = T_BODY @ SPOT.arm.fk(Q_ARM)

# -- one boundary for every entry point ----------------------------------------------------------------

# (label, call taking a dict of arguments, the valid arguments)
ENTRY_POINTS = [
    ("body_rates", lambda a: SPOT.body_rates(**a), {"body_pose": POSE, "q": Q12, "twist": TWIST}),
    ("fk_all", lambda a: SPOT.fk_all(**a), {"body_pose": POSE, "q": Q12, "q_arm": Q_ARM}),
    ("arm_ik_world", lambda a: SPOT.arm_ik_world(**a), {"body_pose": POSE, "T_world": T_HAND, "seed": Q_ARM}),
    (
        "body_ik",
        lambda a: SPOT.body_ik(**a),
        {"body_pose": POSE, "feet": SPOT.body_fk(POSE, Q12), "seed": Q12},
    ),
    ("body_fk", lambda a: SPOT.body_fk(**a), {"body_pose": POSE, "q": Q12}),
    ("pose_from", lambda a: sk.pose_from(**a), {"position": [0.1, 0.2, 0.3], "quat_xyzw": [0, 0, 0.6, 0.8]}),
    ("body_transform", lambda a: sk.body_transform(**a), {"body_pose": POSE}),
    ("nearest_reachable", lambda a: SPOT.leg("fl").nearest_reachable(**a), {"p": [0.0, 0.1, -0.5]}),
    ("leg.ik", lambda a: SPOT.leg("fl").ik(**a), {"p": [0.0, 0.1, -0.5], "seed": [0.0, 1.0, -1.8]}),
    ("arm.ik", lambda a: SPOT.arm.ik(**a), {"T": SPOT.arm.fk(Q_ARM), "seed": Q_ARM}),
    ("paul.type2", lambda a: sk.paul.type2(**a), {"X": 1.0, "Y": 0.5, "Z": 0.3}),
    ("paul.type3", lambda a: sk.paul.type3(**a), {"X1": 1, "Y1": 0, "Z1": 0.6, "X2": 0, "Y2": 1, "Z2": 0.8}),
    ("paul.type6", lambda a: sk.paul.type6(**a), {"W": 1.0, "X": 0.5, "Y": 0.2, "Z1": 0.1, "Z2": 0.3}),
    ("translation", lambda a: sk.translation(**a), {"p": [1.0, 2.0, 3.0]}),
    ("rotation_x", lambda a: sk.rotation_x(**a), {"angle": [0.1, 0.2]}),
    ("transform", lambda a: sk.transform(**a), {"R": np.eye(3), "p": [1.0, 2.0, 3.0]}),
    ("ik_differential", lambda a: CHAIN.ik_differential(**a), {"T_targets": np.eye(4), "q0": [0.1, 0.2]}),
]
HOSTILE = {
    "str": lambda v: np.asarray(v).astype(str),
    "bytes": lambda v: np.asarray(v).astype("S"),
    "complex": lambda v: np.asarray(v) + 0j,
    "object": lambda v: np.asarray(v).astype(object),
    "masked": lambda v: np.ma.masked_array(np.asarray(v, dtype=float)),
    "none": lambda v: None,
}
CASES = [
    pytest.param(call, args, name, make, id=f"{label}-{name}-{kind}")
    for label, call, args in ENTRY_POINTS
    for name in args
    for kind, make in HOSTILE.items()
    if not (kind == "none" and name in ("seed", "q_arm"))  # None: no seed, no arm
]


@pytest.mark.parametrize(("call", "args", "name", "make"), CASES)
def test_non_numeric_and_masked_input_raise_type_error_naming_the_argument(call, args, name, make):
    call(args)  # the valid call works
    hostile = dict(args, **{name: make(args[name])})
    with pytest.raises(TypeError, match=rf"\b{re.escape(name)} must be"):
        call(hostile)


def test_string_arrays_are_not_parsed_as_numbers():
    # the audit's reproducers: these used to run on the parsed numbers
    with pytest.raises(TypeError, match="q"):
        SPOT.fk_all(POSE, [str(v) for v in Q12])
    with pytest.raises(TypeError, match="position"):
        sk.pose_from(["0.1", "0.2", "0.3"], [0, 0, 0, 1])
    with pytest.raises(TypeError, match="p must be"):
        SPOT.leg("fl").nearest_reachable(["0", "0.1", "-0.5"])
    with pytest.raises(TypeError, match="base"):
        sk.Chain.from_mdh(np.array([[0, 0, 0, 0, 0], [0, 0.5, 0, 0, 0]], float), base=np.eye(4).astype(str))


def test_as_real_conversions():
    big = np.arange(6, dtype=">f4").reshape(2, 3)
    out = _boundary.as_real(big, "x")
    assert out.dtype == np.float32 and out.dtype.isnative
    np.testing.assert_array_equal(out, np.arange(6).reshape(2, 3))
    for given in (np.float16, np.int32, np.uint8, bool, ">f8", np.longdouble):
        assert _boundary.as_real(np.ones(3, given), "x").dtype == np.float64
    native = np.ones(3)
    assert _boundary.as_real(native, "x") is native  # no copy for the common case
    assert _boundary.as_real(np.ones(3, np.float32), "x", np.float64).dtype == np.float64
    with pytest.raises(ValueError, match="x must be a rectangular numeric array"):
        _boundary.as_real([[1, 2], [3]], "x")
    for bad in ("1.5", b"1", np.datetime64("2020-01-01"), np.zeros(2, [("a", float)]), {1: 2}):
        with pytest.raises(TypeError, match="x must be"):
            _boundary.as_real(bad, "x")


def test_python_ints_beyond_int64_are_numbers():
    """NumPy holds ints beyond int64 as objects: they are read as float64, as NumPy's float64
    conversion reads them, and an int beyond float64's range is a ValueError saying so."""
    out = _boundary.as_real((10**30, 0, 1.5), "velocity")
    assert out.dtype == np.float64
    np.testing.assert_array_equal(out, [1e30, 0.0, 1.5])
    assert _boundary.as_real([[10**20], [1]], "x", np.float32).dtype == np.float32
    with pytest.raises(ValueError, match="velocity holds an integer too large for float64"):
        _boundary.as_real((10**400, 0, 0), "velocity")
    with pytest.raises(TypeError, match="velocity must be a real numeric array, got tuple"):
        _boundary.as_real((10**30, None), "velocity")
    # the compiled boundary reads them the same way (a batch takes it; one sample its own path)
    leg = SPOT.leg("fl")
    q, status = leg.ik([[10**30, 0, 0]])
    np.testing.assert_array_equal(status, [sk.Status.UNREACHABLE])
    np.testing.assert_array_equal(q, leg.ik([[1e30, 0.0, 0.0]])[0])
    for bad in ([10**400, 0, 0], [[10**400, 0, 0]]):
        with pytest.raises(ValueError, match="p holds an integer too large for float64"):
            leg.ik(bad)
    with pytest.raises(TypeError, match="p must be a real numeric array"):
        leg.ik([[10**30, "1.5", 0]])


def test_float32_of_either_byte_order_stays_float32():
    pose64 = np.stack([POSE, POSE + 0.01])
    target64 = np.stack([_euler_matrix(p) @ SPOT.arm.fk(Q_ARM) for p in pose64])
    q64, status64 = SPOT.arm_ik_world(pose64, target64)
    assert q64.dtype == np.float64 and (status64 == 0).all()
    for dtype in (np.float32, ">f4"):
        q32, status = SPOT.arm_ik_world(pose64.astype(dtype), target64.astype(dtype))
        assert q32.dtype == np.float32
        assert (status == 0).all()
        np.testing.assert_allclose(q32, q64, atol=2e-3)
        # the core binding and the Python broadcasting of the seed agree on the dtype
        p = SPOT.leg("fl").fk([0.1, 1.0, -1.7])
        q, _ = SPOT.leg("fl").ik(np.broadcast_to(p, (2, 3)).astype(dtype), np.array([0.1, 1.0, -1.7]))
        assert q.dtype == np.float32
        np.testing.assert_allclose(q, np.broadcast_to([0.1, 1.0, -1.7], (2, 3)), atol=1e-4)
        q_path, _ = CHAIN.ik_differential(np.eye(4).astype(dtype), np.zeros(2, dtype))
        assert q_path.dtype == np.float32
    # mixed: float64 results
    q, _ = SPOT.arm_ik_world(pose64.astype(np.float32), target64)
    assert q.dtype == np.float64


# -- shapes and broadcasting name the arguments --------------------------------------------------------


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: SPOT.fk_all(POSE, 1.5),
            r"q must have shape \(\.\.\., 12\) or \(\.\.\., 18\) .*, got \(\)",
        ),
        (lambda: SPOT.fk_all(POSE, Q12, np.zeros(5)), r"q_arm must have shape \(\.\.\., 6\), got \(5,\)"),
        (lambda: SPOT.fk_all(np.zeros((5, 6)), np.zeros((3, 12))), r"body_pose \(5, 6\) and q \(3, 12\)"),
        (
            lambda: SPOT.fk_all(POSE, np.zeros((3, 12)), np.zeros((2, 6))),
            r"body_pose \(6,\), q \(3, 12\) and q_arm \(2, 6\) do not broadcast",
        ),
        (lambda: SPOT.body_rates(POSE, Q12, np.zeros(5)), r"twist must have shape \(\.\.\., 6\)"),
        (
            lambda: SPOT.body_rates(np.zeros((2, 6)), Q12, np.zeros((3, 6))),
            r"body_pose \(2, 6\), q \(12,\) and twist \(3, 6\) do not broadcast",
        ),
        (lambda: SPOT.arm_ik_world(POSE, np.eye(3)), r"T_world must have shape \(\.\.\., 4, 4\)"),
        (lambda: SPOT.arm_ik_world(POSE, T_HAND, np.zeros(5)), r"seed must have shape \(\.\.\., 6\)"),
        (
            lambda: SPOT.arm_ik_world(np.zeros((5, 6)), np.zeros((3, 4, 4))),
            r"body_pose \(5, 6\) and T_world \(3, 4, 4\) do not broadcast",
        ),
        (
            lambda: SPOT.arm_ik_world(POSE, np.zeros((3, 4, 4)), np.zeros((2, 6))),
            r"T_world \(3, 4, 4\) and seed \(2, 6\)",
        ),
        (
            lambda: SPOT.body_ik(np.zeros((5, 6)), np.zeros((4, 3)), np.zeros((3, 12))),
            r"body_pose \(5, 6\), feet \(4, 3\) and seed \(3, 12\) do not broadcast",
        ),
        (lambda: SPOT.body_ik(POSE, np.zeros((4, 3)), np.zeros(11)), r"seed must have shape \(\.\.\., 12\)"),
        (lambda: SPOT.body_fk(np.zeros((5, 6)), np.zeros((3, 12))), r"body_pose \(5, 6\) and q \(3, 12\)"),
        (
            lambda: sk.pose_from(np.zeros((2, 3)), np.zeros((3, 4))),
            r"position \(2, 3\) and quat_xyzw \(3, 4\)",
        ),
        (lambda: sk.pose_from(np.zeros(3), np.zeros(3)), r"quat_xyzw must have shape \(\.\.\., 4\)"),
        (
            lambda: sk.paul.type2(np.ones(2), np.ones(3), 0.0),
            r"X \(2,\), Y \(3,\) and Z \(\) do not broadcast",
        ),
        (
            lambda: sk.paul.type6(1, np.ones(2), 1, 1, np.ones(3)),
            r"X \(2,\).* and Z2 \(3,\) do not broadcast",
        ),
        (lambda: sk.transform(np.zeros((2, 3, 3)), np.zeros((3, 3))), r"R \(2, 3, 3\) and p \(3, 3\)"),
        (lambda: SPOT.leg("fl").ik(np.zeros((5, 3)), np.zeros((3, 3))), r"p \(5, 3\) and seed \(3, 3\)"),
        (lambda: SPOT.arm.ik(np.zeros((5, 4, 4)), np.zeros((3, 6))), r"T \(5, 4, 4\) and seed \(3, 6\)"),
        (lambda: SPOT.leg("fl").nearest_reachable(np.zeros((2, 3))), r"p must have shape \(3,\)"),
    ],
)
def test_shape_errors_name_the_arguments(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_body_ik_seed_broadcasts_with_the_poses():
    poses = np.stack([POSE, POSE + [0.01, 0, 0, 0, 0.02, 0]])
    feet = SPOT.body_fk(POSE, Q12)
    seeds = np.stack([Q12, Q12 + 0.05, Q12 - 0.05])[:, None, :]  # (3, 1, 12) against (2,) poses
    out = SPOT.body_ik(poses, feet, seed=seeds)
    assert out.q.shape == (3, 2, 12) and out.status.shape == (3, 2, 4)
    for i in range(3):
        for j in range(2):
            single = SPOT.body_ik(poses[j], feet, seed=seeds[i, 0])
            np.testing.assert_array_equal(out.q[i, j], single.q)
            np.testing.assert_array_equal(out.status[i, j], single.status)
    # a single seed for a batch of poses
    shared = SPOT.body_ik(poses, feet, seed=Q12)
    np.testing.assert_array_equal(shared.q, out.q[0])


def test_arm_ik_world_broadcasts_seeds_and_flags_a_non_rigid_body_pose():
    poses = np.stack([T_BODY, 2.0 * T_BODY, T_BODY])  # the middle one is scaled, not rigid
    seeds = np.stack([Q_ARM, Q_ARM + 0.1])[:, None, :]  # (2, 1, 6) against (3,) poses
    q, status = SPOT.arm_ik_world(poses, T_HAND, seed=seeds)
    assert q.shape == (2, 3, 6)
    np.testing.assert_array_equal(status[:, 1], sk.Status.INVALID_INPUT)
    assert np.isnan(q[:, 1]).all()
    for i in range(2):
        for j in (0, 2):
            single_q, single_status = SPOT.arm_ik_world(T_BODY, T_HAND, seed=seeds[i, 0])
            assert status[i, j] == single_status == sk.Status.OK
            np.testing.assert_allclose(q[i, j], single_q, atol=1e-12)
    np.testing.assert_allclose(q[0, 0], Q_ARM, atol=1e-9)


# -- body_rates ----------------------------------------------------------------------------------------


def _feet_velocity(pose, q12, twist, qd):
    """Foot velocities (4, 3) from the body Jacobian (the C++ core, independent of body_rates)."""
    J = SPOT.body_jacobian(pose, q12)
    return (J[:, :6] @ twist + J[:, 6:] @ qd).reshape(4, 3)


def test_body_rates_nan_joint_stays_in_its_leg_and_sample():
    q = np.stack([Q12, Q12 + 0.05, Q12 - 0.05])
    q[1, 4] = np.nan  # fr.hy of the middle sample
    rates = SPOT.body_rates(POSE, q, TWIST)  # used to raise LinAlgError for the whole batch
    expected_singular = np.zeros((3, 4), dtype=bool)
    expected_singular[1, 1] = True
    np.testing.assert_array_equal(rates.singular, expected_singular)
    assert np.isnan(rates.qd[1, 3:6]).all()
    assert np.isfinite(np.delete(rates.qd[1], [3, 4, 5])).all()
    for k in (0, 2):
        single = SPOT.body_rates(POSE, q[k], TWIST)
        np.testing.assert_allclose(rates.qd[k], single.qd, rtol=0, atol=1e-14)
        np.testing.assert_allclose(_feet_velocity(POSE, q[k], TWIST, rates.qd[k]), 0.0, atol=1e-12)
    # the other legs of the middle sample: as if the NaN joint were finite (legs are independent)
    finite = SPOT.body_rates(POSE, np.where(np.isnan(q[1]), 1.0, q[1]), TWIST)
    np.testing.assert_allclose(np.delete(rates.qd[1], [3, 4, 5]), np.delete(finite.qd, [3, 4, 5]), atol=1e-14)


def test_body_rates_does_not_rely_on_sigma_for_nan_input(monkeypatch):
    # sigma finite for a NaN sample (as a neighbour's value once was): the NaN Jacobian still flags it
    true_singularity = sk.Leg.singularity

    def finite_sigma(leg, q):
        det, sigma = true_singularity(leg, q)
        return det, np.where(np.isnan(sigma), 0.2, sigma)

    monkeypatch.setattr(sk.Leg, "singularity", finite_sigma)
    q = np.stack([Q12, Q12])
    q[1, 0] = np.nan
    rates = SPOT.body_rates(POSE, q, TWIST)
    np.testing.assert_array_equal(rates.singular, [[False] * 4, [True, False, False, False]])
    assert np.isnan(rates.qd[1, :3]).all() and np.isfinite(rates.qd[1, 3:]).all()
    np.testing.assert_allclose(rates.qd[0], SPOT.body_rates(POSE, Q12, TWIST).qd, atol=1e-14)


def test_body_rates_non_finite_twist_or_pose_stays_in_its_sample():
    twists = np.stack([TWIST, np.full(6, np.nan), TWIST * 2, TWIST])
    twists[2, 0] = np.inf
    poses = np.stack([T_BODY, T_BODY, T_BODY, 2.0 * T_BODY])  # the last one is not rigid
    rates = SPOT.body_rates(poses, Q12, twists)
    np.testing.assert_array_equal(rates.singular.all(-1), [False, True, True, True])
    np.testing.assert_array_equal(rates.singular.any(-1), [False, True, True, True])
    assert np.isnan(rates.qd[1:]).all()
    np.testing.assert_allclose(rates.qd[0], SPOT.body_rates(POSE, Q12, TWIST).qd, atol=1e-13)


def test_body_rates_all_nan_and_single_nan():
    rates = SPOT.body_rates(POSE, np.full((5, 12), np.nan), TWIST)
    assert rates.singular.all() and np.isnan(rates.qd).all()
    q = Q12.copy()
    q[0] = np.nan
    rates = SPOT.body_rates(POSE, q, TWIST)
    np.testing.assert_array_equal(rates.singular, [True, False, False, False])
    assert np.isnan(rates.qd[:3]).all() and np.isfinite(rates.qd[3:]).all()
    empty = SPOT.body_rates(POSE, np.zeros((0, 12)), TWIST)
    assert empty.qd.shape == (0, 12) and empty.singular.shape == (0, 4)


def test_body_rates_nan_and_singular_masks_agree(rng):
    q = np.tile(Q12, (200, 1)) + rng.normal(0, 0.3, (200, 12))
    q[rng.random((200, 12)) < 0.05] = np.nan
    beta = np.arctan2(SPOT.leg("fl").knee_offset, SPOT.leg("fl").upper_length)
    q[::7, 2] = -beta  # front-left knee stretched
    rates = SPOT.body_rates(POSE, q, TWIST)
    np.testing.assert_array_equal(np.isnan(rates.qd.reshape(200, 4, 3)).any(-1), rates.singular)
    np.testing.assert_array_equal(np.isnan(rates.qd.reshape(200, 4, 3)).all(-1), rates.singular)
    assert rates.singular[::7, 0].all()
    expected = np.isnan(q.reshape(200, 4, 3)).any(-1)
    assert (rates.singular >= expected).all()  # every leg with a NaN joint is flagged
    for k in np.flatnonzero(~rates.singular.all(-1))[:20]:
        single = SPOT.body_rates(POSE, q[k], TWIST)
        np.testing.assert_array_equal(single.singular, rates.singular[k])
        np.testing.assert_allclose(single.qd, rates.qd[k], atol=1e-14)


@pytest.mark.parametrize("tolerance", [np.nan, -1.0, np.inf, -np.inf])
def test_body_rates_tolerance_out_of_range(tolerance):
    with pytest.raises(ValueError, match="tolerance must be a finite number >= 0"):
        SPOT.body_rates(POSE, Q12, TWIST, tolerance=tolerance)


@pytest.mark.parametrize("tolerance", ["a", None, True, 1j, [1e-6], np.array([1e-6])])
def test_body_rates_tolerance_not_a_number(tolerance):
    with pytest.raises(TypeError, match="tolerance must be a real number"):
        SPOT.body_rates(POSE, Q12, TWIST, tolerance=tolerance)


def test_body_rates_tolerance_bounds_the_singular_flag():
    sigma = np.array([leg.singularity(Q12[3 * i : 3 * i + 3])[1] for i, leg in enumerate(SPOT.legs)])
    for tolerance in (0, np.float32(1e-6), 0):
        assert not SPOT.body_rates(POSE, Q12, TWIST, tolerance=tolerance).singular.any()
    between = (np.sort(sigma)[1] + np.sort(sigma)[2]) / 2
    rates = SPOT.body_rates(POSE, Q12, TWIST, tolerance=between)
    np.testing.assert_array_equal(rates.singular, sigma <= between)


def test_solve_rows_isolates_an_exactly_singular_matrix(rng):
    J = rng.normal(size=(5, 3, 3))
    J[2] = [[1, 2, 3], [2, 4, 6], [0, 0, 1]]  # rank 2: LAPACK reports it singular
    rhs = rng.normal(size=(5, 3))
    x = _solve_rows(J, rhs)
    assert np.isnan(x[2]).all()
    for k in (0, 1, 3, 4):
        np.testing.assert_allclose(J[k] @ x[k], rhs[k], atol=1e-12)


# -- fk_all --------------------------------------------------------------------------------------------


def test_fk_all_rejects_a_scalar_or_missing_q():
    with pytest.raises(ValueError, match=r"q must have shape"):  # 1.5 was used for all 12 joints
        SPOT.fk_all(POSE, 1.5)
    with pytest.raises(TypeError, match=r"^q must be"):  # None gave all-NaN frames
        SPOT.fk_all(POSE, None)
    with pytest.raises(ValueError, match=r"q must have shape"):
        SPOT.fk_all(POSE, np.zeros(3))


def test_fk_all_non_rigid_pose_gives_nan_for_that_sample_only():
    bad_last_row = T_BODY.copy()
    bad_last_row[3, 0] = 0.1
    flipped = T_BODY @ np.diag([1.0, 1.0, -1.0, 1.0])  # orthonormal, det -1
    poses = np.stack([T_BODY, 2.0 * T_BODY, bad_last_row, flipped, T_BODY])
    frames = SPOT.fk_all(poses, Q12, Q_ARM)
    single = SPOT.fk_all(T_BODY, Q12, Q_ARM)
    for name in ("body", "hips", "knees", "feet", "hand"):
        value = getattr(frames, name)
        assert np.isnan(value[1:4]).all(), name  # a scaled pose used to give scaled feet
        np.testing.assert_array_equal(value[0], getattr(single, name))
        np.testing.assert_array_equal(value[4], getattr(single, name))
    # the same samples body_fk rejects
    np.testing.assert_array_equal(np.isnan(SPOT.body_fk(poses, Q12)), np.isnan(frames.feet))


def test_fk_all_quaternion_poses_are_read_as_body_fk_reads_them():
    qx, qw = np.sin(0.2), np.cos(0.2)
    unit = np.array([0.1, 0.0, 0.5, qx, 0.0, 0.0, qw])
    poses = np.stack([unit, unit * [1, 1, 1, 1.1, 1.1, 1.1, 1.1], unit])  # middle: |q| = 1.1
    frames = SPOT.fk_all(poses, Q12)
    assert np.isnan(frames.feet[1]).all() and np.isnan(frames.body[1]).all()
    T = sk.translation([0.1, 0.0, 0.5]) @ sk.rotation_x(0.4)
    np.testing.assert_allclose(frames.body[0], T, atol=1e-15)
    np.testing.assert_allclose(frames.feet, SPOT.body_fk(poses, Q12), atol=1e-14, equal_nan=True)


def test_fk_all_matches_independent_frames(rng):
    poses = np.column_stack([rng.uniform(-0.1, 0.1, (20, 3)), rng.uniform(-0.3, 0.3, (20, 3))])
    q12 = np.tile(Q12, (20, 1)) + rng.normal(0, 0.2, (20, 12))
    for seq in ("XYZ", "xyz", "ZYX"):
        frames = SPOT.fk_all(poses, q12, seq=seq)
        T = sk.body_transform(poses, seq)
        np.testing.assert_allclose(frames.body, T, atol=1e-15)
        np.testing.assert_allclose(frames.feet, SPOT.body_fk(poses, q12, seq), atol=1e-14)
        hips = T[:, None, :3, 3] + np.einsum("nij,kj->nki", T[:, :3, :3], SPOT.hip_positions)
        np.testing.assert_allclose(frames.hips, hips, atol=1e-15)
        # knees at the upper-leg length (with its offset) from the hy joints
        np.testing.assert_allclose(
            np.linalg.norm(frames.feet - frames.knees, axis=-1), SPOT.leg("fl").lower_length
        )
        assert frames.hand is None


def test_fk_all_broadcasts_q_arm():
    q_arm = np.stack([Q_ARM, Q_ARM + 0.1, Q_ARM - 0.1])
    frames = SPOT.fk_all(POSE, Q12, q_arm)
    assert (
        frames.body.shape == (3, 4, 4) and frames.feet.shape == (3, 4, 3) and frames.hand.shape == (3, 4, 4)
    )
    for k in range(3):
        np.testing.assert_allclose(frames.hand[k], T_BODY @ SPOT.arm.fk(q_arm[k]), atol=1e-14)
        np.testing.assert_array_equal(frames.feet[k], SPOT.fk_all(POSE, Q12).feet)


def test_body_transform_and_pose_from_are_float64():
    assert sk.body_transform(POSE.astype(np.float32)).dtype == np.float64
    assert sk.pose_from(np.zeros(3, np.float32), np.array([0, 0, 0, 1], np.float32)).dtype == np.float64
    np.testing.assert_allclose(sk.body_transform(POSE), T_BODY, atol=1e-15)
    T = sk.pose_from([[1, 2, 3], [4, 5, 6]], [0, 0, np.sin(0.3), np.cos(0.3)])
    np.testing.assert_allclose(T[1], sk.translation([4, 5, 6]) @ sk.rotation_z(0.6), atol=1e-15)


# -- the Spot model ------------------------------------------------------------------------------------


def _model(**changes):
    model = copy.deepcopy(SPOT_MODEL)
    for path, value in changes.items():
        *keys, last = path.split("__")
        table = model
        for key in keys:
            table = table[key]
        if value is KeyError:
            del table[last]
        else:
            table[last] = value
    return model


@pytest.mark.parametrize(
    ("model", "error", "message"),
    [
        ({}, ValueError, r"model is missing the key 'hip_positions'"),
        ([], TypeError, r"model must be a dict"),
        (_model(leg=KeyError), ValueError, r"model is missing the key 'leg'"),
        (_model(leg__upper=KeyError), ValueError, r"model\['leg'\] is missing the key 'upper'"),
        (_model(hip_positions__fl=(0.3, np.nan, 0.0)), ValueError, r"model\['hip_positions'\]\['fl'\]"),
        (_model(hip_positions__hr=(0.3, 0.0)), ValueError, r"model\['hip_positions'\]\['hr'\] must be 3"),
        (_model(hip_positions__fr=KeyError), ValueError, r"model\['hip_positions'\] is missing the key 'fr'"),
        (_model(hip_positions=[(0, 0, 0)] * 4), TypeError, r"model\['hip_positions'\] must be a dict"),
        (_model(leg__upper=-0.3), ValueError, r"model\['leg'\]\['upper'\] must be a finite number > 0"),
        (_model(leg__lower=np.inf), ValueError, r"model\['leg'\]\['lower'\]"),
        (_model(leg__hip_offset=-0.1), ValueError, r"model\['leg'\]\['hip_offset'\] must be .* >= 0"),
        (_model(leg__foot_radius=np.nan), ValueError, r"model\['leg'\]\['foot_radius'\]"),
        (
            _model(leg__knee_offset="0.025"),
            TypeError,
            r"model\['leg'\]\['knee_offset'\] must be a real number",
        ),
        (
            _model(leg__limits=((1, 0), (0, 1), (0, 1))),
            ValueError,
            r"model\['leg'\]\['limits'\] must satisfy",
        ),
        (
            _model(leg__limits=((0, 1),) * 2),
            ValueError,
            r"model\['leg'\]\['limits'\] must have shape \(3, 2\)",
        ),
        (_model(arm__mount=(0, 0, np.inf)), ValueError, r"model\['arm'\]\['mount'\]"),
        (
            _model(arm__upper_arm=0.0),
            ValueError,
            r"model\['arm'\]\['upper_arm'\] must be a finite number > 0",
        ),
        (_model(arm__limits=((0, np.nan),) * 6), ValueError, r"model\['arm'\]\['limits'\] must satisfy"),
        (_model(arm__forearm=0.0, arm__forearm_offset=0.0), ValueError, r"are both 0"),
        (_model(arm__hand=None), TypeError, r"model\['arm'\]\['hand'\] must be a real number"),
    ],
)
def test_bad_models_name_the_key(model, error, message):
    with pytest.raises(error, match=message):
        sk.Spot(model=model)


def test_custom_model_is_copied_and_pickles():
    model = _model(hip_positions__fl=(0.31, 0.06, 0.01), leg__upper=0.33)
    spot = sk.Spot(model=model)
    np.testing.assert_array_equal(spot.hip_positions[0], [0.31, 0.06, 0.01])
    feet = spot.body_fk(POSE, Q12)
    assert not np.allclose(feet, SPOT.body_fk(POSE, Q12))
    model["hip_positions"]["fl"] = (9.0, 9.0, 9.0)  # later edits of the caller's dict change nothing
    np.testing.assert_array_equal(spot.hip_positions[0], [0.31, 0.06, 0.01])
    np.testing.assert_array_equal(spot.body_fk(POSE, Q12), feet)
    again = pickle.loads(pickle.dumps(spot))
    np.testing.assert_array_equal(again.body_fk(POSE, Q12), feet)
    np.testing.assert_array_equal(again.stance_feet(0.5), spot.stance_feet(0.5))
    default = pickle.loads(pickle.dumps(SPOT))
    np.testing.assert_array_equal(default.body_fk(POSE, Q12), SPOT.body_fk(POSE, Q12))
    assert np.array_equal(
        sk.Spot(model=copy.deepcopy(SPOT_MODEL)).body_fk(POSE, Q12), SPOT.body_fk(POSE, Q12)
    )


def test_hip_positions_cannot_be_changed_through_the_property():
    hips = SPOT.hip_positions
    hips[:] = 0.0
    assert SPOT.hip_positions[0, 0] == SPOT_MODEL["hip_positions"]["fl"][0]


def test_joint_name_constants():
    assert sk.Spot.leg_names == LEG_NAMES == ("fl", "fr", "hl", "hr")
    names = sk.Spot.joint_names
    assert len(names) == 12 and names[:4] == ("fl.hx", "fl.hy", "fl.kn", "fr.hx") and names[-1] == "hr.kn"
    assert [n.split(".")[0] for n in names] == [leg for leg in LEG_NAMES for _ in range(3)]
    assert sk.Spot.arm_joint_names == ("arm0.sh0", "arm0.sh1", "arm0.el0", "arm0.el1", "arm0.wr0", "arm0.wr1")
    assert SPOT.joint_names is sk.Spot.joint_names


# -- numeric parameters --------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [True, False, "4", 2.0, 1.5, None, np.float64(2.0), np.bool_(True)])
def test_set_num_threads_rejects_non_integers(n):
    before = sk.get_num_threads()
    try:
        with pytest.raises(TypeError, match="n must be an integer"):
            sk.set_num_threads(n)
        assert sk.get_num_threads() == before
    finally:
        sk.set_num_threads(before)


def test_set_num_threads_takes_numpy_integers():
    before = sk.get_num_threads()
    try:
        sk.set_num_threads(np.int64(1))
        assert sk.get_num_threads() == 1
        sk.set_num_threads(np.uint8(2))
        assert sk.get_num_threads() == 2
        with pytest.raises(ValueError):
            sk.set_num_threads(0)
    finally:
        sk.set_num_threads(before)


def test_nearest_reachable_non_finite_point_gives_nan():
    leg = SPOT.leg("fl")
    for bad in ([np.inf, 0.0, 0.0], [0.0, np.nan, -0.5], [0.0, 0.1, -np.inf]):
        for within_limits in (False, True):
            assert np.isnan(leg.nearest_reachable(bad, within_limits)).all()  # [inf, 0, 0] was half NaN
    # a finite far point: reachable, and no farther than any sampled reachable point
    far = np.array([0.3, 0.2, -5.0])
    nearest = leg.nearest_reachable(far)
    solutions = sk.Leg(0.110945, 0.3205, 0.3365, 0.025).ik_all(nearest)  # the same leg, no limits
    assert solutions.exists.any()
    np.testing.assert_allclose(leg.fk(solutions.q[solutions.exists][0]), nearest, atol=1e-9)
    q = np.random.default_rng(7).uniform(-np.pi, np.pi, (100_000, 3))
    assert np.linalg.norm(nearest - far) <= np.linalg.norm(leg.fk(q) - far, axis=-1).min() + 1e-9


def test_paul_non_finite_coefficients_give_no_valid_root():
    t, valid = sk.paul.type2(np.inf, 0.7, 0.3)
    assert not valid.any()
    ti, tj, valid = sk.paul.type6(1.0, np.inf, 0.3, 0.1, 0.2)
    assert not valid.any()
    values = np.array([0.0, 0.5, -1.0, 2.0, np.inf, -np.inf, np.nan, 1e308])
    X, Y, Z = np.meshgrid(values, values, values, indexing="ij")
    t, valid = sk.paul.type2(X, Y, Z)
    assert not np.isnan(t[valid]).any()
    finite = np.isfinite(X) & np.isfinite(Y) & np.isfinite(Z)
    assert not valid[~finite].any()
    ok = valid & (np.abs(X) < 1e300)[..., None] & (np.abs(Y) < 1e300)[..., None]
    residual = X[..., None] * np.sin(t) + Y[..., None] * np.cos(t) - Z[..., None]
    assert np.abs(residual[ok]).max() < 1e-12
    ti, tj, valid = sk.paul.type6(*np.meshgrid(values[:6], values[:6], 0.2, 0.1, 0.3, indexing="ij"))
    assert not (np.isnan(ti) | np.isnan(tj))[valid].any()


def test_scalar_model_parameters_are_real_numbers():
    with pytest.raises(TypeError, match="upper must be a real number"):
        sk.Leg(0.1, "0.3", 0.3)
    with pytest.raises(TypeError, match="limits must be"):
        sk.Leg(0.1, 0.3, 0.3, limits=np.zeros((3, 2)) + 0j)
    with pytest.raises(TypeError, match="upper_arm must be a real number"):
        sk.SpotArm(upper_arm="0.3")
    with pytest.raises(TypeError, match="mount must be"):
        sk.SpotArm(mount=["0", "0", "0"])
    with pytest.raises(TypeError, match="height must be a real number"):
        SPOT.stance_feet("0.5")
    with pytest.raises(TypeError, match="within_limits must be True or False"):
        SPOT.leg("fl").nearest_reachable([0.0, 0.1, -0.9], within_limits="False")
    with pytest.raises(TypeError, match="damping must be a real number"):
        CHAIN.ik_differential(np.eye(4), np.zeros(2), damping="0.1")
    with pytest.raises(TypeError, match="max_iter must be an integer"):
        CHAIN.ik_differential(np.eye(4), np.zeros(2), max_iter=1.5)
    with pytest.raises(TypeError, match="max_iter must be an integer"):
        CHAIN.ik_differential(np.eye(4), np.zeros(2), max_iter=True)
    with pytest.raises(ValueError, match="max_step must be a finite number"):
        CHAIN.ik_differential(np.eye(4), np.zeros(2), max_step=np.nan)
    leg = SPOT.leg("fl")
    far = [0.0, 0.1, -0.9]
    np.testing.assert_array_equal(leg.nearest_reachable(far, np.True_), leg.nearest_reachable(far, True))
    assert leg.nearest_reachable(np.array(far, np.float32)).dtype == np.float64
