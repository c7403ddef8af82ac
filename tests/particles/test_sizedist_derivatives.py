"""Closed-form density derivatives (dustoptics.particles.sizedist_derivatives)
against central finite differences of the densities, and the normalization identity.

Finite differences: the central difference of ``pdf`` with step h = 1e-5 max(|p|, 1e-2)
has a truncation error c h^2 + O(h^4) and a round-off error below
2 eps_f n / (2 h), eps_f = 1e-13 the relative rounding of a density (exp of a
sum of logarithms of size up to ~30, and the quantile-free closed forms); the
difference of the steps h and 2h is three times the truncation error of step h,
so the tolerance is |D(h) - D(2h)| + 4 eps_f n / h + 1e-12 |dn/dp|, elementwise.

Normalization: every density integrates to 1 for every parameter value, so
int dn/dp dr plus the point masses at moving ends (``boundary_terms``) is 0,
checked with ``scipy.integrate.quad`` (on ln r, to 1e-10 of int |dn/dp| dr) to
1e-8 of int |dn/dp| dr plus 1e-13 (for derivatives that vanish).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import integrate

from dustoptics.particles.custom_sizedist import MultiModal, TabulatedDistribution
from dustoptics.particles.sizedist import (
    DeirmendjianGamma,
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    PowerLaw,
    SizeDistribution,
    Truncated,
)
from dustoptics.particles.sizedist_derivatives import (
    boundary_terms,
    number_density_derivative,
    parameter_names,
    parameter_value,
    with_parameter,
)

EPS_F = 1e-13

DISTRIBUTIONS: dict[str, SizeDistribution] = {
    "mars_gamma": ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
    "broad_gamma": ModifiedGamma(r_eff_um=0.5, v_eff=0.4),  # shape 0.5: n -> inf at 0
    "gamma": Gamma(shape=3.0, scale_um=0.32),
    "log_normal": LogNormal(median_radius_um=0.5, sigma=0.4),
    "modified_log_normal": ModifiedLogNormal(r_eff_um=1.4, v_eff=0.35),
    "deirmendjian_c1": DeirmendjianGamma(alpha=6.0, b=1.5, gamma=1.0),
    "deirmendjian_haze_l": DeirmendjianGamma(alpha=2.0, b=15.1186, gamma=0.5),
    "power_law": PowerLaw(exponent=3.0, r_min_um=0.1, r_max_um=10.0),
    "power_law_p0": PowerLaw(exponent=1.0, r_min_um=0.1, r_max_um=10.0),  # <ln r> series
    "truncated_inside": Truncated(
        parent=ModifiedGamma(r_eff_um=1.6, v_eff=0.2), r_min_um=0.5, r_max_um=5.0
    ),
    "truncated_tail": Truncated(
        parent=LogNormal(median_radius_um=0.5, sigma=0.4), r_min_um=1.0, r_max_um=math.inf
    ),
    "truncated_power_law": Truncated(
        parent=PowerLaw(exponent=2.5, r_min_um=0.1, r_max_um=10.0), r_min_um=0.2, r_max_um=3.0
    ),
    # Bounds outside the parent's support move nothing: derivatives 0.
    "truncated_wide": Truncated(
        parent=PowerLaw(exponent=2.5, r_min_um=0.1, r_max_um=10.0), r_min_um=0.05, r_max_um=3.0
    ),
    "cosmoscout_mars": MultiModal(
        modes=(
            ModifiedLogNormal(r_eff_um=0.04, v_eff=0.1),
            ModifiedLogNormal(r_eff_um=1.4, v_eff=0.35),
        ),
        relative_number_densities=(1000.0, 1.0),
    ),
    "nested": MultiModal(
        modes=(
            Truncated(parent=ModifiedGamma(r_eff_um=0.8, v_eff=0.1), r_min_um=0.3, r_max_um=2.0),
            PowerLaw(exponent=3.5, r_min_um=0.5, r_max_um=4.0),
            Gamma(shape=2.0, scale_um=0.5),
        ),
        relative_number_densities=(2.0, 1.0, 0.5),
    ),
}

CASES = [(key, p) for key, d in DISTRIBUTIONS.items() for p in parameter_names(d)]


def _support(d: SizeDistribution) -> tuple[float, float]:
    """Radii holding all but ~1e-12 of the number (finite ends where the support has them)."""
    lo, hi = d.radius_bounds_um(tail_fraction=1e-12, lower_moment=0.0, upper_moment=0.0)
    return lo, hi


def _ends(d: SizeDistribution) -> list[float]:
    """Radii where the density jumps (ends of a finite support), for the quadrature's breakpoints."""
    if isinstance(d, MultiModal):
        return [r for mode in d.modes for r in _ends(mode)]
    if isinstance(d, PowerLaw):
        return [d.r_min_um, d.r_max_um]
    if isinstance(d, Truncated):
        return [r for r in (d.r_min_um, d.r_max_um) if 0.0 < r < math.inf] + _ends(d.parent)
    return []


