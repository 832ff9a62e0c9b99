"""spotkin.Robot from URDF: chains, legs, whole body and the arm against Pinocchio (an independent
oracle), the plain reference (spotkin.reference.urdf) and finite differences; Spot built from its
URDF against the built-in Spot; pickling."""

from __future__ import annotations

import pickle
from functools import cache
from pathlib import Path

import numpy as np
import pinocchio  # the independent oracle (requirements-test.txt: pin); never skipped
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from urdf_helpers import joint, links, pin_q

import spotkin as sk
from spotkin import urdf as su
from spotkin.reference import urdf as ref

SPOT_URDF = Path(sk.__file__).resolve().parent / "robots" / "spot_with_arm.urdf"
GO2_URDF = Path(__file__).resolve().parent / "data" / "go2.urdf"
DTYPES = [np.float64, np.float32]
BATCHES = [(), (1,), (3, 1, 2), (0,)]


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261203)


# --------------------------------------------------------------------------- small URDFs

PI = "3.141592653589793"
HALF_PI = "1.5707963267948966"


def urdf_text(name: str, *parts: str, base: str = "base") -> str:
    return (
        f'<?xml version="1.0"?>\n<robot name="{name}"><link name="{base}"/>\n'
        + "\n".join(parts)
        + "\n</robot>"
    )


# One leg per feature, plus a z-y-y leg that is not roll-pitch-pitch.
ZOO = urdf_text(
    "zoo",
    # TW: joint frames rotated by right angles (yaw 90, roll 180, yaw 180) so that the axes still come out
    # x, -y, y in the body frame; a negative, unnormalised hip axis; a fixed joint between hip roll and
    # pitch; offsets along all three axes at every joint; a forward knee (limits positive, sign +1); a
    # fixed knee rotor and a continuous hip rotor hanging off the tree.
    links("TW_hip", "TW_hip_mount", "TW_thigh", "TW_shank", "TW_toe", "TW_knee_rotor", "TW_hip_rotor"),
    joint("TW_roll", "revolute", "base", "TW_hip", "0.3 0.12 -0.02", f"0 0 {HALF_PI}", "0 -2 0", (-1, 1)),
    joint("TW_mount", "fixed", "TW_hip", "TW_hip_mount", "0.01 0.02 0.03", f"0 0 -{HALF_PI}"),
    joint(
        "TW_pitch", "revolute", "TW_hip_mount", "TW_thigh", "0.02 0.08 -0.01", f"{PI} 0 0", "0 1 0", (-2, 2)
    ),
    joint(
        "TW_knee", "revolute", "TW_thigh", "TW_shank", "0.03 -0.01 0.25", f"0 0 {PI}", "0 0.5 0", (0.2, 2.6)
    ),
    joint("TW_toe_joint", "fixed", "TW_shank", "TW_toe", "0.01 0.02 0.28", "0.3 0.2 0.1"),
    joint("TW_knee_rotor_joint", "fixed", "TW_thigh", "TW_knee_rotor", "0 0.03 0"),
    joint("TW_hip_rotor_spin", "continuous", "base", "TW_hip_rotor", "0.2 0.1 0", axis="1 0 0"),
    # FK: a forward-bending knee (knee limits positive: preferred slot 1), the hip-pitch axis offset
    # vertically from the hip-roll axis (so the two hip branches differ).
    links("FK_hip", "FK_thigh", "FK_calf", "FK_foot"),
    joint("FK_hip_joint", "revolute", "base", "FK_hip", "-0.25 0.06 0.01", axis="1 0 0", limits=(-0.6, 0.6)),
    joint(
        "FK_thigh_joint",
        "revolute",
        "FK_hip",
        "FK_thigh",
        "0.015 0.07 -0.03",
        axis="0 1 0",
        limits=(-1.6, 1.4),
    ),
    joint(
        "FK_calf_joint",
        "revolute",
        "FK_thigh",
        "FK_calf",
        "-0.02 0.012 -0.22",
        axis="0 1 0",
        limits=(0.15, 2.6),
    ),
    joint("FK_foot_joint", "fixed", "FK_calf", "FK_foot", "0.012 -0.008 -0.23"),
    # CT: continuous hip roll and pitch with negative (and unnormalised) axes, a knee whose limits are
    # wider than 2 pi, and a continuous rotor on the hip.
    links("CT_hip", "CT_thigh", "CT_calf", "CT_foot", "CT_rotor"),
    joint("CT_hip_joint", "continuous", "base", "CT_hip", "0.28 -0.07 0.02", axis="-1 0 0"),
    joint("CT_thigh_joint", "continuous", "CT_hip", "CT_thigh", "0.01 -0.09 -0.015", axis="0 -3 0"),
    joint(
        "CT_calf_joint", "revolute", "CT_thigh", "CT_calf", "0.02 -0.01 -0.2", axis="0 1 0", limits=(-7, 7)
    ),
    joint("CT_foot_joint", "fixed", "CT_calf", "CT_foot", "-0.015 0.01 -0.21"),
    joint("CT_rotor_joint", "continuous", "CT_hip", "CT_rotor", "0 -0.02 0", axis="0 1 0"),
    # RY: joint frames rotated by arbitrary angles about the joint axes and undone by fixed joints, a thigh
    # pitched by 0.9 rad at zero, and a knee axis written as -x in a frame yawed by 90 degrees (-y in the
    # body frame).
    links("RY_hip", "RY_undo", "RY_thigh", "RY_knee_frame", "RY_calf", "RY_foot"),
    joint("RY_hip_joint", "revolute", "base", "RY_hip", "-0.3 -0.05 -0.01", "0.4 0 0", "1 0 0", (-0.8, 0.8)),
    joint("RY_undo_joint", "fixed", "RY_hip", "RY_undo", "0.005 -0.03 0.004", "-0.4 0 0"),
    joint(
        "RY_thigh_joint", "revolute", "RY_undo", "RY_thigh", "-0.01 -0.05 0.02", "0 0.9 0", "0 1 0", (-1.5, 2)
    ),
    joint("RY_knee_frame_joint", "fixed", "RY_thigh", "RY_knee_frame", "0.03 0.004 -0.2", f"0 0 {HALF_PI}"),
    joint(
        "RY_calf_joint",
        "revolute",
        "RY_knee_frame",
        "RY_calf",
        "0.01 0.02 -0.03",
        axis="-1 0 0",
        limits=(0.3, 2.7),
    ),
    joint("RY_foot_joint", "fixed", "RY_calf", "RY_foot", "0.02 -0.01 -0.2", "0.3 0.2 0.1"),
    # YAW: z-y-y, not a roll-pitch-pitch leg.
    links("YAW_hip", "YAW_thigh", "YAW_calf", "YAW_foot"),
    joint("YAW_hip_joint", "revolute", "base", "YAW_hip", "0 0.15 0", axis="0 0 1", limits=(-1, 1)),
    joint("YAW_thigh_joint", "revolute", "YAW_hip", "YAW_thigh", "0 0.08 0", axis="0 1 0", limits=(-1, 1)),
    joint("YAW_calf_joint", "revolute", "YAW_thigh", "YAW_calf", "0 0 -0.2", axis="0 1 0", limits=(-2, -0.2)),
    joint("YAW_foot_joint", "fixed", "YAW_calf", "YAW_foot", "0 0 -0.2"),
)


