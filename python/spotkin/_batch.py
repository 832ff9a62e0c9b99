"""``spotkin batch``: spotkin's batch kernels over datasets on disk, chunk by chunk, on a Dask scheduler.

Inputs are ``.npy`` files (read through memory maps, one per chunk) or Zarr arrays; the output is
a Zarr group with one array per result field (``q``, ``status``, ...). The batch axis (the first
leading axis) is cut into chunks of ``--chunk-size`` samples; each chunk is one task that reads its
rows, runs the in-memory kernel (the same per-chunk call as :mod:`spotkin.dask`), writes its output
chunks and then marks itself done. Hence:

- memory is bounded by the chunk size (times the workers), whatever the dataset's size;
- a run that is stopped (Ctrl-C, a kill, a lost worker) and started again with the same command
  redoes only the chunks not marked done, and its output is identical to an uninterrupted run's
  (a chunk's result does not depend on the chunking nor on the thread count);
- everything is checked before any work starts (files, shapes, dtypes, chunking, options, the
  output), with one error message.

The scheduler is Dask's: ``threads`` (the kernels release the GIL), ``processes``,
``synchronous``, or a ``dask.distributed`` scheduler address (``tcp://host:8786``).

This module imports Dask and Zarr only when a batch runs, so ``spotkin demo`` and ``spotkin
inspect`` work without them.
"""

from __future__ import annotations

import argparse
import functools
import math
import os
import re
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from . import robots
from ._support.version import __version__

INSTALL = 'pip install "spotkin[dask]"'
DONE = "chunks_done"  # the per-chunk completion markers, removed once the run is complete
ATTRIBUTE = "spotkin_batch"  # the group attribute describing the run
DEFAULT_CHUNK_BYTES = 32 << 20  # inputs + outputs of one chunk, for the default chunk size
FORMAT = 1
LOCAL_SCHEDULERS = ("threads", "processes", "synchronous", "sync", "single-threaded")


class BatchError(Exception):
    """An input, option or output that cannot be used: reported before any work starts."""


def require():
    """(dask, zarr), or ImportError saying what to install."""
    try:
        import dask
        import dask.array
        import zarr
    except ImportError as error:
        raise ImportError(
            f"spotkin batch needs Dask and Zarr: install them with {INSTALL} "
            f"(dask[array,distributed] and zarr); the import failed with: {error}"
        ) from error
    return dask, zarr


# ---- operations -------------------------------------------------------------------------------------


def _skd():
    from . import dask as skd  # imports Dask: only when a batch is planned

    return skd


@dataclass(frozen=True)
class Operation:
    """One ``spotkin batch`` subcommand: its model, its input files, its options and its plan."""

    model: str  # "robot", "leg", "arm" or "chain"
    inputs: tuple  # (argument name, option, required, help)
    plan: Callable  # (model, dask arrays by argument name, parsed args) -> a spotkin.dask plan
    options: tuple = ()  # the parsed options it passes on (recorded in the output)
    help: str = ""


_POSES = ("body_pose", "--poses", True, "body poses (N, 6) [x, y, z, a, b, c], (N, 7) or (N, 4, 4)")
_Q_BODY = ("q", "--q", True, "leg joints (N, 3 n) in the robot's leg-joint order")
_Q = ("q", "--q", True, "joint values (N, dof)")
_SEED = ("seed", "--seed", False, "seeds (N, dof), or one shared (dof,)")
_POINTS = ("target", "--targets", True, "foot points (N, 3) in the leg frame")
_TOOL = ("target", "--targets", True, "tool poses (N, 4, 4) or (N, 7) in the body frame")
_QD = ("qd", "--qd", True, "joint rates (N, dof)")
_Q_FLOATING = ("q", "--q", True, "floating-base coordinates (N, 7 + n): [x, y, z, qx, qy, qz, qw], joints")
_V_FLOATING = ("qd", "--qd", True, "floating-base velocities (N, 6 + n): [v; w] in the body frame, rates")
_CHAIN_TARGETS = ("target", "--targets", True, "points (N, 3) for 3 joints, tool poses (N, 4, 4) for 6")


# the dynamics plans, shared by a chain's and a floating base's operations
def _inverse_dynamics(model, arrays, options):
    return _skd()._plan_inverse_dynamics(
        model, arrays["q"], arrays["qd"], arrays["qdd"], tuple(options.gravity)
    )


def _forward_dynamics(model, arrays, options):
    return _skd()._plan_forward_dynamics(
        model, arrays["q"], arrays["qd"], arrays["tau"], tuple(options.gravity)
    )


def _mass_matrix(model, arrays, options):
    return _skd()._plan_mass_matrix(model, arrays["q"])


