"""``dustoptics export``: a table file into other formats, placed as ``build`` places them."""

from __future__ import annotations

import pytest
from _cli import config_fixture, run_build  # noqa: F401 (fixture config)

from dustoptics.cli import main
from dustoptics.io import read_hdf5, read_seed_csv


def test_export_places_files_as_build_does(config, tmp_path, capsys):
    """export FILE --out DIR writes into DIR/NAME/, like build."""
    assert run_build(config, tmp_path / "built", "--format", "hdf5,csv") == 0
    h5 = tmp_path / "built" / "small-dust" / "small-dust.h5"
    out = tmp_path / "exported"
    assert main(["export", str(h5), "--out", str(out), "--format", "csv", "--quiet"]) == 0
    assert read_seed_csv(out / "small-dust").equals(read_hdf5(h5))
    # The same files as build's, byte for byte; exporting again is up to date.
    for name in ("MiePhaseFunctionSpectrum.csv", "MieExtinctionSpectrum.csv", "table_summary.json"):
        assert (out / "small-dust" / name).read_bytes() == (h5.parent / name).read_bytes()
    assert main(["export", str(h5), "--out", str(out), "--format", "csv"]) == 0
    assert "3 files up to date" in capsys.readouterr().out
    # Any table file is an input: export from the seed-CSV folder.
    out2 = tmp_path / "from-csv"
    assert main(["export", str(h5.parent), "--out", str(out2), "--format", "hdf5"]) == 0
    assert read_hdf5(out2 / "small-dust" / "small-dust.h5").equals(read_hdf5(h5))


@pytest.mark.parametrize("damage", ["truncate", "garbage", "missing"])
def test_damaged_or_missing_input_is_a_clean_failure(config, tmp_path, capsys, damage):
    assert run_build(config, tmp_path, "--format", "hdf5") == 0
    h5 = tmp_path / "small-dust" / "small-dust.h5"
    if damage == "truncate":
        h5.write_bytes(h5.read_bytes()[:2000])
    elif damage == "garbage":
        h5.write_bytes(b"not an hdf5 file at all")
    else:
        h5.unlink()
    capsys.readouterr()
    for argv in (
        ["info", str(h5)],
        ["export", str(h5), "--out", str(tmp_path / "x"), "--format", "csv"],
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert err.startswith("dustoptics: error: ") and "small-dust.h5" in err
        assert "Traceback" not in err
    assert not (tmp_path / "x").exists()


def _no_writing(monkeypatch):
    from dustoptics.io import outputs

    def no_work(*args, **kwargs):
        raise AssertionError("rendered before the request was checked")

    monkeypatch.setattr(outputs, "write_formats", no_work)


def test_export_over_another_table_is_refused_before_any_work(
    config, tmp_path, capsys, monkeypatch
):
    assert run_build(config, tmp_path / "a", "--format", "netcdf") == 0
    source = tmp_path / "a" / "small-dust" / "small-dust.nc"
    out = tmp_path / "out"
    argv = ["export", str(source), "--out", str(out), "--format", "netcdf", "--quiet"]
    assert main([*argv, "--number-density-per-m3", "1e8"]) == 0  # another table's inputs
    before = (out / "small-dust" / "small-dust.nc").read_bytes()
    _no_writing(monkeypatch)
    assert main(argv) == 1
    assert "hold another table (other inputs, or unreadable)" in capsys.readouterr().err
    assert (out / "small-dust" / "small-dust.nc").read_bytes() == before
    monkeypatch.undo()
    assert main([*argv, "--force"]) == 0
    assert (
        read_hdf5(out / "small-dust" / "small-dust.nc").cross_sections is None
        or read_hdf5(out / "small-dust" / "small-dust.nc").cross_sections.number_density_per_m3
        is None
    )


@pytest.mark.parametrize(
    ("formats", "needle"),
    [
        ("netcdf,disort", "needs the phase function's expansion coefficients"),
        ("libradtran", "needs the phase function's expansion coefficients"),
        ("bruneton", "--format bruneton needs a number density"),
    ],
)
def test_export_of_what_a_table_lacks_is_refused_before_any_work(
    config, tmp_path, capsys, monkeypatch, formats, needle
):
    assert run_build(config, tmp_path / "a", "--format", "netcdf") == 0
    source = tmp_path / "a" / "small-dust" / "small-dust.nc"
    _no_writing(monkeypatch)
    argv = ["export", str(source), "--out", str(tmp_path / "out"), "--format", formats]
    assert main([*argv, "--quiet"]) in (1, 2)
    err = capsys.readouterr().err
    assert needle in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


def test_a_texture_that_loses_its_normalization_is_written_with_a_one_line_warning(
    config, tmp_path, capsys
):
    """The library's warning reaches the user as ``dustoptics: warning: ...``, one line, no
    Python source location."""
    assert (
        run_build(
            config,
            tmp_path / "t",
            "--format",
            "texture",
            "--sampling",
            "cos",
            "--n-angles",
            "16",
            "--quiet",
        )
        == 0
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("dustoptics: warning: the texture's samples (cos sampling, 16 angles)")
    assert ".py:" not in err[0]
