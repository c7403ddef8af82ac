"""Tests for dustoptics.scattering.phase.

Normalization and mean cosines are checked with quadratures that share no code
with the module: composite Gauss-Legendre over ``mu`` (numpy's ``leggauss``)
on sub-intervals that shrink geometrically towards ``mu = +-1``, where the
Henyey-Greenstein lobes peak, and ``scipy.integrate.quad`` for spot checks.
The closed forms of the mean cosines are therefore tested against numbers, not
against their own derivation.  The operations on tables are tested in
test_tabulated_phase.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

from dustoptics.scattering import phase
from dustoptics.scattering.phase import (
    ANALYTIC_MODEL_ALIASES,
    ANALYTIC_MODELS,
    COLLIENNE2013_MARS,
    COSTA2021_MARS_DHG_CODE,
    COSTA2021_MARS_DHG_PAPER,
    DHG_CONVENTIONS,
    MEYRAN2022_G1_COEFFICIENTS,
    PENNDORF1957_SPHERE_INTEGRAL,
    DHGSpectrum,
    ExtrapolationWarning,
    cornette_shanks1992,
    cornette_shanks1992_asymmetry,
    costa2021_mars_dhg,
    dhg_costa2021,
    dhg_costa2021_asymmetry,
    dhg_kobe2026,
    dhg_kobe2026_asymmetry,
    double_henyey_greenstein,
    double_henyey_greenstein_asymmetry,
    draine2003,
    draine2003_asymmetry,
    get_analytic_model,
    henyey_greenstein,
    henyey_greenstein_asymmetry,
    hg_draine_jendersie_deon2023,
    jendersie_deon2023_parameters,
    rayleigh,
    rayleigh_depolarized,
    rayleigh_penndorf1957,
    register_analytic_model,
    two_term_hg_hapke2012,
    two_term_hg_hapke2012_asymmetry,
)

FOUR_PI = 4.0 * math.pi
FAST = settings(max_examples=25, deadline=None)

# ------------------------------------------------------------------ reference

_GL_X, _GL_W = np.polynomial.legendre.leggauss(64)
_EDGES = np.array(
    [-1.0]
    + [-1.0 + 10.0**-k for k in range(7, 0, -1)]
    + [0.0]
    + [1.0 - 10.0**-k for k in range(1, 8)]
    + [1.0]
)
_A, _B = _EDGES[:-1, None], _EDGES[1:, None]
MU_NODES = (0.5 * (_B - _A) * _GL_X + 0.5 * (_B + _A)).ravel()
MU_WEIGHTS = (0.5 * (_B - _A) * _GL_W).ravel()


def sphere_moment(values_at_nodes: np.ndarray, k: int = 0) -> float:
    """``2 pi int P mu^k dmu`` from values of P at MU_NODES (composite Gauss-Legendre)."""
    return float(2.0 * math.pi * np.sum(MU_WEIGHTS * MU_NODES**k * values_at_nodes))


def sphere_quad(func, k: int = 0) -> float:
    """``2 pi int P mu^k dmu`` with scipy's adaptive quad, split where lobes peak."""
    total = 0.0
    for a, b in itertools.pairwise(_EDGES):
        total += integrate.quad(
            lambda m: func(m) * m**k, a, b, epsabs=1e-15, epsrel=1e-13, limit=200
        )[0]
    return 2.0 * math.pi * total


# ------------------------------------------------------------ strategies

g_st = st.floats(-0.95, 0.95)
weight_st = st.floats(0.0, 1.0)
alpha_st = st.floats(-1.0, 50.0)

MODEL_PARAMS = {
    "rayleigh": st.fixed_dictionaries({}),
    "rayleigh_depolarized": st.fixed_dictionaries({"depolarization": st.floats(0.0, 6.0 / 7.0)}),
    "henyey_greenstein": st.fixed_dictionaries({"g": g_st}),
    "dhg_costa2021": st.fixed_dictionaries({"g1": g_st, "g2": g_st, "alpha": weight_st}),
    "dhg_kobe2026": st.fixed_dictionaries({"g1": g_st, "g2": g_st, "f": weight_st}),
    "cornette_shanks1992": st.fixed_dictionaries({"g": g_st}),
    "draine2003": st.fixed_dictionaries({"g": g_st, "alpha": alpha_st}),
    "hg_draine_jendersie_deon2023": st.fixed_dictionaries(
        {"g_hg": g_st, "g_d": g_st, "alpha": alpha_st, "w_d": weight_st}
    ),
    "two_term_hg_hapke2012": st.fixed_dictionaries({"b": g_st, "c": st.floats(-1.0, 1.0)}),
}
NORMALIZED = sorted(MODEL_PARAMS)


