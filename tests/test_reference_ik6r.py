"""The pure-Python reference for 6R arm families (spotkin.reference.ik6r): FK round trips on public
arm tables, perturbed (calibrated) geometry with Newton polish, 7-joint arms with a fixed joint,
near-singular samples, and EAIK (an independent subproblem-decomposition solver) as the oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

import spotkin as sk
from spotkin.reference import ik6r

PI = math.pi
X, Y, Z = np.eye(3)


def dh_rows(d, a, alpha, theta=None):
    theta = np.zeros(len(d)) if theta is None else theta
    return np.array([[0.0, a[i], alpha[i], d[i], theta[i]] for i in range(len(d))])


# Standard DH parameters published by Universal Robots.
UR5 = dh_rows(
    [0.089159, 0, 0, 0.10915, 0.09465, 0.0823],
    [0, -0.425, -0.39225, 0, 0, 0],
    [PI / 2, 0, 0, PI / 2, -PI / 2, 0],
)
UR10 = dh_rows(
    [0.1273, 0, 0, 0.163941, 0.1157, 0.0922],
    [0, -0.612, -0.5723, 0, 0, 0],
    [PI / 2, 0, 0, PI / 2, -PI / 2, 0],
)
UR3 = dh_rows(
    [0.1519, 0, 0, 0.11235, 0.08535, 0.0819],
    [0, -0.24365, -0.21325, 0, 0, 0],
    [PI / 2, 0, 0, PI / 2, -PI / 2, 0],
)
# Franka Panda (modified DH, Craig), flange 0.107 m along the last z.
PANDA = np.array(
    [
        [0, 0.0, 0.0, 0.333, 0],
        [0, 0.0, -PI / 2, 0.0, 0],
        [0, 0.0, PI / 2, 0.316, 0],
        [0, 0.0825, PI / 2, 0.0, 0],
        [0, -0.0825, -PI / 2, 0.384, 0],
        [0, 0.0, PI / 2, 0.0, 0],
        [0, 0.088, PI / 2, 0.0, 0],
    ]
)
# Kinova Gen3 (classic DH) with its small lateral offsets (d2, d4) set to zero: "Gen3-like".
GEN3 = dh_rows(
    [-0.2848, 0.0, -0.4208, 0.0, -0.3143, 0.0, -0.1674],
    np.zeros(7),
    [PI / 2] * 6 + [PI],
    [0, PI, PI, PI, PI, PI, PI],
)


def z1_like() -> ik6r.Chain6:
    """Unitree-Z1-like: yaw, three parallel pitches, yaw, roll (lengths rounded from its URDF)."""
    points = [
        [0, 0, 0.0585],
        [0, 0, 0.1035],
        [-0.35, 0, 0.1035],
        [-0.132, 0, 0.1605],
        [-0.062, 0, 0.1605],
        [-0.0128, 0, 0.1605],
    ]
    tool = np.eye(4)
    tool[:3, 3] = [0.04, 0, 0.1605]
    return ik6r.make_chain([Z, Y, Y, Y, Z, X], points, tool)


def shoulder_arm() -> ik6r.Chain6:
    """A spherical shoulder (z, y, x meet) and a general offset forearm and wrist."""
    c = [0, 0, 0.1]
    tool = np.eye(4)
    tool[:3, :3] = sk.rotation_y(0.3)[:3, :3]
    tool[:3, 3] = [0.75, 0.02, 0.12]
    return ik6r.make_chain(
        [Z, Y, X, Y, X, Z], [c, c, c, [0.3, 0, 0.12], [0.55, 0.05, 0.1], [0.65, 0, 0.12]], tool
    )


def spot_arm_chain() -> ik6r.Chain6:
    """Spot's arm in POE form, from its geometric Jacobian and FK at q = 0 (see from_sk_chain)."""
    arm = sk.Spot().arm
    M, J = arm.fk(np.zeros(6)), arm.jacobian(np.zeros(6))
    axes = J[3:].T
    points = [np.cross(np.cross(h, M[:3, 3]) - v, h) for h, v in zip(axes, J[:3].T)]
    return ik6r.make_chain(axes, points, M)


def angle_gap(qa, qb) -> np.ndarray:
    return np.abs(np.remainder(np.asarray(qa) - np.asarray(qb) + PI, 2 * PI) - PI)


