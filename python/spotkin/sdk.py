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

import functools
import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from ._support.boundary import as_real, check_trailing
from ._support.transforms import quaternion_xyzw
from .model.arm import ARM_JOINT_NAMES

try:
    from bosdyn.api import (
        arm_command_pb2,
        basic_command_pb2,
        geometry_pb2,
        robot_command_pb2,
        robot_state_pb2,
    )
    from google.protobuf import wrappers_pb2
    from google.protobuf.message import Message
except ImportError as error:  # pragma: no cover - exercised by a subprocess test
    raise ImportError(
        'spotkin.sdk needs the Boston Dynamics Spot SDK: pip install "spotkin[sdk]" '
        "(it installs bosdyn-client and bosdyn-api)"
    ) from error

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

LEG_JOINT_NAMES = tuple(f"{leg}.{joint}" for leg in ("fl", "fr", "hl", "hr") for joint in ("hx", "hy", "kn"))
"""The 12 leg joints in the SDK's order, the order of ``q12`` (:attr:`spotkin.Spot.joint_names`)."""
"""The arm's 6 joints in the SDK's order, the order of ``q_arm``."""
GRIPPER_JOINT_NAME = "arm0.f1x"
"""The gripper's joint."""
JOINT_NAMES = (*LEG_JOINT_NAMES, *ARM_JOINT_NAMES, GRIPPER_JOINT_NAME)
"""The SDK's joint index order (``spot_constants_pb2.JOINT_INDEX_*``): a joint command's arrays."""
FOOT_FRAME_NAMES = ("fl_foot", "fr_foot", "hl_foot", "hr_foot")
"""The feet's frames in a robot state's frame tree, in leg order."""

_FIELDS = ("position", "velocity", "acceleration", "load")
_ARM_FIELDS = ("sh0", "sh1", "el0", "el1", "wr0", "wr1")
_QUATERNION_TOLERANCE = 1e-6  # as spotkin's (..., 7) body poses
_ROTATION_TOLERANCE = 1e-6  # max |R^T R - I|, as spotkin's (..., 4, 4) body poses
_LAST_ROW_TOLERANCE = 1e-9
_FLOAT32_MAX = float(np.finfo(np.float32).max)
_CONTACT_MADE = robot_state_pb2.FootState.CONTACT_MADE
_CONTACT_LOST = robot_state_pb2.FootState.CONTACT_LOST
_Q_COLUMN = {name: k for k, name in enumerate((*LEG_JOINT_NAMES, *ARM_JOINT_NAMES))}


# ---- reading messages -------------------------------------------------------------------------------


def _math_helper(value, name: str) -> bool:
    """``value`` is a ``bosdyn.client.math_helpers.<name>`` (recognised without importing the client)."""
    kind = type(value)
    return kind.__name__ == name and kind.__module__ == "bosdyn.client.math_helpers"


def _read_vec3(value):
    if isinstance(value, geometry_pb2.Vec3) or _math_helper(value, "Vec3"):
        return (value.x, value.y, value.z)
    return None


def _read_quat(value):
    if isinstance(value, geometry_pb2.Quaternion) or _math_helper(value, "Quat"):
        return (value.w, value.x, value.y, value.z)
    return None


def _read_se3(value):
    if isinstance(value, geometry_pb2.SE3Pose):
        p, r = value.position, value.rotation
        if not value.HasField("rotation"):  # as math_helpers.SE3Pose.from_proto
            return (p.x, p.y, p.z, 1.0, 0.0, 0.0, 0.0)
        return (p.x, p.y, p.z, r.w, r.x, r.y, r.z)
    if _math_helper(value, "SE3Pose"):
        r = value.rot
        return (value.x, value.y, value.z, r.w, r.x, r.y, r.z)
    return None


def _is_sequence(value) -> bool:
    if isinstance(value, np.ndarray):
        return value.dtype == object and value.ndim > 0
    return isinstance(value, Sequence) and not isinstance(value, (str, bytes, Message))


def _type_name(value) -> str:
    return type(value).__name__


def _gather(value, name: str, read, width: int, what: str) -> np.ndarray:
    """One message, or a (nested) sequence of them, as a float64 array (..., width)."""
    rows: list = []

    def walk(item) -> tuple[int, ...]:
        row = read(item)
        if row is not None:
            rows.append(row)
            return ()
        if not _is_sequence(item):
            raise TypeError(f"{name} must be {what} or a sequence of them, got {_type_name(item)}")
        shapes = {walk(element) for element in item}
        if len(shapes) > 1:
            raise ValueError(f"{name} is a ragged nesting of {what}: every level must hold as many")
        return (len(item), *(shapes.pop() if shapes else ()))

    lead = walk(value)
    try:
        array = np.array(rows, dtype=np.float64).reshape(*lead, width)
    except (TypeError, ValueError):  # a math_helpers object holding non-numbers
        raise TypeError(f"{name} must hold real numbers") from None
    return array


def _nested(messages: list, lead: tuple[int, ...]):
    """One message for lead (), else nested lists with the leading shape."""
    if not lead:
        return messages[0]
    holder = np.empty(len(messages), dtype=object)
    holder[:] = messages
    return holder.reshape(lead).tolist()


