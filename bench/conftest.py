"""Benchmark helpers: every spotkin timing sits beside a baseline from the same run.

At the end of the session a table gives time per item, throughput and the
speed-up over the baseline (ratio of medians), which is what the notes report.
"""

from __future__ import annotations

from collections import defaultdict

import pytest

import spotkin as sk
from spotkin import _core

# benchmark operation -> the kernel whose operation counts give its floor (spotkin/diagnostics.hpp)
FLOOR_KERNELS = {
    "leg.fk": "leg.fk",
    "leg.ik": "leg.ik",
    "body.ik": "body_ik",
    "spot.body_ik": "body_ik",
    "go2.body_ik": "body_ik",
    "body.fk": "body_fk",
    "chain6.fk": "chain6.fk",
    "chain6.jacobian": "chain6.jacobian",
}

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

    An ``impl`` ending in "1thread" runs with spotkin limited to one thread; one
    holding "float32" times float32 inputs (the caller passes them).
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


def median_time(func, rounds: int) -> float:
    """The median wall time (s) of ``rounds`` calls of func() (for benches that time a whole call)."""
    import time

    import numpy as np

    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def cpu_model() -> str:
    """The CPU's model name (Linux /proc/cpuinfo; the platform's processor string elsewhere)."""
    try:
        with open("/proc/cpuinfo") as info:
            for line in info:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    import platform

    return platform.processor() or platform.machine()


def numpy_level() -> str:
    """The widest x86 level NumPy dispatches its own loops to (NPY_DISABLE_CPU_FEATURES lowers it):
    a baseline at a forced spotkin level is only like for like when NumPy runs at that level too."""
    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:  # NumPy 1.x
        try:
            from numpy.core._multiarray_umath import __cpu_features__ as features
        except ImportError:
            return "unknown"
    if features.get("AVX512_SKX"):
        return "AVX-512"
    if features.get("AVX2"):
        return "AVX2"
    return "baseline" if features else "unknown"


def level_line() -> str:
    """The instruction-set level in use, those the CPU has, NumPy's level, and the CPU (SPOTKIN_ISA
    forces a level)."""
    return (
        f"spotkin kernels: {sk.get_isa()} (CPU levels: {', '.join(sk.available_isas())}); "
        f"NumPy: {numpy_level()}; CPU: {cpu_model()}"
    )


def pytest_report_header(config):
    return level_line()


def pytest_terminal_summary(terminalreporter):
    if not _RESULTS:
        return
    write = terminalreporter.write_line
    write("")
    write(level_line())
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

    _where_the_time_goes(write)


def _where_the_time_goes(write) -> None:
    """Per kernel on one thread: ns and TSC cycles per item beside the floor estimate; float32
    over float64; thread scaling. The floor is the kernel's elementary operations (atan2,
    sincos, sqrt, multiply-adds) times their cost measured now, vectorised, in its dtype."""
    rows = [
        (op, n, impl, t)
        for (op, n), impls in sorted(_RESULTS.items())
        for impl, t in impls.items()
        if op in FLOOR_KERNELS and n >= 100_000 and impl.startswith("spotkin") and impl.endswith("1thread")
    ]
    if not rows:
        return
    ghz = _core._tsc_ghz()
    costs = {dtype: _core._elementary_costs(dtype) for dtype in ("float64", "float32")}
    work = _core._kernel_work()
    write("")
    write(
        f"where the time goes (one thread; level {sk.get_isa()}; TSC {ghz:.3f} GHz; floor = elementary "
        "operations x their cost at this level)"
    )
    for dtype, c in costs.items():
        write(
            f"  elementary costs {dtype}, cycles/element: atan2 {c['atan2'] * ghz:.2f}, sincos "
            f"{c['sincos'] * ghz:.2f}, sqrt {c['sqrt'] * ghz:.2f}, multiply-add {c['fma'] * ghz:.3f}"
        )
    write(f"{'operation':<28}{'N':>9}  {'impl':<34}{'ns/item':>10}{'cycles':>10}{'floor':>10}{'/floor':>9}")
    for op, n, impl, t in rows:
        ns = t / n * 1e9
        c = costs["float32" if "float32" in impl else "float64"]
        floor = sum(count * c[name] for name, count in work[FLOOR_KERNELS[op]].items())
        cycles, floor_cycles = ns * ghz, floor * ghz
        write(f"{op:<28}{n:>9}  {impl:<34}{ns:>10.1f}{cycles:>10.0f}{floor_cycles:>10.0f}{ns / floor:>8.1f}x")
    write("")
    write("float32 over float64 (one thread; target >= 1.8x) and thread scaling (all threads over one)")
    for (op, n), impls in sorted(_RESULTS.items()):
        one = impls.get("spotkin-1thread")
        if one is None or n < 100_000:
            continue
        single = impls.get("spotkin-float32-1thread")
        if single is not None:
            write(f"  {op:<26}{n:>9}  float32 {one / single:5.2f}x the float64 throughput")
        both = impls.get("spotkin")
        if both is not None:
            write(f"  {op:<26}{n:>9}  {sk.get_num_threads()} threads {one / both:5.2f}x one thread")
