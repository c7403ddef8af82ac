"""The ``libradtran-nc`` files, read back with scipy's netCDF reader and checked against the
table, against Wiscombe's MIEV0 moments as libRadtran's mie tool converts them, and against
Bohren & Huffman's printed sample for the sign of P34.

libRadtran 2.0.2 (src/mie.c, "Convert from Wiscombe definition to Evans definition"):
P11 = (M1 + M2)/norm, P12 = (M2 - M1)/norm, P33 = 2 S21/norm, P34 = 2 D21/norm with
Wiscombe's M1 = |S1|^2, M2 = |S2|^2, S21 = Re(S1 S2*), D21 = -Im(S1 S2*) (van de Hulst's
amplitudes), norm = M1_0 + M2_0; pmom stored with the factor 2l+1 and summed as
sum_l pmom[l] P_l(mu) (libsrc_c/miecalc.c, mom2phase).  IPRT phase A's aerosol file has
this layout (P1..P4 = P11, P12, P33, P34).
"""

from __future__ import annotations

import csv
import io
import json
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from _data import data_path
from _rt_table import rt_table
from numpy.polynomial import legendre
from scipy.io import netcdf_file

import dustoptics as do
from dustoptics.io import FORMATS, write
from dustoptics.io.describe import describe_path

BENCH = ("mie-benchmarks",)


def read_cdf(path: Path) -> dict[str, Any]:
    with netcdf_file(path, "r", mmap=False) as f:
        out: dict[str, Any] = {name: np.array(v[:]) for name, v in f.variables.items()}
        out["_version"] = np.array(f.version)
        out["_dims"] = f.dimensions.copy()
    return out


@pytest.fixture(scope="module")
def polarized() -> do.Table:
    """Mars dust with the tabulated matrix F11..F34 and its expansion, N = 2e6 m-3."""
    return do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.5, v_eff=0.3),
        [500.0, 900.0],
        np.linspace(0.0, 180.0, 37),
        rtol=1e-6,
        expansion=True,
        polarization=True,
        name="mars pol",
    ).replace(cross_sections={"number_density_per_m3": 2.0e6})


def test_registered() -> None:
    assert "libradtran-nc" in FORMATS


def test_round_trip(polarized: do.Table, tmp_path: Path) -> None:
    assert polarized.expansion is not None and polarized.cross_sections is not None
    cdf, profile = write(polarized, tmp_path, format="libradtran-nc", bottom_km=0.0, top_km=10.0)
    assert cdf.name == "mars_pol.mie.cdf"
    assert profile.name == "mars_pol_aerosol_species.dat"
    assert cdf.read_bytes()[:4] == b"CDF\x01"  # classic netCDF, as libRadtran's mie tool writes
    d = read_cdf(cdf)
    dims = d["_dims"]
    assert dims["nphamat"] == 4 and dims["nhum"] == 1 and dims["nlam"] == 2
    assert int(d["_version"]) == 20110916
    np.testing.assert_allclose(d["wavelen"] * 1e3, polarized.wavelength_nm, rtol=1e-15)
    # ext per particle per cm3 [km-1 cm3] = cext [um2] 1e-12 [m2/um2] 1e6 [cm3/m3] 1e3 [m/km].
    np.testing.assert_allclose(d["ext"][:, 0], polarized.cross_sections.cext_um2 * 1e-3, rtol=1e-15)
    np.testing.assert_array_equal(d["ssa"][:, 0], polarized.ssa)
    pmom = d["pmom"][:, 0]
    assert np.all(pmom[:, 0, 0] == 1.0)  # uvspec refuses a phase function whose pmom_0 != 1
    np.testing.assert_array_equal(d["gg"][:, 0], polarized.g)
    np.testing.assert_array_equal(
        pmom[:, 0, : polarized.expansion.alpha1.shape[1]], polarized.expansion.alpha1
    )
    # The reader errs when nmom reaches nmommax (src/miecalc.c); the last moment is zero.
    assert np.all(d["nmom"] < dims["nmommax"])
    assert np.all(pmom[:, :, -1] == 0.0)
    theta = d["theta"][0, 0, 0]
    assert theta[0] == 180.0 and theta[-1] == 0.0 and np.all(np.diff(theta) < 0)
    assert np.all(d["ntheta"] == theta.size)
    # The species profile, parsed as uvspec does (non-comment rows, top first); the layer's
    # amount times ext is the extinction coefficient N <C_ext> [km-1].
    rows = [ln.split() for ln in profile.read_text().splitlines() if not ln.startswith("#")]
    assert [r[0] for r in rows] == ["10.0", "0.0"] and rows[0][1] == "0"
    n_cm3 = float(rows[1][1])
    np.testing.assert_allclose(d["ext"][:, 0] * n_cm3, polarized.beta_ext_per_m * 1e3, rtol=1e-14)
    text = describe_path(cdf)
    assert text.startswith("libRadtran polarized optical properties:")
    assert polarized.provenance.input_hash in text
    assert describe_path(profile).startswith("libRadtran aerosol species profile:")


