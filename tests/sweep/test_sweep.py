"""Sweeps: shared nodes against single builds, validation, and a real Dask cluster.

The reliability tests run on a ``dask.distributed`` LocalCluster of two
worker processes started here on localhost: a worker killed in the middle of
a sweep, a rerun that must compute nothing, and the same sweep through the
scheduler's address, each compared byte for byte with an undisturbed run.
Grids are small (4 points, 4 wavelengths, 181 angles) to keep them fast.
"""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest
from _sweeps import WAVELENGTHS, small_toml, store_bytes
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import mie as reference_mie

import dustoptics as do
from dustoptics.models.compute import build_table
from dustoptics.models.config import parse_config
from dustoptics.scattering import mie
from dustoptics.scattering.quadrature import QuadratureSettings, panel_nodes
from dustoptics.sweep.spec import (
    config_data,
    load_sweep,
    parse_point,
    parse_points,
    toml_text,
)

distributed = pytest.importorskip(
    "distributed", reason="needs the 'sweep' extra (dask[distributed])"
)
xr = pytest.importorskip("xarray", reason="needs the 'sweep' extra (xarray)")
pytest.importorskip("zarr", reason="needs the 'sweep' extra (zarr)")

from dustoptics.scattering.refinement import _gauss_angles  # noqa: E402
from dustoptics.sweep import local_cluster, sweep  # noqa: E402
from dustoptics.sweep.shared import (  # noqa: E402
    _GRIDS,
    _cell_intensities,
    _cell_rows,
    solve_shared,
)

OVER = {"size_distribution.r_eff_um": [0.8, 1.6], "size_distribution.v_eff": [0.1, 0.3]}


@pytest.fixture(scope="module")
def config_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("sweep") / "small.toml"
    path.write_text(small_toml(), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def cluster():
    """Two worker processes on localhost, as a sweep starts them
    (:func:`dustoptics.sweep.local_cluster`); the numba cache is warmed here
    first, so that the workers load every kernel from it."""
    dust = do.mars_dust()
    mu = np.cos(np.deg2rad(np.linspace(0.0, 180.0, 181)))
    solve_shared(
        m=complex(dust(np.array([550.0]))[0]),
        wavelength_nm=550.0,
        mu_out=mu,
        distributions=[do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2)],
        per_particle=False,
        settings=QuadratureSettings(),
        rtol=1e-3,
        cross_rtol=1e-5,
    )
    with local_cluster(2) as c:
        yield c


@pytest.fixture(scope="module")
def reference(cluster, config_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An undisturbed run through a Client."""
    out = tmp_path_factory.mktemp("ref") / "ref.zarr"
    with distributed.Client(cluster) as client:
        sweep(config_file, OVER, out=out, client=client, chunk_wavelengths=1, progress=None)
    return out


# ---------------------------------------------------------------- shared nodes


def one_grid_intensities(m, x, table, n_angles, symmetric):
    """_cell_intensities of the spheres x (cells of 16) on one grid of
    ``n_angles`` angles (half-grid angles if ``symmetric``) whose angular
    table is ``table``: the intensities and (Q_ext, Q_sca, g Q_sca, x^2 Q_back)."""
    intens = np.empty((x.size, (2 if symmetric else 1) * n_angles))
    sums = _cell_intensities(
        m,
        x,
        np.zeros(x.size, dtype=np.int64),
        np.array([n_angles]),
        table.ravel(),
        np.array([0, table.size]),
        symmetric,
        intens,
        np.arange(x.size),
        16,
    )
    return intens, sums


def test_cell_rows_are_the_kernels_sums_to_the_bit():
    """A cell's weighted row from unweighted sphere intensities equals
    mie._accumulate's row for the same nodes and weights, to the bit."""
    dist = do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2)
    settings = QuadratureSettings()
    lower, upper = np.array([0.0, 8.0]), np.array([8.0, 16.0])
    nodes, node_panel = panel_nodes(
        dist, wavelength_nm=550.0, lower_s=lower, upper_s=upper, settings=settings
    )
    mu = np.cos(np.deg2rad(np.linspace(0.0, 180.0, 37)))
    nmax = mie.wiscombe_nmax(float(nodes.size_parameter.max()))
    table = mie.angular_table(mu, nmax)
    m = 1.55 + 0.003j
    x = nodes.size_parameter
    for per_particle in (False, True):
        expected = mie._accumulate(
            m, x, nodes.weight, node_panel, 2, per_particle, table, mu.size, False, 1, 0j, 0.0
        )
        intens, (qext, qsca, gq, back) = one_grid_intensities(m, x, table, mu.size, False)
        rows = _cell_rows(
            np.arange(2),
            nodes.weight,
            per_particle,
            mu.size,
            16,
            x,
            qext,
            qsca,
            gq,
            back,
            intens,
            np.array([mu.size, mu.size]),
            np.empty(0),
            np.zeros(1, dtype=np.int64),
            np.zeros(2, dtype=np.int64),
        )
        assert np.array_equal(rows, expected)


