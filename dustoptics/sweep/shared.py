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
<dustoptics.scattering.optics._WavelengthSolver.refine>`: coarse rule against
the rules on the halves, most error per unit of work split first, the phase
function to ``rtol``, then the cross-sections and g to ``cross_section_rtol``
from the phase function's panels), with its own error estimates and its own
tolerance.  All distributions refine in lockstep: every step gathers the cells
that any of them needs, computes the spheres of the cells that no distribution
has needed before (:func:`_cell_intensities`), and weights them for each one
(:func:`_cell_rows`).  A cell's spheres are the same numbers whichever
distribution asked first, so the results do not depend on the order of the
distributions or on which others share the group.

How it relates to a single build: a distribution's panels here are cells of
the shared tree, while a single build cuts its own range into equal panels.
Both quadratures converge to the same integrals, and each reports an estimate
of its own error, so the two tables differ by at most the sum of their error
estimates (the tests check it).  With identical panels the two would agree to
the bit: a cell's row is summed sphere by sphere in the order and with the
expressions of :func:`dustoptics.scattering.mie._add_sphere`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from dustoptics.particles.sizedist import SizeDistribution
from dustoptics.scattering import mie
from dustoptics.scattering.optics import (
    _KEEP_FRACTION,
    _angular_tiers,
    _apply_splits,
    _choose_splits,
    _cross_refinement_errors,
    _gauss_angles,
    _panel_cost,
    _phase_refinement_errors,
    _Result,
    _Run,
    _WavelengthSolver,
)
from dustoptics.scattering.quadrature import (
    QuadratureSettings,
    initial_panels,
    panel_nodes,
    size_parameter_at,
)

__all__ = ["SharedStatistics", "solve_shared"]


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
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unweighted intensities and efficiencies of spheres of size parameters ``x``.

    Sphere j is summed on tier ``node_tier[j]`` (< 0: efficiencies only): the
    grid of ``tier_size[t]`` angles (half-grid angles if ``symmetric``) whose
    :func:`mie.angular_table` is ``tables[table_start[t]:table_start[t + 1]]``
    (flattened), as in :func:`mie._accumulate_tiers`.  I(mu) = |S1|^2 +
    |S2|^2 there (+mu then -mu if ``symmetric``) is computed by
    :func:`mie._add_sphere` with weight 1, so that c I afterwards is the
    number the kernel adds for a sphere of weight c, and written to the
    first values of ``out[out_rows[j]]``.  Give the spheres sorted by size,
    so that each batch of Mie coefficients holds spheres of similar n_max.
    Returns Q_ext, Q_sca, g Q_sca and x^2 Q_back.
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
    for j0 in range(0, n_nodes, mie.LANES):
        n_live = min(mie.LANES, n_nodes - j0)
        for s in range(mie.LANES):  # a short last batch repeats its last sphere
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
    angles: bool,
    nodes_per_cell: int,
    x: np.ndarray,
    qext: np.ndarray,
    qsca: np.ndarray,
    gq: np.ndarray,
    back: np.ndarray,
    intens: np.ndarray,
    n_f_cell: np.ndarray,
) -> np.ndarray:
    """One distribution's rows for the cells ``cells`` (indices into the store).

    Node i of row r has weight ``w[r * nodes_per_cell + i]``; node j of the
    store has size parameter ``x[j]``, efficiencies ``qext[j]``, ``qsca[j]``,
    ``gq[j]`` (g Q_sca) and intensities ``intens[j, :n_f_cell[c]]`` on its
    cell's tier.  Each row holds the weighted intensities on the cell's tier
    (if ``angles``; the caller moves them to the full grid) and, in its last
    N_SUMS columns, the sums of :func:`mie._accumulate`, sphere after sphere
    in order of size, with the expressions of :func:`mie._add_sphere`.
    """
    n_f = intens.shape[1] if angles else 0
    out = np.zeros((cells.shape[0], n_f + mie.N_SUMS))
    for r in range(cells.shape[0]):
        c = cells[r]
        row = out[r]
        n_c = n_f_cell[c] if angles else 0
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
            if angles:
                cj = wj / (2.0 * np.pi * x2 * qsca[j]) if per_particle else wj
                values = intens[j]
                for k in range(n_c):
                    row[k] += cj * values[k]
    return out


class _Store:
    """Spheres of the cells computed so far, in arrays grown by doubling:
    per node x, Q_ext, Q_sca, g Q_sca and the intensities on its cell's
    angular tier (undefined until the cell is computed with angles)."""

    def __init__(self, nodes_per_cell: int, n_f: int) -> None:
        self.npc = nodes_per_cell
        self.key: dict[tuple[float, float], int] = {}
        self.n = 0  # cells
        self.has_angles = np.zeros(0, dtype=np.bool_)
        self.tier = np.zeros(0, dtype=np.int64)  # -1: no angles
        self.n_f = np.zeros(0, dtype=np.int64)  # angular values on the cell's tier
        self.nodes = np.empty((5, 0))  # x, qext, qsca, gq, x^2 qback
        self.intens = np.empty((0, n_f))
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
        tier = np.full(size, -1, dtype=np.int64)
        tier[: self.n] = self.tier[: self.n]
        self.tier = tier
        n_f = np.zeros(size, dtype=np.int64)
        n_f[: self.n] = self.n_f[: self.n]
        self.n_f = n_f
        nodes = np.empty((5, size * self.npc))
        nodes[:, :used] = self.nodes[:, :used]
        self.nodes = nodes
        intens = np.empty((size * self.npc, self.intens.shape[1]))
        intens[:used] = self.intens[:used]
        self.intens = intens


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
    """The angular grid of a group of distributions at one wavelength: n_half
    positive Gauss angles (or the output angles, when there are fewer) with
    n_half - 1 orders, so that :meth:`_WavelengthSolver.finish` turns a
    distribution's runs into its result."""

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
        self.legendre = n_half < mu_out.size
        self.gauss = self.legendre
        if self.legendre:
            self.n_half = n_half
            self.mu_half, self.w_half = _gauss_angles(n_half)[:2]
            self.n_f = 2 * n_half
            self.tiers, self._tables, self._table_start, self._maps, self._map_start = (
                _angular_tiers(n_half)
            )
            # The maps from each lower tier to the full grid, as matrices.
            self.regrid = []
            for t, n_t in enumerate(self.tiers[:-1]):
                size = int(n_t) * n_half
                start = int(self._map_start[t])
                self.regrid.append(
                    (
                        self._maps[start : start + size].reshape(int(n_t), n_half),
                        self._maps[start + size : start + 2 * size].reshape(int(n_t), n_half),
                    )
                )
        else:
            # Few output angles: one tier, the output angles themselves.
            table = mie.angular_table(mu_out, self.nmax)
            self.n_f = mu_out.size
            self.tiers = np.array([mu_out.size], dtype=np.int64)
            self._tables = table.ravel()
            self._table_start = np.array([0, table.size], dtype=np.int64)
            self.regrid = []

    def to_full_grid(self, rows: np.ndarray, tier: np.ndarray) -> None:
        """Move the angular values of ``rows`` (in place) from their tiers to
        the full grid by the maps of :func:`mie._interpolation_maps` (exact for
        the spheres' polynomials), as :func:`mie._accumulate_tiers` does."""
        n_top = self.n_f // 2
        for t, (r_even, r_odd) in enumerate(self.regrid):
            idx = np.flatnonzero(tier == t)
            if idx.size == 0:
                continue
            n_t = r_even.shape[0]
            block = np.ascontiguousarray(rows[idx, : 2 * n_t])
            rows[idx, : 2 * n_top] = mie._legendre_regrid(block, r_even, r_odd)


#: Angular grids (positive Gauss angles of a symmetric rule): multiples of 16
#: about 2^(1/4) apart, so that rows are at most ~19 % wider than needed.
_GRIDS = np.unique(16 * np.ceil(32.0 * 2.0 ** (np.arange(80) / 4.0) / 16.0).astype(np.int64))


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
        self.run: _Run | None = None
        self.request: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


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

    Returns
    -------
    list of _Result, SharedStatistics
        One result per distribution, in order, as a single build's solver
        returns it (read by :func:`dustoptics.scattering.optics.compute_optics`'s
        assembly), and the work done.
    """
    lower_moment = 0 if per_particle else 2
    states = []
    nmax = 0
    for dist in distributions:
        edges = initial_panels(
            dist, wavelength_nm=wavelength_nm, settings=settings, lower_moment=lower_moment
        )
        lower, upper = _tree_cells(float(edges[0]), float(edges[-1]), settings)
        state = _Distribution(dist, lower, upper)
        state.max_panels = lower.size * 2**settings.max_level
        states.append(state)
        x_top = float(size_parameter_at(float(upper[-1]), settings=settings))
        nmax = max(nmax, mie.wiscombe_nmax(max(x_top, 1e-3) * 1.0001 + 1.0))
    # The grid of the group's largest sphere, rounded up a ladder of sizes so
    # that the wavelengths of a sweep share a few grids, whose angular tables
    # and interpolation maps each worker then builds once (cached).
    group = _GroupSolver(
        m=m,
        wavelength_nm=wavelength_nm,
        mu_out=mu_out,
        n_half=int(_GRIDS[np.searchsorted(_GRIDS, nmax + 1)]),
        per_particle=per_particle,
        settings=settings,
    )
    return _solve_group(group, states, rtol=rtol, cross_rtol=cross_rtol)


def _solve_group(
    group: _GroupSolver, states: list[_Distribution], *, rtol: float, cross_rtol: float
) -> tuple[list[_Result], SharedStatistics]:
    """Lockstep refinement of distributions that share a grid (see :func:`solve_shared`)."""
    m, wavelength_nm, settings, per_particle = (
        group.m,
        group.wavelength_nm,
        group.settings,
        group.per_particle,
    )
    npc = settings.nodes_per_panel
    store = _Store(npc, group.n_f)
    weighted = 0

    def ensure(lower: np.ndarray, upper: np.ndarray, angles: bool) -> None:
        """Compute the spheres of the cells not yet in the store (with their
        angular sums if ``angles``)."""
        new: dict[tuple[float, float], None] = {}
        upgrade = []
        for k in zip(lower.tolist(), upper.tolist()):
            c = store.key.get(k)
            if c is None:
                new[k] = None
            elif angles and not store.has_angles[c]:
                upgrade.append(c)
        if not new and not upgrade:
            return
        base = store.n
        store.reserve(base + len(new))
        for i, k in enumerate(new):
            store.key[k] = base + i
        store.n = base + len(new)
        lo = np.array([k[0] for k in new], dtype=np.float64)
        hi = np.array([k[1] for k in new], dtype=np.float64)
        nodes, _ = panel_nodes(
            states[0].dist, wavelength_nm=wavelength_nm, lower_s=lo, upper_s=hi, settings=settings
        )
        store.nodes[0, base * npc : store.n * npc] = nodes.size_parameter
        cells = np.concatenate([np.arange(base, store.n), np.array(upgrade, dtype=np.int64)])
        node_rows = (cells[:, None] * npc + np.arange(npc)).ravel()
        x = store.nodes[0, node_rows]
        if angles and group.legendre:
            # The smallest tier that holds n_max + 2 orders of the cell's
            # largest sphere, as :func:`_accumulate_by_tier` chooses.
            x_top = x.reshape(-1, npc).max(axis=1)
            n_needed = (x_top + 4.05 * np.cbrt(x_top) + 2.0).astype(np.int64) + 2
            tier = np.searchsorted(group.tiers, n_needed).astype(np.int64)
            if np.any(tier >= group.tiers.size):
                raise ValueError("a cell's spheres need more orders than the largest tier holds")
        else:
            tier = np.full(cells.size, 0 if angles else -1, dtype=np.int64)
        if angles:
            store.tier[cells] = tier
            store.n_f[cells] = group.tiers[tier] * (2 if group.legendre else 1)
        # By size, so that each batch of Mie coefficients holds spheres of
        # similar n_max.
        order = np.argsort(x, kind="stable")
        node_rows = node_rows[order]
        qext, qsca, gq, back = _cell_intensities(
            m,
            np.ascontiguousarray(x[order]),
            np.repeat(tier, npc)[order],
            group.tiers,
            group._tables,
            group._table_start,
            group.legendre,
            store.intens,
            node_rows,
        )
        store.nodes[1, node_rows] = qext
        store.nodes[2, node_rows] = qsca
        store.nodes[3, node_rows] = gq
        store.nodes[4, node_rows] = back
        if angles:
            store.has_angles[cells] = True
            store.spheres_angles += cells.size * npc
        store.spheres_sums += len(new) * npc

    def rows(
        state: _Distribution, lower: np.ndarray, upper: np.ndarray, angles: bool
    ) -> np.ndarray:
        nonlocal weighted
        cells = np.array(
            [store.key[k] for k in zip(lower.tolist(), upper.tolist())], dtype=np.int64
        )
        nodes, _ = panel_nodes(
            state.dist, wavelength_nm=wavelength_nm, lower_s=lower, upper_s=upper, settings=settings
        )
        weighted += cells.size * npc
        used = store.n * npc
        out = _cell_rows(
            cells,
            nodes.weight,
            per_particle,
            angles,
            npc,
            store.nodes[0, :used],
            store.nodes[1, :used],
            store.nodes[2, :used],
            store.nodes[3, :used],
            store.nodes[4, :used],
            store.intens[:used],
            store.n_f[: store.n],
        )
        if angles:
            group.to_full_grid(out, store.tier[cells])
        return out

    def halves_of(lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mid = 0.5 * (lower + upper)
        return np.concatenate([lower, mid]), np.concatenate([mid, upper])

    # Initial states: each cell with its coarse rule and on its halves.
    lo_all, hi_all = [], []
    for st in states:
        hl, hu = halves_of(st.lower, st.upper)
        lo_all += [st.lower, hl]
        hi_all += [st.upper, hu]
    # Room for the refinement to come: untouched pages of np.empty cost
    # nothing, while growing by copies would touch every page again.
    store.reserve(32 * sum(st.lower.size for st in states))
    ensure(np.concatenate(lo_all), np.concatenate(hi_all), True)
    for st in states:
        hl, hu = halves_of(st.lower, st.upper)
        n = st.lower.size
        first = np.concatenate([rows(st, st.lower, st.upper, True), rows(st, hl, hu, True)])
        # Room for a few splits before _apply_splits grows the pool (by doubling).
        st.pool = np.empty((8 * first.shape[0], first.shape[1]))
        st.pool[: first.shape[0]] = first
        st.n_rows = 3 * n
        st.coarse, st.left, st.right = np.arange(n), np.arange(n, 2 * n), np.arange(2 * n, 3 * n)

    n_f = group.n_f
    phase_norm = n_f if per_particle else n_f + 2
    cross_norm, cross_gnum = (0, 4) if per_particle else (2, 3)

    def refine_all(active: list[_Distribution], angles: bool, tol: float) -> None:
        for st in active:
            st.cost = _panel_cost(st.upper, settings.transition_size_parameter, angles)
        while active:
            still = []
            lo_req, hi_req = [], []
            for st in active:
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
                    st.run = _Run(total, panels, 2 * npc * st.lower.size, error)
                    continue
                split, eval_lower, eval_upper = _choose_splits(
                    panel_error, st.cost, tol, _KEEP_FRACTION, st.lower, st.upper
                )
                st.request = (split, eval_lower, eval_upper)
                lo_req.append(eval_lower)
                hi_req.append(eval_upper)
                still.append(st)
            if not still:
                break
            ensure(np.concatenate(lo_req), np.concatenate(hi_req), angles)
            for st in still:
                assert st.request is not None
                split, eval_lower, eval_upper = st.request
                new_rows = rows(st, eval_lower, eval_upper, angles)
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
            active = still

    refine_all(list(states), True, rtol)
    phase_runs = [st.run for st in states]
    for st in states:
        # The cross-sections continue from the phase function's panels.
        st.pool = np.ascontiguousarray(st.pool[:, n_f:])
    refine_all(list(states), False, cross_rtol)
    results = []
    for st, phase_run in zip(states, phase_runs):
        assert phase_run is not None and st.run is not None
        results.append(group.finish(phase_run, st.run, st.dist))
    stats = SharedStatistics(
        spheres_computed=store.spheres_sums,
        spheres_with_angles=store.spheres_angles,
        spheres_weighted=weighted,
    )
    return results, stats
