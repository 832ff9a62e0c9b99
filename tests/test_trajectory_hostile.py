"""Trajectories under hostile input: every reproducer of the input audit for spotkin.trajectory
(planning scale, pickling, overflowing spans, one numpy boundary), each a test."""

from __future__ import annotations

import copy
import math
import pickle
import time

import numpy as np
import pytest

import spotkin as sk

tj = sk.trajectory
T0 = np.eye(4)
T1 = sk.transform(sk.rotation_z(0.5)[:3, :3], [1.0, 0.2, 0.0])
POSES = np.array(
    [[0.0, 0.0, 0.5, 0.0, 0.0, 0.0], [0.3, 0.1, 0.5, 0.1, 0.0, 0.2], [0.5, -0.1, 0.4, 0.0, 0.1, 0.0]]
)


def random_walk(n: int, seed: int = 0) -> np.ndarray:
    """n poses (n, 6): a random walk in position (steps up to 5 cm) with Euler angles up to 0.2 rad."""
    rng = np.random.default_rng(seed)
    p = np.cumsum(rng.uniform(-0.05, 0.05, (n, 3)), axis=0)
    return np.concatenate([p, rng.uniform(-0.2, 0.2, (n, 3))], axis=1)


def bad_arrays(valid: np.ndarray):
    """The same values as str, complex and object arrays, and as a masked array."""
    return [
        ("str", valid.astype(str)),
        ("complex", valid + 0j),
        ("object", valid.astype(object)),
        ("masked", np.ma.masked_array(valid, mask=np.zeros(valid.shape, bool))),
    ]


# ---- scale of via_points ------------------------------------------------------------------------------


def test_via_points_beyond_a_thousand_waypoints():
    # reported: RuntimeError "blend planning did not converge" from 1001 waypoints on
    path = tj.via_points(random_walk(1001), vmax=0.5, amax=1.0)
    d, b = np.diff(path.times), path.blends
    assert len(d) == 1000
    assert ((b[:-1] + b[1:]) / 2 <= d * (1 + 1e-12)).all()


def test_via_points_900_waypoints_is_fast():
    # reported: 4 s for 900 waypoints
    poses = random_walk(900, seed=1)
    start = time.perf_counter()
    path = tj.via_points(poses, vmax=0.5, amax=1.0, wmax=1.0, alphamax=2.0)
    assert time.perf_counter() - start < 0.5
    assert np.isfinite(path.duration)


# ---- pickling and copying --------------------------------------------------------------------------


def same_samples(a, b, t) -> bool:
    out_a, out_b = a.sample(t), b.sample(t)
    return all(np.array_equal(x, y) for x, y in zip(out_a, out_b))


@pytest.mark.parametrize("profile", tj.PROFILES)
def test_point_to_point_pickles_and_copies(profile):
    traj = tj.point_to_point([0.1, -0.5, 2.0], [1.0, 0.5, 2.0], [1.0, 2.0, 1.0], 3.0, profile)
    t = np.linspace(-0.2, traj.duration + 0.2, 101)
    for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
        back = pickle.loads(pickle.dumps(traj, protocol=protocol))
        assert type(back) is tj.PointToPoint and back.profile == profile
        assert back.duration == traj.duration
        assert same_samples(traj, back, t)
    for clone in (copy.deepcopy(traj), copy.copy(traj)):
        assert same_samples(traj, clone, t)
        np.testing.assert_array_equal(clone.cruise_velocity, traj.cruise_velocity)


@pytest.mark.parametrize(
    "make",
    [
        lambda: tj.linear(T0, T1, vmax=0.5, amax=1.0, wmax=1.0, alphamax=2.0),
        lambda: tj.via_points(POSES, vmax=0.3, amax=1.0, wmax=1.0, alphamax=3.0, blend=0.1),
    ],
)
def test_cartesian_path_pickles_and_copies(make):
    path = make()
    t = np.linspace(-0.1, path.duration + 0.1, 101)
    for clone in (pickle.loads(pickle.dumps(path)), copy.deepcopy(path), copy.copy(path)):
        assert type(clone) is tj.CartesianPath and clone.duration == path.duration
        np.testing.assert_array_equal(clone.times, path.times)
        np.testing.assert_array_equal(clone.blends, path.blends)
        for form in ("matrix", "quaternion"):
            got, want = clone.sample(t, form=form, twist=True), path.sample(t, form=form, twist=True)
            for g, w in zip(got, want):
                np.testing.assert_array_equal(g, w)


