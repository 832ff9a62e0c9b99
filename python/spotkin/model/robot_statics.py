"""A robot's floating-base dynamics and standing statics: :class:`spotkin.Robot` takes these methods from
the base class here; their result types are defined here."""

from __future__ import annotations

from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_real, broadcast_lead
from .._support.forward import core_method
from .._support.transforms import quaternion_xyzw
from ..dynamics import inertia
from ..dynamics.rigid_body import FloatingBase
from .body import body_transform, sequence_code
from .robot_joints import _names

__all__ = ["StanceStatus", "Standing"]


class _FloatingBaseMethods:
    """The floating-base dynamics and statics of :class:`spotkin.Robot` (its base class; see there)."""

    __slots__ = ()

    @property
    def floating_base(self):
        """The whole robot as a floating body carrying its legs and arm
        (:class:`spotkin.dynamics.FloatingBase`, built from the URDF's inertials on first use): A(q)
        (6 + n) x (6 + n), RNEA, ABA, G, the centre of mass and its Jacobian. Its coordinates are
        Pinocchio's free-flyer ones: ``[x, y, z, qx, qy, qz, qw]`` then the joints of
        :attr:`leg_joint_names` and :attr:`arm_joint_names` (see :meth:`floating_q`); velocities
        ``[v_body; w_body]`` in the body frame, then the joint rates."""
        floating = getattr(self, "_floating", None)
        if floating is None:
            legs, arms = self._specs
            if self._model is None or not legs:
                raise ValueError("dynamics need a URDF description; a robot from a model dict has none")
            chains = [self.chain(spec.foot) for spec in legs]
            if self.arm_joint_names:
                arm = self.chain(arms[0].tip)
                if arm.dof != len(self.arm_joint_names):
                    raise ValueError(
                        f"the arm's chain from the body has {arm.dof} joints, not the arm's "
                        f"{len(self.arm_joint_names)}: joints between the body and the arm's base are "
                        "not supported"
                    )
                chains.append(arm)
            body = self.body_inertial
            floating = FloatingBase((body.mass, body.com, body.inertia), chains)
            self._floating = floating
        return floating

    @property
    def mass(self) -> float:
        """The robot's total mass (kg): the body's, the legs' and the arm's links."""
        return self.floating_base.mass

    def floating_q(self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ") -> np.ndarray:
        """The generalised coordinates (..., 7 + n) of :attr:`floating_base`: the body's position and unit
        quaternion ``[x, y, z, qx, qy, qz, qw]`` (from ``body_pose``, any form :func:`spotkin.body_transform`
        takes), then ``q``: the legs' joints (..., 3 n_legs), followed by the arm's when given (..., 3 n_legs
        + n_arm; else the arm at zero). Leading dimensions broadcast; an invalid pose gives NaN there."""
        T = body_transform(body_pose, seq)
        q = self._legs_and_arm(q)
        lead = broadcast_lead(body_pose=(T.shape[:-2], T.shape), q=(q.shape[:-1], q.shape))
        T = np.broadcast_to(T, (*lead, 4, 4))
        q = np.broadcast_to(q, (*lead, q.shape[-1]))
        out = np.concatenate([T[..., :3, 3], quaternion_xyzw(T[..., :3, :3]), q], axis=-1)
        # a sample with an invalid pose or a NaN or Inf joint: NaN throughout
        return np.where(np.isfinite(out).all(axis=-1, keepdims=True), out, np.nan)

    def _legs_and_arm(self, q: ArrayLike) -> np.ndarray:
        """q (..., 3 n_legs) or (..., 3 n_legs + n_arm) in float64, the arm at zero if not given."""
        q = as_real(q, "q", np.float64)
        legs, arm = 3 * len(self._legs), len(self.arm_joint_names)
        self._leg_q(q, "q")  # the width check
        if q.shape[-1] == legs and arm:
            q = np.concatenate([q, np.zeros((*q.shape[:-1], arm))], axis=-1)
        return q

    @core_method(
        "_statics_core", "com", call=("body_pose", "seq", "q", "out"), convert={"seq": sequence_code}
    )
    def center_of_mass(
        self, body_pose: ArrayLike, q: ArrayLike, seq: str = "XYZ", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """The whole robot's centre of mass in the world (..., 3); ``q`` as in :meth:`floating_q`. Leading
        dimensions broadcast; float32 when ``body_pose`` and ``q`` both are. An invalid pose, or a NaN or
        Inf joint, gives NaN in that sample. ``out``: an array of the result's shape and dtype to fill."""
        return self._statics.com(body_pose, sequence_code(seq), q, out)

    @property
    def _statics(self):
        """The C++ statics of the robot (its centre of mass and standing torques), built on first use."""
        statics = getattr(self, "_statics_core", None)
        if statics is None:
            floating = self.floating_base
            statics = _core.RobotStatics(self._body_core, floating._core, floating.mass)
            self._statics_core = statics
        return statics

    @core_method(
        "_statics_core",
        "standing",
        call=("body_pose", "seq", "q", "stance", "gravity", "out"),
        convert={"seq": sequence_code},
    )
    def standing_torques(
        self,
        body_pose: ArrayLike,
        q: ArrayLike,
        stance: ArrayLike | None = None,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        seq: str = "XYZ",
        *,
        out: tuple | None = None,
    ) -> Standing:
        """The leg torques that hold the robot still on its stance feet, and the contact forces.

        Point contacts at the stance feet (the foot points of :meth:`body_fk`) carry world forces f_i
        that carry the weight, sum f_i = -m g, and balance its moment, sum (p_i - c) x f_i = 0 (c the
        centre of mass): the minimum-norm such forces. Where the moment cannot be balanced (fewer than
        three feet down, or collinear ones, as in a trot or a pace), the weight is still carried and the
        moment balanced in the least-squares sense, with the smallest forces among those, and
        ``residual`` gives the moment left. Each leg then holds tau_l = G_l - J_l^T f_l, with G_l its
        joint gravity torques and J_l = d foot_l / d q_l (world axes); a swing leg holds G_l alone.

        ``body_pose`` as :meth:`body_fk` takes it; ``q`` (..., 3 n_legs), or with the arm's joints after
        the legs' (else the arm is at zero; it moves the centre of mass); ``stance`` (..., n_legs) bool,
        default every foot; ``gravity`` (3,) world, m/s². Leading dimensions broadcast.

        Returns :class:`Standing`: ``tau`` (..., 3 n_legs) N m in :attr:`leg_joint_names` order, ``forces``
        (..., n_legs, 3) N (zero on swing feet), ``status`` (:class:`StanceStatus`; an int8 array for a
        batch), ``margin`` (m; a float for one sample): the signed distance of the centre of mass's
        projection, along gravity, to the support polygon (positive inside), and ``residual`` (..., 6):
        the wrench the forces leave unbalanced, [force (N); moment about the centre of mass (N m)] in
        world axes (zero when balanced). The status, checked in this order: UNBALANCED (the moment
        cannot be balanced at these feet, e.g. fewer than three feet with the centre of mass off their
        line or point: tau and forces are the least-squares ones, ``residual`` says what is left), OK
        (every foot pushes), PULLING (the minimum-norm forces pull on a foot though the centre of mass
        projects inside the polygon: a pushing distribution exists, this is not it), OUTSIDE (a foot
        pulls and the centre of mass projects on or outside the polygon: no pushing distribution exists
        on level ground). NaN or Inf input, or an invalid pose: INVALID_INPUT and NaN in that sample.
        ``out``: ``(tau, forces, status, margin, residual)`` arrays of the result's shapes (float of the
        working dtype; status int8), any of them None, to write into.
        """
        return self._statics.standing(body_pose, sequence_code(seq), q, stance, gravity, out)  # a Standing

    def _tree(self, joints) -> inertia.Tree:
        if self._model is None or not self._specs[0]:
            raise ValueError("dynamics need a URDF description; a robot from a model dict has none")
        to_urdf = {}
        aliases = self._joint_aliases()
        for joint in self._model.actuated_joints:
            to_urdf.setdefault(aliases.get(joint.name, joint.name), joint.name)
        if joints is None:
            joints = [to_urdf[name] for name in (*self.leg_joint_names, *self.arm_joint_names)]
        else:
            joints = [to_urdf.get(aliases.get(name, name), name) for name in _names(joints, "joints")]
        feet = [(spec.name, spec.foot, spec.contact_offset) for spec in self._specs[0]]
        names = dict(zip((spec.name for spec in self._specs[0]), self._leg_names))
        feet = [(names[name], link, offset) for name, link, offset in feet]
        return inertia.model_tree(self._model, self._model.root, joints, floating=True, feet=feet)


class StanceStatus(IntEnum):
    """Outcome of :meth:`Robot.standing_torques` for one sample."""

    OK = 0
    """The minimum-norm contact forces balance the robot, and every one pushes on the ground."""
    PULLING = 1
    """They balance, but a foot pulls, though the centre of mass projects inside the support polygon: a
    pushing distribution exists, the minimum-norm one is not it."""
    OUTSIDE = 2
    """They balance only by pulling on a foot, and the centre of mass projects on or outside the support
    polygon: no pushing distribution exists on level ground."""
    INVALID_INPUT = 3
    """NaN or Inf in the input, an invalid body pose or a stance value other than 0/1: everything NaN
    (the code of :attr:`Status.INVALID_INPUT`)."""
    UNBALANCED = 4
    """No forces at these feet balance the weight's moment (fewer than three feet, or collinear ones,
    with the centre of mass off their line or point): tau and forces are the least-squares ones (the
    weight carried, the moment balanced as well as these feet can), ``residual`` the wrench left."""


class Standing(NamedTuple):
    """The result of :meth:`Robot.standing_torques`."""

    tau: np.ndarray
    """(..., 3 n_legs) N m: the leg joint torques that hold the pose, in leg_joint_names order."""
    forces: np.ndarray
    """(..., n_legs, 3) N: the world contact forces on the feet (ground on foot), zero on swing feet."""
    status: np.ndarray | StanceStatus
    """(...) :class:`StanceStatus` values (int8), or one member for a single sample."""
    margin: np.ndarray
    """(...) m: signed distance of the centre of mass's projection to the support polygon, in the plane
    normal to gravity, positive inside (with fewer than three non-collinear feet: minus the distance to
    their segment or point; NaN without gravity). A float for a single sample."""
    residual: np.ndarray
    """(..., 6) the wrench the forces leave unbalanced, [force (N); moment about the centre of mass
    (N m)], world axes: zero when balanced; with two feet down, the weight's moment about their line."""


# The core returns Standing itself, one sample's status as a StanceStatus member (by value)
_core._register_result_type("Standing", Standing)
_core._register_result_type("StanceStatus", tuple(StanceStatus))
