"""spotkin.plot and the CLI's pictures (issue 18), with matplotlib's Agg backend.

What the pictures show is checked against the library's own computations, read back from the artists'
data: the drawn feet are ``body_fk``'s, the hand ``fk_all``'s, the legs' joints ``fk_all``'s, the
links of an unrecognised limb its URDF chain's frames, every branch's foot or tool point its target,
the workspace map's counts ``ik_all``'s at sampled grid points, the curves a trajectory's own samples.
Files are valid PNGs and GIFs of the requested pixel size, the CLI leaks no figure, and without
matplotlib ``import spotkin.plot`` (and the CLI's picture options) say what to install.
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from urdf_helpers import joint, links

import spotkin as sk
from spotkin.__main__ import GIF_SIZE, main

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    from spotkin import plot

    HAVE_MATPLOTLIB = True
except ImportError:  # the tests below that draw are skipped; the ImportError tests still run
    HAVE_MATPLOTLIB = False

ROOT = Path(__file__).resolve().parent.parent
needs_matplotlib = pytest.mark.skipif(
    not HAVE_MATPLOTLIB, reason='needs matplotlib: pip install "spotkin[plot]"'
)
BLOCK_MATPLOTLIB = "import sys; sys.modules['matplotlib'] = None\n"  # any import of it raises ImportError


def _leg(prefix: str, hip: str, side: int) -> str:
    names = [f"{prefix}_{part}" for part in ("hip", "thigh", "calf", "foot")]
    return links(*names) + "".join(
        [
            joint(f"{prefix}_hip_joint", "revolute", "base", names[0], hip, axis="1 0 0", limits=(-0.8, 0.8)),
            joint(
                f"{prefix}_thigh_joint",
                "revolute",
                names[0],
                names[1],
                f"0 {0.08 * side} 0",
                axis="0 1 0",
                limits=(-1.5, 3.0),
            ),
            joint(
                f"{prefix}_calf_joint",
                "revolute",
                names[1],
                names[2],
                "0 0 -0.2",
                axis="0 1 0",
                limits=(-2.6, -0.5),
            ),
            joint(f"{prefix}_foot_joint", "fixed", names[2], names[3], "0 0 -0.21"),
        ]
    )


# Four roll-pitch-pitch legs, a z-y-y limb that is not one (a chain the robot does not solve as a leg) and
# a fixed sensor.
ZOO = (
    '<?xml version="1.0"?><robot name="zoo"><link name="base"/>'
    + _leg("FL", "0.25 0.06 0", 1)
    + _leg("FR", "0.25 -0.06 0", -1)
    + _leg("RL", "-0.25 0.06 0", 1)
    + _leg("RR", "-0.25 -0.06 0", -1)
    + links("YAW_hip", "YAW_thigh", "YAW_calf", "YAW_foot", "lidar")
    + joint("YAW_hip_joint", "revolute", "base", "YAW_hip", "-0.35 0 0.02", axis="0 0 1", limits=(-1, 1))
    + joint("YAW_thigh_joint", "revolute", "YAW_hip", "YAW_thigh", "-0.05 0 0", axis="0 1 0", limits=(-1, 1))
    + joint(
        "YAW_calf_joint", "revolute", "YAW_thigh", "YAW_calf", "0 0 -0.2", axis="0 1 0", limits=(-2, -0.2)
    )
    + joint("YAW_foot_joint", "fixed", "YAW_calf", "YAW_foot", "0 0 -0.2")
    + joint("lidar_joint", "fixed", "base", "lidar", "0.3 0 0.08")
    + "</robot>"
)
ROBOTS = ("spot", "go2", "zoo", "spot_urdf")
HEIGHT = {"spot": 0.5, "go2": 0.28, "zoo": 0.3, "spot_urdf": 0.5}
ARM_Q = np.array([0.3, -1.1, 1.8, 0.2, 0.5, -0.3])


@pytest.fixture(scope="module")
def robots():
    return {
        "spot": sk.Spot(),
        "go2": sk.Robot.from_urdf(sk.robots.path("go2")),
        "zoo": sk.Robot.from_urdf_string(ZOO),
        "spot_urdf": sk.Robot.from_urdf(sk.robots.path("spot_with_arm")),  # its arm is an sk.Chain
    }


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    if HAVE_MATPLOTLIB:
        plt.close("all")


def _artist(ax, gid):
    found = [a for a in ax.get_children() if a.get_gid() == gid]
    assert len(found) == 1, (gid, [a.get_gid() for a in ax.get_children()])
    return found[0]


def _xyz(line) -> np.ndarray:
    return np.array(line.get_data_3d(), dtype=float).T


def _png_size(path) -> tuple[int, int]:
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", f"{path} is not a PNG"
    return struct.unpack(">II", data[16:24])


def _gif_info(path) -> tuple[tuple[int, int], int]:
    data = Path(path).read_bytes()
    assert data[:6] in (b"GIF87a", b"GIF89a"), f"{path} is not a GIF"
    with Image.open(path) as image:
        image.verify()
    with Image.open(path) as image:
        return struct.unpack("<HH", data[6:10]), image.n_frames


def _stance(robot, name, rng):
    """A random body pose near the nominal one and its legs' joints by body_ik (every leg OK)."""
    height = HEIGHT[name]
    feet = robot.stance_feet(height)
    pose = np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]) + rng.uniform(-1, 1, 6) * [
        0.02,
        0.02,
        0.02,
        0.1,
        0.1,
        0.1,
    ]
    result = robot.body_ik(pose, feet)
    assert (result.status == sk.Status.OK).all()
    return pose, result.q


# ---- optional dependency -----------------------------------------------------------------------------------


def _run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=str(ROOT)
    )


def test_spotkin_imports_without_matplotlib_and_plot_says_what_to_install():
    code = BLOCK_MATPLOTLIB + textwrap.dedent(
        """
        import spotkin
        assert spotkin.Spot().leg("fl") is not None
        try:
            import spotkin.plot
        except ImportError as error:
            print(error)
        else:
            raise SystemExit("spotkin.plot imported without matplotlib")
        """
    )
    done = _run(code)
    assert done.returncode == 0, done.stderr
    assert 'pip install "spotkin[plot]"' in done.stdout


def test_importing_spotkin_does_not_import_matplotlib():
    done = _run("import sys, spotkin, spotkin.__main__; print('matplotlib' in sys.modules)")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"


def test_cli_pictures_without_matplotlib_say_what_to_install(tmp_path):
    code = BLOCK_MATPLOTLIB + textwrap.dedent(
        f"""
        from spotkin.__main__ import main
        assert main(["plot", "go2", "--out", {str(tmp_path / "x.png")!r}]) == 1
        assert main(["demo", "--samples", "100", "--plots", {str(tmp_path)!r}]) == 1
        """
    )
    done = _run(code)
    assert done.returncode == 0, done.stderr
    assert done.stderr.count('pip install "spotkin[plot]"') == 2, done.stderr
    assert "Whole body" not in done.stdout  # the missing extra is reported before the showcase runs
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(HAVE_MATPLOTLIB, reason="matplotlib is installed: the subprocess tests block it instead")
def test_plot_import_error_here():
    with pytest.raises(ImportError, match=r'pip install "spotkin\[plot\]"'):
        import spotkin.plot  # noqa: F401