def hexapod_leg(prefix, hip, axes, knee_limits, a="0 0.08 0", b="0.02 0 -0.2", c="0 0 -0.21"):
    """(links, [hip, thigh, calf, foot joints]) of one hexapod leg."""
    names = [f"{prefix}_hip", f"{prefix}_thigh", f"{prefix}_calf", f"{prefix}_foot"]
    return links(*names), [
        joint(f"{prefix}_hip_joint", "revolute", "base", names[0], hip, axis=axes[0], limits=(-0.7, 0.7)),
        joint(f"{prefix}_thigh_joint", "revolute", names[0], names[1], a, axis=axes[1], limits=(-2.2, 2.2)),
        joint(f"{prefix}_calf_joint", "revolute", names[1], names[2], b, axis=axes[2], limits=knee_limits),
        joint(f"{prefix}_foot_joint", "fixed", names[2], names[3], c),
    ]


# Six legs at different places (heights too) with a mix of axis signs (a knee axis of -y takes positive
# limits to bend back). The joints are written hips first, then thighs, then knees, so the whole-body q
# (URDF order) interleaves the legs.
_HEX_LEGS = [
    hexapod_leg("L1", "0.3 0.12 0", ("1 0 0", "0 1 0", "0 1 0"), (-2.6, -0.2)),
    hexapod_leg("R1", "0.31 -0.1 0.01", ("-1 0 0", "0 -1 0", "0 -1 0"), (0.2, 2.6), a="0 -0.07 0.01"),
    hexapod_leg("L2", "0.02 0.15 -0.01", ("1 0 0", "0 -1 0", "0 1 0"), (-2.6, -0.2), b="-0.015 0.005 -0.22"),
    hexapod_leg("R2", "-0.01 -0.16 0", ("1 0 0", "0 1 0", "0 -1 0"), (0.2, 2.6), a="0.01 -0.09 0"),
    hexapod_leg("L3", "-0.33 0.11 0.005", ("-1 0 0", "0 1 0", "0 1 0"), (-2.6, -0.2), c="0.01 0.01 -0.2"),
    hexapod_leg("R3", "-0.3 -0.12 -0.02", ("-1 0 0", "0 -1 0", "0 1 0"), (-2.6, -0.2), a="0 -0.085 -0.01"),
]
HEXAPOD = urdf_text(
    "hexapod", *[parts for parts, _ in _HEX_LEGS], *[js[k] for k in range(4) for _, js in _HEX_LEGS]
)

TEXTS = {"zoo": ZOO, "hexapod": HEXAPOD}
LEG_NAMES = {
    "spot": ("front_left", "front_right", "rear_left", "rear_right"),
    "go2": ("FL", "FR", "RL", "RR"),
    "zoo": ("TW", "FK", "CT", "RY"),
    "hexapod": ("L1", "R1", "L2", "R2", "L3", "R3"),
}
LEG_CASES = [(name, leg) for name, legs in LEG_NAMES.items() for leg in legs]
STANCE_HEIGHT = {"spot": 0.5, "go2": 0.28, "hexapod": 0.3}

# Chains to every leaf with a moving joint, and some intermediate links (fixed children included).
CHAIN_LINKS = {
    "spot": (
        "front_left_foot",
        "front_right_foot",
        "rear_left_foot",
        "rear_right_foot",
        "arm_link_fngr",
        "arm_hand",
        "front_left_upper_leg",
        "rear_right_lower_leg",
        "arm_link_sh0",
        "arm_link_hr0",
        "arm_link_el1",
        "arm_link_wr1",
    ),
    "go2": (
        "FL_foot",
        "FR_foot",
        "RL_foot",
        "RR_foot",
        "FL_thigh_rotor",
        "RR_calf_rotor",
        "FR_hip",
        "RL_thigh",
        "FL_calf",
    ),
    "zoo": (
        "TW_toe",
        "TW_knee_rotor",
        "TW_hip_rotor",
        "CT_rotor",
        "CT_foot",
        "RY_foot",
        "RY_thigh",
        "YAW_foot",
    ),
}
CHAIN_CASES = [(name, link) for name, names in CHAIN_LINKS.items() for link in names]


@cache
def robot(name: str) -> sk.Robot:
    if name == "spot":
        return sk.Robot.from_urdf(SPOT_URDF)
    if name == "go2":
        return sk.Robot.from_urdf(GO2_URDF)
    return sk.Robot.from_urdf_string(TEXTS[name])


@cache
def pin_model(name: str):
    if name == "spot":
        return pinocchio.buildModelFromUrdf(str(SPOT_URDF))
    if name == "go2":
        return pinocchio.buildModelFromUrdf(str(GO2_URDF))
    return pinocchio.buildModelFromXML(TEXTS[name])


@cache
def leg_spec(name: str, leg: str) -> su.LegSpec:
    specs, _ = su.find_legs(robot(name).model)
    return {spec.name: spec for spec in specs}[leg]


def columns(name: str, leg_name: str) -> list[int]:
    """The leg's columns in the whole-body q, found by joint name."""
    return [robot(name).leg_joint_names.index(j) for j in leg_spec(name, leg_name).joint_names]


