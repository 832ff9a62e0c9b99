"""Trajectory generation: synchronised joint motions and Cartesian paths, sampled in batches.

Point to point (joint space)
----------------------------
``point_to_point(q0, qf, vmax, amax, profile)`` moves every axis j by
D_j = qf_j - q0_j from rest to rest with |qd_j| <= vmax_j and |qdd_j| <= amax_j
(``vmax``/``amax`` scalars or (n,) arrays, > 0). Per-axis minimum durations:

- ``"cubic"``: q = q0 + D s(tau), s = 3 tau^2 - 2 tau^3, tau = t / t_f. The speed peaks at
  tau = 1/2 (s' = 3/2), the acceleration at both ends (|s''| = 6), so
  t_f = max(3 |D| / (2 vmax), sqrt(6 |D| / amax)).
- ``"quintic"``: s = 10 tau^3 - 15 tau^4 + 6 tau^5 (zero velocity and acceleration at both
  ends). Peak s' = 15/8 at tau = 1/2, peak |s''| = 10 / sqrt(3) at tau = 1/2 -+ sqrt(3)/6:
  t_f = max(15 |D| / (8 vmax), sqrt(10 |D| / (sqrt(3) amax))).
- ``"trapezoid"`` (bang-coast-bang): accelerate at amax for t_a = v / amax, cruise at v,
  decelerate; |D| = v (t_f - t_a). With v = vmax, t_f = |D| / vmax + vmax / amax, valid when
  |D| >= vmax^2 / amax; otherwise the profile is triangular, t_f = 2 sqrt(|D| / amax), and
  the peak speed sqrt(|D| amax) stays below vmax.

Synchronisation: ``duration`` t_f is the largest per-axis minimum duration (the slowest
axis reaches its active limit); every other axis is stretched to end at t_f too. The
polynomial profiles share s(t / t_f), so the joint path is a straight line. A stretched
trapezoid axis keeps its acceleration amax_j and cruises at the smaller root
v_j = 2 amax_j |D_j| / (amax_j t_f + sqrt(amax_j^2 t_f^2 - 4 amax_j |D_j|)).

Cartesian paths
---------------
``linear(T0, T1, ...)`` moves the position along the straight segment and the orientation by
slerp, both driven by one trapezoidal s(t) in [0, 1] whose limits are the tightest of
vmax / L, amax / L (L the distance) and wmax / theta, alphamax / theta (theta the rotation
angle). ``via_points(poses, ...)`` joins straight segments with parabolic blends: see
:func:`via_points`. Poses are accepted in the forms of :meth:`spotkin.Spot.body_ik`:
(4, 4), (7,) [x, y, z, qx, qy, qz, qw] or (6,) [x, y, z, Euler XYZ].

Sampling
--------
``sample(t)`` takes times of any shape (...) and any real dtype (float32 stays float32,
everything else runs in float64) and evaluates them in C++ with the GIL released. Times
before 0 or after ``duration`` give the end states at rest (zero derivatives); at exactly 0
and ``duration`` the profile's own values (the cubic and trapezoid accelerations are nonzero
there: they jump from rest). A NaN time gives a row of NaN.

Both kinds of trajectory pickle and (deep-)copy. Non-numeric input (str, bytes, object,
complex) and masked arrays raise TypeError naming the argument; wrong shapes, non-finite
poses and limits, and plans that overflow float64 raise ValueError.
"""

from __future__ import annotations

import math
import numbers
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from ._support.boundary import as_index, as_real, quiet_float_errors, rotation_tolerance
from ._support.transforms import quaternion_xyzw
from .model.body import unchecked_transform

__all__ = [
    "PROFILES",
    "BranchPath",
    "CartesianPath",
    "PointToPoint",
    "hold_branch",
    "linear",
    "point_to_point",
    "via_points",
]

PROFILES = ("cubic", "quintic", "trapezoid")
_FORMS = {"matrix": 0, "quaternion": 1}
_HALF_TURN_TOL = 1e-12
_REPEAT_TOL = 1e-12  # rad: a waypoint at the previous position and within this rotation of it is a repeat


