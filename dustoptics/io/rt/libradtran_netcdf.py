"""libRadtran's netCDF optical-property file with the phase matrix (format ``libradtran-nc``).

Written atomically as one set (:func:`dustoptics.io._atomic.write_files`):

``libradtran-nc`` (:func:`write_libradtran_netcdf`) -> ``<name>.mie.cdf`` and ``<name>_aerosol_species.dat``
    The ``.mie.cdf`` file has the layout libRadtran's ``mie`` tool writes
    (libRadtran 2.0.2, ``src/mie.c``, ``create_netcdf_file`` and
    ``write_output_netcdf``) and uvspec reads (``libsrc_c/miecalc.c``,
    ``read_mie_table``), classic netCDF: dimensions ``nlam``, ``nhum`` (1:
    dust does not swell), ``nphamat`` (4), ``nmommax``, ``nthetamax``;
    variables ``wavelen`` [um], ``hum`` [%] (0), ``ext`` [km-1 cm3] (the
    extinction coefficient per particle per cm3, ``1e-3 cext[um2]``), ``ssa``,
    ``gg``, ``nmom``, ``pmom``, ``ntheta``, ``theta`` [deg] and ``phase``.
    ``pmom[l]`` are the Legendre coefficients of each element with the factor
    2 l + 1 included, ``P(mu) = sum_l pmom[l] P_l(mu)`` as libRadtran sums them
    (``mom2phase`` in ``miecalc.c``), ``pmom[0] = 1`` for P11; ``phase`` is
    the same sums at the table's angles, from 180 deg down to 0 deg (the
    reader requires 180 deg first); P11 = 4 pi F11, normalized so that
    (1/2) int P11 dmu = 1.  ``nmommax`` is one more than the longest series,
    whose ``nmom`` moments are all there is (``complete_moments = 1``).

    The four elements, in libRadtran's order for spheres (``ip_red`` in
    ``src/ancillary.c`` maps them to its six P11, P12, P33, P34, P22 = P11,
    P44 = P33; MYSTIC's phase matrix in ``libsrc_c/mystic.c`` puts P34 in row
    3, column 4 and -P34 in row 4, column 3), and their relation to the table
    (:mod:`dustoptics.scattering.expansion`)::

        P11 = 4 pi F11 = a1      P12 = 4 pi F12 = b1
        P33 = 4 pi F33 = a3      P34 = -4 pi F34 = -b2

    libRadtran's sign of P34 is that of Wiscombe's MIEV0 quantity D21 =
    -Im(S1 S2*) (``libsrc_f/MIEV.doc``), computed with van de Hulst's
    amplitudes (m = n - i k), which are the complex conjugates of Bohren &
    Huffman's: D21 = -Im(S2 S1*) in Bohren & Huffman's, whose S34 = Im(S2 S1*)
    is the table's F34.  The mie tool converts MIEV0's moments with P11 =
    (M1 + M2)/norm, P12 = (M2 - M1)/norm, P33 = 2 S21/norm, P34 = 2 D21/norm
    (``src/mie.c``, "Convert from Wiscombe definition to Evans definition").
    The IPRT phase A aerosol case (Emde et al. 2015) gives its phase matrix
    in this file layout and order (``waso.mie.cdf``: P1, P2, P3, P4 with
    ``[[P1, P2, 0, 0], [P2, P1, 0, 0], [0, 0, P3, P4], [0, 0, -P4, P3]]``),
    so its P4 is this P34: minus the table's 4 pi F34.  P12 < 0 for Rayleigh
    scattering at 90 deg in both (libRadtran's own Rayleigh moments in
    ``src/ancillary.c``: P12's l = 0 moment is -Delta/2).

    The profile ``<name>_aerosol_species.dat`` is what uvspec's
    ``aerosol_species_file`` reads: altitude [km] and the species' amount
    in the layer *starting* at that altitude's line (from it up to the line
    above), top line first, the top line's amount 0 (it only marks the top);
    by default one layer from 0 to 1 km, or the profile asked for
    (:mod:`dustoptics.io.rt.profile`), each layer holding its mean number
    density in cm-3 (``1e-6 N[m-3]``), so that uvspec's layer optical depth
    ``ext * amount * dz`` is ``N <C_ext> dz``.  libRadtran's own species files
    are per mass (ext per g m-3, the profile in g m-3); per particle number
    instead needs no particle density and gives the same product.  The uvspec
    input (``aerosol_default`` switches aerosol on, as in libRadtran's example
    ``examples/UVSPEC_AEROSOL_OPAC_POL.INP``; the library directory with its
    trailing slash, since uvspec appends the species name to it; the species
    name is the file name before ``.mie.cdf``); uvspec's default intensity
    correction reads the file's phase function, so no ``disort_intcor`` line
    is needed::

        aerosol_default
        aerosol_species_library ./
        aerosol_species_file <name>_aerosol_species.dat <name>

It needs the table's expansion coefficients (``compute_optics(...,
expansion=True)``), its cross-sections, a number density, and an angle grid
from 0 to 180 deg.  ``tests/io/rt/test_uvspec.py`` runs uvspec on these files
where ``LIBRADTRAN_DIR`` names a libRadtran build.

References
----------
.. [1] B. Mayer and A. Kylling, "Technical note: The libRadtran software
   package for radiative transfer calculations - description and examples
   of use," Atmos. Chem. Phys. 5, 1855-1877 (2005). doi:10.5194/acp-5-1855-2005
.. [2] C. Emde et al., "The libRadtran software package for radiative
   transfer calculations (version 2.0.1)," Geosci. Model Dev. 9, 1647-1672
   (2016). doi:10.5194/gmd-9-1647-2016
.. [3] C. Emde et al., "IPRT polarized radiative transfer model
   intercomparison project - Phase A," J. Quant. Spectrosc. Radiat.
   Transfer 164, 8-36 (2015). doi:10.1016/j.jqsrt.2015.05.007
.. [4] W. J. Wiscombe, "Improved Mie scattering algorithms," Appl. Opt. 19,
   1505-1509 (1980). doi:10.1364/AO.19.001505
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.polynomial import legendre

from dustoptics._files import read_checked
from dustoptics.io._atomic import FormatError, safe_stem, write_files
from dustoptics.io._text import number
from dustoptics.io.registry import Format, register
from dustoptics.io.rt.disort import bound_text, header_lines
from dustoptics.io.rt.libradtran import uniform_layer
from dustoptics.io.rt.profile import RTLayers, RTProfileOptions, coverage_lines
from dustoptics.scattering.expansion import evaluate_matrix
from dustoptics.table.provenance import _installed_version

__all__ = [
    "LIBRADTRAN_ELEMENTS",
    "LIBRADTRAN_NC_SUFFIX",
    "LIBRADTRAN_SPECIES_SUFFIX",
    "describe_libradtran_netcdf",
    "is_libradtran_netcdf",
    "libradtran_matrix_moments",
    "libradtran_netcdf_bytes",
    "libradtran_species_text",
    "write_libradtran_netcdf",
]

LIBRADTRAN_NC_SUFFIX = ".mie.cdf"
LIBRADTRAN_SPECIES_SUFFIX = "_aerosol_species.dat"

#: The phase-matrix elements of the file, in libRadtran's order (``nphamat`` = 4).
LIBRADTRAN_ELEMENTS = ("P11", "P12", "P33", "P34")

#: The ``version`` attribute libRadtran's mie tool writes; with it the reader expects a
#: wavelength dimension (without it, one wavelength per file).
_MIE_TOOL_VERSION = 20110916

#: km-1 cm3 from um2: 1e-12 m2 um-2 * 1e6 cm3 m-3 * 1e3 m km-1.
_UM2_TO_KM_CM3 = 1e-3

_FILE_INFO = "libRadtran optical properties (the mie tool's netCDF layout), written by dustoptics"


def _needs(table: Any) -> None:
    """A ValueError naming what the table lacks for this format."""
    fmt = "libradtran-nc"
    if table.expansion is None:
        raise ValueError(
            f"format {fmt!r} needs the scattering matrix's expansion coefficients, but table "
            f"{table.name!r} has none: compute it with compute_optics(..., expansion=True) "
            "(or optics.expansion = true in a configuration)"
        )
    if table.cross_sections is None:
        raise ValueError(
            f"format {fmt!r} needs extinction and scattering cross-sections; table "
            f"{table.name!r} has none (a phase function only)"
        )
    if table.cross_sections is None or table.cross_sections.number_density_per_m3 is None:
        raise ValueError(
            f"format {fmt!r} needs a number density for its aerosol species profile, but table "
            f"{table.name!r} has none: give --number-density-per-m3 (command line) or "
            "table.replace(cross_sections={'number_density_per_m3': ...})"
        )
    theta = np.asarray(table.theta_deg, dtype=np.float64)
    if theta.size < 2 or theta[0] != 0.0 or theta[-1] != 180.0:
        raise ValueError(
            f"format {fmt!r} needs angles from 0 to 180 deg (libRadtran's phase grid starts "
            f"at 180 deg); table {table.name!r} has {theta[0]!r} .. {theta[-1]!r} deg"
        )


def libradtran_matrix_moments(table: Any) -> np.ndarray:
    """Legendre coefficients of P11, P12, P33, P34 in libRadtran's normalization and signs.

    Parameters
    ----------
    table : dustoptics.table.Table
        With expansion coefficients (``compute_optics(..., expansion=True)``).

    Returns
    -------
    numpy.ndarray, shape (n_wavelengths, 4, n_order)
        ``pmom[w, p, l]`` with the factor 2 l + 1 included, so that element
        ``p`` of :data:`LIBRADTRAN_ELEMENTS` is ``sum_l pmom[w, p, l] P_l(mu)``
        (module docstring: a1, b1, a3 and -b2). [-]

    Notes
    -----
    P11's are ``alpha1``; the others are the elements evaluated from the
    generalized-spherical-function series
    (:func:`dustoptics.scattering.expansion.evaluate_matrix`) at the nodes of
    a Gauss-Legendre rule of ``n_order + 1`` nodes, projected on P_l: every
    element of the series up to order L is a polynomial of degree L in mu,
    so the rule projects it exactly.
    """

    keys = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")
    coefficients = np.stack([np.asarray(table.quantity(k), dtype=np.float64) for k in keys], 1)
    n_wl, _, n_order = coefficients.shape
    mu, weight = legendre.leggauss(n_order + 1)
    theta = np.rad2deg(np.arccos(mu))
    vander = legendre.legvander(mu, n_order - 1)  # (nodes, n_order)
    half = 0.5 * (2.0 * np.arange(n_order) + 1.0)
    out = np.empty((n_wl, 4, n_order))
    for w in range(n_wl):
        el = evaluate_matrix(coefficients[w], theta)
        out[w, 0] = coefficients[w, 0]
        for p, values in enumerate((el["b1"], el["a3"], -el["b2"]), start=1):
            out[w, p] = half * (vander.T @ (weight * values))
    return out


def libradtran_netcdf_bytes(table: Any) -> bytes:
    """The ``.mie.cdf`` file of the ``libradtran-nc`` format (see the module docstring).

    Raises
    ------
    ValueError
        No expansion coefficients, cross-sections or number density, or the
        angles do not run from 0 to 180 deg.
    """

    _needs(table)
    pmom = libradtran_matrix_moments(table)
    n_wl, n_el, n_order = pmom.shape
    nonzero = np.any(pmom != 0.0, axis=1)  # (n_wl, n_order)
    nmom = np.array([int(np.flatnonzero(row)[-1]) + 1 if row.any() else 1 for row in nonzero])
    theta_down = np.asarray(table.theta_deg, dtype=np.float64)[::-1].copy()
    mu = np.cos(np.deg2rad(theta_down))
    mu[0], mu[-1] = -1.0, 1.0
    phase = np.stack(
        [np.stack([legendre.legval(mu, pmom[w, p]) for p in range(n_el)]) for w in range(n_wl)]
    )
    buf = io.BytesIO()
    f = _netcdf_file()(buf, "w", version=1)
    f.file_info = _FILE_INFO
    f.version = np.int32(_MIE_TOOL_VERSION)
    f.complete_moments = np.int32(1)
    f.parameterization = "mie"
    f.table_name = str(table.name)
    f.input_hash = str(table.provenance.input_hash)
    f.written_by = f"dustoptics {_installed_version('dustoptics')}"
    f.phase_matrix_elements = ", ".join(LIBRADTRAN_ELEMENTS)
    f.sign_convention = (
        "P11 = 4 pi F11, P12 = 4 pi F12, P33 = 4 pi F33, P34 = -4 pi F34 with F of Bohren & "
        "Huffman (1983, F34 = Im(S2 S1*)): libRadtran's mie tool and IPRT phase A (Emde et al. "
        "2015), P34 = 2 D21 / norm of Wiscombe's MIEV0"
    )
    f.normalization = (
        "pmom includes the factor 2l+1; P(mu) = sum_l pmom[l] P_l(mu); pmom[P11, 0] = 1"
    )
    f.expansion_error_estimate = bound_text(table.expansion.expansion_error_estimate)
    f.cross_section_error_estimate = bound_text(table.quantity("cross_section_error_estimate"))
    f.createDimension("nlam", n_wl)
    f.createDimension("nmommax", n_order + 1)
    f.createDimension("nphamat", n_el)
    f.createDimension("nhum", 1)
    f.createDimension("nthetamax", theta_down.size)

    def var(name: str, kind: str, dims: tuple[str, ...], data: Any, long: str, unit: str) -> None:
        v = f.createVariable(name, kind, dims)
        v[:] = data
        v.long_name = long
        v.units = unit

    var("wavelen", "d", ("nlam",), table.wavelength_nm * 1e-3, "wavelength", "micrometer")
    var("hum", "d", ("nhum",), [0.0], "relative humidity (dust does not swell)", "per cent")
    two = ("nlam", "nhum")
    ext = np.asarray(table.cross_sections.cext_um2, dtype=np.float64) * _UM2_TO_KM_CM3
    var("ext", "d", two, ext[:, None], "extinction coefficient per particle per cm3", "km^-1 cm^3")
    var("ssa", "d", two, np.asarray(table.ssa)[:, None], "single scattering albedo", "-")
    var("gg", "d", two, np.asarray(table.g)[:, None], "asymmetry factor", "-")
    three = ("nlam", "nhum", "nphamat")
    var(
        "nmom",
        "i",
        three,
        np.repeat(nmom[:, None, None], n_el, 2),
        "number of Legendre polynomials",
        "-",
    )
    padded = np.zeros((n_wl, 1, n_el, n_order + 1))
    padded[:, 0, :, :n_order] = pmom
    var("pmom", "d", (*three, "nmommax"), padded, "Legendre polynomials", "including factor 2*l+1")
    ntheta = np.full((n_wl, 1, n_el), theta_down.size, dtype=np.int32)
    var("ntheta", "i", three, ntheta, "number of scattering angles", "-")
    thetas = np.broadcast_to(theta_down, (n_wl, 1, n_el, theta_down.size))
    var("theta", "d", (*three, "nthetamax"), thetas, "theta", "degrees")
    var("phase", "d", (*three, "nthetamax"), phase[:, None], "phase", "-")
    f.flush()
    data = buf.getvalue()
    f.close()
    return data


def libradtran_species_text(
    table: Any,
    *,
    bottom_km: float = 0.0,
    top_km: float = 1.0,
    layers: RTLayers | None = None,
) -> str:
    """The ``aerosol_species_file`` profile of the ``libradtran-nc`` format (module docstring).

    Parameters
    ----------
    table : dustoptics.table.Table
        With ``number_density_per_m3``.
    bottom_km, top_km : float
        One uniform layer's bottom and top, when ``layers`` is not given. [km]
    layers : RTLayers, optional
        The vertical profile (:func:`dustoptics.io.rt.profile.rt_layers`).

    Raises
    ------
    ValueError
        As :func:`libradtran_netcdf_bytes`, or ``top_km <= bottom_km``.
    """
    if layers is None:
        layers = uniform_layer(bottom_km=bottom_km, top_km=top_km)
    _needs(table)
    stem = safe_stem(table.name)
    n_cm3 = layers.relative_density * float(table.cross_sections.number_density_per_m3) * 1e-6
    lines = [
        *header_lines(table, "dustoptics libRadtran aerosol species profile, format version 1"),
        "# uvspec input (libRadtran 2.0.2) that runs these files as written (optical "
        f"properties: {stem}{LIBRADTRAN_NC_SUFFIX}, ext per particle per cm3; its phase "
        "function serves uvspec's default intensity correction):",
        "#   aerosol_default",
        "#   aerosol_species_library ./",
        f"#   aerosol_species_file {stem + LIBRADTRAN_SPECIES_SUFFIX} {stem}",
        *coverage_lines(table.wavelength_nm),
        f"# profile: {layers.description}; {layers.n_layers} homogeneous layers",
        f"# columns: altitude [km], number density of {stem} [cm-3] in the layer from the "
        "line's altitude up to the line above (top line first; the top line's 0 only marks "
        "the top)",
        f"{number(layers.top_km[-1])} 0",
    ]
    lines += [
        f"{number(layers.bottom_km[i])} {number(float(n_cm3[i]))}"
        for i in reversed(range(layers.n_layers))
    ]
    return "\n".join(lines) + "\n"


def write_libradtran_netcdf(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    bottom_km: float = 0.0,
    top_km: float = 1.0,
    layers: RTLayers | None = None,
) -> list[Path]:
    """Write libRadtran's polarized ``<name>.mie.cdf`` and its species profile into ``out_dir``.

    Both appear together or neither (one atomic set); see the module docstring.

    Parameters
    ----------
    bottom_km, top_km : float
        One uniform layer's bottom and top [km], when ``layers`` is not given.
    layers : RTLayers, optional
        The vertical profile; replaces ``bottom_km`` and ``top_km``.

    Returns
    -------
    list of pathlib.Path
        ``<name>.mie.cdf`` and ``<name>_aerosol_species.dat``.

    Raises
    ------
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).
    ValueError
        As :func:`libradtran_netcdf_bytes` and :func:`libradtran_species_text`.
    """
    profile = libradtran_species_text(table, bottom_km=bottom_km, top_km=top_km, layers=layers)
    data = libradtran_netcdf_bytes(table)
    root = Path(os.fspath(out_dir))
    stem = safe_stem(table.name)
    return write_files(
        {
            root / (stem + LIBRADTRAN_NC_SUFFIX): data,
            root / (stem + LIBRADTRAN_SPECIES_SUFFIX): profile.encode("utf-8"),
        },
        overwrite=overwrite,
    )


def is_libradtran_netcdf(path: Path) -> bool:
    """Whether ``path`` is a ``.mie.cdf`` file this format wrote (a look at its header only)."""
    try:
        with open(path, "rb") as f:
            head = f.read(4096)
    except OSError:
        return False
    return head.startswith(b"CDF") and _FILE_INFO.encode("ascii") in head


#: Largest ``.mie.cdf`` file ``dustoptics info`` reads: 1 GiB, 40 times the file of a
#: 48-wavelength table with 1,801 angles and every moment. [bytes]
_MAX_CDF_BYTES = 1024**3


def _netcdf_file() -> Any:
    """:class:`scipy.io.netcdf_file`."""
    # here: scipy.io (its matlab reader imports scipy.sparse) is 0.04 s of the CPU time of
    # every command that lists the formats (`dustoptics build` of any format)
    from scipy.io import netcdf_file

    return netcdf_file


def describe_libradtran_netcdf(path: Path, full: bool = True) -> str:
    """What a ``.mie.cdf`` file of the ``libradtran-nc`` format holds (``dustoptics info``)."""
    # Read whole, within a bound, then parsed from memory: a header that declares an
    # attribute or dimension of 2**31 bytes reads only what the file holds (MemoryError before).
    data = read_checked(path, limit=_MAX_CDF_BYTES)
    try:
        with _netcdf_file()(io.BytesIO(data), "r", mmap=False) as f:
            attrs = {k: v.decode() if isinstance(v, bytes) else v for k, v in f._attributes.items()}
            if not str(attrs.get("file_info", "")).startswith(_FILE_INFO):
                raise FormatError(f"{str(path)!r}: not a libRadtran file written by dustoptics")
            wl_nm = np.array(f.variables["wavelen"][:], dtype=np.float64) * 1e3
            nmom = np.array(f.variables["nmom"][:])
            theta = np.array(f.variables["theta"][0, 0, 0, :], dtype=np.float64)
            ext = np.array(f.variables["ext"][:], dtype=np.float64)
    except (OSError, ValueError, TypeError, KeyError, IndexError, MemoryError) as exc:
        raise FormatError(f"{str(path)!r}: not a readable libRadtran netCDF file ({exc})") from None
    lines = [
        f"libRadtran polarized optical properties: {path.name}",
        f"table:           {attrs.get('table_name', '?')}",
        f"input_hash:      {attrs.get('input_hash', '?')}",
        f"written by:      {attrs.get('written_by', '?')}",
        f"wavelengths:     {wl_nm.size}, {np.min(wl_nm):.6g} .. {np.max(wl_nm):.6g} nm",
        f"elements:        {attrs.get('phase_matrix_elements', '?')} (nphamat {nmom.shape[-1]})",
        f"moments:         up to {int(np.max(nmom))} per element; {attrs.get('normalization', '')}",
        f"angles:          {theta.size}, {theta[0]:.6g} .. {theta[-1]:.6g} deg",
        f"ext:             {np.min(ext):.6g} .. {np.max(ext):.6g} km^-1 cm^3 (per cm^-3)",
    ]
    if full:
        lines.append(f"signs:           {attrs.get('sign_convention', '?')}")
        lines.append(
            f"accuracy:        moments <= {attrs.get('expansion_error_estimate', '?')}, "
            f"cross-sections <= {attrs.get('cross_section_error_estimate', '?')}"
        )
    return "\n".join(lines)


RECORD = register(
    Format(
        name="libradtran-nc",
        summary="NAME.mie.cdf: libRadtran's P11, P12, P33, P34 (needs the expansion, N0)",
        write=write_libradtran_netcdf,
        suffixes=(".cdf",),
        options=RTProfileOptions,
        needs=frozenset({"cross_sections", "number_density", "expansion", "matrix"}),
        recognise=lambda path: path.suffix.lower() == ".cdf" and is_libradtran_netcdf(path),
        describe=describe_libradtran_netcdf,
    )
)
