"""Chain construction, properties, pickling and bad input."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk
from conftest import random_rigid, random_table

LEG = [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.11, 0.0), (0, 0.32, 0.0, 0.0, 0.0)]


def test_properties():
    limits = [(-1, 1), (-2, 2), (-3, 0)]
    chain = sk.Chain.from_mdh(LEG, tool=sk.translation([0.37, 0, 0]), limits=limits)
    assert chain.dof == 3 and chain.convention == "mdh"
    np.testing.assert_array_equal(chain.lower, [-1, -2, -3])
    np.testing.assert_array_equal(chain.upper, [1, 2, 0])
    np.testing.assert_array_equal(chain.sigma, [0, 0, 0])
    np.testing.assert_array_equal(chain.tool, sk.translation([0.37, 0, 0]))
    np.testing.assert_array_equal(chain.base, np.eye(4))
    assert "RRR" in repr(chain)
    unlimited = sk.Chain.from_dh(LEG)
    assert np.isneginf(unlimited.lower).all() and np.isposinf(unlimited.upper).all()


def test_pickle_round_trip(rng):
    chain = sk.Chain.from_mdh(
        random_table(rng, 5),
        base=random_rigid(rng),
        tool=random_rigid(rng),
        limits=np.tile([-1.0, 1.0], (5, 1)),
    )
    clone = pickle.loads(pickle.dumps(chain))
    q = rng.uniform(-1, 1, (7, 5))
    np.testing.assert_array_equal(clone.fk(q), chain.fk(q))
    np.testing.assert_array_equal(clone.lower, chain.lower)


def test_wrong_last_dimension_names_argument_and_shape():
    chain = sk.Chain.from_mdh(LEG)
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 3\), got \(5, 4\)"):
        chain.fk(np.zeros((5, 4)))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 3\), got \(\)"):
        chain.jacobian(1.0)
    with pytest.raises(ValueError, match=r"got \(2,\)"):
        chain.frames([1.0, 2.0])


@pytest.mark.parametrize("bad", ["abc", [[1, 2, "a"]], [1 + 2j, 0, 0], None, {"q": 1}])
def test_non_numeric_input_raises_type_error(bad):
    chain = sk.Chain.from_mdh(LEG)
    for method in (chain.fk, chain.frames, chain.jacobian, chain.position_jacobian):
        with pytest.raises(TypeError, match="q must be a real numeric array"):
            method(bad)


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ([(2, 0, 0, 0, 0)], "sigma must be 0"),
        ([(0.5, 0, 0, 0, 0)], "sigma must be 0"),
        ([(0, np.nan, 0, 0, 0)], "non-finite"),
        ([(0, 0, np.inf, 0, 0)], "non-finite"),
        ([(0, 0, 0, 0)], r"shape \(n, 5\)"),
        ([(0, 0, 0, 0, 0, 0)], r"shape \(n, 5\)"),
        ([(0, 0, 0, 0, 0), (0, 0, 0)], "numeric table of shape"),
        (np.zeros((0, 5)), "1 to 64 joints"),
        (np.zeros((65, 5)), "1 to 64 joints"),
        ([0, 0, 0, 0, 0], r"shape \(n, 5\)"),
    ],
)
def test_malformed_rows_raise_value_error(rows, message):
    with pytest.raises(ValueError, match=message):
        sk.Chain.from_mdh(rows)


def test_bad_base_tool_limits_convention():
    with pytest.raises(ValueError, match=r"tool must have shape \(4, 4\)"):
        sk.Chain.from_mdh(LEG, tool=np.eye(3))
    with pytest.raises(ValueError, match="base must be a finite rigid transform"):
        sk.Chain.from_mdh(LEG, base=np.full((4, 4), np.nan))
    with pytest.raises(TypeError, match="rows must be a numeric table"):
        sk.Chain.from_mdh([("a", 0, 0, 0, 0)])
    with pytest.raises(ValueError, match=r"limits must have shape \(3, 2\)"):
        sk.Chain.from_mdh(LEG, limits=[(0, 1)])
    with pytest.raises(ValueError, match="lower <= upper"):
        sk.Chain.from_mdh(LEG, limits=[(1, 0), (0, 1), (0, 1)])
    with pytest.raises(ValueError, match="convention must be"):
        sk.Chain(LEG, convention="xyz")
    with pytest.raises(ValueError, match="frame must be"):
        sk.Chain.from_mdh(LEG).jacobian([0, 0, 0], frame="world")


def test_inf_input_gives_non_finite_output_not_a_crash():
    chain = sk.Chain.from_mdh(LEG)
    T = chain.fk([np.inf, 0, 0])
    assert not np.isfinite(T[:3]).all()


def test_set_num_threads_validates():
    with pytest.raises(ValueError, match=r"thread count in \[1, 1024\]"):
        sk.set_num_threads(0)


def test_legs_arms_and_chains_share_the_solver_interface():
    """dof, limits (n, 2), joint_names, fk, jacobian and ik_all (every branch) on each solver; the same
    limits whichever attribute reads them, and ik_all's branches hold the generating configuration."""
    spot = sk.Spot()
    go2 = sk.Robot.from_urdf(sk.robots.path("go2"))
    arm_chain = sk.Robot.from_urdf(sk.robots.path("spot_with_arm")).chain("arm_hand")
    leg_chain = go2.chain("FL_foot")
    solvers = {
        "leg": (spot.leg("fl"), np.array([0.1, 0.9, -1.5])),
        "go2 leg": (go2.legs[0], np.array([0.05, 0.8, -1.6])),
        "arm": (spot.arm, np.array([0.1, -1.0, 1.5, 0.2, 0.5, 0.0])),
        "arm chain": (arm_chain, np.array([0.1, -1.0, 1.5, 0.2, 0.5, 0.0])),
        "leg chain": (leg_chain, np.array([0.05, 0.8, -1.6])),
    }
    for name, (solver, q) in solvers.items():
        assert solver.dof == len(q), name
        limits = solver.limits
        assert limits.shape == (solver.dof, 2) and (limits[:, 0] <= limits[:, 1]).all(), name
        names = solver.joint_names
        assert names is None or len(names) == solver.dof, name
        pose = solver.fk(q)
        target = pose[:3, 3] if pose.shape == (4, 4) and solver.dof == 3 else pose  # a 3-joint chain: p
        J = solver.jacobian(q)
        assert J.shape[-1] == solver.dof, name
        branches = solver.ik_all(target)
        hit = np.abs(np.angle(np.exp(1j * (branches.q - q)))).max(axis=-1) < 1e-9
        assert hit.any(), (name, branches.q, q)  # the generating configuration is among the branches
    assert spot.leg("fl").joint_names == spot.leg_joint_names[:3]
    assert go2.legs[0].joint_names == tuple(go2.leg_joint_names[:3])
    assert spot.arm.joint_names == spot.arm_joint_names
    np.testing.assert_array_equal(arm_chain.limits, np.stack([arm_chain.lower, arm_chain.upper], axis=1))


