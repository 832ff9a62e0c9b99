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

from ._support.public import publish
from .kinematics.cartesian_paths import CartesianPath
from .kinematics.joint_paths import PROFILES, BranchPath, PointToPoint, hold_branch, point_to_point
from .kinematics.path_planning import linear, via_points

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

publish(__name__, globals(), __all__)
