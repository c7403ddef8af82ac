"""The validated domain (dustoptics.scattering.domain): every output against mpmath, and the refusal.

The references: ``tests/reference/mpmath_mie.py`` (30 digits, independent of the
kernel), computed here for the cheap points and read from
``tests/data/mie-benchmarks/domain_reference_mpmath.json`` (written by
``scripts/domain_reference.py``, its provenance in its header) for the large
spheres; the cheap points of the file are recomputed here and must agree to its
stored digits, so the file is what the reference code gives.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from reference.mpmath_mie import mie_reference

import dustoptics as do
from dustoptics.cli import main
from dustoptics.models.compute import mie_request
from dustoptics.models.presets import list_presets, load_preset
from dustoptics.scattering import domain, optics
from dustoptics.scattering.domain import (
    VALIDATED_DOMAIN,
    VERIFIED_ACCURACY,
    OutsideDomainError,
    UnvalidatedWarning,
    domain_summary,
    domain_text,
)
from dustoptics.scattering.mie import MIN_SIZE_PARAMETER, single_sphere

mp = pytest.importorskip("mpmath")

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = ROOT / "tests" / "data" / "mie-benchmarks" / "domain_reference_mpmath.json"
DOC = json.loads(REFERENCE.read_text(encoding="utf-8"))
THETA_DEG = np.array(DOC["provenance"]["theta_deg"])
MU = [math.cos(math.radians(t)) for t in THETA_DEG]
POINTS = DOC["points"]


#: The smallest size parameter a table can hold: radius 1e-6 um at 1e7 nm.
TABLE_MIN_X = 2.0 * math.pi * 1e-6 / 1e4


def _wavelength_nm(x: float) -> float:
    """1000 nm, or 1 cm for the smallest spheres (radii stay >= 1e-6 um). [nm]"""
    return 1000.0 if x >= 1e-2 else 1e7


def _radius_um(x: float) -> float:
    return x * _wavelength_nm(x) * 1e-3 / (2.0 * math.pi)


def _expected(row: dict) -> dict[str, np.ndarray | float]:
    """The table's quantities of one sphere (radius x lambda / (2 pi)) from the reference."""
    x = float(row["x"])
    r_um = _radius_um(x)
    qext, qsca, qback, g = (float(row[key]) for key in ("qext", "qsca", "qback", "g"))
    s1 = np.array([complex(float(a), float(b)) for a, b in row["s1"]])
    s2 = np.array([complex(float(a), float(b)) for a, b in row["s2"]])
    norm = math.pi * x * x * qsca  # F_ij = S_ij / (pi x^2 Q_sca): 2 pi int F11 dmu = 1
    area = math.pi * r_um * r_um
    return {
        "cext_um2": qext * area,
        "csca_um2": qsca * area,
        "cback_um2": qback * area,
        "g": g,
        "phase": 0.5 * (np.abs(s1) ** 2 + np.abs(s2) ** 2) / norm,
        "f12": 0.5 * (np.abs(s2) ** 2 - np.abs(s1) ** 2) / norm,
        "f33": (s2 * s1.conj()).real / norm,
        "f34": (s2 * s1.conj()).imag / norm,
    }


def _check(got: dict, want: dict, label: str) -> None:
    acc = VERIFIED_ACCURACY
    cext = want["cext_um2"]
    for key in ("cext_um2", "csca_um2"):
        assert got[key] == pytest.approx(want[key], rel=acc.cross_section_rtol, abs=0.0), (
            label,
            key,
        )
    assert got["cback_um2"] == pytest.approx(
        want["cback_um2"], rel=acc.backscatter_rtol, abs=0.0
    ), label
    # Absorption relative to extinction (it is their difference).
    cabs = got["cext_um2"] - got["csca_um2"]
    assert abs(cabs - (want["cext_um2"] - want["csca_um2"])) <= acc.cross_section_rtol * cext, label
    assert abs(got["g"] - want["g"]) <= acc.asymmetry_atol, label
    f11 = want["phase"]
    np.testing.assert_allclose(got["phase"], f11, rtol=acc.phase_rtol, atol=0.0, err_msg=label)
    for key in ("f12", "f33", "f34"):
        err = np.abs(got[key] - want[key]) / f11
        assert err.max() <= acc.matrix_rtol, (label, key, float(err.max()))


