"""The façade methods that run from C (spotkin._support.forward.core_method) answer exactly as the
Python functions they were made from: the same values, dtypes, statuses and errors, for single
samples, batches, float32, keywords, out= and the forms only the function handles (a whole-body q,
a non-default frame, a core not built yet)."""

from __future__ import annotations

import inspect
import pickle

import numpy as np
import pytest

import spotkin as sk
from spotkin import robots
from spotkin._support.forward import core_methods

TESTED: set[str] = set()


def _same(a, b):
    if isinstance(a, tuple):
        assert type(a) is type(b) and len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape
        np.testing.assert_array_equal(a, b)
    else:
        assert type(a) is type(b) and (a == b or (a != a and b != b))


def check(obj, name: str, *args, **kwargs):
    """obj.name(*args, **kwargs) through C equals the Python function's answer, or its error."""
    method = getattr(type(obj), name)
    assert type(method).__name__ == "_CoreMethod", f"{type(obj).__name__}.{name} is not a core method"
    TESTED.add(method.__qualname__)
    function = method.__wrapped__
    try:
        expected = function(obj, *args, **kwargs)
    except (ValueError, TypeError) as error:
        with pytest.raises(type(error)) as raised:
            getattr(obj, name)(*args, **kwargs)
        assert str(raised.value) == str(error)
        return None
    got = getattr(obj, name)(*args, **kwargs)
    _same(got, expected)
    return got


@pytest.fixture(scope="module")
def spot():
    return sk.Spot()


@pytest.fixture(scope="module")
def go2():
    return sk.Robot.from_urdf(robots.path("go2"))


@pytest.fixture(scope="module")
def arm_chain():
    return sk.Robot.from_urdf(robots.path("spot_with_arm")).chain("arm_hand")


def test_leg(go2):
    leg = go2.legs[0]
    rng = np.random.default_rng(0)
    q = np.array([0.1, 0.7, -1.4])
    qs = q + rng.uniform(-0.3, 0.3, (5, 3))
    p, ps = leg.fk(q), leg.fk(qs)
    for args, kwargs in [
        ((q,), {}),
        ((qs,), {}),
        ((qs.astype(np.float32),), {}),
        (([0.1, 0.7, -1.4],), {}),
        ((np.zeros(4),), {}),
        (("x",), {}),
        ((q,), {"out": np.empty(3)}),
        ((q,), {"out": np.empty(4)}),
    ]:
        check(leg, "fk", *args, **kwargs)
        check(leg, "jacobian", *args, **({} if "out" in kwargs else kwargs))
    for args, kwargs in [
        ((p,), {}),
        ((ps,), {}),
        ((p, q), {}),
        ((p,), {"seed": q}),
        ((p, None, "nan"), {}),
        ((p,), {"fallback": "nan"}),
        ((p * 10,), {"fallback": "nan"}),
        ((p,), {"fallback": "bad"}),
        ((p,), {"seed": q, "unknown": 1}),
        ((np.full(3, np.nan),), {}),
        ((p.astype(np.float32),), {}),
    ]:
        check(leg, "ik", *args, **kwargs)
    check(leg, "ik_all", ps)
    check(leg, "ik_all", p, out=None)


def test_arm(spot):
    arm = spot.arm
    q = np.full(6, 0.3)
    T = arm.fk(q)
    for name in ("fk", "jacobian"):
        check(arm, name, q)
        check(arm, name, np.tile(q, (2, 1)).astype(np.float32))
        check(arm, name, q[:5])
    for name in ("ik_all", "ik"):
        check(arm, name, T)
        check(arm, name, T, q)
        check(arm, name, T, seed=q)
        check(arm, name, T[:3])


def test_chain(arm_chain):
    q = np.full(6, 0.3)
    check(arm_chain, "fk", q)
    check(arm_chain, "fk", np.zeros((0, 6)))
    check(arm_chain, "jacobian", q)
    check(arm_chain, "jacobian", q, "tool")  # another frame: the function's path
    check(arm_chain, "jacobian", q, frame="base", point=3)
    check(arm_chain, "jacobian", q, point="nowhere")
    check(arm_chain, "jacobian", q, out=np.empty((6, 6)))