# ---- the robot ---------------------------------------------------------------------------------------------


@needs_matplotlib
@pytest.mark.parametrize("name", ROBOTS)
def test_drawn_feet_legs_and_hand_are_the_kinematics(robots, name):
    robot = robots[name]
    rng = np.random.default_rng(18)
    pose, q = _stance(robot, name, rng)
    q_arm = ARM_Q if robot.arm is not None else None
    fig = plot.robot(robot, pose, q, q_arm)
    ax = fig.axes[0]
    frames = robot.fk_all(pose, q, q_arm)
    np.testing.assert_allclose(_xyz(_artist(ax, "feet")), robot.body_fk(pose, q), atol=1e-12)
    for k, leg_name in enumerate(robot.leg_names):
        points = _xyz(_artist(ax, f"leg:{leg_name}"))
        np.testing.assert_allclose(points[0], frames.hips[k], atol=1e-12)
        np.testing.assert_allclose(points[2], frames.knees[k], atol=1e-12)
        np.testing.assert_allclose(points[3], frames.feet[k], atol=1e-12)
        # the hip-pitch joint: on the hip-roll axis' circle, |hip pitch - hip| = |a|
        leg = robot.legs[k]
        assert np.linalg.norm(points[1] - points[0]) == pytest.approx(np.linalg.norm(leg.a), abs=1e-12)
    if q_arm is not None:
        np.testing.assert_allclose(_xyz(_artist(ax, "hand"))[0], frames.hand[:3, 3], atol=1e-12)
        arm = _xyz(_artist(ax, "arm"))
        np.testing.assert_allclose(arm[-1], frames.hand[:3, 3], atol=1e-12)
        if isinstance(robot.arm, sk.SpotArm):  # its joints are the URDF chain's joint origins
            chain = robot.chain("arm_hand")
            origins = (sk.body_transform(pose) @ chain.frames(q_arm))[:, :3, 3]
            for point in arm[:-1]:
                assert np.linalg.norm(origins - point, axis=1).min() < 1e-12
    support = _artist(ax, "support")
    assert support is not None and not _xyz(_artist(ax, "beyond-limits")).size
    assert ax.get_xlabel() == "x (m)" and ax.get_zlabel() == "z (m)" and ax.get_legend() is not None


@needs_matplotlib
def test_links_of_an_unrecognised_limb_are_drawn_from_its_chain(robots):
    """The zoo's z-y-y limb is not a leg: it is drawn from joint frame to joint frame at its zero angles
    (clipped into the limits), as its URDF chain places them."""
    robot = robots["zoo"]
    pose, q = _stance(robot, "zoo", np.random.default_rng(3))
    ax = plot.robot(robot, pose, q).axes[0]
    segments = np.array([_xyz(a) for a in ax.get_children() if a.get_gid() == "tree"])
    chain = robot.chain("YAW_foot")
    q_yaw = np.clip(0.0, chain.lower, chain.upper)
    T = sk.body_transform(pose)
    joints = (T @ chain.frames(q_yaw))[:, :3, 3]  # base, three joint frames, the foot
    lidar = (T @ robot.model.placement("lidar"))[:3, 3]
    expected = [(joints[k], joints[k + 1]) for k in range(1, 4)] + [(joints[0], joints[1]), (T[:3, 3], lidar)]
    for start, end in expected:
        distances = [np.abs(s - [start, end]).max() for s in segments if np.linalg.norm(s[1] - s[0]) > 0]
        assert min(distances) < 1e-12, (start, end)
    assert len(segments) == 5


@needs_matplotlib
@pytest.mark.parametrize("name", ROBOTS)
def test_default_stance_stands_on_the_ground(robots, name):
    robot = robots[name]
    ax = plot.robot(robot).axes[0]
    feet = _xyz(_artist(ax, "feet"))
    pose, q = plot._nominal_stance(robot)
    np.testing.assert_allclose(feet, robot.body_fk(pose, q), atol=1e-12)
    radius = 0.036 if isinstance(robot, sk.Spot) else 0.0
    np.testing.assert_allclose(feet[:, 2], radius, atol=1e-9)  # every foot on the ground
    assert (robot.body_ik(pose, feet).status == sk.Status.OK).all()
    zero_pose, zero_q = plot._zero_stance(robot)
    assert robot.body_fk(zero_pose, zero_q)[:, 2].min() == pytest.approx(radius, abs=1e-12)


@needs_matplotlib
def test_joints_beyond_limits_and_singular_legs_are_marked(robots):
    spot = robots["spot"]
    pose, q = _stance(spot, "spot", np.random.default_rng(5))
    q = q.copy()
    q[2] = -3.0  # fl knee below its limit (-2.7929)
    beta = np.arctan2(spot.leg("hl").knee_offset, spot.leg("hl").upper_length)
    q[8] = -beta  # hl stretched: singular (and beyond the knee's upper limit)
    ax = plot.robot(spot, pose, q, title="marked").axes[0]
    frames = spot.fk_all(pose, q)
    beyond = _xyz(_artist(ax, "beyond-limits"))
    singular = _xyz(_artist(ax, "singular"))
    for knee in (frames.knees[0], frames.knees[2]):
        assert np.abs(beyond - knee).max(axis=1).min() < 1e-12
    assert len(beyond) == 2
    np.testing.assert_allclose(singular, frames.knees[2][None], atol=1e-12)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "joint beyond its limits" in labels and "leg at a singular configuration" in labels
    assert ax.get_title() == "marked"


@needs_matplotlib
def test_robot_draws_into_a_given_axes_of_the_requested_size(tmp_path, robots):
    fig = plt.figure(figsize=(4, 3))
    ax = fig.add_subplot(projection="3d")
    assert plot.robot(robots["go2"], ax=ax) is fig
    path = tmp_path / "go2.png"
    fig.savefig(path, dpi=50)
    assert _png_size(path) == (200, 150)


