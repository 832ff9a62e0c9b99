"""The checked-in type stubs match the built extension."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(
    importlib.util.find_spec("pybind11_stubgen") is None, reason="pybind11-stubgen not installed"
)
def test_core_stub_is_up_to_date():
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "stubs.py"), "--check"], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr


def test_package_is_typed():
    import spotkin

    assert (Path(spotkin.__file__).parent / "py.typed").exists()
    assert (Path(spotkin.__file__).parent / "_core.pyi").exists()
