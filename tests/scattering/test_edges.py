"""Inputs at the edges of the domain (issue 15): refused before any work, or exact.

Each case is an input that, on main at 3e27677, hung, ran out of memory,
raised a traceback from deep inside, or returned a wrong number.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import integrate

import dustoptics as do
from dustoptics._validation import BudgetError
from dustoptics.particles.sizedist import MIN_V_EFF
from dustoptics.scattering import mie
from dustoptics.scattering.optics import WORK_BUDGET, estimate_cost, optics_request
from dustoptics.scattering.quadrature import QuadratureSettings

GAMMA = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        # micrometres by mistake: > 10 min and 7.5 GB before
        (lambda: do.compute_optics(1.5 + 0.001j, GAMMA, [0.44, 0.55]), ValueError, "micrometres"),
        (lambda: do.compute_optics(1.5, GAMMA, [1e-3]), ValueError, "nanometres"),
        # > 200 s / 5 GB, > 180 s, 3.4 GB before
        (
            lambda: do.compute_optics(1.5 + 0.01j, do.ModifiedLogNormal(r_eff_um=1, v_eff=2)),
            BudgetError,
            "allow_large",
        ),
        (
            lambda: do.compute_optics(1.5 + 0.01j, do.ModifiedGamma(r_eff_um=1000, v_eff=0.2)),
            BudgetError,
            "r_eff_um",
        ),
        (
            lambda: do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=1e4)),
            BudgetError,
            "GiB",
        ),
        (
            lambda: do.compute_optics(
                1.5, GAMMA, [550.0], quadrature=QuadratureSettings(panel_width=1e-9)
            ),
            BudgetError,
            "panel_width",
        ),
        (
            lambda: do.compute_optics(1.5, GAMMA, None, np.linspace(0, 180, 2 * 10**6)),
            BudgetError,
            "angles",
        ),
        # NaN size parameters ran Lentz's loop to its cap for > 15 min
        (lambda: do.ModifiedGamma(r_eff_um=1e-300, v_eff=0.2), ValueError, "r_eff_um must be in"),
        (lambda: do.compute_optics(1e300, GAMMA, [550.0]), ValueError, r"\|m\| <= 10000"),
        # tracebacks from inside
        (lambda: do.compute_optics(1 + 1e-300j, GAMMA, [550.0]), ValueError, r"\|m - 1\|"),
        (lambda: do.ModifiedGamma(r_eff_um=1e308, v_eff=0.2), ValueError, "r_eff_um must be in"),
        (lambda: do.LogNormal(median_radius_um=1.0, sigma=10.0), ValueError, "sigma must be in"),
        (lambda: do.Monodisperse(radius_um=1e-100), ValueError, "radius_um must be in"),
        (lambda: do.Monodisperse(radius_um=1e-30), ValueError, "radius_um must be in"),
        (
            lambda: GAMMA.radius_bounds_um(tail_fraction=1e-300),
            ValueError,
            "tail_fraction must be >=",
        ),
        (
            lambda: do.compute_optics(lambda w: None, GAMMA, [550.0]),
            TypeError,
            "must return a complex",
        ),
        # strings and booleans are not numbers
        (lambda: do.ModifiedGamma(r_eff_um="1.5", v_eff=0.2), TypeError, "not str"),
        (lambda: do.compute_optics(1.5, GAMMA, [True]), TypeError, "bool"),
        (
            lambda: do.compute_optics(1.5, GAMMA, [550.0], weighting=np.array(["number"])),
            TypeError,
            "weighting must be a str",
        ),
        # distributions narrower than the documented bound
        (lambda: do.ModifiedGamma(r_eff_um=1.0, v_eff=1e-15), ValueError, "Monodisperse"),
        (lambda: do.ModifiedLogNormal(r_eff_um=1.0, v_eff=1e-15), ValueError, "Monodisperse"),
        (lambda: do.Gamma(shape=1e15, scale_um=1e-15), ValueError, "shape must be <="),
    ],
)
def test_refused_before_any_work(call, error, message):
    with pytest.raises(error, match=message):
        call()


def test_strings_are_both_type_and_value_errors():
    """Callers that catch the package's usual ValueError for bad input still catch them."""
    with pytest.raises(ValueError):
        do.ModifiedGamma(r_eff_um="1.5", v_eff=0.2)


def test_the_budget_can_be_lifted_and_is_estimated_without_allocating():
    big = optics_request(1.5, do.Monodisperse(radius_um=1e4), [360.0, 830.0])
    cost = estimate_cost(big, workers=2)
    # n_max x angles x 16 bytes of pi and tau: 1.75e5 x 1801 x 32 B = 10 GB for one sphere.
    assert cost.memory_bytes > 5e9
    default = estimate_cost(optics_request(1.5, GAMMA), workers=2)
    assert default.memory_bytes < 0.1e9 and default.work < WORK_BUDGET / 100


