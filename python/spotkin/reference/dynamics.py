"""Reference rigid-body dynamics, one sample at a time, from Featherstone's spatial algebra.

R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008 ("RBDA" below): RNEA (Table 5.1),
CRBA (Table 6.2), ABA (Table 7.1, and §9.3 for the floating base). The Coriolis matrix follows
Echeandia & Wensing, "Numerical methods to compute the Coriolis matrix and Christoffel symbols for
rigid-body systems" (J. Comput. Nonlinear Dynam., 2021), eq. 9-12.

The model is a :class:`spotkin.inertia.Tree` (from :func:`spotkin.inertia.tree_of`): joint j moves
body j, whose frame is ``F_j = F_parent · placement_j · M_j(q_j)``. Transforms are built here from
the placements and axes; nothing calls spotkin's compiled core.

Conventions (those of Pinocchio)
--------------------------------
* Spatial motion vectors are ``[v; w]`` (linear first): w the angular velocity, v the velocity of
  the body-fixed point at the frame's origin. Spatial forces are ``[f; n]`` (force, then moment about
  the origin).
* Fixed base: the root frame is the world; ``q``, ``qd``, ``qdd``, ``tau`` are (n,).
* Floating base (``tree.root`` is not None): the configuration is ``body_pose`` (4, 4), the body
  frame in the world, and the joints q (n,). The velocity is ``qd`` (6 + n,): the body's spatial
  velocity in the body frame, ``[R^T p_dot; omega_body]`` (Pinocchio's free-flyer velocity), then
  the joint rates. ``qdd`` is its time derivative and ``tau[:6]`` the wrench [f; n] on the body, in
  the body frame. A world-frame twist ``[p_dot; omega]`` (as in ``Robot.body_jacobian``) is
  ``blockdiag(R, R)`` times the first six entries.
* Gravity is a world-frame vector, default (0, 0, -9.81) m/s².
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .lagrange import planar_2r_gravity as planar_2r_gravity  # this module's names, as before
from .lagrange import planar_2r_mass_matrix as planar_2r_mass_matrix
from .lagrange import rrr_gravity as rrr_gravity
from .lagrange import rrr_mass_matrix as rrr_mass_matrix
from .spatial import (
    crf,
    crm,
    inverse_transform,
    joint_motion,
    motion_subspace,
    motion_transform,
    skew,
    spatial_inertia,
)

GRAVITY = (0.0, 0.0, -9.81)

STANCE_OK = 0
"""The minimum-norm contact forces balance the robot, and every one pushes on the ground."""
STANCE_PULLING = 1
"""They balance, but a foot pulls (negative normal force), though the centre of mass projects inside
the support polygon: a pushing distribution exists, the minimum-norm one is not it."""
STANCE_OUTSIDE = 2
"""They balance only by pulling on a foot, and the centre of mass projects on or outside the support
polygon: no pushing distribution exists (on level ground)."""
STANCE_UNBALANCED = 3
"""No contact forces at these feet balance the weight (fewer than three feet, or collinear ones, with
the centre of mass off their line or point): torques and forces are NaN."""


# --------------------------------------------------------------------------- the model at q


class _State(NamedTuple):
    n: int
    floating: bool
    order: list  # joints, parents before children
    parents: list
    X_up: list  # motion transform parent coordinates -> body j coordinates
    world: list  # body j's pose in the world (4, 4)
    S: list
    M: list  # spatial inertia of body j in its own frame
    base_pose: np.ndarray  # the root's pose in the world
    base_M: np.ndarray | None


def _vector(value, name: str, size: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},), got {array.shape}")
    return array


def _state(tree, q, body_pose) -> _State:
    n = len(tree.parents)
    q = _vector(q, "q", n)
    floating = tree.root is not None
    if floating and body_pose is None:
        raise ValueError("a floating-base tree needs body_pose (4, 4)")
    if not floating and body_pose is not None:
        raise ValueError("body_pose is for floating-base trees; this tree has a fixed base")
    base_pose = np.eye(4) if body_pose is None else np.asarray(body_pose, dtype=float)
    if base_pose.shape != (4, 4):
        raise ValueError(f"body_pose must have shape (4, 4), got {base_pose.shape}")
    parents = [int(p) for p in tree.parents]
    order, placed = [], {-1}
    while len(order) < n:
        ready = [j for j in range(n) if j not in order and parents[j] in placed]
        if not ready:
            raise ValueError("tree.parents does not form a tree rooted at -1")
        order += ready
        placed.update(ready)
    X_up, world, S, M = [None] * n, [None] * n, [None] * n, [None] * n
    for j in order:
        local = tree.placements[j] @ joint_motion(tree.axes[j], int(tree.types[j]), float(q[j]))
        X_up[j] = motion_transform(inverse_transform(local))
        parent_pose = base_pose if parents[j] < 0 else world[parents[j]]
        world[j] = parent_pose @ local
        S[j] = motion_subspace(tree.axes[j], int(tree.types[j]))
        M[j] = spatial_inertia(tree.inertials.mass[j], tree.inertials.com[j], tree.inertials.inertia[j])
    base_M = None
    if floating:
        base_M = spatial_inertia(float(tree.root.mass), tree.root.com, tree.root.inertia)
    return _State(n, floating, order, parents, X_up, world, S, M, base_pose, base_M)


def _gravity_acceleration(state: _State, gravity) -> np.ndarray:
    """The root's fictitious acceleration -[g; 0] in root coordinates (RBDA §5.3: gravity as a base
    acceleration)."""
    g = _vector(gravity, "gravity", 3)
    return -np.concatenate([state.base_pose[:3, :3].T @ g, np.zeros(3)])


def _offset(state: _State) -> int:
    return 6 if state.floating else 0


# --------------------------------------------------------------------------- inverse dynamics


def rnea(tree, q, qd, qdd, gravity=GRAVITY, body_pose=None) -> np.ndarray:
    """Inverse dynamics tau = A(q) qdd + C(q, qd) qd + G(q) by the recursive Newton-Euler algorithm
    (RBDA Table 5.1):
        v_j = X_j v_parent + S_j qd_j
        a_j = X_j a_parent + S_j qdd_j + v_j x S_j qd_j
        f_j = M_j a_j + v_j x* M_j v_j,  then backwards  tau_j = S_j^T f_j,  f_parent += X_j^T f_j
    with the root's acceleration offset by -g. (n,) for a fixed base, (6 + n,) for a floating one."""
    state = _state(tree, q, body_pose)
    k = _offset(state)
    qd = _vector(qd, "qd", k + state.n)
    qdd = _vector(qdd, "qdd", k + state.n)
    a_root = _gravity_acceleration(state, gravity)
    v_root = np.zeros(6)
    if state.floating:
        v_root = qd[:6].copy()
        a_root = a_root + qdd[:6]
    v, a, f = [None] * state.n, [None] * state.n, [None] * state.n
    for j in state.order:
        p = state.parents[j]
        vp, ap = (v_root, a_root) if p < 0 else (v[p], a[p])
        vj = state.S[j] * qd[k + j]
        v[j] = state.X_up[j] @ vp + vj
        a[j] = state.X_up[j] @ ap + state.S[j] * qdd[k + j] + crm(v[j]) @ vj
        f[j] = state.M[j] @ a[j] + crf(v[j]) @ state.M[j] @ v[j]
    tau = np.zeros(k + state.n)
    f_root = np.zeros(6)
    if state.floating:
        f_root = state.base_M @ a_root + crf(v_root) @ state.base_M @ v_root
    for j in reversed(state.order):
        tau[k + j] = state.S[j] @ f[j]
        p = state.parents[j]
        if p < 0:
            f_root = f_root + state.X_up[j].T @ f[j]
        else:
            f[p] = f[p] + state.X_up[j].T @ f[j]
    if state.floating:
        tau[:6] = f_root
    return tau


