"""Colour-matching functions and band weights over a table's wavelengths.

The CIE 1931 2-degree colour-matching functions x̄, ȳ, z̄ are evaluated with the
multi-lobe analytic fit of Wyman, Sloan and Shirley [1]_ (their Equation 4), so
the package carries no tabulated colour data: each function is a sum of
piecewise Gaussians

.. math::

    g(\\lambda; \\mu, \\sigma_1, \\sigma_2) =
        \\exp\\left(-\\tfrac{1}{2} (\\lambda - \\mu)^2 / \\sigma^2\\right),
    \\quad \\sigma = \\sigma_1 \\text{ if } \\lambda < \\mu \\text{ else } \\sigma_2,

with the published coefficients (wavelengths in nm).  Against the CIE's 5 nm
tabulation the fit is within 0.024 of every value (z̄ at 425 nm; the functions
peak at 1.0-1.8), and its integrals over 360-830 nm are within 0.1 % of the
tabulated ones.  [1]_ shows its errors graphically and states that they are
smaller than the spread between the observers whose data make up the CIE
standard.

:func:`band_weights` turns the functions into weights over a table's
wavelength grid, so that a band average of any tabulated quantity is a
weighted sum of its rows (see its Notes for the exact definition).

References
----------
.. [1] C. Wyman, P.-P. Sloan and P. Shirley, "Simple Analytic Approximations to
   the CIE XYZ Color Matching Functions", Journal of Computer Graphics
   Techniques 2(2), 1-11 (2013), https://jcgt.org/published/0002/02/01/
.. [2] CIE 015:2004, Colorimetry, 3rd edition (the 360-830 nm range of the
   tabulated 1931 standard observer).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from dustoptics._validation import as_float_array, check_choice, check_closed_interval

__all__ = [
    "CIE1931_RANGE_NM",
    "CMF_MODELS",
    "BandWeights",
    "band_weights",
    "cmf_cie1931_wyman2013",
]

#: Wavelength range of the CIE 1931 2-degree observer as tabulated by the CIE [2]. [nm]
CIE1931_RANGE_NM = (360.0, 830.0)

# Wyman, Sloan & Shirley (2013), Equation 4: (amplitude, mu [nm], sigma below mu
# [nm], sigma above mu [nm]) of each lobe of x̄, ȳ and z̄.
_LOBES: tuple[tuple[tuple[float, float, float, float], ...], ...] = (
    ((1.056, 599.8, 37.9, 31.0), (0.362, 442.0, 16.0, 26.7), (-0.065, 501.1, 20.4, 26.2)),
    ((0.821, 568.8, 46.9, 40.5), (0.286, 530.9, 16.3, 31.1)),
    ((1.217, 437.0, 11.8, 36.0), (0.681, 459.0, 26.0, 13.8)),
)

#: Colour-matching-function models :func:`band_weights` accepts.
CMF_MODELS = ("cie1931",)

#: Names of the three colour-matching functions, in channel order.
CMF_NAMES = ("xbar", "ybar", "zbar")

# Quadrature of the band integrals: Gauss-Legendre on pieces at most this wide,
# with piece boundaries at every lobe centre (where the fit's second derivative
# jumps), so each piece integrates a smooth function.  16 nodes on <= 5 nm of a
# Gaussian with sigma >= 11.8 nm: error far below float64 rounding.
_GL_NODES = 16
_MAX_PIECE_NM = 5.0


def cmf_cie1931_wyman2013(wavelength_nm: Any) -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions, multi-lobe fit of Wyman et al. 2013.

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelengths, any shape. [nm]

    Returns
    -------
    numpy.ndarray, shape ``wavelength_nm.shape + (3,)``
        x̄, ȳ, z̄ (last axis), dimensionless, ȳ peaking near 1 at 555 nm. [-]

    Notes
    -----
    The formula is defined at every wavelength, but the standard observer is
    only tabulated over 360-830 nm (:data:`CIE1931_RANGE_NM`), so
    :func:`band_weights` uses the fit on that range only (outside it the fit
    is below 5e-4).  Although x̄ has a negative lobe (at 501.1 nm), the sum is
    positive on 360-830 nm (smallest value 1.1e-12, at 830 nm).

    Examples
    --------
    >>> bool(abs(cmf_cie1931_wyman2013(555.0)[1] - 1.0) < 0.01)
    True
    """
    lam = as_float_array("wavelength_nm", wavelength_nm)
    out = np.zeros(lam.shape + (3,), dtype=np.float64)
    for c, lobes in enumerate(_LOBES):
        for amplitude, mu, sigma_low, sigma_high in lobes:
            sigma = np.where(lam < mu, sigma_low, sigma_high)
            out[..., c] += amplitude * np.exp(-0.5 * ((lam - mu) / sigma) ** 2)
    return out


