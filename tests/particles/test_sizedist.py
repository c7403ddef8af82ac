"""Tests for dustoptics.particles.sizedist: the interface and the analytic families.

The analytic moments, tail fractions and bounds are checked against
``scipy.integrate.quad`` of the density (``_sizedist_reference``), which shares no
code with them (the density comes from ``scipy.stats``; the moments from
``scipy.special.poch`` or the log-normal closed form; the tails from incomplete
gamma / normal functions).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable

import numpy as np
import pytest
from _sizedist_reference import (
    FAST,
    MARS_COARSE,
    MOMENT_ORDERS,
    check_against_density,
    check_bounds,
    continuous,
    gammas,
    log_normals,
    quad,
    quad_moment,
)
from hypothesis import given
from hypothesis import strategies as st
from scipy import integrate

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

# --------------------------------------------------------- density, moments


@FAST
@given(dist=continuous)
def test_pdf_is_normalized(dist: SizeDistribution) -> None:
    assert quad_moment(dist, 0.0) == pytest.approx(1.0, rel=1e-9)


@FAST
@given(dist=continuous)
def test_moments_match_quadrature(dist: SizeDistribution) -> None:
    for k in MOMENT_ORDERS:
        assert dist.moment(k) == pytest.approx(quad_moment(dist, k), rel=1e-8), k


@pytest.mark.parametrize("k", [-0.1, 0.0, 0.5, 1.0, 2.0, 3.0, 6.0])
def test_moments_for_singular_modified_gamma(k: float) -> None:
    # v_eff = 0.45: shape = 2/9 < 1, n(r) ~ r^(-7/9) at r -> 0.  quad's
    # algebraic weight takes the factor r^(shape + k - 1) exactly; what is left,
    # n(r) r^(1 - shape), is smooth.
    dist = ModifiedGamma(r_eff_um=1.0, v_eff=0.45)

    def smooth(r: float) -> float:
        r = max(r, 1e-300)  # n(0) is defined as 0; the limit of n(r) r^(1 - shape) is not
        return float(dist.pdf(r)) * float(r ** (1.0 - dist.shape))

    near, _ = integrate.quad(
        smooth,
        0.0,
        dist.scale_um,
        weight="alg",
        wvar=(dist.shape + k - 1.0, 0.0),
        epsabs=0.0,
        epsrel=1e-12,
    )
    far, _ = integrate.quad(
        lambda r: r**k * float(dist.pdf(r)), dist.scale_um, math.inf, epsabs=0.0, epsrel=1e-12
    )
    assert dist.moment(k) == pytest.approx(near + far, rel=1e-8)


def test_modified_gamma_is_hansen_travis_formula() -> None:
    # n(r) ~ r^((1 - 3b)/b) exp(-r/(a b)): the ratio to the unnormalized form is constant.
    a, b = 1.6, 0.2
    r = np.geomspace(0.01, 20.0, 50)
    ratio = ModifiedGamma(r_eff_um=a, v_eff=b).pdf(r) / (
        r ** ((1 - 3 * b) / b) * np.exp(-r / (a * b))
    )
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-12)


def test_seed_mars_dust_is_gamma_3_032() -> None:
    modified = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    plain = Gamma(shape=3.0, scale_um=0.32)
    assert modified.shape == pytest.approx(3.0, rel=1e-14)
    assert modified.scale_um == pytest.approx(0.32, rel=1e-14)
    r = np.linspace(0.0, 15.0, 301)
    np.testing.assert_allclose(modified.pdf(r), plain.pdf(r), rtol=1e-13, atol=0.0)
    for k in MOMENT_ORDERS:
        assert modified.moment(k) == pytest.approx(plain.moment(k), rel=1e-13)


def test_log_normal_closed_form() -> None:
    dist = LogNormal(median_radius_um=0.5, sigma=0.4)
    r = np.array([0.1, 0.5, 2.0])
    expected = np.exp(-((np.log(r / 0.5)) ** 2) / (2 * 0.4**2)) / (np.sqrt(2 * np.pi) * 0.4 * r)
    np.testing.assert_allclose(dist.pdf(r), expected, rtol=1e-13)
    assert dist.moment(2.5) == pytest.approx(0.5**2.5 * math.exp(2.5**2 * 0.4**2 / 2), rel=1e-14)
    assert dist.geometric_std == pytest.approx(math.exp(0.4))


def test_modified_log_normal_is_cosmoscout_log_normal() -> None:
    r_eff, v_eff = 1.4, 0.35
    s2 = math.log(1.0 + v_eff)
    mu = math.log(r_eff) - 2.5 * s2
    dist = ModifiedLogNormal(r_eff_um=r_eff, v_eff=v_eff)
    plain = LogNormal(median_radius_um=math.exp(mu), sigma=math.sqrt(s2))
    same = dist.as_log_normal()
    assert same.median_radius_um == pytest.approx(plain.median_radius_um, rel=1e-15)
    assert same.sigma == pytest.approx(plain.sigma, rel=1e-15)
    r = np.geomspace(0.01, 30.0, 40)
    np.testing.assert_allclose(dist.pdf(r), plain.pdf(r), rtol=1e-13)


@given(
    r_eff=st.floats(0.01, 50.0),
    v_eff=st.floats(1e-3, 0.4999),
    cls=st.sampled_from([ModifiedGamma, ModifiedLogNormal]),
)
def test_effective_radius_and_variance_from_moments_are_the_inputs(
    r_eff: float, v_eff: float, cls: type[ModifiedGamma] | type[ModifiedLogNormal]
) -> None:
    dist = cls(r_eff_um=r_eff, v_eff=v_eff)
    m2, m3, m4 = dist.moment(2), dist.moment(3), dist.moment(4)
    assert m3 / m2 == pytest.approx(r_eff, rel=1e-12)
    # v_eff = m4 m2 / m3^2 - 1 cancels: the ratio carries ~1e-15 of rounding,
    # relative to v_eff that is ~1e-15 / v_eff, so compare the ratio itself.
    assert m4 * m2 / m3**2 == pytest.approx(1.0 + v_eff, rel=1e-12)
    assert dist.r_eff_um == r_eff and dist.v_eff == v_eff


@FAST
@given(dist=st.one_of(gammas, log_normals))
def test_closed_form_r_eff_v_eff_agree_with_moments(dist: SizeDistribution) -> None:
    m2, m3, m4 = dist.moment(2), dist.moment(3), dist.moment(4)
    assert dist.r_eff_um == pytest.approx(m3 / m2, rel=1e-12)
    assert 1.0 + dist.v_eff == pytest.approx(m4 * m2 / m3**2, rel=1e-12)


def test_derived_radii_and_cross_sections() -> None:
    dist = Gamma(shape=3.0, scale_um=0.32)
    # <r^k> = scale^k (shape)(shape+1)...(shape+k-1) for integer k.
    m1, m2, m3 = 0.32 * 3, 0.32**2 * 3 * 4, 0.32**3 * 3 * 4 * 5
    assert dist.mean_radius_um == pytest.approx(m1, rel=1e-14)
    assert dist.area_mean_radius_um == pytest.approx(math.sqrt(m2), rel=1e-14)
    assert dist.volume_mean_radius_um == pytest.approx(m3 ** (1 / 3), rel=1e-14)
    assert dist.mean_cross_section_um2 == pytest.approx(math.pi * m2, rel=1e-14)
    assert dist.mean_volume_um3 == pytest.approx(4 / 3 * math.pi * m3, rel=1e-14)
    # Brief, section 5: the number-mean geometric cross-section of this dust is 3.86 um^2.
    assert dist.mean_cross_section_um2 == pytest.approx(3.86, abs=0.005)


def test_pdf_shapes_and_edges() -> None:
    dist = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    assert isinstance(dist.pdf(1.0), float)
    assert np.shape(dist.pdf(np.ones((2, 3)))) == (2, 3)
    for d in (
        dist,
        ModifiedGamma(r_eff_um=1.0, v_eff=0.45),
        Gamma(shape=1.0, scale_um=1.0),
        LogNormal(median_radius_um=1.0, sigma=0.3),
    ):
        np.testing.assert_array_equal(d.pdf([-1.0, 0.0]), [0.0, 0.0])
        assert math.isnan(d.pdf(math.nan))


# ------------------------------------------------------------- tail fractions


@FAST
@given(dist=continuous, factor=st.floats(0.1, 6.0), k=st.sampled_from([0, 2, 3, 6]))
def test_tail_fractions_match_quadrature(dist: SizeDistribution, factor: float, k: int) -> None:
    r = factor * dist.r_eff_um
    total = dist.moment(k)
    above = quad_moment(dist, k, lo_um=r) / total
    below = quad_moment(dist, k, hi_um=r) / total
    assert dist.moment_tail_fraction(k, r, upper=True) == pytest.approx(above, rel=1e-7, abs=1e-12)
    assert dist.moment_tail_fraction(k, r, upper=False) == pytest.approx(below, rel=1e-7, abs=1e-12)


def test_tail_fraction_edges_and_shapes() -> None:
    for dist in (Gamma(shape=3.0, scale_um=0.32), LogNormal(median_radius_um=1.0, sigma=0.5)):
        out = dist.moment_tail_fraction(2, [[-1.0, 0.0, np.inf]], upper=True)
        assert np.shape(out) == (1, 3)
        np.testing.assert_array_equal(out, [[1.0, 1.0, 0.0]])
        np.testing.assert_array_equal(
            dist.moment_tail_fraction(2, [-1.0, 0.0, np.inf], upper=False), [0.0, 0.0, 1.0]
        )
        assert math.isnan(dist.moment_tail_fraction(0, math.nan, upper=True))
        r = np.geomspace(0.05, 10, 7)
        np.testing.assert_allclose(
            dist.moment_tail_fraction(3, r, upper=True)
            + dist.moment_tail_fraction(3, r, upper=False),
            1.0,
            rtol=1e-14,
        )


@FAST
@given(dist=continuous, factor=st.floats(0.1, 6.0))
def test_tail_fractions_are_ordered_in_moment(dist: SizeDistribution, factor: float) -> None:
    # Higher moments put more weight at large radii (likelihood-ratio ordering):
    # this is what makes radius_bounds_um valid for every order in between.
    r = factor * dist.r_eff_um
    above = [dist.moment_tail_fraction(k, r, upper=True) for k in (0, 1, 2, 3, 4, 6)]
    assert all(a <= b * (1 + 1e-12) + 1e-300 for a, b in itertools.pairwise(above))


# ------------------------------------------------------------------- bounds


@FAST
@given(
    dist=continuous,
    eps=st.sampled_from([0.1, 1e-3, 1e-6, 1e-9]),
    orders=st.sampled_from([(0.0, 6.0), (0.0, 2.0), (2.0, 3.0), (3.0, 3.0)]),
)
def test_radius_bounds_bound_the_tails(
    dist: SizeDistribution, eps: float, orders: tuple[float, float]
) -> None:
    check_bounds(dist, eps, *orders)


@pytest.mark.parametrize("eps", [1e-2, 1e-4, 1e-8])
def test_radius_bounds_are_exact_quantiles_for_one_mode(eps: float) -> None:
    for dist in (ModifiedGamma(r_eff_um=1.6, v_eff=0.2), MARS_COARSE):
        r_lo, r_hi = dist.radius_bounds_um(tail_fraction=eps)
        assert dist.moment_tail_fraction(0, r_lo, upper=False) == pytest.approx(eps, rel=1e-9)
        assert dist.moment_tail_fraction(6, r_hi, upper=True) == pytest.approx(eps, rel=1e-9)
        assert quad_moment(dist, 0, hi_um=r_lo) == pytest.approx(eps, rel=1e-7)


# ------------------------------------------------------------- monodisperse


def test_monodisperse() -> None:
    dist = Monodisperse(radius_um=0.8)
    assert dist.is_monodisperse and not dist.has_density
    with pytest.raises(TypeError, match="no probability density"):
        dist.pdf(0.8)
    assert dist.moment(3) == pytest.approx(0.8**3)
    assert dist.r_eff_um == 0.8 and dist.v_eff == 0.0
    np.testing.assert_array_equal(
        dist.moment_tail_fraction(2, [0.5, 0.8, 1.0], upper=True), [1.0, 0.0, 0.0]
    )
    np.testing.assert_array_equal(
        dist.moment_tail_fraction(2, [0.5, 0.8, 1.0], upper=False), [0.0, 1.0, 1.0]
    )
    assert dist.radius_bounds_um(tail_fraction=1e-3) == (0.8, 0.8)


# ------------------------------------------ more families from the literature


@pytest.mark.parametrize(
    ("alpha", "b", "gamma"), [(2.0, 15.1186, 0.5), (6.0, 1.5, 1.0), (1.0, 8.9443, 0.5)]
)
def test_deirmendjian_gamma(alpha: float, b: float, gamma: float) -> None:
    """Haze L, Cloud C.1 and Haze M of Deirmendjian (1969); mode radii 0.07,
    4 and 0.05 um (his r_c), the density's maximum."""
    d = DeirmendjianGamma(alpha=alpha, b=b, gamma=gamma)
    check_against_density(d, 1e-9, 400.0)
    r_c = {2.0: 0.07, 6.0: 4.0, 1.0: 0.05}[alpha]
    assert d.mode_radius_um == pytest.approx(r_c, rel=1e-4)
    r = np.array([0.98, 1.0, 1.02]) * d.mode_radius_um
    values = d.pdf(r)
    assert values[1] > values[0] and values[1] > values[2]


