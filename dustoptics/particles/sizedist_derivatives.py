"""Derivatives of normalized number size distributions with respect to their parameters.

For a size distribution n(r; p) normalized to 1 (:mod:`dustoptics.particles.sizedist`,
:mod:`dustoptics.particles.custom_sizedist`), :func:`number_density_derivative`
gives dn/dp at given radii in closed form, for every named parameter p of the
analytic families, of a mixture's modes and relative number densities, and of
a truncation.  These are the differentiated quadrature weights of a
polydisperse average: with the nodes r_i and the weights w_i = n(r_i) J_i of a
fixed quadrature (J_i the rule's weight in r),

    <C> = int n C dr ~ sum_i J_i n(r_i) C(r_i),
    d<C>/dp ~ sum_i J_i (dn/dp)(r_i) C(r_i) = sum_i w_i [(dn/dp) / n](r_i) C(r_i)

(``tests/reference/derivatives.py`` writes the rest of the chain).

Where p moves an end of the support (:class:`~dustoptics.particles.sizedist.PowerLaw`'s
``r_min_um`` and ``r_max_um``, :class:`~dustoptics.particles.sizedist.Truncated`'s
bounds), dn/dp holds a point mass at that end besides the function: by
Leibniz's rule d/dp int_a^b n C dr = int_a^b (dn/dp) C dr + n(b) C(b) db/dp -
n(a) C(a) da/dp.  :func:`number_density_derivative` returns the function (the
derivative inside the support) and :func:`boundary_terms` the point masses, as
(radius, coefficient) pairs; both together integrate to 0 (the density stays
normalized), which the tests check with ``scipy.integrate.quad``.

Parameter names are the classes' numeric ``parameters`` (``"r_eff_um"``,
``"v_eff"``, ...); a mixture's are ``"modes[i].<name>"`` and
``"relative_number_densities[i]"``, a truncation's parent's ``"parent.<name>"``,
nested as deep as the distribution is (``"modes[1].parent.v_eff"``).  :func:`parameter_names` lists them,
:func:`parameter_value` reads one and :func:`with_parameter` makes the
distribution with one of them changed (for finite differences).

Closed forms, with L = d ln n / dp (so dn/dp = n L):

- gamma, shape alpha and scale theta: L_alpha = ln(r / theta) - psi(alpha),
  L_theta = (r / theta - alpha) / theta (psi the digamma function);
  :class:`~dustoptics.particles.sizedist.ModifiedGamma` by the chain rule through
  alpha = 1 / v_eff - 2, theta = r_eff v_eff;
- log-normal, z = (ln r - mu) / sigma: L_mu = z / sigma,
  L_sigma = (z^2 - 1) / sigma; ``median_radius_um`` through mu = ln r_med,
  :class:`~dustoptics.particles.sizedist.ModifiedLogNormal` through
  mu = ln r_eff - 5/2 ln(1 + v_eff), sigma = sqrt(ln(1 + v_eff));
- Deirmendjian, s = (alpha + 1) / gamma: L_alpha = ln r + (ln b - psi(s)) / gamma,
  L_b = s / b - r^gamma, L_gamma = 1 / gamma - (s / gamma)(ln b - psi(s)) - b r^gamma ln r;
- power law on [a, b]: L_nu = <ln r> - ln r (the mean of ln r in closed form);
  inside, L_a = n(a) and L_b = -n(b), with the point masses -n(a) at a and +n(b) at b;
- a mixture, n = sum_i w_i n_i with w_i = d_i / D, D = sum_j d_j:
  dn/dp_i = w_i dn_i/dp_i for a mode's parameter and dn/dd_i = (n_i - n) / D;
- a truncation to [a, b], n_T = n / Z with Z = int_a^b n dr: for a parameter q
  of the parent, dn_T/dq = (dn/dq - n_T Z_q) / Z with Z_q = int_a^b dn/dq dr
  (by ``scipy.integrate.quad`` on ln r, relative tolerance 1e-12, over [a, b]
  or, when it holds most of the parent, as minus the integral outside it; the
  parent's own point masses count too); for the bounds, inside
  dn_T/da = n_T n_T(a) and dn_T/db = -n_T n_T(b), with the point masses
  -n_T(a) at a and +n_T(b) at b.

A :class:`~dustoptics.particles.sizedist.Monodisperse` distribution has no
density and its radius no density derivative (dn/dr_0 = -delta'(r - r_0)): the
derivative of an average with respect to its radius is that of the sphere's own
quantity (:func:`dustoptics.scattering.mie_derivatives.sphere_derivatives`,
d/dx); :func:`number_density_derivative` raises TypeError for it.
Distributions given by a table or a function have no named parameters.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from functools import lru_cache, singledispatch

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import special

from dustoptics.particles.custom_sizedist import MultiModal
from dustoptics.particles.sizedist import (
    SIZE_DISTRIBUTIONS,
    DeirmendjianGamma,
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    PowerLaw,
    SizeDistribution,
    Truncated,
    _as_radius,
)

__all__ = [
    "boundary_terms",
    "number_density_derivative",
    "parameter_names",
    "parameter_value",
    "with_parameter",
]

Array = NDArray[np.float64]


def _own(cls: type[SizeDistribution]) -> tuple[str, ...]:
    """A family's own numeric parameters, from its registry record (in the order of its fields)."""
    return tuple(p.name for p in cls.parameters if p.kind == "number")


