"""The reference derivatives path (tests/reference/derivatives.py) against
compute_optics tables and their central finite differences, and against scatrs.

Values: against :func:`compute_optics` at its default tolerances (rtol 1e-4 for
the phase matrix relative to F11, 1e-6 for the cross-sections, absolute for g
and ssa): the two must agree within those (C_back within 1e-4: compute_optics
does not refine on it, and its error is that of F11 at 180 deg).

Derivatives: against the central difference (D(h) = (T(p + h) - T(p - h)) / 2h,
one-sided of second order where k = 0 leaves no room below) of compute_optics
tables at rtol 1e-7 (cross-sections 1e-9), step h = 1e-3 max(|p|, 1e-3).  The
tolerance, elementwise, is

    2 |D(h) - D(2h)|                   (six times the truncation error of D(h) where
                                         it is c h^2; at these steps the h^4 terms count
                                         too: up to 1.5 |D(h) - D(2h)| measured)
    + 10 (e(p + h) + e(p - h)) V / 2h  (the tables' error estimates e, times 10
                                         for estimates that are not bounds)
    + the reference's own derivative error estimate V / s_p
    + 1e-9 |dT/dp|,

with V the scale each error is relative to: F11 at the angle for the phase
matrix, the value for the cross-sections, 1 for g and ssa (for ssa, e is twice
the cross-sections' estimate; for C_back the phase function's plus the
cross-sections').
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from reference.derivatives import ANGULAR, optics_derivatives

from dustoptics.particles.custom_sizedist import MultiModal
from dustoptics.particles.sizedist import (
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    PowerLaw,
    SizeDistribution,
    Truncated,
)
from dustoptics.particles.sizedist_derivatives import parameter_value, with_parameter
from dustoptics.scattering.optics import compute_optics
from dustoptics.table import Table

THETA = np.linspace(0.0, 180.0, 19)
WAVELENGTHS = [450.0, 650.0]

CASES: dict[str, tuple[complex, SizeDistribution, str]] = {
    "gamma_absorbing": (1.5 + 0.01j, ModifiedGamma(r_eff_um=0.5, v_eff=0.1), "scattering"),
    # Lossless spheres up to x ~ 15: above, the n derivative's narrow resonances
    # need far more nodes (see the module's Notes).
    "log_normal_lossless": (1.33 + 0.0j, LogNormal(median_radius_um=0.2, sigma=0.3), "scattering"),
    "multimodal": (
        1.52 + 0.01j,
        MultiModal(
            modes=(
                ModifiedLogNormal(r_eff_um=0.1, v_eff=0.1),
                ModifiedLogNormal(r_eff_um=0.6, v_eff=0.2),
            ),
            relative_number_densities=(50.0, 1.0),
        ),
        "scattering",
    ),
    "gamma_number_weighted": (1.5 + 0.01j, ModifiedGamma(r_eff_um=0.4, v_eff=0.2), "number"),
    "power_law": (1.5 + 0.001j, PowerLaw(exponent=3.5, r_min_um=0.05, r_max_um=0.8), "scattering"),
    "truncated_gamma": (
        1.5 + 0.01j,
        Truncated(parent=ModifiedGamma(r_eff_um=0.5, v_eff=0.2), r_min_um=0.0, r_max_um=1.0),
        "scattering",
    ),
}

#: (table field, kind of its error: relative to F11 ("f11"), to the value ("value"), absolute
#: ("one"), or the backscatter's ("back"): compute_optics does not refine on C_back, whose
#: relative error is that of F11(180 deg) (C_back = 4 pi C_sca F11(180 deg)) and C_sca.
FIELDS = (
    ("phase", "f11"),
    ("f12", "f11"),
    ("f33", "f11"),
    ("f34", "f11"),
    ("cext_um2", "value"),
    ("csca_um2", "value"),
    ("cback_um2", "back"),
    ("ssa", "one"),
    ("g", "one"),
)


def _table(
    m: complex,
    distribution: SizeDistribution,
    weighting: str,
    rtol: float = 1e-4,
    cross_section_rtol: float | None = None,
) -> Table:
    return compute_optics(
        m,
        distribution,
        WAVELENGTHS,
        THETA,
        rtol=rtol,
        weighting=weighting,
        cross_section_rtol=cross_section_rtol,
        polarization=True,
        workers=1,
    )


def _field(t: Table, name: str) -> np.ndarray:
    return np.asarray(t.quantity(name), dtype=np.float64)


def _scale(t: Table, name: str, kind: str) -> np.ndarray:
    if kind == "f11":
        return _field(t, "phase")
    if kind in ("value", "back"):
        return np.abs(_field(t, name))
    return np.ones(len(WAVELENGTHS))


def _error(t: Table, kind: str) -> np.ndarray:
    """The table's error estimate for a field of this kind, per wavelength."""
    if kind == "f11":
        return np.asarray(t.quadrature.error_estimate)[:, None]
    if kind == "back":
        return np.asarray(t.quadrature.error_estimate) + np.asarray(
            t.quadrature.cross_section_error_estimate
        )
    # ssa = C_sca / C_ext: twice the cross-sections' relative error.
    return 2.0 * np.asarray(t.quadrature.cross_section_error_estimate)


