"""spotkin.sdk against the Boston Dynamics Spot SDK itself (issue 19), without a robot.

The messages are real ``bosdyn.api`` protobufs built in the tests: ``SE3Pose``, ``Quaternion``,
``FrameTreeSnapshot`` (with the shape of a robot's: ``body`` at the root), ``KinematicState``,
``RobotState``, the streamed joint states and the joint commands. The oracles are the SDK's own
helpers on the same messages (``bosdyn.client.math_helpers``, ``bosdyn.client.frame_helpers``,
``RobotCommandBuilder``, the joint indices of ``spot_constants_pb2``), scipy's rotations, and spotkin's
FK. The optional extra stays optional: without the SDK, ``import spotkin.sdk`` says what to install.
"""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import spotkin as sk
from conftest import random_rigid

bosdyn = pytest.importorskip("bosdyn.client", reason='the Spot SDK: pip install "spotkin[sdk]"')

from bosdyn.api import (  # noqa: E402
    arm_command_pb2,
    basic_command_pb2,
    geometry_pb2,
    robot_command_pb2,
    robot_state_pb2,
    trajectory_pb2,
)
from bosdyn.api.spot import spot_constants_pb2  # noqa: E402
from bosdyn.client import frame_helpers, math_helpers  # noqa: E402
from bosdyn.client.robot_command import RobotCommandBuilder  # noqa: E402

from spotkin import sdk  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SPOT = sk.Spot()

# A rotation with no symmetry to hide a wrong quaternion order: 0.9 rad about a skew axis.
AXIS = np.array([0.2, -0.5, 0.84]) / np.linalg.norm([0.2, -0.5, 0.84])
SKEW = Rotation.from_rotvec(0.9 * AXIS)


def quaternion(rotation: Rotation) -> geometry_pb2.Quaternion:
    """The SDK's message for a scipy rotation: scipy is (x, y, z, w), the message has named fields."""
    x, y, z, w = rotation.as_quat()
    return geometry_pb2.Quaternion(w=w, x=x, y=y, z=z)


def se3(T: np.ndarray) -> geometry_pb2.SE3Pose:
    """An SE3Pose message for a rigid T, built field by field (not with spotkin)."""
    x, y, z = T[:3, 3]
    return geometry_pb2.SE3Pose(
        position=geometry_pb2.Vec3(x=x, y=y, z=z), rotation=quaternion(Rotation.from_matrix(T[:3, :3]))
    )


def _wxyz(q):
    """The (w, x, y, z) fields of a quaternion message or math_helpers.Quat."""
    return q.w, q.x, q.y, q.z


def robot_like_snapshot(rng) -> tuple[geometry_pb2.FrameTreeSnapshot, dict]:
    """A FrameTreeSnapshot shaped like a robot's (root "body"), built with the protobuf API, and its
    edges {child: (parent, parent_tform_child)}."""
    edges = {
        "odom": ("body", random_rigid(rng)),
        "vision": ("body", random_rigid(rng)),
        "flat_body": ("body", random_rigid(rng)),
        "gpe": ("odom", random_rigid(rng)),
        "hand": ("body", random_rigid(rng)),
        "arm0.link_wr1": ("hand", random_rigid(rng)),
        **{name: ("body", random_rigid(rng)) for name in frame_helpers.FOOT_FRAME_NAMES},
    }
    snapshot = geometry_pb2.FrameTreeSnapshot()
    snapshot.child_to_parent_edge_map["body"].parent_frame_name = ""
    for child, (parent, T) in edges.items():
        snapshot.child_to_parent_edge_map[child].parent_frame_name = parent
        snapshot.child_to_parent_edge_map[child].parent_tform_child.CopyFrom(se3(T))
    return snapshot, edges


# ---- the optional extra --------------------------------------------------------------------------------