def test_chain_dynamics(arm_chain):
    chain = sk.Robot.from_urdf(robots.path("spot_with_arm")).chain("arm_hand")  # dynamics not built yet
    assert chain._dynamics is None  # the first call goes through the function, which builds them
    q = np.full(6, 0.3)
    qs = np.random.default_rng(1).normal(size=(3, 6))
    check(chain, "gravity", q)
    check(chain, "gravity", qs, (0.0, 0.0, -1.0))
    check(chain, "gravity", qs, gravity=[0.0, 9.81, 0.0])
    check(chain, "inverse_dynamics", q, q, q)
    check(chain, "inverse_dynamics", qs, q, qs[:1])
    check(chain, "mass_matrix", q)
    check(chain, "mass_matrix", qs, "packed")
    check(chain, "mass_matrix", qs, layout="nope")
    check(chain, "nonlinear_effects", q, q)
    check(chain, "coriolis_matrix", q, q)
    check(chain, "forward_dynamics", q, q, q)
    check(chain, "forward_dynamics", q, q, q, out=np.empty(6))


def test_whole_body(spot, go2):
    for robot in (go2, spot):
        height = 0.28 if robot is go2 else 0.5
        pose = np.array([0.0, 0.0, height, 0.0, 0.05, 0.0])
        feet = robot.stance_feet(height)
        q = robot.body_ik(pose, feet).q
        whole = np.concatenate([q, np.zeros(len(robot.arm_joint_names))])
        check(robot, "body_ik", pose, feet)
        check(robot, "body_ik", pose, feet, q)
        check(robot, "body_ik", pose, feet, seed=whole)  # a whole-body seed: the function's path
        check(robot, "body_ik", pose, feet, None, "ZYX")
        check(robot, "body_ik", pose, feet, fallback="nan", seq="XYZ")
        check(robot, "body_ik", pose, feet, seq="bad")
        check(robot, "body_ik", pose.astype(np.float32), feet.astype(np.float32))
        check(robot, "standing_torques", pose, q)
        check(robot, "standing_torques", pose, whole, [True, False, True, True])
        check(robot, "standing_torques", np.tile(pose, (3, 1)), q, gravity=(0.0, 0.0, -1.0))
        check(robot, "standing_torques", pose, q, stance=[True, True, False, False])  # UNBALANCED
        check(robot, "standing_torques", pose, q, seq="bad")
        outs = (np.empty(q.shape), np.empty((robot.n_legs, 3)), np.empty((), np.int8), np.empty(()))
        check(robot, "standing_torques", pose, q, out=outs)
        check(robot, "standing_torques", pose, q, out=(None, None, None, None))
        for name in ("body_fk", "body_jacobian", "center_of_mass"):
            check(robot, name, pose, q)
            check(robot, name, pose, whole)
            check(robot, name, np.tile(pose, (2, 1)), q, "ZYX")
            check(robot, name, pose, q[:5])


def test_every_core_method_is_checked_and_documented():
    names = {m.__qualname__ for m in core_methods}
    missing = names - TESTED
    assert not missing, f"core methods not checked here: {sorted(missing)}"
    for method in core_methods:
        function = method.__wrapped__
        assert method.__doc__ == function.__doc__ and method.__doc__
        assert inspect.signature(method) == inspect.signature(function)


def test_the_methods_bind_and_pickle_as_before(go2):
    leg = go2.legs[0]
    bound = leg.fk
    np.testing.assert_array_equal(bound(np.zeros(3)), type(leg).fk(leg, np.zeros(3)))
    assert inspect.signature(bound) == inspect.signature(type(leg).fk.__wrapped__.__get__(leg))
    assert type(leg).fk.__get__(None, type(leg)) is type(leg).fk
    clone = pickle.loads(pickle.dumps(leg))
    np.testing.assert_array_equal(clone.fk(np.zeros(3)), leg.fk(np.zeros(3)))


