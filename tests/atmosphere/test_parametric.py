"""Tests of dustoptics.atmosphere.parametric: Ångström, anomalous diffraction, Costa's turbidity."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import integrate

from dustoptics.atmosphere.parametric import (
    COSTA2021_MARS_HULST,
    ScatteringExceedsExtinctionWarning,
    ada_cext_um2,
    ada_qext,
    angstrom_beta_per_m,
    costa2021_aerosol_coefficients,
    costa2021_turbidity_beta_sca_per_m,
)
from dustoptics.particles.sizedist import ModifiedGamma, Monodisperse
from dustoptics.scattering import optics

WL = np.array([440.0, 550.0, 680.0])


def test_angstrom_law():
    # Identity: at 1000 nm beta = beta0; halving the wavelength multiplies by 2^alpha.
    b = angstrom_beta_per_m([1000.0, 500.0], beta0_per_m=0.04 / 1200.0, alpha=0.8)
    assert b[0] == pytest.approx(0.04 / 1200.0, rel=1e-15)
    assert b[1] / b[0] == pytest.approx(2.0**0.8, rel=1e-14)
    with pytest.raises(ValueError, match=r"beta0_per_m must be > 0 m\^-1; got -1.0"):
        angstrom_beta_per_m(500.0, beta0_per_m=-1.0, alpha=1.0)
    with pytest.raises(ValueError, match=r"wavelength_nm must be > 0 nm"):
        angstrom_beta_per_m([-500.0], beta0_per_m=1.0, alpha=1.0)


def _costa_eq19(rho, tan_b):
    """Costa et al. 2021 eq. (19) written out term by term (independent of the K(w) form)."""
    b = math.atan(tan_b)
    c = math.cos(b) / rho
    e = math.exp(-rho * tan_b)
    return (
        2
        - 4 * e * c * math.sin(rho - b)
        - 4 * e * c**2 * math.cos(rho - 2 * b)
        + 4 * c**2 * math.cos(2 * b)
    )


@pytest.mark.parametrize("m", [1.52 + 0.006j, 1.33 + 0.0j, 1.1 + 0.05j])
@pytest.mark.parametrize("r_um", [0.3, 1.6, 7.0])
def test_ada_qext_matches_printed_formula(m, r_um):
    rho = 4 * math.pi * r_um * 1000.0 * (m.real - 1) / 550.0
    q = ada_qext(wavelength_nm=550.0, radius_um=r_um, refractive_index=m)
    assert q == pytest.approx(_costa_eq19(rho, m.imag / (m.real - 1)), rel=1e-12)


def test_ada_limits():
    # Small spheres, k = 0: Q -> rho^2 / 2 (series of eq. 19); large: Q -> 2 (extinction paradox).
    r = np.array([1e-4, 1e-3])
    rho = 4 * math.pi * r * 1000.0 * 0.5 / 550.0
    np.testing.assert_allclose(
        ada_qext(wavelength_nm=550.0, radius_um=r, refractive_index=1.5), rho**2 / 2, rtol=2e-3
    )
    assert ada_qext(
        wavelength_nm=550.0, radius_um=500.0, refractive_index=1.5 + 0.01j
    ) == pytest.approx(2.0, abs=1e-6)
    with pytest.raises(ValueError, match=r"n > 1 for the anomalous diffraction"):
        ada_qext(wavelength_nm=550.0, radius_um=1.0, refractive_index=0.9)
    with pytest.raises(ValueError, match=r"k >= 0"):
        ada_qext(wavelength_nm=550.0, radius_um=1.0, refractive_index=1.5 - 0.1j)


def test_ada_polydisperse_quadrature_against_scipy_quad():
    dist = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    m = 1.52 + 0.006j

    def integrand(r):
        return (
            dist.pdf(r)
            * math.pi
            * r
            * r
            * float(ada_qext(wavelength_nm=550.0, radius_um=r, refractive_index=m))
        )

    ref, _ = integrate.quad(integrand, 1e-6, 60.0, limit=400, epsabs=0.0, epsrel=1e-11)
    got = ada_cext_um2(wavelength_nm=[550.0], refractive_index=m, distribution=dist)[0]
    assert got == pytest.approx(ref, rel=1e-8)


@pytest.mark.parametrize(
    ("m", "r_eff_um", "low", "high"),
    [
        # Measured ADA / Mie - 1 (compute_optics, rtol 1e-3; cross-sections to 1e-5):
        # Mars dust r_eff 1.6: -0.1175, -0.1326, -0.1479 at 440, 550, 680 nm.
        (1.52 + 0.006j, 1.6, -0.16, -0.10),
        # r_eff 5: -0.0601, -0.0689, -0.0783.
        (1.52 + 0.006j, 5.0, -0.09, -0.05),
        # Nearly index-matched (ADA's domain), r_eff 5: -0.0399, -0.0414, -0.0423.
        (1.05 + 0.0j, 5.0, -0.05, -0.03),
    ],
)
def test_ada_against_exact_mie(m, r_eff_um, low, high):
    """ADA misses the edge contribution and falls 4-15 % short of exact Mie."""
    dist = ModifiedGamma(r_eff_um=r_eff_um, v_eff=0.2)
    ada = ada_cext_um2(wavelength_nm=WL, refractive_index=m, distribution=dist)
    mie = optics.compute_optics(m, dist, WL, [0.0, 180.0], rtol=1e-3).cross_sections.cext_um2
    err = ada / mie - 1.0
    assert np.all((err > low) & (err < high)), err


def test_costa_turbidity_hand_computation():
    # Eq. (17) at 550 nm, T = 2, nu = 4, K = 0.16: 0.434 * 0.65e-16 * pi * (2 pi / 550e-9)^2 * 0.16.
    expected = 0.434 * 0.65e-16 * math.pi * (2 * math.pi / 550e-9) ** 2 * 0.16
    got = costa2021_turbidity_beta_sca_per_m(
        550.0, turbidity=2.0, junge_exponent=4.0, k_factor=0.16
    )
    assert got == pytest.approx(expected, rel=1e-14)
    for kwargs, match in [
        ({"turbidity": 1.0, "junge_exponent": 4.0, "k_factor": 0.1}, r"turbidity must be > 1"),
        (
            {"turbidity": 2.0, "junge_exponent": 7.0, "k_factor": 0.1},
            r"junge_exponent must be in \[2, 6\]; got 7.0",
        ),
        ({"turbidity": 2.0, "junge_exponent": 4.0, "k_factor": [0.1, 0.2]}, r"one per wavelength"),
    ]:
        with pytest.raises(ValueError, match=match):
            costa2021_turbidity_beta_sca_per_m([550.0, 600.0, 700.0], **kwargs)


def _costa_mars(turbidity):
    c = COSTA2021_MARS_HULST
    return costa2021_aerosol_coefficients(
        c["wavelength_nm"],
        refractive_index=c["refractive_index"],
        distribution=Monodisperse(radius_um=c["radius_um"]),
        number_density_per_m3=c["number_density_per_m3"],
        turbidity=turbidity,
        junge_exponent=c["junge_exponent"],
        k_factor=c["k_factor"],
    )


def test_costa_mars_cosmoscout_parameters_are_consistent():
    with warnings.catch_warnings():
        warnings.simplefilter("error", ScatteringExceedsExtinctionWarning)
        out = _costa_mars(COSTA2021_MARS_HULST["turbidity"])
    assert not out.scattering_exceeds_extinction.any()
    assert np.all(out.beta_abs_per_m > 0)


def test_costa_mars_paper_turbidity_warns():
    # Costa et al.'s T in [2, 10]: beta_sca > beta_ext (as CosmoScout VR reports); values unchanged.
    with pytest.warns(ScatteringExceedsExtinctionWarning, match=r"albedo > 1.*turbidity=2.0"):
        out = _costa_mars(2.0)
    assert out.scattering_exceeds_extinction.all()
    assert np.all(out.beta_abs_per_m < 0)
