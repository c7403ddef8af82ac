"""Hardening of the command line: where files go, whole sets, bad input as one line (issue 15).

Each test reproduces a defect found by fuzzing main at 3e27677 and checks it is gone.
"""

from __future__ import annotations

import dataclasses
import errno
import os

import pytest

from dustoptics.cli import main
from dustoptics.io import _atomic
from dustoptics.models.build import TableBuilder

SMALL = """\
name = "{name}"
description = "a small table for the hardening tests"
[material]
model = "constant"
n = 1.5
k = 0.001

[size_distribution]
model = "modified_gamma"
r_eff_um = 0.5
v_eff = 0.1

[optics]
rtol = 1e-2
wavelengths_nm = [440.0, 550.0, 680.0]
n_theta = 19

[phase]
model = "mie"
"""


def _config(tmp_path, name="small", **replace):
    text = SMALL.replace("{name}", name)
    for key, value in replace.items():
        text = text.replace(key, value)
    path = tmp_path / f"cfg-{abs(hash((name, tuple(replace.items()))))}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dustoptics: error: "), err
    return lines[0]


@pytest.mark.parametrize("name", ["../escaped", "/tmp/absolute", "a/b", "..", "x\x1b[31m", "-rf"])
def test_a_name_that_is_not_a_plain_file_name_is_refused(tmp_path, capsys, name):
    config = _config(tmp_path, name=name.replace("\x1b", "\\u001b"))
    out = tmp_path / "out" / "sub"
    assert main(["build", str(config), "--out", str(out), "--format", "csv", "--quiet"]) == 2
    assert "name" in _error_line(capsys)
    assert not (tmp_path / "out").exists() and not (tmp_path / "escaped").exists()


def test_an_output_directory_symlinked_out_of_out_is_refused(tmp_path, capsys):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "small").symlink_to(elsewhere)
    assert main(["build", str(_config(tmp_path)), "--out", str(out), "--quiet", "--force"]) == 1
    assert "outside the output directory" in _error_line(capsys)
    assert list(elsewhere.iterdir()) == []


def test_cosmoscout_needs_are_checked_before_computing(tmp_path, capsys, monkeypatch):
    def no_work(self):
        raise AssertionError("computed before the formats' needs were checked")

    monkeypatch.setattr(TableBuilder, "build", no_work)
    argv = [
        "build",
        str(_config(tmp_path)),
        "--out",
        str(tmp_path / "out"),
        "--format",
        "hdf5,cosmoscout",
    ]
    assert main([*argv, "--quiet"]) == 2
    assert "number density" in _error_line(capsys)


def test_a_failing_format_leaves_the_old_set(tmp_path, capsys, monkeypatch):
    config, out = _config(tmp_path), tmp_path / "out"
    assert main(["build", str(config), "--out", str(out), "--quiet", "--format", "hdf5,csv"]) == 0
    before = {p.name: p.read_bytes() for p in (out / "small").iterdir()}
    # The same set again, with a different table, and a third format that fails.
    config2 = _config(tmp_path, **{"r_eff_um = 0.5": "r_eff_um = 0.6"})
    from dustoptics import io

    def failing(*args, **kwargs):
        raise ValueError("glsl rejects this table (simulated)")

    monkeypatch.setitem(io.FORMATS, "glsl", dataclasses.replace(io.FORMATS["glsl"], write=failing))
    argv = [
        "build",
        str(config2),
        "--out",
        str(out),
        "--quiet",
        "--force",
        "--format",
        "hdf5,csv,glsl",
    ]
    assert main(argv) == 1
    _error_line(capsys)
    assert {p.name: p.read_bytes() for p in (out / "small").iterdir()} == before


def test_full_disk_leaves_the_old_set_with_a_one_line_error(tmp_path, capsys, monkeypatch):
    config, out = _config(tmp_path), tmp_path / "out"
    assert main(["build", str(config), "--out", str(out), "--quiet", "--format", "hdf5,csv"]) == 0
    before = {p.name: p.read_bytes() for p in (out / "small").iterdir()}
    real = _atomic._write_new

    def full(path, content):
        if path.suffix == ".csv":
            raise OSError(
                errno.ENOSPC, "No space left on device\nsecond line of a library's message"
            )
        return real(path, content)

    monkeypatch.setattr(_atomic, "_write_new", full)
    config2 = _config(tmp_path, **{"r_eff_um = 0.5": "r_eff_um = 0.6"})
    assert (
        main(
            ["build", str(config2), "--out", str(out), "--quiet", "--force", "--format", "hdf5,csv"]
        )
        == 1
    )
    line = _error_line(capsys)
    assert "No space left on device" in line
    assert "MiePhaseFunctionSpectrum.csv" in line  # the file that could not be written
    assert {p.name: p.read_bytes() for p in (out / "small").iterdir()} == before


