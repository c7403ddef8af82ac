"""Analytic phase functions and the seed models' parameter sets.

One concept, the analytic phase function, in one module: each model with
its closed-form asymmetry parameter, the registry that names them, and the
published parameter sets (Costa et al. 2021, Collienne et al. 2013) that are
evaluated with them.

Conventions
-----------
Every phase function here is a density per steradian normalized to one over
the sphere, the factor ``1/(4 pi)`` included::

    2 pi integral_{-1}^{1} P(mu) dmu = 1            [P in sr^-1]

Its argument is the cosine of the scattering angle, ``mu = cos(theta)``, with
``theta = 0`` the forward direction.  The functions broadcast with numpy over
``mu`` and over their parameters together: ``g`` of shape ``(n_wl, 1)`` with
``mu`` of shape ``(n_theta,)`` gives a ``(n_wl, n_theta)`` table.  A 0-d result
is returned as a Python float.

Each function has a companion ``<name>_asymmetry`` that returns its mean
cosine (asymmetry parameter) ``<mu> = 2 pi integral P(mu) mu dmu`` in closed
form.  The closed forms follow from the Legendre expansion of Henyey-Greenstein,
``4 pi HG(mu; g) = sum_l (2 l + 1) g^l P_l(mu)``, which gives the moments

    <mu>_HG = g,   <mu^2>_HG = (1 + 2 g^2) / 3,   <mu^3>_HG = (3 g + 2 g^3) / 5

and every other model here is HG times a polynomial in ``mu``.

Models
------
- :func:`rayleigh`, :func:`rayleigh_depolarized` (Chandrasekhar 1950 in the
  form of Bucholtz 1995), :func:`rayleigh_penndorf1957` (as printed by Costa et
  al. 2021; *not* normalized to better than 1e-4, see its Notes).
- :func:`henyey_greenstein` (Henyey & Greenstein 1941).
- Double Henyey-Greenstein in its two published weightings:
  :func:`dhg_costa2021` (``alpha HG(g1) + (1 - alpha) HG(g2)``, as OpenSpace
  and CosmoScout VR evaluate it) and :func:`dhg_kobe2026`
  (``(1 - f) HG(g1) + f HG(g2)``), with the dispatcher
  :func:`double_henyey_greenstein`, which accepts only the weight name that
  belongs to the convention asked for.
- :func:`cornette_shanks1992`, :func:`draine2003` and the HG + Draine blend
  :func:`hg_draine_jendersie_deon2023` with the droplet-diameter fit
  :func:`jendersie_deon2023_parameters` (5 to 50 um).
- :func:`two_term_hg_hapke2012` (Hapke 2012), in scattering angle.
- :data:`ANALYTIC_MODELS`, the one registry of these models: each record
  (:class:`AnalyticModel`) holds the formula, its parameters, their ranges
  and starting values for a fit, the analytic derivatives and the citation.
  :func:`~dustoptics.scattering.fit.fit_phase`, the TOML configuration and
  the sky's fitted approximations read it.  :func:`get_analytic_model` looks
  a model up by name or alias (:data:`ANALYTIC_MODEL_ALIASES`: the hyphenated
  spellings ``henyey-greenstein``, ``dhg-costa2021``, ... and short names
  ``hg``, ``dhg``, ``cs``, ...).

Datasets
--------
- :func:`costa2021_mars_dhg`: Costa et al.'s Mars DHG, extended to any
  wavelength by Meyran's (2022) quadratic in ``g1``; the three-wavelength sets
  :data:`COSTA2021_MARS_DHG_CODE` (their source code, the default) and
  :data:`COSTA2021_MARS_DHG_PAPER` (their printed table: a purple sky).
- :data:`COLLIENNE2013_MARS`: Collienne et al.'s Rayleigh-like coefficients
  and Cornette-Shanks aerosol.

Tables
------
Phase functions sampled on a grid of angles, and what is done to them
(:func:`~dustoptics.scattering.tabulated_phase.sphere_integral`,
:func:`~dustoptics.scattering.tabulated_phase.renormalize`, Meyran's
:func:`~dustoptics.scattering.tabulated_phase.hybrid`, ...), are in
:mod:`dustoptics.scattering.tabulated_phase`.

References
----------
Each model's docstring cites its source; the same citations, as the models'
records carry them, are the constants ``HENYEY_GREENSTEIN_1941``, ...,
``COLLIENNE_2013`` below.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar, Final

import numpy as np
from numpy.typing import ArrayLike

from dustoptics._validation import (
    _show,
    as_float_array,
    check_choice,
)
from dustoptics.scattering._parameters import (
    FloatArray,
    FloatOrArray,
    float_or_array,
    in_interval,
    mixing_weight,
)

__all__ = [
    "ANALYTIC_MODELS",
    "ANALYTIC_MODEL_ALIASES",
    "COLLIENNE2013_MARS",
    "COSTA2021_MARS_DHG_CODE",
    "COSTA2021_MARS_DHG_PAPER",
    "COSTA2021_WAVELENGTH_RANGE_NM",
    "DHG_CONVENTIONS",
    "JENDERSIE_DEON2023_DIAMETER_RANGE_UM",
    "MEYRAN2022_G1_COEFFICIENTS",
    "PENNDORF1957_SPHERE_INTEGRAL",
    "AnalyticModel",
    "Collienne2013",
    "DHGSpectrum",
    "ExtrapolationWarning",
    "HGDraineParameters",
    "cornette_shanks1992",
    "cornette_shanks1992_asymmetry",
    "costa2021_mars_dhg",
    "dhg_costa2021",
    "dhg_costa2021_asymmetry",
    "dhg_kobe2026",
    "dhg_kobe2026_asymmetry",
    "double_henyey_greenstein",
    "double_henyey_greenstein_asymmetry",
    "draine2003",
    "draine2003_asymmetry",
    "get_analytic_model",
    "henyey_greenstein",
    "henyey_greenstein_asymmetry",
    "hg_draine_jendersie_deon2023",
    "hg_draine_jendersie_deon2023_asymmetry",
    "jendersie_deon2023_parameters",
    "rayleigh",
    "rayleigh_asymmetry",
    "rayleigh_depolarized",
    "rayleigh_depolarized_asymmetry",
    "rayleigh_penndorf1957",
    "rayleigh_penndorf1957_asymmetry",
    "register_analytic_model",
    "two_term_hg_hapke2012",
    "two_term_hg_hapke2012_asymmetry",
]


_FOUR_PI: Final = 4.0 * math.pi

# ------------------------------------------------------------------ citations

HENYEY_GREENSTEIN_1941: Final = (
    'L. G. Henyey and J. L. Greenstein, "Diffuse radiation in the Galaxy," '
    "Astrophys. J., vol. 93, pp. 70-83, 1941, doi:10.1086/144246"
)
CHANDRASEKHAR_1950: Final = "S. Chandrasekhar, Radiative Transfer. Oxford: Clarendon Press, 1950"
BUCHOLTZ_1995: Final = (
    'A. Bucholtz, "Rayleigh-scattering calculations for the terrestrial atmosphere," '
    "Appl. Opt., vol. 34, no. 15, pp. 2765-2773, 1995, doi:10.1364/AO.34.002765"
)
PENNDORF_1957: Final = (
    'R. Penndorf, "Tables of the refractive index for standard air and the Rayleigh '
    "scattering coefficient for the spectral region between 0.2 and 20.0 um and their "
    'application to atmospheric optics," J. Opt. Soc. Am., vol. 47, no. 2, pp. 176-182, '
    "1957, doi:10.1364/JOSA.47.000176"
)
CORNETTE_SHANKS_1992: Final = (
    'W. M. Cornette and J. G. Shanks, "Physically reasonable analytic expression for the '
    'single-scattering phase function," Appl. Opt., vol. 31, no. 16, pp. 3152-3160, 1992, '
    "doi:10.1364/AO.31.003152"
)
DRAINE_2003: Final = (
    'B. T. Draine, "Scattering by interstellar dust grains. I. Optical and ultraviolet," '
    "Astrophys. J., vol. 598, pp. 1017-1025, 2003, doi:10.1086/379118"
)
JENDERSIE_DEON_2023: Final = (
    "J. Jendersie and E. d'Eon, \"An approximate Mie scattering function for fog and cloud "
    'rendering," in ACM SIGGRAPH 2023 Talks, 2023, doi:10.1145/3587421.3595409'
)
COSTA_2021: Final = (
    'J. Costa, A. Bock, C. Emmart, C. Hansen, A. Ynnerman and C. Silva, "Interactive '
    'visualization of atmospheric effects for celestial bodies," IEEE Trans. Vis. Comput. '
    "Graph., vol. 27, no. 2, pp. 785-795, 2021, doi:10.1109/TVCG.2020.3030333"
)
MEYRAN_2022: Final = (
    'T. Meyran, "Physically based real-time rendering of the Martian atmosphere," '
    "M.Sc. thesis, Hochschule Hannover, Nov. 2022"
)
HAPKE_2012: Final = (
    "B. Hapke, Theory of Reflectance and Emittance Spectroscopy, 2nd ed. Cambridge: "
    "Cambridge University Press, 2012, doi:10.1017/CBO9781139025683, section 6.4.2"
)
KOBE_2026: Final = (
    'D. Kobe, "Ozone absorption in single atmospheric scattering," graduation work, '
    "Digital Arts and Entertainment, Howest, 2025-2026"
)
COLLIENNE_2013: Final = (
    'P. Collienne, R. Wolff, A. Gerndt and T. Kuhlen, "Physically based rendering of the '
    'Martian atmosphere," 2013 (as cited and described by Meyran 2022, ref. [48], '
    "section 3.4.1)"
)
COSMOSCOUT_VR: Final = (
    "German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres, "
    "https://github.com/cosmoscout/cosmoscout-vr"
)

# ----------------------------------------------------------------- validation


def _g(name: str, value: Any) -> float | FloatArray:
    """An asymmetry-type parameter with ``|g| < 1``."""
    return in_interval(name, value, -1.0, 1.0, closed=False)


def _draine_alpha(value: Any) -> float | FloatArray:
    """Draine's alpha >= -1 (so that ``1 + alpha mu^2 >= 0``), finite."""
    return in_interval("alpha", value, -1.0, math.inf, closed=True)


