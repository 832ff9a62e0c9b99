"""Frame trees: transforms between any two frames of a snapshot, its edges, and snapshots built from
edges. Part of :mod:`spotkin.sdk` (documented there)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._support.boundary import as_real
from .common import (
    _is_sequence,
    _math_helper,
    _read_se3,
    _rigid_inverse,
    _se3_matrix,
    _type_name,
    geometry_pb2,
    robot_state_pb2,
)
from .geometry import matrix_to_se3

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