# ---- point_to_point whose span, duration or rates overflow ---------------------------------------------


@pytest.mark.parametrize("profile", tj.PROFILES)
@pytest.mark.parametrize(
    ("q0", "qf", "vmax", "amax"),
    [
        ([-1e308], [1e308], 1.0, 1.0),  # qf - q0 = inf
        ([0.0, -1e308], [0.0, 1e308], 1.0, 1.0),  # one axis of two
        ([0.0], [1e308], 1e-10, 1.0),  # finite span, duration 1e318 = inf
        ([0.0], [1e308], 1e308, 1e308),  # t_f = 2.4 (or 2) exactly, but 15/8 D or amax t_f overflow
        ([0.0], [1e-300], 1e300, 1e300),  # a real move whose duration underflows to 0: a jump
    ],
)
def test_point_to_point_overflow_raises(profile, q0, qf, vmax, amax):
    with pytest.raises(ValueError, match=r"overflows|not representable"):
        tj.point_to_point(q0, qf, vmax, amax, profile)


def test_point_to_point_trapezoid_cruise_overflow_raises():
    # t_f = 2 is finite, but (amax t_f)^2 in the stretched cruise speed overflows: NaN cruise speed
    with pytest.raises(ValueError, match="overflows"):
        tj.point_to_point([0.0], [1e300], 1e300, 1e300, "trapezoid")


def test_point_to_point_huge_but_representable_is_kept():
    # D = vmax = amax = 1e300: the quintic's t_f = max(15 / 8, sqrt(10 / sqrt(3))) = 2.4028...
    traj = tj.point_to_point([0.0], [1e300], 1e300, 1e300, "quintic")
    assert traj.duration == pytest.approx(math.sqrt(10 / math.sqrt(3)), rel=1e-14)
    q, qd, qdd = traj.sample(np.linspace(0, traj.duration, 101))
    assert np.isfinite(q).all() and np.isfinite(qd).all() and np.isfinite(qdd).all()
    assert q[50, 0] == pytest.approx(0.5e300, rel=1e-14)  # s(1/2) = 1/2
    assert np.abs(qdd).max() <= 1e300 * (1 + 1e-12)


# ---- one numpy boundary ------------------------------------------------------------------------------


POSE_FORMS = {
    "matrix": T1,
    "quaternion": np.array([1.0, 0.2, 0.0, 0.0, 0.0, 0.25, 1.0]),
    "euler": np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.5]),
}


@pytest.mark.parametrize("which", ["T0", "T1"])
@pytest.mark.parametrize("form", POSE_FORMS)
def test_linear_non_numeric_poses(which, form):
    for _, bad in bad_arrays(POSE_FORMS[form]):
        kwargs = {"T0": T0, "T1": POSE_FORMS[form], which: bad}
        with pytest.raises(TypeError, match=which):
            tj.linear(vmax=1.0, amax=1.0, wmax=1.0, alphamax=1.0, **kwargs)


def test_linear_shape_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"T1 must have shape \(4, 4\), \(7,\) or \(6,\), got \(2, 4, 4\)"):
        tj.linear(T0, np.stack([T1, T1]), vmax=1.0, amax=1.0)
    with pytest.raises(ValueError, match=r"T0 must have shape .* got \(\)"):
        tj.linear(1.0, T1, vmax=1.0, amax=1.0)


def test_huge_poses_raise_cleanly():
    huge = np.eye(4)
    huge[:3, :3] = 1e308  # not a rotation; R^T R overflows
    with pytest.raises(ValueError, match="T1 must be a rigid transform"):
        tj.linear(T0, huge, vmax=1.0, amax=1.0)
    far = np.zeros((3, 6))
    far[:, 0] = [-1e308, 1e308, 0.0]  # a distance of 2e308 overflows
    with pytest.raises(ValueError, match="too far apart"):
        tj.via_points(far, vmax=1.0, amax=1.0)
    # the quaternion is scaled before use: |q|^2 = 2e600 does not overflow into an identity rotation
    poses = np.array([[0, 0, 0, 1e300, 0, 0, 0], [1, 0, 0, 1e300, 0, 0, 1e300]])  # half and quarter turn
    path = tj.via_points(poses, 1.0, 1.0, 1.0, 1.0)
    ends = path.sample(np.array([0.0, path.duration]))[:, :3, :3]
    np.testing.assert_allclose(ends[0], sk.rotation_x(math.pi)[:3, :3], atol=1e-15)
    np.testing.assert_allclose(ends[1], sk.rotation_x(math.pi / 2)[:3, :3], atol=1e-15)


