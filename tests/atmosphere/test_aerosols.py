"""OPAC's aerosol types by dustoptics' Mie, the Earth's aerosol controls and the default sky."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from dustoptics.atmosphere import aerosols
from dustoptics.atmosphere.sets import (
    DEFAULT_EARTH_AEROSOL,
    check_earth_aerosol,
    earth_atmosphere,
    earth_atmosphere_kobe2026,
)

# ------------------------------------------------------------------ components


@pytest.mark.parametrize(
    ("name", "rh"),
    [("waso", 80), ("inso", 0), ("soot", 0), ("ssam", 80), ("miam", 0), ("suso", 80)],
)
def test_component_cross_sections_match_opac(name: str, rh: int) -> None:
    """<C_ext> and the albedo by dustoptics' Mie against OPAC's own, shipped beside the indices.

    OPAC (Hess et al. 1998) computed these with its own Mie code from the same size
    distributions and indices; its numbers are printed to 4 digits: 0.3 % on <C_ext>,
    0.002 on the albedo.
    """
    comp = aerosols.aerosol_component(name, relative_humidity_percent=rh)
    wl = [350.0, 550.0, 800.0]
    table = aerosols._component_table(name, comp.relative_humidity_percent, tuple(wl), (0.0, 180.0))
    rows = np.searchsorted(comp.refractive_index.wavelength_nm, wl)
    assert table.cross_sections is not None
    ours = (
        table.cross_sections.cext_um2 * comp.fraction_within_bounds
    )  # OPAC counts the whole log-normal
    np.testing.assert_allclose(ours, comp.opac_cext_um2[rows], rtol=3e-3)
    np.testing.assert_allclose(table.ssa, comp.opac_ssa[rows], atol=2e-3)


def test_one_mode_against_miepython() -> None:
    """The insoluble mode by an independent quadrature of miepython's efficiencies.

    Log-normal in ln r, truncated at OPAC's radii, 4000 midpoints in ln r: <C_ext> and
    <C_sca> to 0.2 % (the sum's own error is below 0.05 %).
    """
    miepython = pytest.importorskip("miepython")
    comp = aerosols.aerosol_component("inso")
    wl_nm = 550.0
    m = complex(comp.refractive_index(wl_nm))
    edges = np.linspace(math.log(comp.r_min_um), math.log(comp.r_max_um), 4001)
    ln_r = 0.5 * (edges[1:] + edges[:-1])
    r = np.exp(ln_r)
    s = math.log(comp.sigma_g)
    w = np.exp(-0.5 * ((ln_r - math.log(comp.mode_radius_um)) / s) ** 2)
    w /= w.sum()
    x = 2 * math.pi * r / (wl_nm * 1e-3)
    eff = np.array([miepython.efficiencies_mx(np.conj(m), xi)[:2] for xi in x])
    qext, qsca = eff[:, 0], eff[:, 1]
    cext = float(np.sum(w * qext * math.pi * r**2))
    csca = float(np.sum(w * qsca * math.pi * r**2))
    table = aerosols._component_table("inso", 0, (wl_nm,), (0.0, 180.0))
    assert table.cross_sections is not None
    assert table.cross_sections.cext_um2[0] == pytest.approx(cext, rel=2e-3)
    assert table.cross_sections.csca_um2[0] == pytest.approx(csca, rel=2e-3)


# ------------------------------------------------------------------ types


@pytest.mark.parametrize("name", list(aerosols.AEROSOL_TYPES))
def test_angstrom_exponents_as_hess_table5(name: str) -> None:
    """Angstrom exponents 350-500 and 500-800 nm within 0.01 of Hess et al.'s Table 5 (80 %).

    Table 5 prints two decimals (0.005) and includes the free troposphere above the mixing
    layer, which the mixing layer alone leaves out: 0.01.  Measured: within 0.006 for all ten.
    """
    kind = aerosols.AEROSOL_TYPES[name]
    table = aerosols.aerosol_table(
        name, wavelength_nm=[350.0, 500.0, 800.0], theta_deg=[0.0, 180.0]
    )
    a1 = aerosols.angstrom_exponent(table, wavelength_nm=(350.0, 500.0))
    a2 = aerosols.angstrom_exponent(table, wavelength_nm=(500.0, 800.0))
    assert a1 == pytest.approx(kind.table5_angstrom[0], abs=0.01)
    assert a2 == pytest.approx(kind.table5_angstrom[1], abs=0.01)


def test_mixture_is_the_number_weighted_sum() -> None:
    """<C_ext> of a type is sum_i (N_i / N) F_i <C_ext>_i; the phase function stays normalized.

    F_i: the share of component i's log-normal within OPAC's radius bounds.
    """
    wl = (440.0, 550.0)
    table = aerosols.aerosol_table("continental-average", wavelength_nm=wl)
    kind = aerosols.AEROSOL_TYPES["continental-average"]
    theta = tuple(aerosols.aerosol_theta_deg().tolist())
    expected = sum(
        n
        / kind.total_number_density_per_cm3
        * aerosols.aerosol_component(c).fraction_within_bounds
        * aerosols._component_table(c, 80 if c == "waso" else 0, wl, theta).cross_sections.cext_um2
        for c, n in kind.number_density_per_cm3.items()
    )
    np.testing.assert_allclose(table.cross_sections.cext_um2, expected, rtol=1e-12)
    mu = np.cos(np.radians(table.theta_deg))
    norm = -2 * math.pi * np.trapezoid(table.phase, mu, axis=1)
    np.testing.assert_allclose(norm, 1.0, atol=2e-3)
    assert table.cross_sections.number_density_per_m3 == pytest.approx(15300.4e6)


# ------------------------------------------------------------------ the Earth


def _tau(atm, wavelength_nm: float) -> float:
    c = atm.constituent("aerosols")
    top = atm.atmosphere_radius_m - atm.planet_radius_m
    cext = np.interp(wavelength_nm, c.table.wavelength_nm, c.table.cross_sections.cext_um2)
    return float(
        c.table.cross_sections.number_density_per_m3
        * cext
        * 1e-12
        * c.profile.column_length_m(top_altitude_m=top)
    )


def test_default_earth_is_a_clear_day() -> None:
    """The default: continental average, vertical optical depth 0.1 at 550 nm (computed there)."""
    atm = earth_atmosphere(wavelength_nm=[450.0, 550.0, 650.0])
    assert atm.constituent("aerosols").table.name == f"opac-{DEFAULT_EARTH_AEROSOL}"
    assert _tau(atm, 550.0) == pytest.approx(0.1, rel=1e-12)


@pytest.mark.parametrize(("tau", "nm"), [(0.3, 550.0), (0.2, 500.0), (0.05, 520.0)])
def test_optical_depth_at_its_wavelength(tau: float, nm: float) -> None:
    """The requested depth at its wavelength, also between grid rows (computed exactly there)."""
    grid = [450.0, 500.0, 550.0, 650.0]
    atm = earth_atmosphere(wavelength_nm=grid, aerosol_optical_depth=tau, aerosol_reference_nm=nm)
    c = atm.constituent("aerosols")
    exact = aerosols.aerosol_table(
        DEFAULT_EARTH_AEROSOL, wavelength_nm=[nm], theta_deg=[0.0, 180.0]
    )
    top = atm.atmosphere_radius_m - atm.planet_radius_m
    got = (
        c.table.cross_sections.number_density_per_m3
        * exact.cross_sections.cext_um2[0]
        * 1e-12
        * c.profile.column_length_m(top_altitude_m=top)
    )
    # Two Mie computations, each converged to 1e-5 in <C_ext> (different angle grids).
    assert got == pytest.approx(tau, rel=1e-4)


def test_turbidity_is_preetham_optical_depth() -> None:
    """T -> beta = 0.04608365822050 T - 0.04586025928522, tau = beta 0.55^-1.3 (Preetham A.3)."""
    beta = 0.04608365822050 * 3.0 - 0.04586025928522
    assert aerosols.preetham_optical_depth(3.0) == pytest.approx(beta * 0.55**-1.3, rel=1e-14)
    atm = earth_atmosphere(wavelength_nm=[450.0, 550.0], turbidity=3.0)
    assert _tau(atm, 550.0) == pytest.approx(beta * 0.55**-1.3, rel=1e-12)


def test_kobe_stays_by_name() -> None:
    """Kobe's constant coefficients by name, unchanged (optical depth 0.0027 at every wavelength)."""
    atm = earth_atmosphere_kobe2026()
    assert atm.constituent("aerosols").table.name == "kobe2026-aerosols"
    kobe = earth_atmosphere(wavelength_nm=[450.0, 550.0], aerosol="kobe2026")
    assert _tau(kobe, 550.0) == pytest.approx(2e-6 / 0.9 * 1200.0, rel=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"aerosol": "fog"}, "aerosol must be one of"),
        ({"aerosol_optical_depth": 0.1, "turbidity": 2.0}, "not both"),
        ({"aerosol_optical_depth": 0.0}, r"aerosol_optical_depth must be > 0"),
        ({"aerosol_optical_depth": 6.0}, r"<= 5"),
        ({"turbidity": 1.0}, r"turbidity must be > 1"),
        ({"turbidity": 11.0}, r"<= 10"),
        ({"aerosol_reference_nm": 200.0}, "250-2500"),
        ({"aerosol_relative_humidity_percent": 60}, "relative_humidity_percent must be one of"),
    ],
)
def test_refused_before_any_work(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        check_earth_aerosol(**kwargs)
    with pytest.raises(ValueError, match=match):
        earth_atmosphere(**kwargs)


# ------------------------------------------------------------------ the CLI


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["sky", "earth", "--aerosol", "fog"], "unknown aerosol 'fog'"),
        (["sky", "earth", "--aerosol-optical-depth", "0.1", "--turbidity", "2"], "not both"),
        (["sky", "earth", "--aerosol-optical-depth", "0.1@100"], "250-2500 nm"),
        (["sky", "earth", "--aerosol-optical-depth", "9"], "<= 5"),
        (["sky", "earth", "--turbidity", "0.5"], "> 1 and <= 10"),
        (["build", "earth", "--turbidity", "2", "--aerosol-optical-depth", "0.2"], "not both"),
        (["build", "mars", "--aerosol", "desert"], "--aerosol changes nothing"),
        (["build", "earth-kobe2026", "--turbidity", "3"], "--turbidity changes nothing"),
    ],
)
def test_cli_refuses(argv: list[str], message: str, tmp_path) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "dustoptics.cli", *argv, "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 2
    assert message in out.stderr
    assert "Traceback" not in out.stderr
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ the default sky


