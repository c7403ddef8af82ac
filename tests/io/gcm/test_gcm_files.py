"""The Mars GCM dust files: values read back, by our readers and by the models' own Fortran
read statements (compiled with gfortran; skipped without it, failed in CI), from presets,
TOML, the API and the command line."""

from __future__ import annotations

import dataclasses
import math
import shutil
import subprocess
from pathlib import Path

import miepython
import numpy as np
import pytest
from _render import missing
from scipy import integrate

from dustoptics._validation import BudgetError
from dustoptics.cli import main
from dustoptics.io import FORMATS
from dustoptics.io.gcm import ames, common, lmd
from dustoptics.models.compute import build_table
from dustoptics.models.config import parse_config
from dustoptics.models.presets import list_presets, load_preset
from dustoptics.particles.catalogue import get_material
from dustoptics.particles.sizedist import ModifiedGamma
from dustoptics.scattering.optics import compute_optics

HERE = Path(__file__).resolve().parent

#: Wolff et al.'s Mars dust index alone, a modified gamma distribution, one wavelength.
WOLFF = """\
name = "wolff-dust"
description = "Wolff et al. 2009 dust, for the GCM file tests"

[material]
model = "catalogue"
name = "marsdust-wolff2009"

[size_distribution]
model = "modified_gamma"
r_eff_um = 1.5
v_eff = 0.3

[optics]
weighting = "scattering"
rtol = 1e-3
wavelengths_nm = [670.0]
n_theta = 19

[phase]
model = "mie"
"""

#: A small LMD grid: three effective radii, five visible wavelengths (0.67 um inside). [um]
RADII_UM = (0.3, 1.5, 4.0)
VIS_UM = (0.4, 0.55, 0.67, 0.9, 1.5)


@pytest.fixture(name="table", scope="module")
def table_fixture():
    return build_table(parse_config(WOLFF, source="wolff.toml"))


def _fortran(tmp_path: Path, source: str) -> Path:
    if shutil.which("gfortran") is None:
        missing("gfortran not installed (Debian gfortran)")
    exe = tmp_path / Path(source).stem
    subprocess.run(["gfortran", "-O0", "-o", str(exe), str(HERE / source)], check=True)
    return exe


def _run(exe: Path, *args: Path) -> np.ndarray:
    out = subprocess.run([str(exe), *map(str, args)], check=True, capture_output=True, text=True)
    return np.array([float(v) for v in out.stdout.split()])


def test_lmd_values_round_trip_and_the_build_s_own_radius_is_the_table(table, tmp_path):
    text, _, optics = lmd.lmd_text(
        table, domain="vis", gcm_radii_um=RADII_UM, gcm_wavelengths_um=VIS_UM
    )
    (path,) = FORMATS["lmd-dustvis"].write(
        table, tmp_path, gcm_radii_um=RADII_UM, gcm_wavelengths_um=VIS_UM
    )
    assert path.name == "wolff-dust_optprop_dustvis_n3.dat"
    assert path.read_text() == text
    f = lmd.read_lmd(path)
    np.testing.assert_allclose(f.wavelength_m, np.array(VIS_UM) * 1e-6, rtol=5e-7)
    np.testing.assert_allclose(f.radius_m, np.array(RADII_UM) * 1e-6, rtol=5e-7)
    for got, want in ((f.qext, optics.qext), (f.ssa, optics.ssa), (f.g, optics.g)):
        np.testing.assert_allclose(got, want, rtol=5e-7)  # 7 significant digits
    # The build is r_eff 1.5 um at 670 nm: the file's row for 1.5 um is the build's table,
    # to the tolerance both were computed to (cross-sections 1e-5 relative).
    assert f.qext[1, 2] == pytest.approx(table.qext[0], rel=3e-5)
    assert f.ssa[1, 2] == pytest.approx(table.ssa[0], rel=3e-5)
    assert f.g[1, 2] == pytest.approx(table.g[0], abs=3e-5)
    # Another radius: the same family at r_eff 4 um, v_eff 0.3 (the build's shape).
    other = compute_optics(
        get_material("marsdust-wolff2009"),
        ModifiedGamma(r_eff_um=4.0, v_eff=0.3),
        [670.0],
        np.linspace(0, 180, 19),
        cross_section_rtol=1e-6,
    )
    assert f.qext[2, 2] == pytest.approx(other.qext[0], rel=3e-5)
    assert "input hash " + table.provenance.input_hash in f.header[1]


