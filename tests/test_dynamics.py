"""Rigid-body dynamics (spotkin.dynamics, C++ kernels) against Pinocchio on Spot's and Go2's URDFs.

Fixed base: a chain of the URDF (the arm, a leg) against Pinocchio's model reduced to that
chain's joints (every other joint locked at 0, so a moving branch such as the gripper finger is
merged rigidly into its parent, as the inertials taken from the reduced model describe). The
chains' inertials are read from Pinocchio's model (mass, lever, inertia about the centre of mass,
in the joint frame: the contract of spotkin.dynamics.LinkInertials), the rest is spotkin's own.
Floating base: the whole robot as a free-flyer, the body carrying every leg and the arm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import spotkin as sk
from spotkin import dynamics as dyn

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

pin = pytest.importorskip("pinocchio")

ROBOTS = Path(sk.__file__).parent / "robots"
SPOT = str(ROBOTS / "spot_with_arm.urdf")
GO2 = str(ROBOTS / "go2.urdf")

# (urdf, tip link) of the fixed-base chains
CHAINS = {
    "spot_arm": (SPOT, "arm_hand"),
    "spot_arm_finger": (SPOT, "arm_link_fngr"),
    "spot_leg": (SPOT, "front_left_foot"),
    "go2_leg": (GO2, "RR_foot"),
}
FLOATING = {
    "spot": (
        SPOT,
        ["arm_link_fngr", "front_left_foot", "front_right_foot", "rear_left_foot", "rear_right_foot"],
    ),
    "go2": (GO2, ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]),
}
TOL64 = 1e-10


def close(a, b, tol=TOL64):
    """max |a - b| <= tol * max(1, max |b|)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, (a.shape, b.shape)
    scale = max(1.0, float(np.max(np.abs(b)))) if b.size else 1.0
    err = float(np.max(np.abs(a - b))) if a.size else 0.0
    assert err <= tol * scale, f"max error {err:.3g} > {tol:.1g} * {scale:.3g}"
    return err / scale


def inertials_from_pin(model, joint_names):
    ids = [model.getJointId(n) for n in joint_names]
    return dyn.LinkInertials(
        np.array([model.inertias[i].mass for i in ids]),
        np.array([model.inertias[i].lever for i in ids]),
        np.array([model.inertias[i].inertia for i in ids]),
    )


def sym(M):
    """Pinocchio's crba fills the upper triangle."""
    return np.triu(M) + np.triu(M, 1).T


class Fixed:
    """A spotkin chain with its inertials and the matching reduced Pinocchio model."""

    def __init__(self, key):
        urdf, tip = CHAINS[key]
        self.chain = sk.Robot.from_urdf(urdf).chain(tip)
        names = self.chain.joint_names
        full = pin.buildModelFromUrdf(urdf)
        lock = [full.getJointId(n) for n in full.names[1:] if n not in names]
        self.model = pin.buildReducedModel(full, lock, pin.neutral(full))
        self.data = self.model.createData()
        self.idx = np.array([self.model.idx_vs[self.model.getJointId(n)] for n in names])
        assert self.model.nv == len(names) == self.chain.dof
        self.inertials = inertials_from_pin(self.model, names)
        self.n = self.chain.dof

    def to_pin(self, x):
        out = np.zeros(self.model.nv)
        out[self.idx] = x
        return out

    def mat(self, M):
        return M[np.ix_(self.idx, self.idx)]

    def random(self, rng, shape=()):
        n = self.n
        return (
            rng.uniform(-np.pi, np.pi, (*shape, n)),
            rng.normal(size=(*shape, n)) * 2,
            rng.normal(size=(*shape, n)) * 5,
        )


@pytest.fixture(scope="module", params=sorted(CHAINS))
def fixed(request):
    return Fixed(request.param)


@pytest.fixture
def rng():
    return np.random.default_rng(17)


# ------------------------------------------------------------------ fixed base vs Pinocchio


def test_fixed_base_matches_pinocchio(fixed, rng):
    m, d, kw = fixed.model, fixed.data, {"inertials": fixed.inertials}
    worst = {}
    for _ in range(20):
        q, qd, qdd = fixed.random(rng)
        qp, vp, ap = fixed.to_pin(q), fixed.to_pin(qd), fixed.to_pin(qdd)
        checks = {
            "rnea": (
                dyn.inverse_dynamics(fixed.chain, q, qd, qdd, **kw),
                pin.rnea(m, d, qp, vp, ap)[fixed.idx],
            ),
            "crba": (dyn.mass_matrix(fixed.chain, q, **kw), fixed.mat(sym(pin.crba(m, d, qp)))),
            "gravity": (
                dyn.gravity(fixed.chain, q, **kw),
                pin.computeGeneralizedGravity(m, d, qp)[fixed.idx],
            ),
            "nle": (
                dyn.nonlinear_effects(fixed.chain, q, qd, **kw),
                pin.nonLinearEffects(m, d, qp, vp)[fixed.idx],
            ),
            "coriolis": (
                dyn.coriolis_matrix(fixed.chain, q, qd, **kw),
                fixed.mat(pin.computeCoriolisMatrix(m, d, qp, vp)),
            ),
            "aba": (
                dyn.forward_dynamics(fixed.chain, q, qd, qdd, **kw),
                pin.aba(m, d, qp, vp, ap)[fixed.idx],
            ),
        }
        for name, (ours, ref) in checks.items():
            worst[name] = max(worst.get(name, 0.0), close(ours, ref))
    print(worst)


