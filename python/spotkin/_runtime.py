"""Worker-thread settings for the batched kernels."""

from __future__ import annotations

import os
import warnings

from . import _core
from ._boundary import as_index

__all__ = ["MAX_THREADS", "get_num_threads", "set_num_threads"]

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
    """The current maximum number of worker threads."""
    return _core.get_num_threads()
