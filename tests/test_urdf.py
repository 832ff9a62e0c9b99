"""spotkin.urdf: parser, tree utilities, leg/arm recognition; Pinocchio as an independent oracle."""

from __future__ import annotations

import math
import time
from functools import cache
from pathlib import Path

import numpy as np
import pinocchio  # the independent oracle (requirements-test.txt: pin); never skipped
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from urdf_helpers import LIMIT, joint_xml, pin_q
from urdf_helpers import joint as urdf_joint

import spotkin.urdf as su
from spotkin.reference import urdf as ref
from spotkin.urdf import (
    ArmSpec,
    ChainData,
    Inertial,
    LegSpec,
    Model,
    describe,
    find_arms,
    find_legs,
    load_urdf,
    parse_urdf,
)
from spotkin.urdf.tree import _motion, _rpy

SPOT = Path(su.__file__).resolve().parent.parent / "robots" / "spot_with_arm.urdf"
GO2 = Path(__file__).resolve().parent / "data" / "go2.urdf"
PI = "3.141592653589793"
HALF_PI = "1.5707963267948966"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261202)


@cache
def spot() -> Model:
    return load_urdf(SPOT)


@cache
def go2() -> Model:
    return load_urdf(GO2)


# --------------------------------------------------------------------------- small URDFs

# One leg whose joint frames are rotated (yaw 90°, roll 180°, yaw 180°), with a negative and
# an unnormalised axis, fixed joints between and after the moving ones, offsets along all
# three axes at every joint, and two rotors hanging off (one fixed, one continuous).
TWISTED = f"""<?xml version="1.0"?>
<robot name="twisted">
  <link name="trunk">
    <inertial>
      <origin xyz="0.01 0.02 0.03" rpy="0.1 0.2 0.3"/>
      <mass value="5"/>
      <inertia ixx="0.1" ixy="0.01" ixz="0" iyy="0.2" iyz="0" izz="0.3"/>
    </inertial>
    <visual><geometry><mesh filename="package://nowhere/trunk.dae"/></geometry></visual>
    <collision><geometry><box size="1 1 1"/></geometry></collision>
  </link>
  <link name="hip"/>
  <link name="hip_mount"/>
  <link name="thigh"/>
  <link name="shank"/>
  <link name="toe"/>
  <link name="knee_rotor"/>
  <link name="hip_rotor"/>
  <joint name="L_roll" type="revolute">
    <parent link="trunk"/><child link="hip"/>
    <origin xyz="0.3 0.12 -0.02" rpy="0 0 {HALF_PI}"/>
    <axis xyz="0 -2 0"/>
    <limit lower="-1" upper="1" {LIMIT}/>
  </joint>
  <joint name="L_mount" type="fixed">
    <parent link="hip"/><child link="hip_mount"/>
    <origin xyz="0.01 0.02 0.03" rpy="0 0 -{HALF_PI}"/>
  </joint>
  <joint name="L_pitch" type="revolute">
    <parent link="hip_mount"/><child link="thigh"/>
    <origin xyz="0.02 0.08 -0.01" rpy="{PI} 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" {LIMIT}/>
  </joint>
  <joint name="L_knee" type="revolute">
    <parent link="thigh"/><child link="shank"/>
    <origin xyz="0.03 -0.01 0.25" rpy="0 0 {PI}"/>
    <axis xyz="0 0.5 0"/>
    <limit lower="0.2" upper="2.6" {LIMIT}/>
  </joint>
  <joint name="L_toe" type="fixed">
    <parent link="shank"/><child link="toe"/>
    <origin xyz="0.01 0.02 0.28" rpy="0.3 0.2 0.1"/>
  </joint>
  <joint name="L_knee_rotor" type="fixed">
    <parent link="thigh"/><child link="knee_rotor"/>
    <origin xyz="0 0.03 0"/>
    <axis xyz="0 0 0"/>
  </joint>
  <joint name="hip_rotor_spin" type="continuous">
    <parent link="trunk"/><child link="hip_rotor"/>
    <origin xyz="0.2 0.1 0"/>
    <axis xyz="1 0 0"/>
  </joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type></transmission>
  <gazebo reference="toe"><mu1>0.9</mu1></gazebo>
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
</robot>
"""
TWISTED_GEOMETRY = {
    "hip_origin": (0.3, 0.12, -0.02),
    "a": (0.0, 0.09, 0.02),
    "b": (0.03, 0.01, -0.25),
    "c": (-0.01, 0.02, -0.28),
    "signs": (1.0, -1.0, 1.0),
}

# FL: continuous hip and thigh with negative axes, a knee with limits wider than 2π and a
# second leaf (a sensor) under the same joints. HL: a forward-bending knee. Plus a prismatic
# slider with a camera, and a continuous rotor off a hip.
SPINNER = f"""<robot name="spinner">
  <link name="base"/>
  <link name="FL_hip"/><link name="FL_thigh"/><link name="FL_calf"/><link name="FL_foot"/>
  <link name="FL_shin_sensor"/><link name="FL_rotor"/>
  <link name="HL_hip"/><link name="HL_thigh"/><link name="HL_calf"/><link name="HL_foot"/>
  <link name="slider"/><link name="camera"/>
  <joint name="FL_hip_joint" type="continuous">
    <parent link="base"/><child link="FL_hip"/>
    <origin xyz="0.2 0.05 0.01"/><axis xyz="-1 0 0"/>
  </joint>
  <joint name="FL_thigh_joint" type="continuous">
    <parent link="FL_hip"/><child link="FL_thigh"/>
    <origin xyz="0.01 0.08 -0.02"/><axis xyz="0 -3 0"/>
    <limit lower="-1" upper="1" {LIMIT}/>
  </joint>
  <joint name="FL_calf_joint" type="revolute">
    <parent link="FL_thigh"/><child link="FL_calf"/>
    <origin xyz="-0.02 0.01 -0.2"/><axis xyz="0 1 0"/>
    <limit lower="-7" upper="7" {LIMIT}/>
  </joint>
  <joint name="FL_foot_joint" type="fixed">
    <parent link="FL_calf"/><child link="FL_foot"/>
    <origin xyz="0.03 -0.01 -0.22"/>
  </joint>
  <joint name="FL_sensor_joint" type="fixed">
    <parent link="FL_calf"/><child link="FL_shin_sensor"/>
    <origin xyz="0 0 -0.3"/>
  </joint>
  <joint name="FL_rotor_joint" type="continuous">
    <parent link="FL_hip"/><child link="FL_rotor"/>
    <origin xyz="0 0.02 0"/><axis xyz="0 1 0"/>
  </joint>
  <joint name="HL_hip_joint" type="revolute">
    <parent link="base"/><child link="HL_hip"/>
    <origin xyz="-0.2 0.05 0.0"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" {LIMIT}/>
  </joint>
  <joint name="HL_thigh_joint" type="revolute">
    <parent link="HL_hip"/><child link="HL_thigh"/>
    <origin xyz="0 0.08 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" {LIMIT}/>
  </joint>
  <joint name="HL_calf_joint" type="revolute">
    <parent link="HL_thigh"/><child link="HL_calf"/>
    <origin xyz="0 0 -0.2"/><axis xyz="0 1 0"/>
    <limit lower="0.1" upper="2.7" {LIMIT}/>
  </joint>
  <joint name="HL_foot_joint" type="fixed">
    <parent link="HL_calf"/><child link="HL_foot"/>
    <origin xyz="0.06 0 -0.2"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="base"/><child link="slider"/>
    <origin xyz="0.1 0 0.1" rpy="0.2 -0.3 0.4"/><axis xyz="0 0 2"/>
    <limit lower="-0.1" upper="0.1" {LIMIT}/>
  </joint>
  <joint name="camera_joint" type="fixed">
    <parent link="slider"/><child link="camera"/>
    <origin xyz="0.01 0.02 0.03" rpy="0 0.5 0"/>
  </joint>
</robot>
"""


