"""Published clear-sky luminance distributions, for judging the Earth's sky.

- :func:`cie_relative_luminance`: the CIE standard general sky (ISO 15469:2004
  / CIE S 011/E:2003), ``L / L_z = f(chi) phi(Z) / (f(Z_s) phi(0))`` with the
  gradation ``phi(Z) = 1 + a exp(b / cos Z)`` and the indicatrix
  ``f(chi) = 1 + c (exp(d chi) - exp(d pi / 2)) + e cos^2 chi``, for the clear
  types 11, 12 and 13 (:data:`CIE_CLEAR_SKIES`);
- :func:`preetham_relative_luminance`: Preetham, Shirley and Smits' (1999)
  Perez distribution of the luminance with their turbidity coefficients
  (appendix A.2);
- :func:`horizon_to_zenith_table`: the luminance near the horizon over the
  zenith's, dustoptics' default Earth beside these models, as text.

References
----------
.. [1] ISO 15469:2004 / CIE S 011/E:2003, "Spatial distribution of daylight -
   CIE standard general sky," Table 1 (parameters a-e of the 15 types).
.. [2] R. Kittler, S. Darula and R. Perez, "A set of standard skies
   characterizing daylight conditions for computer and energy conscious
   design," report of the American-Slovak grant project US-SK 92 052 (1998).
.. [3] A. J. Preetham, P. Shirley and B. Smits, "A practical analytic model
   for daylight," Proc. SIGGRAPH 99, 91-100 (1999), doi:10.1145/311535.311545,
   appendix A.2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from types import MappingProxyType
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from dustoptics.atmosphere.sets import DEFAULT_EARTH_AEROSOL_OPTICAL_DEPTH, earth_atmosphere
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import sky_radiance

__all__ = [
    "CIE_CLEAR_SKIES",
    "HORIZON_VIEW_ELEVATION_DEG",
    "cie_relative_luminance",
    "horizon_to_zenith_table",
    "preetham_relative_luminance",
    "preetham_turbidity",
]

#: The CIE standard general sky's clear types: number -> (a, b, c, d, e) (ISO 15469 Table 1).
#: 11: white-blue sky with a distinct solar corona; 12: CIE standard clear sky, low
#: illuminance turbidity; 13: CIE standard clear sky, polluted atmosphere.
CIE_CLEAR_SKIES: Final = MappingProxyType(
    {
        11: (-1.0, -0.55, 10.0, -3.0, 0.45),
        12: (-1.0, -0.32, 10.0, -3.0, 0.45),
        13: (-1.0, -0.32, 16.0, -3.0, 0.30),
    }
)
#: "Near the horizon" of :func:`horizon_to_zenith_table`: 5 deg above it, where sky scanners
#: still measure (their lowest ring is centred at 6 deg) and the plane-parallel models hold. [deg]
HORIZON_VIEW_ELEVATION_DEG: Final = 5.0


def _angle_to_sun(
    view_zenith_deg: ArrayLike, view_azimuth_deg: ArrayLike, sun_zenith_deg: float
) -> np.ndarray:
    z = np.radians(np.asarray(view_zenith_deg, dtype=float))
    a = np.radians(np.asarray(view_azimuth_deg, dtype=float))
    zs = math.radians(sun_zenith_deg)
    c = np.cos(z) * math.cos(zs) + np.sin(z) * math.sin(zs) * np.cos(a)
    return np.arccos(np.clip(c, -1.0, 1.0))


def cie_relative_luminance(
    sky_type: int, *, view_zenith_deg: ArrayLike, view_azimuth_deg: ArrayLike, sun_zenith_deg: float
) -> np.ndarray:
    """Luminance over the zenith's of a CIE standard general sky. [-]

    Parameters
    ----------
    sky_type : {11, 12, 13}
        A clear type of :data:`CIE_CLEAR_SKIES`.
    view_zenith_deg, view_azimuth_deg : array_like
        Viewing direction, zenith 0-90, azimuth from the Sun's. [deg]
    sun_zenith_deg : float
        The Sun's zenith angle, 0-90. [deg]

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> round(float(cie_relative_luminance(12, view_zenith_deg=0.0, view_azimuth_deg=0.0,
    ...                                    sun_zenith_deg=30.0)), 12)
    1.0
    """
    if sky_type not in CIE_CLEAR_SKIES:
        raise ValueError(f"sky_type must be one of {sorted(CIE_CLEAR_SKIES)}; got {sky_type!r}")
    if not 0.0 <= sun_zenith_deg <= 90.0:
        raise ValueError(f"sun_zenith_deg must be within [0, 90] deg; got {sun_zenith_deg!r}")
    a, b, c, d, e = CIE_CLEAR_SKIES[sky_type]
    z = np.radians(np.asarray(view_zenith_deg, dtype=float))

    def phi(zen: np.ndarray) -> np.ndarray:
        cz = np.cos(zen)
        with np.errstate(divide="ignore"):
            return np.where(cz > 0.0, 1.0 + a * np.exp(b / np.where(cz > 0, cz, 1.0)), 1.0)

    def f(chi: np.ndarray) -> np.ndarray:
        return 1.0 + c * (np.exp(d * chi) - math.exp(d * math.pi / 2)) + e * np.cos(chi) ** 2

    chi = _angle_to_sun(view_zenith_deg, view_azimuth_deg, sun_zenith_deg)
    zs = np.radians(sun_zenith_deg)
    return np.asarray(f(chi) * phi(z) / (f(np.asarray(zs)) * phi(np.asarray(0.0))))


def preetham_turbidity(optical_depth_550nm: float) -> float:
    """The turbidity whose Preetham aerosol optical depth at 550 nm is the given one. [-]

    Inverse of :func:`~dustoptics.atmosphere.aerosols.preetham_optical_depth`:
    ``T = (tau (0.55)^1.3 + 0.04586025928522) / 0.04608365822050``.
    """
    beta = optical_depth_550nm * 0.55**1.3
    return (beta + 0.04586025928522) / 0.04608365822050


def preetham_relative_luminance(
    turbidity: float,
    *,
    view_zenith_deg: ArrayLike,
    view_azimuth_deg: ArrayLike,
    sun_zenith_deg: float,
) -> np.ndarray:
    """Luminance over the zenith's of Preetham et al.'s (1999) sky. [-]

    ``F(theta, gamma) / F(0, theta_s)`` with Perez's
    ``F = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma)`` and
    the luminance coefficients of their appendix A.2: ``A = 0.1787 T - 1.4630``,
    ``B = -0.3554 T + 0.4275``, ``C = -0.0227 T + 5.3251``,
    ``D = 0.1206 T - 2.5771``, ``E = -0.0670 T + 0.3703``.

    Parameters
    ----------
    turbidity : float
        ``T``, > 1 (Preetham et al. show 2-10). [-]
    view_zenith_deg, view_azimuth_deg : array_like
        Viewing direction, zenith 0-90, azimuth from the Sun's. [deg]
    sun_zenith_deg : float
        The Sun's zenith angle, 0-90. [deg]

    Returns
    -------
    numpy.ndarray
    """
    if not turbidity > 1.0:
        raise ValueError(f"turbidity must be > 1; got {turbidity!r}")
    t = float(turbidity)
    a, b = 0.1787 * t - 1.4630, -0.3554 * t + 0.4275
    c, d, e = -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703

    def perez(zen: np.ndarray, gamma: np.ndarray) -> np.ndarray:
        cz = np.cos(zen)
        grad = np.where(cz > 0.0, 1.0 + a * np.exp(b / np.where(cz > 0, cz, 1.0)), 1.0)
        return np.asarray(grad * (1.0 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2))

    gamma = _angle_to_sun(view_zenith_deg, view_azimuth_deg, sun_zenith_deg)
    z = np.radians(np.asarray(view_zenith_deg, dtype=float))
    zs = np.radians(sun_zenith_deg)
    return perez(z, gamma) / perez(np.asarray(0.0), np.asarray(zs))


def horizon_to_zenith_table(
    *,
    sun_elevations_deg: Sequence[float] = (20.0, 40.0, 60.0),
    view_azimuths_deg: Sequence[float] = (90.0, 180.0),
) -> str:
    """Luminance 5 deg above the horizon over the zenith's: the default Earth and the models.

    dustoptics' default Earth (:func:`~dustoptics.atmosphere.sets.earth_atmosphere`:
    OPAC's continental average at optical depth 0.1 at 550 nm, albedo 0.2),
    the CIE clear skies 11-13 and Preetham's sky at the turbidity of the same
    optical depth (:func:`preetham_turbidity`), at each Sun elevation and
    viewing azimuth from the Sun.

    Returns
    -------
    str
        A text table, one row per Sun elevation and azimuth.
    """
    medium = Medium.from_atmosphere(earth_atmosphere())
    turbidity = preetham_turbidity(DEFAULT_EARTH_AEROSOL_OPTICAL_DEPTH)
    zen = 90.0 - HORIZON_VIEW_ELEVATION_DEG
    lines = [
        f"sun_elev  azimuth  dustoptics  CIE11  CIE12  CIE13  Preetham(T={turbidity:.2f})",
    ]
    for elev in sun_elevations_deg:
        sky = sky_radiance(medium, sun_elevation_deg=elev)
        y = sky.xyz()[..., 1]
        y_zenith = float(np.mean(y[0]))
        for az in view_azimuths_deg:
            ours = float(sky._interpolate(y[..., None], zen, az)[0]) / y_zenith
            cie = [
                float(
                    cie_relative_luminance(
                        t, view_zenith_deg=zen, view_azimuth_deg=az, sun_zenith_deg=90.0 - elev
                    )
                )
                for t in (11, 12, 13)
            ]
            pre = float(
                preetham_relative_luminance(
                    turbidity, view_zenith_deg=zen, view_azimuth_deg=az, sun_zenith_deg=90.0 - elev
                )
            )
            lines.append(
                f"{elev:8.0f}  {az:7.0f}  {ours:10.2f}  {cie[0]:5.2f}  {cie[1]:5.2f}  "
                f"{cie[2]:5.2f}  {pre:5.2f}"
            )
    return "\n".join(lines)
