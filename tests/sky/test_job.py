"""dustoptics.sky.job: a sky as files, named before any work and written as one set."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from dustoptics._validation import BudgetError
from dustoptics.sky import scene, space
from dustoptics.sky.job import SUNSET_ELEVATIONS_DEG, SkyJob


def test_targets_are_known_before_any_work(tmp_path: Path) -> None:
    job = SkyJob("mars", out_dir=tmp_path, dust="costa", sunset=True, space=True)
    assert job.name == "mars-costa" and job.sun_elevation_deg == 10.0
    names = [p.name for p in job.targets()]
    assert names[:3] == ["mars-costa_sky.nc", "mars-costa_fisheye.png", "mars-costa_panorama.png"]
    assert names[3:-1] == [f"mars-costa_sunset_{e:+05.1f}.png" for e in SUNSET_ELEVATIONS_DEG]
    assert names[-1] == "mars-costa_limb.png"
    assert {p.parent for p in job.targets()} == {tmp_path}
    compare = SkyJob("compare", out_dir=str(tmp_path))
    assert compare.out_dir == tmp_path and compare.name == "mars-comparison"
    assert [p.name for p in compare.targets()] == [
        "mars-comparison.nc",
        "mars-comparison_radiance.png",
        "mars-comparison_luminance.png",
        "mars-comparison_chromaticity.png",
        "mars-comparison_transmittance.png",
    ]
    assert SkyJob("earth", out_dir=tmp_path).sun_elevation_deg == 45.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "venus"}, "kind must be one of 'mars', 'earth', 'compare'; got 'venus'"),
        ({"kind": "earth", "sun_elevation_deg": -40.0}, r"sun_elevation_deg must be within"),
        ({"kind": "mars", "albedo": 2.0}, r"albedo must be within \[0, 1\]; got 2.0"),
    ],
)
def test_bad_parameters_are_refused(tmp_path: Path, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SkyJob(out_dir=tmp_path, **kwargs)


def test_write_refuses_existing_files_before_any_work(tmp_path: Path, monkeypatch) -> None:
    job = SkyJob("earth", out_dir=tmp_path, size_px=16)
    job.targets()[1].write_bytes(b"old")

    def no_work(self):
        raise AssertionError("computed before the targets were checked")

    monkeypatch.setattr(SkyJob, "files", no_work)
    with pytest.raises(FileExistsError, match="earth_fisheye.png"):
        job.write()


def test_write_gives_the_files_it_announced(tmp_path: Path) -> None:
    pytest.importorskip("xarray")
    job = SkyJob("earth", out_dir=tmp_path, sun_elevation_deg=30.0, size_px=16)
    written = job.write()
    assert written == job.targets()
    assert all(p.stat().st_size > 0 for p in written)
    with pytest.raises(FileExistsError):
        job.write()


def test_an_image_beyond_the_largest_needs_allow_large(tmp_path: Path) -> None:
    with pytest.raises(BudgetError, match=r"size_px = 8193 pixels .* allow_large=True"):
        SkyJob("mars", out_dir=tmp_path, size_px=8193)
    assert SkyJob("mars", out_dir=tmp_path, size_px=8193, allow_large=True).size_px == 8193
    with pytest.raises(ValueError, match="size_px must be an integer >= 16"):
        SkyJob("earth", out_dir=tmp_path, size_px=8)


def test_matplotlib_is_checked_before_any_work(tmp_path: Path, monkeypatch) -> None:
    def missing() -> None:
        raise ImportError("writing PNG images needs matplotlib")

    def no_work(self):
        raise AssertionError("computed before matplotlib was checked")

    monkeypatch.setattr(scene, "check_png_support", missing)
    monkeypatch.setattr(SkyJob, "files", no_work)
    for kind in ("earth", "compare"):
        with pytest.raises(ImportError, match="matplotlib"):
            SkyJob(kind, out_dir=tmp_path).write()
    assert not any(tmp_path.iterdir())


def test_the_limb_budget_is_checked_before_the_sky(tmp_path: Path, monkeypatch) -> None:
    # A work budget below one diffuse field: the limb (--space) is refused, and the sky over
    # the dome, computed first, is never started.
    def no_sky(*args, **kwargs):
        raise AssertionError("the sky was computed before the limb's budget was checked")

    monkeypatch.setattr(space, "WORK_BUDGET", 1.0)
    monkeypatch.setattr(scene, "sky_radiance", no_sky)
    job = SkyJob("earth", out_dir=tmp_path, size_px=16, space=True)
    with pytest.raises(BudgetError, match="limb_radiance would solve"):
        job.write()
    assert not any(tmp_path.iterdir())


def test_without_png_the_job_is_the_netcdf_file_only(tmp_path: Path, monkeypatch) -> None:
    def missing() -> None:
        raise ImportError("writing PNG images needs matplotlib")

    monkeypatch.setattr(scene, "check_png_support", missing)
    for kind in ("mars", "earth", "compare"):
        job = SkyJob(kind, out_dir=tmp_path, png=False)
        assert [p.suffix for p in job.targets()] == [".nc"] and job.record == job.targets()[0]
    with pytest.raises(ValueError, match="sunset and space give PNG images only"):
        SkyJob("earth", out_dir=tmp_path, png=False, sunset=True)


def test_place_leaves_the_same_files_and_refuses_other_inputs(tmp_path: Path) -> None:
    pytest.importorskip("xarray")
    job = SkyJob("earth", out_dir=tmp_path, sun_elevation_deg=30.0, png=False)
    assert job.place().written == (job.record,)
    assert job.recorded_inputs() == json.loads(json.dumps(job.inputs()))
    placed = job.place()
    assert placed.written == () and placed.unchanged == (job.record,)
    other = SkyJob("earth", out_dir=tmp_path, sun_elevation_deg=20.0, png=False)
    with pytest.raises(FileExistsError, match="records another sky"):
        other.place()
    assert other.place(force=True).written == (job.record,)


def test_the_sky_colour_summary_reads_the_zenith_and_the_horizon(tmp_path):
    """D65's chromaticity (IEC 61966-2-1: x 0.3127, y 0.3290) is sRGB white; a horizon twice
    as bright as the zenith gives a luminance ratio of 2."""
    import numpy as np
    import xarray as xr

    from dustoptics.sky.job import sky_colour_summary

    zenith_deg, azimuth_deg = np.array([0.0, 45.0, 90.0]), np.array([0.0, 90.0, 180.0])
    x = np.full((3, 3), 0.3127)
    y = np.full((3, 3), 0.3290)
    lum = np.ones((3, 3))
    lum[2, 2] = 2.0
    dims = ("view_zenith_angle", "view_azimuth_angle")
    ds = xr.Dataset(
        {"chromaticity_x": (dims, x), "chromaticity_y": (dims, y), "luminance_factor": (dims, lum)},
        coords={"view_zenith_angle": zenith_deg, "view_azimuth_angle": azimuth_deg},
    )
    path = tmp_path / "white_sky.nc"
    ds.to_netcdf(path, engine="scipy")
    lines = sky_colour_summary(path).splitlines()
    assert lines[0] == "zenith: xy 0.3127, 0.3290, sRGB #ffffff"
    assert lines[1] == "horizon away from the Sun: xy 0.3127, 0.3290, sRGB #ffffff"
    assert lines[2] == "horizon / zenith luminance: 2"