def _differentiable() -> tuple[type[SizeDistribution], ...]:
    """The registered families given by numbers alone (a table or a function has none)."""
    return tuple(
        cls
        for cls in SIZE_DISTRIBUTIONS.values()
        if cls.parameters and all(p.kind in ("number", "distribution") for p in cls.parameters)
    )


_INDEXED = re.compile(r"^(modes|relative_number_densities)\[(\d+)\]$")


# ----------------------------------------------------------------- parameter names


def parameter_names(distribution: SizeDistribution) -> tuple[str, ...]:
    """The parameters :func:`number_density_derivative` accepts for ``distribution``.

    Parameters
    ----------
    distribution : SizeDistribution
        Any distribution of :mod:`dustoptics.particles.sizedist` or a
        :class:`~dustoptics.particles.custom_sizedist.MultiModal` of them.

    Returns
    -------
    tuple of str
        Field names, ``"modes[i].<name>"``, ``"relative_number_densities[i]"``
        and ``"parent.<name>"`` as the distribution nests them.

    Raises
    ------
    ValueError
        A distribution without named parameters (a table or a density function).

    Examples
    --------
    >>> from dustoptics.particles.sizedist import ModifiedGamma
    >>> parameter_names(ModifiedGamma(r_eff_um=1.6, v_eff=0.2))
    ('r_eff_um', 'v_eff')
    """
    if isinstance(distribution, MultiModal):
        names: list[str] = []
        for i, mode in enumerate(distribution.modes):
            names.extend(f"modes[{i}].{p}" for p in parameter_names(mode))
        names.extend(f"relative_number_densities[{i}]" for i in range(len(distribution.modes)))
        return tuple(names)
    if isinstance(distribution, Truncated):
        # A bound at 0 or infinity is the end of the parent's support: one-sided, left out.
        own = tuple(
            name
            for name, bound in zip(
                _own(Truncated), (distribution.r_min_um, distribution.r_max_um), strict=True
            )
            if 0.0 < bound < math.inf
        )
        return tuple(f"parent.{p}" for p in parameter_names(distribution.parent)) + own
    families = _differentiable()
    if type(distribution) in families:
        return _own(type(distribution))
    raise ValueError(
        f"distribution {distribution!r} has no named parameters to differentiate; allowed: "
        f"{', '.join(c.__name__ for c in families)}, MultiModal (and their nesting)"
    )


def _split(parameter: str) -> tuple[str, str | None]:
    """``"modes[1].parent.v_eff"`` -> (``"modes[1]"``, ``"parent.v_eff"``)."""
    head, _, rest = parameter.partition(".")
    return head, (rest or None)


