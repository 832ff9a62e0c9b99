"""Vec3, Quaternion and SE3Pose to and from arrays. Part of :mod:`spotkin.sdk` (documented there)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_real, check_trailing
from .common import (
    _LAST_ROW_TOLERANCE,
    Message,
    _first_leaf,
    _gather,
    _matrix_quats,
    _nested,
    _quat_matrices,
    _read_quat,
    _read_se3,
    _read_vec3,
    _rotation_ok,
    _se3_matrices,
    geometry_pb2,
)

# ---- geometry: Vec3, Quaternion, SE3Pose --------------------------------------------------------------


def vec3_to_array(vec) -> np.ndarray:
    """(3,) [x, y, z] float64 from a ``bosdyn.api.Vec3`` or a ``math_helpers.Vec3``; (..., 3) from a
    (nested) sequence of them. ``TypeError`` for anything else."""
    return _gather(vec, "vec", _read_vec3, 3, "a bosdyn.api.Vec3 or math_helpers.Vec3")


def array_to_vec3(p: ArrayLike):
    """A ``bosdyn.api.Vec3`` from p (3,); nested lists of them from p (..., 3). NaN stays NaN."""
    p = as_real(p, "p", np.float64)
    lead = check_trailing(p, "p", (3,))
    flat = p.reshape(-1, 3).tolist()
    return _nested([geometry_pb2.Vec3(x=x, y=y, z=z) for x, y, z in flat], lead)


def quat_to_matrix(quat) -> np.ndarray:
    """(3, 3) rotation matrix from a quaternion in the SDK's (w, x, y, z) order.

    ``quat`` is a ``bosdyn.api.Quaternion``, a ``math_helpers.Quat``, a (nested) sequence of them
    (giving (..., 3, 3)), or a real array (..., 4) holding (w, x, y, z) (the scalar first, as the
    SDK; not scipy's (x, y, z, w)). A quaternion whose norm differs from 1 by more than 1e-6, or
    with NaN or Inf, gives a NaN matrix for that sample only. The result is float64.
    """
    leaf = _first_leaf(quat)
    if leaf is None or isinstance(leaf, Message) or type(leaf).__module__ == "bosdyn.client.math_helpers":
        wxyz = _gather(quat, "quat", _read_quat, 4, "a bosdyn.api.Quaternion or math_helpers.Quat")
    else:
        wxyz = as_real(quat, "quat", np.float64)
        check_trailing(wxyz, "quat", (4,))
    return _quat_matrices(wxyz)


def matrix_to_quat(R: ArrayLike):
    """A ``bosdyn.api.Quaternion`` (w, x, y, z; w >= 0) from a rotation matrix R (3, 3); nested lists
    of them from R (..., 3, 3). A matrix that is not a rotation (``max |R^T R - I| > 1e-6``,
    ``det R <= 0``, NaN or Inf) gives a quaternion of NaN for that sample only."""
    R = as_real(R, "R", np.float64)
    lead = check_trailing(R, "R", (3, 3))
    q = _matrix_quats(R)
    q[~_rotation_ok(R)] = np.nan
    flat = q.reshape(-1, 4).tolist()
    return _nested([geometry_pb2.Quaternion(w=w, x=x, y=y, z=z) for w, x, y, z in flat], lead)


def se3_to_matrix(pose) -> np.ndarray:
    """(4, 4) ``a <- b`` transform from a ``bosdyn.api.SE3Pose`` or ``math_helpers.SE3Pose``
    (``a_tform_b``); (..., 4, 4) from a (nested) sequence of them.

    An unset rotation is the identity (as the SDK reads it). An invalid quaternion (see
    :func:`quat_to_matrix`), NaN or Inf give a NaN matrix for that sample only. float64.
    """
    return _se3_matrices(_gather(pose, "pose", _read_se3, 7, "a bosdyn.api.SE3Pose or math_helpers.SE3Pose"))


def matrix_to_se3(T: ArrayLike):
    """A ``bosdyn.api.SE3Pose`` from a rigid transform T (4, 4) (``a_tform_b`` for T = a <- b);
    nested lists of them from T (..., 4, 4).

    The rotation is a unit quaternion with w >= 0. A sample that is not a rigid transform (last
    row not [0, 0, 0, 1] within 1e-9, ``max |R^T R - I| > 1e-6``, ``det R <= 0``, NaN or Inf) gives
    a pose whose seven numbers are NaN, that sample only.
    """
    T = as_real(T, "T", np.float64)
    lead = check_trailing(T, "T", (4, 4))
    q = _matrix_quats(T[..., :3, :3])
    with np.errstate(invalid="ignore"):
        row = np.abs(T[..., 3, :] - [0.0, 0.0, 0.0, 1.0]).max(axis=-1, initial=0.0)
    ok = _rotation_ok(T[..., :3, :3]) & (row <= _LAST_ROW_TOLERANCE) & np.isfinite(T[..., :3, 3]).all(-1)
    values = np.concatenate([T[..., :3, 3], q], axis=-1)
    values[~ok] = np.nan
    messages = [
        geometry_pb2.SE3Pose(
            position=geometry_pb2.Vec3(x=x, y=y, z=z), rotation=geometry_pb2.Quaternion(w=w, x=qx, y=qy, z=qz)
        )
        for x, y, z, w, qx, qy, qz in values.reshape(-1, 7).tolist()
    ]
    return _nested(messages, lead)
