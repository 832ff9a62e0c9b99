"""Single-call latency from Python, by timeit in a fresh interpreter.

pytest-benchmark's harness adds about 0.6-0.9 us per call, and the pytest process
itself (its warning filters and fault handler) slows each call by a further
0.3-1 us, which would hide the sub-microsecond figures the targets name. So the
calls are timed in a separate, plain Python process.
"""

from __future__ import annotations

import subprocess
import sys

SCRIPT = r"""
import timeit
import numpy as np
import spotkin as sk

spot = sk.Spot()
leg, arm = spot.leg("fl"), spot.arm
feet = spot.stance_feet(0.5)
pose = np.array([0.02, -0.01, 0.48, 0.05, -0.08, 0.1])
q12 = spot.body_ik(pose, feet).q
p = leg.fk(np.array([0.1, 1.0, -1.6]))
T = arm.fk(np.array([0.1, -1.0, 1.5, 0.2, 0.5, 0.0]))
rows = np.array([(0, 0, 0, 0.3, 0), (0, 0.05, -np.pi / 2, 0, -np.pi / 2), (0, 0.4, 0, 0, 0),
                 (0, 0.03, -np.pi / 2, 0.42, 0), (0, 0, np.pi / 2, 0, 0), (0, 0, -np.pi / 2, 0, 0)])
chain = sk.Chain.from_mdh(rows, tool=sk.translation([0, 0, 0.1]))
q6 = np.full(6, 0.3)
q3 = np.array([0.1, 0.9, -1.5])
T6 = chain.fk(q6 + 0.1)
targets = {"chain6.fk": 2.0, "chain6.jacobian": 2.0, "leg.ik": 1.0}
targets.update({"arm.ik": 2.0, "arm.ik_all": 2.0, "body_ik": 1.2})
calls = {
    "chain6.fk": lambda: chain.fk(q6),
    "chain6.jacobian": lambda: chain.jacobian(q6),
    "leg.fk": lambda: leg.fk(p),
    "leg.ik": lambda: leg.ik(p),
    "leg.ik_all": lambda: leg.ik_all(p),
    "arm.ik": lambda: arm.ik(T),
    "arm.ik_all": lambda: arm.ik_all(T),
    "leg.ik(p, seed)": lambda: leg.ik(p, q3),
    "arm.ik(T, seed)": lambda: arm.ik(T, q6),
    "chain6.ik": lambda: chain.ik(T6),
    "chain6.ik_nearest": lambda: chain.ik_nearest(T6, q6),
    "body_ik": lambda: spot.body_ik(pose, feet),
    "body_fk": lambda: spot.body_fk(pose, q12),
}
n = 20_000
print("single-call latency from Python (fresh interpreter, best of 7 x 20,000 calls, timeit)")
for name, call in calls.items():
    us = min(timeit.repeat(call, number=n, repeat=7)) / n * 1e6
    target = targets.get(name)
    print(f"  {name:<16} {us:6.2f} us" + ("" if target is None else f"  (target < {target} us)"))
"""


def test_single_call_latency(capsys):
    result = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True)
    with capsys.disabled():
        print("\n" + result.stdout, end="")
