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

from ._support.public import publish
from .scale.dask_calls import *  # noqa: F403 (the public calls: their __all__ below)
from .scale.dask_calls import __all__
from .scale.dask_kernel import ALIGNMENT as ALIGNMENT

# what the graphs' pickles name (a chunk's kernel rebuilds itself through these): here, at this public path
from .scale.dask_kernel import _model_from_pickle as _model_from_pickle
from .scale.dask_kernel import _rebuild_kernel as _rebuild_kernel

publish(__name__, globals(), [*__all__, "_model_from_pickle", "_rebuild_kernel"])
