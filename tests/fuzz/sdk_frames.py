"""Registry entries of ``spotkin.sdk``'s frame trees: ``frame_transform``, ``frame_tree_edges`` and
``frame_tree_snapshot``."""

from __future__ import annotations

import math

import numpy as np
from bosdyn.api import geometry_pb2, robot_state_pb2
from bosdyn.client import frame_helpers, math_helpers

from spotkin import sdk

from .entry import register
from .outputs import describe
from .sdk_messages import (
    FRAMES,
    QUAT_TOL,
    bad_gpe,
    looped,
    pose_matrix,
    rigid,
    same,
    se3,
    second_tree,
    snapshot,
    type_errors,
)
from .slots import ACCEPT, EITHER, REJECT, Arg, Custom


def given_matrix(pose):
    if isinstance(pose, geometry_pb2.SE3Pose) or type(pose).__name__ == "SE3Pose":
        return pose_matrix(pose)
    T = np.asarray(pose, dtype=np.float64)
    R = T[:3, :3]
    ok = np.isfinite(T).all() and np.abs(R.T @ R - np.eye(3)).max() <= 1e-6 and np.linalg.det(R) > 0
    return T if ok else np.full((4, 4), np.nan)


def tree_probe(result, kw, c):
    edges = kw["edges"]
    if not isinstance(result, geometry_pb2.FrameTreeSnapshot):
        return f"not a FrameTreeSnapshot: {describe(result)}"
    if not edges:
        return None if len(result.child_to_parent_edge_map) == 0 else "edges for no edge"
    try:
        frame_helpers.validate_frame_tree_snapshot(result)
    except Exception as error:
        return f"the SDK finds the tree invalid: {type(error).__name__} {error}"
    for child, (parent, pose) in edges.items():
        want = given_matrix(pose)
        got = frame_helpers.get_a_tform_b(result, parent, child, validate=False).to_matrix()
        if np.isnan(want).any():
            if not np.isnan(got[:3]).all():
                return f"{child}: a pose that is not rigid is stored as {describe(got)}, not NaN"
        elif np.abs(got - want).max() > 1e-6:
            return f"{child}: the SDK reads {describe(got)}, given {describe(want)}"
    return None


def with_first_nan(c, v):
    v.reshape(-1)[0] = math.nan
    return v


NAN_KEPT = {"nan": (with_first_nan, ACCEPT, "")}  # a NaN is a value like any other here


