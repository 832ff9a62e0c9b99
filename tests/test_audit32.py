"""What a hostile audit of the whole package found (issue 32): sizes that were allocated before being
bounded, silently wrong answers, loops that never finished, warnings and tracebacks instead of clear
errors, valid float32 input refused, messages that did not name the argument, worker processes that
outlived a killed batch, and an object that could not be pickled. Each reproducer is a test."""

from __future__ import annotations

import math
import os
import pickle
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk
from conftest import panda
from spotkin import urdf
from spotkin.__main__ import LEG_MDH_ROWS, main

SPOT = sk.Spot()
PI = math.pi


def kinova_like() -> sk.Chain:
    """A 7R S-R-S arm (continuous joints 1, 3, 5, 7), as in test_chain_ik7."""
    _, Y, Z = np.eye(3)
    axes = np.array([Z, Y, Z, Y, Z, Y, Z])
    points = np.array(
        [[0, 0, 0.28], [0, 0, 0.28], [0, 0, 0.28], [0, 0.01, 0.69], [0, 0, 1.0], [0, 0, 1.0], [0, 0, 1.0]]
    )
    placements = np.tile(np.eye(4), (7, 1, 1))
    placements[:, :3, 3] = np.diff(np.vstack([np.zeros(3), points]), axis=0)
    free = (-np.inf, np.inf)
    limits = [free, (-2.41, 2.41), free, (-2.66, 2.66), free, (-2.23, 2.23), free]
    return sk.Chain.from_joints(placements, axes, tool=sk.translation([0.0, 0.0, 0.16]), limits=limits)


Q7 = np.array([0.3, 0.5, 0.2, 1.0, -0.4, 0.7, 0.1])


# ---- sizes bounded before anything is allocated -------------------------------------------------------


@pytest.mark.parametrize(
    "arguments, message",
    [
        ({"spacing": 1e-9}, r"spacing 1e-09 m makes a grid of about .* positions.*at most 10,000,000"),
        ({"spacing": 5e-324}, r"spacing .* makes a grid of about inf positions"),
        ({"orientations": 10**12}, r"orientations must be at most 1,000,000"),
        ({"samples": 10**12}, r"samples must be at most 20,000,000"),
        ({"spacing": 0.05, "orientations": 10**6}, r"IK solves .* at most 1e\+10"),
    ],
)
def test_dexterity_bounds_its_grid_and_counts(arguments, message):
    # reported: spacing=1e-9 built 1e9-point axes (killed by the OOM killer)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=message):
        sk.dexterity(SPOT.arm, **{"samples": 2000, **arguments})
    assert time.perf_counter() - start < 10


def test_workspace_counts_are_bounded():
    leg = SPOT.legs[0]
    with pytest.raises(ValueError, match=r"n must be at most 10,000,000,000, got 1,000,000,000,000,000"):
        sk.workspace_volume(leg, n=10**30)  # reported: never finished
    with pytest.raises(ValueError, match=r"n must be at most 20,000,000"):
        sk.workspace(leg, n=10**9)
    # the same samples as before the bound (drawn in place)
    samples = sk.workspace(leg, n=1000, seed=3)
    lower, upper = leg.limits[:, 0], leg.limits[:, 1]
    expected = lower + (upper - lower) * np.random.default_rng(3).random((1000, 3))
    assert np.array_equal(samples.q, expected)


@pytest.mark.parametrize("make, joint", [(kinova_like, 2), (panda, 6)])
def test_free_joint_sample_counts_are_bounded(make, joint):
    # reported: values=2**31 called linspace with 2**31 points; values=2**63 gave IndexError
    chain = make()
    T = chain.fk(np.clip(Q7, chain.lower, chain.upper))
    for values in (2**31, 2**63, 10**5 + 1):
        with pytest.raises(ValueError, match=r"values must be a count of at most 100,000"):
            chain.ik_self_motion(T, joint, values=values)
        with pytest.raises(ValueError, match=r"values must be a count of at most 100,000"):
            chain.ik_nearest_free(T, Q7, joint, values=values)
    with pytest.raises(ValueError, match=r"values must hold at most 100,000 values"):
        chain.ik_self_motion(T, joint, values=np.zeros(100_001))
    grid, sol = chain.ik_self_motion(T, joint, values=5)
    assert grid.shape == (5,) and sol.q.shape == (5, 8, 7)


# ---- silently wrong -----------------------------------------------------------------------------------


