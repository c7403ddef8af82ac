"""``dustoptics sky``: files written whole, errors before any work."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from dustoptics.cli import main
from dustoptics.sky.job import INPUTS_ATTRIBUTE

xr = pytest.importorskip("xarray")
mpl_image = pytest.importorskip("matplotlib.image")


def test_sky_earth_writes_images_and_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sky"
    argv = ["sky", "earth", "--sun-elevation", "30", "--size", "64", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    names = sorted(p.name for p in (out / "earth").iterdir())  # DIR/NAME/, as build writes
    assert names == ["earth_fisheye.png", "earth_panorama.png", "earth_sky.nc"]
    img = mpl_image.imread(out / "earth" / "earth_fisheye.png")
    assert img.shape[:2] == (64, 64)
    ds = xr.open_dataset(out / "earth" / "earth_sky.nc", engine="scipy")
    assert ds.radiance.attrs["units"] == "sr-1"
    assert np.all(ds.radiance.values >= 0)
    # Zenith of a clear Earth sky: bluer than the sunlight's white.
    assert float(ds.chromaticity_x[0, 0]) < 0.30
    assert json.loads(ds.attrs[INPUTS_ATTRIBUTE])["sun_elevation_deg"] == 30.0
    # Again with the same inputs: the same bytes, up to date (exit 0), as build does.
    before = {p: p.read_bytes() for p in (out / "earth").iterdir()}
    assert main(argv[:-1]) == 0
    assert "earth: 3 files up to date in " in capsys.readouterr().out
    assert {p: p.read_bytes() for p in (out / "earth").iterdir()} == before
    # Other inputs: not replaced without --force (exit 1), before any work.
    assert main([*argv, "--albedo", "0.3"]) == 1
    assert "records another sky" in capsys.readouterr().err
    assert main([*argv, "--albedo", "0.3", "--force"]) == 0


def test_sky_reports_progress_without_quiet(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import re

    from dustoptics.sky import _progress

    monkeypatch.setattr(_progress, "QUIET_SECONDS", 0.0)  # report from the start
    argv = ["sky", "earth", "--sun-elevation", "30", "--size", "32", "--out", str(tmp_path)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    # What, k of n, and the time since the start, on stderr.
    assert re.search(r"sky: orders of scattering: \d+ orders .*, [\d.]+ s", err)
    n = 121 * 91  # the dome: default view zenith angles x 2 degree azimuths
    assert f"sky: lines of sight: {n} of {n}, " in err
    # --quiet: none.
    assert main([*argv, "--force", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_sky_size_beyond_the_largest_is_refused_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status = main(["sky", "earth", "--size", "9000", "--out", str(tmp_path / "x")])
    assert status != 0
    err = capsys.readouterr().err
    assert "size_px = 9000 pixels is beyond the largest allowed, 8192" in err
    assert "--allow-large" in err
    assert not (tmp_path / "x").exists()


def test_sky_earth_space_writes_the_limb(tmp_path: Path) -> None:
    out = tmp_path / "sky"
    argv = ["sky", "earth", "--sun-elevation", "30", "--size", "32", "--space"]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0
    img = mpl_image.imread(out / "earth" / "earth_limb.png")
    # A labelled figure of the 1200 x 400 pixel view (LimbRadiance.view_png), axes around it.
    assert img.shape[1] >= 1200 and img.shape[0] >= 400
    # The view: black space and planet (the surface is not rendered) around a lit limb whose
    # brightest pixel is white (the default exposure puts the brightest of the limb there).
    rgb = img[..., :3]
    assert np.mean(np.all(rgb < 0.02, axis=-1)) > 0.3
    assert rgb.max() == 1.0


@pytest.mark.parametrize(
    "extra",
    [["--sun-elevation", "-40"], ["--albedo", "2"]],
)
def test_sky_usage_errors(
    tmp_path: Path, extra: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["sky", "earth", "--out", str(tmp_path / "x"), *extra]) == 2
    assert "error" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
