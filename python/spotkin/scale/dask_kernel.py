"""The call a chunk of a :mod:`spotkin.dask` graph runs: the model travels as its pickle (unpickled once per
process), the closed forms that round their vector blocks apart run in full blocks. Dask is imported
here, the one place that says what to install when it is missing."""

from __future__ import annotations

import collections
import contextlib
import functools
import hashlib
import pickle
import threading
from typing import Any, Callable

import numpy as np

try:
    import dask.array as da
    from dask.array.core import unify_chunks
    from dask.base import tokenize
    from dask.highlevelgraph import HighLevelGraph
except ImportError as error:  # pragma: no cover - exercised in a subprocess by the tests
    raise ImportError(
        'spotkin.dask needs Dask: install it with pip install "spotkin[dask]" '
        f"(dask[array,distributed] and zarr); the import failed with: {error}"
    ) from error


from .._support.runtime import get_num_threads, thread_limit

# Dask, which the graph imports from here
__all__ = ["HighLevelGraph", "da", "tokenize", "unify_chunks"]


# ---- the kernel a chunk runs ------------------------------------------------------------------------

_MODELS: collections.OrderedDict[str, Any] = collections.OrderedDict()
_MODELS_LOCK = threading.Lock()
_MODELS_KEPT = 8


def _model_from_pickle(digest: str, data: bytes):
    """The model pickled as ``data``, unpickled once per process (a small LRU keyed by its digest):
    a robot from a URDF takes milliseconds to rebuild, and a graph has a task per chunk."""
    with _MODELS_LOCK:
        model = _MODELS.get(digest)
        if model is not None:
            _MODELS.move_to_end(digest)
            return model
    model = pickle.loads(data)
    with _MODELS_LOCK:
        _MODELS[digest] = model
        while len(_MODELS) > _MODELS_KEPT:
            _MODELS.popitem(last=False)
    return model


# The core splits a batch between threads at multiples of this many samples (kChunkAlignment in
# cpp/include/spotkin/parallel.hpp), a multiple of every kernel's block: a sample's code path depends
# only on its index in the batch and the batch's size, whatever the thread count.
ALIGNMENT = 64

# A model's methods whose vector blocks and scalar remainders round differently in the last bits (the
# arm's vectorised loop and its scalar epilogue; the chains' closed forms across 16 lanes or one by one)
# are named by its class's _block_dependent: the whole call runs every sample below the last multiple of
# ALIGNMENT in full blocks, the rest as a batch of their own. The samples of a full block are computed
# independently of each other (lanes).


