"""Aerosol coefficients from formulas instead of Mie theory.

- :func:`angstrom_beta_per_m`: Ångström's turbidity law
  ``beta(lambda) = beta0 (lambda / 1 um)^(-alpha)``.
- :func:`ada_qext`: van de Hulst's anomalous diffraction approximation (ADA)
  of the extinction efficiency of an absorbing sphere (Costa et al. 2021,
  eq. 19), and :func:`ada_cext_um2`, its average over a size distribution,
  ``<C_ext> = int n(r) pi r^2 Q_ext(r) dr``, by deterministic Gauss-Legendre
  quadrature.
- :func:`costa2021_turbidity_beta_sca_per_m`: Costa et al.'s scattering
  coefficient from the turbidity (their eq. 17, after Preetham et al. 1999),
  and :func:`costa2021_aerosol_coefficients`, which pairs it with the ADA
  extinction as Costa et al. and CosmoScout VR's ``hulst`` mode do, and warns
  (:class:`ScatteringExceedsExtinctionWarning`) where the two unrelated
  approximations give ``beta_sca > beta_ext``.

ADA accuracy
------------
The ADA assumes a large size parameter and ``|m - 1| << 1``, and it omits
the edge (grazing-ray) contribution, so it falls short of exact Mie.  Measured
against :func:`dustoptics.scattering.optics.compute_optics` for a modified gamma
distribution (v_eff = 0.2) at 440, 550 and 680 nm (``tests/test_parametric.py``):

=====================  ========  =====================
m                      r_eff     ADA / Mie - 1
=====================  ========  =====================
1.52 + 0.006i (Mars)   1.6 um    -11.7 % to -14.8 %
1.52 + 0.006i          5.0 um    -6.0 % to -7.8 %
1.05                   5.0 um    -4.0 % to -4.2 %
=====================  ========  =====================

Use exact Mie for anything quantitative; the ADA is here to reproduce Costa
et al. and CosmoScout VR's ``hulst`` mode.

References
----------
.. [1] H. C. van de Hulst, Light Scattering by Small Particles, Wiley (1957);
   Dover (1981), section 11.22, eq. (22) [ADA for absorbing spheres].
.. [2] J. Costa, A. Bock, C. Emmart, C. Hansen, A. Ynnerman and C. Silva,
   "Interactive visualization of atmospheric effects for celestial bodies,"
   IEEE Trans. Vis. Comput. Graph. 27(2), 785-795 (2021),
   doi:10.1109/TVCG.2020.3030333, eq. (17), (18), (19).
.. [3] A. J. Preetham, P. Shirley and B. Smits, "A practical analytic model for
   daylight," Proc. SIGGRAPH 99, 91-100 (1999), doi:10.1145/311535.311545.
.. [4] A. Ångström, "On the atmospheric transmission of sun radiation and on
   dust in the air," Geogr. Ann. 11, 156-166 (1929), doi:10.1080/20014422.1929.11880498.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dustoptics._validation import (
    _show,
    as_float_array,
    as_increasing_grid,
    check_positive,
    check_real,
)
from dustoptics.particles.sizedist import SizeDistribution
from dustoptics.scattering.optics import resolve_refractive_index
from dustoptics.scattering.quadrature import gauss_legendre

__all__ = [
    "COSTA2021_MARS_HULST",
    "CostaAerosolCoefficients",
    "ScatteringExceedsExtinctionWarning",
    "ada_cext_um2",
    "ada_qext",
    "angstrom_beta_per_m",
    "costa2021_aerosol_coefficients",
    "costa2021_turbidity_beta_sca_per_m",
]

FloatArray = NDArray[np.float64]

_UM2_TO_M2: Final = 1e-12


class ScatteringExceedsExtinctionWarning(UserWarning):
    """A parametric scattering coefficient exceeds the extinction it is paired with."""


# ------------------------------------------------------------------ Ångström


def angstrom_beta_per_m(
    wavelength_nm: ArrayLike, *, beta0_per_m: float, alpha: float
) -> FloatArray:
    """Ångström's turbidity law, ``beta = beta0 (lambda / 1 um)^(-alpha)``.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, > 0. [nm]
    beta0_per_m : float
        Coefficient at 1 um, > 0.  Ångström's turbidity ``beta`` is an optical
        depth; for an exponential layer of scale height ``H`` the coefficient
        at the ground is ``beta / H`` (as in Bruneton's 2016 evaluation:
        ``beta = 0.04``, ``H = 1200 m``). [m^-1]
    alpha : float
        Ångström exponent (0 to about 2.5 for real aerosols; any finite value
        is accepted). [-]

    Returns
    -------
    numpy.ndarray
        Coefficient at each wavelength. [m^-1]

    Examples
    --------
    >>> float(angstrom_beta_per_m(500.0, beta0_per_m=1e-5, alpha=1.0))
    2e-05
    """
    wl = as_float_array("wavelength_nm", wavelength_nm)
    if np.any(wl <= 0.0):
        raise ValueError(f"wavelength_nm must be > 0 nm; got {_show(wl[wl <= 0.0])}")
    b0 = check_positive("beta0_per_m", beta0_per_m, unit="m^-1")
    a = check_real("alpha", alpha)
    return b0 * (wl / 1000.0) ** (-a)


# ---------------------------------------------------------------------- ADA

# K(w) = 1/2 + exp(-w)/w + (exp(-w) - 1)/w^2 = sum_{j>=1} (-1)^(j+1) (j+1)/(j+2)! w^j
_SERIES_TERMS: Final = 30
_SERIES_COEF: Final = np.array(
    [(-1.0) ** (j + 1) * (j + 1) / math.factorial(j + 2) for j in range(1, _SERIES_TERMS + 1)]
)
_SERIES_BELOW: Final = 0.5


def _k_function(w: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """van de Hulst's K(w), with the power series near w = 0 (no cancellation)."""
    out = np.empty_like(w)
    small = np.abs(w) < _SERIES_BELOW
    ws = w[small]
    acc = np.zeros_like(ws)
    for c in _SERIES_COEF[::-1]:
        acc = (acc + c) * ws
    out[small] = acc
    wl = w[~small]
    e = np.exp(-wl)
    out[~small] = 0.5 + e / wl + (e - 1.0) / (wl * wl)
    return out


