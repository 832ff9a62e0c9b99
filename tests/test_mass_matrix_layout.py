"""The mass matrix's layouts (``layout="full" | "lower" | "packed"``) for fixed-base chains, the
floating base and mimic chains: against Pinocchio's crba, the full layout and its own batch
semantics (broadcasting, float32, NaN rows, empty and large streamed batches, threads), and
:func:`spotkin.dynamics.unpack_symmetric`."""

from __future__ import annotations

import numpy as np
import pytest
from test_dynamics import SPOT, Fixed, Floating, close, sym

import spotkin as sk
from spotkin import dynamics as dyn

pytestmark = pytest.mark.usefixtures("every_isa")
pin = pytest.importorskip("pinocchio")

LAYOUTS = ("full", "lower", "packed")


def expected(A: np.ndarray, layout: str) -> np.ndarray:
    """What each layout holds, written from the full matrix."""
    n = A.shape[-1]
    if layout == "full":
        return A
    if layout == "lower":
        return np.tril(A)
    rows, cols = np.tril_indices(n)  # row by row: A[i, j], j <= i, at i (i + 1) / 2 + j
    return A[..., rows, cols]


@pytest.fixture(scope="module", params=["spot_arm", "go2_leg"])
def fixed(request):
    return Fixed(request.param)


@pytest.fixture(scope="module", params=["spot", "go2"])
def floating(request):
    return Floating(request.param)


