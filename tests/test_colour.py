"""CIE 1931 table, solar spectrum, XYZ <-> sRGB, and RGB channels of a table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _data import data_path

from dustoptics.colour import (
    SRGB_PRIMARIES_XY,
    SRGB_WHITE_D65_XY,
    XYZ_TO_LINEAR_SRGB,
    channel_phase,
    channel_weights,
    cmf_cie1931,
    linear_srgb_to_xyz,
    rgb_to_xyz_matrix,
    single_scattering_residual,
    solar_irradiance_astm_g173,
    spectrum_to_xyz,
    srgb_encode,
    xyz_to_display,
    xyz_to_linear_srgb,
    xyz_weights,
)
from dustoptics.io import read_hdf5

TABLES = Path(__file__).resolve().parents[1] / "tables"


def _shared_csv(name: str) -> np.ndarray:
    path = data_path("spectra", name)
    lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    return np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])


def test_cmf_table_equals_cvrl_5nm_tabulation() -> None:
    """At every 5 nm node the shipped 1 nm table equals CVRL's ciexyz31 5 nm table.

    Reference: the CVRL 5 nm tabulation as Bruneton's precomputed_atmospheric_scattering
    carries it (atmosphere/constants.h), read independently of our file.
    """
    ref = _shared_csv("cie1931_2deg_cmf_bruneton_5nm.csv")
    np.testing.assert_array_equal(cmf_cie1931(ref[:, 0]), ref[:, 1:4])


def test_cmf_identities_of_the_standard() -> None:
    # CIE 015: ybar(555 nm) = 1 exactly (the photopic peak normalization), and
    # the three integrals are equal by construction of XYZ (equal-energy white E
    # at x = y = 1/3, to the table's rounding: about 1e-3).
    assert cmf_cie1931(555.0)[1] == 1.0
    lam = np.arange(360.0, 831.0, 1.0)
    xyz = spectrum_to_xyz(lam, np.ones(lam.size))
    np.testing.assert_allclose(xyz / xyz.sum(), 1.0 / 3.0, atol=1e-3)
    with pytest.raises(ValueError, match=r"wavelength_nm must lie within \[360, 830\] nm.*got 359"):
        cmf_cie1931([359.0, 500.0])


def test_solar_spectrum_bins() -> None:
    """ASTM G173 ETR bin means as Bruneton's demo lists them (tests/data, read independently)."""
    ref = _shared_csv("solar_irradiance_bruneton_pas_astmg173.csv")
    np.testing.assert_array_equal(solar_irradiance_astm_g173(ref[:, 0]), ref[:, 1])
    np.testing.assert_array_equal(solar_irradiance_astm_g173(ref[:, 0] + 9.99), ref[:, 1])
    with pytest.raises(ValueError, match=r"\[360, 840\) nm.*got 840"):
        solar_irradiance_astm_g173(840.0)


def _fine_integral(lam: np.ndarray, spectrum: np.ndarray, *, solar: bool) -> np.ndarray:
    """Independent quadrature: midpoint rule on 0.01 nm cells (the solar bin edges are cell edges)."""
    n = round(float(lam[-1] - lam[0]) * 100)
    mid = lam[0] + (np.arange(n) + 0.5) * (lam[-1] - lam[0]) / n
    f = np.interp(mid, lam, spectrum)[:, None] * cmf_cie1931(mid)
    if solar:
        f *= solar_irradiance_astm_g173(mid)[:, None]
    return f.sum(axis=0) * (lam[-1] - lam[0]) / n


@pytest.mark.parametrize("solar", [False, True])
def test_xyz_weights_against_fine_quadrature(solar: bool) -> None:
    lam = np.array([360.0, 371.5, 400.0, 455.0, 512.25, 600.0, 700.0, 830.0])
    spectrum = 1.0 + 0.5 * np.sin(lam / 37.0)
    got = xyz_weights(lam, illuminant="astm-g173" if solar else "equal-energy") @ spectrum
    ref = _fine_integral(lam, spectrum, solar=solar)
    # Midpoint error at 0.01 nm on kinks every nm: O(h^2), far below 1e-7.
    np.testing.assert_allclose(got, ref, rtol=1e-7)


def test_spectrum_to_xyz_broadcasts() -> None:
    lam = np.arange(360.0, 831.0, 10.0)
    spectra = np.stack([np.ones(lam.size), lam / 500.0, (lam / 500.0) ** -4])
    xyz = spectrum_to_xyz(lam, spectra.reshape(3, 1, lam.size))
    assert xyz.shape == (3, 1, 3)
    np.testing.assert_allclose(xyz[1, 0], spectrum_to_xyz(lam, spectra[1]), rtol=1e-15)
    with pytest.raises(ValueError, match="spectrum must have the wavelength"):
        spectrum_to_xyz(lam, np.ones(lam.size - 1))
    with pytest.raises(ValueError, match=r"holds only \(xbar"):
        spectrum_to_xyz(lam[10:], np.ones(lam.size - 10))


