"""Temporary: the old path of :mod:`spotkin._support.boundary`, kept while spotkin.plot imports from it."""

from ._support.boundary import as_index, as_real, as_scalar  # noqa: F401
