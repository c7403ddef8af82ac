"""Table files: CF-1.10 netCDF-4 (``.nc``, also written as ``.h5``), verified when read.

:func:`write_netcdf` stores a :class:`~dustoptics.table.Table` in one netCDF-4
file: the :meth:`~dustoptics.table.Table.to_xarray` dataset (assembled without xarray,
:func:`~dustoptics.table.conversion.dataset_variables`), variable for
variable and attribute for attribute, so that ``xarray.open_dataset``,
``netCDF4``, ``ncdump``, ``h5py`` and ``h5dump`` all read it as labelled data
and :func:`read_netcdf` (:func:`dustoptics.open_table`) returns the table bit
for bit.

Layout (schema :data:`dustoptics.table.SCHEMA`)
    Dimensions and coordinate variables ``wavelength_nm`` [nm] and
    ``theta_deg`` [degree] (HDF5 dimension scales, as netCDF-4 stores them);
    ``phase`` (wavelength_nm, theta_deg) [sr-1], gzip-compressed with the
    shuffle filter; per wavelength ``g``, the cross-sections [um2], error
    estimates, node counts (64-bit integers), the refractive index's real and
    imaginary parts, and the derived quantities (``cabs_um2``, ``ssa``,
    ``qext``, ..., ``beta_ext_per_m`` [m-1], each with ``derived_from``);
    the scalars ``mean_geometric_cross_section_um2`` [um2] and
    ``number_density_per_m3`` [m-3].  Every variable has ``units`` (udunits2)
    and ``long_name``, and ``standard_name`` where the CF standard-name table
    has one (aerosol names only for tables of particles).
Global attributes
    ``Conventions = "CF-1.10"``, ``dustoptics_schema``, ``title``,
    ``institution``, ``source``, ``history``, ``references``, ``comment``,
    ``name``, ``phase_normalization``, ``input_hash``, ``provenance`` (JSON)
    and ``data_sha256``, the digest below.

Why h5py and not the netCDF4 or h5netcdf library
    netCDF-4 files are HDF5 files laid out by conventions (dimension scales,
    attributes), and h5py, a core dependency already, writes that layout with
    full control of what makes the bytes reproducible: no object timestamps
    (``track_times=False``), a fixed HDF5 file-format version (``libver``), a
    fixed creation order.  Neither library would add a capability the table
    needs, and both would add a run-time dependency (netCDF4 a C library).
    The tests prove the files against the real readers: netCDF4 (netCDF-C),
    xarray with h5netcdf, and the IOOS compliance checker for CF-1.10.

Integrity
    Every array is stored with HDF5's Fletcher-32 checksum filter, and
    ``data_sha256`` is the SHA-256 of every variable's name, type, shape,
    little-endian bytes and attributes and of the other global attributes
    (:func:`dataset_digest`), so a flipped bit anywhere in the data or the
    metadata is an error when read, never a changed number.

Readers verify what the writer guarantees
    :func:`read_netcdf` refuses, with :class:`~dustoptics.io.FormatError`
    naming the file and the problem: a missing, empty, truncated or
    non-HDF5 file, a directory; another netCDF file (no ``dustoptics_schema``)
    or an older layout; groups, soft or external links, external raw storage
    and virtual datasets (a crafted file cannot make the reader read other
    files); variables of unknown name, wrong type, shape or units; more than
    :data:`MAX_VALUES` values in a variable, filters other than deflate,
    shuffle and Fletcher-32, or more data than the bytes stored can hold
    (missing chunks, or more than deflate's limit of about 1032:1; all
    checked from the metadata, before anything is allocated or decompressed,
    so the memory a file can ask for is bounded by its size); a digest that
    does not match; values the
    :class:`~dustoptics.table.Table` refuses (non-finite, negative, ...);
    derived variables that disagree with the stored ones; and a phase
    function whose sphere integral is not 1 within what its angle grid
    resolves (:func:`check_normalization`).

Writes are atomic (:mod:`dustoptics.io._atomic`) and byte reproducible.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import FormatError, write_files
from dustoptics.io.registry import Format, register
from dustoptics.scattering.tabulated_phase import sphere_integral
from dustoptics.table import Table, canonical_json, register_table_writer
from dustoptics.table.conversion import Variable, dataset_variables
from dustoptics.table.schema import (
    ANGLE_DIM,
    DERIVATIVE_FIELDS,
    DERIVED,
    DERIVED_DERIVATIVES,
    EXPANSION_FIELDS,
    MATRIX_FIELDS,
    ORDER_DIM,
    PARAMETER_DIM,
    SCALAR_FIELDS,
    SCHEMA,
    UNITS,
    WAVELENGTH_DIM,
    derivative_variable,
)

__all__ = [
    "MAX_VALUES",
    "SUFFIXES",
    "check_normalization",
    "dataset_digest",
    "open_table",
    "read_hdf5",
    "read_netcdf",
    "save_table",
    "write_hdf5",
    "write_netcdf",
]

#: File suffixes of table files (all the same CF-1.10 netCDF-4 format); ``.nc`` first, the default.
SUFFIXES = (".nc", ".h5", ".hdf5", ".nc4")

#: Most values a reader accepts in one variable (2^25, 256 MiB of float64):
#: 100 times the default 48 x 1,801 table, far below what would exhaust memory.
MAX_VALUES = 1 << 25

#: Global attribute that holds :func:`dataset_digest`.
DIGEST_ATTRIBUTE = "data_sha256"

_FILE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
#: Largest number of float64 values per chunk of ``phase`` (1 MiB).
_CHUNK_VALUES = 1 << 17
_GZIP_LEVEL = 6
#: HDF5 file-format versions: fixed so the bytes do not depend on the library's default.
_LIBVER = ("v110", "v110")
#: HDF5's own attributes of dimension scales, not part of the netCDF data model.
_HDF5_ATTRIBUTES = frozenset({"CLASS", "NAME", "DIMENSION_LIST", "REFERENCE_LIST", "_Netcdf4Dimid"})
#: Most bytes deflate can expand one stored byte to (its format's limit is about 1032:1).
_MAX_DEFLATE_RATIO = 1100
_SCALARS = SCALAR_FIELDS
_INTEGERS = ("n_nodes", "cross_section_n_nodes", PARAMETER_DIM)
#: Attributes of the ``parameter`` dimension scale that hold the parameters'
#: names and units (JSON lists): HDF5 dimension scales here hold numbers only.
_PARAMETER_NAMES = "parameter_names"
_PARAMETER_UNITS = "parameter_units"
#: Angular quantities (their derivatives have dimensions parameter, wavelength, angle).
_ANGULAR = ("phase", *MATRIX_FIELDS)


def _h5py() -> Any:
    import h5py  # here: h5py adds ~0.06 s to `import dustoptics` (python -X importtime)

    return h5py


# ------------------------------------------------------------------ digest


def dataset_digest(
    variables: Mapping[str, tuple[np.ndarray, Mapping[str, Any]]], attrs: Mapping[str, Any]
) -> str:
    """SHA-256 (hex) of a table dataset's variables and global attributes.

    Parameters
    ----------
    variables : mapping
        Variable name -> (values, attributes).
    attrs : mapping
        Global attributes (:data:`DIGEST_ATTRIBUTE` is left out).

    Returns
    -------
    str
        The digest of, for each variable in name order, its name, type,
        shape, little-endian bytes and canonical-JSON attributes, then the
        canonical JSON of the global attributes.
    """
    h = hashlib.sha256()
    for name in sorted(variables):
        values, var_attrs = variables[name]
        arr = np.asarray(values)
        little = arr.astype(arr.dtype.newbyteorder("<"), copy=False)
        h.update(
            canonical_json([name, little.dtype.str, list(arr.shape), dict(var_attrs)]).encode()
        )
        h.update(np.ascontiguousarray(little).data)  # the bytes, without a copy
    h.update(canonical_json({k: v for k, v in attrs.items() if k != DIGEST_ATTRIBUTE}).encode())
    return h.hexdigest()


def _file_variables(
    variables: Mapping[str, Variable],
) -> dict[str, tuple[np.ndarray, dict[str, Any]]]:
    """The dataset's variables as the file stores them: the ``parameter``
    coordinate of a table with derivatives becomes the indices 0, 1, ... with
    the names and units as JSON attributes."""
    out = {k: (values, dict(attrs)) for k, (_dims, values, attrs) in variables.items()}
    if PARAMETER_DIM in out:
        names, attrs = out.pop(PARAMETER_DIM)
        units, _ = out.pop("parameter_units")
        attrs[_PARAMETER_NAMES] = json.dumps([str(n) for n in names])
        attrs[_PARAMETER_UNITS] = json.dumps([str(u) for u in units])
        out[PARAMETER_DIM] = (np.arange(names.size, dtype=np.int64), attrs)
    return out


def _derivative_dims() -> dict[str, tuple[str, ...]]:
    """Dimensions of every derivative variable the schema defines."""
    dims: dict[str, tuple[str, ...]] = {}
    for key in (*DERIVATIVE_FIELDS, *DERIVED_DERIVATIVES):
        name = derivative_variable(key)
        dims[name] = (
            (PARAMETER_DIM, WAVELENGTH_DIM, ANGLE_DIM)
            if key in _ANGULAR
            else (PARAMETER_DIM, WAVELENGTH_DIM, ORDER_DIM)
            if key in EXPANSION_FIELDS
            else (PARAMETER_DIM, WAVELENGTH_DIM)
        )
        dims[f"{name}_error_estimate"] = (PARAMETER_DIM, WAVELENGTH_DIM)
    return dims


# ------------------------------------------------------------------ writing


def _writer(table: Table) -> Callable[[Path], None]:
    """A callback that writes the table's dataset to the (temporary) path it is given."""
    h5py = _h5py()
    data, coords = dataset_variables(table)
    variables = _file_variables({**data, **coords})
    attrs = dict(table.global_attributes())
    attrs[DIGEST_ATTRIBUTE] = dataset_digest(variables, attrs)

    def write(path: Path) -> None:
        with h5py.File(path, "w", libver=_LIBVER, track_order=True) as f:
            for key, value in attrs.items():
                f.attrs[key] = value

            def dataset(key: str, **options: Any) -> Any:
                values, var_attrs = variables[key]
                dtype = "<i8" if values.dtype.kind in "iu" else "<f8"
                if values.ndim:
                    # Fletcher-32 needs chunks; one chunk per row of at most 1 MiB.
                    options.setdefault("chunks", values.shape)
                    options["fletcher32"] = True
                obj = f.create_dataset(key, data=values.astype(dtype), track_times=False, **options)
                for name, value in var_attrs.items():
                    obj.attrs[name] = value
                return obj

            scales = {key: dataset(key) for key in (WAVELENGTH_DIM, ANGLE_DIM)}
            for key, scale in scales.items():
                scale.make_scale(key)
            n_wl, n_theta = table.phase.shape
            chunks = (max(1, min(n_wl, _CHUNK_VALUES // n_theta)), n_theta)
            phase = dataset(
                "phase",
                chunks=chunks,
                compression="gzip",
                compression_opts=_GZIP_LEVEL,
                shuffle=True,
            )
            phase.dims[0].attach_scale(scales[WAVELENGTH_DIM])
            phase.dims[1].attach_scale(scales[ANGLE_DIM])
            if ORDER_DIM in coords:
                scales[ORDER_DIM] = dataset(ORDER_DIM)
                scales[ORDER_DIM].make_scale(ORDER_DIM)
            if PARAMETER_DIM in coords:
                scales[PARAMETER_DIM] = dataset(PARAMETER_DIM)
                scales[PARAMETER_DIM].make_scale(PARAMETER_DIM)
            for key, (dims, _values, _attrs) in data.items():
                if key == "phase":
                    continue
                obj = dataset(key)
                for axis, dim in enumerate(dims):
                    obj.dims[axis].attach_scale(scales[dim])

    return write


def _check_table(table: Any) -> Table:
    if not isinstance(table, Table):
        raise TypeError(f"table must be a dustoptics.table.Table; got {type(table).__name__}")
    return table


def write_netcdf(table: Table, path: str | os.PathLike[str], *, overwrite: bool = False) -> Path:
    """Write a table to one CF-1.10 netCDF-4 file (any suffix; see :func:`save_table`).

    Parameters
    ----------
    table : Table
        The table to write.
    path : path-like
        Output file; missing directories are created.
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
    >>> t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0], name="demo")
    >>> do.open_table(write_netcdf(t, "demo.nc")).equals(t)  # doctest: +SKIP
    True
    """
    _check_table(table)
    target = Path(path)
    return write_files({target: _writer(table)}, overwrite=overwrite)[0]


#: The same writer under its older name: a netCDF-4 file is an HDF5 file.
write_hdf5 = write_netcdf


def save_table(table: Table, path: str | os.PathLike[str], *, overwrite: bool = False) -> Path:
    """:meth:`Table.save <dustoptics.table.Table.save>`: write ``path`` in the format of its suffix.

    A path without a suffix gets ``.nc``, the default format.

    Raises
    ------
    ValueError
        The suffix is not one of :data:`SUFFIXES` (nothing is written).
    FileExistsError, OSError
        As :func:`write_netcdf`; an unwritable place is an OSError naming the path.
    """
    _check_table(table)
    target = Path(path)
    if not target.suffix:
        target = target.with_name(target.name + SUFFIXES[0])
    if target.suffix.lower() not in SUFFIXES:
        raise ValueError(
            f"path {str(target)!r}: unknown table file suffix {target.suffix!r}; use one of "
            f"{', '.join(SUFFIXES)} (all CF-1.10 netCDF-4; .nc is the usual one). "
            "Renderer formats (CSV, GLSL, textures) are written by dustoptics.io"
        )
    try:
        return write_netcdf(table, target, overwrite=overwrite)
    except (FileExistsError, IsADirectoryError):
        raise
    except OSError as exc:
        raise OSError(
            exc.errno, f"{target}: cannot write the table there ({exc.strerror or exc})"
        ) from None


def _directory_writer(suffix: str) -> Callable[..., list[Path]]:
    def write(
        table: Table, out_dir: str | os.PathLike[str], *, overwrite: bool = False
    ) -> list[Path]:
        _check_table(table)
        if not _FILE_NAME.fullmatch(table.name):
            raise ValueError(
                f"table name {table.name!r} is not usable as a file name (letters, digits, '.', '_', '-'); "
                "use Table.save with an explicit path"
            )
        return [write_netcdf(table, Path(out_dir) / (table.name + suffix), overwrite=overwrite)]

    write.__doc__ = f"Write ``<out_dir>/<table.name>{suffix}`` (CF-1.10 netCDF-4)."
    return write


NETCDF = register(
    Format(
        name="netcdf",
        summary="NAME.nc: the table and its provenance, CF netCDF-4",
        write=_directory_writer(".nc"),
        suffixes=(".nc",),
        plain_name=True,
        inputs_file=lambda name: f"{name}.nc",
    )
)
HDF5 = register(
    Format(
        name="hdf5",
        summary="NAME.h5: the same file as netcdf, named .h5",
        write=_directory_writer(".h5"),
        suffixes=(".h5",),
        plain_name=True,
        inputs_file=lambda name: f"{name}.h5",
    )
)
register_table_writer(SUFFIXES, save_table)  # Table.save


# ------------------------------------------------------------------ reading


def check_normalization(table: Table) -> None:
    """Check that the phase function integrates to 1 over the sphere, within its grid's resolution.

    For a table whose angles span 0 to 180 degree (3 or more), I = 2 pi int P
    dmu of the phase function read by linear interpolation in angle (exactly,
    :func:`dustoptics.scattering.tabulated_phase.sphere_integral`) must satisfy
    ``|I - 1| <= 2 |I - I_2| + 1e-6``, where I_2 is the same integral on every
    other angle (endpoints kept): the interpolation error of I is about a
    third of ``|I - I_2|`` once the grid resolves the function (second-order
    convergence), and within half of it on the coarsest grids measured (19
    angles, Mie tables of r_eff 0.1-50 um).  A table scaled by a factor, or
    with a row of another function, fails.

    Raises
    ------
    ValueError
        The first wavelength that fails, with I and the tolerance.
    """
    theta = table.theta_deg
    if not table.spans_sphere or theta.size < 3:
        return
    every_other = np.r_[0 : theta.size - 1 : 2, theta.size - 1]
    full = np.atleast_1d(sphere_integral(table.phase, theta_deg=theta))
    coarse = np.atleast_1d(
        sphere_integral(table.phase[:, every_other], theta_deg=theta[every_other])
    )
    tolerance = 2.0 * np.abs(full - coarse) + 1e-6
    bad = np.abs(full - 1.0) > tolerance
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(
            f"phase function at {table.wavelength_nm[i]:g} nm integrates to {full[i]:.9g} over the sphere "
            f"(2 pi int P dmu), not 1 within what its {theta.size} angles resolve ({tolerance[i]:.2g})"
        )


def _string_attribute(path: Path, owner: Any, key: str, where: str) -> str:
    h5py = _h5py()
    aid = owner.attrs.get_id(key)
    if (
        aid.shape not in ((), None)
        or not isinstance(aid.dtype, np.dtype)
        or aid.dtype.kind not in "SOU"
    ):
        raise FormatError(f"{path}: {where} attribute {key!r} must be one string")
    if h5py.check_string_dtype(aid.dtype) is None:
        raise FormatError(f"{path}: {where} attribute {key!r} must be a string")
    value = owner.attrs[key]
    if isinstance(value, bytes):
        value = value.decode("utf-8")
    if not isinstance(value, str):
        raise FormatError(
            f"{path}: {where} attribute {key!r} must be a string; got {type(value).__name__}"
        )
    return value


def _expected_shapes(
    n_wl: int, n_theta: int, n_order: int, n_parameter: int = 0
) -> dict[str, tuple[int, ...]]:
    shapes: dict[str, tuple[int, ...]] = {
        WAVELENGTH_DIM: (n_wl,),
        ANGLE_DIM: (n_theta,),
        "phase": (n_wl, n_theta),
        ORDER_DIM: (n_order,),
        PARAMETER_DIM: (n_parameter,),
    }
    sizes = {
        PARAMETER_DIM: n_parameter,
        WAVELENGTH_DIM: n_wl,
        ANGLE_DIM: n_theta,
        ORDER_DIM: n_order,
    }
    for key, dims in _derivative_dims().items():
        shapes[key] = tuple(sizes[d] for d in dims)
    for key in MATRIX_FIELDS:
        shapes[key] = (n_wl, n_theta)
    for key in EXPANSION_FIELDS:
        shapes[key] = (n_wl, n_order)
    for key in UNITS:
        if key not in shapes:
            shapes[key] = () if key in _SCALARS else (n_wl,)
    return shapes


def _check_storage(path: Path, objects: Mapping[str, Any]) -> None:
    """Refuse, before a value is read, data that cannot come from the bytes stored.

    Each variable's filters must be HDF5's deflate, shuffle and Fletcher-32
    (what :func:`write_netcdf` uses); a variable without deflate must have all
    its bytes stored (no chunk left to the fill value), one with deflate at
    most :data:`_MAX_DEFLATE_RATIO` times its stored bytes (deflate's own
    limit); so the data a file declares is bounded by its size.
    """
    h5z = _h5py().h5z
    allowed = {h5z.FILTER_DEFLATE, h5z.FILTER_SHUFFLE, h5z.FILTER_FLETCHER32}
    declared_total = 0
    for key, obj in objects.items():
        plist = obj.id.get_create_plist()
        codes = [plist.get_filter(i)[0] for i in range(plist.get_nfilters())]
        unknown = [c for c in codes if c not in allowed]
        if unknown:
            raise FormatError(
                f"{path}: variable {key!r} uses HDF5 filter {unknown[0]}; table files use only "
                "deflate, shuffle and Fletcher-32"
            )
        declared = int(obj.size) * int(obj.dtype.itemsize)
        stored = int(obj.id.get_storage_size())
        limit = _MAX_DEFLATE_RATIO * stored if h5z.FILTER_DEFLATE in codes else stored
        if declared > limit:
            raise FormatError(
                f"{path}: variable {key!r} declares {declared} bytes of data but stores "
                f"{stored}, which cannot hold them (chunks missing, or a crafted file); refused "
                "before reading"
            )
        declared_total += declared
    size = path.stat().st_size
    if declared_total > _MAX_DEFLATE_RATIO * size:
        raise FormatError(
            f"{path}: declares {declared_total} bytes of data in a file of {size} bytes; refused "
            "before reading"
        )


def _open_checked(
    path: Path, f: Any, max_values: int = MAX_VALUES
) -> tuple[dict[str, tuple[np.ndarray, dict[str, Any]]], dict[str, str]]:
    """Variables and global attributes of an open file, after every structural check."""
    h5py = _h5py()
    attrs = {key: _string_attribute(path, f, key, "global") for key in f.attrs}
    schema = attrs.get("dustoptics_schema")
    if schema is None:
        if attrs.get("Conventions") == "dustoptics-table-1":
            raise FormatError(
                f"{path}: written in the older dustoptics-table-1 layout; this version reads {SCHEMA}: "
                "rebuild the table (dustoptics build NAME, or Table.save)"
            )
        raise FormatError(
            f"{path}: not a dustoptics table (no dustoptics_schema attribute; "
            f"Conventions {attrs.get('Conventions')!r}): another netCDF or HDF5 file?"
        )
    if schema != SCHEMA:
        raise FormatError(
            f"{path}: table schema {schema!r}; this version of dustoptics reads {SCHEMA!r}"
        )
    if not attrs.get("Conventions", "").startswith("CF-1.10"):
        raise FormatError(
            f"{path}: Conventions must start with 'CF-1.10'; got {attrs.get('Conventions')!r}"
        )
    if DIGEST_ATTRIBUTE not in attrs:
        raise FormatError(
            f"{path}: missing the {DIGEST_ATTRIBUTE} attribute (checksum of the data)"
        )
    # Structure: hard links to datasets only; no external or virtual storage.
    objects = {}
    for key in f:
        link = f.get(key, getlink=True)
        if not isinstance(link, h5py.HardLink):
            raise FormatError(
                f"{path}: {key!r} is a {type(link).__name__}; table files hold no links"
            )
        obj = f[key]
        if not isinstance(obj, h5py.Dataset):
            raise FormatError(
                f"{path}: {key!r} is a {type(obj).__name__}; table files hold only variables"
            )
        if obj.is_virtual:
            raise FormatError(
                f"{path}: variable {key!r} is a virtual dataset (data in other files); refused"
            )
        if obj.external:
            raise FormatError(f"{path}: variable {key!r} keeps its data in external files; refused")
        objects[key] = obj
    for key in (WAVELENGTH_DIM, ANGLE_DIM, "phase", "g"):
        if key not in objects:
            raise FormatError(f"{path}: missing variable {key!r}")
    for key in (WAVELENGTH_DIM, ANGLE_DIM):
        if objects[key].ndim != 1:
            raise FormatError(
                f"{path}: coordinate {key!r} must be 1-D; got shape {objects[key].shape}"
            )
    order = objects.get(ORDER_DIM)
    if order is not None and order.ndim != 1:
        raise FormatError(f"{path}: coordinate {ORDER_DIM!r} must be 1-D; got shape {order.shape}")
    parameter = objects.get(PARAMETER_DIM)
    if parameter is not None and parameter.ndim != 1:
        raise FormatError(
            f"{path}: coordinate {PARAMETER_DIM!r} must be 1-D; got shape {parameter.shape}"
        )
    shapes = _expected_shapes(
        objects[WAVELENGTH_DIM].shape[0],
        objects[ANGLE_DIM].shape[0],
        0 if order is None else order.shape[0],
        0 if parameter is None else parameter.shape[0],
    )
    for key, obj in objects.items():
        if key not in shapes:
            raise FormatError(
                f"{path}: unknown variable {key!r} (not in the table schema {SCHEMA})"
            )
        if obj.shape != shapes[key]:
            raise FormatError(
                f"{path}: variable {key!r} has shape {obj.shape}; expected {shapes[key]}"
            )
        if obj.size > max_values:
            raise FormatError(
                f"{path}: variable {key!r} declares {obj.size} values "
                f"({obj.size * obj.dtype.itemsize} bytes), more than the reader's limit "
                f"{max_values}; refused before reading (max_values= raises it)"
            )
        kind = "i" if key in _INTEGERS else "f"
        if obj.dtype.kind != kind or obj.dtype.itemsize != 8:
            wanted = "64-bit integers" if kind == "i" else "64-bit floats"
            raise FormatError(f"{path}: variable {key!r} must hold {wanted}; got {obj.dtype}")
    _check_storage(path, objects)
    variables = {}
    for key, obj in objects.items():
        var_attrs = {
            name: _string_attribute(path, obj, name, f"variable {key!r}")
            for name in obj.attrs
            if name not in _HDF5_ATTRIBUTES
        }
        try:
            values = obj[()]
        except (OSError, RuntimeError, ValueError) as exc:
            raise FormatError(
                f"{path}: variable {key!r} cannot be read (damaged: checksum or filter): {exc}"
            ) from None
        variables[key] = (
            np.asarray(values, dtype=np.int64 if key in _INTEGERS else np.float64),
            var_attrs,
        )
    digest = dataset_digest(variables, attrs)
    if digest != attrs[DIGEST_ATTRIBUTE]:
        raise FormatError(
            f"{path}: the data do not match their checksum ({DIGEST_ATTRIBUTE}): the file was altered or damaged"
        )
    return variables, attrs


def _check_derived(
    path: Path, table: Table, variables: Mapping[str, tuple[np.ndarray, Any]]
) -> None:
    expected = table.derived()
    present = {key for key in variables if key in DERIVED}
    if present != set(expected):
        raise FormatError(
            f"{path}: derived variables {sorted(present)} do not match those the stored ones define "
            f"{sorted(expected)}"
        )
    for key, values in expected.items():
        stored = variables[key][0]
        if not np.array_equal(stored, values):
            i = int(np.argmax(stored != values))
            raise FormatError(
                f"{path}: derived variable {key!r} disagrees with {DERIVED[key]} at "
                f"{float(table.wavelength_nm[i])!r} nm: file {float(stored[i])!r}, "
                f"recomputed {float(values[i])!r}"
            )


def _parameter_coordinates(
    path: Path, values: np.ndarray, attrs: Mapping[str, Any]
) -> dict[str, tuple[str, np.ndarray, dict[str, Any]]]:
    """The ``parameter`` and ``parameter_units`` coordinates from the stored indices."""
    try:
        names = json.loads(attrs[_PARAMETER_NAMES])
        units = json.loads(attrs[_PARAMETER_UNITS])
    except (KeyError, TypeError, ValueError) as exc:
        raise FormatError(
            f"{path}: variable {PARAMETER_DIM!r} lacks its {_PARAMETER_NAMES!r} and "
            f"{_PARAMETER_UNITS!r} attributes (JSON lists): {exc}"
        ) from None
    ok = (
        isinstance(names, list)
        and isinstance(units, list)
        and len(names) == len(units) == values.size
        and all(isinstance(v, str) for v in (*names, *units))
        and np.array_equal(values, np.arange(values.size))
    )
    if not ok:
        raise FormatError(
            f"{path}: variable {PARAMETER_DIM!r} must index {values.size} parameter names and units"
        )
    own = {k: v for k, v in attrs.items() if k not in (_PARAMETER_NAMES, _PARAMETER_UNITS)}
    return {
        PARAMETER_DIM: (PARAMETER_DIM, np.array(names, dtype=str), own),
        "parameter_units": (
            PARAMETER_DIM,
            np.array(units, dtype=str),
            {"long_name": "unit of each parameter (udunits2)"},
        ),
    }


def _checked_path(path: str | os.PathLike[str], max_values: int) -> Path:
    """``path`` as a Path, once it is a non-empty regular file and ``max_values`` a count."""
    if isinstance(max_values, bool) or not isinstance(max_values, int) or max_values < 1:
        raise ValueError(f"max_values must be an integer >= 1; got {max_values!r}")
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise FormatError(f"{path}: is a directory, not a table file ({', '.join(SUFFIXES)})")
    if not path.is_file():
        raise FormatError(f"{path}: not a regular file")
    if path.stat().st_size == 0:
        raise FormatError(f"{path}: empty file, not a table")
    return path


def read_netcdf(path: str | os.PathLike[str], *, max_values: int = MAX_VALUES) -> Table:
    """Read a table file written by :func:`write_netcdf` (any suffix), verifying it.

    Parameters
    ----------
    path : path-like
        The file.
    max_values : int, optional
        Most values one variable may declare (default :data:`MAX_VALUES`, 2^25: 256 MiB of
        float64); a file declaring more is refused before anything is read. [-]

    Returns
    -------
    Table
        The table as written, bit for bit, with its provenance.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    FormatError
        Anything the module docstring lists under "Readers verify"; the
        message names the file and the problem.  Never an h5py exception.
    """
    import xarray as xr  # here: xarray adds ~0.7 s to `import dustoptics` (-X importtime)

    path = _checked_path(path, max_values)
    h5py = _h5py()
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise FormatError(
            f"{path}: not a netCDF-4/HDF5 file (truncated, or another format): {exc}"
        ) from None
    try:
        with f:
            variables, attrs = _open_checked(path, f, max_values)
    except FormatError:
        raise
    except (OSError, RuntimeError, KeyError, ValueError, TypeError) as exc:
        raise FormatError(f"{path}: damaged file ({type(exc).__name__}: {exc})") from None
    coords = {
        key: (key, variables[key][0], variables[key][1])
        for key in (WAVELENGTH_DIM, ANGLE_DIM, ORDER_DIM)
        if key in variables
    }
    if PARAMETER_DIM in variables:
        coords.update(_parameter_coordinates(path, *variables[PARAMETER_DIM]))
    derivative_dims = _derivative_dims()
    data = {}
    for key, (values, var_attrs) in variables.items():
        if key in coords:
            continue
        if key in derivative_dims:
            data[key] = (derivative_dims[key], values, var_attrs)
            continue
        dims: tuple[str, ...] = (
            (WAVELENGTH_DIM, ANGLE_DIM)
            if key == "phase" or key in MATRIX_FIELDS
            else (WAVELENGTH_DIM, ORDER_DIM)
            if key in EXPANSION_FIELDS
            else (WAVELENGTH_DIM,)
            if values.ndim
            else ()
        )
        data[key] = (dims, values, var_attrs)
    try:
        table = Table.from_xarray(xr.Dataset(data, coords=coords, attrs=attrs))
        check_normalization(table)
    except (ValueError, TypeError) as exc:
        raise FormatError(f"{path}: {exc}") from None
    _check_derived(path, table, variables)
    return table


#: The same reader under its older name: a netCDF-4 file is an HDF5 file.
read_hdf5 = read_netcdf


def open_table(path: str | os.PathLike[str], *, max_values: int = MAX_VALUES) -> Table:
    """Open a table file (``.nc``, ``.h5``, ``.hdf5``, ``.nc4``), verifying it.

    Parameters
    ----------
    path : path-like
        A file written by :meth:`Table.save <dustoptics.table.Table.save>`
        (or ``dustoptics build``).
    max_values : int, optional
        Most values one variable may declare (:func:`read_netcdf`). [-]

    Returns
    -------
    Table
        The table as written, bit for bit.

    Raises
    ------
    FileNotFoundError
        No such file.
    FormatError
        Not a dustoptics table (another netCDF file, a truncated or corrupted
        file, a directory, an empty file, an unknown suffix, ...); the message
        names the file and what is wrong.

    Examples
    --------
    >>> import dustoptics as do
    >>> do.open_table("tables/costa/costa.nc")  # doctest: +SKIP
    """
    p = Path(path)
    if p.is_dir():
        raise FormatError(
            f"{p}: is a directory; open_table reads one table file ({', '.join(SUFFIXES)}); "
            "a seed-CSV directory is read with dustoptics.io.read_seed_csv"
        )
    if p.suffix.lower() not in SUFFIXES:
        raise FormatError(
            f"{p}: unknown table file suffix {p.suffix!r}; expected one of {', '.join(SUFFIXES)}"
        )
    return read_netcdf(p, max_values=max_values)
