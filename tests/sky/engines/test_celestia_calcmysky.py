"""Celestia's and CalcMySky's sky models: limits the models must reach, their files from a fit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from dustoptics.atmosphere import sets as atm
from dustoptics.io.tables.netcdf import read_hdf5
from dustoptics.sky.engines import ENGINES
from dustoptics.sky.engines.calcmysky import (
    calcmysky_medium,
    mars_atmo_example,
    sample_atmo_example,
)
from dustoptics.sky.engines.celestia import COMMUNITY, celestia_sky_rgb
from dustoptics.sky.engines.core import EngineFit, SkyError, sunlight_linear_srgb

TABLES = Path(__file__).resolve().parents[3] / "tables"


@pytest.fixture(scope="module")
def mars():
    dust = read_hdf5(TABLES / "blue-moons" / "blue-moons.nc")
    return atm.mars_atmosphere(dust_table=dust, optical_depth=0.5)


def _thin(rayleigh: float, mie: float = 0.0, g: float = 0.0) -> dict[str, float]:
    return {
        "Mie": mie,
        "MieScaleHeight": 8.0,
        "MieHGAnisotropy": g,
        "planet_radius_km": 3390.0,
        "exposure": 1.0,
        **{f"Rayleigh_{c}": rayleigh for c in "rgb"},
        **{f"Absorption_{c}": 0.0 for c in "rgb"},
    }


def test_celestia_thin_zenith_is_phase_times_column() -> None:
    # Optically thin (tau ~ 1e-5): the zenith's single scattering is the shader's phase
    # times the coefficient times the column, which Celestia's Chapman function gives as
    # H (1 - threshold) in planet radii for the vertical (its shell ends where exp(-z/H) is
    # 0.000125), from the eye 2 m up.  Sun at 45 deg: mu = sin 45.
    beta, h, radius = 1e-6, 8.0, 3390.0
    rgb = celestia_sky_rgb(
        _thin(beta), sun_elevation_deg=45.0, view_zenith_deg=0.0, view_azimuth_deg=0.0
    )
    mu = math.sin(math.radians(45.0))
    column = h / radius * (math.exp(-0.002 / h) - 0.000125)
    expected = 0.75 * (1.0 + mu * mu) * (beta * radius) * column * sunlight_linear_srgb()
    np.testing.assert_allclose(rgb, expected, rtol=3e-5)


def test_celestia_mie_peaks_toward_the_sun_for_positive_g() -> None:
    params = _thin(0.0, mie=1e-6, g=0.7)
    near = celestia_sky_rgb(
        params, sun_elevation_deg=30.0, view_zenith_deg=65.0, view_azimuth_deg=0.0
    )
    away = celestia_sky_rgb(
        params, sun_elevation_deg=30.0, view_zenith_deg=65.0, view_azimuth_deg=180.0
    )
    # Schlick with k = 1.55 g - 0.55 g^3: forward/backward = ((1 + k) / (1 - k))^2 at the
    # same path (the two directions are symmetric about the zenith, same column).
    k = 1.55 * 0.7 - 0.55 * 0.7**3
    scatter_near = math.cos(math.radians(5.0))  # 5 deg from the Sun
    scatter_away = math.cos(math.radians(65.0 + 60.0))  # across the zenith: 125 deg
    ratio = ((1.0 - k * scatter_away) / (1.0 - k * scatter_near)) ** 2
    np.testing.assert_allclose(near / away, ratio, rtol=1e-3)


def test_celestia_community_is_celestiacontents_mars() -> None:
    mars = COMMUNITY["mars"]
    # CelestiaContent's data/solarsys.ssc at d156a8b5: no MieHGAnisotropy (isotropic dust).
    assert mars["MieHGAnisotropy"] == 0.0 and mars["Rayleigh"] == (0.00022, 0.00034, 0.00070)
    # Earth's deprecated "MieAsymmetry -0.7" is read with the opposite sign (solarsys.cpp).
    assert COMMUNITY["earth"]["MieHGAnisotropy"] == 0.7


def test_calcmysky_medium_keeps_the_optical_depth(mars) -> None:
    got = calcmysky_medium(mars)
    top = mars.atmosphere_radius_m - mars.planet_radius_m
    for a, b in zip(mars.constituents, got.constituents, strict=True):
        tau_a = np.asarray(a.table.beta_ext_per_m) * a.profile.column_length_m(top_altitude_m=top)
        tau_b = np.asarray(b.table.beta_ext_per_m) * b.profile.column_length_m(top_altitude_m=top)
        # Within the power law's error (the .atmo states it: 0.6 % for the dust, 1.4 % CO2).
        np.testing.assert_allclose(tau_b, tau_a, rtol=0.015)


def test_mars_atmo_example_is_calcmyskys(mars) -> None:
    example = mars_atmo_example(mars)
    dust = example.constituent("aerosols")
    wl = list(dust.table.wavelength_nm)
    i = wl.index(550.0)
    # examples/mars.atmo: 10.155 um^2 (lambda / 1 um)^0.2, N0 = 4.559e6 m^-3, H = 10.8 km.
    cext = 10.155 * 0.55**0.2
    assert dust.table.quantity("cext_um2")[i] == pytest.approx(cext, rel=1e-12)
    tau = 4.559e6 * cext * 1e-12 * 10.8e3 * (1.0 - math.exp(-120.0 / 10.8))
    assert np.asarray(dust.table.beta_ext_per_m)[i] * dust.profile.column_length_m(
        top_altitude_m=120e3
    ) == pytest.approx(tau, rel=1e-9)
    # Its HG g(550 nm) = 0.64 + 0.23 exp(-0.00002378121 (550 - 310)^2).
    g = 0.64 + 0.23 * math.exp(-0.00002378121 * 240.0**2)
    mu = np.cos(np.radians(dust.table.theta_deg))
    hg = (1 - g * g) / (1 + g * g - 2 * g * mu) ** 1.5 / (4 * math.pi)
    np.testing.assert_allclose(dust.table.phase[i], hg, rtol=1e-12)
    # Ockert-Bell's albedo at 550 nm, linear between 500 (0.78) and 600 nm (0.91).
    assert dust.table.ssa[i] == pytest.approx(0.845, abs=1e-12)


def test_sample_atmo_example_is_calcmyskys_earth() -> None:
    earth = sample_atmo_example(atm.earth_atmosphere())
    aerosols = earth.constituent("aerosols")
    # examples/sample.atmo: 0.042968 um^2 at every wavelength (Angstrom 0), albedo 1,
    # 1.03333e8 m^-3 exp(-h / 1.2 km): tau = N0 C H (1 - exp(-120 / 1.2)).
    tau = 1.03333e8 * 0.042968e-12 * 1.2e3
    got = np.asarray(aerosols.table.beta_ext_per_m) * aerosols.profile.column_length_m(
        top_altitude_m=120e3
    )
    np.testing.assert_allclose(got, tau, rtol=1e-12)
    assert np.all(np.asarray(aerosols.table.ssa) == 1.0)
    # Its phase function (Cornette-Shanks 0.76 plus a spike, times 0.904) is about normalized.
    mu = np.cos(np.radians(aerosols.table.theta_deg))[::-1]
    row = np.asarray(aerosols.table.phase)[0][::-1]
    assert 2 * math.pi * np.trapezoid(row, mu) == pytest.approx(1.0, abs=2e-3)


def _fit(engine: str, params: dict[str, float], name: str) -> EngineFit:
    error = SkyError(45.0, 1.0, 2.0, (0.3, 0.3), (0.3, 0.3), (0.3, 0.3), (0.3, 0.3), 1.0)
    return EngineFit(
        engine=engine,
        atmosphere=name,
        kind="fitted",
        params=params,
        errors=(error,),
        atmosphere_info={"name": name, "planet_radius_m": 3390e3, "atmosphere_radius_m": 3510e3},
    )


def test_the_engines_write_their_files_from_a_fit(mars, tmp_path) -> None:
    celestia = ENGINES["celestia"]
    (ssc,) = celestia.write(_fit("celestia", celestia.initial(mars), "mars"), tmp_path)
    text = ssc.read_text()
    assert 'Modify "Mars" "Sol"' in text and "Delta E 2000 1.00 mean" in text
    calcmysky = ENGINES["calcmysky"]
    (atmo,) = calcmysky.write(_fit("calcmysky", calcmysky.initial(mars), "mars"), tmp_path)
    assert atmo.read_text().startswith("version: 6\n")
    assert "Sun 45 deg 1.00 / 2.00" in atmo.read_text()
