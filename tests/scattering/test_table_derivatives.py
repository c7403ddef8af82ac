"""compute_optics(derivatives=...): exact derivatives of every output against central
finite differences of compute_optics itself, the file round trip, and the boundary.

Tolerances come from the tables: the derivative's own error estimate, plus the
finite difference's error bound, (E(p + h) + E(p - h)) / (2 h) from the two
tables' error estimates, plus its truncation error, bounded by the change of
the difference from step 2h to step h (Richardson: the O(h^2) term shrinks 4x).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import dustoptics as do
from dustoptics.particles.sizedist import LogNormal, ModifiedGamma, Monodisperse
from dustoptics.particles.sizedist_derivatives import with_parameter
from dustoptics.scattering import table_derivatives as td
from dustoptics.scattering.quadrature import QuadratureSettings, _stretch

THETA = np.linspace(0.0, 180.0, 37)
WL = [450.0, 700.0]


def _table(m: Any, dist: do.SizeDistribution, theta_deg: np.ndarray = THETA, **kw: Any) -> do.Table:
    return do.compute_optics(m, dist, WL, theta_deg, rtol=1e-5, workers=1, **kw)


def _shifted(m: complex, dist: do.SizeDistribution, p: str, h: float, **kw: Any) -> do.Table:
    if p == "n":
        return _table(m + h, dist, **kw)
    if p == "k":
        return _table(m + 1j * h, dist, **kw)
    if p == "radius_um":
        return _table(m, Monodisperse(radius_um=dist.mean_radius_um + h), **kw)
    from dustoptics.particles.sizedist_derivatives import parameter_value

    return _table(m, with_parameter(dist, p, parameter_value(dist, p) + h), **kw)


def _value_error(t: do.Table, q: str) -> np.ndarray:
    """The table's absolute error estimate of quantity q (per wavelength, angle or order)."""
    if q.startswith(("alpha", "beta")):
        # expansion_error_estimate bounds each coefficient's error over (2 l + 1).
        assert (
            t.expansion is not None and t.expansion.expansion_error_estimate is not None
        ) and t.expansion is not None
        orders = np.arange(t.expansion.alpha1.shape[1])
        return t.expansion.expansion_error_estimate[:, None] * (2.0 * orders + 1.0)
    if q in ("phase", "f12", "f33", "f34"):
        assert t.quadrature is not None
        rel = t.quadrature.error_estimate
        if q != "phase" and (t.matrix is not None and t.matrix.matrix_error_estimate is not None):
            rel = np.maximum(rel, t.matrix.matrix_error_estimate)
        return rel[:, None] * t.phase
    assert t.quadrature is not None and t.quadrature.cross_section_error_estimate is not None
    if q == "lidar_ratio_sr":
        # 4 pi C_ext / C_back, C_back = 4 pi C_sca P(180 deg): the relative errors add.
        rel = 2.0 * t.quadrature.cross_section_error_estimate + t.quadrature.error_estimate
        return rel * np.abs(t.lidar_ratio_sr)
    if q in ("g", "ssa"):
        return t.quadrature.cross_section_error_estimate
    return t.quadrature.cross_section_error_estimate * np.abs(t.quantity(q))


def _check_against_differences(
    m: complex,
    dist: do.SizeDistribution,
    steps: dict[str, float],
    quantities: tuple[str, ...],
    **kw: Any,
) -> None:
    t = _table(m, dist, derivatives=tuple(steps), **kw)
    for p, h in steps.items():
        plus, minus = _shifted(m, dist, p, h, **kw), _shifted(m, dist, p, -h, **kw)
        plus2, minus2 = _shifted(m, dist, p, 2 * h, **kw), _shifted(m, dist, p, -2 * h, **kw)
        for q in quantities:
            fd = (plus.quantity(q) - minus.quantity(q)) / (2 * h)
            fd2 = (plus2.quantity(q) - minus2.quantity(q)) / (4 * h)
            exact = t.derivative(q, p)
            err = t.derivative_error_estimate(q, p)
            if exact.ndim == 2:
                err = err[:, None]
            tables = (_value_error(plus, q) + _value_error(minus, q)) / (2 * h)
            tol = 3.0 * (err + tables + np.abs(fd2 - fd) / 3.0) + 1e-10 * np.max(np.abs(exact))
            bad = np.abs(exact - fd) > tol
            assert not bad.any(), (
                f"d{q}/d{p}: exact {exact[bad][:3]}, finite difference {fd[bad][:3]}, "
                f"tolerance {tol[bad][:3]}"
            )


