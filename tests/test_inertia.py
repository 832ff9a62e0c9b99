"""Link inertials: Chain.with_inertials (checks, copies, pickling), the merging of fixed children and
locked branches against hand-computed parallel-axis numbers, the trees of chains and robots."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from urdf_helpers import joint

import spotkin as sk
from spotkin import inertia
from spotkin import urdf as su
from spotkin.reference import dynamics as rd

ROD = np.diag([0.0, 1.0, 1.0]) / 12  # a 1 kg, 1 m rod along x, about its centre


def inertial(mass, xyz="0 0 0", rpy="0 0 0", diagonal=(0, 0, 0)) -> str:
    ixx, iyy, izz = diagonal
    return (
        f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{mass}"/>'
        f'<inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>'
    )


def link(name, body="") -> str:
    return f'<link name="{name}">{body}</link>'


HALF_PI = "1.5707963267948966"

# base (5 kg) -j1 (revolute z)-> link1 (2 kg at (0.1, 0, 0), diag(0.01, 0.02, 0.03) yawed by 90°)
#   -fixed (at (0.2, 0, 0), yawed by 90°)-> tool1 (1 kg at (0.1, 0, 0.05) in its frame,
#                                                  diag(0.001, 0.002, 0.003))
#   -finger (continuous x, at (0, 0.3, 0))-> finger (0.5 kg point mass at its origin)
MERGE = (
    '<robot name="merge">'
    + link("base", inertial(5, "0 0 0.1", diagonal=(1, 1, 1)))
    + link("link1", inertial(2, "0.1 0 0", f"0 0 {HALF_PI}", (0.01, 0.02, 0.03)))
    + link("tool1", inertial(1, "0.1 0 0.05", diagonal=(0.001, 0.002, 0.003)))
    + link("finger", inertial(0.5))
    + joint("j1", "revolute", "base", "link1", "0 0 0.1", axis="0 0 1", limits=(-1, 1))
    + joint("fix", "fixed", "link1", "tool1", "0.2 0 0", f"0 0 {HALF_PI}")
    + joint("finger_joint", "continuous", "link1", "finger", "0 0.3 0", axis="1 0 0")
    + "</robot>"
)


def test_fixed_child_merges_by_the_parallel_axis_theorem():
    model = su.parse_urdf(MERGE)
    tree = inertia.model_tree(model, "base", ["j1", "finger_joint"], floating=False)
    # link1 + tool1 (the finger moves on its own). tool1's centre of mass in link1's frame: the yaw
    # maps (0.1, 0, 0.05) to (0, 0.1, 0.05), plus (0.2, 0, 0).
    assert tree.inertials.mass[0] == pytest.approx(3.0)
    np.testing.assert_allclose(tree.inertials.com[0], [0.4 / 3, 0.1 / 3, 0.05 / 3], atol=1e-15)
    # own inertias rotated (yaw 90° swaps x and y): diag(0.02, 0.01, 0.03) + diag(0.002, 0.001, 0.003);
    # parallel axis: the reduced mass 2/3 times (|r|² E - r r^T), r = (0.1, 0.1, 0.05) between the parts
    expected = np.array(
        [
            [0.02 + 0.002 + 1 / 120, -1 / 150, -1 / 300],
            [-1 / 150, 0.01 + 0.001 + 1 / 120, -1 / 300],
            [-1 / 300, -1 / 300, 0.03 + 0.003 + 1 / 75],
        ]
    )
    np.testing.assert_allclose(tree.inertials.inertia[0], expected, atol=1e-15)
    assert tree.inertials.mass[1] == 0.5
    np.testing.assert_allclose(tree.placements[1][:3, 3], [0, 0.3, 0])
    assert list(tree.parents) == [-1, 0]
    assert tree.root is None


def test_locked_branch_merges_into_the_body_it_hangs_from():
    model = su.parse_urdf(MERGE)
    tree = inertia.model_tree(model, "base", ["j1"], floating=False)
    assert tree.inertials.mass[0] == pytest.approx(3.5)
    centre = (2 * np.array([0.1, 0, 0]) + np.array([0.2, 0.1, 0.05]) + 0.5 * np.array([0, 0.3, 0])) / 3.5
    np.testing.assert_allclose(tree.inertials.com[0], centre, atol=1e-15)
    floating = inertia.model_tree(model, "base", ["j1"], floating=True)
    assert float(floating.root.mass) == 5.0
    np.testing.assert_allclose(floating.root.com, [0, 0, 0.1])
    np.testing.assert_allclose(floating.root.inertia, np.eye(3))
    # the finger as the moving joint: link1 and tool1 are then fixed to the base, out of a fixed base
    alone = inertia.model_tree(model, "base", ["finger_joint"], floating=False)
    assert alone.inertials.mass.tolist() == [0.5]
    np.testing.assert_allclose(alone.placements[0][:3, 3], [0, 0.3, 0.1])


def test_merge_inertials_massless_and_single():
    mass, com, matrix = inertia.merge_inertials([])
    assert mass == 0 and not com.any() and not matrix.any()
    T = sk.rotation_z(0.5) @ sk.translation([1, 2, 3])
    mass, com, matrix = inertia.merge_inertials([(T, 2.0, [0.1, 0, 0], ROD)])
    np.testing.assert_allclose(com, T[:3, :3] @ [0.1, 0, 0] + T[:3, 3])
    np.testing.assert_allclose(matrix, T[:3, :3] @ ROD @ T[:3, :3].T, atol=1e-16)


# --------------------------------------------------------------------------- Chain.with_inertials

RODS = (np.ones(3), np.tile([-0.5, 0.0, 0.0], (3, 1)), np.tile(ROD, (3, 1, 1)))


def three_joint_chain():
    return sk.Chain.from_mdh(
        [[0, 0, 0, 0, 0], [0, 1, 0, 0, 0], [0, 1, 0, 0, 0]], tool=sk.translation([1, 0, 0])
    )


def test_with_inertials_copies_and_keeps_the_original():
    chain = three_joint_chain()
    assert chain.inertials is None
    loaded = chain.with_inertials(*RODS)
    assert chain.inertials is None and loaded is not chain
    assert isinstance(loaded.inertials, sk.LinkInertials)
    for got, given in zip(loaded.inertials, RODS):
        np.testing.assert_array_equal(got, given)
        assert not got.flags.writeable
    q = np.array([0.1, 0.2, 0.3])
    np.testing.assert_array_equal(loaded.fk(q), chain.fk(q))
    lists = chain.with_inertials([1, 1, 1], RODS[1].tolist(), RODS[2].tolist())
    np.testing.assert_array_equal(lists.inertials.inertia, RODS[2])


def test_inertials_survive_pickling_and_ik_tolerance():
    chain = three_joint_chain().with_inertials(*RODS)
    for other in (pickle.loads(pickle.dumps(chain)), chain.with_ik_tolerance(1e-3, 1e-3)):
        np.testing.assert_array_equal(other.inertials.com, RODS[1])
    both = pickle.loads(pickle.dumps(chain.with_ik_tolerance(2e-3, 1e-3)))
    np.testing.assert_array_equal(both.inertials.inertia, RODS[2])
    assert both._ik_tolerance == (2e-3, 1e-3)
    urdf_chain = sk.Robot.from_urdf(sk.robots.path("go2")).chain("FL_foot")
    again = pickle.loads(pickle.dumps(urdf_chain))
    np.testing.assert_array_equal(again.inertials.mass, urdf_chain.inertials.mass)
    assert again.joint_names == urdf_chain.joint_names


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        ({"mass": np.ones(2)}, ValueError, "mass must have shape (3,)"),
        ({"mass": -np.ones(3)}, ValueError, "mass must be >= 0"),
        ({"mass": [1, np.nan, 1]}, ValueError, "mass must be finite"),
        ({"mass": "abc"}, TypeError, "mass"),
        ({"com": np.zeros((3, 2))}, ValueError, "com must have shape (3, 3)"),
        ({"com": None}, TypeError, "com"),
        ({"com": np.zeros((3, 3)) + 1j}, TypeError, "com"),
        ({"inertia": np.zeros((3, 3))}, ValueError, "inertia must have shape (3, 3, 3)"),
        (
            {"inertia": np.tile(np.array([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), (3, 1, 1))},
            ValueError,
            "symmetric",
        ),
        ({"inertia": np.tile(np.diag([1.0, -1.0, 1.0]), (3, 1, 1))}, ValueError, "positive semidefinite"),
        ({"inertia": np.ma.masked_array(RODS[2])}, TypeError, "inertia"),
    ],
)
def test_with_inertials_rejects_bad_input(kwargs, error, words):
    arguments = dict(zip(("mass", "com", "inertia"), RODS))
    arguments.update(kwargs)
    with pytest.raises(error, match=words.replace("(", r"\(").replace(")", r"\)")):
        three_joint_chain().with_inertials(**arguments)


# --------------------------------------------------------------------------- trees


def rigid(rotation, translation):
    T = np.eye(4)
    T[:3, :3] = rotation
    T[:3, 3] = translation
    return T


@pytest.mark.parametrize("convention", ["mdh", "dh", "joints"])
def test_chain_tree_puts_each_body_on_frame_j_plus_1(convention, rng):
    """The tree's centre of mass equals the one from Chain.frames (the compiled FK) and the contract:
    body j in frame j + 1."""
    rows = np.array([[0, 0.1, 0.3, 0.2, 0.1], [1, 0.3, -0.7, 0.1, 0.4], [0, 0.2, 1.2, -0.1, -0.3]])
    base = rigid(sk.rotation_x(0.3)[:3, :3] @ sk.rotation_z(-0.5)[:3, :3], [0.1, -0.2, 0.3])
    if convention == "joints":
        placements = np.stack([rigid(sk.rotation_x(a)[:3, :3], [a, 0.1, -a]) for a in (0.2, -0.4, 0.9)])
        chain = sk.Chain.from_joints(placements, [[0, 0, 2], [1, 1, 0], [0, -1, 1]], [0, 1, 0], base=base)
    else:
        chain = getattr(sk.Chain, f"from_{convention}")(rows, base=base)
    mass = np.array([1.0, 2.0, 0.5])
    com = rng.normal(0, 0.2, (3, 3))
    loaded = chain.with_inertials(mass, com, np.tile(ROD, (3, 1, 1)))
    tree = inertia.tree_of(loaded)
    for _ in range(5):
        q = rng.uniform(-1, 1, 3)
        F = chain.frames(q)
        expected = sum(
            m * (F[j + 1][:3, :3] @ c + F[j + 1][:3, 3]) for j, (m, c) in enumerate(zip(mass, com))
        )
        np.testing.assert_allclose(rd.center_of_mass(tree, q), expected / mass.sum(), atol=1e-12)


def test_tree_of_rejects_what_it_cannot_describe():
    with pytest.raises(ValueError, match="no inertials"):
        inertia.tree_of(three_joint_chain())
    with pytest.raises(TypeError, match=r"spotkin\.Chain or spotkin\.Robot"):
        inertia.tree_of("go2")
    with pytest.raises(ValueError, match="joints is for robots"):
        inertia.tree_of(three_joint_chain().with_inertials(*RODS), joints=["a"])


def test_robot_chain_inertials_follow_the_merging_rule():
    """Go2's rotors hang off each leg by fixed joints: a leg chain's bodies carry them, and the hip
    rotor (fixed to the body) is not part of the leg chain. Masses from the file: hip 0.678, thigh
    1.152, calf 0.154, foot 0.04, rotors 0.089 each."""
    robot = sk.Robot.from_urdf(sk.robots.path("go2"))
    chain = robot.chain("FL_foot")
    np.testing.assert_allclose(chain.inertials.mass, [0.678 + 0.089, 1.152 + 0.089, 0.154 + 0.04])
    total = robot.body_inertial.mass + sum(
        robot.chain(f"{leg}_foot").inertials.mass.sum() for leg in robot.leg_names
    )
    model = robot.model
    assert total == pytest.approx(sum(link.inertial.mass for link in model.links.values() if link.inertial))
    # Spot's gripper finger is locked into the wrist body of the arm chain
    spot = sk.Robot.from_urdf(sk.robots.path("spot_with_arm"))
    arm = spot.chain("arm_hand")
    assert arm.inertials.mass[-1] == pytest.approx(0.785 + 0.2)
    finger = spot.chain("arm_link_fngr")
    assert finger.inertials.mass[-2:] == pytest.approx([0.785, 0.2])


def test_robot_tree_order_and_feet():
    spot = sk.Spot()
    tree = inertia.tree_of(spot)
    names = spot.joint_names + spot.arm_joint_names
    aliases = spot._joint_aliases()
    assert tuple(aliases[name] for name in tree.joint_names) == names
    assert tree.foot_names == spot.leg_names
    assert float(spot.body_inertial.mass) == pytest.approx(32.86)
    legs_only = inertia.tree_of(spot, joints=spot.joint_names)  # the arm locked into the body
    assert float(legs_only.root.mass) == pytest.approx(
        32.86 + 2.3364 + 0.2596 + 0.725 * 2 + 0.98 + 0.785 + 0.2
    )
    for k, leg in enumerate(spot.leg_names):
        q = np.zeros(len(tree.joint_names))
        foot = sk.Spot().body_fk(np.zeros(6), np.zeros(12))[k]
        body = tree.feet[k]
        world = np.eye(4)
        chain = []
        while body >= 0:
            chain.append(body)
            body = tree.parents[body]
        for j in reversed(chain):
            world = world @ tree.placements[j]
        np.testing.assert_allclose(world[:3, :3] @ tree.foot_points[k] + world[:3, 3], foot, atol=1e-12)
        assert leg in tree.foot_names and q.shape == (18,)


def test_parsed_inertial_rpy_is_kept_in_the_link_frame():
    model = su.parse_urdf(MERGE)
    R = model.link("link1").inertial.rotation
    assert math.isclose(R[1, 0], 1.0, abs_tol=1e-15)  # yaw 90°: x -> y