def leg3(
    prefix: str,
    axes=("1 0 0", "0 1 0", "0 1 0"),
    origins=("0.2 0.05 0", "0 0.08 0", "0 0 -0.2"),
    foot="0 0 -0.2",
    parent="base",
    foot_name=None,
) -> str:
    """Links and joints of one three-joint leg, as URDF text (no <robot> element)."""
    names = [f"{prefix}_{k}" for k in ("hip", "thigh", "calf")]
    foot_name = foot_name or f"{prefix}_foot"
    out = [f'<link name="{n}"/>' for n in [*names, foot_name]]
    links = [parent, *names]
    for k in range(3):
        body = f'<origin xyz="{origins[k]}"/><axis xyz="{axes[k]}"/><limit lower="-1" upper="1" {LIMIT}/>'
        out.append(joint_xml(f"{names[k]}_joint", "revolute", links[k], names[k], body))
    out.append(joint_xml(f"{prefix}_foot_joint", "fixed", names[2], foot_name, f'<origin xyz="{foot}"/>'))
    return "\n".join(out)


def robot(*parts: str, name: str = "r", base: str = "base") -> str:
    return f'<robot name="{name}"><link name="{base}"/>' + "\n".join(parts) + "</robot>"


# A UR5-like arm (no spherical wrist), a prismatic finger as a 7th joint and a pan-tilt head.
UR_ARM = f"""<robot name="ur">
  <link name="base_link"/>
  <link name="shoulder"/><link name="upper_arm"/><link name="forearm"/>
  <link name="wrist_1"/><link name="wrist_2"/><link name="wrist_3"/>
  <link name="ee_link"/><link name="tool0"/><link name="finger"/>
  <link name="pan"/><link name="tilt"/>
  <joint name="shoulder_pan" type="revolute"><parent link="base_link"/><child link="shoulder"/>
    <origin xyz="0 0 0.089"/><axis xyz="0 0 1"/><limit lower="-6.3" upper="6.3" {LIMIT}/></joint>
  <joint name="shoulder_lift" type="revolute"><parent link="shoulder"/><child link="upper_arm"/>
    <origin xyz="0 0.136 0"/><axis xyz="0 1 0"/><limit lower="-6.3" upper="6.3" {LIMIT}/></joint>
  <joint name="elbow" type="revolute"><parent link="upper_arm"/><child link="forearm"/>
    <origin xyz="0 -0.12 0.425"/><axis xyz="0 1 0"/><limit lower="-3.1" upper="3.1" {LIMIT}/></joint>
  <joint name="wrist_1_joint" type="revolute"><parent link="forearm"/><child link="wrist_1"/>
    <origin xyz="0 0 0.392"/><axis xyz="0 1 0"/><limit lower="-6.3" upper="6.3" {LIMIT}/></joint>
  <joint name="wrist_2_joint" type="revolute"><parent link="wrist_1"/><child link="wrist_2"/>
    <origin xyz="0 0.093 0"/><axis xyz="0 0 1"/><limit lower="-6.3" upper="6.3" {LIMIT}/></joint>
  <joint name="wrist_3_joint" type="revolute"><parent link="wrist_2"/><child link="wrist_3"/>
    <origin xyz="0 0 0.095"/><axis xyz="0 1 0"/><limit lower="-6.3" upper="6.3" {LIMIT}/></joint>
  <joint name="ee_fixed" type="fixed"><parent link="wrist_3"/><child link="ee_link"/>
    <origin xyz="0 0.082 0" rpy="0 0 {HALF_PI}"/></joint>
  <joint name="tool_fixed" type="fixed"><parent link="ee_link"/><child link="tool0"/>
    <origin xyz="0.01 0 0" rpy="-{HALF_PI} 0 0"/></joint>
  <joint name="finger_joint" type="prismatic"><parent link="wrist_3"/><child link="finger"/>
    <origin xyz="0 0.1 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.04" {LIMIT}/></joint>
  <joint name="head_pan" type="continuous"><parent link="base_link"/><child link="pan"/>
    <origin xyz="0.1 0 0.2"/><axis xyz="0 0 1"/></joint>
  <joint name="head_tilt" type="revolute"><parent link="pan"/><child link="tilt"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" {LIMIT}/></joint>
</robot>
"""


# A z-y-y leg, a good leg, a leg with no x/z offset hip-pitch -> knee, one with none knee -> foot.
NON_RPP = robot(
    leg3("yaw", axes=("0 0 1", "0 1 0", "0 1 0")),
    leg3("good", origins=("-0.2 0.05 0", "0 0.08 0", "0 0 -0.2")),
    leg3("flat", origins=("0.2 -0.05 0", "0 -0.08 0", "0 -0.1 0")),
    leg3("short", origins=("-0.2 -0.05 0", "0 -0.08 0", "0 0 -0.2"), foot="0 -0.05 0"),
)

# --------------------------------------------------------------------------- helpers


def random_values(model: Model, rng: np.random.Generator) -> dict[str, float]:
    out = {}
    for j in model.actuated_joints:
        if j.type == "prismatic":
            out[j.name] = float(rng.uniform(-0.3, 0.3))
        else:
            out[j.name] = float(rng.uniform(-4.0, 4.0))
    return out