def gravity_torques(tree, q, gravity=GRAVITY, body_pose=None) -> np.ndarray:
    """G(q): RNEA at rest."""
    nv = len(tree.parents) + (6 if tree.root is not None else 0)
    return rnea(tree, q, np.zeros(nv), np.zeros(nv), gravity, body_pose)


def nonlinear_effects(tree, q, qd, gravity=GRAVITY, body_pose=None) -> np.ndarray:
    """C(q, qd) qd + G(q): RNEA with qdd = 0."""
    return rnea(tree, q, qd, np.zeros(len(np.asarray(qd))), gravity, body_pose)


# --------------------------------------------------------------------------- mass matrix


def crba(tree, q, body_pose=None) -> np.ndarray:
    """A(q) by the composite-rigid-body algorithm (RBDA Table 6.2):
        Ic_j = M_j + sum over children c of X_c^T Ic_c X_c
        A_jj = S_j^T Ic_j S_j;  F = Ic_j S_j, then up the ancestors i: F = X^T F, A_ij = A_ji = S_i^T F.
    A floating base is a 6-DoF joint with S = identity: A is (6 + n, 6 + n)."""
    state = _state(tree, q, body_pose)
    k = _offset(state)
    Ic = [M.copy() for M in state.M]
    Ic_root = state.base_M.copy() if state.floating else np.zeros((6, 6))
    for j in reversed(state.order):
        p = state.parents[j]
        moved = state.X_up[j].T @ Ic[j] @ state.X_up[j]
        if p < 0:
            Ic_root += moved
        else:
            Ic[p] += moved
    A = np.zeros((k + state.n, k + state.n))
    for j in state.order:
        F = Ic[j] @ state.S[j]
        A[k + j, k + j] = state.S[j] @ F
        i = j
        while True:
            F = state.X_up[i].T @ F
            i = state.parents[i]
            if i < 0:
                break
            A[k + i, k + j] = A[k + j, k + i] = state.S[i] @ F
        if state.floating:
            A[:6, k + j] = A[k + j, :6] = F
    if state.floating:
        A[:6, :6] = (Ic_root + Ic_root.T) / 2  # symmetric in exact arithmetic; the sums round apart
    return A


