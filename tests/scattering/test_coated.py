"""Coated spheres: single spheres against a published case and an independent
implementation, limits, populations, and bad input.

Published case: Bohren & Huffman (1983), Appendix B, sample output of BHCOAT
(lambda = 3.0, core radius 0.171, mantle radius 6.265, m_core = 1.59 + 0.66 i,
m_mantle = 1.409 + 0.1747 i: Q_ext = 2.32803, Q_sca = 1.14341, Q_back =
0.0285099), as transcribed in the MieScattering.jl test suite
(github.com/fekad/MieScattering.jl, test/runtests.jl).

Independent implementation: scatrs 0.3 (PyPI; layered spheres), a test-only
dependency.
"""

from __future__ import annotations

import numpy as np
import pytest

import dustoptics as do
from dustoptics.scattering import mie


def test_bohren_huffman_appendix_b() -> None:
    lam = 3.0
    x_core, x = 2 * np.pi * 0.171 / lam, 2 * np.pi * 6.265 / lam
    s = mie.coated_sphere(
        m_core=1.59 + 0.66j, m_shell=1.409 + 0.1747j, x_core=x_core, x=x, mu=np.array([-1.0])
    )
    assert abs(s.qext - 2.32803) <= 0.5e-5
    assert abs(s.qsca - 1.14341) <= 0.5e-5
    # Q_back = 4 |S1(180)|^2 / x^2 (Bohren & Huffman 1983, p. 122).
    assert abs(4 * abs(s.s1[0]) ** 2 / x**2 - 0.0285099) <= 0.5e-7


CASES = [
    (1.5 + 0.01j, 1.31 + 1e-8j, 2.0, 3.0),  # dust core in water ice
    (1.7 + 0.1j, 1.33, 10.0, 12.0),
    (2.0 + 1.0j, 1.5 + 0.001j, 20.0, 30.0),
    (1.33, 1.6 + 0.5j, 40.0, 60.0),  # strongly absorbing shell (Im m y = 30)
    (1.5 + 0.01j, 1.3, 0.01, 0.02),  # Rayleigh-small
    (1.6, 1.5, 150.0, 200.0),  # lossless, large: D_n(m_c x)'s downward start (issue 30)
]


@pytest.mark.parametrize(("m_core", "m_shell", "x_core", "x"), CASES)
def test_against_scatrs_layered(m_core: complex, m_shell: complex, x_core: float, x: float) -> None:
    """Efficiencies, g and amplitudes S1, S2 (same convention, no conjugation)
    within 1e-9 relative."""
    scatrs = pytest.importorskip("scatrs")
    mu = np.linspace(-1.0, 1.0, 13)
    ours = mie.coated_sphere(m_core=m_core, m_shell=m_shell, x_core=x_core, x=x, mu=mu)
    xs, ms = np.array([x_core, x]), np.array([m_core, m_shell], dtype=complex)
    e = scatrs.layered.efficiencies(xs, ms)
    a = scatrs.layered.amplitudes(xs, ms, mu)
    assert ours.qext == pytest.approx(float(e.q_ext), rel=1e-9)
    assert ours.qsca == pytest.approx(float(e.q_sca), rel=1e-9)
    assert ours.g == pytest.approx(float(e.g), rel=1e-9, abs=1e-12)
    for mine, theirs in ((ours.s1, a.s1), (ours.s2, a.s2)):
        assert np.max(np.abs(mine - np.asarray(theirs))) <= 1e-9 * np.max(np.abs(mine))


def test_limits_are_homogeneous_spheres() -> None:
    """No core: the shell's sphere; the core filling the sphere: the core's."""
    mu = np.linspace(-1, 1, 9)
    shell = mie.single_sphere(m=1.33 + 1e-4j, x=7.0, mu=mu)
    core = mie.single_sphere(m=1.6 + 0.05j, x=7.0, mu=mu)
    tiny = mie.coated_sphere(m_core=1.6 + 0.05j, m_shell=1.33 + 1e-4j, x_core=1e-9, x=7.0, mu=mu)
    full = mie.coated_sphere(m_core=1.6 + 0.05j, m_shell=1.33 + 1e-4j, x_core=7.0, x=7.0, mu=mu)
    np.testing.assert_allclose(tiny.s1, shell.s1, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(full.s1, core.s1, rtol=1e-10, atol=1e-12)
    assert full.qext == pytest.approx(core.qext, rel=1e-12)


def test_population_of_coated_spheres_against_scatrs() -> None:
    """Dust cores (m = 1.5 + 0.01 i) in water-ice shells (m = 1.31), core
    volume 1/8, modified gamma outer radii: <C_ext>, <C_sca>, g and <C_back>
    against scatrs' ensemble of layered spheres (rtol 1e-9)."""
    scatrs = pytest.importorskip("scatrs")
    particle = do.CoatedSphere(core=1.5 + 0.01j, shell=1.31, core_volume_fraction=0.125)
    t = do.compute_optics(
        particle, do.ModifiedGamma(r_eff_um=1.0, v_eff=0.1), [550.0], [0.0, 90.0, 180.0],
        expansion=True,
    )  # fmt: skip
    r = scatrs.Ensemble(
        scatrs.LayeredSphere([1.5 + 0.01j, 1.31], [0.5]),
        scatrs.Gamma(effective_radius=1.0, effective_variance=0.1),
    ).compute(0.55, rtol=1e-9, greek=8, refine_backscatter=True)
    assert t.cross_sections.cext_um2[0] == pytest.approx(float(r.c_ext), rel=1e-6)
    assert t.cross_sections.csca_um2[0] == pytest.approx(float(r.c_sca), rel=1e-6)
    assert t.g[0] == pytest.approx(float(r.g), abs=1e-6)
    assert t.cross_sections.cback_um2[0] == pytest.approx(float(r.c_back), rel=1e-4)
    np.testing.assert_allclose(t.expansion.alpha1[0, :9], np.asarray(r.greek.alpha1)[:9], atol=1e-5)
    assert "coated sphere" in t.provenance.inputs["refractive_index"]["description"]
    again = do.optics.recompute(t.provenance)
    assert again.equals(t)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (
            lambda: do.CoatedSphere(core=1.5, shell=1.3, core_radius_fraction=1.2),
            r"core_radius_fraction must be in \[0, 1\]",
        ),
        (
            lambda: do.CoatedSphere(core=1.5, shell=1.3, core_volume_fraction=-0.1),
            r"core_volume_fraction must be in \[0, 1\]",
        ),
        (lambda: do.CoatedSphere(core=1.5, shell=1.3), "exactly one"),
        (
            lambda: mie.coated_sphere(m_core=1.5, m_shell=1.3, x_core=3.0, x=2.0),
            "cannot be thicker than the particle",
        ),
        (
            lambda: mie.coated_sphere(m_core=1.5 - 0.1j, m_shell=1.3, x_core=1.0, x=2.0),
            "m_core must have n > 0 and k >= 0",
        ),
    ],
)
def test_bad_input(build, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        build()