def check_against_pinocchio(model: Model, pm, values: dict[str, float], jacobians: bool = True) -> None:
    """Every link frame (and the Jacobian of every leaf) against Pinocchio."""
    pd = pm.createData()
    q = pin_q(pm, values)
    pinocchio.framesForwardKinematics(pm, pd, q)
    for link in model.links:
        cd = model.chain_data(link)
        qc = [values[n] for n in cd.joint_names]
        T = ref.chain_fk(cd, qc)
        fid = pm.getFrameId(link, pinocchio.FrameType.BODY)
        np.testing.assert_allclose(T, pd.oMf[fid].homogeneous, rtol=0, atol=1e-12, err_msg=link)
        np.testing.assert_allclose(model.placement(link, values), T, rtol=0, atol=1e-12, err_msg=link)
    if not jacobians:
        return
    for link in model.leaves:
        cd = model.chain_data(link)
        qc = [values[n] for n in cd.joint_names]
        J = ref.chain_jacobian(cd, qc)
        fid = pm.getFrameId(link, pinocchio.FrameType.BODY)
        Jp = pinocchio.computeFrameJacobian(pm, pd, q, fid, pinocchio.LOCAL_WORLD_ALIGNED)
        cols = [pm.joints[pm.getJointId(n)].idx_v for n in cd.joint_names]
        np.testing.assert_allclose(J, Jp[:, cols], rtol=0, atol=1e-12, err_msg=link)
        others = np.delete(Jp, cols, axis=1)
        np.testing.assert_allclose(others, 0.0, atol=0, err_msg=link)


@cache
def pin_spot():
    return pinocchio.buildModelFromUrdf(str(SPOT))


def foot_point(model: Model, leg: LegSpec, values) -> np.ndarray:
    cd = model.chain_data(leg.foot)
    T = ref.chain_fk(cd, values)
    return T[:3, :3] @ leg.contact_offset + T[:3, 3] - leg.hip_origin


def check_legs_poe(model: Model, legs, rng, samples: int = 30) -> None:
    """(R1) from the LegSpec equals the URDF chain, translated by the hip origin."""
    for leg in legs:
        assert model.chain_data(leg.foot).joint_names == leg.joint_names
        for _ in range(samples):
            q = rng.uniform(-4, 4, 3)
            np.testing.assert_allclose(
                ref.rpp_leg_fk(leg, q), foot_point(model, leg, q), rtol=0, atol=1e-12, err_msg=leg.name
            )


# --------------------------------------------------------------------------- parser: Spot and Go2


def test_spot_joints_limits_and_order():
    m = spot()
    assert m.name == "spot" and m.root == "body"
    assert repr(m) == "Model(name='spot', 26 links, 25 joints (19 actuated), root='body')"
    act = m.actuated_joints
    assert len(act) == 19
    assert [j.index for j in act] == list(range(19))
    assert all(j.index == -1 for j in m.joints if j.type == "fixed")
    legs = ["front_left", "front_right", "rear_left", "rear_right"]
    expected = [f"{leg}_{k}" for leg in legs for k in ("hip_x", "hip_y", "knee")]
    expected += ["arm_sh0", "arm_sh1", "arm_el0", "arm_el1", "arm_wr0", "arm_wr1", "arm_f1x"]
    assert [j.name for j in act] == expected
    knees = [m.joint(f"{leg}_knee").upper for leg in legs]
    assert knees == [-0.254801, -0.247563, -0.267153, -0.257725]
    hx = m.joint("front_left_hip_x")
    assert hx.lower == -0.78539816339744827899 and hx.upper == 0.78539816339744827899
    assert hx.effort == 45.0 and hx.velocity == 17.647
    assert hx.parent == "body" and hx.child == "front_left_hip"
    np.testing.assert_array_equal(hx.axis, [1, 0, 0])
    np.testing.assert_array_equal(hx.origin[:3, 3], [0.29785, 0.055, 0.0])
    assert m.joint("arm_hr0").axis is None
    assert list(m.links)[:3] == ["body", "front_left_hip", "front_left_upper_leg"]


def test_spot_inertial_rotated_into_link_frame():
    link = spot().link("front_left_hip")
    inertial = link.inertial
    assert inertial.mass == 1.68
    R = ref.rpy_matrix(-0.716521349312305, 0.02956473059648479, 0.03655230014702582)
    diag = np.diag([0.0021147398873455382, 0.0018129577956607131, 0.002265435737304666])
    np.testing.assert_allclose(inertial.rotation, R, atol=1e-15)
    np.testing.assert_allclose(inertial.inertia, R @ diag @ R.T, atol=1e-15)
    np.testing.assert_array_equal(
        inertial.com, [-0.005374345928430557, 0.012841847725212574, 9.875232353806496e-05]
    )
    assert spot().link("front_left_foot").inertial is None
    with pytest.raises(ValueError, match="read-only"):
        inertial.inertia[0, 0] = 1.0


def test_go2_parses_with_encoding_declaration_and_zero_fixed_axes():
    m = go2()
    assert m.root == "base"
    assert len(m.actuated_joints) == 12
    assert [j.name for j in m.actuated_joints] == [
        f"{leg}_{k}_joint" for leg in ("FL", "FR", "RL", "RR") for k in ("hip", "thigh", "calf")
    ]
    radar = m.joint("radar_joint")
    assert radar.type == "fixed" and radar.axis is None
    np.testing.assert_allclose(radar.origin[:3, :3], ref.rpy_matrix(0, 2.8782, 0), atol=1e-15)
    assert m.joint("RL_thigh_joint").lower == -0.5236 and m.joint("RL_thigh_joint").upper == 4.5379
    assert "FL_hip_rotor" in m.links and "FL_hip_rotor" in m.leaves
    assert m.parent_joint("FL_calf_rotor").parent == "FL_thigh"
    # Same result from text and from bytes (the file declares encoding='utf-8').
    text = GO2.read_text(encoding="utf-8")
    assert [j.name for j in parse_urdf(text).joints] == [j.name for j in m.joints]
    assert len(parse_urdf(GO2.read_bytes()).links) == len(m.links)


def test_load_time_is_small():
    for path in (SPOT, GO2):
        best = math.inf
        for _ in range(5):
            t0 = time.perf_counter()
            load_urdf(path)
            best = min(best, time.perf_counter() - t0)
        assert best < 0.05, (path.name, best)


def test_encoding_declaration_in_bytes():
    text = "<?xml version='1.0' encoding='latin-1'?>\n<robot name=\"ü\"><link name=\"é\"/></robot>"
    m = parse_urdf(text.encode("latin-1"))
    assert m.name == "ü" and "é" in m.links


