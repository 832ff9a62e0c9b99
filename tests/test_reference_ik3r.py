"""Reference 3-joint position IK (spotkin.reference.ik3r) against the package FK and brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest

import spotkin as sk
from conftest import joint_distance, newton_oracle, random_rigid, random_table
from spotkin.reference import ik3r
from spotkin.reference import leg as ref_leg

H1, H2, H3 = 0.110945, 0.3205, 0.3365
SPOT_ROWS = [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, H1, 0.0), (0, H2, 0.0, 0.0, 0.0)]
SPOT_TOOL = sk.translation([H3, 0.0, 0.0])
RRR_KINDS = {"3R-general-quartic", "3R-intersecting", "3R-parallel"}


def solve(chain: sk.Chain, p) -> tuple[np.ndarray, str]:
    q_all, valid, kind = ik3r.solve_position(chain.rows, chain.convention, p, chain.base, chain.tool)
    assert q_all.shape == (4, 3) and valid.shape == (4,) and valid.dtype == bool
    n = int(valid.sum())
    assert valid[:n].all() and not valid[n:].any()  # valid slots first
    assert np.isnan(q_all[n:]).all() and np.isfinite(q_all[:n]).all()
    return q_all[:n], kind


def check_round_trip(chain: sk.Chain, q: np.ndarray) -> tuple[float, float, str]:
    """Solve for fk(q); return (distance from q to the nearest solution, worst FK residual, kind)."""
    p = chain.fk(q)[:3, 3]
    sols, kind = solve(chain, p)
    assert len(sols) >= 1
    residual = float(np.max(np.linalg.norm(chain.fk(sols)[:, :3, 3] - p, axis=-1)))
    nearest = min(joint_distance(s, q, chain.sigma) for s in sols)
    return nearest, residual, kind


def rank_deficient(chain: sk.Chain, rng: np.random.Generator) -> bool:
    """Independent structural test: position Jacobian singular at 50 random configurations."""
    q = rng.uniform(-np.pi, np.pi, (50, 3))
    sv = np.linalg.svd(chain.position_jacobian(q), compute_uv=False)
    return bool(np.max(sv[:, -1]) < 1e-9)


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_random_3r_chains_round_trip(rng, convention):
    kinds, worst_q, worst_p, rejected = set(), 0.0, 0.0, 0
    for _ in range(150):
        chain = sk.Chain(
            random_table(rng, 3, prismatic=False),
            convention=convention,
            base=random_rigid(rng),
            tool=random_rigid(rng),
        )
        try:
            ik3r.classify(chain.rows, convention, chain.tool)
        except ValueError:
            assert rank_deficient(chain, rng)  # only structures that cannot place the point in 3D
            rejected += 1
            continue
        assert not rank_deficient(chain, rng)
        for q in rng.uniform(-np.pi, np.pi, (4, 3)):
            nearest, residual, kind = check_round_trip(chain, q)
            kinds.add(kind)
            worst_q, worst_p = max(worst_q, nearest), max(worst_p, residual)
    assert kinds == RRR_KINDS
    assert 0 < rejected < 75
    assert worst_q < 1e-8
    assert worst_p < 1e-12


@pytest.mark.parametrize("pattern", ["PRR", "RPR", "RRP", "PPR", "PRP", "RPP"])
@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_prismatic_chains_round_trip(rng, pattern, convention):
    sigma = np.array([c == "P" for c in pattern], dtype=float)
    done = 0
    while done < 25:
        rows = random_table(rng, 3, prismatic=False)
        rows[:, 0] = sigma
        chain = sk.Chain(rows, convention=convention, base=random_rigid(rng), tool=random_rigid(rng))
        try:
            assert ik3r.classify(rows, convention, chain.tool) == pattern
        except ValueError:
            assert rank_deficient(chain, rng)
            continue
        done += 1
        for _ in range(3):
            q = np.where(sigma == 1, rng.uniform(-1, 1, 3), rng.uniform(-np.pi, np.pi, 3))
            nearest, residual, _ = check_round_trip(chain, q)
            assert nearest < 1e-8
            assert residual < 1e-12


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_closed_forms_are_exact_before_polishing(rng, monkeypatch, convention):
    """With the Newton polish switched off the closed-form candidates alone must round-trip."""
    monkeypatch.setattr(ik3r, "NEWTON_STEPS", 0)
    kinds = set()
    for i in range(240):
        rows = random_table(rng, 3, prismatic=False)
        rows[:, 0] = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, 0, 1), (0, 1, 1)][i % 7]
        chain = sk.Chain(rows, convention=convention, base=random_rigid(rng), tool=random_rigid(rng))
        try:
            ik3r.classify(rows, convention, chain.tool)
        except ValueError:
            continue
        q = np.where(rows[:, 0] == 1, rng.uniform(-1, 1, 3), rng.uniform(-np.pi, np.pi, 3))
        nearest, residual, kind = check_round_trip(chain, q)
        kinds.add(kind)
        assert nearest < 1e-6
        assert residual < 1e-8
    assert kinds >= RRR_KINDS | {"PRR", "RPR", "RRP", "PPR", "PRP", "RPP"}


def test_ppp_is_linear(rng):
    rows = np.array([(1, 0.0, 0.0, 0.0, 0.0), (1, 0.2, np.pi / 2, 0.1, 0.3), (1, 0.0, np.pi / 2, 0.0, 0.0)])
    chain = sk.Chain.from_mdh(rows, base=random_rigid(rng), tool=random_rigid(rng))
    q = rng.uniform(-1, 1, 3)
    sols, kind = solve(chain, chain.fk(q)[:3, 3])
    assert kind == "PPP" and len(sols) == 1
    np.testing.assert_allclose(sols[0], q, rtol=0, atol=1e-12)


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_solution_count_matches_brute_force(rng, convention):
    counts = np.zeros(5, dtype=int)
    for i in range(150):
        chain = sk.Chain(
            random_table(rng, 3, prismatic=False),
            convention=convention,
            base=random_rigid(rng),
            tool=random_rigid(rng),
        )
        try:
            ik3r.classify(chain.rows, convention, chain.tool)
        except ValueError:
            continue
        if i % 2:  # reachable target, or a random point (often 0 solutions)
            p = chain.fk(rng.uniform(-np.pi, np.pi, 3))[:3, 3]
        else:
            p = chain.base[:3, 3] + rng.normal(size=3) * 0.5
        sols, _ = solve(chain, p)
        oracle = newton_oracle(chain, p, rng)
        assert len(sols) == len(oracle), (chain, p, sols, oracle)
        for q in oracle:
            assert min(joint_distance(q, s, chain.sigma) for s in sols) < 1e-7
        counts[len(sols)] += 1
    assert counts[0] > 0 and counts[2] > 0 and counts[4] > 0  # every count occurred


def test_solution_count_prismatic_matches_brute_force(rng):
    counts = np.zeros(5, dtype=int)
    for i in range(80):
        rows = random_table(rng, 3, prismatic=False)
        rows[:, 0] = np.eye(3)[i % 3]  # PRR, RPR, RRP
        convention = ("mdh", "dh")[i % 2]
        chain = sk.Chain(rows, convention=convention, base=random_rigid(rng), tool=random_rigid(rng))
        try:
            ik3r.classify(chain.rows, chain.convention, chain.tool)
        except ValueError:
            continue
        q = np.where(rows[:, 0] == 1, rng.uniform(-1, 1, 3), rng.uniform(-np.pi, np.pi, 3))
        p = chain.fk(q)[:3, 3] + (0.0 if i % 4 < 2 else rng.normal(size=3) * 0.3)
        sols, _ = solve(chain, p)
        assert len(sols) == len(newton_oracle(chain, p, rng))
        counts[len(sols)] += 1
    assert counts[2] > 0 and counts[4] > 0


def spot_leg() -> sk.Chain:
    return sk.Chain.from_mdh(SPOT_ROWS, tool=SPOT_TOOL)


def spot_closed_form(p_course) -> np.ndarray:
    """The leg's known closed form (reference.leg.ik_all, k = 0) mapped to the course angles, eq. (C1)."""
    R_leg_from_course, _ = ref_leg.course_to_leg(np.zeros(3), H1)
    q_leg, exists = ref_leg.ik_all(R_leg_from_course @ p_course, H1, H2, H3, 0.0)
    th = [[ref_leg.wrap_angle(v) for v in (-hx, hy, kn)] for hx, hy, kn in q_leg[exists]]
    return np.array(sorted(th))


