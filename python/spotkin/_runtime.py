"""Worker-thread settings for the batched kernels."""

from __future__ import annotations

from . import _core

__all__ = ["get_num_threads", "set_num_threads"]


def set_num_threads(n: int) -> None:
    """Use up to ``n`` threads for large batches.

    The default is the ``SPOTKIN_NUM_THREADS`` environment variable, or else
    every core. Batches too small to gain from threads always run on the
    calling thread. Results are bit-identical whatever the thread count.
    """
    _core.set_num_threads(int(n))


def get_num_threads() -> int:
    """The current maximum number of worker threads."""
    return _core.get_num_threads()