OPERATIONS: dict[str, Operation] = {
    "body-ik": Operation(
        "robot",
        (
            _POSES,
            ("feet", "--feet", True, "world feet (N, n, 3), or one shared stance (n, 3)"),
            ("seed", "--seed", False, "seeds (N, 3 n), or one shared (3 n,)"),
        ),
        lambda m, a, o: _skd()._plan_body_ik(m, a["body_pose"], a["feet"], a.get("seed"), o.seq, o.fallback),
        ("seq", "fallback"),
        "whole-body IK: q (N, 3 n) and status (N, n) from body poses and feet",
    ),
    "body-fk": Operation(
        "robot",
        (_POSES, _Q_BODY),
        lambda m, a, o: _skd()._plan_body_fk(m, a["body_pose"], a["q"], o.seq),
        ("seq",),
        "world feet (N, n, 3) from body poses and leg joints",
    ),
    "body-jacobian": Operation(
        "robot",
        (_POSES, _Q_BODY),
        lambda m, a, o: _skd()._plan_body_jacobian(m, a["body_pose"], a["q"], o.seq),
        ("seq",),
        "whole-body Jacobians J (N, 3 n, 6 + 3 n)",
    ),
    "body-rates": Operation(
        "robot",
        (_POSES, _Q_BODY, ("twist", "--twist", True, "body twists [v; w] (N, 6), or one shared (6,)")),
        lambda m, a, o: _skd()._plan_body_rates(m, a["body_pose"], a["q"], a["twist"], o.seq, o.tolerance),
        ("seq", "tolerance"),
        "joint rates qd (N, 3 n) that keep the feet fixed, and singular (N, n)",
    ),
    "leg-ik": Operation(
        "leg",
        (_POINTS, _SEED),
        lambda m, a, o: _skd()._plan_ik(m, a["target"], a.get("seed"), o.fallback),
        ("fallback",),
        "one leg's IK: q (N, 3) and status (N,)",
    ),
    "leg-ik-all": Operation(
        "leg",
        (_POINTS,),
        lambda m, a, o: _skd()._plan_ik_all(m, a["target"]),
        (),
        "one leg's IK, every branch: q (N, 4, 3), valid, exists (N, 4), status (N,)",
    ),
    "leg-fk": Operation("leg", (_Q,), lambda m, a, o: _skd()._plan_fk(m, a["q"]), (), "foot points p (N, 3)"),
    "leg-jacobian": Operation(
        "leg", (_Q,), lambda m, a, o: _skd()._plan_jacobian(m, a["q"]), (), "leg Jacobians J (N, 3, 3)"
    ),
    "arm-ik": Operation(
        "arm",
        (_TOOL, _SEED),
        lambda m, a, o: _skd()._plan_ik(m, a["target"], a.get("seed")),
        (),
        "the arm's IK, one solution: q (N, 6) and status (N,)",
    ),
    "arm-ik-all": Operation(
        "arm",
        (_TOOL, ("seed", "--seed", False, "seeds (N, 6) for the singular cases (the Spot Arm only)")),
        lambda m, a, o: _skd()._plan_ik_all(m, a["target"], a.get("seed")),
        (),
        "the arm's IK, every solution: q (N, 8, 6), valid, exists (N, 8), status (N,)",
    ),
    "arm-fk": Operation(
        "arm", (_Q,), lambda m, a, o: _skd()._plan_fk(m, a["q"]), (), "the arm's tool poses T (N, 4, 4)"
    ),
    "arm-jacobian": Operation(
        "arm", (_Q,), lambda m, a, o: _skd()._plan_jacobian(m, a["q"]), (), "the arm's Jacobians J (N, 6, 6)"
    ),
    "chain-fk": Operation(
        "chain",
        (_Q,),
        lambda m, a, o: _skd()._plan_fk(m, a["q"]),
        (),
        "tool poses T (N, 4, 4) of the chain from --base to --link",
    ),
    "chain-jacobian": Operation(
        "chain",
        (_Q,),
        lambda m, a, o: _skd()._plan_jacobian(m, a["q"], o.frame),
        ("frame",),
        "Jacobians J (N, 6, dof) of the chain from --base to --link",
    ),
    "chain-ik": Operation(
        "chain",
        (_CHAIN_TARGETS, _SEED),
        lambda m, a, o: _skd()._plan_ik(m, a["target"], a.get("seed")),
        (),
        "closed-form IK of the chain, one solution: q (N, dof) and status (N,)",
    ),
    "chain-ik-all": Operation(
        "chain",
        (_CHAIN_TARGETS,),
        lambda m, a, o: _skd()._plan_ik_all(m, a["target"]),
        (),
        "closed-form IK of the chain, every solution: q, valid, exists, exact, status",
    ),
    # rigid-body dynamics: a chain from the URDF (fixed at --base), or the robot's floating base
    "chain-inverse-dynamics": Operation(
        "chain",
        (_Q, _QD, ("qdd", "--qdd", True, "joint accelerations (N, dof)")),
        _inverse_dynamics,
        ("gravity",),
        "joint torques tau (N, dof) = A(q) qdd + C(q, qd) qd + G(q) of the chain (recursive Newton-Euler)",
    ),
    "chain-forward-dynamics": Operation(
        "chain",
        (_Q, _QD, ("tau", "--tau", True, "joint torques (N, dof)")),
        _forward_dynamics,
        ("gravity",),
        "joint accelerations qdd (N, dof) of the chain under torques tau (articulated-body algorithm)",
    ),
    "chain-mass-matrix": Operation(
        "chain",
        (_Q,),
        _mass_matrix,
        (),
        "joint-space inertia matrices A (N, dof, dof) of the chain (composite-rigid-body algorithm)",
    ),
    "chain-gravity": Operation(
        "chain",
        (_Q,),
        lambda m, a, o: _skd()._plan_gravity(m, a["q"], tuple(o.gravity)),
        ("gravity",),
        "gravity torques G (N, dof) of the chain",
    ),
    "floating-inverse-dynamics": Operation(
        "robot",
        (_Q_FLOATING, _V_FLOATING, ("qdd", "--qdd", True, "accelerations (N, 6 + n): dv/dt")),
        _inverse_dynamics,
        ("gravity",),
        "generalised forces tau (N, 6 + n) of the floating base (body wrench, then joint torques)",
    ),
    "floating-forward-dynamics": Operation(
        "robot",
        (_Q_FLOATING, _V_FLOATING, ("tau", "--tau", True, "generalised forces (N, 6 + n)")),
        _forward_dynamics,
        ("gravity",),
        "accelerations qdd (N, 6 + n) of the floating base under generalised forces tau",
    ),
    "floating-mass-matrix": Operation(
        "robot",
        (_Q_FLOATING,),
        _mass_matrix,
        (),
        "inertia matrices A (N, 6 + n, 6 + n) of the floating base",
    ),
    "standing-torques": Operation(
        "robot",
        (
            _POSES,
            ("q", "--q", True, "joints (N, 3 n) in the robot's leg-joint order, or with the arm's after"),
            ("stance", "--stance", False, "stance feet (N, n) bool, or one shared (n,) (default: all)"),
        ),
        lambda m, a, o: _skd()._plan_standing_torques(
            m, a["body_pose"], a["q"], a.get("stance"), tuple(o.gravity), o.seq
        ),
        ("gravity", "seq"),
        "leg torques tau (N, 3 n) holding the robot still on its feet, forces (N, n, 3), status, margin",
    ),
}


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def add_parser(commands) -> None:
    """The ``batch`` subcommand and its operations, on an argparse subparsers object."""
    batch = commands.add_parser(
        "batch",
        help=f"run a batch kernel over datasets on disk (.npy, Zarr) into a Zarr group ({INSTALL})",
        description=(
            "Run one of spotkin's batch kernels over inputs on disk (.npy files, memory-mapped, or Zarr "
            "arrays), chunk by chunk on a Dask scheduler, into a Zarr group with one array per result "
            "field. Memory stays bounded by the chunk size; a stopped run resumes where it stopped when "
            f"started again with the same command. Needs {INSTALL}."
        ),
    )
    operations = batch.add_subparsers(dest="operation", required=True, metavar="OPERATION")
    for name, operation in OPERATIONS.items():
        model = operation.model
        parser = operations.add_parser(name, help=operation.help, description=operation.help)
        parser.add_argument(
            "--robot",
            default="spot",
            help=f"'spot' (sk.Spot()), a packaged description ({', '.join(robots.NAMES)}) or a URDF path",
        )
        if model == "leg":
            parser.add_argument("--leg", required=True, help="the leg's name (robot.leg_names)")
        if model == "chain":
            parser.add_argument("--link", required=True, help="the chain's last link")
            parser.add_argument("--base", default=None, help="the chain's base link (default: the body)")
        for _, option, required, text in operation.inputs:
            parser.add_argument(
                option,
                required=required,
                metavar="PATH",
                help=f"{text}: a .npy file or a Zarr array" + ("" if required else " (optional)"),
            )
        if "seq" in operation.options:
            parser.add_argument("--seq", default="XYZ", help="Euler sequence of (N, 6) poses (default XYZ)")
        if "fallback" in operation.options:
            parser.add_argument(
                "--fallback",
                choices=("nearest", "nan"),
                default="nearest",
                help="for an unreachable target: the nearest in-limit configuration (default) or NaN",
            )
        if "tolerance" in operation.options:
            parser.add_argument(
                "--tolerance", type=float, default=1e-6, help="singular-value threshold (default 1e-6)"
            )
        if "gravity" in operation.options:
            parser.add_argument(
                "--gravity",
                type=float,
                nargs=3,
                default=[0.0, 0.0, -9.81],  # a list, as the run's record reads back from JSON
                metavar=("GX", "GY", "GZ"),
                help="gravity in the base's (a chain's) or the world's (a robot's) frame, m/s2 "
                "(default 0 0 -9.81)",
            )
        if "frame" in operation.options:
            parser.add_argument(
                "--frame",
                choices=("base", "tool"),
                default="base",
                help="the Jacobian's frame (default base)",
            )
        parser.add_argument("--out", required=True, metavar="PATH", help="the output Zarr group")
        parser.add_argument(
            "--chunk-size",
            type=_positive_int,
            default=None,
            help="samples per chunk along the batch axis (default: about 32 MiB of inputs and outputs; "
            "a multiple of a Zarr input's chunks; a resumed run keeps its own)",
        )
        parser.add_argument(
            "--scheduler",
            default="threads",
            help="threads (default), processes, synchronous, or a dask.distributed scheduler address "
            "(tcp://host:8786)",
        )
        parser.add_argument(
            "--workers",
            type=_positive_int,
            default=None,
            help="threads or processes of a local scheduler (default: the cores)",
        )
        parser.add_argument(
            "--overwrite",
            action="store_true",
            help="discard an existing output (a Zarr group) and start anew",
        )
        parser.add_argument("--dry-run", action="store_true", help="check everything, print the plan, stop")
        parser.add_argument("--quiet", action="store_true", help="no plan and no progress bar")