def test_spot_leg_four_solutions_match_closed_form(rng):
    chain = spot_leg()
    assert ik3r.classify(SPOT_ROWS, "mdh", SPOT_TOOL) == "3R-parallel"
    for q in rng.uniform(-np.pi, np.pi, (200, 3)):
        p = chain.fk(q)[:3, 3]
        sols, kind = solve(chain, p)
        assert kind == "3R-parallel"
        assert len(sols) == 4
        expected = spot_closed_form(p)
        assert len(expected) == 4
        for s in sols:
            assert min(joint_distance(s, e, [0, 0, 0]) for e in expected) < 1e-10
        assert min(joint_distance(s, q, [0, 0, 0]) for s in sols) < 1e-10
    # Out of reach: nothing.
    assert len(solve(chain, [0.0, 0.0, H1 + H2 + H3])[0]) == 0


def spot_over_axis_q(t1, t2):
    """Second singular set of the course leg: h2 cos(t2) + h3 cos(t2 + t3) = 0."""
    return np.array([t1, t2, math.acos(-H2 * math.cos(t2) / H3) - t2])


def test_spot_leg_near_double_roots(rng):
    chain = spot_leg()
    for _ in range(30):
        t1, t2 = rng.uniform(-np.pi, np.pi, 2)
        t2_over = rng.uniform(-0.7, 0.7)
        for q, n_expected in (
            ([t1, t2, 0.0], 2),  # stretched: the knee branches merge
            ([t1, t2, np.pi], 2),  # folded
            (spot_over_axis_q(t1, t2_over), 2),  # foot above the roll axis plane: hip branches merge
        ):
            q = np.asarray(q)
            p = chain.fk(q)[:3, 3]
            sols, _ = solve(chain, p)
            assert len(sols) == n_expected
            assert min(joint_distance(s, q, [0, 0, 0]) for s in sols) < 1e-6
            assert np.max(np.linalg.norm(chain.fk(sols)[:, :3, 3] - p, axis=-1)) < 1e-12
    # Stretched, then pushed outward by 1e-13 (still the merged root) or by 1e-6 (no solution).
    p = chain.fk([0.2, -0.4, 0.0])[:3, 3]
    hip = chain.frames([0.2, -0.4, 0.0])[2, :3, 3]
    out = (p - hip) / np.linalg.norm(p - hip)
    assert len(solve(chain, p + 1e-13 * out)[0]) == 2
    assert len(solve(chain, p + 1e-6 * out)[0]) == 0


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_random_chains_near_double_roots(rng, convention):
    """Targets on the workspace boundary (det J = 0, found by bisection in q3) still give that root."""
    tested = 0
    while tested < 40:
        chain = sk.Chain(
            random_table(rng, 3, prismatic=False),
            convention=convention,
            base=random_rigid(rng),
            tool=random_rigid(rng),
        )
        try:
            ik3r.classify(chain.rows, convention, chain.tool)
        except ValueError:
            continue
        q1, q2 = rng.uniform(-np.pi, np.pi, 2)
        grid = np.linspace(-np.pi, np.pi, 721)
        det = np.linalg.det(chain.position_jacobian(np.stack([np.full(721, q1), np.full(721, q2), grid], -1)))
        change = np.nonzero(np.sign(det[:-1]) * np.sign(det[1:]) < 0)[0]
        if len(change) == 0:
            continue
        a, b = grid[change[0]], grid[change[0] + 1]
        fa = det[change[0]]
        for _ in range(80):
            m = 0.5 * (a + b)
            fm = np.linalg.det(chain.position_jacobian([q1, q2, m]))
            a, b, fa = (m, b, fm) if np.sign(fm) == np.sign(fa) else (a, m, fa)
        q = np.array([q1, q2, 0.5 * (a + b)])
        p = chain.fk(q)[:3, 3]
        sols, _ = solve(chain, p)
        assert len(sols) >= 1
        # A double root is fixed by p only to ~sqrt(eps / curvature of the fold): 1e-6 .. 4e-5 seen.
        assert min(joint_distance(s, q, [0, 0, 0]) for s in sols) < 1e-4
        assert np.max(np.linalg.norm(chain.fk(sols)[:, :3, 3] - p, axis=-1)) < 1e-12
        tested += 1


