"""``dustoptics fit``: an analytic phase function fitted to a table, per wavelength or channel.

With ``--out DIR`` the fit's JSON and shader constants go into ``DIR/NAME/``
(NAME the table's name), as ``build`` and ``export`` place theirs; the files
are named, and refused if they exist without ``--force``, before any work.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from dustoptics._validation import check_file_name, check_inside
from dustoptics.cli.build import table_builder
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import _float_list, add_command
from dustoptics.io._atomic import check_targets, safe_stem
from dustoptics.io.engines.fit import _IDENTIFIER, FIT_LANGUAGES, write_fit
from dustoptics.io.outputs import read_table
from dustoptics.io.shaders.common import shader_syntax
from dustoptics.scattering.fit import FIT_MODEL_ALIASES, FIT_MODELS, fit_table, resolve_model

__all__ = ["add_parser", "fit_targets", "run"]

_FIT_MODEL_HELP = ", ".join(
    f"{name} ({', '.join(a for a, n in FIT_MODEL_ALIASES.items() if n == name)})"
    for name in FIT_MODELS
)


def add_parser(sub: Any) -> None:
    """Add the ``fit`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "fit",
        help="fit an analytic phase function (HG, double HG, ...) to a table",
        examples=(
            f"{PROG} fit tables/blue-moons/blue-moons.nc --model dhg --out fits",
            f"{PROG} fit hybrid --model hg --colour linear-srgb-astmg173",
        ),
    )
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
    p.add_argument(
        "--out",
        type=Path,
        metavar="DIR",
        help="write JSON, GLSL, HLSL and WGSL into DIR/NAME/, NAME the table's name",
    )
    p.add_argument("--force", action="store_true", help="replace existing files")


def fit_targets(out: Path, name: str, model: str) -> list[Path]:
    """The files ``fit --out DIR`` writes for table ``name`` and model ``model``
    (:func:`dustoptics.io.engines.fit.write_fit`), in ``DIR/NAME/``."""

    folder = out / check_file_name("name", name)
    check_inside(out, folder)
    stem = f"{safe_stem(name)}_{model}"
    extensions = [".json"] + [shader_syntax(lang).extension for lang in FIT_LANGUAGES]
    return [folder / f"{stem}{ext}" for ext in extensions]


def run(args: argparse.Namespace) -> int:
    """Run ``fit``; returns the exit status.  The model, the prefix and where the files go
    are checked before the table is computed or fitted."""

    try:
        model = resolve_model(args.model)
    except ValueError as exc:
        raise UsageError(f"--model: {exc}") from None
    if not _IDENTIFIER.match(args.prefix) or "__" in args.prefix:
        raise UsageError(
            "--prefix must start with a letter and hold only letters, digits and '_' (no '__'); "
            f"got {args.prefix!r}"
        )
    source = Path(args.table)
    if source.exists() and source.suffix.lower() != ".toml":
        table = read_table(source)
        name, builder = table.name, None
    else:
        builder = table_builder(args.table)
        name = builder.name
    if args.out is not None:
        targets = fit_targets(args.out, name, model)
        check_targets(targets, overwrite=args.force)  # before any work
    if builder is not None:
        table = builder.build()
    result = fit_table(
        table,
        model=model,
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
        written = write_fit(
            result, targets[0].parent, stem=name, prefix=args.prefix, overwrite=args.force
        )
        if sorted(written) != sorted(targets):
            raise RuntimeError(f"fit: wrote {sorted(written)}, announced {targets}")
        for path in written:
            print(f"wrote {path}")
    return 0
