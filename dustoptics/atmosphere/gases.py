"""Molecular (Rayleigh) scattering and absorbing gases.

Rayleigh scattering
-------------------
The volume scattering coefficient of a gas of number density ``N`` with
refractive index ``n`` (Costa et al. 2021, eq. 11)::

    beta(lambda) = 8 pi^3 (n^2 - 1)^2 / (3 N lambda^4) * F(delta),
    F(delta) = (6 + 3 delta) / (6 - 7 delta)                 (King factor)

and the cross-section per molecule ``sigma = beta / N``.  ``delta`` is the
depolarization factor of the gas (0.0279 for air after Costa et al., 0.035 in
Penndorf 1957, 0.09 for CO2).  Cross-sections here are per molecule, in
[m^2] (``_m2``) or, in a :class:`~dustoptics.table.Table`, in [um^2].

The refractive index is measured at a reference number density ``N_ref``;
the refractivity scales with number density (Lorentz-Lorenz in the dilute
limit)::

    n(N) - 1 = (n_ref - 1) N / N_ref

so that ``sigma`` is (to first order in ``n - 1``) independent of ``N`` and
``beta`` proportional to it.  Every model here applies that scaling: asking
for Mars's surface density with the laboratory CO2 index gives the Martian
refractivity, not the laboratory one.  Number densities come from pressure
and temperature by the ideal-gas law, ``N = p / (k_B T)``
(:func:`ideal_gas_number_density_per_m3`, ``k_B`` from ``scipy.constants``).

Models (:data:`RAYLEIGH_MODELS`, :func:`get_rayleigh_model`)
-------------------------------------------------------------
``"bodhaine1999"`` (the Earth default)
    Bodhaine et al. 1999: Peck & Reeder's 1972 index of standard air
    (:data:`AIR_PECKREEDER1972`) scaled to the CO2 content, the King factor of
    the N2, O2, Ar and CO2 mixture (wavelength dependent, their eqs. 5, 6 and
    23), ``sigma = 24 pi^3 (n_s^2 - 1)^2 F / (lambda^4 N_s^2 (n_s^2 + 2)^2)``
    (:func:`bodhaine1999_cross_section_m2`), at 360 ppm CO2 (their eq. 30's); the
    number density is their sea-level column at 45 deg N over the 8 km scale
    height, so that the vertical optical depth is their eq. 30 to 1e-4
    (``tests/atmosphere/test_gases.py``).  The formula libRadtran and most RT
    codes use.  It is 0.7-1.2 % below ``"penndorf1957"`` at 360-830 nm
    (the table in ``docs/concepts/earth_sky.rst``, from
    :func:`rayleigh_optical_depth_difference`).
``"penndorf1957"``
    Standard air as Penndorf tabulated it: Edlén's 1953 dispersion formula
    (:data:`AIR_EDLEN1953`), King factor with ``delta = 0.035``, at 0 degC and
    101325 Pa; reproduces Penndorf's Table III to 3e-4 at 360-800 nm.
``"costa2021"``
    Costa et al.'s Earth: standard air (Edlén 1953, whose values are the
    ``m(lambda)`` of their Table 1), King factor with ``delta = 0.0279``,
    Penndorf's phase function, ``N = 2.68731e25 m^-3``.
``"kobe2026"``
    Kobe's simplified Earth: constant ``n = 1.0003`` at
    ``N_s = 2.545e25 m^-3``, no King factor, plain Rayleigh phase function.
``"costa2021-mars"``
    Costa et al.'s Mars CO2 (Bideau-Mehu 1973 index, ``delta = 0.09``,
    Penndorf's phase function) at the Martian surface, 610 Pa and 215 K, with
    the refractivity scaled to that density (see the model's notes).
``"collienne2013"``
    Collienne et al.'s Mars "molecules": three published coefficients, not a
    refractive index (:func:`collienne2013_beta_per_m`).

Absorbing gases
---------------
Ozone absorbs without scattering, ``beta_abs = sigma(lambda) N_O3``
(:func:`ozone_beta_abs_per_m`).  Cross-sections come from the shipped
spectrum of Serdyuchenko et al. 2014 at 233 K in 10 nm bins
(:func:`ozone_serdyuchenko2014`), a user CSV file
(:func:`read_ozone_csv`, format below) or Kobe's three published values
(:data:`KOBE2026_OZONE`), which are usable only at their own wavelengths.

Ozone CSV format::

    # Ozone absorption cross-section, Serdyuchenko et al. 2014, 293 K, ...
    # (one or more comment lines: the citation, kept with the data)
    wavelength_nm,sigma_m2
    360,1.18e-27
    ...

The column header must be ``wavelength_nm`` followed by ``sigma_m2`` [m^2 per
molecule] or ``sigma_cm2`` [cm^2 per molecule] (``sigma_O3_m2`` and
``sigma_O3_cm2`` are accepted too); wavelengths strictly increasing [nm],
cross-sections nonnegative.  Between rows the cross-section is interpolated
linearly; outside the rows it is an error.

References
----------
.. [1] J. Costa, A. Bock, C. Emmart, C. Hansen, A. Ynnerman and C. Silva,
   "Interactive visualization of atmospheric effects for celestial bodies,"
   IEEE Trans. Vis. Comput. Graph. 27(2), 785-795 (2021),
   doi:10.1109/TVCG.2020.3030333, eq. (10), (11), Table 1.
.. [2] R. Penndorf, "Tables of the refractive index for standard air and the
   Rayleigh scattering coefficient for the spectral region between 0.2 and
   20.0 um and their application to atmospheric optics," J. Opt. Soc. Am. 47,
   176-182 (1957), doi:10.1364/JOSA.47.000176.
.. [3] B. Edlén, "The dispersion of standard air," J. Opt. Soc. Am. 43,
   339-344 (1953), doi:10.1364/JOSA.43.000339.
.. [4] L. V. King, "On the complex anisotropic molecule in relation to the
   dispersion and scattering of light," Proc. R. Soc. Lond. A 104, 333-357
   (1923), doi:10.1098/rspa.1923.0113.
.. [6] B. A. Bodhaine, N. B. Wood, E. G. Dutton and J. R. Slusser, "On
   Rayleigh optical depth calculations," J. Atmos. Oceanic Technol. 16,
   1854-1861 (1999), doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
.. [7] E. R. Peck and K. Reeder, "Dispersion of air," J. Opt. Soc. Am. 62,
   958-962 (1972), doi:10.1364/JOSA.62.000958.
.. [5] D. Kobe, "Ozone absorption in single atmospheric scattering,"
   graduation work, Howest DAE, 2025-2026, eq. (8), section 11.5.1.
"""

from __future__ import annotations

import functools
import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import constants

