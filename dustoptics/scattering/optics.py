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

This module checks the request (:func:`estimate_cost`, :func:`check_cost`),
resolves the refractive index, runs the wavelengths (each refined on its own
by :mod:`dustoptics.scattering.refinement`) and assembles the table with its
provenance; :func:`recompute` runs a recorded call again.

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
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
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
from dustoptics.scattering.quadrature import (
    _UPPER_MOMENT,
    QuadratureDiagnostics,
    QuadratureSettings,
    _stretch,
)
from dustoptics.scattering.refinement import _Result, _WavelengthSolver, kernels_loaded
from dustoptics.scattering.table_derivatives import (
    check_parameters,
    index_directions,
    index_parameter_names,
    table_derivatives,
)
from dustoptics.table import (
    DEFAULT_NAME,
    CrossSections,
    Provenance,
    QuadratureRecord,
    Source,
    Table,
    plain,
    records_from_fields,
)

__all__ = [
    "WORK_BUDGET",
    "ConvergenceWarning",
    "QuadratureDiagnostics",
    "check_cost",
    "compute_optics",
    "default_theta_deg",
    "default_wavelengths_nm",
    "estimate_cost",
    "recompute",
    "resolve_refractive_index",
]

WEIGHTINGS = ("scattering", "number")

RefractiveIndexLike = complex | float | Sequence[complex] | Callable[[Any], Any] | str


class ConvergenceWarning(UserWarning):
    """The radius quadrature reached its panel limit before the tolerance."""


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
        # Any other callable is asked one wavelength at a time.
        values = []
        for w in wavelength_nm:
            value = refractive_index(float(w))
            if isinstance(value, (str, bytes, bool, np.bool_)) or not isinstance(
                value, numbers.Number
            ):
                raise TypeError(
                    f"refractive_index callable {_describe(refractive_index)} must return a complex "
                    f"number (m = n + i k); got {value!r} ({type(value).__name__}) at {float(w)!r} nm"
                )
            values.append(complex(cast(complex, value)))
        m = np.array(values, dtype=np.complex128)
        label = _describe(refractive_index)
    elif np.ndim(refractive_index) == 0:
        if isinstance(refractive_index, (bytes, bool, np.bool_)):
            raise TypeError(f"refractive_index must be a complex number; got {refractive_index!r}")
        try:
            m = np.full(
                wavelength_nm.shape, complex(cast(complex, refractive_index)), dtype=np.complex128
            )
        except (TypeError, ValueError):
            raise ValueError(
                "refractive_index must be a complex number, a sequence of complex numbers, "
                f"a catalogue name or a callable wavelength_nm -> complex; got {refractive_index!r}"
            ) from None
        label = f"constant m = {complex(cast(complex, refractive_index))}"
    else:
        probe = np.asarray(refractive_index)
        if probe.dtype.kind in "bUSVO" and not all(
            isinstance(v, numbers.Number) and not isinstance(v, (bool, np.bool_))
            for v in probe.ravel()
        ):
            raise TypeError(
                f"refractive_index given as a sequence must hold complex numbers; got {refractive_index!r}"
            )
        try:
            m = np.array(refractive_index, dtype=np.complex128)
        except (TypeError, ValueError):
            raise ValueError(
                f"refractive_index must be a sequence of complex numbers; got {refractive_index!r}"
            ) from None
        if m.shape != wavelength_nm.shape:
            raise ValueError(
                "refractive_index given as a sequence must have one value per wavelength "
                f"({wavelength_nm.size}); got shape {m.shape}"
            )
        label = "per-wavelength values given by the caller"
    bad = ~(np.isfinite(m.real) & np.isfinite(m.imag))
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"refractive_index must be finite; got {m[i]} at {wavelength_nm[i]} nm")
    if np.any(m.imag < 0):
        i = int(np.argmax(m.imag < 0))
        raise ValueError(
            f"refractive_index must have k >= 0 (m = n + i k, absorption k >= 0); "
            f"got {m[i]} at {wavelength_nm[i]} nm"
        )
    if np.any(m.real <= 0):
        i = int(np.argmax(m.real <= 0))
        raise ValueError(f"refractive_index must have n > 0; got {m[i]} at {wavelength_nm[i]} nm")
    if np.any(np.abs(m) > mie.MAX_INDEX):
        i = int(np.argmax(np.abs(m) > mie.MAX_INDEX))
        raise ValueError(
            f"refractive_index must have |m| <= {mie.MAX_INDEX:g}; got {m[i]} at {wavelength_nm[i]} nm"
        )
    contrast = np.abs(m - 1.0) < mie.MIN_INDEX_CONTRAST
    if np.any(contrast):
        i = int(np.argmax(contrast))
        raise ValueError(
            f"refractive_index m = {m[i]} at {wavelength_nm[i]} nm is within {mie.MIN_INDEX_CONTRAST:g} "
            "of 1: it scatters nothing (or next to nothing) and no phase function is defined; "
            f"|m - 1| must be >= {mie.MIN_INDEX_CONTRAST:g}"
        )
    return m, label


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