class _Kernel:
    """``getattr(model, method)(*blocks, **options)`` on NumPy blocks, its result flattened to a
    tuple of arrays of the planned dtypes. Picklable: the model travels as its pickle.

    For a blocked kernel, :meth:`lanes` and :meth:`patch` compute a chunk's samples as the in-memory
    call on the whole batch (``total`` samples) computes them: those in its full blocks (flat index
    below ``cut``) in batches padded to a multiple of :data:`ALIGNMENT`, the others (the whole batch's
    tail) by one call on that tail."""

    __slots__ = (
        "_data",
        "_digest",
        "cores",
        "cut",
        "dtypes",
        "method",
        "model",
        "options",
        "outputs",
        "tasks",
    )

    def __init__(self, model, method, options, dtypes, cores=(), outputs=(), total=0) -> None:
        self.model, self.method, self.options, self.dtypes = model, method, options, dtypes
        self.cores, self.outputs = cores, outputs  # per-sample shapes of the inputs and outputs
        self.cut = total - total % ALIGNMENT if method in getattr(model, "_block_dependent", ()) else None
        # the graph's chunks (set by _lazy): the threads of a call are the cores' share of one chunk, so
        # that the scheduler's threads, one chunk each, do not each start every core's worth
        self.tasks = 0
        self._data = pickle.dumps(model, protocol=pickle.HIGHEST_PROTOCOL)
        self._digest = hashlib.sha256(self._data).hexdigest()

    @property
    def blocked(self) -> bool:
        return self.cut is not None

    def __call__(self, *blocks: np.ndarray) -> tuple:
        return self._call(*_whole(blocks))

    def _call(self, *blocks: np.ndarray) -> tuple:
        share = (
            thread_limit(max(1, get_num_threads() // self.tasks))
            if self.tasks > 1
            else contextlib.nullcontext()
        )
        with share:
            result = _method(self.model, self.method)(*blocks, **self.options)
        leaves = result if isinstance(result, tuple) else (result,)
        return tuple(np.asarray(leaf, dtype=dtype) for leaf, dtype in zip(leaves, self.dtypes))

    def lanes(self, index: np.ndarray, *blocks: np.ndarray) -> tuple:
        """The samples of a chunk whose flat indices in the whole batch (``index``, the chunk's
        batch shape) are below ``cut``, as in full blocks; the others zero (see :meth:`patch`)."""
        blocks = _whole(blocks)
        lead, count = index.shape, index.size
        flat = [
            np.broadcast_to(b, lead + core).reshape((count, *core)) for b, core in zip(blocks, self.cores)
        ]
        if count and index.max() < self.cut:
            # every sample in full blocks (each chunk but those holding the tail): padded, not scattered
            pad = (-count) % ALIGNMENT
            if pad:
                flat = [np.concatenate([x, np.repeat(x[-1:], pad, axis=0)]) for x in flat]
            return tuple(leaf[:count].reshape(lead + core) for leaf, core in zip(self(*flat), self.outputs))
        keep = np.flatnonzero(index.reshape(-1) < self.cut)
        outs = [np.zeros((count, *core), dtype=dtype) for dtype, core in zip(self.dtypes, self.outputs)]
        if keep.size:
            take = np.concatenate([keep, np.full((-keep.size) % ALIGNMENT, keep[-1])])
            for out, leaf in zip(outs, self(*(x[take] for x in flat))):
                out[keep] = leaf[: keep.size]
        return tuple(out.reshape(lead + core) for out, core in zip(outs, self.outputs))

    def patch(self, results: tuple, tail: tuple, index: np.ndarray, leaf: int) -> np.ndarray:
        """Leaf ``leaf`` of a chunk's :meth:`lanes` with its samples of the whole batch's tail set
        from ``tail``, the kernel's result on that tail (flat indices ``cut`` on)."""
        out = np.array(results[leaf], copy=True)
        flat = index.reshape(-1)
        rows = flat >= self.cut
        out.reshape((flat.size, *self.outputs[leaf]))[rows] = tail[leaf][flat[rows] - self.cut]
        return out

    @property
    def token(self) -> str:
        return tokenize(self._digest, self.method, sorted(self.options.items()), self.dtypes, self.cut)

    def __reduce__(self):
        state = (
            self.method,
            self.options,
            self.dtypes,
            self.cores,
            self.outputs,
            self.cut,
            self.tasks,
        )
        return (_rebuild_kernel, (self._digest, self._data, state))

    def __repr__(self) -> str:
        return f"spotkin kernel {type(self.model).__name__}.{self.method}"


def _whole(blocks: tuple) -> tuple:
    """The kernel's blocks as arrays. The graph hands an input whose per-sample axes are not the
    output's (a pose's 6 numbers) as nested one-element lists, those axes being one chunk each:
    ``concatenate=True`` would copy every input block (np.concatenate of one block)."""
    if not any(isinstance(block, list) for block in blocks):
        return blocks
    out = []
    for block in blocks:
        while isinstance(block, list):
            (block,) = block
        out.append(block)
    return tuple(out)


def _method(model, method: str) -> Callable:
    """``model.method``; a dotted name walks attributes (``"floating_base.mass_matrix"``)."""
    return functools.reduce(getattr, method.split("."), model)


def _rebuild_kernel(digest, data, state) -> _Kernel:
    kernel = _Kernel.__new__(_Kernel)
    kernel.model = _model_from_pickle(digest, data)
    kernel._data, kernel._digest = data, digest
    (
        kernel.method,
        kernel.options,
        kernel.dtypes,
        kernel.cores,
        kernel.outputs,
        kernel.cut,
        kernel.tasks,
    ) = state
    return kernel
