"""Built-in robot descriptions (URDF), as package data. See README.md beside this file for
their provenance and licences."""

from __future__ import annotations

from importlib import resources

__all__ = ["NAMES", "path", "text"]

NAMES = ("spot_with_arm", "go2")
"""The packaged descriptions: ``"spot_with_arm"`` (Boston Dynamics Spot and the Spot Arm) and
``"go2"`` (Unitree Go2)."""


def _resource(name: str):
    if name not in NAMES:
        raise ValueError(f"name must be one of {NAMES}, got {name!r}")
    return resources.files(__name__).joinpath(f"{name}.urdf")


def path(name: str) -> str:
    """The file path of a packaged description, for :meth:`spotkin.Robot.from_urdf`."""
    with resources.as_file(_resource(name)) as file:
        return str(file)


def text(name: str) -> str:
    """The XML text of a packaged description."""
    return _resource(name).read_text(encoding="utf-8")
