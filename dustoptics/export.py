"""Write and read lookup tables: the seed framework's CSV layout.

This module is the only place in the library that writes files.  It turns an
:class:`dustoptics.optics.OpticsTable` into the files the seed thesis's
rendering framework reads (Meyran 2022; layout in ``/work/shared/BRIEF.md``
sections 5 and 7), plus a provenance summary:

``MiePhaseFunctionSpectrum.csv``
    Header: an empty cell, then one column label per wavelength [nm] (written
    as an integer when it is integral, e.g. ``360``).  Then one row per
    scattering angle: theta [deg], then the phase function [sr^-1] at each
    wavelength, normalized so that 2 pi int_{-1}^{1} P dmu = 1.
``MieExtinctionSpectrum.csv``
    Header ``wavelength_nm,cext_m2,qext,csca_m2,qsca,cabs_m2,ssa,g``: the
    wavelength [nm], the mean cross-sections per particle in SI units [m^2],
    the area-weighted efficiencies [-], the single-scattering albedo [-] and
    the asymmetry parameter [-].  (The seed's own file has undocumented units;
    these headers state them.)
``table_summary.json``
    Software versions, the material, the size distribution, the weighting, the
    tolerances, per-wavelength error estimates and node counts, the unit of
    every column, and the sha256 of each CSV file's bytes.

Every number is written with Python's shortest round-trip ``repr``, so
:func:`read_seed_csv` returns the written floats bit for bit.  The
cross-sections are converted from um^2 to m^2 by shifting the decimal exponent
of that ``repr`` by 12 (exact in decimal), so the m^2 value in the file is the
correctly rounded product and reading it back restores the um^2 float exactly.
The bytes written depend only on the table (no timestamps, no paths, sorted
JSON keys), so two builds of the same table give identical files.

Writes are atomic per file: each file is written to a temporary file in the
target directory and moved into place with :func:`os.replace`.
"""

from __future__ import annotations

import csv
import decimal
import hashlib
import io
import json
import math
import os
import tempfile
from collections.abc import Mapping
from dataclasses import asdict, dataclass, is_dataclass
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "EXTINCTION_COLUMNS",
    "EXTINCTION_FILENAME",
    "PHASE_FILENAME",
    "SEED_CSV_FILES",
    "SUMMARY_FILENAME",
    "PhaseTable",
    "SeedTable",
    "existing_outputs",
    "read_extinction_csv",
    "read_phase_csv",
    "read_seed_csv",
    "write_seed_csv",
]

PHASE_FILENAME = "MiePhaseFunctionSpectrum.csv"
EXTINCTION_FILENAME = "MieExtinctionSpectrum.csv"
SUMMARY_FILENAME = "table_summary.json"
#: Every file :func:`write_seed_csv` writes, in the order it writes them.
SEED_CSV_FILES = (PHASE_FILENAME, EXTINCTION_FILENAME, SUMMARY_FILENAME)

#: Version of the layout described in the module docstring (recorded in the summary).
FORMAT_VERSION = 1

_UM2_TO_M2_EXPONENT = -12  # 1 um^2 = 1e-12 m^2

#: Columns of ``MieExtinctionSpectrum.csv``: (header, unit, OpticsTable attribute,
#: decimal exponent shift from the attribute's unit to the file's unit).
EXTINCTION_COLUMNS: tuple[tuple[str, str, str, int], ...] = (
    ("wavelength_nm", "nm", "wavelength_nm", 0),
    ("cext_m2", "m^2", "cext_um2", _UM2_TO_M2_EXPONENT),
    ("qext", "1", "qext", 0),
    ("csca_m2", "m^2", "csca_um2", _UM2_TO_M2_EXPONENT),
    ("qsca", "1", "qsca", 0),
    ("cabs_m2", "m^2", "cabs_um2", _UM2_TO_M2_EXPONENT),
    ("ssa", "1", "ssa", 0),
    ("g", "1", "g", 0),
)

