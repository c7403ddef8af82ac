"""Tests for dustoptics.io.csv.seed: the seed framework's CSV layout on a Table.

One small table (2 wavelengths, 19 angles, rtol 1e-3) is computed once per
module; layout tests that need other wavelength grids reuse its numbers on a
different grid (:func:`_regridded`), since they check formatting, not physics.
"""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np
import pytest
from _data import SEED_PHASE_EXCERPT, SEED_ROWS, data_path

import dustoptics as do
from dustoptics.io import FORMATS, FormatError
from dustoptics.io.csv.seed import (
    EXTINCTION_FILENAME,
    PHASE_FILENAME,
    SEED_CSV_FILES,
    SUMMARY_FILENAME,
    existing_outputs,
    read_phase_csv,
    read_seed_csv,
    write_seed_csv,
)
from dustoptics.table import Table, grouped_fields

PER_WAVELENGTH = ("g", "cext_um2", "csca_um2", "error_estimate", "cross_section_error_estimate")


@pytest.fixture(scope="module")
def table() -> Table:
    optics = do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        wavelength_nm=[440.0, 550.0],
        theta_deg=np.linspace(0.0, 180.0, 19),
        rtol=1e-3,
        weighting="scattering",
        workers=1,
        name="mars-dust",
    )
    return optics.replace(cross_sections={"number_density_per_m3": 1e8})


def _regridded(table: Table, wavelengths_nm: np.ndarray) -> Table:
    """The table's numbers repeated onto another wavelength grid (layout tests only)."""
    idx = np.arange(wavelengths_nm.size) % table.wavelength_nm.size
    changes = {
        name: table.quantity(name)[idx]
        for name in (*PER_WAVELENGTH, "n_nodes", "cross_section_n_nodes", "refractive_index")
    }
    changes.update(
        {
            key: table.quantity(key)
            for key in ("mean_geometric_cross_section_um2", "number_density_per_m3")
        }
    )
    return table.replace(
        wavelength_nm=wavelengths_nm, phase=table.phase[idx], **grouped_fields(changes)
    )


def _files(directory) -> list[str]:
    return sorted(p.name for p in directory.iterdir()) if directory.exists() else []


# ------------------------------------------------------------------ round trip


def test_round_trip_is_bit_exact_with_provenance(table, tmp_path):
    paths = write_seed_csv(table, tmp_path / "t")
    assert [p.name for p in paths] == list(SEED_CSV_FILES)
    back = read_seed_csv(tmp_path / "t")
    assert back.equals(table)  # same bits, not merely close, and the same provenance
    assert back.provenance.sources == table.provenance.sources


def test_phase_only_table_writes_no_extinction_file(table, tmp_path):
    phase_only = table.replace(cross_sections=None)
    paths = write_seed_csv(phase_only, tmp_path)
    assert [p.name for p in paths] == [PHASE_FILENAME, SUMMARY_FILENAME]
    assert read_seed_csv(tmp_path).equals(phase_only)  # g comes back from the summary


def test_molecule_table_has_no_efficiency_columns(table, tmp_path):
    molecule = table.replace(cross_sections={"mean_geometric_cross_section_um2": None})
    write_seed_csv(molecule, tmp_path)
    header = (tmp_path / EXTINCTION_FILENAME).read_text().splitlines()[0]
    assert header == "wavelength_nm,cext_m2,csca_m2,cabs_m2,ssa,g"
    assert read_seed_csv(tmp_path).equals(molecule)


