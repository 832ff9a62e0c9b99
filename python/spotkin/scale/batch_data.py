"""The data of a ``spotkin batch`` run: its inputs (``.npy`` memory maps, Zarr arrays, shared
constants), the job each chunk task runs, and the Zarr output with its per-chunk completion markers."""

from __future__ import annotations

import math
import os
import threading
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .batch_operations import ATTRIBUTE, DONE, BatchError, require

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
