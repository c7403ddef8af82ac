"""The ``libradtran`` files, read back by an independent reader written here from the
libRadtran user's guide (option ``aerosol_file explicit``: altitude [km] and layer file, top
line first with NULL; layer rows wavelength [nm], extinction [km-1], single-scattering
albedo, moments; numpy.loadtxt for the rows), and compared with the Table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _rt_table import rt_table

import dustoptics as do
from dustoptics.io import FORMATS, write


@pytest.fixture(scope="module")
def table() -> do.Table:
    return rt_table()


def test_registered() -> None:
    assert "libradtran" in FORMATS


def test_libradtran_files(table: do.Table, tmp_path: Path) -> None:
    paths = write(table, tmp_path, format="libradtran", bottom_km=0.0, top_km=10.0)
    explicit, layer = paths
    # The explicit file, parsed as uvspec does: non-comment lines "z file", top first.
    entries = [ln.split() for ln in explicit.read_text().splitlines() if not ln.startswith("#")]
    assert entries == [["10.0", "NULL"], ["0.0", layer.name]]
    assert (explicit.parent / entries[1][1]).is_file()
    rows = np.loadtxt(layer, ndmin=2)
    np.testing.assert_array_equal(rows[:, 0], table.wavelength_nm)
    # Extinction [km-1] = N [m-3] * cext [um2] * 1e-12 [m2 um-2] * 1e3 [m km-1].
    np.testing.assert_allclose(
        rows[:, 1],
        table.cross_sections.number_density_per_m3 * table.cross_sections.cext_um2 * 1e-12 * 1e3,
        rtol=1e-15,
    )
    np.testing.assert_allclose(rows[:, 1], table.beta_ext_per_m * 1e3, rtol=1e-15)
    np.testing.assert_array_equal(rows[:, 2], table.ssa)
    l_ = np.arange(table.expansion.alpha1.shape[1])
    np.testing.assert_allclose(
        rows[:, 3:], table.expansion.alpha1 / (2 * l_ + 1), rtol=1e-15, atol=0
    )
    assert rows[0, 3] == 1.0
    header = [ln for ln in layer.read_text().splitlines() if ln.startswith("#")]
    assert any(table.provenance.input_hash in ln for ln in header)


def test_refusals(table: do.Table, tmp_path: Path) -> None:
    plain = table.replace(
        expansion=None,
    )
    with pytest.raises(ValueError, match=r"expansion=True"):
        write(plain, tmp_path, format="libradtran")
    with pytest.raises(ValueError, match="number-density-per-m3"):
        write(
            table.replace(cross_sections={"number_density_per_m3": None}),
            tmp_path,
            format="libradtran",
        )
    with pytest.raises(ValueError, match="top_km"):
        write(table, tmp_path, format="libradtran", bottom_km=2.0, top_km=1.0)
    assert list(tmp_path.iterdir()) == []
