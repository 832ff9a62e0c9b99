"""The objects under test: :class:`Context` (built once per worker, lazily), the constants it builds
them from (DH tables, limits, stance heights, trajectories), pose helpers, and generators of valid
baseline samples."""

from __future__ import annotations

import os
import tempfile

import numpy as np

import spotkin as sk

from .slots import OK
from .urdf_texts import HEXAPOD_URDF, bad_urdfs, go2_text, latin1_urdf

PROFILES = ("cubic", "quintic", "trapezoid")
P2P_Q0, P2P_QF = (0.0, 0.5, -1.0), (1.0, -0.5, 0.5)
CHAIN_ROWS = {
    # the README's DHm leg (sigma, d, alpha, r, theta)
    "mdh3": [(0, 0.0, -np.pi / 2, 0.0, 0.0), (0, 0.0, np.pi / 2, 0.11, 0.0), (0, 0.32, 0.0, 0.0, 0.0)],
    # an elbow arm in classic DH (sigma, a, alpha, d, theta)
    "dh3": [(0, 0.0, np.pi / 2, 0.3, 0.0), (0, 0.4, 0.0, 0.0, 0.0), (0, 0.3, 0.0, 0.0, 0.0)],
    # the Spot arm as DHm (tests/test_chain_ik.py)
    "mdh6": [
        (0, 0.0, 0.0, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, 0.3385, 0.0, 0.0, -np.pi / 2),
        (0, 0.075, -np.pi / 2, 0.4033, 0.0),
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
    ],
    # PUMA 560 in classic DH: a spherical wrist
    "dh6": [
        (0, 0.0, np.pi / 2, 0.0, 0.0),
        (0, 0.4318, 0.0, 0.0, 0.0),
        (0, 0.0203, -np.pi / 2, 0.15005, 0.0),
        (0, 0.0, np.pi / 2, 0.4318, 0.0),
        (0, 0.0, -np.pi / 2, 0.0, 0.0),
        (0, 0.0, 0.0, 0.0, 0.0),
    ],
}
LEG_LIMITS = [(-0.8, 0.8), (-0.9, 2.3), (-2.8, -0.25)]
# chains from URDFs: key -> (Context.robot key, tip link, dof)
URDF_CHAINS = {"go2_fl": ("go2", "FL_foot", 3), "spot_arm": ("spot_urdf", "arm_hand", 6)}
ROBOT_FILES = {"go2": "go2", "spot_urdf": "spot_with_arm"}
STANCE_HEIGHT = {"spot": 0.5, "go2": 0.28, "hexapod": 0.3, "spot_urdf": 0.5}


def rigid(R, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def euler_matrix(angles, seq="XYZ"):
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler(seq, angles).as_matrix()


def quat_matrix(q):
    """The documented conversion (scalar last, s = 2 / |q|^2), without normalising."""
    x, y, z, w = q
    s = 2.0 / (x * x + y * y + z * z + w * w)
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
        ]
    )


def pose_matrix(x, seq="XYZ"):
    """A (6,), (7,) or (4, 4) pose sample as a float64 4x4 (body_transform's reading)."""
    x = np.asarray(x, dtype=np.float64)
    if x.shape == (4, 4):
        return x.copy()
    R = euler_matrix(x[3:], seq) if x.shape == (6,) else quat_matrix(x[3:])
    return rigid(R, x[:3])