def _mu(mu: ArrayLike) -> FloatArray:
    """Scattering-angle cosines: finite, in [-1, 1]."""
    arr = as_float_array("mu", mu)
    if not np.all(np.abs(arr) <= 1.0):
        raise ValueError(
            f"mu (cosine of the scattering angle) must be in the closed interval [-1, 1]; "
            f"got {_show(mu)}"
        )
    return arr


def _broadcast(**arrays: Any) -> tuple[FloatArray, ...]:
    """Broadcast named arrays together or raise ValueError naming their shapes."""
    try:
        return tuple(
            np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in arrays.values()))
        )
    except ValueError:
        shapes = ", ".join(f"{k} {np.shape(v)}" for k, v in arrays.items())
        raise ValueError(f"shapes do not broadcast together: {shapes}") from None


# ---------------------------------------------------------------- the kernels


def _hg(mu: FloatArray, g: Any) -> FloatArray:
    """Henyey-Greenstein [sr^-1] on validated input.

    ``1 + g^2 - 2 g mu`` is evaluated as ``(1 - g)^2 + 2 g (1 - mu)``, which
    keeps its relative accuracy near the forward peak of a strong lobe.
    """
    g = np.asarray(g, dtype=np.float64)
    d = (1.0 - g) ** 2 + 2.0 * g * (1.0 - mu)
    return (1.0 - g) * (1.0 + g) / (d * np.sqrt(d)) / _FOUR_PI


def _draine(mu: FloatArray, g: Any, alpha: Any) -> FloatArray:
    g = np.asarray(g, dtype=np.float64)
    alpha = np.asarray(alpha, dtype=np.float64)
    return _hg(mu, g) * (1.0 + alpha * mu * mu) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0)


def _dhg_costa(mu: FloatArray, g1: Any, g2: Any, alpha: Any) -> FloatArray:
    """``alpha HG(g1) + (1 - alpha) HG(g2)`` on validated input."""
    return alpha * _hg(mu, g1) + (1.0 - alpha) * _hg(mu, g2)


def _dhg_kobe(mu: FloatArray, g1: Any, g2: Any, f: Any) -> FloatArray:
    """``(1 - f) HG(g1) + f HG(g2)`` on validated input."""
    return (1.0 - f) * _hg(mu, g1) + f * _hg(mu, g2)


def _cs_factor(mu: FloatArray, g: Any) -> FloatArray:
    """Cornette-Shanks over Henyey-Greenstein, ``3 (1 + mu^2) / (2 (2 + g^2))``, as fits take it."""
    return 1.5 * (1.0 + mu * mu) / (2.0 + g * g)


def _cornette_shanks(mu: FloatArray, g: Any) -> FloatArray:
    """Cornette-Shanks on validated input, as fits evaluate it (with its gradient's rounding).

    :func:`cornette_shanks1992` rounds differently in the last bit (its own
    order of operations, kept so that tables made with it do not change).
    """
    return _cs_factor(mu, g) * _hg(mu, g)


def _hg_draine(mu: FloatArray, g_hg: Any, g_d: Any, alpha: Any, w_d: Any) -> FloatArray:
    """``(1 - w_d) HG(g_hg) + w_d Draine(g_d, alpha)`` on validated input."""
    return (1.0 - w_d) * _hg(mu, g_hg) + w_d * _draine(mu, g_d, alpha)


def _two_term_hg(mu: FloatArray, b: Any, c: Any) -> FloatArray:
    """Hapke's two-term HG in scattering angle on validated input.

    ``(1 - c)/2 HG(b) + (1 + c)/2 HG(-b)``, in the order of operations the fit
    has always used (its numbers stay the same to the last bit).
    """
    return 0.5 * (1.0 - c) * _hg(mu, b) + 0.5 * (1.0 + c) * _hg(mu, -b)


def _draine_mean(g: Any, alpha: Any) -> FloatArray:
    g = np.asarray(g, dtype=np.float64)
    alpha = np.asarray(alpha, dtype=np.float64)
    return g * (1.0 + alpha * (3.0 + 2.0 * g * g) / 5.0) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0)


# ------------------------------------------------------------------- Rayleigh


def rayleigh(mu: ArrayLike) -> FloatOrArray:
    """Rayleigh phase function for isotropic molecules.

    .. math:: P(\\mu) = \\frac{3}{16 \\pi} (1 + \\mu^2)

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    References
    ----------
    .. [1] S. Chandrasekhar, Radiative Transfer. Oxford: Clarendon Press, 1950.
    """
    m = _mu(mu)
    return float_or_array(3.0 / (16.0 * math.pi) * (1.0 + m * m))


def rayleigh_asymmetry() -> float:
    """Mean cosine of :func:`rayleigh`: 0 (the function is even in ``mu``). [-]"""
    return 0.0


def _depolarization(value: Any) -> float | FloatArray:
    return in_interval("depolarization", value, 0.0, 6.0 / 7.0, closed=True)


def rayleigh_depolarized(mu: ArrayLike, *, depolarization: ArrayLike) -> FloatOrArray:
    """Rayleigh phase function for anisotropic molecules (depolarization factor).

    .. math::

        \\gamma = \\frac{\\delta}{2 - \\delta}, \\qquad
        P(\\mu) = \\frac{3}{16 \\pi (1 + 2 \\gamma)}
                  \\left[(1 + 3 \\gamma) + (1 - \\gamma) \\mu^2\\right]

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    depolarization : array_like
        Depolarization factor ``delta`` for unpolarized incident light
        (``rho_n`` of Bucholtz 1995), in [0, 6/7]; 6/7 is its value for a purely
        anisotropic polarizability.  Broadcasts with ``mu``. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    Notes
    -----
    With ``delta = 0`` this is :func:`rayleigh`.  Normalization:
    ``2 pi int (1 + 3 gamma) + (1 - gamma) mu^2 dmu = 2 pi (8/3)(1 + 2 gamma)``,
    so the prefactor is ``3 / (16 pi (1 + 2 gamma))``.  A form sometimes quoted
    with an extra factor ``2 / (1 + 2 gamma)`` in place of ``1 / (1 + 2 gamma)``
    integrates to 2, not 1.  Penndorf's 1957 constants (see
    :func:`rayleigh_penndorf1957`) are this function at ``delta = 0.035``,
    ``0.76291 (1 + 0.93237 mu^2) / (4 pi)``, rounded.

    References
    ----------
    .. [1] S. Chandrasekhar, Radiative Transfer. Oxford: Clarendon Press, 1950.
    .. [2] A. Bucholtz, "Rayleigh-scattering calculations for the terrestrial
       atmosphere," Appl. Opt., vol. 34, no. 15, pp. 2765-2773, 1995,
       doi:10.1364/AO.34.002765.
    .. [3] K. V. Chance and R. J. D. Spurr, "Ring effect studies: Rayleigh
       scattering, including molecular parameters for rotational Raman
       scattering, and the Fraunhofer spectrum," Appl. Opt., vol. 36, no. 21,
       pp. 5224-5230, 1997, doi:10.1364/AO.36.005224.
    """
    m = _mu(mu)
    delta = np.asarray(_depolarization(depolarization))
    gamma = delta / (2.0 - delta)
    m, gamma = _broadcast(mu=m, depolarization=gamma)
    p = 3.0 / (16.0 * math.pi * (1.0 + 2.0 * gamma)) * ((1.0 + 3.0 * gamma) + (1.0 - gamma) * m * m)
    return float_or_array(p)


