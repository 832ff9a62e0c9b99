"""Built-in robot models as data: the implementation of :mod:`spotkin.models` (documented there)."""

from __future__ import annotations

__all__ = ["LEG_NAMES", "SPOT"]

LEG_NAMES = ("fl", "fr", "hl", "hr")  # SDK order; h = hind

SPOT = {
    "hip_positions": {  # hx joint origins in the body frame
        "fl": (0.29785, 0.055, 0.0),
        "fr": (0.29785, -0.055, 0.0),
        "hl": (-0.29785, 0.055, 0.0),
        "hr": (-0.29785, -0.055, 0.0),
    },
    "leg": {
        "hip_offset": 0.110945,  # hx -> hy, +y for left legs, -y for right legs
        "upper": 0.3205,  # hy -> kn along -z
        "knee_offset": 0.025,  # hy -> kn along +x
        "lower": 0.3365,  # kn -> foot-sphere centre along -z
        "foot_radius": 0.036,
        "limits": ((-0.785398, 0.785398), (-0.898845, 2.295108), (-2.7929, -0.2471)),
    },
    # per-leg limits from the packaged URDF: the knee upper limits differ per leg
    "leg_limits": {
        "fl": (
            (-0.7853981633974483, 0.7853981633974483),
            (-0.8988445647770796, 2.2951079663725435),
            (-2.7929, -0.254801),
        ),
        "fr": (
            (-0.7853981633974483, 0.7853981633974483),
            (-0.8988445647770796, 2.2951079663725435),
            (-2.7929, -0.247563),
        ),
        "hl": (
            (-0.7853981633974483, 0.7853981633974483),
            (-0.8988445647770796, 2.2951079663725435),
            (-2.7929, -0.267153),
        ),
        "hr": (
            (-0.7853981633974483, 0.7853981633974483),
            (-0.8988445647770796, 2.2951079663725435),
            (-2.7929, -0.257725),
        ),
    },
    "arm": {
        "mount": (0.292, 0.0, 0.188),  # sh0 origin in the body frame
        "upper_arm": 0.3385,  # sh1 -> el0 along x
        "forearm": 0.4033,  # el0 -> el1 along x
        "forearm_offset": 0.075,  # el0 -> el1 along z
        "hand": 0.19557,  # wr1 -> hand frame along x
        "limits": (
            (-2.6179938779914944, 3.141592653589793),
            (-3.141592653589793, 0.5235987755982988),
            (0.0, 3.141592653589793),
            (-2.792526803190927, 2.792526803190927),
            (-1.8325957145940461, 1.8325957145940461),
            (-2.8797932657906435, 2.8797932657906435),
        ),
    },
    # MuJoCo Menagerie keyframe: hy = 1.04, kn = -1.8 (body 0.46 m above ground).
    "nominal_stance": (0.0, 1.04, -1.8),
}
