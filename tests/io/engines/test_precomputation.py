"""The sampling rules of dustoptics.io.engines.precomputation, against hand computations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dustoptics.atmosphere import sets as atm
from dustoptics.atmosphere.column import (
    BRUNETON2017_OZONE,
    ExponentialProfile,
)
from dustoptics.io.engines.precomputation import (
    effective_scale_height_m,
    horizontal_column_m,
    nu_clear_angle_deg,
    nu_interpolation_error,
    precomputation_sampling,
    scattering_density_error,
    scattering_orders,
)


@pytest.fixture(scope="module")
def earth():
    return atm.earth_atmosphere(aerosol="kobe2026")  # the set these figures were measured on


def test_effective_scale_height() -> None:
    # An exponential: sqrt(int rho / int |rho''|) = sqrt(H (1 - e^-T/H) / (H^-1 (1 - e^-T/H))) = H.
    assert effective_scale_height_m(
        ExponentialProfile(scale_height_m=8000.0), top_altitude_m=80e3
    ) == pytest.approx(8000.0, rel=1e-3)
    # Bruneton's ozone tent (10-25-40 km): column 15 km, kinks 1/15, 2/15, 1/15 per km.
    assert effective_scale_height_m(BRUNETON2017_OZONE, top_altitude_m=60e3) == pytest.approx(
        math.sqrt(15e3 / (4.0 / 15e3)), rel=1e-3
    )


def test_horizontal_column() -> None:
    # sqrt(pi R H / 2) for an exponential thin against the radius (Chapman's grazing column).
    r, h = 3390e3, 11100.0
    got = horizontal_column_m(
        ExponentialProfile(scale_height_m=h), planet_radius_m=r, top_altitude_m=120e3
    )
    assert got == pytest.approx(math.sqrt(math.pi * r * h / 2.0), rel=5e-3)


def test_orders_of_a_rayleigh_atmosphere(earth) -> None:
    """Molecules only: m = 0.4 beta sqrt(pi R H / 2) / 2 and the Poisson tail, by hand."""
    from scipy.stats import poisson

    mol = earth.constituent("molecules")
    only_air = atm.Atmosphere(
        name="air",
        planet_radius_m=earth.planet_radius_m,
        atmosphere_radius_m=earth.atmosphere_radius_m,
        constituents=(mol, earth.constituent("aerosols")),
        sun_distance_m=earth.sun_distance_m,
        refractivity=earth.refractivity,
    )
    k, m = scattering_orders(only_air, tolerance=0.005, wavelength_nm=[550.0])
    beta_air = np.interp(550.0, mol.table.wavelength_nm, mol.table.beta_sca_per_m)
    aer = only_air.constituent("aerosols").table
    beta_aer = np.interp(550.0, aer.wavelength_nm, aer.beta_sca_per_m)
    length = lambda h: math.sqrt(math.pi * earth.planet_radius_m * h / 2.0)  # noqa: E731
    m_hand = 0.4 * beta_air * length(8000.0) / 2 + 1.0 * beta_aer * length(1200.0) / 2
    assert m == pytest.approx(m_hand, rel=5e-3)
    k_hand = next(k for k in range(1, 50) if poisson.sf(k, m_hand) / -math.expm1(-m_hand) <= 0.005)
    assert k == k_hand


def test_scattering_density_directions(earth) -> None:
    # Kobe's aerosols (Cornette-Shanks 0.76): 16 x 32 directions integrate the phase function to
    # within a few percent, 32 x 64 to 0.5 %.
    assert scattering_density_error(earth, sample_count=16) > 0.005
    assert scattering_density_error(earth, sample_count=32) <= 0.005
    assert precomputation_sampling(earth).scattering_density_sample_count == 32


def test_nu_error_decreases_and_earth_needs_his_default(earth) -> None:
    errors = [nu_interpolation_error(earth, nu_size=n) for n in (8, 16, 32, 64)]
    assert errors == sorted(errors, reverse=True)
    assert precomputation_sampling(earth).scattering_texture_nu_size == 8


def test_nu_clear_angle_is_the_chosen_ones_and_shrinks_with_nu(earth) -> None:
    chosen = precomputation_sampling(earth, nu_size=16)
    assert nu_clear_angle_deg(earth, nu_size=16) == chosen.nu_clear_angle_deg
    angles = [nu_clear_angle_deg(earth, nu_size=n, nu_tolerance=0.001) for n in (8, 16, 32, 64)]
    assert angles == sorted(angles, reverse=True) and angles[0] > angles[-1]
    assert all(5.0 <= a <= 90.0 for a in angles)
    with pytest.raises(ValueError, match="nu_size must be an integer >= 2"):
        nu_clear_angle_deg(earth, nu_size=1)


def test_given_values_are_checked(earth) -> None:
    with pytest.raises(ValueError, match="smallest that does is 32"):
        precomputation_sampling(earth, scattering_density_sample_count=16)
    with pytest.raises(ValueError, match="num_scattering_orders 3 is too small"):
        precomputation_sampling(earth, num_scattering_orders=3)
    with pytest.raises(TypeError, match="must be an integer"):
        precomputation_sampling(earth, nu_size=16.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="tolerance"):
        precomputation_sampling(earth, tolerance=0.0)
    ok = precomputation_sampling(earth, nu_size=16, num_scattering_orders=12)
    assert (ok.scattering_texture_nu_size, ok.num_scattering_orders) == (16, 12)
    assert ok.to_dict()["num_scattering_orders"] == 12
