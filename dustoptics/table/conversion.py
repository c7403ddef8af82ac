"""The table as an xarray Dataset and back, the package's in-memory interchange.

The dataset is flat, like the files written from it: one variable per stored
quantity, named as in :data:`~dustoptics.table.UNITS` whichever record holds
it, the derived quantities beside them, the derivatives along a ``parameter``
dimension, and the provenance as JSON in the global attributes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from dustoptics.table.components import grouped_fields
from dustoptics.table.derivatives import TableDerivatives
from dustoptics.table.provenance import Provenance, _provenance_json
from dustoptics.table.schema import (
    ANGLE_DIM,
    COUNT_FIELDS,
    DEFAULT_NAME,
    DERIVATIVE_FIELDS,
    DERIVED,
    DERIVED_DERIVATIVES,
    EXPANSION_FIELDS,
    FLOAT_FIELDS,
    MATRIX_FIELDS,
    ORDER_DIM,
    PARAMETER_DIM,
    SCALAR_FIELDS,
    SCHEMA,
    UNITS,
    WAVELENGTH_DIM,
    derivative_unit,
    derivative_variable,
)

if TYPE_CHECKING:
    import xarray as xr

    from dustoptics.table.core import Table

__all__ = ["dataset_variables", "per_wavelength_values", "table_fields", "to_dataset"]


def per_wavelength_values(table: Table) -> dict[str, np.ndarray]:
    """Every stored and derived quantity given per wavelength, in schema order."""
    out: dict[str, np.ndarray] = {}
    for key in (*FLOAT_FIELDS, *COUNT_FIELDS):
        value = table.quantity(key)
        if value is not None:
            out[key] = value
    if table.refractive_index is not None:
        out["refractive_index_real"] = table.refractive_index.real
        out["refractive_index_imag"] = table.refractive_index.imag
    out.update(table.derived())
    return out


#: A variable of a table's dataset: its dimensions, values and attributes.
Variable = tuple[tuple[str, ...], np.ndarray, dict[str, Any]]


def dataset_variables(table: Table) -> tuple[dict[str, Variable], dict[str, Variable]]:
    """The variables of :meth:`Table.to_xarray <dustoptics.table.Table.to_xarray>`'s dataset.

    The one assembly of the dataset, into plain dictionaries: :func:`to_dataset` makes the
    xarray Dataset of it and the netCDF writer (:mod:`dustoptics.io.tables.netcdf`) writes
    it without xarray, which would cost a warm ``dustoptics build`` the import of xarray with
    pandas and, where dask is installed, of ``dask.array`` (xarray looks for dask's array
    type the first time it makes a variable): 0.5-0.7 s of its CPU time.

    Parameters
    ----------
    table : Table

    Returns
    -------
    data, coords : dict
        Name -> (dimensions, values, attributes), in the dataset's order; the values are
        copies of the table's.
    """
    wl, angle = WAVELENGTH_DIM, ANGLE_DIM
    attrs = table.variable_attributes
    coords: dict[str, Any] = {
        wl: (wl, np.array(table.wavelength_nm), attrs(wl)),
        angle: (angle, np.array(table.theta_deg), attrs(angle)),
    }
    data: dict[str, Any] = {"phase": ((wl, angle), np.array(table.phase), attrs("phase"))}
    for key, values in per_wavelength_values(table).items():
        data[key] = (wl, np.array(values), attrs(key))
    for key in SCALAR_FIELDS:
        value = table.quantity(key)
        if value is not None:
            data[key] = ((), np.array(np.float64(value)), attrs(key))
    if table.matrix is not None:
        for key in MATRIX_FIELDS:
            data[key] = ((wl, angle), np.array(getattr(table.matrix, key)), attrs(key))
    if table.expansion is not None:
        order = np.arange(table.expansion.n_order, dtype=np.float64)
        coords[ORDER_DIM] = (ORDER_DIM, order, attrs(ORDER_DIM))
        for key in EXPANSION_FIELDS:
            data[key] = ((wl, ORDER_DIM), np.array(getattr(table.expansion, key)), attrs(key))
    if table.derivatives is not None:
        _derivative_variables(table, coords, data)

    def as_variables(variables: dict[str, Any]) -> dict[str, Variable]:
        return {
            key: ((dims,) if isinstance(dims, str) else tuple(dims), np.asarray(v), dict(a))
            for key, (dims, v, a) in variables.items()
        }

    return as_variables(data), as_variables(coords)


def to_dataset(table: Table) -> xr.Dataset:
    """:meth:`Table.to_xarray <dustoptics.table.Table.to_xarray>`."""
    import xarray as xr

    data, coords = dataset_variables(table)
    return xr.Dataset(data, coords=coords, attrs=table.global_attributes())


def _derivative_variables(table: Table, coords: dict[str, Any], data: dict[str, Any]) -> None:
    """The derivatives as variables with a ``parameter`` dimension (see :meth:`to_xarray`)."""
    d = table.derivatives
    assert d is not None
    wl, angle, par = WAVELENGTH_DIM, ANGLE_DIM, PARAMETER_DIM
    coords[par] = (
        par,
        np.array(d.parameters, dtype=str),
        {
            "long_name": "parameter the derivatives are taken with respect to",
            "derivative_method": d.method,
        },
    )
    coords["parameter_units"] = (
        par,
        np.array(d.parameter_units, dtype=str),
        {"long_name": "unit of each parameter (udunits2)"},
    )
    for key in table.derivative_quantities:
        unit, meaning = UNITS[key]
        values = np.stack([table.derivative(key, p) for p in d.parameters])
        errors = np.stack([table.derivative_error_estimate(key, p) for p in d.parameters])
        per_parameter = [derivative_unit(unit, u) for u in d.parameter_units]
        attrs = {"long_name": f"derivative of the {meaning} with respect to each parameter"}
        if len(set(per_parameter)) == 1:
            attrs["units"] = per_parameter[0]
        attrs["units_by_parameter"] = "; ".join(per_parameter)
        if key not in d.values:
            attrs["derived_from"] = f"derivatives of {DERIVED[key]} (chain rule)"
        name = derivative_variable(key)
        attrs["error_estimate"] = f"{name}_error_estimate"
        dims = (
            (par, wl, ORDER_DIM)
            if key in EXPANSION_FIELDS
            else (par, wl, angle)
            if values.ndim == 3
            else (par, wl)
        )
        data[name] = (dims, values, attrs)
        err_attrs = {
            "long_name": f"estimated error of {name} (largest over angle)",
            **{k: v for k, v in attrs.items() if k in ("units", "units_by_parameter")},
        }
        data[f"{name}_error_estimate"] = ((par, wl), errors, err_attrs)


def _expected_dims() -> dict[str, tuple[str, ...]]:
    """Variable -> its dimensions in the schema (derivative variables aside)."""
    wl, angle = WAVELENGTH_DIM, ANGLE_DIM
    expected: dict[str, tuple[str, ...]] = {wl: (wl,), angle: (angle,), "phase": (wl, angle)}
    for key in (*FLOAT_FIELDS, *COUNT_FIELDS, "refractive_index_real", "refractive_index_imag"):
        expected[key] = (wl,)
    expected.update(dict.fromkeys(DERIVED, (wl,)))
    expected.update(dict.fromkeys(SCALAR_FIELDS, ()))
    expected.update(dict.fromkeys(MATRIX_FIELDS, (wl, angle)))
    expected[ORDER_DIM] = (ORDER_DIM,)
    expected.update(dict.fromkeys(EXPANSION_FIELDS, (wl, ORDER_DIM)))
    return expected


def _stored_values(ds: xr.Dataset) -> dict[str, Any]:
    """The stored variables of ``ds`` by name, their dimensions and units checked."""
    expected = _expected_dims()
    names = [str(k) for k in ds.variables if not _is_derivative_variable(str(k))]
    unknown = [k for k in names if k not in expected]
    if unknown:
        raise ValueError(
            f"dataset has variables the table schema {SCHEMA} does not define: {unknown}"
        )
    for key in (WAVELENGTH_DIM, ANGLE_DIM, "phase", "g"):
        if key not in ds.variables:
            raise ValueError(f"dataset lacks the variable {key!r}")
    values: dict[str, Any] = {}
    for name in names:
        var = ds.variables[name]
        if tuple(var.dims) != expected[name]:
            raise ValueError(
                f"variable {name!r} must have dimensions {expected[name]}; got {var.dims}"
            )
        unit = var.attrs.get("units")
        if unit != UNITS[name][0]:
            raise ValueError(
                f"variable {name!r} must be in {UNITS[name][0]!r}; its units are {unit!r}"
            )
        if name not in DERIVED and name != ORDER_DIM:
            values[name] = var.values
    for key in SCALAR_FIELDS:
        if key in values:
            values[key] = float(values[key])
    return values


def _refractive_index(values: dict[str, Any]) -> Any:
    """Pops the real and imaginary parts of the refractive index; m = n + i k, or None."""
    real = values.pop("refractive_index_real", None)
    imag = values.pop("refractive_index_imag", None)
    if (real is None) != (imag is None):
        raise ValueError(
            "refractive_index_real and refractive_index_imag must both be present or neither"
        )
    return None if real is None else real + 1j * imag


def table_fields(ds: xr.Dataset) -> dict[str, Any]:
    """The :class:`~dustoptics.table.Table` arguments a :meth:`to_xarray` dataset holds.

    See :meth:`Table.from_xarray <dustoptics.table.Table.from_xarray>`.
    """
    import xarray as xr

    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray.Dataset; got {type(ds).__name__}")
    schema = ds.attrs.get("dustoptics_schema")
    if schema != SCHEMA:
        raise ValueError(
            f"dataset is not a dustoptics table: its dustoptics_schema attribute is {schema!r}, "
            f"expected {SCHEMA!r}"
        )
    derivatives = _derivatives_from_xarray(ds)
    values = _stored_values(ds)
    try:
        provenance = Provenance.from_dict(_provenance_json(ds.attrs["provenance"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(
            f"dataset attribute 'provenance' is missing or not a provenance record: {exc}"
        ) from None
    refractive_index = _refractive_index(values)
    return {
        **grouped_fields(values),
        "name": ds.attrs.get("name", DEFAULT_NAME),
        "refractive_index": refractive_index,
        "provenance": provenance,
        "derivatives": derivatives,
    }


def _is_derivative_variable(name: str) -> bool:
    return name in (PARAMETER_DIM, "parameter_units") or (
        name.startswith("d_") and f"_d_{PARAMETER_DIM}" in name
    )


def _derivatives_from_xarray(ds: xr.Dataset) -> TableDerivatives | None:
    """The :class:`TableDerivatives` a :meth:`Table.to_xarray` dataset holds, or None."""
    names = [str(k) for k in ds.variables if _is_derivative_variable(str(k))]
    if not names:
        return None
    if PARAMETER_DIM not in ds.variables or "parameter_units" not in ds.variables:
        raise ValueError(
            f"dataset has derivative variables {names} but no {PARAMETER_DIM!r} and "
            "'parameter_units' coordinates"
        )
    parameters = tuple(str(p) for p in ds[PARAMETER_DIM].values)
    units = tuple(str(u) for u in ds["parameter_units"].values)
    known = {derivative_variable(k): k for k in (*DERIVATIVE_FIELDS, *DERIVED_DERIVATIVES)}
    allowed = set(known) | {f"{k}_error_estimate" for k in known}
    allowed |= {PARAMETER_DIM, "parameter_units"}
    unknown = sorted(set(names) - allowed)
    if unknown:
        raise ValueError(
            f"dataset has variables the table schema {SCHEMA} does not define: {unknown}"
        )
    values: dict[str, np.ndarray] = {}
    errors: dict[str, np.ndarray] = {}
    for name, key in known.items():
        if name not in ds.variables:
            continue
        var = ds.variables[name]
        if key in DERIVED_DERIVATIVES and (
            key not in DERIVATIVE_FIELDS or "derived_from" in var.attrs
        ):
            continue  # derived on writing: derived again from the stored ones
        expected = [derivative_unit(UNITS[key][0], u) for u in units]
        if var.attrs.get("units_by_parameter") != "; ".join(expected):
            raise ValueError(
                f"variable {name!r} must be in {'; '.join(expected)} (per parameter); its "
                f"units_by_parameter are {var.attrs.get('units_by_parameter')!r}"
            )
        if f"{name}_error_estimate" not in ds.variables:
            raise ValueError(f"dataset lacks the variable {name + '_error_estimate'!r}")
        values[key] = np.asarray(var.values)
        errors[key] = np.asarray(ds.variables[f"{name}_error_estimate"].values)
    method = str(ds.variables[PARAMETER_DIM].attrs.get("derivative_method", ""))
    return TableDerivatives(
        parameters=parameters,
        parameter_units=units,
        values=values,
        error_estimates=errors,
        method=method,
    )
