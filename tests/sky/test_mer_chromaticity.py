"""The thesis's four Mars models against the rovers' sky colour (issue 28).

The chromaticity looking away from the Sun is held to CDISORT (nanodisort, the
``test`` extra) on the same optics, to 5e-4 in x and y: an independent solution
of the same column (plane-parallel; with the Sun at 30 deg and the view 60 deg
from the zenith the shell's curvature is far below that).  Measured: the
renderer is within 1e-4 of CDISORT for every model, and CDISORT with 16
streams and 10 layers within 6e-5 of 24 streams.  The thesis's own means
(Meyran 2022, section 5.1.2) are not reproduced (the docs say by how much), so
they are no test target.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from dustoptics.scattering import phase
from dustoptics.sky import compare as cmp
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import sunlit_xyz

GENERATED = Path(__file__).resolve().parents[2] / "docs" / "concepts" / "generated"
#: The issue's requirement: catch a change of 0.002 in x or y.
TOLERANCE = 5e-4
SUN_ELEVATION_DEG = 30.0


def test_mer_distance_is_zero_inside_and_signed_outside() -> None:
    (x0, x1), (y0, y1) = cmp.MER_SKY_CHROMATICITY["x"], cmp.MER_SKY_CHROMATICITY["y"]
    for x in (x0, 0.5 * (x0 + x1), x1):
        for y in (y0, 0.5 * (y0 + y1), y1):
            assert cmp.mer_distance(x, y) == (0.0, 0.0)
    assert cmp.mer_distance(x1 + 0.01, y0 - 0.02) == pytest.approx((0.01, -0.02), abs=1e-15)
    assert cmp.mer_distance(x0 - 0.002, 0.380) == pytest.approx((-0.002, 0.0), abs=1e-15)


def test_the_table_says_inside_or_by_how_much() -> None:
    rows = (
        cmp.RoverRow("a", 30.0, 0.400, 0.380, *cmp.mer_distance(0.400, 0.380)),
        cmp.RoverRow("bb", 5.0, 0.4205, 0.3750, *cmp.mer_distance(0.4205, 0.3750)),
    )
    text = cmp.RoverComparison(rows=rows, optical_depth=0.5, ground_albedo=0.2).to_text()
    lines = text.splitlines()
    assert "Bell, Savransky & Wolff 2006" in lines[0]
    assert lines[2].split() == ["a", "30.0", "0.4000", "0.3800", "inside"]
    assert lines[3].split() == ["bb", "5.0", "0.4205", "0.3750", "x", "+0.0125,", "y", "-0.0020"]
    assert "10.1029/2006JE002687" in cmp.BELL_2006


def test_collienne_is_the_thesis_model() -> None:
    # Meyran 2022, eq. (3.1) and appendix A.1.2: the molecules' coefficients,
    # the grey aerosol of optical depth 5.328e-3 with albedo 0.9 (Table 4.1)
    # and a Cornette-Shanks phase function with g = 0.8.
    grid = (360.0, 440.0, 475.0, 510.0, 680.0, 830.0)
    atm = cmp.mars_sky_atmosphere("collienne", wavelength_nm=grid)
    mol, aer = atm.constituents
    beta = (
        mol.table.cross_sections.csca_um2 * 1e-12 * mol.table.cross_sections.number_density_per_m3
    )
    c = phase.COLLIENNE2013_MARS
    expected = [5.75e-6, 5.75e-6, (5.75e-6 + 13.57e-6) / 2, 13.57e-6, 19.918e-6, 19.918e-6]
    np.testing.assert_allclose(beta, expected, rtol=1e-12)
    assert c.rayleigh_scattering_per_m == (5.75e-6, 13.57e-6, 19.918e-6)
    medium = Medium.from_atmosphere(atm)
    tau = medium.vertical_optical_depth()
    top = atm.atmosphere_radius_m - atm.planet_radius_m
    # An exponential profile of 8 km up to the top: beta H (1 - exp(-top / H)).
    np.testing.assert_allclose(
        tau[0], np.array(expected) * 8000.0 * (1 - math.exp(-top / 8000.0)), rtol=2e-3
    )
    np.testing.assert_allclose(tau[1], cmp.COLLIENNE_AEROSOL_OPTICAL_DEPTH, rtol=2e-3)
    np.testing.assert_allclose(
        aer.table.cross_sections.csca_um2 / aer.table.cross_sections.cext_um2, 0.9, rtol=1e-12
    )
    np.testing.assert_allclose(
        aer.table.g, phase.cornette_shanks1992_asymmetry(g=0.8), rtol=0, atol=2e-3
    )


@pytest.fixture(scope="module")
def rovers() -> cmp.RoverComparison:
    return cmp.mer_chromaticity(sun_elevations_deg=(SUN_ELEVATION_DEG,))


@pytest.mark.parametrize("model", cmp.MARS_MODELS)
def test_chromaticity_against_cdisort(model: str, rovers: cmp.RoverComparison) -> None:
    pytest.importorskip(
        "nanodisort",
        reason="the CDISORT reference needs nanodisort: pip install 'dustoptics[test]'",
    )
    from reference.disort import disort_radiance

    (row,) = [r for r in rovers.rows if r.model == model]
    medium = Medium.from_atmosphere(cmp.mars_sky_atmosphere(model, optical_depth=0.5))
    radiance = disort_radiance(
        medium,
        sun_zenith_deg=90.0 - SUN_ELEVATION_DEG,
        view_zenith_deg=np.array([60.0]),
        view_azimuth_deg=np.array([180.0]),
        ground_albedo=0.2,
        n_streams=16,
        n_layers=10,
        n_moments=256,
    )[0]
    xyz = sunlit_xyz(medium.wavelength_nm, radiance)
    x, y = xyz[:2] / xyz.sum()
    assert abs(row.x - x) < TOLERANCE and abs(row.y - y) < TOLERANCE, (model, row, x, y)
    assert (row.dx, row.dy) == cmp.mer_distance(row.x, row.y)


def _rows(text: str) -> dict[tuple[str, float], tuple[float, float]]:
    out = {}
    for line in text.splitlines():
        m = re.match(r"^(\S+)\s+(\d+\.\d)\s+(0\.\d{4})\s+(0\.\d{4})\s", line + " ")
        if m:
            out[(m[1], float(m[2]))] = (float(m[3]), float(m[4]))
    return out


def test_the_generated_docs_table_is_the_codes(rovers: cmp.RoverComparison) -> None:
    # docs/concepts/generated/mars_models_vs_rovers.txt is written by
    # scripts/mars_models_vs_rovers.py; its rows at 30 deg are recomputed here.
    rows = _rows((GENERATED / "mars_models_vs_rovers.txt").read_text(encoding="utf-8"))
    for r in rovers.rows:
        x, y = rows[(r.model, r.sun_elevation_deg)]
        assert abs(x - r.x) < TOLERANCE and abs(y - r.y) < TOLERANCE, (r, x, y)


def test_what_the_docs_say_of_the_generated_table() -> None:
    # docs/concepts/mars_sky_colour.rst: at optical depth 0.5 the hybrid model
    # is inside at no Sun elevation of the table, Costa's is inside with the
    # Sun low and the Blue Moon's with the Sun high; Collienne's mean is far
    # from the thesis's (x 0.313, y 0.318; Meyran 2022, section 5.1.2).
    text = (GENERATED / "mars_models_vs_rovers.txt").read_text(encoding="utf-8")
    rows = _rows(text)
    inside = {k for k, (x, y) in rows.items() if cmp.mer_distance(x, y) == (0.0, 0.0)}
    assert not [k for k in inside if k[0] == "hybrid"]
    assert {("costa", e) for e in (0.0, 10.0)} <= inside
    assert {("blue-moons", e) for e in (70.0, 80.0, 90.0)} <= inside
    assert not [k for k in inside if k[0] == "collienne"]
    assert len(rows) == 40, len(rows)
    collienne = np.array([v for k, v in rows.items() if k[0] == "collienne"]).mean(axis=0)
    assert np.all(np.abs(collienne - (0.313, 0.318)) > 0.05), collienne
