"""The seed framework's CSV layout, with a JSON provenance sidecar.

The seed thesis's rendering framework (Meyran 2022; layout in the project
brief, sections 5 and 7) reads these files; :func:`write_seed_csv` writes a
:class:`~dustoptics.table.Table` as

``MiePhaseFunctionSpectrum.csv``
    Header: an empty cell, then one column label per wavelength [nm] (written
    as an integer when it is integral, e.g. ``360``, as in the seed's file).
    Then one row per scattering angle: theta [deg], then the phase function
    [sr^-1] at each wavelength, normalized so that 2 pi int_{-1}^{1} P dmu = 1.
``MieExtinctionSpectrum.csv`` (only for tables with cross-sections)
    Header ``wavelength_nm,cext_m2,qext,csca_m2,qsca,cabs_m2,ssa,g``: the
    wavelength [nm], the mean cross-sections per particle in SI units [m^2],
    the efficiencies [-], the single-scattering albedo [-] and the asymmetry
    parameter [-].  ``qext`` and ``qsca`` are left out when the table has no
    mean geometric cross-section (molecules).  The seed's own file has
    undocumented units; this header states them.  The framework multiplies a
    chosen column by a number density itself, so no ``beta`` column is written.
``table_summary.json``
    The table's name, its full :class:`~dustoptics.table.Provenance` (inputs,
    input hash, sources with citations, software versions, quadrature
    settings, notes), the per-wavelength error estimates, the scalars, the
    unit of every column and the sha256 of each CSV file's bytes.  A
    phase-only table's ``g`` is stored here, since it has no extinction file.

Every number is written with Python's shortest round-trip ``repr`` (the
cross-sections shifted by a decimal exponent from um^2 to m^2, exactly), so
:func:`read_seed_csv` returns a :class:`~dustoptics.table.Table` that
:meth:`~dustoptics.table.Table.equals` the one written, bit for bit, with its
provenance.  The bytes depend only on the table (no timestamps, no paths,
sorted JSON keys), so writing the same table twice gives identical files.
Writes are atomic (:mod:`dustoptics.io._atomic`).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import FormatError, write_files
from dustoptics.io._text import (
    check_increasing,
    floats,
    load_json,
    number,
    parse,
    read_checked,
    read_rows,
    shift,
    wavelength_label,
)
from dustoptics.io.registry import Format, register
from dustoptics.table import (
    PHASE_NORMALIZATION,
    UNITS,
    Provenance,
    Table,
    grouped_fields,
)
from dustoptics.table.schema import EXPANSION_FIELDS, MATRIX_FIELDS

#: Optional per-wavelength quantities of radiative-transfer tables, kept in the summary.
_EXTRA_PER_WAVELENGTH = (
    "cback_um2",
    "matrix_error_estimate",
    "expansion_error_estimate",
    "r_eff_quadrature_um",
    "v_eff_quadrature",
    "mean_volume_quadrature_um3",
)
_EXTRA_SCALARS = ("mean_volume_um3", "particle_density_kg_m3")

__all__ = [
    "EXTINCTION_COLUMNS",
    "EXTINCTION_FILENAME",
    "FORMAT_VERSION",
    "PHASE_FILENAME",
    "SEED_CSV_FILES",
    "SUMMARY_FILENAME",
    "PhaseFunctionSpectrum",
    "existing_outputs",
    "read_extinction_csv",
    "read_phase_csv",
    "read_seed_csv",
    "seed_csv_paths",
    "write_seed_csv",
]

PHASE_FILENAME = "MiePhaseFunctionSpectrum.csv"
EXTINCTION_FILENAME = "MieExtinctionSpectrum.csv"
SUMMARY_FILENAME = "table_summary.json"
#: Every file :func:`write_seed_csv` may write, in the order it writes them.
SEED_CSV_FILES = (PHASE_FILENAME, EXTINCTION_FILENAME, SUMMARY_FILENAME)

#: Layout identifier recorded in the summary (``format``) and checked by the reader.
FORMAT = "dustoptics seed-framework CSV"
#: Version of the layout described in the module docstring.
FORMAT_VERSION = 2

_UM2_TO_M2_EXPONENT = -12  # 1 um^2 = 1e-12 m^2

#: Columns of ``MieExtinctionSpectrum.csv``: (header, unit, Table attribute,
#: decimal exponent from the attribute's unit to the file's, whether stored
#: (True) or derived and checked on reading (False)).
EXTINCTION_COLUMNS: tuple[tuple[str, str, str, int, bool], ...] = (
    ("wavelength_nm", "nm", "wavelength_nm", 0, True),
    ("cext_m2", "m^2", "cext_um2", _UM2_TO_M2_EXPONENT, True),
    ("qext", "1", "qext", 0, False),
    ("csca_m2", "m^2", "csca_um2", _UM2_TO_M2_EXPONENT, True),
    ("qsca", "1", "qsca", 0, False),
    ("cabs_m2", "m^2", "cabs_um2", _UM2_TO_M2_EXPONENT, False),
    ("ssa", "1", "ssa", 0, False),
    ("g", "1", "g", 0, True),
)
_EFFICIENCIES = ("qext", "qsca")
#: Quantities of the summary whose units it states.
_SUMMARY_UNITS = (
    "wavelength_nm",
    "error_estimate",
    "cross_section_error_estimate",
    "mean_geometric_cross_section_um2",
    "number_density_per_m3",
    "g",
)


@dataclass(frozen=True)
class PhaseFunctionSpectrum:
    """A phase function read from a ``MiePhaseFunctionSpectrum.csv`` alone.

    Attributes
    ----------
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths from the header. [nm]
    theta_deg : numpy.ndarray, shape (n_theta,)
        Scattering angles from the first column. [deg]
    phase : numpy.ndarray, shape (n_wavelength, n_theta)
        Phase function (the file's columns, transposed to the
        :class:`~dustoptics.table.Table` orientation). [sr^-1]
    """

    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray


# ------------------------------------------------------------------ writing


def _columns(table: Table) -> tuple[tuple[str, str, str, int, bool], ...]:
    has_area = (
        table.cross_sections is not None
        and table.cross_sections.mean_geometric_cross_section_um2 is not None
    )
    return tuple(c for c in EXTINCTION_COLUMNS if has_area or c[0] not in _EFFICIENCIES)


def _phase_csv_bytes(table: Table) -> bytes:
    wavelengths = floats("wavelength_nm", table.wavelength_nm)
    theta = floats("theta_deg", table.theta_deg)
    rows = np.asarray(table.phase, dtype=np.float64).T.tolist()  # (theta, wavelength)
    lines = ["," + ",".join(wavelength_label(w) for w in wavelengths)]
    for t, row in zip(theta, rows):
        lines.append(number(t) + "," + ",".join(number(v) for v in row))
    return ("\n".join(lines) + "\n").encode("ascii")


def _extinction_csv_bytes(table: Table) -> bytes:
    columns = _columns(table)
    data = [
        [shift(v, exponent) for v in floats(attribute, table.quantity(attribute))]
        for _header, _unit, attribute, exponent, _stored in columns
    ]
    lines = [",".join(c[0] for c in columns)]
    lines.extend(",".join(cells) for cells in zip(*data))
    return ("\n".join(lines) + "\n").encode("ascii")


def _optional_list(values: np.ndarray | None) -> list[float] | None:
    return None if values is None else np.asarray(values, dtype=np.float64).tolist()


def _summary_bytes(table: Table, hashes: dict[str, str]) -> bytes:
    files: dict[str, Any] = {
        PHASE_FILENAME: {
            "sha256": hashes[PHASE_FILENAME],
            "layout": (
                "header: an empty cell, then the wavelengths; rows: the scattering angle, "
                "then the phase function at each wavelength"
            ),
            "units": {"header wavelengths": "nm", "first column (theta)": "deg", "phase": "sr^-1"},
            "normalization": PHASE_NORMALIZATION,
            "n_wavelength": int(table.wavelength_nm.size),
            "n_theta": int(table.theta_deg.size),
        }
    }
    if table.cross_sections is not None:
        files[EXTINCTION_FILENAME] = {
            "sha256": hashes[EXTINCTION_FILENAME],
            "columns": [
                {
                    "name": header,
                    "unit": unit,
                    "meaning": UNITS[attribute][1],
                    "derived": not stored,
                }
                for header, unit, attribute, _exponent, stored in _columns(table)
            ],
        }
    per_wavelength: dict[str, Any] = {
        "wavelength_nm": table.wavelength_nm.tolist(),
        "error_estimate": _optional_list(table.quantity("error_estimate")),
        "cross_section_error_estimate": _optional_list(
            table.quantity("cross_section_error_estimate")
        ),
        "n_nodes": None
        if (table.quadrature is None or table.quadrature.n_nodes is None)
        else table.quadrature.n_nodes.tolist(),
        "cross_section_n_nodes": None
        if (table.quadrature is None or table.quadrature.cross_section_n_nodes is None)
        else table.quadrature.cross_section_n_nodes.tolist(),
        "refractive_index_real": None
        if table.refractive_index is None
        else table.refractive_index.real.tolist(),
        "refractive_index_imag": None
        if table.refractive_index is None
        else table.refractive_index.imag.tolist(),
    }
    for key in _EXTRA_PER_WAVELENGTH:
        if table.quantity(key) is not None:
            per_wavelength[key] = _optional_list(table.quantity(key))
    for key in (*MATRIX_FIELDS, *EXPANSION_FIELDS):
        if table.quantity(key) is not None:
            per_wavelength[key] = np.asarray(table.quantity(key), dtype=np.float64).tolist()
    if table.cross_sections is None:
        per_wavelength["g"] = table.g.tolist()
    summary = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "name": table.name,
        "input_hash": table.provenance.input_hash,
        "provenance": table.provenance.to_dict(),
        "phase_normalization": PHASE_NORMALIZATION,
        "has_cross_sections": table.cross_sections is not None,
        "mean_geometric_cross_section_um2": table.quantity("mean_geometric_cross_section_um2"),
        "number_density_per_m3": table.quantity("number_density_per_m3"),
        **{key: table.quantity(key) for key in _EXTRA_SCALARS if table.quantity(key) is not None},
        "per_wavelength": per_wavelength,
        "files": files,
        "units": {key: UNITS[key][0] for key in _SUMMARY_UNITS},
    }
    text = json.dumps(summary, indent=2, sort_keys=True, allow_nan=False, ensure_ascii=True)
    return (text + "\n").encode("ascii")


def seed_csv_paths(table: Table, directory: str | os.PathLike[str]) -> list[Path]:
    """The files :func:`write_seed_csv` writes for ``table`` into ``directory``."""
    root = Path(directory)
    names = (
        SEED_CSV_FILES if table.cross_sections is not None else (PHASE_FILENAME, SUMMARY_FILENAME)
    )
    return [root / name for name in names]


def existing_outputs(directory: str | os.PathLike[str]) -> list[Path]:
    """Files of :data:`SEED_CSV_FILES` that already exist in ``directory``.

    Parameters
    ----------
    directory : path-like
        Target directory (need not exist).

    Returns
    -------
    list of pathlib.Path
        The existing paths, in the order of :data:`SEED_CSV_FILES`.
    """
    root = Path(directory)
    return [root / name for name in SEED_CSV_FILES if (root / name).exists()]


def write_seed_csv(
    table: Table, directory: str | os.PathLike[str], *, overwrite: bool = False
) -> list[Path]:
    """Write a table in the seed framework's CSV layout, with its provenance sidecar.

    Parameters
    ----------
    table : Table
        The table to write.
    directory : path-like
        Output directory; created (with its parents) if missing.
    overwrite : bool, optional
        Replace existing files.  Default False: if any of the files exists,
        nothing is written.

    Returns
    -------
    list of pathlib.Path
        ``MiePhaseFunctionSpectrum.csv`` (phase function [sr^-1] vs theta
        [deg] and wavelength [nm]), ``MieExtinctionSpectrum.csv``
        (cross-sections [m^2], efficiencies, albedo, g vs wavelength [nm];
        only when the table has cross-sections) and ``table_summary.json``,
        in that order.

    Raises
    ------
    FileExistsError
        A target exists and ``overwrite`` is False (checked for all files
        before any is written; the message names the paths).
    OSError
        Writing failed; no partial file or set is left behind.

    Examples
    --------
    >>> import dustoptics as do
    >>> from dustoptics.table import Table
    >>> from dustoptics.io.csv.seed import write_seed_csv
    >>> t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0], name="demo")
    >>> [p.name for p in write_seed_csv(t, "out")]        # doctest: +SKIP
    ['MiePhaseFunctionSpectrum.csv', 'MieExtinctionSpectrum.csv', 'table_summary.json']
    """
    if not isinstance(table, Table):
        raise TypeError(f"table must be a dustoptics.table.Table; got {type(table).__name__}")
    paths = seed_csv_paths(table, directory)
    payload = {PHASE_FILENAME: _phase_csv_bytes(table)}
    if table.cross_sections is not None:
        payload[EXTINCTION_FILENAME] = _extinction_csv_bytes(table)
    hashes = {name: hashlib.sha256(data).hexdigest() for name, data in payload.items()}
    payload[SUMMARY_FILENAME] = _summary_bytes(table, hashes)
    return write_files({path: payload[path.name] for path in paths}, overwrite=overwrite)


RECORD = register(
    Format(
        name="csv",
        summary="the seed's Mie*Spectrum.csv files and table_summary.json",
        write=write_seed_csv,
        suffixes=(".csv", ".json"),
        inputs_file=lambda name: SUMMARY_FILENAME,
    )
)


# ------------------------------------------------------------------ reading


def read_phase_csv(path: str | os.PathLike[str]) -> PhaseFunctionSpectrum:
    """Read a ``MiePhaseFunctionSpectrum.csv`` (this package's or the seed's own).

    Parameters
    ----------
    path : path-like
        The CSV file: an empty first header cell, wavelength labels [nm], then
        rows of theta [deg] and the phase function [sr^-1].

    Returns
    -------
    PhaseFunctionSpectrum

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    FormatError
        Malformed content: the message names the file, the line and the
        problem (non-empty first header cell, no wavelength columns, ragged or
        non-numeric rows, no data rows, non-increasing grids, missing final
        newline).
    """
    path = Path(path)
    rows = read_rows(path)
    header = rows[0]
    if header[0].strip() != "":
        raise FormatError(
            f"{path}: the first header cell must be empty (it heads the angle column); got {header[0]!r}"
        )
    if len(header) < 2:
        raise FormatError(f"{path}: the header has no wavelength columns")
    wavelengths = np.array(
        [parse(path, 1, f"{j} (header)", cell) for j, cell in enumerate(header[1:], 2)]
    )
    check_increasing(path, "the header wavelengths [nm]", wavelengths)
    if len(rows) < 2:
        raise FormatError(f"{path}: no data rows after the header")
    width = len(header)
    theta = np.empty(len(rows) - 1)
    values = np.empty((len(rows) - 1, width - 1))
    for i, row in enumerate(rows[1:]):
        line = i + 2
        if len(row) != width:
            raise FormatError(f"{path}: line {line} has {len(row)} cells; the header has {width}")
        theta[i] = parse(path, line, "1 (theta_deg)", row[0])
        for j in range(1, width):
            values[i, j - 1] = parse(path, line, f"{j + 1} ({header[j]} nm)", row[j])
    check_increasing(path, "the angles in the first column [deg]", theta)
    if theta[0] < 0.0 or theta[-1] > 180.0:
        raise FormatError(
            f"{path}: angles must lie in [0, 180] deg; got {theta[0]!r} to {theta[-1]!r}"
        )
    return PhaseFunctionSpectrum(
        wavelength_nm=wavelengths, theta_deg=theta, phase=np.ascontiguousarray(values.T)
    )


def read_extinction_csv(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read the columns of a ``MieExtinctionSpectrum.csv`` written by :func:`write_seed_csv`.

    Parameters
    ----------
    path : path-like
        The CSV file with the columns of :data:`EXTINCTION_COLUMNS`
        (``qext`` and ``qsca`` optional).

    Returns
    -------
    dict of str to numpy.ndarray
        Keyed by :class:`~dustoptics.table.Table` attribute name, with the
        cross-sections converted back to um^2 (``cext_um2``, ...);
        ``wavelength_nm`` [nm]; ``qext``, ``qsca`` (if present), ``ssa``,
        ``g`` [-].

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    FormatError
        Missing columns, ragged or non-numeric rows, no data rows, a
        non-increasing wavelength column; the message names the file.
    """
    path = Path(path)
    rows = read_rows(path)
    header = [cell.strip() for cell in rows[0]]
    required = [c[0] for c in EXTINCTION_COLUMNS if c[0] not in _EFFICIENCIES]
    missing = [name for name in required if name not in header]
    if missing:
        raise FormatError(
            f"{path}: missing column(s) {', '.join(missing)}; expected "
            f"{','.join(c[0] for c in EXTINCTION_COLUMNS)}; got {','.join(header)}"
        )
    if len(rows) < 2:
        raise FormatError(f"{path}: no data rows after the header")
    columns = [c for c in EXTINCTION_COLUMNS if c[0] in header]
    out: dict[str, list[float]] = {c[2]: [] for c in columns}
    for i, row in enumerate(rows[1:]):
        line = i + 2
        if len(row) != len(header):
            raise FormatError(
                f"{path}: line {line} has {len(row)} cells; the header has {len(header)}"
            )
        for name, _unit, attribute, exponent, _stored in columns:
            out[attribute].append(parse(path, line, name, row[header.index(name)], exponent))
    arrays = {key: np.array(values) for key, values in out.items()}
    check_increasing(path, "wavelength_nm", arrays["wavelength_nm"])
    return arrays


