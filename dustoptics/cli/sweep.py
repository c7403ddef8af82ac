"""``dustoptics sweep``: a configuration over its ``[sweep]`` axes on Dask, into a store."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from dustoptics.cli.parser import _worker_count
from dustoptics.cli.report import say

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``sweep`` subcommand to the subparsers ``sub``."""
    p = sub.add_parser(
        "sweep",
        help="compute a configuration over its [sweep] axes on Dask (needs the 'sweep' extra)",
    )
    p.set_defaults(run=run)
    p.add_argument(
        "config",
        metavar="CONFIG",
        help="TOML configuration file with a [sweep] table, or a preset name",
    )
    p.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="STORE",
        help="Zarr store directory (resumed if it exists), or FILE.nc for netCDF",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="dask.distributed scheduler, tcp://HOST:PORT (default: a local cluster)",
    )
    p.add_argument(
        "--workers",
        type=_worker_count,
        metavar="N",
        help="worker processes of the local cluster (default: all cores)",
    )
    p.add_argument(
        "--allow-large",
        action="store_true",
        help="go ahead beyond the budgets (points, work, memory, the store's disk)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")


def run(args: argparse.Namespace) -> int:
    """Run ``sweep`` (:func:`dustoptics.sweep.sweep`); returns the exit status."""
    from dustoptics.sweep import sweep

    ds = sweep(
        args.config,
        out=args.out,
        client=args.scheduler,
        workers=args.workers,
        progress=None if args.quiet else sys.stderr,
        allow_large=args.allow_large,
    )
    say(args, f"sweep: {dict(ds.sizes)} in {args.out}")
    return 0
