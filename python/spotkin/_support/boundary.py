"""The Python side of the numpy boundary: the same checks as the C++ one
(``cpp/bindings/numpy_boundary.hpp``), for the few entry points that compose in NumPy.

- Non-numeric input (str, bytes, object, complex, datetime, structured) raises
  ``TypeError`` naming the argument.
- Masked arrays raise ``TypeError``: their masks would be silently ignored.
- float32 of either byte order stays float32; every other real dtype becomes float64.
- Shape and broadcast errors raise ``ValueError`` naming the arguments.
"""

from __future__ import annotations

import functools
import math
import numbers
import operator

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "FALLBACKS",
    "as_finite",
    "as_flag",
    "as_index",
    "as_real",
    "as_scalar",
    "broadcast_lead",
    "broadcast_seed",
    "check_trailing",
    "fallback_is_nearest",
    "into_out",
    "quiet_float_errors",
    "real_dtype",
    "rigid_transforms",
    "rotation_tolerance",
]


_FLOAT64, _FLOAT32 = np.dtype(np.float64), np.dtype(np.float32)


def _type_name(value) -> str:
    return type(value).__name__


def _python_numbers(array: np.ndarray, name: str) -> np.ndarray | None:
    """An object array of plain Python numbers (NumPy's answer for ints beyond int64) as float64;
    ``ValueError`` for an int beyond float64's range; None when it holds anything else."""
    items = array.ravel().tolist()
    if not all(type(x) in (int, float, bool) for x in items):
        return None
    try:
        return np.array(items, dtype=np.float64).reshape(array.shape)
    except OverflowError:
        raise ValueError(f"{name} holds an integer too large for float64 (beyond about 1.8e308)") from None


def as_real(value: ArrayLike, name: str, dtype=None) -> np.ndarray:
    """``value`` as a real ndarray: float32 (native order) for float32 input, else float64.

    ``dtype`` forces float64 or float32. Raises ``TypeError`` for non-numeric input and
    masked arrays, ``ValueError`` for ragged nested sequences.
    """
    if type(value) is np.ndarray:  # the common case, returned as is (native dtypes are singletons)
        given = value.dtype
        if (given is _FLOAT64 and dtype is not np.float32) or (given is _FLOAT32 and dtype is not np.float64):
            return value
    if isinstance(value, np.ma.MaskedArray):
        raise TypeError(
            f"{name} must be a plain array, got a masked array: its mask would be ignored; "
            f"pass {name}.filled(np.nan) to mark masked entries as missing"
        )
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be a real numeric array, got {_type_name(value)}")
    try:
        array = np.asarray(value)
    except ValueError as error:  # ragged nested lists
        raise ValueError(f"{name} must be a rectangular numeric array: {error}") from None
    except TypeError:
        raise TypeError(f"{name} must be a real numeric array, got {_type_name(value)}") from None
    kind = array.dtype.kind
    if kind not in "biuf" or array.dtype.fields is not None:
        plain = kind == "O" and not isinstance(value, np.ndarray)
        numbers = _python_numbers(array, name) if isinstance(value, (list, tuple)) else None
        if numbers is not None:  # ints beyond int64, as NumPy's float64 conversion reads them
            return numbers if dtype is not np.float32 else numbers.astype(np.float32)
        what = _type_name(value) if plain else f"dtype {array.dtype}"
        raise TypeError(f"{name} must be a real numeric array, got {what}")
    target = dtype if dtype is not None else real_dtype(array)
    if kind == "f" and array.dtype.itemsize > np.dtype(target).itemsize:
        with np.errstate(over="ignore"):  # longdouble beyond the range: Inf (then NaN or ValueError)
            return array.astype(target, copy=False)
    return array.astype(target, copy=False)