@pytest.fixture(scope="module")
def references() -> dict[str, object]:
    return {
        key: optics_derivatives(m, d, WAVELENGTHS, THETA, weighting=w, rtol=1e-6)
        for key, (m, d, w) in CASES.items()
    }


@pytest.mark.parametrize("key", CASES)
def test_values_agree_with_compute_optics_at_its_default_tolerance(key: str, references) -> None:
    m, d, w = CASES[key]
    ref = references[key]
    t = _table(m, d, w)
    tolerance = {"f11": 1e-4, "back": 1e-4, "value": 1e-6, "one": 1e-6}
    for name, kind in FIELDS:
        err = np.abs(getattr(ref, name) - _field(t, name))
        assert np.all(err <= tolerance[kind] * _scale(t, name, kind)), (name, np.max(err))


@pytest.mark.parametrize(
    ("key", "parameter"),
    [(key, p) for key in CASES for p in ("n", "k")]
    + [("gamma_absorbing", "r_eff_um"), ("gamma_absorbing", "v_eff")]
    + [("log_normal_lossless", "median_radius_um"), ("log_normal_lossless", "sigma")]
    + [("multimodal", p) for p in ("modes[1].r_eff_um", "modes[0].v_eff")]
    + [("multimodal", "relative_number_densities[0]")]
    + [("gamma_number_weighted", p) for p in ("r_eff_um", "v_eff")]
    + [("power_law", p) for p in ("exponent", "r_min_um", "r_max_um")]
    + [("truncated_gamma", p) for p in ("parent.r_eff_um", "parent.v_eff", "r_max_um")],
)
def test_derivatives_against_finite_differences_of_tables(
    key: str, parameter: str, references
) -> None:
    m, d, w = CASES[key]
    ref = references[key]
    if parameter in ("n", "k"):
        p = m.real if parameter == "n" else m.imag
    else:
        p = parameter_value(d, parameter)
    s_p = max(abs(p), 1e-3)
    h = 1e-3 * s_p
    one_sided = parameter == "k" and m.imag == 0.0

    def table(delta: float) -> Table:
        if parameter == "n":
            return _table(m + delta, d, w, rtol=1e-7, cross_section_rtol=1e-9)
        if parameter == "k":
            return _table(m + 1j * delta, d, w, rtol=1e-7, cross_section_rtol=1e-9)
        return _table(
            m, with_parameter(d, parameter, p + delta), w, rtol=1e-7, cross_section_rtol=1e-9
        )

    steps = (0.0, h, 2.0 * h, 4.0 * h) if one_sided else (-2.0 * h, -h, h, 2.0 * h)
    tables = {delta: table(delta) for delta in steps}
    base = tables[h]

    def difference(step: float, name: str, kind: str) -> tuple[np.ndarray, np.ndarray]:
        """The difference of step ``step`` and its noise bound."""
        if one_sided:
            t0, t1, t2 = tables[0.0], tables[step], tables[2.0 * step]
            value = (-3 * _field(t0, name) + 4 * _field(t1, name) - _field(t2, name)) / (2 * step)
            return value, (3 * _error(t0, kind) + 4 * _error(t1, kind) + _error(t2, kind)) / (
                2 * step
            )
        tp, tm = tables[step], tables[-step]
        value = (_field(tp, name) - _field(tm, name)) / (2 * step)
        return value, (_error(tp, kind) + _error(tm, kind)) / (2 * step)

    for name, kind in FIELDS:
        exact = ref.derivative(name, parameter)
        d_h, noise_h = difference(h, name, kind)
        d_2h, _ = difference(2.0 * h, name, kind)
        scale = _scale(base, name, kind)
        own = ref.derivative_error_estimate[ref.parameters.index(parameter)]
        if kind == "f11":
            own = own[:, None]
        tol = (
            2.0 * np.abs(d_h - d_2h)
            + 10.0 * noise_h * scale
            + own * scale / s_p
            + 1e-9 * np.abs(exact)
        )
        err = np.abs(exact - d_h)
        assert np.all(err <= tol), (name, float(np.max(err / tol)), err, tol)


