"""A table's files in a directory: read one back, write a set, place it beside what is there.

What ``dustoptics build`` and ``dustoptics export`` do with files, for Python
users too:

- :func:`read_table`: a table from any table file dustoptics writes (HDF5 or
  netCDF, a seed-CSV directory or its ``table_summary.json``);
- :func:`write_formats`: one table in several formats (:data:`dustoptics.io.FORMATS`),
  written as one set (:func:`dustoptics.io._atomic.file_set`), each format's
  options recorded in its files' provenance;
- :func:`place_outputs`: files rendered elsewhere, moved into a directory
  beside the files already there: the same ones are left untouched, different
  ones are replaced only with ``force``;
- :func:`place_table`: both, into ``OUT/NAME/`` (``NAME`` the table's name);
- :func:`prepare_export`: the table and options for a set of formats: a number
  density from an optical depth (cosmoscout);
- :func:`with_inputs`: a table whose provenance records inputs given outside
  its configuration (a number density, an optical depth);
- :func:`write_atmosphere_set`: an atmosphere set's files (CosmoScout VR's,
  optionally Bruneton's) and its provenance record, as ``dustoptics build
  mars`` writes them.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dustoptics._validation import check_file_name, check_inside
from dustoptics.atmosphere.build import SET_PROVENANCE_SUFFIX, set_provenance
from dustoptics.atmosphere.sets import with_optical_depth
from dustoptics.io._atomic import (
    STAGE_PREFIX,
    FormatError,
    _commit,
    file_set,
    scratch,
    write_files,
)
from dustoptics.io.csv.cosmoscout import ProfileOptions, write_atmosphere
from dustoptics.io.csv.seed import SUMMARY_FILENAME, read_seed_csv
from dustoptics.io.engines.bruneton import write_bruneton
from dustoptics.io.registry import FORMATS, FormatOptions, write
from dustoptics.io.rt.profile import RTProfileOptions
from dustoptics.io.tables.netcdf import read_hdf5

if TYPE_CHECKING:
    from dustoptics.atmosphere.sets import Atmosphere
    from dustoptics.table import Table

__all__ = [
    "TABLE_SUFFIXES",
    "Placement",
    "place_outputs",
    "place_table",
    "prepare_export",
    "read_table",
    "with_inputs",
    "write_atmosphere_set",
    "write_formats",
]

#: Suffixes of the files that hold a whole table (netCDF-4/HDF5).
TABLE_SUFFIXES = (".h5", ".hdf5", ".nc")


def read_table(path: str | os.PathLike[str]) -> Table:
    """Read a table from any table file dustoptics writes.

    Parameters
    ----------
    path : path-like
        An HDF5 or netCDF file (``.h5``, ``.hdf5``, ``.nc``), a seed-CSV
        directory or its ``table_summary.json``.

    Returns
    -------
    Table

    Raises
    ------
    FileNotFoundError
        No such file.
    dustoptics.io.FormatError
        A damaged or unrecognized file.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such file or directory: {str(p)!r}")
    if p.is_dir() or p.name == SUMMARY_FILENAME:
        return read_seed_csv(p if p.is_dir() else p.parent)
    if p.suffix.lower() in TABLE_SUFFIXES:
        return read_hdf5(p)
    raise FormatError(
        f"{str(p)!r}: not a table file; give an HDF5 file (.h5, .hdf5, .nc), a seed-CSV "
        f"directory or its {SUMMARY_FILENAME}"
    )


def with_inputs(table: Table, *, note: str | None = None, **inputs: Any) -> Table:
    """The table with inputs added to its provenance, hence with a new input hash.

    For inputs given outside the table's configuration (on the command line:
    a number density, a format's options), so that the files written record
    them.

    Parameters
    ----------
    table : Table
    note : str, optional
        A line added to the provenance's notes.
    **inputs
        JSON-serializable values added to (or replacing) ``provenance.inputs``.

    Returns
    -------
    Table
    """
    prov = table.provenance
    notes = prov.notes if note is None else (*prov.notes, note)
    return table.replace(provenance=replace(prov, inputs={**prov.inputs, **inputs}, notes=notes))


