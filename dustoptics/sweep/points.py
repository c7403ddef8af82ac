"""One point of a sweep read back as a :class:`~dustoptics.table.Table`.

:func:`point_table` selects a point of a sweep's dataset (:func:`dustoptics.sweep.sweep`,
in memory or opened from its Zarr or netCDF store) by its axis values and returns
the table a single build of that point gives, as far as the sweep stores it: the
phase function and ``g``, the cross-sections and the quadrature's error estimates
and nodes (for a Mie model), the scattering matrix (``f12``, ``f33``, ``f34`` and
``matrix_error_estimate``) and the expansion coefficients (``alpha1`` .. ``beta2``
and ``expansion_error_estimate`` over the ``order`` dimension) where the sweep
computed them, and the point's provenance inputs (whose hash is checked against
the one the sweep recorded).  The values are the stored ones, not copies
rounded or resampled.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from dustoptics.sweep.chunk import EXPANSION, MATRIX
from dustoptics.table import (
    CrossSections,
    Expansion,
    Provenance,
    QuadratureRecord,
    ScatteringMatrix,
    Table,
)

__all__ = ["point_table"]


def point_table(ds: Any, point: Mapping[str, float], *, name: str | None = None) -> Table:
    """The table of one point of a sweep.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep (:func:`dustoptics.sweep.sweep`).
    point : Mapping
        The point: every axis of the sweep (its dotted key) -> one of its values,
        e.g. ``{"size_distribution.r_eff_um": 1.6}``.
    name : str, optional
        The table's name (default: the table's default name).

    Returns
    -------
    Table
        ``cross_sections`` and ``quadrature`` for a Mie model (None for an
        analytic one, whose sweep holds NaN there), ``matrix`` and ``expansion``
        where the sweep computed them (None otherwise), and the point's
        provenance inputs.

    Raises
    ------
    ValueError
        ``point`` does not name every axis once, names something that is not an
        axis, or a value the axis does not hold; or the stored provenance does
        not match its recorded hash (a damaged store).
    """
    one = ds.isel(_point_index(ds, point)).load()
    record = json.loads(str(one.provenance.values))
    provenance = Provenance(inputs=record["inputs"])
    if provenance.input_hash != record["input_hash"]:
        raise ValueError(
            f"point {dict(point)}: its stored inputs do not match their recorded hash "
            f"{record['input_hash']}; the store is damaged"
        )
    fields: dict[str, Any] = {
        "wavelength_nm": np.asarray(one.wavelength_nm.values, dtype=np.float64),
        "theta_deg": np.asarray(one.theta_deg.values, dtype=np.float64),
        "phase": _values(one, "phase"),
        "g": _values(one, "g"),
        "provenance": provenance,
        **_mie_records(one),
    }
    if "f12" in one:
        fields["matrix"] = ScatteringMatrix(**{k: _values(one, k) for k in MATRIX})
    if "alpha1" in one:
        fields["expansion"] = Expansion(**{k: _values(one, k) for k in EXPANSION})
    if name is not None:
        fields["name"] = name
    return Table(**fields)


def _point_index(ds: Any, point: Mapping[str, float]) -> dict[str, int]:
    """The index along every axis of the point that ``point`` names by its values."""
    axes = [d for d in ds.phase.dims if d not in ("wavelength_nm", "theta_deg")]
    extra = sorted(set(point) - set(axes))
    missing = [a for a in axes if a not in point]
    if extra or missing:
        raise ValueError(
            f"point must give one value of every axis of the sweep, {axes}; "
            + (f"got {extra} which are not axes" if extra else f"missing {missing}")
        )
    index: dict[str, int] = {}
    for axis in axes:
        hit = np.flatnonzero(np.asarray(ds[axis].values) == point[axis])
        if hit.size != 1:
            raise ValueError(
                f"point: {axis} = {point[axis]!r} is not a value of the sweep's axis; its "
                f"values: {np.asarray(ds[axis].values).tolist()}"
            )
        index[axis] = int(hit[0])
    return index


def _values(one: Any, key: str) -> np.ndarray:
    """A variable of one point, (wavelength[, angle or order]) in that order."""
    var = one[key]
    order = ["wavelength_nm"] + [d for d in var.dims if d != "wavelength_nm"]
    return np.asarray(var.transpose(*order).values, dtype=np.float64)


def _mie_records(one: Any) -> dict[str, Any]:
    """The cross-sections and quadrature records of a Mie point (none for an analytic
    one: the sweep holds NaN there)."""
    cext = _values(one, "cext_um2")
    if not np.all(np.isfinite(cext)):
        return {}
    return {
        "cross_sections": CrossSections(
            cext_um2=cext,
            csca_um2=_values(one, "csca_um2"),
            mean_geometric_cross_section_um2=float(one.mean_geometric_cross_section_um2.values),
        ),
        "quadrature": QuadratureRecord(
            error_estimate=_values(one, "error_estimate"),
            cross_section_error_estimate=_values(one, "cross_section_error_estimate"),
            n_nodes=_values(one, "n_nodes").astype(np.int64),
        ),
    }
