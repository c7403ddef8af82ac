"""Exact derivatives of a computed table, converged on their own radius quadrature.

:func:`~dustoptics.scattering.optics.compute_optics` with ``derivatives=(...)``
first refines its radius quadrature as always (the table's numbers do not
change), then calls :func:`table_derivatives`, which sums the derivatives
over radius panels of their own: it starts from the table's final phase
function panels (recorded in its
:class:`~dustoptics.scattering.quadrature.QuadratureDiagnostics`), adds
panels out to a tail fraction :data:`DERIVATIVE_TAIL_FACTOR` times the
table's (dn/dp grows in the tails), and splits panels until every derivative
meets the table's ``rtol`` (:func:`_refined`).

At fixed nodes r_i with rule weights J_i, each polydisperse sum
S[Y] = sum_i J_i n(r_i) Y(r_i) has the exact derivatives

- dS/dp = sum_i J_i (dn/dp)(r_i) Y(r_i), plus the point masses of
  :func:`~dustoptics.particles.sizedist_derivatives.boundary_terms` where p
  moves an end of the support (p a parameter of the size distribution, by
  name: :func:`~dustoptics.particles.sizedist_derivatives.parameter_names`);
- dS/dm = sum_i J_i n(r_i) dY/dm(r_i), with dY/dn and dY/dk of each sphere
  from the recurrences of :mod:`dustoptics.scattering.mie_derivatives` (the
  table's own Mie coefficients, and S1, S2 with their m derivatives in one
  pass per sphere: ``mie_derivatives_blocked._accumulate_blocked``); a
  parameter q of the refractive index (``"n"``, ``"k"``, a mixture's volume
  fraction) moves m along dm/dq at each wavelength, so
  dS/dq = Re(dm/dq) dS/dn + Im(dm/dq) dS/dk (the chain rule);

and the outputs are quotients of such sums, differentiated by the quotient
rule (``tests/reference/derivatives.py`` writes them out; that module is
the slower reference path, on its own uniformly refined rule).  On many
angles the angular sums are taken at Gauss angles and projected on Legendre
polynomials of degree <= 2 n_max, exactly as the table's phase function is
(the derivative of a polynomial in mu of that degree is one too).

Cost
----
``python scripts/benchmark.py --derivatives`` (section 11) measures the cost
against the table alone.  The distribution's parameters need no Mie work
beyond the sums' weight columns; n and k need S1, S2 and dS/dm of every node
(twice the table's angular work a node).  The refinement's probe sums every
panel on its own at :data:`PROBE_ANGLES` angles, each half of its fine rule
and its coarse rule, all panels of a round in one kernel call
(``mie_derivatives_blocked._accumulate_groups``); a split panel's halves are
its children's coarse rules (the same nodes and weights), so a split sums
only the children's halves.  The final sums over all output angles (or
Legendre orders) take both rules only on the panels whose share of some
error is above :data:`NEGLIGIBLE` of its tolerance, and the others once,
with their coarse rule (about half the final sums' work on the default
table).  The derivatives need 2-3 times the table's panels (d phase / dn
most: its integrand oscillates x times faster than the phase function's),
which is most of what they cost: ``python scripts/derivative_cost.py``
gives the CPU time against the table alone (CHANGELOG for the figures).

Error estimate
--------------
Each sum is also taken with the coarse rule of the panels (one
Gauss-Legendre rule on the panel instead of one on each half), as the
table's own refinement estimates its error (on the panels whose share, below,
is negligible, only the coarse rule is summed, and their shares are added to
the rules' difference).  The estimate of a derivative is
:data:`SAFETY` times the larger of the two rules' difference (the largest
over angle or order) and the sum over panels of each panel's share of it
(the change of the derivative when that panel alone takes its coarse rule,
at :data:`PROBE_ANGLES` output angles), so that errors of opposite sign in
different panels do not cancel in it.  The refinement splits the panels
with the largest shares until every estimate (before the safety factor) is
within ``rtol`` of the derivative's largest magnitude over angle or order,
or after :data:`MAX_ROUNDS` rounds (the estimate then says how far it got).
The cross-sections' estimates also hold their values' stated relative error
times the derivative, so that the single scattering albedo's, propagated from
them with the table's values, covers those values' errors.  The lidar ratio's
derivative is not propagated: its two terms, d<C_ext>/<C_ext> and
d<C_back>/<C_back>, nearly cancel for some parameters (the quotient of
separately converged terms was 20x rtol off), so it is summed from the same
rule's sums as an output of its own (:func:`_lidar_ratio_derivative`), watched
by the refinement and estimated by its rules' difference like the others,
plus the cross-sections' derivative estimates propagated to it
(:func:`_lidar_ratio_terms_error`: the quotient's difference can cancel
between its terms).
The expansion coefficients' estimate adds the round-off of their projection
(the fine sums projected again on :data:`GREEK_EXTRA_NODES` more Gauss
angles).  Where the distribution's density jumps at an end of its support (a
truncation, a power law), the derivatives' range reaches that end
(:func:`_hard_ends`).  ``scripts/calibrate_estimates.py`` checks the estimates against
tight references over random models of every family.

One sphere (:class:`~dustoptics.particles.sizedist.Monodisperse`) has no
quadrature: its derivatives are exact for the table's series of Wiscombe's
n_max terms, and the estimate is the series' truncation error (the change
with :data:`EXTRA_TERMS` more terms) plus its round-off.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

from dustoptics.particles.sizedist import MIN_TAIL_FRACTION, SizeDistribution
from dustoptics.particles.sizedist_derivatives import (
    boundary_terms,
    number_density_derivative,
)
from dustoptics.scattering import mie
from dustoptics.scattering.derivative_panels import _halves, _PanelSums, _Probe
from dustoptics.scattering.derivative_parameters import index_directions, parameter_unit
from dustoptics.scattering.expansion import greek_coefficients
from dustoptics.scattering.mie_derivatives import _accumulate, _series_lengths
from dustoptics.scattering.mie_derivatives_blocked import (
    _accumulate_blocked,
    _accumulate_groups,
    _legendre_evaluate_rows,
    _legendre_project_rows,
)
from dustoptics.scattering.quadrature import (
    QuadratureDiagnostics,
    QuadratureSettings,
    _gauss_points,
    _node_weights,
    _stretch,
    gauss_legendre,
    initial_panels,
    size_parameter_at,
)
from dustoptics.scattering.refinement import _KEEP_FRACTION, _choose_splits, _panel_cost
from dustoptics.table import Table, TableDerivatives

if TYPE_CHECKING:  # the request's module imports this one
    from dustoptics.scattering.optics import OpticsRequest

__all__ = ["table_derivatives"]

#: How the derivatives are computed (recorded with them).
METHOD = (
    "exact derivatives summed over radius panels refined for them to the table's rtol (dn/dp "
    "in closed form, dS/dm from the Mie recurrences, quotient and chain rules); error estimate "
    "= 2 x the panels' differences from their coarse rules, summed without cancellation"
)


@dataclass(frozen=True)
class _Sums:
    """Sums of one node set: angular values (n_w, 4, n_mu) and sums (n_w, 6) per
    weight column, and their n, k (and x) derivatives with column 0's weights."""

    ang: np.ndarray
    dang: np.ndarray
    sums: np.ndarray
    dsums: np.ndarray

    def plus(self, other: _Sums) -> _Sums:
        return _Sums(
            self.ang + other.ang,
            self.dang + other.dang,
            self.sums + other.sums,
            self.dsums + other.dsums,
        )


