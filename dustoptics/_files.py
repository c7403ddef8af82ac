"""Files read within bounds, and the error a damaged or foreign file raises.

The bottom of the package: every layer that reads a file given by a user (the
material and ozone tables, tabulated size distributions, the readers of
:mod:`dustoptics.io`) reads it through :func:`read_checked`, which refuses a
FIFO, a device or an oversized file before reading a byte, and parses JSON
through :func:`load_json`, which refuses nesting deep enough to exhaust the
parser's stack.  Both raise :class:`FormatError` naming the file.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path
from typing import Any

__all__ = [
    "MAX_CONFIG_BYTES",
    "MAX_JSON_DEPTH",
    "MAX_TEXT_BYTES",
    "FormatError",
    "load_json",
    "read_checked",
    "read_config_text",
]

#: Largest text file (CSV, JSON sidecar) a reader accepts: 64 MiB, 40 times a
#: 48 x 1,801 seed CSV table. [bytes]
MAX_TEXT_BYTES = 64 * 1024**2

#: Largest TOML configuration file a command reads (``build CONFIG``, ``sweep CONFIG``,
#: ``retrieve --model``): 16 MiB, a thousand times a preset with a tabulated distribution.
#: [bytes]
MAX_CONFIG_BYTES = 16 * 1024**2

#: Deepest nesting of arrays and objects a JSON sidecar may have (ours have 4).
MAX_JSON_DEPTH = 32


class FormatError(ValueError):
    """A file given to a reader is malformed, truncated or not of the expected format.

    The message names the file and what is wrong with it.
    """


def read_checked(path: str | os.PathLike[str], *, limit: int = MAX_TEXT_BYTES) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes.

    The file is opened without blocking and checked with ``fstat`` before a
    byte is read: a FIFO, a device (``/dev/zero``), a socket or a directory is
    refused, so is a file larger than ``limit``; at most ``limit + 1`` bytes
    are read even if the file grows meanwhile.

    Raises
    ------
    FileNotFoundError
        No such file.
    FormatError
        Not a regular file, or larger than ``limit``.
    """
    p = Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except IsADirectoryError:
        raise FormatError(f"{p}: is a directory, not a regular file") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise FormatError(
                f"{p}: not a regular file (a FIFO, device, socket or directory); refused"
            )
        if info.st_size > limit:
            raise FormatError(
                f"{p}: {info.st_size} bytes, larger than the {limit}-byte limit of this reader"
            )
        chunks = []
        remaining = limit + 1
        while remaining > 0:
            chunk = os.read(fd, min(remaining, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            remaining -= len(chunk)
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > limit:
        raise FormatError(f"{p}: larger than the {limit}-byte limit of this reader")
    return data


def _json_depth(text: str) -> int:
    """Deepest nesting of ``[``/``{`` in JSON text (outside strings)."""
    depth = deepest = 0
    in_string = escaped = False
    for c in text:
        if in_string:
            if escaped:
                escaped = False
            elif c == "\\":
                escaped = True
            elif c == '"':
                in_string = False
        elif c == '"':
            in_string = True
        elif c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth -= 1
    return deepest


def load_json(path: str | os.PathLike[str], *, encoding: str = "utf-8") -> Any:
    """Parse a JSON file read with :func:`read_checked`, nesting at most :data:`MAX_JSON_DEPTH`.

    Raises
    ------
    FormatError
        Not a regular file, too large, not text in ``encoding``, nested too
        deeply, or not JSON.
    """
    p = Path(path)
    try:
        text = read_checked(p).decode(encoding)
    except UnicodeDecodeError as exc:
        raise FormatError(f"{p}: not {encoding} text ({exc.reason} at byte {exc.start})") from None
    if _json_depth(text) > MAX_JSON_DEPTH:
        raise FormatError(f"{p}: JSON nested deeper than {MAX_JSON_DEPTH} levels; refused")
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise FormatError(f"{p}: not valid JSON ({' '.join(str(exc).split())})") from None


def read_config_text(path: str | os.PathLike[str], *, limit: int = MAX_CONFIG_BYTES) -> str:
    """The UTF-8 text of a configuration file, read as :func:`read_checked` reads (a FIFO, a
    device or a file over ``limit`` bytes refused before a byte is read).

    Raises
    ------
    FileNotFoundError
        No such file.
    FormatError
        Not a regular file, larger than ``limit``, or not UTF-8 text.
    """
    data = read_checked(path, limit=limit)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FormatError(
            f"{Path(path)}: not UTF-8 text (byte {exc.start}); a configuration is a TOML file"
        ) from None
