"""``dustoptics fit``: an analytic phase function fitted to a table, per wavelength or channel.

With ``--out DIR`` the fit's JSON and shader constants go into ``DIR/NAME/``
(NAME the table's name), as ``build`` and ``export`` place theirs; the files
are named, and refused if they exist without ``--force``, before any work.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from dustoptics._validation import check_file_name, check_inside
from dustoptics.cli.build_set import table_builder
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import _float_list, add_command
from dustoptics.io._atomic import check_targets, safe_stem, write_files
from dustoptics.io.engines.fit import _IDENTIFIER, FIT_LANGUAGES, write_fit
from dustoptics.io.outputs import read_table
from dustoptics.io.shaders.common import shader_syntax
from dustoptics.models.dust_phase_fit import (
    DUST_FIT_PRESETS,
    dust_phase_glsl,
    dust_phase_wgsl,
    load_dust_phase_fit,
)
from dustoptics.scattering.fit import FIT_MODEL_ALIASES, FIT_MODELS, fit_table, resolve_model

__all__ = ["add_parser", "by_size_targets", "fit_targets", "run"]

_FIT_MODEL_HELP = ", ".join(
    f"{name} ({', '.join(a for a, n in FIT_MODEL_ALIASES.items() if n == name)})"
    for name in FIT_MODELS
)


def add_parser(sub: Any) -> None:
    """Add the ``fit`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "fit",
        examples=(
            f"{PROG} fit tables/blue-moons/blue-moons.nc --model dhg --out fits",
            f"{PROG} fit hybrid --model hg --colour linear-srgb-astmg173",
            f"{PROG} fit blue-moons --by-size --out fits",
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
    p.add_argument(
        "--by-size",
        action="store_true",
        help="the shipped closed form of a Mars dust preset ("
        + ", ".join(DUST_FIT_PRESETS)
        + "): HG + Draine parameters as functions of r_eff per sRGB channel, with its error "
        "table; with --out, as JSON, GLSL and WGSL functions in DIR/NAME/",
    )


def by_size_targets(out: Path, preset: str) -> list[Path]:
    """The files ``fit PRESET --by-size --out DIR`` writes, in ``DIR/PRESET/``."""
    folder = out / check_file_name("name", preset)
    check_inside(out, folder)
    return [folder / f"{preset}_by-size{ext}" for ext in (".json", ".glsl", ".wgsl")]


def _run_by_size(args: argparse.Namespace) -> int:
    """``fit PRESET --by-size``: print the closed form's error table; write its files."""
    if args.table not in DUST_FIT_PRESETS:
        raise UsageError(
            f"--by-size: {args.table!r} has no closed form by size; choose from "
            f"{', '.join(DUST_FIT_PRESETS)}"
        )
    targets = by_size_targets(args.out, args.table) if args.out is not None else []
    check_targets(targets, overwrite=args.force)  # before any work
    fit = load_dust_phase_fit(args.table)
    low, high = fit.r_eff_range_um
    print(
        f"{fit.preset}: HG + Draine by size, r_eff {low:g} .. {high:g} um, v_eff {fit.v_eff:g}, "
        "channels " + " ".join(fit.channels)
    )
    print("  error of the closed form against Mie: solid-angle weighted RMS and largest")
    print("  |P_fit / P_Mie - 1| over 0..180 deg (held: a radius between the fitted ones)")
    print("  (alone: HG + Draine fitted to that radius on its own, fit_phase)")
    print(
        f"  {'r_eff um':>9s}  {'':4s}  {'channel':>7s}  {'rms %':>8s}  {'max %':>8s}  "
        f"{'alone %':>8s}"
    )
    for r, fitted, channel, rms, worst, alone in fit.error_table():
        print(
            f"  {r:9.4f}  {'fit' if fitted else 'held':4s}  {channel:>7s}  {100 * rms:8.2f}  "
            f"{100 * worst:8.2f}  {100 * alone:8.2f}"
        )
    if targets:
        data = {
            "preset": fit.preset,
            "v_eff": fit.v_eff,
            "r_eff_range_um": list(fit.r_eff_range_um),
            "channels": list(fit.channels),
            "coefficients": fit.coefficients.tolist(),
            "coefficients_axes": "channel, parameter (g_hg, g_d, alpha, w_d), power of "
            "ln(r_eff / 1 um)",
            "errors": list(fit.errors),
            "citation": fit.citation,
        }
        texts = [
            json.dumps(data, indent=1, sort_keys=True) + "\n",
            dust_phase_glsl(fit),
            dust_phase_wgsl(fit),
        ]
        written = write_files(
            {t: text.encode() for t, text in zip(targets, texts, strict=True)},
            overwrite=args.force,
        )
        for path in written:
            print(f"wrote {path}")
    return 0


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

    if args.by_size:
        return _run_by_size(args)
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
