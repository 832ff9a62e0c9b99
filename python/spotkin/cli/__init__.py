"""The ``spotkin`` command line (``python -m spotkin``, the ``spotkin`` script): ``main`` parses the
command (``main.py``); ``demo``, ``pictures`` (``demo --plots``, ``plot``) and ``reports``
(``inspect``, ``workspace``) run them; ``spotkin batch`` runs in :mod:`spotkin.scale`. The top layer:
it imports any other part, nothing imports it but ``spotkin.__main__``."""
