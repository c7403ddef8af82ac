"""Tests for dustoptics.io.csv.cosmoscout: CosmoScout VR's per-constituent CSV set.

Hand-made tables with numbers chosen to be checked by hand: a Rayleigh phase
function 3/(16 pi) (1 + mu^2) (brief section 4) on 361 angles (0.5 deg), cross-sections
cext = 2.0 um^2 and csca = 1.5 um^2 at N = 1e8 m^-3, so beta = N C gives
beta_sca = 1.5e-12 m^2 * 1e8 m^-3 = 1.5e-4 m^-1 and beta_abs = 0.5e-4 m^-1;
and an ozone-like absorber with csca = 0.  The wavelengths are the three of
the seed shader (680, 550, 440 nm; brief section 7) in increasing order.
"""

from __future__ import annotations

import numpy as np
import pytest

from dustoptics.io import FORMATS, FormatError
from dustoptics.io.csv.cosmoscout import (
    check_cosmoscout_set,
    cosmoscout_wavelength_text,
    read_cosmoscout_constituent,
    write_cosmoscout_constituent,
    write_cosmoscout_set,
)
from dustoptics.table import Table

WAVELENGTHS_NM = [440.0, 550.0, 680.0]
DENSITY = np.exp(
    -np.linspace(0.0, 120.0, 7) / 11.0
)  # 11 km scale height (brief section 6), max exp(0) = 1


def _table(
    name: str,
    *,
    csca: float,
    cext: float = 2.0,
    n_theta: int = 361,
    density: float | None = 1e8,
) -> Table:
    theta = np.linspace(0.0, 180.0, n_theta)
    mu = np.cos(np.deg2rad(theta))
    phase = np.tile(3.0 / (16.0 * np.pi) * (1.0 + mu**2), (len(WAVELENGTHS_NM), 1))
    phase[1] *= np.linspace(1.1, 0.9, n_theta)  # a different shape per wavelength (resampling test)
    n = len(WAVELENGTHS_NM)
    return Table(
        name=name,
        wavelength_nm=WAVELENGTHS_NM,
        theta_deg=theta,
        phase=phase,
        g=np.zeros(n),
        cext_um2=np.full(n, cext),
        csca_um2=np.full(n, csca),
        number_density_per_m3=density,
    )


@pytest.fixture
def aerosols() -> Table:
    return _table("aerosols", csca=1.5)


@pytest.fixture
def ozone() -> Table:
    return _table(
        "ozone", csca=0.0, cext=3.1e-13
    )  # Kobe's 650 nm cross-section, 3.1e-25 m^2 (brief section 6)


def _reader_rules(directory, names) -> None:
    """CosmoScout's reader, as the brief (section 7) states it, applied independently."""
    reference = None
    for name in names:
        for kind, width in (
            ("phase", 182),
            ("scattering", 2),
            ("absorption", 2),
            ("density", 1),
        ):
            path = directory / f"{name}_{kind}.csv"
            if not path.exists():
                assert kind in ("phase", "scattering") and name == "ozone"
                continue
            lines = path.read_text().splitlines()[1:]  # the first line is skipped
            cells = [line.split(",") for line in lines]
            assert all(len(row) == width for row in cells), path.name
            if kind == "density":
                assert len(cells) == DENSITY.size
                continue
            assert len(cells) == len(WAVELENGTHS_NM), path.name
            nm = [float(np.float32(row[0])) * 1e9 for row in cells]
            if reference is None:
                reference = nm
            assert nm == reference, path.name  # identical in every file, not merely close
    assert np.allclose(reference, WAVELENGTHS_NM, rtol=1e-7)  # float32 has 24 bits: rtol 6e-8


# ------------------------------------------------------------------ writing


def test_set_passes_the_reader_rules(aerosols, ozone, tmp_path):
    paths = write_cosmoscout_set(
        tmp_path, {"aerosols": (aerosols, DENSITY), "ozone": (ozone, DENSITY)}
    )
    assert [p.name for p in paths] == [
        "aerosols_phase.csv", "aerosols_scattering.csv", "aerosols_absorption.csv",
        "aerosols_density.csv", "ozone_absorption.csv", "ozone_density.csv",
    ]  # fmt: skip
    _reader_rules(tmp_path, ["aerosols", "ozone"])
    assert check_cosmoscout_set(tmp_path) == ["aerosols", "ozone"]


def test_headers_and_wavelength_text(aerosols, tmp_path):
    write_cosmoscout_constituent(aerosols, tmp_path, name="dust", density=DENSITY)
    phase = (tmp_path / "dust_phase.csv").read_text().splitlines()
    # The texel centres (j + 1/2) 180 / 181 deg, where CosmoScout's preprocessor reads column j.
    header = phase[0].split(",")
    assert header[0] == "lambda" and len(header) == 182
    np.testing.assert_array_equal(
        [float(c) for c in header[1:]], (np.arange(181) + 0.5) * (180.0 / 181)
    )
    assert [row.split(",")[0] for row in phase[1:]] == ["4.4e-7", "5.5e-7", "6.8e-7"]
    assert (tmp_path / "dust_scattering.csv").read_text().splitlines()[0] == "lambda,beta_sca"
    assert (tmp_path / "dust_absorption.csv").read_text().splitlines()[0] == "lambda,beta_abs"
    assert (tmp_path / "dust_density.csv").read_text().splitlines()[0] == "density"
    assert cosmoscout_wavelength_text(552.5) == "5.525e-7"


