"""dustoptics.models.build: a configuration's table with progress, and the formats' options."""

from __future__ import annotations

import io
import os

import numpy as np
import pytest
from _model_configs import SMALL

from dustoptics.models import presets
from dustoptics.models.build import (
    FormatOptions,
    TableBuilder,
    is_config_path,
    prepare_export,
)
from dustoptics.models.compute import build_table
from dustoptics.models.files import load_config


@pytest.fixture
def small_file(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def small_table(tmp_path_factory):
    path = tmp_path_factory.mktemp("small") / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return build_table(load_config(path))


def test_is_config_path(small_file, tmp_path, monkeypatch):
    assert not is_config_path("hybrid")
    assert is_config_path("mine.toml")
    assert is_config_path(f"configs{os.sep}mine")
    assert is_config_path(str(small_file))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plain").write_text(SMALL, encoding="utf-8")
    assert is_config_path("plain")  # an existing file, whatever its name


def test_from_name_reads_a_preset_or_a_file(small_file):
    assert TableBuilder.from_name("costa").config == presets.load_preset("costa")
    builder = TableBuilder.from_name(str(small_file), allow_large=True)
    assert builder.config == load_config(small_file)
    assert builder.name == "small" and builder.allow_large and builder.progress is None


def test_from_name_refuses_an_unknown_preset_listing_the_valid_ones():
    with pytest.raises(ValueError, match="nope") as caught:
        TableBuilder.from_name("nope")
    for name in presets.list_presets():
        assert name in str(caught.value)


def test_build_is_build_table_and_reports_progress(small_file, monkeypatch):
    from dustoptics import _numba_cache

    monkeypatch.setattr(_numba_cache, "compile_kernels", lambda *args, **kwargs: None)  # cached
    progress = io.StringIO()  # not a terminal: the first and last lines only
    table = TableBuilder(load_config(small_file), progress=progress).build()
    assert table.equals(build_table(load_config(small_file)))
    lines = progress.getvalue().splitlines()
    assert [line.split(",")[0] for line in lines] == [
        "small: 0/10 wavelengths",
        "small: 10/10 wavelengths",
    ]


def test_format_options_for_each_writer():
    options = FormatOptions(channels_nm=(600.0, 500.0, 450.0), n_angles=181, prefix="DUST")
    assert options.for_format("glsl") == {
        "channels_nm": (600.0, 500.0, 450.0),
        "colour": None,
        "prefix": "DUST",
        "function_name": "DUST_MiePhaseFunction",
    }
    assert options.for_format("texture") == {"n_angles": 181}
    assert options.for_format("hdf5") == {}
    # What changes the numbers is recorded (tuples as lists); the prefix is in the names only.
    assert options.recorded("glsl") == {
        "channels_nm": [600.0, 500.0, 450.0],
        "prefix": "DUST",
        "function_name": "DUST_MiePhaseFunction",
    }
    assert FormatOptions().recorded("glsl") == {}


def test_prepare_export_without_cosmoscout_changes_nothing(small_table):
    options = FormatOptions(n_angles=181)
    table, out = prepare_export(small_table, ["hdf5", "texture"], options=options, optical_depth=1)
    assert table is small_table and out is options


def test_prepare_export_for_cosmoscout_needs_a_number_density(small_table):
    with pytest.raises(ValueError, match="cosmoscout format needs a number density"):
        prepare_export(small_table, ["cosmoscout"])


def test_prepare_export_sets_the_density_profile_and_the_optical_depth(small_table):
    table, options = prepare_export(
        small_table,
        ["hdf5", "cosmoscout"],
        optical_depth=0.4,
        reference_wavelength_nm=450.0,
        scale_height_m=11_100.0,
        n_altitudes=64,
    )
    column = table.provenance.inputs["column"]
    assert column["optical_depth"] == 0.4 and column["reference_wavelength_nm"] == 450.0
    # tau = N0 <C_ext> L, L = H (1 - exp(-top / H)) with the 120 km top.
    length = 11_100.0 * (1 - np.exp(-120e3 / 11_100.0))
    i = int(np.flatnonzero(table.wavelength_nm == 450.0)[0])
    tau = (
        table.cross_sections.number_density_per_m3
        * table.cross_sections.cext_um2[i]
        * 1e-12
        * length
    )
    np.testing.assert_allclose(tau, 0.4, rtol=1e-12)
    assert options.density is not None and options.density.shape == (64,)
    # The exponential at the 64 texel centres (i + 1/2) 120 km / 64, where CosmoScout VR's
    # preprocessor reads them (dustoptics.io.csv.cosmoscout).
    z = (np.arange(64) + 0.5) * 120e3 / 64
    np.testing.assert_allclose(options.density, np.exp(-z / 11_100.0), rtol=1e-14)
    assert options.recorded("cosmoscout") == {
        "density_profile": "exponential",
        "scale_height_m": 11_100.0,
        "top_altitude_m": 120_000.0,
        "n_altitudes": 64,
        "density_sampling": "texel centres (i + 1/2) top_altitude_m / n_altitudes",
    }


def test_the_cosmoscout_files_give_the_coefficient_at_every_texel_centre(small_table, tmp_path):
    """beta (written at the largest sample) times the written density is N0 C_ext exp(-z / H)
    at the texel centres z = (i + 1/2) T / N, the altitudes CosmoScout VR's preprocessor reads."""
    from dustoptics.io import read_cosmoscout_constituent
    from dustoptics.io.outputs import write_formats

    table, options = prepare_export(
        small_table.replace(cross_sections={"number_density_per_m3": 1e8}),
        ["cosmoscout"],
        scale_height_m=11_100.0,
        n_altitudes=32,
    )
    write_formats(table, tmp_path, ["cosmoscout"], options=options)
    c = read_cosmoscout_constituent(tmp_path, table.name)
    z = (np.arange(32) + 0.5) * 120e3 / 32
    want = 1e8 * table.cross_sections.cext_um2 * 1e-12 * np.exp(-z / 11_100.0)[:, None]
    got = (c.beta_sca_per_m + c.beta_abs_per_m)[None, :] * c.density[:, None]
    np.testing.assert_allclose(got, want, rtol=1e-6)  # the CSV's printed digits