def test_custom_gravity(fixed, rng):
    g = np.array([1.5, -2.0, -7.0])
    fixed.model.gravity.linear = g
    try:
        q, qd, qdd = fixed.random(rng)
        tau = pin.rnea(fixed.model, fixed.data, fixed.to_pin(q), fixed.to_pin(qd), fixed.to_pin(qdd))
        close(dyn.inverse_dynamics(fixed.chain, q, qd, qdd, g, inertials=fixed.inertials), tau[fixed.idx])
        close(
            dyn.gravity(fixed.chain, q, gravity=g, inertials=fixed.inertials),
            pin.computeGeneralizedGravity(fixed.model, fixed.data, fixed.to_pin(q))[fixed.idx],
        )
    finally:
        fixed.model.gravity.linear = np.array([0.0, 0.0, -9.81])


def test_prismatic_and_dh_chain(rng):
    """A DH chain with a prismatic joint against the same chain built from joints for Pinocchio."""
    rows = [[0, 0.0, 0.0, 0.3, 0.0], [1, 0.2, -np.pi / 2, 0.1, 0.4], [0, 0.25, np.pi / 2, 0.0, -0.3]]
    chain = sk.Chain.from_dh(rows)
    n = chain.dof
    # the same chain as a Pinocchio model, joint by joint from spotkin's own frames at q = 0 is not
    # independent; build it from the DH definition instead: T = RotZ(theta) TransZ(d) TransX(a) RotX(alpha)
    model = pin.Model()
    parent, placement = 0, pin.SE3.Identity()
    inert = []
    for j, (sigma, a, alpha, d, theta) in enumerate(rows):
        pre = placement * pin.SE3(pin.rpy.rpyToMatrix(0, 0, theta), np.array([0, 0, d if sigma == 0 else 0]))
        joint = pin.JointModelRZ() if sigma == 0 else pin.JointModelPZ()
        if sigma == 1:  # d is the offset along z at q = 0: put it after the motion
            pre = placement * pin.SE3(pin.rpy.rpyToMatrix(0, 0, theta), np.zeros(3))
        jid = model.addJoint(parent, joint, pre, f"j{j}")
        post = pin.SE3(pin.rpy.rpyToMatrix(alpha, 0, 0), np.array([a, 0, 0]))
        if sigma == 1:
            post = pin.SE3(np.eye(3), np.array([0, 0, d])) * post
        mass = 1.0 + j
        com = rng.normal(size=3) * 0.1
        A = rng.normal(size=(3, 3))
        inertia_c = A @ A.T * 0.01 + 0.01 * np.eye(3)
        # spotkin's body frame is the frame after post; Pinocchio's joint frame is before post:
        # express the inertia in the joint frame for Pinocchio
        pin_inertia = post.act(pin.Inertia(mass, com, inertia_c))
        model.appendBodyToJoint(jid, pin_inertia, pin.SE3.Identity())
        inert.append((mass, com, inertia_c))
        parent, placement = jid, post
    data = model.createData()
    inertials = dyn.LinkInertials(
        np.array([x[0] for x in inert]), np.array([x[1] for x in inert]), np.array([x[2] for x in inert])
    )
    for _ in range(10):
        q, qd, qdd = rng.uniform(-1, 1, n), rng.normal(size=n), rng.normal(size=n)
        close(dyn.inverse_dynamics(chain, q, qd, qdd, inertials=inertials), pin.rnea(model, data, q, qd, qdd))
        close(dyn.mass_matrix(chain, q, inertials=inertials), sym(pin.crba(model, data, q)))
        close(
            dyn.coriolis_matrix(chain, q, qd, inertials=inertials),
            pin.computeCoriolisMatrix(model, data, q, qd),
        )
        close(dyn.forward_dynamics(chain, q, qd, qdd, inertials=inertials), pin.aba(model, data, q, qd, qdd))


# ------------------------------------------------------------------ identities


