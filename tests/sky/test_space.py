"""The limb seen from space against single scattering and the column's peak."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import dustoptics as do
from dustoptics.atmosphere import sets
from dustoptics.sky import Medium
from dustoptics.sky.space import LimbRadiance, limb_radiance

WL = [440.0, 670.0]


@pytest.fixture(scope="module")
def dust() -> do.Table:
    return do.compute_optics(
        do.mars_dust(), do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2), wavelength_nm=WL
    )


def _thin(atm: sets.Atmosphere, factor: float) -> sets.Atmosphere:
    return sets.Atmosphere(
        name="thin",
        planet_radius_m=atm.planet_radius_m,
        atmosphere_radius_m=atm.atmosphere_radius_m,
        constituents=tuple(
            sets.Constituent(
                role=c.role,
                table=c.table.replace(
                    cross_sections={
                        "number_density_per_m3": c.table.cross_sections.number_density_per_m3
                        * factor
                    }
                ),
                profile=c.profile,
            )
            for c in atm.constituents
        ),
        sun_distance_m=atm.sun_distance_m,
        refractivity=atm.refractivity,
    )


def test_thin_limb_is_single_scattering_along_the_chord(dust: do.Table) -> None:
    # tau -> 0: L = sum_c sigma_sca,c N0_c P_c(beta) int rho_c ds over the
    # chord through the shell (no attenuation, no second order), with the
    # chord integral computed here from the profiles on a fine grid.
    atm = _thin(sets.mars_atmosphere(dust_table=dust, optical_depth=0.5), 1e-5)
    medium = Medium.from_atmosphere(atm)
    h = np.array([2e3, 10e3, 30e3, 60e3])
    beta = 90.0
    limb = limb_radiance(
        medium,
        sun_view_angle_deg=beta,
        tangent_altitude_m=h,
        limb_angle_deg=np.array([0.0]),
        ground_albedo=0.0,
    )
    r_p, r_top = atm.planet_radius_m, atm.atmosphere_radius_m
    expect = np.zeros((h.size, len(WL)))
    for i, hi in enumerate(h):
        r_t = r_p + hi
        half = np.sqrt(r_top**2 - r_t**2)
        s = np.linspace(-half, half, 400_001)
        z = np.sqrt(r_t**2 + s**2) - r_p
        for c in atm.constituents:
            col = np.trapezoid(c.profile.relative_density(np.minimum(z, r_top - r_p)), s)
            t = c.table
            if t.cross_sections is None or not np.any(t.cross_sections.csca_um2 > 0):
                continue
            sca = t.cross_sections.csca_um2 * 1e-12 * t.cross_sections.number_density_per_m3
            expect[i] += sca * col * t.phase_at(np.array([beta]))[:, 0]
    got = limb.radiance[:, 0, :]
    np.testing.assert_allclose(got, expect, rtol=5e-3)
    # Thin: brightest where the chord's column peaks (the lowest tangent point).
    assert np.all(np.diff(got, axis=0) < 0)


def test_dusty_limb_saturates_where_the_chord_is_opaque(dust: do.Table) -> None:
    # Mars with tau 0.5: a chord grazing the ground has an optical depth of
    # ~20, so the limb there is no longer proportional to its column: from
    # 21 km down to 1 km the column grows ~6-fold, the radiance (measured)
    # by 13 % at 440 nm.  Optically thin, the two ratios are equal.
    atm = sets.mars_atmosphere(dust_table=dust, optical_depth=0.5)
    medium = Medium.from_atmosphere(atm)
    h = np.array([1e3, 21e3])
    limb = limb_radiance(
        medium, tangent_altitude_m=h, limb_angle_deg=np.array([0.0]), ground_albedo=0.2
    )
    r = medium.planet_radius_m + h
    tau_chord = 2 * np.einsum(
        "cx,c,ch->xh",
        medium.sigma_ext_m2,
        medium.number_density_per_m3,
        medium.slant.columns(r, np.zeros(2)),
    )
    assert tau_chord[0, 0] > 10  # opaque near the ground
    column_ratio = tau_chord[0, 0] / tau_chord[0, 1]
    radiance_ratio = limb.radiance[0, 0, 0] / limb.radiance[1, 0, 0]
    assert 1.0 < radiance_ratio < 0.5 * column_ratio, (radiance_ratio, column_ratio)


def test_limb_bad_input(dust: do.Table) -> None:
    atm = sets.mars_atmosphere(dust_table=dust, optical_depth=0.5)
    medium = Medium.from_atmosphere(atm)
    with pytest.raises(ValueError, match="limb_angle_deg"):
        limb_radiance(medium, limb_angle_deg=np.array([150.0]))
    with pytest.raises(ValueError, match="tangent_altitude_m"):
        limb_radiance(medium, tangent_altitude_m=np.array([-5.0]))
    with pytest.raises(ValueError, match="sun_view_angle_deg"):
        limb_radiance(medium, sun_view_angle_deg=0.0)


def _layered_limb(planet_radius_m: float) -> LimbRadiance:
    """A limb whose radiance depends on the tangent altitude only (exponential, 10 km)."""
    wl = np.linspace(360.0, 830.0, 48)
    h = np.linspace(0.0, 100e3, 101)
    psi = np.arange(-30.0, 30.01, 1.0)
    shape = np.exp(-h / 10e3)[:, None, None] * np.ones((1, psi.size, wl.size))
    return LimbRadiance(
        name="layered",
        wavelength_nm=wl,
        tangent_altitude_m=h,
        limb_angle_deg=psi,
        radiance=0.1 * shape,
        sun_view_angle_deg=90.0,
        field_sun_zenith_deg=np.array([90.0]),
        n_orders=1,
        error_estimate=0.0,
        tol=1e-4,
        planet_radius_m=planet_radius_m,
    )


def test_the_limb_view_follows_the_planets_curvature() -> None:
    r_m = 3389.5e3
    limb = _layered_limb(r_m)
    xyz, (left, right, bottom, top) = limb.view_xyz(width=801, height=400, half_angle_deg=15.0)
    assert right == pytest.approx(r_m / 1e3 * np.sin(np.radians(15.0)))
    u = np.linspace(left, right, 802)[:-1] + (right - left) / 801 / 2
    v = top - (np.arange(400) + 0.5) / 400 * (top - bottom)
    y_ref = limb.xyz()[:, 0, 1]
    for col in (400, 600, 790):  # the centre, and farther along the arc
        for h_km in (5.0, 20.0, 50.0):
            # The pixel nearest the point at altitude h above the curved ground.
            v_h = np.sqrt((r_m / 1e3 + h_km) ** 2 - u[col] ** 2) - r_m / 1e3
            row = int(np.argmin(np.abs(v - v_h)))
            rho = np.hypot(r_m / 1e3 + v[row], u[col])
            want = np.interp((rho - r_m / 1e3) * 1e3, limb.tangent_altitude_m, y_ref)
            assert xyz[row, col, 1] == pytest.approx(want, rel=1e-9)
    # Below the ground at the arc's ends and above the top: nothing.
    assert xyz[-1, 0, 1] == 0.0 and xyz[0, 400, 1] == 0.0


def test_the_limb_exposure_clips_nothing() -> None:
    from dustoptics import colour

    limb = _layered_limb(3389.5e3)
    e = limb.default_exposure()
    assert np.max(e * colour.xyz_to_linear_srgb(limb.xyz())) == pytest.approx(1.0, rel=1e-12)
    with pytest.raises(ValueError, match="half_angle_deg"):
        limb.view_xyz(half_angle_deg=45.0)
    unknown = dataclasses.replace(limb, planet_radius_m=0.0)
    with pytest.raises(ValueError, match="planet_radius_m"):
        unknown.view_xyz()


def test_limb_budget_refused_before_the_medium_is_built(
    dust: do.Table, monkeypatch: pytest.MonkeyPatch
) -> None:
    from dustoptics._validation import BudgetError
    from dustoptics.sky import orders
    from dustoptics.sky.medium import MediumOptics
    from dustoptics.sky.space import check_limb_cost

    atm = sets.mars_atmosphere(dust_table=dust, optical_depth=0.5)
    medium = Medium.from_atmosphere(atm)
    optics = MediumOptics.from_atmosphere(atm, budget_only=True)
    # The numbers the budget reads (the truncation to rounding: fewer moments
    # projected), so the same estimates as the medium's.
    for name in ("sigma_ext_m2", "sigma_sca_m2", "number_density_per_m3"):
        assert np.array_equal(getattr(optics, name), getattr(medium, name))
    np.testing.assert_allclose(optics.truncation, medium.truncation, rtol=1e-12, atol=0)
    full = MediumOptics.from_atmosphere(atm)
    assert np.array_equal(full.chi, medium.chi)  # the medium's own code
    assert np.array_equal(optics.vertical_optical_depth(), medium.vertical_optical_depth())
    ref = orders.estimate_orders_cost(medium, n_layers=orders.N_LAYERS, tol=1e-4)
    cost = orders.estimate_orders_cost(optics, n_layers=orders.N_LAYERS, tol=1e-4)
    assert (cost.work, cost.memory_bytes, cost.orders) == (ref.work, ref.memory_bytes, ref.orders)

    def no_medium(*args: object, **kwargs: object) -> Medium:
        raise AssertionError("the medium was built before the budget was checked")

    monkeypatch.setattr(Medium, "from_atmosphere", no_medium)
    check_limb_cost(atm)  # within the budget
    many = np.linspace(0.0, 90e3, 2000)
    with pytest.raises(BudgetError, match="lines of sight"):
        check_limb_cost(atm, tangent_altitude_m=many, n_path=100_000)
    with pytest.raises(BudgetError, match="lines of sight"):
        limb_radiance(atm, tangent_altitude_m=many, n_path=100_000)
    with pytest.raises(AssertionError, match="before the budget"):
        limb_radiance(atm, tangent_altitude_m=np.array([10e3]), limb_angle_deg=np.array([0.0]))
