"""Adaptive refinement of the radius quadrature at one wavelength.

:func:`dustoptics.scattering.optics.compute_optics` hands each wavelength to a
:class:`_WavelengthSolver`, which returns the polydisperse phase function,
cross-sections, g (and, when asked, the scattering matrix and its expansion)
converged over the size distribution:

- the radius range is cut into the equal panels of
  :func:`dustoptics.scattering.quadrature.initial_panels`, each integrated
  with one n-point Gauss-Legendre rule and with one on each of its halves; the
  difference estimates the coarse rule's error
  (:func:`_phase_refinement_errors`, :func:`_cross_refinement_errors`,
  :func:`_matrix_refinement_errors`);
- panels are split, most error per unit of work first (:func:`_choose_splits`,
  :func:`_panel_cost`), until the summed estimates meet the tolerance; a split
  panel's halves already know their coarse values, so no sphere is computed
  twice (:func:`_apply_splits`);
- the phase function is refined first (sums over angles), then the
  cross-sections and g continue from its panels without angles, to their own
  tighter tolerance;
- with many output angles, the spheres are summed at Gauss angles and
  projected on Legendre polynomials; a panel whose spheres need fewer orders
  is summed on a smaller Gauss grid and moved to the full one by exact
  polynomial interpolation (:func:`_angular_tiers`,
  :func:`_stacked_interpolation_maps`, :func:`_accumulate_by_tier`).

The kernels of single spheres and their sums are in
:mod:`dustoptics.scattering.mie`, the node placement in
:mod:`dustoptics.scattering.quadrature`.  :mod:`dustoptics.sweep.shared`
refines many distributions on shared spheres with the same error estimates,
split rule and angular grids.  Everything here is internal to the package.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from numba import njit

from dustoptics._numba_cache import B1, F8, F8_1D, F8_2D, I8, I8_1D, kernel
from dustoptics.particles.sizedist import SizeDistribution
from dustoptics.scattering import mie
from dustoptics.scattering.expansion import greek_coefficients
from dustoptics.scattering.quadrature import (
    QuadratureSettings,
    _wright_omega,
    gauss_legendre,
    initial_panels,
    panel_nodes,
    size_parameter_at,
)

__all__: list[str] = []


@njit(cache=True, nogil=True, inline="always")
def _n_max(x: float) -> float:
    """:func:`mie.wiscombe_nmax` before rounding down: x + 4.05 x^(1/3) + 2."""
    return x + 4.05 * np.cbrt(x) + 2.0


@kernel(F8_1D)
def _orders_needed(x_top: np.ndarray) -> np.ndarray:
    """int(:func:`_n_max`) + 2 of each panel's largest size parameter: the orders its
    spheres need in an angular tier (:func:`_order_by_tier`).  Compiled, as
    :func:`_n_max` is everywhere: numba's ``np.cbrt`` differs from numpy's in the
    last bit for some x, and a tier must not change with it."""
    need = np.empty(x_top.shape[0], dtype=np.int64)
    for i in range(x_top.shape[0]):
        need[i] = int(_n_max(x_top[i])) + 2
    return need


#: Refinement splits panels until the unsplit ones hold less than this
#: fraction of the tolerance (see :meth:`_WavelengthSolver.refine`).
_KEEP_FRACTION = 0.9


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
    # The expansion coefficients' own final panels (None: the phase function's).
    expansion_panels_s: np.ndarray | None = None


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


def _read_only(a: np.ndarray) -> np.ndarray:
    """A read-only C-contiguous float64 view (or copy) of ``a``: the kernels that take
    the cached Gauss rules take other angles in the same type, so one signature serves."""
    v = np.require(a, dtype=np.float64, requirements=["C"]).view()
    v.flags.writeable = False
    return v


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
    :func:`mie._accumulate_grids`: tier sizes, their angular tables and start
    offsets, the interpolation maps to the full grid and their offsets.

    A panel whose spheres need fewer orders is summed on a smaller Gauss grid
    (cost ~ n_max x n_angles per sphere) and moved to the full grid by exact
    polynomial interpolation (:func:`mie._interpolation_maps_into`).  Tier sizes
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
    to the grid of ``n_half`` (:func:`mie._interpolation_maps_into`), stacked in
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


@kernel(F8_2D, I8_1D, I8_1D)
def _halves_total(pool: np.ndarray, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Sum over panels p of the rows ``pool[left[p]] + pool[right[p]]``, panel
    after panel: the refinement's current result."""
    total = np.empty(pool.shape[1])
    total[:] = 0.0
    for p in range(left.shape[0]):
        a = pool[left[p]]
        b = pool[right[p]]
        for c in range(pool.shape[1]):
            total[c] += a[c] + b[c]
    return total


