"""The optional parts of a table, one record per physical concept, each checking itself.

A :class:`~dustoptics.table.Table` always holds a phase function and its
asymmetry parameter over wavelength and angle.  What else it holds comes in
records, each present whole or not at all (``table.expansion is not None``):

* :class:`CrossSections`: the mean cross-sections per particle and the
  population's moments and density that turn them into efficiencies, volume
  and mass coefficients (every derived quantity follows from this record);
* :class:`QuadratureRecord`: how well the radius quadrature did, per
  wavelength: error estimates, node counts and the moments of its nodes;
* :class:`ScatteringMatrix`: F12, F33 and F34 beside F11 = phase;
* :class:`Expansion`: the coefficients in generalized spherical functions.

Each record validates its own arrays (finite, consistent lengths, physical
signs) when made, and stores read-only copies; the table then checks that the
record fits its grids (:meth:`CrossSections.check_grid`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields, replace
from typing import Any

import numpy as np

from dustoptics._validation import as_float_array, check_positive
from dustoptics.table.schema import SCALAR_FIELDS

__all__ = [
    "CrossSections",
    "Expansion",
    "QuadratureRecord",
    "ScatteringMatrix",
    "alpha1_from_pmom",
    "grouped_fields",
    "pmom_from_alpha1",
]

_UM2_TO_M2 = 1e-12
_M2_PER_KG = 1e6  # um^2 / (kg m^-3 um^3) -> m^2 kg^-1


def _frozen(arr: np.ndarray) -> np.ndarray:
    out = np.array(arr, copy=True)
    out.setflags(write=False)
    return out


def _per_wavelength(name: str, value: Any, n: int | None) -> np.ndarray | None:
    """A finite 1-D float array of ``n`` values (of any length when ``n`` is None), or None."""
    if value is None:
        return None
    arr = as_float_array(name, value)
    if arr.ndim != 1 or (n is not None and arr.shape != (n,)):
        want = "(n_wavelength,)" if n is None else f"({n},)"
        raise ValueError(
            f"{name} must have shape {want}, one value per wavelength; got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr.tolist()}")
    return _frozen(arr)


def _node_counts(name: str, value: Any, n: int) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.asarray(value)
    if arr.shape != (n,) or arr.dtype.kind not in "iu" or np.any(arr < 1):
        raise ValueError(
            f"{name} must be {n} positive integers, one per wavelength; got {arr.dtype} of shape {arr.shape}"
        )
    return _frozen(arr.astype(np.int64))


def _per_wavelength_2d(name: str, value: Any, n: int | None, m: int | None) -> np.ndarray:
    arr = as_float_array(name, value)
    if (
        arr.ndim != 2
        or (n is not None and arr.shape[0] != n)
        or (m is not None and arr.shape[1] != m)
    ):
        want = f"({'n_wavelength' if n is None else n}, {'n_order' if m is None else m})"
        raise ValueError(f"{name} must have shape {want}; got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return _frozen(arr)


def _optional_positive(name: str, value: Any) -> float | None:
    return None if value is None else check_positive(name, value)


def _same(x: Any, y: Any) -> bool:
    """Whether two values are bit-identical arrays, equal records or equal scalars (or None)."""
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        return x is not None and y is not None and x.dtype == y.dtype and np.array_equal(x, y)
    if isinstance(x, _Record):
        return x.equals(y)
    return bool(x == y)


class _Record:
    """What the records share: a length per wavelength, copies with changes, equality."""

    def _first(self) -> np.ndarray:
        raise NotImplementedError

    @property
    def n_wavelength(self) -> int:
        """Number of wavelengths the record's arrays cover."""
        return int(self._first().shape[0])

    def replace(self, **changes: Any) -> Any:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)  # type: ignore[type-var]

    def equals(self, other: object) -> bool:
        """Whether both hold bit-identical arrays and equal scalars."""
        return type(self) is type(other) and all(
            _same(getattr(self, f.name), getattr(other, f.name))
            for f in fields(self)  # type: ignore[arg-type]
        )

    def check_grid(self, *, n_wavelength: int, n_theta: int) -> None:
        """Check that the record fits a table of ``n_wavelength`` x ``n_theta``.

        Raises
        ------
        ValueError
            The record's wavelength count differs; the message names the record.
        """
        del n_theta
        if self.n_wavelength != n_wavelength:
            raise ValueError(
                f"{type(self).__name__} holds {self.n_wavelength} wavelengths; the table has "
                f"{n_wavelength} (n_wavelength)"
            )


