"""``spotkin inspect`` (what a description holds and what spotkin recognises) and ``spotkin workspace``
(a leg's workspace volume and an arm's dexterous region)."""

from __future__ import annotations

import time

import numpy as np

from .._support.version import __version__
from ..model.robot import Robot
from .pictures import _load_robot


def inspect(path: str) -> int:
    """Print a URDF's tree, the legs and arms spotkin recognises with their geometry, and why the
    other branches were not recognised. A description without legs (an arm, a gripper, a head) is
    described with the chains from its root to each tip: joints, dof, closed-form IK or what applies
    instead, mimic joints (:meth:`spotkin.Chain.from_urdf` builds them)."""
    from .. import urdf
    from ..model.urdf_chain import chains_summary

    model = urdf.load_urdf(path)
    if urdf.find_legs(model)[0]:
        print(Robot.from_urdf(path).describe())
        return 0
    text = urdf.describe(model)
    print(text[: text.index("\nlegs (")])  # the header and the tree
    print("no legs: not a Robot; its chains load with spotkin.Chain.from_urdf(path, tip=...)")
    print(chains_summary(model))
    return 0


def workspace_report(
    source: str = "spot",
    samples: int = 2_000_000,
    spacing: float = 0.05,
    orientations: int = 128,
    seed: int = 0,
) -> int:
    """Print the workspace volume of the robot's first leg (:func:`spotkin.workspace_volume`, ``samples``
    Monte Carlo points) and, with an arm, its dexterity (:func:`spotkin.dexterity` on a grid of
    ``spacing`` with ``orientations`` orientations per position). Deterministic for a given ``seed``."""
    from ..kinematics.workspace import dexterity, workspace_volume

    robot = _load_robot(source)
    name = robot.name or source
    print(f"spotkin {__version__} workspace: {name} (seed {seed})")
    if robot.legs:
        leg = robot.legs[0]
        start = time.perf_counter()
        volume, error = workspace_volume(leg, n=samples, seed=seed)
        elapsed = time.perf_counter() - start
        print(
            f"leg {robot.leg_names[0]}: workspace volume within the joint limits {1e3 * volume:.1f} L "
            f"(± {1e3 * error:.1f} L, one standard error; {samples:,} points tested by the closed-form IK, "
            f"{elapsed:.1f} s)"
        )
    arm = robot.arm
    if arm is not None:
        start = time.perf_counter()
        dex = dexterity(arm, spacing=spacing, orientations=orientations, seed=seed)
        elapsed = time.perf_counter() - start
        print(
            f"arm: {len(dex.positions):,} grid positions ({1e3 * spacing:.0f} mm spacing) x {orientations} "
            f"orientations uniform on SO(3), IK within the limits ({elapsed:.1f} s)"
        )
        print(f"  reached with some sampled orientation: {1e3 * dex.volume(1e-12):.0f} L")
        for level in (0.5, 0.9, 1.0):
            print(
                f"  reached with >= {100 * level:.0f} % of the orientations: {1e3 * dex.volume(level):.1f} L"
            )
        print(
            f"  best position: {100 * dex.fraction.max():.1f} % of the orientations, at "
            f"{np.array2string(dex.positions[np.argmax(dex.fraction)], precision=3)} m (body frame)"
        )
        best = dex.fraction >= 0.5
        if best.any():
            low, high = dex.positions[best].min(0), dex.positions[best].max(0)
            print(
                f"  the >= 50 % region spans x {low[0]:.2f}..{high[0]:.2f}, y {low[1]:.2f}..{high[1]:.2f}, "
                f"z {low[2]:.2f}..{high[2]:.2f} m"
            )
        if np.isfinite(arm.limits).any():  # the same arm with its joint limits removed, for comparison
            unlimited = np.tile([-np.inf, np.inf], (arm.dof, 1))
            free = dexterity(
                arm.with_limits(unlimited), spacing=spacing, orientations=orientations, seed=seed
            )
            print(
                f"  without joint limits: every sampled orientation at {1e3 * free.volume(1.0):.1f} L of "
                f"positions, >= 50 % at {1e3 * free.volume(0.5):.1f} L"
            )
    return 0
