"""The package's layout does not leak: public classes name their public path as ``__module__`` (so
that pickles load whichever file defines them), pickles of the models name public modules only, and
no module is over 600 lines (docs/architecture.md)."""

from __future__ import annotations

import importlib
import inspect
import io
import pickle
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk

PACKAGE = Path(sk.__file__).parent
MAX_LINES = 600

# The public modules, in the order that decides a class's public path: the package itself first
# (what it exports is ``spotkin.X``), then the public modules; the optional extras when installed.
PUBLIC = ["spotkin", "spotkin.urdf", "spotkin.dynamics", "spotkin.inertia", "spotkin.trajectory"]
PUBLIC += ["spotkin.paul", "spotkin.differential", "spotkin.models", "spotkin.robots"]
OPTIONAL = ["spotkin.dask", "spotkin.sdk", "spotkin.plot", "spotkin.sim"]


def _public_modules() -> list:
    found = [importlib.import_module(name) for name in PUBLIC]
    for name in OPTIONAL:
        try:
            found.append(importlib.import_module(name))
        except ImportError:  # the extra is not installed: nothing of it is public here
            continue
    return found


def public_classes() -> dict[type, str]:
    """Every class a public module exports (its ``__all__``), and its public path: the first public
    module exporting it."""
    classes: dict[type, str] = {}
    for module in _public_modules():
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.isclass(obj):
                classes.setdefault(obj, module.__name__)
    return classes


def test_the_public_classes_are_found():
    classes = public_classes()
    assert classes[sk.Chain] == "spotkin"
    assert classes[sk.LegSolutions] == "spotkin"  # a result NamedTuple
    assert classes[sk.StanceStatus] == "spotkin"  # an enum
    assert classes[sk.urdf.Model] == "spotkin.urdf"
    assert classes[sk.dynamics.FloatingBase] == "spotkin.dynamics"
    assert classes[sk.trajectory.BranchPath] == "spotkin.trajectory"
    assert classes[sk.inertia.Tree] == "spotkin.inertia"


@pytest.mark.parametrize(
    "cls", sorted(public_classes(), key=lambda c: c.__qualname__), ids=lambda c: c.__name__
)
def test_a_public_class_names_its_public_path(cls):
    assert cls.__module__ == public_classes()[cls]
    assert getattr(importlib.import_module(cls.__module__), cls.__qualname__) is cls


class _Recorder(pickle.Unpickler):
    """An unpickler noting every (module, name) the pickle names."""

    def __init__(self, data: bytes) -> None:
        super().__init__(io.BytesIO(data))
        self.named: set[tuple[str, str]] = set()

    def find_class(self, module: str, name: str):
        self.named.add((module, name))
        return super().find_class(module, name)


def _reload(obj, protocol: int):
    """(the object unpickled, the modules its pickle names)."""
    data = pickle.dumps(obj, protocol=protocol)
    recorder = _Recorder(data)
    loaded = recorder.load()
    assert type(loaded) is type(obj)
    if type(obj).__repr__ is not object.__repr__:
        assert repr(loaded) == repr(obj)
    return loaded, {module for module, _ in recorder.named}


def _models() -> dict[str, object]:
    spot = sk.Spot()
    dh = sk.Chain.from_mdh([(0, 0.0, 0.0, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.1, 0.0), (0, 0.3, 0.0, 0.0, 0.0)])
    ur5 = sk.Chain.from_urdf(sk.robots.path("ur5"))
    return {
        "Robot": sk.Robot.from_urdf(sk.robots.path("go2")),
        "Spot": spot,
        "Spot with limits": spot.with_limits({"fl.hx": (-0.5, 0.5)}),
        "Chain (DH)": dh,
        "Chain (URDF)": ur5,
        "Chain (URDF, IK tolerance)": ur5.with_ik_tolerance(1e-4, 1e-4),
        "Chain (mimic joints)": sk.Chain.from_urdf(sk.robots.path("panda"), tip="panda_rightfinger"),
        "Leg": spot.leg("fl"),
        "SpotArm": spot.arm,
    }


