"""Interop with the Boston Dynamics Spot SDK: robot state in, joint targets out.

An optional part of spotkin: ``pip install "spotkin[sdk]"`` installs the SDK (``bosdyn-client``,
which brings ``bosdyn-api``). Importing this module without it raises ``ImportError``.

spotkin sends nothing to a robot and receives nothing from one. This module converts the SDK's
messages (the ``bosdyn.api`` protobufs, and the ``bosdyn.client.math_helpers`` objects where they
have one) into NumPy arrays in spotkin's conventions, and arrays back into messages; your program
gets the state and sends commands with the SDK's own clients.

Conventions
-----------
- **Quaternions** in the SDK (``bosdyn.api.Quaternion``, ``math_helpers.Quat``) are (w, x, y, z),
  w the scalar part. Arrays given to :func:`quat_to_matrix` are (..., 4) in that same order,
  (w, x, y, z); spotkin's own (..., 7) body poses are [x, y, z, qx, qy, qz, qw] (scalar last, as
  scipy). A quaternion whose norm differs from 1 by more than 1e-6 is invalid (as in spotkin's body
  poses); valid ones are converted exactly as their normalised rotation.
- **Transforms.** The SDK's ``a_tform_b`` is the 4x4 matrix ``a <- b``: it maps coordinates in
  frame b to frame a (``p_a = T p_b``); its position is b's origin in a. An ``SE3Pose`` with no
  ``rotation`` set has the identity rotation, as in ``math_helpers.SE3Pose.from_proto``.
- **Frame tree.** A ``FrameTreeSnapshot`` maps each child frame to its parent and the
  ``parent_tform_child`` pose; the root's entry has an empty parent name (Spot's root is
  ``"body"``). :func:`frame_transform` (snapshot, a, b) is ``a_tform_b``, as
  ``bosdyn.client.frame_helpers.get_a_tform_b``.
- **Frames of Spot** (``bosdyn.client.frame_helpers`` names): ``"body"`` is spotkin's
  :class:`~spotkin.Spot` body frame (x forward, y left, z up, origin at the centre of the four hip
  ``hx`` joints); ``"odom"`` and ``"vision"`` are world frames with z up (odometry, and vision-
  corrected); ``"flat_body"`` is the body frame turned to be level; ``"fl_foot"`` ... ``"hr_foot"``
  the feet; ``"hand"`` the arm's hand frame (``spot.arm.fk``'s tool frame).
- **Joints.** The SDK names legs ``fl``, ``fr``, ``hl``, ``hr`` (h: hind), each ``hx`` (hip roll),
  ``hy`` (hip pitch), ``kn`` (knee): ``"fl.hx"``, ... ``"hr.kn"`` are ``q12`` in
  :attr:`spotkin.Spot.joint_names` order; the arm's ``"arm0.sh0"``, ``"arm0.sh1"``, ``"arm0.el0"``,
  ``"arm0.el1"``, ``"arm0.wr0"``, ``"arm0.wr1"`` are ``q_arm``; ``"arm0.f1x"`` is the gripper.
  Robot states also report ``"arm0.hr0"``, a fixed joint (always 0): it is skipped. A joint
  command's arrays follow the SDK's joint index (``bosdyn.api.spot.spot_constants_pb2``
  ``JOINT_INDEX_*``, :data:`JOINT_NAMES`): the 12 leg joints, or those then the arm's 6 and the
  gripper (19).
- **Feet.** ``FootState.foot_position_rt_body`` is read as spotkin's foot point (the foot-sphere
  centre that :meth:`spotkin.Spot.body_fk` gives) in the body frame; ``RobotState.foot_state``
  lists the feet in leg order fl, fr, hl, hr.
- **Units**: metres and radians; joint loads in N m.
- **Batches.** Where the SDK has lists, the functions take a (nested) sequence of messages (a list,
  a tuple, a repeated field) and give arrays with those leading dimensions; arrays with leading
  dimensions give nested lists of messages.
- **Bad values.** NaN or Inf in a message, an invalid quaternion, or a 4x4 that is not a rigid
  transform give NaN in that sample's output only. Commands are the exception: a NaN or Inf
  joint target raises ``ValueError``, so that no command carries one.
"""

from __future__ import annotations

from .._support.public import publish
from .commands import (
    arm_joint_position_message,
    arm_joint_positions,
    joint_command_positions,
    joint_positions_message,
)
from .common import ARM_JOINT_NAMES, FOOT_FRAME_NAMES, GRIPPER_JOINT_NAME, JOINT_NAMES, LEG_JOINT_NAMES
from .feet import foot_positions, foot_states
from .frames import frame_transform, frame_tree_edges, frame_tree_snapshot
from .geometry import (
    array_to_vec3,
    matrix_to_quat,
    matrix_to_se3,
    quat_to_matrix,
    se3_to_matrix,
    vec3_to_array,
)
from .joints import joint_positions, joint_states, kinematic_state

__all__ = [
    "ARM_JOINT_NAMES",
    "FOOT_FRAME_NAMES",
    "GRIPPER_JOINT_NAME",
    "JOINT_NAMES",
    "LEG_JOINT_NAMES",
    "arm_joint_position_message",
    "arm_joint_positions",
    "array_to_vec3",
    "foot_positions",
    "foot_states",
    "frame_transform",
    "frame_tree_edges",
    "frame_tree_snapshot",
    "joint_command_positions",
    "joint_positions",
    "joint_positions_message",
    "joint_states",
    "kinematic_state",
    "matrix_to_quat",
    "matrix_to_se3",
    "quat_to_matrix",
    "se3_to_matrix",
    "vec3_to_array",
]

publish(__name__, globals(), __all__)