@kernel(F8_2D, I8_1D, I8_1D, I8_1D, I8, I8)
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
    column = np.empty(n_f)
    column[:] = 0.0
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


@kernel(F8_2D, I8_1D, I8_1D, I8_1D, I8, I8)
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
    sums = np.empty(3)
    sums[:] = 0.0
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

    numpy, not a compiled kernel: a few calls per wavelength on tens of panels,
    where numba's compile time (0.7 s on a first build) is all it would cost.
    ``np.cumsum`` adds in order, as the compiled loop did.
    """
    badness = panel_error / tol
    # ndarray methods rather than numpy's functions: a few calls per round,
    # where the functions' Python wrappers cost more than the work.
    order = (-badness / cost).argsort(kind="stable")
    cumulative = badness[order].cumsum()
    n_split = min(
        int(cumulative.searchsorted(cumulative[-1] - keep_fraction, side="left")) + 1,
        order.shape[0],
    )
    split = order[:n_split]
    split.sort()  # increasing
    lo = lower[split]
    hi = upper[split]
    mid = 0.5 * (lo + hi)
    # The new panels [lo, mid] and [mid, hi], and their halves' edges.
    q1 = 0.5 * (lo + mid)
    q3 = 0.5 * (mid + hi)
    return split, np.concatenate((lo, mid, q1, q3)), np.concatenate((q1, q3, mid, hi))


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
) -> tuple[np.ndarray, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The refinement state after splitting panels ``split`` (see
    :func:`_choose_splits`): ``rows`` hold the new panels' left-half rows, then
    their right-half rows; each new panel's coarse row is its parent's half.
    Kept panels stay in order, the new ones follow.  Rows are appended to
    ``pool`` (grown by doubling when full); returns the pool, its row count,
    and the panels' coarse, left and right row indices, edges and costs.

    numpy, not a compiled kernel (copies and indexing; see :func:`_choose_splits`).
    """
    k2 = rows.shape[0] // 2  # new panels
    if n_rows + 2 * k2 > pool.shape[0]:
        grown = np.empty((2 * (n_rows + 2 * k2), pool.shape[1]))
        grown[:n_rows] = pool[:n_rows]
        pool = grown
    pool[n_rows : n_rows + 2 * k2] = rows[: 2 * k2]
    keep = np.ones(lower.shape[0], dtype=np.bool_)
    keep[split] = False
    kept = keep.nonzero()[0]
    # New panel h < k is split[h]'s left half, whose coarse row is the split
    # panel's left-half row; h >= k its right half.
    new_coarse = np.concatenate((left[split], right[split]))[:k2].astype(np.int64, copy=False)
    new_left = np.arange(n_rows, n_rows + k2, dtype=np.int64)
    return (
        pool,
        n_rows + 2 * k2,
        np.concatenate((coarse[kept], new_coarse)),
        np.concatenate((left[kept], new_left)),
        np.concatenate((right[kept], new_left + k2)),
        np.concatenate((lower[kept], eval_lower[:k2])),
        np.concatenate((upper[kept], eval_upper[k2 : 2 * k2])),
        np.concatenate((cost[kept], new_cost[:k2])),
    )


@kernel(F8_1D, F8, B1)
def _panel_cost(upper: np.ndarray, x_c: float, angles: bool) -> np.ndarray:
    """Relative work of evaluating a panel ending at s = ``upper``: with n =
    n_max at its end (x = x_c omega(s)), ~ (n + 8)^2 with angles (orders x
    tier angles, a tier ~ n + 8 angles), ~ n + 20 for the coefficients alone."""
    cost = np.empty(upper.shape[0])
    for i in range(upper.shape[0]):
        n = _n_max(x_c * _wright_omega(upper[i]))
        cost[i] = (n + 8.0) ** 2 if angles else n + 20.0
    return cost


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
    """Rows of :func:`mie._accumulate_grids` for nodes given panel after panel.

    Each panel is summed on the smallest tier that holds n_max + 2 orders of
    its largest sphere (wiscombe_nmax + 1, plus 1 so that the rounding of the
    cube root can never pick a tier one order short: the kernel reads the
    tables without bounds checks).  The nodes go to the kernel by tier, then
    by size, so that its batches hold spheres of similar n_max
    (:func:`_order_by_tier`, numpy).  Called from Python rather than from a
    compiled caller: a compiled caller is compiled again with the kernel
    inlined, seconds of a first build's compile time for a microsecond a call.
    """
    x_sorted, w_sorted, panel_sorted, node_tier, n_panels = _order_by_tier(
        x, w, node_panel, nodes_per_panel, tiers
    )
    return mie._accumulate_grids(
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
        True,
        n_stokes,
        mie._core_index(m_core, core_fraction),
        core_fraction,
    )