def test_moments_reproduce_the_table_matrix(polarized: do.Table, tmp_path: Path) -> None:
    """sum_l pmom[l] P_l(mu) (numpy's Legendre series, as libRadtran's mom2phase) at the
    table's angles: 4 pi F11, 4 pi F12, 4 pi F33 and -4 pi F34 of the table, to its
    expansion and matrix error estimates (relative to F11); the phase variable holds
    the same sums from 180 deg down."""
    (cdf, _) = write(polarized, tmp_path, format="libradtran-nc")
    d = read_cdf(cdf)
    f12, f33, f34 = polarized.matrix.f12, polarized.matrix.f33, polarized.matrix.f34
    assert f12 is not None and f33 is not None and f34 is not None
    assert (
        polarized.expansion is not None and polarized.expansion.expansion_error_estimate is not None
    )
    assert polarized.matrix is not None and polarized.matrix.matrix_error_estimate is not None
    mu = np.cos(np.deg2rad(polarized.theta_deg))
    four_pi = 4.0 * np.pi
    for w in range(polarized.wavelength_nm.size):
        expected = four_pi * np.stack([polarized.phase[w], f12[w], f33[w], -f34[w]])
        tol = 2.0 * (
            polarized.expansion.expansion_error_estimate[w]
            + polarized.matrix.matrix_error_estimate[w]
        )
        for p in range(4):
            summed = legendre.legval(mu, d["pmom"][w, 0, p])
            assert np.max(np.abs(summed - expected[p]) / expected[0]) <= tol, (w, p)
            np.testing.assert_allclose(
                d["phase"][w, 0, p][::-1], summed, rtol=1e-12, atol=1e-12 * expected[0].max()
            )


def _miev0(case: int) -> dict[tuple[int, int], str]:
    path = data_path(*BENCH, "miev0_wiscombe_legendre_moments.csv")
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return {
        (int(r["moment"]), int(r["k"])): r["value"]
        for r in csv.DictReader(lines)
        if int(r["case"]) == case
    }


