"""The adaptive refinement of one wavelength (dustoptics.scattering.refinement): its
error estimates hold, and its compiled steps equal their numpy statements."""

from __future__ import annotations

import numpy as np
import pytest

import dustoptics as do
from dustoptics.scattering.refinement import _Run, _WavelengthSolver


@pytest.mark.parametrize("weighting", ["scattering", "number"])
def test_doubling_nodes_stays_within_error_estimate(weighting: str) -> None:
    """Every final panel integrated with twice the nodes (its halves halved)
    moves the table by less than the reported error estimates."""
    dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    mat = do.mars_dust()
    wavelengths = [440.0, 680.0]
    t = do.compute_optics(
        mat, dist, wavelengths, np.linspace(0, 180, 181), weighting=weighting, workers=1
    )
    assert np.all(t.converged)
    for i, wl in enumerate(wavelengths):
        solver = _WavelengthSolver(
            m=complex(t.refractive_index[i]),
            wavelength_nm=wl,
            mu_out=t.mu,
            distribution=dist,
            per_particle=weighting == "number",
            settings=t.diagnostics.settings,
        )
        runs = []
        for panels, angles in (
            (t.diagnostics.panels[i], True),
            (t.diagnostics.cross_section_panels[i], False),
        ):
            lo, hi = panels[:, 0], panels[:, 1]
            edges = lo[:, None] + (hi - lo)[:, None] * np.array([0.0, 0.25, 0.5, 0.75, 1.0])
            rows = solver.evaluate(edges[:, :-1].ravel(), edges[:, 1:].ravel(), angles=angles)
            runs.append(
                _Run(
                    rows.sum(axis=0),
                    panels,
                    4 * panels.shape[0] * t.diagnostics.settings.nodes_per_panel,
                    0.0,
                )
            )
        finer = solver.finish(*runs)
        assert finer.n_nodes == 2 * t.quadrature.n_nodes[i]
        assert finer.cross_section_n_nodes == 2 * t.quadrature.cross_section_n_nodes[i]
        assert np.max(np.abs(finer.phase / t.phase[i] - 1)) <= t.quadrature.error_estimate[i]
        assert (
            abs(finer.cext / t.cross_sections.cext_um2[i] - 1)
            <= t.quadrature.cross_section_error_estimate[i]
        )
        assert (
            abs(finer.csca / t.cross_sections.csca_um2[i] - 1)
            <= t.quadrature.cross_section_error_estimate[i]
        )
        assert abs(finer.g - t.g[i]) <= t.quadrature.cross_section_error_estimate[i]


def test_phase_refinement_errors_equal_the_numpy_formula():
    """The compiled error pass of the refinement equals the formula written
    with whole-array numpy operations (sum of the halves; per panel
    max_mu |dF|/F plus the normalization's relative change; for the sum
    max_mu sum_p |dF_p|/F plus the summed normalization changes)."""
    from dustoptics.scattering.refinement import _phase_refinement_errors

    rng = np.random.default_rng(3)
    n_f, width, n_p = 40, 45, 7
    pool = rng.uniform(0.5, 2.0, size=(30, width))
    rows = rng.permutation(30)[: 3 * n_p]
    coarse, left, right = rows[:n_p], rows[n_p : 2 * n_p], rows[2 * n_p :]
    norm = n_f + 2
    total, panel_error, error = _phase_refinement_errors(pool, coarse, left, right, n_f, norm)

    fine = pool[left] + pool[right]
    want_total = fine.sum(axis=0)
    delta = np.abs(fine - pool[coarse])
    rel_f = delta[:, :n_f] / want_total[:n_f]
    rel_norm = delta[:, norm] / want_total[norm]
    np.testing.assert_allclose(total, want_total, rtol=1e-15)
    np.testing.assert_allclose(panel_error, rel_f.max(axis=1) + rel_norm, rtol=1e-14)
    assert error == pytest.approx(rel_f.sum(axis=0).max() + rel_norm.sum(), rel=1e-14)


