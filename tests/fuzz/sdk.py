"""The fuzz registry's entries for ``spotkin.sdk`` (issue 19), the optional Spot SDK interop.

``tests/fuzz/registry.py`` calls :func:`register_entries` once its own entries are made; without
the SDK installed nothing is registered (and nothing of ``spotkin.sdk`` is public there either).

The slots hold real ``bosdyn.api`` messages, the SDK's ``math_helpers`` objects, nested lists of them,
arrays, and hostile values (None, strings, other message types, NaN and Inf fields, non-unit
quaternions, loops in frame trees, NaN joint targets...). The probes judge every result against the
SDK's own helpers (``math_helpers``, ``frame_helpers``, ``RobotCommandBuilder``), scipy, and plain
readings of the message fields.
"""

from __future__ import annotations

import math

import numpy as np

import spotkin as sk

from .batch import Batch
from .entry import register
from .objects import rigid as make_rigid
from .outputs import close, describe
from .slots import ACCEPT, EITHER, REJECT, Arg, Array, Choice, Custom

# values of a batch slot that a joint command must refuse (NaN, Inf, beyond float32)
COMMAND_REFUSED = {
    "nan",
    "inf",
    "-inf",
    "nan_all",
    "nan_single",
    "big",
    "-big",
    "mag_1e300",
    "float32_nan",
    "float32_inf",
}
QUAT_TOL = 1e-6


