"""A quadruped carrying a UR/Z1-type arm (axes 2, 3, 4 parallel) from its URDF: ``robot.arm`` is a
closed-form 6R chain of the parallel family, solved with every branch and checked by FK round
trips and against the chain's own DH-free POE reference."""

from __future__ import annotations

import numpy as np

import spotkin as sk
from spotkin.reference import ik6r

# A Unitree Z1-like arm (its URDF's joint origins and axes, rounded), mounted on Go2's body.
Z1_JOINTS = [
    ("z1_joint1", "base", "z1_link01", "0.1 0 0.08", "0 0 1"),
    ("z1_joint2", "z1_link01", "z1_link02", "0 0 0.045", "0 1 0"),
    ("z1_joint3", "z1_link02", "z1_link03", "-0.35 0 0", "0 1 0"),
    ("z1_joint4", "z1_link03", "z1_link04", "0.218 0 0.057", "0 1 0"),
    ("z1_joint5", "z1_link04", "z1_link05", "0.07 0 0", "0 0 1"),
    ("z1_joint6", "z1_link05", "z1_link06", "0.0492 0 0", "1 0 0"),
]


def go2_with_z1() -> str:
    with open(sk.robots.path("go2"), encoding="utf-8") as file:
        text = file.read()
    parts = []
    for name, parent, child, xyz, axis in Z1_JOINTS:
        parts.append(
            f'<link name="{child}"><inertial><mass value="0.5"/><origin xyz="0 0 0"/>'
            f'<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>'
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="0 0 0"/><axis xyz="{axis}"/>'
            f'<limit lower="-2.9" upper="2.9" effort="30" velocity="3"/></joint>'
        )
    parts.append(
        '<link name="z1_gripper"/><joint name="z1_gripper_fixed" type="fixed"><parent link="z1_link06"/>'
        '<child link="z1_gripper"/><origin xyz="0.051 0 0" rpy="0 0 0"/></joint>'
    )
    end = text.rindex("</robot>")
    return text[:end] + "\n".join(parts) + "\n" + text[end:]


def test_quadruped_with_z1_has_a_closed_form_arm():
    robot = sk.Robot.from_urdf_string(go2_with_z1())
    arm = robot.arm
    assert arm is not None and arm.dof == 6
    assert arm.ik_kind == "6R-three-parallel-234"
    assert not arm.ik_idealised
    assert arm.ik_geometry["axes_5_6_gap"] < 1e-12  # the rank-1 form, as on the real Z1
    rng = np.random.default_rng(7)
    q = rng.uniform(-2.8, 2.8, (500, 6))
    T = arm.fk(q)
    sol = arm.ik_all(T)
    assert (sol.status == sk.Status.OK).all()
    assert (sol.exact == sol.exists).all()
    gap = np.abs(np.angle(np.exp(1j * (sol.q - q[:, None, :])))).max(axis=2)
    assert (np.where(sol.exists, gap, np.inf).min(axis=1) < 1e-7).all()
    # every solution reaches the pose, and the POE reference finds the same set
    found = sol.q[sol.exists]
    assert np.abs(arm.fk(found) - np.repeat(T, sol.exists.sum(axis=1), axis=0)).max() < 1e-9
    poe = ik6r.from_sk_chain(arm)
    for i in range(0, 500, 25):
        ref = ik6r.solve(poe, T[i])
        assert ref.exists.sum() == sol.exists[i].sum()
        for row in ref.q[ref.exists]:
            assert np.abs(np.angle(np.exp(1j * (sol.q[i][sol.exists[i]] - row)))).max(axis=1).min() < 1e-7
    # the nearest solution to a seed near the generating configuration is that configuration
    q_near, status = arm.ik(T, seed=q + 0.01)
    assert (status == sk.Status.OK).all()
    np.testing.assert_allclose(q_near, q, atol=1e-7)