def _first_leaf(value):
    while _is_sequence(value):
        if len(value) == 0:
            return None
        value = value[0]
    return value


# ---- rotations and transforms (vectorised) -------------------------------------------------------------


def _quat_matrices(wxyz: np.ndarray) -> np.ndarray:
    """(..., 4) (w, x, y, z) -> (..., 3, 3); NaN where the norm is not 1 within the tolerance."""
    with np.errstate(all="ignore"):
        w, x, y, z = np.moveaxis(wxyz, -1, 0)
        norm2 = w * w + x * x + y * y + z * z
        s = 2.0 / norm2
        R = np.stack(
            [
                np.stack([1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)], -1),
                np.stack([s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)], -1),
                np.stack([s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)], -1),
            ],
            -2,
        )
        bad = ~(np.abs(np.sqrt(norm2) - 1.0) <= _QUATERNION_TOLERANCE) | ~np.isfinite(R).all((-2, -1))
    R[bad] = np.nan
    return R


def _se3_matrix(pose) -> np.ndarray:
    """One (7,) [x, y, z, w, qx, qy, qz] -> (4, 4): :func:`_se3_matrices` for a single pose, in
    plain floats (a frame walk's edges; the same operations, so the same numbers)."""
    x, y, z, w, qx, qy, qz = (float(v) for v in pose)
    norm2 = w * w + qx * qx + qy * qy + qz * qz
    if not (math.isfinite(norm2) and abs(math.sqrt(norm2) - 1.0) <= _QUATERNION_TOLERANCE):
        return np.full((4, 4), math.nan)
    s = 2.0 / norm2
    T = np.array(
        [
            [1 - s * (qy * qy + qz * qz), s * (qx * qy - qz * w), s * (qx * qz + qy * w), x],
            [s * (qx * qy + qz * w), 1 - s * (qx * qx + qz * qz), s * (qy * qz - qx * w), y],
            [s * (qx * qz - qy * w), s * (qy * qz + qx * w), 1 - s * (qx * qx + qy * qy), z],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )
    return T if math.isfinite(x) and math.isfinite(y) and math.isfinite(z) else np.full((4, 4), math.nan)


def _se3_matrices(pose: np.ndarray) -> np.ndarray:
    """(..., 7) [x, y, z, w, qx, qy, qz] -> (..., 4, 4); NaN for an invalid rotation or number."""
    T = np.zeros((*pose.shape[:-1], 4, 4))
    T[..., :3, :3] = _quat_matrices(pose[..., 3:])
    T[..., :3, 3] = pose[..., :3]
    T[..., 3, 3] = 1.0
    bad = ~np.isfinite(T).all((-2, -1))
    T[bad] = np.nan
    return T


def _rotation_ok(R: np.ndarray) -> np.ndarray:
    """(..., 3, 3) -> (...): finite, orthonormal within the tolerance, det > 0."""
    with np.errstate(all="ignore"):
        finite = np.isfinite(R).all((-2, -1))
        safe = np.where(finite[..., None, None], R, np.eye(3))
        orth = np.abs(np.swapaxes(safe, -1, -2) @ safe - np.eye(3)).max(axis=(-2, -1), initial=0.0)
        return finite & (orth <= _ROTATION_TOLERANCE) & (np.linalg.det(safe) > 0)


def _matrix_quats(R: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations -> (..., 4) unit (w, x, y, z) with w >= 0, the SDK's order."""
    return quaternion_xyzw(R)[..., [3, 0, 1, 2]]


def _rigid_inverse(T: np.ndarray) -> np.ndarray:
    inverse = np.eye(4)
    R = T[:3, :3].T
    inverse[:3, :3] = R
    inverse[:3, 3] = -R @ T[:3, 3]
    return inverse


# ---- geometry: Vec3, Quaternion, SE3Pose --------------------------------------------------------------


def vec3_to_array(vec) -> np.ndarray:
    """(3,) [x, y, z] float64 from a ``bosdyn.api.Vec3`` or a ``math_helpers.Vec3``; (..., 3) from a
    (nested) sequence of them. ``TypeError`` for anything else."""
    return _gather(vec, "vec", _read_vec3, 3, "a bosdyn.api.Vec3 or math_helpers.Vec3")


def array_to_vec3(p: ArrayLike):
    """A ``bosdyn.api.Vec3`` from p (3,); nested lists of them from p (..., 3). NaN stays NaN."""
    p = as_real(p, "p", np.float64)
    lead = check_trailing(p, "p", (3,))
    flat = p.reshape(-1, 3).tolist()
    return _nested([geometry_pb2.Vec3(x=x, y=y, z=z) for x, y, z in flat], lead)


def quat_to_matrix(quat) -> np.ndarray:
    """(3, 3) rotation matrix from a quaternion in the SDK's (w, x, y, z) order.

    ``quat`` is a ``bosdyn.api.Quaternion``, a ``math_helpers.Quat``, a (nested) sequence of them
    (giving (..., 3, 3)), or a real array (..., 4) holding (w, x, y, z) (the scalar first, as the
    SDK; not scipy's (x, y, z, w)). A quaternion whose norm differs from 1 by more than 1e-6, or
    with NaN or Inf, gives a NaN matrix for that sample only. The result is float64.
    """
    leaf = _first_leaf(quat)
    if leaf is None or isinstance(leaf, Message) or type(leaf).__module__ == "bosdyn.client.math_helpers":
        wxyz = _gather(quat, "quat", _read_quat, 4, "a bosdyn.api.Quaternion or math_helpers.Quat")
    else:
        wxyz = as_real(quat, "quat", np.float64)
        check_trailing(wxyz, "quat", (4,))
    return _quat_matrices(wxyz)


def matrix_to_quat(R: ArrayLike):
    """A ``bosdyn.api.Quaternion`` (w, x, y, z; w >= 0) from a rotation matrix R (3, 3); nested lists
    of them from R (..., 3, 3). A matrix that is not a rotation (``max |R^T R - I| > 1e-6``,
    ``det R <= 0``, NaN or Inf) gives a quaternion of NaN for that sample only."""
    R = as_real(R, "R", np.float64)
    lead = check_trailing(R, "R", (3, 3))
    q = _matrix_quats(R)
    q[~_rotation_ok(R)] = np.nan
    flat = q.reshape(-1, 4).tolist()
    return _nested([geometry_pb2.Quaternion(w=w, x=x, y=y, z=z) for w, x, y, z in flat], lead)


def se3_to_matrix(pose) -> np.ndarray:
    """(4, 4) ``a <- b`` transform from a ``bosdyn.api.SE3Pose`` or ``math_helpers.SE3Pose``
    (``a_tform_b``); (..., 4, 4) from a (nested) sequence of them.

    An unset rotation is the identity (as the SDK reads it). An invalid quaternion (see
    :func:`quat_to_matrix`), NaN or Inf give a NaN matrix for that sample only. float64.
    """
    return _se3_matrices(_gather(pose, "pose", _read_se3, 7, "a bosdyn.api.SE3Pose or math_helpers.SE3Pose"))


def matrix_to_se3(T: ArrayLike):
    """A ``bosdyn.api.SE3Pose`` from a rigid transform T (4, 4) (``a_tform_b`` for T = a <- b);
    nested lists of them from T (..., 4, 4).

    The rotation is a unit quaternion with w >= 0. A sample that is not a rigid transform (last
    row not [0, 0, 0, 1] within 1e-9, ``max |R^T R - I| > 1e-6``, ``det R <= 0``, NaN or Inf) gives
    a pose whose seven numbers are NaN, that sample only.
    """
    T = as_real(T, "T", np.float64)
    lead = check_trailing(T, "T", (4, 4))
    q = _matrix_quats(T[..., :3, :3])
    with np.errstate(invalid="ignore"):
        row = np.abs(T[..., 3, :] - [0.0, 0.0, 0.0, 1.0]).max(axis=-1, initial=0.0)
    ok = _rotation_ok(T[..., :3, :3]) & (row <= _LAST_ROW_TOLERANCE) & np.isfinite(T[..., :3, 3]).all(-1)
    values = np.concatenate([T[..., :3, 3], q], axis=-1)
    values[~ok] = np.nan
    messages = [
        geometry_pb2.SE3Pose(
            position=geometry_pb2.Vec3(x=x, y=y, z=z), rotation=geometry_pb2.Quaternion(w=w, x=qx, y=qy, z=qz)
        )
        for x, y, z, w, qx, qy, qz in values.reshape(-1, 7).tolist()
    ]
    return _nested(messages, lead)


# ---- frame trees ----------------------------------------------------------------------------------------


def _snapshot(value):
    """The FrameTreeSnapshot held by a snapshot, a KinematicState or a RobotState, else None."""
    if isinstance(value, geometry_pb2.FrameTreeSnapshot):
        return value
    if isinstance(value, robot_state_pb2.KinematicState):
        return value.transforms_snapshot
    if isinstance(value, robot_state_pb2.RobotState):
        return value.kinematic_state.transforms_snapshot
    return None


_SNAPSHOT_KINDS = "a bosdyn.api.FrameTreeSnapshot, KinematicState or RobotState"


def _frame_name(value, name: str) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a frame name (str), got {_type_name(value)}")
    return value


def _known_frames(edges) -> list[str]:
    names = set(edges)
    names.update(edge.parent_frame_name for edge in edges.values())
    names.discard("")
    return sorted(names)


def _root_from(edges, frame: str, name: str) -> tuple[str, np.ndarray]:
    """(root, root <- frame) by walking up the tree from ``frame``."""
    T = np.eye(4)
    seen = {frame}
    current = frame
    while True:
        edge = edges.get(current)
        if edge is None or not edge.parent_frame_name:  # the root, with or without its own entry
            if edge is None and current == frame and frame not in _known_frames(edges):
                known = _known_frames(edges)
                raise ValueError(
                    f"{name} {frame!r} is not in the frame tree; its frames: "
                    + (", ".join(repr(f) for f in known) if known else "none (an empty snapshot)")
                )
            return current, T
        T = _se3_matrix(_read_se3(edge.parent_tform_child)) @ T
        current = edge.parent_frame_name
        if current in seen:
            raise ValueError(f"the frame tree has a loop through {current!r}")
        seen.add(current)


def _one_transform(snapshot, frame_a: str, frame_b: str) -> np.ndarray:
    edges = snapshot.child_to_parent_edge_map
    root_a, root_T_a = _root_from(edges, frame_a, "frame_a")
    root_b, root_T_b = _root_from(edges, frame_b, "frame_b")
    if root_a != root_b:
        raise ValueError(
            f"frame_a {frame_a!r} and frame_b {frame_b!r} are in separate trees "
            f"(roots {root_a!r} and {root_b!r})"
        )
    with np.errstate(invalid="ignore"):
        T = _rigid_inverse(root_T_a) @ root_T_b
    if not np.isfinite(T).all():
        T[...] = np.nan
    return T


def frame_transform(snapshot, frame_a: str, frame_b: str) -> np.ndarray:
    """(4, 4) ``a_tform_b``: the transform ``frame_a <- frame_b`` from a robot state's frame tree,
    as ``bosdyn.client.frame_helpers.get_a_tform_b`` (``frame_transform(s, "odom", "body")`` is the
    body's pose in the odom frame).

    ``snapshot`` is a ``bosdyn.api.FrameTreeSnapshot``, or a ``KinematicState`` or ``RobotState``
    holding one (``transforms_snapshot``); a sequence of them gives (n, 4, 4). The walk goes from
    each frame up to the root and back down; any two frames of one tree work. A frame that is not in
    the tree, frames in separate trees, or a loop raise ``ValueError`` naming them. An edge with NaN,
    Inf or an invalid quaternion on the path gives a NaN result for that snapshot only.
    """
    frame_a = _frame_name(frame_a, "frame_a")
    frame_b = _frame_name(frame_b, "frame_b")
    one = _snapshot(snapshot)
    if one is not None:
        return _one_transform(one, frame_a, frame_b)
    if not _is_sequence(snapshot):
        raise TypeError(
            f"snapshot must be {_SNAPSHOT_KINDS}, or a sequence of them; got {_type_name(snapshot)}"
        )
    out = np.empty((len(snapshot), 4, 4))
    for k, item in enumerate(snapshot):
        single = _snapshot(item)
        if single is None:
            raise TypeError(f"snapshot[{k}] must be {_SNAPSHOT_KINDS}, got {_type_name(item)}")
        out[k] = _one_transform(single, frame_a, frame_b)
    return out


def frame_tree_edges(snapshot) -> dict[str, tuple[str, np.ndarray]]:
    """Every edge of a frame tree: ``{child: (parent, parent_tform_child (4, 4))}``, the root left out
    (for example to publish them as ROS ``tf`` transforms). ``snapshot`` as in
    :func:`frame_transform`, one of them. Invalid poses give NaN matrices (see :func:`se3_to_matrix`)."""
    one = _snapshot(snapshot)
    if one is None:
        raise TypeError(f"snapshot must be {_SNAPSHOT_KINDS}, got {_type_name(snapshot)}")
    edges = {}
    for child, edge in one.child_to_parent_edge_map.items():
        if edge.parent_frame_name:
            edges[child] = (
                edge.parent_frame_name,
                _se3_matrix(_read_se3(edge.parent_tform_child)),
            )
    return edges


def _pose_message(value, name: str):
    """A SE3Pose message from a (4, 4) array, a SE3Pose message or a math_helpers.SE3Pose."""
    if isinstance(value, geometry_pb2.SE3Pose):
        return value
    if _math_helper(value, "SE3Pose"):
        return value.to_proto()
    T = as_real(value, name, np.float64)
    if T.shape != (4, 4):
        raise ValueError(f"{name} must be a (4, 4) transform or an SE3Pose, got shape {T.shape}")
    return matrix_to_se3(T)


def frame_tree_snapshot(edges: Mapping) -> geometry_pb2.FrameTreeSnapshot:
    """A ``bosdyn.api.FrameTreeSnapshot`` from ``{child: (parent, parent_tform_child)}``, each pose a
    (4, 4) transform, an ``SE3Pose`` message or a ``math_helpers.SE3Pose``; the inverse of
    :func:`frame_tree_edges`.

    The root (the one parent that is no child) gets its own entry with an empty parent name and the
    identity, as in a robot's snapshot. Names must be non-empty strings; a frame that is its own
    parent, a loop, or several roots raise ``ValueError``. A 4x4 that is not a rigid transform is
    stored as NaN (see :func:`matrix_to_se3`).
    """
    if not isinstance(edges, Mapping):
        raise TypeError(
            f"edges must be a dict {{child: (parent, parent_tform_child)}}, got {_type_name(edges)}"
        )
    snapshot = geometry_pb2.FrameTreeSnapshot()
    table = snapshot.child_to_parent_edge_map
    parents = {}
    for child, edge in edges.items():
        if not isinstance(child, str) or not child:
            raise TypeError(f"edges: a child frame name must be a non-empty str, got {child!r}")
        if not isinstance(edge, (tuple, list)) or len(edge) != 2:
            raise TypeError(
                f"edges[{child!r}] must be a pair (parent, parent_tform_child), got {_type_name(edge)}"
            )
        parent, pose = edge
        if not isinstance(parent, str) or not parent:
            raise TypeError(
                f"edges[{child!r}]: the parent frame name must be a non-empty str, got {parent!r}"
            )
        if parent == child:
            raise ValueError(f"edges[{child!r}]: a frame cannot be its own parent")
        parents[child] = parent
        message = _pose_message(pose, f"edges[{child!r}] pose")
        table[child].parent_frame_name = parent
        table[child].parent_tform_child.CopyFrom(message)
    roots = sorted({parent for parent in parents.values() if parent not in parents})
    for child in parents:  # every walk up must end at a root
        seen, current = {child}, child
        while current in parents:
            current = parents[current]
            if current in seen:
                raise ValueError(f"edges: a loop through {current!r}")
            seen.add(current)
    if len(roots) != 1 and parents:
        raise ValueError(f"edges must form one tree, got the roots {roots}")
    for root in roots:
        table[root].parent_frame_name = ""
        table[root].parent_tform_child.CopyFrom(
            geometry_pb2.SE3Pose(position=geometry_pb2.Vec3(), rotation=geometry_pb2.Quaternion(w=1.0))
        )
    return snapshot


# ---- joint states ------------------------------------------------------------------------------------------


def _field(field: str, allowed=_FIELDS) -> str:
    if not isinstance(field, str) or field not in allowed:
        raise ValueError(f"field must be one of {allowed}, got {field!r}")
    return field


def _joint_source(state):
    """("named", repeated JointState) or ("indexed", CombinedJointStates), or None."""
    if isinstance(state, robot_state_pb2.RobotState):
        return "named", state.kinematic_state.joint_states
    if isinstance(state, robot_state_pb2.KinematicState):
        return "named", state.joint_states
    if isinstance(state, robot_state_pb2.RobotStateStreamResponse):
        return "indexed", state.joint_states
    if isinstance(state, robot_state_pb2.CombinedJointStates):
        return "indexed", state
    return None


_STATE_KINDS = "a bosdyn.api.RobotState, KinematicState, RobotStateStreamResponse or CombinedJointStates"


def _one_joint_states(state, field: str, where: str, present: bool = False):
    """(names, values), and with ``present`` a mask of the values the state sets."""
    source = _joint_source(state)
    if source is None:
        raise TypeError(f"{where} must be {_STATE_KINDS}, got {_type_name(state)}")
    kind, joints = source
    if kind == "named":
        names = tuple(joint.name for joint in joints)
        if len(set(names)) != len(names):
            twice = sorted({name for name in names if names.count(name) > 1})
            raise ValueError(f"{where} lists the joints {twice} twice")
        has = [joint.HasField(field) for joint in joints]
        values = np.array(
            [getattr(joint, field).value if set_ else math.nan for joint, set_ in zip(joints, has)],
            dtype=np.float64,
        )
        return (names, values, np.array(has, dtype=bool)) if present else (names, values)
    if field == "acceleration":
        raise ValueError("field 'acceleration': the streamed joint states have position, velocity and load")
    values = np.array(getattr(joints, field), dtype=np.float64)
    if values.size not in (0, len(LEG_JOINT_NAMES), len(JOINT_NAMES)):
        raise ValueError(
            f"{where}: the streamed joint {field}s must number 12 (legs) or 19 (legs, arm, gripper), "
            f"got {values.size}"
        )
    names = JOINT_NAMES[: values.size]
    return (names, values, np.ones(values.size, dtype=bool)) if present else (names, values)


def joint_states(state, field: str = "position") -> tuple[tuple[str, ...], np.ndarray]:
    """``(names, values)``: a robot state's joints by name, as the SDK reports them (the pairs
    :meth:`spotkin.Robot.q_from_names` reads).

    ``state`` is a ``bosdyn.api.RobotState`` or ``KinematicState`` (``joint_states``, names as
    given, ``arm0.hr0`` and ``arm0.f1x`` included), or a streamed ``RobotStateStreamResponse`` or
    ``CombinedJointStates`` (arrays in the SDK's joint index order, named by :data:`JOINT_NAMES`).
    ``field`` is ``"position"`` (rad), ``"velocity"`` (rad/s), ``"acceleration"`` (rad/s^2) or
    ``"load"`` (N m); a value the state does not set is NaN. ``values`` is float64 (k,). A joint
    listed twice, or a streamed array of another length than 12 or 19, raises ``ValueError``.
    """
    return _one_joint_states(state, _field(field), "state")


def joint_positions(state, *, field: str = "position", missing: str = "nan") -> tuple[np.ndarray, np.ndarray]:
    """``(q12, q_arm)`` from a robot state: the leg joints (12,) in :data:`LEG_JOINT_NAMES` order and
    the arm's (6,) in :data:`ARM_JOINT_NAMES` order, float64.

    ``state`` as in :func:`joint_states`, or a sequence of them (giving (n, 12) and (n, 6)).
    Joints the state does not report (the arm's on a Spot without one) or reports without a
    value are NaN (``missing="nan"``), or raise ``ValueError`` naming them (``missing="raise"``);
    a reported NaN stays NaN in its joint. Other joints (the gripper ``arm0.f1x``, the fixed
    ``arm0.hr0``) are skipped. ``field`` picks positions, velocities, accelerations or loads (see
    :func:`joint_states`).
    """
    field = _field(field)
    if not isinstance(missing, str) or missing not in ("nan", "raise"):
        raise ValueError(f"missing must be 'nan' or 'raise', got {missing!r}")

    def one(item, where):
        names, values, present = _one_joint_states(item, field, where, present=True)
        q = np.full(len(_Q_COLUMN), math.nan)
        found = np.zeros(len(_Q_COLUMN), dtype=bool)
        for name, value, set_ in zip(names, values, present):
            k = _Q_COLUMN.get(name)
            if k is not None:
                q[k], found[k] = value, set_
        if missing == "raise" and not found.all():
            absent = [name for name, k in _Q_COLUMN.items() if not found[k]]
            raise ValueError(f"{where} has no {field} for the joints {absent}")
        return q

    if _joint_source(state) is not None:
        q = one(state, "state")
    elif _is_sequence(state):
        q = np.array([one(item, f"state[{k}]") for k, item in enumerate(state)]).reshape(-1, len(_Q_COLUMN))
    else:
        raise TypeError(f"state must be {_STATE_KINDS}, or a sequence of them; got {_type_name(state)}")
    return q[..., :12].copy(), q[..., 12:].copy()


def _joint_names(names, name: str) -> tuple[str, ...]:
    if isinstance(names, (str, bytes, Mapping)) or not isinstance(names, (Sequence, np.ndarray)):
        raise TypeError(f"{name} must be a sequence of joint names, got {_type_name(names)}")
    listed = tuple(names)
    for item in listed:
        if not isinstance(item, str):
            raise TypeError(f"{name} must hold joint names (str), got {_type_name(item)}")
    if len(set(listed)) != len(listed):
        raise ValueError(f"{name} names a joint twice")
    return tuple(map(str, listed))


def kinematic_state(
    names,
    position: ArrayLike,
    *,
    velocity: ArrayLike | None = None,
    acceleration: ArrayLike | None = None,
    load: ArrayLike | None = None,
    frames=None,
) -> robot_state_pb2.KinematicState:
    """A ``bosdyn.api.KinematicState`` from joint values by name and a frame tree: the inverse of
    :func:`joint_states` and :func:`frame_tree_edges` (for tests, simulators and logs).

    ``names`` is a sequence of k joint names (for Spot ``sk.Spot.joint_names +
    sk.Spot.arm_joint_names``, and ``"arm0.f1x"`` for the gripper); ``position`` and the optional
    ``velocity``, ``acceleration`` and ``load`` are (k,) arrays. A NaN value is left unset (the state
    does not report it; :func:`joint_states` reads it back as NaN). ``frames`` is a
    ``FrameTreeSnapshot`` or ``{child: (parent, parent_tform_child)}`` (see
    :func:`frame_tree_snapshot`).
    """
    names = _joint_names(names, "names")
    columns = {}
    given = {"position": position, "velocity": velocity, "acceleration": acceleration, "load": load}
    if position is None:
        raise TypeError("position must be a real numeric array (k,), got None")
    for field, values in given.items():
        if values is None:
            continue
        array = as_real(values, field, np.float64)
        check_trailing(array, field, (len(names),))
        if array.ndim != 1:
            raise ValueError(f"{field} must have shape ({len(names)},), got {array.shape}")
        columns[field] = array.tolist()
    state = robot_state_pb2.KinematicState()
    for k, name in enumerate(names):
        joint = state.joint_states.add(name=name)
        for field, values in columns.items():
            if not math.isnan(values[k]):
                getattr(joint, field).value = values[k]
    if isinstance(frames, geometry_pb2.FrameTreeSnapshot):
        state.transforms_snapshot.CopyFrom(frames)
    elif isinstance(frames, Mapping):
        state.transforms_snapshot.CopyFrom(frame_tree_snapshot(frames))
    elif frames is not None:
        raise TypeError(
            "frames must be a bosdyn.api.FrameTreeSnapshot or a dict {child: (parent, parent_tform_child)}, "
            f"got {_type_name(frames)}"
        )
    return state


# ---- feet -------------------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=1)
def _default_spot():
    from .model.spot import Spot

    return Spot()


def _checked_spot(spot):
    from .model.spot import Spot

    if spot is None:
        return _default_spot()
    if not isinstance(spot, Spot):
        raise TypeError(f"spot must be an sk.Spot or None, got {_type_name(spot)}")
    return spot


_SOURCES = ("auto", "foot_state", "kinematics", "frames")


def _one_feet(state, frame: str, source: str, spot, where: str) -> np.ndarray:
    if isinstance(state, robot_state_pb2.RobotState):
        foot_list = state.foot_state
    elif isinstance(state, robot_state_pb2.KinematicState):
        foot_list = ()
    else:
        raise TypeError(f"{where} must be a bosdyn.api.RobotState or KinematicState, got {_type_name(state)}")
    chosen = source
    if source == "auto":
        chosen = "foot_state" if len(foot_list) == 4 else "kinematics"
    if chosen == "foot_state":
        if len(foot_list) != 4:
            raise ValueError(
                f"{where} has {len(foot_list)} foot states; source='foot_state' needs 4 (fl, fr, hl, hr)"
            )
        feet = np.array([_read_vec3(foot.foot_position_rt_body) for foot in foot_list], dtype=np.float64)
    elif chosen == "kinematics":
        q12, _ = joint_positions(state)
        feet = spot.body_fk(np.eye(4), q12)
    else:
        feet = np.array([frame_transform(state, "body", name)[:3, 3] for name in FOOT_FRAME_NAMES])
    if frame != "body":
        T = frame_transform(state, frame, "body")
        with np.errstate(invalid="ignore"):
            feet = feet @ T[:3, :3].T + T[:3, 3]
    return feet


def foot_positions(state, frame: str = "body", *, source: str = "auto", spot=None) -> np.ndarray:
    """(4, 3) foot points in ``frame``, legs in order fl, fr, hl, hr, float64.

    ``state`` is a ``bosdyn.api.RobotState`` (or a ``KinematicState``, which has no foot states), or a
    sequence of them (giving (n, 4, 3)). ``source``: ``"foot_state"`` reads
    ``RobotState.foot_state`` (``foot_position_rt_body``, in the body frame); ``"kinematics"`` runs
    spotkin's FK on the state's leg joints (``spot``: the :class:`spotkin.Spot` model, default
    ``sk.Spot()``; a leg with a missing joint gets NaN); ``"frames"`` reads the tree's ``fl_foot``
    ... ``hr_foot`` frames; ``"auto"`` (default) takes the foot states when all four are there, else
    the kinematics. The points are then moved into ``frame`` through the state's frame tree
    (``frame_transform(state, frame, "body")``): ``"body"``, ``"odom"``, ``"vision"``, or any frame of
    the tree. Each is spotkin's foot point (the foot-sphere centre), as :meth:`spotkin.Spot.body_ik`
    takes feet.
    """
    frame = _frame_name(frame, "frame")
    if not isinstance(source, str) or source not in _SOURCES:
        raise ValueError(f"source must be one of {_SOURCES}, got {source!r}")
    spot = _checked_spot(spot)
    if isinstance(state, (robot_state_pb2.RobotState, robot_state_pb2.KinematicState)):
        return _one_feet(state, frame, source, spot, "state")
    if not _is_sequence(state):
        raise TypeError(
            f"state must be a bosdyn.api.RobotState or KinematicState, or a sequence; got {_type_name(state)}"
        )
    out = np.empty((len(state), 4, 3))
    for k, item in enumerate(state):
        out[k] = _one_feet(item, frame, source, spot, f"state[{k}]")
    return out


def foot_states(feet: ArrayLike, contact=None) -> list:
    """A list of ``bosdyn.api.FootState`` (for ``RobotState.foot_state``) from foot points ``feet``
    (n, 3) in the body frame, in leg order (fl, fr, hl, hr for Spot); the inverse of
    :func:`foot_positions` with ``source="foot_state"``. ``contact``: None (``CONTACT_UNKNOWN``) or n
    booleans (True: ``CONTACT_MADE``, False: ``CONTACT_LOST``). NaN coordinates stay NaN."""
    feet = as_real(feet, "feet", np.float64)
    if feet.ndim != 2 or feet.shape[1] != 3:
        raise ValueError(f"feet must have shape (n, 3), got {feet.shape}")
    if contact is not None:
        if isinstance(contact, (str, bytes)):
            raise TypeError(f"contact must be None or {len(feet)} booleans, got {_type_name(contact)}")
        flags = np.asarray(contact)
        if flags.dtype != np.bool_:
            raise TypeError(f"contact must be None or {len(feet)} booleans, got dtype {flags.dtype}")
        if flags.shape != (len(feet),):
            raise ValueError(f"contact must have shape ({len(feet)},), got {flags.shape}")
        contact = flags.tolist()
    states = []
    for k, (x, y, z) in enumerate(feet.tolist()):
        state = robot_state_pb2.FootState(foot_position_rt_body=geometry_pb2.Vec3(x=x, y=y, z=z))
        if contact is not None:
            state.contact = _CONTACT_MADE if contact[k] else _CONTACT_LOST
        states.append(state)
    return states


# ---- joint commands ---------------------------------------------------------------------------------------


def _command_values(value, name: str, width: int) -> np.ndarray:
    """A (..., width) float64 array of finite numbers that a float32 field holds."""
    array = as_real(value, name, np.float64)
    check_trailing(array, name, (width,))
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(array) <= _FLOAT32_MAX)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{name}[{', '.join(map(str, where))}] is {array[where]}: a joint command must hold finite "
            "numbers within float32 range (the message's fields are float32)"
        )
    return array