def into_out(result: np.ndarray, out: np.ndarray | None) -> np.ndarray:
    """``result`` written into the caller's ``out`` array and returned (``result`` itself when
    ``out`` is None), with the C++ binder's checks: an ndarray (``TypeError``) of the result's
    dtype (``TypeError``) and shape (``ValueError``), C-contiguous and writeable (``ValueError``).
    For the results computed in Python (chains with mimic joints)."""
    if out is None:
        return result
    if type(out) is not np.ndarray:
        raise TypeError(f"out must be a NumPy array, got {_type_name(out)}")
    if out.dtype != result.dtype:
        raise TypeError(f"out must have dtype {result.dtype}, got {out.dtype}")
    if out.shape != result.shape:
        raise ValueError(f"out must have shape {result.shape}, got {out.shape}")
    if not (out.flags.c_contiguous and out.flags.writeable):
        raise ValueError("out must be a C-contiguous and writeable array")
    out[...] = result
    return out


def rotation_tolerance(dtype) -> float:
    """The largest ``max |R^T R - I|`` a rotation given in ``dtype`` may have: 1e-9 in float64, 1e-6 in
    float32, whose rounding alone leaves up to about 5e-8 (1e-6 is the IK's pose tolerance, which
    :meth:`spotkin.SpotArm.ik` and :meth:`spotkin.Chain.ik` apply to targets of either dtype)."""
    return 1e-6 if np.dtype(dtype) == _FLOAT32 else 1e-9


def rigid_transforms(value: ArrayLike, name: str) -> np.ndarray:
    """Rigid-transform model parameters (a base, a tool: (4, 4); placements: (n, 4, 4)) as a new float64
    array for the core, which checks them to 1e-9. float32 input is checked here to its own precision
    (:func:`rotation_tolerance`: finite, last row [0, 0, 0, 1], det > 0), then each rotation is replaced
    by the nearest rotation in float64, which removes the float32 rounding and nothing else; ``ValueError``
    naming the argument otherwise. Other dtypes go to the core's checks as they are."""
    array = as_real(value, name)
    matrices = array.astype(np.float64)  # a copy
    if array.dtype != _FLOAT32 or matrices.ndim < 2 or matrices.shape[-2:] != (4, 4):
        return matrices
    tolerance = rotation_tolerance(np.float32)
    flat = matrices.reshape(-1, 4, 4)
    for k, T in enumerate(flat):
        R = T[:3, :3]
        rigid = np.isfinite(T).all() and (T[3] == [0.0, 0.0, 0.0, 1.0]).all()
        rigid = rigid and np.abs(R.T @ R - np.eye(3)).max() <= tolerance and np.linalg.det(R) > 0
        if not rigid:
            where = name if matrices.ndim == 2 else f"{name}[{k}]"
            raise ValueError(
                f"{where} must be a finite rigid transform: last row [0, 0, 0, 1], rotation part "
                f"orthonormal to {tolerance:g} (float32) with determinant +1"
            )
        U, _, Vt = np.linalg.svd(R)
        T[:3, :3] = U @ Vt
    return matrices


def real_dtype(*arrays: np.ndarray) -> type:
    """float32 when every array is float32 (either byte order), else float64."""
    if arrays and all(a.dtype.kind == "f" and a.dtype.itemsize == 4 for a in arrays):
        return np.float32
    return np.float64


def check_trailing(array: np.ndarray, name: str, trailing: tuple[int, ...]) -> tuple[int, ...]:
    """Checks ``array.shape == (..., *trailing)`` and returns the leading shape."""
    shape = array.shape
    lead = len(shape) - len(trailing)
    if lead < 0 or shape[lead:] != tuple(trailing):
        expected = ", ".join(["...", *map(str, trailing)])
        raise ValueError(f"{name} must have shape ({expected}), got {shape}")
    return shape[:lead]


def broadcast_lead(**leads: tuple[tuple[int, ...], tuple[int, ...]]) -> tuple[int, ...]:
    """Broadcasts leading shapes; ``leads`` maps an argument name to (leading shape, full shape).

    The error names every argument with its shape: "a (5, 6) and b (3, 4, 3) do not
    broadcast over their leading dimensions".
    """
    try:
        return np.broadcast_shapes(*(lead for lead, _ in leads.values()))
    except ValueError:
        described = [f"{name} {full}" for name, (_, full) in leads.items()]
        listed = " and ".join([", ".join(described[:-1]), described[-1]] if len(described) > 1 else described)
        raise ValueError(f"{listed} do not broadcast over their leading dimensions") from None


