"""Spot SDK messages for the ``spotkin.sdk`` entries (:mod:`fuzz.sdk`): builders (random poses,
quaternions and vectors, a robot-like frame tree and its hostile edits, the non-messages every slot
refuses) and the oracle's own plain readings of them. Imported only when the SDK is installed."""

from __future__ import annotations

import math

import numpy as np
from bosdyn.api import geometry_pb2
from scipy.spatial.transform import Rotation

from spotkin import sdk

from .objects import rigid as make_rigid
from .outputs import close, describe
from .slots import REJECT, Arg

QUAT_TOL = 1e-6


# ---- messages ----


def rigid(seed):
    return make_rigid(
        Rotation.random(random_state=seed).as_matrix(), np.random.default_rng(seed).uniform(-1, 1, 3)
    )


def se3(T):
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    return geometry_pb2.SE3Pose(
        position=geometry_pb2.Vec3(x=T[0, 3], y=T[1, 3], z=T[2, 3]),
        rotation=geometry_pb2.Quaternion(w=w, x=x, y=y, z=z),
    )


def quat(seed):
    x, y, z, w = Rotation.random(random_state=seed).as_quat()
    return geometry_pb2.Quaternion(w=w, x=x, y=y, z=z)


def vec(seed):
    x, y, z = np.random.default_rng(seed).normal(size=3)
    return geometry_pb2.Vec3(x=x, y=y, z=z)


def objects(*items):
    holder = np.empty(len(items), dtype=object)
    holder[:] = list(items)
    return holder


FRAMES = {
    "odom": "body",
    "vision": "body",
    "flat_body": "body",
    "gpe": "odom",
    "hand": "body",
    "arm0.link_wr1": "hand",
    **dict.fromkeys(sdk.FOOT_FRAME_NAMES, "body"),
}


def snapshot(root_edge=True, change=None):
    """A robot-like FrameTreeSnapshot (root "body"); ``change(edges)`` edits the messages."""
    tree = geometry_pb2.FrameTreeSnapshot()
    if root_edge:
        tree.child_to_parent_edge_map["body"].parent_frame_name = ""
    for k, (child, parent) in enumerate(FRAMES.items()):
        edge = tree.child_to_parent_edge_map[child]
        edge.parent_frame_name = parent
        edge.parent_tform_child.CopyFrom(se3(rigid(100 + k)))
    if change is not None:
        change(tree.child_to_parent_edge_map)
    return tree


def bad_gpe(value):
    def change(edges):
        edges["gpe"].parent_tform_child.rotation.w = value

    return change


def looped(edges):
    edges["body"].parent_frame_name = "odom"  # body -> odom -> body


def second_tree(edges):
    edges["x"].parent_frame_name = "r"


def type_errors(valid):
    """Non-messages and wrong messages: TypeError."""
    return {
        "none": lambda c, r, b: Arg(None, REJECT, "type"),
        "str": lambda c, r, b: Arg("body", REJECT, "type"),
        "int": lambda c, r, b: Arg(1, REJECT, "type"),
        "dict": lambda c, r, b: Arg({}, REJECT, "type"),
        "float_array": lambda c, r, b: Arg(np.zeros(3), REJECT, "type"),
        "list_mixed": lambda c, r, b: Arg([valid(), "x"], REJECT, "type"),
    }


# ---- readings of the messages, the oracle's own ----


def walk(value, read):
    """The plain reading of a (nested) sequence of messages: nested lists of read(leaf)."""
    if isinstance(value, (list, tuple, np.ndarray)) or type(value).__name__.startswith("Repeated"):
        return [walk(item, read) for item in value]
    return read(value)


def as_array(nested, trailing):
    array = np.array(nested, dtype=np.float64)
    if array.size == 0:
        return array.reshape(*array.shape[: array.ndim], *trailing) if array.ndim == 1 else array
    return array


def quat_matrix(wxyz):
    w, x, y, z = wxyz
    norm = math.sqrt(w * w + x * x + y * y + z * z) if all(map(math.isfinite, wxyz)) else math.nan
    if not abs(norm - 1.0) <= QUAT_TOL:
        return np.full((3, 3), np.nan)
    return Rotation.from_quat([x, y, z, w]).as_matrix()


def pose_matrix(message):
    if isinstance(message, geometry_pb2.SE3Pose):
        p = message.position
        r = message.rotation if message.HasField("rotation") else geometry_pb2.Quaternion(w=1.0)
        position, wxyz = (p.x, p.y, p.z), (r.w, r.x, r.y, r.z)
    else:  # math_helpers.SE3Pose
        position, wxyz = (
            (message.x, message.y, message.z),
            (message.rot.w, message.rot.x, message.rot.y, message.rot.z),
        )
    T = np.eye(4)
    T[:3, :3] = quat_matrix(wxyz)
    T[:3, 3] = position
    return T if np.isfinite(T).all() else np.full((4, 4), np.nan)


def same(got, want, what, f32=False):
    if not isinstance(got, np.ndarray) or got.dtype != np.float64:
        return f"{what}: not a float64 array: {describe(got)}"
    if got.shape != np.shape(want) or not close(got, want, f32):
        return f"{what}: {describe(got)}, expected {describe(np.asarray(want))}"
    return None


Q_STAND = np.tile([0.05, 0.9, -1.6], 4)
