"""Descriptions from files and text: the size bound, the XML's own encoding, xacro expanded. Part of
:mod:`spotkin.urdf` (documented there)."""

from __future__ import annotations

import os

MAX_BYTES = 64 * 2**20
"""The largest description read (64 MiB): a URDF of kinematics and inertials is far smaller."""

XACRO_EXTRA = 'pip install "spotkin[xacro]"'


def read_file(path: str | os.PathLike) -> str | bytes:
    """The URDF XML in the file at ``path`` (``str`` or ``os.PathLike``): its bytes (so the XML encoding
    declaration decides), or, for a xacro file (:func:`is_xacro`), its expansion. ``OSError`` when it
    cannot be read (``IsADirectoryError``, ``FileNotFoundError``, ...), ``ValueError`` above
    :data:`MAX_BYTES`, ``TypeError`` for another type."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    name = os.fsdecode(os.fspath(path))
    with open(name, "rb") as fh:
        data = fh.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise ValueError(f"{name!r} is larger than {MAX_BYTES // 2**20} MiB: not a URDF description")
    return expand_xacro(data, name) if is_xacro(data, name) else data


def read_text(text: str | bytes) -> str | bytes:
    """URDF XML given as text (``str``, or ``bytes`` honouring the XML encoding declaration), expanded
    when it is xacro (:func:`is_xacro`). ``ValueError`` above :data:`MAX_BYTES`."""
    if isinstance(text, (bytearray, memoryview)):
        text = bytes(text)
    if not isinstance(text, (str, bytes)):
        raise TypeError(f"text must be a str or bytes holding URDF XML, got {type(text).__name__}")
    if len(text) > MAX_BYTES:
        raise ValueError(f"the text is larger than {MAX_BYTES // 2**20} MiB: not a URDF description")
    return expand_xacro(text) if is_xacro(text) else text


def is_xacro(data: str | bytes, name: str | None = None) -> bool:
    """Whether a description is xacro: its file name ends in ``.xacro``, or its text declares the
    ``xmlns:xacro`` namespace or uses ``<xacro:`` elements."""
    if name is not None and name.lower().endswith(".xacro"):
        return True
    markers = ("xmlns:xacro", "<xacro:")
    if isinstance(data, bytes):
        return any(m.encode() in data for m in markers)
    return any(m in data for m in markers)


def expand_xacro(data: str | bytes, name: str | None = None) -> str:
    """The URDF a xacro description expands to, with the ``xacro`` package (``pip install
    "spotkin[xacro]"``); ``name`` is its file (relative ``<xacro:include>`` are resolved from its
    folder). ``ImportError`` saying what to install when ``xacro`` is missing; ``ValueError`` when the
    expansion fails."""
    what = repr(name) if name else "the description"
    try:
        import xacro
    except ImportError:
        example = os.path.basename(name) if name else "robot.urdf.xacro"
        raise ImportError(
            f"{what} is xacro: expanding it needs the xacro package ({XACRO_EXTRA}), or expand it "
            f"first with `xacro {example} > robot.urdf` and load the URDF"
        ) from None
    text = data.decode("utf-8") if isinstance(data, bytes) else data
    try:
        if name is not None:
            doc = xacro.process_file(name)
        else:
            xacro.init_stacks(None)
            doc = xacro.parse(text)
            xacro.process_doc(doc)
        return doc.toxml()
    except Exception as error:  # xacro raises its own XacroException, XML errors, NameError...
        raise ValueError(f"xacro could not expand {what}: {error}") from None
