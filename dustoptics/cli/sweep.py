"""``dustoptics sweep``: a configuration over its ``[sweep]`` axes on Dask, into a store.

A Zarr store that exists is resumed; a ``FILE.nc`` that exists is replaced only
with ``--force``, which is checked before any work.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from dustoptics.cli.errors import PROG
from dustoptics.cli.parser import _worker_count, add_command
from dustoptics.cli.report import say

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``sweep`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "sweep",
        examples=(f"{PROG} sweep my-sweep.toml --out my-sweep.zarr --workers 2",),
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
        "--force",
        action="store_true",
        help="replace an existing FILE.nc (a Zarr store is resumed, never replaced)",
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
    # lazy: dustoptics.sweep adds 40-55 ms to every command's start-up (-X importtime)
    from dustoptics.sweep import sweep

    out = Path(args.out)
    if str(out).endswith(".nc") and (out.exists() or out.is_symlink()) and not args.force:
        # The library replaces it at the end; the command line asks first, before any work.
        raise FileExistsError(f"{str(out)!r} already exists; use --force to replace it")
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
