"""Hostile input at the C++ boundary: thread settings, Ctrl-C, NaN isolation, invalid
transforms, masked and big-endian arrays, allocation failures, huge angles, IK fallbacks.

Each test reproduces a defect a hostile-input audit found; see also tests/test_fuzz.py.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import spotkin as sk
from spotkin import _core
from spotkin.reference import leg as leg_reference

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

SPOT = sk.Spot()
LEG = SPOT.leg("fl")


def run_python(code: str, env: dict | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    full_env = {**os.environ, **(env or {})}
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        env=full_env,
        timeout=timeout,
    )


# -- threads --------------------------------------------------------------------------------------


@pytest.fixture
def restore_threads():
    before = sk.get_num_threads()
    yield
    sk.set_num_threads(before)


@pytest.mark.parametrize("bad", [True, False, "2", 1.5, 2.0, None, [2]])
def test_set_num_threads_rejects_non_integers(bad, restore_threads):
    with pytest.raises(TypeError, match="n must be an integer"):
        sk.set_num_threads(bad)
    with pytest.raises(TypeError, match="n must be an integer"):
        _core.set_num_threads(bad)  # the C++ entry point checks the same


@pytest.mark.parametrize("bad", [0, -3, 10**9, 10**30, _core.MAX_THREADS + 1])
def test_set_num_threads_range(bad, restore_threads):
    with pytest.raises(ValueError, match=r"\[1, 1024\]"):
        sk.set_num_threads(bad)
    with pytest.raises(ValueError):
        _core.set_num_threads(bad)


def test_set_num_threads_accepts_integers(restore_threads):
    sk.set_num_threads(np.int64(2))
    assert sk.get_num_threads() == 2
    sk.set_num_threads(_core.MAX_THREADS)
    assert sk.get_num_threads() == _core.MAX_THREADS == 1024


def test_many_threads_do_not_abort(restore_threads):
    """The audit's abort: 10**9 threads asked, then a large batch. Now capped, and a batch
    with 1024 threads asked gives the single-thread result."""
    q = np.random.default_rng(0).uniform(-2, 2, size=(200_000, 3))
    sk.set_num_threads(1)
    expected = LEG.fk(q)
    sk.set_num_threads(1024)
    np.testing.assert_array_equal(LEG.fk(q), expected)


def test_thread_limit_holds_for_this_thread_only(restore_threads):
    import threading

    sk.set_num_threads(8)
    q = np.random.default_rng(1).uniform(-2, 2, size=(300_000, 3))
    expected = LEG.fk(q)
    seen = {}

    def other():
        seen["other"] = sk.get_num_threads()

    with sk.thread_limit(1):
        assert sk.get_num_threads() == _core.get_num_threads() == 1  # what the kernels read
        np.testing.assert_array_equal(LEG.fk(q), expected)  # bit-identical
        thread = threading.Thread(target=other)
        thread.start()
        thread.join()
        with sk.thread_limit(3):  # nested: the inner limit holds inside
            assert sk.get_num_threads() == 3
        assert sk.get_num_threads() == 1
        sk.set_num_threads(2)  # the setting stays the upper bound
        assert sk.get_num_threads() == 1
    assert seen["other"] == 8 and sk.get_num_threads() == 2
    with sk.thread_limit(64):  # above the setting: the setting
        assert sk.get_num_threads() == 2
    with pytest.raises(RuntimeError), sk.thread_limit(1):
        raise RuntimeError  # the limit is lifted on the way out
    assert sk.get_num_threads() == 2


@pytest.mark.parametrize(
    ("bad", "error"), [(0, ValueError), (-1, ValueError), (1.0, TypeError), ("2", TypeError)]
)
def test_thread_limit_checks_its_argument(bad, error):
    with pytest.raises(error, match="n must"), sk.thread_limit(bad):
        pass


@pytest.mark.parametrize(
    ("value", "expected"),
    [("1000000000", 1024), ("3", 3), (" 7", 7), ("abc", None), ("0", None), ("-2", None), ("1.5", None)],
)
def test_environment_thread_count(value, expected):
    result = run_python(
        "import warnings, os; warnings.simplefilter('always')\n"
        "import spotkin as sk; print(sk.get_num_threads(), os.cpu_count())",
        env={"SPOTKIN_NUM_THREADS": value},
    )
    assert result.returncode == 0, result.stderr
    threads, cores = map(int, result.stdout.split())
    if expected is None:  # ignored, with a warning naming the variable
        assert threads == min(cores, 1024)
        assert "SPOTKIN_NUM_THREADS" in result.stderr
    else:
        assert threads == expected
        assert ("capped" in result.stderr) == (value == "1000000000")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS semantics")
def test_thread_start_failure_falls_back():
    """With address space for only a few thread stacks, 1024 threads asked still finish the
    batch (with the threads that did start), bit-identical, without terminate()."""
    code = """
        import resource
        import numpy as np
        import spotkin as sk
        leg = sk.Spot().leg("fl")
        q = np.random.default_rng(1).uniform(-2, 2, size=(300_000, 3))
        sk.set_num_threads(1)
        expected = leg.fk(q)
        out = np.empty_like(expected)
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[0])
        used = pages * resource.getpagesize()
        resource.setrlimit(resource.RLIMIT_AS, (used + 96 * 2**20, resource.RLIM_INFINITY))
        sk.set_num_threads(1024)
        got = leg.fk(q)
        print("equal" if np.array_equal(got, expected) else "different")
    """
    result = run_python(code)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "equal"


# -- Ctrl-C ---------------------------------------------------------------------------------------


def _interrupt(code: str, wait: float) -> float:
    """Runs ``code`` (which prints "ready", then "interrupted <time>" on KeyboardInterrupt), sends
    it SIGINT ``wait`` seconds after it is ready, and returns how long the interrupt took."""
    proc = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(wait)  # inside the batch by now
    sent = time.perf_counter()  # CLOCK_MONOTONIC: the child's clock too
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    words = out.split()
    assert words[0] == "interrupted", out
    return float(words[1]) - sent


_LONG_BATCH = """
    import sys, time
    import numpy as np
    import spotkin as sk
    sk.set_num_threads({threads})
    J = np.random.default_rng(0).random((100_000, 16, 16))  # ~30 us of SVD each: seconds of work
    print("ready", flush=True)
    try:
        sk.singular_values(J)
    except KeyboardInterrupt:
        print("interrupted", time.perf_counter(), flush=True)
        sys.exit(0)
    print("finished", flush=True)
