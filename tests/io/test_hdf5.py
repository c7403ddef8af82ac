"""Tests for dustoptics.io.hdf5: round trip, netCDF-4 layout (xarray, h5dump), bad files.

One small computed table (3 wavelengths, 181 angles, rtol 1e-3; well under a
second) carries real numbers; a hand-made phase-only table (Rayleigh,
3/(16 pi) (1 + mu^2), brief section 4) covers the optional fields.
"""

from __future__ import annotations

import json
import shutil
import subprocess

import h5py
import numpy as np
import pytest

import dustoptics as do
from dustoptics.io import FORMATS, FormatError
from dustoptics.io.hdf5 import CONVENTIONS, DERIVED, read_hdf5, write_hdf5
from dustoptics.table import UNITS, Table

STORED_PER_WAVELENGTH = (
    "g",
    "cext_um2",
    "csca_um2",
    "error_estimate",
    "cross_section_error_estimate",
)


@pytest.fixture(scope="module")
def table() -> Table:
    optics = do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        wavelength_nm=[440.0, 550.0, 680.0],
        theta_deg=np.linspace(0.0, 180.0, 181),
        rtol=1e-3,
        workers=1,
        name="mars-dust",
    )
    # Meyran's renderer value (brief section 6), as m^-3
    return optics.replace(number_density_per_m3=4.64e8)


@pytest.fixture(scope="module")
def rayleigh() -> Table:
    theta = np.linspace(0.0, 180.0, 37)
    mu = np.cos(np.deg2rad(theta))
    phase = np.tile(3.0 / (16.0 * np.pi) * (1.0 + mu**2), (2, 1))
    return Table(
        name="rayleigh", wavelength_nm=[440.0, 680.0], theta_deg=theta, phase=phase, g=[0.0, 0.0]
    )


@pytest.fixture
def written(table, tmp_path):
    return write_hdf5(table, tmp_path / "t.h5")


# ------------------------------------------------------------------ round trip


def test_round_trip_is_bit_exact_with_provenance(table, written):
    back = read_hdf5(written)
    assert back.equals(table)  # every array bit for bit, scalars, provenance dict
    assert back.provenance.input_hash == table.provenance.input_hash
    assert back.provenance.sources[0].citation == do.mars_dust().citation


def test_phase_only_table_round_trip(rayleigh, tmp_path):
    path = write_hdf5(rayleigh, tmp_path / "r.h5")
    with h5py.File(path, "r") as f:
        assert set(f) == {
            "wavelength_nm",
            "theta_deg",
            "phase",
            "g",
        }  # nothing derived, no cross-sections
    assert read_hdf5(path).equals(rayleigh)


def test_rewrites_are_byte_identical(table, tmp_path):
    first = write_hdf5(table, tmp_path / "a.h5").read_bytes()
    second = write_hdf5(table, tmp_path / "b.h5").read_bytes()
    assert first == second
    with h5py.File(tmp_path / "a.h5", "r") as f:  # and no object carries a timestamp
        for key in ("/", *f):
            info = h5py.h5o.get_info(f[key].id)
            assert (info.ctime, info.mtime, info.atime, info.btime) == (0, 0, 0, 0), key


def test_layout_units_and_compression(table, written):
    with h5py.File(written, "r") as f:
        assert f.attrs["Conventions"] == CONVENTIONS
        assert "netCDF-4 compatible" in f.attrs["format_description"]
        assert f.attrs["input_hash"] == table.provenance.input_hash
        assert json.loads(f.attrs["provenance"]) == table.provenance.to_dict()
        assert json.loads(f.attrs["software"]) == dict(table.provenance.software)
        for key in f:
            assert f[key].attrs["units"] == UNITS[key][0], key
            assert f[key].attrs["long_name"] == UNITS[key][1], key
        for key in DERIVED:
            assert f[key].attrs["derived_from"] == DERIVED[key]
        phase = f["phase"]
        assert (phase.compression, phase.shuffle) == ("gzip", True)
        assert [d[0].name for d in phase.dims] == [
            "/wavelength_nm",
            "/theta_deg",
        ]  # attached scales
        assert f["wavelength_nm"].is_scale and f["theta_deg"].is_scale
        assert phase.id.get_storage_size() < phase.nbytes  # compressed
        np.testing.assert_array_equal(f["beta_sca_per_m"][()], table.beta_sca_per_m)


def test_registry_writes_name_h5(table, tmp_path):
    paths = FORMATS["hdf5"](table, tmp_path, overwrite=False)
    assert [p.name for p in paths] == ["mars-dust.h5"]
    assert read_hdf5(paths[0]).equals(table)
    with pytest.raises(FileExistsError, match="mars-dust.h5"):
        FORMATS["hdf5"](table, tmp_path, overwrite=False)


# ------------------------------------------------------------------ other readers


