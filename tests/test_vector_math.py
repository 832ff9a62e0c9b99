"""The kernels' vectorised atan2 and sincos (cpp/include/spotkin/vector_math.hpp), through private
bindings that run the kernels' own loops, swept densely against a wider reference: long double for
float64 (skipped without extended precision), float64 for float32. Errors are in ulps of the
reference rounded to the dtype (np.spacing)."""

from __future__ import annotations

import numpy as np
import pytest

from spotkin import _core

# at every instruction-set level the CPU has (tests/conftest.py): FMA contraction differs between them
pytestmark = pytest.mark.usefixtures("every_isa")

EXTENDED = np.finfo(np.longdouble).nmant >= 60
DTYPES = [
    pytest.param(np.float64, id="float64"),
    pytest.param(np.float32, id="float32"),
]
WIDE = {np.float64: np.longdouble, np.float32: np.float64}  # the reference's precision
LIMIT = {np.float64: 1e5, np.float32: 8192.0}  # kReducibleLimit, kReducibleLimitFloat
N = 500_000


def wide(dtype):
    if dtype is np.float64 and not EXTENDED:
        pytest.skip("long double has no extended precision here: no float64 reference")
    return WIDE[dtype]


def ulps(got, ref, dtype):
    """|got - ref| in ulps of ref (ref in the wider type), the ulp being np.spacing of ref in dtype."""
    spacing = np.spacing(np.abs(ref.astype(dtype))).astype(ref.dtype)
    return np.abs(got.astype(ref.dtype) - ref) / spacing


