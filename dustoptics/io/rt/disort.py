"""DISORT's phase-function moments as plain text (format ``disort``).

Written atomically (:func:`dustoptics.io._atomic.write_files`) with Python's
shortest round-trip float text (:func:`dustoptics.io._text.number`):

``disort`` (:func:`write_disort`) -> ``<name>_disort.txt``
    One row per wavelength: ``wavelength_nm`` [nm], ``cext_um2`` [um2] (mean
    extinction cross-section per particle), ``ssa`` [1], ``pmom_error`` [1]
    (bound on the error of every moment, ``expansion_error_estimate``; ``nan``
    when the table has none), ``pmom_0 ... pmom_{N-1}`` [1], then the phase
    function ``phase_0 ... phase_{M-1}`` [1] at the ``M`` cosines of the
    header's ``mu_phase:`` line.  Lines starting with ``#`` are the header
    (units, normalization, provenance, the input hash, the profile);
    ``numpy.loadtxt`` reads the rows.  The moments are DISORT's ``PMOM``
    (Stamnes et al. 1988, doi:10.1364/AO.27.002502):

        chi_l = alpha1_l / (2 l + 1) = 1/2 int_{-1}^{1} P(mu) P_l(mu) dmu,

    with P = 4 pi F11 normalized to 1/(4 pi) int P dOmega = 1, so chi_0 = 1
    and chi_1 = g (:func:`dustoptics.scattering.expansion.pmom_from_alpha1`).
    The phase function is the table's own (``4 pi`` times its ``phase``, the
    same normalization), at the cosines of its angles in increasing order
    (180 deg first): CDISORT's ``mu_phase`` and ``phase`` for its new
    intensity correction (Buras, Dowling and Emde 2011,
    doi:10.1016/j.jqsrt.2011.03.019: ``flag.intensity_correction = TRUE``,
    ``flag.old_intensity_correction = FALSE``, ``nphase = M``), which
    interpolates it linearly in the cosine.  A table whose angles do not run
    from 0 to 180 deg gets no phase block (``nphase: 0`` in the header).

    With a number density (the table's, or ``--optical-depth``), the header
    also gives the vertical profile as homogeneous layers (``layer:`` lines,
    top first as DISORT numbers them: bottom and top [km], particle column
    [um-2]); a layer's optical depth at a row's wavelength is ``column *
    cext_um2`` (:mod:`dustoptics.io.rt.profile`).

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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_positive
from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io._text import floats, number
from dustoptics.io.describe_formats import describe_rt_text, is_rt_text
from dustoptics.io.registry import Format, register
from dustoptics.io.rt.profile import RTLayers, RTProfileOptions, coverage_lines, rt_layers
from dustoptics.table.provenance import _installed_version

__all__ = [
    "DISORT_SUFFIX",
    "DisortFile",
    "bound_text",
    "disort_moments",
    "disort_text",
    "header_lines",
    "layer_lines",
    "moment_lines",
    "number_density",
    "phase_grid",
    "read_disort",
    "write_disort",
]

DISORT_SUFFIX = "_disort.txt"

#: The file's layout version (2: the phase-function block and the profile).
_VERSION = 2

#: um-2 per m-2.
_PER_M2_TO_PER_UM2 = 1e-12


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


def phase_grid(table: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """CDISORT's ``mu_phase`` (increasing) and ``phase`` (n_wavelength, nphase), or None.

    ``phase = 4 pi F11`` (1/2 int P dmu = 1, the moments' normalization) at the cosines of
    the table's angles, 180 deg first; None when the angles do not run from 0 to 180 deg.
    """
    theta = np.asarray(table.theta_deg, dtype=np.float64)
    if theta.size < 2 or theta[0] != 0.0 or theta[-1] != 180.0:
        return None
    mu = np.cos(np.deg2rad(theta[::-1]))
    mu[0], mu[-1] = -1.0, 1.0
    return mu, 4.0 * np.pi * np.asarray(table.phase, dtype=np.float64)[:, ::-1]


def number_density(table: Any) -> float | None:
    """The table's number density [m-3], or None."""
    cs = table.cross_sections
    return None if cs is None else cs.number_density_per_m3


def layer_lines(table: Any, layers: RTLayers | None, fmt: str) -> list[str]:
    """Header lines of the vertical profile (DISORT's layers, top first), or none without a
    number density; ``layers`` given without one is a ValueError."""
    n0 = number_density(table)
    if n0 is None:
        if layers is not None:
            raise ValueError(
                f"format {fmt!r} cannot write the profile asked for: table {table.name!r} has no "
                "number density; give --number-density-per-m3 or --optical-depth (command line) "
                "or table.replace(cross_sections={'number_density_per_m3': ...})"
            )
        return []
    n_m3 = check_positive("number_density_per_m3", n0, unit="m-3")
    layers = rt_layers() if layers is None else layers
    column_um2 = np.asarray(layers.column_m) * n_m3 * _PER_M2_TO_PER_UM2
    lines = [
        f"# number density N0 = {number(n_m3)} m-3 where the relative density is 1",
        f"# profile: {layers.description}; {layers.n_layers} homogeneous layers",
        "# layer: bottom [km], top [km], particle column [um-2] (N0 int rho dz), top layer "
        "first (DISORT's order); its optical depth at a row's wavelength: dtauc = column "
        "* cext_um2",
    ]
    for i in reversed(range(layers.n_layers)):
        lines.append(
            f"# layer: {number(layers.bottom_km[i])} {number(layers.top_km[i])} "
            f"{number(float(column_um2[i]))}"
        )
    return lines


def disort_text(table: Any, *, layers: RTLayers | None = None) -> str:
    """The ``disort`` format's text for ``table`` (see the module docstring).

    Parameters
    ----------
    table : dustoptics.table.Table
        With expansion coefficients and cross-sections.
    layers : RTLayers, optional
        The vertical profile (:func:`dustoptics.io.rt.profile.rt_layers`); it needs a
        number density.  Default: one uniform layer from 0 to 1 km when the table has a
        number density, no profile without one.

    Raises
    ------
    ValueError
        The table has no expansion coefficients or no cross-sections, ``layers`` without
        a number density, or a value is not finite.
    """
    wl, cext, pmom = disort_moments(table, "disort")
    ssa = table.ssa
    err = table.expansion.expansion_error_estimate
    err_rows = np.full(wl.shape, np.nan) if err is None else np.asarray(err, dtype=np.float64)
    grid = phase_grid(table)
    nphase = 0 if grid is None else grid[0].size
    lines = header_lines(table, f"dustoptics DISORT moments file, format version {_VERSION}")
    lines += [
        "# columns: wavelength_nm [nm], cext_um2 [um2] (mean extinction cross-section per "
        "particle), ssa [1] (csca / cext), pmom_error [1] (bound on the error of every "
        f"moment; nan: not estimated), pmom_0 ... [1], then phase_0 ... phase_{nphase - 1} "
        f"[1] ({nphase} values)",
        *moment_lines(pmom),
        f"# accuracy: cross-sections and g relative error <= "
        f"{bound_text(table.quantity('cross_section_error_estimate'))}",
        *coverage_lines(wl),
    ]
    if grid is None:
        lines.append(
            "# nphase: 0 (the table's angles do not run from 0 to 180 deg: no phase block)"
        )
    else:
        lines += [
            f"# nphase: {nphase}; phase_k = P(mu_phase_k), P = 4 pi F11 normalized like the "
            "moments (1/2 int P dmu = 1), the table's phase function at its angles, 180 deg "
            "first; CDISORT's mu_phase and phase for its intensity correction of Buras, "
            "Dowling and Emde 2011 (intensity_correction TRUE, old_intensity_correction FALSE)",
            "# mu_phase: " + " ".join(number(x) for x in floats("mu_phase", grid[0])),
        ]
    lines += layer_lines(table, layers, "disort")
    for i in range(wl.size):
        row = [number(wl[i]), number(cext[i]), number(ssa[i]), repr(float(err_rows[i]))]
        row += [number(x) for x in floats("pmom", pmom[i])]
        if grid is not None:
            row += [number(x) for x in floats("phase", grid[1][i])]
        lines.append(" ".join(row))
    return "\n".join(lines) + "\n"


def bound_text(values: Any) -> str:
    """The largest of ``values`` for a header, or "not estimated"."""
    return "not estimated" if values is None else f"{float(np.max(values)):.3g}"


def write_disort(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    layers: RTLayers | None = None,
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
    text = disort_text(table, layers=layers)
    path = Path(os.fspath(out_dir)) / (safe_stem(table.name) + DISORT_SUFFIX)
    return write_files({path: text.encode("utf-8")}, overwrite=overwrite)


@dataclass(frozen=True)
class DisortFile:
    """What a ``<name>_disort.txt`` file holds (:func:`read_disort`).

    Attributes
    ----------
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        [nm]
    cext_um2, ssa, pmom_error : numpy.ndarray, shape (n_wavelength,)
        Extinction cross-section [um2], single-scattering albedo and moment error bound [-].
    pmom : numpy.ndarray, shape (n_wavelength, n_moments)
        DISORT's ``PMOM``, ``pmom[:, 0] = 1``. [-]
    mu_phase : numpy.ndarray, shape (nphase,)
        Cosines of the phase block, increasing (empty without one). [-]
    phase : numpy.ndarray, shape (n_wavelength, nphase)
        Phase function at ``mu_phase``, 1/2 int P dmu = 1. [-]
    layer_bottom_km, layer_top_km, layer_column_per_um2 : numpy.ndarray, shape (n_layers,)
        The profile's layers, from the surface up (empty without a number density):
        DISORT's layer optical depth is ``layer_column_per_um2 * cext_um2``. [km], [km], [um-2]
    """

    wavelength_nm: np.ndarray
    cext_um2: np.ndarray
    ssa: np.ndarray
    pmom_error: np.ndarray
    pmom: np.ndarray
    mu_phase: np.ndarray
    phase: np.ndarray
    layer_bottom_km: np.ndarray
    layer_top_km: np.ndarray
    layer_column_per_um2: np.ndarray

    def dtauc(self) -> np.ndarray:
        """DISORT's layer optical depths, top layer first, shape (n_wavelength, n_layers). [-]"""
        return np.outer(self.cext_um2, self.layer_column_per_um2[::-1])


def _read_header(
    head: list[str],
) -> tuple[int | None, int | None, list[float], list[list[float]]]:
    """The moment count, nphase, mu_phase and the layer lines of a DISORT file's header."""
    n_mom = nphase = None
    mu: list[float] = []
    layers: list[list[float]] = []
    for h in head:
        if h.startswith("moments: pmom_0 ... pmom_"):
            n_mom = int(h.split("(", 1)[1].split()[0])
        elif h.startswith("nphase: "):
            nphase = int(h.split()[1].rstrip(";"))
        elif h.startswith("mu_phase: "):
            mu = [float(x) for x in h.split()[1:]]
        elif h.startswith("layer: ") and not h.startswith("layer: bottom"):
            layers.append([float(x) for x in h.split()[1:]])
    return n_mom, nphase, mu, layers


def read_disort(path: str | os.PathLike[str]) -> DisortFile:
    """Read a ``disort`` file of format version 2 (:func:`disort_text`).

    Raises
    ------
    ValueError
        Not a DISORT file of version 2 written by dustoptics, or its rows do not match its
        header's counts.
    """
    text = Path(os.fspath(path)).read_text(encoding="utf-8")
    lines = text.splitlines()
    title = f"# dustoptics DISORT moments file, format version {_VERSION}"
    if not lines or lines[0] != title:
        raise ValueError(f"{os.fspath(path)!r}: not a DISORT file of format version {_VERSION}")
    n_mom, nphase, mu, layers = _read_header([ln[2:] for ln in lines if ln.startswith("# ")])
    rows = np.array(
        [[float(x) for x in ln.split()] for ln in lines if ln.strip() and ln[0] != "#"],
        dtype=np.float64,
    )
    if n_mom is None or nphase is None or len(mu) != nphase:
        raise ValueError(f"{os.fspath(path)!r}: its header lacks the moment or phase counts")
    if rows.ndim != 2 or rows.shape[1] != 4 + n_mom + nphase:
        raise ValueError(
            f"{os.fspath(path)!r}: rows must have {4 + n_mom + nphase} values "
            f"(4 + {n_mom} moments + {nphase} phase values)"
        )
    lay = np.array(layers[::-1], dtype=np.float64).reshape(-1, 3)
    return DisortFile(
        wavelength_nm=rows[:, 0],
        cext_um2=rows[:, 1],
        ssa=rows[:, 2],
        pmom_error=rows[:, 3],
        pmom=rows[:, 4 : 4 + n_mom],
        mu_phase=np.array(mu, dtype=np.float64),
        phase=rows[:, 4 + n_mom :],
        layer_bottom_km=lay[:, 0],
        layer_top_km=lay[:, 1],
        layer_column_per_um2=lay[:, 2],
    )


RECORD = register(
    Format(
        name="disort",
        summary="NAME_disort.txt: DISORT's moments and phase function (needs the expansion)",
        write=write_disort,
        suffixes=(".txt",),
        options=RTProfileOptions,
        needs=frozenset({"cross_sections", "expansion"}),
        recognise=is_rt_text,
        describe=describe_rt_text,
    )
)