def _order_by_tier(
    x: np.ndarray, w: np.ndarray, node_panel: np.ndarray, nodes_per_panel: int, tiers: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """The nodes of :func:`_accumulate_by_tier` (given panel after panel)
    ordered by tier, then by size: their size parameters, weights, panels and
    tiers, and the number of panels.

    numpy, not a compiled kernel: once per evaluation of new panels, on their
    nodes, where numba's compile time (1.4 s on a first build with the sort it
    used) is all it would cost.
    """
    n_panels = x.shape[0] // nodes_per_panel
    shape = (n_panels, nodes_per_panel)
    by_panel = x[: n_panels * nodes_per_panel].reshape(shape)
    # The first tier that holds n_max + 2 orders of the panel's largest sphere.
    need = _orders_needed(np.ascontiguousarray(by_panel.max(axis=1)))
    panel_tier = np.searchsorted(tiers, need, side="left")
    if n_panels and panel_tier.max() == tiers.shape[0]:
        raise ValueError("a panel's spheres need more orders than the largest angular tier holds")
    # Panels are disjoint, and x grows along each panel's nodes, so ordering
    # the panels by tier, then by their first node, orders the nodes by tier,
    # then by x (lexsort is stable: equal keys keep the panels' order).
    order = np.lexsort((by_panel[:, 0], panel_tier))
    node_tier = np.repeat(panel_tier[order], nodes_per_panel).astype(np.int64, copy=False)
    return (
        by_panel[order].ravel(),
        w[: n_panels * nodes_per_panel].reshape(shape)[order].ravel(),
        node_panel[: n_panels * nodes_per_panel].reshape(shape)[order].ravel(),
        node_tier,
        int(n_panels),
    )


# ----------------------------------------------------------------------------
# The scattering matrix and its expansion (compute_optics(polarization=True,
# expansion=...)): the refinement's error per matrix element, and the
# elements and coefficients from the refined sums.
# ----------------------------------------------------------------------------


@kernel(F8_2D, I8_1D, I8_1D, I8_1D, I8, I8, I8, group="matrix")
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
    columns = np.empty((n_stokes, n_f + 1))
    columns[:] = 0.0
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
        # np.max(columns[k, :n_f]) (the first NaN, if any), without its generic compile.
        col = columns[k]
        worst = col[0]
        for i in range(1, n_f):
            if worst != worst:
                break
            if col[i] != col[i] or col[i] > worst:
                worst = col[i]
        error = max(error, worst + norm_sum)
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


def _finish_matrix(
    solver: _WavelengthSolver, phase_run: _Run, scale: float, greek_run: _Run | None = None
) -> _Matrix:
    """F12, F33, F34 at the output angles and, on the Gauss grid, the
    expansion coefficients of orders 0..2 n_max (see
    :mod:`dustoptics.scattering.expansion`), from a refined run with the
    four blocks I, Q, U, V; ``scale`` turns summed I into the phase function.
    The coefficients come from ``greek_run`` if given (refined further to
    their own tolerance, normalized with its own sums), else from ``phase_run``."""
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
        greek_scale = scale
        if greek_run is not None:
            blocks = greek_run.block_errors
            assert blocks is not None
            values = [greek_run.total[k * n_f : (k + 1) * n_f] for k in range(mie.N_STOKES)]
            s_w, _, s_sca = greek_run.total[solver.n_a : solver.n_a + 3]
            greek_scale = 1.0 / s_w if solver.per_particle else 1.0 / (2.0 * np.pi * s_sca)
        mu = np.concatenate([solver.mu_half, -solver.mu_half])
        w = np.concatenate([solver.w_half, solver.w_half])
        a1, b1, a3, b2 = (4.0 * np.pi * greek_scale * v for v in values)
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
            self.table = mie.angular_table(_read_only(mu_out), self.nmax)
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

    def _greek_errors(
        self, pool: np.ndarray, coarse: np.ndarray, left: np.ndarray, right: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """Summed row, and per panel and summed the expansion coefficients' error
        estimate of :func:`_finish_matrix` (a bound on each coefficient's change
        over (2 l + 1)): (1/2) int of a1's relative change summed over the
        four blocks, weighted by a1, plus the normalization's relative change,
        i.e. per panel sum_k sum_i w_i abs(d_k,i) / N (times 2 pi if per
        particle) + abs(d_N) / N, with N the normalizing sum."""
        norm = self.n_a if self.per_particle else self.n_a + 2
        total = _halves_total(pool, left, right)
        d = np.abs(pool[left] + pool[right] - pool[coarse])
        w = np.concatenate([self.w_half, self.w_half])
        c = (2.0 * np.pi if self.per_particle else 1.0) / total[norm]
        angular = d[:, : self.n_a].reshape(d.shape[0], self.n_stokes, self.n_f).sum(axis=1)
        panel_error = c * (angular @ w) + d[:, norm] / total[norm]
        return total, panel_error, float(panel_error.sum())

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

    def refine(
        self, state: _Panels, *, angles: bool, tol: float, greek: bool = False
    ) -> tuple[_Panels, _Run]:
        """Adaptive refinement of the phase function (``angles``) or the cross-sections to ``tol``
        (with ``greek``, of the expansion coefficients: :meth:`_greek_errors`).

        Starts from ``state`` (whose rows hold angular values only if ``angles``).
        Rows live in one growing pool, and panels refer to theirs by index, so
        a split copies only the new rows.
        """
        if greek:
            errors = self._greek_errors
        else:
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

    def solve(self, rtol: float, cross_rtol: float, expansion_rtol: float | None = None) -> _Result:
        """Refine the phase function (and matrix) to ``rtol``, then, from its panels,
        the expansion coefficients to ``expansion_rtol`` (if the solver computes
        them and it is given) and the cross-sections to ``cross_rtol``."""
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
        # The expansion coefficients continue from the phase function's panels to
        # their own tolerance (the phase function and matrix stay the phase run's).
        greek_run = None
        if self.want_greek and expansion_rtol is not None:
            _, greek_run = self.refine(state, angles=True, tol=expansion_rtol, greek=True)
        # The cross-sections continue from the phase function's panels (whose
        # sums they already hold), refining further without angles.
        sums = _Panels(state.lower, state.upper, *(rows[:, self.n_a :] for rows in state[2:]))
        _, cross_run = self.refine(sums, angles=False, tol=cross_rtol)
        return self.finish(phase_run, cross_run, greek_run=greek_run)

    def finish(
        self,
        phase_run: _Run,
        cross_run: _Run,
        distribution: SizeDistribution | None = None,
        *,
        greek_run: _Run | None = None,
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
        matrix = _finish_matrix(self, phase_run, scale, greek_run) if self.matrix else None
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
            expansion_panels_s=None if greek_run is None else greek_run.panels_s,
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


@kernel(F8_1D, F8_1D)
def _moment_sums(w: np.ndarray, radius: np.ndarray) -> tuple[float, float, float]:
    """Sums of w r^2, w r^3 and w r^4, compensated (Neumaier 1974): for these
    positive terms within an ulp or two of the correctly rounded sum
    (math.fsum, which took a fifth of a sweep's time on its ~10^4 nodes per
    distribution).

    Reference: A. Neumaier, Z. Angew. Math. Mech. 54, 39-51 (1974),
    doi:10.1002/zamm.19740540106.
    """
    sums = np.empty(3)
    sums[:] = 0.0
    comp = np.empty(3)
    comp[:] = 0.0
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


def kernels_loaded() -> bool:
    """Whether a wavelength has been refined in this process, so that numba has
    compiled (or loaded from its cache) the kernels.  Every polydisperse
    wavelength calls :func:`_phase_refinement_errors` or
    :func:`_matrix_refinement_errors` from Python, so their signatures say
    whether one has run; kernels called only from compiled code keep none."""
    if not hasattr(_phase_refinement_errors, "signatures"):
        return True  # numba's JIT off (NUMBA_DISABLE_JIT): plain Python, nothing to compile
    return bool(_phase_refinement_errors.signatures or _matrix_refinement_errors.signatures)