@dataclass(frozen=True, eq=False, kw_only=True)
class CrossSections(_Record):
    """Mean cross-sections per particle and the population that scales them.

    Attributes
    ----------
    cext_um2, csca_um2 : numpy.ndarray, shape (n_wavelength,)
        Mean extinction and scattering cross-sections per particle,
        0 <= csca <= cext, cext > 0. [um^2]
    cback_um2 : numpy.ndarray or None
        Mean backscattering cross-section <C_back> = <4 pi dC_sca/dOmega(180 deg)>
        per particle (Bohren & Huffman 1983, p. 122). [um^2]
    mean_geometric_cross_section_um2 : float or None
        pi <r^2> of the size distribution (None for molecules). [um^2]
    number_density_per_m3 : float or None
        Number density at which the ``beta_*`` coefficients are given. [m^-3]
    mean_volume_um3 : float or None
        4/3 pi <r^3> of the size distribution (analytic). [um^3]
    particle_density_kg_m3 : float or None
        Density of the particles' material, for the mass coefficients. [kg m^-3]

    Examples
    --------
    >>> cs = CrossSections(cext_um2=[2.0, 1.0], csca_um2=[1.0, 1.0])
    >>> cs.ssa.tolist(), cs.cabs_um2.tolist()
    ([0.5, 1.0], [1.0, 0.0])
    """

    cext_um2: np.ndarray
    csca_um2: np.ndarray
    cback_um2: np.ndarray | None = None
    mean_geometric_cross_section_um2: float | None = None
    number_density_per_m3: float | None = None
    mean_volume_um3: float | None = None
    particle_density_kg_m3: float | None = None

    def __post_init__(self) -> None:
        cext = _per_wavelength("cext_um2", self.cext_um2, None)
        assert cext is not None
        csca = _per_wavelength("csca_um2", self.csca_um2, cext.size)
        assert csca is not None
        if np.any(csca < 0) or np.any(cext <= 0):
            raise ValueError("cross-sections must satisfy cext_um2 > 0 and csca_um2 >= 0")
        # Allow the last-bit rounding of a sum, not a physically wrong albedo.
        if np.any(csca > cext * (1 + 1e-12)):
            raise ValueError("csca_um2 must not exceed cext_um2 (single-scattering albedo <= 1)")
        checked: dict[str, Any] = {
            "cext_um2": cext,
            "csca_um2": csca,
            "cback_um2": _per_wavelength("cback_um2", self.cback_um2, cext.size),
        }
        for key in SCALAR_FIELDS:
            checked[key] = _optional_positive(key, getattr(self, key))
        for key, value in checked.items():
            object.__setattr__(self, key, value)

    def _first(self) -> np.ndarray:
        return self.cext_um2

    # ------------------------------------------------------------ derived

    @property
    def cabs_um2(self) -> np.ndarray:
        """Mean absorption cross-section per particle, cext - csca. [um^2]"""
        return self.cext_um2 - self.csca_um2

    @property
    def ssa(self) -> np.ndarray:
        """Single-scattering albedo csca / cext. [-]"""
        return self.csca_um2 / self.cext_um2

    def derived_names(self) -> list[str]:
        """The derived quantities this record defines, in schema order."""
        names = ["cabs_um2", "ssa"]
        if self.mean_geometric_cross_section_um2 is not None:
            names += ["qext", "qsca", "qabs"]
        if self.number_density_per_m3 is not None:
            names += ["beta_ext_per_m", "beta_sca_per_m", "beta_abs_per_m"]
        if self.cback_um2 is not None:
            names += ["lidar_ratio_sr"]
        if self.particle_density_kg_m3 is not None and self.mean_volume_um3 is not None:
            names += ["mass_ext_m2_per_kg", "mass_sca_m2_per_kg", "mass_abs_m2_per_kg"]
        return names

    def efficiency(self, cross_section_um2: np.ndarray) -> np.ndarray | None:
        """A cross-section over pi <r^2> (None without a mean geometric cross-section). [-]"""
        area = self.mean_geometric_cross_section_um2
        return None if area is None else cross_section_um2 / area

    def volume_coefficient(self, cross_section_um2: np.ndarray) -> np.ndarray | None:
        """N times a cross-section (None without a number density). [m^-1]"""
        n = self.number_density_per_m3
        return None if n is None else cross_section_um2 * _UM2_TO_M2 * n

    def mass_coefficient(self, cross_section_um2: np.ndarray) -> np.ndarray | None:
        """A cross-section over rho <V> (None without density and mean volume). [m^2 kg^-1]"""
        rho, volume = self.particle_density_kg_m3, self.mean_volume_um3
        if rho is None or volume is None:
            return None
        return cross_section_um2 * (_M2_PER_KG / (rho * volume))


