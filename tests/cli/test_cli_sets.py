"""``dustoptics build mars|earth|earth-kobe2026``: CosmoScout VR's whole atmosphere sets."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from _cli import config_fixture  # noqa: F401 (fixture config)

import dustoptics as do
from dustoptics.atmosphere.sets import COSMOSCOUT_WAVELENGTHS_NM
from dustoptics.cli import main
from dustoptics.io.csv.cosmoscout import check_cosmoscout_set, read_cosmoscout_constituent


def test_build_earth_on_any_grid(tmp_path):
    argv = ["build", "earth", "--wavelengths-nm", "400,500,600,700", "--out", str(tmp_path)]
    assert main([*argv, "--quiet"]) == 0
    mol = read_cosmoscout_constituent(tmp_path / "earth", "earth_molecules")
    np.testing.assert_allclose(mol.wavelength_m, [400e-9, 500e-9, 600e-9, 700e-9], rtol=1e-6)
    bad = ["build", "earth-kobe2026", "--wavelengths-nm", "400,500", "--out", str(tmp_path)]
    assert main(bad) == 2


def test_build_earth_kobe2026_keeps_his_three_wavelengths(tmp_path):
    assert main(["build", "earth-kobe2026", "--out", str(tmp_path), "--quiet"]) == 0
    mol = read_cosmoscout_constituent(tmp_path / "earth-kobe2026", "earth-kobe2026_molecules")
    np.testing.assert_allclose(mol.wavelength_m, [475e-9, 510e-9, 650e-9], rtol=1e-6)


def test_build_mars_and_earth_write_whole_cosmoscout_sets(config, tmp_path):
    args = ["--out", str(tmp_path), "--quiet", "--dust", str(config), "--optical-depth", "0.6"]
    assert main(["build", "mars", *args]) == 0
    assert main(["build", "earth", "--out", str(tmp_path), "--quiet"]) == 0
    assert check_cosmoscout_set(tmp_path / "mars") == ["mars_aerosols", "mars_molecules"]
    assert check_cosmoscout_set(tmp_path / "earth") == [
        "earth_aerosols",
        "earth_molecules",
        "earth_ozone",
    ]
    # The dust's column reproduces the optical depth at 550 nm: tau = N0 <C_ext> L
    # (exponential profile, 11.1 km, cut at the 120 km top), with <C_ext> computed here and N0
    # the number density at the ground.
    dust = read_cosmoscout_constituent(tmp_path / "mars", "mars_aerosols")
    cfg = do.load_config(config)
    from dataclasses import replace

    at550 = replace(cfg, optics=replace(cfg.optics, wavelengths_nm=(550.0,), n_theta=2))
    cext_m2 = do.build_table(at550).cross_sections.cext_um2[0] * 1e-12
    h, top = 11100.0, 120e3
    # The files give the coefficient where the relative density is 1: the first density
    # sample, at the centre of the first of N texels, (1/2) top / N above the ground.
    lowest_m = 0.5 * top / dust.density.size
    n0 = float(dust.beta_sca_per_m[0] / (read_hdf5_free_csca(cfg, 0))) * np.exp(lowest_m / h)
    length = h * (1 - np.exp(-top / h))
    np.testing.assert_allclose(n0 * cext_m2 * length, 0.6, rtol=1e-12)
    settings = json.loads((tmp_path / "mars" / "mars_settings.json").read_text())
    assert settings["minAltitude"] == 3390e3 and settings["maxAltitude"] == 3510e3
    # The preprocessor finds the files where they stand (not in the writer's staging folder).
    for role in ("molecules", "aerosols"):
        for name in settings[role].values():
            assert Path(name).parent == (tmp_path / "mars").resolve() and Path(name).is_file()
    # Again: the same files, up to date; another optical depth: they differ, --force needed.
    assert main(["build", "mars", *args]) == 0
    assert main(["build", "mars", *args[:-1], "0.7"]) == 1


@pytest.mark.parametrize("formats", ["glsl,texture", "hdf5", "cosmoscout,csv"])
def test_build_mars_refuses_other_formats(formats, tmp_path, capsys):
    """An atmosphere set is CosmoScout VR's format; --format asking for another is refused
    before any computation, naming the formats asked for."""
    argv = ["build", "mars", "--out", str(tmp_path), "--format", formats]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"--format {formats} is not available" in err
    assert not any(tmp_path.iterdir())


def read_hdf5_free_csca(cfg, i):
    """<C_sca> [m^2] of the configuration at CosmoScout's i-th wavelength, computed here."""
    from dataclasses import replace

    grid = replace(
        cfg, optics=replace(cfg.optics, wavelengths_nm=COSMOSCOUT_WAVELENGTHS_NM, n_theta=1801)
    )
    return do.build_table(grid).cross_sections.csca_um2[i] * 1e-12


def test_set_provenance_records_the_command_inputs(config, tmp_path):
    """build mars writes <name>_provenance.json: --optical-depth and --dust are recorded and the
    set's input hash changes with them."""
    base = ["--quiet", "--dust", str(config)]
    assert (
        main(["build", "mars", "--out", str(tmp_path / "a"), *base, "--optical-depth", "0.5"]) == 0
    )
    assert (
        main(["build", "mars", "--out", str(tmp_path / "b"), *base, "--optical-depth", "0.7"]) == 0
    )
    a = json.loads((tmp_path / "a" / "mars" / "mars_provenance.json").read_text())
    b = json.loads((tmp_path / "b" / "mars" / "mars_provenance.json").read_text())
    assert a["inputs"]["optical_depth"] == 0.5 and b["inputs"]["optical_depth"] == 0.7
    assert a["inputs"]["dust"] == str(config)
    assert a["input_hash"] != b["input_hash"]
    n_a = a["constituents"]["aerosols"]["number_density_per_m3"]
    n_b = b["constituents"]["aerosols"]["number_density_per_m3"]
    assert n_b / n_a == pytest.approx(0.7 / 0.5, rel=1e-12)  # N0 is proportional to tau