from dustoptics._files import FormatError, read_checked
from dustoptics._validation import (
    _show,
    as_float_array,
    as_increasing_grid,
    check_choice,
    check_positive,
)
from dustoptics.atmosphere.bodhaine1999 import (
    _BODHAINE_CO2_PPM,
    AIR_PECKREEDER1972,
    BODHAINE_1999,
    _bodhaine_co2,
    bodhaine1999_column_per_m2,
    bodhaine1999_cross_section_m2,
    bodhaine1999_king_factor,
)
from dustoptics.particles.catalogue import get_material
from dustoptics.particles.materials import GasFormulaIndex
from dustoptics.scattering import phase as _phase
from dustoptics.scattering import tabulated_phase as _tabulated
from dustoptics.table import CrossSections, Provenance, Source, Table

__all__ = [
    "AIR_EDLEN1953",
    "AIR_PECKREEDER1972",
    "BODHAINE_1999",
    "BOLTZMANN_J_PER_K",
    "COLLIENNE2013_WAVELENGTH_NM",
    "KOBE2026_OZONE",
    "KOBE2026_OZONE_FRACTION",
    "MARS_SURFACE_PRESSURE_PA",
    "MARS_SURFACE_TEMPERATURE_K",
    "RAYLEIGH_FORMULAS",
    "RAYLEIGH_MODELS",
    "RAYLEIGH_PHASE_MODELS",
    "SERDYUCHENKO_2014",
    "ConstantRefractivity",
    "OzoneCrossSection",
    "RayleighModel",
    "bodhaine1999_column_per_m2",
    "bodhaine1999_cross_section_m2",
    "bodhaine1999_king_factor",
    "collienne2013_beta_per_m",
    "collienne2013_table",
    "get_rayleigh_model",
    "ideal_gas_number_density_per_m3",
    "king_factor",
    "ozone_beta_abs_per_m",
    "ozone_serdyuchenko2014",
    "ozone_table",
    "rayleigh_beta_per_m",
    "rayleigh_cross_section_m2",
    "rayleigh_optical_depth_difference",
    "read_ozone_csv",
    "scaled_refractivity",
]

FloatArray = NDArray[np.float64]

#: Boltzmann constant (exact in the 2019 SI), from ``scipy.constants``. [J K^-1]
BOLTZMANN_J_PER_K: Final = constants.k

_M2_TO_UM2: Final = 1e12
_CM2_TO_M2: Final = 1e-4

#: Mars surface pressure used for the corrected Costa CO2 model: 610 Pa, the
#: value CosmoScout VR uses for Mars's refractive index (``ior`` mode). [Pa]
MARS_SURFACE_PRESSURE_PA: Final = 610.0
#: Mars surface temperature used with :data:`MARS_SURFACE_PRESSURE_PA`. [K]
MARS_SURFACE_TEMPERATURE_K: Final = 215.0

EDLEN_1953: Final = (
    'B. Edlén, "The dispersion of standard air," J. Opt. Soc. Am. 43, 339-344 (1953), '
    "doi:10.1364/JOSA.43.000339 (the formula Penndorf 1957 tabulates)"
)
KING_1923: Final = (
    'L. V. King, "On the complex anisotropic molecule in relation to the dispersion and '
    'scattering of light," Proc. R. Soc. Lond. A 104, 333-357 (1923), doi:10.1098/rspa.1923.0113'
)

#: Standard air (15 degC, 101325 Pa, 300 ppm CO2) after Edlén 1953:
#: ``(n - 1) 1e8 = 6432.8 + 2949810 / (146 - s^2) + 25540 / (41 - s^2)``,
#: ``s`` the vacuum wavenumber in um^-1.  Penndorf 1957 used it over 0.2-20 um;
#: that is its range here.
AIR_EDLEN1953: Final = GasFormulaIndex(
    name="air-edlen1953",
    citation=EDLEN_1953,
    c1=6432.8e-8,
    terms=((2949810e-8, 146.0), (25540e-8, 41.0)),
    wavelength_range_nm=(200.0, 20000.0),
    reference_temperature_k=288.15,
    reference_pressure_pa=101325.0,
    reference_co2_ppm=300.0,
    source="Edlén 1953, eq. (1), as used by Penndorf 1957",
)


# ------------------------------------------------------------------ basic laws


def _positive_array(name: str, value: Any, unit: str) -> FloatArray:
    arr = as_float_array(name, value)
    if np.any(arr <= 0.0):
        raise ValueError(f"{name} must be > 0 {unit}; got {_show(value)}")
    return arr


def _out(arr: FloatArray) -> float | FloatArray:
    return float(arr) if arr.ndim == 0 else arr


def ideal_gas_number_density_per_m3(
    *, pressure_pa: ArrayLike, temperature_k: ArrayLike
) -> float | FloatArray:
    """Number density of an ideal gas, ``N = p / (k_B T)``.

    Parameters
    ----------
    pressure_pa : array_like
        Pressure, > 0. [Pa]
    temperature_k : array_like
        Temperature, > 0. [K]

    Returns
    -------
    float or numpy.ndarray
        Number density. [m^-3]

    Examples
    --------
    >>> round(ideal_gas_number_density_per_m3(pressure_pa=101325.0, temperature_k=273.15) / 1e25, 5)
    2.68678
    """
    p = _positive_array("pressure_pa", pressure_pa, "Pa")
    t = _positive_array("temperature_k", temperature_k, "K")
    return _out(p / (BOLTZMANN_J_PER_K * t))


def king_factor(*, depolarization: ArrayLike) -> float | FloatArray:
    """King correction factor ``F = (6 + 3 delta) / (6 - 7 delta)``.

    Parameters
    ----------
    depolarization : array_like
        Depolarization factor ``delta`` in [0, 6/7) (``F`` diverges at 6/7). [-]

    Returns
    -------
    float or numpy.ndarray
        ``F >= 1``; ``F = 1`` for ``delta = 0`` (isotropic molecules). [-]

    References
    ----------
    .. [1] L. V. King, Proc. R. Soc. Lond. A 104, 333-357 (1923),
       doi:10.1098/rspa.1923.0113.
    .. [2] J. Costa et al., IEEE TVCG 27(2), 785-795 (2021),
       doi:10.1109/TVCG.2020.3030333, eq. (11).
    """
    d = as_float_array("depolarization", depolarization)
    if np.any((d < 0.0) | (d >= 6.0 / 7.0)):
        raise ValueError(f"depolarization must be in [0, 6/7); got {_show(depolarization)}")
    return _out((6.0 + 3.0 * d) / (6.0 - 7.0 * d))


