"""uvspec (libRadtran) runs the ``libradtran`` and ``libradtran-nc`` files with the input lines
their headers give, on the profile asked for on the command line.

Runs where the environment variable ``LIBRADTRAN_DIR`` names a libRadtran build (its
``bin/uvspec`` and ``data/``); skipped otherwise (CI has none).  The column: the test's Mars
dust, exponential with an 11.1 km scale height up to 50 km in three layers of equal column,
at optical depth 0.5 at 500 nm (``--optical-depth``).  Molecules neither scatter nor absorb,
so uvspec's direct transmittance at altitude z is exp(-tau(z) / mu0) mu0 with the exponential
profile's tau(z) = 0.5 (exp(-z/H) - exp(-top/H)) / (1 - exp(-top/H)) (Beer-Lambert; the
layers hold the exact column, so at their boundaries the closed form is exact).
"""

from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _rt_table import rt_table

from dustoptics.cli import main

LIBRADTRAN_DIR = os.environ.get("LIBRADTRAN_DIR")
UVSPEC = Path(LIBRADTRAN_DIR or "/nonexistent") / "bin" / "uvspec"

pytestmark = pytest.mark.skipif(
    not UVSPEC.is_file(),
    reason="LIBRADTRAN_DIR does not name a libRadtran build with bin/uvspec",
)

TAU, REF_NM, H_M, TOP_M, SZA_DEG = 0.5, 500.0, 11_100.0, 50_000.0, 30.0


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("uvspec")
    src = tmp / "t.nc"
    rt_table().replace(cross_sections={"number_density_per_m3": None}).save(src)
    argv = ["export", str(src), "--out", str(tmp), "--format", "libradtran,libradtran-nc"]
    argv += ["--optical-depth", str(TAU), "--reference-wavelength-nm", str(REF_NM)]
    argv += ["--scale-height-m", str(H_M), "--top-altitude-m", str(TOP_M), "--n-layers", "3"]
    assert main([*argv, "--quiet"]) == 0
    return tmp / "mars rt"


def _recipe(path: Path) -> list[str]:
    """The uvspec input lines a header gives (the indented lines after 'uvspec input')."""
    lines = path.read_text().splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("# uvspec input"))
    out = []
    for ln in lines[start + 1 :]:
        if not ln.startswith("#   "):
            break
        out.append(ln[4:].strip())
    return out


def _uvspec(directory: Path, recipe: list[str], zout_km: list[float]) -> tuple[str, str, int]:
    data = Path(str(LIBRADTRAN_DIR)) / "data"
    lines = [
        f"data_files_path {data}/",
        f"atmosphere_file {data}/atmmod/afglus.dat",
        "source solar",
        "output_quantity transmittance",
        "mol_abs_param crs",
        f"wavelength {REF_NM:g} {REF_NM:g}",
        f"sza {SZA_DEG:g}",
        "no_absorption mol",
        "no_scattering mol",
        *recipe,
        "zout " + " ".join(f"{z:g}" for z in zout_km),
        "output_user lambda zout edir edn",
    ]
    run = subprocess.run(
        [str(UVSPEC)],
        input="\n".join(lines) + "\n",
        cwd=directory,
        capture_output=True,
        text=True,
        timeout=120,
    )
    return run.stdout, run.stderr, run.returncode


def _layer_altitudes(explicit: Path) -> list[float]:
    rows = [ln.split() for ln in explicit.read_text().splitlines() if ln and ln[0] != "#"]
    return sorted(float(r[0]) for r in rows)


def _expected_edir(z_km: np.ndarray) -> np.ndarray:
    h, top = H_M / 1000.0, TOP_M / 1000.0
    tau = TAU * (np.exp(-z_km / h) - math.exp(-top / h)) / -math.expm1(-top / h)
    mu0 = math.cos(math.radians(SZA_DEG))
    return mu0 * np.exp(-tau / mu0)


def test_recipes_run_on_the_profile_asked_for(files: Path) -> None:
    explicit = files / "mars_rt_aerosol_explicit.dat"
    species = files / "mars_rt_aerosol_species.dat"
    z = _layer_altitudes(explicit)
    assert len(z) == 4 and z[0] == 0.0 and z[-1] == 50.0
    results = {}
    for name, path in (("explicit", explicit), ("species", species)):
        out, err, code = _uvspec(files, _recipe(path), z)
        assert code == 0, err
        rows = np.loadtxt(out.splitlines(), ndmin=2)
        np.testing.assert_allclose(rows[:, 1], z)
        # uvspec prints 7 significant digits.
        np.testing.assert_allclose(rows[:, 2], _expected_edir(np.array(z)), rtol=2e-6)
        results[name] = rows
    # Both files' moments give the same diffuse irradiance (the same phase function).
    np.testing.assert_allclose(
        results["explicit"][:, 3], results["species"][:, 3], rtol=1e-4, atol=1e-8
    )


def test_the_explicit_recipe_needs_its_intcor_line(files: Path) -> None:
    explicit = files / "mars_rt_aerosol_explicit.dat"
    recipe = _recipe(explicit)
    assert "disort_intcor moments" in recipe
    _, err, _ = _uvspec(files, [r for r in recipe if not r.startswith("disort_intcor")], [0.0])
    assert "disort_intcor moments" in err


def test_uvspec_stops_outside_the_files_wavelengths(files: Path) -> None:
    header = (files / "mars_rt_aerosol_explicit.dat").read_text()
    assert "# wavelength coverage: 500.0 .. 900.0 nm" in header
    data = Path(str(LIBRADTRAN_DIR)) / "data"
    recipe = _recipe(files / "mars_rt_aerosol_explicit.dat")
    lines = [
        f"data_files_path {data}/",
        "source solar",
        "output_quantity transmittance",
        "mol_abs_param crs",
        "wavelength 450 550",
        *recipe,
    ]
    run = subprocess.run(
        [str(UVSPEC)], input="\n".join(lines) + "\n", cwd=files, capture_output=True, text=True
    )
    assert "Error" in run.stderr and "450" in run.stderr
