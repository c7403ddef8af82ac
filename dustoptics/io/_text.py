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
import math
import unicodedata
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._files import (
    MAX_JSON_DEPTH,
    MAX_TEXT_BYTES,
    FormatError,
    load_json,
    read_checked,
)

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


#: Largest number of cells a CSV reader parses (counted before parsing).
MAX_CSV_CELLS = 4_000_000


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