def scaled_refractivity(
    *,
    refractivity: ArrayLike,
    number_density_per_m3: ArrayLike,
    reference_number_density_per_m3: float,
) -> float | FloatArray:
    """Refractivity at another number density, ``(n - 1) N / N_ref``.

    Parameters
    ----------
    refractivity : array_like
        ``n - 1`` at the reference density, >= 0. [-]
    number_density_per_m3 : array_like
        Number density wanted, > 0. [m^-3]
    reference_number_density_per_m3 : float
        Number density at which ``refractivity`` holds, > 0. [m^-3]

    Returns
    -------
    float or numpy.ndarray
        ``n - 1`` at ``number_density_per_m3``. [-]

    Notes
    -----
    Exact for the Lorentz-Lorenz function ``(n^2 - 1)/(n^2 + 2)``, which is
    proportional to density, up to terms of order ``(n - 1)^2`` (3e-4 relative
    for air at sea level).
    """
    r = as_float_array("refractivity", refractivity)
    if np.any(r < 0.0):
        raise ValueError(f"refractivity (n - 1) must be >= 0; got {_show(refractivity)}")
    n = _positive_array("number_density_per_m3", number_density_per_m3, "m^-3")
    n_ref = check_positive(
        "reference_number_density_per_m3", reference_number_density_per_m3, unit="m^-3"
    )
    return _out(r * (n / n_ref))


def rayleigh_cross_section_m2(
    *,
    wavelength_nm: ArrayLike,
    refractivity: ArrayLike,
    number_density_per_m3: ArrayLike,
    depolarization: ArrayLike = 0.0,
) -> float | FloatArray:
    """Rayleigh scattering cross-section per molecule (Costa et al. 2021, eq. 11).

    .. math::

        \\sigma = \\frac{8 \\pi^3 (n^2 - 1)^2}{3 N^2 \\lambda^4}
                  \\frac{6 + 3 \\delta}{6 - 7 \\delta}

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelength, > 0. [nm]
    refractivity : array_like
        ``n - 1`` of the gas *at* ``number_density_per_m3`` (see
        :func:`scaled_refractivity`), >= 0. [-]
    number_density_per_m3 : array_like
        Number density the refractivity belongs to, > 0. [m^-3]
    depolarization : array_like, default 0
        Depolarization factor ``delta`` for the King factor; 0 gives none. [-]

    Returns
    -------
    float or numpy.ndarray
        Cross-section per molecule. [m^2]

    Examples
    --------
    Costa et al.'s Table 1 Mars value at 550 nm: ``n = 1.00045019``,
    ``N = 2.8e23 m^-3``, ``delta = 0.09`` give ``beta = N sigma = 3.0560e-3 m^-1``.

    >>> s = rayleigh_cross_section_m2(wavelength_nm=550.0, refractivity=0.00045019,
    ...                               number_density_per_m3=2.8e23, depolarization=0.09)
    >>> round(s * 2.8e23 * 1e3, 4)
    3.056
    """
    lam_m = _positive_array("wavelength_nm", wavelength_nm, "nm") * 1e-9
    r = as_float_array("refractivity", refractivity)
    if np.any(r < 0.0):
        raise ValueError(f"refractivity (n - 1) must be >= 0; got {_show(refractivity)}")
    n = _positive_array("number_density_per_m3", number_density_per_m3, "m^-3")
    f = np.asarray(king_factor(depolarization=depolarization))
    n2m1 = r * (2.0 + r)  # n^2 - 1 without cancellation
    return _out(8.0 * math.pi**3 * n2m1**2 / (3.0 * n**2 * lam_m**4) * f)


# ------------------------------------------------------------------- models


@dataclass(frozen=True, kw_only=True)
class ConstantRefractivity:
    """A wavelength-independent refractivity ``n - 1`` at a stated number density.

    Parameters
    ----------
    name : str
        Name of the value.
    refractivity : float
        ``n - 1`` at ``reference_number_density_per_m3``, > 0. [-]
    reference_number_density_per_m3 : float
        Number density at which it holds, > 0. [m^-3]
    citation : str
        Where the value comes from.
    """

    name: str
    refractivity: float
    reference_number_density_per_m3: float
    citation: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "refractivity", check_positive("refractivity", self.refractivity))
        object.__setattr__(
            self,
            "reference_number_density_per_m3",
            check_positive(
                "reference_number_density_per_m3", self.reference_number_density_per_m3, unit="m^-3"
            ),
        )

    def refractivity_at(self, wavelength_nm: ArrayLike) -> FloatArray:
        """``n - 1`` at the reference density, the same at every wavelength. [-]"""
        wl = _positive_array("wavelength_nm", wavelength_nm, "nm")
        return np.full(wl.shape, self.refractivity)


def _reference(index: GasFormulaIndex | ConstantRefractivity) -> float:
    if isinstance(index, GasFormulaIndex):
        return index.reference_number_density_m3
    return index.reference_number_density_per_m3


#: Phase-function choices of a :class:`RayleighModel`.
RAYLEIGH_PHASE_MODELS: Final = ("rayleigh", "rayleigh_depolarized", "penndorf1957")
#: Cross-section formulas of a :class:`RayleighModel`: ``"king1923"`` (one
#: depolarization, :func:`rayleigh_cross_section_m2`) or ``"bodhaine1999"``
#: (:func:`bodhaine1999_cross_section_m2`, wavelength-dependent King factor and CO2).
RAYLEIGH_FORMULAS: Final = ("king1923", "bodhaine1999")


