"""The course's small arms and leg (RRR arm, three-joint arm, classic-DH leg, PRPRR arm), rebuilt and checked,
one sample at a time.

Every IK is Paul's method with :mod:`spotkin.reference.paul` and returns EVERY solution:
``(q (4, 3), valid (4,))``, slot = 2 * (theta1 root) + (type-6 root), NaN where invalid,
angles in (-pi, pi]. Each robot also exports a classic-DH table ``(rows, base, tool)``
with rows ``(sigma, a, alpha, d, theta)`` for ``spotkin.Chain.from_dh``.
DH(theta, d, a, alpha) = RotZ(theta) TransZ(d) TransX(a) RotX(alpha).

The course's RRR arm
-----------------
T1^0 = DH(q1, l1, 0, +90deg), T2^1 = DH(q2, 0, l2, 0), T3^2 = DH(q3, 0, 0, +90deg),
E = TransZ(l3) (each matches the printed matrix; the printed T3^0 is garbled, T4^0 is right):
    (R1)  p = ( c1 u, s1 u, l1 + v ),  u = l2 c2 + l3 s23,  v = l2 s2 - l3 c23.
Lengths: the text states l2 = 1.01, l3 = 0.8, but its worked solution uses l2 = 1.05
((T2^1)^-1 has -1.05; 2 * 1.05 * 1.4866 = 3.12186) and l3 = 0.89 ("0.89 S3"); the line
"1.1 c2 + 1.2 s23" mixes in the target's coordinates. Default: the worked lengths
(l1, l2, l3) = (1, 1.05, 0.89), so the worked theta2 values can be checked; the stated ones
are RRR_001_STATED_LENGTHS. Both reach p = (1, 1.1, 1.2).
IK. (T1^0)^-1 p = (c1 px + s1 py, pz - l1, s1 px - c1 py) = (u, v, 0):
    (R2)  px s1 - py c1 = 0                         type 2 -> q1 and q1 + pi (the text misses q1 + pi)
    (R3)  (T2^1)^-1 (u, v): l3 s3 = u c2 + v s2 - l2,  l3 c3 = u s2 - v c2
          type 6 with W = l3, X = u, Y = v, Z1 = -l2, Z2 = 0 -> (q2, q3).
The text's "T3^2 T4^3" has +C3 where -C3 belongs and takes q3 = atan2(a, b) instead of
atan2(a, -b); its q3 = -+11 deg fail FK.

The course's three-joint (3-DOF) arm
-------------------
T01 = DH(q1, a1, 0, +90deg); T12 = RotZ(q2) TransY(a2) (the printed translation (-a2 S2, a2 C2));
T23 = RotZ(q3) TransX(a3), with C3/S3 in its translation (the printed C2/S2 is the typo: only
C3/S3 gives the printed T03). Tool point M = origin of frame 3:
    (A1)  p = ( C1 rho, S1 rho, a1 + h ),  rho = a3 C23 - a2 S2,  h = a3 S23 + a2 C2.
The text's "z = a1 + a2 sin q2" is wrong; (A1) is the z of its own T03. DH rows:
RotZ(q2) TransY(a2) RotZ(q3) = RotZ(q2 + pi/2) TransX(a2) RotZ(q3 - pi/2), so theta offsets
+pi/2 and -pi/2.
IK, with no hole at q1 = 45 deg: (T01)^-1 p = (C1 x + S1 y, z - a1, S1 x - C1 y) = (rho, h, 0):
    (A2)  x S1 - y C1 = 0                           type 2 -> q1, q1 + pi; rho = C1 x + S1 y
          (replaces X = (x - y) / (C1 - S1), which divides by 0 at q1 = 45 deg)
    (A3)  (T12)^-1: a3 S3 = h C2 - rho S2 - a2,  a3 C3 = rho C2 + h S2
          type 6 with W = a3, X = h, Y = -rho, Z1 = -a2, Z2 = 0 -> (q2, q3).
The text gives no lengths; ARM_002_LENGTHS are illustrative.

The course's 3-DOF leg, classic DH with lateral offsets
----------------------------------------------------
Table (theta, a, d, alpha): 0->1 (q1, 0, h1, -90), 1->1' (q2, 0, h2, 90), 1'->2 (0, 0, l2, -90),
2->2' (q3, 0, h3, 90), 2'->3 (0, 0, l3, 0). Product (checked with sympy), H = h2 + h3:
    (L1)  x = C1 P - S1 H,  y = S1 P + C1 H,  z = h1 + l3 C23 + l2 C2,  P = l3 S23 + l2 S2.
    (L2)  J = d(x, y, z)/dq, differentiated here (the text's nine entries are wrong):
          [[-S1 P - C1 H,  C1 Q,  C1 l3 C23],
           [ C1 P - S1 H,  S1 Q,  S1 l3 C23],
           [ 0,           -P,    -l3 S23  ]],   Q = l3 C23 + l2 C2.
IK. (1T0)^-1 p = (C1 x + S1 y, h1 - z, -S1 x + C1 y) = (P, -Q, H):
    (L3)  -x S1 + y C1 = H                          type 2 -> two q1 (none if x^2 + y^2 < H^2)
    (L4)  (2T1)^-1 (u, w), u = C1 x + S1 y, w = h1 - z: l3 S3 = u C2 + w S2, l3 C3 = u S2 - w C2 - l2
          type 6 with W = l3, X = u, Y = w, Z1 = 0, Z2 = -l2 -> (q2, q3).
Three-joint chain: the fixed rows merge into 2T1 = RotZ(q2) TransZ(h2) TransY(-l2) and
3T2 = RotZ(q3) TransZ(h3) TransY(-l3) RotX(90), i.e. DH rows (q2 - 90deg, d h2, a l2, 0),
(q3, d h3, a l3, 0) and tool RotZ(90deg) RotX(90deg). The text gives no lengths;
LEG_003_LENGTHS are illustrative.
The course's PRPRR arm (the summary sheet's preferential-Jacobian exercise)
---------------------------------------------------------------------
The printed DHm table is garbled: its sigma row reads 0 0 0 0 0 (the name says 1 0 1 0 0), its
"r" row holds an angle (pi/2), its theta row puts q1 where a prismatic joint has a constant, and
the printed T_{i-1,i} (all with alpha = 0, T45 with both q5 and c5) match neither. Rebuilt here,
DHm rows (sigma, d, alpha, r, theta), T = RotX(alpha) TransX(d) RotZ(theta) TransZ(r):
    1  P  d1 = 1 (the table's a row)   alpha1 = 0                 r1 = q1, theta1 = 0
    2  R  d2 = 0                       alpha2 = 0                 theta2 = q2
    3  P  d3 = 0                       alpha3 = pi/2 (the "1")    r3 = q3, theta3 = -pi/2
    4  R  d4 = 0                       alpha4 = 0                 theta4 = q4
    5  R  d5 = 0                       alpha5 = pi/2              theta5 = q5 - pi/2
    tool  O6 = O5 + 0.1 x5 (the table has no row 6; illustrative)
alpha3 != 0 is forced (with alpha2 = alpha3 = 0 the two prismatic axes are parallel), as is
alpha5 != 0 (with d5 = 0, alpha5 = 0 puts joints 4 and 5 on one axis): a cylindrical arm (lift,
turn, reach) with a roll-pitch wrist. Only joints 1-3 enter J_3(2).
Hand derivation of J_3(2), for any alpha2, theta2, alpha3, d3, r3 (so the tests can vary them):
    column 1 (P): z1 in R2 = (R_12)^T e_z = RotZ(q2 + theta2)^T RotX(alpha2)^T e_z
                = ( sin(q2 + theta2) sin(alpha2), cos(q2 + theta2) sin(alpha2), cos(alpha2) ),  w = 0
    column 2 (R): z2 x O2O3 in R2, O2O3 = RotX(alpha3) (d3, 0, r3 + q3) = (d3, -sin(alpha3) r, cos(alpha3) r)
                with r = r3 + q3: v = (sin(alpha3) r, d3, 0),  w = (0, 0, 1)
    column 3 (P): z3 in R2 = RotX(alpha3) RotZ(theta3) e_z = (0, -sin(alpha3), cos(alpha3)),  w = 0
    columns 4, 5: 0 (joints after frame 3 do not move O3)
    (P1)  J_3(2) = [[s2 sa2,  sa3 (r3 + q3),  0,   0, 0],
                    [c2 sa2,  d3,            -sa3, 0, 0],
                    [ca2,     0,              ca3, 0, 0],
                    [0, 0, 0, 0, 0], [0, 0, 0, 0, 0],
                    [0,       1,              0,   0, 0]]
It depends on q2 and q3 only (on q3 only for the rebuilt arm, alpha2 = 0): the reason to express
O3's velocity in R2. For the rebuilt arm: v = (q3 q2', -q3', q1'), w = (0, 0, q2').
"""

