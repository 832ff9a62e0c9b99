"""Legs by role (from the hips' geometry, whatever the URDF calls or orders them), joint-limit overrides
(``limits=``, ``with_limits``) reaching every limit-aware call, and the one width rule of the whole-body
calls (the legs' joints, or the legs' then the arm's)."""

from __future__ import annotations

import pathlib
import pickle

import numpy as np
import pytest

import spotkin as sk
from spotkin.model.robot import leg_roles

DATA = pathlib.Path(__file__).parent / "data"
SCRAMBLED = DATA / "go2_scrambled.urdf"
MOUNTED = DATA / "go2_z1_offset_mount.urdf"
QUAD_ROLES = ("front_left", "front_right", "hind_left", "hind_right")


# ---------------------------------------------------------------------------------------------- roles


def test_roles_of_the_builtin_robots():
    assert sk.Spot().leg_roles == QUAD_ROLES  # fl, fr, hl, hr
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    assert go2.leg_names == ("FL", "FR", "RL", "RR")
    assert go2.leg_roles == QUAD_ROLES
    spot_urdf = sk.Robot.from_urdf(sk.robots.path("spot_with_arm"))
    assert dict(zip(spot_urdf.leg_roles, spot_urdf.leg_names))["hind_right"] == "rear_right"


def test_roles_come_from_the_geometry_not_the_names_or_the_order():
    robot = sk.Robot.from_urdf(SCRAMBLED)
    assert robot.leg_names == ("leg_b", "leg_d", "leg_a", "leg_c")  # the file's order
    assert robot.leg_roles == ("hind_right", "hind_left", "front_right", "front_left")
    hips = robot.hip_positions
    for role, hip in zip(robot.leg_roles, hips):
        assert (hip[0] > 0) == role.startswith("front") and (hip[1] > 0) == role.endswith("left")
    # a leg by role is that leg
    assert robot.leg("front_left") is robot.legs[3] and robot.leg("leg_c") is robot.legs[3]
    with pytest.raises(ValueError, match="front_left"):
        robot.leg("front_middle")
    with pytest.raises(TypeError, match="name"):
        robot.leg(0)


def test_leg_order_roles_gives_the_same_q_on_every_robot(rng):
    scrambled = sk.Robot.from_urdf(SCRAMBLED, leg_order="roles")
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"), leg_order="roles")
    assert scrambled.leg_roles == go2.leg_roles == QUAD_ROLES
    assert scrambled.leg_names == ("leg_c", "leg_a", "leg_d", "leg_b")
    assert scrambled.leg_joint_names[:3] == ("leg_c_hip_joint", "leg_c_thigh_joint", "leg_c_calf_joint")
    # the same robot under other names: the same q gives the same feet
    pose = np.array([0.02, -0.01, 0.3, 0.05, -0.04, 0.1])
    q = np.concatenate([rng.uniform(*leg.limits.T, (5, 3)) for leg in go2.legs], axis=1)
    np.testing.assert_allclose(scrambled.body_fk(pose, q), go2.body_fk(pose, q), atol=1e-15)
    feet = go2.stance_feet(0.3)
    np.testing.assert_allclose(scrambled.body_ik(pose, feet).q, go2.body_ik(pose, feet).q, atol=1e-12)
    # and in the URDF's order, the roles permute the columns
    plain = sk.Robot.from_urdf(SCRAMBLED)
    order = [plain.leg_roles.index(role) for role in QUAD_ROLES]
    columns = np.concatenate([np.arange(3 * k, 3 * k + 3) for k in order])
    q_plain = np.empty_like(q)
    q_plain[:, columns] = q
    np.testing.assert_allclose(plain.body_fk(pose, q_plain)[:, order], go2.body_fk(pose, q), atol=1e-15)
    assert pickle.loads(pickle.dumps(scrambled)).leg_names == scrambled.leg_names
    with pytest.raises(ValueError, match="leg_order"):
        sk.Robot.from_urdf(SCRAMBLED, leg_order="alphabetical")


def test_roles_of_a_hexapod_and_odd_layouts():
    hips = np.array(
        [[0.3, 0.1, 0], [0.0, 0.12, 0], [-0.3, 0.1, 0], [0.3, -0.1, 0], [0.0, -0.12, 0], [-0.3, -0.1, 0]]
    )
    assert leg_roles(hips) == (
        "front_left",
        "middle_left",
        "hind_left",
        "front_right",
        "middle_right",
        "hind_right",
    )
    eight = np.array([[x, s * 0.1, 0] for s in (1, -1) for x in (0.3, 0.1, -0.1, -0.3)])
    assert leg_roles(eight)[:4] == ("front_left", "middle_1_left", "middle_2_left", "hind_left")
    assert leg_roles([[0, 0.1, 0], [0, -0.1, 0]]) == ("left", "right")
    assert leg_roles([[0.2, 0.0, 0], [-0.2, 0.0, 0]]) == ("front_center", "hind_center")


# --------------------------------------------------------------------------------------------- limits


