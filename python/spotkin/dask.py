"""Dask arrays in, Dask arrays out: spotkin's batch kernels over chunked arrays, lazily.

``pip install "spotkin[dask]"`` (Dask's ``array`` and ``distributed`` parts, and Zarr).

Each function takes the in-memory call's arguments, with any of the batch arguments a
:class:`dask.array.Array` (NumPy arrays and lists are taken too), and returns the in-memory
call's result record (:class:`~spotkin.BodyIK`, :class:`~spotkin.LegSolutions`, ...) holding
lazy dask arrays. Nothing is computed until the caller computes or stores them::

    import dask.array as da
    import spotkin as sk
    import spotkin.dask as skd

    poses = da.from_zarr("poses.zarr")            # (N, 6), chunked along N
    res = skd.body_ik(sk.Spot(), poses, feet)     # res.q (N, 12), res.status (N, 4)
    da.to_zarr(res.q, "q.zarr")

- **Chunking.** Only the batch (leading) axes are chunked: each output keeps the chunks of the
  batch axes of its inputs (where inputs are chunked differently, their common refinement).
  The trailing axes of a sample (6 pose numbers, a 4x4 transform, ...) are read as one chunk,
  merged first if an input splits them.
- **Broadcasting** follows NumPy over the leading dimensions: shared inputs (one stance of
  feet (4, 3), a seed (12,)) go whole to every chunk.
- **Identical results.** The computed arrays are bit-identical to the in-memory call on the whole
  batch, for any chunking and scheduler. Each chunk is one call of the in-memory method, and most
  kernels answer each sample on its own. The arm's and the chains' closed forms (``SpotArm.ik``,
  ``ik_all``; ``Chain.ik_position``, ``ik``, ``ik_all``) round their full vector blocks and their
  remainder apart in the last bits: for them a chunk computes its samples as the whole call does, in
  full blocks (padded to multiples of :data:`ALIGNMENT`, the core's thread alignment), and the whole
  batch's last ``N mod 64`` samples come from one call on them (one small extra task). The dynamics
  kernels' vector width depends on the instruction-set level only, so any chunk of them computes
  its samples as the whole call does.
- **Checked at once.** Shapes, dtypes, broadcasting and options are checked when the function
  is called, with the in-memory call's ``ValueError``/``TypeError`` messages; NaN samples give
  NaN and ``INVALID_INPUT`` when computed, as everywhere.
- **dtypes** as in memory: float32 inputs give float32 results, other real dtypes float64;
  statuses are int8. A single sample (no leading dimensions) gives 0-d arrays: a status is then
  a 0-d int8 array, not an :class:`~spotkin.Status`.
- **Schedulers.** The models (:class:`~spotkin.Spot`, :class:`~spotkin.Robot`,
  :class:`~spotkin.Leg`, :class:`~spotkin.SpotArm`, :class:`~spotkin.Chain`) pickle, so the
  threaded (the kernels release the GIL), multiprocessing and distributed schedulers all run
  these graphs; a model is unpickled once per worker process, not once per chunk. A chunk's call
  uses its share of the threads (:func:`spotkin.thread_limit`: the thread count over the graph's
  chunks, at least 1), so the scheduler's threads do not each start a thread per core.
- **Several outputs** (``q`` and ``status``) come from one kernel call per chunk: compute or
  store them together (``dask.compute(res.q, res.status)``, ``da.store([...], [...])``), or the
  kernel runs once for each.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import hashlib
import itertools
import math
import operator
import pickle
import threading
from collections.abc import Sequence
from typing import Any, Callable, NamedTuple

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

from ._support.boundary import as_real, broadcast_lead, check_trailing
from ._support.runtime import get_num_threads, thread_limit
from .model.arm import SpotArm
from .model.body import pose_format
from .model.chain import Chain
from .model.leg import Leg
from .model.robot import Robot

__all__ = [
    "body_fk",
    "body_ik",
    "body_jacobian",
    "body_rates",
    "center_of_mass",
    "coriolis_matrix",
    "fk",
    "floating_q",
    "forward_dynamics",
    "gravity",
    "ik",
    "ik_all",
    "inverse_dynamics",
    "jacobian",
    "joint_torques_from_forces",
    "mass_matrix",
    "nonlinear_effects",
    "standing_torques",
]

# A core (per-sample) shape: a tuple, or one of these pose forms resolved from the array's shape.
_BODY_POSE = "body_pose"  # (6,) Euler, (4, 4) matrix or (7,) position + quaternion
_TOOL_POSE = "tool_pose"  # (4, 4) or (7,)


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

# Kernels whose vector blocks and scalar remainders round differently in the last bits (the arm's
# vectorised loop and its scalar epilogue; the chains' closed forms across 16 lanes or one by one):
# the whole call runs every sample below the last multiple of ALIGNMENT in full blocks, the rest as a
# batch of their own. The samples of a full block are computed independently of each other (lanes).
_BLOCKED = {
    ("SpotArm", "ik"),
    ("SpotArm", "ik_all"),
    ("Chain", "ik"),
    ("Chain", "ik_all"),
    ("Chain", "ik_position"),
}


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
        self.cut = total - total % ALIGNMENT if (_kind(model), method) in _BLOCKED else None
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


def _kind(model) -> str:
    return "SpotArm" if isinstance(model, SpotArm) else "Chain" if isinstance(model, Chain) else ""


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


# ---- planning a call: checks, shapes, dtypes ---------------------------------------------------------


class _Plan(NamedTuple):
    """A checked call: what :func:`_lazy` builds a graph from, and what ``spotkin batch`` runs per
    chunk. Internal."""

    kernel: _Kernel
    names: tuple[str, ...]  # the inputs' argument names, in the kernel's positional order
    arrays: tuple  # the inputs as dask arrays
    cores: tuple[tuple[int, ...], ...]  # each input's per-sample shape
    lead: tuple[int, ...]  # the broadcast leading shape
    fields: tuple[str, ...]  # the result's field names
    outputs: tuple[tuple[np.dtype, tuple[int, ...]], ...]  # (dtype, per-sample shape) per field
    record: Callable | None  # builds the result from its leaves (None: a single array)


def _as_dask(value, name: str):
    """A dask array with the in-memory boundary's checks: real numeric dtype, no masked chunks,
    known shape. Anything else goes through the NumPy boundary and becomes one chunk."""
    if isinstance(value, da.Array):
        meta = getattr(value, "_meta", None)
        if isinstance(meta, np.ma.MaskedArray):
            raise TypeError(
                f"{name} must be a plain array, got a dask array of masked chunks: their masks would be "
                f"ignored; fill them first ({name}.map_blocks(np.ma.filled, np.nan))"
            )
        if meta is not None and not isinstance(meta, np.ndarray):
            raise TypeError(f"{name} must hold NumPy chunks, got chunks of {type(meta).__name__}")
        dtype = value.dtype
        if dtype.kind not in "biuf" or dtype.fields is not None:
            raise TypeError(f"{name} must be a real numeric array, got dtype {dtype}")
        if any(isinstance(size, float) and math.isnan(size) for size in value.shape):
            raise ValueError(
                f"{name} has unknown chunk sizes (shape {value.shape}): call {name}.compute_chunk_sizes() "
                "first"
            )
        return value
    array = as_real(value, name)
    return da.from_array(array, chunks=array.shape, name=False)


def _core_of(array, name: str, core) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(leading shape, per-sample shape) of ``array``, with the in-memory call's shape errors."""
    shape = array.shape
    if core == _BODY_POSE:
        _, lead = pose_format(array)
        return lead, shape[len(lead) :]
    if core == _TOOL_POSE:
        if shape[-2:] == (4, 4):
            return shape[:-2], (4, 4)
        if shape[-1:] == (7,):
            return shape[:-1], (7,)
        raise ValueError(
            f"{name} must have shape (..., 4, 4) or (..., 7) [x, y, z, qx, qy, qz, qw], got {shape}"
        )
    return check_trailing(array, name, core), tuple(core)


