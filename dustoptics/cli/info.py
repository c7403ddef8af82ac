"""``dustoptics info``: what a file or folder dustoptics writes holds and how it was made.

A summary by default (a dozen lines per table: what it holds, what it was made
from, its accuracy and input hash); ``--full`` adds the software versions, the
citations, the notes and every input (:func:`dustoptics.io.describe.describe_path`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import add_command
from dustoptics.io import FORMATS
from dustoptics.io.describe import describe_path
from dustoptics.sky import engines  # noqa: F401  (registers the engines' formats, listed here)

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``info`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "info",
        examples=(
            f"{PROG} info tables/blue-moons/blue-moons.nc",
            f"{PROG} info --full tables/blue-moons/",
            f"{PROG} info skies/mars-hybrid/mars-hybrid_sky.nc",
        ),
    )
    p.set_defaults(run=run)
    p.add_argument(
        "file",
        type=Path,
        metavar="FILE",
        help="any file or folder dustoptics writes: a table (.nc, .h5, seed CSV), the files of "
        f"the formats ({', '.join(sorted(FORMATS))}), an atmosphere set, a fit, a sky (.nc, "
        ".png), a sweep (store or .nc), or a folder of them",
    )
    p.add_argument(
        "--full",
        action="store_true",
        help="everything: software versions, citations, notes and every input (default: a summary)",
    )
    p.add_argument(
        "--max-bytes",
        type=int,
        default=None,
        metavar="BYTES",
        help="most bytes read or decompressed from one file, as its header declares them "
        "(a sky, a sweep's coordinates, a texture's pixels; default 256 MiB): a file declaring "
        "more is refused before it is read",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``info``; returns the exit status."""
    # info checks a sweep store's chunks before calling it complete (the sweep layer
    # registers how); imported here, not at the top: every command's parser imports this module.
    import dustoptics.sweep.store  # noqa: F401

    # What a file says is shown, never obeyed: describe_path escapes control characters.
    if args.max_bytes is not None and args.max_bytes < 1:
        raise UsageError(f"--max-bytes must be >= 1; got {args.max_bytes}")
    print(describe_path(args.file, full=args.full, max_bytes=args.max_bytes))
    return 0
