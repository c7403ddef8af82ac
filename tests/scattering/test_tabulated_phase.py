"""Tests for dustoptics.scattering.tabulated_phase.

Table integrals are checked against scipy's ``quad`` of ``np.interp``, the
interpolation a renderer applies, which shares no code with the module.
"""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

import dustoptics as do
from dustoptics.scattering import phase, tabulated_phase
from dustoptics.scattering.phase import (
    cornette_shanks1992,
    dhg_costa2021,
    henyey_greenstein,
    rayleigh,
)
from dustoptics.scattering.tabulated_phase import (
    flatten,
    hybrid,
    mean_cosine,
    renormalize,
    sphere_integral,
    tabulate,
)

FOUR_PI = 4.0 * math.pi
FAST = settings(max_examples=25, deadline=None)
weight_st = st.floats(0.0, 1.0)


def interp_table_integral(p: np.ndarray, theta_deg: np.ndarray) -> float:
    """``2 pi int P(theta) sin(theta) dtheta`` of np.interp of the table, by quad per interval."""
    t = np.deg2rad(theta_deg)
    total = 0.0
    for a, b in itertools.pairwise(t):
        total += integrate.quad(
            lambda x: np.interp(x, t, p) * math.sin(x), a, b, epsabs=1e-16, epsrel=1e-13
        )[0]
    return 2.0 * math.pi * total


uneven_grid_st = (
    st.lists(st.floats(0.01, 179.99), min_size=0, max_size=25, unique=True)
    .map(lambda xs: np.array([0.0, *sorted(xs), 180.0]))
    .filter(lambda t: np.all(np.diff(t) > 1e-3))
)


@FAST
@given(theta=uneven_grid_st, seed=st.integers(0, 2**32 - 1))
def test_sphere_integral_exact_for_piecewise_linear(theta: np.ndarray, seed: int) -> None:
    p = np.random.default_rng(seed).random(theta.size)
    assert sphere_integral(p, theta_deg=theta) == pytest.approx(
        interp_table_integral(p, theta), abs=1e-12
    )


def test_sphere_integral_constant_and_fine_grid() -> None:
    theta = np.linspace(0.0, 180.0, 3)
    assert sphere_integral(np.full(3, 1.0 / FOUR_PI), theta_deg=theta) == pytest.approx(
        1.0, abs=1e-15
    )
    # 0.01 deg intervals near the ends: the weights keep their precision
    theta = np.concatenate(
        [np.linspace(0, 1, 101), np.linspace(2, 178, 89), np.linspace(179, 180, 101)]
    )
    p = np.cos(np.deg2rad(theta)) ** 2 + 0.1
    assert sphere_integral(p, theta_deg=theta) == pytest.approx(
        interp_table_integral(p, theta), abs=1e-12
    )


def test_sampled_analytic_table_is_close_to_normalized() -> None:
    theta = np.linspace(0.0, 180.0, 721)
    for table in (
        tabulate(rayleigh, theta_deg=theta),
        tabulate(henyey_greenstein, theta_deg=theta, g=0.5),
    ):
        assert sphere_integral(table, theta_deg=theta) == pytest.approx(1.0, abs=1e-4)


def test_tabulate_shapes() -> None:
    theta = np.linspace(0.0, 180.0, 19)
    table = tabulate(henyey_greenstein, theta_deg=theta, g=np.array([[0.2], [0.6]]))
    assert table.shape == (2, 19)
    assert table[1, 0] == pytest.approx(henyey_greenstein(1.0, g=0.6))
    assert table[1, -1] == pytest.approx(henyey_greenstein(-1.0, g=0.6))
    assert np.all(sphere_integral(table, theta_deg=theta) > 0)


@FAST
@given(theta=uneven_grid_st, seed=st.integers(0, 2**32 - 1), weight=weight_st)
def test_hybrid_renormalized_on_uneven_grids(theta: np.ndarray, seed: int, weight: float) -> None:
    rng = np.random.default_rng(seed)
    p_mie = rng.random((4, theta.size)) * 10.0
    p_dhg = tabulate(dhg_costa2021, theta_deg=theta, g1=0.67, g2=0.094, alpha=0.743)
    p_dhg = np.broadcast_to(p_dhg, p_mie.shape)
    out = hybrid(p_mie, p_dhg, theta_deg=theta, weight=weight)
    np.testing.assert_allclose(sphere_integral(out, theta_deg=theta), 1.0, rtol=0, atol=1e-12)
    per_angle = hybrid(p_mie, p_dhg, theta_deg=theta, weight=rng.random(theta.size))
    np.testing.assert_allclose(sphere_integral(per_angle, theta_deg=theta), 1.0, rtol=0, atol=1e-12)
    assert np.all(out >= 0)


def test_hybrid_end_weights_and_blend() -> None:
    theta = np.array([0.0, 0.5, 3.0, 20.0, 90.0, 150.0, 180.0])
    p_mie = renormalize(np.array([50.0, 30.0, 5.0, 0.5, 0.05, 0.02, 0.04]), theta_deg=theta)
    p_an = renormalize(tabulate(cornette_shanks1992, theta_deg=theta, g=0.76), theta_deg=theta)
    np.testing.assert_allclose(hybrid(p_mie, p_an, theta_deg=theta, weight=0.0), p_mie, rtol=1e-14)
    np.testing.assert_allclose(hybrid(p_mie, p_an, theta_deg=theta, weight=1.0), p_an, rtol=1e-14)
    # two normalized inputs: the blend is already normalized, renormalization changes nothing
    np.testing.assert_allclose(
        hybrid(p_mie, p_an, theta_deg=theta), 0.5 * p_mie + 0.5 * p_an, rtol=1e-14
    )