# ---- inputs ---------------------------------------------------------------------------------------


class Source:
    """An input array on disk: a ``.npy`` file (each read maps it anew, so a chunk's pages leave the
    resident set with the chunk) or a Zarr array. Picklable: it travels as its path."""

    def __init__(self, option: str, path: str) -> None:
        self.option, self.given = option, path
        self.path = path if "://" in path else os.path.abspath(path)  # workers may have another cwd
        self.kind = "npy" if os.path.isfile(path) else "zarr"
        self._zarr = None
        if self.kind == "npy":
            try:
                array = np.load(path, mmap_mode="r", allow_pickle=False)
            except (ValueError, OSError) as error:
                raise BatchError(f"{option} {path}: not a readable .npy array ({error})") from None
            if not isinstance(array, np.ndarray):
                raise BatchError(f"{option} {path}: a .npz archive; give one .npy array")
            stat = os.stat(path)
            self.shape, self.dtype, self.chunk_rows = tuple(array.shape), array.dtype, None
            self.stamp = {"bytes": stat.st_size, "mtime_ns": stat.st_mtime_ns}
            return
        if "://" not in path and not os.path.exists(path):
            raise BatchError(f"{option} {path}: no such file or Zarr array")
        try:
            array = self._array()
        except Exception as error:  # zarr raises several types for "no array here"
            raise BatchError(
                f"{option} {path}: neither a .npy file nor a Zarr array ({type(error).__name__}: {error}); "
                "for an array inside a Zarr group give its path (group.zarr/name)"
            ) from None
        self.shape, self.dtype = tuple(array.shape), np.dtype(array.dtype)
        chunks = getattr(array, "chunks", None)
        self.chunk_rows = int(chunks[0]) if chunks and self.shape else None
        self.stamp = {} if "://" in path else _folder_stamp(self.path)

    def __getstate__(self) -> dict:
        return {key: value for key, value in self.__dict__.items() if key != "_zarr"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _zarr=None)

    def _array(self):
        if self.kind == "npy":
            return np.load(self.path, mmap_mode="r", allow_pickle=False)
        if self._zarr is None:
            _, zarr = require()
            self._zarr = zarr.open_array(self.path, mode="r")
        return self._zarr

    def read(self, rows: slice | None) -> np.ndarray:
        """Rows ``rows`` of the batch axis, or the whole array (None)."""
        array = self._array()
        return np.asarray(array[rows] if rows is not None else array[...])

    @property
    def fingerprint(self) -> dict:
        """What a resumed run must find again: path, shape, dtype, and a file's size and time (a local
        Zarr array's files' count, total size and latest time; a remote one's are not read)."""
        return {
            "path": self.path,
            "shape": list(self.shape),
            "dtype": self.dtype.str,
            **self.stamp,
        }

    # the array protocol of dask.array.from_array (planning reads only shapes and dtypes)
    @property
    def ndim(self) -> int:
        return len(self.shape)

    def __getitem__(self, index):
        return np.asarray(self._array()[index])


