"""Joint positions by name (issue 19): ``Robot.q_from_names`` and ``Robot.names_from_q`` for Spot, the
packaged URDF robots and a six-legged robot whose joints interleave, the way ROS ``sensor_msgs/JointState``
and other middleware give them: names and positions in any order, subsets, batches.

The oracle is a plain dictionary: ``dict(zip(names, positions))`` read in the order of the robot's q.
"""

from __future__ import annotations

import numpy as np
import pytest
from fuzz.urdf_texts import HEXAPOD_URDF
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk

SDK_EXTRA = ("arm0.hr0", "arm0.f1x")  # reported by a real Spot beside the 18 joints of q12 and q_arm


def _robots():
    return {
        "spot": sk.Spot(),
        "spot_model": sk.Spot(sk.models.SPOT),
        "go2": sk.Robot.from_urdf(sk.robots.path("go2")),
        "spot_urdf": sk.Robot.from_urdf(sk.robots.path("spot_with_arm")),
        "hexapod": sk.Robot.from_urdf_string(HEXAPOD_URDF),
    }


ROBOTS = _robots()


def by_dictionary(names, positions, joints) -> np.ndarray:
    """The oracle: positions looked up by name, NaN where a joint is not given (one sample)."""
    table = dict(zip(names, np.asarray(positions, dtype=float)))
    return np.array([table.get(name, np.nan) for name in joints])


@pytest.mark.parametrize("key", list(ROBOTS))
def test_any_order_gives_the_whole_body_q(key, rng):
    robot = ROBOTS[key]
    joints = robot.leg_joint_names
    q = rng.uniform(-1, 1, len(joints))
    for _ in range(5):
        order = rng.permutation(len(joints))
        names = [joints[k] for k in order]
        got = robot.q_from_names(names, q[order])
        assert np.array_equal(got, q)
        assert np.array_equal(got, by_dictionary(names, q[order], joints))
    names, positions = robot.names_from_q(q)
    assert names == joints and np.array_equal(positions, q)


@pytest.mark.parametrize("key", ["spot", "spot_urdf"])
def test_the_arm_has_its_own_q(key, rng):
    robot = ROBOTS[key]
    assert len(robot.arm_joint_names) == 6
    every = [*robot.leg_joint_names, *robot.arm_joint_names]
    values = rng.uniform(-1, 1, len(every))
    order = rng.permutation(len(every))
    names, positions = [every[k] for k in order], values[order]
    assert np.array_equal(robot.q_from_names(names, positions), values[:-6])
    assert np.array_equal(robot.q_from_names(names, positions, joints=robot.arm_joint_names), values[-6:])
    both = robot.q_from_names(names, positions, joints=every)
    assert np.array_equal(both, values)
    back_names, back = robot.names_from_q(both, joints=every)
    assert back_names == tuple(every) and np.array_equal(back, values)


def test_robots_without_an_arm_have_no_arm_joints():
    assert ROBOTS["go2"].arm_joint_names == ()
    assert ROBOTS["hexapod"].arm_joint_names == ()


def test_the_hexapod_q_follows_the_urdf_order_not_the_legs(rng):
    # its URDF interleaves the legs' joints: q's order is the URDF's, not leg after leg
    robot = ROBOTS["hexapod"]
    leg_by_leg = [name for spec in sk.urdf.find_legs(robot.model)[0] for name in spec.joint_names]
    assert sorted(leg_by_leg) == sorted(robot.leg_joint_names) and leg_by_leg != list(robot.leg_joint_names)
    values = rng.uniform(-1, 1, 18)
    q = robot.q_from_names(leg_by_leg, values)
    assert np.array_equal(q, by_dictionary(leg_by_leg, values, robot.leg_joint_names))
    # each leg's joints land where the whole-body calls read them
    feet = robot.body_fk(np.eye(4), q)
    for k, leg in enumerate(robot.legs):
        assert np.allclose(feet[k], robot.hip_positions[k] + leg.fk(values[3 * k : 3 * k + 3]), atol=1e-12)
    names, positions = robot.names_from_q(q, names=leg_by_leg)
    assert names == tuple(leg_by_leg) and np.array_equal(positions, values)


