"""Colour: CIE 1931 XYZ from spectra, linear and display sRGB, and RGB channels of a table.

Three layers, each usable on its own:

1. **Spectrum to XYZ** on any wavelength grid: :func:`xyz_weights` gives the
   matrix ``W`` with ``XYZ = W @ spectrum`` (the spectrum read linearly between
   its grid wavelengths), :func:`spectrum_to_xyz` applies it.  The
   colour-matching functions are the CIE's tabulation of the 1931 2-degree
   standard observer at 1 nm [1]_ (:func:`cmf_cie1931`, shipped as
   ``dustoptics/refractive_indices/spectra/cie1931_2deg_cmf_1nm.csv``), read
   linearly between its samples; optionally weighted by the extraterrestrial
   solar spectrum of ASTM G173-03 [3]_ (:func:`solar_irradiance_astm_g173`,
   10 nm bin means).
2. **XYZ to sRGB**: :data:`XYZ_TO_LINEAR_SRGB` (IEC 61966-2-1 [2]_),
   :func:`xyz_to_linear_srgb`,
   :func:`linear_srgb_to_xyz`, the display transfer function
   :func:`srgb_encode`, and :func:`xyz_to_display` (exposure, then encoding).
3. **Channels of a table** (:func:`channel_weights`): three rows of weights
   over the table's wavelengths that turn a spectral table into the three
   channels an RGB renderer uses, in one of three named modes:

   ``"wavelengths"``
       three wavelengths (default 680, 550, 440 nm, the seed shader's R, G, B),
       each read by linear interpolation between the table's rows;
   ``"cie1931-xyz"``
       averages weighted by x̄, ȳ, z̄ (no illuminant), put into the R, G, B
       slots.  Nonnegative weights, so each channel is itself a phase
       function; but XYZ is not an RGB space, so colours are wrong;
   ``"linear-srgb-astmg173"``
       linear sRGB weighted by the ASTM G173 solar spectrum and white-balanced
       to the sun: a renderer lit by a white sun (RGB = 1, 1, 1) that uses these
       channels for the scattering coefficient and the phase function
       reproduces the spectral single-scattering colour exactly (to rounding)
       at every scattering angle.  See :func:`channel_weights`, Notes.

:func:`single_scattering_residual` measures how far each mode is from the
spectral result, in CIE XYZ, over scattering angles.

References
----------
.. [1] CIE 015:2018, Colorimetry, 4th ed., DOI 10.25039/TR.015.2018; dataset
   CIE 018:2019, "CIE 1931 colour-matching functions, 2 degree observer",
   DOI 10.25039/CIE.DS.xvudnb9b.
.. [2] IEC 61966-2-1:1999, Multimedia systems and equipment - Colour
   measurement and management - Part 2-1: Default RGB colour space - sRGB.
.. [3] ASTM G173-03 (2012), Standard Tables for Reference Solar Spectral
   Irradiances, extraterrestrial column (NREL RReDC); 10 nm bin means as in
   E. Bruneton, "Precomputed atmospheric scattering: a new implementation"
   (2017, BSD-3-Clause).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np

from dustoptics._validation import (
    as_float_array,
    check_choice,
    check_closed_interval,
    check_positive,
)

__all__ = [
    "CHANNEL_MODES",
    "CIE1931_RANGE_NM",
    "DEFAULT_CHANNELS_NM",
    "DISPLAY_ENCODINGS",
    "ILLUMINANTS",
    "MAX_LUMINOUS_EFFICACY_LM_PER_W",
    "SOLAR_RANGE_NM",
    "SRGB_PRIMARIES_XY",
    "SRGB_WHITE_D65_XY",
    "XYZ_TO_LINEAR_SRGB",
    "ChannelWeights",
    "ColourResidual",
    "channel_phase",
    "channel_weights",
    "cmf_cie1931",
    "delta_e_ciede2000",
    "linear_srgb_to_xyz",
    "rgb_to_xyz_matrix",
    "single_scattering_residual",
    "solar_irradiance_astm_g173",
    "spectrum_to_xyz",
    "srgb_encode",
    "xyz_to_display",
    "xyz_to_lab",
    "xyz_to_linear_srgb",
    "xyz_weights",
]

#: Wavelength range of the CIE 1931 2-degree observer as the CIE tabulates it. [nm]
CIE1931_RANGE_NM = (360.0, 830.0)

#: Wavelength range of the shipped solar spectrum (48 bins of 10 nm). [nm]
SOLAR_RANGE_NM = (360.0, 840.0)

#: Illuminants that :func:`xyz_weights` can multiply the spectrum by.
ILLUMINANTS = ("equal-energy", "astm-g173")

#: Channel modes of :func:`channel_weights`, each named for what it is.
CHANNEL_MODES = ("wavelengths", "cie1931-xyz", "linear-srgb-astmg173")

#: The seed shader's R, G, B wavelengths (mode ``"wavelengths"``). [nm]
DEFAULT_CHANNELS_NM = (680.0, 550.0, 440.0)

#: Display encodings of :func:`xyz_to_display`.
DISPLAY_ENCODINGS = ("srgb", "linear")

#: Luminous efficacy of 555 nm light (CIE 015): Y times this is a photometric quantity. [lm W^-1]
MAX_LUMINOUS_EFFICACY_LM_PER_W = 683.0

#: Chromaticities (x, y) of the sRGB red, green and blue primaries (IEC 61966-2-1).
SRGB_PRIMARIES_XY = ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06))

#: Chromaticity (x, y) of the sRGB white, CIE D65 as IEC 61966-2-1 rounds it.
SRGB_WHITE_D65_XY = (0.3127, 0.3290)

_DATA_PACKAGE = "dustoptics.refractive_indices"
_CMF_FILE = "cie1931_2deg_cmf_1nm.csv"
_SOLAR_FILE = "solar_astm_g173_etr_10nm.csv"


def _read_spectrum_csv(filename: str, header: str) -> np.ndarray:
    """Rows of a shipped CSV (comment lines start with '#'), checking its column header."""
    text = resources.files(_DATA_PACKAGE).joinpath("spectra", filename).read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    if lines[0] != header:
        raise RuntimeError(
            f"shipped file spectra/{filename} has header {lines[0]!r}, expected {header!r}"
        )
    data = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    data.setflags(write=False)
    return data


@functools.cache
def _cmf_table() -> np.ndarray:
    """The CIE 1931 table, shape (471, 4): wavelength [nm], x̄, ȳ, z̄."""
    return _read_spectrum_csv(_CMF_FILE, "wavelength_nm,xbar,ybar,zbar")


@functools.cache
def _solar_table() -> np.ndarray:
    """The ASTM G173 bins, shape (48, 3): start [nm], end [nm], irradiance [W m^-2 nm^-1]."""
    return _read_spectrum_csv(_SOLAR_FILE, "bin_start_nm,bin_end_nm,irradiance_W_m-2_nm-1")


def _check_within(
    name: str, lam: np.ndarray, low: float, high: float, what: str, *, closed: bool
) -> None:
    inside = (lam >= low) & ((lam <= high) if closed else (lam < high))
    if not np.all(inside):
        bad = lam[~inside].ravel()[0]
        end = "]" if closed else ")"
        raise ValueError(
            f"{name} must lie within [{low:g}, {high:g}{end} nm, the range of {what}; got {bad:g} nm "
            "(nothing is extrapolated)"
        )


def cmf_cie1931(wavelength_nm: Any) -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions, from the CIE's 1 nm table.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths in 360-830 nm, any shape. [nm]

    Returns
    -------
    numpy.ndarray, shape ``wavelength_nm.shape + (3,)``
        x̄, ȳ, z̄ (last axis), read linearly between the 1 nm samples of CIE
        018:2019 (the module's reference [1]). [-]

    Raises
    ------
    ValueError
        For a wavelength outside 360-830 nm.

    Examples
    --------
    >>> cmf_cie1931([555.0]).round(6).tolist()
    [[0.51205, 1.0, 0.00575]]
    """
    lam = as_float_array("wavelength_nm", wavelength_nm)
    _check_within("wavelength_nm", lam, *CIE1931_RANGE_NM, "the CIE 1931 table", closed=True)
    table = _cmf_table()
    return np.stack([np.interp(lam, table[:, 0], table[:, k]) for k in (1, 2, 3)], axis=-1)