@pytest.mark.parametrize("per_particle", [False, True])
def test_cross_refinement_errors_equal_the_numpy_formula(per_particle: bool):
    """The compiled error pass of the cross-section refinement equals the
    formula with whole-array numpy operations: relative changes of <C_ext>
    and <C_sca>, and of g = num / norm the bound (|d num| + |g| |d norm|) / norm."""
    from dustoptics.scattering.refinement import _cross_refinement_errors

    rng = np.random.default_rng(5)
    n_p = 9
    pool = rng.uniform(0.5, 2.0, size=(40, 5))
    rows = rng.permutation(40)[: 3 * n_p]
    coarse, left, right = rows[:n_p], rows[n_p : 2 * n_p], rows[2 * n_p :]
    norm, gnum = (0, 4) if per_particle else (2, 3)
    total, panel_error, error = _cross_refinement_errors(pool, coarse, left, right, norm, gnum)

    fine = pool[left] + pool[right]
    want_total = fine.sum(axis=0)
    delta = np.abs(fine - pool[coarse])
    g = want_total[gnum] / want_total[norm]
    cross = np.column_stack(
        [
            delta[:, 1] / want_total[1],
            delta[:, 2] / want_total[2],
            (delta[:, gnum] + abs(g) * delta[:, norm]) / want_total[norm],
        ]
    )
    np.testing.assert_allclose(total, want_total, rtol=1e-15)
    np.testing.assert_allclose(panel_error, cross.max(axis=1), rtol=1e-14)
    assert error == pytest.approx(cross.sum(axis=0).max(), rel=1e-14)


