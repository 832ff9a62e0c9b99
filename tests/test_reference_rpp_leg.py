"""Reference generalised RPP leg (spotkin.reference.rpp_leg) against direct products, finite
differences, the Spot-only reference and brute-force sampling of the nearest in-limit foot."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from spotkin.reference import leg as ref_leg
from spotkin.reference import rpp_leg

INF = math.inf
SPOT_FL = {
    "a": (0.0, 0.110945, 0.0),
    "b": (0.025, 0.0, -0.3205),
    "c": (0.0, 0.0, -0.3365),
    "signs": (1, 1, 1),
}
SPOT_LIMITS = ((-0.785398, -0.898845, -2.7929), (0.785398, 2.295108, -0.254801))
GO2_FL = {"a": (0.0, 0.0955, 0.0), "b": (0.0, 0.0, -0.213), "c": (0.0, 0.0, -0.213), "signs": (1, 1, 1)}
GO2_FL_LIMITS = ((-1.0472, -1.5708, -2.7227), (1.0472, 3.4907, -0.83776))
GO2_RL_LIMITS = ((-1.0472, -0.5236, -2.7227), (1.0472, 4.5379, -0.83776))


def random_geometry(rng: np.random.Generator) -> dict:
    """Offsets in every component (a_x, a_z, b_y, c_x != 0), random axis signs."""
    a_y = rng.choice([-1, 1]) * rng.uniform(0.03, 0.15)
    a = np.array([rng.uniform(-0.08, 0.08), a_y, rng.uniform(-0.06, 0.06)])
    b = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.05, 0.05), -rng.uniform(0.15, 0.4)])
    c = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.04, 0.04), -rng.uniform(0.15, 0.4)])
    return {"a": a, "b": b, "c": c, "signs": rng.choice([-1.0, 1.0], 3)}


def random_limits(rng: np.random.Generator, kinds: str) -> tuple[tuple, tuple]:
    """Per joint: 'f' finite (range 0.6 to 5.5 rad), 'w' wider than 2 pi, 'i' infinite, 'h' half-infinite,
    'k' a forward-bending knee's range (0.2 to 2.8)."""
    lower, upper = [], []
    for kind in kinds:
        centre = rng.uniform(-math.pi, math.pi)
        if kind == "f":
            half = rng.uniform(0.3, 2.75)
            lo, hi = centre - half, centre + half
        elif kind == "w":
            lo, hi = centre - 3.6, centre + 3.6
        elif kind == "i":
            lo, hi = -INF, INF
        elif kind == "h":
            lo, hi = -INF, centre
        else:
            lo, hi = 0.2, 2.8
        lower.append(lo)
        upper.append(hi)
    return tuple(lower), tuple(upper)


def _random_case(seed: int, kinds: str):
    rng = np.random.default_rng(seed)
    return random_geometry(rng), random_limits(rng, kinds)


LEG_CASES = {
    "spot_fl": (SPOT_FL, SPOT_LIMITS),
    "go2_fl": (GO2_FL, GO2_FL_LIMITS),
    "go2_rl": (GO2_FL, GO2_RL_LIMITS),
    "random_finite": _random_case(11, "fff"),
    "random_wide_roll_infinite_knee": _random_case(12, "wfi"),
    "random_half_infinite": _random_case(13, "ihf"),
    "random_forward_knee": _random_case(14, "ffk"),
    "spot_fl_no_limits": (SPOT_FL, ((-INF,) * 3, (INF,) * 3)),
    # no net hip offset (h = a_y + b_y + c_y = 0): the roll torus can pass through the roll axis
    "zero_offset": (
        {"a": (0.03, 0.05, 0.02), "b": (0.02, -0.08, -0.3), "c": (-0.01, 0.03, -0.28), "signs": (1, -1, 1)},
        ((-0.9, -1.2, -2.6), (0.7, 2.1, -0.3)),
    ),
}