def prepare_export(
    table: Table,
    formats: Sequence[str],
    *,
    options: FormatOptions | None = None,
    optical_depth: float | None = None,
    reference_wavelength_nm: float = 550.0,
    scale_height_m: float | None = None,
    top_altitude_m: float | None = None,
    n_altitudes: int | None = None,
) -> tuple[Table, FormatOptions]:
    """The table and format options for writing ``table`` in ``formats``.

    With ``"cosmoscout"`` among the formats, the constituent's density is an
    exponential profile (:class:`~dustoptics.io.csv.cosmoscout.ProfileOptions`,
    recorded in the CosmoScout files' provenance).  An ``optical_depth`` sets the
    table's number density (:func:`~dustoptics.atmosphere.sets.with_optical_depth`,
    recorded in its provenance) for the profile of the formats that write one:
    cosmoscout's, or the radiative-transfer formats' (``disort``, ``libradtran``,
    ``libradtran-nc``: :class:`~dustoptics.io.rt.profile.RTProfileOptions`); both
    kinds together must describe the same column.  Without such a format, the profile
    parameters and the optical depth are not used.

    Parameters
    ----------
    table : Table
    formats : sequence of str
        Names of :data:`dustoptics.io.FORMATS`.
    options : FormatOptions, optional
        The formats' options (default none).
    optical_depth : float, optional
        Vertical optical depth at ``reference_wavelength_nm`` that sets the number
        density, > 0. [-]
    reference_wavelength_nm : float, optional
        Wavelength of ``optical_depth``, within the table's.  Default 550. [nm]
    scale_height_m, top_altitude_m, n_altitudes : optional
        cosmoscout: the profile (:class:`~dustoptics.io.csv.cosmoscout.ProfileOptions`;
        None: the value in ``options``, or the default). [m], [m], [-]

    Returns
    -------
    table : Table
        The table, with its number density set when ``optical_depth`` is given.
    options : FormatOptions
        ``options`` with the profile's parameters for cosmoscout.

    Raises
    ------
    ValueError
        cosmoscout without a number density (neither the table's nor an
        ``optical_depth``), profile parameters out of range, or an optical depth for
        cosmoscout and a radiative-transfer format whose profiles differ.
    """
    options = FormatOptions() if options is None else options
    rt = [name for name in formats if FORMATS[name].options is RTProfileOptions]
    if "cosmoscout" not in formats and not (rt and optical_depth is not None):
        return table, options
    given = {
        "scale_height_m": scale_height_m,
        "top_altitude_m": top_altitude_m,
        "n_altitudes": n_altitudes,
    }
    options = options.replace(**{k: v for k, v in given.items() if v is not None})
    column: tuple[Any, float] | None = None
    if rt:
        rt_options = FORMATS[rt[0]].make_options(options.values)
        column = rt_options.column()
    if "cosmoscout" in formats:
        profile = ProfileOptions(**{k: v for k, v in options.values.items() if k in given})
        if column is not None and optical_depth is not None:
            _same_column(column, profile, rt)
        column = (profile.profile, profile.top_altitude_m)
    if optical_depth is not None and column is not None:
        table = with_optical_depth(
            table,
            optical_depth=optical_depth,
            reference_wavelength_nm=reference_wavelength_nm,
            profile=column[0],
            top_altitude_m=column[1],
        )
    if "cosmoscout" in formats:
        if table.cross_sections is None or table.cross_sections.number_density_per_m3 is None:
            raise ValueError(
                "the cosmoscout format needs a number density for beta [m^-1]: give "
                "optical_depth or a table with number_density_per_m3"
            )
        profile.check(table.wavelength_nm)
    return table, options


def _same_column(column: tuple[Any, float], profile: ProfileOptions, rt: Sequence[str]) -> None:
    """One optical depth gives one number density only if both profiles hold the same column."""
    rt_length = column[0].column_length_m(top_altitude_m=column[1])
    cs_length = profile.profile.column_length_m(top_altitude_m=profile.top_altitude_m)
    if abs(rt_length - cs_length) > 1e-9 * cs_length:
        raise ValueError(
            f"an optical depth sets one number density, but the cosmoscout profile (exponential, "
            f"scale height {profile.scale_height_m:g} m, top {profile.top_altitude_m:g} m: column "
            f"{cs_length:g} m) and the profile of {', '.join(rt)} (column {rt_length:g} m) "
            "differ: give --scale-height-m (and --top-altitude-m) so that both share one, or "
            "write them separately"
        )


