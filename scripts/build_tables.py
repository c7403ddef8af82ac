"""Rebuild the preset tables kept in ``tables/`` (or check that they are current).

Usage::

    python scripts/build_tables.py           # rebuild every preset into tables/NAME/
    python scripts/build_tables.py --check   # exit 1 if any table is out of date

Each preset (``dustoptics presets``) is written as ``tables/NAME/NAME.nc``
(the full table with its provenance, CF-1.10 netCDF-4) and ``tables/NAME/NAME_phase.glsl`` (the
shader snippet at its defaults).  ``--check`` recomputes every preset and
compares it with the stored file: the inputs (their hash) must be equal
and the numbers equal to 1e-9 relative (error estimates: 1e-6; far below the tables' 1e-4 accuracy,
far above the last-bit differences a different CPU or library build may
give), so a change of code or preset that moves a table fails the check.
The test suite runs the same check (``tests/test_tables.py``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dustoptics.compare import table_differences
from dustoptics.io import open_table, write_glsl
from dustoptics.models import presets

REPO_ROOT = Path(__file__).resolve().parents[1]
TABLES = REPO_ROOT / "tables"


def table_path(name: str, root: Path = TABLES) -> Path:
    """The stored table file of preset ``name``."""
    return root / name / f"{name}.nc"


def differences(name: str, root: Path = TABLES) -> list[str]:
    """What differs between the stored table of ``name`` and a fresh build (empty: current)."""
    path = table_path(name, root)
    if not path.exists():
        return [f"{path} is missing"]
    return table_differences(open_table(path), presets.build_preset(name))


def build(names: list[str], root: Path = TABLES) -> None:
    """Rebuild the tables of ``names`` into ``root``."""
    for name in names:
        table = presets.build_preset(name)
        out = root / name
        table.save(table_path(name, root), overwrite=True)
        write_glsl(table, out, overwrite=True)
        print(f"{name}: {out}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check", action="store_true", help="compare instead of rebuilding; exit 1 if stale"
    )
    parser.add_argument("names", nargs="*", help="presets (default: all)")
    args = parser.parse_args(argv)
    names = args.names or presets.list_presets()
    if args.check:
        problems = [p for name in names for p in differences(name)]
        for p in problems:
            print(p, file=sys.stderr)
        if problems:
            print("tables are out of date: run python scripts/build_tables.py", file=sys.stderr)
        return 1 if problems else 0
    build(names)
    return 0


if __name__ == "__main__":
    sys.exit(main())