def test_cross_sections_are_written_in_m2(table, tmp_path):
    write_seed_csv(table, tmp_path)
    lines = (tmp_path / EXTINCTION_FILENAME).read_text().splitlines()
    assert lines[0] == "wavelength_nm,cext_m2,qext,csca_m2,qsca,cabs_m2,ssa,g"
    rows = np.array([[float(c) for c in line.split(",")] for line in lines[1:]])
    np.testing.assert_array_equal(rows[:, 0], table.wavelength_nm)
    # 1 um^2 = 1e-12 m^2; the decimal shift is exact, the float product within one rounding.
    np.testing.assert_allclose(rows[:, 1], table.cross_sections.cext_um2 * 1e-12, rtol=1e-15)
    np.testing.assert_allclose(rows[:, 3], table.cross_sections.csca_um2 * 1e-12, rtol=1e-15)
    np.testing.assert_allclose(rows[:, 5], table.cabs_um2 * 1e-12, rtol=1e-15)
    np.testing.assert_array_equal(rows[:, 2], table.qext)
    np.testing.assert_array_equal(rows[:, 7], table.g)


def test_wavelength_labels_are_integers_when_integral(table, tmp_path):
    write_seed_csv(_regridded(table, np.array([440.0, 552.5])), tmp_path)
    header = (tmp_path / PHASE_FILENAME).read_text().splitlines()[0]
    assert header == ",440,552.5"
    assert read_phase_csv(tmp_path / PHASE_FILENAME).wavelength_nm.tolist() == [440.0, 552.5]


def test_registry_entry(table, tmp_path):
    assert [p.name for p in FORMATS["csv"].write(table, tmp_path, overwrite=False)] == list(
        SEED_CSV_FILES
    )


# ------------------------------------------------------------------ the seed's layout


def test_phase_header_matches_the_seed_table(table, tmp_path):
    seed = data_path(*SEED_PHASE_EXCERPT)
    write_seed_csv(_regridded(table, do.optics.default_wavelengths_nm()), tmp_path)
    ours = (tmp_path / PHASE_FILENAME).read_text().splitlines()
    theirs = [line for line in seed.read_text().splitlines() if not line.startswith("#")]
    # Empty first cell, then 360, 370, ..., 830 written as integers: the same header line.
    assert ours[0].split(",")[0] == "" == theirs[0].split(",")[0]
    assert ours[0] == theirs[0]
    # Rows: an angle in degrees, then one value per wavelength.
    assert all(len(line.split(",")) == 49 for line in ours[1:])
    assert ours[1].split(",")[0] == theirs[1].split(",")[0] == "0.0"
    assert ours[-1].split(",")[0] == theirs[-1].split(",")[0] == "180.0"


def test_reads_the_seed_phase_table(tmp_path):
    # The seed's own file: the excerpt's lines below its commented header.
    lines = data_path(*SEED_PHASE_EXCERPT).read_text().splitlines(keepends=True)
    (tmp_path / PHASE_FILENAME).write_text("".join(ln for ln in lines if not ln.startswith("#")))
    seed = read_phase_csv(tmp_path / PHASE_FILENAME)
    np.testing.assert_array_equal(seed.wavelength_nm, do.optics.default_wavelengths_nm())
    np.testing.assert_array_equal(seed.theta_deg, np.linspace(0.0, 180.0, 1800)[list(SEED_ROWS)])
    assert seed.phase.shape == (48, len(SEED_ROWS))
    assert (
        seed.phase[0, 0] == 27.69420224644522
    )  # first data cell of the seed's file, 360 nm forward


# ------------------------------------------------------------------ summary


def test_summary_records_provenance_and_checksums(table, tmp_path):
    write_seed_csv(table, tmp_path)
    text = (tmp_path / SUMMARY_FILENAME).read_text()
    summary = json.loads(text)
    assert text == json.dumps(summary, indent=2, sort_keys=True) + "\n"  # sorted keys
    assert summary["provenance"] == table.provenance.to_dict()
    assert summary["input_hash"] == table.provenance.input_hash
    assert summary["name"] == "mars-dust"
    assert summary["number_density_per_m3"] == 1e8
    assert summary["provenance"]["software"]["numpy"] == np.__version__
    assert summary["provenance"]["quadrature"]["weighting"] == "scattering"
    assert summary["per_wavelength"]["error_estimate"] == table.quadrature.error_estimate.tolist()
    for name in (PHASE_FILENAME, EXTINCTION_FILENAME):
        digest = hashlib.sha256((tmp_path / name).read_bytes()).hexdigest()
        assert summary["files"][name]["sha256"] == digest
    units = {c["name"]: c["unit"] for c in summary["files"][EXTINCTION_FILENAME]["columns"]}
    assert units == {
        "wavelength_nm": "nm", "cext_m2": "m^2", "qext": "1", "csca_m2": "m^2",
        "qsca": "1", "cabs_m2": "m^2", "ssa": "1", "g": "1",
    }  # fmt: skip
    assert summary["files"][PHASE_FILENAME]["units"]["phase"] == "sr^-1"


