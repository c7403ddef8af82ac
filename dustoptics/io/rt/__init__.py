"""Files that radiative-transfer codes read.

- :mod:`~dustoptics.io.rt.disort`: DISORT's phase-function moments with
  extinction and single-scattering albedo (format ``disort``).
- :mod:`~dustoptics.io.rt.libradtran`: libRadtran's ``aerosol_file explicit``
  list and layer file (format ``libradtran``), with the same moments.
- :mod:`~dustoptics.io.rt.libradtran_netcdf`: libRadtran's netCDF optical-property
  file with the phase matrix P11, P12, P33, P34 in libRadtran's signs, and its
  ``aerosol_species_file`` profile (format ``libradtran-nc``).

All need ``compute_optics(expansion=...)``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io.rt import disort, libradtran, libradtran_netcdf
    from dustoptics.io.rt.disort import DISORT_SUFFIX, disort_text, write_disort
    from dustoptics.io.rt.libradtran import (
        LIBRADTRAN_EXPLICIT_SUFFIX,
        LIBRADTRAN_LAYER_SUFFIX,
        libradtran_texts,
        write_libradtran,
    )
    from dustoptics.io.rt.libradtran_netcdf import write_libradtran_netcdf

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.io.rt.disort": ("DISORT_SUFFIX", "disort_text", "write_disort"),
    "dustoptics.io.rt.libradtran": (
        "LIBRADTRAN_EXPLICIT_SUFFIX",
        "LIBRADTRAN_LAYER_SUFFIX",
        "libradtran_texts",
        "write_libradtran",
    ),
    "dustoptics.io.rt.libradtran_netcdf": ("write_libradtran_netcdf",),
}


__all__ = [
    "DISORT_SUFFIX",
    "LIBRADTRAN_EXPLICIT_SUFFIX",
    "LIBRADTRAN_LAYER_SUFFIX",
    "disort",
    "disort_text",
    "libradtran",
    "libradtran_netcdf",
    "libradtran_texts",
    "write_disort",
    "write_libradtran",
    "write_libradtran_netcdf",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
