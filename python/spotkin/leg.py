"""Temporary: the old path of :mod:`spotkin.model.leg`, kept while spotkin.plot imports from it."""

from .model.leg import SLOT_NAMES  # noqa: F401
