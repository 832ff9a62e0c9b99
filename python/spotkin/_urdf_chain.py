"""Temporary: the old path of :mod:`spotkin.model.urdf_chain`, kept while spotkin.plot imports from it."""

from .model.urdf_chain import tip_candidates  # noqa: F401