def test_spot_answers_to_the_sdk_and_the_urdf_names(rng):
    spot = ROBOTS["spot"]
    sdk_names = [*spot.joint_names, *spot.arm_joint_names, *SDK_EXTRA]
    urdf_names = [*spot.urdf_joint_names[:12], *spot.urdf_joint_names[12:18], "arm_hr0", "arm_f1x"]
    assert spot.urdf_joint_names[18] == "arm_f1x"
    values = rng.uniform(-1, 1, len(sdk_names))
    from_sdk = spot.q_from_names(sdk_names, values)
    from_urdf = spot.q_from_names(urdf_names, values)
    assert np.array_equal(from_sdk, values[:12]) and np.array_equal(from_urdf, values[:12])
    arm = spot.q_from_names(urdf_names[::-1], values[::-1], joints=spot.arm_joint_names)
    assert np.array_equal(arm, values[12:18])
    # the same joints, named either way, give the same URDF-robot answer
    urdf_robot = ROBOTS["spot_urdf"]
    assert np.array_equal(urdf_robot.q_from_names(urdf_names, values), values[:12])
    # names_from_q keeps the names as the caller writes them
    names, positions = spot.names_from_q(from_sdk, names=urdf_names[:12])
    assert names == tuple(urdf_names[:12]) and np.array_equal(positions, values[:12])
    # one joint by both names is named twice
    with pytest.raises(ValueError, match=r"'fl\.hx' twice"):
        spot.q_from_names(["fl.hx", "front_left_hip_x"], [0.1, 0.2], missing="nan")


def test_joints_of_the_robot_outside_q_are_skipped(rng):
    spot = ROBOTS["spot"]
    names = ["arm0.f1x", *spot.joint_names, "arm0.hr0", "front_left_foot_joint"]
    values = rng.uniform(-1, 1, len(names))
    assert np.array_equal(spot.q_from_names(names, values), values[1:13])


@given(
    data=st.data(),
    key=st.sampled_from(sorted(ROBOTS)),
    batch=st.sampled_from([(), (1,), (3,), (2, 1, 2), (0,)]),
    float32=st.booleans(),
)
def test_subsets_and_extras_in_any_order_match_the_dictionary(data, key, batch, float32):
    robot = ROBOTS[key]
    joints = list(robot.leg_joint_names)
    given_joints = data.draw(st.lists(st.sampled_from(joints), unique=True, max_size=len(joints)))
    strangers = data.draw(st.lists(st.sampled_from(["lidar", "wheel", "x.y"]), unique=True, max_size=2))
    names = data.draw(st.permutations(given_joints + strangers))
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    positions = rng.uniform(-3, 3, (*batch, len(names))).astype(np.float32 if float32 else np.float64)
    q = robot.q_from_names(names, positions, missing="nan", unknown="ignore")
    assert q.shape == (*batch, len(joints))
    assert q.dtype == (np.float32 if float32 else np.float64)
    for index in np.ndindex(*batch):
        assert np.array_equal(q[index], by_dictionary(names, positions[index], joints), equal_nan=True)
    complete = len(given_joints) == len(joints)
    if not complete:
        with pytest.raises(ValueError, match="lacks the joints"):
            robot.q_from_names(names, positions, unknown="ignore")
    if strangers:
        with pytest.raises(ValueError, match="not a joint of this robot"):
            robot.q_from_names(names, positions, missing="nan")
    if complete and not strangers:
        back_names, back = robot.names_from_q(q, names=names)
        assert back_names == tuple(names) and np.array_equal(back, positions)


def test_nan_stays_in_its_joint_and_sample():
    go2 = ROBOTS["go2"]
    names = list(go2.leg_joint_names)
    positions = np.ones((3, 12))
    positions[1, 4] = np.nan
    q = go2.q_from_names(names[::-1], positions[:, ::-1])
    assert np.isnan(q).sum() == 1 and np.isnan(q[1, 4])


