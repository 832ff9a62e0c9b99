"""The operations of ``spotkin batch`` (one per batch kernel: its model, input files, options and the
:mod:`spotkin.dask` plan it runs) and the command's arguments."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Callable

from .. import robots

INSTALL = 'pip install "spotkin[dask]"'
DONE = "chunks_done"  # the per-chunk completion markers, removed once the run is complete
ATTRIBUTE = "spotkin_batch"  # the group attribute describing the run
DEFAULT_CHUNK_BYTES = 32 << 20  # inputs + outputs of one chunk, for the default chunk size
FORMAT = 1
LOCAL_SCHEDULERS = ("threads", "processes", "synchronous", "sync", "single-threaded")


class BatchError(Exception):
    """An input, option or output that cannot be used: reported before any work starts."""


def require():
    """(dask, zarr), or ImportError saying what to install."""
    try:
        import dask
        import dask.array
        import zarr
    except ImportError as error:
        raise ImportError(
            f"spotkin batch needs Dask and Zarr: install them with {INSTALL} "
            f"(dask[array,distributed] and zarr); the import failed with: {error}"
        ) from error
    return dask, zarr


# ---- operations -------------------------------------------------------------------------------------


def _skd():
    from . import dask_calls as skd  # imports Dask: only when a batch is planned

    return skd


@dataclass(frozen=True)
class Operation:
    """One ``spotkin batch`` subcommand: its model, its input files, its options and its plan."""

    model: str  # "robot", "leg", "arm" or "chain"
    inputs: tuple  # (argument name, option, required, help)
    plan: Callable  # (model, dask arrays by argument name, parsed args) -> a spotkin.dask plan
    options: tuple = ()  # the parsed options it passes on (recorded in the output)
    help: str = ""


_POSES = ("body_pose", "--poses", True, "body poses (N, 6) [x, y, z, a, b, c], (N, 7) or (N, 4, 4)")
_Q_BODY = ("q", "--q", True, "leg joints (N, 3 n) in the robot's leg-joint order")
_Q = ("q", "--q", True, "joint values (N, dof)")
_SEED = ("seed", "--seed", False, "seeds (N, dof), or one shared (dof,)")
_POINTS = ("target", "--targets", True, "foot points (N, 3) in the leg frame")
_TOOL = ("target", "--targets", True, "tool poses (N, 4, 4) or (N, 7) in the body frame")
_QD = ("qd", "--qd", True, "joint rates (N, dof)")
_Q_FLOATING = ("q", "--q", True, "floating-base coordinates (N, 7 + n): [x, y, z, qx, qy, qz, qw], joints")
_V_FLOATING = ("qd", "--qd", True, "floating-base velocities (N, 6 + n): [v; w] in the body frame, rates")
_CHAIN_TARGETS = ("target", "--targets", True, "points (N, 3) for 3 joints, tool poses (N, 4, 4) for 6")


# the dynamics plans, shared by a chain's and a floating base's operations
def _inverse_dynamics(model, arrays, options):
    return _skd()._plan_inverse_dynamics(
        model, arrays["q"], arrays["qd"], arrays["qdd"], tuple(options.gravity)
    )


def _forward_dynamics(model, arrays, options):
    return _skd()._plan_forward_dynamics(
        model, arrays["q"], arrays["qd"], arrays["tau"], tuple(options.gravity)
    )


def _mass_matrix(model, arrays, options):
    return _skd()._plan_mass_matrix(model, arrays["q"])


OPERATIONS: dict[str, Operation] = {
    "body-ik": Operation(
        "robot",
        (
            _POSES,
            ("feet", "--feet", True, "world feet (N, n, 3), or one shared stance (n, 3)"),
            ("seed", "--seed", False, "seeds (N, 3 n), or one shared (3 n,)"),
        ),
        lambda m, a, o: _skd()._plan_body_ik(m, a["body_pose"], a["feet"], a.get("seed"), o.seq, o.fallback),
        ("seq", "fallback"),
        "whole-body IK: q (N, 3 n) and status (N, n) from body poses and feet",
    ),
    "body-fk": Operation(
        "robot",
        (_POSES, _Q_BODY),
        lambda m, a, o: _skd()._plan_body_fk(m, a["body_pose"], a["q"], o.seq),
        ("seq",),
        "world feet (N, n, 3) from body poses and leg joints",
    ),
    "body-jacobian": Operation(
        "robot",
        (_POSES, _Q_BODY),
        lambda m, a, o: _skd()._plan_body_jacobian(m, a["body_pose"], a["q"], o.seq),
        ("seq",),
        "whole-body Jacobians J (N, 3 n, 6 + 3 n)",
    ),
    "body-rates": Operation(
        "robot",
        (_POSES, _Q_BODY, ("twist", "--twist", True, "body twists [v; w] (N, 6), or one shared (6,)")),
        lambda m, a, o: _skd()._plan_body_rates(m, a["body_pose"], a["q"], a["twist"], o.seq, o.tolerance),
        ("seq", "tolerance"),
        "joint rates qd (N, 3 n) that keep the feet fixed, and singular (N, n)",
    ),
    "leg-ik": Operation(
        "leg",
        (_POINTS, _SEED),
        lambda m, a, o: _skd()._plan_ik(m, a["target"], a.get("seed"), o.fallback),
        ("fallback",),
        "one leg's IK: q (N, 3) and status (N,)",
    ),
    "leg-ik-all": Operation(
        "leg",
        (_POINTS,),
        lambda m, a, o: _skd()._plan_ik_all(m, a["target"]),
        (),
        "one leg's IK, every branch: q (N, 4, 3), valid, exists (N, 4), status (N,)",
    ),
    "leg-fk": Operation("leg", (_Q,), lambda m, a, o: _skd()._plan_fk(m, a["q"]), (), "foot points p (N, 3)"),
    "leg-jacobian": Operation(
        "leg", (_Q,), lambda m, a, o: _skd()._plan_jacobian(m, a["q"]), (), "leg Jacobians J (N, 3, 3)"
    ),
    "arm-ik": Operation(
        "arm",
        (_TOOL, _SEED),
        lambda m, a, o: _skd()._plan_ik(m, a["target"], a.get("seed")),
        (),
        "the arm's IK, one solution: q (N, 6) and status (N,)",
    ),
    "arm-ik-all": Operation(
        "arm",
        (_TOOL, ("seed", "--seed", False, "seeds (N, 6) for the singular cases (the Spot Arm only)")),
        lambda m, a, o: _skd()._plan_ik_all(m, a["target"], a.get("seed")),
        (),
        "the arm's IK, every solution: q (N, 8, 6), valid, exists (N, 8), status (N,)",
    ),
    "arm-fk": Operation(
        "arm", (_Q,), lambda m, a, o: _skd()._plan_fk(m, a["q"]), (), "the arm's tool poses T (N, 4, 4)"
    ),
    "arm-jacobian": Operation(
        "arm", (_Q,), lambda m, a, o: _skd()._plan_jacobian(m, a["q"]), (), "the arm's Jacobians J (N, 6, 6)"
    ),
    "chain-fk": Operation(
        "chain",
        (_Q,),
        lambda m, a, o: _skd()._plan_fk(m, a["q"]),
        (),
        "tool poses T (N, 4, 4) of the chain from --base to --link",
    ),
    "chain-jacobian": Operation(
        "chain",
        (_Q,),
        lambda m, a, o: _skd()._plan_jacobian(m, a["q"], o.frame),
        ("frame",),
        "Jacobians J (N, 6, dof) of the chain from --base to --link",
    ),
    "chain-ik": Operation(
        "chain",
        (_CHAIN_TARGETS, _SEED),
        lambda m, a, o: _skd()._plan_ik(m, a["target"], a.get("seed")),
        (),
        "closed-form IK of the chain, one solution: q (N, dof) and status (N,)",
    ),
    "chain-ik-all": Operation(
        "chain",
        (_CHAIN_TARGETS,),
        lambda m, a, o: _skd()._plan_ik_all(m, a["target"]),
        (),
        "closed-form IK of the chain, every solution: q, valid, exists, exact, status",
    ),
    # rigid-body dynamics: a chain from the URDF (fixed at --base), or the robot's floating base
    "chain-inverse-dynamics": Operation(
        "chain",
        (_Q, _QD, ("qdd", "--qdd", True, "joint accelerations (N, dof)")),
        _inverse_dynamics,
        ("gravity",),
        "joint torques tau (N, dof) = A(q) qdd + C(q, qd) qd + G(q) of the chain (recursive Newton-Euler)",
    ),
    "chain-forward-dynamics": Operation(
        "chain",
        (_Q, _QD, ("tau", "--tau", True, "joint torques (N, dof)")),
        _forward_dynamics,
        ("gravity",),
        "joint accelerations qdd (N, dof) of the chain under torques tau (articulated-body algorithm)",
    ),
    "chain-mass-matrix": Operation(
        "chain",
        (_Q,),
        _mass_matrix,
        (),
        "joint-space inertia matrices A (N, dof, dof) of the chain (composite-rigid-body algorithm)",
    ),
    "chain-gravity": Operation(
        "chain",
        (_Q,),
        lambda m, a, o: _skd()._plan_gravity(m, a["q"], tuple(o.gravity)),
        ("gravity",),
        "gravity torques G (N, dof) of the chain",
    ),
    "floating-inverse-dynamics": Operation(
        "robot",
        (_Q_FLOATING, _V_FLOATING, ("qdd", "--qdd", True, "accelerations (N, 6 + n): dv/dt")),
        _inverse_dynamics,
        ("gravity",),
        "generalised forces tau (N, 6 + n) of the floating base (body wrench, then joint torques)",
    ),
    "floating-forward-dynamics": Operation(
        "robot",
        (_Q_FLOATING, _V_FLOATING, ("tau", "--tau", True, "generalised forces (N, 6 + n)")),
        _forward_dynamics,
        ("gravity",),
        "accelerations qdd (N, 6 + n) of the floating base under generalised forces tau",
    ),
    "floating-mass-matrix": Operation(
        "robot",
        (_Q_FLOATING,),
        _mass_matrix,
        (),
        "inertia matrices A (N, 6 + n, 6 + n) of the floating base",
    ),
    "standing-torques": Operation(
        "robot",
        (
            _POSES,
            ("q", "--q", True, "joints (N, 3 n) in the robot's leg-joint order, or with the arm's after"),
            ("stance", "--stance", False, "stance feet (N, n) bool, or one shared (n,) (default: all)"),
        ),
        lambda m, a, o: _skd()._plan_standing_torques(
            m, a["body_pose"], a["q"], a.get("stance"), tuple(o.gravity), o.seq
        ),
        ("gravity", "seq"),
        "leg torques tau (N, 3 n) holding the robot still on its feet, forces (N, n, 3), status, margin",
    ),
}


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def add_parser(commands) -> None:
    """The ``batch`` subcommand and its operations, on an argparse subparsers object."""
    batch = commands.add_parser(
        "batch",
        help=f"run a batch kernel over datasets on disk (.npy, Zarr) into a Zarr group ({INSTALL})",
        description=(
            "Run one of spotkin's batch kernels over inputs on disk (.npy files, memory-mapped, or Zarr "
            "arrays), chunk by chunk on a Dask scheduler, into a Zarr group with one array per result "
            "field. Memory stays bounded by the chunk size; a stopped run resumes where it stopped when "
            f"started again with the same command. Needs {INSTALL}."
        ),
    )
    operations = batch.add_subparsers(dest="operation", required=True, metavar="OPERATION")
    for name, operation in OPERATIONS.items():
        model = operation.model
        parser = operations.add_parser(name, help=operation.help, description=operation.help)
        parser.add_argument(
            "--robot",
            default="spot",
            help=f"'spot' (sk.Spot()), a packaged description ({', '.join(robots.NAMES)}) or a URDF path",
        )
        if model == "leg":
            parser.add_argument("--leg", required=True, help="the leg's name (robot.leg_names)")
        if model == "chain":
            parser.add_argument("--link", required=True, help="the chain's last link")
            parser.add_argument("--base", default=None, help="the chain's base link (default: the body)")
        for _, option, required, text in operation.inputs:
            parser.add_argument(
                option,
                required=required,
                metavar="PATH",
                help=f"{text}: a .npy file or a Zarr array" + ("" if required else " (optional)"),
            )
        if "seq" in operation.options:
            parser.add_argument("--seq", default="XYZ", help="Euler sequence of (N, 6) poses (default XYZ)")
        if "fallback" in operation.options:
            parser.add_argument(
                "--fallback",
                choices=("nearest", "nan"),
                default="nearest",
                help="for an unreachable target: the nearest in-limit configuration (default) or NaN",
            )
        if "tolerance" in operation.options:
            parser.add_argument(
                "--tolerance", type=float, default=1e-6, help="singular-value threshold (default 1e-6)"
            )
        if "gravity" in operation.options:
            parser.add_argument(
                "--gravity",
                type=float,
                nargs=3,
                default=[0.0, 0.0, -9.81],  # a list, as the run's record reads back from JSON
                metavar=("GX", "GY", "GZ"),
                help="gravity in the base's (a chain's) or the world's (a robot's) frame, m/s2 "
                "(default 0 0 -9.81)",
            )
        if "frame" in operation.options:
            parser.add_argument(
                "--frame",
                choices=("base", "tool"),
                default="base",
                help="the Jacobian's frame (default base)",
            )
        parser.add_argument("--out", required=True, metavar="PATH", help="the output Zarr group")
        parser.add_argument(
            "--chunk-size",
            type=_positive_int,
            default=None,
            help="samples per chunk along the batch axis (default: about 32 MiB of inputs and outputs; "
            "a multiple of a Zarr input's chunks; a resumed run keeps its own)",
        )
        parser.add_argument(
            "--scheduler",
            default="threads",
            help="threads (default), processes, synchronous, or a dask.distributed scheduler address "
            "(tcp://host:8786)",
        )
        parser.add_argument(
            "--workers",
            type=_positive_int,
            default=None,
            help="threads or processes of a local scheduler (default: the cores)",
        )
        parser.add_argument(
            "--overwrite",
            action="store_true",
            help="discard an existing output (a Zarr group) and start anew",
        )
        parser.add_argument("--dry-run", action="store_true", help="check everything, print the plan, stop")
        parser.add_argument("--quiet", action="store_true", help="no plan and no progress bar")