def test_monodisperse_radius_derivative_is_the_spheres() -> None:
    m = 1.5 + 0.01j
    r0 = 0.7
    ref = optics_derivatives(m, Monodisperse(radius_um=r0), WAVELENGTHS, THETA)
    assert ref.parameters == ("radius_um", "n", "k")
    h = 1e-6  # um: truncation ~ 1e-7 of the derivative, round-off ~ 1e-10
    plus = _table(m, Monodisperse(radius_um=r0 + h), "scattering")
    minus = _table(m, Monodisperse(radius_um=r0 - h), "scattering")
    for name, kind in FIELDS:
        fd = (_field(plus, name) - _field(minus, name)) / (2 * h)
        exact = ref.derivative(name, "radius_um")
        scale = np.max(np.abs(exact), axis=-1, keepdims=True) if kind == "f11" else np.abs(exact)
        assert np.all(np.abs(exact - fd) <= 1e-6 * scale + 1e-12), name


def test_against_scatrs_ensemble_derivatives(references) -> None:
    """scatrs 0.3's closed-form ensemble derivatives (rtol 1e-9): within 1e-7 of
    each quantity's scale (the reference's own tolerance is 1e-6 / 1e-8)."""
    scatrs = pytest.importorskip("scatrs")
    m, d, _ = CASES["gamma_absorbing"]
    ref = references["gamma_absorbing"]
    mu = np.cos(np.deg2rad(THETA))
    size = scatrs.Gamma(d.r_eff_um, d.v_eff)
    result = scatrs.Ensemble(scatrs.Sphere(m), size).compute(
        np.array(WAVELENGTHS) * 1e-3, mu=mu, derivatives=True, rtol=1e-9
    )
    names = {
        "r_eff_um": "effective_radius",
        "v_eff": "effective_variance",
        "n": "m_real",
        "k": "m_imag",
    }
    for ours, theirs in names.items():
        ds = result.d(theirs)
        for name, other in (
            ("cext_um2", ds.c_ext),
            ("csca_um2", ds.c_sca),
            ("cback_um2", ds.c_back),
        ):
            np.testing.assert_allclose(ref.derivative(name, ours), other, rtol=1e-7, err_msg=name)
        np.testing.assert_allclose(ref.derivative("g", ours), ds.g, rtol=0, atol=1e-7)
        np.testing.assert_allclose(ref.derivative("ssa", ours), ds.ssa, rtol=0, atol=1e-7)
        for name in ANGULAR:
            other = getattr(ds.phase, "f11" if name == "phase" else name) / (4.0 * math.pi)
            atol = 1e-7 * np.max(np.abs(ref.derivative("phase", ours)), axis=1, keepdims=True)
            assert np.all(np.abs(ref.derivative(name, ours) - other) <= atol), (ours, name)


def test_errors_name_the_parameter() -> None:
    d = ModifiedGamma(r_eff_um=0.5, v_eff=0.1)
    with pytest.raises(ValueError, match=r"parameters must be one of .*'r_eff_um'.*'n', 'k'"):
        optics_derivatives(1.5, d, [550.0], [0.0], parameters=("sigma",))
    with pytest.raises(ValueError, match="repeat"):
        optics_derivatives(1.5, d, [550.0], [0.0], parameters=("n", "n"))
    with pytest.raises(TypeError, match="sequence of names"):
        optics_derivatives(1.5, d, [550.0], [0.0], parameters="n")
    with pytest.raises(ValueError, match="weighting"):
        optics_derivatives(1.5, d, [550.0], [0.0], weighting="area")
    none = optics_derivatives(1.5 + 0.01j, d, [550.0], [0.0, 90.0], parameters=())
    assert none.parameters == () and none.derivative_error_estimate.shape == (0, 1)
    assert none.phase.shape == (1, 2)
    r = optics_derivatives(1.5 + 0.01j, d, [550.0], [0.0], parameters=("k",))
    with pytest.raises(ValueError, match="parameter must be one of 'k'"):
        r.derivative("g", "n")
    with pytest.raises(ValueError, match="quantity"):
        r.derivative("qext", "k")