def as_index(value, name: str) -> int:
    """An integer argument (an IK slot, a count): bool, float and str raise ``TypeError``."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, got {_type_name(value)}")
    try:
        return operator.index(value)
    except TypeError:
        raise TypeError(f"{name} must be an integer, got {_type_name(value)}") from None


def as_scalar(value, name: str) -> float:
    """A real number argument (a tolerance, a length) as a float: bool, str, None, complex
    and arrays raise ``TypeError``. NaN and Inf pass: the caller checks the range."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {_type_name(value)}")
    try:
        return float(value)
    except OverflowError:  # an int beyond the float range
        raise ValueError(
            f"{name} must be a finite number, got an integer of {value.bit_length()} bits"
        ) from None


def as_finite(value, name: str, minimum: float = -math.inf, strict: bool = False) -> float:
    """:func:`as_scalar`, then ``ValueError`` unless finite and ``>= minimum`` (``> minimum``
    when ``strict``)."""
    number = as_scalar(value, name)
    if not math.isfinite(number) or number < minimum or (strict and number == minimum):
        bound = "" if minimum == -math.inf else f" {'>' if strict else '>='} {minimum:g}"
        raise ValueError(f"{name} must be a finite number{bound}, got {value!r}")
    return number


def as_flag(value, name: str) -> bool:
    """A boolean argument: only ``True``, ``False`` and numpy bools; anything else (a
    string such as ``"False"``, a number) raises ``TypeError``."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {_type_name(value)}")
    return bool(value)


FALLBACKS = ("nearest", "nan")


def fallback_is_nearest(fallback: str) -> bool:
    """The UNREACHABLE answer of the leg and body IK: "nearest" (in-limit, toward the target) or "nan"."""
    if type(fallback) is str and fallback == "nearest":  # the default: cheap
        return True
    if not isinstance(fallback, str) or fallback not in FALLBACKS:
        raise ValueError(f"fallback must be one of {FALLBACKS}, got {fallback!r}")
    return fallback == "nearest"


def quiet_float_errors(function):
    """Runs a NumPy-composed entry point under ``np.errstate(all="ignore")``: NaN and Inf
    input give NaN in that sample's output, documented, not a RuntimeWarning (an error
    under ``-W error``), as the C++ kernels do."""

    @functools.wraps(function)
    def quiet(*args, **kwargs):
        with np.errstate(all="ignore"):
            return function(*args, **kwargs)

    return quiet


def limit_table(limits: ArrayLike | None, n: int) -> np.ndarray:
    """Joint limits as a new (n, 2) float64 table of (lower, upper) rows; None: unlimited (+-inf).
    ``ValueError`` for another shape, a NaN, or lower > upper. The one check of every solver's limits."""
    if limits is None:
        return np.tile([-np.inf, np.inf], (n, 1))
    table = as_real(limits, "limits", np.float64).copy()
    if table.shape != (n, 2):
        raise ValueError(f"limits must have shape ({n}, 2) as (lower, upper) rows, got {table.shape}")
    if np.isnan(table).any() or (table[:, 0] > table[:, 1]).any():
        raise ValueError(f"limits must satisfy lower <= upper, with no NaN, got {table.tolist()}")
    return table


def broadcast_seed(T: ArrayLike, seed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Pose targets (..., 4, 4) or (..., 7) and seeds (..., n) broadcast over their leading
    dimensions (the core checks the trailing ones)."""
    T, seed = as_real(T, "T"), as_real(seed, "seed")
    trailing = 2 if T.shape[-2:] == (4, 4) else 1
    if T.shape[:-trailing] == seed.shape[:-1]:
        return T, seed  # nothing to broadcast (the common case: a few microseconds saved per call)
    lead = broadcast_lead(T=(T.shape[:-trailing], T.shape), seed=(seed.shape[:-1], seed.shape))
    return (
        np.broadcast_to(T, (*lead, *T.shape[-trailing:])),
        np.broadcast_to(seed, (*lead, *seed.shape[-1:])),
    )
