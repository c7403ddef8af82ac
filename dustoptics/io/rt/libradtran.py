"""libRadtran's ``aerosol_file explicit`` layer files as plain text (format ``libradtran``).

Written atomically as one set (:func:`dustoptics.io._atomic.write_files`) with
Python's shortest round-trip float text (:func:`dustoptics.io._text.number`):

``libradtran`` (:func:`write_libradtran`) -> ``<name>_aerosol_explicit.dat`` and ``<name>_aerosol_layer.dat``
    What uvspec reads with ``aerosol_file explicit <name>_aerosol_explicit.dat``
    (libRadtran 2.0 user's guide, option ``aerosol_file``; ``aerosol_files``
    in 1.x; Mayer & Kylling 2005, doi:10.5194/acp-5-1855-2005; Emde et al.
    2016, doi:10.5194/gmd-9-1647-2016).  The explicit file has two columns,
    altitude [km] and the name of the file with the optical properties of the
    layer *starting* at that altitude, top line first; the top line only marks
    the top of the uppermost layer and names ``NULL``.  The layer file has one
    row per wavelength: wavelength [nm], extinction coefficient [km-1],
    single-scattering albedo, then the phase-function moments
    ``pmom_0 = 1, pmom_1 = g, ...`` (DISORT's normalization:
    :mod:`dustoptics.io.rt.disort`).  The
    extinction coefficient is ``N <C_ext>`` at the table's
    ``number_density_per_m3`` (``1e-9 N[m-3] cext[um2]`` in km-1); uvspec
    reads the layer file's name relative to its working directory.

These files carry the phase function only (uvspec reads no other element
from them: ``read_optprop_files`` in libRadtran 2.0.2's ``src/aerosol.c``);
for polarized solvers, the format ``libradtran-nc``
(:mod:`dustoptics.io.rt.libradtran_netcdf`) writes the phase matrix in
libRadtran's signs.

It needs the table's expansion coefficients (``compute_optics(...,
expansion=True)`` or ``expansion=N``) and cross-sections; a table without
them is refused with a message naming the option, since projecting the
tabulated phase function onto Legendre polynomials would lose its forward
peak without an error bound.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_positive, check_real
from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io._text import floats, number
from dustoptics.io.describe_formats import describe_rt_text, is_rt_text
from dustoptics.io.registry import Format, register
from dustoptics.io.rt.disort import bound_text, disort_moments, header_lines, moment_lines

__all__ = [
    "LIBRADTRAN_EXPLICIT_SUFFIX",
    "LIBRADTRAN_LAYER_SUFFIX",
    "layer_bounds",
    "libradtran_texts",
    "write_libradtran",
]

LIBRADTRAN_EXPLICIT_SUFFIX = "_aerosol_explicit.dat"
LIBRADTRAN_LAYER_SUFFIX = "_aerosol_layer.dat"

#: How many kilometres-per-metre and um2-per-m2 make km-1 from m-3 and um2.
_UM2_PER_M3_TO_PER_KM = 1e-12 * 1e3


def layer_bounds(*, bottom_km: float, top_km: float) -> tuple[float, float]:
    """The layer's bottom and top [km], checked: real, ``top_km > bottom_km`` (else ValueError)."""
    bottom = check_real("bottom_km", bottom_km)
    top = check_real("top_km", top_km)
    if not top > bottom:
        raise ValueError(f"top_km must exceed bottom_km = {bottom!r}; got top_km = {top!r}")
    return bottom, top