def test_on_many_angles_the_legendre_path_against_finite_differences() -> None:
    """361 angles: the angular sums go through Gauss angles in tiers and Legendre
    polynomials (fewer Gauss angles than output angles), the table's own path."""
    _check_against_differences(
        1.52 + 0.01j,
        ModifiedGamma(r_eff_um=0.4, v_eff=0.15),
        {"r_eff_um": 2e-3, "n": 1e-3, "k": 1e-4},
        ("phase", "f12", "f33", "f34", "g"),
        polarization=True,
        theta_deg=np.linspace(0.0, 180.0, 361),
    )


def test_gamma_absorbing_every_output_against_finite_differences() -> None:
    _check_against_differences(
        1.52 + 0.01j,
        ModifiedGamma(r_eff_um=0.4, v_eff=0.15),
        {"r_eff_um": 2e-3, "v_eff": 2e-3, "n": 1e-3, "k": 1e-4},
        (
            "phase",
            "f12",
            "f33",
            "f34",
            "g",
            "cext_um2",
            "csca_um2",
            "cback_um2",
            "ssa",
            "lidar_ratio_sr",
        ),
        polarization=True,
    )


def test_lidar_ratio_from_its_own_sums_within_the_chain_rules_estimate() -> None:
    """The lidar ratio's derivative is summed with the cross-sections' (stored):
    it agrees with the quotient rule on the table's values within the two
    estimates, its own the tighter (the chain rule's holds both values' errors)."""
    t = _table(1.52 + 0.003j, ModifiedGamma(r_eff_um=0.8, v_eff=0.2), derivatives=("r_eff_um", "n"))
    d = t.derivatives
    assert d is not None and t.cross_sections is not None
    assert "lidar_ratio_sr" in d.values
    assert t.derivative_quantities.count("lidar_ratio_sr") == 1
    for j, p in enumerate(d.parameters):
        chain, chain_error = d._chain_rule("lidar_ratio_sr", j, t.cross_sections)
        own, own_error = (
            t.derivative("lidar_ratio_sr", p),
            t.derivative_error_estimate("lidar_ratio_sr", p),
        )
        assert np.all(np.abs(own - chain) <= chain_error + own_error), p
        assert np.all(own_error < chain_error), p
    # A table whose lidar ratio derivative is not stored (a file written before)
    # derives it by the chain rule, from the dataset and in memory alike.
    ds = t.to_xarray()
    ds["d_lidar_ratio_sr_d_parameter"].attrs["derived_from"] = "derivatives of ... (chain rule)"
    back = do.Table.from_xarray(ds)
    assert back.derivatives is not None and "lidar_ratio_sr" not in back.derivatives.values
    np.testing.assert_array_equal(
        back.derivative("lidar_ratio_sr", "n"),
        d._chain_rule("lidar_ratio_sr", 1, t.cross_sections)[0],
    )