def test_identities(fixed, rng):
    kw = {"inertials": fixed.inertials}
    q, qd, qdd = fixed.random(rng, (50,))
    A = dyn.mass_matrix(fixed.chain, q, **kw)
    np.testing.assert_array_equal(A, np.swapaxes(A, -1, -2))
    assert np.all(np.linalg.eigvalsh(A) > 0)
    C = dyn.coriolis_matrix(fixed.chain, q, qd, **kw)
    G = dyn.gravity(fixed.chain, q, **kw)
    tau = dyn.inverse_dynamics(fixed.chain, q, qd, qdd, **kw)
    close(np.einsum("...ij,...j->...i", A, qdd) + np.einsum("...ij,...j->...i", C, qd) + G, tau)
    close(dyn.nonlinear_effects(fixed.chain, q, qd, **kw), np.einsum("...ij,...j->...i", C, qd) + G)
    close(dyn.forward_dynamics(fixed.chain, q, qd, tau, **kw), qdd, 1e-9)
    # dA/dt - 2 C is skew-symmetric (dA/dt by central differences along qd)
    h = 1e-6
    dA = (dyn.mass_matrix(fixed.chain, q + h * qd, **kw) - dyn.mass_matrix(fixed.chain, q - h * qd, **kw)) / (
        2 * h
    )
    N = dA - 2 * C
    close(N + np.swapaxes(N, -1, -2), np.zeros_like(N), 1e-6 * max(1.0, np.abs(dA).max()))


# ------------------------------------------------------------------ batches and the boundary


@given(shape=st.sampled_from([(), (1,), (3, 1, 2), (2, 3)]), seed=st.integers(0, 2**32 - 1))
def test_batch_shapes_broadcast(shape, seed):
    fx = _fixed("spot_arm")
    rng = np.random.default_rng(seed)
    q, qd, qdd = fx.random(rng, shape)
    kw = {"inertials": fx.inertials}
    tau = dyn.inverse_dynamics(fx.chain, q, qd, qdd, **kw)
    A = dyn.mass_matrix(fx.chain, q, **kw)
    assert tau.shape == (*shape, fx.n) and A.shape == (*shape, fx.n, fx.n)
    flat_q, flat_qd, flat_qdd = (x.reshape(-1, fx.n) for x in (q, qd, qdd))
    for i in range(flat_q.shape[0]):  # each row as a single call, and against Pinocchio
        close(
            tau.reshape(-1, fx.n)[i],
            dyn.inverse_dynamics(fx.chain, flat_q[i], flat_qd[i], flat_qdd[i], **kw),
            0,
        )
        ref = pin.rnea(fx.model, fx.data, fx.to_pin(flat_q[i]), fx.to_pin(flat_qd[i]), fx.to_pin(flat_qdd[i]))
        close(tau.reshape(-1, fx.n)[i], ref[fx.idx])
    # one qd for every sample, gravity per sample
    if shape:
        g = rng.normal(size=(*shape, 3))
        out = dyn.inverse_dynamics(fx.chain, q, qd.reshape(-1, fx.n)[0], qdd, g, **kw)
        for idx in np.ndindex(*shape):
            close(
                out[idx],
                dyn.inverse_dynamics(fx.chain, q[idx], qd.reshape(-1, fx.n)[0], qdd[idx], g[idx], **kw),
            )


_FIXED = {}


def _fixed(key):
    if key not in _FIXED:
        _FIXED[key] = Fixed(key)
    return _FIXED[key]


def test_leading_shapes_broadcast_like_numpy(rng):
    fx = _fixed("spot_leg")
    q = rng.uniform(-1, 1, (4, 1, 3))
    qd = rng.normal(size=(1, 5, 3))
    out = dyn.nonlinear_effects(fx.chain, q, qd, inertials=fx.inertials)
    assert out.shape == (4, 5, 3)
    close(out[2, 3], dyn.nonlinear_effects(fx.chain, q[2, 0], qd[0, 3], inertials=fx.inertials), 0)
    with pytest.raises(ValueError, match=r"q \(4, 3\), qd \(5, 3\) and gravity \(3,\) do not broadcast"):
        dyn.nonlinear_effects(
            fx.chain, rng.normal(size=(4, 3)), rng.normal(size=(5, 3)), inertials=fx.inertials
        )


def test_float32(fixed, rng):
    kw = {"inertials": fixed.inertials}
    q, qd, qdd = fixed.random(rng, (40,))
    q32, qd32, qdd32 = (x.astype(np.float32) for x in (q, qd, qdd))
    for f, args in [
        (dyn.inverse_dynamics, (q32, qd32, qdd32)),
        (dyn.mass_matrix, (q32,)),
        (dyn.coriolis_matrix, (q32, qd32)),
        (dyn.forward_dynamics, (q32, qd32, qdd32)),
        (dyn.gravity, (q32,)),
        (dyn.nonlinear_effects, (q32, qd32)),
    ]:
        out = f(fixed.chain, *args, **kw)
        assert out.dtype == np.float32
        ref = f(fixed.chain, *(a.astype(np.float64) for a in args), **kw)
        tol = 1e-3 if f is dyn.forward_dynamics else 2e-4
        close(out, ref, tol)
    # a float64 argument among float32 ones computes in float64
    assert dyn.inverse_dynamics(fixed.chain, q32, qd32, qdd, **kw).dtype == np.float64


