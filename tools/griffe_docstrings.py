"""A griffe extension for the documentation site (mkdocs.yml): reads spotkin's docstrings as written.

The docstrings are plain prose in reStructuredText's inline style, with NumPy-style ``Parameters``
sections in a few places. Two things in them are not Markdown, and are rewritten when griffe loads the
package (the source files are not touched):

- Sphinx roles (``:meth:`Robot.from_urdf```, ``:class:`spotkin.Chain```, ``:func:``, ``:attr:``,
  ``:data:``, ``:mod:``, ``:exc:``, ``:obj:``) become inline code: ``Robot.from_urdf``. A leading
  ``~`` (Sphinx's "last component only") is honoured.
- A paragraph that follows a NumPy section without being one of its entries (prose written after the
  ``Parameters`` list, at the section's own indentation) is given a ``Notes`` heading, so that the
  parser does not read its words as parameter names.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:meth|class|func|attr|data|mod|exc|obj|const):`(~?)([^`]+)`")
_SECTION = re.compile(r"^(\s*)(Parameters|Returns|Yields|Raises|Warns|Other Parameters|Attributes)\s*$")
_ENTRY = re.compile(r"^\*{0,2}[A-Za-z_]\w*(\s*,\s*\*{0,2}[A-Za-z_]\w*)*\s*(:.*)?$")


def _role(match: re.Match) -> str:
    target = match.group(2).strip()
    if match.group(1):
        target = target.rsplit(".", 1)[-1]
    return f"`{target}`"


def _close_sections(text: str) -> str:
    """Give trailing prose after a NumPy section (at the section's indentation) a ``Notes`` heading."""
    lines = text.split("\n")
    out: list[str] = []
    section_indent: str | None = None
    i = 0
    while i < len(lines):
        line = lines[i]
        header = _SECTION.match(line)
        if header and i + 1 < len(lines) and set(lines[i + 1].strip()) == {"-"}:
            section_indent = header.group(1)
            out += [line, lines[i + 1]]
            i += 2
            continue
        if (
            section_indent is not None
            and out
            and not out[-1].strip()
            and line.strip()
            and line.startswith(section_indent)
            and not line[len(section_indent) :].startswith((" ", "\t"))
            and not _ENTRY.match(line.strip())
        ):
            out += [f"{section_indent}Notes", f"{section_indent}-----"]
            section_indent = None
        out.append(line)
        i += 1
    return "\n".join(out)


def rewrite(text: str) -> str:
    """The docstring ``text`` with Sphinx roles as inline code and its trailing prose under ``Notes``."""
    return _close_sections(_ROLE.sub(_role, text))


class Docstrings(griffe.Extension):
    """Rewrites every docstring as it is loaded (see the module's docstring)."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = rewrite(obj.docstring.value)