@dataclass(frozen=True, eq=False, kw_only=True)
class QuadratureRecord(_Record):
    """How the radius quadrature that computed a table did, per wavelength.

    Attributes
    ----------
    error_estimate : numpy.ndarray, shape (n_wavelength,)
        Estimated largest relative error of the phase function. [-]
    cross_section_error_estimate : numpy.ndarray or None
        Estimated error of the cross-sections (relative) and g (absolute). [-]
    n_nodes, cross_section_n_nodes : numpy.ndarray of int or None
        Radius nodes of the quadrature that gave the phase function, and of
        the (finer) one that gave the cross-sections and g. [-]
    r_eff_quadrature_um, v_eff_quadrature, mean_volume_quadrature_um3 : numpy.ndarray or None
        Effective radius, effective variance and mean particle volume of the
        radius nodes that gave the cross-sections (beside the distribution's
        analytic ones, :attr:`CrossSections.mean_volume_um3`). [um], [-], [um^3]
    """

    error_estimate: np.ndarray
    cross_section_error_estimate: np.ndarray | None = None
    n_nodes: np.ndarray | None = None
    cross_section_n_nodes: np.ndarray | None = None
    r_eff_quadrature_um: np.ndarray | None = None
    v_eff_quadrature: np.ndarray | None = None
    mean_volume_quadrature_um3: np.ndarray | None = None

    def __post_init__(self) -> None:
        err = _per_wavelength("error_estimate", self.error_estimate, None)
        assert err is not None
        n = err.size
        checked: dict[str, np.ndarray | None] = {"error_estimate": err}
        for key in (
            "cross_section_error_estimate",
            "r_eff_quadrature_um",
            "v_eff_quadrature",
            "mean_volume_quadrature_um3",
        ):
            checked[key] = _per_wavelength(key, getattr(self, key), n)
        for key in ("n_nodes", "cross_section_n_nodes"):
            checked[key] = _node_counts(key, getattr(self, key), n)
        for key, value in checked.items():
            object.__setattr__(self, key, value)

    def _first(self) -> np.ndarray:
        return self.error_estimate

    @property
    def achieved_error(self) -> float:
        """Largest phase-function error estimate over wavelength. [-]"""
        return float(np.max(self.error_estimate))


@dataclass(frozen=True, eq=False, kw_only=True)
class ScatteringMatrix(_Record):
    """The scattering matrix beside F11 (the table's phase function).

    Normalized like the phase function; F22 = F11 and F44 = F33 for spheres.
    Bohren & Huffman's signs (F12 < 0 for Rayleigh scattering at 90 degree;
    see :mod:`dustoptics.scattering.expansion`).

    Attributes
    ----------
    f12, f33, f34 : numpy.ndarray, shape (n_wavelength, n_theta)
        Scattering matrix elements. [sr^-1]
    matrix_error_estimate : numpy.ndarray or None, shape (n_wavelength,)
        Estimated largest error of F12, F33, F34 relative to F11 at the same
        angle. [-]
    """

    f12: np.ndarray
    f33: np.ndarray
    f34: np.ndarray
    matrix_error_estimate: np.ndarray | None = None

    def __post_init__(self) -> None:
        f12 = _per_wavelength_2d("f12", self.f12, None, None)
        n, m = f12.shape
        object.__setattr__(self, "f12", f12)
        for key in ("f33", "f34"):
            object.__setattr__(self, key, _per_wavelength_2d(key, getattr(self, key), n, m))
        error = _per_wavelength("matrix_error_estimate", self.matrix_error_estimate, n)
        object.__setattr__(self, "matrix_error_estimate", error)

    def _first(self) -> np.ndarray:
        return self.f12

    def check_grid(self, *, n_wavelength: int, n_theta: int) -> None:
        """Check that F12, F33, F34 have shape (``n_wavelength``, ``n_theta``)."""
        if self.f12.shape != (n_wavelength, n_theta):
            raise ValueError(
                f"f12, f33 and f34 must have shape (n_wavelength, n_theta) = ({n_wavelength}, "
                f"{n_theta}); got {self.f12.shape}"
            )


