"""spotkin.plot reads the solvers through the interface they share (issue 34): any object that answers
``dof``, ``limits``, ``joint_names``, ``fk``, ``jacobian``, ``ik_all`` and ``ik``, and gives what places
its links (a leg's geometry, a chain's frames), is drawn as the solver it stands for; the package is one
module per picture family, none over 600 lines, and no picture asks a solver for its class."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk

matplotlib = pytest.importorskip("matplotlib", reason='needs matplotlib: pip install "spotkin[plot]"')
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from spotkin import plot  # noqa: E402
from spotkin.plot import _solvers  # noqa: E402

INTERFACE = ("dof", "limits", "joint_names", "fk", "jacobian", "ik_all", "ik")
LEG_GEOMETRY = ("a", "b", "c", "signs", "knee", "hip_offset", "reach", "name")
PACKAGE = Path(plot.__file__).parent


class Forwarding:
    """A solver of none of spotkin's classes: it answers only the given attributes, from ``solver``."""

    def __init__(self, solver, names):
        self._solver, self._names = solver, frozenset(names)

    def __getattr__(self, name):
        if name.startswith("__") or name not in self._names:
            raise AttributeError(name)
        return getattr(self._solver, name)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _drawn(fig) -> list:
    """Every line's id and data, and every text, of every panel, in order."""
    found = []
    for ax in fig.axes:
        found.append(ax.get_title())
        for line in ax.get_lines():
            data = line.get_data_3d() if hasattr(line, "get_data_3d") else line.get_xydata().T
            found.append((line.get_gid(), np.asarray(data, dtype=float).round(12).tolist()))
        found += [text.get_text() for text in ax.texts]
        found += [np.asarray(image.get_array()).tolist() for image in ax.images]
    return found


@pytest.fixture(scope="module")
def solvers():
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    return {"leg": sk.Spot().leg("fl"), "chain3": go2.chain("FL_foot"), "go2_leg": go2.legs[1]}


@pytest.mark.parametrize("name", ("leg", "go2_leg"))
def test_a_solver_with_a_legs_geometry_is_drawn_as_the_leg(solvers, name):
    leg = solvers[name]
    stand_in = Forwarding(leg, INTERFACE + LEG_GEOMETRY)
    target = leg.fk([0.1, 0.8, -1.5])
    assert _drawn(plot.branches(stand_in, target)) == _drawn(plot.branches(leg, target))
    for plane in ("xz", "yz"):
        drawn = _drawn(plot.workspace(stand_in, plane, resolution=40))
        assert drawn == _drawn(plot.workspace(leg, plane, resolution=40))


def test_a_solver_with_frames_is_drawn_as_the_chain(solvers):
    chain = solvers["chain3"]
    stand_in = Forwarding(chain, (*INTERFACE, "frames", "sigma"))
    target = chain.fk([0.3, 0.2, -1.0])[:3, 3]
    fig, original = plot.branches(stand_in, target), plot.branches(chain, target)
    assert _drawn(fig) == _drawn(original)
    assert fig._suptitle.get_text().startswith("Forwarding IK, every branch:")
    assert _drawn(plot.workspace(stand_in, "xz", 0.0, resolution=40)) == _drawn(
        plot.workspace(chain, "xz", 0.0, resolution=40)
    )


def test_a_solver_whose_links_cannot_be_placed_is_refused(solvers):
    stand_in = Forwarding(solvers["chain3"], INTERFACE)  # no frames, no leg geometry
    with pytest.raises(TypeError, match="solver"):
        plot.branches(stand_in, np.zeros(3))
    with pytest.raises(TypeError, match="solver"):
        plot.workspace(stand_in)
    with pytest.raises(TypeError, match="solver"):
        plot.branches(Forwarding(solvers["leg"], LEG_GEOMETRY), np.zeros(3))  # no ik_all


def test_panels_name_the_joints_by_the_solvers_joint_names():
    assert _solvers._joint_labels(sk.SpotArm()) == ("sh0", "sh1", "el0", "el1", "wr0", "wr1")  # arm0. dropped
    chain = sk.Robot.from_urdf(sk.robots.path("spot_with_arm")).arm
    assert _solvers._joint_labels(chain) == chain.joint_names
    assert _solvers._joint_labels(sk.Chain.from_dh([(0, 0.3, 0, 0, 0)] * 2)) == ("q1", "q2")
    named = type("Named", (), {"dof": 2})
    named.joint_names = ("a.x", "b.y")
    assert _solvers._joint_labels(named()) == ("a.x", "b.y")  # no shared prefix: kept
    named.joint_names = ("arm.x", "arm.y")
    assert _solvers._joint_labels(named()) == ("x", "y")


def test_one_module_per_picture_family_none_over_600_lines():
    modules = sorted(PACKAGE.glob("*.py"))
    assert len(modules) >= 6
    for path in modules:
        assert len(path.read_text(encoding="utf-8").splitlines()) <= 600, path.name
    assert plot.__all__ == [
        "animate",
        "branches",
        "foot_paths",
        "gait_diagram",
        "reachability",
        "robot",
        "trajectory",
        "walk_animation",
        "workspace",
    ]
    for name in plot.__all__:  # no submodule shadows a public function
        assert inspect.isfunction(getattr(plot, name)), name


def test_no_picture_asks_a_solver_for_its_class():
    solver_classes = {"Leg", "SpotArm", "Chain"}
    for path in PACKAGE.glob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance":
                named = {n.id for n in ast.walk(node.args[1]) if isinstance(n, ast.Name)}
                named |= {n.attr for n in ast.walk(node.args[1]) if isinstance(n, ast.Attribute)}
                assert not named & solver_classes, f"{path.name}:{node.lineno}"
            if isinstance(node, ast.ImportFrom) and node.level == 2 and node.module:  # from ..module import
                classes = {alias.name for alias in node.names} & (solver_classes | {"Robot"})
                assert not classes, (
                    f"{path.name}:{node.lineno}: {classes} from spotkin.{node.module}, not spotkin"
                )