def test_via_points_non_numeric_poses():
    for _, bad in bad_arrays(POSES):
        with pytest.raises(TypeError, match="poses"):
            tj.via_points(bad, vmax=1.0, amax=1.0)
    with pytest.raises(TypeError, match="poses"):
        tj.via_points([["0"] * 6] * 3, vmax=1.0, amax=1.0)  # a list of str is not parsed either


def test_via_points_shape_errors_name_the_argument():
    for shape in [(3,), (3, 5), (3, 4, 3), (1, 7), (2, 2, 4, 4)]:
        with pytest.raises(ValueError, match=r"poses must have shape \(N, 4, 4\), \(N, 7\) or \(N, 6\)"):
            tj.via_points(np.zeros(shape), vmax=1.0, amax=1.0)


LIMITS = {"vmax": 1.0, "amax": 1.0, "wmax": 1.0, "alphamax": 1.0}


@pytest.mark.parametrize("name", [*LIMITS, "blend"])
@pytest.mark.parametrize("value", [True, False, np.True_, "1.0", 1 + 0j, np.complex128(1.0), b"1"])
def test_limits_of_the_wrong_type(name, value):
    with pytest.raises(TypeError, match=name):
        tj.via_points(POSES, **{**LIMITS, name: value})
    if name != "blend":
        with pytest.raises(TypeError, match=name):
            tj.linear(T0, T1, **{**LIMITS, name: value})


def test_limits_none_and_shapes():
    for name in ("vmax", "amax", "blend"):  # None means "no limit" only for the optional wmax, alphamax
        with pytest.raises(TypeError, match=name):
            tj.via_points(POSES, **{**LIMITS, name: None})
    with pytest.raises(ValueError, match="wmax and alphamax go together"):
        tj.via_points(POSES, **{**LIMITS, "wmax": None})
    for value in ([1.0], np.array([1.0, 2.0]), np.ones((1, 1))):
        with pytest.raises(ValueError, match=r"vmax must be a scalar, got shape"):
            tj.linear(T0, T1, **{**LIMITS, "vmax": value})


@pytest.mark.parametrize("name", [*LIMITS, "blend"])
@pytest.mark.parametrize("value", [math.nan, -1.0, math.inf, -math.inf, 10**400, np.float32("nan")])
def test_limits_out_of_range(name, value):
    with pytest.raises(ValueError, match=name):
        tj.via_points(POSES, **{**LIMITS, name: value})
    if name != "blend":
        with pytest.raises(ValueError, match=name):
            tj.linear(T0, T1, **{**LIMITS, name: value})


def test_numpy_scalar_limits_are_accepted():
    limits = {"vmax": np.float32(0.5), "amax": np.int64(1), "wmax": np.array(1.0), "alphamax": 2, "blend": 0}
    path = tj.via_points(POSES, **limits)
    want = tj.via_points(POSES, vmax=0.5, amax=1.0, wmax=1.0, alphamax=2.0)
    np.testing.assert_array_equal(path.times, want.times)


def leg_branches():
    leg = sk.Spot().leg("fl")
    t = np.linspace(0.0, 1.0, 21)
    q = np.stack([0.1 * t, 0.9 + 0.2 * t, -1.6 - 0.2 * t], -1)
    return leg.ik_all(leg.fk(q))


def test_hold_branch_non_integer_branch():
    sol = leg_branches()
    for branch in [1.5, 1.0, True, np.True_, "0", None, np.float64(0.0)]:
        with pytest.raises(TypeError, match="branch"):
            tj.hold_branch(sol.q, sol.valid, branch)
    for branch in [-1, 4, 10**30]:
        with pytest.raises(ValueError, match="branch"):
            tj.hold_branch(sol.q, sol.valid, branch)
    held = tj.hold_branch(sol.q, sol.valid, np.int64(0))
    np.testing.assert_array_equal(held.q, tj.hold_branch(sol.q, sol.valid, 0).q)