def test_cell_rows_on_a_smaller_grid_are_moved_as_the_kernel_moves_them():
    """A cell summed on a smaller Gauss grid of the ladder and moved to the
    distribution's grid equals, to the bit, mie._accumulate's row on that
    grid moved by mie._legendre_regrid (what a single build does), and the
    intensities on the grid (the polynomial of degree 2 n_max that both
    grids resolve) to 1e-12 of the row summed on the larger grid directly."""
    dist = do.ModifiedGamma(r_eff_um=0.3, v_eff=0.2)
    settings = QuadratureSettings()
    lower, upper = np.array([0.0]), np.array([8.0])
    nodes, node_panel = panel_nodes(
        dist, wavelength_nm=550.0, lower_s=lower, upper_s=upper, settings=settings
    )
    x = nodes.size_parameter
    small, large = (int(n) for n in _GRIDS[[0, 3]])  # 32 and 80 half-grid angles
    assert mie.wiscombe_nmax(float(x.max())) + 2 <= small
    m = 1.55 + 0.003j
    mu_s, w_s, table_s = _gauss_angles(small)
    mu_l, _, table_l = _gauss_angles(large)
    r_even, r_odd = reference_mie.interpolation_maps(mu_s, w_s, mu_l)
    intens, (qext, qsca, gq, back) = one_grid_intensities(m, x, table_s, small, True)
    maps = np.concatenate([r_even.ravel(), r_odd.ravel()])
    for per_particle in (False, True):
        rows = _cell_rows(
            np.arange(1),
            nodes.weight,
            per_particle,
            2 * large,
            16,
            x,
            qext,
            qsca,
            gq,
            back,
            intens,
            np.array([2 * small]),
            maps,
            np.array([0, maps.size]),
            np.zeros(1, dtype=np.int64),
        )
        on_small = mie._accumulate(
            m, x, nodes.weight, node_panel, 1, per_particle, table_s, small, True, 1, 0j, 0.0
        )
        moved = mie._legendre_regrid(np.ascontiguousarray(on_small[:, : 2 * small]), r_even, r_odd)
        assert np.array_equal(rows[:, : 2 * large], moved)
        assert np.array_equal(rows[:, 2 * large :], on_small[:, 2 * small :])
        direct = mie._accumulate(
            m, x, nodes.weight, node_panel, 1, per_particle, table_l, large, True, 1, 0j, 0.0
        )
        assert np.allclose(rows[:, : 2 * large], direct[:, : 2 * large], rtol=1e-12, atol=0)


def solve_mars_dust(wavelength_nm, distributions, buffers=None):
    """solve_shared's results for Mars dust at one wavelength, 361 angles,
    scattering weighting, rtol 1e-4 (cross-sections 1e-6)."""
    return solve_shared(
        m=complex(do.mars_dust()(np.array([wavelength_nm]))[0]),
        wavelength_nm=wavelength_nm,
        mu_out=np.cos(np.deg2rad(np.linspace(0.0, 180.0, 361))),
        distributions=distributions,
        per_particle=False,
        settings=QuadratureSettings(),
        rtol=1e-4,
        cross_rtol=1e-6,
        buffers=buffers,
    )[0]


