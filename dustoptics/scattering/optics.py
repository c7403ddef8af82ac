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
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, NamedTuple, cast

import numpy as np
from numba import njit

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
from dustoptics.scattering.expansion import greek_coefficients
from dustoptics.scattering.quadrature import (
    _UPPER_MOMENT,
    QuadratureDiagnostics,
    QuadratureSettings,
    _stretch,
    _wright_omega,
    gauss_legendre,
    initial_panels,
    panel_nodes,
    size_parameter_at,
)
from dustoptics.table import DEFAULT_NAME, Provenance, Source, Table, plain

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


@njit(cache=True, nogil=True)
def _n_max(x: float) -> float:
    """:func:`mie.wiscombe_nmax` before rounding down: x + 4.05 x^(1/3) + 2."""
    return x + 4.05 * np.cbrt(x) + 2.0


#: Refinement splits panels until the unsplit ones hold less than this
#: fraction of the tolerance (see :meth:`_WavelengthSolver.refine`).
_KEEP_FRACTION = 0.9


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


@dataclass(frozen=True)
class _Result:
    phase: np.ndarray
    cext: float
    csca: float
    g: float
    n_nodes: int
    cross_section_n_nodes: int
    err_phase: float
    err_cross: float
    panels_s: np.ndarray
    cross_section_panels_s: np.ndarray
    cback: float = float("nan")
    matrix: _Matrix | None = None
    # Sums of w r^2, w r^3, w r^4 [um^k] over the cross-sections' radius nodes.
    moments: tuple[float, float, float] = (float("nan"),) * 3


@dataclass(frozen=True)
class _Run:
    """One converged refinement: the summed row, its final panels and error."""

    total: np.ndarray
    panels_s: np.ndarray
    n_nodes: int
    error: float
    # With the matrix: per block (I, Q, U, V), the summed panel differences
    # relative to I at each Gauss node, then the normalization's (see
    # :func:`_matrix_refinement_errors`).
    block_errors: np.ndarray | None = None


class _Panels(NamedTuple):
    """Refinement state: panels [lower, upper] in s with rows of their coarse
    rule and of the rules on their left and right halves."""

    lower: np.ndarray
    upper: np.ndarray
    coarse: np.ndarray
    left: np.ndarray
    right: np.ndarray


@lru_cache(maxsize=32)
def _gauss_angles(n_half: int) -> tuple[np.ndarray, ...]:
    """Positive half of the 2 n_half-point Gauss rule in mu, its weights, and
    pi_n, tau_n there for n <= n_half - 1 (:func:`mie.angular_table`; 2 n_half
    >= 2 n_max + 2 nodes integrate |S|^2 P_l, degree <= 4 n_max, exactly).
    Cached: they depend on n_half alone, and wavelengths share them.  Not to
    be modified."""
    mu_g, w_g = gauss_legendre(2 * n_half)
    mu_half = np.ascontiguousarray(mu_g[n_half:])
    w_half = np.ascontiguousarray(w_g[n_half:])
    return mu_half, w_half, mie.angular_table(mu_half, n_half - 1)