# --------------------------------------------------------------------------- forward dynamics


def aba(tree, q, qd, tau, gravity=GRAVITY, body_pose=None) -> np.ndarray:
    """Forward dynamics qdd = A^-1 (tau - C qd - G) by the articulated-body algorithm (RBDA Table 7.1;
    floating base: §9.3, the base's articulated inertia solved last, a_base = -IA^-1 pA).
        pass 1: v_j, c_j = v_j x S_j qd_j, IA_j = M_j, pA_j = v_j x* M_j v_j
        pass 2 (leaves first): U = IA S, D = S^T U, u = tau - S^T pA,
                Ia = IA - U U^T / D, pa = pA + Ia c + U u / D, passed to the parent through X^T . X
        pass 3: a_j = X_j a_parent + c_j, qdd_j = (u - U^T a_j) / D, a_j += S qdd_j
    Gravity enters as the root's acceleration -g (for a floating base it is added back to the body's
    acceleration at the end)."""
    state = _state(tree, q, body_pose)
    k = _offset(state)
    qd = _vector(qd, "qd", k + state.n)
    tau = _vector(tau, "tau", k + state.n)
    gravity_root = _gravity_acceleration(state, gravity)
    v_root = qd[:6].copy() if state.floating else np.zeros(6)
    v, c, IA, pA = [None] * state.n, [None] * state.n, [None] * state.n, [None] * state.n
    for j in state.order:
        p = state.parents[j]
        vj = state.S[j] * qd[k + j]
        v[j] = state.X_up[j] @ (v_root if p < 0 else v[p]) + vj
        c[j] = crm(v[j]) @ vj
        IA[j] = state.M[j].copy()
        pA[j] = crf(v[j]) @ state.M[j] @ v[j]
    if state.floating:
        IA_root = state.base_M.copy()
        pA_root = crf(v_root) @ state.base_M @ v_root - tau[:6]
    U, D, u = [None] * state.n, [None] * state.n, [None] * state.n
    for j in reversed(state.order):
        U[j] = IA[j] @ state.S[j]
        D[j] = state.S[j] @ U[j]
        u[j] = tau[k + j] - state.S[j] @ pA[j]
        p = state.parents[j]
        if p < 0 and not state.floating:
            continue
        Ia = IA[j] - np.outer(U[j], U[j]) / D[j]
        pa = pA[j] + Ia @ c[j] + U[j] * u[j] / D[j]
        if p < 0:
            IA_root += state.X_up[j].T @ Ia @ state.X_up[j]
            pA_root += state.X_up[j].T @ pa
        else:
            IA[p] += state.X_up[j].T @ Ia @ state.X_up[j]
            pA[p] += state.X_up[j].T @ pa
    qdd = np.zeros(k + state.n)
    a_root = gravity_root
    if state.floating:
        a_root = -np.linalg.solve(IA_root, pA_root)
        qdd[:6] = a_root - gravity_root
    a = [None] * state.n
    for j in state.order:
        p = state.parents[j]
        a[j] = state.X_up[j] @ (a_root if p < 0 else a[p]) + c[j]
        qdd[k + j] = (u[j] - U[j] @ a[j]) / D[j]
        a[j] = a[j] + state.S[j] * qdd[k + j]
    return qdd


