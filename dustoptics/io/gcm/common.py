"""What the Mars GCMs' dust files share: the build's particles over a grid of radii.

A :class:`~dustoptics.table.Table` holds one size distribution; a GCM dust file holds
the extinction efficiency Q_ext, the single-scattering albedo (or Q_sca) and the
asymmetry parameter g for each of a grid of particle radii.  The formats therefore do
not read the table's numbers: they read what the table was made of, from its
provenance (the configuration's material and size distribution, which a preset or a
TOML file recorded there), and compute the cross-sections again over the grid:

- :func:`gcm_particles`: the material and size distribution of a configuration's table
  (a table of :func:`dustoptics.scattering.optics.compute_optics` records index values at
  its own wavelengths only: taken when they are one constant, refused otherwise; analytic
  phase models have no particles);
- :func:`distribution_at`: the distribution whose effective radius is one radius of the
  grid: by default the build's own distribution scaled in radius (every length
  parameter ``*_um`` times r / r_eff, so the shape, the effective variance and the
  modes' ratios stay the build's); with ``v_eff`` given, the build's family (or Hansen
  & Travis' modified gamma for families without ``r_eff_um`` and ``v_eff``) at that
  r_eff and v_eff; with ``single=True``, spheres of that one radius;
- :func:`grid_optics`: Q_ext, Q_sca and g per radius and wavelength
  (:func:`~dustoptics.scattering.optics.compute_optics`, cross-section weighted);
- :func:`planck_band_average`: band means weighted by the Planck function, with
  Gauss-Legendre nodes in wavenumber.

Q is per mean geometric cross-section: Q_ext = <C_ext> / (pi <r^2>).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dustoptics._validation import BudgetError
from dustoptics.io.registry import option
from dustoptics.models.config import MaterialConfig, ModeConfig, SizeDistributionConfig
from dustoptics.particles.custom_sizedist import from_dict
from dustoptics.particles.sizedist import SIZE_DISTRIBUTIONS, Monodisperse, SizeDistribution
from dustoptics.scattering.optics import (
    WORK_BUDGET,
    compute_optics,
    estimate_cost,
    optics_request,
)

__all__ = [
    "CROSS_SECTION_RTOL",
    "Bands",
    "GcmOptions",
    "GcmParticles",
    "GridOptics",
    "check_radii",
    "distribution_at",
    "gcm_particles",
    "grid_optics",
    "planck_band_average",
    "planck_bands",
    "planck_wavenumber",
    "scalable_radii",
]

#: Relative tolerance of <C_ext>, <C_sca> (absolute for g) of each grid point: below the
#: files' printed digits (7 for the LMD layout, 4 for the Ames layout). [-]
CROSS_SECTION_RTOL = 1e-5

#: Phase-function tolerance of each grid point's quadrature; the files hold no phase
#: function, so it only has to let the cross-sections converge. [-]
_PHASE_RTOL = 1e-3

#: The few angles the quadrature checks the phase function at (the files hold none). [deg]
_THETA_DEG = np.linspace(0.0, 180.0, 7)

#: Second radiation constant h c / k_B. [cm K] (CODATA 2018)
_C2_CM_K = 1.438776877


@dataclass(frozen=True)
class GcmOptions:
    """Options of every GCM dust file: the radius grid and the size distribution's width."""

    gcm_radii_um: tuple[float, ...] | None = option(
        help="GCM dust files: radius grid in um, comma-separated: effective radii (the Ames "
        "rows are single radii unless --gcm-v-eff is given); default the model's own grid "
        "(LMD: 50 from 0.001 to 10 um; Ames: 20 from 0.1 to 50 um)",
        type="floats",
        metavar="R[,R...]",
    )
    gcm_v_eff: float | None = option(
        help="GCM dust files: effective variance at every radius (default: the build's "
        "distribution scaled to each radius; single radii for the Ames files)",
        type="positive_float",
        metavar="V",
    )

    def check(self, wavelength_nm: Any) -> None:
        """Refuse a bad radius grid or v_eff before the table is computed."""
        del wavelength_nm
        check_radii(self.gcm_radii_um)
        if self.gcm_v_eff is not None and not (
            math.isfinite(self.gcm_v_eff) and self.gcm_v_eff > 0
        ):
            raise ValueError(f"gcm_v_eff must be a finite number > 0; got {self.gcm_v_eff!r}")


