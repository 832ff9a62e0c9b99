"""spotkin.dask's rigid-body dynamics (issue 20 on issue 17's kernels): fixed-base chains and a robot's
floating base, the centre of mass and the standing torques, bit-identical to the in-memory calls for
any chunking (the kernels pick their vector width on the batch's size: a short chunk must not change it),
with NaN rows, float32, broadcasting, and errors raised before any work."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import spotkin as sk

da = pytest.importorskip("dask.array", reason='spotkin.dask needs Dask: pip install "spotkin[dask]"')
dask = pytest.importorskip("dask")
skd = pytest.importorskip("spotkin.dask")

from test_dask import assert_same  # noqa: E402  (after the optional imports)

GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))
SPOT_ARM = sk.Robot.from_urdf(sk.robots.path("spot_with_arm"))
LEG = GO2.chain("FL_foot")
ARM = SPOT_ARM.chain(SPOT_ARM._specs[1][0].tip)  # the arm's chain from the body, as the floating base's


def states(chain: sk.Chain, n: int, seed: int = 0, dtype=np.float64) -> tuple[np.ndarray, ...]:
    """q within the limits, rates and accelerations, each with a NaN row."""
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(chain.lower, -3.0), np.minimum(chain.upper, 3.0)
    q = rng.uniform(lo, hi, (n, chain.dof))
    qd, qdd = rng.normal(0, 1.5, (2, n, chain.dof))
    if n > 5:
        q[5, 0] = np.nan
        qd[min(n - 1, 9), 1] = np.inf
    return tuple(a.astype(dtype) for a in (q, qd, qdd))


def floating_states(robot: sk.Robot, n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    legs = np.tile([0.0, 0.9, -1.6], robot.n_legs) + rng.normal(0, 0.2, (n, 3 * robot.n_legs))
    arm = rng.normal(0, 0.4, (n, len(robot.arm_joint_names)))
    pose = np.array([0.0, 0.0, 0.4, 0.0, 0.0, 0.0]) + rng.normal(0, 0.1, (n, 6))
    q = robot.floating_q(pose, np.concatenate([legs, arm], axis=1))
    nv = robot.floating_base.nv
    v, a = rng.normal(0, 1.0, (2, n, nv))
    if n > 5:
        q[4, 3] = np.nan
    return pose, legs, q, v, a


def chunked(a: np.ndarray, chunk: int):
    return da.from_array(a, chunks=(chunk,) + a.shape[1:])


@pytest.mark.parametrize("chain", [LEG, ARM], ids=["go2-leg", "spot-arm"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_chain_dynamics_match_the_in_memory_calls(chain, dtype):
    q, qd, qdd = states(chain, 203, 1, dtype)
    x, xd, xdd = (chunked(a, 40) for a in (q, qd, qdd))
    tau = chain.inverse_dynamics(q, qd, qdd)
    assert tau.dtype == dtype and np.isnan(tau[5]).all() and np.isfinite(tau[0]).all()
    assert_same(skd.inverse_dynamics(chain, x, xd, xdd), tau)
    assert_same(skd.mass_matrix(chain, x), chain.mass_matrix(q))
    assert_same(skd.gravity(chain, x), chain.gravity(q))
    assert_same(skd.nonlinear_effects(chain, x, xd), chain.nonlinear_effects(q, qd))
    assert_same(skd.coriolis_matrix(chain, x, xd), chain.coriolis_matrix(q, qd))
    assert_same(skd.forward_dynamics(chain, x, xd, chunked(tau, 64)), chain.forward_dynamics(q, qd, tau))
    forces = np.random.default_rng(3).normal(0, 10, (203, 6)).astype(dtype)
    assert_same(
        skd.joint_torques_from_forces(chain, x, chunked(forces, 50)),
        chain.joint_torques_from_forces(q, forces),
    )
    assert_same(
        skd.joint_torques_from_forces(chain, x, forces[0, :3]),
        chain.joint_torques_from_forces(q, forces[0, :3]),
    )
    # gravity per sample, chunked apart from q
    g = np.random.default_rng(4).normal(0, 5, (203, 3))
    assert_same(skd.gravity(chain, x, chunked(g, 30)), chain.gravity(q, g))
    rest = np.zeros_like(qd)
    assert_same(skd.inverse_dynamics(chain, x, rest, xdd, g), chain.inverse_dynamics(q, rest, qdd, g))


@settings(max_examples=25, deadline=None)
@given(
    n=st.integers(1, 70),
    chunk=st.integers(1, 20),
    dtype=st.sampled_from([np.float64, np.float32]),
    which=st.sampled_from(["inverse_dynamics", "mass_matrix", "forward_dynamics", "coriolis_matrix"]),
)
def test_any_chunking_keeps_the_whole_calls_vector_width(n, chunk, dtype, which):
    """Chunks of any size, shorter than a vector block (8 float64, 16 float32 at AVX-512) too, give the
    whole call's bits: each level runs one register width, a short chunk being one partial block."""
    q, qd, qdd = states(ARM, n, n, dtype)
    x, xd, xdd = (chunked(a, chunk) for a in (q, qd, qdd))
    args = {"mass_matrix": (q,), "coriolis_matrix": (q, qd)}.get(which, (q, qd, qdd))
    lazy = {"mass_matrix": (x,), "coriolis_matrix": (x, xd)}.get(which, (x, xd, xdd))
    assert_same(getattr(skd, which)(ARM, *lazy), getattr(ARM, which)(*args))


