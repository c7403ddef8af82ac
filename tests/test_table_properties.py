"""Property tests: any valid table survives xarray and every file suffix to the bit.

Kept apart from the example tests (tests/test_table.py, tests/io/test_netcdf.py),
as xarray keeps its own.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dustoptics.io import open_table
from dustoptics.io.tables.netcdf import SUFFIXES
from dustoptics.scattering.tabulated_phase import renormalize
from dustoptics.table import CrossSections, Provenance, QuadratureRecord, Source, Table

_positive = st.floats(1e-3, 1e3, allow_nan=False, allow_infinity=False)
_json_value = st.one_of(
    st.integers(-(2**53), 2**53),
    st.floats(allow_nan=False, allow_infinity=False),
    st.text(max_size=12),
)
#: Text a table accepts in its sources: anything but NUL and lone surrogates, which files
#: cannot store (the constructor refuses them; tests/test_table.py).
_storable = st.characters(exclude_categories=("Cs",), exclude_characters="\x00")


@st.composite
def tables(draw) -> Table:
    n_wl = draw(st.integers(1, 4))
    wavelengths = sorted(draw(st.sets(st.floats(100.0, 5000.0), min_size=n_wl, max_size=n_wl)))
    interior = sorted(draw(st.sets(st.floats(0.5, 179.5), min_size=1, max_size=30)))
    theta = np.array([0.0, *interior, 180.0])
    raw = np.array(
        draw(st.lists(_positive, min_size=n_wl * theta.size, max_size=n_wl * theta.size))
    )
    phase = renormalize(raw.reshape(n_wl, theta.size), theta_deg=theta)
    per_wavelength = st.lists(st.floats(-1.0, 1.0), min_size=n_wl, max_size=n_wl)
    fields: dict = {
        "name": draw(st.from_regex(r"[A-Za-z0-9][A-Za-z0-9._-]{0,15}", fullmatch=True)),
        "wavelength_nm": wavelengths,
        "theta_deg": theta,
        "phase": phase,
        "g": draw(per_wavelength),
    }
    if draw(st.booleans()):
        cext = np.array(draw(st.lists(_positive, min_size=n_wl, max_size=n_wl)))
        ssa = np.array(draw(st.lists(st.floats(0.0, 1.0), min_size=n_wl, max_size=n_wl)))
        scalars = {}
        if draw(st.booleans()):
            scalars["mean_geometric_cross_section_um2"] = draw(_positive)
        if draw(st.booleans()):
            scalars["number_density_per_m3"] = draw(st.floats(1.0, 1e25))
        fields["cross_sections"] = CrossSections(
            cext_um2=cext, csca_um2=np.minimum(cext * ssa, cext), **scalars
        )
    if draw(st.booleans()):
        errors = st.lists(st.floats(0.0, 0.1), min_size=n_wl, max_size=n_wl)
        counts = st.lists(st.integers(1, 10**6), min_size=n_wl, max_size=n_wl)
        fields["quadrature"] = QuadratureRecord(
            error_estimate=draw(errors),
            cross_section_error_estimate=draw(errors),
            n_nodes=np.array(draw(counts), dtype=np.int64),
            cross_section_n_nodes=np.array(draw(counts), dtype=np.int64),
        )
    if draw(st.booleans()):
        n = np.array(draw(st.lists(st.floats(0.1, 5.0), min_size=n_wl, max_size=n_wl)))
        k = np.array(draw(st.lists(st.floats(0.0, 10.0), min_size=n_wl, max_size=n_wl)))
        fields["refractive_index"] = n + 1j * k
    fields["provenance"] = Provenance(
        inputs=draw(st.dictionaries(st.text(max_size=8), _json_value, max_size=4)),
        sources=tuple(
            Source(name=a, role="test", citation=b)
            for a, b in draw(
                st.lists(
                    st.tuples(st.text(_storable, max_size=8), st.text(_storable, max_size=20)),
                    max_size=2,
                )
            )
        ),
        notes=tuple(draw(st.lists(st.text(max_size=20), max_size=2))),
    )
    return Table(**fields)


@settings(max_examples=60, deadline=None)
@given(table=tables())
def test_xarray_round_trip_is_exact(table: Table) -> None:
    back = Table.from_xarray(table.to_xarray())
    assert back.equals(table)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tables(), suffix=st.sampled_from(SUFFIXES))
def test_file_round_trip_is_exact_and_reproducible(table: Table, suffix: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = table.save(Path(tmp) / f"t{suffix}")
        assert open_table(path).equals(table)
        assert table.save(Path(tmp) / f"again{suffix}").read_bytes() == path.read_bytes()