def check_radii(radii_um: Sequence[float] | None) -> np.ndarray | None:
    """The radius grid as an array, or None; positive, finite and strictly increasing. [um]"""
    if radii_um is None:
        return None
    r = np.asarray(radii_um, dtype=np.float64)
    if r.ndim != 1 or r.size < 1 or not np.all(np.isfinite(r)) or np.any(r <= 0):
        raise ValueError(
            f"gcm_radii_um must be one or more finite radii > 0 [um]; got {list(radii_um)!r}"
        )
    if np.any(np.diff(r) <= 0):
        raise ValueError(f"gcm_radii_um must be strictly increasing; got {r.tolist()!r}")
    return r


@dataclass(frozen=True)
class GcmParticles:
    """The particles a configuration's table was made of.

    Attributes
    ----------
    name : str
        The table's name.
    input_hash : str
        The table's input hash (its provenance's).
    material : object
        The refractive index, as :func:`~dustoptics.scattering.optics.compute_optics` takes it.
    distribution : Mapping
        The size distribution as the configuration records it (``model`` and its
        parameters, radii in [um]; ``modes`` for a multimodal one).
    wavelength_range_nm : tuple of float
        Where the refractive index is defined. [nm]
    """

    name: str
    input_hash: str
    material: Any
    distribution: Mapping[str, Any]
    wavelength_range_nm: tuple[float, float]


def gcm_particles(table: Any, *, format_name: str) -> GcmParticles:
    """The material and size distribution recorded in a table's provenance.

    A configuration's table (a preset, a TOML file) records its material, which gives
    the index at any wavelength.  A table of
    :func:`~dustoptics.scattering.optics.compute_optics` records the index's values at
    its own wavelengths only: it is taken when they are all the same (a constant index,
    valid at every wavelength) and refused otherwise.

    Raises
    ------
    ValueError
        No material and size distribution to compute the grid from (an analytic phase
        model, or a :func:`compute_optics` table whose index varies with wavelength).
    """
    inputs = table.provenance.inputs
    sizes = inputs.get("size_distribution")
    if "schema" in inputs and isinstance(inputs.get("material"), Mapping):
        material = inputs["material"]
        built = MaterialConfig(
            model=material["model"],
            parameters={k: v for k, v in material.items() if k != "model"},
        ).build()
    else:
        built = _constant_index(inputs)
    if built is None or not isinstance(sizes, Mapping):
        raise ValueError(
            f"format {format_name!r} computes a grid of particle radii from what table "
            f"{table.name!r} was made of; it records no material and size distribution that "
            "give the index at other wavelengths (build a dust preset or a TOML configuration "
            "with [material] and [size_distribution]; analytic phase models have no particles)"
        )
    low, high = getattr(built, "wavelength_range_nm", (0.0, math.inf))
    return GcmParticles(
        name=table.name,
        input_hash=table.provenance.input_hash,
        material=built,
        distribution=sizes,
        wavelength_range_nm=(float(low), float(high)),
    )


def _constant_index(inputs: Mapping[str, Any]) -> complex | None:
    """The index of a :func:`compute_optics` table if it is one constant (no core); else None."""
    index = inputs.get("refractive_index")
    if not isinstance(index, Mapping) or "core" in inputs:
        return None
    n = np.asarray(index.get("n", ()), dtype=np.float64)
    k = np.asarray(index.get("k", ()), dtype=np.float64)
    if n.size == 0 or np.ptp(n) != 0 or np.ptp(k) != 0:
        return None
    return complex(n[0], k[0])


def _mode(record: Mapping[str, Any]) -> ModeConfig:
    parameters = {
        k: (_mode(v) if isinstance(v, Mapping) else tuple(v) if isinstance(v, list) else v)
        for k, v in record.items()
        if k not in ("model", "relative_number_density")
    }
    return ModeConfig(
        model=record["model"],
        parameters=parameters,
        relative_number_density=record.get("relative_number_density"),
    )