def test_tree_utilities():
    m = parse_urdf(TWISTED)
    assert m.root == "trunk"
    assert m.leaves == ("toe", "knee_rotor", "hip_rotor")
    assert m.parent_joint("trunk") is None
    assert m.parent_joint("toe").name == "L_toe"
    assert [j.name for j in m.children("thigh")] == ["L_knee", "L_knee_rotor"]
    assert [j.name for j in m.children("trunk")] == ["L_roll", "hip_rotor_spin"]
    assert [j.name for j in m.path("toe")] == ["L_roll", "L_mount", "L_pitch", "L_knee", "L_toe"]
    assert [j.name for j in m.path("toe", base="thigh")] == ["L_knee", "L_toe"]
    assert m.path("trunk") == ()
    with pytest.raises(ValueError, match="'hip_rotor' is not below link 'thigh'"):
        m.path("hip_rotor", base="thigh")
    with pytest.raises(ValueError, match="unknown link 'nope'"):
        m.placement("nope")
    with pytest.raises(ValueError, match="unknown joint 'nope'"):
        m.joint("nope")
    with pytest.raises(ValueError, match="'L_toe' is fixed"):
        m.placement("toe", {"L_toe": 1.0})
    assert [j.name for j in m.actuated_joints] == ["L_roll", "L_pitch", "L_knee", "hip_rotor_spin"]
    assert m.joint("hip_rotor_spin").lower == -math.inf and m.joint("hip_rotor_spin").upper == math.inf
    np.testing.assert_allclose(m.joint("L_roll").axis, [0, -1, 0])
    np.testing.assert_allclose(m.joint("L_knee").axis, [0, 1, 0])
    # The trunk's inertia is rotated into the link frame.
    inertial = m.link("trunk").inertial
    R = ref.rpy_matrix(0.1, 0.2, 0.3)
    local = np.array([[0.1, 0.01, 0], [0.01, 0.2, 0], [0, 0, 0.3]])
    np.testing.assert_allclose(inertial.inertia, R @ local @ R.T, atol=1e-15)
    np.testing.assert_allclose(inertial.com, [0.01, 0.02, 0.03])


def test_chain_data_merges_fixed_joints():
    m = parse_urdf(TWISTED)
    cd = m.chain_data("toe")
    assert isinstance(cd, ChainData)
    assert cd.joint_names == ("L_roll", "L_pitch", "L_knee") and cd.n == 3
    assert cd.base == "trunk" and cd.tip == "toe"
    j = {x.name: x for x in m.joints}
    np.testing.assert_allclose(cd.placements[0], j["L_roll"].origin)
    np.testing.assert_allclose(cd.placements[1], j["L_mount"].origin @ j["L_pitch"].origin)
    np.testing.assert_allclose(cd.placements[2], j["L_knee"].origin)
    np.testing.assert_allclose(cd.tool, j["L_toe"].origin)
    np.testing.assert_array_equal(cd.types, [0, 0, 0])
    assert cd.types.dtype == np.int8
    np.testing.assert_array_equal(cd.limits, [[-1, 1], [-2, 2], [0.2, 2.6]])
    np.testing.assert_array_equal(cd.continuous, [False, False, False])
    np.testing.assert_allclose(np.linalg.norm(cd.axes, axis=1), 1.0)
    np.testing.assert_allclose(ref.chain_fk(cd, [0, 0, 0]), m.placement("toe"), atol=1e-15)
    frames = ref.chain_frames(cd, [0.1, 0.2, 0.3])
    assert frames.shape == (5, 4, 4)
    np.testing.assert_array_equal(frames[0], np.eye(4))
    np.testing.assert_allclose(frames[2], m.placement("thigh", {"L_roll": 0.1, "L_pitch": 0.2}), atol=1e-15)
    # A sub-chain from an inner base.
    sub = m.chain_data("toe", base="hip")
    assert sub.joint_names == ("L_pitch", "L_knee") and sub.base == "hip"
    np.testing.assert_allclose(
        m.placement("hip", {"L_roll": 0.4}) @ ref.chain_fk(sub, [0.2, 0.3]),
        m.placement("toe", {"L_roll": 0.4, "L_pitch": 0.2, "L_knee": 0.3}),
        atol=1e-15,
    )
    # No actuated joint: n = 0, the tool is the placement.
    none = go2().chain_data("radar")
    assert none.n == 0 and none.placements.shape == (0, 4, 4) and none.axes.shape == (0, 3)
    np.testing.assert_allclose(none.tool, go2().placement("radar"))
    np.testing.assert_allclose(ref.chain_fk(none, []), none.tool)
    assert ref.chain_jacobian(none, []).shape == (6, 0)
    with pytest.raises(ValueError, match="read-only"):
        cd.placements[0, 0, 0] = 2.0
    # Continuous and prismatic joints.
    spinner = parse_urdf(SPINNER)
    cd = spinner.chain_data("FL_foot")
    np.testing.assert_array_equal(cd.continuous, [True, True, False])
    np.testing.assert_array_equal(cd.limits, [[-np.inf, np.inf], [-np.inf, np.inf], [-7, 7]])
    cam = spinner.chain_data("camera")
    np.testing.assert_array_equal(cam.types, [1])
    np.testing.assert_allclose(cam.axes, [[0, 0, 1]])


def test_reference_rotations():
    rng = np.random.default_rng(1)
    for _ in range(20):
        r, p, y = rng.uniform(-3, 3, 3)
        R = ref.rpy_matrix(r, p, y)
        expected = ref.axis_angle_matrix([0, 0, 1], y) @ ref.axis_angle_matrix([0, 1, 0], p) @ ref.rot_x(r)
        np.testing.assert_allclose(R, expected, atol=1e-15)
        np.testing.assert_allclose(_rpy(r, p, y), R, atol=1e-15)
        axis = rng.normal(size=3)
        angle = rng.uniform(-4, 4)
        A = ref.axis_angle_matrix(axis, angle)
        np.testing.assert_allclose(A @ A.T, np.eye(3), atol=1e-14)
        np.testing.assert_allclose(A @ axis, axis, atol=1e-14)
        np.testing.assert_allclose(ref.axis_angle_matrix(3 * axis, angle), A, atol=1e-15)
        np.testing.assert_allclose(ref.axis_angle_matrix(-axis, -angle), A, atol=1e-15)
    np.testing.assert_allclose(ref.axis_angle_matrix([0, 1, 0], 0.7), ref.rot_y(0.7), atol=1e-15)


