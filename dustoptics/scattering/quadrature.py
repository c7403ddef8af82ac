"""Deterministic quadrature over particle radius.

Polydisperse averages are integrals over the number distribution n(r),

    <C> = int n(r) C(r) dr,

whose integrands carry Mie resonances: narrow features at a roughly constant
spacing in size parameter x = 2 pi r / lambda.  Small particles (x << 1) have
smooth power-law integrands that vary on a logarithmic scale, large ones need a
resolution that is uniform in x.  The nodes are therefore placed uniformly in the
stretched variable

    s(x) = x / x_c + ln(x / x_c),     ds/dx = 1/x_c + 1/x,

which is logarithmic below the transition size parameter x_c and linear above
it, with a smooth Jacobian (its inverse is x = x_c omega(s), with omega the
Wright omega function).  The interval [s(x_lo), s(x_hi)] is first cut into
equal panels (:func:`initial_panels`), each carrying an n-point Gauss-Legendre
rule (:func:`panel_nodes`).  :func:`dustoptics.scattering.optics.compute_optics` then
refines adaptively: every panel is integrated with one rule and with one rule
on each half, the difference estimates the error, and the worst panels are
halved until the summed estimates meet the tolerances.  Resonances thus get
nodes where they are, and smooth stretches keep few.  :func:`radius_nodes`
gives uniformly refined nodes (for checks of the moments and for baselines).

Tails are truncated where the distribution's analytic moments say they are
negligible (:meth:`dustoptics.particles.sizedist.SizeDistribution.radius_bounds_um`):
below r_lo lies at most ``tail_fraction`` of the moment that normalizes the
average (number for number weighting, area for cross-section weighting), and
above r_hi at most ``tail_fraction`` of the fourth moment.  The forward peak
of the phase function, the quantity most sensitive to large spheres, scales as
the fourth moment (``|S(0)|^2 ~ x^4 Q_ext^2 / 4``, with Q_ext -> 2); every other
polydisperse quantity (cross-sections ~ r^2, the number-weighted phase
function ~ r^2 forward) with a lower one, and the tail fraction of a moment
grows with its order, so bounding the fourth bounds them all.  (The sixth
moment, used before, moved r_hi 15 % further out for the storm-dust
distribution and cost 25 % more time for no change above 1e-7.)  Random
sampling is never used.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.special import roots_legendre

from dustoptics._numba_cache import F8, F8_1D, F8_1D_RO, kernel
from dustoptics._validation import check_open_interval, check_positive
from dustoptics.particles.sizedist import SizeDistribution

__all__ = [
    "QuadratureDiagnostics",
    "QuadratureSettings",
    "RadiusNodes",
    "gauss_legendre",
    "initial_panels",
    "panel_nodes",
    "radius_nodes",
    "size_parameter_at",
]

_UPPER_MOMENT = 4


@dataclass(frozen=True)
class QuadratureSettings:
    """How radius nodes are placed.

    Parameters
    ----------
    nodes_per_panel : int
        Gauss-Legendre nodes in each panel. [-]
    panel_width : float
        Panel width at refinement level 0, in the stretched variable s; above
        the transition it is a width in size parameter divided by
        ``transition_size_parameter``. [-]
    transition_size_parameter : float
        x_c, where node spacing changes from logarithmic to uniform in x. [-]
    tail_fraction : float
        Largest fraction of the relevant moment left out at each end. [-]
    max_level : int
        Bounds the adaptive refinement: at most 2^max_level times the level-0
        panel count, i.e. panels no narrower than 2^-max_level of the initial
        ones on average. [-]
    min_panels : int
        Fewest panels at level 0, so that even a narrow distribution spanning a
        small range of s is resolved before any comparison of levels. [-]

    Notes
    -----
    The defaults (16 nodes, level-0 panels 32 wide) start coarse and let the
    adaptive refinement put nodes where the integrand needs them.  Measured
    for Mars dust (r_eff 1.6 and 4 um, rtol 1e-4), against references at
    rtol 1e-7: the same accuracy (phase function 0.5-4e-6, 25-100x inside its
    estimate) as 8 nodes on panels 2 wide, with 2.5x less time for the storm
    dust, whose level-0 panels at 2 wide spent most of the work on large
    spheres in the tail.
    """

    nodes_per_panel: int = 16
    panel_width: float = 32.0
    transition_size_parameter: float = 1.0
    tail_fraction: float = 1e-7
    max_level: int = 9
    min_panels: int = 4

    def __post_init__(self) -> None:
        if not (isinstance(self.nodes_per_panel, int) and 2 <= self.nodes_per_panel <= 64):
            raise ValueError(
                f"nodes_per_panel must be an integer in [2, 64]; got {self.nodes_per_panel!r}"
            )
        check_positive("panel_width", self.panel_width)
        check_positive("transition_size_parameter", self.transition_size_parameter)
        check_open_interval("tail_fraction", self.tail_fraction, 0.0, 0.01)
        if not (isinstance(self.max_level, int) and 0 <= self.max_level <= 16):
            raise ValueError(f"max_level must be an integer in [0, 16]; got {self.max_level!r}")
        if not (isinstance(self.min_panels, int) and 1 <= self.min_panels <= 1024):
            raise ValueError(f"min_panels must be an integer in [1, 1024]; got {self.min_panels!r}")


@dataclass(frozen=True)
class RadiusNodes:
    """Quadrature nodes for one wavelength.

    Attributes
    ----------
    size_parameter : numpy.ndarray
        x_j = 2 pi r_j / lambda, increasing. [-]
    weight : numpy.ndarray
        w_j such that sum_j w_j f(r_j) approximates int n(r) f(r) dr over the
        truncated range; n is normalized to 1, so sum w_j ~ 1. [-]
    radius_um : numpy.ndarray
        r_j. [um]
    """

    size_parameter: np.ndarray
    weight: np.ndarray
    radius_um: np.ndarray


@dataclass(frozen=True, eq=False)
class QuadratureDiagnostics:
    """Where :func:`~dustoptics.scattering.optics.compute_optics` put its radius nodes, per wavelength.

    Kept in memory with the :class:`~dustoptics.table.Table` (its
    ``diagnostics``) for scripts that study the quadrature
    (``scripts/benchmark.py`` rebuilds the nodes from it); files do not store
    it, since it follows from the table's provenance.

    Attributes
    ----------
    settings : QuadratureSettings
        Radius node placement.
    distribution : SizeDistribution
        The size distribution.
    panels : tuple of numpy.ndarray
        Per wavelength, the phase function's final panels (shape (n_panels, 2))
        in the stretched variable s of this module; each panel's two halves
        carry the Gauss-Legendre rule that gave the table, so
        :func:`panel_nodes` on the halves reproduces the nodes. [-]
    cross_section_panels : tuple of numpy.ndarray
        The same for the cross-sections and g. [-]
    expansion_panels : tuple of numpy.ndarray or None
        The same for the expansion coefficients (refined to their own
        tolerance from the phase function's panels); None without them. [-]
    """

    settings: QuadratureSettings
    distribution: SizeDistribution
    panels: tuple[np.ndarray, ...] = field(repr=False)
    cross_section_panels: tuple[np.ndarray, ...] = field(repr=False)
    expansion_panels: tuple[np.ndarray, ...] | None = field(default=None, repr=False)


@lru_cache(maxsize=64)
def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes (increasing) and weights on [-1, 1], cached by ``n``.

    From scipy.special.roots_legendre; the arrays are read-only.  Used for the
    radius panels and for the angular grid of the Legendre projection.
    """
    t, w = roots_legendre(int(n))
    t.setflags(write=False)
    w.setflags(write=False)
    return t, w


def _stretch(x: np.ndarray | float, x_c: float) -> np.ndarray | float:
    return x / x_c + np.log(x / x_c)


_EPS = float(np.finfo(np.float64).eps)


@kernel(F8)
def _wright_omega(s: float) -> float:
    """Wright omega of real s: the w > 0 with w + ln w = s.

    Lawrence, Corless & Jeffrey (2012), Algorithm 917, on the real line: a
    first guess (e^s below -2, e^(2 (s - 1) / 3) on [-2, 1), s - ln s +
    ln s / s above), one step of the fourth-order Fritsch-Shafer-Crowley
    iteration, and a second where the first's error bound,
    |(2w^2 - 8w - 1) r^4| / (72 (1 + w)^6), exceeds machine epsilon; e^s
    below s = -50 and s above 1e20, where those are exact in double
    precision.  The same steps as ``scipy.special.wrightomega`` for real
    input, whose values it reproduces to the bit (tests/test_quadrature.py);
    compiled, so node placement runs without Python in between.

    P. W. Lawrence, R. M. Corless and D. J. Jeffrey, "Algorithm 917: Complex
    double-precision evaluation of the Wright omega function," ACM Trans.
    Math. Softw. 38(3), 20 (2012). doi:10.1145/2168773.2168779
    """
    if np.isnan(s):
        return s
    if s < -50.0:
        return np.exp(s)
    if s > 1e20:
        return s
    if s < -2.0:
        w = np.exp(s)
    elif s < 1.0:
        w = np.exp(2.0 * (s - 1.0) / 3.0)
    else:
        w = np.log(s)
        w = s - w + w / s
    for _ in range(2):
        r = s - w - np.log(w)
        wp1 = w + 1.0
        t = 2.0 * wp1 * (wp1 + 2.0 / 3.0 * r)
        w = w * (1.0 + r / wp1 * (t - r) / (t - 2.0 * r))
        bound = abs((2.0 * w * w - 8.0 * w - 1.0) * ((r * r) * (r * r)))
        if not bound >= _EPS * 72.0 * ((wp1 * wp1) * (wp1 * wp1) * (wp1 * wp1)):
            break
    return w


@kernel(F8_1D, F8)
def _unstretch(s: np.ndarray, x_c: float) -> np.ndarray:
    """x = x_c omega(s) for a 1-d array s."""
    x = np.empty(s.shape[0])
    for i in range(s.shape[0]):
        x[i] = x_c * _wright_omega(s[i])
    return x


def size_parameter_at(s: np.ndarray | float, *, settings: QuadratureSettings) -> np.ndarray:
    """Size parameter x at stretched coordinates s: the inverse of
    s(x) = x / x_c + ln(x / x_c), x = x_c omega(s) (Wright omega). [-]"""
    s = np.asarray(s, dtype=np.float64)
    x = _unstretch(np.ascontiguousarray(s.ravel()), settings.transition_size_parameter).reshape(
        s.shape
    )
    return x[()] if x.ndim == 0 else x


def initial_panels(
    distribution: SizeDistribution,
    *,
    wavelength_nm: float,
    settings: QuadratureSettings,
    lower_moment: int,
) -> np.ndarray:
    """Level-0 panel edges in the stretched variable s, increasing. [-]

    The truncated radius range [r_lo, r_hi] (see the module docstring) mapped
    to s and cut into max(min_panels, ceil(width / panel_width)) equal panels.

    Parameters
    ----------
    distribution : SizeDistribution
        Number distribution n(r) with a density. [um^-1]
    wavelength_nm : float
        Wavelength in the medium. [nm]
    settings : QuadratureSettings
        Node placement parameters.
    lower_moment : int
        Moment whose lower tail (below r_lo) is bounded by the tail fraction:
        0 for number-weighted averages, 2 for cross-section weighted ones. [-]
    """
    k_um = 2.0 * np.pi / (wavelength_nm * 1e-3)  # wavenumber [um^-1]
    r_lo, r_hi = distribution.radius_bounds_um(
        tail_fraction=settings.tail_fraction,
        lower_moment=lower_moment,
        upper_moment=_UPPER_MOMENT,
    )
    x_c = settings.transition_size_parameter
    s_lo = _stretch(k_um * r_lo, x_c)
    s_hi = _stretch(k_um * r_hi, x_c)
    n0 = max(settings.min_panels, int(np.ceil((s_hi - s_lo) / settings.panel_width)))
    return np.linspace(s_lo, s_hi, n0 + 1)


def panel_nodes(
    distribution: SizeDistribution,
    *,
    wavelength_nm: float,
    lower_s: np.ndarray,
    upper_s: np.ndarray,
    settings: QuadratureSettings,
) -> tuple[RadiusNodes, np.ndarray]:
    """Gauss-Legendre nodes on the panels [lower_s[i], upper_s[i]] of s.

    Returns the nodes (``nodes_per_panel`` per panel, panel after panel) and,
    for each node, the index of its panel.
    """
    k_um = 2.0 * np.pi / (wavelength_nm * 1e-3)
    x_c = settings.transition_size_parameter
    t, gw = gauss_legendre(settings.nodes_per_panel)
    x, ds_weight, node_panel = _gauss_points(
        np.asarray(lower_s, dtype=np.float64), np.asarray(upper_s, dtype=np.float64), t, gw, x_c
    )
    r = x / k_um
    w = _node_weights(x, np.asarray(distribution.pdf(r), dtype=np.float64), ds_weight, x_c, k_um)
    return RadiusNodes(size_parameter=x, weight=w, radius_um=r), node_panel


@kernel(F8_1D, F8_1D, F8_1D_RO, F8_1D_RO, F8)
def _gauss_points(
    lower: np.ndarray, upper: np.ndarray, t: np.ndarray, gw: np.ndarray, x_c: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rule (t, gw) on [-1, 1] mapped to each panel [lower[p], upper[p]]
    of s, panel after panel: the nodes' size parameters x = x_c omega(s) at
    s = mid + half t, their weights half gw in s, and their panel indices."""
    n = t.shape[0]
    x = np.empty(lower.shape[0] * n)
    ds_weight = np.empty(lower.shape[0] * n)
    node_panel = np.empty(lower.shape[0] * n, dtype=np.int64)
    for p in range(lower.shape[0]):
        half = 0.5 * (upper[p] - lower[p])
        mid = 0.5 * (upper[p] + lower[p])
        for i in range(n):
            x[p * n + i] = x_c * _wright_omega(mid + half * t[i])
            ds_weight[p * n + i] = half * gw[i]
            node_panel[p * n + i] = p
    return x, ds_weight, node_panel


@kernel(F8_1D, F8_1D, F8_1D, F8, F8)
def _node_weights(
    x: np.ndarray, density: np.ndarray, ds_weight: np.ndarray, x_c: float, k_um: float
) -> np.ndarray:
    """Weights in r of nodes placed in s: w = n(r) (dr/ds) w_s, with
    dr/ds = (dx/ds) / k and dx/ds = 1 / (1/x_c + 1/x) (the inverse of ds/dx)."""
    w = np.empty(x.shape[0])
    for j in range(x.shape[0]):
        dx_ds = 1.0 / (1.0 / x_c + 1.0 / x[j])
        w[j] = density[j] * (dx_ds / k_um) * ds_weight[j]
    return w


def radius_nodes(
    distribution: SizeDistribution,
    *,
    wavelength_nm: float,
    level: int,
    settings: QuadratureSettings,
    lower_moment: int,
) -> RadiusNodes:
    """Gauss-Legendre nodes over radius on uniformly refined panels.

    Parameters
    ----------
    distribution : SizeDistribution
        Number distribution n(r), normalized to 1. [um^-1]
    wavelength_nm : float
        Wavelength in the medium. [nm]
    level : int
        Refinement level; the panel count is 2^level times level 0's. [-]
    settings : QuadratureSettings
        Node placement parameters.
    lower_moment : int
        See :func:`initial_panels`. [-]

    Returns
    -------
    RadiusNodes
        A single node of weight 1 for a monodisperse distribution.
    """
    k_um = 2.0 * np.pi / (wavelength_nm * 1e-3)
    if distribution.is_monodisperse:
        r = float(distribution.mean_radius_um)
        return RadiusNodes(np.array([k_um * r]), np.array([1.0]), np.array([r]))
    edges0 = initial_panels(
        distribution, wavelength_nm=wavelength_nm, settings=settings, lower_moment=lower_moment
    )
    edges = np.linspace(edges0[0], edges0[-1], (edges0.size - 1) * 2**level + 1)
    nodes, _ = panel_nodes(
        distribution,
        wavelength_nm=wavelength_nm,
        lower_s=edges[:-1],
        upper_s=edges[1:],
        settings=settings,
    )
    return nodes