def solar_irradiance_astm_g173(wavelength_nm: Any) -> np.ndarray:
    """Extraterrestrial solar spectral irradiance, ASTM G173-03, 10 nm bin means.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths in [360, 840) nm, any shape. [nm]

    Returns
    -------
    numpy.ndarray
        The mean irradiance of the 10 nm bin [L, L + 10) holding each
        wavelength (piecewise constant), at 1 au. [W m^-2 nm^-1]

    Examples
    --------
    >>> float(solar_irradiance_astm_g173(555.0))
    1.8504
    """
    lam = as_float_array("wavelength_nm", wavelength_nm)
    _check_within("wavelength_nm", lam, *SOLAR_RANGE_NM, "the ASTM G173 bins", closed=False)
    table = _solar_table()
    index = np.searchsorted(table[:, 0], lam, side="right") - 1
    return table[index, 2]


def _breakpoints(low: float, high: float, grid: np.ndarray, illuminant: str) -> np.ndarray:
    """Every wavelength in [low, high] where the integrand's pieces change."""
    points = [grid, _cmf_table()[:, 0], np.array([low, high])]
    if illuminant == "astm-g173":
        points.append(_solar_table()[:, 0])
    merged = np.unique(np.concatenate(points))
    return merged[(merged >= low) & (merged <= high)]