def test_writes_are_deterministic(table, tmp_path):
    write_seed_csv(table, tmp_path / "a")
    write_seed_csv(table, tmp_path / "b")
    for name in SEED_CSV_FILES:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


# ------------------------------------------------------------------ atomic writes


def test_existing_file_is_not_overwritten(table, tmp_path):
    (tmp_path / EXTINCTION_FILENAME).write_text("keep me\n")
    with pytest.raises(FileExistsError, match=EXTINCTION_FILENAME):
        write_seed_csv(table, tmp_path)
    # Checked for all files before any is written.
    assert _files(tmp_path) == [EXTINCTION_FILENAME]
    assert (tmp_path / EXTINCTION_FILENAME).read_text() == "keep me\n"
    write_seed_csv(table, tmp_path, overwrite=True)
    assert read_seed_csv(tmp_path).equals(table)


@pytest.mark.parametrize("victim", ["fsync", "replace"])
def test_failure_mid_write_leaves_nothing(table, tmp_path, monkeypatch, victim):
    real = getattr(os, victim)
    calls = []

    def fail_second(*args, **kwargs):
        calls.append(args)
        if len(calls) == 2:
            raise OSError(28, "No space left on device (simulated)")
        return real(*args, **kwargs)

    monkeypatch.setattr(os, victim, fail_second)
    existing = tmp_path / "existing"
    existing.mkdir()
    with pytest.raises(OSError, match="simulated"):
        write_seed_csv(table, existing)
    assert _files(existing) == []  # no partial set, no temporary files
    fresh = tmp_path / "fresh" / "nested"
    calls.clear()
    with pytest.raises(OSError, match="simulated"):
        write_seed_csv(table, fresh)
    assert not (tmp_path / "fresh").exists()  # the directories it created are gone too
    monkeypatch.undo()
    write_seed_csv(table, existing)  # and a retry succeeds
    assert _files(existing) == sorted(SEED_CSV_FILES)


def test_not_a_table_is_refused(tmp_path):
    with pytest.raises(TypeError, match="table must be a dustoptics.table.Table"):
        write_seed_csv({"g": [0.5]}, tmp_path)


# ------------------------------------------------------------------ malformed files


@pytest.fixture
def written(table, tmp_path):
    write_seed_csv(table, tmp_path)
    return tmp_path


def test_truncated_file_is_reported_by_checksum(written):
    path = written / PHASE_FILENAME
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:-3]))  # cut at a line boundary: only the checksum can tell
    with pytest.raises(FormatError, match=f"{PHASE_FILENAME}.*truncated"):
        read_seed_csv(written)


def test_truncated_file_mid_row(written):
    path = written / PHASE_FILENAME
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(FormatError, match=PHASE_FILENAME):
        read_seed_csv(written)
    with pytest.raises(FormatError, match=f"{PHASE_FILENAME}.*(truncated|cells)"):
        read_seed_csv(written, verify=False)