def _plan(
    model,
    method: str,
    inputs: Sequence,
    options: dict,
    fields: tuple,
    single: str | None,
) -> _Plan:
    """Checks a call of ``model.method`` on ``inputs`` [(name, value, core)] and plans it: a None
    ``seed`` or ``stance`` is left out (the method's default). ``single``: the field name of a
    one-array result."""
    names, arrays, cores, leads = [], [], [], {}
    for name, value, core in inputs:
        if value is None and name in ("seed", "stance"):
            continue
        array = _as_dask(value, name)
        lead, sample = _core_of(array, name, core)
        names.append(name)
        arrays.append(array)
        cores.append(sample)
        leads[name] = (lead, array.shape)
    lead = broadcast_lead(**leads)
    # one sample of each input, of its dtype: the in-memory call checks the options and gives the
    # result's structure, dtypes and per-sample shapes
    samples = [np.zeros((1, *core), dtype=array.dtype) for array, core in zip(arrays, cores)]
    result = _method(model, method)(*samples, **options)
    leaves = result if isinstance(result, tuple) else (result,)
    outputs = tuple((np.asarray(leaf).dtype, np.asarray(leaf).shape[1:]) for leaf in leaves)
    if isinstance(result, tuple):
        record = type(result)._make if hasattr(type(result), "_fields") else tuple
        fields = getattr(type(result), "_fields", fields)
    else:
        record, fields = None, (single,)
    kernel = _Kernel(
        model,
        method,
        dict(options),
        tuple(dtype for dtype, _ in outputs),
        tuple(cores),
        tuple(core for _, core in outputs),
        math.prod(lead),
    )
    return _Plan(
        kernel, tuple(names), tuple(arrays), tuple(cores), tuple(lead), tuple(fields), outputs, record
    )