def test_classify_known_structures():
    puma_like = [(0, 0.0, 0.0, 0.0, 0.0), (0, 0.0, -np.pi / 2, 0.2, 0.0), (0, 0.4, 0.0, 0.0, 0.0)]
    assert ik3r.classify(puma_like, "mdh", sk.translation([0.3, 0.1, 0.05])) == "3R-parallel"
    elbow_skew = [(0, 0.0, 0.0, 0.0, 0.0), (0, 0.1, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.3, 0.0)]
    assert ik3r.classify(elbow_skew, "mdh", sk.translation([0.2, 0.1, 0.0])) == "3R-intersecting"
    skew = [(0, 0.0, 0.0, 0.0, 0.0), (0, 0.1, 1.0, 0.05, 0.0), (0, 0.3, -0.7, 0.2, 0.3)]
    assert ik3r.classify(skew, "mdh", sk.translation([0.2, 0.1, 0.3])) == "3R-general-quartic"
    scara = [(0, 0.0, 0.0, 0.0, 0.0), (0, 0.3, 0.0, 0.0, 0.0), (1, 0.25, 0.0, 0.0, 0.0)]
    assert ik3r.classify(scara, "mdh", None) == "RRP"
    cylindrical = [(0, 0.0, 0.0, 0.0, 0.0), (1, 0.0, 0.0, 0.0, 0.0), (1, 0.0, np.pi / 2, 0.0, 0.0)]
    assert ik3r.classify(cylindrical, "mdh", None) == "RPP"