def test_zarr_inputs_rewritten_after_a_run_are_not_taken_for_the_same(tmp_path, capsys):
    # reported: a resumed run on a Zarr input rewritten after the kill (same shape, dtype and chunks)
    # mixed the two datasets and said complete
    pytest.importorskip("dask.array")
    zarr = pytest.importorskip("zarr")
    rng = np.random.default_rng(1)
    p = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0]) + rng.normal(0, 0.02, (400, 6))
    store = str(tmp_path / "inputs.zarr")
    group = zarr.open_group(store, mode="w")
    create = group.create_array if hasattr(group, "create_array") else group.create_dataset
    create("poses", shape=p.shape, chunks=(100, 6), dtype=p.dtype)[...] = p
    feet = SPOT.stance_feet(0.5)
    np.save(tmp_path / "feet.npy", feet)
    out = str(tmp_path / "out.zarr")
    command = ["batch", "body-ik", "--poses", f"{store}/poses", "--feet", str(tmp_path / "feet.npy")]
    command += ["--out", out, "--chunk-size", "100", "--quiet"]
    assert main(command) == 0
    time.sleep(0.01)
    zarr.open_array(f"{store}/poses", mode="r+")[...] = p[::-1]  # rewritten in place: same shape and chunks
    capsys.readouterr()
    assert main(command) == 2
    err = capsys.readouterr().err
    assert "holds a run with other inputs" in err
    # an untouched input still resumes (here: is complete)
    out2 = str(tmp_path / "out2.zarr")
    command[command.index(out)] = out2
    assert main(command) == 0 and main(command) == 0
    np.testing.assert_array_equal(zarr.open_group(out2, mode="r")["q"][...], SPOT.body_ik(p[::-1], feet).q)


@pytest.mark.parametrize(
    "solve, coefficients",
    [
        (sk.paul.type2, (0.0, 1.0, -1.0)),  # reported: (-pi, pi) returned
        (sk.paul.type3, (0.0, 0.0, 0.0, -0.0, -1.0, 1.0)),
        (sk.paul.type6, (0.0, 0.0, 1.0, 0.0, -1.0)),
        (sk.paul.type6, (1.0, -0.0, -0.0, -0.0, -1.0)),
    ],
)
def test_paul_angles_are_in_the_half_open_interval(solve, coefficients):
    *angles, valid = solve(*coefficients)
    assert valid.any()
    for t in angles:
        t = t[valid]
        assert ((t > -PI) & (t <= PI)).all(), t
    for t in solve(*(np.full(3, c) for c in coefficients))[:-1]:  # batched too
        assert not (t == -PI).any()


def edge_targets() -> tuple[np.ndarray, np.ndarray]:
    """Leg targets and arm poses on the axes (signed zeros included): where atan2 meets -pi."""
    import itertools

    values = [0.0, -0.0, 0.1, -0.1, 0.3, -0.3, 0.5, -0.5, 1e-300, -1e-300]
    points = np.array(list(itertools.product(values, repeat=3)))
    poses = []
    for R in (np.eye(3), np.diag([1.0, -1, -1]), np.diag([-1.0, 1, -1]), np.diag([-1.0, -1, 1])):
        for p in itertools.product([0.0, 0.3, -0.3, 0.5], repeat=3):
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = R, p
            poses.append(T)
    return points, np.array(poses)


def test_leg_and_arm_angles_are_in_the_half_open_interval():
    # the same -pi edge in the leg and arm kernels: (-pi, pi], shifted by 2 pi only into the limits
    points, poses = edge_targets()
    legs = [
        sk.Leg(0.1, 0.3, 0.3),
        sk.Leg(0.1, 0.3, 0.3, side="right"),
        sk.Leg.from_geometry([0, 0.1, 0], [0, 0, -0.3], [0, 0, -0.3], signs=[-1, -1, -1]),
    ]
    for leg in legs:
        for dtype in (np.float64, np.float32):
            minus_pi = dtype(-PI)
            solutions = leg.ik_all(points.astype(dtype))
            assert not (solutions.q[solutions.exists] == minus_pi).any()
            q, _ = leg.ik(points.astype(dtype))
            assert not (q == minus_pi).any()
    solutions = sk.SpotArm(limits=None).ik_all(poses)
    assert solutions.exists.any() and not (solutions.q[solutions.exists] == -PI).any()
    # with limits, -pi stays where pi is outside them and -pi inside
    leg = sk.Leg(0.1, 0.3, 0.3, limits=[(-3.5, 3.0), (-4, 4), (-4, 4)])
    solutions = leg.ik_all(points)
    hip = solutions.q[..., 0][solutions.valid]
    assert ((hip > -PI) | (hip == -PI)).all() and not (hip > 3.0).any()


