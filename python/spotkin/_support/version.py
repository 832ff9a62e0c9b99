"""The package's version (``spotkin.__version__``, as in pyproject.toml)."""

__version__ = "0.1.0"
