"""Cartesian paths planned under speed and acceleration limits: :func:`~spotkin.trajectory.linear` and
:func:`~spotkin.trajectory.via_points` (each segment's duration and blend). Part of
:mod:`spotkin.trajectory` (documented there)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real
from .._support.transforms import quaternion_xyzw
from .cartesian_paths import _REPEAT_TOL, CartesianPath, _norm, _pose_matrices, _relative_rotations
from .joint_paths import _limit


def _limits(vmax, amax, wmax, alphamax) -> tuple[float, float, float, float]:
    if (wmax is None) != (alphamax is None):
        raise ValueError("wmax and alphamax go together: give both or neither")
    return (
        _limit(vmax, "vmax"),
        _limit(amax, "amax"),
        _limit(wmax, "wmax", optional=True),
        _limit(alphamax, "alphamax", optional=True),
    )


_BIG = 1e300  # caps and offsets of the rate maps stay below this: sums and squares never overflow
_PLAN_ROUNDS = 12  # chord rounds at most: each is feasible; about 8 reach the rounding level
_PLAN_TOL = 1e-12  # a round that speeds no segment up by more than this ends the refinement


def _min_affine_scan(cap: np.ndarray, slope: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """x_0 = cap_0, x_k = min(cap_k, slope_k x_{k-1} + offset_k), for slope >= 0, vectorised.

    x_k is (f_k o ... o f_1)(cap_0) with f(x) = min(c, s x + o). That form is closed under
    composition: g(f(x)) = min(min(c_g, s_g c_f + o_g), s_g s_f x + s_g o_f + o_g); so the
    prefix compositions take ceil(log2 n) doubling steps (Hillis-Steele). o is kept <= c
    (which changes no map) and s <= _BIG, so nothing overflows into a NaN.
    """
    c, s, o = cap.copy(), slope.copy(), offset.copy()
    s[0], o[0] = 0.0, c[0]  # f_0 is the constant cap_0
    step = 1
    with np.errstate(over="ignore"):
        while step < len(c):
            cg, sg, og = c[step:], s[step:], o[step:]
            cf, sf, of = c[:-step], s[:-step], o[:-step]
            c_new = np.minimum(cg, sg * cf + og)
            o_new = np.minimum(sg * of + og, c_new)
            s_new = np.minimum(sg * sf, _BIG)
            c[step:], o[step:], s[step:] = c_new, o_new, s_new
            step *= 2
    return np.minimum(c, o)


def _rate_bound(X: np.ndarray, k: np.ndarray, q: np.ndarray) -> np.ndarray:
    """h(X) = y^2, y = (k x + sqrt(k^2 X + 4 q)) / 2, x = sqrt(X): the largest y with y^2 - k x y <= q."""
    y = (k * np.sqrt(X) + np.sqrt(k * k * X + 4 * q)) / 2
    return y * y


def _chords(lo: np.ndarray, hi: np.ndarray, k: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Slope and offset of the chord of the concave h(X; k, q) over [lo, hi]: below h there."""
    h_lo, h_hi = _rate_bound(lo, k, q), _rate_bound(hi, k, q)
    span = hi - lo
    slope = np.divide(h_hi - h_lo, span, out=np.zeros_like(span), where=span > 0)
    slope = np.clip(slope, 0.0, _BIG)
    return slope, np.minimum(h_lo - slope * lo, _BIG)


