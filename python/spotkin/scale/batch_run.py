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

import functools
import math
import os
import re
import signal
import sys
import threading
import time

import numpy as np

from .. import robots
from .._support.version import __version__
from .batch_data import (
    Constant,
    Job,
    Run,
    Source,
    _previous_description,
    finish_output,
    prepare_output,
    run_chunk,
)
from .batch_operations import (
    DEFAULT_CHUNK_BYTES,
    DONE,
    FORMAT,
    INSTALL,
    LOCAL_SCHEDULERS,
    OPERATIONS,
    BatchError,
    require,
)

# ---- models -------------------------------------------------------------------------------------------


def _load_robot(spec: str):
    from ..model.robot import Robot
    from ..model.spot import Spot

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

        from .._support import runtime as _runtime

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
