"""A :mod:`spotkin.dask` call checked and planned (shapes, dtypes, broadcasting, the kernel), and the plan
as Dask arrays: one kernel call per chunk of the batch axes."""

from __future__ import annotations

import inspect
import itertools
import math
import operator
from collections.abc import Sequence
from typing import Callable, NamedTuple

import numpy as np

from .._support.boundary import as_real, broadcast_lead, check_trailing
from ..model.body import pose_format
from ..model.robot import Robot
from .dask_kernel import HighLevelGraph, _Kernel, _method, da, tokenize, unify_chunks

# A core (per-sample) shape: a tuple, or one of these pose forms resolved from the array's shape.
_BODY_POSE = "body_pose"  # (6,) Euler, (4, 4) matrix or (7,) position + quaternion
_TOOL_POSE = "tool_pose"  # (4, 4) or (7,)

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


_INTERFACE = ("dof", "limits", "joint_names", "fk", "jacobian", "ik_all", "ik")


def _model(model):
    """``model`` when it answers the solver interface every leg, arm and chain shares."""
    if not all(hasattr(model, name) for name in _INTERFACE):
        raise TypeError(
            f"model must be a solver (an sk.Leg, an arm or an sk.Chain: {', '.join(_INTERFACE)}), "
            f"got {type(model).__name__}"
        )
    return model


def _dof(model) -> int:
    return model.dof


def _takes(method, name: str) -> bool:
    """``method`` (a solver's) has a parameter ``name``."""
    return name in inspect.signature(method).parameters


def _fk_gives_poses(model) -> bool:
    """The solver's ``fk`` gives tool poses (..., 4, 4), not points (a leg's feet, (..., 3))."""
    return np.shape(model.fk(np.zeros(model.dof)))[-2:] == (4, 4)


def _target_core(model):
    """A 3-joint solver's targets are points (3,) (a leg's feet, a chain's tool point); a 6- or
    7-joint one's tool poses."""
    return (3,) if model.dof == 3 else _TOOL_POSE
