"""Derivatives of a table's outputs with respect to named input parameters."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from dustoptics._validation import as_float_array
from dustoptics.table.components import CrossSections
from dustoptics.table.provenance import _storable_text
from dustoptics.table.schema import DERIVATIVE_FIELDS, DERIVED_DERIVATIVES

__all__ = ["TableDerivatives"]


def _checked_parameters(params: tuple[str, ...], units: tuple[str, ...]) -> None:
    if not params or not all(isinstance(p, str) and p for p in params):
        raise ValueError(f"parameters must be non-empty strings; got {params!r}")
    if len(set(params)) != len(params):
        raise ValueError(f"parameters must not repeat a name; got {params!r}")
    if len(units) != len(params) or not all(isinstance(u, str) and u for u in units):
        raise ValueError(f"parameter_units must give one unit string per parameter; got {units!r}")
    for p in params:
        _storable_text("parameters", p)


def _checked_pair(
    key: str, value: object, error: object, n_parameter: int
) -> tuple[np.ndarray, np.ndarray]:
    """Read-only copies of one quantity's derivative and its error estimate, checked."""
    v = np.array(as_float_array(f"values[{key!r}]", value), copy=True)
    e = np.array(as_float_array(f"error_estimates[{key!r}]", error), copy=True)
    if v.ndim not in (2, 3) or v.shape[0] != n_parameter or e.shape != v.shape[:2]:
        raise ValueError(
            f"values[{key!r}] must have shape (n_parameter, n_wavelength[, n_theta]) and "
            f"error_estimates[{key!r}] (n_parameter, n_wavelength); got {v.shape} and "
            f"{e.shape}"
        )
    if not (np.all(np.isfinite(v)) and np.all(np.isfinite(e)) and np.all(e >= 0)):
        raise ValueError(f"derivatives of {key!r} must be finite, their error estimates >= 0")
    v.setflags(write=False)
    e.setflags(write=False)
    return v, e


@dataclass(frozen=True, eq=False, kw_only=True)
class TableDerivatives:
    """Derivatives of a table's outputs with respect to named input parameters.

    :func:`dustoptics.compute_optics` fills them (``derivatives=(...)``) and
    :meth:`Table.derivative <dustoptics.table.Table.derivative>` reads them.

    Attributes
    ----------
    parameters : tuple of str
        The parameters, in the order of every array's first axis: a size
        distribution's (``"r_eff_um"``, ``"v_eff"``, ``"modes[0].sigma"``, ...),
        ``"n"`` and ``"k"`` (real and imaginary part of the refractive index
        at each wavelength), a mixture's (``"hematite_fraction"``).
    parameter_units : tuple of str
        Each parameter's unit, udunits2 spelling (``"um"``, ``"1"``).
    values : mapping of str to numpy.ndarray
        Quantity (one of :data:`DERIVATIVE_FIELDS` the table holds) -> derivative,
        shape (n_parameter, n_wavelength[, n_theta]), in the quantity's unit
        per unit of the parameter.
    error_estimates : mapping of str to numpy.ndarray
        Quantity -> estimated error of its derivative, shape (n_parameter,
        n_wavelength) (for angular quantities the largest over angle), in
        the derivative's unit.
    method : str
        How the derivatives and their error estimates were obtained.
    """

    parameters: tuple[str, ...]
    parameter_units: tuple[str, ...]
    values: Mapping[str, np.ndarray]
    error_estimates: Mapping[str, np.ndarray]
    method: str = ""

    def __post_init__(self) -> None:
        params = tuple(self.parameters)
        units = tuple(self.parameter_units)
        _checked_parameters(params, units)
        unknown = sorted(set(self.values) - set(DERIVATIVE_FIELDS))
        if unknown or set(self.values) != set(self.error_estimates):
            raise ValueError(
                f"values must be keyed by quantities of {DERIVATIVE_FIELDS}, error_estimates by "
                f"the same; got {sorted(self.values)} and {sorted(self.error_estimates)}"
            )
        values: dict[str, np.ndarray] = {}
        errors: dict[str, np.ndarray] = {}
        for key in DERIVATIVE_FIELDS:
            if key in self.values:
                values[key], errors[key] = _checked_pair(
                    key, self.values[key], self.error_estimates[key], len(params)
                )
        object.__setattr__(self, "parameters", params)
        object.__setattr__(self, "parameter_units", units)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "error_estimates", errors)

    def equals(self, other: object) -> bool:
        """Whether both hold the same parameters and bit-identical arrays."""
        return (
            isinstance(other, TableDerivatives)
            and self.parameters == other.parameters
            and self.parameter_units == other.parameter_units
            and self.method == other.method
            and list(self.values) == list(other.values)
            and all(
                np.array_equal(self.values[k], other.values[k])
                and np.array_equal(self.error_estimates[k], other.error_estimates[k])
                for k in self.values
            )
        )

    @property
    def quantities(self) -> tuple[str, ...]:
        """The quantities :meth:`pair` gives: the stored ones, then those derived from them."""
        names = [k for k in DERIVATIVE_FIELDS if k in self.values]
        if "cext_um2" in self.values and "csca_um2" in self.values:
            names += ["ssa", "cabs_um2"]
            if "cback_um2" in self.values and "lidar_ratio_sr" not in names:
                names += ["lidar_ratio_sr"]
        return tuple(names)

    def pair(
        self, quantity: str, parameter: str, cross_sections: CrossSections | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """d(quantity)/d(parameter) and its error estimate (stored ones as stored,
        derived ones by the chain rule, from the table's ``cross_sections``).

        Raises
        ------
        ValueError
            An unknown parameter or quantity (the message lists the allowed ones).
        """
        if parameter not in self.parameters:
            raise ValueError(
                f"parameter must be one of {', '.join(map(repr, self.parameters))} (the table's "
                f"derivatives); got {parameter!r}"
            )
        j = self.parameters.index(parameter)
        if quantity in self.values:
            return self.values[quantity][j], self.error_estimates[quantity][j]
        if quantity in DERIVED_DERIVATIVES and quantity in self.quantities:
            assert cross_sections is not None  # the table checks its derivatives' quantities
            return self._chain_rule(quantity, j, cross_sections)
        raise ValueError(
            f"quantity must be one of {', '.join(map(repr, self.quantities))} (the table's "
            f"derivatives); got {quantity!r}"
        )

    def _chain_rule(
        self, quantity: str, j: int, cs: CrossSections
    ) -> tuple[np.ndarray, np.ndarray]:
        """d(ssa), d(cabs) or d(lidar ratio) of parameter ``j``, errors propagated linearly."""
        cext = cs.cext_um2
        dext, eext = self.values["cext_um2"][j], self.error_estimates["cext_um2"][j]
        dsca, esca = self.values["csca_um2"][j], self.error_estimates["csca_um2"][j]
        if quantity == "ssa":
            ssa = cs.ssa
            return (dsca - ssa * dext) / cext, (esca + ssa * eext) / cext
        if quantity == "cabs_um2":
            return dext - dsca, eext + esca
        assert cs.cback_um2 is not None  # lidar_ratio_sr: the table has cback_um2's derivatives
        ratio = 4.0 * np.pi * cext / cs.cback_um2
        dback, eback = self.values["cback_um2"][j], self.error_estimates["cback_um2"][j]
        return (
            ratio * (dext / cext - dback / cs.cback_um2),
            ratio * (eext / cext + eback / cs.cback_um2),
        )
