"""The documentation site builds with warnings as errors, and its API reference covers the public API.

``mkdocs build --strict`` (configuration: ``mkdocs.yml``) fails on a broken link or anchor, a page left
out of the navigation, an object the API reference cannot find or a docstring griffe cannot parse. The
build needs the ``docs`` extra (``requirements-test.txt`` installs it); without it that test is skipped,
saying so. The checks of the sources (every public name and module has its API entry, every picture is
in the gallery) need nothing but the repository.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

import spotkin as sk

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
# The public modules with a page of their own (docs/api/NAME.md); the subpackages' private modules
# are never documented by their own paths.
PUBLIC_MODULES = (
    "urdf",
    "trajectory",
    "dynamics",
    "inertia",
    "paul",
    "differential",
    "models",
    "robots",
    "plot",
    "sim",
    "sdk",
    "dask",
)
_DIRECTIVE = re.compile(r"^::: (\S+)\s*$", re.MULTILINE)


def _exported_objects() -> list[str]:
    """The names of ``spotkin.__all__`` that are not modules (the submodules have pages of their own)."""
    return [name for name in sk.__all__ if not isinstance(getattr(sk, name), types.ModuleType)]


def test_the_api_reference_lists_every_public_name():
    listed = _DIRECTIVE.findall((DOCS / "api" / "spotkin.md").read_text(encoding="utf-8"))
    expected = {f"spotkin.{name}" for name in _exported_objects()}
    assert len(listed) == len(set(listed)), "a name is listed twice in docs/api/spotkin.md"
    assert not expected - set(listed), f"missing from docs/api/spotkin.md: {sorted(expected - set(listed))}"
    assert not set(listed) - expected, f"not in spotkin.__all__: {sorted(set(listed) - expected)}"


@pytest.mark.parametrize("module", PUBLIC_MODULES)
def test_each_public_module_has_a_page(module):
    page = DOCS / "api" / f"{module}.md"
    assert page.exists(), f"no API page for spotkin.{module}"
    assert _DIRECTIVE.findall(page.read_text(encoding="utf-8")) == [f"spotkin.{module}"]


def test_the_api_reference_names_no_private_module():
    for page in sorted((DOCS / "api").glob("*.md")):
        for target in _DIRECTIVE.findall(page.read_text(encoding="utf-8")):
            assert not any(part.startswith("_") for part in target.split(".")), f"{page.name}: {target}"


def test_the_gallery_shows_every_picture():
    text = (DOCS / "gallery.md").read_text(encoding="utf-8")
    pictures = sorted(p.name for p in DOCS.iterdir() if p.suffix in (".png", ".gif"))
    assert pictures
    for name in pictures:
        assert f"]({name})" in text, f"docs/gallery.md does not show {name}"


def _docs_tools_missing() -> str | None:
    for module in ("mkdocs", "mkdocstrings", "mkdocstrings_handlers.python", "material"):
        try:
            if importlib.util.find_spec(module) is None:
                return module
        except ModuleNotFoundError:
            return module
    return None


def test_the_site_builds_strictly(tmp_path):
    missing = _docs_tools_missing()
    if missing:
        pytest.skip(
            f'the documentation tools are not installed ({missing}): pip install ".[docs]" (Python 3.11+)'
        )
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, f"mkdocs build --strict failed:\n{run.stdout}\n{run.stderr}"
    assert (site / "index.html").exists()
    for page in ("conventions", "gallery", "guide/whole-body", "api/spotkin", "derivations"):
        assert (site / page / "index.html").exists(), page
    # every exported object got its entry (griffe found it through the public path)
    html = (site / "api" / "spotkin" / "index.html").read_text(encoding="utf-8")
    for name in _exported_objects():
        assert f'id="spotkin.{name}"' in html, f"no API entry for spotkin.{name}"
    for module in PUBLIC_MODULES:
        page = (site / "api" / module / "index.html").read_text(encoding="utf-8")
        assert re.search(rf'id="spotkin\.{module}\.\w+"', page), f"spotkin.{module}'s page documents nothing"
    # the docstrings' Sphinx roles became inline code (tools/griffe_docstrings.py)
    assert ":meth:`" not in html and ":class:`" not in html
