"""Bevy's and OpenSpace's sky models (Hillaire's passes with each engine's medium) and their
files from a fit; the community rows are the engines' own values."""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate

from dustoptics.atmosphere import sets as atm
from dustoptics.io.engines.bevy import read_bevy_texture_ktx2
from dustoptics.io.tables.netcdf import read_hdf5
from dustoptics.sky.engines import ENGINES, _hillaire
from dustoptics.sky.engines.bevy import _bevy_mars_dust_column_km, bevy_mars_texture, bevy_setup
from dustoptics.sky.engines.core import EngineFit, SkyError
from dustoptics.sky.engines.openspace import COMMUNITY, openspace_setup

TABLES = Path(__file__).resolve().parents[3] / "tables"


@pytest.fixture(scope="module")
def mars():
    dust = read_hdf5(TABLES / "blue-moons" / "blue-moons.nc")
    return atm.mars_atmosphere(dust_table=dust, optical_depth=0.5)


def test_a_chromatic_phase_with_equal_channels_is_the_scalar_one() -> None:
    # The one change to the shared passes: mie_phase may give one value per channel.
    hg = _hillaire.henyey_greenstein(0.7)
    base = {
        "planet_radius_km": 3390.0,
        "top_radius_km": 3510.0,
        "rayleigh_scattering_per_km": np.array([1e-4, 2e-4, 6e-4]),
        "rayleigh_absorption_per_km": np.zeros(3),
        "rayleigh_scale_height_km": 8.0,
        "mie_scattering_per_km": np.array([0.04, 0.036, 0.03]),
        "mie_absorption_per_km": np.array([0.002, 0.008, 0.015]),
        "mie_scale_height_km": 11.1,
        "ozone_absorption_per_km": np.zeros(3),
        "ozone_bottom_km": 10.0,
        "ozone_peak_km": 25.0,
        "ozone_top_km": 40.0,
        "ground_albedo": np.full(3, 0.2),
    }
    scalar = _hillaire.HillaireSetup(mie_phase=hg, **base)
    chromatic = _hillaire.HillaireSetup(
        mie_phase=lambda c: np.repeat(hg(c)[:, None], 3, axis=1), **base
    )
    zen, azi = np.meshgrid([0.0, 45.0, 80.0], [0.0, 90.0, 180.0], indexing="ij")
    a = _hillaire.sky_radiance_rgb(
        scalar, sun_elevation_deg=20.0, view_zenith_deg=zen, view_azimuth_deg=azi
    )
    b = _hillaire.sky_radiance_rgb(
        chromatic, sun_elevation_deg=20.0, view_zenith_deg=zen, view_azimuth_deg=azi
    )
    np.testing.assert_allclose(b, a, rtol=1e-12)
    assert np.all(a > 0.0)


def test_bevys_mars_texture_is_its_file() -> None:
    columns = bevy_mars_texture()
    assert columns.shape == (1024, 3)
    # Bevy's reading (linear in cos theta) integrates to 1 per channel, first column
    # backscattering (the forward end is the largest).
    mu = np.linspace(-1.0, 1.0, 1024)
    integral = 2 * math.pi * np.sum(0.5 * (columns[1:] + columns[:-1]) * np.diff(mu)[:, None], 0)
    np.testing.assert_allclose(integral, 1.0, rtol=1e-5)
    assert np.all(columns[-1] > 100.0 * columns[0])
    repo = os.environ.get("DUSTOPTICS_BEVY_REPO")
    if repo:  # the values are the file's, where a checkout is at hand
        ktx = read_bevy_texture_ktx2(Path(repo) / "assets" / "textures" / "mars_mie_phase.ktx2")
        np.testing.assert_array_equal(ktx[:, :3], columns.astype(np.float32))


def test_bevys_mars_dust_column() -> None:
    # ScatteringMedium::mars: 0.75 exp(1 - exp(h / 4 km)) + 0.25 exp(1 - exp(h / 20 km)).
    f = lambda h: 0.75 * math.exp(1 - math.exp(h / 4)) + 0.25 * math.exp(1 - math.exp(h / 20))  # noqa: E731
    column, _ = integrate.quad(f, 0.0, 120.0, limit=200)
    assert _bevy_mars_dust_column_km() == pytest.approx(column, rel=1e-8)


def test_community_rows_are_the_engines_own(mars) -> None:
    bevy = ENGINES["bevy"].community(mars)
    assert (bevy["dust_scattering_r"], bevy["dust_absorption_b"]) == (30.67e-6, 9.33e-6)
    assert bevy["texture"] == 1.0 and bevy["inner_radius_km"] == 3389.5
    earth = atm.earth_atmosphere()
    bevy_earth = ENGINES["bevy"].community(earth)
    # Bevy's falloff scales are fractions of 60 km applied to Atmosphere::earth's 100 km.
    assert bevy_earth["rayleigh_scale_height_km"] == pytest.approx(8.0 / 60.0 * 100.0)
    space = ENGINES["openspace"].community(mars)
    assert (space["rayleigh_r"], space["rayleigh_b"]) == (0.019918, 0.00575)
    assert space["mie_absorption_g"] == pytest.approx(0.05361771 / 0.23862 - 0.05361771)
    assert COMMUNITY["earth"]["G"] == 0.85


def test_initial_rows_are_the_sets_coefficients(mars) -> None:
    bevy = ENGINES["bevy"].initial(mars)
    setup = bevy_setup(bevy)
    dust = mars.constituent("aerosols").table
    i = list(dust.wavelength_nm).index(550.0)
    assert setup.mie_scattering_per_km[1] == pytest.approx(dust.beta_sca_per_m[i] * 1000.0)
    assert setup.mie_scale_height_km == pytest.approx(11.1)
    space = openspace_setup(ENGINES["openspace"].initial(mars))
    assert space.mie_scattering_per_km[1] == pytest.approx(dust.beta_sca_per_m[i] * 1000.0)


def _fit(engine: str, params, name: str = "mars") -> EngineFit:
    error = SkyError(20.0, 3.0, 6.0, (0.4, 0.38), (0.4, 0.38), (0.4, 0.38), (0.4, 0.38), 1.0)
    return EngineFit(
        engine=engine,
        atmosphere=name,
        kind="fitted",
        params=params,
        errors=(error,),
        atmosphere_info={"name": name, "planet_radius_m": 3390e3, "atmosphere_radius_m": 3510e3},
    )


def test_files_from_a_fit(mars, tmp_path) -> None:
    params = dict(ENGINES["bevy"].initial(mars))
    params["dust_scattering_g"] = 1.234e-5
    files = ENGINES["bevy"].write(_fit("bevy", params), tmp_path)
    assert len(files) == 4
    document = json.loads((tmp_path / "mars_bevy.json").read_text())
    aerosols = next(t for t in document["terms"] if t["name"] == "aerosols")
    assert aerosols["scattering"][1] == 1.234e-5
    assert "Delta E 2000 3.00 mean" in (tmp_path / "mars_bevy_medium.rs").read_text()
    space = dict(ENGINES["openspace"].initial(mars), G=0.61)
    (asset,) = ENGINES["openspace"].write(_fit("openspace", space), tmp_path)
    text = asset.read_text()
    assert re.search(r"\bG = 0\.61\b", text) and "Ozone" not in text
    assert "Delta E 2000 3.00 mean" in text
