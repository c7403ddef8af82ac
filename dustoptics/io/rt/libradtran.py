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
    reads the layer file's name relative to its working directory.  A profile
    of several layers (:mod:`dustoptics.io.rt.profile`: ``--scale-height-m``,
    ``--top-altitude-m``, ``--n-layers``, ``--profile-file``) writes one layer
    file per layer, ``<name>_aerosol_layer_<i>.dat`` from the surface up, each
    with its layer's mean number density.

    The explicit file's header gives the uvspec input that runs the files as
    written (``aerosol_default``, ``aerosol_file explicit ...`` and
    ``disort_intcor moments``: uvspec's default intensity correction for
    DISORT needs a phase function on angles and refuses these files without
    it) and the wavelengths they cover (uvspec stops at the grid's edges).

These files carry the phase function only (uvspec reads no other element
from them: ``read_optprop_files`` in libRadtran 2.0.2's ``src/aerosol.c``);
for polarized solvers, the format ``libradtran-nc``
(:mod:`dustoptics.io.rt.libradtran_netcdf`) writes the phase matrix in
libRadtran's signs.

It needs what DISORT's file needs, and refuses a table without it alike
(:mod:`dustoptics.io.rt.disort`): expansion coefficients and cross-sections.
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
from dustoptics.io.rt.disort import (
    bound_text,
    disort_moments,
    header_lines,
    moment_lines,
    number_density,
)
from dustoptics.io.rt.profile import RTLayers, RTProfileOptions, coverage_lines, rt_layers

__all__ = [
    "LIBRADTRAN_EXPLICIT_SUFFIX",
    "LIBRADTRAN_LAYER_SUFFIX",
    "layer_bounds",
    "libradtran_files",
    "libradtran_texts",
    "uniform_layer",
    "uvspec_explicit_lines",
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


def uvspec_explicit_lines(stem: str) -> list[str]:
    """Header lines: the uvspec input that runs the explicit file as written."""
    return [
        "# uvspec input (libRadtran 2.0.2) that runs these files as written:",
        "#   aerosol_default",
        f"#   aerosol_file explicit {stem + LIBRADTRAN_EXPLICIT_SUFFIX}",
        "#   disort_intcor moments",
        "# (with rte_solver disort, uvspec's default, its default intensity correction needs "
        "the phase function on angles, which these files do not carry: uvspec refuses them "
        "without 'disort_intcor moments'; the libradtran-nc format's file carries it)",
    ]


def _layer_names(stem: str, n_layers: int) -> list[str]:
    if n_layers == 1:
        return [stem + LIBRADTRAN_LAYER_SUFFIX]
    width = len(str(n_layers))
    suffix = LIBRADTRAN_LAYER_SUFFIX.removesuffix(".dat")
    return [f"{stem}{suffix}_{i + 1:0{width}d}.dat" for i in range(n_layers)]


def libradtran_files(table: Any, *, layers: RTLayers | None = None) -> dict[str, str]:
    """The ``libradtran`` format's files by name: the explicit file, then one file per layer.

    Parameters
    ----------
    table : dustoptics.table.Table
        With expansion coefficients, cross-sections and ``number_density_per_m3``.
    layers : RTLayers, optional
        The vertical profile (:func:`dustoptics.io.rt.profile.rt_layers`); default one
        uniform layer from 0 to 1 km.  One layer: ``<name>_aerosol_layer.dat``; more:
        ``<name>_aerosol_layer_<i>.dat`` from the surface up.

    Raises
    ------
    ValueError
        No expansion coefficients, cross-sections or number density.
    """
    layers = rt_layers() if layers is None else layers
    wl, cext, pmom = disort_moments(table, "libradtran")
    n0 = number_density(table)
    if n0 is None:
        raise ValueError(
            f"format 'libradtran' needs an extinction coefficient [km-1], but table "
            f"{table.name!r} has no number density: give --number-density-per-m3 or "
            "--optical-depth (command line) or "
            "table.replace(cross_sections={'number_density_per_m3': ...})"
        )
    n_m3 = check_positive("number_density_per_m3", n0, unit="m-3")
    stem = safe_stem(table.name)
    names = _layer_names(stem, layers.n_layers)
    head = header_lines(table, "dustoptics libRadtran aerosol optical properties, format version 1")
    ssa = table.ssa
    moments = [[number(x) for x in floats("pmom", pmom[i])] for i in range(wl.size)]
    files: dict[str, str] = {}
    explicit = [
        *head,
        *uvspec_explicit_lines(stem),
        *coverage_lines(wl),
        f"# profile: {layers.description}; {layers.n_layers} homogeneous layers, number "
        f"density {number(n_m3)} m-3 where the relative density is 1",
        "# columns: altitude [km], optical-property file of the layer starting at that "
        "altitude (top line first; the top line only marks the top: NULL)",
        f"{number(layers.top_km[-1])} NULL",
    ]
    explicit += [
        f"{number(layers.bottom_km[i])} {names[i]}" for i in reversed(range(layers.n_layers))
    ]
    files[stem + LIBRADTRAN_EXPLICIT_SUFFIX] = "\n".join(explicit) + "\n"
    density = layers.relative_density * n_m3
    for k, name in enumerate(names):
        n_layer = float(density[k])
        ext_km = np.asarray(cext, dtype=np.float64) * (n_layer * _UM2_PER_M3_TO_PER_KM)
        where = (
            ""
            if layers.n_layers == 1
            else f" (layer {k + 1} of {layers.n_layers}, {number(layers.bottom_km[k])} .. "
            f"{number(layers.top_km[k])} km, its mean number density)"
        )
        layer = [
            *head,
            "# one layer's optical properties for uvspec's 'aerosol_file explicit' "
            f"(listed in {stem + LIBRADTRAN_EXPLICIT_SUFFIX})",
            "# columns: wavelength [nm], extinction coefficient [km-1], single scattering "
            "albedo [1], phase-function moments pmom_0 ... [1]",
            f"# extinction coefficient = N <C_ext> with N = {number(n_layer)} m-3{where} "
            "(1e-9 N[m-3] cext[um2] km-1)",
            *moment_lines(pmom),
            f"# accuracy: moments error <= {bound_text(table.expansion.expansion_error_estimate)}; "
            f"cross-sections and g relative error <= "
            f"{bound_text(table.quantity('cross_section_error_estimate'))}",
        ]
        for i in range(wl.size):
            layer.append(" ".join([number(wl[i]), number(ext_km[i]), number(ssa[i]), *moments[i]]))
        files[name] = "\n".join(layer) + "\n"
    return files


def libradtran_texts(table: Any, *, bottom_km: float = 0.0, top_km: float = 1.0) -> tuple[str, str]:
    """The ``libradtran`` format's explicit file and layer file for one uniform layer.

    Parameters
    ----------
    table : dustoptics.table.Table
        With expansion coefficients, cross-sections and ``number_density_per_m3``.
    bottom_km, top_km : float
        Altitudes of the layer's bottom and top. [km]

    Returns
    -------
    (str, str)
        The ``aerosol_file explicit`` file and the layer's optical-property file
        (:func:`libradtran_files` for a profile of several layers).

    Raises
    ------
    ValueError
        No expansion coefficients, cross-sections or number density, or
        ``top_km <= bottom_km``.
    """
    files = libradtran_files(table, layers=uniform_layer(bottom_km=bottom_km, top_km=top_km))
    explicit, layer = files.values()
    return explicit, layer


def uniform_layer(*, bottom_km: float, top_km: float) -> RTLayers:
    """One uniform layer from ``bottom_km`` to ``top_km`` [km] (checked: ``top_km > bottom_km``)."""
    bottom, top = layer_bounds(bottom_km=bottom_km, top_km=top_km)
    return RTLayers(
        bottom_km=(bottom,),
        top_km=(top,),
        column_m=(1000.0 * (top - bottom),),
        description=f"uniform from {number(bottom)} to {number(top)} km",
    )


def write_libradtran(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    bottom_km: float = 0.0,
    top_km: float = 1.0,
    layers: RTLayers | None = None,
) -> list[Path]:
    """Write the explicit file and the layer files (:func:`libradtran_files`) into ``out_dir``.

    All appear together or none (one atomic set).

    Parameters
    ----------
    bottom_km, top_km : float
        One uniform layer's bottom and top [km], when ``layers`` is not given.
    layers : RTLayers, optional
        The vertical profile; replaces ``bottom_km`` and ``top_km``.

    Returns
    -------
    list of pathlib.Path
        ``<name>_aerosol_explicit.dat`` and the layer files.

    Raises
    ------
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).
    ValueError
        As :func:`libradtran_files`.
    """
    if layers is None:
        layers = uniform_layer(bottom_km=bottom_km, top_km=top_km)
    files = libradtran_files(table, layers=layers)
    root = Path(os.fspath(out_dir))
    return write_files(
        {root / name: text.encode("utf-8") for name, text in files.items()}, overwrite=overwrite
    )


RECORD = register(
    Format(
        name="libradtran",
        summary="NAME_aerosol_*.dat: libRadtran's (needs the expansion, N0)",
        write=write_libradtran,
        suffixes=(".dat",),
        options=RTProfileOptions,
        needs=frozenset({"cross_sections", "number_density", "expansion"}),
        recognise=is_rt_text,
        describe=describe_rt_text,
    )
)
