"""``dustoptics sky``: files in ``DIR/NAME/``; sizes, presets and existing files checked first.

The sky itself is computed by :mod:`dustoptics.sky` (``tests/sky``); here the job's files are
replaced by stand-ins, so that only what the command line does is tested.
"""

from __future__ import annotations

import sys

import pytest

from dustoptics.cli import main
from dustoptics.sky.job import INPUTS_ATTRIBUTE, SkyJob
from dustoptics.table import canonical_json

xr = pytest.importorskip("xarray")


def _stand_in_files(job: SkyJob) -> dict:
    """A few bytes for each announced file, and for the netCDF file a netCDF file that records
    the job's inputs (as the job's own records them)."""
    record = xr.Dataset(attrs={INPUTS_ATTRIBUTE: canonical_json(job.inputs())})
    return dict.fromkeys(job.targets(), b"sky") | {
        job.record: bytes(record.to_netcdf(engine="scipy"))
    }


@pytest.fixture(name="stand_in")
def stand_in_fixture(monkeypatch):
    """SkyJob.files gives each announced file a stand-in (no sky is computed)."""
    monkeypatch.setattr(SkyJob, "files", _stand_in_files)


def _no_sky(monkeypatch):
    def no_work(self):
        raise AssertionError("computed before the request was checked")

    monkeypatch.setattr(SkyJob, "files", no_work)


@pytest.mark.parametrize(
    ("argv", "folder"),
    [
        (["sky", "mars", "--dust", "costa"], "mars-costa"),
        (["sky", "earth", "--sunset"], "earth"),
        (["sky", "compare", "--models", "costa,hybrid"], "mars-comparison"),
    ],
)
def test_sky_writes_into_dir_name(tmp_path, capsys, stand_in, argv, folder):
    assert main([*argv, "--out", str(tmp_path), "--quiet"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == [folder]
    names = [p.name for p in (tmp_path / folder).iterdir()]
    assert names and all(n.startswith(folder) for n in names)


def test_sky_again_with_the_same_inputs_is_up_to_date(tmp_path, capsys, stand_in, monkeypatch):
    argv = ["sky", "earth", "--out", str(tmp_path)]
    assert main(argv) == 0
    folder = tmp_path / "earth"
    assert f"earth: wrote 3 files to {folder}" in capsys.readouterr().out
    before = {p: p.stat().st_mtime_ns for p in folder.iterdir()}
    # The same inputs: up to date, exit 0, the files left untouched (as build does).
    assert main(argv) == 0
    assert f"earth: 3 files up to date in {folder} (left untouched)" in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in folder.iterdir()} == before
    # Other inputs: refused before any work without --force, replaced with it.
    _no_sky(monkeypatch)
    assert main([*argv, "--sun-elevation", "20"]) == 1
    err = capsys.readouterr().err
    assert "earth_sky.nc' exists and records another sky (other inputs); use --force" in err
    monkeypatch.setattr(SkyJob, "files", _stand_in_files)
    assert main([*argv, "--sun-elevation", "20", "--force"]) == 0
    assert "earth: wrote 1 file to " in capsys.readouterr().out  # the images are the same bytes


def _no_matplotlib(monkeypatch):
    """Imports of matplotlib fail, as in an installation without the plot extra."""
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.image", None)


@pytest.mark.parametrize("kind", ["earth", "mars", "compare"])
def test_sky_without_matplotlib_writes_the_rest_with_a_note(
    tmp_path, capsys, stand_in, monkeypatch, kind
):
    _no_matplotlib(monkeypatch)
    assert main(["sky", kind, "--out", str(tmp_path), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "note: no PNG images" in err and "dustoptics[plot]" in err
    (folder,) = tmp_path.iterdir()
    assert [p.suffix for p in folder.iterdir()] == [".nc"]
    # --no-png: the same files, no note.
    assert main(["sky", kind, "--out", str(tmp_path), "--quiet", "--no-png"]) == 0
    assert capsys.readouterr().err == ""


def test_sky_no_png_skips_the_images(tmp_path, capsys, stand_in):
    assert main(["sky", "earth", "--out", str(tmp_path), "--quiet", "--no-png"]) == 0
    assert capsys.readouterr().err == ""
    assert [p.name for p in (tmp_path / "earth").iterdir()] == ["earth_sky.nc"]
    # Images only: nothing to write without them.
    assert main(["sky", "earth", "--out", str(tmp_path), "--no-png", "--sunset"]) == 2
    err = capsys.readouterr().err
    assert "with --no-png, --sunset would write nothing (PNG images only)" in err


@pytest.mark.parametrize(
    ("options", "needle"),
    [
        (["earth", "--size", "8"], "--size: must be an integer in [16, 8192]"),
        (["mars", "--dust", "nope"], "--dust: unknown preset 'nope'"),
        (["mars", "--dust", "../x"], "--dust: unknown preset '../x'"),
        (["compare", "--models", "costa,my dust"], "--models: unknown preset 'my dust'"),
    ],
)
def test_sky_options_that_would_fail_are_refused_before_any_work(
    tmp_path, capsys, monkeypatch, options, needle
):
    _no_sky(monkeypatch)
    assert main(["sky", *options, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
