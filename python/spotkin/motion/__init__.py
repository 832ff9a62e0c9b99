"""Motion over the kinematic and dynamic kernels: the robot's measured state and the joint commands
a controller sends (:mod:`spotkin.motion.state`), gaits (:mod:`spotkin.motion.gait`) and their plans
(:mod:`spotkin.motion.plan`, which gives :class:`spotkin.Robot` its ``plan_gait``), and controllers."""

from __future__ import annotations

from .gait import Gait, ResolvedGait
from .plan import GaitPlan
from .state import JointCommand, RobotState

__all__ = ["Gait", "GaitPlan", "JointCommand", "ResolvedGait", "RobotState"]