def _weighted_hat_integrals(
    grid: np.ndarray, low: float, high: float, illuminant: str
) -> np.ndarray:
    """A[k, i] = int_low^high cmf_k(l) S(l) hat_i(l) dl, shape (3, grid.size). [nm]

    Between consecutive breakpoints the hat functions and the colour-matching
    functions are linear and S is constant, so the integrand is quadratic and
    2-point Gauss-Legendre is exact.
    """
    edges = _breakpoints(low, high, grid, illuminant)
    a, b = edges[:-1], edges[1:]
    half, mid = 0.5 * (b - a), 0.5 * (b + a)
    r = 1.0 / np.sqrt(3.0)
    nodes = np.concatenate([mid - half * r, mid + half * r])
    weights = np.concatenate([half, half])
    f = cmf_cie1931(nodes) * weights[:, None]
    if illuminant == "astm-g173":
        f *= solar_irradiance_astm_g173(nodes)[:, None]
    out = np.zeros((3, grid.size))
    if grid.size == 1:
        out[:, 0] = f.sum(axis=0)
        return out
    j = np.clip(np.searchsorted(grid, nodes, side="right") - 1, 0, grid.size - 2)
    t = (nodes - grid[j]) / (grid[j + 1] - grid[j])
    for k in range(3):
        np.add.at(out[k], j, (1.0 - t) * f[:, k])
        np.add.at(out[k], j + 1, t * f[:, k])
    return out


def _coverage(grid: np.ndarray, illuminant: str) -> tuple[float, float, np.ndarray]:
    """The integration range (grid intersected with the data) and each function's share in it."""
    full_low = CIE1931_RANGE_NM[0]
    full_high = CIE1931_RANGE_NM[1]
    low = max(float(grid[0]), full_low)
    high = min(float(grid[-1]), full_high)
    if low >= high:
        raise ValueError(
            f"wavelength_nm spans {grid[0]:g}-{grid[-1]:g} nm, outside the CIE 1931 observer's "
            f"{full_low:g}-{full_high:g} nm; colour is undefined"
        )
    probe = np.array([low, high])
    inside = _weighted_hat_integrals(probe, low, high, illuminant).sum(axis=1)
    total = _weighted_hat_integrals(
        np.array([full_low, full_high]), full_low, full_high, illuminant
    )
    return low, high, inside / total.sum(axis=1)


def _checked_grid(wavelength_nm: Any) -> np.ndarray:
    lam = as_float_array("wavelength_nm", wavelength_nm, ndim=1)
    if lam.size < 2 or np.any(np.diff(lam) <= 0):
        raise ValueError(
            "wavelength_nm must hold at least two strictly increasing wavelengths; got "
            f"{lam.tolist()} [nm]"
        )
    return lam


def xyz_weights(
    wavelength_nm: Any, *, illuminant: str = "equal-energy", min_coverage: float = 0.99
) -> np.ndarray:
    """Matrix that turns a spectrum sampled on a grid into CIE 1931 XYZ.

    Parameters
    ----------
    wavelength_nm : array_like, shape (n,)
        Strictly increasing wavelengths, at least two. [nm]
    illuminant : {"equal-energy", "astm-g173"}
        Multiply the spectrum by nothing, or by the ASTM G173 extraterrestrial
        solar irradiance (:func:`solar_irradiance_astm_g173`, W m^-2 nm^-1),
        as for a reflectance or a phase function lit by the sun.
    min_coverage : float
        Smallest fraction of each (illuminant-weighted) colour-matching
        function's integral over 360-830 nm the grid's range must hold. [-]

    Returns
    -------
    numpy.ndarray, shape (3, n)
        ``W`` with ``XYZ = W @ spectrum``, where the spectrum is read linearly
        between grid wavelengths: ``W[k, i] = int cmf_k S hat_i dlambda`` over
        the grid's range within 360-830 nm, exact (the integrand is piecewise
        quadratic between the merged breakpoints of the grid, the 1 nm CIE
        table and the 10 nm solar bins; 2-point Gauss-Legendre on each). [nm,
        times W m^-2 nm^-1 with the solar illuminant]

    Raises
    ------
    ValueError
        For a grid that is not increasing, outside 360-830 nm, or covering
        less than ``min_coverage`` of a function.

    Notes
    -----
    A spectral radiance in W m^-2 sr^-1 nm^-1 gives X, Y, Z in W m^-2 sr^-1;
    ``MAX_LUMINOUS_EFFICACY_LM_PER_W * Y`` is then the luminance in cd m^-2.

    Examples
    --------
    >>> w = xyz_weights([360.0, 830.0])
    >>> bool(np.allclose(w @ [1.0, 1.0], xyz_weights(np.arange(360.0, 831.0)).sum(axis=1)))
    True
    """
    check_choice("illuminant", illuminant, ILLUMINANTS)
    min_coverage = check_closed_interval("min_coverage", min_coverage, 0.0, 1.0)
    lam = _checked_grid(wavelength_nm)
    low, high, coverage = _coverage(lam, illuminant)
    if np.any(coverage < min_coverage):
        shown = ", ".join(f"{n} {c:.4f}" for n, c in zip(("xbar", "ybar", "zbar"), coverage))
        raise ValueError(
            f"wavelength_nm spans {lam[0]:g}-{lam[-1]:g} nm, which holds only ({shown}) of the "
            f"colour-matching functions' integrals over 360-830 nm; min_coverage is "
            f"{min_coverage:g} (widen the wavelength range or lower min_coverage)"
        )
    return _weighted_hat_integrals(lam, low, high, illuminant)


