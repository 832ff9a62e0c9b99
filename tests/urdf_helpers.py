"""URDF test helpers shared by test_urdf.py, test_robot.py and the fuzz registry (tests/fuzz/):
element builders for small URDFs and Pinocchio configurations.

Imported as a top-level module, as test_fuzz.py imports the fuzz package: pytest puts tests/ on sys.path (no
__init__.py, the default import mode), and the fuzz workers' subprocesses run with tests/ as their
working directory and on PYTHONPATH. The workers never need Pinocchio, so pin_q imports it itself.
"""

from __future__ import annotations

import math

import numpy as np

LIMIT = 'effort="10" velocity="5"'


def links(*names: str) -> str:
    """One empty <link> element per name, concatenated."""
    return "".join(f'<link name="{name}"/>' for name in names)


def joint_xml(name, jtype, parent, child, body: str) -> str:
    """A <joint> element: name, type, parent and child links, then body (origin, axis, limit, ...)."""
    return (
        f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/><child link="{child}"/>{body}</joint>'
    )


def joint(name, jtype, parent, child, xyz="0 0 0", rpy="0 0 0", axis=None, limits=None) -> str:
    """A <joint> element with an <origin>, an optional <axis> and optional (lower, upper) limits."""
    body = f'<origin xyz="{xyz}" rpy="{rpy}"/>'
    if axis is not None:
        body += f'<axis xyz="{axis}"/>'
    if limits is not None:
        body += f'<limit lower="{limits[0]}" upper="{limits[1]}" {LIMIT}/>'
    return joint_xml(name, jtype, parent, child, body)


def pin_q(pm, values: dict[str, float]) -> np.ndarray:
    """Pinocchio's configuration with the named joints at values (the others neutral)."""
    import pinocchio

    q = pinocchio.neutral(pm)
    for name, value in values.items():
        jm = pm.joints[pm.getJointId(name)]
        if jm.nq == 2:  # continuous joints: (cos, sin)
            q[jm.idx_q], q[jm.idx_q + 1] = math.cos(value), math.sin(value)
        else:
            q[jm.idx_q] = value
    return q
