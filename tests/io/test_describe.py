"""dustoptics.io.describe: what a file dustoptics writes holds, as text."""

from __future__ import annotations

import pytest

import dustoptics as do
from dustoptics.io import FormatError, FormatOptions
from dustoptics.io.describe import describe_path, describe_table
from dustoptics.io.outputs import prepare_export, write_formats


@pytest.fixture(scope="module")
def table():
    return do.compute_optics(
        1.5 + 0.01j,
        do.Monodisperse(radius_um=0.5),
        [440.0, 550.0, 680.0],
        [0.0, 45.0, 90.0, 135.0, 180.0],
        name="small",
    )


@pytest.fixture(scope="module")
def folder(table, tmp_path_factory):
    """The table in every format info reads, CosmoScout VR's at 1e8 m^-3."""
    out = tmp_path_factory.mktemp("described")
    formats = ["hdf5", "csv", "glsl", "texture", "cosmoscout"]
    dense, options = prepare_export(
        table.replace(cross_sections={"number_density_per_m3": 1e8}),
        formats,
        options=FormatOptions(),
        n_altitudes=16,
    )
    write_formats(dense, out, formats, options=options)
    return out


def test_describe_table(table):
    text = describe_table(table)
    lines = text.splitlines()
    assert lines[:4] == [
        "name:            small",
        "wavelengths:     3, 440 .. 680 nm",
        "angles:          5, 0 .. 180 deg",
        "phase function:  [sr^-1], 2 pi int P dmu = 1",
    ]
    assert f"input hash:      {table.provenance.input_hash}" in lines
    assert "inputs:" in lines


def test_describe_table_escapes_what_a_terminal_would_obey(table):
    text = describe_table(table.replace(name="evil\x1b]0;pwned\x07"))
    assert "\x1b" not in text and "\x07" not in text and "\\x1b]0;pwned\\x07" in text


@pytest.mark.parametrize(
    ("name", "first"),
    [
        ("small.h5", "name:            small"),
        ("table_summary.json", "name:            small"),
        ("MiePhaseFunctionSpectrum.csv", "name:            small"),
        ("small_phase.glsl", "GLSL snippet:    small_phase.glsl"),
        ("small_phase_theta.json", "texture:         small_phase_theta.raw"),
        ("small_phase_theta.raw", "texture:         small_phase_theta.raw"),
        ("small_phase.csv", "constituent:     small (CosmoScout VR CSV set in "),
        ("small_density.csv", "constituent:     small (CosmoScout VR CSV set in "),
    ],
)
def test_describe_path_reads_each_format(folder, table, name, first):
    text = describe_path(folder / name)
    assert text.startswith(first)
    if not name.startswith(("small_phase.csv", "small_density")):
        assert table.provenance.input_hash in text


def test_describe_path_of_a_folder_has_a_section_per_output(folder):
    text = describe_path(folder)
    for title in (
        "== small (CosmoScout VR) ==",
        "== small.h5 ==",
        "== table_summary.json (seed CSV) ==",
        "== small_phase.glsl ==",
        "== small_phase_theta.json ==",
    ):
        assert title in text


def test_describe_path_refuses_what_dustoptics_does_not_write(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        describe_path(tmp_path / "nope.h5")
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(FormatError, match="not a file dustoptics writes"):
        describe_path(tmp_path / "notes.txt")
    with pytest.raises(FormatError, match="holds no file dustoptics writes"):
        describe_path(tmp_path)
    (tmp_path / "fake.glsl").write_text("// not ours\n")
    with pytest.raises(FormatError, match="not a GLSL snippet written by dustoptics"):
        describe_path(tmp_path / "fake.glsl")


@pytest.mark.parametrize(
    ("suffix", "text"),
    [
        ("_provenance.json", "[" * 100_000 + "]" * 100_000),
        ("_settings.json", "[" * 100_000 + "]" * 100_000),
        ("_provenance.json", '{"input_hash": 1}'),
        ("_settings.json", "[]"),
    ],
)
def test_a_damaged_set_record_is_a_format_error(tmp_path, suffix, text):
    """Nested 100,000 deep or missing its keys: one FormatError, never a RecursionError or
    a KeyError (issue 29 item 7)."""
    from dustoptics.atmosphere.build import set_inputs
    from dustoptics.atmosphere.sets import earth_atmosphere
    from dustoptics.io.outputs import write_atmosphere_set

    grid = [440.0, 550.0, 680.0]
    write_atmosphere_set(
        earth_atmosphere(wavelength_nm=grid),
        tmp_path,
        inputs=set_inputs("earth", wavelength_nm=grid),
    )
    (tmp_path / f"earth{suffix}").write_text(text)
    with pytest.raises(FormatError, match="earth"):
        describe_path(tmp_path)
