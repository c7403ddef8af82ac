"""The sky solver against a published plane-parallel Rayleigh reference.

DISORT's test problem 2 (Rayleigh scattering, beam source; Stamnes et al.
1988), from the expected values its test driver prints: cdisort (C DISORT,
T. E. Dowling, distributed with libRadtran 2.0), ``disotest.c``
(``$Id: disotest.c 2966 2013-07-24 $``), function ``disort_test02``, cases
2a-2d ("Compare To Ref. SW, Table 1": Sweigart 1970); the same numbers are in
the Fortran DISOTEST.f of DISORT 2.0.  A homogeneous layer of optical
thickness 0.2 or 5, single-scattering albedo 0.5 or 1, pure Rayleigh phase
function ``(3 / 16 pi)(1 + cos^2 Theta)``, black ground, Sun at
``mu0 = 0.080442``, beam flux ``FBEAM = pi``; intensities at the top
(``tau = 0``, upward) and at the bottom (downward) for
``|mu| = 0.981986, 0.538263, 0.018014`` in the azimuth of the beam
(``phi = phi0 = 0``), and the fluxes ``FLUP(top)`` and ``RFLDN(bottom)``.

References
----------
K. Stamnes, S.-C. Tsay, W. Wiscombe and K. Jayaweera, Appl. Opt. 27,
2502-2509 (1988), doi:10.1364/AO.27.002502.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dustoptics.atmosphere import sets
from dustoptics.atmosphere.column import PiecewiseLinearProfile
from dustoptics.sky import Medium, line_of_sight_radiance, solve_orders

MU0 = 0.080442
MU = (0.981986, 0.538263, 0.018014)
# (tau, omega): (UU(top, +mu) for MU, UU(bottom, -mu) for MU, FLUP(top), RFLDN(bottom)),
# all for FBEAM = pi (disotest.c, disort_test02, cases a-d).
DISORT_TEST2 = {
    (0.2, 0.5): (
        (7.86713e-03, 2.11501e-02, 1.61796e-01),
        (7.71897e-03, 2.00778e-02, 2.57685e-02),
        5.35063e-02,
        4.41791e-02,
    ),
    (0.2, 1.0): (
        (1.89387e-02, 4.87120e-02, 3.47678e-01),
        (1.86027e-02, 4.64061e-02, 6.77603e-02),
        1.25561e-01,
        1.06123e-01,
    ),
    (5.0, 0.5): (
        (1.01498e-02, 2.45786e-02, 1.62566e-01),
        (1.70004e-04, 3.97168e-05, 1.32472e-05),
        6.24730e-02,
        2.51683e-04,
    ),
    (5.0, 1.0): (
        (4.92370e-02, 8.26993e-02, 3.64010e-01),
        (1.05950e-02, 7.69337e-03, 3.79276e-03),
        2.25915e-01,
        2.68008e-02,
    ),
}
PLANET_RADIUS_M = 1e11  # plane-parallel to ~1e-7 over a 10 km layer
TOP_M = 10e3


def _rayleigh_layer(tau: float, omega: float) -> Medium:
    # Two identical constituents (the set needs molecules and aerosols), each
    # with half the optical depth, both constant up to the top.
    base = sets.earth_atmosphere(
        wavelength_nm=[550.0],
        ozone=None,
        planet_radius_m=PLANET_RADIUS_M,
        atmosphere_radius_m=PLANET_RADIUS_M + TOP_M,
    )
    mol = base.constituent("molecules").table
    mu = np.cos(np.deg2rad(mol.theta_deg))
    phase = (3.0 / (16.0 * math.pi)) * (1.0 + mu**2)
    cext = mol.cross_sections.cext_um2
    n0 = 0.5 * tau / (cext[0] * 1e-12 * TOP_M)
    table = mol.replace(
        phase=phase[None, :],
        cross_sections={"csca_um2": omega * cext, "number_density_per_m3": float(n0)},
    )
    flat = PiecewiseLinearProfile(altitude_m=[0.0, TOP_M], density=[1.0, 1.0])
    atm = sets.Atmosphere(
        name="disort-test2",
        planet_radius_m=PLANET_RADIUS_M,
        atmosphere_radius_m=PLANET_RADIUS_M + TOP_M,
        constituents=(
            sets.Constituent(role="molecules", table=table, profile=flat),
            sets.Constituent(role="aerosols", table=table, profile=flat),
        ),
        sun_distance_m=base.sun_distance_m,
        refractivity=0.0,
    )
    return Medium.from_atmosphere(atm, n_streams=8)


@pytest.mark.parametrize(("tau", "omega"), list(DISORT_TEST2))
def test_disort_test_problem_2(tau: float, omega: float) -> None:
    up_ref, down_ref, flup_ref, rfldn_ref = DISORT_TEST2[(tau, omega)]
    medium = _rayleigh_layer(tau, omega)
    np.testing.assert_allclose(medium.vertical_optical_depth().sum(), tau, rtol=1e-12)
    field = solve_orders(
        medium,
        sun_zenith_deg=math.degrees(math.acos(MU0)),
        geometry="plane-parallel",
        n_layers=200 if tau < 1 else 1000,
        tol=1e-6,
    )
    mu = np.array(MU)
    # Upward at the top: looking down from just below it; downward at the
    # bottom: looking up.  phi = phi0: the view's azimuth from the Sun is 0.
    top = line_of_sight_radiance(
        medium,
        field,
        view_zenith_deg=180.0 - np.rad2deg(np.arccos(mu)),
        view_azimuth_deg=np.zeros(3),
        observer_altitude_m=TOP_M * (1 - 1e-9),
        n_path=800,
    )[:, 0]
    bottom = line_of_sight_radiance(
        medium,
        field,
        view_zenith_deg=np.rad2deg(np.arccos(mu)),
        view_azimuth_deg=np.zeros(3),
        observer_altitude_m=0.0,
        n_path=800,
    )[:, 0]
    fbeam = math.pi
    # Tolerance: the printed values are DISORT's with NSTR = 16, which at the
    # grazing view mu = 0.018014 are below converged CDISORT (NSTR = 128) by
    # 6.4e-4 (omega 0.5) and 1.3e-3 (omega 1); elsewhere they agree with it to
    # 1e-4.  With tau = 0.2 (200 layers) the solver is within 2.8e-4 of
    # converged CDISORT everywhere (measured), so 4e-4 of the printed values
    # except at the grazing view (1.2e-3).  With tau = 5 the grazing beam
    # (tau / mu0 = 62) dies within the top layers, where the layers of
    # this set-up are thickest and the diffuse source's linear interpolation is
    # coarsest: within 0.6 % of the printed values with 1,000 layers (measured;
    # the first order's source follows the beam exactly, so 200 layers give
    # 1.6 %, 400 give 0.8 %).
    if tau < 1:
        rtol_mu = np.array([4e-4, 4e-4, 1.2e-3])
        rtol_flux = 4e-4
    else:
        rtol_mu = np.full(3, 6e-3)
        rtol_flux = 6e-3
    assert np.all(np.abs(fbeam * top / np.array(up_ref) - 1) < rtol_mu), (top, up_ref)
    assert np.all(np.abs(fbeam * bottom / np.array(down_ref) - 1) < rtol_mu), (bottom, down_ref)
    np.testing.assert_allclose(fbeam * field.flux_up[0, 0], flup_ref, rtol=rtol_flux)
    np.testing.assert_allclose(fbeam * field.flux_down_diffuse[0, -1], rfldn_ref, rtol=rtol_flux)
