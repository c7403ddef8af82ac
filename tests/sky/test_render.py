"""dustoptics.sky.render: the spherical horizon, the Legendre recurrence, budgets and progress."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from scipy.integrate import quad

from dustoptics._validation import BudgetError
from dustoptics.atmosphere import sets
from dustoptics.sky import _progress, render
from dustoptics.sky.medium import Medium
from dustoptics.sky.orders import normalized_legendre, solve_orders

R_EARTH_M = 6371e3
H_MOLECULES_M = 8000.0


@pytest.fixture(scope="module")
def thin_earth() -> Medium:
    # Air alone, 1e-4 of its density: optically thin (tau 1e-5 at 550 nm).
    atm = sets.earth_atmosphere(wavelength_nm=[550.0], ozone=None)
    mol = atm.constituent("molecules")
    aer = atm.constituent("aerosols")
    thin = sets.Atmosphere(
        name="thin-earth",
        planet_radius_m=atm.planet_radius_m,
        atmosphere_radius_m=atm.atmosphere_radius_m,
        constituents=(
            sets.Constituent(
                role="molecules",
                table=mol.table.replace(
                    cross_sections={
                        "number_density_per_m3": mol.table.cross_sections.number_density_per_m3
                        * 1e-4
                    }
                ),
                profile=mol.profile,
            ),
            sets.Constituent(
                role="aerosols",
                table=aer.table.replace(cross_sections={"number_density_per_m3": 1e-30}),
                profile=aer.profile,
            ),
        ),
        sun_distance_m=atm.sun_distance_m,
        refractivity=atm.refractivity,
    )
    return Medium.from_atmosphere(thin, n_streams=4)


def test_the_horizon_of_a_thin_shell_is_the_chord_column(thin_earth: Medium) -> None:
    # Optically thin: L = sigma_sca P(Theta) int N ds along the view.  Along
    # the horizontal line of sight from the ground the column is finite in
    # the spherical shell (Chapman's grazing column, about
    # sqrt(pi R / 2 H) = 35 vertical columns), where a plane-parallel column
    # would be infinite; integrated here independently of the renderer.
    medium = thin_earth
    field = solve_orders(medium, sun_zenith_deg=45.0)
    got = render.line_of_sight_radiance(
        medium,
        field,
        view_zenith_deg=np.array([0.0, 60.0, 90.0]),
        view_azimuth_deg=np.full(3, 90.0),
        observer_altitude_m=0.0,
    )[:, 0]
    top = R_EARTH_M + medium.top_altitude_m

    def column(mu: float) -> float:
        s_end = -R_EARTH_M * mu + math.sqrt((R_EARTH_M * mu) ** 2 + top**2 - R_EARTH_M**2)

        def density(s: float) -> float:
            h = math.sqrt(R_EARTH_M**2 + s * s + 2 * R_EARTH_M * s * mu) - R_EARTH_M
            return math.exp(-h / H_MOLECULES_M)

        return quad(density, 0.0, s_end, limit=400, points=[3e5])[0]

    n0 = medium.number_density_per_m3[0]
    sigma = medium.sigma_sca_m2[0, 0]
    mu_sun = math.cos(math.radians(45.0))
    columns = []
    for k, vz in enumerate((0.0, 60.0, 90.0)):
        mu = math.cos(math.radians(vz))
        cos_t = mu * mu_sun + math.sqrt(1 - mu * mu) * math.sqrt(1 - mu_sun**2) * math.cos(
            math.pi / 2
        )
        phase = medium.tables[0].phase_at(np.array([math.degrees(math.acos(cos_t))]))[0, 0]
        expect = sigma * n0 * phase * column(mu)
        assert got[k] == pytest.approx(expect, rel=3e-3), (vz, got[k], expect)
        columns.append(got[k] / (sigma * n0 * phase))
    # Chapman: the horizon's column is about sqrt(pi R / 2 H) vertical columns.
    assert columns[2] / columns[0] == pytest.approx(
        math.sqrt(math.pi * R_EARTH_M / (2 * H_MOLECULES_M)), rel=0.02
    )


@pytest.mark.parametrize("mu", [-1.0, -0.999, -0.3, 0.0, 0.5, 0.99999, 1.0])
def test_packed_legendre_recurrence_is_the_normalized_legendre(mu: float) -> None:
    n_mom, n_modes = 24, 20
    packed = np.empty(int(render._packed_index(n_mom, n_modes)[-1]))
    render._normalized_legendre_packed(mu, n_mom, n_modes, packed)
    full = normalized_legendre(n_mom, np.array(mu))
    offsets = render._packed_index(n_mom, n_modes)
    for m in range(n_modes):
        np.testing.assert_allclose(packed[offsets[m] : offsets[m + 1]], full[m, m:], atol=1e-13)


def test_too_many_lines_of_sight_are_refused_before_work(
    thin_earth: Medium, monkeypatch: pytest.MonkeyPatch
) -> None:
    field = solve_orders(thin_earth, sun_zenith_deg=45.0)
    n = 1000
    # A work budget of half the estimate must refuse before the integration starts.
    cost = render.estimate_render_cost(thin_earth, n_rays=n, n_rows=n, n_path=render.N_PATH)
    monkeypatch.setattr(render, "WORK_BUDGET", cost.work / 2)
    with pytest.raises(BudgetError, match="at most about .* lines of sight") as info:
        render.line_of_sight_radiance(
            thin_earth,
            field,
            view_zenith_deg=np.linspace(0.0, 90.0, n),
            view_azimuth_deg=np.zeros(n),
        )
    assert "allow_large=True" in str(info.value)


def test_progress_is_reported_after_the_quiet_seconds(
    thin_earth: Medium, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_progress, "QUIET_SECONDS", 0.0)
    stream = io.StringIO()
    field = solve_orders(thin_earth, sun_zenith_deg=45.0, progress=stream)
    render.line_of_sight_radiance(
        thin_earth,
        field,
        view_zenith_deg=np.linspace(0.0, 80.0, 40),
        view_azimuth_deg=np.zeros(40),
        progress=stream,
    )
    text = stream.getvalue()
    assert "sky: orders of scattering:" in text
    assert "sky: lines of sight: 40 of 40" in text
    assert text.rstrip().endswith(" s")
    # Silent without a stream, and during the quiet seconds.
    monkeypatch.setattr(_progress, "QUIET_SECONDS", 60.0)
    quiet = io.StringIO()
    solve_orders(thin_earth, sun_zenith_deg=45.0, progress=quiet)
    assert quiet.getvalue() == ""