def test_shared_results_do_not_depend_on_the_other_distributions():
    """A distribution's result is the same to the bit whichever distributions
    share its solve and in whatever order (a cell's spheres are the same
    numbers whoever asked for them first)."""
    dists = [
        do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1),
        do.ModifiedGamma(r_eff_um=1.5, v_eff=0.3),
        do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2),
    ]
    together = solve_mars_dust(600.0, dists)
    for i, dist in enumerate(dists):
        alone = solve_mars_dust(600.0, [dist])[0]
        reversed_ = solve_mars_dust(600.0, dists[::-1])[len(dists) - 1 - i]
        for r in (alone, reversed_):
            assert np.array_equal(r.phase, together[i].phase)
            assert (r.cext, r.csca, r.g, r.err_phase) == (
                together[i].cext,
                together[i].csca,
                together[i].g,
                together[i].err_phase,
            )


def test_intensity_arrays_kept_between_wavelengths_change_no_bit():
    """Stores that reuse the previous wavelength's intensity arrays (their
    rows still hold its spheres, on other grids) give the same bits as fresh
    ones: the larger spheres first, then smaller ones, then larger again."""
    dists = [do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1), do.ModifiedGamma(r_eff_um=2.0, v_eff=0.3)]
    buffers: dict = {}
    for wavelength_nm in (400.0, 900.0, 500.0):
        fresh = solve_mars_dust(wavelength_nm, dists)
        reused = solve_mars_dust(wavelength_nm, dists, buffers=buffers)
        assert buffers[True].size > 0
        for a, b in zip(fresh, reused):
            assert np.array_equal(a.phase, b.phase)
            assert (a.cext, a.csca, a.g, a.err_phase, a.err_cross) == (
                b.cext,
                b.csca,
                b.g,
                b.err_phase,
                b.err_cross,
            )


@pytest.mark.parametrize("weighting", ["scattering", "number"])
def test_shared_nodes_meet_their_error_estimates(weighting):
    """Each distribution solved on the shared tree meets the tolerances it was
    given (phase function 1e-4 at every angle, relative; cross-sections 1e-6
    relative; g 1e-6 absolute) against a reference single build at 100x
    tighter tolerances, and reports estimates within them, with fewer spheres
    computed than weighted.  (Its error estimates, like a single build's,
    are estimates: in one of these 20 cases, number weighting at 700 nm,
    r_eff 0.3 um, v_eff 0.35, the phase function's error is 8.1e-5 against an
    estimate of 4.3e-5, inside the tolerance.)"""
    dust = do.mars_dust()
    theta = np.linspace(0.0, 180.0, 721)  # more angles than n_half: the Legendre path
    dists = [do.ModifiedGamma(r_eff_um=r, v_eff=v) for r in (0.3, 0.9) for v in (0.1, 0.35)] + [
        do.ModifiedLogNormal(r_eff_um=0.6, v_eff=0.2)
    ]
    for wl in (450.0, 700.0):
        m = complex(dust(np.array([wl]))[0])
        results, stats = solve_shared(
            m=m,
            wavelength_nm=wl,
            mu_out=np.cos(np.deg2rad(theta)),
            distributions=dists,
            per_particle=weighting == "number",
            settings=QuadratureSettings(),
            rtol=1e-4,
            cross_rtol=1e-6,
        )
        assert stats.spheres_computed < stats.spheres_weighted
        for dist, r in zip(dists, results):
            ref = do.compute_optics(
                m,
                dist,
                [wl],
                theta,
                weighting=weighting,
                workers=1,
                rtol=1e-6,
                cross_section_rtol=1e-8,
            )
            assert r.err_phase <= 1e-4 and r.err_cross <= 1e-6
            assert (
                np.max(np.abs(r.phase / ref.phase[0] - 1.0))
                <= 1e-4 + ref.quadrature.error_estimate[0]
            )
            cross = 1e-6 + ref.quadrature.cross_section_error_estimate[0]
            assert abs(r.cext / ref.cross_sections.cext_um2[0] - 1.0) <= cross
            assert abs(r.csca / ref.cross_sections.csca_um2[0] - 1.0) <= cross
            assert abs(r.g - ref.g[0]) <= cross


