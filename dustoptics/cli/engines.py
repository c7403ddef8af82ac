"""``dustoptics engines report``: each engine's sky error, fitted and as people use it.

Parses, calls :func:`dustoptics.sky.engines.report.engines_report` (or reads the
table the package ships, :func:`~dustoptics.sky.engines.report.shipped_report`,
with ``--shipped``) and prints the table; ``--out FILE`` also writes it as JSON
(the package's ``report.json`` is written this way).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import add_command
from dustoptics.io._atomic import write_files
from dustoptics.sky.engines import ENGINES
from dustoptics.sky.engines.report import engines_report, planet_sets, shipped_report

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``engines`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "engines",
        examples=(
            f"{PROG} engines report --shipped",
            f"{PROG} engines report --planet mars:blue-moons --engine threejs,godot",
            f"{PROG} engines report --cache-dir cache --out report.json",
        ),
    )
    p.set_defaults(run=run)
    p.add_argument("action", choices=("report",), help="report: the error table")
    p.add_argument(
        "--planet",
        default=None,
        metavar="P1,P2,...",
        help="planet sets: earth, mars:PRESET (default all: earth and every Mie dust preset)",
    )
    p.add_argument(
        "--engine",
        default=None,
        metavar="E1,E2,...",
        help=f"engines (default all: {', '.join(ENGINES)})",
    )
    p.add_argument(
        "--cache-dir", type=Path, default=None, metavar="DIR", help="keep each planet's rows here"
    )
    p.add_argument("--out", type=Path, default=None, metavar="FILE", help="also write it as JSON")
    p.add_argument("--force", action="store_true", help="replace --out if it exists")
    p.add_argument(
        "--shipped",
        action="store_true",
        help="print the table the package ships (computed by this command; no work)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress output")


def _names(text: str | None, allowed: list[str], what: str) -> list[str] | None:
    if text is None:
        return None
    names = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in names if n not in allowed]
    if unknown or not names:
        raise UsageError(f"--{what} must be among {', '.join(allowed)}; got {text!r}")
    return names


def run(args: argparse.Namespace) -> int:
    """Run ``engines report``; returns the exit status."""
    planets = _names(args.planet, list(planet_sets()), "planet")
    engines = _names(args.engine, list(ENGINES), "engine")
    if args.out is not None and args.out.exists() and not args.force:
        raise FileExistsError(f"{str(args.out)!r} exists; use --force to replace it")
    if args.shipped:
        report = shipped_report()
    else:
        report = engines_report(
            planets=planets,
            engines=engines,
            cache_dir=args.cache_dir,
            progress=None if args.quiet else sys.stderr,
        )
    print(report.table_text(), end="")
    rows = report.row_losses()
    print(
        "\nengines and planets where the fitted parameters do not beat the community's "
        "(mean over the dome and the elevations): " + (", ".join(rows) if rows else "none")
    )
    losses = report.losses()
    if losses:
        print("single elevations where they do not (mean or 95th percentile):")
        print("\n".join(f"  {line}" for line in losses))
    if args.out is not None:
        write_files({args.out: report.to_json().encode("utf-8")}, overwrite=True)
    return 0
