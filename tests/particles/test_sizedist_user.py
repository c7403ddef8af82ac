"""Size distributions users bring: Deirmendjian's modified gamma, power law,
tabulated tables, truncation of any distribution, and a density function.

Every moment and tail fraction is checked against ``scipy.integrate.quad`` of
the density itself (in ln r, relative tolerance 1e-12), which shares no code
with the closed forms (incomplete gamma functions, segment integrals).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

import dustoptics as do
from dustoptics.particles.sizedist import (
    DeirmendjianGamma,
    DensityDistribution,
    ModifiedGamma,
    PowerLaw,
    SizeDistribution,
    TabulatedDistribution,
    Truncated,
)


def quad(f, lo: float, hi: float, points=()) -> float:
    """int_lo^hi f(r) dr in ln r."""
    pts = sorted(math.log(p) for p in points if lo < p < hi)
    value, _ = integrate.quad(
        lambda t: f(math.exp(t)) * math.exp(t), math.log(lo), math.log(hi),
        points=pts or None, limit=800, epsabs=0.0, epsrel=1e-12,
    )  # fmt: skip
    return float(value)


def check_against_density(dist: SizeDistribution, lo: float, hi: float, points=()) -> None:
    """Normalization, moments 1..6 and tail fractions from the density by quad."""
    n = lambda r: float(dist.pdf(r))  # noqa: E731
    assert quad(n, lo, hi, points) == pytest.approx(1.0, rel=1e-9)
    for k in (1.0, 2.0, 3.0, 4.0, 6.0):
        assert dist.moment(k) == pytest.approx(
            quad(lambda r, k=k: r**k * n(r), lo, hi, points), rel=1e-8
        ), k
    mid = math.sqrt(lo * hi) if math.isfinite(hi) else 2.0 * dist.r_eff_um
    for k in (0.0, 3.0):
        below = quad(lambda r, k=k: r**k * n(r), lo, mid, points) / dist.moment(k)
        assert dist.moment_tail_fraction(k, mid, upper=False) == pytest.approx(
            below, rel=1e-7, abs=1e-13
        )
        assert dist.moment_tail_fraction(k, mid, upper=True) == pytest.approx(
            1 - below, rel=1e-7, abs=1e-13
        )
    r_lo, r_hi = dist.radius_bounds_um(tail_fraction=1e-6)
    assert lo * (1 - 1e-12) <= r_lo < r_hi <= hi * (1 + 1e-12)
    assert dist.moment_tail_fraction(0, r_lo, upper=False) <= 1e-6 * (1 + 1e-6)
    assert dist.moment_tail_fraction(6, r_hi, upper=True) <= 1e-6 * (1 + 1e-6)


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


def test_tabulated_dn_dr_and_dn_dlnr_and_csv(tmp_path) -> None:
    r = np.array([0.1, 0.3, 0.7, 1.5, 3.0])
    dndr = np.array([0.0, 2.0, 1.5, 0.4, 0.0])
    a = TabulatedDistribution(radius_um=r, dn_dr=dndr)
    check_against_density(a, 0.1, 3.0, points=r)
    # The same table as dN/dln r = r n(r) at the points.
    b = TabulatedDistribution(radius_um=r, dn_dlnr=r * dndr)
    np.testing.assert_allclose(b.pdf(r), a.pdf(r), rtol=1e-14)
    assert b.moment(3.0) == pytest.approx(a.moment(3.0), rel=1e-14)
    path = tmp_path / "sizes.csv"
    path.write_text(
        "# measured\nradius_um,dn_dlnr\n" + "".join(f"{x},{y}\n" for x, y in zip(r, r * dndr))
    )
    c = TabulatedDistribution.from_csv(path)
    assert c.moment(2.0) == pytest.approx(a.moment(2.0), rel=1e-14)


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
    ln = do.LogNormal(median_radius_um=0.2, sigma=0.6).truncated(r_min_um=0.05)
    check_against_density(ln, 0.05, 200.0)
    # Nested, and a density distribution truncated.
    twice = t.truncated(r_min_um=0.5, r_max_um=2.0)
    assert twice.moment(3.0) == pytest.approx(
        parent.truncated(r_min_um=0.5, r_max_um=2.0).moment(3.0), rel=1e-10
    )


def test_density_distribution_is_the_public_way_to_define_one() -> None:
    """Any density function and bounds, no subclassing; it equals the built-in
    model with the same density (here a modified gamma on a wide range)."""
    ref = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    d = DensityDistribution(
        density=lambda r: r**2 * np.exp(-r / 0.32), r_min_um=1e-4, r_max_um=40.0, name="gamma 3"
    )
    for k in (0.0, 2.0, 3.0, 6.0):
        assert d.moment(k) == pytest.approx(ref.moment(k), rel=1e-9)
    assert d.radius_bounds_um(tail_fraction=1e-7)[1] == pytest.approx(
        ref.radius_bounds_um(tail_fraction=1e-7)[1], rel=1e-6
    )
    assert d.to_dict()["parameters"]["name"] == "gamma 3"


def test_user_distributions_through_compute_optics() -> None:
    """The radius quadrature needs only pdf and the tail bounds: a tabulated
    table that is the modified gamma's density on 400 points gives its
    optics (to the table's interpolation error, 1e-4)."""
    ref = ModifiedGamma(r_eff_um=0.5, v_eff=0.1)
    r = np.linspace(0.02, 3.0, 4000)
    tab = TabulatedDistribution(radius_um=r, dn_dr=ref.pdf(r))
    a = do.compute_optics(1.5 + 0.01j, ref, [550.0], [0.0, 90.0, 180.0])
    b = do.compute_optics(1.5 + 0.01j, tab, [550.0], [0.0, 90.0, 180.0])
    np.testing.assert_allclose(b.cext_um2, a.cext_um2, rtol=1e-4)
    np.testing.assert_allclose(b.phase, a.phase, rtol=1e-3)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (
            lambda: TabulatedDistribution(radius_um=[0.1, 0.3, 0.2], dn_dr=[1, 1, 1]),
            "strictly increasing",
        ),
        (
            lambda: TabulatedDistribution(radius_um=[0.1, 0.2, 0.2], dn_dr=[1, 1, 1]),
            "strictly increasing",
        ),
        (
            lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dr=[1, -1]),
            r"dn_dr must be finite and >= 0; got -1.0",
        ),
        (
            lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dlnr=[1, np.nan]),
            "dn_dlnr must be finite",
        ),
        (lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dr=[0, 0]), "holds no particles"),
        (
            lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dr=[1, 1], dn_dlnr=[1, 1]),
            "exactly one",
        ),
        (
            lambda: ModifiedGamma(r_eff_um=1.0, v_eff=0.1).truncated(r_min_um=50.0, r_max_um=60.0),
            "remove the whole",
        ),
        (
            lambda: ModifiedGamma(r_eff_um=1.0, v_eff=0.1).truncated(r_min_um=2.0, r_max_um=1.0),
            "r_min_um < r_max_um",
        ),
        (lambda: do.Monodisperse(radius_um=1.0).truncated(r_min_um=2.0), "remove the whole"),
        (lambda: DeirmendjianGamma(alpha=-1.5, b=1.0, gamma=1.0), r"alpha must be > -1"),
        (lambda: DeirmendjianGamma(alpha=1.0, b=-1.0, gamma=1.0), "b"),
        (
            lambda: PowerLaw(exponent=3.0, r_min_um=1.0, r_max_um=0.5),
            "r_max_um must be finite and > r_min_um",
        ),
        (
            lambda: DensityDistribution(density=lambda r: -r, r_min_um=0.1, r_max_um=1.0),
            "finite and >= 0",
        ),
    ],
)
def test_bad_input(build, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        build()