@dataclass(frozen=True)
class BandWeights:
    """Weights of three colour bands over a wavelength grid.

    Attributes
    ----------
    weights : numpy.ndarray, shape (3, n_wavelength)
        Nonnegative; each row sums to 1 (to rounding).  The band average of a
        tabulated quantity ``q`` (rows over wavelength) is ``weights @ q``. [-]
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        The grid the weights apply to. [nm]
    centroid_nm : numpy.ndarray, shape (3,)
        Weighted mean wavelength of each band over the covered range. [nm]
    coverage : numpy.ndarray, shape (3,)
        Fraction of each function's integral over 360-830 nm that lies within
        the grid's range. [-]
    names : tuple of str
        The weighting function of each band (``"xbar"``, ``"ybar"``, ``"zbar"``).
    model : str
        The colour-matching model (``"cie1931"``: Wyman et al. 2013 fit).
    """

    weights: np.ndarray
    wavelength_nm: np.ndarray
    centroid_nm: np.ndarray
    coverage: np.ndarray
    names: tuple[str, ...]
    model: str


def _gauss_legendre(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights on [a_k, b_k] for each piece k; shapes (n_pieces, _GL_NODES)."""
    x, w = np.polynomial.legendre.leggauss(_GL_NODES)
    half = 0.5 * (b - a)[:, None]
    mid = 0.5 * (b + a)[:, None]
    return mid + half * x[None, :], half * w[None, :]


def _pieces(low: float, high: float) -> tuple[np.ndarray, np.ndarray]:
    """Split [low, high] at lobe centres and into pieces at most _MAX_PIECE_NM wide."""
    cuts = sorted({mu for lobes in _LOBES for _, mu, _, _ in lobes if low < mu < high})
    edges = [low, *cuts, high]
    starts, ends = [], []
    for a, b in pairwise(edges):
        n = max(1, int(np.ceil((b - a) / _MAX_PIECE_NM)))
        e = np.linspace(a, b, n + 1)
        starts.append(e[:-1])
        ends.append(e[1:])
    return np.concatenate(starts), np.concatenate(ends)


def _cmf_integral(low: float, high: float) -> np.ndarray:
    """int_low^high of x̄, ȳ, z̄ (fit), shape (3,). [nm]"""
    a, b = _pieces(low, high)
    nodes, weights = _gauss_legendre(a, b)
    return np.einsum("pk,pkc->c", weights, cmf_cie1931_wyman2013(nodes))


def band_weights(
    wavelength_nm: Any,
    *,
    model: str = "cie1931",
    min_coverage: float = 0.99,
) -> BandWeights:
    """Weights that average a tabulated spectrum over the three colour bands.

    Parameters
    ----------
    wavelength_nm : array_like, shape (n_wavelength,)
        Strictly increasing wavelengths of the table, at least two. [nm]
    model : {"cie1931"}
        Colour-matching functions: the CIE 1931 2-degree observer, evaluated
        with the analytic fit of Wyman, Sloan & Shirley 2013
        (:func:`cmf_cie1931_wyman2013`).
    min_coverage : float
        Smallest accepted fraction of each function's integral over
        360-830 nm that the grid's range must hold (default 0.99: at most 1 %
        of a band's weight may fall outside the table). [-]

    Returns
    -------
    BandWeights
        Weights for the bands weighted by x̄, ȳ and z̄, in that order (long,
        middle and short wavelengths, the roles of R, G and B).

    Raises
    ------
    ValueError
        If the grid is not increasing, has fewer than two wavelengths, does
        not overlap 360-830 nm, or covers less than ``min_coverage`` of a band
        (the message gives each band's coverage and the grid's range).

    Notes
    -----
    Band ``c`` of a quantity ``q(lambda)`` tabulated at ``lambda_i`` is

    .. math::

        q_c = \\frac{\\int q(\\lambda)\\, \\bar w_c(\\lambda)\\, d\\lambda}
                   {\\int \\bar w_c(\\lambda)\\, d\\lambda},

    both integrals over the grid's range intersected with 360-830 nm, with
    ``w_c`` = x̄, ȳ, z̄ and ``q`` read by linear interpolation between grid
    wavelengths (the interpolation used for single-wavelength channels).  Then
    ``q_c = sum_i W_ci q_i`` with ``W_ci`` the integral of ``w_c`` times the
    hat function of node ``i``, divided by the sum over ``i``; the integrals
    are done by 16-point Gauss-Legendre on pieces at most 5 nm wide split at
    the lobe centres, exact to float64 rounding.  No illuminant weights the
    bands (equal-energy white).

    Why x̄, ȳ, z̄ and not r̄, ḡ, b̄: the weights must be nonnegative so that a
    band of phase functions is a convex combination of phase functions, hence
    itself nonnegative and normalized (2 pi int P dmu = 1).  The fit of x̄, ȳ
    and z̄ is positive on 360-830 nm (tested); sRGB matching functions have
    negative lobes and would give channels that are not phase functions.
    The channels are averages, not tristimulus values: a renderer uses each as
    the phase function of its long, middle or short channel.

    Examples
    --------
    >>> w = band_weights(np.arange(360.0, 831.0, 10.0))
    >>> bool(np.allclose(w.weights.sum(axis=1), 1.0))
    True
    """
    check_choice("model", model, CMF_MODELS)
    min_coverage = check_closed_interval("min_coverage", min_coverage, 0.0, 1.0)
    lam = as_float_array("wavelength_nm", wavelength_nm, ndim=1)
    if lam.size < 2 or np.any(np.diff(lam) <= 0):
        raise ValueError(
            "wavelength_nm must hold at least two strictly increasing wavelengths for colour "
            f"bands; got {lam.tolist()} [nm]"
        )
    low = max(float(lam[0]), CIE1931_RANGE_NM[0])
    high = min(float(lam[-1]), CIE1931_RANGE_NM[1])
    if low >= high:
        raise ValueError(
            f"wavelength_nm spans {lam[0]:g}-{lam[-1]:g} nm, outside the CIE 1931 observer's "
            f"{CIE1931_RANGE_NM[0]:g}-{CIE1931_RANGE_NM[1]:g} nm; colour bands are undefined"
        )
    total = _cmf_integral(*CIE1931_RANGE_NM)
    coverage = _cmf_integral(low, high) / total
    if np.any(coverage < min_coverage):
        shown = ", ".join(f"{n} {c:.4f}" for n, c in zip(CMF_NAMES, coverage))
        raise ValueError(
            f"wavelength_nm spans {lam[0]:g}-{lam[-1]:g} nm, which holds only ({shown}) of the "
            f"colour-matching functions' integrals over 360-830 nm; min_coverage is "
            f"{min_coverage:g} (widen the table's wavelength range or lower min_coverage)"
        )
    weights = np.zeros((3, lam.size))
    for i in range(lam.size - 1):
        a = max(float(lam[i]), low)
        b = min(float(lam[i + 1]), high)
        if a >= b:
            continue
        pa, pb = _pieces(a, b)
        nodes, w = _gauss_legendre(pa, pb)
        cmf = cmf_cie1931_wyman2013(nodes)  # (pieces, nodes, 3)
        t = (nodes - lam[i]) / (lam[i + 1] - lam[i])  # hat of node i + 1
        weights[:, i] += np.einsum("pk,pkc->c", w * (1.0 - t), cmf)
        weights[:, i + 1] += np.einsum("pk,pkc->c", w * t, cmf)
    weights /= weights.sum(axis=1, keepdims=True)
    weights.setflags(write=False)
    centroid = weights @ lam
    centroid.setflags(write=False)
    coverage.setflags(write=False)
    lam.setflags(write=False)
    return BandWeights(
        weights=weights,
        wavelength_nm=lam,
        centroid_nm=centroid,
        coverage=coverage,
        names=CMF_NAMES,
        model=model,
    )
