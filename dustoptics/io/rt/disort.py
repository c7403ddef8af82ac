"""DISORT's phase-function moments as plain text (format ``disort``).

Written atomically (:func:`dustoptics.io._atomic.write_files`) with Python's
shortest round-trip float text (:func:`dustoptics.io._text.number`):

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

It needs the table's expansion coefficients (``compute_optics(...,
expansion=True)`` or ``expansion=N``) and cross-sections; a table without
them is refused with a message naming the option, since projecting the
tabulated phase function onto Legendre polynomials would lose its forward
peak without an error bound.

The moments, header and checks are shared with libRadtran's layer files
(:mod:`dustoptics.io.rt.libradtran`), which carry the same moments.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io._text import floats, number
from dustoptics.io.describe_formats import describe_rt_text, is_rt_text
from dustoptics.io.registry import Format, register
from dustoptics.table.provenance import _installed_version

__all__ = [
    "DISORT_SUFFIX",
    "bound_text",
    "disort_moments",
    "disort_text",
    "header_lines",
    "moment_lines",
    "write_disort",
]

DISORT_SUFFIX = "_disort.txt"


def disort_moments(table: Any, fmt: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wavelengths, cext and DISORT's moments of ``table``; a ValueError names what is missing."""
    if table.expansion is None:
        raise ValueError(
            f"format {fmt!r} needs the phase function's Legendre moments, but table "
            f"{table.name!r} has no expansion coefficients: compute it with "
            "compute_optics(..., expansion=True) (or expansion=N for N orders), save it "
            "(table.save) and export that file"
        )
    if table.cross_sections is None:
        raise ValueError(
            f"format {fmt!r} needs extinction and scattering cross-sections; table "
            f"{table.name!r} has none (a phase-function-only table)"
        )
    return table.wavelength_nm, table.cross_sections.cext_um2, table.pmom


def header_lines(table: Any, title: str) -> list[str]:
    """The first lines of a file: its title, the table's name and input hash, the version."""
    return [
        f"# {title}",
        f"# table: {table.name}",
        f"# input_hash: {table.provenance.input_hash} (sha256 of the table's provenance inputs)",
        f"# written by: dustoptics {_installed_version('dustoptics')}",
    ]


def moment_lines(pmom: np.ndarray) -> list[str]:
    """Header lines stating how many moments a row has and their normalization (PMOM)."""
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
    wl, cext, pmom = disort_moments(table, "disort")
    ssa = table.ssa
    err = table.expansion.expansion_error_estimate
    err_rows = np.full(wl.shape, np.nan) if err is None else np.asarray(err, dtype=np.float64)
    lines = header_lines(table, "dustoptics DISORT moments file, format version 1")
    lines += [
        "# columns: wavelength_nm [nm], cext_um2 [um2] (mean extinction cross-section per "
        "particle), ssa [1] (csca / cext), pmom_error [1] (bound on the error of every "
        "moment; nan: not estimated), pmom_0 ... [1]",
        *moment_lines(pmom),
        f"# accuracy: cross-sections and g relative error <= "
        f"{bound_text(table.quantity('cross_section_error_estimate'))}",
    ]
    for i in range(wl.size):
        row = [number(wl[i]), number(cext[i]), number(ssa[i]), repr(float(err_rows[i]))]
        row += [number(x) for x in floats("pmom", pmom[i])]
        lines.append(" ".join(row))
    return "\n".join(lines) + "\n"


def bound_text(values: Any) -> str:
    """The largest of ``values`` for a header, or "not estimated"."""
    return "not estimated" if values is None else f"{float(np.max(values)):.3g}"


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
    path = Path(os.fspath(out_dir)) / (safe_stem(table.name) + DISORT_SUFFIX)
    return write_files({path: text.encode("utf-8")}, overwrite=overwrite)


RECORD = register(
    Format(
        name="disort",
        summary="NAME_disort.txt: DISORT's moments (needs the expansion)",
        write=write_disort,
        suffixes=(".txt",),
        needs=frozenset({"cross_sections", "expansion"}),
        recognise=is_rt_text,
        describe=describe_rt_text,
    )
)
