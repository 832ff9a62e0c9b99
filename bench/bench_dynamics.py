"""Batched rigid-body dynamics (spotkin.dynamics) against Pinocchio, in one run.

Workloads (N = 1e5 random states):
  arm6:   Spot's 6-joint arm (body to arm_hand) as a fixed-base chain; Pinocchio's model of the
          URDF reduced to those joints (the others locked at 0).
  legs12: Go2 as a free-flyer, the body carrying its four 3-joint legs (nv = 6 + 12): spotkin's
          FloatingBase against Pinocchio's free-flyer model of the same URDF. Its CRBA writes an
          18 x 18 matrix per configuration (260 MB for N = 1e5): bound by memory bandwidth.
  legs12-fixed: the same legs with the body held (Pinocchio's fixed-base model, nv = 12; spotkin
          one fixed-base call per 3-joint leg, the 4 x (3 x 3) diagonal blocks of A).
Implementations, per configuration:
  spotkin-1thread           one call on the whole batch, spotkin limited to one thread
  ref:pin-parallel-1thread  pin.rneaInParallel(1, ModelPool, q, v, a) (RNEA only: Pinocchio has no
                            parallel CRBA) at the same thread count
  spotkin-packed[-f32]-1thread  CRBA with layout="packed" (the lower triangle row by row), float64
                            or float32
  ref:pin-loop              a Python loop over pin.rnea / pin.crba
and single calls (N = 1) from Python (target: under 3 us). ``pytest bench/bench_dynamics.py -s``
prints per-configuration times and the ratios (reference time over spotkin's, same run) at the end.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest

import spotkin as sk
from spotkin import dynamics as dyn
from spotkin.dynamics.rigid_body import _core_of

pin = pytest.importorskip("pinocchio")

N = 100_000
ROBOTS = Path(sk.__file__).parent / "robots"
_TIMES: dict = defaultdict(dict)


def _inertials(model, names):
    ids = [model.getJointId(n) for n in names]
    return dyn.LinkInertials(
        np.array([model.inertias[i].mass for i in ids]),
        np.array([model.inertias[i].lever for i in ids]),
        np.array([model.inertias[i].inertia for i in ids]),
    )


def _arm6():
    urdf = str(ROBOTS / "spot_with_arm.urdf")
    chain = sk.Robot.from_urdf(urdf).chain("arm_hand")
    full = pin.buildModelFromUrdf(urdf)
    lock = [full.getJointId(n) for n in full.names[1:] if n not in chain.joint_names]
    model = pin.buildReducedModel(full, lock, pin.neutral(full))
    assert list(model.names[1:]) == list(chain.joint_names)
    core = _core_of(chain, _inertials(model, chain.joint_names))
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, (N, 6))
    return model, core.rnea, core.crba, q, rng.normal(size=(N, 6)), rng.normal(size=(N, 6)), q


def _legs12():
    urdf = str(ROBOTS / "go2.urdf")
    robot = sk.Robot.from_urdf(urdf)
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    chains = [robot.chain(f) for f in ("FL_foot", "FR_foot", "RL_foot", "RR_foot")]
    assert [n for c in chains for n in c.joint_names] == list(model.names[2:])  # same joint order
    body = model.inertias[1]
    fb = dyn.FloatingBase(
        (body.mass, body.lever, body.inertia), chains, [_inertials(model, c.joint_names) for c in chains]
    )
    rng = np.random.default_rng(0)
    quat = rng.normal(size=(N, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    q = np.hstack([rng.normal(size=(N, 3)), quat, rng.uniform(-np.pi, np.pi, (N, 12))])
    v, a = rng.normal(size=(N, 18)), rng.normal(size=(N, 18))
    return model, fb._core.rnea, fb._core.crba, q, v, a, q


def _legs12_fixed():
    """Go2's legs with the body held: four fixed-base 3-joint chains (spotkin: one call per leg);
    Pinocchio's fixed-base model of the same URDF (nv = 12, a block-diagonal A)."""
    urdf = str(ROBOTS / "go2.urdf")
    robot = sk.Robot.from_urdf(urdf)
    model = pin.buildModelFromUrdf(urdf)
    chains = [robot.chain(f) for f in ("FL_foot", "FR_foot", "RL_foot", "RR_foot")]
    assert [n for c in chains for n in c.joint_names] == list(model.names[1:])
    cores = [_core_of(c, _inertials(model, c.joint_names)) for c in chains]
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, (N, 12))
    legs = [np.ascontiguousarray(q[:, 3 * k : 3 * k + 3]) for k in range(4)]
    v, a = rng.normal(size=(N, 12)), rng.normal(size=(N, 12))
    vs = [np.ascontiguousarray(v[:, 3 * k : 3 * k + 3]) for k in range(4)]
    as_ = [np.ascontiguousarray(a[:, 3 * k : 3 * k + 3]) for k in range(4)]

    # float32 copies of the batch, split per leg too (test_rnea's float lanes)
    q32, v32, a32 = (x.astype(np.float32) for x in (q, v, a))
    legs32, vs32, as32 = (
        [np.ascontiguousarray(x[:, 3 * k : 3 * k + 3]) for k in range(4)] for x in (q32, v32, a32)
    )

    def rnea(q_, v_, a_, g):  # the per-leg inputs prepared above (the batch's columns per leg)
        if q_ is q:
            return [c.rnea(ql, vl, al, g) for c, ql, vl, al in zip(cores, legs, vs, as_)]
        if q_ is q32:
            return [c.rnea(ql, vl, al, g) for c, ql, vl, al in zip(cores, legs32, vs32, as32)]
        return np.concatenate(
            [
                c.rnea(q_[..., 3 * k : 3 * k + 3], v_[..., 3 * k : 3 * k + 3], a_[..., 3 * k : 3 * k + 3], g)
                for k, c in enumerate(cores)
            ],
            axis=-1,
        )

    def crba(q_):
        if q_ is q:
            return [c.crba(ql) for c, ql in zip(cores, legs)]
        out = np.zeros((*q_.shape[:-1], 12, 12))
        for k, c in enumerate(cores):
            out[..., 3 * k : 3 * k + 3, 3 * k : 3 * k + 3] = c.crba(q_[..., 3 * k : 3 * k + 3])
        return out

    rnea.float32 = (q32, v32, a32)
    return model, rnea, crba, q, v, a, q