def _folder_stamp(path: str) -> dict:
    """A local Zarr array's stamp, as a .npy file's size and time: its files' count, total size and latest
    modification time (data rewritten in place, same shape, dtype and chunks, changes the times)."""
    files = size = latest = 0
    for folder, _, names in os.walk(path):
        for name in names:
            try:
                stat = os.stat(os.path.join(folder, name))
            except OSError:  # removed while listed
                continue
            files, size, latest = files + 1, size + stat.st_size, max(latest, stat.st_mtime_ns)
    return {"files": files, "bytes": size, "mtime_ns": latest}


class Constant:
    """An input given on the command line as a value (``--gravity GX GY GZ``), shared by every chunk;
    read like a :class:`Source`."""

    kind, chunk_rows = "value", None

    def __init__(self, option: str, value: np.ndarray) -> None:
        self.option, self.value = option, np.array(value)
        self.given = " ".join(str(v) for v in self.value.reshape(-1).tolist())
        self.shape, self.dtype = tuple(self.value.shape), self.value.dtype

    def read(self, rows: slice | None) -> np.ndarray:
        return self.value

    @property
    def fingerprint(self) -> dict:
        return {"value": self.value.tolist(), "dtype": self.dtype.str}


class _PerRun:
    """A cache of the latest runs' values (shared inputs, opened outputs): keyed by the run's token, so
    that a later run in the same process never sees a previous run's files."""

    def __init__(self, kept: int = 2) -> None:
        self.kept, self.lock, self.values = kept, threading.Lock(), {}

    def get(self, token: str, key, make):
        with self.lock:
            run = self.values.setdefault(token, {})
            while len(self.values) > self.kept:
                del self.values[next(iter(self.values))]
            if key not in run:
                run[key] = make()
            return run[key]


_SHARED = _PerRun()
_OUTPUTS = threading.local()


# ---- the job -----------------------------------------------------------------------------------------


@dataclass
class Job:
    """What every chunk task needs: the kernel, the inputs, the output. Picklable."""

    kernel: Callable  # numpy blocks -> tuple of arrays (spotkin.dask's per-chunk call)
    sources: tuple  # Source per kernel input
    batched: tuple  # per input: cut along the batch axis (else shared, read whole)
    out: str
    fields: tuple
    rows: int
    chunk: int
    token: str  # unique to this run
    lead: tuple = ()  # the whole batch's leading shape (rows, ...)

    @property
    def chunks(self) -> int:
        return max(1, math.ceil(self.rows / self.chunk)) if self.rows else 0

    def rows_of(self, index: int) -> slice:
        return slice(index * self.chunk, min((index + 1) * self.chunk, self.rows))


def _output_arrays(job: Job) -> dict:
    """The output group's arrays, opened once per thread and run."""
    cache = getattr(_OUTPUTS, "cache", None)
    if cache is None or cache[0] != job.token:
        _, zarr = require()
        group = zarr.open_group(job.out, mode="r+")
        cache = _OUTPUTS.cache = (job.token, {name: group[name] for name in (*job.fields, DONE)})
    return cache[1]


def _read(job: Job, rows: slice) -> list:
    return [
        source.read(rows) if batched else _SHARED.get(job.token, k, lambda s=source: np.array(s.read(None)))
        for k, (source, batched) in enumerate(zip(job.sources, job.batched))
    ]


