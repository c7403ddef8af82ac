"""The table's core: :class:`Table`, one constituent's phase function over wavelength and angle.

Its optional parts (:mod:`.components`, :mod:`.derivatives` and the in-memory
``table.diagnostics``) are present whole or not at all (``table.expansion is not
None``); :mod:`dustoptics.table` describes the stored and derived quantities.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from dustoptics._validation import as_float_array
from dustoptics.table import conversion, registry
from dustoptics.table.components import (
    RECORD_OF,
    RECORDS,
    CrossSections,
    Expansion,
    QuadratureRecord,
    ScatteringMatrix,
    _frozen,
    _per_wavelength,
    _same,
    grouped_fields,
    pmom_from_alpha1,
)
from dustoptics.table.derivatives import TableDerivatives
from dustoptics.table.provenance import (
    Provenance,
    _installed_version,
    _storable_text,
    canonical_json,
)
from dustoptics.table.schema import (
    AEROSOL_STANDARD_NAMES,
    DEFAULT_NAME,
    DERIVED,
    PHASE_NORMALIZATION,
    SCHEMA,
    STANDARD_NAMES,
    UNITS,
    WAVELENGTH_DIM,
)

if TYPE_CHECKING:
    import os

    import pandas as pd
    import xarray as xr

    from dustoptics.scattering.fit import FitResult
    from dustoptics.scattering.quadrature import QuadratureDiagnostics

__all__ = ["Table"]

#: CrossSections scaling method -> what a table lacks when it gives None.
_LACKS = {
    "efficiency": "has no mean geometric cross-section; {what} is undefined",
    "volume_coefficient": "has no number density; give number_density_per_m3 for {what}",
    "mass_coefficient": (
        "has no particle density or mean volume; {what} needs "
        "compute_optics(particle_density_kg_m3=...)"
    ),
}

#: Quantities the core holds itself (the records hold the other stored ones).
_CORE = ("wavelength_nm", "theta_deg", "phase", "g", "refractive_index")


def _wavelengths(value: Any) -> np.ndarray:
    wl = as_float_array("wavelength_nm", value)
    if wl.ndim != 1 or wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise ValueError(
            f"wavelength_nm must be a non-empty 1-D array of positive values; got {wl!r}"
        )
    if np.any(np.diff(wl) <= 0):
        raise ValueError("wavelength_nm must be strictly increasing")
    return wl


def _angles(value: Any) -> np.ndarray:
    theta = as_float_array("theta_deg", value)
    if theta.ndim != 1 or theta.size < 1:
        raise ValueError(
            f"theta_deg must be a non-empty 1-D array of angles; got shape {theta.shape}"
        )
    if theta[0] < 0.0 or theta[-1] > 180.0 or np.any(np.diff(theta) <= 0):
        raise ValueError(
            "theta_deg must increase strictly within [0, 180] degree; "
            f"got {theta[0]!r} .. {theta[-1]!r}"
        )
    return theta


def _phase(value: Any, n_wavelength: int, n_theta: int) -> np.ndarray:
    phase = as_float_array("phase", value)
    if phase.shape != (n_wavelength, n_theta):
        raise ValueError(
            f"phase must have shape (n_wavelength, n_theta) = ({n_wavelength}, {n_theta}); "
            f"got {phase.shape}"
        )
    if not np.all(np.isfinite(phase)) or np.any(phase < 0):
        raise ValueError("phase must be finite and nonnegative [sr^-1]")
    return phase


def _asymmetry(value: Any, n_wavelength: int) -> np.ndarray:
    if value is None:
        raise ValueError("g must be given, one asymmetry parameter per wavelength")
    g = _per_wavelength("g", value, n_wavelength)
    assert g is not None
    if np.any(np.abs(g) > 1):
        raise ValueError(f"g must satisfy |g| <= 1; got {g.tolist()}")
    return g


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


def _check_provenance(provenance: Any) -> None:
    if not isinstance(provenance, Provenance):
        raise TypeError(f"provenance must be a Provenance; got {type(provenance).__name__}")
    for i, source in enumerate(provenance.sources):
        for key in ("name", "role", "citation"):
            value = getattr(source, key, None)
            if isinstance(value, str):
                _storable_text(f"provenance.sources[{i}].{key}", value)


def _new_record(attribute: str, fields: Mapping[str, Any]) -> Any:
    """The record ``attribute`` made from ``fields`` (for :meth:`Table.replace`)."""
    made = grouped_fields(fields)
    if list(made) != [attribute] or attribute in fields:
        raise ValueError(
            f"{attribute} must be a {RECORDS[attribute].__name__} or a mapping of its fields; "
            f"got {dict(fields)!r}"
        )
    return made[attribute]


def _cross_sections_changed(old: CrossSections | None, new: CrossSections | None) -> bool:
    """Whether the extinction or scattering cross-sections differ (not only the scalars)."""
    if old is None or new is None:
        return old is not new
    return not (
        np.array_equal(old.cext_um2, new.cext_um2) and np.array_equal(old.csca_um2, new.csca_um2)
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
    refractive_index : numpy.ndarray of complex or None
        m = n + i k (k >= 0) used at each wavelength. [-]
    cross_sections : CrossSections or None
        Mean cross-sections per particle with the population's moments and
        number density, or None for a phase-function-only table (e.g. an
        analytic model).
    quadrature : QuadratureRecord or None
        Error estimates, node counts and node moments of the radius
        quadrature that computed the table.
    matrix : ScatteringMatrix or None
        F12, F33, F34 of the population (``compute_optics(polarization=True)``).
    expansion : Expansion or None
        Expansion coefficients in generalized spherical functions
        (``compute_optics(expansion=...)``).
    provenance : Provenance
        Inputs, sources, versions, quadrature and notes.
    diagnostics : QuadratureDiagnostics or None
        The radius panels, quadrature settings and size distribution of the
        computation that made the table (in memory only: files do not store
        them, :meth:`equals` ignores them; they follow from the provenance).
    derivatives : TableDerivatives or None
        Derivatives of the outputs with respect to named parameters
        (``compute_optics(derivatives=...)``), read by :meth:`derivative`.

    Examples
    --------
    >>> t = Table(wavelength_nm=[450.0, 550.0], theta_deg=[0.0, 180.0],
    ...           phase=[[0.1, 0.06], [0.1, 0.06]], g=[0.1, 0.1],
    ...           cross_sections=CrossSections(cext_um2=[2.0, 1.0], csca_um2=[1.0, 1.0]))
    >>> t.ssa.tolist(), t.expansion is None
    ([0.5, 1.0], True)
    """

    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray
    g: np.ndarray
    name: str = DEFAULT_NAME
    refractive_index: np.ndarray | None = None
    cross_sections: CrossSections | None = None
    quadrature: QuadratureRecord | None = None
    matrix: ScatteringMatrix | None = field(default=None, repr=False)
    expansion: Expansion | None = field(default=None, repr=False)
    provenance: Provenance = field(default_factory=Provenance)
    diagnostics: QuadratureDiagnostics | None = field(default=None, repr=False)
    derivatives: TableDerivatives | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty string; got {self.name!r}")
        _storable_text("name", self.name)
        wl = _wavelengths(self.wavelength_nm)
        theta = _angles(self.theta_deg)
        core = {
            "wavelength_nm": wl,
            "theta_deg": theta,
            "phase": _phase(self.phase, wl.size, theta.size),
            "g": _asymmetry(self.g, wl.size),
            "refractive_index": _refractive_index(self.refractive_index, wl.size),
        }
        for attribute, cls in RECORDS.items():
            record = getattr(self, attribute)
            if record is None:
                continue
            if not isinstance(record, cls):
                raise TypeError(
                    f"{attribute} must be a {cls.__name__} or None; got {type(record).__name__}"
                )
            record.check_grid(n_wavelength=wl.size, n_theta=theta.size)
        _check_provenance(self.provenance)
        for key, arr in core.items():
            object.__setattr__(self, key, None if arr is None else _frozen(arr))
        if self.derivatives is not None:
            self._check_derivatives(self.derivatives)

    def _check_derivatives(self, d: Any) -> None:
        if not isinstance(d, TableDerivatives):
            raise TypeError(f"derivatives must be a TableDerivatives; got {type(d).__name__}")
        for key, values in d.values.items():
            stored = self.quantity(key)
            if stored is None:
                raise ValueError(f"derivatives of {key!r} given, but the table has no {key!r}")
            want = (len(d.parameters), *np.shape(stored))
            if values.shape != want:
                raise ValueError(
                    f"derivatives of {key!r} must have shape (n_parameter, ...) = {want}; "
                    f"got {values.shape}"
                )

    def quantity(self, name: str) -> Any:
        """A stored or derived quantity by its schema name (:data:`~dustoptics.table.UNITS`).

        Stored quantities of an absent record are None (``table.quantity("alpha1")``
        is None without :attr:`expansion`); derived ones are computed (and
        raise ``ValueError`` when the table lacks what they need).  Writers
        and sweeps that go through a list of names read the table this way.

        Raises
        ------
        ValueError
            ``name`` is not a quantity of the schema.
        """
        if name in _CORE:
            return getattr(self, name)
        attribute = RECORD_OF.get(name)
        if attribute is not None:
            record = getattr(self, attribute)
            return None if record is None else getattr(record, name)
        if name in DERIVED:
            return getattr(self, name)
        raise ValueError(
            f"quantity must be a stored or derived quantity of the table schema {SCHEMA}; got {name!r}"
        )

    # ------------------------------------------------------------ xarray, pandas, files

    def derived(self) -> dict[str, np.ndarray]:
        """The derived quantities this table defines (see :data:`DERIVED`), by name.

        ``cabs_um2`` and ``ssa`` need cross-sections; ``qext``, ``qsca`` and
        ``qabs`` also a mean geometric cross-section; the ``beta_*``
        coefficients a number density.
        """
        if self.cross_sections is None:
            return {}
        return {key: getattr(self, key) for key in self.cross_sections.derived_names()}

    def variable_attributes(self, key: str) -> dict[str, str]:
        """``long_name``, ``units`` (udunits2), ``standard_name`` (where CF has
        one) and, for derived quantities, ``derived_from`` of variable ``key``."""
        unit, meaning = UNITS[key]
        attrs = {"long_name": meaning, "units": unit}
        standard = STANDARD_NAMES.get(key)
        cs = self.cross_sections
        if standard is None and cs is not None and cs.mean_geometric_cross_section_um2 is not None:
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
                if self.quadrature is not None
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
        [degree]; variables named like the stored quantities (``phase``,
        ``g``, ``cext_um2``, ``alpha1``, ...; the refractive index as
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
        >>> t = Table(wavelength_nm=[450.0, 550.0], theta_deg=[0.0, 90.0, 180.0],
        ...           phase=[[0.2, 0.05, 0.1], [0.3, 0.04, 0.1]], g=[0.5, 0.6])
        >>> ds = t.to_xarray()
        >>> round(float(ds.phase.sel(wavelength_nm=550.0).interp(theta_deg=45.0)), 12)
        0.17
        >>> ds.theta_deg.attrs["units"]
        'degree'
        """
        return conversion.to_dataset(self)

    @classmethod
    def from_xarray(cls, ds: xr.Dataset) -> Table:
        """The table a :meth:`to_xarray` dataset holds (an exact inverse).

        Derived variables (``ssa``, ``cabs_um2``, ...) are not read: the table
        derives them again from the stored ones.

        Parameters
        ----------
        ds : xarray.Dataset
            A dataset with ``dustoptics_schema`` = :data:`~dustoptics.table.SCHEMA`, e.g. from
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
        return cls(**conversion.table_fields(ds))

    def to_dataframe(self) -> pd.DataFrame:
        """The per-wavelength quantities as a :class:`pandas.DataFrame`.

        One row per wavelength (index ``wavelength_nm`` [nm]); columns ``g``,
        the cross-sections, error estimates, node counts, ``refractive_index_real``
        and ``_imag`` and the derived quantities, each where the table has it.
        The units are in the column names (see :data:`UNITS`).

        Examples
        --------
        >>> t = Table(wavelength_nm=[450.0, 550.0], theta_deg=[0.0, 180.0],
        ...           phase=[[0.1, 0.06], [0.1, 0.06]], g=[0.1, 0.1],
        ...           cross_sections=CrossSections(cext_um2=[2.0, 1.0], csca_um2=[1.0, 1.0]))
        >>> t.to_dataframe()["ssa"].tolist()
        [0.5, 1.0]
        """
        import pandas as pd

        index = pd.Index(np.array(self.wavelength_nm), name=WAVELENGTH_DIM)
        columns = {
            key: np.array(values) for key, values in conversion.per_wavelength_values(self).items()
        }
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
        if not registry._WRITERS:
            raise RuntimeError(
                "Table.save: no table file writer is registered; import dustoptics.io "
                "(import dustoptics does), which registers the netCDF-4 writer"
            )
        target = Path(path)
        if not target.suffix:
            target = target.with_name(target.name + next(iter(registry._WRITERS)))
        writer = registry._WRITERS.get(target.suffix.lower())
        if writer is None:
            raise ValueError(
                f"path {str(target)!r}: unknown table file suffix {target.suffix!r}; use one of "
                f"{', '.join(registry._WRITERS)} (the first is the default). "
                "Renderer formats (CSV, GLSL, textures) are written by dustoptics.io"
            )
        return writer(self, target, overwrite=overwrite)

    def replace(self, **changes: Any) -> Table:
        """A copy with some fields changed (validated again).

        A record may be given as a mapping of the fields to change in the
        table's own record, ``table.replace(cross_sections={"number_density_per_m3": 1e8})``,
        or, when the table has none, of the fields of a new one.

        The in-memory :attr:`diagnostics` describe the computation that made
        the numbers, so they are dropped when the phase function, the
        wavelengths or the extinction and scattering cross-sections change,
        unless ``changes`` gives them.  Likewise the scattering :attr:`matrix`
        and the :attr:`expansion` are dropped when the phase function, angles
        or wavelengths change, and the :attr:`derivatives` when the numbers
        they differentiate change.

        Raises
        ------
        ValueError
            A mapping for a record the table does not have that lacks a field
            the record needs, or names a field it does not have.
        """
        for key, value in changes.items():
            if key in RECORDS and isinstance(value, Mapping):
                record = getattr(self, key)
                changes[key] = (
                    _new_record(key, value) if record is None else record.replace(**value)
                )
        numbers = set(changes) & {"phase", "theta_deg", "wavelength_nm", "g"}
        if "cross_sections" in changes and _cross_sections_changed(
            self.cross_sections, changes["cross_sections"]
        ):
            numbers.add("cross_sections")
        stale: list[str] = []
        if numbers - {"theta_deg", "g"}:
            stale.append("diagnostics")
        # The matrix and its expansion belong to the phase function (F11) they
        # were computed with; derivatives to the numbers they differentiate.
        if numbers & {"phase", "theta_deg", "wavelength_nm"}:
            stale += ["matrix", "expansion"]
        if numbers:
            stale.append("derivatives")
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

    def _need_cross_sections(self, what: str) -> CrossSections:
        if self.cross_sections is None:
            raise ValueError(
                f"table {self.name!r} holds a phase function only; {what} needs cross-sections"
            )
        return self.cross_sections

    def _scaled(self, what: str, scaling: str, process: str) -> np.ndarray:
        """Cross-section ``c{process}_um2`` scaled by the :class:`CrossSections` method ``scaling``."""
        cs = self._need_cross_sections(what)
        value = getattr(cs, scaling)(getattr(cs, f"c{process}_um2"))
        if value is None:
            raise ValueError(f"table {self.name!r} " + _LACKS[scaling].format(what=what))
        return value

    @property
    def cabs_um2(self) -> np.ndarray:
        """Mean absorption cross-section per particle, cext - csca. [um^2]"""
        return self._need_cross_sections("cabs_um2").cabs_um2

    @property
    def ssa(self) -> np.ndarray:
        """Single-scattering albedo csca / cext. [-]"""
        return self._need_cross_sections("ssa").ssa

    @property
    def qext(self) -> np.ndarray:
        """Extinction efficiency cext / (pi <r^2>). [-]"""
        return self._scaled("qext", "efficiency", "ext")

    @property
    def qsca(self) -> np.ndarray:
        """Scattering efficiency csca / (pi <r^2>). [-]"""
        return self._scaled("qsca", "efficiency", "sca")

    @property
    def qabs(self) -> np.ndarray:
        """Absorption efficiency cabs / (pi <r^2>). [-]"""
        return self._scaled("qabs", "efficiency", "abs")

    @property
    def beta_ext_per_m(self) -> np.ndarray:
        """Extinction coefficient N cext at the number density. [m^-1]"""
        return self._scaled("beta_ext_per_m", "volume_coefficient", "ext")

    @property
    def beta_sca_per_m(self) -> np.ndarray:
        """Scattering coefficient N csca at the number density. [m^-1]"""
        return self._scaled("beta_sca_per_m", "volume_coefficient", "sca")

    @property
    def beta_abs_per_m(self) -> np.ndarray:
        """Absorption coefficient N cabs at the number density. [m^-1]"""
        return self._scaled("beta_abs_per_m", "volume_coefficient", "abs")

    @property
    def lidar_ratio_sr(self) -> np.ndarray:
        """Extinction-to-backscatter ratio 4 pi <C_ext> / <C_back>. [sr]"""
        cs = self._need_cross_sections("lidar_ratio_sr")
        if cs.cback_um2 is None:
            raise ValueError(f"table {self.name!r} has no backscattering cross-section cback_um2")
        return 4.0 * np.pi * cs.cext_um2 / cs.cback_um2

    @property
    def mass_ext_m2_per_kg(self) -> np.ndarray:
        """Mass extinction coefficient <C_ext> / (rho <V>). [m^2 kg^-1]"""
        return self._scaled("mass_ext_m2_per_kg", "mass_coefficient", "ext")

    @property
    def mass_sca_m2_per_kg(self) -> np.ndarray:
        """Mass scattering coefficient <C_sca> / (rho <V>). [m^2 kg^-1]"""
        return self._scaled("mass_sca_m2_per_kg", "mass_coefficient", "sca")

    @property
    def mass_abs_m2_per_kg(self) -> np.ndarray:
        """Mass absorption coefficient <C_abs> / (rho <V>). [m^2 kg^-1]"""
        return self._scaled("mass_abs_m2_per_kg", "mass_coefficient", "abs")

    @property
    def pmom(self) -> np.ndarray:
        """DISORT's phase-function moments alpha1_l / (2 l + 1), shape (n_wavelength, n_order). [-]"""
        if self.expansion is None:
            raise ValueError(
                f"table {self.name!r} has no expansion coefficients; use compute_optics(expansion=True)"
            )
        return pmom_from_alpha1(self.expansion.alpha1)

    # ------------------------------------------------------------ derivatives

    def _derivative_pair(self, quantity: str, parameter: str) -> tuple[np.ndarray, np.ndarray]:
        if self.derivatives is None:
            raise ValueError(
                f"table {self.name!r} holds no derivatives; compute it with "
                "compute_optics(..., derivatives=(...))"
            )
        return self.derivatives.pair(quantity, parameter, self.cross_sections)

    @property
    def derivative_quantities(self) -> tuple[str, ...]:
        """The quantities :meth:`derivative` gives (stored, then derived), or ()."""
        return () if self.derivatives is None else self.derivatives.quantities

    def derivative(self, quantity: str, parameter: str) -> np.ndarray:
        """d(quantity)/d(parameter), per wavelength (and angle).

        Parameters
        ----------
        quantity : str
            ``"phase"``, ``"f12"``, ``"f33"``, ``"f34"`` (shape (n_wavelength,
            n_theta)), ``"g"``, ``"cext_um2"``, ``"csca_um2"``, ``"cback_um2"``,
            the expansion coefficients ``"alpha1"`` ... ``"beta2"`` (shape
            (n_wavelength, n_order)), ``"lidar_ratio_sr"`` (the quotient rule on the size
            integral's own cext and cback sums; by the chain rule in files that do not store
            it), or the derived ``"ssa"`` and ``"cabs_um2"`` (chain rule), where the table has
            them (:attr:`derivative_quantities`).
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
        return None if self.quadrature is None else self.quadrature.achieved_error

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
        record = self.quadrature
        if record is None or record.cross_section_error_estimate is None or "rtol" not in q:
            raise ValueError(
                f"table {self.name!r} was not computed by quadrature; it has no convergence record"
            )
        return (record.error_estimate <= q["rtol"]) & (
            record.cross_section_error_estimate <= q["cross_section_rtol"]
        )

    def equals(self, other: Table) -> bool:
        """Whether two tables hold bit-identical data and equal provenance.

        :attr:`diagnostics` (in memory only) are not compared.
        """
        if not isinstance(other, Table):
            return False
        return (
            all(_same(getattr(self, k), getattr(other, k)) for k in (*_CORE, *RECORDS))
            and self.name == other.name
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
        >>> t = Table(wavelength_nm=[550.0], theta_deg=[0.0, 90.0, 180.0],
        ...           phase=[[0.2, 0.05, 0.1]], g=[0.5])
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
        if not registry._FITTERS:
            raise RuntimeError(
                "Table.fit: no fitter is registered; import dustoptics.scattering "
                "(import dustoptics does), which registers dustoptics.scattering.fit.fit_table"
            )
        return registry._FITTERS[0](
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
        g = f"g {self.g.min():.4g}-{self.g.max():.4g}"
        if self.cross_sections is not None:
            cext, ssa = self.cross_sections.cext_um2, self.cross_sections.ssa
            lines.append(
                f"  cext {cext.min():.4g}-{cext.max():.4g} um2, "
                f"ssa {ssa.min():.4g}-{ssa.max():.4g}, {g}"
            )
        else:
            lines.append(f"  phase function only, {g}")
        described = _described_inputs(self.provenance.inputs)
        if described:
            lines.append("  " + "; ".join(described))
        if self.quadrature is not None:
            lines.append("  " + _quadrature_line(self.quadrature, self.provenance.quadrature))
        lines.append(f"  input_hash {self.provenance.input_hash[:12]}")
        return "\n".join(lines)


def _described_inputs(inputs: Mapping[str, Any]) -> list[str]:
    """The refractive index and size distribution of a provenance, for :meth:`Table.__repr__`."""
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
    return described


def _quadrature_line(record: QuadratureRecord, q: Mapping[str, Any]) -> str:
    """Weighting, achieved error, tolerance and node counts, for :meth:`Table.__repr__`."""
    rtol = f" (rtol {q['rtol']:g})" if "rtol" in q else ""
    nodes = ""
    if record.n_nodes is not None:
        nodes = f", {int(record.n_nodes.min())}-{int(record.n_nodes.max())} radius nodes"
    weighting = f"{q['weighting']}-weighted, " if "weighting" in q else ""
    return f"{weighting}phase error <= {record.achieved_error:.2g}{rtol}{nodes}"