def pin_frame(pm, pd, link: str) -> np.ndarray:
    return pd.oMf[pm.getFrameId(link, pinocchio.FrameType.BODY)].homogeneous


def circle(a: np.ndarray) -> np.ndarray:
    """|a| on the circle, in [0, pi]."""
    return np.abs((a + np.pi) % (2 * np.pi) - np.pi)


def stack(items, shape) -> np.ndarray:
    """np.array(items) reshaped to shape, also when there are no items."""
    return np.array(items, dtype=np.float64).reshape(shape)


def layout(q: np.ndarray, kind: str) -> np.ndarray:
    """The same values as q, in a contiguous, transposed or strided array."""
    if kind == "transposed":  # the transpose of a C-ordered array, reversed axes
        return np.ascontiguousarray(q.T).T
    if kind == "strided":
        buffer = np.full((*q.shape[:-1], 2 * q.shape[-1]), np.nan, dtype=q.dtype)
        buffer[..., ::2] = q
        return buffer[..., ::2]
    return q


def vee(W: np.ndarray) -> np.ndarray:
    return 0.5 * np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])


def fd_chain_jacobian(chain: sk.Chain, q: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """[v; w] of the tool origin by central differences of chain.fk."""
    J = np.zeros((6, chain.dof))
    R = chain.fk(q)[:3, :3]
    for k in range(chain.dof):
        e = np.zeros(chain.dof)
        e[k] = step
        Tp, Tm = chain.fk(q + e), chain.fk(q - e)
        J[:3, k] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * step)
        J[3:, k] = vee((Tp[:3, :3] - Tm[:3, :3]) / (2 * step) @ R.T)
    return J


def in_limit_q(rng: np.random.Generator, limits: np.ndarray, n: int) -> np.ndarray:
    """Uniform within the limits ([-pi, pi] where unlimited), wrapped into (-pi, pi] where they allow."""
    lower, upper = limits[:, 0], limits[:, 1]
    q = rng.uniform(
        np.where(np.isfinite(lower), lower, -np.pi),
        np.where(np.isfinite(upper), upper, np.pi),
        (n, len(limits)),
    )
    wrapped = np.pi - np.mod(np.pi - q, 2 * np.pi)
    return np.where((wrapped >= lower) & (wrapped <= upper), wrapped, q)