def test_mimic_joint_follows_its_leader():
    text = robot(
        '<link name="a"/><link name="b"/>',
        f'<joint name="j1" type="revolute"><parent link="base"/><child link="a"/><limit lower="-1" upper="1" '
        f"{LIMIT}/></joint>",
        f'<joint name="j2" type="revolute"><parent link="a"/><child link="b"/><limit lower="-1" upper="1" '
        f'{LIMIT}/><mimic joint="j1" multiplier="2" offset="0.1"/></joint>',
    )
    m = parse_urdf(text)
    assert [j.name for j in m.actuated_joints] == ["j1"]  # a mimic joint is no independent variable
    assert [j.name for j in m.mimic_joints] == ["j2"]
    assert (m.joint("j2").mimic, m.joint("j2").multiplier, m.joint("j2").offset) == ("j1", 2.0, 0.1)
    assert m.joint("j1").index == 0 and m.joint("j2").index == -1
    data = m.chain_data("b")
    assert data.n == 2 and data.mimic == (None, ("j1", 2.0, 0.1))  # the full chain, mimic included
    # placement: j2 = 2 * 0.3 + 0.1 about x
    expected = _motion(m.joint("j1"), 0.3) @ _motion(m.joint("j2"), 0.7)
    np.testing.assert_allclose(m.placement("b", {"j1": 0.3}), expected, atol=1e-15)
    np.testing.assert_allclose(m.joint("j1").axis, [1, 0, 0])  # the URDF default axis


# --------------------------------------------------------------------------- Pinocchio oracle


@pytest.mark.parametrize("path", [SPOT, GO2], ids=["spot", "go2"])
def test_frames_and_jacobians_match_pinocchio(path, rng):
    model = load_urdf(path)
    pm = pinocchio.buildModelFromUrdf(str(path))
    assert pm.nq == len(model.actuated_joints)
    for _ in range(15):
        check_against_pinocchio(model, pm, random_values(model, rng))


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-2 * math.pi, 2 * math.pi), min_size=19, max_size=19))
def test_spot_matches_pinocchio_hypothesis(q):
    model = spot()
    values = {j.name: v for j, v in zip(model.actuated_joints, q)}
    check_against_pinocchio(model, pin_spot(), values, jacobians=False)


@pytest.mark.parametrize("name", ["twisted", "spinner", "ur", "non_rpp"])
def test_small_urdfs_match_pinocchio(name, rng, tmp_path):
    text = {"twisted": TWISTED, "spinner": SPINNER, "ur": UR_ARM, "non_rpp": NON_RPP}[name]
    path = tmp_path / f"{name}.urdf"
    path.write_text(text)
    model = load_urdf(path)
    pm = pinocchio.buildModelFromUrdf(str(path))
    assert pm.nv == len(model.actuated_joints)
    for _ in range(15):
        check_against_pinocchio(model, pm, random_values(model, rng))


# --------------------------------------------------------------------------- legs


def test_spot_legs():
    m = spot()
    legs, report = find_legs(m)
    assert [leg.name for leg in legs] == ["front_left", "front_right", "rear_left", "rear_right"]
    for leg in legs:
        left = 1.0 if "left" in leg.name else -1.0
        front = 1.0 if "front" in leg.name else -1.0
        assert leg.joint_names == (f"{leg.name}_hip_x", f"{leg.name}_hip_y", f"{leg.name}_knee")
        assert leg.foot == f"{leg.name}_foot"
        np.testing.assert_allclose(leg.hip_origin, [front * 0.29785, left * 0.055, 0], atol=1e-15)
        np.testing.assert_allclose(leg.a, [0, left * 0.110945, 0], atol=1e-15)
        np.testing.assert_allclose(leg.b, [0.025, 0, -0.3205], atol=1e-15)
        np.testing.assert_allclose(leg.c, [0, 0, -0.3365], atol=1e-15)
        np.testing.assert_array_equal(leg.signs, [1, 1, 1])
        np.testing.assert_array_equal(leg.contact_offset, [0, 0, 0])
        np.testing.assert_array_equal(
            leg.limits[:2],
            [
                [-0.78539816339744827899, 0.78539816339744827899],
                [-0.89884456477707963539, 2.2951079663725435509],
            ],
        )
    np.testing.assert_array_equal(
        [leg.limits[2, 1] for leg in legs], [-0.254801, -0.247563, -0.267153, -0.257725]
    )
    assert "ignored: arm_hand (6 actuated joints)" in report
    with pytest.raises(ValueError, match="read-only"):
        legs[0].a[0] = 1.0


def test_go2_legs():
    m = go2()
    legs, report = find_legs(m)
    assert [leg.name for leg in legs] == ["FL", "FR", "RL", "RR"]
    assert [leg.foot for leg in legs] == ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    for leg in legs:
        left = 1.0 if leg.name[1] == "L" else -1.0
        front = 1.0 if leg.name[0] == "F" else -1.0
        np.testing.assert_allclose(leg.hip_origin, [front * 0.1934, left * 0.0465, 0], atol=1e-15)
        np.testing.assert_allclose(leg.a, [0, left * 0.0955, 0], atol=1e-15)
        np.testing.assert_allclose(leg.b, [0, 0, -0.213], atol=1e-15)
        np.testing.assert_allclose(leg.c, [0, 0, -0.213], atol=1e-15)
        thigh = [-1.5708, 3.4907] if front > 0 else [-0.5236, 4.5379]
        np.testing.assert_array_equal(leg.limits, [[-1.0472, 1.0472], thigh, [-2.7227, -0.83776]])
    for rotor in ("FL_hip_rotor", "FL_thigh_rotor", "FL_calf_rotor", "imu", "radar"):
        assert any(line.startswith(f"ignored: {rotor} (") for line in report)
    assert "ignored: FL_calf_rotor (2 actuated joints)" in report
    arms, arm_report = find_arms(m, legs)
    assert arms == () and arm_report == ()


@pytest.mark.parametrize("model", [spot, go2], ids=["spot", "go2"])
def test_rpp_formula_equals_urdf_chain(model, rng):
    m = model()
    legs, _ = find_legs(m)
    check_legs_poe(m, legs, rng)


def test_twisted_leg(rng):
    m = parse_urdf(TWISTED)
    legs, report = find_legs(m)
    assert len(legs) == 1
    (leg,) = legs
    assert leg.name == "L" and leg.foot == "toe" and leg.joint_names == ("L_roll", "L_pitch", "L_knee")
    for key, value in TWISTED_GEOMETRY.items():
        np.testing.assert_allclose(getattr(leg, key), value, rtol=0, atol=1e-14, err_msg=key)
    np.testing.assert_array_equal(leg.limits, [[-1, 1], [-2, 2], [0.2, 2.6]])
    assert report == ("ignored: knee_rotor (2 actuated joints)", "ignored: hip_rotor (1 actuated joint)")
    check_legs_poe(m, legs, rng)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=3, max_size=3))
def test_twisted_leg_hypothesis(q):
    m = parse_urdf(TWISTED)
    (leg,), _ = find_legs(m, contact_offset=(0.01, -0.02, 0.03))
    np.testing.assert_allclose(ref.rpp_leg_fk(leg, q), foot_point(m, leg, q), rtol=0, atol=1e-12)