def spectrum_to_xyz(
    wavelength_nm: Any,
    spectrum: Any,
    *,
    illuminant: str = "equal-energy",
    min_coverage: float = 0.99,
) -> np.ndarray:
    """CIE 1931 XYZ of spectra sampled on any wavelength grid.

    Parameters
    ----------
    wavelength_nm : array_like, shape (n,)
        Strictly increasing wavelengths. [nm]
    spectrum : array_like, shape (..., n)
        Spectra, wavelength on the last axis (e.g. spectral radiance
        [W m^-2 sr^-1 nm^-1]), read linearly between grid wavelengths.
    illuminant, min_coverage
        As for :func:`xyz_weights`.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        X, Y, Z: ``int spectrum * S * cmf dlambda`` [spectrum unit times nm].

    Examples
    --------
    >>> lam = np.arange(360.0, 831.0, 10.0)
    >>> xyz = spectrum_to_xyz(lam, np.ones(lam.size))
    >>> bool(np.allclose(xyz / xyz.sum(), 1 / 3, atol=1e-3))   # equal-energy white E
    True
    """
    lam = _checked_grid(wavelength_nm)
    values = as_float_array("spectrum", spectrum)
    if values.ndim == 0 or values.shape[-1] != lam.size:
        raise ValueError(
            f"spectrum must have the wavelength ({lam.size} values) on its last axis; got shape "
            f"{values.shape}"
        )
    w = xyz_weights(lam, illuminant=illuminant, min_coverage=min_coverage)
    return np.einsum("...i,ki->...k", values, w)


def rgb_to_xyz_matrix(primaries_xy: Any, white_xy: Any) -> np.ndarray:
    """RGB -> XYZ matrix of an RGB space from its primaries' and white's chromaticities.

    Columns are the primaries' XYZ scaled so that RGB = (1, 1, 1) is the white
    at Y = 1 (the standard construction, e.g. SMPTE RP 177).

    >>> m = rgb_to_xyz_matrix(SRGB_PRIMARIES_XY, SRGB_WHITE_D65_XY)
    >>> m.sum(axis=1).round(4).tolist()   # D65 white, Y = 1
    [0.9505, 1.0, 1.0891]
    """
    p = np.array([[x / y, 1.0, (1.0 - x - y) / y] for x, y in primaries_xy]).T
    wx, wy = white_xy
    white = np.array([wx / wy, 1.0, (1.0 - wx - wy) / wy])
    return p * np.linalg.solve(p, white)[None, :]


#: XYZ -> linear sRGB (rows R, G, B) as IEC 61966-2-1 prints it (four digits;
#: the normative encoding matrix, also colour-science's and Bruneton's).  It
#: differs from the matrix derived from the primaries and the D65 white
#: (:func:`rgb_to_xyz_matrix`) by at most 4e-4 (tested), the standard's rounding.
XYZ_TO_LINEAR_SRGB = np.array(
    [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]]
)
XYZ_TO_LINEAR_SRGB.setflags(write=False)
_LINEAR_SRGB_TO_XYZ = np.linalg.inv(XYZ_TO_LINEAR_SRGB)
_LINEAR_SRGB_TO_XYZ.setflags(write=False)


def xyz_to_linear_srgb(xyz: Any) -> np.ndarray:
    """Linear sRGB (D65 white, Y = 1 white -> RGB = 1) of CIE XYZ, last axis 3.

    Values outside [0, 1] (out of gamut or brighter than white) are kept.

    >>> xyz_to_linear_srgb([0.95047, 1.0, 1.08883]).round(3).tolist()
    [1.0, 1.0, 1.0]
    """
    values = as_float_array("xyz", xyz)
    if values.ndim == 0 or values.shape[-1] != 3:
        raise ValueError(f"xyz must have X, Y, Z on its last axis; got shape {values.shape}")
    return values @ XYZ_TO_LINEAR_SRGB.T


def linear_srgb_to_xyz(rgb: Any) -> np.ndarray:
    """CIE XYZ of linear sRGB, last axis 3 (inverse of :func:`xyz_to_linear_srgb`)."""
    values = as_float_array("rgb", rgb)
    if values.ndim == 0 or values.shape[-1] != 3:
        raise ValueError(f"rgb must have R, G, B on its last axis; got shape {values.shape}")
    return values @ _LINEAR_SRGB_TO_XYZ.T