def ada_qext(
    *, wavelength_nm: ArrayLike, radius_um: ArrayLike, refractive_index: ArrayLike
) -> FloatArray:
    """Extinction efficiency in the anomalous diffraction approximation.

    With ``rho = 4 pi r (n - 1) / lambda`` and ``tan(b) = k / (n - 1)``
    (Costa et al. 2021, eq. 19; van de Hulst 1957, 11.22)::

        Q = 2 - 4 e^(-rho tan b) (cos b / rho) sin(rho - b)
              - 4 e^(-rho tan b) (cos b / rho)^2 cos(rho - 2 b)
              + 4 (cos b / rho)^2 cos(2 b)

    evaluated as ``Q = 4 Re K(w)``, ``w = rho (tan b + i)``, with the power
    series of ``K`` for ``|w| < 0.5`` so that small spheres keep full
    precision (``Q -> rho^2 / 2`` for ``k = 0``).

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelength (relative to the medium), > 0. [nm]
    radius_um : array_like
        Sphere radius, > 0. [um]
    refractive_index : array_like of complex
        ``m = n + i k``, ``n > 1``, ``k >= 0``; all three broadcast. [-]

    Returns
    -------
    numpy.ndarray
        ``Q_ext``. [-]

    Raises
    ------
    ValueError
        ``n <= 1`` (the approximation's phase shift ``rho`` must be positive),
        ``k < 0``, or a non-positive wavelength or radius.
    """
    wl = as_float_array("wavelength_nm", wavelength_nm)
    r = as_float_array("radius_um", radius_um)
    if np.any(wl <= 0.0):
        raise ValueError(f"wavelength_nm must be > 0 nm; got {_show(wl[wl <= 0.0])}")
    if np.any(r <= 0.0):
        raise ValueError(f"radius_um must be > 0 um; got {_show(r[r <= 0.0])}")
    m = np.asarray(refractive_index, dtype=np.complex128)
    if not np.all(np.isfinite(m)):
        raise ValueError(f"refractive_index must be finite; got {_show(m)}")
    if np.any(m.real <= 1.0):
        raise ValueError(
            f"refractive_index must have n > 1 for the anomalous diffraction approximation; got {_show(m)}"
        )
    if np.any(m.imag < 0.0):
        raise ValueError(f"refractive_index must have k >= 0 (m = n + i k); got {_show(m)}")
    rho = 4.0 * math.pi * (r * 1000.0) * (m.real - 1.0) / wl
    w = rho * (m.imag / (m.real - 1.0)) + 1j * rho
    w = np.asarray(w, dtype=np.complex128)
    shape = w.shape
    q = 4.0 * _k_function(w.ravel()).real
    return q.reshape(shape)


