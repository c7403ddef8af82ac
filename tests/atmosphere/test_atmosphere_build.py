"""dustoptics.atmosphere.build: the atmosphere sets by name and their provenance record."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

from dustoptics.atmosphere.build import (
    ATMOSPHERES,
    build_atmosphere,
    set_inputs,
    set_provenance,
)

SMALL_DUST = """\
name = "small-dust"
description = "a small Mie dust for the set tests"
[material]
model = "constant"
n = 1.5
k = 0.001
[size_distribution]
model = "modified_gamma"
r_eff_um = 0.5
v_eff = 0.1
[optics]
rtol = 1e-2
wavelengths_nm = [440.0, 550.0, 680.0]
n_theta = 19
[phase]
model = "mie"
"""


def test_the_sets_by_name():
    assert ATMOSPHERES == ("mars", "earth", "earth-kobe2026")
    kobe = build_atmosphere("earth-kobe2026")
    assert kobe.name == "earth-kobe2026"
    grid = (400.0, 500.0, 600.0, 700.0)
    earth = build_atmosphere("earth", wavelength_nm=grid)
    for constituent in earth.constituents:
        np.testing.assert_array_equal(constituent.table.wavelength_nm, grid)


@pytest.mark.parametrize(
    ("name", "kwargs", "message"),
    [
        ("venus", {}, "name must be one of 'mars', 'earth', 'earth-kobe2026'; got 'venus'"),
        ("earth-kobe2026", {"wavelength_nm": (400.0,)}, "wavelength_nm must be None"),
        ("mars", {"dust": "costa"}, "dust 'costa' has no cross-sections"),
        ("mars", {"dust": "nope"}, "nope"),
    ],
)
def test_build_atmosphere_refuses(name, kwargs, message):
    with pytest.raises(ValueError, match=message):
        build_atmosphere(name, **kwargs)


def test_mars_dust_from_a_configuration_file_and_its_optical_depth(tmp_path):
    path = tmp_path / "dust.toml"
    path.write_text(SMALL_DUST, encoding="utf-8")
    grid = (440.0, 550.0, 680.0)
    a = build_atmosphere("mars", dust=str(path), optical_depth=0.5, wavelength_nm=grid)
    b = build_atmosphere("mars", dust=str(path), optical_depth=0.7, wavelength_nm=grid)
    dust_a = next(c for c in a.constituents if c.role == "aerosols").table
    dust_b = next(c for c in b.constituents if c.role == "aerosols").table
    np.testing.assert_array_equal(dust_a.wavelength_nm, grid)
    assert dust_a.theta_deg.size == 1801  # every 0.1 deg
    # N0 is proportional to tau.
    ratio = (
        dust_b.cross_sections.number_density_per_m3 / dust_a.cross_sections.number_density_per_m3
    )
    assert ratio == pytest.approx(0.7 / 0.5, rel=1e-12)


def test_set_inputs_records_what_changes_the_numbers(tmp_path):
    assert set_inputs("mars") == {
        "set": "mars",
        "dust": "blue-moons",
        "optical_depth": 0.5,
        "reference_wavelength_nm": 550.0,
    }
    ozone = tmp_path / "o3.csv"
    ozone.write_bytes(b"some bytes\n")
    assert set_inputs("earth", ozone_csv=ozone, wavelength_nm=(400, 500)) == {
        "set": "earth",
        "wavelengths_nm": [400.0, 500.0],
        "ozone_csv": {"path": str(ozone), "sha256": hashlib.sha256(b"some bytes\n").hexdigest()},
        "aerosol": {
            "name": "continental-average",
            "optical_depth": 0.1,
            "reference_wavelength_nm": 550.0,
            "relative_humidity_percent": 80,
        },
    }


def test_set_provenance_hashes_the_inputs_and_the_constituents():
    atm = build_atmosphere("earth-kobe2026")
    record = json.loads(set_provenance(atm, set_inputs("earth-kobe2026")))
    assert record["set"] == "earth-kobe2026"
    assert record["format"] == "dustoptics atmosphere set provenance"
    assert set(record["constituents"]) == {c.role for c in atm.constituents}
    other = json.loads(set_provenance(atm, {**set_inputs("earth-kobe2026"), "extra": 1}))
    assert other["input_hash"] != record["input_hash"]