@needs_matplotlib
def test_bad_arguments_raise_errors_that_name_them(robots):
    spot, go2 = robots["spot"], robots["go2"]
    cases = [
        (lambda: plot.robot("spot"), TypeError, "robot"),
        (lambda: plot.robot(spot, [0, 0, 0.5], None), ValueError, "body_pose"),
        (lambda: plot.robot(spot, np.zeros((2, 6))), ValueError, "body_pose"),
        (lambda: plot.robot(spot, [0, 0, 0.5, 0, 0, 0, 2]), ValueError, "body_pose"),  # not a unit quaternion
        (lambda: plot.robot(spot, None, np.zeros(11)), ValueError, "q"),
        (lambda: plot.robot(spot, None, np.full(12, np.nan)), ValueError, "q"),
        (lambda: plot.robot(spot, None, None, np.zeros(5)), ValueError, "q_arm"),
        (lambda: plot.robot(go2, None, None, np.zeros(6)), ValueError, "q_arm"),
        (lambda: plot.robot(spot, seq="XYX2"), ValueError, "seq"),
        (lambda: plot.robot(spot, ax=plt.figure().add_subplot()), ValueError, "ax"),
        (lambda: plot.robot(spot, ax="ax"), TypeError, "ax"),
        (lambda: plot.robot(spot, q="abc"), TypeError, "q"),
        (lambda: plot.branches(spot.leg("fl"), np.zeros((2, 3))), ValueError, "target"),
        (lambda: plot.branches(spot.arm, np.zeros(3)), ValueError, "target"),
        (lambda: plot.branches("leg", np.zeros(3)), TypeError, "solver"),
        (lambda: plot.branches(sk.Chain.from_dh([(0, 0.3, 0, 0, 0)] * 2), np.zeros(3)), ValueError, "chain"),
        (lambda: plot.branches(spot.leg("fl"), np.zeros(3), fig="fig"), TypeError, "fig"),
        (lambda: plot.workspace(spot.leg("fl"), plane="ab"), ValueError, "plane"),
        (lambda: plot.workspace(spot.leg("fl"), plane=1), TypeError, "plane"),
        (lambda: plot.workspace(spot.leg("fl"), resolution=1), ValueError, "resolution"),
        (lambda: plot.workspace(spot.leg("fl"), resolution=2.5), TypeError, "resolution"),
        (lambda: plot.workspace(spot.leg("fl"), offset=np.nan), ValueError, "offset"),
        (lambda: plot.workspace(spot.leg("fl"), extent=[1, 0, 0, 1]), ValueError, "extent"),
        (lambda: plot.workspace(spot.leg("fl"), extent=[0, 1, 0]), ValueError, "extent"),
        (lambda: plot.workspace(spot.arm), ValueError, "3-joint chains"),  # a 6-joint chain
        (lambda: plot.trajectory("traj"), TypeError, "traj"),
        (lambda: plot.trajectory(sk.trajectory.point_to_point([0], [1], 1, 1), t=[[0.0]]), ValueError, "t"),
        (lambda: plot.trajectory(sk.trajectory.point_to_point([0], [1], 1, 1), t=[np.nan]), ValueError, "t"),
        (
            lambda: plot.trajectory(sk.trajectory.point_to_point([0], [1], 1, 1), limits=[0, 1]),
            ValueError,
            "limits",
        ),
        (
            lambda: plot.trajectory(sk.trajectory.point_to_point([0], [1], 1, 1), names=["a", "b"]),
            ValueError,
            "names",
        ),
        (lambda: plot.animate(spot, np.zeros((0, 6)), np.zeros(12)), ValueError, "body_poses"),
        (lambda: plot.animate(spot, [[0, 0, 0.5, 0, 0, 0]] * 2, np.zeros((3, 12))), ValueError, "q"),
        (
            lambda: plot.animate(spot, [[0, 0, 0.5, 0, 0, 0]], np.zeros(12), interval=0),
            ValueError,
            "interval",
        ),
    ]
    for call, error, name in cases:
        with pytest.raises(error, match=name):
            call()


# ---- IK branches -------------------------------------------------------------------------------------------


def _slot_lines(fig) -> dict[int, list]:
    lines: dict[int, list] = {}
    for ax in fig.axes:
        for line in ax.get_lines():
            gid = line.get_gid() or ""
            if gid.startswith("slot:"):
                lines.setdefault(int(gid[5:]), []).append(line)
    return lines


@needs_matplotlib
@pytest.mark.parametrize("name", ("spot", "go2", "zoo"))
def test_every_leg_branch_ends_on_the_target(robots, name):
    robot = robots[name]
    leg = robot.legs[0]
    _, q = _stance(robot, name, np.random.default_rng(7))
    target = leg.fk(q[robot._columns[0]])
    fig = plot.branches(leg, target)
    sol = leg.ik_all(target)
    lines = _slot_lines(fig)
    assert sorted(lines) == np.flatnonzero(sol.exists).tolist()
    for slot, (side, front) in lines.items():
        np.testing.assert_allclose(side.get_xydata()[-1], target[[0, 2]], atol=1e-12)
        np.testing.assert_allclose(front.get_xydata()[-1], target[[1, 2]], atol=1e-12)
        assert (side.get_linestyle() == "-") == bool(sol.valid[slot])
    titles = [ax.get_title() for ax in fig.axes[:4]]
    assert [("✓ valid" in t) for t in titles] == sol.valid.tolist()
    assert f"status {sk.Status(int(sol.status)).name}" in fig._suptitle.get_text()


@needs_matplotlib
def test_branches_of_spot_at_hip_height_and_of_bad_targets(robots):
    leg = robots["spot"].leg("fl")
    fig = plot.branches(leg, [0.3, 0.13, 0.0])
    titles = [ax.get_title() for ax in fig.axes[:4]]
    assert ["✓ valid" in t for t in titles] == [True, False, True, False]  # the tested two-branch case
    assert "beyond limits:" in titles[1]
    for target, status in (([0.9, 0.1, 0.1], "UNREACHABLE"), ([np.nan, 0.0, -0.5], "INVALID_INPUT")):
        fig = plot.branches(leg, target)
        assert not _slot_lines(fig) and f"status {status}" in fig._suptitle.get_text()
        assert sum("no solution" in t.get_text() for ax in fig.axes for t in ax.texts) == 8


@needs_matplotlib
@pytest.mark.parametrize("which", ("spot_arm", "spot_urdf_chain6", "zoo_chain3"))
def test_every_arm_or_chain_solution_reaches_the_target(robots, which):
    if which == "spot_arm":
        solver = robots["spot"].arm
    elif which == "spot_urdf_chain6":
        solver = robots["spot_urdf"].arm
    else:
        solver = robots["zoo"].chain("YAW_foot")
    if which == "zoo_chain3":
        target = solver.fk([0.3, 0.2, -1.0])[:3, 3]
        sol, point = solver.ik_position(target), target
    else:
        target = solver.fk(ARM_Q)
        sol = solver.ik_all(target)
        point = target[:3, 3]
    fig = plot.branches(solver, target)
    lines = _slot_lines(fig)
    assert sorted(lines) == np.flatnonzero(sol.exists).tolist() and len(lines) >= 2
    for slot, (line,) in lines.items():
        np.testing.assert_allclose(_xyz(line)[-1], point, atol=1e-9)
        assert (line.get_linestyle() == "-") == bool(sol.valid[slot])
    assert "status OK" in fig._suptitle.get_text()


# ---- workspace maps ----------------------------------------------------------------------------------------


def _map(fig):
    ax = fig.axes[0]
    image = ax.images[0]
    assert image.get_gid() == "branch-count"
    return ax, np.asarray(image.get_array())


def _grid_points(extent, resolution, plane, offset):
    i, j, k = {"xz": (0, 2, 1), "yz": (1, 2, 0), "xy": (0, 1, 2)}[plane]
    u = np.linspace(extent[0], extent[1], resolution)
    v = np.linspace(extent[2], extent[3], resolution)
    return u, v, (i, j, k)


