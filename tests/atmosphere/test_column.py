"""Tests of dustoptics.atmosphere.column: density profiles, optical depth <-> number density."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from dustoptics.atmosphere.column import (
    BRUNETON2017_OZONE,
    BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3,
    KINK_RELATIVE_SLOPE,
    ExponentialProfile,
    FixedFractionProfile,
    MultiModalProfile,
    PiecewiseLinearProfile,
    mass_loading_kg_m2,
    number_density_from_optical_depth,
    optical_depth,
    sample_profile,
)


def test_exponential_column_length_is_scale_height():
    p = ExponentialProfile(scale_height_m=11000.0)
    assert p.column_length_m() == 11000.0  # int_0^inf exp(-z/H) dz = H
    # Truncated column, against numerical quadrature (scipy.integrate.quad).
    top = 30000.0
    quad, _ = integrate.quad(lambda z: math.exp(-z / 11000.0), 0.0, top)
    assert p.column_length_m(top_altitude_m=top) == pytest.approx(quad, rel=1e-12)
    np.testing.assert_allclose(
        p.relative_density([0.0, 11000.0]), [1.0, math.exp(-1.0)], rtol=1e-15
    )


def test_bruneton_ozone_layer():
    # Bruneton's comment: the profile's integral is 15 km; 300 DU / 15 km = 5.374e18 m^-3.
    assert BRUNETON2017_OZONE.column_length_m() == pytest.approx(15000.0, rel=1e-15)
    assert pytest.approx(300 * 2.687e20 / 15000.0) == BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3
    # His two layers: h/15km - 2/3 below 25 km, -h/15km + 8/3 above (clamped to [0, 1]).
    z = np.array([0.0, 5000.0, 10000.0, 17500.0, 25000.0, 32500.0, 40000.0, 60000.0])
    bruneton = np.clip(
        np.where(z < 25000.0, z / 15000.0 - 2.0 / 3.0, -z / 15000.0 + 8.0 / 3.0), 0.0, 1.0
    )
    np.testing.assert_allclose(BRUNETON2017_OZONE.relative_density(z), bruneton, atol=1e-15)
    # Half the layer: the rising half holds half the column (symmetric tent).
    assert BRUNETON2017_OZONE.column_length_m(top_altitude_m=25000.0) == pytest.approx(
        7500.0, rel=1e-15
    )


def test_piecewise_linear_undefined_above_nonzero_last_node():
    p = PiecewiseLinearProfile(altitude_m=(0.0, 10000.0), density=(1.0, 0.5))
    assert p.column_length_m(top_altitude_m=10000.0) == pytest.approx(7500.0)
    with pytest.raises(ValueError, match=r"above the last node \(10000 m\).*undefined"):
        p.relative_density([20000.0])
    with pytest.raises(ValueError, match=r"undefined"):
        p.column_length_m()
    with pytest.raises(ValueError, match=r"largest value exactly 1"):
        PiecewiseLinearProfile(altitude_m=(0.0, 1.0), density=(0.5, 0.2))
    with pytest.raises(ValueError, match=r"start at exactly 0 m"):
        PiecewiseLinearProfile(altitude_m=(10.0, 20.0), density=(1.0, 0.0))


def test_multimodal_and_fixed_fraction():
    a, b = ExponentialProfile(scale_height_m=1000.0), ExponentialProfile(scale_height_m=9000.0)
    m = MultiModalProfile(profiles=(a, b), weights=(3.0, 1.0))
    # Weighted mean of the modes (weights normalized to 0.75, 0.25): hand computation.
    assert m.column_length_m() == pytest.approx(0.75 * 1000.0 + 0.25 * 9000.0, rel=1e-15)
    assert m.relative_density([0.0])[0] == pytest.approx(1.0)
    f = FixedFractionProfile(base=ExponentialProfile(scale_height_m=7994.0), fraction=6e-7)
    assert f.column_length_m() == 7994.0
    assert f.number_density_per_m3(base_number_density_per_m3=2.545e25) == pytest.approx(
        6e-7 * 2.545e25
    )
    with pytest.raises(ValueError, match=r"fraction must be in \(0, 1\]; got 2.0"):
        FixedFractionProfile(base=ExponentialProfile(scale_height_m=1.0), fraction=2.0)


@pytest.mark.parametrize("tau", [0.05, 0.3, 1.0, 5.0])
@pytest.mark.parametrize(
    "profile",
    [
        ExponentialProfile(scale_height_m=11000.0),
        BRUNETON2017_OZONE,
        MultiModalProfile(
            profiles=(ExponentialProfile(scale_height_m=2000.0), BRUNETON2017_OZONE),
            weights=(1.0, 2.0),
        ),
    ],
)
def test_tau_to_n0_to_tau_round_trip(tau, profile):
    n0 = number_density_from_optical_depth(optical_depth=tau, cext_um2=7.3, profile=profile)
    assert optical_depth(number_density_per_m3=n0, cext_um2=7.3, profile=profile) == pytest.approx(
        tau, rel=1e-14
    )


def test_n0_hand_computation_and_numerical_column():
    # N0 = tau / (C H): 0.5 / (10e-12 m^2 * 11e3 m).
    n0 = number_density_from_optical_depth(optical_depth=0.5, cext_um2=10.0, scale_height_m=11000.0)
    assert n0 == pytest.approx(0.5 / (10e-12 * 11000.0), rel=1e-15)
    # The optical depth is the integral of N0 rho(z) C over altitude (quadrature, finite top).
    p = ExponentialProfile(scale_height_m=11000.0)
    top = 120000.0
    col, _ = integrate.quad(lambda z: n0 * math.exp(-z / 11000.0) * 10e-12, 0.0, top)
    assert optical_depth(
        number_density_per_m3=n0, cext_um2=10.0, profile=p, top_altitude_m=top
    ) == pytest.approx(col, rel=1e-12)


def test_mass_loading():
    # Hand computation: N0 H <V> rho_p with <V> in m^3.
    m = mass_loading_kg_m2(
        number_density_per_m3=2e6,
        scale_height_m=11000.0,
        mean_volume_um3=30.0,
        particle_density_kg_m3=2500.0,
    )
    assert m == pytest.approx(2e6 * 11000.0 * 30.0e-18 * 2500.0, rel=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (
            {"optical_depth": -0.5, "cext_um2": 1.0, "scale_height_m": 1e4},
            r"optical_depth must be > 0; got -0.5",
        ),
        (
            {"optical_depth": 0.5, "cext_um2": 1.0, "scale_height_m": -1e4},
            r"scale_height_m must be > 0 m; got -10000.0",
        ),
        (
            {"optical_depth": 0.5, "cext_um2": 0.0, "scale_height_m": 1e4},
            r"cext_um2 must be > 0 um\^2",
        ),
        ({"optical_depth": 0.5, "cext_um2": 1.0}, r"exactly one of profile or scale_height_m"),
    ],
)
def test_bad_column_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        number_density_from_optical_depth(**kwargs)


def test_sample_profile_for_cosmoscout():
    s = sample_profile(
        ExponentialProfile(scale_height_m=8000.0), top_altitude_m=80000.0, n_altitudes=1024
    )
    assert s.altitude_m.size == 1024 and s.relative_density.max() == 1.0 and s.peak == 1.0
    assert np.all(np.diff(s.relative_density) < 0)
    # A grid that misses the ozone peak at 25 km: samples rescaled, peak < 1 reported.
    o = sample_profile(BRUNETON2017_OZONE, top_altitude_m=80000.0, n_altitudes=1000)
    assert o.relative_density.max() == 1.0
    assert o.peak < 1.0
    np.testing.assert_allclose(
        o.relative_density * o.peak, BRUNETON2017_OZONE.relative_density(o.altitude_m)
    )
    with pytest.raises(ValueError, match=r"n_altitudes must be an integer >= 2"):
        sample_profile(BRUNETON2017_OZONE, top_altitude_m=80000.0, n_altitudes=1)
    with pytest.raises(ValueError, match=r"zero everywhere"):
        sample_profile(BRUNETON2017_OZONE, top_altitude_m=5000.0)
    with pytest.raises(ValueError, match=r"altitude_m must be >= 0 m"):
        ExponentialProfile(scale_height_m=1.0).relative_density([-1.0])


def test_a_densely_sampled_smooth_profile_has_no_inner_edges() -> None:
    # An exponential sampled every 100 m changes slope by 1 - exp(-h/H) per node (1.3 %
    # at H 7.75 km): no node is a kink, the last node ends the profile.
    z = np.linspace(0.0, 120e3, 1201)
    smooth = PiecewiseLinearProfile(altitude_m=z.tolist(), density=np.exp(-z / 7750.0).tolist())
    assert smooth.edges_m() == (120e3,)
    # Two exponentials joined at 40 km (Viking's fit, CalcMySky's mars.atmo): the slope
    # drops by 1 - 0.09 / 0.129 = 30 % there, a real kink at the node nearest the join.
    rho = np.where(z < 40e3, np.exp(-0.129e-3 * z), np.exp(-0.09e-3 * z) * math.exp(-39e-3 * 40))
    joined = PiecewiseLinearProfile(altitude_m=z.tolist(), density=(rho / rho.max()).tolist())
    assert joined.edges_m() == (40e3, 120e3)
    # A kink of more than KINK_RELATIVE_SLOPE is an edge, one of less is not.
    for change, edges in (
        (1.5 * KINK_RELATIVE_SLOPE, (1e3, 2e3)),
        (0.5 * KINK_RELATIVE_SLOPE, (2e3,)),
    ):
        d = (1.0, 0.5, 0.5 - 0.5 * (1.0 - change))
        assert PiecewiseLinearProfile(altitude_m=(0.0, 1e3, 2e3), density=d).edges_m() == edges
