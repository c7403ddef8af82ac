"""What would fail when a command writes its files, refused before any work.

A table's formats need what the table may lack (:func:`check_needs`: cross-sections,
a number density, the expansion coefficients); a name that no file can carry, or
files already in ``DIR/NAME/`` that record other inputs, would make the writing
fail after the computation (:func:`check_outputs` for a table's files,
:func:`check_set_outputs` for an atmosphere set's).  ``build`` and ``export`` call
these before computing or rendering anything.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dustoptics._files import load_json
from dustoptics._validation import check_file_name, check_inside
from dustoptics.atmosphere.build import SET_PROVENANCE_SUFFIX, set_inputs
from dustoptics.cli.errors import UsageError
from dustoptics.io import FORMATS, FormatError, read_hdf5
from dustoptics.io.registry import formats_needing
from dustoptics.models.presets import list_presets
from dustoptics.table import canonical_json

if TYPE_CHECKING:
    from dustoptics.models.config import BuildConfig

__all__ = [
    "NEEDS_DENSITY",
    "check_needs",
    "check_outputs",
    "check_set_outputs",
    "no_expansion",
]

#: The usage error of the cosmoscout format without a number density.
NEEDS_DENSITY = (
    "the cosmoscout format needs a number density for beta [m^-1]: give "
    "--optical-depth (with --reference-wavelength-nm), --number-density-per-m3 or "
    "number_density_per_m3 in the configuration"
)


#: What a name that names files must look like (formats whose records say ``plain_name``).
_PLAIN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


def check_needs(
    formats: Sequence[str],
    *,
    name: str,
    cross_sections: bool,
    density: bool,
    no_expansion: str | None = None,
) -> None:
    """What the formats need of the table (their records' ``needs``), checked before any work.

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
        Why the table has (will have) no expansion coefficients, for the message of the
        formats that need them; None: it has them.

    Raises
    ------
    UsageError
        A format needs what the table lacks; the message says what to give.
    """
    lacking = formats_needing("cross_sections", formats)
    if lacking and not cross_sections:
        raise UsageError(
            f"--format {','.join(lacking)} needs cross-sections, which {name!r} does not have "
            "(a phase function only): build a Mie or hybrid model"
        )
    lacking = formats_needing(("expansion", "matrix"), formats)
    if lacking and no_expansion is not None:
        raise UsageError(
            f"--format {','.join(lacking)} needs the phase function's expansion coefficients, "
            f"{no_expansion}"
        )
    lacking = formats_needing("number_density", formats)
    if lacking and not density:
        if lacking == ["cosmoscout"]:
            raise UsageError(NEEDS_DENSITY)
        raise UsageError(
            f"--format {','.join(lacking)} needs a number density for the coefficients N C: "
            "give --number-density-per-m3 (or number_density_per_m3 in a configuration)"
        )


def _recorded_inputs(path: Path) -> Mapping[str, Any] | None:
    """The provenance inputs a table file or seed-CSV summary records; None if unreadable."""
    try:
        if path.suffix == ".json":
            inputs = load_json(path)["provenance"]["inputs"]
        else:
            inputs = read_hdf5(path).provenance.inputs
    except (FormatError, OSError, ValueError, KeyError, TypeError, RecursionError):
        return None
    return inputs if isinstance(inputs, Mapping) else None


def _files_of_other_tables(
    folder: Path, name: str, formats: Sequence[str], inputs: Mapping[str, Any]
) -> list[Path]:
    """The files in ``folder`` that record a table's inputs (each format record's
    ``inputs_file``) and record other ``inputs`` than these, or cannot be read."""
    expected = {key: canonical_json(value) for key, value in inputs.items()}
    other = []
    for fmt in formats:
        inputs_file = FORMATS[fmt].inputs_file
        path = folder / inputs_file(name) if inputs_file is not None else None
        if path is None or not path.is_file():
            continue
        found = _recorded_inputs(path)
        if found is None or any(
            key not in found or canonical_json(found[key]) != text for key, text in expected.items()
        ):
            other.append(path)
    return other


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
        Without ``force``: the file that records the table's inputs (a record's
        ``inputs_file``: ``NAME.nc``, ``NAME.h5``, the seed CSVs' ``table_summary.json``)
        exists for a format asked for and records other inputs (or cannot be read), so
        the files could not be placed.
    """
    folder = out / check_file_name("name", name)
    check_inside(out, folder)
    strict = sorted(n for n in set(formats) if FORMATS[n].plain_name)
    if strict and not _PLAIN_NAME.fullmatch(name):
        raise ValueError(
            f"{what} {name!r} is not usable as a file name by --format {','.join(strict)}: "
            "use letters, digits, '.', '_' and '-', starting with a letter or digit"
        )
    if force:
        return
    other = _files_of_other_tables(folder, name, formats, inputs)
    if other:
        raise FileExistsError(
            "these files exist and hold another table (other inputs, or unreadable); use --force "
            "to replace them, or another --out: " + ", ".join(repr(str(p)) for p in other)
        )


def check_set_outputs(args: argparse.Namespace, *, dust: str, optical_depth: float) -> None:
    """A set's record that exists in ``DIR/NAME/`` with other inputs: refused before any
    work without ``--force`` (the files could not be placed)."""
    record = args.out / args.name / f"{args.name}{SET_PROVENANCE_SUFFIX}"
    if args.force or not record.is_file():
        return
    # The inputs known before any work (the ozone file is read, and checked, by the work).
    expected = set_inputs(
        args.name,
        dust=dust,
        optical_depth=optical_depth,
        reference_wavelength_nm=args.reference_wavelength_nm,
        wavelength_nm=args.wavelengths_nm,
    )
    try:
        found = load_json(record)["inputs"]
        same = all(canonical_json(found.get(k)) == canonical_json(v) for k, v in expected.items())
    except (FormatError, OSError, ValueError, KeyError, TypeError, AttributeError):
        same = False
    if not same:
        raise FileExistsError(
            f"{str(record)!r} exists and records another set (other inputs); use --force to "
            "replace the set, or another --out"
        )


def no_expansion(name: str, config: BuildConfig) -> str:
    """Why ``config`` (given as ``name``: a preset or a file) cannot have expansion coefficients,
    for :func:`check_needs` (``build`` asks a Mie model for them,
    :meth:`~dustoptics.models.build.TableBuilder.ask_for_expansion`)."""
    return (
        f"which only a Mie model has (phase.model = 'mie' with optics.expansion = true); "
        f"{config.name!r} has phase.model = {config.phase.model!r}"
    )


def check_presets(option: str, names: tuple[str, ...]) -> None:
    """Each name a preset (it names the files, too): a usage error before any work."""
    known = list_presets()
    unknown = [n for n in names if n not in known]
    if unknown:
        raise UsageError(
            f"{option}: unknown preset {', '.join(map(repr, unknown))}; choose from "
            f"{', '.join(known)}"
        )