def test_registry_covers_every_model() -> None:
    assert set(ANALYTIC_MODELS) == set(MODEL_PARAMS) | {"rayleigh_penndorf1957"}
    for name, model in ANALYTIC_MODELS.items():
        assert get_analytic_model(name) is model
        assert model.name == name and model.citation and model.formula
        for alias in model.aliases:
            assert get_analytic_model(alias) is model


def test_hyphenated_spellings_are_aliases_of_the_registry_names() -> None:
    assert get_analytic_model("dhg-costa2021") is ANALYTIC_MODELS["dhg_costa2021"]
    assert get_analytic_model("cs") is ANALYTIC_MODELS["cornette_shanks1992"]
    assert ANALYTIC_MODEL_ALIASES["two-term-hg-hapke2012"] == "two_term_hg_hapke2012"
    # Every underscore name that has a hyphenated spelling accepts it.
    for name in ANALYTIC_MODELS:
        if "_" in name:
            assert get_analytic_model(name.replace("_", "-")).name == name


def test_two_term_hg_is_the_costa_dhg_with_opposite_lobes() -> None:
    """Hapke's two-term HG (1 - c)/2 HG(b) + (1 + c)/2 HG(-b) written out by hand."""
    mu = np.linspace(-1.0, 1.0, 41)
    b, c = 0.4, 0.3

    def hg(g: float) -> np.ndarray:
        return (1 - g * g) / (1 + g * g - 2 * g * mu) ** 1.5 / FOUR_PI

    expected = 0.5 * (1 - c) * hg(b) + 0.5 * (1 + c) * hg(-b)
    np.testing.assert_allclose(two_term_hg_hapke2012(mu, b=b, c=c), expected, rtol=1e-13)
    assert two_term_hg_hapke2012_asymmetry(b=b, c=c) == pytest.approx(-c * b, rel=1e-15)
    with pytest.raises(ValueError, match="c must be in the closed interval"):
        two_term_hg_hapke2012(mu, b=b, c=1.5)


def test_reference_quadrature_is_accurate() -> None:
    """The composite Gauss-Legendre agrees with adaptive quad on a sharp lobe."""
    for g in (0.99, -0.99, 0.95, 0.3):

        def f(m, g=g):
            return (1 - g * g) / (1 + g * g - 2 * g * m) ** 1.5 / FOUR_PI

        assert sphere_moment(f(MU_NODES)) == pytest.approx(sphere_quad(f), abs=1e-12)
        assert sphere_moment(f(MU_NODES), 1) == pytest.approx(g, abs=1e-12)


# -------------------------------------------------- normalization, mean cosine


@pytest.mark.parametrize("name", NORMALIZED)
@FAST
@given(data=st.data())
def test_normalized_and_mean_cosine(name: str, data: st.DataObject) -> None:
    model = ANALYTIC_MODELS[name]
    params = data.draw(MODEL_PARAMS[name])
    values = model.phase(MU_NODES, **params)
    assert np.all(values >= 0.0)
    assert sphere_moment(values) == pytest.approx(1.0, abs=1e-9)
    assert sphere_moment(values, 1) == pytest.approx(model.asymmetry(**params), abs=1e-9)


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("henyey_greenstein", {"g": 0.99}),
        ("henyey_greenstein", {"g": -0.98}),
        ("cornette_shanks1992", {"g": 0.99}),
        ("draine2003", {"g": 0.9, "alpha": 250.0}),
        ("dhg_costa2021", {"g1": 0.67, "g2": 0.094, "alpha": 0.743}),
        ("hg_draine_jendersie_deon2023", {"g_hg": 0.995, "g_d": 0.6, "alpha": 27.0, "w_d": 0.5}),
        ("rayleigh_depolarized", {"depolarization": 6.0 / 7.0}),
    ],
)
def test_normalized_by_adaptive_quad(name: str, params: dict) -> None:
    model = ANALYTIC_MODELS[name]

    def f(m):
        return model.phase(m, **params)

    assert sphere_quad(f) == pytest.approx(1.0, abs=1e-9)
    assert sphere_quad(f, 1) == pytest.approx(model.asymmetry(**params), abs=1e-9)


