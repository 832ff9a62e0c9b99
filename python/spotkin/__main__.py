"""The ``spotkin`` command line: ``spotkin demo`` runs the showcase on built-in data."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from . import __version__
from ._transforms import translation
from .chain import Chain

# Seed 000 Q1.2: the exam's DHm leg, (sigma, d, alpha, r, theta), with Spot's lengths.
_H1, _H2, _H3 = 0.110945, 0.3205, 0.3365
EXAM_LEG_ROWS = [
    (0, 0.0, -np.pi / 2, 0.0, 0.0),
    (0, 0.0, np.pi / 2, _H1, 0.0),
    (0, _H2, 0.0, 0.0, 0.0),
]


def _throughput(func, arg, repeats: int = 3) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        func(arg)
        best = min(best, time.perf_counter() - start)
    return best


def demo(samples: int = 1_000_000) -> int:
    print(f"spotkin {__version__} demo")
    print()
    leg = Chain.from_mdh(EXAM_LEG_ROWS, tool=translation([_H3, 0.0, 0.0]))
    print(f"Seed 000 exam leg as a DHm chain: {leg!r}")
    q = np.array([0.1, -0.6, 1.2])
    T = leg.fk(q)
    print(f"  q = {q} rad -> foot at {np.round(T[:3, 3], 6)} m")
    J = leg.position_jacobian(q)
    t2, t3 = q[1], q[2]
    det_closed = -_H2 * _H3 * np.sin(t3) * (_H2 * np.cos(t2) + _H3 * np.cos(t2 + t3))
    print(f"  det(J) = {np.linalg.det(J):+.9f}, closed form -h2 h3 s3 (h2 c2 + h3 c23) = {det_closed:+.9f}")
    batch = np.random.default_rng(0).uniform(-np.pi, np.pi, (samples, 3))
    for name, func in (("fk", leg.fk), ("jacobian", leg.jacobian)):
        seconds = _throughput(func, batch)
        print(
            f"  {name:>8} on {samples:,} configurations: {seconds * 1e3:7.1f} ms "
            f"({samples / seconds / 1e6:.1f} M/s, {seconds / samples * 1e9:.0f} ns each)"
        )
    worst = _fd_error(leg, batch[:1000])
    print(f"  worst |J - central finite differences| over 1,000 samples: {worst:.1e}")
    return 0


def _fd_error(chain: Chain, q: np.ndarray, step: float = 1e-6) -> float:
    J = chain.position_jacobian(q)
    worst = 0.0
    for j in range(chain.dof):
        dq = np.zeros(chain.dof)
        dq[j] = step
        column = (chain.fk(q + dq)[:, :3, 3] - chain.fk(q - dq)[:, :3, 3]) / (2 * step)
        worst = max(worst, float(np.abs(column - J[:, :, j]).max()))
    return worst


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="spotkin", description=__doc__)
    parser.add_argument("--version", action="version", version=f"spotkin {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    demo_parser = commands.add_parser("demo", help="run the showcase on the built-in Spot model")
    demo_parser.add_argument(
        "--samples", type=int, default=1_000_000, help="batch size for the throughput figures"
    )
    args = parser.parse_args(argv)
    if args.command == "demo":
        return demo(args.samples)
    return 2  # pragma: no cover


if __name__ == "__main__":
    sys.exit(main())