def _compute(job: Job, rows: slice, blocks: list) -> tuple:
    """The kernel on a chunk's rows, as the in-memory call on the whole batch computes them: a blocked
    kernel (the arm's and chains' closed forms) computes the whole batch's tail in one call (see
    spotkin.dask)."""
    kernel = job.kernel
    if not kernel.blocked or job.chunks <= 1:
        return kernel(*blocks)
    inner = tuple(job.lead[1:])
    width = math.prod(inner)
    index = np.arange(rows.start * width, rows.stop * width, dtype=np.int64).reshape((-1, *inner))
    results = kernel.lanes(index, *blocks)
    if rows.stop * width <= kernel.cut:
        return results
    first = kernel.cut // width  # the first row holding part of the tail
    tail_blocks = _read(job, slice(first, job.rows))
    shape = (job.rows - first, *inner)
    skip = kernel.cut - first * width
    tail = kernel(
        *(
            np.broadcast_to(block, shape + core).reshape((-1, *core))[skip:]
            for block, core in zip(tail_blocks, kernel.cores)
        )
    )
    return tuple(kernel.patch(results, tail, index, leaf) for leaf in range(len(results)))


def run_chunk(job: Job, index: int) -> int:
    """Chunk ``index``: read its rows, run the kernel, write the output chunks, then mark it done
    (a chunk stopped before its mark is redone on resume). Returns its number of samples."""
    rows = job.rows_of(index)
    leaves = _compute(job, rows, _read(job, rows))
    arrays = _output_arrays(job)
    for name, leaf in zip(job.fields, leaves):
        arrays[name][rows] = leaf
    arrays[DONE][index] = 1
    return rows.stop - rows.start


# ---- models -------------------------------------------------------------------------------------------


def _load_robot(spec: str):
    from .model.robot import Robot
    from .model.spot import Spot

    if spec == "spot":
        return Spot()
    if spec in robots.NAMES:
        return Robot.from_urdf(robots.path(spec))
    if not os.path.isfile(spec):
        raise BatchError(f"--robot {spec}: not 'spot', a packaged description {robots.NAMES} nor a URDF file")
    try:
        return Robot.from_urdf(spec)
    except (OSError, ValueError) as error:
        raise BatchError(f"--robot {spec}: {error}") from None


def _load_model(args):
    robot = _load_robot(args.robot)
    kind = OPERATIONS[args.operation].model
    try:
        if kind == "robot":
            return robot
        if kind == "leg":
            return robot.leg(args.leg)
        if kind == "arm":
            if robot.arm is None:
                raise BatchError(f"--robot {args.robot}: this robot has no arm")
            return robot.arm
        return robot.chain(args.link, args.base)
    except ValueError as error:
        raise BatchError(f"--robot {args.robot}: {error}") from None


# ---- planning ------------------------------------------------------------------------------------------


@dataclass
class Run:
    """A checked run: the job, what the output must hold, and what remains to do."""

    job: Job
    description: dict
    outputs: tuple  # (name, dtype, shape, chunks)
    lead: tuple
    pending: list = field(default_factory=list)
    resumed: int = 0
    complete: bool = False  # the output already holds the whole result


def _describe_error(message: str, named: dict) -> str:
    """An error of spotkin.dask, with the options and files of the arguments it names."""
    where = [f"{name}: {option} {path}" for name, (option, path) in named.items() if name in message]
    return f"{message} ({'; '.join(where)})" if where else message


def plan(args) -> Run:
    """Checks the inputs, options and output of a parsed ``spotkin batch`` command, before any work."""
    require()
    import dask.array as da

    operation = OPERATIONS[args.operation]
    if args.scheduler not in LOCAL_SCHEDULERS and not re.fullmatch(
        r"[a-z0-9+]+://\S+|[\w.-]+:\d+", args.scheduler
    ):
        raise BatchError(
            f"--scheduler {args.scheduler}: neither threads, processes, synchronous nor a dask.distributed "
            "scheduler address (tcp://host:8786)"
        )
    model = _load_model(args)
    sources, named = {}, {}
    for name, option, _, _ in operation.inputs:
        path = getattr(args, option[2:].replace("-", "_"))
        if path is None:
            continue
        sources[name] = Source(option, path)
        named[name] = (option, path)
    arrays = {}
    for name, source in sources.items():
        if source.dtype.kind not in "biuf" or source.dtype.fields is not None:
            raise BatchError(
                f"{source.option} {source.given}: dtype {source.dtype} is not a real number type "
                "(float, int or bool)"
            )
        arrays[name] = da.from_array(
            source,
            chunks=source.shape,
            name=f"spotkin-batch-input-{name}",
            asarray=True,
            meta=np.empty((0,) * len(source.shape), dtype=source.dtype),
        )
    try:
        planned = operation.plan(model, arrays, args)
    except (ValueError, TypeError) as error:
        raise BatchError(_describe_error(str(error), named)) from None
    for name, array in zip(planned.names, planned.arrays):
        if name not in sources:  # a value option the plan takes as an input (--gravity)
            sources[name] = Constant(f"--{name}", array.compute(scheduler="synchronous"))
    lead = planned.lead
    if not lead:
        raise BatchError(
            "no batch axis: every input holds one sample; give at least one input of shape (N, ...)"
        )
    rows = lead[0]
    batched = []
    for array, core in zip(planned.arrays, planned.cores):
        input_lead = array.shape[: array.ndim - len(core)]
        batched.append(len(input_lead) == len(lead) and input_lead[0] == rows and rows != 1)
    chunk = _chunk_size(args, planned, sources, batched, rows)
    job = Job(
        kernel=planned.kernel,
        sources=tuple(sources[name] for name in planned.names),
        batched=tuple(batched),
        out=args.out if "://" in args.out else os.path.abspath(args.out),
        fields=planned.fields,
        rows=rows,
        chunk=chunk,
        token=f"{planned.kernel._digest[:16]}-{os.getpid()}-{time.time_ns()}",
        lead=tuple(lead),
    )
    outputs = tuple(
        (name, dtype, (*lead, *core), (chunk, *lead[1:], *core))
        for name, (dtype, core) in zip(planned.fields, planned.outputs)
    )
    description = {
        "format": FORMAT,
        "operation": args.operation,
        "model": {
            "robot": args.robot if not os.path.isfile(args.robot) else os.path.abspath(args.robot),
            **{key: getattr(args, key) for key in ("leg", "link", "base") if hasattr(args, key)},
            "digest": planned.kernel._digest,
        },
        "method": planned.kernel.method,
        "options": {name: getattr(args, name) for name in operation.options},
        "inputs": {name: sources[name].fingerprint for name in planned.names},
        "rows": rows,
        "chunk_size": chunk,
        "chunks": job.chunks,
        "fields": list(planned.fields),
        "spotkin": __version__,
    }
    return Run(job, description, outputs, lead)


