"""``info`` on everything dustoptics writes: every format of ``build``/``export``, a fit, a sky
and a sweep, each read back by :func:`dustoptics.io.describe.describe_path` (issue 26)."""

from __future__ import annotations

import io
import shutil
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

import dustoptics as do
from dustoptics.cli import main
from dustoptics.io import FORMATS, FormatError, FormatOptions
from dustoptics.io.describe import describe_path
from dustoptics.io.describe_formats import describer_of
from dustoptics.io.outputs import prepare_export, write_formats
from dustoptics.sky.engines import ENGINES

#: What every file's description starts with, by the file's ending.
FIRST_WORDS = {
    ".nc": "name:",
    ".h5": "name:",
    ".csv": ("name:", "constituent:"),
    "table_summary.json": "name:",
    "_settings.json": "atmosphere set:",
    ".glsl": "GLSL snippet:",
    ".hlsl": "HLSL snippet:",
    ".wgsl": "WGSL snippet:",
    "_disort.txt": "DISORT phase-function moments:",
    "_aerosol_species.dat": "libRadtran aerosol species profile:",
    "_n50.dat": "LMD Mars PCM dust file",
    "_15bands.dat": "NASA Ames Mars GCM dust file",
    "_15bands.json": "NASA Ames Mars GCM dust file",
    ".dat": "libRadtran aerosol optical properties:",
    ".mie.cdf": "libRadtran polarized optical properties:",
    "_bruneton_mie.json": "Bruneton (2017):",
    ".exr": "texture:",
    ".ktx2": "texture:",
    ".npy": "texture:",
    ".raw": "texture:",
    "_float32.json": "texture:",
    "_theta.json": "texture:",
}


@pytest.fixture(scope="module")
def table() -> do.Table:
    return do.compute_optics(
        1.5 + 0.01j,
        do.Monodisperse(radius_um=0.3),
        [440.0, 550.0, 680.0],
        np.linspace(0.0, 180.0, 181),
        name="small",
        expansion=True,
    ).replace(cross_sections={"number_density_per_m3": 1e8})