def _greatest_rates(cap, fwd_k, fwd_q, bwd_k, bwd_q) -> np.ndarray:
    """The greatest X (squared segment rates, normalised) with X <= cap and, at every corner j,
    X_j <= h(X_{j-1}; fwd_k_j, fwd_q_j) and X_{j-1} <= h(X_j; bwd_k_j, bwd_q_j): see :func:`_plan`.

    A forward pass then a backward one solve it, each a min-affine scan. The maps h are concave,
    so each is replaced by its chord over [X_prev, cap] (below h there, and X stays in there):
    every round is feasible and at least as fast as the previous one.
    """
    if len(cap) == 1:  # one segment, no corner
        return cap
    X = np.zeros_like(cap)
    for _round in range(_PLAN_ROUNDS):
        slope, offset = _chords(X[:-1], cap[:-1], fwd_k, fwd_q)
        forward = _min_affine_scan(cap, np.concatenate([[0.0], slope]), np.concatenate([[0.0], offset]))
        slope, offset = _chords(X[1:], cap[1:], bwd_k, bwd_q)
        slope, offset = np.concatenate([[0.0], slope[::-1]]), np.concatenate([[0.0], offset[::-1]])
        rates = _min_affine_scan(forward[::-1], slope, offset)[::-1]
        rates = np.maximum(rates, X)  # never slower than the last feasible round (rounding)
        done = np.all(rates <= X * (1 + _PLAN_TOL))
        X = rates
        if done:
            break
    return X


def _segment_durations(
    dp: np.ndarray, phi: np.ndarray, d_min: np.ndarray, amax: float, alphamax: float, min_blend: float
) -> np.ndarray:
    """The segment durations d_k of the blended broken line: the derivation is in :func:`_plan`."""
    S = len(dp)

    def accel_time(u: np.ndarray, omega: np.ndarray) -> np.ndarray:  # N(u, omega)
        return np.maximum(_norm(u) / amax, _norm(omega) / alphamax)

    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # extremes: caught by _plan
        n, gamma = accel_time(dp, phi), accel_time(np.diff(dp, axis=0), np.diff(phi, axis=0))
        # in the time unit tau (the longest natural segment time), so that the values stay near 1
        tau = max(math.sqrt(float(n.max())), float(d_min.max()))
        n_, gamma_, d_min_ = n / tau / tau, gamma / tau / tau, d_min / tau
        cruise = 1 / d_min_**2
        cap = np.minimum(cruise, _BIG)
        cap[[0, -1]] = np.minimum(cap[[0, -1]], 1 / n_[[0, -1]])  # from and to rest
        corner = 1 / gamma_
        cap[:-1] = np.minimum(cap[:-1], corner)
        cap[1:] = np.minimum(cap[1:], corner)
        if min_blend > 0 and S > 1:
            cap = np.minimum(cap, np.float64(tau / min_blend) ** 2)
        maps = []
        for beta in (np.maximum(n[1:], gamma), np.maximum(n[:-1], gamma)):  # forward, backward
            k = 1 - np.divide(gamma, beta, out=np.zeros_like(gamma), where=beta > 0)
            maps += [k, np.minimum(1 / (beta / tau / tau), _BIG)]
        X = _greatest_rates(cap, *maps)
        d = tau / np.sqrt(X)
    return np.where(X >= cruise, d_min, d)  # exactly the cruise bound where it is the binding one