def libradtran_texts(table: Any, *, bottom_km: float = 0.0, top_km: float = 1.0) -> tuple[str, str]:
    """The ``libradtran`` format's explicit file and layer file (see the module docstring).

    Parameters
    ----------
    table : dustoptics.table.Table
        With expansion coefficients, cross-sections and ``number_density_per_m3``.
    bottom_km, top_km : float
        Altitudes of the layer's bottom and top. [km]

    Returns
    -------
    (str, str)
        The ``aerosol_file explicit`` file and the layer's optical-property file.

    Raises
    ------
    ValueError
        No expansion coefficients, cross-sections or number density, or
        ``top_km <= bottom_km``.
    """
    bottom, top = layer_bounds(bottom_km=bottom_km, top_km=top_km)
    wl, cext, pmom = disort_moments(table, "libradtran")
    if table.cross_sections is None or table.cross_sections.number_density_per_m3 is None:
        raise ValueError(
            f"format 'libradtran' needs an extinction coefficient [km-1], but table "
            f"{table.name!r} has no number density: give --number-density-per-m3 (command "
            "line) or table.replace(cross_sections={'number_density_per_m3': ...})"
        )
    n_m3 = check_positive(
        "number_density_per_m3", table.cross_sections.number_density_per_m3, unit="m-3"
    )
    stem = safe_stem(table.name)
    layer_name = stem + LIBRADTRAN_LAYER_SUFFIX
    ext_km = np.asarray(cext, dtype=np.float64) * (n_m3 * _UM2_PER_M3_TO_PER_KM)
    head = header_lines(table, "dustoptics libRadtran aerosol optical properties, format version 1")
    layer = [
        *head,
        "# one layer's optical properties for uvspec's 'aerosol_file explicit' "
        f"(listed in {stem + LIBRADTRAN_EXPLICIT_SUFFIX})",
        "# columns: wavelength [nm], extinction coefficient [km-1], single scattering "
        "albedo [1], phase-function moments pmom_0 ... [1]",
        f"# extinction coefficient = N <C_ext> with N = {number(n_m3)} m-3 "
        "(1e-9 N[m-3] cext[um2] km-1)",
        *moment_lines(pmom),
        f"# accuracy: moments error <= {bound_text(table.expansion.expansion_error_estimate)}; "
        f"cross-sections and g relative error <= "
        f"{bound_text(table.quantity('cross_section_error_estimate'))}",
    ]
    ssa = table.ssa
    for i in range(wl.size):
        row = [number(wl[i]), number(ext_km[i]), number(ssa[i])]
        row += [number(x) for x in floats("pmom", pmom[i])]
        layer.append(" ".join(row))
    explicit = [
        *head,
        f"# uvspec input: aerosol_default + aerosol_file explicit {stem + LIBRADTRAN_EXPLICIT_SUFFIX}",
        "# columns: altitude [km], optical-property file of the layer starting at that "
        "altitude (top line first; the top line only marks the top: NULL)",
        f"{number(top)} NULL",
        f"{number(bottom)} {layer_name}",
    ]
    return "\n".join(explicit) + "\n", "\n".join(layer) + "\n"


def write_libradtran(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    bottom_km: float = 0.0,
    top_km: float = 1.0,
) -> list[Path]:
    """Write the explicit file and the layer file (:func:`libradtran_texts`) into ``out_dir``.

    Both appear together or neither (one atomic set).

    Returns
    -------
    list of pathlib.Path
        ``<name>_aerosol_explicit.dat`` and ``<name>_aerosol_layer.dat``.

    Raises
    ------
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).
    ValueError
        As :func:`libradtran_texts`.
    """
    explicit, layer = libradtran_texts(table, bottom_km=bottom_km, top_km=top_km)
    root = Path(os.fspath(out_dir))
    stem = safe_stem(table.name)
    return write_files(
        {
            root / (stem + LIBRADTRAN_EXPLICIT_SUFFIX): explicit.encode("utf-8"),
            root / (stem + LIBRADTRAN_LAYER_SUFFIX): layer.encode("utf-8"),
        },
        overwrite=overwrite,
    )


RECORD = register(
    Format(
        name="libradtran",
        summary="NAME_aerosol_*.dat: libRadtran's (needs the expansion, N0)",
        write=write_libradtran,
        suffixes=(".dat",),
        needs=frozenset({"cross_sections", "number_density", "expansion"}),
        recognise=is_rt_text,
        describe=describe_rt_text,
    )
)