@pytest.mark.parametrize("huge", [1e300, -1e17, 1e17])
def test_ik_nearest_free_reduces_a_huge_seed_before_the_distances(huge):
    # reported: a seed of 1e300 or -1e17 was subtracted before being reduced: the wrong solution
    chain = kinova_like()
    T = chain.fk(Q7)
    seed = Q7.copy()
    seed[0] = huge
    reduced = seed.copy()
    reduced[0] = math.atan2(math.sin(huge), math.cos(huge))
    q, status = chain.ik_nearest_free(T, seed, 2, values=8)
    q_reduced, status_reduced = chain.ik_nearest_free(T, reduced, 2, values=8)
    assert status == status_reduced == sk.Status.OK
    np.testing.assert_array_equal(q, q_reduced)
    assert np.abs(chain.fk(q) - T).max() < 1e-9


# ---- never finishing ----------------------------------------------------------------------------------


def comb_urdf(n: int) -> str:
    """A chain of n revolute joints with a fixed leaf link on every link: n + 1 leaves."""
    limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'
    links = [f'<link name="l{i}"/>' for i in range(n + 1)] + [f'<link name="s{i}"/>' for i in range(n)]
    joints = [
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{limit}</joint>'
        for i in range(n)
    ] + [
        f'<joint name="f{i}" type="fixed"><parent link="l{i}"/><child link="s{i}"/></joint>' for i in range(n)
    ]
    return f'<robot name="comb">{"".join(links)}{"".join(joints)}</robot>'


def test_recognition_is_linear_in_the_tree_size():
    # reported: a 10,000-joint chain took 215 s in Robot.from_urdf before failing (a path per leaf)
    seconds = {}
    for n in (10_000, 20_000):
        text = comb_urdf(n)
        start = time.perf_counter()
        with pytest.raises(ValueError, match="no roll-pitch-pitch legs"):
            sk.Robot.from_urdf_string(text)
        seconds[n] = time.perf_counter() - start
    assert seconds[10_000] < 20 and seconds[20_000] < 20, seconds
    model = urdf.parse_urdf(comb_urdf(2000))
    legs, report = urdf.find_legs(model)
    assert not legs and len(report) == 2001
    arms, report = urdf.find_arms(model, legs)
    assert [arm.joint_names for arm in arms] == [tuple(f"j{i}" for i in range(6))]
    assert (
        "l2000: 2000 actuated joints, the first 6 (j0, j1, j2, j3, j4, j5) are taken as an arm; "
        in "\n".join(report)
    )
    assert "j6, j7, j8 and 1991 more not part of it" in "\n".join(report)


# ---- warnings and tracebacks --------------------------------------------------------------------------


def test_non_finite_and_out_of_range_input_gives_no_warning():
    # reported: RuntimeWarning (an error under -W error) instead of NaN/INVALID_INPUT
    chain = kinova_like()
    T = chain.fk(Q7)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        seed = Q7.copy()
        seed[1] = np.inf
        q, status = chain.ik_nearest_free(T, seed, 2, values=8)
        assert status == sk.Status.INVALID_INPUT and np.isnan(q).all()
        q_slots = np.zeros((3, 2, 3))
        q_slots[1, 0, 0] = np.inf
        held = sk.trajectory.hold_branch(q_slots, np.ones((3, 2), bool), 0)
        assert held.jumps.tolist() == [1, 2]
        huge = np.array([np.longdouble("1e400"), 1.0, 1.0])
        t, valid = sk.paul.type2(*huge)
        assert not valid.any() and np.isnan(t).all()
        q, status = SPOT.legs[0].ik(huge)
        assert status == sk.Status.INVALID_INPUT


def run_cli(*arguments: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "spotkin", *arguments], capture_output=True, text=True, timeout=timeout
    )


