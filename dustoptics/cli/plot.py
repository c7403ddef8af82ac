"""``dustoptics plot``: a table's phase function, its map or its spectra, as a figure."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from dustoptics import plot
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import _float_list, add_command
from dustoptics.io._atomic import check_targets
from dustoptics.io.outputs import read_table

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``plot`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "plot",
        examples=(
            f"{PROG} plot tables/blue-moons/blue-moons.nc --kind polar --out blue-moons.png",
        ),
    )
    p.set_defaults(run=run)
    p.add_argument("file", type=Path, metavar="FILE")
    p.add_argument(
        "--kind",
        choices=["phase", "polar", "map", "spectra"],
        default="phase",
        help="phase function (log scale), polar, wavelength x angle map, or spectra",
    )
    p.add_argument(
        "--wavelengths-nm",
        type=_float_list,
        metavar="LIST",
        help="wavelengths to draw for phase/polar [nm] (must be on the table's grid)",
    )
    p.add_argument(
        "--out", type=Path, required=True, metavar="FIG", help="output file, .png or .svg"
    )
    p.add_argument("--force", action="store_true", help="replace an existing figure")


def run(args: argparse.Namespace) -> int:
    """Run ``plot``; returns the exit status."""
    # What would fail when the figure is saved, refused before any work.
    if args.out.suffix.lower() not in plot.SAVE_FORMATS:
        raise UsageError(
            f"--out must end in {' or '.join(plot.SAVE_FORMATS)}; got {str(args.out)!r}"
        )
    check_targets([args.out], overwrite=args.force)
    table = read_table(args.file)
    if args.kind in ("phase", "polar"):
        figure = plot.phase_function(
            table, wavelengths_nm=args.wavelengths_nm, polar=args.kind == "polar"
        )
    elif args.kind == "map":
        figure = plot.phase_map(table)
    else:
        figure = plot.spectra(table)
    path = plot.save(figure, args.out, overwrite=args.force)
    print(f"wrote {path}")
    return 0