def _table_outputs(row: dict) -> dict:
    """The outputs of a Monodisperse table (the polydisperse kernel's path) for one sphere."""
    x = float(row["x"])
    with warnings.catch_warnings():
        # A radius below 1 nm is asked for on purpose (the smallest spheres).
        warnings.filterwarnings("ignore", message="radius_um = .* is below 0.001 um")
        sphere = do.Monodisperse(radius_um=_radius_um(x))
    t = do.compute_optics(
        complex(row["n"], row["k"]),
        sphere,
        wavelength_nm=[_wavelength_nm(x)],
        theta_deg=THETA_DEG,
        polarization=True,
        workers=1,
    )
    cs, mx = t.cross_sections, t.matrix
    assert cs is not None and mx is not None and cs.cback_um2 is not None
    return {
        "cext_um2": float(cs.cext_um2[0]),
        "csca_um2": float(cs.csca_um2[0]),
        "cback_um2": float(cs.cback_um2[0]),
        "g": float(t.g[0]),
        "phase": t.phase[0],
        "f12": mx.f12[0],
        "f33": mx.f33[0],
        "f34": mx.f34[0],
    }


def test_domain_reaches_the_kernels_smallest_sphere():
    assert VALIDATED_DOMAIN.min_size_parameter == MIN_SIZE_PARAMETER
    assert any(row["x"] == 1e-9 for row in POINTS)  # the table path near its smallest


def test_reference_file_names_its_provenance():
    prov = DOC["provenance"]
    assert prov["written_by"] == "python scripts/domain_reference.py"
    assert prov["dps"] >= 30 and prov["mpmath"] and len(prov["commit"]) == 40
    corners = {(row["x"], row["n"], row["k"]) for row in POINTS if row["label"] == "corner"}
    d = VALIDATED_DOMAIN
    assert corners == {
        (x, n, k)
        for x in (d.min_size_parameter, d.max_size_parameter)
        for n in (d.min_n, d.max_n)
        for k in (0.0, d.max_k)
    }


@pytest.mark.parametrize(
    "row", POINTS, ids=lambda r: f"{r['label'][:24]}-x{r['x']:.3g}-m{r['n']:.3g}+{r['k']:.3g}i"
)
def test_every_output_within_the_verified_accuracy(row):
    label = f"{row['label']}: m = {row['n']}+{row['k']}i, x = {row['x']}"
    if row["x"] >= TABLE_MIN_X:  # below it, the single-sphere entry only
        _check(_table_outputs(row), _expected(row), label)
    # The single-sphere entry: efficiencies, g and the amplitudes' phase function.
    want = _expected(row)
    s = single_sphere(m=complex(row["n"], row["k"]), x=float(row["x"]), mu=np.array(MU))
    assert s.qext == pytest.approx(float(row["qext"]), rel=VERIFIED_ACCURACY.cross_section_rtol)
    assert s.qsca == pytest.approx(float(row["qsca"]), rel=VERIFIED_ACCURACY.cross_section_rtol)
    assert abs(s.g - want["g"]) <= VERIFIED_ACCURACY.asymmetry_atol
    np.testing.assert_allclose(s.phase, want["phase"], rtol=VERIFIED_ACCURACY.phase_rtol)


def test_the_file_is_what_the_reference_code_gives():
    """The cheap points (x <= 30), recomputed here to the file's 20 stored digits."""
    cheap = [row for row in POINTS if row["x"] <= 30.0]
    assert len(cheap) >= 10
    for row in cheap:
        ref = mie_reference(
            m=complex(row["n"], row["k"]), x=row["x"], mu=MU, dps=DOC["provenance"]["dps"]
        )
        for key in ("qext", "qsca", "qback", "g"):
            assert float(getattr(ref, key)) == pytest.approx(float(row[key]), rel=1e-18, abs=0.0)
        got = [complex(s) for s in ref.s1]
        want = [complex(float(a), float(b)) for a, b in row["s1"]]
        np.testing.assert_allclose(got, want, rtol=1e-15)


def test_reference_agrees_with_the_rayleigh_limit():
    """The reference itself, against the small-sphere limit (Bohren & Huffman eq. 5.8, 5.11)."""
    m, x = 1.5 + 0.1j, 1e-4
    ref = mie_reference(m=m, x=x, mu=[1.0])
    polar = (m * m - 1) / (m * m + 2)
    assert float(ref.qsca) == pytest.approx(8.0 / 3.0 * x**4 * abs(polar) ** 2, rel=1e-7)
    assert float(ref.qext - ref.qsca) == pytest.approx(4.0 * x * polar.imag, rel=1e-7)


