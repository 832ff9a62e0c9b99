"""Per-target outcome codes shared by every solver."""

from __future__ import annotations

from enum import IntEnum

from .. import _core

__all__ = ["Status"]


class Status(IntEnum):
    """Outcome of one IK target. Arrays of statuses are int8 arrays of these values."""

    OK = 0
    """A solution within the joint limits."""
    UNREACHABLE = 1
    """No geometric solution; see each solver for its documented fallback."""
    JOINT_LIMIT = 2
    """Geometric solutions exist, but none is within the joint limits; q is NaN."""
    INVALID_INPUT = 3
    """NaN or Inf in the input, or a malformed pose; q is NaN."""


_core._register_status(tuple(Status))