def joint_positions_message(
    q12: ArrayLike,
    q_arm: ArrayLike | None = None,
    gripper: ArrayLike | None = None,
    *,
    velocity: ArrayLike | None = None,
    load: ArrayLike | None = None,
):
    """The SDK's joint-position message for a joint command: a ``bosdyn.api.JointCommand.UpdateRequest``
    (what ``JointControlStreamRequest.joint_command`` holds), its arrays in the SDK's joint index
    order (:data:`JOINT_NAMES`).

    ``q12`` (..., 12) are the leg targets (rad, :data:`LEG_JOINT_NAMES` order). With ``q_arm``
    (..., 6) the message holds all 19 joints, so ``gripper`` (..., ) (rad) must be given too.
    ``velocity`` and ``load`` (..., 12 or 19, matching) fill those arrays; fields left out stay
    empty. One message for single targets; nested lists of messages (a stream) for leading
    dimensions, which broadcast. The fields are float32 (about 1e-7 rad of rounding). A NaN or Inf
    target (such as a failed IK's NaN), or one beyond float32, raises ``ValueError``: a command
    never carries one. Gains, timing and the request header are yours to set.
    """
    parts = [_command_values(q12, "q12", 12)]
    if q_arm is not None:
        if gripper is None:
            raise ValueError("gripper must be given with q_arm: the 19-joint command includes arm0.f1x")
        parts.append(_command_values(q_arm, "q_arm", 6))
        gripper = as_real(gripper, "gripper", np.float64)
        parts.append(_command_values(gripper[..., None], "gripper", 1))
    elif gripper is not None:
        raise ValueError("gripper needs q_arm: a leg-only command has 12 joints")
    width = 12 if q_arm is None else 19
    extras = {}
    for field, value in (("velocity", velocity), ("load", load)):
        if value is not None:
            extras[field] = _command_values(value, field, width)
    leads = [p.shape[:-1] for p in parts] + [e.shape[:-1] for e in extras.values()]
    try:
        lead = np.broadcast_shapes(*leads)
    except ValueError:
        raise ValueError(f"q12, q_arm, gripper, velocity and load do not broadcast: {leads}") from None
    position = np.concatenate([np.broadcast_to(p, (*lead, p.shape[-1])) for p in parts], axis=-1)
    fields = {"position": position.reshape(-1, width)}
    fields.update({f: np.broadcast_to(v, (*lead, width)).reshape(-1, width) for f, v in extras.items()})
    messages = []
    for k in range(len(fields["position"])):
        message = basic_command_pb2.JointCommand.UpdateRequest()
        for field, rows in fields.items():
            getattr(message, field).extend(rows[k].tolist())
        messages.append(message)
    return _nested(messages, tuple(lead))


