"""dustoptics.retrieve: known parameters recovered from synthetic observations with
seeded noise, within the returned standard errors; the boundary's checks."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import dustoptics as do
from dustoptics.retrieve import retrieve

xr = pytest.importorskip("xarray")

WL = np.array([400.0, 500.0, 600.0, 750.0, 900.0])
THETA = np.array([5.0, 30.0, 90.0, 150.0])
TRUTH = {"r_eff_um": 0.8, "v_eff": 0.15, "k": 0.004}


def _observations(seed: int) -> tuple[Any, dict[str, float]]:
    """ssa, extinction ratio to 500 nm and phase samples at two wavelengths of the
    true dust, with Gaussian noise of the stated uncertainties (seeded)."""
    t = do.compute_optics(
        complex(1.5, TRUTH["k"]),
        do.ModifiedGamma(r_eff_um=TRUTH["r_eff_um"], v_eff=TRUTH["v_eff"]),
        WL,
        THETA,
    )
    rng = np.random.default_rng(seed)
    assert t.cross_sections is not None
    sigma = {"ssa": 2e-3, "ratio": 5e-3, "phase": 0.02}
    ssa = t.ssa + sigma["ssa"] * rng.standard_normal(WL.size)
    ratio = t.cross_sections.cext_um2 / t.cross_sections.cext_um2[1]
    ratio = ratio + sigma["ratio"] * ratio * rng.standard_normal(WL.size)
    phase = t.phase[[1, 3]]
    phase_sigma = sigma["phase"] * phase
    phase = phase + phase_sigma * rng.standard_normal(phase.shape)
    ds = xr.Dataset(
        {
            "ssa": ("wavelength_nm", ssa, {"uncertainty": sigma["ssa"]}),
            "extinction_ratio": (
                "wavelength_nm",
                ratio,
                {"reference_wavelength_nm": 500.0},
            ),
            "extinction_ratio_uncertainty": ("wavelength_nm", sigma["ratio"] * ratio),
        },
        coords={"wavelength_nm": WL},
    )
    ph = xr.Dataset(
        {
            "phase": (("wavelength_nm", "theta_deg"), phase),
            "phase_uncertainty": (("wavelength_nm", "theta_deg"), phase_sigma),
        },
        coords={"wavelength_nm": WL[[1, 3]], "theta_deg": THETA},
    )
    return xr.merge([ds, ph], join="outer"), sigma


START = {
    "refractive_index": 1.5 + 0.01j,
    "distribution": do.ModifiedGamma(r_eff_um=0.5, v_eff=0.25),
}
BOUNDS = {"r_eff_um": (0.1, 3.0), "v_eff": (0.02, 0.45), "k": (0.0, 0.05)}


def test_recovers_known_parameters_within_its_standard_errors() -> None:
    obs, _ = _observations(seed=7)
    fit = retrieve(obs, model=START, parameters=("r_eff_um", "v_eff", "k"), bounds=BOUNDS)
    assert fit.converged, fit.message
    for p, true in TRUTH.items():
        assert abs(fit.value(p) - true) <= 3.0 * fit.standard_error(p), (
            p,
            fit.value(p),
            true,
            fit.standard_error(p),
        )
        # The data constrain every parameter: far tighter than the bounds.
        assert fit.standard_error(p) < 0.1 * (BOUNDS[p][1] - BOUNDS[p][0])
    n_obs = 2 * WL.size + 2 * THETA.size
    assert fit.residuals.size == len(fit.labels) == n_obs
    # chi^2 of n_obs - 3 degrees of freedom: well inside its 0.1 % .. 99.9 % range.
    assert 0.2 * n_obs < fit.chi_square < 2.5 * n_obs
    assert np.allclose(fit.covariance, fit.covariance.T)
    assert fit.model["distribution"].r_eff_um == fit.value("r_eff_um")
    # Deterministic: the same observations give the same numbers, bit for bit.
    again = retrieve(obs, model=START, parameters=("r_eff_um", "v_eff", "k"), bounds=BOUNDS)
    assert np.array_equal(again.values, fit.values)
    assert np.array_equal(again.covariance, fit.covariance)


def test_a_prior_pulls_and_tightens() -> None:
    obs, _ = _observations(seed=7)
    obs = obs[["ssa"]]
    free = retrieve(
        obs, model=START, parameters=("r_eff_um", "k"), bounds=BOUNDS, max_iterations=30
    )
    held = retrieve(
        obs,
        model=START,
        parameters=("r_eff_um", "k"),
        bounds=BOUNDS,
        priors={"r_eff_um": (0.8, 0.01)},
        max_iterations=30,
    )
    assert held.standard_error("r_eff_um") < 0.01 and held.labels[-1] == "prior:r_eff_um"
    assert held.standard_error("r_eff_um") < free.standard_error("r_eff_um")
    assert abs(held.value("r_eff_um") - 0.8) < 3 * 0.01


def test_boundary_checks_come_before_any_work() -> None:
    obs, _ = _observations(seed=1)
    with pytest.raises(ValueError, match="unknown parameter 'reff'.*'r_eff_um', 'v_eff'"):
        retrieve(obs, model=START, parameters=("reff",), bounds={"reff": (0, 1)})
    with pytest.raises(ValueError, match="bounds must give"):
        retrieve(obs, model=START, parameters=("r_eff_um", "k"), bounds={"k": (0, 1)})
    with pytest.raises(ValueError, match="hold the model's values"):
        retrieve(obs, model=START, parameters=("k",), bounds={"k": (0.02, 0.05)})
    with pytest.raises(ValueError, match="uncertainty"):
        retrieve(
            xr.Dataset({"ssa": ("wavelength_nm", [0.9])}, coords={"wavelength_nm": [500.0]}),
            model=START,
            parameters=("k",),
            bounds=BOUNDS,
        )
    with pytest.raises(ValueError, match="variables must be among"):
        retrieve(
            xr.Dataset({"albedo": ("wavelength_nm", [0.9])}, coords={"wavelength_nm": [500.0]}),
            model=START,
            parameters=("k",),
            bounds=BOUNDS,
        )
    with pytest.raises(ValueError, match="refractive_index must be a number"):
        retrieve(
            obs,
            model={**START, "refractive_index": do.mars_dust()},
            parameters=("k",),
            bounds=BOUNDS,
        )


@pytest.mark.parametrize(
    ("bounds", "match"),
    [
        ({"r_eff_um": (-1.0, 3.0)}, r"lower bound r_eff_um = -1.0 is outside the model's domain"),
        ({"v_eff": (0.02, 5.0)}, r"upper bound v_eff = 5.0 is outside the model's domain"),
        ({"k": (-0.01, 0.05)}, r"lower bound of 'k' must be >= 0"),
        ({"n": (0.0, 2.0)}, r"lower bound of 'n' must be > 0"),
        ({"r_eff_um": (0.1, float("inf"))}, r"bounds must be finite"),
        ({"k": (float("nan"), 0.05)}, r"bounds must be finite"),
    ],
)
def test_bounds_where_the_model_cannot_go_are_refused(bounds: Any, match: str) -> None:
    """The fit may step onto its bounds: one the model cannot take is refused up front."""
    obs, _ = _observations(seed=1)
    model = {**START, "refractive_index": 1.5 + 0.01j}
    with pytest.raises(ValueError, match=match):
        retrieve(obs, model=model, parameters=tuple(bounds), bounds=bounds)


def test_a_table_beyond_the_budget_at_the_upper_bounds_is_refused_before_any(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """r_eff_um up to 3 mm: the table there is beyond compute_optics' budget, refused
    before the start's table is computed (compute_optics is not called); allow_large
    lets it through to the fit."""
    from dustoptics._validation import BudgetError
    from dustoptics.retrieve import fit as fit_module

    calls = []

    def no_tables(*args: Any, **kwargs: Any) -> None:
        calls.append(kwargs)
        raise RuntimeError("no table may be computed")

    monkeypatch.setattr(fit_module, "compute_optics", no_tables)
    obs, _ = _observations(seed=1)
    bounds = {"r_eff_um": (0.1, 3000.0)}
    with pytest.raises(BudgetError, match=r"at the upper bounds \{'r_eff_um': 3000.0\}"):
        retrieve(obs, model=START, parameters=("r_eff_um",), bounds=bounds)
    assert calls == []
    with pytest.raises(RuntimeError, match="no table may be computed"):
        retrieve(obs, model=START, parameters=("r_eff_um",), bounds=bounds, allow_large=True)
    assert calls[0]["allow_large"] is True


def test_hematite_fraction_of_mars_dust_through_the_mixing_rule() -> None:
    """The hematite fraction of Mars dust (Maxwell Garnett in n = 1.5) from its
    single-scattering albedo spectrum, 1e-3 noise, started from the default 3 %."""
    dist = do.ModifiedGamma(r_eff_um=0.6, v_eff=0.15)
    truth = do.compute_optics(do.mars_dust(hematite_fraction=0.05), dist, WL, [0.0, 180.0])
    rng = np.random.default_rng(3)
    ssa = truth.ssa + 1e-3 * rng.standard_normal(WL.size)
    obs = xr.DataArray(
        ssa,
        coords={"wavelength_nm": WL},
        dims="wavelength_nm",
        name="ssa",
        attrs={"uncertainty": 1e-3},
    )
    fit = retrieve(
        obs,
        model={"refractive_index": do.mars_dust(), "distribution": dist},
        parameters=("hematite_fraction",),
        bounds={"hematite_fraction": (0.0, 0.3)},
    )
    assert fit.converged
    assert abs(fit.value("hematite_fraction") - 0.05) <= 3.0 * fit.standard_error(
        "hematite_fraction"
    )
    assert fit.standard_error("hematite_fraction") < 0.005
    assert (
        fit.model["refractive_index"].name
        == do.mars_dust(hematite_fraction=fit.value("hematite_fraction")).name
    )


# ---------------------------------------------------------------- the command line


def test_command_line_fits_the_observations_in_a_file(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    """dustoptics retrieve OBS.nc --model CONFIG --fit ...: the same numbers as the
    library call, printed; the JSON result; usage errors exit 2 before any work."""
    import json

    from dustoptics.cli import main

    obs, _ = _observations(seed=7)
    obs = obs[["ssa", "extinction_ratio", "extinction_ratio_uncertainty"]].dropna("wavelength_nm")
    path = tmp_path / "obs.nc"
    obs.to_netcdf(path, engine="h5netcdf")
    config = tmp_path / "dust.toml"
    config.write_text(
        'name = "start"\ndescription = "a start for the fit"\n'
        '[material]\nmodel = "constant"\nn = 1.5\nk = 0.01\n'
        '[size_distribution]\nmodel = "modified_gamma"\nr_eff_um = 0.5\nv_eff = 0.15\n',
        encoding="utf-8",
    )
    out = tmp_path / "fit.json"
    argv = [
        "retrieve", str(path), "--model", str(config),
        "--fit", "r_eff_um=0.1:3", "--fit", "k=0:0.05", "--out", str(out),
    ]  # fmt: skip
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "converged" in captured.out and "r_eff_um" in captured.out
    assert "chi-square" in captured.err  # progress, one line per table
    record = json.loads(out.read_text(encoding="utf-8"))
    from dustoptics.models.files import load_config

    direct = retrieve(
        obs, model=load_config(config), parameters=["r_eff_um", "k"],
        bounds={"r_eff_um": (0.1, 3.0), "k": (0.0, 0.05)},
    )  # fmt: skip
    assert record["values"] == direct.values.tolist()
    assert record["parameters"] == ["r_eff_um", "k"]
    # The file exists now: refused without --force, before any table.
    assert main(argv) == 1
    assert "already exist" in capsys.readouterr().err
    assert main(["retrieve", str(path), "--model", str(config), "--fit", "k=0"]) == 2
    assert "--fit must be PARAM=LO:HI" in capsys.readouterr().err
    twice = ["--fit", "k=0:1", "--fit", "k=0:0.5"]
    assert main(["retrieve", str(path), "--model", str(config), *twice]) == 2
    assert "--fit k is given twice" in capsys.readouterr().err


def test_command_line_refuses_files_that_are_not_observations(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    """A directory, a FIFO, text and a damaged HDF5 header: one line each, exit 1,
    before any table (the FIFO is never opened, so nothing blocks)."""
    import os

    from dustoptics.cli import main

    text = tmp_path / "text.nc"
    text.write_text("not netCDF\n", encoding="utf-8")
    damaged = tmp_path / "damaged.nc"
    damaged.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    fifo = tmp_path / "fifo.nc"
    os.mkfifo(fifo)
    expected = {
        tmp_path: "not a regular file",
        fifo: "not a regular file",
        text: "not a netCDF file of observations",
        damaged: "not a netCDF file of observations",
        tmp_path / "missing.nc": "no such file",
    }
    for path, message in expected.items():
        argv = ["retrieve", str(path), "--model", "hybrid", "--fit", "r_eff_um=0.5:3"]
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
    assert main(["retrieve", str(path), "--model", "no-such-preset", "--fit", "k=0:1"]) == 2
