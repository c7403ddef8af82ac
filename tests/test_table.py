"""The one Table: what compute_optics returns, its provenance, repr and interpolation."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import dustoptics as do
from dustoptics.scattering.optics import recompute
from dustoptics.table import (
    CrossSections,
    Expansion,
    QuadratureRecord,
    ScatteringMatrix,
    Table,
    grouped_fields,
)

THETA = np.linspace(0.0, 180.0, 91)
WAVELENGTHS = [440.0, 550.0, 680.0]


@pytest.fixture(scope="module")
def table() -> Table:
    return do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        WAVELENGTHS,
        THETA,
        rtol=1e-3,
        workers=1,
    )


def test_compute_optics_returns_the_table(table: Table) -> None:
    assert type(table) is Table
    assert table.name == "table"
    assert not hasattr(do, "OpticsTable")
    # Every per-wavelength diagnostic is a field of the table.
    assert table.quadrature.n_nodes.dtype == np.int64 and np.all(table.quadrature.n_nodes >= 16)
    assert np.all(table.quadrature.cross_section_n_nodes >= table.quadrature.n_nodes)
    np.testing.assert_array_equal(table.refractive_index, do.mars_dust()(np.array(WAVELENGTHS)))
    assert np.all(table.converged)


def test_provenance_is_filled_from_the_call(table: Table) -> None:
    p = table.provenance
    inputs = p.inputs
    assert inputs["refractive_index"]["description"] == do.mars_dust().name
    np.testing.assert_array_equal(inputs["refractive_index"]["n"], table.refractive_index.real)
    np.testing.assert_array_equal(inputs["refractive_index"]["k"], table.refractive_index.imag)
    assert inputs["size_distribution"]["model"] == "modified_gamma"
    assert inputs["size_distribution"]["parameters"] == {"r_eff_um": 1.6, "v_eff": 0.2}
    assert inputs["wavelength_nm"] == WAVELENGTHS
    assert inputs["theta_deg"] == THETA.tolist()
    assert (inputs["weighting"], inputs["rtol"], inputs["cross_section_rtol"]) == (
        "scattering",
        1e-3,
        1e-5,
    )
    assert inputs["quadrature"]["nodes_per_panel"] == do.QuadratureSettings().nodes_per_panel
    assert [s.role for s in p.sources] == ["refractive index", "size distribution"]
    assert p.sources[0].citation == do.mars_dust().citation
    assert p.quadrature["max_error_estimate"] == table.achieved_error
    assert p.quadrature["n_nodes_total"] == int(table.quadrature.n_nodes.sum())
    assert p.quadrature["converged"] is True
    assert set(p.software) >= {"dustoptics", "numpy", "numba"}
    assert len(p.input_hash) == 64


@pytest.mark.parametrize(
    ("index", "description"),
    [
        (1.5 + 0.01j, "constant m = (1.5+0.01j)"),
        ([1.5 + 0.01j, 1.51 + 0.01j], "per-wavelength values given by the caller"),
        ("hematite-querry1985-ordinary", "hematite-querry1985-ordinary"),
    ],
)
def test_refractive_index_description(index, description) -> None:
    t = do.compute_optics(index, do.Monodisperse(radius_um=0.5), [500.0, 600.0], [0.0, 180.0])
    assert t.provenance.inputs["refractive_index"]["description"] == description


def test_callable_refractive_index_is_described_and_recorded() -> None:
    def dust_index(wavelength_nm: float) -> complex:
        return 1.5 + 1e-5j * wavelength_nm

    t = do.compute_optics(dust_index, do.Monodisperse(radius_um=0.5), [500.0, 600.0], [0.0, 180.0])
    assert t.provenance.inputs["refractive_index"]["description"].endswith("dust_index")
    assert t.provenance.inputs["refractive_index"]["k"] == [0.005, 0.006]
    assert t.provenance.sources[0].citation == "given by the caller (no citation recorded)"


def test_recompute_from_provenance_alone_gives_the_same_bytes(table: Table, tmp_path) -> None:
    again = recompute(table.provenance)
    assert again.equals(table)
    do.io.write_hdf5(table, tmp_path / "a.h5")
    do.io.write_hdf5(again, tmp_path / "b.h5")
    assert (tmp_path / "a.h5").read_bytes() == (tmp_path / "b.h5").read_bytes()


def test_recompute_refuses_a_configuration_provenance() -> None:
    with pytest.raises(ValueError, match="lack .* not recorded by compute_optics"):
        recompute(do.Provenance(inputs={"name": "costa"}))


def test_diagnostics_rebuild_the_nodes(table: Table) -> None:
    d = table.diagnostics
    assert d.distribution == do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    for i, panels in enumerate(d.panels):
        # Each final panel's two halves carry nodes_per_panel nodes each.
        assert 2 * panels.shape[0] * d.settings.nodes_per_panel == table.quadrature.n_nodes[i]
    # Changing the numbers drops the diagnostics of the run that made them.
    assert table.replace(phase=table.phase * 1.0).diagnostics is None
    assert table.replace(name="x").diagnostics is d


def test_repr_is_short_and_says_what_the_table_is(table: Table) -> None:
    text = repr(table)
    assert len(text.splitlines()) <= 6 and len(text) < 600
    assert "3 wavelengths 440-680 nm x 91 angles" in text
    assert "modified_gamma(r_eff_um=1.6, v_eff=0.2)" in text
    assert table.provenance.input_hash[:12] in text


def test_phase_at_scalar_and_array(table: Table) -> None:
    # 44 degree is on the grid (2 degree steps): the stored column, unchanged.
    np.testing.assert_array_equal(table.phase_at(44.0), table.phase[:, 22])
    assert table.phase_at(45.0).shape == (3,)
    # Midway between grid angles: the mean of the neighbours (linear in angle).
    np.testing.assert_allclose(
        table.phase_at(45.0), 0.5 * (table.phase[:, 22] + table.phase[:, 23]), rtol=1e-15
    )
    assert table.phase_at([45.0, 90.0]).shape == (3, 2)
    np.testing.assert_array_equal(table.phase_at(np.array([0.0, 180.0])), table.phase[:, [0, -1]])


@pytest.mark.parametrize("bad", [-1.0, 181.0, [[10.0]], np.nan, "ten"])
def test_phase_at_refuses_bad_angles(table: Table, bad) -> None:
    with pytest.raises(ValueError, match="theta_deg"):
        table.phase_at(bad)


def test_phase_at_does_not_extrapolate_a_partial_grid() -> None:
    t = Table(wavelength_nm=[550.0], theta_deg=[10.0, 20.0], phase=[[1.0, 2.0]], g=[0.1])
    assert not t.spans_sphere
    np.testing.assert_array_equal(t.phase_at(15.0), [1.5])
    with pytest.raises(
        ValueError, match=r"within \[10, 20\] degree, the table's range \(no extrapolation\)"
    ):
        t.phase_at(5.0)


def test_argument_and_attribute_names_agree() -> None:
    t = do.compute_optics(
        1.5 + 0.01j, do.Monodisperse(radius_um=0.5), wavelength_nm=[550.0], theta_deg=[0.0, 180.0]
    )
    np.testing.assert_array_equal(t.wavelength_nm, [550.0])
    with pytest.raises(TypeError, match="wavelengths_nm"):
        do.compute_optics(1.5, do.Monodisperse(radius_um=0.5), wavelengths_nm=[550.0])


def test_progress_reports_every_wavelength_in_order() -> None:
    calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        do.compute_optics(
            1.5 + 0.01j,
            do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1),
            [450.0, 550.0, 650.0],
            [0.0, 180.0],
            rtol=1e-3,
            workers=2,
            progress=lambda done, total: calls.append((done, total)),
        )
    assert calls == [(0, 3), (1, 3), (2, 3), (3, 3)]


def test_derived_quantities_are_derived_from_the_stored_ones(table: Table) -> None:
    np.testing.assert_array_equal(
        table.cabs_um2, table.cross_sections.cext_um2 - table.cross_sections.csca_um2
    )
    np.testing.assert_array_equal(
        table.ssa, table.cross_sections.csca_um2 / table.cross_sections.cext_um2
    )
    np.testing.assert_array_equal(
        table.qext,
        table.cross_sections.cext_um2 / table.cross_sections.mean_geometric_cross_section_um2,
    )
    dense = table.replace(cross_sections={"number_density_per_m3": 1e6})
    np.testing.assert_array_equal(dense.beta_ext_per_m, table.cross_sections.cext_um2 * 1e-12 * 1e6)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"name": ""}, "name must be a non-empty string"),
        ({"quadrature": {"n_nodes": [1.5, 2.0, 3.0]}}, "n_nodes must be 3 positive integers"),
        ({"refractive_index": [1.5 - 0.1j] * 3}, "k >= 0"),
        ({"refractive_index": [1.5]}, r"refractive_index must have shape \(3,\)"),
        ({"theta_deg": np.linspace(-1.0, 180.0, 91)}, r"within \[0, 180\] degree"),
    ],
)
def test_bad_fields_are_refused(table: Table, changes, match) -> None:
    with pytest.raises(ValueError, match=match):
        table.replace(**changes)


# ------------------------------------------------------------------ records (issue 37)


def _phase_only(n: int = 2) -> Table:
    return Table(
        wavelength_nm=[450.0, 550.0, 650.0][:n],
        theta_deg=[0.0, 180.0],
        phase=[[1 / (4 * np.pi)] * 2] * n,
        g=[0.0] * n,
    )


def test_a_computed_table_has_its_records_and_presence_is_not_none(table: Table) -> None:
    assert isinstance(table.cross_sections, CrossSections)
    assert isinstance(table.quadrature, QuadratureRecord)
    assert table.matrix is None and table.expansion is None
    plain = _phase_only()
    assert plain.cross_sections is None and plain.quadrature is None
    assert plain.quantity("cext_um2") is None and plain.quantity("alpha1") is None
    np.testing.assert_array_equal(table.quantity("cext_um2"), table.cross_sections.cext_um2)
    np.testing.assert_array_equal(table.quantity("ssa"), table.ssa)
    with pytest.raises(ValueError, match="quantity must be a stored or derived quantity"):
        table.quantity("albedo")


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (
            lambda: CrossSections(cext_um2=[1.0, 2.0], csca_um2=[1.0]),
            ValueError,
            r"csca_um2 must have shape \(2,\)",
        ),
        (
            lambda: CrossSections(cext_um2=[1.0], csca_um2=[2.0]),
            ValueError,
            "must not exceed cext_um2",
        ),
        (lambda: CrossSections(cext_um2=[0.0], csca_um2=[0.0]), ValueError, "cext_um2 > 0"),
        (
            lambda: CrossSections(cext_um2=[1.0], csca_um2=[1.0], number_density_per_m3=-1.0),
            ValueError,
            "number_density_per_m3",
        ),
        (
            lambda: CrossSections(cext_um2=[[1.0]], csca_um2=[1.0]),
            ValueError,
            "one value per wavelength",
        ),
        (
            lambda: QuadratureRecord(error_estimate=[0.1], n_nodes=[0]),
            ValueError,
            "n_nodes must be 1 positive integers",
        ),
        (
            lambda: QuadratureRecord(error_estimate=[np.nan]),
            ValueError,
            "error_estimate must be finite",
        ),
        (
            lambda: ScatteringMatrix(f12=[[0.0, 0.0]], f33=[[0.0]], f34=[[0.0, 0.0]]),
            ValueError,
            r"f33 must have shape \(1, 2\)",
        ),
        (
            lambda: Expansion(
                alpha1=[[1.0, 0.3]],
                alpha2=[[0.0]],
                alpha3=[[0.0]],
                alpha4=[[0.0]],
                beta1=[[0.0]],
                beta2=[[0.0]],
            ),
            ValueError,
            r"alpha2 must have shape \(1, 2\)",
        ),
        (lambda: CrossSections(cext_um2=[1.0]), TypeError, "csca_um2"),
    ],
)
def test_each_record_checks_itself(make, error, match) -> None:
    with pytest.raises(error, match=match):
        make()


def test_the_table_checks_its_records_against_its_grids() -> None:
    plain = _phase_only(2)
    with pytest.raises(ValueError, match="CrossSections holds 3 wavelengths; the table has 2"):
        plain.replace(cross_sections=CrossSections(cext_um2=[1.0] * 3, csca_um2=[0.5] * 3))
    with pytest.raises(ValueError, match=r"f12, f33 and f34 must have shape .* = \(2, 2\)"):
        plain.replace(
            matrix=ScatteringMatrix(f12=[[0.0] * 3] * 2, f33=[[0.0] * 3] * 2, f34=[[0.0] * 3] * 2)
        )
    with pytest.raises(TypeError, match="expansion must be a Expansion or None; got dict"):
        Table(**{**_fields(plain), "expansion": {"alpha1": [[1.0]]}})


def _fields(t: Table) -> dict:
    return {"wavelength_nm": t.wavelength_nm, "theta_deg": t.theta_deg, "phase": t.phase, "g": t.g}


def test_replace_changes_a_record_or_makes_one_from_a_mapping(table: Table) -> None:
    dense = table.replace(cross_sections={"number_density_per_m3": 1e6})
    assert dense.cross_sections.number_density_per_m3 == 1e6
    np.testing.assert_array_equal(dense.cross_sections.cback_um2, table.cross_sections.cback_um2)
    # The cross-sections themselves did not change: diagnostics and derivatives stay.
    assert dense.diagnostics is table.diagnostics
    plain = _phase_only()
    made = plain.replace(cross_sections={"cext_um2": [2.0, 1.0], "csca_um2": [1.0, 1.0]})
    np.testing.assert_array_equal(made.ssa, [0.5, 1.0])
    with pytest.raises(
        ValueError, match=r"cext_um2, csca_um2 must all be given .* without csca_um2"
    ):
        plain.replace(cross_sections={"cext_um2": [2.0, 1.0]})
    with pytest.raises(ValueError, match="cross_sections must be a CrossSections or a mapping"):
        plain.replace(
            cross_sections={"cext_um2": [2.0, 1.0], "csca_um2": [1.0, 1.0], "g": [0.1, 0.1]}
        )
    assert table.replace(cross_sections=None).derivatives is None


def test_grouped_fields_makes_table_arguments_of_flat_ones() -> None:
    plain = _phase_only()
    flat = {**_fields(plain), "cext_um2": [2.0, 1.0], "csca_um2": [1.0, 1.0], "alpha1": None}
    table = Table(**grouped_fields(flat, error_estimate=[0.1, 0.2], n_nodes=None))
    np.testing.assert_array_equal(table.cross_sections.cext_um2, [2.0, 1.0])
    assert table.quadrature.n_nodes is None and table.expansion is None
    with pytest.raises(ValueError, match="cross_sections given both whole and by their quantities"):
        grouped_fields(flat, cross_sections=table.cross_sections)


def test_grouped_fields_groups_flat_quantities_into_records() -> None:
    flat = {"error_estimate": [0.1], "n_nodes": np.array([4]), "alpha1": [[1.0]], "g": [0.2]}
    with pytest.raises(
        ValueError, match="alpha1, alpha2, alpha3, alpha4, beta1, beta2 must all be given"
    ):
        grouped_fields(flat)
    del flat["alpha1"]
    grouped = grouped_fields(flat)
    assert sorted(grouped) == ["g", "quadrature"] and grouped["g"] == [0.2]
    assert grouped["quadrature"].equals(
        QuadratureRecord(error_estimate=[0.1], n_nodes=np.array([4]))
    )
    assert not grouped["quadrature"].equals(QuadratureRecord(error_estimate=[0.1]))


# ------------------------------------------------------------------ xarray and pandas


def test_to_xarray_names_dimensions_units_and_provenance(table: Table) -> None:
    ds = table.to_xarray()
    assert ds.phase.dims == ("wavelength_nm", "theta_deg")
    assert ds.wavelength_nm.attrs["units"] == "nm" and ds.theta_deg.attrs["units"] == "degree"
    for name, var in ds.variables.items():
        assert var.attrs["units"] and var.attrs["long_name"], name
    assert ds.attrs["Conventions"] == "CF-1.10"
    assert json.loads(ds.attrs["provenance"]) == table.provenance.to_dict()
    np.testing.assert_array_equal(ds.ssa.values, table.ssa)  # derived ones are there to use
    assert ds.n_nodes.dtype == np.int64


def test_xarray_selection_and_interpolation_agree_with_the_table(table: Table) -> None:
    ds = table.to_xarray()
    angles = np.array([0.0, 0.7, 45.0, 133.3, 180.0])
    interpolated = ds.phase.interp(theta_deg=angles).values  # linear in angle, like phase_at
    np.testing.assert_allclose(interpolated, table.phase_at(angles), rtol=1e-14, atol=0)
    np.testing.assert_array_equal(ds.phase.sel(wavelength_nm=550.0).values, table.phase[1])
    # A selection is still a table: the stored quantities at those wavelengths.
    part = Table.from_xarray(ds.isel(wavelength_nm=[0, 2]))
    np.testing.assert_array_equal(part.wavelength_nm, [440.0, 680.0])
    np.testing.assert_array_equal(
        part.cross_sections.cext_um2, table.cross_sections.cext_um2[[0, 2]]
    )
    np.testing.assert_array_equal(part.refractive_index, table.refractive_index[[0, 2]])


def test_xarray_plots_with_labels_from_the_attributes(table: Table) -> None:
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines = table.to_xarray().phase.sel(wavelength_nm=550.0).plot()
    axes = lines[0].axes
    assert "[degree]" in axes.get_xlabel() and "[sr-1]" in axes.get_ylabel()
    plt.close("all")


def test_to_dataframe_has_the_per_wavelength_quantities(table: Table) -> None:
    df = table.to_dataframe()
    assert df.index.name == "wavelength_nm" and df.index.tolist() == WAVELENGTHS
    for column in (
        "g",
        "cext_um2",
        "csca_um2",
        "cabs_um2",
        "ssa",
        "qext",
        "error_estimate",
        "n_nodes",
    ):
        np.testing.assert_array_equal(df[column].to_numpy(), table.quantity(column))
    np.testing.assert_array_equal(
        df["refractive_index_imag"].to_numpy(), table.refractive_index.imag
    )
    assert "beta_ext_per_m" not in df  # no number density, no volume coefficients


def test_from_xarray_refuses_what_is_not_a_table(table: Table) -> None:
    ds = table.to_xarray()
    with pytest.raises(TypeError, match="ds must be an xarray.Dataset"):
        Table.from_xarray(ds.phase)
    with pytest.raises(
        ValueError, match="not a dustoptics table: its dustoptics_schema attribute is None"
    ):
        Table.from_xarray(ds.drop_attrs())
    converted = ds.assign(theta_deg=ds.theta_deg.assign_attrs(units="rad"))
    with pytest.raises(ValueError, match="'theta_deg' must be in 'degree'; its units are 'rad'"):
        Table.from_xarray(converted)
    with pytest.raises(
        ValueError, match=r"variables the table schema .* does not define: \['extra'\]"
    ):
        Table.from_xarray(ds.assign(extra=ds.g * 2))
    with pytest.raises(
        ValueError, match=r"'phase' must have dimensions \('wavelength_nm', 'theta_deg'\)"
    ):
        Table.from_xarray(ds.assign(phase=ds.phase.transpose()))


# ------------------------------------------------- what a table does through modules above it


def test_the_package_registers_the_writer_and_the_fitter() -> None:
    from dustoptics.io.tables.netcdf import SUFFIXES, save_table
    from dustoptics.scattering.fit import fit_table

    assert tuple(do.table.registry._WRITERS) == SUFFIXES
    assert set(do.table.registry._WRITERS.values()) == {save_table}
    assert list(do.table.registry._FITTERS) == [fit_table]


def test_save_and_fit_without_a_registration_are_clear_errors(
    table: Table, tmp_path, monkeypatch
) -> None:
    monkeypatch.setattr(do.table.registry, "_WRITERS", {})
    monkeypatch.setattr(do.table.registry, "_FITTERS", [])
    with pytest.raises(RuntimeError, match="no table file writer is registered; import dustoptics"):
        table.save(tmp_path / "t.nc")
    with pytest.raises(RuntimeError, match="no fitter is registered; import dustoptics"):
        table.fit(model="hg")
    assert list(tmp_path.iterdir()) == []


def test_save_dispatches_on_the_suffix(table: Table, tmp_path, monkeypatch) -> None:
    calls = []

    def writer(t, path, *, overwrite=False):
        calls.append((t, path, overwrite))
        return path

    monkeypatch.setattr(do.table.registry, "_WRITERS", {})
    do.table.register_table_writer((".abc", ".XYZ"), writer)
    do.table.register_table_writer([".abc"], writer)  # the same again changes nothing
    assert table.save(tmp_path / "t") == tmp_path / "t.abc"  # the first suffix is the default
    assert table.save(tmp_path / "u.xyz", overwrite=True) == tmp_path / "u.xyz"
    assert calls == [(table, tmp_path / "t.abc", False), (table, tmp_path / "u.xyz", True)]
    with pytest.raises(
        ValueError, match=r"unknown table file suffix '\.nc'; use one of \.abc, \.xyz"
    ):
        table.save(tmp_path / "t.nc")


@pytest.mark.parametrize(
    ("suffixes", "error", "match"),
    [
        ((".nc",), ValueError, r"'\.nc' is already registered to 'save_table'"),
        (("nc",), ValueError, r"suffixes must be file suffixes like '\.nc'.*got 'nc'"),
        ((".n c",), ValueError, r"got '\.n c'"),
        (".nc", TypeError, "not one string"),
    ],
)
def test_register_table_writer_refuses(suffixes, error, match) -> None:
    before = dict(do.table.registry._WRITERS)
    with pytest.raises(error, match=match):
        do.table.register_table_writer(suffixes, lambda t, p, *, overwrite=False: p)
    assert dict(do.table.registry._WRITERS) == before


def test_register_table_fitter_refuses_a_second_fitter() -> None:
    with pytest.raises(ValueError, match="Table.fit is already served by 'fit_table'"):
        do.table.register_table_fitter(lambda table, **kw: None)
    with pytest.raises(TypeError, match="fitter must be callable"):
        do.table.register_table_fitter("fit")  # type: ignore[arg-type]


def test_pmom_is_alpha1_over_2l_plus_1() -> None:
    t = Table(
        wavelength_nm=[550.0],
        theta_deg=[0.0, 180.0],
        phase=[[0.1, 0.05]],
        g=[0.8],
        expansion=Expansion(**{key: [[1.0, 1.5, 2.5]] for key in do.table.schema.EXPANSION_FIELDS}),
    )
    np.testing.assert_array_equal(t.pmom, [[1.0, 0.5, 0.5]])
    np.testing.assert_array_equal(do.table.alpha1_from_pmom(t.pmom), t.expansion.alpha1)
    assert do.expansion.pmom_from_alpha1 is do.table.pmom_from_alpha1


# ------------------------------------------------------- text files cannot store (issue 29)


def _small(**changes) -> Table:
    fields = {
        "wavelength_nm": [550.0],
        "theta_deg": [0.0, 180.0],
        "phase": [[1 / (4 * np.pi)] * 2],
        "g": [0.0],
    }
    return Table(**{**fields, **changes})


@pytest.mark.parametrize("bad", ["a\x00b", "a\ud800b"], ids=["NUL", "lone surrogate"])
def test_the_constructor_refuses_text_files_cannot_store(bad: str, tmp_path) -> None:
    from dustoptics.table import Provenance, Source

    with pytest.raises(ValueError, match=r"^name must .*(NUL|lone surrogate)"):
        _small(name=bad)
    sources = (Source(name="ok", role="test", citation=bad),)
    with pytest.raises(ValueError, match=r"provenance\.sources\[0\]\.citation must"):
        _small(provenance=Provenance(sources=sources))
    # What is accepted is saved: any other text, escapes and all.
    fine = _small(
        name="n\u00e9\U0001f600", provenance=Provenance(sources=(Source("s", "r", "c\x1b"),))
    )
    assert do.open_table(fine.save(tmp_path / "t.nc")).equals(fine)


def test_provenance_json_nested_too_deeply_is_a_value_error() -> None:
    ds = _small().to_xarray()
    ds.attrs["provenance"] = "[" * 100_000 + "]" * 100_000
    with pytest.raises(ValueError, match="provenance.*nested deeper than 32 levels"):
        Table.from_xarray(ds)
