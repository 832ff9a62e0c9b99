"""Reference kinematics of the Spot Arm: FK, Jacobian, closed-form IK, singularity measures.

Slow, per-sample, written straight from the formulas; the C++ results are tested against it.
Units: m, rad.  Frames: body frame of Spot; at q = 0 every arm frame is parallel to it.

Model
-----
q = [sh0, sh1, el0, el1, wr0, wr1]::

    T_hand = Trans(mount) Rz(sh0) Ry(sh1) Trans(a,0,0) Ry(el0) Trans(b,0,h)
             Rx(el1) Ry(wr0) Rx(wr1) Trans(hand,0,0) tool                       (1)

mount = (0.292, 0, 0.188), a = 0.3385, b = 0.4033, h = 0.075, hand = 0.19557,
tool = I (any rigid transform).  The el1, wr0, wr1 axes meet at the el1 origin, the
wrist centre (spherical wrist)::

    c = mount + Rz(sh0) Ry(sh1) s(el0),   s(el0) = (a,0,0) + Ry(el0) (b,0,h)            (2)
      = (a + b cos el0 + h sin el0, 0, -b sin el0 + h cos el0)    [the s components]

Inverse kinematics (ik_all)
---------------------------
1. Wrist pose: T_w = T_target inv(Trans(hand,0,0) tool); c = p(T_w), R_w = R(T_w); c' = c - mount.
2. sh0 = atan2(c'_y, c'_x) (shoulder branch 0, "front") or that + pi (branch 1, "back").
   If hypot(c'_x, c'_y) < SHOULDER_TOL the wrist centre is on the sh0 axis, sh0 is free:
   sh0 = seed[0] (0 without seed), branch 1 = that + pi.
3. Arm plane: (u, y, w) = Rz(-sh0) c' (y = 0 up to rounding, no lateral offset).
   From (2): |c'|^2 = a^2 + b^2 + h^2 + 2a (b cos el0 + h sin el0)  (Paul type 2). With
   L = hypot(b, h), phi = atan2(h, b), K = (|c'|^2 - a^2 - L^2) / (2a):
       L cos(el0 - phi) = K   ->   el0 = phi +- acos(K / L)                          (3)
   |K/L| > 1 + ELBOW_TOL: unreachable (all slots NaN); |K/L| <= 1 + ELBOW_TOL is clamped
   (touching: stretched / folded elbow, both elbow slots equal).
   Elbow branch 0: el0 = phi + acos(K/L), i.e. el0 - phi in [0, pi], el0 in [phi, pi + phi]:
   the root Spot uses (el0 limits [0, pi]).  Equivalently (upper arm x shoulder->wrist-centre)
   . y_arm >= 0: with the front shoulder branch (u >= 0) the elbow lies ABOVE the
   shoulder->wrist-centre line, "elbow up".  Elbow branch 1: el0 = phi - acos(K/L),
   "elbow down".  (In the back shoulder branch u <= 0 and the same roots put the elbow
   below / above the line respectively, seen from the body.)
4. Ry(t) multiplies z + i x by e^{i t}, so sh1 = atan2(u, w) - atan2(s_x, s_z).      (4)
5. R_36 = (Rz(sh0) Ry(sh1 + el0))^T R_w = Rx(el1) Ry(wr0) Rx(wr1), whose entries are
       R00 = c4, R10 = s3 s4, R20 = -c3 s4, R01 = s4 s5, R02 = s4 c5,
       row 1 of Rx(el1)^T R_36 = Ry(wr0) Rx(wr1) is (0, c5, -s5), column 0 is (c4, 0, -s4).
   Wrist branch 0 (wr0 >= 0): el1 = atan2(R10, -R20); branch 1 (wr0 <= 0): el1 + pi.
   Then with M = Rx(el1)^T R_36:  wr0 = atan2(-M20, M00),  wr1 = atan2(-M12, M11).     (5)
   (Branch 1 equals (el1 + pi, -wr0, wr1 + pi).)  Computing wr0, wr1 from M rather than
   from R_36 directly keeps the decomposition exact to rounding even close to wr0 = 0.
   Wrist singular, |sin wr0| = hypot(R10, R20) < WRIST_TOL: el1 is free; el1 = seed[3]
   (0 without seed), wr0 snapped to 0 (R00 > 0) or pi (R00 < 0), wr1 from (5) so the
   orientation is reproduced (error <= ~WRIST_TOL).  Slot 1 of the pair is again
   (el1 + pi, -wr0, wr1 + pi): same wr0 = 0 (or pi), el1 and wr1 shifted by pi.
6. Slot order (fixed): slot = 4*shoulder_branch + 2*elbow_branch + wrist_branch.
   All angles wrapped to (-pi, pi].  Reachable targets give all 8 slots; otherwise none.
"""

