"""Particle size distributions: the interface, and the analytic families of the literature.

A size distribution is a number density of particles per unit radius,
``n(r)``, normalized so that ``integral_0^inf n(r) dr = 1``.  Radii are in
micrometres throughout, so ``n`` is in [um^-1] and the k-th moment
``<r^k> = integral_0^inf r^k n(r) dr`` is in [um^k].

Every distribution knows its moments, the fraction of any moment that lies
above or below a radius, and radii that cut off the tails with a bounded,
documented loss.  All of these are analytic (regularized incomplete gamma
functions, the normal distribution and their inverses from scipy), so the
quadrature that integrates Mie quantities over ``n(r)`` can truncate the radius
range with a known error instead of guessing it.

Models
------
- :class:`ModifiedGamma`: Hansen & Travis (1974), parametrized by effective
  radius and effective variance.
- :class:`Gamma`: the same family by shape and scale.
- :class:`LogNormal`: by median radius and the standard deviation of ``ln r``.
- :class:`ModifiedLogNormal`: CosmoScout VR's log-normal parametrized by
  effective radius and effective variance.
- :class:`Monodisperse`: a single radius (no density).
- :class:`DeirmendjianGamma`: Deirmendjian's (1969) modified gamma distribution.
- :class:`PowerLaw`: Junge's (1963) power law between two radii.
- :class:`Truncated`: any distribution cut to a radius range and renormalized
  (made by :meth:`SizeDistribution.truncated`, so it lives beside the interface).

Registry
--------
Each family registers itself when its class is defined (a class that sets
``model``): :data:`SIZE_DISTRIBUTIONS` maps the model name to the class, whose
``parameters`` (:class:`SizeParameter`) give the constructor's keys and their
ranges.  The TOML configuration, :func:`~dustoptics.particles.custom_sizedist.from_dict`
and :mod:`~dustoptics.particles.sizedist_derivatives` read it, so a new family
is one class.  :func:`get_size_distribution` looks a family up by name or by
an alias (:data:`SIZE_DISTRIBUTION_ALIASES`), among them the names other codes
use for the same distribution:

===================== ================================================ ===================================
here                  elsewhere                                        alias
===================== ================================================ ===================================
``ModifiedGamma``     Hansen & Travis's (1974) gamma; scatrs ``Gamma``  ``hansen_travis1974_gamma``
``DeirmendjianGamma`` Deirmendjian's (1969) modified gamma; scatrs      ``deirmendjian1969_modified_gamma``
                      ``ModifiedGamma``
``PowerLaw``          Junge's (1963) distribution                      ``junge1963``
===================== ================================================ ===================================

Distributions the user puts together (a mixture of modes, a measured table, a
density function) and :func:`~dustoptics.particles.custom_sizedist.from_dict`
are in :mod:`dustoptics.particles.custom_sizedist`.

The effective radius and variance are (Hansen & Travis 1974)::

    r_eff = <r^3> / <r^2>
    v_eff = <r^4> <r^2> / <r^3>^2 - 1

that is, the mean and the relative variance of the radius weighted by the
geometric cross-section ``pi r^2 n(r)``.

References
----------
.. [1] J. E. Hansen and L. D. Travis, "Light scattering in planetary
   atmospheres," Space Sci. Rev., vol. 16, pp. 527-610, 1974,
   doi:10.1007/BF00168069.
.. [2] German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres,
   scattering-table-generator (mie mode, size modes ``modifiedLogNormal`` and
   ``relativeNumberDensity``), https://github.com/cosmoscout/cosmoscout-vr.
"""

from __future__ import annotations

import math
import warnings
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, ClassVar, Final

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import special

from dustoptics._validation import (
    check_open_interval,
    check_positive,
    check_real,
)

__all__ = [
    "MAX_SIGMA",
    "MIN_R_EFF_UM",
    "MIN_TAIL_FRACTION",
    "MIN_V_EFF",
    "RADIUS_RANGE_UM",
    "SIZE_DISTRIBUTIONS",
    "SIZE_DISTRIBUTION_ALIASES",
    "DeirmendjianGamma",
    "Gamma",
    "LogNormal",
    "ModifiedGamma",
    "ModifiedLogNormal",
    "Monodisperse",
    "PowerLaw",
    "SizeDistribution",
    "SizeParameter",
    "Truncated",
    "get_size_distribution",
]

FloatOrArray = float | NDArray[np.float64]

HANSEN_TRAVIS_1974 = (
    'J. E. Hansen and L. D. Travis, "Light scattering in planetary atmospheres," '
    "Space Sci. Rev., vol. 16, pp. 527-610, 1974, doi:10.1007/BF00168069"
)
COSMOSCOUT_VR = (
    "German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres, "
    "scattering-table-generator, https://github.com/cosmoscout/cosmoscout-vr"
)


def _as_radius(radius_um: ArrayLike) -> NDArray[np.float64]:
    """Radii as a float64 array (a copy); NaN is kept and propagates."""
    try:
        return np.array(radius_um, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"radius_um must be real numbers [um]; got {radius_um!r}") from None


def _scalar_or_array(values: NDArray[np.float64]) -> FloatOrArray:
    """Return a Python float for 0-d results and the array otherwise."""
    return float(values) if values.ndim == 0 else values


#: Radii accepted for any size parameter of a distribution (r_eff, median,
#: scale, a monodisperse radius): 1e-6 um (1 pm, below any atom) to 1e6 um
#: (1 m).  Inside it every moment up to order 6 and every derived radius is a
#: finite double; the work a computation needs is bounded separately
#: (:func:`dustoptics.scattering.optics.estimate_cost`). [um]
RADIUS_RANGE_UM = (1e-6, 1e6)

#: Smallest effective variance accepted by :class:`ModifiedGamma` and
#: :class:`ModifiedLogNormal` (and the matching bounds of :class:`Gamma`,
#: shape <= 1e4 - 2, and :class:`LogNormal`, sigma >= 0.01).  Down to it the
#: densities, moments and tail bounds keep full precision (the gamma log-density
#: sums terms of size ``shape``, losing about ``shape * eps``: 1e-12 at 1e4);
#: a narrower population is a :class:`Monodisperse` one to better than its
#: 1 % width. [1]
MIN_V_EFF = 1e-4

#: Largest ``sigma`` of :class:`LogNormal` (geometric standard deviation
#: e^3 = 20; v_eff = e^9 - 1 = 8.1e3, the largest :class:`ModifiedLogNormal`
#: accepts): beyond it the sixth moment overflows for radii near the ends of
#: :data:`RADIUS_RANGE_UM`. [1]
MAX_SIGMA = 3.0

#: Smallest ``tail_fraction`` (quantiles below it are not resolved in double
#: precision: the quantile functions return 0 or overflow). [1]
MIN_TAIL_FRACTION = 1e-15


#: Smallest effective radius of a population: 1e-3 um (1 nm, the size of a molecule).  A
#: smaller one was almost surely given in metres (``r_eff_um=1.6e-6`` meant 1.6 um) and is
#: refused, as wavelengths plainly not in nanometres are
#: (:func:`dustoptics._validation.check_wavelength_unit`); a :class:`Monodisperse`
#: sphere that small only warns (the Rayleigh limit is tested down to 1e-6 um). [um]
MIN_R_EFF_UM = 1e-3