def test_a_truncations_derivative_range_reaches_its_bounds() -> None:
    """The tail bounds leave a sliver below a truncation's bounds (the density
    jumps there); the derivatives' range reaches them exactly."""
    dist = ModifiedGamma(r_eff_um=0.905, v_eff=0.111).truncated(r_min_um=0.2995, r_max_um=1.358)
    settings = QuadratureSettings()
    at = td._At(
        m=1.5 + 0.001j,
        wavelength_nm=450.0,
        distribution=dist,
        settings=settings,
        mu_out=np.array([1.0]),
        index_directions=(),
        dist_parameters=("parent.v_eff",),
        per_particle=False,
        n_q=1,
        n_order=0,
        angular_keys=("phase",),
    )
    lo, hi = dist.radius_bounds_um(
        tail_fraction=settings.tail_fraction * td.DERIVATIVE_TAIL_FACTOR,
        lower_moment=2,
        upper_moment=4,
    )
    assert dist.r_min_um < lo and hi < dist.r_max_um  # the sliver left out
    edges = np.array([_stretch(at.k_um * lo, 1.0), _stretch(at.k_um * hi, 1.0)])
    ends = td._hard_ends(at, edges)
    assert ends[0] == _stretch(at.k_um * dist.r_min_um, 1.0)
    assert ends[-1] == _stretch(at.k_um * dist.r_max_um, 1.0)
    # A bound far beyond the tail bound (more than a panel width) is left alone.
    far = ModifiedGamma(r_eff_um=0.905, v_eff=0.111).truncated(r_min_um=0.0, r_max_um=50.0)
    at_far = td._At(**{**at.__dict__, "distribution": far})
    np.testing.assert_array_equal(td._hard_ends(at_far, edges), edges)


def test_expansion_coefficients_against_finite_differences() -> None:
    """alpha1..alpha4, beta1, beta2 of orders 0..16 (compute_optics(expansion=16))."""
    _check_against_differences(
        1.52 + 0.01j,
        ModifiedGamma(r_eff_um=0.4, v_eff=0.15),
        {"r_eff_um": 2e-3, "k": 1e-4},
        ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2"),
        expansion=16,
    )


def test_lognormal_lossless_small_spheres_against_finite_differences() -> None:
    dist = LogNormal(median_radius_um=0.15, sigma=0.4)
    _check_against_differences(
        1.45 + 0j,
        dist,
        {"median_radius_um": 1e-3, "sigma": 1e-3, "n": 1e-3},
        ("phase", "g", "cext_um2", "csca_um2"),
    )
    t = _table(1.45 + 0j, dist, derivatives=("n", "sigma"))
    # No absorption whatever n or the sizes: ssa = 1 and C_abs = 0 hold exactly.
    assert np.all(t.derivative("ssa", "n") == 0.0)
    assert np.all(t.derivative("cabs_um2", "sigma") == 0.0)


def test_number_weighting_and_monodisperse_radius() -> None:
    _check_against_differences(
        1.5 + 0.005j,
        ModifiedGamma(r_eff_um=0.3, v_eff=0.1),
        {"r_eff_um": 2e-3, "k": 1e-4},
        ("phase", "g", "cext_um2", "csca_um2"),
        weighting="number",
    )
    _check_against_differences(
        1.5 + 0.005j,
        Monodisperse(radius_um=0.4),
        {"radius_um": 1e-4, "n": 1e-4},
        ("phase", "g", "cext_um2", "csca_um2", "cback_um2"),
    )


def test_no_derivatives_gives_the_same_table_bit_for_bit() -> None:
    dist = ModifiedGamma(r_eff_um=0.4, v_eff=0.15)
    plain = _table(1.5 + 0.01j, dist)
    empty = _table(1.5 + 0.01j, dist, derivatives=())
    assert empty.equals(plain) and empty.derivatives is None
    with_d = _table(1.5 + 0.01j, dist, derivatives=("k",))
    for key in ("phase", "g", "cext_um2", "csca_um2", "cback_um2", "error_estimate"):
        assert np.array_equal(with_d.quantity(key), plain.quantity(key)), key
    assert with_d.provenance.inputs["derivatives"] == ["k"]