def test_penndorf_as_printed_is_not_normalized() -> None:
    integral = sphere_quad(rayleigh_penndorf1957)
    assert integral == pytest.approx(0.7629 * (1 + 0.932 / 3), abs=1e-13)
    assert pytest.approx(integral, abs=1e-13) == PENNDORF1957_SPHERE_INTEGRAL
    assert 1.0 - integral == pytest.approx(9.24e-5, abs=1e-7)
    assert sphere_quad(rayleigh_penndorf1957, 1) == pytest.approx(0.0, abs=1e-15)


def test_penndorf_is_rounded_depolarized_rayleigh() -> None:
    mu = np.linspace(-1, 1, 41)
    np.testing.assert_allclose(
        rayleigh_penndorf1957(mu), rayleigh_depolarized(mu, depolarization=0.035), rtol=3e-4
    )


# ----------------------------------------------------------- hand values


def test_henyey_greenstein_hand_values() -> None:
    # (1 - 0.25) / (1 + 0.25 - 1)^1.5 = 0.75 / 0.125 = 6
    assert henyey_greenstein(1.0, g=0.5) == pytest.approx(6.0 / FOUR_PI, rel=1e-15)
    # backward: 0.75 / 1.5^3 = 2/9
    assert henyey_greenstein(-1.0, g=0.5) == pytest.approx((2.0 / 9.0) / FOUR_PI, rel=1e-15)
    assert henyey_greenstein(0.0, g=0.5) == pytest.approx(0.75 / 1.25**1.5 / FOUR_PI, rel=1e-15)
    assert henyey_greenstein(0.3, g=0.0) == pytest.approx(1.0 / FOUR_PI, rel=1e-15)
    assert henyey_greenstein_asymmetry(g=0.3) == 0.3


def test_dhg_hand_values() -> None:
    # alpha HG(g1 = 0.5) + (1 - alpha) HG(g2 = -0.5) at mu = 1: 6 and 2/9 (times 1/(4 pi))
    expected = (0.25 * 6.0 + 0.75 * 2.0 / 9.0) / FOUR_PI
    assert dhg_costa2021(1.0, g1=0.5, g2=-0.5, alpha=0.25) == pytest.approx(expected, rel=1e-15)
    assert dhg_kobe2026(1.0, g1=0.5, g2=-0.5, f=0.75) == pytest.approx(expected, rel=1e-15)
    assert dhg_costa2021_asymmetry(g1=0.5, g2=-0.5, alpha=0.25) == pytest.approx(-0.25)


def test_cornette_shanks_hand_value() -> None:
    # g = 0.5, mu = 0: 3 * 0.75 / (2 * 2.25) / 1.25^1.5
    assert cornette_shanks1992(0.0, g=0.5) == pytest.approx(0.5 / 1.25**1.5 / FOUR_PI, rel=1e-15)
    assert cornette_shanks1992_asymmetry(g=0.5) == pytest.approx(3 * 0.5 * 4.25 / (5 * 2.25))


def test_cornette_shanks_rounds_as_tables_and_fits_always_have() -> None:
    """The checked function and the registry's kernel (what fits evaluate) each keep the
    order of operations their outputs were made with: tables and fits stay the same to the
    last bit, though the two differ there (at g = 0.8, at about a third of the angles)."""
    mu = np.cos(np.deg2rad(np.linspace(0.0, 180.0, 1801)))
    g = 0.8
    d = (1.0 - g) ** 2 + 2.0 * g * (1.0 - mu)
    hg = (1.0 - g) * (1.0 + g) / (d * np.sqrt(d)) / FOUR_PI
    table_order = 1.5 / (2.0 + g * g) * (1.0 + mu * mu) * hg
    fit_order = 1.5 * (1.0 + mu * mu) / (2.0 + g * g) * hg
    np.testing.assert_array_equal(cornette_shanks1992(mu, g=g), table_order)
    kernel = ANALYTIC_MODELS["cornette_shanks1992"].kernel
    assert kernel is not None
    np.testing.assert_array_equal(kernel(mu, np.float64(g)), fit_order)
    assert np.count_nonzero(table_order != fit_order) > 100