@needs_matplotlib
@pytest.mark.parametrize(
    ("name", "plane", "offset"),
    [
        ("spot", "xz", 0.11),
        ("spot", "yz", None),
        ("go2", "xz", None),
        ("go2", "xy", -0.3),
        ("zoo", "xz", 0.05),
    ],
)
def test_workspace_counts_are_ik_all_at_sampled_grid_points(robots, name, plane, offset):
    leg = robots[name].legs[1]
    resolution = 60
    fig = plot.workspace(leg, plane, offset, resolution=resolution)
    ax, counts = _map(fig)
    assert counts.shape == (resolution, resolution)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    u, v, (i, j, k) = _grid_points((x0, x1, y0, y1), resolution, plane, offset)
    if offset is None:
        offset = {"xz": leg.hip_offset, "yz": leg.a[0], "xy": -0.75 * leg.reach[1]}[plane]
    rng = np.random.default_rng(11)
    rows, cols = rng.integers(0, resolution, 400), rng.integers(0, resolution, 400)
    points = np.empty((400, 3))
    points[:, i], points[:, j], points[:, k] = u[cols], v[rows], offset
    sol = leg.ik_all(points)
    valid = sol.valid.sum(axis=1)
    expected = np.where(valid > 0, np.minimum(valid, 3), np.where(sol.exists.any(axis=1), -1, -2))
    np.testing.assert_array_equal(counts[rows, cols], expected)
    assert {-2, 1} <= set(np.unique(counts).tolist())
    assert ax.get_xlabel().startswith("xyz"[i]) and "(m" in ax.get_ylabel()


@needs_matplotlib
def test_workspace_shows_spots_uniqueness_result(robots):
    """One valid branch more than about 8 cm below the hip, two near hip height (tests/test_leg.py)."""
    leg = robots["spot"].leg("fl")
    resolution = 160
    fig = plot.workspace(leg, "xz", 0.11, resolution=resolution)
    ax, counts = _map(fig)
    z = np.linspace(*ax.get_ylim(), resolution)
    below = counts[z < -0.08]
    assert (below <= 1).all() and (below == 1).sum() > 1000
    assert (counts[np.abs(z) < 0.065] == 2).sum() > 20
    lowest = [t.get_text() for t in ax.get_legend().get_texts() if t.get_text().startswith("lowest")]
    assert len(lowest) == 1 and -0.08 < float(lowest[0].split("z = ")[1].split(" m")[0]) < 0


@needs_matplotlib
def test_workspace_singular_sets_are_the_legs(robots):
    leg = robots["spot"].leg("fl")
    offset = 0.11
    fig = plot.workspace(leg, "xz", offset, resolution=120)
    ax, _ = _map(fig)
    cylinder = [line.get_xydata() for line in ax.get_lines() if line.get_gid() == "singular:hip-roll"]
    assert len(cylinder) == 2
    for line in cylinder:  # y = offset, z on the line: y² + z² = h² exactly
        np.testing.assert_allclose(offset**2 + line[:, 1] ** 2, leg.hip_offset**2, rtol=1e-12)
    knee = [c for c in ax.collections if c.get_gid() == "singular:knee"]
    assert knee
    vertices = np.concatenate([path.vertices for c in knee for path in c.get_paths()])
    outer = vertices[np.hypot(*vertices.T) > 0.4]
    assert len(outer) > 50
    # the outer knee set (stretched) is the edge of the reach: inside it branches exist, outside none
    for scale, exists in ((0.97, True), (1.03, False)):
        points = np.stack([outer[:, 0] * scale, np.full(len(outer), offset), outer[:, 1] * scale], axis=1)
        assert (leg.ik_all(points).exists.any(axis=1) == exists).mean() > 0.97


@needs_matplotlib
def test_workspace_of_a_3_joint_chain_counts_ik_position(robots):
    chain = robots["zoo"].chain("YAW_foot")
    resolution = 40
    fig = plot.workspace(chain, "xz", 0.0, resolution=resolution)
    ax, counts = _map(fig)
    u = np.linspace(*ax.get_xlim(), resolution)
    v = np.linspace(*ax.get_ylim(), resolution)
    points = np.stack([*np.meshgrid(u, v)], axis=-1)
    points = np.stack([points[..., 0], np.zeros_like(points[..., 0]), points[..., 1]], axis=-1)
    sol = chain.ik_position(points)
    valid = sol.valid.sum(axis=-1)
    expected = np.where(valid > 0, np.minimum(valid, 3), np.where(sol.exists.any(axis=-1), -1, -2))
    np.testing.assert_array_equal(counts, expected)


# ---- trajectories ------------------------------------------------------------------------------------------


@needs_matplotlib
def test_trajectory_curves_are_the_samples_and_limits_are_drawn():
    vmax, amax = np.array([1.5, 1.0, 2.0]), 4.0
    traj = sk.trajectory.point_to_point([0.0, 1.0, -1.6], [0.3, 0.6, -1.2], vmax, amax, "trapezoid")
    t = np.linspace(0.0, traj.duration, 50)
    limits = np.array([(-0.8, 0.8), (-0.9, 2.3), (-2.8, -0.25)])
    fig = plot.trajectory(traj, t, limits=limits, names=("hx", "hy", "kn"))
    q, qd, qdd = traj.sample(t)
    axes = fig.axes
    for ax, values, prefix in zip(axes, (q, qd, qdd), ("q", "qd", "qdd")):
        for k in range(3):
            (line,) = [a for a in ax.get_lines() if a.get_gid() == f"{prefix}:{k}"]
            np.testing.assert_array_equal(line.get_xdata(), t)
            np.testing.assert_array_equal(line.get_ydata(), values[:, k])
    speed = sorted(abs(line.get_ydata()[0]) for line in axes[1].get_lines() if line.get_gid() == "limit:vmax")
    np.testing.assert_allclose(speed, np.repeat(np.sort(vmax), 2))  # one pair per axis: they differ
    accel = [line.get_ydata()[0] for line in axes[2].get_lines() if line.get_gid() == "limit:amax"]
    assert sorted(accel) == [-amax, amax]  # shared: one pair
    # the q panel spans the motion: the limits within its view are lines, the others listed beside it
    bounds = sorted(line.get_ydata()[0] for line in axes[0].get_lines() if line.get_gid() == "limit:q")
    np.testing.assert_allclose(bounds, [-0.9, -0.8, -0.25, 0.8])
    low, high = axes[0].get_ylim()
    assert low <= q.min() and high >= q.max() and all(low <= b <= high for b in bounds)
    beyond = _artist(axes[0], "limits-beyond:q").get_text().splitlines()
    assert beyond[1:] == ["↑ hy ≤ 2.3", "↓ kn ≥ -2.8"]
    assert axes[2].get_xlabel() == "t (s)" and axes[1].get_ylabel() == "qd (rad/s)"
    assert [t.get_text() for t in axes[0].get_legend().get_texts()][:3] == ["hx", "hy", "kn"]


