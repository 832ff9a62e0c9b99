"""Reference closed-form IK of 6R arm families, one target at a time (plain NumPy and ``math``).

Slow and obvious on purpose: the oracle the future C++ solvers are tested against.

**Chain description** (product of exponentials, as in IK-Geo / EAIK): unit joint axes ``h_i`` and
points ``p_i`` on them, both in the base frame at q = 0, and the tool pose ``M`` at q = 0:

    (K1)  T(q) = E_1(q_1) ... E_n(q_n) M,   E_i(q): x -> p_i + Rot(h_i, q) (x - p_i).

With ``G = T M^-1`` (rotation ``R``, translation ``t``) and the offsets ``p01 = p_1``,
``p_{i,i+1} = p_{i+1} - p_i``, ``p6T = -p_6`` (K1) reads, with ``R_i = Rot(h_i, q_i)``:

    (K2)  R = R_1 ... R_6,   t = p01 + R_1 p12 + R_1 R_2 p23 + ... + R_1 ... R_6 p6T.

**Subproblems** (Paden–Kahan, written as in IK-Geo), ``Rot(k, θ) p = k kᵀp + cos θ (p − k kᵀp)
+ sin θ (k × p)``:

- SP1: ``Rot(k, θ) p = q``: ``θ = atan2(kᵀ(p × q), pᵀq − (kᵀp)(kᵀq))``.
- SP4: ``hᵀ Rot(k, θ) p = d``: ``A cos θ + B sin θ = C`` with ``A = hᵀ(p − k kᵀp)``,
  ``B = hᵀ(k × p)``, ``C = d − (hᵀk)(kᵀp)``; ``θ = atan2(B, A) ± acos(C / hypot(A, B))``
  (root 0: ``+``, root 1: ``−``).
- SP3: ``|Rot(k, θ) p1 − p2| = d`` is SP4 with ``h = p2``, ``d' = (|p1|² + |p2|² − d²) / 2``.
- SP2: ``Rot(k1, θ1) p1 = Rot(k2, θ2) p2``: ``k2ᵀ Rot(k1, θ1) p1 = k2ᵀ p2`` (SP4 for θ1), then θ2
  by SP1.
- SP6 (two SP4 equations in two angles): ``A1 x1 + A2 x2 = e`` with ``x_i = (cos θ_i, sin θ_i)``.
  If ``A2`` is invertible, ``x2 = A2^-1 (e − A1 x1)`` and ``|x2|² = 1`` is a trigonometric
  polynomial of degree 2 in θ1, whose roots are the unit-circle roots of a quartic in
  ``z = exp(i θ1)`` (at most 4). If ``A2`` has rank 1 (UR arms), its left null vector ``n`` gives
  ``nᵀA1 x1 = nᵀe`` (SP4 for θ1, 2 roots) and then one row of ``A2 x2 = e − A1 x1`` (SP4 for θ2).
  Rank 1 means ``s2 < 1e-2 s1`` (singular values): a calibrated UR arm takes this idealised path
  (its answers then need ``polish=True`` to be exact).

**Families and slot order** (8 slots; ``slot = 2 k + b``; NaN where a slot has no solution):

- ``"three_parallel_234"`` (h2 ∥ h3 ∥ h4, UR3/5/10, Unitree Z1). ``R_2 R_3 R_4 = Rot(h2, θ234)``
  with ``θ234 = q2 + s3 q3 + s4 q4`` (``s_j = sign(h_jᵀ h2)``) preserves ``h2ᵀ x``, so (K2) gives two
  equations in q1 and q5 only:

      (P1)  h2ᵀ R_1ᵀ R h6 = h2ᵀ R_5 h6                     (orientation, × h6 on the right)
      (P2)  h2ᵀ R_1ᵀ (t − R p6T − p01) − h2ᵀ(p12 + p23 + p34 + p45) = h2ᵀ R_5 p56   (position)

  solved by SP6. ``k`` (0..3) numbers the (q1, q5) pairs: in the rank-1 case ``k = 2 i1 + i5`` with
  ``i1`` the SP4 root of q1 (shoulder) and ``i5`` that of q5 (wrist flip); in the rank-2 case the
  pairs in increasing q1. Then q6 by SP1 from ``Rot(h6, q6) Rᵀ R_1 h2 = R_5ᵀ h2``, θ234 from
  ``Rot(h2, θ234) = R_1ᵀ R R_6ᵀ R_5ᵀ``, and the planar part
  ``w = R_1ᵀ(t − R p6T − p01) − p12 − Rot(h2, θ234)(p45 + R_5 p56) = R_2 (p23 + R_3 p34)``:
  q3 by SP3 (``|p23 + R_3 p34| = |w|``, ``b`` = its root: the elbow), q2 by SP1, q4 from θ234.
- ``"three_parallel_123"`` (h1 ∥ h2 ∥ h3). ``R_1 R_2 R_3 = Rot(h1, θ123)`` keeps ``h1ᵀ x``, so
  with ``a = Rᵀ h1``, ``u = Rot(h4, −q4) h1`` and ``v = Rot(h6, q6) a`` the orientation reads
  ``R_5ᵀ u = v``, which needs (Q1) ``h5ᵀ u = h5ᵀ v``, and the position projected on h1 reads
  (Q2) ``p45ᵀ u + p56ᵀ v = h1ᵀ(t − R p6T − p01 − p12 − p23 − p34)``: SP6 again, ``A1 x6 + A2 x(−q4)
  = e`` with the ``−q4`` side constant; ``k`` numbers the (q6, −q4) pairs as above. Then q5 by SP1
  (``Rot(h5, q5) v = u``), θ123 from ``Rot(h1, θ123) = R (R_4 R_5 R_6)ᵀ`` and the planar part
  ``w = t − R p6T − p01 − Rot(h1, θ123)(p34 + R_4 (p45 + R_5 p56)) = R_1 (p12 + R_2 p23)``:
  q2 by SP3 (``b`` its root), q1 by SP1, ``q3 = s3 (θ123 − q1 − s2 q2)``.
- ``"spherical_shoulder"`` (h1, h2, h3 meet at c; take p1 = p2 = p3 = c). (K2) gives
  ``u = Rᵀ(t − c) − p6T = R_6ᵀ R_5ᵀ R_4ᵀ p34 + R_6ᵀ R_5ᵀ p45 + R_6ᵀ p56``. For each q5, q6 by SP3 from
  ``|R_6 u − p56 − R_5ᵀ p45| = |p34|`` and then ``m = R_5 (R_6 u − p56) − p45 = R_4ᵀ p34`` requires
  ``h4ᵀ m = h4ᵀ p34``: a scalar residual of q5, solved by scan and bisection as above (``k`` numbers
  the roots in increasing q5; the SP3 root of q6 is part of each root). q4 by SP1. (If h4 ∥ h5 that
  residual does not depend on q5: q6 is scanned instead, q5 by SP3 from
  ``|R_5 (R_6 u − p56) − p45| = |p34|``, same residual.) Then
  ``R_1 R_2 R_3 = R (R_4 R_5 R_6)ᵀ`` by SP2 on h3 (``b`` its root) and SP1 for q3.
- ``"spherical_wrist"`` (h4, h5, h6 meet): the reversed chain (``G^-1 = E_6(−q6) ... E_1(−q1)``) has a
  spherical shoulder; solved that way, same slots.

**Near-special geometry.** :func:`classify` accepts axes parallel to within ``tol_angle`` (the sine
of the angle) and axes meeting to within ``tol_dist`` (largest distance of an axis from the point
nearest to the three). :func:`solve` then solves the idealised chain (the parallel axes replaced by
their mean direction; the meeting axes moved to pass through that point) and, with
``polish=True``, runs Newton steps on the true chain. ``exact`` is True only where the residual on
the true chain is below 1e-10 (max of the position error in m and the rotation error in rad).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .subproblems import SCAN_STEPS as SCAN_STEPS  # this module's names, as before the subproblems moved
from .subproblems import TANGENT as TANGENT
from .subproblems import angle_about, rot, scan_roots, sp1, sp2, sp3, sp6, trig_coefficients
from .subproblems import solve_trig as solve_trig
from .subproblems import sp4 as sp4

FAMILIES = ("spherical_wrist", "three_parallel_234", "three_parallel_123", "spherical_shoulder")
SLOTS = 8
EXACT = 1e-10  # residual below which a solution is exact


class Chain6(NamedTuple):
    """A revolute chain in product-of-exponentials form (K1)."""

    axes: np.ndarray  # (n, 3) unit
    points: np.ndarray  # (n, 3), one point on each axis
    tool: np.ndarray  # (4, 4) tool pose at q = 0


class Solutions(NamedTuple):
    """Every solution of :func:`solve`, slot by slot."""

    q: np.ndarray  # (8, 6) joint values, NaN where a slot has none
    exists: np.ndarray  # (8,) bool
    valid: np.ndarray  # (8,) bool: exists and within the limits after ±2π wrapping
    exact: np.ndarray  # (8,) bool: residual on the true chain below 1e-10
    residual: np.ndarray  # (8,) max(position error, rotation error), NaN where none
    family: str


def make_chain(axes, points, tool=None) -> Chain6:
    axes = np.array(axes, dtype=float)
    points = np.array(points, dtype=float)
    if axes.ndim != 2 or axes.shape[1] != 3 or points.shape != axes.shape:
        raise ValueError(f"axes and points must both have shape (n, 3), got {axes.shape} and {points.shape}")
    norms = np.linalg.norm(axes, axis=1)
    if not np.all(norms > 0):
        raise ValueError("every axis must be non-zero")
    tool = np.eye(4) if tool is None else np.array(tool, dtype=float)
    if tool.shape != (4, 4):
        raise ValueError(f"tool must have shape (4, 4), got {tool.shape}")
    return Chain6(axes / norms[:, None], points, tool)


def from_frames(F: np.ndarray, convention: str) -> Chain6:
    """POE form of a DH chain from its frames at q = 0 (``reference.chain.frames``): joint j turns
    about z of frame j + 1 (modified DH) or frame j (classic DH); the tool is the last frame."""
    n = len(F) - 2
    idx = [j + 1 if convention == "mdh" else j for j in range(n)]
    return make_chain([F[i][:3, 2] for i in idx], [F[i][:3, 3] for i in idx], F[-1])


def from_dh(rows, convention: str = "dh", base=None, tool=None) -> Chain6:
    """POE form of a revolute DH table (rows ``(sigma, a|d, alpha, d|r, theta)``), pure Python."""
    from .chain import frames

    rows = np.asarray(rows, dtype=float)
    if np.any(rows[:, 0] != 0):
        raise ValueError("only revolute joints (sigma = 0) are supported")
    return from_frames(frames(rows, convention, np.zeros(len(rows)), base, tool), convention)


def from_sk_chain(chain) -> Chain6:
    """POE form of an ``sk.Chain`` (revolute): axes and points from its geometric Jacobian at q = 0.

    Column j is ``[h × (p_tool − o); h]``, so ``h × o = h × p_tool − v`` and the point of the axis
    nearest the origin is ``o⊥ = (h × p_tool − v) × h``.
    """
    if np.any(chain.sigma != 0):
        raise ValueError("only revolute chains are supported")
    q0 = np.zeros(chain.dof)
    M = chain.fk(q0)
    J = chain.jacobian(q0)
    axes = J[3:].T
    points = np.array([np.cross(np.cross(h, M[:3, 3]) - v, h) for h, v in zip(axes, J[:3].T)])
    return make_chain(axes, points, M)


def as_chain(description) -> Chain6:
    """A :class:`Chain6` from a Chain6, an ``sk.Chain`` or an ``(axes, points, tool)`` tuple."""
    if isinstance(description, Chain6):
        return description
    if hasattr(description, "jacobian") and hasattr(description, "sigma"):
        return from_sk_chain(description)
    return make_chain(*description)


def fk(chain: Chain6, q) -> np.ndarray:
    """(K1), one configuration."""
    T = np.eye(4)
    for h, p, angle in zip(chain.axes, chain.points, np.ravel(q)):
        E = np.eye(4)
        E[:3, :3] = rot(h, float(angle))
        E[:3, 3] = p - E[:3, :3] @ p
        T = T @ E
    return T @ chain.tool


def jacobian(chain: Chain6, q) -> np.ndarray:
    """(6, n) geometric Jacobian [v; w] of the tool origin in the base frame."""
    T = np.eye(4)
    tip = fk(chain, q)[:3, 3]
    J = np.zeros((6, len(chain.axes)))
    for j, (h, p, angle) in enumerate(zip(chain.axes, chain.points, np.ravel(q))):
        axis, point = T[:3, :3] @ h, T[:3, :3] @ p + T[:3, 3]  # joint j moves with joints < j
        J[:3, j] = np.cross(axis, tip - point)
        J[3:, j] = axis
        E = np.eye(4)
        E[:3, :3] = rot(h, float(angle))
        E[:3, 3] = p - E[:3, :3] @ p
        T = T @ E
    return J


def rotation_log(R: np.ndarray) -> np.ndarray:
    """The rotation vector of R (axis × angle), accurate near 0 and π."""
    c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2.0
    s = np.linalg.norm(w)
    angle = math.atan2(s, c)
    if s < 1e-6 and c < 0:  # near π: the axis from the symmetric part
        B = (R + np.eye(3)) / 2.0
        axis = B[:, int(np.argmax(np.diag(B)))]
        axis = axis / np.linalg.norm(axis)
        if axis @ w < 0:
            axis = -axis
        return axis * angle
    return w * (angle / s) if s > 0 else w


def pose_error(T_target: np.ndarray, T: np.ndarray) -> np.ndarray:
    """[p_target − p; log(R_target Rᵀ)], a (6,) vector in the base frame."""
    return np.concatenate([T_target[:3, 3] - T[:3, 3], rotation_log(T_target[:3, :3] @ T[:3, :3].T)])


def residual(chain: Chain6, q, T_target) -> float:
    e = pose_error(T_target, fk(chain, q))
    return max(float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:])))


def reversed_chain(chain: Chain6) -> Chain6:
    """The chain of ``G^-1 = E_6(−q6) ... E_1(−q1)`` (tool identity): axes and points in reverse."""
    return Chain6(chain.axes[::-1].copy(), chain.points[::-1].copy(), np.eye(4))


def fix_joint(chain: Chain6, joint: int, value: float) -> Chain6:
    """The (n − 1)-joint chain with joint ``joint`` held at ``value``.

    ``E_k(v) E_j(q) = E'_j(q) E_k(v)`` with E'_j about the axis moved by E_k(v), so moving E_k(v) to
    the right through the later joints leaves it in the tool: ``M' = E_k(v) M``.
    """
    n = len(chain.axes)
    if not 0 <= joint < n:
        raise ValueError(f"free_joint must be in [0, {n - 1}], got {joint}")
    E = np.eye(4)
    E[:3, :3] = rot(chain.axes[joint], value)
    E[:3, 3] = chain.points[joint] - E[:3, :3] @ chain.points[joint]
    axes, points = [], []
    for j in range(n):
        if j < joint:
            axes.append(chain.axes[j])
            points.append(chain.points[j])
        elif j > joint:
            axes.append(E[:3, :3] @ chain.axes[j])
            points.append(E[:3, :3] @ chain.points[j] + E[:3, 3])
    return Chain6(np.array(axes), np.array(points), E @ chain.tool)


# ---- classification ------------------------------------------------------------------------------


def _parallel_error(axes) -> float:
    """Largest sine of the angle between the first axis and the others."""
    return max(float(np.linalg.norm(np.cross(axes[0], h))) for h in axes[1:])


def _meeting_point(axes, points) -> tuple[np.ndarray, float]:
    """The point nearest (least squares) to the lines, and the largest distance from it to one."""
    A, b = np.zeros((3, 3)), np.zeros(3)
    for h, p in zip(axes, points):
        P = np.eye(3) - np.outer(h, h)
        A += P
        b += P @ p
    if np.linalg.cond(A) > 1e12:  # all parallel: no single point
        return np.full(3, np.nan), math.inf
    c = np.linalg.solve(A, b)
    return c, max(float(np.linalg.norm((np.eye(3) - np.outer(h, h)) @ (c - p))) for h, p in zip(axes, points))


def classify(description, tol_angle: float = 1e-9, tol_dist: float = 1e-9) -> str:
    """The family of a 6R chain (see the module docstring), checked in the order of ``FAMILIES``.

    Raises ``ValueError`` naming what was checked when the chain fits none.
    """
    chain = as_chain(description)
    if len(chain.axes) != 6:
        raise ValueError(f"a 6-joint chain is needed, got {len(chain.axes)} joints")
    h, p = chain.axes, chain.points
    _, wrist = _meeting_point(h[3:], p[3:])
    par234, par123 = _parallel_error(h[1:4]), _parallel_error(h[0:3])
    _, shoulder = _meeting_point(h[:3], p[:3])
    if wrist <= tol_dist:
        return "spherical_wrist"
    if par234 <= tol_angle:
        return "three_parallel_234"
    if par123 <= tol_angle:
        return "three_parallel_123"
    if shoulder <= tol_dist:
        return "spherical_shoulder"
    raise ValueError(
        "no closed-form family fits: checked axes 4-5-6 meeting (off by "
        f"{wrist:.3g} m), axes 2-3-4 parallel (sin angle {par234:.3g}), axes 1-2-3 parallel "
        f"({par123:.3g}), axes 1-2-3 meeting ({shoulder:.3g} m) against tol_angle={tol_angle:g}, "
        f"tol_dist={tol_dist:g}; use Chain.ik_differential"
    )


def idealise(chain: Chain6, family: str) -> Chain6:
    """The chain made exactly of its family: parallel axes set to their mean direction (signs
    kept), meeting axes moved to pass through their nearest common point."""
    axes, points = chain.axes.copy(), chain.points.copy()
    if family.startswith("three_parallel"):
        idx = [1, 2, 3] if family == "three_parallel_234" else [0, 1, 2]
        signs = [1.0 if axes[j] @ axes[idx[0]] > 0 else -1.0 for j in idx]
        mean = sum(s * axes[j] for s, j in zip(signs, idx))
        mean = mean / np.linalg.norm(mean)
        for s, j in zip(signs, idx):
            axes[j] = s * mean
    else:
        idx = [3, 4, 5] if family == "spherical_wrist" else [0, 1, 2]
        c, _ = _meeting_point(axes[idx], points[idx])
        for j in idx:
            points[j] = c
    return Chain6(axes, points, chain.tool)


# ---- family solvers (tool identity: G = R_1 ... R_6 as in (K2)) --------------------------------------


def _offsets(chain: Chain6):
    p = chain.points
    return p[0], [p[i + 1] - p[i] for i in range(5)], -p[5]


def _solve_234(chain: Chain6, G: np.ndarray) -> list[tuple[int, np.ndarray]]:
    h = chain.axes
    R, t = G[:3, :3], G[:3, 3]
    p01, (p12, p23, p34, p45, p56), p6T = _offsets(chain)
    h2 = h[1]
    # (P1), (P2): trig(q1) − trig(q5) = rhs, each side const + A (cos, sin)
    c1a, a1a, b1a = trig_coefficients(R @ h[5], h[0], h2)
    c5a, a5a, b5a = trig_coefficients(h2, h[4], h[5])
    c1b, a1b, b1b = trig_coefficients(t - R @ p6T - p01, h[0], h2)
    c5b, a5b, b5b = trig_coefficients(h2, h[4], p56)
    A1 = np.array([[a1a, b1a], [a1b, b1b]])
    A2 = -np.array([[a5a, b5a], [a5b, b5b]])
    e = np.array([c5a - c1a, c5b - c1b + h2 @ (p12 + p23 + p34 + p45)])
    out = []
    for k, q1, q5 in sp6(A1, A2, e):
        R1, R5 = rot(h[0], q1), rot(h[4], q5)
        a, b = R.T @ R1 @ h2, R5.T @ h2
        free6 = math.hypot(a @ b - (h[5] @ a) * (h[5] @ b), h[5] @ np.cross(a, b)) <= 1e-15
        q6 = 0.0 if free6 else sp1(a, b, h[5])
        theta = angle_about(h2, R1.T @ R @ rot(h[5], q6).T @ R5.T)
        A, B = R1.T @ (t - R @ p6T - p01) - p12, p45 + R5 @ p56
        if free6:
            # wrist singularity (R_5 h6 = ±h2): only theta ∓ q6 is fixed; take theta with |w|² in the
            # middle of the elbow's range |p23 + R_3 p34|² (or the nearest), then q6 = σ (theta0 − theta)
            const3 = trig_coefficients(p23, h[2], p34)[0]
            mid = p23 @ p23 + p34 @ p34 + 2 * const3
            c, a_, b_ = trig_coefficients(A, h2, B)
            r = math.hypot(a_, b_)
            theta0 = theta
            if r > 0:
                ratio = max(-1.0, min(1.0, ((A @ A + B @ B - mid) / 2 - c) / r))
                theta = math.atan2(b_, a_) + math.acos(ratio)
            sigma = 1.0 if h2 @ (R5 @ h[5]) >= 0 else -1.0
            q6 = sigma * (theta0 - theta)
        R234 = rot(h2, theta)
        w = A - R234 @ B
        for b, q3 in enumerate(sp3(p34, -p23, h[2], float(np.linalg.norm(w)))):
            R3 = rot(h[2], q3)
            q2 = sp1(p23 + R3 @ p34, w, h2)
            q4 = angle_about(h[3], (rot(h2, q2) @ R3).T @ R234)
            out.append((2 * k + b, np.array([q1, q2, q3, q4, q5, q6])))
    return out


def _solve_123(chain: Chain6, G: np.ndarray) -> list[tuple[int, np.ndarray]]:
    h = chain.axes
    R, t = G[:3, :3], G[:3, 3]
    p01, (p12, p23, p34, p45, p56), p6T = _offsets(chain)
    h1, a = h[0], R.T @ h[0]
    s2 = 1.0 if h[1] @ h1 >= 0 else -1.0
    s3 = 1.0 if h[2] @ h1 >= 0 else -1.0
    # (Q1) h5ᵀ Rot(h4, −q4) h1 = h5ᵀ Rot(h6, q6) a;  (Q2) p45ᵀ Rot(h4, −q4) h1 + p56ᵀ Rot(h6, q6) a = d
    c4a, a4a, b4a = trig_coefficients(h[4], h[3], h1)
    c4b, a4b, b4b = trig_coefficients(p45, h[3], h1)
    c6a, a6a, b6a = trig_coefficients(h[4], h[5], a)
    c6b, a6b, b6b = trig_coefficients(p56, h[5], a)
    d = float(h1 @ (t - R @ p6T - p01 - p12 - p23 - p34))
    A1 = np.array([[a6a, b6a], [a6b, b6b]])
    A2 = np.array([[-a4a, -b4a], [a4b, b4b]])
    e = np.array([c4a - c6a, d - c6b - c4b])
    out = []
    for k, q6, minus_q4 in sp6(A1, A2, e):
        q4 = -minus_q4
        u, v = rot(h[3], -q4) @ h1, rot(h[5], q6) @ a
        q5 = sp1(v, u, h[4])  # Rot(h5, q5) v = u (0 when both lie along h5)
        R4, R5 = rot(h[3], q4), rot(h[4], q5)
        theta = angle_about(h1, R @ (R4 @ R5 @ rot(h[5], q6)).T)
        w = t - R @ p6T - p01 - rot(h1, theta) @ (p34 + R4 @ (p45 + R5 @ p56))
        for b, q2 in enumerate(sp3(p23, -p12, h[1], float(np.linalg.norm(w)))):
            q1 = sp1(p12 + rot(h[1], q2) @ p23, w, h1)
            q3 = s3 * (theta - q1 - s2 * q2)
            out.append((2 * k + b, np.array([q1, q2, q3, q4, q5, q6])))
    return out


def _solve_shoulder(chain: Chain6, G: np.ndarray) -> list[tuple[int, np.ndarray]]:
    h = chain.axes
    R, t = G[:3, :3], G[:3, 3]
    c = chain.points[0]  # idealised: p1 = p2 = p3 = c
    p34, p45, p56, p6T = (
        chain.points[3] - c,
        *(chain.points[i + 1] - chain.points[i] for i in (3, 4)),
        -chain.points[5],
    )
    u = R.T @ (t - c) - p6T

    if np.linalg.norm(np.cross(h[3], h[4])) > 1e-2:  # scan q5; residual h4ᵀ(m − p34)

        def wrist(q5):
            R5 = rot(h[4], q5)
            found = []
            for q6 in sp3(u, p56 + R5.T @ p45, h[5], float(np.linalg.norm(p34))):
                m = R5 @ (rot(h[5], q6) @ u - p56) - p45
                found.append((float(h[3] @ (m - p34)), (-sp1(p34, m, h[3]), q5, q6)))
            return found

    else:  # h4 ∥ h5 makes that residual constant in q5: scan q6, v = R_6 u − p56, |R_5 v − p45| = |p34|

        def wrist(q6):
            v = rot(h[5], q6) @ u - p56
            found = []
            for q5 in sp3(v, p45, h[4], float(np.linalg.norm(p34))):
                m = rot(h[4], q5) @ v - p45
                found.append((float(h[3] @ (m - p34)), (-sp1(p34, m, h[3]), q5, q6)))
            return found

    def residuals(x):
        values = [math.nan, math.nan]
        for i, (value, _) in enumerate(wrist(x)):
            values[i] = value
        return values

    out = []
    for k, (x, branch) in enumerate(scan_roots(residuals)[:4]):
        q4, q5, q6 = wrist(x)[branch][1]
        R5 = rot(h[4], q5)
        R03 = R @ (rot(h[3], q4) @ R5 @ rot(h[5], q6)).T
        # Rot(h1, q1) Rot(h2, q2) h3 = R03 h3: Rot(h1, −q1) R03 h3 = Rot(h2, q2) h3 (SP2)
        for b, (m1, q2) in enumerate(sp2(R03 @ h[2], h[2], h[0], h[1])):
            q1 = -m1
            q3 = angle_about(h[2], (rot(h[0], q1) @ rot(h[1], q2)).T @ R03)
            out.append((2 * k + b, np.array([q1, q2, q3, q4, q5, q6])))
    return out


def _solve_family(chain: Chain6, G: np.ndarray, family: str) -> list[tuple[int, np.ndarray]]:
    if family == "three_parallel_234":
        return _solve_234(chain, G)
    if family == "three_parallel_123":
        return _solve_123(chain, G)
    if family == "spherical_shoulder":
        return _solve_shoulder(chain, G)
    # spherical wrist: the reversed chain has a spherical shoulder
    solutions = _solve_shoulder(reversed_chain(chain), np.linalg.inv(G))
    return [(slot, -q[::-1]) for slot, q in solutions]


# ---- the public functions of the reference --------------------------------------------------------


def newton_polish(chain: Chain6, q, T_target, iterations: int = 20) -> np.ndarray:
    """Newton (Gauss–Newton, least squares) steps on the true chain towards T_target."""
    q = np.array(q, dtype=float)
    for _ in range(iterations):
        e = pose_error(T_target, fk(chain, q))
        if max(np.linalg.norm(e[:3]), np.linalg.norm(e[3:])) < 1e-14:
            break
        q = q + np.linalg.lstsq(jacobian(chain, q), e, rcond=None)[0]
    return q


def wrap_into(q: np.ndarray, lower, upper) -> tuple[np.ndarray, bool]:
    """Angles in [−π, π], shifted by ±2π where that brings them into [lower, upper]."""
    q = np.array([math.remainder(v, 2 * math.pi) for v in q])
    ok = True
    for j in range(len(q)):
        for shift in (0.0, 2 * math.pi, -2 * math.pi):
            if lower[j] <= q[j] + shift <= upper[j]:
                q[j] += shift
                break
        else:
            ok = False
    return q, ok


def solve(
    description,
    T,
    *,
    limits=None,
    polish: bool = False,
    family: str | None = None,
    tol_angle: float = 1e-9,
    tol_dist: float = 1e-9,
) -> Solutions:
    """Every IK solution of a 6R chain for the target pose ``T`` (4, 4), in the slots of the module
    docstring. ``limits`` (6, 2) or None. ``polish=True`` refines each solution of the idealised
    family on the true chain (branches that do not converge there are dropped); without it, a chain
    that fits its family only within the tolerances gets the idealised answers, not exact. ``family``
    skips :func:`classify`."""
    chain = as_chain(description)
    family = family or classify(chain, tol_angle, tol_dist)
    T = np.asarray(T, dtype=float)
    lower, upper = (np.full(6, -np.inf), np.full(6, np.inf)) if limits is None else np.asarray(limits).T
    q = np.full((SLOTS, 6), np.nan)
    exists, valid, exact = (np.zeros(SLOTS, bool) for _ in range(3))
    res = np.full(SLOTS, np.nan)
    if not np.all(np.isfinite(T)):
        return Solutions(q, exists, valid, exact, res, family)
    ideal = idealise(chain, family)
    try:
        idealised = classify(chain) != family  # the family fits only within the given tolerances
    except ValueError:
        idealised = True
    G = T @ np.linalg.inv(chain.tool)
    for slot, solution in _solve_family(ideal, G, family):
        r = residual(chain, solution, T)
        if polish or (not idealised and r > 1e-12):  # near a double root acos loses digits: Newton
            solution = newton_polish(chain, solution, T)
            r = residual(chain, solution, T)
            if not r < 1e-6:  # an idealised branch that does not exist on the true chain
                continue
        # unpolished answers of an idealised chain are kept as they are (exact only below EXACT)
        q[slot], valid[slot] = wrap_into(solution, lower, upper)
        exists[slot], res[slot], exact[slot] = True, r, r < EXACT
    return Solutions(q, exists, valid, exact, res, family)


def solve_free(description, T, *, free_joint: int, free_value: float, limits=None, **options) -> Solutions:
    """IK of a 7-joint chain with joint ``free_joint`` held at ``free_value``: the other six joints
    by :func:`solve` on the fixed chain (:func:`fix_joint`); q (8, 7) has ``free_value`` in that
    column. ``limits`` (7, 2) or None."""
    chain = as_chain(description)
    if len(chain.axes) != 7:
        raise ValueError(f"a 7-joint chain is needed, got {len(chain.axes)} joints")
    rest = [j for j in range(7) if j != free_joint]
    sub_limits = None if limits is None else np.asarray(limits, dtype=float)[rest]
    sub = solve(fix_joint(chain, free_joint, float(free_value)), T, limits=sub_limits, **options)
    q = np.full((SLOTS, 7), np.nan)
    q[:, rest] = sub.q
    q[sub.exists, free_joint] = free_value
    valid = sub.valid.copy()
    if limits is not None:
        lo, hi = np.asarray(limits, dtype=float)[free_joint]
        valid &= lo <= free_value <= hi
    return Solutions(q, sub.exists, valid, sub.exact, sub.residual, sub.family)
