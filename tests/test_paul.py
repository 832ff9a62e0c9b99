"""Paul's equation solvers: every case of the appendix's table (corrected), random
equations built from known roots, broadcasting, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

import spotkin as sk

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


@pytest.mark.parametrize(
    ("X", "Y", "Z", "expected"),
    [
        (0.0, 2.0, 1.0, {np.pi / 3, -np.pi / 3}),  # X = 0: cos t = Z / Y
        (2.0, 0.0, 1.0, {np.pi / 6, 5 * np.pi / 6}),  # Y = 0: sin t = Z / X
        (1.0, 1.0, 0.0, {-np.pi / 4, 3 * np.pi / 4}),  # Z = 0: t = atan2(-Y, X), + pi
        (1.0, 1.0, np.sqrt(2.0), {np.pi / 4}),  # X^2 + Y^2 = Z^2: double root
    ],
)
def test_type2_cases_of_the_appendix(X, Y, Z, expected):
    t, valid = sk.paul.type2(X, Y, Z)
    assert valid.all()
    assert {round(float(v), 12) for v in t} == {round(float(v), 12) for v in expected}


def test_type2_no_root_and_identity():
    t, valid = sk.paul.type2([1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0, 0.0])
    np.testing.assert_array_equal(valid, [[False, False], [False, False], [True, True]])
    assert np.isnan(t[:2]).all() and (t[2] == 0).all()


@given(t=st.floats(-np.pi, np.pi), X=st.floats(-10, 10), Y=st.floats(-10, 10))
def test_type2_contains_the_generating_root(t, X, Y):
    if X * X + Y * Y < 1e-6:
        return
    Z = X * np.sin(t) + Y * np.cos(t)
    roots, valid = sk.paul.type2(X, Y, Z)
    assert valid.all()
    np.testing.assert_allclose(X * np.sin(roots) + Y * np.cos(roots), Z, atol=1e-12 * (1 + abs(Z)))
    assert np.abs(wrap(roots - t)).min() < 1e-6  # sqrt-conditioned near the double root


def test_type2_root_order_is_fixed():
    # root 0: eps = +1 in cos t = (Y Z - eps X S) / r^2, sin t = (X Z + eps Y S) / r^2
    X, Y, Z = 0.3, 0.8, 0.5
    r2, S = X * X + Y * Y, np.sqrt(X * X + Y * Y - Z * Z)
    t, _ = sk.paul.type2(X, Y, Z)
    np.testing.assert_allclose(
        t, [np.arctan2(X * Z + Y * S, Y * Z - X * S), np.arctan2(X * Z - Y * S, Y * Z + X * S)]
    )
    del r2


@given(t=st.floats(-np.pi, np.pi), c=st.lists(st.floats(-5, 5), min_size=4, max_size=4))
def test_type3_recovers_the_root(t, c):
    X1, Y1, X2, Y2 = c
    if abs(X1 * Y2 - X2 * Y1) < 1e-3:
        return
    Z1, Z2 = X1 * np.sin(t) + Y1 * np.cos(t), X2 * np.sin(t) + Y2 * np.cos(t)
    root, valid = sk.paul.type3(X1, Y1, Z1, X2, Y2, Z2)
    assert valid and abs(wrap(root - t)) < 1e-9


def test_type3_inconsistent_and_dependent_systems():
    _, valid = sk.paul.type3(1.0, 0.0, 0.5, 0.0, 1.0, 0.5)  # sin = cos = 0.5: not on the circle
    assert not valid
    root, valid = sk.paul.type3(1.0, 1.0, 1.0, 2.0, 2.0, 2.0)  # the same equation twice
    assert valid and abs(np.sin(root) + np.cos(root) - 1.0) < 1e-12
    _, valid = sk.paul.type3(1.0, 1.0, 1.0, 2.0, 2.0, 0.0)  # parallel and contradictory
    assert not valid


@given(
    ti=st.floats(-np.pi, np.pi),
    tj=st.floats(-np.pi, np.pi),
    W=st.floats(0.1, 5),
    X=st.floats(-3, 3),
    Y=st.floats(-3, 3),
    negative=st.booleans(),
)
# found by Hypothesis: a double root in ti whose B3 (a difference of squares) rounds past touching
@example(ti=0.0, tj=0.0, W=1.0, X=0.0, Y=4.637349727702218e-07, negative=False)
@example(ti=1.0, tj=2.1415926535897927, W=1.0, X=0.0, Y=1.0, negative=False)  # Z1 = Z2 = 0: a continuum
def test_type6_recovers_the_pair(ti, tj, W, X, Y, negative):
    W = -W if negative else W
    Z1 = W * np.sin(tj) - X * np.cos(ti) - Y * np.sin(ti)
    Z2 = W * np.cos(tj) - X * np.sin(ti) + Y * np.cos(ti)
    roots_i, roots_j, valid = sk.paul.type6(W, X, Y, Z1, Z2)
    assert valid.any()
    for a, b in zip(roots_i[valid], roots_j[valid]):  # every valid pair solves both equations
        assert abs(W * np.sin(b) - (X * np.cos(a) + Y * np.sin(a) + Z1)) < 1e-9
        assert abs(W * np.cos(b) - (X * np.sin(a) - Y * np.cos(a) + Z2)) < 1e-9
    if X * X + Y * Y < 1e-12:  # ti is (nearly) free: any reported ti solves the pair; tj must match
        assert np.nanmin(np.abs(wrap(roots_j - tj))) < 1e-5
        return
    # Z1 = Z2 = 0 (found by Hypothesis: ti = 1, tj = pi - 1, W = Y = 1, X = 0): the squared sum gives
    # W^2 = X^2 + Y^2 for every ti, a continuum of pairs, each ti with its own tj. The reported
    # pair (ti = 0, as type2 reports an identity) solves both equations (checked above); the
    # generating one cannot be singled out.
    if np.hypot(Z1, Z2) < 1e-10 * (abs(W) + abs(X) + abs(Y)):
        return
    distance = np.maximum(np.abs(wrap(roots_i - ti)), np.abs(wrap(roots_j - tj)))
    assert np.nanmin(distance) < 1e-5


def test_type6_with_zero_w_and_batches_broadcast():
    ti, tj, valid = sk.paul.type6(0.0, 1.0, 1.0, -1.0, 1.0)  # tj free: ti from the type-3 system
    np.testing.assert_array_equal(valid, [True, False])
    assert (
        abs(np.cos(ti[0]) + np.sin(ti[0]) - 1.0) < 1e-12 and abs(np.sin(ti[0]) - np.cos(ti[0]) + 1.0) < 1e-12
    )
    assert tj[0] == 0.0
    t, valid = sk.paul.type2(np.ones((3, 1)), np.ones(4), 0.5)
    assert t.shape == (3, 4, 2) and valid.shape == (3, 4, 2)
    t, valid = sk.paul.type2(np.nan, 1.0, 0.5)
    assert not valid.any()
    with pytest.raises(TypeError, match="X must be a real numeric array"):
        sk.paul.type2("a", 1.0, 0.5)


def test_solvers_match_the_pure_python_reference(rng):
    from spotkin.reference import paul as ref

    n = 400
    t, u = rng.uniform(-np.pi, np.pi, (2, n))
    X, Y, W, X2, Y2 = rng.normal(size=(5, n))
    X[:20] = 0.0  # the appendix's special cases
    Y[20:40] = 0.0
    W[40:50] = 0.0
    Z = X * np.sin(t) + Y * np.cos(t)
    Z[50:80] = 0.0
    Z[80:100] *= 50.0  # out of reach
    roots, valid = sk.paul.type2(X, Y, Z)
    Z1 = W * np.sin(u) - X * np.cos(t) - Y * np.sin(t)
    Z2 = W * np.cos(u) - X * np.sin(t) + Y * np.cos(t)
    ti, tj, valid6 = sk.paul.type6(W, X, Y, Z1, Z2)
    t3, valid3 = sk.paul.type3(X, Y, Z, X2, Y2, X2 * np.sin(t) + Y2 * np.cos(t))
    for i in range(n):
        r_ref, v_ref = ref.type2(X[i], Y[i], Z[i])
        np.testing.assert_array_equal(valid[i], v_ref)
        np.testing.assert_allclose(roots[i], r_ref, atol=1e-12)
        a, b, v = ref.type6(W[i], X[i], Y[i], Z1[i], Z2[i])
        np.testing.assert_array_equal(valid6[i], v)
        np.testing.assert_allclose(ti[i], a, atol=1e-12)
        np.testing.assert_allclose(tj[i], b, atol=1e-12)
        r3, v3 = ref.type3(X[i], Y[i], Z[i], X2[i], Y2[i], X2[i] * np.sin(t[i]) + Y2[i] * np.cos(t[i]))
        assert valid3[i] == v3
        if v3:
            assert abs(wrap(t3[i] - r3)) < 1e-12
