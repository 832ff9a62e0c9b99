"""Workspace sampling, workspace volume and dexterity, against closed forms: a leg with no hip
offset reaches a spherical shell, and an unlimited spherical-wrist arm reaches an orientation
exactly when its wrist centre lands in the shoulder's shell."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk


def test_samples_lie_within_the_limits_and_on_the_fk():
    leg = sk.Spot().legs[0]
    samples = sk.workspace(leg, n=5000, seed=1)
    assert (
        samples.q.shape == (5000, 3)
        and samples.points.shape == (5000, 3)
        and samples.branches.shape == (5000,)
    )
    limits = leg.limits
    assert ((samples.q >= limits[:, 0]) & (samples.q <= limits[:, 1])).all()
    np.testing.assert_allclose(samples.points, leg.fk(samples.q), rtol=0, atol=0)
    # every sample's own configuration is a valid branch (up to rounding at a limit)
    assert np.mean(samples.branches >= 1) > 0.999
    # Spot's limits leave exactly one branch for a foot well below the hip
    low = samples.points[:, 2] < -0.1
    assert low.sum() > 1000 and (samples.branches[low] == 1).all()
    again = sk.workspace(leg, n=5000, seed=1)
    np.testing.assert_array_equal(again.q, samples.q)
    assert sk.workspace(leg, n=0).points.shape == (0, 3)


def test_arm_branch_counts_count_the_valid_ik_solutions():
    arm = sk.SpotArm(limits=None)
    samples = sk.workspace(arm, n=2000, seed=3)
    # without limits, every reachable pose has all eight solutions
    assert (samples.branches == 8).mean() > 0.99
    np.testing.assert_allclose(samples.points, arm.fk(samples.q)[:, :3, 3], rtol=0, atol=0)
    limited = sk.workspace(sk.SpotArm(), n=2000, seed=3)
    assert ((limited.branches >= 1) & (limited.branches <= 8)).mean() > 0.99
    assert (limited.branches < 8).any()


def test_chain_without_a_closed_form_gets_minus_one():
    four = [
        (0, 0.3, np.pi / 2, 0.1, 0.0),
        (0, 0.2, 0.3, 0.0, 0.0),
        (0, 0.2, 0.0, 0.1, 0.0),
        (0, 0.1, 0.0, 0.0, 0.0),
    ]
    planar = [(0, 0.3, 0.0, 0.0, 0.0), (0, 0.2, 0.0, 0.0, 0.0), (0, 0.1, 0.0, 0.0, 0.0)]  # 3R, parallel axes
    for rows in (four, planar):
        samples = sk.workspace(sk.Chain.from_dh(rows), n=10, seed=0)
        assert (samples.branches == -1).all()
    with pytest.raises(ValueError, match="no closed form"):
        sk.workspace_volume(sk.Chain.from_dh(planar), n=10)


def test_leg_volume_is_the_spherical_shell():
    """No hip offset, no knee offset, no limits: |p| in [|u - l|, u + l]."""
    upper, lower = 0.32, 0.25
    leg = sk.Leg(hip_offset=0.0, upper=upper, lower=lower, knee_offset=0.0)
    volume, error = sk.workspace_volume(leg, n=400_000, seed=2)
    shell = 4 / 3 * np.pi * ((upper + lower) ** 3 - (upper - lower) ** 3)
    assert error > 0 and abs(volume - shell) < 4 * error
    assert error < 0.005 * shell


def test_three_joint_chain_volume_is_its_box():
    """A Cartesian PPP chain with stroke limits sweeps a box of their product."""
    rows = [
        (1, 0.0, 0.0, 0.0, 0.0),
        (1, 0.0, np.pi / 2, 0.0, np.pi / 2),
        (1, 0.0, np.pi / 2, 0.0, 0.0),
    ]  # z, -y, x
    chain = sk.Chain.from_mdh(rows, limits=[(0.0, 0.4), (0.0, 0.3), (0.0, 0.2)])
    volume, error = sk.workspace_volume(chain, n=100_000, seed=0)
    assert abs(volume - 0.4 * 0.3 * 0.2) < 4 * error + 1e-12


def shell_fraction(d, L, r_in, r_out):
    """The fraction of the sphere of radius L about p (d from the shoulder) inside the shell."""

    def inside_ball(rho):
        return np.clip((rho**2 - (d - L) ** 2) / (4 * d * L), 0.0, 1.0)

    return inside_ball(r_out) - inside_ball(r_in)


def test_dexterity_of_an_unlimited_arm_is_the_shell_fraction():
    mount, upper_arm, forearm, offset, hand = np.zeros(3), 0.35, 0.3, 0.07, 0.2
    arm = sk.SpotArm(mount, upper_arm, forearm, offset, hand, limits=None)
    dex = sk.dexterity(arm, spacing=0.08, orientations=256, seed=0)
    reach = np.hypot(forearm, offset)
    r_in, r_out = abs(upper_arm - reach), upper_arm + reach
    d = np.linalg.norm(dex.positions - mount, axis=1)
    expected = shell_fraction(d, hand, r_in, r_out)
    # wholly inside or wholly outside the shell (with a margin): every or no orientation
    whole = (d - hand > r_in + 1e-3) & (d + hand < r_out - 1e-3)
    none = (d - hand > r_out + 1e-3) | (d + hand < r_in - 1e-3)
    assert whole.sum() > 50 and none.sum() > 50
    assert (dex.fraction[whole] == 1).all() and (dex.fraction[none] == 0).all()
    # elsewhere a binomial estimate of the expected fraction
    assert np.abs(dex.fraction - expected).max() < 0.15
    assert abs(np.mean(dex.fraction - expected)) < 0.01
    assert dex.volume(1.0) == pytest.approx(np.count_nonzero(dex.fraction == 1) * 0.08**3)


def test_dexterity_of_a_six_joint_chain_matches_the_arm():
    """The unlimited Spot arm rebuilt as a Chain from its joints: the same fractions."""
    mount, upper_arm, forearm, offset, hand = (0.292, 0.0, 0.188), 0.3385, 0.40330, 0.0750, 0.19557
    arm = sk.SpotArm(mount, upper_arm, forearm, offset, hand, limits=None)
    placements = np.stack(
        [
            sk.translation(mount),
            np.eye(4),
            sk.translation([upper_arm, 0, 0]),
            sk.translation([forearm, 0, offset]),
            np.eye(4),
            np.eye(4),
        ]
    )
    axes = [(0, 0, 1), (0, 1, 0), (0, 1, 0), (1, 0, 0), (0, 1, 0), (1, 0, 0)]
    chain = sk.Chain.from_joints(placements, axes, tool=sk.translation([hand, 0, 0]))
    q = np.random.default_rng(0).uniform(-3, 3, (20, 6))
    np.testing.assert_allclose(chain.fk(q), arm.fk(q), rtol=0, atol=1e-12)
    dex_arm = sk.dexterity(arm, spacing=0.15, orientations=32, seed=5)
    dex_chain = sk.dexterity(chain, spacing=0.15, orientations=32, seed=5)
    np.testing.assert_allclose(dex_chain.positions, dex_arm.positions, rtol=0, atol=1e-9)
    assert np.abs(dex_chain.fraction - dex_arm.fraction).mean() < 0.01
    assert dex_arm.fraction.max() == 1.0 and dex_arm.fraction.min() == 0.0


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda: sk.workspace("leg"), TypeError, "obj must be a solver"),
        (lambda: sk.workspace(sk.SpotArm(), n=-1), ValueError, "n must be"),
        (lambda: sk.workspace(sk.SpotArm(), n=2.5), TypeError, "n must be an integer"),
        (lambda: sk.workspace(sk.Chain.from_mdh([(1, 0, 0, 0, 0)])), ValueError, "prismatic"),
        (lambda: sk.workspace_volume(sk.SpotArm()), ValueError, "Leg or a 3-joint Chain"),
        (lambda: sk.dexterity(sk.Spot().legs[0]), ValueError, "6-joint"),
        (lambda: sk.dexterity(sk.SpotArm(), spacing=0.0), ValueError, "spacing"),
        (lambda: sk.dexterity(sk.SpotArm(), orientations=0), ValueError, "orientations"),
    ],
)
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_the_workspace_command_reports_the_leg_and_the_arm(capsys):
    from spotkin.__main__ import main

    args = ["workspace", "--robot", "spot", "--samples", "20000", "--spacing", "0.3", "--orientations", "8"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "leg fl: workspace volume within the joint limits" in out
    assert "reached with >= 100 % of the orientations" in out and "without joint limits" in out
    assert main(["workspace", "--robot", "no_such_robot.urdf"]) == 1
