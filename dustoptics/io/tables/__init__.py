"""Table files: the whole :class:`~dustoptics.table.Table`, written and read back bit for bit.

- :mod:`~dustoptics.io.tables.netcdf`: one CF-1.10 netCDF-4 file (``.nc``, or the same
  bytes as ``.h5``), verified when read (:func:`open_table`, :func:`write_netcdf`,
  :func:`read_netcdf`, and the same reader and writer as :func:`read_hdf5`,
  :func:`write_hdf5`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io.tables import netcdf
    from dustoptics.io.tables.netcdf import (
        open_table,
        read_hdf5,
        read_netcdf,
        write_hdf5,
        write_netcdf,
    )

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.io.tables.netcdf": (
        "open_table",
        "read_hdf5",
        "read_netcdf",
        "write_hdf5",
        "write_netcdf",
    ),
}


__all__ = ["netcdf", "open_table", "read_hdf5", "read_netcdf", "write_hdf5", "write_netcdf"]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
