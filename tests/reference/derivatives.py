"""Polydisperse optics and their exact derivatives: the reference path.

:func:`optics_derivatives` computes what :func:`~dustoptics.scattering.optics.compute_optics`
tabulates (phase function F11, F12, F33, F34, <C_ext>, <C_sca>, <C_abs>, <C_back>,
single-scattering albedo, g) together with their derivatives with respect to
named parameters: the size distribution's (any of
:func:`dustoptics.particles.sizedist_derivatives.parameter_names`) and the real
and imaginary parts of the refractive index, ``"n"`` and ``"k"``.  It is a
reference: its own fixed quadrature, simple and checked, not the adaptive
one.  ``compute_optics(derivatives=...)`` sums the same derivatives on the
table's converged nodes instead (:mod:`dustoptics.scattering.table_derivatives`,
tested against this module).  It lives with the tests, not in the package: it
checks the product and is no part of it.

How the parts combine
---------------------
With fixed radius nodes r_i and rule weights J_i (a Gauss-Legendre rule in r,
so that int f dr ~ sum_i J_i f(r_i)), the quadrature weights of the number
density are w_i = n(r_i) J_i, and every polydisperse sum

    S[Y] = sum_i w_i Y(r_i)  ~  int n Y dr

has the derivatives::

    dS/dp = sum_i J_i (dn/dp)(r_i) Y(r_i) (+ sum_b c_b Y(r_b))
          = sum_i w_i [(dn/dp) / n](r_i) Y(r_i) (+ ...)       (p of the distribution),
    dS/dm = sum_i w_i dY/dm(r_i)                              (m = n + i k),

with dn/dp from :func:`~dustoptics.particles.sizedist_derivatives.number_density_derivative`
(closed forms), the point masses (r_b, c_b) of
:func:`~dustoptics.particles.sizedist_derivatives.boundary_terms` where p moves an end
of the support (Leibniz's rule; an extra node of weight c_b in p's column
only), and dY/dn, dY/dk of each sphere from
:mod:`dustoptics.scattering.mie_derivatives`.  The nodes do not move with p,
so the sum over them is differentiated exactly; only the truncation of the
tails at fixed radii is not (its share is below ``tail_fraction`` of the
moments, default 1e-10).  The kernel sums, for every weight column (n's and
each dn/dp), Y = (I, Q, U, V)(mu) of the sphere (Bohren & Huffman's 2 S11,
2 S12, 2 S33, 2 S34) and (1, x^2 Q_ext, x^2 Q_sca, x^2 g Q_sca, g, x^2 Q_back),
and with n's weights their n and k derivatives.  The outputs are quotients of
such sums, differentiated by the quotient rule:

    F_q = S[Y_q] / (2 pi S[x^2 Q_sca]),  dF_q = (dS[Y_q] - 2 pi F_q dS[x^2 Q_sca]) / (2 pi S[x^2 Q_sca]),
    g   = S[x^2 g Q_sca] / S[x^2 Q_sca],  dg = (dS[x^2 g Q_sca] - g dS[x^2 Q_sca]) / S[x^2 Q_sca],
    ssa = S[x^2 Q_sca] / S[x^2 Q_ext],    <C> = pi (lambda / 2 pi)^2 S[x^2 Q],

for cross-section weighting (``weighting="scattering"``, the physical one);
for ``"number"`` (the seed's) the phase matrix is S[Y / (2 pi x^2 Q_sca)] / S[1]
and g = S[g] / S[1], as ``compute_optics`` has them.  A
:class:`~dustoptics.particles.sizedist.Monodisperse` distribution is one node
of weight 1, and its ``radius_um`` derivative that of the sphere,
d/dr = (2 pi / lambda) d/dx.

Quadrature and convergence
--------------------------
The nodes are those of :mod:`dustoptics.scattering.quadrature`, without its
adaptivity: the radii between the distribution's own tail bounds
(:meth:`~dustoptics.particles.sizedist.SizeDistribution.radius_bounds_um`, the
moments 0 or 2 below and 4 above, as ``compute_optics`` truncates them, at
``tail_fraction``), cut into equal panels of the stretched variable
s = x / x_c + ln(x / x_c) (level 0 as ``compute_optics``'s, and ends of
the support inside the range made panel edges, where the density jumps),
each with a ``nodes_per_panel`` Gauss-Legendre rule.  Each level halves every
panel (twice the nodes).  A wavelength is converged when the change from the
previous level is below the tolerances in every value and every derivative:

- angular values F_q: max over angles of abs(change) / F11, below ``rtol``
  (as ``compute_optics`` measures the matrix);
- cross-sections, relative; g and ssa, absolute: below ``cross_section_rtol``;
- derivatives: the same measures applied to s_p times the derivative,
  s_p = max(abs(p), 1e-3) (a relative change of the parameter; k = 0 counts as
  1e-3), so that the tolerance bounds the error of a linear prediction of
  the output for a change of p by a fraction of itself.

Angles are summed until they converge and then left out: the cross-sections
go on refining alone (as ``compute_optics`` does), from the same nodes.  The
reported error estimates are the last changes (the rule converges fast, so
they overstate the error of the finer level).

Limitation: lossless or nearly lossless spheres (k below about 1e-3) with size
parameters above about 20 have narrow resonances, whose n derivative is a spike
of height ~ 1/width.  Their integral over radius is smooth (a resonance moves
with n as with x), but uniform refinement resolves the spikes slowly: for
m = 1.33 and a log-normal to x ~ 40 the n derivative of the cross-sections
still changed by 2.5e-5 (relative) at 262,144 nodes.  Such wavelengths warn
(:class:`~dustoptics.scattering.optics.ConvergenceWarning`); an adaptive rule,
as ``compute_optics``'s, is the remedy for the integration into the table.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dustoptics._validation import (
    as_increasing_grid,
    check_budget,
    check_choice,
    check_open_interval,
    check_wavelength_unit,
)
from dustoptics.particles.custom_sizedist import MultiModal
from dustoptics.particles.sizedist import PowerLaw, SizeDistribution, Truncated
from dustoptics.particles.sizedist_derivatives import (
    boundary_terms,
    number_density_derivative,
    parameter_names,
    parameter_value,
)
from dustoptics.scattering.mie_derivatives import _accumulate
from dustoptics.scattering.optics import (
    ConvergenceWarning,
    RefractiveIndexLike,
    default_theta_deg,
    default_wavelengths_nm,
    resolve_refractive_index,
)
from dustoptics.scattering.quadrature import (
    QuadratureSettings,
    gauss_legendre,
    size_parameter_at,
)

__all__ = [
    "OpticsDerivatives",
    "optics_derivatives",
]

#: The outputs, as :class:`~dustoptics.table.Table` names them.
ANGULAR = ("phase", "f12", "f33", "f34")
CROSS = ("cext_um2", "csca_um2", "cabs_um2", "cback_um2", "ssa", "g")
QUANTITIES = ANGULAR + CROSS

#: The refractive index's parameters.
INDEX_PARAMETERS = ("n", "k")

#: Moment whose upper tail bounds the radius range (quadrature._UPPER_MOMENT).
_UPPER_MOMENT = 4.0


@dataclass(frozen=True)
class OpticsDerivatives:
    """Polydisperse optics per wavelength and their derivatives.

    Attributes
    ----------
    wavelength_nm : numpy.ndarray
        Wavelengths. [nm]
    theta_deg : numpy.ndarray
        Scattering angles. [deg]
    parameters : tuple of str
        The parameters differentiated, in the order of the derivatives' first axis.
    parameter_values : numpy.ndarray
        Their values, shape (n_parameters, n_wavelengths) (n and k per wavelength).
    refractive_index : numpy.ndarray
        m = n + i k per wavelength. [-]
    weighting : str
        ``"scattering"`` or ``"number"`` (see :func:`optics_derivatives`).
    phase, f12, f33, f34 : numpy.ndarray
        Phase matrix, shape (n_wavelengths, n_angles), normalized as the table's:
        2 pi int F11 dmu = 1, Bohren & Huffman's signs. [sr^-1]
    cext_um2, csca_um2, cabs_um2, cback_um2 : numpy.ndarray
        Mean cross-sections per particle (C_back = 4 pi dC_sca/dOmega at 180 deg). [um^2]
    ssa, g : numpy.ndarray
        Single-scattering albedo and asymmetry parameter. [-]
    error_estimate : numpy.ndarray
        Per wavelength, the phase matrix's last change relative to F11. [-]
    cross_section_error_estimate : numpy.ndarray
        Per wavelength, the cross-sections' last relative change (g and ssa absolute). [-]
    derivative_error_estimate : numpy.ndarray
        Per parameter and wavelength, the derivatives' last change, measured as
        the values' (times max(abs(p), 1e-3)), the larger of the angular and the
        cross-section measure. [-]
    n_nodes : numpy.ndarray
        Radius nodes of the final level, per wavelength (the angles' level may
        be lower). [-]
    converged : numpy.ndarray
        Whether each wavelength met the tolerances within ``max_level``.
    """

    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    parameters: tuple[str, ...]
    parameter_values: np.ndarray
    refractive_index: np.ndarray
    weighting: str
    phase: np.ndarray
    f12: np.ndarray
    f33: np.ndarray
    f34: np.ndarray
    cext_um2: np.ndarray
    csca_um2: np.ndarray
    cabs_um2: np.ndarray
    cback_um2: np.ndarray
    ssa: np.ndarray
    g: np.ndarray
    error_estimate: np.ndarray
    cross_section_error_estimate: np.ndarray
    derivative_error_estimate: np.ndarray
    n_nodes: np.ndarray
    converged: np.ndarray
    _derivatives: Mapping[str, np.ndarray] = field(repr=False)

    def derivative(self, quantity: str, parameter: str) -> np.ndarray:
        """d(quantity)/d(parameter) per wavelength (and angle).

        Parameters
        ----------
        quantity : str
            One of ``phase``, ``f12``, ``f33``, ``f34`` (shape (n_wavelengths,
            n_angles)), ``cext_um2``, ``csca_um2``, ``cabs_um2``, ``cback_um2``,
            ``ssa``, ``g`` (shape (n_wavelengths,)).
        parameter : str
            One of :attr:`parameters`.

        Returns
        -------
        numpy.ndarray
            In the quantity's unit per unit of the parameter (um for radii).

        Raises
        ------
        ValueError
            An unknown quantity, or a parameter not computed.
        """
        check_choice("quantity", quantity, QUANTITIES)
        check_choice("parameter", parameter, self.parameters)
        return np.array(self._derivatives[quantity][self.parameters.index(parameter)])


# ----------------------------------------------------------------------------
# Nodes
# ----------------------------------------------------------------------------


def _jumps(distribution: SizeDistribution) -> list[float]:
    """Radii where the density jumps: the finite ends of supports inside the range."""
    if isinstance(distribution, MultiModal):
        return [r for mode in distribution.modes for r in _jumps(mode)]
    if isinstance(distribution, PowerLaw):
        return [distribution.r_min_um, distribution.r_max_um]
    if isinstance(distribution, Truncated):
        ends = [r for r in (distribution.r_min_um, distribution.r_max_um) if 0.0 < r < math.inf]
        return ends + _jumps(distribution.parent)
    return []


def _stretch(x: np.ndarray, x_c: float) -> np.ndarray:
    return np.asarray(x / x_c + np.log(x / x_c))


@dataclass(frozen=True)
class _Nodes:
    """Radius nodes of one wavelength at one level: size parameters, the rule's
    weights in r (J_i), and the weight columns (n J, then dn/dp J per
    distribution parameter; point-mass nodes appended with 0 in column 0)."""

    x: np.ndarray
    weights: np.ndarray
    n_rule: int


def _level_nodes(
    distribution: SizeDistribution,
    *,
    wavelength_um: float,
    settings: QuadratureSettings,
    lower_moment: float,
    tail_fraction: float,
    level: int,
    dist_parameters: Sequence[str],
) -> _Nodes:
    k_um = 2.0 * math.pi / wavelength_um
    x_c = settings.transition_size_parameter
    r_lo, r_hi = distribution.radius_bounds_um(
        tail_fraction=tail_fraction, lower_moment=lower_moment, upper_moment=_UPPER_MOMENT
    )
    s_lo, s_hi = _stretch(np.array([k_um * r_lo, k_um * r_hi]), x_c)
    n0 = max(settings.min_panels, math.ceil((s_hi - s_lo) / settings.panel_width))
    edges = np.linspace(s_lo, s_hi, n0 * 2**level + 1)
    inner = [r for r in _jumps(distribution) if r_lo < r < r_hi]
    if inner:
        edges = np.unique(np.concatenate([edges, _stretch(k_um * np.array(inner), x_c)]))
    t, gw = gauss_legendre(settings.nodes_per_panel)
    half = 0.5 * np.diff(edges)
    mid = 0.5 * (edges[1:] + edges[:-1])
    s = (mid[:, None] + half[:, None] * t[None, :]).ravel()
    x = np.asarray(size_parameter_at(s, settings=settings), dtype=np.float64)
    dx_ds = 1.0 / (1.0 / x_c + 1.0 / x)
    rule = (half[:, None] * gw[None, :]).ravel() * dx_ds / k_um  # J_i [um]
    r = x / k_um
    columns = [np.asarray(distribution.pdf(r), dtype=np.float64) * rule]
    columns += [number_density_derivative(distribution, r, p) * rule for p in dist_parameters]
    weights = np.column_stack(columns)
    extra_x: list[float] = []
    extra_w: list[np.ndarray] = []
    for j, p in enumerate(dist_parameters):
        for r_b, c_b in boundary_terms(distribution, p):
            row = np.zeros(weights.shape[1])
            row[1 + j] = c_b
            extra_x.append(k_um * r_b)
            extra_w.append(row)
    if extra_x:
        x = np.concatenate([x, extra_x])
        weights = np.vstack([weights, np.array(extra_w)])
    return _Nodes(x=np.ascontiguousarray(x), weights=np.ascontiguousarray(weights), n_rule=r.size)


# ----------------------------------------------------------------------------
# Sums to outputs
# ----------------------------------------------------------------------------


def _outputs(
    ang: np.ndarray | None,
    sums: np.ndarray,
    d_ang: list[np.ndarray],
    d_sums: list[np.ndarray],
    *,
    per_particle: bool,
    area: float,
    lossless: bool,
    is_k: Sequence[bool],
) -> tuple[dict[str, np.ndarray], dict[str, list[np.ndarray]]]:
    """Values and derivatives (one per entry of ``d_sums``; ``is_k`` marks the
    derivative along k) of the outputs from the sums of one weight set
    (``ang`` (4, n_mu) and ``sums``)."""
    s_w, s_ext, s_sca, s_gsca, s_g, s_back = sums
    values: dict[str, np.ndarray] = {}
    derivs: dict[str, list[np.ndarray]] = {q: [] for q in QUANTITIES}
    if ang is not None:
        norm = s_w if per_particle else 2.0 * np.pi * s_sca
        f = ang / norm
        for q, key in enumerate(ANGULAR):
            values[key] = f[q]
        for da, ds in zip(d_ang, d_sums, strict=True):
            d_norm = ds[0] if per_particle else 2.0 * np.pi * ds[2]
            for q, key in enumerate(ANGULAR):
                derivs[key].append((da[q] - f[q] * d_norm) / norm)
    g = s_g / s_w if per_particle else s_gsca / s_sca
    ssa = 1.0 if lossless else s_sca / s_ext
    values.update(
        cext_um2=np.array(area * (s_sca if lossless else s_ext)),
        csca_um2=np.array(area * s_sca),
        cabs_um2=np.array(0.0 if lossless else area * (s_ext - s_sca)),
        cback_um2=np.array(area * s_back),
        ssa=np.array(ssa),
        g=np.array(g),
    )
    for ds, along_k in zip(d_sums, is_k, strict=True):
        # A lossless sphere absorbs nothing whatever its size or n: C_ext = C_sca and
        # ssa = 1 hold exactly but for a change of k.
        exact_zero = lossless and not along_k
        derivs["cext_um2"].append(np.array(area * (ds[2] if exact_zero else ds[1])))
        derivs["csca_um2"].append(np.array(area * ds[2]))
        derivs["cabs_um2"].append(np.array(0.0 if exact_zero else area * (ds[1] - ds[2])))
        derivs["cback_um2"].append(np.array(area * ds[5]))
        d_ssa = 0.0 if exact_zero else (ds[2] - (s_sca / s_ext) * ds[1]) / s_ext
        derivs["ssa"].append(np.array(d_ssa))
        dg = (ds[4] - g * ds[0]) / s_w if per_particle else (ds[3] - g * ds[2]) / s_sca
        derivs["g"].append(np.array(dg))
    return values, derivs


def _evaluate(
    m: complex,
    nodes: _Nodes,
    mu: np.ndarray,
    *,
    per_particle: bool,
    area: float,
    index_parameters: Sequence[str],
    want_x: bool = False,
    x_scale: float = 1.0,
) -> tuple[dict[str, np.ndarray], dict[str, list[np.ndarray]]]:
    """Outputs and derivatives on one set of nodes: distribution parameters
    first (weight columns 1..), then ``index_parameters`` ("n", "k"), then,
    if ``want_x``, the common radius of the nodes (x_scale = dx/dr)."""
    ang, d_ang_m, sums, d_sums_m = _accumulate(m, nodes.x, nodes.weights, mu, per_particle, want_x)
    with_angles = mu.size > 0
    d_ang = [ang[c] for c in range(1, ang.shape[0])]
    d_sums = [sums[c] for c in range(1, sums.shape[0])]
    for p in index_parameters:
        d = INDEX_PARAMETERS.index(p)
        d_ang.append(d_ang_m[d])
        d_sums.append(d_sums_m[d])
    if want_x:
        d_ang.append(d_ang_m[2] * x_scale)
        d_sums.append(d_sums_m[2] * x_scale)
    is_k = [False] * (sums.shape[0] - 1) + [p == "k" for p in index_parameters] + [False] * want_x
    return _outputs(
        ang[0] if with_angles else None,
        sums[0],
        d_ang if with_angles else [],
        d_sums,
        per_particle=per_particle,
        area=area,
        lossless=m.imag == 0.0,
        is_k=is_k,
    )


def _angular_error(
    new: Mapping[str, Any], old: Mapping[str, Any], scales: np.ndarray
) -> tuple[float, np.ndarray]:
    """Largest change of the phase matrix relative to F11, and per parameter
    of its derivatives (times the parameters' scales)."""
    f11 = np.asarray(new["values"]["phase"])
    err = max(float(np.max(np.abs(new["values"][k] - old["values"][k]) / f11)) for k in ANGULAR)
    d_err = np.array(
        [
            max(
                float(np.max(np.abs(new["derivs"][k][j] - old["derivs"][k][j]) / f11)) * scales[j]
                for k in ANGULAR
            )
            for j in range(scales.size)
        ]
    )
    return err, d_err


def _cross_error(
    new: Mapping[str, Any], old: Mapping[str, Any], scales: np.ndarray
) -> tuple[float, np.ndarray]:
    """Largest change of the cross-sections (relative; g and ssa absolute), and
    per parameter of their derivatives (times the parameters' scales)."""

    def size(k: str) -> float:
        return 1.0 if k in ("ssa", "g") else max(float(abs(new["values"][k])), 1e-300)

    # C_abs is C_ext - C_sca: measured through those two.
    keys = ("cext_um2", "csca_um2", "cback_um2", "ssa", "g")
    err = max(float(abs(new["values"][k] - old["values"][k])) / size(k) for k in keys)
    d_err = np.array(
        [
            max(
                float(abs(new["derivs"][k][j] - old["derivs"][k][j])) / size(k) * scales[j]
                for k in keys
            )
            for j in range(scales.size)
        ]
    )
    return err, d_err


@dataclass(frozen=True)
class _Solver:
    """One wavelength: nodes by level, sums, outputs, and the doubling of nodes
    until the values and the derivatives settle (module docstring)."""

    m: complex
    wavelength_um: float
    distribution: SizeDistribution
    mu: np.ndarray
    per_particle: bool
    settings: QuadratureSettings
    lower_moment: float
    tail_fraction: float
    dist_parameters: tuple[str, ...]
    index_parameters: tuple[str, ...]

    @property
    def area(self) -> float:
        """pi (lambda / 2 pi)^2: x^2 -> pi r^2. [um^2]"""
        return math.pi * (self.wavelength_um / (2.0 * math.pi)) ** 2

    def at(self, level: int, angles: bool) -> dict[str, Any]:
        """Outputs and derivatives at one level (without angles if not ``angles``)."""
        nodes = _level_nodes(
            self.distribution,
            wavelength_um=self.wavelength_um,
            settings=self.settings,
            lower_moment=self.lower_moment,
            tail_fraction=self.tail_fraction,
            level=level,
            dist_parameters=self.dist_parameters,
        )
        values, derivs = _evaluate(
            self.m,
            nodes,
            self.mu if angles else self.mu[:0],
            per_particle=self.per_particle,
            area=self.area,
            index_parameters=self.index_parameters,
        )
        return {"values": values, "derivs": derivs, "n_nodes": nodes.n_rule}

    def monodisperse(self, *, with_radius: bool, n_order: int) -> dict[str, Any]:
        """One node of weight 1; the radius derivative by d/dr = (2 pi / lambda) d/dx."""
        k_um = 2.0 * math.pi / self.wavelength_um
        nodes = _Nodes(
            x=np.array([k_um * self.distribution.mean_radius_um]),
            weights=np.ones((1, 1)),
            n_rule=1,
        )
        values, derivs = _evaluate(
            self.m,
            nodes,
            self.mu,
            per_particle=self.per_particle,
            area=self.area,
            index_parameters=self.index_parameters,
            want_x=with_radius,
            x_scale=k_um,
        )
        return {
            "values": values,
            "derivs": derivs,
            "err": 0.0,
            "cross_err": 0.0,
            "d_err": np.zeros(n_order),
            "n_nodes": 1,
            "converged": True,
        }

    def solve(
        self, rtol: float, cross_rtol: float, max_level: int, scales: np.ndarray
    ) -> dict[str, Any]:
        """Double the nodes until the phase matrix (then, without angles, the
        cross-sections) and their derivatives change by less than the tolerances."""
        old = self.at(0, True)
        angular: dict[str, Any] | None = None
        err = cross_err = math.inf
        d_err_ang = np.full(scales.size, math.inf)
        d_err_cross = np.full(scales.size, math.inf)
        new = old
        for level in range(1, max_level + 1):
            new = self.at(level, angular is None)
            if angular is None:
                err, d_err_ang = _angular_error(new, old, scales)
                if err <= rtol and np.all(d_err_ang <= rtol):
                    angular = new
            cross_err, d_err_cross = _cross_error(new, old, scales)
            cross_done = cross_err <= cross_rtol and bool(np.all(d_err_cross <= cross_rtol))
            if angular is not None and cross_done:
                break
            old = new
        final = angular if angular is not None else new
        values = dict(final["values"])
        derivs = {k: list(v) for k, v in final["derivs"].items()}
        for k in CROSS:
            values[k] = new["values"][k]
            derivs[k] = list(new["derivs"][k])
        return {
            "values": values,
            "derivs": derivs,
            "err": err,
            "cross_err": cross_err,
            "d_err": np.maximum(d_err_ang, d_err_cross),
            "n_nodes": new["n_nodes"],
            "converged": angular is not None and cross_done,
        }


# ----------------------------------------------------------------------------
# Public function
# ----------------------------------------------------------------------------


def optics_derivatives(
    refractive_index: RefractiveIndexLike,
    distribution: SizeDistribution,
    wavelength_nm: Sequence[float] | np.ndarray | None = None,
    theta_deg: Sequence[float] | np.ndarray | None = None,
    *,
    parameters: Sequence[str] | None = None,
    weighting: str = "scattering",
    rtol: float = 1e-4,
    cross_section_rtol: float | None = None,
    quadrature: QuadratureSettings | None = None,
    tail_fraction: float = 1e-10,
    max_level: int = 10,
) -> OpticsDerivatives:
    """Polydisperse Mie optics and their exact derivatives, on a fixed radius quadrature.

    Parameters
    ----------
    refractive_index : complex, sequence, str or callable
        m = n + i k (k >= 0), as :func:`~dustoptics.scattering.optics.compute_optics`
        takes it (a constant, one value per wavelength, a catalogue name, a
        material or any callable ``wavelength_nm -> complex``). [-]
    distribution : SizeDistribution
        Number size distribution (an analytic family, a
        :class:`~dustoptics.particles.custom_sizedist.MultiModal` of them, a
        truncation, or a :class:`~dustoptics.particles.sizedist.Monodisperse` radius).
    wavelength_nm : array_like, optional
        Strictly increasing wavelengths; default 360, 370, ..., 830. [nm]
    theta_deg : array_like, optional
        Strictly increasing angles in [0, 180]; default 0 to 180 by 0.1. [deg]
    parameters : sequence of str, optional
        What to differentiate with respect to: names of
        :func:`~dustoptics.particles.sizedist_derivatives.parameter_names` of the
        distribution, and ``"n"``, ``"k"`` (the real and imaginary parts of m,
        shifted by the same amount at every wavelength: each wavelength's
        derivative is with respect to its own m).  Default: all of them.
    weighting : {"scattering", "number"}
        Phase-matrix average by scattering cross-section (physical) or by
        number, as :func:`~dustoptics.scattering.optics.compute_optics`.
    rtol : float
        Tolerance of the phase matrix and its derivatives (module docstring). [-]
    cross_section_rtol : float, optional
        Tolerance of the cross-sections, ssa, g and their derivatives; default
        ``rtol / 100``. [-]
    quadrature : QuadratureSettings, optional
        Nodes per panel, level-0 panel width and transition size parameter
        (its ``tail_fraction`` and ``max_level`` are not used: see below).
    tail_fraction : float
        Moment fraction left out in each tail (module docstring). [-]
    max_level : int
        Most halvings of the level-0 panels. [-]

    Returns
    -------
    OpticsDerivatives
        Values per wavelength, and derivatives by
        :meth:`~OpticsDerivatives.derivative`, with error estimates.

    Raises
    ------
    ValueError
        Bad input; an unknown parameter (the message lists the allowed ones).

    Warns
    -----
    dustoptics.scattering.optics.ConvergenceWarning
        A wavelength did not converge within ``max_level``.

    Examples
    --------
    >>> from dustoptics.particles.sizedist import ModifiedGamma
    >>> d = optics_derivatives(1.5 + 0.01j, ModifiedGamma(r_eff_um=0.5, v_eff=0.1),
    ...                        [550.0], [0.0, 90.0, 180.0], parameters=("r_eff_um", "k"))
    >>> round(float(d.g[0]), 4), round(float(d.derivative("g", "r_eff_um")[0]), 4)
    (0.7022, -0.2157)
    """
    check_choice("weighting", weighting, ("scattering", "number"))
    wl = (
        default_wavelengths_nm()
        if wavelength_nm is None
        else as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    )
    if wl[0] <= 0:
        raise ValueError(f"wavelength_nm must be > 0 nm; got minimum {wl[0]!r}")
    check_wavelength_unit("wavelength_nm", wl)
    theta = (
        default_theta_deg()
        if theta_deg is None
        else as_increasing_grid("theta_deg", theta_deg, low=0.0, high=180.0, unit="degree")
    )
    rtol = check_open_interval("rtol", rtol, 0.0, 0.1)
    cross_rtol = (
        rtol / 100.0
        if cross_section_rtol is None
        else check_open_interval("cross_section_rtol", cross_section_rtol, 0.0, 0.1)
    )
    tail_fraction = check_open_interval("tail_fraction", tail_fraction, 0.0, 0.01)
    if not (isinstance(max_level, int) and 1 <= max_level <= 16):
        raise ValueError(f"max_level must be an integer in [1, 16]; got {max_level!r}")
    settings = QuadratureSettings() if quadrature is None else quadrature
    if not isinstance(settings, QuadratureSettings):
        raise ValueError(f"quadrature must be a QuadratureSettings; got {quadrature!r}")
    if not isinstance(distribution, SizeDistribution):
        raise ValueError(f"distribution must be a SizeDistribution; got {distribution!r}")
    mono = distribution.is_monodisperse
    if not (distribution.has_density or mono):
        raise ValueError(
            "distribution mixes Monodisperse and continuous modes, which the radius "
            f"quadrature does not support; got {distribution!r}"
        )
    allowed = parameter_names(distribution) + INDEX_PARAMETERS
    if mono:
        allowed = ("radius_um", *INDEX_PARAMETERS)
    names = tuple(allowed if parameters is None else parameters)
    if isinstance(parameters, str):
        raise TypeError(f"parameters must be a sequence of names; got the string {parameters!r}")
    for p in names:
        check_choice("parameters", p, allowed)
    if len(set(names)) != len(names):
        raise ValueError(f"parameters must not repeat a name; got {names!r}")
    dist_parameters = [p for p in names if p not in INDEX_PARAMETERS and not mono]
    index_parameters = [p for p in names if p in INDEX_PARAMETERS]
    m_all, _ = resolve_refractive_index(refractive_index, wl)
    mu = np.ascontiguousarray(np.cos(np.deg2rad(theta)))
    per_particle = weighting == "number"
    lower_moment = 0.0 if per_particle else 2.0
    x_top = (
        2.0
        * math.pi
        / (wl[0] * 1e-3)
        * (
            distribution.mean_radius_um
            if mono
            else distribution.radius_bounds_um(
                tail_fraction=tail_fraction, lower_moment=lower_moment, upper_moment=_UPPER_MOMENT
            )[1]
        )
    )
    n_max = x_top + 4.05 * x_top ** (1.0 / 3.0) + 2.0
    check_budget(
        "optics_derivatives",
        16.0 * n_max * mu.size + 8.0 * 4 * mu.size * (len(names) + 2),
        allow_large=False,
        change=f"the largest size parameter is {x_top:.3g}: use fewer angles or smaller spheres",
    )
    # The order of the derivatives as the kernel gives them, then as asked.
    order = (
        dist_parameters
        + index_parameters
        + (["radius_um"] if mono and "radius_um" in names else [])
    )
    scales = np.array(
        [max(abs(parameter_value(distribution, p)), 1e-3) for p in dist_parameters]
        + [0.0] * len(index_parameters)
    )

    per_wl: list[dict[str, Any]] = []
    for i, w in enumerate(wl):
        m = complex(m_all[i])
        for j, p in enumerate(index_parameters):
            scales[len(dist_parameters) + j] = max(abs(m.real if p == "n" else m.imag), 1e-3)
        solver = _Solver(
            m=m,
            wavelength_um=float(w) * 1e-3,
            distribution=distribution,
            mu=mu,
            per_particle=per_particle,
            settings=settings,
            lower_moment=lower_moment,
            tail_fraction=tail_fraction,
            dist_parameters=tuple(dist_parameters),
            index_parameters=tuple(index_parameters),
        )
        if mono:
            per_wl.append(solver.monodisperse(with_radius="radius_um" in names, n_order=len(order)))
        else:
            per_wl.append(solver.solve(rtol, cross_rtol, max_level, scales))

    converged = np.array([r["converged"] for r in per_wl])
    if not converged.all():
        bad = ", ".join(f"{w:g}" for w in wl[~converged])
        warnings.warn(
            f"optics_derivatives did not reach rtol={rtol:g} / cross_section_rtol={cross_rtol:g} "
            f"at wavelengths {bad} nm within max_level={max_level}; see the error estimates",
            ConvergenceWarning,
            stacklevel=2,
        )
    positions = [order.index(p) for p in names]
    values_of = {k: np.stack([r["values"][k] for r in per_wl]) for k in QUANTITIES}
    stacked = {
        k: np.array([np.stack([r["derivs"][k][j] for r in per_wl]) for j in positions]).reshape(
            (len(positions), *values_of[k].shape)
        )
        for k in QUANTITIES
    }
    param_values = np.array(
        [
            m_all.real
            if p == "n"
            else m_all.imag
            if p == "k"
            else np.full(wl.size, parameter_value(distribution, p))
            for p in names
        ]
    )
    return OpticsDerivatives(
        wavelength_nm=wl,
        theta_deg=theta,
        parameters=names,
        parameter_values=param_values.reshape(len(names), wl.size),
        refractive_index=m_all,
        weighting=weighting,
        error_estimate=np.array([r["err"] for r in per_wl]),
        cross_section_error_estimate=np.array([r["cross_err"] for r in per_wl]),
        derivative_error_estimate=np.stack([r["d_err"] for r in per_wl], axis=1)[positions]
        if names
        else np.zeros((0, wl.size)),
        n_nodes=np.array([r["n_nodes"] for r in per_wl], dtype=np.int64),
        converged=converged,
        _derivatives=stacked,
        **values_of,
    )
