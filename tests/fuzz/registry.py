"""The fuzz registry: :data:`REGISTRY`, every entry of every concept module in a fixed order, and
:data:`BY_NAME` (the entries and the canaries by name).

Importing this module fills the registry: each concept module registers its entries
(:func:`fuzz.entry.register`), then the optional modules' (``spotkin.sdk``, ``spotkin.dask``,
``spotkin.plot``, whenever their extra is installed), the joint-limit overrides, the instruction-set
levels and ``Chain.from_urdf``.
"""

from __future__ import annotations

from . import dask as fuzz_dask
from . import isa as fuzz_isa
from . import limits as fuzz_limits
from . import plot as fuzz_plot
from . import sdk as fuzz_sdk
from . import urdf as fuzz_urdf
from .arm import arm_entries
from .canaries import CANARIES, CANARY_FK
from .chains import chain_entries
from .controller import controller_entries
from .dynamics import dynamics_entries
from .entry import REGISTRY
from .functions import function_entries
from .gait import gait_entries
from .joint_names import joint_name_entries
from .legs import leg_entries
from .paul import paul_entries
from .reach import reach_entries, reach_path_entries, reachability_entries
from .robots import robot_entries
from .roundtrip import roundtrip_entries
from .spot import spot_entries
from .trajectory import trajectory_entries
from .workspace import workspace_entries

__all__ = ["BY_NAME", "REGISTRY"]

leg_entries()
chain_entries(arm_entries())
spot_entries()
robot_entries()
dynamics_entries()
function_entries()
paul_entries()
trajectory_entries()
workspace_entries()
gait_entries()
controller_entries()
reach_entries()
reach_path_entries()
reachability_entries()
roundtrip_entries()
joint_name_entries()
fuzz_sdk.register_entries()  # spotkin.sdk, when its optional SDK is installed
fuzz_dask.register_entries()  # spotkin.dask, when Dask is installed
fuzz_plot.register_entries()  # spotkin.plot, when matplotlib is installed
fuzz_limits.register_entries()  # with_limits of robots and chains
fuzz_isa.register_entries()  # instruction-set levels
fuzz_urdf.register_entries()  # Chain.from_urdf (arms, mimic joints)
BY_NAME = {entry.name: entry for entry in REGISTRY}
assert len(BY_NAME) == len(REGISTRY), "registry names must be unique"
BY_NAME.update({name: entry for name, (entry, _) in CANARIES.items()})
BY_NAME[CANARY_FK.name] = CANARY_FK
