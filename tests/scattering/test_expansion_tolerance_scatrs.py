"""The expansion coefficients' own tolerance (rtol / 100, as the cross-sections'):
at default settings the Mars dust's six coefficient sets agree with scatrs' at
rtol 1e-9 to 1e-6 (issue 30 item 4), at 440 and 680 nm.

scatrs expands in Wigner d-functions: its beta1 and beta2 have the opposite
sign of ours (generalized spherical functions P^l_02 = -d^l_02; see
:mod:`dustoptics.scattering.expansion`), and it normalizes alpha1_0 = 1 as we do.
"""

from __future__ import annotations

import numpy as np
import pytest

import dustoptics as do

KEYS = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")
WL_NM = np.array([440.0, 680.0])
R_EFF_UM, V_EFF = 1.6, 0.2


def test_default_coefficients_within_1e_6_of_scatrs_at_rtol_1e_9() -> None:
    scatrs = pytest.importorskip("scatrs")
    material = do.mars_dust()
    m = material(WL_NM)
    ensemble = scatrs.Ensemble(
        scatrs.Sphere(scatrs.refractive.Table((WL_NM * 1e-3).tolist(), list(m))),
        scatrs.Gamma(effective_radius=R_EFF_UM, effective_variance=V_EFF),
    )
    theirs = ensemble.compute(WL_NM * 1e-3, greek="all", rtol=1e-9).greek
    t = do.compute_optics(
        material,
        do.ModifiedGamma(r_eff_um=R_EFF_UM, v_eff=V_EFF),
        WL_NM,
        [0.0, 180.0],
        expansion=True,
    )
    # The coefficients' own tolerance: rtol / 100 (rtol 1e-4 by default).
    assert t.expansion is not None and t.expansion.expansion_error_estimate is not None
    assert np.all(t.expansion.expansion_error_estimate <= 1e-4 / 100)
    assert t.provenance.quadrature["expansion_rtol"] == pytest.approx(1e-6)
    for i in range(WL_NM.size):
        for key in KEYS:
            ours = t.quantity(key)[i]
            ref = np.asarray(getattr(theirs, key))[i]
            sign = -1.0 if key.startswith("beta") else 1.0
            n = min(ours.size, ref.size)
            worst = np.max(np.abs(ours[:n] - sign * ref[:n]))
            assert worst <= 1e-6, (key, WL_NM[i], worst)
            # Orders beyond the shorter series are below the tolerance in the other.
            assert np.max(np.abs(ref[n:]), initial=0.0) <= 1e-6
            assert np.max(np.abs(ours[n:]), initial=0.0) <= 1e-6


def test_the_phase_function_and_cross_sections_stay_those_of_rtol() -> None:
    """Only the coefficients are refined further: the phase function, the matrix
    and the cross-sections of a table with the expansion are those without it
    (on 1,801 angles both sum at Gauss angles, as the expansion needs)."""
    dist = do.ModifiedGamma(r_eff_um=R_EFF_UM, v_eff=V_EFF)
    theta = np.linspace(0.0, 180.0, 1801)
    plain = do.compute_optics(do.mars_dust(), dist, WL_NM, theta, polarization=True, workers=1)
    full = do.compute_optics(
        do.mars_dust(), dist, WL_NM, theta, polarization=True, expansion=True, workers=1
    )
    for key in ("phase", "f12", "f33", "f34", "cext_um2", "csca_um2", "g"):
        np.testing.assert_array_equal(full.quantity(key), plain.quantity(key), err_msg=key)
    assert full.diagnostics is not None and full.diagnostics.expansion_panels is not None
    # More panels for the coefficients than for the phase function where they needed them.
    extra = [
        len(e) - len(p)
        for e, p in zip(full.diagnostics.expansion_panels, full.diagnostics.panels, strict=True)
    ]
    assert min(extra) >= 0 and max(extra) > 0