def homogeneous(R=None, t=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = t
    return T


def rot(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def fk_homogeneous(g: dict, q) -> np.ndarray:
    """The joint chain as a product of 4x4 transforms: rotate about each joint's axis, then translate."""
    s = np.asarray(g["signs"], dtype=float)
    T = homogeneous(rot(0, s[0] * q[0]))
    T = T @ homogeneous(t=g["a"]) @ homogeneous(rot(1, s[1] * q[1]))
    T = T @ homogeneous(t=g["b"]) @ homogeneous(rot(1, s[2] * q[2]))
    return (T @ np.append(np.asarray(g["c"], dtype=float), 1.0))[:3]


def fk_batch(g: dict, Q: np.ndarray) -> np.ndarray:
    """(R1) vectorised over rows of Q, expanded with u = a + Ry(t2) b + Ry(t2 + t3) c."""
    a, b, c = (np.asarray(g[k], dtype=float) for k in "abc")
    th = Q * np.asarray(g["signs"], dtype=float)
    c1, s1 = np.cos(th[:, 0]), np.sin(th[:, 0])
    c2, s2 = np.cos(th[:, 1]), np.sin(th[:, 1])
    c23, s23 = np.cos(th[:, 1] + th[:, 2]), np.sin(th[:, 1] + th[:, 2])
    ux = a[0] + c2 * b[0] + s2 * b[2] + c23 * c[0] + s23 * c[2]
    uy = a[1] + b[1] + c[1]
    uz = a[2] - s2 * b[0] + c2 * b[2] - s23 * c[0] + c23 * c[2]
    return np.stack([ux, c1 * uy - s1 * uz, s1 * uy + c1 * uz], axis=-1)


def squared_distance_and_gradient(q, g: dict, p: np.ndarray):
    """|fk(q) - p|^2 and its gradient 2 J^T (fk - p), in plain floats (fast enough for scipy)."""
    a, b, c = (np.asarray(g[k], dtype=float) for k in "abc")
    s = np.asarray(g["signs"], dtype=float)
    t1, t2, t3 = s[0] * q[0], s[1] * q[1], s[2] * q[2]
    c1, s1, c2, s2 = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
    c23, s23 = math.cos(t2 + t3), math.sin(t2 + t3)
    u3x, u3z = c23 * c[0] + s23 * c[2], -s23 * c[0] + c23 * c[2]
    ux = a[0] + c2 * b[0] + s2 * b[2] + u3x
    uy = a[1] + b[1] + c[1]
    uz = a[2] - s2 * b[0] + c2 * b[2] + u3z
    foot = np.array([ux, c1 * uy - s1 * uz, s1 * uy + c1 * uz])
    e = foot - p

    def rotated(dx, dz):  # Rx(t1) (dx, 0, dz)
        return np.array([dx, -s1 * dz, c1 * dz])

    J = np.column_stack(
        [
            s[0] * np.array([0.0, -foot[2], foot[1]]),
            s[1] * rotated(uz - a[2], -(ux - a[0])),
            s[2] * rotated(u3z, -u3x),
        ]
    )
    return float(e @ e), 2.0 * J.T @ e


def sampled_nearest(g: dict, limits, p: np.ndarray, n: int = 40, refine: int = 20) -> float:
    """Best distance of an n^3 joint grid, then SLSQP (within the limits) from its best `refine`.
    (SLSQP finds the same optima as L-BFGS-B here, ~8 times faster on a loaded machine.)"""
    lower, upper = limits
    axes, bounds = [], []
    for lo, hi in zip(lower, upper):
        if rpp_leg._limited(lo, hi):
            axes.append(np.linspace(lo, hi, n))
            bounds.append((lo, hi))
        else:
            axes.append(np.linspace(-math.pi, math.pi, n, endpoint=False))
            bounds.append((None, None))
    Q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    d = np.linalg.norm(fk_batch(g, Q) - p, axis=1)
    order = np.argsort(d)[:refine]
    best = float(d[order[0]])
    for i in order:
        res = minimize(
            squared_distance_and_gradient,
            Q[i],
            args=(g, p),
            jac=True,
            bounds=bounds,
            method="SLSQP",
            options={"ftol": 1e-16, "maxiter": 500},
        )
        best = min(best, math.sqrt(max(float(res.fun), 0.0)))
    return best


def reachable_in_limits(g: dict, limits, p) -> bool:
    q_all, exists = rpp_leg.ik_all(g, p)
    return any(
        all(rpp_leg.into_range(q_all[slot, k], limits[0][k], limits[1][k]) is not None for k in range(3))
        for slot in range(4)
        if exists[slot]
    )


def unreachable_targets(g: dict, limits, n: int, rng: np.random.Generator) -> np.ndarray:
    """n targets that no in-limit configuration reaches, in seven families: far away, inside the
    hip-roll cylinder, too close to the hip pitch joint, anywhere in the box around the leg
    (behind, above, ...), just past the joint limits (the limit-blocked part of the workspace),
    exactly on the hip-roll cylinder and on the roll axis (degenerate roots of (T3))."""
    a, b, c = (np.asarray(g[k], dtype=float) for k in "abc")
    reach = np.linalg.norm(a) + np.linalg.norm(b) + np.linalg.norm(c)
    h = abs(a[1] + b[1] + c[1])
    lower, upper = limits
    out = []
    family = 0
    while len(out) < n:
        family = (family + 1) % 7
        if family == 0:
            u = rng.normal(size=3)
            p = u / np.linalg.norm(u) * reach * rng.uniform(1.02, 3.0)
        elif family == 1:
            ang, rad = rng.uniform(-math.pi, math.pi), h * math.sqrt(rng.uniform(0.0, 0.98))
            p = np.array([rng.uniform(-reach, reach), rad * math.cos(ang), rad * math.sin(ang)])
        elif family == 2:
            u = rng.normal(size=3)
            inner = abs(np.linalg.norm(b) - np.linalg.norm(c)) + 0.08
            p = a + u / np.linalg.norm(u) * rng.uniform(0.0, inner)
        elif family == 3:
            p = rng.uniform(-reach, reach, 3)
        elif family == 5:
            ang = rng.uniform(-math.pi, math.pi)
            p = np.array([rng.uniform(-reach, reach), h * math.cos(ang), h * math.sin(ang)])
        elif family == 6:
            p = np.array([rng.uniform(-1.5 * reach, 1.5 * reach), 0.0, 0.0])
        else:
            q = []
            for lo, hi in zip(lower, upper):
                if rpp_leg._limited(lo, hi):
                    side = rng.choice([lo, hi])
                    q.append(side + math.copysign(rng.uniform(0.0, 0.6), side - (lo + hi) / 2))
                else:
                    q.append(rng.uniform(-math.pi, math.pi))
            p = rpp_leg.fk(g, q) + rng.normal(scale=0.01, size=3)
        if not reachable_in_limits(g, limits, p):
            out.append(p)
    return np.array(out)


def in_limits(q, limits) -> bool:
    return all(lo <= v <= hi for v, lo, hi in zip(q, *limits))


def check_nearest(g: dict, limits, targets: np.ndarray, n: int = 40, refine: int = 20) -> float:
    """Asserts in-limit results no farther than sampling (+1e-9); returns the largest excess."""
    worst = -math.inf
    for p in targets:
        q, foot = rpp_leg.nearest_in_limits(g, limits[0], limits[1], p)
        assert in_limits(q, limits), (p, q)
        np.testing.assert_allclose(foot, rpp_leg.fk(g, q), atol=1e-15)
        excess = float(np.linalg.norm(foot - p)) - sampled_nearest(g, limits, p, n, refine)
        assert excess <= 1e-9, (p, q, excess)
        worst = max(worst, excess)
    return worst


# ---------------------------------------------------------------- FK, Jacobian, IK


@pytest.mark.parametrize("seed", range(5))
def test_fk_matches_homogeneous_product(seed):
    rng = np.random.default_rng(seed)
    for g in (SPOT_FL, GO2_FL, random_geometry(rng), random_geometry(rng)):
        for q in rng.uniform(-4.0, 4.0, (20, 3)):
            np.testing.assert_allclose(rpp_leg.fk(g, q), fk_homogeneous(g, q), atol=1e-14)
            np.testing.assert_allclose(fk_batch(g, q[None])[0], fk_homogeneous(g, q), atol=1e-14)


def test_geometry_as_dataclass_or_mapping():
    q = np.array([0.3, -0.4, -1.2])
    geom = rpp_leg.RppGeometry()
    np.testing.assert_array_equal(rpp_leg.fk(geom, q), rpp_leg.fk(SPOT_FL, q))
    no_signs = {k: v for k, v in SPOT_FL.items() if k != "signs"}
    np.testing.assert_array_equal(rpp_leg.fk(no_signs, q), rpp_leg.fk(SPOT_FL, q))


@pytest.mark.parametrize("seed", range(5))
def test_jacobian_matches_central_differences(seed):
    rng = np.random.default_rng(100 + seed)
    step = 1e-6
    for g in (SPOT_FL, random_geometry(rng), random_geometry(rng)):
        for q in rng.uniform(-math.pi, math.pi, (20, 3)):
            fd = np.column_stack(
                [(rpp_leg.fk(g, q + step * e) - rpp_leg.fk(g, q - step * e)) / (2 * step) for e in np.eye(3)]
            )
            np.testing.assert_allclose(rpp_leg.jacobian(g, q), fd, atol=1e-9)
            _, grad = squared_distance_and_gradient(q, g, np.zeros(3))
            np.testing.assert_allclose(grad, 2 * rpp_leg.jacobian(g, q).T @ rpp_leg.fk(g, q), atol=1e-12)


def test_spot_matches_the_spot_only_reference():
    rng = np.random.default_rng(7)
    h1, U, L, k = 0.110945, 0.3205, 0.3365, 0.025
    for q in rng.uniform(-math.pi, math.pi, (200, 3)):
        p = ref_leg.fk(q, h1, U, L, k)
        np.testing.assert_allclose(rpp_leg.fk(SPOT_FL, q), p, atol=1e-15)
        np.testing.assert_allclose(rpp_leg.jacobian(SPOT_FL, q), ref_leg.jacobian(q, h1, U, L, k), atol=1e-14)
        q_new, ok_new = rpp_leg.ik_all(SPOT_FL, p)
        q_old, ok_old = ref_leg.ik_all(p, h1, U, L, k)
        np.testing.assert_array_equal(ok_new, ok_old)
        diff = np.vectorize(ref_leg.wrap_angle)(q_new - q_old)
        assert np.max(np.abs(diff)) < 1e-9


def circle_gap(qa, qb) -> float:
    return max(abs(rpp_leg.wrap_angle(float(u) - float(v))) for u, v in zip(qa, qb))


def check_round_trip(g: dict, q) -> None:
    p = rpp_leg.fk(g, q)
    q_all, exists = rpp_leg.ik_all(g, p)
    assert exists.any()
    assert exists[0] == exists[1] and exists[2] == exists[3]  # knee slots of one hip branch together
    sols = q_all[exists]
    assert np.isnan(q_all[~exists]).all() and np.all(np.abs(sols) <= math.pi)
    for sol in sols:
        np.testing.assert_allclose(rpp_leg.fk(g, sol), p, atol=1e-12)
    assert min(circle_gap(sol, q) for sol in sols) < 1e-7


@pytest.mark.parametrize("name", ["spot_fl", "go2_fl", "go2_rl"])
def test_ik_round_trip_within_limits(name):
    g, (lower, upper) = LEG_CASES[name]
    rng = np.random.default_rng(3)
    for q in rng.uniform(lower, upper, (300, 3)):
        check_round_trip(g, q)
        qn, foot = rpp_leg.nearest_in_limits(g, lower, upper, rpp_leg.fk(g, q))
        assert in_limits(qn, (lower, upper)) and np.linalg.norm(foot - rpp_leg.fk(g, q)) < 1e-12


@pytest.mark.parametrize("seed", range(10))
def test_ik_round_trip_random_geometries(seed):
    rng = np.random.default_rng(200 + seed)
    g = random_geometry(rng)
    if seed % 3 == 0:  # forward-bending knee, negative signs
        g["signs"] = np.array([-1.0, 1.0, -1.0])
    for q in rng.uniform(-math.pi, math.pi, (100, 3)):
        check_round_trip(g, q)


def test_existence_is_per_hip_branch_when_a_z_is_nonzero():
    g = {"a": (0.0, 0.1, 0.05), "b": (0.0, 0.0, -0.3), "c": (0.0, 0.0, -0.3), "signs": (1, 1, 1)}
    # |W|^2 = (v_z - a_z)^2 + x^2 with v_z = -eps S: the flipped branch (v_z = +S) is nearer the knee.
    p = np.array([0.0, 0.1, -0.6])  # S = 0.6: normal |W| = 0.65 > 0.6, flipped |W| = 0.55
    _, exists = rpp_leg.ik_all(g, p)
    np.testing.assert_array_equal(exists, [False, False, True, True])


def test_non_finite_and_unconstrained():
    q, foot = rpp_leg.nearest_in_limits(SPOT_FL, *SPOT_LIMITS, [math.nan, 0.0, 0.0])
    assert np.isnan(q).all() and np.isnan(foot).all()
    q_all, exists = rpp_leg.ik_all(SPOT_FL, [math.inf, 0.0, 0.0])
    assert not exists.any() and np.isnan(q_all).all()
    # no limits, far below: the straight leg rolled onto the ray to p (reach sqrt(h^2 + 0.426^2))
    p = np.array([0.0, 0.0955, -2.0])
    q, foot = rpp_leg.nearest_in_limits(GO2_FL, (-INF,) * 3, (INF,) * 3, p)
    np.testing.assert_allclose(foot, p / np.linalg.norm(p) * math.hypot(0.0955, 0.426), atol=1e-12)
    assert np.all(np.abs(q) <= math.pi)


@pytest.mark.parametrize(
    "p", [(0.0, 0.0, 0.0), (1e-300, 0.0, -1e-300), (1e200, -3e199, 2e200), (0.0, 1e250, 0.0), (5.0, 0.0, 0.0)]
)
def test_nearest_extreme_targets(p):
    for name in ("spot_fl", "random_wide_roll_infinite_knee"):
        g, limits = LEG_CASES[name]
        q, foot = rpp_leg.nearest_in_limits(g, *limits, p)
        assert in_limits(q, limits) and np.isfinite(foot).all()
        if max(map(abs, p)) < 10:
            assert np.linalg.norm(foot - p) <= sampled_nearest(g, limits, np.array(p), n=20, refine=4) + 1e-9


def test_into_range():
    assert rpp_leg.into_range(3.0, 2.0, 4.0) == 3.0
    assert rpp_leg.into_range(3.0 - 2 * math.pi, 2.0, 4.0) == pytest.approx(3.0, abs=1e-15)
    assert rpp_leg.into_range(0.0, 2.0, 4.0) is None
    assert rpp_leg.into_range(4.0 + 1e-13, 2.0, 4.0) == 4.0
    assert rpp_leg.into_range(0.5, 3.0, 10.0) == pytest.approx(0.5 + 2 * math.pi)  # range >= 2 pi
    assert rpp_leg.into_range(0.5, -INF, -4.0) == pytest.approx(0.5 - 2 * math.pi)
    assert rpp_leg.into_range(7.0, -INF, INF) == pytest.approx(7.0 - 2 * math.pi)


# ---------------------------------------------------------------- nearest in limits vs sampling


def test_spot_known_case_beats_the_old_fallback():
    """Spot FL, p = (0.9, 0.1, 0.1): the old UNREACHABLE fallback (the branches of the radial
    projection onto the knee-limited shell, first in limits, else clamped) landed at
    q = (0.785398, -0.898845, -0.254801), 13 cm farther than the best in-limit foot."""
    p = np.array([0.9, 0.1, 0.1])
    q, foot = rpp_leg.nearest_in_limits(SPOT_FL, *SPOT_LIMITS, p)
    d_new = float(np.linalg.norm(foot - p))
    assert in_limits(q, SPOT_LIMITS)
    assert d_new <= sampled_nearest(SPOT_FL, SPOT_LIMITS, p) + 1e-9
    d_old = float(np.linalg.norm(rpp_leg.fk(SPOT_FL, [0.785398, -0.898845, -0.254801]) - p))
    np.testing.assert_allclose(d_old, 0.45521427644394, atol=1e-12)
    assert d_old - d_new > 0.13
    np.testing.assert_allclose(d_new, 0.32360763055462, atol=1e-12)


def test_no_limits_never_worse_than_the_spot_only_nearest_reachable():
    """Without limits the exact nearest foot is at most as far as the old radial projection."""
    rng = np.random.default_rng(21)
    h1, U, L, k = 0.110945, 0.3205, 0.3365, 0.025
    for p in rng.normal(scale=0.5, size=(100, 3)):
        _, foot = rpp_leg.nearest_in_limits(SPOT_FL, (-INF,) * 3, (INF,) * 3, p)
        old = np.array(ref_leg.nearest_reachable(p, h1, U, L, k))
        assert np.linalg.norm(foot - p) <= np.linalg.norm(old - p) + 1e-12


@pytest.mark.parametrize("name", ["spot_fl", "random_wide_roll_infinite_knee"])
def test_nearest_matches_sampling_fast(name):
    g, limits = LEG_CASES[name]
    targets = unreachable_targets(g, limits, 10, np.random.default_rng(5))
    check_nearest(g, limits, targets, n=30, refine=5)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(LEG_CASES))
def test_nearest_matches_sampling(name):
    g, limits = LEG_CASES[name]
    targets = unreachable_targets(g, limits, 200, np.random.default_rng(sorted(LEG_CASES).index(name)))
    check_nearest(g, limits, targets)
