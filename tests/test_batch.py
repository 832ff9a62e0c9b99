"""``spotkin batch`` (issue 20): batch kernels over .npy and Zarr datasets into a Zarr group, chunk by
chunk on Dask's schedulers; bit-identical to the in-memory calls; every input checked before any work;
memory bounded by the chunk size (peak RSS); a killed run (the whole command, a worker process of the
multiprocessing scheduler, a worker of a distributed cluster) resumes without redoing finished chunks
and ends identical to an uninterrupted run."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import spotkin as sk
from spotkin.__main__ import main

pytest.importorskip("dask.array", reason='spotkin batch needs Dask: pip install "spotkin[dask]"')
zarr = pytest.importorskip("zarr", reason='spotkin batch needs Zarr: pip install "spotkin[dask]"')

SPOT = sk.Spot()
GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))
SPOT_URDF = sk.Robot.from_urdf(sk.robots.path("spot_with_arm"))
FEET = SPOT.stance_feet(0.5)
COMMAND = [sys.executable, "-m", "spotkin", "batch"]


def poses(n: int, seed: int = 0, nan_rows=(3, 100)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    p = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0]) + rng.normal(0, 1, (n, 6)) * [
        0.03,
        0.03,
        0.03,
        0.06,
        0.06,
        0.06,
    ]
    for row in nan_rows:
        if row < n:
            p[row, row % 6] = np.nan  # NaN rows give statuses, as everywhere
    return p


def same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def save(folder, name: str, array) -> str:
    path = os.path.join(folder, f"{name}.npy")
    np.save(path, array)
    return path


def read_output(out: str) -> dict:
    group = zarr.open_group(out, mode="r")
    return {name: group[name][...] for name in group.array_keys()}


def assert_output(out: str, expected: dict) -> None:
    got = read_output(out)
    assert sorted(got) == sorted(expected), (sorted(got), sorted(expected))
    for name, want in expected.items():
        assert same(got[name], want), name
    attrs = dict(zarr.open_group(out, mode="r").attrs)["spotkin_batch"]
    assert attrs["complete"] is True


# ---- every operation ----------------------------------------------------------------------------------

N = 1000  # 8 chunks of 128 (the last one short): every chunk boundary and the whole batch's tail


def _cases(folder):
    """operation -> (arguments, expected fields), with the in-memory results."""
    rng = np.random.default_rng(4)
    p = poses(N)
    body = SPOT.body_ik(p, FEET)
    twist = np.array([0.05, 0.0, 0.02, 0.0, 0.1, 0.2])
    leg = SPOT.leg("hl")
    q3 = rng.uniform(leg.limits[:, 0], leg.limits[:, 1], (N, 3))
    targets3 = leg.fk(q3)
    targets3[7] = np.nan
    arm = SPOT.arm
    q6 = rng.uniform(arm.limits[:, 0], arm.limits[:, 1], (N, 6))
    T = arm.fk(q6)
    chain = GO2.chain("FL_foot")
    qc = rng.uniform(chain.lower, chain.upper, (N, 3))
    pc = chain.fk(qc)[:, :3, 3]
    urdf_arm = SPOT_URDF.arm
    qu = rng.uniform(urdf_arm.lower, urdf_arm.upper, (N, 6))
    Tu = urdf_arm.fk(qu)
    f = {  # the input files
        "poses": save(folder, "poses", p),
        "feet": save(folder, "feet", FEET),
        "seed12": save(folder, "seed12", body.q[0]),
        "q12": save(folder, "q12", body.q),
        "twist": save(folder, "twist", twist),
        "targets3": save(folder, "targets3", targets3),
        "q3": save(folder, "q3", q3),
        "T": save(folder, "T", T),
        "q6": save(folder, "q6", q6),
        "pc": save(folder, "pc", pc),
        "qc": save(folder, "qc", qc),
        "Tu": save(folder, "Tu", Tu),
    }
    # dynamics: the Go2 leg's chain and the Spot-with-arm robot's floating base
    qd, qdd = rng.normal(0, 1.0, (2, N, 3))
    tau = chain.inverse_dynamics(qc, qd, qdd)
    floating = SPOT_URDF.floating_base
    q_legs = np.tile([0.0, 0.9, -1.6], 4) + rng.normal(0, 0.1, (N, 12))
    qf = SPOT_URDF.floating_q(p, q_legs)
    vf, af = rng.normal(0, 1.0, (2, N, floating.nv))
    tauf = floating.inverse_dynamics(qf, vf, af)
    stance = np.ones((N, 4), dtype=bool)
    stance[::5, 2] = False
    f.update(
        {
            name: save(folder, name, value)
            for name, value in (
                ("qd", qd),
                ("qdd", qdd),
                ("tau", tau),
                ("qf", qf),
                ("vf", vf),
                ("af", af),
                ("tauf", tauf),
                ("q_legs", q_legs),
                ("stance", stance),
            )
        }
    )
    chain_args = ["--robot", "go2", "--link", "FL_foot", "--q", f["qc"]]
    floating_args = ["--robot", "spot_with_arm", "--q", f["qf"]]

    def fields(result, single=None):
        if not isinstance(result, tuple):
            return {single: result}
        names = getattr(type(result), "_fields", ("q", "status"))
        return dict(zip(names, result))

    return {
        "body-ik": (
            ["--poses", f["poses"], "--feet", f["feet"], "--seed", f["seed12"], "--fallback", "nan"],
            fields(SPOT.body_ik(p, FEET, seed=body.q[0], fallback="nan")),
        ),
        "body-fk": (["--poses", f["poses"], "--q", f["q12"]], fields(SPOT.body_fk(p, body.q), "feet")),
        "body-jacobian": (
            ["--poses", f["poses"], "--q", f["q12"], "--seq", "xyz"],
            fields(SPOT.body_jacobian(p, body.q, seq="xyz"), "J"),
        ),
        "body-rates": (
            ["--poses", f["poses"], "--q", f["q12"], "--twist", f["twist"]],
            fields(SPOT.body_rates(p, body.q, twist)),
        ),
        "leg-ik": (
            ["--leg", "hl", "--targets", f["targets3"], "--seed", f["q3"]],
            fields(leg.ik(targets3, seed=q3)),
        ),
        "leg-ik-all": (["--leg", "hl", "--targets", f["targets3"]], fields(leg.ik_all(targets3))),
        "leg-fk": (["--leg", "hl", "--q", f["q3"]], fields(leg.fk(q3), "p")),
        "leg-jacobian": (["--leg", "hl", "--q", f["q3"]], fields(leg.jacobian(q3), "J")),
        "arm-ik": (["--targets", f["T"], "--seed", f["q6"]], fields(arm.ik(T, seed=q6))),
        "arm-ik-all": (["--targets", f["T"]], fields(arm.ik_all(T))),
        "arm-fk": (["--q", f["q6"]], fields(arm.fk(q6), "T")),
        "arm-jacobian": (["--q", f["q6"]], fields(arm.jacobian(q6), "J")),
        "chain-fk": (["--robot", "go2", "--link", "FL_foot", "--q", f["qc"]], fields(chain.fk(qc), "T")),
        "chain-jacobian": (
            ["--robot", "go2", "--link", "FL_foot", "--q", f["qc"], "--frame", "tool"],
            fields(chain.jacobian(qc, frame="tool"), "J"),
        ),
        "chain-ik": (
            ["--robot", "go2", "--link", "FL_foot", "--targets", f["pc"], "--seed", f["qc"]],
            fields(chain.ik(pc, seed=qc)),
        ),
        "chain-ik-all": (
            ["--robot", "go2", "--link", "FL_foot", "--targets", f["pc"]],
            fields(chain.ik_position(pc)),
        ),
        "arm-ik[urdf]": (
            ["--robot", "spot_with_arm", "--targets", f["Tu"]],
            fields(urdf_arm.ik(Tu)),
        ),
        "chain-inverse-dynamics": (
            [*chain_args, "--qd", f["qd"], "--qdd", f["qdd"], "--gravity", "0", "0", "-9.8"],
            fields(chain.inverse_dynamics(qc, qd, qdd, (0.0, 0.0, -9.8)), "tau"),
        ),
        "chain-forward-dynamics": (
            [*chain_args, "--qd", f["qd"], "--tau", f["tau"]],
            fields(chain.forward_dynamics(qc, qd, tau), "qdd"),
        ),
        "chain-mass-matrix": (chain_args, fields(chain.mass_matrix(qc), "A")),
        "chain-gravity": (chain_args, fields(chain.gravity(qc), "G")),
        "floating-inverse-dynamics": (
            [*floating_args, "--qd", f["vf"], "--qdd", f["af"]],
            fields(floating.inverse_dynamics(qf, vf, af), "tau"),
        ),
        "floating-forward-dynamics": (
            [*floating_args, "--qd", f["vf"], "--tau", f["tauf"], "--gravity", "0", "0", "-3.7"],
            fields(floating.forward_dynamics(qf, vf, tauf, (0.0, 0.0, -3.7)), "qdd"),
        ),
        "floating-mass-matrix": (floating_args, fields(floating.mass_matrix(qf), "A")),
        "standing-torques": (
            ["--robot", "spot_with_arm", "--poses", f["poses"], "--q", f["q_legs"], "--stance", f["stance"]],
            fields(SPOT_URDF.standing_torques(p, q_legs, stance=stance)),
        ),
    }


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    folder = tmp_path_factory.mktemp("batch-inputs")
    return _cases(str(folder))


OPERATIONS = [
    "body-ik",
    "body-fk",
    "body-jacobian",
    "body-rates",
    "leg-ik",
    "leg-ik-all",
    "leg-fk",
    "leg-jacobian",
    "arm-ik",
    "arm-ik-all",
    "arm-fk",
    "arm-jacobian",
    "chain-fk",
    "chain-jacobian",
    "chain-ik",
    "chain-ik-all",
    "arm-ik[urdf]",
    "chain-inverse-dynamics",
    "chain-forward-dynamics",
    "chain-mass-matrix",
    "chain-gravity",
    "floating-inverse-dynamics",
    "floating-forward-dynamics",
    "floating-mass-matrix",
    "standing-torques",
]


def test_the_operations_listed_are_the_cli_s():
    from spotkin.scale import batch_operations

    assert sorted(batch_operations.OPERATIONS) == sorted(op for op in OPERATIONS if "[" not in op)


@pytest.mark.parametrize("operation", OPERATIONS)
def test_every_operation_matches_the_in_memory_call(operation, cases, tmp_path, capsys):
    arguments, expected = cases[operation]
    out = str(tmp_path / "out.zarr")
    name = operation.split("[")[0]
    scheduler = "synchronous" if operation.startswith("leg") else "threads"
    code = main(["batch", name, *arguments, "--out", out, "--chunk-size", "128", "--scheduler", scheduler])
    err = capsys.readouterr().err
    assert code == 0, err
    assert_output(out, expected)
    assert re.search(r"100\.0% 1,000/1,000 samples \| .* samples/s \| elapsed \S+ \| ETA \S+", err), err


def test_zarr_inputs_and_their_chunking(tmp_path, capsys):
    p = poses(1000)
    store = str(tmp_path / "inputs.zarr")
    group = zarr.open_group(store, mode="w")
    create = group.create_array if hasattr(group, "create_array") else group.create_dataset
    create("poses", shape=p.shape, chunks=(100, 6), dtype=p.dtype)[...] = p
    create("feet", shape=FEET.shape, chunks=(2, 3), dtype=FEET.dtype)[...] = FEET
    out = str(tmp_path / "out.zarr")
    arguments = ["batch", "body-ik", "--poses", f"{store}/poses", "--feet", f"{store}/feet", "--out", out]
    assert main([*arguments, "--chunk-size", "300"]) == 0
    assert_output(out, dict(SPOT.body_ik(p, FEET)._asdict()))
    capsys.readouterr()
    # a chunk size that cuts the input's stored chunks: one clear error, nothing written
    out2 = str(tmp_path / "out2.zarr")
    assert main([*arguments[:-1], out2, "--chunk-size", "250"]) == 2
    err = capsys.readouterr().err
    assert (
        "chunking: --chunk-size 250 is not a multiple of the chunks of --poses" in err and "(100 rows)" in err
    )
    assert not os.path.exists(out2)
    # the default chunk size is a multiple of the stored chunks
    assert main([*arguments[:-1], out2, "--quiet"]) == 0
    attrs = dict(zarr.open_group(out2, mode="r").attrs)["spotkin_batch"]
    assert attrs["chunk_size"] % 100 == 0
    assert_output(out2, dict(SPOT.body_ik(p, FEET)._asdict()))
    # a group is not an array
    assert main(["batch", "body-ik", "--poses", store, "--feet", f"{store}/feet", "--out", out2 + "x"]) == 2
    assert "group.zarr/name" in capsys.readouterr().err


def test_float32_and_multi_dimensional_batches(tmp_path, capsys):
    p = poses(300).astype(np.float32).reshape(30, 10, 6)
    f32 = FEET.astype(np.float32)
    folder = str(tmp_path)
    out = str(tmp_path / "out.zarr")
    arguments = ["--poses", save(folder, "p", p), "--feet", save(folder, "f", f32), "--out", out]
    assert main(["batch", "body-ik", *arguments, "--chunk-size", "7", "--quiet"]) == 0
    assert_output(out, dict(SPOT.body_ik(p, f32)._asdict()))
    assert read_output(out)["q"].dtype == np.float32
    T = SPOT.arm.fk(np.random.default_rng(0).uniform(-1, 1, (50, 3, 6)))  # the arm's blocked kernel
    out = str(tmp_path / "arm.zarr")
    assert (
        main(["batch", "arm-ik-all", "--targets", save(folder, "T", T), "--out", out, "--chunk-size", "3"])
        == 0
    )
    assert_output(out, dict(SPOT.arm.ik_all(T)._asdict()))


# ---- checks before any work -------------------------------------------------------------------------------


@pytest.fixture
def files(tmp_path):
    folder = str(tmp_path)
    p = poses(200)
    with open(os.path.join(folder, "text.npy"), "w") as handle:
        handle.write("not an array")
    return {
        "poses": save(folder, "poses", p),
        "poses5": save(folder, "poses5", p[:, :5]),
        "short": save(folder, "short", p[:150]),
        "complex": save(folder, "complex", p.astype(complex)),
        "strings": save(folder, "strings", p.astype(str)),
        "feet": save(folder, "feet", FEET),
        "feet_n": save(folder, "feet_n", np.broadcast_to(FEET, (150, 4, 3))),
        "single": save(folder, "single", p[0]),
        "text": os.path.join(folder, "text.npy"),
        "folder": folder,
    }


BAD = [
    (
        ["--poses", "{poses5}", "--feet", "{feet}"],
        r"body_pose must have shape \(\.\.\., 6\).*got \(200, 5\).*--poses",
    ),
    (
        ["--poses", "{poses}", "--feet", "{feet_n}"],
        r"body_pose \(200, 6\) and feet \(150, 4, 3\) do not broadcast",
    ),
    (
        ["--poses", "{complex}", "--feet", "{feet}"],
        r"--poses .*complex.npy: dtype complex128 is not a real number type",
    ),
    (
        ["--poses", "{strings}", "--feet", "{feet}"],
        r"--poses .*strings.npy: dtype <U32 is not a real number type",
    ),
    (["--poses", "{text}", "--feet", "{feet}"], r"--poses .*text.npy: not a readable \.npy array"),
    (
        ["--poses", "{folder}/missing.npy", "--feet", "{feet}"],
        r"--poses .*missing.npy: no such file or Zarr array",
    ),
    (["--poses", "{single}", "--feet", "{feet}"], r"no batch axis"),
    (["--poses", "{poses}", "--feet", "{feet}", "--seq", "abc"], r"seq must be one of"),
    (["--poses", "{poses}", "--feet", "{feet}", "--robot", "nope"], r"--robot nope: not 'spot'"),
    (["--poses", "{poses}", "--feet", "{feet}", "--robot", "{text}"], r"--robot .*text.npy: "),
    (["--poses", "{poses}", "--feet", "{feet}", "--scheduler", "thread"], r"--scheduler thread: neither"),
]


@pytest.mark.parametrize(("arguments", "message"), BAD)
def test_bad_inputs_give_one_clear_error_before_any_work(arguments, message, files, tmp_path, capsys):
    out = str(tmp_path / "never.zarr")
    code = main(["batch", "body-ik", *(a.format(**files) for a in arguments), "--out", out])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("spotkin batch body-ik: error: "), err
    assert re.search(message, err), err
    assert not os.path.exists(out)


def test_bad_models_and_options(files, tmp_path, capsys):
    out = str(tmp_path / "never.zarr")
    q3 = save(files["folder"], "q3", np.zeros((10, 3)))
    for arguments, message in (
        (["leg-fk", "--leg", "XX", "--q", q3], r"leg name must be one of \('fl', 'fr', 'hl', 'hr'\)"),
        (["arm-fk", "--robot", "go2", "--q", q3], "this robot has no arm"),
        (["chain-fk", "--link", "nope", "--q", q3], "nope"),
        (["chain-ik", "--robot", "spot_with_arm", "--link", "arm_link_el0", "--targets", q3], "closed form"),
        (["arm-fk", "--q", q3], r"q must have shape \(\.\.\., 6\), got \(10, 3\)"),
    ):
        assert main(["batch", *arguments, "--out", out]) == 2
        err = capsys.readouterr().err
        assert re.search(message, err), err
        assert not os.path.exists(out)
    with pytest.raises(SystemExit) as exit_info:  # argparse: a missing required input
        main(["batch", "body-ik", "--poses", files["poses"], "--out", out])
    assert exit_info.value.code == 2 and "--feet" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(
            [
                "batch",
                "body-ik",
                "--poses",
                files["poses"],
                "--feet",
                files["feet"],
                "--out",
                out,
                "--chunk-size",
                "0",
            ]
        )
    assert "--chunk-size" in capsys.readouterr().err


def test_outputs_are_protected_and_resumed_runs_must_match(files, tmp_path, capsys):
    folder = tmp_path / "not-zarr"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    base = ["batch", "body-ik", "--poses", files["poses"], "--feet", files["feet"], "--quiet"]
    for flags in ([], ["--overwrite"]):  # a folder of other files is never replaced
        assert main([*base, "--out", str(folder), *flags]) == 2
        assert "is not a Zarr group" in capsys.readouterr().err
    assert (folder / "notes.txt").read_text() == "mine"
    out = str(tmp_path / "out.zarr")
    assert main([*base, "--out", out, "--chunk-size", "64"]) == 0
    before = {p: os.stat(p).st_mtime_ns for p in _files(out)}
    assert main([*base, "--out", out]) == 0  # complete: nothing is redone (the chunk size is the run's)
    assert {p: os.stat(p).st_mtime_ns for p in _files(out)} == before
    assert main([*base, "--out", out, "--chunk-size", "32"]) == 2
    assert "holds a run with other chunk_size" in capsys.readouterr().err
    other = [
        "batch",
        "body-ik",
        "--poses",
        files["poses"],
        "--feet",
        files["feet"],
        "--fallback",
        "nan",
        "--quiet",
    ]
    assert main([*other, "--out", out]) == 2
    assert "holds a run with other options" in capsys.readouterr().err
    assert main([*other, "--out", out, "--overwrite"]) == 0
    assert_output(out, dict(SPOT.body_ik(np.load(files["poses"]), FEET, fallback="nan")._asdict()))


def test_dry_run_checks_and_writes_nothing(files, tmp_path, capsys):
    out = str(tmp_path / "out.zarr")
    command = ["batch", "body-ik", "--poses", files["poses"], "--feet", files["feet"], "--out", out]
    assert main([*command, "--dry-run", "--chunk-size", "64"]) == 0
    text = capsys.readouterr().out
    assert "200 samples in 4 chunks of 64" in text and "q float64 (200, 12), status int8 (200, 4)" in text
    assert not os.path.exists(out)


def _files(folder: str) -> list:
    return [os.path.join(d, f) for d, _, names in os.walk(folder) for f in names]


# ---- without the extra -------------------------------------------------------------------------------------


def test_without_dask_or_zarr_the_command_says_what_to_install(files, tmp_path):
    for blocked in ("dask", "zarr"):
        code = (
            "import sys, importlib.abc\n"
            "class Block(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, name, path=None, target=None):\n"
            f"        if name.split('.')[0] == {blocked!r}:\n"
            "            raise ImportError(f'No module named {name!r} (blocked)')\n"
            "sys.meta_path.insert(0, Block())\n"
            "from spotkin.__main__ import main\n"
            "sys.exit(main(sys.argv[1:]))\n"
        )
        arguments = ["batch", "body-ik", "--poses", files["poses"], "--feet", files["feet"], "--out"]
        result = subprocess.run(
            [sys.executable, "-c", code, *arguments, str(tmp_path / "o.zarr")],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert result.returncode == 1, result.stderr
        assert (
            'spotkin batch needs Dask and Zarr: install them with pip install "spotkin[dask]"'
            in result.stderr
        )
        assert "Traceback" not in result.stderr
        # the rest of the command line works without them
        result = subprocess.run(
            [sys.executable, "-c", code, "inspect", sk.robots.path("go2")],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert result.returncode == 0 and "FL" in result.stdout, result.stderr


# ---- memory, kills and resumes (subprocesses) ------------------------------------------------------------


def _done(out: str) -> int:
    """Chunks marked done so far (while a run writes them)."""
    try:
        group = zarr.open_group(out, mode="r")
        if "chunks_done" not in set(group.array_keys()):
            attrs = dict(group.attrs).get("spotkin_batch", {})
            return attrs.get("chunks", 0) if attrs.get("complete") else 0
        return int(np.count_nonzero(group["chunks_done"][...]))
    except Exception:  # the group is being created
        return 0


def _wait_for(out: str, chunks: int, proc, timeout: float = 120.0) -> int:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        done = _done(out)
        if done >= chunks or proc.poll() is not None:
            return done
        time.sleep(0.01)
    raise AssertionError("the run made no progress")


@pytest.fixture(scope="module")
def big(tmp_path_factory):
    """2e6 poses (96 MB; the outputs 200 MB) and the in-memory result."""
    folder = str(tmp_path_factory.mktemp("batch-big"))
    p = poses(2_000_000, 9, nan_rows=(5, 1_234_567))
    reference = SPOT.body_ik(p, FEET)
    return {"poses": save(folder, "poses", p), "feet": save(folder, "feet", FEET), "reference": reference}


def _command(big, out, *extra):
    return [*COMMAND, "body-ik", "--poses", big["poses"], "--feet", big["feet"], "--out", out, *extra]


def _peak_rss(command) -> tuple[int, str]:
    """(peak RSS in bytes, stderr) of a command run in a fresh process of its own."""
    probe = (
        "import resource, subprocess, sys\n"
        "result = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
        "sys.stderr.write(result.stderr)\n"
        "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n"
        "sys.exit(result.returncode)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe, *command], capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr
    return int(result.stdout.split()[-1]) * 1024, result.stderr


def test_memory_stays_bounded_by_the_chunk_size(big, tmp_path):
    """2e6 poses in chunks of 5e4 on 2 threads: the peak RSS grows by a few chunks' worth over the
    same command's --dry-run (imports and checks), far below the 300 MB of input and outputs."""
    out = str(tmp_path / "out.zarr")
    baseline, _ = _peak_rss(_command(big, out, "--dry-run"))
    peak, err = _peak_rss(_command(big, out, "--chunk-size", "50000", "--workers", "2"))
    data = os.path.getsize(big["poses"]) + big["reference"].q.nbytes + big["reference"].status.nbytes
    chunk = 50_000 * (6 * 8 + 12 * 8 + 4)  # one chunk's input and outputs: 7.4 MB
    growth = peak - baseline
    print(
        f"\npeak RSS {peak / 2**20:.0f} MiB, --dry-run {baseline / 2**20:.0f} MiB: +{growth / 2**20:.0f} MiB "
        f"for {data / 2**20:.0f} MiB of input and output ({chunk / 2**20:.1f} MiB per chunk)"
    )
    assert growth < 12 * chunk < data / 3, err
    assert_output(out, dict(big["reference"]._asdict()))