def test_draine_hand_value() -> None:
    # HG(0.5, mu=1) = 6 / (4 pi); (1 + 1) / (1 + (1 + 0.5) / 3) = 4/3
    assert draine2003(1.0, g=0.5, alpha=1.0) == pytest.approx(8.0 / FOUR_PI, rel=1e-15)


# -------------------------------------------------------------- limits


def test_cornette_shanks_is_rayleigh_at_g0() -> None:
    mu = np.linspace(-1, 1, 101)
    np.testing.assert_allclose(cornette_shanks1992(mu, g=0.0), rayleigh(mu), rtol=1e-15)
    assert cornette_shanks1992_asymmetry(g=0.0) == 0.0
    # and tends to it continuously
    np.testing.assert_allclose(cornette_shanks1992(mu, g=1e-6), rayleigh(mu), rtol=1e-5)


def test_draine_limits() -> None:
    mu = np.linspace(-1, 1, 101)
    for g in (-0.7, 0.0, 0.4, 0.9):
        np.testing.assert_allclose(
            draine2003(mu, g=g, alpha=0.0), henyey_greenstein(mu, g=g), rtol=1e-15
        )
        assert draine2003_asymmetry(g=g, alpha=0.0) == pytest.approx(g, abs=1e-15)
    np.testing.assert_allclose(draine2003(mu, g=0.0, alpha=1.0), rayleigh(mu), rtol=1e-15)


def test_depolarized_rayleigh_limits() -> None:
    mu = np.linspace(-1, 1, 101)
    np.testing.assert_allclose(
        rayleigh_depolarized(mu, depolarization=0.0), rayleigh(mu), rtol=1e-15
    )
    assert rayleigh(1.0) == pytest.approx(3.0 / (8.0 * math.pi))


@FAST
@given(g1=g_st, g2=g_st, f=weight_st)
def test_dhg_conventions_map_onto_each_other(g1: float, g2: float, f: float) -> None:
    mu = np.linspace(-1, 1, 33)
    kobe = dhg_kobe2026(mu, g1=g1, g2=g2, f=f)
    # 1 - (1 - f) differs from f by rounding: compare on the scale of the largest value
    costa = dhg_costa2021(mu, g1=g1, g2=g2, alpha=1.0 - f)
    np.testing.assert_allclose(kobe, costa, rtol=1e-13, atol=1e-14 * float(kobe.max()))
    np.testing.assert_allclose(
        kobe, double_henyey_greenstein(mu, g1=g1, g2=g2, f=f, convention="kobe2026"), rtol=0
    )
    np.testing.assert_allclose(
        double_henyey_greenstein(mu, g1=g1, g2=g2, alpha=1.0 - f),
        dhg_costa2021(mu, g1=g1, g2=g2, alpha=1.0 - f),
        rtol=0,
    )
    assert dhg_kobe2026_asymmetry(g1=g1, g2=g2, f=f) == pytest.approx(
        double_henyey_greenstein_asymmetry(g1=g1, g2=g2, alpha=1.0 - f), abs=1e-15
    )


# ---------------------------------------------------------- broadcasting


def test_broadcast_over_wavelength_and_angle() -> None:
    mu = np.linspace(-1, 1, 7)
    g = np.array([[0.1], [0.5], [0.8]])
    table = henyey_greenstein(mu, g=g)
    assert table.shape == (3, 7)
    for i in range(3):
        np.testing.assert_array_equal(table[i], henyey_greenstein(mu, g=float(g[i, 0])))
    dhg = dhg_costa2021(mu, g1=g, g2=0.094, alpha=np.array([[0.7], [0.8], [0.9]]))
    assert dhg.shape == (3, 7)
    assert np.shape(henyey_greenstein_asymmetry(g=g)) == (3, 1)