def twist_step(T: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """The body pose moved by a world-frame twist: t + v, exp([w]x) R (body_jacobian's convention)."""
    out = T.copy()
    out[:3, :3] = Rotation.from_rotvec(twist[3:]).as_matrix() @ T[:3, :3]
    out[:3, 3] = T[:3, 3] + twist[:3]
    return out


def random_pose_matrix(rng: np.random.Generator, height: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(rng.normal(0, 0.06, 3)).as_matrix()
    T[:3, 3] = [0, 0, height] + rng.normal(0, 0.02, 3)
    return T


def random_poses(rng: np.random.Generator, height: float, shape: tuple[int, ...]) -> np.ndarray:
    """(*shape, 6) Euler poses near [0, 0, height, 0, 0, 0]."""
    spread = np.array([0.02, 0.02, 0.02, 0.06, 0.06, 0.06])
    return np.array([0, 0, height, 0, 0, 0]) + rng.normal(0, 1, (*shape, 6)) * spread


# --------------------------------------------------------------------------- 1. chains from URDF


def test_robots_are_recognised():
    for name, legs in LEG_NAMES.items():
        assert robot(name).leg_names == legs, name
    assert robot("spot").arm is not None and robot("go2").arm is None
    zoo = robot("zoo")
    assert (
        "YAW_foot: not roll-pitch-pitch: axes at zero angles are (0, 0, 1), (0, 1, 0), (0, 1, 0)"
        in zoo.report
    )
    assert not any("YAW" in name for name in zoo.leg_names + zoo.leg_joint_names)
    for rotor in ("TW_knee_rotor", "TW_hip_rotor", "CT_rotor"):
        assert any(line.startswith(f"ignored: {rotor} (") for line in zoo.report), rotor
    # the features are really there
    tw, fk, ct, ry = zoo.legs
    np.testing.assert_array_equal(tw.signs, [1, -1, 1])
    np.testing.assert_array_equal(ct.signs, [-1, -1, 1])
    np.testing.assert_array_equal(ry.signs, [1, 1, -1])
    np.testing.assert_array_equal(ct.limits, [[-np.inf, np.inf], [-np.inf, np.inf], [-7, 7]])
    assert fk.preferred_slot == 1 and tw.preferred_slot == 1
    assert fk.a[2] != 0 and all(np.all(v != 0) for v in (fk.a, fk.b, fk.c))
    assert all(leg.preferred_slot == 0 for leg in robot("hexapod").legs)
    # the hexapod's whole-body q interleaves the legs
    hexapod = robot("hexapod")
    assert hexapod.leg_joint_names[:3] == ("L1_hip_joint", "R1_hip_joint", "L2_hip_joint")
    assert len({np.sign(leg.signs).tobytes() for leg in hexapod.legs}) == 6


@pytest.mark.parametrize("name", ["spot", "go2", "zoo"])
def test_links_without_moving_joints_have_no_chain(name):
    model = robot(name).model
    for link in model.links:
        if not any(j.actuated for j in model.path(link)):
            with pytest.raises(ValueError, match="no actuated joint"):
                robot(name).chain(link)


@pytest.mark.parametrize(("name", "link"), CHAIN_CASES)
def test_chain_matches_pinocchio_reference_and_differences(name, link, rng):
    r, pm = robot(name), pin_model(name)
    pd = pm.createData()
    chain = r.chain(link)
    data = r.model.chain_data(link)
    assert chain.joint_names == data.joint_names
    children = [r.model.joint(j).child for j in chain.joint_names]
    q = rng.uniform(-4, 4, (12, chain.dof))
    T, F, J = chain.fk(q), chain.frames(q), chain.jacobian(q)
    assert T.shape == (12, 4, 4) and F.shape == (12, chain.dof + 2, 4, 4) and J.shape == (12, 6, chain.dof)
    for k in range(len(q)):
        pinocchio.framesForwardKinematics(pm, pd, pin_q(pm, dict(zip(chain.joint_names, q[k]))))
        np.testing.assert_allclose(T[k], pin_frame(pm, pd, link), rtol=0, atol=1e-12)
        expected = [np.eye(4), *(pin_frame(pm, pd, child) for child in children), pin_frame(pm, pd, link)]
        np.testing.assert_allclose(F[k], expected, rtol=0, atol=1e-12)
        Jp = pinocchio.computeFrameJacobian(
            pm,
            pd,
            pin_q(pm, dict(zip(chain.joint_names, q[k]))),
            pm.getFrameId(link, pinocchio.FrameType.BODY),
            pinocchio.LOCAL_WORLD_ALIGNED,
        )
        columns = [pm.joints[pm.getJointId(j)].idx_v for j in chain.joint_names]
        np.testing.assert_allclose(J[k], Jp[:, columns], rtol=0, atol=1e-12)
        np.testing.assert_allclose(T[k], ref.chain_fk(data, q[k]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(F[k], ref.chain_frames(data, q[k]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(J[k], ref.chain_jacobian(data, q[k]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(J[k], fd_chain_jacobian(chain, q[k]), rtol=0, atol=1e-8)
    np.testing.assert_array_equal(F[:, -1], T)


@settings(max_examples=80)
@given(
    case=st.sampled_from(CHAIN_CASES),
    batch=st.sampled_from(BATCHES),
    dtype=st.sampled_from(DTYPES),
    kind=st.sampled_from(["contiguous", "transposed", "strided"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_chain_batches_match_the_reference(case, batch, dtype, kind, seed):
    name, link = case
    chain, data = robot(name).chain(link), robot(name).model.chain_data(link)
    n = chain.dof
    q = layout(np.random.default_rng(seed).uniform(-4, 4, (*batch, n)).astype(dtype), kind)
    if (kind == "strided" and q.size > 1) or (kind == "transposed" and sum(d > 1 for d in q.shape) > 1):
        assert not q.flags.c_contiguous
    T, F, J = chain.fk(q), chain.frames(q), chain.jacobian(q)
    assert T.shape == (*batch, 4, 4) and F.shape == (*batch, n + 2, 4, 4) and J.shape == (*batch, 6, n)
    assert T.dtype == F.dtype == J.dtype == dtype
    q64 = q.astype(np.float64)
    rows = q64.reshape(-1, n)
    T_ref = stack([ref.chain_fk(data, x) for x in rows], (*batch, 4, 4))
    F_ref = stack([ref.chain_frames(data, x) for x in rows], (*batch, n + 2, 4, 4))
    J_ref = stack([ref.chain_jacobian(data, x) for x in rows], (*batch, 6, n))
    tolerance = 1e-12 if dtype == np.float64 else 1e-5
    np.testing.assert_allclose(T, T_ref, rtol=0, atol=tolerance)
    np.testing.assert_allclose(F, F_ref, rtol=0, atol=tolerance)
    np.testing.assert_allclose(J, J_ref, rtol=0, atol=tolerance)
    if dtype == np.float32:  # float32 within 1e-5 of the float64 computation from the same q
        np.testing.assert_allclose(T, chain.fk(q64), rtol=0, atol=1e-5)
        np.testing.assert_allclose(J, chain.jacobian(q64), rtol=0, atol=1e-5)
    np.testing.assert_array_equal(chain.fk(np.ascontiguousarray(q)), T)


def test_chain_has_the_urdf_names_limits_and_arm_closed_form():
    spot = robot("spot")
    chain = spot.chain("arm_hand")
    assert chain.joint_names == ("arm_sh0", "arm_sh1", "arm_el0", "arm_el1", "arm_wr0", "arm_wr1")
    limits = np.array([[spot.model.joint(j).lower, spot.model.joint(j).upper] for j in chain.joint_names])
    np.testing.assert_array_equal(chain.lower, limits[:, 0])
    np.testing.assert_array_equal(chain.upper, limits[:, 1])
    assert spot.arm.joint_names == chain.joint_names and spot.arm.ik_kind == "6R-spherical-wrist"
    # a sub-chain from an inner base
    sub = spot.chain("arm_hand", base="arm_link_sh1")
    assert sub.joint_names == chain.joint_names[2:]
    q = np.array([0.3, -0.7, 1.2, 0.4, -0.5, 0.9])
    np.testing.assert_allclose(spot.chain("arm_link_sh1").fk(q[:2]) @ sub.fk(q[2:]), chain.fk(q), atol=1e-14)
    np.testing.assert_array_equal(robot("zoo").chain("CT_foot").lower[:2], [-np.inf, -np.inf])


# --------------------------------------------------------------------------- 2. legs


@pytest.mark.parametrize(("name", "leg_name"), LEG_CASES)
def test_leg_matches_chain_pinocchio_and_reference(name, leg_name, rng):
    r = robot(name)
    leg, spec = r.leg(leg_name), leg_spec(name, leg_name)
    hip = r.hip_positions[r.leg_names.index(leg_name)]
    np.testing.assert_array_equal(hip, spec.hip_origin)
    chain = r.chain(spec.foot)
    assert chain.joint_names == spec.joint_names
    q = rng.uniform(-4, 4, (400, 3))
    p = leg.fk(q)
    np.testing.assert_allclose(p + hip, chain.fk(q)[..., :3, 3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(p, [ref.rpp_leg_fk(spec, x) for x in q], rtol=0, atol=1e-12)
    # the leg frame has the body's axes: the leg Jacobian is the chain's position Jacobian
    np.testing.assert_allclose(leg.jacobian(q), chain.position_jacobian(q), rtol=0, atol=1e-12)
    pm = pin_model(name)
    pd = pm.createData()
    for x in q[:20]:
        pinocchio.framesForwardKinematics(pm, pd, pin_q(pm, dict(zip(spec.joint_names, x))))
        np.testing.assert_allclose(leg.fk(x) + hip, pin_frame(pm, pd, spec.foot)[:3, 3], rtol=0, atol=1e-12)
    step = 1e-6
    for x in q[:30]:
        fd = np.stack([(leg.fk(x + e) - leg.fk(x - e)) / (2 * step) for e in np.eye(3) * step], axis=1)
        np.testing.assert_allclose(leg.jacobian(x), fd, rtol=0, atol=1e-8)


def test_non_rpp_leg_still_has_a_chain(rng):
    zoo, pm = robot("zoo"), pin_model("zoo")
    pd = pm.createData()
    chain = zoo.chain("YAW_foot")
    assert chain.joint_names == ("YAW_hip_joint", "YAW_thigh_joint", "YAW_calf_joint")
    for q in rng.uniform(-3, 3, (10, 3)):
        pinocchio.framesForwardKinematics(pm, pd, pin_q(pm, dict(zip(chain.joint_names, q))))
        np.testing.assert_allclose(chain.fk(q), pin_frame(pm, pd, "YAW_foot"), rtol=0, atol=1e-12)
    # a z-y-y leg has a closed form as a 3R chain
    q = np.array([0.3, -0.4, -1.1])
    solutions = chain.ik_position(chain.fk(q)[:3, 3])
    assert (circle(solutions.q[solutions.exists] - q).max(axis=1) < 1e-9).any()


def check_round_trip(leg: sk.Leg, n: int, dtype, rng: np.random.Generator) -> None:
    """FK -> IK round trips of random in-limit q: the generating q is among the valid slots, ik is OK."""
    limits = leg.limits
    q = in_limit_q(rng, limits, n).astype(dtype)
    q64 = q.astype(np.float64)
    q = q[((q64 >= limits[:, 0]) & (q64 <= limits[:, 1])).all(axis=1)]  # the float32 cast may step out
    q64 = q.astype(np.float64)
    p = leg.fk(q)
    assert p.dtype == dtype
    solutions = leg.ik_all(p)
    q_ik, status = leg.ik(p)
    assert q_ik.dtype == dtype
    if dtype == np.float64:
        keep, tolerance, fk_tolerance = np.ones(len(q), dtype=bool), 1e-9, 1e-12
    else:
        # float32 targets carry ~1e-7 relative rounding: the angles come back to ~1e-4 rad, more near the
        # singular sets and possibly just past a limit (test_float32_round_trip_at_a_joint_limit)
        sigma = leg.singularity(q64)[1]
        margin = np.minimum(q64 - limits[:, 0], limits[:, 1] - q64).min(axis=1)
        keep, tolerance, fk_tolerance = (sigma > 1e-4) & (margin > 1e-3), 1e-3, 2e-6
        assert keep.mean() > 0.97
    assert solutions.exists[keep].any(axis=1).all()
    error = circle(solutions.q.astype(np.float64) - q64[:, None, :]).max(axis=-1)
    best = np.where(solutions.valid, error, np.inf).min(axis=1)
    assert (best[keep] < tolerance).all(), (leg.name, best[keep].max(), q[keep][np.argmax(best[keep])])
    assert (status[keep] == sk.Status.OK).all(), leg.name
    ok = status == sk.Status.OK
    np.testing.assert_allclose(leg.fk(q_ik[ok]), p[ok], rtol=0, atol=fk_tolerance)
    slack = 1e-12 if dtype == np.float64 else 1e-6
    assert ((q_ik[ok] >= limits[:, 0] - slack) & (q_ik[ok] <= limits[:, 1] + slack)).all()


@pytest.mark.parametrize("dtype", DTYPES, ids=["float64", "float32"])
@pytest.mark.parametrize(("name", "leg_name"), LEG_CASES)
def test_leg_round_trips(name, leg_name, dtype, rng):
    check_round_trip(robot(name).leg(leg_name), 3000, dtype, rng)


@pytest.mark.slow
@pytest.mark.parametrize("dtype", DTYPES, ids=["float64", "float32"])
@pytest.mark.parametrize(("name", "leg_name"), LEG_CASES)
def test_leg_round_trips_1e5(name, leg_name, dtype, rng):
    check_round_trip(robot(name).leg(leg_name), 100_000, dtype, rng)


def test_float32_round_trip_at_a_joint_limit():
    # float32 targets carry ~1e-7 rad of rounding into their solutions: within 2e-6 rad of a
    # limit a solution counts as inside and is set onto the bound (never returned outside it)
    leg = robot("spot").leg("rear_right")  # knee upper limit -0.257725
    q = np.array([0.0, 0.0, -0.2577253], dtype=np.float32)  # 3e-7 inside the limit
    assert q[2] <= leg.limits[2, 1]
    assert leg.ik(leg.fk(q.astype(np.float64)))[1] == sk.Status.OK  # float64
    q_ik, status = leg.ik(leg.fk(q))
    assert status == sk.Status.OK, (status, q_ik)
    assert q_ik[2] <= np.float32(leg.limits[2, 1]) and abs(q_ik[2] - q[2]) < 2e-6


def test_unlimited_and_wide_limits_wrap_on_the_circle(rng):
    ct = robot("zoo").leg("CT")  # continuous hip and thigh, knee limits (-7, 7)
    q = rng.uniform(-12, 12, (2000, 3))
    solutions = ct.ik_all(ct.fk(q))
    assert solutions.valid.any(axis=1).all()
    error = circle(solutions.q - q[:, None, :]).max(axis=-1)
    assert (np.where(solutions.valid, error, np.inf).min(axis=1) < 1e-8).all()
    finite = solutions.q[solutions.exists]
    assert (np.abs(finite[:, :2]) <= np.pi).all() and (np.abs(finite[:, 2]) <= 7).all()


# --------------------------------------------------------------------------- 3. whole body


def stance(name: str, rng: np.random.Generator, noise: float = 0.02) -> np.ndarray:
    r = robot(name)
    return r.stance_feet(STANCE_HEIGHT[name]) + rng.normal(0, noise, (r.n_legs, 3))


@pytest.mark.parametrize("name", ["go2", "spot", "hexapod"])
def test_body_ik_reproduces_the_feet(name, rng):
    r = robot(name)
    n = r.n_legs
    feet = stance(name, rng)
    poses = random_poses(rng, STANCE_HEIGHT[name], (300,))
    q, status = r.body_ik(poses, feet)
    assert q.shape == (300, 3 * n) and status.shape == (300, n) and status.dtype == np.int8
    assert (status == sk.Status.OK).all()
    np.testing.assert_allclose(r.body_fk(poses, q), np.broadcast_to(feet, (300, n, 3)), rtol=0, atol=1e-12)
    # the same feet from each leg's URDF chain, with q read by joint name
    T = sk.body_transform(poses)
    for k, leg_name in enumerate(r.leg_names):
        cols = columns(name, leg_name)
        local = r.chain(leg_spec(name, leg_name).foot).fk(q[:, cols])[:, :3, 3]
        world = T[:, :3, 3] + np.einsum("nij,nj->ni", T[:, :3, :3], local)
        np.testing.assert_allclose(world, np.broadcast_to(feet[k], (300, 3)), rtol=0, atol=1e-12)
        # each leg is the leg IK of the foot in its hip frame
        p = np.einsum("nji,nj->ni", T[:, :3, :3], feet[k] - T[:, :3, 3]) - r.hip_positions[k]
        np.testing.assert_allclose(q[:, cols], r.leg(leg_name).ik(p)[0], rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["go2", "hexapod"])
def test_body_fk_matches_pinocchio(name, rng):
    r, pm = robot(name), pin_model(name)
    pd = pm.createData()
    T = random_pose_matrix(rng, STANCE_HEIGHT[name])
    for _ in range(10):
        q = rng.uniform(-2, 2, 3 * r.n_legs)
        pinocchio.framesForwardKinematics(pm, pd, pin_q(pm, dict(zip(r.leg_joint_names, q))))
        feet = [leg_spec(name, leg).foot for leg in r.leg_names]
        expected = [T[:3, :3] @ pin_frame(pm, pd, foot)[:3, 3] + T[:3, 3] for foot in feet]
        np.testing.assert_allclose(r.body_fk(T, q), expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["go2", "spot", "hexapod"])
def test_body_jacobian_matches_central_differences(name, rng):
    r = robot(name)
    n, step = r.n_legs, 1e-6
    feet = stance(name, rng)
    for _ in range(5):
        T = random_pose_matrix(rng, STANCE_HEIGHT[name])
        q = r.body_ik(T, feet).q
        J = r.body_jacobian(T, q)
        assert J.shape == (3 * n, 6 + 3 * n)
        fd = np.zeros_like(J)
        for k in range(6):
            e = np.zeros(6)
            e[k] = step
            fd[:, k] = (r.body_fk(twist_step(T, e), q) - r.body_fk(twist_step(T, -e), q)).ravel() / (2 * step)
        for k in range(3 * n):
            e = np.zeros(3 * n)
            e[k] = step
            fd[:, 6 + k] = (r.body_fk(T, q + e) - r.body_fk(T, q - e)).ravel() / (2 * step)
        np.testing.assert_allclose(J, fd, rtol=0, atol=1e-8)
        # d foot = v + w x (foot - t) + R J_leg dq, block by block
        R, t = T[:3, :3], T[:3, 3]
        world = r.body_fk(T, q)
        for i, leg_name in enumerate(r.leg_names):
            rows = slice(3 * i, 3 * i + 3)
            np.testing.assert_allclose(J[rows, :3], np.eye(3), atol=1e-15)
            r_i = world[i] - t
            skew = np.array([[0, r_i[2], -r_i[1]], [-r_i[2], 0, r_i[0]], [r_i[1], -r_i[0], 0]])
            np.testing.assert_allclose(J[rows, 3:6], skew, atol=1e-14)
            cols = columns(name, leg_name)
            leg_J = R @ r.leg(leg_name).jacobian(q[cols])
            np.testing.assert_allclose(J[rows][:, [6 + c for c in cols]], leg_J, atol=1e-14)
            others = np.delete(J[rows, 6:], cols, axis=1)
            np.testing.assert_array_equal(others, 0.0)


@pytest.mark.parametrize("batch", BATCHES, ids=str)
@pytest.mark.parametrize("name", ["go2", "hexapod"])
def test_body_batches_and_a_shared_stance(name, batch, rng):
    r = robot(name)
    n = r.n_legs
    feet = stance(name, rng)
    poses = random_poses(rng, STANCE_HEIGHT[name], batch)
    q, status = r.body_ik(poses, feet)
    assert q.shape == (*batch, 3 * n) and status.shape == (*batch, n)
    flat_q, flat_status = q.reshape(-1, 3 * n), status.reshape(-1, n)
    for k, pose in enumerate(poses.reshape(-1, 6)):
        single = r.body_ik(pose, feet)
        np.testing.assert_array_equal(flat_q[k], single.q)
        np.testing.assert_array_equal(flat_status[k], single.status)
    # one stance per pose, the same stance broadcast, and the slow path (fallback given) agree
    per_pose = np.broadcast_to(feet, (*batch, n, 3)).copy()
    np.testing.assert_array_equal(r.body_ik(poses, per_pose).q, q)
    np.testing.assert_array_equal(r.body_ik(poses, feet, fallback="nearest", seq="XYZ").q, q)
    np.testing.assert_array_equal(r.body_ik(poses, feet.tolist()).q, q)  # not an ndarray: the slow path
    assert r.body_fk(poses, q).shape == (*batch, n, 3)
    assert r.body_jacobian(poses, q).shape == (*batch, 3 * n, 6 + 3 * n)
    # float32 in, float32 out, close to float64
    q32, status32 = r.body_ik(poses.astype(np.float32), feet.astype(np.float32))
    assert q32.dtype == np.float32 and q32.shape == q.shape
    np.testing.assert_array_equal(status32, status)
    np.testing.assert_allclose(q32, q, rtol=0, atol=1e-3)


def test_body_broadcasting_poses_against_stances(rng):
    r = robot("hexapod")
    n = r.n_legs
    poses = random_poses(rng, 0.3, (4, 1))
    feet = np.stack([stance("hexapod", rng) for _ in range(3)])  # (3, n, 3)
    q, status = r.body_ik(poses, feet)
    assert q.shape == (4, 3, 3 * n) and status.shape == (4, 3, n)
    for i in range(4):
        for j in range(3):  # another code path than the broadcast one: equal to rounding
            single = r.body_ik(poses[i, 0], feet[j])
            np.testing.assert_allclose(q[i, j], single.q, rtol=0, atol=1e-14)
            np.testing.assert_array_equal(status[i, j], single.status)
    np.testing.assert_allclose(r.body_fk(poses, q), np.broadcast_to(feet, (4, 3, n, 3)), atol=1e-12)
    # a seed per pose picks the branch; q broadcasts against poses in body_fk
    seeded = r.body_ik(poses, feet, seed=q)
    np.testing.assert_allclose(seeded.q, q, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(seeded.status, status)
    np.testing.assert_allclose(r.body_fk(poses[0, 0], q[0]), feet, atol=1e-12)


@pytest.mark.parametrize("name", ["go2", "hexapod", "spot"])
def test_body_statuses_stay_in_their_leg_and_sample(name, rng):
    r = robot(name)
    n = r.n_legs
    feet = stance(name, rng, noise=0.01)
    poses = random_poses(rng, STANCE_HEIGHT[name], (5,))
    reference = r.body_ik(poses, feet)
    assert (reference.status == sk.Status.OK).all()
    for k in range(n):
        far = feet.copy()
        far[k, 2] -= 2.0
        q, status = r.body_ik(poses, far)
        expected = np.zeros((5, n), dtype=np.int8)
        expected[:, k] = sk.Status.UNREACHABLE
        np.testing.assert_array_equal(status, expected)
        cols = columns(name, r.leg_names[k])
        others = np.delete(np.arange(3 * n), cols)
        np.testing.assert_array_equal(q[:, others], reference.q[:, others])
        assert np.isfinite(q[:, cols]).all()  # the nearest in-limit configuration
        assert np.isnan(r.body_ik(poses, far, fallback="nan").q[:, cols]).all()
    bad = poses.copy()
    bad[2, 4] = np.nan
    q, status = r.body_ik(bad, feet)
    expected = np.zeros((5, n), dtype=np.int8)
    expected[2] = sk.Status.INVALID_INPUT
    np.testing.assert_array_equal(status, expected)
    assert np.isnan(q[2]).all()
    np.testing.assert_array_equal(np.delete(q, 2, axis=0), np.delete(reference.q, 2, axis=0))
    # a 4x4 whose rotation part is not a rotation: the same
    T = sk.body_transform(poses)
    T[1, :3, :3] *= 1.1
    status = r.body_ik(T, feet).status
    assert (status[1] == sk.Status.INVALID_INPUT).all() and (np.delete(status, 1, axis=0) == 0).all()
    # a NaN foot: INVALID_INPUT on that leg only
    nan_foot = feet.copy()
    nan_foot[0, 1] = np.nan
    status = r.body_ik(poses, nan_foot).status
    assert (status[:, 0] == sk.Status.INVALID_INPUT).all() and (status[:, 1:] == sk.Status.OK).all()


@pytest.mark.parametrize("name", ["go2", "hexapod"])
def test_body_wrong_shapes_name_the_argument(name):
    r = robot(name)
    n = r.n_legs
    pose = np.array([0, 0, STANCE_HEIGHT[name], 0, 0, 0])
    feet = r.stance_feet(STANCE_HEIGHT[name])
    for bad in (np.zeros((n + 1, 3)), np.zeros((n, 2)), np.zeros(3 * n), np.zeros((2, n, 3)) + feet):
        with pytest.raises(ValueError, match="feet"):
            r.body_ik(np.tile(pose, (3, 1)) if bad.ndim == 3 else pose, bad)
    for bad in (np.zeros(3 * n - 1), np.zeros((2, 3 * n))):
        with pytest.raises(ValueError, match="seed"):
            r.body_ik(np.tile(pose, (3, 1)), feet, seed=bad)
    for bad in (np.zeros(3 * n + 1), np.zeros((n, 3)), np.zeros((2, 3 * n))):
        with pytest.raises(ValueError, match="q"):
            r.body_fk(np.tile(pose, (3, 1)), bad)
        with pytest.raises(ValueError, match="q"):
            r.body_jacobian(np.tile(pose, (3, 1)), bad)
    with pytest.raises(ValueError, match="body_pose"):
        r.body_ik(np.zeros(5), feet)


# --------------------------------------------------------------------------- 4. Spot from its URDF


SDK_TO_URDF = {"fl": "front_left", "fr": "front_right", "hl": "rear_left", "hr": "rear_right"}


def test_spot_is_its_urdf():
    spot, from_urdf = sk.Spot(), sk.Robot.from_urdf(SPOT_URDF)
    assert spot.leg_names == ("fl", "fr", "hl", "hr")
    assert from_urdf.leg_names == tuple(SDK_TO_URDF.values())
    for sdk, leg in zip(spot.leg_names, spot.legs):
        other = from_urdf.leg(SDK_TO_URDF[sdk])
        for attr in ("a", "b", "c", "signs", "limits"):
            np.testing.assert_array_equal(getattr(leg, attr), getattr(other, attr), err_msg=f"{sdk}.{attr}")
        assert leg.preferred_slot == other.preferred_slot == 0
    np.testing.assert_array_equal(spot.hip_positions, from_urdf.hip_positions)
    np.testing.assert_array_equal(
        [leg.limits[2, 1] for leg in spot.legs], [-0.254801, -0.247563, -0.267153, -0.257725]
    )


def test_spot_is_built_through_robots_construction():
    """sk.Spot() goes through Robot's construction path (Robot._assemble) with the SDK's names and the
    arm's dedicated solver: what it recognises, reports and mounts is what Robot.from_urdf does."""
    spot, from_urdf = sk.Spot(), sk.Robot.from_urdf(SPOT_URDF)
    assert "_assemble" not in vars(type(spot)) and "_set_legs" not in vars(type(spot))
    assert set(spot.report) == set(from_urdf.report)
    np.testing.assert_array_equal(spot.arm_mount, from_urdf.arm_mount)
    assert [spec.name for spec in spot._specs[0]] == [SDK_TO_URDF[name] for name in spot.leg_names]
    assert spot.leg_joint_names == tuple(f"{leg}.{j}" for leg in spot.leg_names for j in ("hx", "hy", "kn"))
    assert isinstance(spot.arm, sk.SpotArm) and spot.arm.joint_names == spot.arm_joint_names


def test_spot_body_ik_is_its_urdf_robots(rng):
    spot, from_urdf = sk.Spot(), robot("spot")
    feet = spot.stance_feet(0.5)
    poses = np.array([0, 0, 0.5, 0, 0, 0]) + rng.normal(0, 1, (2000, 6)) * [0.1, 0.1, 0.1, 0.3, 0.3, 0.3]
    a, b = spot.body_ik(poses, feet), from_urdf.body_ik(poses, feet)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.status, b.status)
    assert (a.status == sk.Status.OK).mean() > 0.5 and (a.status != sk.Status.OK).any()
    np.testing.assert_array_equal(spot.body_fk(poses, a.q), from_urdf.body_fk(poses, a.q))


def test_spot_knee_limit_is_respected_by_the_fallback():
    q, status = sk.Spot().leg("hl").ik([0, 0.110945, -0.9])
    assert status == sk.Status.UNREACHABLE
    assert q[2] <= -0.267153 + 1e-12


def test_spot_from_the_model_dict_has_the_same_legs(rng):
    a, b = sk.Spot(), sk.Spot(sk.models.SPOT)
    assert a.leg_names == b.leg_names
    for x, y in zip(a.legs, b.legs):
        # the URDF's a is a difference of joint origins (0.165945 - 0.055): equal to 1e-17
        for attr in ("a", "b", "c"):
            np.testing.assert_allclose(getattr(x, attr), getattr(y, attr), rtol=0, atol=1e-15)
        np.testing.assert_array_equal(x.signs, y.signs)
        np.testing.assert_array_equal(x.limits, y.limits)
        assert x.preferred_slot == y.preferred_slot
    np.testing.assert_array_equal(a.hip_positions, b.hip_positions)
    feet = a.stance_feet(0.5)
    poses = np.array([0, 0, 0.5, 0, 0, 0]) + rng.normal(0, 0.05, (500, 6))
    qa, qb = a.body_ik(poses, feet), b.body_ik(poses, feet)
    np.testing.assert_array_equal(qa.status, qb.status)
    np.testing.assert_allclose(qa.q, qb.q, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- 5. Spot's arm from the URDF


def distinct(rows: np.ndarray, tolerance: float) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for row in rows:
        if all(circle(row - other).max() > tolerance for other in out):
            out.append(row)
    return out


def same_set(a: list[np.ndarray], b: list[np.ndarray], tolerance: float) -> bool:
    def within(x, rows):
        return any(circle(x - y).max() < tolerance for y in rows)

    return len(a) == len(b) and all(within(x, b) for x in a) and all(within(y, a) for y in b)


def test_spot_arm_chain_solutions_are_spot_arms(rng):
    arm, spot_arm = robot("spot").arm, sk.Spot().arm
    assert isinstance(arm, sk.Chain) and arm.ik_kind == "6R-spherical-wrist"
    np.testing.assert_array_equal(arm.lower, spot_arm.limits[:, 0])
    np.testing.assert_array_equal(arm.upper, spot_arm.limits[:, 1])
    limits = spot_arm.limits
    q = rng.uniform(limits[:, 0], limits[:, 1], (2000, 6))
    T = spot_arm.fk(q)
    np.testing.assert_allclose(arm.fk(q), T, rtol=0, atol=1e-14)  # both include the mount
    np.testing.assert_allclose(arm.jacobian(q), spot_arm.jacobian(q), rtol=0, atol=1e-13)
    chain_solutions, arm_solutions = arm.ik_all(T), spot_arm.ik_all(T)
    assert (chain_solutions.status == sk.Status.OK).all() and (arm_solutions.status == sk.Status.OK).all()
    tolerance = 1e-8
    for k in range(len(q)):
        a = distinct(chain_solutions.q[k][chain_solutions.valid[k]], tolerance)
        b = distinct(arm_solutions.q[k][arm_solutions.valid[k]], tolerance)
        assert same_set(a, b, tolerance), (k, q[k], a, b)
        assert any(circle(x - q[k]).max() < tolerance for x in a), (k, q[k])


# --------------------------------------------------------------------------- 6. pickling


def test_pickled_robots_solve_identically(rng):
    zoo = robot("zoo")
    bent = {"TW": (0.05, 0.3, 1.2), "FK": (0.05, -0.5, 1.2), "CT": (0.05, 0.5, -1.2), "RY": (0.05, 0.3, 1.2)}
    zoo_feet = np.array([zoo.hip_positions[k] + leg.fk(bent[leg.name]) for k, leg in enumerate(zoo.legs)])
    hexapod = sk.Robot.from_urdf_string(
        HEXAPOD,
        contact_offset=(0.0, 0.0, -0.02),
        nominal={"L2": (0.1, -0.3, 1.2)},  # knee forward
    )
    cases = [
        (robot("go2"), "RL_foot", robot("go2").stance_feet(0.28), random_poses(rng, 0.28, (50,))),
        (hexapod, "R2_foot", hexapod.stance_feet(0.28), random_poses(rng, 0.28, (50,))),
        (zoo, "YAW_foot", zoo_feet, rng.normal(0, 0.01, (50, 6))),
    ]
    for original, foot, feet, poses in cases:
        copy = pickle.loads(pickle.dumps(original))
        assert type(copy) is sk.Robot and copy is not original
        assert copy.name == original.name and copy.report == original.report
        assert copy.leg_names == original.leg_names and copy.leg_joint_names == original.leg_joint_names
        np.testing.assert_array_equal(copy.hip_positions, original.hip_positions)
        for x, y in zip(copy.legs, original.legs):
            for attr in ("a", "b", "c", "signs", "limits"):
                np.testing.assert_array_equal(getattr(x, attr), getattr(y, attr))
            assert x.preferred_slot == y.preferred_slot
        a, b = original.body_ik(poses, feet), copy.body_ik(poses, feet)
        assert (a.status == sk.Status.OK).mean() > 0.95
        np.testing.assert_array_equal(a.q, b.q)
        np.testing.assert_array_equal(a.status, b.status)
        q = rng.uniform(-1, 1, 3)
        np.testing.assert_array_equal(copy.chain(foot).fk(q), original.chain(foot).fk(q))
    # the options survive: the contact offset moves the feet, the nominal stance sets the slot
    np.testing.assert_allclose(hexapod.leg("L1").c, robot("hexapod").leg("L1").c + [0, 0, -0.02], atol=1e-15)
    assert hexapod.leg("L2").preferred_slot == 1 and robot("hexapod").leg("L2").preferred_slot == 0
    assert pickle.loads(pickle.dumps(hexapod)).leg("L2").preferred_slot == 1