@dataclass(frozen=True, eq=False, kw_only=True)
class Expansion(_Record):
    """Expansion coefficients of the scattering matrix in generalized spherical functions.

    alpha1[:, 0] = 1 and alpha1[:, 1] = 3 g; DISORT's moments are
    alpha1_l / (2 l + 1) (:func:`~dustoptics.table.pmom_from_alpha1`).

    Attributes
    ----------
    alpha1, alpha2, alpha3, alpha4, beta1, beta2 : numpy.ndarray, shape (n_wavelength, n_order)
        The coefficients. [-]
    expansion_error_estimate : numpy.ndarray or None, shape (n_wavelength,)
        Bound on the error of every coefficient divided by (2 l + 1). [-]
    """

    alpha1: np.ndarray
    alpha2: np.ndarray
    alpha3: np.ndarray
    alpha4: np.ndarray
    beta1: np.ndarray
    beta2: np.ndarray
    expansion_error_estimate: np.ndarray | None = None

    def __post_init__(self) -> None:
        alpha1 = _per_wavelength_2d("alpha1", self.alpha1, None, None)
        n, m = alpha1.shape
        object.__setattr__(self, "alpha1", alpha1)
        for key in ("alpha2", "alpha3", "alpha4", "beta1", "beta2"):
            object.__setattr__(self, key, _per_wavelength_2d(key, getattr(self, key), n, m))
        error = _per_wavelength("expansion_error_estimate", self.expansion_error_estimate, n)
        object.__setattr__(self, "expansion_error_estimate", error)

    def _first(self) -> np.ndarray:
        return self.alpha1

    @property
    def n_order(self) -> int:
        """Number of orders l = 0, 1, ... of the coefficients."""
        return int(self.alpha1.shape[1])


def pmom_from_alpha1(alpha1: np.ndarray) -> np.ndarray:
    """DISORT's phase-function moments chi_l = alpha1_l / (2 l + 1). [-]

    The same numbers as ``alpha1`` (:attr:`Expansion.alpha1`) in the
    normalization of DISORT's ``PMOM`` (Stamnes et al. 1988): P(mu) =
    sum_l (2 l + 1) chi_l P_l(mu), chi_0 = 1, chi_1 = g.  Works on the last axis.

    Examples
    --------
    >>> pmom_from_alpha1(np.array([1.0, 1.5, 2.5]))
    array([1. , 0.5, 0.5])
    """
    a = np.asarray(alpha1, dtype=np.float64)
    return a / (2.0 * np.arange(a.shape[-1]) + 1.0)


def alpha1_from_pmom(pmom: np.ndarray) -> np.ndarray:
    """Inverse of :func:`pmom_from_alpha1`: alpha1_l = (2 l + 1) chi_l. [-]"""
    p = np.asarray(pmom, dtype=np.float64)
    return p * (2.0 * np.arange(p.shape[-1]) + 1.0)


#: Table attribute -> the record class it holds.
RECORDS: dict[str, type[_Record]] = {
    "cross_sections": CrossSections,
    "quadrature": QuadratureRecord,
    "matrix": ScatteringMatrix,
    "expansion": Expansion,
}

#: Stored quantity -> the table attribute of the record that holds it.
RECORD_OF: dict[str, str] = {
    f.name: attribute
    for attribute, cls in RECORDS.items()
    for f in fields(cls)  # type: ignore[arg-type]
}


def grouped_fields(values: Mapping[str, Any] | None = None, /, **more: Any) -> dict[str, Any]:
    """:class:`~dustoptics.table.Table` arguments from flat ones, for code that has them flat.

    The stored quantities of the records (a None value meaning absent) are
    grouped into their records; every other argument is passed on as it is.

    Raises
    ------
    ValueError
        A record is given both whole and by its quantities, or some of a
        record's quantities are given without one it needs.

    Examples
    --------
    >>> sorted(grouped_fields({"g": [0.5], "cext_um2": [2.0]}, csca_um2=[1.0], n_nodes=None))
    ['cross_sections', 'g']
    """
    flat = {**(values or {}), **more}
    out = {key: value for key, value in flat.items() if key not in RECORD_OF}
    for attribute, cls in RECORDS.items():
        own = {f.name: flat[f.name] for f in fields(cls) if flat.get(f.name) is not None}  # type: ignore[arg-type]
        if not own:
            continue
        required = [f.name for f in fields(cls) if f.default is MISSING]  # type: ignore[arg-type]
        missing = [key for key in required if key not in own]
        if missing:
            raise ValueError(
                f"{', '.join(required)} must all be given or all be None (the {cls.__name__} of "
                f"a table); got {', '.join(own)} without {', '.join(missing)}"
            )
        if attribute in out:
            raise ValueError(f"{attribute} given both whole and by their quantities")
        out[attribute] = cls(**own)
    return out
