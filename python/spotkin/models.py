"""Built-in robot models, as data. The built-in Spot is the packaged URDF
(``spotkin/robots/spot_with_arm.urdf``, from the public ``bdaiinstitute/spot_description``
package; the official Boston Dynamics spot-sdk URDF has the same kinematics); :data:`SPOT`
holds the same numbers as a dict, for :class:`spotkin.Spot` ``(model=...)`` variations."""

from __future__ import annotations

from .model.presets import LEG_NAMES, SPOT

__all__ = [
    "LEG_NAMES",
    "SPOT",
]