@needs_matplotlib
def test_cartesian_path_curves_are_its_samples():
    poses = np.array([[0.0, 0.0, 0.5, 0.0, 0.0, 0.0], [0.05, 0.06, 0.46, 0.1, -0.08, 0.12]])
    path = sk.trajectory.via_points(poses, vmax=0.1, amax=0.5, wmax=0.4, alphamax=2.0)
    fig = plot.trajectory(path)
    t = np.linspace(0.0, path.duration, 400)
    T, twist = path.sample(t, twist=True)
    series = {
        "x": T[:, 0, 3],
        "z": T[:, 2, 3],
        "vy": twist[:, 1],
        "|v|": np.linalg.norm(twist[:, :3], axis=1),
        "|w|": np.linalg.norm(twist[:, 3:], axis=1),
    }
    lines = {line.get_gid(): line for ax in fig.axes for line in ax.get_lines()}
    for gid, values in series.items():
        np.testing.assert_allclose(lines[gid].get_ydata(), values, atol=1e-15)


# ---- animation and files -----------------------------------------------------------------------------------


@needs_matplotlib
@pytest.mark.parametrize("name", ("spot", "go2", "zoo"))
def test_animation_frames_are_the_kinematics_and_save_as_a_gif(robots, name, tmp_path):
    robot = robots[name]
    height = HEIGHT[name]
    poses = np.array(
        [
            [0.0, 0.0, height, 0.0, 0.0, 0.0],
            [0.02, 0.01, height - 0.02, 0.05, -0.05, 0.08],
            [0.01, -0.02, height - 0.01, -0.05, 0.05, 0.0],
        ]
    )
    q = robot.body_ik(poses, robot.stance_feet(height)).q
    q_arm = np.stack([ARM_Q, ARM_Q + 0.1, ARM_Q - 0.1]) if robot.arm is not None else None
    fig = plt.figure(figsize=(2.4, 2.0))
    anim = plot.animate(robot, poses, q, q_arm, interval=80, fig=fig)
    ax = fig.axes[0]
    np.testing.assert_allclose(_xyz(_artist(ax, "feet")), robot.body_fk(poses[0], q[0]), atol=1e-12)
    path = tmp_path / f"{name}.gif"
    anim.save(str(path), dpi=50)
    assert _gif_info(path) == ((120, 100), 3)
    np.testing.assert_allclose(_xyz(_artist(ax, "feet")), robot.body_fk(poses[-1], q[-1]), atol=1e-12)
    np.testing.assert_allclose(_xyz(_artist(ax, "body-path")), poses[:, :3], atol=1e-12)
    if q_arm is not None:
        hand = robot.fk_all(poses[-1], q[-1], q_arm[-1]).hand
        np.testing.assert_allclose(_xyz(_artist(ax, "hand"))[0], hand[:3, 3], atol=1e-12)
    with Image.open(path) as image:
        assert image.info["duration"] == 80


# ---- the command line --------------------------------------------------------------------------------------


@needs_matplotlib
def test_demo_plots_writes_the_pictures_and_closes_its_figures(tmp_path, capsys):
    folder = tmp_path / "out"
    assert main(["demo", "--samples", "2000", "--plots", str(folder), "--dpi", "40"]) == 0
    out = capsys.readouterr().out
    written = [line.split("wrote ", 1)[1] for line in out.splitlines() if "wrote " in line]
    sizes = {
        "stance": (8, 6),
        "stance_side": (8, 6),
        "leg_branches": (12, 6.5),
        "leg_branches_hip_height": (12, 6.5),
        "arm_branches": (13, 7),
        "workspace": (9.5, 6.5),
        "trajectory": (8, 7),
    }
    expected = [f"spot_{k}.png" for k in sizes] + ["spot_path.gif"]
    go2 = ("stance", "stance_side", "leg_branches", "workspace", "trajectory")
    expected += [f"go2_{k}.png" for k in go2] + ["go2_path.gif"]
    assert [os.path.basename(p) for p in written] == expected
    for path in written:
        assert os.path.getsize(path) <= 200_000, path
        stem = os.path.basename(path).split("_", 1)[1].rsplit(".", 1)[0]
        if path.endswith(".png"):
            width, height = sizes[stem]
            assert _png_size(path) == (round(width * 40), round(height * 40)), path
        else:
            assert _gif_info(path) == ((288, 180), 20)  # 7.2 x 4.5 in: 720 px wide at the default 100 dpi
    assert GIF_SIZE[0] * 100 >= 640
    assert plt.get_fignums() == []


@needs_matplotlib
def test_plot_command_draws_any_urdf_in_its_stance(tmp_path, capsys):
    urdf = tmp_path / "zoo.urdf"
    urdf.write_text(ZOO)
    out = tmp_path / "zoo.png"
    assert main(["plot", str(urdf), "--out", str(out), "--size", "320x240", "--dpi", "80"]) == 0
    assert _png_size(out) == (320, 240)
    assert capsys.readouterr().out.strip() == f"wrote {out}"
    zero = tmp_path / "zero.png"
    assert main(["plot", "go2", "--out", str(zero), "--stance", "zero"]) == 0
    assert _png_size(zero) == (800, 600)
    side = tmp_path / "side.png"
    assert main(["plot", "spot", "--out", str(side), "--view", "side", "--size", "640x480"]) == 0
    assert _png_size(side) == (640, 480)
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "missing.urdf"), "--out", str(out)]) == 1
    assert "spotkin plot:" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["plot", "go2", "--size", "800"])
    assert plt.get_fignums() == []


def test_readme_pictures_exist_and_are_small():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    for name in ("docs/spot_stance.png", "docs/spot_workspace.png"):
        assert f"]({name})" in text
    assert "spotkin demo --plots docs/" in text
    pictures = sorted((ROOT / "docs").glob("*.png")) + sorted((ROOT / "docs").glob("*.gif"))
    assert pictures
    for path in pictures:
        assert path.stat().st_size <= 200_000, path


# ---- issue 32: readable pictures ---------------------------------------------------------------------------


def _overlap(a, b) -> bool:
    """Two display boxes share more than a pixel's sliver."""
    return min(a.x1, b.x1) - max(a.x0, b.x0) > 0.5 and min(a.y1, b.y1) - max(a.y0, b.y0) > 0.5


def _tick_label_boxes(ax, renderer) -> dict[str, list]:
    """Per axis, the display boxes of the tick labels drawn (ticks within the view, non-empty labels)."""
    axes = {"x": ax.xaxis, "y": ax.yaxis}
    if ax.name == "3d":
        axes["z"] = ax.zaxis
    boxes = {}
    for name, axis in axes.items():
        low, high = sorted(axis.get_view_interval())
        locs = axis.get_majorticklocs()
        ticks = axis.get_major_ticks(len(locs))
        span = high - low
        boxes[name] = [
            tick.label1.get_window_extent(renderer)
            for loc, tick in zip(locs, ticks)
            if low - 1e-9 * span <= loc <= high + 1e-9 * span and tick.label1.get_text()
        ]
    return boxes


