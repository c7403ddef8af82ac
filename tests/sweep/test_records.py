"""Sweeps that ask for the scattering matrix and the expansion coefficients.

Each stored value is compared with :func:`dustoptics.compute_optics` at the same
point to the bit: such a sweep builds every point on its own (the shared solver
computes the phase function only), each wavelength is refined on its own whatever
block it is computed in, and the store holds float64, so nothing may differ.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from _sweeps import small_toml

from dustoptics import _validation
from dustoptics._validation import BudgetError
from dustoptics.models.compute import build_table
from dustoptics.models.config import ConfigError, parse_config
from dustoptics.scattering.optics import compute_optics
from dustoptics.sweep.spec import load_sweep, parse_point

distributed = pytest.importorskip(
    "distributed", reason="needs the 'sweep' extra (dask[distributed])"
)
xr = pytest.importorskip("xarray", reason="needs the 'sweep' extra (xarray)")
pytest.importorskip("zarr", reason="needs the 'sweep' extra (zarr)")
pytest.importorskip("h5netcdf", reason="needs the 'sweep' extra (h5netcdf)")

from dustoptics.sweep import local_cluster, point_table, sweep  # noqa: E402
from dustoptics.sweep import run as sweep_run  # noqa: E402

#: Two points, two wavelengths, 37 angles: small and fast.
OVER = {"size_distribution.r_eff_um": [0.4, 0.8]}
ORDER = 12
MATRIX = ("f12", "f33", "f34", "matrix_error_estimate")
EXPANSION = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2", "expansion_error_estimate")


def config_text(options: str) -> str:
    text = small_toml(wavelengths_nm=[450.0, 650.0], n_theta=37)
    text = text.replace("rtol = 1e-4 ", "rtol = 1e-3 ")
    assert "rtol = 1e-3 " in text
    return text.replace("n_theta = 37", f"n_theta = 37\n{options}")


@pytest.fixture(scope="module")
def client():
    with local_cluster(1, processes=False) as cluster, distributed.Client(cluster) as c:
        yield c


def run(tmp_path: Path, options: str, client, out: str = "s.zarr"):
    path = tmp_path / "c.toml"
    path.write_text(config_text(options), encoding="utf-8")
    ds = sweep(
        path, OVER, out=tmp_path / out, client=client, chunk_wavelengths=1, progress=None
    ).load()
    return path, ds


def reference(config_path: Path, r_eff_um: float):
    """``compute_optics`` at the point, with the configuration's settings."""
    spec = load_sweep(config_path, {"size_distribution.r_eff_um": [r_eff_um]})
    config = parse_point(spec.point_data((0,)))
    optics = config.optics
    table = compute_optics(
        config.material.build(),
        config.size_distribution.build(),
        config.wavelengths_nm,
        config.theta_deg,
        rtol=optics.rtol,
        weighting=optics.weighting,
        cross_section_rtol=optics.cross_section_rtol,
        polarization=optics.polarization,
        expansion=False if optics.expansion is None else optics.expansion,
        workers=1,
    )
    return config, table


OPTIONS = {
    "matrix": "polarization = true",
    "expansion": f"expansion = {ORDER}",
    "both": f"polarization = true\nexpansion = {ORDER}",
}


@pytest.mark.parametrize("case", sorted(OPTIONS))
def test_stored_records_equal_compute_optics_to_the_bit(case, client, tmp_path):
    path, ds = run(tmp_path, OPTIONS[case], client)
    matrix, expansion = case in ("matrix", "both"), case in ("expansion", "both")
    assert ds.attrs["method"] == "independent"
    assert all((k in ds) == matrix for k in MATRIX)
    assert all((k in ds) == expansion for k in EXPANSION)
    assert ("order" in ds.dims) == expansion
    if expansion:
        assert ds.sizes["order"] == ORDER + 1
        assert ds.alpha1.dims == ("size_distribution.r_eff_um", "wavelength_nm", "order")
    for r_eff in OVER["size_distribution.r_eff_um"]:
        config, want = reference(path, r_eff)
        got = point_table(ds, {"size_distribution.r_eff_um": r_eff})
        assert np.array_equal(got.phase, want.phase)
        assert np.array_equal(got.g, want.g)
        assert np.array_equal(got.cross_sections.cext_um2, want.cross_sections.cext_um2)
        assert np.array_equal(got.quadrature.error_estimate, want.quadrature.error_estimate)
        assert (got.matrix is None) == (not matrix) and (got.expansion is None) == (not expansion)
        for record, keys in ((got.matrix, MATRIX), (got.expansion, EXPANSION)):
            for key in keys if record is not None else ():
                reference_record = want.matrix if keys is MATRIX else want.expansion
                assert np.array_equal(getattr(record, key), getattr(reference_record, key)), key
        # Provenance records exactly what was computed: the build's inputs, no more.
        inputs = got.provenance.inputs["optics"]
        assert inputs.get("polarization", False) == matrix
        assert inputs.get("expansion") == (ORDER if expansion else None)
        assert got.provenance.input_hash == build_table(config).provenance.input_hash
    if expansion:
        assert np.array_equal(ds.alpha1.isel(order=0).values, np.ones((2, 2)))