@pytest.mark.parametrize(
    "arguments, message",
    [
        (("demo", "--samples", "100000000000"), "spotkin demo: error: --samples must be in [1, 10,000,000]"),
        (("demo", "--dpi", "1"), "spotkin demo: error: --dpi must be in [10, 600]"),
        (("workspace", "--orientations", "1000000000000"), "error: --orientations must be in [1, 1,000,000]"),
        (("workspace", "--samples", "100000000000000"), "error: --samples must be in [1, 10,000,000,000]"),
        (("workspace", "--spacing", "nan"), "error: --spacing must be a positive number of metres"),
        (("plot", "go2", "--size", "10000x10000", "--dpi", "1"), "spotkin plot: error: --dpi must be in"),
    ],
)
def test_the_cli_refuses_out_of_range_options_in_one_line(arguments, message):
    # reported: tracebacks (MemoryError, FreeType's RuntimeError) instead of one line
    result = run_cli(*arguments)
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip() == message or (
        message in result.stderr and len(result.stderr.strip().splitlines()) == 1
    ), result.stderr
    assert "Traceback" not in result.stderr


def test_the_cli_refuses_an_endless_file_in_one_line():
    result = run_cli("inspect", "/dev/zero")
    assert result.returncode in (1, 2), result.stderr
    assert "64 MiB" in result.stderr and len(result.stderr.strip().splitlines()) == 1


def _batch_files(folder, n: int = 64) -> list[str]:
    p = np.tile([0.0, 0.0, 0.5, 0.0, 0.0, 0.0], (n, 1))
    np.save(os.path.join(folder, "poses.npy"), p)
    np.save(os.path.join(folder, "feet.npy"), SPOT.stance_feet(0.5))
    return [
        "body-ik",
        "--poses",
        os.path.join(folder, "poses.npy"),
        "--feet",
        os.path.join(folder, "feet.npy"),
    ]


def test_batch_chunks_larger_than_the_batch_run_as_one(tmp_path):
    # reported: --chunk-size 1e20 created the output, then failed
    pytest.importorskip("dask.array")
    zarr = pytest.importorskip("zarr")
    out = str(tmp_path / "out.zarr")
    assert (
        main(["batch", *_batch_files(str(tmp_path)), "--out", out, "--chunk-size", str(10**20), "--quiet"])
        == 0
    )
    group = zarr.open_group(out, mode="r")
    assert dict(group.attrs)["spotkin_batch"]["chunk_size"] == 64 and group["q"].chunks[0] == 64