def test_beta_is_number_density_times_cross_section(aerosols, tmp_path):
    write_cosmoscout_constituent(aerosols, tmp_path, name="dust", density=DENSITY)
    back = read_cosmoscout_constituent(tmp_path, "dust")
    # 1e8 m^-3 * 1.5 um^2 * 1e-12 m^2/um^2 = 1.5e-4 m^-1; 1e8 * 0.5e-12 = 0.5e-4 m^-1.
    np.testing.assert_allclose(back.beta_sca_per_m, 1.5e-4, rtol=1e-15)
    np.testing.assert_allclose(back.beta_abs_per_m, 0.5e-4, rtol=1e-15)
    np.testing.assert_array_equal(back.wavelength_m, [4.4e-7, 5.5e-7, 6.8e-7])
    np.testing.assert_array_equal(back.density, DENSITY)  # repr text: exact


def test_phase_at_the_texel_centres(aerosols, tmp_path):
    write_cosmoscout_constituent(aerosols, tmp_path, name="dust", density=DENSITY, n_theta=4)
    back = read_cosmoscout_constituent(tmp_path, "dust")
    # 4 columns of a texture over 0-180 deg: centres at 22.5, 67.5, 112.5, 157.5 deg.
    np.testing.assert_array_equal(back.theta_deg, [22.5, 67.5, 112.5, 157.5])
    # On the table's 0.5 deg grid 22.5 and 67.5 ... are nodes: the table's own values.
    np.testing.assert_array_equal(back.phase, aerosols.phase[:, [45, 135, 225, 315]])


def test_other_angle_counts_interpolate_linearly(aerosols, tmp_path):
    write_cosmoscout_constituent(aerosols, tmp_path, name="dust", density=DENSITY, n_theta=7)
    back = read_cosmoscout_constituent(tmp_path, "dust")
    np.testing.assert_allclose(back.theta_deg, (np.arange(7) + 0.5) * 180.0 / 7, rtol=1e-15)
    np.testing.assert_array_equal(back.phase, aerosols.phase_at(back.theta_deg))


def test_the_reader_takes_both_layouts(aerosols, tmp_path):
    # Other writers (CosmoScout's scattering-table generator) put the angles 0..180 deg.
    write_cosmoscout_constituent(aerosols, tmp_path, name="dust", density=DENSITY, n_theta=7)
    path = tmp_path / "dust_phase.csv"
    lines = path.read_text().splitlines()
    lines[0] = "lambda,0,30,60,90,120,150,180"
    path.write_text("\n".join(lines) + "\n")
    back = read_cosmoscout_constituent(tmp_path, "dust")
    np.testing.assert_array_equal(back.theta_deg, [0.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0])
    assert check_cosmoscout_set(tmp_path) == ["dust"]


def test_non_scattering_constituent_has_no_phase_file(ozone, tmp_path):
    paths = write_cosmoscout_constituent(ozone, tmp_path, name="ozone", density=DENSITY)
    assert [p.name for p in paths] == ["ozone_absorption.csv", "ozone_density.csv"]
    back = read_cosmoscout_constituent(tmp_path, "ozone")
    assert back.phase is None and back.theta_deg is None and back.beta_sca_per_m is None
    np.testing.assert_allclose(back.beta_abs_per_m, 3.1e-13 * 1e-12 * 1e8, rtol=1e-15)


def test_registry_entry_needs_a_density(aerosols, tmp_path):
    with pytest.raises(ValueError, match="needs density="):
        FORMATS["cosmoscout"](aerosols, tmp_path, overwrite=False)
    paths = FORMATS["cosmoscout"](aerosols, tmp_path, overwrite=False, density=DENSITY)
    assert paths[0].name == "aerosols_phase.csv"


# ------------------------------------------------------------------ refusals


@pytest.mark.parametrize(
    ("density", "message"),
    [
        (np.ones((2, 2)), "must be 1-dimensional"),
        ([1.0, np.nan], "must be finite"),
        ([1.0, -0.1], "must be >= 0"),
        ([0.5, 0.25], "maximum exactly 1.*got maximum 0.5"),
        ([2.0, 1.0], "maximum exactly 1.*got maximum 2.0"),
        ([1.0], "at least 2 altitudes"),
        ("dense", "real numbers"),
    ],
)
def test_density_is_validated(aerosols, tmp_path, density, message):
    with pytest.raises(ValueError, match=f"density of constituent 'dust'.*{message}"):
        write_cosmoscout_constituent(aerosols, tmp_path, name="dust", density=density)
    assert list(tmp_path.iterdir()) == []


