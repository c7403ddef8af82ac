"""A format is one module holding one record: the example of docs/contributing/adding.rst,
registered here without touching a package file, appears in every place that reads the
registry (``build --help``, ``build``, ``info``, the documentation's format table)."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path

import pytest
from cli._cli import config_fixture  # noqa: F401 (fixture config)

from dustoptics.cli import main
from dustoptics.io import FORMATS, FormatOptions
from dustoptics.io.registry import NEEDS, Format, format_table, option_groups, register

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "contributing" / "example_format.py"


@pytest.fixture(name="example")
def example_fixture():
    """The example format module, imported (so registered) for one test, then unregistered."""
    spec = importlib.util.spec_from_file_location("example_format", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    assert "g-table" not in FORMATS
    sys.modules["example_format"] = module
    spec.loader.exec_module(module)
    try:
        yield module
    finally:
        FORMATS.pop("g-table", None)
        sys.modules.pop("example_format", None)


def test_the_example_is_in_build_help(example, capsys):
    assert main(["build", "--help-all"]) == 0
    out = capsys.readouterr().out
    assert "g-table" in out and "g and ssa per wavelength" in out
    assert "--g-digits N" in out and "significant digits of g and ssa" in out
    assert main(["info", "--help"]) == 0
    assert "g-table" in " ".join(capsys.readouterr().out.split())


def test_build_writes_the_example_with_its_option_recorded(example, config, tmp_path):
    out = tmp_path / "tables"
    assert (
        main(
            [
                "build",
                str(config),
                "--out",
                str(out),
                "--quiet",
                "--format",
                "g-table",
                "--g-digits",
                "4",
            ]
        )
        == 0
    )
    path = out / "small-dust" / "small-dust_g.txt"
    rows = [line.split() for line in path.read_text().splitlines() if not line.startswith("#")]
    assert [r[0] for r in rows] == ["440", "550", "680"]
    digits = [len(v.replace("-", "").replace(".", "").lstrip("0")) for r in rows for v in r[1:]]
    assert max(digits) == 4
    assert FormatOptions(g_digits=4).recorded("g-table") == {"g_digits": 4}


def test_info_recognises_and_describes_the_example(example, config, tmp_path, capsys):
    out = tmp_path / "tables"
    assert main(["build", str(config), "--out", str(out), "--quiet", "--format", "g-table"]) == 0
    capsys.readouterr()
    assert main(["info", str(out / "small-dust" / "small-dust_g.txt")]) == 0
    text = capsys.readouterr().out
    assert text.startswith("g table:         small-dust_g.txt")
    assert "wavelengths:     3" in text


def test_the_docs_format_table_lists_the_example(example):
    table = format_table()
    row = table[table.index("* - ``g-table``") :].splitlines()[:5]
    assert row[1:] == [
        "     - ``.txt``",
        "     - NAME_g.txt: g and ssa per wavelength (an example)",
        "     - cross-sections",
        "     - ``--g-digits``",
    ]


def test_build_refuses_what_a_phase_only_model_cannot_supply(example, tmp_path, capsys):
    status = main(["build", "costa", "--out", str(tmp_path), "--format", "g-table,disort"])
    assert status == 2
    err = capsys.readouterr().err
    assert "--format disort,g-table needs cross-sections, which 'costa' does not have" in err
    assert not list(tmp_path.iterdir())


def test_without_the_example_nothing_mentions_it(capsys):
    assert "g-table" not in FORMATS and "g-table" not in format_table()
    assert main(["build", "--help-all"]) == 0
    assert "g-table" not in capsys.readouterr().out


def test_registering_a_second_record_of_a_name_is_refused():
    with pytest.raises(ValueError, match="'netcdf' is already registered"):
        register(dataclasses.replace(FORMATS["netcdf"], summary="another"))


def test_a_record_names_known_needs_only():
    with pytest.raises(ValueError, match="needs \\['colour'\\] are not among"):
        Format(name="x", summary="x", write=lambda *a, **k: [], needs=frozenset({"colour"}))
    assert set(NEEDS) == {"cross_sections", "number_density", "expansion", "matrix"}


def test_each_option_is_offered_once_in_groups_of_the_formats_that_take_it():
    groups = dict(option_groups())
    names = [f.name for fields in groups.values() for f in fields]
    assert len(names) == len(set(names))
    assert [f.name for f in groups[("exr", "ktx2", "npy")]] == ["layout", "precision"]
    assert [f.name for f in groups[("exr", "ktx2", "npy", "texture")]] == ["sampling", "n_angles"]
    assert [f.name for f in groups[("glsl",)]] == ["glsl_version"]


def test_unknown_format_options_are_refused():
    with pytest.raises(TypeError, match="no format has the options \\['n_angle'\\]"):
        FormatOptions(n_angle=3)