def test_batch_connects_to_its_scheduler_before_writing(tmp_path):
    # reported: an unreachable --scheduler created the output before failing
    pytest.importorskip("distributed")
    out = str(tmp_path / "out.zarr")
    arguments = ["batch", *_batch_files(str(tmp_path)), "--out", out, "--scheduler", "tcp://127.0.0.1:1"]
    environment = {**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"}
    result = subprocess.run(
        [sys.executable, "-m", "spotkin", *arguments],
        capture_output=True,
        text=True,
        timeout=120,
        env=environment,
    )
    assert result.returncode == 2, result.stderr
    assert "--scheduler tcp://127.0.0.1:1: cannot connect" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert not os.path.exists(out)


# ---- valid float32 input ------------------------------------------------------------------------------


def float32_pose() -> tuple[np.ndarray, np.ndarray]:
    R = sk.rotation_z(0.7)[:3, :3] @ np.array(
        [[1, 0, 0], [0, math.cos(0.3), -math.sin(0.3)], [0, math.sin(0.3), math.cos(0.3)]]
    )
    T = sk.transform(R, [0.1, 0.2, 0.3])
    T32 = T.astype(np.float32)
    R32 = T32[:3, :3].astype(np.float64)
    assert np.abs(R32.T @ R32 - np.eye(3)).max() > 1e-9  # float32 rounding alone fails a 1e-9 check
    return T, T32


def test_float32_rigid_transforms_are_accepted():
    T, T32 = float32_pose()
    path = sk.trajectory.linear(np.eye(4, dtype=np.float32), T32, 1.0, 1.0, 1.0, 1.0)
    np.testing.assert_allclose(path.sample(path.duration), T, atol=1e-7)
    path = sk.trajectory.via_points(
        np.stack([np.eye(4), T, np.eye(4)]).astype(np.float32), 1.0, 1.0, 1.0, 1.0
    )
    assert np.isfinite(path.duration)
    chain = sk.Chain.from_mdh([(0, 0.0, 0.0, 0.3, 0.0)] * 3, tool=T32, base=T32)
    np.testing.assert_allclose(chain.tool, T, atol=1e-7)
    R = chain.tool[:3, :3]
    assert np.abs(R.T @ R - np.eye(3)).max() < 1e-15  # the nearest rotation: no float32 rounding left
    arm = sk.SpotArm(tool=T32)
    np.testing.assert_allclose(
        arm.tool, sk.translation([0.19557, 0.0, 0.0]) @ T, atol=1e-7
    )  # the chain's: hand, then tool
    q = np.array([0.4, -1.2, 1.9, 0.3, -0.6, 0.8])
    q_back, status = arm.ik(arm.fk(q), seed=q)
    assert status == sk.Status.OK and np.abs(q_back - q).max() < 1e-9
    placements = np.tile(T32, (2, 1, 1))
    assert sk.Chain.from_joints(placements, np.eye(3)[:2]).dof == 2


def test_float32_transforms_that_are_not_rigid_are_still_refused():
    _, T32 = float32_pose()
    bad = T32.copy()
    bad[0, 1] += 1e-4
    with pytest.raises(ValueError, match=r"tool must be a finite rigid transform.*1e-06 \(float32\)"):
        sk.SpotArm(tool=bad)
    with pytest.raises(ValueError, match=r"base must be a finite rigid transform"):
        sk.Chain.from_mdh([(0, 0.0, 0.0, 0.3, 0.0)] * 3, base=bad)
    with pytest.raises(ValueError, match=r"T1 must be a rigid transform"):
        sk.trajectory.linear(np.eye(4), bad, 1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match=r"tool must be a finite rigid transform"):  # float64: 1e-9 as before
        sk.SpotArm(tool=T32.astype(np.float64))


# ---- messages naming the argument ---------------------------------------------------------------------


def test_messages_name_the_argument():
    arm = SPOT.chain("arm_link_wr1")
    with pytest.raises(ValueError, match=r"^target must have shape \(\.\.\., 4, 4\)"):
        arm.ik(np.zeros((3, 3)), np.zeros(6))
    with pytest.raises(ValueError, match=r"^target must have shape"):
        arm.ik(np.zeros((3, 3)))
    with pytest.raises(TypeError, match=r"^target must be a real numeric array"):
        arm.ik("pose", np.zeros(6))
    with pytest.raises(ValueError, match=r"^target \(5, 4, 4\) and seed \(3, 6\) do not broadcast"):
        arm.ik(np.tile(np.eye(4), (5, 1, 1)), np.zeros((3, 6)))
    leg = sk.Chain.from_mdh(LEG_MDH_ROWS, tool=sk.translation([0.3365, 0.0, 0.0]))
    with pytest.raises(ValueError, match=r"^target must have shape \(\.\.\., 3\)"):
        leg.ik(np.zeros(4), np.zeros(3))
    with pytest.raises(TypeError, match=r"^link must be a link name \(str\), got list"):
        SPOT.chain(link=["arm_link_wr1"])
    with pytest.raises(TypeError, match=r"^base must be a link name \(str\), got list"):
        SPOT.chain("arm_link_wr1", base=["body"])
    text = Path(sk.robots.path("go2")).read_text()
    with pytest.raises(TypeError, match=r"^feet must be a link name or a sequence of link names, got int"):
        sk.Robot.from_urdf_string(text, feet=1)
    with pytest.raises(TypeError, match=r"^feet must hold link names \(str\), got int"):
        sk.Robot.from_urdf_string(text, feet=[1, 2])
    chain = SPOT.chain("arm_link_wr1")
    zeros = np.zeros(chain.dof)
    with pytest.raises(TypeError, match=r"^inertials must be a LinkInertials"):
        sk.dynamics.inverse_dynamics(chain, zeros, zeros, zeros, inertials=1)
    with pytest.raises(TypeError, match=r"^inertials.mass must be a real numeric array"):
        sk.dynamics.inverse_dynamics(chain, zeros, zeros, zeros, inertials=("a", "b", "c"))
    with pytest.raises(TypeError, match=r"^text must be a str or bytes holding URDF XML, got NoneType"):
        urdf.parse_urdf(None)
    with pytest.raises(TypeError, match=r"^n must be an integer, got float"):
        sk.inertia.link_inertials([1.0], [[0.0, 0.0, 0.0]], [np.eye(3)], n=1.5)
    with pytest.raises(ValueError, match=r"^n must be a count >= 0"):
        sk.inertia.link_inertials([1.0], [[0.0, 0.0, 0.0]], [np.eye(3)], n=-1)
    with pytest.raises(TypeError, match=r"^name must be a str or None, got int"):
        sk.Leg(0.1, 0.3, 0.3, name=1)
    with pytest.raises(TypeError, match=r"^name must be a str or None, got int"):
        sk.Leg.from_geometry([0, 0.1, 0], [0, 0, -0.3], [0, 0, -0.3], name=1)
    assert sk.Leg(0.1, 0.3, 0.3, name="fl").name == "fl"


# ---- processes, pickles, documentation ----------------------------------------------------------------


def _descendants(pid: int) -> list[int]:
    """The process ids below ``pid`` (psutil when installed, else /proc)."""
    try:
        import psutil
    except ImportError:
        parents = {}
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                try:
                    with open(f"/proc/{entry}/stat") as stat:
                        fields = stat.read().rsplit(")", 1)[1].split()
                except OSError:
                    continue
                parents.setdefault(int(fields[1]), []).append(int(entry))
        found, stack = [], [pid]
        while stack:
            children = parents.get(stack.pop(), [])
            found += children
            stack += children
        return found
    try:
        return [child.pid for child in psutil.Process(pid).children(recursive=True)]
    except psutil.NoSuchProcess:
        return []


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"  # a zombie has ended
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_processes_workers_end_with_a_killed_batch(tmp_path):
    # reported: after a SIGKILL of `spotkin batch --scheduler processes`, its workers lived on
    pytest.importorskip("dask.array")
    zarr = pytest.importorskip("zarr")
    rng = np.random.default_rng(5)
    p = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0]) + rng.normal(0, 0.02, (1_000_000, 6))
    np.save(tmp_path / "poses.npy", p)
    np.save(tmp_path / "feet.npy", SPOT.stance_feet(0.5))
    out = str(tmp_path / "out.zarr")
    command = [sys.executable, "-m", "spotkin", "batch", "body-ik", "--poses", str(tmp_path / "poses.npy")]
    command += ["--feet", str(tmp_path / "feet.npy"), "--out", out, "--chunk-size", "2000"]
    command += ["--scheduler", "processes", "--workers", "2", "--quiet"]
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers: list[int] = []
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        workers = _descendants(proc.pid)
        try:
            done = int(np.count_nonzero(zarr.open_group(out, mode="r")["chunks_done"][...]))
        except Exception:  # not created yet
            done = 0
        if len(workers) >= 2 and done >= 2:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    workers = _descendants(proc.pid)
    assert workers, "no worker process found"
    proc.kill()
    proc.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(pid) for pid in workers):
        time.sleep(0.1)
    survivors = [pid for pid in workers if _alive(pid)]
    for pid in survivors:  # leave nothing behind, whatever the outcome
        os.kill(pid, signal.SIGKILL)
    assert not survivors, f"{len(survivors)} of {len(workers)} worker processes outlived the killed batch"