def test_lmd_file_read_by_the_pcm_read_loop(table, tmp_path):
    exe = _fortran(tmp_path, "lmd_read.f90")
    ir_um = (6.0, 9.3, 15.0, 30.0)
    for fmt, kw in (
        ("lmd-dustvis", {"gcm_wavelengths_um": VIS_UM}),
        ("lmd-dustir", {"gcm_wavelengths_um": ir_um}),
    ):
        (path,) = FORMATS[fmt].write(table, tmp_path, gcm_radii_um=RADII_UM, **kw)
        values = _run(exe, path)
        f = lmd.read_lmd(path)
        nwvl, nsize = int(values[0]), int(values[1])
        assert (nwvl, nsize) == (f.wavelength_m.size, 3)
        want = np.concatenate(
            [f.wavelength_m, f.radius_m, f.qext.ravel(), f.ssa.ravel(), f.g.ravel()]
        )
        # The PCM reads default REALs (float32): equal to float32 rounding.
        np.testing.assert_allclose(values[2:], want.astype(np.float32), rtol=0, atol=0)


def test_ames_band_mean_against_miepython_and_quad(table):
    # Spheres of 0.3 um in band 5 (7651.11-12500 cm^-1): Planck 6000 K weighted Q_ext by
    # adaptive quadrature of miepython's efficiencies, against 16 Gauss-Legendre nodes.
    grid = ames.ames_grid(table, bands="vis", gcm_radii_um=(0.3,))
    m = get_material("marsdust-wolff2009")

    def mie(nu: float) -> tuple[float, float, float]:
        wl_um = 1e4 / nu
        index = complex(m(np.array([wl_um * 1e3]))[0])
        qext, qsca, _, g = miepython.efficiencies(index.real - 1j * index.imag, 0.6, wl_um)
        return float(qext), float(qsca), float(g)

    def planck(nu: float) -> float:
        return nu**3 / math.expm1(1.438776877 * nu / 6000.0)

    lo, hi = 7651.11, 12500.0
    norm = integrate.quad(planck, lo, hi, epsrel=1e-10)[0]
    qext = integrate.quad(lambda nu: mie(nu)[0] * planck(nu), lo, hi, epsrel=1e-8)[0] / norm
    qsca = integrate.quad(lambda nu: mie(nu)[1] * planck(nu), lo, hi, epsrel=1e-8)[0] / norm
    gq = integrate.quad(lambda nu: mie(nu)[1] * mie(nu)[2] * planck(nu), lo, hi, epsrel=1e-8)[0]
    assert grid["qext"][0, 4] == pytest.approx(qext, rel=2e-5)
    assert grid["qsca"][0, 4] == pytest.approx(qsca, rel=2e-5)
    assert grid["g"][0, 4] == pytest.approx(gq / norm / qsca, abs=2e-5)
    # Wolff's index starts at 263 nm: band 7 (240-400 nm) is averaged over 263-400 nm and
    # says how much of its 6000 K Planck energy that holds.
    assert grid["bands"].upper_cm[6] == pytest.approx(1e7 / 263.0)
    assert 0.9 < grid["bands"].covered[6] < 1.0
    assert np.all(grid["bands"].covered[:6] == 1.0)


