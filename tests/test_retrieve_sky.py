"""dustoptics.retrieve with sky observations: the sky's Jacobian against finite differences of
whole tables, known parameters recovered from a synthetic sky with seeded noise, the up-front
budget, the command line, and the fitted preset's sky inside the rovers' colour range."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import dustoptics as do
from dustoptics._validation import BudgetError
from dustoptics.retrieve import SkySettings, retrieve
from dustoptics.retrieve.sky import SkyModel, sky_progress, sky_samples

xr = pytest.importorskip("xarray")

WL = [450.0, 650.0]
#: Directions (view zenith, azimuth from the Sun) of the synthetic radiance: the zenith, the
#: almucantar, the rovers' view away from the Sun, the aureole's edge. [deg]
ZENITH = np.array([0.0, 50.0, 50.0, 60.0, 75.0])
AZIMUTH = np.array([0.0, 30.0, 120.0, 180.0, 90.0])
SUN_DEG = 40.0
#: Cheap skies (4 streams, 2 wavelengths and the reference): truth and fit share them.
CHEAP = SkySettings(n_streams=4, tol=1e-5)
DIST = do.ModifiedGamma(r_eff_um=0.8, v_eff=0.2)
TRUTH = {"hematite_fraction": 0.05, "r_eff_um": 0.8}


def _radiance(values: Any, sigma: Any) -> Any:
    dims = ("sun_elevation_deg", "wavelength_nm", "direction")
    return xr.Dataset(
        {
            "sky_radiance": (dims, values, {"optical_depth": 0.8, "ground_albedo": 0.25}),
            "sky_radiance_uncertainty": (dims, sigma),
        },
        coords={
            "sun_elevation_deg": [SUN_DEG],
            "wavelength_nm": WL,
            "view_zenith_deg": ("direction", ZENITH),
            "view_azimuth_deg": ("direction", AZIMUTH),
        },
    )


def _model(hematite_fraction: float, r_eff_um: float) -> dict[str, Any]:
    return {
        "refractive_index": do.mars_dust(hematite_fraction=hematite_fraction),
        "distribution": do.ModifiedGamma(r_eff_um=r_eff_um, v_eff=0.2),
    }


def _sky(obs: Any) -> SkyModel:
    var = obs["sky_radiance"]
    return SkyModel(sky_samples(var, np.asarray(obs["sky_radiance_uncertainty"].values)), CHEAP)


@pytest.mark.slow
def test_sky_jacobian_is_the_derivative_of_the_sky() -> None:
    """The chain rule (exact optics derivatives, the sky moved along them) against central
    differences of two whole Mie tables and their skies, for the hematite fraction."""
    obs = _radiance(np.ones((1, 2, 5)), np.ones((1, 2, 5)))
    sky = _sky(obs)
    names = ("hematite_fraction",)
    table = do.compute_optics(**_model(**TRUTH), wavelength_nm=sky.wavelength_nm, derivatives=names)
    base = sky.values(table, sky_progress(None))
    jac = sky.jacobian(table, base, names, np.array([1e-4]), sky_progress(None))[:, 0]
    h = 2e-3
    side = [
        sky.values(
            do.compute_optics(
                **_model(TRUTH["hematite_fraction"] + s, TRUTH["r_eff_um"]),
                wavelength_nm=sky.wavelength_nm,
            ),
            sky_progress(None),
        )
        for s in (h, -h)
    ]
    central = (side[0] - side[1]) / (2 * h)
    # Central differences of the whole chain: truncation O(h^2) and the series' tolerance
    # (1e-5 of the radiance, divided by h) bound their own error to about 1 %.
    assert np.all(np.abs(central) > 1e-3 * np.abs(base))  # the sky does depend on it
    np.testing.assert_allclose(jac, central, rtol=0.02)


@pytest.mark.slow
def test_recovers_known_parameters_from_a_noisy_sky() -> None:
    """Hematite fraction and r_eff from the radiance at 2 wavelengths x 5 directions with 1 %
    seeded noise, started 20 % and 12 % off: within 3 standard errors of the truth."""
    obs = _radiance(np.ones((1, 2, 5)), np.ones((1, 2, 5)))
    sky = _sky(obs)
    truth = sky.values(
        do.compute_optics(**_model(**TRUTH), wavelength_nm=sky.wavelength_nm),
        sky_progress(None),
    )
    # SkyModel orders the samples as the variable (wavelength, direction).
    truth = truth.reshape(1, 2, 5)
    rng = np.random.default_rng(11)
    sigma = 0.01 * truth
    obs = _radiance(truth + sigma * rng.standard_normal(truth.shape), sigma)
    bounds = {"hematite_fraction": (0.0, 0.2), "r_eff_um": (0.3, 2.0)}
    fit = retrieve(
        obs,
        model=_model(0.06, 0.9),
        parameters=tuple(TRUTH),
        bounds=bounds,
        sky=CHEAP,
        max_iterations=12,
        tolerance=1e-3,
    )
    assert fit.converged, fit.message
    for p, true in TRUTH.items():
        assert abs(fit.value(p) - true) <= 3.0 * fit.standard_error(p), (p, fit.value(p))
        assert fit.standard_error(p) < 0.1 * (bounds[p][1] - bounds[p][0])
    assert fit.residuals.size == len(fit.labels) == 10
    assert fit.labels[0].startswith("sky_radiance@sun40deg,450nm")
    # chi^2 of 10 - 2 degrees of freedom: inside its 0.1 % .. 99.9 % range.
    assert 0.9 < fit.chi_square < 26.1
    assert fit.sky_solves >= fit.function_evaluations
    assert fit.history_values.shape[1] == 2
    np.testing.assert_array_equal(fit.history_values[0], [0.06, 0.9])


def test_sky_observations_are_checked_before_any_work() -> None:
    obs = _radiance(np.ones((1, 2, 5)), np.ones((1, 2, 5)))
    bounds = {"hematite_fraction": (0.0, 0.2)}
    kwargs: dict[str, Any] = {
        "model": _model(0.03, 0.8),
        "parameters": ("hematite_fraction",),
        "bounds": bounds,
    }
    no_scene = obs.copy(deep=True)
    no_scene["sky_radiance"].attrs = {}
    with pytest.raises(ValueError, match="needs the attribute 'optical_depth'"):
        retrieve(no_scene, **kwargs)
    bad = obs.copy(deep=True)
    bad["sky_radiance"].attrs["ground_albedo"] = 1.5
    with pytest.raises(ValueError, match=r"ground_albedo must be within \[0, 1\]"):
        retrieve(bad, **kwargs)
    chroma = xr.Dataset(
        {"sky_chromaticity": (("sun_elevation_deg", "chromaticity"), [[0.4, 0.38]])},
        coords={"sun_elevation_deg": [30.0], "chromaticity": ["u", "v"]},
    )
    chroma["sky_chromaticity"].attrs = {"optical_depth": 0.5, "uncertainty": 0.003}
    with pytest.raises(ValueError, match=r"chromaticity = \['x', 'y'\]"):
        retrieve(chroma, **kwargs)
    with pytest.raises(ValueError, match="must have dimensions"):
        retrieve(obs.rename({"direction": "view"}), **kwargs)
    with pytest.raises(ValueError, match="n_streams must be an integer in"):
        SkySettings(n_streams=1)
    with pytest.raises(TypeError, match="sky must be a SkySettings"):
        retrieve(obs, sky={"n_streams": 4}, **kwargs)  # type: ignore[arg-type]


def test_the_sky_solves_are_bounded_up_front() -> None:
    """Too many sky solves are refused after the start's table, before any sky is solved."""
    obs = _radiance(np.ones((1, 2, 5)), np.ones((1, 2, 5)))
    seen: list[Any] = []
    with pytest.raises(BudgetError, match=r"at most 20002 skies.*allow_large=True"):
        retrieve(
            obs,
            model=_model(0.03, 0.8),
            parameters=("hematite_fraction",),
            bounds={"hematite_fraction": (0.0, 0.2)},
            sky=CHEAP,
            max_iterations=10000,  # the optics' tables within their budget, the skies not
            progress=lambda k, chi: seen.append(k),
        )
    assert seen == []  # no evaluation finished: no sky solved