# ---- the graph -------------------------------------------------------------------------------------


def _lazy(plan: _Plan):
    """The plan as dask arrays: one blockwise kernel call per chunk of the batch axes, then one
    array per output field (a getitem of the chunk's tuple; for a blocked kernel split into several
    chunks, the chunks holding the whole batch's tail take it from one call on that tail)."""
    ndim = len(plan.lead)
    loop = tuple(f"n{k}" for k in range(ndim))
    pairs = []
    for number, (array, core) in enumerate(zip(plan.arrays, plan.cores)):
        lead_ndim = array.ndim - len(core)
        split = {axis: -1 for axis in range(lead_ndim, array.ndim) if len(array.chunks[axis]) > 1}
        if split:
            array = array.rechunk(split)  # a sample's numbers in one chunk
        index = loop[ndim - lead_ndim :] + tuple(f"c{number}_{k}" for k in range(len(core)))
        pairs += [array, index]
    token = tokenize(plan.kernel.token, *plan.arrays)
    name = f"spotkin-{plan.kernel.method.replace('_', '-').replace('.', '-')}-{token}"
    metas = tuple(np.empty((0,) * (ndim + len(core)), dtype=dtype) for dtype, core in plan.outputs)
    chunkss, _ = unify_chunks(*pairs)
    loop_chunks = tuple(chunkss[index] for index in loop)
    plan.kernel.tasks = math.prod(len(c) for c in loop_chunks)
    blocked = plan.kernel.blocked and math.prod(len(c) for c in loop_chunks) > 1
    if not blocked:  # every sample's answer is its own (or a single chunk: the whole call itself)
        chunked = da.blockwise(
            plan.kernel, loop, *pairs, name=name, concatenate=False, align_arrays=True, meta=metas
        )
    else:
        flat = _flat_index(plan.lead, loop_chunks)
        chunked = da.blockwise(
            plan.kernel.lanes,
            loop,
            flat,
            loop,
            *pairs,
            name=name,
            concatenate=False,
            align_arrays=True,
            meta=metas,
        )
        tail = _tail(plan, pairs, token, metas)
    blocks = list(itertools.product(*(range(n) for n in chunked.numblocks)))
    leaves = []
    for number, (field, (dtype, core)) in enumerate(zip(plan.fields, plan.outputs)):
        leaf_name = f"{name}-{field}"
        zeros = (0,) * len(core)
        layer = {(leaf_name, *block, *zeros): (operator.getitem, (name, *block), number) for block in blocks}
        dependencies = [chunked]
        if blocked and tail is not None:
            for block in blocks:
                if _last_flat_index(block, loop_chunks, plan.lead) >= plan.kernel.cut:
                    layer[(leaf_name, *block, *zeros)] = (
                        plan.kernel.patch,
                        (name, *block),
                        (tail.name, 0),
                        (flat.name, *block),
                        number,
                    )
            dependencies += [tail, flat]
        graph = HighLevelGraph.from_collections(leaf_name, layer, dependencies=dependencies)
        chunks = chunked.chunks + tuple((size,) for size in core)
        leaves.append(
            da.Array(graph, leaf_name, chunks=chunks, meta=np.empty((0,) * len(chunks), dtype=dtype))
        )
    return leaves[0] if plan.record is None else plan.record(leaves)


