"""Mass properties: the implementation of :mod:`spotkin.inertia` (documented there)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._support.boundary import as_index, as_real
from .._support.transforms import rotation_x, rotation_z, translation

__all__ = ["LinkInertials", "Tree", "link_inertials", "merge_inertials", "model_tree", "tree_of"]


class LinkInertials(NamedTuple):
    """Mass properties of n rigid bodies, row j in body j's own frame."""

    mass: np.ndarray
    """(n,) kg, >= 0."""
    com: np.ndarray
    """(n, 3) m: the centre of mass in the body's frame."""
    inertia: np.ndarray
    """(n, 3, 3) kg m²: the rotational inertia about the centre of mass, in the body frame's axes
    (symmetric positive semidefinite)."""


class Tree(NamedTuple):
    """A kinematic tree with its mass properties, as :func:`tree_of` builds it.

    Body j is moved by joint j. Its frame is ``F_j = F_parent · placements[j] · M_j(q_j)``, with
    ``M_j`` the rotation about (type 0) or translation along (type 1) ``axes[j]`` and ``F_-1`` the
    root frame: the world for a fixed base, the floating body for a floating base.
    """

    joint_names: tuple[str, ...] | None
    """The joints' names (URDF names), in the order of q."""
    parents: np.ndarray
    """(n,) int64: the index of the body each joint hangs from, -1 for the root."""
    placements: np.ndarray
    """(n, 4, 4): joint j's frame in its parent body's frame, at q_j = 0."""
    axes: np.ndarray
    """(n, 3): unit joint axes, in the joint's frame (also the body's frame)."""
    types: np.ndarray
    """(n,) int8: 0 revolute, 1 prismatic."""
    inertials: LinkInertials
    """Body j's mass properties, in body j's frame."""
    root: LinkInertials | None
    """The floating body's mass properties (mass (), com (3,), inertia (3, 3)) in its own frame;
    None for a fixed base."""
    feet: np.ndarray
    """(k,) int64: the body each foot belongs to (empty for a chain)."""
    foot_points: np.ndarray
    """(k, 3): each foot's contact point in its body's frame."""
    foot_names: tuple[str, ...]
    """The legs' names, one per foot."""


def _shaped(value: ArrayLike, name: str, shape: tuple) -> np.ndarray:
    array = as_real(value, name, np.float64)
    if array.shape != shape:
        expected = "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite")
    return np.array(array, dtype=np.float64)


def link_inertials(
    mass: ArrayLike, com: ArrayLike, inertia: ArrayLike, n: int | None = None
) -> LinkInertials:
    """Checked, read-only :class:`LinkInertials` from mass (n,), com (n, 3) and inertia (n, 3, 3).

    ``TypeError`` for non-numeric input or a non-integer ``n``; ``ValueError`` naming the argument
    for a wrong shape, a negative ``n``, a non-finite value, a negative mass, or an inertia that is
    not symmetric (to 1e-9 of its largest entry, then symmetrised) or not positive semidefinite (an
    eigenvalue below -1e-9 of its trace).
    """
    mass_arr = as_real(mass, "mass", np.float64)
    if n is None:
        if mass_arr.ndim != 1:
            raise ValueError(f"mass must have shape (n,), got {mass_arr.shape}")
        n = mass_arr.shape[0]
    else:
        n = as_index(n, "n")  # 1.5, True, "3": TypeError
        if n < 0:
            raise ValueError(f"n must be a count >= 0, got {n}")
    mass_arr = _shaped(mass_arr, "mass", (n,))
    if (mass_arr < 0).any():
        raise ValueError(f"mass must be >= 0, got {mass_arr.tolist()}")
    com_arr = _shaped(com, "com", (n, 3))
    inertia_arr = _shaped(inertia, "inertia", (n, 3, 3))
    for j in range(n):
        matrix = inertia_arr[j]
        with np.errstate(over="ignore", invalid="ignore"):  # near the largest float: Inf fails the checks
            scale = max(float(np.abs(matrix).max()), 1e-300)
            if not np.abs(matrix - matrix.T).max() <= 1e-9 * scale:
                raise ValueError(f"inertia[{j}] must be symmetric, got {matrix.tolist()}")
            matrix = matrix / 2 + matrix.T / 2
            trace = float(np.trace(matrix))
            if not float(np.linalg.eigvalsh(matrix).min()) >= -1e-9 * max(abs(trace), 1e-300):
                raise ValueError(f"inertia[{j}] must be positive semidefinite, got {matrix.tolist()}")
        inertia_arr[j] = matrix
    for array in (mass_arr, com_arr, inertia_arr):
        array.setflags(write=False)
    return LinkInertials(mass_arr, com_arr, inertia_arr)