class Context:
    """The objects the registry's entries are called on, built once per worker (lazily)."""

    def __init__(self):
        self._cache = {}

    def _get(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    @property
    def spot(self):
        return self._get("spot", sk.Spot)

    @property
    def leg(self):
        return self.spot.leg("fl")

    @property
    def arm(self):
        return self.spot.arm

    def robot(self, key):
        """A whole-body robot: "spot" (sk.Spot()), "go2", "spot_urdf" (sk.Robot from the packaged
        URDFs) or "hexapod" (sk.Robot from :data:`HEXAPOD_URDF`)."""

        def make():
            if key == "hexapod":
                return sk.Robot.from_urdf_string(HEXAPOD_URDF)
            if key == "go2_z1":  # Go2 carrying a Z1-like arm with the Z1's joint ranges
                from urdf_helpers import Z1_LIMITS, go2_with_z1

                return sk.Robot.from_urdf_string(go2_with_z1(Z1_LIMITS))
            if key == "go2_feet":  # two of the legs, with a contact offset
                return sk.Robot.from_urdf(
                    sk.robots.path("go2"), feet=["FL_foot", "RR_foot"], contact_offset=(0.0, 0.0, -0.02)
                )
            return sk.Robot.from_urdf(sk.robots.path(ROBOT_FILES[key]))

        return self.spot if key == "spot" else self._get(("robot", key), make)

    def columns(self, key):
        """Per leg (robot.legs order), the indices of its three joints in the whole-body q."""

        def make():
            robot = self.robot(key)
            if isinstance(robot, sk.Spot):
                return [np.arange(3 * k, 3 * k + 3) for k in range(4)]
            specs = {spec.name: spec for spec in sk.urdf.find_legs(robot.model)[0]}
            order = list(robot.leg_joint_names)
            return [np.array([order.index(j) for j in specs[name].joint_names]) for name in robot.leg_names]

        return self._get(("columns", key), make)

    def hips(self, key):
        return self._get(("hips", key), lambda: self.robot(key).hip_positions)

    def nominal(self, key):
        """(3 n,) whole-body joints of the nominal stance (body_ik of stance_feet at its height)."""

        def make():
            robot, height = self.robot(key), STANCE_HEIGHT[key]
            q, status = robot.body_ik([0.0, 0.0, height, 0.0, 0.0, 0.0], robot.stance_feet(height))
            assert (status == OK).all(), (key, status)
            return q

        return self._get(("nominal", key), make)

    def files(self):
        """URDF files for Robot.from_urdf: name -> path (in a temporary folder of this worker)."""

        def make():
            folder = tempfile.TemporaryDirectory(prefix="spotkin-fuzz-")
            self._cache["folder"] = folder  # removed at exit
            go2 = go2_text()
            body = go2.split("?>", 1)[1] if go2.startswith("<?xml") else go2
            contents = {
                "latin1": latin1_urdf(),
                "utf16": ('<?xml version="1.0" encoding="UTF-16"?>' + body).encode("utf-16"),
                "empty": b"",
                "not_xml": b"hello",
                "loop": bad_urdfs()["loop"][0].encode(),
            }
            paths = {"missing": os.path.join(folder.name, "missing.urdf"), "directory": folder.name}
            for name, data in contents.items():
                paths[name] = os.path.join(folder.name, f"{name}.urdf")
                with open(paths[name], "wb") as file:
                    file.write(data)
            return paths

        return self._get("files", make)

    def chain(self, key):
        def make():
            if key in URDF_CHAINS:
                robot, link, _ = URDF_CHAINS[key]
                return self.robot(robot).chain(link)
            rows = CHAIN_ROWS[key]
            if key == "mdh3":
                return sk.Chain.from_mdh(rows, tool=sk.translation([0.37, 0.0, 0.0]), limits=LEG_LIMITS)
            if key == "dh3":
                return sk.Chain.from_dh(rows, base=rigid(euler_matrix([0.1, 0.2, 0.3]), [0.1, 0, 0.2]))
            if key == "mdh6":
                base = sk.translation([0.292, 0.0, 0.188])
                return sk.Chain.from_mdh(
                    rows, base=base, tool=sk.translation([0.19557, 0.0, 0.0]), limits=self.arm.limits
                )
            return sk.Chain.from_dh(rows, tool=sk.translation([0.0, 0.0, 0.1]))

        return self._get(("chain", key), make)

    def p2p(self, profile):
        return self._get(
            ("p2p", profile), lambda: sk.trajectory.point_to_point(P2P_Q0, P2P_QF, 1.0, 2.0, profile)
        )

    def path(self, kind):
        def make():
            if kind == "linear":
                return sk.trajectory.linear(PATH_T0, PATH_T1, 0.5, 1.0, 1.0, 2.0)
            return sk.trajectory.via_points(VIA_POSES, 0.5, 1.0, 1.0, 2.0, blend=0.2)

        return self._get(("path", kind), make)


PATH_T0 = rigid(euler_matrix([0.1, -0.2, 0.3]), [0.1, 0.2, 0.3])
PATH_T1 = rigid(euler_matrix([-0.4, 0.5, 1.2]), [0.6, -0.1, 0.5])
VIA_POSES = np.array(
    [rigid(euler_matrix([0.1 * k, -0.2, 0.3 * k]), [0.1 * k, 0.2 - 0.05 * k * k, 0.3]) for k in range(4)]
)


ROBOT_LEGS = {"spot": 4, "go2": 4, "hexapod": 6, "spot_urdf": 4}
ROBOT_ARMS = {"spot": True, "go2": False, "hexapod": False, "spot_urdf": True}


# ---- baseline samples --------------------------------------------------------------------------------


def in_limits(limits, rng, n, margin=0.05):
    limits = np.asarray(limits, dtype=np.float64)
    lo = np.where(np.isfinite(limits[:, 0]), limits[:, 0], -np.pi)
    hi = np.where(np.isfinite(limits[:, 1]), limits[:, 1], np.pi)
    margin = np.minimum(margin, np.maximum(hi - lo, 0) / 4)  # narrow (or inverted) limits: their middle
    return rng.uniform(
        np.minimum(lo + margin, hi - margin), np.maximum(lo + margin, hi - margin), (n, len(limits))
    )


def rotations(rng, n):
    from scipy.spatial.transform import Rotation

    q = rng.normal(size=(n, 4))
    return Rotation.from_quat(q / np.linalg.norm(q, axis=1, keepdims=True)).as_matrix()


def unit_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def nominal_q12(rng, n):
    return np.tile([0.0, 1.04, -1.8], 4) + rng.uniform(-0.1, 0.1, (n, 12))


def body_poses(rng, n, height=0.48):
    pose = np.zeros((n, 6))
    pose[:, :3] = rng.uniform(-0.03, 0.03, (n, 3)) + [0.0, 0.0, height]
    pose[:, 3:] = rng.uniform(-0.15, 0.15, (n, 3))
    return pose