def test_which_path_answers():
    """A made-up core and façade whose paths answer differently, to see which one ran."""
    from spotkin._support.forward import AT_DEFAULT, core_method

    class Core:
        def f(self, a, b, mode, out):
            if a == "refuse":
                raise ValueError("the core refuses")
            return ("core", a, b, mode, out)

    class Face:
        __slots__ = ("_core",)

        @core_method("_core", "f", call=("a", "b", ("constant",), "out"), convert={"b": str, "c": AT_DEFAULT})
        def f(self, a, b=1, c="default", *, out=None):
            return ("python", a, b, c, out)

    try:
        face = Face()
        face._core = Core()
        assert face.f(1) == ("core", 1, "1", "constant", None)  # the default converted once
        assert face.f(1, 2, out=3) == ("core", 1, "2", "constant", 3)
        assert face.f(a=1, b=2) == ("core", 1, "2", "constant", None)
        assert face.f(1, c="default") == ("core", 1, "1", "constant", None)  # c at its default
        assert face.f(1, c="other") == ("python", 1, 1, "other", None)  # another value: the function
        assert face.f("refuse") == ("python", "refuse", 1, "default", None)  # the core refuses
        with pytest.raises(TypeError, match="unexpected keyword"):
            face.f(1, d=2)
        with pytest.raises(TypeError, match="missing 1 required"):
            face.f()
        with pytest.raises(TypeError, match="positional"):
            face.f(1, 2, 3, 4)
        face._core = None  # not built: the function
        assert face.f(1) == ("python", 1, 1, "default", None)
        del face._core
        assert face.f(1) == ("python", 1, 1, "default", None)
        assert Face.f(Face(), 5) == ("python", 5, 1, "default", None)
    finally:
        core_methods.pop()  # not a façade method: out of the registry


def test_the_hot_core_methods_are_called_past_pybind11s_dispatcher():
    """Every façade method whose core is a compiled class calls it directly (fast_call.hpp); the
    checks above compare those answers with the core called through pybind11."""
    from spotkin import _core

    direct = set(map(tuple, _core._direct_calls()))
    for core_type, names in {
        "Leg": ("fk", "jacobian", "ik", "ik_all"),
        "Arm": ("fk", "jacobian", "ik", "ik_all"),
        "Body": ("ik", "fk", "jacobian"),
        "Chain": ("fk", "jacobian"),
        "ChainDynamics": ("rnea", "gravity", "crba", "aba", "nonlinear_effects", "coriolis_matrix"),
        "FloatingDynamics": ("rnea", "gravity", "crba", "aba", "com", "com_jacobian"),
        "RobotStatics": ("com", "standing"),
    }.items():
        for name in names:
            assert (core_type, name) in direct, (core_type, name)


def test_a_direct_call_declines_what_it_does_not_convert(go2):
    """A direct call converts only True and False, exact ints within C int, and anything as an
    array; another value goes through pybind11's call, which converts it or refuses it (then the
    Python function answers), as before. A made-up façade over the real core shows the path."""
    from spotkin._support.forward import core_method
    from spotkin.model.body import sequence_code

    class Face:
        __slots__ = ("_core",)

        @core_method("_core", "ik")
        def ik(self, p, seed=None, nearest_fallback=True, out=None):
            return "python"

    try:
        leg = go2.legs[0]
        face = Face()
        face._core = leg._core
        p = leg.fk(np.array([0.1, 0.7, -1.4]))
        expected = leg.ik(p)
        for flag in (True, np.True_, 1):  # direct; declined, then converted by pybind11
            q, status = face.ik(p, None, flag)
            np.testing.assert_array_equal(q, expected[0])
            assert status is expected[1]
        assert face.ik(p, None, "yes") == "python"  # declined, refused by pybind11: the function
    finally:
        core_methods.pop()

    class BodyFace:
        __slots__ = ("_core",)

        @core_method("_core", "ik")
        def ik(self, pose, sequence, feet, seed=None, nearest_fallback=True, out=None):
            return "python"

    try:
        face = BodyFace()
        face._core = go2._body_core
        pose = np.array([0.0, 0.0, 0.28, 0.0, 0.05, 0.0])
        feet = go2.stance_feet(0.28)
        q, status = face.ik(pose, sequence_code("XYZ"), feet)
        np.testing.assert_array_equal(q, go2.body_ik(pose, feet).q)
        assert face.ik(pose, 2**40, feet) == "python"  # beyond C int
        assert face.ik(pose, 0.0, feet) == "python"  # not an int
    finally:
        core_methods.pop()
