"""Motion over the kinematic and dynamic kernels: the robot's measured state and the joint commands
a controller sends (:mod:`spotkin.motion.state`), gaits and their plans, and controllers."""

from __future__ import annotations

from .state import JointCommand, RobotState

__all__ = ["JointCommand", "RobotState"]