def test_xarray_h5netcdf_reads_labelled_data(table, written):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    with xr.open_dataset(written, engine="h5netcdf") as ds:
        assert ds["phase"].dims == ("wavelength_nm", "theta_deg")
        assert set(ds.coords) == {"wavelength_nm", "theta_deg"}
        assert ds["wavelength_nm"].attrs["units"] == "nm"
        assert ds["theta_deg"].attrs["units"] == "deg"
        assert ds["phase"].attrs["units"] == "sr^-1"
        assert ds["cext_um2"].attrs["units"] == "um^2"
        assert ds.attrs["Conventions"] == CONVENTIONS
        np.testing.assert_array_equal(ds["wavelength_nm"].values, table.wavelength_nm)
        np.testing.assert_array_equal(ds["theta_deg"].values, table.theta_deg)
        np.testing.assert_array_equal(ds["phase"].sel(wavelength_nm=550.0).values, table.phase[1])
        assert float(ds["number_density_per_m3"]) == 4.64e8


def test_h5dump_reads_the_file(table, written):
    if shutil.which("h5dump") is None:
        pytest.skip("hdf5-tools (h5dump) not installed")
    header = subprocess.run(
        ["h5dump", "-H", str(written)], capture_output=True, text=True, check=True
    ).stdout
    assert 'DATASET "phase"' in header and "DATASPACE  SIMPLE { ( 3, 181 ) / ( 3, 181 ) }" in header
    assert 'ATTRIBUTE "DIMENSION_LIST"' in header and 'ATTRIBUTE "units"' in header
    properties = subprocess.run(
        ["h5dump", "-p", "-H", "-d", "/phase", str(written)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "PREPROCESSING SHUFFLE" in properties and "COMPRESSION DEFLATE" in properties
    data = subprocess.run(
        ["h5dump", "-d", "/wavelength_nm", str(written)], capture_output=True, text=True, check=True
    ).stdout
    assert "440, 550, 680" in data


# ------------------------------------------------------------------ refusals and bad files


def test_existing_file_needs_overwrite(table, written):
    before = written.read_bytes()
    with pytest.raises(FileExistsError, match="t.h5 already exists"):
        write_hdf5(table, written)
    assert written.read_bytes() == before
    write_hdf5(table.replace(name="other"), written, overwrite=True)
    assert read_hdf5(written).name == "other"


def test_failure_mid_write_leaves_no_file(table, tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise OSError("simulated disk failure")

    monkeypatch.setattr(h5py.Dataset, "make_scale", broken)  # fails after the file is created
    with pytest.raises(OSError, match="simulated"):
        write_hdf5(table, tmp_path / "out" / "t.h5")
    assert not (tmp_path / "out").exists()


def test_truncated_file(written):
    data = written.read_bytes()
    written.write_bytes(data[: len(data) // 2])
    with pytest.raises(FormatError, match=r"t\.h5: .*(truncated|damaged)"):
        read_hdf5(written)


def test_not_an_hdf5_file(tmp_path):
    path = tmp_path / "table.h5"
    path.write_text(",440,550\n0.0,1.0,2.0\n")
    with pytest.raises(FormatError, match=r"table\.h5: not a readable HDF5 file"):
        read_hdf5(path)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.h5"):
        read_hdf5(tmp_path / "nope.h5")
    with pytest.raises(FormatError, match="not a regular file"):
        read_hdf5(tmp_path)


def test_other_hdf5_file(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3.0)
    with pytest.raises(FormatError, match=r"other\.h5: missing root attribute 'Conventions'"):
        read_hdf5(path)


def _edit(path, change) -> None:
    with h5py.File(path, "r+") as f:
        change(f)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda f: f.__delitem__("g"), "missing variable 'g'"),
        (lambda f: f.__delitem__("phase"), "missing variable 'phase'"),
        (lambda f: f.attrs.__setitem__("Conventions", "CF-1.8"), "Conventions is 'CF-1.8'"),
        (lambda f: f.attrs.__delitem__("provenance"), "missing root attribute 'provenance'"),
        (lambda f: f.attrs.__setitem__("provenance", "{not json"), "root attribute 'provenance'"),
        (
            lambda f: f.attrs.__setitem__(
                "provenance", f.attrs["provenance"].replace('"r_eff_um":1.6', '"r_eff_um":1.7')
            ),
            "input_hash .* does not match its inputs",
        ),
        (lambda f: f["ssa"].__setitem__(0, 0.5), r"derived variable 'ssa' disagrees .* 440\.0 nm"),
        (lambda f: f["cext_um2"].__setitem__(1, -1.0), "cext_um2 > 0"),
        (lambda f: f.__delitem__("cext_um2"), "cext_um2 and csca_um2 must both be given"),
        (
            lambda f: (f.__delitem__("csca_um2"), f.create_dataset("csca_um2", data=np.ones(2))),
            r"variable 'csca_um2' has shape \(2,\); expected \(3,\)",
        ),
        (
            lambda f: (
                f.__delitem__("g"),
                f.create_dataset("g", data=np.array([b"a", b"b", b"c"])),
            ),
            "variable 'g' must hold floats",
        ),
    ],
)
def test_damaged_content_is_named(written, change, message):
    _edit(written, change)
    with pytest.raises(FormatError, match=rf"t\.h5: .*{message}"):
        read_hdf5(written)