@dataclass(frozen=True, kw_only=True)
class RayleighModel:
    """A gas for Rayleigh scattering: refractive index, King factor, phase function.

    Attributes
    ----------
    name : str
        Model name (a key of :data:`RAYLEIGH_MODELS` for the presets).
    index : GasFormulaIndex or ConstantRefractivity
        Refractive index and the number density at which it holds.
    depolarization : float
        ``delta`` for the King factor and, with ``"rayleigh_depolarized"``,
        the phase function. [-]
    king_correction : bool
        Whether ``beta`` includes the King factor (Costa) or not (Kobe).
    phase_model : str
        ``"rayleigh"`` (``3/(16 pi)(1 + mu^2)``), ``"rayleigh_depolarized"``
        (Chandrasekhar's, with ``depolarization``) or ``"penndorf1957"``
        (``0.7629 (1 + 0.932 mu^2)/(4 pi)`` as Costa et al. print it).
    number_density_per_m3 : float
        The model's number density (e.g. at the surface), used when none is
        given. [m^-3]
    citation : str
        Sources of the model.
    notes : tuple of str
        Choices made, recorded in table provenance.
    formula : str
        Cross-section formula, one of :data:`RAYLEIGH_FORMULAS` (default
        ``"king1923"``).  With ``"bodhaine1999"`` the cross-section is
        :func:`bodhaine1999_cross_section_m2` at ``co2_ppm`` (independent of the
        number density), the refractivity is scaled to ``co2_ppm`` and the
        depolarized phase function takes each wavelength's depolarization
        ``6 (F - 1) / (3 + 7 F)`` (``depolarization`` is then its value at 550 nm).
    co2_ppm : float
        CO2 content for ``"bodhaine1999"``. [ppm by volume]
    """

    name: str
    index: GasFormulaIndex | ConstantRefractivity
    depolarization: float
    king_correction: bool
    phase_model: str
    number_density_per_m3: float
    citation: str
    notes: tuple[str, ...] = ()
    formula: str = "king1923"
    co2_ppm: float = _BODHAINE_CO2_PPM

    def __post_init__(self) -> None:
        if not isinstance(self.index, (GasFormulaIndex, ConstantRefractivity)):
            raise TypeError(
                f"index must be a GasFormulaIndex or ConstantRefractivity; got {type(self.index).__name__}"
            )
        king_factor(depolarization=self.depolarization)  # validates 0 <= delta < 6/7
        object.__setattr__(self, "depolarization", float(self.depolarization))
        check_choice("phase_model", self.phase_model, RAYLEIGH_PHASE_MODELS)
        check_choice("formula", self.formula, RAYLEIGH_FORMULAS)
        object.__setattr__(self, "co2_ppm", _bodhaine_co2(self.co2_ppm))
        object.__setattr__(
            self,
            "number_density_per_m3",
            check_positive("number_density_per_m3", self.number_density_per_m3, unit="m^-3"),
        )

    # -------------------------------------------------------------- physics

    def _density(self, number_density_per_m3: float | None) -> float:
        if number_density_per_m3 is None:
            return self.number_density_per_m3
        return check_positive("number_density_per_m3", number_density_per_m3, unit="m^-3")

    def refractivity(
        self, wavelength_nm: ArrayLike, *, number_density_per_m3: float | None = None
    ) -> FloatArray:
        """``n - 1`` scaled to the number density (default: the model's). [-]

        Raises
        ------
        ValueError
            A wavelength outside the refractive-index formula's range.
        """
        n = self._density(number_density_per_m3)
        if isinstance(self.index, GasFormulaIndex):
            r_ref = self.index.refractivity(wavelength_nm)
        else:
            r_ref = self.index.refractivity_at(wavelength_nm)
        if self.formula == "bodhaine1999":  # Bodhaine et al. eq. (19)
            ref_co2 = getattr(self.index, "reference_co2_ppm", None) or 300.0
            r_ref = r_ref * (1.0 + 0.54e-6 * (self.co2_ppm - ref_co2))
        return np.asarray(
            scaled_refractivity(
                refractivity=r_ref,
                number_density_per_m3=n,
                reference_number_density_per_m3=_reference(self.index),
            ),
            dtype=np.float64,
        )

    def cross_section_m2(
        self, wavelength_nm: ArrayLike, *, number_density_per_m3: float | None = None
    ) -> FloatArray:
        """Scattering cross-section per molecule at the number density. [m^2]"""
        n = self._density(number_density_per_m3)
        if self.formula == "bodhaine1999":
            return bodhaine1999_cross_section_m2(wavelength_nm, co2_ppm=self.co2_ppm)
        return np.asarray(
            rayleigh_cross_section_m2(
                wavelength_nm=wavelength_nm,
                refractivity=self.refractivity(wavelength_nm, number_density_per_m3=n),
                number_density_per_m3=n,
                depolarization=self.depolarization if self.king_correction else 0.0,
            ),
            dtype=np.float64,
        )

    def beta_sca_per_m(
        self, wavelength_nm: ArrayLike, *, number_density_per_m3: float | None = None
    ) -> FloatArray:
        """Volume scattering coefficient ``N sigma``. [m^-1]"""
        n = self._density(number_density_per_m3)
        return n * self.cross_section_m2(wavelength_nm, number_density_per_m3=n)

    def phase_function(self, mu: ArrayLike) -> float | FloatArray:
        """The model's phase function at ``mu = cos(theta)``. [sr^-1]"""
        if self.phase_model == "rayleigh":
            return _phase.rayleigh(mu)
        if self.phase_model == "rayleigh_depolarized":
            return _phase.rayleigh_depolarized(mu, depolarization=self.depolarization)
        return _phase.rayleigh_penndorf1957(mu)

    def with_number_density(self, number_density_per_m3: float) -> RayleighModel:
        """The same gas at another number density. [m^-3]"""
        return _replace(self, number_density_per_m3=number_density_per_m3)

    def at_conditions(self, *, pressure_pa: float, temperature_k: float) -> RayleighModel:
        """The same gas at the ideal-gas number density of ``pressure_pa`` [Pa], ``temperature_k`` [K]."""
        n = ideal_gas_number_density_per_m3(pressure_pa=pressure_pa, temperature_k=temperature_k)
        return self.with_number_density(float(n))

    def table(
        self,
        wavelength_nm: ArrayLike,
        *,
        theta_deg: ArrayLike | None = None,
        name: str | None = None,
        number_density_per_m3: float | None = None,
    ) -> Table:
        """The gas as a :class:`~dustoptics.table.Table` at the number density.

        Parameters
        ----------
        wavelength_nm : array_like
            Strictly increasing wavelengths. [nm]
        theta_deg : array_like, optional
            Angles from 0 to 180; default 0, 0.1, ..., 180 (1,801). [deg]
        name : str, optional
            Table name; default the model name.
        number_density_per_m3 : float, optional
            Number density; default the model's. [m^-3]

        Returns
        -------
        Table
            ``cext_um2 = csca_um2 = sigma`` per molecule [um^2], ``g = 0``,
            the phase function sampled and renormalized to 1 under linear
            interpolation in angle (the printed Penndorf constants integrate
            to 0.99991; the renormalization removes that 9.2e-5).
        """
        wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
        theta = _theta_grid(theta_deg)
        n = self._density(number_density_per_m3)
        sigma_um2 = self.cross_section_m2(wl, number_density_per_m3=n) * _M2_TO_UM2
        if self.formula == "bodhaine1999" and self.phase_model == "rayleigh_depolarized":
            f = bodhaine1999_king_factor(wl, co2_ppm=self.co2_ppm)
            rho = 6.0 * (f - 1.0) / (3.0 + 7.0 * f)
            mu = np.cos(np.deg2rad(theta))
            p = np.asarray(_phase.rayleigh_depolarized(mu[None, :], depolarization=rho[:, None]))
        else:
            p = np.broadcast_to(
                _tabulated.tabulate(self.phase_function, theta_deg=theta), (wl.size, theta.size)
            )
        p = _tabulated.renormalize(p, theta_deg=theta)
        inputs = {
            "kind": "rayleigh-gas",
            "model": self.name,
            "index": self.index.name,
            "depolarization": self.depolarization,
            "king_correction": self.king_correction,
            "phase_model": self.phase_model,
            **(
                {"formula": self.formula, "co2_ppm": self.co2_ppm}
                if self.formula != "king1923"
                else {}
            ),
            "number_density_per_m3": n,
            "wavelength_nm": wl,
            "theta_deg": theta,
        }
        sources = (
            Source(name=self.name, role="gas model", citation=self.citation),
            Source(name=self.index.name, role="refractive index", citation=self.index.citation),
        )
        return Table(
            name=name or self.name,
            wavelength_nm=wl,
            theta_deg=theta,
            phase=p,
            g=np.zeros(wl.size),
            cross_sections=CrossSections(
                cext_um2=sigma_um2, csca_um2=sigma_um2, number_density_per_m3=n
            ),
            provenance=Provenance(inputs=inputs, sources=sources, notes=self.notes),
        )