@pytest.mark.parametrize("protocol", [2, pickle.HIGHEST_PROTOCOL])
@pytest.mark.parametrize("name", list(_models()))
def test_a_model_pickles_by_public_paths_only(name, protocol):
    model = _models()[name]
    loaded, modules = _reload(model, protocol)
    assert "spotkin" in modules
    assert not {m for m in modules if m.startswith("spotkin.")}, f"the pickle names {sorted(modules)}"
    dof = model.dof if not isinstance(model, sk.Robot) else len(model.leg_joint_names)
    q = np.linspace(-0.3, 0.4, 2 * dof).reshape(2, dof)
    if isinstance(model, sk.Robot):
        pose = np.array([0.0, 0.0, 0.4, 0.0, 0.0, 0.0])
        np.testing.assert_array_equal(loaded.body_fk(pose, q), model.body_fk(pose, q))
    else:
        np.testing.assert_array_equal(loaded.fk(q), model.fk(q))


def _results() -> dict[str, object]:
    spot = sk.Spot()
    chain = sk.Chain.from_urdf(sk.robots.path("ur5"))
    return {
        "LegSolutions": spot.leg("fl").ik_all([0.1, 0.12, -0.5]),
        "ChainSolutions": chain.ik_all(chain.fk(np.full(6, 0.3))),
        "BodyIK": spot.body_ik([0.0, 0.0, 0.5, 0.0, 0.0, 0.0], spot.stance_feet(0.5)),
        "Status": sk.Status.OK,
        "FloatingBase": spot.floating_base,
        "PointToPoint": sk.trajectory.point_to_point([0.0, 0.0], [1.0, 0.5], 1.0, 2.0, "quintic"),
        "urdf.Model": sk.urdf.load_urdf(sk.robots.path("go2")),
    }


@pytest.mark.parametrize("name", list(_results()))
def test_a_result_pickles_by_public_paths_only(name):
    value = _results()[name]
    loaded, modules = _reload(value, pickle.HIGHEST_PROTOCOL)
    private = {m for m in modules if m.startswith("spotkin.") and m not in PUBLIC + OPTIONAL}
    assert not private, f"the pickle names {sorted(private)}"
    if isinstance(value, tuple):
        for a, b in zip(loaded, value):
            np.testing.assert_array_equal(a, b)
    elif isinstance(value, sk.dynamics.FloatingBase):
        q = np.r_[0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 1.0, np.full(value.nq - 7, 0.2)]
        np.testing.assert_array_equal(loaded.mass_matrix(q), value.mass_matrix(q))
    elif isinstance(value, sk.trajectory.PointToPoint):
        t = np.linspace(0.0, value.duration, 7)
        for a, b in zip(loaded.sample(t), value.sample(t)):
            np.testing.assert_array_equal(a, b)
    elif isinstance(value, sk.urdf.Model):
        assert sk.urdf.describe(loaded) == sk.urdf.describe(value)
    else:
        assert loaded == value


def test_the_dask_kernel_pickles_by_public_paths_only():
    pytest.importorskip("dask.array")
    from spotkin.scale.dask_calls import _plan_fk

    kernel = _plan_fk(sk.Spot().leg("fl"), np.zeros((4, 3))).kernel
    loaded, modules = _reload(kernel, pickle.HIGHEST_PROTOCOL)
    assert {m for m in modules if m.startswith("spotkin")} == {"spotkin.dask"}
    np.testing.assert_array_equal(loaded(np.zeros((4, 3)))[0], kernel(np.zeros((4, 3)))[0])


def test_no_module_is_over_600_lines():
    long = {
        str(path.relative_to(PACKAGE)): n
        for path in sorted([*PACKAGE.rglob("*.py"), *PACKAGE.rglob("*.pyi")])
        if path.name != "_core.pyi"  # generated by tools/stubs.py
        and (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines: {long}"
