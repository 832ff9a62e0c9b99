"""Single-call latency from Python against Pinocchio (bench/latency.py), in a fresh interpreter.

pytest-benchmark's harness adds about 0.6-0.9 us per call, and the pytest process itself (its warning
filters and fault handler) slows each call by a further 0.3-1 us, which would hide the sub-microsecond
figures the targets name. So the calls are timed in a separate, plain Python process, each next to the
Pinocchio call it is compared with; the targets are ratios. ``pytest bench/bench_latency.py -s`` prints
the table.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("pinocchio")


def test_single_call_latency_against_pinocchio(capsys):
    script = Path(__file__).with_name("latency.py")
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=True)
    with capsys.disabled():
        print("\n" + result.stdout, end="")