def srgb_encode(linear: Any) -> np.ndarray:
    """sRGB display encoding (IEC 61966-2-1 transfer function) of values in [0, 1].

    ``12.92 c`` for ``c <= 0.0031308``, else ``1.055 c^(1/2.4) - 0.055``.

    Raises
    ------
    ValueError
        For values outside [0, 1] (clip or scale first, e.g. with
        :func:`xyz_to_display`).

    >>> srgb_encode([0.0, 0.0031308, 0.5, 1.0]).round(6).tolist()
    [0.0, 0.04045, 0.735357, 1.0]
    """
    c = as_float_array("linear", linear)
    if np.any((c < 0.0) | (c > 1.0)):
        raise ValueError("linear must lie in [0, 1] to be display-encoded; clip or scale it first")
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def xyz_to_display(xyz: Any, *, exposure: float = 1.0, encoding: str = "srgb") -> np.ndarray:
    """Display sRGB values of CIE XYZ: exposure, clip to [0, 1], encode.

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        Tristimulus values; ``Y * exposure = 1`` is display white.
    exposure : float
        Scale applied before clipping (> 0). [-]
    encoding : {"srgb", "linear"}
        IEC 61966-2-1 transfer function, or none.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        R, G, B in [0, 1]. Out-of-gamut and too-bright values are clipped
        per channel (a display cannot show them; no hue-preserving mapping).
    """
    exposure = check_positive("exposure", exposure)
    check_choice("encoding", encoding, DISPLAY_ENCODINGS)
    rgb = np.clip(exposure * xyz_to_linear_srgb(xyz), 0.0, 1.0)
    return srgb_encode(rgb) if encoding == "srgb" else rgb


@dataclass(frozen=True)
class ChannelWeights:
    """Three channels of a spectral table as weights over its wavelengths.

    Attributes
    ----------
    mode : str
        One of :data:`CHANNEL_MODES`.
    weights : numpy.ndarray, shape (3, n_wavelength)
        Channel ``c`` of a quantity ``q`` tabulated over wavelength is
        ``weights[c] @ q``; each row sums to 1. Nonnegative except in mode
        ``"linear-srgb-astmg173"`` (the sRGB matching functions have negative
        lobes). [-]
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        The grid the weights apply to. [nm]
    centroid_nm : numpy.ndarray, shape (3,)
        ``weights @ wavelength_nm``: the channel wavelength, or each band's
        weighted mean wavelength. [nm]
    names : tuple of str
        What each channel is (e.g. ``"680 nm"``, ``"xbar"``, ``"R"``).
    descriptions : tuple of str
        How each channel is made, one line each.
    coverage : numpy.ndarray, shape (3,)
        Fraction of each weighting function's 360-830 nm integral inside the
        grid (1 for ``"wavelengths"``). [-]
    """

    mode: str
    weights: np.ndarray
    wavelength_nm: np.ndarray
    centroid_nm: np.ndarray
    names: tuple[str, ...]
    descriptions: tuple[str, ...]
    coverage: np.ndarray


def _fmt_nm(value: float) -> str:
    return f"{value:.6g}"


def _wavelength_channels(lam: np.ndarray, channels_nm: Any) -> tuple[np.ndarray, tuple[str, ...]]:
    """Linear-interpolation weights of three channel wavelengths over the grid."""
    ch = as_float_array("channels_nm", channels_nm)
    if ch.shape != (3,):
        raise ValueError(
            f"channels_nm must be three wavelengths (one per channel) [nm]; got {ch.tolist()}"
        )
    low, high = float(lam[0]), float(lam[-1])
    weights = np.zeros((3, lam.size))
    descriptions = []
    for c, wl in enumerate(ch):
        if not low <= wl <= high:
            raise ValueError(
                f"channels_nm[{c}] = {wl:g} nm is outside the table's wavelength range "
                f"{_fmt_nm(low)}-{_fmt_nm(high)} nm; nothing is extrapolated (choose channels "
                "within the range or compute the table at wider wavelengths)"
            )
        hit = np.flatnonzero(lam == wl)
        if hit.size:
            weights[c, hit[0]] = 1.0
            descriptions.append(f"{_fmt_nm(wl)} nm: the table's row at {_fmt_nm(wl)} nm")
            continue
        i = int(np.searchsorted(lam, wl)) - 1
        a, b = float(lam[i]), float(lam[i + 1])
        t = (wl - a) / (b - a)
        weights[c, i], weights[c, i + 1] = 1.0 - t, t
        descriptions.append(
            f"{_fmt_nm(wl)} nm: linear in wavelength between the table's rows at "
            f"{_fmt_nm(a)} nm (weight {1.0 - t:.6g}) and {_fmt_nm(b)} nm (weight {t:.6g})"
        )
    return weights, tuple(descriptions)