def test_noncontiguous_empty_and_nan_rows(rng):
    fx = _fixed("spot_arm")
    kw = {"inertials": fx.inertials}
    big = rng.uniform(-1, 1, (10, 2 * fx.n))
    q = big[:, ::2]
    assert not q.flags.c_contiguous
    close(dyn.mass_matrix(fx.chain, q, **kw), dyn.mass_matrix(fx.chain, np.ascontiguousarray(q), **kw), 0)
    close(dyn.gravity(fx.chain, q.T.copy().T, **kw), dyn.gravity(fx.chain, np.ascontiguousarray(q), **kw), 0)
    empty = np.zeros((0, fx.n))
    assert dyn.inverse_dynamics(fx.chain, empty, empty, empty, **kw).shape == (0, fx.n)
    assert dyn.mass_matrix(fx.chain, np.zeros((2, 0, fx.n)), **kw).shape == (2, 0, fx.n, fx.n)
    assert dyn.forward_dynamics(fx.chain, empty, empty, empty, **kw).shape == (0, fx.n)
    q, qd, qdd = fx.random(rng, (20,))
    qd[3, 5] = np.nan
    q[7, 0] = np.inf
    qdd[19, 1] = np.nan
    for f, args in [
        (dyn.inverse_dynamics, (q, qd, qdd)),
        (dyn.forward_dynamics, (q, qd, qdd)),
        (dyn.coriolis_matrix, (q, qd)),
        (dyn.nonlinear_effects, (q, qd)),
    ]:
        out = f(fx.chain, *args, **kw)
        bad = [3, 7, 19] if len(args) == 3 else [3, 7]
        for i in range(20):
            row = out[i]
            if i in bad:
                assert np.all(np.isnan(row))
            else:
                assert np.all(np.isfinite(row))
                close(row, f(fx.chain, *(a[i] for a in args), **kw), 0)
    A = dyn.mass_matrix(fx.chain, q, **kw)
    assert np.all(np.isnan(A[7])) and np.all(np.isfinite(np.delete(A, 7, axis=0)))


@pytest.mark.parametrize("level", sk.available_isas())
def test_float32_blocks_load_nan_rows_and_every_value(rng, level):
    """float32 loads whole blocks of rows as vectors (8 lanes on AVX2, 16 on AVX-512, 4 on SSE2
    and NEON): every value reaches its lane, the last row's tail included, and a NaN or an Inf
    anywhere in a row gives that row NaN and no other."""
    fx = _fixed("spot_arm")
    kw = {"inertials": fx.inertials}
    q, qd, qdd = (x.astype(np.float32) for x in fx.random(rng, (48,)))
    arrays = {"q": q, "qd": qd, "qdd": qdd}
    bad_at = [
        ("q", 7, fx.n - 1, np.inf),
        ("qd", 15, fx.n - 1, np.nan),
        ("qdd", 8, 0, np.nan),
        ("q", 47, 5, -np.inf),
    ]
    with sk.isa(level):
        clean = dyn.inverse_dynamics(fx.chain, q, qd, qdd, **kw)
        close(
            clean, dyn.inverse_dynamics(fx.chain, *(x.astype(np.float64) for x in (q, qd, qdd)), **kw), 2e-4
        )
        for i in range(48):  # each row alone (loaded value by value): the same bits
            assert np.array_equal(clean[i], dyn.inverse_dynamics(fx.chain, q[i], qd[i], qdd[i], **kw))
        for name, i, j, value in bad_at:
            arrays[name][i, j] = value
        out = dyn.inverse_dynamics(fx.chain, q, qd, qdd, **kw)
    bad_rows = sorted({i for _, i, _, _ in bad_at})
    assert np.all(np.isnan(out[bad_rows]))
    good = np.delete(np.arange(48), bad_rows)
    assert np.array_equal(out[good], clean[good])


def test_errors(rng):
    fx = _fixed("spot_arm")
    kw = {"inertials": fx.inertials}
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 6\)"):
        dyn.mass_matrix(fx.chain, np.zeros(5), **kw)
    with pytest.raises(ValueError, match="gravity"):
        dyn.gravity(fx.chain, np.zeros(6), np.zeros(2), **kw)
    with pytest.raises(TypeError, match="qd"):
        dyn.nonlinear_effects(fx.chain, np.zeros(6), "fast", **kw)
    with pytest.raises(ValueError, match="mass"):
        dyn.mass_matrix(fx.chain, np.zeros(6), inertials=(np.ones(5), np.zeros((6, 3)), np.zeros((6, 3, 3))))
    with pytest.raises(ValueError, match="positive semidefinite"):
        dyn.mass_matrix(
            fx.chain, np.zeros(6), inertials=(np.ones(6), np.zeros((6, 3)), -np.eye(3)[None].repeat(6, 0))
        )
    with pytest.raises(ValueError, match="chain carries no inertial"):
        dyn.mass_matrix(sk.Chain.from_dh([[0, 0.1, 0.0, 0.0, 0.0]]), np.zeros(1))


