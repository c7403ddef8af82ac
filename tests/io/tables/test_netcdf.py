"""Tests for dustoptics.io.tables.netcdf: CF-1.10 netCDF-4 table files, proven against real readers.

One small computed table (3 wavelengths, 181 angles, rtol 1e-3; well under a
second) carries real numbers; a hand-made phase-only table (Rayleigh,
3/(16 pi) (1 + mu^2), brief section 4) and a molecule-like table (cross-sections,
no particle size) cover the optional fields.  The readers the files are proven
against: netCDF4 (netCDF-C), xarray (h5netcdf and netCDF4 engines), h5dump, and
the IOOS compliance checker for CF-1.10.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import dustoptics as do
from dustoptics.io import FORMATS, FormatError, open_table, write_netcdf
from dustoptics.io.tables.netcdf import (
    DIGEST_ATTRIBUTE,
    MAX_VALUES,
    SUFFIXES,
    dataset_digest,
)
from dustoptics.scattering.tabulated_phase import renormalize
from dustoptics.table import DERIVED, SCHEMA, UNITS, Table
from dustoptics.table.conversion import dataset_variables

TABLES = Path(__file__).resolve().parents[3] / "tables"
PRESET_FILES = sorted(TABLES.glob("*/*.nc"))


@pytest.fixture(scope="module")
def table() -> Table:
    t = do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        wavelength_nm=[440.0, 550.0, 680.0],
        theta_deg=np.linspace(0.0, 180.0, 181),
        rtol=1e-3,
        workers=1,
        name="mars-dust",
    )
    # Meyran's renderer value (brief section 6), as m^-3
    return t.replace(cross_sections={"number_density_per_m3": 4.64e8})


@pytest.fixture(scope="module")
def rayleigh() -> Table:
    theta = np.linspace(0.0, 180.0, 37)
    mu = np.cos(np.deg2rad(theta))
    phase = np.tile(3.0 / (16.0 * np.pi) * (1.0 + mu**2), (2, 1))
    return Table(
        name="rayleigh",
        wavelength_nm=[440.0, 680.0],
        theta_deg=theta,
        phase=renormalize(phase, theta_deg=theta),
        g=[0.0, 0.0],
    )


@pytest.fixture
def written(table, tmp_path) -> Path:
    return write_netcdf(table, tmp_path / "t.nc")


def _resign(path: Path) -> None:
    """Recompute the stored digest after an edit: a crafted file, consistent but wrong."""
    with h5py.File(path, "r+") as f:
        variables = {}
        for key in f:
            attrs = {
                k: v.decode() if isinstance(v, bytes) else v
                for k, v in f[key].attrs.items()
                if k not in {"CLASS", "NAME", "DIMENSION_LIST", "REFERENCE_LIST"}
            }
            variables[key] = (np.asarray(f[key][()]), attrs)
        attrs = {k: v.decode() if isinstance(v, bytes) else v for k, v in f.attrs.items()}
        f.attrs[DIGEST_ATTRIBUTE] = dataset_digest(variables, attrs)


def _edit(path: Path, change, *, resign: bool = True) -> None:
    with h5py.File(path, "r+") as f:
        change(f)
    if resign:
        _resign(path)


# ------------------------------------------------------------------ round trips


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_save_and_open_every_suffix_to_the_bit(table, tmp_path, suffix):
    path = table.save(tmp_path / f"t{suffix}")
    back = open_table(path)
    assert back.equals(table)  # every array bit for bit, scalars, provenance
    assert back.quadrature.n_nodes.dtype == np.int64
    np.testing.assert_array_equal(back.refractive_index, table.refractive_index)


def test_phase_only_and_molecule_tables_round_trip(rayleigh, table, tmp_path):
    path = rayleigh.save(tmp_path / "r.nc")
    with h5py.File(path, "r") as f:
        assert set(f) == {"wavelength_nm", "theta_deg", "phase", "g"}  # nothing derived
    assert open_table(path).equals(rayleigh)
    molecule = table.replace(cross_sections={"mean_geometric_cross_section_um2": None}, name="gas")
    back = open_table(molecule.save(tmp_path / "gas.nc"))
    assert back.equals(molecule)
    with h5py.File(tmp_path / "gas.nc", "r") as f:
        # Aerosol standard names only for tables of particles.
        assert "standard_name" not in f["ssa"].attrs and "qext" not in f
        assert f["wavelength_nm"].attrs["standard_name"] == "radiation_wavelength"


def test_writes_are_byte_reproducible_and_carry_no_timestamps(table, tmp_path):
    first = table.save(tmp_path / "a.nc").read_bytes()
    second = table.save(tmp_path / "b.nc").read_bytes()
    assert first == second
    assert table.save(tmp_path / "c.h5").read_bytes() == first  # .h5 is the same format
    with h5py.File(tmp_path / "a.nc", "r") as f:
        for key in ("/", *f):
            info = h5py.h5o.get_info(f[key].id)
            assert (info.ctime, info.mtime, info.atime, info.btime) == (0, 0, 0, 0), key


def test_a_table_rebuilt_from_its_file_provenance_gives_the_same_bytes(table, tmp_path):
    from dustoptics.scattering.optics import recompute

    path = table.save(tmp_path / "a.nc")
    stored = open_table(path)
    again = recompute(stored.provenance, name=stored.name).replace(
        cross_sections={"number_density_per_m3": 4.64e8}
    )
    assert again.save(tmp_path / "b.nc").read_bytes() == path.read_bytes()


@pytest.fixture(scope="module")
def full() -> Table:
    """A table with every optional part: expansion, scattering matrix and derivatives."""
    return do.compute_optics(
        1.5 + 0.01j,
        do.ModifiedGamma(r_eff_um=0.4, v_eff=0.15),
        wavelength_nm=[450.0, 650.0],
        theta_deg=np.linspace(0.0, 180.0, 19),
        rtol=1e-3,
        workers=1,
        expansion=True,
        derivatives=("r_eff_um", "k"),
    )


@pytest.mark.parametrize("which", ["table", "rayleigh", "full"])
def test_the_written_variables_are_the_xarray_datasets(which, request):
    """The writer assembles the dataset without xarray: the same variables, in the same
    order, with the same dimensions, types, values and attributes as Table.to_xarray."""
    t = request.getfixturevalue(which)
    ds = t.to_xarray()
    data, coords = dataset_variables(t)
    assert list(data) == [str(k) for k in ds.data_vars]
    assert list(coords) == [str(k) for k in ds.coords]
    for name, (dims, values, attrs) in {**data, **coords}.items():
        var = ds.variables[name]
        assert dims == var.dims, name
        assert values.dtype == var.values.dtype and values.shape == var.shape, name
        np.testing.assert_array_equal(values, var.values, err_msg=name)
        assert attrs == var.attrs, name
    assert dict(t.global_attributes()) == ds.attrs


def test_writing_a_table_file_imports_no_xarray_pandas_or_dask(table, tmp_path):
    """xarray (with pandas, and dask.array where dask is installed: xarray looks for its
    array type on the first variable it makes) is no part of writing a table file."""
    path = table.save(tmp_path / "t.nc")
    code = (
        "import sys\n"
        "from dustoptics.io import open_table, write_netcdf\n"
        "from dustoptics.table import Table\n"
        "import h5py\n"
        f"with h5py.File({str(path)!r}, 'r') as f:\n"
        "    fields = {k: f[k][()] for k in ('wavelength_nm', 'theta_deg', 'phase', 'g')}\n"
        "t = Table(name='t', **fields)\n"
        f"write_netcdf(t, {str(tmp_path / 'again.nc')!r})\n"
        "print(sorted(m for m in ('xarray', 'pandas', 'dask') if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
    assert open_table(tmp_path / "again.nc").phase.tobytes() == table.phase.tobytes()


# ------------------------------------------------------------------ layout (CF-1.10)


def test_cf_layout_units_names_and_checksums(table, written):
    with h5py.File(written, "r") as f:
        assert f.attrs["Conventions"] == "CF-1.10"
        assert f.attrs["dustoptics_schema"] == SCHEMA
        assert "history" in f.attrs and f.attrs["input_hash"] == table.provenance.input_hash
        assert json.loads(f.attrs["provenance"]) == table.provenance.to_dict()
        for key in f:
            assert f[key].attrs["units"] == UNITS[key][0], key
            assert f[key].attrs["long_name"] == UNITS[key][1], key
            if f[key].ndim:  # every array is stored with HDF5's Fletcher-32 checksum
                assert f[key].fletcher32, key
        # Every derived variable the table defines (those of a table with a
        # particle density or a backscatter cross-section are among DERIVED too).
        assert set(table.derived()) <= set(DERIVED)
        for key in table.derived():
            assert f[key].attrs["derived_from"] == DERIVED[key]
        assert f["theta_deg"].attrs["units"] == "degree"
        assert f["theta_deg"].attrs["standard_name"] == "scattering_angle"
        assert f["ssa"].attrs["standard_name"] == (
            "single_scattering_albedo_in_air_due_to_ambient_aerosol_particles"
        )
        assert f["beta_ext_per_m"].attrs["standard_name"] == (
            "volume_extinction_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles"
        )
        phase = f["phase"]
        assert (phase.compression, phase.shuffle) == ("gzip", True)
        assert [d[0].name for d in phase.dims] == ["/wavelength_nm", "/theta_deg"]
        assert phase.id.get_storage_size() < phase.nbytes  # compressed


def test_units_are_valid_for_udunits2(table):
    cf_units = pytest.importorskip("cf_units", reason="cf_units (udunits2) not installed")
    for unit, _ in UNITS.values():
        cf_units.Unit(unit)  # raises ValueError for a unit udunits2 does not know
    assert cf_units.Unit("degree").convert(180.0, cf_units.Unit("radian")) == pytest.approx(np.pi)
    assert cf_units.Unit("um2").convert(1.0, cf_units.Unit("m2")) == pytest.approx(1e-12)


def _cf_problems(path: Path, tmp_path: Path) -> list:
    """What the IOOS compliance checker (cf:1.10, strict) reports for a file, at any priority."""
    runner = pytest.importorskip(
        "compliance_checker.runner",
        reason="compliance-checker not installed (pip install '.[cf]'; .ci/run installs it)",
    )
    runner.CheckSuite.load_all_available_checkers()
    report_path = tmp_path / f"{path.stem}.json"
    passed, errors = runner.ComplianceChecker.run_checker(
        str(path), ["cf:1.10"], 0, "strict", output_filename=str(report_path), output_format="json"
    )
    report = json.loads(report_path.read_text())["cf:1.10"]
    problems = [
        (check["name"], check["msgs"])
        for level in ("high_priorities", "medium_priorities", "low_priorities")
        for check in report[level]
        if check["msgs"]
    ]
    assert passed == (not problems) and not errors
    return problems


@pytest.mark.parametrize("path", PRESET_FILES, ids=[p.stem for p in PRESET_FILES])
def test_compliance_checker_cf_1_10_passes_on_every_preset_file(path, tmp_path):
    assert _cf_problems(path, tmp_path) == []


def test_compliance_checker_finds_what_the_old_layout_got_wrong(written, tmp_path):
    """The check can fail: the unit "deg", no history, Conventions without CF-1.10."""

    def old(f):
        f["theta_deg"].attrs["units"] = "deg"
        del f["theta_deg"].attrs["standard_name"]
        del f.attrs["history"]
        f.attrs["Conventions"] = "dustoptics-table-1"

    _edit(written, old, resign=False)
    messages = " ".join(m for _, msgs in _cf_problems(written, tmp_path) for m in msgs)
    assert '"deg" are not recognized by UDUNITS' in messages
    assert "history should exist" in messages and 'does not contain "CF-1.10"' in messages


def test_preset_files_are_the_schema(tmp_path):
    assert {p.parent.name for p in PRESET_FILES} == set(do.list_presets())
    for path in PRESET_FILES:
        assert open_table(path).name == path.stem


# ------------------------------------------------------------------ other readers


def test_netcdf4_reads_the_file(table, written):
    netCDF4 = pytest.importorskip("netCDF4")
    with netCDF4.Dataset(written) as nc:
        assert dict(nc.dimensions.items()).keys() == {"wavelength_nm", "theta_deg"}
        assert nc.variables["phase"].dimensions == ("wavelength_nm", "theta_deg")
        assert nc.variables["theta_deg"].units == "degree"
        assert nc.getncattr("Conventions") == "CF-1.10"
        np.testing.assert_array_equal(nc.variables["phase"][:].data, table.phase)
        np.testing.assert_array_equal(nc.variables["n_nodes"][:].data, table.quadrature.n_nodes)
        assert float(nc.variables["number_density_per_m3"][...]) == 4.64e8


@pytest.mark.parametrize("engine", ["h5netcdf", "netcdf4"])
def test_xarray_reads_the_file_back_into_the_same_table(table, written, engine):
    xr = pytest.importorskip("xarray")
    pytest.importorskip({"h5netcdf": "h5netcdf", "netcdf4": "netCDF4"}[engine])
    with xr.open_dataset(written, engine=engine) as ds:
        assert ds["phase"].dims == ("wavelength_nm", "theta_deg")
        np.testing.assert_array_equal(ds["phase"].sel(wavelength_nm=550.0).values, table.phase[1])
        back = Table.from_xarray(
            ds.drop_attrs(deep=False).assign_attrs(
                {k: v for k, v in ds.attrs.items() if k != DIGEST_ATTRIBUTE}
            )
        )
    assert back.equals(table)


def test_h5dump_reads_the_file(written):
    if shutil.which("h5dump") is None:
        pytest.skip("hdf5-tools (h5dump) not installed")
    header = subprocess.run(
        ["h5dump", "-H", str(written)], capture_output=True, text=True, check=True
    ).stdout
    assert 'DATASET "phase"' in header and "DATASPACE  SIMPLE { ( 3, 181 ) / ( 3, 181 ) }" in header
    properties = subprocess.run(
        ["h5dump", "-p", "-H", "-d", "/phase", str(written)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "CHECKSUM FLETCHER32" in properties and "COMPRESSION DEFLATE" in properties


# ------------------------------------------------------------------ writing: refusals


def test_registry_writes_name_nc_and_name_h5(table, tmp_path):
    assert [p.name for p in FORMATS["netcdf"].write(table, tmp_path)] == ["mars-dust.nc"]
    assert [p.name for p in FORMATS["hdf5"].write(table, tmp_path)] == ["mars-dust.h5"]
    with pytest.raises(FileExistsError, match="mars-dust.nc"):
        FORMATS["netcdf"].write(table, tmp_path)


def test_save_without_a_suffix_writes_nc(table, tmp_path):
    path = table.save(tmp_path / "mars-dust")
    assert path == tmp_path / "mars-dust.nc" and open_table(path).equals(table)


@pytest.mark.parametrize("name", ["t.csv", "t.json", "t.glsl", "t.nc.tmp"])
def test_save_refuses_an_unknown_suffix_and_writes_nothing(table, tmp_path, name):
    with pytest.raises(ValueError, match=r"unknown table file suffix .* use one of \.nc, \.h5"):
        table.save(tmp_path / "sub" / name)
    assert list(tmp_path.iterdir()) == []


def test_save_to_an_unwritable_place_is_a_clear_error(table, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("a file, not a directory")
    with pytest.raises(OSError, match="file"):
        table.save(blocker / "t.nc")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    with pytest.raises(OSError, match=r"/proc/.*cannot write the table there"):
        table.save("/proc/dustoptics-test/t.nc")


def test_existing_file_needs_overwrite(table, written):
    before = written.read_bytes()
    with pytest.raises(FileExistsError, match=r"t\.nc already exists"):
        table.save(written)
    assert written.read_bytes() == before
    table.replace(name="other").save(written, overwrite=True)
    assert open_table(written).name == "other"


def test_failure_mid_write_leaves_no_file(table, tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise OSError("simulated disk failure")

    monkeypatch.setattr(h5py.Dataset, "make_scale", broken)  # fails after the file is created
    with pytest.raises(OSError, match="simulated"):
        table.save(tmp_path / "out" / "t.nc")
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ reading: what is not a table


def test_not_a_table_file(tmp_path):
    empty = tmp_path / "empty.nc"
    empty.write_bytes(b"")
    with pytest.raises(FormatError, match=r"empty\.nc: empty file"):
        open_table(empty)
    text = tmp_path / "text.nc"
    text.write_text(",440,550\n0.0,1.0,2.0\n")
    with pytest.raises(FormatError, match=r"text\.nc: not a netCDF-4/HDF5 file"):
        open_table(text)
    with pytest.raises(FormatError, match="is a directory"):
        open_table(tmp_path)
    with pytest.raises(FileNotFoundError, match=r"nope\.nc"):
        open_table(tmp_path / "nope.nc")
    with pytest.raises(FormatError, match=r"unknown table file suffix '\.txt'"):
        open_table(tmp_path / "t.txt")


def test_another_netcdf_file(tmp_path):
    xr = pytest.importorskip("xarray")
    path = tmp_path / "other.nc"
    xr.Dataset({"t": ("x", np.arange(3.0))}, attrs={"Conventions": "CF-1.10"}).to_netcdf(
        path, engine="h5netcdf"
    )
    with pytest.raises(FormatError, match=r"other\.nc: not a dustoptics table .* another netCDF"):
        open_table(path)


def test_older_layout_is_named(tmp_path):
    path = tmp_path / "old.h5"
    with h5py.File(path, "w") as f:
        f.attrs["Conventions"] = "dustoptics-table-1"
        f["phase"] = np.ones((1, 2))
    with pytest.raises(
        FormatError, match=r"old\.h5: written in the older dustoptics-table-1 layout"
    ):
        open_table(path)


def test_truncated_file(written):
    data = written.read_bytes()
    written.write_bytes(data[: len(data) // 2])
    with pytest.raises(FormatError, match=r"t\.nc: .*(truncated|damaged)"):
        open_table(written)


def test_random_byte_flips_are_errors_never_other_numbers(table, written):
    """Issue 15: 8 of 120 random flips were read as valid, 5 with changed numbers.

    Now every flip either raises FormatError or reads back the same table (a
    flip in bytes no reader uses, e.g. free space)."""
    original = written.read_bytes()
    rng = np.random.default_rng(20261201)
    outcomes = {"error": 0, "same": 0}
    for _ in range(120):
        data = bytearray(original)
        for position in rng.integers(0, len(data), size=rng.integers(1, 5)):
            data[position] ^= 1 << int(rng.integers(0, 8))
        written.write_bytes(bytes(data))
        try:
            back = open_table(written)
        except FormatError:
            outcomes["error"] += 1
        else:
            assert back.equals(table)
            outcomes["same"] += 1
    assert outcomes["error"] > 60, outcomes


# ------------------------------------------------------------------ reading: crafted files


def test_flipped_value_fails_the_checksum(written):
    _edit(written, lambda f: f["g"].__setitem__(0, 0.9213), resign=False)
    with pytest.raises(FormatError, match=r"t\.nc: the data do not match their checksum"):
        open_table(written)


def test_external_storage_is_refused(written, tmp_path):
    secret = tmp_path / "secret.bin"
    secret.write_bytes(np.arange(3.0).tobytes())

    def external(f):
        del f["g"]
        f.create_dataset("g", shape=(3,), dtype="<f8", external=[(str(secret), 0, 24)])

    _edit(written, external, resign=False)
    with pytest.raises(
        FormatError, match=r"variable 'g' keeps its data in external files; refused"
    ):
        open_table(written)


def test_virtual_dataset_is_refused(written, tmp_path):
    source = tmp_path / "source.h5"
    with h5py.File(source, "w") as s:
        s["x"] = np.full(3, 0.5)

    def virtual(f):
        layout = h5py.VirtualLayout(shape=(3,), dtype="<f8")
        layout[:] = h5py.VirtualSource(str(source), "x", shape=(3,))
        del f["g"]
        f.create_virtual_dataset("g", layout)

    _edit(written, virtual, resign=False)
    with pytest.raises(FormatError, match="virtual dataset"):
        open_table(written)


@pytest.mark.parametrize(
    ("make", "kind"),
    [
        (
            lambda f, other: f.__setitem__("extra", h5py.ExternalLink(str(other), "/x")),
            "ExternalLink",
        ),
        (lambda f, other: f.__setitem__("extra", h5py.SoftLink("/g")), "SoftLink"),
        (lambda f, other: f.create_group("extra"), "Group"),
    ],
)
def test_links_and_groups_are_refused(written, tmp_path, make, kind):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as o:
        o["x"] = np.ones(3)
    _edit(written, lambda f: make(f, other), resign=False)
    with pytest.raises(FormatError, match=rf"'extra' is a {kind}"):
        open_table(written)


def test_huge_declared_size_is_refused_before_allocation(written):
    n = MAX_VALUES + 1

    def huge(f):
        del f["g"]
        f.create_dataset("g", shape=(n,), dtype="<f8", chunks=(1 << 16,), compression="gzip")

    _edit(written, huge, resign=False)
    assert written.stat().st_size < 1 << 20  # a small file that declares 256 MiB
    with pytest.raises(FormatError, match=r"variable 'g' has shape \(33554433,\); expected \(3,\)"):
        open_table(written)


def test_reader_checks_the_declared_size_before_reading(tmp_path, monkeypatch):
    """A consistent file whose axes exceed the limit is refused from its metadata alone."""
    table = Table(
        wavelength_nm=[500.0],
        theta_deg=np.linspace(0.0, 180.0, 181),
        phase=np.full((1, 181), 1 / (4 * np.pi)),
        g=[0.0],
    )
    path = table.save(tmp_path / "t.nc")
    read = []
    monkeypatch.setattr(h5py.Dataset, "__getitem__", lambda self, key: read.append(self.name))
    with pytest.raises(
        FormatError,
        match=r"'theta_deg' declares 181 values \(1448 bytes\), more than the reader's limit "
        r"100; refused before reading \(max_values= raises it\)",
    ):
        open_table(path, max_values=100)
    assert read == []
    monkeypatch.undo()
    assert open_table(path, max_values=181).theta_deg.size == 181
    with pytest.raises(ValueError, match="max_values must be an integer >= 1; got 0"):
        open_table(path, max_values=0)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda f: f["theta_deg"].attrs.__setitem__("units", "deg"),
            "'theta_deg' must be in 'degree'",
        ),
        (
            lambda f: f["phase"].__setitem__((slice(None), slice(None)), f["phase"][()] * 1000),
            r"phase function at 440 nm integrates to 10\d\d\.\d+ over the sphere",
        ),
        (lambda f: f["cext_um2"].__setitem__(1, np.nan), "finite"),
        (lambda f: f["cext_um2"].__setitem__(1, -1.0), "cext_um2 > 0"),
        (lambda f: f["ssa"].__setitem__(0, 0.5), r"derived variable 'ssa' disagrees .* 440\.0 nm"),
        (lambda f: f.__delitem__("ssa"), r"derived variables .* do not match"),
        (lambda f: f.__delitem__("g"), "missing variable 'g'"),
        (lambda f: f.create_dataset("secret", data=np.ones(3)), "unknown variable 'secret'"),
        (
            lambda f: (f.__delitem__("csca_um2"), f.create_dataset("csca_um2", data=np.ones(2))),
            r"variable 'csca_um2' has shape \(2,\); expected \(3,\)",
        ),
        (
            lambda f: (f.__delitem__("n_nodes"), f.create_dataset("n_nodes", data=np.ones(3))),
            "'n_nodes' must hold 64-bit integers",
        ),
        (lambda f: f.attrs.__setitem__("provenance", "{not json"), "attribute 'provenance'"),
        (
            lambda f: f.attrs.__setitem__(
                "provenance", f.attrs["provenance"].replace('"r_eff_um":1.6', '"r_eff_um":1.7')
            ),
            "input_hash .* does not match its inputs",
        ),
        (
            lambda f: f.attrs.__setitem__("dustoptics_schema", "dustoptics-table-9"),
            "table schema 'dustoptics-table-9'",
        ),
        (
            lambda f: f.attrs.__setitem__("Conventions", "CF-1.6"),
            "Conventions must start with 'CF-1.10'",
        ),
        (
            lambda f: f.attrs.__setitem__("name", np.arange(3)),
            "global attribute 'name' must be one string",
        ),
    ],
)
def test_crafted_content_is_named(written, change, message):
    """Files edited consistently (checksum recomputed) still fail on what they break."""
    _edit(written, change)
    with pytest.raises(FormatError, match=rf"t\.nc: .*{message}"):
        open_table(written)


def test_data_the_stored_bytes_cannot_hold_is_refused_before_reading(written, monkeypatch):
    """A small file whose variables declare hundreds of MiB of chunks never written (read
    back as the fill value) or beyond deflate's ratio: refused from the metadata (issue 29)."""
    n = 1 << 23

    def crafted(f):
        for key in ("theta_deg", "phase"):
            del f[key]
        f.create_dataset(
            "theta_deg", shape=(n,), dtype="<f8", chunks=(1 << 16,), compression="gzip"
        )
        f.create_dataset(
            "phase", shape=(3, n), dtype="<f8", chunks=(1, 1 << 16), compression="gzip"
        )
        f["theta_deg"].attrs["units"] = "degree"
        f["phase"].attrs["units"] = "sr-1"

    _edit(written, crafted, resign=False)
    assert written.stat().st_size < 1 << 20  # a small file that declares 256 MiB
    read = []
    monkeypatch.setattr(h5py.Dataset, "__getitem__", lambda self, key: read.append(self.name))
    with pytest.raises(
        FormatError, match=r"'theta_deg' declares 67108864 bytes of data but stores 0, which cannot"
    ):
        open_table(written)
    assert read == []


def test_other_filters_are_refused(written):
    def lzf(f):
        values = f["g"][()]
        del f["g"]
        f.create_dataset("g", data=values, chunks=(3,), compression="lzf")

    _edit(written, lzf)
    with pytest.raises(FormatError, match="'g' uses HDF5 filter 32000; table files use only"):
        open_table(written)


def test_a_constant_phase_function_compresses_within_the_bound(tmp_path):
    theta = np.linspace(0.0, 180.0, 20001)
    table = Table(
        wavelength_nm=[440.0, 550.0, 680.0],
        theta_deg=theta,
        phase=np.full((3, theta.size), 1 / (4 * np.pi)),
        g=[0.0, 0.0, 0.0],
    )
    assert open_table(table.save(tmp_path / "iso.nc")).equals(table)


def test_provenance_nested_100000_deep_is_named(written):
    _edit(written, lambda f: f.attrs.__setitem__("provenance", "[" * 100_000 + "]" * 100_000))
    with pytest.raises(FormatError, match=r"t\.nc: .*'provenance'.*nested deeper than 32 levels"):
        open_table(written)