"""


@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_interrupts_a_long_batch(threads):
    assert _interrupt(_LONG_BATCH.format(threads=threads), 0.5) < 0.5  # ~0.1 s asked; generous


_LONG_DIRECT_BATCH = """
    import sys, time
    import numpy as np
    import spotkin as sk
    sk.set_num_threads(1)
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    go2.standing_torques(np.array([0, 0, 0.3, 0, 0, 0.0]), np.zeros(12))
    pose = np.zeros((2_000_000, 6), np.float32)  # ~1 us each on one thread: seconds of work
    pose[:, 2] = 0.3
    print("ready", flush=True)
    try:
        go2.standing_torques(pose, np.zeros(12, np.float32))  # a core method called past pybind11
    except KeyboardInterrupt:
        print("interrupted", time.perf_counter(), flush=True)
        sys.exit(0)
    print("finished", flush=True)
"""


def test_ctrl_c_interrupts_a_direct_call():
    """The façade's direct call (cpp/bindings/fast_call.hpp) raises the interrupt as pybind11's
    dispatcher does: it neither swallows it nor runs the batch again."""
    assert _interrupt(_LONG_DIRECT_BATCH, 0.5) < 0.5


def test_ctrl_c_interrupts_ik_differential():
    code = """
        import sys, time
        import numpy as np
        import spotkin as sk
        rows = [(0, 0, 0, 0.3, 0), (0, 0, np.pi / 2, 0, 0), (0, 0.4, 0, 0, 0),
                (0, 0, np.pi / 2, 0.4, 0), (0, 0, -np.pi / 2, 0, 0), (0, 0, np.pi / 2, 0.1, 0)]
        chain = sk.Chain.from_mdh(rows)
        T = chain.fk(np.full(6, 0.3))
        targets = np.broadcast_to(T, (400_000, 4, 4))
        q0 = np.zeros((400_000, 6))
        print("ready", flush=True)
        try:
            chain.ik_differential(targets, q0, max_iter=200, position_tolerance=0.0,
                                  orientation_tolerance=0.0)
        except KeyboardInterrupt:
            print("interrupted", time.perf_counter(), flush=True)
            sys.exit(0)
        print("finished", flush=True)
    """
    assert _interrupt(code, 0.8) < 0.5


# -- NaN isolation --------------------------------------------------------------------------------


def test_leg_singularity_nan_sample_is_nan():
    q = np.array([[0.0, 1.0, -1.8], [np.nan, 1.0, -1.8]])
    det, sigma = LEG.singularity(q)
    single_det, single_sigma = LEG.singularity(q[0])
    assert det[0] == single_det and sigma[0] == single_sigma
    assert np.isnan(det[1]) and np.isnan(sigma[1])
    # the value for a finite sample is the smallest singular value of the Jacobian
    np.testing.assert_allclose(sigma[0], np.linalg.svd(LEG.jacobian(q[0]), compute_uv=False)[-1], rtol=1e-12)
    assert np.isnan(LEG.singularity([np.nan, 1.0, -1.8])[1])
    assert np.isnan(LEG.singularity(np.full((5, 3), np.nan))[1]).all()
    assert np.isnan(LEG.singularity(np.array([[np.inf, 0, 0]], dtype=np.float32))[1]).all()


def test_body_rates_nan_joint_affects_only_its_sample():
    body_pose = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    q12 = np.tile([0.05, 0.9, -1.6], 4)
    batch = np.stack([q12, q12, q12])
    batch[1, 4] = np.nan  # fr.hy
    twist = np.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.2])
    rates = SPOT.body_rates(body_pose, batch, twist)
    single = SPOT.body_rates(body_pose, q12, twist)
    np.testing.assert_array_equal(rates.qd[0], single.qd)
    np.testing.assert_array_equal(rates.qd[2], single.qd)
    assert np.isnan(rates.qd[1, 3:6]).all()
    np.testing.assert_array_equal(rates.qd[1, :3], single.qd[:3])


# -- accepted but wrong ---------------------------------------------------------------------------


def _six_joint_chain():
    return sk.Chain.from_mdh(
        [
            (0, 0, 0, 0.3, 0),
            (0, 0, np.pi / 2, 0, 0),
            (0, 0.4, 0, 0, 0),
            (0, 0, np.pi / 2, 0.4, 0),
            (0, 0, -np.pi / 2, 0, 0),
            (0, 0, np.pi / 2, 0.1, 0),
        ]
    )


@pytest.mark.parametrize(
    "corrupt",
    [
        lambda T: T * np.diag([0, 0, 0, 1]),  # rotation all zeros
        lambda T: T @ np.diag([2.0, 2.0, 2.0, 1.0]),  # scaled
        lambda T: T @ np.diag([1.0, 1.0, -1.0, 1.0]),  # a reflection
        lambda T: T + np.array([[0, 0, 0, 0]] * 3 + [[0, 0, 0.5, 0]]),  # bad last row
    ],
)
def test_ik_differential_rejects_non_rigid_targets(corrupt):
    chain = _six_joint_chain()
    q_true = np.array([0.2, 0.3, -0.4, 0.5, 0.6, -0.7])
    good = chain.fk(q_true)
    bad = corrupt(good)
    assert chain.ik_all(bad).status == sk.Status.INVALID_INPUT  # the closed form says so already
    q, info = chain.ik_differential(np.stack([good, bad]), q_true + 0.01)
    assert info.converged[0] and not info.converged[1]
    assert np.isnan(q[1]).all() and np.isnan(info.position_error[1])
    np.testing.assert_allclose(chain.fk(q[0]), good, atol=1e-5)


def test_paul_non_finite_coefficients_have_no_root():
    for args in [(np.inf, 0.7, 0.3), (0.7, -np.inf, 0.3), (0.7, 0.3, np.inf), (np.nan, 0.7, 0.3)]:
        t, valid = sk.paul.type2(*args)
        assert not valid.any() and np.isnan(t).all(), args
    t, valid = sk.paul.type3(np.inf, 1, 0.5, 1, 0, 0.2)
    assert not valid and np.isnan(t)
    for k in range(5):
        coeffs = [1.0, 0.3, 0.2, 0.4, 0.1]
        coeffs[k] = np.inf
        ti, tj, valid = sk.paul.type6(*coeffs)
        assert not valid.any() and np.isnan(ti).all() and np.isnan(tj).all(), coeffs
    # huge finite coefficients still solve: X sin t + Y cos t = Z with X = 1e300
    t, valid = sk.paul.type2(1e300, 0.0, 0.5e300)
    assert valid.all()
    np.testing.assert_allclose(np.sin(t), 0.5)


@pytest.mark.parametrize("which", ["base", "tool"])
@pytest.mark.parametrize(
    "transform",
    [
        2 * np.eye(4),
        np.diag([1.0, 1.0, 1.0, 2.0]),
        np.vstack([np.eye(4)[:3], [[0.1, 0, 0, 1]]]),
        np.diag([1.0, -1.0, 1.0, 1.0]),
        np.full((4, 4), np.nan),
        sk.rotation_x(0.3) @ np.diag([1.0, 1.0, 1.0 + 1e-6, 1.0]),
    ],
)
def test_chain_checks_base_and_tool(which, transform):
    rows = [(0, 0.0, 0.0, 0.0, 0.0), (0, 0.3, 0.0, 0.0, 0.0), (0, 0.3, 0.0, 0.0, 0.0)]
    with pytest.raises(ValueError, match=f"{which} must be a finite rigid transform"):
        sk.Chain.from_mdh(rows, **{which: transform})
    with pytest.raises(ValueError, match=f"{which} must be a finite rigid transform"):
        sk.Chain.from_dh(rows, **{which: transform})
    good = sk.rotation_z(0.4) @ sk.translation([0.1, 0.2, 0.3])
    chain = sk.Chain.from_mdh(rows, **{which: good})
    plain = sk.Chain.from_mdh(rows)
    q = np.array([0.1, -0.2, 0.3])
    expected = good @ plain.fk(q) if which == "base" else plain.fk(q) @ good
    np.testing.assert_allclose(chain.fk(q), expected, atol=1e-15)


def test_spot_arm_checks_its_tool():
    with pytest.raises(ValueError, match="tool must be a finite rigid transform"):
        sk.SpotArm(tool=2 * np.eye(4))


# -- one boundary ---------------------------------------------------------------------------------


def test_masked_arrays_are_rejected():
    q = np.ma.masked_array(np.zeros((2, 3)), mask=[[0, 0, 1], [0, 0, 0]])
    with pytest.raises(TypeError, match="q must be a plain array, got a masked array"):
        LEG.fk(q)
    with pytest.raises(TypeError, match="masked array"):
        SPOT.body_ik(np.ma.masked_array([0.0, 0, 0.5, 0, 0, 0]), SPOT.stance_feet(0.5))


@pytest.mark.parametrize("dtype", [">f4", "<f4"])
def test_float32_of_either_byte_order_stays_float32(dtype):
    q = np.array([[0.1, 0.9, -1.5], [0.0, 1.1, -2.0]], dtype=dtype)
    p = LEG.fk(q)
    assert p.dtype == np.float32
    np.testing.assert_array_equal(p, LEG.fk(q.astype(np.float32)))
    assert LEG.jacobian(q).dtype == np.float32


@pytest.mark.parametrize("dtype", [">f8", np.float16, np.int16, np.uint8, bool])
def test_other_real_dtypes_run_in_float64(dtype):
    q = np.array([[0, 1, -1], [1, 0, -2]]).astype(dtype)
    p = LEG.fk(q)
    assert p.dtype == np.float64
    np.testing.assert_array_equal(p, LEG.fk(q.astype(np.float64)))


def test_too_large_to_allocate_raises_memory_error():
    with pytest.raises(MemoryError):
        LEG.fk(np.broadcast_to(np.zeros(3), (10**10, 3)))
    with pytest.raises(MemoryError):
        SPOT.arm.fk(np.broadcast_to(np.zeros(6, dtype=np.float32), (10**10, 6)))


# -- huge angles ----------------------------------------------------------------------------------


def _exactly_reduced(q):
    """libm's sin and cos reduce exactly (Payne-Hanek); atan2 brings the angle back."""
    return np.array([math.atan2(math.sin(x), math.cos(x)) for x in np.ravel(q)]).reshape(np.shape(q))


