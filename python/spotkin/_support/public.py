"""Public paths for what the package defines in its subpackages.

A public class (or function) is defined in a subpackage (``spotkin.model.chain``) and imported by the
module users import it from (``spotkin``, ``spotkin.urdf``, ...). :func:`publish` gives it that
module as its ``__module__``, so that its pickles, which name ``__module__`` and ``__qualname__``,
and its repr do not depend on the file that defines it: the files can move, the pickles still load.
"""

from __future__ import annotations

import types
from collections.abc import Iterable, Mapping

__all__ = ["publish"]


def publish(module: str, namespace: Mapping[str, object], names: Iterable[str]) -> None:
    """Set ``__module__`` to ``module`` (a public module's name) on the classes and functions among
    ``names`` in ``namespace`` (that module's globals) which the package defines, so that
    ``getattr(import_module(obj.__module__), obj.__qualname__) is obj``. Modules and other values
    are left alone, and so is what the package's root already exports (``"spotkin"``): a class that
    ``spotkin`` and ``spotkin.dynamics`` both export keeps ``spotkin``."""
    for name in names:
        obj = namespace[name]
        if not isinstance(obj, (type, types.FunctionType)):
            continue
        if obj.__module__.startswith("spotkin.") and obj.__qualname__ == name:
            obj.__module__ = module
