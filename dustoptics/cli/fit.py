"""``dustoptics fit``: an analytic phase function fitted to a table, per wavelength or channel."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from dustoptics.cli.parser import _float_list

__all__ = ["add_parser", "run"]

_FIT_MODEL_HELP = (
    "henyey-greenstein (hg), dhg-costa2021 (dhg), dhg-kobe2026 (dhg-kobe), cornette-shanks1992 (cs), "
    "hg-draine-jendersie-deon2023 (hg-draine), two-term-hg-hapke2012 (tthg)"
)


def add_parser(sub: Any) -> None:
    """Add the ``fit`` subcommand to the subparsers ``sub``."""
    p = sub.add_parser("fit", help="fit an analytic phase function (HG, double HG, ...) to a table")
    p.set_defaults(run=run)
    p.add_argument("table", metavar="NAME_OR_FILE", help="a preset name or a table file")
    p.add_argument(
        "--model", default="dhg", help="model or alias (default dhg): " + _FIT_MODEL_HELP
    )
    p.add_argument(
        "--colour",
        choices=["wavelengths", "cie1931-xyz", "linear-srgb-astmg173"],
        help="fit three renderer channels instead of every wavelength",
    )
    p.add_argument(
        "--channels",
        type=_float_list,
        metavar="R,G,B",
        help="channel wavelengths with --colour wavelengths [nm] (default 680,550,440)",
    )
    p.add_argument(
        "--forward-cutoff",
        type=float,
        default=0.0,
        metavar="DEG",
        help="leave angles below DEG out of the loss (default 0)",
    )
    p.add_argument("--prefix", default="DUST", help="name prefix of the shader constants")
    p.add_argument("--out", type=Path, metavar="DIR", help="write JSON, GLSL, HLSL and WGSL there")
    p.add_argument("--force", action="store_true", help="replace existing files")


def run(args: argparse.Namespace) -> int:
    """Run ``fit``; returns the exit status."""
    from dustoptics.cli.build import table_builder
    from dustoptics.io.engines.fit import write_fit
    from dustoptics.io.outputs import read_table
    from dustoptics.scattering.fit import fit_table

    source = Path(args.table)
    if source.exists() and source.suffix.lower() != ".toml":
        table = read_table(source)
    else:
        table = table_builder(args.table).build()
    result = fit_table(
        table,
        model=args.model,
        colour=args.colour,
        channels_nm=args.channels,
        forward_cutoff_deg=args.forward_cutoff,
    )
    print(f"{table.name}: {result.model}, {result.formula}")
    print(f"  loss: {result.loss}")
    names = "  ".join(f"{n:>10s}" for n in result.parameter_names)
    print(f"  {'row':>10s}  {names}  {'max rel':>9s}  {'median':>9s}  {'g error':>9s}")
    for i, label in enumerate(result.labels):
        values = "  ".join(f"{v:10.6f}" for v in result.parameters[i])
        print(
            f"  {label:>10s}  {values}  {result.max_relative_error[i]:9.3g}  "
            f"{result.median_relative_error[i]:9.3g}  {result.g_error[i]:+9.2e}"
        )
    if args.out is not None:
        for path in write_fit(
            result, args.out, stem=table.name, prefix=args.prefix, overwrite=args.force
        ):
            print(f"wrote {path}")
    return 0
