"""``dustoptics export``: a table file in other formats; and how ``build`` writes a table.

The table's files go into ``--out DIR`` / the table's name
(:func:`~dustoptics.io.outputs.place_table`), with the format options given
(:func:`~dustoptics.io.outputs.prepare_export`); files that already hold the
same table are left untouched.  Before any work, :func:`check_outputs` refuses
a table name that a format cannot write and the table files (``NAME.nc``,
``NAME.h5``, the seed CSVs' summary) that exist and record other inputs, unless
``--force``.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from dustoptics.cli.checks import NEEDS_DENSITY, check_needs, check_outputs
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.formats import (
    add_format_options,
    format_option_names,
    unused_format_options,
)
from dustoptics.cli.parser import _positive_float, add_command
from dustoptics.cli.report import report_placement
from dustoptics.compare import table_differences
from dustoptics.io import FORMATS, FormatError, FormatOptions, read_hdf5
from dustoptics.io.outputs import (
    TABLE_SUFFIXES,
    place_table,
    prepare_export,
    read_table,
    with_inputs,
)
from dustoptics.io.registry import NEEDS
from dustoptics.io.rt.profile import RTProfileOptions
from dustoptics.sky.engines import ENGINES

__all__ = [
    "NEEDS_DENSITY",
    "add_parser",
    "check_profile_density",
    "format_options",
    "run",
    "same_table",
    "takes_optical_depth",
    "write_table",
]


def same_table(existing: Path, new: Path) -> bool:
    """Both files are HDF5 files that hold the same table
    (:func:`dustoptics.compare.table_differences`): the existing one is up to date."""
    if existing.suffix.lower() not in TABLE_SUFFIXES:
        return False
    try:
        return not table_differences(read_hdf5(existing), read_hdf5(new))
    except (FormatError, OSError):
        return False


def add_parser(sub: Any) -> None:
    """Add the ``export`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "export",
        examples=(
            f"{PROG} export tables/blue-moons/blue-moons.nc --out shaders --format glsl,texture",
        ),
    )
    p.set_defaults(run=run)
    p.add_argument(
        "file",
        type=Path,
        metavar="FILE",
        help="a table file (.nc, .h5), a seed-CSV directory or its table_summary.json",
    )
    p.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="DIR",
        help="output directory; files go to DIR/NAME/, NAME the table's name (as for build)",
    )
    p.add_argument("--quiet", action="store_true", help="no summary output")
    add_format_options(p, default=(), required=True)
    g = p.add_argument_group(
        "optical depth (cosmoscout, disort, libradtran, libradtran-nc: the number density)"
    )
    g.add_argument(
        "--optical-depth",
        type=_positive_float,
        metavar="TAU",
        help="vertical optical depth that sets the number density for the profile the files "
        "carry (recorded in the provenance); instead of --number-density-per-m3",
    )
    g.add_argument(
        "--reference-wavelength-nm",
        type=_positive_float,
        default=550.0,
        metavar="NM",
        help="wavelength of that optical depth [nm] (default 550), within the table's",
    )


def run(args: argparse.Namespace) -> int:
    """Run ``export``; returns the exit status."""
    engines = [f for f in args.format if f in ENGINES]
    if engines:
        raise UsageError(
            f"--format {','.join(engines)} is fitted to a planet's sky, not written from a table: "
            f"'{PROG} build mars --dust PRESET --format {engines[0]}' (or 'build earth')"
        )
    table = read_table(args.file)
    if args.number_density_per_m3 is not None:
        table = with_inputs(
            table.replace(cross_sections={"number_density_per_m3": args.number_density_per_m3}),
            number_density_per_m3=args.number_density_per_m3,
        )
    unused = unused_format_options(args, args.format)
    if args.optical_depth is not None and not takes_optical_depth(args.format):
        unused.append("--optical-depth")
    if unused:
        raise UsageError(
            f"{', '.join(unused)} changes nothing with --format {','.join(args.format)}; remove it"
        )
    check_needs(
        args.format,
        name=table.name,
        cross_sections=NEEDS["cross_sections"].present(table),
        density=NEEDS["number_density"].present(table)
        or (args.optical_depth is not None and NEEDS["cross_sections"].present(table)),
        no_expansion=None
        if table.expansion is not None
        else f"which {str(args.file)!r} does not hold: build the table from a configuration "
        "with 'expansion = true' under [optics] (or compute_optics(..., expansion=True))",
    )
    check_profile_density(
        args,
        args.format,
        density=NEEDS["number_density"].present(table) or args.optical_depth is not None,
    )
    try:
        format_options(args).check(args.format, wavelength_nm=table.wavelength_nm)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    check_outputs(
        args.out, table.name, args.format, inputs=table.provenance.inputs, force=args.force
    )
    return write_table(args, table, args.format)


def takes_optical_depth(formats: Sequence[str]) -> bool:
    """Whether one of ``formats`` writes a profile that ``--optical-depth`` fills: cosmoscout
    and the radiative-transfer formats."""
    return any(
        name == "cosmoscout" or FORMATS[name].options is RTProfileOptions for name in formats
    )


def check_profile_density(
    args: argparse.Namespace, formats: Sequence[str], *, density: bool
) -> None:
    """A profile asked for (``--scale-height-m``, ...) for the disort format needs a number
    density (its layers' particle columns): a usage error without one, before any work."""
    profile = FORMATS["disort"].make_options(format_options(args).values)
    if "disort" in formats and profile.given() and not density:
        raise UsageError(
            "--format disort writes the profile asked for as layers of particles, which needs a "
            "number density: give --number-density-per-m3 or --optical-depth"
        )


def format_options(args: argparse.Namespace) -> FormatOptions:
    """The format options given on the command line (every format record's options)."""
    return FormatOptions(**{name: getattr(args, name) for name in format_option_names()})


def write_table(args: argparse.Namespace, table: Any, formats: Sequence[str]) -> int:
    """``build`` and ``export``: the table's files go into ``--out DIR`` / the table's name."""
    optical_depth = getattr(args, "optical_depth", None)
    if optical_depth is not None and args.number_density_per_m3 is not None:
        raise UsageError("give --optical-depth or --number-density-per-m3, not both")
    no_density = table.cross_sections is None or table.cross_sections.number_density_per_m3 is None
    if "cosmoscout" in formats and optical_depth is None and no_density:
        raise UsageError(NEEDS_DENSITY)
    table, options = prepare_export(
        table,
        formats,
        options=format_options(args),
        optical_depth=optical_depth,
        reference_wavelength_nm=getattr(args, "reference_wavelength_nm", 550.0),
    )
    placed = place_table(
        table, args.out, formats, options=options, force=args.force, same=same_table
    )
    report_placement(args, table.name, args.out / table.name, placed)
    return 0
