"""Trajectories: point-to-point profiles and Cartesian paths against the per-sample reference,
finite differences, limits, boundary conditions, bad input and the body IK round trip."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from conftest import BATCH_SHAPES, TOLERANCE
from spotkin import _core
from spotkin.reference import trajectory as ref

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

PROFILES = sk.trajectory.PROFILES


def reference_rows(q0, qf, vmax, amax, profile, times):
    rows = [ref.point_to_point(list(q0), list(qf), vmax, amax, profile, float(t)) for t in np.ravel(times)]
    n = len(q0)
    return tuple(np.array([r[i] for r in rows]).reshape((*np.shape(times), n)) for i in range(3))


# ---- per-axis minimum durations, from hand-worked numbers ----------------------------------------


@pytest.mark.parametrize(
    ("profile", "D", "vmax", "amax", "expected"),
    [
        ("cubic", 2.0, 1.0, 1e6, 3.0),  # 3 D / (2 Kv)
        ("cubic", 6.0, 1e6, 1.0, 6.0),  # sqrt(6 D / Ka)
        ("quintic", 8.0, 1.0, 1e6, 15.0),  # 15 D / (8 Kv)
        ("quintic", 0.4 * math.sqrt(3), 1e6, 1.0, 2.0),  # sqrt(10 D / (sqrt(3) Ka))
        ("trapezoid", 10.0, 2.0, 1.0, 7.0),  # D / Kv + Kv / Ka
        ("trapezoid", 1.0, 2.0, 1.0, 2.0),  # triangular: 2 sqrt(D / Ka)
        ("trapezoid", 4.0, 2.0, 1.0, 4.0),  # the boundary case D = Kv^2 / Ka: both formulas agree
        ("quintic", 0.0, 1.0, 1.0, 0.0),
    ],
)
def test_min_duration(profile, D, vmax, amax, expected):
    code = PROFILES.index(profile)
    assert _core.trajectory_min_duration(code, D, vmax, amax) == pytest.approx(expected, rel=1e-14)
    assert ref.min_duration(profile, D, vmax, amax) == pytest.approx(expected, rel=1e-14)
    traj = sk.trajectory.point_to_point([0.0, 0.0], [D, -D / 2], vmax, amax, profile)
    assert traj.duration == pytest.approx(expected, rel=1e-14)


# ---- sampling against the reference ---------------------------------------------------------------


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("scalar_limits", [True, False])
def test_sample_matches_reference(rng, profile, scalar_limits):
    for _ in range(5):
        n = 6
        q0, qf = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
        qf[2] = q0[2]  # one axis that does not move
        vmax = 1.5 if scalar_limits else rng.uniform(0.2, 3, n)
        amax = 2.0 if scalar_limits else rng.uniform(0.2, 5, n)
        traj = sk.trajectory.point_to_point(q0, qf, vmax, amax, profile)
        T = traj.duration
        t = np.concatenate([[-1.0, 0.0, T, T + 1.0], rng.uniform(0, T, 200)])
        got = traj.sample(t)
        want = reference_rows(q0, qf, vmax, amax, profile, t)
        for g, w in zip(got, want):
            np.testing.assert_allclose(g, w, rtol=0, atol=1e-12)


@pytest.mark.parametrize("profile", PROFILES)
def test_finite_differences(rng, profile):
    q0, qf = rng.uniform(-2, 2, 4), rng.uniform(-2, 2, 4)
    traj = sk.trajectory.point_to_point(q0, qf, rng.uniform(0.5, 2, 4), rng.uniform(0.5, 2, 4), profile)
    T, h = traj.duration, 1e-6
    t = rng.uniform(0.01 * T, 0.99 * T, 500)
    _, qd, qdd = traj.sample(t)
    qp, qdp, _ = traj.sample(t + h)
    qm, qdm, _ = traj.sample(t - h)
    np.testing.assert_allclose((qp - qm) / (2 * h), qd, atol=1e-7)
    # the trapezoid's acceleration jumps at the ramp ends: skip samples within h of a switch
    switches = np.concatenate([traj.ramp_time, T - traj.ramp_time])
    far = (np.abs(t[:, None] - switches[None, :]) > 2 * h).all(axis=1)
    assert far.sum() > 400
    np.testing.assert_allclose(((qdp - qdm) / (2 * h))[far], qdd[far], atol=1e-6)


# ---- limits: respected on every axis, reached on the slowest --------------------------------------


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("bound", ["velocity", "acceleration"])
def test_limits_met_and_reached(rng, profile, bound):
    n = 5
    q0, qf = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
    vmax, amax = rng.uniform(0.5, 1.5, n), rng.uniform(0.5, 1.5, n)
    if bound == "velocity":
        amax = amax * 1e3
    else:
        vmax = vmax * 1e3
    traj = sk.trajectory.point_to_point(q0, qf, vmax, amax, profile)
    T = traj.duration
    # the peaks: velocity at T/2 (and on the cruise); acceleration at the ends (cubic, trapezoid)
    # or at tau = 1/2 -+ sqrt(3)/6 (quintic)
    peaks = T * np.array([0.5, 0.5 - math.sqrt(3) / 6, 0.5 + math.sqrt(3) / 6])
    t = np.concatenate([np.linspace(0, T, 200_001), peaks])
    _, qd, qdd = traj.sample(t)
    peak_v, peak_a = np.abs(qd).max(axis=0), np.abs(qdd).max(axis=0)
    assert (peak_v <= vmax * (1 + 1e-12)).all()
    assert (peak_a <= amax * (1 + 1e-12)).all()
    slow = int(np.argmax(np.abs(qf - q0) / (vmax if bound == "velocity" else np.sqrt(amax))))
    assert traj.axis_durations[slow] == T
    if bound == "velocity":
        assert peak_v[slow] == pytest.approx(vmax[slow], rel=1e-12)
    else:
        assert peak_a[slow] == pytest.approx(amax[slow], rel=1e-12)


def test_triangular_trapezoid():
    # D = 1 < vmax^2 / amax = 100: never cruises; t_f = 2 sqrt(D / a) = 2, peak speed sqrt(D a) = 1 at t = 1
    traj = sk.trajectory.point_to_point([0.0], [1.0], 10.0, 1.0, "trapezoid")
    assert traj.duration == pytest.approx(2.0, rel=1e-15)
    q, qd, qdd = traj.sample(np.array([0.5, 1.0, 1.5]))
    np.testing.assert_allclose(q[:, 0], [0.125, 0.5, 0.875], atol=1e-15)
    np.testing.assert_allclose(qd[:, 0], [0.5, 1.0, 0.5], atol=1e-15)
    np.testing.assert_allclose(qdd[[0, 2], 0], [1.0, -1.0], atol=1e-15)  # t = 1 is the switch


def test_trapezoid_with_cruise():
    # D = 10, vmax = 2, amax = 1: ramps of 2 s, t_f = 7, q(2) = 2, q(3.5) = 5
    traj = sk.trajectory.point_to_point([1.0], [11.0], 2.0, 1.0, "trapezoid")
    assert traj.duration == pytest.approx(7.0, rel=1e-15)
    q, qd, qdd = traj.sample(np.array([1.0, 2.0, 3.5, 6.0]))
    np.testing.assert_allclose(q[:, 0], [1.5, 3.0, 6.0, 10.5], atol=1e-14)
    np.testing.assert_allclose(qd[:, 0], [1.0, 2.0, 2.0, 1.0], atol=1e-14)
    np.testing.assert_allclose(qdd[:, 0], [1.0, 0.0, 0.0, -1.0], atol=1e-14)


@pytest.mark.parametrize("profile", PROFILES)
def test_boundary_conditions_and_synchronisation(rng, profile):
    q0, qf = rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)
    traj = sk.trajectory.point_to_point(q0, qf, rng.uniform(0.5, 2, 6), rng.uniform(0.5, 2, 6), profile)
    T = traj.duration
    assert T == traj.axis_durations.max()
    assert (traj.axis_durations < T).sum() == 5  # the other axes are stretched
    q, qd, qdd = traj.sample(np.array([0.0, T]))
    np.testing.assert_allclose(q[0], q0, atol=1e-15)
    np.testing.assert_allclose(q[1], qf, atol=1e-15)
    np.testing.assert_array_equal(qd, 0.0)
    if profile == "quintic":
        np.testing.assert_array_equal(qdd, 0.0)
    # every axis is still moving just before t_f, and has arrived at t_f: all end together
    _, qd_late, _ = traj.sample(T * (1 - 1e-3))
    assert (np.abs(qd_late) > 0).all()
    # outside [0, t_f]: at rest at the end states
    q, qd, qdd = traj.sample(np.array([-5.0, T + 5.0]))
    np.testing.assert_array_equal(q, [q0, qf])
    np.testing.assert_array_equal(qd, 0.0)
    np.testing.assert_array_equal(qdd, 0.0)


def test_stretched_trapezoid_axes_keep_their_acceleration(rng):
    q0, qf = np.zeros(3), np.array([4.0, 1.0, -0.5])
    traj = sk.trajectory.point_to_point(q0, qf, 1.0, 1.0, "trapezoid")
    assert traj.duration == pytest.approx(5.0, rel=1e-15)
    np.testing.assert_allclose(np.abs(traj.acceleration), 1.0)
    # axis j: v^2 - a t_f v + a |D_j| = 0: v^2 - 5 v + 1 = 0 and v^2 - 5 v + 0.5 = 0
    assert traj.cruise_velocity[1] == pytest.approx((5 - math.sqrt(21)) / 2, rel=1e-14)
    assert traj.cruise_velocity[2] == pytest.approx(-(5 - math.sqrt(23)) / 2, rel=1e-14)


def test_zero_length(recwarn):
    q0 = np.array([0.3, -1.0, 2.0])
    for profile in PROFILES:
        traj = sk.trajectory.point_to_point(q0, q0.copy(), 1.0, 1.0, profile)
        assert traj.duration == 0.0
        q, qd, qdd = traj.sample(np.array([-1.0, 0.0, 0.5, 1.0]))
        np.testing.assert_array_equal(q, np.broadcast_to(q0, (4, 3)))
        np.testing.assert_array_equal(qd, 0.0)
        np.testing.assert_array_equal(qdd, 0.0)
    assert len(recwarn) == 0


def test_one_moving_axis_among_still_ones():
    traj = sk.trajectory.point_to_point([0.0, 1.0], [1.0, 1.0], 1.0, 1.0, "trapezoid")
    q, qd, qdd = traj.sample(np.linspace(0, traj.duration, 11))
    assert np.isfinite(q).all()
    np.testing.assert_array_equal(q[:, 1], 1.0)
    np.testing.assert_array_equal(qd[:, 1], 0.0)
    np.testing.assert_array_equal(qdd[:, 1], 0.0)


# ---- bad input ------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["vmax", "amax"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf, [1.0, 0.0, 1.0]])
def test_bad_limits(name, value):
    kwargs = {"vmax": 1.0, "amax": 1.0, name: value}
    with pytest.raises(ValueError, match=name):
        sk.trajectory.point_to_point([0, 0, 0.0], [1, 1, 1.0], **kwargs)


@pytest.mark.parametrize("name", ["q0", "qf"])
def test_nan_positions(name):
    kwargs = {"q0": [0.0, 0.0], "qf": [1.0, 1.0], name: [0.0, math.nan]}
    with pytest.raises(ValueError, match=f"{name} must be finite"):
        sk.trajectory.point_to_point(vmax=1.0, amax=1.0, **kwargs)


def test_shape_mismatch():
    with pytest.raises(ValueError, match=r"qf must have the shape of q0, \(3,\), got \(2,\)"):
        sk.trajectory.point_to_point([0, 0, 0.0], [1, 1.0], 1.0, 1.0)
    with pytest.raises(ValueError, match=r"vmax must be a scalar or \(3,\), got shape \(2,\)"):
        sk.trajectory.point_to_point([0, 0, 0.0], [1, 1, 1.0], [1.0, 1.0], 1.0)
    with pytest.raises(ValueError, match=r"q0 must be \(n,\), got shape \(2, 2\)"):
        sk.trajectory.point_to_point(np.zeros((2, 2)), np.ones((2, 2)), 1.0, 1.0)
    with pytest.raises(ValueError, match="profile"):
        sk.trajectory.point_to_point([0.0], [1.0], 1.0, 1.0, "septic")
    traj = sk.trajectory.point_to_point([0.0], [1.0], 1.0, 1.0)
    with pytest.raises(TypeError, match="t must be a real numeric array"):
        traj.sample("soon")


# ---- batching, dtypes, layouts ---------------------------------------------------------------------


TRAJ6 = {p: sk.trajectory.point_to_point(np.zeros(6), np.linspace(-1, 2, 6), 1.0, 2.0, p) for p in PROFILES}


@given(
    shape=st.sampled_from(BATCH_SHAPES),
    dtype=st.sampled_from([np.float32, np.float64]),
    profile=st.sampled_from(PROFILES),
    seed=st.integers(0, 2**32 - 1),
)
def test_sample_batch_shapes_and_dtypes(shape, dtype, profile, seed):
    traj = TRAJ6[profile]
    t = np.random.default_rng(seed).uniform(-0.2, traj.duration + 0.2, shape).astype(dtype)
    got = traj.sample(t)
    want = reference_rows(traj.q0, traj.qf, 1.0, 2.0, profile, t.astype(np.float64))
    for g, w in zip(got, want):
        assert g.shape == (*shape, 6)
        assert g.dtype == dtype
        np.testing.assert_allclose(g, w, rtol=0, atol=TOLERANCE[dtype] * 10)


def test_sample_layouts_and_empty():
    traj = TRAJ6["quintic"]
    t = np.linspace(0, traj.duration, 24).reshape(4, 6)
    q_full = traj.sample(t)[0]
    np.testing.assert_array_equal(traj.sample(t.T)[0], q_full.transpose(1, 0, 2))
    np.testing.assert_array_equal(traj.sample(t[:, ::2])[0], q_full[:, ::2])
    ints = np.arange(3, dtype=np.int64)
    np.testing.assert_array_equal(traj.sample(ints)[0], traj.sample(ints * 1.0)[0])
    for shape in [(0,), (2, 0)]:
        q, qd, qdd = traj.sample(np.zeros(shape))
        assert q.shape == qd.shape == qdd.shape == (*shape, 6)
    assert traj.sample(0.5)[0].shape == (6,)


def test_nan_time_gives_nan_rows():
    traj = TRAJ6["trapezoid"]
    q, qd, qdd = traj.sample(np.array([0.5, math.nan, 1.0]))
    for a in (q, qd, qdd):
        assert np.isnan(a[1]).all()
        assert np.isfinite(a[[0, 2]]).all()


# ---- Cartesian paths ---------------------------------------------------------------------------------


def random_quaternion(rng) -> np.ndarray:
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def pose7(p, q) -> np.ndarray:
    return np.concatenate([p, q])


def test_linear_matches_reference(rng):
    for _ in range(10):
        p0, p1 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        q0, q1 = random_quaternion(rng), random_quaternion(rng)
        limits = dict(
            vmax=rng.uniform(0.2, 2),
            amax=rng.uniform(0.2, 2),
            wmax=rng.uniform(0.2, 2),
            alphamax=rng.uniform(0.2, 2),
        )
        path = sk.trajectory.linear(pose7(p0, q0), pose7(p1, q1), **limits)
        t = np.concatenate([[0.0, path.duration], rng.uniform(0, path.duration, 100)])
        T, twist = path.sample(t, twist=True)
        for i, ti in enumerate(t):
            p, q, v, w = ref.linear(p0, q0, p1, q1, t=ti, **limits)
            np.testing.assert_allclose(T[i, :3, 3], p, atol=1e-12)
            np.testing.assert_allclose(T[i, :3, :3], ref.quaternion_to_matrix(q), atol=1e-12)
            np.testing.assert_allclose(twist[i], np.concatenate([v, w]), atol=1e-12)
            np.testing.assert_array_equal(T[i, 3], [0, 0, 0, 1])


def test_linear_limits_and_slerp(rng):
    T0 = sk.transform(np.eye(3), [0.0, 0.0, 0.5])
    R1 = sk.rotation_z(0.8)[:3, :3] @ sk.rotation_x(0.3)[:3, :3]
    T1 = sk.transform(R1, [0.4, -0.2, 0.6])
    vmax, amax, wmax, alphamax = 0.3, 0.5, 2.0, 2.0
    path = sk.trajectory.linear(T0, T1, vmax, amax, wmax, alphamax)
    t = np.linspace(0, path.duration, 20_001)
    poses, twist = path.sample(t, form="quaternion", twist=True)
    np.testing.assert_allclose(np.linalg.norm(poses[:, 3:], axis=1), 1.0, atol=1e-15)
    speed, rate = np.linalg.norm(twist[:, :3], axis=1), np.linalg.norm(twist[:, 3:], axis=1)
    assert speed.max() <= vmax * (1 + 1e-12)
    assert rate.max() <= wmax * (1 + 1e-12)
    # here the translation is the tighter speed limit (L / vmax > theta / wmax): reached on the cruise
    L = np.linalg.norm(T1[:3, 3] - T0[:3, 3])
    angle = math.acos((np.trace(R1) - 1) / 2)
    assert L / vmax > angle / wmax
    assert speed.max() == pytest.approx(vmax, rel=1e-12)
    dt = t[1] - t[0]
    accel = np.linalg.norm(np.diff(twist[:, :3], axis=0), axis=1) / dt
    assert accel.max() <= amax * (1 + 1e-9)
    assert accel.max() == pytest.approx(amax, rel=1e-9)
    # the translation stays on the segment, the orientation turns about one fixed axis
    d = T1[:3, 3] - T0[:3, 3]
    rel = poses[:, :3] - T0[:3, 3]
    np.testing.assert_allclose(np.cross(rel, d), 0.0, atol=1e-15)
    cruise = speed > vmax * (1 - 1e-12)
    assert cruise.sum() > 1000
    w = twist[cruise, 3:]
    np.testing.assert_allclose(w, np.broadcast_to(w[0], w.shape), atol=1e-14)  # constant angular rate
    # equal time steps in the cruise turn by equal angles
    Ts = path.sample(t[cruise][::100])
    steps = [math.acos(min(1.0, (np.trace(A[:3, :3].T @ B[:3, :3]) - 1) / 2)) for A, B in zip(Ts, Ts[1:])]
    np.testing.assert_allclose(steps, steps[0], atol=1e-9)
    # endpoints exactly (at rest)
    ends, ends_twist = path.sample(np.array([0.0, path.duration]), twist=True)
    np.testing.assert_allclose(ends[0], T0, atol=1e-15)
    np.testing.assert_allclose(ends[1], T1, atol=1e-15)
    np.testing.assert_array_equal(ends_twist, 0.0)


def test_linear_triangular_and_angular_limit():
    # a pure rotation by 1 rad with wmax = 10, alphamax = 1: triangular, t_f = 2 sqrt(1 / 1) = 2
    T0 = sk.transform(np.eye(3), [0.0, 0.0, 0.5])
    T1 = sk.transform(sk.rotation_y(1.0)[:3, :3], [0.0, 0.0, 0.5])
    path = sk.trajectory.linear(T0, T1, vmax=1.0, amax=1.0, wmax=10.0, alphamax=1.0)
    assert path.duration == pytest.approx(2.0, rel=1e-14)
    _, twist = path.sample(np.array([0.5, 1.0, 1.5]), twist=True)
    np.testing.assert_allclose(twist[:, 4], [0.5, 1.0, 0.5], atol=1e-14)
    np.testing.assert_array_equal(twist[:, [0, 1, 2, 3, 5]], 0.0)


def test_linear_half_turn_axis_choice():
    T0 = np.eye(4)
    T1 = sk.transform(sk.rotation_x(math.pi)[:3, :3], [0.0, 0.0, 0.0])
    path = sk.trajectory.linear(T0, T1, vmax=1.0, amax=1.0, wmax=1.0, alphamax=1.0)
    T, twist = path.sample(np.array([path.duration / 2, path.duration]), twist=True)
    assert twist[0, 3] > 0 and np.allclose(twist[0, [4, 5]], 0)  # about +x, the documented choice
    np.testing.assert_allclose(T[1], T1, atol=1e-15)
    np.testing.assert_allclose(T[0][:3, :3], sk.rotation_x(math.pi / 2)[:3, :3], atol=1e-12)


def test_linear_zero_length_and_bad_input():
    T0 = sk.transform(np.eye(3), [0.1, 0.2, 0.5])
    path = sk.trajectory.linear(T0, T0, vmax=1.0, amax=1.0)
    assert path.duration == 0.0
    T, twist = path.sample(np.array([0.0, 1.0]), twist=True)
    np.testing.assert_allclose(T, np.broadcast_to(T0, (2, 4, 4)), atol=1e-15)
    np.testing.assert_array_equal(twist, 0.0)
    T1 = sk.transform(np.eye(3), [1.0, 0.2, 0.5])
    for kwargs, name in [({"vmax": 0.0}, "vmax"), ({"amax": -1.0}, "amax"), ({"vmax": math.nan}, "vmax")]:
        with pytest.raises(ValueError, match=name):
            sk.trajectory.linear(T0, T1, **{"vmax": 1.0, "amax": 1.0, **kwargs})
    with pytest.raises(ValueError, match="wmax and alphamax"):
        sk.trajectory.linear(T0, T1, vmax=1.0, amax=1.0, wmax=1.0)
    with pytest.raises(ValueError, match="T1 must be finite"):
        sk.trajectory.linear(T0, np.full((4, 4), math.nan), vmax=1.0, amax=1.0)
    with pytest.raises(ValueError, match=r"T0 must have shape \(4, 4\), \(7,\) or \(6,\), got \(3, 3\)"):
        sk.trajectory.linear(np.eye(3), T1, vmax=1.0, amax=1.0)
    with pytest.raises(ValueError, match="rigid transform"):
        sk.trajectory.linear(2 * np.eye(4), T1, vmax=1.0, amax=1.0)
    with pytest.raises(ValueError, match="pure rotation"):
        sk.trajectory.linear(T0, sk.transform(sk.rotation_z(1.0)[:3, :3], T0[:3, 3]), vmax=1.0, amax=1.0)
    with pytest.raises(ValueError, match="form"):
        path.sample(0.0, form="euler")


def waypoint_poses(rng, n=5):
    poses = []
    for i in range(n):
        p = np.array([0.1 * i, 0.05 * (-1) ** i, 0.5 + 0.02 * i]) + rng.uniform(-0.02, 0.02, 3)
        euler = rng.uniform(-0.15, 0.15, 3)
        poses.append(np.concatenate([p, euler]))
    return np.array(poses)


def test_via_points_matches_reference(rng):
    poses = waypoint_poses(rng)
    path = sk.trajectory.via_points(poses, vmax=0.2, amax=0.5, wmax=0.5, alphamax=2.0)
    mats = sk.body_transform(poses)
    t = np.concatenate([[0.0, path.duration], path.times, rng.uniform(0, path.duration, 300)])
    T, twist = path.sample(t, twist=True)
    for i, ti in enumerate(t):
        T_ref, twist_ref = ref.blended(
            path.times,
            path.blends,
            mats[:, :3, 3],
            mats[:, :3, :3],
            path.linear_velocity,
            path.angular_velocity,
            float(ti),
        )
        np.testing.assert_allclose(T[i], T_ref, atol=1e-12)
        np.testing.assert_allclose(twist[i], twist_ref, atol=1e-12)
    # segments run straight from waypoint to waypoint: d_k v_k = P_{k+1} - P_k, exp(d_k w_k) R_k = R_{k+1}
    d = np.diff(path.times)
    np.testing.assert_allclose(path.linear_velocity * d[:, None], np.diff(mats[:, :3, 3], axis=0), atol=1e-14)
    for k in range(len(d)):
        R_next = ref.rodrigues(path.angular_velocity[k] * d[k]) @ mats[k, :3, :3]
        np.testing.assert_allclose(R_next, mats[k + 1, :3, :3], atol=1e-13)


def test_via_points_blends(rng):
    poses = waypoint_poses(rng, 6)
    vmax, amax = 0.2, 0.5
    path = sk.trajectory.via_points(poses, vmax=vmax, amax=amax, blend=0.2)
    mats = sk.body_transform(poses)
    P = mats[:, :3, 3]
    t = np.linspace(0, path.duration, 200_001)
    T, twist = path.sample(t, twist=True)
    # ends exactly at the first and last poses, at rest
    np.testing.assert_allclose(T[0], mats[0], atol=1e-15)
    np.testing.assert_allclose(T[-1], mats[-1], atol=1e-15)
    np.testing.assert_array_equal(twist[[0, -1]], 0.0)
    # continuous velocity, and the acceleration (difference quotient) within amax
    dt = t[1] - t[0]
    accel = np.linalg.norm(np.diff(twist[:, :3], axis=0), axis=1) / dt
    assert accel.max() <= amax * (1 + 1e-9)
    assert np.linalg.norm(twist[:, :3], axis=1).max() <= vmax * (1 + 1e-12)
    v = np.vstack([np.zeros(3), path.linear_velocity, np.zeros(3)])
    for k in range(1, len(P) - 1):
        b, tk = path.blends[k], path.times[k]
        assert b >= 0.2
        inside = np.abs(t - tk) <= b / 2
        bound = max(np.linalg.norm(v[k]), np.linalg.norm(v[k + 1])) * b / 2
        assert np.linalg.norm(T[inside, :3, 3] - P[k], axis=1).max() <= bound * (1 + 1e-12)
        # near, not through: at t_k the path is at P_k + (v_k - v_{k-1}) b / 8
        at_k = path.sample(tk)[:3, 3]
        np.testing.assert_allclose(at_k, P[k] + (v[k + 1] - v[k]) * b / 8, atol=1e-14)
        # velocity entering and leaving the blend equals the segment velocities
        _, tw = path.sample(np.array([tk - b / 2, tk + b / 2]), twist=True)
        np.testing.assert_allclose(tw[:, :3], [v[k], v[k + 1]], atol=1e-14)
    # the whole path is time-consistent: finite differences of the pose give the twist
    h = 1e-6
    ts = rng.uniform(h, path.duration - h, 200)
    Tp, Tm = path.sample(ts + h), path.sample(ts - h)
    _, tw = path.sample(ts, twist=True)
    np.testing.assert_allclose((Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * h), tw[:, :3], atol=1e-8)
    dR = np.einsum("nij,nkj->nik", Tp[:, :3, :3] - Tm[:, :3, :3], path.sample(ts)[:, :3, :3]) / (2 * h)
    w_fd = np.stack([dR[:, 2, 1], dR[:, 0, 2], dR[:, 1, 0]], axis=1)
    np.testing.assert_allclose(w_fd, tw[:, 3:], atol=1e-7)


def test_via_points_bad_input(rng):
    poses = waypoint_poses(rng, 3)
    with pytest.raises(ValueError, match=r"poses must have shape .* got \(1, 6\)"):
        sk.trajectory.via_points(poses[:1], vmax=1.0, amax=1.0)
    with pytest.raises(ValueError, match="amax"):
        sk.trajectory.via_points(poses, vmax=1.0, amax=0.0)
    with pytest.raises(ValueError, match="blend"):
        sk.trajectory.via_points(poses, vmax=1.0, amax=1.0, blend=-1.0)
    bad = poses.copy()
    bad[1, 0] = math.nan
    with pytest.raises(ValueError, match=r"poses\[1\] must be finite"):
        sk.trajectory.via_points(bad, vmax=1.0, amax=1.0)
    # repeated waypoints are dropped, not divided by zero
    path = sk.trajectory.via_points(np.repeat(poses, 2, axis=0), vmax=1.0, amax=1.0)
    assert len(path.times) == 3


# ---- planning the blends: by hand, near the physical optimum, against the reference, at scale ----------


def test_via_points_plans_by_hand():
    # an L of two 10 m legs at vmax = amax = 1: every blend fits at the cruise bound, nothing slows down.
    # b_0 = b_2 = 1 (from / to rest), b_1 = |(0, 1) - (1, 0)| = sqrt(2); t_k = b_0 / 2 + 10 k
    corner = np.array([[0.0, 0, 0, 0, 0, 0], [10, 0, 0, 0, 0, 0], [10, 10, 0, 0, 0, 0]])
    path = sk.trajectory.via_points(corner, vmax=1.0, amax=1.0)
    np.testing.assert_allclose(path.times, [0.5, 10.5, 20.5], rtol=1e-15)
    np.testing.assert_allclose(path.blends, [1.0, math.sqrt(2), 1.0], rtol=1e-15)
    assert path.duration == pytest.approx(21.0, rel=1e-15)
    # out and back, 1 m each, vmax = 10, amax = 2: the reversal blend b_1 = 2 v / amax = v must fit in
    # d = 1 / v (half of each segment), so v^2 <= 1: v = 1, d = 1, b = [0.5, 1, 0.5], duration 2.5
    back = np.array([[0.0, 0, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]])
    path = sk.trajectory.via_points(back, vmax=10.0, amax=2.0)
    np.testing.assert_allclose(path.times, [0.25, 1.25, 2.25], rtol=1e-15)
    np.testing.assert_allclose(path.blends, [0.5, 1.0, 0.5], rtol=1e-15)
    np.testing.assert_allclose(path.linear_velocity, [[1, 0, 0], [-1, 0, 0]], rtol=1e-15)


@pytest.mark.parametrize("n", [3, 11, 1001])
def test_via_points_straight_line_near_the_trapezoid(n):
    # 10 m in a straight line, vmax = 1, amax = 0.5: no plan with continuous velocity and |a| <= amax
    # beats the trapezoid's 10 / 1 + 1 / 0.5 = 12 s; the blended plan stays within 2.5 % of it
    poses = np.zeros((n, 6))
    poses[:, 0] = np.linspace(0.0, 10.0, n)
    path = sk.trajectory.via_points(poses, vmax=1.0, amax=0.5)
    assert 12.0 * (1 - 1e-12) <= path.duration <= 12.0 * 1.025
    if n == 3:  # two 5 m segments at vmax, blends of 2 s from and to rest, none in the middle
        assert path.duration == pytest.approx(12.0, rel=1e-15)


def test_via_points_circle_speed():
    # a regular polygon on a circle of radius R: at equal speeds v a corner blend changes the velocity by
    # v L / R in b = v L / (R amax), which fits in d = L / v only if v^2 <= amax R (centripetal limit)
    R, amax = 1.0, 0.5
    s = np.linspace(0.0, 2 * np.pi, 2001)[:-1]
    poses = np.stack([R * np.cos(s), R * np.sin(s), 0 * s, 0 * s, 0 * s, 0 * s], axis=1)
    path = sk.trajectory.via_points(poses, vmax=10.0, amax=amax)
    speed = np.linalg.norm(path.linear_velocity, axis=1)
    assert speed.max() <= math.sqrt(amax * R) * (1 + 1e-9)
    assert speed.max() >= 0.99 * math.sqrt(amax * R)


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """log of a rotation matrix (angle < pi) as a rotation vector."""
    angle = math.acos(min(1.0, max(-1.0, (np.trace(R) - 1) / 2)))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2
    return axis if angle < 1e-12 else axis * angle / math.sin(angle)


PLAN_CASES = {
    "close waypoints": dict(spacing=0.01, vmax=1.0, amax=0.5, wmax=2.0, alphamax=1.0, blend=0.0),
    "minimum blend": dict(spacing=0.05, vmax=0.5, amax=2.0, wmax=None, alphamax=None, blend=0.3),
    "rotation bound": dict(spacing=0.2, vmax=2.0, amax=5.0, wmax=0.5, alphamax=0.2, blend=0.0),
    "uneven spacing": dict(spacing=None, vmax=1.0, amax=1.0, wmax=None, alphamax=None, blend=0.0),
}


@pytest.mark.parametrize("case", PLAN_CASES)
def test_via_points_plan_matches_reference(rng, case):
    c = PLAN_CASES[case]
    n = 40
    if c["spacing"] is None:  # nearly collinear, spacing from 1 mm to 1 m: long speed ramps
        lateral = rng.uniform(-1e-3, 1e-3, n - 1)
        steps = np.stack([10 ** rng.uniform(-3, 0, n - 1), lateral, np.zeros(n - 1)], 1)
        poses = np.concatenate([np.zeros((n, 3)), rng.uniform(-0.05, 0.05, (n, 3))], axis=1)
        poses[1:, :3] = np.cumsum(steps, axis=0)
    else:
        walk = np.cumsum(rng.uniform(-c["spacing"], c["spacing"], (n, 3)), axis=0)
        poses = np.concatenate([walk, rng.uniform(-0.3, 0.3, (n, 3))], axis=1)
    limits = {k: c[k] for k in ("vmax", "amax", "wmax", "alphamax", "blend")}
    path = sk.trajectory.via_points(poses, **limits)
    mats = sk.body_transform(poses)
    phis = [rotation_vector(B[:3, :3] @ A[:3, :3].T) for A, B in zip(mats, mats[1:])]
    wmax = c["wmax"] or math.inf
    alphamax = c["alphamax"] or math.inf
    d_ref, b_ref = ref.blend_plan(mats[:, :3, 3], phis, c["vmax"], c["amax"], wmax, alphamax, c["blend"])
    np.testing.assert_allclose(np.diff(path.times), d_ref, rtol=1e-9)
    np.testing.assert_allclose(path.blends, b_ref, rtol=1e-9, atol=1e-15)
    # the case exercises the planning: some segments are slowed below their cruise bound
    d_min = np.maximum(
        np.linalg.norm(np.diff(poses[:, :3], axis=0), axis=1) / c["vmax"], np.linalg.norm(phis, axis=1) / wmax
    )
    assert (d_ref > d_min * (1 + 1e-6)).sum() >= 3


def test_via_points_1e5_waypoints():
    rng = np.random.default_rng(5)
    n = 100_000
    s = np.linspace(0.0, 40 * np.pi, n)
    positions = np.stack([np.cos(s), np.sin(s), s / 50], axis=1) + rng.normal(0.0, 3e-4, (n, 3))
    euler = np.stack([0.1 * np.sin(s / 7), 0.1 * np.cos(s / 5), s / 20], axis=1)
    vmax, amax, wmax, alphamax = 1.0, 2.0, 1.0, 2.0
    start = time.perf_counter()
    path = sk.trajectory.via_points(np.concatenate([positions, euler], axis=1), vmax, amax, wmax, alphamax)
    assert time.perf_counter() - start < 5.0
    assert len(path.times) == n
    P = path.waypoints[:, :3, 3]
    d, b = np.diff(path.times), path.blends
    rounding = 8 * np.spacing(path.duration)  # of the times, hence of d = diff(times)
    # the blends fit in their segments; straight segments within the speed limits
    assert (d > 0).all()
    assert ((b[:-1] + b[1:]) / 2 <= d + rounding).all()
    speed = np.linalg.norm(path.linear_velocity, axis=1)
    np.testing.assert_allclose(
        path.linear_velocity * d[:, None], np.diff(P, axis=0), rtol=0, atol=1e-14 + speed.max() * rounding
    )
    assert np.linalg.norm(path.linear_velocity, axis=1).max() <= vmax * (1 + 1e-12)
    assert np.linalg.norm(path.angular_velocity, axis=1).max() <= wmax * (1 + 1e-12)
    # each blend is long enough for its velocity change: the acceleration bounds
    v = np.vstack([np.zeros(3), path.linear_velocity, np.zeros(3)])
    w = np.vstack([np.zeros(3), path.angular_velocity, np.zeros(3)])
    assert (np.linalg.norm(np.diff(v, axis=0), axis=1) <= amax * b * (1 + 1e-12)).all()
    assert (np.linalg.norm(np.diff(w, axis=0), axis=1) <= alphamax * b * (1 + 1e-12)).all()
    # sampled: the velocity is continuous across every blend start and end ...
    delta = 1e-9
    edges = np.concatenate([path.times - b / 2, path.times + b / 2])
    edges = edges[(edges > delta) & (edges < path.duration - delta)]
    _, before = path.sample(edges - delta, twist=True)
    _, after = path.sample(edges + delta, twist=True)
    assert np.abs(after - before).max() <= 1e-7
    # ... the linear acceleration inside a blend (a difference quotient over its middle half) within amax
    inner = b > 1e-6
    _, early = path.sample(path.times[inner] - b[inner] / 4, twist=True)
    _, late = path.sample(path.times[inner] + b[inner] / 4, twist=True)
    accel = np.linalg.norm(late[:, :3] - early[:, :3], axis=1) / (b[inner] / 2)
    assert accel.max() <= amax * (1 + 1e-6)
    # ... and the path passes within max(|v_{k-1}|, |v_k|) b_k / 2 of every waypoint
    at_waypoints = path.sample(path.times)[:, :3, 3]
    speed = np.linalg.norm(v, axis=1)
    reach = np.maximum(speed[:-1], speed[1:]) * b / 2
    assert (reach > 0).all()
    assert (np.linalg.norm(at_waypoints - P, axis=1) <= reach * (1 + 1e-9) + 1e-12).all()


@given(
    shape=st.sampled_from(BATCH_SHAPES),
    dtype=st.sampled_from([np.float32, np.float64]),
    form=st.sampled_from(["matrix", "quaternion"]),
)
def test_path_sample_batch_shapes_and_dtypes(shape, dtype, form):
    path = PATH
    t = np.random.default_rng(len(shape)).uniform(-0.1, path.duration + 0.1, shape).astype(dtype)
    poses, twist = path.sample(t, form=form, twist=True)
    assert poses.shape == (*shape, *((4, 4) if form == "matrix" else (7,)))
    assert twist.shape == (*shape, 6)
    assert poses.dtype == twist.dtype == dtype
    want, want_twist = path.sample(t.astype(np.float64), form=form, twist=True)
    np.testing.assert_allclose(poses, want, atol=TOLERANCE[dtype])
    np.testing.assert_allclose(twist, want_twist, atol=TOLERANCE[dtype])


PATH = sk.trajectory.via_points(
    waypoint_poses(np.random.default_rng(1), 4), vmax=0.3, amax=1.0, wmax=1.0, alphamax=3.0
)


def test_path_nan_and_empty_times():
    poses = PATH.sample(np.array([0.1, math.nan]), form="quaternion")
    assert np.isnan(poses[1]).all() and np.isfinite(poses[0]).all()
    assert PATH.sample(np.zeros((0, 3))).shape == (0, 3, 4, 4)
    # a long batch (blocks of samples inside) mixing NaN, clamped, blend and segment times, against one
    # time at a time
    t = np.linspace(-0.5, PATH.duration + 0.5, 203)
    t[[0, 63, 64, 130]] = math.nan
    for form in ("matrix", "quaternion"):
        batch, twist = PATH.sample(t, form=form, twist=True)
        for i, ti in enumerate(t):
            one, one_twist = PATH.sample(ti, form=form, twist=True)
            np.testing.assert_array_equal(batch[i], one)
            np.testing.assert_array_equal(twist[i], one_twist)


# ---- through the whole-body IK ------------------------------------------------------------------


@pytest.mark.parametrize("form", ["matrix", "quaternion"])
def test_body_ik_round_trip(rng, form):
    spot = sk.Spot()
    feet = spot.stance_feet(height=0.5)
    poses = np.array(
        [
            [0.0, 0.0, 0.5, 0.0, 0.0, 0.0],
            [0.05, 0.02, 0.45, 0.05, -0.1, 0.2],
            [-0.03, 0.04, 0.52, -0.08, 0.05, -0.1],
        ]
    )
    for path in (
        sk.trajectory.linear(poses[0], poses[1], vmax=0.2, amax=0.5, wmax=0.5, alphamax=1.0),
        sk.trajectory.via_points(poses, vmax=0.2, amax=0.5, wmax=0.5, alphamax=1.0),
    ):
        t = np.linspace(0, path.duration, 101).reshape(1, 101)
        body = path.sample(t, form=form)
        res = spot.body_ik(body, feet)
        assert res.q.shape == (1, 101, 12)
        assert (np.asarray(res.status) == 0).all()
        feet_back = spot.body_fk(body, res.q)
        np.testing.assert_allclose(feet_back, np.broadcast_to(feet, (1, 101, 4, 3)), atol=1e-9)


# -- holding an IK branch along a path ---------------------------------------------------------------------


def test_hold_branch_reports_the_wrist_flip():
    arm = sk.Spot().arm
    t = np.linspace(-1.0, 1.0, 201)
    q = np.tile([0.2, -1.0, 1.6, 0.3, 0.0, 0.5], (len(t), 1))
    q[:, 4] = 0.4 * t  # wr0 crosses 0: a wrist singularity
    sol = arm.ik_all(arm.fk(q))
    branch = int(np.argmin(np.abs(sol.q[0] - q[0]).max(axis=-1)))
    held = sk.trajectory.hold_branch(sol.q, sol.valid, branch)
    assert len(held.jumps) >= 1  # the held slot flips the wrist where wr0 changes sign
    k = held.jumps[0]
    assert abs(t[k]) < 0.05  # at the crossing (the slot may vanish exactly there, or jump)
    later = k + 10
    assert not np.allclose(held.q[later], q[later], atol=0.1)  # the slot now holds the flipped wrist
    assert held.ok[:k].all() and not held.ok[k:].any()
    np.testing.assert_allclose(held.q[:k], q[:k], atol=1e-9)  # before the jump: the generating path


def test_hold_branch_continuous_path_and_bad_input():
    leg = sk.Spot().leg("fl")
    t = np.linspace(0.0, 1.0, 101)
    q = np.stack([0.1 * t, 0.9 + 0.2 * t, -1.6 - 0.2 * t], -1)
    sol = leg.ik_all(leg.fk(q))
    held = sk.trajectory.hold_branch(sol.q, sol.valid, 0)
    assert held.ok.all() and len(held.jumps) == 0
    np.testing.assert_allclose(held.q, q, atol=1e-12)
    valid = sol.valid.copy()
    valid[50, 0] = False  # the branch vanishes for one sample: reported, and the rest is not ok
    held = sk.trajectory.hold_branch(sol.q, valid, 0)
    assert held.jumps.tolist() == [50, 51] and held.ok[:50].all() and not held.ok[50:].any()
    with pytest.raises(ValueError, match="branch"):
        sk.trajectory.hold_branch(sol.q, sol.valid, 4)
    with pytest.raises(ValueError, match="max_step"):
        sk.trajectory.hold_branch(sol.q, sol.valid, 0, max_step=0.0)
    with pytest.raises(ValueError, match="q_slots"):
        sk.trajectory.hold_branch(sol.q[0], sol.valid, 0)
