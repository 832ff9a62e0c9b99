"""The fuzz registry's entries for ``spotkin.sdk`` (issue 19), the optional Spot SDK interop.

``tests/fuzz/registry.py`` calls :func:`register_entries` once its own entries are made; without
the SDK installed nothing is registered (and nothing of ``spotkin.sdk`` is public there either).

The slots hold real ``bosdyn.api`` messages, the SDK's ``math_helpers`` objects, nested lists of them,
arrays, and hostile values (None, strings, other message types, NaN and Inf fields, non-unit
quaternions, loops in frame trees, NaN joint targets...). The probes judge every result against the
SDK's own helpers (``math_helpers``, ``frame_helpers``, ``RobotCommandBuilder``), scipy, and plain
readings of the message fields.

The entries are in :mod:`fuzz.sdk_conversions` (messages to arrays and back), :mod:`fuzz.sdk_frames`
(frame trees), :mod:`fuzz.sdk_joints` (joint states), :mod:`fuzz.sdk_feet` and
:mod:`fuzz.sdk_commands` (joint commands); the messages they build and read in
:mod:`fuzz.sdk_messages`. Those modules import the SDK: they are imported only when it is installed.
"""

from __future__ import annotations


def register_entries() -> None:
    try:  # the SDK, and spotkin.sdk (which needs it)
        import bosdyn.api
        import bosdyn.client.robot_command  # noqa: F401

        import spotkin.sdk  # noqa: F401
    except ImportError:  # the optional extra is not installed
        return
    from . import sdk_commands, sdk_conversions, sdk_feet, sdk_frames, sdk_joints

    sdk_conversions.register_entries()
    sdk_frames.register_entries()
    sdk_joints.register_entries()
    sdk_feet.register_entries()
    sdk_commands.register_entries()