def _interior_radii(d: SizeDistribution, step: float) -> np.ndarray:
    lo, hi = _support(d)
    r = np.geomspace(lo, hi, 61)
    ends = np.array(_ends(d))
    if ends.size:  # keep the differences off the jumps of the density
        r = r[np.min(np.abs(r[:, None] - ends[None, :]), axis=1) > 1e3 * step * max(1.0, hi)]
    return r


@pytest.mark.parametrize(("key", "parameter"), CASES)
def test_against_finite_differences(key: str, parameter: str) -> None:
    d = DISTRIBUTIONS[key]
    p = parameter_value(d, parameter)
    h = 1e-5 * max(abs(p), 1e-2)
    r = _interior_radii(d, h)

    def n(value: float) -> np.ndarray:
        return np.asarray(with_parameter(d, parameter, value).pdf(r), dtype=np.float64)

    d_h = (n(p + h) - n(p - h)) / (2.0 * h)
    d_2h = (n(p + 2.0 * h) - n(p - 2.0 * h)) / (4.0 * h)
    exact = number_density_derivative(d, r, parameter)
    n0 = n(p)
    tol = np.abs(d_h - d_2h) + 4.0 * EPS_F * n0 / h + 1e-12 * np.abs(exact)
    err = np.abs(exact - d_h)
    assert np.all(err <= tol), (float(np.max(err - tol)), r[np.argmax(err - tol)])
    # Not a vacuous check: the derivative is resolved well inside its own size, or it
    # vanishes (to rounding, against its natural size max(n) / |p|), as for a bound of a
    # truncation's parent outside the truncation, and the difference agrees (above).
    natural = float(np.max(n0)) / max(abs(p), 1e-2)
    peak = float(np.max(np.abs(exact)))
    assert np.max(tol) < 1e-3 * peak or peak < 1e-12 * natural


@pytest.mark.parametrize(("key", "parameter"), CASES)
def test_derivative_integrates_to_zero(key: str, parameter: str) -> None:
    d = DISTRIBUTIONS[key]
    lo, hi = _support(d)
    cuts = sorted({lo, hi, *(r for r in _ends(d) if lo < r < hi)})

    def f(u: float) -> float:
        r = math.exp(u)
        return float(number_density_derivative(d, [r], parameter)[0]) * r

    pieces = [(math.log(a), math.log(b)) for a, b in itertools.pairwise(cuts)]
    size = sum(
        integrate.quad(lambda u: abs(f(u)), a, b, epsabs=1e-14, epsrel=1e-8, limit=400)[0]
        for a, b in pieces
    )
    # The integral cancels to 0: asked to 1e-10 of int |dn/dp| dr (a relative
    # tolerance of its own would not be reachable).
    eps = 1e-10 * size / len(pieces) + 1e-15
    total = sum(integrate.quad(f, a, b, epsabs=eps, epsrel=1e-10, limit=400)[0] for a, b in pieces)
    masses = boundary_terms(d, parameter)
    total += sum(c for _, c in masses)
    size += sum(abs(c) for _, c in masses)
    assert abs(total) <= 1e-8 * size + 1e-13, (total, size)