def test_unknown_parameter_is_refused_before_any_work() -> None:
    calls: list[int] = []
    with pytest.raises(
        ValueError, match=r"unknown parameter 'r_eff'.*'r_eff_um', 'v_eff', 'n', 'k'"
    ):
        do.compute_optics(
            1.5 + 0.01j,
            ModifiedGamma(r_eff_um=0.4, v_eff=0.15),
            WL,
            derivatives=("r_eff",),
            progress=lambda done, total: calls.append(done),
        )
    assert calls == []
    with pytest.raises(TypeError, match="sequence of parameter names"):
        do.compute_optics(1.5, ModifiedGamma(r_eff_um=0.4, v_eff=0.15), WL, derivatives="n")
    with pytest.raises(ValueError, match="repeat"):
        do.compute_optics(1.5, ModifiedGamma(r_eff_um=0.4, v_eff=0.15), WL, derivatives=("n", "n"))


def test_table_derivative_and_xarray_and_file_round_trip(tmp_path: Path) -> None:
    t = _table(1.5 + 0.01j, ModifiedGamma(r_eff_um=0.4, v_eff=0.15), derivatives=("r_eff_um", "k"))
    with pytest.raises(ValueError, match="parameter must be one of 'r_eff_um', 'k'"):
        t.derivative("phase", "v_eff")
    with pytest.raises(ValueError, match="quantity must be one of"):
        t.derivative("qext", "k")
    ds = t.to_xarray()
    assert list(ds["parameter"].values) == ["r_eff_um", "k"]
    d_phase = ds["d_phase_d_parameter"]
    assert d_phase.dims == ("parameter", "wavelength_nm", "theta_deg")
    assert d_phase.attrs["units_by_parameter"] == "sr-1 um-1; sr-1"
    assert ds["d_g_d_parameter"].attrs["units_by_parameter"] == "um-1; 1"
    np.testing.assert_array_equal(d_phase.sel(parameter="k").values, t.derivative("phase", "k"))
    np.testing.assert_array_equal(
        ds["d_ssa_d_parameter_error_estimate"].sel(parameter="r_eff_um").values,
        t.derivative_error_estimate("ssa", "r_eff_um"),
    )
    assert do.Table.from_xarray(ds).equals(t)
    path = t.save(tmp_path / "d.nc")
    back = do.open_table(path)
    assert back.equals(t) and back.derivatives is not None
    np.testing.assert_array_equal(back.derivative("ssa", "k"), t.derivative("ssa", "k"))
    # A table without derivatives writes and reads as before.
    plain = _table(1.5 + 0.01j, ModifiedGamma(r_eff_um=0.4, v_eff=0.15))
    assert do.open_table(plain.save(tmp_path / "p.nc")).derivatives is None
    # Derivatives belong to the numbers they differentiate.
    assert t.replace(phase=t.phase * 1.0).derivatives is None
    assert t.replace(name="other").derivatives is not None


def test_against_the_reference_path_on_its_own_uniform_rule() -> None:
    """The backscatter has no error estimate of its own in the table (the refinement
    watches cext, csca and g), so its derivatives are checked against the reference
    path of tests/reference/derivatives.py, an independent quadrature refined to
    rtol 1e-7 (cross-sections 1e-9)."""
    from reference.derivatives import optics_derivatives

    dist = LogNormal(median_radius_um=0.15, sigma=0.4)
    names = ("median_radius_um", "sigma", "n", "k")
    t = _table(1.5 + 0.002j, dist, derivatives=names)
    ref = optics_derivatives(1.5 + 0.002j, dist, WL, THETA, parameters=names, rtol=1e-7)
    for p in names:
        for q in ("phase", "g", "cext_um2", "csca_um2", "cback_um2"):
            exact, other = t.derivative(q, p), ref.derivative(q, p)
            err = t.derivative_error_estimate(q, p)
            scale = np.abs(other) if exact.ndim == 1 else np.max(np.abs(other), axis=-1)
            # Reference: its derivative estimate (relative to s_p = max(|p|, 1e-3)) is
            # below 1e-7 of the values; 1e-6 of the derivative's size covers it.
            tol = 3.0 * err + 1e-6 * scale
            if q == "cback_um2":
                # C_back = 4 pi C_sca F11(180 deg): the table refines it no better
                # than the phase function, to its error estimate relative to F11.
                assert t.quadrature is not None
                tol = tol + 3.0 * t.quadrature.error_estimate * scale
            if exact.ndim == 2:
                tol = tol[:, None]
            assert np.all(np.abs(exact - other) <= tol), (q, p, np.max(np.abs(exact - other)))


