"""``dustoptics info``: what every file and folder dustoptics writes holds."""

from __future__ import annotations

import json

import numpy as np
from _cli import config_fixture, run_build  # noqa: F401 (fixture config)

from dustoptics.cli import main
from dustoptics.io import read_hdf5


def test_info_describes_provenance(config, tmp_path, capsys):
    assert run_build(config, tmp_path, "--format", "hdf5,csv") == 0
    capsys.readouterr()
    table = read_hdf5(tmp_path / "small-dust" / "small-dust.h5")
    for target in ("small-dust/small-dust.h5", "small-dust", "small-dust/table_summary.json"):
        assert main(["info", str(tmp_path / target)]) == 0
        out = capsys.readouterr().out
        assert "name:            small-dust" in out
        assert table.provenance.input_hash in out
        assert "wavelengths:     3, 440 .. 680 nm" in out
        assert "modified_gamma" in out


def test_info_reads_every_format_and_a_build_folder(config, tmp_path, capsys):
    args = ["--format", "hdf5,csv,glsl,texture,cosmoscout", "--number-density-per-m3", "1e8"]
    assert run_build(config, tmp_path, *args) == 0
    folder = tmp_path / "small-dust"
    table = read_hdf5(folder / "small-dust.h5")
    digest = table.provenance.input_hash
    capsys.readouterr()
    expected = {
        "small-dust_phase.glsl": ["GLSL snippet:    small-dust_phase.glsl", digest, "MIE_PHASE"],
        "small-dust_phase_theta.json": ["shape:           3 wavelengths x 721 angles", digest],
        "small-dust_phase_theta.raw": ["texture:         small-dust_phase_theta.raw", digest],
        "small-dust_phase.csv": ["constituent:     small-dust", "phase function:  181 angles"],
        "small-dust_density.csv": ["density:         1024 altitudes"],
        "MiePhaseFunctionSpectrum.csv": ["name:            small-dust", digest],
    }
    for name, needles in expected.items():
        assert main(["info", str(folder / name)]) == 0, name
        out = capsys.readouterr().out
        for needle in needles:
            assert needle in out, (name, needle)
    # The folder: one section per output found.
    assert main(["info", str(folder)]) == 0
    out = capsys.readouterr().out
    for title in (
        "== small-dust (CosmoScout VR) ==",
        "== small-dust.h5 ==",
        "== table_summary.json (seed CSV) ==",
        "== small-dust_phase.glsl ==",
        "== small-dust_phase_theta.json ==",
    ):
        assert title in out
    # beta_sca = N0 <C_sca> at the first texel centre's density (the largest written sample,
    # 1): the default exponential, scale height 10 km, sampled at (i + 1/2) 120 km / 1024.
    c_sca_m2 = table.cross_sections.csca_um2 * 1e-12 * np.exp(-0.5 * 120e3 / 1024 / 10e3)
    assert f"beta_sca:        {1e8 * c_sca_m2.min():.6g} .. {1e8 * c_sca_m2.max():.6g} m^-1" in out


def test_info_reads_an_atmosphere_set(config, tmp_path, capsys):
    argv = ["build", "mars", "--out", str(tmp_path), "--quiet", "--dust", str(config)]
    assert main(argv) == 0
    record = json.loads((tmp_path / "mars" / "mars_provenance.json").read_text())
    for target in ("mars", "mars/mars_settings.json", "mars/mars_provenance.json"):
        assert main(["info", str(tmp_path / target)]) == 0
        out = capsys.readouterr().out
        assert "atmosphere set:  mars" in out
        assert f"input hash:      {record['input_hash']}" in out
        assert "constituent:     mars_aerosols" in out and "constituent:     mars_molecules" in out
        assert "optical_depth=0.5" in out  # the summary: what the set was made from
        assert main(["info", "--full", str(tmp_path / target)]) == 0
        assert '"optical_depth": 0.5' in capsys.readouterr().out  # every input, as JSON


def test_info_refuses_what_dustoptics_does_not_write(tmp_path, capsys):
    other = tmp_path / "notes.txt"
    other.write_text("hello\n")
    assert main(["info", str(other)]) == 1
    assert "not a file dustoptics writes" in capsys.readouterr().err
    assert main(["info", str(tmp_path)]) == 1
    assert "holds no file dustoptics writes" in capsys.readouterr().err


def test_info_shows_a_summary_and_everything_with_full(config, tmp_path, capsys):
    """A summary by default (what the table holds, what made it, its accuracy and hash);
    --full adds the software, the citations, the notes and every input."""
    assert run_build(config, tmp_path, "--format", "netcdf") == 0
    path = tmp_path / "small-dust" / "small-dust.nc"
    table = read_hdf5(path)
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    summary = capsys.readouterr().out
    lines = summary.splitlines()
    assert len(lines) <= 16
    assert "sizes:           modified_gamma(r_eff_um=1, v_eff=0.2)" in lines
    assert "phase model:     mie, scattering-weighted" in lines
    assert f"input hash:      {table.provenance.input_hash}" in lines
    assert lines[-1].startswith("more:            software") and "info --full" in lines[-1]
    assert "inputs:" not in lines and "software:" not in summary
    assert main(["info", "--full", str(path)]) == 0
    full = capsys.readouterr().out
    assert "inputs:" in full.splitlines() and "software:        dustoptics " in full
    assert len(full.splitlines()) > len(lines)


def test_info_names_the_expansion_coefficients_and_the_matrix(tmp_path, capsys):
    import dustoptics as do
    from dustoptics.io import write_hdf5

    table = do.compute_optics(
        1.5,
        do.Monodisperse(radius_um=0.5),
        [550.0, 650.0],
        [0.0, 90.0, 180.0],
        polarization=True,
        expansion=True,
    )
    path = tmp_path / "table.nc"
    write_hdf5(table, path)
    order = table.expansion.n_order - 1
    for extra in ([], ["--full"]):
        assert main(["info", str(path), *extra]) == 0
        out = capsys.readouterr().out
        assert f"expansion:       alpha1-4, beta1-2, orders l = 0 .. {order}, error <= " in out
        assert "matrix:          F12, F33, F34 beside F11, error <= " in out


def test_info_names_no_expansion_when_the_table_has_none(config, tmp_path, capsys):
    assert run_build(config, tmp_path, "--format", "netcdf") == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "small-dust" / "small-dust.nc")]) == 0
    out = capsys.readouterr().out
    assert "expansion:" not in out and "matrix:" not in out


def test_info_max_bytes_bounds_what_it_reads(tmp_path, capsys):
    """A sky's netCDF of 2 x 1,000 float64 values is described within --max-bytes of its
    size and refused, in one line naming the file and its size, below it."""
    from scipy.io import netcdf_file

    path = tmp_path / "small_sky.nc"
    with netcdf_file(path, "w", version=2) as f:
        f.title = "a small sky"
        f.createDimension("wavelength_nm", 1000)
        f.createVariable("wavelength_nm", "f8", ("wavelength_nm",))[:] = np.linspace(400, 700, 1000)
        f.createVariable("radiance", "f8", ("wavelength_nm",))[:] = 1.0
    assert main(["info", "--max-bytes", str(path.stat().st_size), str(path)]) == 0
    assert "radiance" in capsys.readouterr().out
    assert main(["info", "--max-bytes", "7999", str(path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    size = path.stat().st_size
    assert len(err) == 1 and "small_sky.nc" in err[0], err
    assert f"{size} bytes, larger than the 7999-byte limit" in err[0], err
    assert main(["info", "--max-bytes", "0", str(path)]) == 2