def _verify_checksums(root: Path, summary: dict[str, Any], names: list[str]) -> None:
    summary_path = root / SUMMARY_FILENAME
    files = summary["files"]
    for name in names:
        entry = files.get(name)
        if not isinstance(entry, dict) or not isinstance(entry.get("sha256"), str):
            raise FormatError(
                f"{summary_path}: records no sha256 for {name} (removed from the summary?), so "
                "the file cannot be checked; pass verify=False to read it unchecked"
            )
        actual = hashlib.sha256(read_checked(root / name)).hexdigest()
        if actual != entry["sha256"]:
            raise FormatError(
                f"{root / name}: sha256 {actual} differs from the {entry['sha256']} recorded in "
                f"{summary_path} (the file was changed or truncated after it was written)"
            )


def _read_summary(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise FileNotFoundError(
            f"{path}: no such file (it carries the table's provenance; for a bare "
            f"{PHASE_FILENAME} use read_phase_csv)"
        )
    try:
        summary = load_json(path, encoding="ascii")
    except FormatError as exc:
        detail = str(exc).removeprefix(f"{path}: ")
        raise FormatError(f"{path}: not a valid JSON table summary ({detail})") from None
    if not isinstance(summary, dict):
        raise FormatError(f"{path}: not a table summary (expected a JSON object)")
    if summary.get("format") != FORMAT or summary.get("format_version") != FORMAT_VERSION:
        raise FormatError(
            f"{path}: format {summary.get('format')!r} version {summary.get('format_version')!r}; "
            f"this reader reads {FORMAT!r} version {FORMAT_VERSION}"
        )
    keys = (
        "name", "provenance", "has_cross_sections", "mean_geometric_cross_section_um2",
        "number_density_per_m3", "per_wavelength", "files",
    )  # fmt: skip
    missing = [key for key in keys if key not in summary]
    if missing:
        raise FormatError(f"{path}: missing key(s) {', '.join(missing)}")
    if not isinstance(summary["per_wavelength"], dict) or not isinstance(summary["files"], dict):
        raise FormatError(f"{path}: 'per_wavelength' and 'files' must be JSON objects")
    return summary


def _check_derived(path: Path, table: Table, columns: dict[str, np.ndarray]) -> None:
    for header, _unit, attribute, _exponent, stored in EXTINCTION_COLUMNS:
        if stored or attribute not in columns:
            continue
        try:
            expected = table.quantity(attribute)
        except ValueError as exc:
            raise FormatError(f"{path}: column {header} cannot be checked: {exc}") from None
        if not np.array_equal(columns[attribute], expected):
            i = int(np.argmax(columns[attribute] != expected))
            raise FormatError(
                f"{path}: column {header} disagrees with the stored columns at "
                f"wavelength {float(table.wavelength_nm[i])!r} nm: file {float(columns[attribute][i])!r}, "
                f"recomputed {float(expected[i])!r}"
            )


def _guard(path: Path, build: Callable[[], Any]) -> Any:
    try:
        return build()
    except FormatError:
        raise
    except (ValueError, TypeError, KeyError) as exc:
        raise FormatError(f"{path}: {exc}") from None


def read_seed_csv(directory: str | os.PathLike[str], *, verify: bool = True) -> Table:
    """Read a directory written by :func:`write_seed_csv`.

    Parameters
    ----------
    directory : path-like
        Directory holding ``MiePhaseFunctionSpectrum.csv``,
        ``table_summary.json`` and (for tables with cross-sections)
        ``MieExtinctionSpectrum.csv``.
    verify : bool, optional
        Check each CSV file's sha256 against the summary first (default True):
        a file whose digest differs, or that the summary records no digest
        for, is an error.  False reads the files unchecked (files edited by
        hand); their shapes are still checked against the summary's.

    Returns
    -------
    Table
        The table as written, bit for bit, with its provenance (whose input
        hash is checked against its inputs).

    Raises
    ------
    FileNotFoundError
        A file is missing.
    FormatError
        A file is malformed or truncated, its checksum does not match the
        summary or is missing from it, a derived column disagrees with the
        stored ones, or the files disagree with each other or with the shapes
        the summary records; the message names the file and the problem.
    """
    root = Path(directory)
    summary_path = root / SUMMARY_FILENAME
    summary = _read_summary(summary_path)
    has_cross_sections = summary["has_cross_sections"]
    if not isinstance(has_cross_sections, bool):
        raise FormatError(f"{summary_path}: has_cross_sections must be true or false")
    needed = [root / PHASE_FILENAME] + ([root / EXTINCTION_FILENAME] if has_cross_sections else [])
    for path in needed:
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such file (listed in {summary_path})")
    if verify:
        _verify_checksums(root, summary, [path.name for path in needed])
    phase = read_phase_csv(root / PHASE_FILENAME)
    entry = summary["files"].get(PHASE_FILENAME)
    recorded = (
        (entry.get("n_wavelength"), entry.get("n_theta")) if isinstance(entry, dict) else None
    )
    if (
        recorded is not None
        and all(type(n) is int for n in recorded)
        and (recorded != phase.phase.shape)
    ):
        raise FormatError(
            f"{root / PHASE_FILENAME}: {phase.phase.shape[0]} wavelengths x "
            f"{phase.phase.shape[1]} angles, but {summary_path} records {recorded[0]} x "
            f"{recorded[1]} (a cut or edited file)"
        )
    per_wavelength = summary["per_wavelength"]

    def array(key: str) -> np.ndarray | None:
        value = per_wavelength.get(key)
        return None if value is None else np.array(value, dtype=np.float64)

    def counts(key: str) -> np.ndarray | None:
        value = per_wavelength.get(key)
        if value is not None and not all(type(v) is int for v in value):
            raise FormatError(f"{summary_path}: per_wavelength.{key} must be a list of integers")
        return None if value is None else np.array(value, dtype=np.int64)

    def refractive_index() -> np.ndarray | None:
        n, k = array("refractive_index_real"), array("refractive_index_imag")
        if (n is None) != (k is None):
            raise FormatError(
                f"{summary_path}: refractive_index_real and _imag must both be given or neither"
            )
        return None if n is None or k is None else n + 1j * k

    listed = _guard(summary_path, lambda: array("wavelength_nm"))
    if listed is None or not np.array_equal(listed, phase.wavelength_nm):
        raise FormatError(
            f"{root / PHASE_FILENAME}: header wavelengths differ from those listed in {summary_path}"
        )
    fields: dict[str, Any] = {}
    if has_cross_sections:
        extinction_path = root / EXTINCTION_FILENAME
        columns = read_extinction_csv(extinction_path)
        if not np.array_equal(columns["wavelength_nm"], phase.wavelength_nm):
            raise FormatError(
                f"{extinction_path}: wavelengths ({columns['wavelength_nm'].size} values) differ "
                f"from the header of {root / PHASE_FILENAME} ({phase.wavelength_nm.size} values)"
            )
        fields = {
            "cext_um2": columns["cext_um2"],
            "csca_um2": columns["csca_um2"],
            "g": columns["g"],
        }
    else:
        columns = {}
        fields = {"g": _guard(summary_path, lambda: array("g"))}
        if fields["g"] is None:
            raise FormatError(f"{summary_path}: a phase-only table needs per_wavelength.g")
    extra: dict[str, Any] = {
        key: array(key) for key in (*_EXTRA_PER_WAVELENGTH, *MATRIX_FIELDS, *EXPANSION_FIELDS)
    }
    extra.update({key: summary.get(key) for key in _EXTRA_SCALARS})
    fields.update(extra)
    table = _guard(
        summary_path,
        lambda: Table(
            name=summary["name"],
            wavelength_nm=phase.wavelength_nm,
            theta_deg=phase.theta_deg,
            phase=phase.phase,
            refractive_index=refractive_index(),
            provenance=Provenance.from_dict(summary["provenance"]),
            **grouped_fields(
                fields,
                error_estimate=array("error_estimate"),
                cross_section_error_estimate=array("cross_section_error_estimate"),
                n_nodes=counts("n_nodes"),
                cross_section_n_nodes=counts("cross_section_n_nodes"),
                mean_geometric_cross_section_um2=summary["mean_geometric_cross_section_um2"],
                number_density_per_m3=summary["number_density_per_m3"],
            ),
        ),
    )
    if columns:
        _check_derived(root / EXTINCTION_FILENAME, table, columns)
    return table
