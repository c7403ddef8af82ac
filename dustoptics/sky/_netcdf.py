"""The sky's netCDF files without xarray: classic netCDF through scipy, as xarray writes them.

``dustoptics sky`` writes a sky as ``xarray.Dataset.to_netcdf(engine="scipy")`` would
(classic netCDF with 64-bit offsets, ``scipy.io.netcdf_file``), byte for byte, without
building a Dataset: importing xarray (with pandas) and the ``dask.array`` and
``distributed`` modules it imports where dask is installed (the first variable it makes,
the scheduler it looks up to write) took a warm ``sky mars`` 1-1.5 s.  The encoding is
xarray's for these variables (:func:`netcdf3_bytes`); the tests hold the bytes to xarray's.
:func:`read_netcdf3` reads such a file back (variables and global attributes).
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["Variable", "netcdf3_bytes", "read_netcdf3"]

#: A variable: its dimensions, values and attributes (as ``xarray.Dataset`` takes them).
Variable = tuple[tuple[str, ...], np.ndarray, Mapping[str, Any]]

#: xarray's coercions of dtypes classic netCDF lacks (``xarray.backends.netcdf3``).
_NC3_COERCIONS = {
    "int64": "int32",
    "uint64": "int32",
    "uint32": "int32",
    "uint16": "int16",
    "uint8": "int8",
    "bool": "int8",
}


def _coerce(arr: np.ndarray) -> np.ndarray:
    """``arr`` in a dtype classic netCDF stores, its values unchanged (xarray's coercion)."""
    new = _NC3_COERCIONS.get(str(arr.dtype))
    if new is None:
        return arr
    cast = arr.astype(new)
    if not (cast == arr).all():
        raise ValueError(f"values of dtype {arr.dtype} do not fit {new} (classic netCDF)")
    return cast


def _attribute(value: Any) -> Any:
    """An attribute value as xarray encodes it for classic netCDF: text as UTF-8 bytes,
    numbers as one-dimensional arrays (64-bit integers as 32-bit)."""
    if isinstance(value, bytes):
        return value
    if isinstance(value, str):
        return value.encode("utf-8")
    arr = _coerce(np.atleast_1d(value))
    if arr.ndim > 1:
        raise ValueError("netCDF attributes must be 1-dimensional")
    return arr


def netcdf3_bytes(
    data: Mapping[str, Variable], coords: Mapping[str, Variable], attrs: Mapping[str, Any]
) -> bytes:
    """Classic netCDF (64-bit offsets) of a dataset, as xarray's scipy engine writes it.

    ``xarray.Dataset(data, coords=coords, attrs=attrs).to_netcdf(engine="scipy")`` for
    numeric variables: the global attributes, the dimensions in the order the variables
    (data, then coordinates) name them, each variable with its attributes and, for
    floating-point values, ``_FillValue`` NaN (CF's default, as xarray adds it).

    Parameters
    ----------
    data, coords : mapping
        Name -> (dimensions, values, attributes): data variables and coordinates.
    attrs : mapping
        Global attributes (text or numbers).

    Returns
    -------
    bytes
    """
    from scipy.io import netcdf_file  # lazy: scipy.io adds ~0.1 s to start-up

    variables = {**data, **coords}
    dims: dict[str, int] = {}
    arrays = {}
    for name, (var_dims, values, _) in variables.items():
        arr = _coerce(np.asarray(values))
        if arr.dtype.kind not in "iuf" or arr.ndim != len(var_dims):
            raise ValueError(f"variable {name!r}: numbers with one dimension per axis expected")
        for dim, size in zip(var_dims, arr.shape):
            if dims.setdefault(dim, size) != size:
                raise ValueError(f"dimension {dim!r} has sizes {dims[dim]} and {size}")
        arrays[name] = arr
    buf = io.BytesIO()
    out = netcdf_file(buf, mode="w", mmap=False, version=2)
    for key, value in attrs.items():
        setattr(out, key, _attribute(value))
    for dim, size in dims.items():
        out.createDimension(dim, size)
    for name, (var_dims, _, var_attrs) in variables.items():
        arr = arrays[name]
        var = out.createVariable(name, arr.dtype, tuple(var_dims))
        for key, value in var_attrs.items():
            setattr(var, key, _attribute(value))
        if arr.dtype.kind == "f" and "_FillValue" not in var_attrs:
            var._FillValue = _attribute(np.array(np.nan, dtype=arr.dtype))
        var.data[...] = arr
    out.flush()
    content = buf.getvalue()
    out.close()
    return content


def read_netcdf3(
    source: Any, *, names: tuple[str, ...] | None = None
) -> tuple[dict[str, tuple[tuple[str, ...], np.ndarray]], dict[str, Any]]:
    """The variables and global attributes of a classic netCDF file.

    Parameters
    ----------
    source : path-like or file-like
        A classic netCDF file (as :func:`netcdf3_bytes` or xarray's scipy engine writes).
    names : tuple of str, optional
        Only these variables (those present); default all.

    Returns
    -------
    variables : dict
        Name -> (dimensions, values as a native-endian copy; ``_FillValue`` left as is).
    attrs : dict
        Global attributes, text decoded from UTF-8.

    Raises
    ------
    OSError, TypeError, ValueError
        The file is missing or not classic netCDF.
    """
    from scipy.io import netcdf_file  # lazy: as above

    with netcdf_file(source, mode="r", mmap=False) as f:
        attrs = {
            k: v.decode("utf-8") if isinstance(v, bytes) else v for k, v in f._attributes.items()
        }
        variables = {
            name: (
                tuple(var.dimensions),
                np.array(var.data, dtype=var.data.dtype.newbyteorder("=")),
            )
            for name, var in f.variables.items()
            if names is None or name in names
        }
    return variables, attrs