def _unknown(distribution: SizeDistribution, parameter: object) -> ValueError:
    try:
        allowed = ", ".join(map(repr, parameter_names(distribution)))
    except ValueError as exc:
        return exc
    if isinstance(distribution, Truncated) and parameter in _own(Truncated):
        return ValueError(
            f"the derivative with respect to {parameter} = {getattr(distribution, parameter)!r} "
            f"of {distribution!r} is one-sided (a bound at 0 or infinity is the end of the "
            f"parent's support); parameter must be one of {allowed}"
        )
    return ValueError(
        f"parameter must be one of {allowed} for {type(distribution).__name__}; got {parameter!r}"
    )


def _check(distribution: SizeDistribution, parameter: object) -> str:
    if not isinstance(distribution, SizeDistribution):
        raise TypeError(f"distribution must be a SizeDistribution; got {distribution!r}")
    if not isinstance(parameter, str) or parameter not in parameter_names(distribution):
        raise _unknown(distribution, parameter)
    return parameter


def parameter_value(distribution: SizeDistribution, parameter: str) -> float:
    """The value of one named parameter (see :func:`parameter_names`).

    Examples
    --------
    >>> from dustoptics.particles.sizedist import LogNormal
    >>> parameter_value(LogNormal(median_radius_um=0.5, sigma=0.4), "sigma")
    0.4
    """
    _check(distribution, parameter)
    head, rest = _split(parameter)
    indexed = _INDEXED.match(head)
    if indexed:
        assert isinstance(distribution, MultiModal)
        i = int(indexed.group(2))
        if indexed.group(1) == "relative_number_densities":
            return float(distribution.relative_number_densities[i])
        assert rest is not None
        return parameter_value(distribution.modes[i], rest)
    if head == "parent" and rest is not None:
        assert isinstance(distribution, Truncated)
        return parameter_value(distribution.parent, rest)
    return float(getattr(distribution, head))


def with_parameter(
    distribution: SizeDistribution, parameter: str, value: float
) -> SizeDistribution:
    """A copy of ``distribution`` with one named parameter set to ``value``.

    The copy is constructed anew, so it is validated as any distribution.

    Examples
    --------
    >>> from dustoptics.particles.sizedist import ModifiedGamma
    >>> with_parameter(ModifiedGamma(r_eff_um=1.6, v_eff=0.2), "v_eff", 0.25)
    ModifiedGamma(r_eff_um=1.6, v_eff=0.25)
    """
    _check(distribution, parameter)
    head, rest = _split(parameter)
    indexed = _INDEXED.match(head)
    if indexed:
        assert isinstance(distribution, MultiModal)
        i = int(indexed.group(2))
        if indexed.group(1) == "relative_number_densities":
            densities = list(distribution.relative_number_densities)
            densities[i] = value
            return dataclasses.replace(distribution, relative_number_densities=tuple(densities))
        assert rest is not None
        modes = list(distribution.modes)
        modes[i] = with_parameter(modes[i], rest, value)
        return dataclasses.replace(distribution, modes=tuple(modes))
    if head == "parent" and rest is not None:
        assert isinstance(distribution, Truncated)
        return dataclasses.replace(
            distribution, parent=with_parameter(distribution.parent, rest, value)
        )
    return dataclasses.replace(distribution, **{head: value})  # type: ignore[type-var]


# ------------------------------------------------------------------- derivatives


def number_density_derivative(
    distribution: SizeDistribution, radius_um: ArrayLike, parameter: str
) -> NDArray[np.float64]:
    """dn/dp of a normalized number density at given radii, in closed form.

    Parameters
    ----------
    distribution : SizeDistribution
        The distribution n(r; p), normalized to 1. [um^-1]
    radius_um : array_like
        Radii. [um]
    parameter : str
        A name of :func:`parameter_names`.

    Returns
    -------
    numpy.ndarray
        dn/dp with the shape of ``radius_um``: 0 outside the support (and at
        r <= 0), NaN where ``radius_um`` is NaN. [um^-1 per unit of p]  Where p
        moves an end of the support this is the derivative inside it; the point
        masses at the ends are :func:`boundary_terms`.

    Raises
    ------
    ValueError
        An unknown parameter (the message lists the allowed ones).
    TypeError
        ``distribution`` is not a SizeDistribution, or has no density (a
        :class:`~dustoptics.particles.sizedist.Monodisperse` radius: see the
        module docstring).

    Examples
    --------
    >>> from dustoptics.particles.sizedist import ModifiedGamma
    >>> d = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    >>> [round(float(v), 6) for v in number_density_derivative(d, [0.5, 1.0], "r_eff_um")]
    [-0.718394, 0.052377]
    """
    _check(distribution, parameter)
    r = _as_radius(radius_um)
    return _derivative(distribution, r, parameter)


