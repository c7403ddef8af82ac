"""Size distributions put together by the user: a mixture of modes, a table, a function.

:mod:`dustoptics.particles.sizedist` holds the analytic families of the literature, each a
formula with a few parameters; here are the distributions a user assembles from other things.
Each is a :class:`~dustoptics.particles.sizedist.SizeDistribution`, so the quadrature
integrates them like any other.

- :class:`MultiModal`: a mixture of any distributions, weighted by relative number density
  (how CosmoScout VR combines its size modes).
- :class:`TabulatedDistribution`: a measured table, n(r) linear between its radii; moments
  and tail fractions exact for that piecewise-linear n(r).
- :class:`DensityDistribution`: any density function on a finite radius range, integrated
  numerically.
- :func:`from_dict`: the distribution a provenance record describes, for every model of
  both modules (it lives here because it must know them all).

A distribution cut to a radius range (:class:`~dustoptics.particles.sizedist.Truncated`) is
made by the interface's own :meth:`~dustoptics.particles.sizedist.SizeDistribution.truncated`
and so lives beside it.

References
----------
.. [1] German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres,
   scattering-table-generator (mie mode, size mode ``relativeNumberDensity``),
   https://github.com/cosmoscout/cosmoscout-vr.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dustoptics._files import FormatError, read_checked
from dustoptics._validation import as_float_array, check_real
from dustoptics.particles.sizedist import (
    COSMOSCOUT_VR,
    SIZE_DISTRIBUTIONS,
    FloatOrArray,
    SizeDistribution,
    SizeParameter,
    _as_radius,
    _check_radius_range,
    _numeric_bounds,
    _scalar_or_array,
)

__all__ = [
    "DensityDistribution",
    "MultiModal",
    "TabulatedDistribution",
    "from_dict",
]


# ------------------------------------------------------------------- mixtures


@dataclass(frozen=True, slots=True, kw_only=True)
class MultiModal(SizeDistribution):
    """Mixture of size modes weighted by relative number density.

    .. math::

        n(r) = \\sum_i w_i n_i(r), \\qquad w_i = d_i / \\sum_j d_j

    with ``d_i`` the relative number densities and ``n_i`` the modes, each
    normalized to 1.  Moments are the weighted sums ``<r^k> = sum_i w_i
    <r^k>_i``.  This is how CosmoScout VR combines its size modes (scattering
    cross-sections weighted by relative number density).

    Parameters
    ----------
    modes : sequence of SizeDistribution
        The modes, at least one (mixtures may be nested).
    relative_number_densities : sequence of float
        One positive, finite number per mode; only ratios matter (they are
        normalized to the :attr:`number_fractions`). [1]

    Examples
    --------
    CosmoScout VR's Mars aerosols: a fine and a coarse mode, 1000 : 1 in number.

    >>> from dustoptics.particles.sizedist import ModifiedLogNormal
    >>> mars = MultiModal(
    ...     modes=(ModifiedLogNormal(r_eff_um=0.04, v_eff=0.1),
    ...            ModifiedLogNormal(r_eff_um=1.4, v_eff=0.35)),
    ...     relative_number_densities=(1000.0, 1.0),
    ... )
    >>> round(mars.number_fractions[0], 6)
    0.999001

    References
    ----------
    .. [1] German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres,
       scattering-table-generator, https://github.com/cosmoscout/cosmoscout-vr.
    """

    model: ClassVar[str] = "multimodal"
    citation: ClassVar[str] = COSMOSCOUT_VR
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("modes", kind="distributions"),
        SizeParameter("relative_number_densities", kind="numbers"),
    )

    modes: Sequence[SizeDistribution]  # stored as a tuple
    relative_number_densities: Sequence[float]  # stored as a tuple of float
    _weights: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if isinstance(self.modes, SizeDistribution):
            raise TypeError(
                f"modes must be a sequence of SizeDistribution; got the single {self.modes!r} "
                "(wrap it in a tuple)"
            )
        if isinstance(self.modes, (str, bytes, Mapping)) or not isinstance(
            self.modes, (Sequence, np.ndarray)
        ):
            raise TypeError(
                f"modes must be a sequence of SizeDistribution (a tuple or list); got {self.modes!r}"
            )
        modes = tuple(self.modes)
        if not modes:
            raise ValueError("modes must contain at least one SizeDistribution; got none")
        for i, mode in enumerate(modes):
            if not isinstance(mode, SizeDistribution):
                raise TypeError(f"modes[{i}] must be a SizeDistribution; got {mode!r}")
        densities = as_float_array(
            "relative_number_densities", np.atleast_1d(self.relative_number_densities), ndim=1
        )
        if densities.size != len(modes):
            raise ValueError(
                f"relative_number_densities must have one entry per mode ({len(modes)} modes); "
                f"got {densities.size}: {densities.tolist()!r}"
            )
        if not np.all(densities > 0.0):
            raise ValueError(
                f"relative_number_densities must all be > 0; got {densities.tolist()!r}"
            )
        object.__setattr__(self, "modes", modes)
        object.__setattr__(self, "relative_number_densities", tuple(densities.tolist()))
        # Scaled by the largest first, so that densities near the float range's
        # end (1e308) sum without overflow.
        scaled = densities / densities.max()
        object.__setattr__(self, "_weights", tuple((scaled / math.fsum(scaled)).tolist()))

    @property
    def number_fractions(self) -> tuple[float, ...]:
        """Fraction of the particles in each mode, summing to 1. [1]"""
        return self._weights

    @property
    def has_density(self) -> bool:
        """Whether every mode has a density."""
        return all(mode.has_density for mode in self.modes)

    @property
    def is_monodisperse(self) -> bool:
        """Whether every mode is monodisperse at one and the same radius."""
        return (
            all(m.is_monodisperse for m in self.modes)
            and len({m.r_eff_um for m in self.modes}) == 1
        )

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        """Number density ``sum_i w_i n_i(r)`` [um^-1].

        Raises
        ------
        TypeError
            If a mode has no density (a :class:`Monodisperse` mode); integrate
            such a mixture mode by mode.
        """
        r = _as_radius(radius_um)
        total = np.zeros_like(r)
        for weight, mode in zip(self._weights, self.modes, strict=True):
            total = total + weight * np.asarray(mode.pdf(r))
        return _scalar_or_array(total)

    def moment(self, k: float) -> float:
        """Moment ``sum_i w_i <r^k>_i`` [um^k]; finite when every mode's is."""
        k = check_real("k", k)
        return math.fsum(
            w * mode.moment(k) for w, mode in zip(self._weights, self.modes, strict=True)
        )

    def _moment_shares(self, k: float) -> NDArray[np.float64]:
        """Each mode's share of the mixture's k-th moment, summing to 1."""
        contributions = np.array(
            [w * m.moment(k) for w, m in zip(self._weights, self.modes, strict=True)],
            dtype=np.float64,
        )
        shares: NDArray[np.float64] = contributions / math.fsum(contributions)
        return shares

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        shares = self._moment_shares(k)
        total = np.zeros_like(radius_um)
        for share, mode in zip(shares, self.modes, strict=True):
            total = total + share * mode._tail(k, radius_um, upper)
        return total

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        bounds = [m._bounds(tail_fraction, lower_moment, upper_moment) for m in self.modes]
        return min(lo for lo, _ in bounds), max(hi for _, hi in bounds)

    def _parameters(self) -> dict[str, Any]:
        return {
            "relative_number_densities": list(self.relative_number_densities),
            "number_fractions": list(self.number_fractions),
        }

    def to_dict(self) -> dict[str, Any]:
        """Plain description for provenance; see :meth:`SizeDistribution.to_dict`."""
        out = super(MultiModal, self).to_dict()
        out["modes"] = [mode.to_dict() for mode in self.modes]
        return out