@pytest.mark.slow
def test_command_line_fits_a_sky_file(tmp_path: Any, capsys: pytest.CaptureFixture[str]) -> None:
    """dustoptics retrieve with a sky_radiance file: the library's numbers, progress with the
    sky solves' estimate on stderr; beyond the budget exit 1 with the message, no traceback."""
    import json

    from dustoptics.cli import main

    obs = _radiance(np.ones((1, 2, 5)), np.ones((1, 2, 5)))
    sky = _sky(obs)
    truth = sky.values(
        do.compute_optics(**_model(**TRUTH), wavelength_nm=sky.wavelength_nm),
        sky_progress(None),
    ).reshape(1, 2, 5)
    obs = _radiance(truth, 0.01 * truth)
    path = tmp_path / "sky.nc"
    obs.to_netcdf(path, engine="h5netcdf")
    config = tmp_path / "dust.toml"
    config.write_text(
        'name = "start"\ndescription = "a start for the fit"\n'
        '[material]\nmodel = "mars_dust"\nhematite_fraction = 0.04\n'
        '[size_distribution]\nmodel = "modified_gamma"\nr_eff_um = 0.8\nv_eff = 0.2\n',
        encoding="utf-8",
    )
    out = tmp_path / "fit.json"
    argv = [
        "retrieve", str(path), "--model", str(config), "--fit", "hematite_fraction=0:0.2",
        "--sky-streams", "4", "--sky-tol", "1e-5", "--max-iterations", "1", "--out", str(out),
    ]  # fmt: skip
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "sky solves" in captured.out and "hematite_fraction" in captured.out
    assert "retrieve: at most" in captured.err and "evaluation 1: chi-square" in captured.err
    record = json.loads(out.read_text(encoding="utf-8"))
    from dustoptics.models.files import load_config

    direct = retrieve(
        obs, model=load_config(config), parameters=["hematite_fraction"],
        bounds={"hematite_fraction": (0.0, 0.2)}, sky=CHEAP, max_iterations=1,
    )  # fmt: skip
    assert record["values"] == direct.values.tolist()
    assert record["sky_solves"] == direct.sky_solves
    argv = argv[:-2] + ["--max-iterations", "20000"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "beyond the budget" in err and "--allow-large" in err and "Traceback" not in err
    assert main(argv[:-2] + ["--sky-streams", "1"]) == 2
    assert "n_streams must be an integer" in capsys.readouterr().err


@pytest.mark.slow
def test_the_fitted_preset_puts_the_rovers_sky_inside_the_mer_range() -> None:
    """The preset mer-sky-fit, recomputed as ``sky compare`` computes its rover table (the
    preset's Mie table on the comparison's grid, the renderer's defaults: 20 streams,
    tolerance 1e-4), at the fit's scene: inside the range."""
    from dustoptics.models import presets
    from dustoptics.sky import Medium
    from dustoptics.sky.compare import AWAY_FROM_SUN, MER_SKY_CHROMATICITY, mars_sky_atmosphere
    from dustoptics.sky.scene import sky_radiance

    assert "mer-sky-fit" in presets.list_presets()
    config = presets.load_preset("mer-sky-fit")
    assert {s.name for s in config.sources} >= {"wolff2009", "bell2006"}
    medium = Medium.from_atmosphere(mars_sky_atmosphere("mer-sky-fit", optical_depth=0.5))
    sky = sky_radiance(
        medium,
        sun_elevation_deg=30.0,
        ground_albedo=0.2,
        view_zenith_deg=np.array([59.0, 60.0, 61.0]),
        azimuth_step_deg=45.0,
    )
    x, y = sky.chromaticity(sky.at(**AWAY_FROM_SUN)).tolist()
    (x0, x1), (y0, y1) = MER_SKY_CHROMATICITY["x"], MER_SKY_CHROMATICITY["y"]
    assert x0 <= x <= x1 and y0 <= y <= y1, (x, y)