def write_formats(
    table: Table,
    out_dir: str | os.PathLike[str],
    formats: Sequence[str],
    *,
    overwrite: bool = False,
    options: FormatOptions | None = None,
    root: str | os.PathLike[str] | None = None,
) -> list[Path]:
    """Write a table into a directory in several formats, as one set.

    The options that change a format's numbers
    (:meth:`~dustoptics.io.registry.FormatOptions.recorded`) are added to
    the provenance inputs of the table that format's writer gets, under
    ``"export"``: the files record them, and their input hash changes with
    them.  The set is written whole or not at all
    (:func:`dustoptics.io._atomic.file_set`).

    Parameters
    ----------
    table : Table
    out_dir : path-like
        Directory the files go into.
    formats : sequence of str
        Names of :data:`dustoptics.io.FORMATS`.
    overwrite : bool, optional
        Replace existing files.  Default False.
    options : FormatOptions, optional
        The formats' options; default none (each writer's defaults).
    root : path-like, optional
        Directory every file must stay inside; default ``out_dir``.

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    ValueError
        An unknown format, or options a format rejects.
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).
    """
    if options is None:
        options = FormatOptions()
    out = Path(out_dir)
    written: list[Path] = []
    # One set: every format is prepared, then all are moved into place together.
    with file_set(root if root is not None else out, overwrite=overwrite):
        for name in formats:
            recorded = options.recorded(name)
            table_for_format = (
                with_inputs(table, export={"format": name, **recorded}) if recorded else table
            )
            written.extend(
                write(
                    table_for_format,
                    out,
                    format=name,
                    overwrite=overwrite,
                    **options.for_format(name),
                )
            )
    return written


@dataclass(frozen=True)
class Placement:
    """What :func:`place_outputs` did: files written, and files left as they were.

    Attributes
    ----------
    written : tuple of pathlib.Path
        Files written (new, or replaced with ``force``).
    unchanged : tuple of pathlib.Path
        Files that already held the same bytes or content, left untouched.
    """

    written: tuple[Path, ...]
    unchanged: tuple[Path, ...]


def place_outputs(
    render: Callable[[Path], Sequence[Path]],
    out_dir: str | os.PathLike[str],
    *,
    force: bool,
    same: Callable[[Path, Path], bool] | None = None,
) -> Placement:
    """Write the files a function renders into a directory, beside the files there.

    ``render`` writes into an empty temporary directory; each of its files is
    then compared with the file of the same name in ``out_dir``:

    - none there: the file is written;
    - the same bytes, or the same content by ``same`` (``dustoptics build``:
      an HDF5 file that holds the same table, same inputs and grids, numbers
      equal to 1e-9 relative, only the recorded software versions differ):
      the existing file is left untouched ("up to date");
    - anything else: replaced with ``force``, otherwise :class:`FileExistsError`
      naming every such file, before anything is written.

    The new files appear together or not at all (:mod:`dustoptics.io._atomic`).
    The comparison is made holding ``out_dir``'s lock, after a write that was
    interrupted there has been completed, so it sees the files as they are
    when the new ones are moved in.  Other files in ``out_dir`` are left alone.

    Parameters
    ----------
    render : callable
        ``render(directory) -> paths``: writes the files into ``directory``
        (subdirectories allowed) and returns their paths.
    out_dir : path-like
        Where the files go.
    force : bool
        Replace existing files that differ.
    same : callable, optional
        ``same(existing, new) -> bool``: whether an existing file and the new
        one of the same name hold the same content although their bytes
        differ; default: only the same bytes are the same.

    Returns
    -------
    Placement

    Raises
    ------
    FileExistsError
        Files exist and differ, and ``force`` is False (nothing is written).
    """
    out = Path(out_dir)
    unchanged: list[Path] = []

    def select(targets: list[Path]) -> list[Path]:
        # Under out's lock, after an interrupted write there was completed: compare with
        # what is there now, not with what was there before the lock.
        keep: list[Path] = []
        conflicts: list[Path] = []
        given = {Path(os.path.abspath(t)): t for t in rendered}
        for target in targets:
            if target.is_file():
                new = rendered[given[target]]
                if target.read_bytes() == new.read_bytes() or (
                    same is not None and same(target, new)
                ):
                    unchanged.append(given[target])
                    continue
                conflicts.append(given[target])
            keep.append(target)
        if conflicts and not force:
            raise FileExistsError(
                "these files exist and differ from the new ones; use --force to replace them: "
                + ", ".join(repr(str(c)) for c in conflicts)
            )
        return keep

    with tempfile.TemporaryDirectory(prefix="dustoptics-") as tmp:
        staging = Path(tmp).resolve()
        rendered: dict[Path, Path] = {}
        # A private directory, read back below: the write into out is the durable one.
        with scratch(staging):
            paths = render(staging)
        for path in paths:
            rendered[out / Path(path).resolve().relative_to(staging)] = Path(path)
        contents: dict[Path, bytes] = {t: p.read_bytes() for t, p in rendered.items()}
        if _all_up_to_date(out, rendered, same):
            # Nothing to write: no staging directory, no lock (a read-only folder of the
            # same files is up to date).  Each file is replaced only whole (os.replace), so
            # files that all hold the new content are one set even while a writer runs.
            return Placement(written=(), unchanged=tuple(rendered))
        written = _commit(contents, overwrite=force, root=out, select=select)
    return Placement(written=tuple(written), unchanged=tuple(unchanged))