def boundary_terms(
    distribution: SizeDistribution, parameter: str
) -> tuple[tuple[float, float], ...]:
    """Point masses of dn/dp where p moves an end of the support.

    Returns ``((radius_um, coefficient), ...)`` such that
    dn/dp = :func:`number_density_derivative` + sum coefficient delta(r - radius_um);
    empty for parameters that do not move an end.  [um, um^-1 per unit of p]

    Raises
    ------
    ValueError
        An unknown parameter (a truncation's bound at 0 or infinity is none:
        its derivative is one-sided).

    Examples
    --------
    >>> from dustoptics.particles.sizedist import PowerLaw
    >>> boundary_terms(PowerLaw(exponent=3.0, r_min_um=0.1, r_max_um=1.0), "r_min_um")
    ((0.1, -20.202020202020204),)
    """
    _check(distribution, parameter)
    return _boundary(distribution, parameter)


def _nonzero_product(n: Array, log_derivative: Array, r: Array) -> Array:
    """n L, with 0 where n is 0 (L may be infinite there) and NaN where r is."""
    with np.errstate(invalid="ignore", over="ignore"):
        out = np.where(n > 0.0, n * log_derivative, 0.0)
    return np.where(np.isnan(r), np.nan, out)


def _log_r(r: Array) -> Array:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(np.where(r > 0.0, r, np.nan))


@singledispatch
def _derivative(distribution: SizeDistribution, r: Array, parameter: str) -> Array:
    raise _unknown(distribution, parameter)


@singledispatch
def _boundary(distribution: SizeDistribution, parameter: str) -> tuple[tuple[float, float], ...]:
    return ()


def _gamma_log_derivatives(shape: float, scale: float, r: Array) -> tuple[Array, Array]:
    """(L_shape, L_scale) of a gamma density."""
    with np.errstate(divide="ignore", invalid="ignore"):
        l_shape = _log_r(r) - math.log(scale) - special.digamma(shape)
        l_scale = (r / scale - shape) / scale
    return l_shape, l_scale


@_derivative.register
def _(distribution: Gamma, r: Array, parameter: str) -> Array:
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    l_shape, l_scale = _gamma_log_derivatives(distribution.shape, distribution.scale_um, r)
    return _nonzero_product(n, l_shape if parameter == "shape" else l_scale, r)


@_derivative.register
def _(distribution: ModifiedGamma, r: Array, parameter: str) -> Array:
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    a, b = distribution.r_eff_um, distribution.v_eff
    l_shape, l_scale = _gamma_log_derivatives(distribution.shape, distribution.scale_um, r)
    # shape = 1/b - 2, scale = a b.
    if parameter == "r_eff_um":
        return _nonzero_product(n, l_scale * b, r)
    return _nonzero_product(n, -l_shape / (b * b) + l_scale * a, r)


def _log_normal_log_derivatives(mu: float, sigma: float, r: Array) -> tuple[Array, Array]:
    """(L_mu, L_sigma) of a log-normal density."""
    z = (_log_r(r) - mu) / sigma
    return z / sigma, (z * z - 1.0) / sigma


@_derivative.register
def _(distribution: LogNormal, r: Array, parameter: str) -> Array:
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    mu, sigma = distribution._mu_sigma()
    l_mu, l_sigma = _log_normal_log_derivatives(mu, sigma, r)
    if parameter == "median_radius_um":
        return _nonzero_product(n, l_mu / distribution.median_radius_um, r)
    return _nonzero_product(n, l_sigma, r)