def _radius_panels(
    distribution: SizeDistribution, wavelength_nm: float, n_minus_1: float
) -> tuple[FloatArray, FloatArray]:
    """Nodes and weights (including n(r)) over the distribution's radius range."""
    r_lo, r_hi = distribution.radius_bounds_um(
        tail_fraction=1e-9, lower_moment=2.0, upper_moment=2.0
    )
    # Panel edges: at most a factor 1.25 in radius (small particles) and at most
    # pi/4 in the phase shift rho (one eighth of an ADA oscillation).
    drho_dr = 4.0 * math.pi * 1000.0 * n_minus_1 / wavelength_nm
    edges = [r_lo]
    while edges[-1] < r_hi:
        r = edges[-1]
        edges.append(min(r_hi, r * 1.25, r + (math.pi / 4.0) / drho_dr))
    a = np.array(edges[:-1])
    b = np.array(edges[1:])
    t, wts = gauss_legendre(8)
    half = 0.5 * (b - a)
    nodes = (0.5 * (a + b))[:, None] + half[:, None] * t[None, :]
    weights = half[:, None] * wts[None, :]
    nodes = nodes.ravel()
    weights = weights.ravel() * np.asarray(distribution.pdf(nodes), dtype=np.float64)
    return nodes, weights


def ada_cext_um2(
    *,
    wavelength_nm: ArrayLike,
    refractive_index: Any,
    distribution: SizeDistribution,
) -> FloatArray:
    """Mean ADA extinction cross-section per particle over a size distribution.

    ``<C_ext> = int n(r) pi r^2 Q_ext(r) dr`` (Costa et al. 2021, eq. 18), with
    composite 8-point Gauss-Legendre panels no wider than a factor 1.25 in
    radius and pi/4 in the ADA phase shift, between radii that leave at most
    1e-9 of ``<r^2>`` in each tail (``Q_ext <= 4`` bounds the neglected part
    by ``4e-9 pi <r^2>``).

    Parameters
    ----------
    wavelength_nm : array_like
        Strictly increasing wavelengths. [nm]
    refractive_index : complex, sequence, str or callable
        As for :func:`dustoptics.scattering.optics.compute_optics`; ``n > 1``. [-]
    distribution : SizeDistribution
        Number size distribution (a Monodisperse one gives ``pi r^2 Q``).

    Returns
    -------
    numpy.ndarray
        ``<C_ext>`` per wavelength. [um^2]
    """
    if not isinstance(distribution, SizeDistribution):
        raise TypeError(
            f"distribution must be a SizeDistribution; got {type(distribution).__name__}"
        )
    wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    if wl[0] <= 0.0:
        raise ValueError(f"wavelength_nm must be > 0 nm; got minimum {wl[0]!r}")
    m, _ = resolve_refractive_index(refractive_index, wl)
    out = np.empty(wl.size)
    if distribution.is_monodisperse:
        r = distribution.moment(1.0)
        return math.pi * r * r * ada_qext(wavelength_nm=wl, radius_um=r, refractive_index=m)
    if not distribution.has_density:
        raise ValueError(
            f"distribution mixes Monodisperse and continuous modes; got {distribution!r}"
        )
    for i, (w, mi) in enumerate(zip(wl, m)):
        if mi.real <= 1.0:
            raise ValueError(
                f"refractive_index must have n > 1 for the anomalous diffraction approximation; "
                f"got {mi} at {w} nm"
            )
        nodes, weights = _radius_panels(distribution, float(w), float(mi.real - 1.0))
        q = ada_qext(wavelength_nm=w, radius_um=nodes, refractive_index=mi)
        out[i] = math.pi * float(np.sum(weights * nodes * nodes * q))
    return out