def _chunk_size(args, planned, sources, batched, rows) -> int:
    zarr_rows = [
        (sources[name].option, sources[name].given, sources[name].chunk_rows)
        for name, is_batched in zip(planned.names, batched)
        if is_batched and sources[name].chunk_rows
    ]
    chunk = args.chunk_size
    if chunk is None:
        previous = _previous_description(args.out)
        chunk = previous.get("chunk_size") if previous else None
        if not isinstance(chunk, int) or chunk < 1:
            per_row = sum(
                math.prod(array.shape[1:]) * array.dtype.itemsize if is_batched else 0
                for array, is_batched in zip(planned.arrays, batched)
            ) + sum(math.prod((*planned.lead[1:], *core)) * dtype.itemsize for dtype, core in planned.outputs)
            chunk = max(1024, DEFAULT_CHUNK_BYTES // max(1, per_row))
            step = math.lcm(*(length for _, _, length in zarr_rows)) if zarr_rows else 1
            chunk = max(step, chunk // step * step)
        return int(min(chunk, max(rows, 1)))
    for option, path, length in zarr_rows:
        if chunk % length and chunk < rows:
            raise BatchError(
                f"chunking: --chunk-size {chunk} is not a multiple of the chunks of {option} {path} along "
                f"the batch axis ({length} rows): each task would read parts of several stored chunks; "
                f"use a multiple of {length} or rechunk the input"
            )
    return int(min(chunk, max(rows, 1)))  # a chunk larger than the batch is the whole batch


# ---- the output ----------------------------------------------------------------------------------------


def _previous_description(out: str) -> dict | None:
    _, zarr = require()
    if not _exists(out):
        return None
    try:
        group = zarr.open_group(out, mode="r")
    except Exception:
        return None
    value = group.attrs.get(ATTRIBUTE)
    return dict(value) if isinstance(value, dict) else None


def _exists(out: str) -> bool:
    return "://" in out or os.path.exists(out)


def _is_zarr(out: str) -> bool:
    return any(os.path.exists(os.path.join(out, name)) for name in ("zarr.json", ".zgroup", ".zarray"))


def _create(group, name, shape, chunks, dtype, fill_value):
    if hasattr(group, "create_array"):  # zarr 3
        return group.create_array(
            name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value, overwrite=True
        )
    return group.create_dataset(  # zarr 2
        name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value, overwrite=True
    )


def _fill_value(name: str, dtype: np.dtype):
    if dtype.kind == "f":
        return float("nan")
    if dtype.kind == "b":
        return False
    return -1 if name == "status" else 0  # status -1: not computed yet


def prepare_output(run: Run, overwrite: bool) -> None:
    """Creates the output group (or checks the one a previous run left) and finds the chunks left to do."""
    _, zarr = require()
    out = run.job.out
    previous = _previous_description(out)
    if _exists(out) and "://" not in out:
        if not os.path.isdir(out) or (os.listdir(out) and not _is_zarr(out)):
            raise BatchError(f"--out {out}: exists and is not a Zarr group; choose another path")
    if overwrite and _exists(out):
        group = zarr.open_group(out, mode="w")
        previous = None
    elif previous is not None:
        differences = sorted(
            key
            for key in set(previous) | set(run.description)
            if key not in ("complete", "spotkin") and previous.get(key) != run.description.get(key)
        )
        if differences:
            raise BatchError(
                f"--out {out} holds a run with other {', '.join(differences)}; resume it with the command "
                "that started it, choose another --out, or pass --overwrite to start anew"
            )
        group = zarr.open_group(out, mode="r+")
    else:
        if _exists(out) and "://" not in out and os.listdir(out):
            raise BatchError(
                f"--out {out}: a Zarr group that is not a spotkin batch output; choose another path, or pass "
                "--overwrite to replace it"
            )
        group = zarr.open_group(out, mode="a")
    if previous is not None and previous.get("complete"):
        run.pending, run.resumed, run.complete = [], run.job.chunks, True
        return
    group.attrs[ATTRIBUTE] = {**run.description, "complete": False}
    members = set(group.array_keys())
    for name, dtype, shape, chunks in run.outputs:
        if name in members and previous is not None:
            array = group[name]
            if (
                tuple(array.shape) == shape
                and np.dtype(array.dtype) == dtype
                and tuple(array.chunks) == chunks
            ):
                continue
        _create(group, name, shape, chunks, dtype, _fill_value(name, dtype))
    if DONE in members and previous is not None and group[DONE].shape == (run.job.chunks,):
        done = np.asarray(group[DONE][:])
    else:
        _create(group, DONE, (run.job.chunks,), (1,), np.uint8, 0)
        done = np.zeros(run.job.chunks, dtype=np.uint8)
    run.pending = [int(i) for i in np.flatnonzero(done == 0)]
    run.resumed = run.job.chunks - len(run.pending)
    _remove_partial_writes(out)


def _remove_partial_writes(out: str) -> None:
    """Zarr's local store writes a chunk to a temporary file and renames it; a killed run can leave
    temporaries (``*.partial``) behind."""
    if "://" in out:
        return
    for folder, _, files in os.walk(out):
        for name in files:
            if name.endswith(".partial"):
                os.remove(os.path.join(folder, name))


def finish_output(run: Run) -> None:
    _, zarr = require()
    group = zarr.open_group(run.job.out, mode="r+")
    done = np.asarray(group[DONE][:]) if DONE in set(group.array_keys()) else None
    if done is not None and not done.all():  # pragma: no cover - every task reported success
        raise RuntimeError(f"{int((done == 0).sum())} chunks are not marked done")
    group.attrs[ATTRIBUTE] = {**run.description, "complete": True}
    if done is not None:
        del group[DONE]


# ---- progress -----------------------------------------------------------------------------------------


def _clock(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "--:--"
    seconds = round(seconds)
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}"


class Progress:
    """A progress bar on stderr: samples done, rate, elapsed time and ETA. Redrawn in place on a
    terminal, else a line every ``interval`` seconds."""

    def __init__(self, total: int, done: int, label: str, enabled: bool, stream=None, interval: float = 5.0):
        self.total, self.done, self.label, self.enabled = total, done, label, enabled
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval = 0.2 if self.tty else interval
        self.start = time.monotonic()
        self.new = 0
        self.first = None  # (time, samples) at the first finished chunk: the rate leaves out start-up
        self.last = -math.inf
        self.lock = threading.Lock()

    def update(self, rows: int) -> None:
        with self.lock:
            now = time.monotonic()
            if self.first is None:
                self.first = (now, rows)
            self.done += rows
            self.new += rows
            if now - self.last >= self.interval or self.done >= self.total:
                self.last = now
                self._draw(now)

    def line(self, now: float | None = None) -> str:
        now = time.monotonic() if now is None else now
        elapsed = now - self.start
        rate = self.new / elapsed if elapsed > 0 else 0.0
        if self.first is not None and now - self.first[0] > 0.5 and self.new > self.first[1]:
            rate = (self.new - self.first[1]) / (now - self.first[0])  # the steady rate, after start-up
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        fraction = self.done / self.total if self.total else 1.0
        width = 24
        bar = "#" * int(fraction * width)
        return (
            f"{self.label} [{bar:<{width}}] {fraction:6.1%} {self.done:,}/{self.total:,} samples | "
            f"{_rate(rate)} | elapsed {_clock(elapsed)} | ETA {_clock(left)}"
        )

    def _draw(self, now: float) -> None:
        if not self.enabled:
            return
        end = "\r" if self.tty and self.done < self.total else "\n"
        self.stream.write(self.line(now) + end)
        self.stream.flush()

    def close(self) -> None:
        if self.enabled and self.tty and self.done < self.total:
            self.stream.write("\n")
            self.stream.flush()


def _rate(rate: float) -> str:
    if rate >= 1e6:
        return f"{rate / 1e6:.2f} M samples/s"
    if rate >= 1e3:
        return f"{rate / 1e3:.1f} k samples/s"
    return f"{rate:.0f} samples/s"


# ---- running -------------------------------------------------------------------------------------------


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def _die_with_parent(parent: int) -> None:
    """The initializer of ``--scheduler processes`` workers: a worker ends when the ``spotkin batch``
    process that started it does, also when that one is killed (SIGKILL leaves it no chance to stop its
    pool): on Linux by ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, and everywhere by a thread that checks the
    parent process id every second."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - no libc prctl: the thread below
            pass
    if os.getppid() != parent:  # the parent died before the request above
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="spotkin-batch-parent", daemon=True).start()


def connect(scheduler: str):
    """A ``dask.distributed`` client of the scheduler at address ``scheduler`` (None for a local
    scheduler), connected before the output is created: an unreachable scheduler is a ``BatchError``
    and nothing is written. The timeout is Dask's ``distributed.comm.timeouts.connect`` (30 s)."""
    if scheduler in LOCAL_SCHEDULERS:
        return None
    try:
        from distributed import Client
    except ImportError as error:
        raise ImportError(
            f"--scheduler {scheduler} needs dask.distributed: install it with {INSTALL}"
        ) from error
    try:
        return Client(scheduler)
    except (OSError, TimeoutError, ValueError) as error:
        reason = f"{type(error).__name__}: {error}"
        raise BatchError(f"--scheduler {scheduler}: cannot connect ({reason})") from None


def _close(client) -> None:
    if client is not None:
        try:
            client.close()
        except Exception:  # pragma: no cover - closing only
            pass


def execute(run: Run, scheduler: str, workers: int | None, progress: Progress, client=None) -> None:
    """Runs the pending chunks on a Dask scheduler, reporting each finished chunk to ``progress``
    (``client``: a connected ``dask.distributed`` client for a scheduler address, see :func:`connect`)."""
    dask, _ = require()
    from dask.callbacks import Callback

    job, pending = run.job, run.pending
    if not pending:
        return
    token = job.token
    job_key = f"spotkin-batch-job-{token}"
    prefix = f"spotkin-batch-chunk-{token}-"
    tasks = [
        dask.delayed(run_chunk, pure=False)(
            dask.delayed(job, name=job_key, traverse=False), i, dask_key_name=f"{prefix}{i}"
        )
        for i in pending
    ]
    if scheduler in LOCAL_SCHEDULERS:
        local = {"sync": "synchronous", "single-threaded": "synchronous"}.get(scheduler, scheduler)
        workers = workers or _cores()
        threads_each = max(1, _cores() // workers) if local != "synchronous" else _cores()

        class Report(Callback):
            def _posttask(self, key, result, dsk, state, worker_id):
                if isinstance(key, str) and key.startswith(prefix):
                    progress.update(result)

        from ._support import runtime as _runtime

        before, variable = _runtime.get_num_threads(), os.environ.get("SPOTKIN_NUM_THREADS")
        try:  # the chunks share the cores: no more spotkin threads than a worker's share
            _runtime.set_num_threads(threads_each)
            os.environ["SPOTKIN_NUM_THREADS"] = str(threads_each)  # for spawned worker processes
            with Report():
                options = {} if local == "synchronous" else {"num_workers": workers}
                if local == "processes":  # the workers end with this process, even when it is killed
                    options["initializer"] = functools.partial(_die_with_parent, os.getpid())
                dask.compute(*tasks, scheduler=local, **options)
        finally:
            _runtime.set_num_threads(before)
            if variable is None:
                os.environ.pop("SPOTKIN_NUM_THREADS", None)
            else:
                os.environ["SPOTKIN_NUM_THREADS"] = variable
        return
    from distributed import as_completed

    own = client is None
    client = connect(scheduler) if own else client
    try:
        futures = client.compute(tasks)
        try:
            for future in as_completed(futures):
                progress.update(future.result())
        finally:
            client.cancel(futures)
    finally:
        if own:
            _close(client)


def main(args) -> int:
    """``spotkin batch ...``: 0 on success, 2 for an input, option or output that cannot be used
    (nothing was done), 1 when the run failed midway (run the same command to resume), 130 when
    interrupted."""
    name = f"spotkin batch {args.operation}"
    client = None
    try:
        run = plan(args)
        if args.dry_run:
            _print_plan(run, args, sys.stdout, dry=True)
            return 0
        client = connect(args.scheduler)  # before the output exists: an unreachable scheduler writes nothing
        prepare_output(run, args.overwrite)
    except BatchError as error:
        _close(client)
        print(f"{name}: error: {error}", file=sys.stderr)
        return 2
    except ImportError as error:
        _close(client)
        print(f"{name}: {error}", file=sys.stderr)
        return 1
    if run.complete:
        _close(client)
        if not args.quiet:
            print(f"{name}: {run.job.out} is complete: nothing to do", file=sys.stderr)
        return 0
    if not args.quiet:
        _print_plan(run, args, sys.stderr)
    total_chunks = run.job.chunks
    progress = Progress(
        run.job.rows, run.job.rows - sum(_span(run.job, i) for i in run.pending), name, not args.quiet
    )
    interrupted = False
    previous_handler = None
    if threading.current_thread() is threading.main_thread():
        previous_handler = signal.getsignal(signal.SIGTERM)
        signal.signal(signal.SIGTERM, _raise_interrupt)  # a polite kill stops like Ctrl-C
    try:
        execute(run, args.scheduler, args.workers, progress, client)
        finish_output(run)
    except KeyboardInterrupt:
        interrupted = True
    except Exception as error:
        progress.close()
        done = _done_count(run)
        print(
            f"{name}: failed: {type(error).__name__}: {error}\n"
            f"{name}: {done} of {total_chunks} chunks are done; run the same command again to resume",
            file=sys.stderr,
        )
        return 1
    finally:
        _close(client)
        if previous_handler is not None:
            signal.signal(signal.SIGTERM, previous_handler)
    progress.close()
    if interrupted:
        print(
            f"{name}: interrupted; {_done_count(run)} of {total_chunks} chunks are done; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    if not args.quiet:
        print(f"{name}: done: {run.job.out}", file=sys.stderr)
    return 0


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


def _span(job: Job, index: int) -> int:
    rows = job.rows_of(index)
    return rows.stop - rows.start


def _done_count(run: Run) -> int:
    try:
        _, zarr = require()
        group = zarr.open_group(run.job.out, mode="r")
        if DONE not in set(group.array_keys()):
            return run.job.chunks
        return int(np.count_nonzero(np.asarray(group[DONE][:])))
    except Exception:  # reporting only
        return run.job.chunks - len(run.pending)


def _print_plan(run: Run, args, stream, dry: bool = False) -> None:
    job = run.job
    fields = ", ".join(f"{name} {np.dtype(dtype).name} {shape}" for name, dtype, shape, _ in run.outputs)
    inputs = ", ".join(
        f"{source.option} {source.given} {source.shape} {source.dtype}" + ("" if batched else " (shared)")
        for source, batched in zip(job.sources, job.batched)
    )
    workers = args.workers or _cores()
    per_chunk = sum(
        math.prod(shape[1:]) * np.dtype(dtype).itemsize for _, dtype, shape, _ in run.outputs
    ) + sum(
        math.prod(source.shape[1:]) * source.dtype.itemsize
        for source, batched in zip(job.sources, job.batched)
        if batched
    )
    lines = [
        f"spotkin batch {args.operation}: {job.rows:,} samples in {job.chunks:,} chunks of {job.chunk:,} "
        f"(about {per_chunk * job.chunk / 2**20:.1f} MiB of inputs and outputs per chunk)",
        f"  inputs: {inputs}",
        f"  output: {job.out}: {fields}",
        f"  scheduler: {args.scheduler}"
        + (f", {workers} workers" if args.scheduler in ("threads", "processes") else ""),
    ]
    if not dry and run.resumed:
        lines.append(f"  resuming: {run.resumed:,} of {job.chunks:,} chunks were done")
    if dry:
        lines.append("  dry run: nothing was computed or written")
    stream.write("\n".join(lines) + "\n")
    stream.flush()
