"""Chains from the course (its Spot problem and summary sheet), and Jacobians against finite differences."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk
from conftest import random_rigid, random_table, vee_so3

H1, H2, H3 = 0.110945, 0.3205, 0.3365


def course_leg() -> sk.Chain:
    """The course's Spot problem: DHm rows (d, alpha, r, theta), foot at (h3, 0, 0) in frame 3."""
    return sk.Chain.from_mdh(
        [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, H1, 0.0), (0, H2, 0.0, 0.0, 0.0)],
        tool=sk.translation([H3, 0.0, 0.0]),
    )


def test_course_leg_fk_is_the_closed_form_of_q14(rng):
    th = rng.uniform(-np.pi, np.pi, (500, 3))
    t1, t2, t3 = th.T
    planar = H3 * np.cos(t2 + t3) + H2 * np.cos(t2)
    expected = np.stack(
        [
            planar * np.cos(t1) + H1 * np.sin(t1),
            H3 * np.sin(t2 + t3) + H2 * np.sin(t2),
            -planar * np.sin(t1) + H1 * np.cos(t1),
        ],
        axis=-1,
    )
    np.testing.assert_allclose(course_leg().fk(th)[:, :3, 3], expected, rtol=0, atol=1e-14)


def test_course_leg_jacobian_determinant(rng):
    th = rng.uniform(-np.pi, np.pi, (500, 3))
    _, t2, t3 = th.T
    expected = -H2 * H3 * np.sin(t3) * (H2 * np.cos(t2) + H3 * np.cos(t2 + t3))
    det = np.linalg.det(course_leg().position_jacobian(th))
    np.testing.assert_allclose(det, expected, rtol=0, atol=1e-14)


def test_course_leg_both_singular_sets_drop_rank():
    leg = course_leg()
    stretched = [0.3, 0.7, 0.0]  # sin(th3) = 0
    t2 = 0.4  # h2 cos(t2) + h3 cos(t2 + t3) = 0
    over_axis = [0.3, t2, np.arccos(-H2 * np.cos(t2) / H3) - t2]
    for q in (stretched, over_axis):
        assert abs(np.linalg.det(leg.position_jacobian(q))) < 1e-15
        assert np.linalg.svd(leg.position_jacobian(q), compute_uv=False)[-1] < 1e-14


def test_seed004_rrr_jacobian_example(rng):
    # T01 = RotZ(q1); T12: alpha = +90 deg; T23: d = a. Jacobian of O3 (the course's summary sheet).
    a = 0.7
    rrr = sk.Chain.from_mdh([(0, 0, 0, 0, 0), (0, 0, np.pi / 2, 0, 0), (0, a, 0, 0, 0)])
    q = rng.uniform(-np.pi, np.pi, (200, 3))
    s1, c1, s2, c2 = np.sin(q[:, 0]), np.cos(q[:, 0]), np.sin(q[:, 1]), np.cos(q[:, 1])
    zero = np.zeros_like(s1)
    linear = np.stack(
        [
            np.stack([-a * s1 * c2, -a * c1 * s2, zero], -1),
            np.stack([a * c1 * c2, -a * s1 * s2, zero], -1),
            np.stack([zero, a * c2, zero], -1),
        ],
        -2,
    )
    J = rrr.jacobian(q)
    np.testing.assert_allclose(J[:, :3], linear, rtol=0, atol=1e-15)
    np.testing.assert_allclose(J[:, 3:, 0], np.tile([0, 0, 1.0], (200, 1)), atol=1e-15)
    np.testing.assert_allclose(J[:, 3:, 1], np.stack([s1, -c1, zero], -1), atol=1e-15)


def test_seed004_rrprr_prismatic_column(rng):
    rows = random_table(rng, 5, prismatic=False)
    rows[2, 0] = 1  # RRPRR
    chain = sk.Chain.from_mdh(rows, tool=random_rigid(rng))
    q = rng.uniform(-1, 1, (50, 5))
    J = chain.jacobian(q)
    F = chain.frames(q)
    np.testing.assert_allclose(J[:, :3, 2], F[:, 3, :3, 2], atol=1e-15)  # z_3 of frame 3 (DHm)
    np.testing.assert_array_equal(J[:, 3:, 2], 0.0)
    np.testing.assert_allclose(
        J[:, :3, 4], np.cross(F[:, 5, :3, 2], F[:, 6, :3, 3] - F[:, 5, :3, 3]), atol=1e-14
    )


def finite_difference_jacobian(chain: sk.Chain, q: np.ndarray, step: float = 1e-6) -> np.ndarray:
    J = np.zeros((6, chain.dof))
    for j in range(chain.dof):
        dq = np.zeros(chain.dof)
        dq[j] = step
        plus, minus = chain.fk(q + dq), chain.fk(q - dq)
        J[:3, j] = (plus[:3, 3] - minus[:3, 3]) / (2 * step)
        dR = (plus[:3, :3] - minus[:3, :3]) / (2 * step)
        J[3:, j] = vee_so3(dR @ chain.fk(q)[:3, :3].T)
    return J


@pytest.mark.parametrize("convention", ["mdh", "dh"])
@pytest.mark.parametrize("dof", [3, 6, 12])
def test_jacobian_matches_central_differences(rng, convention, dof):
    for _ in range(10):
        chain = sk.Chain(
            random_table(rng, dof), convention=convention, base=random_rigid(rng), tool=random_rigid(rng)
        )
        q = rng.uniform(-np.pi, np.pi, dof)
        np.testing.assert_allclose(chain.jacobian(q), finite_difference_jacobian(chain, q), rtol=0, atol=1e-8)


def test_tool_frame_jacobian_rotates_both_blocks(rng):
    chain = sk.Chain.from_dh(random_table(rng, 6), tool=random_rigid(rng))
    q = rng.uniform(-np.pi, np.pi, (10, 6))
    R = chain.fk(q)[:, :3, :3]
    J, J_tool = chain.jacobian(q), chain.jacobian(q, frame="tool")
    np.testing.assert_allclose(R @ J_tool[:, :3], J[:, :3], atol=1e-14)
    np.testing.assert_allclose(R @ J_tool[:, 3:], J[:, 3:], atol=1e-14)


def test_classic_dh_joint_turns_about_previous_z(rng):
    # Classic DH with one revolute joint about the base z axis: a rotation about z0.
    chain = sk.Chain.from_dh([(0, 0.5, 0.3, 0.2, 0.0)])
    q = 0.8
    T = chain.fk([q])
    expected = (
        sk.rotation_z(q) @ sk.translation([0, 0, 0.2]) @ sk.translation([0.5, 0, 0]) @ sk.rotation_x(0.3)
    )
    np.testing.assert_allclose(T, expected, atol=1e-15)
    np.testing.assert_allclose(chain.jacobian([q])[3:, 0], [0, 0, 1], atol=1e-15)
