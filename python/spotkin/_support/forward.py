"""Façade methods that run from C: :func:`core_method`.

Most of the façade's hot methods only pass their arguments to a core object, as
``return self._core.fk(q, out)`` does. Run as Python, that costs a frame, a bound method and a keyword
parse: about 0.2 µs, as much as the kernel of one sample. :func:`core_method` turns such a method
into ``spotkin._core._CoreMethod`` (cpp/bindings/forward.cpp), which makes the same call from C.

The Python function stays the method's definition and documentation (``__wrapped__``,
``inspect.signature``, the docs site), and it runs every case the fast path does not take: a core not
built yet, a keyword it does not know, an argument whose value selects another path, and any
``ValueError`` or ``TypeError`` the core raises (the function handles the other forms it accepts,
or raises its documented error). tests/test_core_method.py checks each decorated method against its
function.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence

from .. import _core

__all__ = ["AT_DEFAULT", "core_method", "core_methods"]

#: A converter meaning: the fast path only when this parameter is left at its default.
AT_DEFAULT = inspect.Parameter.empty

_POSITIONAL = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)

# every method made here, for the tests
core_methods: list[object] = []


def core_method(
    target: str,
    method: str,
    call: Sequence[str | tuple[object]] | None = None,
    convert: Mapping[str, Callable[[object], object] | object] | None = None,
) -> Callable[[Callable], object]:
    """Decorator: the method calls ``getattr(self, target).<method>(*args)`` from C.

    ``call`` lists the core method's arguments: a parameter's name, or ``(constant,)``; by default
    every parameter after ``self`` in order. ``convert`` maps a parameter to the function applied
    to a value the caller gives (its default is converted once, here), or to :data:`AT_DEFAULT`:
    any other value takes the Python function. The decorated function must return exactly
    ``getattr(self, target).<method>(*args)`` for the arguments the fast path takes.
    """
    convert = dict(convert or {})

    def decorate(function: Callable) -> object:
        parameters = list(inspect.signature(function).parameters.values())[1:]  # after self
        names = tuple(p.name for p in parameters)
        if any(p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) for p in parameters):
            raise TypeError(f"{function.__qualname__}: a core method takes no *args or **kwargs")
        unknown = set(convert) - set(names)
        if unknown:
            raise ValueError(f"{function.__qualname__}: convert names no parameter: {sorted(unknown)}")
        defaults, converters = [], []
        for p in parameters:
            converter = convert.get(p.name)
            default = p.default
            if (
                converter is not None
                and converter is not AT_DEFAULT
                and default is not inspect.Parameter.empty
            ):
                default = converter(default)
            defaults.append(default)
            converters.append(converter)
        order, constants = [], []
        for entry in call if call is not None else names:
            if isinstance(entry, tuple):
                constants.append(entry[0])
                order.append(-len(constants))
            else:
                order.append(names.index(entry))
        n_positional = sum(p.kind in _POSITIONAL for p in parameters)
        made = _core._core_method(
            function,
            target,
            method,
            names,
            tuple(defaults),
            tuple(converters),
            n_positional,
            tuple(order),
            tuple(constants),
            inspect.Parameter.empty,
        )
        for attribute in ("__module__", "__name__", "__qualname__", "__doc__"):
            setattr(made, attribute, getattr(function, attribute))
        made.__wrapped__ = function
        core_methods.append(made)
        return made

    return decorate
