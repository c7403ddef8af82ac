"""Tests of dustoptics.atmosphere.sets: complete CosmoScout VR sets for Mars and Earth."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from _data import data_path

import dustoptics as do
from dustoptics.atmosphere import gases
from dustoptics.atmosphere import sets as atm
from dustoptics.atmosphere.column import (
    BRUNETON2017_OZONE,
    BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3,
    ExponentialProfile,
    optical_depth,
)
from dustoptics.io.csv.cosmoscout import (
    check_cosmoscout_set,
    read_cosmoscout_constituent,
    write_atmosphere,
)
from dustoptics.table import Table

WL15 = np.linspace(360.0, 830.0, 15)  # CosmoScout's default wavelength set
SPECTRA_DIR = ("spectra",)


@pytest.fixture(scope="module")
def dust_table() -> Table:
    dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    return do.compute_optics(
        do.mars_dust(), dist, WL15, np.linspace(0.0, 180.0, 181), rtol=1e-3, name="blue-moon-dust"
    )


def test_mars_set_passes_reader_rules(dust_table, tmp_path):
    mars = atm.mars_atmosphere(
        dust_table=dust_table, optical_depth=0.5, reference_wavelength_nm=550.0
    )
    files = write_atmosphere(mars, tmp_path)
    assert check_cosmoscout_set(tmp_path) == ["mars_aerosols", "mars_molecules"]
    settings = json.loads((tmp_path / "mars_settings.json").read_text())
    # BRIEF section 6: Mars radius 3390 km, atmosphere top 3510 km.
    assert settings["minAltitude"] == 3390e3 and settings["maxAltitude"] == 3510e3
    assert settings["aerosols"]["density"] == str(tmp_path.resolve() / "mars_aerosols_density.csv")
    for entry in ("molecules", "aerosols"):
        for key in ("phase", "betaSca", "betaAbs", "density"):
            assert (tmp_path / settings[entry][key]).is_file()
    assert "ozone" not in settings
    assert settings["ior"] == pytest.approx(
        gases.get_rayleigh_model("costa2021-mars").refractivity(550.0)
    )
    assert files[-1].name == "mars_settings.json"


def test_mars_dust_reproduces_optical_depth(dust_table, tmp_path):
    mars = atm.mars_atmosphere(
        dust_table=dust_table, optical_depth=0.7, reference_wavelength_nm=550.0
    )
    dust = mars.constituent("aerosols")
    cext_550 = float(np.interp(550.0, dust_table.wavelength_nm, dust_table.cross_sections.cext_um2))
    tau = optical_depth(
        number_density_per_m3=dust.table.quantity("number_density_per_m3"),
        cext_um2=cext_550,
        profile=dust.profile,
        top_altitude_m=mars.thickness_m,
    )
    assert tau == pytest.approx(0.7, rel=1e-13)
    # The written coefficients times the density are N0 <C> exp(-z / H) at the texel centres z.
    write_atmosphere(mars, tmp_path)
    read = read_cosmoscout_constituent(tmp_path, "mars_aerosols")
    z = mars.density_altitudes_m
    assert read.density[0] == 1.0
    np.testing.assert_allclose(
        np.outer(read.density, read.beta_sca_per_m),
        np.outer(np.exp(-z / 11100.0), dust.table.beta_sca_per_m),
        rtol=1e-12,
    )


def test_write_is_deterministic_and_refuses_overwrite(dust_table, tmp_path):
    mars = atm.mars_atmosphere(dust_table=dust_table)
    a, b = tmp_path / "a", tmp_path / "b"
    fa = write_atmosphere(mars, a)
    fb = write_atmosphere(mars, b)
    for x, y in zip(fa, fb, strict=True):  # the settings name the files by absolute path
        assert x.read_bytes().replace(bytes(a.resolve()), b"") == y.read_bytes().replace(
            bytes(b.resolve()), b""
        )
    with pytest.raises(FileExistsError):
        write_atmosphere(mars, a)
    write_atmosphere(mars, a, overwrite=True)


def test_mars_collienne_molecules(tmp_path):
    # Collienne's coefficients exist only at 440, 510, 680 nm: a 3-wavelength set.
    wl = np.array([440.0, 510.0, 680.0])
    dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    dust = do.compute_optics(
        1.52 + 0.006j, dist, wl, np.linspace(0.0, 180.0, 181), rtol=1e-3, name="dust"
    )
    mars = atm.mars_atmosphere(dust_table=dust, molecules="collienne2013")
    np.testing.assert_allclose(
        mars.constituent("molecules").table.beta_sca_per_m,
        [5.75e-6, 13.57e-6, 19.918e-6],
        rtol=1e-15,
    )
    write_atmosphere(mars, tmp_path)
    check_cosmoscout_set(tmp_path)


def test_kobe_earth_with_ozone(tmp_path):
    earth = atm.earth_atmosphere_kobe2026(name="earth")
    write_atmosphere(earth, tmp_path)
    assert check_cosmoscout_set(tmp_path) == ["earth_aerosols", "earth_molecules", "earth_ozone"]
    settings = json.loads((tmp_path / "earth_settings.json").read_text())
    assert set(settings["ozone"]) == {"betaAbs", "density"}
    # Hand computation (Kobe 11.5.1): beta_O3 = sigma * 6e-7 * N_s at the ground.
    expected = np.array([4.5e-26, 1.9e-25, 3.1e-25]) * 6e-7 * 2.545e25
    ozone = read_cosmoscout_constituent(tmp_path, "earth_ozone")
    at_z0 = np.exp(-earth.density_altitudes_m[0] / np.array([7994.0, 1200.0]))  # first texel
    np.testing.assert_allclose(ozone.beta_abs_per_m / at_z0[0], expected, rtol=1e-12)
    # Kobe's Rayleigh coefficients (6.56e-6, 1.73e-5, 2.30e-5 at 650, 510, 475 nm).
    mol = read_cosmoscout_constituent(tmp_path, "earth_molecules")
    np.testing.assert_allclose(
        mol.beta_sca_per_m / at_z0[0], [2.30e-5, 1.73e-5, 6.56e-6], rtol=5e-3
    )
    # Kobe's aerosols: beta_sca 2e-6, extinction beta_sca / 0.9.
    aer = read_cosmoscout_constituent(tmp_path, "earth_aerosols")
    np.testing.assert_allclose(aer.beta_sca_per_m / at_z0[1], 2e-6, rtol=1e-12)
    np.testing.assert_allclose(aer.beta_abs_per_m / at_z0[1], 2e-6 / 0.9 - 2e-6, rtol=1e-9)
    # Ozone follows the molecules' profile (fixed fraction).
    np.testing.assert_array_equal(ozone.density, mol.density)


def test_earth_with_tabulated_ozone_and_bruneton_layer(tmp_path):
    xs = gases.read_ozone_csv(data_path("spectra", "ozone_xsec_bruneton_pas_233K.csv"))
    earth = atm.earth_atmosphere(
        wavelength_nm=WL15,
        molecules="penndorf1957",
        ozone=xs,
        ozone_profile=BRUNETON2017_OZONE,
        ozone_number_density_per_m3=BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3,
    )
    write_atmosphere(earth, tmp_path)
    check_cosmoscout_set(tmp_path)
    ozone = read_cosmoscout_constituent(tmp_path, "earth_ozone")
    # The 1024-sample grid misses the 25 km peak: samples rescaled to 1 and beta by the same factor,
    # so beta * density equals sigma * N(z) at every sample.
    z = earth.density_altitudes_m  # the texel centres, where CosmoScout reads the values
    n_z = BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3 * BRUNETON2017_OZONE.relative_density(z)
    np.testing.assert_allclose(
        np.outer(ozone.density, ozone.beta_abs_per_m),
        np.outer(n_z, xs(WL15)),
        rtol=1e-12,
        atol=1e-30,
    )


def test_default_earth_is_cosmoscouts_15_wavelengths_with_standard_air_and_ozone(tmp_path):
    """CosmoScout VR's 15 wavelengths, Penndorf standard air (by name; the default is
    Bodhaine et al. 1999 since issue 40, tests/atmosphere/test_gases.py), shipped ozone in
    Bruneton's layer."""
    assert atm.earth_atmosphere().constituent("molecules").table.name == "bodhaine1999"
    earth = atm.earth_atmosphere(molecules="penndorf1957")
    np.testing.assert_allclose(earth.wavelength_nm, np.linspace(360.0, 830.0, 15), rtol=1e-15)
    write_atmosphere(earth, tmp_path)
    assert check_cosmoscout_set(tmp_path) == ["earth_aerosols", "earth_molecules", "earth_ozone"]
    # Molecules against Penndorf 1957 Table III (0 degC, 1013.25 hPa; tests/data),
    # interpolated log-log between its 10 nm rows, 360-800 nm (its 810-830 nm rows are
    # not a Rayleigh law, see test_gases): within 0.5 %.
    ref = pd.read_csv(
        data_path("spectra", "rayleigh_penndorf1957_bruneton_clearsky.csv"),
        comment="#",
    )
    wl, beta_ref = ref["wavelength_nm"].to_numpy(), ref["beta_rayleigh_per_m_0C"].to_numpy()
    mol = earth.constituent("molecules").table
    inside = mol.wavelength_nm <= 800.0
    expected = np.exp(np.interp(np.log(mol.wavelength_nm), np.log(wl), np.log(beta_ref)))
    dev = np.abs(mol.beta_sca_per_m / expected - 1.0)[inside]
    assert dev.max() < 5e-3  # measured 2.5e-4 (at 561 nm; log-log interpolation included)
    # Ozone: shipped spectrum at the bin starts (Bruneton's values, read independently).
    o3 = pd.read_csv(data_path(*SPECTRA_DIR, "ozone_xsec_bruneton_pas_233K.csv"), comment="#")
    sigma = np.interp(earth.wavelength_nm, o3["wavelength_nm"], o3["sigma_O3_m2"])
    ozone = earth.constituent("ozone").table
    np.testing.assert_allclose(
        ozone.beta_abs_per_m, sigma * BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3, rtol=1e-12
    )