def test_floating_base_matches_the_in_memory_calls():
    pose, legs, q, v, a = floating_states(SPOT_ARM, 157, 2)
    floating = SPOT_ARM.floating_base
    assert_same(
        skd.floating_q(SPOT_ARM, chunked(pose, 40), chunked(legs, 25)), SPOT_ARM.floating_q(pose, legs)
    )
    x, xv, xa = chunked(q, 30), chunked(v, 30), chunked(a, 45)
    tau = floating.inverse_dynamics(q, v, a)
    assert tau.shape == (157, floating.nv) and np.isnan(tau[4]).all()
    assert_same(skd.inverse_dynamics(SPOT_ARM, x, xv, xa), tau)
    assert_same(skd.mass_matrix(SPOT_ARM, x), floating.mass_matrix(q))
    assert_same(skd.gravity(SPOT_ARM, x, (0.0, 0.0, -9.8)), floating.gravity(q, (0.0, 0.0, -9.8)))
    assert_same(skd.nonlinear_effects(SPOT_ARM, x, xv), floating.nonlinear_effects(q, v))
    assert_same(skd.coriolis_matrix(SPOT_ARM, x, xv), floating.coriolis_matrix(q, v))
    assert_same(skd.forward_dynamics(SPOT_ARM, x, xv, chunked(tau, 64)), floating.forward_dynamics(q, v, tau))


def test_center_of_mass_and_standing_torques():
    for robot, height in ((GO2, 0.28), (SPOT_ARM, 0.5)):
        pose, legs, _, _, _ = floating_states(robot, 131, 3)
        pose[:, 2] = height
        pose[7, 0] = np.nan
        x, xq = chunked(pose, 6), chunked(legs, 25)
        assert_same(skd.center_of_mass(robot, x, xq), robot.center_of_mass(pose, legs))
        assert_same(
            skd.center_of_mass(robot, x.astype(np.float32), xq.astype(np.float32)),
            robot.center_of_mass(pose.astype(np.float32), legs.astype(np.float32)),
        )
        want = robot.standing_torques(pose, legs)
        assert want.status[7] == sk.StanceStatus.INVALID_INPUT and (want.status == sk.StanceStatus.OK).any()
        assert_same(skd.standing_torques(robot, x, xq), want)
        stance = np.ones((131, robot.n_legs), dtype=bool)
        stance[::3, 1] = False
        assert_same(
            skd.standing_torques(robot, x, xq, stance=chunked(stance, 17), gravity=[0.0, 0.0, -3.7]),
            robot.standing_torques(pose, legs, stance=stance, gravity=[0.0, 0.0, -3.7]),
        )
    arm = np.zeros((131, 6))  # the arm's joints after the legs'
    both = np.concatenate([legs, arm + 0.3], axis=1)
    assert_same(skd.center_of_mass(SPOT_ARM, pose, chunked(both, 20)), SPOT_ARM.center_of_mass(pose, both))


def test_single_samples_and_broadcasting():
    q, qd, qdd = states(ARM, 1, 4)
    assert_same(skd.inverse_dynamics(ARM, q[0], qd[0], qdd[0]), ARM.inverse_dynamics(q[0], qd[0], qdd[0]))
    assert skd.mass_matrix(ARM, q[0]).shape == (6, 6)
    q, qd, qdd = states(ARM, 12, 5)
    lazy = skd.inverse_dynamics(ARM, chunked(q, 5)[:, None], qd[0], chunked(qdd, 4)[None])
    assert lazy.shape == (12, 12, 6)
    assert_same(lazy, ARM.inverse_dynamics(q[:, None], qd[0], qdd[None]))


def test_bad_inputs_fail_at_once():
    q, qd, qdd = states(ARM, 10, 6)
    with pytest.raises(ValueError, match=r"\(\.\.\., 6\)"):
        skd.inverse_dynamics(ARM, q[:, :5], qd, qdd)
    with pytest.raises(ValueError, match="gravity"):
        skd.gravity(ARM, q, (0.0, -9.81))
    with pytest.raises(ValueError, match="broadcast"):
        skd.coriolis_matrix(ARM, chunked(q, 3), qd[:7])
    with pytest.raises(TypeError, match=r"sk\.Chain or an sk\.Robot"):
        skd.mass_matrix(GO2.leg("FL"), q)
    with pytest.raises(ValueError, match="inertials"):
        skd.mass_matrix(sk.Chain.from_dh([(0, 0.0, 0.0, 0.3, 0.0)]), np.zeros((4, 1)))
    with pytest.raises(ValueError, match="forces"):
        skd.joint_torques_from_forces(ARM, q, np.zeros((10, 5)))
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 12\) or \(\.\.\., 18\)"):
        skd.center_of_mass(SPOT_ARM, np.zeros(6), np.zeros((3, 13)))
    with pytest.raises(ValueError, match="stance"):
        skd.standing_torques(GO2, np.zeros(6), np.zeros(12), stance=np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="gravity"):
        skd.standing_torques(GO2, np.zeros(6), np.zeros(12), gravity=np.zeros((2, 3)))


@pytest.mark.parametrize("scheduler", ["processes", "synchronous"])
def test_dynamics_on_the_process_scheduler(scheduler):
    pose, legs, q, v, a = floating_states(GO2, 300, 7)
    assert_same(
        skd.inverse_dynamics(GO2, chunked(q, 64), chunked(v, 64), a),
        GO2.floating_base.inverse_dynamics(q, v, a),
        scheduler,
    )
    assert_same(
        skd.standing_torques(GO2, chunked(pose, 50), legs), GO2.standing_torques(pose, legs), scheduler
    )
