"""The scattering matrix of a population: signs, accuracy, and the phase-only path.

Sign convention (Bohren & Huffman 1983, Eq. 4.77, exp(-i w t), m = n + i k):
F12 = (|S2|^2 - |S1|^2) / 2, F33 = Re(S2 S1*), F34 = Im(S2 S1*), all divided
by the same normalization as F11 = (|S1|^2 + |S2|^2) / 2.  Checked against
Bohren & Huffman's own printed sample (Appendix A, p. 482), which states this
convention, and against Wiscombe's MIEV0 Legendre moments of |S1|^2, |S2|^2,
Re(S1 S2*), -Im(S1 S2*) (stated for m = n - i k, whose amplitudes are the
complex conjugates of ours).
"""

from __future__ import annotations

import csv
import json
from decimal import Decimal

import miepython
import numpy as np
import pytest
from _data import data_path
from numpy.polynomial import legendre
from scipy import stats
from scipy.special import roots_legendre

import dustoptics as do
from dustoptics.scattering import expansion

BENCH = ("mie-benchmarks",)


def half_unit(text: str) -> float:
    """Half a unit in the last printed digit."""
    return 0.5 * 10.0 ** Decimal(text.strip()).as_tuple().exponent


def test_bohren_huffman_sample_matrix() -> None:
    """B&H Appendix A, m = 1.55, r = 0.525 um, lambda = 0.6328 um: POL = -S12/S11,
    S33/S11 and S34/S11 at 21 angles, to half a unit of the printed digits
    (6 significant figures), and Q_back = 2.92534 from <C_back>."""
    data = json.loads(
        data_path(*BENCH, "bohren_huffman_bhmie_sample.json").read_text(), parse_float=str
    )
    inputs = data["inputs"]
    rows = data["table"]
    theta = np.array([float(r["theta_deg"]) for r in rows])
    radius = float(inputs["sphere_radius_um"])
    t = do.compute_optics(
        complex(float(inputs["m_real"]), float(inputs["m_imag"])),
        do.Monodisperse(radius_um=radius),
        [float(inputs["wavelength_um"]) * 1e3],
        theta,
        polarization=True,
    )
    for i, row in enumerate(rows):
        for key, value in (
            ("POL_minus_S12_over_S11", -t.matrix.f12[0, i] / t.phase[0, i]),
            ("S33_over_S11", t.matrix.f33[0, i] / t.phase[0, i]),
            ("S34_over_S11", t.matrix.f34[0, i] / t.phase[0, i]),
        ):
            text = row[key]
            # Six significant figures, or the fixed digits of a small value.
            tol = max(half_unit(text), 0.5e-5 * abs(float(text)))
            assert abs(value - float(text)) <= tol + 1e-12, (key, row["theta_deg"], value, text)
    qback = t.cross_sections.cback_um2[0] / (np.pi * radius**2)
    assert abs(qback - float(data["scalars"]["Qback"])) <= half_unit(data["scalars"]["Qback"])


def _miev0_moments(case: int) -> dict[tuple[int, int], str]:
    path = data_path(*BENCH, "miev0_wiscombe_legendre_moments.csv")
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    out = {}
    for row in csv.DictReader(lines):
        if int(row["case"]) == case:
            out[(int(row["moment"]), int(row["k"]))] = row["value"]
    return out