_COLUMN_MEANINGS = {
    "wavelength_nm": "vacuum wavelength",
    "cext_m2": "mean extinction cross-section per particle",
    "qext": "extinction efficiency <C_ext> / (pi <r^2>)",
    "csca_m2": "mean scattering cross-section per particle",
    "qsca": "scattering efficiency <C_sca> / (pi <r^2>)",
    "cabs_m2": "mean absorption cross-section per particle, <C_ext> - <C_sca>",
    "ssa": "single-scattering albedo <C_sca> / <C_ext>",
    "g": "asymmetry parameter 2 pi int P mu dmu",
}

PHASE_NORMALIZATION = "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)"


# ------------------------------------------------------------------ results


@dataclass(frozen=True)
class PhaseTable:
    """A phase function read from ``MiePhaseFunctionSpectrum.csv``.

    Attributes
    ----------
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths from the header. [nm]
    theta_deg : numpy.ndarray, shape (n_theta,)
        Scattering angles from the first column. [deg]
    phase : numpy.ndarray, shape (n_wavelength, n_theta)
        Phase function (the file's columns, transposed to the
        :class:`~dustoptics.optics.OpticsTable` orientation). [sr^-1]
    """

    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray


@dataclass(frozen=True)
class SeedTable:
    """Everything :func:`read_seed_csv` reads back from a directory.

    Attributes
    ----------
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths. [nm]
    theta_deg : numpy.ndarray, shape (n_theta,)
        Scattering angles, 0 = forward. [deg]
    phase : numpy.ndarray, shape (n_wavelength, n_theta)
        Phase function, 2 pi int P dmu = 1. [sr^-1]
    cext_um2, csca_um2, cabs_um2 : numpy.ndarray, shape (n_wavelength,)
        Mean cross-sections per particle, converted back from the file's m^2. [um^2]
    qext, qsca : numpy.ndarray, shape (n_wavelength,)
        Efficiencies. [-]
    ssa : numpy.ndarray, shape (n_wavelength,)
        Single-scattering albedo. [-]
    g : numpy.ndarray, shape (n_wavelength,)
        Asymmetry parameter. [-]
    """

    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray
    cext_um2: np.ndarray
    csca_um2: np.ndarray
    cabs_um2: np.ndarray
    qext: np.ndarray
    qsca: np.ndarray
    ssa: np.ndarray
    g: np.ndarray


# ------------------------------------------------------------------ formatting


def _floats(name: str, values: Any) -> list[float]:
    """Plain Python floats (``repr`` of numpy scalars is not a number in numpy 2)."""
    out = np.asarray(values, dtype=np.float64).ravel().tolist()
    for x in out:
        if not math.isfinite(x):
            raise ValueError(f"table.{name} must be finite to be written; got {x!r}")
    return out


def _number(x: float) -> str:
    """Shortest string that parses back to exactly ``x``."""
    return repr(x)


def _wavelength_label(x: float) -> str:
    """``360`` for 360.0, the round-trip repr otherwise."""
    return str(int(x)) if x.is_integer() else repr(x)


def _shift(x: float, exponent: int) -> str:
    """``repr(x)`` times 10**exponent, exactly, as a decimal string."""
    if exponent == 0 or x == 0.0:
        return repr(x)
    return format(decimal.Decimal(repr(x)).scaleb(exponent), "e")


def _phase_csv_bytes(table: Any) -> bytes:
    wavelengths = _floats("wavelength_nm", table.wavelength_nm)
    theta = _floats("theta_deg", table.theta_deg)
    phase = np.asarray(table.phase, dtype=np.float64)
    if phase.shape != (len(wavelengths), len(theta)):
        raise ValueError(
            f"table.phase must have shape (n_wavelength, n_theta) = "
            f"({len(wavelengths)}, {len(theta)}); got {phase.shape}"
        )
    columns = _floats("phase", phase.T)  # row-major over (theta, wavelength)
    n = len(wavelengths)
    lines = ["," + ",".join(_wavelength_label(w) for w in wavelengths)]
    for i, t in enumerate(theta):
        row = columns[i * n : (i + 1) * n]
        lines.append(_number(t) + "," + ",".join(_number(v) for v in row))
    return ("\n".join(lines) + "\n").encode("ascii")


