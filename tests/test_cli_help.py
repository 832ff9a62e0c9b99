"""The command line's help reads as plain text: no reST markup (double backticks) in any command's help."""

from __future__ import annotations

import contextlib
import io

import pytest

from spotkin.__main__ import main


def _help(argv):
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as exit_info:
        main([*argv, "--help"])
    assert exit_info.value.code == 0
    return out.getvalue()


@pytest.mark.parametrize(
    "argv", [[], ["demo"], ["inspect"], ["plot"], ["workspace"], ["walk"], ["batch"], ["batch", "body-ik"]]
)
def test_help_has_no_rest_markup(argv):
    text = _help(argv)
    assert "usage: spotkin" in text
    assert "``" not in text and ":func:" not in text and ":meth:" not in text