@pytest.mark.parametrize("rule", ["maxwell_garnett", "bruggeman"])
def test_through_the_mixing_rules_against_finite_differences(rule: str) -> None:
    """d/d(hematite fraction) and d/d(host n) of Mars dust (3 % hematite in n = 1.5)
    by the chain rule, against central differences of compute_optics on mars_dust."""
    dist = ModifiedGamma(r_eff_um=0.3, v_eff=0.1)
    names = ("hematite_fraction", "host_n", "host_k")
    t = do.compute_optics(
        do.mars_dust(rule=rule), dist, WL, THETA, rtol=1e-5, workers=1, derivatives=names
    )
    assert t.derivatives is not None and t.derivatives.parameter_units == ("1", "1", "1")
    for p, h in (("hematite_fraction", 1e-3), ("host_n", 1e-3), ("host_k", 1e-4)):

        def at(step: float, p: str = p) -> do.Table:
            if p == "hematite_fraction":
                mix = do.mars_dust(rule=rule, hematite_fraction=0.03 + step)
            else:
                dm = step if p == "host_n" else 1j * step
                mix = do.mars_dust(rule=rule, host_index=1.5 + 0.001j + dm)
            return do.compute_optics(mix, dist, WL, THETA, rtol=1e-5, workers=1)

        if p != "hematite_fraction":
            # host_n, host_k at a slightly absorbing host (k = 0 is the edge of k >= 0).
            t = do.compute_optics(
                do.mars_dust(rule=rule, host_index=1.5 + 0.001j),
                dist,
                WL,
                THETA,
                rtol=1e-5,
                workers=1,
                derivatives=names,
            )
        plus, minus, plus2, minus2 = at(h), at(-h), at(2 * h), at(-2 * h)
        for q in ("phase", "g", "cext_um2", "csca_um2", "ssa"):
            fd = (plus.quantity(q) - minus.quantity(q)) / (2 * h)
            fd2 = (plus2.quantity(q) - minus2.quantity(q)) / (4 * h)
            exact = t.derivative(q, p)
            err = t.derivative_error_estimate(q, p)
            if exact.ndim == 2:
                err = err[:, None]
            tables = (_value_error(plus, q) + _value_error(minus, q)) / (2 * h)
            tol = 3.0 * (err + tables + np.abs(fd2 - fd) / 3.0) + 1e-10 * np.max(np.abs(exact))
            assert np.all(np.abs(exact - fd) <= tol), (rule, p, q, np.max(np.abs(exact - fd)))


def test_recompute_gives_the_derivatives_again() -> None:
    from dustoptics.scattering.optics import recompute

    t = _table(1.5 + 0.01j, ModifiedGamma(r_eff_um=0.4, v_eff=0.15), derivatives=("v_eff", "k"))
    assert recompute(t.provenance, workers=1).equals(t)
    mixed = _table(
        do.mars_dust(), ModifiedGamma(r_eff_um=0.4, v_eff=0.15), derivatives=("hematite_fraction",)
    )
    with pytest.raises(ValueError, match="unknown parameter 'hematite_fraction'"):
        recompute(mixed.provenance)