def test_spinner_legs(rng):
    m = parse_urdf(SPINNER)
    legs, report = find_legs(m)
    assert [leg.name for leg in legs] == ["FL", "HL"]
    fl, hl = legs
    assert fl.foot == "FL_foot"  # chosen by name over the (farther) shin sensor
    assert any("FL_foot: chosen as the foot" in line and "FL_shin_sensor" in line for line in report)
    np.testing.assert_array_equal(fl.signs, [-1, -1, 1])
    np.testing.assert_allclose(fl.hip_origin, [0.2, 0.05, 0.01])
    np.testing.assert_allclose(fl.a, [0.01, 0.08, -0.02])
    np.testing.assert_allclose(fl.b, [-0.02, 0.01, -0.2])
    np.testing.assert_allclose(fl.c, [0.03, -0.01, -0.22])
    np.testing.assert_array_equal(fl.limits, [[-np.inf, np.inf], [-np.inf, np.inf], [-7, 7]])
    np.testing.assert_allclose(hl.c, [0.06, 0, -0.2])  # the knee bends forward
    np.testing.assert_array_equal(hl.limits[2], [0.1, 2.7])
    assert "ignored: FL_rotor (2 actuated joints)" in report
    assert "ignored: camera (1 actuated joint)" in report
    check_legs_poe(m, legs, rng)


def test_feet_and_contact_offsets(rng):
    m = parse_urdf(SPINNER)
    legs, _ = find_legs(m, feet=["FL_shin_sensor"])
    assert [leg.foot for leg in legs] == ["FL_shin_sensor"]
    np.testing.assert_allclose(legs[0].c, [0, 0, -0.3])
    # A non-leaf foot with a contact offset gives the same point.
    legs, _ = find_legs(m, feet=["HL_calf"], contact_offset={"HL_calf": (0.06, 0, -0.2)})
    np.testing.assert_allclose(legs[0].c, [0.06, 0, -0.2])
    np.testing.assert_array_equal(legs[0].contact_offset, [0.06, 0, -0.2])
    check_legs_poe(m, legs, rng)
    legs, _ = find_legs(m, contact_offset=(0, 0, -0.02))
    np.testing.assert_allclose(legs[1].c, [0.06, 0, -0.22])
    check_legs_poe(m, legs, rng)
    # Rotated frames: the offset is in the foot link frame.
    tw = parse_urdf(TWISTED)
    (leg,), _ = find_legs(tw, contact_offset={"toe": (0.0, 0.0, 0.05)})
    R = tw.placement("toe")[:3, :3]
    np.testing.assert_allclose(leg.c, np.array(TWISTED_GEOMETRY["c"]) + R @ [0, 0, 0.05], atol=1e-14)
    check_legs_poe(tw, (leg,), rng)
    with pytest.raises(ValueError, match="'nope'"):
        find_legs(m, feet=["nope"])
    with pytest.raises(ValueError, match="foot link 'FL_rotor' is not a leg candidate"):
        find_legs(m, feet=["FL_rotor"])
    with pytest.raises(ValueError, match="'FL_foot' and 'FL_shin_sensor'"):
        find_legs(m, feet=["FL_foot", "FL_shin_sensor"])
    with pytest.raises(ValueError, match="contact_offset names link 'camera'"):
        find_legs(m, contact_offset={"camera": (0, 0, 0)})


def test_foot_chosen_by_distance():
    text = robot(
        leg3("A", foot_name="A_end_1"),
        '<link name="A_end_2"/><joint name="A_j2" type="fixed"><parent link="A_calf"/>'
        '<child link="A_end_2"/><origin xyz="0 0 -0.25"/></joint>',
    )
    legs, report = find_legs(parse_urdf(text))
    assert legs[0].foot == "A_end_2"
    assert any("farthest from the knee" in line for line in report)


def test_non_rpp_leg_is_reported_not_forced(rng):
    m = parse_urdf(NON_RPP)
    legs, report = find_legs(m)
    assert [leg.name for leg in legs] == ["good"]
    assert "yaw_foot: not roll-pitch-pitch: axes at zero angles are (0, 0, 1), (0, 1, 0), (0, 1, 0)" in report
    assert any(line.startswith("flat_foot: not a leg: the hip-pitch to knee vector b") for line in report)
    assert any(line.startswith("short_foot: not a leg: the knee to foot vector c") for line in report)
    with pytest.raises(ValueError, match="'yaw_foot': not roll-pitch-pitch"):
        find_legs(m, feet=["yaw_foot"])
    check_legs_poe(m, legs, rng)


def test_tolerance_of_axis_recognition():
    tilted = leg3("t", axes=("1 1e-7 0", "0 1 0", "0 1 0"))
    assert find_legs(parse_urdf(robot(tilted)))[0] == ()
    legs, _ = find_legs(parse_urdf(robot(tilted)), tolerance=1e-6)
    assert len(legs) == 1


def test_leg_names_fall_back_to_feet():
    text = robot(leg3("x"), leg3("y", origins=("-0.2 0.05 0", "0 0.08 0", "0 0 -0.2")))
    legs, _ = find_legs(parse_urdf(text))
    assert [leg.name for leg in legs] == ["x", "y"]
    # Rename the second leg's joints so that both legs get the name "x".
    for k in ("hip", "thigh", "calf"):
        text = text.replace(f'name="y_{k}_joint"', f'name="x_{k}_joint2"')
    legs, report = find_legs(parse_urdf(text))
    assert [leg.name for leg in legs] == ["x_foot", "y_foot"]
    assert any("not unique" in line for line in report)


def test_prismatic_three_joint_leaf_is_not_a_leg():
    text = robot(leg3("p")).replace(
        'name="p_calf_joint" type="revolute"', 'name="p_calf_joint" type="prismatic"'
    )
    legs, report = find_legs(parse_urdf(text))
    assert legs == () and report == ("p_foot: not a leg: joint 'p_calf_joint' is prismatic",)


def test_leg_spec_validation():
    kw = dict(
        name="x",
        joint_names=("a", "b", "c"),
        foot="f",
        hip_origin=(0, 0, 0),
        a=(0, 1, 0),
        b=(0, 0, -1),
        c=(0, 0, -1),
        limits=[[-1, 1]] * 3,
    )
    LegSpec(signs=(1, -1, 1), **kw)
    with pytest.raises(ValueError, match="signs"):
        LegSpec(signs=(1, 0.5, 1), **kw)
    with pytest.raises(ValueError, match="finite"):
        LegSpec(signs=(1, 1, 1), **{**kw, "a": (0, math.nan, 0)})


# --------------------------------------------------------------------------- arms