def test_power_law() -> None:
    d = PowerLaw(exponent=4.0, r_min_um=0.05, r_max_um=10.0)
    check_against_density(d, 0.05, 10.0)
    assert d.pdf(0.04) == 0.0 and d.pdf(11.0) == 0.0
    # nu = 1: ln-uniform, int r^-1 = ln(r_max / r_min) (the p = 0 branch).
    flat = PowerLaw(exponent=1.0, r_min_um=0.1, r_max_um=10.0)
    assert flat.moment(0.0) == pytest.approx(1.0)
    assert flat.moment_tail_fraction(0.0, 1.0, upper=True) == pytest.approx(0.5)


# ----------------------------------------------------------------- truncation


def test_truncation_of_any_distribution() -> None:
    """A truncated distribution's moments against quad of the parent's density
    on [r_min, r_max], renormalized."""
    parent = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    t = parent.truncated(r_min_um=0.1, r_max_um=3.0)
    assert isinstance(t, Truncated)
    check_against_density(t, 0.1, 3.0)
    inside = quad(lambda r: float(parent.pdf(r)), 0.1, 3.0)
    assert t.pdf(1.0) == pytest.approx(float(parent.pdf(1.0)) / inside, rel=1e-10)
    assert t.pdf(3.5) == 0.0
    # Truncated log-normal (the IPRT and libRadtran way), open above.
    ln = LogNormal(median_radius_um=0.2, sigma=0.6).truncated(r_min_um=0.05)
    check_against_density(ln, 0.05, 200.0)
    # A truncated distribution truncated again.
    twice = t.truncated(r_min_um=0.5, r_max_um=2.0)
    assert twice.moment(3.0) == pytest.approx(
        parent.truncated(r_min_um=0.5, r_max_um=2.0).moment(3.0), rel=1e-10
    )


