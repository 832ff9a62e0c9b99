"""Closed-form dynamics from Lagrange's equations (docs/dynamics.md): a planar 2R arm and an RRR arm of
uniform rods, the hand derivations the reference dynamics (:mod:`spotkin.reference.dynamics`) are
checked against."""

from __future__ import annotations

import math

import numpy as np

# --------------------------------------------------------------------------- closed forms (Lagrange)


def planar_2r_mass_matrix(q, masses, lengths) -> np.ndarray:
    """A(q) of a planar 2R arm of uniform rods (docs/dynamics.md): joint 1 at the origin, link i of
    mass m_i and length l_i, q2 relative to link 1.
        A11 = m1 l1²/3 + m2 (l1² + l2²/3 + l1 l2 c2),  A12 = m2 (l2²/3 + l1 l2 c2 / 2),  A22 = m2 l2²/3"""
    (m1, m2), (l1, l2) = masses, lengths
    c2 = math.cos(q[1])
    a11 = m1 * l1**2 / 3 + m2 * (l1**2 + l2**2 / 3 + l1 * l2 * c2)
    a12 = m2 * (l2**2 / 3 + l1 * l2 * c2 / 2)
    return np.array([[a11, a12], [a12, m2 * l2**2 / 3]])


def planar_2r_gravity(q, masses, lengths, g0=9.81) -> np.ndarray:
    """G(q) of the planar 2R arm with gravity -g0 along the plane's y axis (angles from x):
    G1 = g0 ((m1 / 2 + m2) l1 c1 + m2 l2 c12 / 2),  G2 = g0 m2 l2 c12 / 2"""
    (m1, m2), (l1, l2) = masses, lengths
    c1, c12 = math.cos(q[0]), math.cos(q[0] + q[1])
    return np.array([g0 * ((m1 / 2 + m2) * l1 * c1 + m2 * l2 * c12 / 2), g0 * m2 * l2 * c12 / 2])


def rrr_mass_matrix(q, masses, lengths) -> np.ndarray:
    """A(q) of the course's RRR arm (DH(q1, l1, 0, 90°), DH(q2, 0, l2, 0), DH(q3, 0, 0, 90°), tool
    TransZ(l3)) with uniform thin rods: link 1 along the vertical axis 1 (no inertia about it), link 2
    from joint 2 to joint 3, link 3 from joint 3 to the tool. With r3 = l2 c2 + l3 s23 / 2:
        A11 = m2 l2² c2² / 3 + m3 r3² + m3 l3² s23² / 12,   A12 = A13 = 0,
        A22 = m2 l2² / 3 + m3 (l2² + l3² / 3 + l2 l3 s3),  A23 = m3 (l3² / 3 + l2 l3 s3 / 2),
        A33 = m3 l3² / 3."""
    (_, m2, m3), (_, l2, l3) = masses, lengths
    c2, s3, s23 = math.cos(q[1]), math.sin(q[2]), math.sin(q[1] + q[2])
    r3 = l2 * c2 + l3 * s23 / 2
    a11 = m2 * l2**2 * c2**2 / 3 + m3 * r3**2 + m3 * l3**2 * s23**2 / 12
    a22 = m2 * l2**2 / 3 + m3 * (l2**2 + l3**2 / 3 + l2 * l3 * s3)
    a23 = m3 * (l3**2 / 3 + l2 * l3 * s3 / 2)
    return np.array([[a11, 0.0, 0.0], [0.0, a22, a23], [0.0, a23, m3 * l3**2 / 3]])


def rrr_gravity(q, masses, lengths, g0=9.81) -> np.ndarray:
    """G(q) of the course's RRR arm with gravity -g0 along z0 (U = g0 sum m_i z_i):
    G1 = 0,  G2 = g0 (m2 l2 c2 / 2 + m3 (l2 c2 + l3 s23 / 2)),  G3 = g0 m3 l3 s23 / 2"""
    (_, m2, m3), (_, l2, l3) = masses, lengths
    c2, s23 = math.cos(q[1]), math.sin(q[1] + q[2])
    return np.array([0.0, g0 * (m2 * l2 * c2 / 2 + m3 * (l2 * c2 + l3 * s23 / 2)), g0 * m3 * l3 * s23 / 2])
