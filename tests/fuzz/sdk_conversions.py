"""Registry entries of ``spotkin.sdk``'s conversions: Vec3, Quaternion and SE3Pose messages to arrays,
and arrays back to messages."""

from __future__ import annotations

import math

import numpy as np
from bosdyn.api import geometry_pb2
from bosdyn.client import math_helpers
from scipy.spatial.transform import Rotation

from spotkin import sdk

from .batch import Batch
from .entry import register
from .outputs import close, describe
from .sdk_messages import (
    objects,
    pose_matrix,
    quat,
    quat_matrix,
    rigid,
    same,
    se3,
    snapshot,
    type_errors,
    vec,
    walk,
)
from .slots import REJECT, Arg, Custom


def array_probe(trailing, read, name):
    def probe(result, kw, c):
        nested = walk(kw[name], read)
        want = np.array(nested, dtype=np.float64)
        if want.size == 0:
            want = want.reshape(*want.shape, *trailing) if want.shape[-1:] != trailing[-1:] else want
        return same(result, want, name)

    return probe


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


def register_entries() -> None:
    """Registers these entries (:mod:`fuzz.sdk` calls it when the SDK is installed)."""
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
