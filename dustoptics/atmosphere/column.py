"""The atmospheric column: density profiles, optical depth and number density.

A constituent's number density at altitude ``z`` above the surface is
``N(z) = N0 rho(z)``, with ``rho`` a dimensionless *relative density* whose
largest value is 1 and ``N0`` [m^-3] the number density where ``rho = 1``.
A renderer (CosmoScout VR, Bruneton's model) stores ``rho`` sampled on an
altitude grid and the coefficients ``beta = N0 <C>`` at ``rho = 1``.

Every profile knows its *column length*, the altitude integral of ``rho``::

    L = int_0^top rho(z) dz      [m]       (L = H for an exponential profile)

so that the vertical optical depth at a wavelength is ``tau = N0 <C_ext> L``.
A measured optical depth at a reference wavelength therefore fixes ``N0``
(:func:`number_density_from_optical_depth`), and from it the coefficients at
every wavelength.  With a particle density it also gives the mass loading
``M = N0 L rho_p <V>`` [kg m^-2] (:func:`mass_loading_kg_m2`).

Profiles (frozen dataclasses)
-----------------------------
- :class:`ExponentialProfile`: ``exp(-z / H)``.
- :class:`PiecewiseLinearProfile`: linear between nodes (Bruneton's ozone
  layer is :data:`BRUNETON2017_OZONE`).
- :class:`MultiModalProfile`: a weighted sum of profiles.
- :class:`FixedFractionProfile`: the shape of another profile at a fixed
  fraction of its number density (Kobe's ozone: 6e-7 of the air).

:func:`sample_profile` samples a profile at evenly spaced altitudes for
CosmoScout VR's ``<name>_density.csv`` (largest sample exactly 1).

References
----------
.. [1] E. Bruneton, precomputed_atmospheric_scattering, demo (2017), ozone
   density profile, https://github.com/ebruneton/precomputed_atmospheric_scattering.
.. [2] J. Costa et al., "Interactive visualization of atmospheric effects for
   celestial bodies," IEEE TVCG 27(2), 785-795 (2021),
   doi:10.1109/TVCG.2020.3030333, eq. (11), (18).
.. [3] D. Kobe, "Ozone absorption in single atmospheric scattering,"
   graduation work, Howest DAE, 2025-2026, section 11.5.1.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dustoptics._validation import (
    MAX_GRID_POINTS,
    _show,
    as_float_array,
    as_increasing_grid,
    check_positive,
    check_real,
)

__all__ = [
    "BRUNETON2017_OZONE",
    "BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3",
    "DOBSON_UNIT_PER_M2",
    "DensityProfile",
    "DensitySamples",
    "ExponentialProfile",
    "FixedFractionProfile",
    "MultiModalProfile",
    "PiecewiseLinearProfile",
    "mass_loading_kg_m2",
    "number_density_from_optical_depth",
    "optical_depth",
    "sample_profile",
]

FloatArray = NDArray[np.float64]

_UM2_TO_M2: Final = 1e-12
_UM3_TO_M3: Final = 1e-18


def _altitudes(altitude_m: ArrayLike) -> FloatArray:
    z = as_float_array("altitude_m", altitude_m)
    if np.any(z < 0.0):
        raise ValueError(f"altitude_m must be >= 0 m (above the surface); got {_show(z[z < 0.0])}")
    return z


def _top(top_altitude_m: Any) -> float:
    if top_altitude_m == math.inf:
        return math.inf
    return check_positive("top_altitude_m", top_altitude_m, unit="m")


class DensityProfile(ABC):
    """Relative density ``rho(z)`` of a constituent, largest value 1.

    Subclasses are frozen dataclasses implementing :meth:`relative_density`
    and :meth:`column_length_m`.
    """

    @abstractmethod
    def relative_density(self, altitude_m: ArrayLike) -> FloatArray:
        """``rho`` at altitudes >= 0 above the surface. [-]"""

    @abstractmethod
    def column_length_m(self, *, top_altitude_m: float = math.inf) -> float:
        """``int_0^top rho(z) dz``, the column length. [m]"""

    def edges_m(self) -> tuple[float, ...]:
        """Altitudes above the ground where ``rho`` or its slope jumps, increasing. [m]

        A layer's top and bottom, the nodes of a piecewise-linear profile:
        where a quadrature over altitude must put a node (or a layer boundary)
        to stay accurate (:class:`~dustoptics.sky.medium.Medium` does).  A smooth
        profile has none (the default).
        """
        return ()

    def to_dict(self) -> dict[str, Any]:
        """Plain description for provenance."""
        out: dict[str, Any] = {"profile": type(self).__name__}
        for key, value in vars(self).items():
            if isinstance(value, DensityProfile):
                out[key] = value.to_dict()
            elif isinstance(value, tuple) and value and isinstance(value[0], DensityProfile):
                out[key] = [v.to_dict() for v in value]
            else:
                out[key] = list(value) if isinstance(value, tuple) else value
        return out


@dataclass(frozen=True)
class ExponentialProfile(DensityProfile):
    """Hydrostatic (isothermal) profile ``rho = exp(-z / H)``.

    Parameters
    ----------
    scale_height_m : float
        Scale height ``H``, > 0. [m]
    """

    scale_height_m: float

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "scale_height_m", check_positive("scale_height_m", self.scale_height_m, unit="m")
        )

    def relative_density(self, altitude_m: ArrayLike) -> FloatArray:
        """``exp(-z / H)``. [-]"""
        return np.exp(-_altitudes(altitude_m) / self.scale_height_m)

    def column_length_m(self, *, top_altitude_m: float = math.inf) -> float:
        """``H (1 - exp(-top / H))``; ``H`` for an unbounded column. [m]"""
        top = _top(top_altitude_m)
        return self.scale_height_m * -math.expm1(-top / self.scale_height_m)


#: Relative slope change above which a piecewise-linear profile's node is an edge
#: (:meth:`PiecewiseLinearProfile.edges_m`). [-]
KINK_RELATIVE_SLOPE: Final = 0.05


@dataclass(frozen=True)
class PiecewiseLinearProfile(DensityProfile):
    """Relative density linear between nodes (Bruneton's layered profiles).

    Parameters
    ----------
    altitude_m : sequence of float
        Node altitudes, strictly increasing, the first exactly 0. [m]
    density : sequence of float
        Relative density at the nodes, in [0, 1], largest exactly 1. [-]

    Notes
    -----
    Above the last node the density is zero when the last node's value is 0
    (the continuous continuation); otherwise asking above the last node is an
    error, since the profile is not defined there.
    """

    altitude_m: Sequence[float]
    density: Sequence[float]

    def __post_init__(self) -> None:
        z = as_increasing_grid("altitude_m", self.altitude_m, unit="m")
        d = as_float_array("density", self.density, ndim=1)
        if z.size < 2 or d.shape != z.shape:
            raise ValueError(
                f"altitude_m and density must have the same length >= 2; got {z.size} and {d.size}"
            )
        if z[0] != 0.0:
            raise ValueError(f"altitude_m must start at exactly 0 m (the surface); got {z[0]!r}")
        if np.any((d < 0.0) | (d > 1.0)) or d.max() != 1.0:
            raise ValueError(
                f"density must lie in [0, 1] with largest value exactly 1; got {_show(d)}"
            )
        object.__setattr__(self, "altitude_m", tuple(z.tolist()))
        object.__setattr__(self, "density", tuple(d.tolist()))

    def _check_top(self, z: FloatArray) -> None:
        if self.density[-1] != 0.0 and np.any(z > self.altitude_m[-1]):
            raise ValueError(
                f"altitude_m above the last node ({self.altitude_m[-1]:g} m) of a profile whose last "
                f"density is {self.density[-1]!r} (not 0): undefined there; got {_show(z[z > self.altitude_m[-1]])}"
            )

    def relative_density(self, altitude_m: ArrayLike) -> FloatArray:
        """Linear interpolation between nodes (0 above a last node of 0). [-]"""
        z = _altitudes(altitude_m)
        self._check_top(z)
        return np.interp(z, self.altitude_m, self.density, right=0.0)

    def edges_m(self) -> tuple[float, ...]:
        """The nodes above the ground where the slope jumps, and the last node. [m]

        A node is an edge where the slope changes by more than
        :data:`KINK_RELATIVE_SLOPE` of the larger of its two slopes: a layer's top,
        the join of two exponentials, ozone's triangle.  A smooth curve sampled
        densely (CalcMySky's 1,201 nodes of a Viking density fit) changes slope by
        ``h / H`` per node (1.3 % for 100 m nodes on a 7.75 km scale height): a
        quadrature treats it as the smooth curve it samples, and making each of its
        nodes an edge of every path would multiply the sky's work by the node count.
        """
        z = np.asarray(self.altitude_m)
        slope = np.diff(np.asarray(self.density)) / np.diff(z)
        jump = np.abs(np.diff(slope))
        scale = np.maximum(np.abs(slope[1:]), np.abs(slope[:-1]))
        kinks = z[1:-1][jump > KINK_RELATIVE_SLOPE * scale]
        return (*kinks.tolist(), float(z[-1]))

    def column_length_m(self, *, top_altitude_m: float = math.inf) -> float:
        """Exact integral of the piecewise-linear function up to ``top_altitude_m``. [m]"""
        top = _top(top_altitude_m)
        self._check_top(np.array([top]))
        z = np.array(self.altitude_m)
        d = np.array(self.density)
        if top < z[-1]:
            keep = z < top
            z = np.append(z[keep], top)
            d = np.append(d[keep], np.interp(top, self.altitude_m, self.density))
        return float(np.sum(0.5 * (d[1:] + d[:-1]) * np.diff(z)))


@dataclass(frozen=True)
class MultiModalProfile(DensityProfile):
    """Weighted sum of profiles, ``rho = sum_i w_i rho_i / sum_i w_i``.

    Parameters
    ----------
    profiles : sequence of DensityProfile
        The modes, each with largest value 1.
    weights : sequence of float
        Relative weights (> 0) of the modes at their peaks; only ratios matter.

    Notes
    -----
    The sum's largest value is 1 when all modes peak at the same altitude
    (e.g. exponentials); otherwise it is below 1, and :func:`sample_profile`
    reports the factor by which it rescales the samples to a peak of 1.
    ``N0`` always refers to ``rho = 1`` of this definition.
    """

    profiles: Sequence[DensityProfile]
    weights: Sequence[float]

    def __post_init__(self) -> None:
        profiles = tuple(self.profiles)
        if not profiles or not all(isinstance(p, DensityProfile) for p in profiles):
            raise ValueError(
                f"profiles must be a non-empty sequence of DensityProfile; got {self.profiles!r}"
            )
        w = as_float_array("weights", self.weights, ndim=1)
        if w.size != len(profiles) or np.any(w <= 0.0):
            raise ValueError(
                f"weights must be {len(profiles)} values > 0 (one per profile); got {_show(w)}"
            )
        object.__setattr__(self, "profiles", profiles)
        object.__setattr__(self, "weights", tuple((w / w.sum()).tolist()))

    def relative_density(self, altitude_m: ArrayLike) -> FloatArray:
        """Weighted mean of the modes' relative densities. [-]"""
        z = _altitudes(altitude_m)
        total = sum(
            w * p.relative_density(z) for w, p in zip(self.weights, self.profiles, strict=True)
        )
        return np.asarray(total, dtype=np.float64)

    def edges_m(self) -> tuple[float, ...]:
        """Every mode's edges, increasing, once each. [m]"""
        return tuple(sorted({e for p in self.profiles for e in p.edges_m()}))

    def column_length_m(self, *, top_altitude_m: float = math.inf) -> float:
        """Weighted mean of the modes' column lengths. [m]"""
        return float(
            sum(
                w * p.column_length_m(top_altitude_m=top_altitude_m)
                for w, p in zip(self.weights, self.profiles, strict=True)
            )
        )


@dataclass(frozen=True)
class FixedFractionProfile(DensityProfile):
    """The shape of a base profile at a fixed fraction of its number density.

    Kobe (2026) models ozone as ``6e-7`` of the air: same relative density
    as the Rayleigh layer, and ``N0_O3 = fraction * N0_air``
    (:meth:`number_density_per_m3`).

    Parameters
    ----------
    base : DensityProfile
        The profile followed (e.g. the molecules' exponential).
    fraction : float
        Ratio of number densities, in (0, 1]. [-]
    """

    base: DensityProfile
    fraction: float

    def __post_init__(self) -> None:
        if not isinstance(self.base, DensityProfile):
            raise TypeError(f"base must be a DensityProfile; got {type(self.base).__name__}")
        f = check_real("fraction", self.fraction)
        if not 0.0 < f <= 1.0:
            raise ValueError(f"fraction must be in (0, 1]; got {self.fraction!r}")
        object.__setattr__(self, "fraction", f)

    def relative_density(self, altitude_m: ArrayLike) -> FloatArray:
        """The base profile's relative density. [-]"""
        return self.base.relative_density(altitude_m)

    def edges_m(self) -> tuple[float, ...]:
        """The base profile's edges. [m]"""
        return self.base.edges_m()

    def column_length_m(self, *, top_altitude_m: float = math.inf) -> float:
        """The base profile's column length. [m]"""
        return self.base.column_length_m(top_altitude_m=top_altitude_m)

    def number_density_per_m3(self, *, base_number_density_per_m3: float) -> float:
        """``fraction * N0_base``. [m^-3]"""
        return self.fraction * check_positive(
            "base_number_density_per_m3", base_number_density_per_m3, unit="m^-3"
        )


#: One Dobson unit, 2.687e20 molecules per m^2 (as in Bruneton's demo). [m^-2]
DOBSON_UNIT_PER_M2: Final = 2.687e20

#: Bruneton's ozone layer: 0 below 10 km, rising linearly to 1 at 25 km and
#: back to 0 at 40 km (his two 25-km layers, ``h/15km - 2/3`` and
#: ``-h/15km + 8/3``), whose column length is 15 km.
BRUNETON2017_OZONE: Final = PiecewiseLinearProfile(
    altitude_m=(0.0, 10000.0, 25000.0, 40000.0), density=(0.0, 0.0, 1.0, 0.0)
)

#: Peak ozone number density of Bruneton's demo: 300 DU over the 15 km column
#: length of :data:`BRUNETON2017_OZONE`. [m^-3]
BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3: Final = 300.0 * DOBSON_UNIT_PER_M2 / 15000.0


# ----------------------------------------------------- optical depth <-> N0


def _profile(profile: DensityProfile | None, scale_height_m: float | None) -> DensityProfile:
    if (profile is None) == (scale_height_m is None):
        raise ValueError("give exactly one of profile or scale_height_m")
    if profile is None:
        return ExponentialProfile(scale_height_m=scale_height_m)  # type: ignore[arg-type]
    if not isinstance(profile, DensityProfile):
        raise TypeError(f"profile must be a DensityProfile; got {type(profile).__name__}")
    return profile


def number_density_from_optical_depth(
    *,
    optical_depth: float,
    cext_um2: float,
    profile: DensityProfile | None = None,
    scale_height_m: float | None = None,
    top_altitude_m: float = math.inf,
) -> float:
    """Number density ``N0`` from a vertical optical depth: ``tau / (<C_ext> L)``.

    Parameters
    ----------
    optical_depth : float
        Vertical optical depth at the reference wavelength, > 0. [-]
    cext_um2 : float
        Mean extinction cross-section per particle at that wavelength, > 0. [um^2]
    profile : DensityProfile, optional
        Density profile; or give ``scale_height_m`` for an exponential one.
    scale_height_m : float, optional
        Scale height of an exponential profile, > 0. [m]
    top_altitude_m : float, default inf
        Top of the column (a renderer's atmosphere top). [m]

    Returns
    -------
    float
        Number density where the relative density is 1. [m^-3]

    Examples
    --------
    Mars, tau = 0.5 at 11 km scale height with <C_ext> = 10 um^2:

    >>> number_density_from_optical_depth(optical_depth=0.5, cext_um2=10.0, scale_height_m=11000.0)
    4545454.545454546
    """
    tau = check_positive("optical_depth", optical_depth)
    c = check_positive("cext_um2", cext_um2, unit="um^2")
    length = _profile(profile, scale_height_m).column_length_m(top_altitude_m=top_altitude_m)
    return tau / (c * _UM2_TO_M2 * length)


def optical_depth(
    *,
    number_density_per_m3: float,
    cext_um2: ArrayLike,
    profile: DensityProfile | None = None,
    scale_height_m: float | None = None,
    top_altitude_m: float = math.inf,
) -> float | FloatArray:
    """Vertical optical depth ``tau = N0 <C_ext> L`` (inverse of :func:`number_density_from_optical_depth`).

    Parameters
    ----------
    number_density_per_m3 : float
        ``N0``, > 0. [m^-3]
    cext_um2 : array_like
        Mean extinction cross-section(s) per particle, > 0. [um^2]
    profile, scale_height_m, top_altitude_m
        As for :func:`number_density_from_optical_depth`.

    Returns
    -------
    float or numpy.ndarray
        Optical depth per cross-section given. [-]
    """
    n0 = check_positive("number_density_per_m3", number_density_per_m3, unit="m^-3")
    c = as_float_array("cext_um2", cext_um2)
    if np.any(c <= 0.0):
        raise ValueError(f"cext_um2 must be > 0 um^2; got {_show(cext_um2)}")
    length = _profile(profile, scale_height_m).column_length_m(top_altitude_m=top_altitude_m)
    tau = n0 * c * _UM2_TO_M2 * length
    return float(tau) if tau.ndim == 0 else tau


def mass_loading_kg_m2(
    *,
    number_density_per_m3: float,
    mean_volume_um3: float,
    particle_density_kg_m3: float,
    profile: DensityProfile | None = None,
    scale_height_m: float | None = None,
    top_altitude_m: float = math.inf,
) -> float:
    """Column mass of particles per unit area, ``N0 L rho_p <V>``.

    Parameters
    ----------
    number_density_per_m3 : float
        ``N0``, > 0. [m^-3]
    mean_volume_um3 : float
        Mean particle volume ``4/3 pi <r^3>`` (``SizeDistribution.mean_volume_um3``), > 0. [um^3]
    particle_density_kg_m3 : float
        Material density of the particles, > 0 (Mars dust ~2500). [kg m^-3]
    profile, scale_height_m, top_altitude_m
        As for :func:`number_density_from_optical_depth`.

    Returns
    -------
    float
        Mass loading. [kg m^-2]
    """
    n0 = check_positive("number_density_per_m3", number_density_per_m3, unit="m^-3")
    v = check_positive("mean_volume_um3", mean_volume_um3, unit="um^3")
    rho = check_positive("particle_density_kg_m3", particle_density_kg_m3, unit="kg m^-3")
    length = _profile(profile, scale_height_m).column_length_m(top_altitude_m=top_altitude_m)
    return n0 * length * v * _UM3_TO_M3 * rho


# ------------------------------------------------------------------ sampling


@dataclass(frozen=True, eq=False)
class DensitySamples:
    """A profile sampled at evenly spaced altitudes, rescaled to a peak of 1.

    Attributes
    ----------
    altitude_m : numpy.ndarray
        Evenly spaced altitudes from the bottom to the top of the grid. [m]
    relative_density : numpy.ndarray
        Samples divided by their largest value (so the largest is exactly 1). [-]
    peak : float
        The largest raw sample: multiply ``N0`` by it to get the number
        density at ``relative_density = 1`` (1 for profiles that reach 1 on
        the grid). [-]
    """

    altitude_m: FloatArray
    relative_density: FloatArray
    peak: float


def sample_profile(
    profile: DensityProfile,
    *,
    top_altitude_m: float,
    n_altitudes: int = 1024,
    bottom_altitude_m: float = 0.0,
) -> DensitySamples:
    """Sample a profile at evenly spaced altitudes (CosmoScout VR's density file).

    Parameters
    ----------
    profile : DensityProfile
        The profile.
    top_altitude_m : float
        Last altitude (the atmosphere's top above the surface), > bottom. [m]
    n_altitudes : int, default 1024
        Number of samples, 2 to 1,000,000 (CosmoScout's default 1024). [-]
    bottom_altitude_m : float, default 0
        First altitude. [m]

    Returns
    -------
    DensitySamples

    Raises
    ------
    ValueError
        Bad grid, or a profile that is zero everywhere on it.
    """
    if not isinstance(profile, DensityProfile):
        raise TypeError(f"profile must be a DensityProfile; got {type(profile).__name__}")
    if (
        isinstance(n_altitudes, bool)
        or not isinstance(n_altitudes, (int, np.integer))
        or n_altitudes < 2
    ):
        raise ValueError(f"n_altitudes must be an integer >= 2; got {n_altitudes!r}")
    if n_altitudes > MAX_GRID_POINTS:
        raise ValueError(f"n_altitudes must be <= {MAX_GRID_POINTS}; got {n_altitudes!r}")
    bottom = check_real("bottom_altitude_m", bottom_altitude_m)
    top = check_positive("top_altitude_m", top_altitude_m, unit="m")
    if not 0.0 <= bottom < top:
        raise ValueError(
            f"altitudes must satisfy 0 <= bottom_altitude_m < top_altitude_m; got {bottom!r}, {top!r}"
        )
    z = np.linspace(bottom, top, int(n_altitudes))
    raw = np.asarray(profile.relative_density(z), dtype=np.float64)
    peak = float(raw.max())
    if peak <= 0.0:
        raise ValueError(f"profile {profile!r} is zero everywhere between {bottom:g} and {top:g} m")
    rel = raw / peak
    rel[np.argmax(raw)] = 1.0
    z.setflags(write=False)
    rel.setflags(write=False)
    return DensitySamples(altitude_m=z, relative_density=rel, peak=peak)
