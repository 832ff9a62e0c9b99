"""spotkin: exact, batched, fast kinematics for Spot-like legged robots."""

from __future__ import annotations

from . import differential as differential  # a public module outside __all__, bound as before
from . import dynamics, inertia, paul, trajectory, urdf
from . import models as models  # a public module outside __all__, bound as before
from ._support.runtime import (
    MAX_THREADS,
    available_isas,
    get_isa,
    get_num_threads,
    isa,
    set_isa,
    set_num_threads,
    thread_limit,
)
from ._support.status import Status
from ._support.transforms import rotation_x, rotation_y, rotation_z, transform, translation
from ._support.version import __version__ as __version__
from .dynamics import LinkInertials, unpack_symmetric
from .kinematics.differential import (
    compatible,
    dls,
    manipulability,
    nullspace_projector,
    pinv,
    rank,
    singular_values,
)
from .kinematics.workspace import Dexterity, WorkspaceSamples, dexterity, workspace, workspace_volume
from .model.arm import ArmSingularity, ArmSolutions, SpotArm, pose_from
from .model.body import EULER_SEQUENCES, body_transform
from .model.chain import Chain, ChainSolutions, IKDifferentialInfo
from .model.leg import Leg, LegSolutions
from .model.robot import Robot
from .model.robot_body import BodyFrames, BodyIK, BodyRates
from .model.robot_statics import StanceStatus, Standing
from .model.spot import Spot

__all__ = [
    "EULER_SEQUENCES",
    "MAX_THREADS",
    "ArmSingularity",
    "ArmSolutions",
    "BodyFrames",
    "BodyIK",
    "BodyRates",
    "Chain",
    "ChainSolutions",
    "Dexterity",
    "IKDifferentialInfo",
    "Leg",
    "LegSolutions",
    "LinkInertials",
    "Robot",
    "Spot",
    "SpotArm",
    "StanceStatus",
    "Standing",
    "Status",
    "WorkspaceSamples",
    "available_isas",
    "body_transform",
    "compatible",
    "dexterity",
    "dls",
    "dynamics",
    "get_isa",
    "get_num_threads",
    "inertia",
    "isa",
    "manipulability",
    "nullspace_projector",
    "paul",
    "pinv",
    "pose_from",
    "rank",
    "rotation_x",
    "rotation_y",
    "rotation_z",
    "set_isa",
    "set_num_threads",
    "singular_values",
    "thread_limit",
    "trajectory",
    "transform",
    "translation",
    "unpack_symmetric",
    "urdf",
    "workspace",
    "workspace_volume",
]