def test_mismatched_wavelengths_are_refused(aerosols, tmp_path):
    shifted = aerosols.replace(name="haze", wavelength_nm=[440.0, 550.0, 700.0])
    with pytest.raises(
        ValueError, match="'haze' has wavelengths .* 'dust' has .*identical wavelengths"
    ):
        write_cosmoscout_set(tmp_path, {"dust": (aerosols, DENSITY), "haze": (shifted, DENSITY)})
    assert list(tmp_path.iterdir()) == []


def test_tables_without_what_cosmoscout_needs(aerosols, tmp_path):
    with pytest.raises(ValueError, match="no number_density_per_m3"):
        write_cosmoscout_constituent(
            aerosols.replace(number_density_per_m3=None),
            tmp_path,
            name="dust",
            density=DENSITY,
        )
    with pytest.raises(ValueError, match="phase function only"):
        write_cosmoscout_constituent(
            aerosols.replace(cext_um2=None, csca_um2=None),
            tmp_path,
            name="dust",
            density=DENSITY,
        )


@pytest.mark.parametrize(
    ("name", "n_theta"), [("a/b", 181), ("", 181), ("dust", 1), ("dust", 90.0)]
)
def test_bad_name_or_angle_count(aerosols, tmp_path, name, n_theta):
    with pytest.raises(ValueError, match="name must be|n_theta must be"):
        write_cosmoscout_constituent(
            aerosols, tmp_path, name=name, density=DENSITY, n_theta=n_theta
        )


def test_set_is_written_all_or_nothing(aerosols, ozone, tmp_path):
    (tmp_path / "ozone_density.csv").write_text("keep me\n")
    with pytest.raises(FileExistsError, match="ozone_density.csv"):
        write_cosmoscout_set(tmp_path, {"aerosols": (aerosols, DENSITY), "ozone": (ozone, DENSITY)})
    assert [p.name for p in tmp_path.iterdir()] == ["ozone_density.csv"]
    write_cosmoscout_set(
        tmp_path,
        {"aerosols": (aerosols, DENSITY), "ozone": (ozone, DENSITY)},
        overwrite=True,
    )
    assert check_cosmoscout_set(tmp_path) == ["aerosols", "ozone"]


# ------------------------------------------------------------------ the checker on broken sets


@pytest.fixture
def written(aerosols, ozone, tmp_path):
    write_cosmoscout_set(tmp_path, {"aerosols": (aerosols, DENSITY), "ozone": (ozone, DENSITY)})
    return tmp_path


def _edit(path, change) -> None:
    path.write_text(change(path.read_text()))


@pytest.mark.parametrize(
    ("file", "change", "message"),
    [
        # 4.41e-7 m is another float32 than 4.4e-7 m: the same wavelength must read the same everywhere.
        (
            "ozone_absorption.csv",
            lambda t: t.replace("4.4e-7", "4.41e-7"),
            "differ from",
        ),
        (
            "aerosols_phase.csv",
            lambda t: t.replace("\n5.5e-7,", "\n5.5e-7,1.0,", 1),
            "line 3 has 183 cells",
        ),
        (
            "aerosols_scattering.csv",
            lambda t: t.replace("lambda,beta_sca", "lambda,beta"),
            "header must be",
        ),
        (
            "aerosols_absorption.csv",
            lambda t: t.rstrip("\n"),
            "does not end with a newline",
        ),
        (
            "aerosols_density.csv",
            lambda t: t.replace("\n1.0\n", "\n0.9\n"),
            "maximum 1",
        ),
        ("aerosols_density.csv", lambda t: t + "-0.5\n", "must be >= 0"),
        (
            "ozone_absorption.csv",
            lambda t: t.replace("\n6.8e-7,", "\n6.8e-7x,"),
            "not a number",
        ),
        (
            "aerosols_phase.csv",
            lambda t: t.replace("lambda,0.4972", "lambda,0.6", 1),
            "texel centres",
        ),
        (
            "aerosols_scattering.csv",
            lambda t: t.splitlines()[0] + "\n" + t.splitlines()[1] + "\n",
            "differs from",
        ),
    ],
)
def test_checker_reports_the_first_violation(written, file, change, message):
    _edit(written / file, change)
    with pytest.raises(FormatError, match=f"{file}.*{message}"):
        check_cosmoscout_set(written)


def test_checker_needs_complete_constituents(written):
    (written / "ozone_density.csv").unlink()
    with pytest.raises(FormatError, match="ozone_density.csv: missing"):
        check_cosmoscout_set(written)
    (written / "aerosols_scattering.csv").unlink()
    with pytest.raises(
        FormatError, match="only one of aerosols_phase.csv and aerosols_scattering.csv"
    ):
        check_cosmoscout_set(written)


def test_checker_on_an_empty_directory(tmp_path):
    with pytest.raises(FormatError, match="no CosmoScout files"):
        check_cosmoscout_set(tmp_path)
    with pytest.raises(FileNotFoundError, match="no such directory"):
        check_cosmoscout_set(tmp_path / "missing")