from __future__ import annotations

import math

import numpy as np

from .paul import type2, type6

__all__ = [
    "ARM_002_LENGTHS",
    "LEG_003_LENGTHS",
    "PRPRR_004_PARAMS",
    "RRR_001_LENGTHS",
    "RRR_001_STATED_LENGTHS",
    "RRR_001_TARGET",
    "arm_002_dh",
    "arm_002_fk",
    "arm_002_ik",
    "dh",
    "leg_003_dh",
    "leg_003_dh_table",
    "leg_003_fk",
    "leg_003_ik",
    "leg_003_jacobian",
    "prprr_004_frames",
    "prprr_004_jacobian_3_in_2",
    "prprr_004_mdh",
    "rrr_001_dh",
    "rrr_001_fk",
    "rrr_001_ik",
]

RRR_001_LENGTHS = (1.0, 1.05, 0.89)  # (l1, l2, l3) used by the worked solution
RRR_001_STATED_LENGTHS = (1.0, 1.01, 0.8)  # (l1, l2, l3) as stated in the text
RRR_001_TARGET = (1.0, 1.1, 1.2)
ARM_002_LENGTHS = (0.10, 0.12, 0.09)  # (a1, a2, a3), illustrative
LEG_003_LENGTHS = (0.05, 0.03, 0.02, 0.11, 0.13)  # (h1, h2, h3, l2, l3), illustrative