def _check_radius(name: str, value: Any) -> float:
    out = check_positive(name, value, unit="um")
    low, high = RADIUS_RANGE_UM
    if not low <= out <= high:
        hint = " (was it in metres?)" if out < low else ""
        raise ValueError(f"{name} must be in [{low:g}, {high:g}] um; got {value!r}{hint}")
    return out


def _metres_message(name: str, value: float) -> str:
    return (
        f"{name} must be in micrometres; got {value!r}, below {MIN_R_EFF_UM:g} um (1 nm, the "
        f"size of a molecule): was it in metres? ({value:g} m = {value * 1e6:g} um)"
    )


def _check_r_eff(name: str, value: Any) -> float:
    """An effective radius: a radius (:func:`_check_radius`), plainly not in metres."""
    out = check_positive(name, value, unit="um")
    if out < MIN_R_EFF_UM:
        raise ValueError(_metres_message(name, out))
    return _check_radius(name, out)


def _check_v_eff(value: Any, high: float) -> float:
    out = check_real("v_eff", value)
    if not MIN_V_EFF <= out < high:
        raise ValueError(
            f"v_eff must be in [{MIN_V_EFF:g}, {high:g}) (narrower populations: use Monodisperse); "
            f"got {value!r}"
        )
    return out


def _check_radius_range(r_min_um: Any, r_max_um: Any) -> tuple[float, float]:
    """``(r_min_um, r_max_um)`` of a finite support, ``0 < r_min_um < r_max_um < inf`` [um]."""
    lo = check_positive("r_min_um", r_min_um, unit="um")
    hi = check_positive("r_max_um", r_max_um, unit="um")
    if not (hi > lo and math.isfinite(hi)):
        raise ValueError(f"r_max_um must be finite and > r_min_um = {lo!r} um; got {r_max_um!r}")
    return lo, hi


def _check_tail_fraction(tail_fraction: Any) -> float:
    out = check_open_interval("tail_fraction", tail_fraction, 0.0, 0.5)
    if out < MIN_TAIL_FRACTION:
        raise ValueError(f"tail_fraction must be >= {MIN_TAIL_FRACTION:g}; got {tail_fraction!r}")
    return out


@dataclass(frozen=True)
class SizeParameter:
    """One constructor parameter of a size-distribution family, as others read it.

    The TOML configuration checks a number against ``(low, high)`` and then lets
    the class check the rest; :mod:`~dustoptics.particles.sizedist_derivatives`
    differentiates with respect to the ``"number"`` parameters.

    Attributes
    ----------
    name : str
        Keyword of the constructor, with the unit in the name (``r_eff_um``).
    low, high : float
        Open range of a number (``-inf``/``inf``: unbounded); the class may
        demand more. [parameter's unit]
    kind : {"number", "numbers", "distribution", "distributions"}
        A number, an array of numbers, a nested size distribution or several.
    required : bool
        False for a parameter that may be left out (one of two alternatives).
    """

    name: str
    low: float = 0.0
    high: float = math.inf
    kind: str = "number"
    required: bool = True


#: Every size-distribution family, by its ``model`` name: filled by the classes
#: themselves when they are defined (:meth:`SizeDistribution.__init_subclass__`).
_REGISTRY: dict[str, type[SizeDistribution]] = {}
_ALIASES: dict[str, str] = {}

#: Read-only view of the registry: model name -> class.
SIZE_DISTRIBUTIONS: Final[Mapping[str, type[SizeDistribution]]] = MappingProxyType(_REGISTRY)

#: Other names of the families (peers' names among them), each to its model name.
SIZE_DISTRIBUTION_ALIASES: Final[Mapping[str, str]] = MappingProxyType(_ALIASES)


def get_size_distribution(name: str) -> type[SizeDistribution]:
    """The size-distribution class registered as ``name`` or under one of its aliases.

    Raises
    ------
    ValueError
        For an unknown name; the message lists the valid ones.

    Examples
    --------
    >>> get_size_distribution("hansen_travis1974_gamma").__name__
    'ModifiedGamma'
    """
    model = _ALIASES.get(name, name)
    if model not in _REGISTRY:
        valid = ", ".join(repr(n) for n in (*_REGISTRY, *_ALIASES))
        raise ValueError(f"size distribution model must be one of {valid}; got {name!r}")
    return _REGISTRY[model]


