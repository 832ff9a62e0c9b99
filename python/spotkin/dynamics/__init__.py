"""Rigid-body dynamics of serial chains and of a floating body carrying chains, batched in C++.

Model
    A chain's link ``j`` is the body moved by joint ``j``; its inertial parameters are
    ``LinkInertials(mass, com, inertia)``: ``mass`` (n,) in kg, ``com`` (n, 3) the centre of
    mass in frame ``j + 1`` of :meth:`spotkin.Chain.frames` (the frame after joint ``j``'s
    motion), ``inertia`` (n, 3, 3) about the centre of mass in that frame's axes (kg m^2). A
    link carries everything rigidly attached to it; a moving branch that hangs off the chain
    (a gripper finger on an arm chain) is counted as rigid at the pose its inertials were
    taken in. :func:`inertials_of` reads ``chain.inertials`` when the chain carries them.

Conventions
    ``q``, ``qd``, ``qdd``, ``tau`` are (..., n) in the chain's joint order (rad, rad/s,
    rad/s^2, N m; m, m/s, m/s^2 and N for prismatic joints). ``gravity`` is a (3,) (or
    (..., 3)) vector in the chain's root frame (the frame before its ``base``), default
    (0, 0, -9.81) m/s^2. The dynamic model is ``A(q) qdd + C(q, qd) qd + G(q) = tau`` with
    ``C`` the matrix for which ``dA/dt - 2 C`` is skew-symmetric (as Pinocchio's
    ``computeCoriolisMatrix``).

Mass matrix layouts
    ``layout="full"`` gives A (..., n, n). ``"lower"`` gives the same shape with the strict
    upper triangle zero (the storage ``numpy.linalg.cholesky`` and
    ``scipy.linalg.cho_factor(..., lower=True)`` read). ``"packed"`` gives the lower triangle
    row by row, (..., n (n + 1) / 2): ``A[i, j]`` (``j <= i``) at ``i (i + 1) / 2 + j``, about
    half the memory of a large batch; :func:`unpack_symmetric` restores (..., n, n).

Batches
    Every argument broadcasts over its leading dimensions like NumPy; float32 inputs (all
    of them) give float32 results, anything else float64. A sample with a NaN or an Inf in
    any input gives NaN in its whole result row, and only it.
"""

from __future__ import annotations

from .._support.public import publish
from .rigid_body import *  # noqa: F403 (its __all__, below)
from .rigid_body import GRAVITY as GRAVITY
from .rigid_body import __all__

publish(__name__, globals(), __all__)