def test_spot_arm():
    m = spot()
    legs, _ = find_legs(m)
    arms, report = find_arms(m, legs)
    assert len(arms) == 1
    (arm,) = arms
    assert isinstance(arm, ArmSpec)
    assert arm.name == "arm"
    assert arm.joint_names == ("arm_sh0", "arm_sh1", "arm_el0", "arm_el1", "arm_wr0", "arm_wr1")
    assert arm.tip == "arm_hand" and arm.base == "body"
    assert arm.spherical_wrist
    np.testing.assert_allclose(arm.wrist_center, [0.292 + 0.3385 + 0.4033, 0, 0.188 + 0.075], atol=1e-12)
    assert any(
        line.startswith("arm_link_fngr: 7 actuated joints, the first 6") and "arm_f1x" in line
        for line in report
    )


def test_ur_arm_is_not_spherical():
    m = parse_urdf(UR_ARM)
    legs, _ = find_legs(m)
    assert legs == ()
    arms, report = find_arms(m, legs)
    (arm,) = arms
    assert arm.joint_names == (
        "shoulder_pan",
        "shoulder_lift",
        "elbow",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    )
    assert arm.tip == "tool0" and arm.base == "base_link"
    assert not arm.spherical_wrist and arm.wrist_center is None
    assert arm.name == "tool0"  # the joint names share no prefix
    assert "tilt: 2 actuated joints, not an arm" in report
    assert any(line.startswith("finger: 7 actuated joints") for line in report)
    assert any("wrist not spherical" in line for line in report)


def test_spherical_wrist_with_rotated_frames_and_offsets():
    # Wrist axes z, x, z through one point, reached through rotated frames; then offset the
    # last axis sideways by 1 mm and the wrist is no longer spherical.
    def arm(last_offset: str) -> str:
        rows = [
            ("j1", "base", "l1", "0 0 0.1", "0 0 0.3", "0 0 1"),
            ("j2", "l1", "l2", "0 0.1 0", f"{HALF_PI} 0 0", "0 0 1"),
            ("j3", "l2", "l3", "0.4 0 0", "0 0 0", "0 0 -1"),
            ("j4", "l3", "l4", "0.3 0.05 0", f"0 {HALF_PI} 0", "0 0 1"),
            ("j5", "l4", "l5", "0 0 0.2", "0 0 0", "0 1 0"),
            ("j6", "l5", "l6", last_offset, "0.4 0 0", "0 0 1"),
        ]
        parts = [f'<link name="{r[2]}"/>' for r in rows] + ['<link name="flange"/>']
        for name, parent, child, xyz, rpy, axis in rows:
            parts.append(urdf_joint(name, "revolute", parent, child, xyz, rpy, axis, (-3, 3)))
        parts.append(
            '<joint name="f" type="fixed"><parent link="l6"/><child link="flange"/>'
            '<origin xyz="0 0 0.1"/></joint>'
        )
        return robot(*parts)

    m = parse_urdf(arm("0 0 0"))
    (good,), _ = find_arms(m, ())
    assert good.spherical_wrist and good.tip == "flange" and good.name == "j"
    np.testing.assert_allclose(good.wrist_center, m.placement("l5")[:3, 3], atol=1e-12)
    (bad,), report = find_arms(parse_urdf(arm("0.001 0 0")), ())
    assert not bad.spherical_wrist and bad.wrist_center is None
    assert "do not meet" in report[0]
    # With a loose tolerance the 1 mm offset is accepted.
    (loose,), _ = find_arms(parse_urdf(arm("0.001 0 0")), (), tolerance=2e-3)
    assert loose.spherical_wrist


def test_describe():
    m = spot()
    legs, report = find_legs(m)
    arms, arm_report = find_arms(m, legs)
    text = describe(m, legs, arms, report + arm_report)
    assert text.startswith("robot 'spot': 26 links, 25 joints (19 actuated), root 'body'")
    assert "          front_left_foot  <- fixed front_left_foot_joint" in text
    assert (
        "front_left: joints front_left_hip_x, front_left_hip_y, front_left_knee; foot front_left_foot" in text
    )
    assert "a = (0, 0.110945, 0), b = (0.025, 0, -0.3205), c = (0, 0, -0.3365)" in text
    assert "hip origin (-0.29785, -0.055, 0)" in text
    assert "spherical wrist: yes" in text
    assert "arm_link_fngr: 7 actuated joints" in text
    go = go2()
    legs, report = find_legs(go)
    text = describe(go, legs, (), report)
    assert "radar  <- fixed radar_joint" in text and "arms (0):" in text
    assert "ignored: imu (0 actuated joints)" in text
    assert describe(parse_urdf(robot())).startswith("robot 'r': 1 link, 0 joints")


# --------------------------------------------------------------------------- validation errors


def joint(name="j", jtype="revolute", parent="base", child="a", body=None):
    body = f'<limit lower="-1" upper="1" {LIMIT}/>' if body is None else body
    return joint_xml(name, jtype, parent, child, body)


def inertial_link(mass="1", inertia='ixx="1" iyy="1" izz="1"', origin=""):
    return (
        f'<link name="a"><inertial>{origin}<mass value="{mass}"/><inertia {inertia}/></inertial></link>'
        + joint()
    )