def _assert_tick_labels_apart(fig) -> None:
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        for name, boxes in _tick_label_boxes(ax, renderer).items():
            assert len(boxes) >= 2, (ax.get_title(), name)
            for k, a in enumerate(boxes):
                for b in boxes[k + 1 :]:
                    assert not _overlap(a, b), (ax.get_title(), name, a, b)


@needs_matplotlib
@pytest.mark.parametrize("which", ("spot_arm", "spot_urdf_chain6", "zoo_chain3"))
def test_tick_labels_of_the_branch_panels_do_not_overlap(robots, which):
    if which == "zoo_chain3":
        solver = robots["zoo"].chain("YAW_foot")
        fig = plot.branches(solver, solver.fk([0.3, 0.2, -1.0])[:3, 3])
    else:
        solver = robots["spot"].arm if which == "spot_arm" else robots["spot_urdf"].arm
        fig = plot.branches(solver, solver.fk([0.4, -1.2, 1.9, 0.3, -0.6, 0.8]))  # the demo's target
    _assert_tick_labels_apart(fig)


@needs_matplotlib
@pytest.mark.parametrize("name", ("spot", "go2"))
def test_tick_labels_of_the_robot_and_its_animation_do_not_overlap(robots, name):
    robot = robots[name]
    _assert_tick_labels_apart(plot.robot(robot))
    pose, q = plot._nominal_stance(robot)
    anim = plot.animate(robot, np.stack([pose, pose + [0.05, 0.03, -0.03, 0.1, -0.1, 0.1]]), q)
    _assert_tick_labels_apart(anim.figure)
    anim._draw_was_started = True  # dropped unplayed on purpose


def _q_of(text: str) -> np.ndarray:
    assert text.startswith("q = (") and text.endswith(")"), text
    return np.array([float(v.rstrip("°")) for v in text[5:-1].split(", ")])


@needs_matplotlib
@pytest.mark.parametrize("which", ("spot_arm", "spot_urdf_chain6", "zoo_chain3", "spot_leg"))
def test_each_branch_panel_prints_its_q_in_degrees(robots, which):
    if which == "spot_leg":
        solver = robots["spot"].leg("fl")
        target = np.array([0.3, 0.13, 0.0])
        sol = solver.ik_all(target)
    elif which == "zoo_chain3":
        solver = robots["zoo"].chain("YAW_foot")
        target = solver.fk([0.3, 0.2, -1.0])[:3, 3]
        sol = solver.ik_position(target)
    else:
        solver = robots["spot"].arm if which == "spot_arm" else robots["spot_urdf"].arm
        target = solver.fk(ARM_Q)
        sol = solver.ik_all(target)
    fig = plot.branches(solver, target)
    lines = _slot_lines(fig)
    texts = {}
    for ax in fig.axes:
        for text in ax.texts:
            if (text.get_gid() or "").startswith("q:"):
                texts[int(text.get_gid()[2:])] = (ax, text.get_text())
    assert sorted(texts) == np.flatnonzero(sol.exists).tolist() and len(texts) >= 2
    for slot, (ax, text) in texts.items():
        assert lines[slot][0].axes is ax  # in the branch's own panel
        np.testing.assert_allclose(_q_of(text), np.degrees(sol.q[slot]), atol=0.05 + 1e-9)
    qs = [text for _, text in texts.values()]
    assert len(set(qs)) == len(qs)  # look-alike branches are told apart


@needs_matplotlib
def test_q_text_gives_prismatic_joints_in_metres():
    chain = sk.Chain.from_dh(
        [(0, 0, 0, 0, 0), (1, 0, 0, 0, 0), (0, 0.3, 0, 0, 0)]
    )  # (sigma, a, alpha, d, theta)
    assert plot._q_text(chain, np.array([0.5, 0.125, -np.pi / 2])) == "q = (28.6°, 0.125 m, -90.0°)"


@needs_matplotlib
def test_titles_name_the_robot_readably(robots):
    def named(name):
        return sk.Robot.from_urdf_string(ZOO.replace('name="zoo"', f'name="{name}"'))

    assert plot._robot_name(robots["go2"]) == "Go2"  # go2_description
    assert plot._robot_name(robots["spot"]) == "Spot"
    assert plot._robot_name(named("anymal_c_robot")) == "Anymal c"
    assert plot._robot_name(named("my-dog_Description")) == "My dog"
    assert plot._robot_name(named("ANYmal_urdf_description")) == "ANYmal"
    assert plot._robot_name(named("_description")) == "Robot"
    assert plot.robot(robots["go2"]).axes[0].get_title().startswith("Go2: body at (")
    pose, q = plot._nominal_stance(robots["go2"])
    anim = plot.animate(robots["go2"], pose[None], q)
    assert anim.figure.axes[0].get_title() == "Go2: frame 1 of 1"
    anim._draw_was_started = True


@needs_matplotlib
@pytest.mark.parametrize("name", ("spot", "go2"))
def test_animation_is_wide_and_its_legend_is_beside_the_robot(robots, name, tmp_path):
    robot = robots[name]
    pose, q = plot._nominal_stance(robot)
    poses = np.stack([pose, pose + [0.05, 0.04, -0.03, 0.1, -0.08, 0.12]])
    anim = plot.animate(robot, poses, robot.body_ik(poses, robot.body_fk(pose, q)).q)
    fig = anim.figure
    path = tmp_path / "wide.gif"
    anim.save(str(path))
    (width, _), frames = _gif_info(path)
    assert width >= 640 and frames == 2
    _assert_legend_beside(fig)


