"""Worker-thread settings for the batched kernels."""

from __future__ import annotations

import contextlib
import os
import warnings
from collections.abc import Iterator

from .. import _core
from .boundary import as_index

__all__ = [
    "MAX_THREADS",
    "available_isas",
    "get_isa",
    "get_num_threads",
    "isa",
    "set_isa",
    "set_num_threads",
    "thread_limit",
]

MAX_THREADS: int = _core.MAX_THREADS
"""The most threads :func:`set_num_threads` accepts (1024)."""


def _check_environment() -> None:
    """SPOTKIN_NUM_THREADS follows set_num_threads' rules; the core has already read it
    (ignored unless a positive integer, capped at MAX_THREADS): say so when it did either."""
    text = os.environ.get("SPOTKIN_NUM_THREADS")
    if text is None:
        return
    parsed = _core._parse_thread_count(text)
    if parsed < 0:
        warnings.warn(
            f"SPOTKIN_NUM_THREADS={text!r} is not a positive integer thread count and is ignored; "
            f"using {_core.get_num_threads()} threads",
            RuntimeWarning,
            stacklevel=3,
        )
    elif parsed == MAX_THREADS and text.strip() != str(MAX_THREADS):
        warnings.warn(
            f"SPOTKIN_NUM_THREADS={text!r} is capped at {MAX_THREADS} threads", RuntimeWarning, stacklevel=3
        )


_check_environment()


def set_num_threads(n: int) -> None:
    """Use up to ``n`` threads for large batches.

    The default is the ``SPOTKIN_NUM_THREADS`` environment variable, or else
    every core. Batches too small to gain from threads always run on the
    calling thread. Results are bit-identical whatever the thread count.

    ``n`` must be an integer (a Python or numpy int): bool, str and float raise
    ``TypeError``, even an integral float such as ``2.0``; ``n`` outside
    ``[1, MAX_THREADS]`` (1024) raises ``ValueError``. If a thread cannot be started
    (resource limits), the threads that did start share the batch.
    """
    _core.set_num_threads(as_index(n, "n"))


def get_num_threads() -> int:
    """The most worker threads a call from this thread uses: :func:`set_num_threads`' setting, or
    less inside :func:`thread_limit`."""
    return _core.get_num_threads()


@contextlib.contextmanager
def thread_limit(n: int) -> Iterator[None]:
    """Within the block, spotkin calls made from *this* thread use at most ``n`` threads.

    For code that runs its own threads: a Dask worker thread, a thread pool of one batch per
    thread, a data-loader worker. Each thread that calls spotkin with the full thread count would
    start a full set of its own, so ``k`` such threads would run ``k`` times the cores' worth.
    ``spotkin.dask`` sets it for its chunks. Other threads are not affected, nor is
    :func:`set_num_threads`' setting, which stays the upper bound; blocks nest (the inner limit
    holds inside). ``n`` follows :func:`set_num_threads`' rules. Results are bit-identical
    whatever the thread count::

        with sk.thread_limit(1):
            res = spot.body_ik(poses, feet)     # on this thread alone
    """
    previous = _core._set_thread_limit(as_index(n, "n"))  # n checked as set_num_threads checks it
    try:
        yield
    finally:
        _core._set_thread_limit(previous)


# ---- instruction-set levels ---------------------------------------------------------------------


def available_isas() -> tuple[str, ...]:
    """The instruction-set levels this CPU runs, lowest first: on x86-64 some of ``"sse2"``,
    ``"avx2"`` (AVX2 + FMA, x86-64-v3) and ``"avx512"`` (x86-64-v4); ``("neon",)`` on aarch64."""
    return tuple(_core.available_isas())


def get_isa() -> str:
    """The level whose compiled kernels run now: the best this CPU has (the last of
    :func:`available_isas`), unless :func:`set_isa` or the ``SPOTKIN_ISA`` environment variable
    chose a lower one."""
    return _core.get_isa()


def set_isa(level: str) -> None:
    """Run the kernels compiled for ``level`` (one of :func:`available_isas`, or ``"best"``).

    For benchmarking and testing a lower level on a larger CPU: every level gives results within
    the documented tolerances, but not bit-identical ones across levels (lane widths and fused
    multiply-adds differ); within one level, results are bit-identical for any thread count.
    ``SPOTKIN_ISA=avx2`` sets it for a whole process (read once, at import: a level the CPU lacks
    fails the import). A level the CPU lacks, or an unknown name, raises ``ValueError``; a
    non-str ``TypeError``. Set it between calls: the level is read per kernel call, so a batch
    running on other threads while it changes may compute some chunks at each level (each within
    tolerance, not bit-identical)."""
    if not isinstance(level, str):
        raise TypeError(f"level must be a str such as 'avx2', got {type(level).__name__}")
    _core.set_isa(level)


@contextlib.contextmanager
def isa(level: str) -> Iterator[None]:
    """Within the block, the kernels of ``level`` run (:func:`set_isa`'s rules); the previous
    level comes back after it. The setting is process-wide::

        for level in sk.available_isas():
            with sk.isa(level):
                q, status = spot.body_ik(poses, feet)
    """
    previous = get_isa()
    set_isa(level)
    try:
        yield
    finally:
        _core.set_isa(previous)
