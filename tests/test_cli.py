"""Tests for the ``dustoptics`` command line, called through ``main(argv)``.

Builds use two wavelengths, 19 angles and rtol 1e-3 (about half a second each).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from _shared import shared_path

import dustoptics as do
from dustoptics import cli
from dustoptics.io.seed_csv import (
    EXTINCTION_FILENAME,
    PHASE_FILENAME,
    SEED_CSV_FILES,
    read_phase_csv,
    read_seed_csv,
)

QUICK = ["--wavelengths-nm", "440,550", "--n-theta", "19", "--rtol", "1e-3"]


def _build(tmp_path, *extra: str) -> list[str]:
    return ["build", "mars-dust", "--out", str(tmp_path), *QUICK, *extra]


def test_build_writes_the_files(tmp_path, capsys):
    assert cli.main(_build(tmp_path)) == 0
    out, err = capsys.readouterr()
    target = tmp_path / "mars-dust"
    assert sorted(p.name for p in target.iterdir()) == sorted(SEED_CSV_FILES)
    for name in SEED_CSV_FILES:
        assert f"wrote {target / name}" in out
    assert "worst error_estimate" in out
    assert "computing 2 wavelengths x 19 angles" in err  # progress goes to stderr
    table = read_seed_csv(target)
    assert table.wavelength_nm.tolist() == [440.0, 550.0]
    np.testing.assert_array_equal(table.theta_deg, np.linspace(0.0, 180.0, 19))


def test_quiet_build_prints_no_progress(tmp_path, capsys):
    assert cli.main(_build(tmp_path, "--quiet")) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert "wrote" in out


def test_two_builds_give_identical_bytes(tmp_path, capsys):
    assert cli.main(_build(tmp_path / "a", "--quiet")) == 0
    assert cli.main(_build(tmp_path / "b", "--quiet")) == 0
    for name in SEED_CSV_FILES:
        first = (tmp_path / "a" / "mars-dust" / name).read_bytes()
        assert first == (tmp_path / "b" / "mars-dust" / name).read_bytes(), name


def test_existing_output_needs_force(tmp_path, capsys):
    target = tmp_path / "mars-dust"
    target.mkdir()
    (target / PHASE_FILENAME).write_text("keep me\n")
    assert cli.main(_build(tmp_path, "--quiet")) == 1
    err = capsys.readouterr().err
    assert f"dustoptics: error: {target / PHASE_FILENAME} already exists" in err
    assert "--force" in err and "Traceback" not in err
    assert (target / PHASE_FILENAME).read_text() == "keep me\n"
    assert not (target / EXTINCTION_FILENAME).exists()  # checked before computing or writing
    assert cli.main(_build(tmp_path, "--quiet", "--force")) == 0
    assert read_phase_csv(target / PHASE_FILENAME).phase.shape == (2, 19)


def test_seed_preset_reproduces_the_seed_table(tmp_path, capsys):
    """mars-dust-seed: number weighting on the seed's 1,800 angles (BRIEF section 5)."""
    seed_path = shared_path("seed-tables", PHASE_FILENAME)
    args = [
        "build",
        "mars-dust-seed",
        "--out",
        str(tmp_path),
        "--wavelengths-nm",
        "550",
        "--rtol",
        "1e-3",
    ]
    assert cli.main(args) == 0
    ours_text = (tmp_path / "mars-dust-seed" / PHASE_FILENAME).read_text().splitlines()
    seed_text = seed_path.read_text().splitlines()
    # The same angle column, character for character.
    assert [line.split(",", 1)[0] for line in ours_text] == [line.split(",", 1)[0] for line in seed_text]
    ours, seed = read_phase_csv(tmp_path / "mars-dust-seed" / PHASE_FILENAME), read_phase_csv(seed_path)
    column = int(np.flatnonzero(seed.wavelength_nm == 550.0)[0])
    relative = np.abs(ours.phase[0] / seed.phase[column] - 1.0)
    # The seed's Monte-Carlo noise: 0.4-0.5 % median, about 3 % maximum.
    assert np.median(relative) < 0.01
    assert relative.max() < 0.05


def test_unknown_preset_is_a_usage_error(capsys):
    assert cli.main(["build", "nope"]) == 2
    err = capsys.readouterr().err
    assert "nope" in err
    for name in cli.PRESETS:
        assert name in err


@pytest.mark.parametrize(
    ("args", "parameter", "message"),
    [
        (["--rtol", "-1"], "--rtol", "open interval"),
        (["--rtol", "abc"], "--rtol", "must be a number"),
        (["--rtol", "0.5"], "--rtol", "open interval"),
        (["--wavelengths-nm", "550,440"], "--wavelengths-nm", "strictly increasing"),
        (["--wavelengths-nm", "440,,550"], "--wavelengths-nm", "comma-separated"),
        (["--wavelengths-nm", "blue"], "--wavelengths-nm", "not a number"),
        (["--wavelengths-nm", "0,550"], "--wavelengths-nm", "> 0 nm"),
        (["--n-theta", "1"], "--n-theta", ">= 2"),
        (["--n-theta", "1.5"], "--n-theta", "integer"),
    ],
)
def test_bad_options_exit_2_naming_the_parameter(tmp_path, capsys, args, parameter, message):
    assert cli.main(["build", "--out", str(tmp_path), *args]) == 2
    err = capsys.readouterr().err
    assert f"argument {parameter}: " in err and message in err
    assert not any(tmp_path.iterdir())


def test_library_error_exits_1_without_traceback(tmp_path, capsys):
    args = ["build", "--out", str(tmp_path), "--wavelengths-nm", "100", "--n-theta", "3", "--quiet"]
    assert cli.main(args) == 1
    err = capsys.readouterr().err
    assert err.startswith("dustoptics: error: ") and "range" in err
    assert "Traceback" not in err


def test_version(capsys):
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"dustoptics {do.__version__}"


def test_no_command_is_a_usage_error(capsys):
    assert cli.main([]) == 2
    assert "COMMAND" in capsys.readouterr().err


def test_presets_lists_names_and_sources(capsys):
    assert cli.main(["presets"]) == 0
    out = capsys.readouterr().out
    for name, preset in cli.PRESETS.items():
        assert name in out and preset.description in out and preset.source in out


def test_materials_lists_the_catalogue(capsys):
    assert cli.main(["materials"]) == 0
    assert capsys.readouterr().out.split() == list(do.list_materials())


def test_broken_pipe_is_not_an_error(monkeypatch):
    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    assert cli.main(["materials"]) == 0


def test_build_function_rejects_unknown_preset(tmp_path):
    with pytest.raises(KeyError, match="mars-dust, mars-dust-seed"):
        cli.build("nope", tmp_path)


def test_module_entry_point_runs():
    done = subprocess.run(
        [sys.executable, "-m", "dustoptics.cli", "--version"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0
    assert done.stdout.strip() == f"dustoptics {do.__version__}"


def test_broken_pipe_during_help_is_not_an_error(monkeypatch):
    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    assert cli.main(["build", "--help"]) == 0
