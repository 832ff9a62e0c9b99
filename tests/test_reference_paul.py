"""Paul's equation types 2, 3 and 6 (the course's Spot problem, appendix), built from known roots."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from spotkin.reference.paul import type2, type3, type6

PI = math.pi
angles = st.floats(-PI, PI, allow_nan=False)
coefs = st.floats(-2.0, 2.0, allow_nan=False)


def angle_gap(a: float, b: float) -> float:
    """Distance between two angles on the circle."""
    return abs(math.remainder(a - b, 2 * PI))


def residual2(X, Y, Z, t):
    return X * math.sin(t) + Y * math.cos(t) - Z


def contains(roots, valid, t, tol=1e-8) -> bool:
    return any(v and angle_gap(r, t) < tol for r, v in zip(roots, valid))


# --- type 2: the appendix table, case by case ------------------------------------------------------


@pytest.mark.parametrize(
    ("X", "Y", "Z", "expected"),
    [
        (0.0, 2.0, 1.0, {PI / 3, -PI / 3}),  # X = 0: cos t = 1/2
        (0.0, -2.0, 1.0, {2 * PI / 3, -2 * PI / 3}),  # X = 0: cos t = -1/2
        (2.0, 0.0, 1.0, {PI / 6, 5 * PI / 6}),  # Y = 0: sin t = 1/2
        (-2.0, 0.0, 1.0, {-PI / 6, -5 * PI / 6}),  # Y = 0: sin t = -1/2
        (1.0, 1.0, 0.0, {-PI / 4, 3 * PI / 4}),  # Z = 0: atan2(-Y, X) and + pi
        (-1.0, math.sqrt(3), 0.0, {PI / 3, -2 * PI / 3}),  # Z = 0: tan t = sqrt(3)
        (1.0, 1.0, 1.0, {0.0, PI / 2}),  # general
        (math.sqrt(3), 1.0, 1.0, {0.0, 2 * PI / 3}),  # general: 2 sin(t + 30deg) = 1
    ],
)
def test_type2_appendix_cases(X, Y, Z, expected):
    roots, valid = type2(X, Y, Z)
    assert valid.all()
    assert len(expected) == 2
    for t in expected:
        assert contains(roots, valid, t, 1e-14)


def test_type2_no_solution_when_x2_y2_below_z2():
    for X, Y, Z in [(1.0, 1.0, 2.0), (0.0, 1.0, 1.5), (1.0, 0.0, -1.5), (0.3, -0.4, 0.5000001)]:
        roots, valid = type2(X, Y, Z)
        assert not valid.any()
        assert np.isnan(roots).all()


def test_type2_x_y_zero():
    roots, valid = type2(0.0, 0.0, 0.5)
    assert not valid.any() and np.isnan(roots).all()
    roots, valid = type2(0.0, 0.0, 0.0)  # identity: every angle; t = 0 twice
    assert valid.all()
    np.testing.assert_array_equal(roots, [0.0, 0.0])


def test_type2_touching_gives_a_double_root():
    expected = math.atan2(3.0, 4.0)  # 3 sin t + 4 cos t = 5 at sin t = 3/5, cos t = 4/5
    for Z in (5.0, 5.0 * (1 + 1e-14)):
        roots, valid = type2(3.0, 4.0, Z)
        assert valid.all()
        np.testing.assert_allclose(roots, [expected, expected], rtol=0, atol=1e-12)
    assert not type2(3.0, 4.0, 5.0 * (1 + 1e-9))[1].any()  # beyond the 1e-12 tolerance


def test_type2_angles_in_half_open_interval():
    roots, valid = type2(0.0, 1.0, -1.0)  # cos t = -1: t = pi, never -pi
    assert valid.all()
    np.testing.assert_array_equal(roots, [PI, PI])
    roots, _ = type2(-1.0, 0.0, 0.0)  # sin t = 0: 0 and pi
    assert set(np.round(roots, 15)) == {0.0, PI}


def test_type2_root_order_is_plus_sqrt_first(rng):
    """Root k is atan2 of the eps = +1 / -1 formula, including the special-case branches."""
    cases = [(0.0, 1.3, 0.4), (0.0, -1.3, 0.4), (0.7, 0.0, -0.2), (-0.7, 0.0, -0.2), (1.1, -0.6, 0.0)]
    cases += [tuple(rng.uniform(-1, 1, 2)) + (rng.uniform(-0.5, 0.5),) for _ in range(50)]
    for X, Y, Z in cases:
        roots, valid = type2(X, Y, Z)
        r2 = X * X + Y * Y
        D = r2 - Z * Z
        if D <= 0:
            continue
        assert valid.all()
        for k, eps in enumerate((1, -1)):
            c = (Y * Z - eps * X * math.sqrt(D)) / r2
            s = (X * Z + eps * Y * math.sqrt(D)) / r2
            assert angle_gap(roots[k], math.atan2(s, c)) < 1e-13


def test_type2_random_equations_from_known_roots(rng):
    for _ in range(2000):
        t = rng.uniform(-PI, PI)
        X, Y = rng.uniform(-2, 2, 2)
        if abs(X * math.cos(t) - Y * math.sin(t)) < 1e-3:  # near the double root: ill-conditioned
            continue
        Z = X * math.sin(t) + Y * math.cos(t)
        roots, valid = type2(X, Y, Z)
        assert valid.all()
        assert contains(roots, valid, t)
        for r in roots:
            assert abs(residual2(X, Y, Z, r)) < 1e-12
            assert -PI < r <= PI


@given(t=angles, X=coefs, Y=coefs)
def test_type2_property_known_root(t, X, Y):
    assume(abs(X * math.cos(t) - Y * math.sin(t)) > 1e-4)
    Z = X * math.sin(t) + Y * math.cos(t)
    roots, valid = type2(X, Y, Z)
    assert valid.all() and contains(roots, valid, t, 1e-9)


@given(X=coefs, Y=coefs, Z=st.floats(-3.0, 3.0, allow_nan=False))
def test_type2_property_valid_roots_solve_and_invalid_means_no_root(X, Y, Z):
    roots, valid = type2(X, Y, Z)
    r2 = X * X + Y * Y
    if valid.any():
        for r in roots:
            assert abs(residual2(X, Y, Z, r)) <= 1e-12 * max(1.0, math.sqrt(r2))
    else:
        assert np.isnan(roots).all()
        assert math.hypot(X, Y) < abs(Z)  # no root only if X^2 + Y^2 < Z^2
    if r2 < Z * Z * (1 - 1e-9):
        assert not valid.any()


@given(X=coefs, Y=coefs, grow=st.floats(1e-9, 10.0))
def test_type2_property_unreachable(X, Y, grow):
    Z = math.hypot(X, Y) * (1 + grow) if X or Y else grow
    assume(Z > math.hypot(X, Y))  # subnormal X, Y: the product can round back to the hypotenuse
    assert not type2(X, Y, Z)[1].any()
    assert not type2(X, Y, -Z)[1].any()


# --- type 3 -----------------------------------------------------------------------------------


def test_type3_appendix_special_case_y1_x2_zero():
    t = 2.5
    X1, Y2 = 0.7, -1.9
    got, ok = type3(X1, 0.0, X1 * math.sin(t), 0.0, Y2, Y2 * math.cos(t))
    assert ok
    assert angle_gap(got, math.atan2((X1 * math.sin(t)) / X1, (Y2 * math.cos(t)) / Y2)) < 1e-15
    assert angle_gap(got, t) < 1e-14


def test_type3_random_from_known_angle(rng):
    for _ in range(2000):
        t = rng.uniform(-PI, PI)
        X1, Y1, X2, Y2 = rng.uniform(-2, 2, 4)
        if abs(X1 * Y2 - X2 * Y1) < 1e-3:
            continue
        Z1 = X1 * math.sin(t) + Y1 * math.cos(t)
        Z2 = X2 * math.sin(t) + Y2 * math.cos(t)
        got, ok = type3(X1, Y1, Z1, X2, Y2, Z2)
        assert ok
        assert angle_gap(got, t) < 1e-10
        assert abs(residual2(X1, Y1, Z1, got)) < 1e-12
        assert abs(residual2(X2, Y2, Z2, got)) < 1e-12


def test_type3_inconsistent_system_is_invalid():
    # sin t = 0.5 and cos t = 0.5: s^2 + c^2 = 0.5
    got, ok = type3(1.0, 0.0, 0.5, 0.0, 1.0, 0.5)
    assert not ok and math.isnan(got)
    got, ok = type3(1.0, 1.0, 1.0, 1.0, -1.0, 1.0 + 1e-6)
    assert not ok


def test_type3_degenerate_parallel_rows():
    t = 0.9
    X1, Y1 = 0.6, -1.2
    Z1 = X1 * math.sin(t) + Y1 * math.cos(t)
    for k in (2.0, -0.5):  # second row = k * first row: one equation, two roots
        got, ok = type3(X1, Y1, Z1, k * X1, k * Y1, k * Z1)
        assert ok
        assert abs(residual2(X1, Y1, Z1, got)) < 1e-12
        assert abs(residual2(k * X1, k * Y1, k * Z1, got)) < 1e-12
        other = math.atan2(-Y1, X1) * 2 + PI - t  # the second root of X1 s + Y1 c = Z1
        assert min(angle_gap(got, t), angle_gap(got, other)) < 1e-10
    assert not type3(X1, Y1, Z1, 2 * X1, 2 * Y1, 2 * Z1 + 0.1)[1]  # parallel, contradictory


def test_type3_null_rows():
    got, ok = type3(0.0, 0.0, 0.0, 1.0, 0.0, 0.5)  # 0 = 0 and sin t = 1/2
    assert ok and abs(math.sin(got) - 0.5) < 1e-15
    assert not type3(0.0, 0.0, 1.0, 1.0, 0.0, 0.5)[1]  # 0 = 1
    got, ok = type3(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # identity
    assert ok and got == 0.0


@given(t=angles, X1=coefs, Y1=coefs, X2=coefs, Y2=coefs)
def test_type3_property(t, X1, Y1, X2, Y2):
    assume(abs(X1 * Y2 - X2 * Y1) > 1e-3)
    Z1 = X1 * math.sin(t) + Y1 * math.cos(t)
    Z2 = X2 * math.sin(t) + Y2 * math.cos(t)
    got, ok = type3(X1, Y1, Z1, X2, Y2, Z2)
    assert ok and angle_gap(got, t) < 1e-9


# --- type 6 -----------------------------------------------------------------------------------


def residual6(W, X, Y, Z1, Z2, ti, tj):
    return (
        W * math.sin(tj) - (X * math.cos(ti) + Y * math.sin(ti) + Z1),
        W * math.cos(tj) - (X * math.sin(ti) - Y * math.cos(ti) + Z2),
    )


def build6(ti, tj, W, X, Y):
    """Z1, Z2 such that (ti, tj) solves the type-6 system."""
    Z1 = W * math.sin(tj) - X * math.cos(ti) - Y * math.sin(ti)
    Z2 = W * math.cos(tj) - X * math.sin(ti) + Y * math.cos(ti)
    return Z1, Z2


def b_derivative(ti, X, Y, Z1, Z2):
    """d/dti of the squared-and-added equation; small near the double root."""
    return 2 * (Y * Z1 + X * Z2) * math.cos(ti) - 2 * (X * Z1 - Y * Z2) * math.sin(ti)


def test_type6_random_from_known_angles(rng):
    for _ in range(2000):
        ti, tj = rng.uniform(-PI, PI, 2)
        W, X, Y = rng.uniform(-2, 2, 3)
        Z1, Z2 = build6(ti, tj, W, X, Y)
        if abs(b_derivative(ti, X, Y, Z1, Z2)) < 1e-2 or abs(W) < 1e-2:
            continue
        TI, TJ, valid = type6(W, X, Y, Z1, Z2)
        assert valid.all()
        assert any(angle_gap(a, ti) < 1e-8 and angle_gap(b, tj) < 1e-8 for a, b in zip(TI, TJ))
        scale = 1 + abs(W) + abs(X) + abs(Y) + abs(Z1) + abs(Z2)
        for a, b in zip(TI, TJ):
            assert max(map(abs, residual6(W, X, Y, Z1, Z2, a, b))) < 1e-12 * scale


@given(ti=angles, tj=angles, W=coefs, X=coefs, Y=coefs)
def test_type6_property(ti, tj, W, X, Y):
    Z1, Z2 = build6(ti, tj, W, X, Y)
    assume(abs(W) > 1e-3 and abs(b_derivative(ti, X, Y, Z1, Z2)) > 1e-3)
    TI, TJ, valid = type6(W, X, Y, Z1, Z2)
    assert valid.all()
    assert any(angle_gap(a, ti) < 1e-7 and angle_gap(b, tj) < 1e-7 for a, b in zip(TI, TJ))


def test_type6_w_zero_frees_tj():
    ti = 1.2
    X, Y = 0.8, -0.3
    Z1 = -(X * math.cos(ti) + Y * math.sin(ti))
    Z2 = -(X * math.sin(ti) - Y * math.cos(ti))
    TI, TJ, valid = type6(0.0, X, Y, Z1, Z2)
    np.testing.assert_array_equal(valid, [True, False])
    assert angle_gap(TI[0], ti) < 1e-14 and TJ[0] == 0.0
    assert np.isnan(TI[1]) and np.isnan(TJ[1])
    assert not type6(0.0, X, Y, Z1 + 0.1, Z2)[2].any()  # W = 0 but inconsistent


def test_type6_no_solution():
    # |(X c + Y s + Z1, X s - Y c + Z2)| <= 1 + 0.5 < W for every ti
    assert not type6(2.0, 1.0, 0.0, 0.5, 0.0)[2].any()
    assert not type6(10.0, 1.0, 0.0, 0.0, 0.0)[2].any()
