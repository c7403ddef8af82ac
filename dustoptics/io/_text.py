"""Exact number formatting and strict CSV parsing shared by the text formats.

Every float is written with Python's shortest round-trip ``repr``, so reading
the text back with :func:`float` gives the written float bit for bit.  A unit
change by a power of ten (um^2 -> m^2, nm -> m) is applied to that decimal
text by shifting its exponent (:func:`shift`), which is exact in decimal: the
file holds the correctly rounded converted value, and shifting back when
reading (:func:`parse` with ``exponent``) restores the original float exactly.

The parsing helpers raise :class:`~dustoptics.io._atomic.FormatError` naming
the file, the line and the column.
"""

from __future__ import annotations

import csv
import decimal
import io
import json
import math
import os
import stat
import unicodedata
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import FormatError

__all__ = [
    "MAX_CSV_CELLS",
    "MAX_JSON_DEPTH",
    "MAX_TEXT_BYTES",
    "check_increasing",
    "floats",
    "load_json",
    "number",
    "parse",
    "printable",
    "read_checked",
    "read_rows",
    "shift",
    "wavelength_label",
]


def floats(name: str, values: Any) -> list[float]:
    """Plain Python floats of ``values`` (``repr`` of numpy scalars is not a number in numpy 2).

    Raises
    ------
    ValueError
        A value is not finite; the message names ``name``.
    """
    out = np.asarray(values, dtype=np.float64).ravel().tolist()
    for x in out:
        if not math.isfinite(x):
            raise ValueError(f"table.{name} must be finite to be written; got {x!r}")
    return out


def number(x: float) -> str:
    """Shortest string that parses back to exactly ``x``.

    >>> number(0.1), number(1e-7)
    ('0.1', '1e-07')
    """
    return repr(float(x))


def wavelength_label(x: float) -> str:
    """``360`` for 360.0, the round-trip repr otherwise.

    >>> wavelength_label(360.0), wavelength_label(552.5)
    ('360', '552.5')
    """
    return str(int(x)) if float(x).is_integer() else repr(float(x))


def shift(x: float, exponent: int) -> str:
    """``repr(x)`` times ``10**exponent``, exactly, as a decimal string.

    >>> shift(1.5, -12), shift(440.0, -9)
    ('1.5e-12', '4.400e-7')
    """
    if exponent == 0 or x == 0.0:
        return repr(float(x))
    return format(decimal.Decimal(repr(float(x))).scaleb(exponent), "e")


#: Largest text file (CSV, JSON sidecar) a reader accepts: 64 MiB, 40 times a
#: 48 x 1,801 seed CSV table. [bytes]
MAX_TEXT_BYTES = 64 * 1024**2

#: Largest number of cells a CSV reader parses (counted before parsing).
MAX_CSV_CELLS = 4_000_000

#: Deepest nesting of arrays and objects a JSON sidecar may have (ours have 4).
MAX_JSON_DEPTH = 32


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


def read_rows(path: Path) -> list[list[str]]:
    """Rows of an ASCII CSV file that ends with a newline.

    The file is read with :func:`read_checked` (a regular file, at most
    :data:`MAX_TEXT_BYTES`); its cells are counted before parsing (at most
    :data:`MAX_CSV_CELLS`); a blank line, or a cell beyond the csv module's
    field limit, is a :class:`FormatError`.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    FormatError
        Not a regular file, too large, not ASCII, empty, missing its final
        newline (truncated), blank lines, or too many or too long cells.
    """
    data = read_checked(path)
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as exc:
        raise FormatError(
            f"{path}: not an ASCII CSV file ({exc.reason} at byte {exc.start})"
        ) from None
    if not text:
        raise FormatError(f"{path}: file is empty (expected a header line)")
    if not text.endswith("\n"):
        raise FormatError(f"{path}: file does not end with a newline (truncated?)")
    cells = text.count(",") + text.count("\n")
    if cells > MAX_CSV_CELLS:
        raise FormatError(
            f"{path}: about {cells} cells, more than the {MAX_CSV_CELLS} this reader accepts"
        )
    try:
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error as exc:
        raise FormatError(f"{path}: not a valid CSV file ({exc})") from None
    for i, row in enumerate(rows, start=1):
        if not row or all(not cell.strip() for cell in row):
            raise FormatError(f"{path}: line {i} is blank (expected comma-separated values)")
    return rows


def parse(path: Path, line: int, column: str, cell: str, exponent: int = 0) -> float:
    """Parse one finite number; undo a decimal shift of ``exponent`` exactly.

    Raises
    ------
    FormatError
        Not a finite number; the message names the file, line and column.
    """
    try:
        if exponent:
            value = float(decimal.Decimal(cell.strip()).scaleb(-exponent))
        else:
            value = float(cell)
    except (ValueError, decimal.InvalidOperation):
        raise FormatError(f"{path}: line {line}, column {column}: not a number: {cell!r}") from None
    if not math.isfinite(value):
        raise FormatError(f"{path}: line {line}, column {column}: not a finite number: {cell!r}")
    return value


def check_increasing(path: Path, what: str, values: np.ndarray) -> None:
    """Raise :class:`FormatError` unless ``values`` increase strictly."""
    if values.size > 1 and not np.all(np.diff(values) > 0):
        i = int(np.argmax(np.diff(values) <= 0))
        raise FormatError(
            f"{path}: {what} must be strictly increasing; got {values[i]!r} then {values[i + 1]!r}"
        )


def printable(text: str) -> str:
    """``text`` safe for a terminal: control and format characters escaped.

    Escape sequences (ESC, CSI ``\\x9b``), carriage returns, backspaces, NUL,
    bidirectional overrides and every other character of Unicode category C
    are shown as Python escapes (``\\x1b``, ``\\u202e``), so that text read
    from a file cannot move the cursor, recolour or rewrite the terminal.
    Tabs and newlines are escaped too: one call gives one line.

    >>> printable("red\\x1b[31m")
    'red\\\\x1b[31m'
    """
    out = []
    for c in str(text):
        if unicodedata.category(c).startswith("C"):
            code = ord(c)
            out.append(
                f"\\x{code:02x}"
                if code < 0x100
                else (f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}")
            )
        else:
            out.append(c)
    return "".join(out)