def test_without_the_sdk_the_import_says_what_to_install():
    code = textwrap.dedent(
        """
        import sys
        for name in ("bosdyn", "bosdyn.api", "bosdyn.client"):
            sys.modules[name] = None  # as if the SDK were not installed
        import spotkin  # the core needs no SDK
        assert "spotkin.sdk" not in sys.modules
        try:
            import spotkin.sdk
        except ImportError as error:
            print(error)
        else:
            raise SystemExit("spotkin.sdk imported without the SDK")
        """
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert 'pip install "spotkin[sdk]"' in done.stdout


def test_the_extra_is_declared_and_optional():
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert not any("bosdyn" in requirement for requirement in project["dependencies"])
    assert any(r.startswith("bosdyn-client") for r in project["optional-dependencies"]["sdk"])
    tests = (ROOT / "requirements-test.txt").read_text(encoding="utf-8")
    assert "bosdyn-client" in tests


# ---- quaternions, poses, vectors -----------------------------------------------------------------------


def test_the_quaternion_order_is_w_x_y_z():
    message = quaternion(SKEW)
    R = sdk.quat_to_matrix(message)
    assert np.abs(R - SKEW.as_matrix()).max() < 1e-15
    assert np.abs(R - math_helpers.Quat.from_proto(message).to_matrix()).max() < 1e-15
    # the array form follows the SDK too: (w, x, y, z)
    x, y, z, w = SKEW.as_quat()
    assert np.abs(sdk.quat_to_matrix([w, x, y, z]) - R).max() < 1e-15
    # the test can fail: the same numbers read scalar-last are another rotation
    assert np.abs(Rotation.from_quat([w, x, y, z]).as_matrix() - R).max() > 0.1
    # a yaw is a rotation about z, the SDK's and spotkin's
    yaw = math_helpers.Quat.from_yaw(0.7)
    assert np.abs(sdk.quat_to_matrix(yaw) - sk.rotation_z(0.7)[:3, :3]).max() < 1e-15
    roll = math_helpers.Quat.from_roll(-0.4)
    assert np.abs(sdk.quat_to_matrix(roll.to_proto()) - sk.rotation_x(-0.4)[:3, :3]).max() < 1e-15
    back = sdk.matrix_to_quat(SKEW.as_matrix())
    assert isinstance(back, geometry_pb2.Quaternion) and back.w > 0
    assert np.allclose([back.w, back.x, back.y, back.z], [w, x, y, z], atol=1e-15)


@given(seed=st.integers(0, 2**32 - 1))
def test_quaternions_round_trip_and_agree_with_the_sdk(seed):
    rotations = Rotation.random(20, random_state=seed)
    # half of them near 180 degrees, where the trace is about -1
    flips = Rotation.from_rotvec(
        np.pi * rotations[:10].as_rotvec() / np.linalg.norm(rotations[:10].as_rotvec(), axis=1)[:, None]
    )
    matrices = np.concatenate([rotations.as_matrix(), flips.as_matrix()])
    messages = sdk.matrix_to_quat(matrices)
    assert isinstance(messages, list) and len(messages) == 30
    for R, message in zip(matrices, messages):
        assert message.w >= 0
        assert abs(math.hypot(message.w, message.x, message.y, message.z) - 1) < 1e-15
        assert np.abs(math_helpers.Quat.from_proto(message).to_matrix() - R).max() < 1e-14
        sdk_q = math_helpers.Quat.from_matrix(R)  # the SDK's own conversion, up to the sign
        sign = (
            1.0
            if sdk_q.w * message.w + sdk_q.x * message.x + sdk_q.y * message.y + sdk_q.z * message.z > 0
            else -1.0
        )
        assert np.allclose(
            [message.w, message.x, message.y, message.z], sign * np.array(list(_wxyz(sdk_q))), atol=1e-12
        )
    assert np.abs(sdk.quat_to_matrix(messages) - matrices).max() < 1e-14


@given(seed=st.integers(0, 2**32 - 1))
def test_poses_round_trip_and_agree_with_the_sdk(seed):
    rng = np.random.default_rng(seed)
    T = np.array([random_rigid(rng) for _ in range(6)])
    messages = [se3(t) for t in T]
    mine = sdk.se3_to_matrix(messages)
    assert mine.shape == (6, 4, 4) and mine.dtype == np.float64
    for t, message, matrix in zip(T, messages, mine):
        helper = math_helpers.SE3Pose.from_proto(message)
        assert np.abs(helper.to_matrix() - matrix).max() < 1e-14
        assert np.abs(matrix - t).max() < 1e-14
        point = rng.normal(size=3)
        assert np.allclose(helper.transform_point(*point), matrix[:3, :3] @ point + matrix[:3, 3], atol=1e-14)
        assert np.abs(sdk.se3_to_matrix(helper) - matrix).max() < 1e-14  # math_helpers objects too
        # spotkin's message read by the SDK
        back = sdk.matrix_to_se3(t)
        assert np.abs(math_helpers.SE3Pose.from_proto(back).to_matrix() - t).max() < 1e-14
        assert np.abs(sdk.se3_to_matrix(math_helpers.SE3Pose.from_matrix(t)) - t).max() < 1e-14
    # products agree: the SDK's a_tform_b * b_tform_c is the matrix product
    ab, bc = (math_helpers.SE3Pose.from_proto(m) for m in messages[:2])
    assert np.abs(sdk.se3_to_matrix(ab * bc) - mine[0] @ mine[1]).max() < 1e-14
    assert np.abs(sdk.se3_to_matrix(ab.inverse()) - np.linalg.inv(mine[0])).max() < 1e-13


def test_batches_nest_both_ways(rng):
    T = np.array([[random_rigid(rng) for _ in range(3)] for _ in range(2)])
    nested = sdk.matrix_to_se3(T)
    assert len(nested) == 2 and all(len(row) == 3 for row in nested)
    assert all(isinstance(m, geometry_pb2.SE3Pose) for row in nested for m in row)
    assert np.abs(sdk.se3_to_matrix(nested) - T).max() < 1e-14
    assert sdk.se3_to_matrix([]).shape == (0, 4, 4)
    assert sdk.matrix_to_se3(np.zeros((0, 4, 4))) == []
    assert sdk.quat_to_matrix(np.zeros((2, 0, 4))).shape == (2, 0, 3, 3)
    p = rng.normal(size=(4, 3))
    vectors = sdk.array_to_vec3(p)
    assert all(isinstance(v, geometry_pb2.Vec3) for v in vectors)
    assert np.array_equal(sdk.vec3_to_array(vectors), p)
    assert np.array_equal(sdk.vec3_to_array(math_helpers.Vec3(*p[0])), p[0])
    # a repeated field of the SDK is a batch too
    trajectory = trajectory_pb2.SE3Trajectory()
    for t in T[0]:
        trajectory.points.add().pose.CopyFrom(se3(t))
    assert np.abs(sdk.se3_to_matrix([point.pose for point in trajectory.points]) - T[0]).max() < 1e-14
    # strided and float32 arrays in
    strided = np.repeat(T[0], 2, axis=0)[::2]
    assert np.abs(sdk.se3_to_matrix(sdk.matrix_to_se3(strided)) - T[0]).max() < 1e-14
    single = sdk.matrix_to_se3(T[0, 0].astype(np.float32))
    assert np.abs(sdk.se3_to_matrix(single) - T[0, 0]).max() < 1e-6


def test_an_unset_rotation_is_the_identity_as_in_the_sdk():
    message = geometry_pb2.SE3Pose(position=geometry_pb2.Vec3(x=1.0, y=2.0, z=3.0))
    assert not message.HasField("rotation")
    assert np.array_equal(sdk.se3_to_matrix(message), math_helpers.SE3Pose.from_proto(message).to_matrix())
    assert np.array_equal(sdk.se3_to_matrix(message), sk.translation([1.0, 2.0, 3.0]))


def test_bad_numbers_give_nan_in_their_sample_only(rng):
    T = random_rigid(rng)
    good = se3(T)
    scaled = se3(T)
    scaled.rotation.w *= 2.0  # not a unit quaternion
    zero = geometry_pb2.SE3Pose(rotation=geometry_pb2.Quaternion())  # set, and zero
    nan = se3(T)
    nan.position.y = math.nan
    inf = se3(T)
    inf.rotation.x = math.inf
    out = sdk.se3_to_matrix([good, scaled, zero, nan, inf, good])
    assert np.isnan(out[1:5]).all()
    assert np.abs(out[[0, 5]] - T).max() < 1e-14
    # within the tolerance, a quaternion is read as its normalised rotation
    near = se3(T)
    near.rotation.w *= 1 + 4e-7
    assert np.abs(sdk.se3_to_matrix(near) - T).max() < 1e-6
    # matrices that are not rigid transforms give NaN fields, that sample only
    bad = np.array([T, T, T, T])
    bad[1, :3, :3] *= 2.0
    bad[2, 3, 0] = 1e-3
    bad[3, :3, 0] *= -1.0  # a reflection
    poses = sdk.matrix_to_se3(bad)
    values = np.array([list(math_helpers.SE3Pose.from_proto(p)) for p in poses])
    assert np.isnan(values[1:]).all() and np.isfinite(values[0]).all()
    quats = sdk.matrix_to_quat(np.array([T[:3, :3], np.full((3, 3), np.nan)]))
    assert np.isfinite(list(_wxyz(quats[0]))).all() and np.isnan(list(_wxyz(quats[1]))).all()


def test_wrong_types_and_shapes_are_named():
    with pytest.raises(TypeError, match=r"pose must be a bosdyn\.api\.SE3Pose"):
        sdk.se3_to_matrix(geometry_pb2.Vec3())
    with pytest.raises(TypeError, match="pose must be"):
        sdk.se3_to_matrix("body")
    with pytest.raises(TypeError, match="quat must be"):
        sdk.quat_to_matrix(geometry_pb2.SE3Pose())
    with pytest.raises(ValueError, match=r"quat must have shape \(\.\.\., 4\)"):
        sdk.quat_to_matrix([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="ragged"):
        sdk.vec3_to_array([[geometry_pb2.Vec3()], []])
    with pytest.raises(ValueError, match=r"T must have shape \(\.\.\., 4, 4\)"):
        sdk.matrix_to_se3(np.eye(3))
    with pytest.raises(TypeError, match="R must be a real numeric array"):
        sdk.matrix_to_quat("identity")


# ---- frame trees ---------------------------------------------------------------------------------------


def test_frame_walks_agree_with_get_a_tform_b(rng):
    snapshot, _ = robot_like_snapshot(rng)
    assert frame_helpers.validate_frame_tree_snapshot(snapshot)
    frames = frame_helpers.get_frame_names(snapshot)
    assert len(frames) == 11
    for a in frames:
        for b in frames:
            reference = frame_helpers.get_a_tform_b(snapshot, a, b).to_matrix()
            assert np.abs(sdk.frame_transform(snapshot, a, b) - reference).max() < 1e-12, (a, b)
    odom_body = frame_helpers.get_odom_tform_body(snapshot).to_matrix()
    assert np.abs(sdk.frame_transform(snapshot, "odom", "body") - odom_body).max() < 1e-12
    # a KinematicState, a RobotState, and a list of them
    kinematic = robot_state_pb2.KinematicState(transforms_snapshot=snapshot)
    state = robot_state_pb2.RobotState(kinematic_state=kinematic)
    assert np.array_equal(
        sdk.frame_transform(kinematic, "gpe", "hand"), sdk.frame_transform(snapshot, "gpe", "hand")
    )
    many = sdk.frame_transform([state, snapshot, kinematic], "vision", "fl_foot")
    assert many.shape == (3, 4, 4) and np.array_equal(many[0], many[1])


@given(seed=st.integers(0, 2**32 - 1), size=st.integers(1, 12))
def test_random_trees_agree_with_the_sdk(seed, size):
    rng = np.random.default_rng(seed)
    names = [f"frame{k}" for k in range(size + 1)]
    snapshot = geometry_pb2.FrameTreeSnapshot()
    snapshot.child_to_parent_edge_map[names[0]].parent_frame_name = ""
    for k in range(1, size + 1):
        edge = snapshot.child_to_parent_edge_map[names[k]]
        edge.parent_frame_name = names[int(rng.integers(k))]  # any earlier frame: a tree
        edge.parent_tform_child.CopyFrom(se3(random_rigid(rng)))
    for _ in range(10):
        a, b = rng.choice(names, 2)
        reference = frame_helpers.get_a_tform_b(snapshot, a, b).to_matrix()
        assert np.abs(sdk.frame_transform(snapshot, a, b) - reference).max() < 1e-11


def test_edges_and_snapshots_round_trip(rng):
    snapshot, edges = robot_like_snapshot(rng)
    read = sdk.frame_tree_edges(snapshot)
    assert set(read) == set(edges)
    for child, (parent, T) in edges.items():
        assert read[child][0] == parent and np.abs(read[child][1] - T).max() < 1e-14
    rebuilt = sdk.frame_tree_snapshot(read)
    assert frame_helpers.validate_frame_tree_snapshot(rebuilt)
    assert rebuilt.child_to_parent_edge_map["body"].parent_frame_name == ""
    for a, b in (("odom", "hand"), ("gpe", "hr_foot"), ("arm0.link_wr1", "vision")):
        reference = frame_helpers.get_a_tform_b(rebuilt, a, b).to_matrix()
        assert np.abs(sdk.frame_transform(snapshot, a, b) - reference).max() < 1e-12
    # message edges pass through, math_helpers poses too
    messages = {
        "odom": ("body", se3(edges["odom"][1])),
        "gpe": ("odom", math_helpers.SE3Pose.from_matrix(edges["gpe"][1])),
    }
    small = sdk.frame_tree_snapshot(messages)
    assert (
        np.abs(sdk.frame_transform(small, "body", "gpe") - edges["odom"][1] @ edges["gpe"][1]).max() < 1e-12
    )


def test_frame_errors_are_clear(rng):
    snapshot, _ = robot_like_snapshot(rng)
    with pytest.raises(
        ValueError, match=r"frame_b 'tool' is not in the frame tree; its frames: 'arm0\.link_wr1'"
    ):
        sdk.frame_transform(snapshot, "body", "tool")
    with pytest.raises(ValueError, match="an empty snapshot"):
        sdk.frame_transform(geometry_pb2.FrameTreeSnapshot(), "odom", "body")
    with pytest.raises(TypeError, match="frame_a must be a frame name"):
        sdk.frame_transform(snapshot, None, "body")
    with pytest.raises(TypeError, match=r"snapshot must be a bosdyn\.api\.FrameTreeSnapshot"):
        sdk.frame_transform({"odom": "body"}, "odom", "body")
    loop = geometry_pb2.FrameTreeSnapshot()
    loop.child_to_parent_edge_map["a"].parent_frame_name = "b"
    loop.child_to_parent_edge_map["b"].parent_frame_name = "a"
    with pytest.raises(ValueError, match="loop"):
        sdk.frame_transform(loop, "a", "b")
    two = sdk.frame_tree_snapshot({"x": ("r", np.eye(4))})
    two.child_to_parent_edge_map["y"].parent_frame_name = "s"
    with pytest.raises(ValueError, match="separate trees"):
        sdk.frame_transform(two, "x", "y")
    with pytest.raises(ValueError, match="one tree"):
        sdk.frame_tree_snapshot({"x": ("r", np.eye(4)), "y": ("s", np.eye(4))})
    with pytest.raises(ValueError, match="loop"):
        sdk.frame_tree_snapshot({"x": ("y", np.eye(4)), "y": ("x", np.eye(4)), "z": ("w", np.eye(4))})
    with pytest.raises(TypeError, match="non-empty str"):
        sdk.frame_tree_snapshot({"x": ("", np.eye(4))})
    with pytest.raises(ValueError, match=r"\(4, 4\)"):
        sdk.frame_tree_snapshot({"x": ("r", np.eye(3))})
    # the messages the tests read are never changed by a look-up
    before = snapshot.SerializeToString(deterministic=True)
    with pytest.raises(ValueError):
        sdk.frame_transform(snapshot, "nowhere", "body")
    assert snapshot.SerializeToString(deterministic=True) == before


def test_a_bad_edge_spoils_only_the_paths_through_it(rng):
    snapshot, _ = robot_like_snapshot(rng)
    snapshot.child_to_parent_edge_map["gpe"].parent_tform_child.rotation.w = 5.0
    assert np.isnan(sdk.frame_transform(snapshot, "gpe", "body")).all()
    assert np.isfinite(sdk.frame_transform(snapshot, "odom", "hand")).all()
    good, _ = robot_like_snapshot(rng)
    both = sdk.frame_transform([snapshot, good], "gpe", "vision")
    assert np.isnan(both[0]).all() and np.isfinite(both[1]).all()


# ---- joint states --------------------------------------------------------------------------------------


def reported_state(rng, q12, q_arm, gripper=0.2, skip=()):
    """A KinematicState as a robot reports it, built with the protobuf API: names in the SDK's
    listing (with arm0.hr0 between the shoulder and the elbow), shuffled, velocities and loads."""
    names = [
        *sk.Spot.joint_names,
        "arm0.sh0",
        "arm0.sh1",
        "arm0.hr0",
        *sk.Spot.arm_joint_names[2:],
        "arm0.f1x",
    ]
    values = {**dict(zip(sk.Spot.joint_names, q12)), **dict(zip(sk.Spot.arm_joint_names, q_arm))}
    values.update({"arm0.hr0": 0.0, "arm0.f1x": gripper})
    state = robot_state_pb2.KinematicState()
    for name in rng.permutation(names):
        if name in skip:
            continue
        joint = state.joint_states.add(name=str(name))
        joint.position.value = values[name]
        joint.velocity.value = 10 * values[name]
        joint.load.value = -values[name]
    return state


def test_joint_states_by_name_to_q(rng):
    q12, q_arm = rng.uniform(-1, 1, 12), rng.uniform(-1, 1, 6)
    state = reported_state(rng, q12, q_arm)
    got12, got_arm = sdk.joint_positions(state)
    assert np.array_equal(got12, q12) and np.array_equal(got_arm, q_arm)
    velocity12, velocity_arm = sdk.joint_positions(state, field="velocity")
    assert np.array_equal(velocity12, 10 * q12) and np.array_equal(velocity_arm, 10 * q_arm)
    assert np.array_equal(sdk.joint_positions(state, field="load")[0], -q12)
    assert np.isnan(sdk.joint_positions(state, field="acceleration")[0]).all()  # not reported
    # the same from a RobotState, and Spot's own name map on the raw pairs
    whole = robot_state_pb2.RobotState(kinematic_state=state)
    assert np.array_equal(sdk.joint_positions(whole)[0], q12)
    names, values = sdk.joint_states(state)
    assert len(names) == 20 and {"arm0.hr0", "arm0.f1x"} <= set(names)
    assert np.array_equal(SPOT.q_from_names(names, values), q12)
    assert np.array_equal(SPOT.q_from_names(names, values, joints=SPOT.arm_joint_names), q_arm)
    assert values[names.index("arm0.f1x")] == 0.2
    # a list of states is a batch
    many12, many_arm = sdk.joint_positions([state, whole, state])
    assert many12.shape == (3, 12) and many_arm.shape == (3, 6) and np.array_equal(many12[1], q12)


def test_a_missing_joint_is_nan_or_an_error(rng):
    q12, q_arm = rng.uniform(-1, 1, 12), rng.uniform(-1, 1, 6)
    state = reported_state(rng, q12, q_arm, skip=("hl.kn", *sk.Spot.arm_joint_names))
    got12, got_arm = sdk.joint_positions(state)
    assert (
        np.isnan(got_arm).all()
        and np.isnan(got12[8])
        and np.array_equal(np.delete(got12, 8), np.delete(q12, 8))
    )
    with pytest.raises(ValueError, match=r"hl\.kn"):
        sdk.joint_positions(state, missing="raise")
    unset = reported_state(rng, q12, q_arm)
    joint = next(j for j in unset.joint_states if j.name == "fr.hy")
    joint.ClearField("position")  # reported, without a value
    got12, got_arm = sdk.joint_positions(unset)
    assert np.isnan(got12[4]) and np.isnan(got12).sum() == 1 and np.array_equal(got_arm, q_arm)


def test_streamed_joint_states_follow_the_joint_index(rng):
    values = rng.uniform(-1, 1, 19)
    stream = robot_state_pb2.RobotStateStreamResponse()
    stream.joint_states.position.extend(values)
    stream.joint_states.velocity.extend(2 * values)
    q12, q_arm = sdk.joint_positions(stream)
    float32 = values.astype(np.float32).astype(np.float64)  # the streamed fields are float32
    assert np.array_equal(q12[2], float32[spot_constants_pb2.JOINT_INDEX_FL_KN])
    assert np.array_equal(q12[9], float32[spot_constants_pb2.JOINT_INDEX_HR_HX])
    assert np.array_equal(q_arm[5], float32[spot_constants_pb2.JOINT_INDEX_A0_WR1])
    assert np.array_equal(np.concatenate([q12, q_arm]), float32[:18])
    assert np.array_equal(sdk.joint_positions(stream.joint_states, field="velocity")[0], 2 * float32[:12])
    legs_only = robot_state_pb2.CombinedJointStates(position=values[:12].tolist())
    q12, q_arm = sdk.joint_positions(legs_only)
    assert np.array_equal(q12, float32[:12]) and np.isnan(q_arm).all()
    with pytest.raises(ValueError, match=r"12 \(legs\) or 19"):
        sdk.joint_positions(robot_state_pb2.CombinedJointStates(position=[0.0] * 7))
    with pytest.raises(ValueError, match="acceleration"):
        sdk.joint_positions(stream, field="acceleration")


def test_kinematic_state_is_the_inverse(rng):
    names = [*sk.Spot.joint_names, *sk.Spot.arm_joint_names, "arm0.f1x"]
    position = rng.uniform(-1, 1, len(names))
    position[3] = np.nan  # not reported
    load = rng.uniform(-5, 5, len(names))
    T_body_odom = random_rigid(rng)
    state = sdk.kinematic_state(names, position, load=load, frames={"odom": ("body", T_body_odom)})
    assert isinstance(state, robot_state_pb2.KinematicState)
    assert not state.joint_states[3].HasField("position") and state.joint_states[3].HasField("load")
    assert not state.joint_states[0].HasField("velocity")
    read_names, read = sdk.joint_states(state)
    assert read_names == tuple(names) and np.array_equal(read, position, equal_nan=True)
    assert np.array_equal(sdk.joint_states(state, field="load")[1], load)
    reference = frame_helpers.get_odom_tform_body(state.transforms_snapshot).to_matrix()
    assert np.abs(reference - np.linalg.inv(T_body_odom)).max() < 1e-12
    copied = sdk.kinematic_state(names[:2], position[:2], frames=state.transforms_snapshot)
    assert copied.transforms_snapshot == state.transforms_snapshot
    # the wire format keeps it all
    parsed = robot_state_pb2.KinematicState.FromString(state.SerializeToString())
    assert np.array_equal(sdk.joint_states(parsed)[1], position, equal_nan=True)
    with pytest.raises(ValueError, match=r"position must have shape \(\.\.\., 19\)"):
        sdk.kinematic_state(names, position[:5])
    with pytest.raises(ValueError, match="twice"):
        sdk.kinematic_state(["fl.hx", "fl.hx"], [0.0, 0.0])


# ---- feet ----------------------------------------------------------------------------------------------


def standing_state(rng, q12, T_odom_body, q_arm=None):
    """A RobotState with joint states, foot states (from spotkin's FK) and a robot-like frame tree."""
    names = list(sk.Spot.joint_names)
    values = list(q12)
    if q_arm is not None:
        names += list(sk.Spot.arm_joint_names)
        values += list(q_arm)
    feet_body = SPOT.body_fk(np.eye(4), q12)
    frames = {
        "odom": ("body", np.linalg.inv(T_odom_body)),
        "vision": ("body", random_rigid(rng)),
        **{name: ("body", sk.translation(p)) for name, p in zip(sdk.FOOT_FRAME_NAMES, feet_body)},
    }
    kinematic = sdk.kinematic_state(names, values, frames=frames)
    return robot_state_pb2.RobotState(kinematic_state=kinematic, foot_state=sdk.foot_states(feet_body))


def test_feet_from_every_source_agree(rng):
    q12 = np.tile([0.05, 0.9, -1.6], 4) + rng.uniform(-0.1, 0.1, 12)
    T_odom_body = sk.body_transform([1.0, -2.0, 0.5, 0.05, -0.02, 0.8])
    state = standing_state(rng, q12, T_odom_body)
    in_odom = SPOT.body_fk(T_odom_body, q12)
    odom_tform_body = frame_helpers.get_a_tform_b(state.kinematic_state.transforms_snapshot, "odom", "body")
    for source in ("auto", "foot_state", "kinematics", "frames"):
        feet = sdk.foot_positions(state, frame="odom", source=source)
        assert feet.shape == (4, 3) and np.abs(feet - in_odom).max() < 1e-12, source
        body = sdk.foot_positions(state, source=source)
        # the SDK moves each body-frame foot into odom the same way
        for k in range(4):
            assert np.allclose(odom_tform_body.transform_point(*body[k]), feet[k], atol=1e-12)
    # foot states are read as given: Vec3 in the body frame, legs fl, fr, hl, hr
    listed = np.array(
        [
            [f.foot_position_rt_body.x, f.foot_position_rt_body.y, f.foot_position_rt_body.z]
            for f in state.foot_state
        ]
    )
    assert np.array_equal(sdk.foot_positions(state, source="foot_state"), listed)
    assert np.array_equal(
        sdk.foot_positions(state.kinematic_state), sdk.foot_positions(state, source="kinematics")
    )
    vision = sdk.foot_positions(state, frame="vision")
    T_vision_body = sdk.frame_transform(state, "vision", "body")
    assert np.abs(vision - (listed @ T_vision_body[:3, :3].T + T_vision_body[:3, 3])).max() < 1e-12
    many = sdk.foot_positions([state, state], frame="odom")
    assert many.shape == (2, 4, 3)


def test_feet_with_a_missing_joint_or_foot_state(rng):
    q12 = np.tile([0.0, 0.9, -1.6], 4)
    state = standing_state(rng, q12, np.eye(4))
    del state.foot_state[2]
    auto = sdk.foot_positions(state)  # three foot states: the kinematics instead
    assert np.abs(auto - SPOT.body_fk(np.eye(4), q12)).max() < 1e-12
    with pytest.raises(ValueError, match="3 foot states"):
        sdk.foot_positions(state, source="foot_state")
    state.kinematic_state.joint_states[4].ClearField("position")  # fr.hy
    feet = sdk.foot_positions(state, source="kinematics")
    assert np.isnan(feet[1]).all() and np.isfinite(np.delete(feet, 1, axis=0)).all()
    with pytest.raises(ValueError, match="source must be one of"):
        sdk.foot_positions(state, source="guess")
    with pytest.raises(TypeError, match=r"spot must be an sk\.Spot"):
        sdk.foot_positions(state, spot=sk.Robot.from_urdf(sk.robots.path("go2")))
    with pytest.raises(ValueError, match="frame_a 'map' is not in the frame tree"):
        sdk.foot_positions(state, frame="map")
    contact = sdk.foot_states(np.zeros((4, 3)), contact=[True, False, True, True])
    assert [c.contact for c in contact] == [
        robot_state_pb2.FootState.CONTACT_MADE,
        robot_state_pb2.FootState.CONTACT_LOST,
    ] + [robot_state_pb2.FootState.CONTACT_MADE] * 2
    with pytest.raises(ValueError, match=r"feet must have shape \(n, 3\)"):
        sdk.foot_states(np.zeros((4, 2)))


# ---- joint commands ------------------------------------------------------------------------------------


def test_joint_commands_follow_the_sdk_joint_index(rng):
    q12, q_arm, gripper = rng.uniform(-1, 1, 12), rng.uniform(-1, 1, 6), -0.7
    legs = sdk.joint_positions_message(q12)
    assert isinstance(legs, basic_command_pb2.JointCommand.UpdateRequest) and len(legs.position) == 12
    assert len(legs.velocity) == 0 and len(legs.load) == 0
    message = sdk.joint_positions_message(q12, q_arm, gripper, velocity=np.zeros(19), load=np.ones(19))
    position = np.array(message.position)
    as_float32 = np.float32  # the message's fields are float32
    index = {
        "fl.hx": spot_constants_pb2.JOINT_INDEX_FL_HX,
        "fr.kn": spot_constants_pb2.JOINT_INDEX_FR_KN,
        "hl.hy": spot_constants_pb2.JOINT_INDEX_HL_HY,
        "hr.kn": spot_constants_pb2.JOINT_INDEX_HR_KN,
    }
    for name, k in index.items():
        assert position[k] == as_float32(q12[sk.Spot.joint_names.index(name)])
    assert position[spot_constants_pb2.JOINT_INDEX_A0_SH0] == as_float32(q_arm[0])
    assert position[spot_constants_pb2.JOINT_INDEX_A0_WR1] == as_float32(q_arm[5])
    assert position[spot_constants_pb2.JOINT_INDEX_A0_F1X] == as_float32(gripper)
    assert list(message.velocity) == [0.0] * 19 and list(message.load) == [1.0] * 19
    # the streamed request round-trips through the wire format
    request = robot_command_pb2.JointControlStreamRequest(joint_command=message)
    parsed = robot_command_pb2.JointControlStreamRequest.FromString(request.SerializeToString())
    back12, back_arm, back_gripper = sdk.joint_command_positions(parsed)
    assert np.array_equal(back12, q12.astype(np.float32)) and np.array_equal(
        back_arm, q_arm.astype(np.float32)
    )
    assert back_gripper == as_float32(gripper) and np.abs(back12 - q12).max() < 1e-7
    _, leg_arm, leg_gripper = sdk.joint_command_positions(legs)
    assert np.isnan(leg_arm).all() and np.isnan(leg_gripper)
    assert np.array_equal(sdk.joint_command_positions(message, field="load")[0], np.ones(12))


def test_a_stream_of_commands(rng):
    q12 = rng.uniform(-1, 1, (5, 12))
    stream = sdk.joint_positions_message(q12, rng.uniform(-1, 1, 6), gripper=np.linspace(0, 1, 5))
    assert len(stream) == 5 and all(len(m.position) == 19 for m in stream)
    back12, _, grippers = sdk.joint_command_positions(stream)
    assert np.abs(back12 - q12).max() < 1e-7 and np.allclose(grippers, np.linspace(0, 1, 5), atol=1e-7)
    assert sdk.joint_positions_message(np.zeros((0, 12))) == []


def test_a_command_never_carries_nan(rng):
    q12 = np.tile([0.0, 0.9, -1.6], 4)
    for bad in (np.nan, np.inf, 1e39):
        targets = q12.copy()
        targets[4] = bad
        with pytest.raises(ValueError, match=r"q12\[4\]"):
            sdk.joint_positions_message(targets)
    with pytest.raises(ValueError, match="gripper must be given with q_arm"):
        sdk.joint_positions_message(q12, np.zeros(6))
    with pytest.raises(ValueError, match="gripper needs q_arm"):
        sdk.joint_positions_message(q12, gripper=0.0)
    with pytest.raises(ValueError, match=r"velocity must have shape \(\.\.\., 19\)"):
        sdk.joint_positions_message(q12, np.zeros(6), 0.0, velocity=np.zeros(12))
    with pytest.raises(ValueError, match=r"q12 must have shape \(\.\.\., 12\)"):
        sdk.joint_positions_message(np.zeros(18))
    with pytest.raises(ValueError, match=r"q_arm\[2\]"):
        sdk.arm_joint_position_message([0.0, 0.0, np.nan, 0.0, 0.0, 0.0])


def test_arm_joint_positions_match_the_command_builder(rng):
    q_arm = rng.uniform(-1, 1, 6)
    mine = sdk.arm_joint_position_message(q_arm)
    built = RobotCommandBuilder.create_arm_joint_trajectory_point(*q_arm).position
    assert mine == built  # protobuf equality: every field
    command = RobotCommandBuilder.arm_joint_command(*q_arm)
    points = command.synchronized_command.arm_command.arm_joint_move_command.trajectory.points
    assert np.array_equal(sdk.arm_joint_positions(points), q_arm[None])
    assert np.array_equal(sdk.arm_joint_positions(points[0]), q_arm)
    partial = arm_command_pb2.ArmJointPosition()
    partial.el0.value = 0.5
    assert np.array_equal(
        sdk.arm_joint_positions(partial), [np.nan, np.nan, 0.5, np.nan, np.nan, np.nan], equal_nan=True
    )
    many = sdk.arm_joint_position_message(rng.uniform(-1, 1, (3, 6)))
    assert len(many) == 3 and all(isinstance(m, arm_command_pb2.ArmJointPosition) for m in many)


# ---- the README's flow, end to end ---------------------------------------------------------------------


def test_body_ik_against_the_odom_frame_from_a_state(rng):
    """Read a state, lower and pitch the body in odom with the feet kept, command the answer."""
    q12_now = np.tile([0.0, 0.9, -1.6], 4)
    q_arm_now = np.array([0.0, -3.1, 3.1, 0.0, 0.0, 0.0])
    T_odom_body_now = sk.body_transform([3.0, -1.0, 0.52, 0.0, 0.02, 2.5])
    state = standing_state(rng, q12_now, T_odom_body_now, q_arm_now)
    q12, q_arm = sdk.joint_positions(state.kinematic_state)
    T_odom_body = sdk.frame_transform(state.kinematic_state.transforms_snapshot, "odom", "body")
    feet = sdk.foot_positions(state, frame="odom")
    target = T_odom_body @ sk.body_transform([0.0, 0.0, -0.05, 0.0, 0.1, 0.0])
    res = SPOT.body_ik(target, feet, seed=q12)
    assert (res.status == sk.Status.OK).all()
    assert np.abs(SPOT.body_fk(target, res.q) - feet).max() < 1e-9
    cmd = sdk.joint_positions_message(res.q, q_arm, gripper=0.0)
    back12, back_arm, _ = sdk.joint_command_positions(cmd)
    assert np.abs(back12 - res.q).max() < 1e-6 and np.abs(back_arm - q_arm_now).max() < 1e-6