def test_describe_warns_about_ranges_beyond_two_pi():
    text = sk.robots.text("go2").replace(
        'name="FL_calf_joint"', 'name="FL_calf_joint"', 1
    )  # Go2's own ranges are below 2 pi: no warning
    assert "wider than 2π" not in sk.Robot.from_urdf_string(text).describe()
    wide = _with_range(sk.robots.text("go2"), "FL_thigh_joint", -9.42, 9.42)
    note = [line for line in sk.Robot.from_urdf_string(wide).describe().splitlines() if "2π" in line]
    assert len(note) == 1 and "FL_thigh_joint" in note[0] and "limits=" in note[0]
    narrowed = sk.Robot.from_urdf_string(wide, limits={"FL_thigh_joint": (-1.5, 3.4)})
    assert "wider than 2π" not in narrowed.describe()


def _with_range(text, joint, lower, upper):
    start = text.index(f'name="{joint}"')
    at = text.index("<limit", start)
    end = text.index("/>", at)
    return text[:at] + f'<limit lower="{lower}" upper="{upper}" effort="20" velocity="30"' + text[end:]


def test_limits_reach_the_leg_ik_and_its_fallback():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    leg = go2.leg("FL")
    q = np.array([0.0, 0.9, -1.6])
    p = leg.fk(q)
    assert leg.ik(p)[1] == sk.Status.OK
    tight = go2.with_limits({"FL_calf_joint": (-1.5, -0.9)})  # the knee cannot bend to -1.6
    assert tight is not go2 and go2.leg("FL").limits[2, 0] < -2.0  # the original is unchanged
    np.testing.assert_array_equal(tight.leg("FL").limits[2], [-1.5, -0.9])
    assert tight.leg("FL").ik(p)[1] == sk.Status.JOINT_LIMIT
    # an unreachable target's fallback is the nearest configuration inside the new limits
    q_far, status = tight.leg("FL").ik(p * 3.0)
    assert status == sk.Status.UNREACHABLE
    assert -1.5 - 1e-12 <= q_far[2] <= -0.9 + 1e-12
    assert not -1.5 <= leg.ik(p * 3.0)[0][2] <= -0.9  # the original's fallback is outside them
    res = tight.body_ik([0.0, 0.0, 0.3, 0, 0, 0], go2.body_fk([0.0, 0.0, 0.3, 0, 0, 0], np.tile(q, 4)))
    assert res.status[0] != sk.Status.OK and (res.status[1:] == sk.Status.OK).all()
    # the same through from_urdf, through pickling, and combined with a later override
    again = sk.Robot.from_urdf(sk.robots.path("go2"), limits={"FL_calf_joint": (-1.5, -0.9)})
    np.testing.assert_array_equal(again.leg("FL").limits, tight.leg("FL").limits)
    restored = pickle.loads(pickle.dumps(tight))
    np.testing.assert_array_equal(restored.leg("FL").limits, tight.leg("FL").limits)
    both = tight.with_limits({"FR_calf_joint": (-2.0, -1.0)})
    np.testing.assert_array_equal(both.leg("FL").limits[2], [-1.5, -0.9])
    np.testing.assert_array_equal(both.leg("FR").limits[2], [-2.0, -1.0])
    assert "[-1.5, -0.9]" in both.describe()


def test_limits_reach_the_arm_and_the_workspace():
    robot = sk.Robot.from_urdf(MOUNTED)
    narrow = robot.with_limits({"z1_joint1": (-0.5, 0.5)})
    np.testing.assert_array_equal(narrow.arm.lower[0], -0.5)
    q = np.array([1.0, 1.0, -1.0, 0.2, 0.1, 0.3])
    T = robot.arm.fk(q)
    assert robot.arm.ik(T, q)[1] == sk.Status.OK
    _, status = narrow.arm.ik(T, q)
    assert status != sk.Status.OK
    assert bool(np.isfinite(robot.arm.ik_all(T).q).any())
    sols = narrow.arm.ik_all(T)
    assert not sols.valid[np.isfinite(sols.q).all(-1) & (np.abs(sols.q[..., 0]) > 0.5)].any()
    leg = robot.leg("FL")
    tight = robot.with_limits(
        {"FL_hip_joint": (-0.01, 0.01), "FL_thigh_joint": (0.5, 0.6), "FL_calf_joint": (-1.6, -1.5)}
    )
    volume_tight = sk.workspace_volume(tight.leg("FL"), n=20_000, seed=1)[0]
    assert 0 < volume_tight < 0.2 * sk.workspace_volume(leg, n=20_000, seed=1)[0]