# --------------------------------------------------------- Costa turbidity


def costa2021_turbidity_beta_sca_per_m(
    wavelength_nm: ArrayLike,
    *,
    turbidity: float,
    junge_exponent: float,
    k_factor: ArrayLike,
) -> FloatArray:
    """Costa et al.'s aerosol scattering coefficient from the turbidity (eq. 17).

    .. math::

        \\beta_{sca} = 0.434\\, C(T)\\, \\pi \\left(\\frac{2 \\pi}{\\lambda}\\right)^{\\nu - 2} K,
        \\qquad C(T) = (0.65 T - 0.65) \\times 10^{-16}

    with ``lambda`` in metres (as in Preetham et al. 1999, whose concentration
    factor ``(0.6544 T - 0.6510) 1e-16`` Costa et al. round).

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, > 0. [nm]
    turbidity : float
        Turbidity ``T > 1`` (``C(T) > 0``; Costa et al. use 2-10). [-]
    junge_exponent : float
        Junge exponent ``nu`` in [2, 6] (van de Hulst's range; 4 in Costa et al.). [-]
    k_factor : array_like
        Götz's wavelength-dependent factor ``K``, one value or one per
        wavelength, > 0 (Costa et al. Mars: 0.31, 0.16, 0.27 at 680, 550,
        440 nm as printed; CosmoScout VR's reproduction uses 0.07, 0.16, 0.31
        at 440, 550, 680 nm). [-]

    Returns
    -------
    numpy.ndarray
        Scattering coefficient at the bottom of the layer. [m^-1]
    """
    wl = as_float_array("wavelength_nm", wavelength_nm)
    if np.any(wl <= 0.0):
        raise ValueError(f"wavelength_nm must be > 0 nm; got {_show(wl[wl <= 0.0])}")
    t = check_real("turbidity", turbidity)
    if t <= 1.0:
        raise ValueError(
            f"turbidity must be > 1 (C(T) = (0.65 T - 0.65) 1e-16 > 0); got {turbidity!r}"
        )
    nu = check_real("junge_exponent", junge_exponent)
    if not 2.0 <= nu <= 6.0:
        raise ValueError(f"junge_exponent must be in [2, 6]; got {junge_exponent!r}")
    k = as_float_array("k_factor", k_factor)
    if np.any(k <= 0.0):
        raise ValueError(f"k_factor must be > 0; got {_show(k)}")
    if k.ndim > 0 and k.shape != wl.shape:
        raise ValueError(
            f"k_factor must be one value or one per wavelength ({wl.size}); got shape {k.shape}"
        )
    c = (0.65 * t - 0.65) * 1e-16
    return 0.434 * c * math.pi * (2.0 * math.pi / (wl * 1e-9)) ** (nu - 2.0) * k


@dataclass(frozen=True, eq=False)
class CostaAerosolCoefficients:
    """Costa et al.'s parametric aerosol coefficients at the bottom of the layer.

    Attributes
    ----------
    wavelength_nm : numpy.ndarray
        Wavelengths. [nm]
    cext_um2 : numpy.ndarray
        ADA mean extinction cross-section per particle. [um^2]
    number_density_per_m3 : float
        Particle number density. [m^-3]
    beta_ext_per_m : numpy.ndarray
        ``N <C_ext>`` (ADA). [m^-1]
    beta_sca_per_m : numpy.ndarray
        Turbidity scattering coefficient (eq. 17). [m^-1]
    scattering_exceeds_extinction : numpy.ndarray of bool
        Where ``beta_sca > beta_ext`` (an impossible albedo > 1).
    """

    wavelength_nm: FloatArray
    cext_um2: FloatArray
    number_density_per_m3: float
    beta_ext_per_m: FloatArray
    beta_sca_per_m: FloatArray
    scattering_exceeds_extinction: NDArray[np.bool_]

    @property
    def beta_abs_per_m(self) -> FloatArray:
        """``beta_ext - beta_sca`` (negative where scattering exceeds extinction). [m^-1]"""
        return self.beta_ext_per_m - self.beta_sca_per_m