def test_truncation_open_above_is_recorded_and_computed() -> None:
    """r_max_um = inf (the default) is recorded as null, JSON having no infinity, and read
    back as inf; a table is computed from it (issue 29: it failed after the work)."""
    import json

    import dustoptics as do
    from dustoptics.particles.custom_sizedist import from_dict

    t = ModifiedGamma(r_eff_um=1.0, v_eff=0.2).truncated(r_min_um=0.5)
    record = t.to_dict()
    assert record["parameters"]["r_max_um"] is None
    json.dumps(record, allow_nan=False)
    assert from_dict(record) == t and from_dict(record).r_max_um == math.inf
    table = do.compute_optics(1.5, t, [550.0], [0.0, 180.0], rtol=1e-2)
    assert table.provenance.inputs["size_distribution"]["parameters"]["r_max_um"] is None


# -------------------------------------------------------------- provenance


def test_to_dict_and_immutability() -> None:
    dist = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    d = dist.to_dict()
    assert d["model"] == "modified_gamma"
    assert "doi:10.1007/BF00168069" in d["citation"] == dist.citation
    assert d["parameters"] == {"r_eff_um": 1.6, "v_eff": 0.2}
    assert d["derived"] == {"r_eff_um": 1.6, "v_eff": 0.2}
    assert LogNormal(median_radius_um=1.0, sigma=0.2).to_dict()["parameters"] == {
        "median_radius_um": 1.0,
        "sigma": 0.2,
    }
    with pytest.raises(dataclasses.FrozenInstanceError):
        dist.v_eff = 0.3  # type: ignore[misc]
    with pytest.raises(TypeError):
        ModifiedGamma(1.6, 0.2)  # type: ignore[call-arg]  # keyword-only
    assert dist == ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    assert len({dist, ModifiedGamma(r_eff_um=1.6, v_eff=0.2), MARS_COARSE}) == 2
    assert "r_eff_um=1.6" in repr(dist)