def test_scalar_in_float_out() -> None:
    for name, model in ANALYTIC_MODELS.items():
        params = dict.fromkeys(model.parameters, 0.3)
        assert isinstance(model.phase(0.2, **params), float), name


def test_broadcast_mismatch_names_shapes() -> None:
    with pytest.raises(ValueError, match=r"mu \(4,\).*g \(3,\)"):
        henyey_greenstein(np.zeros(4), g=np.zeros(3))


# ----------------------------------------------------------- bad input


@pytest.mark.parametrize("bad", [1.0, -1.0, 1.5, math.nan, math.inf])
def test_g_out_of_range(bad: float) -> None:
    with pytest.raises(ValueError, match=r"g must be .*\(-1\.0, 1\.0\)|g must be a finite"):
        henyey_greenstein(0.5, g=bad)
    with pytest.raises(ValueError, match="g"):
        cornette_shanks1992(0.5, g=bad)


def test_g_error_names_value_and_range() -> None:
    with pytest.raises(
        ValueError, match=r"g must be in the open interval \(-1\.0, 1\.0\); got 1\.0"
    ):
        henyey_greenstein(0.0, g=1.0)
    with pytest.raises(ValueError, match=r"g1 must .*out of range: \[1\.2\]"):
        dhg_costa2021(0.0, g1=[0.5, 1.2], g2=0.1, alpha=0.5)
    with pytest.raises(ValueError, match="g_hg"):
        hg_draine_jendersie_deon2023(0.0, g_hg=-1.0, g_d=0.5, alpha=1.0, w_d=0.5)


@pytest.mark.parametrize("bad", [-0.1, 1.1, math.nan])
def test_weights_out_of_range(bad: float) -> None:
    with pytest.raises(ValueError, match="alpha"):
        dhg_costa2021(0.0, g1=0.5, g2=0.1, alpha=bad)
    with pytest.raises(ValueError, match="f must"):
        dhg_kobe2026(0.0, g1=0.5, g2=0.1, f=bad)
    with pytest.raises(ValueError, match="w_d"):
        hg_draine_jendersie_deon2023(0.0, g_hg=0.5, g_d=0.5, alpha=1.0, w_d=bad)


def test_other_parameter_ranges() -> None:
    with pytest.raises(ValueError, match=r"alpha must be in the closed interval \[-1\.0, inf\]"):
        draine2003(0.0, g=0.5, alpha=-1.5)
    with pytest.raises(ValueError, match="depolarization"):
        rayleigh_depolarized(0.0, depolarization=0.9)
    with pytest.raises(ValueError, match=r"mu \(cosine"):
        rayleigh(1.0001)
    with pytest.raises(ValueError, match="mu must be finite"):
        henyey_greenstein([0.0, math.nan], g=0.2)


def test_unknown_convention_lists_valid_ones() -> None:
    with pytest.raises(
        ValueError, match=r"convention must be one of 'costa2021', 'kobe2026'; got 'meyran'"
    ):
        double_henyey_greenstein(0.0, g1=0.5, g2=0.1, alpha=0.5, convention="meyran")
    assert DHG_CONVENTIONS == ("costa2021", "kobe2026")


def test_weight_name_must_match_convention() -> None:
    with pytest.raises(ValueError, match=r"'costa2021' takes its weight as 'alpha', not 'f'"):
        double_henyey_greenstein(0.0, g1=0.5, g2=0.1, f=0.3)
    with pytest.raises(ValueError, match=r"'kobe2026' takes its weight as 'f', not 'alpha'"):
        double_henyey_greenstein(0.0, g1=0.5, g2=0.1, alpha=0.3, convention="kobe2026")
    with pytest.raises(ValueError, match="needs the weight 'f'"):
        double_henyey_greenstein_asymmetry(g1=0.5, g2=0.1, convention="kobe2026")


def test_unknown_model_lists_valid_ones() -> None:
    with pytest.raises(ValueError, match="name must be one of 'rayleigh'.*'henyey_greenstein'"):
        get_analytic_model("mie")