def test_boundary_terms_are_the_density_at_the_moving_ends() -> None:
    d = PowerLaw(exponent=3.0, r_min_um=0.1, r_max_um=10.0)
    ((a, ca),) = boundary_terms(d, "r_min_um")
    ((b, cb),) = boundary_terms(d, "r_max_um")
    assert (a, b) == (0.1, 10.0)
    assert ca == pytest.approx(-float(d.pdf(0.1)), rel=1e-14)
    assert cb == pytest.approx(float(d.pdf(10.0)), rel=1e-14)
    assert boundary_terms(d, "exponent") == ()
    mix = DISTRIBUTIONS["nested"]
    assert isinstance(mix, MultiModal)
    ((r, c),) = boundary_terms(mix, "modes[1].r_max_um")
    assert r == 4.0
    assert c == pytest.approx(mix.number_fractions[1] * float(mix.modes[1].pdf(4.0)), rel=1e-14)


def test_parameter_names_follow_the_nesting() -> None:
    assert parameter_names(DISTRIBUTIONS["cosmoscout_mars"]) == (
        "modes[0].r_eff_um",
        "modes[0].v_eff",
        "modes[1].r_eff_um",
        "modes[1].v_eff",
        "relative_number_densities[0]",
        "relative_number_densities[1]",
    )
    assert parameter_names(DISTRIBUTIONS["truncated_tail"]) == (
        "parent.median_radius_um",
        "parent.sigma",
        "r_min_um",
    )
    assert "modes[0].parent.v_eff" in parameter_names(DISTRIBUTIONS["nested"])
    assert parameter_names(Monodisperse(radius_um=1.0)) == ("radius_um",)


def test_with_parameter_round_trips() -> None:
    for key, parameter in CASES:
        d = DISTRIBUTIONS[key]
        value = parameter_value(d, parameter)
        assert with_parameter(d, parameter, value) == d
        changed = with_parameter(d, parameter, value * 1.01)
        assert parameter_value(changed, parameter) == pytest.approx(value * 1.01, rel=1e-15)


def test_relative_number_densities_only_their_ratios_matter() -> None:
    """Scaling every d_i leaves n unchanged: sum_i d_i dn/dd_i = 0."""
    d = DISTRIBUTIONS["nested"]
    assert isinstance(d, MultiModal)
    r = np.geomspace(0.2, 5.0, 50)
    total = sum(
        d.relative_number_densities[i]
        * number_density_derivative(d, r, f"relative_number_densities[{i}]")
        for i in range(3)
    )
    np.testing.assert_allclose(total, 0.0, atol=1e-14 * float(np.max(d.pdf(r))))


def test_edges() -> None:
    d = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    out = number_density_derivative(d, [np.nan, -1.0, 0.0, 1.0], "v_eff")
    assert np.isnan(out[0]) and out[1] == 0.0 and out[2] == 0.0 and np.isfinite(out[3])
    assert number_density_derivative(d, 1.0, "r_eff_um").shape == ()
    power = PowerLaw(exponent=3.0, r_min_um=0.1, r_max_um=10.0)
    assert np.all(number_density_derivative(power, [0.05, 20.0], "exponent") == 0.0)


def test_errors_name_the_parameter_and_what_is_allowed() -> None:
    d = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    with pytest.raises(ValueError, match=r"parameter must be one of 'r_eff_um', 'v_eff'.*'sigma'"):
        number_density_derivative(d, 1.0, "sigma")
    with pytest.raises(ValueError, match="one-sided"):
        number_density_derivative(DISTRIBUTIONS["truncated_tail"], 1.0, "r_max_um")
    with pytest.raises(TypeError, match="no density"):
        number_density_derivative(Monodisperse(radius_um=1.0), 1.0, "radius_um")
    with pytest.raises(TypeError, match="SizeDistribution"):
        number_density_derivative("gamma", 1.0, "v_eff")  # type: ignore[arg-type]
    table = TabulatedDistribution(
        radius_um=np.array([0.1, 1.0, 2.0]), dn_dr=np.array([0.0, 1.0, 0.0])
    )
    with pytest.raises(ValueError, match="no named parameters"):
        parameter_names(table)