def _all_up_to_date(
    out: Path, rendered: Mapping[Path, Path], same: Callable[[Path, Path], bool] | None
) -> bool:
    """Whether every target already holds its new file's bytes (or content, by ``same``), and
    no interrupted write is left in ``out`` (which the next write must settle first)."""
    with contextlib.suppress(OSError):
        if any(e.name.startswith(STAGE_PREFIX) for e in out.iterdir()):
            return False
    for target, new in rendered.items():
        if not target.is_file() or target.is_symlink():
            return False
        if target.read_bytes() != new.read_bytes() and not (same is not None and same(target, new)):
            return False
    return True


def place_table(
    table: Table,
    out: str | os.PathLike[str],
    formats: Sequence[str],
    *,
    options: FormatOptions | None = None,
    force: bool = False,
    same: Callable[[Path, Path], bool] | None = None,
) -> Placement:
    """Write a table in several formats into ``out/NAME/``, as ``dustoptics build`` does.

    :func:`write_formats` renders the files, :func:`place_outputs` places
    them: files that already hold the same bytes (or the same content, by
    ``same``) are left untouched.

    Parameters
    ----------
    table : Table
        Its name (a plain file name) names the directory.
    out : path-like
        The output directory; the files go into ``out/<table.name>/``.
    formats : sequence of str
        Names of :data:`dustoptics.io.FORMATS`.
    options : FormatOptions, optional
        The formats' options (:func:`prepare_export`).
    force : bool, optional
        Replace existing files that differ.  Default False.
    same : callable, optional
        See :func:`place_outputs`.

    Returns
    -------
    Placement

    Raises
    ------
    ValueError
        The table's name is not a plain file name, or leads outside ``out``
        (a symbolic link); an unknown format or an option a format rejects.
    FileExistsError
        Files exist and differ, and ``force`` is False (nothing is written).
    """
    # The name may come from a file: it must not choose where files go.
    out_dir = Path(out) / check_file_name("name", table.name)
    check_inside(out, out_dir)
    return place_outputs(
        lambda directory: write_formats(
            table, directory, formats, overwrite=False, options=options
        ),
        out_dir,
        force=force,
        same=same,
    )


def write_atmosphere_set(
    atmosphere: Atmosphere,
    directory: str | os.PathLike[str],
    *,
    inputs: Mapping[str, Any],
    bruneton: bool = False,
    overwrite: bool = False,
    final_directory: str | os.PathLike[str] | None = None,
) -> list[Path]:
    """Write a set's files into a directory: CosmoScout VR's, Bruneton's, its provenance.

    Parameters
    ----------
    atmosphere : Atmosphere
    directory : path-like
        Output directory (created if missing).
    inputs : mapping
        What made the set (:func:`~dustoptics.atmosphere.build.set_inputs`),
        recorded in ``<name>_provenance.json``
        (:func:`~dustoptics.atmosphere.build.set_provenance`).
    bruneton : bool, optional
        Also Bruneton's model parameters
        (:func:`dustoptics.io.engines.bruneton.write_bruneton`).  Default False.
    overwrite : bool, optional
        Replace existing files.  Default False.
    final_directory : path-like, optional
        Where the files will stand when ``directory`` is a staging folder
        (:func:`place_outputs` renders into one): CosmoScout's settings name the
        CSV files by their absolute paths there.  Default: ``directory``.

    Returns
    -------
    list of pathlib.Path
        CosmoScout VR's CSV files and settings, Bruneton's files, the record.

    Raises
    ------
    FileExistsError
        A file exists and ``overwrite`` is False.
    """
    record = set_provenance(atmosphere, inputs)
    # The settings name the CSV files where they will stand, not in a staging folder.
    final = Path(final_directory if final_directory is not None else directory).resolve()
    written = write_atmosphere(
        atmosphere, directory, overwrite=overwrite, path_prefix=f"{final.as_posix()}/"
    )
    if bruneton:
        written += write_bruneton(atmosphere, directory, overwrite=overwrite)
    path = Path(directory) / f"{atmosphere.name}{SET_PROVENANCE_SUFFIX}"
    return written + write_files({path: record.encode("utf-8")}, overwrite=overwrite)
