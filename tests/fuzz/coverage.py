"""The public API and the registry's coverage of it."""

from __future__ import annotations

import inspect
from collections.abc import Callable

import spotkin as sk

from .entry import REGISTRY

# Callables that take no input worth fuzzing, with the reason. Anything else public must be registered.
EXCLUDED = {
    "spotkin.Status": "IntEnum of result codes: int methods only, no spotkin code",
    "spotkin.StanceStatus": "IntEnum of result codes: int methods only, no spotkin code",
    "spotkin.ReachStatus": "IntEnum of result codes: int methods only, no spotkin code",
}

# Optional modules (each needs an extra's dependency, which requirements-test.txt installs): their
# public callables must be registered too, whenever the module imports.
OPTIONAL_MODULES = ("spotkin.sdk", "spotkin.dask", "spotkin.plot")


def _optional_modules() -> list:
    """(prefix, module) of each optional module that imports here."""
    import importlib

    found = []
    for name in OPTIONAL_MODULES:
        try:
            found.append((name, importlib.import_module(name)))
        except ImportError:  # the extra is not installed: nothing of it is public here
            continue
    return found


def _is_record(cls) -> bool:
    """A NamedTuple result record (built by spotkin, only tuple methods)."""
    return isinstance(cls, type) and issubclass(cls, tuple) and hasattr(cls, "_fields")


def public_callables() -> dict[str, Callable]:
    """Every public function, class (its constructor) and method reachable from ``spotkin.__all__``,
    ``spotkin.paul.__all__``, ``spotkin.trajectory.__all__`` and the ``__all__`` of each optional module
    that imports (:data:`OPTIONAL_MODULES`); NamedTuple records keep only methods that tuples do not
    have."""
    found = {}
    core = [("spotkin", sk), ("spotkin.paul", sk.paul), ("spotkin.trajectory", sk.trajectory)]
    for prefix, module in core + _optional_modules():
        for name in module.__all__:
            obj = getattr(module, name)
            qual = f"{prefix}.{name}"
            if inspect.ismodule(obj) or not callable(obj):
                continue
            if not inspect.isclass(obj):
                found[qual] = obj
                continue
            record = _is_record(obj)
            if not record:
                found[qual] = obj
            for attr in dir(obj):
                if attr.startswith("_"):
                    continue
                raw = inspect.getattr_static(obj, attr)
                if isinstance(raw, property) or not callable(getattr(obj, attr)):
                    continue
                if record and hasattr(tuple, attr):
                    continue
                found[f"{qual}.{attr}"] = getattr(obj, attr)
    return found


def _inherited_from_covered(qual: str, covered: set[str]) -> bool:
    """``qual`` is a method a public class inherits unchanged (the same function object) from a public
    base class whose method the registry covers: ``spotkin.SpotArm.gravity`` is ``spotkin.Chain.gravity``.
    tests/test_spot_arm_chain.py runs every such method on a SpotArm against the plain chain's answer."""
    prefix, _, attr = qual.rpartition(".")
    module_name, _, class_name = prefix.rpartition(".")
    try:
        import importlib

        cls = getattr(importlib.import_module(module_name), class_name)
    except (ImportError, AttributeError):
        return False
    if not inspect.isclass(cls):
        return False
    raw = inspect.getattr_static(cls, attr, None)
    for base in cls.__mro__[1:]:
        if inspect.getattr_static(base, attr, None) is raw and raw is not None:
            if f"{module_name}.{base.__name__}.{attr}" in covered:
                return True
    return False


def coverage_problems() -> list[str]:
    """Public callables missing from the registry, stale registry entries, and registry slots that do
    not match the signature's parameters. A method inherited unchanged from a public class is covered
    by that class's entry."""
    public = public_callables()
    covered = {e.covers for e in REGISTRY if e.covers}
    problems = []
    for qual in sorted(public):
        if any(qual == q or qual.startswith(q + ".") for q in EXCLUDED):
            continue
        if qual not in covered and not _inherited_from_covered(qual, covered):
            problems.append(f"{qual} is public but not in the fuzz registry (tests/fuzz/)")
    for qual in sorted(covered - set(public)):
        problems.append(f"the registry covers {qual}, which is not public (any more)")
    for entry in REGISTRY:
        if entry.covers not in public:
            continue
        params = [
            p
            for p in inspect.signature(public[entry.covers]).parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and p.name not in ("self", "cls")
        ]
        names, slots = [p.name for p in params], [s.name for s in entry.slots]
        if sorted(names) != sorted(slots):
            problems.append(f"{entry.name}: slots {slots} do not match the parameters {names}")
    return problems