def costa2021_aerosol_coefficients(
    wavelength_nm: ArrayLike,
    *,
    refractive_index: Any,
    distribution: SizeDistribution,
    number_density_per_m3: float,
    turbidity: float,
    junge_exponent: float,
    k_factor: ArrayLike,
) -> CostaAerosolCoefficients:
    """ADA extinction (eq. 18-19) and turbidity scattering (eq. 17), checked.

    Parameters
    ----------
    wavelength_nm : array_like
        Strictly increasing wavelengths. [nm]
    refractive_index, distribution
        As for :func:`ada_cext_um2`.
    number_density_per_m3 : float
        Particle number density, > 0. [m^-3]
    turbidity, junge_exponent, k_factor
        As for :func:`costa2021_turbidity_beta_sca_per_m`.

    Returns
    -------
    CostaAerosolCoefficients

    Warns
    -----
    ScatteringExceedsExtinctionWarning
        Where ``beta_sca > beta_ext`` (CosmoScout VR found this for Costa et
        al.'s Mars parameters at turbidity 2-10).  The values are returned
        unchanged: nothing is clamped.
    """
    wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    n = check_positive("number_density_per_m3", number_density_per_m3, unit="m^-3")
    cext = ada_cext_um2(
        wavelength_nm=wl, refractive_index=refractive_index, distribution=distribution
    )
    beta_ext = n * cext * _UM2_TO_M2
    beta_sca = costa2021_turbidity_beta_sca_per_m(
        wl, turbidity=turbidity, junge_exponent=junge_exponent, k_factor=k_factor
    )
    bad = beta_sca > beta_ext
    if np.any(bad):
        warnings.warn(
            f"turbidity scattering exceeds ADA extinction (albedo > 1) at wavelength_nm "
            f"{wl[bad].tolist()}: beta_sca {beta_sca[bad].tolist()} > beta_ext {beta_ext[bad].tolist()} m^-1 "
            f"(turbidity={turbidity!r}, number_density_per_m3={n!r}); the two approximations are "
            "independent and these parameters are inconsistent",
            ScatteringExceedsExtinctionWarning,
            stacklevel=2,
        )
    return CostaAerosolCoefficients(
        wavelength_nm=wl,
        cext_um2=cext,
        number_density_per_m3=n,
        beta_ext_per_m=beta_ext,
        beta_sca_per_m=beta_sca,
        scattering_exceeds_extinction=bad,
    )


#: CosmoScout VR's reproduction of Costa et al.'s Mars aerosols (``hulst``
#: mode): wavelengths 440, 550, 680 nm; r = 1.6 um; m = 1.52 + (0.013, 0.006,
#: 0.001) i; K = (0.07, 0.16, 0.31); nu = 4; turbidity 1.01; N = 0.02e8 m^-3.
#: Costa et al.'s own Table 1 gives T in [2, 10] and N = 2.8e29 cm^-3, with
#: which scattering exceeds extinction.
COSTA2021_MARS_HULST: Final = MappingProxyType(
    {
        "wavelength_nm": (440.0, 550.0, 680.0),
        "radius_um": 1.6,
        "refractive_index": (1.52 + 0.013j, 1.52 + 0.006j, 1.52 + 0.001j),
        "k_factor": (0.07, 0.16, 0.31),
        "junge_exponent": 4.0,
        "turbidity": 1.01,
        "number_density_per_m3": 0.02e8,
    }
)
