"""HDF5 tables: self-describing, compressed, netCDF-4 compatible, with provenance.

:func:`write_hdf5` stores a :class:`~dustoptics.table.Table` in one HDF5 file
laid out as netCDF-4 lays out its data, so that ``h5dump``, ``h5py``,
``netCDF4`` and ``xarray.open_dataset(path, engine="h5netcdf")`` all read it as
labelled data:

Dimensions (HDF5 dimension scales, named after their coordinate variables)
    ``wavelength_nm`` (n_wavelength) [nm] and ``theta_deg`` (n_theta) [deg].
Stored variables (read back by :func:`read_hdf5`)
    ``phase`` (wavelength_nm, theta_deg) [sr^-1], gzip-compressed with the
    shuffle filter; ``g`` [1]; ``cext_um2`` and ``csca_um2`` [um^2] (tables
    with cross-sections); ``error_estimate`` and
    ``cross_section_error_estimate`` [1] (when known); the scalars
    ``mean_geometric_cross_section_um2`` [um^2] and ``number_density_per_m3``
    [m^-3] (when known).
Derived variables (written for convenience, verified on reading)
    ``cabs_um2``, ``ssa``, ``qext``, ``qsca``, ``qabs`` and, when the table has
    a number density, ``beta_ext_per_m``, ``beta_sca_per_m``,
    ``beta_abs_per_m`` [m^-1].  Each carries ``derived_from``, the formula.
    The reader recomputes them from the stored variables and refuses a file
    in which they disagree (a file edited by hand in one place only).
Every variable
    has the attributes ``units`` and ``long_name`` from
    :data:`dustoptics.table.UNITS`.
Root attributes
    ``title``, ``Conventions`` (``"dustoptics-table-1"``),
    ``format_description``, ``name``, ``phase_normalization``, ``input_hash``,
    ``provenance`` (the canonical JSON of
    :meth:`~dustoptics.table.Provenance.to_dict`: inputs, sources with
    citations, software versions, quadrature settings and achieved error,
    notes) and ``software`` (JSON of the versions).

All values are float64, so :func:`read_hdf5` returns the written numbers bit
for bit.  The file's bytes depend only on the table: no object timestamps
(``track_times=False``), a fixed file-format version (``libver``) and a fixed
creation order, so writing the same table twice gives byte-identical files.
Writes are atomic (:mod:`dustoptics.io._atomic`).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io import register_format
from dustoptics.io._atomic import FormatError, write_files
from dustoptics.table import (
    PHASE_NORMALIZATION,
    UNITS,
    Provenance,
    Table,
    canonical_json,
)

__all__ = ["CONVENTIONS", "DERIVED", "HDF5_SUFFIX", "read_hdf5", "write_hdf5", "write_hdf5_files"]

#: File-name suffix of :func:`write_hdf5_files`.
HDF5_SUFFIX = ".h5"

#: Value of the root ``Conventions`` attribute; the reader requires it.
CONVENTIONS = "dustoptics-table-1"

FORMAT_DESCRIPTION = (
    "dustoptics optical table, layout dustoptics-table-1: netCDF-4 compatible HDF5 "
    "(dimension scales wavelength_nm and theta_deg, units and long_name attributes on every "
    "variable, provenance as a JSON string attribute); derived variables carry derived_from "
    "and are recomputed from the stored ones when read"
)

#: Derived variables: name -> formula (recorded as the ``derived_from`` attribute).
DERIVED: dict[str, str] = {
    "cabs_um2": "cext_um2 - csca_um2",
    "ssa": "csca_um2 / cext_um2",
    "qext": "cext_um2 / mean_geometric_cross_section_um2",
    "qsca": "csca_um2 / mean_geometric_cross_section_um2",
    "qabs": "cabs_um2 / mean_geometric_cross_section_um2",
    "beta_ext_per_m": "number_density_per_m3 * cext_um2 * 1e-12",
    "beta_sca_per_m": "number_density_per_m3 * csca_um2 * 1e-12",
    "beta_abs_per_m": "number_density_per_m3 * cabs_um2 * 1e-12",
}

_PER_WAVELENGTH = ("g", "cext_um2", "csca_um2", "error_estimate", "cross_section_error_estimate")
_SCALARS = ("mean_geometric_cross_section_um2", "number_density_per_m3")
_COUNTS = ("n_nodes", "cross_section_n_nodes")
_DIMS = ("wavelength_nm", "theta_deg")
_FILE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
#: Largest number of float64 values per chunk of ``phase`` (1 MiB).
_CHUNK_VALUES = 1 << 17
_GZIP_LEVEL = 6
#: HDF5 file-format versions: fixed so the bytes do not depend on the library's default.
_LIBVER = ("v110", "v110")


def _h5py() -> Any:
    try:
        import h5py
    except ImportError:  # pragma: no cover - h5py is a core dependency
        raise ImportError("HDF5 export needs h5py: python3 -m pip install h5py") from None
    return h5py


def _attrs(dataset: Any, key: str) -> None:
    unit, meaning = UNITS[key]
    dataset.attrs["units"] = unit
    dataset.attrs["long_name"] = meaning
    if key in DERIVED:
        dataset.attrs["derived_from"] = DERIVED[key]


def _derived_values(table: Table) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    if not table.has_cross_sections:
        return out
    out["cabs_um2"] = table.cabs_um2
    out["ssa"] = table.ssa
    if table.mean_geometric_cross_section_um2 is not None:
        out["qext"], out["qsca"], out["qabs"] = table.qext, table.qsca, table.qabs
    if table.number_density_per_m3 is not None:
        out["beta_ext_per_m"] = table.beta_ext_per_m
        out["beta_sca_per_m"] = table.beta_sca_per_m
        out["beta_abs_per_m"] = table.beta_abs_per_m
    return out


def _writer(table: Table) -> Callable[[Path], None]:
    h5py = _h5py()

    def write(path: Path) -> None:
        with h5py.File(path, "w", libver=_LIBVER, track_order=True) as f:
            f.attrs["title"] = f"dustoptics optical table {table.name!r}"
            f.attrs["Conventions"] = CONVENTIONS
            f.attrs["format_description"] = FORMAT_DESCRIPTION
            f.attrs["name"] = table.name
            f.attrs["phase_normalization"] = PHASE_NORMALIZATION
            f.attrs["input_hash"] = table.provenance.input_hash
            f.attrs["provenance"] = canonical_json(table.provenance.to_dict())
            f.attrs["software"] = canonical_json(dict(table.provenance.software))

            def dataset(key: str, data: Any, **options: Any) -> Any:
                ds = f.create_dataset(
                    key, data=np.asarray(data, dtype="<f8"), track_times=False, **options
                )
                _attrs(ds, key)
                return ds

            scales = {key: dataset(key, getattr(table, key)) for key in _DIMS}
            for key, scale in scales.items():
                scale.make_scale(key)
            n_wl, n_theta = table.phase.shape
            chunks = (max(1, min(n_wl, _CHUNK_VALUES // n_theta)), n_theta)
            phase = dataset(
                "phase", table.phase, chunks=chunks, compression="gzip",
                compression_opts=_GZIP_LEVEL, shuffle=True,
            )  # fmt: skip
            phase.dims[0].attach_scale(scales["wavelength_nm"])
            phase.dims[1].attach_scale(scales["theta_deg"])
            per_wavelength = {key: getattr(table, key) for key in _PER_WAVELENGTH}
            if table.refractive_index is not None:
                per_wavelength["refractive_index_real"] = table.refractive_index.real
                per_wavelength["refractive_index_imag"] = table.refractive_index.imag
            per_wavelength.update(_derived_values(table))
            for key, values in per_wavelength.items():
                if values is not None:
                    dataset(key, values).dims[0].attach_scale(scales["wavelength_nm"])
            for key in _COUNTS:
                values = getattr(table, key)
                if values is not None:
                    ds = f.create_dataset(
                        key, data=np.asarray(values, dtype="<i8"), track_times=False
                    )
                    _attrs(ds, key)
                    ds.dims[0].attach_scale(scales["wavelength_nm"])
            for key in _SCALARS:
                value = getattr(table, key)
                if value is not None:
                    dataset(key, value)

    return write


def write_hdf5(table: Table, path: str | os.PathLike[str], *, overwrite: bool = False) -> Path:
    """Write a table to one netCDF-4 compatible HDF5 file.

    Parameters
    ----------
    table : Table
        The table to write.
    path : path-like
        Output file (conventionally ``.h5`` or ``.nc``); missing directories
        are created.
    overwrite : bool, optional
        Replace an existing file.  Default False.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False (nothing is written).
    OSError
        Writing failed; no partial file is left behind.

    Examples
    --------
    >>> import dustoptics as do
    >>> from dustoptics.table import Table
    >>> from dustoptics.io.hdf5 import write_hdf5, read_hdf5
    >>> t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0], name="demo")
    >>> read_hdf5(write_hdf5(t, "demo.h5")).equals(t)      # doctest: +SKIP
    True
    """
    if not isinstance(table, Table):
        raise TypeError(f"table must be a dustoptics.table.Table; got {type(table).__name__}")
    target = Path(path)
    return write_files({target: _writer(table)}, overwrite=overwrite)[0]


def write_hdf5_files(
    table: Table, out_dir: str | os.PathLike[str], *, overwrite: bool = False
) -> list[Path]:
    """Write ``<out_dir>/<table.name>.h5`` (the ``"hdf5"`` entry of :data:`dustoptics.io.FORMATS`).

    Parameters
    ----------
    table : Table
        The table; its name must be usable as a file name (letters, digits,
        ``.``, ``_``, ``-``).
    out_dir : path-like
        Output directory; created if missing.
    overwrite : bool, optional
        Replace an existing file.  Default False.

    Returns
    -------
    list of pathlib.Path
        The one written file.
    """
    if not isinstance(table, Table):
        raise TypeError(f"table must be a dustoptics.table.Table; got {type(table).__name__}")
    if not _FILE_NAME.fullmatch(table.name):
        raise ValueError(
            f"table name {table.name!r} is not usable as a file name (letters, digits, '.', '_', '-'); "
            "use write_hdf5 with an explicit path"
        )
    return [write_hdf5(table, Path(out_dir) / (table.name + HDF5_SUFFIX), overwrite=overwrite)]


register_format("hdf5", write_hdf5_files)


# ------------------------------------------------------------------ reading


def _read_attr(path: Path, f: Any, key: str) -> str:
    if key not in f.attrs:
        raise FormatError(f"{path}: missing root attribute {key!r}")
    value = f.attrs[key]
    if isinstance(value, bytes):
        value = value.decode("utf-8")
    if not isinstance(value, str):
        raise FormatError(f"{path}: root attribute {key!r} must be a string; got {value!r}")
    return value


def _read_array(
    path: Path, f: Any, key: str, shape: tuple[int, ...] | None, *, required: bool, kind: str = "f"
) -> Any:
    h5py = _h5py()
    if key not in f:
        if required:
            raise FormatError(f"{path}: missing variable {key!r}")
        return None
    obj = f[key]
    if not isinstance(obj, h5py.Dataset):
        raise FormatError(f"{path}: {key!r} is not a dataset")
    if obj.dtype.kind != kind:
        wanted = "floats" if kind == "f" else "integers"
        raise FormatError(f"{path}: variable {key!r} must hold {wanted}; got dtype {obj.dtype}")
    if shape is not None and obj.shape != shape:
        raise FormatError(f"{path}: variable {key!r} has shape {obj.shape}; expected {shape}")
    try:
        data = obj[()]
    except (OSError, RuntimeError) as exc:
        raise FormatError(
            f"{path}: variable {key!r} cannot be read (damaged or truncated?): {exc}"
        ) from None
    return np.asarray(data, dtype=np.float64 if kind == "f" else np.int64)


def _check_derived(path: Path, f: Any, table: Table) -> None:
    expected = _derived_values(table)
    for key, formula in DERIVED.items():
        if key not in f:
            continue
        if key not in expected:
            raise FormatError(
                f"{path}: variable {key!r} ({formula}) is present but the stored variables "
                "it derives from are not"
            )
        values = _read_array(path, f, key, expected[key].shape, required=True)
        if not np.array_equal(values, expected[key]):
            i = int(np.argmax(values != expected[key]))
            raise FormatError(
                f"{path}: derived variable {key!r} disagrees with {formula} at wavelength "
                f"{float(table.wavelength_nm[i])!r} nm: file {float(values[i])!r}, recomputed {float(expected[key][i])!r}"
            )


def read_hdf5(path: str | os.PathLike[str]) -> Table:
    """Read a table written by :func:`write_hdf5`.

    Parameters
    ----------
    path : path-like
        The HDF5 file.

    Returns
    -------
    Table
        The table as written, bit for bit, with its provenance (whose input
        hash is checked against its inputs).

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    FormatError
        Not an HDF5 file, truncated or damaged, not a ``dustoptics-table-1``
        file, a variable missing or of the wrong shape, a derived variable
        that disagrees with the stored ones, or a provenance record that does
        not match its input hash; the message names the file and the problem.
    """
    path = Path(path)
    h5py = _h5py()
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if not path.is_file():
        raise FormatError(f"{path}: not a regular file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise FormatError(
            f"{path}: not a readable HDF5 file (truncated or another format?): {exc}"
        ) from None
    try:
        with f:
            conventions = _read_attr(path, f, "Conventions")
            if conventions != CONVENTIONS:
                raise FormatError(
                    f"{path}: Conventions is {conventions!r}; this reader reads {CONVENTIONS!r}"
                )
            name = _read_attr(path, f, "name")
            try:
                provenance = Provenance.from_dict(json.loads(_read_attr(path, f, "provenance")))
            except ValueError as exc:  # json.JSONDecodeError is a ValueError
                raise FormatError(f"{path}: root attribute 'provenance': {exc}") from None
            wavelength = _read_array(path, f, "wavelength_nm", None, required=True)
            theta = _read_array(path, f, "theta_deg", None, required=True)
            if wavelength.ndim != 1 or theta.ndim != 1:
                raise FormatError(f"{path}: wavelength_nm and theta_deg must be 1-D")
            n_wl = (wavelength.size,)
            fields: dict[str, Any] = {
                "phase": _read_array(
                    path, f, "phase", (wavelength.size, theta.size), required=True
                ),
                "g": _read_array(path, f, "g", n_wl, required=True),
            }
            for key in _PER_WAVELENGTH[1:]:
                fields[key] = _read_array(path, f, key, n_wl, required=False)
            for key in _COUNTS:
                fields[key] = _read_array(path, f, key, n_wl, required=False, kind="i")
            n = _read_array(path, f, "refractive_index_real", n_wl, required=False)
            k = _read_array(path, f, "refractive_index_imag", n_wl, required=False)
            if (n is None) != (k is None):
                raise FormatError(
                    f"{path}: refractive_index_real and _imag must both be present or neither"
                )
            fields["refractive_index"] = None if n is None or k is None else n + 1j * k
            for key in _SCALARS:
                value = _read_array(path, f, key, (), required=False)
                fields[key] = None if value is None else float(value)
            try:
                table = Table(
                    name=name,
                    wavelength_nm=wavelength,
                    theta_deg=theta,
                    provenance=provenance,
                    **fields,
                )
            except ValueError as exc:
                raise FormatError(f"{path}: {exc}") from None
            _check_derived(path, f, table)
    except FormatError:
        raise
    except (OSError, RuntimeError, KeyError) as exc:
        raise FormatError(f"{path}: damaged HDF5 file ({type(exc).__name__}: {exc})") from None
    return table