_HALF_PI = math.pi / 2


def _rot_z(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)


def _rot_x(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], dtype=float)


def _trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Classic DH: RotZ(theta) TransZ(d) TransX(a) RotX(alpha)."""
    return _rot_z(theta) @ _trans(0, 0, d) @ _trans(a, 0, 0) @ _rot_x(alpha)


def _empty() -> tuple[np.ndarray, np.ndarray]:
    return np.full((4, 3), math.nan), np.zeros(4, dtype=bool)


def _paul_3r(first: tuple[float, float, float], second) -> tuple[np.ndarray, np.ndarray]:
    """Shared two-step Paul solve: q1 from type2(*first), then (q2, q3) from type6(*second(q1))."""
    q, valid = _empty()
    roots1, ok1 = type2(*first)
    for i in range(2):
        if not ok1[i]:
            continue
        t2, t3, ok6 = type6(*second(roots1[i]))
        for k in range(2):
            if ok6[k]:
                q[2 * i + k] = (roots1[i], t2[k], t3[k])
                valid[2 * i + k] = True
    return q, valid


# --- The course's RRR arm ------------------------------------------------------------------------


def rrr_001_fk(q, lengths=RRR_001_LENGTHS) -> np.ndarray:
    """T4^0 = T1^0 T2^1 T3^2 E (the course's RRR arm), (4, 4); position is (R1)."""
    l1, l2, l3 = lengths
    q1, q2, q3 = (float(v) for v in q)
    return dh(q1, l1, 0, _HALF_PI) @ dh(q2, 0, l2, 0) @ dh(q3, 0, 0, _HALF_PI) @ _trans(0, 0, l3)


def rrr_001_ik(p, lengths=RRR_001_LENGTHS) -> tuple[np.ndarray, np.ndarray]:
    """Every (q1, q2, q3) putting the tool at p: (R2) type 2 then (R3) type 6. (q (4, 3), valid (4,))."""
    l1, l2, l3 = lengths
    px, py, pz = (float(v) for v in p)

    def second(q1: float):
        u = math.cos(q1) * px + math.sin(q1) * py
        return l3, u, pz - l1, -l2, 0.0

    return _paul_3r((px, -py, 0.0), second)


def rrr_001_dh(lengths=RRR_001_LENGTHS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, base, tool) for ``Chain.from_dh``; rows (sigma, a, alpha, d, theta)."""
    l1, l2, l3 = lengths
    rows = np.array([(0, 0.0, _HALF_PI, l1, 0.0), (0, l2, 0.0, 0.0, 0.0), (0, 0.0, _HALF_PI, 0.0, 0.0)])
    return rows, np.eye(4), _trans(0, 0, l3)


# --- The course's three-joint arm ----------------------------------------------------------------------


def arm_002_fk(q, lengths=ARM_002_LENGTHS) -> np.ndarray:
    """T03 = T01 T12 T23 with T23's translation (a3 C3, a3 S3) (corrected), (4, 4)."""
    a1, a2, a3 = lengths
    q1, q2, q3 = (float(v) for v in q)
    T01 = dh(q1, a1, 0, _HALF_PI)
    T12 = _rot_z(q2) @ _trans(0, a2, 0)
    T23 = _rot_z(q3) @ _trans(a3, 0, 0)
    return T01 @ T12 @ T23


def arm_002_ik(p, lengths=ARM_002_LENGTHS) -> tuple[np.ndarray, np.ndarray]:
    """Every (q1, q2, q3) reaching p: (A2) type 2 then (A3) type 6. (q (4, 3), valid (4,))."""
    a1, a2, a3 = lengths
    x, y, z = (float(v) for v in p)

    def second(q1: float):
        rho = math.cos(q1) * x + math.sin(q1) * y
        return a3, z - a1, -rho, -a2, 0.0

    return _paul_3r((x, -y, 0.0), second)


def arm_002_dh(lengths=ARM_002_LENGTHS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, base, tool) for ``Chain.from_dh``; theta offsets +pi/2, -pi/2 absorb TransY(a2)."""
    a1, a2, a3 = lengths
    rows = np.array([(0, 0.0, _HALF_PI, a1, 0.0), (0, a2, 0.0, 0.0, _HALF_PI), (0, a3, 0.0, 0.0, -_HALF_PI)])
    return rows, np.eye(4), np.eye(4)


# --- The course's classic-DH leg ----------------------------------------------------------------------


def leg_003_dh_table(lengths=LEG_003_LENGTHS) -> np.ndarray:
    """The course's classic-DH leg: its five-row table as ``Chain.from_dh`` rows (sigma, a, alpha, d, theta).

    Rows 1' -> 2 and 2' -> 3 are fixed: use q = (q1, q2, 0, q3, 0) with a chain built on it.
    """
    h1, h2, h3, l2, l3 = lengths
    return np.array(
        [
            (0, 0.0, -_HALF_PI, h1, 0.0),
            (0, 0.0, _HALF_PI, h2, 0.0),
            (0, 0.0, -_HALF_PI, l2, 0.0),
            (0, 0.0, _HALF_PI, h3, 0.0),
            (0, 0.0, 0.0, l3, 0.0),
        ]
    )


def leg_003_fk(q, lengths=LEG_003_LENGTHS) -> np.ndarray:
    """3T0 as the product of the five DH matrices of the course's classic-DH leg, (4, 4); position is (L1)."""
    h1, h2, h3, l2, l3 = lengths
    q1, q2, q3 = (float(v) for v in q)
    return (
        dh(q1, h1, 0, -_HALF_PI)
        @ dh(q2, h2, 0, _HALF_PI)
        @ dh(0, l2, 0, -_HALF_PI)
        @ dh(q3, h3, 0, _HALF_PI)
        @ dh(0, l3, 0, 0)
    )


def leg_003_jacobian(q, lengths=LEG_003_LENGTHS) -> np.ndarray:
    """d(x, y, z)/dq of (L1), written out as (L2), (3, 3)."""
    _, h2, h3, l2, l3 = lengths
    q1, q2, q3 = (float(v) for v in q)
    s1, c1 = math.sin(q1), math.cos(q1)
    s2, c2 = math.sin(q2), math.cos(q2)
    s23, c23 = math.sin(q2 + q3), math.cos(q2 + q3)
    P = l3 * s23 + l2 * s2
    Q = l3 * c23 + l2 * c2
    H = h2 + h3
    return np.array(
        [
            [-s1 * P - c1 * H, c1 * Q, c1 * l3 * c23],
            [c1 * P - s1 * H, s1 * Q, s1 * l3 * c23],
            [0.0, -P, -l3 * s23],
        ]
    )


def leg_003_ik(p, lengths=LEG_003_LENGTHS) -> tuple[np.ndarray, np.ndarray]:
    """Every (q1, q2, q3) putting the foot at p: (L3) type 2 then (L4) type 6. (q (4, 3), valid (4,))."""
    h1, h2, h3, l2, l3 = lengths
    x, y, z = (float(v) for v in p)

    def second(q1: float):
        u = math.cos(q1) * x + math.sin(q1) * y
        return l3, u, h1 - z, 0.0, -l2

    return _paul_3r((-x, y, h2 + h3), second)


def leg_003_dh(lengths=LEG_003_LENGTHS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, base, tool) of the merged three-joint chain for ``Chain.from_dh``; same 3T0 as leg_003_fk."""
    h1, h2, h3, l2, l3 = lengths
    rows = np.array([(0, 0.0, -_HALF_PI, h1, 0.0), (0, l2, 0.0, h2, -_HALF_PI), (0, l3, 0.0, h3, 0.0)])
    return rows, np.eye(4), _rot_z(_HALF_PI) @ _rot_x(_HALF_PI)


# --- The course's PRPRR arm ----------------------------------------------------------------------

PRPRR_004_PARAMS = {
    "d1": 1.0,
    "alpha2": 0.0,
    "theta2": 0.0,
    "alpha3": _HALF_PI,
    "d3": 0.0,
    "r3": 0.0,
    "theta3": -_HALF_PI,
    "alpha4": 0.0,
    "alpha5": _HALF_PI,
    "theta5": -_HALF_PI,
    "tool": 0.1,
}


def prprr_004_mdh(params=PRPRR_004_PARAMS) -> tuple[np.ndarray, np.ndarray]:
    """(rows (5, 5) as (sigma, d, alpha, r, theta) for ``spotkin.Chain.from_mdh``, tool (4, 4))."""
    P = params
    rows = np.array(
        [
            (1, P["d1"], 0.0, 0.0, 0.0),
            (0, 0.0, P["alpha2"], 0.0, P["theta2"]),
            (1, P["d3"], P["alpha3"], P["r3"], P["theta3"]),
            (0, 0.0, P["alpha4"], 0.0, 0.0),
            (0, 0.0, P["alpha5"], 0.0, P["theta5"]),
        ]
    )
    return rows, _trans(P["tool"], 0, 0)


def _mdh(d: float, alpha: float, r: float, theta: float) -> np.ndarray:
    return _rot_x(alpha) @ _trans(d, 0, 0) @ _rot_z(theta) @ _trans(0, 0, r)


def prprr_004_frames(q, params=PRPRR_004_PARAMS) -> list[np.ndarray]:
    """[T_00 = I, T_01, ..., T_05, T_06] of the rebuilt arm, multiplied out from its DHm rows."""
    P = params
    q1, q2, q3, q4, q5 = (float(v) for v in q)
    links = [
        _mdh(P["d1"], 0.0, q1, 0.0),
        _mdh(0.0, P["alpha2"], 0.0, P["theta2"] + q2),
        _mdh(P["d3"], P["alpha3"], P["r3"] + q3, P["theta3"]),
        _mdh(0.0, P["alpha4"], 0.0, q4),
        _mdh(0.0, P["alpha5"], 0.0, P["theta5"] + q5),
        _trans(P["tool"], 0, 0),
    ]
    out = [np.eye(4)]
    for link in links:
        out.append(out[-1] @ link)
    return out


def prprr_004_jacobian_3_in_2(q, params=PRPRR_004_PARAMS) -> np.ndarray:
    """J_3(2) (6, 5), the hand derivation (P1) of the module docstring."""
    P = params
    q2, q3 = float(q[1]), float(q[2])
    sa2, ca2 = math.sin(P["alpha2"]), math.cos(P["alpha2"])
    sa3, ca3 = math.sin(P["alpha3"]), math.cos(P["alpha3"])
    s2, c2 = math.sin(q2 + P["theta2"]), math.cos(q2 + P["theta2"])
    J = np.zeros((6, 5))
    J[:3, 0] = (s2 * sa2, c2 * sa2, ca2)
    J[:3, 1] = (sa3 * (P["r3"] + q3), P["d3"], 0.0)
    J[3:, 1] = (0.0, 0.0, 1.0)
    J[:3, 2] = (0.0, -sa3, ca3)
    return J