def _build(record: Mapping[str, Any]) -> SizeDistribution:
    if "parameters" in record:  # a SizeDistribution.to_dict record (compute_optics' tables)
        return from_dict(record)
    if record["model"] == "multimodal":
        return SizeDistributionConfig(
            model="multimodal", modes=tuple(_mode(m) for m in record["modes"])
        ).build()
    return SizeDistributionConfig(model=record["model"], modes=(_mode(record),)).build()


def _scaled(record: Any, factor: float) -> Any:
    """``record`` with every length parameter (``*_um``, nested modes included) times ``factor``."""
    if isinstance(record, Mapping):
        return {
            k: (v * factor if k.endswith("_um") else _scaled(v, factor)) for k, v in record.items()
        }
    if isinstance(record, list):
        return [_scaled(v, factor) for v in record]
    return record


def _has_lengths(record: Any) -> bool:
    if isinstance(record, Mapping):
        return any(k.endswith("_um") or _has_lengths(v) for k, v in record.items())
    if isinstance(record, list):
        return any(_has_lengths(v) for v in record)
    return False


def distribution_at(
    distribution: Mapping[str, Any],
    *,
    r_eff_um: float,
    v_eff: float | None = None,
    single: bool = False,
) -> SizeDistribution:
    """The distribution of one grid point.

    Parameters
    ----------
    distribution : Mapping
        The configuration's size distribution record (:attr:`GcmParticles.distribution`).
    r_eff_um : float
        The grid point: effective radius (or the spheres' radius with ``single``). [um]
    v_eff : float, optional
        Effective variance; None keeps the build's shape. [-]
    single : bool
        Spheres of radius ``r_eff_um`` when ``v_eff`` is None.

    Returns
    -------
    SizeDistribution

    Raises
    ------
    ValueError
        A family without length parameters (``deirmendjian_gamma``) cannot be scaled:
        give ``v_eff``.
    """
    if v_eff is not None:
        family = SIZE_DISTRIBUTIONS.get(str(distribution["model"]))
        names = {p.name for p in getattr(family, "parameters", ())}
        if family is None or not {"r_eff_um", "v_eff"} <= names:
            family = SIZE_DISTRIBUTIONS["modified_gamma"]
        return family(r_eff_um=r_eff_um, v_eff=v_eff)  # type: ignore[call-arg]
    if single:
        return Monodisperse(radius_um=r_eff_um)
    if not _has_lengths(distribution):
        raise ValueError(
            f"size distribution {distribution['model']!r} has no length parameter to scale to "
            "each radius of the grid; give gcm_v_eff (--gcm-v-eff)"
        )
    own = _build(distribution).r_eff_um
    try:
        return _build(_scaled(distribution, r_eff_um / own))
    except ValueError as err:
        raise ValueError(
            f"the build's size distribution scaled to r_eff {r_eff_um:g} um cannot be made "
            f"({err}); give larger radii (--gcm-radii-um) or a v_eff (--gcm-v-eff)"
        ) from None


def scalable_radii(
    distribution: Mapping[str, Any], radii_um: np.ndarray, *, v_eff: float | None
) -> np.ndarray:
    """The radii of a default grid at which :func:`distribution_at` can make the distribution.

    Scaling a multimodal build down to the smallest radii of a model's grid takes its fine
    mode below 1 nm, the smallest radius the size distributions take; a default grid
    leaves those radii out (a grid the user gives is taken whole or refused). [um]
    """
    kept = []
    for r in radii_um:
        try:
            distribution_at(distribution, r_eff_um=float(r), v_eff=v_eff)
        except ValueError:
            continue
        kept.append(r)
    if not kept:
        raise ValueError(
            "the build's size distribution cannot be scaled to any radius of the default grid; "
            "give gcm_radii_um (--gcm-radii-um) or gcm_v_eff (--gcm-v-eff)"
        )
    return np.asarray(kept, dtype=np.float64)


