"""spotkin.plot.walk_animation: a walk recorded by the simulator, animated. The frames are the recorded
ticks at the frame rate asked (fewer when capped), each frame's feet are where the recorded body pose and
joints put them (the robot's FK, computed here from the recording), the feet in contact are the ones the
simulator found touching, the camera follows the body, the GIF is written, and bad input is refused by
name."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import spotkin as sk

pytest.importorskip("mujoco", reason='the walk is simulated: pip install "spotkin[sim]"')
matplotlib = pytest.importorskip("matplotlib", reason='needs matplotlib: pip install "spotkin[plot]"')
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the optional imports)
from PIL import Image  # noqa: E402  (a dependency of matplotlib)

from spotkin import plot, sim  # noqa: E402

GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))
RATE = 500.0  # the simulator's default control rate


@pytest.fixture(scope="module")
def walk():
    result = sim.run(GO2, sk.GaitController(GO2, "trot"), duration=1.0, velocity=(0.2, 0.0, 0.0))
    assert not result.metrics.fell
    return result


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _animate(robot, result, **options):
    anim = plot.walk_animation(robot, result, **options)
    anim._draw_was_started = True  # drawn frame by frame here, never played: no warning when collected
    return anim


def _artist(fig, gid):
    for ax in fig.axes:
        for artist in ax.get_children():
            if artist.get_gid() == gid:
                return artist
    raise AssertionError(f"no artist {gid!r}")


def _points(fig, gid) -> np.ndarray:
    """(m, 3) or (m, 2) data of a drawn line."""
    line = _artist(fig, gid)
    if hasattr(line, "get_data_3d"):
        return np.array(line.get_data_3d(), dtype=np.float64).T
    return np.asarray(line.get_xydata(), dtype=np.float64)


def _rotation(quaternion) -> np.ndarray:
    """World <- body rotation of an (x, y, z, w) unit quaternion."""
    x, y, z, w = quaternion
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _simulated_feet(robot, result, tick: int) -> np.ndarray:
    """(n, 3) the feet at a recorded tick: the recorded body pose, the recorded joints, the robot's FK."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = _rotation(result.quaternion[tick]), result.position[tick]
    return np.asarray(robot.body_fk(T, result.q[tick]))


def test_the_frames_are_the_ticks_at_the_frame_rate(walk):
    span = walk.t[-1] - walk.t[0]
    anim = _animate(GO2, walk)  # 20 frames a second by default
    count = math.floor(span * 20) + 1
    assert count == 20
    assert len(list(anim.new_frame_seq())) == count
    np.testing.assert_array_equal(anim.ticks, np.arange(count) * round(RATE / 20))
    assert anim.frame_interval == pytest.approx(50.0)  # real time
    anim = _animate(GO2, walk, fps=8)
    assert len(list(anim.new_frame_seq())) == math.floor(span * 8) + 1
    np.testing.assert_allclose(walk.t[anim.ticks], np.arange(len(anim.ticks)) / 8, atol=0.5 / RATE)
    anim = _animate(GO2, walk, fps=20, max_frames=7)  # capped: spread over the walk, still in real time
    assert len(list(anim.new_frame_seq())) == 7
    assert anim.ticks[0] == 0 and anim.ticks[-1] == len(walk.t) - 1
    np.testing.assert_allclose(walk.t[anim.ticks], np.linspace(walk.t[0], walk.t[-1], 7), atol=0.5 / RATE)
    assert anim.frame_interval == pytest.approx(1e3 * span / 6)


@pytest.mark.parametrize("view", ["3d", "side"])
def test_each_frames_feet_are_where_the_simulator_put_them(walk, view):
    anim = _animate(GO2, walk, view=view)
    fig = anim.figure
    columns = [0, 1, 2] if view == "3d" else [0, 2]  # the side view draws x and z
    in_the_air = 0
    for k in range(len(anim.ticks)):
        anim._func(k)
        tick = k * round(RATE / 20)
        feet = _simulated_feet(GO2, walk, tick)
        np.testing.assert_allclose(_points(fig, "feet"), feet[:, columns], atol=1e-9)
        down = walk.contact[tick]
        np.testing.assert_allclose(_points(fig, "contact"), feet[down][:, columns], atol=1e-9)
        in_the_air += int((~down).sum())
        if down.any():  # the feet in contact are on the ground: level with each other within a few mm
            assert np.ptp(feet[down, 2]) < 0.005
        assert np.isclose(_points(fig, "body-path")[-1], walk.position[tick][columns]).all()
        assert f"t = {walk.t[tick]:.2f} s" in fig.axes[0].get_title()
    assert in_the_air > 0  # a trot lifts its feet
    footholds = _points(fig, "footholds")
    assert len(footholds) >= 4  # every foot touched down at the start at least