# --------------------------------------------------------------- bad input

BAD_CONSTRUCTIONS: list[tuple[Callable[[], object], str]] = [
    (lambda: ModifiedGamma(r_eff_um=0.0, v_eff=0.2), r"r_eff_um must be > 0 um; got 0\.0"),
    (lambda: ModifiedGamma(r_eff_um=-1.0, v_eff=0.2), r"r_eff_um must be > 0"),
    (
        lambda: ModifiedGamma(r_eff_um=1.6, v_eff=0.0),
        r"v_eff must be in \[0\.0001, 0\.5\) \(narrower populations: use Monodisperse\); got 0\.0",
    ),
    (lambda: ModifiedGamma(r_eff_um=1.6, v_eff=0.5), r"v_eff .*\[0\.0001, 0\.5\).*0\.5"),
    (lambda: ModifiedGamma(r_eff_um=1.6, v_eff=-0.1), r"v_eff .*\[0\.0001, 0\.5\)"),
    (
        lambda: ModifiedGamma(r_eff_um=math.nan, v_eff=0.2),
        r"r_eff_um must be a finite real number; got nan",
    ),
    (
        lambda: ModifiedGamma(r_eff_um=1.6, v_eff=math.inf),
        r"v_eff must be a finite real number; got inf",
    ),
    (lambda: Gamma(shape=0.0, scale_um=1.0), r"shape must be > 0; got 0\.0"),
    (lambda: Gamma(shape=-2.0, scale_um=1.0), r"shape must be > 0; got -2\.0"),
    (lambda: Gamma(shape=2.0, scale_um=math.nan), r"scale_um must be a finite real number"),
    (
        lambda: LogNormal(median_radius_um=1.0, sigma=0.0),
        r"sigma must be in \[0\.0099\d*, 3\].*got 0\.0",
    ),
    (lambda: LogNormal(median_radius_um=-1.0, sigma=0.3), r"median_radius_um must be > 0 um"),
    (lambda: ModifiedLogNormal(r_eff_um=1.0, v_eff=0.0), r"v_eff must be in \[0\.0001, .*got 0\.0"),
    (
        lambda: ModifiedLogNormal(r_eff_um=math.inf, v_eff=0.1),
        r"r_eff_um must be a finite real number",
    ),
    (lambda: Monodisperse(radius_um=0.0), r"radius_um must be > 0 um; got 0\.0"),
    (
        lambda: ModifiedGamma(r_eff_um=1.0, v_eff=0.1).truncated(r_min_um=50.0, r_max_um=60.0),
        "remove the whole",
    ),
    (
        lambda: ModifiedGamma(r_eff_um=1.0, v_eff=0.1).truncated(r_min_um=2.0, r_max_um=1.0),
        "r_min_um < r_max_um",
    ),
    (lambda: Monodisperse(radius_um=1.0).truncated(r_min_um=2.0), "remove the whole"),
    (lambda: DeirmendjianGamma(alpha=-1.5, b=1.0, gamma=1.0), r"alpha must be > -1"),
    (lambda: DeirmendjianGamma(alpha=1.0, b=-1.0, gamma=1.0), "b"),
    (
        lambda: PowerLaw(exponent=3.0, r_min_um=1.0, r_max_um=0.5),
        "r_max_um must be finite and > r_min_um",
    ),
]