@pytest.mark.parametrize("magnitude", [1e6, 1e9, 1e15, 1e300])
def test_huge_leg_angles_equal_their_exact_remainder(magnitude):
    rng = np.random.default_rng(3)
    q = rng.uniform(-1, 1, size=(700, 3)) * magnitude  # 700: more than one 512-sample block
    q[::3] = rng.uniform(-2, 2, size=q[::3].shape)  # ordinary rows in between
    reduced = _exactly_reduced(q)
    p = LEG.fk(q)
    expected = np.array(
        [
            leg_reference.fk(qi, LEG.hip_offset, LEG.upper_length, LEG.lower_length, LEG.knee_offset)
            for qi in reduced
        ]
    )
    np.testing.assert_allclose(p, expected, atol=1e-12)
    np.testing.assert_allclose(LEG.jacobian(q), LEG.jacobian(reduced), atol=1e-12)
    np.testing.assert_allclose(LEG.singularity(q)[1], LEG.singularity(reduced)[1], atol=1e-12)


def test_huge_angles_everywhere():
    q6 = np.array([1e15, -3e12, 7e9, 1e300, 2.5e6, -1e16])
    reduced = _exactly_reduced(q6)
    np.testing.assert_allclose(SPOT.arm.fk(q6), SPOT.arm.fk(reduced), atol=1e-12)
    np.testing.assert_allclose(SPOT.arm.jacobian(q6), SPOT.arm.jacobian(reduced), atol=1e-12)
    np.testing.assert_allclose(
        SPOT.arm.singularity(q6).manipulability, SPOT.arm.singularity(reduced).manipulability, atol=1e-12
    )
    chain = _six_joint_chain()
    np.testing.assert_allclose(chain.fk(q6), chain.fk(reduced), atol=1e-12)
    np.testing.assert_allclose(chain.frames(q6), chain.frames(reduced), atol=1e-12)
    np.testing.assert_allclose(chain.jacobian(q6), chain.jacobian(reduced), atol=1e-12)
    q12 = np.tile([1e15, 1e15 + 0.5, -1e15], 4)
    pose = np.array([0.0, 0.0, 0.5, 1e14, -1e13, 3e15])
    pose_reduced = np.concatenate([pose[:3], _exactly_reduced(pose[3:])])
    np.testing.assert_allclose(
        SPOT.body_fk(pose, q12), SPOT.body_fk(pose_reduced, _exactly_reduced(q12)), atol=1e-12
    )
    np.testing.assert_allclose(
        SPOT.body_jacobian(pose, q12), SPOT.body_jacobian(pose_reduced, _exactly_reduced(q12)), atol=1e-12
    )
    feet = SPOT.stance_feet(0.5)
    a, b = SPOT.body_ik(pose, feet), SPOT.body_ik(pose_reduced, feet)
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)
    np.testing.assert_array_equal(a.status, b.status)


