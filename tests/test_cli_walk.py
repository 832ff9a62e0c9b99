"""``spotkin walk``: a short walk of Go2 and of Spot in the simulator prints its figures and writes its
pictures; without MuJoCo it says what to install; bad options are refused before any work."""

from __future__ import annotations

import contextlib
import io
import subprocess
import sys

import pytest

from spotkin.__main__ import main


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def test_a_walk_prints_its_figures_and_writes_its_pictures(tmp_path):
    pytest.importorskip("mujoco")
    pytest.importorskip("matplotlib")
    code, out, err = _run(
        ["walk", "go2", "--velocity", "0.2", "0", "0.3", "--duration", "2", "--plots", str(tmp_path)]
    )
    assert code == 0, err
    for line in (
        "distance",
        "speed",
        "heading",
        "lowest body",
        "falls         none",
        "torques",
        "ms per tick",
    ):
        assert line in out, out
    assert "h = 0.341 m" in out and "trot" in out
    written = sorted(path.name for path in tmp_path.iterdir())
    assert written == ["go2_foot_paths.png", "go2_gait.png", "go2_walk.gif"], written
    for name in written:
        assert f"wrote {tmp_path / name}" in out
    gif = (tmp_path / "go2_walk.gif").read_bytes()
    assert gif.startswith(b"GIF89a")
    from PIL import Image

    with Image.open(tmp_path / "go2_walk.gif") as image:
        assert image.size == (600, 375)
        assert image.n_frames == 40  # the last 2 s at 20 frames a second
    assert len(gif) <= 200_000


def test_spot_walks_from_the_command_line():
    pytest.importorskip("mujoco")
    code, out, err = _run(
        ["walk", "spot", "--gait", "walk", "--velocity", "0.1", "0", "0", "--duration", "1"]
    )
    assert code == 0, err
    assert out.startswith("spot: ") and "walk at (+0.100 m/s" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["walk", "go2", "--duration", "0"], "--duration must be in"),
        (["walk", "go2", "--velocity", "nan", "0", "0"], "--velocity must be three finite numbers"),
        (["walk", "go2", "--dpi", "5"], "--dpi must be in"),
    ],
)
def test_bad_options_are_refused_first(argv, message):
    code, _, err = _run(argv)
    assert code == 2 and message in err


def test_an_unknown_gait_or_robot_is_one_line():
    pytest.importorskip("mujoco")
    code, _, err = _run(["walk", "go2", "--gait", "canter", "--duration", "0.1"])
    assert code == 1 and "unknown gait 'canter'" in err
    code, _, err = _run(["walk", "no_such_robot.urdf", "--duration", "0.1"])
    assert code == 1 and "spotkin walk:" in err


def test_without_mujoco_walk_says_what_to_install():
    code = (
        "import sys\n"
        "sys.modules['mujoco'] = None\n"
        "from spotkin.__main__ import main\n"
        "sys.exit(main(['walk', 'go2', '--duration', '0.1']))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 1, run.stderr
    assert 'pip install "spotkin[sim]"' in run.stderr