def test_shipped_ozone_against_serdyuchenko_293K_bins():
    """The shipped 233 K bin means against the 293 K measurement binned the same way.

    Serdyuchenko et al. 2014 (raw 293 K samples) averaged over [L, L + 10) nm
    (tests/data, by scripts/make_test_data.py): in the Chappuis band (500-700 nm) the temperature
    dependence is small (their Part 2: a few percent); measured 0.2-4.6 %.
    """
    bins = pd.read_csv(
        data_path(*SPECTRA_DIR, "ozone_xsec_serdyuchenko2014_293K_binmean_500-700nm.csv"),
        comment="#",
    )
    shipped = gases.ozone_serdyuchenko2014()
    starts = np.arange(500.0, 700.0, 10.0)
    np.testing.assert_array_equal(bins["bin_start_nm"].to_numpy(), starts)
    assert np.all(bins["n_samples"].to_numpy() == 1000)
    binned = bins["sigma_O3_cm2"].to_numpy() * 1e-4
    np.testing.assert_allclose(shipped(starts), binned, rtol=0.05)


def test_optical_depth_recorded_in_provenance(dust_table):
    profile = ExponentialProfile(scale_height_m=11100.0)
    t = atm.with_optical_depth(
        dust_table,
        optical_depth=0.6,
        reference_wavelength_nm=550.0,
        profile=profile,
        top_altitude_m=120e3,
    )
    column = t.provenance.inputs["column"]
    assert column["optical_depth"] == 0.6 and column["reference_wavelength_nm"] == 550.0
    assert any("optical depth 0.6 at 550 nm" in n for n in t.provenance.notes)
    # Identity: tau = N0 <C_ext> L, L = H (1 - exp(-top / H)).
    cext = np.interp(550.0, dust_table.wavelength_nm, dust_table.cross_sections.cext_um2) * 1e-12
    length = 11100.0 * (1 - np.exp(-120e3 / 11100.0))
    np.testing.assert_allclose(
        t.cross_sections.number_density_per_m3 * cext * length, 0.6, rtol=1e-12
    )
    assert t.provenance.input_hash != dust_table.provenance.input_hash


