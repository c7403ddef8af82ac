"""Polydisperse Mie optics: converged tables over wavelength and angle.

:func:`compute_optics` averages single-sphere Mie results over a size
distribution n(r) (normalized to 1) with the deterministic quadrature of
:mod:`dustoptics.scattering.quadrature`:

    <C_ext> = int n C_ext dr,   <C_sca> = int n C_sca dr,   <C_abs> = <C_ext> - <C_sca>,

    P(theta) = int n C_sca p(theta; r) dr / int n C_sca dr        (weighting="scattering")
    P(theta) = int n p(theta; r) dr                               (weighting="number")

with each sphere's phase function p normalized so that 2 pi int p dmu = 1; the
table's phase function obeys the same normalization (per steradian).  The
asymmetry parameter is g = 2 pi int P mu dmu of the exact P, i.e. the
C_sca-weighted mean of the spheres' g for ``"scattering"`` and the plain number
mean for ``"number"``; it is summed on the cross-sections' radius quadrature
(refined to ``cross_section_rtol``, absolute for g), not the phase function's
(``rtol``).  So the mean cosine of the tabulated P differs from g by at most
about ``error_estimate + cross_section_error_estimate`` (the two quadratures'
errors; e.g. 1.1e-6 at rtol 1e-3 for r_eff 0.5 um, v_eff 0.125, m 2 + 0.0156i,
639 nm), and g is the more accurate of the two.  Efficiencies are area
weighted: Q = <C> / (pi <r^2>).

:func:`compute_optics` is request -> solve -> assemble.  :func:`optics_request`
validates the call once, before any work, into a frozen :class:`OpticsRequest`
(the refractive index resolved at the wavelengths: :func:`resolve_refractive_index`),
which the cost check (:func:`estimate_cost`, :func:`check_cost`), the
derivatives, :func:`dustoptics.models.compute.build_table` and the sweep's
chunks take and the provenance records; :func:`compute_request` checks its
cost, solves its wavelengths (each refined on its own by
:mod:`dustoptics.scattering.refinement`, on threads) and assembles the table
(:mod:`dustoptics.scattering.solve`); :func:`recompute` runs a recorded
request again.

``weighting="number"`` is the seed thesis's model (Meyran 2022): an unweighted
average of normalized phase functions, there computed from random radii.  It is
not the physical single-scattering phase function of a particle population
(that is the cross-section weighted one), but it reproduces the published
"Blue Moon's" table.

References
----------
.. [1] J. E. Hansen and L. D. Travis, "Light scattering in planetary
   atmospheres," Space Sci. Rev. 16, 527-610 (1974). doi:10.1007/BF00168069
.. [2] C. F. Bohren and D. R. Huffman, *Absorption and Scattering of Light by
   Small Particles*, Wiley, 1983.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple, cast

import numpy as np

from dustoptics._validation import (
    BudgetError,
    as_increasing_grid,
    check_budget,
    check_choice,
    check_open_interval,
    check_positive,
    check_wavelength_unit,
)
from dustoptics.particles.catalogue import get_material
from dustoptics.particles.coated import CoatedSphere
from dustoptics.particles.custom_sizedist import from_dict as _distribution_from_dict
from dustoptics.particles.materials import RefractiveIndex
from dustoptics.particles.sizedist import SizeDistribution
from dustoptics.scattering import mie
from dustoptics.scattering.derivative_parameters import check_parameters, index_parameter_names
from dustoptics.scattering.domain import check_domain
from dustoptics.scattering.quadrature import (
    _UPPER_MOMENT,
    QuadratureDiagnostics,
    QuadratureSettings,
    _stretch,
)
from dustoptics.scattering.solve import (
    ConvergenceWarning,
    assemble_table,
    request_indices,
    solve_wavelengths,
)
from dustoptics.scattering.table_derivatives import table_derivatives
from dustoptics.table import DEFAULT_NAME, Provenance, Source, Table

__all__ = [
    "WORK_BUDGET",
    "ConvergenceWarning",
    "OpticsRequest",
    "QuadratureDiagnostics",
    "RequestCost",
    "check_cost",
    "compute_optics",
    "compute_request",
    "default_theta_deg",
    "default_wavelengths_nm",
    "estimate_cost",
    "optics_request",
    "recompute",
    "resolve_refractive_index",
]

WEIGHTINGS = ("scattering", "number")

RefractiveIndexLike = complex | float | Sequence[complex] | Callable[[Any], Any] | str


def default_wavelengths_nm() -> np.ndarray:
    """48 wavelengths 360, 370, ..., 830 nm (Bruneton's precomputed-scattering grid). [nm]"""
    return np.arange(360.0, 831.0, 10.0)


def default_theta_deg() -> np.ndarray:
    """1,801 scattering angles 0, 0.1, ..., 180 deg. [deg]"""
    return np.linspace(0.0, 180.0, 1801)


def _describe(obj: Any) -> str:
    name = getattr(obj, "name", None)
    if name:
        return str(name)
    qualname = getattr(obj, "__qualname__", None)
    if qualname:
        return f"callable {getattr(obj, '__module__', '?')}.{qualname}"
    return repr(obj)


def _index_source(refractive_index: RefractiveIndexLike, label: str) -> Source:
    """The refractive index as a provenance source, with its citation."""
    if isinstance(refractive_index, str):
        refractive_index = get_material(refractive_index)
    citation = (
        getattr(refractive_index, "citation", "")
        if isinstance(refractive_index, RefractiveIndex)
        else ""
    )
    if not citation:
        citation = "given by the caller (no citation recorded)"
    return Source(name=label, role="refractive index", citation=citation)


def resolve_refractive_index(
    refractive_index: RefractiveIndexLike, wavelength_nm: np.ndarray
) -> tuple[np.ndarray, str]:
    """Evaluate a refractive-index specification at the wavelengths.

    Accepts a complex constant, a sequence with one value per wavelength, a
    catalogue name (see :func:`dustoptics.particles.catalogue.list_materials`), a material
    or mixture object, or any callable ``wavelength_nm -> complex``.  Returns
    the complex array m = n + i k and a description.  Raises ValueError for
    k < 0, n <= 0, non-finite values, or a wavelength outside the data.
    """
    if isinstance(refractive_index, str):
        refractive_index = get_material(refractive_index)
    if isinstance(refractive_index, RefractiveIndex):
        # Materials evaluate arrays and raise for wavelengths outside their data.
        m = np.asarray(refractive_index(wavelength_nm), dtype=np.complex128)
        label = _describe(refractive_index)
    elif callable(refractive_index):
        m = _index_from_callable(refractive_index, wavelength_nm)
        label = _describe(refractive_index)
    elif np.ndim(refractive_index) == 0:
        m, label = _index_from_constant(refractive_index, wavelength_nm)
    else:
        m = _index_from_sequence(refractive_index, wavelength_nm)
        label = "per-wavelength values given by the caller"
    _check_index_values(m, wavelength_nm)
    return m, label


def _index_from_callable(function: Callable[[Any], Any], wavelength_nm: np.ndarray) -> np.ndarray:
    """Any callable other than a material, asked one wavelength at a time."""
    values = []
    for w in wavelength_nm:
        value = function(float(w))
        if isinstance(value, (str, bytes, bool, np.bool_)) or not isinstance(value, numbers.Number):
            raise TypeError(
                f"refractive_index callable {_describe(function)} must return a complex "
                f"number (m = n + i k); got {value!r} ({type(value).__name__}) at {float(w)!r} nm"
            )
        values.append(complex(cast(complex, value)))
    return np.array(values, dtype=np.complex128)


def _index_from_constant(value: Any, wavelength_nm: np.ndarray) -> tuple[np.ndarray, str]:
    """One value for every wavelength, and its description."""
    if isinstance(value, (bytes, bool, np.bool_)):
        raise TypeError(f"refractive_index must be a complex number; got {value!r}")
    try:
        m = np.full(wavelength_nm.shape, complex(cast(complex, value)), dtype=np.complex128)
    except (TypeError, ValueError):
        raise ValueError(
            "refractive_index must be a complex number, a sequence of complex numbers, "
            f"a catalogue name or a callable wavelength_nm -> complex; got {value!r}"
        ) from None
    return m, f"constant m = {complex(cast(complex, value))}"


def _index_from_sequence(values: Any, wavelength_nm: np.ndarray) -> np.ndarray:
    """One value per wavelength."""
    probe = np.asarray(values)
    if probe.dtype.kind in "bUSVO" and not all(
        isinstance(v, numbers.Number) and not isinstance(v, (bool, np.bool_)) for v in probe.ravel()
    ):
        raise TypeError(
            f"refractive_index given as a sequence must hold complex numbers; got {values!r}"
        )
    try:
        m = np.array(values, dtype=np.complex128)
    except (TypeError, ValueError):
        raise ValueError(
            f"refractive_index must be a sequence of complex numbers; got {values!r}"
        ) from None
    if m.shape != wavelength_nm.shape:
        raise ValueError(
            "refractive_index given as a sequence must have one value per wavelength "
            f"({wavelength_nm.size}); got shape {m.shape}"
        )
    return m


#: The refractive index's domain, in the order checked: (where m is outside it, the
#: message before " at LAMBDA nm" with ``{m}`` for the value).
_INDEX_DOMAIN: tuple[tuple[Callable[[np.ndarray], np.ndarray], str], ...] = (
    (
        lambda m: ~(np.isfinite(m.real) & np.isfinite(m.imag)),
        "refractive_index must be finite; got {m}",
    ),
    (
        lambda m: m.imag < 0,
        "refractive_index must have k >= 0 (m = n + i k, absorption k >= 0); got {m}",
    ),
    (lambda m: m.real <= 0, "refractive_index must have n > 0; got {m}"),
    (
        lambda m: np.abs(m) > mie.MAX_INDEX,
        f"refractive_index must have |m| <= {mie.MAX_INDEX:g}; got {{m}}",
    ),
)


def _check_index_values(m: np.ndarray, wavelength_nm: np.ndarray) -> None:
    """Refuse values of m outside the kernel's domain, naming the first wavelength."""
    for outside, message in _INDEX_DOMAIN:
        bad = outside(m)
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(message.format(m=m[i]) + f" at {wavelength_nm[i]} nm")
    contrast = np.abs(m - 1.0) < mie.MIN_INDEX_CONTRAST
    if np.any(contrast):
        i = int(np.argmax(contrast))
        raise ValueError(
            f"refractive_index m = {m[i]} at {wavelength_nm[i]} nm is within {mie.MIN_INDEX_CONTRAST:g} "
            "of 1: it scatters nothing (or next to nothing) and no phase function is defined; "
            f"|m - 1| must be >= {mie.MIN_INDEX_CONTRAST:g}"
        )


@dataclass(frozen=True, eq=False)
class OpticsRequest:
    """One :func:`compute_optics` call's physics, validated once, before any work.

    Made by :func:`optics_request` (never directly): the grids, tolerances,
    weighting and options of the call with the defaults filled in, and the
    refractive index resolved at the wavelengths.  The cost check
    (:func:`check_cost`), the computation (:func:`compute_request`), the
    derivatives, :func:`dustoptics.models.compute.build_table` and the
    sweep's chunks take it, and :meth:`inputs` is what the table's
    provenance records.  It holds no run options (threads, progress, name):
    those do not change the result.

    Attributes
    ----------
    refractive_index : complex, sequence, str, callable or CoatedSphere
        As given (its citation and, for derivatives, its parameters).
    distribution : SizeDistribution
        The number size distribution.
    wavelength_nm : numpy.ndarray
        Strictly increasing wavelengths. [nm]
    theta_deg : numpy.ndarray
        Strictly increasing scattering angles in [0, 180]. [degree]
    rtol : float
        The phase function's (and matrix's) tolerance. [-]
    weighting : {"scattering", "number"}
        How the spheres' phase functions are averaged.
    cross_section_rtol : float
        The cross-sections' tolerance (relative; absolute for g). [-]
    quadrature : QuadratureSettings
        Radius node placement.
    polarization : bool
        Whether the scattering matrix is computed.
    expansion_order : int or None
        None: no expansion coefficients; -1: every order the population needs;
        N: orders 0..N.
    particle_density_kg_m3 : float or None
        Density of the particle material. [kg m^-3]
    derivatives : tuple of str
        Checked parameter names to differentiate with respect to.
    m : numpy.ndarray
        Refractive index (of the shell, for a coated sphere) per wavelength. [-]
    index_label : str
        Its description.
    m_core : numpy.ndarray
        A coated sphere's core index per wavelength (zeros without a core). [-]
    core_fraction : float
        Core radius over particle radius (0 without a core). [-]
    """

    refractive_index: RefractiveIndexLike
    distribution: SizeDistribution
    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    rtol: float
    weighting: str
    cross_section_rtol: float
    quadrature: QuadratureSettings
    polarization: bool
    expansion_order: int | None
    particle_density_kg_m3: float | None
    derivatives: tuple[str, ...]
    m: np.ndarray
    index_label: str
    m_core: np.ndarray
    core_fraction: float

    @property
    def per_particle(self) -> bool:
        """Phase functions averaged by number (``weighting="number"``)."""
        return self.weighting == "number"

    @property
    def n_stokes(self) -> int:
        """Stokes elements each sphere contributes: 4 with the matrix or expansion, else 1."""
        return mie.N_STOKES if (self.polarization or self.expansion_order is not None) else 1

    @property
    def expansion_rtol(self) -> float | None:
        """The expansion coefficients' own tolerance (issue 30): as the cross-sections'. [-]"""
        return None if self.expansion_order is None else self.rtol / 100.0

    @property
    def mu_out(self) -> np.ndarray:
        """Cosines of the output angles. [-]"""
        return np.cos(np.deg2rad(self.theta_deg))

    @property
    def coated(self) -> bool:
        """The particle is a :class:`~dustoptics.particles.coated.CoatedSphere`."""
        return isinstance(self.refractive_index, CoatedSphere)

    def inputs(self) -> dict[str, Any]:
        """The provenance's inputs: everything needed to compute the table again."""
        m = self.m
        inputs: dict[str, Any] = {
            "refractive_index": {"description": self.index_label, "n": m.real, "k": m.imag},
            "size_distribution": self.distribution.to_dict(),
            "wavelength_nm": self.wavelength_nm,
            "theta_deg": self.theta_deg,
            "weighting": self.weighting,
            "rtol": self.rtol,
            "cross_section_rtol": self.cross_section_rtol,
            "quadrature": self.quadrature,
        }
        # Recorded only when used, so that other tables' provenance is unchanged.
        if self.polarization:
            inputs["polarization"] = True
        if self.expansion_order is not None:
            inputs["expansion"] = True if self.expansion_order < 0 else self.expansion_order
        if self.particle_density_kg_m3 is not None:
            inputs["particle_density_kg_m3"] = self.particle_density_kg_m3
        if self.derivatives:
            inputs["derivatives"] = list(self.derivatives)
        if self.core_fraction > 0.0 or self.coated:
            inputs["core"] = {
                "n": self.m_core.real,
                "k": self.m_core.imag,
                "core_radius_fraction": self.core_fraction,
            }
        return inputs

    def sources(self) -> tuple[Source, Source]:
        """The refractive index's and the size distribution's sources, with citations."""
        return (
            _index_source(self.refractive_index, self.index_label),
            Source(
                name=self.distribution.model,
                role="size distribution",
                citation=self.distribution.citation,
            ),
        )


def optics_request(
    refractive_index: RefractiveIndexLike,
    distribution: SizeDistribution,
    wavelength_nm: Sequence[float] | np.ndarray | None = None,
    theta_deg: Sequence[float] | np.ndarray | None = None,
    *,
    rtol: float = 1e-4,
    weighting: str = "scattering",
    cross_section_rtol: float | None = None,
    quadrature: QuadratureSettings | None = None,
    polarization: bool = False,
    expansion: bool | int = False,
    particle_density_kg_m3: float | None = None,
    derivatives: Sequence[str] = (),
) -> OpticsRequest:
    """Validate a :func:`compute_optics` call's physics once: its :class:`OpticsRequest`.

    The parameters are :func:`compute_optics`'s (which see); the refractive
    index is resolved at the wavelengths (:func:`resolve_refractive_index`).
    Nothing is computed; the cost is checked by :func:`check_cost`.

    Raises
    ------
    ValueError
        Bad input: the message names the parameter, the value and what is allowed.
    TypeError
        A string or boolean given as a number, ``weighting`` not a string, a
        refractive-index callable that returns no number.
    """
    _check_distribution(distribution)
    wl, theta = _grids(wavelength_nm, theta_deg)
    rtol = check_open_interval("rtol", rtol, 0.0, 0.1)
    cross_rtol = (
        rtol / 100.0
        if cross_section_rtol is None
        else check_open_interval("cross_section_rtol", cross_section_rtol, 0.0, 0.1)
    )
    if not isinstance(weighting, str):
        raise TypeError(f"weighting must be a str, one of {WEIGHTINGS}; got {weighting!r}")
    check_choice("weighting", weighting, WEIGHTINGS)
    settings = QuadratureSettings() if quadrature is None else quadrature
    if not isinstance(settings, QuadratureSettings):
        raise ValueError(f"quadrature must be a QuadratureSettings; got {quadrature!r}")
    if not isinstance(polarization, (bool, np.bool_)):
        raise ValueError(f"polarization must be True or False; got {polarization!r}")
    n_order = _check_expansion(expansion)
    derivative_names = _check_derivatives(derivatives, refractive_index, distribution)
    density = (
        None
        if particle_density_kg_m3 is None
        else check_positive("particle_density_kg_m3", particle_density_kg_m3, unit="kg m-3")
    )
    m, label, m_core, core_fraction = _resolve_particle(refractive_index, wl)
    return OpticsRequest(
        refractive_index=refractive_index,
        distribution=distribution,
        wavelength_nm=_read_only(wl),
        theta_deg=_read_only(theta),
        rtol=rtol,
        weighting=weighting,
        cross_section_rtol=cross_rtol,
        quadrature=settings,
        polarization=bool(polarization),
        expansion_order=n_order,
        particle_density_kg_m3=density,
        derivatives=derivative_names,
        m=_read_only(m),
        index_label=label,
        m_core=_read_only(m_core),
        core_fraction=core_fraction,
    )


def _read_only(values: np.ndarray) -> np.ndarray:
    """A read-only copy: the request's arrays cannot change after validation."""
    out = np.array(values, copy=True)
    out.setflags(write=False)
    return out


def _check_distribution(distribution: Any) -> None:
    if not isinstance(distribution, SizeDistribution):
        raise ValueError(
            f"distribution must be a dustoptics SizeDistribution (e.g. ModifiedGamma); got {distribution!r}"
        )
    if not (distribution.has_density or distribution.is_monodisperse):
        raise ValueError(
            "distribution mixes Monodisperse and continuous modes, which the radius "
            f"quadrature does not support; got {distribution!r}"
        )


def _grids(
    wavelength_nm: Sequence[float] | np.ndarray | None,
    theta_deg: Sequence[float] | np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The wavelengths [nm] and angles [degree], checked, or their defaults."""
    wl = (
        default_wavelengths_nm()
        if wavelength_nm is None
        else as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    )
    if wl[0] <= 0:
        raise ValueError(f"wavelength_nm must be > 0 nm; got minimum {wl[0]!r}")
    check_wavelength_unit("wavelength_nm", wl)
    theta = (
        default_theta_deg()
        if theta_deg is None
        else as_increasing_grid("theta_deg", theta_deg, low=0.0, high=180.0, unit="degree")
    )
    return wl, theta


def _check_derivatives(
    derivatives: Sequence[str],
    refractive_index: RefractiveIndexLike,
    distribution: SizeDistribution,
) -> tuple[str, ...]:
    names = check_parameters(derivatives, distribution, index_parameter_names(refractive_index))
    if names and isinstance(refractive_index, CoatedSphere):
        raise ValueError(
            "derivatives are not available for coated spheres (CoatedSphere); got "
            f"derivatives={names!r}"
        )
    return names


def _resolve_particle(
    refractive_index: RefractiveIndexLike, wavelength_nm: np.ndarray
) -> tuple[np.ndarray, str, np.ndarray, float]:
    """(m of the particle or shell, its description, m of the core, core radius fraction)."""
    if isinstance(refractive_index, CoatedSphere):
        m, shell_label = resolve_refractive_index(refractive_index.shell, wavelength_nm)
        m_core, core_label = resolve_refractive_index(refractive_index.core, wavelength_nm)
        label = refractive_index.describe(core_label, shell_label)
        return m, label, m_core, refractive_index.radius_fraction
    m, label = resolve_refractive_index(refractive_index, wavelength_nm)
    return m, label, np.zeros_like(m), 0.0


def _request_from_inputs(inputs: Mapping[str, Any]) -> OpticsRequest:
    """The request that recorded these provenance inputs (:func:`recompute`)."""
    index = inputs["refractive_index"]
    m = np.asarray(index["n"], dtype=np.float64) + 1j * np.asarray(index["k"], dtype=np.float64)
    particle: Any = m.tolist()
    if "core" in inputs:
        core = inputs["core"]
        m_core = np.asarray(core["n"], dtype=np.float64) + 1j * np.asarray(
            core["k"], dtype=np.float64
        )
        particle = CoatedSphere(
            core=m_core.tolist(),
            shell=m.tolist(),
            core_radius_fraction=core["core_radius_fraction"],
        )
    # Derivatives again, as recorded; a mixture's parameters (hematite_fraction, ...)
    # are refused before any work: the recorded index values do not hold the mixture.
    return optics_request(
        particle,
        _distribution_from_dict(inputs["size_distribution"]),
        inputs["wavelength_nm"],
        inputs["theta_deg"],
        rtol=inputs["rtol"],
        weighting=inputs["weighting"],
        cross_section_rtol=inputs["cross_section_rtol"],
        quadrature=QuadratureSettings(**inputs["quadrature"]),
        polarization=bool(inputs.get("polarization", False)),
        expansion=inputs.get("expansion", False),
        particle_density_kg_m3=inputs.get("particle_density_kg_m3"),
        derivatives=tuple(inputs.get("derivatives", ())),
    )


#: Largest estimated work of one :func:`compute_optics` call without
#: ``allow_large=True``, in sphere-order-angle terms (see
#: :func:`estimate_cost`).  Measured on a loaded 2-core machine (scripts in
#: the test suite's budget tests): 1-2e9 terms a second; the default Mars
#: table (r_eff 1.6 um, v_eff 0.2) is about 3.5e9, r_eff 30 um, v_eff 0.1 on
#: three wavelengths and 1,801 angles 1.2e11 (64 s).  1e12 is about ten
#: minutes.
WORK_BUDGET = 1e12


class RequestCost(NamedTuple):
    """What :func:`estimate_cost` expects a :func:`compute_optics` call to need."""

    memory_bytes: float
    work: float
    min_size_parameter: float
    max_size_parameter: float
    initial_panels: float


def estimate_cost(request: OpticsRequest, *, workers: int) -> RequestCost:
    """Estimate the memory and work of a request's computation before any is done.

    From the truncated radius range (the distribution's analytic tail
    bounds, as the quadrature places them), the smallest and largest
    wavelengths give the size-parameter range [x_lo, x_hi]; the largest sphere
    needs n_max = x_hi + 4.05 x_hi^(1/3) + 2 orders (Wiscombe 1980).  Memory:
    each thread's angular tables (pi_n, tau_n at n_max orders and at the
    output angles, or at 2 n_max Gauss angles when that is fewer) and its
    level-0 panel rows, plus the tables returned.  Work: 16 times the level-0
    nodes (the refinement's typical end) times orders times (angles + 8),
    for every wavelength.  Nothing is allocated in proportion to the
    estimate.

    Parameters
    ----------
    request : OpticsRequest
        The validated call (:func:`optics_request`).
    workers : int
        Threads over wavelengths (each holds its own tables).

    Raises
    ------
    ValueError
        The distribution's radii overflow, or its size parameters leave the
        kernel's domain (below :data:`dustoptics.scattering.mie.MIN_SIZE_PARAMETER`).
    """
    distribution, wavelength_nm = request.distribution, request.wavelength_nm
    settings, n_theta = request.quadrature, int(request.theta_deg.size)
    k_max = 2.0 * math.pi / (float(wavelength_nm[0]) * 1e-3)
    k_min = 2.0 * math.pi / (float(wavelength_nm[-1]) * 1e-3)
    try:
        with np.errstate(all="raise"):
            if distribution.is_monodisperse:
                r_lo = r_hi = float(distribution.mean_radius_um)
            else:
                r_lo, r_hi = distribution.radius_bounds_um(
                    tail_fraction=settings.tail_fraction,
                    lower_moment=0 if request.per_particle else 2,
                    upper_moment=_UPPER_MOMENT,
                )
            float(distribution.mean_cross_section_um2)
            x_lo, x_hi = k_min * r_lo, k_max * r_hi
    except (OverflowError, ZeroDivisionError, FloatingPointError, ValueError) as exc:
        raise ValueError(
            f"distribution {distribution!r} is outside the range the quadrature can integrate "
            f"({type(exc).__name__}: {exc}); choose radii between about 1e-3 and 1e3 um"
        ) from None
    if not (math.isfinite(x_lo) and math.isfinite(x_hi) and x_hi > 0):
        raise ValueError(
            f"distribution {distribution!r} gives size parameters {x_lo!r} .. {x_hi!r} at "
            f"{wavelength_nm[0]:g} .. {wavelength_nm[-1]:g} nm, which are not finite and positive"
        )
    if x_lo < mie.MIN_SIZE_PARAMETER:
        raise ValueError(
            f"distribution {distribution!r}: its radii start at size parameter 2 pi r / lambda = "
            f"{x_lo:.3g} (radius {r_lo:.3g} um at {wavelength_nm[-1]:g} nm), below "
            f"{mie.MIN_SIZE_PARAMETER:g}, the kernel's tested domain; choose a larger radius, a "
            "narrower distribution, or weighting='scattering' (whose lower tail is the area's)"
        )
    n_max = x_hi + 4.05 * x_hi ** (1.0 / 3.0) + 2.0
    n_wl = int(wavelength_nm.size)
    if distribution.is_monodisperse:
        n_angles = float(n_theta)
        panels = 1.0
        nodes = 1.0
    else:
        x_c = settings.transition_size_parameter
        width = float(_stretch(x_hi, x_c) - _stretch(k_max * r_lo, x_c))
        panels = max(float(settings.min_panels), math.ceil(width / settings.panel_width))
        # Level-0 nodes times 16: the adaptive refinement typically ends with
        # 6-20 times the level-0 nodes (measured for r_eff 1.6-100 um).
        nodes = panels * settings.nodes_per_panel * 16.0
        n_angles = float(min(n_theta, 2.0 * (n_max + 16.0)))
    tables = 2.0 * 2.0 * (n_max + 1.0) * n_angles * 8.0
    rows = 4.0 * panels * (n_angles + 5.0) * 8.0 + 8.0 * 8.0 * nodes
    memory = min(workers, n_wl) * (tables + rows) + 4.0 * n_wl * float(n_theta) * 8.0
    # Per sphere and order: the coefficients (about 8 angle terms' worth) and the angular sums.
    work = n_wl * nodes * n_max * (n_angles + 8.0)
    return RequestCost(memory, work, x_lo, x_hi, panels)


def check_cost(request: OpticsRequest, *, workers: int, allow_large: bool) -> RequestCost:
    """:func:`estimate_cost`, then refuse a request beyond the budget.

    Parameters
    ----------
    request : OpticsRequest
        The validated call (:func:`optics_request`).
    workers : int
        Threads over wavelengths.
    allow_large : bool
        Go ahead beyond the budget.

    Raises
    ------
    dustoptics._validation.BudgetError
        Estimated memory above :data:`dustoptics._validation.MEMORY_BUDGET_BYTES`
        or work above :data:`WORK_BUDGET`, and ``allow_large`` is False; the
        message says what drives the estimate and what to change.
    """
    cost = estimate_cost(request, workers=workers)
    wl, n_theta = request.wavelength_nm, request.theta_deg.size
    check_budget(
        "compute_optics",
        cost.memory_bytes,
        allow_large=allow_large,
        change=(
            f"the largest size parameter is {cost.max_size_parameter:.3g} (2 pi r / lambda at the "
            "tail's largest radius and the shortest wavelength) and the grids hold "
            f"{wl.size} wavelengths x {n_theta} angles: use fewer angles or wavelengths, a "
            "smaller r_eff_um / v_eff or radius, longer wavelengths, or a wider panel_width"
        ),
    )
    if cost.work > WORK_BUDGET and not allow_large:
        raise BudgetError(
            f"compute_optics would need about {cost.work:.3g} sphere-order-angle terms (largest size "
            f"parameter {cost.max_size_parameter:.3g}, {cost.initial_panels:.0f} initial radius panels, "
            f"{wl.size} wavelengths x {n_theta} angles), beyond the budget of {WORK_BUDGET:g} "
            "(about ten minutes): use a smaller r_eff_um / v_eff or radius, longer or fewer "
            "wavelengths, fewer angles or a wider panel_width, or pass allow_large=True "
            "(--allow-large on the command line) to go ahead"
        )
    return cost


def compute_optics(
    refractive_index: RefractiveIndexLike,
    distribution: SizeDistribution,
    wavelength_nm: Sequence[float] | np.ndarray | None = None,
    theta_deg: Sequence[float] | np.ndarray | None = None,
    *,
    rtol: float = 1e-4,
    weighting: str = "scattering",
    cross_section_rtol: float | None = None,
    quadrature: QuadratureSettings | None = None,
    workers: int | None = None,
    name: str = DEFAULT_NAME,
    progress: Callable[[int, int], None] | None = None,
    allow_large: bool = False,
    allow_unvalidated: bool = False,
    polarization: bool = False,
    expansion: bool | int = False,
    particle_density_kg_m3: float | None = None,
    derivatives: Sequence[str] = (),
) -> Table:
    """Polydisperse Mie optics of spheres, converged over the size distribution.

    Parameters
    ----------
    refractive_index : complex, sequence, str or callable
        m = n + i k (k >= 0) relative to the surrounding medium: one value for
        all wavelengths, one per wavelength, a catalogue material name, a
        material or mixture (e.g. :func:`dustoptics.particles.mixing.mars_dust`), or any
        callable ``wavelength_nm -> complex``. [-]
    distribution : SizeDistribution
        Number size distribution, e.g. ``ModifiedGamma(r_eff_um=1.6, v_eff=0.2)``.
    wavelength_nm : array_like, optional
        Strictly increasing wavelengths; default 360, 370, ..., 830. [nm]
    theta_deg : array_like, optional
        Strictly increasing scattering angles in [0, 180]; default 0 to 180 in
        0.1 degree steps (1,801 angles). [degree]
    rtol : float
        Target for the largest relative change of the phase function at any
        angle between successive quadrature refinements. [-]
    weighting : {"scattering", "number"}
        How the spheres' phase functions are averaged: by scattering cross-section
        (physical) or by number (the seed thesis's unweighted average).
    cross_section_rtol : float, optional
        Target for <C_ext>, <C_sca> (relative) and g (absolute); default
        ``rtol / 100``. [-]
    quadrature : QuadratureSettings, optional
        Radius node placement; the defaults suit r_eff 0.05-10 um.
    workers : int, optional
        Threads over wavelengths (default: all cores).  Each wavelength is
        computed by one thread in a fixed order, so results are the same to the
        bit whatever the count.
    name : str, optional
        The table's name (default ``"table"``).
    progress : callable, optional
        Called as ``progress(done, total)`` with the number of wavelengths
        done, first with 0 and last with ``total``.  It does not change the
        result.
    allow_large : bool
        Go ahead even when the estimated memory exceeds
        :data:`dustoptics._validation.MEMORY_BUDGET_BYTES` (2 GiB) or the
        estimated work exceeds :data:`WORK_BUDGET` (about ten minutes); see
        :func:`estimate_cost`.  Default False: such a call raises
        :class:`dustoptics._validation.BudgetError` before any work.
    allow_unvalidated : bool
        Go ahead, with a
        :class:`~dustoptics.scattering.domain.UnvalidatedWarning`, when the
        size parameters or refractive indices leave the validated domain
        (:data:`~dustoptics.scattering.domain.VALIDATED_DOMAIN`, where every
        output's accuracy is verified against arbitrary-precision
        references).  Default False: such a call raises
        :class:`~dustoptics.scattering.domain.OutsideDomainError` before any
        work.  The table's provenance records whether it stayed inside.
    polarization : bool
        Also compute the scattering matrix F12, F33, F34 (F22 = F11 = phase,
        F44 = F33 for spheres), normalized like the phase function and with
        Bohren & Huffman's signs (:mod:`dustoptics.scattering.expansion`); the
        quadrature then refines until every element's error, relative to F11
        at each angle, is below ``rtol``.
    expansion : bool or int
        Also compute the expansion coefficients alpha1..alpha4, beta1, beta2
        in generalized spherical functions: ``True`` for every order the
        population needs (2 n_max + 1 of the largest sphere; the series ends
        there), an integer N for orders 0..N.  Refines like ``polarization``,
        then the coefficients further, from those panels, to their own
        tolerance ``rtol / 100`` as the cross-sections (their error estimate
        ``expansion_error_estimate`` bounds each coefficient's error over
        2 l + 1); the phase function and matrix stay those of ``rtol``.
    particle_density_kg_m3 : float, optional
        Density of the particle material, for the mass extinction, scattering
        and absorption coefficients (``table.mass_ext_m2_per_kg``, ...); for
        Mars dust :data:`dustoptics.particles.mixing.MARS_DUST_DENSITY_KG_M3`. [kg m^-3]
    derivatives : sequence of str, optional
        Parameters to differentiate every output with respect to: the size
        distribution's by name (``"r_eff_um"``, ``"v_eff"``, ``"sigma"``,
        ``"modes[0].r_eff_um"``, ...; ``"radius_um"`` of a monodisperse one),
        ``"n"`` and ``"k"`` (the refractive index's real and imaginary parts,
        each wavelength's own), and a mixture's (``"volume_fraction"``, for
        :func:`~dustoptics.particles.mixing.mars_dust` also
        ``"hematite_fraction"``, ``"host_n"``, ``"host_k"``).  Exact
        derivatives of every output the table holds (the matrix and the
        expansion coefficients too, when asked for) on the converged
        quadrature, with error estimates
        (:mod:`dustoptics.scattering.table_derivatives`); read them with
        :meth:`Table.derivative`.  Default ``()``: none, and the table is the
        same to the bit as without the argument.

    Returns
    -------
    Table
        Phase function, cross-sections, g, error estimates, node counts and
        the refractive index used, per wavelength; its provenance records the
        call (the refractive index's description, citation and values, the
        size distribution and its parameters, the grids, the weighting, the
        tolerances and quadrature settings) with the achieved error and the
        software versions, and its ``diagnostics`` the radius panels.

    Raises
    ------
    ValueError
        Bad input (the message names the parameter, value and allowed range):
        also wavelengths plainly not in nanometres (all below 10 nm), an index
        within :data:`dustoptics.scattering.mie.MIN_INDEX_CONTRAST` of 1, a
        sphere below :data:`dustoptics.scattering.mie.MIN_SIZE_PARAMETER`,
        and a request beyond the budget (:class:`~dustoptics._validation.BudgetError`).
    TypeError
        A string or boolean given as a number, ``weighting`` not a string, a
        refractive-index callable that returns no number.

    Warns
    -----
    ConvergenceWarning
        A wavelength did not reach the tolerances at ``quadrature.max_level``;
        its ``error_estimate`` says how far it got.

    Notes
    -----
    Three steps: :func:`optics_request` validates the call once (an
    :class:`OpticsRequest`, which the provenance records), and
    :func:`compute_request` checks its cost, solves it (threads over
    wavelengths, progress) and assembles the table (checks, warnings,
    provenance).

    Examples
    --------
    >>> import dustoptics as do
    >>> t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 90.0, 180.0])
    >>> round(float(t.qext[0]), 6)
    3.092896
    """
    request = optics_request(
        refractive_index,
        distribution,
        wavelength_nm,
        theta_deg,
        rtol=rtol,
        weighting=weighting,
        cross_section_rtol=cross_section_rtol,
        quadrature=quadrature,
        polarization=polarization,
        expansion=expansion,
        particle_density_kg_m3=particle_density_kg_m3,
        derivatives=derivatives,
    )
    return _run(
        request,
        workers=workers,
        name=name,
        progress=progress,
        allow_large=allow_large,
        allow_unvalidated=allow_unvalidated,
    )


def compute_request(
    request: OpticsRequest,
    *,
    workers: int | None = None,
    name: str = DEFAULT_NAME,
    progress: Callable[[int, int], None] | None = None,
    allow_large: bool = False,
    allow_unvalidated: bool = False,
) -> Table:
    """Compute the table of a validated request: cost check, solve, assemble.

    Parameters
    ----------
    request : OpticsRequest
        From :func:`optics_request`.
    workers, name, progress, allow_large, allow_unvalidated
        As :func:`compute_optics`'s.

    Returns
    -------
    Table
        The table :func:`compute_optics` returns for the same arguments, to the bit.
    """
    return _run(
        request,
        workers=workers,
        name=name,
        progress=progress,
        allow_large=allow_large,
        allow_unvalidated=allow_unvalidated,
    )


def _run(
    request: OpticsRequest,
    *,
    workers: int | None,
    name: str,
    progress: Callable[[int, int], None] | None,
    allow_large: bool,
    allow_unvalidated: bool,
) -> Table:
    """request -> cost and domain checks -> solve -> assemble (-> derivatives); each public
    entry calls this directly, so that warnings point at its caller."""
    if not isinstance(request, OpticsRequest):
        raise TypeError(
            f"request must be an OpticsRequest (see optics_request); got {type(request).__name__}"
        )
    threads = _check_run_options(workers, name, progress, allow_large)
    cost = check_cost(request, workers=threads, allow_large=allow_large)
    check_domain(
        m=request_indices(request),
        min_size_parameter=cost.min_size_parameter,
        max_size_parameter=cost.max_size_parameter,
        allow_unvalidated=allow_unvalidated,
    )
    results = solve_wavelengths(request, workers=threads, progress=progress)
    table = assemble_table(request, results, cost=cost, name=name)
    if not request.derivatives:
        return table
    return table.replace(derivatives=table_derivatives(table, request, workers=threads))


def _check_run_options(
    workers: int | None,
    name: str,
    progress: Callable[[int, int], None] | None,
    allow_large: bool,
) -> int:
    """The options that do not change the result, checked; returns the thread count."""
    if not isinstance(allow_large, bool):
        raise TypeError(f"allow_large must be True or False; got {allow_large!r}")
    if workers is None:
        workers = os.cpu_count() or 1
    elif not (isinstance(workers, int) and workers >= 1):
        raise ValueError(f"workers must be a positive integer; got {workers!r}")
    if not isinstance(name, str) or not name:
        raise ValueError(f"name must be a non-empty string; got {name!r}")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be a callable progress(done, total); got {progress!r}")
    return workers


# ---------------------------------------------------------------------- recompute


def recompute(
    provenance: Provenance, *, workers: int | None = None, name: str = DEFAULT_NAME
) -> Table:
    """Compute a table again from the provenance :func:`compute_optics` recorded.

    The provenance alone suffices: its inputs hold the refractive index's
    values at every wavelength (whatever the source: catalogue, mixture,
    constant or callable), the size distribution's model and parameters, the
    grids, weighting, tolerances and quadrature settings.  With the same
    software versions the result is the same table to the bit, and its
    provenance is the original's (inputs, sources, notes) with the new run's
    software versions and quadrature record.

    Parameters
    ----------
    provenance : Provenance
        ``table.provenance`` of a table from :func:`compute_optics` (not of a
        configuration's table, whose inputs are the configuration; rebuild
        those with :func:`dustoptics.models.compute.build_table`).
    workers : int, optional
        Threads over wavelengths (does not change the result).
    name : str, optional
        The new table's name.

    Returns
    -------
    Table

    Raises
    ------
    ValueError
        The provenance was not recorded by :func:`compute_optics`.
    """
    if not isinstance(provenance, Provenance):
        raise TypeError(
            f"provenance must be a dustoptics Provenance; got {type(provenance).__name__}"
        )
    inputs = provenance.inputs
    required = (
        "refractive_index",
        "size_distribution",
        "wavelength_nm",
        "theta_deg",
        "weighting",
        "rtol",
        "cross_section_rtol",
        "quadrature",
    )
    missing = [key for key in required if key not in inputs]
    if missing:
        raise ValueError(
            f"provenance inputs lack {', '.join(missing)}: it was not recorded by compute_optics "
            "(a configuration's table is rebuilt with build_table)"
        )
    table = compute_request(_request_from_inputs(inputs), workers=workers, name=name)
    # The same values of m; only the caller's description of them is restored.
    return table.replace(
        provenance=Provenance(
            inputs=inputs,
            sources=provenance.sources,
            software=table.provenance.software,
            quadrature=table.provenance.quadrature,
            notes=provenance.notes,
        )
    )


def _check_expansion(expansion: Any) -> int | None:
    """None (no expansion), -1 (every order needed) or the highest order N."""
    if expansion is False or expansion is None:
        return None
    if expansion is True:
        return -1
    if isinstance(expansion, (int, np.integer)) and not isinstance(expansion, bool):
        if expansion < 0:
            raise ValueError(f"expansion must be True, False or an order N >= 0; got {expansion!r}")
        return int(expansion)
    raise ValueError(
        f"expansion must be True, False or an order N >= 0 (an integer); got {expansion!r}"
    )
