"""The search for a published Mars dust inside the rovers' colour range (issue 28)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from dustoptics._validation import BudgetError
from dustoptics.sky import mer_search as ms
from dustoptics.sky.compare import mer_distance

SEARCH_TABLE = (
    Path(__file__).resolve().parents[2] / "docs" / "concepts" / "generated" / "mer_dust_search.txt"
)


def test_the_grid_is_bounded_before_any_work() -> None:
    many = tuple(0.1 * k for k in range(1, 60))
    n = len(ms.PUBLISHED_DUSTS) * len(many) * 2 * 2
    with pytest.raises(BudgetError, match=rf"would render {n} skies .* budget of 200"):
        ms.search_mer_dust(optical_depths=many)
    with pytest.raises(ValueError, match="optical_depths"):
        ms.search_mer_dust(optical_depths=(0.5, -1.0))
    with pytest.raises(ValueError, match="ground_albedos"):
        ms.search_mer_dust(ground_albedos=(1.5,))
    with pytest.raises(ValueError, match="dusts"):
        ms.search_mer_dust(dusts=())


def test_every_dust_names_its_sources() -> None:
    for d in ms.PUBLISHED_DUSTS:
        assert re.search(r"(Wolff|Tomasko|Ehlers) et al\. \d{4}", d.sources), d
        assert d.r_eff_um > 0 and 0 < d.v_eff < 0.5


def test_the_generated_table_is_the_codes() -> None:
    # docs/concepts/generated/mer_dust_search.txt is written by
    # scripts/mer_dust_search.py; the row its verdict names (the first inside
    # the range, or the closest) is recomputed here, one sky.
    text = SEARCH_TABLE.read_text(encoding="utf-8")
    verdict = text.strip().splitlines()[-1]
    rows = [
        m.groups()
        for m in re.finditer(
            r"^(\S+)\s+(\d\.\d\d)\s+(\d\.\d\d)\s+(\d+\.\d)\s+(0\.\d{4})\s+(0\.\d{4})\s+(.*)$",
            text,
            flags=re.MULTILINE,
        )
    ]
    assert len(rows) == 64, len(rows)
    inside = [r for r in rows if r[6] == "inside"]
    assert verdict.startswith(f"{len(inside)} of 64 inside the range"), verdict
    # What docs/concepts/mars_sky_colour.rst says of the table: some rows are
    # inside, each with the Sun at 60 degree; the Blue Moon's dust at the lower
    # optical depths, Wolff et al.'s index at the higher ones.
    assert inside and all(float(r[3]) == 60.0 for r in inside)
    assert max(float(r[1]) for r in inside if r[0].startswith("blue-moons")) <= 0.5
    assert min(float(r[1]) for r in inside if r[0].startswith("wolff2009")) >= 1.0
    if inside:
        name, tau, albedo, sun, x, y, _ = inside[0]
    else:
        m = re.search(r"closest: (\S+), tau (\S+), albedo (\S+), Sun (\S+) degree", verdict)
        assert m is not None, verdict
        name, tau, albedo, sun = m.groups()
        (x, y) = next(
            r[4:6]
            for r in rows
            if r[0] == name
            and float(r[1]) == float(tau)
            and float(r[2]) == float(albedo)
            and float(r[3]) == float(sun)
        )
    (dust,) = [d for d in ms.PUBLISHED_DUSTS if d.name == name]
    again = ms.search_mer_dust(
        dusts=(dust,),
        optical_depths=(float(tau),),
        ground_albedos=(float(albedo),),
        sun_elevations_deg=(float(sun),),
    )
    (row,) = again.rows
    assert abs(row.x - float(x)) < 5e-4 and abs(row.y - float(y)) < 5e-4, (row, x, y)
    assert (row.dx, row.dy) == mer_distance(row.x, row.y)
    assert (row.distance == 0.0) == bool(inside)