def test_default_sky_between_cie_clear_sky_and_preetham() -> None:
    """Luminance 5 deg above the horizon over the zenith's, Sun 60 deg, 90 deg from it.

    The two published clear skies disagree there by a factor 2.3: CIE 12 (standard clear
    sky) gives 1.10, Preetham et al. at the same optical depth (T 1.99) 2.48.  A physical
    sky at optical depth 0.1 belongs between them; Kobe's nearly aerosol-free set (optical
    depth 0.0027) does not (3.1, above both).  Measured: 1.71 (1.72 with Penndorf air).
    """
    from dustoptics.sky import daylight
    from dustoptics.sky.medium import Medium
    from dustoptics.sky.scene import sky_radiance

    sky = sky_radiance(Medium.from_atmosphere(earth_atmosphere()), sun_elevation_deg=60.0)
    y = sky.xyz()[..., 1]
    ours = float(sky._interpolate(y[..., None], 85.0, 90.0)[0]) / float(np.mean(y[0]))
    cie12 = float(
        daylight.cie_relative_luminance(
            12, view_zenith_deg=85.0, view_azimuth_deg=90.0, sun_zenith_deg=30.0
        )
    )
    pre = float(
        daylight.preetham_relative_luminance(
            daylight.preetham_turbidity(0.1),
            view_zenith_deg=85.0,
            view_azimuth_deg=90.0,
            sun_zenith_deg=30.0,
        )
    )
    assert cie12 < ours < pre