def test_ames_files_read_by_the_model_read_statements(table, tmp_path):
    exe = _fortran(tmp_path, "ames_read.f90")
    grids, paths = {}, {}
    for bands in ("vis", "ir"):
        grids[bands] = ames.ames_grid(table, bands=bands, gcm_nodes_per_band=4)
        paths[bands] = FORMATS[f"ames-dust{bands}"].write(table, tmp_path, gcm_nodes_per_band=4)
    assert [p.name for p in paths["vis"]] == [
        "wolff-dust_Dust_vis_15bands.dat",
        "wolff-dust_Dust_vis_15bands.json",
    ]
    values = _run(exe, paths["vis"][0], paths["ir"][0])
    vis = values[: 20 * 21].reshape(20, 3, 7)
    ir = values[20 * 21 :].reshape(20, 3, 8)
    for bands, got in (("vis", vis), ("ir", ir)):
        grid = grids[bands]
        back = ames.read_ames(paths[bands][0], n_bands=got.shape[2])
        for k, name in enumerate(("qext", "qsca", "g")):
            # e10.3: four significant digits, read as real*4.
            np.testing.assert_allclose(got[:, k], grid[name], rtol=5.1e-4)
            np.testing.assert_allclose(got[:, k], getattr(back, name).astype(np.float32), rtol=0)


def test_every_dust_preset_builds_gcm_files(tmp_path):
    built = []
    for name in list_presets():
        config = load_preset(name)
        if config.material is None:
            continue
        small = dataclasses.replace(
            config,
            optics=dataclasses.replace(config.optics, wavelengths_nm=(670.0,), n_theta=19),
        )
        table = build_table(small)
        (path,) = FORMATS["lmd-dustvis"].write(
            table, tmp_path / name, gcm_radii_um=(0.5, 2.0), gcm_wavelengths_um=(0.5, 0.67, 0.8)
        )
        f = lmd.read_lmd(path)
        assert np.all(f.qext > 0) and np.all((f.ssa > 0) & (f.ssa <= 1))
        built.append(name)
    assert "cosmoscout-mars" in built and "blue-moons" in built  # multimodal and single


def test_scaling_keeps_the_build_s_shape():
    # A two-mode distribution scaled to r_eff 3 um keeps its effective variance (an identity
    # of scaling every radius by one factor).
    record = {
        "model": "multimodal",
        "modes": [
            {
                "model": "modified_log_normal",
                "r_eff_um": 0.04,
                "v_eff": 0.1,
                "relative_number_density": 1000.0,
            },
            {
                "model": "modified_gamma",
                "r_eff_um": 1.6,
                "v_eff": 0.2,
                "relative_number_density": 1.0,
            },
        ],
    }
    own = common.distribution_at(record, r_eff_um=1.0, v_eff=None)
    scaled = common.distribution_at(record, r_eff_um=3.0, v_eff=None)
    assert scaled.r_eff_um == pytest.approx(3.0, rel=1e-12)
    assert scaled.v_eff == pytest.approx(own.v_eff, rel=1e-10)
    fixed = common.distribution_at(record, r_eff_um=3.0, v_eff=0.25)
    assert isinstance(fixed, ModifiedGamma) and fixed.v_eff == 0.25


def test_the_default_lmd_grid_leaves_out_radii_a_fine_mode_cannot_reach():
    # cosmoscout-mars' fine mode (r_eff 0.04 um) scaled to the PCM's smallest radii would be
    # below 1 nm: the default grid keeps its tail, from the first radius that can be made.
    record = load_preset("cosmoscout-mars").size_distribution.to_inputs()
    default = np.asarray(lmd.DEFAULT_RADII_UM)
    kept = common.scalable_radii(record, default, v_eff=None)
    assert 0 < kept.size < default.size
    np.testing.assert_array_equal(kept, default[default.size - kept.size :])
    with pytest.raises(ValueError, match="below 0.001 um"):
        common.distribution_at(record, r_eff_um=float(default[-kept.size - 1]), v_eff=None)
    # With a v_eff the family needs no scaling: every radius of the grid.
    assert common.scalable_radii(record, default, v_eff=0.3).size == default.size