def _assert_legend_beside(fig) -> None:
    """The legend is inside the figure and clear of the axes and of everything drawn of the robot."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent(renderer)
    assert fig.bbox.x0 <= legend.x0 and legend.x1 <= fig.bbox.x1 + 1
    assert fig.bbox.y0 <= legend.y0 and legend.y1 <= fig.bbox.y1 + 1
    assert not _overlap(legend, ax.get_window_extent(renderer))
    drawn = [a for a in ax.get_children() if (a.get_gid() or "").split(":")[0] in ROBOT_GIDS]
    assert len(drawn) > 5
    for artist in drawn:
        assert not _overlap(legend, artist.get_window_extent(renderer)), artist.get_gid()
    for boxes in _tick_label_boxes(ax, renderer).values():
        assert not any(_overlap(legend, box) for box in boxes)


ROBOT_GIDS = {"feet", "leg", "arm", "hand", "body", "support", "body-path", "tool-path", "body-start"}


@needs_matplotlib
@pytest.mark.parametrize("view", ("3d", "side"))
def test_stance_legend_is_beside_the_robot(robots, view):
    _assert_legend_beside(plot.robot(robots["spot"], view=view))


@needs_matplotlib
def test_the_demos_motion_is_visible(robots):
    """The demo's body path moves the body by several centimetres and degrees on each robot: at least
    5 % of the picture's span, and the body's outline at frame 1 stays drawn for comparison."""
    import spotkin.cli.pictures as cli

    for robot, height, scale in ((robots["spot"], 0.5, 1.5), (robots["go2"], 0.3, 0.9)):
        path = sk.trajectory.via_points(cli._scaled_waypoints(height, scale), **cli.DEMO_PATH_LIMITS)
        T = path.sample(np.linspace(0.0, path.duration, cli.GIF_FRAMES))
        legs = robot.body_ik(T, robot.stance_feet(height))
        assert (legs.status == sk.Status.OK).all()
        anim = plot.animate(robot, T, legs.q, cli._held_arm(robot, T) if robot.arm is not None else None)
        ax = anim.figure.axes[0]
        span = max(np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()), np.ptp(ax.get_zlim()))
        assert np.ptp(T[:, :3, 3], axis=0).max() >= 0.05 * span
        np.testing.assert_allclose(
            _xyz(_artist(ax, "body-start"))[:-1], plot._frame(robot, T[0], legs.q[0], None).outline
        )
        anim._draw_was_started = True


@needs_matplotlib
@pytest.mark.parametrize(("view", "axes"), (("side", (0, 2)), ("front", (1, 2)), ("top", (0, 1))))
@pytest.mark.parametrize("name", ("spot", "go2"))
def test_side_front_and_top_views_project_the_robot(robots, name, view, axes):
    robot = robots[name]
    pose, q = _stance(robot, name, np.random.default_rng(32))
    q_arm = ARM_Q if robot.arm is not None else None
    fig = plot.robot(robot, pose, q, q_arm, view=view)
    ax = fig.axes[0]
    assert ax.name != "3d"
    names = "xyz"
    assert (ax.get_xlabel(), ax.get_ylabel()) == (f"{names[axes[0]]} (m)", f"{names[axes[1]]} (m)")
    frames = robot.fk_all(pose, q, q_arm)
    cols = list(axes)
    np.testing.assert_allclose(_artist(ax, "feet").get_xydata(), robot.body_fk(pose, q)[:, cols], atol=1e-12)
    for k, leg_name in enumerate(robot.leg_names):
        points = _artist(ax, f"leg:{leg_name}").get_xydata()
        np.testing.assert_allclose(
            points[[0, 2, 3]],
            np.stack([frames.hips[k], frames.knees[k], frames.feet[k]])[:, cols],
            atol=1e-12,
        )
    if q_arm is not None:
        np.testing.assert_allclose(_artist(ax, "hand").get_xydata()[0], frames.hand[:3, 3][cols], atol=1e-12)
    if view != "top":
        assert _artist(ax, "ground").get_ydata()[0] == pytest.approx(frames.feet[:, 2].min(), abs=1e-12)
    assert ax.get_aspect() == 1.0
    assert view in ax.get_title()


@needs_matplotlib
def test_side_view_draws_into_a_2d_axes_and_refuses_a_3d_one(robots):
    fig = plt.figure()
    ax = fig.add_subplot()
    assert plot.robot(robots["go2"], ax=ax, view="side") is fig
    with pytest.raises(ValueError, match="ax"):
        plot.robot(robots["go2"], ax=ax, view="3d")
    with pytest.raises(ValueError, match="ax"):
        plot.robot(robots["go2"], ax=plt.figure().add_subplot(projection="3d"), view="top")
    with pytest.raises(ValueError, match="view"):
        plot.robot(robots["go2"], view="left")
    with pytest.raises(TypeError, match="view"):
        plot.robot(robots["go2"], view=3)


@needs_matplotlib
def test_the_lowest_target_line_is_drawn_for_legs_only(robots):
    leg_ax = plot.workspace(robots["spot"].leg("fl"), "xz", 0.11, resolution=80).axes[0]
    assert _artist(leg_ax, "lowest-two-branches") is not None
    chain = sk.Chain.from_dh(
        [(0, 0, np.pi / 2, 0.3, 0), (0, 0.3, 0, 0, 0), (0, 0.25, 0, 0, 0)]
    )  # an elbow arm
    ax, counts = _map(plot.workspace(chain, "xz", 0.0, resolution=80))
    assert (counts >= 2).any()  # where the leg's line would be drawn
    assert not [a for a in ax.get_children() if a.get_gid() == "lowest-two-branches"]
    assert not [t for t in ax.get_legend().get_texts() if t.get_text().startswith("lowest")]


@needs_matplotlib
def test_the_q_panel_spans_the_motion_not_far_limits():
    traj = sk.trajectory.point_to_point([0.0, 0.5], [0.4, 0.2], 1.0, 4.0)
    q = traj.sample(np.linspace(0.0, traj.duration, 400))[0]
    far = [(-3 * np.pi, 3 * np.pi), (-np.inf, np.inf)]
    ax = plot.trajectory(traj, limits=far).axes[0]
    low, high = ax.get_ylim()
    assert low <= q.min() and high >= q.max() and high - low <= 1.5 * np.ptp(q)
    assert not [line for line in ax.get_lines() if line.get_gid() == "limit:q"]
    assert _artist(ax, "limits-beyond:q").get_text().splitlines()[1:] == ["↓ q1 ≥ -9.42", "↑ q1 ≤ 9.42"]
    near = [(-0.05, 0.45), (0.1, np.inf)]  # just beyond the motion: drawn and in view
    ax = plot.trajectory(traj, limits=near).axes[0]
    low, high = ax.get_ylim()
    bounds = sorted(line.get_ydata()[0] for line in ax.get_lines() if line.get_gid() == "limit:q")
    assert bounds == [-0.05, 0.1, 0.45] and low < -0.05 and high > 0.5
    assert not [t for t in ax.texts if t.get_gid() == "limits-beyond:q"]


@needs_matplotlib
def test_the_arm_is_drawn_on_its_mount(robots):
    """A robot whose arm's base sits on an offset from the body: the drawn arm is the chain's frames
    composed with ``arm_mount``, its tool point ``fk_all``'s hand."""
    robot = sk.Robot.from_urdf(sk.robots.path("spot_with_arm"))
    mount = sk.body_transform([0.1, -0.05, 0.07, 0.0, 0.3, 0.5])
    robot._arm_mount = mount  # a mount that the URDF does not have, set as the loader sets it
    pose, q = _stance(robot, "spot_urdf", np.random.default_rng(8))
    ax = plot.robot(robot, pose, q, ARM_Q).axes[0]
    T = sk.body_transform(pose) @ robot.arm_mount
    np.testing.assert_allclose(_xyz(_artist(ax, "arm")), (T @ robot.arm.frames(ARM_Q))[:, :3, 3], atol=1e-12)
    np.testing.assert_allclose(
        _xyz(_artist(ax, "hand"))[0], robot.fk_all(pose, q, ARM_Q).hand[:3, 3], atol=1e-12
    )


# ---- whole-body reachability -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def spot_reach(robots):
    """A small grid's reachability of Spot (0.2 m spacing: 1440 points, a third of a second)."""
    return robots["spot"].reachability(spacing=0.2)