# --------------------------------------------------------------------------- world-frame quantities


def _world_columns(state: _State):
    """Per velocity index, its world-frame motion vector s (6,), the body it acts on (-1 for the
    floating base's six) and that body's ancestors-or-self sets."""
    columns = []
    if state.floating:
        X = motion_transform(state.base_pose)
        columns += [(X[:, i], -1) for i in range(6)]
    for j in range(state.n):
        columns.append((motion_transform(state.world[j]) @ state.S[j], j))
    return columns


def _supports(state: _State, body: int) -> set:
    """The bodies whose joints move ``body``: itself and its ancestors (and -1, the floating base)."""
    chain = {-1} if state.floating else set()
    while body >= 0:
        chain.add(body)
        body = state.parents[body]
    return chain


def body_jacobians(tree, q, body_pose=None) -> list:
    """Per body j (and first, for a floating base, the body itself) the (6, nv) world-frame Jacobian:
    world spatial velocity [v; w] of the body (v: the velocity of its point at the world origin) =
    J qd. Column i is the world-frame motion vector of velocity index i when it moves the body."""
    state = _state(tree, q, body_pose)
    return _body_jacobians(state)


def _body_jacobians(state: _State) -> list:
    columns = _world_columns(state)
    bodies = ([-1] if state.floating else []) + list(range(state.n))
    out = []
    for body in bodies:
        moved_by = _supports(state, body)
        J = np.zeros((6, len(columns)))
        for i, (s, owner) in enumerate(columns):
            if owner in moved_by:
                J[:, i] = s
        out.append(J)
    return out


def _world_inertias(state: _State) -> list:
    """Spatial inertias in world coordinates: X^-T M X^-1 with X = the body's motion transform."""
    out = []
    poses = ([state.base_pose] if state.floating else []) + state.world
    inertias = ([state.base_M] if state.floating else []) + state.M
    for T, M in zip(poses, inertias):
        X_inverse = motion_transform(inverse_transform(T))
        out.append(X_inverse.T @ M @ X_inverse)
    return out


