"""Tests of dustoptics.scattering.quadrature's compiled pieces (the quadrature's
behaviour as a whole is tested through the tables in test_optics and
test_accuracy)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import wrightomega

from dustoptics.scattering.quadrature import (
    QuadratureSettings,
    _unstretch,
    _wright_omega,
    size_parameter_at,
)


def test_wright_omega_equals_scipy_to_the_bit():
    """The compiled Wright omega takes the steps of scipy.special.wrightomega
    for real input (Lawrence, Corless & Jeffrey 2012), so the node placement
    is unchanged by it: equal values, bit for bit, over the stretched
    coordinates the quadrature uses (-60..2,000), on both sides of each
    branch point of the first guess, and at the ends of the real line."""
    rng = np.random.default_rng(2012)
    edges = np.array([-50.0, -2.0, 1.0])
    near = (edges[:, None] + np.linspace(-1e-9, 1e-9, 201)[None, :]).ravel()
    s = np.concatenate(
        [
            rng.uniform(-60.0, 10.0, 200_000),
            rng.uniform(10.0, 2000.0, 100_000),
            near,
            [1e20, 2e20, 1e300],
        ]
    )
    np.testing.assert_array_equal(_unstretch(s, 1.0), wrightomega(s))
    assert np.isnan(_wright_omega(np.nan))
    assert _wright_omega(np.inf) == np.inf
    assert _wright_omega(-np.inf) == 0.0


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=-40.0, max_value=1e6))
def test_wright_omega_solves_its_equation(s: float):
    """w + ln w = s, to a few units in the last place of max(|s|, 1)."""
    w = _wright_omega(s)
    assert w > 0.0
    assert w + np.log(w) == pytest.approx(s, rel=0, abs=8 * np.finfo(float).eps * max(abs(s), 1.0))


def test_size_parameter_at_keeps_the_shape():
    """Scalars give scalars, arrays keep their shape."""
    settings_ = QuadratureSettings(transition_size_parameter=2.0)
    assert np.ndim(size_parameter_at(3.0, settings=settings_)) == 0
    s = np.linspace(-3.0, 9.0, 12).reshape(3, 4)
    x = size_parameter_at(s, settings=settings_)
    assert x.shape == (3, 4)
    np.testing.assert_array_equal(x, 2.0 * wrightomega(s))


@given(x=st.floats(1e-6, 1e4), x_c=st.floats(0.1, 10.0))
@settings(max_examples=50, deadline=None)
def test_size_parameter_at_inverts_the_stretch(x: float, x_c: float) -> None:
    """size_parameter_at(s) returns the x with s = x / x_c + ln(x / x_c)."""
    s = x / x_c + np.log(x / x_c)
    got = float(size_parameter_at(s, settings=QuadratureSettings(transition_size_parameter=x_c)))
    assert got == pytest.approx(x, rel=1e-12)