def test_huge_prismatic_displacements_are_not_reduced():
    chain = sk.Chain.from_mdh([(1, 0.0, 0.0, 0.0, 0.0), (0, 0.2, 0.0, 0.0, 0.0)])
    T = chain.fk([1e6, 1e6])
    assert T[2, 3] == 1e6  # a displacement along z, as given
    np.testing.assert_allclose(T[:3, :3], sk.rotation_z(_exactly_reduced(1e6))[:3, :3], atol=1e-12)


# -- the UNREACHABLE fallback ---------------------------------------------------------------------


def test_leg_fallback_choice():
    far = np.array([[0.0, 0.11, -2.0], [0.05, 0.12, -0.5]])
    q_nearest, status = LEG.ik(far)
    assert status[0] == sk.Status.UNREACHABLE and status[1] == sk.Status.OK
    assert np.isfinite(q_nearest).all()
    q_nan, status_nan = LEG.ik(far, fallback="nan")
    np.testing.assert_array_equal(status_nan, status)
    assert np.isnan(q_nan[0]).all()
    np.testing.assert_array_equal(q_nan[1], q_nearest[1])
    np.testing.assert_array_equal(LEG.ik(far, fallback="nearest")[0], q_nearest)
    with pytest.raises(ValueError, match="fallback must be one of"):
        LEG.ik(far, fallback="closest")
    with pytest.raises(ValueError, match="fallback must be one of"):
        LEG.ik(far, fallback=None)