def joint_command_positions(message, field: str = "position") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q12, q_arm, gripper)`` read back from a joint command: a ``JointCommand.UpdateRequest`` or a
    ``JointControlStreamRequest`` (its ``joint_command``), or a sequence of them (giving (n, 12),
    (n, 6), (n,)); the inverse of :func:`joint_positions_message`. ``field`` is ``"position"``,
    ``"velocity"`` or ``"load"``. A 12-joint command gives NaN for the arm and gripper; an array of
    another length raises ``ValueError``."""
    field = _field(field, ("position", "velocity", "load"))

    def one(item, where):
        if isinstance(item, robot_command_pb2.JointControlStreamRequest):
            item = item.joint_command
        if not isinstance(item, basic_command_pb2.JointCommand.UpdateRequest):
            raise TypeError(
                f"{where} must be a bosdyn.api.JointCommand.UpdateRequest or JointControlStreamRequest, "
                f"got {_type_name(item)}"
            )
        values = np.array(getattr(item, field), dtype=np.float64)
        if values.size not in (12, 19):
            raise ValueError(f"{where}: a joint command's {field} has 12 or 19 values, got {values.size}")
        full = np.full(19, math.nan)
        full[: values.size] = values
        return full

    if _is_sequence(message):
        rows = np.array([one(item, f"message[{k}]") for k, item in enumerate(message)]).reshape(-1, 19)
    else:
        rows = one(message, "message")
    return rows[..., :12].copy(), rows[..., 12:18].copy(), rows[..., 18].copy()


def arm_joint_position_message(q_arm: ArrayLike):
    """A ``bosdyn.api.ArmJointPosition`` (``sh0`` ... ``wr1``, the positions of an
    ``ArmJointTrajectoryPoint`` in an ``ArmJointMoveCommand``) from ``q_arm`` (6,) in
    :data:`ARM_JOINT_NAMES` order; nested lists of them for (..., 6). A NaN or Inf target raises
    ``ValueError``. ``bosdyn.client.robot_command.RobotCommandBuilder.arm_joint_command(*q_arm)``
    builds a whole arm command from the same six numbers."""
    q_arm = _command_values(q_arm, "q_arm", 6)
    messages = [
        arm_command_pb2.ArmJointPosition(
            **{joint: wrappers_pb2.DoubleValue(value=value) for joint, value in zip(_ARM_FIELDS, row)}
        )
        for row in q_arm.reshape(-1, 6).tolist()
    ]
    return _nested(messages, q_arm.shape[:-1])


def _read_arm(value):
    if isinstance(value, arm_command_pb2.ArmJointTrajectoryPoint):
        value = value.position
    if isinstance(value, arm_command_pb2.ArmJointPosition):
        return tuple(getattr(value, j).value if value.HasField(j) else math.nan for j in _ARM_FIELDS)
    return None


def arm_joint_positions(message) -> np.ndarray:
    """``q_arm`` (6,) float64 from a ``bosdyn.api.ArmJointPosition`` or ``ArmJointTrajectoryPoint``;
    (..., 6) from a (nested) sequence of them (a trajectory's ``points``). A joint the message does
    not set (the robot then keeps its current angle) is NaN."""
    return _gather(
        message, "message", _read_arm, 6, "a bosdyn.api.ArmJointPosition or ArmJointTrajectoryPoint"
    )
