"""What the parts of :mod:`spotkin.sdk` share: the SDK's message modules (imported here, the one place that
says what to install when the SDK is missing), the joint and frame names, and the readers and
vectorised rotations the conversions use."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .._support.transforms import quaternion_xyzw
from ..model.arm import ARM_JOINT_NAMES

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

# the SDK's modules, which the other parts import from here
__all__ = [
    "Message",
    "arm_command_pb2",
    "basic_command_pb2",
    "geometry_pb2",
    "robot_command_pb2",
    "robot_state_pb2",
    "wrappers_pb2",
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