def register_entries() -> None:
    try:
        from bosdyn.api import (
            arm_command_pb2,
            basic_command_pb2,
            geometry_pb2,
            robot_command_pb2,
            robot_state_pb2,
        )
        from bosdyn.client import frame_helpers, math_helpers
        from bosdyn.client.robot_command import RobotCommandBuilder
        from scipy.spatial.transform import Rotation

        from spotkin import sdk
    except ImportError:  # the optional extra is not installed
        return

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

    # ---- Vec3, Quaternion, SE3Pose to arrays ----

    vec_table = {
        "valid": lambda c, r, b: Arg(vec(1)),
        "math_helpers": lambda c, r, b: Arg(math_helpers.Vec3(0.1, -0.2, 0.3)),
        "list": lambda c, r, b: Arg([vec(1), vec(2), vec(3)]),
        "tuple": lambda c, r, b: Arg((vec(1), vec(2))),
        "nested": lambda c, r, b: Arg([[vec(1), vec(2)], [vec(3), vec(4)]]),
        "object_array": lambda c, r, b: Arg(objects(vec(1), vec(2))),
        "empty": lambda c, r, b: Arg([]),
        "nan": lambda c, r, b: Arg(geometry_pb2.Vec3(x=math.nan, y=1.0)),
        "inf": lambda c, r, b: Arg([vec(1), geometry_pb2.Vec3(z=-math.inf)]),
        "big": lambda c, r, b: Arg(geometry_pb2.Vec3(x=1e308)),
        "ragged": lambda c, r, b: Arg([[vec(1)], []], REJECT, "value"),
        "wrong_message": lambda c, r, b: Arg(quat(1), REJECT, "type"),
        **type_errors(lambda: vec(1)),
    }

    def vec_read(v):
        return [v.x, v.y, v.z]

    def array_probe(trailing, read, name):
        def probe(result, kw, c):
            nested = walk(kw[name], read)
            want = np.array(nested, dtype=np.float64)
            if want.size == 0:
                want = want.reshape(*want.shape, *trailing) if want.shape[-1:] != trailing[-1:] else want
            return same(result, want, name)

        return probe

    register(
        name="sdk.vec3_to_array",
        covers="spotkin.sdk.vec3_to_array",
        call=lambda c, **k: sdk.vec3_to_array(**k),
        slots=[Custom("vec", vec_table)],
        probe=array_probe((3,), vec_read, "vec"),
    )

    def quat_read(q):
        if isinstance(q, (list, np.ndarray)) and np.ndim(q) == 1:
            return quat_matrix(tuple(float(v) for v in q))
        return quat_matrix((q.w, q.x, q.y, q.z))

    def quat_probe(result, kw, c):
        value = kw["quat"]
        numeric = isinstance(value, np.ndarray) and value.dtype != object
        if numeric or (isinstance(value, list) and value and isinstance(value[0], float)):
            value = np.asarray(value, dtype=np.float64)
            flat = value.reshape(-1, 4)
            want = np.array([quat_matrix(tuple(row)) for row in flat]).reshape(*value.shape[:-1], 3, 3)
        else:
            nested = walk(value, lambda q: quat_matrix((q.w, q.x, q.y, q.z)))
            want = np.array(nested, dtype=np.float64)
            if want.size == 0:
                want = want.reshape(*want.shape, 3, 3)
        return same(result, want, "quat")

    near = quat(3)
    near.w *= 1 + 4e-7  # within the tolerance: the normalised rotation
    quat_table = {
        "valid": lambda c, r, b: Arg(quat(1)),
        "math_helpers": lambda c, r, b: Arg(math_helpers.Quat.from_yaw(0.4)),
        "list": lambda c, r, b: Arg([quat(1), quat(2)]),
        "nested": lambda c, r, b: Arg([[quat(1)], [quat(2)]]),
        "empty": lambda c, r, b: Arg([]),
        "array": lambda c, r, b: Arg(np.array([0.5, 0.5, -0.5, 0.5])),
        "array_batch": lambda c, r, b: Arg(np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.6, 0.8, 0.0]])),
        "array_float32": lambda c, r, b: Arg(np.array([0.5, 0.5, -0.5, 0.5], dtype=np.float32)),
        "array_int": lambda c, r, b: Arg(np.array([0, 0, 1, 0])),
        "float_list": lambda c, r, b: Arg([1.0, 0.0, 0.0, 0.0]),
        "array_empty": lambda c, r, b: Arg(np.zeros((0, 4))),
        "array_nonunit": lambda c, r, b: Arg(np.array([[1.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])),
        "array_nan": lambda c, r, b: Arg(np.array([[np.nan, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0]])),
        "near_unit": lambda c, r, b: Arg(near),
        "nonunit": lambda c, r, b: Arg([quat(1), geometry_pb2.Quaternion(w=2.0)]),
        "zero": lambda c, r, b: Arg(geometry_pb2.Quaternion()),
        "nan": lambda c, r, b: Arg(geometry_pb2.Quaternion(w=math.nan)),
        "inf": lambda c, r, b: Arg(geometry_pb2.Quaternion(x=math.inf, w=1.0)),
        "huge": lambda c, r, b: Arg(geometry_pb2.Quaternion(w=1e308, x=1e308)),
        "wrong_message": lambda c, r, b: Arg(vec(1), REJECT, "type"),
        "array_short": lambda c, r, b: Arg(np.zeros(3), REJECT, "shape"),
        "array_complex": lambda c, r, b: Arg(np.zeros(4, dtype=complex), REJECT, "type"),
        "str_array": lambda c, r, b: Arg(np.array(["1", "0", "0", "0"]), REJECT, "type"),
        "ragged": lambda c, r, b: Arg([[quat(1)], []], REJECT, "value"),
        **{k: v for k, v in type_errors(lambda: quat(1)).items() if k not in ("float_array", "int")},
        "int": lambda c, r, b: Arg(1, REJECT, "shape"),  # a number: an array of the wrong shape
    }
    register(
        name="sdk.quat_to_matrix",
        covers="spotkin.sdk.quat_to_matrix",
        call=lambda c, **k: sdk.quat_to_matrix(**k),
        slots=[Custom("quat", quat_table)],
        probe=quat_probe,
    )

    def unset_rotation(c, r, b):
        return Arg(geometry_pb2.SE3Pose(position=geometry_pb2.Vec3(x=1.0, y=2.0)))

    def pose_with(change):
        def make(c, r, b):
            message = se3(rigid(5))
            change(message)
            return Arg([se3(rigid(6)), message])

        return make

    pose_table = {
        "valid": lambda c, r, b: Arg(se3(rigid(1))),
        "math_helpers": lambda c, r, b: Arg(math_helpers.SE3Pose.from_matrix(rigid(2))),
        "list": lambda c, r, b: Arg([se3(rigid(1)), se3(rigid(2)), se3(rigid(3))]),
        "nested": lambda c, r, b: Arg([[se3(rigid(1))], [se3(rigid(2))]]),
        "object_array": lambda c, r, b: Arg(objects(se3(rigid(1)), se3(rigid(2)))),
        "empty": lambda c, r, b: Arg([]),
        "unset_rotation": unset_rotation,
        "nonunit": pose_with(lambda m: setattr(m.rotation, "w", 3.0)),
        "zero_rotation": pose_with(lambda m: m.rotation.CopyFrom(geometry_pb2.Quaternion())),
        "nan_position": pose_with(lambda m: setattr(m.position, "y", math.nan)),
        "inf_rotation": pose_with(lambda m: setattr(m.rotation, "x", math.inf)),
        "huge_position": pose_with(lambda m: setattr(m.position, "x", 1e308)),
        "ragged": lambda c, r, b: Arg([[se3(rigid(1))], []], REJECT, "value"),
        "wrong_message": lambda c, r, b: Arg(quat(1), REJECT, "type"),
        "snapshot": lambda c, r, b: Arg(snapshot(), REJECT, "type"),
        **type_errors(lambda: se3(rigid(1))),
    }

    def pose_probe(result, kw, c):
        nested = walk(kw["pose"], pose_matrix)
        want = np.array(nested, dtype=np.float64)
        if want.size == 0:
            want = want.reshape(*want.shape, 4, 4)
        return same(result, want, "pose")

    register(
        name="sdk.se3_to_matrix",
        covers="spotkin.sdk.se3_to_matrix",
        call=lambda c, **k: sdk.se3_to_matrix(**k),
        slots=[Custom("pose", pose_table)],
        probe=pose_probe,
    )

    # ---- arrays to Vec3, Quaternion, SE3Pose ----

    def nested_messages(result, lead, kind):
        """The messages of a result in C order, or a reason why it is not lead-shaped nested lists."""
        if lead == ():
            return [result] if isinstance(result, kind) else f"not one {kind.__name__}: {describe(result)}"
        if not isinstance(result, list) or len(result) != lead[0]:
            return f"not a list of {lead[0]}: {describe(result)}"
        found = []
        for item in result:
            inner = nested_messages(item, lead[1:], kind)
            if isinstance(inner, str):
                return inner
            found += inner
        return found

    def plain(value, trailing):
        array = np.asarray(value)
        f32 = array.dtype.kind == "f" and array.dtype.itemsize == 4
        array = array.astype(np.float64)
        return array, array.shape[: array.ndim - len(trailing)], f32

    def vec_out_probe(result, kw, c):
        p, lead, _ = plain(kw["p"], (3,))
        messages = nested_messages(result, lead, geometry_pb2.Vec3)
        if isinstance(messages, str):
            return messages
        got = np.array([[m.x, m.y, m.z] for m in messages], dtype=np.float64).reshape(p.shape)
        return (
            None
            if close(got, p, False) and np.array_equal(np.isnan(got), np.isnan(p))
            else f"Vec3s {describe(got)}, expected {describe(p)}"
        )

    register(
        name="sdk.array_to_vec3",
        covers="spotkin.sdk.array_to_vec3",
        call=lambda c, **k: sdk.array_to_vec3(**k),
        slots=[Batch("p", (3,))],
        baseline=lambda c, rng, n: {"p": rng.normal(size=(n, 3))},
        probe=vec_out_probe,
    )

    def rotation_ok(R):
        if not np.isfinite(R).all():
            return False
        orth = np.abs(R.T @ R - np.eye(3)).max()
        if orth > 1e-5 or np.linalg.det(R) <= 0:
            return False
        return True if orth < 1e-7 else None  # None: borderline, either answer

    def quat_out_probe(result, kw, c):
        R, lead, f32 = plain(kw["R"], (3, 3))
        messages = nested_messages(result, lead, geometry_pb2.Quaternion)
        if isinstance(messages, str):
            return messages
        for k, (m, r) in enumerate(zip(messages, R.reshape(-1, 3, 3))):
            wxyz = [m.w, m.x, m.y, m.z]
            ok = rotation_ok(r)
            if ok is None:
                continue
            if not ok:
                if not np.isnan(wxyz).all():
                    return f"sample {k}: not a rotation {describe(r)}, but the quaternion {wxyz} is not NaN"
                continue
            if m.w < 0 or abs(np.linalg.norm(wxyz) - 1) > 1e-12:
                return f"sample {k}: {wxyz} is not a unit quaternion with w >= 0"
            orth = np.abs(r.T @ r - np.eye(3)).max()
            if (
                np.abs(math_helpers.Quat.from_proto(m).to_matrix() - r).max()
                > (1e-6 if f32 else 1e-9) + 2 * orth
            ):
                return f"sample {k}: the SDK reads {wxyz} as another rotation than {describe(r)}"
        return None

    register(
        name="sdk.matrix_to_quat",
        covers="spotkin.sdk.matrix_to_quat",
        call=lambda c, **k: sdk.matrix_to_quat(**k),
        slots=[Batch("R", (3, 3))],
        baseline=lambda c, rng, n: {
            "R": Rotation.random(n, random_state=int(rng.integers(2**31))).as_matrix()
        },
        probe=quat_out_probe,
    )

    def se3_out_probe(result, kw, c):
        T, lead, f32 = plain(kw["T"], (4, 4))
        messages = nested_messages(result, lead, geometry_pb2.SE3Pose)
        if isinstance(messages, str):
            return messages
        for k, (m, t) in enumerate(zip(messages, T.reshape(-1, 4, 4))):
            values = list(math_helpers.SE3Pose.from_proto(m))
            ok = rotation_ok(t[:3, :3])
            row = np.abs(t[3] - [0, 0, 0, 1]).max() if np.isfinite(t[3]).all() else np.inf
            if ok is not None and (row <= 1e-10 or row > 1e-8):
                ok = ok and row <= 1e-10 and np.isfinite(t[:3, 3]).all()
            else:
                continue
            if not ok:
                if not np.isnan(values).all():
                    return (
                        f"sample {k}: not a rigid transform {describe(t)}, but the pose {values} is not NaN"
                    )
                continue
            back = math_helpers.SE3Pose.from_proto(m).to_matrix()
            scale = max(1.0, np.abs(t[:3, 3]).max())
            orth = np.abs(t[:3, :3].T @ t[:3, :3] - np.eye(3)).max()  # a rotation within it is read
            if m.rotation.w < 0 or np.abs(back - t).max() > ((1e-6 if f32 else 1e-9) + 2 * orth) * scale:
                return f"sample {k}: the SDK reads the pose as {describe(back)}, not {describe(t)}"
        return None

    register(
        name="sdk.matrix_to_se3",
        covers="spotkin.sdk.matrix_to_se3",
        call=lambda c, **k: sdk.matrix_to_se3(**k),
        slots=[Batch("T", (4, 4), pose="T", quat_ok=False)],
        baseline=lambda c, rng, n: {"T": np.array([rigid(int(s)) for s in rng.integers(2**31, size=n)])},
        probe=se3_out_probe,
    )

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

    register(
        name="sdk.frame_tree_snapshot",
        covers="spotkin.sdk.frame_tree_snapshot",
        call=lambda c, **k: sdk.frame_tree_snapshot(**k),
        slots=[Custom("edges", tree_edges_table)],
        probe=tree_probe,
    )

    def with_first_nan(c, v):
        v.reshape(-1)[0] = math.nan
        return v

    NAN_KEPT = {"nan": (with_first_nan, ACCEPT, "")}  # a NaN is a value like any other here

    # ---- joint states ----

    SDK_LISTING = [
        *sk.Spot.joint_names,
        "arm0.sh0",
        "arm0.sh1",
        "arm0.hr0",
        *sk.Spot.arm_joint_names[2:],
        "arm0.f1x",
    ]

    def named_state(seed=1, skip=(), change=None, kind="kinematic"):
        rng = np.random.default_rng(seed)
        state = robot_state_pb2.KinematicState()
        for name in rng.permutation(SDK_LISTING):
            if name in skip:
                continue
            joint = state.joint_states.add(name=str(name))
            value = 0.0 if name == "arm0.hr0" else float(rng.uniform(-1, 1))
            joint.position.value, joint.velocity.value, joint.load.value = value, 2 * value, -value
        if change is not None:
            change(state)
        if kind == "robot":
            return robot_state_pb2.RobotState(kinematic_state=state)
        return state

    def streamed(count=19, kind="response"):
        values = np.random.default_rng(count).uniform(-1, 1, count).tolist()
        combined = robot_state_pb2.CombinedJointStates(position=values, velocity=values, load=values)
        if kind == "combined":
            return combined
        return robot_state_pb2.RobotStateStreamResponse(joint_states=combined)

    def nan_value(state):
        state.joint_states[3].position.value = math.nan
        state.joint_states[5].velocity.value = math.inf

    def twice(state):
        state.joint_states.add(name=state.joint_states[0].name).position.value = 0.0

    def unset(state):
        state.joint_states[0].ClearField("position")

    state_table = {
        "valid": lambda c, r, b: Arg(named_state()),
        "robot_state": lambda c, r, b: Arg(named_state(kind="robot")),
        "stream": lambda c, r, b: Arg(streamed()),
        "stream_legs": lambda c, r, b: Arg(streamed(12)),
        "combined": lambda c, r, b: Arg(streamed(19, "combined")),
        "no_arm": lambda c, r, b: Arg(named_state(skip=sk.Spot.arm_joint_names + ("arm0.hr0", "arm0.f1x"))),
        "missing_leg_joint": lambda c, r, b: Arg(named_state(skip=("hl.kn",))),
        "unset_value": lambda c, r, b: Arg(named_state(change=unset)),
        "nan_values": lambda c, r, b: Arg(named_state(change=nan_value)),
        "empty_state": lambda c, r, b: Arg(robot_state_pb2.KinematicState()),
        "empty_stream": lambda c, r, b: Arg(robot_state_pb2.CombinedJointStates()),
        "named_twice": lambda c, r, b: Arg(named_state(change=twice), REJECT, "value"),
        "stream_7": lambda c, r, b: Arg(streamed(7), REJECT, "value"),
        "wrong_message": lambda c, r, b: Arg(se3(rigid(1)), REJECT, "type"),
        **{k: v for k, v in type_errors(named_state).items() if k != "list_mixed"},
    }

    def read_states(state, field):
        """(names, values) read field by field, the oracle's way."""
        if isinstance(state, robot_state_pb2.RobotState):
            state = state.kinematic_state
        if isinstance(state, robot_state_pb2.KinematicState):
            names = tuple(j.name for j in state.joint_states)
            values = [getattr(j, field).value if j.HasField(field) else math.nan for j in state.joint_states]
            return names, np.array(values, dtype=np.float64)
        if isinstance(state, robot_state_pb2.RobotStateStreamResponse):
            state = state.joint_states
        values = np.array(getattr(state, field), dtype=np.float64)
        return sdk.JOINT_NAMES[: len(values)], values

    STREAMS = ("stream", "stream_legs", "combined", "empty_stream")

    def states_probe(result, kw, c):
        names, values = read_states(kw["state"], kw.get("field", "position"))
        if not (isinstance(result, tuple) and len(result) == 2 and result[0] == names):
            return f"names {describe(result)}, expected {names}"
        return same(result[1], values, "values")

    register(
        name="sdk.joint_states",
        covers="spotkin.sdk.joint_states",
        call=lambda c, **k: sdk.joint_states(**k),
        slots=[
            Custom("state", {**state_table, "list": lambda c, r, b: Arg([named_state()], REJECT, "type")}),
            Choice("field", "position", ("position", "velocity", "acceleration", "load"), default="omit"),
        ],
        probe=states_probe,
        pair_rule=lambda plan: (
            REJECT if plan["state"] in STREAMS and plan["field"] == "choice:acceleration" else None
        ),
    )

    Q_NAMES = (*sk.Spot.joint_names, *sk.Spot.arm_joint_names)

    def q_of(state, field):
        names, values = read_states(state, field)
        table = dict(zip(names, values))
        return np.array([table.get(name, math.nan) for name in Q_NAMES])

    def positions_probe(result, kw, c):
        field = kw.get("field", "position")
        state = kw["state"]
        want = (
            np.array([q_of(s, field) for s in state]).reshape(-1, 18)
            if isinstance(state, list)
            else q_of(state, field)
        )
        if not (isinstance(result, tuple) and len(result) == 2):
            return f"not (q12, q_arm): {describe(result)}"
        return same(result[0], want[..., :12], "q12") or same(result[1], want[..., 12:], "q_arm")

    def positions_pairs(plan):
        if plan["state"] in STREAMS + ("list_streams",) and plan["field"] == "choice:acceleration":
            return REJECT
        incomplete = (
            "no_arm",
            "missing_leg_joint",
            "unset_value",
            "empty_state",
            "empty_stream",
            "stream_legs",
        )
        if plan["state"] in incomplete and plan["missing"] == "choice:raise":
            return REJECT
        if plan["missing"] == "choice:raise" and plan["field"] == "choice:acceleration":
            return REJECT  # the states here report no accelerations
        return None

    register(
        name="sdk.joint_positions",
        covers="spotkin.sdk.joint_positions",
        call=lambda c, **k: sdk.joint_positions(**k),
        slots=[
            Custom(
                "state",
                {
                    **state_table,
                    "list": lambda c, r, b: Arg(
                        [named_state(1), named_state(2, kind="robot"), named_state(3)]
                    ),
                    "list_streams": lambda c, r, b: Arg([streamed(), streamed(19, "combined")]),
                    "empty_list": lambda c, r, b: Arg([]),
                    "nested_list": lambda c, r, b: Arg([[named_state()]], REJECT, "type"),
                    "list_mixed": lambda c, r, b: Arg([named_state(), "x"], REJECT, "type"),
                },
            ),
            Choice("field", "position", ("position", "velocity", "acceleration", "load"), default="omit"),
            Choice("missing", "nan", ("nan", "raise"), default="omit"),
        ],
        probe=positions_probe,
        pair_rule=positions_pairs,
    )

    def names_arg(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value, expect, why)

    EVERY = [*Q_NAMES, "arm0.f1x"]

    def frames_arg(kind):
        def make(c, r, b):
            if kind == "dict":
                return Arg({"odom": ("body", rigid(7)), "gpe": ("odom", rigid(8))})
            if kind == "snapshot":
                return Arg(snapshot())
            if kind == "loop":
                return Arg({"a": ("b", np.eye(4)), "b": ("a", np.eye(4))}, REJECT, "value")
            return Arg("odom", REJECT, "type")

        return make

    def kinematic_probe(result, kw, c):
        if not isinstance(result, robot_state_pb2.KinematicState):
            return f"not a KinematicState: {describe(result)}"
        names = tuple(str(n) for n in kw["names"])
        for field in ("position", "velocity", "acceleration", "load"):
            given = kw.get(field)
            got_names, got = read_states(result, field)
            if got_names != names:
                return f"names {got_names}, expected {names}"
            want = (
                np.full(len(names), np.nan)
                if given is None
                else np.asarray(given, dtype=np.float64).reshape(-1)
            )
            if not np.array_equal(got, want, equal_nan=True):
                return f"{field}s {describe(got)}, given {describe(want)} (NaN: unset)"
        frames = kw.get("frames")
        if frames is None:
            return None if not result.HasField("transforms_snapshot") else "a frame tree from no frames"
        if isinstance(frames, geometry_pb2.FrameTreeSnapshot):
            return None if result.transforms_snapshot == frames else "the snapshot is not the one given"
        return tree_probe(result.transforms_snapshot, {"edges": frames}, c)

    def values_array(name, optional=True):
        extra = {"optional": True, "default": "omit"} if optional else {}
        return Array(name, lambda c: np.linspace(-1.0, 1.0, 19), inf_ok=True, extra=NAN_KEPT, **extra)

    register(
        name="sdk.kinematic_state",
        covers="spotkin.sdk.kinematic_state",
        call=lambda c, **k: sdk.kinematic_state(**k),
        slots=[
            Custom(
                "names",
                {
                    "valid": names_arg(EVERY),
                    "tuple": names_arg(tuple(EVERY)),
                    "array": names_arg(np.array(EVERY)),
                    "twice": names_arg([EVERY[0], *EVERY[:-1]], REJECT, "value"),
                    "str": names_arg("fl.hx", REJECT, "type"),
                    "ints": names_arg(list(range(19)), REJECT, "type"),
                    "none": names_arg(None, REJECT, "type"),
                    "dict": names_arg(dict.fromkeys(EVERY, 0.0), REJECT, "type"),
                    "fewer": names_arg(EVERY[:-1], REJECT),  # 18 names for 19 positions
                },
            ),
            values_array("position", optional=False),
            values_array("velocity"),
            values_array("acceleration"),
            values_array("load"),
            Custom(
                "frames",
                {
                    "none": lambda c, r, b: Arg(None),
                    "dict": frames_arg("dict"),
                    "snapshot": frames_arg("snapshot"),
                    "loop": frames_arg("loop"),
                    "str": frames_arg("str"),
                },
                default="omit",
            ),
        ],
        probe=kinematic_probe,
    )

    # ---- feet ----

    Q_STAND = np.tile([0.05, 0.9, -1.6], 4)

    def standing(seed=1, feet=4, skip=(), kinematic=False):
        rng = np.random.default_rng(seed)
        spot = sk.Spot()
        q12 = Q_STAND + rng.uniform(-0.1, 0.1, 12)
        feet_body = spot.body_fk(np.eye(4), q12)
        names = [n for n in sk.Spot.joint_names if n not in skip]
        values = [v for n, v in zip(sk.Spot.joint_names, q12) if n not in skip]
        frames = {
            "odom": ("body", rigid(seed + 10)),
            "vision": ("body", rigid(seed + 11)),
            **{name: ("body", sk.translation(p)) for name, p in zip(sdk.FOOT_FRAME_NAMES, feet_body)},
        }
        state = sdk.kinematic_state(names, values, frames=frames)
        if kinematic:
            return state
        return robot_state_pb2.RobotState(kinematic_state=state, foot_state=sdk.foot_states(feet_body)[:feet])

    feet_states = {
        "valid": lambda c, r, b: Arg(standing()),
        "kinematic_state": lambda c, r, b: Arg(standing(kinematic=True)),
        "three_feet": lambda c, r, b: Arg(standing(feet=3)),
        "no_feet": lambda c, r, b: Arg(standing(feet=0)),
        "missing_joint": lambda c, r, b: Arg(standing(skip=("fr.kn",))),
        "list": lambda c, r, b: Arg([standing(1), standing(2)]),
        "empty_list": lambda c, r, b: Arg([]),
        "nested_list": lambda c, r, b: Arg([[standing()]], REJECT, "type"),
        "stream": lambda c, r, b: Arg(streamed(), REJECT, "type"),
        "wrong_message": lambda c, r, b: Arg(snapshot(), REJECT, "type"),
        **type_errors(standing),
    }

    def feet_of(state, frame, source, spot):
        """The oracle: each source read plainly, moved into ``frame`` by the SDK's get_a_tform_b."""
        kinematic = state.kinematic_state if isinstance(state, robot_state_pb2.RobotState) else state
        feet_list = state.foot_state if isinstance(state, robot_state_pb2.RobotState) else []
        if source == "auto":
            source = "foot_state" if len(feet_list) == 4 else "kinematics"
        tree = kinematic.transforms_snapshot
        if source == "foot_state":
            body = np.array(
                [
                    [f.foot_position_rt_body.x, f.foot_position_rt_body.y, f.foot_position_rt_body.z]
                    for f in feet_list
                ]
            )
        elif source == "kinematics":
            table = dict(zip(*read_states(kinematic, "position")))
            q12 = np.array([table.get(n, np.nan) for n in sk.Spot.joint_names])
            body = np.array(
                [spot.hip_positions[k] + spot.legs[k].fk(q12[3 * k : 3 * k + 3]) for k in range(4)]
            )
        else:
            body = np.array(
                [frame_helpers.get_a_tform_b(tree, "body", f).get_translation() for f in sdk.FOOT_FRAME_NAMES]
            )
        if frame == "body":
            return body
        pose = frame_helpers.get_a_tform_b(tree, frame, "body")
        return np.array([pose.transform_point(*p) for p in body])

    def feet_probe(result, kw, c):
        state, frame, source = kw["state"], kw.get("frame", "body"), kw.get("source", "auto")
        spot = kw.get("spot") or c.spot
        if isinstance(state, list):
            want = np.array([feet_of(s, frame, source, spot) for s in state]).reshape(-1, 4, 3)
        else:
            want = feet_of(state, frame, source, spot)
        if isinstance(result, np.ndarray) and result.shape == want.shape and result.dtype == np.float64:
            if (
                np.array_equal(np.isnan(result), np.isnan(want))
                and np.nanmax(np.abs(result - want), initial=0) < 1e-11
            ):
                return None
        return f"feet {describe(result)}, expected {describe(want)}"

    register(
        name="sdk.foot_positions",
        covers="spotkin.sdk.foot_positions",
        call=lambda c, **k: sdk.foot_positions(**k),
        slots=[
            Custom("state", feet_states),
            Custom(
                "frame",
                {
                    "valid": lambda c, r, b: Arg("odom"),
                    "body": lambda c, r, b: Arg("body"),
                    "vision": lambda c, r, b: Arg("vision"),
                    "foot_frame": lambda c, r, b: Arg("hl_foot"),
                    "unknown": lambda c, r, b: Arg("map", REJECT, "value"),
                    "none": lambda c, r, b: Arg(None, REJECT, "type"),
                    "int": lambda c, r, b: Arg(1, REJECT, "type"),
                },
                default="omit",
            ),
            Choice("source", "auto", ("auto", "foot_state", "kinematics", "frames"), default="omit"),
            Custom(
                "spot",
                {
                    "none": lambda c, r, b: Arg(None),
                    "spot": lambda c, r, b: Arg(c.spot),
                    "robot": lambda c, r, b: Arg(c.robot("go2"), REJECT, "type"),
                    "str": lambda c, r, b: Arg("spot", REJECT, "type"),
                },
                default="omit",
            ),
        ],
        probe=feet_probe,
        pair_rule=lambda plan: (
            EITHER
            if plan["state"] == "empty_list"
            else REJECT
            if plan["source"] == "choice:foot_state"
            and plan["state"] in ("three_feet", "no_feet", "kinematic_state")
            else None
        ),
    )

    def foot_states_probe(result, kw, c):
        feet = np.asarray(kw["feet"], dtype=np.float64)
        if not (isinstance(result, list) and len(result) == len(feet)):
            return f"not a list of {len(feet)} FootState: {describe(result)}"
        for k, (state, p) in enumerate(zip(result, feet)):
            if not isinstance(state, robot_state_pb2.FootState):
                return f"item {k} is not a FootState"
            got = [
                state.foot_position_rt_body.x,
                state.foot_position_rt_body.y,
                state.foot_position_rt_body.z,
            ]
            if not np.array_equal(got, p, equal_nan=True):
                return f"foot {k} at {got}, given {p}"
            contact = kw.get("contact")
            want = 0 if contact is None else (1 if contact[k] else 2)
            if state.contact != want:
                return f"foot {k} contact {state.contact}, expected {want}"
        return None

    register(
        name="sdk.foot_states",
        covers="spotkin.sdk.foot_states",
        call=lambda c, **k: sdk.foot_states(**k),
        slots=[
            Array("feet", lambda c: c.spot.body_fk(np.eye(4), Q_STAND), inf_ok=True, extra=NAN_KEPT),
            Custom(
                "contact",
                {
                    "none": lambda c, r, b: Arg(None),
                    "valid": lambda c, r, b: Arg([True, False, True, True]),
                    "array": lambda c, r, b: Arg(np.array([False] * 4)),
                    "short": lambda c, r, b: Arg([True] * 3, REJECT, "value"),
                    "ints": lambda c, r, b: Arg([1, 0, 1, 1], REJECT, "type"),
                    "str": lambda c, r, b: Arg("yes", REJECT, "type"),
                },
                default="omit",
            ),
        ],
        probe=foot_states_probe,
    )

    # ---- joint commands ----

    def command_probe(result, kw, c):
        parts = [np.asarray(kw["q12"], dtype=np.float64)]
        if kw.get("q_arm") is not None:
            parts.append(np.asarray(kw["q_arm"], dtype=np.float64))
            parts.append(np.asarray(kw["gripper"], dtype=np.float64)[..., None])
        width = sum(p.shape[-1] for p in parts)
        extras = {
            f: np.asarray(kw[f], dtype=np.float64) for f in ("velocity", "load") if kw.get(f) is not None
        }
        lead = np.broadcast_shapes(*(p.shape[:-1] for p in [*parts, *extras.values()]))
        position = np.concatenate([np.broadcast_to(p, (*lead, p.shape[-1])) for p in parts], -1).reshape(
            -1, width
        )
        messages = nested_messages(result, lead, basic_command_pb2.JointCommand.UpdateRequest)
        if isinstance(messages, str):
            return messages
        for k, message in enumerate(messages):
            if list(message.position) != position[k].astype(np.float32).tolist():
                return f"message {k}: position {list(message.position)}, expected {position[k].tolist()}"
            for field in ("velocity", "load"):
                want = (
                    np.broadcast_to(extras[field], (*lead, width)).reshape(-1, width)[k]
                    if field in extras
                    else np.zeros(0)
                )
                if list(getattr(message, field)) != want.astype(np.float32).tolist():
                    return f"message {k}: {field} {list(getattr(message, field))}, expected {want.tolist()}"
        return None

    def command_rule(with_arm):
        def rule(plan):
            if any(v in COMMAND_REFUSED for v in plan.values()):
                return REJECT
            arm = plan["q_arm"] not in ("omit", "none")
            grip = plan["gripper"] not in ("omit", "none")
            extra = any(plan[f] not in ("omit", "none") for f in ("velocity", "load"))
            if arm != grip:
                return REJECT
            if extra and arm != with_arm:
                return REJECT  # 12 velocities with 19 joints, or 19 with 12
            return None

        return rule

    for with_arm in (False, True):
        width = 19 if with_arm else 12
        default = "valid" if with_arm else "omit"
        register(
            name=f"sdk.joint_positions_message[{'arm' if with_arm else 'legs'}]",
            covers="spotkin.sdk.joint_positions_message",
            call=lambda c, **k: sdk.joint_positions_message(**k),
            slots=[
                Batch("q12", (12,)),
                Batch("q_arm", (6,), optional=True, default=default),
                Batch("gripper", (), optional=True, default=default),
                Batch("velocity", (width,), optional=True, default="omit"),
                Batch("load", (width,), optional=True, default="omit"),
            ],
            baseline=lambda c, rng, n, width=width: {
                "q12": Q_STAND + rng.uniform(-0.2, 0.2, (n, 12)),
                "q_arm": rng.uniform(-1, 1, (n, 6)),
                "gripper": rng.uniform(-1, 0, n),
                "velocity": rng.uniform(-1, 1, (n, width)),
                "load": rng.uniform(-5, 5, (n, width)),
            },
            probe=command_probe,
            pair_rule=command_rule(with_arm),
        )

    def update(count=19, velocity=True):
        values = np.random.default_rng(count).uniform(-1, 1, count).tolist()
        message = basic_command_pb2.JointCommand.UpdateRequest(position=values)
        if velocity:
            message.velocity.extend(values)
            message.load.extend(values)
        return message

    commands = {
        "valid": lambda c, r, b: Arg(update()),
        "legs": lambda c, r, b: Arg(update(12)),
        "positions_only": lambda c, r, b: Arg(update(19, velocity=False)),
        "stream_request": lambda c, r, b: Arg(
            robot_command_pb2.JointControlStreamRequest(joint_command=update())
        ),
        "list": lambda c, r, b: Arg([update(), update(12)]),
        "empty_list": lambda c, r, b: Arg([]),
        "count_7": lambda c, r, b: Arg(update(7), REJECT, "value"),
        "empty_message": lambda c, r, b: Arg(basic_command_pb2.JointCommand.UpdateRequest(), REJECT, "value"),
        "nested_list": lambda c, r, b: Arg([[update()]], REJECT, "type"),
        "wrong_message": lambda c, r, b: Arg(arm_command_pb2.ArmJointPosition(), REJECT, "type"),
        **type_errors(update),
    }

    def read_command(message, field):
        if isinstance(message, robot_command_pb2.JointControlStreamRequest):
            message = message.joint_command
        values = np.full(19, np.nan)
        got = list(getattr(message, field))
        values[: len(got)] = got
        return values

    def command_read_probe(result, kw, c):
        field = kw.get("field", "position")
        message = kw["message"]
        want = (
            np.array([read_command(m, field) for m in message]).reshape(-1, 19)
            if isinstance(message, list)
            else read_command(message, field)
        )
        if not (isinstance(result, tuple) and len(result) == 3):
            return f"not (q12, q_arm, gripper): {describe(result)}"
        return (
            same(result[0], want[..., :12], "q12")
            or same(result[1], want[..., 12:18], "q_arm")
            or same(result[2], want[..., 18], "gripper")
        )

    register(
        name="sdk.joint_command_positions",
        covers="spotkin.sdk.joint_command_positions",
        call=lambda c, **k: sdk.joint_command_positions(**k),
        slots=[
            Custom("message", commands),
            Choice("field", "position", ("position", "velocity", "load"), default="omit"),
        ],
        probe=command_read_probe,
        pair_rule=lambda plan: (
            REJECT
            if plan["message"] in ("positions_only",) and plan["field"] in ("choice:velocity", "choice:load")
            else None
        ),
    )

    def arm_message_probe(result, kw, c):
        q, lead, _ = plain(kw["q_arm"], (6,))
        messages = nested_messages(result, lead, arm_command_pb2.ArmJointPosition)
        if isinstance(messages, str):
            return messages
        for k, (message, row) in enumerate(zip(messages, q.reshape(-1, 6))):
            if message != RobotCommandBuilder.create_arm_joint_trajectory_point(*row.tolist()).position:
                return f"message {k} differs from RobotCommandBuilder's for {row.tolist()}"
        return None

    register(
        name="sdk.arm_joint_position_message",
        covers="spotkin.sdk.arm_joint_position_message",
        call=lambda c, **k: sdk.arm_joint_position_message(**k),
        slots=[Batch("q_arm", (6,))],
        baseline=lambda c, rng, n: {"q_arm": rng.uniform(-2, 2, (n, 6))},
        probe=arm_message_probe,
        pair_rule=lambda plan: REJECT if plan["q_arm"] in COMMAND_REFUSED else None,
    )

    def arm_point(seed=1, clear=()):
        q = np.random.default_rng(seed).uniform(-1, 1, 6).tolist()
        point = RobotCommandBuilder.create_arm_joint_trajectory_point(*q)
        for joint in clear:
            point.position.ClearField(joint)
        return point

    def arm_read(value):
        if isinstance(value, arm_command_pb2.ArmJointTrajectoryPoint):
            value = value.position
        return [
            getattr(value, j).value if value.HasField(j) else math.nan
            for j in ("sh0", "sh1", "el0", "el1", "wr0", "wr1")
        ]

    def nan_joint(seed=1):
        point = arm_point(seed)
        point.position.el0.value = math.nan
        return point.position

    arm_messages = {
        "valid": lambda c, r, b: Arg(arm_point().position),
        "point": lambda c, r, b: Arg(arm_point()),
        "repeated": lambda c, r, b: Arg(
            RobotCommandBuilder.arm_joint_command(
                0.1, -1.0, 1.2, 0.0, 0.3, -0.2
            ).synchronized_command.arm_command.arm_joint_move_command.trajectory.points
        ),
        "list": lambda c, r, b: Arg([arm_point(1), arm_point(2).position]),
        "nested": lambda c, r, b: Arg([[arm_point(1)], [arm_point(2)]]),
        "empty": lambda c, r, b: Arg([]),
        "partial": lambda c, r, b: Arg(arm_point(clear=("sh1", "wr1")).position),
        "nothing_set": lambda c, r, b: Arg(arm_command_pb2.ArmJointPosition()),
        "nan": lambda c, r, b: Arg(nan_joint()),
        "ragged": lambda c, r, b: Arg([[arm_point()], []], REJECT, "value"),
        "wrong_message": lambda c, r, b: Arg(update(), REJECT, "type"),
        **type_errors(arm_point),
    }

    register(
        name="sdk.arm_joint_positions",
        covers="spotkin.sdk.arm_joint_positions",
        call=lambda c, **k: sdk.arm_joint_positions(**k),
        slots=[Custom("message", arm_messages)],
        probe=array_probe((6,), arm_read, "message"),
    )