def _replace(model: RayleighModel, **changes: Any) -> RayleighModel:
    return replace(model, **changes)


def _theta_grid(theta_deg: ArrayLike | None) -> FloatArray:
    if theta_deg is None:
        return np.linspace(0.0, 180.0, 1801)
    theta = as_increasing_grid("theta_deg", theta_deg, low=0.0, high=180.0, unit="deg")
    if theta.size < 2 or theta[0] != 0.0 or theta[-1] != 180.0:
        raise ValueError(
            f"theta_deg must run from exactly 0 to exactly 180 deg; got {_show(theta)}"
        )
    return theta


def _penndorf1957() -> RayleighModel:
    return RayleighModel(
        name="penndorf1957",
        index=AIR_EDLEN1953,
        depolarization=0.035,
        king_correction=True,
        phase_model="rayleigh_depolarized",
        number_density_per_m3=float(
            ideal_gas_number_density_per_m3(pressure_pa=101325.0, temperature_k=273.15)
        ),
        citation=f"{_phase.PENNDORF_1957}; index {EDLEN_1953}; King factor {KING_1923}",
        notes=(
            (
                "Standard air at 0 degC and 101325 Pa (Penndorf's Table III conditions), "
                "Edlén 1953 index scaled from 15 degC by number density, delta = 0.035 (Penndorf)."
            ),
            (
                "Phase function: Chandrasekhar's depolarized Rayleigh at delta = 0.035, of which "
                "Penndorf's 0.7629 (1 + 0.932 mu^2)/(4 pi) is the rounded form."
            ),
        ),
    )


def _bodhaine1999() -> RayleighModel:
    f550 = float(bodhaine1999_king_factor(550.0))
    return RayleighModel(
        name="bodhaine1999",
        index=AIR_PECKREEDER1972,
        depolarization=6.0 * (f550 - 1.0) / (3.0 + 7.0 * f550),
        king_correction=True,
        phase_model="rayleigh_depolarized",
        number_density_per_m3=bodhaine1999_column_per_m2() / 8000.0,
        citation=f"{BODHAINE_1999}; index {AIR_PECKREEDER1972.citation}",
        formula="bodhaine1999",
        notes=(
            (
                "Bodhaine et al. 1999 eq. (2): Peck & Reeder 1972 index at 360 ppm CO2 (eq. 19), "
                "King factor of N2, O2, Ar, CO2 (eqs. 5, 6, 23), N_s = 2.546899e19 cm^-3."
            ),
            (
                "Number density: their sea-level column at 45 deg N (eq. 30's 0.0021520 over "
                "1e-28 cm^2, 2.152e29 m^-2) over the 8 km scale height, so that the vertical "
                "optical depth is their eq. 30."
            ),
            (
                "Phase function: Chandrasekhar's depolarized Rayleigh with each wavelength's "
                "depolarization 6 (F - 1) / (3 + 7 F)."
            ),
        ),
    )


def rayleigh_optical_depth_difference(
    wavelength_nm: ArrayLike, *, model: str = "penndorf1957", reference: str = "bodhaine1999"
) -> FloatArray:
    """Relative difference of two models' vertical optical depths in Earth's default column.

    ``tau_model / tau_reference - 1`` with each model's number density over the
    same 8 km scale height (:func:`~dustoptics.atmosphere.sets.earth_atmosphere`'s
    column), i.e. ``N sigma`` of the two models.

    Examples
    --------
    Penndorf's standard air against Bodhaine et al. (the default since issue 40):

    >>> d = rayleigh_optical_depth_difference([360.0, 440.0, 550.0, 680.0, 830.0])
    >>> print(" ".join(f"{100 * x:+.2f}%" for x in d))
    +0.69% +0.92% +1.06% +1.13% +1.17%
    """
    wl = _positive_array("wavelength_nm", wavelength_nm, "nm")
    a = get_rayleigh_model(model)
    b = get_rayleigh_model(reference)
    return np.asarray(
        a.beta_sca_per_m(wl) / b.beta_sca_per_m(wl) - 1.0,
        dtype=np.float64,
    )


def _costa2021() -> RayleighModel:
    return RayleighModel(
        name="costa2021",
        index=AIR_EDLEN1953,
        depolarization=0.0279,
        king_correction=True,
        phase_model="penndorf1957",
        number_density_per_m3=2.68731e25,
        citation=f"{_phase.COSTA_2021}, eq. (10), (11), Table 1; index {EDLEN_1953}",
        notes=(
            (
                "Costa et al. Table 1 (Earth): N = 2.68731e19 cm^-3 (0 degC), delta = 0.0279, "
                "Penndorf phase function; m(lambda) = 1.00027598, 1.00027783, 1.00028276 at "
                "680, 550, 440 nm are Edlén's standard air at 15 degC."
            ),
            (
                "Here n - 1 is scaled to N (0 degC): the table uses one consistent state. Costa's "
                "printed beta values are Penndorf's (delta = 0.035); with delta = 0.0279 this model "
                "is 1.2 % lower."
            ),
        ),
    )


def _kobe2026() -> RayleighModel:
    n_s = 2.545e25
    return RayleighModel(
        name="kobe2026",
        index=ConstantRefractivity(
            name="air-kobe2026-constant",
            refractivity=3.0e-4,
            reference_number_density_per_m3=n_s,
            citation=f"{_phase.KOBE_2026}, eq. (8): n = 1.0003 at N_s = 2.545e25 m^-3",
        ),
        depolarization=0.0,
        king_correction=False,
        phase_model="rayleigh",
        number_density_per_m3=n_s,
        citation=f"{_phase.KOBE_2026}, eq. (8)",
        notes=("Kobe's simplified Rayleigh: n = 1.0003, N_s = 2.545e25 m^-3, no King factor.",),
    )