@pytest.fixture
def rng():
    return np.random.default_rng(23)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_fixed_base_layouts_match_pinocchio(fixed, layout, rng):
    q = rng.uniform(-np.pi, np.pi, (6, fixed.n))
    ours = dyn.mass_matrix(fixed.chain, q, inertials=fixed.inertials, layout=layout)
    n = fixed.n
    assert ours.shape == ((6, n, n) if layout != "packed" else (6, n * (n + 1) // 2))
    for i in range(len(q)):
        A = fixed.mat(sym(pin.crba(fixed.model, fixed.data, fixed.to_pin(q[i]))))
        close(ours[i], expected(A, layout))
    # the same numbers as the full layout, bit for bit
    full = dyn.mass_matrix(fixed.chain, q, inertials=fixed.inertials)
    np.testing.assert_array_equal(ours, expected(full, layout))
    if layout == "packed":
        np.testing.assert_array_equal(dyn.unpack_symmetric(ours), full)
    if layout == "lower":  # the storage numpy's Cholesky reads
        np.testing.assert_allclose(np.linalg.cholesky(ours), np.linalg.cholesky(full), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_floating_base_layouts_match_pinocchio(floating, layout, rng):
    fl = floating
    qs = [fl.random(rng)[0] for _ in range(4)]
    ours = fl.fb.mass_matrix(np.array(qs), layout=layout)
    nv = fl.fb.nv
    assert ours.shape == ((4, nv, nv) if layout != "packed" else (4, nv * (nv + 1) // 2))
    for i, q in enumerate(qs):
        A = sym(pin.crba(fl.model, fl.data, fl.to_pin(q, fl.iq)))[np.ix_(fl.iv, fl.iv)]
        close(ours[i], expected(A, layout))
    np.testing.assert_array_equal(ours, expected(fl.fb.mass_matrix(np.array(qs)), layout))


@pytest.mark.parametrize("layout", ["lower", "packed"])
@pytest.mark.parametrize("shape", [(), (1,), (3, 1, 2), (0,), (0, 3)])
def test_batch_semantics(fixed, layout, shape, rng):
    chain, inertials, n = fixed.chain, fixed.inertials, fixed.n
    q = rng.uniform(-np.pi, np.pi, (*shape, n))
    ours = dyn.mass_matrix(chain, q, inertials=inertials, layout=layout)
    full = dyn.mass_matrix(chain, q, inertials=inertials)
    np.testing.assert_array_equal(ours, expected(full, layout))
    assert ours.shape[: len(shape)] == shape
    # float32 stays float32, near the float64 answer
    q32 = q.astype(np.float32)
    ours32 = dyn.mass_matrix(chain, q32, inertials=inertials, layout=layout)
    assert ours32.dtype == np.float32
    np.testing.assert_array_equal(ours32, expected(dyn.mass_matrix(chain, q32, inertials=inertials), layout))
    if ours.size:
        close(ours32, dyn.mass_matrix(chain, q32.astype(float), inertials=inertials, layout=layout), 1e-4)


@pytest.mark.parametrize("layout", ["lower", "packed"])
def test_nan_rows_non_contiguous_threads_and_streamed_batches(fixed, layout, rng):
    chain, inertials, n = fixed.chain, fixed.inertials, fixed.n
    # 60,000 samples: more than the 2 MB a thread's share needs for streamed (non-temporal) stores
    q = rng.uniform(-np.pi, np.pi, (60_000, n))
    q[7, 1] = np.nan
    q[59_999, 0] = np.inf
    threads = sk.get_num_threads()
    try:
        sk.set_num_threads(1)
        one = dyn.mass_matrix(chain, q, inertials=inertials, layout=layout)
        sk.set_num_threads(2)
        two = dyn.mass_matrix(chain, q, inertials=inertials, layout=layout)
    finally:
        sk.set_num_threads(threads)
    np.testing.assert_array_equal(one, two)
    assert np.isnan(one[7]).all() and np.isnan(one[59_999]).all()
    assert np.isfinite(np.delete(one, [7, 59_999], axis=0)).all()
    small = dyn.mass_matrix(chain, q[:100], inertials=inertials, layout=layout)  # not streamed
    np.testing.assert_array_equal(one[:100], small)
    # (a NaN sample is NaN in every element, the zero triangle included)
    np.testing.assert_array_equal(
        small[8:], expected(dyn.mass_matrix(chain, q[8:100], inertials=inertials), layout)
    )
    # a strided view gives what its copy gives
    view = q[:200:2]
    np.testing.assert_array_equal(
        dyn.mass_matrix(chain, view, inertials=inertials, layout=layout), one[:200:2]
    )


def test_chain_methods_and_mimic_chains(rng):
    chain = sk.Robot.from_urdf(SPOT).chain("arm_hand")
    q = rng.uniform(-1, 1, (3, chain.dof))
    full = chain.mass_matrix(q)
    np.testing.assert_array_equal(chain.mass_matrix(q, layout="packed"), expected(full, "packed"))
    np.testing.assert_array_equal(chain.mass_matrix(q, "lower"), np.tril(full))
    # a chain with mimic joints computes A = M^T A_full M in NumPy, then lays it out the same way
    from test_urdf_loading import COUPLED

    coupled = sk.Chain.from_urdf(COUPLED)
    qc = np.c_[rng.uniform(-1, 1, (4, 2)), rng.uniform(0, 0.2, 4)]
    A = coupled.mass_matrix(qc)
    np.testing.assert_array_equal(coupled.mass_matrix(qc, layout="packed"), expected(A, "packed"))
    np.testing.assert_array_equal(coupled.mass_matrix(qc, layout="lower"), np.tril(A))
    with pytest.raises(ValueError, match="layout must be 'full', 'lower' or 'packed', got 'upper'"):
        coupled.mass_matrix(qc, layout="upper")
    # a NaN sample: NaN in every element, as in the C++ layouts
    qc[1, 0] = np.nan
    for layout in ("lower", "packed"):
        out = coupled.mass_matrix(qc, layout=layout)
        assert np.isnan(out[1]).all() and np.isfinite(np.delete(out, 1, axis=0)).all()


def test_unpack_symmetric_and_errors(fixed, rng):
    chain, inertials, n = fixed.chain, fixed.inertials, fixed.n
    q = rng.uniform(-1, 1, n)
    packed = dyn.mass_matrix(chain, q, inertials=inertials, layout="packed")
    A = dyn.unpack_symmetric(packed)
    np.testing.assert_array_equal(A, A.T)
    np.testing.assert_array_equal(A, dyn.mass_matrix(chain, q, inertials=inertials))
    # packing order, written out for n = 3: A00, A10, A11, A20, A21, A22
    np.testing.assert_array_equal(
        dyn.unpack_symmetric([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), [[1, 2, 4], [2, 3, 5], [4, 5, 6]]
    )
    assert dyn.unpack_symmetric(np.zeros((2, 0, 10), np.float32)).shape == (2, 0, 4, 4)
    assert dyn.unpack_symmetric(np.zeros(10, np.float32)).dtype == np.float32
    with pytest.raises(ValueError, match=r"packed must have shape \(\.\.\., n \(n \+ 1\) / 2\)"):
        dyn.unpack_symmetric(np.zeros(4))
    with pytest.raises(ValueError, match="packed must have shape"):
        dyn.unpack_symmetric(np.zeros((3, 0)))
    with pytest.raises(ValueError, match="packed"):
        dyn.unpack_symmetric(1.0)
    with pytest.raises(ValueError, match="layout must be 'full', 'lower' or 'packed', got 'upper'"):
        dyn.mass_matrix(chain, q, inertials=inertials, layout="upper")
    with pytest.raises(TypeError, match="layout must be a str"):
        dyn.mass_matrix(chain, q, inertials=inertials, layout=2)