def merge_inertials(parts) -> tuple[float, np.ndarray, np.ndarray]:
    """One rigid body from parts ``(T, mass, com, inertia)``: each part's mass properties in its own
    frame, placed by T (4, 4) in the merged body's frame. Returns (mass, com (3,), inertia about the
    merged centre of mass (3, 3)): masses add, the centre of mass is the mass-weighted mean, and each
    part's inertia is rotated, ``R I R^T``, then moved to the merged centre of mass by the
    parallel-axis theorem, ``+ m (|d|² E - d d^T)`` with d the part's centre of mass relative to the
    merged one. A massless result has its centre of mass at the origin."""
    placed = []
    for T, mass, com, inertia in parts:
        R, t = np.asarray(T)[:3, :3], np.asarray(T)[:3, 3]
        placed.append((float(mass), R @ np.asarray(com) + t, R @ np.asarray(inertia) @ R.T))
    total = sum(m for m, _, _ in placed)
    centre = sum((m * c for m, c, _ in placed), np.zeros(3)) / total if total > 0 else np.zeros(3)
    inertia = np.zeros((3, 3))
    for m, c, rotated in placed:
        d = c - centre
        inertia += rotated + m * (d @ d * np.eye(3) - np.outer(d, d))
    return total, centre, (inertia + inertia.T) / 2


# --------------------------------------------------------------------------- trees from URDF models


def _path_transform(model, top: str, link: str) -> np.ndarray:
    """``link``'s frame in ``top``'s frame with every joint between them at 0."""
    T = np.eye(4)
    for joint in model.path(link, top):
        T = T @ joint.origin
    return T


def model_tree(model, root: str, moving, floating: bool, feet=()) -> Tree:
    """The tree of ``model`` (a :class:`spotkin.urdf.Model`) rooted at link ``root``, with the joints
    named in ``moving`` (in that order: the order of q) moving and every other joint locked at 0.

    Each link joins the body of the nearest moving joint above it, or the root body. For a fixed base
    (``floating=False``) the root body is dropped. ``feet``: (name, link, offset (3,)) per foot, the
    contact point being the link's origin plus the link's rotation times ``offset`` (a foot that no
    moving joint carries is left out).
    """
    moving = tuple(moving)
    index = {name: k for k, name in enumerate(moving)}
    if len(index) != len(moving):
        raise ValueError(f"moving names a joint twice: {moving}")
    joints = [model.joint(name) for name in moving]
    for joint in joints:
        if not joint.actuated:
            raise ValueError(f"joint {joint.name!r} is fixed: it cannot be a moving joint")
        model.path(joint.child, root)  # ValueError when the joint is not below the root

    def owner(link: str) -> tuple[int, str]:
        """(body index or -1, the body's link) for ``link``; (-2, '') when it is above the root."""
        current = link
        while True:
            if current == root:
                return -1, root
            joint = model.parent_joint(current)
            if joint is None:
                return -2, ""
            if joint.name in index:
                return index[joint.name], joint.child
            current = joint.parent

    n = len(moving)
    parents = np.empty(n, dtype=np.int64)
    placements = np.empty((n, 4, 4))
    for k, joint in enumerate(joints):
        parent, parent_link = owner(joint.parent)
        parents[k] = parent
        placements[k] = _path_transform(model, parent_link, joint.parent) @ joint.origin
    parts: dict[int, list] = {k: [] for k in range(-1, n)}
    for name, link in model.links.items():
        if link.inertial is None:
            continue
        body, body_link = owner(name)
        if body == -2:
            continue
        inertial = link.inertial
        T = _path_transform(model, body_link, name)
        parts[body].append((T, inertial.mass, inertial.com, inertial.inertia))
    merged = [merge_inertials(parts[k]) for k in range(n)]
    inertials = link_inertials(
        [m for m, _, _ in merged],
        np.reshape([c for _, c, _ in merged], (n, 3)),
        np.reshape([i for _, _, i in merged], (n, 3, 3)),
    )
    root_inertial = None
    if floating:
        mass, com, inertia = merge_inertials(parts[-1])
        root_inertial = LinkInertials(*(np.array(x) for x in (mass, com, inertia)))
        for array in root_inertial:
            array.setflags(write=False)
    foot_bodies, foot_points, foot_names = [], [], []
    for name, link, offset in feet:
        body, body_link = owner(link)
        if body < 0:  # a leg left out of the moving joints: locked, no foot of the tree
            continue
        T = _path_transform(model, body_link, link)
        foot_bodies.append(body)
        foot_points.append(T[:3, 3] + T[:3, :3] @ np.asarray(offset, dtype=float))
        foot_names.append(name)
    axes = np.array([joint.axis for joint in joints], dtype=float).reshape(n, 3)
    types = np.array([1 if joint.type == "prismatic" else 0 for joint in joints], dtype=np.int8)
    return _frozen_tree(
        moving,
        parents,
        placements,
        axes,
        types,
        inertials,
        root_inertial,
        np.array(foot_bodies, dtype=np.int64),
        np.reshape(foot_points, (len(foot_bodies), 3)),
        tuple(foot_names),
    )


