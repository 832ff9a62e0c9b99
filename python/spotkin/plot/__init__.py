"""Pictures of robots and their kinematics, drawn with matplotlib (an optional dependency:
``pip install "spotkin[plot]"``).

- :func:`robot`: a 3D stick figure of any loaded robot (or its side, front or top view): every
  link from joint frame to joint frame, the joints, the feet, the support polygon, the body axes
  and the arm; joints beyond their limits and legs at a singular configuration are marked.
- :func:`branches`: every IK branch of one target side by side (a leg's 4, an arm's 8, a
  3- or 6-joint chain's), the valid ones drawn solid, each with its joint values, the status in
  the title.
- :func:`workspace`: a planar slice of a leg's (or a 3-joint chain's) reach, coloured by the
  number of valid IK branches, from one batched IK call over the grid; the unreachable and
  limit-blocked regions, the singular sets and contours of ``|det J|``.
- :func:`trajectory`: a point-to-point motion's q, qd and qdd against time with the speed and
  acceleration limits, or a Cartesian path's position and velocities.
- :func:`animate`: a matplotlib animation of the robot along a body path (``.save("path.gif")``);
  :func:`walk_animation`: one of a walk in the simulator (a :class:`spotkin.sim.SimResult`), the feet
  in contact marked, the camera following the body.
- :func:`gait_diagram`: a walk's contacts, a bar per leg against time (planned and measured);
  :func:`foot_paths`: the feet's paths in side view over each leg's sagittal workspace.
- :func:`reachability`: the hand positions a legged robot reaches with its feet fixed (a
  :class:`spotkin.Reachability`), a 3D scatter coloured by height, the robot standing among them, the
  volume in the title.

Every function returns the matplotlib Figure it drew in, or draws into an ``ax`` (or ``fig``)
that it is given, so that pictures compose and save as usual (``fig.savefig("stance.png")``).
Figures are made with ``matplotlib.pyplot``, so ``plt.show()`` shows them and ``plt.close(fig)``
frees them; nothing here picks a backend. Colours are chosen to stay distinct in greyscale,
helped by line styles, markers and hatching.

The solvers are read through the interface they share (``dof``, ``limits``, ``joint_names``, ``fk``,
``jacobian``, ``ik_all``, ``ik``); a picture that draws a solver's links asks for what places them (a
leg's geometry, a chain's frames), not for its class.
"""

# One module per picture family: _robot (with _stance, one configuration in the world, and _artists, its
# drawing), _branches, _workspace_map, _trajectory, _animation, _gait (walks), _walk (a simulated walk,
# animated), _reach (whole-body reachability); _common (style, argument checks, axes) and _solvers (the
# solver interface as the pictures read it) hold what they share.

from __future__ import annotations

try:  # the optional extra, checked before any picture module imports it
    import matplotlib.animation
    import matplotlib.pyplot  # noqa: F401
    import mpl_toolkits.mplot3d.art3d  # noqa: F401
    import PIL.Image  # noqa: F401 (a dependency of matplotlib)
except ImportError as _error:  # pragma: no cover - tested in a subprocess with matplotlib blocked
    raise ImportError(
        'spotkin.plot needs matplotlib, an optional dependency: pip install "spotkin[plot]" '
        "(or pip install matplotlib)"
    ) from _error

from ._animation import animate
from ._branches import _q_text as _q_text
from ._branches import branches
from ._gait import foot_paths, gait_diagram
from ._reach import reachability
from ._robot import _description as _description
from ._robot import robot
from ._stance import _frame as _frame
from ._stance import _nominal_stance as _nominal_stance
from ._stance import _robot_name as _robot_name
from ._stance import _zero_stance as _zero_stance
from ._trajectory import trajectory
from ._walk import walk_animation
from ._workspace_map import workspace

__all__ = [
    "animate",
    "branches",
    "foot_paths",
    "gait_diagram",
    "reachability",
    "robot",
    "trajectory",
    "walk_animation",
    "workspace",
]