@lru_cache(maxsize=8)
def _angular_tiers(n_half: int) -> tuple[np.ndarray, ...]:
    """Angular tiers below the grid of n_half half-grid angles, flattened for
    :func:`mie._accumulate_tiers`: tier sizes, their angular tables and start
    offsets, the interpolation maps to the full grid and their offsets.

    A panel whose spheres need fewer orders is summed on a smaller Gauss grid
    (cost ~ n_max x n_angles per sphere) and moved to the full grid by exact
    polynomial interpolation (:func:`mie._interpolation_maps`).  Tier sizes
    fall by 2^(1/4), in multiples of 16, down to 32 half-grid angles.  Cached
    (neighbouring wavelengths share n_half, and a table over 360-830 nm
    spans about 8 values; ~2 MB each at n_half ~ 200, ~20 MB at 500).
    Not to be modified.
    """
    tiers = {n_half}
    k = 1
    while (t := 16 * -(-int(n_half * 2.0 ** (-k / 4)) // 16)) >= 32:
        tiers.add(t)
        k += 1
    sizes = np.array(sorted(tiers))
    tables = [_gauss_angles(int(t))[2].ravel() for t in sizes]
    maps, map_start = _stacked_interpolation_maps(sizes[:-1], n_half)
    return (
        sizes,
        np.concatenate(tables),
        np.cumsum([0] + [a.size for a in tables]),
        maps,
        map_start,
    )


def _stacked_interpolation_maps(sizes: np.ndarray, n_half: int) -> tuple[np.ndarray, np.ndarray]:
    """Interpolation maps from the Gauss grids of ``sizes`` half-grid angles
    to the grid of ``n_half`` (:func:`mie._interpolation_maps`), stacked in
    one flat array: for each size, R_even then R_odd.  Returns the array and
    the start of each size's maps (one more, the end).  The maps are written
    in place: at n_half ~ 1,000 they take ~100 MB, and building each apart
    then joining them took more time than computing them."""
    mu_half = _gauss_angles(n_half)[0]
    start = np.zeros(len(sizes) + 1, dtype=np.int64)
    start[1:] = np.cumsum(2 * np.asarray(sizes, dtype=np.int64) * n_half)
    maps = np.empty(int(start[-1]))
    for i, n in enumerate(sizes):
        mu, w = _gauss_angles(int(n))[:2]
        block = maps[start[i] : start[i + 1]]
        half = int(n) * n_half
        mie._interpolation_maps_into(
            mu,
            w,
            mu_half,
            block[:half].reshape(int(n), n_half),
            block[half:].reshape(int(n), n_half),
        )
    return maps, start


@njit(cache=True, nogil=True)
def _halves_total(pool: np.ndarray, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Sum over panels p of the rows ``pool[left[p]] + pool[right[p]]``, panel
    after panel: the refinement's current result."""
    total = np.zeros(pool.shape[1])
    for p in range(left.shape[0]):
        a = pool[left[p]]
        b = pool[right[p]]
        for c in range(pool.shape[1]):
            total[c] += a[c] + b[c]
    return total


@njit(cache=True, nogil=True)
def _phase_refinement_errors(
    pool: np.ndarray, coarse: np.ndarray, left: np.ndarray, right: np.ndarray, n_f: int, norm: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """Summed row and relative phase errors of a refinement state.

    Panel p has rows ``pool[coarse[p]]`` (its coarse rule) and ``pool[left[p]]``,
    ``pool[right[p]]`` (the rules on its halves).  Returns the sum over panels of
    the halves' rows F; per panel max_mu |dF_p(mu)| / F(mu) plus the relative
    change of the normalization (column ``norm``: sum w, or sum w x^2 Q_sca);
    and for the sum max_mu sum_p |dF_p(mu)| / F(mu) plus the summed relative
    changes of the normalization.  One pass over the rows, no temporaries.
    """
    n_p = coarse.shape[0]
    total = _halves_total(pool, left, right)
    column = np.zeros(n_f)
    panel_error = np.empty(n_p)
    norm_sum = 0.0
    for p in range(n_p):
        a = pool[left[p]]
        b = pool[right[p]]
        z = pool[coarse[p]]
        rel_norm = abs(a[norm] + b[norm] - z[norm]) / total[norm]
        worst = 0.0
        for i in range(n_f):
            d = abs(a[i] + b[i] - z[i]) / total[i]
            column[i] += d
            worst = max(worst, d)
        panel_error[p] = worst + rel_norm
        norm_sum += rel_norm
    # max over mu as np.max would (a NaN propagates), without its generic compile.
    worst_sum = column[0]
    for i in range(1, n_f):
        if column[i] > worst_sum or column[i] != column[i]:
            worst_sum = column[i]
    return total, panel_error, worst_sum + norm_sum


@njit(cache=True, nogil=True)
def _cross_refinement_errors(
    pool: np.ndarray, coarse: np.ndarray, left: np.ndarray, right: np.ndarray, norm: int, gnum: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """Summed row and errors of <C_ext>, <C_sca> (relative) and g (absolute)
    of a refinement state of rows of sums (see :func:`_phase_refinement_errors`):
    per panel the largest of the three, and the largest of their sums over
    panels.  g = num / norm (columns ``gnum`` and ``norm``), so
    |dg| <= (|d num| + |g| |d norm|) / norm.
    """
    n_p = coarse.shape[0]
    total = _halves_total(pool, left, right)
    g = abs(total[gnum] / total[norm])
    panel_error = np.empty(n_p)
    sums = np.zeros(3)
    for p in range(n_p):
        a = pool[left[p]]
        b = pool[right[p]]
        z = pool[coarse[p]]
        e_ext = abs(a[1] + b[1] - z[1]) / total[1]
        e_sca = abs(a[2] + b[2] - z[2]) / total[2]
        e_g = (abs(a[gnum] + b[gnum] - z[gnum]) + g * abs(a[norm] + b[norm] - z[norm])) / total[
            norm
        ]
        panel_error[p] = max(e_ext, e_sca, e_g)
        sums[0] += e_ext
        sums[1] += e_sca
        sums[2] += e_g
    return total, panel_error, max(sums[0], sums[1], sums[2])


@njit(cache=True, nogil=True)
def _stable_argsort(keys: np.ndarray) -> np.ndarray:
    """np.argsort(keys, kind="mergesort") for 1-d float64 keys (stable, NaN last).

    A bottom-up merge sort of the indices.  Written out because numba's
    generic merge sort compiles for about 2 s; a stable sort's order is
    unique, so the result is the same.
    """
    n = keys.shape[0]
    order = np.arange(n)
    scratch = np.empty(n, dtype=np.int64)
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i = lo
            j = mid
            k = lo
            while i < mid and j < hi:
                a = keys[order[i]]
                b = keys[order[j]]
                # b < a, with NaN after every number: take from the right only then.
                if b < a or (a != a and b == b):
                    scratch[k] = order[j]
                    j += 1
                else:
                    scratch[k] = order[i]
                    i += 1
                k += 1
            while i < mid:
                scratch[k] = order[i]
                i += 1
                k += 1
            while j < hi:
                scratch[k] = order[j]
                j += 1
                k += 1
        order, scratch = scratch, order
        width *= 2
    return order


@njit(cache=True, nogil=True)
def _search_left(a: np.ndarray, v: float) -> int:
    """np.searchsorted(a, v) (side "left", NaN sorted last) for increasing float64 ``a``.

    Written out because numba's searchsorted compiles comparisons for every
    numeric type, complex included (about 1 s).
    """
    lo = 0
    hi = a.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if a[mid] < v or (v != v and a[mid] == a[mid]):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def _choose_splits(
    panel_error: np.ndarray,
    cost: np.ndarray,
    tol: float,
    keep_fraction: float,
    lower: np.ndarray,
    upper: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The panels to split, and the edges of the halves of their halves.

    Panels in order of error per unit of ``cost`` (stable) until the rest hold
    less than ``keep_fraction`` of ``tol``.  Returns the split panels' indices
    (increasing) and the lower and upper edges of the 2k panels to evaluate:
    the new panels are the split panels' left halves, then their right
    halves, and each is evaluated on its own two halves (left halves of all
    new panels first).
    """
    badness = panel_error / tol
    order = _stable_argsort(-badness / cost)
    cumulative = np.cumsum(badness[order])
    n_split = min(_search_left(cumulative, cumulative[-1] - keep_fraction) + 1, order.shape[0])
    chosen = np.zeros(badness.shape[0], dtype=np.bool_)
    for i in range(n_split):
        chosen[order[i]] = True
    split = np.flatnonzero(chosen)  # increasing
    k = split.shape[0]
    new_lower = np.empty(2 * k)
    new_upper = np.empty(2 * k)
    for i in range(k):
        lo = lower[split[i]]
        hi = upper[split[i]]
        mid = 0.5 * (lo + hi)
        new_lower[i] = lo
        new_upper[i] = mid
        new_lower[k + i] = mid
        new_upper[k + i] = hi
    eval_lower = np.empty(4 * k)
    eval_upper = np.empty(4 * k)
    for i in range(2 * k):
        mid = 0.5 * (new_lower[i] + new_upper[i])
        eval_lower[i] = new_lower[i]
        eval_upper[i] = mid
        eval_lower[2 * k + i] = mid
        eval_upper[2 * k + i] = new_upper[i]
    return split, eval_lower, eval_upper


@njit(cache=True, nogil=True)
def _apply_splits(
    pool: np.ndarray,
    n_rows: int,
    rows: np.ndarray,
    split: np.ndarray,
    coarse: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    cost: np.ndarray,
    new_cost: np.ndarray,
    eval_lower: np.ndarray,
    eval_upper: np.ndarray,
):
    """The refinement state after splitting panels ``split`` (see
    :func:`_choose_splits`): ``rows`` hold the new panels' left-half rows, then
    their right-half rows; each new panel's coarse row is its parent's half.
    Kept panels stay in order, the new ones follow.  Rows are appended to
    ``pool`` (grown by doubling when full); returns the pool, its row count,
    and the panels' coarse, left and right row indices, edges and costs.
    """
    k2 = rows.shape[0] // 2  # new panels
    width = pool.shape[1]
    if n_rows + 2 * k2 > pool.shape[0]:
        grown = np.empty((2 * (n_rows + 2 * k2), width))
        for r in range(n_rows):
            for c in range(width):
                grown[r, c] = pool[r, c]
        pool = grown
    for r in range(2 * k2):
        for c in range(width):
            pool[n_rows + r, c] = rows[r, c]
    keep = np.ones(lower.shape[0], dtype=np.bool_)
    for p in split:
        keep[p] = False
    n_keep = lower.shape[0] - split.shape[0]
    size = n_keep + k2
    new_coarse = np.empty(size, dtype=np.int64)
    new_left = np.empty(size, dtype=np.int64)
    new_right = np.empty(size, dtype=np.int64)
    new_lower = np.empty(size)
    new_upper = np.empty(size)
    new_costs = np.empty(size)
    i = 0
    for p in range(lower.shape[0]):
        if keep[p]:
            new_coarse[i] = coarse[p]
            new_left[i] = left[p]
            new_right[i] = right[p]
            new_lower[i] = lower[p]
            new_upper[i] = upper[p]
            new_costs[i] = cost[p]
            i += 1
    k = split.shape[0]
    for h in range(k2):
        parent = split[h % k]
        new_coarse[i] = left[parent] if h < k else right[parent]
        new_left[i] = n_rows + h
        new_right[i] = n_rows + k2 + h
        new_lower[i] = eval_lower[h]
        new_upper[i] = eval_upper[k2 + h]
        new_costs[i] = new_cost[h]
        i += 1
    return pool, n_rows + 2 * k2, new_coarse, new_left, new_right, new_lower, new_upper, new_costs


@njit(cache=True, nogil=True)
def _panel_cost(upper: np.ndarray, x_c: float, angles: bool) -> np.ndarray:
    """Relative work of evaluating a panel ending at s = ``upper``: with n =
    n_max at its end (x = x_c omega(s)), ~ (n + 8)^2 with angles (orders x
    tier angles, a tier ~ n + 8 angles), ~ n + 20 for the coefficients alone."""
    cost = np.empty(upper.shape[0])
    for i in range(upper.shape[0]):
        n = _n_max(x_c * _wright_omega(upper[i]))
        cost[i] = (n + 8.0) ** 2 if angles else n + 20.0
    return cost


@njit(cache=True, nogil=True)
def _accumulate_by_tier(
    m: complex,
    x: np.ndarray,
    w: np.ndarray,
    node_panel: np.ndarray,
    nodes_per_panel: int,
    per_particle: bool,
    tiers: np.ndarray,
    tables: np.ndarray,
    table_start: np.ndarray,
    maps: np.ndarray,
    map_start: np.ndarray,
    n_stokes: int,
    m_core: complex,
    core_fraction: float,
) -> np.ndarray:
    """Rows of :func:`mie._accumulate_tiers` for nodes given panel after panel.

    Each panel is summed on the smallest tier that holds n_max + 2 orders of
    its largest sphere (wiscombe_nmax + 1, plus 1 so that the rounding of the
    cube root can never pick a tier one order short: the kernel reads the
    tables without bounds checks).  The nodes go to the kernel by tier, then
    by size, so that its batches hold spheres of similar n_max.
    """
    n_panels = x.shape[0] // nodes_per_panel
    n_tiers = tiers.shape[0]
    panel_tier = np.empty(n_panels, dtype=np.int64)
    x_first = np.empty(n_panels)
    count = np.zeros(n_tiers + 1, dtype=np.int64)
    for p in range(n_panels):
        x_top = x[p * nodes_per_panel]
        for j in range(p * nodes_per_panel, (p + 1) * nodes_per_panel):
            x_top = max(x_top, x[j])
        # The first tier that holds n_max + 2 orders (np.searchsorted, side "left").
        need = int(_n_max(x_top)) + 2
        t = 0
        while t < n_tiers and tiers[t] < need:
            t += 1
        panel_tier[p] = t
        if panel_tier[p] == n_tiers:
            raise ValueError(
                "a panel's spheres need more orders than the largest angular tier holds"
            )
        x_first[p] = x[p * nodes_per_panel]
        count[panel_tier[p] + 1] += 1
    # Panels are disjoint, and x grows along each panel's nodes, so ordering
    # the panels by tier, then by their first node, orders the nodes by tier,
    # then by x: a stable sort by x, then a counting sort by tier.
    for t in range(n_tiers):
        count[t + 1] += count[t]
    by_tier = np.empty(n_panels, dtype=np.int64)
    for p in _stable_argsort(x_first):
        by_tier[count[panel_tier[p]]] = p
        count[panel_tier[p]] += 1
    x_sorted = np.empty(x.shape[0])
    w_sorted = np.empty(x.shape[0])
    panel_sorted = np.empty(x.shape[0], dtype=np.int64)
    node_tier = np.empty(x.shape[0], dtype=np.int64)
    for k in range(n_panels):
        p = by_tier[k]
        for i in range(nodes_per_panel):
            j = p * nodes_per_panel + i
            x_sorted[k * nodes_per_panel + i] = x[j]
            w_sorted[k * nodes_per_panel + i] = w[j]
            panel_sorted[k * nodes_per_panel + i] = node_panel[j]
            node_tier[k * nodes_per_panel + i] = panel_tier[p]
    return mie._accumulate_tiers(
        m,
        x_sorted,
        w_sorted,
        panel_sorted,
        node_tier,
        n_panels,
        per_particle,
        tiers,
        tables,
        table_start,
        maps,
        map_start,
        n_stokes,
        m_core,
        core_fraction,
    )


# ----------------------------------------------------------------------------
# The scattering matrix and its expansion (compute_optics(polarization=True,
# expansion=...)): the refinement's error per matrix element, and the
# elements and coefficients from the refined sums.
# ----------------------------------------------------------------------------


@njit(cache=True, nogil=True)
def _matrix_refinement_errors(
    pool: np.ndarray,
    coarse: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    n_f: int,
    n_stokes: int,
    norm: int,
) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """:func:`_phase_refinement_errors` for rows of ``n_stokes`` angular
    blocks (I, Q, U, V; see ``mie.N_STOKES``), every block's differences
    relative to I at the same angle (the matrix elements' errors relative to
    F11).  Returns the summed row; per panel the largest relative difference
    in any block plus the normalization's; the largest over blocks of the
    summed estimate; and per block the summed differences at each angle
    (relative to I) with the normalization's summed relative change appended
    (shape (n_stokes, n_f + 1)).  Block 0 gives the phase function's error
    exactly as :func:`_phase_refinement_errors` does.
    """
    n_p = coarse.shape[0]
    total = _halves_total(pool, left, right)
    columns = np.zeros((n_stokes, n_f + 1))
    panel_error = np.empty(n_p)
    norm_sum = 0.0
    for p in range(n_p):
        a = pool[left[p]]
        b = pool[right[p]]
        z = pool[coarse[p]]
        rel_norm = abs(a[norm] + b[norm] - z[norm]) / total[norm]
        worst = 0.0
        for k in range(n_stokes):
            col = columns[k]
            o = k * n_f
            for i in range(n_f):
                d = abs(a[o + i] + b[o + i] - z[o + i]) / total[i]
                col[i] += d
                worst = max(worst, d)
        panel_error[p] = worst + rel_norm
        norm_sum += rel_norm
    error = 0.0
    for k in range(n_stokes):
        columns[k, n_f] = norm_sum
        error = max(error, np.max(columns[k, :n_f]) + norm_sum)
    return total, panel_error, error, columns


@dataclass(frozen=True)
class _Matrix:
    """One wavelength's matrix elements (normalized like the phase function),
    their error estimate relative to F11, and the expansion coefficients."""

    f12: np.ndarray
    f33: np.ndarray
    f34: np.ndarray
    error: float
    greek: np.ndarray | None
    greek_error: float


def _finish_matrix(solver: _WavelengthSolver, phase_run: _Run, scale: float) -> _Matrix:
    """F12, F33, F34 at the output angles and, on the Gauss grid, the
    expansion coefficients of orders 0..2 n_max (see
    :mod:`dustoptics.scattering.expansion`), from a refined run with the
    four blocks I, Q, U, V; ``scale`` turns summed I into the phase function."""
    n_f = solver.n_f
    blocks = phase_run.block_errors
    assert blocks is not None
    values = [phase_run.total[k * n_f : (k + 1) * n_f] for k in range(mie.N_STOKES)]
    if solver.gauss:
        lmax = 2 * solver.nmax
        at_output = [
            mie._legendre_evaluate(
                mie._legendre_project(solver.mu_half, solver.w_half, np.ascontiguousarray(v), lmax),
                solver.mu_out,
            )
            for v in values[1:]
        ]
    else:
        at_output = list(values[1:])
    error = max(float(np.max(blocks[k, :n_f]) + blocks[k, n_f]) for k in range(1, mie.N_STOKES))
    greek = None
    greek_error = float("nan")
    if solver.want_greek:
        mu = np.concatenate([solver.mu_half, -solver.mu_half])
        w = np.concatenate([solver.w_half, solver.w_half])
        a1, b1, a3, b2 = (4.0 * np.pi * scale * v for v in values)
        greek = greek_coefficients(
            mu=mu, weight=w, a1=a1, a3=a3, b1=b1, b2=b2, lmax=2 * solver.nmax
        )
        # (1/2) int a1 dmu is 1 to round-off (~1e-13); make alpha1_0 exactly 1.
        greek = greek / greek[0, 0]
        # |d^l_mn| <= 1, so each coefficient over (2 l + 1) moves by at most
        # (1/2) int |da| dmu: the blocks' summed differences times a1, plus
        # the normalization's relative change.
        greek_error = float(0.5 * np.sum(w * a1 * np.sum(blocks[:, :n_f], axis=0)) + blocks[0, n_f])
    return _Matrix(
        f12=at_output[0] * scale,
        f33=at_output[1] * scale,
        f34=at_output[2] * scale,
        error=error,
        greek=greek,
        greek_error=greek_error,
    )


class _WavelengthSolver:
    """One wavelength: angular tables once, then adaptive refinement over radius.

    Each panel is integrated twice, with one n-point Gauss-Legendre rule and
    with one on each of its halves; the difference estimates the coarse rule's
    error, and the halves' sum is kept.  Panels are split, most error per unit
    of work first, until the summed estimates meet the tolerance; a split
    panel's halves already know their coarse values, so no evaluation is
    ever repeated.

    Two refinements run one after the other, because their costs differ: the
    phase function (sums over angles, O(n_max^2) a sphere) to ``rtol``, then
    the cross-sections and g (O(n_max) a sphere) to ``cross_section_rtol``,
    continuing from the phase function's panels without angles.  Refining both
    with one criterion spent the angular sums on nodes that only the
    cross-sections' tighter tolerance needed.
    """

    def __init__(
        self,
        *,
        m: complex,
        wavelength_nm: float,
        mu_out: np.ndarray,
        distribution: SizeDistribution,
        per_particle: bool,
        settings: QuadratureSettings,
        n_stokes: int = 1,
        expansion: bool = False,
        m_core: complex = 0j,
        core_fraction: float = 0.0,
    ) -> None:
        self.m = m
        # Coated spheres: core index and radius fraction (0: homogeneous).
        self.m_core = m_core
        self.core_fraction = core_fraction
        # 4: the scattering matrix (I, Q, U, V blocks, see mie.N_STOKES); 1: the phase function.
        self.n_stokes = n_stokes
        self.wavelength_um = wavelength_nm * 1e-3
        self.wavelength_nm = wavelength_nm
        self.mu_out = mu_out
        self.distribution = distribution
        self.per_particle = per_particle
        self.settings = settings
        if distribution.is_monodisperse:
            self.edges = np.empty(0)
            x_top = 2.0 * np.pi * distribution.mean_radius_um / self.wavelength_um
        else:
            self.edges = initial_panels(
                distribution,
                wavelength_nm=wavelength_nm,
                settings=settings,
                lower_moment=0 if per_particle else 2,
            )
            x_top = float(size_parameter_at(self.edges[-1], settings=settings))
        # Every node lies below the top panel's end; n_max there bounds all.
        self.nmax = mie.wiscombe_nmax(max(x_top, 1e-3) * 1.0001 + 1.0)
        n_half = 16 * ((self.nmax + 1 + 15) // 16)
        # Sum at Gauss angles and project on Legendre polynomials when that is
        # cheaper than summing at every output angle.  2 n_half >= 2 nmax + 2
        # nodes integrate |S|^2 P_l (degree <= 4 nmax) exactly.
        # ``gauss`` asks for the Gauss grid whatever the output angles (the
        # expansion coefficients are projected from it).
        self.want_greek = expansion
        self.gauss = expansion or (n_half < mu_out.size and not distribution.is_monodisperse)
        self.legendre = self.gauss and not distribution.is_monodisperse
        if self.gauss:
            self.n_half = n_half
            self.mu_half, self.w_half = _gauss_angles(n_half)[:2]
            self.n_f = 2 * n_half
            if self.legendre:
                self.tiers, self._tables, self._table_start, self._maps, self._map_start = (
                    _angular_tiers(n_half)
                )
            else:  # one sphere on the Gauss grid
                self.table = _gauss_angles(n_half)[2]
        else:
            # Summed at the output angles directly (few angles, or one sphere).
            self.table = mie.angular_table(mu_out, self.nmax)
            self.n_f = mu_out.size
        self.matrix = n_stokes > 1
        # Cross-sections alone: no angles.
        self.no_angles = np.empty((0, 0))

    @property
    def n_a(self) -> int:
        """Angular columns of a row (n_stokes blocks of n_f); the sums follow."""
        return self.n_stokes * self.n_f

    def _accumulate(
        self,
        x: np.ndarray,
        w: np.ndarray,
        node_panel: np.ndarray,
        n_panels: int,
        table: np.ndarray,
        n_mu: int,
        symmetric: bool,
        n_stokes: int,
    ) -> np.ndarray:
        # The kernel computes the Mie coefficients of consecutive spheres in
        # batches that share the largest member's n_max: sorted by size, a
        # batch wastes little.
        order = np.argsort(x, kind="stable")
        return mie._accumulate(
            self.m,
            x[order],
            w[order],
            node_panel[order],
            n_panels,
            self.per_particle,
            table,
            n_mu,
            symmetric,
            n_stokes,
            self.m_core,
            self.core_fraction,
        )

    def evaluate(self, lower: np.ndarray, upper: np.ndarray, *, angles: bool = True) -> np.ndarray:
        """Rows of angular values (if ``angles``) and sums, one per panel [lower, upper] in s."""
        nodes, node_panel = panel_nodes(
            self.distribution,
            wavelength_nm=self.wavelength_nm,
            lower_s=lower,
            upper_s=upper,
            settings=self.settings,
        )
        x, w = nodes.size_parameter, nodes.weight
        if not angles:
            return self._accumulate(x, w, node_panel, lower.size, self.no_angles, 0, False, 1)
        if not self.legendre:
            return self._accumulate(
                x, w, node_panel, lower.size, self.table, self.n_f, False, self.n_stokes
            )
        return _accumulate_by_tier(
            self.m,
            x,
            w,
            node_panel,
            self.settings.nodes_per_panel,
            self.per_particle,
            self.tiers,
            self._tables,
            self._table_start,
            self._maps,
            self._map_start,
            self.n_stokes,
            self.m_core,
            self.core_fraction,
        )

    def halves(
        self, lower: np.ndarray, upper: np.ndarray, *, angles: bool = True
    ) -> tuple[np.ndarray, np.ndarray]:
        """Rows for the left and right halves of each panel."""
        mid = 0.5 * (lower + upper)
        rows = self.evaluate(
            np.concatenate([lower, mid]), np.concatenate([mid, upper]), angles=angles
        )
        return rows[: lower.size], rows[lower.size :]

    def _phase_errors(
        self, pool: np.ndarray, coarse: np.ndarray, left: np.ndarray, right: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """Summed row, and relative phase error per panel and of the sum (see
        :func:`_phase_refinement_errors`; for the matrix or the expansion,
        :func:`_matrix_refinement_errors`)."""
        norm = self.n_a if self.per_particle else self.n_a + 2
        if self.matrix:
            return _matrix_refinement_errors(
                pool, coarse, left, right, self.n_f, self.n_stokes, norm
            )[:3]
        return _phase_refinement_errors(pool, coarse, left, right, self.n_f, norm)

    def _cross_errors(
        self, pool: np.ndarray, coarse: np.ndarray, left: np.ndarray, right: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """Summed row, and the largest error of <C_ext>, <C_sca> (relative) and
        g (absolute) per panel and of the sum (see :func:`_cross_refinement_errors`)."""
        norm, gnum = (0, 4) if self.per_particle else (2, 3)
        return _cross_refinement_errors(pool, coarse, left, right, norm, gnum)

    def _split_cost(self, upper: np.ndarray, angles: bool) -> np.ndarray:
        """Relative work of evaluating panels ending at ``upper`` (in s) (see
        :func:`_panel_cost`)."""
        return _panel_cost(upper, self.settings.transition_size_parameter, angles)

    def initial_state(self) -> _Panels:
        """The initial panels, each integrated with its coarse rule and on its halves."""
        lower, upper = self.edges[:-1], self.edges[1:]
        left, right = self.halves(lower, upper)
        return _Panels(lower, upper, self.evaluate(lower, upper), left, right)

    def refine(self, state: _Panels, *, angles: bool, tol: float) -> tuple[_Panels, _Run]:
        """Adaptive refinement of the phase function (``angles``) or the cross-sections to ``tol``.

        Starts from ``state`` (whose rows hold angular values only if ``angles``).
        Rows live in one growing pool, and panels refer to theirs by index, so
        a split copies only the new rows.
        """
        errors = self._phase_errors if angles else self._cross_errors
        lower, upper = state.lower, state.upper
        n = lower.size
        pool = np.concatenate([state.coarse, state.left, state.right])
        n_rows = 3 * n
        coarse, left, right = np.arange(n), np.arange(n, 2 * n), np.arange(2 * n, 3 * n)
        cost = self._split_cost(upper, angles)
        max_panels = (self.edges.size - 1) * 2**self.settings.max_level
        while True:
            total, panel_error, error = errors(pool, coarse, left, right)
            if error <= tol or lower.size >= max_panels:
                break
            # Split the panels that remove the most error per unit of work
            # until the rest's summed error is below 0.9 tol: the halves of a
            # split panel are usually far below the remaining 0.1 tol, and
            # splitting more than needed (a margin of tol/2) cost 10 % more
            # work for the default table.  Work per node grows with n_max
            # (the angular sum ~ n_max x angles), so a wide panel of large
            # spheres is split only if its error is worth it.
            split, eval_lower, eval_upper = _choose_splits(
                panel_error, cost, tol, _KEEP_FRACTION, lower, upper
            )
            rows = self.evaluate(eval_lower, eval_upper, angles=angles)
            new_cost = self._split_cost(eval_upper[eval_upper.size // 2 :], angles)
            pool, n_rows, coarse, left, right, lower, upper, cost = _apply_splits(
                pool,
                n_rows,
                rows,
                split,
                coarse,
                left,
                right,
                lower,
                upper,
                cost,
                new_cost,
                eval_lower,
                eval_upper,
            )
        order = np.argsort(lower, kind="stable")
        panels = np.column_stack([lower[order], upper[order]])
        blocks = None
        if angles and self.matrix:
            norm = self.n_a if self.per_particle else self.n_a + 2
            blocks = _matrix_refinement_errors(
                pool, coarse, left, right, self.n_f, self.n_stokes, norm
            )[3]
        run = _Run(total, panels, 2 * self.settings.nodes_per_panel * lower.size, error, blocks)
        return _Panels(lower, upper, pool[coarse], pool[left], pool[right]), run

    def solve(self, rtol: float, cross_rtol: float) -> _Result:
        if self.distribution.is_monodisperse:
            x = np.array([2.0 * np.pi * self.distribution.mean_radius_um / self.wavelength_um])
            n_mu = self.n_half if self.gauss else self.n_f
            rows = mie._accumulate(
                self.m,
                x,
                np.ones(1),
                np.zeros(1, dtype=np.int64),
                1,
                self.per_particle,
                self.table,
                n_mu,
                self.gauss,
                self.n_stokes,
                self.m_core,
                self.core_fraction,
            )
            blocks = np.zeros((self.n_stokes, self.n_f + 1)) if self.matrix else None
            run = _Run(rows[0], np.empty((0, 2)), 1, 0.0, blocks)
            return self.finish(run, _Run(rows[0, self.n_a :], run.panels_s, 1, 0.0))
        state, phase_run = self.refine(self.initial_state(), angles=True, tol=rtol)
        # The cross-sections continue from the phase function's panels (whose
        # sums they already hold), refining further without angles.
        sums = _Panels(state.lower, state.upper, *(rows[:, self.n_a :] for rows in state[2:]))
        _, cross_run = self.refine(sums, angles=False, tol=cross_rtol)
        return self.finish(phase_run, cross_run)

    def finish(
        self, phase_run: _Run, cross_run: _Run, distribution: SizeDistribution | None = None
    ) -> _Result:
        """Phase function from ``phase_run``, cross-sections and g from
        ``cross_run`` (of ``distribution``, default the solver's)."""
        n_f = self.n_f
        f = phase_run.total[:n_f]
        if self.gauss:
            beta = mie._legendre_project(
                self.mu_half, self.w_half, np.ascontiguousarray(f), 2 * self.nmax
            )
            f = mie._legendre_evaluate(beta, self.mu_out)
        # Normalized with the phase run's own sums, so 2 pi int P dmu = 1 holds
        # for the nodes that made P.
        s_w, _, s_sca = phase_run.total[self.n_a : self.n_a + 3]
        scale = 1.0 / s_w if self.per_particle else 1.0 / (2.0 * np.pi * s_sca)
        phase = f * scale
        matrix = _finish_matrix(self, phase_run, scale) if self.matrix else None
        s_w, s_ext, s_sca, s_gsca, s_g, s_back = cross_run.total
        g = s_g / s_w if self.per_particle else s_gsca / s_sca
        area = (self.wavelength_um / (2.0 * np.pi)) ** 2 * np.pi  # x^2 -> pi r^2 [um^2]
        # n(r) is normalized analytically, so <C> = sum w_j C_j; dividing by
        # sum w_j would renormalize to the truncated *number* distribution, which
        # for cross-section weighting drops up to ~0.3 % of the (tiny) particles
        # below r_lo and biases <C> high.
        return _Result(
            phase=phase,
            cext=area * s_ext,
            csca=area * s_sca,
            g=float(g),
            n_nodes=phase_run.n_nodes,
            cross_section_n_nodes=cross_run.n_nodes,
            err_phase=phase_run.error,
            err_cross=cross_run.error,
            panels_s=phase_run.panels_s,
            cross_section_panels_s=cross_run.panels_s,
            cback=area * s_back,
            matrix=matrix,
            moments=self.node_moments(
                cross_run.panels_s, self.distribution if distribution is None else distribution
            ),
        )

    def node_moments(
        self, panels_s: np.ndarray, distribution: SizeDistribution
    ) -> tuple[float, float, float]:
        """Sums of w r^k, k = 2, 3, 4, over the radius nodes of the final
        panels ``panels_s`` (their halves carry the rule that was used) [um^k]."""
        if distribution.is_monodisperse:
            r = distribution.mean_radius_um
            return r**2, r**3, r**4
        lower, upper = panels_s[:, 0], panels_s[:, 1]
        mid = 0.5 * (lower + upper)
        nodes, _ = panel_nodes(
            distribution,
            wavelength_nm=self.wavelength_nm,
            lower_s=np.concatenate([lower, mid]),
            upper_s=np.concatenate([mid, upper]),
            settings=self.settings,
        )
        radius = nodes.size_parameter * self.wavelength_um / (2.0 * np.pi)
        m2, m3, m4 = _moment_sums(nodes.weight, radius)
        return m2, m3, m4


@njit(cache=True, nogil=True)
def _moment_sums(w: np.ndarray, radius: np.ndarray) -> tuple[float, float, float]:
    """Sums of w r^2, w r^3 and w r^4, compensated (Neumaier 1974): for these
    positive terms within an ulp or two of the correctly rounded sum
    (math.fsum, which took a fifth of a sweep's time on its ~10^4 nodes per
    distribution).

    Reference: A. Neumaier, Z. Angew. Math. Mech. 54, 39-51 (1974),
    doi:10.1002/zamm.19740540106.
    """
    sums = np.zeros(3)
    comp = np.zeros(3)
    for j in range(w.shape[0]):
        # The terms as numpy forms them (x * x, then pow).
        r = radius[j]
        terms = (w[j] * (r * r), w[j] * r**3.0, w[j] * r**4.0)
        for k in range(3):
            term = terms[k]
            t = sums[k] + term
            if abs(sums[k]) >= abs(term):
                comp[k] += (sums[k] - t) + term
            else:
                comp[k] += (term - t) + sums[k]
            sums[k] = t
    return sums[0] + comp[0], sums[1] + comp[1], sums[2] + comp[2]


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
        there), an integer N for orders 0..N.  Refines like ``polarization``.
    particle_density_kg_m3 : float, optional
        Density of the particle material, for the mass extinction, scattering
        and absorption coefficients (``table.mass_ext_m2_per_kg``, ...); for
        Mars dust :data:`dustoptics.particles.mixing.MARS_DUST_DENSITY_KG_M3`. [kg m^-3]

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
        return solver.solve(rtol, cross_rtol)

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
        # leave to one thread.  (Every polydisperse wavelength calls
        # _phase_refinement_errors from Python, so its signatures say whether
        # one has run; kernels called only from compiled code keep none.)
        # Each wavelength's result is the same either way.
        if not (_phase_refinement_errors.signatures or _matrix_refinement_errors.signatures):
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
    if not_converged.any():
        bad = ", ".join(f"{w:g}" for w in wl[not_converged])
        warnings.warn(
            f"radius quadrature did not reach rtol={rtol:g} / cross_section_rtol={cross_rtol:g} "
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
    sources = (
        _index_source(refractive_index, label),
        Source(name=distribution.model, role="size distribution", citation=distribution.citation),
    )
    return Table(
        name=name,
        wavelength_nm=wl,
        theta_deg=theta,
        phase=phase,
        g=np.array([r.g for r in results]),
        cext_um2=cext,
        csca_um2=csca,
        error_estimate=err_phase,
        cross_section_error_estimate=err_cross,
        n_nodes=n_nodes,
        cross_section_n_nodes=cross_n_nodes,
        refractive_index=m,
        mean_geometric_cross_section_um2=float(distribution.mean_cross_section_um2),
        cback_um2=np.array([r.cback for r in results]),
        r_eff_quadrature_um=moments[:, 1] / moments[:, 0],
        v_eff_quadrature=moments[:, 2] * moments[:, 0] / moments[:, 1] ** 2 - 1.0,
        mean_volume_quadrature_um3=4.0 / 3.0 * np.pi * moments[:, 1],
        mean_volume_um3=float(distribution.mean_volume_um3),
        particle_density_kg_m3=density,
        **extra,
        provenance=Provenance(inputs=plain(inputs), sources=sources, quadrature=plain(record)),
        diagnostics=QuadratureDiagnostics(
            settings=settings,
            distribution=distribution,
            panels=tuple(r.panels_s for r in results),
            cross_section_panels=tuple(r.cross_section_panels_s for r in results),
        ),
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