def coriolis_matrix(tree, q, qd, body_pose=None) -> np.ndarray:
    """C(q, qd) with C qd = the velocity terms of RNEA and dA/dt - 2 C skew-symmetric (Christoffel-
    consistent; Pinocchio's computeCoriolisMatrix). In world coordinates, body by body:
        C = sum_b J_b^T (M_b dJ_b/dt + B(M_b, v_b) J_b),   B(M, v) = (v x* M - M v x + (M v) xbar*) / 2
    where dJ/dt's column i is v_owner(i) x s_i (each column is a world motion vector carried by its
    body) and (h xbar*) m = m x* h (Echeandia & Wensing 2021, eq. 12). The Christoffel form follows:
    dA/dt = sum (dJ^T M J + J^T M dJ) + J^T (v x* M - M v x) J, so dA/dt - 2C
    = sum (dJ^T M J - J^T M dJ) - J^T (M v xbar*) J, and both terms are skew."""
    state = _state(tree, q, body_pose)
    k = _offset(state)
    qd = _vector(qd, "qd", k + state.n)
    columns = _world_columns(state)
    jacobians = _body_jacobians(state)
    inertias = _world_inertias(state)
    bodies = ([-1] if state.floating else []) + list(range(state.n))
    body_velocity = {b: J @ qd for b, J in zip(bodies, jacobians)}
    C = np.zeros((k + state.n, k + state.n))
    for body, J, M in zip(bodies, jacobians, inertias):
        v = body_velocity[body]
        J_dot = np.zeros_like(J)
        for i, (s, owner) in enumerate(columns):
            if J[:, i].any():
                J_dot[:, i] = crm(body_velocity[owner]) @ s
        h = M @ v
        bar = np.column_stack([crf(np.eye(6)[i]) @ h for i in range(6)])
        B = (crf(v) @ M - M @ crm(v) + bar) / 2
        C += J.T @ (M @ J_dot + B @ J)
    return C


def kinetic_energy(tree, q, qd, body_pose=None) -> float:
    """sum over bodies of v_b^T M_b v_b / 2, each body's spatial velocity from the Jacobians."""
    state = _state(tree, q, body_pose)
    qd = _vector(qd, "qd", _offset(state) + state.n)
    return sum(0.5 * (J @ qd) @ M @ (J @ qd) for J, M in zip(_body_jacobians(state), _world_inertias(state)))


def _masses_and_centres(state: _State, tree) -> list:
    """(mass, world centre of mass, body index) per body (-1: the floating base)."""
    out = []
    if state.floating:
        com = state.base_pose[:3, :3] @ tree.root.com + state.base_pose[:3, 3]
        out.append((float(tree.root.mass), com, -1))
    for j in range(state.n):
        com = state.world[j][:3, :3] @ tree.inertials.com[j] + state.world[j][:3, 3]
        out.append((float(tree.inertials.mass[j]), com, j))
    return out


def potential_energy(tree, q, gravity=GRAVITY, body_pose=None) -> float:
    """U = -sum m_b g . c_b (zero at the world origin)."""
    state = _state(tree, q, body_pose)
    g = _vector(gravity, "gravity", 3)
    return -sum(m * g @ c for m, c, _ in _masses_and_centres(state, tree))


def center_of_mass(tree, q, body_pose=None) -> np.ndarray:
    """The world centre of mass of the moving bodies (and of the floating body): (3,)."""
    state = _state(tree, q, body_pose)
    parts = _masses_and_centres(state, tree)
    total = sum(m for m, _, _ in parts)
    return sum(m * c for m, c, _ in parts) / total


def point_jacobian(J: np.ndarray, point) -> np.ndarray:
    """(3, nv) velocity of a world point carried by a body with world Jacobian J (6, nv): v + w x p."""
    return J[:3] - skew(point) @ J[3:]


def center_of_mass_jacobian(tree, q, body_pose=None) -> np.ndarray:
    """d(center_of_mass)/dt = J_com qd: (3, nv), the mass-weighted mean of each body's centre-of-mass
    point Jacobian."""
    state = _state(tree, q, body_pose)
    parts = _masses_and_centres(state, tree)
    total = sum(m for m, _, _ in parts)
    jacobians = _body_jacobians(state)
    return sum(m * point_jacobian(J, c) for (m, c, _), J in zip(parts, jacobians)) / total


# --------------------------------------------------------------------------- statics


