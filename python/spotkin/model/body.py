"""Whole-body kinematics helpers: body poses in every accepted form.

A body pose is one of

- ``(..., 6)`` ``[x, y, z, a, b, c]``: position, then Euler angles in the sequence
  ``seq`` (scipy's names). The default ``"XYZ"`` is intrinsic X, Y', Z'' (Tait–Bryan,
  as in the course this library follows): R = Rx(a) Ry(b) Rz(c). Lower case is
  extrinsic: ``"xyz"`` gives R = Rz(c) Ry(b) Rx(a), ROS roll-pitch-yaw. Pass the same
  ``seq`` to every call that reads the pose;
- ``(..., 4, 4)`` homogeneous transforms (world <- body);
- ``(..., 7)`` ``[x, y, z, qx, qy, qz, qw]`` (scipy's scalar-last quaternions).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _core

__all__ = ["EULER_SEQUENCES", "body_transform"]

_AXES = {"x": 0, "y": 1, "z": 2}
EULER_SEQUENCES = tuple(
    s
    for case in (str.upper, str.lower)
    for s in (case(a + b + c) for a in "xyz" for b in "xyz" for c in "xyz")
    if s[0] != s[1] and s[1] != s[2]
)
"""Every accepted ``seq``: the 12 intrinsic (upper case) and 12 extrinsic (lower case)
Tait–Bryan and proper Euler sequences, as in scipy."""

FORMAT_EULER, FORMAT_MATRIX, FORMAT_QUATERNION = 0, 1, 2


def _sequence(seq: str) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    axes = tuple(_AXES[ch.lower()] for ch in seq)
    if seq.isupper():  # intrinsic: R = R_0(a) R_1(b) R_2(c)
        return axes, (0, 1, 2)
    # extrinsic: R = R_2(c) R_1(b) R_0(a)
    return (axes[2], axes[1], axes[0]), (2, 1, 0)


_PARSED = {seq: _sequence(seq) for seq in EULER_SEQUENCES}
# The core's packed form: axis[0] + 3 axis[1] + 9 axis[2], + 27 for reversed angle order.
_CODES = {
    seq: axes[0] + 3 * axes[1] + 9 * axes[2] + (27 if order[0] == 2 else 0)
    for seq, (axes, order) in _PARSED.items()
}
_SEQ_ERROR = "seq must be one of scipy's Euler sequences, e.g. 'XYZ' or 'xyz', got {!r}"


def parse_sequence(seq: str) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    """(axes, order) such that R = R_axes[0](angle[order[0]]) R_axes[1](...) R_axes[2](...)."""
    try:
        return _PARSED[seq]
    except (KeyError, TypeError):
        raise ValueError(_SEQ_ERROR.format(seq)) from None


def sequence_code(seq: str) -> int:
    """The packed int the core takes for an Euler sequence."""
    try:
        return _CODES[seq]
    except (KeyError, TypeError):
        raise ValueError(_SEQ_ERROR.format(seq)) from None


def pose_format(body_pose: np.ndarray) -> tuple[int, tuple[int, ...]]:
    """(format code, leading shape) of a body-pose array."""
    shape = body_pose.shape
    last = shape[-1] if shape else None
    if last == 6:
        return FORMAT_EULER, shape[:-1]
    if shape[-2:] == (4, 4):
        return FORMAT_MATRIX, shape[:-2]
    if last == 7:
        return FORMAT_QUATERNION, shape[:-1]
    raise ValueError(
        "body_pose must have shape (..., 6) [x, y, z, a, b, c], (..., 4, 4) or (..., 7) "
        f"[x, y, z, qx, qy, qz, qw], got {shape}"
    )


def _elementary(axis: int, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    R = np.zeros((*angle.shape, 3, 3))
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., j, i] = s
    R[..., i, j] = -s
    return R


def body_transform(body_pose: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None) -> np.ndarray:
    """The world <- body transform (..., 4, 4) of body poses in any accepted form.

    Poses are checked as :meth:`spotkin.Robot.body_ik` checks them, and an invalid one
    gives a NaN transform for that sample only: a matrix whose last row is not
    ``[0, 0, 0, 1]`` (1e-9) or whose rotation is not one (``max |R^T R - I| > 1e-6`` or
    ``det R <= 0``), a quaternion whose norm is not 1 within 1e-6 (never renormalised:
    it is converted with s = 2 / |q|^2), NaN or Inf. A valid matrix comes back as given.
    The result is float64. Non-numeric or masked input raises ``TypeError``, a shape other
    than (..., 6), (..., 4, 4), (..., 7) ``ValueError``, naming ``body_pose``; ``seq`` is
    checked for every form. ``out``: a float64 array of the result's shape to write into.
    """
    return _core.body_transform(body_pose, sequence_code(seq), out)


def unchecked_transform(pose: np.ndarray, seq: str = "XYZ") -> np.ndarray:
    """body_transform without its checks (float64 poses): for callers that check poses
    their own way (the trajectories normalise quaternions first)."""
    fmt, lead = pose_format(pose)
    axes, order = parse_sequence(seq)
    return _transform_of(pose, fmt, lead, axes, order)


def _transform_of(pose, fmt, lead, axes, order) -> np.ndarray:
    if fmt == FORMAT_MATRIX:
        return pose.copy()
    T = np.zeros((*lead, 4, 4))
    T[..., 3, 3] = 1.0
    T[..., :3, 3] = pose[..., :3]
    if fmt == FORMAT_EULER:
        R = np.broadcast_to(np.eye(3), (*lead, 3, 3))
        for k in range(3):
            R = R @ _elementary(axes[k], pose[..., 3 + order[k]])
    else:
        x, y, z, w = np.moveaxis(pose[..., 3:], -1, 0)
        s = 2.0 / (x * x + y * y + z * z + w * w)
        R = np.stack(
            [
                np.stack([1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)], -1),
                np.stack([s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)], -1),
                np.stack([s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)], -1),
            ],
            -2,
        )
    T[..., :3, :3] = R
    return T
