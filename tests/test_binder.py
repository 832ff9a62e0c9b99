"""The one boundary (cpp/bindings/binder.hpp): out=, broadcasting without copies, NaN rows,
aliasing, and bit-identical results for any thread count, on the calls that go through it
(the legs' kinematics and IK, the fixed-base dynamics)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import spotkin as sk

SPOT = sk.Spot()
LEG = SPOT.leg("fl")
RNG = np.random.default_rng(7)


@pytest.fixture(scope="module")
def arm():
    return sk.Robot.from_urdf(sk.robots.path("spot_with_arm")).arm


def leg_q(shape):
    lo, hi = LEG.limits[:, 0], LEG.limits[:, 1]
    return lo + (hi - lo) * RNG.uniform(0.1, 0.9, (*shape, 3))


def arm_q(arm, shape):
    return RNG.uniform(-1, 1, (*shape, arm.dof))


# ---- out= ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("shape", [(), (1,), (5,), (3, 1, 2)])
def test_out_is_filled_and_returned(shape, dtype):
    q = leg_q(shape).astype(dtype)
    want = LEG.fk(q)
    out = np.full((*shape, 3), -7.0, dtype)
    got = LEG.fk(q, out=out)
    assert got is out
    np.testing.assert_array_equal(out, want)
    J = np.empty((*shape, 3, 3), dtype)
    assert LEG.jacobian(q, out=J) is J
    np.testing.assert_array_equal(J, LEG.jacobian(q))


def test_ik_out_takes_a_tuple_with_none_entries():
    q = leg_q((6,))
    p = LEG.fk(q)
    want_q, want_status = LEG.ik(p, q)
    q_out = np.empty((6, 3))
    got_q, got_status = LEG.ik(p, q, out=(q_out, None))
    assert got_q is q_out
    np.testing.assert_array_equal(got_q, want_q)
    np.testing.assert_array_equal(got_status, want_status)
    status_out = np.empty(6, np.int8)
    _, got_status = LEG.ik(p, q, out=(None, status_out))
    assert got_status is status_out
    np.testing.assert_array_equal(status_out, want_status)
    # a single target: its status is a Status unless an array is given for it
    _, status1 = LEG.ik(p[0], out=(np.empty(3), None))
    assert isinstance(status1, sk.Status)
    s0 = np.empty((), np.int8)
    _, status0 = LEG.ik(p[0], out=(None, s0))
    assert status0 is s0 and int(s0) == int(status1)


def test_ik_all_out(arm):
    p = LEG.fk(leg_q((4,)))
    outs = (np.empty((4, 4, 3)), np.empty((4, 4), bool), np.empty((4, 4), bool), np.empty(4, np.int8))
    got = LEG.ik_all(p, out=outs)
    want = LEG.ik_all(p)
    for g, o, w in zip(got, outs, want):
        assert g is o
        np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize(
    "out, error, match",
    [
        (np.empty((5, 3), np.float32), TypeError, r"out\[0\] \(p\) must have dtype float64, got float32"),
        (np.empty((5, 4)), ValueError, r"out\[0\] \(p\) must have shape \(5, 3\), got \(5, 4\)"),
        (np.empty((3, 5)).T, ValueError, r"C-contiguous"),
        ([[0.0] * 3] * 5, TypeError, r"out\[0\] \(p\) must be a NumPy array, got list"),
        (np.ma.zeros((5, 3)), TypeError, r"must be a NumPy array"),
    ],
)
def test_out_errors_name_the_output(out, error, match):
    with pytest.raises(error, match=match):
        LEG.fk(leg_q((5,)), out=out)


def test_out_must_be_writeable_and_counted():
    out = np.empty((5, 3))
    out.flags.writeable = False
    with pytest.raises(ValueError, match="writeable"):
        LEG.fk(leg_q((5,)), out=out)
    with pytest.raises(ValueError, match="out must hold 2 arrays"):
        LEG.ik(LEG.fk(leg_q((5,))), out=(np.empty((5, 3)),))
    with pytest.raises(TypeError, match="out must be a tuple of 2 arrays"):
        LEG.ik(LEG.fk(leg_q((5,))), out=np.empty((5, 3)))


def test_out_may_alias_the_input():
    """An input that shares memory with an output is read from a copy (as NumPy's ufuncs do)."""
    q = leg_q((700,))  # more than one block of 512
    want = LEG.fk(q)
    got = LEG.fk(q, out=q)
    assert got is q
    np.testing.assert_array_equal(q, want)


def test_dynamics_out(arm):
    q, qd, qdd = (arm_q(arm, (9,)) for _ in range(3))
    tau = np.empty((9, arm.dof))
    assert arm.inverse_dynamics(q, qd, qdd, out=tau) is tau
    np.testing.assert_array_equal(tau, arm.inverse_dynamics(q, qd, qdd))
    n = arm.dof
    packed = np.empty((9, n * (n + 1) // 2))
    assert arm.mass_matrix(q, layout="packed", out=packed) is packed
    np.testing.assert_array_equal(packed, arm.mass_matrix(q, layout="packed"))
    with pytest.raises(ValueError, match=r"out\[0\] \(A\) must have shape \(9, 6, 6\)"):
        arm.mass_matrix(q, out=packed)
    g = np.empty(n, np.float32)
    assert arm.gravity(q[0].astype(np.float32), out=g) is g


# ---- broadcasting ------------------------------------------------------------------------------------


def test_partial_broadcast_equals_the_explicit_one(arm):
    """(3, 1) against (1, 4) leading shapes: gathered block by block, never materialised."""
    q = arm_q(arm, (3, 1))
    qd = arm_q(arm, (1, 4))
    qdd = arm_q(arm, (4,))
    got = arm.inverse_dynamics(q, qd, qdd)
    full = [np.broadcast_to(x, (3, 4, arm.dof)).copy() for x in (q, qd, qdd)]
    np.testing.assert_array_equal(got, arm.inverse_dynamics(*full))
    assert got.shape == (3, 4, arm.dof)


def test_seed_broadcasts_against_the_targets():
    q = leg_q((4, 5))
    p = LEG.fk(q)
    seed = leg_q((5,))
    got = LEG.ik(p, seed)
    want = LEG.ik(p, np.broadcast_to(seed, (4, 5, 3)).copy())
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    with pytest.raises(ValueError, match=r"p \(4, 5, 3\) and seed \(3, 3\) do not broadcast"):
        LEG.ik(p, leg_q((3,)))


@pytest.mark.parametrize("n", [1, 600, 5000])
def test_shared_row_broadcasts_over_large_batches(arm, n):
    """One seed or gravity for every sample (stride 0), across block and thread boundaries."""
    q = arm_q(arm, (n,))
    g = np.array([0.3, -0.2, -9.7])
    np.testing.assert_array_equal(arm.gravity(q, g), arm.gravity(q, np.tile(g, (n, 1))))
    p = LEG.fk(leg_q((n,)))
    seed = leg_q(())
    np.testing.assert_array_equal(LEG.ik(p, seed)[0], LEG.ik(p, np.tile(seed, (n, 1)))[0])


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_broadcast_views_are_read_as_broadcasts(arm, dtype):
    """An argument that is itself a broadcast view (np.broadcast_to: leading strides 0) is read row
    by row as a broadcast, never copied whole, with the bits of its materialised copy: fully and
    partly repeated, beside arguments that are not, with NaN and huge angles in a repeated row, in
    batches across block and thread boundaries."""
    q = arm_q(arm, (3, 1)).astype(dtype)
    views = [np.broadcast_to(q, (3, 700, arm.dof)), np.broadcast_to(q[0, 0], (2100, arm.dof))]
    for view in views:
        assert 0 in view.strides
        np.testing.assert_array_equal(arm.gravity(view), arm.gravity(view.copy()))
        np.testing.assert_array_equal(arm.fk(view), arm.fk(view.copy()))
    qd = arm_q(arm, (700,)).astype(dtype)
    view = views[0]
    want = arm.inverse_dynamics(view.copy(), qd, qd)
    np.testing.assert_array_equal(arm.inverse_dynamics(view, qd, qd), want)
    row = leg_q((2,)).astype(dtype)
    row[1, 0] = np.nan
    bad = np.broadcast_to(row[:, None], (2, 600, 3))
    p = LEG.fk(bad)
    np.testing.assert_array_equal(p, LEG.fk(bad.copy()))
    assert np.isnan(p[1]).all() and np.isfinite(p[0]).all()
    if dtype == np.float64:
        seed = leg_q(()) + np.array([2e6 * np.pi, 0.0, 0.0])  # huge, an exact multiple of 2 pi away
        targets = LEG.fk(leg_q((600,)))
        seeds = np.broadcast_to(seed, (600, 3))
        np.testing.assert_array_equal(LEG.ik(targets, seeds)[0], LEG.ik(targets, seeds.copy())[0])
    poses = np.broadcast_to(np.array([0.0, 0.0, 0.5, 0.02, -0.03, 0.1], dtype), (5, 400, 6))
    feet = SPOT.stance_feet(0.5).astype(dtype)
    got, want = SPOT.body_ik(poses, feet), SPOT.body_ik(poses.copy(), feet)
    np.testing.assert_array_equal(got.q, want.q)
    np.testing.assert_array_equal(got.status, want.status)
    assert got.q.dtype == dtype and got.q.shape == (5, 400, 12)


def test_a_broadcast_view_costs_no_copy_of_itself():
    """Two million poses as one broadcast row: the peak memory grows by the outputs, not by a
    96 MB copy of the poses (as it did)."""
    code = """
        import resource
        import numpy as np
        import spotkin as sk
        go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
        go2.center_of_mass(np.array([0, 0, 0.3, 0, 0, 0.0]), np.zeros(12))
        out = np.empty((2_000_000, 3))
        out[:] = 0.0  # the output's pages, touched before the baseline
        pose = np.broadcast_to(np.array([0, 0, 0.3, 0.1, 0, 0]), (2_000_000, 6))
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        go2.center_of_mass(pose, np.zeros(12), out=out)
        print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024)
    """
    result = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert float(result.stdout) < 40.0  # MB; a copy of the poses is 96 MB


# ---- NaN rows and huge angles --------------------------------------------------------------------------


def test_nan_rows_and_huge_angles_in_a_shared_row():
    p = LEG.fk(leg_q((700,)))
    seed = leg_q(())
    huge = seed + np.array([2e6 * np.pi, 0.0, 0.0])  # an exact multiple of 2 pi away (beyond the limit)
    np.testing.assert_array_equal(LEG.ik(p, huge)[0], LEG.ik(p, seed)[0])
    q = leg_q((700,))
    q[3, 1] = np.nan
    q[600, 2] = np.inf
    p = LEG.fk(q)
    assert np.isnan(p[3]).all() and np.isnan(p[600]).all()
    assert np.isfinite(np.delete(p, [3, 600], axis=0)).all()


# ---- threads --------------------------------------------------------------------------------------------


def test_bit_identical_for_any_thread_count(arm):
    q = arm_q(arm, (40, 1))
    qd = arm_q(arm, (1, 500))
    p = LEG.fk(leg_q((20_000,)))
    seed = leg_q((20_000,))
    threads = sk.get_num_threads()
    try:
        results = []
        for t in (1, 2, 3):
            sk.set_num_threads(t)
            results.append((arm.nonlinear_effects(q, qd), LEG.ik(p, seed)[0], arm.mass_matrix(q[:, 0])))
    finally:
        sk.set_num_threads(threads)
    for r in results[1:]:
        for a, b in zip(results[0], r):
            np.testing.assert_array_equal(a, b)


def test_floating_base_out_and_broadcast():
    robot = sk.Robot.from_urdf(sk.robots.path("go2"))
    fb = robot.floating_base if hasattr(robot, "floating_base") else None
    if fb is None:
        pytest.skip("no floating base on this robot")
    q = np.zeros((5, fb.nq))
    q[:, 6] = 1.0
    q[:, 7:] = RNG.uniform(-0.5, 0.5, (5, fb.nq - 7))
    A = np.empty((5, fb.nv, fb.nv))
    assert fb.mass_matrix(q, out=A) is A
    np.testing.assert_array_equal(A, fb.mass_matrix(q))
    g = np.empty((5, fb.nv))
    assert fb.gravity(q, out=g) is g
    # one gravity vector per sample, broadcast against one configuration
    gravities = np.array([[0.0, 0.0, -9.81], [0.0, 0.5, -9.7]])
    tau = fb.gravity(q[0], gravities)
    assert tau.shape == (2, fb.nv)
    np.testing.assert_array_equal(tau[1], fb.gravity(q[0], gravities[1]))


# ---- one sample: the fast path ----------------------------------------------------------------------


def test_one_sample_answers_the_bits_of_its_batch_row(arm):
    """A lone sample (the fast path: the caller's memory, inline) gives its row of a batch bit for bit,
    for kinematics, IK, the body, the dynamics, the statics and the pose transform."""
    q = leg_q((6,))
    p = LEG.fk(q)
    qa = arm_q(arm, (6,))
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    feet = go2.stance_feet(0.3)
    poses = np.array([0.01, -0.01, 0.29, 0.03, -0.04, 0.05]) + RNG.normal(0, 0.01, (6, 6))
    q12 = go2.body_ik(poses, feet).q
    calls = {
        "leg.fk": lambda s: LEG.fk(q[s]),
        "leg.ik": lambda s: LEG.ik(p[s])[0],
        "leg.ik seeded": lambda s: LEG.ik(p[s], q[s])[0],
        "leg.ik_all": lambda s: LEG.ik_all(p[s]).q,
        "arm.fk": lambda s: arm.fk(qa[s]),
        "arm.jacobian": lambda s: arm.jacobian(qa[s]),
        "arm.gravity": lambda s: arm.gravity(qa[s]),
        "arm.rnea": lambda s: arm.inverse_dynamics(qa[s], qa[s], qa[s]),
        "arm.mass_matrix": lambda s: arm.mass_matrix(qa[s]),
        "body_ik": lambda s: go2.body_ik(poses[s], feet).q,
        "body_ik seeded": lambda s: go2.body_ik(poses[s], feet, q12[s]).q,
        "body_jacobian": lambda s: go2.body_jacobian(poses[s], q12[s]),
        "standing_torques": lambda s: go2.standing_torques(poses[s], q12[s]).tau,
        "center_of_mass": lambda s: go2.center_of_mass(poses[s], q12[s]),
        "body_transform": lambda s: sk.body_transform(poses[s]),
    }
    for name, call in calls.items():
        batch = call(slice(None))
        for k in (0, 3, 5):
            assert np.array_equal(call(k), batch[k], equal_nan=True), (name, k)


def test_one_sample_from_lists_and_tuples_equals_arrays(arm):
    """Short lists of Python numbers take the fast path as float64, with the bits of a float64 array."""
    q = [0.1, 0.9, -1.5]
    assert np.array_equal(LEG.fk(q), LEG.fk(np.array(q)))
    assert np.array_equal(LEG.fk((0, 1, -2)), LEG.fk(np.array([0.0, 1.0, -2.0])))  # ints, as NumPy reads them
    qa = [0.1, -0.5, 0.7, 0.2, 0.3, -0.1]
    g = [0.0, 0.0, -9.81]
    assert np.array_equal(arm.gravity(qa, g), arm.gravity(np.array(qa), np.array(g)))
    assert (
        LEG.fk(q).dtype == np.float64 and LEG.fk([True, False, True]).dtype == np.float64
    )  # bools: as NumPy


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_one_sample_keeps_the_dtype_rules(arm, dtype):
    """float32 only when every primary argument is; a parameter of the other dtype (gravity, a seed)
    takes the working one, as in a batch."""
    qa = arm_q(arm, ()).astype(dtype)
    g64 = np.array([0.0, 0.0, -9.81])
    assert arm.gravity(qa, g64).dtype == dtype
    assert arm.gravity(qa, g64.astype(np.float32)).dtype == dtype
    batch = arm.gravity(np.stack([qa, qa]), g64.astype(np.float32))
    assert np.array_equal(arm.gravity(qa, g64.astype(np.float32)), batch[0])
    p = LEG.fk(leg_q(()).astype(dtype))
    seed = leg_q(()).astype(np.float32 if dtype == np.float64 else np.float64)
    assert LEG.ik(p, seed)[0].dtype == dtype
    mixed = LEG.fk(np.stack([leg_q(()).astype(np.float32)]))  # shape (1, 3): a batch, not the fast path
    assert mixed.dtype == np.float32


def test_one_sample_unusual_values_take_the_general_path():
    """NaN, Inf and huge angles in a lone sample: the same answers as in a batch (the general path)."""
    q = np.array([[0.1, 0.9, 1e7], [np.nan, 0.9, -1.5], [0.1, np.inf, -1.5], [0.1, 0.9, -1.5]])
    batch = LEG.fk(q)
    for k in range(len(q)):
        assert np.array_equal(LEG.fk(q[k]), batch[k], equal_nan=True), k
    assert np.isnan(LEG.fk(q[1])).all() and np.isfinite(LEG.fk(q[0])).all()


def test_one_sample_out_overlapping_its_input_is_read_first():
    q = np.array([0.1, 0.9, -1.5])
    want = LEG.fk(q)
    assert np.array_equal(LEG.fk(q, out=q), want) and np.array_equal(q, want)  # written in place, read first
    buffer = np.zeros(6)
    buffer[:3] = [0.1, 0.9, -1.5]
    LEG.fk(buffer[:3], out=buffer[3:])
    assert np.array_equal(buffer[3:], want)
    with pytest.raises(ValueError, match="out must hold 1"):
        LEG.fk(q, out=(np.empty(3), np.empty(3)))
    with pytest.raises(TypeError, match=r"out\[0\] \(p\) must have dtype float64"):
        LEG.fk(np.array([0.1, 0.9, -1.5]), out=np.empty(3, np.float32))


# A single sample's outputs come from a pool of spare arrays (binder.cpp, SparePool): an array is
# handed out again only when nothing else refers to it. These check that a result anyone can still
# reach is never written by a later call.
def _spot_and_stance():
    robot = sk.Spot()
    feet = robot.stance_feet(0.5)
    return robot, feet


def test_a_held_result_is_never_overwritten_by_later_calls():
    robot, feet = _spot_and_stance()
    poses = [np.array([0.0, 0.0, 0.5, 0.02 * k, -0.01 * k, 0.03 * k]) for k in range(6)]
    held = [robot.body_ik(p, feet) for p in poses]  # each kept: none may be reused
    copies = [(r.q.copy(), r.status.copy()) for r in held]
    for p in poses[::-1]:
        robot.body_ik(p, feet)  # dropped at once: free to reuse
    for p in poses:
        robot.body_ik(p, feet)
    for r, (q, status) in zip(held, copies):
        np.testing.assert_array_equal(r.q, q)
        np.testing.assert_array_equal(r.status, status)
    assert len({id(r.q) for r in held}) == len(held)


def test_what_still_refers_to_a_result_keeps_it():
    import weakref

    robot, feet = _spot_and_stance()
    a = np.array([0.0, 0.0, 0.5, 0.05, 0.0, 0.0])
    b = np.array([0.0, 0.0, 0.5, -0.05, 0.0, 0.0])
    q_a = robot.body_ik(a, feet).q
    expected = q_a.copy()
    view = q_a[2:5]  # a view (its base is the result)
    memory = memoryview(robot.body_ik(a, feet).q)  # an exported buffer
    weak_target = robot.body_ik(a, feet).q
    weak = weakref.ref(weak_target)
    del q_a, weak_target
    for _ in range(40):
        robot.body_ik(b, feet)
    np.testing.assert_array_equal(view, expected[2:5])
    np.testing.assert_array_equal(np.asarray(memory), expected)
    alive = weak()  # let go by the pool (as it would be without one), or alive and never rewritten
    assert alive is None or np.array_equal(alive, expected)


def test_a_result_changed_before_it_was_dropped_is_not_handed_out_changed():
    robot, feet = _spot_and_stance()
    pose = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    for change in ("shape", "readonly", "strides"):
        for _ in range(3):
            q = robot.body_ik(pose, feet).q
            if change == "shape":
                q.shape = (4, 3)
            elif change == "readonly":
                q.flags.writeable = False
            else:
                with warnings.catch_warnings():  # deprecated in NumPy 2.4, still possible
                    warnings.simplefilter("ignore", DeprecationWarning)
                    q.strides = (0,)
            del q
            fresh = robot.body_ik(pose, feet)
            assert fresh.q.shape == (12,) and fresh.q.strides == (8,) and fresh.q.flags.writeable
            assert fresh.q.flags.c_contiguous and fresh.q.flags.owndata and fresh.q.base is None
            np.testing.assert_array_equal(fresh.q, robot.body_ik(pose, feet).q)


def test_reused_outputs_answer_as_new_ones():
    robot, feet = _spot_and_stance()
    rng = np.random.default_rng(7)
    poses = np.concatenate(
        [rng.uniform(-0.03, 0.03, (50, 3)) + [0, 0, 0.5], rng.uniform(-0.2, 0.2, (50, 3))], axis=1
    )
    batch = robot.body_ik(poses, feet)
    for k in range(len(poses)):  # each call's arrays those the last call dropped
        one = robot.body_ik(poses[k], feet)
        np.testing.assert_array_equal(one.q, batch.q[k])
        np.testing.assert_array_equal(one.status, batch.status[k])
        assert one.q.dtype == np.float64 and one.status.dtype == np.int8
    pose32 = poses[0].astype(np.float32)
    one32 = robot.body_ik(pose32, feet.astype(np.float32))
    assert one32.q.dtype == np.float32  # float32 spares apart from float64 ones of the same shape
    assert robot.body_ik(poses[0], feet).q.dtype == np.float64