def _flat_index(lead: tuple, chunks: tuple):
    """Each sample's index in the whole batch (C order), lazily, with the batch's chunks."""
    if len(lead) == 1:
        return da.arange(lead[0], chunks=chunks[0], dtype=np.int64)
    grids = da.indices(lead, dtype=np.int64, chunks=chunks)
    strides = np.cumprod((1, *lead[:0:-1]))[::-1]
    return sum(grids[axis] * int(stride) for axis, stride in enumerate(strides))


def _last_flat_index(block: tuple, chunks: tuple, lead: tuple) -> int:
    last = [sum(sizes[: k + 1]) - 1 for k, sizes in zip(block, chunks)]
    return int(np.ravel_multi_index(last, lead)) if all(v >= 0 for v in last) else -1


def _tail(plan: _Plan, pairs: list, token: str, metas: tuple):
    """One call of the kernel on the whole batch's tail (flat indices ``cut`` on, fewer than
    ALIGNMENT samples), gathered from the inputs' last chunks; None without a tail."""
    total, cut = math.prod(plan.lead), plan.kernel.cut
    if total == cut:
        return None
    positions = np.unravel_index(np.arange(cut, total), plan.lead)
    inputs = []
    for number, (array, core) in enumerate(zip(pairs[::2], plan.cores)):
        whole = da.broadcast_to(array, plan.lead + core)
        picked = whole[cut:] if len(plan.lead) == 1 else whole.vindex[positions]
        inputs += [picked.rechunk(-1), ("t", *(f"c{number}_{k}" for k in range(len(core))))]
    return da.blockwise(
        plan.kernel, ("t",), *inputs, name=f"spotkin-tail-{token}", concatenate=False, meta=metas
    )


# ---- models ------------------------------------------------------------------------------------------


def _robot(robot) -> Robot:
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be an sk.Robot or sk.Spot, got {type(robot).__name__}")
    return robot


def _model(model):
    if not isinstance(model, (Leg, SpotArm, Chain)):
        raise TypeError(f"model must be an sk.Leg, sk.SpotArm or sk.Chain, got {type(model).__name__}")
    return model


def _dof(model) -> int:
    return 3 if isinstance(model, Leg) else 6 if isinstance(model, SpotArm) else model.dof


def _target_core(model):
    """A leg's targets are foot points (3,); an arm's tool poses; a chain's points (3,) for 3
    joints (:meth:`Chain.ik_position`), tool poses otherwise (:meth:`Chain.ik`)."""
    if isinstance(model, Leg) or (isinstance(model, Chain) and model.dof == 3):
        return (3,)
    return _TOOL_POSE


# ---- whole body --------------------------------------------------------------------------------------


def _plan_body_ik(robot, body_pose, feet, seed=None, seq="XYZ", fallback="nearest") -> _Plan:
    robot = _robot(robot)
    legs = robot.n_legs
    inputs = [("body_pose", body_pose, _BODY_POSE), ("feet", feet, (legs, 3)), ("seed", seed, (3 * legs,))]
    return _plan(robot, "body_ik", inputs, {"seq": seq, "fallback": fallback}, (), None)