def test_the_camera_follows_the_body_or_frames_the_walk(walk):
    anim = _animate(GO2, walk)
    ax = anim.figure.axes[0]
    middles, widths = [], []
    for k in (0, len(anim.ticks) - 1):
        anim._func(k)
        middles.append(np.mean(ax.get_xlim()))
        widths.append(np.ptp(ax.get_xlim()))
    moved = walk.position[anim.ticks[-1], 0] - walk.position[0, 0]
    assert moved > 0.02
    assert middles[1] - middles[0] == pytest.approx(moved, abs=1e-9)
    assert widths[0] == pytest.approx(widths[1])
    assert not ax.axison  # no box moving under the robot
    anim = _animate(GO2, walk, follow=False)
    ax = anim.figure.axes[0]
    limits = ax.get_xlim(), ax.get_ylim(), ax.get_zlim()
    anim._func(len(anim.ticks) - 1)
    assert (ax.get_xlim(), ax.get_ylim(), ax.get_zlim()) == limits
    every_foot = np.concatenate([_simulated_feet(GO2, walk, tick) for tick in anim.ticks])
    for axis, (low, high) in enumerate(limits):
        assert low <= every_foot[:, axis].min() + 1e-9 and every_foot[:, axis].max() <= high + 1e-9


def test_saving_writes_a_gif(walk, tmp_path):
    fig = plt.figure(figsize=(3.0, 2.0))
    anim = plot.walk_animation(GO2, walk, fps=10, fig=fig, title="Go2 trotting")
    path = tmp_path / "walk.gif"
    anim.save(str(path), dpi=40)
    assert path.read_bytes().startswith(b"GIF89a")
    with Image.open(path) as image:
        assert image.size == (120, 80)
        assert image.n_frames == 10
        assert image.info["duration"] == 100
    assert fig.axes[0].get_title().startswith("Go2 trotting: t = ")


def test_a_robot_with_an_arm_is_drawn_with_it():
    spot = sk.Spot()
    result = sim.run(spot, sk.GaitController(spot, "trot"), duration=0.3, velocity=(0.2, 0.0, 0.0))
    q_arm = np.array([0.0, -1.2, 1.9, 0.0, 0.4, 0.0])
    anim = _animate(spot, result, q_arm=q_arm, view="side", fps=10)
    anim._func(2)
    tick = 2 * round(RATE / 10)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = _rotation(result.quaternion[tick]), result.position[tick]
    hand = spot.fk_all(T, result.q[tick], q_arm).hand
    np.testing.assert_allclose(_points(anim.figure, "hand")[0], hand[[0, 2], 3], atol=1e-9)
    np.testing.assert_allclose(
        _points(anim.figure, "feet"), _simulated_feet(spot, result, tick)[:, [0, 2]], atol=1e-9
    )


def _bad_cases(walk):
    plan = GO2.plan_gait("trot", velocity=[0.2, 0.0, 0.0], duration=0.2, rate=50)
    blind = sim.run(GO2, sk.GaitController(GO2, "stand"), duration=0.05, record=False)
    nan_q = walk.q.copy()
    nan_q[3, 2] = np.nan
    return [
        ({"robot": "go2"}, TypeError, "robot"),
        ({"result": "walk"}, TypeError, "result"),
        ({"result": plan}, TypeError, "result"),  # a plan is no simulated walk
        ({"result": blind}, ValueError, "result"),
        ({"result": dataclasses.replace(walk, q=walk.q[:, :9])}, ValueError, "result.q"),
        ({"result": dataclasses.replace(walk, q=nan_q)}, ValueError, "result.q"),
        ({"fps": 0}, ValueError, "fps"),
        ({"fps": -20.0}, ValueError, "fps"),
        ({"fps": math.nan}, ValueError, "fps"),
        ({"fps": "20"}, TypeError, "fps"),
        ({"max_frames": 0}, ValueError, "max_frames"),
        ({"max_frames": 2.5}, TypeError, "max_frames"),
        ({"view": "back"}, ValueError, "view"),
        ({"view": 3}, TypeError, "view"),
        ({"follow": "yes"}, TypeError, "follow"),
        ({"q_arm": np.zeros(6)}, ValueError, "q_arm"),  # Go2 has no arm
        ({"fig": "figure"}, TypeError, "fig"),
        ({"title": 3}, TypeError, "title"),
    ]


def test_bad_input_is_refused_by_name(walk):
    for change, error, name in _bad_cases(walk):
        arguments = {"robot": GO2, "result": walk, **change}
        with pytest.raises(error, match=name):
            plot.walk_animation(arguments.pop("robot"), arguments.pop("result"), **arguments)
