"""spotkin.dask (issue 20): Dask arrays in, Dask arrays out, bit-identical to the in-memory calls, on the
threaded, multiprocessing and distributed schedulers; the models pickle (round trips, a spawn pool); the
module says what to install when Dask is missing.

The fuzz registry (tests/fuzz/dask.py) feeds every function hostile inputs; here: chunkings, broadcasting,
laziness, the schedulers, and errors raised before any work."""

from __future__ import annotations

import copy
import functools
import multiprocessing
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk

da = pytest.importorskip("dask.array", reason='spotkin.dask needs Dask: pip install "spotkin[dask]"')
dask = pytest.importorskip("dask")
skd = pytest.importorskip("spotkin.dask")

SPOT = sk.Spot()
GO2 = sk.Robot.from_urdf(sk.robots.path("go2"))
FEET = SPOT.stance_feet(0.5)


def poses(n: int, seed: int = 0, height: float = 0.5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    scale = [0.03, 0.03, 0.03, 0.06, 0.06, 0.06]
    return np.array([0.0, 0.0, height, 0.0, 0.0, 0.0]) + rng.normal(0, 1, (n, 6)) * scale


def same(a, b) -> bool:
    """Bit-identical: dtype, shape and every value (NaN where NaN)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def assert_same(lazy, eager, scheduler="threads"):
    """A lazy result (an array or a record of them) computes to the in-memory result, bit for bit."""
    lazy_leaves = list(lazy) if isinstance(lazy, tuple) else [lazy]
    eager_leaves = list(eager) if isinstance(eager, tuple) else [eager]
    assert type(lazy) is type(eager) or not isinstance(eager, tuple)
    assert all(isinstance(leaf, da.Array) for leaf in lazy_leaves)
    computed = dask.compute(*lazy_leaves, scheduler=scheduler)
    assert len(computed) == len(eager_leaves)
    for got, want in zip(computed, eager_leaves):
        assert same(got, want), (got, want)


def with_nan_rows(p: np.ndarray, rows=(3, 17)) -> np.ndarray:
    p = p.copy()
    for row in rows:
        p[row, row % p.shape[1]] = np.nan
    return p


# ---- every function, bit-identical to the in-memory call ---------------------------------------------


def test_body_functions_match_the_in_memory_calls():
    p = with_nan_rows(poses(1003))
    x = da.from_array(p, chunks=(100, 6))
    res = SPOT.body_ik(p, FEET)
    lazy = skd.body_ik(SPOT, x, FEET)
    assert isinstance(lazy, sk.BodyIK) and lazy.q.chunks == ((100,) * 10 + (3,), (12,))
    assert lazy.status.chunks == (x.chunks[0], (4,)) and lazy.status.dtype == np.int8
    assert_same(lazy, res)
    assert (res.status[3] == sk.Status.INVALID_INPUT).all()  # the NaN rows give statuses
    q = da.from_array(res.q, chunks=(250, 12))
    twist = np.array([0.05, 0.0, 0.02, 0.0, 0.1, 0.2])
    assert_same(skd.body_fk(SPOT, x, q), SPOT.body_fk(p, res.q))
    assert_same(skd.body_jacobian(SPOT, x, q), SPOT.body_jacobian(p, res.q))
    assert_same(skd.body_rates(SPOT, x, q, twist), SPOT.body_rates(p, res.q, twist))
    assert_same(
        skd.body_ik(SPOT, x, FEET, seq="xyz", fallback="nan"),
        SPOT.body_ik(p, FEET, seq="xyz", fallback="nan"),
    )


def test_robots_from_urdf():
    from fuzz.urdf_texts import HEXAPOD_URDF  # six legs whose joints interleave in q

    for robot, height in ((GO2, 0.28), (sk.Robot.from_urdf_string(HEXAPOD_URDF), 0.3)):
        feet = robot.stance_feet(height)
        p = poses(517, 1, height=height) * [1, 1, 1, 0.5, 0.5, 0.5]
        x = da.from_array(p, chunks=70)
        res = robot.body_ik(p, feet)
        assert (res.status == sk.Status.OK).mean() > 0.9
        assert_same(skd.body_ik(robot, x, feet), res)
        assert_same(skd.body_fk(robot, x, res.q), robot.body_fk(p, res.q))
        assert_same(skd.body_jacobian(robot, x, res.q), robot.body_jacobian(p, res.q))


def test_legs_arms_and_chains_match_the_in_memory_calls():
    rng = np.random.default_rng(2)
    leg = SPOT.leg("hr")
    q = rng.uniform(leg.limits[:, 0], leg.limits[:, 1], (401, 3))
    p = with_nan_rows(leg.fk(q))
    x, seeds = da.from_array(p, chunks=64), da.from_array(q + 0.05, chunks=100)
    assert_same(skd.fk(leg, da.from_array(q, chunks=50)), leg.fk(q))
    assert_same(skd.jacobian(leg, da.from_array(q, chunks=50)), leg.jacobian(q))
    assert_same(skd.ik(leg, x), leg.ik(p))
    assert_same(skd.ik(leg, x, seed=seeds, fallback="nan"), leg.ik(p, seed=q + 0.05, fallback="nan"))
    assert_same(skd.ik_all(leg, x), leg.ik_all(p))

    arm = SPOT.arm
    qa = rng.uniform(arm.limits[:, 0], arm.limits[:, 1], (203, 6))
    T = arm.fk(qa)
    T[5, 0, 0] = np.nan
    xT = da.from_array(T, chunks=(40, 4, 4))
    assert_same(skd.fk(arm, da.from_array(qa, chunks=33)), arm.fk(qa))
    assert_same(skd.jacobian(arm, qa), arm.jacobian(qa))  # NumPy in: one chunk
    assert_same(skd.ik(arm, xT, seed=qa), arm.ik(T, seed=qa))
    assert_same(skd.ik_all(arm, xT), arm.ik_all(T))
    quat = np.concatenate([T[:, :3, 3], np.tile([0.0, 0.0, 0.0, 1.0], (203, 1))], axis=1)
    assert_same(skd.ik(arm, da.from_array(quat, chunks=50)), arm.ik(quat))

    chain = GO2.chain("FL_foot")  # 3 joints: points
    qc = rng.uniform(chain.lower, chain.upper, (150, 3))
    pc = chain.fk(qc)[:, :3, 3]
    assert_same(skd.fk(chain, da.from_array(qc, chunks=40)), chain.fk(qc))
    assert_same(skd.jacobian(chain, qc, frame="tool"), chain.jacobian(qc, frame="tool"))
    assert_same(skd.ik(chain, da.from_array(pc, chunks=40), seed=qc), chain.ik(pc, seed=qc))
    assert_same(skd.ik_all(chain, da.from_array(pc, chunks=40)), chain.ik_position(pc))
    spot_arm = sk.Robot.from_urdf(sk.robots.path("spot_with_arm")).arm  # 6 joints: poses
    q6 = rng.uniform(spot_arm.lower, spot_arm.upper, (90, 6))
    T6 = spot_arm.fk(q6)
    assert_same(skd.ik(spot_arm, da.from_array(T6, chunks=(30, 4, 4))), spot_arm.ik(T6))
    assert_same(skd.ik_all(spot_arm, da.from_array(T6, chunks=(30, 4, 4))), spot_arm.ik_all(T6))


def test_broadcasting_follows_numpy():
    p = poses(240)
    res = SPOT.body_ik(p, FEET)
    seed = res.q[0]
    x = da.from_array(p, chunks=50)
    # a shared seed (12,), a (1, 12) one, per-pose feet (N, 4, 3) chunked otherwise,
    # poses (N, 1, 6) x feet (K, 4, 3)
    assert_same(skd.body_ik(SPOT, x, FEET, seed=seed), SPOT.body_ik(p, FEET, seed=seed))
    assert_same(skd.body_ik(SPOT, x, FEET, seed=seed[None]), SPOT.body_ik(p, FEET, seed=seed[None]))
    feet = FEET + np.random.default_rng(3).uniform(-0.01, 0.01, (240, 4, 3))
    lazy = skd.body_ik(SPOT, x, da.from_array(feet, chunks=(80, 4, 3)))
    assert lazy.q.chunks[0] == (50, 30, 20, 50, 10, 40, 40)  # the common refinement of both chunkings
    assert_same(lazy, SPOT.body_ik(p, feet))
    grid_feet = FEET + np.linspace(-0.01, 0.01, 7)[:, None, None]
    lazy = skd.body_ik(SPOT, da.from_array(p[:, None, :], chunks=(60, 1, 6)), grid_feet)
    assert lazy.q.shape == (240, 7, 12) and lazy.q.chunks[:2] == ((60,) * 4, (7,))
    assert_same(lazy, SPOT.body_ik(p[:, None, :], grid_feet))


def test_only_the_batch_axes_are_chunked():
    """A pose's numbers split across chunks are merged; the output keeps the batch chunks."""
    p = poses(300)
    x = da.from_array(p, chunks=(70, 4))
    lazy = skd.body_ik(SPOT, x, da.from_array(FEET, chunks=(1, 2)))
    assert lazy.q.chunks == ((70, 70, 70, 70, 20), (12,))
    assert_same(lazy, SPOT.body_ik(p, FEET))
    T = SPOT.arm.fk(np.zeros((30, 6)) + 0.1)
    lazy = skd.ik_all(SPOT.arm, da.from_array(T, chunks=(7, 2, 3)))
    assert lazy.q.chunks == ((7, 7, 7, 7, 2), (8,), (6,))
    assert_same(lazy, SPOT.arm.ik_all(T))


def test_dtypes_single_samples_and_empty_batches():
    p = poses(90)
    p32, f32 = p.astype(np.float32), FEET.astype(np.float32)
    lazy = skd.body_ik(SPOT, da.from_array(p32, chunks=40), f32)
    assert lazy.q.dtype == np.float32
    assert_same(lazy, SPOT.body_ik(p32, f32))
    assert skd.body_ik(SPOT, da.from_array(p32, chunks=40), FEET).q.dtype == np.float64  # as NumPy promotes
    ints = (p * 100).astype(np.int32)
    assert_same(skd.fk(SPOT.leg("fl"), da.from_array(ints[:, :3], chunks=20)), SPOT.leg("fl").fk(ints[:, :3]))
    big_endian = p.astype(">f8")
    assert_same(skd.body_ik(SPOT, da.from_array(big_endian, chunks=30), FEET), SPOT.body_ik(p, FEET))
    single = skd.body_ik(SPOT, p[0], FEET)  # single in, single out (0-d batch)
    assert single.q.shape == (12,) and single.status.shape == (4,)
    assert_same(single, SPOT.body_ik(p[0], FEET))
    status = skd.ik(SPOT.leg("fl"), [0.0, 0.11, -0.5])[1].compute()
    assert np.asarray(status).shape == () and int(status) == int(SPOT.leg("fl").ik([0.0, 0.11, -0.5])[1])
    empty = skd.body_ik(SPOT, da.zeros((0, 6), chunks=(10, 6)), FEET)
    assert empty.q.shape == (0, 12)
    assert_same(empty, SPOT.body_ik(np.zeros((0, 6)), FEET))
    strided = p[::-3, :]  # negative strides, non-contiguous
    assert_same(skd.body_ik(SPOT, da.from_array(strided, chunks=7), FEET), SPOT.body_ik(strided, FEET))


@given(
    n=st.integers(1, 400),
    chunk=st.integers(1, 120),
    split=st.integers(1, 6),
    seed_kind=st.sampled_from(["none", "shared", "batched"]),
    nan=st.booleans(),
)
def test_any_chunking_gives_the_in_memory_result(n, chunk, split, seed_kind, nan):
    p = poses(n, seed=n)
    if nan:
        p[n // 2, 0] = np.nan
    base = SPOT.body_ik(p, FEET)
    seed = {"none": None, "shared": base.q[0], "batched": base.q[::-1] + 0.01}[seed_kind]
    x = da.from_array(p, chunks=(chunk, split))
    lazy_seed = seed if seed_kind != "batched" else da.from_array(seed, chunks=(max(1, chunk // 2 + 1), 12))
    assert_same(skd.body_ik(SPOT, x, FEET, seed=lazy_seed), SPOT.body_ik(p, FEET, seed=seed), "synchronous")


# ---- laziness and errors ------------------------------------------------------------------------------


def _never(block):
    raise AssertionError("an input chunk was computed")


def test_nothing_is_computed_until_asked():
    x = da.from_array(poses(100), chunks=25).map_blocks(_never, dtype=np.float64)
    res = skd.body_ik(SPOT, x, FEET)  # builds the graph only
    assert res.q.shape == (100, 12)
    with pytest.raises(AssertionError, match="computed"):
        res.q.compute(scheduler="synchronous")


def test_a_dataset_far_beyond_memory_plans_lazily():
    """1e10 poses (480 GB): the graph is built at once; any chunk computes alone."""
    stance = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])
    x = da.zeros((10**10, 6), chunks=(10**6, 6)) + da.from_array(stance)
    res = skd.body_ik(SPOT, x, FEET)
    assert res.q.shape == (10**10, 12) and res.q.numblocks == (10**4, 1)
    head = res.q.blocks[0].compute(scheduler="synchronous")
    assert same(head, SPOT.body_ik(np.tile(stance, (10**6, 1)), FEET).q)


def test_bad_inputs_fail_at_once_with_the_in_memory_messages():
    x = da.from_array(poses(100), chunks=25).map_blocks(_never, dtype=np.float64)  # never computed
    cases = [
        (lambda: skd.body_ik(SPOT, x[:, :5], FEET), ValueError, r"body_pose must have shape \(\.\.\., 6\)"),
        (
            lambda: skd.body_ik(SPOT, x, FEET[:3]),
            ValueError,
            r"feet must have shape \(\.\.\., 4, 3\), got \(3, 3\)",
        ),
        (lambda: skd.body_ik(SPOT, x, np.zeros((7, 4, 3))), ValueError, "do not broadcast"),
        (
            lambda: skd.body_ik(SPOT, x, FEET, seed=np.zeros(11)),
            ValueError,
            r"seed must have shape \(\.\.\., 12\)",
        ),
        (
            lambda: skd.body_ik(SPOT, x.astype(complex), FEET),
            TypeError,
            "body_pose must be a real numeric array",
        ),
        (lambda: skd.body_ik(SPOT, x, FEET, seq="nope"), ValueError, "seq must be one of"),
        (lambda: skd.body_ik(SPOT, x, FEET, fallback="closest"), ValueError, "fallback must be one of"),
        (lambda: skd.body_ik(SPOT, None, FEET), TypeError, "body_pose"),
        (lambda: skd.body_ik(SPOT.leg("fl"), x, FEET), TypeError, "robot must be an sk.Robot"),
        (lambda: skd.body_fk(SPOT, x, da.zeros((100, 11))), ValueError, r"q must have shape \(\.\.\., 12\)"),
        (lambda: skd.fk(SPOT, x[:, :3]), TypeError, "model must be a solver"),
        (lambda: skd.fk(SPOT.arm, x[:, :5]), ValueError, r"q must have shape \(\.\.\., 6\)"),
        (lambda: skd.jacobian(SPOT.leg("fl"), x[:, :3], frame="tool"), ValueError, "frame is for a Chain"),
        (lambda: skd.jacobian(GO2.chain("FL_foot"), x[:, :3], frame="world"), ValueError, "frame"),
        (lambda: skd.ik(SPOT.arm, x[:, :3]), ValueError, r"target must have shape \(\.\.\., 4, 4\)"),
        (
            lambda: skd.ik(SPOT.arm, da.from_array(SPOT.arm.fk(np.zeros((4, 6)))), fallback="nearest"),
            ValueError,
            "fallback",
        ),
        (lambda: skd.ik_all(SPOT.leg("fl"), x[:, :3], seed=x[:, :3]), TypeError, "takes no seed"),
        (
            lambda: skd.ik_all(sk.Chain.from_mdh([(0, 0, 0, 0, 0)] * 2), np.tile(np.eye(4), (5, 1, 1))),
            ValueError,
            "closed form",
        ),
    ]
    for make, error, pattern in cases:
        with pytest.raises(error, match=pattern):
            make()


def test_dask_specific_bad_inputs():
    masked = da.ma.masked_invalid(da.from_array(poses(20), chunks=10))
    with pytest.raises(TypeError, match="masked"):
        skd.body_ik(SPOT, masked, FEET)
    unknown = da.from_array(poses(20), chunks=10)
    unknown = unknown[unknown[:, 0] > -1.0]  # boolean indexing: unknown chunk sizes
    with pytest.raises(ValueError, match="compute_chunk_sizes"):
        skd.body_ik(SPOT, unknown, FEET)
    assert_same(skd.body_ik(SPOT, unknown.compute_chunk_sizes(), FEET), SPOT.body_ik(poses(20), FEET))
    with pytest.raises(TypeError, match="real numeric"):
        skd.fk(SPOT.leg("fl"), da.from_array(np.array([["a", "b", "c"]]), chunks=1))
    with pytest.raises(TypeError, match="masked array"):
        skd.fk(SPOT.leg("fl"), np.ma.masked_invalid([[0.0, 1.0, np.nan]]))


# ---- pickling: the models travel -----------------------------------------------------------------------


def _hexapod_like() -> sk.Robot:
    """Go2 with two of its feet named, a contact offset and a nominal stance: every from_urdf option."""
    return sk.Robot.from_urdf_string(
        sk.robots.text("go2"),
        feet=["FL_foot", "RR_foot"],
        contact_offset=(0.0, 0.0, -0.02),
        nominal={"FL": (0.0, 0.8, -1.5)},
    )


def models():
    """Every kind of model, with the calls that must agree after a round trip."""
    rng = np.random.default_rng(5)
    q12 = np.tile([0.0, 1.04, -1.8], 4) + rng.uniform(-0.1, 0.1, (20, 12))
    p = poses(20)
    custom = copy.deepcopy(sk.models.SPOT)
    custom["leg"]["upper"] = 0.35
    yield "Spot()", SPOT, lambda m: [*m.body_ik(p, FEET), m.body_fk(p, q12), m.arm.fk(q12[:, :6])]
    yield "Spot(model)", sk.Spot(custom), lambda m: [*m.body_ik(p, m.stance_feet(0.5)), m.body_fk(p, q12)]
    feet = GO2.stance_feet(0.28)
    go2_poses = poses(20, height=0.28) * [1, 1, 1, 0.5, 0.5, 0.5]
    yield "Robot(go2)", GO2, lambda m: [*m.body_ik(go2_poses, feet), m.body_jacobian(go2_poses, q12)]
    two = _hexapod_like()
    yield (
        "Robot(options)",
        two,
        lambda m: [*m.body_ik(poses(20, height=0.28), m.stance_feet(0.28)), m.leg_names],
    )
    yield (
        "Robot(spot arm)",
        sk.Robot.from_urdf(sk.robots.path("spot_with_arm")),
        lambda m: [
            m.arm.fk(q12[:, :6]),
            *m.arm.ik(m.arm.fk(q12[:, :6])),
        ],
    )
    leg = SPOT.leg("hl")
    yield (
        "Leg(spot)",
        leg,
        lambda m: [m.fk(q12[:, 6:9]), *m.ik(leg.fk(q12[:, 6:9])), m.preferred_slot, m.name],
    )
    yield (
        "Leg()",
        sk.Leg(0.11, 0.32, 0.34, 0.02, "right", limits=[(-1, 1), (-1, 2), (-2.7, -0.2)]),
        lambda m: [*m.ik_all(m.fk(q12[:, :3]))],
    )
    geometry = sk.Leg.from_geometry(
        (0, 0.08, 0.01), (0.02, 0, -0.2), (0, 0, -0.21), (1, -1, 1), preferred_slot=1
    )
    yield "Leg.from_geometry", geometry, lambda m: [*m.ik(m.fk(q12[:, :3])), m.preferred_slot]
    yield "SpotArm()", SPOT.arm, lambda m: [*m.ik_all(m.fk(q12[:, :6])), m.jacobian(q12[:, :6])]
    tool = sk.translation([0.0, 0.0, 0.1])
    yield "SpotArm(tool)", sk.SpotArm(tool=tool, limits=None), lambda m: [*m.ik(m.fk(q12[:, :6]))]
    rows = [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.11, 0.0), (0, 0.32, 0.0, 0.0, 0.0)]
    mdh = sk.Chain.from_mdh(rows, tool=sk.translation([0.37, 0, 0]), limits=[(-1, 1), (-2, 2), (-2.5, 2.5)])
    yield "Chain.from_mdh", mdh, lambda m: [m.fk(q12[:, :3]), *m.ik_position(m.fk(q12[:, :3])[:, :3, 3])]
    dh = sk.Chain.from_dh(rows, base=sk.translation([0.1, 0, 0.2]))
    yield "Chain.from_dh", dh, lambda m: [m.frames(q12[:, :3]), m.jacobian(q12[:, :3], frame="tool")]
    urdf_chain = GO2.chain("RR_foot")
    yield (
        "Chain(urdf)",
        urdf_chain,
        lambda m: [m.fk(q12[:, :3]), m.joint_names, *m.ik(m.fk(q12[:, :3])[:, :3, 3])],
    )


MODELS = list(models())


def _values_equal(a, b) -> bool:
    if isinstance(a, (str, tuple, int, type(None))) and not isinstance(a, np.ndarray):
        return a == b
    return same(a, b)


@pytest.mark.parametrize(("label", "model", "calls"), MODELS, ids=[m[0] for m in MODELS])
def test_models_round_trip_through_pickle(label, model, calls):
    import cloudpickle  # what dask's schedulers ship tasks with

    want = calls(model)
    copies = [
        pickle.loads(pickle.dumps(model, protocol)) for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1)
    ]
    copies += [copy.deepcopy(model), copy.copy(model), cloudpickle.loads(cloudpickle.dumps(model))]
    for other in copies:
        assert type(other) is type(model) and repr(other) == repr(model)
        got = calls(other)
        assert len(got) == len(want) and all(_values_equal(a, b) for a, b in zip(got, want)), label


@pytest.fixture(scope="module")
def spawn_pool():
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        yield pool


def test_models_travel_to_a_spawn_pool(spawn_pool):
    """Bound methods pickle their model: a spawn pool (fresh interpreters) computes the same bits."""
    p = with_nan_rows(poses(4000))
    chunks = np.array_split(p, 7)
    parts = spawn_pool.map(functools.partial(SPOT.body_ik, feet=FEET), chunks)
    assert same(np.concatenate([r.q for r in parts]), SPOT.body_ik(p, FEET).q)
    assert same(np.concatenate([r.status for r in parts]), SPOT.body_ik(p, FEET).status)
    leg = GO2.leg("RL")
    q = np.random.default_rng(1).uniform(leg.limits[:, 0], leg.limits[:, 1], (3000, 3))
    parts = spawn_pool.map(leg.ik_all, np.array_split(leg.fk(q), 5))
    assert same(np.concatenate([r.q for r in parts]), leg.ik_all(leg.fk(q)).q)
    chain = GO2.chain("FR_foot")
    assert same(np.concatenate(spawn_pool.map(chain.jacobian, np.array_split(q, 3))), chain.jacobian(q))
    arm = SPOT.arm
    T = arm.fk(np.random.default_rng(2).uniform(arm.limits[:, 0], arm.limits[:, 1], (500, 6)))
    # the arm's closed form rounds its vector blocks and its remainder apart: pieces at multiples of 64
    parts = spawn_pool.map(arm.ik_all, np.split(T, [128, 256, 384]))
    assert same(np.concatenate([r.q for r in parts]), arm.ik_all(T).q)


def test_a_model_is_unpickled_once_per_process():
    from spotkin.dask import _model_from_pickle
    from spotkin.scale.dask_calls import _plan_body_ik

    kernel = _plan_body_ik(GO2, poses(3, height=0.28), GO2.stance_feet(0.28)).kernel
    first, second = pickle.loads(pickle.dumps(kernel)), pickle.loads(pickle.dumps(kernel))
    assert first.model is second.model  # the per-process cache
    assert first.model is _model_from_pickle(kernel._digest, kernel._data)
    x = poses(5, height=0.28)
    assert all(
        same(a, b) for a, b in zip(first(x, GO2.stance_feet(0.28)), GO2.body_ik(x, GO2.stance_feet(0.28)))
    )


# ---- schedulers ------------------------------------------------------------------------------------------


class ThreadSpy:
    """A model whose 'kernel' reports the thread count its call may use (picklable: module level)."""

    def fk(self, q):
        return np.full(q.shape[:-1], sk.get_num_threads(), dtype=np.float64)


@pytest.mark.parametrize(("chunks", "expected"), [(8, 1), (2, 2), (1, 4)])
def test_a_chunk_uses_its_share_of_the_threads(chunks, expected):
    """The scheduler's threads run a chunk each: each call gets the thread count over the graph's chunks
    (at least 1), so 2 chunks on 4 threads use 2 each, and a single chunk every thread."""
    from spotkin.scale.dask_graph import _lazy, _plan

    before = sk.get_num_threads()
    sk.set_num_threads(4)
    try:
        q = da.from_array(np.zeros((64, 3)), chunks=(64 // chunks, 3))
        lazy = _lazy(_plan(ThreadSpy(), "fk", [("q", q, (3,))], {}, (), "n"))
        assert lazy.numblocks == (chunks,)
        assert set(lazy.compute(scheduler="threads").tolist()) == {expected}
        assert sk.get_num_threads() == 4  # the calling thread's own count is untouched
    finally:
        sk.set_num_threads(before)


def _workload():
    p = with_nan_rows(poses(20_000, 7))
    x = da.from_array(p, chunks=2500)
    leg = GO2.leg("FR")
    q = np.random.default_rng(8).uniform(leg.limits[:, 0], leg.limits[:, 1], (5000, 3))
    lazy = [skd.body_ik(SPOT, x, FEET), skd.ik(leg, da.from_array(leg.fk(q), chunks=1000), seed=q)]
    eager = [SPOT.body_ik(p, FEET), leg.ik(leg.fk(q), seed=q)]
    # dynamics: the robot's floating base (its model built in the worker from the pickled robot)
    qf = GO2.floating_q(p[:3003] * [1, 1, 0.56, 1, 1, 1], np.tile([0.0, 0.9, -1.6], 4))
    v = np.random.default_rng(9).normal(0, 1, (3003, GO2.floating_base.nv))
    lazy.append((skd.nonlinear_effects(GO2, da.from_array(qf, chunks=500), v),))
    eager.append((GO2.floating_base.nonlinear_effects(qf, v),))
    return lazy, eager


@pytest.mark.parametrize("scheduler", ["threads", "processes", "synchronous"])
def test_local_schedulers(scheduler):
    lazy, eager = _workload()
    for result, want in zip(lazy, eager):
        assert_same(result, want, scheduler)


def test_distributed_local_cluster(cluster):
    """Two worker processes: the models travel by pickle, the results are the in-memory ones."""
    _, client = cluster
    lazy, eager = _workload()
    computed = client.compute([leaf for result in lazy for leaf in result], sync=True)
    want = [leaf for result in eager for leaf in result]
    assert all(same(a, b) for a, b in zip(computed, want))
    workers = client.run(os.getpid)
    assert len(workers) == 2 and os.getpid() not in workers.values()


def test_the_same_code_on_a_cluster_address(cluster):
    """What the README shows: a Client connected by address makes the default scheduler."""
    local, _ = cluster
    from distributed import Client

    p = poses(3000)
    with Client(local.scheduler_address):
        res = skd.body_ik(SPOT, da.from_array(p, chunks=500), FEET)
        q, status = dask.compute(res.q, res.status)
    assert same(q, SPOT.body_ik(p, FEET).q) and same(status, SPOT.body_ik(p, FEET).status)


# ---- the optional dependency ------------------------------------------------------------------------------

BLOCK = (
    "import sys, importlib.abc\n"
    "class Block(importlib.abc.MetaPathFinder):\n"
    "    def find_spec(self, name, path=None, target=None):\n"
    "        if name.split('.')[0] in {blocked!r}:\n"
    "            raise ImportError(f'No module named {{name!r}} (blocked)')\n"
    "sys.meta_path.insert(0, Block())\n"
)


def run_blocked(blocked: set, code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", BLOCK.format(blocked=blocked) + code],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_without_dask_the_import_says_what_to_install():
    result = run_blocked(
        {"dask"},
        "import spotkin as sk\n"  # spotkin itself never needs Dask
        "spot = sk.Spot()\n"
        "assert spot.body_ik([0, 0, 0.5, 0, 0, 0], spot.stance_feet(0.5)).status.tolist() == [0] * 4\n"
        "try:\n"
        "    import spotkin.dask\n"
        "except ImportError as error:\n"
        "    print('IMPORTERROR', error)\n",
    )
    assert result.returncode == 0, result.stderr
    assert 'IMPORTERROR spotkin.dask needs Dask: install it with pip install "spotkin[dask]"' in result.stdout