def contains(solutions: ik6r.Solutions, q, tol=1e-7) -> bool:
    gaps = angle_gap(solutions.q[solutions.exists], q).max(axis=1)
    return bool(gaps.size and gaps.min() < tol)


def perturbed(chain: ik6r.Chain6, rng, angle=1e-3) -> ik6r.Chain6:
    """Every axis tilted by ``angle`` rad about a random direction normal to it."""
    axes = []
    for h in chain.axes:
        n = np.cross(h, rng.normal(size=3))
        axes.append(ik6r.rot(n / np.linalg.norm(n), angle) @ h)
    return ik6r.Chain6(np.array(axes), chain.points, chain.tool)


CHAINS_234 = {
    "UR5": lambda: ik6r.from_dh(UR5),
    "UR10": lambda: ik6r.from_dh(UR10),
    "UR3": lambda: ik6r.from_dh(UR3),
    "Z1-like": z1_like,
}


# ---- the chain description ------------------------------------------------------------------------


def test_poe_matches_the_dh_tables_and_sk_chain(rng):
    for rows in (UR5, UR10, UR3):
        chain, poe = sk.Chain.from_dh(rows), ik6r.from_dh(rows)
        from_sk = ik6r.as_chain(chain)
        for q in rng.uniform(-PI, PI, (20, 6)):
            assert np.abs(ik6r.fk(poe, q) - chain.fk(q)).max() < 1e-12
            assert np.abs(ik6r.fk(from_sk, q) - chain.fk(q)).max() < 1e-12
            assert np.abs(ik6r.jacobian(poe, q) - chain.jacobian(q)).max() < 1e-12
    arm, spot = sk.Spot().arm, spot_arm_chain()
    for q in rng.uniform(-PI, PI, (20, 6)):
        assert np.abs(ik6r.fk(spot, q) - arm.fk(q)).max() < 1e-12


def test_classify():
    assert all(ik6r.classify(make()) == "three_parallel_234" for make in CHAINS_234.values())
    assert ik6r.classify(shoulder_arm()) == "spherical_shoulder"
    assert ik6r.classify(ik6r.reversed_chain(shoulder_arm())) == "spherical_wrist"
    assert ik6r.classify(spot_arm_chain()) == "spherical_wrist"
    assert ik6r.classify(sk.Chain.from_dh(UR5)) == "three_parallel_234"
    general = ik6r.make_chain(
        [Z, Y, X, Y, Z, X], [[0, 0, 0], [0.1, 0, 0], [0.2, 0.1, 0], [0.3, 0, 0.1], [0.4, 0.1, 0], [0.5, 0, 0]]
    )
    with pytest.raises(ValueError, match=r"axes 2-3-4 parallel.*ik_differential"):
        ik6r.classify(general)
    with pytest.raises(ValueError, match="6-joint"):
        ik6r.classify(ik6r.from_dh(PANDA, "mdh"))


# ---- round trips ------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(CHAINS_234))
def test_round_trip_three_parallel_234(name, rng):
    chain = CHAINS_234[name]()
    limits = np.tile([-2 * PI, 2 * PI], (6, 1))
    for q in rng.uniform(-PI, PI, (150, 6)):
        T = ik6r.fk(chain, q)
        sol = ik6r.solve(chain, T, limits=limits)
        assert contains(sol, q), q
        assert sol.exact[sol.exists].all() and (sol.valid == sol.exists).all()
        assert sol.exists.sum() in (2, 4, 6, 8)
        for slot in np.flatnonzero(sol.exists):  # every slot is a solution, no duplicates
            assert np.abs(ik6r.fk(chain, sol.q[slot]) - T).max() < 1e-10
            others = sol.q[sol.exists & (np.arange(8) != slot)]
            assert (angle_gap(others, sol.q[slot]).max(axis=1) > 1e-6).all()


@pytest.mark.parametrize(
    ("name", "make", "family"),
    [
        ("shoulder", shoulder_arm, "spherical_shoulder"),
        ("wrist", lambda: ik6r.reversed_chain(shoulder_arm()), "spherical_wrist"),
        ("spot_arm", spot_arm_chain, "spherical_wrist"),
        (
            "parallel_123",
            lambda: ik6r.make_chain(
                [Y, Y, Y, Z, Y, X],
                np.cumsum(
                    [
                        [0, 0, 0.1],
                        [0.3, 0, 0],
                        [0.25, 0.05, 0],
                        [0.1, 0, 0.02],
                        [0, 0.07, 0.1],
                        [0.05, 0, 0.03],
                    ],
                    axis=0,
                ),
            ),
            "three_parallel_123",
        ),
    ],
)
def test_round_trip_searched_families(name, make, family, rng):
    chain = make()
    for q in rng.uniform(-PI, PI, (12, 6)):
        T = ik6r.fk(chain, q)
        sol = ik6r.solve(chain, T)
        assert sol.family == family
        assert contains(sol, q), q
        assert (sol.residual[sol.exists] < 1e-10).all()