@dataclass(frozen=True)
class GridOptics:
    """Efficiencies and asymmetry parameter per radius and wavelength.

    Attributes
    ----------
    radius_um : numpy.ndarray, shape (n_radius,)
        The grid. [um]
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        [nm]
    qext, qsca, g : numpy.ndarray, shape (n_radius, n_wavelength)
        <C_ext> / (pi <r^2>), <C_sca> / (pi <r^2>) [-] and the cross-section weighted
        asymmetry parameter [-].
    """

    radius_um: np.ndarray
    wavelength_nm: np.ndarray
    qext: np.ndarray
    qsca: np.ndarray
    g: np.ndarray

    @property
    def ssa(self) -> np.ndarray:
        """Single-scattering albedo Q_sca / Q_ext. [-]"""
        return self.qsca / self.qext


def grid_optics(
    particles: GcmParticles,
    *,
    radius_um: np.ndarray,
    wavelength_nm: np.ndarray,
    v_eff: float | None,
    single: bool = False,
) -> GridOptics:
    """Q_ext, Q_sca and g of the particles at every radius and wavelength.

    Each radius is one :func:`~dustoptics.scattering.optics.compute_optics` call over all
    wavelengths, cross-section weighted (g = <C_sca g> / <C_sca>, the physical average,
    whatever the build's phase-function weighting), to :data:`CROSS_SECTION_RTOL`.
    """
    low, high = particles.wavelength_range_nm
    if wavelength_nm.min() < low or wavelength_nm.max() > high:
        raise ValueError(
            f"wavelengths {wavelength_nm.min():g}-{wavelength_nm.max():g} nm reach beyond the "
            f"refractive index's range {low:g}-{high:g} nm"
        )
    dists = [
        distribution_at(particles.distribution, r_eff_um=float(r), v_eff=v_eff, single=single)
        for r in radius_um
    ]
    _check_work(particles, dists, radius_um, wavelength_nm)
    shape = (radius_um.size, wavelength_nm.size)
    qext, qsca, g = np.empty(shape), np.empty(shape), np.empty(shape)
    for i, dist in enumerate(dists):
        t = compute_optics(
            particles.material,
            dist,
            wavelength_nm,
            _THETA_DEG,
            rtol=_PHASE_RTOL,
            cross_section_rtol=CROSS_SECTION_RTOL,
            weighting="scattering",
            allow_large=True,
        )
        qext[i], qsca[i], g[i] = t.qext, t.qsca, t.g
    return GridOptics(radius_um=radius_um, wavelength_nm=wavelength_nm, qext=qext, qsca=qsca, g=g)


def _check_work(
    particles: GcmParticles,
    dists: Sequence[SizeDistribution],
    radius_um: np.ndarray,
    wavelength_nm: np.ndarray,
) -> None:
    """Refuse, before any work, a grid whose estimated work exceeds the package's budget."""
    works = [
        estimate_cost(
            optics_request(
                particles.material,
                d,
                wavelength_nm,
                _THETA_DEG,
                rtol=_PHASE_RTOL,
                cross_section_rtol=CROSS_SECTION_RTOL,
            ),
            workers=1,
        ).work
        for d in dists
    ]
    total = float(sum(works))
    if total > WORK_BUDGET:
        worst = int(np.argmax(works))
        raise BudgetError(
            f"the radius grid would take about {total / WORK_BUDGET:.1f} times the work budget "
            f"(about ten minutes): the distribution at r_eff {radius_um[worst]:g} um alone is "
            f"{works[worst] / WORK_BUDGET:.2f} of it; give smaller or fewer radii "
            "(--gcm-radii-um), a narrower distribution (--gcm-v-eff) or fewer wavelengths"
        )


def planck_wavenumber(wavenumber_cm: Any, temperature_k: float) -> np.ndarray:
    """Planck's function per wavenumber, up to a constant factor: nu^3 / (exp(c2 nu / T) - 1).

    Parameters
    ----------
    wavenumber_cm : array_like
        [cm^-1]
    temperature_k : float
        [K]

    Returns
    -------
    numpy.ndarray
        B_nu(T) / (2 h c^2) in [cm^-3]; only ratios are used.
    """
    nu = np.asarray(wavenumber_cm, dtype=np.float64)
    return nu**3 / np.expm1(_C2_CM_K * nu / temperature_k)