def test_body_fallback_choice():
    feet = SPOT.stance_feet(0.5)
    poses = np.array([[0.0, 0.0, 0.5, 0, 0, 0], [0.0, 0.0, 2.0, 0, 0, 0]])  # the second: feet out of reach
    near = SPOT.body_ik(poses, feet)
    nan = SPOT.body_ik(poses, feet, fallback="nan")
    np.testing.assert_array_equal(near.status, nan.status)
    assert (near.status[1] == sk.Status.UNREACHABLE).all()
    assert np.isfinite(near.q).all() and np.isnan(nan.q[1]).all()
    np.testing.assert_array_equal(nan.q[0], near.q[0])
    single = SPOT.body_ik(poses[1], feet, fallback="nan")
    assert np.isnan(single.q).all()
    with pytest.raises(ValueError, match="fallback"):
        SPOT.body_ik(poses, feet, fallback="NaN")


def test_ragged_input_is_a_value_error():
    with pytest.raises(ValueError, match="q must be a rectangular numeric array"):
        LEG.fk([[0.0, 1.0, 2.0], [0.0, 1.0]])


def test_nearest_reachable_of_huge_points():
    # beyond reach, the answer depends on the direction only: no overflow in |p|^2
    for direction in ([1.0, 1.0, 0.0], [0.3, -0.2, -1.0], [-1.0, 0.0, 0.0]):
        huge = LEG.nearest_reachable(np.array(direction) * 1e308)
        np.testing.assert_allclose(huge, LEG.nearest_reachable(direction), atol=1e-12)
        assert np.isfinite(LEG.ik(np.array(direction) * 1e308)[0]).all()
    assert np.isnan(LEG.nearest_reachable([np.inf, 0.0, 0.0])).all()