def _outs_like(result) -> tuple:
    """Empty out= arrays of each result's dtype and shape (a Status: int8 of shape ())."""
    return tuple(
        np.empty((), np.int8) if isinstance(r, sk.Status) else np.empty(np.shape(r), np.asarray(r).dtype)
        for r in result
    )


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_chain_ik_writes_into_out_and_returns_those_arrays(rng, shape):
    """Chain.ik, ik_all and ik_position take out= (a control loop allocates nothing): the arrays come
    back themselves, holding exactly what the call without out= returns; a held joint's choice
    (made in NumPy) is copied in."""
    here = Path(sk.__file__).parent / "robots"
    ur5 = sk.Chain.from_urdf(str(here / "ur5.urdf"))
    leg = sk.Chain.from_urdf(str(here / "go2.urdf"), tip="FL_foot")
    panda = sk.Chain.from_urdf(str(here / "panda.urdf")).with_ik_tolerance()
    q6 = rng.uniform(-2.0, 2.0, (*shape, 6))
    T = ur5.fk(q6)
    for call in (lambda **k: ur5.ik(T, q6, **k), lambda **k: ur5.ik_all(T, **k)):
        plain = call()
        out = _outs_like(plain)
        got = call(out=out)
        assert all(g is o for g, o in zip(got, out))
        for g, p in zip(got, plain):
            np.testing.assert_array_equal(np.asarray(g), np.asarray(p))
    p = leg.fk(rng.uniform(-1.0, 1.0, (*shape, 3)))[..., :3, 3]
    for call in (lambda **k: leg.ik_position(p, **k), lambda **k: leg.ik_all(p, **k)):
        plain = call()
        out = _outs_like(plain)
        got = call(out=out)
        assert type(got) is type(plain) and all(g is o for g, o in zip(got, out))
        for g, p_ in zip(got, plain):
            np.testing.assert_array_equal(np.asarray(g), np.asarray(p_))
    q7 = np.array([0.1, -0.5, 0.2, -2.0, 0.3, 1.5, 0.4]) + rng.uniform(-0.05, 0.05, (*shape, 7))
    T7 = panda.fk(q7)
    plain = panda.ik(T7, q7, free_joint=3, free_value=q7[..., 3])
    out = _outs_like(plain)
    got = panda.ik(T7, q7, free_joint=3, free_value=q7[..., 3], out=out)
    assert all(g is o for g, o in zip(got, out))
    np.testing.assert_array_equal(got[0], plain[0])
    np.testing.assert_array_equal(got[1], np.asarray(plain[1], np.int8))
    with pytest.raises(ValueError, match=r"out\[0\] \(q\) must have shape"):
        ur5.ik(T, out=(np.empty((*shape, 5)), None))
    with pytest.raises(TypeError, match="out must be a tuple of 2"):
        panda.ik(T7, q7, free_joint=3, free_value=0.0, out=np.empty(7))
    with pytest.raises(ValueError, match="out must hold 2 arrays"):
        panda.ik(T7, q7, free_joint=3, free_value=0.0, out=(None, None, None))
    with pytest.raises(TypeError, match=r"out\[0\] \(q\) must have dtype float64"):
        panda.ik(T7, q7, free_joint=3, free_value=q7[..., 3], out=(np.empty((*shape, 7), np.float32), None))