def _costa2021_mars() -> RayleighModel:
    co2 = get_material("co2-bideaumehu1973")
    if not isinstance(co2, GasFormulaIndex):  # pragma: no cover - catalogue invariant
        raise TypeError("co2-bideaumehu1973 must be a gas formula")
    n_mars = float(
        ideal_gas_number_density_per_m3(
            pressure_pa=MARS_SURFACE_PRESSURE_PA, temperature_k=MARS_SURFACE_TEMPERATURE_K
        )
    )
    return RayleighModel(
        name="costa2021-mars",
        index=co2,
        depolarization=0.09,
        king_correction=True,
        phase_model="penndorf1957",
        number_density_per_m3=n_mars,
        citation=f"{_phase.COSTA_2021}, eq. (10), (11), Table 1 (Mars); index {co2.citation}",
        notes=(
            (
                "Costa et al.'s Table 1 Mars values use the laboratory CO2 index (0 degC, 1 atm) with "
                "N = 2.8e23 m^-3 (printed as a mass density), giving beta = 3.056e-3 m^-1 at 550 nm, "
                "about 400x too large for Mars."
            ),
            (
                f"Corrected here as CosmoScout VR does: N from the ideal-gas law at "
                f"{MARS_SURFACE_PRESSURE_PA:g} Pa and {MARS_SURFACE_TEMPERATURE_K:g} K and n - 1 scaled "
                "to that N (3.4e-6 at 550 nm)."
            ),
        ),
    )


_RAYLEIGH_FACTORIES: Final[Mapping[str, Callable[[], RayleighModel]]] = MappingProxyType(
    {
        "bodhaine1999": _bodhaine1999,
        "penndorf1957": _penndorf1957,
        "costa2021": _costa2021,
        "kobe2026": _kobe2026,
        "costa2021-mars": _costa2021_mars,
    }
)

#: Names of the Rayleigh gas models (see the module docstring).
RAYLEIGH_MODELS: Final = tuple(_RAYLEIGH_FACTORIES)


def get_rayleigh_model(name: str) -> RayleighModel:
    """A Rayleigh gas model by name (one of :data:`RAYLEIGH_MODELS`).

    Raises
    ------
    ValueError
        Unknown name (the message lists the valid ones).
    """
    check_choice("model", name, RAYLEIGH_MODELS)
    return _RAYLEIGH_FACTORIES[name]()


def rayleigh_beta_per_m(
    wavelength_nm: ArrayLike,
    *,
    model: str | RayleighModel = "costa2021",
    number_density_per_m3: float | None = None,
    pressure_pa: float | None = None,
    temperature_k: float | None = None,
) -> FloatArray:
    """Rayleigh scattering coefficient of a gas model.

    Parameters
    ----------
    wavelength_nm : array_like
        Vacuum wavelengths inside the index formula's range. [nm]
    model : str or RayleighModel, default "costa2021"
        A name of :data:`RAYLEIGH_MODELS` or a model object.
    number_density_per_m3 : float, optional
        Number density; give it, or ``pressure_pa`` and ``temperature_k``, or
        neither (the model's own). [m^-3]
    pressure_pa, temperature_k : float, optional
        Ideal-gas state. [Pa], [K]

    Returns
    -------
    numpy.ndarray
        ``beta_sca``, same shape as ``wavelength_nm``. [m^-1]

    Examples
    --------
    Kobe's ``beta_R`` at 650 nm (printed as 6.56e-6 m^-1 in his section 11.3.2):

    >>> round(float(rayleigh_beta_per_m(650.0, model="kobe2026")) * 1e6, 3)
    6.554
    """
    gas = get_rayleigh_model(model) if isinstance(model, str) else model
    if not isinstance(gas, RayleighModel):
        raise TypeError(
            f"model must be a name in {RAYLEIGH_MODELS} or a RayleighModel; got {model!r}"
        )
    if number_density_per_m3 is not None and (pressure_pa is not None or temperature_k is not None):
        raise ValueError("give number_density_per_m3 or pressure_pa and temperature_k, not both")
    if (pressure_pa is None) != (temperature_k is None):
        raise ValueError(
            f"pressure_pa and temperature_k must be given together; got pressure_pa={pressure_pa!r}, "
            f"temperature_k={temperature_k!r}"
        )
    if pressure_pa is not None:
        gas = gas.at_conditions(pressure_pa=pressure_pa, temperature_k=temperature_k)  # type: ignore[arg-type]
    elif number_density_per_m3 is not None:
        gas = gas.with_number_density(number_density_per_m3)
    return gas.beta_sca_per_m(wavelength_nm)


# ------------------------------------------------------------ Collienne 2013

#: Wavelengths of Collienne et al.'s three coefficients. [nm]
COLLIENNE2013_WAVELENGTH_NM: Final = tuple(_phase.COLLIENNE2013_MARS.wavelength_nm)


def _at_points(
    name: str, wavelength_nm: ArrayLike, points: tuple[float, ...], values: tuple[float, ...]
) -> FloatArray:
    wl = as_float_array("wavelength_nm", wavelength_nm)
    lookup = dict(zip(points, values, strict=True))
    bad = [w for w in np.unique(wl).tolist() if w not in lookup]
    if bad:
        raise ValueError(
            f"{name} is published only at wavelength_nm in {list(points)}; got {bad} "
            "(no interpolation or extrapolation between published points)"
        )
    return np.vectorize(lookup.__getitem__, otypes=[np.float64])(wl) if wl.size else wl


def collienne2013_beta_per_m(wavelength_nm: ArrayLike) -> FloatArray:
    """Collienne et al.'s Mars "Rayleigh" coefficients, only at 440, 510 and 680 nm. [m^-1]

    Values from :data:`dustoptics.scattering.phase.COLLIENNE2013_MARS` (5.75e-6,
    13.57e-6, 19.918e-6 m^-1): chosen by eye, increasing with wavelength, not
    computed from a refractive index.

    Raises
    ------
    ValueError
        Any other wavelength.
    """
    c = _phase.COLLIENNE2013_MARS
    return _at_points(
        "collienne2013 beta",
        wavelength_nm,
        tuple(c.wavelength_nm),
        tuple(c.rayleigh_scattering_per_m),
    )