def test_joint_limits_filter_with_wrapping(rng):
    chain = ik6r.from_dh(UR5)
    q = np.array([0.3, -1.0, 1.2, 0.4, -0.6, 0.8])
    limits = np.array([[0.0, 2 * PI]] * 6)  # q1 = 0.3 inside, -1.0 must be shifted by 2π
    sol = ik6r.solve(chain, ik6r.fk(chain, q), limits=limits)
    assert sol.valid.all() == sol.exists.all()
    slot = np.argmin(angle_gap(sol.q, q).max(axis=1))
    assert np.allclose(sol.q[slot], np.where(q < 0, q + 2 * PI, q))
    narrow = np.array([[0.2, 0.4], [-1.1, -0.9], [1.1, 1.3], [0.3, 0.5], [-0.7, -0.5], [0.7, 0.9]])
    sol = ik6r.solve(chain, ik6r.fk(chain, q), limits=narrow)
    assert sol.valid.sum() == 1 and np.allclose(sol.q[sol.valid][0], q)


def test_non_finite_target_gives_no_solution():
    sol = ik6r.solve(ik6r.from_dh(UR5), np.full((4, 4), np.nan))
    assert not sol.exists.any() and np.isnan(sol.q).all()


# ---- calibrated geometry ------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["UR5", "spot_arm"])
def test_perturbed_geometry_is_polished(name, rng):
    ideal = ik6r.from_dh(UR5) if name == "UR5" else spot_arm_chain()
    chain = perturbed(ideal, rng)
    with pytest.raises(ValueError, match="ik_differential"):
        ik6r.classify(chain)  # not special within the default 1e-9
    family = ik6r.classify(chain, tol_angle=1e-2, tol_dist=1e-2)
    assert family == ik6r.classify(ideal)
    n_samples = 40 if name == "UR5" else 8
    hits = []
    for q in rng.uniform(-PI, PI, (n_samples, 6)):
        T = ik6r.fk(chain, q)
        rough = ik6r.solve(chain, T, tol_angle=1e-2, tol_dist=1e-2)
        assert not rough.exact.any()  # the idealised answers are never reported exact
        sol = ik6r.solve(chain, T, tol_angle=1e-2, tol_dist=1e-2, polish=True)
        hits.append(contains(sol, q, 1e-8))
        assert (sol.exact == (sol.residual < ik6r.EXACT)).all()
        assert sol.exact[sol.exists].all()
    print(name, "hits", sum(hits), "of", n_samples)
    # the generating branch can be lost near a wrist singularity or the workspace boundary, where
    # 1e-3 of geometry moves solutions far (a true, general 6R chain may have more than 8)
    assert sum(hits) >= n_samples - max(1, n_samples // 10)


# ---- 7 joints, one held -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("rows", "convention", "free_joint", "family"),
    [
        (PANDA, "mdh", 6, "spherical_shoulder"),
        (GEN3, "dh", 2, "spherical_wrist"),
        (GEN3, "dh", 6, "spherical_shoulder"),
    ],
    ids=["panda_q7", "gen3_q3", "gen3_q7"],
)
def test_seven_joints_with_a_free_joint(rows, convention, free_joint, family, rng):
    chain = ik6r.from_dh(rows, convention)
    reference = sk.Chain(rows, convention=convention)
    for q in rng.uniform(-PI, PI, (6, 7)):
        T = ik6r.fk(chain, q)
        assert np.abs(T - reference.fk(q)).max() < 1e-12
        sol = ik6r.solve_free(chain, T, free_joint=free_joint, free_value=q[free_joint])
        assert sol.family == family
        assert contains(sol, q), q
        assert (sol.q[sol.exists, free_joint] == q[free_joint]).all()
        for qs in sol.q[sol.exists]:
            assert np.abs(ik6r.fk(chain, qs) - T).max() < 1e-10


# ---- near-singular samples of the parallel family --------------------------------------------------


