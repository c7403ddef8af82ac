"""``dustoptics export``: a table file in other formats; and how ``build`` writes a table.

The table's files go into ``--out DIR`` / the table's name
(:func:`~dustoptics.io.outputs.place_table`), with the format options given
(:func:`~dustoptics.models.build.prepare_export`); files that already hold the
same table are left untouched.  Before any work, :func:`check_outputs` refuses
a table name that a format cannot write and the table files (``NAME.nc``,
``NAME.h5``, the seed CSVs' summary) that exist and record other inputs, unless
``--force``.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import _add_format_options, add_command
from dustoptics.cli.report import report_placement

__all__ = [
    "NEEDS_DENSITY",
    "add_parser",
    "check_needs",
    "check_outputs",
    "run",
    "same_table",
    "write_table",
]

#: The usage error of the cosmoscout format without a number density.
NEEDS_DENSITY = (
    "the cosmoscout format needs a number density for beta [m^-1]: give "
    "--optical-depth (with --reference-wavelength-nm), --number-density-per-m3 or "
    "number_density_per_m3 in the configuration"
)


#: Formats whose files are named by the table's name as it is, which their writers
#: require to be letters, digits, '.', '_' and '-', starting with a letter or digit.
_PLAIN_NAME_FORMATS = ("cosmoscout", "hdf5", "netcdf")
_PLAIN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


#: Formats that need the table's cross-sections, and those that need a number density too
#: (their coefficients are N C [m^-1]).
_NEEDS_CROSS_SECTIONS = ("bruneton", "cosmoscout", "disort", "libradtran")
_NEEDS_NUMBER_DENSITY = ("bruneton", "cosmoscout", "libradtran")


def check_needs(
    formats: Sequence[str],
    *,
    name: str,
    cross_sections: bool,
    density: bool,
    no_expansion: str | None = None,
) -> None:
    """What the formats need of the table, checked before any work.

    Parameters
    ----------
    formats : sequence of str
        The formats to write.
    name : str
        The table's name, for the message.
    cross_sections : bool
        Whether the table has (will have) cross-sections.
    density : bool
        Whether it has (will have) a number density.
    no_expansion : str, optional
        Why the table has (will have) no expansion coefficients, for the
        ``disort`` and ``libradtran`` formats' message; None: it has them.

    Raises
    ------
    UsageError
        A format needs what the table lacks; the message says what to give.
    """
    lacking = sorted(set(formats) & set(_NEEDS_CROSS_SECTIONS))
    if lacking and not cross_sections:
        raise UsageError(
            f"--format {','.join(lacking)} needs cross-sections, which {name!r} does not have "
            "(a phase function only): build a Mie or hybrid model"
        )
    lacking = sorted(set(formats) & {"disort", "libradtran"})
    if lacking and no_expansion is not None:
        raise UsageError(
            f"--format {','.join(lacking)} needs the phase function's expansion coefficients, "
            f"{no_expansion}"
        )
    lacking = sorted(set(formats) & set(_NEEDS_NUMBER_DENSITY))
    if lacking and not density:
        if lacking == ["cosmoscout"]:
            raise UsageError(NEEDS_DENSITY)
        raise UsageError(
            f"--format {','.join(lacking)} needs a number density for the coefficients N C: "
            "give --number-density-per-m3 (or number_density_per_m3 in a configuration)"
        )


def _recorded_inputs(path: Path) -> Mapping[str, Any] | None:
    """The provenance inputs a table file or seed-CSV summary records; None if unreadable."""
    import json

    from dustoptics.io import FormatError, read_hdf5

    try:
        if path.suffix == ".json":
            inputs = json.loads(path.read_text(encoding="utf-8"))["provenance"]["inputs"]
        else:
            inputs = read_hdf5(path).provenance.inputs
    except (FormatError, OSError, ValueError, KeyError, TypeError, RecursionError):
        return None
    return inputs if isinstance(inputs, Mapping) else None


def check_outputs(
    out: Path,
    name: str,
    formats: Sequence[str],
    *,
    inputs: Mapping[str, Any],
    force: bool,
    what: str = "the table's name",
) -> None:
    """What would fail when the files are written, refused before any work.

    Parameters
    ----------
    out : pathlib.Path
        ``--out DIR``: the files go into ``DIR/NAME/``.
    name : str
        The table's name.
    formats : sequence of str
        The formats to write.
    inputs : mapping
        Inputs the table records (:attr:`~dustoptics.table.Provenance.inputs`), or
        those known before it is computed (a configuration's); the inputs a file
        records are compared key by key for these keys only.
    force : bool
        ``--force``: existing files may be replaced.
    what : str, optional
        What ``name`` is, for the message.

    Raises
    ------
    ValueError
        ``name`` is not a plain file name, leads outside ``out``, or is not usable
        by a format that names its files by it.
    FileExistsError
        Without ``force``: ``DIR/NAME/NAME.nc`` or ``.h5`` or the seed CSVs'
        ``table_summary.json`` exists for a format asked for and records other
        inputs (or cannot be read), so the files could not be placed.
    """
    from dustoptics._validation import check_file_name, check_inside
    from dustoptics.io.csv.seed import SUMMARY_FILENAME
    from dustoptics.table import canonical_json

    folder = out / check_file_name("name", name)
    check_inside(out, folder)
    strict = sorted(set(formats) & set(_PLAIN_NAME_FORMATS))
    if strict and not _PLAIN_NAME.fullmatch(name):
        raise ValueError(
            f"{what} {name!r} is not usable as a file name by --format {','.join(strict)}: "
            "use letters, digits, '.', '_' and '-', starting with a letter or digit"
        )
    if force:
        return
    recorded = [folder / f"{name}.nc"] if "netcdf" in formats else []
    recorded += [folder / f"{name}.h5"] if "hdf5" in formats else []
    recorded += [folder / SUMMARY_FILENAME] if "csv" in formats else []
    expected = {key: canonical_json(value) for key, value in inputs.items()}
    other = []
    for path in recorded:
        if not path.is_file():
            continue
        found = _recorded_inputs(path)
        if found is None or any(
            key not in found or canonical_json(found[key]) != text for key, text in expected.items()
        ):
            other.append(path)
    if other:
        raise FileExistsError(
            "these files exist and hold another table (other inputs); use --force to replace "
            "them, or another --out: " + ", ".join(repr(str(p)) for p in other)
        )


def same_table(existing: Path, new: Path) -> bool:
    """Both files are HDF5 files that hold the same table
    (:func:`dustoptics.compare.table_differences`): the existing one is up to date."""
    from dustoptics.compare import table_differences
    from dustoptics.io import FormatError, read_hdf5
    from dustoptics.io.outputs import TABLE_SUFFIXES

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
        help="convert a table file into other formats",
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
    _add_format_options(p, default=(), required=True)


def run(args: argparse.Namespace) -> int:
    """Run ``export``; returns the exit status."""
    from dustoptics.io.outputs import read_table, with_inputs

    table = read_table(args.file)
    if args.number_density_per_m3 is not None:
        table = with_inputs(
            table.replace(number_density_per_m3=args.number_density_per_m3),
            number_density_per_m3=args.number_density_per_m3,
        )
    check_needs(
        args.format,
        name=table.name,
        cross_sections=table.has_cross_sections,
        density=table.number_density_per_m3 is not None,
        no_expansion=None
        if table.alpha1 is not None
        else f"which {str(args.file)!r} does not hold: build the table from a configuration "
        "with 'expansion = true' under [optics] (or compute_optics(..., expansion=True))",
    )
    check_outputs(
        args.out, table.name, args.format, inputs=table.provenance.inputs, force=args.force
    )
    return write_table(args, table, args.format)


def write_table(args: argparse.Namespace, table: Any, formats: Sequence[str]) -> int:
    """``build`` and ``export``: the table's files go into ``--out DIR`` / the table's name."""
    from dustoptics.io.outputs import place_table
    from dustoptics.models.build import FormatOptions, prepare_export

    optical_depth = getattr(args, "optical_depth", None)
    if "cosmoscout" in formats:
        if optical_depth is not None and args.number_density_per_m3 is not None:
            raise UsageError("give --optical-depth or --number-density-per-m3, not both")
        if optical_depth is None and table.number_density_per_m3 is None:
            raise UsageError(NEEDS_DENSITY)
    table, options = prepare_export(
        table,
        formats,
        options=FormatOptions(
            channels_nm=args.channels_nm,
            colour=args.colour,
            resolution_deg=args.resolution_deg,
            sampling=args.sampling,
            n_angles=args.n_angles,
            prefix=args.prefix,
            glsl_version=args.glsl_version,
            layout=args.layout,
            precision=args.precision,
        ),
        optical_depth=optical_depth,
        reference_wavelength_nm=getattr(args, "reference_wavelength_nm", 550.0),
        scale_height_m=args.scale_height_m,
        top_altitude_m=args.top_altitude_m,
        n_altitudes=args.n_altitudes,
    )
    placed = place_table(
        table, args.out, formats, options=options, force=args.force, same=same_table
    )
    report_placement(args, table.name, args.out / table.name, placed)
    return 0
