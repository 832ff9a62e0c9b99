"""Mass properties of chains and robots: the data the dynamics consume.

:class:`LinkInertials` holds one rigid body per joint of a chain: the body moved by joint j,
expressed in frame j + 1 of :meth:`spotkin.Chain.frames` (the frame after joint j's motion; for a
chain from a URDF, the child link frame of joint j).

:func:`tree_of` describes a chain (fixed base) or a whole robot (floating base) as a kinematic tree:
per moving joint its parent, placement, axis, type and body inertial. This is the model the
reference dynamics (:mod:`spotkin.reference.dynamics`) take.

Merging (the rule :meth:`spotkin.Robot.chain` and :func:`tree_of` follow, as Pinocchio merges fixed
children and as its ``buildReducedModel`` locks joints): every link rigidly attached to a moving body
adds its mass, centre of mass and inertia (parallel-axis theorem) to that body. A joint that is not one
of the moving joints is locked at 0, so the subtree it carries is rigid and merges into the body it
hangs from: a gripper finger on an arm chain joins the wrist body. For a fixed-base chain, the base
link and everything that hangs from it without passing through one of the chain's joints (the body and
the other legs, for a leg chain) is not part of the chain's dynamics. See ``docs/dynamics.md``.
"""

from __future__ import annotations

from ._support.public import publish
from .dynamics.inertia import LinkInertials, Tree, link_inertials, merge_inertials, model_tree, tree_of
from .dynamics.inertia import chain_tree as chain_tree

__all__ = [
    "LinkInertials",
    "Tree",
    "link_inertials",
    "merge_inertials",
    "model_tree",
    "tree_of",
]

publish(__name__, globals(), __all__)