# ------------------------------------------- tables and density functions


def _power_integrals(
    p: float, a: NDArray[np.float64], b: NDArray[np.float64]
) -> NDArray[np.float64]:
    """int_a^b r^p dr for arrays 0 < a <= b."""
    if abs(p + 1.0) < 1e-12:
        return np.asarray(np.log(b / a))
    return np.asarray((b ** (p + 1.0) - a ** (p + 1.0)) / (p + 1.0))


def _tail_point_by_point(
    below: Callable[[float], float], radius_um: NDArray[np.float64], upper: bool
) -> NDArray[np.float64]:
    """Tail fractions from ``below(r)``, a moment's fraction below one radius (NaN stays NaN)."""
    flat = np.atleast_1d(radius_um).astype(np.float64).ravel()
    fraction = np.array([np.nan if np.isnan(v) else below(float(v)) for v in flat])
    fraction = np.clip(fraction, 0.0, 1.0).reshape(np.shape(radius_um))
    return np.asarray(1.0 - fraction if upper else fraction, dtype=np.float64)


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class TabulatedDistribution(SizeDistribution):
    """A measured distribution: n(r) linear between tabulated radii, 0 outside.

    Give the radii and either ``dn_dr`` (number per unit radius, n(r)) or
    ``dn_dlnr`` (number per unit ln r, r n(r); converted at the points,
    n_i = (dN/dlnr)_i / r_i).  Only the shape matters: the table is
    normalized to 1.  Moments and tail fractions are exact for the piecewise
    linear n(r) (sums of int r^k (c0 + c1 r) dr over the segments), so the
    radius quadrature integrates exactly this n(r); nothing is extrapolated
    beyond the first and last radius.  Compared by identity.

    Parameters
    ----------
    radius_um : array_like
        Strictly increasing radii, > 0, at least two. [um]
    dn_dr : array_like, optional
        n(r) at the radii, finite and >= 0, not all 0. [um^-1, any scale]
    dn_dlnr : array_like, optional
        dN/dln r at the radii instead (exactly one of the two). [any scale]
    """

    model: ClassVar[str] = "tabulated"
    parameters: ClassVar[tuple[SizeParameter, ...]] = (
        SizeParameter("radius_um", kind="numbers"),
        SizeParameter("dn_dr", kind="numbers", required=False),
        SizeParameter("dn_dlnr", kind="numbers", required=False),
    )
    citation: ClassVar[str] = "measured or user-supplied table (piecewise linear n(r))"

    radius_um: np.ndarray
    dn_dr: np.ndarray | None = None
    dn_dlnr: np.ndarray | None = None
    _norm: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        r = as_float_array("radius_um", self.radius_um, ndim=1)
        if (self.dn_dr is None) == (self.dn_dlnr is None):
            raise ValueError("give exactly one of dn_dr and dn_dlnr (values at radius_um)")
        key = "dn_dr" if self.dn_dr is not None else "dn_dlnr"
        v = as_float_array(key, getattr(self, key), ndim=1)
        if r.size < 2 or v.shape != r.shape:
            raise ValueError(
                f"radius_um and {key} must be 1-D arrays of the same length >= 2; got {r.size} and {v.size}"
            )
        if not np.all(np.isfinite(r)) or np.any(r <= 0.0):
            i = int(np.argmax(~np.isfinite(r) | (r <= 0.0)))
            raise ValueError(
                f"radius_um must be finite and > 0 um; got {float(r[i])!r} at index {i}"
            )
        if np.any(np.diff(r) <= 0.0):
            i = int(np.argmax(np.diff(r) <= 0.0))
            raise ValueError(
                "radius_um must be strictly increasing (sorted, no duplicates); "
                f"got {float(r[i])!r} then {float(r[i + 1])!r} at indices {i}, {i + 1}"
            )
        if not np.all(np.isfinite(v)) or np.any(v < 0.0):
            i = int(np.argmax(~np.isfinite(v) | (v < 0.0)))
            raise ValueError(
                f"{key} must be finite and >= 0; got {float(v[i])!r} at index {i} (radius {float(r[i])!r} um)"
            )
        if not np.any(v > 0.0):
            raise ValueError(f"{key} must not be 0 everywhere: the table holds no particles")
        for name, arr in (("radius_um", r), (key, v)):
            arr = arr.copy()
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "_norm", 1.0)
        object.__setattr__(self, "_norm", self._raw_moment(0.0, float(r[-1])))
        object.__setattr__(self, "dn_dr" if key == "dn_dr" else "dn_dlnr", v)

    @classmethod
    def from_csv(cls, path: str | Any) -> TabulatedDistribution:
        """Read a table from a CSV file with a header line.

        Columns ``radius_um`` and one of ``dn_dr`` or ``dn_dlnr``; lines
        starting with ``#`` are comments.

        Parameters
        ----------
        path : str or path-like
            The file.

        Raises
        ------
        FileNotFoundError
            No such file.
        dustoptics.io.FormatError
            Not a regular file (a FIFO, a device), larger than
            :data:`dustoptics._files.MAX_TEXT_BYTES`, not UTF-8 text, or not a
            CSV file (a cell beyond the csv module's field limit).
        ValueError
            Missing columns, or a value that is not a number.
        """

        p = Path(path)
        try:
            text = read_checked(p).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise FormatError(f"{p}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
        lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
        try:
            rows = list(csv.reader(lines, skipinitialspace=True))
        except csv.Error as exc:
            raise FormatError(f"{p}: not a valid CSV file ({exc})") from None
        columns = [c.strip() for c in rows[0]] if rows else []
        if "radius_um" not in columns or ("dn_dr" in columns) == ("dn_dlnr" in columns):
            raise ValueError(
                f"{path}: a size table needs the columns radius_um and exactly one of dn_dr, dn_dlnr; "
                f"got {columns}"
            )
        key = "dn_dr" if "dn_dr" in columns else "dn_dlnr"
        i, j = columns.index("radius_um"), columns.index(key)
        try:
            radius = [float(row[i]) for row in rows[1:]]
            values = [float(row[j]) for row in rows[1:]]
        except (ValueError, IndexError) as exc:
            raise ValueError(f"{path}: unreadable number in the size table ({exc})") from None
        return cls(radius_um=np.array(radius), **{key: np.array(values)})

    @property
    def _density_points(self) -> NDArray[np.float64]:
        if self.dn_dr is not None:
            return np.asarray(self.dn_dr)
        return np.asarray(self.dn_dlnr) / np.asarray(self.radius_um)

    def _raw_moment(self, k: float, upto: float) -> float:
        """int_{r_0}^{upto} r^k n(r) dr of the piecewise linear n, divided by _norm."""
        r = np.asarray(self.radius_um)
        n = self._density_points
        a = r[:-1]
        b = np.minimum(r[1:], upto)
        keep = b > a
        if not keep.any():
            return 0.0
        a, b = a[keep], b[keep]
        slope = np.diff(n)[keep] / np.diff(r)[keep]
        c0 = n[:-1][keep] - slope * a
        total = c0 * _power_integrals(k, a, b) + slope * _power_integrals(k + 1.0, a, b)
        return math.fsum(total) / self._norm

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        r = _as_radius(radius_um)
        grid = np.asarray(self.radius_um)
        values = np.interp(r, grid, self._density_points, left=0.0, right=0.0) / self._norm
        inside = (r >= grid[0]) & (r <= grid[-1])
        return _scalar_or_array(np.where(np.isnan(r), np.nan, np.where(inside, values, 0.0)))

    def moment(self, k: float) -> float:
        """Moment of the piecewise linear n(r) (exact) [um^k]."""
        k = check_real("k", k)
        return self._raw_moment(k, float(self.radius_um[-1]))

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        full = self._raw_moment(k, float(self.radius_um[-1]))
        return _tail_point_by_point(lambda v: self._raw_moment(k, v) / full, radius_um, upper)

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        support = (float(self.radius_um[0]), float(self.radius_um[-1]))
        return _numeric_bounds(self, tail_fraction, lower_moment, upper_moment, support)

    def _parameters(self) -> dict[str, Any]:
        key = "dn_dr" if self.dn_dr is not None else "dn_dlnr"
        return {
            "radius_um": np.asarray(self.radius_um).tolist(),
            key: np.asarray(getattr(self, key)).tolist(),
        }


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class DensityDistribution(SizeDistribution):
    """A distribution defined by any density function on a finite radius range.

    The public way to bring one's own model: give ``density(radius_um) ->
    n(r)`` (vectorized over a numpy array, any positive scale) and the radii
    between which it lives; it is normalized to 1 there.  Moments and tail
    fractions are integrated numerically (adaptive Gauss-Kronrod in ln r,
    ``scipy.integrate.quad``, relative tolerance 1e-11), deterministic.
    Compared by identity.

    Parameters
    ----------
    density : callable
        ``density(radius_um: numpy.ndarray) -> numpy.ndarray``, finite and
        >= 0 on [r_min_um, r_max_um]. [any scale, per um]
    r_min_um, r_max_um : float
        The range, 0 < r_min_um < r_max_um < inf. [um]
    name : str
        What the model is (recorded in provenance).

    Examples
    --------
    >>> import numpy as np
    >>> d = DensityDistribution(density=lambda r: np.exp(-r), r_min_um=0.01, r_max_um=10.0, name="exp")
    >>> round(d.moment(0.0), 9)
    1.0
    """

    model: ClassVar[str] = "density_function"
    citation: ClassVar[str] = "user-supplied density function"

    density: Any
    r_min_um: float
    r_max_um: float
    name: str = "density function"
    _norm: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not callable(self.density):
            raise ValueError(f"density must be a callable radius_um -> n(r); got {self.density!r}")
        lo, hi = _check_radius_range(self.r_min_um, self.r_max_um)
        object.__setattr__(self, "r_min_um", lo)
        object.__setattr__(self, "r_max_um", hi)
        probe = np.geomspace(lo, hi, 257)
        values = np.asarray(self.density(probe), dtype=np.float64)
        if values.shape != probe.shape:
            raise ValueError(
                f"density must return one value per radius (shape {probe.shape}); got {values.shape}"
            )
        bad = ~np.isfinite(values) | (values < 0.0)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(
                f"density must be finite and >= 0 on [r_min_um, r_max_um]; got {float(values[i])!r} at {float(probe[i])!r} um"
            )
        object.__setattr__(self, "_norm", 1.0)
        norm = self._integral(0.0, lo, hi)
        if not norm > 0.0:
            raise ValueError("density integrates to 0 over [r_min_um, r_max_um]: no particles")
        object.__setattr__(self, "_norm", norm)

    def _integral(self, k: float, a: float, b: float) -> float:
        """int_a^b r^k n(r) dr / _norm, in ln r."""

        if b <= a:
            return 0.0

        def f(t: float) -> float:
            r = math.exp(t)
            return float(np.asarray(self.density(np.array([r])), dtype=np.float64)[0]) * r ** (
                k + 1.0
            )

        # here: scipy.integrate (with scipy.optimize, linalg, sparse) is 0.25 s of a warm
        # `dustoptics build`'s CPU, and only a tabulated or custom density needs it
        from scipy.integrate import quad

        value, _ = quad(f, math.log(a), math.log(b), epsabs=0.0, epsrel=1e-11, limit=500)
        return value / self._norm

    def pdf(self, radius_um: ArrayLike) -> FloatOrArray:
        r = _as_radius(radius_um)
        inside = (r >= self.r_min_um) & (r <= self.r_max_um)
        safe = np.where(inside, r, self.r_min_um)
        values = (
            np.asarray(self.density(np.atleast_1d(safe)), dtype=np.float64).reshape(r.shape)
            / self._norm
        )
        return _scalar_or_array(np.where(np.isnan(r), np.nan, np.where(inside, values, 0.0)))

    def moment(self, k: float) -> float:
        """Moment, integrated numerically [um^k]."""
        k = check_real("k", k)
        return self._integral(k, self.r_min_um, self.r_max_um)

    def _tail(self, k: float, radius_um: NDArray[np.float64], upper: bool) -> NDArray[np.float64]:
        lo, hi = self.r_min_um, self.r_max_um
        full = self._integral(k, lo, hi)
        return _tail_point_by_point(
            lambda v: self._integral(k, lo, min(max(v, lo), hi)) / full, radius_um, upper
        )

    def _bounds(
        self, tail_fraction: float, lower_moment: float, upper_moment: float
    ) -> tuple[float, float]:
        return _numeric_bounds(
            self, tail_fraction, lower_moment, upper_moment, (self.r_min_um, self.r_max_um)
        )

    def _parameters(self) -> dict[str, Any]:
        return {"name": self.name, "r_min_um": self.r_min_um, "r_max_um": self.r_max_um}


# -------------------------------------------------------------- records


def from_dict(data: Mapping[str, Any]) -> SizeDistribution:
    """The size distribution a :meth:`SizeDistribution.to_dict` record describes.

    Parameters
    ----------
    data : Mapping
        ``model`` (one of the models' names) and ``parameters`` (the
        constructor's arguments); a ``multimodal`` record also ``modes``.

    Returns
    -------
    SizeDistribution
        Equal to the distribution that wrote the record.

    Raises
    ------
    ValueError
        Unknown model, missing or unexpected parameters.

    Examples
    --------
    >>> from dustoptics.particles.sizedist import ModifiedGamma
    >>> from_dict(ModifiedGamma(r_eff_um=1.6, v_eff=0.2).to_dict())
    ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    """
    model = data.get("model") if isinstance(data, Mapping) else None
    if model == DensityDistribution.model:
        raise ValueError(
            "a density_function size distribution cannot be rebuilt from its record "
            "(its density is a Python callable); construct it again"
        )
    models = [name for name in SIZE_DISTRIBUTIONS if name != DensityDistribution.model]
    if model not in models:
        raise ValueError(
            f"size distribution model must be one of {', '.join(map(repr, models))}; got {model!r}"
        )
    parameters = data.get("parameters")
    if not isinstance(parameters, Mapping):
        raise ValueError(
            f"size distribution record needs a 'parameters' mapping; got {parameters!r}"
        )
    cls = SIZE_DISTRIBUTIONS[model]
    try:
        if model == MultiModal.model:
            modes = data.get("modes")
            if not isinstance(modes, list):
                raise ValueError(f"a multimodal record needs a list of 'modes'; got {modes!r}")
            return MultiModal(
                modes=tuple(from_dict(mode) for mode in modes),
                relative_number_densities=parameters["relative_number_densities"],
            )
        nested = {p.name for p in cls.parameters if p.kind == "distribution"}
        return cls(
            **{
                name: from_dict(value) if name in nested else value
                for name, value in parameters.items()
            }
        )
    except (KeyError, TypeError) as exc:
        raise ValueError(
            f"size distribution record for {model!r} has wrong parameters: {exc}"
        ) from None