def test_cie_and_preetham_formulas() -> None:
    """Identities: 1 at the zenith; CIE 12's gradation at the horizon 1 / (1 - exp(-0.32))."""
    from dustoptics.sky import daylight

    for t in (11, 12, 13):
        assert float(
            daylight.cie_relative_luminance(
                t, view_zenith_deg=0.0, view_azimuth_deg=0.0, sun_zenith_deg=40.0
            )
        ) == pytest.approx(1.0)
    # Sun at the zenith: chi = Z, so L(90)/L(0) = f(90 deg) phi(90) / (f(0) phi(0)).
    a, b, c, d, e = daylight.CIE_CLEAR_SKIES[12]
    f0 = 1 + c * (1 - math.exp(d * math.pi / 2)) + e
    expected = 1.0 / (f0 * (1 + a * math.exp(b)))
    got = float(
        daylight.cie_relative_luminance(
            12, view_zenith_deg=90.0, view_azimuth_deg=0.0, sun_zenith_deg=0.0
        )
    )
    assert got == pytest.approx(expected, rel=1e-12)
    assert float(
        daylight.preetham_relative_luminance(
            2.0, view_zenith_deg=0.0, view_azimuth_deg=0.0, sun_zenith_deg=40.0
        )
    ) == pytest.approx(1.0)
    assert daylight.preetham_turbidity(aerosols.preetham_optical_depth(2.5)) == pytest.approx(2.5)