def body_ik(robot: Robot, body_pose, feet, seed=None, seq: str = "XYZ", fallback: str = "nearest"):
    """:meth:`Robot.body_ik` over dask arrays: a :class:`~spotkin.BodyIK` of lazy ``q`` (..., 3 n)
    and ``status`` (..., n), chunked along the batch axes as the inputs are.

    ``body_pose`` (..., 6), (..., 4, 4) or (..., 7), ``feet`` (..., n, 3) and ``seed`` (..., 3 n)
    broadcast over their leading dimensions (a shared stance of feet (n, 3) is typical); ``seq`` and
    ``fallback`` as in memory. ``robot`` is any :class:`~spotkin.Robot` (``sk.Spot()`` included).
    """
    return _lazy(_plan_body_ik(robot, body_pose, feet, seed, seq, fallback))


def _plan_body_fk(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, (3 * robot.n_legs,))]
    return _plan(robot, "body_fk", inputs, {"seq": seq}, (), "feet")


def body_fk(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """:meth:`Robot.body_fk` over dask arrays: lazy world feet (..., n, 3) from ``body_pose`` and the
    leg joints ``q`` (..., 3 n)."""
    return _lazy(_plan_body_fk(robot, body_pose, q, seq))


def _plan_body_jacobian(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, (3 * robot.n_legs,))]
    return _plan(robot, "body_jacobian", inputs, {"seq": seq}, (), "J")


def body_jacobian(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """:meth:`Robot.body_jacobian` over dask arrays: lazy (..., 3 n, 6 + 3 n) Jacobians."""
    return _lazy(_plan_body_jacobian(robot, body_pose, q, seq))


def _plan_body_rates(robot, body_pose, q, twist, seq="XYZ", tolerance=1e-6) -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, (3 * robot.n_legs,)), ("twist", twist, (6,))]
    return _plan(robot, "body_rates", inputs, {"seq": seq, "tolerance": tolerance}, (), None)


def body_rates(robot: Robot, body_pose, q, twist, seq: str = "XYZ", tolerance: float = 1e-6):
    """:meth:`Robot.body_rates` over dask arrays: a :class:`~spotkin.BodyRates` of lazy ``qd``
    (..., 3 n) and ``singular`` (..., n)."""
    return _lazy(_plan_body_rates(robot, body_pose, q, twist, seq, tolerance))


# ---- legs, arms, chains ------------------------------------------------------------------------------


def _plan_fk(model, q) -> _Plan:
    model = _model(model)
    return _plan(model, "fk", [("q", q, (_dof(model),))], {}, (), "p" if isinstance(model, Leg) else "T")


def fk(model, q):
    """Lazy forward kinematics of an :class:`~spotkin.Leg` (foot points (..., 3)), an
    :class:`~spotkin.SpotArm` or a :class:`~spotkin.Chain` (tool poses (..., 4, 4)) for joint
    values ``q`` (..., dof)."""
    return _lazy(_plan_fk(model, q))


def _plan_jacobian(model, q, frame=None, point=None) -> _Plan:
    model = _model(model)
    options = {}
    for name, value in (("frame", frame), ("point", point)):
        if value is None:
            continue
        if not isinstance(model, Chain):
            raise ValueError(
                f"{name} is for a Chain's Jacobian; a {type(model).__name__}'s has none, got {value!r}"
            )
        options[name] = value
    return _plan(model, "jacobian", [("q", q, (_dof(model),))], options, (), "J")


def jacobian(model, q, frame: str | int | None = None, point: str | int | None = None):
    """Lazy Jacobians of an :class:`~spotkin.Leg` ((..., 3, 3), d foot / d q), an
    :class:`~spotkin.SpotArm` ((..., 6, 6)) or a :class:`~spotkin.Chain` ((..., 6, dof)); ``frame``
    (default ``"base"``) and ``point`` (default ``"tool"``) only for a chain, as
    :meth:`Chain.jacobian` (the preferential Jacobian J_point(frame))."""
    return _lazy(_plan_jacobian(model, q, frame, point))