def test_split_bookkeeping_equals_the_numpy_formula():
    """The compiled split step of the refinement does what its numpy
    statement says: split panels in order of error per cost until the rest
    hold < keep_fraction of tol; the new panels (left halves, then right
    halves) take their parent's half rows as coarse rows and the evaluated
    rows as their halves; kept panels keep their order and rows."""
    from dustoptics.scattering.refinement import _apply_splits, _choose_splits

    rng = np.random.default_rng(11)
    n_p, width, tol, keep_fraction = 12, 6, 1e-4, 0.9
    edges = np.sort(rng.uniform(-3.0, 9.0, n_p + 1))
    lower, upper = edges[:-1], edges[1:]
    panel_error = rng.uniform(0.0, 0.3, n_p) * tol
    cost = rng.uniform(1.0, 50.0, n_p)
    split, eval_lower, eval_upper = _choose_splits(
        panel_error, cost, tol, keep_fraction, lower, upper
    )

    badness = panel_error / tol
    order = np.argsort(-badness / cost, kind="stable")
    cumulative = np.cumsum(badness[order])
    n_split = int(np.searchsorted(cumulative, cumulative[-1] - keep_fraction)) + 1
    want_split = np.sort(order[:n_split])
    np.testing.assert_array_equal(split, want_split)
    assert badness[np.setdiff1d(np.arange(n_p), split)].sum() < keep_fraction
    mid = 0.5 * (lower[split] + upper[split])
    new_lower = np.concatenate([lower[split], mid])
    new_upper = np.concatenate([mid, upper[split]])
    new_mid = 0.5 * (new_lower + new_upper)
    np.testing.assert_array_equal(eval_lower, np.concatenate([new_lower, new_mid]))
    np.testing.assert_array_equal(eval_upper, np.concatenate([new_mid, new_upper]))

    n_rows = 3 * n_p
    pool = rng.uniform(size=(n_rows + 1, width))  # full: the new rows must grow it
    coarse, left, right = np.arange(n_p), np.arange(n_p, 2 * n_p), np.arange(2 * n_p, 3 * n_p)
    k = 2 * split.size
    rows = rng.uniform(size=(2 * k, width))
    new_cost = rng.uniform(1.0, 50.0, k)
    got = _apply_splits(
        pool.copy(),
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
    grown, rows_after, got_coarse, got_left, got_right, got_lower, got_upper, got_cost = got
    keep = np.ones(n_p, dtype=bool)
    keep[split] = False
    assert rows_after == n_rows + 2 * k
    np.testing.assert_array_equal(grown[:n_rows], pool[:n_rows])
    np.testing.assert_array_equal(grown[n_rows:rows_after], rows)
    np.testing.assert_array_equal(
        got_coarse, np.concatenate([coarse[keep], left[split], right[split]])
    )
    np.testing.assert_array_equal(
        got_left, np.concatenate([left[keep], np.arange(n_rows, n_rows + k)])
    )
    np.testing.assert_array_equal(
        got_right, np.concatenate([right[keep], np.arange(n_rows + k, n_rows + 2 * k)])
    )
    np.testing.assert_array_equal(got_lower, np.concatenate([lower[keep], new_lower]))
    np.testing.assert_array_equal(got_upper, np.concatenate([upper[keep], new_upper]))
    np.testing.assert_array_equal(got_cost, np.concatenate([cost[keep], new_cost]))


@pytest.mark.parametrize("per_particle", [False, True])
def test_accumulate_by_tier_equals_the_full_grid(per_particle: bool):
    """The solver's entry to the kernel (tier per panel, nodes ordered by
    tier then size, panels given in any order) gives each panel the row that
    summing every sphere on the full angle grid gives, to round-off (1e-10 of
    each row's largest value, as the tiers' own test in test_mie)."""
    from dustoptics.scattering import mie
    from dustoptics.scattering.refinement import _accumulate_by_tier, _angular_tiers, _gauss_angles

    m = 1.52 + 0.004j
    n_full = 96
    tiers = _angular_tiers(n_full)
    per = 8
    # Six disjoint panels of increasing size, handed over in shuffled order.
    starts = [0.5, 4.0, 12.0, 30.0, 52.0, 71.0]
    panels = [np.linspace(a, a + 2.0, per) for a in starts]
    shuffled = [4, 1, 5, 0, 3, 2]
    x = np.concatenate([panels[p] for p in shuffled])
    w = np.linspace(0.5, 1.5, x.size)
    node_panel = np.repeat(np.arange(len(shuffled)), per)
    fast = _accumulate_by_tier(m, x, w, node_panel, per, per_particle, *tiers, 1, 0j, 0.0)
    simple = mie._accumulate(
        m,
        x,
        w,
        node_panel,
        len(shuffled),
        per_particle,
        _gauss_angles(n_full)[2],
        n_full,
        True,
        1,
        0j,
        0.0,
    )
    assert fast.shape == simple.shape
    for p in range(len(shuffled)):
        np.testing.assert_allclose(fast[p], simple[p], rtol=0, atol=1e-10 * np.abs(simple[p]).max())


def test_accumulate_by_tier_rejects_spheres_beyond_the_largest_tier():
    """The kernel reads its angular tables without bounds checks, so a panel
    whose spheres need more orders than the largest tier holds is an error,
    not a read past the tables."""
    from dustoptics.scattering.refinement import _accumulate_by_tier, _angular_tiers

    x = np.linspace(100.0, 110.0, 8)  # n_max ~ 130 > 96
    with pytest.raises(ValueError, match="largest angular tier"):
        _accumulate_by_tier(
            1.5 + 0.01j,
            x,
            np.ones(8),
            np.zeros(8, dtype=np.int64),
            8,
            False,
            *_angular_tiers(96),
            1,
            0j,
            0.0,
        )


def test_nodes_go_to_the_smallest_tier_that_holds_them_by_tier_then_size():
    """_order_by_tier: each panel's nodes go, together and in order, to the smallest tier
    with n_max + 2 orders of its largest sphere (n_max = x + 4.05 x^(1/3) + 2, Wiscombe's
    rule before rounding); the nodes come ordered by tier, then by size parameter."""
    from dustoptics.scattering.refinement import _order_by_tier

    rng = np.random.default_rng(5)
    npp, n_panels = 4, 40
    edges = np.sort(10 ** rng.uniform(-1.0, 2.5, n_panels + 1))  # disjoint panels
    inside = np.sort(rng.uniform(0.0, 1.0, (n_panels, npp)), axis=1)
    x = (edges[:-1, None] + np.diff(edges)[:, None] * inside)[rng.permutation(n_panels)].ravel()
    w = rng.uniform(size=x.size)
    node_panel = np.repeat(np.arange(n_panels), npp)
    tiers = np.array([32, 48, 64, 96, 128, 192, 400, 640])
    xs, ws, panels, node_tier, n = _order_by_tier(x, w, node_panel, npp, tiers)
    assert n == n_panels
    np.testing.assert_array_equal(np.sort(xs), np.sort(x))
    for j in range(x.size):  # each node keeps its weight and panel
        i = int(np.flatnonzero(x == xs[j])[0])
        assert (ws[j], panels[j]) == (w[i], node_panel[i])
    for p in range(n_panels):
        mine = panels == p
        np.testing.assert_array_equal(xs[mine], x[p * npp : (p + 1) * npp])
        top = x[(p + 1) * npp - 1]
        need = top + 4.05 * np.cbrt(top) + 2.0 + 2.0  # rounded down (to the last bit)
        t = node_tier[mine][0]
        assert np.all(node_tier[mine] == t)
        assert tiers[t] >= np.floor(need * (1.0 - 1e-12))  # holds the orders
        assert t == 0 or tiers[t - 1] < np.floor(need * (1.0 + 1e-12))  # the smallest that does
    key = node_tier * 1e6 + xs
    assert np.all(np.diff(key) > 0)
    with pytest.raises(ValueError, match="more orders than the largest angular tier"):
        _order_by_tier(x, w, node_panel, npp, tiers[:3])