def test_few_output_angles_sum_at_the_angles_themselves():
    """With fewer output angles than a distribution's Gauss grid (61 angles,
    r_eff 2 um at 450 nm), its spheres are summed at the output angles
    directly (no grid, no move), in a store of their own beside the one of
    the ladder's grids (r_eff 0.05 um); each result still meets its
    tolerance against a reference single build at 100x tighter tolerances."""
    dust = do.mars_dust()
    theta = np.linspace(0.0, 180.0, 61)
    dists = [do.ModifiedGamma(r_eff_um=r, v_eff=0.2) for r in (0.05, 2.0)]
    m = complex(dust(np.array([450.0]))[0])
    results, _ = solve_shared(
        m=m,
        wavelength_nm=450.0,
        mu_out=np.cos(np.deg2rad(theta)),
        distributions=dists,
        per_particle=False,
        settings=QuadratureSettings(),
        rtol=1e-4,
        cross_rtol=1e-6,
    )
    for dist, r in zip(dists, results):
        ref = do.compute_optics(
            m, dist, [450.0], theta, workers=1, rtol=1e-6, cross_section_rtol=1e-8
        )
        assert (
            np.max(np.abs(r.phase / ref.phase[0] - 1.0)) <= 1e-4 + ref.quadrature.error_estimate[0]
        )
        assert abs(r.g - ref.g[0]) <= 1e-6 + ref.quadrature.cross_section_error_estimate[0]


# ---------------------------------------------------------------- the specification


def test_config_data_round_trips_every_preset():
    for name in do.list_presets():
        config = do.presets.load_preset(name)
        again = parse_config(toml_text(config_data(config)))
        assert again.to_inputs() == config.to_inputs()


def test_axis_value_outside_its_range_is_rejected_before_any_work(config_file, tmp_path):
    out = tmp_path / "never.zarr"
    over = {"size_distribution.v_eff": [0.2, 0.7]}
    with pytest.raises(ValueError, match=r"size_distribution\.v_eff.*0\.7.*\(0, 0\.5\)"):
        sweep(config_file, over, out=out, progress=None)
    assert not out.exists()
    with pytest.raises(ValueError, match=r"material\.hematite_fraction.*1\.5.*\[0, 1\]"):
        load_sweep(config_file, {"material.hematite_fraction": [0.03, 1.5]})
    with pytest.raises(ValueError, match=r"not a numeric input"):
        load_sweep(config_file, {"size_distribution.model": [1.0]})
    with pytest.raises(ValueError, match=r"material\.host_index\.n, material\.host_index\.k"):
        load_sweep(config_file, {"material.host_index": [1.5]})
    with pytest.raises(TypeError, match=r"values must be numbers"):
        load_sweep(config_file, {"size_distribution.r_eff_um": ["big"]})


def test_points_parsed_by_section_equal_whole_parses(config_file):
    """parse_points validates a point that differs from the first only in its
    size distribution by that section alone: the same configurations as
    parsing each point's whole text, with a non-size axis in the sweep too."""
    over = dict(OVER, **{"material.hematite_fraction": [0.0, 0.05]})
    spec = load_sweep(config_file, over)
    data = [spec.point_data(i) for i in spec.indices()]
    assert parse_points(data) == [parse_point(d) for d in data]


