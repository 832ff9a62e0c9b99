"""Motion over the kinematic and dynamic kernels: the robot's measured state and the joint commands
a controller sends (:mod:`spotkin.motion.state`), gaits (:mod:`spotkin.motion.gait`) and their plans
(:mod:`spotkin.motion.plan`, which gives :class:`spotkin.Robot` its ``plan_gait``), and the closed-loop
gait controller (:mod:`spotkin.motion.controller`); whole-body reach with an arm, the feet fixed
(:mod:`spotkin.motion.reach`, which gives :class:`spotkin.Robot` its ``reach``), over the capsule model of
:mod:`spotkin.motion.capsules`."""

from __future__ import annotations

from .controller import GaitController
from .gait import Gait, ResolvedGait, hip_height
from .plan import GaitPlan
from .reach import ReachBox, ReachResult, ReachStatus
from .reach_path import ReachPath
from .reachability import Reachability
from .state import JointCommand, RobotState

__all__ = [
    "Gait",
    "GaitController",
    "GaitPlan",
    "JointCommand",
    "ReachBox",
    "ReachPath",
    "ReachResult",
    "ReachStatus",
    "Reachability",
    "ResolvedGait",
    "RobotState",
    "hip_height",
]
