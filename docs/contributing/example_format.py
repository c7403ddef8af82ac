"""An example format: g and the single-scattering albedo per wavelength, as a text file.

The whole of a format is this module: its writer, its options (each with its command-line
help), what it needs from the table, and how ``dustoptics info`` recognises and describes
its files, in one record registered once.  In the package it would be
``dustoptics/io/<group>/g_table.py`` plus one line in ``dustoptics/io/__init__.py`` that
names it (``FORMAT_MODULES``); ``tests/io/test_format_registry.py`` registers it from here.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io.registry import Format, option, register

#: The first line of every file, by which ``recognise`` knows it.
FIRST_LINE = "# dustoptics g table"


@dataclass(frozen=True)
class GTableOptions:
    """The format's options; None leaves the writer's default."""

    g_digits: int | None = option(
        help="significant digits of g and ssa (default 6)", type="positive_int", metavar="N"
    )


def write_g_table(
    table: Any, out_dir: str | os.PathLike[str], *, overwrite: bool = False, g_digits: int = 6
) -> list[Path]:
    """Write ``<name>_g.txt``: wavelength [nm], g [-] and ssa [-], one row each, atomically."""
    rows = [FIRST_LINE, f"# table {table.name}, input hash {table.provenance.input_hash}"]
    rows += [
        f"{wl:g} {g:.{g_digits}g} {ssa:.{g_digits}g}"
        for wl, g, ssa in zip(table.wavelength_nm, table.g, table.ssa, strict=True)
    ]
    path = Path(out_dir) / f"{safe_stem(table.name)}_g.txt"
    return write_files({path: ("\n".join(rows) + "\n").encode("ascii")}, overwrite=overwrite)


def is_g_table(path: Path) -> bool:
    """A ``.txt`` file whose first line is :data:`FIRST_LINE`."""
    if path.suffix != ".txt" or not path.is_file():
        return False
    with open(path, encoding="ascii", errors="replace") as f:
        return f.readline().rstrip("\n") == FIRST_LINE


def describe_g_table(path: Path, full: bool = True) -> str:
    """What a g table holds, for ``dustoptics info``."""
    lines = path.read_text(encoding="ascii").splitlines()
    rows = [line.split() for line in lines if not line.startswith("#")]
    return "\n".join(
        [f"g table:         {path.name}", f"  {lines[1][2:]}", f"wavelengths:     {len(rows)}"]
    )


RECORD = register(
    Format(
        name="g-table",
        summary="NAME_g.txt: g and ssa per wavelength (an example)",
        write=write_g_table,
        suffixes=(".txt",),
        options=GTableOptions,
        needs=frozenset({"cross_sections"}),
        recognise=is_g_table,
        describe=describe_g_table,
    )
)