def register_entries() -> None:
    """Registers these entries (:mod:`fuzz.sdk` calls it when the SDK is installed)."""
    # ---- frame trees ----

    def tree_arg(expect=ACCEPT, why="", **options):
        return lambda c, r, b: Arg(snapshot(**options), expect, why)

    snapshot_table = {
        "valid": tree_arg(),
        "no_root_entry": tree_arg(root_edge=False),
        "kinematic_state": lambda c, r, b: Arg(
            robot_state_pb2.KinematicState(transforms_snapshot=snapshot())
        ),
        "robot_state": lambda c, r, b: Arg(
            robot_state_pb2.RobotState(
                kinematic_state=robot_state_pb2.KinematicState(transforms_snapshot=snapshot())
            )
        ),
        "list": lambda c, r, b: Arg(
            [snapshot(), robot_state_pb2.KinematicState(transforms_snapshot=snapshot())]
        ),
        "empty_list": lambda c, r, b: Arg([]),
        "nonunit_edge": tree_arg(change=bad_gpe(4.0)),
        "nan_edge": tree_arg(change=bad_gpe(math.nan)),
        "second_tree": tree_arg(change=second_tree),
        "loop": tree_arg(REJECT, "value", change=looped),
        "empty": lambda c, r, b: Arg(geometry_pb2.FrameTreeSnapshot(), REJECT, "value"),
        "nested_list": lambda c, r, b: Arg([[snapshot()]], REJECT, "type"),
        "wrong_message": lambda c, r, b: Arg(se3(rigid(1)), REJECT, "type"),
        **type_errors(snapshot),
    }

    def frame_table(valid, others):
        table = {"valid": lambda c, r, b, v=valid: Arg(v)}
        table.update({name: (lambda c, r, b, v=name: Arg(v)) for name in others})
        table.update(
            {
                "unknown": lambda c, r, b: Arg("map", REJECT, "value"),
                "other_tree": lambda c, r, b: Arg("x", REJECT, "value"),
                "empty": lambda c, r, b: Arg("", REJECT, "value"),
                "none": lambda c, r, b: Arg(None, REJECT, "type"),
                "int": lambda c, r, b: Arg(0, REJECT, "type"),
                "bytes": lambda c, r, b, v=valid: Arg(v.encode(), REJECT, "type"),
            }
        )
        return table

    def path_valid(tree, frame):
        edges = tree.child_to_parent_edge_map
        while frame in edges and edges[frame].parent_frame_name:
            r = edges[frame].parent_tform_child.rotation
            norm = math.sqrt(r.w**2 + r.x**2 + r.y**2 + r.z**2)
            if not abs(norm - 1) <= QUAT_TOL:
                return False
            frame = edges[frame].parent_frame_name
        return True

    def snapshots_of(value):
        items = value if isinstance(value, list) else [value]
        trees = []
        for item in items:
            if isinstance(item, robot_state_pb2.RobotState):
                item = item.kinematic_state
            if isinstance(item, robot_state_pb2.KinematicState):
                item = item.transforms_snapshot
            trees.append(item)
        return trees

    def transform_probe(result, kw, c):
        a, b = kw["frame_a"], kw["frame_b"]
        trees = snapshots_of(kw["snapshot"])
        wants = []
        for tree in trees:
            if path_valid(tree, a) and path_valid(tree, b):
                rooted = geometry_pb2.FrameTreeSnapshot()
                rooted.CopyFrom(tree)
                rooted.child_to_parent_edge_map[
                    "body"
                ].parent_frame_name = ""  # the SDK needs the root's entry
                wants.append(frame_helpers.get_a_tform_b(rooted, a, b, validate=False).to_matrix())
            else:
                wants.append(np.full((4, 4), np.nan))
        want = np.array(wants).reshape(-1, 4, 4) if isinstance(kw["snapshot"], list) else wants[0]
        if (
            isinstance(result, np.ndarray)
            and result.shape == want.shape
            and want.size
            and np.isfinite(want).all()
        ):
            if np.abs(result - want).max() > 1e-11:
                return f"a_tform_b {describe(result)}, the SDK's {describe(want)}"
            return None
        return same(result, want, "a_tform_b")

    register(
        name="sdk.frame_transform",
        covers="spotkin.sdk.frame_transform",
        call=lambda c, **k: sdk.frame_transform(**k),
        slots=[
            Custom("snapshot", snapshot_table),
            Custom("frame_a", frame_table("odom", ("gpe", "hand", "body", "arm0.link_wr1"))),
            Custom("frame_b", frame_table("body", ("vision", "fl_foot", "gpe", "odom"))),
        ],
        probe=transform_probe,
        pair_rule=lambda plan: (
            EITHER
            if plan["snapshot"] == "empty_list"
            and any(plan[f] in ("unknown", "other_tree", "empty") for f in ("frame_a", "frame_b"))
            else None
        ),
    )

    def edges_probe(result, kw, c):
        tree = snapshots_of(kw["snapshot"])[0]
        if not isinstance(result, dict):
            return f"not a dict: {describe(result)}"
        want = {
            child: edge for child, edge in tree.child_to_parent_edge_map.items() if edge.parent_frame_name
        }
        if set(result) != set(want):
            return f"edges {sorted(result)}, expected {sorted(want)}"
        for child, (parent, T) in result.items():
            if parent != want[child].parent_frame_name:
                return f"{child}: parent {parent!r}, expected {want[child].parent_frame_name!r}"
            message = same(T, pose_matrix(want[child].parent_tform_child), child)
            if message:
                return message
        return None

    register(
        name="sdk.frame_tree_edges",
        covers="spotkin.sdk.frame_tree_edges",
        call=lambda c, **k: sdk.frame_tree_edges(**k),
        slots=[
            Custom(
                "snapshot",
                {
                    **{
                        k: v
                        for k, v in snapshot_table.items()
                        if k not in ("list", "empty_list", "loop", "empty")
                    },
                    "loop": tree_arg(change=looped),  # read edge by edge: no walk
                    "empty": lambda c, r, b: Arg(geometry_pb2.FrameTreeSnapshot()),
                    "list": lambda c, r, b: Arg([snapshot()], REJECT, "type"),
                },
            )
        ],
        probe=edges_probe,
    )

    def edges_arg(change=None, expect=ACCEPT, why=""):
        def make(c, r, b):
            edges = {child: (parent, rigid(200 + k)) for k, (child, parent) in enumerate(FRAMES.items())}
            if change is not None:
                change(edges)
            return Arg(edges, expect, why)

        return make

    def set_edge(child, value):
        return lambda edges: edges.__setitem__(child, value)

    def edge_pose(child, make):
        return lambda edges: edges.__setitem__(child, (edges[child][0], make(edges[child][1])))

    def non_rigid(T):
        T = T.copy()
        T[:3, :3] *= 2.0
        return T

    def with_nan(T):
        T = T.copy()
        T[0, 3] = math.nan
        return T

    tree_edges_table = {
        "valid": edges_arg(),
        "messages": edges_arg(edge_pose("gpe", se3)),
        "math_helpers": edges_arg(edge_pose("hand", math_helpers.SE3Pose.from_matrix)),
        "lists": edges_arg(lambda e: e.update({k: list(v) for k, v in e.items()})),
        "float32": edges_arg(edge_pose("odom", lambda T: T.astype(np.float32))),
        "empty": lambda c, r, b: Arg({}),
        "non_rigid": edges_arg(edge_pose("odom", non_rigid)),
        "nan_pose": edges_arg(edge_pose("vision", with_nan)),
        "loop": edges_arg(lambda e: e.update({"body": ("odom", np.eye(4))}), REJECT, "value"),
        "two_roots": edges_arg(set_edge("x", ("r", np.eye(4))), REJECT, "value"),
        "own_parent": edges_arg(set_edge("x", ("x", np.eye(4))), REJECT, "value"),
        "empty_parent": edges_arg(set_edge("x", ("", np.eye(4))), REJECT, "type"),
        "empty_child": edges_arg(set_edge("", ("body", np.eye(4))), REJECT, "type"),
        "int_child": edges_arg(set_edge(3, ("body", np.eye(4))), REJECT, "type"),
        "not_a_pair": edges_arg(set_edge("x", "body"), REJECT, "type"),
        "triple": edges_arg(set_edge("x", ("body", np.eye(4), 0)), REJECT, "type"),
        "pose_3x3": edges_arg(set_edge("x", ("body", np.eye(3))), REJECT, "value"),
        "pose_str": edges_arg(set_edge("x", ("body", "identity")), REJECT, "type"),
        "pose_none": edges_arg(set_edge("x", ("body", None)), REJECT, "type"),
        "list_of_pairs": lambda c, r, b: Arg([("odom", ("body", np.eye(4)))], REJECT, "type"),
        "none": lambda c, r, b: Arg(None, REJECT, "type"),
        "snapshot": lambda c, r, b: Arg(snapshot(), REJECT, "type"),
    }

    register(
        name="sdk.frame_tree_snapshot",
        covers="spotkin.sdk.frame_tree_snapshot",
        call=lambda c, **k: sdk.frame_tree_snapshot(**k),
        slots=[Custom("edges", tree_edges_table)],
        probe=tree_probe,
    )