@pytest.mark.parametrize(("case", "x"), [(9, 1.0), (10, 100.0)])
def test_miev0_polarized_legendre_moments(case: int, x: float) -> None:
    """Wiscombe's MIEV0 test cases 9 and 10 (m = 1.33 - 1e-5 i in his convention,
    IPOLZN = 1234): Legendre moments of |S1|^2, |S2|^2, Re(S1 S2*) and
    -Im(S1 S2*), normalized by 4 / (x^2 Q_sca), to 7 significant figures.

    From our coefficients: 4 |S1|^2 / (x^2 Q_sca) = a1 - b1, 4 |S2|^2 / ... =
    a1 + b1, 4 Re(S1 S2*) / ... = a3 and, with his conjugated amplitudes,
    4 (-Im(S1 S2*))_MIEV0 / ... = -4 Im(S2 S1*) / ... = -b2 (a1 = 4 pi F11 etc.).
    """
    wavelength_nm = 1000.0
    t = do.compute_optics(
        1.33 + 1e-5j,
        do.Monodisperse(radius_um=x * wavelength_nm * 1e-3 / (2 * np.pi)),
        [wavelength_nm],
        [0.0, 180.0],
        expansion=True,
    )
    coefficients = np.array(
        [t.quantity(k)[0] for k in ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")]
    )
    n_order = coefficients.shape[1]
    mu, w = roots_legendre(n_order + 8)
    el = expansion.evaluate_matrix(coefficients, np.rad2deg(np.arccos(mu)))
    quantities = {1: el["a1"] - el["b1"], 2: el["a1"] + el["b1"], 3: el["a3"], 4: -el["b2"]}
    reference = _miev0_moments(case)
    assert len(reference) >= 8
    for (moment, k), text in reference.items():
        p = legendre.legval(mu, np.eye(moment + 1)[moment])
        value = 0.5 * np.sum(w * quantities[k] * p)
        tol = 0.5e-6 * abs(float(text)) + 1e-12
        assert abs(value - float(text)) <= tol, (case, moment, k, value, text)


def brute_force_matrix(
    m: complex, r_eff: float, v_eff: float, wavelength_nm: float, theta: np.ndarray
):
    """I, Q, U, V of a modified gamma population from miepython at every node of
    dense uniform Gauss panels (as tests/scattering/test_accuracy.py: 16 nodes
    per 0.25 of size parameter, tails cut at 1e-10 of the sixth moment)."""
    shape = (1 - 2 * v_eff) / v_eff
    scale = r_eff * v_eff
    r_lo = stats.gamma(shape + 2).ppf(1e-10) * scale
    r_hi = stats.gamma(shape + 6).isf(1e-10) * scale
    k = 2 * np.pi / (wavelength_nm * 1e-3)
    edges = np.linspace(r_lo, r_hi, int(np.ceil((r_hi - r_lo) * k / 0.25)) + 1)
    t, w = roots_legendre(16)
    half = 0.5 * np.diff(edges)
    r = ((edges[:-1] + half)[:, None] + half[:, None] * t).ravel()
    wr = (half[:, None] * w).ravel() * stats.gamma(shape, scale=scale).pdf(r)
    mu = np.cos(np.deg2rad(theta))
    total = np.zeros((4, mu.size))
    csca = 0.0
    for rj, wj in zip(r, wr):
        x = k * rj
        # miepython's m = n - i k: its amplitudes are the conjugates of ours.
        s1, s2 = miepython.S1_S2(np.conj(m), x, mu, norm="wiscombe")
        s1, s2 = np.conj(s1), np.conj(s2)
        p1, p2, c = np.abs(s1) ** 2, np.abs(s2) ** 2, s2 * np.conj(s1)
        total += wj * np.array([p1 + p2, p2 - p1, 2 * c.real, 2 * c.imag])
        csca += wj * miepython.efficiencies_mx(np.conj(m), x)[1] * x * x
    return total / (2 * np.pi * csca)


def test_matrix_against_brute_force() -> None:
    """F12, F33, F34 within 1e-4 of F11 at every angle of an independent
    brute-force average (issue 17's accuracy target), at default settings."""
    theta = np.linspace(0.0, 180.0, 181)
    ref = brute_force_matrix(1.5 + 0.01j, 0.5, 0.1, 550.0, theta)
    t = do.compute_optics(
        1.5 + 0.01j, do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1), [550.0], theta, polarization=True
    )
    f11 = ref[0]
    assert np.max(np.abs(t.phase[0] - f11) / f11) <= 1e-4
    for j, key in enumerate(("f12", "f33", "f34"), start=1):
        assert np.max(np.abs(t.quantity(key)[0] - ref[j]) / f11) <= 1e-4, key
    assert t.matrix.matrix_error_estimate[0] <= t.provenance.quadrature["rtol"]
    # Spheres: |F12|, |F33|, |F34| <= F11, and F12^2 + F33^2 + F34^2 <= F11^2.
    assert np.all(
        t.matrix.f12[0] ** 2 + t.matrix.f33[0] ** 2 + t.matrix.f34[0] ** 2
        <= t.phase[0] ** 2 * (1 + 1e-9)
    )


def test_phase_only_path_unchanged_by_the_matrix() -> None:
    """Asking for the matrix refines until every element meets rtol; the phase
    function it returns agrees with the phase-only table within their estimates,
    and the phase-only table has no matrix."""
    d = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    plain = do.compute_optics(1.52 + 0.01j, d, [450.0, 700.0])
    full = do.compute_optics(1.52 + 0.01j, d, [450.0, 700.0], polarization=True)
    assert plain.matrix is None and plain.expansion is None
    bound = plain.quadrature.error_estimate + full.quadrature.error_estimate
    assert np.all(np.max(np.abs(full.phase / plain.phase - 1), axis=1) <= bound)
    cross_bound = (
        plain.quadrature.cross_section_error_estimate + full.quadrature.cross_section_error_estimate
    )
    assert np.all(
        np.abs(full.cross_sections.cext_um2 / plain.cross_sections.cext_um2 - 1) <= cross_bound
    )
    # Forward: S1(0) = S2(0), so F12 = F34 = 0 and F33 = F11.
    assert np.all(np.abs(full.matrix.f12[:, 0]) <= 1e-12 * full.phase[:, 0])
    np.testing.assert_allclose(full.matrix.f33[:, 0], full.phase[:, 0], rtol=1e-12)


def test_backscatter_and_lidar_ratio() -> None:
    """<C_back> = 4 pi P(180) <C_sca> for cross-section weighting (B&H p. 122
    definition; the table's phase function at 180 deg) and S = 4 pi <C_ext> / <C_back>."""
    t = do.compute_optics(1.52 + 0.01j, do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2), [550.0])
    np.testing.assert_allclose(
        t.cross_sections.cback_um2,
        4 * np.pi * t.phase[:, -1] * t.cross_sections.csca_um2,
        rtol=3e-4,
    )
    np.testing.assert_allclose(
        t.lidar_ratio_sr,
        4 * np.pi * t.cross_sections.cext_um2 / t.cross_sections.cback_um2,
        rtol=1e-15,
    )