def _extinction_csv_bytes(table: Any) -> bytes:
    n = np.asarray(table.wavelength_nm).size
    data = []
    for header, _unit, attribute, exponent in EXTINCTION_COLUMNS:
        values = _floats(attribute, getattr(table, attribute))
        if len(values) != n:
            raise ValueError(
                f"table.{attribute} must have one value per wavelength ({n}); got {len(values)}"
            )
        data.append([_shift(v, exponent) for v in values])
    lines = [",".join(column[0] for column in EXTINCTION_COLUMNS)]
    lines.extend(",".join(cells) for cells in zip(*data))
    return ("\n".join(lines) + "\n").encode("ascii")


def _installed_version(distribution: str) -> str:
    try:
        return _dist_version(distribution)
    except PackageNotFoundError:
        return "not installed"


def _plain(value: Any) -> Any:
    """JSON-ready copy: dataclasses to dicts, numpy to Python numbers and lists."""
    if is_dataclass(value) and not isinstance(value, type):
        return _plain(asdict(value))
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _summary_bytes(table: Any, hashes: Mapping[str, str], metadata: Mapping[str, Any] | None) -> bytes:
    from dustoptics import __version__

    m = np.asarray(table.refractive_index, dtype=np.complex128)
    summary: dict[str, Any] = {
        "format": "dustoptics seed-framework CSV",
        "format_version": FORMAT_VERSION,
        "software": {
            "dustoptics": __version__,
            "numpy": np.__version__,
            "miepython": _installed_version("miepython"),
        },
        "material": table.material,
        "refractive_index": {
            "convention": "m = n + i k, k >= 0 for absorption",
            "n": m.real,
            "k": m.imag,
        },
        "distribution": table.distribution.to_dict(),
        "mean_geometric_cross_section_um2": float(table.mean_geometric_cross_section_um2),
        "weighting": table.weighting,
        "rtol": float(table.rtol),
        "cross_section_rtol": float(table.cross_section_rtol),
        "quadrature": table.settings,
        "wavelength_nm": table.wavelength_nm,
        "error_estimate": table.error_estimate,
        "cross_section_error_estimate": table.cross_section_error_estimate,
        "n_nodes": np.asarray(table.n_nodes, dtype=np.int64),
        "converged": np.asarray(table.converged, dtype=bool),
        "files": {
            PHASE_FILENAME: {
                "sha256": hashes[PHASE_FILENAME],
                "layout": (
                    "header: an empty cell, then the wavelengths; rows: the scattering angle, "
                    "then the phase function at each wavelength"
                ),
                "units": {"header wavelengths": "nm", "first column (theta)": "deg", "phase": "sr^-1"},
                "normalization": PHASE_NORMALIZATION,
                "n_wavelength": int(np.asarray(table.wavelength_nm).size),
                "n_theta": int(np.asarray(table.theta_deg).size),
            },
            EXTINCTION_FILENAME: {
                "sha256": hashes[EXTINCTION_FILENAME],
                "columns": [
                    {"name": header, "unit": unit, "meaning": _COLUMN_MEANINGS[header]}
                    for header, unit, _attribute, _exponent in EXTINCTION_COLUMNS
                ],
            },
        },
        "units": {
            "wavelength_nm": "nm",
            "mean_geometric_cross_section_um2": "um^2",
            "error_estimate": "1 (largest relative change of the phase function between the last two quadrature levels)",
            "cross_section_error_estimate": "1 (relative for <C_ext>, <C_sca>; absolute for g)",
            "n_nodes": "count of radius nodes",
            "rtol": "1",
            "cross_section_rtol": "1",
        },
    }
    if metadata:
        summary["metadata"] = metadata
    text = json.dumps(_plain(summary), indent=2, sort_keys=True, allow_nan=False, ensure_ascii=True)
    return (text + "\n").encode("ascii")


# ------------------------------------------------------------------ writing


