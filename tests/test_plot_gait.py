"""spotkin.plot.gait_diagram and foot_paths: the bars are the contacts given, the paths the feet's own
(leg.fk relative to the hip-pitch joint), over the region the leg reaches; bad input gets a clear answer."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk

plot = pytest.importorskip("spotkin.plot")
import matplotlib.pyplot as plt  # noqa: E402  (after the optional import)

GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))


@pytest.fixture(scope="module")
def plan():
    return GO2.plan_gait("trot", velocity=[0.3, 0.0, 0.0], duration=1.0, rate=100)


def _artist(fig, gid):
    for ax in fig.axes:
        for artist in ax.get_children():
            if artist.get_gid() == gid:
                return artist
    return None


def test_the_gait_diagram_draws_each_legs_stance(plan):
    measured = plan.contact.copy()
    measured[10:20, 0] = False
    fig = plot.gait_diagram(plan.contact, plan.t, legs=GO2.leg_names, measured=measured, title="trot")
    try:
        dt = plan.t[1] - plan.t[0]
        for k in range(4):
            bars = _artist(fig, f"stance:{k}")
            drawn = sum(width for _, width in _spans(bars))
            assert drawn == pytest.approx(plan.contact[:, k].sum() * dt)
        assert sum(w for _, w in _spans(_artist(fig, "measured:0"))) == pytest.approx(
            measured[:, 0].sum() * dt
        )
        labels = [tick.get_text() for tick in fig.axes[0].get_yticklabels()]
        assert labels == list(GO2.leg_names)[::-1]
        assert fig.axes[0].get_title() == "trot"
    finally:
        plt.close(fig)
    fig, ax = plt.subplots()
    try:
        assert plot.gait_diagram(plan.contact.astype(int), ax=ax) is fig  # 0 / 1, tick numbers
    finally:
        plt.close(fig)


def _spans(collection):
    """(x, width) of a broken_barh collection's rectangles."""
    out = []
    for path in collection.get_paths():
        xs = path.vertices[:, 0]
        out.append((xs.min(), xs.max() - xs.min()))
    return out


def test_the_foot_paths_are_the_feet_relative_to_the_hips(plan):
    fig = plot.foot_paths(GO2, plan.q, title="Go2")
    try:
        assert len([ax for ax in fig.axes if ax.get_visible()]) == 4
        names = list(GO2.leg_joint_names)
        for k, leg in enumerate(GO2.legs):
            columns = [names.index(j) for j in leg.joint_names]
            feet = leg.fk(plan.q[:, columns]) - leg.a
            drawn = np.asarray(_artist(fig, f"path:{k}").get_xydata())
            np.testing.assert_allclose(drawn, feet[:, [0, 2]], atol=1e-12)
            # the path lies in the region drawn as reachable: the leg's IK reaches every planned foot
            assert (np.asarray(leg.ik(feet + leg.a)[1]) == 0).all()
    finally:
        plt.close(fig)
    fig, ax = plt.subplots()
    try:
        assert plot.foot_paths(GO2, plan.q, ax=ax) is fig
    finally:
        plt.close(fig)


def test_bad_input_gets_a_clear_answer(plan):
    with pytest.raises(TypeError, match="bool"):
        plot.gait_diagram(np.full((5, 4), 0.5))
    with pytest.raises(ValueError, match="ticks, n_legs"):
        plot.gait_diagram(np.ones(4, dtype=bool))
    with pytest.raises(ValueError, match="increasing"):
        plot.gait_diagram(plan.contact, plan.t[::-1])
    with pytest.raises(ValueError, match="legs"):
        plot.gait_diagram(plan.contact, legs=["a", "b"])
    with pytest.raises(ValueError, match="measured"):
        plot.gait_diagram(plan.contact, measured=plan.contact[:5])
    with pytest.raises(TypeError, match="robot"):
        plot.foot_paths(GO2.legs[0], plan.q)
    with pytest.raises(ValueError, match="q must"):
        plot.foot_paths(GO2, plan.q[:, :6])
    with pytest.raises(ValueError, match="finite"):
        plot.foot_paths(GO2, np.full((3, 12), np.nan))
    fig = plt.figure()
    try:
        with pytest.raises(ValueError, match="2D"):
            plot.foot_paths(GO2, plan.q, ax=fig.add_subplot(projection="3d"))
    finally:
        plt.close(fig)