# ------------------------------------------------------------------ floating base vs Pinocchio


class Floating:
    def __init__(self, key):
        urdf, tips = FLOATING[key]
        robot = sk.Robot.from_urdf(urdf)
        self.chains = [robot.chain(t) for t in tips]
        self.model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
        self.data = self.model.createData()
        names = [n for c in self.chains for n in c.joint_names]
        assert sorted(names) == sorted(self.model.names[2:])  # every joint of the robot, once
        jid = [self.model.getJointId(n) for n in names]
        self.iv = np.r_[np.arange(6), [self.model.idx_vs[i] for i in jid]]
        self.iq = np.r_[np.arange(7), [self.model.idx_qs[i] for i in jid]]
        body = self.model.inertias[1]
        self.fb = dyn.FloatingBase(
            (body.mass, body.lever, body.inertia),
            self.chains,
            [inertials_from_pin(self.model, c.joint_names) for c in self.chains],
        )
        self.n = len(names)

    def random(self, rng):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        q = np.r_[rng.normal(size=3), quat, rng.uniform(-np.pi, np.pi, self.n)]
        return q, rng.normal(size=6 + self.n), rng.normal(size=6 + self.n) * 3

    def to_pin(self, x, index):
        out = np.zeros(len(x))
        out[index] = x
        return out


@pytest.fixture(scope="module", params=sorted(FLOATING))
def floating(request):
    return Floating(request.param)


def test_floating_base_matches_pinocchio(floating, rng):
    fl, m, d = floating, floating.model, floating.data
    assert fl.fb.nq == m.nq and fl.fb.nv == m.nv
    worst = {}
    for _ in range(20):
        q, v, a = fl.random(rng)
        qp, vp, ap = fl.to_pin(q, fl.iq), fl.to_pin(v, fl.iv), fl.to_pin(a, fl.iv)
        checks = {
            "rnea": (fl.fb.inverse_dynamics(q, v, a), pin.rnea(m, d, qp, vp, ap)[fl.iv]),
            "crba": (fl.fb.mass_matrix(q), sym(pin.crba(m, d, qp))[np.ix_(fl.iv, fl.iv)]),
            "gravity": (fl.fb.gravity(q), pin.computeGeneralizedGravity(m, d, qp)[fl.iv]),
            "nle": (fl.fb.nonlinear_effects(q, v), pin.nonLinearEffects(m, d, qp, vp)[fl.iv]),
            "aba": (fl.fb.forward_dynamics(q, v, a), pin.aba(m, d, qp, vp, ap)[fl.iv]),
            "coriolis": (
                fl.fb.coriolis_matrix(q, v),
                pin.computeCoriolisMatrix(m, d, qp, vp)[np.ix_(fl.iv, fl.iv)],
            ),
            "com": (fl.fb.center_of_mass(q), pin.centerOfMass(m, d, qp)),
            "com_jacobian": (fl.fb.center_of_mass_jacobian(q), pin.jacobianCenterOfMass(m, d, qp)[:, fl.iv]),
        }
        for name, (ours, ref) in checks.items():
            worst[name] = max(worst.get(name, 0.0), close(ours, ref))
    print(worst)


def test_floating_identities(floating, rng):
    fl = floating
    qs, vs, as_ = zip(*(fl.random(rng) for _ in range(16)))
    q, v, a = np.array(qs), np.array(vs), np.array(as_)
    A = fl.fb.mass_matrix(q)
    assert np.all(np.linalg.eigvalsh(A) > 0)
    tau = fl.fb.inverse_dynamics(q, v, a)
    close(np.einsum("...ij,...j->...i", A, a) + fl.fb.nonlinear_effects(q, v), tau)
    close(fl.fb.forward_dynamics(q, v, tau), a, 1e-9)
    # h = C v + G, and dA/dt - 2 C is skew-symmetric (dA/dt by central differences along v)
    C = fl.fb.coriolis_matrix(q, v)
    close(np.einsum("...ij,...j->...i", C, v) + fl.fb.gravity(q), fl.fb.nonlinear_effects(q, v))
    h = 1e-6
    m = fl.model
    for i in range(3):
        dA = (
            fl.fb.mass_matrix(_integrate(m, fl, q[i], v[i], h))
            - fl.fb.mass_matrix(_integrate(m, fl, q[i], v[i], -h))
        ) / (2 * h)
        N = dA - 2 * C[i]
        close(N + N.T, np.zeros_like(N), 1e-6 * max(1.0, np.abs(dA).max()))
    # A depends on the joints only, not on the body's pose
    q2 = q.copy()
    q2[:, :7] = fl.random(rng)[0][:7]
    close(fl.fb.mass_matrix(q2), A)
    # the centre of mass Jacobian by central differences along the body-frame twist
    eps = 1e-6
    q0, v0 = q[0], v[0]
    J = fl.fb.center_of_mass_jacobian(q0)
    m = fl.model
    dq = fl.fb.center_of_mass(_integrate(m, fl, q0, v0, eps)) - fl.fb.center_of_mass(
        _integrate(m, fl, q0, v0, -eps)
    )
    close(J @ v0, dq / (2 * eps), 1e-6)
    # float32 and batch shapes
    out32 = fl.fb.inverse_dynamics(q.astype(np.float32), v.astype(np.float32), a.astype(np.float32))
    assert out32.dtype == np.float32
    close(out32, tau, 1e-3)
    assert fl.fb.mass_matrix(q.reshape(2, 8, -1)).shape == (2, 8, fl.n + 6, fl.n + 6)
    assert fl.fb.center_of_mass(np.zeros((0, fl.n + 7))).shape == (0, 3)
    qn = q.copy()
    qn[5, 9] = np.nan
    out = fl.fb.inverse_dynamics(qn, v, a)
    assert np.all(np.isnan(out[5])) and np.all(np.isfinite(np.delete(out, 5, 0)))