def existing_outputs(directory: str | os.PathLike[str]) -> list[Path]:
    """Files :func:`write_seed_csv` would replace in ``directory``.

    Parameters
    ----------
    directory : path-like
        Target directory (need not exist).

    Returns
    -------
    list of pathlib.Path
        The paths among :data:`SEED_CSV_FILES` that already exist, in order.
    """
    root = Path(directory)
    return [root / name for name in SEED_CSV_FILES if (root / name).exists()]


def _stage(directory: Path, name: str, data: bytes) -> Path:
    """Write ``data`` to a new temporary file beside ``directory / name``."""
    path: Path | None = None
    try:
        with tempfile.NamedTemporaryFile(
            mode="wb", prefix=f".{name}.", suffix=".tmp", dir=directory, delete=False
        ) as handle:
            path = Path(handle.name)
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(path, 0o644)  # NamedTemporaryFile creates 0600; tables are meant to be shared
    except BaseException:
        if path is not None:
            path.unlink(missing_ok=True)
        raise
    return path


def write_seed_csv(
    table: Any,
    directory: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    metadata: Mapping[str, Any] | None = None,
) -> list[Path]:
    """Write a table in the seed framework's CSV layout, with a provenance summary.

    Parameters
    ----------
    table : OpticsTable
        From :func:`dustoptics.compute_optics`.  Every value must be finite.
    directory : path-like
        Output directory; created (with its parents) if missing.
    overwrite : bool, optional
        Replace existing files.  Default False: if any of the files exists,
        nothing is written.
    metadata : mapping, optional
        JSON-serializable extra provenance (e.g. the preset name), stored under
        ``"metadata"`` in the summary.

    Returns
    -------
    list of pathlib.Path
        ``MiePhaseFunctionSpectrum.csv`` (phase function [sr^-1] vs theta
        [deg] and wavelength [nm]), ``MieExtinctionSpectrum.csv``
        (cross-sections [m^2], efficiencies, albedo, g vs wavelength [nm]) and
        ``table_summary.json``, in that order.

    Raises
    ------
    FileExistsError
        A target exists and ``overwrite`` is False (checked for all files
        before any is written; the message names the path).
    ValueError
        The table has non-finite values or inconsistent shapes.

    Notes
    -----
    All bytes are prepared in memory, then each file is written to a
    temporary file in ``directory`` and, once all are complete, moved into
    place with :func:`os.replace`.  On any error the temporary files are
    removed, and so are files this call had newly created, so a failed call
    leaves no partial set behind.  (With ``overwrite=True``, files replaced
    before a failure in the final renames are not restored.)

    Examples
    --------
    >>> import dustoptics as do
    >>> from dustoptics import export
    >>> t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0])
    >>> paths = export.write_seed_csv(t, "out")            # doctest: +SKIP
    >>> [p.name for p in paths]                            # doctest: +SKIP
    ['MiePhaseFunctionSpectrum.csv', 'MieExtinctionSpectrum.csv', 'table_summary.json']
    """
    root = Path(directory)
    if not overwrite:
        existing = existing_outputs(root)
        if existing:
            names = ", ".join(str(p) for p in existing)
            raise FileExistsError(f"{names} already exists (pass overwrite=True to replace)")

    payload = {
        PHASE_FILENAME: _phase_csv_bytes(table),
        EXTINCTION_FILENAME: _extinction_csv_bytes(table),
    }
    hashes = {name: hashlib.sha256(data).hexdigest() for name, data in payload.items()}
    payload[SUMMARY_FILENAME] = _summary_bytes(table, hashes, metadata)

    created_directory = not root.exists()
    root.mkdir(parents=True, exist_ok=True)
    staged: dict[str, Path] = {}
    replaced: list[Path] = []
    targets = [root / name for name in SEED_CSV_FILES]
    preexisting = {target for target in targets if target.exists()}
    try:
        for name in SEED_CSV_FILES:
            staged[name] = _stage(root, name, payload[name])
        for name, target in zip(SEED_CSV_FILES, targets):
            os.replace(staged[name], target)
            del staged[name]
            replaced.append(target)
    except BaseException:
        for temporary in staged.values():
            temporary.unlink(missing_ok=True)
        for target in replaced:
            if target not in preexisting:
                target.unlink(missing_ok=True)
        if created_directory:
            try:
                root.rmdir()
            except OSError:
                pass
        raise
    return targets


