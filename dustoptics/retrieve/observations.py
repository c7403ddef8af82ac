"""The observations of :func:`~dustoptics.retrieve.fit.retrieve`, checked, and the model's
values at them.

The optical variables (``ssa``, ``g``, ``extinction_ratio``, ``phase``; the package
docstring says what each is) become :class:`Observation` samples; the sky's
(``sky_radiance``, ``sky_chromaticity``) go to :func:`~dustoptics.retrieve.sky.sky_samples`.
Everything a file may hold wrongly is refused here with a ValueError or a TypeError
naming the variable, the value and what is allowed: coordinates that are missing, not
numbers, not finite, outside their domain ((0, 1e7] nm, [0, 180] deg) or in another
unit (an attribute ``units``), values and uncertainties that are not numbers or not of
the variable's shape, a reference wavelength that is not one finite number > 0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dustoptics.retrieve.sky import SKY_OBSERVABLES, sky_samples
from dustoptics.table import Table

__all__ = [
    "OBSERVABLES",
    "Observation",
    "observations_of",
    "optical_grid",
    "predict",
    "sample_labels",
]

#: Observation variables :func:`retrieve` understands, and their dimensions.
OBSERVABLES: Mapping[str, tuple[str, ...]] = {
    "ssa": ("wavelength_nm",),
    "g": ("wavelength_nm",),
    "extinction_ratio": ("wavelength_nm",),
    "phase": ("wavelength_nm", "theta_deg"),
}


@dataclass(frozen=True)
class Observation:
    """The finite samples of one optical variable, one entry per sample.

    Attributes
    ----------
    name : str
        ``ssa``, ``g``, ``extinction_ratio`` or ``phase``.
    wavelength_nm : numpy.ndarray
        Wavelength of each sample. [nm]
    theta_deg : numpy.ndarray
        Scattering angle of each sample (NaN: none). [deg]
    value : numpy.ndarray
        The observed values (in the variable's unit).
    sigma : numpy.ndarray
        Their one-sigma uncertainties (same unit), finite and > 0.
    reference_nm : float
        The extinction ratio's reference wavelength (NaN for the others). [nm]
    """

    name: str
    wavelength_nm: np.ndarray  # per sample
    theta_deg: np.ndarray  # per sample (NaN: none)
    value: np.ndarray
    sigma: np.ndarray
    reference_nm: float = math.nan


def observations_of(observations: Any) -> tuple[list[Observation], list[Any]]:
    """The optical observations and the sky's samples (:func:`~dustoptics.retrieve.sky.sky_samples`)."""
    observations = _as_dataset(observations)
    known = (*OBSERVABLES, *SKY_OBSERVABLES)
    names = [str(k) for k in observations.data_vars if not str(k).endswith("_uncertainty")]
    unknown = [k for k in names if k not in known]
    if unknown or not names:
        raise ValueError(
            f"observations: variables must be among {', '.join(known)} (with "
            f"<name>_uncertainty); got {names}"
        )
    found = []
    sky = []
    for name in names:
        var, sigma_values = _variable_and_sigma(observations, name)
        if name in SKY_OBSERVABLES:
            sky += sky_samples(var, sigma_values)
        else:
            found.append(_optical_observation(name, var, sigma_values))
    if sum(o.value.size for o in found) + sum(s.value.size for s in sky) == 0:
        raise ValueError("observations: no finite samples")
    return [o for o in found if o.value.size], sky


def _as_dataset(observations: Any) -> Any:
    """``observations`` as an xarray Dataset (a named DataArray becomes one)."""
    # lazy: the package imports without xarray (tests/test_packaging.py); it adds 0.7-1 s
    import xarray as xr

    if isinstance(observations, xr.DataArray):
        if observations.name is None:
            known = (*OBSERVABLES, *SKY_OBSERVABLES)
            raise ValueError(f"observations: a DataArray must be named, one of {', '.join(known)}")
        observations = observations.to_dataset()
    if not isinstance(observations, xr.Dataset):
        raise TypeError(
            "observations must be an xarray Dataset or named DataArray; "
            f"got {type(observations).__name__}"
        )
    return observations


#: Units the coordinates may declare (an attribute ``units``); none declared means these.
_COORDINATE_UNITS: Mapping[str, tuple[str, ...]] = {
    "wavelength_nm": ("nm", "nanometer", "nanometers", "nanometre", "nanometres"),
    "theta_deg": ("deg", "degree", "degrees"),
}
#: Domain of each coordinate of the optical observations: (low, high, inclusive low). [nm, deg]
_COORDINATE_DOMAIN: Mapping[str, tuple[float, float, bool]] = {
    "wavelength_nm": (0.0, 1e7, False),
    "theta_deg": (0.0, 180.0, True),
}


def _numbers(name: str, what: str, raw: Any) -> np.ndarray:
    """``raw`` as float64, or a TypeError naming the variable and its dtype."""
    array = np.asarray(raw)
    if array.dtype.kind not in "biuf":
        raise TypeError(
            f"observations: {name!r} {what} must be real numbers; got dtype {array.dtype} "
            f"({np.ravel(array)[:3].tolist()!r}...)"
        )
    return np.asarray(array, dtype=np.float64)


def _coordinate(var: Any, name: str, coordinate: str) -> np.ndarray:
    """A coordinate of an optical observation, checked: present, numbers in its unit
    and domain, finite (:data:`_COORDINATE_DOMAIN`)."""
    if coordinate not in var.coords:
        raise ValueError(
            f"observations: {name!r} needs the coordinate {coordinate!r} along its dimension"
        )
    coord = var[coordinate]
    units = coord.attrs.get("units")
    if units is not None and str(units).strip().lower() not in _COORDINATE_UNITS[coordinate]:
        raise ValueError(
            f"observations: {name!r} coordinate {coordinate} must be in "
            f"{_COORDINATE_UNITS[coordinate][0]}; got units={units!r}"
        )
    values = _numbers(name, f"coordinate {coordinate}", coord.values)
    low, high, inclusive = _COORDINATE_DOMAIN[coordinate]
    inside = (values >= low if inclusive else values > low) & (values <= high)
    if not np.all(inside):
        bad = values[~inside][:5].tolist()
        interval = f"{'[' if inclusive else '('}{low:g}, {high:g}]"
        raise ValueError(
            f"observations: {name!r} coordinate {coordinate} must be finite and within "
            f"{interval}; got {bad}"
        )
    return values


def _variable_and_sigma(observations: Any, name: str) -> tuple[Any, np.ndarray]:
    """The variable ``name`` in its dimensions' order, and its one-sigma uncertainties."""
    var = observations[name]
    dims = OBSERVABLES.get(name) or SKY_OBSERVABLES[name]
    if set(var.dims) != set(dims) or var.ndim != len(dims):
        raise ValueError(f"observations: {name!r} must have dimensions {dims}; got {var.dims}")
    var = var.transpose(*dims)
    _numbers(name, "values", var.values)
    if f"{name}_uncertainty" in observations:
        sigma = observations[f"{name}_uncertainty"]
        if not set(sigma.dims) <= set(dims):
            raise ValueError(
                f"observations: {name + '_uncertainty'!r} must have dimensions among {dims}; "
                f"got {sigma.dims}"
            )
        try:
            sigma = sigma.transpose(*[d for d in dims if d in sigma.dims]).broadcast_like(var)
        except (ValueError, KeyError, IndexError) as exc:
            raise ValueError(
                f"observations: {name + '_uncertainty'!r} does not match {name!r} "
                f"(shape {sigma.shape} against {var.shape}): {exc}"
            ) from None
        if sigma.shape != var.shape:
            raise ValueError(
                f"observations: {name + '_uncertainty'!r} must have the shape of {name!r} "
                f"{var.shape}; got {sigma.shape}"
            )
        return var, _numbers(name, "uncertainties", sigma.values)
    if "uncertainty" in var.attrs:
        raw = var.attrs["uncertainty"]
        sigma_values = _numbers(name, "attribute uncertainty", raw)
        if sigma_values.size != 1:
            raise ValueError(
                f"observations: {name!r} attribute uncertainty must be one number; "
                f"got {np.ravel(sigma_values)[:5].tolist()}"
            )
        return var, np.full(var.shape, float(sigma_values.ravel()[0]))
    raise ValueError(
        f"observations: {name!r} needs its one-sigma uncertainty: a variable "
        f"{name + '_uncertainty'!r} or an attribute 'uncertainty'"
    )


def _reference_nm(var: Any) -> float:
    """The ``reference_wavelength_nm`` of an extinction ratio: a finite number > 0. [nm]"""
    if "reference_wavelength_nm" not in var.attrs:
        raise ValueError(
            "observations: 'extinction_ratio' needs the attribute reference_wavelength_nm"
        )
    raw = var.attrs["reference_wavelength_nm"]
    array = np.asarray(raw)
    reference = float(array.ravel()[0]) if array.dtype.kind in "biuf" and array.size == 1 else None
    low, high, _ = _COORDINATE_DOMAIN["wavelength_nm"]
    if reference is None or not low < reference <= high:
        shown = f"{reference:g}" if reference is not None else repr(raw)
        raise ValueError(
            "observations: 'extinction_ratio' attribute reference_wavelength_nm must be one "
            f"finite number within ({low:g}, {high:g}] nm; got {shown}"
        )
    return reference


def _optical_observation(name: str, var: Any, sigma_values: np.ndarray) -> Observation:
    """The finite samples of an optical observable (not the sky's)."""
    values = np.asarray(var.values, dtype=np.float64)
    wl = _coordinate(var, name, "wavelength_nm")
    if values.ndim == 2:
        theta = _coordinate(var, name, "theta_deg")
        wl_s, theta_s = np.meshgrid(wl, theta, indexing="ij")
    else:
        wl_s, theta_s = wl, np.full(wl.shape, np.nan)
    keep = np.isfinite(values)
    if not np.all(np.isfinite(sigma_values[keep]) & (sigma_values[keep] > 0)):
        bad = sigma_values[keep][~(np.isfinite(sigma_values[keep]) & (sigma_values[keep] > 0))]
        raise ValueError(
            f"observations: {name!r} uncertainties must be finite and > 0; got {bad[:5].tolist()}"
        )
    reference = _reference_nm(var) if name == "extinction_ratio" else math.nan
    return Observation(
        name,
        wl_s[keep].ravel(),
        theta_s[keep].ravel(),
        values[keep].ravel(),
        sigma_values[keep].ravel(),
        reference,
    )


def predict(
    table: Table, obs: Observation, parameters: Sequence[str]
) -> tuple[np.ndarray, np.ndarray]:
    """Model values at the samples and their derivatives (n_samples, n_parameters)."""
    i = np.searchsorted(table.wavelength_nm, obs.wavelength_nm)
    if obs.name == "phase":
        j = np.searchsorted(table.theta_deg, obs.theta_deg)
        value = table.phase[i, j]
        jac = [table.derivative("phase", p)[i, j] for p in parameters]
    elif obs.name == "extinction_ratio":
        assert table.cross_sections is not None
        r = int(np.searchsorted(table.wavelength_nm, obs.reference_nm))
        cext = table.cross_sections.cext_um2
        value = cext[i] / cext[r]
        jac = []
        for p in parameters:
            d = table.derivative("cext_um2", p)
            jac.append(value * (d[i] / cext[i] - d[r] / cext[r]))
    else:
        value = table.quantity(obs.name)[i]
        jac = [table.derivative(obs.name, p)[i] for p in parameters]
    return np.asarray(value), np.column_stack(jac)


def sample_labels(obs: Observation) -> list[str]:
    if obs.name == "phase":
        return [f"phase@{w:g}nm,{t:g}deg" for w, t in zip(obs.wavelength_nm, obs.theta_deg)]
    return [f"{obs.name}@{w:g}nm" for w in obs.wavelength_nm]


def optical_grid(obs: Sequence[Observation]) -> tuple[np.ndarray, np.ndarray]:
    """The wavelengths [nm] and angles [deg] of the table the optical observations need
    (empty without optical observations)."""
    if not obs:
        return np.zeros(0), np.zeros(0)
    wavelengths = np.unique(
        np.concatenate(
            [o.wavelength_nm for o in obs]
            + [np.array([o.reference_nm]) for o in obs if math.isfinite(o.reference_nm)]
        )
    )
    thetas = np.concatenate([o.theta_deg[np.isfinite(o.theta_deg)] for o in obs])
    theta = np.unique(thetas) if thetas.size else np.array([0.0, 180.0])
    return wavelengths, theta