@_derivative.register
def _(distribution: ModifiedLogNormal, r: Array, parameter: str) -> Array:
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    mu, sigma = distribution._mu_sigma()
    l_mu, l_sigma = _log_normal_log_derivatives(mu, sigma, r)
    v = distribution.v_eff
    # mu = ln r_eff - 5/2 ln(1 + v), sigma = sqrt(ln(1 + v)).
    if parameter == "r_eff_um":
        return _nonzero_product(n, l_mu / distribution.r_eff_um, r)
    return _nonzero_product(n, -2.5 / (1.0 + v) * l_mu + l_sigma / (2.0 * sigma * (1.0 + v)), r)


@_derivative.register
def _(distribution: DeirmendjianGamma, r: Array, parameter: str) -> Array:
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    alpha, b, gamma = distribution.alpha, distribution.b, distribution.gamma
    s = (alpha + 1.0) / gamma
    log_r = _log_r(r)
    with np.errstate(invalid="ignore", over="ignore"):
        r_gamma = np.where(r > 0.0, np.abs(r) ** gamma, np.nan)
        common = math.log(b) - float(special.digamma(s))
        if parameter == "alpha":
            log_derivative = log_r + common / gamma
        elif parameter == "b":
            log_derivative = s / b - r_gamma
        else:
            log_derivative = 1.0 / gamma - s / gamma * common - b * r_gamma * log_r
    return _nonzero_product(n, log_derivative, r)


def _power_law_mean_log(distribution: PowerLaw) -> float:
    """<ln r> of a power law on [a, b]: ln a + E[t], t = ln(r / a) with density
    ~ exp(p t) on [0, L], p = 1 - nu, L = ln(b / a):
    E[t] = L / (1 - exp(-p L)) - 1 / p, or its series L/2 + p L^2/12 - p^3 L^4/720 near p L = 0."""
    a, b = distribution.r_min_um, distribution.r_max_um
    p = 1.0 - distribution.exponent
    span = math.log(b / a)
    pl = p * span
    if abs(pl) < 1e-4:
        mean_t = span / 2.0 + p * span * span / 12.0 - p**3 * span**4 / 720.0
    else:
        mean_t = span / -math.expm1(-pl) - 1.0 / p
    return math.log(a) + mean_t


@_derivative.register
def _(distribution: PowerLaw, r: Array, parameter: str) -> Array:
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    if parameter == "exponent":
        log_derivative = _power_law_mean_log(distribution) - _log_r(r)
    elif parameter == "r_min_um":
        log_derivative = np.full_like(r, float(distribution.pdf(distribution.r_min_um)))
    else:
        log_derivative = np.full_like(r, -float(distribution.pdf(distribution.r_max_um)))
    return _nonzero_product(n, log_derivative, r)


@_boundary.register
def _(distribution: PowerLaw, parameter: str) -> tuple[tuple[float, float], ...]:
    if parameter == "r_min_um":
        a = distribution.r_min_um
        return ((a, -float(distribution.pdf(a))),)
    if parameter == "r_max_um":
        b = distribution.r_max_um
        return ((b, float(distribution.pdf(b))),)
    return ()


@_derivative.register
def _(distribution: Monodisperse, r: Array, parameter: str) -> Array:
    raise TypeError(
        f"Monodisperse(radius_um={distribution.radius_um!r}) has no density, and its radius "
        "no density derivative (dn/dr0 = -delta'(r - r0)); differentiate the sphere's own "
        "quantity instead (dustoptics.scattering.mie_derivatives.sphere_derivatives, d/dx)"
    )


@_derivative.register
def _(distribution: MultiModal, r: Array, parameter: str) -> Array:
    head, rest = _split(parameter)
    indexed = _INDEXED.match(head)
    assert indexed is not None
    i = int(indexed.group(2))
    weights = distribution.number_fractions
    if indexed.group(1) == "modes":
        assert rest is not None
        return weights[i] * _derivative(distribution.modes[i], r, rest)
    # dn/dd_i = (n_i - n) / D; the weights w_i = d_i / D.
    total = distribution.relative_number_densities[i] / weights[i]
    n_i = np.asarray(distribution.modes[i].pdf(r), dtype=np.float64)
    n = np.asarray(distribution.pdf(r), dtype=np.float64)
    return np.asarray((n_i - n) / total, dtype=np.float64)