def test_presets_and_earth_aerosols_stay_inside():
    """Every Mie preset's request and the largest Earth aerosol lie in the domain."""
    for name in list_presets():
        config = load_preset(name)
        if not config.phase.uses_mie:
            continue
        request = mie_request(config)
        cost = optics.estimate_cost(request, workers=1)
        assert domain.check_domain(
            m=request.m,
            min_size_parameter=cost.min_size_parameter,
            max_size_parameter=cost.max_size_parameter,
            allow_unvalidated=False,
        ), name
    earth = [row for row in POINTS if row["label"].startswith("largest Earth")]
    assert len(earth) == 1 and earth[0]["x"] > 2000.0


def test_outside_refused_before_any_work(monkeypatch):
    def no_work(*args, **kwargs):  # pragma: no cover - must not run
        raise AssertionError("the solve ran")

    monkeypatch.setattr(optics, "solve_wavelengths", no_work)
    big = do.Monodisperse(
        radius_um=1.2 * VALIDATED_DOMAIN.max_size_parameter * 0.55 / (2 * math.pi)
    )
    with pytest.raises(
        OutsideDomainError,
        match=r"size parameter 3600 > 3000: outside the validated domain.*allow_unvalidated=True",
    ):
        do.compute_optics(1.5, big, [550.0], [0.0, 180.0])
    with pytest.raises(OutsideDomainError, match=r"refractive index 12\+0j.*--allow-unvalidated"):
        do.compute_optics(12.0, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0])
    with pytest.raises(OutsideDomainError, match=r"refractive index 1\.005\+0j"):
        do.compute_optics(1.005, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0])
    with pytest.raises(TypeError, match="allow_unvalidated must be True or False"):
        do.compute_optics(
            1.5, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0], allow_unvalidated=1
        )


def test_allowed_outside_warns_and_records_it():
    with pytest.warns(UnvalidatedWarning, match="refractive index 12\\+0.5j"):
        t = do.compute_optics(
            12.0 + 0.5j,
            do.Monodisperse(radius_um=0.5),
            [550.0],
            [0.0, 180.0],
            allow_unvalidated=True,
        )
    record = t.provenance.quadrature["domain"]
    assert (
        record["inside"] is False
        and record["n"] == [12.0, 12.0]
        and record["validated"] == domain_text()
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        inside = do.compute_optics(1.5, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0])
    assert inside.provenance.quadrature["domain"]["inside"] is True


def _outside_config(tmp_path: Path) -> Path:
    path = tmp_path / "dense.toml"
    path.write_text(
        'name = "dense"\ndescription = "an index above the validated domain"\n[material]\nmodel = "constant"\nn = 12.0\nk = 0.01\n'
        '[size_distribution]\nmodel = "modified_gamma"\nr_eff_um = 0.3\nv_eff = 0.1\n'
        '[optics]\nrtol = 1e-2\nwavelengths_nm = [550.0]\nn_theta = 7\n[phase]\nmodel = "mie"\n',
        encoding="utf-8",
    )
    return path


def test_cli_refuses_outside_and_goes_on_with_the_flag(tmp_path, capsys):
    config = _outside_config(tmp_path)
    out = tmp_path / "out"
    assert main(["build", str(config), "--out", str(out), "--format", "netcdf", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "outside the validated domain" in err and "--allow-unvalidated" in err
    assert not out.exists() or not any(out.rglob("*.nc"))
    status = main(
        [
            "build",
            str(config),
            "--out",
            str(out),
            "--format",
            "netcdf",
            "--quiet",
            "--allow-unvalidated",
        ]
    )
    assert status == 0
    assert "outside the validated domain" in capsys.readouterr().err
    (nc,) = out.rglob("*.nc")
    assert main(["info", str(nc)]) == 0
    assert "OUTSIDE the validated domain" in capsys.readouterr().out


def test_readme_and_docs_state_the_domain_from_the_constant():
    """The README's and the accuracy page's generated block hold domain_text() (regenerate
    with scripts/domain_reference.py --docs)."""
    want = domain_summary()
    assert domain_text() in want
    for path in (ROOT / "README.md", ROOT / "docs" / "concepts" / "accuracy.rst"):
        text = path.read_text(encoding="utf-8")
        block = re.search(
            r"validated-domain:begin[^\n]*\n(.*?)\n[^\n]*validated-domain:end", text, re.S
        )
        assert block is not None, path
        assert block.group(1).strip() == want, path
