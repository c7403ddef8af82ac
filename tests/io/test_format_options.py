"""The formats' options (dustoptics.io.FormatOptions, generated from the format records) and
the table and options for a set of formats (dustoptics.io.outputs.prepare_export)."""

from __future__ import annotations

import numpy as np
import pytest

from dustoptics.io import FormatOptions, read_cosmoscout_constituent
from dustoptics.io.outputs import prepare_export, write_formats
from dustoptics.models.compute import build_table
from dustoptics.models.config import parse_config

SMALL = """\
name = "small"
description = "three wavelengths, for the tests of the formats' options"

[material]
model = "mars_dust"
hematite_fraction = 0.03
host_index = { n = 1.5, k = 0.0 }
hematite = "querry-extraordinary"
rule = "maxwell_garnett"

[size_distribution]
model = "modified_gamma"
r_eff_um = 1.0
v_eff = 0.2

[optics]
weighting = "scattering"
rtol = 1e-3
wavelengths_nm = { start = 400, stop = 490, step = 10 }
n_theta = 19

[phase]
model = "mie"
"""


@pytest.fixture(scope="module")
def small_table():
    return build_table(parse_config(SMALL))


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
    density = options.for_format("cosmoscout")["density"]
    assert density.shape == (64,)
    # The exponential at the 64 texel centres (i + 1/2) 120 km / 64, where CosmoScout VR's
    # preprocessor reads them (dustoptics.io.csv.cosmoscout).
    z = (np.arange(64) + 0.5) * 120e3 / 64
    np.testing.assert_allclose(density, np.exp(-z / 11_100.0), rtol=1e-14)
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