@pytest.mark.parametrize(
    ("rows", "tool", "message"),
    [
        pytest.param(SPOT_ROWS, None, "cannot be placed in 3D", id="tool-on-axis-3"),
        pytest.param([(0, 0, 0, 0, 0), (0, 0.3, 0, 0, 0), (0, 0.2, 0, 0, 0)], "x", "in 3D", id="planar"),
        pytest.param([(0, 0, 0, 0, 0), (0, 0, 0.5, 0, 0), (0, 0, 1.1, 0, 0)], "x", "in 3D", id="concurrent"),
        pytest.param([(0, 0, 0, 0, 0), (0, 0, 0, 0.4, 0), (0, 0.3, 0.5, 0, 0)], "x", "in 3D", id="coaxial"),
        pytest.param([(1, 0, 0, 0, 0), (1, 0.2, 0, 0, 0), (0, 0.3, 0.5, 0, 0)], "x", "in 3D", id="PP-par"),
        pytest.param([(0, 0, 0, 0, 0), (0, 0.3, 0.5, 0, 0)], None, "3-joint table", id="two-rows"),
        pytest.param([(2, 0, 0, 0, 0), (0, 0.3, 0.5, 0, 0), (0, 0.3, 0.5, 0, 0)], None, "sigma", id="sigma"),
    ],
)
def test_structures_without_closed_form_raise(rows, tool, message):
    tool = sk.translation([0.2, 0.1, 0.3]) if tool == "x" else tool
    with pytest.raises(ValueError, match=message):
        ik3r.classify(rows, "mdh", tool)
    with pytest.raises(ValueError, match=message):
        ik3r.solve_position(rows, "mdh", [0.1, 0.2, 0.3], None, tool)


def test_bad_convention_raises():
    with pytest.raises(ValueError, match="convention"):
        ik3r.classify(SPOT_ROWS, "craig", SPOT_TOOL)


def test_slot_order_and_invalid_targets(rng):
    chain = spot_leg()
    for q in rng.uniform(-np.pi, np.pi, (50, 3)):
        sols, _ = solve(chain, chain.fk(q)[:3, 3])
        assert all(-np.pi < v <= np.pi for v in sols.ravel())
        for a, b in zip(sols[:-1], sols[1:]):  # lexicographic (q1, q2, q3), q1 within 1e-7 a tie
            assert a[0] < b[0] - 1e-7 or (abs(a[0] - b[0]) <= 1e-7 and a[1] < b[1])
    for p in ([np.nan, 0.0, 0.0], [np.inf, 1.0, 2.0]):
        q_all, valid, kind = ik3r.solve_position(SPOT_ROWS, "mdh", p, None, SPOT_TOOL)
        assert kind == "3R-parallel" and not valid.any() and np.isnan(q_all).all()


def test_order_key_is_a_monotone_pseudo_angle():
    angles = np.linspace(-np.pi, np.pi, 20001)[1:]  # (-pi, pi]
    keys = np.array([ik3r.order_key(a, 0, 1.0) for a in angles])
    slopes = np.diff(keys) / np.diff(angles)
    assert slopes.min() > 0.5 - 1e-6 and slopes.max() < 1.0 + 1e-6  # a tie on keys is one on angles
    assert keys[0] > -2.0 and keys[-1] > 2.0 - 1e-12
    assert ik3r.order_key(-np.pi + 1e-9, 0, 1.0) == 2.0  # -pi + rounding is +pi
    assert ik3r.order_key(-np.pi + 1e-6, 0, 1.0) < -2.0 + 1e-5
    assert ik3r.order_key(0.3, 1, 2.0) == 0.15  # prismatic: v / s
