"""The built-in data ``spotkin demo`` shows and draws: the body's via points and their limits, the
arm's joints."""

from __future__ import annotations

import numpy as np

DEMO_WAYPOINTS = np.array(
    [  # the demo's body path, [x, y, z, roll, pitch, yaw] (Spot standing 0.5 m high)
        [0.00, 0.00, 0.50, 0.00, 0.00, 0.00],
        [0.05, 0.06, 0.46, 0.10, -0.08, 0.12],
        [-0.04, 0.05, 0.44, -0.05, 0.12, -0.10],
        [0.00, -0.06, 0.48, 0.08, 0.05, 0.05],
        [0.00, 0.00, 0.50, 0.00, 0.00, 0.00],
    ]
)
DEMO_PATH_LIMITS = {"vmax": 0.1, "amax": 0.5, "wmax": 0.4, "alphamax": 2.0, "blend": 0.3}
DEMO_ARM_Q = np.array([0.0, -1.2, 1.9, 0.0, 0.4, 0.0])  # the arm's joints at the start of the body path