def ur5_singular(kind: str, rng, jitter: float) -> np.ndarray:
    """A UR5 configuration at (jitter = 0) or near a shoulder, elbow or wrist singularity."""
    a2, a3, d5 = -0.425, -0.39225, 0.09465
    while True:
        q = rng.uniform(-PI, PI, 6)
        if kind == "elbow":
            q[2] = rng.choice([0.0, PI]) + jitter
        elif kind == "wrist":
            q[4] = rng.choice([0.0, PI]) + jitter
        else:  # shoulder: a2 c2 + a3 c23 + d5 s234 = 0 (the wrist point on the base axis)
            value = a2 * math.cos(q[1]) + a3 * math.cos(q[1] + q[2])
            if abs(value) > 0.9 * d5:
                continue
            q[3] = math.asin(-value / d5) - q[1] - q[2] + jitter
        return q


@pytest.mark.parametrize(
    "kind",
    [
        "shoulder",
        "elbow",
        "wrist",
    ],
)
def test_near_singular_ur5(kind, rng):
    chain = ik6r.from_dh(UR5)
    for jitter in (0.0, 1e-9, -1e-7, 1e-5):
        for _ in range(10):
            q = ur5_singular(kind, rng, jitter)
            if jitter == 0.0:  # the sample is singular: an independent check of the formula above
                sigma = np.linalg.svd(ik6r.jacobian(chain, q), compute_uv=False)
                assert sigma[-1] < 1e-9 * sigma[0]
            T = ik6r.fk(chain, q)
            sol = ik6r.solve(chain, T)
            assert sol.exists.any()
            assert (sol.residual[sol.exists] < 1e-9).all()
            if kind == "wrist" and abs(jitter) < 1e-6:
                continue  # q4 and q6 trade off: any split is a solution
            assert contains(sol, q, 1e-5 if jitter == 0.0 else 1e-6), (kind, jitter, q)


# ---- EAIK --------------------------------------------------------------------------------------------


def eaik_robot(chain: ik6r.Chain6):
    """EAIK's H, P description of the chain (its tool rotation at q = 0 is the identity)."""
    from eaik.IK_HP import HPRobot

    p = chain.points
    P = np.vstack([p[0], np.diff(p, axis=0), chain.tool[:3, 3] - p[-1]])
    return HPRobot(chain.axes.copy(), P)


def eaik_pose(chain: ik6r.Chain6, T: np.ndarray) -> np.ndarray:
    pose = T.copy()
    pose[:3, :3] = T[:3, :3] @ chain.tool[:3, :3].T
    return pose


def same_sets(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    def covered(x, y):
        return all(angle_gap(y, row).max(axis=1).min() < tol for row in x) if len(x) else True

    return len(a) > 0 and len(b) > 0 and covered(a, b) and covered(b, a)


EAIK_CHAINS = {
    **CHAINS_234,
    "shoulder": shoulder_arm,
    "wrist": lambda: ik6r.reversed_chain(shoulder_arm()),
    "spot_arm": spot_arm_chain,
}


@pytest.mark.parametrize("name", sorted(EAIK_CHAINS))
def test_against_eaik(name, rng):
    pytest.importorskip("eaik", reason="EAIK is not installed (pip install EAIK; see requirements-test.txt)")
    chain = EAIK_CHAINS[name]()
    robot = eaik_robot(chain)
    assert robot.hasKnownDecomposition()
    n_samples = 60 if name in CHAINS_234 else 10
    least_squares = 0
    for q in rng.uniform(-PI, PI, (n_samples, 6)):
        T = ik6r.fk(chain, q)
        assert np.abs(robot.fwdKin(q) - eaik_pose(chain, T)).max() < 1e-12  # the same robot
        theirs = robot.IK(eaik_pose(chain, T))
        exact = [qe for qe, ls in zip(theirs.Q, theirs.is_LS) if not ls]
        ours = ik6r.solve(chain, T)
        if len(exact) < theirs.num_solutions():
            least_squares += 1
            continue  # reported below: compare only where EAIK answers exactly
        assert same_sets(np.array(exact), ours.q[ours.exists], 1e-6), (name, q)
    print(
        f"EAIK {name} ({robot.getKinematicFamily()}): "
        f"{least_squares} of {n_samples} targets with least-squares answers"
    )
    if name in CHAINS_234 or name == "spot_arm":  # EAIK answers these exactly for most targets
        assert least_squares < n_samples