@pytest.mark.parametrize(("case", "x"), [(9, 1.0), (10, 100.0)])
def test_what_libradtrans_mie_tool_writes_from_miev0(case: int, x: float, tmp_path: Path) -> None:
    """Wiscombe's MIEV0 cases 9 and 10 (IPOLZN = 1234, 7 significant figures), converted
    as libRadtran's mie tool converts them: the file's pmom of P11, P12, P33, P34, including
    the sign of P34 (2 D21 / norm)."""
    ref = _miev0(case)
    wavelength_nm = 1000.0
    t = do.compute_optics(
        1.33 + 1e-5j,
        do.Monodisperse(radius_um=x * wavelength_nm * 1e-3 / (2 * np.pi)),
        [wavelength_nm],
        np.linspace(0.0, 180.0, 181),
        expansion=True,
        name="miev0",
    ).replace(cross_sections={"number_density_per_m3": 1.0})
    (cdf, _) = write(t, tmp_path, format="libradtran-nc")
    pmom = read_cdf(cdf)["pmom"][0, 0]
    norm = float(ref[(0, 1)]) + float(ref[(0, 2)])
    moments = sorted({m for m, _ in ref})
    assert len(moments) >= 3
    for m in moments:
        m1, m2, s21, d21 = (float(ref[(m, k)]) for k in (1, 2, 3, 4))
        expected = (2 * m + 1) / norm * np.array([m1 + m2, m2 - m1, 2 * s21, 2 * d21])
        # Half a unit of the 7th significant figure of each printed value (at most
        # 0.5e-6 of it), propagated through the sums.
        half = (
            0.5e-6
            * (2 * m + 1)
            / norm
            * np.array([abs(m1) + abs(m2), abs(m1) + abs(m2), 2 * abs(s21), 2 * abs(d21)])
        )
        got = pmom[:, m]
        # Measured: at most 0.96 of it (case 10), 0.22 (case 9).
        assert np.all(np.abs(got - expected) <= half + 1e-12), (case, m, got, expected)


def test_sign_of_p34_against_bohren_huffman(tmp_path: Path) -> None:
    """Bohren & Huffman's sample (m = 1.55, x = 5.213), printed in their convention
    (S34 = Im(S2 S1*)): the file's P34 / P11 is minus their S34 / S11, and P12 / P11 is
    minus their POL, at all 21 printed angles to half a unit of the printed digits;
    S34 / S11 changes sign over the angles, so a flipped sign cannot pass."""
    data = json.loads(
        data_path(*BENCH, "bohren_huffman_bhmie_sample.json").read_text(), parse_float=str
    )
    inputs = data["inputs"]
    theta = np.array([float(r["theta_deg"]) for r in data["table"]])
    t = do.compute_optics(
        complex(float(inputs["m_real"]), float(inputs["m_imag"])),
        do.Monodisperse(radius_um=float(inputs["sphere_radius_um"])),
        [float(inputs["wavelength_um"]) * 1e3],
        theta,
        expansion=True,
        name="bh",
    ).replace(cross_sections={"number_density_per_m3": 1.0})
    (cdf, _) = write(t, tmp_path, format="libradtran-nc")
    d = read_cdf(cdf)
    phase = d["phase"][0, 0][:, ::-1]  # back to the table's ascending angles
    printed_s34 = np.array([float(r["S34_over_S11"]) for r in data["table"]])
    assert printed_s34.min() < -0.1 and printed_s34.max() > 0.1
    for i, row in enumerate(data["table"]):
        for key, value in (
            ("S34_over_S11", -phase[3, i] / phase[0, i]),
            ("POL_minus_S12_over_S11", -phase[1, i] / phase[0, i]),
            ("S33_over_S11", phase[2, i] / phase[0, i]),
        ):
            text = row[key]
            half = 0.5 * 10.0 ** int(Decimal(text.strip()).as_tuple().exponent)
            tol = max(half, 0.5e-5 * abs(float(text)))
            assert abs(value - float(text)) <= tol + 1e-9, (key, row["theta_deg"], value, text)


def test_refusals(tmp_path: Path) -> None:
    table = rt_table()
    with pytest.raises(ValueError, match=r"expansion=True"):
        plain = table.replace(
            expansion=None,
        )
        write(plain, tmp_path, format="libradtran-nc")
    with pytest.raises(ValueError, match=r"number-density-per-m3"):
        write(
            table.replace(cross_sections={"number_density_per_m3": None}),
            tmp_path,
            format="libradtran-nc",
        )
    with pytest.raises(ValueError, match=r"top_km must exceed"):
        write(table, tmp_path, format="libradtran-nc", bottom_km=2.0, top_km=1.0)
    narrow = do.compute_optics(
        1.5, do.Monodisperse(radius_um=0.2), [500.0], [0.0, 90.0], expansion=True
    ).replace(cross_sections={"number_density_per_m3": 1.0})
    with pytest.raises(ValueError, match=r"angles from 0 to 180 deg"):
        write(narrow, tmp_path, format="libradtran-nc")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(FileExistsError):
        write(table, tmp_path, format="libradtran-nc")
        write(table, tmp_path, format="libradtran-nc")