def test_bimodal_mixture_and_threads() -> None:
    """A mixture of two modes: a mode's radius and a relative number density; the
    result does not depend on the number of threads."""
    from dustoptics.particles.custom_sizedist import MultiModal

    dist = MultiModal(
        modes=(ModifiedGamma(r_eff_um=0.2, v_eff=0.1), ModifiedGamma(r_eff_um=0.6, v_eff=0.1)),
        relative_number_densities=(10.0, 1.0),
    )
    _check_against_differences(
        1.5 + 0.005j,
        dist,
        {"modes[1].r_eff_um": 2e-3, "relative_number_densities[0]": 1e-2},
        ("phase", "g", "cext_um2", "csca_um2"),
    )
    names = ("modes[0].v_eff", "k")
    one = do.compute_optics(1.5 + 0.005j, dist, WL, THETA, workers=1, derivatives=names)
    two = do.compute_optics(1.5 + 0.005j, dist, WL, THETA, workers=2, derivatives=names)
    assert one.equals(two)
    assert one.derivatives is not None and one.derivatives.parameter_units == ("1", "1")


def test_size_derivatives_agree_whatever_index_ones_are_asked_with_them() -> None:
    """Without a parameter of the refractive index the angular m derivatives are not
    summed (half a sphere's work), and the derivatives' own refinement follows
    only the derivatives asked for: the distribution's derivatives agree with
    those computed along with n and k within the two error estimates."""
    dist = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    kw = {"rtol": 1e-4, "workers": 1, "polarization": True, "expansion": 16}
    size = do.compute_optics(
        1.52 + 0.004j, dist, WL, THETA, derivatives=("r_eff_um", "v_eff"), **kw
    )
    both = do.compute_optics(
        1.52 + 0.004j, dist, WL, THETA, derivatives=("n", "r_eff_um", "k", "v_eff"), **kw
    )
    assert size.derivatives is not None and both.derivatives is not None
    for q in size.derivatives.values:
        for p in ("r_eff_um", "v_eff"):
            a, b = size.derivative(q, p), both.derivative(q, p)
            bound = size.derivative_error_estimate(q, p) + both.derivative_error_estimate(q, p)
            diff = np.abs(a - b).reshape(a.shape[0], -1).max(axis=1)
            assert np.all(diff <= bound), (q, p, diff, bound)


@pytest.mark.parametrize("names", [("radius_um",), ("k",), ("n", "radius_um")])
def test_monodisperse_any_subset_with_its_series_truncation_error(names: tuple[str, ...]) -> None:
    """A single sphere's derivatives for any subset of its parameters are the same
    as with all of them, and their estimate is the series' truncation error: above
    0, and at least the change when the series is summed with ten more terms."""
    from dustoptics.scattering import table_derivatives as td

    sphere = Monodisperse(radius_um=0.7)
    every = do.compute_optics(
        1.5 + 0.01j, sphere, [550.0], THETA, derivatives=("radius_um", "n", "k")
    )
    some = do.compute_optics(1.5 + 0.01j, sphere, [550.0], THETA, derivatives=names)
    for p in names:
        for q in ("phase", "g", "cext_um2", "csca_um2", "cback_um2"):
            assert np.array_equal(some.derivative(q, p), every.derivative(q, p)), (p, q)
            assert np.all(some.derivative_error_estimate(q, p) > 0.0), (p, q)
    # The estimate covers the longer series' change (computed here at 20 more terms).
    assert some.diagnostics is not None
    at = td._At(
        m=1.5 + 0.01j,
        wavelength_nm=550.0,
        distribution=sphere,
        settings=some.diagnostics.settings,
        mu_out=np.cos(np.deg2rad(THETA)),
        index_directions=[1j] if "k" in names else ([1.0 + 0j] if "n" in names else []),
        dist_parameters=(),
        per_particle=False,
        n_q=1,
        n_order=0,
        angular_keys=("phase",),
    )
    with_radius = "radius_um" in names
    short, _ = td._monodisperse_derivatives(at, with_radius=with_radius, extra_terms=0)
    long, _ = td._monodisperse_derivatives(at, with_radius=with_radius, extra_terms=20)
    order = (["radius_um"] if with_radius else []) + [p for p in names if p != "radius_um"]
    for j, p in enumerate(order):
        change = np.max(np.abs(long[j, 0] - short[j, 0]))
        assert change <= some.derivative_error_estimate("phase", p)[0], p
