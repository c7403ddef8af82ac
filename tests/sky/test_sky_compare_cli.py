"""``dustoptics sky compare`` prints the rover table it wrote (issue 28)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from dustoptics.cli import main
from dustoptics.sky import compare as cmp

pytest.importorskip("xarray")
pytest.importorskip("matplotlib")


def test_sky_compare_prints_the_rover_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    real = cmp.compare_mars_models

    def coarse(**kwargs: Any) -> Any:
        # The command's own computation on a coarser sky, to run in a test.
        return real(**kwargs, sun_elevations_deg=(30.0,), azimuth_step_deg=45.0)

    monkeypatch.setattr(cmp, "compare_mars_models", coarse)
    out = tmp_path / "skies"
    assert main(["sky", "compare", "--models", "collienne,hybrid", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    table = cmp.read_rover_comparison(out / "mars-comparison" / "mars-comparison.nc")
    assert table.to_text() in printed
    assert [(r.model, r.sun_elevation_deg) for r in table.rows] == [
        ("collienne", 30.0),
        ("hybrid", 30.0),
    ]
    # The rows are the chromaticity the dataset holds, with the verdict of each.
    for r in table.rows:
        assert (r.dx, r.dy) == cmp.mer_distance(r.x, r.y)
        assert (r.verdict == "inside") == r.inside