def joint_torques_from_forces(J, F) -> np.ndarray:
    """tau = J^T F: the joint torques that balance a wrench or force F (m,) applied where the Jacobian
    J (m, n) maps joint rates to that point's velocity (virtual work: tau . dq = F . J dq)."""
    J = np.asarray(J, dtype=float)
    F = np.asarray(F, dtype=float)
    if J.ndim != 2:
        raise ValueError(f"J must have shape (m, n), got {J.shape}")
    if F.shape != (J.shape[0],):
        raise ValueError(f"F must have shape ({J.shape[0]},), got {F.shape}")
    return J.T @ F


class Standing(NamedTuple):
    """The result of :func:`standing_torques`."""

    tau: np.ndarray
    """(n,) joint torques holding the pose."""
    forces: np.ndarray
    """(k, 3) world contact forces on the stance feet (ground on foot)."""
    status: int
    """STANCE_OK, STANCE_PULLING, STANCE_OUTSIDE or STANCE_UNBALANCED."""
    margin: float
    """Signed distance (m) of the centre of mass's projection to the support polygon, in the plane
    normal to gravity: with three or more non-collinear feet, the smallest signed distance to the
    polygon's edge lines (positive inside); otherwise minus the distance to the feet's segment or
    point."""
    residual: np.ndarray
    """(6,) the wrench the forces leave unbalanced: [-m g - sum f_i; -sum (p_i - c) x f_i] (world)."""