def channel_weights(
    wavelength_nm: Any,
    *,
    mode: str,
    channels_nm: Any = None,
    min_coverage: float = 0.99,
) -> ChannelWeights:
    """Weights that turn a table's wavelength rows into three renderer channels.

    Parameters
    ----------
    wavelength_nm : array_like, shape (n,)
        The table's strictly increasing wavelengths. [nm]
    mode : {"wavelengths", "cie1931-xyz", "linear-srgb-astmg173"}
        ``"wavelengths"``: three wavelengths ``channels_nm`` (default
        680, 550, 440 nm), read linearly between rows.
        ``"cie1931-xyz"``: averages weighted by x̄, ȳ, z̄, no illuminant
        (in R, G, B order: long, middle, short).
        ``"linear-srgb-astmg173"``: linear sRGB channels of the table lit by
        the ASTM G173 extraterrestrial sun, each divided by the sun's own
        linear sRGB value (white balance to the sun).
    channels_nm : sequence of 3 floats, optional
        Only for ``"wavelengths"``. [nm]
    min_coverage : float
        For the colour modes: smallest fraction of each weighting function's
        integral over 360-830 nm the grid must hold. [-]

    Returns
    -------
    ChannelWeights

    Notes
    -----
    In mode ``"linear-srgb-astmg173"``, with ``A = xyz_weights(grid,
    illuminant="astm-g173")`` and ``M = XYZ_TO_LINEAR_SRGB``,
    ``weights[c, i] = (M A)[c, i] / sum_i (M A)[c, i]``.  The denominator is the
    sun's linear sRGB, so a renderer that draws the sun as white (1, 1, 1) and
    forms single scattering as ``beta_c * P_c(theta)`` per channel, with
    ``beta_c = weights[c] @ beta`` and ``P_c`` from :func:`channel_phase`,
    outputs ``M @ XYZ_spectral(theta) / RGB_sun``: exactly the spectral
    single-scattering colour (to rounding), white-balanced to the sun.
    The product of two channel values is not the channel of a product, so the
    identity is exact for one scattering event in an optically thin medium;
    extinction along the paths (``exp(-tau(lambda))``) adds the usual RGB
    rendering error, which this module does not hide.

    Examples
    --------
    >>> w = channel_weights(np.arange(360.0, 831.0, 10.0), mode="linear-srgb-astmg173")
    >>> bool(np.allclose(w.weights.sum(axis=1), 1.0))
    True
    """
    check_choice("mode", mode, CHANNEL_MODES)
    lam = _checked_grid(wavelength_nm)
    if mode != "wavelengths" and channels_nm is not None:
        raise ValueError(f"channels_nm is only for mode='wavelengths'; got mode={mode!r}")
    if mode == "wavelengths":
        weights, descriptions = _wavelength_channels(
            lam, DEFAULT_CHANNELS_NM if channels_nm is None else channels_nm
        )
        names = tuple(f"{_fmt_nm(w)} nm" for w in weights @ lam)
        coverage = np.ones(3)
    else:
        illuminant = "equal-energy" if mode == "cie1931-xyz" else "astm-g173"
        a = xyz_weights(lam, illuminant=illuminant, min_coverage=min_coverage)
        _, _, coverage = _coverage(lam, illuminant)
        span = f"{_fmt_nm(max(lam[0], 360.0))}-{_fmt_nm(min(lam[-1], 830.0))} nm"
        if mode == "cie1931-xyz":
            names = ("xbar", "ybar", "zbar")
            raw = a
            descriptions = tuple(
                f"average weighted by CIE 1931 2-deg {n} (CIE 1 nm table, no illuminant) over {span}"
                for n in names
            )
        else:
            names = ("R", "G", "B")
            raw = XYZ_TO_LINEAR_SRGB @ a
            descriptions = tuple(
                f"linear sRGB {n} of the table lit by the ASTM G173 extraterrestrial sun over {span}, "
                f"divided by the sun's own {n} (white sun)"
                for n in names
            )
        weights = raw / raw.sum(axis=1, keepdims=True)
    centroid = weights @ lam
    for array in (weights, centroid, coverage, lam):
        array.setflags(write=False)
    return ChannelWeights(
        mode=mode,
        weights=weights,
        wavelength_nm=lam,
        centroid_nm=centroid,
        names=names,
        descriptions=descriptions,
        coverage=coverage,
    )


def channel_phase(channels: ChannelWeights, phase: Any, *, csca_um2: Any = None) -> np.ndarray:
    """Phase function of each channel, weighted by scattering if cross-sections are given.

    Parameters
    ----------
    channels : ChannelWeights
    phase : array_like, shape (n_wavelength, n_angles)
        Phase function rows over wavelength. [sr^-1]
    csca_um2 : array_like, shape (n_wavelength,), optional
        Scattering cross-section per wavelength. [um^2]

    Returns
    -------
    numpy.ndarray, shape (3, n_angles)
        ``P_c = sum_i W_ci csca_i P_i / sum_i W_ci csca_i`` (with ``csca = 1``
        when not given), so that ``csca_c P_c`` is the channel of
        ``csca P``: the quantity single scattering needs.  Each ``P_c`` keeps
        the normalization of the rows. [sr^-1]
    """
    p = as_float_array("phase", phase, ndim=2)
    n = channels.wavelength_nm.size
    if p.shape[0] != n:
        raise ValueError(f"phase must have {n} rows (one per wavelength); got shape {p.shape}")
    if csca_um2 is None:
        return channels.weights @ p
    s = as_float_array("csca_um2", csca_um2, ndim=1)
    if s.shape != (n,):
        raise ValueError(f"csca_um2 must have {n} values; got shape {s.shape}")
    ws = channels.weights * s[None, :]
    return (ws @ p) / ws.sum(axis=1, keepdims=True)