# ------------------------------------------------------ Costa et al. 2021


def test_costa_code_values() -> None:
    d = COSTA2021_MARS_DHG_CODE
    np.testing.assert_array_equal(d.wavelength_nm, [440.0, 550.0, 680.0])
    np.testing.assert_array_equal(d.g1, [0.67, 0.4, 0.03])
    np.testing.assert_array_equal(d.g2, 0.094)
    np.testing.assert_array_equal(d.alpha, 0.743)
    assert "10.1109/TVCG.2020.3030333" in d.citation and "Meyran" in d.citation
    with pytest.raises(ValueError, match="read-only"):
        d.g1[0] = 0.0


def test_costa_paper_values_recorded_not_default() -> None:
    p = COSTA2021_MARS_DHG_PAPER
    np.testing.assert_array_equal(p.g2, [0.099, 0.89, 0.094])
    np.testing.assert_array_equal(p.alpha, [0.01, 0.04, 0.743])
    assert "not the default" in p.model
    d = costa2021_mars_dhg([440.0, 550.0, 680.0])
    np.testing.assert_array_equal(d.g2, COSTA2021_MARS_DHG_CODE.g2)
    np.testing.assert_array_equal(d.alpha, COSTA2021_MARS_DHG_CODE.alpha)


def test_meyran_quadratic_reproduces_code_values() -> None:
    d = costa2021_mars_dhg([440.0, 550.0, 680.0])
    residual = d.g1 - COSTA2021_MARS_DHG_CODE.g1
    # Residuals 5.3e-9, 5.5e-9, 5.8e-9: the quadratic's printed 9 significant digits.
    assert np.all(np.abs(residual) < 1e-8)
    assert np.all(residual > 0)
    a, b, c = MEYRAN2022_G1_COEFFICIENTS
    assert a * 830.0**2 + b * 830.0 + c == pytest.approx(-0.4655, abs=1e-4)


def test_costa_quadratic_warns_above_690nm() -> None:
    with pytest.warns(ExtrapolationWarning, match=r"g1 < 0.*\[700\.0, 830\.0\]"):
        d = costa2021_mars_dhg([550.0, 700.0, 830.0])
    assert d.g1[2] == pytest.approx(-0.4655, abs=1e-4)
    assert issubclass(ExtrapolationWarning, UserWarning)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        costa2021_mars_dhg(np.linspace(300.0, 689.0, 50))


def test_costa_quadratic_outside_hg_domain_raises() -> None:
    with pytest.raises(ValueError, match=r"\|g1\| < 1.*\[250\.0\]"):
        costa2021_mars_dhg([250.0, 550.0])
    with pytest.raises(ValueError, match=r"\|g1\| < 1.*\[1000\.0\]"):
        costa2021_mars_dhg(1000.0)