def test_srgb_matrix_and_encoding() -> None:
    """IEC 61966-2-1's printed 4-digit matrix (as Bruneton's constants.h lists it), and its derivation."""
    path = data_path("spectra", "xyz_to_linear_srgb_bruneton.csv")
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    printed = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:4]])
    np.testing.assert_array_equal(XYZ_TO_LINEAR_SRGB, printed)
    # Derived from the primaries and D65 (x, y = 0.3127, 0.3290): equal to the printed
    # matrix to its rounding (measured 3.7e-4, in the green row).
    derived = np.linalg.inv(rgb_to_xyz_matrix(SRGB_PRIMARIES_XY, SRGB_WHITE_D65_XY))
    np.testing.assert_allclose(derived, printed, atol=4e-4)
    rgb = np.array([[0.2, 0.5, 0.9], [1.0, 0.0, 0.3]])
    np.testing.assert_allclose(xyz_to_linear_srgb(linear_srgb_to_xyz(rgb)), rgb, atol=1e-15)
    # IEC 61966-2-1 transfer function: the break point 0.0031308 -> 0.04045 (both branches
    # meet there to 1e-7), 0 -> 0, 1 -> 1.
    np.testing.assert_allclose(srgb_encode([0.0, 0.0031308, 1.0]), [0.0, 0.04045, 1.0], atol=1e-7)
    # D65 white (x, y = 0.3127, 0.3290, Y = 1) at exposure 0.5: linear 0.5 each.
    d65 = np.array([0.3127 / 0.3290, 1.0, (1 - 0.3127 - 0.3290) / 0.3290])
    np.testing.assert_allclose(xyz_to_display(d65, exposure=0.5, encoding="linear"), 0.5, rtol=4e-4)
    np.testing.assert_allclose(xyz_to_display(4 * d65), 1.0)  # clipped at display white
    with pytest.raises(ValueError, match="linear must lie in"):
        srgb_encode([1.5])
    with pytest.raises(ValueError, match="exposure must be > 0"):
        xyz_to_display(d65, exposure=0.0)


def test_channel_weights_modes_and_errors() -> None:
    lam = np.arange(360.0, 831.0, 10.0)
    wl = channel_weights(lam, mode="wavelengths")
    np.testing.assert_array_equal(wl.centroid_nm, [680.0, 550.0, 440.0])
    xyz = channel_weights(lam, mode="cie1931-xyz")
    assert np.all(xyz.weights >= 0)
    assert xyz.centroid_nm[0] > xyz.centroid_nm[1] > xyz.centroid_nm[2]
    srgb = channel_weights(lam, mode="linear-srgb-astmg173")
    np.testing.assert_allclose(srgb.weights.sum(axis=1), 1.0, rtol=1e-14)
    assert srgb.weights.min() < 0  # the sRGB matching functions' negative lobes
    assert srgb.centroid_nm[0] > srgb.centroid_nm[1] > srgb.centroid_nm[2]
    with pytest.raises(ValueError, match="mode must be one of 'wavelengths', 'cie1931-xyz'"):
        channel_weights(lam, mode="cie1931")
    with pytest.raises(ValueError, match="channels_nm is only for mode='wavelengths'"):
        channel_weights(lam, mode="cie1931-xyz", channels_nm=(680, 550, 440))
    with pytest.raises(ValueError, match=r"channels_nm\[0\] = 900 nm is outside"):
        channel_weights(lam, mode="wavelengths", channels_nm=(900, 550, 440))


def test_channel_phase_weights_by_scattering() -> None:
    lam = np.arange(360.0, 831.0, 10.0)
    ch = channel_weights(lam, mode="linear-srgb-astmg173")
    rng = np.random.default_rng(1)
    phase = rng.random((lam.size, 5))
    csca = 1.0 + rng.random(lam.size)
    p = channel_phase(ch, phase, csca_um2=csca)
    # Identity: channel scattering times channel phase is the channel of csca * P.
    np.testing.assert_allclose(
        (ch.weights @ csca)[:, None] * p, ch.weights @ (csca[:, None] * phase), rtol=1e-13
    )


def test_single_scattering_residual_of_blue_moons_table() -> None:
    """Spectral vs RGB colour of once-scattered sunlight, Blue Moon's dust table, 0-180 deg.

    Identity: linear sRGB weighted by the sun reproduces the spectral colour to
    rounding.  The other two modes are not colour spaces of a white-balanced
    renderer; their residuals (measured with this test's inputs: three
    wavelengths 680/550/440 nm, median 0.027, max 0.082 of Y; CIE XYZ bands put
    in R, G, B, median 0.086, max 0.153 of Y) are what the sRGB mode removes.
    """
    table = read_hdf5(TABLES / "blue-moons" / "blue-moons.nc")
    args = (table.wavelength_nm, table.theta_deg, table.phase)
    exact = single_scattering_residual(
        *args, mode="linear-srgb-astmg173", csca_um2=table.quantity("csca_um2")
    )
    assert exact.max_relative_error < 1e-13
    three = single_scattering_residual(
        *args, mode="wavelengths", csca_um2=table.quantity("csca_um2")
    )
    bands = single_scattering_residual(
        *args, mode="cie1931-xyz", csca_um2=table.quantity("csca_um2")
    )
    assert three.max_relative_error > 1e-2
    assert bands.max_relative_error > 1e-2
    # A grey table: every mode is exact (the sun's own colour), whatever its channels.
    grey = np.repeat(table.phase[20:21], table.wavelength_nm.size, axis=0)
    for mode in ("wavelengths", "cie1931-xyz", "linear-srgb-astmg173"):
        r = single_scattering_residual(table.wavelength_nm, table.theta_deg, grey, mode=mode)
        assert r.max_relative_error < 1e-13, mode