def test_a_grid_over_the_work_budget_is_refused_before_any_work(tmp_path):
    # cosmoscout-mars' shape (v_eff 2.1) scaled to the PCM's largest radii reaches size
    # parameters near 2e4: its default LMD grid is refused at once, naming the options.
    config = load_preset("cosmoscout-mars")
    small = dataclasses.replace(
        config, optics=dataclasses.replace(config.optics, wavelengths_nm=(670.0,), n_theta=19)
    )
    table = build_table(small)
    with pytest.raises(BudgetError, match="times the work budget.*--gcm-radii-um"):
        FORMATS["lmd-dustvis"].write(table, tmp_path)
    with pytest.raises(ValueError, match="scaled to r_eff 0.01 um cannot be made"):
        FORMATS["lmd-dustvis"].write(table, tmp_path, gcm_radii_um=(0.01, 1.0))
    assert not list(tmp_path.iterdir())


def test_refusals_name_what_is_wrong(table, tmp_path):
    analytic = build_table(load_preset("costa"))
    with pytest.raises(ValueError, match="records no material and size distribution"):
        FORMATS["lmd-dustvis"].write(analytic, tmp_path)
    # compute_optics' own table records its index at its wavelengths only: refused unless
    # it is one constant.
    varying = compute_optics(
        get_material("marsdust-wolff2009"), ModifiedGamma(r_eff_um=1.0, v_eff=0.2), [550.0, 670.0]
    )
    with pytest.raises(ValueError, match="give the index at other wavelengths"):
        FORMATS["ames-dustir"].write(varying, tmp_path)
    with pytest.raises(ValueError, match="gcm_radii_um must be strictly increasing"):
        FORMATS["ames-dustvis"].write(table, tmp_path, gcm_radii_um=(2.0, 1.0))
    with pytest.raises(ValueError, match="bracket the PCM's infrared reference wavelength 9.3"):
        FORMATS["lmd-dustir"].write(table, tmp_path, gcm_wavelengths_um=(10.0, 20.0))
    with pytest.raises(ValueError, match="at most 60"):
        FORMATS["lmd-dustvis"].write(table, tmp_path, gcm_radii_um=tuple(np.geomspace(1, 9, 61)))
    assert not list(tmp_path.iterdir())


def test_command_line_build_options_and_info(tmp_path, capsys):
    config = tmp_path / "wolff.toml"
    config.write_text(WOLFF, encoding="utf-8")
    out = tmp_path / "tables"
    args = ["build", str(config), "--out", str(out), "--quiet"]
    args += ["--format", "lmd-dustvis,ames-dustvis", "--gcm-radii-um", "0.5,2"]
    args += ["--gcm-wavelengths-um", "0.5,0.67,1", "--gcm-v-eff", "0.2"]
    args += ["--gcm-nodes-per-band", "3"]
    # The Ames file with 2 radii: our readers read it; the model reads 20 (info says so).
    assert main(args) == 0
    folder = out / "wolff-dust"
    f = lmd.read_lmd(folder / "wolff-dust_optprop_dustvis_n2.dat")
    assert f.radius_m.tolist() == [5e-7, 2e-6]
    assert "v_eff = 0.2" in f.header[3]
    capsys.readouterr()
    assert main(["info", str(folder / "wolff-dust_optprop_dustvis_n2.dat")]) == 0
    text = capsys.readouterr().out
    assert text.startswith("LMD Mars PCM dust file (visible)") and "radii:           2" in text
    assert main(["info", str(folder / "wolff-dust_Dust_vis_15bands.dat")]) == 0
    text = capsys.readouterr().out
    assert text.startswith("NASA Ames Mars GCM dust file (visible)")
    assert "(the model reads 20, nbin_rt)" in text and "table wolff-dust" in text