@pytest.mark.parametrize(("build", "message"), BAD_CONSTRUCTIONS)
def test_bad_parameters_raise(build: Callable[[], object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build()


def test_bad_method_arguments_raise() -> None:
    dist = ModifiedGamma(r_eff_um=1.0, v_eff=0.45)  # shape = 2/9
    with pytest.raises(ValueError, match=r"k must be > -shape = -0\.222.*; got -0\.5"):
        dist.moment(-0.5)
    with pytest.raises(ValueError, match="k must be a finite real number; got nan"):
        dist.moment(math.nan)
    with pytest.raises(ValueError, match=r"k must be > -shape"):
        dist.moment_tail_fraction(-1.0, 1.0, upper=True)
    with pytest.raises(ValueError, match=r"k must be > -shape"):
        dist.radius_bounds_um(tail_fraction=1e-3, lower_moment=-1.0)
    for eps in (0.0, 0.5, -1e-3, math.nan):
        with pytest.raises(ValueError, match=r"tail_fraction must .*"):
            dist.radius_bounds_um(tail_fraction=eps)
    with pytest.raises(
        ValueError, match=r"tail_fraction must be in the open interval \(0\.0, 0\.5\)"
    ):
        dist.radius_bounds_um(tail_fraction=0.5)
    with pytest.raises(ValueError, match="lower_moment must be <= upper_moment"):
        dist.radius_bounds_um(tail_fraction=1e-3, lower_moment=3.0, upper_moment=2.0)
    with pytest.raises(TypeError):
        dist.moment_tail_fraction(2, 1.0, True)  # type: ignore[call-arg]  # keyword-only


def test_the_families_register_themselves_once() -> None:
    """The registry holds every family by its model name; a second class with a taken name fails."""
    from dustoptics.particles import sizedist as sd

    assert sd.SIZE_DISTRIBUTIONS["modified_gamma"] is sd.ModifiedGamma
    assert sd.get_size_distribution("deirmendjian1969_modified_gamma") is sd.DeirmendjianGamma
    assert len(sd.SIZE_DISTRIBUTIONS) == 11  # 10 families a TOML file can name + density_function
    with pytest.raises(ValueError, match="'gamma' is already registered by Gamma"):

        class Other(sd.Gamma):
            model = "gamma"

    assert sd.SIZE_DISTRIBUTIONS["gamma"] is sd.Gamma
    with pytest.raises(ValueError, match="size distribution model must be one of 'modified_gamma'"):
        sd.get_size_distribution("lognormal")