def test_a_killed_run_resumes_without_redoing_chunks(big, tmp_path):
    """SIGKILL mid-run (no chance to clean up), then the same command: the finished chunks stay as they
    were, the rest is done, and the output equals an uninterrupted run's and the in-memory call's."""
    out = str(tmp_path / "out.zarr")
    extra = ("--chunk-size", "5000", "--workers", "1")  # 400 chunks
    proc = subprocess.Popen(_command(big, out, *extra), stderr=subprocess.PIPE, stdout=subprocess.DEVNULL)
    done = _wait_for(out, 40, proc)
    proc.kill()
    proc.wait()
    stderr = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.returncode == -signal.SIGKILL, stderr
    done = _done(out)
    assert 40 <= done < 400, done
    kept = {path: os.stat(path).st_mtime_ns for path in _files(os.path.join(out, "q"))}
    result = subprocess.run(_command(big, out, *extra), capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    assert f"resuming: {done:,} of 400 chunks were done" in result.stderr
    unchanged = sum(
        os.stat(path).st_mtime_ns == stamp for path, stamp in kept.items() if os.path.exists(path)
    )
    assert unchanged >= done  # each finished chunk's q file was left alone
    assert not any(path.endswith(".partial") for path in _files(out))
    uninterrupted = str(tmp_path / "uninterrupted.zarr")
    assert (
        main(
            [
                "batch",
                "body-ik",
                "--poses",
                big["poses"],
                "--feet",
                big["feet"],
                "--out",
                uninterrupted,
                "--chunk-size",
                "5000",
                "--quiet",
            ]
        )
        == 0
    )
    assert_output(out, read_output(uninterrupted))
    assert_output(out, dict(big["reference"]._asdict()))


def test_a_killed_worker_process_of_the_multiprocessing_scheduler(big, tmp_path):
    psutil = pytest.importorskip("psutil")
    out = str(tmp_path / "out.zarr")
    extra = ("--chunk-size", "10000", "--scheduler", "processes", "--workers", "2")  # 200 chunks
    proc = subprocess.Popen(_command(big, out, *extra), stderr=subprocess.PIPE, stdout=subprocess.DEVNULL)
    _wait_for(out, 20, proc)
    workers = [
        child
        for child in psutil.Process(proc.pid).children(recursive=True)
        if "resource_tracker" not in " ".join(child.cmdline())
    ]
    assert workers, "no worker process found"
    workers[0].kill()
    _, stderr = proc.communicate(timeout=300)
    stderr = stderr.decode()
    if proc.returncode == 0:  # the run ended before the kill landed: nothing to resume
        pytest.skip("the run finished before its worker was killed")
    assert proc.returncode == 1, stderr
    assert "run the same command again to resume" in stderr
    done = _done(out)
    result = subprocess.run(_command(big, out, *extra), capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    assert f"resuming: {done:,} of 200 chunks were done" in result.stderr
    assert_output(out, dict(big["reference"]._asdict()))


def test_a_distributed_cluster_with_a_worker_killed_mid_run(big, tmp_path, cluster):
    """The same command against a scheduler address; a worker process killed mid-run is restarted by
    its nanny and its chunks are run again: the output is the in-memory result."""
    local, client = cluster
    out = str(tmp_path / "out.zarr")
    extra = ("--chunk-size", "10000", "--scheduler", local.scheduler_address)  # 200 chunks
    proc = subprocess.Popen(_command(big, out, *extra), stderr=subprocess.PIPE, stdout=subprocess.DEVNULL)
    _wait_for(out, 20, proc)
    pids = client.run(os.getpid)
    os.kill(next(iter(pids.values())), signal.SIGKILL)
    _, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr.decode()
    assert "ETA" in stderr.decode()
    assert_output(out, dict(big["reference"]._asdict()))
