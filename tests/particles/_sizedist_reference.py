"""Reference integrals for the size-distribution tests (test_sizedist, test_custom_sizedist).

Moments and tail fractions are checked against ``scipy.integrate.quad`` of the density,
which shares no code with the closed forms (incomplete gamma and normal functions, segment
integrals).  Quadrature runs in ``t = ln r`` (``dr = r dt``), where every integrand here is a
smooth bump, with a tolerance of 1e-12 so that 1e-8 comparisons are meaningful.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import settings
from hypothesis import strategies as st
from scipy import integrate

from dustoptics.particles.custom_sizedist import MultiModal
from dustoptics.particles.sizedist import (
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    SizeDistribution,
)

MOMENT_ORDERS = (1, 2, 3, 4, 6)
FAST = settings(max_examples=15, deadline=None)  # quad is the slow part

# CosmoScout VR, scattering-table-generator/mie-settings/mars_realistic.json.
MARS_FINE = ModifiedLogNormal(r_eff_um=0.04, v_eff=0.1)
MARS_COARSE = ModifiedLogNormal(r_eff_um=1.4, v_eff=0.35)


def _windows_ln_r(dist: SizeDistribution, k: float) -> list[tuple[float, float, float]]:
    """``(start, peak, end)`` in ln r outside which ``r^(k+1) n(r)`` is < e^-40 of its peak."""
    if isinstance(dist, MultiModal):
        return [w for mode in dist.modes for w in _windows_ln_r(mode, k)]
    if isinstance(dist, (Gamma, ModifiedGamma)):
        # In t = ln r the integrand is ~ exp(a t - e^t / scale), a = shape + k + 1,
        # i.e. exp(a (d + 1 - e^d)) times its peak at distance d from the peak:
        # exponential decay below, Gaussian of width 1/sqrt(a) near the peak for
        # large a, double-exponential decay above.
        a = dist.shape + k + 1.0
        peak = math.log(dist.scale_um * a)
        return [(peak - 40.0 / a - 12.0 / math.sqrt(a), peak, peak + 4.0)]
    assert isinstance(dist, (LogNormal, ModifiedLogNormal))
    # A Gaussian in t of width sigma, centred at mu + (k + 1) sigma^2.
    peak = math.log(dist.median_radius_um) + (k + 1.0) * dist.sigma**2
    return [(peak - 9.0 * dist.sigma, peak, peak + 9.0 * dist.sigma)]


def quad_moment(
    dist: SizeDistribution, k: float, lo_um: float = 0.0, hi_um: float = math.inf
) -> float:
    """``integral_lo^hi r^k n(r) dr`` by adaptive quadrature in ln r (gamma and
    log-normal families and mixtures of them)."""
    windows = _windows_ln_r(dist, k)
    t_lo = min(w[0] for w in windows) if lo_um <= 0.0 else math.log(lo_um)
    t_hi = max(w[2] for w in windows) if math.isinf(hi_um) else math.log(hi_um)
    if t_hi <= t_lo:
        return 0.0

    def integrand(t: float) -> float:
        r = math.exp(t)
        return float(r ** (k + 1.0)) * float(dist.pdf(r))

    inner = sorted({p for w in windows for p in w if t_lo < p < t_hi})
    value, _ = integrate.quad(
        integrand, t_lo, t_hi, points=inner or None, limit=500, epsabs=0.0, epsrel=1e-12
    )
    return float(value)


def check_bounds(dist: SizeDistribution, eps: float, lower: float, upper: float) -> None:
    """``radius_bounds_um`` leaves at most ``eps`` of the moments in each tail."""
    r_lo, r_hi = dist.radius_bounds_um(tail_fraction=eps, lower_moment=lower, upper_moment=upper)
    assert 0.0 < r_lo < r_hi
    limit = eps * (1.0 + 1e-6)
    for p in {lower, 0.5 * (lower + upper), upper}:
        total = dist.moment(p)
        assert quad_moment(dist, p, hi_um=r_lo) / total <= limit, ("below", p)
        assert quad_moment(dist, p, lo_um=r_hi) / total <= limit, ("above", p)


def quad(f, lo: float, hi: float, points=()) -> float:
    """int_lo^hi f(r) dr in ln r (any density on a finite or half-open range)."""
    pts = sorted(math.log(p) for p in points if lo < p < hi)
    value, _ = integrate.quad(
        lambda t: f(math.exp(t)) * math.exp(t), math.log(lo), math.log(hi),
        points=pts or None, limit=800, epsabs=0.0, epsrel=1e-12,
    )  # fmt: skip
    return float(value)


def check_against_density(dist: SizeDistribution, lo: float, hi: float, points=()) -> None:
    """Normalization, moments 1..6 and tail fractions from the density by quad on [lo, hi]."""
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


# ----------------------------------------------------------------- strategies

modified_gammas = st.builds(
    ModifiedGamma,
    r_eff_um=st.floats(0.05, 20.0),
    # v_eff <= 1/3 keeps shape >= 1 (no singularity at r = 0 for quad);
    # the singular range is tested separately.
    v_eff=st.floats(0.01, 0.33),
)
gammas = st.builds(Gamma, shape=st.floats(1.0, 100.0), scale_um=st.floats(0.005, 5.0))
log_normals = st.builds(
    LogNormal, median_radius_um=st.floats(0.01, 10.0), sigma=st.floats(0.05, 1.2)
)
modified_log_normals = st.builds(
    ModifiedLogNormal, r_eff_um=st.floats(0.02, 20.0), v_eff=st.floats(0.01, 1.0)
)
continuous = st.one_of(modified_gammas, gammas, log_normals, modified_log_normals)