def test_float64_seed_beside_float32_targets_is_reduced_then_narrowed():
    """A float64 seed of 1e308 rad is an angle: reduced exactly, then cast (no overflow warning)."""
    q_true = np.array([0.3, -0.6, 1.4, 0.2, 0.5, -0.3])
    T = SPOT.arm.fk(q_true).astype(np.float32)
    huge = np.array([1e308, -3e300, 1e200, 7e250, -1e308, 5e299])
    q, status = SPOT.arm.ik(T, seed=huge)
    q_reduced, status_reduced = SPOT.arm.ik(T, seed=_exactly_reduced(huge).astype(np.float32))
    assert status == status_reduced == sk.Status.OK
    np.testing.assert_array_equal(q, q_reduced)
    p = LEG.fk(np.array([0.1, 0.9, -1.5])).astype(np.float32)
    seed = np.array([1e308, 1e308, -1e308])
    np.testing.assert_array_equal(
        LEG.ik(p, seed=seed)[0], LEG.ik(p, seed=_exactly_reduced(seed).astype(np.float32))[0]
    )


def test_integers_beyond_the_float_range_are_value_errors():
    with pytest.raises(ValueError, match="tolerance must be a finite number"):
        SPOT.body_rates(np.zeros(6), np.zeros(12), np.zeros(6), tolerance=10**400)
    with pytest.raises(ValueError, match="damping"):
        sk.dls(np.eye(3), np.ones(3), damping=10**400)


def test_body_calls_promote_mixed_float32_and_float64():
    pose32 = np.array([0.0, 0.0, 0.5, 0.05, -0.1, 0.2], dtype=np.float32)
    feet = SPOT.stance_feet(0.5)
    q12 = SPOT.body_ik(pose32.astype(np.float64), feet).q
    assert SPOT.body_ik(pose32, feet).q.dtype == np.float64  # feet float64: promoted
    assert SPOT.body_ik(pose32, feet.astype(np.float32)).q.dtype == np.float32
    assert SPOT.body_fk(pose32, q12).dtype == np.float64
    assert SPOT.body_fk(pose32, q12.astype(np.float32)).dtype == np.float32
    far = feet * 1e300  # far, finite: out of reach, not an Inf of a narrowing cast
    res = SPOT.body_ik(pose32, far)
    assert (res.status == sk.Status.UNREACHABLE).all()
    huge = q12 + 2 * np.pi * 1e290  # angles beyond float32: reduced exactly in float64
    np.testing.assert_allclose(
        SPOT.body_fk(pose32, huge), SPOT.body_fk(pose32, _exactly_reduced(huge)), atol=1e-12
    )
