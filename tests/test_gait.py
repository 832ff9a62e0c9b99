"""Gaits and the reference gait planner (issue 35): the presets' contact patterns, the swing curve, the
footholds and their workspace bound, the crawl's support margin, the plan's q, qd and torques, roles
from hip positions, gait transitions, and bad input."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from fuzz.urdf_texts import HEXAPOD_URDF
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from spotkin.reference import gait as ref
from spotkin.reference import gait_plan

GO2_PATH = Path(sk.__file__).parent / "robots" / "go2.urdf"
SPOT = sk.Spot()
GO2 = sk.Robot.from_urdf(GO2_PATH)
ROBOTS = {"spot": SPOT, "go2": GO2}
PRESETS = ("stand", "walk", "trot", "pace", "bound", "pronk", "gallop")


def _by_role(robot, values) -> dict:
    return dict(zip(robot.leg_roles, values))


def _schedule(resolved, t):
    """The steady contacts (ticks, 4) at times t, from the reference phase and contact."""
    return np.array([ref.contact(ref.phase(x, resolved.offsets, resolved.period), resolved.duty) for x in t])


@pytest.mark.parametrize("name", PRESETS)
def test_each_preset_has_its_contact_pattern(name):
    resolved = sk.Gait(name).resolve(SPOT)
    t = np.linspace(0.0, resolved.period, 2001)[:-1]
    down = {role: column for role, column in zip(resolved.roles, _schedule(resolved, t).T)}
    fl, fr, hl, hr = (down[r] for r in ("front_left", "front_right", "hind_left", "hind_right"))
    for column in down.values():  # each foot is down for the duty's fraction of the cycle
        assert abs(column.mean() - min(resolved.duty, 1.0)) <= 1e-3
    if name == "trot":
        assert (fl == hr).all() and (fr == hl).all() and (fl != fr).any()
    elif name == "pace":
        assert (fl == hl).all() and (fr == hr).all() and (fl != fr).any()
    elif name == "bound":
        assert (fl == fr).all() and (hl == hr).all() and (fl != hl).any()
    elif name in ("pronk", "stand"):
        assert (fl == fr).all() and (fl == hl).all() and (fl == hr).all()
    elif name == "walk":
        swinging = 4 - np.array([fl, fr, hl, hr]).sum(axis=0)
        assert swinging.max() == 1  # one foot in swing at a time
        lifts = {role: t[np.flatnonzero(~column & np.roll(column, 1))[0]] for role, column in down.items()}
        order = sorted(lifts, key=lambda role: (lifts[role] - lifts["hind_left"]) % resolved.period)
        assert order == ["hind_left", "front_left", "hind_right", "front_right"]  # the lateral sequence


@given(st.floats(0.0, 20.0), st.floats(0.05, 0.95))
def test_the_duty_is_the_stance_fraction_at_any_start(start, duty):
    gait = sk.Gait(
        "custom",
        offsets=dict.fromkeys(("front_left", "front_right", "hind_left", "hind_right"), 0.3),
        duty=duty,
    )
    t = start + np.arange(4000) / 4000.0
    down = np.array([ref.contact(ref.phase(x, [0.3], 1.0), gait.duty)[0] for x in t])
    assert abs(down.mean() - duty) <= 2e-3


@given(
    st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3),
    st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3),
    st.floats(0.0, 0.2),
)
def test_the_swing_starts_and_ends_at_rest_reaches_its_apex_and_is_smooth(p0, p1, height):
    s = np.linspace(0.0, 1.0, 2001)
    samples = [ref.swing(p0, p1, x, height) for x in s]
    p = np.array([row[0] for row in samples])
    dp = np.array([row[1] for row in samples])
    np.testing.assert_allclose(p[0], p0, atol=1e-15)
    np.testing.assert_allclose(p[-1], p1, atol=1e-15)
    eps = 1e-5  # central differences of position, the curve held at its ends outside [0, 1]
    for end in (0.0, 1.0):
        ahead, behind = ref.swing(p0, p1, end + eps, height)[0], ref.swing(p0, p1, end - eps, height)[0]
        assert np.abs((ahead - behind) / (2 * eps)).max() <= 1e-8 * (
            1 + height + np.abs(np.subtract(p1, p0)).max()
        )
    apex = max(p0[2], p1[2]) + height
    assert p[:, 2].max() == pytest.approx(apex, abs=1e-12)
    assert ref.swing(p0, p1, 0.5, height)[0][2] == pytest.approx(apex, abs=1e-12)
    h = s[1] - s[0]  # the velocity is the derivative and continuous, the acceleration bounded
    np.testing.assert_allclose((p[2:] - p[:-2]) / (2 * h), dp[1:-1], atol=1e-4)
    bound = 10 / math.sqrt(3) * max(np.hypot(p1[0] - p0[0], p1[1] - p0[1]), 4 * (apex - min(p0[2], p1[2])))
    assert np.abs(np.diff(dp, axis=0)).max() <= bound * h * 1.01 + 1e-12


@given(
    st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(0.1, 1.0), st.floats(0.2, 0.6)
)
def test_the_raibert_foothold_terms_have_their_sign_and_size(vx, dv, yaw_rate, t_stance, h):
    nominal, r = np.array([0.3, 0.15, 0.0]), np.array([0.3, 0.15])
    # the velocity term: half the stance's travel, ahead
    p = ref.foothold(nominal, r, (vx, 0.0), (vx, 0.0), 0.0, t_stance, h)
    np.testing.assert_allclose(p, nominal + [vx * t_stance / 2, 0.0, 0.0], atol=1e-15)
    # the capture point: faster than commanded, the foot lands k (v - v_cmd) sqrt(h / g) farther
    q = ref.foothold(nominal, r, (vx, 0.0), (vx + dv, 0.0), 0.0, t_stance, h, k=0.7)
    assert q[0] - p[0] == pytest.approx(0.7 * dv * math.sqrt(h / ref.G), abs=1e-12)
    # the yaw rate: the hip's velocity omega z x r
    w = ref.foothold(nominal, r, (0.0, 0.0), (0.0, 0.0), yaw_rate, t_stance, h)
    np.testing.assert_allclose(
        w[:2] - nominal[:2], yaw_rate * np.array([-r[1], r[0]]) * t_stance / 2, atol=1e-15
    )


def test_a_foothold_out_of_reach_is_shortened_towards_the_nominal_one():
    leg, hip = GO2.legs[0], GO2.hip_positions[0]
    resolved = sk.Gait("trot").resolve(GO2)
    pose = sk.body_transform([0.0, 0.0, resolved.height, 0.0, 0.0, 0.0])
    nominal = resolved.stance[0]
    near = nominal + [0.05, 0.0, 0.0]
    assert ref.bounded_foothold(leg, hip, near, nominal, [pose])[1] is False
    far = nominal + [0.6, 0.1, 0.0]
    p, shortened = ref.bounded_foothold(leg, hip, far, nominal, [pose])
    assert shortened
    along = (p - nominal)[:2] / (far - nominal)[:2]
    assert (
        np.ptp(along) <= 1e-12 and p[2] == nominal[2] and 0.0 < along[0] < 1.0
    )  # on the line towards the nominal foot
    assert leg.ik(pose[:3, :3].T @ (p - pose[:3, 3]) - hip)[1] == sk.Status.OK
    beyond = nominal + (p - nominal) * 1.01
    assert leg.ik(pose[:3, :3].T @ (beyond - pose[:3, 3]) - hip)[1] != sk.Status.OK


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_a_command_too_fast_is_shortened_and_every_foot_stays_reachable(name):
    robot = ROBOTS[name]
    h = sk.Gait("trot").resolve(robot).hip_height
    plan = robot.plan_gait("trot", velocity=[6.0 * h, 0.0, 0.3], duration=2.5, rate=100)
    assert plan.shortened.any()
    assert (plan.status == sk.Status.OK).all()  # the legs never get a foot they cannot reach
    slow = robot.plan_gait("trot", velocity=[0.5 * h, 0.0, 0.0], duration=1.5, rate=100)
    assert not slow.shortened.any()


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_the_crawl_keeps_the_centre_of_mass_inside_its_support_polygon(name):
    robot = ROBOTS[name]
    resolved = sk.Gait("walk").resolve(robot)
    h = resolved.hip_height
    plan = robot.plan_gait("walk", velocity=[0.3 * h, 0.0, 0.0], duration=2.5 * resolved.period, rate=100)
    assert (plan.status == sk.Status.OK).all()
    assert plan.margin.min() > 0.02  # m, at every tick: three feet or four
    assert (plan.contact.sum(axis=1) >= 3).all()
    assert plan.body_pose[-1, 0] > 0.2 * h * resolved.period  # it walks
    # the margin is robot.standing_torques's (its support polygon and centre of mass)
    for k in range(0, len(plan.t), 37):
        standing = robot.standing_torques(plan.body_pose[k], plan.q[k], stance=plan.contact[k])
        assert standing.margin == pytest.approx(plan.margin[k], abs=1e-9)


@pytest.mark.parametrize("name", ["spot", "go2"])
def test_the_plan_q_gives_its_feet_and_qd_is_the_rate_of_q(name):
    robot = ROBOTS[name]
    h = sk.Gait("trot").resolve(robot).hip_height
    errors = []
    for rate in (200, 400):
        plan = robot.plan_gait(
            "trot", velocity=[0.8 * h, 0.1 * h, 0.4], duration=1.5, rate=rate, attitude=(0.05, -0.04)
        )
        assert (plan.status == sk.Status.OK).all()
        np.testing.assert_allclose(robot.body_fk(plan.body_pose, plan.q), plan.feet, rtol=0, atol=1e-9)
        central = (plan.q[2:] - plan.q[:-2]) * (rate / 2)
        errors.append(np.abs(central - plan.qd[1:-1]).max())
        assert errors[-1] <= 0.03 * np.abs(plan.qd).max()
        # seeded with the previous tick's q: no branch flip, no jump
        assert np.abs(np.diff(plan.q, axis=0)).max() <= 1.5 * np.abs(plan.qd).max() / rate
    assert errors[1] < errors[0] / 3  # the central differences converge to qd: O(dt^2)


def test_the_stance_forces_carry_the_weight():
    plan = SPOT.plan_gait("trot", velocity=[0.3, 0.0, 0.2], duration=1.5, rate=100)
    four = np.flatnonzero(plan.contact.all(axis=1))
    two = np.flatnonzero(plan.contact.sum(axis=1) == 2)
    assert len(four) and len(two)
    for k in four[::5]:  # four feet: the torques of robot.standing_torques, every moment balanced
        standing = SPOT.standing_torques(plan.body_pose[k], plan.q[k])
        np.testing.assert_allclose(plan.tau[k], standing.tau, atol=1e-9)
        assert np.abs(plan.residual[k]).max() <= 1e-9
    weight = np.array([0.0, 0.0, -SPOT.mass * ref.G])
    for k in two[::7]:  # two feet: the weight carried, its moment about their line is what is left
        com = SPOT.center_of_mass(plan.body_pose[k], plan.q[k])
        forces, residual = ref.stance_forces(plan.feet[k], plan.contact[k], com, SPOT.mass)
        np.testing.assert_allclose(forces.sum(axis=0), -weight, atol=1e-9)
        np.testing.assert_allclose(residual, plan.residual[k], atol=1e-12)
        a, b = plan.feet[k][plan.contact[k]]
        axis = (b - a) / np.linalg.norm(b - a)
        assert residual[3:] @ axis == pytest.approx(-np.cross(com - a, weight) @ axis, abs=1e-9)
        assert np.linalg.norm(residual[3:] - (residual[3:] @ axis) * axis) <= 1e-9
        assert np.isfinite(plan.tau[k]).all()


def _renamed_go2() -> sk.Robot:
    """Go2 with the front-left and hind-right legs' names swapped, and the front-right and hind-left's."""
    text = GO2_PATH.read_text()
    swaps = {"FL_": "RR_", "RR_": "FL_", "FR_": "RL_", "RL_": "FR_"}
    text = re.sub("FL_|RR_|FR_|RL_", lambda m: swaps[m.group(0)], text)
    return sk.Robot.from_urdf_string(text)


def test_roles_come_from_the_hips_not_the_joint_names():
    renamed = _renamed_go2()
    assert _by_role(renamed, renamed.leg_names)["front_left"] == "RR"  # its names lie
    a, b = (
        robot.plan_gait("trot", velocity=[0.2, 0.0, 0.0], duration=1.0, rate=100) for robot in (GO2, renamed)
    )
    contact_a, contact_b = _by_role(GO2, a.contact.T), _by_role(renamed, b.contact.T)
    feet_a, feet_b = _by_role(GO2, a.feet.transpose(1, 0, 2)), _by_role(renamed, b.feet.transpose(1, 0, 2))
    assert not contact_a["front_left"].all()  # it steps
    for role in contact_a:
        np.testing.assert_array_equal(contact_a[role], contact_b[role])
        np.testing.assert_allclose(feet_a[role], feet_b[role], atol=1e-12)


def test_gait_transitions_keep_the_feet_and_body_continuous():
    robot = GO2
    gaits = {name: sk.Gait(name).resolve(robot) for name in ("walk", "trot", "pace", "bound")}
    h, rate = gaits["trot"].hip_height, 200
    changes = [
        (3.0, gaits["trot"], None),
        (5.0, gaits["pace"], None),
        (7.0, gaits["trot"], None),
        (8.5, gaits["bound"], [0.3 * h, 0.0, 0.2]),
    ]
    out = gait_plan.plan(robot, gaits["walk"], [0.5 * h, 0.0, 0.0], 10.0, rate, changes=changes)
    assert (out["status"] == 0).all()
    steps = np.abs(np.diff(out["feet"], axis=0)).max()
    assert steps <= 4.0 / rate  # no foot moves faster than 4 m/s: none teleports
    assert np.abs(np.diff(out["body_pose"], axis=0)).max() <= 1.0 / rate
    central = (out["q"][2:] - out["q"][:-2]) * (rate / 2)
    assert np.abs(central - out["qd"][1:-1]).max() <= 0.05 * np.abs(out["qd"]).max()
    # after each blend, the new gait's pattern: the trot's diagonals, the pace's sides
    roles = robot.leg_roles
    down = {role: out["contact"][:, k] for k, role in enumerate(roles)}
    trot = (out["t"] > 4.2) & (out["t"] < 5.0)
    pace = (out["t"] > 6.2) & (out["t"] < 7.0)
    assert (down["front_left"][trot] == down["hind_right"][trot]).all()
    assert (down["front_left"][pace] == down["hind_left"][pace]).all()
    assert (down["front_left"][pace] != down["front_right"][pace]).any()


@pytest.mark.parametrize(
    ("before", "after"),
    [("pace", "trot"), ("trot", "pace"), ("walk", "trot"), ("trot", "bound"), ("bound", "gallop")],
)
def test_a_gait_change_moves_the_offsets_least(before, after):
    """The offsets blend the shorter way round, all shifted by the one c that makes the largest move
    smallest (the new gait's pattern, its clock relabelled): from the pace to the trot each pair moves
    a quarter cycle, not the hind pair a half, and no leg's clock ever runs backwards in the blend."""
    robot = GO2
    old, new = sk.Gait(before).resolve(robot), sk.Gait(after).resolve(robot)
    state = gait_plan.start(robot, old)
    state.t, state.t0, state.duration = 5.0, 0.0, 0.0  # long settled in the old gait
    gait_plan.change(state, new)
    move = state.new["offsets"] - state.old["offsets"]
    shortest = (new.offsets - old.offsets + 0.5) % 1.0 - 0.5
    assert np.abs(move).max() == pytest.approx((shortest.max() - shortest.min()) / 2.0, abs=1e-12)
    relabel = (state.new["offsets"] - new.offsets) % 1.0
    assert np.ptp((relabel - relabel[0] + 0.5) % 1.0 - 0.5) < 1e-12  # the new pattern, one c for all
    if (before, after) == ("pace", "trot"):
        assert np.abs(move).max() == pytest.approx(0.25)
    # the clock changes speed over at least the periods' difference (the crawl's 8 sqrt(h / g) to
    # the trot's 2.5 sqrt(h / g) over more than the trot's own period)
    assert state.duration >= max(new.period, abs(old.period - new.period))
    for t in np.linspace(state.t, state.t + state.duration, 201):
        P, Pd = gait_plan.blended(state, t)
        assert (1.0 / P["period"] + Pd["offsets"] > 0.0).all()  # each leg's phase moves forwards


def test_standing_holds_the_body_still():
    plan = SPOT.plan_gait("stand", velocity=[0.5, 0.0, 0.3], duration=0.5, rate=50)
    assert plan.contact.all()
    np.testing.assert_allclose(
        plan.body_pose, np.broadcast_to(plan.body_pose[0], plan.body_pose.shape), atol=1e-15
    )
    assert np.abs(plan.qd).max() <= 1e-12


def test_plan_gait_broadcasts_commands():
    velocity = np.array([[[0.1, 0.0, 0.0]], [[0.0, 0.05, 0.2]]])  # (2, 1, 3)
    plan = GO2.plan_gait(sk.Gait("trot"), velocity=velocity, duration=0.3, rate=100)
    ticks = len(plan.t)
    assert plan.body_pose.shape == (2, 1, ticks, 6) and plan.feet.shape == (2, 1, ticks, 4, 3)
    assert plan.status.shape == (2, 1, ticks) and plan.status.dtype == np.int8
    one = GO2.plan_gait("trot", velocity=velocity[1, 0], duration=0.3, rate=100)
    for name in sk.GaitPlan._fields[1:]:
        np.testing.assert_array_equal(getattr(plan, name)[1, 0], getattr(one, name))


def test_the_defaults_scale_with_the_robot():
    spot, go2 = (sk.Gait("trot").resolve(robot) for robot in (SPOT, GO2))
    for resolved in (spot, go2):  # Froude scaling: T / sqrt(h / g) is the preset's constant
        assert resolved.period / math.sqrt(resolved.hip_height / ref.G) == pytest.approx(2.5)
        assert resolved.step_height == pytest.approx(0.15 * resolved.hip_height)
    assert spot.hip_height > go2.hip_height and spot.period > go2.period
    custom = sk.Gait("trot", period=0.4, duty=0.55, step_height=0.07, height=0.3).resolve(GO2)
    assert (custom.period, custom.duty, custom.step_height, custom.height) == (0.4, 0.55, 0.07, 0.3)
    assert sk.Gait.__module__ == sk.GaitPlan.__module__ == "spotkin"


def test_bad_input_gets_a_clear_answer():
    with pytest.raises(ValueError, match=r"unknown gait 'canter'.*trot"):
        sk.Gait("canter")
    for period in (0.0, -0.5, math.nan, math.inf):
        with pytest.raises(ValueError, match="period"):
            sk.Gait("trot", period=period)
    for duty in (0.0, 1.0, 1.5, -0.1, math.nan):
        with pytest.raises(ValueError, match="duty"):
            sk.Gait("trot", duty=duty)
    with pytest.raises(ValueError, match=r"unknown roles.*FL_hip_joint"):
        sk.Gait("custom", duty=0.6, offsets={"FL_hip_joint": 0.0, "front_right": 0.5})
    with pytest.raises(ValueError, match="missing"):
        sk.Gait("trot", offsets={"front_left": 0.0, "front_right": 0.5})
    with pytest.raises(ValueError, match="custom gait needs"):
        sk.Gait("custom", duty=0.5)
    with pytest.raises(ValueError, match=r"above 0\.75"):
        sk.Gait("walk", duty=0.7)
    with pytest.raises(TypeError, match="period"):
        sk.Gait("trot", period="fast")
    with pytest.raises(ValueError, match="quadrupeds"):
        sk.Gait("trot").resolve(sk.Robot.from_urdf_string(HEXAPOD_URDF))
    with pytest.raises(ValueError, match="velocity must be finite"):
        GO2.plan_gait("trot", velocity=[math.nan, 0.0, 0.0], duration=0.1)
    with pytest.raises(ValueError, match="velocity"):
        GO2.plan_gait("trot", velocity=[0.1, 0.0], duration=0.1)
    with pytest.raises(ValueError, match="duration"):
        GO2.plan_gait("trot", duration=-1.0)
    with pytest.raises(TypeError, match="gait"):
        GO2.plan_gait(3, duration=0.1)


@pytest.mark.parametrize(("duty", "factor"), [(0.6, 2.5), (0.5, 2.5), (0.75, 3.0), (0.4, 2.2)])
@pytest.mark.parametrize("h", [0.25, 0.53])
def test_the_pendulum_sway_is_the_periodic_orbit_s_fundamental(duty, factor, h):
    """``pendulum_sway`` against the linear inverted pendulum integrated exactly, piece by piece:
    y'' = w^2 (y - p(t)), p = +-1 (W = 1) while one side's pair alone is down, 0 otherwise; the
    periodic orbit's initial state solves x(T) = x(0); its fundamental, by quadrature, is kappa, and
    the higher harmonics are under 5 % of it for the presets' period factors."""
    period = factor * math.sqrt(h / ref.G)
    omega = math.sqrt(ref.G / h)
    alone = min(duty, 1.0 - duty) * period
    n = 4000
    dt = period / n
    t = (np.arange(n) + 0.5) * dt
    # centred on t = 0: +1 around 0, -1 around T / 2
    p = np.where(np.abs((t + period / 2) % period - period / 2) < alone / 2, 1.0, 0.0)
    p -= np.where(np.abs(t - period / 2) < alone / 2, 1.0, 0.0)
    c, s = math.cosh(omega * dt), math.sinh(omega * dt)
    step = np.array([[c, s / omega], [omega * s, c]])  # (y - p, y') over dt at a constant p

    def period_map(x):
        states = []
        for k in range(n):
            z = step @ np.array([x[0] - p[k], x[1]])
            x = np.array([z[0] + p[k], z[1]])
            states.append(x[0])
        return x, np.array(states)

    zero, _ = period_map(np.zeros(2))
    Phi = np.column_stack([period_map(e)[0] - zero for e in np.eye(2)])
    x0 = np.linalg.solve(np.eye(2) - Phi, zero)
    end, y = period_map(x0)
    np.testing.assert_allclose(end, x0, atol=1e-9)  # periodic
    samples = np.arange(1, n + 1) * dt
    harmonics = [
        2.0 / n * abs(np.sum(y * np.exp(-2j * math.pi * k * samples / period))) for k in (1, 2, 3, 5)
    ]
    kappa = ref.pendulum_sway(duty, period, h)
    assert harmonics[0] == pytest.approx(kappa, rel=2e-3)
    assert max(harmonics[1:]) < 0.05 * kappa