def _choice(value, name: str, choices) -> str:
    """A string option: TypeError for a non-string, ValueError for an unknown one."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, one of {tuple(choices)}, got {type(value).__name__}")
    if value not in choices:
        raise ValueError(f"{name} must be one of {tuple(choices)}, got {value!r}")
    return value


def _flag(value, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a bool, got {type(value).__name__}")
    return bool(value)


def _no_bool(value: ArrayLike, name: str) -> None:
    """TypeError for a bool limit, which the C++ boundary takes as a number (a speed is not a truth value)."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a real number or array, got a bool")
    if isinstance(value, (int, float)):
        return
    try:
        kind = np.asarray(value).dtype.kind
    except (TypeError, ValueError):  # not an array at all: the C++ boundary names it
        return
    if kind == "b":
        raise TypeError(f"{name} must be a real number or array, got a bool array")


# where |qd| and |qdd| peak, in tau = t / t_f: the ends, 1/2 -+ sqrt(3)/6 (quintic), 1/2
_PEAK_TAU = np.array([0.0, 0.5 - math.sqrt(3) / 6, 0.5, 0.5 + math.sqrt(3) / 6, 1.0])


class PointToPoint:
    """A synchronised rest-to-rest joint trajectory; build it with :func:`point_to_point`.

    Attributes: ``q0``, ``qf`` (n,), ``vmax``, ``amax`` (n,), ``profile``, ``duration`` t_f,
    ``axis_durations`` (n,) (each axis's own minimum time; t_f is their maximum), and for the
    trapezoid the signed ``acceleration``, ``cruise_velocity`` and ``ramp_time`` per axis.
    Pickles and copies (it is rebuilt from q0, qf, vmax, amax and the profile).
    """

    def __init__(self, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, profile: str):
        _choice(profile, "profile", PROFILES)
        _no_bool(vmax, "vmax")
        _no_bool(amax, "amax")
        self._core = _core.PointToPoint(q0, qf, vmax, amax, PROFILES.index(profile))
        self.profile = profile
        self.q0 = np.array(q0, dtype=np.float64)
        self.qf = np.array(qf, dtype=np.float64)
        n = self.q0.shape[0]
        self.vmax = np.broadcast_to(np.asarray(vmax, dtype=np.float64), (n,)).copy()
        self.amax = np.broadcast_to(np.asarray(amax, dtype=np.float64), (n,)).copy()
        self.duration: float = self._core.duration
        self.axis_durations: np.ndarray = self._core.axis_durations
        self.acceleration: np.ndarray = self._core.acceleration
        self.cruise_velocity: np.ndarray = self._core.cruise_velocity
        self.ramp_time: np.ndarray = self._core.ramp_time
        self._check_range()

    def _check_range(self) -> None:
        """The plan must be representable: a span qf - q0, a duration and peak rates that overflow (or a
        duration that underflows to 0 for a real move) would sample as NaN or jump."""
        with np.errstate(over="ignore", invalid="ignore"):
            span = self.qf - self.q0
        if not np.isfinite(span).all():
            raise ValueError("qf - q0 overflows: the span of the motion is not a finite float")
        moving = bool((span != 0).any())
        if not math.isfinite(self.duration) or (moving and not self.duration > 0):
            raise ValueError(
                f"the motion's duration is not representable ({self.duration}): span and limits too far apart"
            )
        if not moving:
            return
        # the rates peak at _PEAK_TAU and at the trapezoid's ramp ends: overflow shows there
        T = self.duration
        t = np.concatenate([T * _PEAK_TAU, self.ramp_time, T - self.ramp_time])
        q, qd, qdd = self._core.sample(t)
        plan = (self.acceleration, self.cruise_velocity, self.ramp_time, q.ravel(), qd.ravel(), qdd.ravel())
        # a trapezoid axis that moves but neither accelerates nor cruises lost its speed to an overflow
        stalled = self.profile == "trapezoid" and bool(
            ((span != 0) & ((self.acceleration == 0) | (self.cruise_velocity == 0))).any()
        )
        if stalled or not np.isfinite(np.concatenate(plan)).all():
            raise ValueError("the motion's velocity or acceleration overflows: span and limits too far apart")

    def sample(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (..., n), at times t (...). At rest outside [0, duration]; NaN t -> NaN rows."""
        return self._core.sample(t)

    def __reduce__(self):
        return (PointToPoint, (self.q0, self.qf, self.vmax, self.amax, self.profile))

    def __repr__(self) -> str:
        axes = self.q0.shape[0]
        return f"PointToPoint(profile={self.profile!r}, axes={axes}, duration={self.duration:.6g})"


def point_to_point(
    q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, profile: str = "quintic"
) -> PointToPoint:
    """A synchronised rest-to-rest motion from q0 to qf (n,): see the module docstring for the profiles.

    Raises ValueError for limits that are not positive and finite, NaN/inf positions, mismatched
    shapes, or a motion whose span, duration or peak rates overflow (e.g. q0 = -1e308, qf = 1e308);
    TypeError for non-numeric input and bool limits. qf == q0 gives a zero-length trajectory
    (duration 0).
    """
    return PointToPoint(q0, qf, vmax, amax, profile)


# ---- Cartesian paths ---------------------------------------------------------------------------


def _pose_matrices(poses: np.ndarray, name, dtypes=(np.float64,)) -> np.ndarray:
    """Checked rigid transforms (N, 4, 4) of N poses (N, 4, 4), (N, 7) or (N, 6) (float64, shape
    already checked); ``name(i)`` names pose i in the errors. ``dtypes``, one or one per pose, is the
    dtype each was given in: a float32 rotation is checked to float32 precision
    (:func:`rotation_tolerance`) and then replaced by the nearest rotation."""
    flat = poses.reshape(len(poses), -1)
    bad = np.flatnonzero(~np.isfinite(flat).all(axis=1))
    if bad.size:
        raise ValueError(f"{name(bad[0])} must be finite (no NaN or inf)")
    if poses.shape[1:] == (7,):
        scale = np.abs(poses[:, 3:]).max(axis=1)
        bad = np.flatnonzero(~(scale > 0))
        if bad.size:
            raise ValueError(f"{name(bad[0])} has a zero quaternion")
        # |q| in [1, 2] after scaling: s = 2 / |q|^2 neither overflows nor underflows
        poses = np.concatenate([poses[:, :3], poses[:, 3:] / scale[:, None]], axis=1)
    T = unchecked_transform(poses)  # checked here: quaternions are normalised above
    if poses.shape[1:] == (4, 4):
        R = T[:, :3, :3]
        tolerance = np.broadcast_to([rotation_tolerance(dtype) for dtype in dtypes], len(R))
        with np.errstate(over="ignore", invalid="ignore"):  # huge entries: not orthonormal
            gram_error = np.abs(np.einsum("nki,nkj->nij", R, R) - np.eye(3))
            # np.allclose(atol=tolerance): 1e-9 in float64
            orthonormal = (gram_error <= tolerance[:, None, None] + 1e-5 * np.eye(3)).all(axis=(1, 2))
            det = np.einsum("ni,ni->n", R[:, 0], np.cross(R[:, 1], R[:, 2]))
        rigid = orthonormal & (det > 0) & (poses[:, 3] == [0.0, 0.0, 0.0, 1.0]).all(axis=1)
        bad = np.flatnonzero(~rigid)
        if bad.size:
            raise ValueError(
                f"{name(bad[0])} must be a rigid transform (orthonormal rotation, last row [0, 0, 0, 1])"
            )
        rounded = tolerance > 1e-9
        if rounded.any():  # float32 rotations: the nearest rotation, without the float32 rounding
            U, _, Vt = np.linalg.svd(R[rounded])
            T[rounded, :3, :3] = U @ Vt
    return T


def _norm(u: np.ndarray) -> np.ndarray:
    """|u| of 3-vectors along the last axis, without overflow (hypot) for huge components."""
    return np.hypot(np.hypot(u[..., 0], u[..., 1]), u[..., 2])


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products of quaternions [x, y, z, w] along the last axis."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def _relative_rotations(quats: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World rotation vectors phi_k with R_{k+1} = exp(phi_k) R_k, each the shortest way, and the
    quaternions re-signed along the chain so that q_{k+1} = exp(phi_k) * q_k.

    The relative quaternion r_k = q_{k+1} q_k^-1 is taken with w >= 0; a half turn (|w| <= 1e-12)
    is ambiguous and is taken about the axis whose largest-magnitude component is positive. Flipping
    r_k flips q_{k+1}, and so every later quaternion: the signs are a cumulative product.
    """
    r = _quat_mul(quats[1:], quats[:-1] * [-1.0, -1.0, -1.0, 1.0])
    v, w = r[:, :3], r[:, 3]
    lead = v[np.arange(len(v)), np.argmax(np.abs(v), axis=1)]
    flip = np.where(np.abs(w) <= _HALF_TURN_TOL, lead < 0, w < 0)
    sign = np.where(flip, -1.0, 1.0)
    v, w = v * sign[:, None], w * sign
    s = np.linalg.norm(v, axis=1)
    scale = np.divide(2 * np.arctan2(s, w), s, out=np.zeros_like(s), where=s > 0)
    signs = np.concatenate([[1.0], np.cumprod(sign)])
    return v * scale[:, None], quats * signs[:, None]


class CartesianPath:
    """A Cartesian path through waypoints; build it with :func:`linear` or :func:`via_points`.

    The path passes waypoint k (position P_k, rotation R_k) at time ``times[k]``; between
    blends it moves at constant linear velocity ``linear_velocity[k]`` and constant world
    angular velocity ``angular_velocity[k]``: p = P_k + v_k (t - t_k), R = exp(w_k (t - t_k)) R_k.
    Around waypoint k a blend of duration ``blends[k]`` centred on t_k changes the velocity at
    a constant rate from (v_{k-1}, w_{k-1}) to (v_k, w_k) (zero outside the path):
    with u = t - t_k + b_k / 2, f2 = u^2 / (2 b_k), f1 = t - t_k - f2,
    p = P_k + v_{k-1} f1 + v_k f2 and R = exp(w_{k-1} f1) exp(w_k f2) R_k.
    The path starts exactly at the first pose and stops exactly at the last; interior
    waypoints are passed near, not through (see :func:`via_points`). Pickles and copies.
    """

    def __init__(
        self,
        waypoints: np.ndarray,
        times: np.ndarray,
        blends: np.ndarray,
        quaternions: np.ndarray,
        linear_velocity: np.ndarray,
        angular_velocity: np.ndarray,
    ):
        # the plan's arrays, as linear / via_points build them; checked, since the class is public
        waypoints = as_real(waypoints, "waypoints", np.float64)
        if waypoints.ndim != 3 or waypoints.shape[1:] != (4, 4) or len(waypoints) < 1:
            raise ValueError(f"waypoints must have shape (K, 4, 4) with K >= 1, got {waypoints.shape}")
        count = len(waypoints)
        arrays = {}
        for name, value, shape in (
            ("times", times, (count,)),
            ("blends", blends, (count,)),
            ("quaternions", quaternions, (count, 4)),
            ("linear_velocity", linear_velocity, (count - 1, 3)),
            ("angular_velocity", angular_velocity, (count - 1, 3)),
        ):
            array = as_real(value, name, np.float64)
            if array.shape != shape:
                raise ValueError(f"{name} must have shape {shape} for {count} waypoints, got {array.shape}")
            arrays[name] = array
        times, blends, quaternions = arrays["times"], arrays["blends"], arrays["quaternions"]
        linear_velocity, angular_velocity = arrays["linear_velocity"], arrays["angular_velocity"]
        self.waypoints = waypoints
        self.times = times
        self.blends = blends
        self.linear_velocity = linear_velocity
        self.angular_velocity = angular_velocity
        self._quaternions = quaternions
        self._core = _core.WaypointPath(
            times, blends, waypoints[:, :3, 3].copy(), quaternions, linear_velocity, angular_velocity
        )
        self.duration: float = self._core.duration

    def sample(self, t: ArrayLike, form: str = "matrix", twist: bool = False):
        """Poses at times t (...): ``form="matrix"`` (..., 4, 4) or ``"quaternion"`` (..., 7)
        [x, y, z, qx, qy, qz, qw], both accepted by :meth:`spotkin.Spot.body_ik`.

        With ``twist=True`` returns (poses, twist), twist (..., 6) = [v; w], the linear velocity
        and the angular velocity, both in the world frame. Times are clamped to
        [0, duration] (zero twist outside); a NaN time gives NaN. A non-string ``form`` or a
        non-bool ``twist`` raises TypeError, an unknown ``form`` ValueError.
        """
        code = _FORMS[_choice(form, "form", _FORMS)]
        return self._core.sample(t, code, _flag(twist, "twist"))

    def __reduce__(self):
        arrays = (self.times, self.blends, self._quaternions, self.linear_velocity, self.angular_velocity)
        return (CartesianPath, (self.waypoints, *arrays))

    def __repr__(self) -> str:
        return f"CartesianPath(waypoints={len(self.times)}, duration={self.duration:.6g})"


def _limit(value, name: str, *, optional: bool = False, zero_ok: bool = False) -> float:
    """A scalar limit: TypeError unless a real number (bool, str, complex are not), ValueError
    unless finite and positive (or zero, where ``zero_ok``); None means "no limit" where ``optional``."""
    if value is None and optional:
        return math.inf
    if isinstance(value, (bool, np.bool_, str, bytes, complex)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    if not isinstance(value, numbers.Real):  # an array, a list, None...
        array = as_real(value, name)
        if array.shape != ():
            raise ValueError(f"{name} must be a scalar, got shape {array.shape}")
        if np.asarray(value).dtype.kind == "b":
            raise TypeError(f"{name} must be a real number, got a bool")
        value = array[()]
    try:
        v = float(value)
    except OverflowError:  # an int beyond the float range
        v = math.inf
    if not (math.isfinite(v) and (v > 0 or (zero_ok and v == 0))):
        bound = ">= 0" if zero_ok else "positive"
        raise ValueError(f"{name} must be {bound} and finite, got {v}")
    return v


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


class BranchPath(NamedTuple):
    """One IK branch held along a sampled path, from :func:`hold_branch`."""

    q: np.ndarray
    """(K, n) the held slot's joint values; NaN where the branch does not exist or is invalid."""
    ok: np.ndarray
    """(K,) bool: the branch is valid at this sample and reached continuously from the previous one."""
    jumps: np.ndarray
    """(J,) indices k where the branch is discontinuous between samples k - 1 and k (a joint moves
    more than ``max_step``), appears or disappears: never taken silently."""
    max_step: np.ndarray
    """(K,) the largest joint move from the previous sample (0 at k = 0; revolute moves wrapped)."""


@quiet_float_errors
def hold_branch(q_slots: ArrayLike, valid: ArrayLike, branch: int, max_step: float = 0.2) -> BranchPath:
    """Hold IK slot ``branch`` along a path and report every jump.

    ``q_slots`` (K, S, n) and ``valid`` (K, S) are the ``q`` and ``valid`` (or ``exists``) of an
    ``ik_all``-style result over K consecutive path samples: :meth:`Leg.ik_all`, :meth:`SpotArm.ik_all`
    (slots with a fixed branch meaning). :meth:`Chain.ik` and :meth:`Chain.ik_position` sort their
    slots by joint value, so a slot there is not a branch: hold one only where the sort order is
    stable. A jump is a sample where the branch vanishes or reappears, or where a joint moves by more
    than ``max_step`` (rad or length units; revolute moves measured on the circle) from the previous
    sample: typically a singularity crossing (the wrist flipping, the elbow stretching), where the
    solver's slots swap meaning. Sample the path finely enough that real motion stays below
    ``max_step``. Vectorised over the path.

    Non-numeric or masked arrays and a non-integer ``branch`` (1.5, True) raise TypeError; wrong
    shapes, a branch out of range and a NaN, infinite or non-positive ``max_step`` ValueError.
    """
    q = as_real(q_slots, "q_slots", np.float64)
    if q.ndim != 3:
        raise ValueError(f"q_slots must have shape (K, S, n), got {q.shape}")
    flags = as_real(valid, "valid")
    if flags.shape != q.shape[:2]:
        raise ValueError(f"valid must have shape (K, S) = {q.shape[:2]} (that of q_slots), got {flags.shape}")
    if not np.isin(flags, (0, 1)).all():
        raise ValueError("valid must hold booleans (or 0 and 1)")
    ok_slot = flags.astype(bool)
    branch = as_index(branch, "branch")
    if not 0 <= branch < q.shape[1]:
        raise ValueError(f"branch must be a slot index in [0, {q.shape[1]}), got {branch}")
    max_step = _limit(max_step, "max_step")
    held = np.where(ok_slot[:, branch, None], q[:, branch], np.nan)
    step = np.zeros(len(held))
    if len(held) > 1:
        delta = np.diff(held, axis=0)
        wrapped = np.abs(np.mod(delta + np.pi, 2 * np.pi) - np.pi)  # revolute joints: on the circle
        step[1:] = np.max(np.minimum(wrapped, np.abs(delta)), axis=-1, initial=0.0)
    present = ok_slot[:, branch]
    jump = np.zeros(len(held), dtype=bool)
    jump[1:] = (present[1:] != present[:-1]) | (present[1:] & present[:-1] & ~(step[1:] <= max_step))
    ok = present & ~jump
    if len(ok) > 1:  # after a jump the branch is no longer the one chosen: not ok until the end
        ok &= np.cumsum(jump) == 0
    return BranchPath(held, ok, np.nonzero(jump)[0], step)