def test_bad_input(dust_table):
    with pytest.raises(ValueError, match=r"optical_depth must be > 0; got -0.5"):
        atm.mars_atmosphere(dust_table=dust_table, optical_depth=-0.5)
    with pytest.raises(
        ValueError, match=r"reference_wavelength_nm must lie within .*\[360, 830\] nm.*880"
    ):
        atm.mars_atmosphere(dust_table=dust_table, reference_wavelength_nm=880.0)
    with pytest.raises(ValueError, match=r"scale_height_m must be > 0 m"):
        atm.mars_atmosphere(dust_table=dust_table, dust_scale_height_m=-1.0)
    with pytest.raises(
        ValueError, match=r"molecules must be one of 'costa2021-mars', 'collienne2013'"
    ):
        atm.mars_atmosphere(dust_table=dust_table, molecules="kobe2026")
    with pytest.raises(ValueError, match=r"published only at wavelength_nm"):
        atm.earth_atmosphere(wavelength_nm=[450.0, 550.0], ozone=gases.KOBE2026_OZONE)
    with pytest.raises(ValueError, match=r"ozone_number_density_per_m3 is required"):
        atm.earth_atmosphere(ozone_profile=ExponentialProfile(scale_height_m=5000.0))
    with pytest.raises(ValueError, match=r"atmosphere_radius_m must exceed planet_radius_m"):
        atm.earth_atmosphere(atmosphere_radius_m=6000e3)
