"""Paul's standard trigonometric equations (types 2, 3 and 6 of Paul's method), batched.

Every function broadcasts its inputs like NumPy and returns every root with a
validity mask; invalid roots are NaN, and a root marked valid is never NaN (Inf or
NaN coefficients give no valid root). Angles are in (-pi, pi], computed in float64.
Coefficients must be real numbers or arrays (``TypeError`` otherwise, naming the
coefficient); shapes that do not broadcast raise ``ValueError`` naming them all.

- :func:`type2` ``X sin t + Y cos t = Z``: two roots (eps = +1, -1 in
  cos t = (Y Z - eps X S) / r^2, sin t = (X Z + eps Y S) / r^2, S = sqrt(r^2 - Z^2),
  r^2 = X^2 + Y^2). No root when r^2 < Z^2: no real solution (the course this library
  follows calls this case "singular"; see docs/course-errata.md). X = Y = 0: no root
  unless Z = 0, where every t solves it and t = 0 is reported.
- :func:`type3` the 2x2 linear system in (sin t, cos t): one root.
- :func:`type6` the coupled pair ``W sin tj = X cos ti + Y sin ti + Z1``,
  ``W cos tj = X sin ti - Y cos ti + Z2``: up to two (ti, tj) pairs.
"""

from __future__ import annotations

from ._support.public import publish
from .kinematics.paul import *  # noqa: F403 (its __all__, below)
from .kinematics.paul import __all__

publish(__name__, globals(), __all__)