def test_the_floating_base_pickles():
    # reported: pickle.dumps(robot.floating_base) raised TypeError
    for robot in (SPOT, sk.Robot.from_urdf(sk.robots.path("go2"))):
        floating = robot.floating_base
        copy = pickle.loads(pickle.dumps(floating))
        rng = np.random.default_rng(2)
        q = np.concatenate([[0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 1.0], rng.uniform(-0.5, 0.5, floating.nq - 7)])
        v = rng.normal(0, 1, floating.nv)
        assert copy.nq == floating.nq and copy.mass == floating.mass
        for method, arguments in (
            ("inverse_dynamics", (q, v, v)),
            ("mass_matrix", (q,)),
            ("forward_dynamics", (q, v, v)),
            ("center_of_mass", (q,)),
        ):
            np.testing.assert_array_equal(
                getattr(copy, method)(*arguments), getattr(floating, method)(*arguments)
            )


def test_the_chunking_guarantee_is_documented():
    # one register width per level, whatever the batch's size: a sample's bits do not depend on
    # the batch around it (tests/test_dynamics.py checks it); said where the thread-count
    # guarantee is, and no longer the old narrow model's "may differ in the last bit"
    root = Path(__file__).resolve().parent.parent
    pages = ("docs/guide/dynamics.md", "docs/dynamics.md")
    texts = [(root / name).read_text(encoding="utf-8") for name in pages]
    texts.append(sk.dynamics.FloatingBase.__doc__)
    for text in texts:
        flat = " ".join(text.split())
        assert "any chunking of a batch into calls, a single sample included" in flat, text[:80]
        assert "narrow model" not in flat, text[:80]