def _scattered(ax) -> np.ndarray:
    """(m, 3) the points of the "reachable" scatter, in drawing order."""
    scatter = _artist(ax, "reachable")
    return np.column_stack([np.ma.getdata(v) for v in scatter._offsets3d]).astype(float)


def _reach_axes(fig):
    return next(ax for ax in fig.axes if getattr(ax, "name", "") == "3d")


@needs_matplotlib
def test_reachability_draws_the_reachable_points_coloured_by_height(spot_reach):
    fig = plot.reachability(spot_reach)
    assert isinstance(fig, matplotlib.figure.Figure)
    ax = _reach_axes(fig)
    want = spot_reach.points[spot_reach.reachable]
    assert len(want) > 100
    np.testing.assert_array_equal(_scattered(ax), want)
    np.testing.assert_array_equal(np.asarray(_artist(ax, "reachable").get_array()), want[:, 2])
    bar = next(a for a in fig.axes if a.get_gid() == "height")  # the colour bar spans the heights
    assert bar.get_ylim() == pytest.approx((want[:, 2].min(), want[:, 2].max()))
    title = ax.get_title()
    assert f"{spot_reach.volume:.3f} m³" in title
    assert f"{len(want)} of {spot_reach.reachable.size} points" in title
    spans = np.array([np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()), np.ptp(ax.get_zlim())])
    np.testing.assert_allclose(np.array(ax.get_box_aspect()) / ax.get_box_aspect()[0], spans / spans[0])


@needs_matplotlib
def test_reachability_of_points_along_an_approach(robots):
    spot = robots["spot"]
    points = np.array([[0.8, 0.0, 0.5], [0.6, 0.2, 0.3], [3.0, 0.0, 0.0], [0.7, -0.1, np.nan]])
    result = spot.reachability(points, approach=[1.0, 0.0, 0.0])
    assert result.reachable.tolist() == [True, True, False, False]
    ax = _reach_axes(plot.reachability(result, spot))
    np.testing.assert_array_equal(_scattered(ax), points[:2])
    assert "2 of 4 points reachable" in ax.get_title() and "m³" not in ax.get_title()
    nothing = spot.reachability([[3.0, 0.0, 0.0]])  # nothing reachable: no colour bar, still a picture
    fig = plot.reachability(nothing, title="far away")
    assert len(_scattered(_reach_axes(fig))) == 0 and _reach_axes(fig).get_title() == "far away"
    assert not [a for a in fig.axes if a.get_gid() == "height"]


@needs_matplotlib
def test_reachability_draws_into_a_given_axes(spot_reach, robots):
    fig = plt.figure(figsize=(4, 3))
    ax = fig.add_subplot(projection="3d")
    assert plot.reachability(spot_reach, robots["spot"], ax=ax) is fig
    assert len(_scattered(ax)) == spot_reach.reachable.sum()
    assert _artist(ax, "feet") is not None


@needs_matplotlib
def test_reachability_draws_the_robot_at_the_reach_nominal_pose(spot_reach, robots):
    """The robot stands where the reach's box is centred: the body at the nominal height over the
    nominal stance's feet (the default of ``reachability``), or over the feet it was given."""
    from spotkin.motion.reach import _scales

    spot = robots["spot"]
    h0, _, feet = _scales(spot)
    ax = _reach_axes(plot.reachability(spot_reach, spot))
    np.testing.assert_allclose(_xyz(_artist(ax, "feet")), feet, atol=1e-9)
    np.testing.assert_allclose(_xyz(_artist(ax, "body-axis:x"))[0], [0.0, 0.0, h0], atol=1e-12)
    assert len(_xyz(_artist(ax, "arm"))) > 2
    assert ax.get_title().startswith("Spot: ")
    moved = feet + [0.1, -0.05, 0.02]
    result = spot.reachability([[0.9, -0.05, 0.5]], feet=moved)
    ax = _reach_axes(plot.reachability(result, spot, feet=moved))
    np.testing.assert_allclose(_xyz(_artist(ax, "feet")), moved, atol=1e-9)
    np.testing.assert_allclose(_xyz(_artist(ax, "body-axis:x"))[0], [0.1, -0.05, h0 + 0.02], atol=1e-12)


@needs_matplotlib
def test_reachability_of_go2_with_an_arm():
    from urdf_helpers import robot_named

    go2 = robot_named("go2_z1")
    result = go2.reachability([[0.5, 0.0, 0.4], [0.4, 0.2, 0.5], [2.0, 0.0, 0.0]])
    ax = _reach_axes(plot.reachability(result, go2))
    assert len(_scattered(ax)) == result.reachable.sum() >= 1
    hand = _xyz(_artist(ax, "hand"))[0]
    assert np.isfinite(hand).all() and ax.get_title().startswith("Go2: ")


@needs_matplotlib
def test_reachability_rejects_bad_arguments_naming_them(spot_reach, robots):
    spot, go2 = robots["spot"], robots["go2"]
    marked = spot_reach.points.copy()
    marked[spot_reach.reachable] = np.nan
    far = spot.stance_feet(0.5) * [3.0, 3.0, 1.0]
    cases = [
        (lambda: plot.reachability("result"), TypeError, "result"),
        (lambda: plot.reachability(tuple(spot_reach)), TypeError, "result"),
        (lambda: plot.reachability(None), TypeError, "result"),
        (
            lambda: plot.reachability(spot_reach._replace(reachable=spot_reach.reachable * 1)),
            TypeError,
            "result",
        ),
        (lambda: plot.reachability(spot_reach._replace(points=spot_reach.points[:2])), ValueError, "result"),
        (lambda: plot.reachability(spot_reach._replace(points=marked)), ValueError, "result"),
        (
            lambda: plot.reachability(spot_reach._replace(points=spot_reach.points + 2e6)),
            ValueError,
            "result",
        ),
        (lambda: plot.reachability(spot_reach._replace(volume="big")), TypeError, "result.volume"),
        (lambda: plot.reachability(spot_reach, "spot"), TypeError, "robot"),
        (lambda: plot.reachability(spot_reach, go2), ValueError, "robot"),  # no arm: not the result's robot
        (lambda: plot.reachability(spot_reach, feet=np.zeros((4, 3))), ValueError, "feet"),
        (lambda: plot.reachability(spot_reach, spot, feet=np.zeros((3, 3))), ValueError, "feet"),
        (lambda: plot.reachability(spot_reach, spot, feet=np.full((4, 3), np.nan)), ValueError, "feet"),
        (lambda: plot.reachability(spot_reach, spot, feet=far), ValueError, "feet"),  # out of reach
        (lambda: plot.reachability(spot_reach, spot, feet="abc"), TypeError, "feet"),
        (lambda: plot.reachability(spot_reach, ax=plt.figure().add_subplot()), ValueError, "ax"),
        (lambda: plot.reachability(spot_reach, ax="ax"), TypeError, "ax"),
        (lambda: plot.reachability(spot_reach, title=3), TypeError, "title"),
    ]
    for call, error, name in cases:
        with pytest.raises(error, match=name):
            call()