@pytest.mark.parametrize(
    ("name", "edit", "message"),
    [
        (PHASE_FILENAME, lambda t: "theta" + t, "first header cell must be empty"),
        (
            PHASE_FILENAME,
            lambda t: t.replace("\n10.0,", "\n10.0,,", 1),
            "line 3 has 4 cells; the header has 3",
        ),
        (
            PHASE_FILENAME,
            lambda t: t.replace("\n10.0,", "\nten,", 1),
            "line 3, column 1 .theta_deg.: not a number: 'ten'",
        ),
        (PHASE_FILENAME, lambda t: t.splitlines()[0] + "\n", "no data rows"),
        (PHASE_FILENAME, lambda t: "", "empty"),
        (PHASE_FILENAME, lambda t: t.replace(",440,550", ",550,440", 1), "strictly increasing"),
        (
            PHASE_FILENAME,
            lambda t: t.replace(",440,550", ",440,560", 1),
            "differ from those listed",
        ),
        (EXTINCTION_FILENAME, lambda t: t.replace(",g\n", "\n", 1), "missing column.*g"),
        (
            EXTINCTION_FILENAME,
            lambda t: t.replace("440.0,", "440.0,x", 1),
            "column cext_m2: not a number",
        ),
        (EXTINCTION_FILENAME, lambda t: t.rstrip("\n"), "does not end with a newline"),
        (
            EXTINCTION_FILENAME,
            lambda t: (
                "\n".join(
                    ",".join(cells[:-2] + ["0.5"] + cells[-1:]) if i == 1 else ",".join(cells)
                    for i, cells in enumerate(line.split(",") for line in t.splitlines())
                )
                + "\n"
            ),
            r"column ssa disagrees .* 440\.0 nm: file 0\.5",
        ),
        (SUMMARY_FILENAME, lambda t: t[: len(t) // 2], "not a valid JSON table summary"),
        (SUMMARY_FILENAME, lambda t: t.replace('"r_eff_um": 1.6', '"r_eff_um": 1.7'), "altered"),
        (
            SUMMARY_FILENAME,
            lambda t: t.replace('"format_version": 2', '"format_version": 1'),
            "version 1",
        ),
    ],
)
def test_malformed_files_name_the_file_and_problem(written, name, edit, message):
    path = written / name
    path.write_text(edit(path.read_text()))
    with pytest.raises(FormatError, match=f"{name}.*{message}"):
        read_seed_csv(written, verify=False)


@pytest.mark.parametrize("name", [PHASE_FILENAME, EXTINCTION_FILENAME])
def test_a_summary_without_digests_is_refused_unless_verify_is_false(written, name):
    """The digests deleted from the summary: not read as valid (issue 29 item 9)."""
    summary = json.loads((written / SUMMARY_FILENAME).read_text())
    del summary["files"][name]["sha256"]
    (written / SUMMARY_FILENAME).write_text(json.dumps(summary))
    with pytest.raises(FormatError, match=f"records no sha256 for {name}.*verify=False"):
        read_seed_csv(written)
    assert read_seed_csv(written, verify=False).phase.shape == (2, 19)


def test_a_cut_phase_csv_without_digests_is_not_read_as_a_smaller_table(written):
    summary = json.loads((written / SUMMARY_FILENAME).read_text())
    for entry in summary["files"].values():
        del entry["sha256"]
    (written / SUMMARY_FILENAME).write_text(json.dumps(summary))
    path = written / PHASE_FILENAME
    path.write_text("".join(path.read_text().splitlines(keepends=True)[:7]))  # 6 angles
    with pytest.raises(FormatError, match="records no sha256"):
        read_seed_csv(written)
    with pytest.raises(FormatError, match=r"2 wavelengths x 6 angles, but .* records 2 x 19"):
        read_seed_csv(written, verify=False)


def test_missing_files(written):
    (written / EXTINCTION_FILENAME).unlink()
    with pytest.raises(FileNotFoundError, match=EXTINCTION_FILENAME):
        read_seed_csv(written)
    (written / SUMMARY_FILENAME).unlink()
    with pytest.raises(FileNotFoundError, match=f"{SUMMARY_FILENAME}.*read_phase_csv"):
        read_seed_csv(written)


def test_existing_outputs(written, tmp_path):
    assert [p.name for p in existing_outputs(written)] == list(SEED_CSV_FILES)
    assert existing_outputs(tmp_path / "nowhere") == []
