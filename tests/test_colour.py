"""CIE 1931 colour-matching functions (Wyman et al. 2013 fit) and band weights."""

from __future__ import annotations

import numpy as np
import pytest
from _shared import shared_path

from dustoptics.colour import band_weights, cmf_cie1931_wyman2013


def _cie_table() -> np.ndarray:
    path = shared_path("reference-data", "spectra", "cie1931_2deg_cmf_bruneton_5nm.csv")
    lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    assert lines[0] == "wavelength_nm,xbar,ybar,zbar"
    return np.loadtxt(lines[1:], delimiter=",")


def test_fit_against_cie_tabulation() -> None:
    """The fit against the CIE's 5 nm tabulation (CVRL ciexyz31, via Bruneton).

    Wyman, Sloan & Shirley show the multi-lobe fit's residuals graphically: a
    few hundredths at most, on functions that peak at 1.0 (x̄, ȳ) and 1.78 (z̄).
    We allow 0.03 absolute (measured: 0.0238, z̄ at 425 nm; 0.0146 x̄; 0.0070 ȳ)
    and 0.2 % in each function's integral over 360-830 nm (measured: 0.09 %).
    """
    table = _cie_table()
    lam, ref = table[:, 0], table[:, 1:4]
    fit = cmf_cie1931_wyman2013(lam)
    assert fit.shape == ref.shape
    assert np.max(np.abs(fit - ref)) < 0.03
    ratio = np.trapezoid(fit, lam, axis=0) / np.trapezoid(ref, lam, axis=0)
    np.testing.assert_allclose(ratio, 1.0, atol=2e-3)
    # Chromaticity of equal-energy white: the CIE data give x = y = z = 1/3 to
    # about 1e-3 by construction; the fit agrees with the table to 1e-3.
    white_fit = fit.sum(axis=0) / fit.sum()
    white_ref = ref.sum(axis=0) / ref.sum()
    np.testing.assert_allclose(white_fit, white_ref, atol=1e-3)


def test_fit_is_positive_on_the_cie_range() -> None:
    # x̄ has a negative lobe at 501.1 nm, but the sum stays positive (0.1 nm grid).
    values = cmf_cie1931_wyman2013(np.linspace(360.0, 830.0, 4701))
    assert np.all(values > 0)


def test_broadcasting_shapes() -> None:
    # ȳ's main lobe peaks at 568.8 nm with amplitude 0.821, its second at 530.9 nm (0.286).
    grid = np.array([[530.9, 568.8], [600.0, 700.0]])
    out = cmf_cie1931_wyman2013(grid)
    assert out.shape == (2, 2, 3)
    np.testing.assert_array_equal(out[1, 0], cmf_cie1931_wyman2013(600.0))
    with pytest.raises(ValueError, match="wavelength_nm must be finite"):
        cmf_cie1931_wyman2013([500.0, np.nan])


def test_band_weights_properties() -> None:
    lam = np.arange(360.0, 831.0, 10.0)
    w = band_weights(lam)
    assert w.weights.shape == (3, lam.size)
    assert np.all(w.weights >= 0)
    np.testing.assert_allclose(w.weights.sum(axis=1), 1.0, rtol=1e-15)
    np.testing.assert_array_equal(w.coverage, [1.0, 1.0, 1.0])
    # Band mean wavelengths: long, middle, short (x̄ > ȳ > z̄), the roles of R, G, B.
    assert w.centroid_nm[0] > w.centroid_nm[1] > w.centroid_nm[2]
    assert w.names == ("xbar", "ybar", "zbar")


def test_band_average_of_linear_spectrum_is_centroid() -> None:
    # q(lambda) = lambda is read exactly by linear interpolation, so its band
    # average is the band's mean wavelength, whatever the grid.
    fine = band_weights(np.arange(360.0, 831.0, 1.0))
    coarse = band_weights(np.array([360.0, 500.0, 600.0, 830.0]))
    np.testing.assert_allclose(coarse.centroid_nm, fine.centroid_nm, rtol=1e-13)
    np.testing.assert_allclose(
        fine.weights @ np.arange(360.0, 831.0, 1.0), fine.centroid_nm, rtol=1e-15
    )


def test_band_average_matches_cie_tabulation() -> None:
    """Band average of a smooth spectrum with the fit vs with the tabulated CMFs.

    q(lambda) = (lambda / 550 nm)^-4 (Rayleigh-like).  Weighted by the 5 nm
    table (trapezoid) and by the fit, the averages agree to 1 %, the size of
    the fit's residuals relative to the functions.
    """
    table = _cie_table()
    lam, ref = table[:, 0], table[:, 1:4]
    q = (lam / 550.0) ** -4
    from_table = np.trapezoid(ref * q[:, None], lam, axis=0) / np.trapezoid(ref, lam, axis=0)
    from_fit = band_weights(lam).weights @ q
    np.testing.assert_allclose(from_fit, from_table, rtol=1e-2)


@pytest.mark.parametrize(
    ("wavelength_nm", "kwargs", "message"),
    [
        ([550.0], {}, "at least two strictly increasing wavelengths"),
        ([550.0, 500.0], {}, "at least two strictly increasing wavelengths"),
        ([900.0, 1000.0], {}, "outside the CIE 1931 observer's 360-830 nm"),
        ([440.0, 680.0], {}, r"holds only \(xbar 0\.93.*min_coverage is 0\.99"),
        ([400.0, 700.0], {"model": "cie1964"}, "model must be one of 'cie1931'"),
        (
            [400.0, 700.0],
            {"min_coverage": 1.5},
            r"min_coverage must be in the closed interval \[0\.0, 1\.0\]",
        ),
    ],
)
def test_band_weights_errors(wavelength_nm, kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        band_weights(wavelength_nm, **kwargs)


def test_grey_spectrum_identity() -> None:
    # A quantity equal at every wavelength has that value in every band.
    lam = np.array([380.0, 420.0, 500.0, 555.0, 640.0, 780.0])
    w = band_weights(lam, min_coverage=0.99)
    rows = np.tile(np.array([0.3, 2.0, 5.5]), (lam.size, 1))
    np.testing.assert_allclose(w.weights @ rows, np.tile([0.3, 2.0, 5.5], (3, 1)), rtol=1e-15)
