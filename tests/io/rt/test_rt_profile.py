"""The vertical profile of the DISORT and libRadtran files: the layers asked for, their column,
``--optical-depth``, and the options refused where they cannot be honoured."""

from __future__ import annotations

import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest
from _rt_table import N_M3, rt_table

from dustoptics.cli import main
from dustoptics.io.rt.disort import read_disort
from dustoptics.io.rt.profile import read_profile_file, rt_layers


def test_default_is_the_one_layer_of_before() -> None:
    layers = rt_layers()
    assert (layers.bottom_km, layers.top_km, layers.column_m) == ((0.0,), (1.0,), (1000.0,))


def test_exponential_layers_hold_equal_shares_of_the_closed_form_column() -> None:
    h, top = 11_100.0, 50_000.0
    layers = rt_layers(scale_height_m=h, top_altitude_m=top, n_layers=4)
    column = h * -math.expm1(-top / h)  # int_0^top exp(-z/H) dz
    assert layers.total_column_m == pytest.approx(column, rel=1e-14)
    # Boundaries rounded to 1 m: each share within exp(0) * 1 m of a quarter.
    np.testing.assert_allclose(layers.column_m, column / 4, atol=1.0)
    assert layers.bottom_km[0] == 0.0 and layers.top_km[-1] == 50.0
    assert layers.top_km[:-1] == layers.bottom_km[1:]
    # Each layer's column is the closed form between its boundaries.
    for b, t, c in zip(layers.bottom_km, layers.top_km, layers.column_m, strict=True):
        assert c == pytest.approx(h * (math.exp(-b * 1e3 / h) - math.exp(-t * 1e3 / h)), rel=1e-12)


def test_uniform_layers_to_a_top() -> None:
    layers = rt_layers(top_altitude_m=5000.0, n_layers=2)
    assert layers.bottom_km == (0.0, 2.5) and layers.top_km == (2.5, 5.0)
    np.testing.assert_array_equal(layers.relative_density, 1.0)


def test_profile_file(tmp_path: Path) -> None:
    path = tmp_path / "dust.txt"
    path.write_text("# altitude [km], relative density\n0 2\n10, 2\n30 0\n")
    profile = read_profile_file(path)
    assert profile.density == (1.0, 1.0, 0.0)
    layers = rt_layers(profile_file=path)
    # Trapezoids: 10 km at 1, then 20 km from 1 to 0.
    assert layers.column_m == (10_000.0, 10_000.0)
    np.testing.assert_allclose(layers.relative_density, [1.0, 0.5])


