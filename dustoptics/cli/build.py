"""``dustoptics build``: a preset's or configuration's table, or a whole atmosphere set.

``build NAME_OR_CONFIG`` computes the table (:class:`~dustoptics.models.build.TableBuilder`)
and writes it into ``DIR/NAME/`` in each format asked for (:mod:`dustoptics.cli.export`);
``build mars|earth|earth-kobe2026`` computes the set
(:func:`~dustoptics.atmosphere.build.build_atmosphere`) and writes CosmoScout VR's files
(:func:`~dustoptics.atmosphere.build.write_atmosphere_set`).  What the formats need and
where the files go is checked before anything is computed.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from dustoptics.atmosphere.build import (
    ATMOSPHERES,
)
from dustoptics.cli.aerosol_options import AEROSOL_OPTIONS, add_aerosol_options
from dustoptics.cli.build_set import run_set, table_builder
from dustoptics.cli.checks import check_needs, check_outputs, no_expansion
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.export import (
    check_profile_density,
    format_options,
    takes_optical_depth,
    write_table,
)
from dustoptics.cli.formats import add_format_options, format_option_names, unused_format_options
from dustoptics.cli.parser import _float_list, _positive_float, add_command
from dustoptics.io.outputs import with_inputs
from dustoptics.io.registry import formats_needing
from dustoptics.models.build import TableBuilder
from dustoptics.models.files import PresetCopyWarning
from dustoptics.models.presets import DEFAULT_PRESET
from dustoptics.sky.engines import ENGINES

__all__ = ["DEFAULT_FORMATS", "add_parser", "run", "table_builder"]

#: Formats written by ``build`` when ``--format`` is not given: ``NAME.nc`` and the seed CSVs.
DEFAULT_FORMATS = ("netcdf", "csv")

#: Options of ``build`` that only a set uses (those only a table's formats use: the format
#: records' options, :func:`_table_options`).
_SET_OPTIONS = ("dust", "ozone_csv", "wavelengths_nm")


def add_parser(sub: Any) -> None:
    """Add the ``build`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "build",
        examples=(
            f"{PROG} build hybrid --out tables --format netcdf,glsl",
            f"{PROG} build my-dust.toml --out tables --format netcdf,disort,libradtran",
            f"{PROG} build mars --out sets --optical-depth 0.7",
        ),
    )
    p.set_defaults(run=run)
    p.add_argument(
        "name",
        nargs="?",
        default=DEFAULT_PRESET,
        metavar="NAME_OR_CONFIG",
        help=f"preset name (see 'presets'), TOML configuration file, or an atmosphere set "
        f"({', '.join(ATMOSPHERES)}) (default {DEFAULT_PRESET})",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("tables"),
        metavar="DIR",
        help="output directory; files go to DIR/NAME/ (default ./tables); files that "
        "already hold the same table are left untouched",
    )
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    p.add_argument(
        "--allow-unvalidated",
        action="store_true",
        help="go ahead, with a warning recorded in the table, where the size parameters or "
        "refractive indices leave the validated domain (see 'dustoptics info'; default: refuse)",
    )
    add_format_options(p, default=DEFAULT_FORMATS, required=False)
    g = p.add_argument_group(
        "atmosphere sets ('build mars', 'build earth': CosmoScout VR's full set)"
    )
    g.add_argument(
        "--dust",
        default=None,
        metavar="PRESET_OR_CONFIG",
        help="Mars dust model (default blue-moons)",
    )
    g.add_argument(
        "--optical-depth",
        type=_positive_float,
        metavar="TAU",
        help="vertical optical depth: of the Mars dust (default 0.5; clear seasons 0.3-1), or, "
        "for one preset with --format cosmoscout, disort, libradtran or libradtran-nc, sets its "
        "number density for the profile those files carry (recorded in the provenance)",
    )
    g.add_argument(
        "--reference-wavelength-nm",
        type=_positive_float,
        default=550.0,
        metavar="NM",
        help="wavelength of that optical depth [nm] (default 550)",
    )
    g.add_argument(
        "--wavelengths-nm",
        type=_float_list,
        metavar="L1,L2,...",
        help="wavelengths of the mars and earth sets [nm] (default CosmoScout VR's 15, 360-830)",
    )
    g.add_argument(
        "--ozone-csv",
        type=Path,
        metavar="FILE",
        help="Earth: ozone cross-sections (see dustoptics.atmosphere.gases.read_ozone_csv) in Bruneton's layer",
    )
    add_aerosol_options(p)


def _table_options() -> list[str]:
    """The options only a table's formats use: the format records' options that are None
    unless given, and the number density."""
    return [*format_option_names(defaults=False), "number_density_per_m3"]


def _refuse_unused_options(args: argparse.Namespace) -> None:
    """An option given where it changes nothing is a usage error, never silently ignored."""

    def given(names: Sequence[str]) -> list[str]:
        return ["--" + n.replace("_", "-") for n in names if getattr(args, n, None) is not None]

    unused_aerosol = given(AEROSOL_OPTIONS) if args.name != "earth" else []
    if args.name in ATMOSPHERES:
        unused = given(_table_options()) + unused_aerosol
        unused += given(("dust", "optical_depth") if args.name == "earth" else ("ozone_csv",))
        where = f"'build {args.name}' (an atmosphere set)"
    else:
        unused = given(_SET_OPTIONS) + unused_aerosol
        unused += unused_format_options(args, args.format or DEFAULT_FORMATS)
        if args.optical_depth is not None and not takes_optical_depth(args.format or ()):
            unused.append("--optical-depth")
        where = f"'build {args.name}' with --format {','.join(args.format or DEFAULT_FORMATS)}"
    if unused:
        raise UsageError(f"{', '.join(unused)} changes nothing in {where}; remove it")


def run(args: argparse.Namespace) -> int:
    """Run ``build``; returns the exit status."""
    _refuse_unused_options(args)
    if args.name in ATMOSPHERES:
        return run_set(args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        builder = table_builder(
            args.name,
            progress=None if args.quiet else sys.stderr,
            allow_large=args.allow_large,
        )
        builder.allow_unvalidated = args.allow_unvalidated
        if args.number_density_per_m3 is not None:
            # An input of the table: recorded in its provenance like the configuration's own.
            builder.config = replace(
                builder.config, number_density_per_m3=args.number_density_per_m3
            )
        _check_build_request(args, builder)
        table = builder.build()
    for w in caught:
        print(f"{PROG}: warning: {w.message}", file=sys.stderr)
        if issubclass(w.category, PresetCopyWarning):
            table = with_inputs(table, note=f"warning: {w.message}")
    return write_table(args, table, args.format or DEFAULT_FORMATS)


def _check_build_request(args: argparse.Namespace, builder: TableBuilder) -> None:
    """What the formats need and where the files go, checked before the table is computed."""
    formats = args.format or DEFAULT_FORMATS
    engines = [f for f in formats if f in ENGINES]
    if engines:
        raise UsageError(
            f"--format {','.join(engines)} is fitted to a planet's sky: build a set "
            f"('{PROG} build mars --dust {args.name} --format {engines[0]}')"
        )
    config = builder.config
    if not config.phase.uses_mie and args.number_density_per_m3 is not None:
        raise UsageError(
            f"--number-density-per-m3 changes nothing in 'build {args.name}': "
            f"{builder.name!r} is a phase function without cross-sections; remove it"
        )
    _ask_for_needs(args.name, builder, formats)
    density = (
        args.number_density_per_m3 is not None
        or config.number_density_per_m3 is not None
        or (getattr(args, "optical_depth", None) is not None and takes_optical_depth(formats))
    )
    check_profile_density(args, formats, density=density)
    check_needs(
        formats,
        name=builder.name,
        cross_sections=config.phase.uses_mie,
        density=density,
        no_expansion=None
        if builder.config.optics.expansion is not None
        else no_expansion(args.name, builder.config),
    )
    # Each format's own check of its options (a shader's channels, cosmoscout's profile).
    format_options(args).check(formats, wavelength_nm=builder.config.wavelengths_nm)
    # Where the files go, and what they would replace, is checked before any work, too.
    check_outputs(
        args.out,
        builder.name,
        formats,
        inputs=builder.config.to_inputs(),
        force=args.force,
        what="the configuration's name",
    )


def _ask_for_needs(name: str, builder: TableBuilder, formats: Sequence[str]) -> None:
    """What the formats need that the computation can supply is asked of it (the expansion
    coefficients, and with them the scattering matrix's), for a Mie model; what it cannot
    supply is left to :func:`check_needs` to refuse."""
    needing = formats_needing(("expansion", "matrix"), formats)
    if needing and builder.config.phase.model == "mie":
        builder.ask_for_expansion(f"--format {','.join(needing)}")
