"""dustoptics.io.outputs: a table's files in a directory, placed beside what is there."""

from __future__ import annotations

import dataclasses
import json

import pytest

import dustoptics as do
from dustoptics.atmosphere.build import SET_PROVENANCE_SUFFIX, set_inputs
from dustoptics.atmosphere.sets import earth_atmosphere
from dustoptics.io import FormatError, FormatOptions, read_hdf5, write_hdf5
from dustoptics.io.csv.cosmoscout import check_cosmoscout_set
from dustoptics.io.outputs import (
    Placement,
    place_outputs,
    place_table,
    read_table,
    with_inputs,
    write_atmosphere_set,
    write_formats,
)


@pytest.fixture(scope="module")
def table():
    return do.compute_optics(
        1.5 + 0.01j,
        do.Monodisperse(radius_um=0.5),
        [440.0, 550.0, 680.0],
        [0.0, 45.0, 90.0, 135.0, 180.0],
        name="small",
    )


def test_read_table_reads_hdf5_and_seed_csv(table, tmp_path):
    write_formats(table, tmp_path, ["hdf5", "csv"])
    assert read_table(tmp_path / "small.h5").equals(table)
    assert read_table(tmp_path).equals(table)
    assert read_table(tmp_path / "table_summary.json").equals(table)


def test_read_table_refuses_a_missing_file_and_another_format(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        read_table(tmp_path / "nope.h5")
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(FormatError, match="not a table file"):
        read_table(tmp_path / "notes.txt")


def test_with_inputs_records_them_and_changes_the_input_hash(table):
    given = with_inputs(table, note="given here", number_density_per_m3=2e8)
    assert given.provenance.inputs["number_density_per_m3"] == 2e8
    assert given.provenance.notes[-1] == "given here"
    assert given.provenance.input_hash != table.provenance.input_hash
    assert with_inputs(table).provenance.input_hash == table.provenance.input_hash


def test_write_formats_records_the_options_that_change_numbers(table, tmp_path):
    options = FormatOptions(n_angles=181)
    written = write_formats(table, tmp_path, ["hdf5", "texture"], options=options)
    assert sorted(p.name for p in written) == [
        "small.h5",
        "small_phase_theta.json",
        "small_phase_theta.raw",
    ]
    sidecar = json.loads((tmp_path / "small_phase_theta.json").read_text())
    assert sidecar["provenance"]["inputs"]["export"] == {"format": "texture", "n_angles": 181}
    assert read_hdf5(tmp_path / "small.h5").equals(table)  # its options change nothing
    with pytest.raises(FileExistsError):
        write_formats(table, tmp_path, ["hdf5"])


def _render(contents):
    def render(directory):
        for name, data in contents.items():
            (directory / name).write_bytes(data)
        return [directory / name for name in contents]

    return render


def test_place_outputs_leaves_the_same_files_and_refuses_different_ones(tmp_path):
    first = place_outputs(_render({"a.txt": b"a", "b.txt": b"b"}), tmp_path, force=False)
    assert first == Placement(written=(tmp_path / "a.txt", tmp_path / "b.txt"), unchanged=())
    again = place_outputs(_render({"a.txt": b"a", "c.txt": b"c"}), tmp_path, force=False)
    assert again.written == (tmp_path / "c.txt",) and again.unchanged == (tmp_path / "a.txt",)
    with pytest.raises(FileExistsError, match="b.txt"):
        place_outputs(_render({"b.txt": b"B", "d.txt": b"d"}), tmp_path, force=False)
    assert not (tmp_path / "d.txt").exists()  # nothing written
    forced = place_outputs(_render({"b.txt": b"B"}), tmp_path, force=True)
    assert forced.written == (tmp_path / "b.txt",) and (tmp_path / "b.txt").read_bytes() == b"B"


def test_place_outputs_asks_same_about_different_bytes(tmp_path):
    place_outputs(_render({"a.txt": b"a"}), tmp_path, force=False)
    placed = place_outputs(
        _render({"a.txt": b"A"}), tmp_path, force=False, same=lambda old, new: True
    )
    assert placed.unchanged == (tmp_path / "a.txt",)
    assert (tmp_path / "a.txt").read_bytes() == b"a"


def test_place_table_writes_into_out_slash_name(table, tmp_path):
    placed = place_table(table, tmp_path, ["hdf5", "csv"])
    assert {p.parent for p in placed.written} == {tmp_path / "small"}
    assert read_table(tmp_path / "small" / "small.h5").equals(table)
    assert place_table(table, tmp_path, ["hdf5", "csv"]).written == ()
    # Other software versions recorded: different bytes, the same table by `same`.
    path = tmp_path / "small" / "small.h5"
    other = dict(table.provenance.software, numpy="0.0.0-elsewhere")
    prov = dataclasses.replace(table.provenance, software=other)
    write_hdf5(table.replace(provenance=prov), path, overwrite=True)
    with pytest.raises(FileExistsError):
        place_table(table, tmp_path, ["hdf5"])
    same = place_table(table, tmp_path, ["hdf5"], same=lambda old, new: True)
    assert same.unchanged == (path,)


@pytest.mark.parametrize("name", ["../escaped", "a/b", ".hidden"])
def test_place_table_refuses_a_name_that_is_not_a_plain_file_name(table, tmp_path, name):
    with pytest.raises(ValueError, match="plain file name"):
        place_table(table.replace(name=name), tmp_path / "out", ["hdf5"])
    assert not (tmp_path / "out").exists()


def test_write_atmosphere_set_writes_the_record_beside_cosmoscouts_files(tmp_path):
    grid = (440.0, 550.0, 680.0)
    atm = earth_atmosphere(wavelength_nm=grid)
    inputs = set_inputs("earth", wavelength_nm=grid)
    written = write_atmosphere_set(atm, tmp_path, inputs=inputs, bruneton=True)
    record = tmp_path / f"earth{SET_PROVENANCE_SUFFIX}"
    assert record in written and (tmp_path / "earth_bruneton.json") in written
    assert json.loads(record.read_text())["inputs"] == {
        **inputs,
        "constituents": {c.role: c.table.provenance.input_hash for c in atm.constituents},
        "number_densities_per_m3": {
            c.role: c.table.cross_sections.number_density_per_m3 for c in atm.constituents
        },
    }
    assert check_cosmoscout_set(tmp_path) == ["earth_aerosols", "earth_molecules", "earth_ozone"]
    with pytest.raises(FileExistsError):
        write_atmosphere_set(atm, tmp_path, inputs=inputs)


def test_files_all_up_to_date_are_left_without_a_write_and_a_leftover_settles_first(
    tmp_path, monkeypatch
):
    """An up-to-date build on a read-only folder failed creating its staging directory: now
    nothing is staged or locked when every file is the same; with a staging directory left
    by an interrupted write, the write goes on as before (it settles that first)."""
    from dustoptics.io import _atomic, outputs

    def render(d):
        (d / "a.txt").write_text("A")
        return [d / "a.txt"]

    assert place_outputs(render, tmp_path, force=False).written == (tmp_path / "a.txt",)

    def no_write(*args, **kwargs):
        raise PermissionError(30, "Read-only file system", str(tmp_path))

    monkeypatch.setattr(outputs, "_commit", no_write)
    placed = place_outputs(render, tmp_path, force=False)
    assert placed.written == () and placed.unchanged == (tmp_path / "a.txt",)
    (tmp_path / f"{_atomic.STAGE_PREFIX}left").mkdir()
    with pytest.raises(PermissionError):
        place_outputs(render, tmp_path, force=False)