@dataclass(frozen=True)
class ColourResidual:
    """Spectral vs RGB single-scattering colour over scattering angles.

    Attributes
    ----------
    mode : str
        The channel mode compared.
    theta_deg : numpy.ndarray, shape (n_angles,)
        Scattering angles. [deg]
    xyz_spectral : numpy.ndarray, shape (n_angles, 3)
        ``int xyz(l) E_sun(l) csca(l) P(l, theta) dl``, ASTM G173 sun. [um^2 W m^-2 sr^-1]
    xyz_rgb : numpy.ndarray, shape (n_angles, 3)
        What the RGB renderer shows, lit by a white sun, back in XYZ:
        ``M^-1 (RGB_sun * csca_c * P_c)``. [um^2 W m^-2 sr^-1]
    relative_error : numpy.ndarray, shape (n_angles, 3)
        ``(xyz_rgb - xyz_spectral) / Y_spectral`` at each angle. [-]
    max_relative_error : float
        Largest absolute relative error over angles and X, Y, Z. [-]
    median_relative_error : float
        Median over angles of the largest of the three. [-]
    """

    mode: str
    theta_deg: np.ndarray
    xyz_spectral: np.ndarray
    xyz_rgb: np.ndarray
    relative_error: np.ndarray
    max_relative_error: float
    median_relative_error: float


def single_scattering_residual(
    wavelength_nm: Any,
    theta_deg: Any,
    phase: Any,
    *,
    mode: str,
    csca_um2: Any = None,
    channels_nm: Any = None,
) -> ColourResidual:
    """How well three channels reproduce the spectral single-scattering colour.

    Parameters
    ----------
    wavelength_nm : array_like, shape (n,)
        The table's wavelengths; must cover 360-830 nm to 99 %. [nm]
    theta_deg : array_like, shape (m,)
        The table's scattering angles. [deg]
    phase : array_like, shape (n, m)
        Phase function rows. [sr^-1]
    mode : str
        A channel mode (:data:`CHANNEL_MODES`).
    csca_um2 : array_like, shape (n,), optional
        Scattering cross-sections (1 if not given). [um^2]
    channels_nm : sequence of 3 floats, optional
        For mode ``"wavelengths"``. [nm]

    Returns
    -------
    ColourResidual

    Notes
    -----
    The spectral truth is the colour of once-scattered sunlight:
    ``XYZ(theta) = A @ (csca P(theta))`` with ``A = xyz_weights(grid,
    illuminant="astm-g173")``.  The renderer draws the sun white and forms
    ``csca_c P_c(theta)`` in each channel; to compare, its output is
    converted back with the sun's colour: ``XYZ_rgb = M^-1 (RGB_sun *
    csca_c P_c)``, ``RGB_sun = M A 1``.  For a grey table (no wavelength
    dependence) every mode is exact; the residual measures what each mode does
    with the table's colour.
    """
    lam = _checked_grid(wavelength_nm)
    theta = as_float_array("theta_deg", theta_deg, ndim=1)
    p = as_float_array("phase", phase, ndim=2)
    if p.shape != (lam.size, theta.size):
        raise ValueError(f"phase must have shape ({lam.size}, {theta.size}); got {p.shape}")
    s = np.ones(lam.size) if csca_um2 is None else as_float_array("csca_um2", csca_um2, ndim=1)
    channels = channel_weights(lam, mode=mode, channels_nm=channels_nm)
    a = xyz_weights(lam, illuminant="astm-g173")
    xyz_spec = (a @ (s[:, None] * p)).T
    rgb_sun = XYZ_TO_LINEAR_SRGB @ a.sum(axis=1)
    per_channel = (channels.weights @ s)[:, None] * channel_phase(channels, p, csca_um2=s)
    xyz_rgb = linear_srgb_to_xyz((rgb_sun[:, None] * per_channel).T)
    rel = (xyz_rgb - xyz_spec) / xyz_spec[:, 1:2]
    worst = np.abs(rel).max(axis=1)
    return ColourResidual(
        mode=mode,
        theta_deg=theta,
        xyz_spectral=xyz_spec,
        xyz_rgb=xyz_rgb,
        relative_error=rel,
        max_relative_error=float(worst.max()),
        median_relative_error=float(np.median(worst)),
    )


