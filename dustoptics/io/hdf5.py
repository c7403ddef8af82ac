"""The table file under its older module name: netCDF-4 files are HDF5 files.

:mod:`dustoptics.io.netcdf` writes and reads them (``.nc`` and ``.h5`` alike);
this module only keeps ``from dustoptics.io.hdf5 import read_hdf5, write_hdf5``
working.
"""

from __future__ import annotations

from dustoptics.io.netcdf import read_hdf5, write_hdf5

__all__ = ["read_hdf5", "write_hdf5"]