def _plan_ik(model, target, seed=None, fallback=None) -> _Plan:
    model = _model(model)
    options = {}
    if isinstance(model, Leg):
        method = "ik"
        if fallback is not None:
            options["fallback"] = fallback
    else:
        method = "ik"
        if fallback is not None and fallback != "nan":
            raise ValueError(
                f"fallback must be None or 'nan' for a {type(model).__name__}: arm and chain IK give NaN "
                f"for a target without a solution, got {fallback!r}"
            )
    inputs = [("target", target, _target_core(model)), ("seed", seed, (_dof(model),))]
    return _plan(model, method, inputs, options, ("q", "status"), None)


def ik(model, target, seed=None, fallback: str | None = None):
    """Lazy closed-form IK, one solution per target: ``(q, status)`` as dask arrays.

    - :class:`~spotkin.Leg`: :meth:`Leg.ik` of foot points ``target`` (..., 3); ``fallback``
      ``"nearest"`` (the default) or ``"nan"``.
    - :class:`~spotkin.SpotArm`: :meth:`SpotArm.ik` of tool poses (..., 4, 4) or (..., 7).
    - :class:`~spotkin.Chain`: :meth:`Chain.ik` (points (..., 3) for 3 joints, tool poses for 6).

    ``seed`` (..., dof) picks the nearest valid branch and broadcasts against ``target``. Arms and
    chains give NaN without a solution: their ``fallback`` may only be None or ``"nan"``.
    """
    return _lazy(_plan_ik(model, target, seed, fallback))


def _plan_ik_all(model, target, seed=None) -> _Plan:
    model = _model(model)
    if isinstance(model, SpotArm):
        inputs = [("target", target, _TOOL_POSE), ("seed", seed, (6,))]
        return _plan(model, "ik_all", inputs, {}, (), None)
    if seed is not None:
        raise TypeError(f"ik_all of a {type(model).__name__} takes no seed (only a SpotArm's does)")
    if isinstance(model, Leg):
        return _plan(model, "ik_all", [("target", target, (3,))], {}, (), None)
    return _plan(model, "ik_all", [("target", target, _target_core(model))], {}, (), None)


def ik_all(model, target, seed=None):
    """Lazy closed-form IK with every branch: the in-memory record (``q``, ``valid``, ``exists``,
    ``status``) of dask arrays.

    :meth:`Leg.ik_all` (foot points (..., 3)), :meth:`SpotArm.ik_all` (tool poses; ``seed`` (..., 6)
    fixes the free angle in singular cases), or a :class:`~spotkin.Chain`'s :meth:`Chain.ik_all`
    (3 joints: points; 6 joints: tool poses). Only the arm takes a ``seed``.
    """
    return _lazy(_plan_ik_all(model, target, seed))


# ---- dynamics ----------------------------------------------------------------------------------------

_GRAVITY = (0.0, 0.0, -9.81)


def _dynamics(model) -> tuple[str, int, int]:
    """(method prefix, nq, nv): a :class:`~spotkin.Chain`'s own methods (fixed base: q and its rates
    (..., dof)), or a :class:`~spotkin.Robot`'s :attr:`~spotkin.Robot.floating_base` (q (..., 7 + n),
    v (..., 6 + n))."""
    if isinstance(model, Chain):
        return "", model.dof, model.dof
    if isinstance(model, Robot):
        floating = model.floating_base  # ValueError for a robot without a URDF description
        return "floating_base.", floating.nq, floating.nv
    raise TypeError(
        f"model must be an sk.Chain or an sk.Robot (its floating base), got {type(model).__name__}"
    )


def _plan_dynamics(model, method: str, inputs: Sequence, single: str) -> _Plan:
    prefix, _, _ = _dynamics(model)
    return _plan(model, prefix + method, inputs, {}, (), single)