INVALID = {
    "malformed": ("<robot name='x'><link name='a'></robot>", r"malformed URDF \(XML error at line 1, column"),
    "not robot": ("<model name='x'><link name='a'/></model>", "<model>, not <robot>"),
    "link no name": (robot("<link/>"), "link #2"),
    "joint no name": (robot('<link name="a"/>', joint(name="")), "joint #1"),
    "duplicate link": (robot('<link name="base"/>'), "duplicate link name 'base'"),
    "duplicate joint": (
        robot('<link name="a"/><link name="b"/>', joint(), joint(child="b")),
        "duplicate joint name 'j'",
    ),
    "no parent": (
        robot('<link name="a"/>', '<joint name="j" type="fixed"><child link="a"/></joint>'),
        "joint 'j': missing parent link",
    ),
    "no child": (
        robot('<link name="a"/>', '<joint name="j" type="fixed"><parent link="base"/></joint>'),
        "joint 'j': missing child link",
    ),
    "undeclared child": (robot(joint(child="ghost")), "joint 'j': child link 'ghost' is not declared"),
    "undeclared parent": (
        robot('<link name="a"/>', joint(parent="ghost")),
        "joint 'j': parent link 'ghost' is not declared",
    ),
    "two parents": (
        robot('<link name="a"/><link name="b"/>', joint(child="b"), joint(name="k", parent="a", child="b")),
        "link 'b' has two parent joints: 'j' and 'k'",
    ),
    "loop": (
        robot(
            '<link name="a"/><link name="b"/>',
            joint(parent="a", child="b"),
            joint(name="k", parent="b", child="a"),
        ),
        "loop through links",
    ),
    "self loop": (robot(joint(parent="base", child="base")), "joint 'j': a loop, link 'base'"),
    "two roots": (
        robot('<link name="a"/><link name="b"/><link name="c"/>', joint(parent="a", child="b")),
        "3 root links .*'base', 'a', 'c'",
    ),
    "no links": ("<robot name='empty'></robot>", "robot 'empty' has no links"),
    "zero axis": (
        robot('<link name="a"/>', joint(body=f'<axis xyz="0 0 0"/><limit lower="0" upper="1" {LIMIT}/>')),
        "joint 'j': the axis of a revolute joint must not be zero",
    ),
    "nan origin": (
        robot('<link name="a"/>', joint(body=f'<origin xyz="0 nan 0"/><limit {LIMIT}/>')),
        "joint 'j': origin xyz: 'nan' is not a number",
    ),
    "inf rpy": (
        robot('<link name="a"/>', joint(body=f'<origin rpy="0 1e999 0"/><limit {LIMIT}/>')),
        "joint 'j': origin rpy: '1e999' is not finite",
    ),
    "text axis": (
        robot('<link name="a"/>', joint(body=f'<axis xyz="0 one 0"/><limit {LIMIT}/>')),
        "joint 'j': axis xyz: 'one' is not a number",
    ),
    "underscore": (
        robot('<link name="a"/>', joint(body='<limit lower="-1_0" upper="1"/>')),
        "joint 'j': limit lower: '-1_0' is not a number",
    ),
    "limit inf": (
        robot('<link name="a"/>', joint(body='<limit lower="-inf" upper="1"/>')),
        "joint 'j': limit lower: '-inf' is not a number",
    ),
    "bad effort": (
        robot('<link name="a"/>', joint(body='<limit lower="-1" upper="1" effort="x"/>')),
        "joint 'j': limit effort: 'x' is not a number",
    ),
    "two numbers": (
        robot('<link name="a"/>', joint(body=f'<origin xyz="1 2"/><limit {LIMIT}/>')),
        r"joint 'j': origin xyz: expected 3 numbers, got 2",
    ),
    "four numbers": (
        robot('<link name="a"/>', joint(body=f'<axis xyz="1 0 0 0"/><limit {LIMIT}/>')),
        r"joint 'j': axis xyz: expected 3 numbers, got 4",
    ),
    "lower above upper": (
        robot('<link name="a"/>', joint(body='<limit lower="1" upper="-1"/>')),
        "joint 'j': lower limit 1 is above upper limit -1",
    ),
    "no limit": (robot('<link name="a"/>', joint(body="")), "joint 'j': a revolute joint needs a <limit>"),
    "no limit prismatic": (
        robot('<link name="a"/>', joint(jtype="prismatic", body="")),
        "joint 'j': a prismatic joint needs a <limit>",
    ),
    "floating": (
        robot(
            '<link name="a"/><link name="b"/>',
            joint(),
            joint(name="k", jtype="floating", parent="a", child="b"),
        ),
        "joint 'k': type 'floating' is only supported as the root joint",
    ),
    "planar": (
        robot('<link name="a"/>', joint(jtype="planar", body="")),
        "joint 'j': type 'planar' is not supported",
    ),
    "unknown type": (
        robot('<link name="a"/>', joint(jtype="hinge", body="")),
        "joint 'j': unknown type 'hinge'",
    ),
    "no type": (
        robot('<link name="a"/>', '<joint name="j"><parent link="base"/><child link="a"/></joint>'),
        "joint 'j': missing type",
    ),
    "negative mass": (robot(inertial_link(mass="-1")), "link 'a': inertial: negative mass -1"),
    "text mass": (robot(inertial_link(mass="heavy")), "link 'a': inertial: mass: 'heavy' is not a number"),
    "no mass": (
        robot('<link name="a"><inertial><inertia ixx="1" iyy="1" izz="1"/></inertial></link>'),
        "link 'a': inertial: missing <mass>",
    ),
    "no inertia": (
        robot('<link name="a"><inertial><mass value="1"/></inertial></link>'),
        "link 'a': inertial: missing <inertia>",
    ),
    "missing ixx": (
        robot(inertial_link(inertia='iyy="1" izz="1"')),
        "link 'a': inertial: inertia has no ixx",
    ),
    "inf inertia": (
        robot(inertial_link(inertia='ixx="1" iyy="1e400" izz="1"')),
        "link 'a': inertial: inertia iyy: '1e400' is not finite",
    ),
    "not psd": (
        robot(inertial_link(inertia='ixx="1" iyy="1" izz="-0.5"')),
        "link 'a': inertial: the inertia matrix is not positive semidefinite",
    ),
    "not psd off-diagonal": (
        robot(inertial_link(inertia='ixx="1" iyy="1" izz="1" ixy="2"')),
        "link 'a'.*not positive semidefinite",
    ),
    "bad inertial origin": (
        robot(inertial_link(origin='<origin xyz="0 0"/>')),
        "link 'a': inertial: origin xyz: expected 3 numbers",
    ),
}


@pytest.mark.parametrize("case", list(INVALID))
def test_validation_errors(case):
    text, message = INVALID[case]
    with pytest.raises(ValueError, match=message):
        parse_urdf(text)


def test_fixed_joint_axis_is_ignored_and_default_axis():
    m = parse_urdf(
        robot(
            '<link name="a"/><link name="b"/>',
            joint(jtype="fixed", body='<axis xyz="0 0 0"/>'),
            joint(name="k", jtype="continuous", parent="a", child="b", body=""),
        )
    )
    assert m.joint("j").axis is None
    np.testing.assert_array_equal(m.joint("k").axis, [1, 0, 0])
    assert m.joint("k").effort is None and m.joint("k").velocity is None


def test_inertial_constructor_validates():
    with pytest.raises(ValueError, match="not symmetric"):
        Inertial(1.0, np.zeros(3), [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]], np.eye(3))
    with pytest.raises(ValueError, match="finite"):
        Inertial(1.0, np.zeros(3), np.diag([1, math.inf, 1]), np.eye(3))
    with pytest.raises(ValueError, match="mass"):
        Inertial(-1.0, np.zeros(3), np.eye(3), np.eye(3))
    # Loose semidefiniteness: a tiny negative eigenvalue from rounding is accepted.
    Inertial(1.0, np.zeros(3), np.diag([1.0, 1.0, -1e-12]), np.eye(3))


def test_load_urdf_accepts_pathlike_and_str(tmp_path):
    path = tmp_path / "r.urdf"
    path.write_text(TWISTED)
    assert load_urdf(path).name == "twisted"
    assert load_urdf(str(path)).name == "twisted"


def test_packaged_go2_is_the_test_copy():
    """The demo's packaged Go2 (spotkin/robots/go2.urdf) is byte-identical to the test data."""
    import spotkin as sk

    assert Path(sk.robots.path("go2")).read_bytes() == GO2.read_bytes()