def collienne2013_table(
    wavelength_nm: ArrayLike = COLLIENNE2013_WAVELENGTH_NM,
    *,
    theta_deg: ArrayLike | None = None,
    name: str = "collienne2013-molecules",
) -> Table:
    """Collienne et al.'s Mars molecules as a Table (Rayleigh phase function).

    The coefficients are published without a number density.  The table
    carries them per unit number density: ``number_density_per_m3 = 1`` and
    ``csca_um2 = cext_um2 = beta * 1e12``, so ``beta_sca_per_m`` returns the
    published values (to rounding, 1e-16).  The phase function is
    :func:`dustoptics.scattering.phase.rayleigh` (Collienne's molecules are a Rayleigh
    layer with hand-chosen coefficients).
    """
    wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    beta = collienne2013_beta_per_m(wl)
    theta = _theta_grid(theta_deg)
    p = _tabulated.renormalize(
        np.broadcast_to(
            _tabulated.tabulate(_phase.rayleigh, theta_deg=theta), (wl.size, theta.size)
        ),
        theta_deg=theta,
    )
    c = _phase.COLLIENNE2013_MARS
    return Table(
        name=name,
        wavelength_nm=wl,
        theta_deg=theta,
        phase=p,
        g=np.zeros(wl.size),
        cross_sections=CrossSections(
            cext_um2=beta * _M2_TO_UM2, csca_um2=beta * _M2_TO_UM2, number_density_per_m3=1.0
        ),
        provenance=Provenance(
            inputs={"kind": "collienne2013-molecules", "wavelength_nm": wl, "theta_deg": theta},
            sources=(
                Source(name="collienne2013", role="scattering coefficients", citation=c.citation),
            ),
            notes=(
                (
                    "Coefficients published without a number density: carried per unit density "
                    "(number_density_per_m3 = 1, cross-section = beta)."
                ),
            ),
        ),
    )


# -------------------------------------------------------------------- ozone

_SIGMA_COLUMN = re.compile(r"^sigma(?:_o3)?_(m2|cm2)$", re.IGNORECASE)
_OZONE_INTERPOLATION: Final = ("linear", "points")


@dataclass(frozen=True, kw_only=True, eq=False)
class OzoneCrossSection:
    """An ozone absorption cross-section spectrum.

    Attributes
    ----------
    name : str
        Name of the spectrum.
    wavelength_nm : numpy.ndarray
        Strictly increasing wavelengths. [nm]
    sigma_m2 : numpy.ndarray
        Absorption cross-section per molecule, >= 0. [m^2]
    citation : str
        Source of the values.
    interpolation : {"linear", "points"}
        ``"linear"``: linear between rows, error outside.  ``"points"``: the
        values hold only at the listed wavelengths (a few values read off a
        figure); any other wavelength is an error.
    """

    name: str
    wavelength_nm: FloatArray
    sigma_m2: FloatArray
    citation: str
    interpolation: str = "linear"

    def __post_init__(self) -> None:
        wl = as_increasing_grid("wavelength_nm", self.wavelength_nm, unit="nm")
        if wl[0] <= 0.0:
            raise ValueError(f"wavelength_nm must be > 0 nm; got minimum {wl[0]!r}")
        sigma = as_float_array("sigma_m2", self.sigma_m2, ndim=1)
        if sigma.shape != wl.shape:
            raise ValueError(
                f"sigma_m2 must have one value per wavelength ({wl.size}); got {sigma.size}"
            )
        if np.any(sigma < 0.0):
            raise ValueError(f"sigma_m2 must be >= 0 m^2; got {_show(sigma)}")
        check_choice("interpolation", self.interpolation, _OZONE_INTERPOLATION)
        if not self.citation or not self.citation.strip():
            raise ValueError(
                "citation must name the source of the cross-sections; got an empty string"
            )
        if self.interpolation == "linear" and wl.size < 2:
            raise ValueError(
                "a 'linear' spectrum needs at least 2 wavelengths; use interpolation='points'"
            )
        for key, arr in (("wavelength_nm", wl), ("sigma_m2", sigma)):
            arr.setflags(write=False)
            object.__setattr__(self, key, arr)

    @property
    def wavelength_range_nm(self) -> tuple[float, float]:
        """First and last tabulated wavelength. [nm]"""
        return float(self.wavelength_nm[0]), float(self.wavelength_nm[-1])

    def __call__(self, wavelength_nm: ArrayLike) -> FloatArray:
        """Cross-section at the wavelengths. [m^2]

        Raises
        ------
        ValueError
            Outside the tabulated range, or (``"points"``) not a listed wavelength.
        """
        if self.interpolation == "points":
            return _at_points(
                f"ozone cross-section {self.name!r}",
                wavelength_nm,
                tuple(self.wavelength_nm.tolist()),
                tuple(self.sigma_m2.tolist()),
            )
        wl = as_float_array("wavelength_nm", wavelength_nm)
        low, high = self.wavelength_range_nm
        outside = (wl < low) | (wl > high)
        if np.any(outside):
            raise ValueError(
                f"wavelength_nm outside the ozone cross-section {self.name!r}: valid range "
                f"[{low:g}, {high:g}] nm; got {_show(np.unique(wl[outside]))} nm (no extrapolation)"
            )
        return np.interp(wl, self.wavelength_nm, self.sigma_m2)


#: Kobe's ozone cross-sections, read off a figure of P. Kutz's: 4.5e-22,
#: 1.9e-21, 3.1e-21 cm^2 at 475, 510, 650 nm (Kobe 2026, section 11.5.1).
#: Three values read from a plot: usable only at these wavelengths.
KOBE2026_OZONE: Final = OzoneCrossSection(
    name="ozone-kobe2026",
    wavelength_nm=np.array([475.0, 510.0, 650.0]),
    sigma_m2=np.array([4.5e-26, 1.9e-25, 3.1e-25]),
    citation=f"{_phase.KOBE_2026}, section 11.5.1 (values read from a figure by P. Kutz)",
    interpolation="points",
)

#: Kobe's ozone number density as a fraction of the air (Rayleigh) density:
#: 6e-7 ("0.00006 %"), Kobe 2026 section 11.5.1. [-]
KOBE2026_OZONE_FRACTION: Final = 6e-7


#: Citation of the shipped ozone spectrum (:func:`ozone_serdyuchenko2014`).
SERDYUCHENKO_2014: Final = (
    'A. Serdyuchenko, V. Gorshelev, M. Weber, W. Chehade and J. P. Burrows, "High spectral '
    'resolution ozone absorption cross-sections - Part 2: Temperature dependence," Atmos. Meas. '
    "Tech. 7, 625-636 (2014), doi:10.5194/amt-7-625-2014; 233 K, 10 nm bin means as in E. Bruneton, "
    "precomputed_atmospheric_scattering (2017, BSD-3-Clause), demo/demo.cc kOzoneCrossSection"
)


