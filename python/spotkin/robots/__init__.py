"""Built-in robot descriptions (URDF), as package data. See README.md beside this file for
their provenance and licences."""

from __future__ import annotations

from importlib import resources

__all__ = ["NAMES", "path", "text"]

NAMES = ("spot_with_arm", "go2", "ur5", "panda")
"""The packaged descriptions: ``"spot_with_arm"`` (Boston Dynamics Spot and the Spot Arm), ``"go2"``
(Unitree Go2), and two arms for :meth:`spotkin.Chain.from_urdf`: ``"ur5"`` (a Universal Robots UR5)
and ``"panda"`` (a Franka Emika Panda with its hand, whose second finger mimics the first)."""


def _resource(name: str):
    if name not in NAMES:
        raise ValueError(f"name must be one of {NAMES}, got {name!r}")
    return resources.files(__name__).joinpath(f"{name}.urdf")


def path(name: str) -> str:
    """The file path of a packaged description, for :meth:`spotkin.Robot.from_urdf` (legged robots) or
    :meth:`spotkin.Chain.from_urdf` (arms)."""
    with resources.as_file(_resource(name)) as file:
        return str(file)


def text(name: str) -> str:
    """The XML text of a packaged description."""
    return _resource(name).read_text(encoding="utf-8")
