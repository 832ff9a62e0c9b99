"""Homogeneous-transform helpers against the reference elementary matrices."""

from __future__ import annotations

import numpy as np
import pytest

import spotkin as sk
from spotkin.reference import chain as ref


def test_elementary_rotations_match_reference(rng):
    for angle in rng.uniform(-4, 4, 20):
        np.testing.assert_allclose(sk.rotation_x(angle), ref.rot_x(angle), atol=1e-15)
        np.testing.assert_allclose(sk.rotation_z(angle), ref.rot_z(angle), atol=1e-15)
        c, s = np.cos(angle), np.sin(angle)
        expected_y = np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]])
        np.testing.assert_allclose(sk.rotation_y(angle), expected_y, atol=1e-15)


def test_batched_helpers_broadcast(rng):
    angles = rng.uniform(-1, 1, (4, 2))
    assert sk.rotation_y(angles).shape == (4, 2, 4, 4)
    p = rng.uniform(-1, 1, (4, 1, 3))
    T = sk.transform(sk.rotation_z(angles)[..., :3, :3], p)
    assert T.shape == (4, 2, 4, 4)
    np.testing.assert_array_equal(T[..., :3, 3], np.broadcast_to(p, (4, 2, 3)))
    np.testing.assert_array_equal(sk.translation(p)[..., :3, 3], p)


def test_helpers_reject_bad_shapes_and_types():
    with pytest.raises(ValueError, match=r"p must have shape \(\.\.\., 3\)"):
        sk.translation([1, 2])
    with pytest.raises(ValueError, match=r"R must have shape \(\.\.\., 3, 3\)"):
        sk.transform(np.eye(4), [0, 0, 0])
    with pytest.raises(TypeError, match="angle must be a real numeric array"):
        sk.rotation_x("a")