def test_bytes_are_deterministic() -> None:
    from dustoptics.io.rt.libradtran_netcdf import libradtran_netcdf_bytes

    table = rt_table()
    first = libradtran_netcdf_bytes(table)
    assert first == libradtran_netcdf_bytes(table)
    with netcdf_file(io.BytesIO(first), "r", mmap=False) as f:
        assert f.variables["pmom"].shape[2] == 4


CONFIG = """\
name = "small-dust"
description = "two wavelengths of Blue Moon's dust with the expansion, for libradtran-nc"

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
rtol = 1e-3
wavelengths_nm = [440.0, 680.0]
n_theta = 19
expansion = true

[phase]
model = "mie"
"""


def test_build_export_and_info_from_the_command_line(tmp_path: Path, capsys: Any) -> None:
    from dustoptics.cli import main

    config = tmp_path / "rt.toml"
    config.write_text(CONFIG, encoding="utf-8")
    out = tmp_path / "out"
    argv = ["build", str(config), "--out", str(out), "--quiet", "--format"]
    density = ["--number-density-per-m3", "1e8"]
    assert main([*argv, "netcdf,libradtran-nc", *density]) == 0
    folder = out / "small-dust"
    assert sorted(p.name for p in folder.iterdir()) == [
        "small-dust.mie.cdf",
        "small-dust.nc",
        "small-dust_aerosol_species.dat",
    ]
    table = do.open_table(folder / "small-dust.nc")
    assert table.expansion is not None
    pmom = read_cdf(folder / "small-dust.mie.cdf")["pmom"]
    np.testing.assert_array_equal(
        pmom[:, 0, 0, : table.expansion.alpha1.shape[1]], table.expansion.alpha1
    )
    capsys.readouterr()
    assert main(["info", str(folder / "small-dust.mie.cdf")]) == 0
    assert "P11, P12, P33, P34" in capsys.readouterr().out
    again = tmp_path / "again"
    export = ["export", str(folder / "small-dust.nc"), "--out", str(again), "--quiet"]
    assert main([*export, "--format", "libradtran-nc"]) == 0
    exported = read_cdf(again / "small-dust" / "small-dust.mie.cdf")["pmom"]
    np.testing.assert_array_equal(exported, pmom)
    # Without the expansion in the configuration: the format asks for it, the build computes
    # it, says so and records it (the same coefficients as the configuration's own).
    config.write_text(CONFIG.replace("expansion = true\n", ""), encoding="utf-8")
    capsys.readouterr()
    asked = tmp_path / "asked"
    build = ["build", str(config), "--out", str(asked), "--format", "netcdf,libradtran-nc"]
    assert main([*build, *density]) == 0
    err = capsys.readouterr().err
    note = (
        "--format libradtran-nc needs the phase function's expansion coefficients: computed "
        "(optics.expansion = true)"
    )
    assert f"dustoptics: {note}" in err
    recorded = do.open_table(asked / "small-dust" / "small-dust.nc")
    assert note in recorded.provenance.notes
    assert recorded.provenance.inputs["optics"]["expansion"] is True
    np.testing.assert_array_equal(
        read_cdf(asked / "small-dust" / "small-dust.mie.cdf")["pmom"], pmom
    )


def test_another_cdf_file_is_not_taken_for_one(tmp_path: Path) -> None:
    from dustoptics.io import FormatError
    from dustoptics.io.describe_formats import describer_of

    other = tmp_path / "other.mie.cdf"
    with netcdf_file(other, "w", version=1) as f:
        f.file_info = "Netcdf file created using libRadtran-Mie-tool"
        f.createDimension("nlam", 1)
        f.createVariable("wavelen", "d", ("nlam",))[:] = [0.5]
    assert describer_of(other) is None
    with pytest.raises(FormatError, match="not a file dustoptics writes"):
        describe_path(other)
