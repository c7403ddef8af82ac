"""Tests of dustoptics.particles.materials: the interface, each kind, CSV tables.

Materials of the catalogue (dustoptics.particles.catalogue) serve as examples;
the catalogue's own data are checked in test_catalogue.
"""

from __future__ import annotations

import cmath
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dustoptics.particles.catalogue import get_material
from dustoptics.particles.materials import (
    ConstantIndex,
    GasFormulaIndex,
    OrientationAverage,
    TabulatedIndex,
    read_index_csv,
    write_index_csv,
)

VISIBLE_NM = np.arange(360.0, 831.0, 10.0)  # Bruneton's 48 wavelengths


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
# GasFormulaIndex
# ---------------------------------------------------------------------------


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


@pytest.mark.parametrize("special", ["fifo", "/dev/zero"])
def test_read_index_csv_refuses_what_is_not_a_regular_file(tmp_path: Path, special: str) -> None:
    import os

    from dustoptics.io import FormatError

    path = tmp_path / "index.csv"
    if special == "fifo":
        os.mkfifo(path)  # opened for reading, it would block forever
    else:
        path = Path(special)
    with pytest.raises(FormatError, match="not a regular file"):
        read_index_csv(path)