WORKLOADS = {"arm6": _arm6, "legs12": _legs12, "legs12-fixed": _legs12_fixed}
_CACHE: dict = {}


def workload(name):
    if name not in _CACHE:
        _CACHE[name] = WORKLOADS[name]()
    return _CACHE[name]


def run(benchmark, key, impl, func, *args, rounds=5):
    benchmark.group = f"dynamics {key}"
    threads = sk.get_num_threads()
    sk.set_num_threads(1)
    try:
        result = benchmark.pedantic(func, args=args, rounds=rounds, iterations=1, warmup_rounds=1)
    finally:
        sk.set_num_threads(threads)
    _TIMES[key][impl] = benchmark.stats.stats.median
    return result


@pytest.mark.parametrize("name", sorted(WORKLOADS))
def test_agree_with_pinocchio(name):
    model, rnea, crba, q, v, a, _ = workload(name)
    data = model.createData()
    tau = rnea(q[:50], v[:50], a[:50], model.gravity.linear)
    A = crba(q[:50])
    for i in range(50):
        np.testing.assert_allclose(tau[i], pin.rnea(model, data, q[i], v[i], a[i]), atol=1e-9)
        M = pin.crba(model, data, q[i])
        np.testing.assert_allclose(A[i], np.triu(M) + np.triu(M, 1).T, atol=1e-9)