def test_costa_clamp() -> None:
    wl = np.array([300.0, 439.0, 440.0, 500.0, 680.0, 700.0, 1000.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = costa2021_mars_dhg(wl, outside="clamp")
    quad = costa2021_mars_dhg([440.0, 500.0, 680.0]).g1
    np.testing.assert_array_equal(d.g1[:3], quad[0])
    assert d.g1[0] == pytest.approx(0.670000005272, abs=1e-12)
    assert d.g1[3] == quad[1]
    np.testing.assert_array_equal(d.g1[4:], quad[2])
    assert d.g1[-1] == pytest.approx(0.030000005768, abs=1e-12)


def test_costa_error_mode() -> None:
    d = costa2021_mars_dhg([440.0, 680.0], outside="error")
    assert d.g1.shape == (2,)
    with pytest.raises(ValueError, match=r"\[440\.0, 680\.0\].*got \[700\.0\]"):
        costa2021_mars_dhg([550.0, 700.0], outside="error")
    with pytest.raises(ValueError, match="outside must be one of 'quadratic', 'clamp', 'error'"):
        costa2021_mars_dhg(550.0, outside="extrapolate")
    with pytest.raises(ValueError, match="wavelength_nm must be > 0"):
        costa2021_mars_dhg([-1.0])


def test_costa_spectrum_phase_rows_normalized() -> None:
    d = costa2021_mars_dhg(np.linspace(440.0, 680.0, 48))
    table = d.phase(MU_NODES)
    assert table.shape == (48, MU_NODES.size)
    for row, g in zip(table, d.asymmetry()):
        assert sphere_moment(row) == pytest.approx(1.0, abs=1e-9)
        assert sphere_moment(row, 1) == pytest.approx(g, abs=1e-9)
    # blue scatters more forward than red: the source of the blue glow
    assert np.all(np.diff(d.asymmetry()) < 0)


def test_dhg_spectrum_validates() -> None:
    with pytest.raises(ValueError, match=r"g2 must have the shape of wavelength_nm \(2,\)"):
        DHGSpectrum(
            wavelength_nm=[1.0, 2.0],
            g1=[0.1, 0.2],
            g2=[0.1],
            alpha=[0.5, 0.5],
            model="x",
            citation="y",
        )
    with pytest.raises(ValueError, match="alpha"):
        DHGSpectrum(wavelength_nm=[1.0], g1=[0.1], g2=[0.1], alpha=[1.5], model="x", citation="y")


# ------------------------------------------------- Jendersie & d'Eon 2023


def test_jendersie_deon_parameters() -> None:
    d = np.array([5.0, 10.0, 20.0, 50.0])
    p = jendersie_deon2023_parameters(diameter_um=d)
    np.testing.assert_allclose(p.g_hg, np.exp(-0.0990567 / (d - 1.67154)), rtol=1e-15)
    np.testing.assert_allclose(p.g_d, np.exp(-2.20679 / (d + 3.91029) - 0.428934), rtol=1e-15)
    np.testing.assert_allclose(p.alpha, np.exp(3.62489 - 8.29288 / (d + 5.52825)), rtol=1e-15)
    np.testing.assert_allclose(p.w_d, np.exp(-0.599085 / (d - 0.641583) - 0.665888), rtol=1e-15)
    assert p.g_hg[0] == pytest.approx(0.970678, abs=1e-6)
    assert np.all((p.g_hg > 0.97) & (p.g_hg < 1.0) & (p.w_d > 0.4) & (p.w_d < 0.55))
    table = p.phase(MU_NODES)
    assert table.shape == (4, MU_NODES.size)
    for row, g in zip(table, p.asymmetry()):
        assert sphere_moment(row) == pytest.approx(1.0, abs=1e-9)
        assert sphere_moment(row, 1) == pytest.approx(g, abs=1e-9)


@pytest.mark.parametrize("bad", [4.9, 50.1, math.nan])
def test_jendersie_deon_range(bad: float) -> None:
    with pytest.raises(ValueError, match="diameter_um"):
        jendersie_deon2023_parameters(diameter_um=bad)


# ---------------------------------------------------------- Collienne 2013


def test_collienne_dataset() -> None:
    c = COLLIENNE2013_MARS
    assert c.wavelength_nm == (440.0, 510.0, 680.0)
    assert c.rayleigh_scattering_per_m == (5.75e-6, 13.57e-6, 19.918e-6)
    assert c.aerosol_g == 0.8
    assert {g for g, _ in c.aerosol_g_alternatives} == {0.76, 0.5}
    mu = np.linspace(-1, 1, 11)
    np.testing.assert_array_equal(c.aerosol_phase(mu), cornette_shanks1992(mu, g=0.8))
    assert "Collienne" in c.citation


def test_module_exports_exist() -> None:
    for name in phase.__all__:
        assert hasattr(phase, name), name


def test_registering_a_taken_name_or_wrong_bounds_is_refused() -> None:
    hg = ANALYTIC_MODELS["henyey_greenstein"]
    with pytest.raises(ValueError, match="'henyey_greenstein' is already registered"):
        register_analytic_model(hg)
    with pytest.raises(ValueError, match="'henyey-greenstein' is already registered"):
        register_analytic_model(dataclasses.replace(hg, name="hg_copy"))
    with pytest.raises(ValueError, match="must give one"):
        register_analytic_model(
            dataclasses.replace(hg, name="hg_copy", aliases=(), bounds=((-1.0, 1.0),) * 2)
        )
    assert "hg_copy" not in ANALYTIC_MODELS