@pytest.mark.parametrize(
    ("keywords", "match"),
    [
        ({"n_layers": 0}, "n_layers must be within 1 .. 200"),
        ({"scale_height_m": -1.0}, "scale_height_m must be finite and > 0"),
        ({"scale_height_m": 1e4, "top_altitude_m": 10.0, "n_layers": 50}, "thinner than 1 m"),
    ],
)
def test_refusals(keywords: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        rt_layers(**keywords)


def test_profile_file_refusals(tmp_path: Path) -> None:
    bad = tmp_path / "bad.txt"
    bad.write_text("1 1\n2 0\n")
    with pytest.raises(ValueError, match="must start at exactly 0"):
        rt_layers(profile_file=bad)
    bad.write_text("0 1\nten 0\n")
    with pytest.raises(ValueError, match="line 2: expected two numbers"):
        rt_layers(profile_file=bad)
    good = tmp_path / "good.txt"
    good.write_text("0 1\n5 0\n")
    with pytest.raises(ValueError, match="scale_height_m cannot be honoured"):
        rt_layers(profile_file=good, scale_height_m=1e4)


def _export(tmp_path: Path, *extra: str, density: bool = False) -> tuple[int, Path]:
    src = tmp_path / "t.nc"
    if not src.exists():
        t = rt_table()
        if not density:
            t = t.replace(cross_sections={"number_density_per_m3": None})
        t.save(src)
    out = tmp_path / "out"
    code = main(["export", str(src), "--out", str(out), "--quiet", "--force", *extra])
    return code, out / "mars rt"


def test_cli_writes_the_profile_and_optical_depth_asked_for(tmp_path: Path) -> None:
    """The issue's command line: the files follow --scale-height-m and --top-altitude-m, and
    --optical-depth gives the column its optical depth at the reference wavelength in all
    three files."""
    formats = ["--format", "disort,libradtran,libradtran-nc"]
    tau = ["--optical-depth", "0.5", "--reference-wavelength-nm", "900"]
    profile = ["--scale-height-m", "11100", "--top-altitude-m", "50000", "--n-layers", "3"]
    code, out = _export(tmp_path, *formats, *tau, *profile)
    assert code == 0
    f = read_disort(out / "mars_rt_disort.txt")
    assert f.layer_top_km[-1] == 50.0 and f.layer_bottom_km.size == 3
    np.testing.assert_allclose(f.dtauc()[1].sum(), 0.5, rtol=1e-12)
    # libradtran: sum over layer files of ext [km-1] * thickness [km].
    explicit = [
        ln.split() for ln in (out / "mars_rt_aerosol_explicit.dat").read_text().splitlines()
    ]
    levels = [(float(z), name) for z, name in (r for r in explicit if r[0] != "#")]
    tau_900 = 0.0
    for (z_top, _), (z_bottom, name) in itertools.pairwise(levels):
        rows = np.loadtxt(out / name, ndmin=2)
        tau_900 += rows[1, 1] * (z_top - z_bottom)
    assert tau_900 == pytest.approx(0.5, rel=1e-12)
    # libradtran-nc: ext per particle per cm3 [km-1 cm3] * density [cm-3] * thickness [km].
    species = np.loadtxt(out / "mars_rt_aerosol_species.dat", ndmin=2)
    ext = rt_table().cross_sections.cext_um2[1] * 1e-3
    dz = species[:-1, 0] - species[1:, 0]
    assert np.sum(ext * species[1:, 1] * dz) == pytest.approx(0.5, rel=1e-12)
    assert species[0, 1] == 0.0 and species[0, 0] == 50.0


def test_cli_profile_changes_the_files(tmp_path: Path) -> None:
    """Before, --scale-height-m and --top-altitude-m were accepted and the files came out
    the same."""
    formats = ["--format", "disort,libradtran-nc", "--number-density-per-m3", str(N_M3)]
    assert _export(tmp_path / "a", *formats)[0] == 0
    profile = ["--scale-height-m", "11100", "--top-altitude-m", "50000"]
    assert _export(tmp_path / "b", *formats, *profile)[0] == 0
    for name in ("mars_rt_disort.txt", "mars_rt_aerosol_species.dat"):
        a = (tmp_path / "a" / "out" / "mars rt" / name).read_text()
        b = (tmp_path / "b" / "out" / "mars rt" / name).read_text()
        assert a != b and "exponential, scale height 11100.0 m, top 50000.0 m" in b


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            ["--format", "netcdf", "--scale-height-m", "11100"],
            r"--scale-height-m \(taken by cosmoscout, disort",
        ),
        (["--format", "disort", "--n-layers", "3"], "needs a number density"),
        (
            ["--format", "libradtran", "--optical-depth", "0.5", "--number-density-per-m3", "1e6"],
            "not both",
        ),
        (["--format", "netcdf", "--optical-depth", "0.5"], "--optical-depth changes nothing"),
        (
            ["--format", "disort", "--optical-depth", "0.5", "--n-layers", "0"],
            "must be >= 1|positive|n-layers",
        ),
    ],
)
def test_cli_refuses_what_it_cannot_honour(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    code, out = _export(tmp_path, *extra)
    assert code == 2
    assert re.search(message, capsys.readouterr().err)
    assert not out.exists()
