"""Generate the type stubs of spotkin._core with pybind11-stubgen.

python tools/stubs.py           # rewrite python/spotkin/_core.pyi
python tools/stubs.py --check   # exit 1 if the checked-in stub is stale
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

STUB = Path(__file__).resolve().parents[1] / "python" / "spotkin" / "_core.pyi"


def generate() -> str:
    with tempfile.TemporaryDirectory() as out:
        subprocess.run(
            [sys.executable, "-m", "pybind11_stubgen", "spotkin._core", "-o", out],
            check=True,
            capture_output=True,
        )
        return (Path(out) / "spotkin" / "_core.pyi").read_text()


def main() -> int:
    text = generate()
    if "--check" in sys.argv[1:]:
        if STUB.read_text() != text:
            print(f"{STUB} is stale: run `python tools/stubs.py`", file=sys.stderr)
            return 1
        return 0
    STUB.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
