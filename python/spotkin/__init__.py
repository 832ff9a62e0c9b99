"""spotkin: exact, batched, fast kinematics for Spot-like legged robots."""

from __future__ import annotations

from . import differential as differential  # a public module outside __all__, bound as before
from . import dynamics, inertia, paul, trajectory, urdf
from . import models as models  # a public module outside __all__, bound as before
from ._support.public import publish
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
from .motion import (
    Gait,
    GaitController,
    GaitPlan,
    Reachability,
    ReachBox,
    ReachPath,
    ReachResult,
    ReachStatus,
)

# What the models' pickles call to rebuild them, at this path (publish below) whichever file defines
# them: a pickle names "spotkin" only.
from .model.arm import _rebuild_spot_arm as _rebuild_spot_arm  # isort: skip
from .model.chain import _rebuild_chain as _rebuild_chain  # isort: skip
from .model.chain import _rebuild_joints as _rebuild_joints  # isort: skip
from .model.chain import _rebuild_with_ik_tolerance as _rebuild_with_ik_tolerance  # isort: skip
from .model.chain import _rebuild_with_inertials as _rebuild_with_inertials  # isort: skip
from .model.leg import _rebuild_leg as _rebuild_leg  # isort: skip
from .model.mimic import _rebuild_mimic as _rebuild_mimic  # isort: skip
from .model.robot import _rebuild_robot as _rebuild_robot  # isort: skip
from .model.spot import _rebuild_spot as _rebuild_spot  # isort: skip

_REBUILDERS = (
    "_rebuild_chain",
    "_rebuild_joints",
    "_rebuild_leg",
    "_rebuild_mimic",
    "_rebuild_robot",
    "_rebuild_spot",
    "_rebuild_spot_arm",
    "_rebuild_with_ik_tolerance",
    "_rebuild_with_inertials",
)

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
    "Gait",
    "GaitController",
    "GaitPlan",
    "IKDifferentialInfo",
    "Leg",
    "LegSolutions",
    "LinkInertials",
    "ReachBox",
    "ReachPath",
    "ReachResult",
    "ReachStatus",
    "Reachability",
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

# the public classes and functions, and the rebuilders, name this package as their module
publish(__name__, globals(), [*__all__, *_REBUILDERS])
