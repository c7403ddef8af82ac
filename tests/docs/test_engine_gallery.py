"""The engines' gallery: scripts/engine_gallery.py draws the same bytes each run, its exact
panel is the package's own fisheye, its labels are the report's numbers, and the docs page
shows one picture per engine and planet."""

from __future__ import annotations

import dataclasses
import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

from dustoptics.models.presets import DEFAULT_PRESET
from dustoptics.sky.engines import ENGINES
from dustoptics.sky.engines.core import reference_skies
from dustoptics.sky.engines.gallery import (
    engine_panels,
    exact_dome,
    fisheye_directions,
    fisheye_from_grid,
)
from dustoptics.sky.engines.report import build_planet, shipped_report

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "engine_gallery.py"
PICTURES = ROOT / "docs" / "gallery" / "engines"
PAGE = ROOT / "docs" / "gallery" / "engines.rst"
PLANET = f"mars:{DEFAULT_PRESET}"
#: A tiny picture: 16-pixel fisheyes on a 15 x 30 deg grid (seconds).
TINY = ["--size", "16", "--zenith-step", "15", "--azimuth-step", "30"]


def _script():
    spec = importlib.util.spec_from_file_location("engine_gallery", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def mars():
    atmosphere = build_planet(PLANET)
    sky = exact_dome(
        atmosphere,
        sun_elevation_deg=45.0,
        view_zenith_deg=np.linspace(0, 90, 7),
        azimuth_step_deg=30.0,
    )
    (dome,) = reference_skies(atmosphere, sun_elevations_deg=[45.0])
    return atmosphere, sky, dome


def _rows(engine: str) -> dict:
    rows = {(r.engine, r.kind): r for r in shipped_report().rows if r.planet == PLANET}
    if (engine, "fitted") not in rows:
        pytest.skip(f"the shipped report has no {engine} rows for {PLANET}")
    return {k: rows[(engine, k)] for k in ("fitted", "community")}


def test_the_script_writes_the_same_bytes_twice(tmp_path):
    pytest.importorskip("matplotlib")
    _rows("godot")
    script = _script()
    argv = [*TINY, "--planets", PLANET, "--engines", "godot", "--sun-elevations", "0"]
    assert script.main([*argv, "--out", str(tmp_path / "a")]) == 0
    assert script.main([*argv, "--out", str(tmp_path / "b")]) == 0
    name = f"godot-{PLANET.replace(':', '-')}.png"
    first = (tmp_path / "a" / name).read_bytes()
    assert first == (tmp_path / "b" / name).read_bytes()
    assert first.startswith(b"\x89PNG\r\n\x1a\n")
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == [name]


def test_the_exact_panel_is_the_package_fisheye(mars):
    _, sky, _ = mars
    e = sky.default_exposure()
    mine = fisheye_from_grid(
        sky.view_zenith_deg, sky.view_azimuth_deg, sky.xyz(), size=24, exposure=e
    )
    assert np.array_equal(mine, sky.fisheye(size=24, exposure=e))
    assert mine[0, 0].tolist() == [0, 0, 0]  # outside the horizon circle
    zen, azi, inside = fisheye_directions(24)
    assert inside.sum() > 0.75 * 24 * 24 and zen.max() <= 90.0 and np.all(np.abs(azi) <= 180)


def test_labels_are_the_rows_numbers_and_a_tampered_row_is_refused(mars):
    atmosphere, sky, dome = mars
    rows = _rows("godot")
    panels = engine_panels(rows, atmosphere, sky, dome, size=16)
    want = [
        next(e.delta_e_mean for e in rows[k].errors if e.sun_elevation_deg == 45.0)
        for k in ("fitted", "community")
    ]
    assert panels.row_delta_e_mean == tuple(want)
    assert np.allclose(panels.delta_e_mean, want, atol=0.05)
    # The fitted sky is nearer the exact one than the community's (the table's claim).
    assert panels.delta_e_mean[0] < panels.delta_e_mean[1]
    assert all(im.shape == (16, 16, 3) and im.dtype == np.uint8 for im in panels.images)
    wrong = dataclasses.replace(
        rows["fitted"],
        errors=tuple(
            dataclasses.replace(e, delta_e_mean=e.delta_e_mean + 1.0) for e in rows["fitted"].errors
        ),
    )
    with pytest.raises(ValueError, match="the row says"):
        engine_panels({**rows, "fitted": wrong}, atmosphere, sky, dome, size=16)
    only_sunset = dataclasses.replace(
        rows["fitted"], errors=tuple(e for e in rows["fitted"].errors if e.sun_elevation_deg == 0)
    )
    with pytest.raises(ValueError, match="sun_elevation_deg must be one of"):
        engine_panels({**rows, "fitted": only_sunset}, atmosphere, sky, dome, size=16)


def test_the_docs_page_shows_every_picture_and_every_engine():
    page = PAGE.read_text(encoding="utf-8")
    assert "python scripts/engine_gallery.py" in page
    shown = set(re.findall(r"^\.\. image:: engines/(\S+\.png)$", page, re.M))
    drawn = {p.name for p in PICTURES.glob("*.png")}
    assert shown == drawn
    for engine in ENGINES:
        assert f"{engine}-earth.png" in drawn, engine
    assert f"godot-{PLANET.replace(':', '-')}.png" in drawn
    assert sum((PICTURES / name).stat().st_size for name in drawn) < 3_000_000
