"""The documentation runs as written: every ```python block of README.md and docs/**/*.md is executed.

Each block runs in a fresh namespace of its own, so that a reader can copy any one snippet and run
it: a block defines (or imports) every name it uses. Blocks run in file order, each compiled with its
real line numbers, so a traceback points into the Markdown file. A block that is intentionally not
executable is preceded by an HTML comment ``<!-- not-run: reason -->`` (none at the time of writing).

The same files must not point to material a user of the repository does not have, and the demo
command must speak of robots, legs and arms and reject a bad ``--samples`` cleanly.
"""

from __future__ import annotations

import re
import traceback
from pathlib import Path

import pytest

import spotkin as sk
from spotkin.__main__ import main

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]

_FENCE = re.compile(r"^```(\S*)\s*$")
_NOT_RUN = re.compile(r"^<!--\s*not-run:\s*\S.*-->\s*$")
# Course vocabulary that means nothing to a user of the repository ("seed 000", "exam", "annex",
# question numbers such as "Q3.2"), and paths outside it.
_FORBIDDEN = re.compile(r"\.\./shared|seeds?[\s_]*0\d\d|exam(?!pl|in)|annex|\bQ\d\.\d", re.IGNORECASE)


def _blocks(path: Path) -> list[tuple[int, str, bool]]:
    """Every ```python block of a Markdown file: (line of its first code line, source, runs)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    blocks = []
    i = 0
    while i < len(lines):
        match = _FENCE.match(lines[i])
        if match and match.group(1):
            language = match.group(1)
            start = i + 1
            end = start
            while end < len(lines) and lines[end].strip() != "```":
                end += 1
            if end == len(lines):
                raise AssertionError(f"{path.name}:{i + 1}: unclosed code fence")
            previous = next((lines[j] for j in range(i - 1, -1, -1) if lines[j].strip()), "")
            if language == "python":
                blocks.append((start + 1, "\n".join(lines[start:end]), not _NOT_RUN.match(previous)))
            i = end + 1
        else:
            i += 1
    return blocks


def _headings(path: Path) -> set[str]:
    """GitHub's anchors for the headings of a Markdown file (outside code blocks)."""
    anchors, fenced = set(), False
    for text in path.read_text(encoding="utf-8").splitlines():
        if text.startswith("```"):
            fenced = not fenced
        elif not fenced and text.startswith("#"):
            title = text.lstrip("#").strip().lower()
            anchors.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return anchors


def _cases():
    for path in DOCUMENTS:
        for line, source, runs in _blocks(path):
            yield pytest.param(path, line, source, runs, id=f"{path.relative_to(ROOT)}:{line}")


@pytest.fixture
def restore_threads():
    before = sk.get_num_threads()
    yield
    sk.set_num_threads(before)


def test_the_documents_have_python_blocks():
    # the README is the quick start (its five examples); the manual's blocks are in docs/
    assert len(_blocks(ROOT / "README.md")) >= 5
    assert sum(len(_blocks(path)) for path in DOCUMENTS[1:]) >= 20


@pytest.mark.parametrize(("path", "line", "source", "runs"), list(_cases()))
def test_python_block_runs(path, line, source, runs, restore_threads):
    if not runs:
        pytest.skip(f"{path.name}:{line}: marked not-run")
    if "from spotkin import plot" in source:  # the optional extra: drawn into files with Agg
        matplotlib = pytest.importorskip("matplotlib", reason='the block draws: pip install "spotkin[plot]"')
        matplotlib.use("Agg")
    if "from spotkin import sim" in source:  # the optional extra
        pytest.importorskip("mujoco", reason='the block simulates: pip install "spotkin[sim]"')
    # pad with blank lines so that tracebacks give the Markdown file's own line numbers
    code = compile("\n" * (line - 1) + source, str(path), "exec")
    namespace = {"__name__": f"{path.stem}_block_{line}"}
    try:
        exec(code, namespace)
    except Exception as error:
        frames = [f for f in traceback.extract_tb(error.__traceback__) if f.filename == str(path)]
        where = frames[-1].lineno if frames else line
        raise AssertionError(
            f"{path.relative_to(ROOT)}:{where}: {type(error).__name__}: {error} "
            f"(in the python block starting at line {line})"
        ) from error


@pytest.mark.parametrize("path", DOCUMENTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_documents_speak_to_users_of_the_repository(path):
    for number, text in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        match = _FORBIDDEN.search(text)
        assert match is None, f"{path.relative_to(ROOT)}:{number}: {match.group(0)!r} in {text.strip()!r}"


@pytest.mark.parametrize("path", DOCUMENTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_and_anchors_resolve(path):
    text = path.read_text(encoding="utf-8")
    for target, anchor in re.findall(r"\]\(([^)#\s]*)(?:#([^)\s]*))?\)", text):
        if "://" in target or target.startswith("mailto:"):
            continue
        linked = path.parent / target if target else path
        assert linked.exists(), f"{path.relative_to(ROOT)}: broken link {target!r}"
        if anchor and linked.suffix == ".md":
            assert anchor in _headings(linked), f"{path.relative_to(ROOT)}: no heading for {target}#{anchor}"


def test_demo_rejects_a_non_positive_sample_count(capsys):
    for samples in ("0", "-5"):
        with pytest.raises(SystemExit) as exit_info:
            main(["demo", "--samples", samples])
        assert exit_info.value.code == 2  # argparse's usage error
        assert "--samples" in capsys.readouterr().err


def test_demo_speaks_of_robots_legs_and_arms(capsys, restore_threads):
    assert main(["demo", "--samples", "2000"]) == 0
    out = capsys.readouterr().out
    assert _FORBIDDEN.search(out) is None, _FORBIDDEN.search(out).group(0)
    assert re.search(r"\bseed\s+\d", out, re.IGNORECASE) is None
    for word in ("Whole body", "leg", "Arm"):
        assert word in out