def atan2_sweep(rng, dtype):
    """(y, x) in every octant: random angles; ratios min/max uniform in [0, 1], about 1/2 (where the
    kernel reduces by pi/4) and 1/4 (t crosses a binade), tiny and underflowing; magnitudes across the
    range (to 1e300 in float64, 1e35 in float32); subnormal pairs."""
    top = {np.float64: 300.0, np.float32: 35.0}[dtype]
    angle = rng.uniform(-np.pi, np.pi, N)
    radius = 10.0 ** rng.uniform(-top, top, N)
    ratio = np.concatenate(
        [
            rng.uniform(0, 1, N),
            0.5 + rng.uniform(-1e-3, 1e-3, N // 4),
            0.25 + rng.uniform(-5e-3, 5e-3, N // 4),
            10.0 ** rng.uniform(-top - 30, 0, N // 4),
        ]
    )
    hi = 10.0 ** rng.uniform(-top, top, ratio.size)
    tiny = np.finfo(dtype).smallest_subnormal
    nmant = np.finfo(dtype).nmant
    sub_hi = rng.integers(1, 2**nmant, N // 4)
    sub_lo = np.floor(rng.uniform(0, 1, N // 4) * sub_hi)
    a = np.concatenate([radius * np.sin(angle), hi, (sub_hi * tiny).astype(dtype)]).astype(dtype)
    b = np.concatenate([radius * np.cos(angle), ratio * hi, (sub_lo * tiny).astype(dtype)]).astype(dtype)
    swap = rng.random(a.size) < 0.5
    y, x = np.where(swap, a, b), np.where(swap, b, a)
    return y * rng.choice(np.array([-1, 1], dtype), y.size), x * rng.choice(np.array([-1, 1], dtype), x.size)


@pytest.mark.parametrize("dtype", DTYPES)
def test_atan2_within_2_ulp(dtype):
    w = wide(dtype)
    y, x = atan2_sweep(np.random.default_rng(20260501), dtype)
    got = _core._vector_atan2(y, x)
    assert got.dtype == dtype and got.shape == y.shape
    err = ulps(got, np.arctan2(y.astype(w), x.astype(w)), dtype)
    worst = int(np.argmax(err))
    assert err[worst] <= 2.0, f"{err[worst]:.3f} ulp at y={y[worst]!r}, x={x[worst]!r}: {got[worst]!r}"


@pytest.mark.parametrize("dtype", DTYPES)
def test_atan2_special_cases_match_numpy(dtype):
    """Signed zeros, infinities, NaN and y = +-x exactly as np.arctan2 (correctly rounded in the wider
    type): atan2(+-0, +0) = +-0, atan2(+-0, -0) = +-pi, pi/4 and 3 pi/4 for y = +-x of any size; the
    other pairs of the grid within 2 ulp. atan2(+-Inf, +-Inf) is NaN, as documented in vector_math.hpp
    (std::atan2: an odd multiple of pi/4)."""
    info = np.finfo(dtype)
    magnitudes = [0.0, 1.0, 3.5, 1e-30, 1e30, info.smallest_subnormal, 7 * info.smallest_subnormal, info.max]
    values = np.array([s * m for m in magnitudes for s in (1, -1)] + [np.inf, -np.inf, np.nan], dtype)
    y, x = (v.ravel() for v in np.meshgrid(values, values))
    magnitude = 10.0 ** np.random.default_rng(7).uniform(-35, 35, 1000)  # y = +-x, every sign
    v = magnitude.astype(dtype)
    y = np.concatenate([y, v, v, -v, -v])
    x = np.concatenate([x, v, -v, v, -v])
    got = _core._vector_atan2(y, x)
    ref_wide = np.arctan2(y.astype(WIDE[dtype]), x.astype(WIDE[dtype]))
    ref = ref_wide.astype(dtype)
    both_infinite = np.isinf(y) & np.isinf(x)
    assert np.isnan(got[both_infinite]).all()
    exact = ~both_infinite & (
        (y == 0) | (x == 0) | np.isinf(y) | np.isinf(x) | np.isnan(y) | np.isnan(x) | (np.abs(y) == np.abs(x))
    )
    np.testing.assert_array_equal(got[exact], ref[exact])  # NaN where NaN
    np.testing.assert_array_equal(np.signbit(got[exact & (ref == 0)]), np.signbit(ref[exact & (ref == 0)]))
    if dtype is np.float32 or EXTENDED:
        rest = ~both_infinite & ~exact
        assert (ulps(got[rest], ref_wide[rest], dtype) <= 2.0).all()


def sincos_sweep(rng, dtype):
    """Uniform on [-4, 4] and on the reducible range, log-uniform magnitudes from the smallest normal up,
    and the neighbours (0 to 3 ulps either way) of the dtype's values nearest k pi/2."""
    limit, tiny = LIMIT[dtype], np.finfo(dtype).tiny
    signs = rng.choice([-1.0, 1.0], N)
    half_pi = np.arctan2(np.longdouble(1), np.longdouble(0))
    k = rng.integers(-int(limit / half_pi), int(limit / half_pi) + 1, N)
    nearest = (k * half_pi).astype(dtype)
    steps = rng.integers(-3, 4, N).astype(dtype)
    x = [
        rng.uniform(-4, 4, N),
        rng.uniform(-limit, limit, N),
        signs * 10.0 ** rng.uniform(np.log10(tiny), np.log10(limit), N),
        nearest + steps * np.spacing(nearest),
        np.array([0.0, -0.0, tiny, -tiny, np.finfo(dtype).smallest_subnormal]),
    ]
    x = np.concatenate([np.asarray(part, dtype) for part in x])
    return x[np.abs(x) < limit]


@pytest.mark.parametrize("dtype", DTYPES)
def test_sincos_within_2_ulp_away_from_zeros(dtype):
    """|error| <= 2 ulp + 2 |x| eps^2. The second term is the reduction's: x - k pi/2 is computed
    with pi/2 in three parts, whose sum misses pi/2 by about eps^2 relative (and, in float32, k times
    the third part is rounded at that scale): an absolute error of order |x| eps^2 that stays after the
    reduction. Near a zero of sin or cos it is the whole error, many ulps of the tiny result; away
    from the zeros it is far below one ulp, and the bound is 2 ulp."""
    w = wide(dtype)
    x = sincos_sweep(np.random.default_rng(20260502), dtype)
    s, c = _core._vector_sincos(x)
    assert s.dtype == c.dtype == dtype and s.shape == c.shape == x.shape
    eps = float(np.finfo(dtype).eps)
    allowance = 2 * np.abs(x.astype(w)) * eps**2
    for name, got, ref in (("sin", s, np.sin(x.astype(w))), ("cos", c, np.cos(x.astype(w)))):
        spacing = np.spacing(np.abs(ref.astype(dtype))).astype(w)
        excess = (np.abs(got.astype(w) - ref) - allowance) / spacing
        worst = int(np.argmax(excess))
        assert excess[worst] <= 2.0, f"{name}: {excess[worst]:.3f} ulp beyond 2|x|eps^2 at x={x[worst]!r}"
    assert (s[x == 0] == 0).all() and (c[x == 0] == 1).all()


def test_bad_arguments_raise():
    a = np.zeros(4)
    with pytest.raises(TypeError, match="y must be a numpy array"):
        _core._vector_atan2([0.0], a)
    with pytest.raises(TypeError, match="x must have dtype float64 or float32"):
        _core._vector_atan2(a, a.astype(np.int64))
    with pytest.raises(TypeError, match="x must have the dtype of y"):
        _core._vector_atan2(a, a.astype(np.float32))
    with pytest.raises(ValueError, match="x must have the length of y"):
        _core._vector_atan2(a, a[:3])
    with pytest.raises(ValueError, match="x must be 1-D"):
        _core._vector_sincos(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="x must be contiguous"):
        _core._vector_sincos(a[::2])
    empty = _core._vector_sincos(np.zeros(0, np.float32))
    assert all(part.dtype == np.float32 and part.shape == (0,) for part in empty)