def test_multimodal_densities_near_the_float_limit():
    d = do.MultiModal(
        modes=(GAMMA, do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1)),
        relative_number_densities=(1e308, 1e308),
    )
    assert d.number_fractions == (0.5, 0.5)


@pytest.mark.parametrize("v_eff", [MIN_V_EFF, 1e-3, 0.01])
def test_modified_gamma_density_is_normalized_down_to_the_smallest_v_eff(v_eff):
    """int n(r) dr = 1 and <r^3>/<r^2> = r_eff to 1e-9 at the narrowest accepted width."""
    d = do.ModifiedGamma(r_eff_um=1.6, v_eff=v_eff)
    width = 1.6 * math.sqrt(v_eff)
    lo, hi = 1.6 - 12 * width, 1.6 + 12 * width
    points = np.linspace(lo, hi, 41)
    total = sum(
        integrate.quad(d.pdf, a, b, epsabs=0, epsrel=1e-12)[0]
        for a, b in itertools.pairwise(points)
    )
    m2 = sum(
        integrate.quad(lambda r: r**2 * d.pdf(r), a, b, epsabs=0, epsrel=1e-12)[0]
        for a, b in itertools.pairwise(points)
    )
    m3 = sum(
        integrate.quad(lambda r: r**3 * d.pdf(r), a, b, epsabs=0, epsrel=1e-12)[0]
        for a, b in itertools.pairwise(points)
    )
    assert abs(total - 1) < 1e-9
    assert abs(m3 / m2 - 1.6) < 1e-8


def test_narrowest_gamma_converges_to_the_single_sphere():
    """At v_eff = 1e-4 the table is the single sphere's to its width (1 %): no wrong q_ext."""
    narrow = do.compute_optics(
        1.5 + 0.01j, do.ModifiedGamma(r_eff_um=0.5, v_eff=MIN_V_EFF), [550.0], [0.0, 90.0, 180.0]
    )
    one = do.compute_optics(
        1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 90.0, 180.0]
    )
    assert abs(narrow.qext[0] / one.qext[0] - 1) < 0.02


@pytest.mark.parametrize("k", [0.0, 0.01])
def test_smallest_spheres_are_rayleigh_and_never_negative(k):
    """Monodisperse(1e-6 um): Q_ext from the Rayleigh limit, C_abs >= 0, 0 <= ssa <= 1."""
    m = 1.5 + 1j * k
    t = do.compute_optics(m, do.Monodisperse(radius_um=1e-6), [360.0, 830.0], [0.0, 90.0, 180.0])
    x = 2 * np.pi * 1e-6 / (t.wavelength_nm * 1e-3)
    K = (m * m - 1) / (m * m + 2)
    q_rayleigh = 8 / 3 * x**4 * abs(K) ** 2 + 4 * x * K.imag  # Bohren & Huffman (1983) eq. 5.8-5.9
    assert np.allclose(t.qext, q_rayleigh, rtol=1e-6)
    assert np.all(t.cabs_um2 >= 0) and np.all((t.ssa >= 0) & (t.ssa <= 1))
    if k == 0:
        assert np.all(t.cabs_um2 == 0) and np.all(t.ssa == 1)


@pytest.mark.parametrize(
    ("m", "x", "message"),
    [
        (1.5 + 0.01j, 1e-100, r"x must be >= 1e-30"),
        (1.0, 1.0, r"differ from 1"),
        (1 + 1e-300j, 1e-8, r"differ from 1"),
        (1e300, 1.0, r"\|m\| <= 10000"),
        (complex("nan"), 1.0, "finite"),
        ("1.5", 1.0, "complex number"),
        (1.5, float("nan"), "finite"),
    ],
)
def test_single_sphere_validates_like_compute_optics(m, x, message):
    with pytest.raises((ValueError, TypeError), match=message):
        mie.single_sphere(m=m, x=x)


def test_single_sphere_at_the_smallest_size_parameter_is_finite():
    s = mie.single_sphere(m=1.5 + 0.01j, x=mie.MIN_SIZE_PARAMETER)
    assert np.isfinite([s.qext, s.qsca, s.g]).all() and s.qext > 0 and s.qsca > 0


def test_single_sphere_beyond_the_memory_budget_is_refused():
    """x = 1e12 needs 1e12 orders (found by scripts/fuzz.py: a MemoryError before)."""
    with pytest.raises(BudgetError, match="n_max"):
        mie.single_sphere(m=2 + 1e-300j, x=1e12)
