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
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from . import _core
from .body import body_transform

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
_REPEAT_TOL = 1e-12  # rad: a waypoint at the same position and within this rotation is a repeat


class PointToPoint:
    """A synchronised rest-to-rest joint trajectory; build it with :func:`point_to_point`.

    Attributes: ``q0``, ``qf`` (n,), ``vmax``, ``amax`` (n,), ``profile``, ``duration`` t_f,
    ``axis_durations`` (n,) (each axis's own minimum time; t_f is their maximum), and for the
    trapezoid the signed ``acceleration``, ``cruise_velocity`` and ``ramp_time`` per axis.
    """

    def __init__(self, q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, profile: str):
        if profile not in PROFILES:
            raise ValueError(f"profile must be one of {PROFILES}, got {profile!r}")
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

    def sample(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (..., n), at times t (...). At rest outside [0, duration]; NaN t -> NaN rows."""
        return self._core.sample(t)

    def __repr__(self) -> str:
        axes = self.q0.shape[0]
        return f"PointToPoint(profile={self.profile!r}, axes={axes}, duration={self.duration:.6g})"


def point_to_point(
    q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, amax: ArrayLike, profile: str = "quintic"
) -> PointToPoint:
    """A synchronised rest-to-rest motion from q0 to qf (n,): see the module docstring for the profiles.

    Raises ValueError for limits that are not positive and finite, NaN/inf positions, or
    mismatched shapes. qf == q0 gives a zero-length trajectory (duration 0).
    """
    return PointToPoint(q0, qf, vmax, amax, profile)


# ---- Cartesian paths ---------------------------------------------------------------------------


def _pose_matrix(pose: ArrayLike, name: str) -> np.ndarray:
    arr = np.asarray(pose, dtype=np.float64)
    if arr.shape not in ((4, 4), (7,), (6,)):
        raise ValueError(f"{name} must have shape (4, 4), (7,) or (6,), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    T = body_transform(arr)
    R = T[:3, :3]
    if arr.shape == (4, 4) and (
        not np.allclose(R.T @ R, np.eye(3), atol=1e-9)
        or np.linalg.det(R) < 0
        or not np.array_equal(arr[3], [0.0, 0.0, 0.0, 1.0])
    ):
        raise ValueError(f"{name} must be a rigid transform (orthonormal rotation, last row [0, 0, 0, 1])")
    if arr.shape == (7,) and not np.linalg.norm(arr[3:]) > 0:
        raise ValueError(f"{name} has a zero quaternion")
    return T


def _quaternion(R: np.ndarray) -> np.ndarray:
    """[x, y, z, w] of a rotation matrix (Shepperd: the largest of w, x, y, z first)."""
    tr = np.trace(R)
    i = int(np.argmax([R[0, 0], R[1, 1], R[2, 2], tr]))
    if i == 3:
        w = math.sqrt(1.0 + tr) / 2
        q = [(R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w), w]
    else:
        j, k = (i + 1) % 3, (i + 2) % 3
        r = math.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k]) / 2
        q = [0.0, 0.0, 0.0, (R[k, j] - R[j, k]) / (4 * r)]
        q[i], q[j], q[k] = r, (R[j, i] + R[i, j]) / (4 * r), (R[k, i] + R[i, k]) / (4 * r)
    q = np.array(q)
    return q / np.linalg.norm(q)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    (ax, ay, az, aw), (bx, by, bz, bw) = a, b
    return np.array(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ]
    )


def _relative_rotation(q_from: np.ndarray, q_to: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The world rotation vector phi with R_to = exp(phi) R_from, the shortest way, and q_to
    re-signed so that q_to = exp(phi) * q_from.

    A half turn (|w| of the relative quaternion <= 1e-12) is ambiguous; it is taken about the
    axis whose largest-magnitude component is positive.
    """
    r = _quat_mul(q_to, q_from * [-1, -1, -1, 1])
    flip = r[3] < 0
    if abs(r[3]) <= _HALF_TURN_TOL:
        v = r[:3]
        flip = v[np.argmax(np.abs(v))] < 0
    if flip:
        r, q_to = -r, -q_to
    s = np.linalg.norm(r[:3])
    phi = np.zeros(3) if s == 0 else 2 * math.atan2(s, r[3]) * r[:3] / s
    return phi, q_to


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
    waypoints are passed near, not through (see :func:`via_points`).
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
        self.waypoints = waypoints
        self.times = times
        self.blends = blends
        self.linear_velocity = linear_velocity
        self.angular_velocity = angular_velocity
        self._core = _core.WaypointPath(
            times, blends, waypoints[:, :3, 3].copy(), quaternions, linear_velocity, angular_velocity
        )
        self.duration: float = self._core.duration

    def sample(self, t: ArrayLike, form: str = "matrix", twist: bool = False):
        """Poses at times t (...): ``form="matrix"`` (..., 4, 4) or ``"quaternion"`` (..., 7)
        [x, y, z, qx, qy, qz, qw], both accepted by :meth:`spotkin.Spot.body_ik`.

        With ``twist=True`` returns (poses, twist), twist (..., 6) = [v; w], the linear velocity
        and the angular velocity, both in the world frame. Times are clamped to
        [0, duration] (zero twist outside); a NaN time gives NaN.
        """
        if form not in _FORMS:
            raise ValueError(f"form must be 'matrix' or 'quaternion', got {form!r}")
        return self._core.sample(t, _FORMS[form], bool(twist))

    def __repr__(self) -> str:
        return f"CartesianPath(waypoints={len(self.times)}, duration={self.duration:.6g})"


def _positive(value: float | None, name: str, optional: bool = False) -> float:
    if value is None and optional:
        return math.inf
    v = float(value)  # type: ignore[arg-type]
    if not (v > 0 and math.isfinite(v)):
        raise ValueError(f"{name} must be positive and finite, got {value}")
    return v


def _limits(vmax, amax, wmax, alphamax) -> tuple[float, float, float, float]:
    if (wmax is None) != (alphamax is None):
        raise ValueError("wmax and alphamax go together: give both or neither")
    return (
        _positive(vmax, "vmax"),
        _positive(amax, "amax"),
        _positive(wmax, "wmax", optional=True),
        _positive(alphamax, "alphamax", optional=True),
    )


def _plan(
    poses: list[np.ndarray], vmax: float, amax: float, wmax: float, alphamax: float, min_blend: float
) -> CartesianPath:
    """Segment durations d_k and blend durations b_k for the blended broken line.

    d_k starts at the cruise bound max(L_k / vmax, theta_k / wmax); b_k is the shortest blend
    that changes the velocity within the acceleration limits,
    max(|v_k - v_{k-1}| / amax, |w_k - w_{k-1}| / alphamax, min_blend for interior waypoints).
    A segment too short for its two half blends, (b_k + b_{k+1}) / 2 > d_k, is slowed down
    (d_k raised by bisection until they fit), and the sweep repeats until every segment fits.
    """
    quats = [_quaternion(poses[0][:3, :3])]
    kept = [poses[0]]
    rotvecs = []
    for T in poses[1:]:
        phi, q = _relative_rotation(quats[-1], _quaternion(T[:3, :3]))
        if np.array_equal(T[:3, 3], kept[-1][:3, 3]) and np.linalg.norm(phi) <= _REPEAT_TOL:
            continue  # a repeated waypoint
        kept.append(T)
        quats.append(q)
        rotvecs.append(phi)
    P = np.array([T[:3, 3] for T in kept])
    dp = np.diff(P, axis=0)
    phis = np.array(rotvecs).reshape(-1, 3)
    lengths = np.linalg.norm(dp, axis=1)
    angles = np.linalg.norm(phis, axis=1)
    if np.any((lengths == 0) & (angles > 0) & math.isinf(wmax)):
        raise ValueError("a pure rotation between waypoints needs finite wmax and alphamax")
    d = np.maximum(lengths / vmax, angles / wmax)
    W = len(kept)

    def blends_for(d: np.ndarray) -> np.ndarray:
        v = np.zeros((W + 1, 3))
        w = np.zeros((W + 1, 3))
        v[1:W] = dp / d[:, None]
        w[1:W] = phis / d[:, None]
        b = np.maximum(
            np.linalg.norm(np.diff(v, axis=0), axis=1) / amax,
            np.linalg.norm(np.diff(w, axis=0), axis=1) / alphamax,
        )
        b[1:-1] = np.maximum(b[1:-1], min_blend)
        return b

    for _sweep in range(1000):
        b = blends_for(d)
        excess = (b[:-1] + b[1:]) / 2 - d
        bad = np.flatnonzero(excess > 1e-15 * np.maximum(d, 1.0))
        if bad.size == 0:
            break
        k = int(bad[0])
        lo, hi = d[k], max(2 * d[k], 1e-300)

        def fits(dk: float, k: int = k) -> bool:
            trial = d.copy()
            trial[k] = dk
            bb = blends_for(trial)
            return (bb[k] + bb[k + 1]) / 2 <= dk

        while not fits(hi):
            hi *= 2
        for _ in range(200):
            mid = (lo + hi) / 2
            if mid in (lo, hi):
                break
            lo, hi = (lo, mid) if fits(mid) else (mid, hi)
        d[k] = hi
    else:  # pragma: no cover - the sweep converges: d only grows and large d always fits
        raise RuntimeError("via_points: blend planning did not converge")
    b = blends_for(d)
    times = b[0] / 2 + np.concatenate([[0.0], np.cumsum(d)])
    return CartesianPath(
        np.array(kept),
        times,
        b,
        np.array(quats),
        (dp / d[:, None]).reshape(-1, 3),
        (phis / d[:, None]).reshape(-1, 3),
    )


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
    """
    vmax_, amax_, wmax_, alphamax_ = _limits(vmax, amax, wmax, alphamax)
    return _plan([_pose_matrix(T0, "T0"), _pose_matrix(T1, "T1")], vmax_, amax_, wmax_, alphamax_, 0.0)


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
    slowed down so that its blends fit. Around each interior waypoint k a blend of duration
    b_k >= max(blend, |dv| / amax, |dw| / alphamax) changes the velocity at a constant rate,
    so the velocity is continuous and the acceleration stays within amax. The path passes
    *through* the first and last poses and *near* the interior ones: at the waypoint's time
    it is at P_k + (v_k - v_{k-1}) b_k / 8, and the whole blend stays within
    max(|v_{k-1}|, |v_k|) b_k / 2 of P_k. The angular acceleration in a blend is
    |dw| / b_k plus a gyroscopic term at most |w_{k-1}| |w_k| / 4 (so alphamax is
    exact on straight segments and when the rotation axes agree). Repeated consecutive
    poses (same position, rotation within 1e-12 rad) are dropped.
    """
    arr = np.asarray(poses, dtype=np.float64)
    if arr.ndim not in (2, 3) or arr.shape[0] < 2 or arr.shape[1:] not in ((4, 4), (7,), (6,)):
        raise ValueError(f"poses must have shape (N, 4, 4), (N, 7) or (N, 6) with N >= 2, got {arr.shape}")
    if not (math.isfinite(blend) and blend >= 0):
        raise ValueError(f"blend must be >= 0 and finite, got {blend}")
    vmax_, amax_, wmax_, alphamax_ = _limits(vmax, amax, wmax, alphamax)
    mats = [_pose_matrix(p, f"poses[{i}]") for i, p in enumerate(arr)]
    return _plan(mats, vmax_, amax_, wmax_, alphamax_, float(blend))


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
    """
    q = np.asarray(q_slots, dtype=np.float64)
    ok_slot = np.asarray(valid, dtype=bool)
    if q.ndim != 3 or ok_slot.shape != q.shape[:2]:
        raise ValueError(f"q_slots must be (K, S, n) and valid (K, S), got {q.shape} and {ok_slot.shape}")
    if not 0 <= branch < q.shape[1]:
        raise ValueError(f"branch must be a slot index in [0, {q.shape[1]}), got {branch}")
    if not (np.isfinite(max_step) and max_step > 0):
        raise ValueError(f"max_step must be positive and finite, got {max_step}")
    held = np.where(ok_slot[:, branch, None], q[:, branch], np.nan)
    step = np.zeros(len(held))
    if len(held) > 1:
        delta = np.diff(held, axis=0)
        wrapped = np.abs(np.mod(delta + np.pi, 2 * np.pi) - np.pi)  # revolute joints: on the circle
        step[1:] = np.max(np.minimum(wrapped, np.abs(delta)), axis=-1)
    present = ok_slot[:, branch]
    jump = np.zeros(len(held), dtype=bool)
    jump[1:] = (present[1:] != present[:-1]) | (present[1:] & present[:-1] & ~(step[1:] <= max_step))
    ok = present & ~jump
    if len(ok) > 1:  # after a jump the branch is no longer the one chosen: not ok until the end
        ok &= np.cumsum(jump) == 0
    return BranchPath(held, ok, np.nonzero(jump)[0], step)