def _integrate(model, fl, q, v, t):
    """q (ours) moved for time t along v (ours) with Pinocchio's integrate, back in our order."""
    qp = pin.integrate(model, fl.to_pin(q, fl.iq), fl.to_pin(v, fl.iv) * t)
    return qp[fl.iq]


def _with_threads(n, f, *args):
    previous = sk.get_num_threads()
    sk.set_num_threads(n)
    try:
        return f(*args)
    finally:
        sk.set_num_threads(previous)


@pytest.mark.parametrize("count", [3, 8, 13, 5003, 20_000])
def test_bits_do_not_depend_on_threads_and_rows_equal_single_calls(count, rng):
    """Chunks start on block boundaries and the lane width is chosen on the whole batch, so the
    thread count never changes a bit (20 000 arm mass matrices are streamed out with non-temporal
    stores). A batch shorter than a block (8 lanes; 16 in float32) runs on 2-lane (4) models, whose
    rounding may differ from the wide one's by an ulp: a single call equals its batch row to 1e-14."""
    fx, fl = _fixed("spot_arm"), _floating("go2")
    kw = {"inertials": fx.inertials}
    q, qd, qdd = fx.random(rng, (count,))
    states = [fl.random(rng) for _ in range(min(count, 300))]
    qf, vf, af = (np.array(x) for x in zip(*states))
    calls = {
        "rnea": lambda: dyn.inverse_dynamics(fx.chain, q, qd, qdd, **kw),
        "crba": lambda: dyn.mass_matrix(fx.chain, q, **kw),
        "coriolis": lambda: dyn.coriolis_matrix(fx.chain, q, qd, **kw),
        "aba": lambda: dyn.forward_dynamics(fx.chain, q, qd, qdd, **kw),
        "floating crba": lambda: fl.fb.mass_matrix(qf),
        "floating aba": lambda: fl.fb.forward_dynamics(qf, vf, af),
        "float32 rnea": lambda: dyn.inverse_dynamics(
            fx.chain, *(x.astype(np.float32) for x in (q, qd, qdd)), **kw
        ),
    }
    one = {name: _with_threads(1, f) for name, f in calls.items()}
    two = {name: _with_threads(2, f) for name, f in calls.items()}
    for name in calls:
        np.testing.assert_array_equal(one[name], two[name], err_msg=name)
    for i in rng.choice(count, size=min(count, 8), replace=False):
        close(one["rnea"][i], dyn.inverse_dynamics(fx.chain, q[i], qd[i], qdd[i], **kw), 1e-14)
        close(one["crba"][i], dyn.mass_matrix(fx.chain, q[i], **kw), 1e-14)
        close(one["coriolis"][i], dyn.coriolis_matrix(fx.chain, q[i], qd[i], **kw), 1e-14)
        close(one["aba"][i], dyn.forward_dynamics(fx.chain, q[i], qd[i], qdd[i], **kw), 1e-13)
        ref = pin.rnea(fx.model, fx.data, fx.to_pin(q[i]), fx.to_pin(qd[i]), fx.to_pin(qdd[i]))[fx.idx]
        close(one["rnea"][i], ref)
        if i < len(states):
            close(one["floating crba"][i], fl.fb.mass_matrix(qf[i]), 1e-14)
            close(one["floating aba"][i], fl.fb.forward_dynamics(qf[i], vf[i], af[i]), 1e-13)


# ---------------------------------------------------------- the URDF's own inertials (spotkin.inertia)


