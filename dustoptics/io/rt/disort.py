"""Plain-text files that radiative-transfer codes read: DISORT moments and libRadtran layers.

Two formats of :data:`dustoptics.io.FORMATS`, both written atomically
(:func:`dustoptics.io._atomic.write_files`) with Python's shortest round-trip
float text (:func:`dustoptics.io._text.number`):

``disort`` (:func:`write_disort`) -> ``<name>_disort.txt``
    One row per wavelength: ``wavelength_nm`` [nm], ``cext_um2`` [um2] (mean
    extinction cross-section per particle), ``ssa`` [1], ``pmom_error`` [1]
    (bound on the error of every moment, ``expansion_error_estimate``; ``nan``
    when the table has none), then ``pmom_0 ... pmom_{N-1}`` [1].  Lines
    starting with ``#`` are the header (units, normalization, provenance and
    the input hash); ``numpy.loadtxt`` reads the rows.  The moments are
    DISORT's ``PMOM`` (Stamnes et al. 1988, doi:10.1364/AO.27.002502):

        chi_l = alpha1_l / (2 l + 1) = 1/2 int_{-1}^{1} P(mu) P_l(mu) dmu,

    with P = 4 pi F11 normalized to 1/(4 pi) int P dOmega = 1, so chi_0 = 1
    and chi_1 = g (:func:`dustoptics.scattering.expansion.pmom_from_alpha1`).

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
    ``pmom_0 = 1, pmom_1 = g, ...`` (DISORT's normalization, above).  The
    extinction coefficient is ``N <C_ext>`` at the table's
    ``number_density_per_m3`` (``1e-9 N[m-3] cext[um2]`` in km-1); uvspec
    reads the layer file's name relative to its working directory.

Both need the table's expansion coefficients (``compute_optics(...,
expansion=True)`` or ``expansion=N``) and cross-sections; a table without
them is refused with a message naming the option, since projecting the
tabulated phase function onto Legendre polynomials would lose its forward
peak without an error bound.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_positive, check_real
from dustoptics.io import register_format
from dustoptics.io._atomic import write_files
from dustoptics.io._text import floats, number

__all__ = [
    "DISORT_SUFFIX",
    "LIBRADTRAN_EXPLICIT_SUFFIX",
    "LIBRADTRAN_LAYER_SUFFIX",
    "disort_text",
    "libradtran_texts",
    "write_disort",
    "write_libradtran",
]

DISORT_SUFFIX = "_disort.txt"
LIBRADTRAN_EXPLICIT_SUFFIX = "_aerosol_explicit.dat"
LIBRADTRAN_LAYER_SUFFIX = "_aerosol_layer.dat"

#: How many kilometres-per-metre and um2-per-m2 make km-1 from m-3 and um2.
_UM2_PER_M3_TO_PER_KM = 1e-12 * 1e3


def _stem(name: str) -> str:
    stem = re.sub(r"[^A-Za-z0-9._-]", "_", name).lstrip(".")
    return stem or "table"


def _checked(table: Any, fmt: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wavelengths, cext and pmom of ``table``, or a ValueError naming what to compute."""
    if table.alpha1 is None:
        raise ValueError(
            f"format {fmt!r} needs the phase function's Legendre moments, but table "
            f"{table.name!r} has no expansion coefficients: compute it with "
            "compute_optics(..., expansion=True) (or expansion=N for N orders), save it "
            "(table.save) and export that file"
        )
    if table.cext_um2 is None:
        raise ValueError(
            f"format {fmt!r} needs extinction and scattering cross-sections; table "
            f"{table.name!r} has none (a phase-function-only table)"
        )
    return table.wavelength_nm, table.cext_um2, table.pmom


def _header(table: Any, title: str) -> list[str]:
    from dustoptics.table import _installed_version

    return [
        f"# {title}",
        f"# table: {table.name}",
        f"# input_hash: {table.provenance.input_hash} (sha256 of the table's provenance inputs)",
        f"# written by: dustoptics {_installed_version('dustoptics')}",
    ]


def _moment_note(pmom: np.ndarray) -> list[str]:
    return [
        f"# moments: pmom_0 ... pmom_{pmom.shape[1] - 1} ({pmom.shape[1]} per wavelength), "
        "DISORT's PMOM normalization",
        "#   pmom_l = alpha1_l / (2 l + 1) = 1/2 int_{-1}^{1} P(mu) P_l(mu) dmu,",
        "#   P normalized to 1/(4 pi) int P dOmega = 1, so pmom_0 = 1 and pmom_1 = g",
    ]


