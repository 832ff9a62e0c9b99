"""Reference kinematics of URDF chains and roll-pitch-pitch legs, one sample at a time.

Slow and obvious on purpose: plain NumPy and ``math``, straight from the formulas.

URDF semantics: a joint moves its child link as ``origin · Rot(axis, q)`` (revolute,
continuous) or ``origin · Trans(axis · q)`` (prismatic). A chain (see
``spotkin.urdf.ChainData``) merges the fixed joints: with ``F_0 = I``,

    (U1)  F_{j+1} = F_j · placements[j] · M_j(q_j),    tip = F_n · tool.

Geometric Jacobian of the tool origin p in the base frame, column j with z_j the joint
axis and o_j the joint origin (both in the base frame):

    (U2)  revolute [z_j × (p − o_j); z_j],   prismatic [z_j; 0].

Roll-pitch-pitch leg (``spotkin.urdf.LegSpec``), foot in the leg frame:

    (R1)  p = Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c)).
"""

from __future__ import annotations

import math

import numpy as np


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw: Rz(yaw) · Ry(pitch) · Rx(roll), (3, 3)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    Ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    Rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return Rz @ Ry @ Rx


def axis_angle_matrix(axis, angle: float) -> np.ndarray:
    """Rodrigues: R = I + sin(angle) K + (1 − cos(angle)) K², K = [u]×, u = axis / |axis|."""
    x, y, z = (float(v) for v in axis)
    norm = math.sqrt(x * x + y * y + z * z)
    x, y, z = x / norm, y / norm, z / norm
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def joint_motion(axis, joint_type: int, q: float) -> np.ndarray:
    """The (4, 4) motion of one joint: Rot(axis, q) for type 0, Trans(axis · q) for type 1."""
    M = np.eye(4)
    if joint_type == 1:
        M[:3, 3] = np.asarray(axis, dtype=float) * q
    else:
        M[:3, :3] = axis_angle_matrix(axis, q)
    return M


def chain_frames(chain_data, q) -> np.ndarray:
    """(n + 2, 4, 4): [I (base), child link frames of joints 0..n-1 after their motion, tool] (U1)."""
    n = len(chain_data.joint_names)
    q = [float(v) for v in np.ravel(q)]
    if len(q) != n:
        raise ValueError(f"expected {n} joint values, got {len(q)}")
    out = np.empty((n + 2, 4, 4))
    T = np.eye(4)
    out[0] = T
    for j in range(n):
        T = T @ chain_data.placements[j] @ joint_motion(chain_data.axes[j], int(chain_data.types[j]), q[j])
        out[j + 1] = T
    out[n + 1] = T @ chain_data.tool
    return out


def chain_fk(chain_data, q) -> np.ndarray:
    """The (4, 4) tool frame in the base frame (U1)."""
    return chain_frames(chain_data, q)[-1]


def chain_jacobian(chain_data, q) -> np.ndarray:
    """(6, n) geometric Jacobian [v; w] of the tool origin, in the base frame (U2)."""
    F = chain_frames(chain_data, q)
    n = len(chain_data.joint_names)
    p = F[-1][:3, 3]
    J = np.zeros((6, n))
    for j in range(n):
        joint_frame = F[j] @ chain_data.placements[j]  # the motion does not move the axis
        z = joint_frame[:3, :3] @ np.asarray(chain_data.axes[j], dtype=float)
        o = joint_frame[:3, 3]
        if int(chain_data.types[j]) == 1:
            J[:3, j] = z
        else:
            J[:3, j] = np.cross(z, p - o)
            J[3:, j] = z
    return J


def rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rpp_leg_fk(leg_spec, q) -> np.ndarray:
    """Foot position (3,) in the leg frame from (R1)."""
    q1, q2, q3 = (float(v) for v in np.ravel(q))
    s1, s2, s3 = (float(v) for v in leg_spec.signs)
    a, b, c = (np.asarray(v, dtype=float) for v in (leg_spec.a, leg_spec.b, leg_spec.c))
    return rot_x(s1 * q1) @ (a + rot_y(s2 * q2) @ (b + rot_y(s3 * q3) @ c))