@_boundary.register
def _(distribution: MultiModal, parameter: str) -> tuple[tuple[float, float], ...]:
    head, rest = _split(parameter)
    indexed = _INDEXED.match(head)
    assert indexed is not None
    if indexed.group(1) != "modes" or rest is None:
        return ()
    i = int(indexed.group(2))
    w = distribution.number_fractions[i]
    return tuple((r, w * c) for r, c in _boundary(distribution.modes[i], rest))


def _integral(f: Callable[[Array], Array], lo: float, hi: float) -> float:
    """int_lo^hi f(r) dr by ``scipy.integrate.quad`` in u = ln r (relative 1e-12,
    absolute 1e-15: the densities are normalized to 1)."""
    if not hi > lo:
        return 0.0
    # here: scipy.integrate (with scipy.optimize, linalg, sparse) is 0.25 s of a warm
    # `dustoptics build`'s CPU, and only truncated distributions' derivatives need it
    from scipy import integrate

    def g(u: float) -> float:
        r = math.exp(u)
        return float(f(np.array([r]))[0]) * r

    value, _ = integrate.quad(g, math.log(lo), math.log(hi), epsabs=1e-15, epsrel=1e-12, limit=400)
    return float(value)


@lru_cache(maxsize=256)
def _normalization_derivative(distribution: Truncated, rest: str) -> float:
    """Z_q = d/dq int_a^b n dr for a parameter q of the parent.

    The parent's density derivative integrates to 0 over its support (point
    masses included), so Z_q is also minus its integral outside [a, b]; the
    smaller of the two ranges (by number) is integrated, within the radii
    holding all but 1e-15 of the parent's number, where the rest is negligible.
    Cached: a quadrature's nodes ask for it once per call.
    """
    parent = distribution.parent
    a, b = distribution.r_min_um, distribution.r_max_um
    lo, hi = parent._bounds(1e-15, 0.0, 0.0)

    def dn(x: Array) -> Array:
        return _derivative(parent, x, rest)

    masses = _boundary(parent, rest)
    if distribution._inside(0.0) <= 0.5:
        inside = _integral(dn, max(a, lo), min(b, hi))
        return inside + sum(c for rb, c in masses if a <= rb <= b)
    outside = _integral(dn, lo, min(a, hi)) + _integral(dn, max(b, lo), hi)
    return -(outside + sum(c for rb, c in masses if not a <= rb <= b))


@_derivative.register
def _(distribution: Truncated, r: Array, parameter: str) -> Array:
    a, b = distribution.r_min_um, distribution.r_max_um
    z = distribution._inside(0.0)
    n_t = np.asarray(distribution.pdf(r), dtype=np.float64)
    inside = (r >= a) & (r <= b)
    head, rest = _split(parameter)
    if head == "parent" and rest is not None:
        z_q = _normalization_derivative(distribution, rest)
        out = np.where(inside, (_derivative(distribution.parent, r, rest) - n_t * z_q) / z, 0.0)
    elif head == "r_min_um":
        out = n_t * float(distribution.pdf(a))
    else:
        out = -n_t * float(distribution.pdf(b))
    return np.where(np.isnan(r), np.nan, out)


@_boundary.register
def _(distribution: Truncated, parameter: str) -> tuple[tuple[float, float], ...]:
    head, rest = _split(parameter)
    a, b = distribution.r_min_um, distribution.r_max_um
    z = distribution._inside(0.0)
    if head == "parent" and rest is not None:
        return tuple((rb, c / z) for rb, c in _boundary(distribution.parent, rest) if a <= rb <= b)
    if head == "r_min_um":
        return ((a, -float(distribution.pdf(a))),)
    return ((b, float(distribution.pdf(b))),)