def test_hold_branch_max_step():
    sol = leg_branches()
    for max_step in [math.nan, -0.1, 0.0, math.inf]:
        with pytest.raises(ValueError, match="max_step"):
            tj.hold_branch(sol.q, sol.valid, 0, max_step=max_step)
    for max_step in ["0.2", True, 0.2j]:
        with pytest.raises(TypeError, match="max_step"):
            tj.hold_branch(sol.q, sol.valid, 0, max_step=max_step)


def test_hold_branch_non_numeric_arrays():
    sol = leg_branches()
    q, valid = np.asarray(sol.q), np.asarray(sol.valid)
    for _, bad in bad_arrays(q):
        with pytest.raises(TypeError, match="q_slots"):
            tj.hold_branch(bad, valid, 0)
    for bad in (valid.astype(str), np.ma.masked_array(valid), valid.astype(object)):
        with pytest.raises(TypeError, match="valid"):
            tj.hold_branch(q, bad, 0)


def test_hold_branch_shape_errors_name_the_argument():
    sol = leg_branches()
    q, valid = np.asarray(sol.q), np.asarray(sol.valid)
    with pytest.raises(ValueError, match=r"q_slots must have shape \(K, S, n\), got \(4, 3\)"):
        tj.hold_branch(q[0], valid, 0)
    with pytest.raises(ValueError, match=r"valid must have shape \(K, S\) = \(21, 4\).* got \(21, 3\)"):
        tj.hold_branch(q, valid[:, :3], 0)
    with pytest.raises(ValueError, match="valid must hold booleans"):
        tj.hold_branch(q, valid * 2.0, 0)


# ---- sampling: times, form, twist ----------------------------------------------------------------------


P2P = tj.point_to_point([0.0, 1.0], [1.0, -1.0], 1.0, 2.0, "trapezoid")
PATH = tj.via_points(POSES, vmax=0.3, amax=1.0, wmax=1.0, alphamax=3.0)


@pytest.mark.parametrize("sample", [P2P.sample, PATH.sample], ids=["PointToPoint", "CartesianPath"])
def test_sample_non_numeric_times(sample):
    t = np.array([0.1, 0.5])
    for _, bad in [*bad_arrays(t), ("str scalar", "0.5"), ("None", None), ("bytes", b"0.5")]:
        with pytest.raises(TypeError, match="t must be"):
            sample(bad)
    with pytest.raises((TypeError, ValueError), match="t must be"):
        sample([[0.1], [0.2, 0.3]])  # ragged


def test_sample_form_and_twist():
    for form in [None, 1, ["matrix"], b"matrix"]:
        with pytest.raises(TypeError, match="form"):
            PATH.sample(0.1, form=form)
    for form in ["euler", "Matrix", ""]:
        with pytest.raises(ValueError, match="form"):
            PATH.sample(0.1, form=form)
    for twist in [1, "yes", None, np.array([True, False])]:
        with pytest.raises(TypeError, match="twist"):
            PATH.sample(0.1, twist=twist)
    pose, twist = PATH.sample(0.1, twist=np.True_)
    assert pose.shape == (4, 4) and twist.shape == (6,)


def test_point_to_point_profile_and_limit_types():
    for profile in [None, 2, ["cubic"]]:
        with pytest.raises(TypeError, match="profile"):
            tj.point_to_point([0.0], [1.0], 1.0, 1.0, profile)
    for name in ("vmax", "amax"):
        for value in [True, np.array([True, True])]:
            with pytest.raises(TypeError, match=name):
                tj.point_to_point([0.0, 0.0], [1.0, 1.0], **{"vmax": 1.0, "amax": 1.0, name: value})
    for name in ("q0", "qf"):
        for _, bad in bad_arrays(np.array([0.0, 0.5])):
            with pytest.raises(TypeError, match=name):
                tj.point_to_point(**{"q0": [0.0, 0.0], "qf": [1.0, 1.0], name: bad}, vmax=1.0, amax=1.0)