def disort_text(table: Any) -> str:
    """The ``disort`` format's text for ``table`` (see the module docstring).

    Raises
    ------
    ValueError
        The table has no expansion coefficients or no cross-sections, or a
        value is not finite.
    """
    wl, cext, pmom = _checked(table, "disort")
    ssa = table.ssa
    err = table.expansion_error_estimate
    err_rows = np.full(wl.shape, np.nan) if err is None else np.asarray(err, dtype=np.float64)
    lines = _header(table, "dustoptics DISORT moments file, format version 1")
    lines += [
        "# columns: wavelength_nm [nm], cext_um2 [um2] (mean extinction cross-section per "
        "particle), ssa [1] (csca / cext), pmom_error [1] (bound on the error of every "
        "moment; nan: not estimated), pmom_0 ... [1]",
        *_moment_note(pmom),
        f"# accuracy: cross-sections and g relative error <= "
        f"{_max_text(table.cross_section_error_estimate)}",
    ]
    for i in range(wl.size):
        row = [number(wl[i]), number(cext[i]), number(ssa[i]), repr(float(err_rows[i]))]
        row += [number(x) for x in floats("pmom", pmom[i])]
        lines.append(" ".join(row))
    return "\n".join(lines) + "\n"


def _max_text(values: Any) -> str:
    return "not estimated" if values is None else f"{float(np.max(values)):.3g}"


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
    bottom = check_real("bottom_km", bottom_km)
    top = check_real("top_km", top_km)
    if not top > bottom:
        raise ValueError(f"top_km must exceed bottom_km = {bottom!r}; got top_km = {top!r}")
    wl, cext, pmom = _checked(table, "libradtran")
    if table.number_density_per_m3 is None:
        raise ValueError(
            f"format 'libradtran' needs an extinction coefficient [km-1], but table "
            f"{table.name!r} has no number density: give --number-density-per-m3 (command "
            "line) or table.replace(number_density_per_m3=...)"
        )
    n_m3 = check_positive("number_density_per_m3", table.number_density_per_m3, unit="m-3")
    stem = _stem(table.name)
    layer_name = stem + LIBRADTRAN_LAYER_SUFFIX
    ext_km = np.asarray(cext, dtype=np.float64) * (n_m3 * _UM2_PER_M3_TO_PER_KM)
    head = _header(table, "dustoptics libRadtran aerosol optical properties, format version 1")
    layer = [
        *head,
        "# one layer's optical properties for uvspec's 'aerosol_file explicit' "
        f"(listed in {stem + LIBRADTRAN_EXPLICIT_SUFFIX})",
        "# columns: wavelength [nm], extinction coefficient [km-1], single scattering "
        "albedo [1], phase-function moments pmom_0 ... [1]",
        f"# extinction coefficient = N <C_ext> with N = {number(n_m3)} m-3 "
        "(1e-9 N[m-3] cext[um2] km-1)",
        *_moment_note(pmom),
        f"# accuracy: moments error <= {_max_text(table.expansion_error_estimate)}; "
        f"cross-sections and g relative error <= "
        f"{_max_text(table.cross_section_error_estimate)}",
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


def _directory(out_dir: str | os.PathLike[str]) -> Path:
    return Path(os.fspath(out_dir))


def write_disort(
    table: Any, out_dir: str | os.PathLike[str], *, overwrite: bool = False
) -> list[Path]:
    """Write ``<name>_disort.txt`` (:func:`disort_text`) into ``out_dir``, atomically.

    Returns
    -------
    list of pathlib.Path
        The written file.

    Raises
    ------
    FileExistsError
        The file exists and ``overwrite`` is False (nothing is written).
    ValueError
        As :func:`disort_text`.
    """
    text = disort_text(table)
    path = _directory(out_dir) / (_stem(table.name) + DISORT_SUFFIX)
    return write_files({path: text.encode("utf-8")}, overwrite=overwrite)


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
    root = _directory(out_dir)
    stem = _stem(table.name)
    return write_files(
        {
            root / (stem + LIBRADTRAN_EXPLICIT_SUFFIX): explicit.encode("utf-8"),
            root / (stem + LIBRADTRAN_LAYER_SUFFIX): layer.encode("utf-8"),
        },
        overwrite=overwrite,
    )


register_format("disort", write_disort)
register_format("libradtran", write_libradtran)
