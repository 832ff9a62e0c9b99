"""Whole-body reach (``Robot.reach``): the batched search against its pure-Python reference, the
success rate on targets made from random feasible configurations, round trips through FK (hand and
feet), every constraint checked by independent code (joint limits, the box, the support margin from
``standing_torques``, the capsules), statuses, bad input and batch semantics. On Spot (built in, its
arm's dedicated closed form) and on Go2 carrying a Z1-like arm (three parallel axes) with the Z1's
joint ranges."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from urdf_helpers import robot_named

import spotkin as sk
from spotkin.motion import reach as reach_module
from spotkin.motion.capsules import capsule_model
from spotkin.reference import reach as ref
from spotkin.reference import reach_geometry

ROBOTS = ("spot", "go2_z1", "heavy_ur5")  # three arm families: Spot's, a Z1-like one, a UR5


_TARGETS: dict = {}


def targets_of(name: str, n: int = 1000, seed: int = 11):
    key = (name, n, seed)
    if key not in _TARGETS:
        robot = robot_named(name)
        _TARGETS[key] = ref.feasible_samples(reach_module.reference_problem(robot, np.eye(4)), n, seed)
    return _TARGETS[key]


def check_answers(robot, T, res, feet=None, margin=None, stance=None):
    """Every OK answer: the hand on the target and the feet on theirs (1e-10), joints within limits, the
    body within the default box (offsets in the ``stance`` frame, default the world's), the support
    margin (from standing_torques) at least ``margin``, and no collision (the reference's capsule
    check)."""
    h0, L, nominal_feet = reach_module._scales(robot)
    feet = nominal_feet if feet is None else feet
    margin = reach_module.MARGIN_FRACTION * L if margin is None else margin
    ok = np.asarray(res.status) == sk.ReachStatus.OK
    pose, q = res.body_pose[ok], res.q[ok]
    frames = robot.fk_all(pose, q)
    assert np.abs(frames.hand - T[ok]).max(initial=0.0) < 1e-10
    assert np.abs(frames.feet - feet).max(initial=0.0) < 1e-10
    limits = robot.limits
    assert ((q >= limits[:, 0] - 1e-12) & (q <= limits[:, 1] + 1e-12)).all()
    box = reach_module.default_box(robot)
    if stance is not None:
        local = np.linalg.solve(stance, sk.body_transform(pose))
        pose_in_stance = np.array([ref.pose_of(T_local) for T_local in local]).reshape(-1, 6)
    else:
        pose_in_stance = pose
    offset = pose_in_stance - [0.0, 0.0, h0, 0.0, 0.0, 0.0]
    assert ((offset >= box.lower - 1e-9) & (offset <= box.upper + 1e-9)).all()
    standing = robot.standing_torques(pose, q)
    assert np.all(np.asarray(standing.margin) >= margin - 1e-9)
    np.testing.assert_allclose(standing.margin, np.asarray(res.margin)[ok], atol=1e-9)
    problem = reach_module.reference_problem(robot, np.eye(4), feet)
    assert not any(ref.collides(problem, row, T) for row, T in zip(q, sk.body_transform(pose)))


@pytest.mark.parametrize("name", ROBOTS)
def test_success_rate_on_feasible_targets(name):
    """At least 99.5 % of targets made from feasible configurations are reached exactly, with every
    constraint held."""
    robot = robot_named(name)
    T, _, _ = targets_of(name)
    res = robot.reach(T)
    solved = np.mean(res.status == sk.ReachStatus.OK)
    assert solved >= 0.995, f"{name}: {solved:.2%} solved"
    assert set(np.unique(res.status)) <= {sk.ReachStatus.OK, sk.ReachStatus.UNREACHABLE}
    check_answers(robot, T, res)


def _compare(robot, T, feet=None, seed=None, margin=None):
    res = robot.reach(T, feet=feet, seed=seed, margin=margin)
    for k in range(len(T)):
        problem = reach_module.reference_problem(
            robot,
            T[k],
            None if feet is None else feet[k],
            None if seed is None else (seed[0][k], seed[1][k]),
            margin,
        )
        want = ref.reach(problem)
        assert res.status[k] == want["status"], k
        assert res.arm_branch[k] == want["slot"], k
        np.testing.assert_allclose(res.body_pose[k], want["body_pose"], atol=1e-7, err_msg=str(k))
        np.testing.assert_allclose(res.q[k], want["q"], atol=1e-7, err_msg=str(k))
        np.testing.assert_allclose(res.margin[k], want["margin"], atol=1e-7, err_msg=str(k))
        np.testing.assert_allclose(res.distance[k], want["distance"], atol=1e-7, err_msg=str(k))
        np.testing.assert_allclose(res.arm_branches[k], want["branches"], atol=1e-7, err_msg=str(k))
        np.testing.assert_array_equal(res.arm_valid[k], want["valid"])
    return res


@pytest.mark.parametrize("name", ROBOTS)
def test_batched_search_matches_the_reference(name):
    robot = robot_named(name)
    T, _, _ = targets_of(name, 8, seed=3)
    far = T[:2].copy()
    far[:, :3, 3] += [[0.0, 0.0, 3.0], [-2.5, 1.0, 0.0]]  # out of reach: the repair and its fallback
    bad = T[:1].copy()
    bad[0, 0, 0] = math.nan
    res = _compare(robot, np.concatenate([T, far, bad]))
    assert list(res.status[-3:]) == [sk.ReachStatus.UNREACHABLE] * 2 + [sk.ReachStatus.INVALID_INPUT]


@pytest.mark.parametrize("name", ROBOTS)
def test_seeded_search_matches_the_reference(name):
    robot = robot_named(name)
    T, _, _ = targets_of(name, 5, seed=4)
    first = robot.reach(T)
    moved = T.copy()
    moved[:, :3, 3] += [0.01, -0.01, 0.005]
    _compare(robot, moved, seed=(first.body_pose, first.q))


def _planar_motion(yaw, shift):
    G = np.eye(4)
    G[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    G[:3, 3] = shift
    return G


@pytest.mark.parametrize("name", ROBOTS)
def test_moving_the_feet_and_the_target_together_moves_the_answer_only(name):
    """(S): a stance turned and shifted (feet and target by the same planar motion) gives the same
    joints, and the body pose moved by that motion; the reference agrees on the moved problem."""
    robot = robot_named(name)
    T, _, _ = targets_of(name, 6, seed=5)
    G = _planar_motion(0.7, [1.5, -2.0, 0.3])
    feet = reach_module._scales(robot)[2]
    moved_feet = feet @ G[:3, :3].T + G[:3, 3]
    here = robot.reach(T)
    there = _compare(robot, G @ T, feet=np.broadcast_to(moved_feet, (6, robot.n_legs, 3)))
    np.testing.assert_allclose(there.q, here.q, atol=1e-7)
    np.testing.assert_allclose(
        sk.body_transform(there.body_pose), G @ sk.body_transform(here.body_pose), atol=1e-9
    )
    check_answers(robot, G @ T, there, feet=moved_feet, stance=G)


def test_unreachable_target_gets_the_nearest_pose_reached():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 1, seed=6)
    far = T[0].copy()
    far[:3, 3] = [3.0, 0.5, 0.6]
    res = robot.reach(far)
    assert res.status == sk.ReachStatus.UNREACHABLE and res.arm_branch == -1
    hand = robot.fk_all(res.body_pose, res.q).hand
    assert res.distance == pytest.approx(np.linalg.norm(hand[:3, 3] - far[:3, 3]), abs=1e-9)
    assert 1.5 < res.distance < 3.0
    angle = np.linalg.norm(ref.rotation_log(far[:3, :3] @ hand[:3, :3].T))
    assert res.angle == pytest.approx(angle, abs=1e-9)
    limits = robot.limits
    assert ((res.q >= limits[:, 0] - 1e-12) & (res.q <= limits[:, 1] + 1e-12)).all()
    np.testing.assert_allclose(
        robot.body_fk(res.body_pose, res.q), reach_module._scales(robot)[2], atol=1e-10
    )


def test_unstable_when_only_poses_below_the_margin_reach():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 3, seed=7)
    res = robot.reach(T, margin=5.0)  # no centre of mass is 5 m inside Spot's feet
    assert (res.status == sk.ReachStatus.UNSTABLE).all()
    frames = robot.fk_all(res.body_pose, res.q)
    assert np.abs(frames.hand - T).max() < 1e-10  # the hand still on the target
    assert (res.distance == 0.0).all() and (res.margin < 5.0).all()
    check_answers(robot, T, robot.reach(T, margin=np.array([0.0, 5.0, 0.0])), margin=0.0)


def test_bad_samples_get_invalid_input_alone():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 1, seed=8)
    good = T[0]
    nan = good.copy()
    nan[1, 3] = math.nan
    scaled = good.copy()
    scaled[:3, :3] *= 1.01
    reflected = good.copy()
    reflected[:3, 0] *= -1.0
    last_row = good.copy()
    last_row[3, 2] = 0.5
    batch = np.stack([good, nan, scaled, reflected, last_row, good])
    res = robot.reach(batch)
    assert list(res.status) == [0, 3, 3, 3, 3, 0]
    assert (
        np.isnan(res.q[1:5]).all()
        and np.isnan(res.body_pose[1:5]).all()
        and (res.arm_branch[1:5] == -1).all()
    )
    feet = np.broadcast_to(reach_module._scales(robot)[2], (2, 4, 3)).copy()
    feet[1, 2, 0] = math.inf
    assert list(robot.reach(good, feet=feet).status) == [0, 3]
    assert list(robot.reach(good, margin=[0.02, math.nan]).status) == [0, 3]
    first = robot.reach(good)
    seed_q = np.stack([first.q, first.q])
    seed_q[1, 0] = math.nan
    assert list(robot.reach(good, seed=(first.body_pose, seed_q)).status) == [0, 3]


def test_bad_arguments_raise_naming_them():
    spot = robot_named("spot")
    with pytest.raises(ValueError, match="T_hand_world"):
        spot.reach(np.eye(3))
    with pytest.raises(ValueError, match="feet"):
        spot.reach(np.eye(4), feet=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="box"):
        spot.reach(np.eye(4), box=np.zeros((2, 5)))
    with pytest.raises(ValueError, match="box"):
        spot.reach(np.eye(4), box=np.array([np.ones(6), -np.ones(6)]))
    with pytest.raises(ValueError, match="seed q"):
        spot.reach(np.eye(4), seed=(np.zeros(6), np.zeros(12)))
    with pytest.raises(TypeError, match="seed"):
        spot.reach(np.eye(4), seed="previous")
    with pytest.raises(TypeError, match="T_hand_world"):
        spot.reach("eye")
    with pytest.raises(ValueError, match="do not broadcast"):
        spot.reach(np.broadcast_to(np.eye(4), (3, 4, 4)), margin=np.zeros(2))
    with pytest.raises(ValueError, match="reach needs an arm"):
        robot_named("go2").reach(np.eye(4))


@pytest.mark.parametrize("lead", [(), (1,), (3, 1, 2), (0,)])
def test_batch_shapes_broadcast(lead):
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 2, seed=9)
    margins = np.array([0.02, 0.03])  # broadcasts against the targets' leading dimensions
    targets = np.broadcast_to(T[0], (*lead, 4, 4))
    res = robot.reach(targets) if lead != (3, 1, 2) else robot.reach(targets, margin=margins)
    assert res.body_pose.shape == (*lead, 6) and res.q.shape == (*lead, 18)
    assert res.arm_branches.shape == (*lead, 8, 6) and res.arm_valid.shape == (*lead, 8)
    if lead == ():
        assert isinstance(res.status, sk.ReachStatus) and isinstance(res.margin, float)
        assert isinstance(res.arm_branch, int)
    else:
        expected = (3, 1, 2) if lead == (3, 1, 2) else lead  # the margins' (2,) broadcasts into (3, 1, 2)
        assert res.status.shape == expected and res.status.dtype == np.int8
    if math.prod(lead):
        single = robot.reach(T[0])
        flat = res.q.reshape(-1, 18)
        np.testing.assert_allclose(flat, np.broadcast_to(single.q, flat.shape), atol=1e-12)


def test_float32_noncontiguous_and_empty():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 4, seed=10)
    res32 = robot.reach(T.astype(np.float32))
    assert res32.body_pose.dtype == np.float32 and res32.q.dtype == np.float32
    assert (res32.status == sk.ReachStatus.OK).all()
    strided = np.repeat(T, 2, axis=0)[::2]
    assert not strided.flags.c_contiguous
    np.testing.assert_allclose(robot.reach(strided).q, robot.reach(T).q, atol=1e-12)
    empty = robot.reach(np.zeros((0, 4, 4)))
    assert empty.q.shape == (0, 18) and empty.status.shape == (0,)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.integers(1, 3), min_size=0, max_size=3), st.integers(0, 3))
def test_any_batch_shape_answers_each_sample_as_alone(lead, pick):
    robot = robot_named("go2_z1")
    T, _, _ = targets_of("go2_z1", 4, seed=12)
    lead = tuple(lead)
    count = math.prod(lead)
    chosen = np.array([T[(pick + k) % 4] for k in range(count)]).reshape(*lead, 4, 4)
    res = robot.reach(chosen)
    assert res.q.shape == (*lead, 18)
    statuses = np.reshape(res.status, lead)
    for k, index in enumerate(np.ndindex(*lead)):
        alone = robot.reach(T[(pick + k) % 4])
        # the arm's closed form alone differs by an ulp or so between one pose and a batch (its scalar
        # and lane paths), which the refinement's differences can grow to ~1e-10
        np.testing.assert_allclose(res.q[index], alone.q, atol=1e-8)
        assert statuses[index] == alone.status


def test_a_moving_target_with_seeds_gives_a_continuous_answer():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 1, seed=13)
    result, jumps = robot.reach(T[0]), []
    for step in range(1, 30):
        target = T[0].copy()
        target[:3, 3] += step * np.array([0.004, -0.003, 0.002])
        nxt = robot.reach(target, seed=result)
        assert nxt.status == sk.ReachStatus.OK
        jumps.append(np.abs(np.asarray(nxt.q) - np.asarray(result.q)).max())
        result = nxt
    assert max(jumps) < 0.1, max(jumps)


def test_capsule_distances_against_dense_sampling():
    rng = np.random.default_rng(2)
    s = np.linspace(0.0, 1.0, 801)
    for _ in range(200):
        a, b, c, d = rng.normal(size=(4, 3))
        centre, half = rng.normal(size=3) * 0.3, rng.random(3) * 0.5
        p = a + s[:, None] * (b - a)
        outside = np.maximum(np.abs(p - centre) - half, 0.0)
        dense_box = np.sqrt((outside**2).sum(-1)).min()
        box = reach_geometry.segment_box_distance(a, b, centre, half)
        assert box <= dense_box + 1e-12 and dense_box - box < 5e-3
        q = c + s[:, None] * (d - c)
        dense = np.sqrt(((p[:, None, :] - q[None, :, :]) ** 2).sum(-1)).min()
        seg = reach_geometry.segment_distance(a, b, c, d)
        assert seg <= dense + 1e-12 and dense - seg < 5e-3
    assert reach_geometry.segment_distance([0, 0, 0], [0, 0, 0], [1, 0, 0], [1, 1, 0]) == pytest.approx(1.0)
    assert reach_geometry.segment_box_distance([2, 0, 0], [2, 0, 0], [0, 0, 0], [1, 1, 1]) == pytest.approx(
        1.0
    )


def test_capsule_model_flags_an_arm_through_the_body():
    spot = robot_named("spot")
    model = capsule_model(spot, spot.chain("arm_hand"))
    assert model.radius == pytest.approx(0.04 * min(leg.reach[1] for leg in spot.legs))
    assert len(model.arm_points) >= 3 and model.arm_vs_body.any()
    problem = reach_module.reference_problem(spot, np.eye(4))
    stance = np.asarray(spot.body_ik(problem.nominal, problem.feet).q)
    forward = np.concatenate([stance, [0.0, -0.5, 0.5, 0.0, 0.0, 0.0]])  # the arm up and forward
    T_nominal = sk.body_transform(problem.nominal)
    assert not ref.collides(problem, forward, T_nominal)
    through = np.concatenate([stance, [math.pi, 0.5, 0.3, 0.0, 0.0, 0.0]])  # down behind, into the body
    assert ref.collides(problem, through, T_nominal)


@pytest.mark.parametrize("name", ROBOTS)
def test_reach_path_holds_every_constraint_at_every_sample(name):
    robot = robot_named(name)
    T, _, _ = targets_of(name, 12, seed=14)
    feet = reach_module._scales(robot)[2]
    problem = reach_module.reference_problem(robot, np.eye(4))
    limits = robot.limits
    margin = reach_module.MARGIN_FRACTION * reach_module._scales(robot)[1]
    done = 0
    for k in range(len(T) - 1):
        start = robot.reach(T[k])
        path = robot.reach_path(start, T[k + 1], n=30)
        assert path.body_pose.shape == (30, 6) and path.q.shape == (30, 18) and path.t.shape == (30,)
        np.testing.assert_array_equal(path.body_pose[0], start.body_pose)
        np.testing.assert_allclose(path.q[0], start.q, atol=1e-12)
        if path.status != sk.ReachStatus.OK:
            assert not path.ok.all()
            continue
        done += 1
        assert path.ok.all() and path.order in (
            "together",
            "body_first",
            "arm_first",
            "via_zero",
            "via_middle",
        )
        np.testing.assert_array_equal(path.body_pose[-1], path.answer.body_pose)
        np.testing.assert_array_equal(path.q[-1], path.answer.q)
        hand = robot.fk_all(path.body_pose[-1], path.q[-1]).hand
        assert np.abs(hand - T[k + 1]).max() < 1e-10
        assert np.abs(robot.body_fk(path.body_pose, path.q) - feet).max() < 1e-10  # the feet never move
        assert ((path.q >= limits[:, 0] - 1e-12) & (path.q <= limits[:, 1] + 1e-12)).all()
        standing = robot.standing_torques(path.body_pose, path.q)
        assert (np.asarray(standing.margin) >= margin - 1e-9).all()
        np.testing.assert_allclose(standing.margin, path.margin, atol=1e-9)
        assert not any(
            ref.collides(problem, row, T) for row, T in zip(path.q, sk.body_transform(path.body_pose))
        )
        steps = np.abs(np.diff(path.q, axis=0)).max(axis=1)
        assert steps[0] < 0.05 * steps.max() + 1e-12 and steps[-1] < 0.05 * steps.max() + 1e-12  # at rest
    assert done >= len(T) - 3


def test_reach_path_stays_at_the_start_when_the_target_is_out_of_reach():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 1, seed=15)
    start = robot.reach(T[0])
    far = T[0].copy()
    far[:3, 3] += [3.0, 0.0, 0.0]
    path = robot.reach_path(start, far, n=5)
    assert path.status == sk.ReachStatus.UNREACHABLE and path.order == "start"
    np.testing.assert_array_equal(path.q, np.broadcast_to(start.q, (5, 18)))
    assert path.ok.all()  # the start itself holds


def test_reach_path_bad_arguments():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 1, seed=15)
    start = robot.reach(T[0])
    with pytest.raises(ValueError, match="n must be in"):
        robot.reach_path(start, T[0], n=1)
    with pytest.raises(ValueError, match="n must be in"):
        robot.reach_path(start, T[0], n=10**9)  # refused before any memory is taken
    with pytest.raises(ValueError, match="start q"):
        robot.reach_path((start.body_pose, start.q[:12]), T[0])
    with pytest.raises(TypeError, match="start"):
        robot.reach_path("here", T[0])
    with pytest.raises(ValueError, match="target"):
        robot.reach_path(start, np.eye(3))
    with pytest.raises(ValueError, match="start must be finite"):
        robot.reach_path((start.body_pose * np.nan, start.q), T[0])
    with pytest.raises(ValueError, match="reach_path needs an arm"):
        robot_named("go2").reach_path((np.zeros(6), np.zeros(12)), T[0])


def test_reach_is_bit_identical_for_any_thread_count():
    robot = robot_named("go2_z1")
    T, _, _ = targets_of("go2_z1", 300, seed=16)
    threads = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = robot.reach(T)
        sk.set_num_threads(2)
        two = robot.reach(T)
    finally:
        sk.set_num_threads(threads)
    np.testing.assert_array_equal(one.q, two.q)
    np.testing.assert_array_equal(one.body_pose, two.body_pose)
    np.testing.assert_array_equal(one.status, two.status)


@pytest.mark.parametrize("name", ROBOTS)
def test_reachability_answers_hold_every_constraint(name):
    robot = robot_named(name)
    _, _, qs = targets_of(name, 40, seed=17)
    problem = reach_module.reference_problem(robot, np.eye(4))
    # the hands of feasible arm configurations at the nominal body pose, and two points out of any reach
    hands = robot.fk_all(problem.nominal, qs).hand
    points = np.concatenate([hands[:, :3, 3], [[4.0, 0.0, 0.5], [0.0, -3.0, 2.0]]])
    result = robot.reachability(points, spacing=0.1)
    assert result.reachable.shape == (42,) and result.q.shape == (42, 18) and result.hand.shape == (42, 4, 4)
    assert not result.reachable[-2:].any()
    assert result.reachable[:-2].mean() > 0.5
    assert result.volume == pytest.approx(result.reachable.sum() * 0.1**3)
    ok = result.reachable
    frames = robot.fk_all(result.body_pose[ok], result.q[ok])
    assert np.abs(frames.hand - result.hand[ok]).max() < 1e-10
    assert np.abs(frames.hand[:, :3, 3] - points[ok]).max() < 1e-10
    assert np.abs(robot.body_fk(result.body_pose[ok], result.q[ok]) - problem.feet).max() < 1e-10
    limits = robot.limits
    assert ((result.q[ok] >= limits[:, 0] - 1e-12) & (result.q[ok] <= limits[:, 1] + 1e-12)).all()
    standing = robot.standing_torques(result.body_pose[ok], result.q[ok])
    assert (np.asarray(standing.margin) >= problem.margin - 1e-9).all()
    poses = sk.body_transform(result.body_pose[ok])
    assert not any(ref.collides(problem, row, T) for row, T in zip(result.q[ok], poses))
    assert np.isnan(result.q[~ok]).all()


def test_reachability_along_an_approach_and_on_a_grid():
    spot = robot_named("spot")
    points = np.array([[0.9, 0.0, 0.6], [0.8, 0.3, 0.3], [0.6, -0.2, 0.9]])
    down = spot.reachability(points, approach=[0.0, 0.0, -1.0])
    ok = down.reachable
    assert ok.any()
    np.testing.assert_allclose(
        down.hand[ok][:, :3, 0], np.broadcast_to([0.0, 0.0, -1.0], (ok.sum(), 3)), atol=1e-12
    )
    per_point = spot.reachability(
        points, approach=[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], axis="x"
    )
    assert per_point.reachable.shape == (3,)
    grid = spot.reachability(spacing=0.25)
    assert grid.points.ndim == 4 and grid.reachable.shape == grid.points.shape[:-1]
    assert grid.spacing == 0.25 and grid.volume == pytest.approx(grid.reachable.sum() * 0.25**3)
    assert 0.5 < grid.volume < 10.0  # Spot's arm reaches about a metre
    assert (grid.points[..., 2] >= reach_module._scales(spot)[2][:, 2].min() - 1e-12).all()


def test_reachability_prunes_only_what_no_reach_attains():
    """The points searched lie within the arm's length plus the box's motion of its nominal base: every
    hand of a feasible configuration does."""
    from spotkin.motion import reachability as module

    for name in ROBOTS:
        robot = robot_named(name)
        T, _, _ = targets_of(name, 1000, seed=11)
        numbers = reach_module._numbers(robot)
        box = reach_module.default_box(robot)
        base = module._arm_base(robot, numbers.feet)
        first = np.asarray(numbers.chain.frames(np.zeros(6)))[1, :3, 3]
        lo, hi = np.abs(box.lower), np.abs(box.upper)
        limit = module._arm_length(numbers.chain) + np.linalg.norm(np.maximum(lo[:3], hi[:3]))
        limit += np.maximum(lo[3:], hi[3:]).sum() * np.linalg.norm(first)
        assert np.linalg.norm(T[:, :3, 3] - base, axis=1).max() <= limit


def test_reachability_bad_arguments():
    spot = robot_named("spot")
    with pytest.raises(ValueError, match="approach"):
        spot.reachability([[0.9, 0.0, 0.6]], approach=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="axis"):
        spot.reachability([[0.9, 0.0, 0.6]], axis="w")
    with pytest.raises(ValueError, match="spacing"):
        spot.reachability([[0.9, 0.0, 0.6]], spacing=-0.1)
    with pytest.raises(ValueError, match="coarser spacing"):
        spot.reachability(spacing=1e-6)  # a grid of 1e19 points: refused before any memory is taken
    with pytest.raises(ValueError, match="points"):
        spot.reachability(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="do not broadcast"):
        spot.reachability(np.zeros((4, 3)), approach=np.ones((3, 3)))
    with pytest.raises(TypeError, match="directions"):
        spot.reachability([[0.9, 0.0, 0.6]], directions=2.5)
    with pytest.raises(ValueError, match="reachability needs an arm"):
        robot_named("go2").reachability([[0.3, 0.0, 0.3]])
    nan = spot.reachability([[math.nan, 0.0, 0.5], [0.9, 0.0, 0.6]])
    assert not nan.reachable[0]


def test_spot_from_its_urdf_reaches_with_its_chain_arm():
    """Spot loaded as any robot (its arm a 6R chain of the spherical-wrist family, not the built-in
    Spot's dedicated closed form): the same success rate, the same answers as the reference."""
    robot = sk.Robot.from_urdf(sk.robots.path("spot_with_arm"))
    assert robot.arm.ik_kind == "6R-spherical-wrist"
    T, _, _ = ref.feasible_samples(reach_module.reference_problem(robot, np.eye(4)), 300, seed=18)
    res = robot.reach(T)
    assert np.mean(res.status == sk.ReachStatus.OK) >= 0.995
    check_answers(robot, T, res)
    _compare(robot, T[:4])


def test_reach_path_flags_a_start_outside_the_box():
    robot = robot_named("spot")
    T, _, _ = targets_of("spot", 2, seed=19)
    start = robot.reach(T[0])
    high = np.array(start.body_pose, float)
    high[2] += 0.1  # above the default box (its top is 0.1 hip heights over the nominal pose)
    legs = np.asarray(robot.body_ik(high, reach_module._scales(robot)[2]).q)
    path = robot.reach_path((high, np.concatenate([legs, start.q[12:]])), T[1], n=10)
    assert not path.ok[0] and path.status != sk.ReachStatus.OK


def test_targets_near_the_arm_singularities_get_exact_answers_or_a_status():
    """Spot's hands from arm configurations within 1e-7 rad of its singular sets (wr0 = 0: the wrist's
    outer axes aligned; el0 = 0: the elbow stretched, at its limit): each answer is exact where OK, and
    every answer finite."""
    robot = robot_named("spot")
    problem = reach_module.reference_problem(robot, np.eye(4))
    _, offsets, qs = targets_of("spot", 40, seed=20)
    q = qs.copy()
    q[:20, 12 + 4] = 1e-7 * np.random.default_rng(1).standard_normal(20)  # wr0 near 0
    q[20:, 12 + 2] = 1e-7  # el0 near 0
    T = robot.fk_all(problem.nominal + offsets, q).hand
    res = robot.reach(T)
    assert set(np.unique(res.status)) <= {
        sk.ReachStatus.OK,
        sk.ReachStatus.UNREACHABLE,
        sk.ReachStatus.UNSTABLE,
    }
    ok = res.status == sk.ReachStatus.OK
    assert ok[:20].mean() > 0.9 and ok[20:].mean() > 0.5
    assert np.abs(robot.fk_all(res.body_pose[ok], res.q[ok]).hand - T[ok]).max() < 1e-9
    assert np.isfinite(res.q).all() and np.isfinite(res.body_pose).all()


def test_a_hand_target_under_the_ground_is_not_reached():
    """The ground (the plane through the lowest foot point) is a capsule constraint: a hand target below
    it, which the arm alone could reach, gets no OK answer."""
    spot = robot_named("spot")
    T = np.eye(4)
    T[:3, :3] = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]  # the gripper pointing down
    T[:3, 3] = [0.9, 0.0, -0.05]
    assert spot.reach(T).status != sk.ReachStatus.OK
    T[2, 3] = 0.25
    above = spot.reach(T)
    assert above.status == sk.ReachStatus.OK
    assert above.body_pose[2] < reach_module._scales(spot)[0]  # the body leans down to it