def _frozen_tree(names, parents, placements, axes, types, inertials, root, feet, points, foot_names) -> Tree:
    for array in (parents, placements, axes, types, feet, points):
        array.setflags(write=False)
    return Tree(names, parents, placements, axes, types, inertials, root, feet, points, foot_names)


# --------------------------------------------------------------------------- trees from chains


def chain_tree(chain) -> Tree:
    """A chain as a fixed-base tree whose root frame is the world (the chain's base folded in).

    URDF-style and modified-DH chains move each joint last (``T(j-1, j) = P_j · M_j(q_j)``: in DHm
    RotZ(q) commutes with TransZ(r)), so body j's frame is the chain's frame j + 1. Classic DH moves
    first, ``T(j-1, j) = RotZ(theta) · M(q) · P_j`` with ``P_j = TransZ(d) TransX(a) RotX(alpha)``:
    body j's frame is then frame j + 1 times ``P_j^-1``, and its inertials are moved by ``P_j``.
    """
    if getattr(chain, "full_chain", None) is not None:
        raise ValueError(
            "this chain has mimic joints: tree_of(chain.full_chain) gives the tree of every joint, which "
            "moves as q_full = chain.mimic_matrix @ q + chain.mimic_offset"
        )
    inertials = chain.inertials
    if inertials is None:
        raise ValueError("the chain has no inertials: give them with Chain.with_inertials")
    n = chain.dof
    base = chain.base
    types = np.array(chain.sigma, dtype=np.int8)
    axes = np.tile([0.0, 0.0, 1.0], (n, 1))
    placements = np.empty((n, 4, 4))
    mass, com, inertia = (np.array(x) for x in inertials)
    if chain.convention == "joints":
        joint_placements, joint_axes, _ = chain._joints  # as given to Chain.from_joints
        placements[:] = joint_placements
        axes = joint_axes / np.linalg.norm(joint_axes, axis=1, keepdims=True)
    elif chain.convention == "mdh":
        for j, (_, d, alpha, r, theta) in enumerate(chain.rows):
            screw_x = rotation_x(alpha) @ translation([d, 0, 0])
            placements[j] = screw_x @ rotation_z(theta) @ translation([0, 0, r])
    else:  # classic DH
        previous = np.eye(4)
        for j, (_, a, alpha, d, theta) in enumerate(chain.rows):
            after = translation([0, 0, d]) @ translation([a, 0, 0]) @ rotation_x(alpha)
            placements[j] = previous @ rotation_z(theta)
            R, t = after[:3, :3], after[:3, 3]
            com[j] = R @ com[j] + t
            inertia[j] = R @ inertia[j] @ R.T
            previous = after
    placements[0] = base @ placements[0]
    return _frozen_tree(
        chain.joint_names,
        np.arange(-1, n - 1, dtype=np.int64),
        placements,
        axes,
        types,
        link_inertials(mass, com, inertia),
        None,
        np.zeros(0, dtype=np.int64),
        np.zeros((0, 3)),
        (),
    )


def tree_of(source, joints=None) -> Tree:
    """The kinematic tree the dynamics take, from a :class:`spotkin.Chain` or a :class:`spotkin.Robot`.

    - A chain (it needs inertials: :meth:`spotkin.Chain.with_inertials`, or a chain from
      :meth:`spotkin.Robot.chain`) gives a fixed-base tree whose root frame is the world: the
      chain's base transform is folded into the first placement.
    - A robot gives a floating-base tree: the root is the body (the URDF's root link), whose mass
      properties are :attr:`spotkin.Robot.body_inertial`. The moving joints are ``joints`` (URDF
      names), by default the legs' joints in the order of the whole-body q
      (:attr:`spotkin.Robot.leg_joint_names`) then the arm's (:attr:`spotkin.Robot.arm_joint_names`);
      every other joint (a gripper finger, a rotor) is locked at 0 and merged into the body it hangs
      from. The tree's feet are the legs' contact points.
    """
    make = getattr(type(source), "_tree", None)  # Chain._tree and Robot._tree (this module is below both)
    if make is None:
        raise TypeError(f"source must be a spotkin.Chain or spotkin.Robot, got {type(source).__name__}")
    return make(source, joints)