def _plan(
    poses: np.ndarray, vmax: float, amax: float, wmax: float, alphamax: float, min_blend: float
) -> CartesianPath:
    """Segment durations d_k and blend durations b_k for the blended broken line through the rigid
    transforms ``poses`` (W, 4, 4).

    With the twist (v_k, w_k) = (dp_k, phi_k) / d_k of segment k and the norm
    N(u, omega) = max(|u| / amax, |omega| / alphamax), blend j lasts
    b_j = max(N(twist_j - twist_{j-1}), min_blend), with a zero twist before the start and after
    the end (no min_blend there). The durations follow from four steps:

    1. Fit rule: b_j <= min(d_{j-1}, d_j) (a blend takes at most half of each adjacent segment)
       makes (b_k + b_{k+1}) / 2 <= d_k. For one segment (:func:`linear`) it is exact.
    2. In rates r = 1 / d, with a, b the (dp, phi) of segments j-1 and j, x = r_{j-1} <= y = r_j,
       gamma_j = N(b - a), beta_j = max(N(b), gamma_j): N(b y - a x) = N(b (y - x) + (b - a) x)
       <= beta (y - x) + gamma x, so the rule holds if beta y^2 - (beta - gamma) x y <= 1, i.e.
       y <= h_j(x), increasing, h_j(x) >= x while x^2 <= 1 / gamma_j. Likewise x <= h'_j(y) with
       max(N(a), gamma_j) when x >= y. Caps: r_k <= 1 / d_min_k (the cruise bound
       max(L_k / vmax, theta_k / wmax)), r^2 <= 1 / gamma_j next to a corner (equal rates,
       exact), r^2 <= 1 / N(dp, phi) on the first and last segments (from and to rest),
       r <= 1 / min_blend next to an interior waypoint.
    3. The constraints are increasing maps, so the feasible rates are closed under the
       elementwise max: there is a greatest (fastest) plan, and with h(x) >= x a forward pass
       X_k = min(cap_k, h_k(X_{k-1})) (X = r^2) then a backward one reach it.
    4. Each pass is a prefix composition of maps min(c, s X + o) (:func:`_min_affine_scan`).
       h_j is concave in X, so its chord over [X, cap] (X the previous round's feasible plan,
       0 at first) bounds it from below there: rounds of chords increase to the greatest plan,
       about two digits a round (:func:`_greatest_rates`). O(W log W), no Python loop over
       the waypoints.

    The blends are then b_j from the chosen d; segments not slowed keep d_k = d_min_k exactly.
    """
    quats = quaternion_xyzw(poses[:, :3, :3])
    positions = poses[:, :3, 3]
    phis, signed = _relative_rotations(quats)
    # drop repeats: a pose at the previous position within _REPEAT_TOL of its rotation
    repeat = (positions[1:] == positions[:-1]).all(axis=1) & (_norm(phis) <= _REPEAT_TOL)
    if repeat.any():
        keep = np.concatenate([[True], ~repeat])
        poses, positions = poses[keep], positions[keep]
        phis, signed = _relative_rotations(quats[keep])
    quats = signed
    with np.errstate(over="ignore", invalid="ignore"):
        dp = np.diff(positions, axis=0)
        lengths = _norm(dp)
    if not np.isfinite(lengths).all():
        raise ValueError("consecutive waypoints are too far apart: their distance overflows")
    angles = _norm(phis)
    if math.isinf(wmax) and np.any((lengths == 0) & (angles > 0)):
        raise ValueError("a pure rotation between waypoints needs finite wmax and alphamax")
    S = len(dp)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # extremes: checked below
        d = np.maximum(lengths / vmax, angles / wmax)
        if S:
            d = _segment_durations(dp, phis, d, amax, alphamax, min_blend)
        v = np.zeros((S + 2, 3))
        w = np.zeros((S + 2, 3))
        v[1:-1] = dp / d[:, None]
        w[1:-1] = phis / d[:, None]
        b = np.maximum(_norm(np.diff(v, axis=0)) / amax, _norm(np.diff(w, axis=0)) / alphamax)
        b[1:-1] = np.maximum(b[1:-1], min_blend)
        times = b[0] / 2 + np.concatenate([[0.0], np.cumsum(d)])
    if not (np.isfinite(times).all() and np.isfinite(b).all() and np.isfinite(v).all() and (d > 0).all()):
        raise ValueError("the waypoints and limits span too many orders of magnitude to plan in float64")
    return CartesianPath(poses, times, b, quats, v[1:-1], w[1:-1])