@functools.cache
def ozone_serdyuchenko2014() -> OzoneCrossSection:
    """The ozone absorption spectrum the package ships: Serdyuchenko et al. 2014 at 233 K.

    48 values, the means of the measured 233 K spectrum over 10 nm bins
    [L, L + 10) nm for L = 360, 370, ..., 830, as Bruneton's precomputed
    atmospheric scattering demo (BSD-3-Clause) lists them and uses them: each
    bin's mean at its start wavelength L, linear between them (so the range is
    360-830 nm).  The file, with its citation, licence and provenance, is
    ``dustoptics/refractive_indices/spectra/ozone_serdyuchenko2014_233K_10nm.csv``.

    Returns
    -------
    OzoneCrossSection
        ``sigma_m2`` per molecule. [m^2]

    Examples
    --------
    >>> o3 = ozone_serdyuchenko2014()
    >>> float(o3(600.0))  # the Chappuis band's peak region
    5.019e-25
    """
    text = (
        resources.files("dustoptics.refractive_indices")
        .joinpath("spectra", "ozone_serdyuchenko2014_233K_10nm.csv")
        .read_text(encoding="utf-8")
    )
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    if lines[0] != "bin_start_nm,bin_end_nm,cross_section_m2":  # pragma: no cover - shipped file
        raise RuntimeError(f"unexpected header of the shipped ozone spectrum: {lines[0]!r}")
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    return OzoneCrossSection(
        name="ozone-serdyuchenko2014-233K",
        wavelength_nm=rows[:, 0],
        sigma_m2=rows[:, 2],
        citation=SERDYUCHENKO_2014,
    )


def read_ozone_csv(path: str | os.PathLike[str], *, name: str | None = None) -> OzoneCrossSection:
    """Read an ozone cross-section spectrum from the documented CSV format.

    Parameters
    ----------
    path : path-like
        CSV file: comment lines (``#``) with the citation, then the header
        ``wavelength_nm,sigma_m2`` (or ``sigma_cm2``, ``sigma_O3_m2``,
        ``sigma_O3_cm2``), then rows. See the module docstring.
    name : str, optional
        Name of the spectrum; default the file's stem.

    Returns
    -------
    OzoneCrossSection
        With ``interpolation="linear"`` and the comment lines as citation.

    Raises
    ------
    ValueError
        No citation, a wrong header, a malformed row, wavelengths not strictly
        increasing, or a negative cross-section (the message names the line).
    """
    p = Path(path)
    citation: list[str] = []
    header: list[str] | None = None
    wl: list[float] = []
    sigma: list[float] = []
    scale = 1.0
    try:
        content = read_checked(p).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FormatError(f"{p}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    for lineno, raw in enumerate(content.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            if header is None:
                citation.append(line.lstrip("#").strip())
            continue
        cells = [c.strip() for c in line.split(",")]
        if header is None:
            header = cells
            m = _SIGMA_COLUMN.match(cells[1]) if len(cells) == 2 else None
            if cells[0] != "wavelength_nm" or m is None:
                raise ValueError(
                    f"{p}:{lineno}: header must be 'wavelength_nm,sigma_m2' or "
                    f"'wavelength_nm,sigma_cm2'; got {line!r}"
                )
            scale = 1.0 if m.group(1).lower() == "m2" else _CM2_TO_M2
            continue
        if len(cells) != 2:
            raise ValueError(f"{p}:{lineno}: expected 2 columns; got {line!r}")
        try:
            w, s = float(cells[0]), float(cells[1])
        except ValueError:
            raise ValueError(f"{p}:{lineno}: not numbers: {line!r}") from None
        wl.append(w)
        sigma.append(s * scale)
    if header is None or not wl:
        raise ValueError(f"{p}: no header line and data rows found")
    cite = " ".join(c for c in citation if c)
    if not cite:
        raise ValueError(f"{p}: the file must start with comment lines (#) giving the citation")
    return OzoneCrossSection(
        name=name or p.stem, wavelength_nm=np.array(wl), sigma_m2=np.array(sigma), citation=cite
    )


def ozone_beta_abs_per_m(
    wavelength_nm: ArrayLike,
    *,
    cross_section: OzoneCrossSection,
    number_density_per_m3: float,
) -> FloatArray:
    """Ozone absorption coefficient ``beta_abs = sigma(lambda) N_O3``.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths the spectrum covers. [nm]
    cross_section : OzoneCrossSection
        Absorption cross-section spectrum (e.g. :data:`KOBE2026_OZONE`).
    number_density_per_m3 : float
        Ozone number density, > 0. [m^-3]

    Returns
    -------
    numpy.ndarray
        Absorption coefficient. [m^-1]
    """
    if not isinstance(cross_section, OzoneCrossSection):
        raise TypeError(
            f"cross_section must be an OzoneCrossSection; got {type(cross_section).__name__}"
        )
    n = check_positive("number_density_per_m3", number_density_per_m3, unit="m^-3")
    return cross_section(wavelength_nm) * n


def ozone_table(
    wavelength_nm: ArrayLike,
    *,
    cross_section: OzoneCrossSection,
    number_density_per_m3: float,
    theta_deg: ArrayLike | None = None,
    name: str = "ozone",
) -> Table:
    """Ozone as a :class:`~dustoptics.table.Table`: absorbing only.

    ``cext_um2`` is the absorption cross-section [um^2], ``csca_um2 = 0``, so
    ``beta_abs_per_m = N sigma`` and ``beta_sca_per_m = 0``.  A Table needs a
    phase function for every constituent: ozone carries the isotropic
    ``1/(4 pi)`` with ``g = 0``.  It has no effect on any radiance, because
    a renderer weights a constituent's phase function by its scattering
    coefficient, which is zero; isotropic is the one choice that claims
    nothing about a scattering that does not happen.

    Raises
    ------
    ValueError
        A wavelength the spectrum does not cover, or a cross-section of
        exactly zero (Table requires ``cext_um2 > 0``).
    """
    wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    sigma = ozone_beta_abs_per_m(wl, cross_section=cross_section, number_density_per_m3=1.0)
    if np.any(sigma <= 0.0):
        raise ValueError(
            f"ozone cross-section {cross_section.name!r} is zero at wavelength_nm "
            f"{_show(wl[sigma <= 0.0])}; a Table needs cext_um2 > 0"
        )
    theta = _theta_grid(theta_deg)
    n = check_positive("number_density_per_m3", number_density_per_m3, unit="m^-3")
    return Table(
        name=name,
        wavelength_nm=wl,
        theta_deg=theta,
        phase=np.full((wl.size, theta.size), 1.0 / (4.0 * math.pi)),
        g=np.zeros(wl.size),
        cross_sections=CrossSections(
            cext_um2=sigma * _M2_TO_UM2, csca_um2=np.zeros(wl.size), number_density_per_m3=n
        ),
        provenance=Provenance(
            inputs={
                "kind": "ozone",
                "cross_section": cross_section.name,
                "interpolation": cross_section.interpolation,
                "number_density_per_m3": n,
                "wavelength_nm": wl,
                "theta_deg": theta,
            },
            sources=(
                Source(
                    name=cross_section.name,
                    role="absorption cross-section",
                    citation=cross_section.citation,
                ),
            ),
            notes=("Absorbing only: csca = 0; the isotropic phase function carries no weight.",),
        ),
    )