_NO_GRAVITY = object()  # a call without a gravity argument (A(q), C(q, qd))


def _rates(model, names: Sequence[str], values: Sequence, gravity=_NO_GRAVITY) -> list:
    """The (name, value, core) inputs of a dynamics call: q (nq,), then each rate (nv,), then
    ``gravity`` (3,) for the calls that take it."""
    _, nq, nv = _dynamics(model)
    inputs = [(name, value, (nq if name == "q" else nv,)) for name, value in zip(names, values)]
    if gravity is not _NO_GRAVITY:
        inputs.append(("gravity", gravity, (3,)))
    return inputs


def _plan_inverse_dynamics(model, q, qd, qdd, gravity=_GRAVITY) -> _Plan:
    return _plan_dynamics(
        model, "inverse_dynamics", _rates(model, ("q", "qd", "qdd"), (q, qd, qdd), gravity), "tau"
    )


def inverse_dynamics(model, q, qd, qdd, gravity=_GRAVITY):
    """Lazy joint torques tau = A(q) qdd + C(q, qd) qd + G(q) (recursive Newton–Euler).

    ``model``: a :class:`~spotkin.Chain` with inertials (:meth:`Chain.inverse_dynamics`: ``q``,
    ``qd``, ``qdd`` (..., dof)), or a :class:`~spotkin.Robot` for its floating base
    (:meth:`spotkin.dynamics.FloatingBase.inverse_dynamics`: ``q`` (..., 7 + n) as
    :meth:`Robot.floating_q` gives it, ``qd``, ``qdd`` (..., 6 + n)). ``gravity`` (3,) or (..., 3).
    All broadcast over their leading dimensions."""
    return _lazy(_plan_inverse_dynamics(model, q, qd, qdd, gravity))


def _plan_mass_matrix(model, q) -> _Plan:
    return _plan_dynamics(model, "mass_matrix", _rates(model, ("q",), (q,)), "A")


def mass_matrix(model, q):
    """Lazy joint-space inertia matrices A(q), (..., nv, nv) (composite-rigid-body algorithm) of a
    :class:`~spotkin.Chain` or a :class:`~spotkin.Robot`'s floating base (see :func:`inverse_dynamics`)."""
    return _lazy(_plan_mass_matrix(model, q))


def _plan_gravity(model, q, gravity=_GRAVITY) -> _Plan:
    return _plan_dynamics(model, "gravity", _rates(model, ("q",), (q,), gravity), "G")


def gravity(model, q, gravity=_GRAVITY):
    """Lazy gravity torques G(q), (..., nv) (see :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_gravity(model, q, gravity))


def _plan_nonlinear_effects(model, q, qd, gravity=_GRAVITY) -> _Plan:
    return _plan_dynamics(model, "nonlinear_effects", _rates(model, ("q", "qd"), (q, qd), gravity), "h")


def nonlinear_effects(model, q, qd, gravity=_GRAVITY):
    """Lazy h = C(q, qd) qd + G(q), (..., nv) (see :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_nonlinear_effects(model, q, qd, gravity))


def _plan_coriolis_matrix(model, q, qd) -> _Plan:
    return _plan_dynamics(model, "coriolis_matrix", _rates(model, ("q", "qd"), (q, qd)), "C")