@pytest.mark.parametrize("name", sorted(WORKLOADS))
@pytest.mark.parametrize(
    "impl", ["spotkin-1thread", "spotkin-f32-1thread", "ref:pin-parallel-1thread", "ref:pin-loop"]
)
def test_rnea(benchmark, name, impl):
    model, rnea, _, q, v, a, _ = workload(name)
    g = model.gravity.linear.copy()
    if impl == "spotkin-1thread":
        run(benchmark, f"rnea.{name} N={N}", impl, rnea, q, v, a, g)
    elif impl == "spotkin-f32-1thread":  # float lanes (target: 1.8x the float64 throughput)
        q32, v32, a32 = getattr(rnea, "float32", None) or (x.astype(np.float32) for x in (q, v, a))
        g32 = g.astype(np.float32)
        run(benchmark, f"rnea.{name} N={N}", impl, rnea, q32, v32, a32, g32)
    elif impl == "ref:pin-parallel-1thread":
        pool = pin.ModelPool(model, 1)
        qT, vT, aT = (np.asfortranarray(x.T) for x in (q, v, a))
        tau = np.asfortranarray(np.zeros((model.nv, N)))
        run(benchmark, f"rnea.{name} N={N}", impl, pin.rneaInParallel, 1, pool, qT, vT, aT, tau)
    else:
        data = model.createData()

        def loop():
            for i in range(N):
                pin.rnea(model, data, q[i], v[i], a[i])

        run(benchmark, f"rnea.{name} N={N}", impl, loop, rounds=2)


@pytest.mark.parametrize("name", sorted(WORKLOADS))
@pytest.mark.parametrize(
    "impl", ["spotkin-1thread", "spotkin-packed-1thread", "spotkin-packed-f32-1thread", "ref:pin-loop"]
)
def test_crba(benchmark, name, impl):
    model, _, crba, q, *_ = workload(name)
    if impl == "spotkin-1thread":
        run(benchmark, f"crba.{name} N={N}", impl, crba, q)
    elif impl.startswith("spotkin-packed"):
        if name == "legs12-fixed":
            pytest.skip("four 3 x 3 blocks: no packed form in this workload")
        # the lower triangle row by row (layout="packed"): (6 + n) (7 + n) / 2 values, not (6 + n)^2
        q_in = q.astype(np.float32) if "f32" in impl else q
        run(benchmark, f"crba.{name} N={N}", impl, lambda x: crba(x, "packed"), q_in)
    else:
        data = model.createData()

        def loop():
            for i in range(N):
                pin.crba(model, data, q[i])

        run(benchmark, f"crba.{name} N={N}", impl, loop, rounds=2)


@pytest.mark.parametrize("name", ["arm6", "legs12"])
@pytest.mark.parametrize("impl", ["spotkin", "ref:pin"])
def test_single_rnea(benchmark, name, impl):
    model, rnea, _, q, v, a, _ = workload(name)
    g = model.gravity.linear.copy()
    q1, v1, a1 = q[0].copy(), v[0].copy(), a[0].copy()
    benchmark.group = f"dynamics single rnea.{name}"
    if impl == "spotkin":
        benchmark.pedantic(rnea, args=(q1, v1, a1, g), rounds=2000, iterations=20, warmup_rounds=50)
    else:
        data = model.createData()
        benchmark.pedantic(
            pin.rnea, args=(model, data, q1, v1, a1), rounds=2000, iterations=20, warmup_rounds=50
        )
    _TIMES[f"single rnea.{name}"][impl] = benchmark.stats.stats.median


def test_summary():
    """Prints per-configuration times and spotkin's speed-up over each reference (same run)."""
    lines = []
    for key, impls in sorted(_TIMES.items()):
        n = N if "N=" in key else 1
        ours = {i: t for i, t in impls.items() if not i.startswith("ref:")}
        for impl, t in sorted(impls.items(), key=lambda kv: kv[1]):
            ratios = [f"{t / o:5.1f}x {i}" for i, o in ours.items()] if impl.startswith("ref:") else []
            ratio = f"  {impl} over: {', '.join(ratios)}" if ratios else ""
            lines.append(f"{key:<24} {impl:<26} {t / n * 1e9:10.1f} ns/config{ratio}")
    print("\n" + "\n".join(lines))
