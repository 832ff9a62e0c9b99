"""The MuJoCo simulator for legged robots (an optional extra: ``pip install "spotkin[sim]"``).

- :func:`mujoco_model` (:func:`mjcf` for its XML): the robot's MuJoCo model, from its spotkin
  description alone: its tree and inertials, joint limits, a free body, a sphere per foot, capsules
  and a box for the links and the body, torque motors with the URDF's effort limits, a terrain.
- :func:`run`: a controller (``controller.step(t, state, velocity) -> JointCommand``, see
  :mod:`spotkin.motion`) driving the robot in it; a :class:`SimResult` per control tick, and its
  :class:`Metrics` (distance, speed, drift, heading, lowest height, falls, torques, the tick's cost).
- Terrains: :class:`Flat` (``None``), :class:`Slope`, :class:`Step`, :class:`Bumps`.
- :func:`hip_height`: the robot's nominal standing hip height h, the speed scale of a walk
  ("0.5 h per second"); :func:`foot_radius`: its foot spheres' radius.
"""

from __future__ import annotations

try:  # the optional extra, checked before any module of the simulator imports it
    import mujoco  # noqa: F401
except ImportError as _error:  # tested in a subprocess with mujoco blocked
    raise ImportError(
        'spotkin.sim needs MuJoCo, an optional dependency: pip install "spotkin[sim]" (or pip install mujoco)'
    ) from _error

from .._support.public import publish
from .model import foot_radius, hip_height, mjcf, mujoco_model
from .runner import Metrics, SimResult, run
from .terrain import Bumps, Flat, Slope, Step

__all__ = [
    "Bumps",
    "Flat",
    "Metrics",
    "SimResult",
    "Slope",
    "Step",
    "foot_radius",
    "hip_height",
    "mjcf",
    "mujoco_model",
    "run",
]

publish(__name__, globals(), __all__)