def linear(
    T0: ArrayLike,
    T1: ArrayLike,
    vmax: float,
    amax: float,
    wmax: float | None = None,
    alphamax: float | None = None,
) -> CartesianPath:
    """A straight-line Cartesian motion from pose T0 to T1, at rest at both ends.

    One trapezoidal s(t) in [0, 1] drives both p = p0 + s (p1 - p0) and the orientation by
    slerp, R = exp(s theta u) R0 (the shortest rotation, theta <= pi; an exact half turn is
    taken about the axis whose largest-magnitude component is positive). The limits on s are
    ds/dt <= min(vmax / L, wmax / theta) and |d2s/dt2| <= min(amax / L, alphamax / theta),
    so the speed, acceleration, angular rate and angular acceleration all stay within their
    limits and the tightest one is reached (triangular s(t) when the cruise is never reached).
    ``wmax``/``alphamax`` are optional (both are needed for a pure rotation).

    Poses as in :func:`via_points`; non-numeric or masked poses and bool/str/complex limits raise
    TypeError, wrong shapes and non-finite or non-positive limits ValueError.
    """
    vmax_, amax_, wmax_, alphamax_ = _limits(vmax, amax, wmax, alphamax)
    names = ("T0", "T1")
    given = [as_real(pose, name) for pose, name in zip((T0, T1), names)]
    dtypes = [arr.dtype for arr in given]
    ends = [arr.astype(np.float64, copy=False) for arr in given]
    for arr, name in zip(ends, names):
        if arr.shape not in ((4, 4), (7,), (6,)):
            raise ValueError(f"{name} must have shape (4, 4), (7,) or (6,), got {arr.shape}")
    if ends[0].shape == ends[1].shape:  # one checked conversion for both
        mats = _pose_matrices(np.stack(ends), names.__getitem__, dtypes)
    else:
        mats = np.concatenate(
            [_pose_matrices(a[None], lambda _, n=name: n, (d,)) for a, name, d in zip(ends, names, dtypes)]
        )
    return _plan(mats, vmax_, amax_, wmax_, alphamax_, 0.0)


def via_points(
    poses: ArrayLike,
    vmax: float,
    amax: float,
    wmax: float | None = None,
    alphamax: float | None = None,
    blend: float = 0.0,
) -> CartesianPath:
    """A broken line through the waypoints ``poses`` ((N, 4, 4), (N, 7) or (N, 6)), with
    parabolic blends, at rest at both ends.

    Each straight segment is run at constant velocity, as fast as vmax (and wmax) allow unless
    slowed down so that its blends fit, each blend taking at most half of each adjacent segment
    (the fastest such plan up to a triangle-inequality bound on the blends: see ``_plan``).
    Around each interior waypoint k a blend of duration
    b_k >= max(blend, |dv| / amax, |dw| / alphamax) changes the velocity at a constant rate,
    so the velocity is continuous and the acceleration stays within amax. The path passes
    *through* the first and last poses and *near* the interior ones: at the waypoint's time
    it is at P_k + (v_k - v_{k-1}) b_k / 8, and the whole blend stays within
    max(|v_{k-1}|, |v_k|) b_k / 2 of P_k. The angular acceleration in a blend is
    |dw| / b_k plus a gyroscopic term at most |w_{k-1}| |w_k| / 4 (so alphamax is
    exact on straight segments and when the rotation axes agree). A pose at the same position
    as the previous one and within 1e-12 rad of its rotation is a repeat and is dropped.
    Planning is O(N log N) (1e5 waypoints in well under a second).

    Non-numeric or masked poses and bool/str/complex limits raise TypeError; wrong shapes,
    non-finite poses and non-finite or negative limits ValueError.
    """
    arr = as_real(poses, "poses")
    dtype, arr = arr.dtype, arr.astype(np.float64, copy=False)
    if arr.ndim not in (2, 3) or arr.shape[0] < 2 or arr.shape[1:] not in ((4, 4), (7,), (6,)):
        raise ValueError(f"poses must have shape (N, 4, 4), (N, 7) or (N, 6) with N >= 2, got {arr.shape}")
    min_blend = _limit(blend, "blend", zero_ok=True)
    vmax_, amax_, wmax_, alphamax_ = _limits(vmax, amax, wmax, alphamax)
    mats = _pose_matrices(arr, lambda i: f"poses[{i}]", (dtype,))
    return _plan(mats, vmax_, amax_, wmax_, alphamax_, min_blend)