import math

import numpy as np

MOUNT = (0.292, 0.0, 0.188)
A = 0.3385
B = 0.4033
H = 0.075
HAND = 0.19557

LOWER = np.array([-2.61799, -3.14159, 0.0, -2.79253, -1.8326, -2.87979])
UPPER = np.array([3.14159, 0.523599, 3.14159, 2.79253, 1.8326, 2.87979])

SHOULDER_TOL = 1e-12  # m: wrist centre closer than this to the sh0 axis -> shoulder singular
WRIST_TOL = 1e-9  # |sin wr0| below this -> wrist singular
ELBOW_TOL = 1e-12  # |K/L| <= 1 + ELBOW_TOL counts as reachable (clamped)
LIMIT_TOL = 1e-12

OK, UNREACHABLE, JOINT_LIMIT, INVALID_INPUT = 0, 1, 2, 3


# ---------------------------------------------------------------- elementary transforms
def rot_x(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _hom(R=None, p=None):
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def _inv(T):
    """Inverse of a rigid transform: (R, p)^-1 = (R^T, -R^T p)."""
    R, p = T[:3, :3], T[:3, 3]
    return _hom(R.T, -R.T @ p)


def wrap(x):
    """Wrap an angle to (-pi, pi]."""
    return math.pi - (math.pi - x) % (2.0 * math.pi)


def _tool(tool):
    return np.eye(4) if tool is None else np.asarray(tool, dtype=float)


# ---------------------------------------------------------------- forward kinematics
def _chain(q, mount, a, b, h, hand, tool):
    """Walk (1); return ([(axis_i, point_i)] in the body frame for the 6 joints, T_hand)."""
    sh0, sh1, el0, el1, wr0, wr1 = (float(v) for v in q)
    steps = [  # (transform before the joint, joint axis unit vector, joint angle)
        (_hom(p=mount), (0, 0, 1), sh0),
        (np.eye(4), (0, 1, 0), sh1),
        (_hom(p=(a, 0, 0)), (0, 1, 0), el0),
        (_hom(p=(b, 0, h)), (1, 0, 0), el1),
        (np.eye(4), (0, 1, 0), wr0),
        (np.eye(4), (1, 0, 0), wr1),
    ]
    rot = {(1, 0, 0): rot_x, (0, 1, 0): rot_y, (0, 0, 1): rot_z}
    T = np.eye(4)
    joints = []
    for pre, ax, t in steps:
        T = T @ pre
        joints.append((T[:3, :3] @ np.array(ax, dtype=float), T[:3, 3].copy()))
        T = T @ _hom(rot[ax](t))
    T = T @ _hom(p=(hand, 0, 0)) @ _tool(tool)
    return joints, T


def fk(q, *, mount=MOUNT, a=A, b=B, h=H, hand=HAND, tool=None):
    """Hand (tool) pose in the body frame, eq. (1). Returns (4, 4)."""
    return _chain(q, mount, a, b, h, hand, tool)[1]


def jacobian(q, *, mount=MOUNT, a=A, b=B, h=H, hand=HAND, tool=None):
    """Geometric Jacobian [v; w] (6, 6) of the final frame's origin in the body frame.

    Revolute column i = [z_i x (p_tool - p_i); z_i], z_i the joint axis, p_i a point on it.
    """
    joints, T = _chain(q, mount, a, b, h, hand, tool)
    p = T[:3, 3]
    J = np.zeros((6, 6))
    for i, (z, pi) in enumerate(joints):
        J[:3, i] = np.cross(z, p - pi)
        J[3:, i] = z
    return J


# ---------------------------------------------------------------- inverse kinematics
def _wrist_pairs(R36, el1_free):
    """The two X-Y-X decompositions R36 = Rx(el1) Ry(wr0) Rx(wr1), eq. (5)."""
    s4 = math.hypot(R36[1, 0], R36[2, 0])
    singular = s4 < WRIST_TOL
    el1 = el1_free if singular else math.atan2(R36[1, 0], -R36[2, 0])
    out = []
    for e1 in (el1, el1 + math.pi):
        M = rot_x(e1).T @ R36
        if singular:
            w0 = 0.0 if R36[0, 0] > 0 else math.pi
        else:
            w0 = math.atan2(-M[2, 0], M[0, 0])
        w1 = math.atan2(-M[1, 2], M[1, 1])
        out.append((e1, w0, w1))
    return out


def ik_all(T, *, seed=None, mount=MOUNT, a=A, b=B, h=H, hand=HAND, tool=None):
    """All 8 closed-form IK branches (see the module docstring, steps 1-6).

    seed: optional (6,) joint vector, used only in singular cases: sh0 = seed[0] when the
    wrist centre is on the sh0 axis, el1 = seed[3] when sin(wr0) = 0 (0 without seed).
    Returns (q_all (8, 6), NaN rows for missing branches; exists (8,) bool).
    Slot = 4*shoulder_branch + 2*elbow_branch + wrist_branch.
    """
    T = np.asarray(T, dtype=float)
    q_all = np.full((8, 6), np.nan)
    exists = np.zeros(8, dtype=bool)
    sh0_free = 0.0 if seed is None else float(seed[0])
    el1_free = 0.0 if seed is None else float(seed[3])

    Tw = T @ _inv(_hom(p=(hand, 0, 0)) @ _tool(tool))  # step 1
    c = Tw[:3, 3] - np.asarray(mount, dtype=float)
    Rw = Tw[:3, :3]

    L, phi = math.hypot(b, h), math.atan2(h, b)  # step 3, eq. (3)
    ratio = (float(c @ c) - a * a - L * L) / (2.0 * a) / L
    if not abs(ratio) <= 1.0 + ELBOW_TOL:  # also rejects NaN
        return q_all, exists
    delta = math.acos(min(1.0, max(-1.0, ratio)))
    el0s = (phi + delta, phi - delta)

    r = math.hypot(c[0], c[1])  # step 2
    sh0_front = sh0_free if r < SHOULDER_TOL else math.atan2(c[1], c[0])

    for i, sh0 in enumerate((sh0_front, sh0_front + math.pi)):
        u = math.cos(sh0) * c[0] + math.sin(sh0) * c[1]  # arm plane, y ~ 0
        w = c[2]
        for j, el0 in enumerate(el0s):
            sx = a + b * math.cos(el0) + h * math.sin(el0)  # eq. (2)
            sz = -b * math.sin(el0) + h * math.cos(el0)
            sh1 = math.atan2(u, w) - math.atan2(sx, sz)  # eq. (4)
            R36 = (rot_z(sh0) @ rot_y(sh1 + el0)).T @ Rw  # step 5
            for k, (el1, wr0, wr1) in enumerate(_wrist_pairs(R36, el1_free)):
                slot = 4 * i + 2 * j + k
                q_all[slot] = [wrap(v) for v in (sh0, sh1, el0, el1, wr0, wr1)]
                exists[slot] = True
    return q_all, exists


def wrap_into_limits(q, lower=LOWER, upper=UPPER):
    """Per joint try q, q - 2 pi, q + 2 pi; the first in [lower, upper] (+- 1e-12) wins.

    Returns (q_wrapped (6,), ok).  Joints with no candidate in limits are left unchanged.
    """
    q = np.asarray(q, dtype=float)
    out = q.copy()
    ok = True
    for i, v in enumerate(q):
        for cand in (v, v - 2.0 * math.pi, v + 2.0 * math.pi):
            if lower[i] - LIMIT_TOL <= cand <= upper[i] + LIMIT_TOL:
                out[i] = cand
                break
        else:
            ok = False
    return out, ok


def _valid_pose(T):
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        return False
    if np.max(np.abs(T[3] - [0.0, 0.0, 0.0, 1.0])) > 1e-9:
        return False
    R = T[:3, :3]
    return np.max(np.abs(R.T @ R - np.eye(3))) <= 1e-6 and np.linalg.det(R) >= 0.0


def ik(T, *, lower=LOWER, upper=UPPER, seed=None, mount=MOUNT, a=A, b=B, h=H, hand=HAND, tool=None):
    """One IK solution within the joint limits. Returns (q (6,), status).

    INVALID_INPUT: T non-finite, last row != [0,0,0,1] (1e-9), max|R^T R - I| > 1e-6 or
    det R < 0 (also a non-finite seed).  UNREACHABLE: no branch exists.  JOINT_LIMIT:
    branches exist, none fits the limits after wrap_into_limits.  q is NaN unless OK.
    OK: among valid slots the one minimising max_j |wrap(q_j - seed_j)|; without seed
    the lowest valid slot.  Ties -> lowest slot.  q is returned wrapped into the limits.
    """
    nan = np.full(6, np.nan)
    T = np.asarray(T, dtype=float)
    if not _valid_pose(T):
        return nan, INVALID_INPUT
    if seed is not None:
        seed = np.asarray(seed, dtype=float)
        if seed.shape != (6,) or not np.all(np.isfinite(seed)):
            return nan, INVALID_INPUT
    q_all, exists = ik_all(T, seed=seed, mount=mount, a=a, b=b, h=h, hand=hand, tool=tool)
    if not exists.any():
        return nan, UNREACHABLE
    best, best_cost = None, math.inf
    for slot in range(8):
        if not exists[slot]:
            continue
        qw, ok = wrap_into_limits(q_all[slot], lower, upper)
        if not ok:
            continue
        if seed is None:
            return qw, OK
        cost = max(abs(wrap(qw[j] - seed[j])) for j in range(6))
        if cost < best_cost:
            best, best_cost = qw, cost
    if best is None:
        return nan, JOINT_LIMIT
    return best, OK


# ---------------------------------------------------------------- singularities, poses
def singularity(q, *, mount=MOUNT, a=A, b=B, h=H, hand=HAND, tool=None):
    """Distances to the three singularities, plus manipulability.

    wrist:    |sin wr0|  (el1 and wr1 axes aligned at 0).
    elbow:    |sin(el0 - phi)|, phi = atan2(h, b).  Equals |det| of the planar 2x2 Jacobian
              d(wrist centre in the arm plane)/d(sh1, el0) divided by a*hypot(b, h), and
              equals sqrt(1 - (K/L)^2), the margin of the type-2 equation (3). 0 when
              the elbow is stretched or folded.
    shoulder: distance (m) of the wrist centre from the sh0 axis, hypot(c'_x, c'_y).
    manipulability: sqrt(det(J J^T)) of the geometric Jacobian at the hand (tool) point.
    """
    sh0, sh1, el0 = float(q[0]), float(q[1]), float(q[2])
    s = np.array([a + b * math.cos(el0) + h * math.sin(el0), 0.0, -b * math.sin(el0) + h * math.cos(el0)])
    c = rot_z(sh0) @ rot_y(sh1) @ s  # eq. (2), relative to mount
    J = jacobian(q, mount=mount, a=a, b=b, h=h, hand=hand, tool=tool)
    return {
        "wrist": abs(math.sin(float(q[4]))),
        "elbow": abs(math.sin(el0 - math.atan2(h, b))),
        "shoulder": math.hypot(c[0], c[1]),
        "manipulability": math.sqrt(max(float(np.linalg.det(J @ J.T)), 0.0)),
    }


def pose_from(position, quat_xyzw):
    """(4, 4) pose from a position and a scalar-last quaternion (x, y, z, w), scipy order.

    Non-finite input or | |q| - 1 | > 1e-6 -> all-NaN matrix (no silent normalisation).
    Accepted quaternions use R = I + s w [v]x + s [v]x^2 form with s = 2/|q|^2, so R is an
    exact rotation even for |q| = 1 +- 1e-6.
    """
    x, y, z, w = (float(v) for v in quat_xyzw)
    p = np.asarray(position, dtype=float)
    n2 = x * x + y * y + z * z + w * w
    if not (np.all(np.isfinite(p)) and math.isfinite(n2)) or abs(math.sqrt(n2) - 1.0) > 1e-6:
        return np.full((4, 4), np.nan)
    s = 2.0 / n2
    R = np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
        ]
    )
    return _hom(R, p)
