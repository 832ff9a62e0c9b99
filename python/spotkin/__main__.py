"""``python -m spotkin`` and the ``spotkin`` script: the command line, in :mod:`spotkin.cli`."""

from __future__ import annotations

import sys

from .cli.demo import LEG_MDH_ROWS
from .cli.main import main
from .cli.pictures import GIF_SIZE

__all__ = ["GIF_SIZE", "LEG_MDH_ROWS", "main"]

if __name__ == "__main__":
    sys.exit(main())
