"""Benchmark helpers: every spotkin timing sits beside a baseline from the same run.

At the end of the session a table gives time per item, throughput and the
speed-up over the baseline (ratio of medians), which is what the notes report.
"""

from __future__ import annotations

from collections import defaultdict

import pytest

import spotkin as sk

SIZES = [1, 1_000, 100_000, 1_000_000]
_RESULTS: dict[tuple[str, int], dict[str, float]] = defaultdict(dict)


def rounds_for(n: int) -> dict:
    if n >= 1_000_000:
        return {"rounds": 7, "iterations": 1, "warmup_rounds": 1}
    if n >= 100_000:
        return {"rounds": 10, "iterations": 1, "warmup_rounds": 1}
    if n >= 1_000:
        return {"rounds": 200, "iterations": 5, "warmup_rounds": 5}
    return {"rounds": 2000, "iterations": 20, "warmup_rounds": 50}


@pytest.fixture
def measure(benchmark):
    """measure(op, n, impl, func, *args): time func(*args) and record the median.

    An ``impl`` ending in "1thread" runs with spotkin limited to one thread.
    """

    def run(op: str, n: int, impl: str, func, *args):
        benchmark.group = f"{op} N={n}"
        benchmark.extra_info.update(op=op, n=n, impl=impl)
        threads = sk.get_num_threads()
        if impl.endswith("1thread"):
            sk.set_num_threads(1)
        try:
            result = benchmark.pedantic(func, args=args, **rounds_for(n))
        finally:
            sk.set_num_threads(threads)
        _RESULTS[(op, n)][impl] = benchmark.stats.stats.median
        return result

    return run


def pytest_terminal_summary(terminalreporter):
    if not _RESULTS:
        return
    write = terminalreporter.write_line
    write("")
    write(
        "spotkin benchmark summary (medians; speed-up = the chunked NumPy baseline's time, or EAIK's,"
        " over spotkin's, same run; vs unchunked = the whole-array NumPy form's)"
    )
    write(
        f"{'operation':<28}{'N':>9}  {'impl':<34}{'time/item':>12}{'items/s':>12}{'speed-up':>10}"
        f"{'vs unchunked':>14}"
    )
    for (op, n), impls in sorted(_RESULTS.items()):
        # the baseline: a NumPy implementation, EAIK, or a named reference point ("ref:...")
        baselines = ("numpy", "eaik", "ref:")
        # the speed-up is against the chunked NumPy form (the targets' baseline); the unchunked
        # one, where measured, gets its own column
        base = next(
            (t for name, t in impls.items() if name.startswith(baselines) and "unchunked" not in name), None
        )
        unchunked = next((t for name, t in impls.items() if name.startswith("numpy-unchunked")), None)
        for impl, t in sorted(impls.items(), key=lambda kv: kv[1]):
            per = t / n
            spotkin = not impl.startswith(baselines)
            ratio = f"{base / t:9.2f}x" if base and spotkin else ""
            ratio_unchunked = f"{unchunked / t:9.2f}x" if unchunked and spotkin else ""
            unit = f"{per * 1e9:9.1f} ns" if per < 1e-6 else f"{per * 1e6:9.2f} us"
            write(f"{op:<28}{n:>9}  {impl:<34}{unit:>12}{1 / per:>12.3g}{ratio:>10}{ratio_unchunked:>14}")