def test_chain_methods_with_the_urdfs_inertials(fixed, rng):
    """Chain.inertials (merged from the URDF by spotkin.inertia) give Pinocchio's values: the whole
    path from the URDF's <inertial> elements to the kernels."""
    chain, m, d = fixed.chain, fixed.model, fixed.data
    assert chain.inertials is not None
    for _ in range(5):
        q, qd, qdd = fixed.random(rng)
        qp, vp, ap = fixed.to_pin(q), fixed.to_pin(qd), fixed.to_pin(qdd)
        close(dyn.inverse_dynamics(chain, q, qd, qdd), pin.rnea(m, d, qp, vp, ap)[fixed.idx])
        close(dyn.mass_matrix(chain, q), fixed.mat(sym(pin.crba(m, d, qp))))
        close(dyn.forward_dynamics(chain, q, qd, qdd), pin.aba(m, d, qp, vp, ap)[fixed.idx])


def test_floating_base_with_the_urdfs_inertials(rng):
    urdf, tips = FLOATING["spot"]
    robot = sk.Robot.from_urdf(urdf)
    fb = dyn.FloatingBase(robot.body_inertial, [robot.chain(t) for t in tips])
    fl = _floating("spot")
    for _ in range(5):
        q, v, a = fl.random(rng)
        qp, vp, ap = fl.to_pin(q, fl.iq), fl.to_pin(v, fl.iv), fl.to_pin(a, fl.iv)
        close(fb.inverse_dynamics(q, v, a), pin.rnea(fl.model, fl.data, qp, vp, ap)[fl.iv])
        close(fb.mass_matrix(q), sym(pin.crba(fl.model, fl.data, qp))[np.ix_(fl.iv, fl.iv)])
        close(fb.center_of_mass(q), pin.centerOfMass(fl.model, fl.data, qp))


_FLOATING = {}


def _floating(key):
    if key not in _FLOATING:
        _FLOATING[key] = Floating(key)
    return _FLOATING[key]


# ---------------------------------------------------------- the pure-Python reference (spotkin.reference)

REFERENCE_CHAINS = ["critter_leg", "critter_arm", "zoo_leg", "zoo_continuous_leg"]


@pytest.mark.parametrize("case", REFERENCE_CHAINS)
def test_kernels_match_the_reference_on_the_test_robots(case, rng):
    """The test robots of tests/test_reference_dynamics.py (a prismatic arm joint, inertials rotated by
    rpy, a locked finger, negative and unnormalised axes, continuous joints) against the reference."""
    import test_reference_dynamics as trd

    from spotkin.reference import dynamics as rd

    name, link, _ = trd.CASES[case]
    chain = trd.robot(name).chain(link)
    tree = sk.inertia.tree_of(chain)
    n = chain.dof
    q = rng.uniform(-1.2, 1.2, (6, n))
    qd, qdd = rng.normal(0, 1.5, (6, n)), rng.normal(0, 2, (6, n))
    tau, A = dyn.inverse_dynamics(chain, q, qd, qdd), dyn.mass_matrix(chain, q)
    C, qdd_aba = dyn.coriolis_matrix(chain, q, qd), dyn.forward_dynamics(chain, q, qd, qdd)
    for i in range(len(q)):
        close(tau[i], rd.rnea(tree, q[i], qd[i], qdd[i]))
        close(A[i], rd.crba(tree, q[i]))
        close(C[i], rd.coriolis_matrix(tree, q[i], qd[i]))
        close(qdd_aba[i], rd.aba(tree, q[i], qd[i], qdd[i]))


@pytest.mark.parametrize("convention", ["dh", "mdh"])
def test_dh_chains_with_prismatic_joints_match_the_reference(convention, rng):
    rows = [
        [0, 0.1, 0.3, 0.2, 0.1],
        [1, 0.2, -np.pi / 2, 0.15, 0.4],
        [0, 0.25, np.pi / 2, 0.05, -0.3],
        [0, 0.0, 0.7, 0.1, 0.2],
    ]
    n = len(rows)
    A = rng.normal(size=(n, 3, 3))
    chain = getattr(sk.Chain, f"from_{convention}")(
        rows, base=sk.translation([0.1, -0.2, 0.3])
    ).with_inertials(
        rng.uniform(0.5, 2, n),
        rng.normal(0, 0.1, (n, 3)),
        A @ np.swapaxes(A, 1, 2) * 0.01 + 0.001 * np.eye(3),
    )
    from spotkin.reference import dynamics as rd

    tree = sk.inertia.tree_of(chain)
    g = np.array([0.3, -1.0, -9.0])
    for _ in range(5):
        q, qd, qdd = rng.uniform(-1, 1, n), rng.normal(size=n), rng.normal(size=n)
        close(dyn.inverse_dynamics(chain, q, qd, qdd, g), rd.rnea(tree, q, qd, qdd, g))
        close(dyn.mass_matrix(chain, q), rd.crba(tree, q))
        close(dyn.coriolis_matrix(chain, q, qd), rd.coriolis_matrix(tree, q, qd))
        close(dyn.forward_dynamics(chain, q, qd, qdd, g), rd.aba(tree, q, qd, qdd, g))