def test_sweep_table_in_toml_gives_the_axes(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(
        small_toml(
            '\n[sweep]\n"size_distribution.r_eff_um" = [1.0, 2.0]\n'
            "material.hematite_fraction = { start = 0.0, stop = 0.06, num = 3 }\n"
        ),
        encoding="utf-8",
    )
    spec = load_sweep(path)
    assert [a.key for a in spec.axes] == [
        "size_distribution.r_eff_um",
        "material.hematite_fraction",
    ]
    assert spec.axes[1].values == (0.0, 0.03, 0.06)
    point = parse_point(spec.point_data((1, 2)))
    assert point.size_distribution.build().r_eff_um == 2.0
    assert point.material.parameters["hematite_fraction"] == 0.06


def test_independent_points_equal_single_builds_to_the_bit(cluster, config_file, tmp_path):
    over = {"size_distribution.r_eff_um": [0.8, 1.6], "material.host_index.n": [1.45, 1.5]}
    with distributed.Client(cluster) as client:
        ds = sweep(
            config_file, over, out=tmp_path / "i.zarr", client=client, shared=False, progress=None
        ).load()
    assert ds.attrs["method"] == "independent"
    spec = load_sweep(config_file, over)
    for index in spec.indices():
        table = build_table(parse_point(spec.point_data(index)))
        point = ds.isel({a.key: i for a, i in zip(spec.axes, index)})
        assert np.array_equal(point.phase.values, table.phase)
        assert np.array_equal(point.cext_um2.values, table.cross_sections.cext_um2)
        assert np.array_equal(point.g.values, table.g)
        record = json.loads(str(point.provenance.values))
        assert record["input_hash"] == table.provenance.input_hash


def test_shared_sweep_is_within_the_error_estimates_of_single_builds(reference, config_file):
    ds = xr.open_zarr(reference).load()
    assert ds.attrs["method"] == "shared"
    assert ds.phase.dims == (*OVER, "wavelength_nm", "theta_deg")
    spec = load_sweep(config_file, OVER)
    for index in spec.indices():
        table = build_table(parse_point(spec.point_data(index)))
        point = ds.isel({a.key: i for a, i in zip(spec.axes, index)})
        bound = point.error_estimate.values + table.quadrature.error_estimate
        assert np.all(np.max(np.abs(point.phase.values / table.phase - 1.0), axis=1) <= bound)
        cross = (
            point.cross_section_error_estimate.values
            + table.quadrature.cross_section_error_estimate
        )
        assert np.all(np.abs(point.cext_um2.values / table.cross_sections.cext_um2 - 1.0) <= cross)
        assert np.all(np.abs(point.g.values - table.g) <= cross)
        assert json.loads(str(point.provenance.values))["input_hash"] == table.provenance.input_hash


# ---------------------------------------------------------------- reliability on Dask


def test_rerun_recomputes_nothing_and_a_lost_chunk_only(reference, config_file, cluster, tmp_path):
    before = store_bytes(reference)
    calls: list[tuple[int, int]] = []
    with distributed.Client(cluster) as client:
        sweep(
            config_file,
            OVER,
            out=reference,
            client=client,
            chunk_wavelengths=1,
            progress=lambda done, total: calls.append((done, total)),
        )
        assert calls == [(16, 16)]  # everything was done before the first report
        assert store_bytes(reference) == before
        copy = tmp_path / "copy.zarr"
        import shutil

        shutil.copytree(reference, copy)
        (copy / "sweep-done" / "0.0.2").unlink()  # as if stopped before this marker
        calls.clear()
        sweep(
            config_file,
            OVER,
            out=copy,
            client=client,
            chunk_wavelengths=1,
            progress=lambda done, total: calls.append((done, total)),
        )
    assert calls == [(12, 16), (16, 16)]
    assert store_bytes(copy) == before
    # The recomputed chunk's marker: its work, its wall time and the CPU time
    # of its thread, which cannot exceed the wall time.
    marker = json.loads((copy / "sweep-done" / "0.0.2").read_text())
    assert marker["spheres_computed"] > 0
    assert 0.0 < marker["cpu_seconds"] <= marker["seconds"] + 0.01


def counting_writes(monkeypatch) -> list[str]:
    """The chunks that this process writes (``run._write_chunk``), recorded."""
    from dustoptics.sweep import run

    written: list[str] = []
    write = run._write_chunk

    def spy(store, region, name, result):
        written.append(name)
        write(store, region, name, result)

    monkeypatch.setattr(run, "_write_chunk", spy)
    return written


@settings(max_examples=50, deadline=None)
@given(n=st.integers(min_value=0, max_value=200))
def test_spread_order_is_a_permutation_starting_at_both_ends(n):
    from dustoptics.sweep.run import _spread

    order = _spread(n)
    assert sorted(order) == list(range(n))
    assert order[:2] == [0, n - 1][: min(n, 2)]


def test_spread_order_halves_the_widest_gap_first():
    from dustoptics.sweep.run import _spread

    assert _spread(5) == [0, 4, 2, 1, 3]
    assert _spread(9)[:5] == [0, 8, 4, 2, 6]


def test_chunks_go_out_longest_first_as_far_as_known():
    """Before any chunk has finished, chunks go in the spread order; after,
    the waiting chunk whose interpolated time is longest goes next."""
    from dustoptics.sweep.run import _Order

    order = _Order([(0, w) for w in range(10)] + [(1, w) for w in range(10)])
    first = [order.next() for _ in range(4)]
    assert [c[-1] for c in first] == [0, 0, 9, 9]  # both blocks' ends
    order.finished((0, 0), 1.0)
    order.finished((0, 9), 10.0)
    # Block 0: interpolated 1 + w; block 1 knows nothing: the mean, 5.5.
    assert order.next() == (0, 8)
    order.finished((1, 0), 9.0)
    order.finished((1, 9), 0.5)
    # Block 1 now: 9 at w = 0 falling to 0.5 at w = 9, so w = 1 is longest (8.06).
    assert order.next() == (1, 1)
    remaining = [order.next() for _ in range(14)]
    assert order.next() is None and None not in remaining
    assert len(set(remaining)) == 14


@settings(max_examples=40, deadline=None)
@given(
    n_blocks=st.integers(min_value=1, max_value=4),
    n_w=st.integers(min_value=1, max_value=12),
    times=st.lists(st.floats(min_value=0.01, max_value=10.0), min_size=48, max_size=48),
    seed=st.integers(min_value=0, max_value=2**16),
)
def test_each_chunk_chosen_is_the_longest_estimate_by_brute_force(n_blocks, n_w, times, seed):
    """Whatever finishes when, the chunk chosen is the one with the longest
    time estimated from scratch (linear interpolation between a block's
    nearest finished chunks, their value beyond them, the mean of all
    finished for a block with none; then the spread order)."""
    import random

    from dustoptics.sweep.run import _Order, _spread

    def estimate(known, c):
        mine = {w: t for (b, w), t in known.items() if b == c[0]}
        if not mine:
            return sum(known.values()) / len(known) if known else 0.0
        return float(np.interp(c[1], sorted(mine), [mine[w] for w in sorted(mine)]))

    chunks = [(b, w) for b in range(n_blocks) for w in range(n_w)]
    rank = {w: i for i, w in enumerate(_spread(n_w))}
    order = _Order(chunks)
    pending, known = set(chunks), {}
    rng = random.Random(seed)
    running = []
    while pending or running:
        if running and (not pending or rng.random() < 0.5):
            done = running.pop(rng.randrange(len(running)))
            known[done] = times[done[0] * 12 + done[1]]
            order.finished(done, known[done])
            continue
        best = max((estimate(known, c), -rank[c[1]]) for c in pending)
        chosen = order.next()
        assert chosen in pending and (estimate(known, chosen), -rank[chosen[1]]) == best
        pending.remove(chosen)
        running.append(chosen)
    assert order.next() is None


def test_local_cluster_workers_run_with_its_settings(cluster):
    """The workers of the cluster a sweep starts got its Dask settings (the
    nanny passes the configuration to the processes it starts)."""
    import dask

    from dustoptics.sweep.run import _LOCAL_CLUSTER_CONFIG

    def settings() -> dict:
        return {key: dask.config.get(key) for key in _LOCAL_CLUSTER_CONFIG}

    with distributed.Client(cluster) as client:
        seen = client.run(settings)
    assert len(seen) == 2
    for values in seen.values():
        assert values == _LOCAL_CLUSTER_CONFIG


def test_workers_that_see_the_store_write_their_chunks(
    reference, config_file, cluster, tmp_path, monkeypatch
):
    """Worker processes of a local cluster see the store, so the client
    writes nothing itself; the store equals the reference and the run's
    token is gone."""
    written = counting_writes(monkeypatch)
    out = tmp_path / "w.zarr"
    with distributed.Client(cluster) as client:
        sweep(config_file, OVER, out=out, client=client, chunk_wavelengths=1, progress=None)
    assert written == []
    assert store_bytes(out) == store_bytes(reference)
    assert sorted(p.name for p in (out / "sweep-done").iterdir()) == sorted(
        f"0.0.{w}" for w in range(len(WAVELENGTHS))
    )


def test_workers_that_do_not_see_the_store_return_their_chunks(
    reference, config_file, tmp_path, monkeypatch
):
    """Where workers do not see the client's store (another machine, no
    shared filesystem), the client writes every chunk: the same bytes.  The
    workers are threads of this process here, so that they see the patch."""
    from dustoptics.sweep import run

    written = counting_writes(monkeypatch)
    monkeypatch.setattr(run, "_sees", lambda store, token: False)
    out = tmp_path / "c.zarr"
    with (
        local_cluster(1, threads=2, processes=False) as local,
        distributed.Client(local) as client,
    ):
        sweep(config_file, OVER, out=out, client=client, chunk_wavelengths=1, progress=None)
    assert sorted(written) == [f"0.0.{w}" for w in range(len(WAVELENGTHS))]
    assert store_bytes(out) == store_bytes(reference)


def test_chunks_written_out_of_the_clients_sight_are_an_error(config_file, tmp_path, monkeypatch):
    """A worker that reports a chunk written that the client's store does not
    hold (it wrote to another filesystem at the same path): the sweep fails
    and names the chunks, rather than return a store with holes."""
    from dustoptics.sweep import run

    monkeypatch.setattr(run, "_write_chunk", lambda store, region, name, result: None)
    with (
        local_cluster(1, processes=False) as local,
        distributed.Client(local) as client,
        pytest.raises(RuntimeError, match=r"chunks \['0\.0', '0\.1'\] finished"),
    ):
        sweep(
            config_file,
            {"size_distribution.r_eff_um": [0.8]},
            out=tmp_path / "h.zarr",
            client=client,
            chunk_wavelengths=2,
            progress=None,
        )


def test_worker_killed_mid_sweep_finishes_identically(reference, config_file, cluster, tmp_path):
    """A watcher kills (SIGKILL) the process of the first worker it sees busy
    with a task of the sweep; the sweep finishes and the store equals the
    undisturbed run's."""
    import threading
    import time

    killed: list[int] = []
    with distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        stop = threading.Event()

        def watch() -> None:
            deadline = time.monotonic() + 60
            while not stop.is_set() and time.monotonic() < deadline:
                busy = [w for w, keys in client.processing().items() if keys]
                if busy and busy[0] in pids:
                    os.kill(pids[busy[0]], signal.SIGKILL)
                    killed.append(pids[busy[0]])
                    return
                time.sleep(0.005)

        watcher = threading.Thread(target=watch)
        watcher.start()
        out = tmp_path / "killed.zarr"
        try:
            sweep(config_file, OVER, out=out, client=client, chunk_wavelengths=1, progress=None)
        finally:
            stop.set()
            watcher.join()
        client.wait_for_workers(2, timeout=60)
    assert killed, "no worker was seen busy"
    assert store_bytes(out) == store_bytes(reference)


def test_scheduler_address_gives_identical_bytes_and_workers_use_the_numba_cache(
    reference, config_file, cluster, tmp_path
):
    out = tmp_path / "address.zarr"
    sweep(
        config_file,
        OVER,
        out=out,
        client=cluster.scheduler_address,
        chunk_wavelengths=1,
        progress=None,
    )
    assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
    assert store_bytes(out) == store_bytes(reference)

    def cache_stats() -> dict[str, tuple[int, int]]:
        from dustoptics.sweep import shared

        return {
            name: (sum(f.stats.cache_hits.values()), sum(f.stats.cache_misses.values()))
            for name, f in (
                ("_cell_intensities", shared._cell_intensities),
                ("_cell_rows", shared._cell_rows),
            )
        }

    with distributed.Client(cluster) as client:
        for worker, stats in client.run(cache_stats).items():
            for name, (hits, misses) in stats.items():
                assert hits >= 1 and misses == 0, (worker, name, hits, misses)


def test_netcdf_output_and_cli(cluster, config_file, tmp_path):
    from dustoptics.cli import main

    text = small_toml('\n[sweep]\n"size_distribution.r_eff_um" = [1.0, 2.0]\n')
    path = tmp_path / "c.toml"
    path.write_text(text, encoding="utf-8")
    nc = tmp_path / "s.nc"
    code = main(
        ["sweep", str(path), "--out", str(nc), "--scheduler", cluster.scheduler_address, "--quiet"]
    )
    assert code == 0 and nc.is_file()
    assert not Path(str(nc) + ".zarr-partial").exists()
    ds = xr.open_dataset(nc, engine="h5netcdf")
    assert ds.phase.dims == ("size_distribution.r_eff_um", "wavelength_nm", "theta_deg")
    assert ds.phase.shape == (2, 4, 181)
    assert np.all(np.isfinite(ds.phase.values))
    bad = tmp_path / "bad.toml"
    bad.write_text(
        small_toml('\n[sweep]\n"size_distribution.v_eff" = [0.2, 0.6]\n'), encoding="utf-8"
    )
    assert main(["sweep", str(bad), "--out", str(tmp_path / "x.zarr"), "--quiet"]) == 1
    assert not (tmp_path / "x.zarr").exists()
    assert main(["sweep", str(path), "--out", str(tmp_path / "y.zarr"), "--workers", "0"]) == 2


# ---------------------------------------------------------------- failures and interrupts


def test_a_full_disk_on_a_worker_is_one_error_without_worker_tracebacks(
    config_file, tmp_path, monkeypatch, capfd, caplog
):
    """A chunk that fails on its worker (here: no space left while writing it) is
    raised by the sweep as the worker's OSError; Dask logs no "Compute Failed" with the
    worker's traceback (7 lines on stderr before the one-line error)."""
    import errno

    from dustoptics.sweep import run

    def full(store, region, name, result):
        raise OSError(errno.ENOSPC, "No space left on device", str(store))

    monkeypatch.setattr(run, "_write_chunk", full)
    with (
        local_cluster(1, threads=2, processes=False) as local,
        distributed.Client(local) as client,
        pytest.raises(OSError, match=r"No space left on device") as info,
    ):
        sweep(config_file, OVER, out=tmp_path / "full.zarr", client=client, progress=None)
    assert info.value.errno == errno.ENOSPC
    err = capfd.readouterr().err
    logged = [r.getMessage() for r in caplog.records if r.levelno >= 40]
    assert "Compute Failed" not in err and "Traceback" not in err, err
    assert not [m for m in logged if "Compute Failed" in m], logged


_INTERRUPTED = """
import os, signal, sys
from pathlib import Path
from dustoptics.sweep import sweep

if __name__ == "__main__":
    config, out, interrupt = sys.argv[1], sys.argv[2], sys.argv[3] == "interrupt"
    sent = []

    def progress(done, total):
        if interrupt and done and not sent:  # a Ctrl-C after the first chunk
            sent.append(done)
            os.killpg(os.getpgrp(), signal.SIGINT)

    try:
        sweep(config, {"size_distribution.r_eff_um": [0.8, 1.6]}, out=out, workers=1,
              chunk_wavelengths=1, progress=progress)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
    print("finished", file=sys.stderr)
"""


def test_ctrl_c_closes_the_cluster_quietly_and_a_resume_finishes_quietly(config_file, tmp_path):
    """A Ctrl-C (SIGINT to the whole process group, as a terminal sends it) during a
    sweep on a local cluster of worker processes: the sweep raises KeyboardInterrupt
    after closing the cluster, and no worker prints a traceback (each printed one).
    The finished chunks stay; a resume computes the rest and prints nothing either
    (no "Cannot close a running event loop")."""
    import subprocess
    import sys

    from dustoptics.sweep import verify_store
    from dustoptics.sweep.store import done_chunks, read_layout

    script = tmp_path / "interrupted.py"
    script.write_text(_INTERRUPTED, encoding="utf-8")
    out = tmp_path / "interrupted.zarr"

    def run(mode: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, str(script), str(config_file), str(out), mode],
            capture_output=True,
            text=True,
            timeout=300,
            start_new_session=True,  # its own process group: the SIGINT stays there
        )

    first = run("interrupt")
    assert (first.returncode, first.stderr.strip()) == (130, "interrupted"), first.stderr
    done = done_chunks(out, read_layout(out), repair=False)
    assert 1 <= len(done) < len(WAVELENGTHS)
    again = run("resume")
    assert (again.returncode, again.stderr.strip()) == (0, "finished"), again.stderr
    assert verify_store(out) == len(WAVELENGTHS)


def test_cli_refuses_a_point_beyond_the_budget_and_allow_large_reaches_the_library(
    tmp_path, monkeypatch, capsys
):
    """``dustoptics sweep`` with r_eff 2000 um: one line naming the point and
    ``--allow-large``, before any cluster starts; ``--allow-large`` is passed on."""
    import dustoptics.sweep
    from dustoptics.cli import main

    path = tmp_path / "big.toml"
    path.write_text(small_toml('\n[sweep]\n"size_distribution.r_eff_um" = [1.0, 2000.0]\n'))
    out = tmp_path / "big.zarr"
    assert main(["sweep", str(path), "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "r_eff_um = 2000.0" in err and "--allow-large" in err
    assert not out.exists()
    seen: dict = {}

    def recorded(config, **kwargs):
        seen.update(kwargs)
        return xr.Dataset()

    monkeypatch.setattr(dustoptics.sweep, "sweep", recorded)
    assert main(["sweep", str(path), "--out", str(out), "--allow-large", "--quiet"]) == 0
    assert seen["allow_large"] is True