def _rule_nodes(
    panels: np.ndarray, *, wavelength_nm: float, settings: Any, halves: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Size parameters and rule weights J (dr per node, no density) of the panels'
    rule: one on each half (``halves``, the table's) or one per panel."""
    lower, upper = panels[:, 0], panels[:, 1]
    if halves:
        mid = 0.5 * (lower + upper)
        lower, upper = np.concatenate([lower, mid]), np.concatenate([mid, upper])
    k_um = 2.0 * math.pi / (wavelength_nm * 1e-3)
    x_c = settings.transition_size_parameter
    t, gw = gauss_legendre(settings.nodes_per_panel)
    x, ds_weight, _ = _gauss_points(
        np.ascontiguousarray(lower, dtype=np.float64),
        np.ascontiguousarray(upper, dtype=np.float64),
        t,
        gw,
        x_c,
    )
    rule = _node_weights(x, np.ones_like(x), ds_weight, x_c, k_um)
    return x, rule


def _weight_columns(
    distribution: SizeDistribution,
    x: np.ndarray,
    rule: np.ndarray,
    *,
    k_um: float,
    dist_parameters: Sequence[str],
) -> np.ndarray:
    """Weight columns of nodes in their given order: n J, then dn/dp J per parameter."""
    r = x / k_um
    columns = [np.asarray(distribution.pdf(r), dtype=np.float64) * rule]
    columns += [number_density_derivative(distribution, r, p) * rule for p in dist_parameters]
    return np.column_stack(columns)


def _weights(
    distribution: SizeDistribution,
    x: np.ndarray,
    rule: np.ndarray,
    *,
    k_um: float,
    dist_parameters: Sequence[str],
    boundary: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Nodes sorted by size and their weight columns: n J, then dn/dp J per
    distribution parameter, with the point-mass nodes of moving support ends
    (unless ``boundary`` is false: a part of a rule whose whole has them)."""
    weights = _weight_columns(distribution, x, rule, k_um=k_um, dist_parameters=dist_parameters)
    extra_x: list[float] = []
    extra_w: list[np.ndarray] = []
    for j, p in enumerate(dist_parameters if boundary else ()):
        for r_b, c_b in boundary_terms(distribution, p):
            row = np.zeros(weights.shape[1])
            row[1 + j] = c_b
            extra_x.append(k_um * r_b)
            extra_w.append(row)
    if extra_x:
        x = np.concatenate([x, extra_x])
        weights = np.vstack([weights, np.array(extra_w)])
    order = np.argsort(x, kind="stable")
    return np.ascontiguousarray(x[order]), np.ascontiguousarray(weights[order])


def _read_only(a: np.ndarray) -> np.ndarray:
    """A read-only C-contiguous float64 copy (the type ``mie.angular_table`` and
    ``mie._legendre_project`` are compiled for)."""
    v = np.array(a, dtype=np.float64, order="C")
    v.flags.writeable = False
    return v


def _sums(
    m: complex,
    distribution: SizeDistribution,
    x: np.ndarray,
    rule: np.ndarray,
    *,
    k_um: float,
    dist_parameters: Sequence[str],
    mu: np.ndarray,
    per_particle: bool,
    with_m: bool,
    n_stokes: int = 4,
    boundary: bool = True,
) -> _Sums:
    """Sums at the angles ``mu`` (none: the cross-sections alone); ``boundary``
    as :func:`_weights`; the angular m derivatives only ``with_m``."""
    xs, w = _weights(
        distribution, x, rule, k_um=k_um, dist_parameters=dist_parameters, boundary=boundary
    )
    if mu.size == 0:
        table = np.empty((0, 0))
    else:
        table = mie.angular_table(_read_only(mu), int(_series_lengths(xs).max()))
    return _Sums(
        *_accumulate_blocked(m, xs, w, table, int(mu.size), False, n_stokes, per_particle, with_m)
    )


#: Half-grid sizes of the angular tiers: multiples of TIER_STEP; a node is summed
#: on the smallest with n_half >= n_max + 1 (cost ~ n_max n_half a node, so the
#: finer the steps the less is wasted; each tier costs one projection).
TIER_STEP = 16


@lru_cache(maxsize=64)
def _tier_grid(n_half: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The positive half of the 2 n_half-point Gauss rule (nodes, weights) and
    its ``mie.angular_table`` for n_max <= n_half - 1, read-only (shared by
    the wavelengths' threads)."""
    mu_g, w_g = gauss_legendre(2 * n_half)
    mu_half = _read_only(mu_g[n_half:])
    w_half = _read_only(w_g[n_half:])
    table = mie.angular_table(mu_half, n_half - 1)
    table.flags.writeable = False
    return mu_half, w_half, table


def _legendre_sums(
    m: complex,
    distribution: SizeDistribution,
    x: np.ndarray,
    rule: np.ndarray,
    *,
    k_um: float,
    dist_parameters: Sequence[str],
    per_particle: bool,
    with_m: bool,
    lmax: int,
    n_stokes: int,
    boundary: bool = True,
) -> _Sums:
    """Sums whose angular parts are Legendre coefficients (orders 0..lmax):
    the nodes are summed in tiers of similar n_max, each on the Gauss grid its
    largest sphere needs (2 n_half >= 2 n_max + 2 nodes integrate the products
    of two amplitudes, degree <= 2 n_max, exactly), and each tier's sums
    projected on P_l and added (the projection is linear); ``boundary`` as
    :func:`_weights`."""
    xs, w = _weights(
        distribution, x, rule, k_um=k_um, dist_parameters=dist_parameters, boundary=boundary
    )
    n_w = w.shape[1]
    ang = np.zeros((n_w, n_stokes, lmax + 1))
    dang = np.zeros((2, n_stokes, lmax + 1))
    sums = np.zeros((n_w, 6))
    dsums = np.zeros((2, 6))
    nmax = _series_lengths(xs)
    # The nodes come sorted by x, so by n_max: each tier is a run of them.
    tier = -(-(nmax + 1) // TIER_STEP)
    bounds = np.flatnonzero(np.diff(tier)) + 1
    for start, stop in zip([0, *bounds.tolist()], [*bounds.tolist(), xs.size], strict=True):
        n_half = TIER_STEP * int(tier[start])
        mu_half, w_half, table = _tier_grid(n_half)
        a, da, s_, ds_ = _accumulate_blocked(
            m,
            xs[start:stop],
            np.ascontiguousarray(w[start:stop]),
            table,
            n_half,
            True,
            n_stokes,
            per_particle,
            with_m,
        )
        top = min(lmax, 2 * int(nmax[start:stop].max()))
        parts = [a.reshape(-1, 2 * n_half)]
        if with_m:  # without, da is zero: not projected
            parts.append(da.reshape(-1, 2 * n_half))
        beta = _legendre_project_rows(mu_half, w_half, np.concatenate(parts), top)
        ang[:, :, : top + 1] += beta[: a.shape[0] * n_stokes].reshape(a.shape[0], n_stokes, -1)
        if with_m:
            dang[:, :, : top + 1] += beta[a.shape[0] * n_stokes :].reshape(2, n_stokes, -1)
        sums += s_
        dsums += ds_
    return _Sums(ang, dang, sums, dsums)


def _directions(
    s: _Sums, n_dist: int, index_directions: Sequence[complex]
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Derivatives of the angular values and the sums along every parameter:
    the distribution's (weight columns 1..), then the index's (dm = a + i b:
    a d/dn + b d/dk)."""
    d_ang = [s.ang[1 + j] for j in range(n_dist)]
    d_sums = [s.sums[1 + j] for j in range(n_dist)]
    for dm in index_directions:
        d_ang.append(dm.real * s.dang[0] + dm.imag * s.dang[1])
        d_sums.append(dm.real * s.dsums[0] + dm.imag * s.dsums[1])
    return d_ang, d_sums


@dataclass(frozen=True)
class _Wavelength:
    """Derivatives at one wavelength: per quantity, (n_parameter, ...) arrays."""

    values: dict[str, np.ndarray]
    errors: dict[str, np.ndarray]


def _angular(
    s: _Sums,
    n_dist: int,
    index_directions: Sequence[complex],
    *,
    per_particle: bool,
    n_q: int,
    project: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """dF_q/dp at the output angles, shape (n_parameter, n_q, n_theta)."""
    d_ang, d_sums = _directions(s, n_dist, index_directions)
    norm = s.sums[0, 0] if per_particle else 2.0 * math.pi * s.sums[0, 2]
    f = s.ang[0] / norm
    out = []
    for da, ds in zip(d_ang, d_sums, strict=True):
        d_norm = ds[0] if per_particle else 2.0 * math.pi * ds[2]
        out.append(np.stack([project((da[q] - f[q] * d_norm) / norm) for q in range(n_q)]))
    return np.array(out)


#: The expansion coefficients, in the order of greek_coefficients' rows.
EXPANSION_KEYS = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")


def _greek(
    s: _Sums,
    n_dist: int,
    index_directions: Sequence[complex],
    per_particle: bool,
    n_order: int,
    lmax: int,
) -> np.ndarray:
    """Derivatives of the expansion coefficients (orders 0..n_order - 1), shape
    (n_parameter, 6, n_order), from the Legendre coefficients of the sums:
    dF11, dF12, dF33, dF34 at Gauss nodes that integrate their products with
    the generalized spherical functions exactly, then the same projection as
    the table's (:func:`~dustoptics.scattering.expansion.greek_coefficients`,
    linear in the elements; the table's division by alpha1_0, 1 to round-off,
    has zero derivative since 2 pi int dF11 dmu = 0)."""
    n_nodes = (n_order - 1 + lmax) // 2 + 2
    mu_g, w_g = gauss_legendre(n_nodes)
    mu = np.array(mu_g, dtype=np.float64)
    weight = np.array(w_g, dtype=np.float64)

    def at_nodes(f: np.ndarray) -> np.ndarray:
        return np.asarray(mie._legendre_evaluate(np.ascontiguousarray(f), mu))

    d_f = _angular(s, n_dist, index_directions, per_particle=per_particle, n_q=4, project=at_nodes)
    four_pi = 4.0 * math.pi
    return np.array(
        [
            greek_coefficients(
                mu=mu,
                weight=weight,
                a1=four_pi * d[0],
                a3=four_pi * d[2],
                b1=four_pi * d[1],
                b2=four_pi * d[3],
                lmax=n_order - 1,
            )
            for d in d_f
        ]
    )


#: Gauss angles added to the expansion coefficients' projection to measure its
#: round-off (:meth:`_Plan.outputs`).
GREEK_EXTRA_NODES = 32

#: The cross-sections whose derivatives :func:`_cross` gives (after g).
_CROSS_KEYS = ("cext_um2", "csca_um2", "cback_um2")
#: The per-wavelength outputs of :func:`_cross` and of the probe's last columns,
#: in order: g, the cross-sections, the lidar ratio.
_SCALAR_KEYS = ("g", *_CROSS_KEYS, "lidar_ratio_sr")


def _lidar_ratio_derivative(s_ext: Any, s_back: Any, d_ext: Any, d_back: Any) -> np.ndarray:
    """d(4 pi <C_ext> / <C_back>) from one rule's sums: their values (S_ext,
    S_back) and derivatives, by the quotient rule,
    4 pi (dS_ext S_back - S_ext dS_back) / S_back^2 (the efficiencies' unit of
    area cancels). [sr per unit of the parameter]

    Both terms come from the same nodes, so their quadrature errors cancel
    where the terms do (where the lidar ratio changes little with the
    parameter), and the rules' difference of the quotient is its own error
    estimate (the quotient of the table's values, refined separately, and of
    the derivatives' sums kept each term's error: up to 20x rtol)."""
    return np.asarray(4.0 * math.pi * (d_ext * s_back - s_ext * d_back) / (s_back * s_back))


def _cross(
    s: _Sums,
    n_dist: int,
    index_directions: Sequence[complex],
    *,
    per_particle: bool,
    area: float,
    lossless: bool,
) -> dict[str, np.ndarray]:
    """Derivatives of g, <C_ext>, <C_sca>, <C_back> and the lidar ratio, one per
    parameter."""
    d_ang, d_sums = _directions(s, n_dist, index_directions)
    del d_ang
    s_w, s_ext, s_sca, s_gsca, s_g, s_back = s.sums[0]
    g = s_g / s_w if per_particle else s_gsca / s_sca
    out: dict[str, list[Any]] = {k: [] for k in _SCALAR_KEYS}
    for j, ds in enumerate(d_sums):
        if per_particle:
            out["g"].append((ds[4] - g * ds[0]) / s_w)
        else:
            out["g"].append((ds[3] - g * ds[2]) / s_sca)
        d_ext = ds[1]
        if lossless:
            # The table holds C_ext = C_sca where k = 0 (no absorption): along n and
            # the distribution the same holds, along k C_ext moves as absorption does.
            dm = index_directions[j - n_dist] if j >= n_dist else 0j
            d_ext = ds[2] + dm.imag * (s.dsums[1, 1] - s.dsums[1, 2])
        out["cext_um2"].append(area * d_ext)
        out["csca_um2"].append(area * ds[2])
        out["cback_um2"].append(area * ds[5])
        out["lidar_ratio_sr"].append(
            _lidar_ratio_derivative(s_sca if lossless else s_ext, s_back, d_ext, ds[5])
        )
    return {k: np.array(v) for k, v in out.items()}


@dataclass(frozen=True)
class _At:
    """One wavelength's fixed inputs to the derivative sums."""

    m: complex
    wavelength_nm: float
    distribution: SizeDistribution
    settings: QuadratureSettings
    mu_out: np.ndarray
    index_directions: Sequence[complex]
    dist_parameters: Sequence[str]
    per_particle: bool
    n_q: int
    n_order: int
    angular_keys: tuple[str, ...]

    @property
    def k_um(self) -> float:
        """Wavenumber. [um^-1]"""
        return 2.0 * math.pi / (self.wavelength_nm * 1e-3)

    @property
    def area(self) -> float:
        """pi / k^2, the efficiencies' unit of area. [um^2]"""
        return math.pi / self.k_um**2

    @property
    def lossless(self) -> bool:
        return self.m.imag == 0.0

    @property
    def n_dist(self) -> int:
        return len(self.dist_parameters)

    def common(self) -> dict[str, Any]:
        """The keywords every sum of this wavelength shares."""
        return {
            "k_um": self.k_um,
            "dist_parameters": self.dist_parameters,
            "per_particle": self.per_particle,
            # The angular m derivatives (half the work a sphere) only for index parameters.
            "with_m": bool(self.index_directions),
        }

    def rule(self, panels: np.ndarray, *, halves: bool) -> tuple[np.ndarray, np.ndarray]:
        """Nodes (size parameters) and rule weights of panels, fine or coarse."""
        return _rule_nodes(
            panels, wavelength_nm=self.wavelength_nm, settings=self.settings, halves=halves
        )


def _one_wavelength(
    i: int,
    table: Table,
    diagnostics: QuadratureDiagnostics,
    *,
    m: complex,
    index_directions: Sequence[complex],
    dist_parameters: Sequence[str],
    with_radius: bool,
    per_particle: bool,
    rtol: float,
) -> _Wavelength:
    matrix = table.matrix is not None
    n_order = 0 if table.expansion is None else int(table.expansion.alpha1.shape[1])
    at = _At(
        m=m,
        wavelength_nm=float(table.wavelength_nm[i]),
        distribution=diagnostics.distribution,
        settings=diagnostics.settings,
        mu_out=np.cos(np.deg2rad(np.asarray(table.theta_deg, dtype=np.float64))),
        index_directions=index_directions,
        dist_parameters=dist_parameters,
        per_particle=per_particle,
        n_q=4 if (matrix or n_order) else 1,
        n_order=n_order,
        angular_keys=("phase", "f12", "f33", "f34")[: 4 if matrix else 1],
    )
    if at.distribution.is_monodisperse:
        return _monodisperse(at, with_radius=with_radius)
    return _refined(at, diagnostics.panels[i], rtol=rtol)


#: The derivatives' own refinement stops after this many rounds of splits.
MAX_ROUNDS = 10
#: The derivatives' radius range leaves out this fraction of the table's tail
#: fraction: dn/dp = n d(ln n)/dp grows in the tails (d(ln n)/dv_eff of a
#: modified gamma ~ r / (r_eff v_eff^2)), so the table's tails, negligible for
#: the values, are not for the derivatives.
DERIVATIVE_TAIL_FACTOR = 1e-4


def _hard_ends(at: _At, edges: np.ndarray) -> np.ndarray:
    """``edges`` (stretched coordinate) with an end moved onto the end of the
    distribution's support where its density jumps (a truncation's or a power
    law's ``r_min_um``, ``r_max_um``) when it lies within one panel width
    beyond it.

    The tail bounds leave out a sliver at such an end (its share of the
    number is below the tail fraction), but the density there is not small:
    at the default tail fraction the sliver moved the derivatives of a
    truncated distribution by 3.6e-10 of their scale (d phase / d v_eff of
    its parent at 0 deg), 7x their estimate."""
    edges = edges.copy()
    x_c, width = at.settings.transition_size_parameter, at.settings.panel_width
    lo = getattr(at.distribution, "r_min_um", 0.0)
    hi = getattr(at.distribution, "r_max_um", math.inf)
    if isinstance(lo, float) and lo > 0.0:
        s_lo = float(_stretch(at.k_um * lo, x_c))
        if 0.0 < edges[0] - s_lo <= width:
            edges[0] = s_lo
    if isinstance(hi, float) and math.isfinite(hi):
        s_hi = float(_stretch(at.k_um * hi, x_c))
        if 0.0 < s_hi - edges[-1] <= width:
            edges[-1] = s_hi
    return edges


def _extended(at: _At, panels: np.ndarray) -> np.ndarray:
    """The table's panels (sorted) with panels added below and above them out
    to the bounds of the tail fraction times :data:`DERIVATIVE_TAIL_FACTOR`
    (no wider than the level-0 panels), or to the support's ends where the
    density jumps there (:func:`_hard_ends`)."""
    settings = at.settings
    tail = max(MIN_TAIL_FRACTION, settings.tail_fraction * DERIVATIVE_TAIL_FACTOR)
    edges = initial_panels(
        at.distribution,
        wavelength_nm=at.wavelength_nm,
        settings=replace(settings, tail_fraction=tail),
        lower_moment=0 if at.per_particle else 2,
    )
    edges = _hard_ends(at, edges)
    panels = panels[np.argsort(panels[:, 0], kind="stable")]
    parts = [panels]
    for lo, hi, first in ((edges[0], panels[0, 0], True), (panels[-1, 1], edges[-1], False)):
        if hi > lo:
            n = max(1, math.ceil((hi - lo) / settings.panel_width))
            cut = np.linspace(lo, hi, n + 1)
            cut[0 if not first else -1] = panels[0, 0] if first else panels[-1, 1]
            extra = np.column_stack([cut[:-1], cut[1:]])
            parts.insert(0 if first else len(parts), extra)
    return np.concatenate(parts)


@dataclass(frozen=True)
class _Plan:
    """How one wavelength's sums are taken: at the output angles or as Legendre
    coefficients (orders 0..lmax)."""

    legendre: bool
    lmax: int

    def sums(self, at: _At, panels: np.ndarray, *, halves: bool, boundary: bool) -> _Sums:
        """The sums of the panels' fine (``halves``) or coarse rule."""
        x, rule = at.rule(panels, halves=halves)
        if self.legendre:
            return _legendre_sums(
                at.m,
                at.distribution,
                x,
                rule,
                lmax=self.lmax,
                n_stokes=at.n_q,
                boundary=boundary,
                **at.common(),
            )
        return _sums(
            at.m,
            at.distribution,
            x,
            rule,
            mu=np.ascontiguousarray(at.mu_out),
            n_stokes=at.n_q,
            boundary=boundary,
            **at.common(),
        )

    def outputs(
        self, at: _At, fine: _Sums, coarse: _Sums
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """Every derivative of the fine rule's sums, and its difference from the
        coarse rule's (the largest over angle or order), by key."""
        pair = [
            _angular(
                s,
                at.n_dist,
                at.index_directions,
                per_particle=at.per_particle,
                n_q=at.n_q,
                project=lambda f: f,
            )
            for s in (fine, coarse)
        ]
        if self.legendre:
            shape = pair[0].shape
            rows = np.concatenate([pair[0], pair[0] - pair[1]]).reshape(-1, shape[-1])
            found = _legendre_evaluate_rows(rows, np.ascontiguousarray(at.mu_out))
            ang, diff = found.reshape((2, *shape[:-1], at.mu_out.size))
        else:
            ang, diff = pair[0], pair[0] - pair[1]
        values: dict[str, np.ndarray] = {}
        errors: dict[str, np.ndarray] = {}
        for q, key in enumerate(at.angular_keys):
            values[key] = ang[:, q]
            errors[key] = np.max(np.abs(diff[:, q]), axis=-1)
        if at.n_order:
            # The fine sums also on GREEK_EXTRA_NODES more Gauss angles: exact
            # either way but for round-off, so the difference is the
            # projection's round-off (the sums' Legendre series run to order
            # 2 n_max, thousands for the largest spheres, and their forward
            # peak is far above the coefficients: the coefficients' error was
            # up to 3.5e-10 of their scale, 3.8x the estimate without it).
            greek = [
                _greek(s, at.n_dist, at.index_directions, at.per_particle, at.n_order, lmax)
                for s, lmax in (
                    (fine, self.lmax),
                    (coarse, self.lmax),
                    (fine, self.lmax + 2 * GREEK_EXTRA_NODES),
                )
            ]
            for j, key in enumerate(EXPANSION_KEYS):
                values[key] = greek[0][:, j]
                errors[key] = np.max(np.abs(greek[0][:, j] - greek[1][:, j]), axis=-1) + np.max(
                    np.abs(greek[0][:, j] - greek[2][:, j]), axis=-1
                )
        cross = [
            _cross(
                s,
                at.n_dist,
                at.index_directions,
                per_particle=at.per_particle,
                area=at.area,
                lossless=at.lossless,
            )
            for s in (fine, coarse)
        ]
        for key, v in cross[0].items():
            values[key] = v
            errors[key] = np.abs(v - cross[1][key])
        return values, errors


#: The stated estimate is this multiple of the rules' difference: the
#: difference overstates the fine rule's error where the rules converge, but
#: in 1-3 % of the cases of ``scripts/calibrate_estimates.py`` the error was up
#: to 1.6 times it (expansion coefficients, f12, g near their tolerance).
SAFETY = 2.0

#: A panel's coarse rule is summed over all output angles (or orders) only if
#: its share of some derivative's error is above this fraction of that
#: derivative's tolerance: the others' shares, summed, stay within about 1 % of
#: it on the default Mars-dust table (and are added to the estimate).
NEGLIGIBLE = 1e-3

#: Output angles (evenly picked) at which the derivatives' refinement compares
#: each panel's rules.
PROBE_ANGLES = 24


def _probe_mu(at: _At) -> np.ndarray:
    """The output angles' cosines at which panels are compared (all if few)."""
    n = at.mu_out.size
    if n <= PROBE_ANGLES:
        return np.ascontiguousarray(at.mu_out)
    pick = np.unique(np.round(np.linspace(0, n - 1, PROBE_ANGLES)).astype(np.int64))
    return np.ascontiguousarray(at.mu_out[pick])


def _probe_table(at: _At, panels: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """``mie.angular_table`` of the probe angles for every node of ``panels``
    (and of panels split from them: they lie inside)."""
    x_top = float(size_parameter_at(panels[:, 1].max(), settings=at.settings))
    return mie.angular_table(_read_only(mu), int(_series_lengths(np.array([x_top])).max()))


def _interval_sums(at: _At, intervals: np.ndarray, mu: np.ndarray, table: np.ndarray) -> _PanelSums:
    """The sums of one Gauss rule on each interval (rows of ``intervals``, in
    the panels' coordinate) at the angles ``mu``, without the point masses of
    moving ends: one kernel call for all of them (``_accumulate_groups``)."""
    n = intervals.shape[0]
    x, rule = at.rule(intervals, halves=False)
    weights = _weight_columns(
        at.distribution, x, rule, k_um=at.k_um, dist_parameters=at.dist_parameters
    )
    starts = np.arange(n + 1, dtype=np.int64) * at.settings.nodes_per_panel
    return _PanelSums(
        *_accumulate_groups(
            at.m,
            np.ascontiguousarray(x),
            np.ascontiguousarray(weights),
            starts,
            table,
            int(mu.size),
            at.n_q,
            at.per_particle,
            bool(at.index_directions),
        )
    )


def _panel_probe(at: _At, panels: np.ndarray, mu: np.ndarray, table: np.ndarray) -> _Probe:
    """Each panel's sums on each half and with its coarse rule at the angles
    ``mu``, without the point masses of moving ends (the same in both rules):
    one kernel call for all of them."""
    n = panels.shape[0]
    left, right = _halves(panels)
    rows = _interval_sums(at, np.concatenate([left, right, panels]), mu, table)
    return _Probe.of(
        rows.take(np.arange(n)), rows.take(np.arange(n, 2 * n)), rows.take(np.arange(2 * n, 3 * n))
    )


def _boundary_probe(at: _At, mu: np.ndarray) -> tuple[np.ndarray, ...]:
    """The point masses' sums at ``mu`` (no rule nodes), as :class:`_PanelSums`
    fields of one panel."""
    xs, w = _weights(
        at.distribution,
        np.empty(0),
        np.empty(0),
        k_um=at.k_um,
        dist_parameters=at.dist_parameters,
    )
    ang, dang, sums, dsums = _accumulate(
        at.m, xs, np.ascontiguousarray(w), mu, at.per_particle, False
    )
    return ang[:, : at.n_q], dang[:, : at.n_q], sums, dsums


def _batched_outputs(
    at: _At, ang: np.ndarray, dang: np.ndarray, sums: np.ndarray, dsums: np.ndarray
) -> np.ndarray:
    """Derivatives of the angular outputs at the probe angles, then of g and
    the cross-sections and the lidar ratio (as :func:`_angular`,
    :func:`_cross`), for a batch of sums (leading axis): shape (batch,
    n_parameter, n_q n_mu + 5)."""
    n_q = at.n_q
    d_ang = [ang[:, 1 + j, :n_q] for j in range(at.n_dist)]
    d_sums = [sums[:, 1 + j] for j in range(at.n_dist)]
    for dm in at.index_directions:
        d_ang.append(dm.real * dang[:, 0, :n_q] + dm.imag * dang[:, 1, :n_q])
        d_sums.append(dm.real * dsums[:, 0] + dm.imag * dsums[:, 1])
    s0 = sums[:, 0]
    norm = s0[:, 0] if at.per_particle else 2.0 * math.pi * s0[:, 2]
    f = ang[:, 0, :n_q] / norm[:, None, None]
    g = s0[:, 4] / s0[:, 0] if at.per_particle else s0[:, 3] / s0[:, 2]
    out = []
    for j, (da, ds) in enumerate(zip(d_ang, d_sums, strict=True)):
        d_norm = ds[:, 0] if at.per_particle else 2.0 * math.pi * ds[:, 2]
        angular = (da - f * d_norm[:, None, None]) / norm[:, None, None]
        if at.per_particle:
            dg = (ds[:, 4] - g * ds[:, 0]) / s0[:, 0]
        else:
            dg = (ds[:, 3] - g * ds[:, 2]) / s0[:, 2]
        d_ext = ds[:, 1]
        if at.lossless:
            dm = at.index_directions[j - at.n_dist] if j >= at.n_dist else 0j
            d_ext = ds[:, 2] + dm.imag * (dsums[:, 1, 1] - dsums[:, 1, 2])
        s_ext = s0[:, 2] if at.lossless else s0[:, 1]
        lidar = _lidar_ratio_derivative(s_ext, s0[:, 5], d_ext, ds[:, 5])
        cross = np.column_stack(
            [dg, at.area * d_ext, at.area * ds[:, 2], at.area * ds[:, 5], lidar]
        )
        out.append(np.concatenate([angular.reshape(angular.shape[0], -1), cross], axis=1))
    return np.stack(out, axis=1)


def _panel_errors(
    at: _At, fine: _PanelSums, coarse: _PanelSums, boundary: tuple[np.ndarray, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """The outputs of the panels' summed fine rules (with the point masses), and
    each panel's share of their error: the change of the outputs when that
    panel's fine rule is replaced by its coarse one, shape (n_panels,
    n_parameter, n_outputs)."""
    total = [f.sum(axis=0) + b for f, b in zip(fine.fields(), boundary, strict=True)]
    whole = _batched_outputs(at, *(t[None] for t in total))
    swapped = _batched_outputs(
        at,
        *(t[None] - (f - c) for t, f, c in zip(total, fine.fields(), coarse.fields(), strict=True)),
    )
    return whole[0], np.abs(whole - swapped)


def _by_key(at: _At, shares: np.ndarray) -> dict[str, np.ndarray]:
    """The sum over panels of shares (n_panels, n_parameter, n_outputs) per
    output key, the largest over the probe angles for the angular ones."""
    summed = shares.sum(axis=0)  # (n_parameter, n_outputs)
    n_par = summed.shape[0]
    n_mu = (summed.shape[1] - len(_SCALAR_KEYS)) // at.n_q
    angular = summed[:, : at.n_q * n_mu].reshape(n_par, at.n_q, n_mu).max(axis=-1)
    out = {key: angular[:, q] for q, key in enumerate(at.angular_keys)}
    for j, key in enumerate(_SCALAR_KEYS):
        out[key] = summed[:, at.n_q * n_mu + j]
    return out


def _with_panel_errors(
    at: _At, errors: dict[str, np.ndarray], shares: np.ndarray, left_out: np.ndarray
) -> dict[str, np.ndarray]:
    """The estimates: the larger of the summed rules' difference (plus the
    shares of the panels ``left_out`` of it, whose coarse rules were not
    summed) and the sum over panels of each panel's share (no cancellation
    between panels), the largest over the probe angles for the angular outputs."""
    summed = _by_key(at, shares)
    missing = _by_key(at, left_out)
    out = dict(errors)
    for key in (*at.angular_keys, *_SCALAR_KEYS):
        out[key] = np.maximum(errors[key] + missing[key], summed[key])
    if at.n_order:
        # The expansion coefficients' sums cancel between panels as the phase
        # function's do: their estimate grows by the phase function's ratio.
        ratio = np.maximum(out["phase"] / np.maximum(errors["phase"], 1e-300), 1.0)
        for key in EXPANSION_KEYS:
            out[key] = errors[key] * ratio
    return out


def _scale(at: _At, whole: np.ndarray) -> np.ndarray:
    """The magnitude each output of :func:`_batched_outputs` is held to: the
    largest over the probe angles for the angular ones, its own for the others."""
    n_par, n_out = whole.shape
    n_ang = n_out - len(_SCALAR_KEYS)
    n_mu = n_ang // at.n_q
    mag = np.abs(whole)
    scale = np.empty_like(mag)
    top = mag[:, :n_ang].reshape(n_par, at.n_q, n_mu).max(axis=-1)
    scale[:, :n_ang] = np.repeat(top, n_mu, axis=-1)
    scale[:, n_ang:] = mag[:, n_ang:]
    return scale


def _badness(at: _At, whole: np.ndarray, shares: np.ndarray, rtol: float) -> np.ndarray:
    """Per panel, its largest share of an output's error in units of that
    output's tolerance (``rtol`` times :func:`_scale`)."""
    return np.asarray(np.max(shares / (rtol * _scale(at, whole) + 1e-300), axis=(1, 2)))


def _refined(at: _At, table_panels: np.ndarray, *, rtol: float) -> _Wavelength:
    """The derivatives refined to ``rtol`` on their own panels, from the table's.

    Each panel is summed on its own at :data:`PROBE_ANGLES` output angles
    (and without angles for the cross-sections and g), with its fine and its
    coarse rule; a panel's share of a derivative's error is the change when
    that panel alone takes its coarse rule (:func:`_panel_errors`), and the
    shares are summed over panels, so that errors of opposite signs do not
    hide each other.  Until every summed share is within ``rtol`` of its
    derivative's magnitude, the panels with the largest shares are split (the
    rule of :func:`~dustoptics.scattering.refinement._choose_splits`); only
    the children's halves are summed (their coarse rules are their parents'
    halves).  The derivatives are then summed over the final panels at every
    output angle (or in Legendre coefficients), fine and coarse rule where a
    panel's share of some error is above :data:`NEGLIGIBLE` of its tolerance,
    the coarse rule alone elsewhere, and the estimate is the larger of the
    totals' difference (plus the shares of the panels summed once) and the
    summed shares (:func:`_with_panel_errors`).
    """
    panels = _extended(at, table_panels)
    mu = _probe_mu(at)
    table = _probe_table(at, panels, mu)
    boundary = _boundary_probe(at, mu)
    probe = _panel_probe(at, panels, mu, table)
    whole, shares = _panel_errors(at, probe.fine, probe.coarse, boundary)
    max_panels = panels.shape[0] * 2**6
    for _ in range(MAX_ROUNDS):
        if np.all(shares.sum(axis=0) <= rtol * _scale(at, whole)):
            break
        if panels.shape[0] >= max_panels:
            break
        cost = _panel_cost(
            np.ascontiguousarray(panels[:, 1]), at.settings.transition_size_parameter, True
        )
        split, _, _ = _choose_splits(
            _badness(at, whole, shares, rtol),
            cost,
            1.0,
            _KEEP_FRACTION,
            panels[:, 0].copy(),
            panels[:, 1].copy(),
        )
        # The children (left ones, then right ones): their coarse rules are
        # the parents' halves; only their own halves are summed.
        parents = probe.take(split)
        children = np.concatenate(_halves(panels[split]))
        n_new = children.shape[0]
        quarters = _interval_sums(at, np.concatenate(_halves(children)), mu, table)
        new = _Probe.of(
            quarters.take(np.arange(n_new)),
            quarters.take(np.arange(n_new, 2 * n_new)),
            parents.left.joined(parents.right),
        )
        keep = np.ones(panels.shape[0], dtype=bool)
        keep[split] = False
        panels = np.concatenate([panels[keep], children])
        probe = probe.take(keep).joined(new)
        whole, shares = _panel_errors(at, probe.fine, probe.coarse, boundary)
    x_top = float(size_parameter_at(panels[:, 1].max(), settings=at.settings))
    nmax = mie.wiscombe_nmax(max(x_top, 1e-3) * 1.0001 + 1.0)
    n_half = 16 * ((nmax + 1 + 15) // 16)
    plan = _Plan(legendre=bool(2 * n_half < at.mu_out.size or at.n_order), lmax=2 * nmax)
    # Both rules only where they can matter: the panels whose share of some
    # derivative's error is above NEGLIGIBLE of its tolerance.  The others are
    # summed once, with their coarse rule (their share is its error), into
    # both totals (their rules' difference counts as zero in the totals'
    # difference), and their shares are added to the estimate.
    badness = _badness(at, whole, shares, rtol)
    sig = badness > NEGLIGIBLE
    sig[np.argmax(badness)] = True
    fine = plan.sums(at, panels[sig], halves=True, boundary=True)
    coarse = plan.sums(at, panels[sig], halves=False, boundary=True)
    if not np.all(sig):
        rest = plan.sums(at, panels[~sig], halves=False, boundary=False)
        fine, coarse = fine.plus(rest), coarse.plus(rest)
    values, errors = plan.outputs(at, fine, coarse)
    errors = _with_panel_errors(at, errors, shares, shares[~sig])
    errors["lidar_ratio_sr"] = errors["lidar_ratio_sr"] + _lidar_ratio_terms_error(at, fine, errors)
    return _Wavelength(values, {k: SAFETY * e for k, e in errors.items()})


def _lidar_ratio_terms_error(at: _At, s: _Sums, errors: dict[str, np.ndarray]) -> np.ndarray:
    """The estimates of d<C_ext> and d<C_back> (their quadrature's, before the
    values' errors are added) propagated to the lidar ratio's derivative,
    4 pi (e_ext / S_back + S_ext e_back / S_back^2) / area, with S the
    efficiency sums of ``s``. [sr per unit of the parameter]

    The rules' difference of the quotient can cancel between its two terms
    (the coarse rule's errors in d<C_ext> and d<C_back> cancelling where the
    fine rule's do not): on ``scripts/calibrate_estimates.py``'s modified
    log-normals at 450 nm the error was up to 2.3x the quotient's estimate
    alone, and d<C_back>'s error up to 1.9x its quadrature estimate."""
    s_w, s_ext, s_sca, _, _, s_back = s.sums[0]
    del s_w
    ext = s_sca if at.lossless else s_ext
    four_pi = 4.0 * math.pi / at.area
    return np.asarray(
        four_pi * (errors["cext_um2"] / s_back + ext * errors["cback_um2"] / (s_back * s_back))
    )


#: Terms added to Wiscombe's n_max to estimate a single sphere's series
#: truncation error: beyond n_max the terms fall faster than geometrically, so
#: the next ten hold all of the rest that double precision sees.
EXTRA_TERMS = 10


def _monodisperse_derivatives(
    at: _At, *, with_radius: bool, extra_terms: int
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """One sphere's angular derivatives (n_parameter, n_q, n_theta) and those of
    the cross-sections and g, with its series ``extra_terms`` longer than the table's."""
    k_um, per_particle, n_q = at.k_um, at.per_particle, at.n_q
    x = np.array([k_um * at.distribution.mean_radius_um])
    ang, dang, sums, dsums = _accumulate(
        at.m,
        x,
        np.ones((1, 1)),
        np.ascontiguousarray(at.mu_out),
        per_particle,
        with_radius,
        extra_terms,
    )
    n_theta = at.mu_out.size
    ang_d = np.empty((0, n_q, n_theta))
    cross: dict[str, np.ndarray] = {k: np.empty(0) for k in _SCALAR_KEYS}
    if with_radius:
        # d/dr = k d/dx: the kernel's x direction, read as a direction "n" of weight k.
        radial = _Sums(ang, dang[[2, 2]] * k_um, sums, dsums[[2, 2]] * k_um)
        ang_d = _angular(
            radial, 0, [1.0 + 0j], per_particle=per_particle, n_q=n_q, project=lambda f: f
        )
        # Lossless: C_ext = C_sca, as the table holds it (d/dr is real: no absorption term).
        cross = _cross(
            radial, 0, [1.0 + 0j], per_particle=per_particle, area=at.area, lossless=at.lossless
        )
    directions = list(at.index_directions)
    if directions:
        s = _Sums(ang, dang[:2], sums, dsums[:2])
        ang_m = _angular(s, 0, directions, per_particle=per_particle, n_q=n_q, project=lambda f: f)
        cross_m = _cross(
            s, 0, directions, per_particle=per_particle, area=at.area, lossless=at.lossless
        )
        ang_d = np.concatenate([ang_d, ang_m])
        cross = {k: np.concatenate([cross[k], cross_m[k]]) for k in cross}
    return ang_d, cross


def _monodisperse(at: _At, *, with_radius: bool) -> _Wavelength:
    """One sphere: its derivatives exactly for the table's series (Wiscombe's
    n_max terms), with the series' truncation error as the estimate: the change
    when :data:`EXTRA_TERMS` more terms are summed, plus the round-off of a sum
    of n_max terms (n_max eps of the largest derivative over angle)."""
    ang_d, cross = _monodisperse_derivatives(at, with_radius=with_radius, extra_terms=0)
    ang_l, cross_l = _monodisperse_derivatives(at, with_radius=with_radius, extra_terms=EXTRA_TERMS)
    x = at.k_um * at.distribution.mean_radius_um
    roundoff = mie.wiscombe_nmax(x) * float(np.finfo(np.float64).eps)
    values: dict[str, np.ndarray] = {}
    errors: dict[str, np.ndarray] = {}
    for q, key in enumerate(at.angular_keys):
        values[key] = ang_d[:, q]
        errors[key] = np.max(
            np.abs(ang_l[:, q] - ang_d[:, q]) + roundoff * np.abs(ang_d[:, q]), axis=-1
        )
    for key, v in cross.items():
        values[key] = v
        errors[key] = np.abs(cross_l[key] - v) + roundoff * np.abs(v)
    return _Wavelength(values, errors)


def _add_value_errors(
    table: Table, values: dict[str, np.ndarray], errors: dict[str, np.ndarray]
) -> None:
    """Add to each cross-section derivative's estimate its value's stated relative
    error times the derivative, in place.

    The single scattering albedo's and the lidar ratio's derivatives combine these
    with the table's values (TableDerivatives.pair), so their propagated
    estimates then cover those values' errors too.  <C_back> is
    4 pi <C_sca> P(180 deg): its value's relative error is at most the phase
    function's (error_estimate) plus <C_sca>'s."""
    record = table.quadrature
    if record is None or record.cross_section_error_estimate is None:
        return
    rel = np.asarray(record.cross_section_error_estimate)
    for key in _CROSS_KEYS:
        if key == "cback_um2":
            rel = rel + np.asarray(record.error_estimate)
        errors[key] = errors[key] + rel * np.abs(values[key])


def table_derivatives(
    table: Table, request: OpticsRequest, *, workers: int = 1
) -> TableDerivatives:
    """Derivatives of a table of :func:`~dustoptics.scattering.optics.compute_optics`.

    Parameters
    ----------
    table : Table
        The table computed for ``request`` in this process (its
        ``diagnostics`` hold the radius panels), of homogeneous spheres.
    request : OpticsRequest
        Its request (:func:`~dustoptics.scattering.optics.optics_request`):
        the parameters (``request.derivatives``, checked, in the order
        wanted), the refractive index whose parameters move m (dm/dp per
        wavelength: ``"n"``: 1, ``"k"``: 1j, a mixture's by the chain rule)
        and the weighting.
    workers : int
        Threads over wavelengths; the result does not depend on it.

    Returns
    -------
    TableDerivatives
        Of ``phase`` (and ``f12``, ``f33``, ``f34`` where the table has the
        matrix, ``alpha1`` ... ``beta2`` where it has the expansion of a
        polydisperse population), ``g``, ``cext_um2``, ``csca_um2``,
        ``cback_um2``, with error estimates (module docstring).
    """
    parameters = request.derivatives
    directions = index_directions(request.refractive_index, parameters, request.wavelength_nm)
    diagnostics = table.diagnostics
    if diagnostics is None or table.refractive_index is None:
        raise ValueError(
            f"table {table.name!r} has no quadrature diagnostics: derivatives need the table "
            "compute_optics returns, not one read from a file or changed"
        )
    distribution = diagnostics.distribution
    index_names = [p for p in parameters if p in directions]
    with_radius = distribution.is_monodisperse and "radius_um" in parameters
    dist_parameters = (
        [] if distribution.is_monodisperse else [p for p in parameters if p not in directions]
    )
    order = (["radius_um"] if with_radius else []) + dist_parameters + index_names
    per_particle = request.per_particle
    m_all = np.asarray(table.refractive_index)

    def one(i: int) -> _Wavelength:
        return _one_wavelength(
            i,
            table,
            diagnostics,
            m=complex(m_all[i]),
            index_directions=[complex(directions[p][i]) for p in index_names],
            dist_parameters=dist_parameters,
            with_radius=with_radius,
            per_particle=per_particle,
            rtol=request.rtol,
        )

    n_wl = table.wavelength_nm.size
    if workers > 1 and n_wl > 1:
        with ThreadPoolExecutor(max_workers=min(workers, n_wl)) as pool:
            results = list(pool.map(one, range(n_wl)))
    else:
        results = [one(i) for i in range(n_wl)]
    positions = [order.index(p) for p in parameters]
    keys = list(results[0].values)
    values = {k: np.stack([r.values[k] for r in results], axis=1)[positions] for k in keys}
    errors = {k: np.stack([r.errors[k] for r in results], axis=1)[positions] for k in keys}
    _add_value_errors(table, values, errors)
    return TableDerivatives(
        parameters=tuple(parameters),
        parameter_units=tuple(parameter_unit(p) for p in parameters),
        values=values,
        error_estimates=errors,
        method=METHOD,
    )