@pytest.mark.parametrize("convention", ["dh", "mdh"])
def test_floating_base_with_general_axes_and_prismatic_joints(convention, rng):
    """The floating CRBA's sparse (+-e_k axis) and general subspace forms, and prismatic joints: DH chains
    (axes along z before an x-screw: general in the link frame) on a rotated mount, against the fixed-base
    CRBA of each chain (its joint block) and against RNEA (A a + h = tau)."""
    rows = [
        [0, 0.1, 0.3, 0.2, 0.1],
        [1, 0.2, -np.pi / 2, 0.15, 0.4],
        [0, 0.25, np.pi / 2, 0.05, -0.3],
    ]
    mount = sk.translation([0.1, -0.2, 0.3]) @ sk.rotation_z(0.7) @ sk.rotation_x(0.4)
    chains = []
    for k in range(2):
        A = rng.normal(size=(3, 3, 3))
        chains.append(
            getattr(sk.Chain, f"from_{convention}")(
                rows[k:] + rows[:k], base=mount if k else np.eye(4)
            ).with_inertials(
                rng.uniform(0.5, 2, 3),
                rng.normal(0, 0.1, (3, 3)),
                A @ np.swapaxes(A, 1, 2) * 0.01 + 0.001 * np.eye(3),
            )
        )
    fb = dyn.FloatingBase((3.0, np.array([0.02, -0.01, 0.03]), np.diag([0.1, 0.2, 0.25])), chains)
    quat = rng.normal(size=(8, 4))
    q = np.hstack([rng.normal(size=(8, 3)), quat, rng.uniform(-1, 1, (8, 6))])
    v, a = rng.normal(size=(8, 12)), rng.normal(size=(8, 12))
    A = fb.mass_matrix(q)
    close(np.einsum("...ij,...j->...i", A, a) + fb.nonlinear_effects(q, v), fb.inverse_dynamics(q, v, a))
    for k, c in enumerate(chains):
        block = A[:, 6 + 3 * k : 9 + 3 * k, 6 + 3 * k : 9 + 3 * k]
        close(block, dyn.mass_matrix(c, q[:, 7 + 3 * k : 10 + 3 * k]))
    close(A[:, 6:9, 9:12], np.zeros((8, 3, 3)), 0)
    close(fb.mass_matrix(q, layout="lower"), np.tril(A), 0)
    close(dyn.unpack_symmetric(fb.mass_matrix(q, layout="packed")), A, 0)


# ------------------------------------------------------------------ a sample's bits, alone or in any batch


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_sample_has_the_same_bits_alone_and_in_batches_of_any_size(dtype, rng):
    """The kernels' vector width depends on the instruction-set level only (every_isa runs each
    level): one sample, a batch shorter than the lanes and a long batch give a row the same bits."""
    fx = _fixed("spot_arm")
    q, qd, qdd = (x.astype(dtype) for x in fx.random(rng, (37,)))
    fixed_calls = {
        "rnea": lambda s: dyn.inverse_dynamics(fx.chain, q[s], qd[s], qdd[s], inertials=fx.inertials),
        "crba": lambda s: dyn.mass_matrix(fx.chain, q[s], inertials=fx.inertials),
        "crba packed": lambda s: dyn.mass_matrix(fx.chain, q[s], inertials=fx.inertials, layout="packed"),
        "crba lower": lambda s: dyn.mass_matrix(fx.chain, q[s], inertials=fx.inertials, layout="lower"),
        "aba": lambda s: dyn.forward_dynamics(fx.chain, q[s], qd[s], qdd[s], inertials=fx.inertials),
    }
    base = sk.Robot.from_urdf(GO2).floating_base
    quat = rng.normal(size=(37, 4))
    fq = np.hstack([rng.normal(size=(37, 3)), quat / np.linalg.norm(quat, axis=1, keepdims=True)])
    fq = np.hstack([fq, rng.uniform(-1, 1, (37, base.nq - 7))]).astype(dtype)
    fv, fa = (rng.normal(size=(37, base.nv)).astype(dtype) for _ in range(2))
    floating_calls = {
        "floating rnea": lambda s: base.inverse_dynamics(fq[s], fv[s], fa[s]),
        "floating crba": lambda s: base.mass_matrix(fq[s]),
        "floating crba lower": lambda s: base.mass_matrix(fq[s], layout="lower"),
        "floating crba packed": lambda s: base.mass_matrix(fq[s], layout="packed"),
        "floating aba": lambda s: base.forward_dynamics(fq[s], fv[s], fa[s]),
    }
    for name, call in {**fixed_calls, **floating_calls}.items():
        whole = call(slice(None))
        assert whole.dtype == dtype, name
        for k in (0, 5, 36):
            assert np.array_equal(call(k), whole[k]), (name, k)
        for part in (slice(3, 4), slice(3, 6), slice(10, 17)):
            assert np.array_equal(call(part), whole[part]), (name, part)
