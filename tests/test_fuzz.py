"""Fuzz harness (issue 13): every public function and method of spotkin against hostile inputs.

What it covers
--------------
``tests/fuzz/`` holds a registry of spotkin's public API: every callable reachable from
``spotkin.__all__``, ``spotkin.paul.__all__`` and ``spotkin.trajectory.__all__`` (functions,
constructors, classmethods and methods of ``Spot``, ``Robot`` (the packaged Go2 and Spot URDFs, and
a six-legged robot whose joints interleave in ``q``), ``Leg`` (Spot's, and of any geometry),
``SpotArm``, ``Chain`` built with ``from_mdh``/``from_dh`` as 3-joint and 6-joint spherical-wrist
chains and from URDFs (a Go2 leg, the Spot arm), ``PointToPoint`` and ``CartesianPath`` objects;
URDF loading with malformed, hostile and oddly encoded descriptions), plus the pickling and copying
of every object (one module of the package per concept; its ``__init__.py`` lists them). Optional
modules (``fuzz.coverage.OPTIONAL_MODULES``: ``spotkin.sdk``, ``spotkin.dask`` and ``spotkin.plot``,
whose entries are in ``tests/fuzz/sdk.py``, ``dask.py`` and ``plot.py``) are covered whenever their
extra is installed, as the test requirements do.
:func:`test_registry_covers_the_public_api` fails when a public callable is missing from the
registry, when the registry covers something no longer public, or when an entry's argument slots
do not match the callable's parameters: new API is fuzzed by default, once described. The only
exclusions are ``spotkin.Status`` and ``spotkin.StanceStatus`` (IntEnums, ``fuzz.coverage.EXCLUDED``);
NamedTuple result records are skipped unless they grow methods of their own.

Each registry entry describes its argument slots (a batch array ``(..., *trailing)``, a
fixed-shape array, a real, an integer, an enum string, a flag, or an explicit table). Each slot
generates hostile variants: wrong shapes, 0-d and empty arrays, every dtype (float16/32/64,
longdouble, big-endian ``>f4``/``>f8``, ints, bool, complex, str, bytes, object, datetime,
structured), read-only, zero-stride (``np.broadcast_to``), negative-stride, Fortran-ordered and
strided views, masked arrays, lists and tuples, None, NaN, ±Inf, 1e308, subnormals, huge values
(1e6, 1e15, 1e300 rad), malformed poses (zero, scaled or reflected rotations, bad last rows,
non-unit quaternions), a 1e10-sample batch, bad enum strings, and bad numbers (negative, zero,
NaN, Inf, bool, str, complex, 1.5 for an integer, 2**63).

Each case runs in a worker subprocess (a pool of long-lived workers, replaced when one dies; each
limited to 6 GiB of address space and one spotkin thread). A crash, an abort or a hang (no answer
within the timeout) fails the case. Otherwise the only acceptable outcomes are a result that is
correct per the documentation, or ``ValueError``/``TypeError``/``MemoryError`` where the input is
invalid (``TypeError`` for non-numeric input, ``ValueError`` for a bad shape, each naming the
argument; ``MemoryError`` for a batch too large to allocate; ``OSError`` for a file that cannot be
read). Other exceptions, ``LinAlgError``, pybind11's "incompatible function arguments", any
warning, and an accepted invalid input fail.
"Correct per the documentation" is checked by oracles:

(a) shapes and dtypes follow the batch semantics (leading dimensions kept, float32 in gives
    float32 out, every other real dtype float64, a single target's status is an ``sk.Status``);
(b) a sample with NaN/Inf or an invalid pose gives NaN floats, False validity flags and
    INVALID_INPUT in that sample (per leg for the whole-body calls), and nothing else changes;
(c) a finite, valid sample gives finite results or a documented status/NaN, checked against the
    documented formula (fk(ik(target)) = target, NumPy/SciPy references, Paul residuals, limits);
(d) angles beyond 64 rad give NaN/INVALID_INPUT (an angle bound) or the result at the angle
    reduced exactly (``atan2(sin q, cos q)`` with Python's math); times beyond a trajectory's
    ends give the end state;
(e) every sample of a batch equals a single call on that sample alone.

Modes
-----
CI (the default, ``python -m pytest tests/test_fuzz.py``): a fixed seed (``SEED`` below); every
variant of every slot with the other slots at a valid baseline (the randomly placed NaN, Inf and
huge values three times), three combinations per entry (all float32, all batched, batched with a
NaN), and 40 random pairs of variants of two slots per entry: about 45,000 planned cases (plus the
canaries). "Light" entries (Spot's whole-body code on other robots,
the URDF chains' shared kernels) run fewer batch variants, once each, and 12 pairs in CI.

Exhaustive (``python -m pytest tests/test_fuzz.py -m fuzz_exhaustive``, or
``SPOTKIN_FUZZ=exhaustive python -m pytest tests/test_fuzz.py``): more variants (more dtypes,
tuples, 1001 waypoints, ...), every variant three times with fresh random draws, and every pair
of variants of every two slots: about 1.9 million planned cases, many times the CI run's time. It is skipped
unless selected.

Environment: ``SPOTKIN_FUZZ_SEED`` (another seed, to explore), ``SPOTKIN_FUZZ_WORKERS`` (default:
up to 2), ``SPOTKIN_FUZZ_TIMEOUT`` (seconds per case, default 30), ``SPOTKIN_FUZZ_ONLY`` (run
only the entries whose name contains this text).
"""

