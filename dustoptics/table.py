"""The table as data: one model for a computed optical table and its provenance.

Every exporter writes a :class:`Table` and every reader returns one, so a table
read back from any format has the same fields, units and provenance as the one
that was written.  A table describes one constituent of an atmosphere (a dust
population, a gas): its phase function over wavelength and scattering angle,
its mean cross-sections per particle, and, when the user gives a number
density, its volume coefficients.

Stored quantities (and their units)
-----------------------------------
``wavelength_nm`` [nm], ``theta_deg`` [deg] (0 = forward scattering),
``phase`` [sr^-1] normalized so that 2 pi int_{-1}^{1} P dmu = 1,
``cext_um2`` and ``csca_um2`` [um^2] (mean cross-sections per particle),
``g`` [-] (asymmetry parameter of ``phase``), the quadrature's error
estimates [-], ``mean_geometric_cross_section_um2`` [um^2] (pi <r^2>) and
``number_density_per_m3`` [m^-3].

Everything else is derived, never stored twice: ``cabs_um2 = cext - csca``,
``ssa = csca / cext``, ``qext = cext / (pi <r^2>)``, and
``beta_ext_per_m = N cext`` (and likewise for scattering and absorption), so a
file can never hold an albedo that disagrees with its cross-sections.

Provenance
----------
:class:`Provenance` records every input parameter (``inputs``, a JSON-ready
mapping), the sources with their citations, the software versions, the
quadrature settings and the achieved error.  :attr:`Provenance.input_hash` is
the SHA-256 of the canonical JSON of ``inputs`` (sorted keys, shortest
round-trip floats): two tables built from the same inputs carry the same hash,
whatever the software version or the machine.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, is_dataclass, replace
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from typing import Any

import numpy as np

from dustoptics._validation import as_float_array, check_positive

__all__ = [
    "PHASE_NORMALIZATION",
    "SOFTWARE",
    "UNITS",
    "Provenance",
    "Source",
    "Table",
    "canonical_json",
    "plain",
    "software_versions",
]

#: How every phase function in the package is normalized.
PHASE_NORMALIZATION = "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)"

#: Distributions whose versions a table records.
SOFTWARE = ("dustoptics", "miepython", "numpy", "scipy", "numba", "h5py")

#: Unit and meaning of every quantity of a :class:`Table` (stored or derived).
UNITS: Mapping[str, tuple[str, str]] = {
    "wavelength_nm": ("nm", "vacuum wavelength"),
    "theta_deg": ("deg", "scattering angle, 0 = forward"),
    "phase": ("sr^-1", "phase function, " + PHASE_NORMALIZATION),
    "cext_um2": ("um^2", "mean extinction cross-section per particle"),
    "csca_um2": ("um^2", "mean scattering cross-section per particle"),
    "cabs_um2": ("um^2", "mean absorption cross-section per particle, cext - csca"),
    "qext": ("1", "extinction efficiency cext / (pi <r^2>)"),
    "qsca": ("1", "scattering efficiency csca / (pi <r^2>)"),
    "qabs": ("1", "absorption efficiency cabs / (pi <r^2>)"),
    "ssa": ("1", "single-scattering albedo csca / cext"),
    "g": ("1", "asymmetry parameter 2 pi int P mu dmu"),
    "error_estimate": ("1", "estimated largest relative error of the phase function"),
    "cross_section_error_estimate": (
        "1",
        "estimated error of cext, csca (relative) and g (absolute)",
    ),
    "mean_geometric_cross_section_um2": ("um^2", "pi <r^2> of the size distribution"),
    "number_density_per_m3": ("m^-3", "number density at which beta is given"),
    "beta_ext_per_m": ("m^-1", "extinction coefficient N cext"),
    "beta_sca_per_m": ("m^-1", "scattering coefficient N csca"),
    "beta_abs_per_m": ("m^-1", "absorption coefficient N cabs"),
}

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


def _installed_version(distribution: str) -> str:
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


@dataclass(frozen=True, eq=False)
class Table:
    """One constituent's optical table over wavelength and scattering angle.

    Construct it from computed results (:meth:`from_optics`) or read it from a
    file; every array is validated and stored read-only.

    Attributes
    ----------
    name : str
        Name of the table (a preset name, or what the user chose).
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Strictly increasing vacuum wavelengths. [nm]
    theta_deg : numpy.ndarray, shape (n_theta,)
        Strictly increasing scattering angles from 0 to 180. [deg]
    phase : numpy.ndarray, shape (n_wavelength, n_theta)
        Phase function, 2 pi int P dmu = 1. [sr^-1]
    g : numpy.ndarray, shape (n_wavelength,)
        Asymmetry parameter of ``phase``. [-]
    cext_um2, csca_um2 : numpy.ndarray or None
        Mean extinction and scattering cross-sections per particle, or None
        for a phase-function-only table (e.g. an analytic model). [um^2]
    error_estimate : numpy.ndarray or None
        Estimated largest relative error of ``phase`` per wavelength. [-]
    cross_section_error_estimate : numpy.ndarray or None
        Estimated error of the cross-sections (relative) and g (absolute). [-]
    mean_geometric_cross_section_um2 : float or None
        pi <r^2> of the size distribution (None for molecules). [um^2]
    number_density_per_m3 : float or None
        Number density at which the ``beta_*`` coefficients are given. [m^-3]
    provenance : Provenance
        Inputs, sources, versions, quadrature and notes.
    """

    name: str
    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray
    g: np.ndarray
    cext_um2: np.ndarray | None = None
    csca_um2: np.ndarray | None = None
    error_estimate: np.ndarray | None = None
    cross_section_error_estimate: np.ndarray | None = None
    mean_geometric_cross_section_um2: float | None = None
    number_density_per_m3: float | None = None
    provenance: Provenance = field(default_factory=Provenance)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty string; got {self.name!r}")
        wl = as_float_array("wavelength_nm", self.wavelength_nm)
        if wl.ndim != 1 or wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
            raise ValueError(
                f"wavelength_nm must be a non-empty 1-D array of positive values; got {wl!r}"
            )
        if np.any(np.diff(wl) <= 0):
            raise ValueError("wavelength_nm must be strictly increasing")
        theta = as_float_array("theta_deg", self.theta_deg)
        if theta.ndim != 1 or theta.size < 2:
            raise ValueError(
                f"theta_deg must be a 1-D array of at least 2 angles; got shape {theta.shape}"
            )
        if theta[0] != 0.0 or theta[-1] != 180.0 or np.any(np.diff(theta) <= 0):
            raise ValueError(
                "theta_deg must increase strictly from exactly 0 to exactly 180 deg; "
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
        arrays: dict[str, Any] = {
            "wavelength_nm": wl,
            "theta_deg": theta,
            "phase": phase,
            "g": _per_wavelength("g", self.g, n),
            "cext_um2": _per_wavelength("cext_um2", self.cext_um2, n),
            "csca_um2": _per_wavelength("csca_um2", self.csca_um2, n),
            "error_estimate": _per_wavelength("error_estimate", self.error_estimate, n),
            "cross_section_error_estimate": _per_wavelength(
                "cross_section_error_estimate", self.cross_section_error_estimate, n
            ),
        }
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
        for key in ("mean_geometric_cross_section_um2", "number_density_per_m3"):
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, check_positive(key, value))
        if not isinstance(self.provenance, Provenance):
            raise TypeError(
                f"provenance must be a Provenance; got {type(self.provenance).__name__}"
            )
        for key, arr in arrays.items():
            if arr is not None:
                arr = np.array(arr, dtype=np.float64, copy=True)
                arr.setflags(write=False)
            object.__setattr__(self, key, arr)

    # ------------------------------------------------------------ construction

    @classmethod
    def from_optics(
        cls,
        optics: Any,
        *,
        name: str,
        inputs: Mapping[str, Any],
        sources: tuple[Source, ...] = (),
        notes: tuple[str, ...] = (),
        number_density_per_m3: float | None = None,
    ) -> Table:
        """A table from :func:`dustoptics.scattering.optics.compute_optics` results.

        Parameters
        ----------
        optics : dustoptics.scattering.optics.OpticsTable
            Computed optics.
        name : str
            Table name.
        inputs : Mapping
            Every input parameter, JSON-ready (hashed into the provenance).
        sources : tuple of Source
            Materials and models with citations.
        notes : tuple of str
            Remarks recorded in the provenance.
        number_density_per_m3 : float, optional
            Number density for the ``beta_*`` coefficients. [m^-3]
        """
        quadrature = {
            "weighting": optics.weighting,
            "rtol": float(optics.rtol),
            "cross_section_rtol": float(optics.cross_section_rtol),
            "settings": plain(optics.settings),
            "n_nodes": np.asarray(optics.n_nodes, dtype=np.int64).tolist(),
            "converged": bool(np.all(optics.converged)),
        }
        return cls(
            name=name,
            wavelength_nm=optics.wavelength_nm,
            theta_deg=optics.theta_deg,
            phase=optics.phase,
            g=optics.g,
            cext_um2=optics.cext_um2,
            csca_um2=optics.csca_um2,
            error_estimate=optics.error_estimate,
            cross_section_error_estimate=optics.cross_section_error_estimate,
            mean_geometric_cross_section_um2=float(optics.mean_geometric_cross_section_um2),
            number_density_per_m3=number_density_per_m3,
            provenance=Provenance(
                inputs=inputs, sources=sources, quadrature=quadrature, notes=notes
            ),
        )

    def replace(self, **changes: Any) -> Table:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)

    # ------------------------------------------------------------ derived

    @property
    def mu(self) -> np.ndarray:
        """cos(theta). [-]"""
        return np.cos(np.deg2rad(self.theta_deg))

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
    def achieved_error(self) -> float | None:
        """Largest phase-function error estimate over wavelength, or None. [-]"""
        if self.error_estimate is None:
            return None
        return float(np.max(self.error_estimate))

    def equals(self, other: Table) -> bool:
        """Whether two tables hold bit-identical data and equal provenance."""
        if not isinstance(other, Table):
            return False
        for key in (
            "wavelength_nm",
            "theta_deg",
            "phase",
            "g",
            "cext_um2",
            "csca_um2",
            "error_estimate",
            "cross_section_error_estimate",
        ):
            a, b = getattr(self, key), getattr(other, key)
            if (a is None) != (b is None):
                return False
            if a is not None and not np.array_equal(a, b):
                return False
        return (
            self.name == other.name
            and self.mean_geometric_cross_section_um2 == other.mean_geometric_cross_section_um2
            and self.number_density_per_m3 == other.number_density_per_m3
            and self.provenance.to_dict() == other.provenance.to_dict()
        )

    def phase_at(self, theta_deg: Any) -> np.ndarray:
        """Phase function at other angles by linear interpolation in angle.

        This is the interpolation a renderer applies to the table (and that
        :func:`dustoptics.scattering.phase.sphere_integral` integrates exactly); at angles
        of the table's own grid it returns the stored values unchanged.

        Parameters
        ----------
        theta_deg : array_like
            Angles within [0, 180]. [deg]

        Returns
        -------
        numpy.ndarray, shape (n_wavelength, n_angles)
            Interpolated phase function. [sr^-1]
        """
        t = as_float_array("theta_deg", theta_deg)
        if t.ndim != 1 or not np.all(np.isfinite(t)) or np.any((t < 0) | (t > 180)):
            raise ValueError("theta_deg must be a 1-D array of angles within [0, 180] deg")
        grid = self.theta_deg
        i = np.clip(np.searchsorted(grid, t, side="right") - 1, 0, grid.size - 2)
        frac = (t - grid[i]) / (grid[i + 1] - grid[i])
        return self.phase[:, i] * (1.0 - frac) + self.phase[:, i + 1] * frac

    def __repr__(self) -> str:
        kind = "phase + cross-sections" if self.has_cross_sections else "phase only"
        return (
            f"Table(name={self.name!r}, {self.wavelength_nm.size} wavelengths "
            f"{self.wavelength_nm[0]:g}-{self.wavelength_nm[-1]:g} nm, "
            f"{self.theta_deg.size} angles, {kind}, input_hash={self.provenance.input_hash[:12]})"
        )
