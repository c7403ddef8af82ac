"""The radiative-transfer fields (scattering matrix, expansion coefficients,
backscatter, mass coefficients, quadrature moments) in to_xarray and in the
saved netCDF file, read back exactly, and by netCDF-C (netCDF4) as labelled
variables with an ``order`` dimension."""

from __future__ import annotations

import numpy as np
import pytest

import dustoptics as do


@pytest.fixture(scope="module")
def table() -> do.Table:
    return do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        [440.0, 680.0],
        np.linspace(0.0, 180.0, 37),
        rtol=1e-3,
        polarization=True,
        expansion=True,
        particle_density_kg_m3=do.MARS_DUST_DENSITY_KG_M3,
        name="mars-rt",
    )


def test_fields_present(table: do.Table) -> None:
    assert table.matrix.f12.shape == table.phase.shape
    assert table.expansion.alpha1.shape[0] == 2 and np.all(table.expansion.alpha1[:, 0] == 1.0)
    np.testing.assert_allclose(table.expansion.alpha1[:, 1], 3 * table.g, atol=1e-6)
    # kappa_ext = <C_ext> / (rho <V>), [m2 kg-1] from [um2] / ([kg m-3] [um3]).
    expected = (
        table.cross_sections.cext_um2
        * 1e-12
        / (2500.0 * table.cross_sections.mean_volume_um3 * 1e-18)
    )
    np.testing.assert_allclose(table.mass_ext_m2_per_kg, expected, rtol=1e-14)
    # The quadrature's own moments agree with the analytic ones to its tail cut.
    d = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    np.testing.assert_allclose(table.quadrature.r_eff_quadrature_um, d.r_eff_um, rtol=1e-6)
    np.testing.assert_allclose(table.quadrature.v_eff_quadrature, d.v_eff, rtol=1e-5)
    np.testing.assert_allclose(
        table.quadrature.mean_volume_quadrature_um3, d.mean_volume_um3, rtol=1e-6
    )


def test_to_xarray_round_trip(table: do.Table) -> None:
    ds = table.to_xarray()
    assert ds.alpha1.dims == ("wavelength_nm", "order")
    assert ds.f34.dims == ("wavelength_nm", "theta_deg")
    assert ds.mass_ext_m2_per_kg.attrs["units"] == "m2 kg-1"
    assert do.Table.from_xarray(ds).equals(table)


def test_saved_file_round_trip_and_netcdf_c(table: do.Table, tmp_path) -> None:
    netCDF4 = pytest.importorskip("netCDF4")
    path = table.save(tmp_path / "rt.nc")
    back = do.open_table(path)
    assert back.equals(table)
    np.testing.assert_array_equal(back.expansion.beta2, table.expansion.beta2)
    with netCDF4.Dataset(path) as nc:
        assert nc.variables["alpha2"].dimensions == ("wavelength_nm", "order")
        assert nc.dimensions["order"].size == table.expansion.alpha1.shape[1]
        np.testing.assert_array_equal(nc.variables["f12"][:], table.matrix.f12)
        assert nc.variables["cback_um2"].units == "um2"