@dataclass(frozen=True)
class Bands:
    """Spectral bands and the nodes that average over them.

    Attributes
    ----------
    edges_cm : numpy.ndarray, shape (n_band + 1,)
        Band edges in increasing wavenumber, as the model defines them. [cm^-1]
    lower_cm, upper_cm : numpy.ndarray, shape (n_band,)
        The part of each band inside the refractive index's range. [cm^-1]
    covered : numpy.ndarray, shape (n_band,)
        Fraction of each band's Planck energy inside that part. [-]
    wavelength_nm : numpy.ndarray
        All nodes, increasing wavelength. [nm]
    weights : numpy.ndarray, shape (n_band, n_nodes)
        Planck-times-quadrature weights per band over ``wavelength_nm``, rows summing to 1.
    """

    edges_cm: np.ndarray
    lower_cm: np.ndarray
    upper_cm: np.ndarray
    covered: np.ndarray
    wavelength_nm: np.ndarray
    weights: np.ndarray


def planck_bands(
    edges_cm: Sequence[float],
    *,
    temperature_k: float,
    nodes_per_band: int,
    wavelength_range_nm: tuple[float, float],
) -> Bands:
    """Gauss-Legendre nodes in wavenumber over each band, Planck-weighted.

    A band reaching beyond the refractive index's range is averaged over the part inside
    it; :attr:`Bands.covered` says how much of its Planck energy that part holds.

    Raises
    ------
    ValueError
        A band entirely outside the refractive index's range.
    """
    edges = np.asarray(edges_cm, dtype=np.float64)
    nu_low = 1e7 / wavelength_range_nm[1] if wavelength_range_nm[1] < math.inf else 0.0
    nu_high = 1e7 / wavelength_range_nm[0] if wavelength_range_nm[0] > 0 else math.inf
    lower = np.maximum(edges[:-1], nu_low)
    upper = np.minimum(edges[1:], nu_high)
    if np.any(upper <= lower):
        bad = int(np.argmax(upper <= lower))
        raise ValueError(
            f"band {bad + 1} ({edges[bad]:g}-{edges[bad + 1]:g} cm^-1) lies outside the "
            f"refractive index's range {wavelength_range_nm[0]:g}-{wavelength_range_nm[1]:g} nm"
        )
    x, w = np.polynomial.legendre.leggauss(nodes_per_band)
    n_band = edges.size - 1
    nodes = np.empty((n_band, nodes_per_band))
    weights = np.empty((n_band, nodes_per_band))
    covered = np.empty(n_band)
    fine_x, fine_w = np.polynomial.legendre.leggauss(64)
    for b in range(n_band):
        half, mid = 0.5 * (upper[b] - lower[b]), 0.5 * (upper[b] + lower[b])
        nodes[b] = mid + half * x
        weights[b] = half * w * planck_wavenumber(nodes[b], temperature_k)
        whole_half, whole_mid = 0.5 * (edges[b + 1] - edges[b]), 0.5 * (edges[b + 1] + edges[b])
        whole = (
            whole_half * fine_w @ planck_wavenumber(whole_mid + whole_half * fine_x, temperature_k)
        )
        inside = half * fine_w @ planck_wavenumber(mid + half * fine_x, temperature_k)
        covered[b] = inside / whole
        weights[b] /= weights[b].sum()
    wavelength = 1e7 / nodes.ravel()
    order = np.argsort(wavelength)
    full = np.zeros((n_band, wavelength.size))
    for b in range(n_band):
        full[b, b * nodes_per_band : (b + 1) * nodes_per_band] = weights[b]
    return Bands(
        edges_cm=edges,
        lower_cm=lower,
        upper_cm=upper,
        covered=covered,
        wavelength_nm=wavelength[order],
        weights=full[:, order],
    )


def planck_band_average(optics: GridOptics, bands: Bands) -> tuple[np.ndarray, ...]:
    """Band means (Q_ext, Q_sca, g), each shape (n_radius, n_band).

    <Q_ext> = sum w Q_ext, <Q_sca> = sum w Q_sca, <g> = sum w Q_sca g / sum w Q_sca, with
    the Planck weights w of :func:`planck_bands` (g weighted by the scattering it
    describes, as single-scattering properties of a band combine).
    """
    qext = optics.qext @ bands.weights.T
    qsca = optics.qsca @ bands.weights.T
    g = (optics.qsca * optics.g) @ bands.weights.T / qsca
    return qext, qsca, g