from __future__ import annotations

import collections
import os

import pytest
from fuzz.canaries import CANARIES, CANARY_FK
from fuzz.cases import cases_for, label
from fuzz.coverage import coverage_problems, public_callables
from fuzz.registry import BY_NAME, REGISTRY
from fuzz.worker import Pool

EXHAUSTIVE = os.environ.get("SPOTKIN_FUZZ", "").lower() == "exhaustive"
SEED = int(os.environ.get("SPOTKIN_FUZZ_SEED", "20261113"))
WORKERS = int(os.environ.get("SPOTKIN_FUZZ_WORKERS", str(min(2, os.cpu_count() or 1))))
TIMEOUT = float(os.environ.get("SPOTKIN_FUZZ_TIMEOUT", "30"))
ONLY = os.environ.get("SPOTKIN_FUZZ_ONLY", "")
ENTRIES = [entry.name for entry in REGISTRY if ONLY in entry.name]


def test_registry_covers_the_public_api():
    problems = coverage_problems()
    assert not problems, "\n".join(problems)


def test_variants_are_well_formed():
    """Every case builds its arguments from declared variants (a typo in the registry fails here)."""
    for entry in REGISTRY:
        for slot in entry.slots:
            assert slot.default == "omit" or slot.default in slot.variants(True) or slot.default == "valid", (
                f"{entry.name}: slot {slot.name} has an unknown default {slot.default!r}"
            )
            if slot.default == "omit":
                assert slot.optional or _has_default(entry, slot.name), (
                    f"{entry.name}: {slot.name} is required"
                )


def _has_default(entry, name) -> bool:
    import inspect

    public = public_callables()
    if entry.covers not in public:
        return True
    parameter = inspect.signature(public[entry.covers]).parameters.get(name)
    return parameter is None or parameter.default is not inspect.Parameter.empty


def test_the_harness_catches_crashes_hangs_and_wrong_results():
    """Canaries broken on purpose (tests/fuzz/canaries.py): each must be caught, the pool must survive."""
    canaries = CANARIES
    cases = [{"entry": name, "variants": [], "seed": 0} for name in canaries]
    fk = CANARY_FK
    fk_cases = [
        {"entry": fk.name, "variants": [["q", v]], "seed": 1} for v in ("nan", "complex128", "float32")
    ]
    small = Pool(1, timeout=3)
    try:
        results = small.run(cases + fk_cases + cases[:1])
    finally:
        small.close()
    kinds = [result.get("kind") for result in results]
    assert kinds[: len(canaries)] == [kind for _, kind in canaries.values()], kinds
    assert kinds[len(canaries) :] == [
        "NaN/Inf/invalid input: no NaN",
        "accepted invalid input",
        "output dtype",
        "crash",
    ], kinds
    assert small.restarts == 3


@pytest.fixture(scope="module")
def pool():
    workers = Pool(WORKERS, TIMEOUT)
    yield workers
    workers.close()


def run(pool, name: str, exhaustive: bool) -> None:
    entry = BY_NAME[name]
    cases = cases_for(entry, exhaustive, SEED)
    results = pool.run(cases)
    failures = collections.defaultdict(list)
    for case, result in zip(cases, results):
        if not result["ok"]:
            failures[result["kind"]].append((label(case), result["detail"]))
    if failures:
        lines = [f"{sum(map(len, failures.values()))} of {len(cases)} cases of {name} fail:"]
        for kind, found in sorted(failures.items(), key=lambda item: -len(item[1])):
            labels = ", ".join(label for label, _ in found[:4]) + (", ..." if len(found) > 4 else "")
            lines.append(f"- {kind} ({len(found)}): {labels}\n    {found[0][1][:600]}")
        pytest.fail("\n".join(lines), pytrace=False)


@pytest.mark.skipif(EXHAUSTIVE, reason="SPOTKIN_FUZZ=exhaustive: test_fuzz_exhaustive runs instead")
@pytest.mark.parametrize("name", ENTRIES)
def test_fuzz(pool, name):
    run(pool, name, exhaustive=False)


@pytest.mark.fuzz_exhaustive
@pytest.mark.parametrize("name", ENTRIES)
def test_fuzz_exhaustive(pool, name, request):
    expression = request.config.getoption("markexpr") or ""
    selected = "fuzz_exhaustive" in expression and "not fuzz_exhaustive" not in expression
    if not (EXHAUSTIVE or selected):
        pytest.skip("exhaustive fuzzing: select with -m fuzz_exhaustive or SPOTKIN_FUZZ=exhaustive")
    run(pool, name, exhaustive=True)