def rayleigh_depolarized_asymmetry(*, depolarization: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`rayleigh_depolarized`: 0 for every ``depolarization``. [-]"""
    delta = np.asarray(_depolarization(depolarization))
    return float_or_array(np.zeros_like(delta))


#: ``2 pi int P dmu`` of :func:`rayleigh_penndorf1957` as printed:
#: ``0.7629 (1 + 0.932 / 3) = 0.9999076`` (1 - 9.24e-5).
PENNDORF1957_SPHERE_INTEGRAL: Final = 0.7629 * (1.0 + 0.932 / 3.0)


def rayleigh_penndorf1957(mu: ArrayLike) -> FloatOrArray:
    """Penndorf's Rayleigh phase function for air, as Costa et al. 2021 print it.

    .. math:: P(\\mu) = \\frac{0.7629 (1 + 0.932 \\mu^2)}{4 \\pi}

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function with the printed constants. [sr^-1]

    Notes
    -----
    With the printed constants the sphere integral is
    ``0.7629 (1 + 0.932 / 3) = 0.9999076``
    (:data:`PENNDORF1957_SPHERE_INTEGRAL`), short of 1 by 9.2e-5: the constants
    are rounded values of :func:`rayleigh_depolarized` at ``delta = 0.035``
    (``0.76291``, ``0.93237``).  This function is returned as printed, not
    renormalized, so that it reproduces Costa et al.'s renderer; use
    :func:`rayleigh_depolarized` for a normalized function, or
    :func:`~dustoptics.scattering.tabulated_phase.renormalize` on a table.

    References
    ----------
    .. [1] R. Penndorf, "Tables of the refractive index for standard air and the
       Rayleigh scattering coefficient for the spectral region between 0.2 and
       20.0 um and their application to atmospheric optics," J. Opt. Soc. Am.,
       vol. 47, no. 2, pp. 176-182, 1957, doi:10.1364/JOSA.47.000176.
    .. [2] J. Costa et al., "Interactive visualization of atmospheric effects
       for celestial bodies," IEEE Trans. Vis. Comput. Graph., vol. 27, no. 2,
       pp. 785-795, 2021, doi:10.1109/TVCG.2020.3030333, eq. (10).
    """
    m = _mu(mu)
    return float_or_array(0.7629 * (1.0 + 0.932 * m * m) / _FOUR_PI)


def rayleigh_penndorf1957_asymmetry() -> float:
    """``2 pi int P mu dmu`` of :func:`rayleigh_penndorf1957`: 0 (even in ``mu``). [-]"""
    return 0.0


# ---------------------------------------------------------- Henyey-Greenstein


def henyey_greenstein(mu: ArrayLike, *, g: ArrayLike) -> FloatOrArray:
    """Henyey-Greenstein phase function.

    .. math:: P(\\mu) = \\frac{1}{4 \\pi} \\frac{1 - g^2}{(1 + g^2 - 2 g \\mu)^{3/2}}

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g : array_like
        Asymmetry parameter, ``|g| < 1``; broadcasts with ``mu``. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    References
    ----------
    .. [1] L. G. Henyey and J. L. Greenstein, "Diffuse radiation in the
       Galaxy," Astrophys. J., vol. 93, pp. 70-83, 1941, doi:10.1086/144246.
    """
    m = _mu(mu)
    gg = _g("g", g)
    m, gg = _broadcast(mu=m, g=gg)
    return float_or_array(_hg(m, gg))


def henyey_greenstein_asymmetry(*, g: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`henyey_greenstein`: ``<mu> = g``. [-]"""
    return float_or_array(np.array(_g("g", g), dtype=np.float64))


# ------------------------------------------------------ double Henyey-Greenstein

#: The two published weightings of the double Henyey-Greenstein function.
DHG_CONVENTIONS: Final = ("costa2021", "kobe2026")
_DHG_WEIGHT_NAME: Final = {"costa2021": "alpha", "kobe2026": "f"}


def dhg_costa2021(mu: ArrayLike, *, g1: ArrayLike, g2: ArrayLike, alpha: ArrayLike) -> FloatOrArray:
    """Double Henyey-Greenstein as Costa et al. 2021 (OpenSpace, CosmoScout VR) weight it.

    .. math:: P(\\mu) = \\alpha\\, HG(\\mu; g_1) + (1 - \\alpha)\\, HG(\\mu; g_2)

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g1, g2 : array_like
        Asymmetry parameters of the two lobes, ``|g| < 1``. [-]
    alpha : array_like
        Weight of the ``g1`` lobe, in [0, 1]; all arguments broadcast
        together. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    Notes
    -----
    Costa et al.'s eq. (16) prints the numerators as ``1 + g^2``; their code,
    which this follows, uses the Henyey-Greenstein ``1 - g^2``.  With
    ``alpha = 1 - f`` this is :func:`dhg_kobe2026`.

    References
    ----------
    .. [1] J. Costa et al., "Interactive visualization of atmospheric effects
       for celestial bodies," IEEE Trans. Vis. Comput. Graph., vol. 27, no. 2,
       pp. 785-795, 2021, doi:10.1109/TVCG.2020.3030333, eq. (16).
    """
    m = _mu(mu)
    a = mixing_weight("alpha", alpha)
    m, g1a, g2a, a = _broadcast(mu=m, g1=_g("g1", g1), g2=_g("g2", g2), alpha=a)
    return float_or_array(_dhg_costa(m, g1a, g2a, a))


def dhg_costa2021_asymmetry(*, g1: ArrayLike, g2: ArrayLike, alpha: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`dhg_costa2021`: ``alpha g1 + (1 - alpha) g2``. [-]"""
    g1a, g2a, a = _broadcast(g1=_g("g1", g1), g2=_g("g2", g2), alpha=mixing_weight("alpha", alpha))
    return float_or_array(a * g1a + (1.0 - a) * g2a)


def dhg_kobe2026(mu: ArrayLike, *, g1: ArrayLike, g2: ArrayLike, f: ArrayLike) -> FloatOrArray:
    """Double Henyey-Greenstein as Kobe 2026 (and Meyran 2022, eq. 2.30) weight it.

    .. math:: P(\\mu) = (1 - f)\\, HG(\\mu; g_1) + f\\, HG(\\mu; g_2)

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g1, g2 : array_like
        Asymmetry parameters, ``|g| < 1``; the source intends ``g1 > 0``
        (forward lobe) and ``g2 < 0`` (backward lobe) but any ``|g| < 1`` is
        accepted. [-]
    f : array_like
        Weight of the ``g2`` lobe, in [0, 1]; all arguments broadcast
        together. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    Notes
    -----
    With ``f = 1 - alpha`` this is :func:`dhg_costa2021`.

    References
    ----------
    .. [1] D. Kobe, "Ozone absorption in single atmospheric scattering,"
       graduation work, Howest, 2025-2026, eq. 5.
    .. [2] T. Meyran, "Physically based real-time rendering of the Martian
       atmosphere," M.Sc. thesis, Hochschule Hannover, 2022, eq. (2.30).
    """
    m = _mu(mu)
    w = mixing_weight("f", f)
    m, g1a, g2a, w = _broadcast(mu=m, g1=_g("g1", g1), g2=_g("g2", g2), f=w)
    return float_or_array(_dhg_kobe(m, g1a, g2a, w))


def dhg_kobe2026_asymmetry(*, g1: ArrayLike, g2: ArrayLike, f: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`dhg_kobe2026`: ``(1 - f) g1 + f g2``. [-]"""
    g1a, g2a, w = _broadcast(g1=_g("g1", g1), g2=_g("g2", g2), f=mixing_weight("f", f))
    return float_or_array((1.0 - w) * g1a + w * g2a)


def _dhg_weight(convention: str, alpha: Any, f: Any) -> tuple[str, Any]:
    check_choice("convention", convention, DHG_CONVENTIONS)
    expected = _DHG_WEIGHT_NAME[convention]
    given = {"alpha": alpha, "f": f}
    other = "f" if expected == "alpha" else "alpha"
    if given[other] is not None:
        raise ValueError(
            f"convention {convention!r} takes its weight as {expected!r}, not {other!r} "
            f"(costa2021: alpha HG(g1) + (1 - alpha) HG(g2); "
            f"kobe2026: (1 - f) HG(g1) + f HG(g2))"
        )
    if given[expected] is None:
        raise ValueError(f"convention {convention!r} needs the weight {expected!r}")
    return expected, given[expected]


def double_henyey_greenstein(
    mu: ArrayLike,
    *,
    g1: ArrayLike,
    g2: ArrayLike,
    alpha: ArrayLike | None = None,
    f: ArrayLike | None = None,
    convention: str = "costa2021",
) -> FloatOrArray:
    """Double Henyey-Greenstein in a named weighting convention.

    ========== ========================================== ==========
    convention formula                                    weight
    ========== ========================================== ==========
    costa2021  ``alpha HG(g1) + (1 - alpha) HG(g2)``       ``alpha``
    kobe2026   ``(1 - f) HG(g1) + f HG(g2)``               ``f``
    ========== ========================================== ==========

    Each convention accepts only its own weight's name, so a weight cannot be
    read in the wrong convention: ``f=`` with ``convention="costa2021"`` raises.

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g1, g2 : array_like
        Asymmetry parameters, ``|g| < 1``. [-]
    alpha, f : array_like, optional
        The weight, in [0, 1], under the name the convention uses. [-]
    convention : {"costa2021", "kobe2026"}
        See :func:`dhg_costa2021` and :func:`dhg_kobe2026`.

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    Raises
    ------
    ValueError
        For an unknown convention (the message lists the valid ones) or a
        weight given under the other convention's name.
    """
    name, w = _dhg_weight(convention, alpha, f)
    if name == "alpha":
        return dhg_costa2021(mu, g1=g1, g2=g2, alpha=w)
    return dhg_kobe2026(mu, g1=g1, g2=g2, f=w)


def double_henyey_greenstein_asymmetry(
    *,
    g1: ArrayLike,
    g2: ArrayLike,
    alpha: ArrayLike | None = None,
    f: ArrayLike | None = None,
    convention: str = "costa2021",
) -> FloatOrArray:
    """Mean cosine of :func:`double_henyey_greenstein` in the named convention. [-]"""
    name, w = _dhg_weight(convention, alpha, f)
    if name == "alpha":
        return dhg_costa2021_asymmetry(g1=g1, g2=g2, alpha=w)
    return dhg_kobe2026_asymmetry(g1=g1, g2=g2, f=w)


# ----------------------------------------------------------- Cornette-Shanks


def cornette_shanks1992(mu: ArrayLike, *, g: ArrayLike) -> FloatOrArray:
    """Cornette-Shanks phase function.

    .. math::

        P(\\mu) = \\frac{1}{4 \\pi} \\frac{3 (1 - g^2)}{2 (2 + g^2)}
                  \\frac{1 + \\mu^2}{(1 + g^2 - 2 g \\mu)^{3/2}}
                = \\frac{3}{2 (2 + g^2)} (1 + \\mu^2)\\, HG(\\mu; g)

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g : array_like
        Parameter ``|g| < 1``; broadcasts with ``mu``.  It is *not* the mean
        cosine (see :func:`cornette_shanks1992_asymmetry`). [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    Notes
    -----
    At ``g = 0`` this is exactly :func:`rayleigh`.

    References
    ----------
    .. [1] W. M. Cornette and J. G. Shanks, "Physically reasonable analytic
       expression for the single-scattering phase function," Appl. Opt.,
       vol. 31, no. 16, pp. 3152-3160, 1992, doi:10.1364/AO.31.003152.
    """
    m = _mu(mu)
    m, gg = _broadcast(mu=m, g=_g("g", g))
    # The formula of the registry's kernel (_cornette_shanks, what fits evaluate) in this
    # function's own order of operations: the two round differently in the last bit, and
    # each keeps its own so that neither tables nor fits change.
    return float_or_array(1.5 / (2.0 + gg * gg) * (1.0 + m * m) * _hg(m, gg))


def cornette_shanks1992_asymmetry(*, g: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`cornette_shanks1992`.

    .. math:: \\langle \\mu \\rangle = \\frac{3 g (4 + g^2)}{5 (2 + g^2)}

    Derivation: ``P = 3 (1 + mu^2) HG / (2 (2 + g^2))``, so
    ``<mu> = 3 (<mu>_HG + <mu^3>_HG) / (2 (2 + g^2))`` with ``<mu>_HG = g`` and
    ``<mu^3>_HG = (3 g + 2 g^3) / 5``.

    Parameters
    ----------
    g : array_like
        Parameter ``|g| < 1``. [-]

    Returns
    -------
    float or numpy.ndarray
        Mean cosine of the scattering angle. [-]
    """
    gg = np.asarray(_g("g", g), dtype=np.float64)
    return float_or_array(3.0 * gg * (4.0 + gg * gg) / (5.0 * (2.0 + gg * gg)))


# ---------------------------------------------------------------------- Draine


def draine2003(mu: ArrayLike, *, g: ArrayLike, alpha: ArrayLike) -> FloatOrArray:
    """Draine's phase function.

    .. math::

        P(\\mu) = HG(\\mu; g)\\,
                  \\frac{1 + \\alpha \\mu^2}{1 + \\alpha (1 + 2 g^2) / 3}

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g : array_like
        Henyey-Greenstein parameter, ``|g| < 1``. [-]
    alpha : array_like
        Draine's alpha, ``>= -1`` so that the function is nonnegative.
        ``alpha = 0`` is Henyey-Greenstein; ``alpha = 1`` with ``g = 0`` is
        Rayleigh.  All arguments broadcast together. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    References
    ----------
    .. [1] B. T. Draine, "Scattering by interstellar dust grains. I. Optical
       and ultraviolet," Astrophys. J., vol. 598, pp. 1017-1025, 2003,
       doi:10.1086/379118, eq. (4).
    """
    m = _mu(mu)
    m, gg, a = _broadcast(mu=m, g=_g("g", g), alpha=_draine_alpha(alpha))
    return float_or_array(_draine(m, gg, a))


def draine2003_asymmetry(*, g: ArrayLike, alpha: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`draine2003`.

    .. math::

        \\langle \\mu \\rangle = g\\,
            \\frac{1 + \\alpha (3 + 2 g^2) / 5}{1 + \\alpha (1 + 2 g^2) / 3}

    from ``<mu>_HG = g`` and ``<mu^3>_HG = (3 g + 2 g^3) / 5``. [-]
    """
    gg, a = _broadcast(g=_g("g", g), alpha=_draine_alpha(alpha))
    return float_or_array(_draine_mean(gg, a))


def _hg_draine_parameters(g_hg: Any, g_d: Any, alpha: Any, w_d: Any) -> dict[str, Any]:
    """The blend's four parameters, each checked, by name (for :func:`_broadcast`)."""
    return {
        "g_hg": _g("g_hg", g_hg),
        "g_d": _g("g_d", g_d),
        "alpha": _draine_alpha(alpha),
        "w_d": mixing_weight("w_d", w_d),
    }


def hg_draine_jendersie_deon2023(
    mu: ArrayLike,
    *,
    g_hg: ArrayLike,
    g_d: ArrayLike,
    alpha: ArrayLike,
    w_d: ArrayLike,
) -> FloatOrArray:
    """Jendersie & d'Eon's blend of Henyey-Greenstein and Draine.

    .. math::

        P(\\mu) = (1 - w_D)\\, HG(\\mu; g_{HG}) + w_D\\, \\mathrm{Draine}(\\mu; g_D, \\alpha)

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    g_hg : array_like
        Parameter of the Henyey-Greenstein lobe, ``|g| < 1``. [-]
    g_d : array_like
        HG parameter of the Draine lobe, ``|g| < 1``. [-]
    alpha : array_like
        Draine's alpha, ``>= -1``. [-]
    w_d : array_like
        Weight of the Draine lobe, in [0, 1].  All arguments broadcast
        together; :func:`jendersie_deon2023_parameters` gives all four from a
        water-droplet diameter. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    References
    ----------
    .. [1] J. Jendersie and E. d'Eon, "An approximate Mie scattering function
       for fog and cloud rendering," in ACM SIGGRAPH 2023 Talks, 2023,
       doi:10.1145/3587421.3595409.
    """
    m = _mu(mu)
    m, gh, gd, a, w = _broadcast(mu=m, **_hg_draine_parameters(g_hg, g_d, alpha, w_d))
    return float_or_array(_hg_draine(m, gh, gd, a, w))


def hg_draine_jendersie_deon2023_asymmetry(
    *, g_hg: ArrayLike, g_d: ArrayLike, alpha: ArrayLike, w_d: ArrayLike
) -> FloatOrArray:
    """Mean cosine of :func:`hg_draine_jendersie_deon2023`.

    ``<mu> = (1 - w_D) g_HG + w_D <mu>_Draine(g_D, alpha)``, with the Draine
    mean cosine of :func:`draine2003_asymmetry`. [-]
    """
    gh, gd, a, w = _broadcast(**_hg_draine_parameters(g_hg, g_d, alpha, w_d))
    return float_or_array((1.0 - w) * gh + w * _draine_mean(gd, a))


@dataclass(frozen=True, eq=False)
class HGDraineParameters:
    """Parameters of :func:`hg_draine_jendersie_deon2023` for given droplet diameters.

    Attributes
    ----------
    diameter_um : numpy.ndarray
        Water-droplet diameters. [um]
    g_hg, g_d, alpha, w_d : numpy.ndarray
        The blend's parameters, same shape as ``diameter_um``. [-]
    citation : str
        Source of the fit.
    """

    diameter_um: FloatArray
    g_hg: FloatArray
    g_d: FloatArray
    alpha: FloatArray
    w_d: FloatArray
    citation: str = JENDERSIE_DEON_2023

    def phase(self, mu: ArrayLike) -> FloatArray:
        """Phase function [sr^-1], shape ``diameter_um.shape + mu.shape``."""
        m = _mu(mu)
        ex = (...,) + (None,) * m.ndim
        return np.asarray(
            hg_draine_jendersie_deon2023(
                m, g_hg=self.g_hg[ex], g_d=self.g_d[ex], alpha=self.alpha[ex], w_d=self.w_d[ex]
            )
        )

    def asymmetry(self) -> FloatArray:
        """Mean cosine [-], shape ``diameter_um.shape``."""
        return np.asarray(
            hg_draine_jendersie_deon2023_asymmetry(
                g_hg=self.g_hg, g_d=self.g_d, alpha=self.alpha, w_d=self.w_d
            )
        )


#: Validity range of the diameter fit of :func:`jendersie_deon2023_parameters`. [um]
JENDERSIE_DEON2023_DIAMETER_RANGE_UM: Final = (5.0, 50.0)


def jendersie_deon2023_parameters(*, diameter_um: ArrayLike) -> HGDraineParameters:
    """Jendersie & d'Eon's fit of the HG + Draine parameters to Mie water droplets.

    For droplet diameters ``5 <= d <= 50`` um (``d`` in um)::

        g_HG  = exp(-0.0990567 / (d - 1.67154))
        g_D   = exp(-2.20679 / (d + 3.91029) - 0.428934)
        alpha = exp(3.62489 - 8.29288 / (d + 5.52825))
        w_D   = exp(-0.599085 / (d - 0.641583) - 0.665888)

    Parameters
    ----------
    diameter_um : array_like
        Droplet diameter, in [5, 50]. [um]

    Returns
    -------
    HGDraineParameters
        Arrays of the shape of ``diameter_um`` (0-d for a scalar).

    Raises
    ------
    ValueError
        Outside [5, 50] um.  The talk gives further piecewise fits for smaller
        droplets (0.1 to 5 um); they are not included here.

    Notes
    -----
    The fit is for water droplets in air at visible wavelengths; it is not a
    model of Martian dust.  The constants were checked against two
    independent public implementations of the talk's equations (7)-(10)
    (Blender Cycles' fitted Mie phase, and a WebGPU sky renderer), which agree
    to all printed digits.

    References
    ----------
    .. [1] J. Jendersie and E. d'Eon, "An approximate Mie scattering function
       for fog and cloud rendering," in ACM SIGGRAPH 2023 Talks, 2023,
       doi:10.1145/3587421.3595409, eqs. (7)-(10).
    """
    low, high = JENDERSIE_DEON2023_DIAMETER_RANGE_UM
    d = np.asarray(
        in_interval("diameter_um", diameter_um, low, high, closed=True), dtype=np.float64
    )
    g_hg = np.exp(-0.0990567 / (d - 1.67154))
    g_d = np.exp(-2.20679 / (d + 3.91029) - 0.428934)
    alpha = np.exp(3.62489 - 8.29288 / (d + 5.52825))
    w_d = np.exp(-0.599085 / (d - 0.641583) - 0.665888)
    for arr in (d, g_hg, g_d, alpha, w_d):
        arr.setflags(write=False)
    return HGDraineParameters(diameter_um=d, g_hg=g_hg, g_d=g_d, alpha=alpha, w_d=w_d)


# ------------------------------------------------------------ Hapke two-term


def two_term_hg_hapke2012(mu: ArrayLike, *, b: ArrayLike, c: ArrayLike) -> FloatOrArray:
    """Hapke's two-term Henyey-Greenstein function, in scattering angle.

    .. math:: P(\\mu) = \\frac{1 - c}{2} HG(\\mu; b) + \\frac{1 + c}{2} HG(\\mu; -b)

    Parameters
    ----------
    mu : array_like
        Cosine of the scattering angle, in [-1, 1]. [-]
    b : array_like
        Lobe width, ``|b| < 1`` (Hapke uses ``0 <= b < 1``). [-]
    c : array_like
        Lobe balance, in [-1, 1]; ``c > 0`` puts more light in the backward
        lobe, as Hapke's phase-angle form states it.  All arguments broadcast
        together. [-]

    Returns
    -------
    float or numpy.ndarray
        Phase function, normalized to 1 over the sphere. [sr^-1]

    Notes
    -----
    Hapke writes the function of the phase angle ``g = 180 deg - theta``;
    in the scattering angle the two lobes swap.  It is the Costa double HG
    (:func:`dhg_costa2021`) with ``g1 = b``, ``g2 = -b`` and
    ``alpha = (1 - c) / 2``.

    References
    ----------
    .. [1] B. Hapke, Theory of Reflectance and Emittance Spectroscopy, 2nd ed.
       Cambridge: Cambridge University Press, 2012,
       doi:10.1017/CBO9781139025683, section 6.4.2.
    """
    m = _mu(mu)
    m, bb, cc = _broadcast(mu=m, b=_g("b", b), c=in_interval("c", c, -1.0, 1.0, closed=True))
    return float_or_array(_two_term_hg(m, bb, cc))


def two_term_hg_hapke2012_asymmetry(*, b: ArrayLike, c: ArrayLike) -> FloatOrArray:
    """Mean cosine of :func:`two_term_hg_hapke2012`: ``-c b``. [-]"""
    bb, cc = _broadcast(b=_g("b", b), c=in_interval("c", c, -1.0, 1.0, closed=True))
    return float_or_array(-cc * bb)


# ------------------------------------------------- derivatives and fit starts
#
# What a fit (:mod:`dustoptics.scattering.fit`) reads from a model's record beside its
# formula: the analytic derivatives with respect to the parameters, and starting points
# from a table's Legendre moments <P_0..P_3>.  Parameters come as the columns of an
# array p of shape (n, k) (n rows, k parameters), mu has shape (m,).


def _col(p: FloatArray, i: int) -> FloatArray:
    return p[:, i : i + 1]


def _hg_dlog(mu: FloatArray, g: FloatArray) -> tuple[FloatArray, FloatArray]:
    """HG(g) and d ln HG / dg = -2 g / (1 - g^2) - 3 (g - mu) / (1 + g^2 - 2 g mu)."""
    d = (1.0 - g) ** 2 + 2.0 * g * (1.0 - mu)
    value = (1.0 - g) * (1.0 + g) / (d * np.sqrt(d)) / _FOUR_PI
    return value, -2.0 * g / ((1.0 - g) * (1.0 + g)) - 3.0 * (g - mu) / d


def _hg_gradient(mu: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    h, dl = _hg_dlog(mu, _col(p, 0))
    return h, (h * dl)[:, :, None]


def _cs_gradient(mu: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    g = _col(p, 0)
    h, dl = _hg_dlog(mu, g)
    f = _cs_factor(mu, g) * h
    return f, (f * (dl - 2.0 * g / (2.0 + g * g)))[:, :, None]


def _dhg_costa_gradient(mu: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    a = _col(p, 2)
    h1, dl1 = _hg_dlog(mu, _col(p, 0))
    h2, dl2 = _hg_dlog(mu, _col(p, 1))
    jac = np.stack([a * h1 * dl1, (1.0 - a) * h2 * dl2, h1 - h2], axis=-1)
    return a * h1 + (1.0 - a) * h2, jac


def _dhg_kobe_gradient(mu: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    f = _col(p, 2)
    h1, dl1 = _hg_dlog(mu, _col(p, 0))
    h2, dl2 = _hg_dlog(mu, _col(p, 1))
    jac = np.stack([(1.0 - f) * h1 * dl1, f * h2 * dl2, h2 - h1], axis=-1)
    return (1.0 - f) * h1 + f * h2, jac


def _hg_draine_gradient(mu: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    gh, gd, a, w = (_col(p, i) for i in range(4))
    h, dlh = _hg_dlog(mu, gh)
    hd, dld = _hg_dlog(mu, gd)
    norm = 1.0 + a * (1.0 + 2.0 * gd * gd) / 3.0
    shape = 1.0 + a * mu * mu
    draine = hd * shape / norm
    d_gd = draine * (dld - (4.0 * a * gd / 3.0) / norm)
    d_a = draine * (mu * mu / shape - ((1.0 + 2.0 * gd * gd) / 3.0) / norm)
    jac = np.stack([(1.0 - w) * h * dlh, w * d_gd, w * d_a, draine - h], axis=-1)
    return (1.0 - w) * h + w * draine, jac


def _two_term_hg_gradient(mu: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    b, c = _col(p, 0), _col(p, 1)
    hf, dlf = _hg_dlog(mu, b)
    hb, dlb = _hg_dlog(mu, -b)
    d_b = 0.5 * (1.0 - c) * hf * dlf - 0.5 * (1.0 + c) * hb * dlb
    jac = np.stack([d_b, 0.5 * (hb - hf)], axis=-1)
    return 0.5 * (1.0 - c) * hf + 0.5 * (1.0 + c) * hb, jac


def _gauss_two_node(m: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Nodes x1 >= x2 and weight of x1 of the two-node rule with moments m1..m3 (m0 = 1).

    ``<P_l>`` of HG(g) is ``g^l``, so a two-lobe model's lobes are the nodes.
    Falls back to (m1 + s, m1 - s, 1/2), s = sqrt(max(m2 - m1^2, 0)), where the
    moments are not those of two nodes.
    """
    m1, m2, m3 = m[:, 1], m[:, 2], m[:, 3]
    var = m2 - m1 * m1
    det = np.where(np.abs(var) > 1e-12, var, 1e-12)
    a = (m3 - m1 * m2) / det  # x^2 = a x + b for both nodes
    b = (m2 * m2 - m1 * m3) / det
    disc = a * a + 4.0 * b
    ok = (disc > 0) & (var > 1e-12)
    root = np.sqrt(np.where(ok, disc, 0.0))
    x1 = np.where(ok, 0.5 * (a + root), m1 + np.sqrt(np.maximum(var, 0.0)))
    x2 = np.where(ok, 0.5 * (a - root), m1 - np.sqrt(np.maximum(var, 0.0)))
    span = np.where(np.abs(x1 - x2) > 1e-12, x1 - x2, 1.0)
    w1 = np.where(ok, (m1 - x2) / span, 0.5)
    return x1, x2, w1


def _clip_g(x: FloatArray) -> FloatArray:
    return np.clip(x, -0.98, 0.98)


def _const(n: int, *values: float) -> FloatArray:
    return np.tile(np.array(values, dtype=np.float64), (n, 1))


def _hg_starts(m: FloatArray) -> list[FloatArray]:
    n = m.shape[0]
    return [_clip_g(m[:, 1:2]), _const(n, 0.5), _const(n, -0.3)]


def _cs_starts(m: FloatArray) -> list[FloatArray]:
    n = m.shape[0]
    # Invert the CS mean cosine on a fine grid (monotonic in g): start at the table's g.
    grid = np.linspace(-0.98, 0.98, 197)
    gcs = np.asarray(cornette_shanks1992_asymmetry(g=grid))
    start = np.interp(np.clip(m[:, 1], gcs[0], gcs[-1]), gcs, grid)[:, None]
    return [start, _const(n, 0.5), _const(n, -0.3)]


def _dhg_costa_starts(m: FloatArray) -> list[FloatArray]:
    n = m.shape[0]
    x1, x2, w1 = _gauss_two_node(m)
    moment = np.stack([_clip_g(x1), _clip_g(x2), np.clip(w1, 0.02, 0.98)], axis=1)
    g = _clip_g(m[:, 1])
    return [
        moment,
        np.stack([np.clip(g + 0.2, -0.9, 0.95), np.clip(g - 0.4, -0.9, 0.9), np.full(n, 0.7)], 1),
        _const(n, 0.8, -0.2, 0.9),
        _const(n, 0.6, 0.1, 0.5),
    ]


def _dhg_kobe_starts(m: FloatArray) -> list[FloatArray]:
    n = m.shape[0]
    x1, x2, w1 = _gauss_two_node(m)
    moment = np.stack(
        [np.clip(x1, 0.02, 0.98), np.clip(x2, -0.98, -0.02), np.clip(1.0 - w1, 0.02, 0.98)], 1
    )
    g = np.clip(m[:, 1], 0.05, 0.95)
    return [moment, np.stack([g, np.full(n, -0.3), np.full(n, 0.1)], 1), _const(n, 0.8, -0.5, 0.3)]


def _hg_draine_starts(m: FloatArray) -> list[FloatArray]:
    n = m.shape[0]
    x1, x2, w1 = _gauss_two_node(m)
    moment = np.stack(
        [_clip_g(x1), _clip_g(x2), np.full(n, 1.0), np.clip(1.0 - w1, 0.02, 0.98)], axis=1
    )
    return [moment, _const(n, 0.9, 0.5, 10.0, 0.5), _const(n, 0.6, -0.2, 1.0, 0.3)]


def _two_term_hg_starts(m: FloatArray) -> list[FloatArray]:
    n = m.shape[0]
    # <P_1> = -c b, <P_2> = b^2: b from the second moment, c from the first.
    b = np.clip(np.sqrt(np.clip(m[:, 2], 0.0, None)), 0.02, 0.98)
    c = np.clip(-m[:, 1] / b, -0.98, 0.98)
    return [np.stack([b, c], 1), _const(n, 0.5, -0.5), _const(n, 0.9, -0.9)]


def _forward_lobe_first(p: FloatArray) -> FloatArray:
    """Costa's DHG with g1 >= g2 (swapping the lobes with alpha -> 1 - alpha)."""
    out = p.copy()
    swap = p[:, 0] < p[:, 1]
    out[swap, 0], out[swap, 1], out[swap, 2] = p[swap, 1], p[swap, 0], 1.0 - p[swap, 2]
    return out


# ------------------------------------------------------------------- registry


@dataclass(frozen=True)
class AnalyticModel:
    """One analytic phase function, by name: its formula, parameters and source.

    Everything that reads a phase model (the TOML configuration, the presets,
    :func:`~dustoptics.scattering.fit.fit_phase`, the sky's fitted
    approximations) reads this record; nothing lists the models a second time.

    Attributes
    ----------
    name : str
        Registry name (the function's name, author and year).
    phase : callable
        ``phase(mu, **parameters)`` [sr^-1], with its range checks.
    asymmetry : callable
        ``asymmetry(**parameters)``, the mean cosine [-].
    parameters : tuple of str
        Names of the keyword parameters, in order.
    citation : str
        Where the model is defined.
    formula : str
        The model in words and symbols (``mu = cos(theta)``).
    aliases : tuple of str
        Other accepted spellings (hyphenated, short) of :attr:`name`.
    kernel : callable or None
        ``kernel(mu, *parameters)``: the same formula as :attr:`phase`
        without range checks, for arrays that are already valid.
    bounds : tuple of (float, float)
        Per parameter, the open range a fit searches (empty: not fitted).
    starts : callable or None
        ``starts(moments)``: starting points (a list of arrays, shape
        ``(n, k)``) from the Legendre moments ``<P_0..P_3>`` of ``n`` tables
        (shape ``(n, 4)``).
    gradient : callable or None
        ``gradient(mu, p)`` -> ``(value, d value / d p)``, shapes ``(n, m)``
        and ``(n, m, k)``, for parameters ``p`` of shape ``(n, k)`` and
        ``mu`` of shape ``(m,)``: the analytic derivatives a fit uses.
    canonical : callable or None
        ``canonical(p)``: the one ordering of equivalent parameter sets a fit
        reports (a two-lobe model's lobes), or None to report as found.
    fit_name : str or None
        The name a fit's results and files carry (:attr:`name` or one of
        :attr:`aliases`); None: :attr:`name`.  The package's own models keep
        the hyphenated names their fits have always been written under
        (``cornette-shanks1992``), so fit outputs do not change.
    fit_citation : str or None
        The citation a fit's results carry; None: :attr:`citation`.
    """

    name: str
    phase: Callable[..., FloatOrArray]
    asymmetry: Callable[..., FloatOrArray]
    parameters: tuple[str, ...]
    citation: str
    formula: str = ""
    aliases: tuple[str, ...] = ()
    kernel: Callable[..., FloatArray] | None = None
    bounds: tuple[tuple[float, float], ...] = ()
    starts: Callable[[FloatArray], list[FloatArray]] | None = None
    gradient: Callable[[FloatArray, FloatArray], tuple[FloatArray, FloatArray]] | None = None
    canonical: Callable[[FloatArray], FloatArray] | None = None
    fit_name: str | None = None
    fit_citation: str | None = None

    @property
    def fittable(self) -> bool:
        """Whether :func:`~dustoptics.scattering.fit.fit_phase` can fit it."""
        return self.gradient is not None and self.starts is not None and bool(self.bounds)

    @property
    def fit_label(self) -> str:
        """The name a fit's results and files carry: :attr:`fit_name`, else :attr:`name`."""
        return self.fit_name or self.name


_REGISTRY: dict[str, AnalyticModel] = {}
_ALIASES: dict[str, str] = {}

#: Every analytic phase model, by name (a read-only view of the registry).
ANALYTIC_MODELS: Final[Mapping[str, AnalyticModel]] = MappingProxyType(_REGISTRY)

#: Other spellings of the models' names (hyphenated, short), each to its registry name.
ANALYTIC_MODEL_ALIASES: Final[Mapping[str, str]] = MappingProxyType(_ALIASES)


def register_analytic_model(model: AnalyticModel) -> AnalyticModel:
    """Add a phase model to :data:`ANALYTIC_MODELS` (its aliases to :data:`ANALYTIC_MODEL_ALIASES`).

    The package's own models are registered this way when this module is
    imported; a model registered later is read like them by the TOML
    configuration and, with ``bounds``, ``starts`` and ``gradient``, by
    :func:`~dustoptics.scattering.fit.fit_phase`.

    Parameters
    ----------
    model : AnalyticModel
        The record.

    Returns
    -------
    AnalyticModel
        ``model`` itself.

    Raises
    ------
    ValueError
        A name or alias already taken; ``bounds`` that do not give one range
        per parameter; a fittable model without ``kernel``.
    """
    for label in (model.name, *model.aliases):
        if label in _REGISTRY or label in _ALIASES:
            raise ValueError(f"phase model name or alias {label!r} is already registered")
    if model.bounds and len(model.bounds) != len(model.parameters):
        raise ValueError(
            f"bounds of {model.name!r} must give one (low, high) per parameter "
            f"{model.parameters}; got {len(model.bounds)}"
        )
    if model.fittable and model.kernel is None:
        raise ValueError(f"fittable phase model {model.name!r} needs a kernel")
    if model.fit_name is not None and model.fit_name not in (model.name, *model.aliases):
        raise ValueError(
            f"fit_name of {model.name!r} must be its name or one of its aliases "
            f"{model.aliases}; got {model.fit_name!r}"
        )
    _REGISTRY[model.name] = model
    for alias in model.aliases:
        _ALIASES[alias] = model.name
    return model


_G: Final = (-1.0, 1.0)  # the open range of an asymmetry parameter g

# The package's own models, in the order of the module docstring.
for _model in (
    AnalyticModel(
        "rayleigh",
        rayleigh,
        rayleigh_asymmetry,
        (),
        CHANDRASEKHAR_1950,
        formula="3 (1 + mu^2) / (16 pi)",
    ),
    AnalyticModel(
        "rayleigh_depolarized",
        rayleigh_depolarized,
        rayleigh_depolarized_asymmetry,
        ("depolarization",),
        f"{CHANDRASEKHAR_1950}; {BUCHOLTZ_1995}",
        formula="3 ((1 + 3 gamma) + (1 - gamma) mu^2) / (16 pi (1 + 2 gamma)), "
        "gamma = delta / (2 - delta), delta the depolarization factor",
        aliases=("rayleigh-depolarized",),
    ),
    AnalyticModel(
        "rayleigh_penndorf1957",
        rayleigh_penndorf1957,
        rayleigh_penndorf1957_asymmetry,
        (),
        f"{PENNDORF_1957}; as printed in {COSTA_2021}",
        formula="0.7629 (1 + 0.932 mu^2) / (4 pi)",
        aliases=("rayleigh-penndorf1957",),
    ),
    AnalyticModel(
        "henyey_greenstein",
        henyey_greenstein,
        henyey_greenstein_asymmetry,
        ("g",),
        HENYEY_GREENSTEIN_1941,
        formula="HG(g) = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2))",
        aliases=("henyey-greenstein", "hg"),
        kernel=_hg,
        bounds=(_G,),
        starts=_hg_starts,
        gradient=_hg_gradient,
        fit_name="henyey-greenstein",
        fit_citation="L. G. Henyey and J. L. Greenstein, Astrophys. J. 93, 70-83 (1941), "
        "doi:10.1086/144246",
    ),
    AnalyticModel(
        "dhg_costa2021",
        dhg_costa2021,
        dhg_costa2021_asymmetry,
        ("g1", "g2", "alpha"),
        COSTA_2021,
        formula="alpha HG(g1) + (1 - alpha) HG(g2)",
        aliases=("dhg-costa2021", "dhg"),
        kernel=_dhg_costa,
        bounds=(_G, _G, (0.0, 1.0)),
        starts=_dhg_costa_starts,
        gradient=_dhg_costa_gradient,
        canonical=_forward_lobe_first,
        fit_name="dhg-costa2021",
        fit_citation="J. Costa et al., IEEE TVCG 27(2), 785-795 (2021), "
        "doi:10.1109/TVCG.2020.3030333",
    ),
    AnalyticModel(
        "dhg_kobe2026",
        dhg_kobe2026,
        dhg_kobe2026_asymmetry,
        ("g1", "g2", "f"),
        KOBE_2026,
        formula="(1 - f) HG(g1) + f HG(g2), g1 >= 0 >= g2",
        aliases=("dhg-kobe2026", "dhg-kobe"),
        kernel=_dhg_kobe,
        bounds=((0.0, 1.0), (-1.0, 0.0), (0.0, 1.0)),
        starts=_dhg_kobe_starts,
        gradient=_dhg_kobe_gradient,
        fit_name="dhg-kobe2026",
        fit_citation="Kobe (2026), master's thesis (the seed's third source)",
    ),
    AnalyticModel(
        "cornette_shanks1992",
        cornette_shanks1992,
        cornette_shanks1992_asymmetry,
        ("g",),
        CORNETTE_SHANKS_1992,
        formula="3 (1 - g^2) (1 + mu^2) / (8 pi (2 + g^2) (1 + g^2 - 2 g mu)^(3/2))",
        aliases=("cornette-shanks1992", "cs"),
        kernel=_cornette_shanks,
        bounds=(_G,),
        starts=_cs_starts,
        gradient=_cs_gradient,
        fit_name="cornette-shanks1992",
        fit_citation="W. M. Cornette and J. G. Shanks, Appl. Opt. 31(16), 3152-3160 (1992), "
        "doi:10.1364/AO.31.003152",
    ),
    AnalyticModel(
        "draine2003",
        draine2003,
        draine2003_asymmetry,
        ("g", "alpha"),
        DRAINE_2003,
        formula="Draine(g, alpha) = HG(g) (1 + alpha mu^2) / (1 + alpha (1 + 2 g^2) / 3)",
        kernel=_draine,
    ),
    AnalyticModel(
        "hg_draine_jendersie_deon2023",
        hg_draine_jendersie_deon2023,
        hg_draine_jendersie_deon2023_asymmetry,
        ("g_hg", "g_d", "alpha", "w_d"),
        JENDERSIE_DEON_2023,
        formula="(1 - w_d) HG(g_hg) + w_d Draine(g_d, alpha), "
        "Draine(g, a) = HG(g) (1 + a mu^2) / (1 + a (1 + 2 g^2) / 3)",
        aliases=("hg-draine-jendersie-deon2023", "hg-draine"),
        kernel=_hg_draine,
        bounds=(_G, _G, (-1.0, 200.0), (0.0, 1.0)),
        starts=_hg_draine_starts,
        gradient=_hg_draine_gradient,
        fit_name="hg-draine-jendersie-deon2023",
        fit_citation="J. Jendersie and E. d'Eon, ACM SIGGRAPH 2023 Talks, "
        "doi:10.1145/3587421.3595409",
    ),
    AnalyticModel(
        "two_term_hg_hapke2012",
        two_term_hg_hapke2012,
        two_term_hg_hapke2012_asymmetry,
        ("b", "c"),
        HAPKE_2012,
        formula="(1 - c)/2 HG(b) + (1 + c)/2 HG(-b) (scattering angle; Hapke's phase "
        "angle is 180 deg - theta)",
        aliases=("two-term-hg-hapke2012", "tthg"),
        kernel=_two_term_hg,
        bounds=((0.0, 1.0), (-1.0, 1.0)),
        starts=_two_term_hg_starts,
        gradient=_two_term_hg_gradient,
        fit_name="two-term-hg-hapke2012",
        fit_citation="B. Hapke, Theory of Reflectance and Emittance Spectroscopy, 2nd ed., "
        "Cambridge University Press (2012), doi:10.1017/CBO9781139025683, section 6.4.2",
    ),
):
    register_analytic_model(_model)


def get_analytic_model(name: str) -> AnalyticModel:
    """The analytic phase function registered as ``name`` (or one of its aliases).

    Raises
    ------
    ValueError
        For an unknown name; the message lists the valid ones.
    """
    canonical = ANALYTIC_MODEL_ALIASES.get(name, name)
    check_choice("name", canonical, (*ANALYTIC_MODELS, *ANALYTIC_MODEL_ALIASES))
    return ANALYTIC_MODELS[canonical]


# --------------------------------------------------------- Costa et al. 2021


class ExtrapolationWarning(UserWarning):
    """A parametrization was evaluated where its source gives no data and it misbehaves."""


def _readonly(name: str, values: Any) -> FloatArray:
    arr = as_float_array(name, values)
    arr = np.atleast_1d(arr)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a scalar or 1-dimensional; got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class DHGSpectrum:
    """Double Henyey-Greenstein parameters per wavelength, Costa et al.'s weighting.

    The phase function at wavelength ``i`` is
    ``alpha[i] HG(g1[i]) + (1 - alpha[i]) HG(g2[i])`` (:func:`dhg_costa2021`).

    Attributes
    ----------
    wavelength_nm : numpy.ndarray
        Vacuum wavelengths, 1-D. [nm]
    g1, g2 : numpy.ndarray
        Lobe parameters, ``|g| < 1``, same shape. [-]
    alpha : numpy.ndarray
        Weight of the ``g1`` lobe, in [0, 1], same shape. [-]
    model : str
        What the numbers are (source and variant).
    citation : str
        Where they come from.

    The arrays are read-only copies.
    """

    wavelength_nm: FloatArray
    g1: FloatArray
    g2: FloatArray
    alpha: FloatArray
    model: str
    citation: str

    convention: ClassVar[str] = "costa2021"

    def __post_init__(self) -> None:
        wl = _readonly("wavelength_nm", self.wavelength_nm)
        if not np.all(wl > 0):
            raise ValueError(f"wavelength_nm must be > 0 [nm]; got {_show(wl)}")
        fields = {"g1": self.g1, "g2": self.g2, "alpha": self.alpha}
        for name, values in fields.items():
            arr = _readonly(name, values)
            if arr.shape != wl.shape:
                raise ValueError(
                    f"{name} must have the shape of wavelength_nm {wl.shape}; got {arr.shape}"
                )
            if name == "alpha":
                mixing_weight(name, arr)
            else:
                _g(name, arr)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "wavelength_nm", wl)

    def phase(self, mu: ArrayLike) -> FloatArray:
        """Phase function [sr^-1] of shape ``(n_wavelength,) + mu.shape``."""
        m = _mu(mu)
        ex = (slice(None),) + (None,) * m.ndim
        return np.asarray(dhg_costa2021(m, g1=self.g1[ex], g2=self.g2[ex], alpha=self.alpha[ex]))

    def asymmetry(self) -> FloatArray:
        """Mean cosine per wavelength [-], shape ``(n_wavelength,)``."""
        return np.asarray(dhg_costa2021_asymmetry(g1=self.g1, g2=self.g2, alpha=self.alpha))


#: Costa et al.'s Mars DHG from their source code (OpenSpace), used in the paper's
#: renderings and by Meyran 2022 (Table 3.7 and appendix).  The code lists the
#: channels as (680, 550, 440) nm; stored here in increasing wavelength.  The default.
COSTA2021_MARS_DHG_CODE: Final = DHGSpectrum(
    wavelength_nm=np.array((440.0, 550.0, 680.0)),
    g1=np.array((0.67, 0.4, 0.03)),
    g2=np.array((0.094, 0.094, 0.094)),
    alpha=np.array((0.743, 0.743, 0.743)),
    model="costa2021 Mars DHG, source-code values",
    citation=f"{COSTA_2021}; values from their OpenSpace source as listed by {MEYRAN_2022}",
)

#: Costa et al.'s Mars DHG as printed in their paper's parameter table, at
#: (680, 550, 440) nm g2 = (0.094, 0.89, 0.099), alpha = (0.743, 0.04, 0.01); g1 as in
#: the code.  At 550 and 440 nm almost all weight goes to the g2 lobe, which then
#: dominates: the sky renders purple (Meyran 2022, section 3.4.2, calls these values
#: erroneous).  Recorded for reproduction only; NOT the default.
COSTA2021_MARS_DHG_PAPER: Final = DHGSpectrum(
    wavelength_nm=np.array((440.0, 550.0, 680.0)),
    g1=np.array((0.67, 0.4, 0.03)),
    g2=np.array((0.099, 0.89, 0.094)),
    alpha=np.array((0.01, 0.04, 0.743)),
    model="costa2021 Mars DHG, values printed in the paper (purple sky; not the default)",
    citation=f"{COSTA_2021}, parameter table",
)

#: Meyran 2022's quadratic through Costa et al.'s three g1 values,
#: ``g1(lambda) = a lambda^2 + b lambda + c`` with lambda in nm: (a, b, c).
MEYRAN2022_G1_COEFFICIENTS: Final = (-1.63170163e-6, -8.39160839e-4, 1.35512821)

#: The wavelength span of Costa et al.'s data; outside it the quadratic extrapolates. [nm]
COSTA2021_WAVELENGTH_RANGE_NM: Final = (440.0, 680.0)

_COSTA_OUTSIDE: Final = ("quadratic", "clamp", "error")


def _meyran_g1(wavelength_nm: FloatArray) -> FloatArray:
    a, b, c = MEYRAN2022_G1_COEFFICIENTS
    return (a * wavelength_nm + b) * wavelength_nm + c


def costa2021_mars_dhg(wavelength_nm: ArrayLike, *, outside: str = "quadratic") -> DHGSpectrum:
    """Costa et al.'s Mars double Henyey-Greenstein at any wavelength.

    ``g2 = 0.094`` and ``alpha = 0.743`` at every wavelength (Costa et al.'s
    source code), and ``g1`` from Meyran's quadratic through the code's three
    values (0.67, 0.4, 0.03 at 440, 550, 680 nm)::

        g1(lambda) = -1.63170163e-6 lambda^2 - 8.39160839e-4 lambda + 1.35512821

    with ``lambda`` in nm.  The quadratic reproduces the three values to 6e-9.

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelengths, scalar or 1-D, > 0. [nm]
    outside : {"quadratic", "clamp", "error"}
        What to do outside Costa et al.'s 440-680 nm:

        - ``"quadratic"`` (Meyran 2022): evaluate the quadratic everywhere.  It
          falls below zero above 689.76 nm (g1(700) = -0.032, g1(830) = -0.47),
          which turns the forward lobe into a backward one; an
          :class:`ExtrapolationWarning` names those wavelengths.  Below
          275.55 nm or above 971.47 nm it leaves ``|g1| < 1`` and ValueError is
          raised.
        - ``"clamp"``: hold ``g1`` at the quadratic's end values,
          ``g1(440) = 0.670000005272`` below 440 nm and
          ``g1(680) = 0.030000005768`` above 680 nm (continuous at the ends).
        - ``"error"``: raise ValueError for any wavelength outside
          [440, 680] nm.

    Returns
    -------
    DHGSpectrum
        Parameters per wavelength, shape ``(n_wavelength,)``.

    Notes
    -----
    The values printed in Costa et al.'s paper differ
    (:data:`COSTA2021_MARS_DHG_PAPER`) and give a purple sky; they are not
    used here.  The clamp is an option, never applied silently.

    References
    ----------
    .. [1] J. Costa et al., "Interactive visualization of atmospheric effects
       for celestial bodies," IEEE Trans. Vis. Comput. Graph., vol. 27, no. 2,
       pp. 785-795, 2021, doi:10.1109/TVCG.2020.3030333.
    .. [2] T. Meyran, "Physically based real-time rendering of the Martian
       atmosphere," M.Sc. thesis, Hochschule Hannover, 2022, section 4.
    """
    check_choice("outside", outside, _COSTA_OUTSIDE)
    wl = _readonly("wavelength_nm", wavelength_nm)
    if not np.all(wl > 0):
        raise ValueError(f"wavelength_nm must be > 0 [nm]; got {_show(wavelength_nm)}")
    low, high = COSTA2021_WAVELENGTH_RANGE_NM
    beyond = (wl < low) | (wl > high)
    if outside == "error" and np.any(beyond):
        raise ValueError(
            f"wavelength_nm [nm] must be in the closed interval [{low}, {high}] with "
            f"outside='error' (Costa et al.'s data span); got {_show(wl[beyond])}; "
            f"use outside='clamp' or 'quadratic' to extend"
        )
    if outside == "clamp":
        g1 = _meyran_g1(np.clip(wl, low, high))
    else:
        g1 = _meyran_g1(wl)
        invalid = np.abs(g1) >= 1.0
        if np.any(invalid):
            raise ValueError(
                f"Meyran's quadratic g1(lambda) leaves the Henyey-Greenstein domain |g1| < 1 "
                f"below 275.55 nm and above 971.47 nm; got wavelength_nm {_show(wl[invalid])}; "
                f"use outside='clamp'"
            )
        negative = g1 < 0.0
        if np.any(negative):
            warnings.warn(
                f"Meyran's quadratic gives g1 < 0 (a backward lobe) above 689.76 nm, an "
                f"extrapolation artefact: at wavelength_nm {_show(wl[negative])} g1 = "
                f"{_show(np.round(g1[negative], 4))}; use outside='clamp' to hold "
                f"g1(680 nm) = 0.03",
                ExtrapolationWarning,
                stacklevel=2,
            )
    n = wl.shape
    return DHGSpectrum(
        wavelength_nm=wl,
        g1=g1,
        g2=np.full(n, 0.094),
        alpha=np.full(n, 0.743),
        model=f"costa2021 Mars DHG, g1 from meyran2022 quadratic, outside={outside!r}",
        citation=f"{COSTA_2021}; g1(lambda) from {MEYRAN_2022}",
    )


# ------------------------------------------------------------ Collienne 2013


@dataclass(frozen=True)
class Collienne2013:
    """Collienne et al.'s Mars parameters for Bruneton's sky model.

    Rayleigh-like scattering coefficients chosen by eye, increasing with
    wavelength (the reverse of molecular Rayleigh scattering) to give a
    yellowish day sky and a bluish sunset, and one wavelength-independent
    Cornette-Shanks aerosol phase function.  A renderer preset, not a
    physical model (Meyran 2022, section 3.4.1).

    Attributes
    ----------
    wavelength_nm : tuple of float
        (440, 510, 680). [nm]
    rayleigh_scattering_per_m : tuple of float
        (5.75e-6, 13.57e-6, 19.918e-6), as in Meyran's configuration file.
        Meyran's eq. (3.1) prints the same digits times 1e-3 with no unit. [m^-1]
    aerosol_g : float
        Cornette-Shanks ``g`` used here: 0.8, the value Meyran's text (section
        4) attributes to Collienne's model. [-]
    aerosol_g_alternatives : tuple of (float, str)
        Other values found for the same model: 0.76 in CosmoScout VR's
        reproduction, 0.5 in Meyran's configuration file.  Meyran's shader
        listing for this model evaluates Henyey-Greenstein, not Cornette-Shanks.
    citation : str
        Source.
    """

    wavelength_nm: tuple[float, ...] = (440.0, 510.0, 680.0)
    rayleigh_scattering_per_m: tuple[float, ...] = (5.75e-6, 13.57e-6, 19.918e-6)
    aerosol_g: float = 0.8
    aerosol_g_alternatives: tuple[tuple[float, str], ...] = (
        (0.76, f"CosmoScout VR's reproduction ({COSMOSCOUT_VR})"),
        (0.5, f"Meyran's configuration file ({MEYRAN_2022}, appendix)"),
    )
    citation: str = COLLIENNE_2013

    def aerosol_phase(self, mu: ArrayLike) -> FloatOrArray:
        """Aerosol phase function [sr^-1]: ``cornette_shanks1992(mu, g=aerosol_g)``."""
        return cornette_shanks1992(mu, g=self.aerosol_g)


#: Collienne et al. 2013 Mars preset (see :class:`Collienne2013`).
COLLIENNE2013_MARS: Final = Collienne2013()