# ------------------------------------------------------------------ reading


def _read_rows(path: Path) -> list[list[str]]:
    try:
        text = path.read_text(encoding="ascii")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not an ASCII CSV file ({exc.reason} at byte {exc.start})") from None
    rows = list(csv.reader(io.StringIO(text, newline="")))
    if not rows:
        raise ValueError(f"{path}: file is empty (expected a header line)")
    if text and not text.endswith("\n"):
        raise ValueError(f"{path}: file does not end with a newline (truncated?)")
    return rows


def _parse(path: Path, line: int, column: str, cell: str, exponent: int = 0) -> float:
    try:
        if exponent:
            value = float(decimal.Decimal(cell.strip()).scaleb(-exponent))
        else:
            value = float(cell)
    except (ValueError, decimal.InvalidOperation):
        raise ValueError(f"{path}: line {line}, column {column}: not a number: {cell!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{path}: line {line}, column {column}: not a finite number: {cell!r}")
    return value


def _check_increasing(path: Path, what: str, values: np.ndarray) -> None:
    if values.size > 1 and not np.all(np.diff(values) > 0):
        i = int(np.argmax(np.diff(values) <= 0))
        raise ValueError(
            f"{path}: {what} must be strictly increasing; got {values[i]!r} then {values[i + 1]!r}"
        )


def read_phase_csv(path: str | os.PathLike[str]) -> PhaseTable:
    """Read a ``MiePhaseFunctionSpectrum.csv`` (this package's or the seed's own).

    Parameters
    ----------
    path : path-like
        The CSV file: an empty first header cell, wavelength labels [nm], then
        rows of theta [deg] and the phase function [sr^-1].

    Returns
    -------
    PhaseTable

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Malformed content: the message names the file, the line and the
        problem (non-empty first header cell, no wavelength columns, ragged or
        non-numeric rows, no data rows, non-increasing grids, missing final
        newline).
    """
    path = Path(path)
    rows = _read_rows(path)
    header = rows[0]
    if header[0].strip() != "":
        raise ValueError(
            f"{path}: the first header cell must be empty (it heads the angle column); got {header[0]!r}"
        )
    if len(header) < 2:
        raise ValueError(f"{path}: the header has no wavelength columns")
    wavelengths = np.array(
        [_parse(path, 1, f"{j + 1} (header)", cell) for j, cell in enumerate(header[1:], start=1)]
    )
    _check_increasing(path, "the header wavelengths [nm]", wavelengths)
    if len(rows) < 2:
        raise ValueError(f"{path}: no data rows after the header")
    width = len(header)
    theta = np.empty(len(rows) - 1)
    values = np.empty((len(rows) - 1, width - 1))
    for i, row in enumerate(rows[1:]):
        line = i + 2
        if len(row) != width:
            raise ValueError(f"{path}: line {line} has {len(row)} cells; the header has {width}")
        theta[i] = _parse(path, line, "1 (theta_deg)", row[0])
        for j in range(1, width):
            values[i, j - 1] = _parse(path, line, f"{j + 1} ({header[j]} nm)", row[j])
    _check_increasing(path, "the angles in the first column [deg]", theta)
    if theta[0] < 0.0 or theta[-1] > 180.0:
        raise ValueError(f"{path}: angles must lie in [0, 180] deg; got {theta[0]!r} to {theta[-1]!r}")
    return PhaseTable(wavelength_nm=wavelengths, theta_deg=theta, phase=np.ascontiguousarray(values.T))


