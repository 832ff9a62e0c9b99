"""The course's RRR arm, three-joint arm and classic-DH leg: FK vs sk.Chain and its formulas, IK, Jacobian."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from spotkin.reference import course_robots as cr

PI = math.pi
C, S = math.cos, math.sin

ROBOTS = {
    "rrr_001": (cr.rrr_001_fk, cr.rrr_001_ik, cr.rrr_001_dh, cr.RRR_001_LENGTHS),
    "arm_002": (cr.arm_002_fk, cr.arm_002_ik, cr.arm_002_dh, cr.ARM_002_LENGTHS),
    "leg_003": (cr.leg_003_fk, cr.leg_003_ik, cr.leg_003_dh, cr.LEG_003_LENGTHS),
}


def wrapped_gap(a, b) -> float:
    return float(np.max(np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))))


def random_lengths(rng, n):
    return tuple(rng.uniform(0.05, 1.0, n) * rng.choice([-1.0, 1.0], n))


# --- FK: spotkin.Chain and the printed closed forms ---------------------------------------------


@pytest.mark.parametrize("name", ROBOTS)
def test_fk_matches_spotkin_chain(name, rng):
    fk, _, table, lengths = ROBOTS[name]
    for L in (lengths, random_lengths(rng, len(lengths))):
        rows, base, tool = table(L)
        chain = sk.Chain.from_dh(rows, base=base, tool=tool)
        q = rng.uniform(-PI, PI, (200, 3))
        expected = np.stack([fk(qk, L) for qk in q])
        np.testing.assert_allclose(chain.fk(q), expected, rtol=0, atol=1e-13)


def test_leg_003_five_row_table_with_fixed_rows(rng):
    L = random_lengths(rng, 5)
    chain = sk.Chain.from_dh(cr.leg_003_dh_table(L))
    for q in rng.uniform(-PI, PI, (100, 3)):
        padded = [q[0], q[1], 0.0, q[2], 0.0]
        np.testing.assert_allclose(chain.fk(padded), cr.leg_003_fk(q, L), rtol=0, atol=1e-13)


def test_rrr_001_fk_is_the_printed_t40(rng):
    l1, l2, l3 = L = random_lengths(rng, 3)
    for q1, q2, q3 in rng.uniform(-PI, PI, (100, 3)):
        c1, s1, c2, s2 = C(q1), S(q1), C(q2), S(q2)
        c23, s23 = C(q2 + q3), S(q2 + q3)
        printed = np.array(
            [
                [c1 * c23, s1, c1 * s23, l3 * s23 * c1 + l2 * c1 * c2],
                [s1 * c23, -c1, s1 * s23, l3 * s23 * s1 + l2 * c2 * s1],
                [s23, 0, -c23, l1 - l3 * c23 + l2 * s2],
                [0, 0, 0, 1],
            ]
        )
        np.testing.assert_allclose(cr.rrr_001_fk((q1, q2, q3), L), printed, rtol=0, atol=1e-14)


def test_arm_002_fk_is_the_printed_t03(rng):
    a1, a2, a3 = L = random_lengths(rng, 3)
    for q1, q2, q3 in rng.uniform(-PI, PI, (100, 3)):
        C1, S1, C2, S2, C3, S3 = C(q1), S(q1), C(q2), S(q2), C(q3), S(q3)
        C23, S23 = C(q2 + q3), S(q2 + q3)
        printed = np.array(
            [
                [C1 * (C2 * C3 - S2 * S3), -C1 * (S2 * C3 + C2 * S3), S1, C1 * (-a2 * S2 + a3 * C23)],
                [S1 * (C2 * C3 - S2 * S3), -S1 * (S2 * C3 + C2 * S3), -C1, S1 * (-a2 * S2 + a3 * C23)],
                [S2 * C3 + S3 * C2, -S2 * S3 + C2 * C3, 0, a1 + a2 * C2 + a3 * S23],
                [0, 0, 0, 1],
            ]
        )
        np.testing.assert_allclose(cr.arm_002_fk((q1, q2, q3), L), printed, rtol=0, atol=1e-14)


def test_arm_002_sin_q3_formula_of_the_text(rng):
    a1, a2, a3 = L = random_lengths(rng, 3)
    for q in rng.uniform(-PI, PI, (100, 3)):
        x, y, z = cr.arm_002_fk(q, L)[:3, 3]
        s3 = (a1**2 - a2**2 - a3**2 + x**2 + y**2 + z**2 - 2 * a1 * z) / (2 * a2 * a3)
        assert abs(s3 - S(q[2])) < 1e-12


def test_leg_003_fk_is_the_printed_mgd(rng):
    h1, h2, h3, l2, l3 = L = random_lengths(rng, 5)
    for q1, q2, q3 in rng.uniform(-PI, PI, (100, 3)):
        inner = l3 * S(q2 + q3) + l2 * S(q2)
        printed = [
            C(q1) * inner - S(q1) * (h2 + h3),
            C(q1) * (h2 + h3) + S(q1) * inner,
            h1 + l3 * C(q2 + q3) + l2 * C(q2),
        ]
        np.testing.assert_allclose(cr.leg_003_fk((q1, q2, q3), L)[:3, 3], printed, rtol=0, atol=1e-14)


# --- IK round trips -----------------------------------------------------------------------------


def check_round_trip(fk, ik, q, L, tol_p=1e-10):
    p = fk(q, L)[:3, 3]
    sols, valid = ik(p, L)
    assert sols.shape == (4, 3) and valid.shape == (4,)
    assert valid.all()
    for s in sols:
        np.testing.assert_allclose(fk(s, L)[:3, 3], p, rtol=0, atol=tol_p)
        assert np.all(sols > -PI) and np.all(sols <= PI)
    assert min(wrapped_gap(s, q) for s in sols) < 1e-7


@pytest.mark.parametrize("name", ROBOTS)
def test_ik_round_trip(name, rng):
    fk, ik, _, lengths = ROBOTS[name]
    for k in range(400):
        L = lengths if k % 2 else random_lengths(rng, len(lengths))
        check_round_trip(fk, ik, rng.uniform(-PI, PI, 3), L)


@pytest.mark.parametrize("name", ROBOTS)
def test_ik_solutions_are_distinct_in_general(name, rng):
    fk, ik, _, lengths = ROBOTS[name]
    sols, valid = ik(fk(rng.uniform(-PI, PI, 3), lengths)[:3, 3], lengths)
    assert valid.all()
    for i in range(4):
        for j in range(i):
            assert wrapped_gap(sols[i], sols[j]) > 1e-6


@given(q=st.lists(st.floats(-PI, PI), min_size=3, max_size=3))
def test_ik_round_trip_property(q):
    for fk, ik, _, lengths in ROBOTS.values():
        p = fk(q, lengths)[:3, 3]
        sols, valid = ik(p, lengths)
        for s, ok in zip(sols, valid):
            if ok:
                np.testing.assert_allclose(fk(s, lengths)[:3, 3], p, rtol=0, atol=1e-9)


def test_arm_002_no_hole_at_45_degrees(rng):
    for q1 in (PI / 4, -3 * PI / 4):
        for q23 in rng.uniform(-PI, PI, (20, 2)):
            check_round_trip(cr.arm_002_fk, cr.arm_002_ik, np.array([q1, *q23]), cr.ARM_002_LENGTHS)


def test_unreachable_targets_have_no_solution():
    l1, l2, l3 = cr.RRR_001_LENGTHS
    assert not cr.rrr_001_ik((0.0, 0.0, l1 + l2 + l3 + 0.01))[1].any()
    a1, a2, a3 = cr.ARM_002_LENGTHS
    assert not cr.arm_002_ik((a2 + a3 + 0.01, 0.0, a1))[1].any()
    _, h2, h3, _, _ = cr.LEG_003_LENGTHS
    r = 0.9 * abs(h2 + h3)  # x^2 + y^2 < (h2 + h3)^2: type 2 in q1 has no root
    assert not cr.leg_003_ik((r, 0.0, 0.0))[1].any()


# --- The course's RRR arm worked example ----------------------------------------------------------------


@pytest.mark.parametrize("lengths", [cr.RRR_001_LENGTHS, cr.RRR_001_STATED_LENGTHS])
def test_rrr_001_worked_target_has_four_solutions(lengths):
    p = np.array([1.0, 1.1, 1.2])
    sols, valid = cr.rrr_001_ik(p, lengths)
    assert valid.all()
    for s in sols:
        np.testing.assert_allclose(cr.rrr_001_fk(s, lengths)[:3, 3], p, rtol=0, atol=1e-12)
    theta1 = math.atan2(1.1, 1.0)
    # the text prints 0.8329810667 rad, one digit off (0.83298126...); its 47.72631098 deg is right
    assert abs(theta1 - 0.8329810667) < 3e-7
    assert abs(math.degrees(theta1) - 47.72631098) < 1e-7
    gaps = sorted(min(abs(s[0] - theta1), abs(s[0] - (theta1 - PI))) for s in sols)
    assert gaps[-1] < 1e-14
    assert sum(abs(s[0] - theta1) < 1e-14 for s in sols) == 2  # text's branch
    assert sum(abs(s[0] - (theta1 - PI)) < 1e-14 for s in sols) == 2  # theta1 + pi, missed by the text


def test_rrr_001_worked_theta2_matches_the_text_with_its_lengths():
    sols, _ = cr.rrr_001_ik((1.0, 1.1, 1.2), cr.RRR_001_LENGTHS)
    on_text_branch = sorted(s[1] for s in sols if abs(s[0] - math.atan2(1.1, 1.0)) < 1e-12)
    # the text rounds its coefficients (3,12186 / 0,42 / 2,56038), hence 1e-4
    np.testing.assert_allclose(on_text_branch, [-0.48808245312, 0.75554685412], rtol=0, atol=1e-4)


def test_rrr_001_printed_answer_fails_fk():
    for q_deg in ((47.72, 43.28, -11.0), (47.72, -27.96, 11.0)):
        reached = cr.rrr_001_fk(np.radians(q_deg))[:3, 3]
        assert np.linalg.norm(reached - [1.0, 1.1, 1.2]) > 0.2


# --- The course's classic-DH leg: Jacobian ----------------------------------------------------------------


def test_leg_003_jacobian_central_differences(rng):
    h = 1e-6
    for k in range(200):
        L = cr.LEG_003_LENGTHS if k % 2 else random_lengths(rng, 5)
        q = rng.uniform(-PI, PI, 3)
        fd = np.empty((3, 3))
        for j in range(3):
            dq = np.zeros(3)
            dq[j] = h
            fd[:, j] = (cr.leg_003_fk(q + dq, L)[:3, 3] - cr.leg_003_fk(q - dq, L)[:3, 3]) / (2 * h)
        np.testing.assert_allclose(cr.leg_003_jacobian(q, L), fd, rtol=0, atol=1e-9)


def test_leg_003_jacobian_matches_spotkin_chain(rng):
    L = random_lengths(rng, 5)
    rows, base, tool = cr.leg_003_dh(L)
    chain = sk.Chain.from_dh(rows, base=base, tool=tool)
    q = rng.uniform(-PI, PI, (200, 3))
    expected = np.stack([cr.leg_003_jacobian(qk, L) for qk in q])
    np.testing.assert_allclose(chain.position_jacobian(q), expected, rtol=0, atol=1e-13)


def test_leg_003_df1_dq3_is_not_zero():
    q = (0.3, 0.4, 0.5)
    J = cr.leg_003_jacobian(q)
    _, _, _, _, l3 = cr.LEG_003_LENGTHS
    assert abs(J[0, 2] - C(0.3) * l3 * C(0.9)) < 1e-15
    assert abs(J[0, 2]) > 0.05