def test_netcdf_round_trip_keeps_every_record(client, tmp_path):
    _, zarr_ds = run(tmp_path, OPTIONS["both"], client)
    run(tmp_path, OPTIONS["both"], client, out="s.nc")
    with xr.open_dataset(tmp_path / "s.nc", engine="h5netcdf") as reread:
        for key in ("phase", *MATRIX, *EXPANSION):
            assert reread[key].dims == zarr_ds[key].dims
            assert np.array_equal(reread[key].values, zarr_ds[key].values), key
        a = point_table(reread, {"size_distribution.r_eff_um": 0.8})
    b = point_table(zarr_ds, {"size_distribution.r_eff_um": 0.8})
    for key in MATRIX:
        assert np.array_equal(getattr(a.matrix, key), getattr(b.matrix, key))
    for key in EXPANSION:
        assert np.array_equal(getattr(a.expansion, key), getattr(b.expansion, key))
    assert a.provenance.input_hash == b.provenance.input_hash


def test_every_order_is_refused_naming_the_key_before_any_work(tmp_path, monkeypatch):
    path = tmp_path / "c.toml"
    path.write_text(config_text("expansion = true"), encoding="utf-8")
    parse_config(path.read_text(encoding="utf-8"))  # a valid configuration for a build

    def no_work(*args, **kwargs):
        raise AssertionError("a chunk was computed")

    monkeypatch.setattr(sweep_run, "compute_chunk", no_work)
    with pytest.raises(ConfigError, match=r"optics\.expansion: a sweep cannot take true"):
        sweep(path, OVER, out=tmp_path / "s.zarr", workers=1, progress=None)
    assert not (tmp_path / "s.zarr").exists()


def test_polarization_is_a_mie_option_of_the_configuration():
    text = config_text("polarization = true")
    hybrid = text.replace('model = "mie"', 'model = "hybrid"')
    with pytest.raises(ConfigError, match=r"optics\.polarization: is available for phase"):
        parse_config(hybrid)
    with pytest.raises(ConfigError, match=r"optics\.polarization: must be true or false"):
        parse_config(text.replace("polarization = true", "polarization = 1"))
    assert parse_config(text).optics.to_inputs()["polarization"] is True
    assert "polarization" not in parse_config(config_text("")).optics.to_inputs()


@pytest.mark.parametrize("case", ["", "matrix", "expansion", "both"])
def test_chunk_memory_estimate_counts_the_extra_arrays(case, tmp_path, monkeypatch):
    path = tmp_path / "c.toml"
    path.write_text(config_text(OPTIONS.get(case, "")), encoding="utf-8")
    spec, _, configs, costs = sweep_run._load(path, OVER)
    layout = sweep_run._layout(spec, 2, 1, 400)
    template = sweep_run._template(spec, configs, layout, "independent")
    n_theta = 37
    values = n_theta + 6
    values += (3 * n_theta + 1) if case in ("matrix", "both") else 0
    values += (6 * (ORDER + 1) + 1) if case in ("expansion", "both") else 0
    monkeypatch.setattr(_validation, "MEMORY_BUDGET_BYTES", 0)
    with pytest.raises(BudgetError, match=rf"a chunk of the sweep .* x {values} values"):
        sweep_run._check_cost(
            spec,
            costs,
            layout,
            template,
            store=tmp_path / "s.zarr",
            in_memory=False,
            allow_large=False,
        )
    provenance = [json.loads(str(v)) for v in template.provenance.values]
    assert all(
        ("expansion" in p["inputs"]["optics"]) == (case in ("expansion", "both"))
        for p in provenance
    )


def test_the_progress_line_fits_80_columns_at_a_million_point_wavelengths():
    import io

    from dustoptics.sweep.run import _Progress

    stream = io.StringIO()
    progress = _Progress(stream, None, 1_000_000, 0)
    progress.start -= 86_399.0  # a day, less a second: the longest elapsed and ETA figures
    progress.add(1)
    lines = stream.getvalue().splitlines()
    assert lines[-1].startswith("sweep [") and "1/1000000 point-wavelengths" in lines[-1]
    assert max(map(len, lines)) <= 80, lines