def test_layouts_non_contiguous_readonly_and_lists(rng):
    go2 = ROBOTS["go2"]
    names = list(go2.leg_joint_names)[::-1]
    base = rng.uniform(-1, 1, (4, 24))
    strided = base[:, ::2]
    strided.flags.writeable = False
    want = np.array([by_dictionary(names, row, go2.leg_joint_names) for row in strided])
    assert np.array_equal(go2.q_from_names(names, strided), want)
    assert np.array_equal(go2.q_from_names(names, np.asfortranarray(strided)), want)
    assert np.array_equal(go2.q_from_names(tuple(names), strided.tolist()), want)
    assert np.array_equal(go2.q_from_names(np.array(names), strided[0]), want[0])
    assert np.array_equal(
        go2.q_from_names(names, np.broadcast_to(strided[0], (5, 12))), np.tile(want[0], (5, 1))
    )
    ints = go2.q_from_names(names, np.arange(12))
    assert ints.dtype == np.float64 and np.array_equal(
        ints, by_dictionary(names, np.arange(12), go2.leg_joint_names)
    )


def test_names_from_q_is_the_inverse(rng):
    for robot in ROBOTS.values():
        q = rng.uniform(-1, 1, (2, 3, len(robot.leg_joint_names))).astype(np.float32)
        names, positions = robot.names_from_q(q)
        assert names == robot.leg_joint_names and positions.dtype == np.float32
        assert np.array_equal(positions, q) and not np.shares_memory(positions, q)
        subset = list(names[::3])
        picked_names, picked = robot.names_from_q(q, names=subset)
        assert picked_names == tuple(subset) and np.array_equal(picked, q[..., ::3])


def test_bad_input_is_named():
    go2 = ROBOTS["go2"]
    names = list(go2.leg_joint_names)
    with pytest.raises(ValueError, match=r"positions must have shape \(\.\.\., 12\), got \(11,\)"):
        go2.q_from_names(names, np.zeros(11))
    with pytest.raises(ValueError, match=r"names lacks the joints 'FL_hip_joint'"):
        go2.q_from_names(names[1:], np.zeros(11))
    with pytest.raises(ValueError, match=r"names: 'lidar' is not a joint of this robot"):
        go2.q_from_names([*names, "lidar"], np.zeros(13))
    with pytest.raises(ValueError, match="'FL_hip_joint' twice"):
        go2.q_from_names([*names, "FL_hip_joint"], np.zeros(13))
    with pytest.raises(TypeError, match="names must be a sequence of joint names"):
        go2.q_from_names("FL_hip_joint", np.zeros(1))
    with pytest.raises(TypeError, match="names must hold joint names"):
        go2.q_from_names([1, 2], np.zeros(2))
    with pytest.raises(TypeError, match="positions must be a real numeric array"):
        go2.q_from_names(names, np.zeros(12, dtype=complex))
    with pytest.raises(ValueError, match="missing must be one of"):
        go2.q_from_names(names, np.zeros(12), missing="zero")
    with pytest.raises(ValueError, match="unknown must be one of"):
        go2.q_from_names(names, np.zeros(12), unknown=None)
    with pytest.raises(ValueError, match=r"joints: 'arm0.sh0' is not a joint of this robot"):
        go2.q_from_names(names, np.zeros(12), joints=["arm0.sh0"])
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 12\)"):
        go2.names_from_q(np.zeros(13))
    with pytest.raises(ValueError, match="not a joint of q"):
        ROBOTS["spot"].names_from_q(np.zeros(12), names=["arm0.sh0"])
    with pytest.raises(ValueError, match="twice"):
        go2.names_from_q(np.zeros(12), names=["FL_hip_joint", "FL_hip_joint"])


def test_a_ros_joint_state_round_trip(rng):
    """As a ROS node would use it: a JointState-like message (name, position lists) both ways."""

    class JointState:  # the fields of sensor_msgs/JointState that matter here
        def __init__(self, name, position):
            self.name, self.position = list(name), list(position)

    spot = ROBOTS["spot"]
    q12 = rng.uniform(-1, 1, 12)
    q_arm = rng.uniform(-1, 1, 6)
    every = (*spot.joint_names, *spot.arm_joint_names)
    names, positions = spot.names_from_q(np.concatenate([q12, q_arm]), joints=every)
    message = JointState([*names, "arm0.f1x"], [*positions.tolist(), 0.3])
    assert np.array_equal(spot.q_from_names(message.name, message.position), q12)
    assert np.array_equal(
        spot.q_from_names(message.name, message.position, joints=spot.arm_joint_names), q_arm
    )
