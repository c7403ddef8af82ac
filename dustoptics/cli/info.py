"""``dustoptics info``: what a file or folder dustoptics writes holds and how it was made."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``info`` subcommand to the subparsers ``sub``."""
    p = sub.add_parser("info", help="what a table file holds and how it was made")
    p.set_defaults(run=run)
    p.add_argument(
        "file",
        type=Path,
        metavar="FILE",
        help="any file or folder dustoptics writes: HDF5, seed CSV, GLSL, texture (sidecar or "
        ".raw), CosmoScout VR CSV, an atmosphere set's folder or files",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``info``; returns the exit status."""
    from dustoptics.io.describe import describe_path

    # What a file says is shown, never obeyed: describe_path escapes control characters.
    print(describe_path(args.file))
    return 0
