"""Accuracy at default settings against an independent brute-force computation.

The reference shares nothing with dustoptics but the physics: single-sphere
miepython at every node, the modified gamma density from scipy.stats, tails cut
by scipy's own quantiles at 1e-10 of the sixth moment, and dense composite
Gauss-Legendre panels uniform in radius (16 nodes per panel, panels 0.25 wide in
size parameter, i.e. ~64 nodes per unit of x).  Its own convergence is checked
by halving the panels in the cheap case.

Targets (issue: "Accuracy to reach"): phase function within 1e-4 relative at
every angle, <C_ext>, <C_sca> within 1e-6 relative and g within 1e-6, for
k >= 0.001 at default settings.
"""

from __future__ import annotations

import miepython
import numpy as np
import pytest
from scipy import stats
from scipy.special import roots_legendre

import dustoptics as do

THETA = np.linspace(0.0, 180.0, 181)


def brute_force(
    m: complex, r_eff: float, v_eff: float, wavelength_nm: float, *, dx_panel: float = 0.25
):
    shape = (1 - 2 * v_eff) / v_eff
    scale = r_eff * v_eff
    r_lo = stats.gamma(shape + 2).ppf(1e-10) * scale
    r_hi = stats.gamma(shape + 6).isf(1e-10) * scale
    k = 2 * np.pi / (wavelength_nm * 1e-3)
    n_panels = int(np.ceil((r_hi - r_lo) * k / dx_panel))
    edges = np.linspace(r_lo, r_hi, n_panels + 1)
    t, w = roots_legendre(16)
    half = 0.5 * np.diff(edges)
    r = ((edges[:-1] + half)[:, None] + half[:, None] * t).ravel()
    wr = (half[:, None] * w).ravel() * stats.gamma(shape, scale=scale).pdf(r)
    mu = np.cos(np.deg2rad(THETA))
    mm = np.conj(m)  # miepython's n - ik
    s_ext = s_sca = s_gsca = 0.0
    p_sum = np.zeros_like(mu)
    for rj, wj in zip(r, wr):
        x = k * rj
        qext, qsca, _, g = miepython.efficiencies_mx(mm, x)
        p = miepython.i_unpolarized(mm, x, mu, norm="one")  # 2 pi int p dmu = 1
        area = np.pi * rj * rj
        s_ext += wj * qext * area
        s_sca += wj * qsca * area
        s_gsca += wj * qsca * area * g
        p_sum += wj * qsca * area * p
    # The density is normalized to 1 over (0, inf): <C> = int n C dr needs no
    # division by the truncated number integral.
    return {"cext": s_ext, "csca": s_sca, "g": s_gsca / s_sca, "phase": p_sum / s_sca}


def check(t: do.Table, i: int, ref: dict) -> None:
    assert np.max(np.abs(t.phase[i] / ref["phase"] - 1)) <= 1e-4
    assert t.cross_sections.cext_um2[i] == pytest.approx(ref["cext"], rel=1e-6)
    assert t.cross_sections.csca_um2[i] == pytest.approx(ref["csca"], rel=1e-6)
    assert abs(t.g[i] - ref["g"]) <= 1e-6


def test_brute_force_reference_is_converged() -> None:
    """The reference itself: halving its panels changes it by far less than the targets."""
    coarse = brute_force(1.5 + 0.01j, 0.5, 0.1, 440.0)
    fine = brute_force(1.5 + 0.01j, 0.5, 0.1, 440.0, dx_panel=0.125)
    assert np.max(np.abs(coarse["phase"] / fine["phase"] - 1)) < 1e-7
    assert abs(coarse["csca"] / fine["csca"] - 1) < 1e-9


@pytest.mark.parametrize(
    ("m", "r_eff", "v_eff", "wavelengths", "dx_panel"),
    [
        (1.5 + 0.01j, 0.5, 0.1, [440.0, 680.0], 0.25),
        ("mars", 1.6, 0.2, [550.0], 0.25),
        # k = 0.001: resonances are narrow enough that the reference itself needs
        # half-width panels (at 0.25 its <C_ext> is 1.3e-6 low; at 0.125 it agrees
        # with dustoptics to 2e-8).
        (1.52 + 0.001j, 1.0, 0.3, [600.0], 0.125),
    ],
)
def test_default_settings_reach_targets(m, r_eff, v_eff, wavelengths, dx_panel) -> None:
    dust = do.mars_dust() if m == "mars" else m
    t = do.compute_optics(dust, do.ModifiedGamma(r_eff_um=r_eff, v_eff=v_eff), wavelengths, THETA)
    for i, wl in enumerate(wavelengths):
        check(
            t, i, brute_force(complex(t.refractive_index[i]), r_eff, v_eff, wl, dx_panel=dx_panel)
        )


@pytest.mark.slow
def test_storm_dust_reaches_targets() -> None:
    """r_eff = 4 um, v_eff = 0.3 (dust-storm particles), k = 0.003, at 830 nm."""
    m = 1.52 + 0.003j
    t = do.compute_optics(m, do.ModifiedGamma(r_eff_um=4.0, v_eff=0.3), [830.0], THETA)
    check(t, 0, brute_force(m, 4.0, 0.3, 830.0))


def test_nonabsorbing_spheres_reach_1e3() -> None:
    """k = 0: resonances are arbitrarily narrow and no quadrature resolves them
    all, so the target is 1e-3 for the phase function (README, Accuracy).
    Measured for this case: 4e-4 (phase), 1e-5 (<C_ext>) against the reference
    at 0.0625-wide panels."""
    m = 1.5 + 0.0j
    t = do.compute_optics(m, do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2), [550.0], THETA)
    ref = brute_force(m, 1.0, 0.2, 550.0, dx_panel=0.125)
    assert np.max(np.abs(t.phase[0] / ref["phase"] - 1)) <= 1e-3
    assert t.cross_sections.cext_um2[0] == pytest.approx(ref["cext"], rel=1e-4)
    assert abs(t.g[0] - ref["g"]) <= 1e-4