class SizeDistribution(ABC):
    """A normalized number distribution of particle radii, ``n(r)`` [um^-1].

    Subclasses provide the moments and the moment tail fractions analytically;
    the derived radii and cross-sections below follow from the moments.
    Instances are immutable and hashable.

    Attributes
    ----------
    model : str
        Short name of the model, recorded with every table built from it and
        its key in :data:`SIZE_DISTRIBUTIONS`.
    citation : str
        Where the model is defined.
    parameters : tuple of SizeParameter
        The constructor's parameters, with their ranges, in order.
    aliases : tuple of str
        Other names of the family (:data:`SIZE_DISTRIBUTION_ALIASES`).

    Notes
    -----
    A subclass that sets ``model`` registers itself in
    :data:`SIZE_DISTRIBUTIONS`; the TOML configuration, :func:`from_dict
    <dustoptics.particles.custom_sizedist.from_dict>` and the derivatives
    read the registry, so a new family is one class.
    """

    __slots__ = ()

    model: ClassVar[str]
    citation: ClassVar[str]
    parameters: ClassVar[tuple[SizeParameter, ...]] = ()
    aliases: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Register a family that names its ``model`` (a dataclass rebuilt with slots replaces
        its first version under the same name)."""
        super().__init_subclass__(**kwargs)
        name = cls.__dict__.get("model")
        if name is None:
            return
        known = _REGISTRY.get(name)
        if known is not None and known.__qualname__ != cls.__qualname__:
            raise ValueError(
                f"size distribution model {name!r} is already registered by {known.__qualname__}"
            )
        _REGISTRY[name] = cls
        for alias in cls.__dict__.get("aliases", ()):
            _ALIASES[alias] = name

    # ------------------------------------------------------------------ density

    @property
    def has_density(self) -> bool:
        """Whether ``n(r)`` is a density (False when it has a point mass)."""
        return True

    @property
    def is_monodisperse(self) -> bool:
        """Whether every particle has the same radius."""
        return False

    @abstractmethod
    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        """Number density ``n(r)`` [um^-1], normalized to 1 over r > 0.

        Parameters
        ----------
        radius_um : array_like
            Radius. [um]

        Returns
        -------
        float or numpy.ndarray
            ``n(r)``, with the shape of ``radius_um``; 0 where ``r <= 0`` and
            NaN where ``radius_um`` is NaN. [um^-1]
        """

    # ------------------------------------------------------------------ moments

    @abstractmethod
    def moment(self, k: float) -> float:
        """Moment ``<r^k> = integral_0^inf r^k n(r) dr`` [um^k].

        Parameters
        ----------
        k : float
            Order of the moment; any real number for which the moment is finite.

        Returns
        -------
        float
            ``<r^k>``. [um^k]

        Raises
        ------
        ValueError
            If ``k`` is not finite or the moment diverges.
        """

    @abstractmethod
    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        """Fraction of the k-th moment above (``upper``) or below ``radius_um``.

        ``k`` is validated by the caller; ``radius_um`` may hold r <= 0 or NaN.
        """

    @abstractmethod
    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        """Unvalidated implementation of :meth:`radius_bounds_um`."""

    def _parameters(self) -> dict[str, Any]:
        """Model parameters, keyed by name with the unit in the name (:attr:`parameters`)."""
        return {p.name: getattr(self, p.name) for p in self.parameters}

    def moment_tail_fraction(self, k: float, radius_um: ArrayLike, *, upper: bool) -> FloatOrArray:
        """Fraction of the k-th moment integral above or below a radius.

        With ``M_k = integral_0^inf r'^k n(r') dr'``::

            upper=True:   F_k^>(r) = integral_r^inf r'^k n(r') dr' / M_k
            upper=False:  F_k^<(r) = integral_0^r   r'^k n(r') dr' / M_k = 1 - F_k^>(r)

        ``k = 0`` is the number fraction, ``k = 2`` the fraction of the
        geometric cross-section, ``k = 3`` the fraction of the volume.

        Parameters
        ----------
        k : float
            Order of the moment (any real for which ``<r^k>`` is finite).
        radius_um : array_like
            Radius where the distribution is cut. [um]
        upper : bool
            True for the fraction above ``radius_um``, False for the fraction
            at or below it (the two differ only for :class:`Monodisperse`,
            whose whole mass sits at one radius).

        Returns
        -------
        float or numpy.ndarray
            The fraction in [0, 1], with the shape of ``radius_um``; NaN where
            ``radius_um`` is NaN. [1]

        Notes
        -----
        For the gamma family the k-weighted distribution ``r^k n(r) / M_k`` is
        again a gamma distribution with shape ``shape + k``, so the fractions
        are the regularized incomplete gamma functions ``Q(shape + k, r/scale)``
        and ``P(shape + k, r/scale)``.  For the log-normal family it is again
        log-normal with ``ln`` median ``mu + k sigma^2``, so the fractions are
        the normal survival and distribution functions of
        ``(ln r - mu - k sigma^2) / sigma``.  A mixture weights each mode's
        fraction by the mode's share of the k-th moment.
        """
        k = check_real("k", k)
        self.moment(k)  # raises if the moment diverges
        r = _as_radius(radius_um)
        return _scalar_or_array(self._tail(k, r, bool(upper)))

    def radius_bounds_um(
        self,
        *,
        tail_fraction: float,
        lower_moment: float = 0.0,
        upper_moment: float = 6.0,
    ) -> tuple[float, float]:
        """Radii that cut off the tails of the distribution with a bounded loss.

        Returns ``(r_lo, r_hi)`` such that, with the tail fractions ``F_k^<``
        and ``F_k^>`` of :meth:`moment_tail_fraction` and ``eps = tail_fraction``::

            F_p^<(r_lo) <= eps   for every moment order p >= lower_moment,
            F_p^>(r_hi) <= eps   for every moment order p <= upper_moment.

        So for every p in ``[lower_moment, upper_moment]`` the integral
        ``integral r^p n(r) dr`` restricted to ``[r_lo, r_hi]`` misses at most
        ``eps`` of ``<r^p>`` in each tail, ``2 eps`` in total.  The defaults,
        0 to 6, cover the particle number (p = 0), the geometric and
        large-particle cross-sections (p = 2), absorption of small particles
        (p = 3) and Rayleigh scattering (p = 6).  More generally, if
        ``|f(r)| <= A r^q`` for ``r >= r_hi`` with ``q <= upper_moment``, the
        part of ``integral f n dr`` above ``r_hi`` is at most
        ``A eps <r^q>`` (and likewise below ``r_lo``).

        Parameters
        ----------
        tail_fraction : float
            Largest fraction ``eps`` of a moment allowed in each tail; in the
            open interval (0, 0.5). [1]
        lower_moment : float, default 0
            Moment order whose lower tail is bounded. [1]
        upper_moment : float, default 6
            Moment order whose upper tail is bounded; must be
            ``>= lower_moment``. [1]

        Returns
        -------
        r_lo_um, r_hi_um : tuple of float
            Lower and upper radius, ``0 < r_lo_um <= r_hi_um``. [um]

        Notes
        -----
        For one continuous mode the bounds are the exact quantiles,
        ``F_lower^<(r_lo) = F_upper^>(r_hi) = eps`` (up to the rounding of
        ``scipy.special.gammaincinv``/``gammainccinv`` or
        ``scipy.special.ndtri``).  The statement for other orders p follows
        because the tail fractions are monotonic in the order: the density of
        ``r^p n(r)`` relative to that of ``r^q n(r)`` is proportional to
        ``r^(p - q)``, increasing in r for p > q, so ``F_p^>(r)`` does not
        decrease and ``F_p^<(r)`` does not increase with p (likelihood-ratio
        ordering).

        For a :class:`~dustoptics.particles.custom_sizedist.MultiModal` the bounds
        are the smallest ``r_lo`` and the largest ``r_hi`` of its modes.  This is
        still a valid bound: the mixture's tail fraction is a weighted mean of the
        modes' fractions,
        ``F^<(r) = sum_i c_i F_i^<(r) / sum_i c_i`` with ``c_i >= 0`` the
        modes' contributions to the moment, and each ``F_i^<`` is
        non-decreasing in r, so at ``r_lo = min_i r_lo,i`` every
        ``F_i^<(r_lo) <= F_i^<(r_lo,i) <= eps`` and hence their mean is too
        (symmetrically for ``r_hi``).  It is conservative: the mixture's own
        tail is usually much smaller than ``eps``.
        """
        eps = _check_tail_fraction(tail_fraction)
        lower = check_real("lower_moment", lower_moment)
        upper = check_real("upper_moment", upper_moment)
        if lower > upper:
            raise ValueError(
                f"lower_moment must be <= upper_moment; got lower_moment={lower_moment!r}, "
                f"upper_moment={upper_moment!r}"
            )
        self.moment(lower)  # raise if either moment diverges
        self.moment(upper)
        return self._bounds(eps, lower, upper)

    # ---------------------------------------------------------- derived radii

    @property
    def mean_radius_um(self) -> float:
        """Number-mean radius ``<r>``. [um]"""
        return self.moment(1.0)

    @property
    def area_mean_radius_um(self) -> float:
        """Radius of the mean cross-section, ``sqrt(<r^2>)``. [um]"""
        return math.sqrt(self.moment(2.0))

    @property
    def volume_mean_radius_um(self) -> float:
        """Radius of the mean volume, ``cbrt(<r^3>)``. [um]"""
        return float(np.cbrt(self.moment(3.0)))

    @property
    def r_eff_um(self) -> float:
        """Effective radius ``<r^3> / <r^2>`` (Hansen & Travis 1974). [um]"""
        return self.moment(3.0) / self.moment(2.0)

    @property
    def v_eff(self) -> float:
        """Effective variance ``<r^4> <r^2> / <r^3>^2 - 1`` (Hansen & Travis 1974). [1]"""
        m3 = self.moment(3.0)
        return self.moment(4.0) * self.moment(2.0) / (m3 * m3) - 1.0

    @property
    def mean_cross_section_um2(self) -> float:
        """Mean geometric cross-section ``pi <r^2>``. [um^2]"""
        return math.pi * self.moment(2.0)

    @property
    def mean_volume_um3(self) -> float:
        """Mean particle volume ``4/3 pi <r^3>``. [um^3]"""
        return 4.0 / 3.0 * math.pi * self.moment(3.0)

    def truncated(self, *, r_min_um: float = 0.0, r_max_um: float = math.inf) -> SizeDistribution:
        """This distribution restricted to [r_min_um, r_max_um] and renormalized to 1.

        As libRadtran's ``mie`` and the IPRT cases integrate over a finite
        radius range.  See :class:`Truncated`.  A monodisperse distribution
        inside the bounds is returned unchanged.

        Parameters
        ----------
        r_min_um, r_max_um : float
            0 <= r_min_um < r_max_um <= inf. [um]

        Raises
        ------
        ValueError
            If the bounds are not ordered or keep no particles.
        """
        if self.is_monodisperse:
            r = self.mean_radius_um
            if not r_min_um <= r <= r_max_um:
                raise ValueError(
                    f"truncation bounds r_min_um={r_min_um!r}, r_max_um={r_max_um!r} remove the whole "
                    f"distribution (all particles at {r!r} um)"
                )
            return self
        return Truncated(parent=self, r_min_um=r_min_um, r_max_um=r_max_um)

    # ------------------------------------------------------------- provenance

    def to_dict(self) -> dict[str, Any]:
        """Plain description for provenance (metadata of tables and files).

        Returns
        -------
        dict
            ``model`` (str), ``citation`` (str), ``parameters`` (dict of the
            constructor's arguments, with the unit in each key: ``_um`` for
            micrometres, none for dimensionless numbers) and ``derived``
            (``r_eff_um`` and ``v_eff`` of the distribution).  A mixture adds
            ``modes``, a list of its modes' dicts.
        """
        return {
            "model": self.model,
            "citation": self.citation,
            "parameters": self._parameters(),
            "derived": {"r_eff_um": self.r_eff_um, "v_eff": self.v_eff},
        }


# ---------------------------------------------------------------------- gamma


class _GammaFamily(SizeDistribution):
    """Gamma distributions, ``n(r) ~ r^(shape - 1) exp(-r / scale)``."""

    __slots__ = ()

    @abstractmethod
    def _shape_scale(self) -> tuple[float, float]:
        """``(shape, scale_um)`` of the gamma distribution."""

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        shape, scale = self._shape_scale()
        r = _as_radius(radius_um)
        # scipy.special rather than scipy.stats: same density, without
        # scipy.stats' import time (~0.4 s) and per-call overhead.
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            y = r / scale
            density = np.exp(special.xlogy(shape - 1.0, y) - y - special.gammaln(shape)) / scale
        return _scalar_or_array(np.where(r > 0.0, density, np.where(np.isnan(r), np.nan, 0.0)))

    def moment(self, k: float) -> float:
        """Moment ``<r^k> = scale^k Gamma(shape + k) / Gamma(shape)`` [um^k].

        Finite for ``k > -shape``; see :meth:`SizeDistribution.moment`.
        """
        k = check_real("k", k)
        shape, scale = self._shape_scale()
        if not shape + k > 0.0:
            raise ValueError(
                f"k must be > -shape = {-shape!r} for the moment of this gamma distribution "
                f"to be finite; got {k!r}"
            )
        return float(scale**k * special.poch(shape, k))

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        shape, scale = self._shape_scale()
        x = np.clip(radius_um, 0.0, None) / scale  # r <= 0: whole moment lies above
        fraction = special.gammaincc(shape + k, x) if upper else special.gammainc(shape + k, x)
        return np.asarray(fraction, dtype=np.float64)

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        shape, scale = self._shape_scale()
        r_lo = scale * special.gammaincinv(shape + lower_moment, tail_fraction)
        r_hi = scale * special.gammainccinv(shape + upper_moment, tail_fraction)
        return float(r_lo), float(r_hi)

    @property
    def r_eff_um(self) -> float:
        """Effective radius, ``scale (shape + 2)`` for a gamma distribution. [um]"""
        shape, scale = self._shape_scale()
        return scale * (shape + 2.0)

    @property
    def v_eff(self) -> float:
        """Effective variance, ``1 / (shape + 2)`` for a gamma distribution. [1]"""
        shape, _ = self._shape_scale()
        return 1.0 / (shape + 2.0)


@dataclass(frozen=True, slots=True, kw_only=True)
class ModifiedGamma(_GammaFamily):
    r"""Modified gamma distribution of Hansen & Travis (1974).

    .. math::

        n(r) \propto r^{(1 - 3b)/b} \exp\left(-\frac{r}{a b}\right),
        \qquad a = r_\mathrm{eff},\; b = v_\mathrm{eff},

    a gamma distribution with ``shape = (1 - 2b)/b`` and ``scale = a b`` [um],
    normalized here to 1.  Its effective radius and effective variance are
    exactly ``a`` and ``b``: ``<r^3>/<r^2> = scale (shape + 2) = a`` and
    ``<r^4><r^2>/<r^3>^2 - 1 = 1/(shape + 2) = b``.

    Parameters
    ----------
    r_eff_um : float
        Effective radius ``a = <r^3>/<r^2>``, > 0. [um]
    v_eff : float
        Effective variance ``b``, in [:data:`MIN_V_EFF`, 0.5) = [1e-4, 0.5);
        at 0.5 the shape reaches 0 and the distribution can no longer be
        normalized. [1]

    Notes
    -----
    The Martian dust model of the seed thesis uses ``r_eff_um=1.6, v_eff=0.2``
    (after Tomasko et al. 1999), i.e. ``Gamma(shape=3, scale_um=0.32)``.
    For ``v_eff > 1/3`` the shape is below 1 and ``n(r)`` diverges
    (integrably) at r -> 0.

    References
    ----------
    .. [1] J. E. Hansen and L. D. Travis, "Light scattering in planetary
       atmospheres," Space Sci. Rev., vol. 16, pp. 527-610, 1974,
       doi:10.1007/BF00168069.

    Examples
    --------
    >>> d = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    >>> round(d.shape, 12), round(d.scale_um, 12)
    (3.0, 0.32)
    """

    model: ClassVar[str] = "modified_gamma"
    citation: ClassVar[str] = HANSEN_TRAVIS_1974
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("r_eff_um"),
        SizeParameter("v_eff", 0.0, 0.5),
    )
    aliases: ClassVar[tuple[str, ...]] = ("hansen_travis1974_gamma",)

    # ``field()`` keeps the base class's r_eff_um/v_eff properties from being
    # taken as default values; the slots then shadow those properties.
    r_eff_um: float = field()
    v_eff: float = field()

    def __post_init__(self) -> None:
        object.__setattr__(self, "r_eff_um", _check_r_eff("r_eff_um", self.r_eff_um))
        object.__setattr__(self, "v_eff", _check_v_eff(self.v_eff, 0.5))

    @property
    def shape(self) -> float:
        """Gamma shape ``(1 - 2 v_eff) / v_eff``. [1]"""
        return (1.0 - 2.0 * self.v_eff) / self.v_eff

    @property
    def scale_um(self) -> float:
        """Gamma scale ``r_eff v_eff``. [um]"""
        return self.r_eff_um * self.v_eff

    def _shape_scale(self) -> tuple[float, float]:
        return self.shape, self.scale_um


@dataclass(frozen=True, slots=True, kw_only=True)
class Gamma(_GammaFamily):
    r"""Gamma distribution by shape and scale.

    .. math::

        n(r) = \frac{r^{\alpha - 1} e^{-r/\theta}}{\Gamma(\alpha)\, \theta^\alpha},
        \qquad \alpha = \mathrm{shape},\; \theta = \mathrm{scale}

    with ``r_eff = theta (alpha + 2)`` and ``v_eff = 1 / (alpha + 2)``
    (Hansen & Travis 1974); :class:`ModifiedGamma` is the same family by those.

    Parameters
    ----------
    shape : float
        Shape ``alpha`` > 0. [1]
    scale_um : float
        Scale ``theta`` > 0. [um]

    References
    ----------
    .. [1] J. E. Hansen and L. D. Travis, "Light scattering in planetary
       atmospheres," Space Sci. Rev., vol. 16, pp. 527-610, 1974,
       doi:10.1007/BF00168069.
    """

    model: ClassVar[str] = "gamma"
    citation: ClassVar[str] = HANSEN_TRAVIS_1974
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("shape"),
        SizeParameter("scale_um"),
    )

    shape: float
    scale_um: float

    def __post_init__(self) -> None:
        shape = check_positive("shape", self.shape)
        if shape > 1.0 / MIN_V_EFF - 2.0:
            raise ValueError(
                f"shape must be <= {1.0 / MIN_V_EFF - 2.0:g} (v_eff >= {MIN_V_EFF:g}; narrower "
                f"populations: use Monodisperse); got {self.shape!r}"
            )
        object.__setattr__(self, "shape", shape)
        object.__setattr__(self, "scale_um", _check_radius("scale_um", self.scale_um))
        _check_r_eff("r_eff_um (scale_um (shape + 2))", self.r_eff_um)

    def _shape_scale(self) -> tuple[float, float]:
        return self.shape, self.scale_um


# ------------------------------------------------------------------ log-normal


class _LogNormalFamily(SizeDistribution):
    """Log-normal distributions, ``ln r ~ Normal(mu, sigma)``."""

    __slots__ = ()

    @abstractmethod
    def _mu_sigma(self) -> tuple[float, float]:
        """``(mu, sigma)``: mean and standard deviation of ``ln(r / 1 um)``."""

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        mu, sigma = self._mu_sigma()
        r = _as_radius(radius_um)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = (np.log(np.where(r > 0.0, r, np.nan)) - mu) / sigma
            density = np.exp(-0.5 * z * z) / (r * sigma * math.sqrt(2.0 * math.pi))
        return _scalar_or_array(np.where(r > 0.0, density, np.where(np.isnan(r), np.nan, 0.0)))

    def moment(self, k: float) -> float:
        """Moment ``<r^k> = exp(k mu + k^2 sigma^2 / 2)`` [um^k], finite for every real k."""
        k = check_real("k", k)
        mu, sigma = self._mu_sigma()
        return math.exp(k * mu + 0.5 * k * k * sigma * sigma)

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        mu, sigma = self._mu_sigma()
        with np.errstate(divide="ignore", invalid="ignore"):
            log_r = np.where(radius_um > 0.0, np.log(radius_um), -np.inf)
        log_r = np.where(np.isnan(radius_um), np.nan, log_r)
        z = (log_r - mu - k * sigma * sigma) / sigma
        fraction = special.ndtr(-z) if upper else special.ndtr(z)
        return np.asarray(fraction, dtype=np.float64)

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        mu, sigma = self._mu_sigma()
        z = float(-special.ndtri(tail_fraction))
        r_lo = math.exp(mu + lower_moment * sigma * sigma - z * sigma)
        r_hi = math.exp(mu + upper_moment * sigma * sigma + z * sigma)
        return r_lo, r_hi

    @property
    def r_eff_um(self) -> float:
        """Effective radius, ``exp(mu + 5 sigma^2 / 2)`` for a log-normal. [um]"""
        mu, sigma = self._mu_sigma()
        return math.exp(mu + 2.5 * sigma * sigma)

    @property
    def v_eff(self) -> float:
        """Effective variance, ``exp(sigma^2) - 1`` for a log-normal. [1]"""
        _, sigma = self._mu_sigma()
        return math.expm1(sigma * sigma)


@dataclass(frozen=True, slots=True, kw_only=True)
class LogNormal(_LogNormalFamily):
    r"""Log-normal distribution by median radius and logarithmic width.

    .. math::

        n(r) = \frac{1}{\sqrt{2\pi}\, \sigma r}
               \exp\left(-\frac{(\ln r - \mu)^2}{2 \sigma^2}\right),
        \qquad \mu = \ln r_\mathrm{med}

    so ``ln r`` is normally distributed with mean ``mu`` and standard
    deviation ``sigma``; ``<r^k> = exp(k mu + k^2 sigma^2 / 2)``.

    Parameters
    ----------
    median_radius_um : float
        Median radius ``r_med = exp(mu)`` of the number distribution, in
        :data:`RADIUS_RANGE_UM`. [um]
    sigma : float
        Standard deviation of ``ln r``, in [0.01, :data:`MAX_SIGMA`] (v_eff
        from :data:`MIN_V_EFF` to 8.1e3).  It is the natural logarithm of
        the geometric standard deviation: ``sigma = ln(sigma_g)``, so a
        geometric standard deviation of 1.5 is ``sigma = 0.405``. [1]

    Notes
    -----
    CosmoScout VR's plain ``logNormal`` size mode takes the same ``mu``
    (which it calls the mean, of ``ln r``) and ``sigma``.

    References
    ----------
    .. [1] J. E. Hansen and L. D. Travis, "Light scattering in planetary
       atmospheres," Space Sci. Rev., vol. 16, pp. 527-610, 1974,
       doi:10.1007/BF00168069.
    """

    model: ClassVar[str] = "log_normal"
    citation: ClassVar[str] = HANSEN_TRAVIS_1974
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("median_radius_um"),
        SizeParameter("sigma"),
    )

    median_radius_um: float
    sigma: float

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "median_radius_um",
            _check_radius("median_radius_um", self.median_radius_um),
        )
        sigma = check_real("sigma", self.sigma)
        low = math.sqrt(math.log1p(MIN_V_EFF))
        if not low <= sigma <= MAX_SIGMA:
            raise ValueError(
                f"sigma must be in [{low:.6g}, {MAX_SIGMA:g}] (v_eff from {MIN_V_EFF:g} to "
                f"{math.expm1(MAX_SIGMA**2):.3g}); got {self.sigma!r}"
            )
        object.__setattr__(self, "sigma", sigma)
        _check_r_eff("r_eff_um (median exp(5 sigma^2 / 2))", self.r_eff_um)

    @property
    def geometric_std(self) -> float:
        """Geometric standard deviation ``exp(sigma)``. [1]"""
        return math.exp(self.sigma)

    def _mu_sigma(self) -> tuple[float, float]:
        return math.log(self.median_radius_um), self.sigma


@dataclass(frozen=True, slots=True, kw_only=True)
class ModifiedLogNormal(_LogNormalFamily):
    r"""Log-normal distribution by effective radius and effective variance.

    CosmoScout VR's ``modifiedLogNormal`` size mode: a :class:`LogNormal` with

    .. math::

        s^2 = \ln(1 + v_\mathrm{eff}), \qquad
        \mu = \ln r_\mathrm{eff} - \tfrac{5}{2} s^2, \qquad
        \sigma = s,

    i.e. ``median_radius_um = exp(mu)``.  Its effective radius and variance are
    exactly the given ones: with ``<r^k> = exp(k mu + k^2 s^2 / 2)``,

    - ``<r^3>/<r^2> = exp(mu + (9 - 4) s^2 / 2) = exp(mu + 5 s^2 / 2) = r_eff``,
    - ``<r^4><r^2>/<r^3>^2 = exp((16 + 4 - 18) s^2 / 2) = exp(s^2) = 1 + v_eff``.

    Parameters
    ----------
    r_eff_um : float
        Effective radius ``<r^3>/<r^2>``, > 0. [um]
    v_eff : float
        Effective variance, in [:data:`MIN_V_EFF`, e^9 - 1 = 8.1e3] (sigma <=
        :data:`MAX_SIGMA`); large values put the median far below ``r_eff``,
        since ``median = r_eff (1 + v_eff)^(-5/2)``. [1]

    Notes
    -----
    CosmoScout's Mars aerosol settings use two such modes,
    ``(r_eff_um=0.04, v_eff=0.1)`` and ``(r_eff_um=1.4, v_eff=0.35)``, with
    relative number densities 1000 : 1 (see
    :class:`~dustoptics.particles.custom_sizedist.MultiModal`).

    References
    ----------
    .. [1] German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres,
       scattering-table-generator, https://github.com/cosmoscout/cosmoscout-vr.
    .. [2] J. E. Hansen and L. D. Travis, "Light scattering in planetary
       atmospheres," Space Sci. Rev., vol. 16, pp. 527-610, 1974,
       doi:10.1007/BF00168069 (definition of r_eff and v_eff).
    """

    model: ClassVar[str] = "modified_log_normal"
    citation: ClassVar[str] = COSMOSCOUT_VR
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("r_eff_um"),
        SizeParameter("v_eff"),
    )

    # ``field()`` keeps the base class's r_eff_um/v_eff properties from being
    # taken as default values; the slots then shadow those properties.
    r_eff_um: float = field()
    v_eff: float = field()

    def __post_init__(self) -> None:
        object.__setattr__(self, "r_eff_um", _check_r_eff("r_eff_um", self.r_eff_um))
        object.__setattr__(
            self, "v_eff", _check_v_eff(self.v_eff, math.expm1(MAX_SIGMA**2) * (1 + 1e-12))
        )
        _check_radius("median_radius_um (r_eff (1 + v_eff)^(-5/2))", self.median_radius_um)

    @property
    def sigma(self) -> float:
        """Standard deviation of ``ln r``, ``sqrt(ln(1 + v_eff))``. [1]"""
        return math.sqrt(math.log1p(self.v_eff))

    @property
    def median_radius_um(self) -> float:
        """Median radius ``exp(mu) = r_eff (1 + v_eff)^(-5/2)``. [um]"""
        return math.exp(self._mu_sigma()[0])

    def as_log_normal(self) -> LogNormal:
        """The same distribution as a :class:`LogNormal`."""
        return LogNormal(median_radius_um=self.median_radius_um, sigma=self.sigma)

    def _mu_sigma(self) -> tuple[float, float]:
        s2 = math.log1p(self.v_eff)
        return math.log(self.r_eff_um) - 2.5 * s2, math.sqrt(s2)


# --------------------------------------------------------------- monodisperse


@dataclass(frozen=True, slots=True, kw_only=True)
class Monodisperse(SizeDistribution):
    """All particles of one radius: ``n(r) = delta(r - radius_um)``.

    It has no density, so :meth:`pdf` raises; a quadrature should test
    :attr:`is_monodisperse` (or :attr:`has_density`) and use the single node
    ``radius_um`` with weight 1.  Moments are ``radius_um^k``, ``r_eff_um`` is
    ``radius_um`` and ``v_eff`` is 0.

    Parameters
    ----------
    radius_um : float
        Radius of every particle, in :data:`RADIUS_RANGE_UM` (1e-6 to 1e6). [um]
    """

    model: ClassVar[str] = "monodisperse"
    parameters: ClassVar[tuple[SizeParameter, ...]] = (SizeParameter("radius_um"),)
    citation: ClassVar[str] = "single particle radius (no size distribution)"

    radius_um: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius_um", _check_radius("radius_um", self.radius_um))
        if self.radius_um < MIN_R_EFF_UM:
            warnings.warn(
                f"radius_um = {self.radius_um!r} um is below {MIN_R_EFF_UM:g} um (1 nm, the size "
                f"of a molecule): was it in metres? ({self.radius_um:g} m = "
                f"{self.radius_um * 1e6:g} um); taken as micrometres",
                UserWarning,
                stacklevel=3,
            )

    @property
    def has_density(self) -> bool:
        """False: the distribution is a point mass."""
        return False

    @property
    def is_monodisperse(self) -> bool:
        """True."""
        return True

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        """Not defined: a single radius has no probability density.

        Raises
        ------
        TypeError
            Always.  Use :attr:`radius_um` as the only quadrature node.
        """
        raise TypeError(
            f"Monodisperse(radius_um={self.radius_um!r}) has no probability density; "
            "use its radius_um as the single quadrature node with weight 1"
        )

    def moment(self, k: float) -> float:
        """Moment ``radius_um^k`` [um^k]."""
        return float(self.radius_um ** check_real("k", k))

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        above = np.where(self.radius_um > radius_um, 1.0, 0.0)
        fraction = above if upper else 1.0 - above
        return np.where(np.isnan(radius_um), np.nan, fraction)

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        return self.radius_um, self.radius_um

    @property
    def r_eff_um(self) -> float:
        """Effective radius, ``radius_um``. [um]"""
        return self.radius_um

    @property
    def v_eff(self) -> float:
        """Effective variance, 0. [1]"""
        return 0.0


# ----------------------------------------- more families from the literature

DEIRMENDJIAN_1969 = (
    "D. Deirmendjian, Electromagnetic Scattering on Spherical Polydispersions, "
    "Elsevier, New York, 1969 (modified gamma distribution, Eq. 2.22)"
)
JUNGE_1963 = "C. E. Junge, Air Chemistry and Radioactivity, Academic Press, New York, 1963"


def _numeric_bounds(
    dist: SizeDistribution,
    tail_fraction: float,
    lower_moment: float,
    upper_moment: float,
    support: tuple[float, float],
) -> tuple[float, float]:
    """Quantile radii from a distribution's own tail fractions by bisection
    in ln r (Brent's method) within its finite ``support``: F_lower^<(r_lo)
    = eps and F_upper^>(r_hi) = eps, or the support's ends when their tails
    are already below eps."""

    # here: scipy.optimize (with scipy.linalg, sparse) is 0.2 s of a warm `dustoptics
    # build`'s CPU, and the modified gamma and log-normal families never come here
    from scipy.optimize import brentq

    lo, hi = support

    def below(ln_r: float) -> float:
        return float(dist._tail(lower_moment, np.array(math.exp(ln_r)), False)) - tail_fraction

    def above(ln_r: float) -> float:
        return float(dist._tail(upper_moment, np.array(math.exp(ln_r)), True)) - tail_fraction

    a, b = math.log(lo), math.log(hi)
    r_lo = (
        math.exp(brentq(below, a, b, xtol=1e-14, rtol=1e-13)) if below(a) < 0.0 < below(b) else lo
    )
    r_hi = (
        math.exp(brentq(above, a, b, xtol=1e-14, rtol=1e-13)) if above(a) > 0.0 > above(b) else hi
    )
    return r_lo, max(r_lo, r_hi)


@dataclass(frozen=True, slots=True, kw_only=True)
class DeirmendjianGamma(SizeDistribution):
    r"""Deirmendjian's (1969) modified gamma distribution.

    .. math::

        n(r) = a\, r^\alpha \exp(-b\, r^\gamma),

    normalized here to 1 (the constant ``a`` follows from the others).  With
    t = b r^gamma it is a generalized gamma distribution:
    <r^k> = b^(-k/gamma) Gamma((alpha + 1 + k)/gamma) / Gamma((alpha + 1)/gamma),
    and the tail fractions are regularized incomplete gamma functions of
    shape (alpha + 1 + k)/gamma at b r^gamma.  Its mode radius is
    r_c = (alpha / (b gamma))^(1/gamma).

    Parameters
    ----------
    alpha : float
        Power of r, > -1. [1]
    b : float
        Rate, > 0, in [um^-gamma] (Deirmendjian's radii are in um). [um^-gamma]
    gamma : float
        Power of r in the exponent, > 0. [1]

    Examples
    --------
    Deirmendjian's haze L (alpha = 2, b = 15.1186, gamma = 1/2; his mode radius
    0.07 um) and cloud C.1 (alpha = 6, b = 3/2, gamma = 1; mode radius 4 um):

    >>> haze_l = DeirmendjianGamma(alpha=2.0, b=15.1186, gamma=0.5)
    >>> round(haze_l.mode_radius_um, 4)
    0.07
    >>> round(DeirmendjianGamma(alpha=6.0, b=1.5, gamma=1.0).mode_radius_um, 12)
    4.0

    References
    ----------
    .. [1] D. Deirmendjian, *Electromagnetic Scattering on Spherical
       Polydispersions*, Elsevier, New York, 1969.
    """

    model: ClassVar[str] = "deirmendjian_gamma"
    citation: ClassVar[str] = DEIRMENDJIAN_1969
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("alpha", -1.0),
        SizeParameter("b"),
        SizeParameter("gamma"),
    )
    aliases: ClassVar[tuple[str, ...]] = ("deirmendjian1969_modified_gamma",)

    alpha: float
    b: float
    gamma: float

    def __post_init__(self) -> None:
        alpha = check_real("alpha", self.alpha)
        if not alpha > -1.0:
            raise ValueError(
                f"alpha must be > -1 for n(r) = a r^alpha exp(-b r^gamma) to be normalizable; got {alpha!r}"
            )
        object.__setattr__(self, "alpha", alpha)
        object.__setattr__(self, "b", check_positive("b", self.b, unit="um^-gamma"))
        object.__setattr__(self, "gamma", check_positive("gamma", self.gamma))

    @property
    def mode_radius_um(self) -> float:
        """Mode radius (alpha / (b gamma))^(1/gamma) (0 for alpha <= 0). [um]"""
        if self.alpha <= 0.0:
            return 0.0
        return float((self.alpha / (self.b * self.gamma)) ** (1.0 / self.gamma))

    def _shape(self, k: float) -> float:
        return (self.alpha + 1.0 + k) / self.gamma

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        r = _as_radius(radius_um)
        s = self._shape(0.0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            log_n = (
                math.log(self.gamma)
                + s * math.log(self.b)
                - special.gammaln(s)
                + special.xlogy(self.alpha, r)
                - self.b * np.abs(r) ** self.gamma
            )
            density = np.exp(log_n)
        return _scalar_or_array(np.where(r > 0.0, density, np.where(np.isnan(r), np.nan, 0.0)))

    def moment(self, k: float) -> float:
        """Moment b^(-k/gamma) Gamma((alpha+1+k)/gamma) / Gamma((alpha+1)/gamma) [um^k]."""
        k = check_real("k", k)
        if not self._shape(k) > 0.0:
            raise ValueError(
                f"k must be > -(alpha + 1) = {-(self.alpha + 1.0)!r} for a finite moment; got {k!r}"
            )
        log_m = (
            special.gammaln(self._shape(k))
            - special.gammaln(self._shape(0.0))
            - k / self.gamma * math.log(self.b)
        )
        return float(math.exp(log_m))

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        t = self.b * np.clip(radius_um, 0.0, None) ** self.gamma
        s = self._shape(k)
        return np.asarray(
            special.gammaincc(s, t) if upper else special.gammainc(s, t), dtype=np.float64
        )

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        t_lo = special.gammaincinv(self._shape(lower_moment), tail_fraction)
        t_hi = special.gammainccinv(self._shape(upper_moment), tail_fraction)
        return float((t_lo / self.b) ** (1.0 / self.gamma)), float(
            (t_hi / self.b) ** (1.0 / self.gamma)
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class PowerLaw(SizeDistribution):
    r"""Power-law (Junge) distribution between two radii.

    .. math::

        n(r) \propto r^{-\nu}, \qquad r_\mathrm{min} \le r \le r_\mathrm{max},

    0 outside, normalized to 1; moments and tail fractions are closed forms
    (with p = k - nu + 1: (r^p - r_min^p) / p, or ln(r / r_min) at p = 0).

    Parameters
    ----------
    exponent : float
        nu (any real; Junge's continental aerosol has nu ~ 4). [1]
    r_min_um, r_max_um : float
        Radii bounding the distribution, 0 < r_min_um < r_max_um. [um]

    References
    ----------
    .. [1] C. E. Junge, *Air Chemistry and Radioactivity*, Academic Press, 1963.
    """

    model: ClassVar[str] = "power_law"
    citation: ClassVar[str] = JUNGE_1963
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("exponent", -math.inf),
        SizeParameter("r_min_um"),
        SizeParameter("r_max_um"),
    )
    aliases: ClassVar[tuple[str, ...]] = ("junge1963",)

    exponent: float
    r_min_um: float
    r_max_um: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "exponent", check_real("exponent", self.exponent))
        lo, hi = _check_radius_range(self.r_min_um, self.r_max_um)
        object.__setattr__(self, "r_min_um", lo)
        object.__setattr__(self, "r_max_um", hi)

    def _integral(self, k: float, r: NDArray[np.float64]) -> NDArray[np.float64]:
        """int_{r_min}^{r} r'^(k - nu) dr' for r in [r_min, r_max]."""
        p = k - self.exponent + 1.0
        r = np.clip(r, self.r_min_um, self.r_max_um)
        if abs(p) < 1e-12:
            return np.log(r / self.r_min_um)
        return (r**p - self.r_min_um**p) / p

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        r = _as_radius(radius_um)
        norm = float(self._integral(0.0, np.array(self.r_max_um)))
        inside = (r >= self.r_min_um) & (r <= self.r_max_um)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            density = np.where(inside, np.abs(r) ** -self.exponent / norm, 0.0)
        return _scalar_or_array(np.where(np.isnan(r), np.nan, density))

    def moment(self, k: float) -> float:
        """Moment ``int r^(k - nu) dr / int r^(-nu) dr`` over [r_min, r_max] [um^k]."""
        k = check_real("k", k)
        top = np.array(self.r_max_um)
        return float(self._integral(k, top) / self._integral(0.0, top))

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        below = self._integral(k, radius_um) / self._integral(k, np.array(self.r_max_um))
        below = np.where(np.isnan(radius_um), np.nan, below)
        return np.asarray(1.0 - below if upper else below, dtype=np.float64)

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        return _numeric_bounds(
            self, tail_fraction, lower_moment, upper_moment, (self.r_min_um, self.r_max_um)
        )


# ----------------------------------------------------------------- truncation


@dataclass(frozen=True, slots=True, kw_only=True)
class Truncated(SizeDistribution):
    """Any distribution restricted to [r_min, r_max] and renormalized.

    n_T(r) = n(r) / (F_0(r_max) - F_0(r_min)) inside, 0 outside, with F_k the
    parent's cumulative k-moment fractions; moments and tail fractions follow
    from the parent's exactly: <r^k>_T = <r^k> (F_k(r_max) - F_k(r_min)) /
    (F_0(r_max) - F_0(r_min)).  Made by :meth:`SizeDistribution.truncated`.

    Parameters
    ----------
    parent : SizeDistribution
        The distribution to truncate (with a density).
    r_min_um, r_max_um : float
        0 <= r_min_um < r_max_um <= inf (None: inf; provenance records inf as
        None, since JSON has no infinity). [um]
    """

    model: ClassVar[str] = "truncated"
    citation: ClassVar[str] = (
        "truncation of the parent distribution to [r_min, r_max], renormalized"
    )

    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("parent", kind="distribution"),
        SizeParameter("r_min_um", -math.inf),
        SizeParameter("r_max_um"),
    )

    parent: SizeDistribution
    r_min_um: float
    r_max_um: float

    def __post_init__(self) -> None:
        if not isinstance(self.parent, SizeDistribution) or not self.parent.has_density:
            raise ValueError(
                f"parent must be a SizeDistribution with a density; got {self.parent!r}"
            )
        lo = check_real("r_min_um", self.r_min_um)
        if self.r_max_um is None:
            object.__setattr__(self, "r_max_um", math.inf)
        hi = (
            float(self.r_max_um)
            if self.r_max_um == math.inf
            else check_real("r_max_um", self.r_max_um)
        )
        if lo < 0.0 or not hi > lo:
            raise ValueError(
                f"truncation bounds must satisfy 0 <= r_min_um < r_max_um; got r_min_um={self.r_min_um!r}, "
                f"r_max_um={self.r_max_um!r}"
            )
        object.__setattr__(self, "r_min_um", lo)
        object.__setattr__(self, "r_max_um", hi)
        if not self._inside(0.0) > 0.0:
            raise ValueError(
                f"truncation bounds r_min_um={lo!r}, r_max_um={hi!r} remove the whole distribution "
                f"{self.parent!r} (no particles between them); allowed: bounds that keep some of it"
            )

    def _cumulative(self, k: float, r: NDArray[np.float64]) -> NDArray[np.float64]:
        finite = np.where(np.isinf(r), 1.0, r)
        below = np.asarray(self.parent._tail(k, finite, False), dtype=np.float64)
        return np.where(np.isinf(r), 1.0, np.where(r <= 0.0, 0.0, below))

    def _inside(self, k: float) -> float:
        lo = self._cumulative(k, np.array(self.r_min_um))
        hi = self._cumulative(k, np.array(self.r_max_um))
        return float(hi - lo)

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        r = _as_radius(radius_um)
        inside = (r >= self.r_min_um) & (r <= self.r_max_um)
        values = np.asarray(self.parent.pdf(r), dtype=np.float64) / self._inside(0.0)
        return _scalar_or_array(np.where(np.isnan(r), np.nan, np.where(inside, values, 0.0)))

    def moment(self, k: float) -> float:
        """Moment of the truncated distribution from the parent's [um^k]."""
        k = check_real("k", k)
        return self.parent.moment(k) * self._inside(k) / self._inside(0.0)

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        r = np.clip(radius_um, self.r_min_um, self.r_max_um)
        lo = self._cumulative(k, np.array(self.r_min_um))
        below = (self._cumulative(k, r) - lo) / self._inside(k)
        below = np.where(np.isnan(radius_um), np.nan, np.clip(below, 0.0, 1.0))
        return np.asarray(1.0 - below if upper else below, dtype=np.float64)

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        p_lo, p_hi = self.parent._bounds(tail_fraction * 1e-3, lower_moment, upper_moment)
        lo = max(self.r_min_um, p_lo) if self.r_min_um > 0.0 else min(p_lo, self.r_max_um * 1e-3)
        hi = min(self.r_max_um, p_hi) if math.isfinite(self.r_max_um) else max(p_hi, lo * 10.0)
        if not hi > lo:
            lo, hi = (
                (self.r_min_um if self.r_min_um > 0.0 else hi * 1e-3),
                min(self.r_max_um, max(p_hi, hi)),
            )
        return _numeric_bounds(self, tail_fraction, lower_moment, upper_moment, (lo, hi))

    def _parameters(self) -> dict[str, Any]:
        return {
            "r_min_um": self.r_min_um,
            # JSON has no infinity: no upper bound is recorded as null (read back as inf).
            "r_max_um": self.r_max_um if math.isfinite(self.r_max_um) else None,
            "parent": self.parent.to_dict(),
        }
