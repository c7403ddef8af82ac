"""Tests of dustoptics.atmosphere.gases: Rayleigh scattering of gases and ozone absorption."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from _data import data_path
from scipy import constants

from dustoptics.atmosphere import gases
from dustoptics.atmosphere.gases import (
    KOBE2026_OZONE,
    OzoneCrossSection,
    get_rayleigh_model,
    ideal_gas_number_density_per_m3,
    king_factor,
    ozone_beta_abs_per_m,
    rayleigh_beta_per_m,
    rayleigh_cross_section_m2,
    read_ozone_csv,
)
from dustoptics.scattering import tabulated_phase

SPECTRA = ("spectra",)


# ------------------------------------------------------------------ basic laws


def test_ideal_gas_matches_loschmidt_constant():
    # CODATA Loschmidt constant at 273.15 K, 101.325 kPa (scipy.constants).
    loschmidt = constants.physical_constants["Loschmidt constant (273.15 K, 101.325 kPa)"][0]
    n = ideal_gas_number_density_per_m3(pressure_pa=101325.0, temperature_k=273.15)
    assert n == pytest.approx(loschmidt, rel=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"pressure_pa": -1.0, "temperature_k": 273.15}, r"pressure_pa must be > 0 Pa; got -1.0"),
        ({"pressure_pa": 0.0, "temperature_k": 273.15}, r"pressure_pa must be > 0"),
        ({"pressure_pa": 610.0, "temperature_k": -5.0}, r"temperature_k must be > 0 K; got -5.0"),
        ({"pressure_pa": float("nan"), "temperature_k": 200.0}, r"pressure_pa must be finite"),
    ],
)
def test_ideal_gas_rejects_bad_state(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ideal_gas_number_density_per_m3(**kwargs)


def test_king_factor_limits_and_values():
    # delta = 0 (isotropic molecules): no correction (identity).
    assert king_factor(depolarization=0.0) == 1.0
    # The formula (6 + 3 d)/(6 - 7 d) evaluated by hand at Costa's and Penndorf's deltas.
    assert king_factor(depolarization=0.0279) == pytest.approx(6.0837 / 5.8047, rel=1e-12)
    assert king_factor(depolarization=0.035) == pytest.approx(6.105 / 5.755, rel=1e-12)
    # Increasing in delta and divergent at 6/7 (denominator zero).
    d = np.linspace(0.0, 0.85, 50)
    assert np.all(np.diff(king_factor(depolarization=d)) > 0)
    assert king_factor(depolarization=6 / 7 - 1e-9) > 1e8
    for bad in (-0.01, 6 / 7, 1.0):
        with pytest.raises(ValueError, match=r"depolarization must be in \[0, 6/7\)"):
            king_factor(depolarization=bad)


# ------------------------------------------------------- published Rayleigh values


def _penndorf() -> pd.DataFrame:
    path = data_path(*SPECTRA, "rayleigh_penndorf1957_bruneton_clearsky.csv")
    return pd.read_csv(path, comment="#")


def test_standard_air_against_penndorf_table():
    """Penndorf 1957 Table III (0 degC, 1013.25 hPa), 360-800 nm: within 1 %.

    Measured: largest deviation 3.1e-4 (at 540 nm) for 360-800 nm.
    """
    ref = _penndorf()
    wl = ref["wavelength_nm"].to_numpy()
    beta_ref = ref["beta_rayleigh_per_m_0C"].to_numpy()
    beta = rayleigh_beta_per_m(wl, model="penndorf1957")
    ok = wl <= 800.0
    dev = np.abs(beta[ok] / beta_ref[ok] - 1.0)
    assert dev.max() < 1e-2  # the requirement
    assert dev.max() < 5e-4  # what this model achieves (measured 3.1e-4)


def test_penndorf_rows_810_830_are_not_a_rayleigh_law():
    """The three last rows of the transcription deviate by 1.2-2.8 % from the model.

    They cannot be Rayleigh values: between neighbouring rows a Rayleigh
    coefficient falls at least as fast as lambda^-4 (n - 1 decreases with
    wavelength in the visible), but these rows fall as lambda^-3.1 or slower,
    while every other pair falls as lambda^-4.0 to -4.2.  The model keeps the
    lambda^-4.1 law there.
    """
    ref = _penndorf()
    wl = ref["wavelength_nm"].to_numpy()
    beta_ref = ref["beta_rayleigh_per_m_0C"].to_numpy()
    exponent = -np.diff(np.log(beta_ref)) / np.diff(np.log(wl))
    assert np.all(exponent[wl[1:] <= 800.0] > 3.95)
    assert np.all(exponent[wl[1:] >= 810.0] < 3.5)
    model = rayleigh_beta_per_m(wl, model="penndorf1957")
    model_exponent = -np.diff(np.log(model)) / np.diff(np.log(wl))
    assert np.all(model_exponent > 4.0)


def test_costa_earth_table_values_are_penndorfs():
    # Costa et al. 2021, Table 1, Earth beta_R at 680, 550, 440 nm (from Penndorf [11]).
    costa = np.array([5.1768e-6, 12.2588e-6, 30.5964e-6])
    beta = rayleigh_beta_per_m([680.0, 550.0, 440.0], model="penndorf1957")
    np.testing.assert_allclose(beta, costa, rtol=5e-4)


def test_costa_mars_table_reproduced_by_eq11():
    """Costa Table 1 Mars beta_R from their own inputs: n_CO2, N = 2.8e23, delta = 0.09."""
    wl = np.array([680.0, 550.0, 440.0])
    n_minus_1 = np.array([0.00044661, 0.00045019, 0.00045558])  # Table 1, nCO2
    beta_printed = np.array([1.2871e-3, 3.0560e-3, 7.6406e-3])  # Table 1, beta_R
    sigma = rayleigh_cross_section_m2(
        wavelength_nm=wl, refractivity=n_minus_1, number_density_per_m3=2.8e23, depolarization=0.09
    )
    np.testing.assert_allclose(sigma * 2.8e23, beta_printed, rtol=5e-5)


def test_kobe_published_rayleigh_coefficients():
    # Kobe 2026, section 11.3.2: beta_R = (6.56e-6, 1.73e-5, 2.30e-5) at (650, 510, 475) nm.
    beta = rayleigh_beta_per_m([650.0, 510.0, 475.0], model="kobe2026")
    np.testing.assert_allclose(beta, [6.56e-6, 1.73e-5, 2.30e-5], rtol=5e-3)  # 3 printed digits


def test_mars_co2_refractivity_is_scaled_to_mars_density():
    gas = get_rayleigh_model("costa2021-mars")
    n_mars = ideal_gas_number_density_per_m3(pressure_pa=610.0, temperature_k=215.0)
    assert gas.number_density_per_m3 == pytest.approx(n_mars, rel=1e-15)
    # Hand computation: Costa's printed n_CO2(550) - 1 = 4.5019e-4 at 0 degC, 1 atm,
    # times the density ratio.
    n_stp = ideal_gas_number_density_per_m3(pressure_pa=101325.0, temperature_k=273.15)
    expected = 4.5019e-4 * n_mars / n_stp
    assert gas.refractivity(550.0) == pytest.approx(expected, rel=1e-4)
    # BRIEF section 6: Mars surface N ~ 2.05e23 m^-3 and n - 1 ~ 3.4e-6 (CosmoScout: 3.37e-6).
    assert n_mars == pytest.approx(2.05e23, rel=5e-3)
    assert gas.refractivity(550.0) == pytest.approx(3.37e-6, rel=3e-2)


def test_cross_section_independent_of_density_and_beta_proportional():
    gas = get_rayleigh_model("costa2021")
    wl = np.array([400.0, 700.0])
    s1 = gas.cross_section_m2(wl, number_density_per_m3=2.5e25)
    s2 = gas.cross_section_m2(wl, number_density_per_m3=2.5e22)
    # (n^2 - 1)^2 / N^2 is constant to first order in n - 1 (~3e-4 relative).
    np.testing.assert_allclose(s1, s2, rtol=1e-3)
    b1 = gas.beta_sca_per_m(wl, number_density_per_m3=2.5e25)
    b2 = gas.beta_sca_per_m(wl, number_density_per_m3=2.5e22)
    np.testing.assert_allclose(b1 / b2, 1000.0 * s1 / s2, rtol=1e-12)


def test_pressure_temperature_and_number_density_give_same_beta():
    n = ideal_gas_number_density_per_m3(pressure_pa=80000.0, temperature_k=250.0)
    a = rayleigh_beta_per_m(550.0, model="costa2021", pressure_pa=80000.0, temperature_k=250.0)
    b = rayleigh_beta_per_m(550.0, model="costa2021", number_density_per_m3=n)
    assert a == b


def test_rayleigh_bad_input():
    with pytest.raises(ValueError, match=r"model must be one of 'penndorf1957'.*got 'air'"):
        rayleigh_beta_per_m(550.0, model="air")
    with pytest.raises(
        ValueError, match=r"outside the data of material 'air-edlen1953'.*\[200, 20000\]"
    ):
        rayleigh_beta_per_m(150.0, model="costa2021")
    with pytest.raises(ValueError, match=r"outside the data of material 'co2-bideaumehu1973'"):
        rayleigh_beta_per_m(2000.0, model="costa2021-mars")
    with pytest.raises(ValueError, match=r"pressure_pa must be > 0 Pa; got -610.0"):
        rayleigh_beta_per_m(550.0, model="costa2021-mars", pressure_pa=-610.0, temperature_k=215.0)
    with pytest.raises(ValueError, match=r"must be given together"):
        rayleigh_beta_per_m(550.0, pressure_pa=610.0)
    with pytest.raises(ValueError, match=r"not both"):
        rayleigh_beta_per_m(
            550.0, number_density_per_m3=1e23, pressure_pa=610.0, temperature_k=215.0
        )
    with pytest.raises(ValueError, match=r"wavelength_nm must be > 0 nm"):
        rayleigh_cross_section_m2(
            wavelength_nm=-1.0, refractivity=3e-4, number_density_per_m3=2.5e25
        )


def test_rayleigh_table():
    gas = get_rayleigh_model("costa2021")
    wl = np.linspace(360.0, 830.0, 15)
    t = gas.table(wl, theta_deg=np.linspace(0.0, 180.0, 181))
    np.testing.assert_allclose(t.beta_sca_per_m, gas.beta_sca_per_m(wl), rtol=1e-12)
    np.testing.assert_array_equal(t.beta_abs_per_m, 0.0)
    np.testing.assert_allclose(
        tabulated_phase.sphere_integral(t.phase, theta_deg=t.theta_deg), 1.0, rtol=1e-12
    )
    # Penndorf's shape: P(0)/P(90) = 1 + 0.932.
    assert t.phase[0, 0] / t.phase[0, 90] == pytest.approx(1.932, rel=1e-12)
    np.testing.assert_array_equal(t.g, 0.0)


def test_collienne_coefficients_only_at_published_wavelengths():
    t = gases.collienne2013_table()
    np.testing.assert_allclose(t.beta_sca_per_m, [5.75e-6, 13.57e-6, 19.918e-6], rtol=1e-15)
    with pytest.raises(
        ValueError,
        match=r"published only at wavelength_nm in \[440.0, 510.0, 680.0\]; got \[550.0\]",
    ):
        gases.collienne2013_beta_per_m([440.0, 550.0])


# -------------------------------------------------------------------- ozone


def test_kobe_ozone_hand_computation():
    # Kobe 2026, 11.5.1: sigma (4.5e-26, 1.9e-25, 3.1e-25) m^2 times N_s = 2.545e25 m^-3
    # gives his beta_O = (1.15, 4.84, 7.89) m^-1 (3 printed digits).
    beta = ozone_beta_abs_per_m(
        [475.0, 510.0, 650.0], cross_section=KOBE2026_OZONE, number_density_per_m3=2.545e25
    )
    np.testing.assert_allclose(
        beta, [4.5e-26 * 2.545e25, 1.9e-25 * 2.545e25, 3.1e-25 * 2.545e25], rtol=1e-15
    )
    np.testing.assert_allclose(beta, [1.15, 4.84, 7.89], rtol=5e-3)


def test_kobe_ozone_only_at_its_three_wavelengths():
    with pytest.raises(
        ValueError, match=r"published only at wavelength_nm in \[475.0, 510.0, 650.0\]"
    ):
        KOBE2026_OZONE([500.0])


def test_ozone_csv_round_trip_and_interpolation(tmp_path):
    path = tmp_path / "o3.csv"
    path.write_text(
        "# Test spectrum written by this test; two rows, cm^2 per molecule\n"
        "wavelength_nm,sigma_cm2\n500,1.0e-21\n600,5.0e-21\n",
        encoding="utf-8",
    )
    xs = read_ozone_csv(path)
    assert xs.citation.startswith("Test spectrum")
    # Linear interpolation at the midpoint, cm^2 -> m^2 (x 1e-4): hand computation.
    assert xs(550.0) == pytest.approx(3.0e-25, rel=1e-12)
    n_o3 = 6e-7 * 2.545e25
    assert ozone_beta_abs_per_m(
        550.0, cross_section=xs, number_density_per_m3=n_o3
    ) == pytest.approx(3.0e-25 * n_o3, rel=1e-12)
    with pytest.raises(
        ValueError, match=r"outside the ozone cross-section 'o3': valid range \[500, 600\] nm"
    ):
        xs([450.0])


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            "wavelength_nm,sigma_m2\n500,1e-25\n600,2e-25\n",
            r"comment lines \(#\) giving the citation",
        ),
        ("# cite\nlambda,sigma_m2\n500,1e-25\n", r"header must be 'wavelength_nm,sigma_m2'"),
        ("# cite\nwavelength_nm,sigma_m2\n500,abc\n", r":3: not numbers"),
        ("# cite\nwavelength_nm,sigma_m2\n600,1e-25\n500,1e-25\n", r"strictly increasing"),
        ("# cite\nwavelength_nm,sigma_m2\n500,-1e-25\n600,1e-25\n", r"sigma_m2 must be >= 0"),
    ],
)
def test_ozone_csv_errors(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=match):
        read_ozone_csv(path)


def test_ozone_csv_reads_shared_bruneton_spectrum():
    path = data_path(*SPECTRA, "ozone_xsec_bruneton_pas_233K.csv")
    xs = read_ozone_csv(path)
    ref = pd.read_csv(path, comment="#")
    np.testing.assert_array_equal(xs.sigma_m2, ref["sigma_O3_m2"].to_numpy())
    assert "Serdyuchenko" in xs.citation


def test_ozone_table_absorbs_only():
    t = gases.ozone_table(
        [475.0, 510.0, 650.0], cross_section=KOBE2026_OZONE, number_density_per_m3=1.527e19
    )
    np.testing.assert_array_equal(t.beta_sca_per_m, 0.0)
    np.testing.assert_allclose(
        t.beta_abs_per_m, KOBE2026_OZONE([475.0, 510.0, 650.0]) * 1.527e19, rtol=1e-12
    )
    np.testing.assert_allclose(t.phase, 1.0 / (4.0 * math.pi))


def test_ozone_cross_section_validation():
    with pytest.raises(ValueError, match=r"citation must name the source"):
        OzoneCrossSection(
            name="x", wavelength_nm=[500.0, 600.0], sigma_m2=[1e-25, 1e-25], citation=" "
        )
    with pytest.raises(ValueError, match=r"interpolation must be one of 'linear', 'points'"):
        OzoneCrossSection(
            name="x",
            wavelength_nm=[500.0, 600.0],
            sigma_m2=[1e-25, 1e-25],
            citation="c",
            interpolation="cubic",
        )
    with pytest.raises(ValueError, match=r"number_density_per_m3 must be > 0"):
        ozone_beta_abs_per_m(475.0, cross_section=KOBE2026_OZONE, number_density_per_m3=-1.0)


def test_mars_co2_cross_section_against_vardavas_keady_form():
    """CO2 Rayleigh cross-section with its King factor vs an independent formula.

    Vardavas & Carver (1984) form, sigma = 4.577e-21 / lam^4 K(delta) (A (1 + B / lam^2))^2
    cm^2 (lam in um), with Keady & Kilcrease's CO2 coefficients A = 4.39e-4, B = 6.4e-3
    (photochem_clima_data's rayleigh.yaml, in tests/data).  At the same King factor
    (delta = 0.09, Costa et al.) the Bideau-Mehu index gives 0.8-1.3 % more (measured);
    the file's own delta = 0.0774 makes its King factor 2.3 % smaller.
    """
    rows = pd.read_csv(data_path(*SPECTRA, "rayleigh_vardavas_params_photochem.csv"), comment="#")
    co2 = rows[rows["species"] == "CO2"].iloc[0]
    wl = np.array([400.0, 550.0, 700.0])
    lam_um = wl / 1000.0
    refr = co2["A"] * (1.0 + co2["B"] / lam_um**2)
    sigma_ref = 4.577e-21 / lam_um**4 * king_factor(depolarization=0.09) * refr**2 * 1e-4
    sigma = get_rayleigh_model("costa2021-mars").cross_section_m2(wl)
    np.testing.assert_allclose(sigma / sigma_ref, 1.0, atol=0.015)
    assert king_factor(depolarization=0.09) / king_factor(depolarization=co2["Delta"]) == (
        pytest.approx(1.0226, abs=5e-4)
    )
