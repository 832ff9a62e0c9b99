"""The built-in Spot model: four legs in SDK order, from the official URDF numbers."""

from __future__ import annotations

import numpy as np

from .arm import SpotArm
from .leg import Leg
from .models import LEG_NAMES, SPOT

__all__ = ["Spot"]


class Spot:
    """Boston Dynamics Spot. Body frame: x forward, y left, z up, origin at the
    centre of the four hx joints. Legs in SDK order: fl, fr, hl, hr."""

    __slots__ = ("_arm", "_legs", "_model")

    def __init__(self, model: dict | None = None) -> None:
        self._model = SPOT if model is None else model
        leg = self._model["leg"]
        self._legs = tuple(
            Leg(
                leg["hip_offset"],
                leg["upper"],
                leg["lower"],
                leg["knee_offset"],
                side="left" if name.endswith("l") else "right",
                limits=leg["limits"],
                name=name,
            )
            for name in LEG_NAMES
        )
        arm = self._model["arm"]
        self._arm = SpotArm(
            arm["mount"],
            arm["upper_arm"],
            arm["forearm"],
            arm["forearm_offset"],
            arm["hand"],
            limits=arm["limits"],
        )

    @property
    def arm(self) -> SpotArm:
        """The Spot Arm, mounted at its official position on the body."""
        return self._arm

    @property
    def legs(self) -> tuple[Leg, Leg, Leg, Leg]:
        """The four legs in SDK order (fl, fr, hl, hr)."""
        return self._legs

    def leg(self, name: str) -> Leg:
        """One leg by SDK name: "fl", "fr", "hl" or "hr"."""
        try:
            return self._legs[LEG_NAMES.index(name)]
        except ValueError:
            raise ValueError(f"leg name must be one of {LEG_NAMES}, got {name!r}") from None

    @property
    def hip_positions(self) -> np.ndarray:
        """(4, 3) hx joint origins in the body frame, SDK order."""
        return np.array([self._model["hip_positions"][name] for name in LEG_NAMES], dtype=np.float64)

    def __reduce__(self):
        return (Spot, (None if self._model is SPOT else self._model,))

    def __repr__(self) -> str:
        return "Spot()"