@pytest.fixture(scope="module")
def every_format(table: do.Table, tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("OpenEXR")
    out = tmp_path_factory.mktemp("every-format")
    # The engines' formats write a planet set, not a table (tests/sky/engines describe them).
    formats = sorted(n for n in FORMATS if n not in ENGINES)
    dense, options = prepare_export(table, formats, options=FormatOptions(), n_altitudes=16)
    write_formats(dense, out, formats, options=options)
    return out


def _first_words(name: str) -> str | tuple[str, ...]:
    for ending, first in FIRST_WORDS.items():
        if name.endswith(ending):
            return first
    raise AssertionError(f"{name}: a file no test expects (add it to FIRST_WORDS)")


def test_every_file_of_every_format_is_described(every_format: Path, table: do.Table) -> None:
    files = sorted(every_format.iterdir())
    # Every format wrote something, and each file is read by a describer.
    assert len(files) >= len(FORMATS)
    for path in files:
        text = describe_path(path, full=False)
        assert text.startswith(_first_words(path.name)), (path.name, text[:80])
        if path.suffix in (".nc", ".h5", ".glsl", ".hlsl", ".wgsl", ".txt", ".exr", ".ktx2"):
            assert table.provenance.input_hash in describe_path(path), path.name
    # The folder: one section per output, none left out.
    folder = describe_path(every_format)
    for path in files:
        if path.suffix in (".raw", ".npy") or path.name.endswith(
            ("Spectrum.csv", "_phase.csv", "_scattering.csv", "_absorption.csv", "_density.csv")
        ):
            continue  # described with their sidecar, the seed CSV set or the constituent
        assert f"== {path.name}" in folder, path.name


def test_shader_descriptions_give_the_sampling_rule(every_format: Path) -> None:
    for suffix in (".glsl", ".hlsl", ".wgsl"):
        text = describe_path(every_format / f"small_phase{suffix}")
        assert "resolution: 0.25 deg, 721 samples" in text
        assert "MIE_PHASE_N" in text


def test_texture_containers_carry_their_metadata(every_format: Path) -> None:
    for suffix in (".exr", ".ktx2"):
        (path,) = every_format.glob(f"*{suffix}")
        text = describe_path(path)
        assert "sampling:        column j (0..720) at theta_j = 180 j / 720 deg" in text
        assert "sphere integral of the samples:" in text


def test_rt_files_state_their_rows(every_format: Path) -> None:
    text = describe_path(every_format / "small_disort.txt")
    assert "wavelengths:     3, 440 .. 680 nm" in text
    layers = describe_path(every_format / "small_aerosol_explicit.dat")
    assert "layers:          1, altitudes 0 .. 1 km: small_aerosol_layer.dat" in layers


def test_a_fit_its_shaders_and_a_sky_through_the_command_line(
    every_format: Path, tmp_path: Path
) -> None:
    pytest.importorskip("matplotlib")
    assert (
        main(["fit", str(every_format / "small.nc"), "--model", "hg", "--out", str(tmp_path)]) == 0
    )
    fit = tmp_path / "small"
    for path in sorted(fit.iterdir()):
        buffer = io.StringIO()
        with redirect_stdout(buffer):
            assert main(["info", str(path)]) == 0
        assert "henyey-greenstein" in buffer.getvalue(), path.name
    text = describe_path(fit / "small_henyey-greenstein.json")
    assert text.startswith("phase-function fit:")
    assert "440 nm: g " in text
    sky_out = tmp_path / "skies"
    args = ["sky", "mars", "--size", "32", "--out", str(sky_out), "--quiet"]
    assert main(args) == 0
    (sky_dir,) = sky_out.iterdir()
    nc = next(sky_dir.glob("*_sky.nc"))
    text = describe_path(nc, full=False)
    assert text.startswith("sky:") and "radiance_relative_error_max:" in text
    for png in sky_dir.glob("*.png"):
        assert f"the sky in {nc.name}" in describe_path(png)
    assert f"== {nc.name} ==" in describe_path(sky_dir)


def test_a_sweep_store_and_file(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    pytest.importorskip("zarr")
    from sweep._sweeps import small_toml  # tests/sweep: the small sweeps of the sweep tests

    from dustoptics.sweep import sweep

    config = tmp_path / "small.toml"
    config.write_text(small_toml(wavelengths_nm=[550.0, 650.0]), encoding="utf-8")
    over = {"size_distribution.r_eff_um": [1.0, 1.5]}
    store = tmp_path / "small.zarr"
    sweep(config, over, out=store, workers=1, progress=None)
    text = describe_path(store)
    assert text.startswith("sweep:")
    assert "size_distribution.r_eff_um: 2: 1, 1.5" in text
    assert "(complete: every chunk checked against its digests)" in text  # sweep imported
    # A chunk marker gone: the store says it is incomplete.
    marker = next((store / "sweep-done").iterdir())
    shutil.rmtree(marker) if marker.is_dir() else marker.unlink()
    assert "incomplete" in describe_path(store)


def test_what_is_not_ours_is_refused(tmp_path: Path) -> None:
    (tmp_path / "a.wgsl").write_text("// someone else's\nfn f() {}\n")
    with pytest.raises(FormatError, match="not a WGSL snippet written by dustoptics"):
        describe_path(tmp_path / "a.wgsl")
    (tmp_path / "b.ktx2").write_bytes(b"not a ktx2 file at all" * 4)
    with pytest.raises(FormatError, match="not a KTX2 file"):
        describe_path(tmp_path / "b.ktx2")
    (tmp_path / "c.png").write_bytes(b"GIF89a")
    with pytest.raises(FormatError, match="not a PNG image"):
        describe_path(tmp_path / "c.png")
    (tmp_path / "d.txt").write_text("# dustoptics DISORT moments file, format version 1\nx y\n")
    with pytest.raises(FormatError, match="does not start with a number"):
        describe_path(tmp_path / "d.txt")
    assert describer_of(tmp_path / "notes.md") is None
