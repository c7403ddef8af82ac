"""compare_tables: identities, the seed-vs-physical weighting, grid checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dustoptics.compare import TableComparison, compare_tables
from dustoptics.models import presets
from dustoptics.models.compute import build_table
from dustoptics.table import Table


def _at(name: str, wavelengths_nm: tuple[float, ...]) -> Table:
    """A preset built at some of its wavelengths only.

    Each wavelength is computed independently (compute_optics's contract), so
    these are rows of the full preset table, at a fraction of the cost.
    """
    config = presets.load_preset(name)
    optics = dataclasses.replace(config.optics, wavelengths_nm=wavelengths_nm)
    return build_table(dataclasses.replace(config, optics=optics))


@pytest.fixture(scope="module")
def collienne() -> Table:
    return presets.build_preset("collienne")


@pytest.fixture(scope="module")
def costa() -> Table:
    return presets.build_preset("costa")


def test_a_table_against_itself(costa: Table) -> None:
    c = compare_tables(costa, costa)
    assert isinstance(c, TableComparison)
    np.testing.assert_array_equal(c.forward_peak_ratio, 1.0)
    np.testing.assert_array_equal(c.median_rel_diff, 0.0)
    np.testing.assert_array_equal(c.max_rel_diff, 0.0)
    np.testing.assert_array_equal(c.g_a, c.g_b)
    np.testing.assert_array_equal(c.wavelength_nm, costa.wavelength_nm)
    assert not c.interpolated


def test_swapping_inverts_the_peak_ratio(costa: Table, collienne: Table) -> None:
    ab, ba = compare_tables(costa, collienne), compare_tables(collienne, costa)
    np.testing.assert_allclose(ab.forward_peak_ratio * ba.forward_peak_ratio, 1.0, rtol=1e-15)
    np.testing.assert_array_equal(ab.g_a, ba.g_b)
    # the ratio is the tables' own forward values
    np.testing.assert_array_equal(ab.forward_peak_ratio, collienne.phase[:, 0] / costa.phase[:, 0])
    rel = np.abs(collienne.phase - costa.phase) / costa.phase
    np.testing.assert_array_equal(ab.max_rel_diff, rel.max(axis=1))
    np.testing.assert_array_equal(ab.median_rel_diff, np.median(rel, axis=1))


def test_seed_against_physical_weighting() -> None:
    """BRIEF section 2: at 360 nm the physical forward peak is 67.3 sr^-1 and the
    seed's number-weighted one 28.6 sr^-1 (ratio 2.353); the median difference
    over angles is 20-36 % at 360-680 nm."""
    wavelengths = (360.0, 550.0, 680.0)
    seed, physical = _at("blue-moons-seed", wavelengths), _at("blue-moons", wavelengths)
    with pytest.raises(ValueError, match=r"theta_deg grids differ: 1800 values in a, 1801 in b"):
        compare_tables(seed, physical)
    c = compare_tables(seed, physical, theta_deg=np.linspace(0.0, 180.0, 181))
    assert c.interpolated
    assert c.forward_peak_ratio[0] == pytest.approx(67.3 / 28.6, abs=0.006)  # from 3-digit values
    assert np.all((c.median_rel_diff > 0.18) & (c.median_rel_diff < 0.37)), c.median_rel_diff
    assert np.all(c.g_b > c.g_a)  # weighting by C_sca favours the large, forward-scattering grains


def test_mismatched_wavelengths(costa: Table) -> None:
    fewer = _at("costa", (360.0, 370.0))
    with pytest.raises(ValueError, match=r"wavelength_nm grids differ: 48 values in a, 2 in b"):
        compare_tables(costa, fewer)
    shifted = _at("costa", tuple(float(w) for w in costa.wavelength_nm[:-1]) + (831.0,))
    with pytest.raises(
        ValueError, match=r"wavelength_nm grids differ: first at index 47, 830.0 nm in a, 831.0"
    ):
        compare_tables(costa, shifted)


def test_mismatched_angles_and_bad_theta(costa: Table) -> None:
    config = presets.load_preset("costa")
    coarse = build_table(
        dataclasses.replace(config, optics=dataclasses.replace(config.optics, n_theta=181))
    )
    with pytest.raises(
        ValueError, match=r"theta_deg grids differ: 1801 values in a, 181 in b; pass theta_deg="
    ):
        compare_tables(costa, coarse)
    c = compare_tables(
        costa, coarse, theta_deg=coarse.theta_deg
    )  # coarse grid points are fine-grid points
    np.testing.assert_allclose(c.forward_peak_ratio, coarse.phase[:, 0] / costa.phase[:, 0], rtol=0)
    with pytest.raises(ValueError, match="starting at exactly 0 deg"):
        compare_tables(costa, coarse, theta_deg=[10.0, 20.0])
    with pytest.raises(ValueError, match=r"within \[0, 180\]"):
        compare_tables(costa, coarse, theta_deg=[0.0, 200.0])
    with pytest.raises(TypeError, match="b must be a dustoptics Table"):
        compare_tables(costa, costa.phase)  # type: ignore[arg-type]


def test_text_and_frame(costa: Table, collienne: Table) -> None:
    c = compare_tables(costa, collienne)
    text = c.to_text()
    assert str(c) == text
    lines = text.splitlines()
    assert lines[0] == "b = 'collienne' against a = 'costa' (1801 angles)"
    assert len(lines) == 3 + costa.wavelength_nm.size
    assert len({len(line) for line in lines[1:]}) == 1  # aligned columns
    assert lines[3].split()[0] == "360"
    frame = c.to_frame()
    assert list(frame.columns) == [
        "wavelength_nm",
        "forward_peak_ratio",
        "g_a",
        "g_b",
        "median_rel_diff",
        "max_rel_diff",
    ]
    np.testing.assert_array_equal(frame["max_rel_diff"].to_numpy(), c.max_rel_diff)
    assert not c.max_rel_diff.flags.writeable