def estimate_cost(
    distribution: SizeDistribution,
    wavelength_nm: np.ndarray,
    n_theta: int,
    *,
    settings: QuadratureSettings,
    weighting: str,
    workers: int,
) -> RequestCost:
    """Estimate the memory and work of :func:`compute_optics` before any is done.

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

    Raises
    ------
    ValueError
        The distribution's radii overflow, or its size parameters leave the
        kernel's domain (below :data:`dustoptics.scattering.mie.MIN_SIZE_PARAMETER`).
    """
    k_max = 2.0 * math.pi / (float(wavelength_nm[0]) * 1e-3)
    k_min = 2.0 * math.pi / (float(wavelength_nm[-1]) * 1e-3)
    try:
        with np.errstate(all="raise"):
            if distribution.is_monodisperse:
                r_lo = r_hi = float(distribution.mean_radius_um)
            else:
                r_lo, r_hi = distribution.radius_bounds_um(
                    tail_fraction=settings.tail_fraction,
                    lower_moment=0 if weighting == "number" else 2,
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


def check_cost(
    distribution: SizeDistribution,
    wl: np.ndarray,
    n_theta: int,
    *,
    settings: QuadratureSettings,
    weighting: str,
    workers: int,
    allow_large: bool,
) -> RequestCost:
    """:func:`estimate_cost`, then refuse a request beyond the budget.

    Raises
    ------
    dustoptics._validation.BudgetError
        Estimated memory above :data:`dustoptics._validation.MEMORY_BUDGET_BYTES`
        or work above :data:`WORK_BUDGET`, and ``allow_large`` is False; the
        message says what drives the estimate and what to change.
    """
    cost = estimate_cost(
        distribution, wl, n_theta, settings=settings, weighting=weighting, workers=workers
    )
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
    rtol: float = 1e-4,
    weighting: str = "scattering",
    *,
    cross_section_rtol: float | None = None,
    quadrature: QuadratureSettings | None = None,
    workers: int | None = None,
    name: str = DEFAULT_NAME,
    progress: Callable[[int, int], None] | None = None,
    wavelengths_nm: Sequence[float] | np.ndarray | None = None,
    allow_large: bool = False,
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
    wavelengths_nm : array_like, optional
        Deprecated spelling of ``wavelength_nm``.
    allow_large : bool
        Go ahead even when the estimated memory exceeds
        :data:`dustoptics._validation.MEMORY_BUDGET_BYTES` (2 GiB) or the
        estimated work exceeds :data:`WORK_BUDGET` (about ten minutes); see
        :func:`estimate_cost`.  Default False: such a call raises
        :class:`dustoptics._validation.BudgetError` before any work.
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

    Examples
    --------
    >>> import dustoptics as do
    >>> t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 90.0, 180.0])
    >>> round(float(t.qext[0]), 6)
    3.092896
    """
    if wavelengths_nm is not None:
        if wavelength_nm is not None:
            raise TypeError(
                "give wavelength_nm only (wavelengths_nm is its deprecated spelling), not both"
            )
        warnings.warn(
            "compute_optics(wavelengths_nm=...) is deprecated; use wavelength_nm=",
            DeprecationWarning,
            stacklevel=2,
        )
        wavelength_nm = wavelengths_nm
    if not isinstance(distribution, SizeDistribution):
        raise ValueError(
            f"distribution must be a dustoptics SizeDistribution (e.g. ModifiedGamma); got {distribution!r}"
        )
    if not (distribution.has_density or distribution.is_monodisperse):
        raise ValueError(
            "distribution mixes Monodisperse and continuous modes, which the radius "
            f"quadrature does not support; got {distribution!r}"
        )
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
    rtol = check_open_interval("rtol", rtol, 0.0, 0.1)
    cross_rtol = (
        rtol / 100.0
        if cross_section_rtol is None
        else check_open_interval("cross_section_rtol", cross_section_rtol, 0.0, 0.1)
    )
    if not isinstance(weighting, str):
        raise TypeError(f"weighting must be a str, one of {WEIGHTINGS}; got {weighting!r}")
    check_choice("weighting", weighting, WEIGHTINGS)
    if not isinstance(allow_large, bool):
        raise TypeError(f"allow_large must be True or False; got {allow_large!r}")
    settings = QuadratureSettings() if quadrature is None else quadrature
    if not isinstance(settings, QuadratureSettings):
        raise ValueError(f"quadrature must be a QuadratureSettings; got {quadrature!r}")
    if workers is None:
        workers = os.cpu_count() or 1
    elif not (isinstance(workers, int) and workers >= 1):
        raise ValueError(f"workers must be a positive integer; got {workers!r}")
    if not isinstance(name, str) or not name:
        raise ValueError(f"name must be a non-empty string; got {name!r}")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be a callable progress(done, total); got {progress!r}")
    cost = check_cost(
        distribution,
        wl,
        theta.size,
        settings=settings,
        weighting=weighting,
        workers=workers,
        allow_large=allow_large,
    )
    if not isinstance(polarization, (bool, np.bool_)):
        raise ValueError(f"polarization must be True or False; got {polarization!r}")
    n_order = _check_expansion(expansion)
    derivative_names = check_parameters(
        derivatives, distribution, index_parameter_names(refractive_index)
    )
    if derivative_names and isinstance(refractive_index, CoatedSphere):
        raise ValueError(
            "derivatives are not available for coated spheres (CoatedSphere); got "
            f"derivatives={derivative_names!r}"
        )
    density = (
        None
        if particle_density_kg_m3 is None
        else check_positive("particle_density_kg_m3", particle_density_kg_m3, unit="kg m-3")
    )
    if isinstance(refractive_index, CoatedSphere):
        m, shell_label = resolve_refractive_index(refractive_index.shell, wl)
        m_core, core_label = resolve_refractive_index(refractive_index.core, wl)
        core_fraction = refractive_index.radius_fraction
        label = refractive_index.describe(core_label, shell_label)
    else:
        m, label = resolve_refractive_index(refractive_index, wl)
        m_core, core_fraction = np.zeros_like(m), 0.0

    mu_out = np.cos(np.deg2rad(theta))
    per_particle = weighting == "number"
    n_stokes = mie.N_STOKES if (polarization or n_order is not None) else 1
    # The expansion coefficients' own tolerance (issue 30): as the cross-sections'.
    expansion_rtol = None if n_order is None else rtol / 100.0

    def one(i: int) -> _Result:
        solver = _WavelengthSolver(
            m=complex(m[i]),
            wavelength_nm=float(wl[i]),
            mu_out=mu_out,
            distribution=distribution,
            per_particle=per_particle,
            settings=settings,
            n_stokes=n_stokes,
            expansion=n_order is not None,
            m_core=complex(m_core[i]),
            core_fraction=core_fraction,
        )
        return solver.solve(rtol, cross_rtol, expansion_rtol)

    def report(done: int) -> None:
        if progress is not None:
            progress(done, wl.size)

    report(0)
    results: list[_Result] = []
    n_threads = min(workers, wl.size)
    if n_threads > 1:
        # In a process that has not computed a table yet, the first wavelength
        # alone compiles (or loads from numba's cache) the kernels before
        # threads share them; after that, it is the costliest wavelength to
        # leave to one thread.  Each wavelength's result is the same either way.
        if not kernels_loaded():
            results.append(one(0))
            report(1)
        with ThreadPoolExecutor(max_workers=n_threads) as pool:
            for result in pool.map(one, range(len(results), wl.size)):
                results.append(result)
                report(len(results))
    else:
        for i in range(wl.size):
            results.append(one(i))
            report(i + 1)

    err_phase = np.array([r.err_phase for r in results])
    err_cross = np.array([r.err_cross for r in results])
    phase = np.vstack([r.phase for r in results])
    cext = np.array([r.cext for r in results])
    csca = np.array([r.csca for r in results])
    finite = np.all(np.isfinite(phase)) and np.all(np.isfinite(cext)) and np.all(np.isfinite(csca))
    if not (finite and np.all(phase > 0) and np.all(csca > 0)):
        raise ValueError(
            f"compute_optics: refractive_index {label} with distribution {distribution!r} at "
            f"{wl[0]:g} .. {wl[-1]:g} nm gives a phase function or cross-section that is not finite "
            "and positive: the input lies outside the kernel's tested domain "
            f"(size parameters {cost.min_size_parameter:.3g} .. {cost.max_size_parameter:.3g})"
        )
    # Absorption: <C_abs> = <C_ext> - <C_sca> >= 0.  With k = 0 it is exactly 0
    # (no absorption, an identity of the physics); with k > 0 the difference
    # is kept unless it is negative beyond round-off (1e-12 of <C_ext>), which
    # would be a wrong number and raises.
    # (A coated sphere absorbs if its shell or its core does.)
    lossless = (m.imag == 0.0) & ((m_core.imag == 0.0) | (core_fraction == 0.0))
    cabs = np.where(lossless, 0.0, cext - csca)
    cext = np.where(lossless, csca, cext)
    if np.any(cabs < -1e-12 * cext):
        i = int(np.argmax(cabs < -1e-12 * cext))
        raise ValueError(
            f"compute_optics: <C_abs> = {cabs[i]!r} um^2 < 0 at {wl[i]:g} nm for refractive_index "
            f"{label} with distribution {distribution!r}: the input lies outside the kernel's tested domain"
        )
    csca = np.minimum(csca, cext)
    extra = _matrix_fields(results, polarization=bool(polarization), n_order=n_order)
    if polarization:
        err_phase = np.maximum(err_phase, extra["matrix_error_estimate"])
    not_converged = (err_phase > rtol) | (err_cross > cross_rtol)
    if expansion_rtol is not None:
        not_converged |= extra["expansion_error_estimate"] > expansion_rtol
    if not_converged.any():
        bad = ", ".join(f"{w:g}" for w in wl[not_converged])
        also = "" if expansion_rtol is None else f" / expansion rtol={expansion_rtol:g}"
        warnings.warn(
            f"radius quadrature did not reach rtol={rtol:g} / cross_section_rtol={cross_rtol:g}{also} "
            f"at wavelengths {bad} nm within max_level={settings.max_level}; "
            "see error_estimate",
            ConvergenceWarning,
            stacklevel=2,
        )
    n_nodes = np.array([r.n_nodes for r in results], dtype=np.int64)
    cross_n_nodes = np.array([r.cross_section_n_nodes for r in results], dtype=np.int64)
    inputs = {
        "refractive_index": {"description": label, "n": m.real, "k": m.imag},
        "size_distribution": distribution.to_dict(),
        "wavelength_nm": wl,
        "theta_deg": theta,
        "weighting": weighting,
        "rtol": rtol,
        "cross_section_rtol": cross_rtol,
        "quadrature": settings,
    }
    # Recorded only when used, so that other tables' provenance is unchanged.
    if polarization:
        inputs["polarization"] = True
    if n_order is not None:
        inputs["expansion"] = True if n_order < 0 else n_order
    if density is not None:
        inputs["particle_density_kg_m3"] = density
    if derivative_names:
        inputs["derivatives"] = list(derivative_names)
    if core_fraction > 0.0 or isinstance(refractive_index, CoatedSphere):
        inputs["core"] = {
            "n": m_core.real,
            "k": m_core.imag,
            "core_radius_fraction": core_fraction,
        }
    moments = np.array([r.moments for r in results])
    record = {
        "method": "adaptive Gauss-Legendre panels over radius (dustoptics.scattering.quadrature), "
        "error = summed differences of each panel's rule and the rules on its halves",
        "weighting": weighting,
        "rtol": rtol,
        "cross_section_rtol": cross_rtol,
        "settings": settings,
        "converged": not bool(not_converged.any()),
        "max_error_estimate": float(err_phase.max()),
        "max_cross_section_error_estimate": float(err_cross.max()),
        "n_nodes_total": int(n_nodes.sum()),
        "cross_section_n_nodes_total": int(cross_n_nodes.sum()),
    }
    if expansion_rtol is not None:  # recorded only when used (other provenance unchanged)
        record["expansion_rtol"] = expansion_rtol
        record["max_expansion_error_estimate"] = float(extra["expansion_error_estimate"].max())
    sources = (
        _index_source(refractive_index, label),
        Source(name=distribution.model, role="size distribution", citation=distribution.citation),
    )
    records = records_from_fields(dict(extra))
    table = Table(
        name=name,
        wavelength_nm=wl,
        theta_deg=theta,
        phase=phase,
        g=np.array([r.g for r in results]),
        refractive_index=m,
        cross_sections=CrossSections(
            cext_um2=cext,
            csca_um2=csca,
            cback_um2=np.array([r.cback for r in results]),
            mean_geometric_cross_section_um2=float(distribution.mean_cross_section_um2),
            mean_volume_um3=float(distribution.mean_volume_um3),
            particle_density_kg_m3=density,
        ),
        quadrature=QuadratureRecord(
            error_estimate=err_phase,
            cross_section_error_estimate=err_cross,
            n_nodes=n_nodes,
            cross_section_n_nodes=cross_n_nodes,
            r_eff_quadrature_um=moments[:, 1] / moments[:, 0],
            v_eff_quadrature=moments[:, 2] * moments[:, 0] / moments[:, 1] ** 2 - 1.0,
            mean_volume_quadrature_um3=4.0 / 3.0 * np.pi * moments[:, 1],
        ),
        matrix=records["matrix"],
        expansion=records["expansion"],
        provenance=Provenance(inputs=plain(inputs), sources=sources, quadrature=plain(record)),
        diagnostics=QuadratureDiagnostics(
            settings=settings,
            distribution=distribution,
            panels=tuple(r.panels_s for r in results),
            cross_section_panels=tuple(r.cross_section_panels_s for r in results),
            expansion_panels=(
                None
                if expansion_rtol is None
                else tuple(
                    r.panels_s if r.expansion_panels_s is None else r.expansion_panels_s
                    for r in results
                )
            ),
        ),
    )
    if not derivative_names:
        return table
    return table.replace(
        derivatives=table_derivatives(
            table,
            parameters=derivative_names,
            index_directions=index_directions(refractive_index, derivative_names, wl),
            weighting=weighting,
            workers=workers,
        )
    )


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
    index = inputs["refractive_index"]
    m = np.asarray(index["n"], dtype=np.float64) + 1j * np.asarray(index["k"], dtype=np.float64)
    particle: Any = m.tolist()
    # Derivatives again, as recorded; a mixture's parameters (hematite_fraction, ...)
    # are refused before any work: the recorded index values do not hold the mixture.
    derivatives = tuple(inputs.get("derivatives", ()))
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
    table = compute_optics(
        particle,
        _distribution_from_dict(inputs["size_distribution"]),
        inputs["wavelength_nm"],
        inputs["theta_deg"],
        inputs["rtol"],
        inputs["weighting"],
        cross_section_rtol=inputs["cross_section_rtol"],
        quadrature=QuadratureSettings(**inputs["quadrature"]),
        workers=workers,
        name=name,
        polarization=bool(inputs.get("polarization", False)),
        expansion=inputs.get("expansion", False),
        particle_density_kg_m3=inputs.get("particle_density_kg_m3"),
        derivatives=derivatives,
    )
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


def _matrix_fields(
    results: Sequence[_Result], *, polarization: bool, n_order: int | None
) -> dict[str, Any]:
    """The optional matrix and expansion fields of a table from the
    wavelengths' results (coefficients zero-padded to one order count)."""
    out: dict[str, Any] = {}
    if not (polarization or n_order is not None):
        return out
    matrices = [r.matrix for r in results if r.matrix is not None]
    assert len(matrices) == len(results)
    if polarization:
        for key in ("f12", "f33", "f34"):
            out[key] = np.vstack([getattr(mx, key) for mx in matrices])
        out["matrix_error_estimate"] = np.array([mx.error for mx in matrices])
    if n_order is not None:
        greek = [mx.greek for mx in matrices if mx.greek is not None]
        assert len(greek) == len(results)
        size = max(g.shape[1] for g in greek) if n_order < 0 else n_order + 1
        coefficients = np.zeros((6, len(results), size))
        for i, g in enumerate(greek):
            k = min(size, g.shape[1])
            coefficients[:, i, :k] = g[:, :k]
        for j, key in enumerate(("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")):
            out[key] = coefficients[j]
        out["expansion_error_estimate"] = np.array([mx.greek_error for mx in matrices])
    return out
