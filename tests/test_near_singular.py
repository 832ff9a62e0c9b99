"""Hypothesis property tests near every singular set: IK stays finite and exact."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk

LEG = sk.Leg(0.110945, 0.3205, 0.3365, 0.025)  # no limits: the singular sets lie outside Spot's
ARM = sk.SpotArm(limits=None)
BETA = np.arctan2(0.025, 0.3205)
PHI = np.arctan2(0.075, 0.4033)

angles = st.floats(-np.pi, np.pi, allow_nan=False)
offsets = (
    st.sampled_from([0.0, 1e-15, -1e-15])
    | st.floats(-12, -3).map(lambda e: 10.0**e)
    | st.floats(-12, -3).map(lambda e: -(10.0**e))
)


@given(hx=angles, hy=angles, offset=offsets, folded=st.booleans())
def test_leg_near_the_stretched_or_folded_knee(hx, hy, offset, folded):
    q = np.array([hx, hy, -BETA + (np.pi if folded else 0.0) + offset])
    p = LEG.fk(q)
    sol = LEG.ik_all(p)
    assert sol.exists.all() and np.isfinite(sol.q).all()
    assert np.abs(LEG.fk(sol.q) - p).max() < 1e-12


@given(x=st.floats(-0.6, 0.6), angle=angles, radial=offsets)
def test_leg_near_the_hip_roll_cylinder(x, angle, radial):
    # feet at distance |h1| (1 + radial) from the hip-roll axis, where the hip branches merge
    r = 0.110945 * (1.0 + max(radial, 0.0))
    p = np.array([x, r * np.cos(angle), r * np.sin(angle)])
    sol = LEG.ik_all(p)
    if sol.exists.any():
        assert np.isfinite(sol.q).all()
        assert np.abs(LEG.fk(sol.q) - p).max() < 1e-12
    else:
        q, status = LEG.ik(p)
        assert status == sk.Status.UNREACHABLE and np.isfinite(q).all()


@given(
    q=st.lists(angles, min_size=6, max_size=6),
    wrist=offsets,
    elbow=offsets,
    which=st.sampled_from(["w", "e"]),
)
def test_arm_near_wrist_and_elbow_singularities(q, wrist, elbow, which):
    q = np.array(q)
    if which == "w":
        q[4] = wrist  # wr0 ~ 0: el1 and wr1 align
    else:
        q[2] = PHI + elbow  # elbow stretched
    T = ARM.fk(q)
    sol = ARM.ik_all(T, seed=q)
    assert sol.exists.all() and np.isfinite(sol.q).all()
    assert np.abs(ARM.fk(sol.q) - T).max() < 1e-9


@given(q=st.lists(angles, min_size=3, max_size=3), offset=offsets)
def test_chain_jacobian_rank_drops_smoothly_near_singularity(q, offset):
    # the course's DHm leg: det J = -h2 h3 sin(th3) (h2 cos th2 + h3 cos(th2 + th3)) stays exact near th3 = 0
    chain = sk.Chain.from_mdh(
        [(0, 0, -np.pi / 2, 0, 0), (0, 0, np.pi / 2, 0.110945, 0), (0, 0.3205, 0, 0, 0)],
        tool=sk.translation([0.3365, 0, 0]),
    )
    th = np.array([q[0], q[1], offset])
    expected = -0.3205 * 0.3365 * np.sin(th[2]) * (0.3205 * np.cos(th[1]) + 0.3365 * np.cos(th[1] + th[2]))
    assert abs(np.linalg.det(chain.position_jacobian(th)) - expected) < 1e-15
