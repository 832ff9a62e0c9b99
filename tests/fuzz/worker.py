"""The worker processes that run the cases, and the pool of them."""

from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
import tempfile
import time

from .cases import label
from .judge import run_case
from .objects import Context

TESTS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the workers import fuzz from tests/


ADDRESS_SPACE = 6 << 30  # bytes: allocations beyond it fail (MemoryError), as do excess thread stacks


def worker_main() -> None:
    """Reads cases (JSON lines) on stdin, writes verdicts on the original stdout; everything the
    library prints goes to stderr."""
    import resource

    proto = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
    ctx = Context()
    proto.write(json.dumps({"ready": True}) + "\n")
    for line in sys.stdin:
        case = json.loads(line)
        sys.stderr.write(f"case {label(case)}\n")
        proto.write(json.dumps(run_case(case, ctx)) + "\n")


class _Worker:
    def __init__(self):
        env = dict(
            os.environ,
            SPOTKIN_NUM_THREADS="1",
            OPENBLAS_NUM_THREADS="1",
            OMP_NUM_THREADS="1",
            MKL_NUM_THREADS="1",
            PYTHONFAULTHANDLER="1",
        )
        env["PYTHONPATH"] = os.pathsep.join(p for p in (TESTS, env.get("PYTHONPATH")) if p)
        self.stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(
            [sys.executable, "-c", "from fuzz.worker import worker_main; worker_main()"],
            cwd=TESTS,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            text=True,
            bufsize=1,
        )
        self.case = None
        self.deadline = 0.0

    def tail(self, size=1500) -> str:
        self.stderr.seek(0, os.SEEK_END)
        end = self.stderr.tell()
        self.stderr.seek(max(0, end - size))
        text = self.stderr.read().decode(errors="replace")
        return "\n".join(line for line in text.splitlines() if not line.startswith("case "))[-size:]

    def kill(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for stream in (self.proc.stdin, self.proc.stdout):
            try:
                stream.close()
            except OSError:  # a broken pipe to a dead worker
                pass
        self.stderr.close()


class Pool:
    """Long-lived worker subprocesses; one dying (crash, abort) or stuck (timeout) is a failure of its
    case and is replaced."""

    def __init__(self, size: int = 2, timeout: float = 60.0):
        self.size, self.timeout = size, timeout
        self.workers: list[_Worker] = []
        self.restarts = 0

    def _spawn(self) -> _Worker:
        worker = _Worker()
        selector = selectors.DefaultSelector()
        selector.register(worker.proc.stdout, selectors.EVENT_READ)
        ready = selector.select(timeout=300)
        selector.close()
        line = worker.proc.stdout.readline() if ready else ""
        if not line.startswith('{"ready"'):
            tail = worker.tail()
            worker.kill()
            raise RuntimeError(f"a fuzz worker failed to start: {line!r}\n{tail}")
        return worker

    def run(self, cases: list[dict]) -> list[dict]:
        results: list[dict | None] = [None] * len(cases)
        pending = list(range(len(cases)))[::-1]
        while len(self.workers) < self.size:
            self.workers.append(self._spawn())
        busy: dict[int, _Worker] = {}
        selector = selectors.DefaultSelector()
        try:
            while pending or busy:
                for worker in self.workers:
                    if worker.case is None and pending:
                        index = pending.pop()
                        worker.case, worker.deadline = index, time.monotonic() + self.timeout
                        worker.proc.stdin.write(json.dumps(cases[index]) + "\n")
                        worker.proc.stdin.flush()
                        selector.register(worker.proc.stdout, selectors.EVENT_READ, worker)
                        busy[index] = worker
                wait = max(0.0, min(w.deadline for w in busy.values()) - time.monotonic())
                events = selector.select(timeout=wait)
                done = [key.data for key, _ in events]
                for worker in list(busy.values()):
                    if worker not in done and time.monotonic() > worker.deadline:
                        done.append(worker)
                for worker in done:
                    index = worker.case
                    selector.unregister(worker.proc.stdout)
                    del busy[index]
                    worker.case = None
                    line = worker.proc.stdout.readline() if worker in [k.data for k, _ in events] else None
                    if line:
                        results[index] = json.loads(line)
                        continue
                    if line is None:
                        results[index] = {
                            "ok": False,
                            "kind": "hang (timeout)",
                            "detail": f"no answer within {self.timeout:.0f} s",
                        }
                    else:
                        worker.proc.wait()
                        code = worker.proc.returncode
                        how = f"signal {-code}" if code < 0 else f"exit code {code}"
                        results[index] = {"ok": False, "kind": "crash", "detail": f"{how}: {worker.tail()}"}
                    worker.kill()
                    self.workers[self.workers.index(worker)] = self._spawn()
                    self.restarts += 1
        finally:
            selector.close()
        return results  # type: ignore[return-value]

    def close(self):
        for worker in self.workers:
            try:
                worker.proc.stdin.close()  # the worker's loop ends
            except OSError:
                pass
            try:
                worker.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
            worker.kill()
        self.workers = []