def test_leftovers_of_a_killed_run_do_not_block_a_rerun(tmp_path, capsys):
    out = tmp_path / "out" / "small"
    out.mkdir(parents=True)
    (out / ".small.nc.k3j4l5m6.tmp").write_bytes(
        b"half an HDF5 file"
    )  # an older version's temporary
    (out / ".dustoptics-stage-abcd1234").mkdir()  # a staging directory whose lock is free
    (out / ".dustoptics-stage-abcd1234" / "small.nc").write_bytes(b"half")
    assert main(["build", str(_config(tmp_path)), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert "small.nc" in names and not any(_atomic.is_leftover(n) for n in names)


def test_a_request_beyond_the_budget_names_the_flag(tmp_path, capsys):
    config = _config(tmp_path, **{"r_eff_um = 0.5": "r_eff_um = 1000.0"})
    assert main(["build", str(config), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    line = _error_line(capsys)
    assert "--allow-large" in line and "r_eff_um" in line


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("n_theta = 19", "n_theta = 9223372036854775807", "n_theta"),
        (
            "wavelengths_nm = [440.0, 550.0, 680.0]",
            "wavelengths_nm = { start = 1.0, stop = 1e12, step = 1.0 }",
            "wavelengths",
        ),
        ("wavelengths_nm = [440.0, 550.0, 680.0]", "wavelengths_nm = [0.44, 0.55]", "micrometres"),
        ("r_eff_um = 0.5", 'r_eff_um = "1.5"', "r_eff_um"),
        ("v_eff = 0.1", "v_eff = 1e-15", "v_eff"),
    ],
)
def test_bad_configurations_are_one_line_errors(tmp_path, capsys, key, value, message):
    config = _config(tmp_path, **{key: value})
    assert main(["build", str(config), "--out", str(tmp_path / "out"), "--quiet"]) in (1, 2)
    assert message in _error_line(capsys)
    assert not (tmp_path / "out").exists()


def test_a_fifo_as_ozone_csv_is_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "ozone.csv"
    os.mkfifo(fifo)
    argv = ["build", "earth", "--out", str(tmp_path / "out"), "--ozone-csv", str(fifo), "--quiet"]
    assert main(argv) == 1
    assert "not a regular file" in _error_line(capsys)


def test_info_escapes_what_the_file_says(tmp_path, capsys):
    import dustoptics as do

    table = do.compute_optics(
        1.5 + 0.01j,
        do.Monodisperse(radius_um=0.5),
        [550.0],
        [0.0, 90.0, 180.0],
        name="evil\x1b]0;pwned\x07\x1b[2J",
    )
    path = tmp_path / "evil.h5"
    do.io.write_hdf5(table, path)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\\x1b]0;pwned" in out


@pytest.mark.parametrize(
    ("options", "message"),
    [
        # found by scripts/fuzz.py: MemoryError / IndexError tracebacks before
        (["--format", "glsl", "--resolution-deg", "1e-9"], "resolution_deg"),
        (["--format", "texture", "--n-angles", "100000000000"], "n_angles"),
        (
            [
                "--format",
                "cosmoscout",
                "--number-density-per-m3",
                "1",
                "--n-altitudes",
                "9223372036854775807",
            ],
            "n_altitudes",
        ),
        (["--format", ""], "unknown format"),  # argparse's usage error, on one line
    ],
)
def test_export_options_beyond_their_limits_are_one_line_errors(tmp_path, capsys, options, message):
    import dustoptics as do

    table = do.compute_optics(
        1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 90.0, 180.0], name="small"
    )
    do.io.write_hdf5(table, tmp_path / "small.h5")
    argv = [
        "export",
        str(tmp_path / "small.h5"),
        "--out",
        str(tmp_path / "out"),
        "--quiet",
        *options,
    ]
    assert main(argv) in (1, 2)
    assert message in _error_line(capsys)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "options",
    [
        ["--format", "hdf5,csv,glsl", "--channels-nm", "1000,550,440"],  # outside 440-680 nm
        ["--format", "glsl", "--colour", "cie1931-xyz"],  # 440-680 nm does not cover the bands
        ["--format", "glsl", "--resolution-deg", "0.7"],  # does not divide 180 deg
    ],
)
def test_glsl_options_are_checked_before_computing(tmp_path, capsys, monkeypatch, options):
    def no_work(self):
        raise AssertionError("computed before the formats' needs were checked")

    monkeypatch.setattr(TableBuilder, "build", no_work)
    argv = ["build", str(_config(tmp_path)), "--out", str(tmp_path / "out"), "--quiet", *options]
    assert main(argv) in (1, 2)
    _error_line(capsys)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kind", ["fifo", "device", "large", "binary"])
def test_a_configuration_that_is_not_a_small_text_file_is_refused_before_reading(
    tmp_path, capsys, kind
):
    """``build CONFIG`` reads through the guarded reader, as ``sweep`` and ``retrieve --model``:
    a FIFO (which hung), /dev/zero (MemoryError), a file over the limit, bytes that are not
    UTF-8."""
    from dustoptics._files import MAX_CONFIG_BYTES

    path = tmp_path / "model.toml"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":
        path = "/dev/zero"
    elif kind == "large":
        with open(path, "wb") as f:
            f.truncate(MAX_CONFIG_BYTES + 1)
    else:
        path.write_bytes(b"name = \xff\xfe\n")
    assert main(["build", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    line = _error_line(capsys)
    assert str(path) in line
    assert ("not a regular file" in line) if kind in ("fifo", "device") else True
    assert ("limit" in line) if kind == "large" else True
    assert ("not UTF-8" in line) if kind == "binary" else True
    assert not (tmp_path / "out").exists()


def test_more_sweep_workers_than_a_machine_holds_is_a_usage_error(tmp_path, capsys):
    """--workers 1000 started a thousand processes and failed after minutes."""
    most = 4 * (os.cpu_count() or 1)
    argv = ["sweep", "blue-moons", "--out", str(tmp_path / "s.zarr"), "--workers", str(most + 1)]
    pytest.importorskip("dask")
    assert main(argv) == 1
    assert f"at most {most} worker processes" in _error_line(capsys)
    assert not (tmp_path / "s.zarr").exists()