def test_renormalize_does_not_modify_input_and_is_exact() -> None:
    theta = np.array([0.0, 1.0, 10.0, 100.0, 180.0])
    p = np.array([[4.0, 3.0, 2.0, 1.0, 0.5], [1.0, 1.0, 1.0, 1.0, 1.0]])
    before = p.copy()
    out = renormalize(p, theta_deg=theta)
    np.testing.assert_array_equal(p, before)
    np.testing.assert_allclose(sphere_integral(out, theta_deg=theta), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(out[1], 1.0 / FOUR_PI, rtol=1e-14)


def test_flatten() -> None:
    theta = np.linspace(0.0, 180.0, 37)
    p = renormalize(tabulate(henyey_greenstein, theta_deg=theta, g=0.8), theta_deg=theta)
    np.testing.assert_allclose(flatten(p, theta_deg=theta, amount=1.0), 1.0 / FOUR_PI, rtol=1e-14)
    np.testing.assert_allclose(flatten(p, theta_deg=theta, amount=0.0), p, rtol=1e-14)
    half = flatten(p, theta_deg=theta, amount=0.25)
    np.testing.assert_allclose(half, 0.75 * p + 0.25 / FOUR_PI, rtol=1e-13)
    assert sphere_integral(half, theta_deg=theta) == pytest.approx(1.0, abs=1e-13)


def test_table_validation() -> None:
    theta = np.linspace(0.0, 180.0, 5)
    p = np.full((2, 5), 0.1)
    with pytest.raises(
        ValueError, match=r"p_mie has shape \(2, 5\) but p_analytic has shape \(3, 5\)"
    ):
        hybrid(p, np.full((3, 5), 0.1), theta_deg=theta)
    with pytest.raises(
        ValueError, match=r"phase has shape \(2, 5\) but theta_deg has shape \(4,\)"
    ):
        sphere_integral(p, theta_deg=np.array([0.0, 60.0, 120.0, 180.0]))
    with pytest.raises(
        ValueError, match=r"p_analytic has shape \(2, 4\) but theta_deg has shape \(5,\)"
    ):
        hybrid(p, np.full((2, 4), 0.1), theta_deg=theta)
    with pytest.raises(ValueError, match="exactly 0 and end at exactly 180"):
        renormalize(p, theta_deg=np.linspace(0.0, 179.0, 5))
    with pytest.raises(ValueError, match="exactly 0 and end at exactly 180"):
        renormalize(p, theta_deg=np.linspace(1.0, 180.0, 5))
    with pytest.raises(ValueError, match="strictly increasing"):
        renormalize(p, theta_deg=np.array([0.0, 90.0, 45.0, 135.0, 180.0]))
    with pytest.raises(ValueError, match=r"must be <= 180"):
        renormalize(p, theta_deg=np.array([0.0, 45.0, 90.0, 135.0, 181.0]))
    with pytest.raises(ValueError, match=r"p_mie must be >= 0"):
        hybrid(p - 0.2, p, theta_deg=theta)
    with pytest.raises(ValueError, match="finite"):
        sphere_integral(np.array([0.1, np.nan, 0.1, 0.1, 0.1]), theta_deg=theta)
    with pytest.raises(ValueError, match="positive sphere integral"):
        renormalize(np.zeros(5), theta_deg=theta)
    with pytest.raises(ValueError, match=r"weight has shape \(4,\)"):
        hybrid(p, p, theta_deg=theta, weight=np.full(4, 0.5))


def test_mean_cosine_is_exact_for_linear_interpolation() -> None:
    """Against scipy quad of the piecewise-linear-in-theta function (independent)."""
    theta = np.array([0.0, 3.0, 10.0, 45.0, 90.0, 91.0, 150.0, 180.0])
    values = np.array([[9.0, 5.0, 2.0, 0.5, 0.1, 0.1, 0.05, 0.2]])
    expected = (
        2
        * math.pi
        * integrate.quad(
            lambda t: np.interp(t, np.deg2rad(theta), values[0]) * math.sin(t) * math.cos(t),
            0.0,
            math.pi,
            points=np.deg2rad(theta[1:-1]),
            epsabs=1e-14,
            epsrel=1e-13,
            limit=200,
        )[0]
    )
    assert mean_cosine(values, theta_deg=theta)[0] == pytest.approx(expected, rel=1e-11)


@pytest.mark.parametrize("bad", [-0.1, 1.1, math.nan])
def test_weights_out_of_range(bad: float) -> None:
    theta = np.linspace(0, 180, 5)
    p = np.full(5, 1 / FOUR_PI)
    with pytest.raises(ValueError, match="weight"):
        hybrid(p, p, theta_deg=theta, weight=bad)
    with pytest.raises(ValueError, match="weight"):
        hybrid(p, p, theta_deg=theta, weight=np.array([0.5, 0.5, bad, 0.5, 0.5]))
    with pytest.raises(ValueError, match="amount"):
        flatten(p, theta_deg=theta, amount=bad)


def test_module_exports_exist() -> None:
    for name in tabulated_phase.__all__:
        assert hasattr(tabulated_phase, name), name


@pytest.mark.parametrize("name", tabulated_phase.__all__)
def test_tabulated_phase_names_live_in_their_own_module_only(name: str) -> None:
    """The old ``phase.<name>`` path (never released) is gone."""
    assert name not in phase.__all__
    assert not hasattr(phase, name)
    with pytest.raises(ImportError):
        exec(f"from dustoptics.scattering.phase import {name}", {})


def test_package_names_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert do.hybrid is hybrid
        assert do.renormalize is renormalize
        assert do.sphere_integral is sphere_integral


def test_phase_still_refuses_unknown_names() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        phase.no_such_name  # noqa: B018