def read_extinction_csv(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a ``MieExtinctionSpectrum.csv`` written by :func:`write_seed_csv`.

    Parameters
    ----------
    path : path-like
        The CSV file with the columns of :data:`EXTINCTION_COLUMNS`.

    Returns
    -------
    dict of str to numpy.ndarray
        Keyed by :class:`~dustoptics.optics.OpticsTable` attribute name, with
        the cross-sections converted back to um^2 (``cext_um2``, ...);
        ``wavelength_nm`` [nm]; ``qext``, ``qsca``, ``ssa``, ``g`` [-].

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Missing columns, ragged or non-numeric rows, no data rows, a
        non-increasing wavelength column; the message names the file.
    """
    path = Path(path)
    rows = _read_rows(path)
    header = [cell.strip() for cell in rows[0]]
    missing = [name for name, *_ in EXTINCTION_COLUMNS if name not in header]
    if missing:
        raise ValueError(
            f"{path}: missing column(s) {', '.join(missing)}; expected "
            f"{','.join(name for name, *_ in EXTINCTION_COLUMNS)}; got {','.join(header)}"
        )
    if len(rows) < 2:
        raise ValueError(f"{path}: no data rows after the header")
    out: dict[str, list[float]] = {attribute: [] for _n, _u, attribute, _e in EXTINCTION_COLUMNS}
    for i, row in enumerate(rows[1:]):
        line = i + 2
        if len(row) != len(header):
            raise ValueError(f"{path}: line {line} has {len(row)} cells; the header has {len(header)}")
        for name, _unit, attribute, exponent in EXTINCTION_COLUMNS:
            out[attribute].append(_parse(path, line, name, row[header.index(name)], exponent))
    arrays = {key: np.array(values) for key, values in out.items()}
    _check_increasing(path, "wavelength_nm", arrays["wavelength_nm"])
    return arrays


def _verify_checksums(root: Path) -> None:
    summary_path = root / SUMMARY_FILENAME
    if not summary_path.exists():
        return
    try:
        summary = json.loads(summary_path.read_text(encoding="utf-8"))
        files = summary["files"]
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"{summary_path}: not a valid table summary ({exc})") from None
    for name in (PHASE_FILENAME, EXTINCTION_FILENAME):
        expected = files.get(name, {}).get("sha256") if isinstance(files, dict) else None
        if expected is None:
            continue
        actual = hashlib.sha256((root / name).read_bytes()).hexdigest()
        if actual != expected:
            raise ValueError(
                f"{root / name}: sha256 {actual} differs from the {expected} recorded in "
                f"{summary_path} (the file was changed or truncated after it was written)"
            )


def read_seed_csv(directory: str | os.PathLike[str], *, verify: bool = True) -> SeedTable:
    """Read a directory written by :func:`write_seed_csv`.

    Parameters
    ----------
    directory : path-like
        Directory holding ``MiePhaseFunctionSpectrum.csv`` and
        ``MieExtinctionSpectrum.csv``.
    verify : bool, optional
        If ``table_summary.json`` is present, check each CSV file's sha256
        against it first.  Default True.

    Returns
    -------
    SeedTable
        The numbers as written, bit for bit (cross-sections in um^2).

    Raises
    ------
    FileNotFoundError
        A CSV file is missing.
    ValueError
        A file is malformed or truncated, its checksum does not match the
        summary, or the two files list different wavelengths; the message
        names the file and the problem.
    """
    root = Path(directory)
    phase_path, extinction_path = root / PHASE_FILENAME, root / EXTINCTION_FILENAME
    for path in (phase_path, extinction_path):
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such file")
    if verify:
        _verify_checksums(root)
    phase = read_phase_csv(phase_path)
    extinction = read_extinction_csv(extinction_path)
    if not np.array_equal(extinction["wavelength_nm"], phase.wavelength_nm):
        raise ValueError(
            f"{extinction_path}: wavelengths ({extinction['wavelength_nm'].size} values) differ from "
            f"the header of {phase_path} ({phase.wavelength_nm.size} values)"
        )
    return SeedTable(
        wavelength_nm=phase.wavelength_nm,
        theta_deg=phase.theta_deg,
        phase=phase.phase,
        cext_um2=extinction["cext_um2"],
        csca_um2=extinction["csca_um2"],
        cabs_um2=extinction["cabs_um2"],
        qext=extinction["qext"],
        qsca=extinction["qsca"],
        ssa=extinction["ssa"],
        g=extinction["g"],
    )
