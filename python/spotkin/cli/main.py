"""The ``spotkin`` command line: ``spotkin demo`` runs the showcase on built-in data (``--plots DIR``
also writes its pictures); ``spotkin inspect ROBOT.urdf`` shows what a description holds and what
spotkin recognises; ``spotkin plot ROBOT.urdf`` draws a robot in its nominal or zero stance;
``spotkin batch OPERATION`` runs a batch kernel over datasets on disk (``spotkin[dask]``);
``spotkin workspace --robot spot`` estimates a leg's workspace volume and an arm's dexterous region;
``spotkin walk ROBOT.urdf`` walks a quadruped in the MuJoCo simulator (``spotkin[sim]``)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from .._support.version import __version__
from ..scale import batch_operations, batch_run
from ..scale.batch_operations import _positive_int
from .demo import demo
from .pictures import PLOT_EXTRA, plot_stance
from .reports import inspect, workspace_report
from .walk import SIM_EXTRA, walk


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT in pixels (e.g. 800x600), got {text!r}"
        ) from None
    if width < 16 or height < 16 or width > 10_000 or height > 10_000:
        raise argparse.ArgumentTypeError(f"each side must be 16 to 10000 pixels, got {text!r}")
    return width, height


DEMO_MAX_SAMPLES = 10_000_000  # the demo holds a few arrays of this many samples (GBs at the bound)
WALK_MAX_DURATION = 3600.0  # s: an hour of simulated walk (about half an hour of computing)
DPI_RANGE = (10, 600)  # below 10 dpi the fonts get no pixel (FreeType refuses); above, GIF frames of GBs


def _out_of_range(args) -> str | None:
    """What is wrong with a parsed option's value (a count, a resolution) that argparse's types accept,
    or None: checked before anything is loaded, computed or allocated."""
    from ..kinematics import workspace as _workspace

    checks = []
    if args.command == "demo":
        checks.append(("--samples", args.samples, 1, DEMO_MAX_SAMPLES))
    if args.command in ("demo", "plot", "walk"):
        checks.append(("--dpi", args.dpi, *DPI_RANGE))
    if args.command == "walk":
        if not (np.isfinite(args.duration) and 0 < args.duration <= WALK_MAX_DURATION):
            return f"--duration must be in (0, {WALK_MAX_DURATION:g}] seconds, got {args.duration}"
        if not np.isfinite(args.velocity).all():
            return f"--velocity must be three finite numbers, got {args.velocity}"
    if args.command == "workspace":
        checks.append(("--samples", args.samples, 1, _workspace.MAX_VOLUME_SAMPLES))
        checks.append(("--orientations", args.orientations, 1, _workspace.MAX_ORIENTATIONS))
        checks.append(("--seed", args.seed, 0, 2**64 - 1))
        if not (np.isfinite(args.spacing) and args.spacing > 0):
            return f"--spacing must be a positive number of metres, got {args.spacing}"
    for option, value, low, high in checks:
        if not low <= value <= high:
            return f"{option} must be in [{low:,}, {high:,}], got {value:,}"
    return None


def main(argv: list[str] | None = None) -> int:
    # the module docstring without its reST markup: ``spotkin demo`` reads "spotkin demo" in a terminal
    parser = argparse.ArgumentParser(prog="spotkin", description=__doc__.replace("``", '"'))
    parser.add_argument("--version", action="version", version=f"spotkin {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    demo_parser = commands.add_parser("demo", help="run the showcase on the built-in Spot model")
    demo_parser.add_argument(
        "--samples",
        type=_positive_int,
        default=1_000_000,
        help="batch size for the throughput figures (1 to 10,000,000; default 1,000,000)",
    )
    inspect_parser = commands.add_parser(
        "inspect", help="show a URDF's tree and the legs and arms spotkin recognises in it"
    )
    inspect_parser.add_argument("urdf", help="path of the URDF file")
    demo_parser.add_argument(
        "--plots",
        metavar="DIR",
        help=f"also write the demo's pictures (PNGs and GIFs) into DIR (needs matplotlib: {PLOT_EXTRA})",
    )
    dpi_help = "resolution of the pictures (10 to 600; default 100)"
    demo_parser.add_argument("--dpi", type=_positive_int, default=100, help=dpi_help)
    plot_parser = commands.add_parser(
        "plot", help=f"draw a robot from its URDF in its nominal or zero stance (needs {PLOT_EXTRA})"
    )
    plot_parser.add_argument("urdf", help="path of the URDF file, or spot, spot_with_arm, go2 (packaged)")
    plot_parser.add_argument("--out", help="the PNG to write (default: NAME_stance.png here)")
    plot_parser.add_argument("--stance", choices=("nominal", "zero"), default="nominal")
    plot_parser.add_argument(
        "--view", choices=("3d", "side", "front", "top"), default="3d", help="3D (default) or a 2D view"
    )
    plot_parser.add_argument(
        "--size", type=_size, default=(800, 600), help="WIDTHxHEIGHT in pixels (800x600)"
    )
    plot_parser.add_argument("--dpi", type=_positive_int, default=100, help=dpi_help)
    workspace_parser = commands.add_parser(
        "workspace", help="estimate a leg's workspace volume and an arm's dexterous region by sampling"
    )
    workspace_parser.add_argument(
        "--robot", default="spot", help="spot (built-in), a packaged name or a URDF path"
    )
    workspace_parser.add_argument(
        "--samples",
        type=_positive_int,
        default=2_000_000,
        help="Monte Carlo points for the leg volume (at most 1e10; default 2,000,000)",
    )
    workspace_parser.add_argument(
        "--spacing", type=float, default=0.05, help="arm grid spacing, m (default 0.05)"
    )
    workspace_parser.add_argument(
        "--orientations",
        type=_positive_int,
        default=128,
        help="orientations sampled per arm grid position (at most 1,000,000; default 128)",
    )
    workspace_parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    walk_parser = commands.add_parser(
        "walk",
        help=f"walk a quadruped in the MuJoCo simulator with the closed-loop gait controller ({SIM_EXTRA})",
    )
    walk_parser.add_argument("urdf", help="path of the URDF file, or spot (built-in), go2 (packaged)")
    walk_parser.add_argument(
        "--gait", default="trot", help="stand, walk, trot, pace, bound, pronk or gallop (default trot)"
    )
    walk_parser.add_argument(
        "--velocity",
        type=float,
        nargs=3,
        default=(0.3, 0.0, 0.0),
        metavar=("VX", "VY", "YAW_RATE"),
        help="the command: m/s forward, m/s to the left, rad/s (default 0.3 0 0), ramped over 1 s",
    )
    walk_parser.add_argument("--duration", type=float, default=10.0, help="seconds simulated (default 10)")
    walk_parser.add_argument(
        "--plots",
        metavar="DIR",
        help=f"also write the gait diagram, the foot paths and an animation of the walk (GIF) into DIR "
        f"({PLOT_EXTRA})",
    )
    walk_parser.add_argument("--dpi", type=_positive_int, default=100, help=dpi_help)
    batch_operations.add_parser(commands)  # spotkin batch OPERATION ... (spotkin/scale/batch_*.py)
    args = parser.parse_args(argv)
    if args.command == "batch":
        return batch_run.main(args)
    refused = _out_of_range(args)
    if refused:  # before any work, as argparse refuses malformed values: one line, exit 2
        print(f"spotkin {args.command}: error: {refused}", file=sys.stderr)
        return 2
    if args.command == "demo":
        try:
            return demo(args.samples, args.plots, args.dpi)
        except (ImportError, OSError) as error:
            print(f"spotkin demo: {error}", file=sys.stderr)
            return 1
    if args.command == "plot":
        try:
            return plot_stance(args.urdf, args.out, args.stance, args.size, args.dpi, args.view)
        except (ImportError, OSError, ValueError) as error:
            print(f"spotkin plot: {error}", file=sys.stderr)
            return 1
    if args.command == "workspace":
        try:
            return workspace_report(args.robot, args.samples, args.spacing, args.orientations, args.seed)
        except (OSError, ValueError) as error:
            print(f"spotkin workspace: {error}", file=sys.stderr)
            return 1
    if args.command == "walk":
        try:
            return walk(args.urdf, args.gait, args.velocity, args.duration, args.plots, args.dpi)
        except (ImportError, OSError, ValueError, TypeError) as error:
            print(f"spotkin walk: {error}", file=sys.stderr)
            return 1
    if args.command == "inspect":
        try:
            return inspect(args.urdf)
        except (OSError, ValueError) as error:
            print(f"spotkin inspect: {error}", file=sys.stderr)
            return 1
    return 2  # pragma: no cover
