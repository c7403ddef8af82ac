"""Rayleigh scattering of dry air after Bodhaine et al. (1999).

Their cross-section per molecule (eq. 2) from Peck & Reeder's (1972) index of
standard air scaled to the CO2 content (eq. 19) and the King factor of the N2,
O2, Ar and CO2 mixture (eqs. 5, 6, 23), and their sea-level column (eq. 30's
prefactor, scaled by the mean molecular weight, eq. 17).  The Earth default of
:mod:`dustoptics.atmosphere.gases` (``"bodhaine1999"``), which re-exports these.

References
----------
.. [1] B. A. Bodhaine, N. B. Wood, E. G. Dutton and J. R. Slusser, "On
   Rayleigh optical depth calculations," J. Atmos. Oceanic Technol. 16,
   1854-1861 (1999), doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
.. [2] E. R. Peck and K. Reeder, "Dispersion of air," J. Opt. Soc. Am. 62,
   958-962 (1972), doi:10.1364/JOSA.62.000958.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dustoptics._validation import _show, as_float_array
from dustoptics.particles.materials import GasFormulaIndex

__all__ = [
    "AIR_PECKREEDER1972",
    "BODHAINE_1999",
    "bodhaine1999_column_per_m2",
    "bodhaine1999_cross_section_m2",
    "bodhaine1999_king_factor",
]

FloatArray = NDArray[np.float64]

_CM2_TO_M2: Final = 1e-4


def _wavelengths(value: ArrayLike) -> FloatArray:
    arr = as_float_array("wavelength_nm", value)
    if np.any(arr <= 0.0):
        raise ValueError(f"wavelength_nm must be > 0 nm; got {_show(value)}")
    return arr


BODHAINE_1999: Final = (
    'B. A. Bodhaine, N. B. Wood, E. G. Dutton and J. R. Slusser, "On Rayleigh optical depth '
    'calculations," J. Atmos. Oceanic Technol. 16, 1854-1861 (1999), '
    "doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2"
)

#: Standard air (15 degC, 101325 Pa, 300 ppm CO2) after Peck & Reeder 1972,
#: Bodhaine et al. 1999 eq. (4): ``(n - 1) 1e8 = 8060.51 + 2480990 / (132.274 - s^2)
#: + 17455.7 / (39.32957 - s^2)``, ``s`` in um^-1, for wavelengths above 230 nm.
AIR_PECKREEDER1972: Final = GasFormulaIndex(
    name="air-peckreeder1972",
    citation=(
        'E. R. Peck and K. Reeder, "Dispersion of air," J. Opt. Soc. Am. 62, 958-962 (1972), '
        "doi:10.1364/JOSA.62.000958"
    ),
    c1=8060.51e-8,
    terms=((2480990e-8, 132.274), (17455.7e-8, 39.32957)),
    wavelength_range_nm=(230.0, 20000.0),
    reference_temperature_k=288.15,
    reference_pressure_pa=101325.0,
    reference_co2_ppm=300.0,
    source="Bodhaine et al. 1999, eq. (4)",
)

#: Molecules per cm^3 of Bodhaine et al.'s standard air (288.15 K, 1013.25 hPa). [cm^-3]
_BODHAINE_NS_PER_CM3: Final = 2.546899e19
#: Bodhaine et al.'s eq. (30) prefactor: the sea-level column at 45 deg N (1013.25 hPa,
#: 360 ppm CO2) times 1e-28 cm^2. [-]
_BODHAINE_EQ30_PREFACTOR: Final = 0.0021520
#: CO2 content of Bodhaine et al.'s eq. (30). [ppm by volume]
_BODHAINE_CO2_PPM: Final = 360.0


def _bodhaine_co2(co2_ppm: float) -> float:
    c = float(co2_ppm)
    if not (math.isfinite(c) and 0.0 <= c <= 1e4):
        raise ValueError(f"co2_ppm must be within [0, 10000] ppm by volume; got {co2_ppm!r}")
    return c


def bodhaine1999_king_factor(wavelength_nm: ArrayLike, *, co2_ppm: float = 360.0) -> FloatArray:
    """King factor of dry air with ``co2_ppm`` of CO2 (Bodhaine et al. 1999, eqs. 5, 6, 23).

    ``F = (78.084 F_N2 + 20.946 F_O2 + 0.934 F_Ar + C F_CO2) / (78.084 + 20.946 +
    0.934 + C)``, ``C`` the CO2 content in percent by volume, ``F_N2 = 1.034 +
    3.17e-4 / lambda^2``, ``F_O2 = 1.096 + 1.385e-3 / lambda^2 + 1.448e-4 /
    lambda^4``, ``F_Ar = 1``, ``F_CO2 = 1.15`` (``lambda`` in um).

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelengths, > 0. [nm]
    co2_ppm : float
        CO2 content, in [0, 10000]. [ppm by volume]

    Returns
    -------
    numpy.ndarray
        ``F(air)`` (1.048-1.053 at 360-830 nm). [-]
    """
    c = _bodhaine_co2(co2_ppm) * 1e-4  # percent by volume
    lam2 = (_wavelengths(wavelength_nm) * 1e-3) ** 2
    f_n2 = 1.034 + 3.17e-4 / lam2
    f_o2 = 1.096 + 1.385e-3 / lam2 + 1.448e-4 / lam2**2
    return np.asarray(
        (78.084 * f_n2 + 20.946 * f_o2 + 0.934 * 1.0 + c * 1.15) / (78.084 + 20.946 + 0.934 + c),
        dtype=np.float64,
    )


def bodhaine1999_cross_section_m2(
    wavelength_nm: ArrayLike, *, co2_ppm: float = 360.0
) -> FloatArray:
    """Rayleigh cross-section per molecule of dry air (Bodhaine et al. 1999, eq. 2).

    ``sigma = 24 pi^3 (n_s^2 - 1)^2 / (lambda^4 N_s^2 (n_s^2 + 2)^2) F(air)`` with
    ``n_s - 1 = (n_300 - 1)(1 + 0.54 (C - 0.0003))`` (their eq. 19, ``C`` the CO2
    content by volume, ``n_300`` Peck & Reeder's :data:`AIR_PECKREEDER1972`),
    ``N_s = 2.546899e19 cm^-3`` and ``F`` :func:`bodhaine1999_king_factor`.

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelengths in [230, 20000]. [nm]
    co2_ppm : float
        CO2 content, in [0, 10000]; their eq. 30 is at 360. [ppm by volume]

    Returns
    -------
    numpy.ndarray
        Cross-section per molecule. [m^2]

    Examples
    --------
    At 550 nm and 360 ppm the fit Bodhaine et al. give with their eq. (30),
    ``(1.0455996 - 341.29061 l^-2 - 0.90230850 l^2) / (1 + 0.0027059889 l^-2 -
    85.968563 l^2)`` in 1e-28 cm^2 (``l`` in um), is 45.1047 (4.51047e-31 m^2):

    >>> round(float(bodhaine1999_cross_section_m2(550.0)) * 1e31, 4)
    4.5105
    """
    wl = _wavelengths(wavelength_nm)
    c = _bodhaine_co2(co2_ppm) * 1e-6
    r = AIR_PECKREEDER1972.refractivity(wl) * (1.0 + 0.54 * (c - 3e-4))
    n2m1 = r * (2.0 + r)
    lam_cm = wl * 1e-7
    sigma_cm2 = (
        24.0
        * math.pi**3
        * n2m1**2
        / (lam_cm**4 * _BODHAINE_NS_PER_CM3**2 * (n2m1 + 3.0) ** 2)
        * bodhaine1999_king_factor(wl, co2_ppm=co2_ppm)
    )
    return np.asarray(sigma_cm2 * _CM2_TO_M2, dtype=np.float64)


def bodhaine1999_column_per_m2(*, co2_ppm: float = 360.0) -> float:
    """Molecules per m^2 in Bodhaine et al.'s sea-level column at 45 deg N, 1013.25 hPa.

    Their eq. (30)'s ``0.0021520`` over 1e-28 cm^2 at 360 ppm CO2, scaled by the
    mean molecular weight ``m_a = 15.0556 C + 28.9595`` [g mol^-1] (their eq. 17,
    ``C`` by volume) for another CO2 content (the column is ``P A / (m_a g)``). [m^-2]
    """
    c = _bodhaine_co2(co2_ppm) * 1e-6
    m_360 = 15.0556 * _BODHAINE_CO2_PPM * 1e-6 + 28.9595
    return _BODHAINE_EQ30_PREFACTOR / (1e-28 * _CM2_TO_M2) * m_360 / (15.0556 * c + 28.9595)