def test_chain_with_limits(rng):
    chain = sk.Robot.from_urdf(MOUNTED).arm
    by_name = chain.with_limits({"z1_joint2": (0.1, 0.2)})
    by_index = chain.with_limits({1: (0.1, 0.2)})
    table = np.c_[chain.lower, chain.upper]
    table[1] = (0.1, 0.2)
    by_table = chain.with_limits(table)
    for c in (by_name, by_index, by_table):
        np.testing.assert_array_equal(np.c_[c.lower, c.upper], table)
        assert c.joint_names == chain.joint_names and c.inertials is chain.inertials
    np.testing.assert_array_equal(chain.lower[1], 0.0)  # unchanged
    restored = pickle.loads(pickle.dumps(by_name))
    np.testing.assert_array_equal(restored.lower, by_name.lower)
    q = np.array([0.3, 1.0, -1.0, 0.2, 0.1, 0.3])
    sols = by_name.ik_all(chain.fk(q))
    assert not sols.valid[
        np.isfinite(sols.q).all(-1) & ((sols.q[..., 1] < 0.1) | (sols.q[..., 1] > 0.2))
    ].any()
    with pytest.raises(ValueError, match="nope"):
        chain.with_limits({"nope": (0, 1)})
    with pytest.raises(ValueError, match="lower <= upper"):
        chain.with_limits({0: (1.0, 0.0)})
    with pytest.raises(ValueError, match="out of range"):
        chain.with_limits({6: (0.0, 1.0)})
    with pytest.raises(ValueError, match="shape"):
        chain.with_limits(np.zeros((5, 2)))
    with pytest.raises(TypeError):
        chain.with_limits({"z1_joint1": "wide"})


def test_spot_with_limits_by_sdk_names():
    spot = sk.Spot()
    knee = spot.with_limits({"fl.kn": (-2.0, -1.0), "arm0.sh0": (-1.0, 1.0)})
    np.testing.assert_array_equal(knee.leg("fl").limits[2], [-2.0, -1.0])
    np.testing.assert_array_equal(knee.arm.limits[0], [-1.0, 1.0])
    np.testing.assert_array_equal(knee.leg("fr").limits, spot.leg("fr").limits)
    by_urdf = spot.with_limits({"front_left_knee": (-2.0, -1.0)})
    np.testing.assert_array_equal(by_urdf.leg("fl").limits[2], [-2.0, -1.0])
    restored = pickle.loads(pickle.dumps(knee))
    np.testing.assert_array_equal(restored.leg("fl").limits[2], [-2.0, -1.0])
    with pytest.raises(ValueError, match="not a moving joint"):
        spot.with_limits({"fl.foot": (0, 1)})
    with pytest.raises(TypeError, match="limits"):
        spot.with_limits([(0, 1)])


# ---------------------------------------------------------------------------------------- width rule


@pytest.mark.parametrize("name", ["spot", "mounted"])
def test_every_whole_body_call_takes_legs_or_legs_and_arm(name, rng):
    robot = sk.Spot() if name == "spot" else sk.Robot.from_urdf(MOUNTED)
    n = 3 * robot.n_legs
    pose = np.array([0.01, 0.02, 0.3, 0.03, -0.02, 0.05])
    feet = robot.body_fk(
        pose, robot.body_ik(pose, robot.stance_feet(0.3) if name == "mounted" else robot.stance_feet()).q
    )
    q_legs = robot.body_ik(pose, feet).q
    q_arm = np.array([0.2, 0.8, -0.9, 0.1, 0.3, -0.2])
    q_all = np.r_[q_legs, q_arm]
    np.testing.assert_array_equal(robot.body_fk(pose, q_all), robot.body_fk(pose, q_legs))
    J = robot.body_jacobian(pose, q_all)
    assert J.shape == (n, 6 + n + 6)
    np.testing.assert_array_equal(J[:, : 6 + n], robot.body_jacobian(pose, q_legs))
    assert not J[:, 6 + n :].any()
    frames = robot.fk_all(pose, q_all)
    np.testing.assert_array_equal(frames.hand, robot.fk_all(pose, q_legs, q_arm).hand)
    with pytest.raises(ValueError, match="q_arm must be None"):
        robot.fk_all(pose, q_all, q_arm)
    twist = np.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.2])
    rates = robot.body_rates(pose, q_all, twist)
    assert rates.qd.shape == (n + 6,)
    np.testing.assert_array_equal(rates.qd[:n], robot.body_rates(pose, q_legs, twist).qd)
    np.testing.assert_array_equal(rates.qd[n:], 0.0)
    assert np.isnan(robot.body_rates(pose, np.r_[q_legs, np.full(6, np.nan)], twist).qd[n:]).all()
    np.testing.assert_array_equal(
        robot.body_ik(pose, feet, seed=q_all).q, robot.body_ik(pose, feet, seed=q_legs).q
    )
    assert robot.center_of_mass(pose, q_all).shape == (3,)
    assert robot.standing_torques(pose, q_all).tau.shape == (n,)
    assert robot.floating_q(pose, q_all).shape == (7 + n + 6,)
    for call in (
        lambda q: robot.body_fk(pose, q),
        lambda q: robot.body_jacobian(pose, q),
        lambda q: robot.body_rates(pose, q, twist),
        lambda q: robot.fk_all(pose, q),
        lambda q: robot.body_ik(pose, feet, seed=q),
        lambda q: robot.center_of_mass(pose, q),
        lambda q: robot.standing_torques(pose, q),
    ):
        with pytest.raises(ValueError, match=rf"\(\.\.\., {n}\) or \(\.\.\., {n + 6}\)"):
            call(np.zeros(n + 3))