def coriolis_matrix(model, q, qd):
    """Lazy Coriolis matrices C(q, qd), (..., nv, nv), with dA/dt - 2 C skew-symmetric (see
    :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_coriolis_matrix(model, q, qd))


def _plan_forward_dynamics(model, q, qd, tau, gravity=_GRAVITY) -> _Plan:
    inputs = _rates(model, ("q", "qd", "tau"), (q, qd, tau), gravity)
    return _plan_dynamics(model, "forward_dynamics", inputs, "qdd")


def forward_dynamics(model, q, qd, tau, gravity=_GRAVITY):
    """Lazy accelerations qdd = A(q)^-1 (tau - C qd - G), (..., nv) (articulated-body algorithm; see
    :func:`inverse_dynamics` for ``model``)."""
    return _lazy(_plan_forward_dynamics(model, q, qd, tau, gravity))


def _last_axis(value, name: str, check: Callable) -> tuple[int, ...]:
    """The per-sample shape (k,) of an input whose width the model allows several values of: the
    array's last axis, after ``check`` (the in-memory call's own shape check) accepted it."""
    shape = _as_dask(value, name).shape  # a TypeError for what is not a real numeric array
    check(np.zeros(shape[-1:] if shape else ()))
    return tuple(shape[-1:])


def _plan_joint_torques_from_forces(chain, q, forces) -> _Plan:
    if not isinstance(chain, Chain):
        raise TypeError(f"chain must be an sk.Chain, got {type(chain).__name__}")

    def check(forces):
        if forces.ndim == 0 or forces.shape[-1] not in (3, 6):
            raise ValueError(f"forces must have shape (..., 6) or (..., 3), got {forces.shape}")

    inputs = [("q", q, (chain.dof,)), ("forces", forces, _last_axis(forces, "forces", check))]
    return _plan(chain, "joint_torques_from_forces", inputs, {}, (), "tau")


def joint_torques_from_forces(chain, q, forces):
    """Lazy tau = J(q)^T F, (..., dof) (:meth:`Chain.joint_torques_from_forces`): ``forces`` (..., 6)
    or (..., 3) at the tool, base axes."""
    return _lazy(_plan_joint_torques_from_forces(chain, q, forces))


def _robot_q(robot: Robot, q) -> tuple[int, ...]:
    return _last_axis(q, "q", robot._legs_and_arm)


def _plan_floating_q(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, _robot_q(robot, q))]
    return _plan(robot, "floating_q", inputs, {"seq": seq}, (), "q")


def floating_q(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """Lazy floating-base coordinates (..., 7 + n) (:meth:`Robot.floating_q`): the body's position and
    quaternion, then ``q``, the legs' joints (..., 3 n) or the legs' and the arm's, for
    :func:`inverse_dynamics` and the other functions of a robot's floating base."""
    return _lazy(_plan_floating_q(robot, body_pose, q, seq))


def _plan_center_of_mass(robot, body_pose, q, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [("body_pose", body_pose, _BODY_POSE), ("q", q, _robot_q(robot, q))]
    # the floating base's kernels run in float64 (Robot.center_of_mass converts the result)
    return _plan(robot, "center_of_mass", inputs, {"seq": seq}, (), "com")


def center_of_mass(robot: Robot, body_pose, q, seq: str = "XYZ"):
    """Lazy centres of mass in the world (..., 3) (:meth:`Robot.center_of_mass`): ``body_pose`` as
    :func:`body_fk` takes it, ``q`` the legs' joints (..., 3 n), or the legs' and the arm's."""
    return _lazy(_plan_center_of_mass(robot, body_pose, q, seq))


def _plan_standing_torques(robot, body_pose, q, stance=None, gravity=_GRAVITY, seq="XYZ") -> _Plan:
    robot = _robot(robot)
    inputs = [
        ("body_pose", body_pose, _BODY_POSE),
        ("q", q, _robot_q(robot, q)),
        ("stance", stance, (robot.n_legs,)),
    ]
    g = as_real(gravity, "gravity", np.float64)
    options = {"gravity": tuple(float(v) for v in g) if g.shape == (3,) else g, "seq": seq}
    return _plan(robot, "standing_torques", inputs, options, (), None)


def standing_torques(robot: Robot, body_pose, q, stance=None, gravity=_GRAVITY, seq: str = "XYZ"):
    """Lazy :meth:`Robot.standing_torques`: a :class:`~spotkin.Standing` of dask arrays (``tau``
    (..., 3 n), ``forces`` (..., n, 3), ``status`` (...) int8, ``margin`` (...)). ``stance`` (..., n)
    bool (default every foot) broadcasts with ``body_pose`` and ``q``; ``gravity`` is one (3,) vector."""
    return _lazy(_plan_standing_torques(robot, body_pose, q, stance, gravity, seq))