def _hull(points: list) -> list:
    """Convex hull of 2-D points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def _support_margin(feet: list, com: np.ndarray, up: np.ndarray) -> float:
    """See :attr:`Standing.margin`."""
    u = np.cross(up, [1.0, 0.0, 0.0])
    if np.linalg.norm(u) < 0.5:
        u = np.cross(up, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(up, u)
    flat = [(float(p @ u), float(p @ w)) for p in feet]
    c = np.array([com @ u, com @ w])
    hull = _hull(flat)
    scale = max([1.0] + [abs(x) for p in flat for x in p])
    area = 0.0
    for i in range(len(hull)):
        (x0, y0), (x1, y1) = hull[i], hull[(i + 1) % len(hull)]
        area += x0 * y1 - x1 * y0
    if len(hull) >= 3 and area > 1e-12 * scale**2:
        margin = math.inf
        for i in range(len(hull)):
            a, b = np.array(hull[i]), np.array(hull[(i + 1) % len(hull)])
            edge = b - a
            inward = np.array([-edge[1], edge[0]]) / np.linalg.norm(edge)  # left of a CCW edge
            margin = min(margin, float((c - a) @ inward))
        return margin
    if len(hull) == 1:
        return -float(np.linalg.norm(c - np.array(hull[0])))
    a, b = np.array(hull[0]), np.array(hull[-1])  # collinear: the extreme points
    t = min(1.0, max(0.0, float((c - a) @ (b - a) / ((b - a) @ (b - a)))))
    return -float(np.linalg.norm(c - (a + t * (b - a))))


def standing_torques(tree, body_pose, q, stance_feet, gravity=GRAVITY) -> Standing:
    """Joint torques that hold a floating-base robot still on its stance feet.

    Point contacts at the stance feet (``stance_feet``: indices into ``tree.feet``, or a (k,) bool
    mask) carry forces f_i (world frame, ground on foot) that balance the weight:
        sum f_i = -m g,    sum (p_i - c) x f_i = 0   (c: the centre of mass)
    — six equations A f = b in 3 k unknowns. f is the minimum-norm solution (the pseudo-inverse);
    then tau = G_joints - sum J_i^T f_i over the stance feet (J_i: the foot point's Jacobian, joint
    columns). When no f solves A f = b (|A f - b| > 1e-9 m |g|), f carries the weight exactly and the
    moment in least squares, the smallest such: f = f_p + N z over the forces with sum f_i = -m g
    (f_p = pinv(C) (-m g), C = [I ... I], N an orthonormal basis of C's null space), z = pinv(M N)
    (-M f_p) (M f = sum (p_i - c) x f_i; singular values below 1e-9 of the largest dropped).
    ``residual`` = b - A f, the wrench left. Status, in this order:
      STANCE_UNBALANCED when |A f - b| > 1e-9 m |g| for the exact minimum-norm f (the least-squares f);
      STANCE_OK when every normal component -f_i . g / |g| >= -1e-9 m |g| (with g = 0, the forces are
      zero and the status OK; the margin is then NaN);
      otherwise STANCE_PULLING when the centre of mass projects inside the support polygon
      (margin > 0), STANCE_OUTSIDE when not.
    """
    if tree.root is None:
        raise ValueError("standing_torques needs a floating-base tree (tree_of(robot))")
    state = _state(tree, q, body_pose)
    g = _vector(gravity, "gravity", 3)
    k_feet = len(tree.feet)
    stance = np.asarray(stance_feet)
    if stance.dtype == bool:
        if stance.shape != (k_feet,):
            raise ValueError(f"stance_feet as a mask must have shape ({k_feet},), got {stance.shape}")
        stance = np.flatnonzero(stance)
    stance = [int(i) for i in np.ravel(stance)]
    if any(not 0 <= i < k_feet for i in stance) or len(set(stance)) != len(stance):
        raise ValueError(f"stance_feet must be distinct foot indices in [0, {k_feet}), got {stance}")
    parts = _masses_and_centres(state, tree)
    total = sum(m for m, _, _ in parts)
    com = sum(m * c for m, c, _ in parts) / total
    jacobians = _body_jacobians(state)
    body_row = {b: i for i, b in enumerate(([-1] if state.floating else []) + list(range(state.n)))}
    points, foot_jacobians = [], []
    for i in stance:
        body = int(tree.feet[i])
        T = state.world[body]
        p = T[:3, :3] @ tree.foot_points[i] + T[:3, 3]
        points.append(p)
        foot_jacobians.append(point_jacobian(jacobians[body_row[body]], p))
    A = np.zeros((6, 3 * len(stance)))
    for i, p in enumerate(points):
        A[:3, 3 * i : 3 * i + 3] = np.eye(3)
        A[3:, 3 * i : 3 * i + 3] = skew(p - com)
    b = np.concatenate([-total * g, np.zeros(3)])
    weight = total * float(np.linalg.norm(g))
    forces = (np.linalg.pinv(A) @ b).reshape(len(stance), 3) if stance else np.zeros((0, 3))
    up = -g / np.linalg.norm(g)
    margin = _support_margin(points, com, up) if points else -math.inf
    unbalanced = float(np.linalg.norm(A @ forces.ravel() - b)) > 1e-9 * weight
    if unbalanced:  # the weight exactly, the moment in least squares, the smallest forces
        k = len(stance)
        C = A[:3]
        f_p = np.linalg.pinv(C) @ b[:3]
        _, _, Vt = np.linalg.svd(C)
        N = Vt[3:].T  # (3 k, 3 k - 3): C's null space
        M = A[3:]
        z = np.linalg.pinv(M @ N, rcond=1e-9) @ (-M @ f_p) if k > 1 else np.zeros(0)
        forces = (f_p + N @ z).reshape(k, 3)
    residual = b - (A @ forces.ravel() if stance else np.zeros(6))
    G = gravity_torques(tree, q, g, body_pose)
    tau = G[6:].copy()
    for f, Jp in zip(forces, foot_jacobians):
        tau -= joint_torques_from_forces(Jp[:, 6:], f)
    normals = forces @ up
    if unbalanced:
        status = STANCE_UNBALANCED
    elif weight == 0.0 or (normals >= -1e-9 * weight).all():  # no gravity: zero forces, nothing pulls
        status = STANCE_OK
    else:
        status = STANCE_PULLING if margin > 0 else STANCE_OUTSIDE
    return Standing(tau, forces, status, margin, residual)
