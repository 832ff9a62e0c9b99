"""URDF parsing, kinematic-tree utilities and recognition of legs and arms.

Standard library plus NumPy only: the XML is read with :mod:`xml.etree.ElementTree`.
Only kinematics, inertia and collision spheres (:attr:`Link.spheres`: a foot's contact sphere)
are kept; meshes (``package://`` paths or any other), visuals, other collision geometry,
transmissions and ``<gazebo>`` tags are read past and never loaded.
A ``.xacro`` description is expanded first with the ``xacro`` package when it is
installed (``pip install "spotkin[xacro]"``; see :func:`read_description`).

Joints
------
* ``<mimic joint="leader" multiplier="m" offset="o"/>``: the joint follows its leader,
  ``q = m q_leader + o``. It is no independent variable: :attr:`Model.actuated_joints`
  leaves it out (:attr:`Model.mimic_joints` lists it), and every chain it lies on moves it
  with its leader (:meth:`spotkin.Chain.from_urdf`).
* A ``floating`` joint from the root link (a massless ``world`` link), or a ``fixed`` joint
  from a link called ``world``, is the robot's root joint (:class:`RootJoint`): the world
  link and that joint are dropped and the robot's base link becomes the root. A
  ``floating`` joint anywhere else, and every ``planar`` joint, is refused.

Conventions (standard URDF semantics)
-------------------------------------
* ``origin rpy`` is fixed-axis roll-pitch-yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``.
* A joint moves its child as ``T_parent_child(q) = origin · Rot(axis, q)`` (revolute,
  continuous) or ``origin · Trans(axis · q)`` (prismatic); ``axis`` is in the joint frame.
* Every problem found in a file raises :class:`ValueError` naming the joint or link.
  Unknown link or joint names passed to the methods raise :class:`ValueError` too.

Recognition
-----------
:func:`find_legs` finds roll-pitch-pitch legs (hip roll about ±x, hip pitch and knee about
±y of the root frame at zero angles) and returns their geometry as used by the leg solver:
``p_leg(q) = Rx(s1 q1) (a + Ry(s2 q2) (b + Ry(s3 q3) c))`` in a frame at the hip-roll joint
origin with axes parallel to the root frame. :func:`find_arms` finds 6-joint arms and tells
whether their wrist is spherical. :func:`describe` prints a summary.
"""

from __future__ import annotations

from .._support.public import publish
from .files import MAX_BYTES as MAX_BYTES
from .files import XACRO_EXTRA as XACRO_EXTRA
from .files import expand_xacro, is_xacro, read_file, read_text
from .parse import load_urdf, parse_urdf
from .recognition import ArmSpec, LegSpec, describe, find_arms, find_legs
from .tree import JOINT_TYPES as JOINT_TYPES
from .tree import ChainData, Inertial, Joint, Link, Model, RootJoint

__all__ = [
    "ArmSpec",
    "ChainData",
    "Inertial",
    "Joint",
    "LegSpec",
    "Link",
    "Model",
    "RootJoint",
    "describe",
    "expand_xacro",
    "find_arms",
    "find_legs",
    "is_xacro",
    "load_urdf",
    "parse_urdf",
    "read_file",
    "read_text",
]

publish(__name__, globals(), __all__)