def xyz_to_lab(xyz: Any, white_xyz: Any) -> np.ndarray:
    """CIE 1976 L*a*b* of CIE XYZ relative to a reference white (CIE 15:2004, Eq. 8.1-8.3).

    ``L* = 116 f(Y/Yn) - 16``, ``a* = 500 (f(X/Xn) - f(Y/Yn))``,
    ``b* = 200 (f(Y/Yn) - f(Z/Zn))``, with ``f(t) = t^(1/3)`` above
    ``(6/29)^3`` and ``t / (3 (6/29)^2) + 4/29`` below.  Last axis X, Y, Z;
    ``white_xyz`` broadcasts against ``xyz``.

    >>> xyz_to_lab([0.95047, 1.0, 1.08883], [0.95047, 1.0, 1.08883]).round(6).tolist()
    [100.0, 0.0, 0.0]
    """
    values = as_float_array("xyz", xyz)
    white = as_float_array("white_xyz", white_xyz)
    if values.ndim == 0 or values.shape[-1] != 3:
        raise ValueError(f"xyz must have X, Y, Z on its last axis; got shape {values.shape}")
    if white.ndim == 0 or white.shape[-1] != 3 or not np.all(white > 0):
        raise ValueError(f"white_xyz must be three positive values on its last axis; got {white!r}")
    t = values / white
    delta = 6.0 / 29.0
    f = np.where(t > delta**3, np.cbrt(np.maximum(t, delta**3)), t / (3 * delta**2) + 4.0 / 29.0)
    return np.stack(
        [
            116.0 * f[..., 1] - 16.0,
            500.0 * (f[..., 0] - f[..., 1]),
            200.0 * (f[..., 1] - f[..., 2]),
        ],
        axis=-1,
    )


def delta_e_ciede2000(lab1: Any, lab2: Any) -> np.ndarray:
    """CIE Delta E 2000 colour difference of two L*a*b* colours (last axis L, a, b). [-]

    The formula of CIE 142-2001 as written out, with its worked pairs, by
    G. Sharma, W. Wu and E. N. Dalal, "The CIEDE2000 color-difference formula:
    implementation notes, supplementary test data, and mathematical
    observations," Color Res. Appl. 30(1), 21-30 (2005), doi:10.1002/col.20070
    (parametric factors kL = kC = kH = 1; hue mean and difference as in their
    Eq. 10-14).
    """
    a = as_float_array("lab1", lab1)
    b = as_float_array("lab2", lab2)
    if a.shape[-1:] != (3,) or b.shape[-1:] != (3,):
        raise ValueError("lab1 and lab2 must have L, a, b on their last axis")
    l1, a1, b1 = a[..., 0], a[..., 1], a[..., 2]
    l2, a2, b2 = b[..., 0], b[..., 1], b[..., 2]
    c_bar = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    g = 0.5 * (1.0 - np.sqrt(c_bar**7 / (c_bar**7 + 25.0**7)))
    a1p, a2p = (1.0 + g) * a1, (1.0 + g) * a2
    c1p, c2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.degrees(np.arctan2(b1, a1p)) % 360.0
    h2p = np.degrees(np.arctan2(b2, a2p)) % 360.0
    dl = l2 - l1
    dc = c2p - c1p
    zero = c1p * c2p == 0.0
    dh = h2p - h1p
    dh = np.where(dh > 180.0, dh - 360.0, np.where(dh < -180.0, dh + 360.0, dh))
    dh = np.where(zero, 0.0, dh)
    dhh = 2.0 * np.sqrt(c1p * c2p) * np.sin(np.radians(dh) / 2.0)
    l_bar = 0.5 * (l1 + l2)
    cp_bar = 0.5 * (c1p + c2p)
    hsum = h1p + h2p
    far = np.abs(h1p - h2p) > 180.0
    h_bar = np.where(far, np.where(hsum < 360.0, hsum + 360.0, hsum - 360.0), hsum) / 2.0
    h_bar = np.where(zero, hsum, h_bar)
    t = (
        1.0
        - 0.17 * np.cos(np.radians(h_bar - 30.0))
        + 0.24 * np.cos(np.radians(2.0 * h_bar))
        + 0.32 * np.cos(np.radians(3.0 * h_bar + 6.0))
        - 0.20 * np.cos(np.radians(4.0 * h_bar - 63.0))
    )
    d_theta = 30.0 * np.exp(-(((h_bar - 275.0) / 25.0) ** 2))
    r_c = 2.0 * np.sqrt(cp_bar**7 / (cp_bar**7 + 25.0**7))
    s_l = 1.0 + 0.015 * (l_bar - 50.0) ** 2 / np.sqrt(20.0 + (l_bar - 50.0) ** 2)
    s_c = 1.0 + 0.045 * cp_bar
    s_h = 1.0 + 0.015 * cp_bar * t
    r_t = -np.sin(np.radians(2.0 * d_theta)) * r_c
    tl, tc, th = dl / s_l, dc / s_c, dhh / s_h
    return np.sqrt(tl**2 + tc**2 + th**2 + r_t * tc * th)
