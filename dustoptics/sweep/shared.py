"""Shared radius nodes: many size distributions at one wavelength and index.

Points of a sweep that differ only in their size distribution see the same
refractive index m at each wavelength, and their quadratures need Mie results
for overlapping ranges of sphere sizes.  :func:`solve_shared` computes each
sphere once and weights it for every distribution that needs it, the way
``make_mie_table`` and scatrs share spheres across distributions.

Nodes come from one tree of panels in the stretched size variable s of
:mod:`dustoptics.scattering.quadrature`: the cells of level l are
[i W / 2^l, (i + 1) W / 2^l] with W = ``QuadratureSettings.panel_width``,
each carrying the same n-point Gauss-Legendre rule as a panel of
:func:`~dustoptics.scattering.optics.compute_optics`.  A distribution starts
from the cells of the coarsest level that cuts its truncated radius range
(the same tail bounds as a single build) into at least ``min_panels`` cells,
and refines exactly as a single build does (:meth:`_WavelengthSolver.refine
<dustoptics.scattering.refinement._WavelengthSolver.refine>`: coarse rule against
the rules on the halves, most error per unit of work split first, the phase
function to ``rtol``, then the cross-sections and g to ``cross_section_rtol``
from the phase function's panels), with its own error estimates and its own
tolerance.  The distributions refine one after the other: every step
computes the spheres of the cells that no distribution has needed before
(:func:`_cell_intensities`, on the smallest Gauss grid of a ladder,
:data:`_GRIDS`, that holds their orders) and weights them for this one
(:func:`_cell_rows`, which moves each weighted row to the distribution's own
grid, the ladder's grid for its largest sphere).  A cell's spheres are the
same numbers whichever distribution asked first (their Mie coefficients are
computed in batches within the cell), so a distribution's result does not
depend on the order of the distributions or on which others share the solve
(tested to the bit).

How it relates to a single build: a distribution's panels here are cells of
the shared tree, while a single build cuts its own range into equal panels
and sums on its own grids.  Both quadratures converge to the same integrals,
and each reports an estimate of its own error, so the two tables differ by
at most the sum of their error estimates (the tests check it).  A cell's row
is the row :func:`dustoptics.scattering.mie._accumulate` gives on the cell's
grid, moved as :func:`dustoptics.scattering.mie._legendre_regrid` moves it,
to the bit (tested).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit

from dustoptics.particles.sizedist import SizeDistribution
from dustoptics.scattering import mie
from dustoptics.scattering.quadrature import (
    QuadratureSettings,
    initial_panels,
    panel_nodes,
    size_parameter_at,
)
from dustoptics.scattering.refinement import (
    _KEEP_FRACTION,
    _apply_splits,
    _choose_splits,
    _cross_refinement_errors,
    _gauss_angles,
    _panel_cost,
    _phase_refinement_errors,
    _Result,
    _Run,
    _stacked_interpolation_maps,
    _WavelengthSolver,
)

__all__ = ["SharedStatistics", "solve_shared"]


@njit(cache=True, nogil=True)
def _cell_batches(n_nodes: int, nodes_per_cell: int) -> list[tuple[int, int]]:
    """[start, end) of the batches of at most mie.LANES spheres that
    :func:`_cell_intensities` computes together: each within one cell."""
    batches = []
    for c0 in range(0, n_nodes, nodes_per_cell):
        c1 = min(c0 + nodes_per_cell, n_nodes)
        for j0 in range(c0, c1, mie.LANES):
            batches.append((j0, min(j0 + mie.LANES, c1)))
    return batches


@njit(cache=True, nogil=True)
def _cell_intensities(
    m: complex,
    x: np.ndarray,
    node_tier: np.ndarray,
    tier_size: np.ndarray,
    tables: np.ndarray,
    table_start: np.ndarray,
    symmetric: bool,
    out: np.ndarray,
    out_rows: np.ndarray,
    nodes_per_cell: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unweighted intensities and efficiencies of spheres of size parameters ``x``.

    Sphere j is summed on tier ``node_tier[j]`` (< 0: efficiencies only): the
    grid of ``tier_size[t]`` angles (half-grid angles if ``symmetric``) whose
    :func:`mie.angular_table` is ``tables[table_start[t]:table_start[t + 1]]``
    (flattened), as in :func:`mie._accumulate_tiers`.  I(mu) = |S1|^2 +
    |S2|^2 there (+mu then -mu if ``symmetric``) is computed by
    :func:`mie._add_sphere` with weight 1, so that c I afterwards is the
    number the kernel adds for a sphere of weight c, and written to the
    first values of ``out[out_rows[j]]``.  Give the spheres cell after cell,
    ``nodes_per_cell`` each, in increasing size: the Mie coefficients are
    computed in batches of spheres of one cell (of similar n_max), whose
    downward recurrences start at the batch's largest n_max, so that a
    sphere's numbers depend on its cell alone, not on the other cells
    computed with it.  Returns Q_ext, Q_sca, g Q_sca and x^2 Q_back.
    """
    n_nodes = x.shape[0]
    qext = np.empty(n_nodes)
    qsca = np.empty(n_nodes)
    gq = np.empty(n_nodes)
    back = np.empty(n_nodes)
    if n_nodes == 0:
        return qext, qsca, gq, back
    x_top = x[0]
    for j in range(n_nodes):
        x_top = max(x_top, x[j])
    nmax_all = mie.wiscombe_nmax(x_top)
    ws = mie._workspace(nmax_all)
    coef = np.empty((nmax_all + 4, 4))
    n_top = tier_size[tier_size.shape[0] - 1]
    n_pad = mie.BLOCK * ((n_top + mie.BLOCK - 1) // mie.BLOCK)
    acc = np.empty(8 * n_pad)
    scratch = np.empty(2 * n_top + mie.N_SUMS)
    x_b = np.empty(mie.LANES)
    nmax_b = np.empty(mie.LANES, dtype=np.int64)
    for j0, j_end in _cell_batches(n_nodes, nodes_per_cell):
        n_live = j_end - j0
        for s in range(mie.LANES):  # a short batch repeats its last sphere
            x_b[s] = x[j0 + min(s, n_live - 1)]
            nmax_b[s] = mie.wiscombe_nmax(x_b[s])
        mie._mie_coefficients(m, x_b, nmax_b, ws)
        for s in range(n_live):
            j = j0 + s
            qext[j] = ws[mie._QEXT + s]
            qsca[j] = ws[mie._QSCA + s]
            gq[j] = ws[mie._GQ + s]
            back[j] = mie._backscatter(ws, s, nmax_b[s])
            t = node_tier[j]
            if t < 0:
                continue
            n_t = tier_size[t]
            width = 8 * mie.BLOCK * ((n_t + mie.BLOCK - 1) // mie.BLOCK)
            flat = tables[table_start[t] : table_start[t + 1]]
            table = flat.reshape((flat.shape[0] // width, width))
            n_f = 2 * n_t if symmetric else n_t
            row = scratch[: n_f + mie.N_SUMS]
            row[:] = 0.0
            mie._add_sphere(
                row,
                1.0,
                x_b[s],
                nmax_b[s],
                ws,
                s,
                False,
                table,
                n_t,
                symmetric,
                1,
                coef,
                acc[:width],
            )
            target = out[out_rows[j]]
            for k in range(n_f):
                target[k] = row[k]
    return qext, qsca, gq, back


@njit(cache=True, nogil=True)
def _cell_rows(
    cells: np.ndarray,
    w: np.ndarray,
    per_particle: bool,
    n_f: int,
    nodes_per_cell: int,
    x: np.ndarray,
    qext: np.ndarray,
    qsca: np.ndarray,
    gq: np.ndarray,
    back: np.ndarray,
    intens: np.ndarray,
    cell_values: np.ndarray,
    maps: np.ndarray,
    map_start: np.ndarray,
    cell_map: np.ndarray,
) -> np.ndarray:
    """One distribution's rows for the cells ``cells`` (indices into the store).

    Node i of row r has weight ``w[r * nodes_per_cell + i]``; node j of the
    store has size parameter ``x[j]``, efficiencies ``qext[j]``, ``qsca[j]``,
    ``gq[j]`` (g Q_sca) and intensities ``intens[j, :cell_values[c]]``.  Each
    row holds the weighted intensities on the distribution's grid of ``n_f``
    values (0: none), and, in its last N_SUMS columns, the sums of
    :func:`mie._accumulate`, sphere after sphere in order of size, with the
    expressions of :func:`mie._add_sphere`.  A cell whose values are fewer
    than ``n_f`` (a smaller symmetric Gauss grid, ``+mu`` then ``-mu``) is
    summed there and moved to the distribution's grid by the maps (R_even
    then R_odd, :func:`mie._interpolation_maps`) at
    ``maps[map_start[cell_map[c]]:]`` with :func:`mie._legendre_regrid`:
    one move per row, not per sphere.
    """
    n_rows = cells.shape[0]
    out = np.zeros((n_rows, n_f + mie.N_SUMS))
    # Rows summed on a smaller grid wait in ``small`` to be moved, by grid.
    small = np.empty((n_rows, n_f))
    n_small = 0
    small_row = np.empty(n_rows, dtype=np.int64)
    for r in range(n_rows):
        c = cells[r]
        row = out[r]
        for i in range(nodes_per_cell):
            j = c * nodes_per_cell + i
            wj = w[r * nodes_per_cell + i]
            xj = x[j]
            x2 = xj * xj
            row[n_f] += wj
            row[n_f + 1] += wj * x2 * qext[j]
            row[n_f + 2] += wj * x2 * qsca[j]
            row[n_f + 3] += wj * x2 * gq[j]
            row[n_f + 4] += wj * gq[j] / qsca[j]
            row[n_f + 5] += wj * back[j]
        if n_f == 0:
            continue
        n_c = cell_values[c]
        if n_c == n_f:
            target = row
        else:
            target = small[n_small]
            small_row[n_small] = r
            n_small += 1
            for k in range(n_c):
                target[k] = 0.0
        for i in range(nodes_per_cell):
            j = c * nodes_per_cell + i
            wj = w[r * nodes_per_cell + i]
            x2 = x[j] * x[j]
            cj = wj / (2.0 * np.pi * x2 * qsca[j]) if per_particle else wj
            values = intens[j]
            for k in range(n_c):
                target[k] += cj * values[k]
    if n_small == 0:
        return out
    # Rows of one grid together (a counting sort by grid), each group moved
    # by one call of the kernel's own function.
    n_maps = map_start.shape[0] - 1
    count = np.zeros(n_maps + 1, dtype=np.int64)
    for q in range(n_small):
        count[cell_map[cells[small_row[q]]] + 1] += 1
    for t in range(n_maps):
        count[t + 1] += count[t]
    by_grid = np.empty(n_small, dtype=np.int64)
    for q in range(n_small):
        t = cell_map[cells[small_row[q]]]
        by_grid[count[t]] = q
        count[t] += 1
    half = n_f // 2
    q0 = 0
    while q0 < n_small:
        t = cell_map[cells[small_row[by_grid[q0]]]]
        q1 = q0
        while q1 < n_small and cell_map[cells[small_row[by_grid[q1]]]] == t:
            q1 += 1
        n_t = cell_values[cells[small_row[by_grid[q0]]]] // 2
        block = np.empty((q1 - q0, 2 * n_t))
        for b in range(q1 - q0):
            v = small[by_grid[q0 + b]]
            for k in range(2 * n_t):
                block[b, k] = v[k]
        start = map_start[t]
        size = n_t * half
        moved = mie._legendre_regrid(
            block,
            maps[start : start + size].reshape((n_t, half)),
            maps[start + size : start + 2 * size].reshape((n_t, half)),
        )
        for b in range(q1 - q0):
            row = out[small_row[by_grid[q0 + b]]]
            for k in range(n_f):
                row[k] = moved[b, k]
        q0 = q1
    return out


#: Angular grids (positive Gauss angles of a symmetric rule): multiples of 16
#: about 2^(1/4) apart.  A cell's spheres are summed on the smallest that
#: holds their orders; a distribution's rows live on the smallest that holds
#: its largest sphere's, so that they are at most ~19 % wider than needed.
_GRIDS = np.unique(16 * np.ceil(32.0 * 2.0 ** (np.arange(80) / 4.0) / 16.0).astype(np.int64))


@lru_cache(maxsize=4)
def _ladder_tables(n_tiers: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first ``n_tiers`` grids of :data:`_GRIDS`, flattened for
    :func:`_cell_intensities`: sizes, angular tables and their offsets.
    Cached (the wavelengths of a sweep share them).  Not to be modified."""
    sizes = _GRIDS[:n_tiers].copy()
    tables = [_gauss_angles(int(n))[2].ravel() for n in sizes]
    return sizes, np.concatenate(tables), np.cumsum([0] + [a.size for a in tables])


@lru_cache(maxsize=16)
def _ladder_maps(n_half: int) -> tuple[np.ndarray, np.ndarray]:
    """Interpolation maps from each grid of :data:`_GRIDS` below ``n_half``
    to the grid of ``n_half`` (R_even then R_odd, flattened, see
    :func:`mie._interpolation_maps`) and their offsets.  Cached.  Not to be
    modified."""
    return _stacked_interpolation_maps(_GRIDS[: np.searchsorted(_GRIDS, n_half)], n_half)


class _Store:
    """Spheres of the cells computed so far, with their intensities on the
    cells' grids: the ladder :data:`_GRIDS` (``symmetric``, half-grid angles
    ``+mu`` then ``-mu``), or a single grid, the output angles.  Arrays grow
    by doubling: per node x, Q_ext, Q_sca, g Q_sca, x^2 Q_back and the
    intensities (undefined until the cell is computed with angles).  The
    intensities are rows of a flat array, ``spare`` (a previous store's) if
    given: it grows only when too small, and keeps its pages."""

    def __init__(
        self,
        *,
        nodes_per_cell: int,
        width: int,
        symmetric: bool,
        sizes: np.ndarray,
        tables: np.ndarray,
        table_start: np.ndarray,
        spare: np.ndarray | None = None,
    ) -> None:
        self.npc = nodes_per_cell
        self.symmetric = symmetric
        self.sizes, self.tables, self.table_start = sizes, tables, table_start
        self.key: dict[tuple[float, float], int] = {}
        self.n = 0  # cells
        self.has_angles = np.zeros(0, dtype=np.bool_)
        self.tier = np.zeros(0, dtype=np.int64)  # grid of the cell's intensities
        self.n_values = np.zeros(0, dtype=np.int64)  # intensities per sphere
        self.nodes = np.empty((5, 0))  # x, qext, qsca, gq, x^2 qback
        self.flat = spare if spare is not None else np.empty(0)
        self.intens = self.flat[:0].reshape(0, width)
        self.spheres_angles = 0
        self.spheres_sums = 0

    def reserve(self, n_cells: int) -> None:
        """Room for ``n_cells`` cells."""
        if n_cells <= self.has_angles.size:
            return
        size = max(n_cells, 2 * self.has_angles.size)
        used = self.n * self.npc
        grown = np.zeros(size, dtype=np.bool_)
        grown[: self.n] = self.has_angles[: self.n]
        self.has_angles = grown
        tier = np.zeros(size, dtype=np.int64)
        tier[: self.n] = self.tier[: self.n]
        self.tier = tier
        n_values = np.zeros(size, dtype=np.int64)
        n_values[: self.n] = self.n_values[: self.n]
        self.n_values = n_values
        nodes = np.empty((5, size * self.npc))
        nodes[:, :used] = self.nodes[:, :used]
        self.nodes = nodes
        width = self.intens.shape[1]
        needed = size * self.npc * width
        if needed > self.flat.size:
            flat = np.empty(needed)
            flat[: used * width] = self.flat[: used * width]
            self.flat = flat
        # Rows keep their place in the flat array: growing within it moves nothing.
        self.intens = self.flat[:needed].reshape(size * self.npc, width)

    def ensure(
        self,
        m: complex,
        lower: np.ndarray,
        upper: np.ndarray,
        angles: bool,
        dist: SizeDistribution,
        wavelength_nm: float,
        settings: QuadratureSettings,
    ) -> np.ndarray:
        """Compute the spheres of the cells [lower, upper] not yet in the
        store (with their intensities if ``angles``); return the cells' indices."""
        keys = list(zip(lower.tolist(), upper.tolist()))
        new: dict[tuple[float, float], None] = {}
        upgrade = []
        for k in keys:
            c = self.key.get(k)
            if c is None:
                new[k] = None
            elif angles and not self.has_angles[c]:
                upgrade.append(c)
        if new or upgrade:
            self._compute(m, list(new), upgrade, angles, dist, wavelength_nm, settings)
        return np.array([self.key[k] for k in keys], dtype=np.int64)

    def _compute(
        self,
        m: complex,
        new: list[tuple[float, float]],
        upgrade: list[int],
        angles: bool,
        dist: SizeDistribution,
        wavelength_nm: float,
        settings: QuadratureSettings,
    ) -> None:
        npc = self.npc
        base = self.n
        self.reserve(base + len(new))
        for i, k in enumerate(new):
            self.key[k] = base + i
        self.n = base + len(new)
        if new:
            # A cell's nodes in x do not depend on the distribution.
            nodes, _ = panel_nodes(
                dist,
                wavelength_nm=wavelength_nm,
                lower_s=np.array([k[0] for k in new]),
                upper_s=np.array([k[1] for k in new]),
                settings=settings,
            )
            self.nodes[0, base * npc : self.n * npc] = nodes.size_parameter
        cells = np.concatenate([np.arange(base, self.n), np.array(upgrade, dtype=np.int64)])
        cell_nodes = (cells[:, None] * npc + np.arange(npc)).ravel()
        x = self.nodes[0, cell_nodes]
        if angles and self.symmetric:
            # The smallest grid that holds n_max + 2 orders of the cell's
            # largest sphere, as :func:`_accumulate_by_tier` chooses.
            x_top = x.reshape(-1, npc).max(axis=1)
            n_needed = (x_top + 4.05 * np.cbrt(x_top) + 2.0).astype(np.int64) + 2
            tier = np.searchsorted(self.sizes, n_needed).astype(np.int64)
            if np.any(tier >= self.sizes.size):
                raise ValueError("a cell's spheres need more orders than the largest grid holds")
        else:
            tier = np.full(cells.size, 0 if angles else -1, dtype=np.int64)
        node_rows = cell_nodes
        qext, qsca, gq, back = _cell_intensities(
            m,
            np.ascontiguousarray(x),
            np.repeat(tier, npc),
            self.sizes,
            self.tables,
            self.table_start,
            self.symmetric,
            self.intens,
            node_rows,
            npc,
        )
        self.nodes[1, node_rows] = qext
        self.nodes[2, node_rows] = qsca
        self.nodes[3, node_rows] = gq
        self.nodes[4, node_rows] = back
        if angles:
            self.tier[cells] = tier
            self.n_values[cells] = self.sizes[tier] * (2 if self.symmetric else 1)
            self.has_angles[cells] = True
            self.spheres_angles += cells.size * npc
        self.spheres_sums += len(new) * npc


@dataclass(frozen=True)
class SharedStatistics:
    """Work of one shared solve.

    Attributes
    ----------
    spheres_computed : int
        Spheres whose Mie coefficients were computed (each once). [-]
    spheres_with_angles : int
        Of those, spheres whose angular sums were computed. [-]
    spheres_weighted : int
        Sphere-distribution pairs summed: the spheres independent builds on
        the same panels would have computed. [-]
    """

    spheres_computed: int
    spheres_with_angles: int
    spheres_weighted: int


class _GroupSolver(_WavelengthSolver):
    """The angular grid of distributions at one wavelength: n_half positive
    Gauss angles with n_half - 1 orders, or the output angles when there are
    fewer, so that :meth:`_WavelengthSolver.finish` turns a distribution's
    runs into its result."""

    def __init__(
        self,
        *,
        m: complex,
        wavelength_nm: float,
        mu_out: np.ndarray,
        n_half: int,
        per_particle: bool,
        settings: QuadratureSettings,
    ) -> None:
        self.m = m
        self.wavelength_um = wavelength_nm * 1e-3
        self.wavelength_nm = wavelength_nm
        self.mu_out = mu_out
        self.per_particle = per_particle
        self.settings = settings
        # The phase function alone, homogeneous spheres (see _WavelengthSolver).
        self.n_stokes, self.matrix, self.want_greek = 1, False, False
        self.m_core, self.core_fraction = 0j, 0.0
        self.nmax = n_half - 1  # orders of the angular table
        self.legendre = self.gauss = n_half < mu_out.size
        if self.legendre:
            self.n_half = n_half
            self.mu_half, self.w_half = _gauss_angles(n_half)[:2]
            self.n_f = 2 * n_half
            self.maps, self.map_start = _ladder_maps(n_half)
        else:
            self.n_f = mu_out.size
            self.maps, self.map_start = np.empty(0), np.zeros(1, dtype=np.int64)


class _Distribution:
    """One distribution's refinement state (see :meth:`_WavelengthSolver.refine`)."""

    def __init__(self, dist: SizeDistribution, lower: np.ndarray, upper: np.ndarray) -> None:
        self.dist = dist
        self.lower = lower
        self.upper = upper
        self.max_panels = lower.size
        self.pool = np.empty((0, 0))
        self.n_rows = 0
        self.coarse = self.left = self.right = np.empty(0, dtype=np.int64)
        self.cost = np.empty(0)


def _tree_cells(
    s_lo: float, s_hi: float, settings: QuadratureSettings
) -> tuple[np.ndarray, np.ndarray]:
    """The cells of the coarsest tree level that covers [s_lo, s_hi] with at
    least ``min_panels`` cells (at most max_level levels below the root)."""
    width = settings.panel_width
    for _ in range(settings.max_level + 1):
        first = np.floor(s_lo / width)
        last = np.ceil(s_hi / width)
        if last - first >= settings.min_panels:
            break
        width /= 2.0
    index = np.arange(first, last)
    return index * width, (index + 1.0) * width


def solve_shared(
    *,
    m: complex,
    wavelength_nm: float,
    mu_out: np.ndarray,
    distributions: Sequence[SizeDistribution],
    per_particle: bool,
    settings: QuadratureSettings,
    rtol: float,
    cross_rtol: float,
    buffers: dict[bool, np.ndarray] | None = None,
) -> tuple[list[_Result], SharedStatistics]:
    """Converged polydisperse results of several distributions at one wavelength.

    Parameters
    ----------
    m : complex
        Refractive index m = n + i k, k >= 0. [-]
    wavelength_nm : float
        Wavelength. [nm]
    mu_out : numpy.ndarray
        Cosines of the output angles. [-]
    distributions : sequence of SizeDistribution
        Distributions with a density (no Monodisperse modes).
    per_particle : bool
        Number weighting (True) or scattering weighting (False) of the phase
        function, as ``weighting`` of :func:`compute_optics`.
    settings : QuadratureSettings
        Node rule, tree root width, tail bounds and refinement limit.
    rtol, cross_rtol : float
        Each distribution's tolerances for the phase function and for the
        cross-sections and g. [-]
    buffers : dict, optional
        The spheres' intensity arrays, kept from one call to the next (pass
        the same dict for every wavelength): a store of the 100-point
        benchmark sweep reserves ~100 MB, and one fresh each wavelength
        faulted its pages in again, in the kernel's time (huge pages, which
        numpy asks for, are zeroed 2 MiB at a time).  Results do not depend
        on it.

    Returns
    -------
    list of _Result, SharedStatistics
        One result per distribution, in order, as a single build's solver
        returns it (read by :func:`dustoptics.scattering.optics.compute_optics`'s
        assembly), and the work done.
    """
    lower_moment = 0 if per_particle else 2
    states = []
    grids = []
    for dist in distributions:
        edges = initial_panels(
            dist, wavelength_nm=wavelength_nm, settings=settings, lower_moment=lower_moment
        )
        lower, upper = _tree_cells(float(edges[0]), float(edges[-1]), settings)
        state = _Distribution(dist, lower, upper)
        state.max_panels = lower.size * 2**settings.max_level
        states.append(state)
        # Each distribution's rows live on the grid of its own largest
        # sphere, rounded up the ladder: one grid for all would make the
        # rows of small particles as wide as those of the largest (3x wider
        # on average, 2x slower, for r_eff 0.5-4 um).
        x_top = float(size_parameter_at(float(upper[-1]), settings=settings))
        nmax = mie.wiscombe_nmax(max(x_top, 1e-3) * 1.0001 + 1.0)
        grids.append(int(_GRIDS[np.searchsorted(_GRIDS, nmax + 1)]))
    solvers = {
        n: _GroupSolver(
            m=m,
            wavelength_nm=wavelength_nm,
            mu_out=mu_out,
            n_half=n,
            per_particle=per_particle,
            settings=settings,
        )
        for n in sorted(set(grids))
    }
    npc = settings.nodes_per_panel
    stores: dict[bool, _Store] = {}
    legendre_grids = [n for n, g in solvers.items() if g.legendre]
    if legendre_grids:
        n_tiers = int(np.searchsorted(_GRIDS, max(legendre_grids))) + 1
        sizes, tables, table_start = _ladder_tables(n_tiers)
        stores[True] = _Store(
            nodes_per_cell=npc,
            width=2 * int(sizes[-1]),
            symmetric=True,
            sizes=sizes,
            tables=tables,
            table_start=table_start,
            spare=None if buffers is None else buffers.pop(True, None),
        )
    if len(legendre_grids) < len(solvers):
        # Few output angles: sums at the output angles themselves.
        nmax = max(n for n, g in solvers.items() if not g.legendre) - 1
        table = mie.angular_table(mu_out, nmax)
        stores[False] = _Store(
            nodes_per_cell=npc,
            width=mu_out.size,
            symmetric=False,
            sizes=np.array([mu_out.size], dtype=np.int64),
            tables=table.ravel(),
            table_start=np.array([0, table.size], dtype=np.int64),
            spare=None if buffers is None else buffers.pop(False, None),
        )
    for store in stores.values():
        # Room for the refinement to come: untouched pages of np.empty cost
        # nothing, while growing by copies would touch every page again.
        store.reserve(32 * max(st.lower.size for st in states))
    results = []
    weighted = 0
    # One distribution after the other, so that only one holds its rows
    # (hundreds of panels x the angular grid each): refining all of them in
    # step kept them all in memory and ran 2-4x slower for 100 of them.
    for st, n_half in zip(states, grids):
        group = solvers[n_half]
        result, n_weighted = _solve_one(
            group, stores[group.legendre], st, rtol=rtol, cross_rtol=cross_rtol
        )
        results.append(result)
        weighted += n_weighted
    stats = SharedStatistics(
        spheres_computed=sum(s.spheres_sums for s in stores.values()),
        spheres_with_angles=sum(s.spheres_angles for s in stores.values()),
        spheres_weighted=weighted,
    )
    if buffers is not None:
        buffers.update((key, store.flat) for key, store in stores.items())
    return results, stats


def _solve_one(
    group: _GroupSolver, store: _Store, st: _Distribution, *, rtol: float, cross_rtol: float
) -> tuple[_Result, int]:
    """One distribution's refinement on the shared cells (see
    :func:`solve_shared`), and the sphere-distribution pairs it weighted."""
    m, wavelength_nm, settings, per_particle = (
        group.m,
        group.wavelength_nm,
        group.settings,
        group.per_particle,
    )
    npc = settings.nodes_per_panel
    n_f = group.n_f
    weighted = 0

    def rows(lower: np.ndarray, upper: np.ndarray, angles: bool) -> np.ndarray:
        nonlocal weighted
        cells = store.ensure(m, lower, upper, angles, st.dist, wavelength_nm, settings)
        nodes, _ = panel_nodes(
            st.dist, wavelength_nm=wavelength_nm, lower_s=lower, upper_s=upper, settings=settings
        )
        weighted += cells.size * npc
        used = store.n * npc
        return _cell_rows(
            cells,
            nodes.weight,
            per_particle,
            n_f if angles else 0,
            npc,
            store.nodes[0, :used],
            store.nodes[1, :used],
            store.nodes[2, :used],
            store.nodes[3, :used],
            store.nodes[4, :used],
            store.intens[:used],
            store.n_values[: store.n],
            group.maps,
            group.map_start,
            # A cell's grid is the ladder's grid number tier, whose maps to
            # the group's grid come tier-th (unused for cells on that grid).
            store.tier[: store.n],
        )

    phase_norm = n_f if per_particle else n_f + 2
    cross_norm, cross_gnum = (0, 4) if per_particle else (2, 3)

    def refine(angles: bool, tol: float) -> _Run:
        st.cost = _panel_cost(st.upper, settings.transition_size_parameter, angles)
        while True:
            if angles:
                total, panel_error, error = _phase_refinement_errors(
                    st.pool, st.coarse, st.left, st.right, n_f, phase_norm
                )
            else:
                total, panel_error, error = _cross_refinement_errors(
                    st.pool, st.coarse, st.left, st.right, cross_norm, cross_gnum
                )
            if error <= tol or st.lower.size >= st.max_panels:
                order = np.argsort(st.lower, kind="stable")
                panels = np.column_stack([st.lower[order], st.upper[order]])
                return _Run(total, panels, 2 * npc * st.lower.size, error)
            split, eval_lower, eval_upper = _choose_splits(
                panel_error, st.cost, tol, _KEEP_FRACTION, st.lower, st.upper
            )
            new_rows = rows(eval_lower, eval_upper, angles)
            new_cost = _panel_cost(
                eval_upper[eval_upper.size // 2 :], settings.transition_size_parameter, angles
            )
            (st.pool, st.n_rows, st.coarse, st.left, st.right, st.lower, st.upper, st.cost) = (
                _apply_splits(
                    st.pool,
                    st.n_rows,
                    new_rows,
                    split,
                    st.coarse,
                    st.left,
                    st.right,
                    st.lower,
                    st.upper,
                    st.cost,
                    new_cost,
                    eval_lower,
                    eval_upper,
                )
            )

    # Each cell with its coarse rule and on its halves.
    n = st.lower.size
    mid = 0.5 * (st.lower + st.upper)
    first = rows(
        np.concatenate([st.lower, st.lower, mid]), np.concatenate([st.upper, mid, st.upper]), True
    )
    # Room for a few splits before _apply_splits grows the pool (by doubling).
    st.pool = np.empty((8 * first.shape[0], first.shape[1]))
    st.pool[: first.shape[0]] = first
    st.n_rows = 3 * n
    st.coarse, st.left, st.right = np.arange(n), np.arange(n, 2 * n), np.arange(2 * n, 3 * n)
    phase_run = refine(True, rtol)
    # The cross-sections continue from the phase function's panels.
    st.pool = np.ascontiguousarray(st.pool[: st.n_rows, n_f:])
    cross_run = refine(False, cross_rtol)
    st.pool = np.empty((0, 0))
    return group.finish(phase_run, cross_run, st.dist), weighted
